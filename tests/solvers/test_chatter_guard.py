"""The Newton chatter guard shared by the static and dynamic solvers (masonrydam/solvers/chatter.py): what it
does on a sequence of joint-state patterns, against the rule its docstring states (a pattern seen before in
the step, other than the previous iteration's, stabilizes; two repeats of one pattern release; at most
MAX_STABILIZATIONS times a step)."""
from __future__ import annotations

from masonrydam.solvers.chatter import MAX_STABILIZATIONS, OPEN_TANGENT_STABILIZED, ChatterGuard


class PatternModel:
    """Stands in for a Model: the joint-state signatures of successive iterations, and what the guard set."""

    def __init__(self, signatures):
        self.signatures = iter(signatures)
        self.open_tangent, self.latched = None, 0

    def state_signature(self):
        return next(self.signatures)

    def set_open_tangent(self, value):
        self.open_tangent = value

    def latch_broken_bonds(self):
        self.latched += 1


def actions(signatures, regular=1e-6):
    model = PatternModel(signatures)
    guard = ChatterGuard(model, regular)
    out = [guard.observe() for _ in signatures]
    return out, model, guard


def test_cycling_stabilizes_and_a_settled_pattern_releases():
    # A B A: A comes back (not from the previous iteration): cycling. Then C C C: settled after two repeats.
    out, model, guard = actions(["A", "B", "A", "C", "C", "C"])
    assert out == [None, None, "stabilize", None, None, "release"]
    assert model.latched == 1 and model.open_tangent == 1e-6 and not guard.stabilized


def test_a_pattern_repeated_by_the_next_iteration_is_convergence_not_cycling():
    out, model, guard = actions(["A", "A", "A", "B", "B"])
    assert out == [None] * 5 and model.open_tangent is None and model.latched == 0


def test_stays_stabilized_while_the_pattern_keeps_changing():
    out, model, guard = actions(["A", "B", "A", "B", "A", "B"])
    assert out == [None, None, "stabilize", None, None, None]
    assert guard.stabilized and model.open_tangent == OPEN_TANGENT_STABILIZED


def test_at_most_max_stabilizations_a_step():
    cycle = ["A", "B", "A", "A", "A"]  # stabilize on the third, release on the fifth; then again
    out, _, _ = actions(cycle * (MAX_STABILIZATIONS + 2))
    assert out.count("stabilize") == MAX_STABILIZATIONS and out.count("release") == MAX_STABILIZATIONS
