"""The dynamic solver: :class:`DynamicSolver` integrates a model through a dynamic stage.

Nonlinear dynamic analysis under uniform base excitation, displacements relative to the moving supports
(Chopra, *Dynamics of Structures*, 4th ed. 2012, sec. 9.4 and 13.1). The solver sets up a stage and drives its
rooms: the stage's linear terms (:mod:`.equations`), the stability check of a conditionally stable scheme
(:mod:`.stability`), the energy balance (:mod:`.energy`), the step control (:mod:`.step_control`: fixed steps
halved where they fail, or dt = "auto"), the implicit step (:mod:`.implicit`, with the effective-matrix solver
of :mod:`.effective` and the joint-space systems of :mod:`masonrydam.solvers.joint_space`) and the explicit step
(:mod:`.explicit`). States are full-DOF arrays (n_dof,) in m, m/s, m/s2; times in s; energies in J. The theory,
its references and what was measured are in docs/dynamics.md.
"""
from __future__ import annotations

import time

import numpy as np
from threadpoolctl import threadpool_limits

from ...assembly.elastic import elastic_joint_full
from ...assembly.mass import MassMatrix
from ...errors import RunStopped, SceneError, StepInterrupted
from ...materials.joint_laws import joint_laws
from ..linear.direct import Factorization, resolve_backend
from ..newton import within_step_stop
from .compiled_loop import CompiledLoop, compiled_loop_off
from .effective import MAX_CACHED, EffectiveSolver
from .energy import EnergyBalance
from .equations import StageEquations
from .explicit import run_central_difference
from .implicit import ImplicitStep, JointSpaces
from .settings import OPEN_TANGENT_DYNAMIC, DynamicSettings
from .stability import check_time_step, stable_step
from .stage import DynamicStage, DynamicState, DynamicStats, StepState
from .step_control import AdaptiveStepping, FixedSteps

#: the open-joint tangent factor the static solver regularises with, restored after a dynamic stage
#: (:data:`masonrydam.solvers.static.stepping.OPEN_TANGENT_REGULAR`)
OPEN_TANGENT_AFTER_STAGE = 1e-6


class DynamicSolver:
    """Time integration of a :class:`~masonrydam.assembly.model.Model` through a :class:`~.stage.DynamicStage`.

    ``run(stage, u0, ...)`` continues from the displacement ``u0`` and the joint state committed in
    the model (the static state) and returns the final :class:`~.stage.DynamicState`. ``on_step(rec)`` is
    called for every recorded step with a dict: ``step`` (index within the stage), ``t`` (s), ``u``,
    ``v``, ``a`` (relative, full-DOF), ``a_abs`` (absolute), ``ag`` (dim,) m/s2, ``energy`` (dict, J),
    ``iterations`` (Newton iterations since the last record), ``reaction`` (full-DOF, N, at the
    constrained DOFs; zero elsewhere), ``final`` (bool).

    ``stop_requested()``, when given, is asked after every converged step (and between the Newton iterations of an
    implicit step, which is then abandoned); a status it returns (e.g.
    ``"interrupted"``) records that step (if the stride skipped it) and raises
    :class:`~masonrydam.errors.RunStopped` naming the step and the time.
    """

    def __init__(self, model, settings: DynamicSettings, mass: MassMatrix | None = None, progress=None,
                 stop_requested=None):
        self.model, self.s = model, settings
        model.use_stored_frames()  # the joints' forces-only evaluations from stored frames, as the compiled loop's
        self.mass = mass if mass is not None else MassMatrix(model, settings.mass == "lumped")
        if self.mass.lumped != (settings.mass == "lumped"):
            raise ValueError("the mass matrix passed does not match settings.mass")
        self.progress = progress
        self.stop_requested = stop_requested
        #: raises StepInterrupted between two Newton or joint-space iterations of an implicit step (a step of a large
        #: 3D model in the general Newton path can take minutes, a joint-space attempt 5-13 s on the 8-monolith dam)
        self._stop_within_step = within_step_stop(stop_requested)
        self.stats = DynamicStats()
        self.backend = resolve_backend(settings.linear_solver)
        self._elastic_joints = None  # the full-DOF elastic joint stiffness, computed once if needed

    def _elastic_joints_full(self):
        if self._elastic_joints is None:
            self._elastic_joints = elastic_joint_full(self.model)
        return self._elastic_joints

    # -- a stage ------------------------------------------------------------------------------------
    def run(self, stage: DynamicStage, u0=None, v0=None, a0=None, f_static=None, equilibrate=True, t0=0.0,
            energy0=None, on_step=None, record_initial=True, fluid0=None) -> DynamicState:
        """Integrate ``stage`` from ``u0`` (m, full-DOF; default zero) and ``v0`` (m/s; default zero) at
        time ``t0``; the joints start from the state committed in the model.

        f_static: constant external load (full-DOF, N; default zero): the loads of the static stages.
        equilibrate: take the constant load on the free DOFs as ``f_int(u0)`` (the static state carried
        over exactly, the structure starts at rest in equilibrium; the difference from ``f_static``
        (the static solver's tolerance) is reported in ``stats.static_residual``). Pass False to start
        from a state that is not in equilibrium (e.g. a block released from a tilted position).
        a0: initial acceleration (default: from the equation of motion at t0).
        fluid0: the compressible reservoir's state at t0 (default: at rest), e.g. ``state.fluid`` of the
        stage before.
        """
        t_wall = time.perf_counter()
        m, s = self.model, self.s
        steps_before, rejected_before = self.stats.steps, self.stats.steps_rejected
        self.on_step = on_step or (lambda rec: None)
        self._check_joint_laws()
        eq = self.eq = StageEquations(m, s, self.mass, stage, self._elastic_joints_full)
        self.energy = EnergyBalance(m, s, eq, self.stats)
        free = eq.free
        u = np.zeros(m.n_dof) if u0 is None else np.array(u0, dtype=np.float64)
        v = np.zeros(m.n_dof) if v0 is None else np.array(v0, dtype=np.float64)
        self.f_static = np.zeros(m.n_dof) if f_static is None else np.asarray(f_static, dtype=np.float64).copy()
        dtc = check_time_step(eq, s, self.backend, self.stats)
        dt_reason = None
        if s.stable_step:  # dt = "auto" with an explicit scheme: the stage's dt is its output interval
            interval = s.dt
            s.dt, per_interval = stable_step(interval, dtc, s.stability_safety)
            s.stable_step = False  # chosen: the settings now hold the step
            stage.output_stride *= per_interval
            dt_reason = (f"dt = auto: {s.dt:.4g} s = output interval {interval:g} s / {per_interval}, the largest "
                         f"such step below {s.stability_safety:g} x dt_crit ({dtc:.4g} s, {self.stats.dt_limit}"
                         + (", lowered by the stiffness part of the Rayleigh damping" if s.damping is not None
                            and s.damping.beta > 0 else "") + ")")
        m.set_open_tangent(OPEN_TANGENT_DYNAMIC)
        m.time_step = 0.0  # the state carried over, not a step in time
        stepping = None
        try:
            st = self._initial_state(stage, u, v, a0, t0, equilibrate, fluid0)
            self.energy.start(st, energy0)
            self._iters_since_record = 0
            self._last_emitted_t = None if record_initial else st.t
            if record_initial:
                self._emit(stage, 0, st, final=False)
            if s.scheme.explicit:
                st = run_central_difference(m, s, eq, self.energy, self.stats, stage, st, self.record_step,
                                            self.fail)
            else:
                # "auto": the all-stick matrices get the L D L^T with fast substitutions (linear/direct.py)
                # nonlinear blocks change every entry of the tangent in every iteration: no low-rank
                # updates (their search costs and never pays), and a new factorization reuses the
                # symbolic analysis of the one it evicts (same pattern; PARDISO phase 22)
                self.effective = EffectiveSolver(m.indptr, m.indices, eq.n, self.backend,
                                                 s.low_rank_max if m.condensable else 0, max_cached=MAX_CACHED,
                                                 stats=self.stats, symmetric_fast=s.linear_solver == "auto",
                                                 reuse_analysis=not m.condensable)
                ref = self.effective.factorize(eq.elastic_effective(s.dt), pin=True, key=("elastic", s.dt),
                                               symmetric=True)
                self.joint_spaces = JointSpaces(m, s, eq, self.effective, self.stats,
                                                extra_levels=stage.levels if s.adaptive else 0,
                                                stop_check=self._stop_within_step)
                self.joint_spaces.set_up(ref)
                stepping = (AdaptiveStepping(self, s, eq, self.energy, self.stats) if s.adaptive
                            else FixedSteps(self, s, self.stats))
                self.compiled_loop = None
                self.stage_duration = stage.duration
                why_not = compiled_loop_off(m, s, eq, self.joint_spaces.by_step.get(s.dt))
                if why_not:
                    self.stats.compiled_loop_off = why_not
                else:
                    self.compiled_loop = CompiledLoop(self)
                self._last_converged = (0, st)
                try:
                    # one BLAS thread: the dense LU of the joint-space solver (LAPACK) must be bitwise
                    # reproducible, and with few cores threads only slowed these small systems down
                    with threadpool_limits(limits=1, user_api="blas"):
                        st = stepping.run(stage, st)
                except StepInterrupted as stop:  # a stop asked for within a step: keep the last converged one
                    k, last = self._last_converged
                    self.refuse_step(last)
                    self.fail(stage, last, RunStopped(stop.status, f"at step {k} of {stage.n_steps} (t = {last.t:.4g} s) "
                                                                   f"of stage '{stage.name}', within the step after it "
                                                                   "(abandoned)"))
                finally:
                    self.joint_spaces.close()  # their factors and columns: each stage sets up its own
        finally:
            m.set_open_tangent(OPEN_TANGENT_AFTER_STAGE)
            self.stats.wall_time_s += time.perf_counter() - t_wall
        entry = {"stage": stage.name, "steps": self.stats.steps - steps_before, "dt": s.dt, "integrator": s.integrator,
                 "dt_critical": dtc}
        if dt_reason is not None:
            entry["dt_reason"] = dt_reason
        if s.local_damping > 0.0:
            entry["local_damping"] = s.local_damping
        if s.adaptive:
            entry.update({"dt": "auto", "dt_max": s.dt, "dt_min": s.dt_min, "tolerance": s.tolerance,
                          "steps_rejected": self.stats.steps_rejected - rejected_before,
                          "dt_smallest": stepping.smallest_step, "dt_largest": stepping.largest_step})
        self.stats.per_stage.append(entry)
        return DynamicState(st.t, st.u, st.v, st.a, st.energy, st.fluid, st.fw)

    def _check_joint_laws(self):
        """Refuse a joint set whose law has no dynamic step (``JointLaw.dynamics``: its energy split and
        joint-space kernels are not written)."""
        static_only = [g for g in self.model.igroups if not g.joint_law.dynamics]
        if static_only:
            g = static_only[0]
            usable = ", ".join(f'"{law.name}"' for law in joint_laws() if law.dynamics)
            raise SceneError(f"joints.{g.name}.law", f"the {g.joint_law.title} joint law is available in static stages "
                                                     "only so far (its energy split and joint-space kernels are not "
                                                     f"written); use law = {usable} for a dynamic analysis")

    def _initial_state(self, stage, u, v, a0, t0, equilibrate, fluid0):
        """The stage's initial :class:`~.stage.StepState` at ``t0``: the static state carried over (its forces
        taken as the constant load where ``equilibrate``), displaced by ``stage.initial_displacement`` where
        given, and the acceleration from the equation of motion unless ``a0`` is given."""
        m, eq = self.model, self.eq
        free = eq.free
        f_int, K = m.evaluate(u, want_tangent=True)
        fs = self.f_static[free].copy()
        if equilibrate:
            diff = f_int[free] - fs
            scale = max(np.linalg.norm(fs), np.linalg.norm(f_int[free]), 1e-30)
            self.stats.static_residual = float(np.linalg.norm(diff) / scale)
            fs = f_int[free].copy()
        eq.static_load = fs
        if stage.initial_displacement is not None:  # released from a displaced state (the loads stay those
            # of the state it was displaced from, so the displacement is out of equilibrium)
            shift = np.where(np.isnan(stage.initial_displacement), 0.0, stage.initial_displacement)
            shift[~np.isin(np.arange(m.n_dof), free)] = 0.0
            u = u + shift
            f_int, K = m.evaluate(u, want_tangent=True)
            m.commit()  # the displaced state is where the stage starts: its joint states (slip) included
        ag0 = eq.ground_at(0.0)
        if a0 is None:
            # (the pressure of a compressible reservoir is a state: its force at t0 is that of the
            # water carried over from the stage before, zero for water at rest)
            rhs = fs + eq.ground_load(ag0, 0.0) + eq.update_state_force() - f_int[free] - eq.damping_force(v[free])
            if eq.fluid is not None and fluid0 is not None:
                rhs = rhs.copy()
                rhs[eq.fluid.wet_eq] += eq.fluid.force(fluid0)
            a = np.zeros(m.n_dof)
            if eq.mass_diagonal is not None:
                md = eq.mass_diagonal
                with np.errstate(divide="ignore", invalid="ignore"):
                    a[free] = np.where(md > 0, rhs / np.where(md > 0, md, 1.0), 0.0)
            else:
                # DOFs without mass (massless rock) start with zero acceleration: their rows of the
                # positive semi-definite M are zero, the rest is solved on its own
                has = eq.mass_free.diagonal() > 0
                if has.all():
                    a[free] = Factorization(eq.mass_free, self.backend).solve(rhs)
                elif has.any():
                    Mh = eq.mass_free[has][:, has].tocsr()
                    a[free[has]] = Factorization(Mh, self.backend).solve(rhs[has])
        else:
            a = np.array(a0, dtype=np.float64)
        st = StepState(t0, 0.0, u, v, a, f_int, None if np.array_equal(K.data, eq.elastic_data) else K.data.copy(),
                       ag0)
        st.Kc_u = m.continuum_force(u)
        if eq.fluid is not None:  # the water from the stage before, or at rest
            st.fluid = fluid0 if fluid0 is not None else eq.fluid.initial_state()
            st.fw = eq.fluid.force(st.fluid)
        return st

    # -- what the step control drives -----------------------------------------------------------
    def try_step(self, st, t_end, h, can_split=True, error_check=None, split_joint_space=True,
                 joint_space_result=None):
        """One implicit step of size ``h`` from the committed state ``st`` to stage time ``t_end``: (ok,
        new_state, why); see :meth:`~.implicit.ImplicitStep.solve` (``joint_space_result``: a step the compiled
        loop handed back after its joint-space call)."""
        step = ImplicitStep(self.model, self.s, self.eq, self.effective, self.energy, self.joint_spaces, self.stats,
                            self._count_iterations, st, t_end, h,
                            stop_check=self._stop_within_step)
        return step.solve(can_split=can_split, error_check=error_check, split_joint_space=split_joint_space,
                          joint_space_result=joint_space_result)

    def refuse_step(self, st):
        """Back to the committed state ``st`` after a step that failed or was refused: the joints' trial states
        reverted, their relative displacements and tractions restored."""
        self.model.revert()
        self.energy.restore_joint_fields(st)

    def _count_iterations(self, n):
        self._iters_since_record += n

    def record_step(self, stage, k, st, n_steps):
        """After converged step ``k`` of ``n_steps``: recorded every ``output_stride`` steps and at the last,
        the progress told, and the run stopped where a stop was requested."""
        self._last_converged = (k, st)
        self._maybe_emit(stage, k, st, n_steps)

    def fail(self, stage, st, exc):
        """Record the last converged state (if not yet recorded) and raise ``exc``."""
        if self._last_emitted_t != st.t:
            self._emit(stage, -1, st, final=True)
        raise exc

    # -- records --------------------------------------------------------------------------------
    def _emit(self, stage, k, st, final):
        m, eq = self.model, self.eq
        a_abs = st.a.copy()
        if eq.terms.support_excitation:  # else the motion is total already
            for c in range(m.dim):
                a_abs[c::m.dim] += st.ag[c]
        rec = {"step": k, "t": st.t, "u": st.u, "v": st.v, "a": st.a, "a_abs": a_abs, "ag": st.ag.copy(),
               "energy": dict(st.energy), "iterations": self._iters_since_record, "final": final,
               "stage_fraction": min(1.0, st.tau / stage.duration),
               "reaction": eq.reaction(st.u, st.v, a_abs, st.f_int, self.f_static, st),
               "bottom_acceleration": eq.bottom_at(st.tau, st.ag),
               "fluid": getattr(st, "fluid", None)}
        self._iters_since_record = 0
        self._last_emitted_t = st.t
        t0 = time.perf_counter()
        self.on_step(rec)
        self.stats.output_time_s += time.perf_counter() - t0

    def between_calls(self, stage, k, st, n_steps):
        """After a call of the compiled step loop that ended between grid points (``st`` past grid point ``k``): the
        last converged state kept, the progress told and a stop asked for, as :meth:`record_step` does without
        recording."""
        self._last_converged = (k, st)
        if self.progress is not None:
            self.progress(st.tau / stage.duration)
        status = self.stop_requested() if self.stop_requested is not None else None
        if status is not None:
            self.fail(stage, st, RunStopped(status, f"after step {k} of {n_steps} (t = {st.t:.4g} s) of stage "
                                                    f"'{stage.name}'"))

    def _maybe_emit(self, stage, k, st, n_steps):
        last = k == n_steps
        if last or k % stage.output_stride == 0:
            self._emit(stage, k, st, final=last)
        if self.progress is not None:
            self.progress(st.tau / stage.duration)
        status = self.stop_requested() if self.stop_requested is not None else None
        if status is not None and not last:
            self.fail(stage, st, RunStopped(status, f"at step {k} of {n_steps} (t = {st.t:.4g} s) of stage "
                                                    f"'{stage.name}'"))
