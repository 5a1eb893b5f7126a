"""Loads given in time in dynamic stages (masonrydam.effects.dynamic_loads): nodal forces, tractions and
pressures times a time function (table, file, pulse, harmonic).

Closed forms (Chopra, Dynamics of Structures, 4th ed., 2012): an undamped oscillator of mass m and stiffness k
at rest, under a force F suddenly applied at t = 0 and held, moves as u = F/k (1 - cos(omega t)) (eq. 4.3.2:
twice the static displacement at its peak); under F sin(Omega t) from rest, u = F/k / (1 - b^2) (sin(Omega t) -
b sin(omega t)), b = Omega / omega (eq. 3.1.6). The oscillator: a stiff 1 x 1 m block (1000 kg) on a linear
joint of normal stiffness kn over 1 m (k = kn), pressed by a uniform pressure on its top edge (no rocking).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
import scenes
from masonrydam.effects.dynamic_loads import TimeFunction, normalize_time_function
from masonrydam.errors import SceneError

KN, RHO, P = 1.0e9, 1000.0, 1.0e5  # Pa/m, kg/m3, Pa: k = 1e9 N/m, m = 1000 kg, F = 1e5 N
OMEGA = math.sqrt(KN / RHO)  # 1000 rad/s


def oscillator(time_function, steps=300, dt=6e-5, integrator="newmark_average"):
    return scenes.oscillator({"dt": dt, "steps": steps, "integrator": integrator,
                              "loads": [{"type": "edge_pressure", "set": "top_edge", "pressure": P,
                                         "time_function": time_function}]}, normal_stiffness=KN, density=RHO)


def top_history(ds):
    top = ds.y.values > 1.0 - 1e-9
    dyn = np.isfinite(ds.time.values)
    return ds.time.values[dyn], -ds.displacement.sel(component="y").values[dyn][:, top].mean(axis=1)


def test_suddenly_applied_force_doubles_the_static_displacement():
    ds = masonrydam.run(oscillator({"type": "pulse", "shape": "rectangular", "duration": 1.0}))
    t, u = top_history(ds)
    closed = P / KN * (1.0 - np.cos(OMEGA * t))
    assert np.abs(u - closed).max() <= 0.01 * 2 * P / KN
    assert u.max() == pytest.approx(2 * P / KN, rel=0.01)
    assert "loads given in time" in ds.attrs["simulated_effects"]


def test_harmonic_force_from_rest():
    b = 0.5
    ds = masonrydam.run(oscillator({"type": "harmonic", "frequency": b * OMEGA / (2 * math.pi)}, steps=400))
    t, u = top_history(ds)
    closed = P / KN / (1 - b * b) * (np.sin(b * OMEGA * t) - b * np.sin(OMEGA * t))
    assert np.abs(u - closed).max() <= 0.01 * np.abs(closed).max()


def test_time_functions():
    def at(spec, times, base_dir=None):
        tf = TimeFunction.build(normalize_time_function(spec, "tf"), "tf", base_dir)
        return np.array([tf.at(x) for x in times])

    np.testing.assert_allclose(at({"type": "table", "time": [0, 1, 2], "values": [0, 2, 0]}, [-1, 0.5, 1.5, 3]),
                               [0, 1, 1, 0])
    np.testing.assert_allclose(at({"type": "pulse", "shape": "half_sine", "duration": 0.2, "start": 0.1},
                                  [0.05, 0.2, 0.25, 0.35]), [0, 1, math.sin(0.75 * math.pi), 0], atol=1e-12)
    np.testing.assert_allclose(at({"type": "pulse", "shape": "triangular", "duration": 2.0}, [0.5, 1, 1.5, 2.5]),
                               [0.5, 1, 0.5, 0])
    np.testing.assert_allclose(at({"type": "harmonic", "frequency": 1.0, "phase": 90, "start": 1, "duration": 2},
                                  [0.5, 1.0, 1.25, 3.5]), [0, 1, 0, 0], atol=1e-12)


def test_time_function_from_a_file(tmp_path):
    (tmp_path / "blast.txt").write_text("# t (s)  p (-)\n0 0\n0.01 1\n0.03 0\n")
    spec = {"type": "file", "path": "blast.txt", "column": 0}
    tf = TimeFunction.build(normalize_time_function(spec, "tf"), "tf", tmp_path)
    assert tf.at(0.005) == pytest.approx(0.5) and tf.at(0.02) == pytest.approx(0.5) and tf.at(1.0) == 0.0
    with pytest.raises(SceneError) as err:
        TimeFunction.build(normalize_time_function(dict(spec, column=1), "tf"), "tf", tmp_path)
    assert err.value.key == "tf.column"
    with pytest.raises(SceneError) as err:
        TimeFunction.build(normalize_time_function(dict(spec, path="none.txt"), "tf"), "tf", tmp_path)
    assert err.value.key == "tf.path"


@pytest.mark.parametrize("change, key", [
    ({"time_function": None}, "stages[1].loads[0].time_function"),
    ({"time_function": {"type": "chirp"}}, "stages[1].loads[0].time_function.type"),
    ({"time_function": {"type": "pulse"}}, "stages[1].loads[0].time_function.duration"),
    ({"time_function": {"type": "table", "time": [0, 0], "values": [1, 2]}}, "stages[1].loads[0].time_function.time"),
    ({"time_function": {"type": "harmonic", "frequency": -1}}, "stages[1].loads[0].time_function.frequency"),
    ({"type": "displacement"}, "stages[1].loads[0].type"),
    ({"set": "nowhere"}, "stages[1].loads[0].set"),
])
def test_bad_dynamic_loads_are_named(change, key):
    s = oscillator({"type": "pulse", "duration": 1.0}, steps=2)
    load = s["stages"][1]["loads"][0]
    load.update(change)
    if load.get("time_function", 1) is None:
        del load["time_function"]
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == key


def test_released_from_an_initial_displacement():
    """The oscillator released from rest at u0 (the block pushed down 0.1 mm onto its joint, the static state
    undisplaced) swings as u0 cos(omega t) (Chopra eq. 2.1.3 with zero initial velocity)."""
    u0 = 1e-4
    s = oscillator({"type": "pulse", "duration": 1.0})
    st = s["stages"][1]
    del st["loads"]
    st["initial_displacement"] = {"groups": ["block"], "displacement": [0.0, -u0]}
    ds = masonrydam.run(s)
    t, u = top_history(ds)
    assert t[0] == 0.0 and u[0] == pytest.approx(u0, rel=1e-9)
    np.testing.assert_allclose(u, u0 * np.cos(OMEGA * t), atol=0.01 * u0)
    assert "released from an initial displacement" in ds.attrs["simulated_effects"]
    st["initial_displacement"] = {"groups": ["wall"], "displacement": [0.0, -u0]}
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].initial_displacement.groups"
    st["initial_displacement"] = {"groups": ["block"], "rotation": 0.001}
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].initial_displacement.rotation_center"


def test_a_step_that_could_pass_over_the_load_is_refused():
    """A 2 ms pulse between the ends of 10 ms steps would never be seen (both ends give zero force)."""
    s = oscillator({"type": "pulse", "duration": 0.002, "start": 0.001}, dt=0.01, steps=3)
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].dt" and "0.0005" in str(err.value)
    s["stages"][1].update(dt="auto", dt_max=0.01)
    del s["stages"][1]["steps"]
    s["stages"][1]["duration"] = 0.02
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].dt_max"


def test_release_past_the_friction_limit_dissipates():
    """A block on a Mohr-Coulomb joint (mu = 0.2) under gravity, released 1 mm sideways (far past its elastic
    slip, mu m g / (ks A) = 2 um): the start is a sliding state (committed), so friction only dissipates and
    the kinetic energy never exceeds the elastic energy the joint held at the start, (mu m g)^2 / (2 ks A)."""
    s = oscillator({"type": "pulse", "duration": 1.0}, steps=200)
    s["model"]["gravity"] = [0.0, -9.80665]
    s["joints"]["joints"] = {"law": "mohr_coulomb", "normal_stiffness": KN, "shear_stiffness": KN,
                             "friction_angle": math.degrees(math.atan(0.2))}
    s["stages"][0]["loads"] = [{"type": "self_weight"}]
    st = s["stages"][1]
    del st["loads"]
    st["initial_displacement"] = {"groups": ["block"], "displacement": ["1 mm", 0.0]}
    ds = masonrydam.run(s)
    dyn = np.isfinite(ds.time.values)
    assert ds.energy_joint_friction.values[dyn].min() >= -1e-9
    stored = (0.2 * RHO * 9.80665) ** 2 / (2 * KN)
    assert ds.energy_kinetic.values[dyn].max() <= 1.01 * stored
