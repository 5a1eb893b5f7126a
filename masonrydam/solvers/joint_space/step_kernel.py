"""One dynamic joint-space step in a single compiled call: :func:`joint_space_step`.

The same algorithm as :meth:`masonrydam.solvers.joint_space.condensation.JointSpace._solve_step` for a dynamic
step (no bond latching per point, no fresh Newton budget after a release) with every column of the flexibility
stored and the all-stick factorization an ``L D L^T`` (:class:`~masonrydam.solvers.linear.direct.SymmetricFactorization`):
the elastic predictor (one substitution), the joint law at the points, the start guess from the last step's
force change, Newton with the capacitance matrix (its LU kept across steps and updated by Sherman-Morrison-Woodbury
where few rows changed), the backtracking line search, points held sticking after
:data:`~.condensation.FLIPS_BEFORE_HOLD` state changes and let go when the held problem converges, the
initial-stiffness phase, the latch of a state pattern that comes back, and the recovery of the displacements from
the stored columns of ``K_ref^-1 B^T``. Every floating-point operation is the one the Python loop performs, in the
same order, with the same kernels (:mod:`.kernels`) and the same LAPACK ``getrf``: the two give the same step bit
for bit (``tests/solvers/test_compiled_joint_space.py``).

Why it is written out: the Python loop drives some hundred calls of a few microseconds each per step. On the coarse
Koyna section (benchmarks/bench_step_kernel.py, about two iterations a step) it took 0.36-0.41 ms a step against
0.15 ms for this one call, which is then mostly the capacitance LU and its updates. The theory and its references
are in :mod:`.condensation` and docs/dynamics.md ("The joint-space step in equations").

Statuses (:data:`STEP_CONVERGED` ...): the kernel does not raise; :meth:`~.condensation.JointSpace.solve_step`
turns a status into the result or the exception the Python loop gives.
"""
from __future__ import annotations

import math

import numba
import numpy as np
from numba import types

from ...errors import STATUS_NAN, STATUS_OK
from ..linear.dense_lu import STATUS_SINGULAR
from ..linear.ldlt_kernels import UNSIGNED, ldlt_solve_vector
from .kernels import (add_flexibility_product, add_point_force_changes, apply_correction, capacitance_assemble,
                      capacitance_update_solve, condensed_residual, joint_law_at_points, joint_space_correction,
                      state_key, subtract_columns_product)

try:
    # LAPACK's dgetrf through numba's own binding, the one np.linalg.inv uses inside numba: it calls the
    # scipy.linalg.cython_lapack routine that scipy.linalg.lapack.dgetrf calls (the same factors bit for bit),
    # and a kernel that uses it can be cached (a ctypes function pointer cannot). It is numba's internal API:
    # where a numba release moves it, AVAILABLE is False and the joint space keeps its Python loop
    from numba.np.linalg import _LAPACK, ensure_lapack

    ensure_lapack()
    _dgetrf = _LAPACK().numba_xxgetrf(types.float64)
    #: the compiled step can run (numba's LAPACK binding found)
    AVAILABLE = True
except (ImportError, AttributeError, TypeError):  # pragma: no cover - depends on the numba release
    _dgetrf = None
    AVAILABLE = False

#: the step converged (``u`` written)
STEP_CONVERGED = 0
#: the iteration limits were reached: ``u`` holds the last iterate (the caller goes on from it)
STEP_NOT_CONVERGED = 1
#: the predictor's substitution gave NaN or infinity (a singular effective matrix)
STEP_FACTOR_NAN = 2
#: the joint law or the condensed residual gave NaN (the point in ``info[0]``, -1 for the residual)
STEP_LAW_NAN = 3
#: a singular capacitance matrix (``counts[0]`` iterations; its size in ``counts[6]``)
STEP_SINGULAR = 4
#: NaN in a Newton correction
STEP_CORRECTION_NAN = 5
#: NaN in the displacements recovered from the stored columns
STEP_RECOVERY_NAN = 6

#: entries of ``counts``: iterations, capacitance LU factorizations, low-rank updates, points held, recoveries
#: from the stored columns, the step ended with every point in its predictor state (0/1), the active components
#: of a singular matrix, bonds latched broken at flipping points and fresh Newton budgets after releases (a static
#: step)
N_COUNTS = 9


@numba.njit(cache=True)
def capacitance_getrf(ST, slot, rows, qt, singular_pivot):
    """``(status, J, piv)``: what :func:`~.condensation.capacitance_lu` returns (the same assembly, LAPACK's
    ``dgetrf``, 0-based row swaps ``piv`` (na,) int64 and the same singularity test), compiled."""
    na = rows.shape[0]
    J = np.empty((na, na)).T  # Fortran order
    scale = np.zeros(1)
    piv = np.zeros(na, dtype=np.int64)
    st = capacitance_assemble(ST, slot, rows, qt, J, scale)
    if st != STATUS_OK:
        return st, J, piv
    ipiv = np.empty(na, dtype=np.int32)
    info = 0
    if na > 0:
        info = _dgetrf(ord("d"), na, na, J.ctypes, na, ipiv.ctypes)
    for i in range(na):
        piv[i] = ipiv[i] - 1
    smallest = np.inf
    for i in range(na):
        a = abs(J[i, i])
        if not (a < np.inf):
            return STATUS_NAN, J, piv
        if a < smallest:
            smallest = a
    if info > 0 or not (smallest > singular_pivot * scale[0]):
        return STATUS_SINGULAR, J, piv
    return STATUS_OK, J, piv


@numba.njit(cache=True)
def _copy(dst, src):
    """``dst[:] = src`` (1D) as a loop: numba's slice assignment compiles its shape-error messages (seconds)."""
    for i in range(dst.shape[0]):
        dst[i] = src[i]


@numba.njit(cache=True)
def _copy2(dst, src):
    """``dst[...] = src`` (2D), as :func:`_copy`."""
    for i in range(dst.shape[0]):
        for j in range(dst.shape[1]):
            dst[i, j] = src[i, j]


@numba.njit(cache=True)
def _fill_int8(dst, value):
    for i in range(dst.shape[0]):
        dst[i] = value


@numba.njit(cache=True)
def csr_product(indptr, indices, data, x, out):
    """``out = A x`` for a CSR matrix, each row summed in the order of its entries (as scipy's csr_matvec: the
    same bits). Subscripts are unsigned (:data:`~masonrydam.solvers.linear.ldlt_kernels.UNSIGNED`): with the
    signed ones numba tests each for wrap-around, and the product of the Koyna example's stiffness (7 666 rows,
    126 012 entries) took 140 us against scipy's 63 (AMD EPYC); unsigned it is no slower than scipy's."""
    start = UNSIGNED(indptr[0])
    for i in range(out.shape[0]):
        acc = 0.0
        end = UNSIGNED(indptr[i + 1])
        k = start
        while k < end:
            acc += data[k] * x[UNSIGNED(indices[k])]
            k += UNSIGNED(1)
        out[i] = acc
        start = end


@numba.njit(cache=True)
def _evaluate(delta, delta2, delta_y, q_n, params_table, param_index, weight, base, trial, traction, q, qt, codes,
              info, held, ST, slot, wk, F, err):
    """The law at ``delta`` (flat (m,), and ``delta2`` (P, dim) the same memory) and the condensed residual there
    (JointSpace._evaluate): a status, the error in err[0]."""
    st = joint_law_at_points(np.zeros(0, dtype=np.int64), q.shape[0], params_table, param_index, weight,
                             delta2, base, trial, traction, q, qt, codes, info, held)
    if st != STATUS_OK:
        return st
    return condensed_residual(delta, delta_y, q, q_n, ST, slot, wk, F, err, info)


@numba.njit(cache=True)
def _reevaluate(points, params_table, param_index, weight, delta2, base, trial, traction, q, qt, codes, info, held, ST,
                slot, wk, F, err):
    """The law again at ``points`` only and the residual updated by their force change
    (:func:`~.kernels.joint_space_reevaluate_points`, compiled)."""
    dim = q.shape[1]
    q_old = np.empty((points.shape[0], dim))
    for k in range(points.shape[0]):
        for c in range(dim):
            q_old[k, c] = q[points[k], c]
    st = joint_law_at_points(points, points.shape[0], params_table, param_index, weight, delta2,
                             base, trial, traction, q, qt, codes, info, held)
    if st != STATUS_OK:
        return st
    return add_point_force_changes(points, q, q_old, ST, slot, wk, F, err, info)


@numba.njit(cache=True)
def _flagged(flags):
    """The indices (int64) of the nonzero entries of ``flags``."""
    n = 0
    for i in range(flags.shape[0]):
        if flags[i]:
            n += 1
    out = np.empty(n, dtype=np.int64)
    n = 0
    for i in range(flags.shape[0]):
        if flags[i]:
            out[n] = i
            n += 1
    return out


@numba.njit(cache=True)
def _active(qt):
    """``(rows, qt_rows)`` of :func:`~.kernels.active_components`."""
    dim = qt.shape[1]
    P = qt.shape[0]
    n = 0
    for p in range(P):
        for c in range(dim):
            for d in range(dim):
                if qt[p, c, d] != 0.0:
                    n += 1
                    break
    rows = np.empty(n, dtype=np.int64)
    qt_rows = np.empty((n, dim))
    n = 0
    for p in range(P):
        for c in range(dim):
            nz = False
            for d in range(dim):
                if qt[p, c, d] != 0.0:
                    nz = True
                    break
            if nz:
                rows[n] = p * dim + c
                for d in range(dim):
                    qt_rows[n, d] = qt[p, c, d]
                n += 1
    return rows, qt_rows


@numba.njit(cache=True)
def _same_bits(a, b):
    """Whether two finite (n, k) float arrays hold the same bytes (the Python loop compares keys as bytes: a
    zero of the other sign differs)."""
    if a.shape[0] != b.shape[0]:
        return False
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            x, y = a[i, j], b[i, j]
            if x != y or math.copysign(1.0, x) != math.copysign(1.0, y):
                return False
    return True


@numba.njit(cache=True)
def joint_space_step(Lp, Li, Lx, d, perm, Bp, Bi, Bx, BTp, BTi, BTx, free, XT, recovery_columns_max,
                     params_table, param_index, weight, base, trial, traction, q, qt, codes, info, held, ST, slot, wk,
                     u_n, R_n, force_tolerance, dq_last, has_dq_last, JT, piv, ref_rows, ref_qt, has_ref,
                     max_newton, max_fixed, flips_before_hold, update_min_changes, update_change_fraction,
                     singular_pivot, latch_column, open_code, latch_flipping_bonds, flips_before_latch,
                     fresh_budget_releases, delta_n, delta_n2, delta, delta2, guess, guess2, u_out, dq_out, counts,
                     err_out):
    """One step condensed on the joints (see the module's docstring and ``JointSpace._solve_step``).

    Factor ``Lp, Li, Lx, d, perm`` (:class:`~masonrydam.solvers.linear.direct.SymmetricFactorization`); ``B``
    (m, n_dof) and ``B_f^T`` (n_eq, m) as CSR arrays; ``free`` (n_eq,) int64; ``XT`` (m or 0, n_eq) the stored
    columns of ``X = K_ref^-1 B_f^T`` and ``recovery_columns_max`` (0: none); the law's parameters and point
    arrays as in :func:`~.kernels.joint_points_evaluate` (``base`` (P, ns) loaded from the groups, and changed
    only where a pattern that comes back latches its broken bonds); ``ST``, ``slot``, ``wk`` as in
    :func:`~.kernels.condensed_residual`; ``u_n`` (n_dof,) m, ``R_n`` (n_eq,) N; ``force_tolerance`` N;
    ``dq_last`` (m,) N the last step's force change where ``has_dq_last``; the reference capacitance LU ``J``
    (given as its transpose ``JT``, C order), ``piv`` and its rows ``ref_rows``, ``ref_qt`` where ``has_ref``; the iteration limits and
    constants of :mod:`.condensation`; ``latch_column`` the law's bond column where it latches broken bonds
    (-1: it does not); ``open_code`` (codes,) bool: the codes whose result state is open; what a static step does
    besides (``JointSpace._solve_step``): ``latch_flipping_bonds`` latches the bond of a point that has flipped
    ``flips_before_latch`` times and whose bond broke in an iterate of the step (``JointSpace._bond_chatter``; needs
    ``latch_column`` >= 0), and ``fresh_budget_releases`` releases of held points start a fresh Newton budget (0 in a
    dynamic step); work arrays for the
    relative displacements at the step's start, the iterate and the start guess, each flat (m,) with a (P, dim)
    view of the same memory (``delta_n2`` ...: numba's reshape would compile its error messages, seconds of the
    first run).

    Writes ``u_out`` (n_dof,) m (the converged or last iterate), ``dq_out`` (m,) N (the step's force change),
    ``counts`` (:data:`N_COUNTS`,) and ``err_out[0]`` (the last force error, N). Returns ``(status, JT, piv,
    ref_rows, ref_qt, has_ref)``: a step status and the reference LU to keep (transposed, as given)."""
    dim = q.shape[1]
    P = q.shape[0]
    m = P * dim
    n_eq = free.shape[0]
    J = JT.T  # (the caller passes the transpose: a 1 x 1 matrix would otherwise type as C order)
    for i in range(counts.shape[0]):
        counts[i] = 0
    err = np.zeros(1)
    # elastic predictor y = u_n - K_ref^-1 R_n
    x = np.empty(n_eq)
    w = np.empty(n_eq)
    if ldlt_solve_vector(Lp, Li, Lx, d, perm, R_n, x, w) != 0:
        return STEP_FACTOR_NAN, J.T, piv, ref_rows, ref_qt, has_ref
    u_y = u_n.copy()
    for i in range(n_eq):
        u_y[free[i]] -= x[i]
    delta_y = np.empty(m)
    csr_product(Bp, Bi, Bx, u_n, delta_n)
    csr_product(Bp, Bi, Bx, u_y, delta_y)
    none_held = np.zeros(P, dtype=np.int8)
    st = joint_law_at_points(np.zeros(0, dtype=np.int64), P, params_table, param_index, weight,
                             delta_n2, base, trial, traction, q, qt, codes, info, none_held)
    if st != STATUS_OK:
        return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
    q_n = q.copy()
    _copy(delta, delta_y)
    F = np.zeros(m)
    if _evaluate(delta, delta2, delta_y, q_n, params_table, param_index, weight, base, trial, traction, q, qt, codes,
                 info, held, ST, slot, wk, F, err) != STATUS_OK:
        return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
    unchanged = True
    for p in range(P):
        for c in range(dim):
            if q[p, c] != q_n[p, c]:
                unchanged = False
    if unchanged:  # every point kept its elastic state: the predictor is the solution
        _copy(u_out, u_y)
        for i in range(m):
            dq_out[i] = 0.0
        counts[5] = 1
        err_out[0] = err[0]
        return STEP_CONVERGED, J.T, piv, ref_rows, ref_qt, has_ref
    e = err[0]
    if has_dq_last:  # start from the joint forces changing as in the last step, if that is closer
        s_dq = np.zeros(m)
        add_flexibility_product(ST, slot, dq_last, s_dq)
        for i in range(m):
            guess[i] = delta[i] - s_dq[i]
        trial_saved, traction_saved, q_saved = trial.copy(), traction.copy(), q.copy()
        qt_saved, codes_saved, F_saved = qt.copy(), codes.copy(), F.copy()
        if _evaluate(guess, guess2, delta_y, q_n, params_table, param_index, weight, base, trial, traction, q, qt, codes,
                     info, held, ST, slot, wk, F, err) != STATUS_OK:
            return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
        if err[0] < e:
            _copy(delta, guess)
            e = err[0]
        else:
            _copy2(trial, trial_saved)
            _copy2(traction, traction_saved)
            _copy2(q, q_saved)
            for p in range(P):
                codes[p] = codes_saved[p]
                for c in range(dim):
                    for dd in range(dim):
                        qt[p, c, dd] = qt_saved[p, c, dd]
            _copy(F, F_saved)
    flips = np.zeros(P, dtype=np.int64)
    released = np.zeros(P, dtype=np.bool_)
    # every pass that adds a key iterates once after it: at most (releases + 1) Newton budgets and the fixed phase
    seen = np.empty(((fresh_budget_releases + 1) * max_newton + max_fixed + 2, P), dtype=np.int8)
    # the bonds broken in any iterate of the step (the bond column, accumulated from base), where the step latches
    # the bonds of flipping points
    latching = latch_flipping_bonds and latch_column >= 0
    broke = np.zeros(P)
    if latching:
        for p in range(P):
            broke[p] = max(0.0, base[p, latch_column])
    newton_start = 0
    restarts = 0
    n_seen = 0
    key = np.empty(P, dtype=np.int8)
    # the last pass's state key: as the Newton iterations see it (forgotten at a release, has_prev) and as the
    # test of a pattern that comes back sees it (kept, has_prev_sig)
    prev_key = np.empty(P, dtype=np.int8)
    prev_sig = np.empty(P, dtype=np.int8)
    has_prev = False
    has_prev_sig = False
    stabilized = False
    same = 0
    it = 0
    converged = True
    step = np.zeros(m)
    z = np.zeros(max(m, 16))
    while True:
        state_key(codes, traction, key)
        if e <= force_tolerance:
            any_held = False
            for p in range(P):
                if held[p] != 0:
                    any_held = True
                    break
            if not any_held:
                break
            was_held = held != 0
            _fill_int8(held, 0)
            pts = _flagged(was_held)
            if _reevaluate(pts, params_table, param_index, weight, delta2, base, trial, traction, q,
                                             qt, codes, info, held, ST, slot, wk, F, err) != STATUS_OK:
                return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
            e = err[0]
            if e <= force_tolerance:
                break
            for p in range(P):
                if was_held[p]:
                    released[p] = True
                    flips[p] = 0
            if restarts < fresh_budget_releases and it - newton_start < max_newton:
                restarts += 1  # the release changed the active set: Newton's iterations count from here
                counts[8] += 1
                newton_start = it
                for p in range(P):
                    flips[p] = 0
            state_key(codes, traction, key)
            has_prev = False
        if it - newton_start >= max_newton + max_fixed:
            any_held = False
            for p in range(P):
                if held[p] != 0:
                    any_held = True
                    break
            if any_held:  # hand back an iterate of the true law, not of the held problem
                _fill_int8(held, 0)
                if _evaluate(delta, delta2, delta_y, q_n, params_table, param_index, weight, base, trial, traction, q, qt,
                             codes, info, held, ST, slot, wk, F, err) != STATUS_OK:
                    return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
                e = err[0]
                if e <= force_tolerance:
                    break
            converged = False
            break
        fixed_point = it - newton_start >= max_newton
        if latching:
            for p in range(P):
                broke[p] = max(broke[p], trial[p, latch_column])
        if has_prev:
            changed = False
            for p in range(P):
                if key[p] != prev_key[p]:
                    changed = True
                    break
            same = 0 if changed else same + 1
            if same >= 2 and stabilized:
                for p in range(P):
                    flips[p] = 0
                stabilized = False
                n_seen = 0
            else:
                n_hold = 0
                n_crack = 0
                hold = np.zeros(P, dtype=np.bool_)
                crack = np.zeros(P, dtype=np.bool_)
                for p in range(P):
                    if key[p] != prev_key[p]:
                        flips[p] += 1
                    if flips[p] >= flips_before_hold and not released[p] and held[p] == 0:
                        hold[p] = True
                        n_hold += 1
                if latching:
                    for p in range(P):
                        # flipping across the cohesion jump: the bond stays broken for the step
                        if flips[p] >= flips_before_latch and broke[p] != 0 and base[p, latch_column] == 0:
                            crack[p] = True
                            n_crack += 1
                            base[p, latch_column] = max(base[p, latch_column], broke[p])
                            flips[p] = 0
                            if hold[p]:
                                hold[p] = False
                                n_hold -= 1
                    counts[7] += n_crack
                if n_hold > 0 or n_crack > 0:
                    for p in range(P):
                        if hold[p]:
                            held[p] = 1
                    counts[3] += n_hold
                    for p in range(P):
                        if crack[p]:
                            hold[p] = True  # (the points evaluated again: the held ones and the latched ones)
                    if _reevaluate(_flagged(hold), params_table, param_index, weight, delta2, base,
                                                     trial, traction, q, qt, codes, info, held, ST, slot, wk, F,
                                                     err) != STATUS_OK:
                        return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
                    e = err[0]
                    if e <= force_tolerance:
                        continue  # the held problem is solved already: let the true law decide
                    state_key(codes, traction, key)
        found = _seen_before(key, seen, n_seen)
        if not stabilized and found and not (has_prev_sig and _same_rows(key, prev_sig)):
            stabilized = True  # a state pattern came back: latch broken bonds, open points get the initial stiffness
            if latch_column >= 0:
                for p in range(P):
                    if trial[p, latch_column] != 0 and base[p, latch_column] == 0:
                        base[p, latch_column] = 1.0
            if _evaluate(delta, delta2, delta_y, q_n, params_table, param_index, weight, base, trial, traction, q, qt,
                         codes, info, held, ST, slot, wk, F, err) != STATUS_OK:
                return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
            e = err[0]
        if not found:
            for p in range(P):
                seen[n_seen, p] = key[p]
            n_seen += 1
        for p in range(P):
            prev_key[p] = key[p]
            prev_sig[p] = key[p]
        has_prev = has_prev_sig = True
        if stabilized:
            for p in range(P):
                if open_code[codes[p]]:
                    for c in range(dim):
                        for dd in range(dim):
                            qt[p, c, dd] = 0.0
        if fixed_point:
            for p in range(P):
                for c in range(dim):
                    for dd in range(dim):
                        qt[p, c, dd] = 0.0
        rows, qt_rows = _active(qt)
        st, J, piv, ref_rows, ref_qt, has_ref = _correction(ST, slot, F, rows, qt_rows, qt, J, piv, ref_rows, ref_qt,
                                                            has_ref, z, step, update_min_changes,
                                                            update_change_fraction, singular_pivot, counts)
        if st == STATUS_SINGULAR:
            counts[0] = it
            counts[6] = rows.shape[0]
            err_out[0] = e
            return STEP_SINGULAR, J.T, piv, ref_rows, ref_qt, has_ref
        it += 1
        if st != STATUS_OK:
            counts[0] = it
            return STEP_CORRECTION_NAN, J.T, piv, ref_rows, ref_qt, has_ref
        st, e = _line_search(delta, delta2, delta_y, q_n, e, step, params_table, param_index, weight, base, trial, traction,
                             q, qt, codes, info, held, ST, slot, wk, F, err)
        if st != STATUS_OK:
            counts[0] = it
            return STEP_LAW_NAN, J.T, piv, ref_rows, ref_qt, has_ref
    counts[0] = it
    err_out[0] = e
    dq = dq_out
    nnz = 0
    for p in range(P):
        for c in range(dim):
            v = q[p, c] - q_n[p, c]
            dq[p * dim + c] = v
            if v != 0.0:
                nnz += 1
    _copy(u_out, u_y)
    if nnz > 0:
        nz = np.empty(nnz, dtype=np.int64)
        k = 0
        for i in range(m):
            if dq[i] != 0.0:
                nz[k] = i
                k += 1
        if nnz <= recovery_columns_max:  # u = y - X dq from the stored columns of X
            uf = np.empty(n_eq)
            for i in range(n_eq):
                uf[i] = u_y[free[i]]
            vals = np.empty(nnz)
            for k in range(nnz):
                vals[k] = dq[nz[k]]
            if subtract_columns_product(XT, nz, vals, uf) != STATUS_OK:
                return STEP_RECOVERY_NAN, J.T, piv, ref_rows, ref_qt, has_ref
            for i in range(n_eq):
                u_out[free[i]] = uf[i]
            counts[4] = 1
        else:
            rhs = np.empty(n_eq)
            csr_product(BTp, BTi, BTx, dq, rhs)
            if ldlt_solve_vector(Lp, Li, Lx, d, perm, rhs, x, w) != 0:
                return STEP_FACTOR_NAN, J.T, piv, ref_rows, ref_qt, has_ref
            for i in range(n_eq):
                u_out[free[i]] -= x[i]
    return (STEP_CONVERGED if converged else STEP_NOT_CONVERGED), J.T, piv, ref_rows, ref_qt, has_ref


def compiled_already() -> bool:
    """Whether :func:`joint_space_step` needs no compiling: compiled or loaded in this process, or in numba's cache on
    disk for the source as it is (its index holds an entry). Asked before a static stage takes the kernel (see
    :data:`~.condensation.STATIC_COMPILED_STEP`). The cache is read through numba's internal ``_cache`` object:
    where a numba release changes it, the answer is False (the Python loop, the same results)."""
    if joint_space_step.signatures:
        return True
    try:
        return bool(joint_space_step._cache._cache_file._load_index())
    except Exception:  # noqa: BLE001 - numba's internals: any failure means "not known to be cached"
        return False



@numba.njit(cache=True)
def _seen_before(key, seen, n_seen):
    for k in range(n_seen):
        if _same_rows(key, seen[k]):
            return True
    return False


@numba.njit(cache=True)
def _line_search(delta, delta2, delta_y, q_n, e0, step, params_table, param_index, weight, base, trial, traction, q, qt, codes,
                 info, held, ST, slot, wk, F, err):
    """``delta += lam step`` (JointSpace._line_search, steps 1, 1/2, 1/4): (status, the error at the new delta)."""
    delta_old = delta.copy()
    best_e = np.inf
    best_lam = 0.0
    have_best = False
    lam = 1.0
    for k in range(3):
        lam = 1.0 if k == 0 else (0.5 if k == 1 else 0.25)
        for i in range(delta.shape[0]):
            delta[i] = delta_old[i] + lam * step[i]
        st = _evaluate(delta, delta2, delta_y, q_n, params_table, param_index, weight, base, trial, traction, q, qt, codes,
                       info, held, ST, slot, wk, F, err)
        if st != STATUS_OK:
            return st, err[0]
        e_try = err[0]
        if not have_best or e_try < best_e:
            best_e, best_lam, have_best = e_try, lam, True
        if e_try <= e0:
            return STATUS_OK, e_try
    if best_lam != lam:
        for i in range(delta.shape[0]):
            delta[i] = delta_old[i] + best_lam * step[i]
        st = _evaluate(delta, delta2, delta_y, q_n, params_table, param_index, weight, base, trial, traction, q, qt, codes,
                       info, held, ST, slot, wk, F, err)
        return st, err[0]
    return STATUS_OK, best_e


@numba.njit(cache=True)
def _correction(ST, slot, F, rows, qt_rows, qt, J, piv, ref_rows, ref_qt, has_ref, z, step, update_min_changes,
                update_change_fraction, singular_pivot, counts):
    """The Newton correction into ``step`` (JointSpace._correction): the reference LU when the active set and its
    rows are those of the reference, a low-rank update of it when few rows changed, else a new LU that becomes
    the reference. Returns (status, J, piv, ref_rows, ref_qt, has_ref)."""
    na = rows.shape[0]
    if na == 0:
        return apply_correction(ST, slot, F, rows, z, step), J, piv, ref_rows, ref_qt, has_ref
    if has_ref and _same_rows(rows, ref_rows) and _same_bits(qt_rows, ref_qt):
        st = joint_space_correction(ST, slot, F, rows, qt, J, piv, z, step)
        return st, J, piv, ref_rows, ref_qt, has_ref
    if has_ref:
        max_changes = max(update_min_changes, (ref_rows.shape[0] + na) // update_change_fraction)
        st = capacitance_update_solve(ST, slot, ref_rows, ref_qt, J, piv, rows, qt_rows, F, max_changes, z)
        if st == STATUS_OK:
            counts[2] += 1
            return apply_correction(ST, slot, F, rows, z, step), J, piv, ref_rows, ref_qt, has_ref
    st, J_new, piv_new = capacitance_getrf(ST, slot, rows, qt, singular_pivot)
    if st != STATUS_OK:
        return st, J, piv, ref_rows, ref_qt, False
    counts[1] += 1
    st = joint_space_correction(ST, slot, F, rows, qt, J_new, piv_new, z, step)
    return st, J_new, piv_new, rows, qt_rows, True


@numba.njit(cache=True)
def _same_rows(a, b):
    if a.shape[0] != b.shape[0]:
        return False
    for i in range(a.shape[0]):
        if a[i] != b[i]:
            return False
    return True
