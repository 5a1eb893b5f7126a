"""Uplift during an earthquake (``[reservoir] uplift.earthquake``): the options of
CADAM3D (Leclerc, Leger & Tinawi 2003, Adv. Eng. Softw. 34:583-601; user's manual sec. 3.6) and the FERC
Engineering Guidelines ch. 3 sec. 3-8.2: the pore pressure kept at its static value, the full
reservoir pressure entering the joint where it opens, or none there.

A slender block on a dry, cohesionless joint with the reservoir on its upstream face is rocked
downstream by a ground acceleration pulse: its heel opens. The pore pressure at an open point must
then be rho_w g (level - z) with "full_head" (the joint is at z = 0), zero with "none", and the static
profile (linear from the heel to the toe, hydrostatics) with "static".
"""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam

LEVEL, B, H = 0.75, 0.5, 1.0
GAMMA = 1000.0 * 9.80665  # the default gravity of [model]


def scene(rule):
    return {
        "model": {"name": "rocking_uplift", "thickness": 1.0},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.125, "blocks": [
            {"x0": 0.0, "y0": -0.25, "x1": B, "y1": 0.0, "group": "base"},
            {"x0": 0.0, "y0": 0.0, "x1": B, "y1": H, "group": "block"}]}},
        "materials": {"base": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2400.0},
                      "block": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2400.0}},
        "joints": {"joints": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": 60.0}},
        "reservoir": {"level": LEVEL, "face": "left_edge",
                      "uplift": {"joints": ["joints"], "cracked": "full_head", "earthquake": rule}},
        "supports": [{"set": "base"}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "water", "steps": 2, "loads": [{"type": "reservoir"}]},
                   {"name": "quake", "type": "dynamic", "dt": 0.002, "duration": 0.3, "integrator": "hht",
                    "ground_motion": {"x": {"pulse": {"shape": "half_sine", "amplitude": -6.0, "duration": 0.2}}}}],
    }


@pytest.mark.parametrize("rule", ["full_head", "none", "static"])
def test_pore_pressure_in_opening_joints(rule):
    ds = masonrydam.run(scene(rule))
    dyn = ds.where(~np.isnan(ds.time), drop=True)
    state = dyn.joint_state.values
    p = dyn.joint_pore_pressure.values
    x = ds.joint_x.values
    opened = state == 2
    assert opened.any(), "the pulse must open the heel"
    # the heel: open points at the upstream end
    k = int(np.argmax(opened.sum(axis=1)))
    heel_open = opened[k] & (x < 0.5 * B)
    assert heel_open.any()
    # the pore pressure is updated at the start of each step from the committed state: compare at the step
    # after, where the opening has persisted
    both = opened[k] & opened[k - 1] & (x < 0.5 * B)
    static = ds.joint_pore_pressure.values[np.isnan(ds.time.values)][-1]
    if rule == "full_head":
        np.testing.assert_allclose(p[k][both], GAMMA * LEVEL, rtol=1e-9)
    elif rule == "none":
        np.testing.assert_allclose(p[k][both], 0.0, atol=1e-9)
    else:
        np.testing.assert_allclose(p[k], static, rtol=1e-12)
    assert "uplift in the dynamic stages" in ds.attrs["simulated_effects"]
