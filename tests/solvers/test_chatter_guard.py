"""The Newton chatter guard shared by the static and dynamic solvers (masonrydam/solvers/chatter.py): what it
does on a sequence of joint-state patterns, against the rule its docstring states (a pattern seen before in
the step, other than the previous iteration's, stabilizes; two repeats of one pattern release; at most
MAX_STABILIZATIONS times a step)."""
from __future__ import annotations

from masonrydam.solvers.chatter import (MAX_STABILIZATIONS, OPEN_TANGENT_STABILIZED, STAGNATION_WINDOW,
                                        ChatterGuard)


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


class BondModel(PatternModel):
    """A PatternModel whose latch reports ``bonds`` newly latched points (the Model's count)."""

    def __init__(self, signatures, bonds=3):
        super().__init__(signatures)
        self.bonds = bonds

    def latch_broken_bonds(self):
        self.latched += 1
        return self.bonds


def stagnation_actions(signatures, residuals, stagnation=True, bonds=3):
    model = BondModel(signatures, bonds)
    guard = ChatterGuard(model, 1e-6, stagnation=stagnation)
    return [guard.observe(r) for r in residuals], model, guard


def test_a_stagnating_residual_with_a_moving_pattern_latches_the_broken_bonds():
    # new patterns every iteration (no exact repeat) and a residual that falls by 10 % an iteration: after
    # STAGNATION_WINDOW + 1 residuals it has not halved over the window (0.9^4 = 0.66 > STAGNATION_RATIO)
    n = STAGNATION_WINDOW + 1
    residuals = [0.9 ** k for k in range(2 * n)]
    out, model, guard = stagnation_actions([f"P{k}" for k in range(2 * n)], residuals)
    assert out[:n - 1] == [None] * (n - 1) and out[n - 1] == "latch"
    assert out[n:2 * n - 1] == [None] * (n - 1) and out[2 * n - 1] == "latch"  # the window starts again
    assert model.latched == 2 and model.open_tangent is None and not guard.stabilized


def test_no_latch_while_newton_converges_or_the_pattern_is_settled_or_in_a_dynamic_step():
    n = 3 * (STAGNATION_WINDOW + 1)
    fast = [0.5 ** k * 0.99 ** k for k in range(n)]  # halves and more within every window
    assert stagnation_actions([f"P{k}" for k in range(n)], fast)[0] == [None] * n
    slow = [1.0] * n
    assert stagnation_actions(["A"] * n, slow)[0] == [None] * n  # no state change: not the joints' doing
    assert stagnation_actions([f"P{k}" for k in range(n)], slow, stagnation=False)[0] == [None] * n
    n = (MAX_STABILIZATIONS + 2) * (STAGNATION_WINDOW + 1)  # at most MAX_STABILIZATIONS latches a step
    out, model, _ = stagnation_actions([f"P{k}" for k in range(n)], [1.0] * n, bonds=0)
    assert out == [None] * n and model.latched == MAX_STABILIZATIONS  # nothing latched: nothing evaluated again
