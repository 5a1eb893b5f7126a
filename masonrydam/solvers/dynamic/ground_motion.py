"""A ground acceleration record as the dynamic solver reads it: :class:`GroundMotion`.

One component (x, y or z) of the uniform base excitation, in m/s2, sampled every ``dt`` s from the stage's
start, linear between samples and zero after the last one. The records themselves are read and processed by
:mod:`masonrydam.records`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from ...errors import SceneError


@numba.njit(cache=True)
def record_at(t, times, values) -> float:
    """The record (samples ``values`` at ``times``) linear between samples and zero outside them, at ``t`` (s)."""
    if t < 0.0 or t > times[times.shape[0] - 1] * (1 + 1e-12):
        return 0.0
    return np.interp(t, times, values)


@numba.njit(cache=True)
def chord_error(t0, t1, times, values, dt) -> float:
    """:meth:`GroundMotion.chord_error` of the record sampled every ``dt`` s (``times``, ``values``), compiled: the
    compiled step loop (:mod:`.loop_kernel`) measures its steps with it. |d| is linear on each piece between the
    breakpoints (samples inside the step, the record's end with its jump to zero), and integrated exactly also where d
    changes sign inside a piece; the pieces are summed in order."""
    if t1 <= t0:
        return 0.0
    count = values.shape[0]
    t_end = times[count - 1] * (1 + 1e-12)
    i0 = int(math.floor(t0 / dt)) + 1
    i1 = min(int(math.ceil(t1 / dt)) - 1, count - 1)
    jump = t0 <= t_end < t1 and values[count - 1] != 0.0
    if i1 < i0 and not jump:  # no sample inside the step (most steps): the chord is the record
        return 0.0
    a0 = record_at(t0, times, values)
    a1 = record_at(t1, times, values)
    n_in = 0
    for i in range(i0, i1 + 1):
        if t0 < i * dt < t1:
            n_in += 1
    if n_in == 0 and not jump:
        return 0.0
    m = n_in + 2 + (2 if jump else 0)
    tt = np.empty(m)
    f = np.empty(m)
    tt[0], f[0] = t0, a0
    j = 1
    for i in range(i0, i1 + 1):
        ti = i * dt
        if t0 < ti < t1:
            tt[j], f[j] = ti, np.interp(ti, times, values)
            j += 1
    tt[j], f[j] = t1, a1
    if jump:  # a_g falls from the last sample to zero at t_end: the segment split there
        k = 0
        while k < j + 1 and tt[k] <= t_end:
            k += 1
        for i in range(j, k - 1, -1):
            tt[i + 2], f[i + 2] = tt[i], f[i]
        tt[k], f[k] = t_end, values[count - 1]
        tt[k + 1], f[k + 1] = t_end, 0.0
    total = 0.0
    da = f[0] - (a0 + (a1 - a0) * (tt[0] - t0) / (t1 - t0))
    for i in range(m - 1):
        db = f[i + 1] - (a0 + (a1 - a0) * (tt[i + 1] - t0) / (t1 - t0))
        width = abs(da) + abs(db)
        if da * db >= 0.0:
            piece = 0.5 * width
        else:
            piece = 0.5 * (da * da + db * db) / width
        total += piece * (tt[i + 1] - tt[i])
        da = db
    return total


@dataclass
class GroundMotion:
    """One ground acceleration component: samples ``values`` (m/s2) every ``dt`` s from the stage start,
    interpolated linearly in between and zero after the last sample. ``attrs``: provenance (netCDF
    attributes)."""

    component: int
    values: np.ndarray
    dt: float
    name: str = ""
    attrs: dict = field(default_factory=dict)

    def __post_init__(self):
        self.values = np.ascontiguousarray(self.values, dtype=np.float64)
        if self.values.ndim != 1 or len(self.values) < 2:
            raise SceneError(f"ground_motion.{'xyz'[self.component]}", "a record needs at least 2 samples")
        if not np.isfinite(self.values).all():
            raise SceneError(f"ground_motion.{'xyz'[self.component]}", "the record contains NaN or infinity")
        if not (math.isfinite(self.dt) and self.dt > 0):
            raise SceneError(f"ground_motion.{'xyz'[self.component]}.dt", f"must be > 0, got {self.dt!r}")
        self._times = np.arange(len(self.values)) * self.dt

    @property
    def duration(self) -> float:
        return (len(self.values) - 1) * self.dt

    def at(self, t: float) -> float:
        return float(record_at(t, self._times, self.values))

    @property
    def peak_velocity(self) -> float:
        """Peak ground velocity (m/s) of the record as given (trapezoidal integral from rest)."""
        if not hasattr(self, "_pgv"):
            v = np.concatenate(([0.0], np.cumsum(0.5 * (self.values[1:] + self.values[:-1]) * self.dt)))
            self._pgv = float(np.max(np.abs(v)))
        return self._pgv

    def chord_error(self, t0: float, t1: float) -> float:
        """Integral over [t0, t1] of |a_g(t) - chord| (m/s), the chord being the straight line between
        a_g(t0) and a_g(t1): the velocity a step from t0 to t1 misses by taking the ground load as linear
        over the step (the implicit schemes see its ends only). Exact for the piecewise-linear record,
        including its jump to zero after the last sample. Zero when the record is linear over the step."""
        return chord_error(t0, t1, self._times, self.values, self.dt)
