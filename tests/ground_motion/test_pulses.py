"""The one pulse definition (masonrydam.pulses) against the closed forms of each shape (Chopra, Dynamics of
Structures, 2012, secs. 4.7-4.9): peak, duration and integral, evaluated (a dynamic load's time function)
and sampled (a ground-motion pulse); and the scene's choices read from it."""
from __future__ import annotations

import math

import numpy as np
import pytest

from masonrydam.effects import dynamic_loads
from masonrydam.pulses import PULSE_SHAPES, pulse_samples, unit_pulse
from masonrydam.scene import reference, schema

#: shape -> (time of the peak as a fraction of the duration, integral of the unit pulse / duration)
CLOSED_FORMS = {"rectangular": (0.5, 1.0), "half_sine": (0.5, 2.0 / math.pi), "triangular": (0.5, 0.5)}


def test_every_shape_has_its_closed_form():
    assert set(PULSE_SHAPES) == set(CLOSED_FORMS)


@pytest.mark.parametrize("shape", PULSE_SHAPES)
@pytest.mark.parametrize("duration", [0.05, 0.37])
def test_unit_pulse_peak_duration_and_integral(shape, duration):
    at_peak, integral = CLOSED_FORMS[shape]
    assert unit_pulse(shape, at_peak * duration, duration) == pytest.approx(1.0, rel=1e-15)
    assert unit_pulse(shape, -1e-9, duration) == 0.0
    assert unit_pulse(shape, duration * (1 + 1e-9), duration) == 0.0
    # the integral by Simpson's rule on a grid with a node at the peak (exact for the rectangle and the
    # triangle, within 1e-13 for the sine)
    n = 2000
    t = np.linspace(0.0, duration, n + 1)
    v = np.array([unit_pulse(shape, float(s), duration) for s in t])
    assert v.max() == pytest.approx(1.0, rel=1e-12) and v.min() >= -1e-15  # sin(pi) at the end
    h = duration / n
    simpson = h / 3.0 * (v[0] + v[-1] + 4.0 * v[1:-1:2].sum() + 2.0 * v[2:-1:2].sum())
    assert simpson == pytest.approx(integral * duration, rel=1e-12)


def test_unit_pulse_refuses_an_unknown_shape():
    with pytest.raises(ValueError, match="unknown pulse shape"):
        unit_pulse("gaussian", 0.1, 1.0)


@pytest.mark.parametrize("duration,dt", [(0.2, 0.001), (0.2, 3.1e-4), (0.0137, 0.0005)])
def test_rectangular_samples_keep_the_impulse(duration, dt):
    a = 3.92
    v = pulse_samples("rectangular", a, duration, dt)
    assert v[0] == 0.0 and v[-1] == 0.0 and v.max() == a
    assert np.trapezoid(v, dx=dt) == pytest.approx(a * duration, rel=1e-12)


@pytest.mark.parametrize("shape", ["half_sine", "triangular"])
def test_sampled_pulses_peak_end_and_integral(shape):
    a, duration, dt = 2.5, 0.2, 0.001  # duration / (2 dt) a whole number: a sample at the peak
    v = pulse_samples(shape, a, duration, dt)
    n = round(duration / dt)
    assert len(v) == n + 2 and v[0] == 0.0 and v[-1] == 0.0
    assert v[n // 2] == pytest.approx(a, rel=1e-15) and v.max() == pytest.approx(a, rel=1e-15)
    at_peak, integral = CLOSED_FORMS[shape]
    trapezoid = np.trapezoid(v, dx=dt)
    if shape == "triangular":  # the linear interpolation of the samples is the triangle itself
        assert trapezoid == pytest.approx(a * integral * duration, rel=1e-12)
    else:  # the trapezoidal rule's error on a sine: (pi dt / duration)^2 / 12 relative
        assert trapezoid == pytest.approx(a * integral * duration, rel=(math.pi * dt / duration) ** 2 / 10)


def test_a_rectangular_pulse_shorter_than_dt_is_refused():
    with pytest.raises(ValueError, match="shorter than dt"):
        pulse_samples("rectangular", 1.0, 0.001, 0.01)


def test_the_scene_reads_its_pulse_shapes_from_the_one_list():
    assert schema.PULSE_SHAPES is PULSE_SHAPES
    assert dynamic_loads.PULSE_SHAPES is PULSE_SHAPES
    assert reference.PULSE_SHAPES is PULSE_SHAPES
