"""The static Newton step's line search evaluates the full step once, with its tangent, and takes it as the next
iterate where the search accepts it (masonrydam/solvers/static/line_search.py). That must change nothing but the
cost: the same steps, iterates and joint states, bit for bit, as evaluating g(1) forces-only and then the taken
iterate again (Crisfield 1991, sec. 9.3.1, the secant search both run). Checked on the Eindhoven wall J4D
(inviscid) pushed 0.8 mm, where the secant search shortens some steps and accepts the full one in others."""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam
from masonrydam.solvers.static import line_search
from masonrydam.scene.scene import Scene, set_key
from repository_paths import EXAMPLES


def j4d_to_its_first_peak():
    data = Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data
    for name in ("bed_joints", "head_joints", "unit_cracks"):  # the inviscid law: its Newton iterations search more
        data["joints"][name].pop("relaxation_time")
    set_key(data, "stages[1].loads[0].value", ["0.8 mm", "0 mm"])
    set_key(data, "stages[1].steps", 8)
    return data


@pytest.mark.slow
def test_taking_the_evaluated_full_step_changes_nothing_but_the_cost(monkeypatch):
    counts = {"full": 0, "shortened": 0}
    full_step, search = line_search._full_step, line_search.secant_line_search

    def counted_full(step, iterate, du):
        counts["full"] += 1
        return full_step(step, iterate, du)

    def counted_search(*args, **kwargs):
        s, searched = search(*args, **kwargs)
        counts["shortened"] += s < 1.0
        return s, searched

    monkeypatch.setattr(line_search, "_full_step", counted_full)
    monkeypatch.setattr(line_search, "secant_line_search", counted_search)
    reused = masonrydam.run(j4d_to_its_first_peak())
    monkeypatch.setattr(line_search, "_full_step", lambda step, iterate, du: None)  # the search evaluates g(1)
    plain = masonrydam.run(j4d_to_its_first_peak())
    assert reused.attrs["completed"] == plain.attrs["completed"] == "true"
    for name in ("displacement", "reaction", "joint_traction_normal", "joint_traction_shear", "joint_plastic_slip",
                 "joint_state", "load_factor", "iterations"):
        np.testing.assert_array_equal(reused[name].values, plain[name].values, err_msg=name)
    assert reused.attrs["newton_iterations"] == plain.attrs["newton_iterations"]
    # both branches ran: full steps taken as evaluated, and steps the search shortened
    assert 0 < counts["shortened"] < counts["full"]
