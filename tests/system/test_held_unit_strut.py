"""The strut a held top makes: one unit between a fixed base and a top beam that is pushed sideways
while kept level and at its height, on no-tension joints that do not slide. Against a hand calculation.

The unit (b wide, h high, t thick) and the beams are nearly rigid. Each joint has normal stiffness kn, shear
stiffness ks and no tensile strength: an open point carries nothing (Tzamtzis & Asteris sec. 3.4). Its cohesion is
large, so a compressed point sticks. Pushing the top by u turns the unit by theta about its centre. The configuration is
symmetric under a half turn about that centre, so the centre moves by u/2 and not vertically. The bottom joint
closes over one half of its length and opens over the other, and the top joint does the same on the opposite
side: a diagonal strut. Each joint's closing varies linearly, ``kn theta x`` over ``0 <= x <= b/2``, which gives:

- the normal force of each joint, which is also the vertical force V needed to hold the top at its height:
  ``N = kn theta t b^2 / 8``, acting at b/3 from the centre;
- the unit's moment balance (the two shear forces H, h apart, against the two normal forces, 2b/3 apart):
  ``H h = 2 N b / 3``;
- the shear carried by the closed half of each joint: ``H = ks t (b/2) (u - theta h) / 2``.

Hence ``theta = (ks u / 4) / (kn b^2 / (12 h) + ks h / 4)``. V grows in proportion to u, without a bound: this is
the mechanism that makes the held Eindhoven wall J4D harden past its first peak
(docs/masonry_softening.md, "Why the held wall hardens"). In the model the joints are integrated at Gauss points
(two per element), so that no integration point sits on the neutral axis at the centre.
"""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam

B, H_UNIT, T = 0.2, 0.1, 0.1          # m: the unit's width, height and thickness
KN = KS = 1.0e10                      # Pa/m
E_RIGID = 1.0e14                      # Pa: units and beams nearly rigid against the joints (kn h / E = 1e-5)
U = 1.0e-4                            # m: the push


def held_unit_scene(u: float, steps: int = 4) -> dict:
    blocks = [{"x0": 0.0, "y0": -0.05, "x1": B, "y1": 0.0, "group": "foundation"},
              {"x0": 0.0, "y0": 0.0, "x1": B, "y1": H_UNIT, "group": "unit"},
              {"x0": 0.0, "y0": H_UNIT, "x1": B, "y1": H_UNIT + 0.05, "group": "beam"}]
    rigid = {"youngs_modulus": E_RIGID, "poisson_ratio": 0.0, "density": 0.0}
    return {"model": {"name": "held_unit", "thickness": T},
            "mesh": {"generator": "blocks_2d", "parameters": {"blocks": blocks, "element_size": 0.05}},
            "materials": {g: dict(rigid) for g in ("foundation", "unit", "beam")},
            # no tension, and a cohesion far above any shear stress here: a closed point sticks
            "joints": {"joints": {"normal_stiffness": KN, "shear_stiffness": KS, "friction_angle": 30.0,
                                  "cohesion": 1.0e9, "tensile_strength": 0.0, "integration": "gauss"}},
            "supports": [{"set": "base", "components": ["x", "y"]}],  # the foundation's bottom edge
            "stages": [{"name": "push", "steps": steps, "loads": [
                {"type": "displacement", "set": "top", "components": ["x", "y"], "value": [u, 0.0]}]}],
            "output": {"nodes": "all", "joints": "all"}}


def hand_calculation(u: float):
    """``(theta, V, H)``: the unit's rotation (rad), the vertical force holding the top (N, compression) and the
    horizontal force (N) of the module docstring."""
    theta = (KS * u / 4.0) / (KN * B ** 2 / (12.0 * H_UNIT) + KS * H_UNIT / 4.0)
    normal = KN * theta * T * B ** 2 / 8.0
    return theta, normal, 2.0 * normal * B / (3.0 * H_UNIT)


def test_a_held_unit_on_no_tension_joints_makes_a_strut_as_the_hand_calculation():
    ds = masonrydam.run(held_unit_scene(U))
    top = ds.driven.sel(component="x").values > 0
    horizontal = ds.reaction.sel(component="x").values[-1, top].sum()
    vertical = ds.reaction.sel(component="y").values[-1, top].sum()
    theta, v_hand, h_hand = hand_calculation(U)
    # within the blocks' own compliance (kn h / E = 1e-5 of the joints'): 1.5e-5 and 2e-5 here
    assert horizontal == pytest.approx(h_hand, rel=1e-4)
    assert -vertical == pytest.approx(v_hand, rel=1e-4)  # the beam pushes down on the unit: compression
    # half of each joint is open, on opposite sides: the bottom joint closed where the top one is open
    state = ds.joint_state.values[-1]
    y, x = ds.joint_y.values, ds.joint_x.values
    bottom, upper = np.isclose(y, 0.0), np.isclose(y, H_UNIT)
    assert (state[bottom] == 2).sum() == (state[bottom] != 2).sum() == bottom.sum() // 2
    assert set(np.round(x[bottom][state[bottom] == 2], 6)) == set(np.round(x[upper][state[upper] != 2], 6))
    # V grows in proportion to the push (no bound): twice the push, twice the force
    ds2 = masonrydam.run(held_unit_scene(2.0 * U))
    vertical2 = ds2.reaction.sel(component="y").values[-1, top].sum()
    assert vertical2 == pytest.approx(2.0 * vertical, rel=1e-6)
    # the unit turned by theta: the largest opening is theta times the outermost Gauss point's distance from the
    # centre, (b - L) / 2 + L / (2 sqrt 3) with elements of L = 0.05 m
    length = 0.05
    far = (B - length) / 2.0 + length / (2.0 * np.sqrt(3.0))
    assert ds.joint_opening.values[-1].max() == pytest.approx(theta * far, rel=1e-4)
