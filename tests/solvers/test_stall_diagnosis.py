"""The words a static step that does not converge ends with: where its last Newton iterate is out of
balance, and which joint points its next correction would switch (``solvers.diagnostics.newton_stall``).

A block of 0.5 x 0.5 m on a base, joined by a Mohr-Coulomb joint with nodal (lumped) integration, at rest
(every joint point sticks). The residual and the correction are given, so what the words must say is known:
the free DOF with the largest residual, its node's position, and the joint points that a correction lifting
the block by 1 mm opens (all of them), the nearest one named with its states before and after.
"""
from __future__ import annotations

import re

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import ConvergenceError
from masonrydam.scene import build_mesh, build_model, build_stages
from masonrydam.scene.scene import Scene
from masonrydam.solvers.diagnostics import newton_stall

G = 9.80665


def block_on_base(gravity=(0.0, -G), friction_angle=30.0):
    return {
        "model": {"name": "block", "thickness": 1.0, "gravity": list(gravity)},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
            {"x0": -0.25, "y0": -0.25, "x1": 0.75, "y1": 0.0, "group": "base"},
            {"x0": 0.0, "y0": 0.0, "x1": 0.5, "y1": 0.5, "group": "block"}]}},
        "materials": {g: {"youngs_modulus": 20e9, "poisson_ratio": 0.0, "density": 2000.0} for g in ("base", "block")},
        "joints": {"joints": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": friction_angle,
                              "integration": "lumped"}},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": [{"name": "weight", "loads": [{"type": "self_weight"}]}],
    }


@pytest.fixture
def model():
    scene = Scene(block_on_base())
    mesh = build_mesh(scene.normalized, ".")
    m = build_model(scene.normalized, mesh)
    m.set_constraints(build_stages(scene.normalized, mesh, m)[0].supports)
    return m


def _numbers(text: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", text)]


def test_names_the_largest_residual_and_the_joint_points_the_next_correction_switches(model):
    free = model.dofmap.free
    block = np.unique(next(g for g in model.cgroups if g.name == "block").conn)  # the block's nodes
    target = int(block[np.argmax(model.coords[block, 0] + model.coords[block, 1])])  # its top right corner
    k = int(np.nonzero(free == 2 * target + 1)[0][0])  # its y DOF among the free ones
    r = np.full(len(free), 1.0)
    r[k] = -7.5  # N: the largest, in y
    lift = np.zeros(model.n_dof)
    lift[2 * block + 1] = 1e-3  # a correction that lifts the block 1 mm: every joint point opens

    def residual(v, tangent):
        model.evaluate(v, want_tangent=False)  # the joints' trial state at v
        return r, None

    text = newton_stall(model, np.zeros(model.n_dof), residual, lambda K, rr: lift[free])
    corner = model.coords[target]
    head = f"out of balance most at node {target} ({corner[0]:.4g}, {corner[1]:.4g}) m, by 7.5 N in y"
    assert head in text
    n_points = sum(g.points.shape[0] * g.points.shape[1] for g in model.igroups if g.nonlinear)
    assert f"(joints {n_points})" in text and "(stick to open)" in text
    # the nearest switching point: the joint point closest to the corner, on the joint (y = 0) at x = 0.5
    nearest = _numbers(text.split("the nearest at")[1])[:2]
    assert nearest == pytest.approx([0.5, 0.0], abs=1e-12)
    # without a correction (no solve), the residual only
    assert newton_stall(model, np.zeros(model.n_dof), residual, None).endswith("by 7.5 N in y")


def test_a_step_that_does_not_converge_says_where():
    """Past the sliding threshold (k = 0.8 > tan 30 deg = 0.58) the block has no equilibrium: the failure names
    where the last iterate is out of balance, on the block."""
    with pytest.raises(ConvergenceError) as err:
        masonrydam.run(block_on_base(gravity=(0.8 * G, -G)))
    text = str(err.value)
    assert "the last iterate is out of balance most at node" in text
    x, y = _numbers(text.split("out of balance most at node")[1])[1:3]
    assert -1e-12 <= x <= 0.5 + 1e-12 and -1e-12 <= y <= 0.5 + 1e-12
