"""Past a limit point by relaxation: where a static stage's path has a limit point under its own control (the
prescribed displacements of a push), hold the loads of the step that finds no equilibrium (once it is
cut to a quarter, :data:`RELAX_AFTER_CUTS`) and let the softening joints relax to an equilibrium there, then go on
(``[[stages]] limit_point = "relax"``).

Beyond a limit point no equilibrium lies near the path. A wall pushed by a stiff actuator snaps there to another
state, at about the same displacement: its force drops at once. Path following (the default, ``"follow"``) traces
the equilibrium path through the snap-back instead; where that path turns back to zero load or cannot be followed
(the inviscid Eindhoven wall, docs/masonry_softening.md) the stage stops. The relaxation finds the state the
snap lands on:

- during the hold every joint set whose law has a viscous regularisation relaxes with one relaxation time ``tau``
  (Duvaut-Lions, Simo & Hughes 1998, Computational Inelasticity, sec. 2.7), in pseudo-time steps ``dt = r tau``,
  ``r`` from :data:`R_FIRST`, doubling while the steps converge and a quarter where one does not, each committed,
  each from the last relaxed state moved on by half the last step's change (:data:`HOLD_PREDICTOR`); with ``r``
  small the viscous tangent is nearly the elastic one, positive where the inviscid one is singular;
- once the joints' own law leaves the relaxed state out of balance by less than :data:`RETRY_BELOW` of the force
  scale, the stage's own step (the joints' own relaxation times, inviscid where they have none) is tried from it,
  then after 1, 2, 4, ... more hold steps each time it fails; the first that converges ends the hold and is the
  step recorded; a relaxed state that is already out of balance by no more than the stage's force tolerance
  under the joints' own law ends the hold by itself (it is that equilibrium);
- the next step is as long as the held one, and grows back after steps that converge without a hold.

What it costs (docs/masonry_softening.md): past the Eindhoven wall's peak nearly every quarter step is held. The
Newton iterations of the attempts that end in a hold, of the hold steps and of the tries from the relaxed state are
capped (:data:`RETRY_MAX_ITERATIONS`, :data:`HOLD_MAX_ITERATIONS`) below the stage's own budget, at counts that
none of the converged ones reached there, and every Newton solve of such a stage gives up once its residual
stagnates (:data:`STAGNATION_WINDOW`): most of those that fail cycle at a corner of the joint law.

The end state is an equilibrium of the joints' own law. Only ``r = dt / tau`` enters the hold, so the value of
``tau`` does not matter, but the path the relaxation takes to the end state does: it is the viscous flow's, with
one relaxation time for every set (docs/masonry_softening.md says what that picks). Viscous (Perzyna) blocks relax
over the hold's pseudo-time too. Closed-form check: the snap-back bar of tests/solvers/test_composite_joints.py.

Why not a library: the hold acts on the joints' own law state through their trial / commit protocol, which no
solver library reaches.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import replace

import numpy as np

from ...errors import NumericalError
from ..linear.direct import SingularMatrix
from ..newton import Stagnation, force_scale

#: a step of a stage with ``limit_point = "relax"`` that finds no equilibrium is held and relaxed where it is no
#: longer than the nominal step cut this many times (:func:`holds`)
RELAX_AFTER_CUTS = 2
#: the first pseudo-time step of a hold, in relaxation times; it doubles after each converged step. Why 64: on the
#: inviscid Eindhoven wall J4D (docs/masonry_softening.md) no hold step up to r = 128 failed in 88 holds from r = 1,
#: and the seven doublings to there cost about 30 Newton iterations a hold. From 64 (and with :data:`HOLD_PREDICTOR`)
#: its 40-step run took 39 % fewer iterations, and its curve moved by 0.5 % at the peak and 1.1 % or less at 1 to 4 mm
R_FIRST = 64.0
#: the largest pseudo-time step, in relaxation times (a step this long is all but inviscid)
R_MAX = 1e6
#: the smallest, below which a hold that keeps failing gives up
R_MIN = 1e-6
#: hold steps before a hold gives up
MAX_HOLD_STEPS = 400
#: the relaxation time of the hold (s); only dt / tau enters, so any positive value gives the same steps
TAU_HOLD = 1.0
#: the stage's own step is tried once the joints' own residual at the relaxed state is below this fraction of the
#: force scale (each try that fails costs a Newton solve; the hold steps alone are cheaper)
RETRY_BELOW = 1e-2
#: each hold step after the first starts from the relaxed state plus this fraction of the last hold step's change of
#: the displacements (the held DOFs do not change). Why a half: the Duvaut-Lions stress of a step is
#: ``(trial + r inviscid) / (1 + r)``, so a relaxed state's distance to the end state falls about as ``1 / r``, and
#: with ``r`` doubling each step changes the state by about half as much as the one before. On J4D pushed 2.3 mm it
#: cut the converged hold steps' Newton iterations by 7 % (4.2 to 3.9 a step); the curve the same to the digits shown
HOLD_PREDICTOR = 0.5
#: Newton iterations of a hold step before it counts as failed (and ``r`` is quartered). Why: on the inviscid
#: Eindhoven wall J4D (docs/masonry_softening.md) every converged hold step took 3 to 8 iterations and none that
#: ran past 8 converged by 30, where a failed step cost 30; a third of the hold's iterations went into them
HOLD_MAX_ITERATIONS = 10
#: Newton iterations of a try of the stage's own step from the relaxed state (there 4 to 15 converged, none later)
RETRY_MAX_ITERATIONS = 20
#: a Newton solve of a hold, of a try from the relaxed state or of the stage's own step gives up where the smallest
#: residual of its last this many iterates is not below half the smallest before them, from iteration
#: :data:`STAGNATION_FIRST` on (:class:`~masonrydam.solvers.newton.Stagnation`). Why: on the inviscid Eindhoven wall
#: J4D (docs/masonry_softening.md) three in four of the tries from the relaxed state and of the push's own steps past
#: the peak failed, each after its whole budget, cycling at a corner of the joint law: about 60 % of the run. With
#: this window none of the hold steps that converged there would have been given up, and 3 of the 28 push steps and 6
#: of the 86 tries that did (those were held instead, or tried again later: the curve moved by 0.6 % at 4 mm and
#: 0.5 % at 2 mm)
STAGNATION_WINDOW = 5
STAGNATION_FIRST = 6
#: an iterate of such a solve whose residual is below this fraction of the force tolerance passes the work test, as
#: in the dynamic solver (the residual is down to round-off there). Why: most hold steps took one more iteration
#: after their residual had reached 1e-10 of the force scale, for the work test alone; on J4D this cut the Newton
#: iterations by 8 % (the curve the same to the digits shown)
ROUNDOFF_FRACTION = 1e-3


def holds(st, size: float, nominal: float, can_cut: bool) -> bool:
    """Whether a step of load-factor length ``size`` of stage ``st`` that found no equilibrium is held
    (:func:`relax_past_limit`) rather than cut: with ``limit_point = "relax"`` (and loads proportional to the load
    factor), where it is no longer than the nominal step ``nominal`` cut :data:`RELAX_AFTER_CUTS` times, or
    cannot be cut again (``can_cut`` False). After a hold the next step is as long as the held one (the step
    grows back after steps that converge without one): past a peak nearly every step crosses a limit point,
    and each longer attempt that fails first costs a whole Newton solve."""
    return st.limit_point == "relax" and st.varying is None and (
        size <= nominal / 2.0 ** RELAX_AFTER_CUTS * (1.0 + 1e-9) or not can_cut)


def attempt(solver, st, size: float, nominal: float, can_cut: bool, trial, f_ext, state_load):
    """The stage's step from ``trial`` (:meth:`StaticSolver._newton`, its ``(ok, u, iterations, f_int)``). With
    ``limit_point = "relax"`` it gives up once its residual stagnates (:data:`STAGNATION_WINDOW`), and where a
    failure would be held (:func:`holds`) it has at most :data:`RETRY_MAX_ITERATIONS` Newton iterations. Why: past
    the Eindhoven wall's peak four in five of these steps fail and go to a hold or a cut, each after the stage's
    whole iteration budget (30), and none of those that converged took more than 20."""
    if st.limit_point != "relax":
        return solver._newton(trial, f_ext, can_cut, state_load)
    cap = RETRY_MAX_ITERATIONS if holds(st, size, nominal, can_cut) else solver.s.max_iterations
    with _at_most(solver, cap):
        return solver._newton(trial, f_ext, can_cut, state_load)


@contextmanager
def _at_most(solver, max_iterations: int):
    """The solver's Newton steps within the block take at most ``max_iterations`` (and the stage's own limit), give
    up once their residual stagnates (:class:`~masonrydam.solvers.newton.Stagnation`, :data:`STAGNATION_WINDOW`),
    and pass an iterate down to round-off without the work test (:data:`ROUNDOFF_FRACTION`)."""
    settings, give_up, roundoff = solver.s, solver.give_up, solver.roundoff_fraction
    solver.s = replace(settings, max_iterations=min(max_iterations, settings.max_iterations))
    solver.give_up = lambda: Stagnation(STAGNATION_WINDOW, STAGNATION_FIRST)
    solver.roundoff_fraction = ROUNDOFF_FRACTION
    try:
        yield
    finally:
        solver.s, solver.give_up, solver.roundoff_fraction = settings, give_up, roundoff


def _states(model) -> list[tuple[object, np.ndarray]]:
    """The committed state arrays of every group that has one, copied (restored where a hold gives up)."""
    return [(g, g.state_committed.copy()) for g in (*model.cgroups, *model.igroups)
            if getattr(g, "state_committed", None) is not None]


def _out_of_balance(model, u, f_ext):
    """The residual of the joints' own law at ``u`` (free DOFs) from the committed state, over the force scale (the
    larger of the external and internal forces' norms over all DOFs: the reactions of a push count), and the
    internal forces (n_dof,) N there. The trial state at ``u`` is left for the caller to commit (the relaxed state is
    that equilibrium) or revert; where a law gives up there, it is reverted and the residual is infinite."""
    try:
        f_int, _ = model.evaluate(u, want_tangent=False)
    except NumericalError:  # a law that gives up there: far from it
        model.revert()
        return float("inf"), None
    free = model.dofmap.free
    scale = force_scale(float(np.linalg.norm(f_ext)), float(np.linalg.norm(f_int)))
    return float(np.linalg.norm((f_ext - f_int)[free])) / scale, f_int


def _step(solver, trial, f_ext, max_iterations: int):
    """One Newton step from ``trial`` at ``f_ext``, at most ``max_iterations`` (and the stage's own limit):
    ``(converged, u, f_int)``; a singular tangent (the inviscid one at the limit point is nearly singular) or a law
    that gives up is a step that did not converge."""
    try:
        with _at_most(solver, max_iterations):
            ok, u_new, _, f_int = solver._newton(trial.copy(), f_ext, False, None)
    except (SingularMatrix, NumericalError):
        return False, trial, None
    return ok, u_new, f_int


def relax_past_limit(solver, st, u: np.ndarray, trial: np.ndarray, f_ext: np.ndarray, load_factor: float,
                     stage_stats: dict):
    """Hold the loads of a step that found no equilibrium and relax the joints until the stage's step converges.

    ``solver``: the :class:`~masonrydam.solvers.static.stepping.StaticSolver`, at the last converged state ``u``
    (n_dof,) m; ``st``: the stage; ``trial`` (n_dof,) m: ``u`` with the step's prescribed displacements;
    ``f_ext`` (n_dof,) N: the step's external forces, at ``load_factor``; the model's ``time_step`` (s) is the
    step's own (the joints' own relaxation). Returns ``(ok, u_new, f_int, words)``: on success the converged
    displacements and internal forces, committed, with ``[load_factor, hold steps]`` appended to
    ``stage_stats["relaxed_limit_points"]``; else the state of ``u`` restored and what was tried, in words."""
    m = solver.model
    step_time = m.time_step
    viscous = [g for g in m.igroups if g.joint_law.relaxation_time_column is not None]
    if not viscous:
        return False, u, None, ("limit_point = \"relax\" needs joints whose law relaxes (a viscous "
                                "regularisation: law = \"composite\"); this model has none")
    own = [g.params_table.copy() for g in viscous]
    saved = _states(m)
    where = solver._where
    r, steps, failed, next_try, gap = R_FIRST, 0, 0, 0, 1
    prev = None
    try:
        while steps < MAX_HOLD_STEPS and r >= R_MIN:
            for g in viscous:
                g.joint_law.set_relaxation_time(g.params_table, TAU_HOLD)
            m.time_step = r * TAU_HOLD
            solver._where = f"{where}, relaxing (hold step {steps + 1}, dt = {r:.3g} tau)"
            start = trial if prev is None else trial + HOLD_PREDICTOR * (trial - prev)
            ok, u_hold = _step(solver, start, f_ext, HOLD_MAX_ITERATIONS)[:2]
            for g, p in zip(viscous, own):
                g.params_table[:] = p
            if not ok:
                m.revert()
                failed += 1
                r /= 4.0
                continue
            m.commit()
            steps += 1
            prev, trial = trial, u_hold
            m.time_step = step_time
            balance, f_own = _out_of_balance(m, u_hold, f_ext)
            if balance <= solver.s.force_tolerance:  # settled: an equilibrium of the joints' own law already
                m.commit()
                stage_stats.setdefault("relaxed_limit_points", []).append([float(load_factor), steps])
                return True, u_hold, f_own, ""
            m.revert()
            # the stage's own step: once near the joints' own equilibrium, after 1, 2, 4, ... hold steps more
            # each time it fails (a try that fails costs a whole Newton solve, a hold step a few iterations)
            if steps >= next_try and balance <= RETRY_BELOW:
                solver._where = f"{where}, after {steps} hold step(s)"
                ok, u_new, f_int = _step(solver, trial, f_ext, RETRY_MAX_ITERATIONS)
                if ok:
                    m.commit()
                    stage_stats.setdefault("relaxed_limit_points", []).append([float(load_factor), steps])
                    return True, u_new, f_int, ""
                m.revert()
                gap *= 2
                next_try = steps + gap
            r = min(2.0 * r, R_MAX)
    finally:
        for g, p in zip(viscous, own):
            g.params_table[:] = p
        solver._where, m.time_step = where, step_time
    for g, state in saved:
        g.state_committed[:] = state
    m.revert()
    return False, u, None, (f"relaxing the joints at the step's loads did not reach an equilibrium of "
                            f"their own law ({steps} hold steps, {failed} that did not converge, the last "
                            f"dt = {r:.3g} tau)")
