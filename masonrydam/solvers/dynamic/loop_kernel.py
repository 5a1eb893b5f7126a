"""Many implicit steps in one compiled call: :func:`implicit_steps`, the kernel of :mod:`.compiled_loop`.

The steps of the common path - linear blocks, nonlinear joints of one fused law, a Newmark-family scheme at a fixed
dt or with the error control of dt = "auto", a step that the joint-space iteration solves and that then passes the
full residual test, the energy-growth test and the local error test - done as :class:`~.implicit.ImplicitStep` and
the step controls (:mod:`.step_control`) do them, operation for operation: the
ground acceleration (``np.interp`` of the record), the ground loads (``-(a_g . M iota)``), :func:`~.kernels.step_loads`
and :func:`~.kernels.step_constant`, the residual at the start (:func:`~.kernels.newmark_kinematics`,
:func:`~.kernels.newmark_residual`, the sparse products in scipy's order), the joint-space step
(:func:`masonrydam.solvers.joint_space.step_kernel.joint_space_step`), the joints' forces at its solution
(:func:`masonrydam.elements.interface.interface_forces` and the assembly of
:func:`~masonrydam.assembly.sparsity.scatter_vector`),
the residual there, the energy balance of :meth:`~.energy.EnergyBalance.record` and
:meth:`~.energy.EnergyBalance.accept` with the same kernels and the same order of sums, the local error of
:meth:`~.step_control.AdaptiveStepping.step_error` (with the compiled :func:`~.ground_motion.chord_error`), the commit
and the choice of the next step size. The steps it
takes are equal bit for bit to those of the Python loop (``tests/solvers/test_compiled_loop.py``).

Where a step leaves the common path (the joint-space iteration does not converge or fails, the full residual is
above the tolerance, the step gains energy or its local error is above the tolerance, NaN), the kernel stops *after*
that step's joint-space call and hands the step back (:data:`HANDED_BACK`): the joint space's own state (its last
force change, its capacitance LU) is then exactly what the Python loop would have left, and
:class:`~.compiled_loop.CompiledLoop` finishes the step in Python from the joint-space result. What the kernel
changed for the step handed back (the joints' trial state and fields) is what the Python step evaluates again from
the committed state. With dt = "auto" the kernel also returns where a step it accepted chose another step size
(:data:`LEVEL_CHANGED`): that size's joint space is another one.

Why it is written out: the Python around one joint-space call took about 200 us a step on the coarse Koyna section
(the step's set-up, two residuals, the model's forces, the energy balance; docs/performance.md), against 68 us for
the joint-space call and 10 us for its floor (one substitution and one joint-law pass over the points;
benchmarks/bench_step_kernel.py).
"""
from __future__ import annotations

import numba
import numpy as np

from ...elements.interface import interface_forces
from ...errors import STATUS_OK
from ..joint_space.step_kernel import STEP_CONVERGED, csr_product, joint_space_step
from .ground_motion import chord_error, record_at
from .kernels import (difference_norm, dot_product, euclidean_norm, free_norm, ground_load, joint_step_energy,
                      joint_stored_energy_range, newmark_kinematics, newmark_residual, step_constant, step_loads,
                      step_works)

#: every step asked for was taken
ALL_TAKEN = 0
#: the step after the last one taken is handed back (its joint-space call made; see the module's docstring)
HANDED_BACK = 1

#: dt = "auto": the step accepted last took another step size (the state is before grid point ``k``)
LEVEL_CHANGED = 2

#: entries of ``adapt`` (dt = "auto"): the peaks of the error measures, the last error, the smallest and largest steps
#: taken, and the constants of :class:`~.step_control.AdaptiveStepping`
ADAPT_U_PEAK, ADAPT_V_PEAK, ADAPT_LAST_ERROR, ADAPT_SMALLEST, ADAPT_LARGEST, ADAPT_TOLERANCE, ADAPT_ERROR_CONSTANT, \
    ADAPT_DISPLACEMENT_FLOOR, ADAPT_GROW_FRACTION, ADAPT_PEAK_GROUND_VELOCITY = range(10)
N_ADAPT = 10

#: entries of ``totals``: steps taken, joint-space iterations, capacitance LU factorizations, their low-rank
#: updates, points held, recoveries from the stored columns
N_TOTALS = 6

#: indices of the energy terms in ``energy`` (the order of :data:`~.energy.ENERGY_KEYS`)
E_INPUT, E_EXTERNAL, E_HYDRO, E_KINETIC, E_STRAIN, E_DAMPING, E_JOINT, E_STORED, E_DISSIPATED, E_FRICTION, \
    E_BOND, E_CONTACT, E_NUMERICAL, E_ERROR = range(14)


@numba.njit(cache=True)
def _ground_at(t, times, values):
    """:meth:`~.ground_motion.GroundMotion.at`; a component without a record (no samples) is zero."""
    if times.shape[0] == 0:
        return 0.0
    return record_at(t, times, values)


@numba.njit(cache=True)
def _ground_load(ag, influence, support_excitation, out):
    """:meth:`~.equations.StageEquations.ground_load` without loads given in time: ``-(a_g . M iota)``."""
    if support_excitation:
        ground_load(ag, influence, out)
    else:
        for i in range(out.shape[0]):
            out[i] = 0.0


@numba.njit(cache=True)
def _residual(u, f_int, free, un, vn, an, h, beta, gamma, mass_diag, Mp, Mi, Mx, damped, Cp, Ci, Cx, w_m, const,
              p1_norm, a1, v1, ma, ma_unscaled, cv1, R):
    """:meth:`~.implicit.ImplicitStep.residual` at ``u`` with internal forces ``f_int`` (n_dof,) into ``a1``, ``v1``,
    ``ma`` (``M a1``, scaled), ``cv1`` (``C v1``) and ``R`` (n,), and the force scale of its convergence test
    (:meth:`~.implicit.ImplicitStep.force_scale` at the first iteration); returns ``(status, scale)``. A consistent
    mass's product ``M a1`` is also kept unscaled in ``ma_unscaled`` where that has n entries (the residual at the
    step's solution: the energy balance's, not computed again; (0,) at its start, where it is not needed)."""
    newmark_kinematics(u, free, un, vn, an, h, beta, gamma, mass_diag, a1, v1, ma)
    if mass_diag.shape[0] != free.shape[0]:
        csr_product(Mp, Mi, Mx, a1, ma)
        for i in range(ma_unscaled.shape[0]):
            ma_unscaled[i] = ma[i]
    if damped:
        csr_product(Cp, Ci, Cx, v1, cv1)
    status = newmark_residual(ma, w_m, cv1, f_int, free, const, R)
    return status, max(euclidean_norm(ma), free_norm(f_int, free), p1_norm, 0.0, 1e-30)


@numba.njit(cache=True)
def _growth(e):
    """:func:`~.energy.energy_growth`, in its order of operations."""
    return (e[E_KINETIC] + e[E_STRAIN] + e[E_STORED] + e[E_DAMPING] - e[E_EXTERNAL] - e[E_INPUT]
            - e[E_HYDRO])


@numba.njit(cache=True)
def implicit_steps(k_first, k_last, dt, duration, t, tau, beta, gamma, am, af, w_m, weight_m, weight_f,
                   free, mass_diag, Mp, Mi, Mx, damped, Cp, Ci, Cx, Kp, Ki, Kx, static_load,
                   ground_times, ground_values, ground_dt, influence, support_excitation,
                   conn, N, frame, jw, thickness, jparams, jparam_index, law_id, jdofs, group_ends, compliance_n,
                   compliance_s, jweight, committed, base, trial, delta, traction, fe, jinfo, base2,
                   prev_delta, prev_traction, prev_state,
                   js_fixed, js_params, js_param_index, js_weight, js_base, js_trial, js_traction, js_q, js_qt,
                   js_codes, js_info, js_held, ST, slot, wk, dq_last, has_dq, JT, piv, ref_rows, ref_qt, has_ref, max_newton,
                   n_fixed, flips_before_hold, update_min_changes, update_change_fraction, singular_pivot,
                   latch_column, open_code, js_work, u_js, dq_out, counts, err_out,
                   force_tolerance, joint_space_fraction, growth_check, growth_tolerance,
                   energy, kinetic0, strain0, stored0, energy_stats,
                   adaptive, control, adapt, u_stage_start,
                   u, v, a, f_int, kc_u, cv, ag, totals):
    """The steps of an implicit stage toward grid points ``k_first`` .. ``k_last`` (1-based, grid point ``k`` at
    ``min(k dt, duration)``) from the committed state, in place: one step a grid point at a fixed dt (``adaptive``
    False), steps of ``dt / 2^level`` with the error control of :class:`~.step_control.AdaptiveStepping` for dt =
    "auto" (``adaptive``; ``control`` = [level, hold count, top level], ``adapt`` (:data:`N_ADAPT`,) its peaks,
    last error, smallest and largest steps and constants, ``u_stage_start`` (n,) m the displacements the stage
    started from). The state starts before grid point ``k_first``; the joint space given is the one of the
    starting level's step size.

    Scheme: ``dt`` s, Newmark's ``beta``, ``gamma``, the alpha weights ``am``, ``af`` and ``w_m = (1 - am)/(1 - af)``,
    ``weight_m = am/(1 - af)``, ``weight_f = af/(1 - af)``. Stage terms on the ``free`` (n,) DOFs: the lumped
    mass ``mass_diag`` (n,) or (0,) and the consistent one as CSR (``Mp, Mi, Mx``), the damping ``C`` (CSR; ``damped``),
    the blocks' full-DOF stiffness ``K`` (CSR, n_dof rows), the static load (n,) N, the ground records (three tuples
    of sample times and values, empty for a direction without one, and their sample intervals ``ground_dt`` (3,)
    s), ``influence`` (dim, n) kg (``M iota``). The
    joints as one set (the model's sets one after the other; ``group_ends`` the element index where each ends): the
    arguments of :func:`~masonrydam.elements.interface.interface_forces` with the law's states ``committed``,
    ``base``, ``trial`` (ne, nip, ns) (``base2`` a (P, ns) view of ``base``), the element DOFs ``jdofs``, the
    compliances and areas of the energy balance, and the snapshot of the last step's fields ``prev_*``. The joint
    space: the arguments of :func:`~masonrydam.solvers.joint_space.step_kernel.joint_space_step` (``js_fixed`` those
    that never change, ``js_work`` its six work arrays). Tolerances: ``force_tolerance`` (relative),
    ``joint_space_fraction`` of it for the joint-space iteration, the energy-growth test where ``growth_check`` (and,
    with dt = "auto", below the top level). Energies: ``energy`` (14,) J in the order of
    :data:`~.energy.ENERGY_KEYS`, the references ``kinetic0``,
    ``strain0``, ``stored0``, and ``energy_stats`` = [largest term, largest growth, largest error]. The state: ``t``,
    ``tau`` (s), ``u, v, a, f_int, kc_u`` (n_dof,), ``cv`` (n,) the damping force of its velocity, ``ag`` (dim,).
    ``totals`` (:data:`N_TOTALS`,) are added to.

    Returns ``(outcome, k, on_grid, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status)``: :data:`ALL_TAKEN`
    (the state is on grid point ``k = k_last``, ``on_grid``), :data:`LEVEL_CHANGED` (dt = "auto": the last step
    accepted changed the level; the state is before grid point ``k``) or :data:`HANDED_BACK` (the next step, toward
    grid point ``k``, is the Python step's: from its joint-space result where ``status`` >= 0, the iterate in
    ``u_js`` and the counts of :data:`~masonrydam.solvers.joint_space.step_kernel.N_COUNTS` in ``counts``; from its
    start where ``status`` is -1, a shorter last step of the stage); the state's times, the joint space's reference
    LU and whether it keeps a last force change."""
    n = free.shape[0]
    n_dof = u.shape[0]
    dim = ag.shape[0]
    lumped = mass_diag.shape[0] == n
    zeros = np.zeros(n)
    state_force = np.zeros(n)
    ag1 = np.zeros(dim)
    g1 = np.empty(n)
    g0 = np.empty(n)
    p1 = np.empty(n)
    pn = np.empty(n)
    pg1 = np.empty(n)
    pg0 = np.empty(n)
    const = np.empty(n)
    un = np.empty(n)
    vn = np.empty(n)
    an = np.empty(n)
    ma_n = np.zeros(n)  # stays zero with a lumped mass (step_constant takes mass_diag a_n there)
    a1 = np.empty(n)
    v1 = np.empty(n)
    ma = np.empty(n)
    cv1 = np.zeros(n)
    R = np.empty(n)
    fc = np.empty(n_dof)
    f = np.empty(n_dof)
    mv1 = np.zeros(n)
    # a consistent mass's products with the step's start and end accelerations: ``M a_n`` (``ma0``) is the last
    # accepted step's ``M a1`` (``a_n`` is its ``a1``, bit for bit), carried over instead of computed again (the
    # first step of a call computes it); ``M a1`` (``ma1``) is the residual's before its alpha weight. Each saves a
    # sparse product a step, the same bits
    ma0 = np.zeros(n)
    ma0_ready = False
    ma1 = np.zeros(n)
    no_copy = np.zeros(0)  # the residual at a step's start keeps no unscaled M a1
    w = np.empty(10)
    split = np.zeros(5)
    e = np.empty(14)
    a_new = np.empty(n_dof)
    n_groups = group_ends.shape[0]
    P = js_q.shape[0]
    ns = base2.shape[1]
    delta_n, delta_n2, delta_i, delta_i2, guess, guess2 = js_work
    u1 = np.empty(n)
    status = STEP_CONVERGED
    k = k_first
    level = control[0]
    hold = control[1]
    top = control[2]
    level_start = level
    h = dt / 2.0 ** level
    t_grid = min(k * dt, duration)
    while True:
        # -- the step toward grid point k (AdaptiveStepping.run; FixedSteps: level 0, one step a grid point)
        t_end = tau + h
        if t_end > t_grid - 1e-9 * dt:
            if abs(t_grid - t_end) > 1e-9 * dt:  # a shorter last step of the stage: the Python step's
                return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, -1
            t_end = t_grid
        # -- the step's loads and constant part (ImplicitStep.__init__)
        for c in range(dim):
            ag1[c] = _ground_at(t_end, ground_times[c], ground_values[c])
        _ground_load(ag1, influence, support_excitation, g1)
        _ground_load(ag, influence, support_excitation, g0)
        step_loads(static_load, g1, g0, state_force, p1, pn, pg1, pg0)
        for i in range(n):
            un[i] = u[free[i]]
            vn[i] = v[free[i]]
            an[i] = a[free[i]]
        if not lumped and not ma0_ready:
            csr_product(Mp, Mi, Mx, an, ma0)
            ma0_ready = True
        cv_n = cv if af != 0.0 else zeros
        step_constant(p1, pn, mass_diag, ma0 if am != 0.0 and not lumped else ma_n, an, weight_m, cv_n, f_int, free,
                      weight_f, const)
        p1_norm = euclidean_norm(p1)
        # -- the residual at the start and the joint-space step (ImplicitStep.solve, _joint_space_start)
        residual_status, ref = _residual(u, f_int, free, un, vn, an, h, beta, gamma, mass_diag, Mp, Mi, Mx, damped,
                                         Cp, Ci, Cx, w_m, const, p1_norm, a1, v1, ma, no_copy, cv1, R)
        if residual_status != STATUS_OK:
            return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, -1
        for p in range(P):
            js_held[p] = 0
            for s in range(ns):
                js_base[p, s] = base2[p, s]
        tolerance = joint_space_fraction * force_tolerance * ref
        dq_start = dq_last if has_dq else dq_out
        Lp, Li, Lx, dd, perm, Bp, Bi, Bx, BTp, BTi, BTx, js_free, XT, recovery_columns_max = js_fixed
        status, JT, piv, ref_rows, ref_qt, has_ref = joint_space_step(
            Lp, Li, Lx, dd, perm, Bp, Bi, Bx, BTp, BTi, BTx, js_free, XT, recovery_columns_max,
            js_params, js_param_index, js_weight, js_base, js_trial, js_traction, js_q, js_qt, js_codes,
            js_info, js_held, ST, slot, wk, u, R, tolerance, dq_start, has_dq, JT, piv, ref_rows, ref_qt, has_ref,
            max_newton, n_fixed, flips_before_hold, update_min_changes, update_change_fraction, singular_pivot,
            latch_column, open_code,
            False, 0, 0, delta_n, delta_n2, delta_i, delta_i2, guess, guess2, u_js, dq_out, counts, err_out)
        for p in range(P):
            js_held[p] = 0
        if status != STEP_CONVERGED:
            return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
        predictor = counts[5] != 0
        its = 0 if predictor else counts[0]
        if predictor:
            has_dq = False
        else:
            has_dq = True
            for i in range(dq_out.shape[0]):
                dq_last[i] = dq_out[i]
            if latch_column >= 0:  # JointSpace._store_latched_bonds
                for p in range(P):
                    if js_base[p, latch_column] > base2[p, latch_column]:
                        base2[p, latch_column] = js_base[p, latch_column]
        # -- the forces at the joint-space solution and the residual there (Model.evaluate, forces only)
        csr_product(Kp, Ki, Kx, u_js, fc)
        for i in range(n_dof):
            f[i] = fc[i]
        if interface_forces(conn, u_js, N, frame, jw, thickness, jparams, jparam_index, base, trial, delta,
                            traction, fe, jinfo, law_id) != STATUS_OK:
            return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
        for el in range(fe.shape[0]):
            for r in range(fe.shape[1]):
                f[jdofs[el, r]] += fe[el, r]
        residual_status, scale = _residual(u_js, f, free, un, vn, an, h, beta, gamma, mass_diag, Mp, Mi, Mx, damped,
                                           Cp, Ci, Cx, w_m, const, p1_norm, a1, v1, ma, ma1, cv1, R)
        if residual_status != STATUS_OK:
            return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
        if not euclidean_norm(R) <= force_tolerance * scale:
            return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
        # -- the energy balance of the step (EnergyBalance.record, record_works)
        if not lumped:
            csr_product(Mp, Mi, Mx, v1, mv1)
        # the end state's a over all DOFs (zero where constrained), for step_works
        for i in range(n_dof):
            a_new[i] = 0.0
        for i in range(n):
            a_new[free[i]] = a1[i]
        step_works(free, u, u_js, pg0, pg1, static_load, cv, cv1, f_int, f, kc_u, fc, v1, mass_diag, mv1, a, a_new,
                   ma0, ma1, w)
        for i in range(14):
            e[i] = energy[i]
        e[E_INPUT] += w[0] - 0.0
        e[E_HYDRO] = e[E_HYDRO] + 0.0
        e[E_EXTERNAL] += w[1]
        e[E_DAMPING] += w[2]
        e[E_JOINT] += w[3]
        kinetic_before = e[E_KINETIC]
        e[E_KINETIC] = w[4] - kinetic0
        e[E_STRAIN] = 0.5 * dot_product(u_js, fc) - strain0
        numerical = w[5] - (e[E_KINETIC] - kinetic_before)
        numerical -= (am - 0.5) * w[6] + (af - 0.5) * (w[8] + w[7] - w[9])
        e[E_NUMERICAL] = e[E_NUMERICAL] + numerical
        stored = 0.0
        start = 0
        for gi in range(n_groups):
            stored = stored + joint_stored_energy_range(traction, compliance_n, compliance_s, start, group_ends[gi])
            start = group_ends[gi]
        e[E_STORED] = stored - stored0
        for i in range(5):
            split[i] = 0.0
        joint_step_energy(prev_delta, prev_traction, prev_state, delta, traction, trial, jweight, split)
        e[E_FRICTION] = e[E_FRICTION] + split[0]
        e[E_BOND] = e[E_BOND] + split[1]
        e[E_CONTACT] = e[E_CONTACT] + split[2]
        e[E_DISSIPATED] = e[E_JOINT] - e[E_STORED]
        e[E_ERROR] = e[E_INPUT] + e[E_EXTERNAL] + e[E_HYDRO] - (e[E_KINETIC] + e[E_STRAIN] + e[E_DAMPING]
                                                                 + e[E_STORED] + e[E_FRICTION] + e[E_BOND]
                                                                 + e[E_CONTACT] + e[E_NUMERICAL])
        if growth_check and (not adaptive or level < top):  # ImplicitStep._finish: a step that gains energy
            g = _growth(e)                                       # is refused (handed back)
            cap = growth_tolerance * energy_stats[0]
            allowed = max(cap, _growth(energy) + 0.01 * cap)
            if g > allowed and energy_stats[0] > 0:
                return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
        if adaptive:  # AdaptiveStepping.step_error
            for i in range(n):
                u1[i] = u_js[free[i]]
            e_zx = h * h * adapt[ADAPT_ERROR_CONSTANT] * difference_norm(a1, an)
            u_peak = max(adapt[ADAPT_U_PEAK], difference_norm(u1, u_stage_start))
            eta_zx = e_zx / max(u_peak, adapt[ADAPT_DISPLACEMENT_FLOOR] * np.sqrt(n))
            v_max = 0.0
            for i in range(n):
                v_max = max(v_max, abs(v1[i]))
            v_peak = max(adapt[ADAPT_V_PEAK], v_max)
            miss = 0.0
            for c in range(3):
                if ground_times[c].shape[0]:
                    miss = max(miss, chord_error(tau, t_end, ground_times[c], ground_values[c], ground_dt[c]))
            eta_input = miss / max(v_peak, adapt[ADAPT_PEAK_GROUND_VELOCITY], 1e-300) if miss > 0 else 0.0
            scale_e = max(energy_stats[0], abs(e[E_INPUT]), abs(e[E_EXTERNAL]), 1e-300)
            eta_event = abs(e[E_CONTACT] - energy[E_CONTACT]) / scale_e
            if energy_stats[0] <= 0:
                eta_event = 0.0
            eta = max(eta_zx, eta_input, eta_event)
            if not (eta <= adapt[ADAPT_TOLERANCE] or not level < top):
                return HANDED_BACK, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
            adapt[ADAPT_LAST_ERROR] = eta
            adapt[ADAPT_U_PEAK] = u_peak
            adapt[ADAPT_V_PEAK] = v_peak
        # -- the commit (Model.commit) and the accepted step (EnergyBalance.accept)
        for el in range(trial.shape[0]):
            for gp in range(trial.shape[1]):
                for s in range(ns):
                    committed[el, gp, s] = trial[el, gp, s]
                    base[el, gp, s] = trial[el, gp, s]
                    prev_state[el, gp, s] = trial[el, gp, s]
                for c in range(dim):
                    prev_delta[el, gp, c] = delta[el, gp, c]
                    prev_traction[el, gp, c] = traction[el, gp, c]
        for i in range(14):
            energy[i] = e[i]
        energy_stats[0] = max(energy_stats[0], abs(e[E_INPUT]), abs(e[E_EXTERNAL]), abs(e[E_KINETIC]),
                              abs(e[E_STRAIN]), abs(e[E_JOINT]), abs(e[E_DAMPING]))
        g = _growth(e)
        if g > energy_stats[1]:
            energy_stats[1] = g
        energy_stats[2] = max(energy_stats[2], abs(e[E_ERROR]))
        # the new state
        t = t - tau + t_end
        tau = t_end
        for i in range(n_dof):
            u[i] = u_js[i]
            v[i] = 0.0
            a[i] = a_new[i]
            f_int[i] = f[i]
            kc_u[i] = fc[i]
        for i in range(n):
            v[free[i]] = v1[i]
            cv[i] = cv1[i]
        for c in range(dim):
            ag[c] = ag1[c]
        if not lumped:  # the next step's M a_n
            for i in range(n):
                ma0[i] = ma1[i]
        totals[0] += 1
        totals[1] += its
        totals[2] += counts[1]
        totals[3] += counts[2]
        totals[4] += counts[3]
        totals[5] += counts[4]
        if adaptive:  # AdaptiveStepping.run after an accepted step
            adapt[ADAPT_SMALLEST] = min(adapt[ADAPT_SMALLEST], h)
            adapt[ADAPT_LARGEST] = max(adapt[ADAPT_LARGEST], h)
            hold -= 1
            grow_below = adapt[ADAPT_GROW_FRACTION] * adapt[ADAPT_TOLERANCE]
            if level > 0 and hold <= 0 and adapt[ADAPT_LAST_ERROR] < grow_below:
                h_up = dt / 2.0 ** (level - 1)
                x = tau / h_up
                if abs(x - round(x)) < 1e-6:
                    level -= 1
            elif level > top:
                level = top
            control[0] = level
            control[1] = hold
        if not t_grid - tau > 1e-9 * dt:  # grid point k reached
            if k == k_last:
                return ALL_TAKEN, k, True, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
            k += 1
            t_grid = min(k * dt, duration)
        if level != level_start:  # another step size: its joint space is the caller's to give
            return LEVEL_CHANGED, k, False, t, tau, JT, piv, ref_rows, ref_qt, has_ref, has_dq, status
