"""Reading quantities with units from a scene.

A scene value is either a plain number, taken as SI, or a string ``"<number> <unit>"`` such as
``"16.7 GPa"``, ``"82 N/mm3"`` or ``"10 mm"``; the unit must have the dimension the key expects.
"""
from __future__ import annotations

import re

from ..errors import SceneError

# unit -> (dimension, factor to SI)
_UNITS = {
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
}
SI_UNIT = {"stress": "Pa", "stiffness": "N/m3", "length": "m", "density": "kg/m3", "force": "N",
           "angle": "deg", "acceleration": "m/s2"}
_NUM = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/0-9.]+)?\s*$")


def quantity(value, dimension: str, key: str) -> float:
    """Convert ``value`` (number or 'number unit' string) to SI for ``dimension``; errors name ``key``."""
    if isinstance(value, bool):
        raise SceneError(key, f"expected a number in {SI_UNIT[dimension]}, got {value!r}")
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str):
        m = _NUM.match(value)
        if not m:
            raise SceneError(key, f"cannot read {value!r} as a quantity; write a number (SI, {SI_UNIT[dimension]}) "
                                  f"or e.g. '10 {SI_UNIT[dimension]}'")
        number, unit = float(m.group(1)), m.group(2)
        if unit is None:
            return number
        if unit not in _UNITS:
            raise SceneError(key, f"unknown unit {unit!r} in {value!r}")
        dim, factor = _UNITS[unit]
        if dim != dimension:
            raise SceneError(key, f"unit {unit!r} is a {dim}, but this key expects a {dimension} "
                                  f"({SI_UNIT[dimension]})")
        return number * factor
    raise SceneError(key, f"expected a number in {SI_UNIT[dimension]}, got {type(value).__name__} {value!r}")
