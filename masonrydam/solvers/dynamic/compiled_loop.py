"""The compiled step loop of the implicit stages: :class:`CompiledLoop` runs the steps between two records in one call
of :func:`.loop_kernel.implicit_steps` and hands a step that leaves the common path back to the Python step.

The common path (:func:`compiled_loop_off` says why a stage is not on it): an implicit scheme, at a fixed dt or
with dt = "auto" (the steps of a size whose joint space is set up; a sub-step size's is set up by the first Python
step that needs it); linear blocks with small kinematics; every joint set nonlinear with the same fused law, small
kinematics and no rate-dependence, solved in joint space by the compiled kernel; no compressible water, no loads
given in time, no state forces, no push of a reservoir bottom. A step on it is the Python step's arithmetic, bit
for bit (``tests/solvers/test_compiled_loop.py``). One that leaves it (the joint-space iteration does not converge,
the full residual is above the tolerance, the step gains energy, its local error is above the tolerance, NaN) is
finished by :class:`~.implicit.ImplicitStep` from its joint-space result, and a refused one is halved or retried
smaller by the step control (:mod:`.step_control`) as before. Between two calls Python records the state (every
``output_stride`` grid points, at least every :data:`~.step_control.GRID_POINTS_PER_CALL`), tells the progress
and asks whether to stop; the steps in between are not asked.
See docs/dynamics.md ("The compiled step loop").
"""
from __future__ import annotations

import numpy as np

from ..joint_space import MAX_INITIAL_STIFFNESS_ITERATIONS, SPLIT_INITIAL_STIFFNESS_ITERATIONS
from ..joint_space.signals import stop_signals_held
from ..joint_space.step_kernel import AVAILABLE
from .energy import ENERGY_KEYS
from .implicit import JOINT_SPACE_FORCE_FRACTION
from .loop_kernel import (ADAPT_DISPLACEMENT_FLOOR, ADAPT_ERROR_CONSTANT, ADAPT_GROW_FRACTION, ADAPT_LARGEST,
                          ADAPT_LAST_ERROR, ADAPT_PEAK_GROUND_VELOCITY, ADAPT_SMALLEST, ADAPT_TOLERANCE, ADAPT_U_PEAK,
                          ADAPT_V_PEAK, E_BOND, E_CONTACT, E_NUMERICAL, HANDED_BACK, N_ADAPT, N_TOTALS, implicit_steps)
from .stage import StepState
from .step_control import ADAPTIVE_DISPLACEMENT_FLOOR, ADAPTIVE_GROW_FRACTION

#: implicit stages run their common-path steps in the compiled loop (False: every step in Python, the same results;
#: for comparisons and benchmarks)
COMPILED_LOOP = True


def compiled_loop_off(model, settings, equations, joint_space) -> str:
    """Why a stage's steps cannot take the compiled loop ("" where they can): the conditions of the module's
    docstring, checked on the ``model``, its stage ``settings`` and ``equations`` and the nominal step's
    :class:`~masonrydam.solvers.joint_space.JointSpace` (None: none set up)."""
    m, s, eq = model, settings, equations
    if not COMPILED_LOOP:
        return "switched off (compiled_loop.COMPILED_LOOP)"
    if not AVAILABLE:
        return "numba's LAPACK binding is not available"
    if s.scheme.explicit:
        return "an explicit scheme"
    if joint_space is None or not joint_space.compiled:
        return "no compiled joint-space step (joint_space off, no nonlinear joints, or flexibility computed as needed)"
    if not m.condensable or m.plastic or m.large or m.rate_dependent:
        return "nonlinear or rate-dependent blocks"
    groups = list(m.igroups)
    g0 = groups[0]
    for g in groups:
        law = g.joint_law
        if (not g.nonlinear or law is not g0.joint_law or not law.fused or g.kinematics != "small"
                or law.time_step_column is not None or g.N.shape != g0.N.shape or not np.array_equal(g.N, g0.N)
                or g.dofs.shape[1] != g0.dofs.shape[1]):
            return (f"joint set '{g.name}' (linear, a law without a fused kernel or with a time step, large "
                    "kinematics, or another law or integration rule than the first set's)")
    if eq.fluid is not None:
        return "a compressible reservoir"
    terms = eq.terms
    if terms.force is not None or terms.state_force is not None or eq.bottom_influence_free is not None:
        return "loads given in time, state forces or a reservoir bottom's push"
    return ""


def _joined(arrays):
    return np.ascontiguousarray(np.concatenate(arrays))


class CompiledLoop:
    """The compiled step loop of one implicit stage (see the module's docstring): ``solver`` the
    :class:`~.solver.DynamicSolver` running the stage (its model, settings, equations, energy balance, joint spaces
    and stats). :meth:`run` takes the steps of a fixed dt, :meth:`run_adaptive` those of dt = "auto"."""

    def __init__(self, solver):
        m, s, eq = solver.model, solver.s, solver.eq
        self.solver, self.model, self.s, self.eq = solver, m, s, eq
        self.energy, self.stats = solver.energy, solver.stats
        self.groups = groups = list(m.igroups)
        beta, gamma, am, af = s.coefficients()
        self.scheme = (beta, gamma, am, af, (1.0 - am) / (1.0 - af), am / (1.0 - af), af / (1.0 - af))
        self.growth_enabled = bool(m.nonlinear and s.energy_growth_tolerance > 0)
        # the joint sets as one: elements one set after the other, parameter rows offset
        self.ends = np.cumsum([g.n_elem for g in groups]).astype(np.int64)
        offsets = np.cumsum([0] + [len(g.params_table) for g in groups[:-1]])
        self.joint_fixed = (
            _joined([g.conn for g in groups]), np.ascontiguousarray(groups[0].N), _joined([g.frame for g in groups]),
            _joined([g.jw for g in groups]), _joined([g.thickness for g in groups]),
            _joined([g.params_table for g in groups]),
            _joined([g.param_index + off for g, off in zip(groups, offsets)]).astype(groups[0].param_index.dtype),
            groups[0].law_id, _joined([g.dofs for g in groups]).astype(np.int64), self.ends)
        self.energy.joint_stored()  # (the compliances, once per stage)
        self.energy_fixed = (_joined([c[0] for c in self.energy._compliance]),
                             _joined([c[1] for c in self.energy._compliance]), _joined(self.energy._weights()))
        mass = eq.mass_free
        self.mass_csr = ((mass.indptr, mass.indices, mass.data) if mass is not None
                         else (np.zeros(1, np.int32), np.zeros(0, np.int32), np.zeros(0)))
        C = eq.damping_free
        self.damping_csr = ((C.indptr, C.indices, C.data) if eq.damped
                            else (np.zeros(1, np.int32), np.zeros(0, np.int32), np.zeros(0)))
        K = m.K_continuum.tocsr()
        self.stiffness_csr = (K.indptr, K.indices, K.data)
        empty = np.zeros(0)
        times, values, steps = [empty] * 3, [empty] * 3, np.ones(3)
        for c, g in eq.ground.items():
            times[c], values[c], steps[c] = g._times, g.values, g.dt
        self.ground = (tuple(times), tuple(values), steps, np.ascontiguousarray(eq.mass_influence_free),
                       bool(eq.terms.support_excitation))
        self.free = np.asarray(eq.free, dtype=np.int64)

    def joint_space(self, h):
        """The joint space of step size ``h`` where it is set up and solved by the compiled kernel, else None (the
        step is the Python step's, which sets up a sub-step size's joint space when it first needs it)."""
        js = self.solver.joint_spaces.by_step.get(h)
        return js if js is not None and js.compiled else None

    def run(self, st, k_first, k_last, can_split):
        """Fixed dt: steps ``k_first`` .. ``k_last`` (1-based, each ending at ``k dt``) from the committed state ``st``;
        ``can_split``: a failed step may still be halved (the joint-space iteration's limit and the energy-growth
        test depend on it, as in :meth:`~.implicit.ImplicitStep.solve`).

        Returns ``(state, k_done, handed_back)``: the state after the last step taken (``st`` itself where none
        was), its index, and for the step after it, where it was handed back, the joint-space result to finish it
        from (a callable in place of :meth:`~masonrydam.solvers.joint_space.JointSpace.solve_step`; None where the
        step is to be taken from its start by the Python step, or where every step was taken)."""
        js = self.joint_space(self.s.dt)
        control = np.array([0, 0, 0], dtype=np.int64)
        adapt = np.zeros(N_ADAPT)
        n_fixed = SPLIT_INITIAL_STIFFNESS_ITERATIONS if can_split else MAX_INITIAL_STIFFNESS_ITERATIONS
        st, _, k, on_grid, handed_back = self._call(st, k_first, k_last, js, n_fixed, self.growth_enabled and can_split,
                                                    False, control, adapt, np.zeros(0))
        return st, (k if on_grid else k - 1), handed_back

    def run_adaptive(self, st, k_first, k_last, stepping, level, hold):
        """dt = "auto": the steps toward grid points ``k_first`` .. ``k_last`` (multiples of dt_max) at step size
        ``dt / 2^level`` from the committed state ``st`` (before grid point ``k_first``), with
        ``stepping``'s (:class:`~.step_control.AdaptiveStepping`) error control, until grid point ``k_last`` is
        reached, a step takes another size, or one is handed back.

        Returns ``(state, outcome, k, on_grid, handed_back, level, hold)``: the state after the last step taken, the
        kernel's outcome, the grid point it is on (``on_grid``) or works toward, the step handed back (as in
        :meth:`run`) and the step control's level and hold count."""
        s = self.s
        js = self.joint_space(s.dt / 2 ** level)
        control = np.array([level, hold, stepping.top], dtype=np.int64)
        adapt = np.zeros(N_ADAPT)
        adapt[ADAPT_U_PEAK], adapt[ADAPT_V_PEAK], adapt[ADAPT_LAST_ERROR] = (stepping.u_peak, stepping.v_peak,
                                                                            stepping.last_error)
        adapt[ADAPT_SMALLEST], adapt[ADAPT_LARGEST] = np.inf, 0.0
        adapt[ADAPT_TOLERANCE] = s.tolerance
        adapt[ADAPT_ERROR_CONSTANT] = s.scheme.error_constant(s.alpha, s.rho_inf)
        adapt[ADAPT_DISPLACEMENT_FLOOR] = ADAPTIVE_DISPLACEMENT_FLOOR
        adapt[ADAPT_GROW_FRACTION] = ADAPTIVE_GROW_FRACTION
        adapt[ADAPT_PEAK_GROUND_VELOCITY] = stepping.peak_ground_velocity
        st, outcome, k, on_grid, handed_back = self._call(st, k_first, k_last, js, MAX_INITIAL_STIFFNESS_ITERATIONS,
                                                          self.growth_enabled, True, control, adapt,
                                                          stepping.u_stage_start)
        # the peaks and error of the steps it accepted (a step handed back is measured again by the Python step)
        stepping.u_peak, stepping.v_peak = float(adapt[ADAPT_U_PEAK]), float(adapt[ADAPT_V_PEAK])
        stepping.last_error = float(adapt[ADAPT_LAST_ERROR])
        if adapt[ADAPT_LARGEST] > 0:
            stepping.error_levels = 0
            stepping.smallest_step = min(stepping.smallest_step, float(adapt[ADAPT_SMALLEST]))
            stepping.largest_step = max(stepping.largest_step, float(adapt[ADAPT_LARGEST]))
            self.stats.dt_smallest = min(self.stats.dt_smallest, float(adapt[ADAPT_SMALLEST]))
            self.stats.dt_largest = max(self.stats.dt_largest, float(adapt[ADAPT_LARGEST]))
        return st, outcome, k, on_grid, handed_back, int(control[0]), int(control[1])

    def _call(self, st, k_first, k_last, js, n_fixed, growth_check, adaptive, control, adapt, u_stage_start):
        """One call of the kernel (see :meth:`run`); returns (state, outcome, k, on_grid, handed_back)."""
        m, s, eq, groups = self.model, self.s, self.eq, self.groups
        free = eq.free
        m.time_step = s.dt / 2 ** int(control[0])
        joined = [_joined([getattr(g, name) for g in groups])
                  for name in ("state_committed", "state_base", "state_trial", "delta", "traction", "fe")]
        committed, base, trial, delta, traction, fe = joined
        prev = [_joined([j[i] for j in st.joints]) for i in range(3)]
        u, v, a, f_int, kc_u = (np.array(x, dtype=np.float64) for x in (st.u, st.v, st.a, st.f_int, st.Kc_u))
        if eq.damped:
            cv = np.array(st.cv if st.cv is not None else eq.damping_force(st.free_values(free)[1]))
        else:
            cv = np.zeros(eq.n)
        energy = np.array([float(st.energy.get(key, 0.0)) for key in ENERGY_KEYS])
        stats = self.stats
        energy_stats = np.array([self.energy.scale, stats.energy_growth_max, stats.energy_error_max])
        ref = self.energy._reference
        ka = js.kernel_arguments()
        totals = np.zeros(N_TOTALS, dtype=np.int64)
        u_js = np.empty(m.n_dof)
        ag = np.array(st.ag, dtype=np.float64)
        info = np.zeros(1, dtype=np.int64)
        P, ns = js.base.shape
        with stop_signals_held():  # (a stop asked for within the call is answered after it, at the record)
            result = implicit_steps(
                k_first, k_last, s.dt, self.solver.stage_duration, st.t, st.tau, *self.scheme, self.free,
                eq.kernel_mass_diagonal, *self.mass_csr, eq.damped, *self.damping_csr, *self.stiffness_csr,
                eq.static_load, *self.ground, *self.joint_fixed, *self.energy_fixed, committed, base, trial, delta,
                traction, fe, info, base.reshape(P, ns), *prev,
                ka["fixed"], js.params_table, js.param_index, js.weight, js.base, js.trial, js.traction, js.q, js.qt,
                js.codes, js.info, js.held, js.ST, js.slot, js.wk, ka["dq_last"], ka["has_dq"], ka["JT"], ka["piv"],
                ka["ref_rows"], ka["ref_qt"], ka["has_ref"], ka["max_newton"], n_fixed, ka["flips_before_hold"],
                ka["update_min_changes"], ka["update_change_fraction"], ka["singular_pivot"], ka["latch_column"],
                ka["open_code"], ka["work"], u_js, ka["dq_out"], ka["counts"], ka["err_out"],
                s.force_tolerance, JOINT_SPACE_FORCE_FRACTION, growth_check, s.energy_growth_tolerance,
                energy, ref["kinetic0"], ref["strain0"], ref["stored0"], energy_stats,
                adaptive, control, adapt, u_stage_start,
                u, v, a, f_int, kc_u, cv, ag, totals)
        outcome, k, on_grid, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status = result
        # the joint sets' arrays back as the last step taken committed them: its state, and its relative
        # displacements and tractions (a step handed back after its joints were evaluated left its trial values in
        # the joined arrays; the Python step evaluates them again, and a stop before it records these)
        start = 0
        for g, end in zip(groups, self.ends):
            for name, x in (("state_committed", committed), ("state_base", committed), ("state_trial", committed),
                            ("delta", prev[0]), ("traction", prev[1])):
                getattr(g, name)[...] = x[start:end]
            start = end
        steps = int(totals[0])
        js.keep_compiled_steps(steps, totals, JT, piv, ref_rows, ref_qt, has_ref, ka["dq_last"], has_dq)
        stats.steps += steps
        stats.compiled_loop_steps += steps
        stats.joint_space_steps += steps
        stats.joint_space_iterations += int(totals[1])
        self.solver._count_iterations(int(totals[1]))
        if steps:
            self.energy.scale = float(energy_stats[0])
            stats.energy_growth_max = float(energy_stats[1])
            stats.energy_error_max = float(energy_stats[2])
            if energy_stats[0] > 0:
                stats.energy_error_relative = stats.energy_error_max / self.energy.scale
            stats.energy_scale = self.energy.scale
            stats.energy_numerical = float(energy[E_NUMERICAL])
            stats.energy_contact = float(energy[E_CONTACT])
            stats.energy_bond_break = float(energy[E_BOND])
            st = self._state(t, tau, u, v, a, f_int, kc_u, cv, ag, energy, prev)
        handed_back = None
        if outcome == HANDED_BACK:
            stats.compiled_loop_handbacks += 1
            if status >= 0:  # its joint-space call was made: the Python step goes on from its result
                u_step = u_js.copy()

                def handed_back(*_):
                    return js.finish_compiled_step(status, JT, piv, ref_rows, ref_qt, has_ref, u_step, n_fixed)
        return st, outcome, int(k), bool(on_grid), handed_back

    def _state(self, t, tau, u, v, a, f_int, kc_u, cv, ag, energy, prev):
        """The :class:`~.stage.StepState` the last step taken ended in."""
        free = self.eq.free
        new = StepState(float(t), float(tau), u, v, a, f_int, None, ag)
        new.keep_free_values(free, v[free], a[free])
        new.cv = cv
        new.Kc_u = kc_u
        new.energy = {key: float(x) for key, x in zip(ENERGY_KEYS, energy)}
        joints, start = [], 0
        for end in self.ends:
            joints.append(tuple(x[start:end].copy() for x in prev))
            start = end
        new.joints = joints
        return new
