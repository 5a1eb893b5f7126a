"""Checked scene values: each helper converts one value of a scene (or of a scene fragment that an
effect owns, :mod:`masonrydam.effects`) and raises :class:`~masonrydam.errors.SceneError` naming its
dotted key when the value is wrong. Quantities go to SI through :mod:`masonrydam.units`."""
from __future__ import annotations

import difflib
import os
from pathlib import Path

from .errors import OutputError, SceneError
from .units import finite, plausible, quantity

COMPONENT_NAMES = ("x", "y", "z")


def check_keys(d: dict, allowed, where: str):
    if not isinstance(d, dict):
        raise SceneError(where, f"expected a table, got {type(d).__name__}")
    for k in d:
        if k not in allowed:
            close = difflib.get_close_matches(k, list(allowed), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else f"; known keys: {', '.join(sorted(allowed))}"
            raise SceneError(f"{where}.{k}" if where else k, f"unknown key{hint}")


def choice(value, options, key):
    if value not in options:
        raise SceneError(key, f"must be one of {list(options)}, got {value!r}")
    return value


def integer(value, key, minimum=None, maximum=None, why=""):
    """An integer scene value in ``[minimum, maximum]`` (None: unbounded); ``why`` says what the maximum guards."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise SceneError(key, f"expected an integer, got {value!r}")
    if minimum is not None and value < minimum:
        raise SceneError(key, f"must be >= {minimum}, got {value}")
    if maximum is not None and value > maximum:
        raise SceneError(key, f"must be <= {maximum:.0e}, got {value}" + (f": {why}" if why else ""))
    return value


def boolean(value, key):
    if not isinstance(value, bool):
        raise SceneError(key, f"expected true or false, got {value!r}")
    return value


def positive(value, dimension, key, allow_zero=False):
    v = quantity(value, dimension, key)  # finite, and in the plausible range of the key
    if v < 0 if allow_zero else v <= 0:
        raise SceneError(key, f"must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    return v


def vector(value, dimension, key, dim):
    if not isinstance(value, (list, tuple)) or len(value) != dim:
        raise SceneError(key, f"expected a list of {dim} values, got {value!r}")
    return [quantity(v, dimension, f"{key}[{i}]") for i, v in enumerate(value)]


def components(value, key, dim):
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, (list, tuple)) or not value:
        raise SceneError(key, f"expected a list of components from {COMPONENT_NAMES[:dim]}, got {value!r}")
    for c in value:
        if c not in COMPONENT_NAMES[:dim]:
            raise SceneError(key, f"unknown component {c!r}; use {list(COMPONENT_NAMES[:dim])}")
    if len(set(value)) != len(value):
        raise SceneError(key, f"repeated component in {value!r}")
    return list(value)


def number(value, key, minimum=None, maximum=None, open_min=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(key, f"expected a number, got {value!r}")
    try:
        v = finite(float(value), key, value)
    except OverflowError:
        raise SceneError(key, "the integer given is too large for a number") from None
    if minimum is not None and (v <= minimum if open_min else v < minimum):
        raise SceneError(key, f"must be {'>' if open_min else '>='} {minimum:g}, got {value!r}")
    if maximum is not None and v > maximum:
        raise SceneError(key, f"must be <= {maximum:g}, got {value!r}")
    return v


def seconds(value, key, allow_zero=False):
    """A time in s (plain number, or a string '<number> s' / '<number> ms'); finite, > 0 (>= 0 with
    ``allow_zero``: a start time, a relaxation time that may be off) and, for a time step, in the
    plausible range of units.PLAUSIBLE."""
    given = value
    if isinstance(value, str):
        parts = value.split()
        factor = {"s": 1.0, "ms": 1e-3}.get(parts[-1]) if len(parts) == 2 else None
        if factor is None:
            raise SceneError(key, f"cannot read {value!r} as a time; write a number of seconds or e.g. '10 ms'")
        try:
            value = float(parts[0]) * factor
        except ValueError:
            raise SceneError(key, f"cannot read {value!r} as a time") from None
    return plausible(number(value, key, 0.0, open_min=not allow_zero), "time", key, given)


def check_output_path(path, option: str = "-o") -> Path:
    """``path`` as a :class:`~pathlib.Path` once it is known that a file can be written there: it is
    not a folder, and its folder exists and is writable. The error names ``option`` (the CLI option or
    the argument that gave the path). Nothing is created."""
    p = Path(path)
    if p.is_dir():
        raise OutputError(f"{option} {str(p)!r} is a folder; give a file path")
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.exists():
        raise OutputError(f"{option} {str(p)!r}: the folder {str(folder)!r} does not exist; create it first")
    if not folder.is_dir():
        raise OutputError(f"{option} {str(p)!r}: {str(folder)!r} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):  # results are written beside the target, then renamed
        raise OutputError(f"{option} {str(p)!r}: the folder {str(folder)!r} is not writable")
    return p
