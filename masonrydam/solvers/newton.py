"""One Newton loop, and its parts, shared by the static load steps and the implicit dynamic steps.

- :func:`newton_iterations`: the loop (convergence test, chatter guard, correction, line search and update, to
  an iteration limit) over a :class:`NewtonStep`, which says what an iterate is, its force scale, the correction
  and how the iterate moves along it;
- :class:`ConvergenceTest`: the force residual against a force scale, and the work of the last correction
  against the first (Crisfield, *Non-linear Finite Element Analysis of Solids and Structures*, vol. 1, 1991,
  sec. 9.3.3);
- line searches: :func:`secant_line_search` on the work of the correction (Crisfield 1991, sec. 9.3.1; the
  static steps) and :func:`backtracking_line_search` on the residual norm (the dynamic steps, whose joint laws
  make the work along the correction jump);
- :class:`CycleDamping`: the correction halved while the residual norm comes back every other iteration;
- :class:`StepCutting`: how often a step that fails may be halved;
- and, in :mod:`.chatter`, the guard against joint-state patterns that cycle.

The static stepping (:mod:`.static.stepping`) and the implicit dynamic step (:mod:`.dynamic.implicit`) each give
the loop their own :class:`NewtonStep`: they differ in what an iterate holds (a tangent and a residual, or the
step's accelerations and velocities too), in the iteration matrix (a factorization per tangent, or the dynamic
effective-matrix solver with its cached and low-rank-updated factorizations), in the line search and in the
work they measure; see docs/dynamics.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..errors import NumericalError, StepInterrupted

#: a force scale is never below this (N): a step with no load and no residual converges at once
FORCE_SCALE_FLOOR = 1e-30


def force_scale(*norms: float) -> float:
    """The force scale of a convergence test (N): the largest of ``norms`` (Euclidean norms of the forces of the
    step: internal, external, inertia, the first residual), at least :data:`FORCE_SCALE_FLOOR`."""
    return max(*norms, FORCE_SCALE_FLOOR)


@dataclass(frozen=True)
class ConvergenceTest:
    """Convergence of a Newton iterate: the force residual norm ``rn <= force_tolerance * scale`` and the work
    of the last correction ``<= energy_tolerance`` x that of the first (both dimensionless tolerances).

    ``roundoff_fraction``: where given, an iterate whose residual is below ``roundoff_fraction *
    force_tolerance * scale`` passes the work test whatever the works are (the residual is down to round-off,
    where the work test has nothing left to say; with very small dynamic steps it could not be met).
    """

    force_tolerance: float
    energy_tolerance: float
    roundoff_fraction: float | None = None

    def forces_converged(self, rn: float, scale: float) -> bool:
        """The force test alone."""
        return rn <= self.force_tolerance * scale

    def work_converged(self, first_work: float | None, last_work: float | None, rn: float, scale: float) -> bool:
        """The work test: true before the first correction (``last_work`` None) and where the first correction
        did no work."""
        return (last_work is None or first_work == 0 or last_work <= self.energy_tolerance * first_work
                or (self.roundoff_fraction is not None
                    and rn <= self.roundoff_fraction * self.force_tolerance * scale))

    def converged(self, rn: float, scale: float, first_work: float | None, last_work: float | None) -> bool:
        """Both tests."""
        force_ok = self.forces_converged(rn, scale)
        work_ok = self.work_converged(first_work, last_work, rn, scale)
        return force_ok and work_ok


def secant_line_search(directional_residual, g0: float, max_tries: int = 6, first: float | None = None
                       ) -> tuple[float, bool]:
    """Secant line search on ``g(s) = du . r(u + s du)`` (Crisfield 1991, sec. 9.3.1): the step length ``s``
    in [0.1, 1] where ``|g(s)| <= |g0| / 2``, from at most ``max_tries`` evaluations.

    ``directional_residual(s)`` returns ``g(s)`` (N m), or raises :class:`~masonrydam.errors.NumericalError`
    where a material law gives up at that trial point (a shorter step is then taken); ``g0 = g(0)``; ``first``:
    ``g(1)`` where the caller has it already (it counts as the first evaluation). Returns (s, searched):
    ``searched`` says whether the search moved away from the full step in a way worth counting.
    """
    if g0 <= 0:
        return 1.0, False
    s_prev, g_prev, s = 0.0, g0, 1.0
    for k in range(max_tries):
        try:
            g = first if k == 0 and first is not None else directional_residual(s)
        except NumericalError:  # a law gave up at this trial point: a shorter step
            return (0.5 if k == 0 else s_prev if s_prev > 0 else 0.1), False
        if not np.isfinite(g):
            return 0.5, False
        if abs(g) <= 0.5 * abs(g0):
            return s, k > 0
        if g == g_prev:
            return s, False
        s_new = s - g * (s - s_prev) / (g - g_prev)
        s_prev, g_prev = s, g
        s = float(np.clip(s_new, 0.1, 1.0))
    return s, True


#: the shorter steps a backtracking line search tries after the full step
BACKTRACKING_STEPS = (0.5, 0.25)


def backtracking_line_search(iterate_at, residual_norm, full_norm: float, rn: float,
                             steps: tuple[float, ...] = BACKTRACKING_STEPS):
    """Backtracking on the residual norm where the full correction did not reduce it (``full_norm > rn``):
    tries the ``steps`` in turn until one reduces it, and takes the step with the smallest norm seen.

    ``iterate_at(s)`` evaluates the iterate at step length ``s`` (which leaves the material laws' trial state at
    that point) and ``residual_norm(iterate)`` gives its residual norm (N). Returns (s, iterate) with the
    iterate evaluated last at ``s`` (so that the laws' trial state is the chosen iterate's); ``s = 1`` when no
    shorter step did better.
    """
    best_norm, best_step = full_norm, 1.0
    for trial_step in steps:
        iterate = iterate_at(trial_step)
        norm = residual_norm(iterate)
        if norm < best_norm:
            best_norm, best_step = norm, trial_step
        if norm <= rn:
            break
    if best_step == trial_step:
        return best_step, iterate
    return best_step, iterate_at(best_step)  # evaluated again at the chosen step (the laws' trial state)


class CycleDamping:
    """Damping of the Newton correction where the residual norm repeats every other iteration (a two-cycle:
    e.g. the friction direction of a pivot point flipping from one iterate to the next): the correction is
    halved, down to 1/64, each time the norm comes back to within 1e-6 of the one two iterations before."""

    def __init__(self):
        self.norms = []
        self.factor = 1.0

    def observe(self, rn: float) -> bool:
        """Take the residual norm of the iterate about to be corrected; True where the damping was increased."""
        self.norms.append(rn)
        norms = self.norms
        if len(norms) >= 3 and abs(norms[-1] - norms[-3]) <= 1e-6 * norms[-1] and norms[-1] > 0:
            self.factor = max(self.factor * 0.5, 1.0 / 64.0)
            return True
        return False


@dataclass(frozen=True)
class StepCutting:
    """How far a step that fails may be cut (halved): at most ``max_cuts`` times in a row and, where
    ``smallest`` is given, never below that size."""

    max_cuts: int
    smallest: float | None = None

    @classmethod
    def from_nominal(cls, max_cuts: int, nominal: float) -> "StepCutting":
        """At most ``max_cuts`` halvings of a step of size ``nominal``: down to ``nominal / 2^max_cuts``."""
        return cls(max_cuts, nominal / 2.0 ** max_cuts)

    def can_cut(self, cuts: int, size: float | None = None) -> bool:
        """Whether a step of ``size`` already cut ``cuts`` times in a row may be halved once more."""
        return cuts + 1 <= self.max_cuts and (self.smallest is None or size / 2.0 >= self.smallest)


def within_step_stop(stop_requested):
    """The check a solver makes between two iterations of a step (Newton or joint-space), for the stop requests
    ``stop_requested()`` (None: never asked; returns None then): it raises
    :class:`~masonrydam.errors.StepInterrupted` with the status the requests give (``"interrupted"``,
    ``"terminated"``); the solver then abandons the step and keeps the last converged one. Shared by the static
    and the dynamic solvers."""
    if stop_requested is None:
        return None

    def _stop_within_step():
        status = stop_requested()
        if status is not None:
            raise StepInterrupted(status)

    return _stop_within_step


class IterationFailed(Exception):
    """Raised by :meth:`NewtonStep.advance` where the new iterate cannot be evaluated (a material law gives up
    there): the loop ends without convergence."""


class NewtonStep(Protocol):
    """What :func:`newton_iterations` needs of the step it solves. An iterate is any object with a
    ``residual_norm`` (N)."""

    def force_scale(self, iterate, iteration: int) -> float:
        """The force scale (N) of the convergence test at ``iterate``, the ``iteration``-th."""

    def after_guard(self, iterate, action: str):
        """The iterate evaluated again at the same displacements after the chatter guard's ``action``
        ("stabilize" or "release")."""

    def correction(self, iterate):
        """The Newton correction at ``iterate`` (free DOFs)."""

    def advance(self, iterate, correction):
        """(new iterate, work of the correction at ``iterate``, work of the step taken), the new iterate along
        the correction (after a line search) and evaluated; raises :class:`IterationFailed` where it cannot be
        evaluated."""


class Stagnation:
    """Gives up a Newton iteration whose residual has stopped falling: at iteration ``k >= first``, where the
    smallest relative residual of the last ``window`` iterates is not below half the smallest before them.

    Why: past the inviscid Eindhoven wall's peak (docs/masonry_softening.md), most Newton solves that fail cycle
    at a corner of the joint law for the rest of their budget; those failures took 60 % of the run. Where a failure
    is cut or held anyway, ending it once it stagnates costs nothing but the iterations saved. One instance per
    Newton solve (it keeps the history)."""

    def __init__(self, window: int, first: int):
        self.window, self.first = window, first
        self.history: list[float] = []

    def __call__(self, iteration: int, relative_residual: float) -> bool:
        h = self.history
        h.append(relative_residual)
        k = len(h) - 1
        if k < self.first or k - self.window < 0:
            return False
        return min(h[k - self.window + 1:]) >= 0.5 * min(h[:k - self.window + 1])


@dataclass
class NewtonResult:
    """converged; iterate: the last iterate (None where it could not be evaluated); iterations: the
    corrections taken."""

    converged: bool
    iterate: object
    iterations: int


def newton_iterations(step: NewtonStep, start, test: ConvergenceTest, max_iterations: int, guard=None,
                      on_check=None, give_up=None) -> NewtonResult:
    """Newton iterations of ``step`` from the evaluated iterate ``start``, at most ``max_iterations``
    corrections: converged when ``test`` passes; ``guard`` (a :class:`~.chatter.ChatterGuard`, None for a linear
    model) observes every iterate that is corrected, and an iterate it acts on is evaluated again
    (:meth:`NewtonStep.after_guard`). ``on_check(iteration, residual_norm, scale)`` is told of every test;
    ``give_up(iteration, residual_norm / scale)`` (e.g. a :class:`Stagnation`), where given, ends an iterate that
    has not converged as a failure when it returns True."""
    first_work = last_work = None
    current = start
    for it in range(max_iterations + 1):
        rn = current.residual_norm
        scale = step.force_scale(current, it)
        if on_check is not None:
            on_check(it, rn, scale)
        if test.converged(rn, scale, first_work, last_work):
            return NewtonResult(True, current, it)
        if it == max_iterations or (give_up is not None and give_up(it, rn / scale if scale > 0 else rn)):
            break
        if guard is not None:
            # cycling: the stabilized iteration; settled: back to the consistent tangent (the guard's module
            # docstring); either way the iteration matrix and residual are evaluated again
            action = guard.observe(rn)
            if action is not None:
                current = step.after_guard(current, action)
        dx = step.correction(current)
        try:
            current, work_here, work = step.advance(current, dx)
        except IterationFailed:
            return NewtonResult(False, None, it + 1)
        if first_work is None:
            first_work = work_here
        last_work = work
    return NewtonResult(False, current, it)
