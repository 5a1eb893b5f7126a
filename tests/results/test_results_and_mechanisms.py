"""Results file (netCDF via xarray), run metadata, mechanism and non-convergence reporting, and the
command line summary.

Sources:
- results layout and attributes: docs/results.md and masonrydam/results/writer.py (CF-1.8 style:
  every variable with ``units`` and ``long_name``; streamed step by step, a stopped run keeps every
  converged step and is marked ``completed = "false"``);
- statics of a rigid block on a joint (equilibrium of forces): the bed-joint force equals the load
  above it; a block on a no-tension joint (tensile strength 0: an open joint transmits no traction,
  Tzamtzis & Asteris, sec. 3.4 and docs/method.md, joint law) cannot carry a net upward load
  larger than its weight; on a cohesionless Mohr-Coulomb joint it cannot carry a horizontal load
  larger than tan(phi) times the normal force (tau_y = c - t_n tan(phi), Tzamtzis & Asteris eq. 12);
- docs/method.md, robustness: a mechanism is reported by naming the free part; a run that stops keeps the
  converged steps.
"""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
import xarray as xr

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import ConvergenceError, MasonrydamError, MechanismError
from scenes import WALL_NORMAL_STIFFNESS, WALL_SHEAR_STIFFNESS, WALL_THICKNESS, WALL_UNIT_DENSITY, small_wall

G = 9.80665
T = WALL_THICKNESS  # thickness (m)
RHO = WALL_UNIT_DENSITY  # units, kg/m3
RHO_BEAM = 7850.0


def wall_scene(self_weight=True, pressure="0.1 MPa", **params) -> dict:
    """2 courses x 2 units (0.2 x 0.1 m) running-bond wall on a fixed base, one element per unit
    height; stage 'gravity' (self-weight) and stage 'press' (pressure on the top edge)."""
    stages = []
    if self_weight:
        stages.append({"name": "gravity", "steps": 1, "loads": [{"type": "self_weight"}]})
    stages.append({"name": "press", "steps": 2,
                   "loads": [{"type": "edge_pressure", "set": "top_edge", "pressure": pressure}]})
    bed_joints = {"normal_stiffness": WALL_NORMAL_STIFFNESS, "shear_stiffness": WALL_SHEAR_STIFFNESS,
                  "friction_angle": 36.87}
    return small_wall(length=0.4, height=0.2, elements_per_unit=1, bed_joints=bed_joints, stages=stages,
                      overrides={"model.name": "tiny_wall", "mesh.parameters": params})


def block_scene(stage2: dict, phi=30.0, solver=None) -> dict:
    """One 0.2 x 0.1 m unit on a 0.05 m fixed base beam, joined by a cohesionless no-tension
    Mohr-Coulomb 'base_joint'. Stage 'gravity' then ``stage2``."""
    s = {
        "model": {"name": "block", "thickness": T},
        "mesh": {"generator": "masonry_wall_2d",
                 "parameters": {"length": 0.2, "height": 0.1, "unit_length": 0.2, "unit_height": 0.1,
                                "elements_per_unit": 1, "base_beam_height": 0.05}},
        "materials": {"units": {"youngs_modulus": "16.7 GPa", "poisson_ratio": 0.15, "density": RHO},
                      "base_beam": {"youngs_modulus": "210 GPa", "poisson_ratio": 0.3, "density": RHO_BEAM}},
        "joints": {"base_joint": {"normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3",
                                  "cohesion": 0.0, "tensile_strength": 0.0, "friction_angle": phi}},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": [{"name": "gravity", "steps": 1, "loads": [{"type": "self_weight"}]}, stage2],
    }
    if solver:
        s["solver"] = solver
    return s


BLOCK_WEIGHT = RHO * 0.2 * 0.1 * T * G  # N (35.3 N)


@pytest.fixture(scope="module")
def wall_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("res") / "o.nc"
    ds = masonrydam.run(wall_scene(), output=path)
    return path, ds


# ------------------------------------------------------------------------------------------------
# netCDF output
# ------------------------------------------------------------------------------------------------
VARIABLES = ["displacement", "reaction", "joint_opening", "joint_slip", "joint_plastic_slip",
             "joint_traction_normal", "joint_traction_shear", "joint_state", "load_factor", "stage",
             "iterations", "x", "y", "joint_x", "joint_y", "joint_normal_x", "joint_normal_y", "joint_weight"]


def test_netcdf_structure(wall_run):
    path, ds_mem = wall_run
    assert path.exists()
    with xr.open_dataset(path) as ds:
        for c in ("step", "node", "component"):
            assert c in ds.coords, f"coordinate {c} missing"
        assert list(ds["component"].values) == ["x", "y"]
        assert "joint_point" in ds.dims
        for v in VARIABLES:
            assert v in ds.variables, f"variable {v} missing"
            assert ds[v].attrs.get("units"), f"{v} has no units"
            assert ds[v].attrs.get("long_name"), f"{v} has no long_name"
        assert ds.displacement.dims == ("step", "node", "component")
        assert ds.reaction.dims == ("step", "node", "component")
        assert ds.joint_opening.dims == ("step", "joint_point")
        assert ds.joint_state.dims == ("step", "joint_point")
        assert ds.displacement.attrs["units"] == "m"
        assert ds.reaction.attrs["units"] == "N"
        assert ds.joint_opening.attrs["units"] == "m"
        assert ds.joint_slip.attrs["units"] == "m"
        assert ds.joint_traction_normal.attrs["units"] == "Pa"
        assert ds.joint_traction_shear.attrs["units"] == "Pa"
        # 1 gravity step + 2 pressure steps, all nodes, every lumped joint point (2 per element)
        assert ds.sizes["step"] == 3
        assert list(ds.stage.values) == [0, 1, 1]
        assert np.allclose(ds.load_factor.values, [1.0, 0.5, 1.0])
        # bed joint: 4 elements along 0.4 m; head joints: 1 in course 0 (2 units), 2 in course 1
        # (half, full, half unit); 2 lumped points per interface element
        n_jp = 2 * (4 + 1 + 2)
        assert ds.sizes["joint_point"] == n_jp
        assert set(np.unique(ds.joint_state.values)) <= {0, 1, 2}
        assert json.loads(ds.stage.attrs["stage_names"]) == ["gravity", "press"]
        # the returned in-memory dataset is the file's content
        xr.testing.assert_identical(ds.load(), ds_mem)


def test_joint_point_is_a_coordinate(wall_run):
    """docs/results.md: coordinates step, node, component and joint_point."""
    path, _ = wall_run
    with xr.open_dataset(path) as ds:
        assert "joint_point" in ds.coords


def test_netcdf_global_attributes(wall_run):
    path, _ = wall_run
    with xr.open_dataset(path) as ds:
        a = ds.attrs
        assert a["masonrydam_version"] == masonrydam.__version__
        assert re.fullmatch(r"[0-9a-f]{64}", a["scene_hash"])
        settings = json.loads(a["solver_settings"])
        assert settings["method"] == "newton" and settings["max_iterations"] == 30
        assert settings["linear_solver_backend"] in ("pardiso", "superlu")
        assert a["completed"] == "true"
        assert a["status"] == "completed"
        eff = a["simulated_effects"]
        assert "self-weight" in eff and "edge pressures" in eff and "Mohr-Coulomb" in eff
        for absent in ("nodal forces", "edge tractions", "prescribed displacements"):
            assert absent not in eff
        assert json.loads(a["scene"])["model"]["name"] == "tiny_wall"
        assert int(a["steps"]) == 3


def test_reactions_and_bed_joint_force_balance_the_loads(wall_run):
    """Statics: base reaction = weight + pressure resultant; the bed-joint force (sum of traction x
    tributary area, lumped points) = pressure resultant + weight of the upper course."""
    _, ds = wall_run
    L, H = 0.4, 0.2
    weight = RHO * L * H * T * G
    press = 0.1e6 * L * T
    last = ds.isel(step=-1)
    ry = float(last.reaction.sel(component="y").sum())
    rx = float(last.reaction.sel(component="x").sum())
    assert ry == pytest.approx(weight + press, rel=1e-6)
    assert abs(rx) < 1e-6 * (weight + press)
    sets = json.loads(ds.joint_set.attrs["set_names"])
    bed = (ds.joint_set == sets.index("bed_joints")).values
    force = float((last.joint_traction_normal.values[bed] * ds.joint_weight.values[bed]).sum())
    assert force == pytest.approx(-(press + weight / 2), rel=1e-5)
    # contact everywhere: compression, no opening beyond the elastic closure, no slip under vertical load
    assert (last.joint_traction_normal.values[bed] < 0).all()
    assert (last.joint_state.values == 0).all()
    # gravity step alone: reaction equals the weight
    assert float(ds.isel(step=0).reaction.sel(component="y").sum()) == pytest.approx(weight, rel=1e-6)


def test_scene_hash_same_scene_same_hash_changed_parameter_different(tmp_path, wall_run):
    _, ds = wall_run
    again = masonrydam.run(wall_scene(), output=tmp_path / "again.nc")
    assert again.attrs["scene_hash"] == ds.attrs["scene_hash"]
    changed = wall_scene()
    changed["joints"]["bed_joints"]["friction_angle"] = 30.0
    other = masonrydam.run(changed, output=tmp_path / "other.nc")
    assert re.fullmatch(r"[0-9a-f]{64}", other.attrs["scene_hash"])
    assert other.attrs["scene_hash"] != ds.attrs["scene_hash"]
    # the same quantity written with a unit is the same scene (the hash is of the normalised scene)
    same = wall_scene()
    same["model"]["thickness"] = "100 mm"
    assert masonrydam.Scene(same).hash == ds.attrs["scene_hash"]


def test_effects_not_requested_are_not_listed(tmp_path):
    ds = masonrydam.run(wall_scene(self_weight=False), output=tmp_path / "nw.nc")
    eff = ds.attrs["simulated_effects"]
    assert "self-weight" not in eff
    assert "edge pressures" in eff
    # no gravity: the reaction is the pressure resultant only
    ry = float(ds.isel(step=-1).reaction.sel(component="y").sum())
    assert ry == pytest.approx(0.1e6 * 0.4 * T, rel=1e-6)


def test_output_none_returns_dataset_without_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    ds = masonrydam.run(wall_scene(self_weight=False))
    assert isinstance(ds, xr.Dataset) and ds.attrs["completed"] == "true"
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------------
# mechanisms and non-convergence
# ------------------------------------------------------------------------------------------------
def open_nc(path):
    with xr.open_dataset(path) as ds:
        return ds.load()


def test_no_supports_is_a_mechanism_before_solving(tmp_path):
    s = wall_scene()
    s["supports"] = []
    out = tmp_path / "free.nc"
    with pytest.raises(MechanismError) as ei:
        masonrydam.run(s, output=out)
    msg = str(ei.value)
    assert "units" in msg, "the message must name the element groups of the free part"
    assert "gravity" in msg and "before solving" in msg
    assert ei.value.parts and "no support" in ei.value.parts[0]
    ds = open_nc(out)
    assert ds.attrs["completed"] == "false"
    assert ds.sizes["step"] == 0
    assert int(ds.attrs["newton_iterations"]) == 0
    assert ds.attrs["status"] == "failed" and "MechanismError" in ds.attrs["status_reason"]


def test_partial_supports_vertical_translation_is_a_mechanism(tmp_path):
    """Only the left edge held in x (rotation and x translation restrained): the wall can still
    translate vertically; the mechanism report names that free rigid-body motion."""
    s = wall_scene()
    s["supports"] = [{"set": "left", "components": ["x"]}]
    with pytest.raises(MechanismError) as ei:
        masonrydam.run(s, output=tmp_path / "m.nc")
    assert "translation y" in str(ei.value)


def test_block_lifted_off_a_no_tension_joint(tmp_path):
    """An upward edge traction of 200 N on a 35.3 N block resting on a no-tension joint: the joint
    opens and the block floats away. The run must stop with a masonrydam error (not a LinAlgError
    or NaNs) naming the stage or the free part, keep the converged steps, and never report a
    converged state in which the joint carries the block with a net upward load."""
    f_up = 1.0e4  # Pa on the 0.2 m top edge x 0.1 m thickness = 200 N
    stage = {"name": "lift", "steps": 2, "loads": [{"type": "edge_traction", "set": "top_edge", "traction": [0.0, f_up]}]}
    out = tmp_path / "lift.nc"
    with pytest.raises(MasonrydamError) as ei:
        masonrydam.run(block_scene(stage), output=out)
    err = ei.value
    assert isinstance(err, (MechanismError, ConvergenceError)), type(err)
    msg = str(err)
    assert "lift" in msg or "units" in msg
    assert any(str(out) in n for n in getattr(err, "__notes__", []))
    assert out.exists()
    ds = open_nc(out)
    assert ds.attrs["completed"] == "false"
    assert ds.attrs["status"] == "failed" and type(err).__name__ in ds.attrs["status_reason"]
    # the gravity stage converged and is in the file
    assert ds.sizes["step"] >= 1
    assert int(ds.stage.values[0]) == 0 and float(ds.load_factor.values[0]) == 1.0
    assert np.isfinite(ds.displacement.values).all()
    # statics: no converged step with an upward load above the weight; no tension in the joint
    lift = ds.stage.values == 1
    applied = ds.load_factor.values[lift] * f_up * 0.2 * T
    assert (applied <= BLOCK_WEIGHT * (1 + 1e-3)).all()
    assert (ds.joint_traction_normal.values <= 1e-6).all()
    # and the run did not give up long before the block could float (load factor ~ W / F)
    assert (ds.load_factor.values[lift].max() if lift.any() else 0.0) > 0.5 * BLOCK_WEIGHT / (f_up * 0.2 * T)


def test_block_lifted_by_nodal_forces(tmp_path):
    # 3 top nodes x 100 N upward on a 35.3 N block
    stage = {"name": "pull", "steps": 1, "loads": [{"type": "nodal", "set": "top", "force": [0.0, 100.0]}]}
    out = tmp_path / "pull.nc"
    with pytest.raises(MasonrydamError) as ei:
        masonrydam.run(block_scene(stage), output=out)
    assert isinstance(ei.value, (MechanismError, ConvergenceError))
    assert "pull" in str(ei.value) or "units" in str(ei.value)
    ds = open_nc(out)
    assert ds.attrs["completed"] == "false"
    pull = ds.stage.values == 1
    assert (ds.load_factor.values[pull] * 300.0 <= BLOCK_WEIGHT * (1 + 1e-3)).all()
    assert ds.sizes["step"] >= 1 and int(ds.stage.values[0]) == 0


def test_non_convergence_keeps_converged_steps(tmp_path):
    """A horizontal load of 300 N on a 35.3 N block on a cohesionless joint with phi = 30 deg
    (friction capacity W tan(phi) = 20.4 N) under load control: the stage 'slide' cannot converge
    beyond the friction capacity. The file keeps the gravity step and the converged slide steps."""
    phi = 30.0
    stage = {"name": "slide", "steps": 2, "loads": [{"type": "nodal", "set": "top", "force": [100.0, 0.0]}]}
    out = tmp_path / "slide.nc"
    with pytest.raises(ConvergenceError) as ei:
        masonrydam.run(block_scene(stage, phi=phi), output=out)
    assert "stage 'slide'" in str(ei.value)
    ds = open_nc(out)
    assert ds.attrs["completed"] == "false"
    assert ds.attrs["status"] == "failed"
    assert "slide" in ds.attrs["status_reason"] and "ConvergenceError" in ds.attrs["status_reason"]
    assert json.loads(ds.attrs["per_stage"])[0]["stage"] == "gravity"
    assert list(ds.stage.values[:1]) == [0]
    slide = ds.stage.values == 1
    assert slide.any(), "the steps of 'slide' below the friction capacity converge and are kept"
    capacity = BLOCK_WEIGHT * math.tan(math.radians(phi))
    applied = ds.load_factor.values[slide] * 300.0
    assert (applied <= capacity * (1 + 1e-3)).all()
    # the run stopped close to the friction capacity (step cuts), not at the first difficulty
    assert applied.max() > 0.8 * capacity
    # steps are numbered consecutively and every written step is finite
    assert list(ds.step.values) == list(range(ds.sizes["step"]))
    assert np.isfinite(ds.displacement.values).all() and np.isfinite(ds.joint_traction_shear.values).all()
    # Coulomb: |tau| <= c - t_n tan(phi) at every converged joint point (c = 0)
    tau = np.abs(ds.joint_traction_shear.values[..., 0])
    tn = ds.joint_traction_normal.values
    assert (tau <= -tn * math.tan(math.radians(phi)) * (1 + 1e-6) + 1e-6).all()


# ------------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_cli_run_default(tmp_path, capsys):
    out = tmp_path / "w.nc"
    rc = main(["run", "--default", "-o", str(out), "--no-progress"])
    stdout, stderr = capsys.readouterr()
    assert rc == 0, stderr
    assert "effects" in stdout and "wall time" in stdout
    assert "self-weight" in stdout and "prescribed displacements" in stdout
    assert str(out) in stdout
    ds = open_nc(out)
    assert ds.attrs["completed"] == "true"
    assert json.loads(ds.stage.attrs["stage_names"]) == ["gravity_and_precompression", "lateral_push"]
    # docs/scene_guide.md: a displacement load is an increment over the stage: the top beam moved 1 mm sideways
    # and not vertically from where the first stage left it
    top = (ds.y == float(ds.y.max())).values
    u = ds.displacement.values[:, top, :]
    end_first = int(np.nonzero(ds.stage.values == 0)[0][-1])
    assert np.allclose(u[-1, :, 0] - u[end_first, :, 0], 1e-3, rtol=1e-12, atol=1e-15)
    assert np.allclose(u[-1, :, 1], u[end_first, :, 1], rtol=1e-12, atol=1e-15)


def test_cli_run_stopped_exit_code_and_note(tmp_path, capsys):
    """A run that stops reports the error and where the converged steps were kept, exit code 2."""
    out = tmp_path / "s.nc"
    scene = tmp_path / "slide.toml"
    scene.write_text("""
[model]
name = "block"
thickness = 0.1
[mesh]
generator = "masonry_wall_2d"
[mesh.parameters]
length = 0.2
height = 0.1
unit_length = 0.2
unit_height = 0.1
elements_per_unit = 1
base_beam_height = 0.05
[materials.units]
youngs_modulus = "16.7 GPa"
poisson_ratio = 0.15
density = 1800
[materials.base_beam]
youngs_modulus = "210 GPa"
poisson_ratio = 0.3
density = 7850
[joints.base_joint]
normal_stiffness = "82 N/mm3"
shear_stiffness = "36 N/mm3"
friction_angle = 30
[[supports]]
set = "base"
[[stages]]
name = "gravity"
[[stages.loads]]
type = "self_weight"
[[stages]]
name = "slide"
steps = 2
[[stages.loads]]
type = "nodal"
set = "top"
force = [100.0, 0.0]
""")
    rc = main(["run", str(scene), "-o", str(out), "--no-progress"])
    _, err = capsys.readouterr()
    assert rc == 2
    assert "stage 'slide'" in err and str(out) in err and "Traceback" not in err
    assert open_nc(out).attrs["completed"] == "false"


@pytest.mark.parametrize("fast", [True, False])
def test_writer_records_read_back_exactly(tmp_path, fast):
    """The streamed writer (masonrydam/results/writer.py) appends records through netCDF4's low-level
    ``Variable._put`` (fast) or the public ``var[k] = x`` (its fallback); either way xarray reads back
    exactly the values written, a static step has NaN dynamic variables, and the step count grows by
    one per record."""
    from masonrydam.results.writer import ENERGY_VARIABLES, ResultWriter

    rng = np.random.default_rng(7)
    n_nodes, n_out, n_jp, dim = 6, 3, 4, 2
    jp = {"x": rng.random((n_jp, dim)), "set": np.zeros(n_jp, int), "set_names": ["bed"],
          "element": np.arange(n_jp), "point": np.zeros(n_jp, int), "normal": np.tile([0.0, 1.0], (n_jp, 1)),
          "shear_axes": np.tile([[[1.0, 0.0]]], (n_jp, 1, 1)), "weight": np.ones(n_jp)}
    path = tmp_path / "w.nc"
    w = ResultWriter(path, rng.random((n_nodes, dim)), np.array([0, 2, 5]), jp, dim, {}, dynamic=True)
    w._fast_append = fast and w._fast_append
    assert w._fast_append == fast
    written = []
    for k in range(4):
        rec = {"u": rng.random((n_out, dim)), "r": rng.random((n_out, dim)),
               "joints": {"opening": rng.random(n_jp), "slip": rng.random((n_jp, 1)), "plastic_slip": rng.random((n_jp, 1)),
                          "t_normal": rng.random(n_jp), "t_shear": rng.random((n_jp, 1)),
                          "state": rng.integers(0, 3, n_jp).astype(np.int8)},
               "dynamic": None if k == 0 else {
                   "time": 0.01 * k, "velocity": rng.random((n_out, dim)), "acceleration": rng.random((n_out, dim)),
                   "acceleration_absolute": rng.random((n_out, dim)), "ground_acceleration": rng.random(dim),
                   "energy": {name: float(rng.random()) for name in ENERGY_VARIABLES}}}
        w.write_step(int(k > 0), 0.25 * k, k + 1, rec["u"], rec["r"], rec["joints"], rec["dynamic"])
        written.append(rec)
    w.close(True, "done")
    ds = xr.load_dataset(path)
    assert ds.sizes["step"] == 4
    assert list(ds.stage.values) == [0, 1, 1, 1] and list(ds.iterations.values) == [1, 2, 3, 4]
    assert np.array_equal(ds.load_factor.values, [0.0, 0.25, 0.5, 0.75])
    assert np.isnan(ds.time.values[0]) and np.isnan(ds.velocity.values[0]).all()
    for k, rec in enumerate(written):
        assert np.array_equal(ds.displacement.values[k], rec["u"])
        assert np.array_equal(ds.reaction.values[k], rec["r"])
        assert np.array_equal(ds.joint_opening.values[k], rec["joints"]["opening"])
        assert np.array_equal(ds.joint_slip.values[k], rec["joints"]["slip"])
        assert np.array_equal(ds.joint_traction_shear.values[k], rec["joints"]["t_shear"])
        assert np.array_equal(ds.joint_state.values[k], rec["joints"]["state"])
        if rec["dynamic"] is not None:
            d = rec["dynamic"]
            assert ds.time.values[k] == d["time"]
            assert np.array_equal(ds.acceleration_absolute.values[k], d["acceleration_absolute"])
            assert np.array_equal(ds.ground_acceleration.values[k], d["ground_acceleration"])
            for name in ENERGY_VARIABLES:
                assert ds[f"energy_{name}"].values[k] == d["energy"][name]
