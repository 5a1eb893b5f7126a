"""Loads given in time in a dynamic stage: nodal forces, tractions and pressures times a time function
(an impact on a wall, a blast pressure, a shaker), on top of the static loads and any ground motion.

A dynamic stage's ``loads`` are loads of the static kinds ``nodal``, ``traction`` / ``edge_traction`` and
``pressure`` / ``edge_pressure``, each with a ``time_function`` (dimensionless) by which its magnitude is
multiplied at the stage time ``t`` (s, from the stage's start):

- ``{ type = "table", time = [...], values = [...] }``: linear interpolation between the points; before the
  first and after the last time the end values hold;
- ``{ type = "file", path = "pulse.txt", column = 0 }``: the same from a text file of columns (the time in s
  first, then value columns; ``column`` counts the value columns from 0 without the time column, as a ground
  motion's ``column`` does; ``#`` comments), a path relative to the scene file;
- ``{ type = "pulse", shape = "rectangular" | "half_sine" | "triangular", duration = 0.05, start = 0 }``:
  1 (rectangular), ``sin(pi s / duration)`` (half sine) or a symmetric triangle of peak 1 for ``0 <= s <=
  duration``, ``s = t - start``, and 0 outside (:func:`masonrydam.pulses.unit_pulse`);
- ``{ type = "harmonic", frequency = 2.0, phase = 0, start = 0, duration = ... }``: ``sin(2 pi f s + phase)``
  for ``s = t - start >= 0`` (and ``s <= duration`` when given; phase in degrees), 0 before.

The load vector is assembled once per load (the consistent nodal forces of :mod:`.loads`) and scaled in
time: :func:`load_history` gives the stage's ``force(t)`` (:class:`masonrydam.solvers.dynamic.DynamicTerms`),
whose work the energy balance counts as ``input``. Closed forms that check it (tests/effects/test_dynamic_loads.py):
an undamped oscillator under a suddenly applied constant force, ``u = F/k (1 - cos(omega t))``, and under a
harmonic force, ``u = F/k / (1 - b^2) (sin(Omega t) - b sin(omega t))``, ``b = Omega/omega`` (Chopra,
Dynamics of Structures, 4th ed., 2012, eqs. 4.3.2 and 3.1.6).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..checks import check_keys, choice, number
from ..checks import seconds as _seconds
from ..errors import SceneError
from ..keys import REQUIRED, TIME, Section
from ..keys import key as row
from ..pulses import PULSE_SHAPES, unit_pulse
from .base import Effect, EffectRun, add_force
from .loads import LOAD_TYPES, load_vector

TIME_FUNCTIONS = ("table", "file", "pulse", "harmonic")
#: static load types a dynamic stage takes, with a time function
DYNAMIC_LOAD_TYPES = ("nodal", "traction", "edge_traction", "pressure", "edge_pressure")


def normalize_time_function(d, key: str) -> dict:
    """The normalised time function of a dynamic load (see the module docstring); SceneError naming the key."""
    if not isinstance(d, dict) or "type" not in d:
        raise SceneError(key, f"expected a table with 'type' (one of {list(TIME_FUNCTIONS)}), e.g. "
                              "{ type = \"pulse\", shape = \"half_sine\", duration = 0.01 }")
    kind = choice(d["type"], TIME_FUNCTIONS, f"{key}.type")
    if kind == "table":
        check_keys(d, {"type", "time", "values"}, key)
        t, v = d.get("time"), d.get("values")
        if not isinstance(t, list) or not isinstance(v, list) or len(t) != len(v) or len(t) < 2:
            raise SceneError(key, "'time' and 'values' must be lists of the same length (2 or more points)")
        t = [number(x, f"{key}.time[{i}]") for i, x in enumerate(t)]
        v = [number(x, f"{key}.values[{i}]") for i, x in enumerate(v)]
        if any(b <= a for a, b in zip(t, t[1:])):
            raise SceneError(f"{key}.time", "must increase strictly")
        return {"type": "table", "time": t, "values": v}
    if kind == "file":
        check_keys(d, {"type", "path", "column"}, key)
        if not isinstance(d.get("path"), str):
            raise SceneError(f"{key}.path", "is required: a text file of columns (time in s first)")
        col = d.get("column", 0)
        if isinstance(col, bool) or not isinstance(col, int) or col < 0:
            raise SceneError(f"{key}.column", f"must be a value column index >= 0 (counted after the time "
                                              f"column), got {col!r}")
        return {"type": "file", "path": d["path"], "column": col}
    if kind == "pulse":
        check_keys(d, {"type", "shape", "duration", "start"}, key)
        if "duration" not in d:
            raise SceneError(f"{key}.duration", "is required (s)")
        return {"type": "pulse", "shape": choice(d.get("shape", "rectangular"), PULSE_SHAPES, f"{key}.shape"),
                "duration": _seconds(d["duration"], f"{key}.duration"),
                "start": _seconds(d.get("start", 0), f"{key}.start", allow_zero=True)}
    check_keys(d, {"type", "frequency", "phase", "start", "duration"}, key)
    if "frequency" not in d:
        raise SceneError(f"{key}.frequency", "is required (Hz)")
    return {"type": "harmonic", "frequency": number(d["frequency"], f"{key}.frequency", 0.0, open_min=True),
            "phase": number(d.get("phase", 0.0), f"{key}.phase"),
            "start": _seconds(d.get("start", 0), f"{key}.start", allow_zero=True),
            "duration": None if "duration" not in d else _seconds(d["duration"], f"{key}.duration")}


def normalize_dynamic_load(d, key: str, dim: int) -> dict:
    """A load of a dynamic stage: a static load of a type in :data:`DYNAMIC_LOAD_TYPES` (normalised by
    :mod:`.loads`) with its ``time_function``."""
    if not isinstance(d, dict) or "type" not in d:
        raise SceneError(f"{key}.type", "every load needs a 'type'")
    if d["type"] not in DYNAMIC_LOAD_TYPES:
        raise SceneError(f"{key}.type", f"a dynamic stage takes loads of type {list(DYNAMIC_LOAD_TYPES)} with a "
                                        f"time_function, got {d['type']!r} (self-weight and the static loads stay "
                                        "applied from the static stages; prescribed displacements are static)")
    if "time_function" not in d:
        raise SceneError(f"{key}.time_function", "is required: how the load varies in time, e.g. "
                                                 "{ type = \"harmonic\", frequency = 2.0 }")
    static = {k: v for k, v in d.items() if k != "time_function"}
    out = LOAD_TYPES[d["type"]](static, key, dim)
    out["time_function"] = normalize_time_function(d["time_function"], f"{key}.time_function")
    return out


@dataclass
class TimeFunction:
    """A normalised time function, evaluated by :meth:`at` (dimensionless) at the stage time ``t`` (s)."""

    spec: dict
    time: np.ndarray | None = None
    values: np.ndarray | None = None

    @classmethod
    def build(cls, spec: dict, key: str, base_dir: Path | None = None) -> "TimeFunction":
        if spec["type"] == "table":
            return cls(spec, np.asarray(spec["time"], float), np.asarray(spec["values"], float))
        if spec["type"] == "file":
            path = Path(spec["path"])
            if not path.is_absolute() and base_dir is not None:
                path = Path(base_dir) / path
            try:
                data = np.loadtxt(path, comments="#", ndmin=2)
            except (OSError, ValueError) as exc:
                raise SceneError(f"{key}.path", f"cannot read '{path}' as columns of numbers: {exc}") from None
            col = spec["column"] + 1  # (the time is column 0 of the file)
            if data.shape[1] <= col:
                raise SceneError(f"{key}.column", f"'{path}' has {data.shape[1] - 1} value column(s) after the "
                                                  f"time; value column {spec['column']} is not there")
            t, v = data[:, 0], data[:, col]
            if len(t) < 2 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(data[:, [0, col]])):
                raise SceneError(f"{key}.path", f"'{path}': the times (column 0) must increase strictly and the "
                                                "values be finite")
            return cls(spec, t, v)
        return cls(spec)

    def at(self, t: float) -> float:
        s = self.spec
        if self.time is not None:
            return float(np.interp(t, self.time, self.values))
        tau = t - s["start"]
        if s["type"] == "pulse":
            return unit_pulse(s["shape"], tau, s["duration"])
        if tau < 0.0 or (s["duration"] is not None and tau > s["duration"]):
            return 0.0
        return math.sin(2.0 * math.pi * s["frequency"] * tau + math.radians(s["phase"]))


#: a dynamic stage's (largest) step may be at most this fraction of its loads' time scale (:func:`time_scale`)
STEPS_PER_TIME_SCALE = 4


def time_scale(tf: "TimeFunction") -> float:
    """The shortest time (s) over which a time function changes: a pulse's duration, the closest points of a
    table or file, a fifth of a harmonic's period. A step longer than a quarter of it could pass over the load
    (both ends of a step may miss a short pulse entirely: neither a fixed step nor the error estimate of
    ``dt = "auto"``, which looks at the step's ends, would see it), so dynamic stages refuse such steps."""
    s = tf.spec
    if s["type"] == "pulse":
        return s["duration"]
    if s["type"] == "harmonic":
        return 0.2 / s["frequency"]
    return float(np.min(np.diff(tf.time)))


def load_history(loads: list[tuple[np.ndarray, TimeFunction]]):
    """``force(t) -> (n_dof,)`` N: the sum of each load vector (n_dof,) N times its time function at ``t``."""
    vectors = [np.asarray(f, dtype=np.float64) for f, _ in loads]
    functions = [tf for _, tf in loads]

    def force(t: float) -> np.ndarray:
        out = np.zeros_like(vectors[0])
        for f, tf in zip(vectors, functions):
            a = tf.at(t)
            if a != 0.0:
                out += a * f
        return out

    return force


def _describe(scene, model):
    lines = []
    for st in scene["stages"]:
        if st["type"] != "dynamic" or not st.get("loads"):
            continue
        what = ", ".join(f"{ld['type']} on '{ld['set']}' x {ld['time_function']['type']}" for ld in st["loads"])
        lines.append(f"dynamic stage '{st['name']}': loads given in time: {what}")
    return lines


def _add_loads_in_time(context, st: dict, i: int, stage_parts) -> None:
    """``force(t)`` (n_dof,) N of a dynamic stage's loads given in time into ``stage_parts.loads`` (None without
    such loads)."""
    if not st.get("loads"):
        return
    parts = []
    for j, ld in enumerate(st["loads"]):
        key = f"stages[{i}].loads[{j}]"
        kind = {"edge_traction": "traction", "edge_pressure": "pressure"}.get(ld["type"], ld["type"])
        tf = TimeFunction.build(ld["time_function"], f"{key}.time_function", context.base_dir)
        scale = time_scale(tf)
        if st["dt"] > scale / STEPS_PER_TIME_SCALE:
            what = "dt_max" if st.get("adaptive") else "dt"
            raise SceneError(f"stages[{i}].{what}", f"{st['dt']:g} s is too long for {key}.time_function, which "
                                                    f"changes within {scale:g} s: the steps could pass over it; use "
                                                    f"{what} <= {scale / STEPS_PER_TIME_SCALE:g} s")
        parts.append((load_vector(context, dict(ld, type=kind), key), tf))
    stage_parts.loads = load_history(parts)


class DynamicLoadsRun(EffectRun):
    """Adds each dynamic stage's loads given in time (its ``loads``, built with the stage) to its forces."""

    def dynamic_terms(self, stage, terms) -> None:
        if stage.loads is not None:
            add_force(terms, stage.loads)


def _activate(context):
    return DynamicLoadsRun() if any(st.loads is not None for st in context.dynamic_stages) else None


# -- the rows of its scene keys in the scene reference (docs/scene.md) ----------------------------------------
_TF = "stages[].loads[].time_function"
_TIME_LOADS = Section("Loads of a dynamic stage", "A load of a dynamic stage is a static load of type "
                      + ", ".join(f"`{t}`" for t in DYNAMIC_LOAD_TYPES) + " with the keys it has in a static stage "
                      "and a `time_function`, by which its magnitude is multiplied at the stage time t (from the "
                      "stage's start).", (
    row(f"{_TF}", "table", "how the load varies in time", default=REQUIRED, variants=("dynamic",)),
    row(f"{_TF}.type", "string", "`table`: linear between points; `file`: the same from a text file; `pulse`; "
       "`harmonic`: sin(2 pi f s + phase)", default=REQUIRED, choices=TIME_FUNCTIONS, variants=TIME_FUNCTIONS),
    row(f"{_TF}.time", "list", "times, strictly increasing (plain numbers)", "s", default=REQUIRED,
       variants=("table",)),
    row(f"{_TF}.values", "list", "values at those times (the end values hold outside)", default=REQUIRED,
       variants=("table",)),
    row(f"{_TF}.path", "string", "a text file of columns, time (s) first, relative to the scene file's folder",
       default=REQUIRED, variants=("file",)),
    row(f"{_TF}.column", "integer", "the value column, from 0 without the time column", default=0, variants=("file",)),
    row(f"{_TF}.shape", "string", "1 (rectangular), a half sine or a symmetric triangle of peak 1 over `duration`",
       default="rectangular", choices=PULSE_SHAPES, variants=("pulse",)),
    row(f"{_TF}.duration", "number", "pulse length; harmonic: length of the shaking (default: to the end)", "s",
       TIME, default_text="required (pulse)", variants=("pulse", "harmonic")),
    row(f"{_TF}.start", "number", "when it starts", "s", TIME, default=0, variants=("pulse", "harmonic")),
    row(f"{_TF}.frequency", "number", "frequency", "Hz", default=REQUIRED, variants=("harmonic",)),
    row(f"{_TF}.phase", "number", "phase", "deg", default=0.0, variants=("harmonic",)),
), "type")


def _effects():
    return [Effect("dynamic_loads", "a dynamic stage's 'loads' with a 'time_function'", __name__,
                   "consistent nodal forces scaled in time; closed forms of Chopra (2012), Dynamics of Structures, "
                   "eqs. 3.1.6 and 4.3.2", "tests/effects/test_dynamic_loads.py", _describe, activate=_activate,
                   dynamic_stage=_add_loads_in_time, dynamic_loads=normalize_dynamic_load, scene_keys=(_TIME_LOADS,),
                   scene_keys_place="dynamic_stage")]


EFFECTS = _effects()
