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
- plain text (whitespace, tab, comma or semicolon separated; see :func:`read_record`): leading lines
  that are not rows of numbers are a header (kept in ``header_lines``); the last of them may name the
  columns (``time,acc (g)``, ``Time[s]<TAB>Accel[g]``). An optional time column comes first and gives
  the time step; every other column is a value column, read as one trace each. Units come from the
  header (``units: g``, ``... in units of cm/s2``, a unit in brackets in a column name) or from
  ``units=``; the time step from the time column, a ``dt: 0.01`` header line, or ``dt=``. Lines
  starting with ``#``, ``%`` or ``!`` are comments, anywhere.

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
_BRACKETED = re.compile(r"[\[(]\s*([^\[\]()]+?)\s*[\])]")
_NAME_TOKEN = re.compile(r"[^\s\[(]+(?:\s*[\[(][^\])]*[\])])?")
_TIME_NAME = re.compile(r"(?:t|time|times|tiempo|zeit|temps|tempo|sec|secs|seconds?)(?:[\s_]*(?:s|secs?|seconds?))?")
_SECONDS = {"s", "sec", "secs", "second", "seconds"}
_DECIMAL_COMMA = re.compile(r"^\s*[-+]?\d+,\d+\s*(?:[;\t ]|$)")

# How the options of read_record are named to the user in messages; a caller passes its own names
# (option_names=) so that its users read them as they type them.
PYTHON_OPTION_NAMES = {"units": "units=", "dt": "dt=", "column": "column=", "format": "format="}
CLI_OPTION_NAMES = {"units": "--units", "dt": "--dt", "column": "--column", "format": "--format"}


def scene_option_names(key: str) -> dict:
    """Option names for a scene ground-motion component at dotted ``key``
    (``{"units": f"{key}.units", ...}``), for ``read_record(..., option_names=)``."""
    return {o: f"{key}.{o}" for o in PYTHON_OPTION_NAMES}


class _Options:
    """The caller's spelling of the options: ``units=`` (Python keyword), ``--units`` (command
    line) or ``stages[1].ground_motion.x.units`` (scene key)."""

    def __init__(self, names=None):
        self.names = dict(PYTHON_OPTION_NAMES)
        unknown = sorted(set(names or ()) - set(PYTHON_OPTION_NAMES))
        if unknown:
            raise RecordError(f"option_names: unknown option(s) {unknown}; known: {sorted(PYTHON_OPTION_NAMES)}")
        self.names.update(names or {})
        self.python = self.names == PYTHON_OPTION_NAMES

    def _style(self, o):
        n = self.names[o]
        return "keyword" if n.endswith("=") else "cli" if n.startswith("-") else "key"

    def label(self, o) -> str:
        """The option as a label: ``units``, ``--units``, ``stages[1].ground_motion.x.units``."""
        n = self.names[o]
        return n[:-1] if n.endswith("=") else n

    def ask(self, o) -> str:
        """How to give it: ``pass units=``, ``pass --units``, ``set stages[1].ground_motion.x.units``."""
        return f"set {self.names[o]}" if self._style(o) == "key" else f"pass {self.names[o]}"

    def example(self, o, value_text: str) -> str:
        """``units=g``, ``--units g``, ``stages[1].ground_motion.x.units = g``."""
        n, style = self.names[o], self._style(o)
        return f"{n}{value_text}" if style == "keyword" else f"{n} {value_text}" if style == "cli" \
            else f"{n} = {value_text}"

    def given(self, o, value) -> str:
        """The value the caller gave, as the caller wrote it: ``dt=0.01``, ``--dt 0.01``, ``... .dt = 0.01``."""
        if isinstance(value, str):
            text = value if self._style(o) == "cli" else repr(value)
        else:
            text = _num(value)
        return self.example(o, text)


def _value(x) -> str:
    """``repr`` of a value for a message, NumPy scalars shown as the Python value they hold."""
    return repr(x.item() if isinstance(x, np.generic) else x)


def _num(x) -> str:
    """A number for a message: ``0.01``, ``3``, never ``np.float64(0.01)``."""
    if isinstance(x, (bool, np.bool_)):
        return str(bool(x))
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    try:
        return f"{float(x):.10g}"
    except (TypeError, ValueError):
        return repr(x)


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


def _check_dt(dt, what="dt", option=None) -> float:
    try:
        dtf = float(dt)
    except (TypeError, ValueError):
        raise RecordError(f"{what}: expected a positive time step in seconds, got {dt!r}", option) from None
    if not np.isfinite(dtf) or dtf <= 0.0:
        raise RecordError(f"{what}: expected a positive time step in seconds, got {_num(dt)}", option)
    return dtf


def _same_dt(a: float, b: float, rtol: float = 1e-6) -> bool:
    return abs(a - b) <= rtol * max(abs(a), abs(b))


def _parse_given_units(given: str, opts: _Options) -> tuple[str, str, float]:
    try:
        return parse_units(given, opts.label("units"))
    except RecordError as exc:
        raise RecordError(str(exc), "units") from None


def _resolve_units(found: str | None, found_where: str, given: str | None, path: Path,
                   context: str, opts: _Options | None = None,
                   found_line: str | None = None) -> tuple[str, str, float, str]:
    """Combine the units found in the file (``found``, stated in ``found_where``, e.g. "header", on
    the line ``found_line``) with the units the caller gave. Returns ``(quantity, unit, factor,
    source)``; ``source`` is ``found_where`` or ``"argument"``."""
    opts = opts or _Options()
    if found is None and given is None:
        raise RecordError(f"{path}: the physical units are not stated in the file; {opts.ask('units')} "
                          f"(acceleration: g, m/s2, cm/s2, gal, mm/s2). Found: {context}", "units")
    if found is not None:
        qf, uf, ff = parse_units(found, f"{path}: units in {found_where}")
        if given is not None:
            qg, ug, fg = _parse_given_units(given, opts)
            if (qg, fg) != (qf, ff):
                line = "" if found_line is None else f" {found_line.strip()!r}"
                raise RecordError(f"{path}: {opts.given('units', given)} ({qg}) contradicts the {found_where}{line}, "
                                  f"which says {found!r} ({qf})", "units")
        return qf, uf, ff, found_where
    qg, ug, fg = _parse_given_units(given, opts)
    return qg, ug, fg, "argument"


def _check_quantity(path: Path, found_quantity: str, requested: str, evidence: str, option=None):
    if found_quantity != requested:
        hint = ""
        if requested == "acceleration":
            hint = (f"; it cannot be used as an acceleration. Read it with quantity='{found_quantity}' "
                    f"(returned in {SI_UNITS[found_quantity]}), or use an acceleration record (for PEER data, "
                    f"the matching .AT2 file)")
        raise RecordError(f"{path}: this is a {found_quantity} record ({evidence}), "
                          f"not {'an' if requested[0] in 'aeiou' else 'a'} {requested} record{hint}", option)


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


def _read_peer(path: Path, lines, found, units, dt, quantity, opts: _Options) -> obspy.Stream:
    i_npts, npts, dt_text, layout = found
    header = [ln.rstrip() for ln in lines[: i_npts + 1] if ln.strip()]
    dt_file = _check_dt(dt_text, f"{path}: DT in header line {i_npts + 1}")
    if dt is not None and not _same_dt(_check_dt(dt, opts.label("dt"), "dt"), dt_file):
        raise RecordError(f"{path}: {opts.given('dt', dt)} contradicts the header line {i_npts + 1} "
                          f"{lines[i_npts].strip()!r} (DT = {_num(dt_file)} s)", "dt")
    head_text = "\n".join(header[:-1]) + "\n" + lines[i_npts]
    # quantity: keyword in the header, units in the header, file extension; all must agree
    kws = {m.group(1).lower() for m in _QUANTITY_IN_HEADER.finditer(head_text)}
    if len(kws) > 1:
        raise RecordError(f"{path}: the header names several quantities ({', '.join(sorted(kws))}):\n"
                          f"{_show(header)}")
    m_units = _UNITS_IN_HEADER.search(head_text)
    found_units = m_units.group(1) if m_units else None
    q_units, unit, factor, units_source = _resolve_units(
        found_units, "header", units, path, f"PEER header\n{_show(header)}", opts)
    units_line = None
    if m_units:
        units_line = next((ln.strip() for ln in header + [lines[i_npts]] if _UNITS_IN_HEADER.search(ln)), None)
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
    _check_quantity(path, q_file, quantity, evidence, "units" if units_source == "argument" else None)

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
        unit_factor=factor, units_from=units_source, units_source=units_line if units_source != "argument" else None,
        npts_header=npts, dt_header=dt_file)
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

def _fields(s: str) -> list[str]:
    """Split a line at its separator: ``;`` if it has one, else ``,``, else whitespace (tabs too)."""
    if ";" in s:
        parts = s.split(";")
    elif "," in s:
        parts = s.split(",")
    else:
        return s.split()
    parts = [p.strip() for p in parts]
    while parts and not parts[-1]:
        parts.pop()
    return parts


def _numeric_row(s: str):
    """The numbers of a data line, or None where the line is not a row of numbers."""
    fields = _fields(s)
    if not fields or not all(_NUMBER.fullmatch(f) for f in fields):
        return None
    return [float(f.replace("D", "E").replace("d", "e")) for f in fields]


def _column_names(line: str, ncol: int, data_line: str):
    """The names in a column line such as ``time,acc (g)`` or ``Time[s]<TAB>Accel[g]``, split like the
    data line; None where the line does not have one name per data column."""
    t = line.lstrip("#%!").strip()
    if ";" in data_line or "," in data_line:
        parts = t.split(";" if ";" in data_line else ",")
    elif "\t" in t:
        parts = t.split("\t")
    else:
        parts = _NAME_TOKEN.findall(t)
    parts = [p.strip() for p in parts if p.strip()]
    return parts if len(parts) == ncol else None


def _unit_in_name(name: str):
    """The unit in brackets in a column name (``Accel[g]``, ``acc (cm/sec^2)``) if masonrydam knows it."""
    for text in reversed(_BRACKETED.findall(name)):
        try:
            parse_units(text)
        except RecordError:
            continue
        return text
    return None


def _is_time_name(name: str) -> bool:
    """``t``, ``time``, ``Time[s]``, ``time_s``, ``sec`` ...: a name that says the column holds times."""
    return bool(_TIME_NAME.fullmatch(_BRACKETED.sub("", name).strip().lower()))


def _columns_text(names, value_cols, tcol) -> str:
    shown = ", ".join(f"{k} = {names[j]!r}" if names else f"{k} = column {j + 1} of the file"
                      for k, j in enumerate(value_cols))
    excl = "" if tcol is None else (f", the time column {names[tcol]!r} not counted" if names
                                    else ", the time column (column 1 of the file) not counted")
    return f"value columns, counted from 0{excl}: {shown}"


def _read_text(path: Path, lines, units, dt, quantity, column=None, single=False,
               opts: _Options | None = None) -> obspy.Stream:
    opts = opts or _Options()
    header = []        # (line number, text): the lines before the data and the comment lines
    declared = []      # (key, value, line number, text) from 'units: g' / 'dt = 0.01' lines
    rows = []
    first = None       # line index of the first data row
    last_header = None  # (line number, text) of the last non-declaration header line before the data
    for j, line in enumerate(lines):
        s = line.strip()
        if not s:
            continue
        comment = s[0] in "#%!"
        row = None if comment else _numeric_row(s)
        if row is None:
            if not comment and first is not None:
                raise RecordError(
                    f"{path}: line {j + 1} {s[:80]!r} is not a row of numbers, but the data began at line "
                    f"{first + 1}; header lines may only precede the data, and comment lines start with '#', "
                    f"'%' or '!'. First lines:\n{_show(lines)}")
            header.append((j + 1, s))
            m = _DECLARATION.match(s.lstrip("#%! "))
            if m:
                key = "units" if m.group(1).lower().startswith("unit") else "dt"
                declared.append((key, m.group(2), j + 1, s))
            elif first is None:
                last_header = (j + 1, s)
            continue
        if first is None:
            first = j
            ncol = len(row)
            if last_header is not None and last_header[0] != max(n for n, _ in header):
                last_header = None  # a declaration separates it from the data
        elif len(row) != ncol:
            raise RecordError(f"{path}: line {j + 1} has {len(row)} columns, the first data line (line {first + 1}) "
                              f"has {ncol}")
        rows.append(row)
    if first is None or len(rows) < 2:
        hint = ""
        if any(_DECIMAL_COMMA.match(s) for _, s in header):
            hint = "\n(numbers with a decimal comma, such as '0,01', are not read: write them with a '.')"
        raise RecordError(f"{path}: no record found (fewer than 2 rows of numbers). First lines:\n{_show(lines)}"
                          f"{hint}\nKnown formats: PEER AT2 (NPTS=/DT= header), obspy formats (SAC, MiniSEED, "
                          f"...), plain text with header lines, an optional time column and value columns")
    arr = np.asarray(rows, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        k = int(np.argmax(~np.all(np.isfinite(arr), axis=1)))
        raise RecordError(f"{path}: data row {k + 1} holds a number too large for a float: {rows[k]}")
    nrows = len(rows)
    names = _column_names(last_header[1], ncol, lines[first]) if last_header is not None else None
    names_line = last_header[1] if names is not None else None

    # the time column: the first of several columns, named as time (t, time, sec, ...) or, where the
    # columns are not named, strictly increasing and starting at (or within one step of) 0 or evenly spaced
    tcol, t_evidence = None, None
    if ncol >= 2:
        c = arr[:, 0]
        steps = np.diff(c)
        increasing = bool(np.all(steps > 0))
        if names is not None:
            if _is_time_name(names[0]):
                tcol, t_evidence = 0, f"named {names[0]!r}"
        elif increasing:
            mean = (c[-1] - c[0]) / (nrows - 1)
            even = bool(np.max(np.abs(steps - mean)) <= 1e-3 * mean)
            near0 = abs(c[0]) <= 1.001 * steps[0]
            if near0 or even:
                tcol = 0
                t_evidence = "increasing from " + _num(c[0]) + (" s in even steps" if even else " s")
    value_cols = [j for j in range(ncol) if j != tcol]
    nval = len(value_cols)
    found = (f"plain text with {ncol} column(s), {nrows} rows"
             + (f", time column ({t_evidence})" if tcol is not None else ", no time column")
             + (f", column line {names_line!r}" if names_line else "")
             + (f", {len(header)} header line(s)" if header else ""))

    # which value columns
    if column is not None:
        if isinstance(column, (bool, np.bool_)) or not isinstance(column, (int, np.integer)):
            raise RecordError(f"{opts.label('column')}: expected a column number (0 for the first value column), "
                              f"got {_value(column)}", "column")
        if not 0 <= int(column) < nval:
            raise RecordError(f"{path}: {opts.given('column', int(column))} is not a value column of this file: "
                              f"{nval} {_columns_text(names, value_cols, tcol)}", "column")
        chosen = [int(column)]
    elif single and nval > 1:
        also = "; read_record() returns them all" if opts.python else ""
        raise RecordError(f"{path}: {nval} value columns found, one is needed; choose it with "
                          f"{opts.example('column', 'N')} ({_columns_text(names, value_cols, tcol)}){also}",
                          "column")
    else:
        chosen = list(range(nval))

    # units: stated once for the file ('units: g', 'in units of cm/s2') and/or per column ('acc [g]')
    file_units = []  # (unit text, where, line)
    for key, value, n, text in declared:
        if key == "units":
            where = "'# units:' declaration" if text[0] in "#%!" else f"header line {n}"
            parse_units(value, f"{path}: units in {where} {text!r}")
            file_units.append((value, where, text))
    for n, text in header:
        m = _UNITS_IN_HEADER.search(text)
        if m and not _DECLARATION.match(text.lstrip("#%! ")):
            try:
                parse_units(m.group(1))
            except RecordError:
                continue  # 'units in SI' and the like: not a statement masonrydam can use
            file_units.append((m.group(1), f"header line {n}", text))
    distinct = {parse_units(u)[::2]: (u, w, t) for u, w, t in file_units}
    if len(distinct) > 1:
        said = "; ".join(f"{u!r} in {w} {t!r}" for u, w, t in distinct.values())
        raise RecordError(f"{path}: the header states different units ({said}); masonrydam does not choose",
                          "units")
    file_unit = next(iter(distinct.values()), None)

    col_units = {}
    for k in chosen:
        j = value_cols[k]
        cname = names[j] if names else None
        col_unit = _unit_in_name(cname) if cname else None
        if col_unit is not None and file_unit is not None and parse_units(col_unit)[::2] != \
                parse_units(file_unit[0])[::2]:
            raise RecordError(f"{path}: the column {cname!r} is in {col_unit!r}, but the {file_unit[1]} "
                              f"{file_unit[2]!r} says {file_unit[0]!r}; masonrydam does not choose", "units")
        if col_unit is not None:
            stated, where, source_line = col_unit, "column line", names_line
        elif file_unit is not None:
            stated, where, source_line = file_unit
        else:
            stated = where = source_line = None
        context = found + ("; the header has no 'units: ...' line and no unit in a column name such as 'acc (g)'"
                           if stated is None else "")
        q_units, unit, factor, units_from = _resolve_units(stated, where, units, path, context, opts, source_line)
        _check_quantity(path, q_units, quantity, f"units {unit!r}", "units" if units_from == "argument" else None)
        col_units[k] = (cname, unit, q_units, factor, units_from, source_line)

    # time step
    dt_decl = None
    for key, value, n, text in declared:
        if key == "dt":
            d = _check_dt(value, f"{path}: time step in line {n} {text!r}")
            if dt_decl is not None and not _same_dt(d, dt_decl[0], 1e-3):
                raise RecordError(f"{path}: the header states two time steps, {_num(dt_decl[0])} s "
                                  f"({dt_decl[1]!r}) and {_num(d)} s ({text!r})")
            dt_decl = (d, text)
    dt_arg = _check_dt(dt, opts.label("dt"), "dt") if dt is not None else None
    if dt_decl is not None and dt_arg is not None and not _same_dt(dt_decl[0], dt_arg, 1e-3):
        raise RecordError(f"{path}: {opts.given('dt', dt)} contradicts the file's declaration {dt_decl[1]!r} "
                          f"(dt = {_num(dt_decl[0])} s)", "dt")
    t0 = 0.0
    if tcol is None:
        if dt_arg is not None:
            dt_final, dt_source = dt_arg, "argument"
        elif dt_decl is not None:
            dt_final, dt_source = dt_decl[0], "declaration"
        else:
            raise RecordError(f"{path}: {found}; the time step is not stated: {opts.ask('dt')} (seconds) or add "
                              f"a '# dt: <seconds>' line", "dt")
    else:
        tname = names[tcol] if names else "column 1"
        t = arr[:, tcol]
        t_unit = _BRACKETED.findall(tname)
        if t_unit and t_unit[-1].strip().lower() not in _SECONDS:
            raise RecordError(f"{path}: the time column {tname!r} is in {t_unit[-1]!r}; masonrydam reads times in "
                              f"seconds (s)")
        steps = np.diff(t)
        if np.any(steps <= 0):
            k = int(np.argmax(steps <= 0))
            raise RecordError(f"{path}: {found}; the time column is not increasing at row {k + 2} "
                              f"(t = {_num(t[k])} then {_num(t[k + 1])})")
        dt_col = float((t[-1] - t[0]) / (nrows - 1))
        dev = np.abs(steps - dt_col)
        if dev.max() > 1e-3 * dt_col:
            k = int(np.argmax(dev))
            raise RecordError(
                f"{path}: {found}; the time column is not uniformly spaced: mean step {dt_col:.6g} s but "
                f"step {steps[k]:.6g} s between rows {k + 1} and {k + 2} (t = {_num(t[k])}, {_num(t[k + 1])}); "
                f"resample the record to a constant time step first")
        if dt_arg is not None and abs(dt_arg - dt_col) > 1e-3 * dt_col:
            raise RecordError(f"{path}: {opts.given('dt', dt)} contradicts the time column {tname!r}, whose step "
                              f"is {dt_col:.6g} s", "dt")
        if dt_decl is not None and abs(dt_decl[0] - dt_col) > 1e-3 * dt_col:
            raise RecordError(f"{path}: the declaration {dt_decl[1]!r} (dt = {_num(dt_decl[0])} s) contradicts the "
                              f"time column {tname!r}, whose step is {dt_col:.6g} s")
        dt_final, dt_source, t0 = dt_col, "time column", float(t[0])

    header_lines = [text for _, text in header][:200]
    out = obspy.Stream()
    for k in chosen:
        j = value_cols[k]
        cname, unit, q_units, factor, units_from, source_line = col_units[k]
        meta = _new_stats_meta(
            source_file=str(path), format="TEXT", format_variant=f"plain text, {ncol} column(s)"
            + (", time column" if tcol is not None else ""),
            header_lines=header_lines, quantity=q_units, original_units=unit, units=SI_UNITS[q_units],
            unit_factor=factor, units_from=units_from, units_source=None if units_from == "argument" else source_line,
            dt_from=dt_source, time_start=t0, column=k, column_name=cname, value_columns=nval,
            time_column=(names[tcol] if names else "column 1") if tcol is not None else None)
        if cname is not None:
            meta.component = cname
        elif nval > 1:
            meta.component = f"column {k}"
        meta.provenance.append({
            "step": "read", "function": "masonrydam.records.readers.read_record",
            "parameters": {"file": str(path), "format": meta.format_variant, "column": k,
                           "original_units": unit, "factor_to_si": factor, "npts": nrows, "dt": dt_final}})
        out.append(_make_trace(arr[:, j] * factor, dt_final, meta))
    return out


# ----------------------------------------------------------------------------------------------
# obspy formats
# ----------------------------------------------------------------------------------------------

def _read_obspy(path: Path, st: obspy.Stream, fmt: str | None, units, dt, quantity, opts: _Options) -> obspy.Stream:
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
                          f"can rely on{hint}: {opts.ask('units')} (acceleration: g, m/s2, cm/s2, gal, mm/s2)",
                          "units")
    q, unit, factor = _parse_given_units(units, opts)
    _check_quantity(path, q, quantity, f"units {unit!r}", "units")
    out = obspy.Stream()
    for tr in st:
        if dt is not None and not _same_dt(_check_dt(dt, opts.label("dt"), "dt"), tr.stats.delta):
            raise RecordError(f"{path}: {opts.given('dt', dt)} contradicts the file ({tr.id}: "
                              f"delta = {_num(tr.stats.delta)} s)", "dt")
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
                quantity: str = "acceleration", column: int | None = None,
                option_names: dict | None = None) -> obspy.Stream:
    """Read a ground-motion record; return an :class:`obspy.Stream` in SI units.

    path: the file. format: ``None`` (detect: PEER header, then obspy's own detection, then plain
    text), ``"AT2"``/``"PEER"``, ``"TEXT"``, or an obspy format name (``"SAC"``, ``"MSEED"``, ...).
    units: units of the values in the file (``g``, ``m/s2``, ``cm/s2``/``gal``, ``mm/s2``; for
    velocity ``m/s``, ``cm/s``, ``mm/s``; for displacement ``m``, ``cm``, ``mm``); required where the
    file does not state them, and checked against the file where it does. dt: time step in s;
    required for text without a time column (unless a ``dt: <s>`` header line states it), checked
    against the file otherwise. quantity: what the caller needs (``"acceleration"``, ``"velocity"``
    or ``"displacement"``); a record of another quantity is an error (e.g. a PEER ``.DT2``
    displacement file read as acceleration). column: ``None`` (all traces) or the index of the one
    trace to return: for plain text, the value column counted from 0 *excluding the time column*
    (``column=k`` gives the trace that ``read_record(path)[k]`` would); for obspy formats, the trace
    index; for PEER files (one trace) only 0. option_names: how the caller's user spells the
    options in error messages, a dict over ``"units"``, ``"dt"``, ``"column"``, ``"format"``
    (default :data:`PYTHON_OPTION_NAMES`, ``units=``; :data:`CLI_OPTION_NAMES` gives ``--units``,
    :func:`scene_option_names` the scene keys); a :class:`RecordError` about one of them also
    carries its generic name in ``.option``.

    Plain text layouts: lines before the first row of numbers are a header (free text such as a
    station name, ``units: g`` and ``dt: 0.01`` declarations, a line naming the columns); lines
    starting with ``#``, ``%`` or ``!`` are comments anywhere; columns are separated by whitespace
    (tabs too), commas or semicolons. The first of several columns is the time column where the
    column line names it (``t``, ``time``, ``Time[s]``, ``sec``) or, without a column line, where it
    is strictly increasing and starts at 0 (within one step) or is evenly spaced; it must then be
    evenly spaced (to 1e-3 of the step) and gives dt. Every other column is a value column and gives
    one trace. Units are taken from the header where it states them: a unit in brackets in the
    column's name (``acc (g)``, ``Accel[cm/sec^2]``), a ``units: gal`` line, or ``... in units of
    m/s2``; two different statements are an error. The trace's ``stats.masonrydam`` then holds
    ``units_from`` (``"column line"``, ``"header line N"``, ``"'# units:' declaration"`` or
    ``"argument"``) and ``units_source`` (the header line, or None for the argument), ``column``
    (0-based value-column index), ``column_name``, ``value_columns``, ``time_column``, ``dt_from``
    and ``time_start`` (s).

    Each trace has ``stats.delta`` (s), ``stats.npts`` and ``stats.masonrydam`` with ``source_file``,
    ``format``, ``format_variant``, ``header_lines``, ``quantity``, ``original_units``, ``units``
    (the SI unit of the data), ``unit_factor``, where found ``event``, ``date``, ``station``,
    ``component``, and ``provenance`` (a list of dicts, the first one describing the read).
    """
    return _read(path, format, units, dt, quantity, column, _Options(option_names), single=False)


def _read(path, format, units, dt, quantity, column, opts: _Options, single: bool) -> obspy.Stream:
    if quantity not in QUANTITIES:
        raise RecordError(f"quantity must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    path = Path(path)
    if not path.is_file():
        raise RecordError(f"record file not found: {path}")
    raw = path.read_bytes()
    lines = _text_lines(raw)
    fmt = None if format is None else str(format)
    key = None if fmt is None else fmt.lower()
    fmt_given = opts.given("format", format) if format is not None else None

    if key in _PEER_NAMES or key is None:
        found = _find_npts_line(lines) if lines is not None else None
        if found is not None:
            return _pick(_read_peer(path, lines, found, units, dt, quantity, opts), column, single, path, opts)
        if key is not None:
            head = _show(lines) if lines is not None else "    (binary file)"
            raise RecordError(f"{path}: {fmt_given}, but no 'NPTS=..., DT=...' (or '<npts> <dt> NPTS, "
                              f"DT') line was found in the first {_MAX_HEADER_LINES} lines:\n{head}", "format")
    if key in _TEXT_NAMES:
        if lines is None:
            raise RecordError(f"{path}: {fmt_given}, but the file is binary", "format")
        return _read_text(path, lines, units, dt, quantity, column, single, opts)

    # obspy formats: explicit name, or obspy's own detection
    try:
        st = obspy.read(str(path), format=None if key is None else fmt.upper())
    except TypeError as exc:
        if key is not None:
            raise RecordError(f"{path}: obspy cannot read it as {fmt_given}: {exc}", "format") from None
        st = None
    except Exception as exc:  # noqa: BLE001 - obspy plugins raise many types
        if key is not None:
            raise RecordError(f"{path}: obspy failed to read it as {fmt_given}: "
                              f"{type(exc).__name__}: {exc}", "format") from None
        st = None
    if st is not None:
        if len(st) == 0:
            raise RecordError(f"{path}: obspy read the file but found no traces")
        return _pick(_read_obspy(path, st, fmt, units, dt, quantity, opts), column, single, path, opts)
    if lines is None:
        raise RecordError(f"{path}: unknown format: a binary file that obspy does not recognise "
                          f"(first bytes {raw[:16]!r}); {opts.ask('format')} with an obspy format name", "format")
    return _read_text(path, lines, units, dt, quantity, column, single, opts)


def _pick(st: obspy.Stream, column, single: bool, path: Path, opts: _Options) -> obspy.Stream:
    """The trace ``column`` of a PEER or obspy stream (all of them for None)."""
    listing = "; ".join(f"{k} = {tr.id}" for k, tr in enumerate(st))
    if column is not None:
        if isinstance(column, (bool, np.bool_)) or not isinstance(column, (int, np.integer)):
            raise RecordError(f"{opts.label('column')}: expected a trace number (0 for the first), got "
                              f"{_value(column)}", "column")
        if not 0 <= int(column) < len(st):
            raise RecordError(f"{path}: {opts.given('column', int(column))}, but the file holds {len(st)} "
                              f"trace(s), counted from 0: {listing}", "column")
        return obspy.Stream([st[int(column)]])
    if single and len(st) != 1:
        raise RecordError(f"{path}: expected one trace, found {len(st)} ({listing}); choose one with "
                          f"{opts.example('column', 'N')}", "column")
    return st


def read_trace(path, *, format: str | None = None, units: str | None = None, dt: float | None = None,
               quantity: str = "acceleration", column: int | None = None,
               option_names: dict | None = None) -> obspy.Trace:
    """:func:`read_record` for one trace; returns that :class:`obspy.Trace` (data in SI units, e.g.
    m/s2; ``stats.delta`` in s). A file with several value columns (or traces) needs ``column=``
    (0-based, the time column not counted); without it the error lists the columns found."""
    return _read(path, format, units, dt, quantity, column, _Options(option_names), single=True)[0]
