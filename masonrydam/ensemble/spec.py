"""The ensemble file: a base scene and the axes swept over it, read and checked into an :class:`EnsembleSpec`.

:func:`load_ensemble` (a TOML file) and :func:`parse_ensemble` (a dictionary) read ``[ensemble]`` (the base
scene, its dynamic stage and ground-motion component, the demand joint sets), ``[axes.records]``,
``[axes.intensity]`` (``scale_to_pga`` in g or m/s2, or ``scale_to_sa`` with period s and damping),
``[[axes.parameters]]`` (scene keys over values, or sampled from a distribution with one Latin hypercube:
:func:`latin_hypercube`, :func:`transform`), ``[axes.sampling]`` and ``[execution]``. Every error is a
:class:`~masonrydam.errors.SceneError` whose key is the ensemble key, raised before any run;
:meth:`EnsembleSpec.member_scene` writes a member's record and intensity into the base stage's ground motion.

Every key with its default, and how a member's ground motion is made: docs/ensembles.md, section "Every key"
(under "The ensemble file").
"""
from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..checks import COMPONENT_NAMES
from ..checks import boolean as _bool
from ..checks import check_keys as _check_keys
from ..checks import integer as _int
from ..checks import number as _number
from ..checks import seconds as _seconds
from ..errors import SceneError
from ..materials.joint_laws import joint_law
from ..scene.schema import plain
from ..scene.scene import Scene, path_parts, read_toml, set_key
from ..units import NUMBER_WITH_UNIT, SI_UNIT, UNITS, quantity

#: suffixes (lower case) of the files taken from ``axes.records.folder``: PEER acceleration files, plain
#: text and the obspy formats masonrydam.records.readers reads (velocity/displacement files are left out)
RECORD_SUFFIXES = (".at2", ".txt", ".csv", ".dat", ".asc", ".acc", ".sac", ".mseed", ".miniseed", ".msd",
                   ".gse2", ".gse")
#: the source keys of a ground-motion component, replaced by the member's record
SOURCE_KEYS = ("record", "file", "values", "pulse", "format", "units", "dt", "column")
#: the scaling keys of a ground-motion component, replaced by the member's intensity
SCALING_KEYS = ("scale", "scale_to_pga", "scale_to_sa")
#: sampled distributions and their parameters
DISTRIBUTIONS = {"lognormal": ("median", "dispersion"), "normal": ("mean", "std"), "uniform": ("low", "high")}
#: the intensity measures: scene scaling key -> (measure, long name)
INTENSITY_MEASURES = {"scale_to_pga": ("pga", "peak ground acceleration"),
                      "scale_to_sa": ("sa", "pseudo-spectral acceleration")}

#: dimension of scene keys by their last name, for the units of a parameter axis whose values are plain
#: numbers (SI); a value written with a unit gives its own dimension
_KEY_DIMENSIONS = {
    "friction_angle": "angle", "residual_friction_angle": "angle", "dilatancy_angle": "angle",
    "cohesion": "stress", "tensile_strength": "stress", "compressive_strength": "stress",
    "youngs_modulus": "stress", "dilatancy_confinement": "stress",
    "normal_stiffness": "stiffness", "shear_stiffness": "stiffness", "residual_shear_stiffness": "stiffness",
    "shear_stiffness_2": "stiffness",
    "density": "density", "submerged_density": "density",
    "mode_I_fracture_energy": "fracture_energy", "mode_II_fracture_energy": "fracture_energy",
    "cap_fracture_energy": "fracture_energy",
    "thickness": "length", "level": "length", "element_size": "length", "cap_peak_plastic_strain": "length",
    "dt": "time", "duration": "time", "dt_max": "time", "dt_min": "time", "relaxation_time": "time",
    "poisson_ratio": "1", "ratio": "1", "dilatancy_decay": "1", "cap_shear_factor": "1", "alpha": "1",
    "rho_inf": "1", "tolerance": "1", "scale": "1",
}


# ------------------------------------------------------------------------------------------------
# the parts of a spec
# ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class RecordSpec:
    """One record of the ``record`` axis.

    name: its coordinate value (a bundled record's name; for a file the path as written, relative to
    the ensemble file, or the table's ``name``); kind: ``"bundled"`` or ``"file"``; source: the
    ground-motion source keys it puts in a member scene (``{"record": name}``, or ``{"file": absolute
    path}`` with ``format``, ``units``, ``dt``, ``column`` where given); key: the ensemble key it came from.
    """

    name: str
    kind: str
    source: dict
    key: str


@dataclass(frozen=True)
class IntensitySpec:
    """The ``intensity`` axis.

    scaling: the scene key it sets (``"scale_to_pga"`` or ``"scale_to_sa"``); measure: ``"pga"`` or
    ``"sa"``; values: the intensities in m/s2 (SI), in the file's order; given: as written; period (s)
    and damping (ratio): of ``scale_to_sa``, else None.
    """

    scaling: str
    measure: str
    values: tuple
    given: tuple
    period: float | None = None
    damping: float | None = None

    def scaling_keys(self, value: float) -> dict:
        """The scaling keys of a member's ground-motion component at intensity ``value`` (m/s2)."""
        if self.scaling == "scale_to_pga":
            return {"scale_to_pga": float(value)}
        return {"scale_to_sa": {"sa": float(value), "period": self.period, "damping": self.damping}}


@dataclass
class ParameterSpec:
    """One ``[[axes.parameters]]`` entry.

    index: its position in ``axes.parameters``; key: the scene key (``set_key`` syntax); name: its axis or
    coordinate name, ``p_<last part of key>`` (more of the path where two would collide); kind: ``"grid"``
    (``values``) or ``"sampled"`` (``distribution``); values: what is written into the member scenes
    (grid: the values as written; sampled: the samples in SI, one per sample index); coords: the
    coordinate values (grid: SI floats where the values are quantities, else as written; sampled: the
    samples); units: SI unit of the coordinate ("" if unknown); dimension: the units' dimension or None;
    distribution: sampled only: ``{"type": ..., <its parameters in SI>}``.
    """

    index: int
    key: str
    name: str
    kind: str
    values: list
    coords: list
    units: str = ""
    dimension: str | None = None
    distribution: dict | None = None

    @property
    def ensemble_key(self) -> str:
        return f"axes.parameters[{self.index}]"


@dataclass
class EnsembleSpec:
    """A checked ensemble file.

    name: the ensemble's name; path: the ensemble file (None for a dictionary); ensemble_dir: its folder
    (what record paths are relative to); scene_path: the base scene file; scene_dir: its folder, the
    ``base_dir`` of the member scenes; base_scene: the base scene's raw dictionary (as in its TOML);
    base_normalized: the same, normalised (SI); stage: index of the dynamic stage (in ``[[stages]]``) that
    gets the records; stage_name: its name; component: ``"x"``, ``"y"`` or ``"z"``; history: keep member
    result files; demand_sets: joint sets measured (:mod:`.measures`); records: :class:`RecordSpec` list;
    intensity: :class:`IntensitySpec`; parameters: :class:`ParameterSpec` list in file order (grid and
    sampled); samples: the Latin hypercube size (None without sampled parameters); seed: its seed; workers:
    LocalCluster workers; scheduler: a scheduler address or None; raw: the ensemble dictionary as read.
    """

    name: str
    path: Path | None
    ensemble_dir: Path
    scene_path: Path
    scene_dir: Path
    base_scene: dict
    base_normalized: dict
    stage: int
    stage_name: str
    component: str
    history: bool
    demand_sets: list
    records: list
    intensity: IntensitySpec
    parameters: list = field(default_factory=list)
    samples: int | None = None
    seed: int | None = None
    workers: int = 1
    scheduler: str | None = None
    raw: dict = field(default_factory=dict)

    @classmethod
    def from_toml(cls, path) -> "EnsembleSpec":
        return load_ensemble(path)

    @property
    def grid_parameters(self) -> list:
        return [p for p in self.parameters if p.kind == "grid"]

    @property
    def sampled_parameters(self) -> list:
        return [p for p in self.parameters if p.kind == "sampled"]

    @property
    def ground_motion_key(self) -> str:
        """The scene key of the ground-motion component the records go to (``stages[1].ground_motion.x``)."""
        return f"stages[{self.stage}].ground_motion.{self.component}"

    @property
    def n_members(self) -> int:
        n = len(self.records) * len(self.intensity.values)
        for p in self.grid_parameters:
            n *= len(p.values)
        return n * (self.samples if self.sampled_parameters else 1)

    def member_scene(self, record: RecordSpec, intensity: float, assignments=()) -> dict:
        """The raw scene of one member: a copy of the base scene with ``record`` at ``intensity`` (m/s2) in
        the ground motion and ``assignments`` (``(scene key, value)`` pairs) set with ``set_key``."""
        data = copy.deepcopy(self.base_scene)
        st = data["stages"][self.stage]
        gm = st.get("ground_motion")
        if not isinstance(gm, dict):
            gm = st["ground_motion"] = {}
        comp = gm.get(self.component)
        comp = {k: copy.deepcopy(v) for k, v in (comp or {}).items() if k not in SOURCE_KEYS + SCALING_KEYS}
        comp.update(copy.deepcopy(record.source))
        comp.update(self.intensity.scaling_keys(intensity))
        gm[self.component] = comp
        for key, value in assignments:
            set_key(data, key, value)
        return data


# ------------------------------------------------------------------------------------------------
# reading
# ------------------------------------------------------------------------------------------------

def load_ensemble(path) -> EnsembleSpec:
    """Read and check the ensemble file ``path`` (TOML)."""
    path = Path(path)
    return parse_ensemble(read_toml(path, "ensemble", "an ensemble"), path.parent, path=path)


def load_spec(path) -> EnsembleSpec:
    """:func:`load_ensemble` (the same function)."""
    return load_ensemble(path)


def parse_ensemble(data: dict, ensemble_dir=".", path=None) -> EnsembleSpec:
    """Check the ensemble dictionary ``data`` (as read from TOML); relative paths are relative to
    ``ensemble_dir``. ``path``: the file it came from (for the default name), or None."""
    data = plain(data)
    ensemble_dir = Path(ensemble_dir)
    _check_keys(data, {"ensemble", "axes", "execution"}, "")
    for req in ("ensemble", "axes"):
        if req not in data:
            raise SceneError(req, "section is required ([ensemble] with the base scene, [axes.records], "
                                  "[axes.intensity])")
    ens = data["ensemble"]
    _check_keys(ens, {"name", "scene", "stage", "component", "history", "demand_sets", "set"}, "ensemble")
    name = ens.get("name", Path(path).stem if path is not None else "ensemble")
    if not isinstance(name, str) or not name.strip():
        raise SceneError("ensemble.name", f"expected a non-empty string, got {name!r}")

    scene_path, scene_dir, base, normalized = _base_scene(ens, ensemble_dir)
    stage, stage_name = _stage(ens, normalized)
    component = _component(ens, normalized, stage)
    history = _bool(ens.get("history", False), "ensemble.history")
    demand_sets = _demand_sets(ens, normalized)

    axes = data["axes"]
    _check_keys(axes, {"records", "intensity", "parameters", "sampling"}, "axes")
    for req in ("records", "intensity"):
        if req not in axes:
            raise SceneError(f"axes.{req}", "is required" + (" (names, files or folder)" if req == "records" else
                                                            " (scale_to_pga or scale_to_sa)"))
    records = _records(axes["records"], ensemble_dir)
    intensity = _intensity(axes["intensity"])
    parameters = _parameters(axes.get("parameters", []))
    samples, seed = _sampling(axes, parameters)
    execution = data.get("execution", {})
    _check_keys(execution, {"workers", "scheduler"}, "execution")
    workers = _int(execution.get("workers", os.cpu_count() or 1), "execution.workers", 1)
    scheduler = execution.get("scheduler")
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise SceneError("execution.scheduler", f"expected an address such as \"tcp://host:8786\", got {scheduler!r}")

    spec = EnsembleSpec(name=name.strip(), path=None if path is None else Path(path), ensemble_dir=ensemble_dir,
                        scene_path=scene_path, scene_dir=scene_dir, base_scene=base, base_normalized=normalized,
                        stage=stage, stage_name=stage_name, component=component, history=history,
                        demand_sets=demand_sets, records=records, intensity=intensity, parameters=parameters,
                        samples=samples, seed=seed, workers=workers, scheduler=scheduler, raw=data)
    _check_parameter_keys(spec)
    _check_first_member(spec)
    return spec


def _base_scene(ens, ensemble_dir):
    if "scene" not in ens:
        raise SceneError("ensemble.scene", "is required: the base scene file, relative to the ensemble file")
    if not isinstance(ens["scene"], str) or not ens["scene"].strip():
        raise SceneError("ensemble.scene", f"expected a file name, got {ens['scene']!r}")
    p = Path(ens["scene"])
    p = p if p.is_absolute() else ensemble_dir / p
    if not p.is_file():
        what = "is a folder, not a scene file" if p.is_dir() else "does not exist"
        raise SceneError("ensemble.scene", f"the base scene '{p}' {what}")
    try:
        sc = Scene.from_toml(p)
    except SceneError as exc:
        raise SceneError("ensemble.scene", f"the base scene '{p}' is not valid: {exc}") from None
    fixed = ens.get("set", {})  # scene keys changed for every member (e.g. a component turned off)
    if not isinstance(fixed, dict):
        raise SceneError("ensemble.set", f"expected a table of scene keys and values, got {fixed!r}")
    if fixed:
        data = sc.data
        for key, value in fixed.items():
            try:
                set_key(data, key, value)
            except SceneError as exc:
                raise SceneError(f"ensemble.set.{key}", str(exc)) from None
        try:
            sc = Scene(data, base_dir=p.parent, source=str(p))
        except SceneError as exc:
            raise SceneError("ensemble.set", f"the base scene with these keys is not valid: {exc}") from None
    return p, p.parent, sc.data, sc.normalized


def _stage(ens, normalized):
    stages = normalized["stages"]
    dynamic = [i for i, s in enumerate(stages) if s["type"] == "dynamic"]
    if "stage" not in ens:
        if not dynamic:
            raise SceneError("ensemble.scene", "the base scene has no dynamic stage (type = \"dynamic\") to put "
                                               "the records in; its stages are "
                                               + ", ".join(f"{s['name']} ({s['type']})" for s in stages))
        i = dynamic[0]
    else:
        i = _int(ens["stage"], "ensemble.stage", 0)
        if i >= len(stages):
            raise SceneError("ensemble.stage", f"the base scene has {len(stages)} stages (indices 0 to "
                                               f"{len(stages) - 1}), got {i}")
        if stages[i]["type"] != "dynamic":
            hint = f"; its dynamic stages: {dynamic}" if dynamic else "; it has no dynamic stage"
            raise SceneError("ensemble.stage", f"stage {i} ('{stages[i]['name']}') of the base scene is "
                                               f"{stages[i]['type']}, not dynamic{hint}")
    return i, stages[i]["name"]


def _component(ens, normalized, stage):
    dim = normalized["model"]["dimension"]
    names = COMPONENT_NAMES[:dim]
    if "component" in ens:
        c = ens["component"]
        if c not in names:
            raise SceneError("ensemble.component", f"must be one of {list(names)}, got {c!r}")
        return c
    given = list(normalized["stages"][stage]["ground_motion"])
    return given[0] if len(given) == 1 else "x"


def _demand_sets(ens, normalized):
    joints = normalized["joints"]
    if "demand_sets" not in ens:
        return [k for k, j in joints.items() if joint_law(j["law"]).nonlinear]
    sets = ens["demand_sets"]
    if isinstance(sets, str):
        sets = [sets]
    if not isinstance(sets, list) or not all(isinstance(s, str) for s in sets):
        raise SceneError("ensemble.demand_sets", f"expected a list of joint set names, got {sets!r}")
    for j, s in enumerate(sets):
        if s not in joints:
            raise SceneError(f"ensemble.demand_sets[{j}]", f"'{s}' is not a joint set of the base scene (its sets: "
                                                          f"{', '.join(joints) or 'none'})")
    if len(set(sets)) != len(sets):
        raise SceneError("ensemble.demand_sets", f"repeated joint set in {sets}")
    return list(sets)


def _file_options(d, key, defaults=None):
    """The read options (format, units, dt, column) of a record file table, over ``defaults``."""
    out = dict(defaults or {})
    if "format" in d:
        if not isinstance(d["format"], str):
            raise SceneError(f"{key}.format", f"expected a format name, got {d['format']!r}")
        out["format"] = d["format"]
    if "units" in d:
        if not isinstance(d["units"], str):
            raise SceneError(f"{key}.units", f"expected units such as \"g\", got {d['units']!r}")
        out["units"] = d["units"]
    if "dt" in d:
        out["dt"] = _seconds(d["dt"], f"{key}.dt")
    if "column" in d:
        out["column"] = _int(d["column"], f"{key}.column", 0)
    return out


def _file_record(path: Path, name: str, options: dict, key: str, option_key: str) -> RecordSpec:
    # obspy only where the ensemble reads records: keeps 'masonrydam ensemble-report' start-up short
    from .. import records as rec

    try:
        rec.read_trace(path, format=options.get("format"), units=options.get("units"), dt=options.get("dt"),
                       column=options.get("column"), option_names=rec.readers.scene_option_names(option_key))
    except rec.RecordError as exc:
        raise SceneError(key, str(exc)) from None
    return RecordSpec(name=name, kind="file", source={"file": str(path.resolve()), **options}, key=key)


def _records(d, ensemble_dir):
    # obspy only where the ensemble reads records: keeps 'masonrydam ensemble-report' start-up short
    from .. import records as rec

    key = "axes.records"
    _check_keys(d, {"names", "files", "folder", "format", "units", "dt"}, key)
    defaults = _file_options({k: d[k] for k in ("format", "units", "dt") if k in d}, key)
    out = []
    names = d.get("names", [])
    if isinstance(names, str):
        names = [names]
    if not isinstance(names, list):
        raise SceneError(f"{key}.names", f"expected a list of bundled record names, got {names!r}")
    for j, n in enumerate(names):
        k = f"{key}.names[{j}]"
        if not isinstance(n, str):
            raise SceneError(k, f"expected a record name, got {n!r}")
        try:
            info = rec.record_info(n)
        except rec.RecordError as exc:
            raise SceneError(k, str(exc)) from None
        if info["quantity"] != "acceleration":
            raise SceneError(k, f"bundled record '{n}' is a {info['quantity']} record; a ground motion is an "
                                "acceleration record")
        out.append(RecordSpec(name=n, kind="bundled", source={"record": n}, key=k))
    files = d.get("files", [])
    if isinstance(files, (str, dict)):
        files = [files]
    if not isinstance(files, list):
        raise SceneError(f"{key}.files", f"expected a list of record files, got {files!r}")
    for j, f in enumerate(files):
        k = f"{key}.files[{j}]"
        if isinstance(f, dict):
            _check_keys(f, {"file", "name", "format", "units", "dt", "column"}, k)
            if not isinstance(f.get("file"), str):
                raise SceneError(f"{k}.file", "is required: the record file, relative to the ensemble file")
            opts, text = _file_options(f, k, defaults), f["file"]
            name = f.get("name", text)
            if not isinstance(name, str) or not name:
                raise SceneError(f"{k}.name", f"expected a non-empty string, got {name!r}")
            option_key = k
        elif isinstance(f, str):
            opts, text, name, option_key = defaults, f, f, key
        else:
            raise SceneError(k, f"expected a file name or a table {{ file = ..., units = ... }}, got {f!r}")
        p = Path(text)
        p = p if p.is_absolute() else ensemble_dir / p
        if not p.is_file():
            raise SceneError(k, f"record file '{p}' " + ("is a folder" if p.is_dir() else "does not exist"))
        out.append(_file_record(p, Path(name).as_posix() if name == text else name, opts, k, option_key))
    if "folder" in d:
        k = f"{key}.folder"
        if not isinstance(d["folder"], str):
            raise SceneError(k, f"expected a folder name, got {d['folder']!r}")
        folder = Path(d["folder"])
        full = folder if folder.is_absolute() else ensemble_dir / folder
        if not full.is_dir():
            raise SceneError(k, f"'{full}' " + ("is a file, not a folder" if full.exists() else "does not exist"))
        found = sorted(p for p in full.iterdir()
                       if p.is_file() and not p.name.startswith(".") and p.suffix.lower() in RECORD_SUFFIXES)
        if not found:
            raise SceneError(k, f"the folder '{full}' holds no record files (files ending in "
                                f"{', '.join(RECORD_SUFFIXES)})")
        for p in found:
            out.append(_file_record(p, (folder / p.name).as_posix(), defaults, f"{k} ({p.name})", key))
    if not out:
        raise SceneError(key, "give at least one record: names (bundled), files or folder")
    seen = {}
    for r in out:
        if r.name in seen:
            raise SceneError(r.key, f"record '{r.name}' is already on the axis ({seen[r.name]})")
        seen[r.name] = r.key
    return out


def _acceleration(v, key):
    a = quantity(v, "acceleration", key)
    if a <= 0:
        raise SceneError(key, f"must be > 0, got {v!r}")
    return a


def _intensity(d):
    key = "axes.intensity"
    _check_keys(d, set(INTENSITY_MEASURES), key)
    given = [k for k in INTENSITY_MEASURES if k in d]
    if len(given) != 1:
        raise SceneError(key, "give one of scale_to_pga = [...] or scale_to_sa = { values = [...], period = ... }")
    scaling = given[0]
    measure = INTENSITY_MEASURES[scaling][0]
    period = damping = None
    if scaling == "scale_to_pga":
        vals, vk = d[scaling], f"{key}.scale_to_pga"
    else:
        t, sk = d[scaling], f"{key}.scale_to_sa"
        _check_keys(t, {"values", "period", "damping"}, sk)
        for req in ("values", "period"):
            if req not in t:
                raise SceneError(f"{sk}.{req}", "is required (the spectral accelerations and their period)")
        vals, vk = t["values"], f"{sk}.values"
        period = _seconds(t["period"], f"{sk}.period")
        damping = _number(t.get("damping", 0.05), f"{sk}.damping", 0.0, 1.0, open_min=True)
    if not isinstance(vals, list) or not vals:
        raise SceneError(vk, f"expected a non-empty list of accelerations (\"0.3 g\" or m/s2), got {vals!r}")
    si = [_acceleration(v, f"{vk}[{j}]") for j, v in enumerate(vals)]
    for j, v in enumerate(si):
        if any(math.isclose(v, w, rel_tol=1e-12) for w in si[:j]):
            raise SceneError(f"{vk}[{j}]", f"repeats the intensity {vals[j]!r}")
    return IntensitySpec(scaling=scaling, measure=measure, values=tuple(si), given=tuple(vals), period=period,
                         damping=damping)


def _split_quantity(value, key):
    """``(SI value, dimension)`` of a parameter value: a plain number -> (float, None); ``"<number> <unit>"``
    with a known unit (or s, ms) -> (SI float, dimension); anything else -> (value, None), not a quantity."""
    if isinstance(value, bool):
        return value, None
    if isinstance(value, (int, float)):
        if not math.isfinite(float(value)):
            raise SceneError(key, f"must be a finite number, got {value!r}")
        return float(value), None
    if isinstance(value, str):
        m = NUMBER_WITH_UNIT.match(value)
        if m and m.group(2) is None:
            return value, None  # a number written as a string: the scene decides what it is
        if m and m.group(2) in UNITS:
            dim, factor = UNITS[m.group(2)]
            return float(m.group(1)) * factor, dim
        if m and m.group(2) in ("s", "ms"):
            return float(m.group(1)) * (1.0 if m.group(2) == "s" else 1e-3), "time"
    return value, None


def _units_of(key, dims, key_name):
    dims = {d for d in dims if d is not None}
    if len(dims) > 1:
        raise SceneError(key, f"the values mix quantities of different kinds ({', '.join(sorted(dims))})")
    dim = dims.pop() if dims else _KEY_DIMENSIONS.get(key_name)
    if dim is None:
        return "", None
    return ("1" if dim == "1" else SI_UNIT[dim]), dim


def _key_name(key):
    return key.split(".")[-1].split("[")[0]


def _distribution(d, key):
    if not isinstance(d, dict) or "type" not in d:
        raise SceneError(key, "expected a table with 'type' (lognormal, normal or uniform) and its parameters, e.g. "
                              "{ type = \"lognormal\", median = \"0.1 MPa\", dispersion = 0.3 }")
    kind = d["type"]
    if kind not in DISTRIBUTIONS:
        raise SceneError(f"{key}.type", f"must be one of {list(DISTRIBUTIONS)}, got {kind!r}")
    params = DISTRIBUTIONS[kind]
    _check_keys(d, {"type", *params}, key)
    out, dims = {"type": kind}, []
    for p in params:
        if p not in d:
            raise SceneError(f"{key}.{p}", f"is required for a {kind} distribution ({', '.join(params)})")
        if kind == "lognormal" and p == "dispersion":
            v, dim = _number(d[p], f"{key}.{p}"), None  # the standard deviation of ln(x): a plain number
        else:
            v, dim = _split_quantity(d[p], f"{key}.{p}")
            if not isinstance(v, float):
                raise SceneError(f"{key}.{p}", f"expected a number or a quantity such as \"0.1 MPa\", got {d[p]!r}")
            dims.append(dim)
        out[p] = v
    kinds = sorted({dim for dim in dims if dim is not None})
    if len(kinds) > 1:
        raise SceneError(key, f"the parameters mix quantities of different kinds ({', '.join(kinds)})")
    if kind == "lognormal":
        if out["median"] <= 0:
            raise SceneError(f"{key}.median", f"a lognormal median must be > 0, got {d['median']!r}")
        if out["dispersion"] <= 0:
            raise SceneError(f"{key}.dispersion", f"must be > 0 (the standard deviation of ln x), got "
                                                  f"{d['dispersion']!r}")
    elif kind == "normal":
        if out["std"] <= 0:
            raise SceneError(f"{key}.std", f"must be > 0, got {d['std']!r}")
    elif not out["low"] < out["high"]:
        raise SceneError(f"{key}.high", f"must be larger than low ({d['low']!r}), got {d['high']!r}")
    return out, dims


def _parameters(entries):
    key = "axes.parameters"
    if isinstance(entries, dict):
        entries = [entries]
    if not isinstance(entries, list):
        raise SceneError(key, "expected an array of tables [[axes.parameters]] with key and values (or distribution)")
    out, seen = [], {}
    for i, e in enumerate(entries):
        k = f"{key}[{i}]"
        _check_keys(e, {"key", "values", "distribution"}, k)
        if not isinstance(e.get("key"), str) or not e["key"].strip():
            raise SceneError(f"{k}.key", "is required: a scene key such as \"joints.joints.friction_angle\"")
        skey = e["key"].strip()
        if skey in seen:
            raise SceneError(f"{k}.key", f"'{skey}' is already swept by axes.parameters[{seen[skey]}]")
        seen[skey] = i
        if ("values" in e) == ("distribution" in e):
            raise SceneError(k, "give 'values' (a list) or 'distribution' (a table), one of them")
        if "values" in e:
            vals = e["values"]
            if not isinstance(vals, list) or not vals:
                raise SceneError(f"{k}.values", f"expected a non-empty list, got {vals!r}")
            pairs = [_split_quantity(v, f"{k}.values[{j}]") for j, v in enumerate(vals)]
            coords = [c for c, _ in pairs]
            for j, c in enumerate(coords):
                if any(type(c) is type(o) and c == o for o in coords[:j]):
                    raise SceneError(f"{k}.values[{j}]", f"repeats the value {vals[j]!r}")
            units, dim = _units_of(f"{k}.values", [d for _, d in pairs], _key_name(skey))
            out.append(ParameterSpec(index=i, key=skey, name="", kind="grid", values=list(vals), coords=coords,
                                     units=units, dimension=dim))
        else:
            dist, dims = _distribution(e["distribution"], f"{k}.distribution")
            units, dim = _units_of(f"{k}.distribution", dims, _key_name(skey))
            out.append(ParameterSpec(index=i, key=skey, name="", kind="sampled", values=[], coords=[], units=units,
                                     dimension=dim, distribution=dist))
    names = parameter_names([p.key for p in out])
    for p, n in zip(out, names):
        p.name = n
    return out


def parameter_names(keys) -> list:
    """Axis names of the scene keys ``keys``: ``p_<last part>``, with more of the path (``p_bed_friction_angle``)
    where two would collide; list indices join their name (``stages[1]`` -> ``stages1``)."""
    tokens = [[piece.replace("[", "").replace("]", "") for piece in k.split(".")] for k in keys]
    depth = [1] * len(keys)
    while True:
        names = ["p_" + "_".join(t[-d:]) for t, d in zip(tokens, depth)]
        clash = {n for n in names if names.count(n) > 1}
        if not clash:
            return names
        grown = False
        for i, n in enumerate(names):
            if n in clash and depth[i] < len(tokens[i]):
                depth[i] += 1
                grown = True
        if not grown:  # (keys differing only in case or punctuation): number them
            return [n if names.count(n) == 1 else f"{n}_{i}" for i, n in enumerate(names)]


def _sampling(axes, parameters):
    sampled = [p for p in parameters if p.kind == "sampled"]
    if "sampling" not in axes:
        if sampled:
            raise SceneError("axes.sampling.samples", f"is required: axes.parameters[{sampled[0].index}] is sampled "
                                                      "from a distribution ([axes.sampling] samples = N, seed = S)")
        return None, None
    d = axes["sampling"]
    _check_keys(d, {"samples", "seed"}, "axes.sampling")
    if not sampled:
        raise SceneError("axes.sampling", "no parameter is sampled (give a [[axes.parameters]] a 'distribution', "
                                          "or remove [axes.sampling])")
    if "samples" not in d:
        raise SceneError("axes.sampling.samples", "is required (the number of Latin hypercube samples)")
    n = _int(d["samples"], "axes.sampling.samples", 1)
    seed = _int(d.get("seed", 0), "axes.sampling.seed", 0)
    u = latin_hypercube(len(sampled), n, seed)
    for j, p in enumerate(sampled):
        p.values = [float(x) for x in transform(u[:, j], p.distribution)]
        p.coords = list(p.values)
    return n, seed


def latin_hypercube(d: int, n: int, seed: int) -> np.ndarray:
    """``(n, d)`` points in (0, 1): one Latin hypercube (:class:`scipy.stats.qmc.LatinHypercube`), one point
    in each of the ``n`` bins ``[k/n, (k+1)/n)`` of every column; the same for the same seed."""
    # scipy.stats (a second to import) only for sampled parameters, not on every worker
    from scipy.stats import qmc

    try:
        sampler = qmc.LatinHypercube(d=d, rng=np.random.default_rng(seed))
    except TypeError:  # scipy < 1.15
        sampler = qmc.LatinHypercube(d=d, seed=np.random.default_rng(seed))
    u = sampler.random(n)
    # (a point exactly on 0 would map to -inf: move it into its bin)
    return np.clip(u, 1e-12, 1.0 - 1e-12)


def transform(u, dist: dict) -> np.ndarray:
    """The quantiles ``u`` (in (0, 1)) of the distribution ``dist`` (SI parameters, as parsed)."""
    # scipy.stats (a second to import) only for sampled parameters, not on every worker
    from scipy.stats import norm

    u = np.asarray(u, dtype=float)
    kind = dist["type"]
    if kind == "lognormal":
        return dist["median"] * np.exp(dist["dispersion"] * norm.ppf(u))
    if kind == "normal":
        return dist["mean"] + dist["std"] * norm.ppf(u)
    return dist["low"] + (dist["high"] - dist["low"]) * u


def cdf(x, dist: dict) -> np.ndarray:
    """The distribution function of ``dist`` at ``x`` (the inverse of :func:`transform`)."""
    # scipy.stats (a second to import) only for sampled parameters, not on every worker
    from scipy.stats import norm

    x = np.asarray(x, dtype=float)
    kind = dist["type"]
    if kind == "lognormal":
        return norm.cdf(np.log(x / dist["median"]) / dist["dispersion"])
    if kind == "normal":
        return norm.cdf((x - dist["mean"]) / dist["std"])
    return (x - dist["low"]) / (dist["high"] - dist["low"])


# ------------------------------------------------------------------------------------------------
# checks against the base scene
# ------------------------------------------------------------------------------------------------

def _normalize(data, spec):
    Scene(data, base_dir=spec.scene_dir)


def _check_parameter_keys(spec: EnsembleSpec):
    """Every swept key, with each of its values (grid) or samples, set alone on the base scene must give a
    valid scene; the error names ``axes.parameters[i].key`` (a key the scene does not know, or that would
    change the member's record or intensity) or the value (``.values[j]``, ``.distribution``)."""
    gm_parts = path_parts(spec.ground_motion_key)
    for p in spec.parameters:
        k = p.ensemble_key
        try:
            parts = path_parts(p.key)
        except SceneError as exc:
            raise SceneError(f"{k}.key", f"'{p.key}': {exc}") from None
        if parts[:len(gm_parts)] == gm_parts and (len(parts) == len(gm_parts) or
                                                 parts[len(gm_parts)] in SOURCE_KEYS + SCALING_KEYS):
            raise SceneError(f"{k}.key", f"'{p.key}' is the record or the intensity of the members "
                                         f"({spec.ground_motion_key}); sweep them with [axes.records] and "
                                         "[axes.intensity]")
        values = p.values
        for j, v in enumerate(values):
            data = copy.deepcopy(spec.base_scene)
            try:
                set_key(data, p.key, v)
            except SceneError as exc:
                raise SceneError(f"{k}.key", f"'{p.key}' is not a key of the base scene: {exc}") from None
            try:
                _normalize(data, spec)
            except SceneError as exc:
                missing = _creates_tables(spec.base_scene, parts)
                if j == 0 and missing:
                    raise SceneError(f"{k}.key", f"'{p.key}': the base scene has no '{missing}' (setting the key "
                                                 f"creates it, and the scene then says: {exc})") from None
                if j == 0 and _names_the_key(exc, p.key, parts):
                    raise SceneError(f"{k}.key", f"'{p.key}' is not a key of the base scene: {exc}") from None
                where = f"{k}.values[{j}]" if p.kind == "grid" else f"{k}.distribution"
                what = repr(v) if p.kind == "grid" else f"sample {j} = {v:g}"
                raise SceneError(where, f"{what} makes the base scene invalid: {exc}") from None


def _creates_tables(data, parts) -> str | None:
    """The first table along the key ``parts`` that the base scene ``data`` does not have (a joint set,
    material or section it does not define: then any complaint of the scene is about the key), as a
    dotted path; None where every table along it exists."""
    node, path = data, ""
    for part in parts[:-1]:
        path += f"[{part}]" if isinstance(part, int) else (f".{part}" if path else part)
        if isinstance(part, int):
            if not isinstance(node, list) or part >= len(node):
                return None
        elif not isinstance(node, dict) or part not in node:
            return path
        node = node[part]
    return None


def _names_the_key(exc: SceneError, key: str, parts) -> bool:
    """Whether the scene's complaint is about the key itself (an unknown key or table), not its value."""
    msg = str(exc)
    if "unknown key" not in msg and "expected a table" not in msg:
        return False
    try:
        where = path_parts(exc.key)
    except SceneError:
        return True
    return parts[:len(where)] == where  # the complaint is on the key's path


def _check_first_member(spec: EnsembleSpec):
    """The first member (first record, intensity, values and sample) must make a valid scene."""
    assignments = [(p.key, p.values[0]) for p in spec.parameters]
    try:
        data = spec.member_scene(spec.records[0], spec.intensity.values[0], assignments)
        _normalize(data, spec)
    except SceneError as exc:
        raise SceneError("ensemble", f"the first member's scene ({spec.records[0].name}, intensity "
                                     f"{spec.intensity.values[0]:g} m/s2) is not valid: {exc}") from None


__all__ = ["EnsembleSpec", "RecordSpec", "IntensitySpec", "ParameterSpec", "load_ensemble", "load_spec",
           "parse_ensemble",
           "parameter_names", "latin_hypercube", "transform", "cdf", "RECORD_SUFFIXES", "SOURCE_KEYS",
           "SCALING_KEYS", "DISTRIBUTIONS", "INTENSITY_MEASURES"]
