"""The secant line search of a static load step's Newton iteration (Crisfield 1991, Non-linear Finite Element
Analysis of Solids and Structures, vol. 1, sec. 9.3.1; :func:`masonrydam.solvers.newton.secant_line_search`), on
``g(s) = du . r(u + s du)``, with the full step evaluated first as the next iterate.

Why: where the search accepts the full step (``|g(1)| <= |g(0)| / 2``), the iterate there was evaluated twice:
forces only for ``g(1)``, then again with its tangent. Evaluating the full step once, with the tangent, and taking
``g(1)`` from its residual saves the first (on the inviscid Eindhoven wall J4D relaxed past its limit points, 82 s
became 69 s; docs/masonry_softening.md); where the search goes on, the tangent was computed for nothing. The
steps, iterates and states are the same, bit for bit: a law's forces do not depend on whether its tangent is
asked for (tests/elements/test_interface_forces.py), bonds are latched only on the iterate taken, and where the full
step cannot be evaluated (a law that gives up, a residual that is not finite) the search goes on as it would have.
"""
from __future__ import annotations

from ...errors import NumericalError
from ..newton import IterationFailed, secant_line_search


def advance(step, iterate, du):
    """The iterate at ``u + s du`` of the load step ``step`` (a
    :class:`~masonrydam.solvers.static.stepping.LoadStepNewton`) from ``iterate`` along the correction ``du``
    (free DOFs, m), ``s`` from the secant line search (1 without one), evaluated with its tangent; and the work
    ``|s du . r|`` (N m), twice (as :meth:`~masonrydam.solvers.newton.NewtonStep.advance` returns it)."""
    solver, free = step.solver, step.free
    g0 = float(du @ iterate.r)
    s = 1.0
    if step.s.line_search and g0 > 0:
        full = _full_step(step, iterate, du)
        g1 = None if full is None else float(du @ full.r)
        if g1 is not None and abs(g1) <= 0.5 * abs(g0):
            if step.guard.stabilized:  # (what evaluating the taken iterate does)
                step.model.latch_broken_bonds()
            return full, abs(g0), abs(g0)

        def directional_residual(t):
            trial = iterate.u.copy()
            trial[free] += t * du
            f_int, _ = step.model.evaluate(trial, want_tangent=False)
            return float(du @ (solver._with_state_load(step.f_ext) - f_int)[free])

        s, searched = secant_line_search(directional_residual, g0, first=g1)
        if searched:
            solver.stats.line_searches += 1
    u = iterate.u.copy()
    u[free] += s * du
    work = abs(s * g0)
    return step.evaluate(u), work, work


def _full_step(step, iterate, du):
    """The iterate at ``u + du`` evaluated with its tangent and no bonds latched; None where a law gives up there or
    the residual is not finite (``evaluate`` raises; the search then evaluates it again, and shortens the step as
    before)."""
    u = iterate.u.copy()
    u[step.free] += du
    law_failure = step.solver._law_failure
    try:
        return step.evaluate(u, latch=False)
    except (IterationFailed, NumericalError):
        step.solver._law_failure = law_failure  # (not an attempt that failed: the search shortens the step)
        return None
