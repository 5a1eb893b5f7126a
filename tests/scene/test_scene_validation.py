"""Scene validation: implausible magnitudes (unit slips), NaN and infinity, NumPy
values from Python, and ``masonrydam check`` finding the mechanisms that ``run`` finds.

Plausible ranges (masonrydam/units.py, PLAUSIBLE) lie orders of magnitude beyond real values:
Young's modulus of masonry and concrete 1-50 GPa, steel 210 GPa (so 1e30 Pa, or '30e9 MPa', is a
slip); joint stiffnesses 1e9-1e13 N/m3 (Lourenco & Rots 1997: kn = 82 N/mm3 = 8.2e10 N/m3, so 82
is N/mm3 typed as N/m3); joint cohesion and tensile strength kPa to a few MPa; seismic time steps
0.0001-0.05 s (so dt = 5 is milliseconds typed as seconds); gravity 9.81 m/s2 (981 is cm/s2).
"""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import MechanismError, SceneError
from masonrydam.scene.scene import Scene
from masonrydam.scene.schema import normalize
from masonrydam.units import PLAUSIBLE, SI_UNIT, plausible
from test_scene_errors import BASE_TOML, base_scene, expect_scene_error, modified

G = 9.80665


def with_dynamic_stage(scene: dict, **stage) -> dict:
    """``scene`` with a dynamic stage (a short rectangular pulse) after its static stages."""
    dyn = {"name": "shake", "type": "dynamic", "dt": 0.002, "duration": 0.01,
           "ground_motion": {"x": {"pulse": {"shape": "rectangular", "amplitude": "0.1 g", "duration": 0.005}}}}
    dyn.update(stage)
    scene["stages"].append(dyn)
    return scene


# ------------------------------------------------------------------------------------------------
# implausible magnitudes: the key and the likely unit slip are named
# ------------------------------------------------------------------------------------------------
def test_youngs_modulus_1e30_is_rejected_with_a_unit_hint(tmp_path, no_solve):
    err = expect_scene_error(modified(materials__units__youngs_modulus=1e30), tmp_path,
                             "materials.units.youngs_modulus")
    assert "implausibly large" in str(err) and "unit" in str(err)


@pytest.mark.parametrize("edits,key,words", [
    ({"materials__units__youngs_modulus": "30e9 MPa"}, "materials.units.youngs_modulus", ["'30e9 MPa'", "unit"]),
    ({"materials__units__youngs_modulus": 16700}, "materials.units.youngs_modulus", ["'16700 MPa'"]),
    ({"materials__units__density": 1.8}, "materials.units.density", ["t/m3"]),
    ({"materials__units__density": 18000.0}, "materials.units.density", ["N/m3"]),
    ({"joints__bed_joints__normal_stiffness": 82}, "joints.bed_joints.normal_stiffness", ["as N/m3", "'82 N/mm3'"]),
    ({"joints__head_joints__shear_stiffness": "36e9 N/mm3"}, "joints.head_joints.shear_stiffness", ["unit"]),
    ({"joints__bed_joints__cohesion": 1e12}, "joints.bed_joints.cohesion", ["MPa", "another unit"]),
    ({"joints__bed_joints__tensile_strength": "5e4 MPa"}, "joints.bed_joints.tensile_strength", ["unit"]),
    ({"model__thickness": 1e5}, "model.thickness", ["mm as m"]),
    ({"mesh__parameters__length": "4e7 mm"}, "mesh.parameters.length", ["implausibly large"]),
    ({"mesh__parameters__unit_height": 2e5}, "mesh.parameters.unit_height", ["mm as m"]),
    ({"model__gravity": [0.0, -981.0]}, "model.gravity[1]", ["cm/s2"]),
])
def test_implausible_values_name_key_and_slip(tmp_path, no_solve, edits, key, words):
    err = expect_scene_error(modified(**edits), tmp_path, key)
    for w in words:
        assert w in str(err), str(err)


@pytest.mark.parametrize("stage,key,words", [
    ({"dt": 5}, "stages[2].dt", ["milliseconds as seconds", "'5 ms'"]),
    ({"dt": "5000 ms"}, "stages[2].dt", ["'5000 ms'"]),
    ({"ground_motion": {"x": {"pulse": {"shape": "rectangular", "amplitude": 981.0, "duration": 0.005}}}},
     "stages[2].ground_motion.x.pulse.amplitude", ["cm/s2"]),
    ({"ground_motion": {"x": {"record": "elcentro_1940_ns_peknold", "scale_to_pga": 300.0}}},
     "stages[2].ground_motion.x.scale_to_pga", ["cm/s2"]),
    ({"ground_motion": {"x": {"values": [0.0, 1.0, 0.0], "dt": 20}}}, "stages[2].ground_motion.x.dt", ["ms"]),
])
def test_implausible_dynamic_values(tmp_path, no_solve, stage, key, words):
    err = expect_scene_error(with_dynamic_stage(base_scene(), **stage), tmp_path, key)
    for w in words:
        assert w in str(err), str(err)


def test_generous_bounds_accept_real_and_idealised_values(no_solve):
    """Rigid-block idealisations (E = 1e14 Pa, kn = 1e15 N/m3), strong real values and tilted or
    amplified gravity all stay valid."""
    s = modified(materials__units__youngs_modulus=1e14, materials__units__density="7.85 t/m3",
                 joints__bed_joints__normal_stiffness=1e15, joints__bed_joints__shear_stiffness="1 MN/m3",
                 joints__bed_joints__cohesion="10 MPa", joints__bed_joints__tensile_strength=0.0,
                 model__thickness="3 m", model__gravity=[0.7 * G, -G])
    n = Scene(with_dynamic_stage(s, dt="0.5 ms")).normalized
    assert n["materials"]["units"]["youngs_modulus"] == 1e14
    assert n["joints"]["bed_joints"]["shear_stiffness"] == 1e6
    assert n["stages"][2]["dt"] == pytest.approx(5e-4)
    Scene(with_dynamic_stage(base_scene(), dt=0.02, ground_motion={"x": {"pulse": {
        "shape": "half_sine", "amplitude": "2 g", "duration": 0.1}}}))


@pytest.mark.parametrize("pattern", sorted(PLAUSIBLE))
def test_every_plausible_range_rejects_outside_with_its_key(pattern):
    """Each entry of the one table: a value beyond its bounds is a SceneError naming the key, with
    a message that formats (its hint included), both for a plain number and one with a unit."""
    rng = PLAUSIBLE[pattern]
    key = pattern.replace("*", "x").replace("stages.", "stages[1].")
    unit = SI_UNIT[rng.dimension]
    for v in [b for b in ((rng.low or 0.0) / 10.0, (rng.high or 0.0) * 10.0) if b > 0]:
        for given in (v, f"{v!r} {unit}"):
            with pytest.raises(SceneError) as ei:
                plausible(v, rng.dimension, key, given)
            assert ei.value.key == key and "implausibly" in str(ei.value) and "{" not in str(ei.value)
        mid = rng.low if rng.low is not None else rng.high
        assert plausible(mid, rng.dimension, key) == mid


# ------------------------------------------------------------------------------------------------
# NaN and infinity (TOML has nan and inf literals)
# ------------------------------------------------------------------------------------------------
DISPLACEMENT_STAGE = """
[[stages]]
name = "push"
[[stages.loads]]
type = "displacement"
set = "top"
components = ["x"]
value = [{v}]
"""

DYNAMIC_STAGE = """
[[stages]]
name = "shake"
type = "dynamic"
dt = {v}
duration = 0.01
ground_motion = { x = { pulse = { shape = "rectangular", amplitude = "0.1 g", duration = 0.005 } } }
"""


def toml_with(tmp_path, edit: str, value: str):
    text = BASE_TOML.replace("{phi}", "36.87")
    if edit == "gravity":
        text = text.replace('thickness = "100 mm"', f'thickness = "100 mm"\ngravity = [0.0, {value}]')
    elif edit == "thickness":
        text = text.replace('thickness = "100 mm"', f"thickness = {value}")
    elif edit == "length":
        text = text.replace("length = 0.4", f"length = {value}")
    elif edit == "cohesion":
        text = text.replace("friction_angle = 36.87", f"friction_angle = 36.87\ncohesion = {value}")
    elif edit == "friction_angle":
        text = BASE_TOML.replace("{phi}", value)
    elif edit == "poisson_ratio":
        text = text.replace("poisson_ratio = 0.15", f"poisson_ratio = {value}")
    elif edit == "factor":
        text = text.replace('type = "self_weight"', f'type = "self_weight"\nfactor = {value}')
    elif edit == "displacement":
        text += DISPLACEMENT_STAGE.replace("{v}", value)
    elif edit == "dt":
        text += DYNAMIC_STAGE.replace("{v}", value)
    elif edit == "force_tolerance":
        text += f"\n[solver]\nforce_tolerance = {value}\n"
    p = tmp_path / "scene.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("edit,value,key", [
    ("gravity", "nan", "model.gravity[1]"),
    ("gravity", "-inf", "model.gravity[1]"),
    ("gravity", "'1e999 m/s2'", "model.gravity[1]"),
    ("thickness", "inf", "model.thickness"),
    ("length", "nan", "mesh.parameters.length"),
    ("cohesion", "inf", "joints.bed_joints.cohesion"),
    ("cohesion", "nan", "joints.bed_joints.cohesion"),
    ("friction_angle", "nan", "joints.bed_joints.friction_angle"),
    ("poisson_ratio", "nan", "materials.units.poisson_ratio"),
    ("factor", "nan", "stages[0].loads[0].factor"),
    ("factor", "inf", "stages[0].loads[0].factor"),
    ("displacement", "nan", "stages[1].loads[0].value[0]"),
    ("displacement", "-inf", "stages[1].loads[0].value[0]"),
    ("dt", "nan", "stages[1].dt"),
    ("dt", "inf", "stages[1].dt"),
    ("force_tolerance", "nan", "solver.force_tolerance"),
])
def test_nan_and_inf_from_toml_name_the_key(tmp_path, no_solve, edit, value, key):
    with pytest.raises(SceneError) as ei:
        Scene.from_toml(toml_with(tmp_path, edit, value))
    assert ei.value.key == key, str(ei.value)
    assert "nan" in str(ei.value) or "inf" in str(ei.value) or "1e999" in str(ei.value)


def test_cli_check_nan_gravity_exit_code_2(tmp_path, capsys, no_solve):
    assert main(["check", str(toml_with(tmp_path, "gravity", "nan"))]) == 2
    _, err = capsys.readouterr()
    assert "scene key 'model.gravity[1]'" in err and "finite" in err and "Traceback" not in err


@pytest.mark.parametrize("gravity", ["9.81", [0.0, -9.81, 0.0], [0.0], {"y": -9.81}])
def test_gravity_of_wrong_shape_names_model_gravity(tmp_path, no_solve, gravity):
    err = expect_scene_error(modified(model__gravity=gravity), tmp_path, "model.gravity")
    assert "list of 2 values" in str(err)


def extruded_scene(generator="masonry_wall_2d", depth=0.1, **inner):
    s = base_scene()
    s["model"] = {"dimension": 3}
    params = dict(base_scene()["mesh"]["parameters"], **inner)
    s["mesh"] = {"generator": "extruded", "parameters": {"generator": generator, "parameters": params, "depth": depth}}
    return s


def blocks_scene(**corner):
    s = base_scene()
    blocks = [{"x0": 0.0, "y0": 0.0, "x1": 1.0, "y1": 0.5, "group": "units"},
              dict({"x0": 0.0, "y0": 0.5, "x1": 1.0, "y1": 1.0, "group": "units"}, **corner)]
    s["mesh"] = {"generator": "blocks_2d", "parameters": {"blocks": blocks, "element_size": 0.5}}
    return s


@pytest.mark.parametrize("scene,key", [
    (extruded_scene(length=float("inf")), "mesh.parameters.parameters.length"),
    (extruded_scene(unit_height=float("nan")), "mesh.parameters.parameters.unit_height"),
    (extruded_scene(length=1e5), "mesh.parameters.parameters.length"),
    (extruded_scene(depth=float("nan")), "mesh.parameters.depth"),
    (extruded_scene(generator="masonry_wall_3d"), "mesh.parameters.generator"),
    (blocks_scene(x1=float("inf")), "mesh.parameters.blocks[1].x1"),
    (blocks_scene(y1=float("nan")), "mesh.parameters.blocks[1].y1"),
    (blocks_scene(y1=1e30), "mesh.parameters.blocks[1].y1"),
])
def test_generator_numbers_finite_and_plausible(tmp_path, no_solve, scene, key):
    """Numbers the generators read themselves (block corners, the 2D parameters inside 'extruded')
    are checked like the others, before any meshing."""
    expect_scene_error(scene, tmp_path, key)


def test_nan_in_python_dict_and_in_unit_string(tmp_path, no_solve):
    expect_scene_error(modified(model__gravity=[0.0, float("nan")]), tmp_path, "model.gravity[1]")
    expect_scene_error(modified(joints__bed_joints__normal_stiffness="1e999 N/mm3"), tmp_path,
                       "joints.bed_joints.normal_stiffness", match="finite")
    expect_scene_error(modified(materials__units__youngs_modulus=10 ** 400), tmp_path,
                       "materials.units.youngs_modulus")


# ------------------------------------------------------------------------------------------------
# NumPy values from Python
# ------------------------------------------------------------------------------------------------
def numpy_scene(plain: bool) -> dict:
    """base_scene() with NumPy values (``plain=False``) or the plain values they hold."""
    conv = (lambda x: x.tolist() if isinstance(x, np.ndarray) else x.item()) if plain else (lambda x: x)
    s = base_scene()
    s["model"]["thickness"] = conv(np.array(0.1))  # 0-d array
    s["model"]["gravity"] = conv(np.array([0.0, -G]))
    s["model"]["hypothesis"] = conv(np.str_("plane_stress"))
    s["mesh"]["parameters"]["elements_per_unit"] = conv(np.int32(1))
    s["mesh"]["parameters"]["length"] = conv(np.float64(0.4))
    s["materials"]["units"]["youngs_modulus"] = conv(np.float32(16.7e9))
    s["materials"]["units"]["poisson_ratio"] = conv(np.float64(0.15))
    s["joints"]["bed_joints"]["points"] = conv(np.int64(2))
    s["joints"]["bed_joints"]["integration"] = "gauss"
    s["stages"][0]["steps"] = conv(np.int64(3))
    s["stages"][0]["loads"][0]["factor"] = conv(np.float32(0.5))
    s["stages"][1]["loads"].append({"type": "displacement", "set": "top", "components": ["x"],
                                    "value": conv(np.array([1e-4]))})
    s["solver"] = {"line_search": conv(np.bool_(False)), "max_iterations": conv(np.uint8(20))}
    s["output"] = {"nodes": conv(np.array(["top"]))}
    return s


def test_numpy_values_give_the_same_scene_as_plain_values(no_solve):
    a, b = Scene(numpy_scene(plain=False)), Scene(numpy_scene(plain=True))
    assert a.normalized == b.normalized
    assert a.hash == b.hash
    assert a.normalized["stages"][0]["steps"] == 3 and type(a.normalized["stages"][0]["steps"]) is int
    assert a.normalized["solver"]["line_search"] is False
    assert a.normalized["materials"]["units"]["youngs_modulus"] == float(np.float32(16.7e9))
    assert normalize(numpy_scene(plain=False)) == b.normalized
    # the raw copy is plain too (no NumPy object in Scene.data)
    assert type(a.data["stages"][0]["steps"]) is int and a.data["model"]["gravity"] == [0.0, -G]


def test_numpy_steps_run_like_plain_steps(tmp_path):
    s = base_scene()
    s["stages"] = [dict(s["stages"][0], steps=np.int64(2))]
    ds = masonrydam.run(s, output=tmp_path / "np.nc")
    assert ds.sizes["step"] == 2


@pytest.mark.parametrize("edits,key", [
    ({"stages__0__steps": np.int64(0)}, "stages[0].steps"),
    ({"stages__0__steps": np.float64(2.0)}, "stages[0].steps"),
    ({"model__thickness": np.float64(-0.1)}, "model.thickness"),
    ({"model__thickness": np.array(np.inf)}, "model.thickness"),
    ({"model__gravity": np.array([0.0, np.nan])}, "model.gravity[1]"),
    ({"model__gravity": np.array([0.0, -9.81, 0.0])}, "model.gravity"),
    ({"model__hypothesis": np.str_("axisymmetric")}, "model.hypothesis"),
    ({"materials__units__poisson_ratio": np.float32(0.7)}, "materials.units.poisson_ratio"),
    ({"materials__units__youngs_modulus": np.float64(1e30)}, "materials.units.youngs_modulus"),
    ({"joints__bed_joints__friction_angle": np.float64(95.0)}, "joints.bed_joints.friction_angle"),
    ({"solver": {"line_search": np.int64(1)}}, "solver.line_search"),
    ({"solver": {"force_tolerance": np.float64(2.0)}}, "solver.force_tolerance"),
    ({"mesh__parameters__bond": np.array(["running"])}, "mesh.parameters.bond"),
])
def test_numpy_errors_show_no_numpy_repr(tmp_path, no_solve, edits, key):
    err = expect_scene_error(modified(**edits), tmp_path, key)
    assert "np." not in str(err) and "array(" not in str(err) and "float64" not in str(err), str(err)


# ------------------------------------------------------------------------------------------------
# `masonrydam check` finds the mechanisms that `run` finds
# ------------------------------------------------------------------------------------------------
FLOATING_BLOCK_TOML = """
[model]
name = "floating_block"

[mesh]
generator = "blocks_2d"
[mesh.parameters]
element_size = 0.25
blocks = [{ x0 = 0.0, y0 = 0.0, x1 = 1.0, y1 = 0.5, group = "base" },
          { x0 = 0.0, y0 = 0.5, x1 = 1.0, y1 = 1.0, group = "block" },
          { x0 = 2.0, y0 = 2.0, x1 = 2.5, y1 = 2.5, group = "loose" }]

[materials.base]
youngs_modulus = "20 GPa"
poisson_ratio = 0.2
density = 2000
[materials.block]
youngs_modulus = "20 GPa"
poisson_ratio = 0.2
density = 2000
[materials.loose]
youngs_modulus = "20 GPa"
poisson_ratio = 0.2
density = 2000

[joints.joints]
normal_stiffness = 1e11
shear_stiffness = 1e11
friction_angle = 30.0

[[supports]]
set = "base"

[[stages]]
name = "gravity"
[[stages.loads]]
type = "self_weight"
"""


def mechanism_scenes(tmp_path):
    no_supports = tmp_path / "no_supports.toml"
    no_supports.write_text(BASE_TOML.replace("{phi}", "36.87").replace('[[supports]]\nset = "base"\n', ""))
    floating = tmp_path / "floating.toml"
    floating.write_text(FLOATING_BLOCK_TOML)
    return {"no_supports": (no_supports, "units"), "floating": (floating, "loose")}


@pytest.mark.parametrize("case", ["no_supports", "floating"])
def test_check_reports_the_mechanism_that_run_reports(tmp_path, capsys, case):
    path, group = mechanism_scenes(tmp_path)[case]
    with pytest.raises(MechanismError) as ei:
        masonrydam.run(path)
    run_msg = str(ei.value)
    assert "before solving" in run_msg and group in run_msg and "no support" in run_msg
    capsys.readouterr()
    assert main(["check", str(path)]) == 2
    out, err = capsys.readouterr()
    assert f"masonrydam: error: {run_msg}" in err
    assert "is valid" not in out and "Traceback" not in err


def test_check_finds_the_mechanism_without_solving(tmp_path, capsys, no_solve):
    path, _ = mechanism_scenes(tmp_path)["floating"]
    assert main(["check", str(path)]) == 2
    _, err = capsys.readouterr()
    assert "stage 'gravity': the model is a mechanism before solving" in err
    # with the loose block removed the same scene is valid
    text = FLOATING_BLOCK_TOML.replace(',\n          { x0 = 2.0, y0 = 2.0, x1 = 2.5, y1 = 2.5, group = "loose" }', "")
    text = text.replace('[materials.loose]\nyoungs_modulus = "20 GPa"\npoisson_ratio = 0.2\ndensity = 2000\n', "")
    path.write_text(text)
    assert main(["check", str(path)]) == 0
    out, _ = capsys.readouterr()
    assert "is valid" in out
