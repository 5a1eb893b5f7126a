"""Scene validation: every bad input is a SceneError whose ``key`` names the offending entry, raised
before anything is solved (masonrydam.errors.SceneError, masonrydam/scene/schema.py, docs/scene_guide.md "A scene
is a TOML file ...": numbers are SI, strings with units are accepted, a unit of the wrong kind is an
error that names the key).

Physical admissibility limits asserted here:
- Poisson's ratio of an isotropic elastic solid lies in (-1, 0.5) (positive-definite strain energy;
  0.5 is incompressible and makes the plane-strain D matrix singular), e.g. Timoshenko & Goodier,
  Theory of Elasticity, or any elasticity text;
- Mohr-Coulomb friction angle in [0, 90) deg (tan(phi) finite, Tzamtzis & Asteris sec. 3.4, eq. 12);
- joint stiffnesses kn, ks > 0 and residual (hardening) shear stiffness below the elastic ks
  (Tzamtzis & Asteris sec. 3.4; docs/method.md);
- a linear joint has no strength parameters (docs/scene_guide.md: law 'linear');
- Young's modulus of masonry units / concrete is O(1-100) GPa (Lourenco & Rots 1997: 16.7 GPa for
  the Eindhoven units), so 16700 in a SI file is a forgotten 'MPa'.
"""
from __future__ import annotations

import copy

import pytest

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import SceneError
from masonrydam.scene.scene import Scene
from masonrydam.scene.schema import normalize
from masonrydam.units import quantity


def base_scene() -> dict:
    """A 3-course, 2-unit running-bond wall (units 0.2 x 0.1 m), one element per unit height."""
    return {
        "model": {"name": "tiny_wall", "hypothesis": "plane_stress", "thickness": 0.1},
        "mesh": {"generator": "masonry_wall_2d",
                 "parameters": {"length": 0.4, "height": 0.3, "unit_length": 0.2, "unit_height": 0.1,
                                "bond": "running", "elements_per_unit": 1}},
        "materials": {"units": {"youngs_modulus": "16.7 GPa", "poisson_ratio": 0.15, "density": 1800}},
        "joints": {
            "bed_joints": {"law": "mohr_coulomb", "normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3",
                           "cohesion": 0.0, "friction_angle": 36.87, "residual_shear_stiffness": 0.0},
            "head_joints": {"law": "linear", "normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3"},
        },
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": [
            {"name": "gravity", "steps": 1, "loads": [{"type": "self_weight"}]},
            {"name": "press", "steps": 1, "loads": [{"type": "edge_pressure", "set": "top_edge", "pressure": "0.1 MPa"}]},
        ],
    }


def expect_scene_error(scene, tmp_path, key, match=None):
    """Run ``scene``; it must raise SceneError with ``.key == key`` before solving and before any
    result file is created."""
    out = tmp_path / "never.nc"
    with pytest.raises(SceneError) as ei:
        masonrydam.run(scene, output=out)
    err = ei.value
    assert err.key == key, f"expected key {key!r}, got {err.key!r} ({err})"
    assert f"scene key '{key}'" in str(err)
    if match is not None:
        assert match in str(err), str(err)
    assert not out.exists(), "no result file may be created for an invalid scene"
    return err


def modified(**edits):
    """base_scene() with edits given as dotted paths -> value (value None deletes the entry)."""
    s = base_scene()
    for path, value in edits.items():
        *parents, last = path.split("__")
        d = s
        for p in parents:
            d = d[int(p)] if isinstance(d, list) else d[p]
        if value is None:
            del d[last]
        else:
            d[last] = value
    return s


def test_base_scene_is_valid(no_solve):
    sc = Scene(base_scene())
    assert sc.normalized["model"]["thickness"] == 0.1
    from masonrydam.scene import build_mesh, build_model, build_stages

    mesh = build_mesh(sc.normalized, sc.base_dir)
    model = build_model(sc.normalized, mesh)
    assert len(build_stages(sc.normalized, mesh, model)) == 2


# ------------------------------------------------------------------------------------------------
# unknown keys
# ------------------------------------------------------------------------------------------------
def test_unknown_top_level_key(tmp_path, no_solve):
    s = base_scene()
    s["materals"] = {}
    err = expect_scene_error(s, tmp_path, "materals")
    assert "did you mean 'materials'" in str(err)


def test_unknown_top_level_key_without_close_match_lists_known_keys(tmp_path, no_solve):
    s = base_scene()
    s["zzz"] = 1
    err = expect_scene_error(s, tmp_path, "zzz")
    assert "known keys" in str(err) and "stages" in str(err)


@pytest.mark.parametrize("path,typo,suggestion", [
    (("joints", "bed_joints"), "frction_angle", "friction_angle"),
    (("model",), "thicknes", "thickness"),
    (("materials", "units"), "poison_ratio", "poisson_ratio"),
    (("mesh", "parameters"), "elements_per_uni", "elements_per_unit"),
])
def test_unknown_nested_key_with_suggestion(tmp_path, no_solve, path, typo, suggestion):
    s = base_scene()
    d = s
    for p in path:
        d = d[p]
    d[typo] = 1
    err = expect_scene_error(s, tmp_path, ".".join(path + (typo,)))
    assert f"did you mean '{suggestion}'" in str(err)


def test_unknown_key_in_a_load(tmp_path, no_solve):
    s = base_scene()
    s["stages"][0]["loads"][0]["factr"] = 2.0
    err = expect_scene_error(s, tmp_path, "stages[0].loads[0].factr")
    assert "did you mean 'factor'" in str(err)


# ------------------------------------------------------------------------------------------------
# out-of-range values
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("edits,key", [
    ({"joints__bed_joints__normal_stiffness": -1.0e10}, "joints.bed_joints.normal_stiffness"),
    ({"joints__bed_joints__shear_stiffness": "-36 N/mm3"}, "joints.bed_joints.shear_stiffness"),
    ({"joints__head_joints__normal_stiffness": 0.0}, "joints.head_joints.normal_stiffness"),
    ({"joints__bed_joints__friction_angle": 90}, "joints.bed_joints.friction_angle"),
    ({"joints__bed_joints__friction_angle": -1}, "joints.bed_joints.friction_angle"),
    ({"joints__bed_joints__friction_angle": "90 deg"}, "joints.bed_joints.friction_angle"),
    ({"joints__bed_joints__friction_angle": float("nan")}, "joints.bed_joints.friction_angle"),
    ({"joints__bed_joints__cohesion": -1.0}, "joints.bed_joints.cohesion"),
    ({"joints__bed_joints__tensile_strength": -1.0}, "joints.bed_joints.tensile_strength"),
    ({"model__thickness": 0}, "model.thickness"),
    ({"model__thickness": -0.1}, "model.thickness"),
    ({"model__thickness": float("inf")}, "model.thickness"),
    ({"materials__units__poisson_ratio": 0.5}, "materials.units.poisson_ratio"),
    ({"materials__units__poisson_ratio": -1.0}, "materials.units.poisson_ratio"),
    ({"materials__units__poisson_ratio": "0.2"}, "materials.units.poisson_ratio"),
    ({"materials__units__density": -1.0}, "materials.units.density"),
    ({"materials__units__youngs_modulus": float("nan")}, "materials.units.youngs_modulus"),
    ({"materials__units__youngs_modulus": None}, "materials.units.youngs_modulus"),
    ({"stages__0__steps": 0}, "stages[0].steps"),
    ({"model__hypothesis": "axisymmetric"}, "model.hypothesis"),
    ({"joints__bed_joints__law": "coulomb"}, "joints.bed_joints.law"),
    ({"joints__bed_joints__friction_angle": None}, "joints.bed_joints.friction_angle"),
])
def test_out_of_range_values(tmp_path, no_solve, edits, key):
    expect_scene_error(modified(**edits), tmp_path, key)


def test_implausible_youngs_modulus_suggests_mpa(tmp_path, no_solve):
    err = expect_scene_error(modified(materials__units__youngs_modulus=16700), tmp_path,
                             "materials.units.youngs_modulus")
    assert "MPa" in str(err)


def test_density_far_too_large(tmp_path, no_solve):
    # 18 kN/m3 x g: a unit weight multiplied by g once more
    err = expect_scene_error(modified(materials__units__density=18000.0 * 9.81), tmp_path, "materials.units.density")
    assert "N/m3" in str(err)


@pytest.mark.parametrize("unit_weight", [18000.0, 24000.0])
def test_density_given_as_unit_weight(tmp_path, no_solve, unit_weight):
    """The unit weight of brickwork (~18 kN/m3) or concrete (~24 kN/m3) typed where a density in
    kg/m3 is expected: 18000-24000 kg/m3 is denser than lead (11340 kg/m3) and impossible for
    masonry or concrete (1500-2500 kg/m3, EN 1991-1-1 Annex A)."""
    err = expect_scene_error(modified(materials__units__density=unit_weight), tmp_path, "materials.units.density")
    assert "N/m3" in str(err)


def test_residual_shear_stiffness_not_below_shear_stiffness(tmp_path, no_solve):
    for value in ("36 N/mm3", "40 N/mm3"):
        expect_scene_error(modified(joints__bed_joints__residual_shear_stiffness=value), tmp_path,
                           "joints.bed_joints.residual_shear_stiffness")
    # just below is accepted
    s = normalize(modified(joints__bed_joints__residual_shear_stiffness="35 N/mm3"))
    assert s["joints"]["bed_joints"]["residual_shear_stiffness"] == pytest.approx(3.5e10)


@pytest.mark.parametrize("key", ["cohesion", "friction_angle", "tensile_strength", "residual_shear_stiffness"])
def test_linear_joint_with_strength_parameter(tmp_path, no_solve, key):
    s = base_scene()
    s["joints"]["head_joints"][key] = 1.0
    err = expect_scene_error(s, tmp_path, f"joints.head_joints.{key}")
    assert "linear" in str(err)


def test_lumped_integration_with_points(tmp_path, no_solve):
    expect_scene_error(modified(joints__bed_joints__points=2), tmp_path, "joints.bed_joints.points")


# ------------------------------------------------------------------------------------------------
# units
# ------------------------------------------------------------------------------------------------
def test_wrong_unit_kind_names_the_key(tmp_path, no_solve):
    err = expect_scene_error(modified(joints__bed_joints__normal_stiffness="82 MPa"), tmp_path,
                             "joints.bed_joints.normal_stiffness")
    assert "stress" in str(err) and "stiffness" in str(err)


@pytest.mark.parametrize("edits,key", [
    ({"model__thickness": "100 MPa"}, "model.thickness"),
    ({"materials__units__youngs_modulus": "16.7 N/mm3"}, "materials.units.youngs_modulus"),
    ({"mesh__parameters__length": "0.4 GPa"}, "mesh.parameters.length"),
    ({"model__gravity": [0.0, "9.81 MPa"]}, "model.gravity[1]"),
    ({"stages__1__loads__0__pressure": "0.1 m"}, "stages[1].loads[0].pressure"),
    ({"joints__bed_joints__normal_stiffness": "82 N/mm^3"}, "joints.bed_joints.normal_stiffness"),
    ({"joints__bed_joints__normal_stiffness": "82 furlongs"}, "joints.bed_joints.normal_stiffness"),
])
def test_bad_unit_strings(tmp_path, no_solve, edits, key):
    expect_scene_error(modified(**edits), tmp_path, key)


@pytest.mark.parametrize("value,dimension,expected", [
    ("16.7 GPa", "stress", 1.67e10),
    ("0.30 MPa", "stress", 3.0e5),
    ("82 N/mm3", "stiffness", 8.2e10),
    ("36 N/mm3", "stiffness", 3.6e10),
    ("100 mm", "length", 0.1),
    ("10 cm", "length", 0.1),
    ("1.8 t/m3", "density", 1800.0),
    ("1 g", "acceleration", 9.80665),
    ("36.87 deg", "angle", 36.87),
    ("2e3", "force", 2000.0),
    (5, "length", 5.0),
])
def test_unit_conversion(value, dimension, expected):
    assert quantity(value, dimension, "k") == pytest.approx(expected, rel=1e-12)


def test_unit_strings_converted_in_normalized_scene():
    s = base_scene()
    s["model"]["thickness"] = "100 mm"
    n = normalize(s)
    assert n["model"]["thickness"] == pytest.approx(0.1, rel=1e-12)
    assert n["materials"]["units"]["youngs_modulus"] == pytest.approx(1.67e10, rel=1e-12)
    assert n["joints"]["bed_joints"]["normal_stiffness"] == pytest.approx(8.2e10, rel=1e-12)
    assert n["joints"]["bed_joints"]["shear_stiffness"] == pytest.approx(3.6e10, rel=1e-12)
    assert n["stages"][1]["loads"][0]["pressure"] == pytest.approx(1.0e5, rel=1e-12)
    # normalisation does not change the caller's dictionary
    assert s["model"]["thickness"] == "100 mm"


# ------------------------------------------------------------------------------------------------
# consistency between the scene and the mesh
# ------------------------------------------------------------------------------------------------
def test_material_for_group_not_in_mesh(tmp_path, no_solve):
    s = base_scene()
    s["materials"]["top_beam"] = {"youngs_modulus": "210 GPa", "poisson_ratio": 0.3}
    err = expect_scene_error(s, tmp_path, "materials.top_beam")
    assert "units" in str(err)  # lists the groups the mesh has


def test_mesh_group_without_material(tmp_path, no_solve):
    s = base_scene()
    s["mesh"]["parameters"]["base_beam_height"] = 0.1
    s["joints"]["base_joint"] = {"law": "linear", "normal_stiffness": 1e12, "shear_stiffness": 1e12}
    err = expect_scene_error(s, tmp_path, "materials")
    assert "base_beam" in str(err)


def test_joint_set_without_parameters(tmp_path, no_solve):
    s = base_scene()
    del s["joints"]["head_joints"]
    err = expect_scene_error(s, tmp_path, "joints")
    assert "head_joints" in str(err)


def test_joint_parameters_for_set_not_in_mesh(tmp_path, no_solve):
    s = base_scene()
    s["joints"]["lift_joints"] = {"law": "linear", "normal_stiffness": 1e10, "shear_stiffness": 1e10}
    err = expect_scene_error(s, tmp_path, "joints.lift_joints")
    assert "bed_joints" in str(err)


def test_unknown_support_set(tmp_path, no_solve):
    err = expect_scene_error(modified(supports__0__set="bottom"), tmp_path, "supports[0].set")
    assert "'bottom'" in str(err) and "base" in str(err)


def test_unknown_load_sets(tmp_path, no_solve):
    expect_scene_error(modified(stages__1__loads__0__set="roof_edge"), tmp_path, "stages[1].loads[0].set")
    s = base_scene()
    s["stages"][1]["loads"].append({"type": "nodal", "set": "roof", "force": [0.0, -1.0]})
    expect_scene_error(s, tmp_path, "stages[1].loads[1].set")
    s = base_scene()
    s["stages"][1]["loads"].append({"type": "displacement", "set": "nowhere", "components": ["x"], "value": [1e-3]})
    expect_scene_error(s, tmp_path, "stages[1].loads[1].set")


def test_unknown_output_sets(tmp_path, no_solve):
    s = base_scene()
    s["output"] = {"joints": ["lift_joints"]}
    expect_scene_error(s, tmp_path, "output.joints")


def test_displacement_on_supported_dofs(tmp_path, no_solve):
    s = base_scene()
    s["stages"][1]["loads"].append({"type": "displacement", "set": "base", "components": ["x"], "value": ["1 mm"]})
    err = expect_scene_error(s, tmp_path, "stages[1].loads[1].set")
    assert "support" in str(err)


def test_duplicate_stage_names(tmp_path, no_solve):
    err = expect_scene_error(modified(stages__1__name="gravity"), tmp_path, "stages")
    assert "unique" in str(err)


@pytest.mark.parametrize("section", ["mesh", "materials", "stages"])
def test_required_sections(tmp_path, no_solve, section):
    s = base_scene()
    del s[section]
    expect_scene_error(s, tmp_path, section)


@pytest.mark.parametrize("edits,key", [
    ({"mesh__parameters__height": 0.25}, "mesh.parameters.height"),
    ({"mesh__parameters__bond": "gothic"}, "mesh.parameters.bond"),
    ({"mesh__parameters__elements_per_unit": 1.5}, "mesh.parameters.elements_per_unit"),
    ({"mesh__parameters__elements_per_unit": 0}, "mesh.parameters.elements_per_unit"),
    ({"mesh__parameters__joint_thickness": -0.01}, "mesh.parameters.joint_thickness"),
    ({"mesh__parameters__length": None}, "mesh.parameters.length"),
    ({"mesh__generator": "gothic_cathedral"}, "mesh.generator"),
])
def test_bad_generator_parameters(tmp_path, no_solve, edits, key):
    expect_scene_error(modified(**edits), tmp_path, key)


@pytest.mark.parametrize("edits,key", [
    ({"mesh__parameters__element": "hex"}, "mesh.parameters.element"),
    ({"mesh__parameters__order": 3}, "mesh.parameters.order"),
])
def test_bad_element_kind_or_order_names_the_key(tmp_path, no_solve, edits, key):
    expect_scene_error(modified(**edits), tmp_path, key)


# ------------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------------
BASE_TOML = """
[model]
name = "tiny_wall"
thickness = "100 mm"

[mesh]
generator = "masonry_wall_2d"
[mesh.parameters]
length = 0.4
height = 0.3
unit_length = 0.2
unit_height = 0.1
elements_per_unit = 1

[materials.units]
youngs_modulus = "16.7 GPa"
poisson_ratio = 0.15
density = 1800

[joints.bed_joints]
normal_stiffness = "82 N/mm3"
shear_stiffness = "36 N/mm3"
friction_angle = {phi}

[joints.head_joints]
law = "linear"
normal_stiffness = "82 N/mm3"
shear_stiffness = "36 N/mm3"

[[supports]]
set = "base"

[[stages]]
name = "gravity"
[[stages.loads]]
type = "self_weight"
"""


def write_toml(tmp_path, phi="36.87"):
    p = tmp_path / "scene.toml"
    p.write_text(BASE_TOML.replace("{phi}", phi))
    return p


def test_toml_scene_matches_dict_scene(tmp_path):
    sc = Scene.from_toml(write_toml(tmp_path))
    assert sc.normalized["joints"]["bed_joints"]["friction_angle"] == 36.87
    assert sc.normalized["model"]["thickness"] == pytest.approx(0.1)
    assert sc.source == str(tmp_path / "scene.toml")


@pytest.mark.parametrize("command", ["run", "check"])
def test_cli_invalid_scene_exit_code_2(tmp_path, capsys, no_solve, command):
    path = write_toml(tmp_path, phi="90")
    argv = [command, str(path)] + (["-o", str(tmp_path / "o.nc"), "--no-progress"] if command == "run" else [])
    rc = main(argv)
    out, err = capsys.readouterr()
    assert rc == 2
    assert "scene key 'joints.bed_joints.friction_angle'" in err
    assert "Traceback" not in err and "Traceback" not in out
    assert not (tmp_path / "o.nc").exists()


def test_cli_unknown_key_typo(tmp_path, capsys, no_solve):
    path = tmp_path / "typo.toml"
    path.write_text(BASE_TOML.replace("{phi}", "30").replace("friction_angle", "frction_angle"))
    rc = main(["check", str(path)])
    _, err = capsys.readouterr()
    assert rc == 2
    assert "scene key 'joints.bed_joints.frction_angle'" in err and "did you mean 'friction_angle'" in err


def test_cli_not_toml_and_missing_file(tmp_path, capsys, no_solve):
    bad = tmp_path / "bad.toml"
    bad.write_text("[model\nthickness = 0.1\n")
    assert main(["check", str(bad)]) == 2
    _, err = capsys.readouterr()
    assert "scene key 'scene'" in err and "Traceback" not in err
    assert main(["run", str(tmp_path / "missing.toml"), "--no-progress"]) == 2
    _, err = capsys.readouterr()
    assert "scene key 'scene'" in err and "does not exist" in err


def test_cli_check_valid_scene(tmp_path, capsys, no_solve):
    assert main(["check", str(write_toml(tmp_path))]) == 0
    out, _ = capsys.readouterr()
    assert "is valid" in out and "self-weight" in out


def test_scene_dict_is_not_mutated_by_validation(no_solve):
    s = base_scene()
    before = copy.deepcopy(s)
    Scene(s)
    assert s == before
