"""Arc-length control of static stages (masonrydam/solvers/static/arc_length.py): Crisfield's
cylindrical method, chosen by a stage (``control = "arc_length"``) or switched on where load control
stalls.

Closed form: a rigid block (2b x 2h) on a no-tension, no-slip base, pushed by a horizontal body force
lambda m g, rocks about its toe once lambda g exceeds g b/h; turned by theta it stays in equilibrium
at lambda(theta) = tan(alpha - theta), alpha = atan(b/h) (moments about the toe of the weight and of
the horizontal force, both at the centre of mass, with exact kinematics: Housner 1963, BSSA 53(2),
the static pushover of a rocking block; e.g. Makris & Konstantinidis 2003, EESD 32, eq. 2). The branch
descends: load control stops at its peak, arc-length control follows it down to theta = alpha.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import ConvergenceError, SceneError
from scenes import tilted_block

ALPHA = math.atan(0.25)


def _rotation(ds):
    """The block's rotation (rad) at every recorded step, from its two bottom corners."""
    x, y = ds.x.values, ds.y.values
    d = ds.displacement.values
    corners = []
    for xc in (0.0, 0.5):
        c = np.nonzero((np.abs(x - xc) < 1e-9) & (np.abs(y) < 1e-9))[0]
        corners.append(c[np.argmax(np.abs(d[:, c, 1]).max(axis=0))])  # the block's node of the pair
    left, right = corners
    return np.arctan2(d[:, left, 1] - d[:, right, 1], 0.5 + d[:, right, 0] - d[:, left, 0])


@pytest.mark.reference
def test_arc_length_follows_the_toppling_branch():
    s = tilted_block("large")
    s["stages"][1].update({"control": "arc_length", "steps": 20, "until_failure": True})
    ds = masonrydam.run(s)
    theta = _rotation(ds)
    push = 0.5 * ds.load_factor.values  # horizontal acceleration / g
    branch = (theta > 1e-3) & (theta < ALPHA - 1e-3)
    assert branch.sum() >= 10  # the descending branch is recorded, not one point
    np.testing.assert_allclose(push[branch], np.tan(ALPHA - theta[branch]), rtol=2e-3, atol=2e-4)
    assert theta.max() > ALPHA  # followed down to toppling
    assert 0.5 * ds.attrs["limit_load_factor"] == pytest.approx(0.25, rel=1e-3)  # the peak, b/h
    assert "arc-length" in ds.attrs["limit_state"] and ds.attrs["arc_length_steps"] > 10


@pytest.mark.slow
def test_load_control_switches_to_arc_length_where_it_stalls(tmp_path):
    """The same block loaded to 0.5 g under load control: the steps stall at the peak (0.25 g), the stage
    goes on under arc-length control and follows the descending branch; it cannot reach 0.5 g on it, so
    the run stops with an error that says so, and the file keeps the branch."""
    import xarray as xr

    s = tilted_block("large")
    s["stages"][1].update({"until_failure": False, "steps": 20})
    out = tmp_path / "tilt.nc"
    with pytest.raises(ConvergenceError) as err:
        masonrydam.run(s, output=out)
    assert "arc-length" in str(err.value) and "peaked at" in str(err.value)
    ds = xr.load_dataset(out)
    theta = _rotation(ds)
    push = 0.5 * ds.load_factor.values
    branch = (theta > 1e-3) & (theta < ALPHA - 1e-3)
    assert branch.sum() >= 5
    np.testing.assert_allclose(push[branch], np.tan(ALPHA - theta[branch]), rtol=2e-3, atol=2e-4)


def test_bad_control():
    s = tilted_block("large")
    s["stages"][1]["control"] = "arclength"
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[1].control"
