"""Scene builders shared by the tests: each returns a fresh scene dictionary (what ``masonrydam.run`` takes)
of one closed-form or published problem, with its physical parameters as keywords and any other entry changed through
``overrides``.

``overrides`` is a mapping merged into the scene by :func:`merged`: a dotted key names one entry
(``{"stages.1.dt": 0.001}``, list items by their index), a nested dictionary is merged key by key
(``{"joints": {"joints": {"cohesion": 1e5}}}``), any other value replaces the entry. Use it for changes that
do not alter the problem's identity; a test that needs another problem writes its own scene.

The problems:

- :func:`sliding_block`: Newmark's (1965) rigid block on a Coulomb joint under a ground-acceleration pulse;
- :func:`rocking_block`, :func:`rocking_block_model`: Housner's (1963) slender block on a no-tension,
  no-slip joint;
- :func:`tilted_block`: the same kind of block under a growing horizontal body force (a tilted table);
- :func:`block_on_elastic_joint`: a rigid block on linear joint springs with a modal stage (Chopra 2012,
  sec. 10.2);
- :func:`small_wall`: a running-bond wall of 0.2 x 0.1 m units on a fixed base (the simplified micro-model,
  Lourenco 1996);
- :func:`dam_with_reservoir`: a triangular-topped gravity dam on a rock block with water and uplift (the
  gravity method of USBR 1987, sec. 5.7-5.11);
- :func:`koyna_el_centro`: examples/koyna_el_centro.toml (the Koyna section of Chopra & Chakrabarti
  1973 under El Centro) with time steps and a mesh of the test's own.

:func:`toml_text` writes a scene dictionary as TOML, for tests of the command line.
"""
from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

#: standard gravity (m/s2), the one the scenes' default gravity uses
G = 9.80665


# ----------------------------------------------------------------------------------------------
# overrides
# ----------------------------------------------------------------------------------------------

def merged(scene: dict, overrides: Mapping | None) -> dict:
    """``scene`` with ``overrides`` merged into it (in place; ``scene`` is returned). A key with dots is a
    path (``"stages.1.output.stride"``; an integer part indexes a list); a dictionary value merges into a
    dictionary entry key by key; any other value replaces the entry (lists are replaced whole)."""
    for key, value in (overrides or {}).items():
        parts = key.split(".")
        parent = scene
        for part in parts[:-1]:
            parent = _child(parent, part, key)
        _assign(parent, parts[-1], copy.deepcopy(value), key)
    return scene


def _child(container, part, key):
    if isinstance(container, list):
        return container[_index(container, part, key)]
    return container.setdefault(part, {})


def _assign(container, part, value, key):
    if isinstance(container, list):
        container[_index(container, part, key)] = value
    elif isinstance(value, Mapping) and isinstance(container.get(part), dict):
        merged(container[part], value)
    else:
        container[part] = value


def _index(items: list, part: str, key: str) -> int:
    if not part.lstrip("-").isdigit():
        raise KeyError(f"override {key!r}: {part!r} is not an index of a list")
    return int(part)


def toml_text(scene: Mapping) -> str:
    """``scene`` as the text of a TOML file (each top-level entry one line, inner tables inline), for tests
    that give the command line a scene file."""
    lines = []
    for key, value in scene.items():
        lines.append(f"{key} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float, np.integer, np.floating)):
        x = float(value) if isinstance(value, (float, np.floating)) else int(value)
        if isinstance(x, float) and not math.isfinite(x):
            return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
        return repr(x)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, Mapping):
        return "{" + ", ".join(f'"{k}" = {_toml_value(v)}' for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML form for {type(value).__name__}")


# ----------------------------------------------------------------------------------------------
# Newmark's (1965) sliding block
# ----------------------------------------------------------------------------------------------

def sliding_block(*, shape="rectangular", amplitude=0.4 * G, pulse=0.2, mu=0.2, dt=0.002, duration=0.6,
                  integrator="hht", kn=1e10, damping=None, output=None, overrides=None, **pulse_stage):
    """A 2 x 0.5 m block on a fixed 2 x 0.25 m base (E = 30 GPa, 2000 kg/m3, quad4 of 0.25 m), joined by a
    cohesionless Coulomb joint of friction coefficient ``mu`` and stiffness ``kn`` (normal and shear): a
    gravity stage, then a dynamic stage ``"pulse"`` of ``duration`` s under one horizontal ground
    acceleration pulse (``shape``, ``amplitude`` in m/s2, ``pulse`` s long). Newmark (1965), Geotechnique
    15:139-160: once the ground acceleration exceeds mu g the block slips, a rigid block's permanent slip
    is a closed form of the pulse. ``damping``, ``output`` and the other keywords (``max_iterations``,
    ``joint_space``, ``mass``, integrator parameters, ...) are keys of the dynamic stage."""
    phi = math.degrees(math.atan(mu))
    stage = {"name": "pulse", "type": "dynamic", "dt": dt, "duration": duration, "integrator": integrator,
             "ground_motion": {"x": {"pulse": {"shape": shape, "amplitude": amplitude, "duration": pulse}}}}
    if damping:
        stage["damping"] = damping
    if output:
        stage["output"] = output
    stage.update(pulse_stage)
    scene = {
        "model": {"name": "sliding_block", "thickness": 1.0},
        "mesh": {"generator": "blocks_2d", "parameters": {"blocks": [
            {"x0": 0, "y0": 0, "x1": 2, "y1": 0.25, "group": "base"},
            {"x0": 0, "y0": 0.25, "x1": 2, "y1": 0.75, "group": "block"}], "element_size": 0.25}},
        "materials": {"base": {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": 2000},
                      "block": {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": 2000}},
        "joints": {"joints": {"normal_stiffness": kn, "shear_stiffness": kn, "friction_angle": phi}},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]}, stage],
    }
    return merged(scene, overrides)


# ----------------------------------------------------------------------------------------------
# Housner's (1963) rocking block
# ----------------------------------------------------------------------------------------------

#: the rocking block's width 2b and height 2h (m): b/h = 0.2
ROCKING_BLOCK_WIDTH, ROCKING_BLOCK_HEIGHT = 0.3, 1.5


def rocking_block(stages, *, overrides=None):
    """A 0.3 x 1.5 m block (b/h = 0.2) standing at (0, 0) on a 0.5 x 0.1 m base, both nearly rigid
    (E = 200 GPa, 2000 kg/m3, quad4 of 0.05 m), on a cohesionless, no-tension joint (kn = ks = 1e12 Pa/m)
    whose friction (45 degrees) is well above b/h, so that the block rocks and does not slide (Housner
    1963, BSSA 53(2):403-417: it starts to rock when the base acceleration exceeds g b/h). ``stages`` are
    the scene's stages."""
    b, h = ROCKING_BLOCK_WIDTH, ROCKING_BLOCK_HEIGHT
    scene = {"model": {"name": "rocking", "thickness": 1.0},
             "mesh": {"generator": "blocks_2d", "parameters": {"blocks": [
                 {"x0": -0.1, "y0": -0.1, "x1": b + 0.1, "y1": 0.0, "group": "base"},
                 {"x0": 0.0, "y0": 0.0, "x1": b, "y1": h, "group": "block"}], "element_size": 0.05}},
             "materials": {"base": {"youngs_modulus": 200e9, "poisson_ratio": 0.2, "density": 2000},
                           "block": {"youngs_modulus": 200e9, "poisson_ratio": 0.2, "density": 2000}},
             # no-tension, cohesionless joint, friction well above b/h so that the block rocks, not slides
             "joints": {"joints": {"normal_stiffness": 1e12, "shear_stiffness": 1e12, "friction_angle": 45.0}},
             "supports": [{"set": "base", "components": ["x", "y"]}],
             "stages": stages}
    return merged(scene, overrides)


def rocking_block_model():
    """The model of :func:`rocking_block` (no loads), its supports and the block's node numbers, for tests
    that drive the dynamic solver directly: ``(model, supports, block_nodes)``."""
    from masonrydam.scene import build_mesh, build_model, build_stages
    from masonrydam.scene.scene import Scene

    sc = Scene(rocking_block([{"name": "gravity", "loads": []}]))
    mesh = build_mesh(sc.normalized, ".")
    model = build_model(sc.normalized, mesh)
    supports = build_stages(sc.normalized, mesh, model)[0].supports
    block = np.unique(model.cgroups[[g.name for g in model.cgroups].index("block")].conn)
    return model, supports, block


def tilted_block(kinematics, dim=2, *, overrides=None):
    """A 0.5 x 2 m block (2D; a 0.5 x 0.5 x 2 m prism in 3D) on a 0.25 m thick base, quad4/hex8 of 0.25 m,
    E = 30 GPa, 2400 kg/m3, on a joint that cannot slide (friction 80 degrees, tan = 5.7 > b/h = 0.25):
    gravity, then a stage ``"tilt"`` of 100 steps, until failure, of weight plus a horizontal body force
    0.5 g lambda, a table tilted by tan(alpha) = 0.5 lambda (the block topples at tan(alpha) = b/h).
    ``kinematics`` is ``[model] kinematics`` ("small" or "large")."""
    if dim == 2:
        model = {"name": "tilt", "thickness": 1.0, "kinematics": kinematics}
        mesh = {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
            {"x0": 0.0, "y0": -0.25, "x1": 0.5, "y1": 0.0, "group": "base"},
            {"x0": 0.0, "y0": 0.0, "x1": 0.5, "y1": 2.0, "group": "block"}]}}
    else:
        model = {"name": "tilt", "dimension": 3, "kinematics": kinematics}
        mesh = {"generator": "blocks_3d", "parameters": {"element_size": 0.25, "blocks": [
            {"x0": 0.0, "y0": 0.0, "z0": -0.25, "x1": 0.5, "y1": 0.5, "z1": 0.0, "group": "base"},
            {"x0": 0.0, "y0": 0.0, "z0": 0.0, "x1": 0.5, "y1": 0.5, "z1": 2.0, "group": "block"}]}}
    scene = {"model": model, "mesh": mesh,
             "materials": {g: {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2400.0}
                           for g in ("base", "block")},
             "joints": {"joints": {"normal_stiffness": 1e12, "shear_stiffness": 1e12, "friction_angle": 80.0}},
             "supports": [{"set": "base"}],
             "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                        {"name": "tilt", "steps": 100, "until_failure": True,
                         "loads": [{"type": "self_weight", "acceleration": [0.5 * G] + [0.0] * (dim - 1)}]}]}
    return merged(scene, overrides)


# ----------------------------------------------------------------------------------------------
# a rigid block on an elastic joint, with a modal stage
# ----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ElasticJointBlock:
    """Dimensions and properties of :func:`block_on_elastic_joint` (SI units)."""

    width: float = 2.0
    height: float = 1.0
    density: float = 2000.0
    normal_stiffness: float = 1e9
    shear_stiffness: float = 4e8
    thickness: float = 1.0
    element_size: float = 0.125


ELASTIC_JOINT_BLOCK = ElasticJointBlock()


def block_on_elastic_joint(modes=6, mass="consistent", *, overrides=None):
    """A 2 x 1 m block on a 2 x 0.5 m fixed base, both rigid against the joint (E = 1e14 Pa: E A / H =
    2e14 N/m against kn A = 2e9 N/m), on a linear joint (kn = 1e9, ks = 4e8 Pa/m): gravity, then a modal
    stage ``"modes"`` of ``modes`` modes with ``mass`` ("consistent" or "lumped"). A rigid body on
    distributed springs (Chopra, Dynamics of Structures, 4th ed., sec. 10.2): a vertical mode
    omega^2 = kn A / m and two coupled sliding-rocking modes."""
    p = ELASTIC_JOINT_BLOCK
    material = {"youngs_modulus": 1e14, "poisson_ratio": 0.2, "density": p.density}
    scene = {
        "model": {"name": "block_modes", "thickness": p.thickness},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": p.element_size, "blocks": [
            {"x0": 0.0, "y0": -0.5, "x1": p.width, "y1": 0.0, "group": "base"},
            {"x0": 0.0, "y0": 0.0, "x1": p.width, "y1": p.height, "group": "block"}]}},
        "materials": {"base": dict(material), "block": dict(material)},
        "joints": {"joints": {"law": "linear", "normal_stiffness": p.normal_stiffness,
                              "shear_stiffness": p.shear_stiffness}},
        "supports": [{"set": "base"}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "modes", "type": "modal", "modes": modes, "mass": mass}],
    }
    return merged(scene, overrides)


def oscillator(dynamic_stage: dict, *, normal_stiffness=1.0e9, density=1000.0, overrides=None):
    """An undamped one-degree-of-freedom oscillator: a stiff 1 x 1 m block (``density`` kg/m3: m = 1000 kg) on
    a linear joint of normal stiffness ``normal_stiffness`` (Pa/m) over 1 m (k = kn), on a fixed base, without
    gravity; a static stage "rest" and the dynamic stage ``dynamic_stage`` (its name, type and mass given here:
    "load", lumped). Chopra, Dynamics of Structures, 4th ed., 2012, ch. 3-4 (omega = sqrt(kn / rho))."""
    material = {"youngs_modulus": 1e14, "poisson_ratio": 0.0, "density": density}
    scene = {
        "model": {"name": "sdof", "thickness": 1.0, "gravity": [0.0, 0.0]},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.5, "blocks": [
            {"x0": 0, "y0": -0.5, "x1": 1, "y1": 0, "group": "base"},
            {"x0": 0, "y0": 0, "x1": 1, "y1": 1, "group": "block"}]}},
        "materials": {"base": dict(material), "block": dict(material)},
        "joints": {"joints": {"law": "linear", "normal_stiffness": normal_stiffness,
                              "shear_stiffness": normal_stiffness}},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": [{"name": "rest", "steps": 1, "loads": []},
                   dict({"name": "load", "type": "dynamic", "mass": "lumped"}, **dynamic_stage)],
    }
    return merged(scene, overrides)


# ----------------------------------------------------------------------------------------------
# a small masonry wall
# ----------------------------------------------------------------------------------------------

#: the joint stiffnesses of the small wall (Lourenco & Rots 1997's Eindhoven walls: kn = 82, ks = 36 N/mm3)
WALL_NORMAL_STIFFNESS, WALL_SHEAR_STIFFNESS = "82 N/mm3", "36 N/mm3"
#: the small wall's thickness (m) and its units' density (kg/m3)
WALL_THICKNESS, WALL_UNIT_DENSITY = 0.1, 1800.0


def small_wall(*, length=0.8, height=0.4, elements_per_unit=3, bond="running", normal_stiffness=WALL_NORMAL_STIFFNESS,
               shear_stiffness=WALL_SHEAR_STIFFNESS, bed_joints=None, stages=None, overrides=None):
    """A wall ``length`` x ``height`` of 0.2 x 0.1 m units (masonry_wall_2d: expanded units, zero-thickness bed
    and head joints; E = 16.7 GPa, nu = 0.15, 1800 kg/m3, 0.1 m thick) on a fixed base. Head joints are linear
    (kn = 82, ks = 36 N/mm3 unless given); ``bed_joints`` gives the bed joints' entry (default: linear, the
    same stiffnesses). ``stages`` default to one stage "gravity": self-weight and 0.2 MPa on the top edge."""
    linear = {"law": "linear", "normal_stiffness": normal_stiffness, "shear_stiffness": shear_stiffness}
    scene = {
        "model": {"name": "wall", "thickness": WALL_THICKNESS},
        "mesh": {"generator": "masonry_wall_2d",
                 "parameters": {"length": length, "height": height, "unit_length": 0.2, "unit_height": 0.1,
                                "bond": bond, "elements_per_unit": elements_per_unit}},
        "materials": {"units": {"youngs_modulus": "16.7 GPa", "poisson_ratio": 0.15, "density": WALL_UNIT_DENSITY}},
        "joints": {"bed_joints": bed_joints or dict(linear), "head_joints": dict(linear)},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": stages or [{"name": "gravity", "steps": 1, "loads": [
            {"type": "self_weight"}, {"type": "edge_pressure", "set": "top_edge", "pressure": "0.2 MPa"}]}],
    }
    return merged(scene, overrides)


# ----------------------------------------------------------------------------------------------
# a weightless 3D block on a cohesive joint, driven by its top face
# ----------------------------------------------------------------------------------------------

def driven_block_on_cohesive_joint(name, stages, *, normal_stiffness=1e11):
    """A 1 x 1 x 0.5 m block on a 1 x 1 x 0.5 m base (blocks_3d, 0.5 m elements, E = 30 GPa, nu = 0.2), joined by
    a Mohr-Coulomb joint (kn = ``normal_stiffness``, ks = 1e11 Pa/m, phi = 45 deg, c = 0.5 MPa, no tensile
    strength), without gravity, the base held; each of ``stages``, a list of ``(stage name, [ux, uy, uz])``,
    drives the top face to that displacement (m) in one step."""
    blocks = [{"x0": 0, "y0": 0, "z0": -0.5, "x1": 1, "y1": 1, "z1": 0, "group": "base"},
              {"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 0.5, "group": "block"}]
    return {"model": {"name": name, "dimension": 3, "gravity": [0.0, 0.0, 0.0]},
            "mesh": {"generator": "blocks_3d", "parameters": {"element_size": 0.5, "blocks": blocks}},
            "materials": {g: {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2400.0} for g in ("base", "block")},
            "joints": {"joints": {"normal_stiffness": normal_stiffness, "shear_stiffness": 1e11, "friction_angle": 45.0,
                                  "cohesion": "0.5 MPa"}},
            "supports": [{"set": "base"}],
            "stages": [{"name": stage, "steps": 1, "loads": [{"type": "displacement", "set": "top",
                                                              "components": ["x", "y", "z"], "value": list(value)}]}
                       for stage, value in stages]}


# ----------------------------------------------------------------------------------------------
# a gravity dam with its reservoir
# ----------------------------------------------------------------------------------------------

#: density of the dam's concrete (kg/m3)
DAM_CONCRETE_DENSITY = 2400.0


def dam_with_reservoir(*, height=30.0, crest_width=5.0, downstream_slope=0.8, level=28.0, element_size=2.0,
                       friction_angle=45.0, youngs_modulus=25e9, joint_stiffness=1e11, foundation_width=None,
                       stages=None, overrides=None):
    """A gravity dam (gravity_dam_2d: vertical upstream face, crest ``crest_width``, downstream face
    ``downstream_slope`` horizontal per vertical; concrete 2400 kg/m3) on a massless rock block 10 m deep and
    ``foundation_width`` wide (default: twice the base plus 20 m), joined by a cohesionless base joint
    (``friction_angle``, kn = ks = ``joint_stiffness``), with water at ``level`` and its uplift on the base
    joint (linear from headwater to the toe). Stages default to "gravity" (self-weight) then "water" (the
    reservoir in 4 steps). Checked against the gravity method (USBR, Design of Small Dams 1987, sec. 5.7-5.11;
    USACE EM 1110-2-2200, ch. 3-4)."""
    if foundation_width is None:
        foundation_width = 2.0 * (crest_width + downstream_slope * height) + 20.0
    material = {"youngs_modulus": youngs_modulus, "poisson_ratio": 0.2}
    scene = {
        "model": {"name": "dam_water", "hypothesis": "plane_strain"},
        "mesh": {"generator": "gravity_dam_2d",
                 "parameters": {"height": height, "crest_width": crest_width, "downstream_slope": downstream_slope,
                                "foundation_width": foundation_width, "foundation_depth": 10.0,
                                "element_size": element_size}},
        "materials": {"dam": dict(material, density=DAM_CONCRETE_DENSITY), "foundation": dict(material, density=0.0)},
        "joints": {"base_joint": {"normal_stiffness": joint_stiffness, "shear_stiffness": joint_stiffness,
                                  "friction_angle": friction_angle}},
        "reservoir": {"level": level, "uplift": {"joints": ["base_joint"]}},
        "supports": [{"set": "foundation_bottom"}],
        "stages": stages or [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                             {"name": "water", "steps": 4, "loads": [{"type": "reservoir"}]}],
    }
    return merged(scene, overrides)


# ----------------------------------------------------------------------------------------------
# the Koyna section (Chopra & Chakrabarti 1973) under El Centro
# ----------------------------------------------------------------------------------------------

def koyna_el_centro(*, element_size, dt, steps=None, duration=None, output=None, overrides=None):
    """examples/koyna_el_centro.toml (the Koyna section, Chopra & Chakrabarti 1973 profile, cut by 10 lift
    joints and the base joint, Mohr-Coulomb joints with a brittle bond; self-weight, then El Centro 1940 at
    0.5 g with HHT) on a mesh of ``element_size`` m, its dynamic stage stepped at a fixed ``dt`` for
    ``steps`` steps or ``duration`` s, recording ``output``. Read it with ``base_dir=EXAMPLES`` where
    a file it names must be found."""
    import tomllib

    from masonrydam.scene.schema import set_time_steps
    from repository_paths import EXAMPLES

    scene = tomllib.loads((EXAMPLES / "koyna_el_centro.toml").read_text())
    scene["mesh"]["parameters"]["element_size"] = element_size
    stage = set_time_steps(scene["stages"][1], dt, steps=steps, duration=duration)
    if output is not None:
        stage["output"] = output
    return merged(scene, overrides)
