"""Intensity measures and elastic response spectra of an acceleration record.

Every function takes either an :class:`obspy.Trace` (data in m/s2, time step from ``stats.delta``)
or a 1-D array of accelerations in m/s2 together with ``dt`` in s. Results are SI: m/s2, m/s, m, s.

Conventions (stated here once, used everywhere):

- The record is used as given: no baseline correction, filtering or padding happens inside a
  measure. Raw records should go through :mod:`masonrydam.records.processing` first; the bundled
  PEER records are already baseline-corrected and band-passed by their providers.
- Velocity and displacement are cumulative trapezoidal integrals with zero initial velocity and
  displacement (``v[0] = d[0] = 0``). PGV and PGD are their peak absolute values.
- Integrals of ``a**2`` (Arias intensity, Husid plot) and of ``|a|`` (CAV) use the trapezoidal rule.
  Arias intensity ``Ia = pi / (2 g) * integral(a**2 dt)`` (Arias 1970), in m/s, with
  ``g = 9.80665 m/s2``. CAV is the plain ``integral(|a| dt)`` over the whole record, in m/s (not the
  EPRI (1988) "standardized" CAV with its 0.025 g threshold).
- The Husid function ``H(t)`` is the cumulative ``integral(a**2)`` normalised to 1; times at which it
  reaches given fractions are interpolated linearly between samples; the significant duration
  ``D5-95 = t(0.95) - t(0.05)`` (Trifunac & Brady 1975). Times are measured from the first sample.
- Response spectra: linear SDOF oscillators ``u'' + 2 zeta w u' + w**2 u = -a_g(t)`` starting at rest,
  with the ground acceleration interpolated linearly between samples. Each step is solved exactly
  for that piecewise-linear excitation (Nigam & Jennings 1969, BSSA 59(2) 909-922; Chopra, Dynamics
  of Structures, sec. 5.2). The recurrence is evaluated on sub-steps of the record step (the
  excitation is interpolated linearly, which is exact within the piecewise-linear assumption) so that
  every natural period is sampled at least ``min_samples_per_period`` times; with 32 samples the
  peak of a harmonic response is missed by at most ``1 - cos(pi/32) = 0.5 %``. Response is computed
  over the record duration only (pad the record with zeros for free vibration after its end).
  ``Sd = max|u|``, pseudo-velocity ``Sv = w Sd`` and pseudo-acceleration ``Sa = w**2 Sd``. For
  ``T = 0`` (a rigid oscillator), ``Sd = Sv = 0`` and ``Sa = PGA``.
"""
from __future__ import annotations

import math

import numba
import numpy as np

from ..errors import STATUS_NAN, STATUS_OK
from .errors import RecordError
from .readers import G

STATUS_BAD_INPUT = 4  # a period or damping outside the kernel's domain; info = (damping idx, period idx)


def as_series(acc, dt=None) -> tuple[np.ndarray, float]:
    """``(a, dt)``: float64 contiguous accelerations (m/s2) and the time step (s) of a Trace or array."""
    if hasattr(acc, "stats") and hasattr(acc, "data"):
        meta = acc.stats.get("masonrydam") or {}
        q = meta.get("quantity", "acceleration")
        if q != "acceleration":
            raise RecordError(f"this trace is a {q} record ({meta.get('source_file', '?')}); the measures "
                              f"need an acceleration record")
        tr_dt = float(acc.stats.delta)
        if dt is not None and abs(float(dt) - tr_dt) > 1e-9 * tr_dt:
            raise RecordError(f"dt={dt} contradicts the trace's delta={tr_dt}")
        a, dt = acc.data, tr_dt
    else:
        if dt is None:
            raise RecordError("dt (s) is required when the record is given as an array")
        a = acc
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.ndim != 1 or a.size < 2:
        raise RecordError(f"expected a 1-D record with at least 2 samples, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise RecordError(f"the record has {int(np.sum(~np.isfinite(a)))} non-finite samples")
    dt = float(dt)
    if not (np.isfinite(dt) and dt > 0):
        raise RecordError(f"dt must be a positive number of seconds, got {dt!r}")
    return a, dt


def _cumtrapz(y: np.ndarray, dt: float) -> np.ndarray:
    out = np.empty_like(y)
    out[0] = 0.0
    np.cumsum(0.5 * dt * (y[1:] + y[:-1]), out=out[1:])
    return out


def pga(acc, dt=None) -> float:
    """Peak ground acceleration max|a| (m/s2)."""
    a, _ = as_series(acc, 1.0 if dt is None and not hasattr(acc, "stats") else dt)
    return float(np.max(np.abs(a)))


def velocity(acc, dt=None) -> np.ndarray:
    """Ground velocity (m/s): cumulative trapezoidal integral of the acceleration, ``v[0] = 0``."""
    a, dt = as_series(acc, dt)
    return _cumtrapz(a, dt)


def displacement(acc, dt=None) -> np.ndarray:
    """Ground displacement (m): trapezoidal integral of :func:`velocity`, ``d[0] = 0``."""
    a, dt = as_series(acc, dt)
    return _cumtrapz(_cumtrapz(a, dt), dt)


def pgv(acc, dt=None) -> float:
    """Peak ground velocity (m/s) of the trapezoidal velocity (see module notes on baselines)."""
    return float(np.max(np.abs(velocity(acc, dt))))


def pgd(acc, dt=None) -> float:
    """Peak ground displacement (m) of the twice-integrated record (see module notes on baselines)."""
    return float(np.max(np.abs(displacement(acc, dt))))


def arias_intensity(acc, dt=None) -> float:
    """Arias intensity ``pi / (2 g) * integral(a**2 dt)`` (m/s), trapezoidal rule."""
    a, dt = as_series(acc, dt)
    return float(math.pi / (2.0 * G) * _cumtrapz(a * a, dt)[-1])


def husid(acc, dt=None) -> np.ndarray:
    """Normalised Husid function at the samples: cumulative ``integral(a**2)`` / total, from 0 to 1."""
    a, dt = as_series(acc, dt)
    e = _cumtrapz(a * a, dt)
    if e[-1] <= 0.0:
        raise RecordError("the record is identically zero: no Husid function / significant duration")
    return e / e[-1]


def husid_times(acc, dt=None, fractions=(0.05, 0.95)) -> np.ndarray:
    """Times (s, from the first sample) at which the Husid function first reaches each fraction."""
    a, dt = as_series(acc, dt)
    f = np.atleast_1d(np.asarray(fractions, dtype=np.float64))
    if np.any(~np.isfinite(f)) or np.any(f < 0.0) or np.any(f > 1.0):
        raise RecordError(f"Husid fractions must lie in [0, 1], got {f.tolist()}")
    h = husid(a, dt)
    out = np.empty_like(f)
    for k, fk in enumerate(f):
        i = int(np.searchsorted(h, fk, side="left"))  # first sample with h >= fk
        if i == 0:
            out[k] = 0.0
            continue
        h0, h1 = h[i - 1], h[i]
        out[k] = (i - 1 + (fk - h0) / (h1 - h0)) * dt
    return out


def significant_duration(acc, dt=None, start: float = 0.05, end: float = 0.95) -> float:
    """Significant duration (s) between the Husid fractions ``start`` and ``end`` (default D5-95)."""
    if not (0.0 <= start < end <= 1.0):
        raise RecordError(f"significant duration needs 0 <= start < end <= 1, got start={start}, end={end}")
    t0, t1 = husid_times(acc, dt, (start, end))
    return float(t1 - t0)


def cav(acc, dt=None) -> float:
    """Cumulative absolute velocity ``integral(|a| dt)`` over the whole record (m/s), trapezoidal rule."""
    a, dt = as_series(acc, dt)
    return float(_cumtrapz(np.abs(a), dt)[-1])


# ----------------------------------------------------------------------------------------------
# Response spectrum kernel
# ----------------------------------------------------------------------------------------------

@numba.njit(cache=True)
def _step_coefficients(w, z, h, c):
    """Exact one-step recurrence of ``u'' + 2 z w u' + w**2 u = p(t)`` (unit mass) for a load ``p`` varying
    linearly over the step ``h`` (0 <= z < 1, w > 0):

        u1 = c0 u0 + c1 v0 + c2 p0 + c3 p1,    v1 = c4 u0 + c5 v0 + c6 p0 + c7 p1.

    Derived as free vibration from the initial state minus the particular solution of the linear load
    ``p0 + s t`` (``s = (p1 - p0) / h``): ``u_p(t) = (p0 + s t) / k - 2 z s / (w k)``, ``k = w**2``; the
    result is the recurrence of Nigam & Jennings (1969) / Chopra (Table 5.2.1) in another arrangement.
    """
    wd = w * math.sqrt(1.0 - z * z)
    e = math.exp(-z * w * h)
    cs = math.cos(wd * h)
    sn = math.sin(wd * h)
    a = e * (cs + z * w / wd * sn)  # u1 from u0
    b = e * sn / wd  # u1 from v0
    ap = -e * w * w / wd * sn  # v1 from u0
    bp = e * (cs - z * w / wd * sn)  # v1 from v0
    k = w * w
    r = 2.0 * z / (w * k * h)
    kh = 1.0 / (k * h)
    c[0] = a
    c[1] = b
    c[2] = -a * (1.0 / k + r) + b * kh + r
    c[3] = a * r - b * kh + 1.0 / k - r
    c[4] = ap
    c[5] = bp
    c[6] = -ap * (1.0 / k + r) + bp * kh - kh
    c[7] = ap * r - bp * kh + kh


@numba.njit(cache=True)
def sdof_peak_kernel(acc, dt, omegas, zetas, n_sub, sd_out, info):
    """Peak relative displacement of SDOF oscillators under the ground acceleration ``acc``.

    acc (n,) m/s2; dt s; omegas (n_per,) rad/s (> 0); zetas (n_damp,) in [0, 1); n_sub (n_per,) int64
    sub-steps per record step (>= 1); sd_out (n_damp, n_per) receives max|u| (m); info (2,) int64
    receives (damping index, period index) of a failure. Returns a ``STATUS_*`` code.
    """
    n = acc.shape[0]
    c = np.empty(8)
    for j in range(zetas.shape[0]):
        z = zetas[j]
        for k in range(omegas.shape[0]):
            w = omegas[k]
            m = n_sub[k]
            if not (w > 0.0) or not (z >= 0.0) or not (z < 1.0) or m < 1:
                info[0] = j
                info[1] = k
                return STATUS_BAD_INPUT
            h = dt / m
            _step_coefficients(w, z, h, c)
            c0, c1, c2, c3, c4, c5, c6, c7 = c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]
            u = 0.0
            v = 0.0
            peak = 0.0
            inv_m = 1.0 / m
            for i in range(n - 1):
                pa = -acc[i]
                p1 = -acc[i + 1]
                dp = (p1 - pa) * inv_m
                for s in range(m):
                    pb = p1 if s == m - 1 else pa + dp
                    un = c0 * u + c1 * v + c2 * pa + c3 * pb
                    v = c4 * u + c5 * v + c6 * pa + c7 * pb
                    u = un
                    au = abs(u)
                    if au > peak:
                        peak = au
                    pa = pb
            if not (peak - peak == 0.0):
                info[0] = j
                info[1] = k
                return STATUS_NAN
            sd_out[j, k] = peak
    return STATUS_OK


def _periods_dampings(periods, dampings):
    T = np.atleast_1d(np.asarray(periods, dtype=np.float64))
    Z = np.atleast_1d(np.asarray(dampings, dtype=np.float64))
    if T.ndim != 1 or T.size == 0:
        raise RecordError(f"periods must be a non-empty 1-D list of seconds, got shape {T.shape}")
    if Z.ndim != 1 or Z.size == 0:
        raise RecordError(f"dampings must be a non-empty 1-D list of ratios, got shape {Z.shape}")
    bad = ~np.isfinite(T) | (T < 0.0)
    if bad.any():
        raise RecordError(f"periods must be 0 (rigid, Sa = PGA) or positive finite seconds; got "
                          f"{T[bad][:5].tolist()}")
    bad = ~np.isfinite(Z) | (Z < 0.0) | (Z >= 1.0)
    if bad.any():
        raise RecordError(f"damping ratios must lie in [0, 1) (e.g. 0.05 for 5 %); got {Z[bad][:5].tolist()}")
    return T, Z


def response_spectrum(acc, dt=None, periods=None, dampings=0.05, *, min_samples_per_period: int = 32):
    """Elastic pseudo-spectra ``(Sa, Sv, Sd)`` (m/s2, m/s, m), each of shape (n_dampings, n_periods).

    acc: Trace or array (m/s2) with ``dt`` (s); periods: natural periods in s (0 allowed: Sa = PGA);
    dampings: damping ratios in [0, 1) (a scalar gives one row); min_samples_per_period: the record
    step is divided into sub-steps so that each period is sampled at least this often (1: evaluate at
    the record samples only). See the module notes for the method.
    """
    a, dt = as_series(acc, dt)
    if periods is None:
        raise RecordError("periods (s) are required")
    T, Z = _periods_dampings(periods, dampings)
    if int(min_samples_per_period) < 1:
        raise RecordError(f"min_samples_per_period must be >= 1, got {min_samples_per_period}")
    pos = T > 0.0
    Tp = T[pos]
    omegas = 2.0 * np.pi / Tp
    n_sub = np.maximum(1, np.ceil(dt * int(min_samples_per_period) / Tp - 1e-9)).astype(np.int64)
    sd_pos = np.zeros((Z.size, Tp.size))
    info = np.zeros(2, dtype=np.int64)
    status = sdof_peak_kernel(a, dt, omegas, Z, n_sub, sd_pos, info)
    if status != STATUS_OK:
        j, k = int(info[0]), int(info[1])
        what = "a non-finite response" if status == STATUS_NAN else "invalid input"
        raise RecordError(f"response spectrum: {what} for period {float(Tp[k]):g} s, damping {float(Z[j]):g}")
    Sd = np.zeros((Z.size, T.size))
    Sd[:, pos] = sd_pos
    w = np.zeros(T.size)
    w[pos] = omegas
    Sv = Sd * w
    Sa = Sd * w * w
    Sa[:, ~pos] = np.max(np.abs(a))
    return Sa, Sv, Sd


def spectral_acceleration(acc, dt=None, period: float = 0.0, damping: float = 0.05, **kwargs) -> float:
    """Pseudo-spectral acceleration Sa(T, zeta) in m/s2 (T = 0 gives the PGA)."""
    Sa, _, _ = response_spectrum(acc, dt, [period], [damping], **kwargs)
    return float(Sa[0, 0])


def summary(acc, dt=None) -> dict:
    """All scalar measures of a record: PGA, PGV, PGD, Arias, D5-95 (with its start/end), CAV; SI units."""
    a, dt = as_series(acc, dt)
    t5, t95 = husid_times(a, dt, (0.05, 0.95))
    return {"pga": pga(a, dt), "pgv": pgv(a, dt), "pgd": pgd(a, dt), "arias_intensity": arias_intensity(a, dt),
            "d5_95": float(t95 - t5), "t5": float(t5), "t95": float(t95), "cav": cav(a, dt),
            "duration": (a.size - 1) * dt, "npts": int(a.size), "dt": dt}
