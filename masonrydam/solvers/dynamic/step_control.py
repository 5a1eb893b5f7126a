"""Step control of the implicit dynamic stages: fixed steps halved where they fail (:class:`FixedSteps`) and
error-controlled steps, dt = "auto" (:class:`AdaptiveStepping`).

Fixed steps: ``dt`` each (the last one ends at the stage's duration); a step that fails (no convergence, a
singular matrix, NaN, energy created) is reverted and split in two halves, recursively, at most
``max_substeps`` times (:class:`masonrydam.solvers.newton.StepCutting`).

dt = "auto": steps of ``dt_max / 2^k`` chosen by the larger of three local errors (:meth:`AdaptiveStepping.step_error`:
the Zienkiewicz-Xie estimate, the ground motion between a step's ends, the energy of contact events) against
``tolerance``; refused steps are retried smaller, steps never cross a multiple of dt_max (the output grid), and a
step that does not converge at dt_min is halved up to ``max_substeps`` more times. See docs/dynamics.md and, for
what the tolerance buys, docs/accuracy.md.

Both drive a ``solver`` that offers ``try_step(st, t_end, h, can_split, error_check, split_joint_space)`` ->
(ok, new_state, why), ``refuse_step(st)`` (revert to the committed state ``st``), ``record_step(stage, k, st,
n_steps)`` and ``fail(stage, st, exc)`` (:class:`~.solver.DynamicSolver`).
"""
from __future__ import annotations

import math
from functools import partial

import numpy as np

from ...errors import ConvergenceError
from ..newton import StepCutting
from .kernels import difference_norm
from .loop_kernel import HANDED_BACK

#: dt = "auto": a step is taken one level larger when its error is below this fraction of the tolerance
#: (the Zienkiewicz-Xie estimate goes like h^3 on a smooth response: doubling h multiplies it by 8)
ADAPTIVE_GROW_FRACTION = 0.1
#: dt = "auto": steps taken at a level after a refusal before the step may grow again (a step that grows
#: straight back into the event that refused it is refused again: measured on the Koyna example at
#: tolerance 1e-5, 36 874 refusals for 80 809 steps without this hold)
ADAPTIVE_HOLD_STEPS = 4
#: dt = "auto": RMS displacement (m) below which the Zienkiewicz-Xie error is measured absolutely
ADAPTIVE_DISPLACEMENT_FLOOR = 1e-4
#: how a step refused by dt = "auto"'s error control says so
ERROR_REFUSAL = "local error"

#: a call of the compiled step loop (:mod:`.compiled_loop`) ends at the next record or after this many grid points
#: (steps of a fixed dt, multiples of dt_max with dt = "auto"), whichever comes first: Python then tells the
#: progress and asks whether to stop (signals are held during a call), so a stop waits at most this many grid
#: points; a call costs about 0.1-0.2 ms of Python
GRID_POINTS_PER_CALL = 64


def last_grid_point(k: int, stride: int, n_steps: int) -> int:
    """The grid point a call of the loop starting toward grid point ``k`` ends at: the next record (every ``stride``),
    at most :data:`GRID_POINTS_PER_CALL` on, never the stage's last (``n_steps``, which may be shorter)."""
    return min(-(-k // stride) * stride, n_steps - 1, k + GRID_POINTS_PER_CALL - 1)


def step_end(k: int, n_steps: int, dt: float, duration: float, tau: float) -> tuple[float, float]:
    """End time and size of step ``k`` (1-based) of a stage: nominal steps use h = dt exactly (the
    cached effective matrix is keyed by its values); the last step ends at the stage's duration."""
    t_end = min(k * dt, duration) if k == n_steps else k * dt
    h = dt if k < n_steps or abs(t_end - tau - dt) <= 1e-9 * dt else t_end - tau
    return t_end, h


class FixedSteps:
    """Steps of ``dt``, each halved where it fails, at most ``max_substeps`` times in a row. Where the solver has a
    ``compiled_loop`` (:class:`~.compiled_loop.CompiledLoop`), the steps up to the next record go through it, and a
    step it hands back is finished here from its joint-space result."""

    def __init__(self, solver, settings, stats):
        self.solver, self.s, self.stats = solver, settings, stats
        self.cutting = StepCutting(settings.max_substeps)

    def run(self, stage, st):
        """Integrate ``stage`` from the committed state ``st``; returns the last state."""
        s = self.s
        n_steps = stage.n_steps
        loop = getattr(self.solver, "compiled_loop", None)
        k = 1
        while k <= n_steps:
            handed_back = None
            if loop is not None and k < n_steps:
                # the steps up to the next record (not the stage's last, which may be shorter) in one call
                last = last_grid_point(k, max(1, stage.output_stride), n_steps)
                st, k_done, handed_back = loop.run(st, k, last, self.cutting.can_cut(0))
                if k_done >= k:
                    self.solver.record_step(stage, k_done, st, n_steps)
                k = k_done + 1
                if k_done == last:
                    continue
            t_end, h = step_end(k, n_steps, s.dt, stage.duration, st.tau)
            if h <= 1e-9 * s.dt:
                break
            st = self.advance(stage, st, t_end, h, 0, handed_back)
            self.stats.steps += 1
            self.solver.record_step(stage, k, st, n_steps)
            k += 1
        return st

    def advance(self, stage, st, t_end, h, level, joint_space_result=None):
        """Advance the committed state ``st`` by ``h`` to stage time ``t_end`` (``level``: halvings so far),
        halving on failure; ``joint_space_result``: the compiled loop's joint-space call for this step."""
        can_cut = self.cutting.can_cut(level)
        ok, new, why = self.solver.try_step(st, t_end, h, can_split=can_cut, joint_space_result=joint_space_result)
        if ok:
            return new
        self.solver.refuse_step(st)
        if not can_cut:
            self.solver.fail(stage, st, ConvergenceError(
                f"dynamic stage '{stage.name}': no convergence in the step from t = {st.t:.6g} s to "
                f"{st.t + h:.6g} s (sub-step {h:.4g} s after {level} halving(s) of dt = {self.s.dt:g} s; "
                f"max_substeps = {self.s.max_substeps}): {why}. Every converged step before t = {st.t:.6g} s "
                "was kept"))
        self.stats.substeps += 1
        st = self.advance(stage, st, st.tau + 0.5 * h, 0.5 * h, level + 1)
        return self.advance(stage, st, t_end, 0.5 * h, level + 1)


class AdaptiveStepping:
    """dt = "auto" over one stage: steps of dt / 2^level, the level set by the local error of each step
    (:meth:`step_error`); ``equations``: the stage's :class:`~.equations.StageEquations` (free DOFs, ground
    motion), ``energy``: its :class:`~.energy.EnergyBalance`. ``smallest_step``, ``largest_step`` (s): the
    steps taken in the stage."""

    def __init__(self, solver, settings, equations, energy, stats):
        self.solver, self.s, self.energy, self.stats = solver, settings, energy, stats
        self.free = equations.free
        self.ground = equations.ground
        self.smallest_step, self.largest_step = math.inf, 0.0
        #: the largest ||u - u_0|| (m) and |v| (m/s) of the accepted steps so far, and the records' peak
        #: ground velocity (m/s): the scales of the error measures
        self.u_peak = self.v_peak = 0.0
        self.peak_ground_velocity = 0.0
        self.u_stage_start = None
        #: the last step's error (relative) and the levels its refusal asks to go down
        self.last_error, self.error_levels = 0.0, 0

    def run(self, stage, st):
        """Integrate ``stage`` from the committed state ``st``; returns the last state.

        A step above the tolerance is refused and retried smaller, one well below it lets the next step
        double. Steps never cross a multiple of dt (the largest step), so the output, every
        ``output_stride`` multiples of dt, lands on a regular grid without interpolation, and the
        effective matrices and joint-space systems exist for a few step sizes only (each set up the first
        time it is used). A step that does not converge is retried smaller like a refused one; below dt_min
        (and ``max_substeps`` further halvings) the run stops with a ConvergenceError after recording the
        last converged state."""
        s, solver = self.s, self.solver
        n_steps, top = stage.n_steps, stage.levels
        #: the largest number of halvings of dt by the error control (dt_min), for the compiled loop
        self.top = top
        self.u_stage_start = st.u[self.free].copy()
        self.u_peak = self.v_peak = 0.0
        self.peak_ground_velocity = max((g.peak_velocity for g in self.ground.values()), default=0.0)
        self.last_error, self.error_levels = 0.0, 0
        level = hold = 0
        last_level = top + s.max_substeps
        loop = getattr(solver, "compiled_loop", None)
        stride = max(1, stage.output_stride)
        k = 0
        while k < n_steps:
            k += 1
            t_grid = min(k * s.dt, stage.duration)
            while t_grid - st.tau > 1e-9 * s.dt:
                handed_back = None
                if loop is not None and k < n_steps and loop.joint_space(s.dt / 2 ** level) is not None:
                    # the steps up to the next record grid point (not the stage's last) in compiled calls
                    last = last_grid_point(k, stride, n_steps)
                    st, outcome, k, on_grid, handed_back, level, hold = loop.run_adaptive(st, k, last, self, level,
                                                                                          hold)
                    if on_grid:
                        break
                    # before grid point k: the progress told and a stop asked for, no record
                    solver.between_calls(stage, k - 1, st, n_steps)
                    t_grid = min(k * s.dt, stage.duration)
                    if outcome != HANDED_BACK:  # another step size: its joint space, if it has one yet
                        continue
                h = s.dt / 2 ** level
                t_end = st.tau + h
                if t_end > t_grid - 1e-9 * s.dt:  # the step that reaches the grid point (or the stage's end)
                    if abs(t_grid - t_end) > 1e-9 * s.dt:
                        h = t_grid - st.tau  # a shorter last step of the stage
                    t_end = t_grid
                # a joint-space iteration that does not converge goes on in the general path at every
                # level (the error decides the step size); below dt_min a step is halved for Newton's sake only
                ok, new, why = solver.try_step(st, t_end, h, can_split=level < top,
                                               error_check=partial(self.step_error, enforce=level < top),
                                               split_joint_space=False, joint_space_result=handed_back)
                if not ok:
                    solver.refuse_step(st)
                    self.stats.steps_rejected += 1
                    if level >= last_level:
                        solver.fail(stage, st, ConvergenceError(
                            f"dynamic stage '{stage.name}': no convergence in the step from t = {st.t:.6g} s to "
                            f"{st.t + h:.6g} s (step {h:.4g} s: dt_min = {s.dt_min:.4g} s and max_substeps = "
                            f"{s.max_substeps} further halvings): {why}. Every converged step before t = "
                            f"{st.t:.6g} s was kept"))
                    if why.startswith(ERROR_REFUSAL):
                        level = min(level + self.error_levels, top)
                    else:
                        level += 1
                    hold = ADAPTIVE_HOLD_STEPS
                    continue
                st = new
                self.stats.steps += 1
                self.smallest_step = min(self.smallest_step, h)
                self.largest_step = max(self.largest_step, h)
                self.stats.dt_smallest = min(self.stats.dt_smallest, h)
                self.stats.dt_largest = max(self.stats.dt_largest, h)
                hold -= 1
                if level > 0 and hold <= 0 and self.last_error < ADAPTIVE_GROW_FRACTION * s.tolerance:
                    # one level up where the larger step stays on its own grid (steps never cross a
                    # multiple of dt, and a step of dt / 2^(level-1) starts at one of its multiples)
                    h_up = s.dt / 2 ** (level - 1)
                    if abs(st.tau / h_up - round(st.tau / h_up)) < 1e-6:
                        level -= 1
                elif level > top:
                    level = top  # a halving below dt_min for convergence: back to dt_min
            solver.record_step(stage, k, st, n_steps)
        return st

    def step_error(self, new, st, h, enforce=True):
        """Local error of the step st -> new for dt = "auto" (None when it is within the tolerance,
        else why not). Three measures, the largest counts:

        - the Zienkiewicz-Xie estimate of the Newmark family, ``e = h^2 (beta - 1/6) (a_{n+1} - a_n)``
          (Zienkiewicz & Xie 1991, Earthquake Eng. Struct. Dyn. 20:871-887: the difference between the
          scheme's displacement and a third-order Taylor expansion), as ``||e|| / U`` (Euclidean norms
          over the free DOFs), U the largest ``||u - u_0||`` since the stage began (this step included;
          at least :data:`ADAPTIVE_DISPLACEMENT_FLOOR` per DOF, so that the first steps of a quiet
          record are not driven to dt_min);
        - the ground motion: the velocity the step misses by taking the ground acceleration as linear
          between its ends (:meth:`~.ground_motion.GroundMotion.chord_error`: a pulse that ends, or record
          samples inside a step longer than the record's interval) over the larger of the peak ground velocity and the
          largest relative velocity so far. The displacement estimate above cannot see it: the velocity
          error it leaves grows into the displacement over the rest of the record;
        - events: the energy a contact event leaves unaccounted by the trapezoidal rule (the step's
          change of ``joint_contact``, see :func:`~.kernels.joint_step_energy`: a joint point
          that opens or closes within the step) over the largest energy term so far. It shrinks as the
          event is resolved (the penetration stepped over goes like h), so steps are refined where
          joints open and close; sliding that starts or stops shows in the first measure as the
          jump of the acceleration.
        """
        s = self.s
        error_constant = s.scheme.error_constant(s.alpha, s.rho_inf)
        free = self.free
        # Euclidean norms over the free DOFs, as Zienkiewicz & Xie: a joint's rattle, a few DOFs with
        # large accelerations, weighs by its share of the motion, not as much as the whole structure
        u1, v1, a1 = new.free_values(free)
        e_zx = h * h * error_constant * difference_norm(a1, st.free_values(free)[2])
        u_peak = max(self.u_peak, difference_norm(u1, self.u_stage_start))
        eta_zx = e_zx / max(u_peak, ADAPTIVE_DISPLACEMENT_FLOOR * math.sqrt(len(free)))
        # the ground load between the step's ends: the velocity missed, over the velocity scale
        v_peak = max(self.v_peak, float(np.max(np.abs(v1), initial=0.0)))
        miss = max((g.chord_error(st.tau, new.tau) for g in self.ground.values()), default=0.0)
        eta_input = miss / max(v_peak, self.peak_ground_velocity, 1e-300) if miss > 0 else 0.0
        scale = max(self.energy.scale, abs(new.energy["input"]), abs(new.energy["external"]), 1e-300)
        eta_event = abs(new.energy["joint_contact"] - st.energy["joint_contact"]) / scale
        if self.energy.scale <= 0:
            eta_event = 0.0
        eta = max(eta_zx, eta_input, eta_event)
        self.last_error = eta
        if eta <= s.tolerance or not enforce:  # at dt_min the step is taken whatever its error
            self.error_levels = 0
            self.u_peak, self.v_peak = u_peak, v_peak  # the peaks of accepted steps only
            return None
        # error ~ h^3: the level that should bring it within 0.8 x the tolerance
        self.error_levels = max(1, int(math.ceil(math.log2((eta / (0.8 * s.tolerance)) ** (1.0 / 3.0)))))
        what = ("contact events" if eta_event >= eta else "ground motion between the step's ends" if eta_input >= eta
                else "Zienkiewicz-Xie estimate")
        return f"{ERROR_REFUSAL} {eta:.3g} > tolerance {s.tolerance:g} ({what})"
