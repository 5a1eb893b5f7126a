"""Water on a dam: the reservoir, the tailwater and the silt, as a scene section and as stage loads.

Scene::

    [reservoir]
    level = 91.75          # water surface, m on the vertical axis (the axis gravity acts along)
    density = 1000.0       # kg/m3
    face = "upstream_face" # facet set; only its part below the level is loaded
    tailwater = { level = 5.0, face = "downstream_face" }
    silt = { level = 12.0, submerged_density = 1100.0, lateral_coefficient = 0.5 }
    uplift = { joints = ["base_joint", "lift_joints"] }   # masonrydam.effects.reservoir.uplift

A static stage applies it with the load ``{ type = "reservoir" }``: the water rises from an empty
reservoir (the lowest point of the face) to ``level`` over the stage's increments, the tailwater and
the silt with it. ``{ type = "reservoir", level = 120.0 }`` raises the water from the level reached
so far to 120 m. Pressure is not proportional to the level, so the face and pore pressures are
recomputed at every increment (one facet integration per increment; the pore pressures at every
Newton iteration, one sparse product). Later stages keep the water at the level reached; the dynamic
stages keep the static water forces (dynamic water: added mass, acoustic reservoir, is another
effect).

Loads (:mod:`masonrydam.effects.reservoir.hydrostatics`, integrated exactly over the wetted part of each
facet): hydrostatic pressure ``rho_w g (level - z)`` normal to the face, so that on an inclined or
stepped face the water weight above the face comes with it; tailwater the same on its face; silt as
the geostatic stress of a submerged soil layer, vertical ``gamma' (level_silt - z)`` and horizontal
``K`` times that (USACE EM 1110-2-2200, Gravity Dam Design, 1995, sec. 3-5; USBR Design of Small Dams,
1987, sec. 5.6), on the reservoir's face, in addition to the water pressure.
"""
from __future__ import annotations

import numpy as np

from ...checks import check_keys, choice, number, positive
from ...errors import SceneError
from ...keys import REQUIRED, UNIT, Section
from ...keys import key as row
from ...mesh.facets import owner_centroids
from ...materials.joint_laws import RESULT_OPEN, RESULT_SLIP
from ...units import quantity
from ..base import Effect
from . import uplift as _uplift
from .hydrostatics import facet_pressure_forces

#: default facet sets (the names of the dam generators)
DEFAULT_FACE = "upstream_face"
DEFAULT_TAILWATER_FACE = "downstream_face"


def _level(value, key):
    return quantity(value, "length", key)


def normalize_section(d, model: dict) -> dict:
    """The ``[reservoir]`` section; ``model``: the normalised ``[model]`` section (gravity)."""
    key = "reservoir"
    check_keys(d, {"level", "density", "face", "tailwater", "silt", "uplift", "dynamic", "acoustic"}, key)
    if "level" not in d:
        raise SceneError(f"{key}.level", "is required (the water surface, m on the vertical axis)")
    g = np.asarray(model["gravity"], dtype=float)
    gnorm = float(np.linalg.norm(g))
    axis = int(np.argmax(np.abs(g)))
    if gnorm == 0.0 or np.linalg.norm(np.delete(g, axis)) > 1e-9 * gnorm:
        raise SceneError("model.gravity", f"a reservoir needs gravity along a coordinate axis (the vertical the water "
                                          f"levels are measured on), got {model['gravity']}")
    out = {"level": _level(d["level"], f"{key}.level"),
           "density": positive(d.get("density", 1000.0), "density", f"{key}.density"),
           "face": _face_name(d.get("face", DEFAULT_FACE), f"{key}.face"),
           "vertical_axis": axis, "gravity": gnorm, "tailwater": None, "silt": None, "uplift": None}
    if "tailwater" in d:
        tk = f"{key}.tailwater"
        t = d["tailwater"]
        check_keys(t, {"level", "face"}, tk)
        if "level" not in t:
            raise SceneError(f"{tk}.level", "is required (m on the vertical axis)")
        out["tailwater"] = {"level": _level(t["level"], f"{tk}.level"),
                            "face": _face_name(t.get("face", DEFAULT_TAILWATER_FACE), f"{tk}.face")}
    if "silt" in d:
        sk = f"{key}.silt"
        s = d["silt"]
        check_keys(s, {"level", "submerged_density", "lateral_coefficient", "face"}, sk)
        for req in ("level", "submerged_density"):
            if req not in s:
                raise SceneError(f"{sk}.{req}", "is required (silt surface, m; submerged density, kg/m3)")
        level = _level(s["level"], f"{sk}.level")
        if level > out["level"]:
            raise SceneError(f"{sk}.level", f"{level:g} m is above the reservoir level {out['level']:g} m")
        out["silt"] = {"level": level,
                       "submerged_density": positive(s["submerged_density"], "density", f"{sk}.submerged_density"),
                       "lateral_coefficient": number(s.get("lateral_coefficient", 0.5), f"{sk}.lateral_coefficient",
                                                     0.0, 3.0, open_min=True),
                       "face": _face_name(s.get("face", out["face"]), f"{sk}.face")}
    if "uplift" in d:
        out["uplift"] = _uplift.normalize(d["uplift"], f"{key}.uplift")
    out["dynamic"] = choice(d.get("dynamic", "none"), DYNAMIC, f"{key}.dynamic")
    out["acoustic"] = None
    if out["dynamic"] == "acoustic":
        out["acoustic"] = _acoustic(d.get("acoustic", {}), f"{key}.acoustic")
    elif "acoustic" in d:
        raise SceneError(f"{key}.acoustic", f"is only read with dynamic = \"acoustic\" (dynamic is "
                                            f"\"{out['dynamic']}\")")
    return out


#: how the water moves with the dam in the dynamic stages: not at all (its static pressure stays),
#: Westergaard's added mass (:mod:`.added_mass`) or acoustic elements (:mod:`.acoustic`)
DYNAMIC = ("none", "westergaard", "acoustic")
#: speed of sound in water (m/s) by default (fresh water at about 10 degrees C; USACE EM 1110-2-6051 sec. 3-7
#: uses 4 720 ft/s = 1 439 m/s)
SOUND_SPEED = 1440.0
#: highest frequency (Hz) the acoustic elements resolve with 10 elements per wavelength, by default
MAX_FREQUENCY = 25.0


def _acoustic(d, key) -> dict:
    """The ``acoustic`` table of ``[reservoir]`` (dynamic = "acoustic")."""
    if not isinstance(d, dict):
        raise SceneError(key, f"expected a table, e.g. {{ sound_speed = 1440.0 }}, got {d!r}")
    check_keys(d, {"length", "sound_speed", "bottom_reflection", "element_size", "max_frequency"}, key)
    c = d.get("sound_speed", SOUND_SPEED)
    if c != "incompressible":
        if isinstance(c, str):
            raise SceneError(f"{key}.sound_speed", f"expected a speed in m/s or \"incompressible\", got {c!r}")
        c = number(c, f"{key}.sound_speed", 0.0, open_min=True)
    alpha = number(d.get("bottom_reflection", 1.0), f"{key}.bottom_reflection")
    if not -1.0 < alpha <= 1.0:
        raise SceneError(f"{key}.bottom_reflection", f"the wave reflection coefficient alpha must lie in (-1, 1] (1: a "
                                                     f"rigid bottom, 0: full absorption, -1 would be a free surface), "
                                                     f"got {alpha!r}")
    return {"length": None if "length" not in d else positive(d["length"], "length", f"{key}.length"),
            "sound_speed": c, "bottom_reflection": alpha,
            "element_size": None if "element_size" not in d else positive(d["element_size"], "length",
                                                                           f"{key}.element_size"),
            "max_frequency": number(d.get("max_frequency", MAX_FREQUENCY), f"{key}.max_frequency", 0.0, open_min=True)}


def _face_name(value, key):
    if not isinstance(value, str):
        raise SceneError(key, f"expected the name of a facet set, got {value!r}")
    return value


def normalize_load(d, key, dim) -> dict:
    """The stage load ``{ type = "reservoir" [, level = ...] }``."""
    check_keys(d, {"type", "level"}, key)
    return {"type": "reservoir", "level": None if "level" not in d else _level(d["level"], f"{key}.level")}


SECTIONS = {"reservoir": normalize_section}
LOAD_TYPES = {"reservoir": normalize_load}


class _Face:
    """A loaded facet set: type, facets (n, nfn), inward points (n, dim), elevation range (m) and key;
    ``level`` (m) must lie above its lowest point (else a SceneError naming ``level_key``, with ``hint``)."""

    def __init__(self, mesh, name, key, vertical_axis, level, level_key, hint):
        if name not in mesh.facet_sets:
            what = "edge" if mesh.dim == 2 else "face"
            raise SceneError(key, f"no facet ({what}) set '{name}' in the mesh (facet sets: {sorted(mesh.facet_sets)})")
        fs = mesh.facet_sets[name]
        self.name, self.key, self.type = name, key, fs.type
        self.facets = np.asarray(fs.facets, dtype=np.int64)
        self.inward = owner_centroids(mesh, fs.type, self.facets)
        z = mesh.points[np.unique(self.facets), vertical_axis]
        self.bottom, self.top = float(z.min()), float(z.max())
        if level <= self.bottom:
            raise SceneError(level_key, f"{level:g} m is not above the lowest point of the face '{name}' "
                                        f"({self.bottom:g} m): {hint}")


class Reservoir:
    """The water of a scene's ``[reservoir]`` section on ``model`` (built from ``mesh``)."""

    def __init__(self, spec: dict, mesh, model, thickness: float):
        self.spec = spec
        self.model = model
        self.thickness = thickness
        self.vertical = ax = spec["vertical_axis"]
        self.unit_weight = spec["density"] * spec["gravity"]
        self.face = _Face(mesh, spec["face"], "reservoir.face", ax, spec["level"], "reservoir.level",
                          "no water would touch it")
        self.tail = None if spec["tailwater"] is None else \
            _Face(mesh, spec["tailwater"]["face"], "reservoir.tailwater.face", ax, spec["tailwater"]["level"],
                  "reservoir.tailwater.level", "remove the tailwater if there is none")
        self.silt = None if spec["silt"] is None else \
            _Face(mesh, spec["silt"]["face"], "reservoir.silt.face", ax, spec["silt"]["level"], "reservoir.silt.level",
                  "remove the silt if there is none")
        normals = self._facet_normals(mesh)
        total = normals.sum(axis=0)
        norm = float(np.linalg.norm(total))
        if norm == 0.0:
            raise SceneError("reservoir.face", f"the face '{self.face.name}' has no horizontal extent to push on (is it "
                                               "the upstream face of the dam?)")
        #: horizontal unit vector pointing downstream: minus the area-weighted horizontal part of the upstream
        #: face's outward normal
        self.downstream = -total / norm
        #: the upstream face's nodes (m, dim) and their horizontal outward unit normals (m, dim), area-weighted
        #: over the facets around each node (zero where the face is horizontal there): where each joint line's
        #: heel is and which way it faces (3D; JointLines, for a curved face such as an arch's)
        self.face_nodes = None
        if mesh.dim == 3:
            nodes, inv = np.unique(self.face.facets, return_inverse=True)
            at_node = np.zeros((len(nodes), mesh.dim))
            np.add.at(at_node, inv.reshape(self.face.facets.shape), normals[:, None, :])
            length = np.linalg.norm(at_node, axis=1)
            at_node /= np.where(length > 0, length, 1.0)[:, None]
            self.face_nodes = (mesh.points[nodes, : mesh.dim], at_node)
        self.uplift = None
        if spec["uplift"] is not None:
            self.uplift = _uplift.Uplift(spec["uplift"], model, self.unit_weight, ax, self.downstream,
                                         "reservoir.uplift", upstream_face=self.face_nodes)

    def _facet_normals(self, mesh):
        """The horizontal part of the outward area normal of each facet of the upstream face, (n_facets, dim)
        (m2 in 3D, m in 2D)."""
        f = self.face
        X = mesh.points[f.facets][..., : mesh.dim]
        dim = mesh.dim
        if dim == 2:
            t = X[:, 1] - X[:, 0]
            n = np.stack([t[:, 1], -t[:, 0]], axis=1)
        elif f.type.startswith("tri"):
            n = 0.5 * np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
        else:  # quadrilaterals: half the cross product of the diagonals of the corners
            n = 0.5 * np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
        mid = X.mean(axis=1)
        flip = np.einsum("nk,nk->n", f.inward - mid, n) > 0
        n[flip] *= -1
        n[:, self.vertical] = 0.0
        return n

    def face_force(self, level: float, tail: float | None, silt: float | None) -> np.ndarray:
        """Nodal forces (n_dof,) N of the water at ``level``, the tailwater at ``tail`` and the silt at
        ``silt`` (m; None: none)."""
        m = self.model
        f = np.zeros(m.n_dof)
        kw = dict(vertical_axis=self.vertical, thickness=self.thickness)
        for face, lev, gamma, K in ((self.face, level, self.unit_weight, None),
                                    (self.tail, tail, self.unit_weight, None),
                                    (self.silt, silt, None if self.silt is None else
                                     self.spec["silt"]["submerged_density"] * self.spec["gravity"],
                                     None if self.silt is None else self.spec["silt"]["lateral_coefficient"])):
            if face is None or lev is None or lev <= face.bottom:
                continue
            f += facet_pressure_forces(m.coords, face.type, face.facets, face.inward, surface_level=lev,
                                       unit_weight=gamma, lateral_coefficient=K, **kw)
        return f

    def empty(self) -> tuple:
        """Levels (reservoir, tailwater, silt) of an empty reservoir: the lowest points of the faces."""
        return (self.face.bottom, None if self.tail is None else self.tail.bottom,
                None if self.silt is None else self.silt.bottom)

    def full(self, level: float | None = None) -> tuple:
        """Levels (reservoir, tailwater, silt) of the scene, the reservoir at ``level`` if given."""
        s = self.spec
        return (s["level"] if level is None else level, None if s["tailwater"] is None else s["tailwater"]["level"],
                None if s["silt"] is None else s["silt"]["level"])


class StageWater:
    """The water of one static stage: levels going linearly in the load factor from ``start`` to
    ``end`` (tuples reservoir, tailwater, silt, m); the solver asks for the face forces once per
    increment (:meth:`external`) and for the pore forces at every iteration (:meth:`pore`)."""

    def __init__(self, reservoir: Reservoir, start: tuple, end: tuple):
        self.reservoir, self.start, self.end = reservoir, start, end
        self._cache = (None, None)
        self.last_failure = None  # see failure_hint

    def levels(self, lam: float) -> tuple:
        return tuple(None if a is None else a + lam * (b - a) for a, b in zip(self.start, self.end))

    def external(self, lam: float) -> np.ndarray:
        """Face forces (n_dof,) N at load factor ``lam`` (cached for the last ``lam``)."""
        if self._cache[0] != lam:
            self._cache = (lam, self.reservoir.face_force(*self.levels(lam)))
        return self._cache[1]

    @property
    def state_dependent(self) -> bool:
        return self.reservoir.uplift is not None

    def pore(self, lam: float, trial: bool = True) -> np.ndarray:
        """Pore-pressure forces (n_dof,) N at ``lam`` with the joints' trial (or committed) states."""
        up = self.reservoir.uplift
        if up is None:
            return np.zeros(self.reservoir.model.n_dof)
        level, tail, _ = self.levels(lam)
        return up.force(up.pore_pressure(level, tail, trial, step=(id(self), lam) if trial else None))

    def failure_hint(self) -> str:
        """The joint lines whose cracks grew most in the failed attempt of a step (trial states against
        the committed ones), in words, for the message of a stage that found no equilibrium."""
        up = self.reservoir.uplift
        if up is None:
            return ""
        L = up.lines
        w = L.weight
        total = np.bincount(L.line, weights=w, minlength=L.n_lines)
        words = []
        for trial in (False, True):
            codes = L.gather([g.result_states(trial=trial) for g in L.groups])
            words.append((np.bincount(L.line, weights=w * (codes == RESULT_OPEN), minlength=L.n_lines) / total,
                          np.bincount(L.line, weights=w * (codes == RESULT_SLIP), minlength=L.n_lines) / total))
        (open0, _), (open1, slip1) = words
        order = np.argsort(-(open1 - open0))[:2]
        k = int(order[0])
        #: the line whose crack grew most in the failed attempt: name, open fraction before and after
        self.last_failure = {"line": L.names[k], "open_before": float(open0[k]), "open_after": float(open1[k])}
        parts = [f"'{L.names[k]}' open over {100 * open1[k]:.0f} % (was {100 * open0[k]:.0f} %), sliding over "
                 f"{100 * slip1[k]:.0f} %" for k in order if open1[k] > open0[k] or slip1[k] > 0.99]
        return ("; in the last attempt joint line " + ", ".join(parts)) if parts else ""

    def total(self, lam: float, trial: bool = True) -> np.ndarray:
        return self.external(lam) + self.pore(lam, trial)

    def state_load(self, lam: float) -> np.ndarray:
        """The loads that follow the joints' trial states: the pore forces (n_dof,) N at ``lam``."""
        return self.pore(lam)

    def limit(self, lam: float, target: float) -> tuple[dict, str]:
        """A stage limit at ``lam`` (``target`` tried): the result attribute ``limit_reservoir_level`` (m) and
        the words for the limit state."""
        reached, tried = self.levels(lam)[0], self.levels(target)[0]
        return ({"limit_reservoir_level": float(reached)},
                f"reservoir level reached {reached:.6g} m (tried {tried:.6g} m)")


def describe(scene, model) -> list[str]:
    r = scene.get("reservoir")
    if not r:
        return []
    facet = "edges" if model.dim == 2 else "faces"
    out = [f"reservoir: hydrostatic pressure normal to the wetted {facet} of '{r['face']}' (density {r['density']:g} "
           f"kg/m3, level {r['level']:g} m), integrated exactly over partly wet {facet}"]
    floods = [ld["level"] for st in scene["stages"] if st["type"] == "static" for ld in st["loads"]
              if ld["type"] == "reservoir" and ld["level"] is not None]
    if floods:
        out[0] += f"; raised to {', '.join(f'{x:g}' for x in floods)} m in stage(s)"
    if r["tailwater"]:
        out.append(f"tailwater: hydrostatic pressure on '{r['tailwater']['face']}' up to {r['tailwater']['level']:g} m")
    if r["silt"]:
        s = r["silt"]
        out.append(f"silt: geostatic load on '{s['face']}' up to {s['level']:g} m (submerged density "
                   f"{s['submerged_density']:g} kg/m3, lateral coefficient {s['lateral_coefficient']:g}; USACE "
                   "EM 1110-2-2200 sec. 3-5)")
    return out


def _check_scene(stages, parts):
    """A reservoir load needs the [reservoir] section, and the section a stage that applies it; one
    reservoir load per stage."""
    used = False
    for i, st in enumerate(stages):
        if st["type"] != "static":
            continue
        found = [j for j, ld in enumerate(st["loads"]) if ld["type"] == "reservoir"]
        if found and "reservoir" not in parts:
            raise SceneError(f"stages[{i}].loads[{found[0]}].type", "a reservoir load needs a [reservoir] section "
                                                                    "(level, density, face, ...)")
        if len(found) > 1:
            raise SceneError(f"stages[{i}].loads[{found[1]}]", "one reservoir load per stage (give the level "
                                                               "the stage raises the water to)")
        used = used or bool(found)
    if "reservoir" in parts and not used:
        raise SceneError("reservoir", "no static stage applies the water: add { type = \"reservoir\" } to the loads "
                                      "of a stage")
    dyn = parts.get("reservoir", {}).get("dynamic", "none") if isinstance(parts.get("reservoir"), dict) else "none"
    if dyn != "none" and not any(st["type"] in ("dynamic", "modal") for st in stages):
        raise SceneError("reservoir.dynamic", f"\"{dyn}\" moves the water with the dam in dynamic and modal stages; "
                                              "the scene has neither (remove the key, or add a stage)")


def _reservoir(context, stage) -> "Reservoir":
    """The run's :class:`Reservoir` (built once, kept with the stages' carried values)."""
    if "reservoir" not in stage.carried:
        stage.carried["reservoir"] = Reservoir(context.scene["reservoir"], context.mesh, context.model,
                                               context.scene["model"]["thickness"])
    return stage.carried["reservoir"]


def _add_reservoir_load(context, stage, ld, key):
    """A static stage raises (or lowers) the water to ``level``: the levels at its start and end."""
    reservoir = _reservoir(context, stage)
    levels = stage.carried.get("water_levels")
    start = reservoir.empty() if levels is None else levels[1]
    end = reservoir.full(ld["level"]) if levels is None else \
        (ld["level"] if ld["level"] is not None else start[0],) + tuple(start[1:])
    if levels is None and ld["level"] is not None and ld["level"] <= reservoir.face.bottom:
        raise SceneError(f"{key}.level", f"{ld['level']:g} m is not above the lowest point of the face "
                                         f"'{reservoir.face.name}' ({reservoir.face.bottom:g} m)")
    stage.carried["water_levels"] = (start, end)


def _finish_stage(context, stage):
    """The water of a static stage (:class:`StageWater`, its ``varying`` load) once the water is on the
    dam: later stages keep the water where the last one left it."""
    if not context.scene.get("reservoir"):
        return
    _reservoir(context, stage)
    levels = stage.carried.get("water_levels")
    if levels is None:
        return
    start, end = levels
    stage.varying = StageWater(stage.carried["reservoir"], start, end)
    stage.carried["water_levels"] = (end, end)
    control = stage.spec.get("control", "load")
    if control != "load":
        raise SceneError(f"stages[{stage.index}].control", f"\"{control}\": path following does not carry the "
                         "reservoir's water on this stage (its loads follow the level and the cracks, not one load "
                         "factor); use \"load\"")


def _activate(context):
    # (run.py imports this module: a top-level import would be a cycle)
    from .run import activate

    return activate(context)


# -- the rows of its scene keys in the scene reference (docs/scene.md) ----------------------------------------
_RESERVOIR = Section("[reservoir]", "Water on a dam. A static stage applies it with the load `{ type = "
                     "\"reservoir\" }`; `level` is on the vertical axis (the axis gravity acts along).", (
    row("reservoir.level", "number", "water level", "m", UNIT, REQUIRED),
    row("reservoir.density", "number", "water density", "kg/m3", UNIT, 1000.0),
    row("reservoir.face", "string", "facet set the water loads (only its part below the level)",
       default=DEFAULT_FACE),
    row("reservoir.tailwater", "table", "water downstream `{ level, face }`"),
    row("reservoir.silt", "table", "silt against the face `{ level, submerged_density, lateral_coefficient, face }`"),
    row("reservoir.uplift", "table", "pore pressure in joints `{ joints, drains, cracked, earthquake }`"),
    row("reservoir.dynamic", "string", "the water in dynamic and modal stages: static pressure only, Westergaard's "
       "added mass, or acoustic pressure elements", default="none", choices=DYNAMIC),
    row("reservoir.acoustic", "table", "dynamic = \"acoustic\": the fluid domain"),
    row("reservoir.tailwater.level", "number", "tailwater level", "m", UNIT, REQUIRED),
    row("reservoir.tailwater.face", "string", "facet set it loads", default=DEFAULT_TAILWATER_FACE),
    row("reservoir.silt.level", "number", "silt surface (not above the water)", "m", UNIT, REQUIRED),
    row("reservoir.silt.submerged_density", "number", "submerged density of the silt", "kg/m3", UNIT, REQUIRED),
    row("reservoir.silt.lateral_coefficient", "number", "horizontal / vertical stress, in (0, 3]", default=0.5),
    row("reservoir.silt.face", "string", "facet set it loads", default_text="the reservoir's face"),
    row("reservoir.uplift.joints", "list", "joint sets with pore pressure (a single string is one)",
       default=REQUIRED),
    row("reservoir.uplift.drains", "table", "a drain line `{ distance, efficiency }` (default: none)"),
    row("reservoir.uplift.cracked", "string", "pressure in the cracked part from the heel: full reservoir head, the "
       "intact profile, or none", default="full_head", choices=_uplift.CRACKED),
    row("reservoir.uplift.earthquake", "string", "pore pressure in joints that open during the dynamic stages",
       default="static", choices=_uplift.EARTHQUAKE),
    row("reservoir.uplift.drains.distance", "number", "distance of the drain line from the upstream end", "m", UNIT,
       REQUIRED),
    row("reservoir.uplift.drains.efficiency", "number", "drain efficiency, 0 to 1", default=REQUIRED),
    row("reservoir.acoustic.length", "number", "reservoir length upstream of the face (Sommerfeld far end)", "m",
       UNIT, default_text="3 H"),
    row("reservoir.acoustic.sound_speed", "number or string", "speed of sound, or `\"incompressible\"`", "m/s",
       default=SOUND_SPEED),
    row("reservoir.acoustic.bottom_reflection", "number", "wave reflection coefficient of the bottom, in (-1, 1] (1: "
       "rigid)", default=1.0),
    row("reservoir.acoustic.element_size", "number", "size of the first layer of fluid elements", "m", UNIT,
       default_text="the wetted facets' median"),
    row("reservoir.acoustic.max_frequency", "number", "highest frequency resolved with 10 elements per wavelength "
       "(the largest layer)", "Hz", default=MAX_FREQUENCY),
))


def _effects():
    return [Effect("reservoir", "[reservoir] with a { type = \"reservoir\" } load in a static stage", __name__,
                   "hydrostatics (White, Fluid Mechanics, ch. 2); USBR Design of Small Dams (1987) sec. 5.6; "
                   "USACE EM 1110-2-2200 (1995) ch. 3",
                   "tests/effects/test_reservoir.py, tests/effects/test_hydrostatics.py, "
                   "tests/effects/test_curved_face_water.py",
                   describe, activate=_activate, stage_loads={"reservoir": _add_reservoir_load},
                   finish_stage=_finish_stage, check_scene=_check_scene, scene_keys=(_RESERVOIR,),
                   section_meanings={"reservoir": "water on a dam: reservoir, tailwater, silt, uplift, water in "
                                                  "earthquakes"})]


EFFECTS = _effects()
