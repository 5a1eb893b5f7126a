"""Processing steps for acceleration traces, each recorded as provenance.

Every function takes an :class:`obspy.Trace` (data in m/s2, as returned by
:func:`masonrydam.records.read_record`), leaves it unchanged and returns a processed copy whose
``stats.masonrydam.provenance`` list ends with one entry::

    {"step": "bandpass", "parameters": {...}, "function": "obspy.core.trace.Trace.filter",
     "library": "obspy 1.5.1"}

:func:`provenance_attrs` flattens the metadata and the provenance into attributes that netCDF can
store (numbers and strings; the provenance list as a JSON string), for the result files.
"""
from __future__ import annotations

import json
import math
from fractions import Fraction

import numpy as np
import obspy
import scipy
from obspy.core.util import AttribDict

from . import measures
from .errors import RecordError
from .readers import parse_units


def _lib(name: str) -> str:
    return {"obspy": f"obspy {obspy.__version__}", "scipy": f"scipy {scipy.__version__}",
            "numpy": f"numpy {np.__version__}", "masonrydam": "masonrydam"}[name]


def _start(trace) -> obspy.Trace:
    """A processed copy of ``trace`` with a ``stats.masonrydam.provenance`` list."""
    if not isinstance(trace, obspy.Trace):
        raise RecordError(f"expected an obspy.Trace, got {type(trace).__name__} (take one trace of a Stream, "
                          f"e.g. stream[0])")
    out = trace.copy()
    if out.data.dtype != np.float64:
        out.data = out.data.astype(np.float64)
    meta = out.stats.get("masonrydam")
    if meta is None:
        meta = AttribDict()
        out.stats.masonrydam = meta
    if "provenance" not in meta:
        meta.provenance = []
    if meta.get("quantity", "acceleration") != "acceleration":
        raise RecordError(f"processing expects an acceleration trace, this one is a {meta.quantity} record")
    return out


def _record(tr, step: str, function: str, library: str, **parameters):
    tr.stats.masonrydam.provenance.append(
        {"step": step, "parameters": parameters, "function": function, "library": _lib(library)})
    return tr


def baseline_correct(trace, method: str = "linear", order: int | None = None) -> obspy.Trace:
    """Remove a baseline with obspy's ``Trace.detrend``: ``"demean"`` (mean), ``"linear"`` (least-squares
    line) or ``"polynomial"`` (least-squares polynomial of ``order``, default 2)."""
    tr = _start(trace)
    if method not in ("demean", "linear", "polynomial"):
        raise RecordError(f"baseline method must be 'demean', 'linear' or 'polynomial', got {method!r}")
    params = {"method": method}
    if method == "polynomial":
        order = 2 if order is None else int(order)
        if order < 0:
            raise RecordError(f"polynomial baseline order must be >= 0, got {order}")
        tr.detrend("polynomial", order=order)
        params["order"] = order
    elif order is not None:
        raise RecordError(f"order= applies to method='polynomial' only (method={method!r})")
    else:
        tr.detrend(method)
    return _record(tr, "baseline_correction", "obspy.core.trace.Trace.detrend", "obspy", **params)


def taper(trace, max_percentage: float = 0.05, side: str = "both", max_length: float | None = None) -> obspy.Trace:
    """Cosine (Tukey) taper with obspy's ``Trace.taper``: ``max_percentage`` of the length at each end
    (0 to 0.5), optionally at most ``max_length`` s; ``side`` is ``"both"``, ``"left"`` or ``"right"``."""
    tr = _start(trace)
    if not (0.0 < float(max_percentage) <= 0.5):
        raise RecordError(f"taper max_percentage must lie in (0, 0.5], got {max_percentage}")
    if side not in ("both", "left", "right"):
        raise RecordError(f"taper side must be 'both', 'left' or 'right', got {side!r}")
    tr.taper(max_percentage=float(max_percentage), type="cosine", max_length=max_length, side=side)
    return _record(tr, "taper", "obspy.core.trace.Trace.taper", "obspy", type="cosine",
                   max_percentage=float(max_percentage), max_length=max_length, side=side)


def bandpass(trace, freqmin: float | None, freqmax: float | None, corners: int = 4) -> obspy.Trace:
    """Zero-phase Butterworth filter with obspy's ``Trace.filter(..., zerophase=True)``.

    freqmin/freqmax in Hz: both given -> band-pass, only ``freqmin`` -> high-pass, only ``freqmax`` ->
    low-pass. ``corners`` is the order of the Butterworth filter; run forwards and backwards, the
    effective order is ``2 * corners`` and the phase is zero.
    """
    tr = _start(trace)
    nyq = 0.5 / tr.stats.delta
    fmin = None if freqmin is None else float(freqmin)
    fmax = None if freqmax is None else float(freqmax)
    if fmin is None and fmax is None:
        raise RecordError("bandpass needs freqmin and/or freqmax (Hz)")
    if fmin is not None and not (0.0 < fmin < nyq):
        raise RecordError(f"freqmin={fmin} Hz must lie in (0, Nyquist={nyq:g} Hz)")
    if fmax is not None and not (0.0 < fmax < nyq):
        raise RecordError(f"freqmax={fmax} Hz must lie in (0, Nyquist={nyq:g} Hz); resample first or lower it")
    if fmin is not None and fmax is not None and not fmin < fmax:
        raise RecordError(f"bandpass needs freqmin < freqmax, got {fmin} and {fmax} Hz")
    corners = int(corners)
    if corners < 1:
        raise RecordError(f"corners must be >= 1, got {corners}")
    if fmin is not None and fmax is not None:
        kind, kw = "bandpass", {"freqmin": fmin, "freqmax": fmax}
    elif fmin is not None:
        kind, kw = "highpass", {"freq": fmin}
    else:
        kind, kw = "lowpass", {"freq": fmax}
    tr.filter(kind, corners=corners, zerophase=True, **kw)
    return _record(tr, "bandpass", "obspy.core.trace.Trace.filter", "obspy", type=f"butterworth {kind}",
                   freqmin=fmin, freqmax=fmax, corners=corners, zerophase=True, effective_order=2 * corners)


def resample(trace, dt: float, method: str = "polyphase") -> obspy.Trace:
    """Resample to the time step ``dt`` (s) with an anti-alias filter.

    ``"polyphase"`` (default): :func:`scipy.signal.resample_poly` with the rational ratio of the two steps
    (a zero-phase Kaiser-windowed FIR low-pass at the lower Nyquist frequency); the ratio must be a
    fraction with a denominator up to 1000. ``"fourier"``: obspy's ``Trace.resample`` (FFT; when
    down-sampling obspy first applies its automatic low-pass).
    """
    # scipy.signal (a second to import) only for resampling: keeps the start of seismic runs short
    from scipy.signal import resample_poly

    tr = _start(trace)
    dt = float(dt)
    if not (math.isfinite(dt) and dt > 0):
        raise RecordError(f"resample: dt must be a positive number of seconds, got {dt!r}")
    old = float(tr.stats.delta)
    n_old = tr.stats.npts
    if method == "polyphase":
        ratio = Fraction(old / dt).limit_denominator(1000)  # new samples per old sample = up / down
        if abs(float(ratio) - old / dt) > 1e-9 * (old / dt):
            raise RecordError(f"resample: the step ratio {old}/{dt} is not a fraction with a small denominator; "
                              f"use method='fourier'")
        up, down = ratio.numerator, ratio.denominator
        data = resample_poly(tr.data, up, down)
        tr.data = np.ascontiguousarray(data, dtype=np.float64)
        tr.stats.delta = dt
        return _record(tr, "resample", "scipy.signal.resample_poly", "scipy", dt_old=old, dt_new=dt,
                       up=up, down=down, npts_old=n_old, npts_new=tr.stats.npts,
                       anti_alias="Kaiser-windowed FIR (scipy default window ('kaiser', 5.0))")
    if method == "fourier":
        down = dt > old
        tr.resample(1.0 / dt, window="hann", no_filter=not down)
        return _record(tr, "resample", "obspy.core.trace.Trace.resample", "obspy", dt_old=old, dt_new=dt,
                       window="hann", npts_old=n_old, npts_new=tr.stats.npts,
                       anti_alias="obspy automatic Chebyshev low-pass" if down else "none (up-sampling)")
    raise RecordError(f"resample method must be 'polyphase' or 'fourier', got {method!r}")


def trim_significant_duration(trace, start: float = 0.05, end: float = 0.95, pad: float = 0.0) -> obspy.Trace:
    """Keep the part of the record between the Husid fractions ``start`` and ``end`` (default the
    D5-95 window), widened by ``pad`` seconds on each side (clipped to the record)."""
    tr = _start(trace)
    if not (0.0 <= start < end <= 1.0):
        raise RecordError(f"trim needs 0 <= start < end <= 1, got start={start}, end={end}")
    if not (pad >= 0.0):
        raise RecordError(f"pad must be >= 0 s, got {pad}")
    dt = tr.stats.delta
    t0, t1 = measures.husid_times(tr.data, dt, (start, end))
    i0 = max(0, int(math.floor((t0 - pad) / dt + 1e-9)))
    i1 = min(tr.stats.npts - 1, int(math.ceil((t1 + pad) / dt - 1e-9)))
    n_old = tr.stats.npts
    start_time = tr.stats.starttime + i0 * dt
    tr.data = np.ascontiguousarray(tr.data[i0:i1 + 1])
    tr.stats.starttime = start_time
    return _record(tr, "trim_significant_duration", "masonrydam.records.measures.husid_times", "masonrydam",
                   start_fraction=float(start), end_fraction=float(end), pad=float(pad),
                   t_start=float(t0), t_end=float(t1), first_sample=i0, last_sample=i1,
                   npts_old=n_old, npts_new=tr.stats.npts)


def _target_in_si(value, units: str, what: str) -> float:
    q, unit, factor = parse_units(units, f"{what} units")
    if q != "acceleration":
        raise RecordError(f"{what} units must be an acceleration unit, got {units!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise RecordError(f"{what} must be a positive acceleration, got {v!r}")
    return v * factor


def scale(trace, factor: float, reason: str = "user") -> obspy.Trace:
    """Multiply the record by ``factor``."""
    tr = _start(trace)
    factor = float(factor)
    if not math.isfinite(factor):
        raise RecordError(f"scale factor must be finite, got {factor!r}")
    tr.data = tr.data * factor
    return _record(tr, "scale", "numpy.multiply", "numpy", factor=factor, reason=reason)


def scale_to_pga(trace, pga: float, units: str = "m/s2") -> obspy.Trace:
    """Scale the record so that its PGA equals ``pga`` (in ``units``: m/s2, g, cm/s2, ...)."""
    tr = _start(trace)
    target = _target_in_si(pga, units, "target PGA")
    current = measures.pga(tr)
    if current <= 0.0:
        raise RecordError("cannot scale an all-zero record")
    factor = target / current
    tr.data = tr.data * factor
    return _record(tr, "scale_to_pga", "masonrydam.records.measures.pga", "masonrydam", target=float(pga),
                   target_units=units, target_m_s2=target, pga_before_m_s2=current, factor=factor)


def scale_to_sa(trace, sa: float, period: float, damping: float = 0.05, units: str = "m/s2",
                min_samples_per_period: int = 32) -> obspy.Trace:
    """Scale the record so that its pseudo-spectral acceleration at ``period`` (s) and ``damping`` equals
    ``sa`` (in ``units``). The spectrum is linear in the record, so the scaled record hits the target to
    rounding error."""
    tr = _start(trace)
    target = _target_in_si(sa, units, "target Sa")
    current = measures.spectral_acceleration(tr, None, float(period), float(damping),
                                             min_samples_per_period=min_samples_per_period)
    if current <= 0.0:
        raise RecordError(f"Sa({period} s, {damping}) of the record is zero; cannot scale to it")
    factor = target / current
    tr.data = tr.data * factor
    return _record(tr, "scale_to_sa", "masonrydam.records.measures.response_spectrum", "masonrydam",
                   target=float(sa), target_units=units, target_m_s2=target, period=float(period),
                   damping=float(damping), sa_before_m_s2=current, factor=factor,
                   min_samples_per_period=int(min_samples_per_period))


def _jsonable(v):
    if isinstance(v, (str, bool, int, float)) or v is None:
        return v
    if isinstance(v, (np.integer, np.floating)):
        return v.item()
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_jsonable(x) for x in v]
    return str(v)


def provenance_attrs(trace, prefix: str = "record_") -> dict:
    """netCDF-storable attributes (str, int, float) describing ``trace``: its metadata (source file,
    format, units, event, station, ...), npts and dt, and ``<prefix>provenance``, the provenance list as
    a JSON string."""
    meta = trace.stats.get("masonrydam") or {}
    attrs = {f"{prefix}npts": int(trace.stats.npts), f"{prefix}dt": float(trace.stats.delta)}
    for key, value in meta.items():
        if key == "provenance":
            continue
        v = _jsonable(value)
        if isinstance(v, bool):
            v = str(v).lower()
        elif v is None:
            continue
        elif isinstance(v, (list, dict)):
            v = json.dumps(v)
        attrs[f"{prefix}{key}"] = v
    attrs[f"{prefix}provenance"] = json.dumps(_jsonable(list(meta.get("provenance", []))))
    return attrs
