"""A 3D cohesive joint driven through zero normal stress.

The static stages of 3D dams stalled where points of a joint sat at almost zero normal stress: with cohesion
``c`` and no tensile strength the Mohr-Coulomb joint (Tzamtzis & Asteris sec. 3.4, eq. 12) jumps there from a
shear strength ``c`` (closed, bond intact) to none (open, bond broken), and a point at the tip of a crack flipped
across that jump from one joint-space Newton iterate to the next. The joint space now latches the bond of such a
point broken for the step (``JointSpace._bond_chatter``). These tests drive a block on a cohesive joint (kn = ks
= 1e11 Pa/m, phi = 45 deg, c = 0.5 MPa, ft = 0, no weight) through a small opening with shear in both
directions, then a small closure with shear, and check the closed form of the law: open, every traction is
zero; closed again on the broken bond, every point slides with ``|tau| = -t_n tan(phi)`` along the shear
displacement; and the block's equilibrium (reaction on the driven face = joint force).
"""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam
from masonrydam.materials import mohr_coulomb as mc
from masonrydam.solvers.joint_space import condensation as js_module
from scenes import driven_block_on_cohesive_joint

TAN_PHI = 1.0  # phi = 45 deg
KN = 1e11


def _scene():
    return driven_block_on_cohesive_joint("zero_stress", [("open", [2e-6, 1e-6, 1e-6]), ("close", [4e-6, 3e-6, -2.5e-6])],
                                          normal_stiffness=KN)


@pytest.fixture(scope="module")
def result():
    return masonrydam.run(_scene())


def test_an_opened_cohesive_joint_carries_nothing(result):
    """Stage "open": every point is open (state 2) and carries no traction (Tzamtzis & Asteris sec. 3.4); the block, held
    only by the drive, needs no force there."""
    step = result.isel(step=int(np.flatnonzero(result.stage.values == 0)[-1]))
    assert (step.joint_state.values == mc.OPEN).all()
    assert not np.abs(step.joint_traction_normal.values).any()
    assert not np.abs(step.joint_traction_shear.values).any()
    assert np.abs(step.reaction.values).max() <= 1e-6 * KN * 1e-6


def test_closed_on_a_broken_bond_every_point_slides_at_the_friction_limit(result):
    """Stage "close": the joint closes (t_n < 0) on the bonds that broke, so ``c = 0`` and every point slides
    with ``|tau| = -t_n tan(phi)`` (Tzamtzis & Asteris eq. 12) along the shear displacement; the reaction on the driven
    face balances the joint force."""
    step = result.isel(step=-1)
    t_n = step.joint_traction_normal.values
    tau = np.atleast_2d(step.joint_traction_shear.values.reshape(t_n.shape[0], -1))
    assert (t_n < 0).all()
    assert (step.joint_state.values == mc.SLIP).all()
    np.testing.assert_allclose(np.linalg.norm(tau, axis=1), -t_n * TAN_PHI, rtol=1e-6)
    w = step.joint_weight.values if "step" not in result.joint_weight.dims else step.joint_weight.values
    normal = np.column_stack([result[f"joint_normal_{a}"].values for a in "xyz"])
    # the joint's normal force on the block (N) against the drive's reaction on the top face
    joint_force_z = float(np.sum(w * t_n * normal[:, 2]))
    react = step.reaction.values.reshape(-1, 3)
    top = np.isclose(result.z.values, result.z.values.max())
    # the drive pulls the block down onto the joint as hard as the joint pushes it up (-w t_n on +n)
    assert joint_force_z < 0
    assert abs(react[top, 2].sum() - joint_force_z) <= 1e-6 * abs(joint_force_z)


def test_bond_chatter_latches_only_flipping_points_whose_bond_broke():
    """``JointSpace._bond_chatter``: a point is latched broken only after FLIPS_BEFORE_LATCH state changes in
    the step, with its bond broken in one of the step's iterates and intact in the committed base."""
    from types import SimpleNamespace

    from masonrydam.materials.joint_laws import joint_law

    law = joint_law("mohr_coulomb")
    base = np.zeros((4, mc.N_JOINT_STATE))
    base[3, mc.S_BOND_BROKEN] = 1.0  # already broken when the step starts: nothing to latch
    broke = np.zeros_like(base)
    broke[[0, 1, 3], mc.S_BOND_BROKEN] = 1.0
    fake = SimpleNamespace(law=law, base=base, n_points=4, static=True)
    flips = np.array([js_module.FLIPS_BEFORE_LATCH, js_module.FLIPS_BEFORE_LATCH - 1, 5, 5])
    assert js_module.JointSpace._latches(fake)
    assert js_module.JointSpace._bond_chatter(fake, flips, broke).tolist() == [True, False, False, False]
    # a dynamic step's joint space never latches (it keeps no broken bonds): its histories stay those of the
    # hold-and-release
    fake.static = False
    assert not js_module.JointSpace._latches(fake)
    assert not js_module.JointSpace._bond_chatter(fake, flips, None).any()
