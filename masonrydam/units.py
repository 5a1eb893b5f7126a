"""Reading quantities with units from a scene.

A scene value is either a plain number, taken as SI, or a string ``"<number> <unit>"`` such as
``"16.7 GPa"``, ``"82 N/mm3"`` or ``"10 mm"``; the unit must have the dimension the key expects.
A value must be finite (TOML's ``nan`` and ``inf`` are errors), and the keys of :data:`PLAUSIBLE`
must lie in a plausible range for masonry, concrete, rock and steel structures, so that a unit
slip (MPa typed as Pa, N/mm3 as N/m3, ms as s, ...) is an error that names the key.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from fnmatch import fnmatchcase

import numpy as np

from .errors import SceneError

# unit -> (dimension, factor to SI)
UNITS = {
    "Pa": ("stress", 1.0), "kPa": ("stress", 1e3), "MPa": ("stress", 1e6), "GPa": ("stress", 1e9),
    "N/m2": ("stress", 1.0), "N/mm2": ("stress", 1e6), "kN/m2": ("stress", 1e3),
    "N/m3": ("stiffness", 1.0), "kN/m3": ("stiffness", 1e3), "MN/m3": ("stiffness", 1e6),
    "GN/m3": ("stiffness", 1e9), "N/mm3": ("stiffness", 1e9), "MPa/m": ("stiffness", 1e6),
    "MPa/mm": ("stiffness", 1e9), "GPa/m": ("stiffness", 1e9),
    "m": ("length", 1.0), "cm": ("length", 1e-2), "mm": ("length", 1e-3),
    "kg/m3": ("density", 1.0), "t/m3": ("density", 1e3), "g/cm3": ("density", 1e3),
    "N": ("force", 1.0), "kN": ("force", 1e3), "MN": ("force", 1e6),
    "deg": ("angle", 1.0), "degree": ("angle", 1.0), "degrees": ("angle", 1.0),
    "m/s2": ("acceleration", 1.0), "g": ("acceleration", 9.80665),
    "N/m": ("fracture_energy", 1.0), "J/m2": ("fracture_energy", 1.0), "N/mm": ("fracture_energy", 1e3),
}
SI_UNIT = {"stress": "Pa", "stiffness": "N/m3", "length": "m", "density": "kg/m3", "force": "N",
           "angle": "deg", "acceleration": "m/s2", "time": "s", "fracture_energy": "N/m"}
NUMBER_WITH_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/0-9.]+)?\s*$")


@dataclass(frozen=True)
class Plausible:
    """Plausible range of a physical key: ``low <= value`` (positive values; zero and negative values are
    left to the key's own sign check) and ``|value| <= high``, in SI; None: no bound. ``what`` names the
    quantity; the hints say which unit slip most likely gave a plain number outside (``{v:g}``: the
    number); for a value written with a unit, :data:`UNIT_HINT` is given instead."""

    what: str
    dimension: str
    low: float | None = None
    high: float | None = None
    low_hint: str = ""
    high_hint: str = ""


#: hint for a value written with a unit that is out of range (e.g. '82e9 N/mm3' for '82 N/mm3')
UNIT_HINT = "does the number go with the unit written (not a number for a smaller unit, or in SI)?"
_JOINT_STIFFNESS = Plausible(
    "a joint stiffness", "stiffness", 1e6, 1e17,
    "joint stiffnesses of masonry, concrete and rock are about 1e9-1e13 N/m3 (1-10000 N/mm3): did you give "
    "N/mm3 (or MPa/mm, GPa/m) as N/m3? write e.g. '{v:g} N/mm3'",
    "joint stiffnesses of masonry, concrete and rock are about 1e9-1e13 N/m3: is the value in another unit?")
_STRENGTH = Plausible(
    "a joint strength", "stress", None, 1e9, "",
    "joint cohesion and tensile strength are kPa to a few MPa (1e3-1e7 Pa): is the value in another unit?")
_LENGTH = Plausible("a length", "length", None, 1e4, "", "did you give mm as m? write e.g. '{v:g} mm'")
_GROUND_ACCELERATION = Plausible(
    "a ground acceleration", "acceleration", None, 100.0, "",
    "did you give cm/s2 (gal) or mm/s2 as m/s2? write m/s2, or g as e.g. '0.3 g'")
_TIME_STEP = Plausible(
    "a time step", "time", 1e-9, 1.0,
    "steps below a nanosecond would take more than a billion steps a second of motion: is the value in another unit?",
    "seismic records and analyses use 0.0001-0.05 s: did you give milliseconds as seconds? write e.g. '{v:g} ms'")

#: Plausibility ranges of the physical scene keys (the one table of them), by dotted key with the list
#: indices removed (``stages[2].ground_motion.x.dt`` is ``stages.ground_motion.x.dt``; ``*`` matches
#: any part). The bounds lie orders of magnitude beyond real masonry, concrete, rock and steel
#: structures (and beyond the "rigid" idealisations in the tests: blocks of 1e14 Pa, joints of 1e15
#: N/m3), so that only a unit slip or a typo falls outside. Applied by :func:`quantity` (and by the
#: schema's time reader) to every key that matches, with the same dimension.
PLAUSIBLE: dict[str, Plausible] = {
    "materials.*.youngs_modulus": Plausible(
        "a Young's modulus of masonry, concrete, rock or steel", "stress", 1e6, 1e15,
        "values are SI (Pa): did you mean '{v:g} MPa'?",
        "masonry and concrete are 1-50 GPa, steel 210 GPa: is the value in another unit?"),
    "materials.*.density": Plausible(
        "a density", "density", 10.0, 1.2e4,  # lead: 11 340 kg/m3
        "did you give t/m3 (or g/cm3) as kg/m3? write e.g. '{v:g} t/m3'",
        "did you give a unit weight in N/m3 (e.g. 18000 for brickwork, 24000 for concrete)? "
        "a density is in kg/m3 (e.g. 1800, 2400)"),
    "joints.*.normal_stiffness": _JOINT_STIFFNESS,
    "joints.*.shear_stiffness": _JOINT_STIFFNESS,
    "joints.*.cohesion": _STRENGTH,
    "joints.*.tensile_strength": _STRENGTH,
    "model.thickness": _LENGTH,
    "mesh.parameters.*": _LENGTH,  # generator lengths (and the openings, polylines, ... inside them)
    "model.gravity": Plausible(
        "a gravity component", "acceleration", None, 100.0, "",
        "did you give cm/s2 (gal) or mm/s2 as m/s2? standard gravity is 9.80665 m/s2 (or write '1 g')"),
    "stages.ground_motion.*.pulse.amplitude": _GROUND_ACCELERATION,
    "stages.ground_motion.*.scale_to_pga": _GROUND_ACCELERATION,
    "stages.ground_motion.*.scale_to_sa.sa": _GROUND_ACCELERATION,
    "reservoir.density": Plausible(
        "the density of water", "density", 500.0, 3000.0,
        "did you give t/m3 (or g/cm3) as kg/m3? write e.g. '{v:g} t/m3'",
        "did you give a unit weight in N/m3 (9810 for water)? a density is in kg/m3 (1000 for water)"),
    "reservoir.silt.submerged_density": Plausible(
        "a submerged density of silt", "density", 10.0, 1.2e4,
        "did you give t/m3 (or g/cm3) as kg/m3? write e.g. '{v:g} t/m3'",
        "did you give a unit weight in N/m3? a density is in kg/m3 (submerged silt about 900-1200)"),
    "reservoir.level": _LENGTH,
    "reservoir.*.level": _LENGTH,
    "reservoir.uplift.drains.distance": _LENGTH,
    "stages.loads.level": _LENGTH,
    "stages.dt": _TIME_STEP,  # analysis time step of a dynamic stage
    "stages.dt_max": _TIME_STEP,  # dt = "auto": largest and smallest step
    "stages.dt_min": _TIME_STEP,
    "stages.output.dt": _TIME_STEP,  # output grid of a dynamic stage
    "stages.ground_motion.*.dt": _TIME_STEP,  # time step of a record (and of its resampling)
}
_INDEX = re.compile(r"\[\d+\]")


def _is_plain_number(text: str) -> bool:
    m = NUMBER_WITH_UNIT.match(text)
    return m is not None and m.group(2) is None


def plausible(v: float, dimension: str, key: str, given=None) -> float:
    """``v`` (SI) if it lies in the :data:`PLAUSIBLE` range of ``key`` (or ``key`` has none); else a
    SceneError naming ``key`` and the likely unit slip. ``given``: the value as written, for the message."""
    name = _INDEX.sub("", key)
    for pattern, rng in PLAUSIBLE.items():
        if rng.dimension != dimension or not fnmatchcase(name, pattern):
            continue
        unit, with_unit = SI_UNIT[dimension], isinstance(given, str) and not _is_plain_number(given)
        shown = f"{given!r} = {v:g} {unit}" if with_unit else f"{v:g} {unit}"
        if rng.low is not None and 0.0 < v < rng.low:
            hint = UNIT_HINT if with_unit else rng.low_hint.format(v=v)
            raise SceneError(key, f"{shown} is implausibly small for {rng.what} (plausible from {rng.low:g} "
                                  f"{unit}); {hint}")
        if rng.high is not None and abs(v) > rng.high:
            hint = UNIT_HINT if with_unit else rng.high_hint.format(v=v)
            raise SceneError(key, f"{shown} is implausibly large for {rng.what} (plausible up to {rng.high:g} "
                                  f"{unit}); {hint}")
        break
    return v


def finite(v: float, key: str, given) -> float:
    """``v`` if it is a finite number, else a SceneError naming ``key`` (``given``: the value as written)."""
    if not math.isfinite(v):
        raise SceneError(key, f"must be a finite number, got {given!r}")
    return v


def quantity(value, dimension: str, key: str) -> float:
    """Convert ``value`` (number or 'number unit' string) to SI for ``dimension``; errors name ``key``.
    The result is finite and, for the keys of :data:`PLAUSIBLE`, in the plausible range."""
    if isinstance(value, np.generic):  # (a NumPy scalar from a generator called from Python)
        value = value.item()
    if isinstance(value, bool):
        raise SceneError(key, f"expected a number in {SI_UNIT[dimension]}, got {value!r}")
    if isinstance(value, (int, float)):
        try:
            v = float(value)
        except OverflowError:
            raise SceneError(key, f"the integer given is too large for a number in {SI_UNIT[dimension]}") from None
    elif isinstance(value, str):
        m = NUMBER_WITH_UNIT.match(value)
        if not m:
            raise SceneError(key, f"cannot read {value!r} as a quantity; write a number (SI, {SI_UNIT[dimension]}) "
                                  f"or e.g. '10 {SI_UNIT[dimension]}'")
        v, unit = float(m.group(1)), m.group(2)
        if unit is not None:
            if unit not in UNITS:
                raise SceneError(key, f"unknown unit {unit!r} in {value!r}")
            dim, factor = UNITS[unit]
            if dim != dimension:
                raise SceneError(key, f"unit {unit!r} is a {dim}, but this key expects a {dimension} "
                                      f"({SI_UNIT[dimension]})")
            v = v * factor
    else:
        raise SceneError(key, f"expected a number in {SI_UNIT[dimension]}, got {type(value).__name__} {value!r}")
    return plausible(finite(v, key, value), dimension, key, value)
