"""A Newton solve that stagnates gives up early (masonrydam.solvers.newton.Stagnation, used by the relaxation past
limit points, masonrydam/solvers/static/relaxation.py): a residual that keeps falling is never given up, one that
cycles between two values (Newton at a corner of a joint law) is given up once the window has shown no progress,
and newton_iterations reports it as a solve that did not converge, with the iterations it took. And the same solves
let an iterate that is down to round-off pass without the work test."""
from __future__ import annotations

import numpy as np

from masonrydam.solvers.newton import ConvergenceTest, Stagnation, newton_iterations


def test_a_residual_that_halves_every_iteration_is_never_given_up():
    stop = Stagnation(window=5, first=6)
    assert not any(stop(k, 0.5 ** k) for k in range(40))


def test_a_residual_quadratically_converging_after_a_plateau_is_kept():
    """A plateau shorter than the window (a line search crossing a corner), then Newton's quadratic convergence."""
    history = [1.0, 0.3, 0.1, 0.1, 0.09, 0.1, 0.095, 1e-3, 1e-7, 1e-14]
    stop = Stagnation(window=5, first=6)
    assert not any(stop(k, r) for k, r in enumerate(history))


def test_a_two_cycle_is_given_up_once_the_window_shows_no_progress():
    """The 1.82 mm stall of the inviscid Eindhoven wall (docs/masonry_softening.md): Newton alternates between a
    small and a large residual. At k = 6 the window (iterates 2 to 6) still holds the first fall to 3e-5 from 0.2
    before it; at k = 7 (iterates 3 to 7) its smallest, 3e-5, is not below half the 3e-5 before it."""
    history = [1.0, 0.2, 3e-5, 2.0, 3e-5, 2.0, 3e-5, 2.0, 3e-5, 2.0, 3e-5]
    stop = Stagnation(window=5, first=6)
    given_up = [k for k, r in enumerate(history) if stop(k, r)]
    assert given_up[0] == 7


def test_not_before_the_first_iteration_it_may_act():
    stop = Stagnation(window=2, first=6)
    assert [stop(k, 1.0) for k in range(8)] == [False] * 6 + [True, True]


class _Scalar:
    """Newton on g(x) = 0 for a scalar g, as a NewtonStep: the iterates' residual is -g(x)."""

    class Iterate:
        def __init__(self, x, g):
            self.u, self.r = x, -g
            self.residual_norm = abs(g)

    def __init__(self, g, dg):
        self.g, self.dg = g, dg

    def evaluate(self, x):
        return self.Iterate(x, self.g(x))

    def force_scale(self, iterate, iteration):
        return 1.0

    def correction(self, iterate):
        return iterate.r / self.dg(iterate.u)

    def advance(self, iterate, dx):
        work = abs(dx * iterate.r)
        return self.evaluate(iterate.u + dx), work, work


def test_newton_on_a_cycling_problem_gives_up_before_its_budget():
    """Newton on x^3 - 2 x + 2 = 0 from x0 = 0 cycles 0, 1, 0, 1, ... exactly (residuals 2, 1, 2, 1, ...): with the
    stagnation test it stops at iteration 6, the first it may act at; without it, it runs its whole budget."""
    step = _Scalar(lambda x: x ** 3 - 2.0 * x + 2.0, lambda x: 3.0 * x * x - 2.0)
    test = ConvergenceTest(1e-10, 1e-20)
    plain = newton_iterations(step, step.evaluate(0.0), test, 30)
    stopped = newton_iterations(step, step.evaluate(0.0), test, 30, give_up=Stagnation(5, 6))
    assert not plain.converged and plain.iterations == 30
    assert not stopped.converged and stopped.iterations == 6


def test_newton_that_converges_is_not_given_up():
    """Newton on atan(x) = 0 from x0 = 0.5 converges (cubically near 0) within 5 iterations, as without the test."""
    step = _Scalar(np.arctan, lambda x: 1.0 / (1.0 + x * x))
    test = ConvergenceTest(1e-12, 1e-10)
    plain = newton_iterations(step, step.evaluate(0.5), test, 30)
    stopped = newton_iterations(step, step.evaluate(0.5), test, 30, give_up=Stagnation(5, 6))
    assert plain.converged and stopped.converged
    assert stopped.iterations == plain.iterations
    assert abs(stopped.iterate.u) < 1e-12


def test_an_iterate_down_to_round_off_passes_without_the_work_test():
    """The relaxation's solves (masonrydam/solvers/static/relaxation.py, ROUNDOFF_FRACTION) let an iterate whose
    residual is below a thousandth of the force tolerance pass whatever its correction's work. Newton on
    x^2 - 2 = 0 from 1.5 converges quadratically, residuals 0.25, 7e-3, 6e-6, 4.5e-12, 4e-16. At 4.5e-12 the force
    test (1e-6) has passed, but the work of the correction that led there is 1.3e-11, against the first's 2.1e-2
    (the test asks 1e-20 of it): one more iteration, to round-off, for the work test alone."""
    step = _Scalar(lambda x: x * x - 2.0, lambda x: 2.0 * x)
    plain = newton_iterations(step, step.evaluate(1.5), ConvergenceTest(1e-6, 1e-20), 30)
    roundoff = newton_iterations(step, step.evaluate(1.5), ConvergenceTest(1e-6, 1e-20, 1e-3), 30)
    assert plain.converged and roundoff.converged
    assert (plain.iterations, roundoff.iterations) == (4, 3)
    assert 1e-12 < roundoff.iterate.residual_norm <= 1e-9 and abs(roundoff.iterate.u - np.sqrt(2.0)) < 1e-11
    # with round-off below 1e-6 of the tolerance the iterate at 4.5e-12 is above it: the work test decides again
    assert newton_iterations(step, step.evaluate(1.5), ConvergenceTest(1e-6, 1e-20, 1e-6), 30).iterations == 4
