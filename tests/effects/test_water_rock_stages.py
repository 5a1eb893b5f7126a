"""What the reservoir, the uplift and the foundation carry from one dynamic stage to the next, the
coupled dam-water modes, and the effect of the uplift options on the response.

A record split into two dynamic stages must give the history of the same record in one stage: the
dynamic equations do not know where a stage ends (the compressible water's pressure and the pore
pressures entered during the shaking are states; the static reactions the absorbing boundaries replace
are loads). The coupled modes of dam and compressible water tend to those with the incompressible
added mass as the sound speed grows (Zienkiewicz & Bettess 1978, IJNME 13:1-16: the water's
compressibility enters through G = (1/c^2) int N^T N).
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

import masonrydam
from test_acoustic_dynamic import rigid_dam
from test_earthquake_water import scene as uplift_scene
from test_foundation_run import column


def _split(scene, stage_index, cut):
    """The scene with its dynamic stage ``stage_index`` (ground motion given as values) split at sample
    ``cut`` into two stages."""
    s = copy.deepcopy(scene)
    st = s["stages"][stage_index]
    gm = st["ground_motion"]["x"]
    dt = gm["dt"]
    vals = gm["values"]
    first = copy.deepcopy(st)
    second = copy.deepcopy(st)
    first["name"], second["name"] = "first", "second"
    first["ground_motion"]["x"] = {"values": vals[:cut + 1], "dt": dt}
    second["ground_motion"]["x"] = {"values": vals[cut:], "dt": dt}
    total = st["duration"] if "duration" in st else (len(vals) - 1) * dt
    first["duration"] = cut * dt
    second["duration"] = total - cut * dt
    s["stages"][stage_index:stage_index + 1] = [first, second]
    return s


def _history(ds, var="displacement"):
    d = ds.where(~np.isnan(ds.time), drop=True)
    t = d.time.values
    keep = np.r_[True, np.diff(t) > 1e-12]  # the second stage records its start again
    return t[keep], d[var].values[keep]


@pytest.mark.slow
def test_compressible_water_carries_over_between_stages():
    dt = 0.002
    t = np.arange(0.0, 0.4 + 1e-12, dt)
    acc = np.where(t < 0.1, np.sin(2 * np.pi * t / 0.1), 0.0) * 3.0
    s = rigid_dam(sound_speed=1440.0, height=10.0, level=10.0, size=1.0, ground={"values": acc.tolist(), "dt": dt},
                  dt=dt)
    s["materials"]["block"]["youngs_modulus"] = 2e10  # a flexible dam: the water and the dam interact
    s["stages"][1]["duration"] = 0.4
    one = masonrydam.run(s)
    two = masonrydam.run(_split(s, 1, 30))
    t1, F1 = _history(one, "hydrodynamic_force")
    t2, F2 = _history(two, "hydrodynamic_force")
    np.testing.assert_allclose(t2, t1, atol=1e-9)
    scale = np.abs(F1).max()
    assert scale > 0
    np.testing.assert_allclose(F2, F1, atol=1e-6 * scale)
    _, u1 = _history(one)
    _, u2 = _history(two)
    np.testing.assert_allclose(u2, u1, atol=1e-6 * np.abs(u1).max())


@pytest.mark.parametrize("rule", ["full_head", "none"])
@pytest.mark.slow
def test_uplift_entered_in_the_shaking_carries_over(rule):
    s = uplift_scene(rule)
    dt = 0.002
    t = np.arange(0.0, 0.3 + 1e-12, dt)
    acc = np.where(t < 0.2, -6.0 * np.sin(np.pi * t / 0.2), 0.0)
    s["stages"][2]["ground_motion"]["x"] = {"values": acc.tolist(), "dt": dt}
    s["stages"][2]["duration"] = 0.3
    one = masonrydam.run(s)
    two = masonrydam.run(_split(s, 2, 60))
    _, u1 = _history(one)
    _, u2 = _history(two)
    # to the Newton tolerance: the second stage starts from the acceleration of its equation of motion,
    # not from the Newmark one (with the crack's pore pressure left out it was off by 1e-3 of the peak)
    np.testing.assert_allclose(u2, u1, atol=1e-4 * np.abs(u1).max())


@pytest.mark.slow
def test_uplift_options_order_the_response():
    """Water entering the opened heel pushes the block further than the static uplift, and a drained
    crack less (crest displacement at the end of the pulse)."""
    peak = {}
    for rule in ("full_head", "static", "none"):
        ds = masonrydam.run(uplift_scene(rule))
        _, u = _history(ds)
        peak[rule] = float(np.abs(u[..., 0]).max())
    assert peak["full_head"] > 1.2 * peak["static"] > 1.2 * 1.2 * peak["none"]


def test_foundation_reactions_are_kept_in_every_stage():
    """Gravity on a rock column with a compliant base, then two dynamic stages without ground motion:
    the column stays at rest (the static reactions at the released base are loads in both stages)."""
    s = column()
    dt = 0.0025
    s["stages"][1]["ground_motion"]["x"] = {"values": [0.0] * 41, "dt": dt}
    s["stages"][1]["duration"] = 0.1
    s["stages"].append(copy.deepcopy(s["stages"][1]))
    s["stages"][2]["name"] = "second"
    ds = masonrydam.run(s)
    _, u = _history(ds)
    _, v = _history(ds, "velocity")
    assert np.abs(v).max() < 1e-9
    assert np.abs(u - u[0]).max() < 1e-9
    assert abs(float(ds.attrs["static_residual_carried"])) < 1e-9


def test_coupled_modes_tend_to_the_added_mass():
    """The coupled dam-water eigenproblem with c = 1e6 m/s gives the modes of the incompressible added
    mass (a flexible dam, H = 10 m: (omega H / c)^2 ~ 1e-5)."""
    def scene(c):
        s = rigid_dam(sound_speed=c, height=10.0, level=10.0, size=1.0, ground={"values": [0.0, 0.0], "dt": 0.01})
        s["materials"]["block"]["youngs_modulus"] = 2e10
        s["stages"][1] = {"name": "modes", "type": "modal", "modes": 3}
        return s
    inc = masonrydam.run(scene("incompressible")).frequency.values
    cmp_ = masonrydam.run(scene(1e6)).frequency.values
    np.testing.assert_allclose(cmp_, inc, rtol=1e-4)
    dry = copy.deepcopy(scene("incompressible"))
    dry["reservoir"]["dynamic"] = "none"
    del dry["reservoir"]["acoustic"]
    assert masonrydam.run(dry).frequency.values[0] > 1.05 * inc[0]  # the water makes the dam slower
