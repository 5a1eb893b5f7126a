"""Reading ground-motion records into obspy objects in SI units.

:func:`read_record` returns an :class:`obspy.Stream` whose traces hold float64 data in m/s2
(acceleration; m/s for velocity and m for displacement records read with ``quantity=``) and a
``stats.masonrydam`` dictionary with the metadata found in the file and the provenance list that
the processing steps of :mod:`masonrydam.records.processing` extend.

Supported inputs:

- PEER strong-motion files (``.AT2``, and ``.VT2``/``.DT2`` for velocity/displacement): the old
  PEER / Pacific Engineering layout (4 header lines ending in ``NPTS=  4000, DT= .01000 SEC``), the
  NGA-West2 layout (``NPTS=   5372, DT=   .0100 SEC,``), the 7-line "Peknold version" of El Centro
  distributed with OpenSees (``*** Begin data ***``, ``*** End Data ***``), and the NGA layout with a
  ``<npts> <dt> NPTS, DT`` line. The quantity and the units are taken from the header ("ACCELERATION
  ... IN UNITS OF G", "The units are (g)", "DISPLACEMENT ... IN UNITS OF CM").
- anything :func:`obspy.read` recognises (SAC, MiniSEED, GSE2, ...), detected by obspy itself. These
  formats do not carry trustworthy physical units, so ``units=`` is required.
- plain text with one column (values; ``dt=`` required) or two columns (time, value; the time step
  is taken from the time column, which must be uniformly spaced). ``units=`` is required. Lines
  starting with ``#`` are comments and may declare ``units: g`` and ``dt: 0.01``.

A file whose format, quantity, units or time step cannot be determined raises :class:`RecordError`
with what was found; nothing is guessed.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import obspy
from obspy.core.util import AttribDict

from .errors import RecordError

G = 9.80665  # standard gravity, m/s2 (used to convert records in units of g)

# quantity -> {canonical unit: factor to SI}
UNITS = {
    "acceleration": {"g": G, "m/s2": 1.0, "cm/s2": 1e-2, "gal": 1e-2, "mm/s2": 1e-3},
    "velocity": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3},
    "displacement": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
}
SI_UNITS = {"acceleration": "m/s2", "velocity": "m/s", "displacement": "m"}
QUANTITIES = tuple(UNITS)

_PEER_EXT = {".at2": "acceleration", ".vt2": "velocity", ".dt2": "displacement"}
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?")
_NPTS_EQ = re.compile(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[Ee][-+]?\d+)?)", re.I)
_NPTS_COLS = re.compile(r"^\s*(\d+)\s+([-+]?(?:\d+\.?\d*|\.\d+)(?:[Ee][-+]?\d+)?)\s+NPTS\s*,\s*DT\b", re.I)
_UNITS_IN_HEADER = re.compile(r"UNITS\s+(?:OF|ARE|IN)\s*:?\s*\(?\s*([A-Za-z][A-Za-z0-9/*^]*)", re.I)
_QUANTITY_IN_HEADER = re.compile(r"\b(ACCELERATION|VELOCITY|DISPLACEMENT)\b", re.I)
_DECLARATION = re.compile(r"^\s*(units?|dt|time[ _]?step)\s*[:=]\s*(\S+)", re.I)
_OLD_PEER_EVENT = re.compile(
    r"^(?P<event>.+?)\s+(?P<date>\d{1,2}/\d{1,2}/\d{2,4})(?:\s+(?P<time>\d{3,4}))?\s*,\s*(?P<station>.+?)\s*,"
    r"\s*(?P<component>\S+)\s*(?P<note>.*)$")
_MAX_HEADER_LINES = 40


# ----------------------------------------------------------------------------------------------
# units
# ----------------------------------------------------------------------------------------------

def _canonical_unit_text(text: str) -> str:
    u = text.strip().strip("()[]").lower().replace(" ", "")
    u = u.replace("²", "2").replace("**2", "2").replace("^2", "2")
    u = u.replace("/sec/sec", "/s2").replace("/s/s", "/s2").replace("/sec2", "/s2").replace("/sec", "/s")
    u = u.replace("sec", "s")
    if u in ("gals", "galileo"):
        u = "gal"
    return u


def parse_units(text: str, what: str = "units") -> tuple[str, str, float]:
    """``(quantity, canonical unit, factor to SI)`` for a unit string such as ``'g'``, ``'cm/s2'``,
    ``'gal'``, ``'CM/SEC/SEC'`` or ``'cm'``; :class:`RecordError` for anything else."""
    if not isinstance(text, str) or not text.strip():
        raise RecordError(f"{what}: expected a unit string, got {text!r}")
    u = _canonical_unit_text(text)
    for quantity, table in UNITS.items():
        if u in table:
            return quantity, u, table[u]
    known = "; ".join(f"{q}: {', '.join(t)}" for q, t in UNITS.items())
    raise RecordError(f"{what}: unknown unit {text!r} (known units - {known})")


# ----------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------

def _new_stats_meta(**kw) -> AttribDict:
    meta = AttribDict()
    meta.update(kw)
    meta.setdefault("provenance", [])
    return meta


def _show(lines, n=6) -> str:
    shown = [ln.rstrip()[:100] for ln in lines[:n]]
    return "\n".join(f"    | {ln}" for ln in shown) if shown else "    (empty file)"


def _check_dt(dt, what="dt") -> float:
    try:
        dtf = float(dt)
    except (TypeError, ValueError):
        raise RecordError(f"{what}: expected a positive time step in seconds, got {dt!r}") from None
    if not np.isfinite(dtf) or dtf <= 0.0:
        raise RecordError(f"{what}: expected a positive time step in seconds, got {dt!r}")
    return dtf


def _same_dt(a: float, b: float, rtol: float = 1e-6) -> bool:
    return abs(a - b) <= rtol * max(abs(a), abs(b))


def _resolve_units(found: str | None, found_where: str, given: str | None, path: Path,
                   context: str) -> tuple[str, str, float, str]:
    """Combine the units found in the file with the ``units=`` argument. Returns
    ``(quantity, unit, factor, source)``."""
    if found is None and given is None:
        raise RecordError(f"{path}: the physical units are not stated in the file; pass units= (acceleration: "
                          f"g, m/s2, cm/s2, gal, mm/s2). Found: {context}")
    if found is not None:
        qf, uf, ff = parse_units(found, f"{path}: units in {found_where}")
        if given is not None:
            qg, ug, fg = parse_units(given, "units argument")
            if (qg, fg) != (qf, ff):
                raise RecordError(f"{path}: units={given!r} ({qg}) contradicts the {found_where}, which "
                                  f"says {found!r} ({qf})")
        return qf, uf, ff, found_where
    qg, ug, fg = parse_units(given, "units argument")
    return qg, ug, fg, "argument"


def _check_quantity(path: Path, found_quantity: str, requested: str, evidence: str):
    if found_quantity != requested:
        hint = ""
        if requested == "acceleration":
            hint = (f"; it cannot be used as an acceleration. Read it with quantity='{found_quantity}' "
                    f"(returned in {SI_UNITS[found_quantity]}), or use an acceleration record (for PEER data, "
                    f"the matching .AT2 file)")
        raise RecordError(f"{path}: this is a {found_quantity} record ({evidence}), "
                          f"not {'an' if requested[0] in 'aeiou' else 'a'} {requested} record{hint}")


def _make_trace(data: np.ndarray, dt: float, meta: AttribDict) -> obspy.Trace:
    tr = obspy.Trace(data=np.ascontiguousarray(data, dtype=np.float64))
    tr.stats.delta = dt
    tr.stats.masonrydam = meta
    return tr


# ----------------------------------------------------------------------------------------------
# PEER AT2 / VT2 / DT2
# ----------------------------------------------------------------------------------------------

def _find_npts_line(lines):
    """Index, npts, dt and layout of the PEER ``NPTS``/``DT`` line among the first lines, or None."""
    for i, line in enumerate(lines[:_MAX_HEADER_LINES]):
        m = _NPTS_EQ.search(line)
        if m:
            return i, int(m.group(1)), m.group(2), "npts="
        m = _NPTS_COLS.match(line)
        if m:
            return i, int(m.group(1)), m.group(2), "npts-dt-columns"
    return None


def _peer_variant(header, layout) -> str:
    text = "\n".join(header).upper()
    if layout == "npts-dt-columns":
        return "PEER NGA (<npts> <dt> NPTS, DT line)"
    if "BEGIN DATA" in text:
        return "PEER AT2, Peknold version (OpenSees)"
    if "PEER NGA" in text:
        return "PEER NGA-West2"
    if "PEER STRONG MOTION" in text or "PACIFIC ENGINEERING" in text:
        return "PEER old (Pacific Engineering)"
    return "PEER-style (NPTS/DT line)"


def _peer_event_metadata(header) -> dict:
    """Event, date, station and component from the second header line, where the layout is known."""
    if len(header) < 2:
        return {}
    line = header[1].strip()
    parts = [p.strip() for p in line.split(",")]
    if len(parts) == 4 and re.fullmatch(r"\d{1,2}/\d{1,2}/\d{2,4}", parts[1]):  # NGA-West2
        return {"event": parts[0], "date": parts[1], "station": parts[2], "component": parts[3]}
    m = _OLD_PEER_EVENT.match(line)  # old PEER / Pacific Engineering
    if m:
        out = {"event": m.group("event"), "date": m.group("date"), "station": m.group("station"),
               "component": m.group("component")}
        if m.group("time"):
            out["time"] = m.group("time")
        if m.group("note").strip():
            out["station"] = f"{out['station']} {m.group('note').strip()}"
        return out
    return {}


def _read_peer(path: Path, lines, found, units, dt, quantity) -> obspy.Stream:
    i_npts, npts, dt_text, layout = found
    header = [ln.rstrip() for ln in lines[: i_npts + 1] if ln.strip()]
    dt_file = _check_dt(dt_text, f"{path}: DT in header line {i_npts + 1}")
    if dt is not None and not _same_dt(_check_dt(dt), dt_file):
        raise RecordError(f"{path}: dt={dt} contradicts the header line {i_npts + 1} "
                          f"{lines[i_npts].strip()!r}")
    head_text = "\n".join(header[:-1]) + "\n" + lines[i_npts]
    # quantity: keyword in the header, units in the header, file extension; all must agree
    kws = {m.group(1).lower() for m in _QUANTITY_IN_HEADER.finditer(head_text)}
    if len(kws) > 1:
        raise RecordError(f"{path}: the header names several quantities ({', '.join(sorted(kws))}):\n"
                          f"{_show(header)}")
    m_units = _UNITS_IN_HEADER.search(head_text)
    found_units = m_units.group(1) if m_units else None
    q_units, unit, factor, units_source = _resolve_units(
        found_units, "header", units, path, f"PEER header\n{_show(header)}")
    q_header = kws.pop() if kws else None
    if q_header is not None and q_header != q_units:
        raise RecordError(f"{path}: the header names a {q_header} record but its units {unit!r} are a "
                          f"{q_units}:\n{_show(header)}")
    q_file = q_header or q_units
    if q_header:
        kw_line = next(ln for ln in header if re.search(q_header, ln, re.I))
        evidence = f"header: {kw_line.strip()!r}"
    else:
        evidence = f"units {unit!r}"
    q_ext = _PEER_EXT.get(path.suffix.lower())
    if q_ext is not None and q_ext != q_file:
        raise RecordError(f"{path}: the file extension {path.suffix!r} means {q_ext}, but the header "
                          f"describes a {q_file} record:\n{_show(header)}")
    _check_quantity(path, q_file, quantity, evidence)

    values = []
    end_marker = None
    for j in range(i_npts + 1, len(lines)):
        line = lines[j]
        s = line.strip()
        if not s:
            continue
        if s.startswith("*") or not any(c.isdigit() for c in s):
            end_marker = s
            rest = [ln for ln in lines[j + 1:] if ln.strip()]
            if rest:
                raise RecordError(f"{path}: line {j + 1} {s!r} ends the data, but {len(rest)} more "
                                  f"non-empty line(s) follow (first: {rest[0].strip()[:60]!r})")
            break
        nums = _NUMBER.findall(s)
        if _NUMBER.sub("", s).strip():
            raise RecordError(f"{path}: line {j + 1} of the data is not a list of numbers: {s[:80]!r}")
        values.extend(nums)
    if len(values) != npts:
        raise RecordError(f"{path}: header line {i_npts + 1} says NPTS={npts}, but {len(values)} values "
                          f"follow it")
    data = np.array([float(v.replace("D", "E").replace("d", "e")) for v in values], dtype=np.float64)
    meta = _new_stats_meta(
        source_file=str(path), format="PEER", format_variant=_peer_variant(header, layout),
        header_lines=header, quantity=q_file, original_units=unit, units=SI_UNITS[q_file],
        unit_factor=factor, units_from=units_source, npts_header=npts, dt_header=dt_file)
    if end_marker:
        meta.end_marker = end_marker
    meta.update(_peer_event_metadata(header))
    meta.provenance.append({
        "step": "read", "function": "masonrydam.records.readers.read_record",
        "parameters": {"file": str(path), "format": meta.format_variant, "original_units": unit,
                       "factor_to_si": factor, "npts": npts, "dt": dt_file}})
    return obspy.Stream([_make_trace(data * factor, dt_file, meta)])


# ----------------------------------------------------------------------------------------------
# plain text
# ----------------------------------------------------------------------------------------------

def _read_text(path: Path, lines, units, dt, quantity) -> obspy.Stream:
    declared = {}
    comments = []
    rows = []
    first_rows = []
    ncol = None
    for j, line in enumerate(lines):
        s = line.strip()
        if not s:
            continue
        if s[0] in "#%!":
            comments.append(s)
            m = _DECLARATION.match(s.lstrip("#%! "))
            if m:
                key = "dt" if m.group(1).lower() in ("dt", "timestep", "time_step", "time step") else "units"
                declared[key] = m.group(2)
            continue
        fields = [f for f in re.split(r"[\s,;]+", s) if f]
        try:
            row = [float(f) for f in fields]
        except ValueError:
            raise RecordError(
                f"{path}: not a recognised record format: line {j + 1} {s[:80]!r} is neither a comment "
                f"('#') nor a row of numbers. First lines:\n{_show(lines)}\nKnown formats: PEER AT2 "
                f"(NPTS=/DT= header), obspy formats (SAC, MiniSEED, ...), plain text with 1 column "
                f"(values) or 2 columns (time, value)") from None
        if ncol is None:
            ncol = len(row)
            if ncol not in (1, 2):
                raise RecordError(f"{path}: plain text with {ncol} columns found (line {j + 1}: {s[:80]!r}); "
                                  f"expected 1 column (values) or 2 columns (time, value)")
        elif len(row) != ncol:
            raise RecordError(f"{path}: line {j + 1} has {len(row)} columns, the first data line has {ncol}")
        rows.append(row)
        if len(first_rows) < 3:
            first_rows.append(s)
    if ncol is None or len(rows) < 2:
        raise RecordError(f"{path}: no record found (fewer than 2 data rows). First lines:\n{_show(lines)}")
    arr = np.asarray(rows, dtype=np.float64)
    found = f"plain text with {ncol} column(s), {len(rows)} rows"

    # units: from a '# units:' declaration or the argument, never guessed
    q_units, unit, factor, units_source = _resolve_units(
        declared.get("units"), "'# units:' declaration", units, path, found)
    _check_quantity(path, q_units, quantity, f"units {unit!r}")

    dt_decl = _check_dt(declared["dt"], f"{path}: '# dt:' declaration") if "dt" in declared else None
    dt_arg = _check_dt(dt) if dt is not None else None
    if dt_decl is not None and dt_arg is not None and not _same_dt(dt_decl, dt_arg):
        raise RecordError(f"{path}: dt={dt} contradicts the file's declaration dt: {declared['dt']}")
    dt_given = dt_arg if dt_arg is not None else dt_decl
    t0 = 0.0
    if ncol == 1:
        if dt_given is None:
            raise RecordError(f"{path}: {found}; the time step is not stated: pass dt= (seconds) or add a "
                              f"'# dt: <seconds>' line")
        values, dt_final, dt_source = arr[:, 0], dt_given, ("argument" if dt_arg is not None else "declaration")
    else:
        t, values = arr[:, 0], arr[:, 1]
        steps = np.diff(t)
        if np.any(steps <= 0):
            k = int(np.argmax(steps <= 0))
            raise RecordError(f"{path}: {found}; the time column is not increasing at row {k + 2} "
                              f"(t = {t[k]!r} then {t[k + 1]!r})")
        dt_col = (t[-1] - t[0]) / (len(t) - 1)
        dev = np.abs(steps - dt_col)
        if dev.max() > 1e-3 * dt_col:
            k = int(np.argmax(dev))
            raise RecordError(
                f"{path}: {found}; the time column is not uniformly spaced: mean step {dt_col:.6g} s but "
                f"step {steps[k]:.6g} s between rows {k + 1} and {k + 2} (t = {t[k]!r}, {t[k + 1]!r}); "
                f"resample the record to a constant time step first")
        if dt_given is not None and abs(dt_given - dt_col) > 1e-3 * dt_col:
            raise RecordError(f"{path}: dt={dt_given} contradicts the time column (step {dt_col:.6g} s)")
        dt_final = dt_given if dt_given is not None else float(dt_col)
        dt_source = "time column"
        t0 = float(t[0])
    meta = _new_stats_meta(
        source_file=str(path), format="TEXT", format_variant=f"plain text, {ncol} column(s)",
        header_lines=comments[:20], quantity=q_units, original_units=unit, units=SI_UNITS[q_units],
        unit_factor=factor, units_from=units_source, dt_from=dt_source, time_start=t0)
    meta.provenance.append({
        "step": "read", "function": "masonrydam.records.readers.read_record",
        "parameters": {"file": str(path), "format": meta.format_variant, "original_units": unit,
                       "factor_to_si": factor, "npts": len(values), "dt": dt_final}})
    return obspy.Stream([_make_trace(values * factor, dt_final, meta)])


# ----------------------------------------------------------------------------------------------
# obspy formats
# ----------------------------------------------------------------------------------------------

def _read_obspy(path: Path, st: obspy.Stream, fmt: str | None, units, dt, quantity) -> obspy.Stream:
    formats = sorted({getattr(tr.stats, "_format", fmt or "?") for tr in st})
    found = (f"obspy format {'/'.join(formats)}, {len(st)} trace(s): "
             + "; ".join(f"{tr.id} npts={tr.stats.npts} delta={tr.stats.delta:g}" for tr in st[:4]))
    if units is None:
        hints = []
        for tr in st[:1]:
            sac = tr.stats.get("sac")
            if sac is not None and "idep" in sac:
                hints.append(f"SAC header idep={sac['idep']}")
        hint = f" ({', '.join(hints)})" if hints else ""
        raise RecordError(f"{path}: {found}; this format does not state physical units that masonrydam "
                          f"can rely on{hint}: pass units= (acceleration: g, m/s2, cm/s2, gal, mm/s2)")
    q, unit, factor = parse_units(units, "units argument")
    _check_quantity(path, q, quantity, f"units {unit!r}")
    out = obspy.Stream()
    for tr in st:
        if dt is not None and not _same_dt(_check_dt(dt), tr.stats.delta):
            raise RecordError(f"{path}: dt={dt} contradicts the file ({tr.id}: delta={tr.stats.delta})")
        new = tr.copy()
        new.data = np.asarray(tr.data, dtype=np.float64) * factor
        fmt_name = getattr(tr.stats, "_format", fmt)
        meta = _new_stats_meta(
            source_file=str(path), format=str(fmt_name), format_variant=str(fmt_name), header_lines=[],
            quantity=q, original_units=unit, units=SI_UNITS[q], unit_factor=factor, units_from="argument",
            trace_id=tr.id, starttime=str(tr.stats.starttime))
        if tr.stats.station:
            meta.station = tr.stats.station
        if tr.stats.channel:
            meta.component = tr.stats.channel
        meta.provenance.append({
            "step": "read", "function": "obspy.read",
            "parameters": {"file": str(path), "format": str(fmt_name), "original_units": unit,
                           "factor_to_si": factor, "npts": int(tr.stats.npts), "dt": float(tr.stats.delta),
                           "obspy_version": obspy.__version__}})
        new.stats.masonrydam = meta
        out.append(new)
    return out


# ----------------------------------------------------------------------------------------------
# entry point
# ----------------------------------------------------------------------------------------------

_PEER_NAMES = {"at2", "vt2", "dt2", "peer"}
_TEXT_NAMES = {"text", "txt", "ascii", "csv", "dat"}


def _text_lines(raw: bytes):
    if b"\x00" in raw[:4096]:
        return None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.splitlines()


def read_record(path, *, format: str | None = None, units: str | None = None, dt: float | None = None,
                quantity: str = "acceleration") -> obspy.Stream:
    """Read a ground-motion record; return an :class:`obspy.Stream` in SI units.

    path: the file. format: ``None`` (detect: PEER header, then obspy's own detection, then plain
    text), ``"AT2"``/``"PEER"``, ``"TEXT"``, or an obspy format name (``"SAC"``, ``"MSEED"``, ...).
    units: units of the values in the file (``g``, ``m/s2``, ``cm/s2``/``gal``, ``mm/s2``; for
    velocity ``m/s``, ``cm/s``, ``mm/s``; for displacement ``m``, ``cm``, ``mm``); required where the
    file does not state them, and checked against the file where it does. dt: time step in s;
    required for one-column text, checked against the file otherwise. quantity: what the caller
    needs (``"acceleration"``, ``"velocity"`` or ``"displacement"``); a record of another quantity
    is an error (e.g. a PEER ``.DT2`` displacement file read as acceleration).

    Each trace has ``stats.delta``, ``stats.npts`` and ``stats.masonrydam`` with ``source_file``,
    ``format``, ``format_variant``, ``header_lines``, ``quantity``, ``original_units``, ``units``
    (the SI unit of the data), ``unit_factor``, where found ``event``, ``date``, ``station``,
    ``component``, and ``provenance`` (a list of dicts, the first one describing the read).
    """
    if quantity not in QUANTITIES:
        raise RecordError(f"quantity must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    path = Path(path)
    if not path.is_file():
        raise RecordError(f"record file not found: {path}")
    raw = path.read_bytes()
    lines = _text_lines(raw)
    fmt = None if format is None else str(format)
    key = None if fmt is None else fmt.lower()

    if key in _PEER_NAMES or key is None:
        found = _find_npts_line(lines) if lines is not None else None
        if found is not None:
            return _read_peer(path, lines, found, units, dt, quantity)
        if key is not None:
            head = _show(lines) if lines is not None else "    (binary file)"
            raise RecordError(f"{path}: format={format!r}, but no 'NPTS=..., DT=...' (or '<npts> <dt> NPTS, "
                              f"DT') line was found in the first {_MAX_HEADER_LINES} lines:\n{head}")
    if key in _TEXT_NAMES:
        if lines is None:
            raise RecordError(f"{path}: format={format!r}, but the file is binary")
        return _read_text(path, lines, units, dt, quantity)

    # obspy formats: explicit name, or obspy's own detection
    try:
        st = obspy.read(str(path), format=None if key is None else fmt.upper())
    except TypeError as exc:
        if key is not None:
            raise RecordError(f"{path}: obspy cannot read it as format {format!r}: {exc}") from None
        st = None
    except Exception as exc:  # noqa: BLE001 - obspy plugins raise many types
        if key is not None:
            raise RecordError(f"{path}: obspy failed to read it as format {format!r}: "
                              f"{type(exc).__name__}: {exc}") from None
        st = None
    if st is not None:
        if len(st) == 0:
            raise RecordError(f"{path}: obspy read the file but found no traces")
        return _read_obspy(path, st, fmt, units, dt, quantity)
    if lines is None:
        raise RecordError(f"{path}: unknown format: a binary file that obspy does not recognise "
                          f"(first bytes {raw[:16]!r}); pass format= with an obspy format name")
    return _read_text(path, lines, units, dt, quantity)


def read_trace(path, **kwargs) -> obspy.Trace:
    """:func:`read_record` for a file holding exactly one trace; returns that :class:`obspy.Trace`."""
    st = read_record(path, **kwargs)
    if len(st) != 1:
        raise RecordError(f"{path}: expected one trace, found {len(st)} ({', '.join(tr.id for tr in st)})")
    return st[0]
