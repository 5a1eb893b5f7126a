"""The scene reference: every key a scene may hold, as a declarative table, and its Markdown form.

Each :class:`Key` row gives the dotted path of a key (``[]`` marks the items of a list, ``<name>`` a
name the user chooses: ``materials.<group>.youngs_modulus``, ``stages[].loads[].pressure``), its type,
its SI unit and whether a string with a unit is accepted, its default, its allowed values and a
one-line meaning. The allowed values are the schema's own tuples where it has them (imported here,
so they cannot drift). ``tests/scene/test_scene_reference.py`` checks the table against the keys the
schema accepts, both ways, and the choices against those the schema checks.

``docs/scene.md`` is :func:`render_markdown`'s text; regenerate it with::

    python -m masonrydam.scene.reference > docs/scene.md
"""
from __future__ import annotations

import inspect
import sys
from dataclasses import replace

from generators import GENERATORS
from generators.dams import PRESETS
from generators.walls import BONDS

from ..effects import effect_reference, effect_sections_meaning, load_types
from ..assembly.groups import JOINT_FRAMES, KINEMATICS
from ..materials.continuum_laws import CONTINUUM_LAWS
from ..elements.quadrature import QUADRATURE_SCHEMES
from ..keys import ABSENT, REQUIRED, TIME, UNIT, Key, Section, key
from ..pulses import PULSE_SHAPES
from ..materials import joint_laws as jl
from ..results.writer import OutputOptions
from ..solvers.dynamic import ADAPTIVE_DEFAULT_LEVELS, INTEGRATORS, JOINT_SPACE_MODES, SCHEMES
from ..solvers.linear.direct import LINEAR_SOLVERS
from .schema import (AUTO_DT_MAX_DEFAULT, AUTO_TOLERANCE_DEFAULT, G_STANDARD, HYPOTHESES, LIMIT_POINTS,
                     PROCESSING_STEPS, STAGE_TYPES, STATIC_CONTROLS, SUPPORT_KINDS)

__all__ = ["Key", "Section", "REQUIRED", "ABSENT", "SECTIONS", "keys", "render_markdown", "main"]


_k = key


_TOP = Section("Top level", "The sections of a scene. Unknown keys are errors anywhere, with the closest known "
                            "key suggested.", (
    _k("model", "table", "dimension, plane hypothesis, thickness, gravity and kinematics", default_text="{}"),
    _k("mesh", "table", "the generator and its parameters, or a mesh file", default=REQUIRED),
    _k("materials", "table", "one table per element group: `[materials.<group>]`", default=REQUIRED),
    _k("joints", "table", "one table per joint set of the mesh: `[joints.<set>]` (every joint set needs one)",
       default_text="{}"),
    _k("supports", "list", "the supports: `[[supports]]`", default_text="[]"),
    _k("stages", "list", "the analysis stages in order: static, then at most one modal, then dynamic",
       default=REQUIRED),
    _k("solver", "table", "settings of the static solver", default_text="{}"),
    _k("output", "table", "what the result file records and how it is written", default_text="{}"),
    *(_k(name, "table", meaning) for name, meaning in effect_sections_meaning().items()),
))

_MODEL = Section("[model]", "", (
    _k("model.name", "string", "name of the model (in the run summary and the result's attributes)",
       default="scene"),
    _k("model.dimension", "integer", "2 or 3", default=2),
    _k("model.hypothesis", "string", "2D: plane stress or plane strain (the plastic laws need plane strain); "
                                     "3D: leave it out", default="plane_stress", choices=HYPOTHESES),
    _k("model.thickness", "number", "2D: out-of-plane thickness", "m", UNIT, default=1.0),
    _k("model.gravity", "list", "gravity vector, one value per axis", "m/s2", UNIT,
       default_text=f"[0, -{G_STANDARD:g}] (2D), [0, 0, -{G_STANDARD:g}] (3D)"),
    _k("model.kinematics", "string", "\"large\": total Lagrangian blocks (St. Venant-Kirchhoff) and joints whose "
                                     "frame turns with them (elastic blocks only)", default="small",
       choices=KINEMATICS),
))

_MESH = Section("[mesh]", "Give exactly one of `generator` (with `parameters`) and `file`.", (
    _k("mesh.generator", "string", "a parametric model generator (its parameters: the sections below)",
       choices=sorted(GENERATORS)),
    _k("mesh.parameters", "table", "the generator's parameters", default_text="{}"),
    _k("mesh.file", "string", "a mesh file read by meshio (a `.msh` file as `export-mesh` writes it), relative to "
                              "the scene file's folder"),
    _k("mesh.joints", "list", "with `file`: the physical groups (lines in 2D, surfaces in 3D) that are joints",
       default=[]),
))


# -- generator parameters: meanings and units by hand; type and default from the generator's signature ------
_TYPES = {"float": "number", "int": "integer", "bool": "bool", "str": "string", "list": "list", "dict": "table"}

_WALL_OPENINGS_2D = ("list of `{ x0, y0, width, height, lintel_height = 0, lintel_bearing = 0 }` openings (m; y0 "
                     "from the underside of the masonry); facet sets `opening_<i>`")
_DAM_SECTION = {
    "height": ("m", "height of a parametric section"),
    "crest_width": ("m", "crest width of a parametric section"),
    "crest_kink_height": ("m", "elevation above the base of the kink in the downstream face (default: `height`, "
                               "one downstream slope)"),
    "upstream_slope": ("", "upstream face slope, horizontal : vertical (the heel upstream of the crest)"),
    "downstream_slope": ("", "downstream face slope below the kink, horizontal : vertical"),
    "downstream_upper_slope": ("", "downstream face slope above the kink"),
    "polyline": ("m", "the section's vertices `[[x, y], ...]` instead of the parameters (horizontal base and crest "
                      "edges, faces rising monotonically)"),
    "preset": ("", "a named section instead of the parameters: `\"koyna\"` (Koyna dam, reservoir level 91.75 m)"),
    "lift_spacing": ("m", "lift joints at every multiple of this below the crest"),
    "lift_heights": ("m", "lift joints at these heights above the base (instead of `lift_spacing`)"),
    "foundation_width": ("m", "width of a rock block under the dam, joined by `base_joint` (0: no foundation; the "
                              "base is then the support set `base`)"),
    "foundation_depth": ("m", "depth of the rock block"),
    "galleries": ("m", "list of `{ x, y, width, height }` rectangular openings (x, y: lower-left corner in the "
                       "section); facet sets `gallery_<i>`"),
    "element_size": ("m", "element size (default: height / 20)"),
    "order": ("", "element order, 1 or 2"),
    "reservoir_level": ("m", "water level above the base: facet set `upstream_wet` and node set `waterline` there "
                             "(the Koyna preset: 91.75)"),
}
_GENERATOR_PARAMETERS = {
    "masonry_wall_2d": {
        "length": ("m", "wall length"),
        "height": ("m", "height of the masonry (without the beams)"),
        "unit_length": ("m", "unit (brick) length"),
        "unit_height": ("m", "unit height"),
        "joint_thickness": ("m", "mortar joint thickness, added to the unit size (the expanded units meet at "
                                 "zero-thickness joints)"),
        "bond": ("", "bond of the front elevation (`running` = `stretcher`); header, English and Flemish need "
                     "`unit_width`"),
        "elements_per_unit": ("", "elements along the shortest side of an expanded unit (unless `element_size`)"),
        "order": ("", "element order, 1 or 2"),
        "element": ("", "`\"quad\"` (quad4 / quad8), `\"quad9\"` or `\"tri\"` (tri3 / tri6)"),
        "base_beam_height": ("m", "height of a beam under the wall (group `base_beam`; 0: none)"),
        "top_beam_height": ("m", "height of a beam on the wall (group `top_beam`; 0: none)"),
        "beam_joints": ("", "joints `base_joint` and `top_joint` between the beams and the wall (false: glued)"),
        "unit_width": ("m", "the header's face (header, English and Flemish bonds)"),
        "unit_cracks": ("", "a potential crack at mid-length of every whole unit (joint set `unit_cracks`)"),
        "openings": ("m", _WALL_OPENINGS_2D),
        "element_size": ("m", "element size; 0: from `elements_per_unit`"),
    },
    "masonry_wall_3d": {
        "length": ("m", "wall length (x)"),
        "height": ("m", "height of the masonry (z, without the beams)"),
        "unit_length": ("m", "unit (brick) length"),
        "unit_height": ("m", "unit height"),
        "unit_width": ("m", "unit width"),
        "joint_thickness": ("m", "mortar joint thickness, added to the unit size"),
        "bond": ("", "bond (`stretcher` = `running`)"),
        "thickness": ("m", "wall thickness: 0 for the bond's own, or whole wythes for stretcher and stack bond "
                           "(joined by `collar_joints`)"),
        "elements_per_unit": ("", "elements along the shortest side of an expanded unit (unless `element_size`)"),
        "order": ("", "1: hex8, 2: hex20"),
        "element_size": ("m", "element size; 0: from `elements_per_unit`"),
        "unit_cracks": ("", "a potential crack at mid-length of every whole unit (joint set `unit_cracks`)"),
        "openings": ("m", "list of `{ x0, z0, width, height, lintel_height = 0, lintel_bearing = 0 }` openings "
                          "through the thickness (z0 from the underside of the masonry)"),
        "base_beam_height": ("m", "height of a beam under the wall (0: none)"),
        "top_beam_height": ("m", "height of a beam on the wall (0: none)"),
        "beam_joints": ("", "joints `base_joint` and `top_joint` between the beams and the wall (false: glued)"),
    },
    "blocks_2d": {
        "blocks": ("m", "list of `{ x0, y0, x1, y1, group }` rectangles, each its own body (element group `group`, "
                        "default `blocks`)"),
        "element_size": ("m", "largest element edge"),
        "order": ("", "element order, 1 or 2"),
        "element": ("", "`\"quad\"` (quad4 / quad8), `\"quad9\"` or `\"tri\"`"),
        "rotation_deg": ("deg", "the whole model turned counter-clockwise about the origin (the sets keep their "
                                "unrotated names)"),
        "joint_name": ("", "name of the joint set between the blocks"),
    },
    "blocks_3d": {
        "blocks": ("m", "list of `{ x0, y0, z0, x1, y1, z1, group }` boxes, each its own body"),
        "element_size": ("m", "largest element edge"),
        "order": ("", "1: hex8, 2: hex20"),
        "rotation_deg": ("deg", "`[about_x, about_y, about_z]`, applied in that order about the origin (default: "
                                "none)"),
        "joint_name": ("", "name of the joint set between the boxes"),
    },
    "extruded": {
        "generator": ("", "the 2D generator whose model is extruded"),
        "parameters": ("", "that generator's parameters (its section above)"),
        "depth": ("m", "thickness of the slab, along y from 0 to `depth`"),
        "layers": ("", "elements through the thickness"),
    },
    "gravity_dam_2d": {**_DAM_SECTION, "element": ("", "`\"quad\"` (quad4 / quad8) or `\"tri\"` (tri3 / tri6)")},
    "gravity_dam_3d": {
        "valley_bottom_width": ("m", "valley width at the dam base"),
        "valley_top_width": ("m", "valley width at the crest (the dam axis x runs from 0 to it)"),
        "n_monoliths": ("", "number of equal monoliths, separated by `contraction_joints`"),
        **{k: v for k, v in _DAM_SECTION.items() if k != "order"},
        "order": ("", "1: hex8, 2: hex20"),
    },
    "arch_dam_3d": {
        "height": ("m", "dam height (z from the base, 0, to the crest)"),
        "crest_radius": ("m", "extrados (upstream face) radius of the crest arch"),
        "central_angle_deg": ("deg", "full central angle of every horizontal arch, in (0, 180]"),
        "crest_thickness": ("m", "arch thickness at the crest"),
        "n_monoliths": ("", "equal-angle cantilever monoliths, separated by radial `contraction_joints`"),
        "base_thickness": ("m", "arch thickness at the base (default: `crest_thickness`; linear in between)"),
        "base_radius": ("m", "extrados radius at the base (default: `crest_radius`; linear in between)"),
        "valley_bottom_width": ("m", "bottom width of a trapezoidal valley whose top width is the crest chord of "
                                     "the dam axis; the bank monoliths stand on it (default: all full height)"),
        "lift_spacing": ("m", "horizontal `lift_joints` at every multiple of it above the base"),
        "foundation_depth": ("m", "depth of a rock block under the valley floor, joined by `base_joint` (0: no "
                                  "foundation; the base is then the support set `base`)"),
        "foundation_extent": ("m", "radial widening of the rock block upstream and downstream of the arch"),
        "element_size": ("m", "element size (default: height / 20)"),
        "order": ("", "1: hex8, 2: hex20"),
        "reservoir_level": ("m", "water level above the base: facet set `upstream_wet` and node set `waterline` "
                                 "there"),
        "crown_overhang": ("m", "double curvature: the largest upstream offset (towards -y) of the crown's upstream "
                                "face from the crest's, >= 0 (0: a vertical crown); the crown's upstream face is the parabola "
                                "y = -crown_overhang (1 - ((z - z_o) / (H - z_o))^2) (z_o: `overhang_height`, H: "
                                "`height`), each horizontal arch's centre moving with it"),
        "overhang_height": ("m", "elevation z_o of the largest overhang above the base, strictly between 0 and "
                                 "`height` (default: 0.45 `height`)"),
    },
}
_GENERATOR_TEXT = {
    "masonry_wall_2d": "A 2D wall of courses of units, on optional beams. Groups `units`, `lintels`, `base_beam`, "
                       "`top_beam`; joint sets `bed_joints`, `head_joints`, `unit_cracks`, `lintel_joints`, "
                       "`base_joint`, `top_joint`; node sets `base`, `top`, `left`, `right`, `beams`; facet sets "
                       "`base_edge`, `top_edge`, `left_edge`, `right_edge`, `opening_<i>`.",
    "masonry_wall_3d": "A 3D wall of hexahedral units in a bond pattern. Joint sets `bed_joints`, `head_joints`, "
                       "`collar_joints`, `unit_cracks`, `lintel_joints`, `base_joint`, `top_joint`; node sets `base`, "
                       "`top`, `left`, `right`, `front`, `back`, `<group>_nodes`, `beams`; facet sets `base_face`, "
                       "`top_face`, `left_face`, `right_face`, `front_face`, `back_face`, `opening_<i>`.",
    "blocks_2d": "Axis-aligned rectangular blocks meshed conformally, with joints between different blocks.",
    "blocks_3d": "Axis-aligned boxes meshed with hexahedra, with surface joints between different boxes.",
    "extruded": "A 2D generator's model extruded into a 3D slab: x stays, the 2D y becomes z (up) and the "
                "thickness runs along y; quad4 blocks become hex8 and the joints 8-node surface interfaces (the 2D "
                "model must be of linear quadrilaterals: order 1, element \"quad\"). Facet sets `front_face` and "
                "`back_face` are added.",
    "gravity_dam_2d": "A gravity dam section (x upstream to downstream, y up; gmsh), given by parameters, a polyline "
                      "or a preset, with lift joints, an optional foundation block and galleries. Facet sets "
                      "`upstream_face`, `downstream_face`, `crest`, `upstream_wet`, `base` or `foundation_bottom`, "
                      "`foundation_sides`, `foundation_top`.",
    "gravity_dam_3d": "A dam of monoliths across a trapezoidal valley (x along the axis, y downstream, z up): the "
                      "section of `gravity_dam_2d` extruded into hexahedra, with `lift_joints`, "
                      "`contraction_joints` and `base_joint`; facet set `dam_ends` at the banks.",
    "arch_dam_3d": "A single-centre arch dam of cantilever monoliths (x across the valley, symmetric about 0; y "
                   "downstream; z up; the crown's upstream face on x = y = 0, or overhanging upstream on a parabola "
                   "with `crown_overhang`: a double-curvature arch), a mapped grid of hexahedra with "
                   "`lift_joints`, `contraction_joints` and `base_joint`; facet sets `upstream_face`, "
                   "`downstream_face`, `crest`, `dam_ends` (the two ends of the arch), `upstream_wet`, `base` or "
                   "`foundation_bottom`, `foundation_sides`, `foundation_top`; node set `crest_upstream`.",
}
_GENERATOR_CHOICES = {"bond": BONDS, "preset": tuple(PRESETS),
                      "generator": tuple(sorted(g for g in GENERATORS if g.endswith("_2d")))}


def _generator_keys(name: str) -> tuple:
    """The rows of generator ``name``: unit and meaning from the table above; type, default and whether a
    string with a unit is read from its signature (the schema converts parameters annotated ``float``)."""
    sig = inspect.signature(GENERATORS[name])
    rows = []
    for p, (unit, meaning) in _GENERATOR_PARAMETERS[name].items():
        par = sig.parameters.get(p)
        ann = "?" if par is None else str(par.annotation)
        base = ann.split("|")[0].strip()
        if par is None or par.default is inspect.Parameter.empty:
            default = REQUIRED
        else:
            default = ABSENT if par.default is None else par.default
        unit_string = UNIT if ann == "float" and unit else ""
        rows.append(_k(f"mesh.parameters.{p}", _TYPES.get(base, base), meaning, unit, unit_string, default,
                       choices=_GENERATOR_CHOICES.get(p) if p in ("bond", "preset", "generator") else None,
                       variants=(name,)))
    return tuple(rows)


_GENERATOR_SECTIONS = tuple(
    Section(f"[mesh] generator = \"{name}\"", _GENERATOR_TEXT[name] + (
        " Lengths given as plain numbers are in m; where the unit-string column is empty, the parameter takes plain "
        "numbers only."), _generator_keys(name), "generator")
    for name in GENERATORS)


# -- materials: the law keys of each law from CONTINUUM_LAWS --------------------------------------------------
_LAW_KEYS = {
    "yield_stress": ("number", "Pa", UNIT, "yield stress"),
    "isotropic_hardening": ("number", "Pa", "", "isotropic hardening modulus (negative: softening, needs "
                                                "`regularisation_length`)"),
    "kinematic_hardening": ("number", "Pa", "", "kinematic hardening modulus (>= 0)"),
    "residual_yield_stress": ("number", "Pa", UNIT, "yield stress that softening stops at"),
    "cohesion": ("number", "Pa", UNIT, "cohesion"),
    "friction_angle": ("number", "deg", "", "friction angle, 0 to 89.9"),
    "dilation_angle": ("number", "deg", "", "dilation angle (left out: the friction angle, associated flow)"),
    "cohesion_hardening": ("number", "Pa", "", "cohesion hardening modulus (negative: softening, needs "
                                               "`regularisation_length`)"),
    "residual_cohesion": ("number", "Pa", UNIT, "cohesion that softening stops at"),
    "match": ("string", "", "", "Drucker-Prager cone matched to Mohr-Coulomb in plane strain, on the outer or the "
                                "inner edges"),
    "viscosity": ("number", "Pa s", "", "Perzyna viscosity (0: rate-independent; > 0: static stages need a "
                                        "`duration`)"),
    "regularisation_length": ("number", "m", UNIT, "element size that a softening modulus holds for (each "
                                                   "element's modulus is scaled by its size)"),
}


def _law_rows() -> tuple:
    rows = []
    for k, (type_, unit, unit_string, meaning) in _LAW_KEYS.items():
        laws = tuple(law for law, spec in CONTINUUM_LAWS.items() if k in spec)
        defaults = {CONTINUUM_LAWS[law][k] for law in laws}
        default = next(iter(defaults)) if len(defaults) == 1 else ABSENT
        if default is None:
            default = ABSENT if k in ("dilation_angle", "regularisation_length") else REQUIRED
        rows.append(_k(f"materials.<group>.{k}", type_, meaning, unit, unit_string, default,
                       choices=("plane_strain", "outer", "inner") if k == "match" else None, variants=laws))
    return tuple(rows)


_MATERIALS = Section("[materials.&lt;group&gt;]", "One table per element group of the mesh (the generators' "
                     "groups, or the physical groups of a mesh file). The law keys apply to the laws in the column "
                     "\"For\"; a key of another law is an error. The plastic laws need plane strain in 2D.", (
    _k("materials.<group>.model", "string", "the elastic model (the only one)", default="linear_elastic",
       choices=("linear_elastic",)),
    _k("materials.<group>.youngs_modulus", "number", "Young's modulus", "Pa", UNIT, REQUIRED),
    _k("materials.<group>.poisson_ratio", "number", "Poisson's ratio, in (-1, 0.5)", default=REQUIRED),
    _k("materials.<group>.density", "number", "mass density (self-weight, inertia)", "kg/m3", UNIT, 0.0),
    _k("materials.<group>.integration", "string", "`\"reduced\"`: 2 x 2 (x 2) Gauss points for quad8 / hex20",
       default="full", choices=("full", "reduced")),
    _k("materials.<group>.law", "string", "continuum law: elastic, or elasto-plastic (small strains)",
       default="elastic", choices=tuple(CONTINUUM_LAWS)),
    *_law_rows(),
), "law")


# -- joints: the law keys of each registered joint law (masonrydam.materials.joint_laws) ---------------------
def _joint_default(default):
    return REQUIRED if default is jl.REQUIRED else ABSENT if default is jl.OPTIONAL else default


def _joint_law_rows() -> tuple:
    """One row per law key, in the order the laws declare them; a key of several laws (``cohesion``) is one row
    with its meaning and unit from the first law, and its default in words where the laws' defaults differ."""
    by_name = {}
    for law in jl.joint_laws():
        for k in law.keys:
            by_name.setdefault(k.name, []).append((law.name, k))
    rows = []
    for name, owners in by_name.items():
        first = owners[0][1]
        defaults = [_joint_default(k.default) for _, k in owners]
        same = all(d is defaults[0] or d == defaults[0] for d in defaults)
        words = [repr(d) if d is REQUIRED or d is ABSENT else format(d, "g") for d in defaults]
        text = "" if same else ", ".join(f"{w} ({law})" for (law, _), w in zip(owners, words))
        unit_string = TIME if first.dimension == "time" else UNIT if first.dimension is not None else ""
        rows.append(_k(f"joints.<set>.{name}", "number", first.meaning, first.si_unit, unit_string,
                       defaults[0] if same else ABSENT, default_text=text,
                       variants=tuple(law for law, _ in owners)))
    return tuple(rows)


_JOINTS = Section("[joints.&lt;set&gt;]", "One table per joint set of the mesh. " + "; ".join(
    f"`{law.name}`: {law.description}" for law in jl.joint_laws()) + ".", (
    _k("joints.<set>.law", "string", "joint law", default=jl.DEFAULT_JOINT_LAW,
       choices=tuple(law.name for law in jl.joint_laws())),
    _k("joints.<set>.normal_stiffness", "number", "normal stiffness kn", "N/m3", UNIT, REQUIRED),
    _k("joints.<set>.shear_stiffness", "number", "shear stiffness ks", "N/m3", UNIT, REQUIRED),
    *_joint_law_rows(),
    _k("joints.<set>.integration", "string", "integration rule along the joint (nodal `lumped`; 16-node interfaces "
       "then take 3 x 3 Lobatto)", default="lumped", choices=QUADRATURE_SCHEMES),
    _k("joints.<set>.points", "integer", "points per direction of a `gauss`, `lobatto` or `newton-cotes` rule "
       "(triangles: in all; default: the nodes per edge)", default=ABSENT),
    _k("joints.<set>.frame", "string", "large kinematics: the joint frame turns with the mid-surface, or with the "
       "bottom face (a side that slides far over a supporting face)", default_text="\"mid_surface\"",
       choices=JOINT_FRAMES),
), "law")

_SUPPORTS = Section("[[supports]]", "", (
    _k("supports[].set", "string", "node set", default=REQUIRED),
    _k("supports[].components", "list", "components held (`\"x\"`, `\"y\"`, `\"z\"`; a single string is one)",
       default_text="all"),
    _k("supports[].kind", "string", "`fixed`: held at zero; `tied`: the set's nodes share one displacement in "
       "these components (a loading beam kept level)", default="fixed", choices=SUPPORT_KINDS),
))

_STAGE_NAME = _k("stages[].name", "string", "stage name (unique)", default_text="\"stageN\" (N from 1)")


def _type_row(variant):
    return _k("stages[].type", "string", "stage type", default="static", choices=STAGE_TYPES, variants=(variant,))


def _for(variants, rows):
    return tuple(replace(r, variants=tuple(variants)) for r in rows)


_STATIC = Section("[[stages]] type = \"static\"", "A static stage applies its loads over `steps` increments, "
                  "from the state the previous stages left.", _for(("static",), (
    _STAGE_NAME,
    _type_row("static"),
    _k("stages[].steps", "integer", "load increments (at most 10^6)", default=1),
    _k("stages[].loads", "list", "the stage's loads `[[stages.loads]]`", default=[]),
    _k("stages[].control", "string", "`load`: load and displacement control, switching to arc length where a step "
       "finds no equilibrium; `arc_length`: Crisfield's cylindrical arc length from the start; `opening`: indirect "
       "displacement control on the opening of the cracking joints; `dissipation`: every step dissipates a chosen "
       "energy in the joints (the stage's own control until they dissipate); path following is refused on a stage "
       "with reservoir water", default="load",
       choices=STATIC_CONTROLS),
    _k("stages[].limit_point", "string", "control `load` only, where a step finds no equilibrium after its cuts: "
       "`follow` the path under arc-length control; `relax`: hold the step's loads and let the joints with a viscous "
       "regularisation relax until they reach an equilibrium of their own law (the snap of a pushed wall; "
       "docs/masonry_softening.md)", default="follow", choices=LIMIT_POINTS),
    _k("stages[].until_failure", "bool", "last stage only: run until no equilibrium is found and record the peak "
       "(a reservoir stage: the level reached)", default=False),
    _k("stages[].duration", "number", "physical time of the stage, for viscous blocks (Perzyna) or joints "
       "(`relaxation_time`)", "s", default=ABSENT),
)), "type")


_STATIC_TYPES = tuple(load_types())
_FACET_TYPES = ("traction", "edge_traction", "pressure", "edge_pressure")
_SET_TYPES = ("nodal", *_FACET_TYPES, "displacement")
_LOADS = Section("[[stages.loads]] of a static stage", "A load is applied in full at the end of its stage. The "
                 "loads of earlier stages stay applied.", (
    _k("stages[].loads[].type", "string", "load type (`edge_traction`, `edge_pressure`: the 2D names of `traction` "
       "and `pressure`)", default=REQUIRED, choices=_STATIC_TYPES, variants=_STATIC_TYPES),
    _k("stages[].loads[].factor", "number", "multiplier of the self-weight", default=1.0, variants=("self_weight",)),
    _k("stages[].loads[].acceleration", "list", "a body force rho a in its own direction instead of [model] gravity "
       "(pseudo-static seismic coefficient, tilt table)", "m/s2", UNIT, default_text="[model] gravity",
       variants=("self_weight",)),
    _k("stages[].loads[].groups", "list", "the element groups whose weight is applied (a foundation's rock carries "
       "its own weight before the dam is built: `groups = [\"dam\"]`)", default_text="all groups",
       variants=("self_weight",)),
    _k("stages[].loads[].set", "string", "node set (nodal, displacement) or facet set (edges in 2D, faces in 3D)",
       default=REQUIRED, variants=_SET_TYPES),
    _k("stages[].loads[].force", "list", "force on every node of the set, one value per axis", "N", UNIT,
       REQUIRED, variants=("nodal",)),
    _k("stages[].loads[].traction", "list", "traction vector on the facets, one value per axis", "Pa", UNIT,
       REQUIRED, variants=("traction", "edge_traction")),
    _k("stages[].loads[].pressure", "number", "pressure normal to the facets (positive pushes into the body)", "Pa",
       UNIT, REQUIRED, variants=("pressure", "edge_pressure")),
    _k("stages[].loads[].components", "list", "components driven (`\"x\"`, `\"y\"`, `\"z\"`)", default=REQUIRED,
       variants=("displacement",)),
    _k("stages[].loads[].value", "list", "displacement increment over the stage, one per component", "m", UNIT,
       REQUIRED, variants=("displacement",)),
    _k("stages[].loads[].level", "number", "water level the stage raises the reservoir to", "m", UNIT,
       default_text="[reservoir] level; later stages: the level reached", variants=("reservoir",)),
), "type")

_MODAL = Section("[[stages]] type = \"modal\"", "At most one, after the static stages and before the dynamic "
                 "ones: the modes of the static state (sticking joint points elastic, open points free).", _for(
    ("modal",), (
        _STAGE_NAME,
        _type_row("modal"),
        _k("stages[].modes", "integer", "number of modes: fewer than the free DOFs at the stage (checked before any "
           "stage runs)", default=6),
        _k("stages[].mass", "string", "mass matrix", default="consistent", choices=("lumped", "consistent")),
    )), "type")

_DYNAMIC = Section("[[stages]] type = \"dynamic\"", "A time history from the state of the static stages, whose "
                   "loads stay applied. It needs a ground motion, an initial velocity or loads with a time "
                   "function; `steps` or `duration` gives its length (with a ground motion: the record's by "
                   "default).", _for(("dynamic",), (
    _STAGE_NAME,
    _type_row("dynamic"),
    _k("stages[].dt", "number or string", "time step, or `\"auto\"`: implicit schemes take steps dt_max / 2^k chosen "
       "by their local error, never crossing a multiple of dt_max; central_difference takes the largest stable step "
       "that divides the output interval (`output.dt`, default 0.01 s), its reason in the run summary", "s", TIME,
       REQUIRED),
    _k("stages[].steps", "integer", "number of steps (of dt_max with dt = \"auto\"; at most 10^9); or give "
       "`duration`"),
    _k("stages[].duration", "number", "length of the stage (at most 10^9 steps of dt, or of dt_max; a warning where "
       "it runs past ten times its longest ground motion); or give `steps`", "s", TIME),
    _k("stages[].tolerance", "number", "dt = \"auto\": relative local error per step", default=AUTO_TOLERANCE_DEFAULT),
    _k("stages[].dt_max", "number", "dt = \"auto\": largest step (the output grid)", "s", TIME,
       default_text=f"output dt, else {AUTO_DT_MAX_DEFAULT:g}"),
    _k("stages[].dt_min", "number", "dt = \"auto\": smallest step", "s", TIME,
       default_text=f"dt_max / {2 ** ADAPTIVE_DEFAULT_LEVELS}"),
    _k("stages[].integrator", "string", "time integrator ("
       + "; ".join(f"`{sc.name}`: explicit, with a computed critical step; needs mass = \"lumped\""
                   for sc in SCHEMES if sc.explicit) + ")", default="hht", choices=INTEGRATORS),
    _k("stages[].alpha", "number", "HHT alpha, in [-1/3, 0]", default=-0.1),
    _k("stages[].rho_inf", "number", "generalized-alpha spectral radius at infinite frequency, in [0, 1]",
       default=0.8),
    _k("stages[].mass", "string", "mass matrix", default="lumped", choices=("lumped", "consistent")),
    _k("stages[].damping", "table", "Rayleigh damping `[stages.damping]` (default: none)"),
    _k("stages[].ground_motion", "table", "base excitation, one table per axis `[stages.ground_motion.x]`"),
    _k("stages[].initial_velocity", "table or list", "initial velocity of element groups (a table or a list of "
       "tables)"),
    _k("stages[].initial_displacement", "table or list", "a displacement of element groups added to the state the "
       "stage starts from, out of equilibrium, with the velocity it had (at rest after the static stages; a table or a list of "
       "tables)"),
    _k("stages[].loads", "list", "loads given in time (below)", default=[]),
    _k("stages[].output", "table", "which steps and what the stage records `[stages.output]`", default_text="{}"),
    _k("stages[].max_iterations", "integer", "Newton iterations per step", default=25),
    _k("stages[].max_substeps", "integer", "halvings of a step that does not converge", default=4),
    _k("stages[].force_tolerance", "number", "Newton tolerance on the residual force (relative), in (0, 1)",
       default=1e-6),
    _k("stages[].energy_tolerance", "number", "Newton tolerance on the work of the correction (relative), in (0, 1)",
       default=1e-8),
    _k("stages[].low_rank_max", "integer", "largest low-rank update of a kept factorization (joint DOFs that "
       "changed state)", default=256),
    _k("stages[].joint_space", "string or bool", "implicit steps solved on the joint unknowns, condensed from the "
       "linear blocks (`auto` = `on`; true: `on`, false: `off`)", default="auto", choices=JOINT_SPACE_MODES),
)), "type")

_DAMPING = Section("[stages.damping]", "Rayleigh damping C = alpha M + beta K: give `ratio` and `frequencies`, or "
                   "`alpha` and `beta`. With central_difference, `model = \"local\"` and a `ratio` give local "
                   "(non-viscous) damping, the same ratio at every frequency, which leaves the stable step alone "
                   "(docs/dam_3d.md).", (
    _k("stages[].damping.model", "string", "`rayleigh`: viscous C = alpha M + beta K; `local`: the force "
       "-alpha_L |f_int - f_s| sign(v) at every DOF, alpha_L = tanh(pi ratio) (Cundall 1987; explicit only)",
       default="rayleigh", choices=("rayleigh", "local")),
    _k("stages[].damping.ratio", "number", "damping ratio at the two frequencies, in [0, 0.99]; local: at every "
       "frequency, in [0, 0.3]"),
    _k("stages[].damping.frequencies", "list", "the two frequencies [f1, f2], f1 < f2", "Hz"),
    _k("stages[].damping.alpha", "number", "mass-proportional coefficient", "1/s", default_text="0 (with beta)"),
    _k("stages[].damping.beta", "number", "stiffness-proportional coefficient", "s", default_text="0 (with alpha)"),
    _k("stages[].damping.exclude_joints", "bool", "keep the penalty stiffness of the joints out of the damping",
       default=True),
))

_GM = "stages[].ground_motion"
_GROUND = Section("[stages.ground_motion.&lt;axis&gt;]", "One table per axis (`x`, `y`, and `z` in 3D) with exactly "
                  "one source: `record`, `file`, `values` (with `dt`) or `pulse`; then optional `processing` and one "
                  "scaling (`scale`, `scale_to_pga` or `scale_to_sa`). Every step lands in the result attribute "
                  "`stageN_ground_motion_<axis>_provenance`.", (
    _k(f"{_GM}.x", "table", "ground acceleration along x"),
    _k(f"{_GM}.y", "table", "ground acceleration along y"),
    _k(f"{_GM}.z", "table", "3D: ground acceleration along z"),
    _k(f"{_GM}.<axis>.record", "string", "a bundled record (`masonrydam records list`)"),
    _k(f"{_GM}.<axis>.file", "string", "a record file (PEER AT2, anything obspy reads, plain text), relative to "
       "the scene file's folder"),
    _k(f"{_GM}.<axis>.format", "string", "`file`: `\"AT2\"` / `\"PEER\"`, `\"TEXT\"` or an obspy format name",
       default_text="detected"),
    _k(f"{_GM}.<axis>.units", "string", "units of the values (`g`, `m/s2`, `cm/s2`, `gal`, `mm/s2`): `file`, where "
       "the file does not state them; `values`", default_text="\"m/s2\" (values)"),
    _k(f"{_GM}.<axis>.dt", "number", "time step of `values`; of a `file` without a time column; of a `pulse`'s "
       "samples (default: the stage's dt)", "s", TIME),
    _k(f"{_GM}.<axis>.column", "integer", "`file`: the value column of a text file, from 0 without the time column"),
    _k(f"{_GM}.<axis>.values", "list", "accelerations at every `dt`, in `units`"),
    _k(f"{_GM}.<axis>.pulse", "table", "a pulse `{ shape, amplitude, duration }`"),
    _k(f"{_GM}.<axis>.processing", "list", "processing steps applied in order before the scaling (below)",
       default=[]),
    _k(f"{_GM}.<axis>.scale", "number", "factor on the accelerations"),
    _k(f"{_GM}.<axis>.scale_to_pga", "number", "scale to this peak ground acceleration", "m/s2", UNIT),
    _k(f"{_GM}.<axis>.scale_to_sa", "table", "scale to a pseudo-spectral acceleration `{ sa, period, damping }`"),
    _k(f"{_GM}.<axis>.pulse.shape", "string", "pulse shape: `amplitude` times 1 (rectangular), a half sine or a "
       "symmetric triangle of peak 1 over `duration` (masonrydam.pulses; Chopra 2012, secs. 4.7-4.9)",
       default=REQUIRED, choices=PULSE_SHAPES),
    _k(f"{_GM}.<axis>.pulse.amplitude", "number", "peak acceleration", "m/s2", UNIT, REQUIRED),
    _k(f"{_GM}.<axis>.pulse.duration", "number", "pulse length", "s", TIME, REQUIRED),
    _k(f"{_GM}.<axis>.scale_to_sa.sa", "number", "target pseudo-spectral acceleration", "m/s2", UNIT, REQUIRED),
    _k(f"{_GM}.<axis>.scale_to_sa.period", "number", "its period", "s", TIME, REQUIRED),
    _k(f"{_GM}.<axis>.scale_to_sa.damping", "number", "its damping ratio, in (0, 1]", default=0.05),
))

_P = f"{_GM}.<axis>.processing[]"
_PROCESSING = Section("processing = [{ step = ... }, ...]", "The processing steps of a ground-motion component "
                      "(`masonrydam.records.processing`); their values are checked when the record is built.", (
    _k(f"{_P}.step", "string", "the step", default=REQUIRED, choices=tuple(PROCESSING_STEPS),
       variants=tuple(PROCESSING_STEPS)),
    _k(f"{_P}.method", "string", "`\"demean\"`, `\"linear\"` or `\"polynomial\"`", default="linear",
       variants=("baseline",)),
    _k(f"{_P}.order", "integer", "order of the polynomial baseline", default_text="2", variants=("baseline",)),
    _k(f"{_P}.max_percentage", "number", "cosine taper over this fraction of the length at each end, 0 to 0.5",
       default=0.05, variants=("taper",)),
    _k(f"{_P}.side", "string", "`\"both\"`, `\"left\"` or `\"right\"`", default="both", variants=("taper",)),
    _k(f"{_P}.max_length", "number", "longest taper", "s", default_text="none", variants=("taper",)),
    _k(f"{_P}.freqmin", "number", "high-pass corner (zero-phase Butterworth; with freqmax: band-pass)", "Hz",
       variants=("bandpass",)),
    _k(f"{_P}.freqmax", "number", "low-pass corner", "Hz", variants=("bandpass",)),
    _k(f"{_P}.corners", "integer", "filter order (run forwards and backwards)", default=4, variants=("bandpass",)),
    _k(f"{_P}.dt", "number", "new time step", "s", TIME, REQUIRED, variants=("resample",)),
    _k(f"{_P}.method", "string", "`\"polyphase\"` (rational ratio) or `\"fourier\"`", default="polyphase",
       variants=("resample",)),
    _k(f"{_P}.start", "number", "Husid fraction where the kept window starts", default=0.05, variants=("trim",)),
    _k(f"{_P}.end", "number", "Husid fraction where it ends", default=0.95, variants=("trim",)),
    _k(f"{_P}.pad", "number", "widening of the window on each side", "s", default=0.0, variants=("trim",)),
), "step")

_IV = "stages[].initial_velocity"
_INITIAL = Section("initial_velocity", "A table or a list of tables: a translation (`velocity`) or a rigid rotation "
                   "(`angular_velocity` about `rotation_center`) of element groups. A stage with an initial velocity "
                   "may have no ground motion.", (
    _k(f"{_IV}.groups", "list", "element groups (a single string is one)", default=REQUIRED),
    _k(f"{_IV}.velocity", "list", "velocity, one value per axis", "m/s"),
    _k(f"{_IV}.angular_velocity", "number or list", "2D: a number; 3D: a vector [wx, wy, wz]", "rad/s"),
    _k(f"{_IV}.rotation_center", "list", "the point the rotation is about (with `angular_velocity`)", "m", UNIT),
))

_ID = "stages[].initial_displacement"
_INITIAL_DISPLACEMENT = Section("initial_displacement", "A table or a list of tables: a translation (`displacement`) "
                                "or a small rigid rotation (`rotation` about `rotation_center`, u = theta x (x - c)) "
                                "of element groups, added to the state before the stage; it starts there with the velocity it had (at rest after "
                                "the static stages). A "
                                "stage with an initial displacement may have no ground motion.", (
    _k(f"{_ID}.groups", "list", "element groups (a single string is one)", default=REQUIRED),
    _k(f"{_ID}.displacement", "list", "displacement, one value per axis", "m", UNIT),
    _k(f"{_ID}.rotation", "number or list", "2D: a number; 3D: a vector [tx, ty, tz] (small)", "rad"),
    _k(f"{_ID}.rotation_center", "list", "the point the rotation is about (with `rotation`)", "m", UNIT),
))

_STAGE_OUTPUT = Section("[stages.output]", "What a dynamic stage records. Every dynamic stage that selects nodes or "
                        "joints must select the same ones.", (
    _k("stages[].output.stride", "integer", "record every k-th step", default=1),
    _k("stages[].output.dt", "number", "output interval instead of `stride`: a whole multiple of dt (or dt_max)",
       "s", TIME),
    _k("stages[].output.nodes", "string or list", "`\"all\"` or one or more node sets", default_text="[output] nodes"),
    _k("stages[].output.joints", "string or list", "`\"all\"` or one or more joint sets",
       default_text="[output] joints"),
))

_SOLVER = Section("[solver]", "The static solver (Newton with step cutting; the dynamic stages have their own "
                  "settings).", (
    _k("solver.method", "string", "`newton`: a new tangent every iteration; `modified_newton`: the step's first one",
       default="newton", choices=("newton", "modified_newton")),
    _k("solver.line_search", "bool", "line search on the Newton correction", default=True),
    _k("solver.max_iterations", "integer", "Newton iterations per step before it is cut", default=30),
    _k("solver.force_tolerance", "number", "convergence: residual force relative to the applied forces, in (0, 1)",
       default=1e-6),
    _k("solver.energy_tolerance", "number", "convergence: work of the correction relative to the first one, in "
       "(0, 1)", default=1e-10),
    _k("solver.max_step_cuts", "integer", "halvings of a step that does not converge", default=8),
    _k("solver.linear_solver", "string", "`auto`: PARDISO (SuperLU without it); AMG for large 3D models",
       default="auto", choices=LINEAR_SOLVERS),
    _k("solver.joint_space", "string", "`auto`: each step first solved on the joint unknowns, condensed from the "
       "all-stick stiffness, and checked on the full residual; `off`: the general Newton path alone",
       default="auto", choices=("auto", "off")),
))

_OUT = OutputOptions()
_OUTPUT = Section("[output]", "What the result file records, and how steps reach it: they are collected in memory "
                  "and written in blocks.", (
    _k("output.nodes", "string or list", "`\"all\"` or one or more node sets whose nodes are recorded", default="all"),
    _k("output.joints", "string or list", "`\"all\"` or one or more joint sets whose points are recorded",
       default="all"),
    _k("output.stress", "string", "`element`: the continuum stress of every element (mean of its integration "
       "points) at every recorded step", default="none", choices=("none", "element")),
    _k("output.precision", "string", "`single`: nodal and joint fields as float32 (half the size)",
       default=_OUT.precision, choices=("double", "single")),
    _k("output.compression", "integer", "zlib level of the step variables, 0 (none) to 9", default=_OUT.compression),
    _k("output.buffer_steps", "integer", "steps collected before a block is written", default=_OUT.buffer_steps),
    _k("output.flush_seconds", "number", "a block is written at the latest this long after the previous one",
       "s", TIME, _OUT.flush_seconds),
))

#: the tables of the reference, in the order of docs/scene.md
SECTIONS: tuple = (_TOP, _MODEL, _MESH, *_GENERATOR_SECTIONS, _MATERIALS, _JOINTS, _SUPPORTS, _STATIC, _LOADS,
                   _MODAL, _DYNAMIC, _DAMPING, _GROUND, _PROCESSING, _INITIAL, _INITIAL_DISPLACEMENT, _STAGE_OUTPUT,
                   *effect_reference("dynamic_stage"), _SOLVER, _OUTPUT, *effect_reference("section"))


def keys() -> list:
    """Every row of the reference, in order."""
    return [k for s in SECTIONS for k in s.keys]


# -- Markdown -----------------------------------------------------------------------------------------------
def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f"\"{v}\""
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return str(v)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _default(k: Key) -> str:
    if k.default_text:
        return k.default_text
    if k.default is REQUIRED:
        return "required"
    if k.default is ABSENT:
        return "-"
    return f"`{_value(k.default)}`"


def _table(section: Section) -> list:
    show_for = bool(section.discriminator) and len({k.variants for k in section.keys}) > 1
    head = ["Key", "Type", "Unit", "Unit string", "Default", "Values"] + (["For"] if show_for else []) + ["Meaning"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    for k in section.keys:
        cells = [f"`{k.path}`", k.type, k.unit, k.unit_string, _default(k),
                 ", ".join(f"`{_value(c)}`" for c in k.choices) if k.choices else ""]
        if show_for:
            cells.append(", ".join(k.variants) if k.variants else "all")
        cells.append(k.meaning)
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return lines


_INTRO = """\
# Scene reference

Every key a scene may hold. This file is generated from `masonrydam/scene/reference.py`
(`python -m masonrydam.scene.reference > docs/scene.md`); `tests/scene/test_scene_reference.py` checks the
table against the keys the schema accepts.

How to read it:

- A key is a dotted path: `[]` marks the items of a list (`stages[].loads[].pressure` is the
  `pressure` of a load of a stage; `--set` takes the same paths with indices, `stages[0].loads[1].pressure`),
  `<group>`, `<set>` and `<axis>` stand for a name (an element group, a joint set, `x`, `y` or `z`).
- Numbers are SI, in the unit given. Where the column "Unit string" says `yes`, a string with a unit
  of the right kind is accepted too (`"16.7 GPa"`, `"82 N/mm3"`, `"10 mm"`, `"0.3 g"`, `"30 deg"`);
  `s, ms` means a time written as `"0.01 s"` or `"10 ms"`. Elsewhere the key takes a plain number.
- NaN and infinity are errors, and so are values orders of magnitude outside the plausible range of
  their key (`PLAUSIBLE` in `masonrydam/units.py`).
- Default: `required` must be given; `-` means the key is optional and has no value of its own
  (the feature is off, or the value is computed as the meaning says).
- "For": the values of the section's `type`, `law`, `step` or generator that the key applies to.
"""


def render_markdown() -> str:
    """The text of ``docs/scene.md``."""
    out = [_INTRO]
    for s in SECTIONS:
        out.append(f"## {s.title}\n")
        if s.text:
            out.append(s.text + "\n")
        out.append("\n".join(_table(s)) + "\n")
    return "\n".join(out)


def main(argv=None) -> int:
    sys.stdout.write(render_markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
