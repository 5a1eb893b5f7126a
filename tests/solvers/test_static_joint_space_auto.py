"""The static joint space with ``linear_solver = "auto"`` where the general path takes AMG.

A 3D model of ``AUTO_ITERATIVE_MIN_DOF`` equations or more gets AMG on the general Newton path. Its static stages
are still condensed on the joints (one L D L^T factorization of the all-stick stiffness) up to
``STATIC_JOINT_SPACE_AUTO_MAX_EQUATIONS`` equations: AMG on a tangent with sliding and open joints converges badly,
and the 20-monolith dam of ``examples/dam_3d_reservoir.toml`` (60 258 equations) filled its reservoir in 54 s
condensed against more than 900 s on the AMG path. An explicit ``linear_solver = "amg"`` keeps the general path
alone.
Here the threshold of AMG is lowered so that a small block on a cohesive joint, sheared and lifted, crosses it.
"""
from __future__ import annotations

import numpy as np

import masonrydam
from masonrydam.solvers.linear import direct
from masonrydam.solvers.static import stepping
from scenes import driven_block_on_cohesive_joint


def _scene():
    return driven_block_on_cohesive_joint("auto_amg", [("shear", [2e-5, 1e-5, -1e-6]), ("lift", [3e-5, 1e-5, 2e-6])])


def test_auto_condenses_where_the_general_path_takes_amg(monkeypatch):
    direct_run = masonrydam.run(_scene())
    assert int(direct_run.attrs["joint_space_steps"]) > 0
    monkeypatch.setattr(direct, "AUTO_ITERATIVE_MIN_DOF", 10)
    auto = masonrydam.run(_scene())
    assert int(auto.attrs["joint_space_steps"]) == int(direct_run.attrs["joint_space_steps"])
    np.testing.assert_array_equal(auto.joint_state.values, direct_run.joint_state.values)
    u, u_ref = auto.displacement.values, direct_run.displacement.values
    assert np.abs(u - u_ref).max() <= 1e-9 * np.abs(u_ref).max()
    # above the limit (as before this rule at any size): the general path alone
    monkeypatch.setattr(stepping, "STATIC_JOINT_SPACE_AUTO_MAX_EQUATIONS", 10)
    assert int(masonrydam.run(_scene()).attrs["joint_space_steps"]) == 0
