"""The bundled record library: ``records/catalog.toml`` and the record files next to it.

In a source checkout the library is the top-level ``records/`` folder. An installed package (``pip
install .``) carries the same folder as the data-only sub-package ``masonrydam._bundled_records``
(mapped in ``pyproject.toml``), found with :mod:`importlib.resources`.
"""
from __future__ import annotations

import difflib
import functools
from importlib import resources
from pathlib import Path

import tomllib  # Python >= 3.11 (pyproject requires-python)

from .errors import RecordError
from .readers import read_trace

CATALOG_FILE = "catalog.toml"
_REQUIRED = ("file", "quantity", "event", "date", "station", "component", "units", "dt", "npts", "format",
             "source_repository", "source_path", "source_commit")


def _candidates():
    """Places where the library may be, in order: installed data package, editable mapping, checkout."""
    out = []
    try:
        out.append(resources.files("masonrydam") / "_bundled_records")
    except (ModuleNotFoundError, TypeError):  # pragma: no cover
        pass
    try:
        out.append(resources.files("masonrydam._bundled_records"))
    except (ModuleNotFoundError, TypeError):
        pass
    out.append(Path(__file__).resolve().parents[2] / "records")  # masonrydam/records/catalog.py -> the checkout
    return out


@functools.lru_cache(maxsize=1)
def library_dir():
    """The folder (a :class:`pathlib.Path` or an importlib Traversable) holding ``catalog.toml``."""
    tried = []
    for cand in _candidates():
        try:
            if (cand / CATALOG_FILE).is_file():
                return cand
        except OSError:  # pragma: no cover
            pass
        tried.append(str(cand))
    raise RecordError("the bundled record library was not found (looked for catalog.toml in: "
                      + "; ".join(tried) + "); reinstall masonrydam")


@functools.lru_cache(maxsize=1)
def load_catalog() -> dict:
    """``{name: entry}`` from ``catalog.toml``; each entry is a dict of the catalog fields."""
    text = (library_dir() / CATALOG_FILE).read_text(encoding="utf-8")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RecordError(f"the record catalog {CATALOG_FILE} is not valid TOML: {exc}") from None
    for name, entry in data.items():
        if not isinstance(entry, dict):
            raise RecordError(f"{CATALOG_FILE}: '{name}' must be a table")
        missing = [k for k in _REQUIRED if k not in entry]
        if missing:
            raise RecordError(f"{CATALOG_FILE}: record '{name}' lacks {', '.join(missing)}")
    return data


def record_names() -> list[str]:
    return list(load_catalog())


def record_info(name: str) -> dict:
    """The catalog entry of ``name`` (a copy, with ``name`` added); unknown names suggest close matches."""
    cat = load_catalog()
    if name not in cat:
        close = difflib.get_close_matches(name, list(cat), n=3, cutoff=0.5)
        hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
        raise RecordError(f"unknown record {name!r}{hint} (`masonrydam records list` shows the "
                          f"{len(cat)} bundled records)")
    return {"name": name, **cat[name]}


def list_records(quantity: str | None = None) -> list[dict]:
    """Catalog entries (dicts with ``name``), in catalog order; ``quantity`` filters (e.g. "acceleration")."""
    out = [record_info(n) for n in record_names()]
    if quantity is not None:
        out = [e for e in out if e["quantity"] == quantity]
    return out


def record_path(name: str):
    """The file of record ``name`` (a Path, or a Traversable inside an installed package)."""
    return library_dir() / record_info(name)["file"]


def peak_value(entry: dict) -> tuple[float, str]:
    """The catalogued peak of an entry: ``(PGA in g, "g")`` or ``(PGD in cm, "cm")``."""
    if entry["quantity"] == "acceleration":
        return float(entry["pga_g"]), "g"
    return float(entry["pgd_cm"]), "cm"


def load_record(name: str):
    """Read bundled record ``name`` as an :class:`obspy.Trace` in SI units (m/s2 for acceleration).

    The catalog's units are checked against the file header; ``stats.masonrydam`` gets the catalog
    fields (``catalog_name``, ``event``, ``date`` (ISO, UTC), ``station``, ``component``, source
    repository/path/commit, ...), which take precedence over the values parsed from the header.
    """
    info = record_info(name)
    with resources.as_file(library_dir() / info["file"]) as path:
        tr = read_trace(Path(path), units=info["units"], quantity=info["quantity"])
    meta = tr.stats.masonrydam
    meta.source_file = f"{info['file']} (bundled record '{name}')"
    meta.catalog_name = name
    for key in ("event", "date", "station", "component", "source_repository", "source_path",
                "source_commit", "license", "notes"):
        if key in info:
            meta[key] = info[key]
    meta.provenance[0]["parameters"]["file"] = meta.source_file
    meta.provenance[0]["parameters"]["catalog_name"] = name
    return tr


__all__ = ["library_dir", "load_catalog", "record_names", "record_info", "list_records", "record_path",
           "peak_value", "load_record"]
