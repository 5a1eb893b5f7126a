"""Initial velocities of a dynamic stage (``initial_velocity``): a translation or a
rigid rotation of element groups at the start of the stage, with or without ground motion.

A block launched along a Coulomb joint stops after v0^2 / (2 g tan(phi)) in v0 / (g tan(phi))
(constant deceleration mu g: Newton's second law with Coulomb friction, e.g. Meriam & Kraige,
Engineering Mechanics: Dynamics, sec. 3/4); nothing else moves it.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import SceneError

G = 9.80665
PHI = 30.0


def scene(iv, duration=0.3, dt=0.001):
    return {
        "model": {"name": "launched_block", "thickness": 1.0},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
            {"x0": 0.0, "y0": -0.25, "x1": 1.0, "y1": 0.0, "group": "base"},
            {"x0": 0.0, "y0": 0.0, "x1": 1.0, "y1": 0.5, "group": "block"}]}},
        "materials": {g: {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2400.0} for g in ("base", "block")},
        "joints": {"joints": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": PHI}},
        "supports": [{"set": "base"}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "slide", "type": "dynamic", "dt": dt, "duration": duration, "integrator": "hht",
                    "initial_velocity": iv, "output": {"stride": 5}}],
    }


def test_a_launched_block_stops_after_the_coulomb_distance():
    v0 = 1.0
    ds = masonrydam.run(scene({"groups": ["block"], "velocity": [v0, 0.0]}))
    dyn = ds.where(~np.isnan(ds.time), drop=True)
    top = ds.y.values > 0.49
    u = dyn.displacement.sel(component="x").values[:, top].mean(axis=1)
    v = dyn.velocity.sel(component="x").values[:, top].mean(axis=1)
    mu = math.tan(math.radians(PHI))
    assert v[0] == pytest.approx(v0, rel=1e-12)
    assert u[-1] == pytest.approx(v0**2 / (2 * G * mu), rel=0.01)
    t = dyn.time.values
    stop = t[np.argmax(np.abs(v) < 0.01 * v0)]
    assert stop == pytest.approx(v0 / (G * mu), abs=0.01)
    assert "initial velocity [1.0, 0.0] m/s of block" in ds.attrs["simulated_effects"]
    assert "no ground motion" in ds.attrs["simulated_effects"]


def test_rigid_rotation_field():
    w, c = 0.5, [0.5, 0.25]
    ds = masonrydam.run(scene({"groups": "block", "angular_velocity": w, "rotation_center": c}, duration=0.002))
    first = ds.where(~np.isnan(ds.time), drop=True).isel(step=0)
    x, y = ds.x.values, ds.y.values
    block = y > 1e-9
    vel = first.velocity.values
    np.testing.assert_allclose(vel[block, 0], -w * (y[block] - c[1]), atol=1e-12)
    np.testing.assert_allclose(vel[block, 1], w * (x[block] - c[0]), atol=1e-12)
    assert np.abs(vel[y < -1e-9]).max() == 0.0  # the supported base does not move


def test_bad_initial_velocity():
    for iv, key in (({"groups": ["nope"], "velocity": [1.0, 0.0]}, "stages[1].initial_velocity.groups"),
                    ({"groups": ["block"], "velocity": [1.0]}, "stages[1].initial_velocity.velocity"),
                    ({"groups": ["block"], "angular_velocity": 1.0}, "stages[1].initial_velocity.rotation_center"),
                    ({"groups": ["block"], "velocity": [1.0, 0.0], "angular_velocity": 1.0},
                     "stages[1].initial_velocity")):
        with pytest.raises(SceneError) as err:
            masonrydam.run(scene(iv))
        assert err.value.key == key
    s = scene({"groups": ["block"], "velocity": [1.0, 0.0]})
    del s["stages"][1]["duration"]
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].duration"
