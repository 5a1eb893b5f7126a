"""Scene schema: validation and normalisation of a scene dictionary (from TOML or Python).

:func:`normalize` checks every key (unknown keys are errors, with the closest known key suggested),
converts quantities to SI, fills defaults and returns a new plain dictionary. Every error is a
:class:`~masonrydam.errors.SceneError` naming the dotted key, raised before any meshing or solving.
"""
from __future__ import annotations

import copy
import inspect

import numpy as np

from ..elements.quadrature import QUADRATURE_SCHEMES
from ..errors import SceneError
from ..pulses import PULSE_SHAPES
from ..solvers.dynamic import INTEGRATORS, scheme_named
from ..solvers.linear.direct import LINEAR_SOLVERS
from ..checks import COMPONENT_NAMES
from ..checks import boolean as _bool
from ..checks import check_keys as _check_keys
from ..checks import choice as _choice
from ..checks import components as _components
from ..checks import integer as _int
from ..checks import number as _number
from ..checks import positive as _positive
from ..checks import seconds as _time
from ..checks import vector as _vector
from ..units import quantity
from ..effects import check_scene, load_types, normalize_dynamic_load, sections
from ..assembly.groups import JOINT_FRAMES, KINEMATICS
from ..materials.continuum_laws import CONTINUUM_LAWS, material_law
from ..materials.joint_laws import DEFAULT_JOINT_LAW, JOINT_KEYS, joint_law, joint_laws
from ..results.writer import OutputOptions

HYPOTHESES = ("plane_stress", "plane_strain")
SUPPORT_KINDS = ("fixed", "tied")
G_STANDARD = 9.80665


def plain(value):
    """A deep copy of ``value`` with NumPy values made plain Python ones: a NumPy scalar
    (``np.int64``, ``np.float32``, ``np.bool_``, ``np.str_``, ...) or 0-d array becomes the
    int, float, bool or str it holds and an array a (nested) list, in dict keys too, so that a scene
    built in Python with NumPy passes the same checks as one read from TOML and no error message
    shows a NumPy repr. Other objects are deep-copied as they are."""
    if isinstance(value, dict):
        return {plain(k): plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [plain(v) for v in value]
    if isinstance(value, tuple):
        return tuple(plain(v) for v in value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):  # (an object array may hold NumPy scalars: convert its items too)
        return plain(value.item() if value.ndim == 0 else value.tolist())
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return copy.deepcopy(value)


#: static stage control: its own (load / displacement, arc-length where that stalls), arc-length from the start,
#: indirect displacement control on the cracks' opening, or dissipation-based control
STATIC_CONTROLS = ("load", "arc_length", "opening", "dissipation")
#: what control "load" does where a step finds no equilibrium (masonrydam.solvers.static.relaxation)
LIMIT_POINTS = ("follow", "relax")


def _model(d):
    _check_keys(d, {"name", "dimension", "hypothesis", "thickness", "gravity", "kinematics"}, "model")
    dim = _int(d.get("dimension", 2), "model.dimension")
    if dim not in (2, 3):
        raise SceneError("model.dimension", f"must be 2 or 3, got {dim}")
    out = {"name": str(d.get("name", "scene")), "dimension": dim}
    if dim == 2:
        out["hypothesis"] = _choice(d.get("hypothesis", "plane_stress"), HYPOTHESES, "model.hypothesis")
        out["thickness"] = _positive(d.get("thickness", 1.0), "length", "model.thickness")
        gravity = [0.0, -G_STANDARD]
    else:
        for k in ("hypothesis", "thickness"):
            if k in d and not (k == "hypothesis" and d[k] == "3d"):
                raise SceneError(f"model.{k}", "applies to 2D models only; a 3D model is a solid (remove it)")
        out["hypothesis"] = "3d"
        out["thickness"] = 1.0
        gravity = [0.0, 0.0, -G_STANDARD]
    out["gravity"] = _vector(d.get("gravity", gravity), "acceleration", "model.gravity", dim)
    # "large": total Lagrangian blocks and joints whose frame turns with them
    out["kinematics"] = _choice(d.get("kinematics", "small"), KINEMATICS, "model.kinematics")
    return out


def _generator_parameters(name, params, key):
    """The parameters of generator ``name`` checked against its signature (lengths and angles to SI,
    finite and plausible); those of the 2D generator inside ``extruded`` too."""
    # (generators imports masonrydam, whose __init__ imports this module: a top-level import would be a cycle)
    from generators import GENERATORS

    sig = inspect.signature(GENERATORS[name])
    allowed = {p for p in sig.parameters if p != "key"}
    _check_keys(params, allowed, key)
    missing = [p.name for p in sig.parameters.values() if p.default is inspect.Parameter.empty and p.name not in params]
    if missing:
        raise SceneError(f"{key}.{missing[0]}", f"required by generator '{name}'")
    conv = {}
    for k, v in params.items():
        kind = str(sig.parameters[k].annotation)
        pkey = f"{key}.{k}"
        if kind == "float" and k.endswith("_deg"):
            conv[k] = quantity(v, "angle", pkey)
        elif kind == "float":  # generator lengths (m)
            conv[k] = quantity(v, "length", pkey)
        elif kind == "int":
            conv[k] = _int(v, pkey)
        elif kind == "bool":
            conv[k] = _bool(v, pkey)
        elif kind == "str" and not isinstance(v, str):
            raise SceneError(pkey, f"expected a string, got {v!r}")
        else:
            conv[k] = v
    if name == "extruded":  # the 2D generator and its parameters (``parameters`` is required)
        inner = _choice(conv["generator"], sorted(g for g in GENERATORS if g.endswith("_2d")), f"{key}.generator")
        conv["parameters"] = _generator_parameters(inner, conv["parameters"], f"{key}.parameters")
    return conv


def _mesh(d):
    # (generators imports masonrydam, whose __init__ imports this module: a top-level import would be a cycle)
    from generators import GENERATORS

    _check_keys(d, {"generator", "parameters", "file", "joints"}, "mesh")
    has_gen, has_file = "generator" in d, "file" in d
    if has_gen == has_file:
        raise SceneError("mesh", "give exactly one of 'generator' (with 'parameters') or 'file'")
    if has_gen:
        name = _choice(d["generator"], sorted(GENERATORS), "mesh.generator")
        params = _generator_parameters(name, d.get("parameters", {}), "mesh.parameters")
        return {"generator": name, "parameters": params}
    joints = d.get("joints", [])
    if not isinstance(joints, list) or not all(isinstance(j, str) for j in joints):
        raise SceneError("mesh.joints", f"expected a list of physical group names, got {joints!r}")
    return {"file": str(d["file"]), "joints": joints}


def _material(name, d):
    key = f"materials.{name}"
    _check_keys(d, {"model", "youngs_modulus", "poisson_ratio", "density", "law", "integration"}
                | {k for spec in CONTINUUM_LAWS.values() for k in spec}, key)
    _choice(d.get("model", "linear_elastic"), ("linear_elastic",), f"{key}.model")
    for req in ("youngs_modulus", "poisson_ratio"):
        if req not in d:
            raise SceneError(f"{key}.{req}", "is required")
    # plausible ranges of E and density (MPa typed as Pa, unit weight typed as density): units.PLAUSIBLE
    E = _positive(d["youngs_modulus"], "stress", f"{key}.youngs_modulus")
    nu = d["poisson_ratio"]
    if isinstance(nu, bool) or not isinstance(nu, (int, float)) or not (-1.0 < nu < 0.5):  # (nan fails too)
        raise SceneError(f"{key}.poisson_ratio", f"must be in (-1, 0.5), got {nu!r}")
    rho = _positive(d.get("density", 0.0), "density", f"{key}.density", allow_zero=True)
    # "reduced": 2 x 2 (x 2) Gauss points for quad8 / hex20 (the elements' full rule locks in plastic flow)
    integration = _choice(d.get("integration", "full"), ("full", "reduced"), f"{key}.integration")
    return {"model": "linear_elastic", "youngs_modulus": E, "poisson_ratio": float(nu), "density": rho,
            "integration": integration, **material_law(d, key)}


def _joint(name, d):
    key = f"joints.{name}"
    laws = joint_laws()
    _check_keys(d, set(JOINT_KEYS).union(*(law.key_names for law in laws)), key)
    law = joint_law(_choice(d.get("law", DEFAULT_JOINT_LAW), tuple(law.name for law in laws), f"{key}.law"))
    for req in ("normal_stiffness", "shear_stiffness"):
        if req not in d:
            raise SceneError(f"{key}.{req}", "is required")
    kn = _positive(d["normal_stiffness"], "stiffness", f"{key}.normal_stiffness")
    ks = _positive(d["shear_stiffness"], "stiffness", f"{key}.shear_stiffness")
    for k in d:
        if k not in JOINT_KEYS and k not in law.key_names:
            owners = " or ".join(f'"{other.name}"' for other in laws if k in other.key_names)
            raise SceneError(f"{key}.{k}", f"is a parameter of law = {owners}, not of law = \"{law.name}\"")
    # the law's own keys, read by its descriptor (masonrydam.materials.joint_laws)
    out = {"law": law.name, "normal_stiffness": kn, "shear_stiffness": ks, **law.normalize(d, key, ks)}
    # default: nodal ("lumped") integration (Schellekens & de Borst 1993); the build step switches
    # 16-node (quad8) interfaces to 3x3 Newton-Cotes, whose lumped corner weights would be negative
    # large kinematics: the joint's frame turns with its current mid-surface (as in Tzamtzis & Asteris), or with its
    # bottom face (a supporting face on which the top side may slide far)
    if "frame" in d:
        out["frame"] = _choice(d["frame"], JOINT_FRAMES, f"{key}.frame")
    out["integration_given"] = "integration" in d
    out["integration"] = _choice(d.get("integration", "lumped"), QUADRATURE_SCHEMES, f"{key}.integration")
    if "points" in d:
        out["points"] = _int(d["points"], f"{key}.points", 1)
        if out["integration"] == "lumped":
            raise SceneError(f"{key}.points", "lumped integration has one point per node; remove 'points'")
    return out


def _load(d, key, dim):
    """One load of a static stage, normalised by the effect that owns its type (:mod:`masonrydam.effects`)."""
    types = load_types()
    if not isinstance(d, dict) or "type" not in d:
        raise SceneError(f"{key}.type", "every load needs a 'type'")
    _choice(d["type"], tuple(types), f"{key}.type")
    return types[d["type"]](d, key, dim)


def _solver(d):
    _check_keys(d, {"method", "line_search", "max_iterations", "force_tolerance", "energy_tolerance",
                    "max_step_cuts", "linear_solver", "joint_space"}, "solver")
    out = {
        "method": _choice(d.get("method", "newton"), ("newton", "modified_newton"), "solver.method"),
        "line_search": _bool(d.get("line_search", True), "solver.line_search"),
        "max_iterations": _int(d.get("max_iterations", 30), "solver.max_iterations", 1),
        "max_step_cuts": _int(d.get("max_step_cuts", 8), "solver.max_step_cuts", 0),
        "linear_solver": _choice(d.get("linear_solver", "auto"), LINEAR_SOLVERS, "solver.linear_solver"),
        "joint_space": _choice(d.get("joint_space", "auto"), ("auto", "off"), "solver.joint_space"),
    }
    for k, default in (("force_tolerance", 1e-6), ("energy_tolerance", 1e-10)):
        v = d.get(k, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < 1:
            raise SceneError(f"solver.{k}", f"must be a number in (0, 1), got {v!r}")
        out[k] = float(v)
    return out


def _selection(value, key):
    if value == "all" or value is None:
        return "all"
    if isinstance(value, str):
        return [value]
    if isinstance(value, list) and value and all(isinstance(v, str) for v in value):
        return value
    raise SceneError(key, f"expected 'all' or a list of one or more set names, got {value!r}")


STAGE_TYPES = ("static", "modal", "dynamic")
#: the most load steps of a static stage, and time steps of a dynamic one (more would run for days: a slipped
#: exponent); a dynamic stage given by its duration is held to the same count (scene.stages._dynamic_stage)
MAX_STATIC_STEPS = 10**6
MAX_DYNAMIC_STEPS = 10**9
STEPS_WHY = "more would run for days (a slipped exponent?)"
#: damping models of a dynamic stage: viscous Rayleigh damping, local (non-viscous) damping of an explicit step
DAMPING_MODELS = ("rayleigh", "local")
#: keys of a dynamic stage that apply to dt = "auto" only
AUTO_STEP_KEYS = ("tolerance", "dt_min", "dt_max")
_DYNAMIC_KEYS = {"name", "type", "steps", "duration", "dt", "integrator", "alpha", "rho_inf", "mass", "damping",
                 "ground_motion", "output", "max_iterations", "max_substeps", "force_tolerance", "energy_tolerance",
                 "low_rank_max", "joint_space", "initial_velocity", "initial_displacement", "loads", *AUTO_STEP_KEYS}
#: dt = "auto" without dt_max (and without output.dt): the largest step (s)
AUTO_DT_MAX_DEFAULT = 0.01
#: dt = "auto": default relative local error per step (see solvers.dynamic.step_control.AdaptiveStepping.step_error)
AUTO_TOLERANCE_DEFAULT = 1e-5


#: processing steps of a ground-motion component (``processing = [{ step = "...", ... }, ...]``, applied in
#: order before the scaling) and the keys each takes: those of :mod:`masonrydam.records.processing`
PROCESSING_STEPS = {
    "baseline": {"method", "order"},            # records.baseline_correct
    "taper": {"max_percentage", "side", "max_length"},  # records.taper
    "bandpass": {"freqmin", "freqmax", "corners"},     # records.bandpass (zero-phase Butterworth)
    "resample": {"dt", "method"},               # records.resample
    "trim": {"start", "end", "pad"},            # records.trim_significant_duration (Husid fractions)
}


def _processing(steps, key):
    """The normalised list of processing steps (each a dict with 'step' and its parameters; the values
    are checked by the processing functions when the record is built, with this key in the error)."""
    if not isinstance(steps, list):
        raise SceneError(key, "expected a list of tables such as { step = \"bandpass\", freqmin = 0.1, freqmax = 25 }")
    out = []
    for j, st in enumerate(steps):
        k = f"{key}[{j}]"
        if not isinstance(st, dict) or "step" not in st:
            raise SceneError(k, f"expected a table with 'step' (one of {sorted(PROCESSING_STEPS)})")
        name = _choice(st["step"], tuple(PROCESSING_STEPS), f"{k}.step")
        _check_keys(st, PROCESSING_STEPS[name] | {"step"}, k)
        params = {}
        for p, v in st.items():
            if p == "step":
                continue
            if p in ("method", "side"):
                if not isinstance(v, str):
                    raise SceneError(f"{k}.{p}", f"expected a string, got {v!r}")
                params[p] = v
            elif p == "dt":
                params[p] = _time(v, f"{k}.{p}")
            elif p in ("order", "corners"):
                params[p] = _int(v, f"{k}.{p}", 0)
            else:
                params[p] = _number(v, f"{k}.{p}")
        out.append({"step": name, **params})
    return out


def _ground_component(d, key):
    """One ground-motion component: exactly one source (record, file, values, pulse), optional
    processing steps, and an optional scaling (scale, scale_to_pga or scale_to_sa). ``column`` (with
    'file' only): which value column of a text file with several, counted from 0 without the time
    column (as ``masonrydam records show FILE --column N``)."""
    _check_keys(d, {"record", "file", "format", "units", "dt", "column", "values", "pulse", "processing", "scale",
                    "scale_to_pga", "scale_to_sa"}, key)
    sources = [k for k in ("record", "file", "values", "pulse") if k in d]
    if len(sources) != 1:
        raise SceneError(key, "give exactly one of 'record' (a bundled record, `masonrydam records list`), "
                              "'file' (a record file), 'values' (with 'dt') or 'pulse'")
    src = sources[0]
    out = {"source": src}
    if src == "record":
        if not isinstance(d["record"], str):
            raise SceneError(f"{key}.record", f"expected a record name, got {d['record']!r}")
        for k in ("format", "units", "dt", "column"):
            if k in d:
                raise SceneError(f"{key}.{k}", "applies to 'file' and 'values' only (a bundled record knows it)"
                                 if k != "column" else "applies to 'file' only (a bundled record has one trace)")
        out["record"] = d["record"]
    elif src == "file":
        out["file"] = str(d["file"])
        out["format"] = None if "format" not in d else str(d["format"])
        out["units"] = None if "units" not in d else str(d["units"])
        out["dt"] = None if "dt" not in d else _time(d["dt"], f"{key}.dt")
        out["column"] = None if "column" not in d else _int(d["column"], f"{key}.column", 0)
    elif src == "values":
        vals = d["values"]
        if not isinstance(vals, list) or len(vals) < 2:
            raise SceneError(f"{key}.values", "expected a list of at least 2 accelerations")
        out["values"] = [_number(v, f"{key}.values[{j}]") for j, v in enumerate(vals)]
        if "dt" not in d:
            raise SceneError(f"{key}.dt", "is required with 'values' (s)")
        out["dt"] = _time(d["dt"], f"{key}.dt")
        out["units"] = str(d.get("units", "m/s2"))
        for k in ("format", "column"):
            if k in d:
                raise SceneError(f"{key}.{k}", "applies to 'file' only")
    else:
        p = d["pulse"]
        pk = f"{key}.pulse"
        _check_keys(p, {"shape", "amplitude", "duration"}, pk)
        for req in ("shape", "amplitude", "duration"):
            if req not in p:
                raise SceneError(f"{pk}.{req}", "is required")
        out["pulse"] = {"shape": _choice(p["shape"], PULSE_SHAPES, f"{pk}.shape"),
                        "amplitude": quantity(p["amplitude"], "acceleration", f"{pk}.amplitude"),
                        "duration": _time(p["duration"], f"{pk}.duration")}
        out["dt"] = None if "dt" not in d else _time(d["dt"], f"{key}.dt")
        for k in ("format", "units", "column"):
            if k in d:
                raise SceneError(f"{key}.{k}", "has no meaning for a pulse")
    scalings = [k for k in ("scale", "scale_to_pga", "scale_to_sa") if k in d]
    if len(scalings) > 1:
        raise SceneError(f"{key}.{scalings[1]}", f"give one of 'scale', 'scale_to_pga', 'scale_to_sa', not {scalings}")
    out["processing"] = _processing(d["processing"], f"{key}.processing") if "processing" in d else []
    out["scale"] = None if "scale" not in d else _number(d["scale"], f"{key}.scale")
    out["scale_to_pga"] = None if "scale_to_pga" not in d else _positive(d["scale_to_pga"], "acceleration",
                                                                          f"{key}.scale_to_pga")
    out["scale_to_sa"] = None
    if "scale_to_sa" in d:
        sk = f"{key}.scale_to_sa"
        t = d["scale_to_sa"]
        _check_keys(t, {"sa", "period", "damping"}, sk)
        for req in ("sa", "period"):
            if req not in t:
                raise SceneError(f"{sk}.{req}", "is required (target pseudo-spectral acceleration and its period)")
        out["scale_to_sa"] = {"sa": _positive(t["sa"], "acceleration", f"{sk}.sa"),
                              "period": _time(t["period"], f"{sk}.period"),
                              "damping": _number(t.get("damping", 0.05), f"{sk}.damping", 0.0, 1.0, open_min=True)}
    return out


def set_time_steps(stage: dict, dt, *, steps=None, duration=None) -> dict:
    """Give the dynamic stage ``stage`` of a scene dictionary (as read from TOML, changed in place and
    returned) other time steps: ``dt`` a step (s) or ``"auto"``, and ``steps`` or ``duration`` as its new
    length where one is given (else it keeps its own). The keys of dt = "auto" it had
    (:data:`AUTO_STEP_KEYS`) are dropped; give new ones after this call. For scripts and benchmarks
    that run a bundled example with settings of their own."""
    for k in AUTO_STEP_KEYS:
        stage.pop(k, None)
    if steps is not None or duration is not None:
        stage.pop("steps", None)
        stage.pop("duration", None)
        stage.update({"steps": steps} if steps is not None else {"duration": duration})
    stage["dt"] = dt
    return stage


def _numbers(value, n, key) -> list:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise SceneError(key, f"expected a list of {n} numbers, got {value!r}")
    return [_number(v, f"{key}[{i}]") for i, v in enumerate(value)]


def _initial_velocity(d, key, dim, translation="velocity", rotation="angular_velocity",
                      translation_dimension=None) -> list:
    """``initial_velocity`` of a dynamic stage: a table or a list of tables ``{ groups = [...], velocity =
    [vx, vy(, vz)] }`` (m/s) or ``{ groups, angular_velocity = w (2D, rad/s; 3D: [wx, wy, wz]),
    rotation_center = [x, y(, z)] }`` (a rigid rotation about the centre, v = w x (x - c)).
    ``initial_displacement`` has the same form with ``displacement`` (m, a string with a length unit too)
    and ``rotation`` (rad, small: u = theta x (x - c)): ``translation``, ``rotation`` name the keys."""
    items = d if isinstance(d, list) else [d]
    out = []
    for i, t in enumerate(items):
        k = key if not isinstance(d, list) else f"{key}[{i}]"
        if not isinstance(t, dict):
            raise SceneError(k, f"expected a table {{ groups = [...], velocity = [...] }}, got {t!r}")
        _check_keys(t, {"groups", translation, rotation, "rotation_center"}, k)
        groups = t.get("groups")
        groups = [groups] if isinstance(groups, str) else groups
        if not isinstance(groups, list) or not groups or not all(isinstance(g, str) for g in groups):
            raise SceneError(f"{k}.groups", f"expected a list of element group names, got {t.get('groups')!r}")
        if (translation in t) == (rotation in t):
            raise SceneError(k, f"give '{translation}' = [x, y(, z)] (a translation) or '{rotation}' with "
                                "'rotation_center' (a rigid rotation), one of them")
        item = {"groups": list(groups)}
        if translation in t:
            if "rotation_center" in t:
                raise SceneError(f"{k}.rotation_center", f"goes with '{rotation}'")
            item[translation] = (_numbers(t[translation], dim, f"{k}.{translation}") if translation_dimension is None
                                 else _vector(t[translation], translation_dimension, f"{k}.{translation}", dim))
        else:
            w = t[rotation]
            item[rotation] = (_number(w, f"{k}.{rotation}") if dim == 2 else _numbers(w, 3, f"{k}.{rotation}"))
            if "rotation_center" not in t:
                raise SceneError(f"{k}.rotation_center", f"is required with '{rotation}' (the point the "
                                                         "rotation is about, m)")
            item["rotation_center"] = _vector(t["rotation_center"], "length", f"{k}.rotation_center", dim)
        out.append(item)
    return out



def _rayleigh_damping(damp: dict, dk: str) -> dict:
    """The normalised Rayleigh ``[stages.damping]`` table (``dk``: its scene key)."""
    by_ratio = "ratio" in damp or "frequencies" in damp
    by_coef = "alpha" in damp or "beta" in damp
    if by_ratio == by_coef:
        raise SceneError(dk, "give 'ratio' and 'frequencies' = [f1, f2] (Hz), or the Rayleigh coefficients "
                             "'alpha' (1/s) and 'beta' (s)")
    d = {"model": "rayleigh", "exclude_joints": _bool(damp.get("exclude_joints", True), f"{dk}.exclude_joints")}
    if by_ratio:
        if "ratio" not in damp or "frequencies" not in damp:
            raise SceneError(dk, "'ratio' needs 'frequencies' = [f1, f2] (Hz) and vice versa")
        d["ratio"] = _number(damp["ratio"], f"{dk}.ratio", 0.0, 0.99)
        fr = damp["frequencies"]
        if not isinstance(fr, list) or len(fr) != 2:
            raise SceneError(f"{dk}.frequencies", f"expected [f1, f2] in Hz, got {fr!r}")
        f1 = _number(fr[0], f"{dk}.frequencies[0]", 0.0, open_min=True)
        f2 = _number(fr[1], f"{dk}.frequencies[1]", 0.0, open_min=True)
        if not f1 < f2:
            raise SceneError(f"{dk}.frequencies", f"need f1 < f2, got {fr!r}")
        d["frequencies"] = [f1, f2]
    else:
        d["alpha"] = _number(damp.get("alpha", 0.0), f"{dk}.alpha", 0.0)
        d["beta"] = _number(damp.get("beta", 0.0), f"{dk}.beta", 0.0)
    return d


def _dynamic_stage(s, key, dim, index):
    _check_keys(s, _DYNAMIC_KEYS, key)
    out = {"name": str(s.get("name", f"stage{index + 1}")), "type": "dynamic"}
    loads = s.get("loads", [])
    if not isinstance(loads, list):
        raise SceneError(f"{key}.loads", "expected an array of tables [[stages.loads]]")
    # loads given in time (effects.dynamic_loads), on top of the static stages' loads, which stay applied
    out["loads"] = [normalize_dynamic_load(ld, f"{key}.loads[{j}]", dim) for j, ld in enumerate(loads)]
    if "dt" not in s:
        raise SceneError(f"{key}.dt", "is required for a dynamic stage (analysis time step, s, or \"auto\" for error-controlled steps)")
    o = s.get("output", {})
    if not isinstance(o, dict):
        raise SceneError(f"{key}.output", f"expected a table, e.g. {{ stride = 10 }}, got {o!r}")
    out_dt = None if "dt" not in o else _time(o["dt"], f"{key}.output.dt")
    integ_named = s.get("integrator", "hht")
    explicit = integ_named in INTEGRATORS and scheme_named(integ_named).explicit
    out["stable_step"] = False
    if s["dt"] == "auto" and explicit:
        # the explicit step chosen by the program: the largest stable one that divides the output interval
        for k in ("tolerance", "dt_min", "dt_max", "steps"):
            if k in s:
                raise SceneError(f"{key}.{k}", f"does not apply to dt = \"auto\" with {integ_named}: the program "
                                               "takes the largest stable step that divides the output interval "
                                               "(give output.dt and duration)")
        out["adaptive"] = False
        out["stable_step"] = True
        out["dt"] = out_dt or AUTO_DT_MAX_DEFAULT  # the output grid; the steps divide it
        out["dt_min"] = None
        out["tolerance"] = AUTO_TOLERANCE_DEFAULT
    elif s["dt"] == "auto":
        # error-controlled steps: dt_max / 2^k down to dt_min (solvers.dynamic.step_control.AdaptiveStepping)
        out["adaptive"] = True
        out["dt"] = _time(s.get("dt_max", out_dt or AUTO_DT_MAX_DEFAULT), f"{key}.dt_max")
        out["dt_min"] = None if "dt_min" not in s else _time(s["dt_min"], f"{key}.dt_min")
        if out["dt_min"] is not None and out["dt_min"] > out["dt"]:
            raise SceneError(f"{key}.dt_min", f"{out['dt_min']:g} s is larger than dt_max = {out['dt']:g} s")
        out["tolerance"] = _number(s.get("tolerance", AUTO_TOLERANCE_DEFAULT), f"{key}.tolerance", 0.0, 1.0,
                                   open_min=True)
    else:
        for k in AUTO_STEP_KEYS:
            if k in s:
                raise SceneError(f"{key}.{k}", f"applies to dt = \"auto\" (error-controlled steps) only; dt is "
                                               f"{s['dt']!r}")
        if isinstance(s["dt"], str) and s["dt"].strip().lower() == "auto":
            raise SceneError(f"{key}.dt", "write dt = \"auto\" (lower case) for error-controlled steps")
        out["adaptive"] = False
        out["dt"] = _time(s["dt"], f"{key}.dt")
        out["dt_min"] = None
        out["tolerance"] = AUTO_TOLERANCE_DEFAULT
    out["output_dt"] = out_dt
    if "steps" in s and "duration" in s:
        raise SceneError(f"{key}.steps", "give 'steps' or 'duration', not both")
    out["steps"] = _int(s["steps"], f"{key}.steps", 1, MAX_DYNAMIC_STEPS, STEPS_WHY) if "steps" in s else None
    out["duration"] = _time(s["duration"], f"{key}.duration") if "duration" in s else None
    integ = _choice(s.get("integrator", "hht"), INTEGRATORS, f"{key}.integrator")
    out["integrator"] = integ
    scheme = scheme_named(integ)
    if "alpha" in s and "alpha" not in scheme.parameters:
        raise SceneError(f"{key}.alpha", f"is the HHT parameter; integrator is '{integ}'")
    if "rho_inf" in s and "rho_inf" not in scheme.parameters:
        raise SceneError(f"{key}.rho_inf", f"is the generalized-alpha parameter; integrator is '{integ}'")
    out["alpha"] = _number(s.get("alpha", -0.1), f"{key}.alpha", -1.0 / 3.0, 0.0)
    out["rho_inf"] = _number(s.get("rho_inf", 0.8), f"{key}.rho_inf", 0.0, 1.0)
    out["mass"] = _choice(s.get("mass", "lumped"), ("lumped", "consistent"), f"{key}.mass")
    if scheme.explicit and out["mass"] != "lumped":
        raise SceneError(f"{key}.mass", f"{scheme.label} is explicit and needs mass = 'lumped'")
    out["max_iterations"] = _int(s.get("max_iterations", 25), f"{key}.max_iterations", 1)
    out["max_substeps"] = _int(s.get("max_substeps", 4), f"{key}.max_substeps", 0)
    out["low_rank_max"] = _int(s.get("low_rank_max", 256), f"{key}.low_rank_max", 0)
    js = s.get("joint_space", "auto")
    if isinstance(js, bool):
        js = "on" if js else "off"
    out["joint_space"] = _choice(js, ("auto", "on", "off"), f"{key}.joint_space")
    for k, default in (("force_tolerance", 1e-6), ("energy_tolerance", 1e-8)):
        v = s.get(k, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < 1:
            raise SceneError(f"{key}.{k}", f"must be a number in (0, 1), got {v!r}")
        out[k] = float(v)
    damp = s.get("damping")
    if damp is None:
        out["damping"] = None
    else:
        dk = f"{key}.damping"
        _check_keys(damp, {"model", "ratio", "frequencies", "alpha", "beta", "exclude_joints"}, dk)
        dmodel = _choice(damp.get("model", "rayleigh"), DAMPING_MODELS, f"{dk}.model")
        if dmodel == "local":
            if not scheme.explicit:
                raise SceneError(f"{dk}.model", f"local damping acts in an explicit step only (integrator = "
                                                f"\"central_difference\"); {scheme.label} takes model = \"rayleigh\"")
            for k in ("frequencies", "alpha", "beta", "exclude_joints"):
                if k in damp:
                    raise SceneError(f"{dk}.{k}", "is a Rayleigh damping key; local damping takes 'ratio' alone "
                                                  "(the same ratio at every frequency)")
            if "ratio" not in damp:
                raise SceneError(f"{dk}.ratio", "is required with model = \"local\" (e.g. 0.05)")
            out["damping"] = {"model": "local", "ratio": _number(damp["ratio"], f"{dk}.ratio", 0.0, 0.3)}
        else:
            out["damping"] = _rayleigh_damping(damp, dk)
    out["initial_velocity"] = (None if "initial_velocity" not in s else
                               _initial_velocity(s["initial_velocity"], f"{key}.initial_velocity", dim))
    # a displaced start (released from a deformed shape: a pluck test), on top of the static state
    out["initial_displacement"] = (None if "initial_displacement" not in s else
                                   _initial_velocity(s["initial_displacement"], f"{key}.initial_displacement", dim,
                                                     "displacement", "rotation", "length"))
    gm = s.get("ground_motion")
    if gm is None and (out["initial_velocity"] is not None or out["initial_displacement"] is not None
                       or out["loads"]):  # free motion, or loads in time
        if out["steps"] is None and out["duration"] is None:
            raise SceneError(f"{key}.duration", "is required for a dynamic stage without ground motion (or give "
                                                "'steps')")
        gm = {}
    elif not isinstance(gm, dict) or not gm:
        raise SceneError(f"{key}.ground_motion", "is required: give at least one component, e.g. "
                                                 "[stages.ground_motion.x] record = \"elcentro_1940_ns_peknold\" "
                                                 "(or an initial_velocity for a free motion, or loads with a "
                                                 "time_function)")
    _check_keys(gm, set(COMPONENT_NAMES[:dim]), f"{key}.ground_motion")
    out["ground_motion"] = {c: _ground_component(v, f"{key}.ground_motion.{c}") for c, v in gm.items()}
    _check_keys(o, {"stride", "dt", "nodes", "joints"}, f"{key}.output")
    stride = _int(o.get("stride", 1), f"{key}.output.stride", 1)
    if out_dt is not None:
        if "stride" in o:
            raise SceneError(f"{key}.output.dt", "give 'stride' (every k-th step) or 'dt' (an output interval), not both")
        ratio = out_dt / out["dt"]
        stride = int(round(ratio))
        if stride < 1 or abs(ratio - stride) > 1e-6 * ratio:
            what = "dt_max" if out["adaptive"] else "dt"
            raise SceneError(f"{key}.output.dt", f"{out_dt:g} s must be a whole multiple of the stage's {what} = "
                                                 f"{out['dt']:g} s (the output lands on steps, not between them)")
    out["output"] = {"stride": stride,
                     "nodes": None if "nodes" not in o else _selection(o["nodes"], f"{key}.output.nodes"),
                     "joints": None if "joints" not in o else _selection(o["joints"], f"{key}.output.joints")}
    return out


def _output_options(d: dict) -> dict:
    """How steps reach the file (:class:`~masonrydam.results.writer.OutputOptions`)."""
    default = OutputOptions()
    compression = _int(d.get("compression", default.compression), "output.compression", 0)
    if compression > 9:
        raise SceneError("output.compression", f"is a zlib level from 0 (none) to 9, got {compression}")
    return {"precision": _choice(d.get("precision", default.precision), ("double", "single"), "output.precision"),
            "compression": compression,
            "buffer_steps": _int(d.get("buffer_steps", default.buffer_steps), "output.buffer_steps", 1),
            "flush_seconds": _time(d.get("flush_seconds", default.flush_seconds), "output.flush_seconds")}


def normalize(raw: dict) -> dict:
    """Validate ``raw`` and return the normalised scene (SI floats, defaults filled). NumPy values in
    ``raw`` are taken as the plain Python values they hold (:func:`plain`)."""
    raw = plain(raw)
    effect_sections = sections()
    _check_keys(raw, {"model", "mesh", "materials", "joints", "supports", "stages", "solver", "output",
                      *effect_sections}, "")
    for req in ("mesh", "materials", "stages"):
        if req not in raw:
            raise SceneError(req, "section is required")
    model = _model(raw.get("model", {}))
    dim = model["dimension"]
    mats = raw["materials"]
    if not isinstance(mats, dict) or not mats:
        raise SceneError("materials", "give at least one material group, e.g. [materials.units]")
    joints = raw.get("joints", {})
    if not isinstance(joints, dict):
        raise SceneError("joints", "expected a table of joint sets")
    supports = raw.get("supports", [])
    if not isinstance(supports, list):
        raise SceneError("supports", "expected an array of tables [[supports]]")
    sup = []
    for i, s in enumerate(supports):
        _check_keys(s, {"set", "components", "kind"}, f"supports[{i}]")
        if "set" not in s:
            raise SceneError(f"supports[{i}].set", "is required")
        # "fixed": the components are held at zero; "tied": the set's nodes share one displacement in them (free to
        # translate together: a rigid loading beam kept level, Model.add_tie)
        sup.append({"set": str(s["set"]), "components": _components(s.get("components", list(COMPONENT_NAMES[:dim])),
                                                                      f"supports[{i}].components", dim),
                    "kind": _choice(s.get("kind", "fixed"), SUPPORT_KINDS, f"supports[{i}].kind")})
    stages = raw["stages"]
    if not isinstance(stages, list) or not stages:
        raise SceneError("stages", "give at least one stage as [[stages]]")
    st = []
    for i, s in enumerate(stages):
        key = f"stages[{i}]"
        if not isinstance(s, dict):
            raise SceneError(key, f"expected a table, got {type(s).__name__}")
        kind = _choice(s.get("type", "static"), STAGE_TYPES, f"{key}.type")
        if kind == "dynamic":
            st.append(_dynamic_stage(s, key, dim, i))
            continue
        if kind == "modal":
            if any(x["type"] != "static" for x in st):
                raise SceneError(f"{key}.type", "one modal stage, after the static stages and before the dynamic "
                                                "ones (it takes the modes of the static state)")
            _check_keys(s, {"name", "type", "modes", "mass"}, key)
            st.append({"name": str(s.get("name", f"stage{i + 1}")), "type": "modal",
                       "modes": _int(s.get("modes", 6), f"{key}.modes", 1),
                       "mass": _choice(s.get("mass", "consistent"), ("lumped", "consistent"), f"{key}.mass")})
            continue
        if st and st[-1]["type"] in ("dynamic", "modal"):
            raise SceneError(f"{key}.type", "static stages must come before the modal and dynamic stages (they "
                                            "continue from the static state)")
        _check_keys(s, {"name", "type", "steps", "loads", "until_failure", "duration", "control", "limit_point"}, key)
        loads = s.get("loads", [])
        if not isinstance(loads, list):
            raise SceneError(f"{key}.loads", "expected an array of tables [[stages.loads]]")
        st.append({"name": str(s.get("name", f"stage{i + 1}")), "type": "static",
                   "steps": _int(s.get("steps", 1), f"{key}.steps", 1, MAX_STATIC_STEPS, STEPS_WHY),
                   "until_failure": _bool(s.get("until_failure", False), f"{key}.until_failure"),
                   "loads": [_load(ld, f"{key}.loads[{j}]", dim) for j, ld in enumerate(loads)]})
        # "load" (the stage's loads and prescribed displacements, arc-length where that stalls) or "arc_length"
        st[-1]["control"] = _choice(s.get("control", "load"), STATIC_CONTROLS, f"{key}.control")
        # where "load" control finds no equilibrium: follow the path (arc length) or relax the joints there
        st[-1]["limit_point"] = _choice(s.get("limit_point", "follow"), LIMIT_POINTS, f"{key}.limit_point")
        if st[-1]["limit_point"] == "relax" and st[-1]["control"] != "load":
            raise SceneError(f"{key}.limit_point", f"\"relax\" acts where control \"load\" stalls; this stage's "
                                                   f"control is \"{st[-1]['control']}\"")
        if "duration" in s:  # physical time, for rate-dependent (Perzyna) blocks
            st[-1]["duration"] = _positive(s["duration"], "time", f"{key}.duration")
        if st[-1]["until_failure"] and i != len(stages) - 1:
            raise SceneError(f"{key}.until_failure", "applies to the last stage only (the run ends where the stage "
                                                     "finds no equilibrium)")
    names = [s["name"] for s in st]
    if len(set(names)) != len(names):
        raise SceneError("stages", f"stage names must be unique, got {names}")
    dyn_out = [(i, x["output"]) for i, x in enumerate(st) if x["type"] == "dynamic"
               and (x["output"]["nodes"] is not None or x["output"]["joints"] is not None)]
    for (i, a), (j, b) in zip(dyn_out, dyn_out[1:]):
        if (a["nodes"], a["joints"]) != (b["nodes"], b["joints"]):
            raise SceneError(f"stages[{j}].output", f"selects other nodes or joints than stages[{i}].output; the "
                                                    "result file has one node and joint selection for all stages")
    effect_parts = {name: norm(raw[name], model) for name, norm in effect_sections.items() if name in raw}
    check_scene(st, effect_parts)
    out_raw = raw.get("output", {})
    _check_keys(out_raw, {"nodes", "joints", "precision", "compression", "buffer_steps", "flush_seconds", "stress"},
                "output")
    return {
        "model": model,
        "mesh": _mesh(raw["mesh"]),
        "materials": {str(k): _material(k, v) for k, v in mats.items()},
        "joints": {str(k): _joint(k, v) for k, v in joints.items()},
        "supports": sup,
        "stages": st,
        "solver": _solver(raw.get("solver", {})),
        **effect_parts,
        "output": {"nodes": _selection(out_raw.get("nodes", "all"), "output.nodes"),
                   "stress": _choice(out_raw.get("stress", "none"), ("none", "element"), "output.stress"),
                   "joints": _selection(out_raw.get("joints", "all"), "output.joints"),
                   **_output_options(out_raw)},
    }
