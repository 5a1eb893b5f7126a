"""Pulse shapes: the one definition behind a ground-motion pulse (``stages.ground_motion.<axis>.pulse``,
sampled at the analysis step by :func:`pulse_samples`) and a dynamic load's pulse time function
(``time_function = { type = "pulse" }``, evaluated at any time by :func:`unit_pulse`).

With ``s`` the time since the pulse started and ``t_d`` its duration, every shape is zero for ``s < 0`` and
``s > t_d`` and has the peak 1; for ``0 <= s <= t_d`` (Chopra, *Dynamics of Structures*, 4th ed. 2012,
secs. 4.7 to 4.9, where they are the rectangular, half-cycle sine and symmetrical triangular pulse forces):

- ``rectangular``: ``1``; integral ``t_d``;
- ``half_sine``: ``sin(pi s / t_d)``, peak at ``s = t_d / 2``; integral ``2 t_d / pi``;
- ``triangular``: ``1 - |2 s / t_d - 1|``, rising linearly to the peak at ``s = t_d / 2`` and falling back
  to zero at ``t_d``; integral ``t_d / 2``.

This module sits at the bottom of the package (it imports numpy only), so that the scene schema, the
effects and the records may all read it without importing obspy.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["PULSE_SHAPES", "unit_pulse", "pulse_samples"]

#: the pulse shapes (see the module docstring for their formulas)
PULSE_SHAPES = ("rectangular", "half_sine", "triangular")


def unit_pulse(shape: str, time_since_start: float, duration: float) -> float:
    """The pulse ``shape`` of peak 1 and length ``duration`` (s) at ``time_since_start`` (s): zero before 0
    and after ``duration`` (formulas in the module docstring)."""
    s = time_since_start
    if s < 0.0 or s > duration:
        return 0.0
    if shape == "rectangular":
        return 1.0
    if shape == "half_sine":
        return math.sin(math.pi * s / duration)
    if shape == "triangular":
        return 1.0 - abs(2.0 * s / duration - 1.0)
    raise ValueError(f"unknown pulse shape {shape!r}; use one of {PULSE_SHAPES}")


def pulse_samples(shape: str, amplitude: float, duration: float, dt: float) -> np.ndarray:
    """Samples (n,) every ``dt`` (s) from t = 0 of the pulse ``shape`` of peak ``amplitude`` and length
    ``duration`` (s), followed by one zero sample (a ground acceleration given in the scene).

    - rectangular: a zero sample at t = 0 (the structure starts at rest), then ``amplitude`` for
      ``floor(duration / dt)`` samples and one sample with the remainder, so that the trapezoidal
      integral of the samples is the impulse ``amplitude * duration``. The linear interpolation of the
      samples is the pulse from t = dt/2 to dt/2 + duration with its two jumps spread over one dt each
      (same impulse; the time shift does not change the response).
    - half_sine, triangular: ``amplitude`` times :func:`unit_pulse` at t = k dt for 0 <= t <= duration,
      zero after (a triangle whose peak falls on a sample, ``duration / (2 dt)`` a whole number, is
      reproduced exactly by the linear interpolation of the samples).

    Raises ValueError for a rectangular pulse shorter than ``dt``.
    """
    if shape == "rectangular":
        n = int(math.floor(duration / dt + 1e-9))
        frac = max(duration / dt - n, 0.0)  # in [0, 1)
        if n == 0:
            raise ValueError(f"the pulse ({duration:g} s) is shorter than dt ({dt:g} s)")
        # 0, n x amplitude, [frac x amplitude], 0: trapezoidal integral = amplitude (n + frac) dt
        vals = [0.0] + [amplitude] * n + ([amplitude * frac] if frac > 1e-9 else []) + [0.0]
        return np.array(vals)
    if shape not in PULSE_SHAPES:
        raise ValueError(f"unknown pulse shape {shape!r}; use one of {PULSE_SHAPES}")
    n = int(math.ceil(duration / dt - 1e-9))
    t = np.arange(n + 2) * dt
    # a sample a round-off past the end still takes the pulse's end value
    end = duration * (1 + 1e-12)
    vals = np.array([amplitude * unit_pulse(shape, min(tk, duration), duration) if tk <= end else 0.0
                     for tk in t.tolist()])
    vals[-1] = 0.0
    return vals
