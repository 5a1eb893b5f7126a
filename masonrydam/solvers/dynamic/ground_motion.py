"""A ground acceleration record as the dynamic solver reads it: :class:`GroundMotion`.

One component (x, y or z) of the uniform base excitation, in m/s2, sampled every ``dt`` s from the stage's
start, linear between samples and zero after the last one. The records themselves are read and processed by
:mod:`masonrydam.records`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...errors import SceneError


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
        if t < 0.0 or t > self._times[-1] * (1 + 1e-12):
            return 0.0
        return float(np.interp(t, self._times, self.values))

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
        if t1 <= t0:
            return 0.0
        t_end = self._times[-1] * (1 + 1e-12)
        # breakpoints of a_g inside the step: samples, and the record's end (a jump to zero)
        i0 = int(math.floor(t0 / self.dt)) + 1
        i1 = min(int(math.ceil(t1 / self.dt)) - 1, len(self.values) - 1)
        jump = t0 <= t_end < t1 and self.values[-1] != 0.0
        if i1 < i0 and not jump:  # no sample inside the step (most steps): the chord is the record
            return 0.0
        a0, a1 = self.at(t0), self.at(t1)
        t_in = np.arange(i0, i1 + 1) * self.dt if i1 >= i0 else np.zeros(0)
        t_in = t_in[(t_in > t0) & (t_in < t1)]
        if len(t_in) == 0 and not jump:
            return 0.0
        tt = np.concatenate(([t0], t_in, [t1]))
        f = np.concatenate(([a0], np.interp(t_in, self._times, self.values), [a1]))
        if jump:  # a_g falls from the last sample to zero at t_end: split the segment there
            k = int(np.searchsorted(tt, t_end, side="right"))
            tt = np.concatenate((tt[:k], [t_end, t_end], tt[k:]))
            f = np.concatenate((f[:k], [self.values[-1], 0.0], f[k:]))
        d = f - (a0 + (a1 - a0) * (tt - t0) / (t1 - t0))
        # |d| is linear on each piece: integrated exactly, also where d changes sign inside it (one pass
        # in numpy: a step of dt_max over a pulse sampled at dt_min holds a thousand samples)
        da, db, h = d[:-1], d[1:], np.diff(tt)
        same = da * db >= 0.0
        width = np.abs(da) + np.abs(db)
        piece = np.where(same, 0.5 * width, 0.5 * (da * da + db * db) / np.where(same, 1.0, width))
        return float(np.sum(piece * h))
