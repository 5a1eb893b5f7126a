"""Ensemble files: the spec, the member enumeration, the Latin hypercube and the member measures."""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy import stats

import masonrydam
from masonrydam.ensemble import (MEASURES, enumerate_members, load_ensemble, measure_attrs, member_axes,
                                 member_measures, sample_coordinates)
from masonrydam.ensemble.members import member_id
from masonrydam.ensemble.spec import parameter_names
from masonrydam.errors import SceneError
from masonrydam.scene.scene import Scene

G = 9.80665
RECORDS3 = ["elcentro_1940_ns_peknold", "elcentro_1940_ns_peer", "northridge_1994_arleta_360"]

# Newmark's sliding block (examples/sliding_block_pulse.toml), small: a fixed dt and a short stage
BASE = """
[model]
name = "tiny_block"
hypothesis = "plane_stress"
thickness = 1.0

[mesh]
generator = "blocks_2d"
[mesh.parameters]
element_size = 0.25
blocks = [
  { x0 = 0.0, y0 = 0.0, x1 = 2.0, y1 = 0.25, group = "base" },
  { x0 = 0.0, y0 = 0.25, x1 = 2.0, y1 = 0.75, group = "block" },
]

[materials.base]
youngs_modulus = "30 GPa"
poisson_ratio = 0.2
density = 2000

[materials.block]
youngs_modulus = "30 GPa"
poisson_ratio = 0.2
density = 2000

[joints.joints]
law = "mohr_coulomb"
normal_stiffness = "10 GPa/m"
shear_stiffness = "10 GPa/m"
friction_angle = 11.31        # tan(phi) = 0.2
cohesion = 0.0

[[supports]]
set = "base"
components = ["x", "y"]

[[stages]]
name = "gravity"
[[stages.loads]]
type = "self_weight"

[[stages]]
name = "shake"
type = "dynamic"
dt = 0.005
duration = 0.4
integrator = "hht"
mass = "lumped"
[stages.ground_motion.x]
pulse = { shape = "rectangular", amplitude = "0.4 g", duration = 0.2 }
processing = [{ step = "taper", max_percentage = 0.05 }]
"""


def write(tmp_path: Path, ensemble: str, base: str = BASE, name: str = "ens.toml") -> Path:
    (tmp_path / "base.toml").write_text(base)
    p = tmp_path / name
    p.write_text(ensemble)
    return p


def pulse_record(folder: Path, name: str = "pulse.txt") -> Path:
    """A 0.4 g rectangular pulse of 0.2 s, then 0.2 s of rest, as a text record (units g, dt 0.01 s)."""
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / name
    p.write_text("rectangular pulse\nunits: g\ndt: 0.01\n" + "\n".join(str(v) for v in [0.4] * 20 + [0.0] * 20) + "\n")
    return p


GRID = f"""
[ensemble]
scene = "base.toml"
[axes.records]
names = {json.dumps(RECORDS3)}
[axes.intensity]
scale_to_pga = ["0.1 g", "0.2 g", 3.0, "0.5 g"]
[[axes.parameters]]
key = "joints.joints.friction_angle"
values = [30, 35]
"""


# ------------------------------------------------------------------------------------------------
# enumeration
# ------------------------------------------------------------------------------------------------

def test_grid_members_counts_coords_and_scenes(tmp_path):
    spec = load_ensemble(write(tmp_path, GRID))
    assert spec.name == "ens" and spec.stage == 1 and spec.stage_name == "shake" and spec.component == "x"
    assert spec.demand_sets == ["joints"] and spec.history is False and spec.n_members == 24
    assert spec.scene_path == tmp_path / "base.toml" and spec.scene_dir == tmp_path
    members = enumerate_members(spec)
    assert len(members) == 24
    pga = [0.1 * G, 0.2 * G, 3.0, 0.5 * G]
    combos = {(m.coords["record"], round(m.coords["intensity"], 9), m.coords["p_friction_angle"]) for m in members}
    assert combos == {(r, round(a, 9), float(f)) for r in RECORDS3 for a in pga for f in (30, 35)}
    ids = [m.member_id for m in members]
    assert len(set(ids)) == 24 and all(re.fullmatch(r"[0-9a-f]{12}", i) for i in ids)
    # stable: the same file read again gives the same ids, the id is the hash of the coords
    assert [m.member_id for m in enumerate_members(load_ensemble(tmp_path / "ens.toml"))] == ids
    assert ids[5] == member_id(members[5].coords)
    # order: record x intensity x friction, the last fastest
    assert [m.coords["p_friction_angle"] for m in members[:4]] == [30.0, 35.0, 30.0, 35.0]
    assert members[2].coords["intensity"] == pytest.approx(0.2 * G)
    assert members[8].coords["record"] == RECORDS3[1] and members[8].position == {"record": 1, "intensity": 0,
                                                                                   "p_friction_angle": 0}
    for m in members:
        gm = m.scene["stages"][1]["ground_motion"]["x"]
        # the pulse is replaced by the record, the scaling by the intensity, the processing kept
        assert gm == {"record": m.coords["record"], "scale_to_pga": pytest.approx(m.coords["intensity"], rel=1e-15),
                      "processing": [{"step": "taper", "max_percentage": 0.05}]}
        assert m.scene["joints"]["joints"]["friction_angle"] == m.coords["p_friction_angle"]
        assert m.scene["joints"]["joints"]["cohesion"] == 0.0 and m.base_dir == tmp_path
    # the base scene is not changed, and a member scene is a valid scene
    assert "pulse" in spec.base_scene["stages"][1]["ground_motion"]["x"]
    sc = Scene(members[-1].scene, base_dir=members[-1].base_dir)
    g = sc.normalized["stages"][1]["ground_motion"]["x"]
    assert g["record"] == RECORDS3[2] and g["scale_to_pga"] == pytest.approx(0.5 * G)
    assert sc.normalized["joints"]["joints"]["friction_angle"] == 35.0

    axes = member_axes(spec)
    assert list(axes) == ["record", "intensity", "p_friction_angle"]
    assert axes["record"].values == RECORDS3
    assert axes["intensity"].values == pytest.approx(pga)
    assert axes["intensity"].attrs["units"] == "m/s2" and axes["intensity"].attrs["measure"] == "pga"
    assert axes["intensity"].attrs["scene_key"] == "stages[1].ground_motion.x.scale_to_pga"
    assert axes["p_friction_angle"].values == [30.0, 35.0]
    assert axes["p_friction_angle"].attrs["units"] == "deg"
    assert axes["p_friction_angle"].attrs["scene_key"] == "joints.joints.friction_angle"
    values, attrs = axes["record"]  # (values, attrs) tuples
    assert json.loads(attrs["kinds"]) == {r: "bundled" for r in RECORDS3}
    assert sample_coordinates(spec) == {}


def test_sa_intensity_file_records_and_name_collisions(tmp_path):
    pulse_record(tmp_path / "recs", "a.txt")
    pulse_record(tmp_path / "recs", "b.txt")
    (tmp_path / "recs" / "notes.md").write_text("not a record")
    pulse_record(tmp_path, "single.txt")
    text = """
[ensemble]
name = "sa_run"
scene = "base.toml"
history = true
[axes.records]
files = ["single.txt"]
folder = "recs"
[axes.intensity]
scale_to_sa = { values = ["0.3 g", "0.6 g"], period = 0.3, damping = 0.05 }
[[axes.parameters]]
key = "materials.block.density"
values = ["2.0 t/m3", 2400]
[[axes.parameters]]
key = "materials.base.density"
values = [2100]
[execution]
workers = 2
scheduler = "tcp://127.0.0.1:8786"
"""
    spec = load_ensemble(write(tmp_path, text))
    assert spec.name == "sa_run" and spec.history is True and spec.workers == 2
    assert spec.scheduler == "tcp://127.0.0.1:8786"
    assert [r.name for r in spec.records] == ["single.txt", "recs/a.txt", "recs/b.txt"]
    members = enumerate_members(spec)
    assert len(members) == 3 * 2 * 2 * 1
    axes = member_axes(spec)
    assert list(axes) == ["record", "intensity", "p_block_density", "p_base_density"]
    assert axes["p_block_density"].values == [2000.0, 2400.0]
    assert axes["p_block_density"].attrs["units"] == "kg/m3"
    assert axes["intensity"].attrs["measure"] == "sa" and axes["intensity"].attrs["period"] == 0.3
    assert axes["intensity"].attrs["damping"] == 0.05
    assert axes["intensity"].attrs["scene_key"] == "stages[1].ground_motion.x.scale_to_sa.sa"
    m = members[-1]
    gm = m.scene["stages"][1]["ground_motion"]["x"]
    assert gm["file"] == str((tmp_path / "recs" / "b.txt").resolve())
    assert gm["scale_to_sa"] == {"sa": pytest.approx(0.6 * G), "period": 0.3, "damping": 0.05}
    assert "pulse" not in gm and "scale_to_pga" not in gm
    assert m.scene["materials"]["block"]["density"] == 2400 and m.scene["materials"]["base"]["density"] == 2100
    assert members[0].scene["materials"]["block"]["density"] == "2.0 t/m3"  # written as given
    Scene(m.scene, base_dir=m.base_dir)  # valid

    assert parameter_names(["joints.bed.friction_angle", "joints.head.friction_angle", "joints.bed.cohesion"]) == \
        ["p_bed_friction_angle", "p_head_friction_angle", "p_cohesion"]
    assert parameter_names(["stages[1].loads[0].pressure", "stages[2].loads[0].pressure"]) == \
        ["p_stages1_loads0_pressure", "p_stages2_loads0_pressure"]


# ------------------------------------------------------------------------------------------------
# Latin hypercube
# ------------------------------------------------------------------------------------------------

LHS = """
[ensemble]
scene = "base.toml"
[axes.records]
names = ["elcentro_1940_ns_peknold", "elcentro_1940_ns_peer"]
[axes.intensity]
scale_to_pga = ["0.2 g"]
[[axes.parameters]]
key = "joints.joints.friction_angle"
values = [25, 30, 35]
[[axes.parameters]]
key = "joints.joints.cohesion"
distribution = {{ type = "lognormal", median = "0.1 MPa", dispersion = 0.3 }}
[[axes.parameters]]
key = "materials.block.density"
distribution = {{ type = "normal", mean = 2000, std = 100 }}
[[axes.parameters]]
key = "joints.joints.tensile_strength"
distribution = {{ type = "uniform", low = "10 kPa", high = "50 kPa" }}
[axes.sampling]
samples = {n}
seed = {seed}
"""


def test_latin_hypercube_samples(tmp_path):
    n = 8
    spec = load_ensemble(write(tmp_path, LHS.format(n=n, seed=1)))
    samp = {p.name: np.array(p.values) for p in spec.sampled_parameters}
    assert list(samp) == ["p_cohesion", "p_density", "p_tensile_strength"]
    assert all(len(v) == n for v in samp.values())
    c, rho, ft = samp["p_cohesion"], samp["p_density"], samp["p_tensile_strength"]
    # supports
    assert np.all(c > 0) and np.all((ft >= 1e4) & (ft <= 5e4))
    # stratified: one sample in each 1/n quantile bin, for each key (distribution functions from scipy)
    for x, F in ((c, stats.lognorm(s=0.3, scale=1e5).cdf), (rho, stats.norm(2000, 100).cdf),
                 (ft, stats.uniform(1e4, 4e4).cdf)):
        assert sorted(np.floor(F(x) * n).astype(int)) == list(range(n))
    # the keys are not sampled in the same order (one hypercube, independent columns)
    assert not np.array_equal(np.argsort(c), np.argsort(ft))
    # reproducible with the same seed, other samples with another
    again = load_ensemble(write(tmp_path, LHS.format(n=n, seed=1), name="again.toml"))
    assert [p.values for p in again.sampled_parameters] == [p.values for p in spec.sampled_parameters]
    other = load_ensemble(write(tmp_path, LHS.format(n=n, seed=2), name="other.toml"))
    assert not np.allclose(other.sampled_parameters[0].values, c)

    members = enumerate_members(spec)
    assert len(members) == 2 * 1 * 3 * n and spec.n_members == len(members)
    assert len({m.member_id for m in members}) == len(members)
    assert set(members[0].coords) == {"record", "intensity", "p_friction_angle", "sample"}
    assert [m.coords["sample"] for m in members[:n + 1]] == list(range(n)) + [0]
    for m in members:
        k = m.coords["sample"]
        assert m.scene["joints"]["joints"]["cohesion"] == c[k] == m.sampled["p_cohesion"]
        assert m.scene["materials"]["block"]["density"] == rho[k]
        assert m.scene["joints"]["joints"]["tensile_strength"] == ft[k]
    # the ids change with the samples (a new seed must not reuse stored results)
    assert {m.member_id for m in enumerate_members(other)}.isdisjoint({m.member_id for m in members})

    axes = member_axes(spec)
    assert list(axes) == ["record", "intensity", "p_friction_angle", "sample"]
    assert axes["sample"].values == list(range(n)) and axes["sample"].attrs["seed"] == 1
    assert axes["sample"].attrs["p_cohesion"] == pytest.approx(list(c))
    sc = sample_coordinates(spec)
    assert list(sc) == ["p_cohesion", "p_density", "p_tensile_strength"]
    assert sc["p_cohesion"].values == pytest.approx(list(c)) and sc["p_cohesion"].attrs["units"] == "Pa"
    assert sc["p_density"].attrs["units"] == "kg/m3"
    assert json.loads(sc["p_cohesion"].attrs["distribution"]) == {"type": "lognormal", "median": 1e5,
                                                                 "dispersion": 0.3}


# ------------------------------------------------------------------------------------------------
# measures
# ------------------------------------------------------------------------------------------------

def test_measures_of_a_member_run(tmp_path):
    pulse_record(tmp_path / "recs")
    text = """
[ensemble]
scene = "base.toml"
[axes.records]
files = ["recs/pulse.txt"]
[axes.intensity]
scale_to_pga = ["0.3 g"]
[[axes.parameters]]
key = "joints.joints.friction_angle"
values = [11.31]
"""
    spec = load_ensemble(write(tmp_path, text))
    (member,) = enumerate_members(spec)
    ds = masonrydam.run(Scene(member.scene, base_dir=member.base_dir))
    # the member ran its record at its intensity
    assert ds.attrs["stage1_ground_motion_x_pga_m_s2"] == pytest.approx(0.3 * G, rel=1e-12)
    m = member_measures(ds, spec)
    assert set(m) == {"peak_displacement", "peak_drift", "peak_slip_joints", "residual_slip_joints",
                      "peak_opening_joints", "residual_opening_joints", "cracked_ratio_joints", "energy_dissipated"}

    # the same numbers read directly from the result
    dyn = np.isfinite(ds.time.values)
    first = int(np.argmax(dyn))
    assert ds.time.values[first] == 0.0
    d = ds.isel(step=np.flatnonzero(dyn))
    ref = ds.isel(step=first)
    slip = abs(d.joint_slip - ref.joint_slip).isel(shear_direction=0)
    assert m["peak_slip_joints"] == pytest.approx(float(slip.max()), rel=1e-12)
    assert m["residual_slip_joints"] == pytest.approx(float(slip.isel(step=-1).max()), rel=1e-12)
    assert m["peak_opening_joints"] == pytest.approx(max(0.0, float((d.joint_opening - ref.joint_opening).max())))
    du = d.displacement - ref.displacement
    assert m["peak_displacement"] == pytest.approx(float(np.sqrt((du ** 2).sum("component")).max()), rel=1e-12)
    top, bottom = ds.y == ds.y.max(), ds.y == ds.y.min()
    dux = du.sel(component="x")
    drift = abs(dux.where(top).mean("node") - dux.where(bottom).mean("node")) / float(ds.y.max() - ds.y.min())
    assert m["peak_drift"] == pytest.approx(float(drift.max()), rel=1e-12)
    last = ds.isel(step=-1)
    w = last.joint_weight
    assert m["cracked_ratio_joints"] == pytest.approx(float(w.where(last.joint_state == 2, 0).sum() / w.sum()))
    e = float(last.energy_joint - last.energy_joint_stored + last.energy_damping + last.energy_numerical)
    assert m["energy_dissipated"] == pytest.approx(e, rel=1e-9)

    # the physics: Newmark's rigid block, A = 0.3 g, a_y = 0.2 g, t0 = 0.2 s: s = A (A - a_y) t0^2 / (2 a_y)
    s_newmark = 0.3 * 0.1 * 0.2 ** 2 / (2 * 0.2) * G
    assert 0.85 * s_newmark < m["residual_slip_joints"] < 1.15 * s_newmark
    assert m["peak_slip_joints"] >= m["residual_slip_joints"] > 0.02
    # the block (2 m x 0.5 m x 1 m, 2000 kg/m3) slides on mu = 0.2: friction work mu m g s
    mass = 2.0 * 0.5 * 1.0 * 2000.0
    assert m["energy_dissipated"] == pytest.approx(0.2 * mass * G * m["residual_slip_joints"], rel=0.01)
    assert m["peak_drift"] > 0.9 * m["residual_slip_joints"] / 0.75  # the top slid, the base did not
    assert m["cracked_ratio_joints"] == 0.0 and m["residual_opening_joints"] < 1e-4


def _fake_result():
    """A made-up result: 1 static and 4 dynamic steps, 3 nodes, two joint sets."""
    n_step = 5
    time = np.array([np.nan, 0.0, 0.1, 0.2, 0.3])
    disp = np.zeros((n_step, 3, 2))
    # top node (y = 2), x: the state at t = 0 (0.5) is the reference, not the last static step (0.45)
    disp[:, 2, 0] = [0.45, 0.5, 0.6, 0.9, 0.7]
    disp[:, 2, 1] = [-0.1, -0.1, -0.1, -0.5, -0.1]
    disp[:, 1, 0] = [0.2, 0.2, 0.25, 0.3, 0.2]  # a mid node (y = 1)
    slip = np.zeros((n_step, 4, 1))
    slip[:, :, 0] = [[0.05, 0.0, 1.0, 1.0], [0.0, 0.0, 1.0, 1.0], [0.1, -0.3, 1.0, 1.5],
                     [0.2, -0.1, 1.0, 1.0], [0.15, -0.05, 1.0, 1.2]]
    opening = np.zeros((n_step, 4))
    opening[:, 0] = [0.01, 0.01, 0.03, 0.02, 0.015]
    state = np.zeros((n_step, 4), dtype=np.int8)
    state[-1] = [2, 0, 2, 2]
    energy = {"energy_joint_dissipated": [np.nan, 0.0, 1.0, 3.0, 5.0], "energy_damping": [np.nan, 0.0, 0.5, 1.0, 2.0],
              "energy_numerical": [np.nan, 0.0, 0.1, 0.2, 0.25]}
    sf = np.array([[3.0, 2.5], [2.0, 2.5], [1.2, np.nan], [1.5, 1.1], [1.4, 1.3]])
    sf[0, 0] = 0.5  # a static step: not counted
    ds = xr.Dataset(
        {"displacement": (("step", "node", "component"), disp),
         "x": ("node", [0.0, 0.0, 0.0]), "y": ("node", [0.0, 1.0, 2.0]),
         "joint_slip": (("step", "joint_point", "shear_direction"), slip),
         "joint_opening": (("step", "joint_point"), opening),
         "joint_state": (("step", "joint_point"), state),
         "joint_weight": ("joint_point", [1.0, 3.0, 1.0, 1.0]),
         "joint_set": ("joint_point", np.array([0, 0, 1, 1], np.int32), {"set_names": '["bed", "head"]'}),
         "sliding_safety_factor": (("step", "section"), sf),
         **{k: ("step", np.array(v)) for k, v in energy.items()}},
        coords={"step": np.arange(n_step), "time": ("step", time), "component": ["x", "y"],
                "shear_direction": ["t"]})
    return ds


def test_measures_definitions_on_a_made_up_result():
    m = member_measures(_fake_result(), demand_sets=["bed", "head"])
    assert m["peak_displacement"] == pytest.approx(math.hypot(0.4, 0.4))
    assert m["peak_drift"] == pytest.approx(0.4 / 2.0)  # top +0.4 at t = 0.2, the bottom node never moves
    assert m["peak_slip_bed"] == pytest.approx(0.3) and m["residual_slip_bed"] == pytest.approx(0.15)
    assert m["peak_slip_head"] == pytest.approx(0.5) and m["residual_slip_head"] == pytest.approx(0.2)
    assert m["peak_opening_bed"] == pytest.approx(0.02) and m["residual_opening_bed"] == pytest.approx(0.005)
    assert m["peak_opening_head"] == 0.0
    assert m["cracked_ratio_bed"] == pytest.approx(1.0 / 4.0)  # weights 1 (open) and 3 (stick)
    assert m["cracked_ratio_head"] == pytest.approx(1.0)
    assert m["min_sliding_safety_factor"] == pytest.approx(1.1)
    assert m["energy_dissipated"] == pytest.approx(5.0 + 2.0 + 0.25)
    # a set that is not in the result gives NaN; without a reservoir assessment no sliding factor
    ds = _fake_result().drop_vars("sliding_safety_factor")
    m2 = member_measures(ds, demand_sets=["lift"])
    assert math.isnan(m2["peak_slip_lift"]) and "min_sliding_safety_factor" not in m2
    # units and long names for the dataset
    assert measure_attrs("peak_slip_bed") == {"units": "m", "long_name": "peak slip of joint set bed (max over its "
                                                                        "points)"}
    assert measure_attrs("energy_dissipated")["units"] == "J" and MEASURES["peak_drift"][0] == "1"


# ------------------------------------------------------------------------------------------------
# errors
# ------------------------------------------------------------------------------------------------

def _error(tmp_path, text, base=BASE) -> SceneError:
    with pytest.raises(SceneError) as info:
        load_ensemble(write(tmp_path, text, base))
    return info.value


HEAD = """
[ensemble]
scene = "base.toml"
[axes.records]
names = ["elcentro_1940_ns_peknold"]
[axes.intensity]
scale_to_pga = ["0.2 g"]
"""


def test_error_missing_base_scene(tmp_path):
    exc = _error(tmp_path, HEAD.replace("base.toml", "nowhere.toml"))
    assert exc.key == "ensemble.scene" and "nowhere.toml" in str(exc) and "does not exist" in str(exc)


def test_error_unknown_swept_key(tmp_path):
    text = HEAD + """
[[axes.parameters]]
key = "joints.joints.cohesion"
values = [0.0]
[[axes.parameters]]
key = "joints.joints.frction_angle"
values = [30]
"""
    exc = _error(tmp_path, text)
    assert exc.key == "axes.parameters[1].key"
    assert "joints.joints.frction_angle" in str(exc) and "did you mean 'friction_angle'" in str(exc)
    # a joint set the base scene does not have
    exc = _error(tmp_path, HEAD + '[[axes.parameters]]\nkey = "joints.bed.friction_angle"\nvalues = [30]\n')
    assert exc.key == "axes.parameters[0].key" and "the base scene has no 'joints.bed'" in str(exc)
    # a list index the scene does not have
    exc = _error(tmp_path, HEAD + '[[axes.parameters]]\nkey = "stages[5].dt"\nvalues = [0.01]\n')
    assert exc.key == "axes.parameters[0].key" and "index [5]" in str(exc)
    # a bad value names the value
    exc = _error(tmp_path, HEAD + '[[axes.parameters]]\nkey = "joints.joints.cohesion"\nvalues = [0.0, -5]\n')
    assert exc.key == "axes.parameters[0].values[1]" and "joints.joints.cohesion" in str(exc)
    # the record and the intensity are axes of their own
    exc = _error(tmp_path, HEAD + '[[axes.parameters]]\nkey = "stages[1].ground_motion.x.scale_to_pga"\n'
                                  'values = [1.0]\n')
    assert exc.key == "axes.parameters[0].key" and "[axes.intensity]" in str(exc)


def test_error_records(tmp_path):
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "readme.md").write_text("no records here")
    exc = _error(tmp_path, HEAD.replace('names = ["elcentro_1940_ns_peknold"]', 'folder = "empty"'))
    assert exc.key == "axes.records.folder" and "holds no record files" in str(exc)
    exc = _error(tmp_path, HEAD.replace('names = ["elcentro_1940_ns_peknold"]', 'folder = "missing"'))
    assert exc.key == "axes.records.folder" and "does not exist" in str(exc)
    exc = _error(tmp_path, HEAD.replace('"elcentro_1940_ns_peknold"]',
                                        '"elcentro_1940_ns_peknold", "elcentro_194_ns"]'))
    assert exc.key == "axes.records.names[1]" and "unknown record 'elcentro_194_ns'" in str(exc)
    assert "did you mean" in str(exc)
    exc = _error(tmp_path, HEAD.replace('"elcentro_1940_ns_peknold"]', '"elcentro_1940_ns_peer_displacement"]'))
    assert exc.key == "axes.records.names[0]" and "displacement" in str(exc)
    exc = _error(tmp_path, HEAD.replace('names = ["elcentro_1940_ns_peknold"]', 'files = ["nofile.AT2"]'))
    assert exc.key == "axes.records.files[0]" and "does not exist" in str(exc)
    (tmp_path / "nounits.txt").write_text("\n".join(["0.1", "0.2", "0.1"]) + "\n")
    exc = _error(tmp_path, HEAD.replace('names = ["elcentro_1940_ns_peknold"]', 'files = ["nounits.txt"]'))
    assert exc.key == "axes.records.files[0]" and "axes.records." in str(exc)  # asks for axes.records.units/dt


def test_error_base_scene_without_dynamic_stage(tmp_path):
    static = BASE[:BASE.index('[[stages]]\nname = "shake"')]
    exc = _error(tmp_path, HEAD, base=static)
    assert exc.key == "ensemble.scene" and "no dynamic stage" in str(exc)
    exc = _error(tmp_path, HEAD.replace('scene = "base.toml"', 'scene = "base.toml"\nstage = 0'))
    assert exc.key == "ensemble.stage" and "static, not dynamic" in str(exc)
    exc = _error(tmp_path, HEAD.replace('scene = "base.toml"', 'scene = "base.toml"\nstage = 4'))
    assert exc.key == "ensemble.stage"


@pytest.mark.parametrize("dist, key, words", [
    ('{ type = "lognormal", median = "0.1 MPa", dispersion = -0.3 }', "distribution.dispersion", "> 0"),
    ('{ type = "lognormal", median = 0, dispersion = 0.3 }', "distribution.median", "> 0"),
    ('{ type = "normal", mean = 1e5, std = 0 }', "distribution.std", "> 0"),
    ('{ type = "uniform", low = "50 kPa", high = "10 kPa" }', "distribution.high", "larger than low"),
    ('{ type = "beta", a = 1 }', "distribution.type", "lognormal"),
    ('{ type = "normal", mean = 1e5 }', "distribution.std", "required"),
    ('{ type = "uniform", low = "1 kPa", high = "2 mm" }', "distribution", "different kinds"),
    # valid parameters, but samples the scene refuses (negative cohesion)
    ('{ type = "normal", mean = 1e3, std = 1e4 }', "distribution", "sample"),
])
def test_error_bad_distributions(tmp_path, dist, key, words):
    text = HEAD + f'[[axes.parameters]]\nkey = "joints.joints.cohesion"\ndistribution = {dist}\n' \
                  "[axes.sampling]\nsamples = 20\nseed = 3\n"
    exc = _error(tmp_path, text)
    assert exc.key == f"axes.parameters[0].{key}" and words in str(exc)


def test_error_other_inputs(tmp_path):
    exc = _error(tmp_path, HEAD + '[[axes.parameters]]\nkey = "joints.joints.cohesion"\n'
                                  'distribution = { type = "uniform", low = 0, high = 1e3 }\n')
    assert exc.key == "axes.sampling.samples"
    exc = _error(tmp_path, HEAD + "[axes.sampling]\nsamples = 4\n")
    assert exc.key == "axes.sampling" and "no parameter is sampled" in str(exc)
    exc = _error(tmp_path, HEAD.replace('["0.2 g"]', '["0.2 g", "-0.1 g"]'))
    assert exc.key == "axes.intensity.scale_to_pga[1]"
    exc = _error(tmp_path, HEAD.replace('["0.2 g"]', '["0.2 g", "0.2 g"]'))
    assert exc.key == "axes.intensity.scale_to_pga[1]" and "repeats" in str(exc)
    exc = _error(tmp_path, HEAD.replace('["0.2 g"]', '["0.2 MPa"]'))
    assert exc.key == "axes.intensity.scale_to_pga[0]"
    exc = _error(tmp_path, HEAD.replace('scale_to_pga = ["0.2 g"]', "scale_to_sa = { values = [1.0] }"))
    assert exc.key == "axes.intensity.scale_to_sa.period"
    exc = _error(tmp_path, HEAD.replace("[axes.intensity]\nscale_to_pga", "[axes.intensity]\nscale_to_pgv"))
    assert exc.key == "axes.intensity.scale_to_pgv" and "scale_to_pga" in str(exc)
    exc = _error(tmp_path, HEAD.replace('scene = "base.toml"', 'scene = "base.toml"\ndemand_sets = ["bed"]'))
    assert exc.key == "ensemble.demand_sets[0]" and "joints" in str(exc)
    exc = _error(tmp_path, HEAD.replace('scene = "base.toml"', 'scene = "base.toml"\ncomponent = "z"'))
    assert exc.key == "ensemble.component"
    exc = _error(tmp_path, HEAD + '[[axes.parameters]]\nkey = "joints.joints.cohesion"\nvalues = [0.0]\n'
                                  '[[axes.parameters]]\nkey = "joints.joints.cohesion"\nvalues = [1.0]\n')
    assert exc.key == "axes.parameters[1].key" and "already swept" in str(exc)
