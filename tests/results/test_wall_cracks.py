"""The failure mechanisms named from a wall's joints (masonrydam.results.wall_cracks), on a synthetic result whose
joints are put by hand into the states of each mechanism the Eindhoven tests show (Raijmakers & Vermeltfoort
1992; Lourenço & Rots 1997): a stair-case crack, a crushed toe, a sliding row; and on the states that are not one
(a single vertical crack, compression on the cap along the strut)."""
from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from masonrydam.results.wall_cracks import OPEN_AT, SLIDING_SLIP, wall_cracks

LENGTH, HEIGHT, ROWS, PER_ROW = 1.0, 1.0, 11, 20


def wall_result(open_head=(), cap=(), slip_rows=()):
    """One step of a wall 1 m x 1 m: ROWS bed-joint rows of PER_ROW points, a head joint point at each (x, y) of
    the grid between rows; ``open_head``: (x, y) of the head-joint points open by 2 OPEN_AT; ``cap``: (x, y) of
    bed-joint points on the cap; ``slip_rows``: (row index, fraction of its points slipped 2 SLIDING_SLIP)."""
    xs = (np.arange(PER_ROW) + 0.5) / PER_ROW * LENGTH
    ys = np.linspace(0.0, HEIGHT, ROWS)
    bx, by = np.meshgrid(xs, ys)
    hx, hy = np.meshgrid(xs, 0.5 * (ys[1:] + ys[:-1]))
    x = np.concatenate([bx.ravel(), hx.ravel()])
    y = np.concatenate([by.ravel(), hy.ravel()])
    which = np.concatenate([np.zeros(bx.size, int), np.ones(hx.size, int)])
    opening = np.zeros(x.size)
    slip = np.zeros(x.size)
    state = np.zeros(x.size, np.int8)
    for px, py in open_head:
        k = np.flatnonzero(which == 1)[np.argmin(np.hypot(hx.ravel() - px, hy.ravel() - py))]
        opening[k], state[k] = 2 * OPEN_AT, 2
    for px, py in cap:
        k = np.argmin(np.hypot(bx.ravel() - px, by.ravel() - py))
        state[k] = 3
    for r, fraction in slip_rows:
        slip[np.flatnonzero(which == 0)[r * PER_ROW:r * PER_ROW + int(fraction * PER_ROW)]] = 2 * SLIDING_SLIP
    point = ("step", "joint_point")
    ds = xr.Dataset({
        "joint_opening": (point, opening[None]), "joint_state": (point, state[None]),
        "joint_plastic_slip": (("step", "joint_point", "shear_direction"), slip[None, :, None]),
        "joint_x": ("joint_point", x), "joint_y": ("joint_point", y), "joint_set": ("joint_point", which)})
    ds.joint_set.attrs["set_names"] = json.dumps(["bed_joints", "head_joints"])
    return ds


STAIR = [(0.1 + 0.8 * t, 0.05 + 0.9 * t) for t in np.linspace(0.0, 1.0, 10)]


def test_a_stair_case_crack_a_crushed_toe_and_a_sliding_row_are_named():
    toe = [(0.975, 0.0), (0.925, 0.0), (0.875, 0.0), (0.975, 0.1)]
    w = wall_cracks(wall_result(open_head=STAIR, cap=toe, slip_rows=[(0, 1.0)]))
    words = w.words()
    assert "diagonal stair-case cracking" in words
    assert "toe crushing at the bottom right corner (4 bed-joint points" in words
    assert "sliding along the bed joint at y = 0.000 m" in words
    assert w.counts["head_joints"]["open"] == len(STAIR)
    assert w.counts["bed_joints"]["crushing"] == len(toe)
    assert w.open_heights == pytest.approx((0.05, 0.95))


def test_a_vertical_crack_a_partly_slipping_row_and_cap_points_along_the_strut_are_not_a_toe_or_a_slide():
    vertical = [(0.5, 0.05 + 0.1 * k) for k in range(10)]
    strut = [(0.5, 0.5), (0.45, 0.4), (0.55, 0.6)]
    w = wall_cracks(wall_result(open_head=vertical, cap=strut, slip_rows=[(5, 0.7)]))
    assert len(w.mechanisms) == 1 and w.mechanisms[0].startswith("a band of bed joints on the compression cap (3")
    assert w.counts["bed_joints"]["crushing"] == 3 and w.counts["head_joints"]["open"] == 10
    assert w.crushing_at == pytest.approx((0.5, 0.5), abs=0.03)
    # a short diagonal (a third of the height) is not the wall's stair-case either
    assert wall_cracks(wall_result(open_head=STAIR[:3])).mechanisms == []
    # nor is a corner of a band that runs along the strut a crushed toe: 4 of its 20 cap points are in the corner
    band = [(0.975, 0.0), (0.925, 0.0), (0.875, 0.0), (0.975, 0.1)] + [(0.325 + 0.05 * (k % 4), 0.3 + 0.1 * (k // 4))
                                                                        for k in range(16)]
    w = wall_cracks(wall_result(cap=band))
    assert len(w.mechanisms) == 1 and w.mechanisms[0].startswith("a band of bed joints on the compression cap (20")


def test_a_result_without_the_joints_or_the_step_is_refused_by_name():
    ds = wall_result()
    with pytest.raises(ValueError, match="joint_opening"):
        wall_cracks(ds.drop_vars("joint_opening"))
    with pytest.raises(ValueError, match="step 3"):
        wall_cracks(ds, 3)
    ds.joint_set.attrs["set_names"] = json.dumps(["lift_joints", "contraction_joints"])
    with pytest.raises(ValueError, match="not those of a masonry wall"):
        wall_cracks(ds)
