"""The scene reference (masonrydam/scene/reference.py, docs/scene.md) against the schema.

- docs/scene.md is the rendered table (editing the table without regenerating the file fails);
- the keys of the table are the keys the schema accepts, both ways: every (prefix, allowed keys) that
  the key checker (``masonrydam.checks.check_keys``) is called with while normalising a broad set of
  scenes (every TOML scene of the repository, and the hand-written ones below, which reach the
  remaining sections) is recorded by patching the checker in every module that holds it; the prefixes
  are mapped to the table's path patterns (list indices to ``[]``, user names to ``<group>``,
  ``<set>``, ``<axis>``) and, where the allowed keys depend on a value (a stage's or a load's
  ``type``, a processing ``step``, the generator), to that value (:attr:`Key.variants`);
- the allowed values of the table are those the schema checks (``masonrydam.checks.choice``, recorded
  the same way);
- the defaults of the table are those the schema fills in.
"""
from __future__ import annotations

import importlib
import re
import sys
import tomllib
from contextlib import contextmanager

import pytest

import masonrydam.checks as checks
from masonrydam import effects
from masonrydam.scene import reference as ref
from masonrydam.scene import schema
from repository_paths import REPOSITORY_ROOT

ROOT = REPOSITORY_ROOT

#: keys the schema accepts without passing them to the key checker, with where they are checked:
#: a dynamic stage's load hands its other keys to the static load's normaliser and reads
#: ``time_function`` itself (masonrydam.effects.dynamic_loads.normalize_dynamic_load)
OUTSIDE_CHECKER = {"stages[].loads[].time_function"}

#: allowed values the generators check (not masonrydam.checks.choice): the table's tuple must be theirs
def _generator_choices():
    from generators.dams import PRESETS
    from generators.walls import BONDS

    return {"mesh.parameters.bond": tuple(BONDS), "mesh.parameters.preset": tuple(PRESETS)}


# -- scenes --------------------------------------------------------------------------------------------
def _toml_scenes():
    files = sorted(ROOT.glob("examples/*.toml")) + sorted(ROOT.glob("masonrydam/scenes/*.toml"))
    assert len(files) >= 10
    read = [(f.relative_to(ROOT).as_posix(), tomllib.loads(f.read_text(encoding="utf-8"))) for f in files]
    return [(name, data) for name, data in read if "ensemble" not in data]  # (ensemble files are no scenes)


_BLOCKS = {"blocks": [{"x0": 0, "y0": 0, "x1": 1, "y1": 0.5, "group": "base"},
                      {"x0": 0, "y0": 0.5, "x1": 1, "y1": 1, "group": "block"}], "element_size": 0.25}
_ELASTIC = {"youngs_modulus": "30 GPa", "poisson_ratio": 0.2, "density": 2400}
_JOINT = {"normal_stiffness": "10 GPa/m", "shear_stiffness": "10 GPa/m", "friction_angle": 30.0}
_RECORD = {"record": "elcentro_1940_ns_peknold"}


def _minimal(mesh, dim=2, **extra):
    scene = {"model": {"dimension": dim}, "mesh": mesh, "materials": {"base": dict(_ELASTIC)},
             "stages": [{"loads": [{"type": "self_weight"}]}]}
    scene.update(extra)
    return scene


def _static_scene():
    """2D: every static option, every material law, every joint law, both support kinds, solver, output."""
    wall = {"length": "1.0 m", "height": "0.62 m", "unit_length": "210 mm", "unit_height": "52 mm",
            "joint_thickness": "10 mm", "bond": "english", "elements_per_unit": 2, "order": 2, "element": "quad",
            "base_beam_height": "100 mm", "top_beam_height": "100 mm", "beam_joints": True, "unit_width": "100 mm",
            "unit_cracks": True, "openings": [{"x0": 0.3, "y0": 0.2, "width": 0.3, "height": 0.2}],
            "element_size": "20 mm"}
    soft = {"regularisation_length": "50 mm", "viscosity": 1e3}
    return {
        "model": {"name": "everything_static", "dimension": 2, "hypothesis": "plane_strain", "thickness": "100 mm",
                  "gravity": [0.0, "-1 g"], "kinematics": "small"},
        "mesh": {"generator": "masonry_wall_2d", "parameters": wall},
        "materials": {
            "units": {**_ELASTIC, "model": "linear_elastic", "integration": "reduced", "law": "elastic"},
            "vm": {**_ELASTIC, "law": "von_mises", "yield_stress": "250 MPa", "isotropic_hardening": -1e8,
                   "kinematic_hardening": 1e8, "residual_yield_stress": "50 MPa", **soft},
            "tr": {**_ELASTIC, "law": "tresca", "yield_stress": "250 MPa", "isotropic_hardening": 1e8,
                   "residual_yield_stress": 0.0, **soft},
            "dp": {**_ELASTIC, "law": "drucker_prager", "cohesion": "1 MPa", "friction_angle": 30.0,
                   "dilation_angle": 10.0, "cohesion_hardening": -1e6, "residual_cohesion": "0.1 MPa",
                   "match": "outer", **soft},
            "mc": {**_ELASTIC, "law": "mohr_coulomb", "cohesion": "1 MPa", "friction_angle": 30.0,
                   "dilation_angle": 0.0, "cohesion_hardening": 0.0, "residual_cohesion": 0.0, **soft},
        },
        "joints": {
            "bed_joints": {**_JOINT, "law": "mohr_coulomb", "cohesion": "0.1 MPa", "friction_angle": "30 deg",
                           "tensile_strength": "0.05 MPa", "residual_shear_stiffness": "1 N/mm3",
                           "integration": "gauss", "points": 2},
            "head_joints": {"law": "linear", "normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3",
                            "integration": "lobatto", "frame": "bottom"},
            "unit_cracks": {"law": "composite", "normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3",
                            "tensile_strength": "0.16 MPa", "mode_I_fracture_energy": "12 N/m",
                            "cohesion": "0.224 MPa", "friction_angle": 36.87, "residual_friction_angle": "30 deg",
                            "dilatancy_angle": 10.0, "dilatancy_confinement": "1 MPa", "dilatancy_decay": 5.0,
                            "mode_II_fracture_energy": "50 N/m", "compressive_strength": "10 MPa",
                            "cap_shear_factor": 9.0, "cap_fracture_energy": "5000 N/m",
                            "cap_peak_plastic_strain": "0.1 mm", "shear_stiffness_2": "36 N/mm3",
                            "relaxation_time": "1 ms"},
        },
        "supports": [{"set": "base", "components": ["x", "y"], "kind": "fixed"},
                     {"set": "top", "components": "y", "kind": "tied"}],
        "stages": [
            {"name": "load", "type": "static", "steps": 2, "control": "load", "duration": 1.0, "loads": [
                {"type": "self_weight", "factor": 1.0, "acceleration": ["0.1 g", "-1 g"]},
                {"type": "nodal", "set": "top", "force": ["1 kN", 0.0]},
                {"type": "traction", "set": "top_edge", "traction": [0.0, "-0.3 MPa"]},
                {"type": "edge_traction", "set": "top_edge", "traction": [0.0, -1e3]},
                {"type": "pressure", "set": "left_edge", "pressure": "0.1 MPa"},
                {"type": "edge_pressure", "set": "left_edge", "pressure": 1e3},
            ]},
            {"name": "push", "steps": 5, "control": "arc_length",
             "loads": [{"type": "displacement", "set": "top", "components": ["x"], "value": ["1 mm"]}]},
            {"name": "soften", "steps": 5, "control": "opening", "until_failure": True},
        ],
        "solver": {"method": "modified_newton", "line_search": False, "max_iterations": 40,
                   "force_tolerance": 1e-7, "energy_tolerance": 1e-12, "max_step_cuts": 4,
                   "linear_solver": "superlu", "joint_space": "off"},
        "output": {"nodes": ["top"], "joints": "bed_joints", "stress": "element", "precision": "single",
                   "compression": 4, "buffer_steps": 16, "flush_seconds": "500 ms"},
    }


def _dynamic_scene():
    """2D: a modal stage and dynamic stages with every option, every ground-motion source and
    processing step, initial velocities and loads with every time function."""
    out = {"nodes": ["block_nodes"], "joints": ["joints"]}
    return {
        "model": {"hypothesis": "plane_strain"},
        "mesh": {"generator": "blocks_2d", "parameters": {**_BLOCKS, "order": 1, "element": "quad",
                                                          "rotation_deg": "5 deg", "joint_name": "joints"}},
        "materials": {"base": dict(_ELASTIC), "block": dict(_ELASTIC)},
        "joints": {"joints": dict(_JOINT)},
        "supports": [{"set": "base"}],
        "stages": [
            {"name": "gravity", "loads": [{"type": "self_weight"}]},
            {"name": "modes", "type": "modal", "modes": 4, "mass": "lumped"},
            {"name": "quake", "type": "dynamic", "dt": "auto", "tolerance": 1e-4, "dt_min": "0.1 ms",
             "dt_max": "10 ms", "steps": 100, "integrator": "hht", "alpha": -0.05, "mass": "lumped",
             "damping": {"ratio": 0.05, "frequencies": [1.0, 10.0], "exclude_joints": False},
             "ground_motion": {
                 "x": {**_RECORD, "processing": [
                     {"step": "baseline", "method": "polynomial", "order": 2},
                     {"step": "taper", "max_percentage": 0.05, "side": "both", "max_length": 1.0},
                     {"step": "bandpass", "freqmin": 0.1, "freqmax": 20.0, "corners": 4},
                     {"step": "resample", "dt": "5 ms", "method": "polyphase"},
                     {"step": "trim", "start": 0.05, "end": 0.95, "pad": 1.0}],
                     "scale_to_sa": {"sa": "0.5 g", "period": "0.3 s", "damping": 0.05}},
                 "y": {"values": [0.0, 0.1, 0.0], "dt": 0.01, "units": "g", "scale": 0.5}},
             "output": {"dt": "20 ms", **out}, "max_iterations": 20, "max_substeps": 3, "force_tolerance": 1e-7,
             "energy_tolerance": 1e-9, "low_rank_max": 128, "joint_space": True},
            {"name": "pulse", "type": "dynamic", "dt": 0.01, "duration": "2 s", "integrator": "generalized_alpha",
             "rho_inf": 0.7, "mass": "consistent", "damping": {"alpha": 0.1, "beta": 1e-4},
             "ground_motion": {
                 "x": {"pulse": {"shape": "half_sine", "amplitude": "0.4 g", "duration": "200 ms"}, "dt": "5 ms",
                       "scale_to_pga": "0.3 g"},
                 "y": {"file": "record.txt", "format": "TEXT", "units": "cm/s2", "dt": 0.01, "column": 1}},
             "output": {"stride": 2, **out}, "joint_space": "off",
             "initial_velocity": [{"groups": ["block"], "velocity": [0.1, 0.0]},
                                  {"groups": "base", "angular_velocity": 0.1, "rotation_center": ["0 m", "0.5 m"]}]},
            {"name": "impact", "type": "dynamic", "dt": "1 ms", "steps": 10, "integrator": "central_difference",
             "initial_velocity": {"groups": ["block"], "velocity": [0.0, -0.1]},
             "initial_displacement": [{"groups": ["block"], "displacement": ["0 mm", "-0.1 mm"]},
                                      {"groups": "base", "rotation": 1e-5, "rotation_center": [0.0, 0.0]}],
             "loads": [
                 {"type": "nodal", "set": "top", "force": [1e3, 0.0],
                  "time_function": {"type": "table", "time": [0.0, 0.01], "values": [0.0, 1.0]}},
                 {"type": "traction", "set": "top_edge", "traction": [0.0, -1e3],
                  "time_function": {"type": "pulse", "shape": "triangular", "duration": "5 ms", "start": 0}},
                 {"type": "edge_pressure", "set": "left_edge", "pressure": "1 kPa",
                  "time_function": {"type": "harmonic", "frequency": 2.0, "phase": 90.0, "start": 0.001,
                                    "duration": 0.5}},
                 {"type": "pressure", "set": "right_edge", "pressure": 1e3,
                  "time_function": {"type": "file", "path": "force.txt", "column": 1}},
                 {"type": "edge_traction", "set": "top_edge", "traction": [1.0, 0.0],
                  "time_function": {"type": "pulse", "duration": 0.01}}]},
        ],
    }


def _dam_scene():
    """2D dam: the reservoir with everything, a foundation with mass, a modal and a dynamic stage."""
    dam = {"height": 100.0, "crest_width": 10.0, "crest_kink_height": 80.0, "upstream_slope": 0.0,
           "downstream_slope": 0.8, "downstream_upper_slope": 0.0, "lift_spacing": 20.0, "foundation_width": 200.0,
           "foundation_depth": 100.0, "galleries": [{"x": 5.0, "y": 10.0, "width": 2.0, "height": 3.0}],
           "element_size": 5.0, "order": 1, "element": "quad", "reservoir_level": 90.0}
    return {
        "model": {"hypothesis": "plane_strain"},
        "mesh": {"generator": "gravity_dam_2d", "parameters": dam},
        "materials": {"dam": dict(_ELASTIC), "foundation": dict(_ELASTIC)},
        "joints": {"lift_joints": dict(_JOINT), "base_joint": dict(_JOINT)},
        "supports": [{"set": "foundation_bottom"}],
        "stages": [
            {"name": "gravity", "loads": [{"type": "self_weight"}]},
            {"name": "water", "loads": [{"type": "reservoir"}]},
            {"name": "overtop", "loads": [{"type": "reservoir", "level": "95 m"}]},
            {"name": "modes", "type": "modal"},
            {"name": "quake", "type": "dynamic", "dt": 0.01, "ground_motion": {"x": dict(_RECORD)}},
        ],
        "reservoir": {"level": "90 m", "density": "1 t/m3", "face": "upstream_face",
                      "tailwater": {"level": 5.0, "face": "downstream_face"},
                      "silt": {"level": 10.0, "submerged_density": 1100.0, "lateral_coefficient": 0.5,
                               "face": "upstream_face"},
                      "uplift": {"joints": ["base_joint", "lift_joints"], "drains": {"distance": "5 m",
                                                                                      "efficiency": 0.67},
                                 "cracked": "full_head", "earthquake": "full_head"},
                      "dynamic": "acoustic",
                      "acoustic": {"length": "300 m", "sound_speed": "incompressible", "bottom_reflection": 0.8,
                                   "element_size": "5 m", "max_frequency": 20.0}},
        "foundation": {"mass": True, "group": "foundation",
                       "absorbing": {"bottom": "foundation_bottom", "sides": ["foundation_sides"]},
                       "motion": "within"},
    }


def _scenes_3d():
    """3D: the 3D generators and extruded 2D ones, large kinematics, a ground motion along z, a
    Westergaard reservoir; and a mesh file."""
    dam3d = {"valley_bottom_width": 100.0, "valley_top_width": 200.0, "n_monoliths": 4, "preset": "koyna",
             "lift_heights": [30.0, 60.0], "element_size": 10.0, "order": 1}
    wall3d = {"length": 1.0, "height": 0.6, "unit_length": 0.21, "unit_height": 0.052, "unit_width": 0.1,
              "bond": "flemish", "thickness": 0.0}
    quake = {"name": "quake", "type": "dynamic", "dt": 0.01,
             "ground_motion": {"x": dict(_RECORD), "z": {**_RECORD, "scale": 0.5}}}
    scenes = [
        ("3d dam", {**_minimal({"generator": "gravity_dam_3d", "parameters": dam3d}, 3),
                    "model": {"dimension": 3, "hypothesis": "3d", "kinematics": "large"},
                    "stages": [{"loads": [{"type": "self_weight"}, {"type": "reservoir"}]}, quake],
                    "reservoir": {"level": 90.0, "dynamic": "westergaard"},
                    "foundation": {"mass": False, "absorbing": False}}),
        ("3d wall", _minimal({"generator": "masonry_wall_3d", "parameters": wall3d}, 3)),
        ("3d arch", _minimal({"generator": "arch_dam_3d", "parameters": {
            "height": 30.0, "crest_radius": "50 m", "central_angle_deg": "100 deg", "crest_thickness": 4.0,
            "n_monoliths": 3, "valley_bottom_width": 20.0, "element_size": 10.0}}, 3)),
        ("3d boxes", _minimal({"generator": "blocks_3d", "parameters": {
            "blocks": [{"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 1, "group": "base"}],
            "element_size": 0.5, "order": 2, "rotation_deg": [0.0, 0.0, 10.0], "joint_name": "joints"}}, 3)),
        ("mesh file", _minimal({"file": "model.msh", "joints": ["bed_joints"]})),
    ]
    inner = {"masonry_wall_2d": {"length": 1.0, "height": 0.6, "unit_length": 0.21, "unit_height": 0.052},
             "blocks_2d": dict(_BLOCKS), "gravity_dam_2d": {"preset": "koyna"}}
    for name, params in inner.items():
        scenes.append((f"extruded {name}", _minimal({"generator": "extruded", "parameters": {
            "generator": name, "parameters": params, "depth": "0.5 m", "layers": 2}}, 3)))
    return scenes


def _hand_scenes():
    return [("static", _static_scene()), ("dynamic", _dynamic_scene()), ("dam", _dam_scene()), *_scenes_3d()]


# -- recording the key checker and the choices ------------------------------------------------------------
def _pattern(where: str) -> str:
    """A checked prefix or key (``stages[2].ground_motion.x.processing[0]``) as a path pattern of the
    table (``stages[].ground_motion.<axis>.processing[]``)."""
    p = re.sub(r"\[\d+\]", "[]", where)
    p = re.sub(r"^materials\.[^.]+", "materials.<group>", p)
    p = re.sub(r"^joints\.[^.]+", "joints.<set>", p)
    p = re.sub(r"\.ground_motion\.[xyz](?=\.|$)", ".ground_motion.<axis>", p)
    return p.replace("initial_velocity[]", "initial_velocity").replace("initial_displacement[]", "initial_displacement")


def _variant(pattern: str, d, scene: dict):
    """(pattern, the value the allowed keys depend on, or None)."""
    if pattern == "mesh.parameters":
        return pattern, scene["mesh"]["generator"]
    if pattern == "mesh.parameters.parameters":  # the 2D generator inside 'extruded'
        return "mesh.parameters", scene["mesh"]["parameters"]["generator"]
    if pattern == "stages[]":
        return pattern, d.get("type", "static")
    if pattern in ("stages[].loads[]", "stages[].loads[].time_function"):
        return pattern, d.get("type")
    if pattern.endswith(".processing[]"):
        return pattern, d.get("step")
    return pattern, None


def _modules_holding(obj):
    effects.sections(), effects.load_types()  # import every effect module
    importlib.import_module("generators")  # the generators' own modules

    for name, mod in list(sys.modules.items()):
        if mod is None or not (name == "generators" or name.startswith(("masonrydam.", "generators."))):
            continue
        for attr, value in list(vars(mod).items()):
            if value is obj:
                yield mod, attr


@contextmanager
def _recording():
    """Patch check_keys and choice wherever they are held; yield (accepted, choices, current):
    accepted[(pattern, variant)] = allowed keys, choices[pattern] = {option tuples}; current['scene'] is
    the raw scene being normalised."""
    accepted, choices, current = {}, {}, {}
    check_keys, choice = checks.check_keys, checks.choice

    def recording_check_keys(d, allowed, where):
        key = _variant(_pattern(where), d if isinstance(d, dict) else {}, current["scene"])
        accepted.setdefault(key, set()).update(allowed)
        return check_keys(d, allowed, where)

    def recording_choice(value, options, key):
        choices.setdefault(_pattern(key), set()).add(tuple(options))
        return choice(value, options, key)

    with pytest.MonkeyPatch.context() as mp:
        for obj, new in ((check_keys, recording_check_keys), (choice, recording_choice)):
            held = list(_modules_holding(obj))
            assert held, f"{obj.__name__} is held by no module"
            for mod, attr in held:
                mp.setattr(mod, attr, new)
        yield accepted, choices, current


def _normalise_all():
    with _recording() as (accepted, choices, current):
        for name, scene in _toml_scenes() + _hand_scenes():
            current["scene"] = scene
            try:
                schema.normalize(scene)
            except Exception as exc:  # a test scene that the schema rejects reaches nothing after the error
                raise AssertionError(f"scene '{name}' does not normalise: {exc}") from exc
    return accepted, choices


@pytest.fixture(scope="module")
def recorded():
    return _normalise_all()


def _split(path: str):
    return tuple(path.rsplit(".", 1)) if "." in path else ("", path)


def _applies(row: ref.Key, variant) -> bool:
    return variant is None or not row.variants or variant in row.variants


def _disagreements(accepted: dict) -> list:
    """Messages for every schema key missing from the table and every table key the schema does not accept."""
    rows = [r for r in ref.keys() if r.path not in OUTSIDE_CHECKER]
    problems = []
    for (pattern, variant), allowed in sorted(accepted.items(), key=lambda kv: (kv[0][0], str(kv[0][1]))):
        documented = {_split(r.path)[1] for r in rows if _split(r.path)[0] == pattern and _applies(r, variant)}
        for k in sorted(set(allowed) - documented):
            path = f"{pattern}.{k}" if pattern else k
            where = f" (for {variant})" if variant is not None else ""
            problems.append(f"the schema accepts '{path}'{where}, which docs/scene.md does not document "
                            f"(masonrydam/scene/reference.py)")
    for r in rows:
        parent, leaf = _split(r.path)
        reached = [(v, allowed) for (p, v), allowed in accepted.items() if p == parent and _applies(r, v)]
        if not any(leaf in allowed for _, allowed in reached):
            why = "" if reached else " (no test scene reaches its table: add one to tests/test_scene_reference.py)"
            problems.append(f"docs/scene.md documents '{r.path}'"
                            f"{' for ' + ', '.join(r.variants) if r.variants else ''}, which the schema does not "
                            f"accept{why}")
    return problems


# -- tests ------------------------------------------------------------------------------------------------
def test_docs_scene_md_is_the_rendered_table():
    text = (ROOT / "docs" / "scene.md").read_text(encoding="utf-8")
    assert text == ref.render_markdown(), \
        "docs/scene.md is out of date: python -m masonrydam.scene.reference > docs/scene.md"
    assert "/work/" not in text and "/tmp" not in text


def test_main_writes_the_reference(capsys):
    assert ref.main([]) == 0
    assert capsys.readouterr().out == ref.render_markdown()


def test_every_row_is_well_formed():
    types = {"number", "integer", "string", "bool", "list", "table"}
    seen = set()
    for r in ref.keys():
        assert r.meaning and "\n" not in r.meaning, r.path
        assert set(r.type.split(" or ")) <= types, (r.path, r.type)
        assert r.unit_string in ("", ref.UNIT, ref.TIME), r.path
        assert not r.unit_string or r.unit, f"{r.path}: a unit string needs a unit"
        assert (r.path, r.variants) not in seen, f"{r.path} twice"
        seen.add((r.path, r.variants))


def test_table_keys_are_the_schema_keys(recorded):
    accepted, _ = recorded
    problems = _disagreements(accepted)
    assert not problems, "\n".join(problems)


def test_time_function_is_read_outside_the_key_checker():
    """OUTSIDE_CHECKER: the schema reads these keys itself; a dynamic load needs its time_function."""
    scene = _dynamic_scene()
    load = scene["stages"][-1]["loads"][0]
    del load["time_function"]
    with pytest.raises(Exception, match="time_function"):
        schema.normalize(scene)


def test_an_undocumented_schema_key_fails(recorded):
    accepted, _ = recorded
    extended = {k: set(v) for k, v in accepted.items()}
    extended[("solver", None)].add("new_key")
    extended[("stages[]", "dynamic")].add("new_dynamic_key")
    problems = _disagreements(extended)
    assert any("'solver.new_key'" in p for p in problems)
    assert any("'stages[].new_dynamic_key' (for dynamic)" in p for p in problems)


def test_choices_are_the_schema_choices(recorded):
    _, choices = recorded
    rows = ref.keys()
    problems = []
    for path, options in sorted(choices.items()):
        for opts in sorted(options):
            if not any(r.path == path and r.choices == opts for r in rows):
                documented = [r.choices for r in rows if r.path == path]
                problems.append(f"'{path}': the schema allows {list(opts)}, docs/scene.md lists {documented}")
    elsewhere = _generator_choices()
    for r in rows:
        if r.choices is None:
            continue
        if r.path in elsewhere:
            if r.choices != elsewhere[r.path]:
                problems.append(f"'{r.path}': the generator allows {list(elsewhere[r.path])}, docs/scene.md lists "
                                f"{list(r.choices)}")
        elif r.choices not in choices.get(r.path, set()):
            problems.append(f"'{r.path}': docs/scene.md lists {list(r.choices)}, which the schema does not check "
                            f"(it checks {sorted(choices.get(r.path, set()))})")
    assert not problems, "\n".join(problems)


# -- defaults -------------------------------------------------------------------------------------------
def _defaults_scene():
    """Every section present with its required keys only, so that the schema fills in the rest."""
    load = {"type": "nodal", "set": "top", "force": [1.0, 0.0]}
    return {
        "mesh": {"generator": "blocks_2d", "parameters": dict(_BLOCKS)},
        "materials": {"e": {"youngs_modulus": 3e10, "poisson_ratio": 0.2},
                      "vm": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "law": "von_mises", "yield_stress": 1e8},
                      "tr": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "law": "tresca", "yield_stress": 1e8},
                      "dp": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "law": "drucker_prager", "cohesion": 1e6,
                             "friction_angle": 30.0},
                      "mc": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "law": "mohr_coulomb", "cohesion": 1e6,
                             "friction_angle": 30.0}},
        "joints": {"mc": {"normal_stiffness": 1e10, "shear_stiffness": 1e10, "friction_angle": 30.0}},
        "supports": [{"set": "base"}],
        "stages": [
            {"loads": [{"type": "self_weight"}, {"type": "reservoir"}]},
            {"type": "modal"},
            {"type": "dynamic", "dt": 0.01,
             "ground_motion": {"x": {**_RECORD, "scale_to_sa": {"sa": 1.0, "period": 0.5}}},
             "damping": {"ratio": 0.05, "frequencies": [1.0, 10.0]},
             "loads": [{**load, "time_function": {"type": "pulse", "duration": 0.1}},
                       {**load, "time_function": {"type": "harmonic", "frequency": 2.0}},
                       {**load, "time_function": {"type": "file", "path": "f.txt"}}]},
            {"type": "dynamic", "dt": "auto", "ground_motion": {"x": dict(_RECORD)}},
        ],
        "reservoir": {"level": 10.0, "tailwater": {"level": 1.0}, "silt": {"level": 2.0, "submerged_density": 1e3},
                      "uplift": {"joints": ["mc"]}, "dynamic": "acoustic"},
        "foundation": {},
    }


def _resolve(raw, norm, parts, disc, variants, found):
    """Walk ``parts`` (a row's path split at dots) through the normalised scene and the raw one side by side;
    append to ``found`` the values the schema filled in (absent from the raw scene) whose table satisfies
    the row's variants."""
    if not parts:
        return
    part, rest = parts[0], parts[1:]
    if part.startswith("<"):  # a user name: every one
        for name in norm if isinstance(norm, dict) else ():
            _resolve((raw or {}).get(name) if isinstance(raw, dict) else None, norm[name], rest, disc, variants, found)
        return
    name, is_list = (part[:-2], True) if part.endswith("[]") else (part, False)
    if not isinstance(norm, dict) or name not in norm:
        return
    sub_raw = raw.get(name) if isinstance(raw, dict) else None
    if is_list:
        items = norm[name] if isinstance(norm[name], list) else []
        for i, item in enumerate(items):
            item_raw = sub_raw[i] if isinstance(sub_raw, list) and i < len(sub_raw) else None
            _resolve(item_raw, item, rest, disc, variants, found)
        return
    if rest:
        _resolve(sub_raw, norm[name], rest, disc, variants, found)
        return
    given = isinstance(raw, dict) and name in raw
    if not given and (not variants or norm.get(disc) in variants):
        found.append(norm[name])


def test_defaults_are_the_schema_defaults():
    raw = _defaults_scene()
    norm = schema.normalize(raw)
    checked, problems = set(), []
    for section in ref.SECTIONS:
        if section.discriminator == "generator":
            continue  # defaults from the generators' signatures (reference._generator_keys)
        for r in section.keys:
            if r.default_text or r.default is ref.REQUIRED or r.default is ref.ABSENT:
                continue
            found = []
            _resolve(raw, norm, r.path.split("."), section.discriminator, r.variants, found)
            for value in found:
                checked.add(r.path)
                if value != r.default or type(value) is bool and type(r.default) is not bool:
                    problems.append(f"'{r.path}': the schema fills in {value!r}, docs/scene.md says {r.default!r}")
    assert not problems, "\n".join(problems)
    solver_output = {r.path for s in ref.SECTIONS if s.title in ("[solver]", "[output]") for r in s.keys}
    assert solver_output <= checked, sorted(solver_output - checked)
    assert len(checked) >= 60, len(checked)
