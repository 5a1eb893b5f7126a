"""The modal stage: ``{ type = "modal", modes = N }`` after the static stages, on
their state. Checked against the closed forms of a rigid block on an elastic joint (a rigid body on
distributed springs: Chopra, Dynamics of Structures, 4th ed., sec. 10.2 for the eigenproblem; the
springs are the joint's normal and shear stiffness times its lumped point areas): the vertical mode
omega^2 = kn A / m with the block's whole mass as effective mass, and the two coupled sliding-rocking
modes of the 2 x 2 problem on (slip u at the joint, rotation theta). With lumped mass the block's
rotary inertia is that of its nodal masses (trapezoid sums over the grid, O(h^2) below m (B^2 + H^2) / 12)."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import masonrydam
from masonrydam.errors import SceneError

from scenes import ELASTIC_JOINT_BLOCK as BLOCK, block_on_elastic_joint

B, H, RHO, T, HE = BLOCK.width, BLOCK.height, BLOCK.density, BLOCK.thickness, BLOCK.element_size
KN, KS = BLOCK.normal_stiffness, BLOCK.shear_stiffness


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_rigid_block_on_a_joint(mass):
    ds = masonrydam.run(block_on_elastic_joint(mass=mass))
    m = RHO * B * H * T
    A = B * T
    # lumped joint points at the nodes: trapezoid weights along the base
    x = np.arange(0.0, B + 1e-9, HE)
    w = np.full(len(x), HE * T)
    w[[0, -1]] *= 0.5
    k_theta = KN * float(np.sum(w * (x - B / 2) ** 2))
    J = m * (B * B + H * H) / 12.0
    if mass == "lumped":  # the nodal masses of the block's grid (trapezoid weights) carry its rotary inertia
        y = np.arange(0.0, H + 1e-9, HE)
        wy = np.full(len(y), HE)
        wy[[0, -1]] *= 0.5
        wx = w / T
        J = RHO * T * float(np.sum(np.outer(wx, wy) * ((x[:, None] - B / 2) ** 2 + (y[None, :] - H / 2) ** 2)))
    # DOFs: slip u of the block at the joint, rotation theta about the base centre; centroid at H/2
    M2 = np.array([[m, m * H / 2], [m * H / 2, J + m * H * H / 4]])
    K2 = np.diag([KS * A, k_theta])
    w2 = np.sqrt(scipy.linalg.eigh(K2, M2, eigvals_only=True))
    f_vertical = np.sqrt(KN * A / m) / (2 * np.pi)
    expected = np.sort(np.concatenate([w2 / (2 * np.pi), [f_vertical]]))
    f = ds.frequency.values
    np.testing.assert_allclose(f[:3], expected, rtol=2e-4)
    k = int(np.argmin(np.abs(f - f_vertical)))
    ey = ds.effective_mass.sel(component="y").values[k]
    assert ey == pytest.approx(m, rel=2e-4)
    assert ds.period.values[k] == pytest.approx(1.0 / f_vertical, rel=2e-4)
    # the vertical mode moves the block only vertically: its x effective mass is nil
    assert ds.effective_mass.sel(component="x").values[k] < 1e-6 * m
    assert ds.mode_shape.dims == ("mode", "node", "component")
    assert "modal stage 'modes': 6 lowest modes" in ds.attrs["simulated_effects"]


def test_modal_stage_order_and_keys():
    s = block_on_elastic_joint()
    s["stages"] = [s["stages"][1], s["stages"][0]]
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].type"
    s = block_on_elastic_joint()
    s["stages"][1]["modes"] = 0
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].modes"
