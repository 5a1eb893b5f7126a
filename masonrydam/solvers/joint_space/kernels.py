"""Numba kernels of the joint-space (condensed) Newton solver, :mod:`masonrydam.solvers.joint_space.condensation`.

Notation (see that module): the ``P`` joint integration points of the nonlinear joint sets, each with
``dim`` local relative-displacement components, give ``m = P * dim`` joint unknowns ``delta``
(local frame, m). Columns of the joint flexibility ``S = B K_ref^-1 B^T`` (m/N) are rows of ``ST``
(k, m), so that a column is contiguous: column ``j`` of ``S`` is ``ST[slot[j]]``, with ``slot`` (m,)
int64 (``slot = arange(m)`` when every column is stored; ``-1`` for a column not in the store, which
no kernel reads: :class:`~masonrydam.solvers.joint_space.condensation.FlexibilityColumns` fetches the columns a
call needs first). ``q`` (P, dim) is the joint force
correction ``w (t - D0 delta)`` (N) and ``qt`` (P, dim, dim) its derivative ``w (C - D0)`` (N/m), with
``w`` the point's tributary area (m^2), ``D0 = diag(ks, [ks,] kn)`` and ``t``, ``C`` the traction and
tangent of the joint law.

All kernels are single-threaded and deterministic (docs/architecture.md) and return a status code.
The LU of the capacitance matrix is LAPACK's ``getrf`` (called from :mod:`.condensation`, pinned to
one BLAS thread); the substitutions with its factors and the small LU of a Woodbury update are
written out here (:func:`lu_solve_colmajor`, :func:`masonrydam.solvers.linear.dense_lu.lu_solve_inplace`).
"""
from __future__ import annotations

import numba
import numpy as np

from ...errors import STATUS_NAN, STATUS_OK
from ...materials.mohr_coulomb import (P_COHESION, P_KN, P_KS, P_KS_RESIDUAL, P_OPEN_TANGENT, P_TAN_PHI,
                                      P_TENSILE_STRENGTH, S_BACK_STRESS, S_BOND_BROKEN, S_CODE, S_PLASTIC_SLIP,
                                      STICK, mohr_coulomb_point, write_tangent, write_trial)
from ..linear.dense_lu import lu_factor_inplace, lu_forward_inplace, lu_solve_inplace
from ..linear.ldlt_kernels import UNSIGNED

#: more rows changed than allowed for an update of the reference LU: refactorize instead
STATUS_TOO_MANY_CHANGES = 5
#: the residual needs a column of S that is not in the store (slot -1): nothing written to F
STATUS_MISSING_COLUMNS = 6


@numba.njit(cache=True, inline="always")
def _add_scaled(out, row, v):
    """``out += v row`` (both (n,)): one column of S or X (a contiguous row of its transpose)."""
    for i in range(out.shape[0]):
        out[i] += row[i] * v


@numba.njit(cache=True, inline="always")
def _finite_status(x):
    """STATUS_OK when every entry of ``x`` is finite, else STATUS_NAN."""
    for i in range(x.shape[0]):
        if not (abs(x[i]) < np.inf):
            return STATUS_NAN
    return STATUS_OK


@numba.njit(cache=True)
def joint_law_at_points(points, n, params_table, param_index, weight, delta, state_base, state_trial, traction, q,
                        qt, codes, info, held):
    """The joint law at the points ``points[:n]``, or at the points ``0 .. n-1`` when ``points`` is empty
    (see :func:`joint_points_evaluate` for the arrays). The only kernel that contains the law: the
    residual kernels take its results (compiled once, the law costs about 1.4 s of the first run;
    inside each residual kernel it was compiled again). One call for all the points: the law
    (:func:`~masonrydam.materials.mohr_coulomb.mohr_coulomb_point`) gets scalars read here, because a
    per-point helper that takes the arrays (or row views of them) pays reference counts per point
    that cost several times the law (588 points: 52 us that way, about 8 us in one loop).
    Returns a status, with the failing point in ``info[0]``."""
    dim = delta.shape[1]
    ns = dim - 1
    tangent = np.zeros((dim, dim))
    for k in range(n):
        p = points[k] if points.shape[0] else k
        ip = param_index[p]
        ks = params_table[ip, P_KS]
        kn = params_table[ip, P_KN]
        (st, code, broken, slip1, slip2, back1, back2, tau1, tau2, t_n, C11, C12, C21, C22, C1n, C2n, Cnn) = \
            mohr_coulomb_point(ks, kn, params_table[ip, P_COHESION], params_table[ip, P_TAN_PHI],
                               params_table[ip, P_TENSILE_STRENGTH], params_table[ip, P_KS_RESIDUAL],
                               params_table[ip, P_OPEN_TANGENT], ns, delta[p, 0], delta[p, 1] if ns == 2 else 0.0,
                               delta[p, ns], state_base[p, S_CODE], state_base[p, S_BOND_BROKEN],
                               state_base[p, S_PLASTIC_SLIP], state_base[p, S_PLASTIC_SLIP + 1],
                               state_base[p, S_BACK_STRESS], state_base[p, S_BACK_STRESS + 1])
        if st != STATUS_OK:
            info[0] = p
            return st
        w = weight[p]
        if held[p] != 0:
            # held sticking: the committed state, elastic tractions from the committed plastic slip
            for j in range(state_base.shape[1]):
                state_trial[p, j] = state_base[p, j]
            state_trial[p, S_CODE] = STICK
            for c in range(ns):
                traction[p, c] = ks * (delta[p, c] - state_base[p, S_PLASTIC_SLIP + c])
            traction[p, ns] = kn * delta[p, ns]
            code = STICK
        else:
            write_trial(state_trial[p], traction[p], ns, code, broken, slip1, slip2, back1, back2, tau1, tau2, t_n)
        icode = int(code)
        codes[p] = icode
        if icode == STICK:
            for c in range(ns):
                q[p, c] = -w * ks * state_trial[p, S_PLASTIC_SLIP + c]
            q[p, ns] = 0.0
            for c in range(dim):
                for d in range(dim):
                    qt[p, c, d] = 0.0
            continue
        write_tangent(tangent, ns, C11, C12, C21, C22, C1n, C2n, Cnn)
        for c in range(dim):
            k0 = kn if c == ns else ks
            q[p, c] = w * (traction[p, c] - k0 * delta[p, c])
            for d in range(dim):
                qt[p, c, d] = w * tangent[c, d]
            qt[p, c, c] -= w * k0
        for c in range(dim):
            if not (abs(q[p, c]) < np.inf):
                info[0] = p
                return STATUS_NAN
    return STATUS_OK


_ALL_POINTS = np.zeros(0, dtype=np.int64)


def joint_points_evaluate(params_table, param_index, weight, delta, state_base, state_trial, traction, q, qt,
                          codes, info, held):
    """Joint law at every point for the local relative displacements ``delta`` (P, dim), from
    ``state_base`` (P, N_JOINT_STATE; read only) into ``state_trial`` and ``traction`` (P, dim).

    Writes ``q`` (P, dim) N, ``qt`` (P, dim, dim) N/m and the state ``codes`` (P,) int8. A sticking point
    has ``qt = 0`` and ``q = -w ks s_p`` (shear), 0 (normal) - written from the plastic slip, not as the
    difference ``w (t - D0 delta)``, so that it is exactly the same in every iteration and step while
    the point sticks (its correction then never enters the condensed system). A point with
    ``held[p] != 0`` (P,) int8 is held sticking whatever its ``delta``: elastic traction
    ``D0 (delta - s_p)``, committed state otherwise (an iteration device of
    :meth:`~masonrydam.solvers.joint_space.condensation.JointSpace.solve_step`, never a converged state). Returns
    STATUS_OK, or STATUS_NAN with the point in ``info[0]``."""
    return joint_law_at_points(_ALL_POINTS, delta.shape[0], params_table, param_index, weight, delta, state_base,
                               state_trial, traction, q, qt, codes, info, held)


@numba.njit(cache=True)
def _force_norm(wk, F, err, info):
    """``err[0] = |wk * F|`` (N), a scaled 2-norm (no overflow of the squares for a large but finite
    residual); STATUS_NAN with ``info[0] = -1`` for a non-finite residual."""
    m = F.shape[0]
    big = 0.0
    for i in range(m):
        x = abs(wk[i] * F[i])
        if not (x < np.inf):
            info[0] = -1
            return STATUS_NAN
        if x > big:
            big = x
    acc = 0.0
    if big > 0.0:
        for i in range(m):
            x = wk[i] * F[i] / big
            acc += x * x
    err[0] = big * np.sqrt(acc)
    return STATUS_OK


def joint_space_reevaluate_points(points, params_table, param_index, weight, delta, state_base, state_trial, traction,
                                  q, qt, codes, info, held, ST, slot, wk, F, err):
    """The joint law again at the listed ``points`` (k,) int64, distinct, only - the others and ``delta`` unchanged,
    e.g. after their ``held`` flag changed - with the condensed residual updated by the change of
    their joint forces, ``F += S (q_new - q_old)`` (columns of those points), and its norm ``err[0]``.
    Equals :func:`joint_space_evaluate_residual` at the same arguments up to round-off, at the cost
    of ``k`` points instead of all. Same arguments and statuses."""
    dim = q.shape[1]
    q_old = q[points]
    st = joint_law_at_points(points, points.shape[0], params_table, param_index, weight, delta.reshape(-1, dim),
                             state_base, state_trial, traction, q, qt, codes, info, held)
    if st != STATUS_OK:
        return st
    return add_point_force_changes(points, q, q_old, ST, slot, wk, F, err, info)


@numba.njit(cache=True)
def add_point_force_changes(points, q, q_old, ST, slot, wk, F, err, info):
    """``F += S (q[points] - q_old)`` (columns of those points' components) and ``err[0] = |wk * F|``:
    the residual update of :func:`joint_space_reevaluate_points`; ``q_old`` (k, dim) the forces of
    ``points`` before the law was evaluated there again. Returns STATUS_OK or STATUS_NAN."""
    dim = q.shape[1]
    n = points.shape[0]
    for k in range(n):
        p = points[k]
        for c in range(dim):
            v = q[p, c] - q_old[k, c]
            if v != 0.0:
                _add_scaled(F, ST[slot[p * dim + c]], v)
    return _force_norm(wk, F, err, info)


def active_components(qt):
    """``(rows, qt_rows)``: the flat components ``p * dim + c`` (na,) int64, ascending, whose row of ``qt``
    (P, dim, dim) is not zero, and those rows (na, dim) - the active set of the capacitance matrix
    (:func:`capacitance_assemble`). numpy, not numba: compiled it cost 0.55 s of the first run for
    a few microseconds a call."""
    flat = qt.reshape(-1, qt.shape[2])
    rows = np.flatnonzero(flat.any(axis=1)).astype(np.int64)
    return rows, flat[rows]


@numba.njit(cache=True)
def state_key(codes, traction, key):
    """``key[p] = 2 codes[p] + (first shear traction > 0)`` (P,) int8: the state of every point with its
    friction direction (a point whose friction direction flips changes its key)."""
    for p in range(codes.shape[0]):
        key[p] = 2 * codes[p] + (1 if traction[p, 0] > 0.0 else 0)


@numba.njit(cache=True)
def add_flexibility_product(ST, slot, dq, F):
    """``F += S dq`` (both flat (m,)): one column of ``S`` (a contiguous row of ``ST``) per nonzero
    entry of ``dq``, which is nonzero only where a point's joint force changed."""
    for j in range(F.shape[0]):
        if dq[j] != 0.0:
            _add_scaled(F, ST[slot[j]], dq[j])


@numba.njit(cache=True)
def subtract_columns_product(XT, cols, vals, out):
    """``out -= X[:, cols] @ vals`` with ``X`` given by its transpose ``XT`` (m, n) (a column of ``X`` is a
    contiguous row of ``XT``); ``cols`` (k,) int64, ``vals`` (k,), ``out`` (n,). Costs ``2 k n`` flops
    streamed from memory, against ``4 nnz(L)`` indexed ones for a sparse substitution. Returns
    STATUS_OK, or STATUS_NAN when ``out`` is not finite."""
    for k in range(cols.shape[0]):
        _add_scaled(out, XT[cols[k]], -vals[k])
    return _finite_status(out)


@numba.njit(cache=True)
def capacitance_assemble(ST, slot, rows, qt, J, scale):
    """The capacitance matrix ``I + Qt_a S_:a`` into ``J`` (na, na), ``na = len(rows)``, Fortran order
    (LAPACK then factorizes it in place; a column of ``J`` is filled contiguously from one contiguous
    row of ``ST``).

    ``rows`` (na,) int64 are the flat components ``p * dim + c`` whose row of ``Qt`` is not zero (a point
    that slides without hardening has a zero normal row, so in 2D it adds one row, not two);
    ``J[i, j] = delta_ij + sum_d qt[p_i, c_i, d] S[(p_i, d), rows_j]``. ``scale[0]`` receives max |J|
    (the reference of the singularity test). Returns STATUS_OK or STATUS_NAN."""
    dim = qt.shape[1]
    na = rows.shape[0]
    base = np.empty(na, dtype=np.int64)  # first component of the point of row i
    qa = np.empty((na, dim))  # the Qt row of row i
    for i in range(na):
        p = rows[i] // dim
        c = rows[i] - p * dim
        base[i] = p * dim
        for d in range(dim):
            qa[i, d] = qt[p, c, d]
    for j in range(na):
        rj = ST[slot[rows[j]]]
        for i in range(na):
            b = base[i]
            acc = 0.0
            for d in range(dim):
                acc += qa[i, d] * rj[UNSIGNED(b + d)]
            J[i, j] = acc
        J[j, j] += 1.0
    big = 0.0
    for j in range(na):
        for i in range(na):
            a = abs(J[i, j])
            if not (a < np.inf):
                return STATUS_NAN
            if a > big:
                big = a
    scale[0] = big
    return STATUS_OK


@numba.njit(cache=True)
def lu_solve_colmajor(A, piv, w):
    """Solve ``A x = w`` in place with LAPACK ``getrf`` factors ``A`` (n, n) in Fortran order and the
    0-based sequential row swaps ``piv`` (n,): both triangular passes run down the columns of ``A``,
    which are contiguous (Golub & Van Loan 2013, Alg. 3.1.3 and 3.1.4, column versions)."""
    n = A.shape[0]
    lu_forward_inplace(A, piv, w)
    for col in range(n - 1, -1, -1):
        wc = w[col] / A[col, col]
        w[col] = wc
        if wc != 0.0:
            for r in range(col):
                w[r] -= A[r, col] * wc


@numba.njit(cache=True)
def joint_space_correction(ST, slot, F, rows, qt, J, piv, z, step):
    """Newton correction ``D`` of the condensed system ``delta + S q(delta) = const``, written to ``step`` (m,).

    With ``z = Qt_a D`` on the components ``rows`` where ``Qt`` has a nonzero row (the other
    components of ``Qt D`` vanish): ``D = -F - S_:a z`` and ``(I + Qt_a S_:a) z = -Qt_a F``, solved with
    the LU factors of :func:`~masonrydam.solvers.joint_space.condensation.capacitance_lu` in ``J``, ``piv`` (row
    swaps in LAPACK's order, 0-based); ``z`` (>= na) is work space.
    Returns STATUS_OK or STATUS_NAN."""
    dim = qt.shape[1]
    na = rows.shape[0]
    w = z[:na]
    for i in range(na):
        p = rows[i] // dim
        c = rows[i] % dim
        acc = 0.0
        for d in range(dim):
            acc += qt[p, c, d] * F[p * dim + d]
        w[i] = -acc
    lu_solve_colmajor(J, piv, w)
    return apply_correction(ST, slot, F, rows, w, step)




@numba.njit(cache=True)
def _apply_ref_inverse(Jref, piv, ref_rows_n, JRN, posR, nN_idx, v, x):
    """``x = J_ref(U)^-1 v`` for the capacitance matrix of the reference rows embedded in the union U:
    rows of U not in the reference are identity rows, so ``x_N = v_N`` and
    ``x_R = LU^-1 (v_R - J_RN v_N)``."""
    nr = ref_rows_n
    t = np.empty(nr)
    for i in range(nr):
        t[i] = 0.0
    nU = v.shape[0]
    for u in range(nU):
        if posR[u] >= 0:
            t[posR[u]] += v[u]
    for k in range(nN_idx.shape[0]):
        vn = v[nN_idx[k]]
        if vn != 0.0:
            for i in range(nr):
                t[i] -= JRN[i, k] * vn
    lu_solve_colmajor(Jref, piv, t)
    for u in range(nU):
        if posR[u] >= 0:
            x[u] = t[posR[u]]
        else:
            x[u] = v[u]


@numba.njit(cache=True)
def capacitance_update_solve(ST, slot, ref_rows, ref_qt, Jref, piv, rows, qt_rows, F, max_changes, z):
    """Solve ``(I + Qt_c S_:c) z = -Qt_c F`` for the current active components ``rows`` (sorted, with
    their rows of Qt in ``qt_rows`` (nc, dim)) from the LU (``Jref``, ``piv``) of the capacitance
    matrix of reference components ``ref_rows`` (sorted; ``ref_qt`` (nr, dim)).

    On the union U of both sets the two matrices differ only in the rows whose Qt row changed (the
    set D): ``J_c = J_r + E_D W`` with ``W = (Qt_c - Qt_r)_D S_:U``, and the Sherman-Morrison-Woodbury
    identity (Golub & Van Loan 2013, sec. 2.1.4) gives ``z = y - Y (I + W Y)^-1 W y`` with
    ``y = J_r^-1 b``, ``Y = J_r^-1 E_D``: |D| solves with the old factors and a |D| x |D| LU instead of
    an LU of size |U|. Returns STATUS_OK, STATUS_TOO_MANY_CHANGES (|D| > max_changes: nothing is
    written), STATUS_SINGULAR or STATUS_NAN; ``z`` (>= nc) receives the solution in the order of
    ``rows``."""
    dim = qt_rows.shape[1]
    nr = ref_rows.shape[0]
    nc = rows.shape[0]
    U = np.empty(nr + nc, dtype=np.int64)
    posR = np.empty(nr + nc, dtype=np.int64)
    posC = np.empty(nr + nc, dtype=np.int64)
    i = 0
    j = 0
    nU = 0
    while i < nr or j < nc:
        if j >= nc or (i < nr and ref_rows[i] < rows[j]):
            U[nU] = ref_rows[i]
            posR[nU] = i
            posC[nU] = -1
            i += 1
        elif i >= nr or rows[j] < ref_rows[i]:
            U[nU] = rows[j]
            posR[nU] = -1
            posC[nU] = j
            j += 1
        else:
            U[nU] = rows[j]
            posR[nU] = i
            posC[nU] = j
            i += 1
            j += 1
        nU += 1
    # changed rows and their Qt differences
    D = np.empty(nU, dtype=np.int64)
    dq = np.empty((nU, dim))
    nd = 0
    for u in range(nU):
        diff = False
        for d in range(dim):
            a = ref_qt[posR[u], d] if posR[u] >= 0 else 0.0
            b = qt_rows[posC[u], d] if posC[u] >= 0 else 0.0
            dq[nd, d] = b - a
            if a != b:
                diff = True
        if diff:
            D[nd] = u
            nd += 1
    if nd > max_changes:
        return STATUS_TOO_MANY_CHANGES
    # columns of the union outside the reference and J_RN
    nN = 0
    for u in range(nU):
        if posR[u] < 0:
            nN += 1
    N_idx = np.empty(nN, dtype=np.int64)
    k = 0
    for u in range(nU):
        if posR[u] < 0:
            N_idx[k] = u
            k += 1
    JRN = np.empty((nr, nN))
    for kk in range(nN):  # one contiguous row of ST per column, read in increasing order
        col = ST[slot[U[N_idx[kk]]]]
        for ii in range(nr):
            b = (ref_rows[ii] // dim) * dim
            acc = 0.0
            for d in range(dim):
                acc += ref_qt[ii, d] * col[UNSIGNED(b + d)]
            JRN[ii, kk] = acc
    # right-hand side b = -Qt_c F on U
    b = np.zeros(nU)
    for u in range(nU):
        if posC[u] >= 0:
            p = U[u] // dim
            acc = 0.0
            for d in range(dim):
                acc += qt_rows[posC[u], d] * F[p * dim + d]
            b[u] = -acc
    y = np.empty(nU)
    _apply_ref_inverse(Jref, piv, nr, JRN, posR, N_idx, b, y)
    # Y = J_r^-1 E_D (nU x nd), W = dQt_D S_:U (nd x nU)
    Y = np.empty((nd, nU))
    e = np.zeros(nU)
    col_out = np.empty(nU)
    for kk in range(nd):
        e[D[kk]] = 1.0
        _apply_ref_inverse(Jref, piv, nr, JRN, posR, N_idx, e, col_out)
        e[D[kk]] = 0.0
        for u in range(nU):
            Y[kk, u] = col_out[u]
    W = np.empty((nd, nU))
    for u in range(nU):  # one contiguous row of ST per column of W
        col = ST[slot[U[u]]]
        for kk in range(nd):
            b = (U[D[kk]] // dim) * dim
            acc = 0.0
            for d in range(dim):
                acc += dq[kk, d] * col[UNSIGNED(b + d)]
            W[kk, u] = acc
    Cm = np.empty((nd, nd))
    for a in range(nd):
        for c in range(nd):
            acc = 0.0
            for u in range(nU):
                acc += W[a, u] * Y[c, u]
            Cm[a, c] = acc
        Cm[a, a] += 1.0
    cpiv = np.empty(nd, dtype=np.int64)
    st = lu_factor_inplace(Cm, cpiv)
    if st != STATUS_OK:
        return st
    s = np.empty(nd)
    for a in range(nd):
        acc = 0.0
        for u in range(nU):
            acc += W[a, u] * y[u]
        s[a] = acc
    lu_solve_inplace(Cm, cpiv, s)
    for u in range(nU):
        acc = y[u]
        for c in range(nd):
            acc -= Y[c, u] * s[c]
        if posC[u] >= 0:
            z[posC[u]] = acc
    for jj in range(nc):
        if not (abs(z[jj]) < np.inf):
            return STATUS_NAN
    return STATUS_OK


@numba.njit(cache=True)
def apply_correction(ST, slot, F, rows, z, step):
    """``step = -F - S_:a z`` (m,) for the components ``rows`` and their ``z``; STATUS_OK or STATUS_NAN."""
    for i in range(F.shape[0]):
        step[i] = -F[i]
    for j in range(rows.shape[0]):
        if z[j] != 0.0:
            _add_scaled(step, ST[slot[rows[j]]], -z[j])
    return _finite_status(step)


def joint_space_evaluate_residual(params_table, param_index, weight, delta, state_base, state_trial, traction, q, qt,
                                  codes, info, held, ST, slot, delta_y, q_n, wk, F, err):
    """The joint law at ``delta`` (:func:`joint_points_evaluate`, same arguments and outputs) and then the
    condensed residual ``F = delta - delta_y + S (q - q_n)`` (:func:`add_flexibility_product`; only the
    points whose ``q`` changed contribute) and its force norm ``err[0] = |wk * F|`` (N): two kernels,
    :func:`joint_law_at_points` and :func:`condensed_residual`. ``delta``, ``delta_y``, ``wk``, ``F`` flat (m,); ``q_n`` (P, dim). Returns the law's
    status (a NaN of the law with its point in ``info[0]``), STATUS_NAN with ``info[0] = -1`` for a
    non-finite residual, or STATUS_MISSING_COLUMNS (the law evaluated, ``F`` untouched) when a
    component whose ``q`` changed has no column in the store: the caller fetches the columns of the
    nonzero entries of ``q - q_n`` and calls again."""
    st = joint_points_evaluate(params_table, param_index, weight, delta.reshape(q.shape), state_base, state_trial,
                               traction, q, qt, codes, info, held)
    if st != STATUS_OK:
        return st
    return condensed_residual(delta, delta_y, q, q_n, ST, slot, wk, F, err, info)


@numba.njit(cache=True)
def condensed_residual(delta, delta_y, q, q_n, ST, slot, wk, F, err, info):
    """``F = delta - delta_y + S (q - q_n)`` and ``err[0] = |wk * F|`` from the law's ``q`` (the residual
    part of :func:`joint_space_evaluate_residual`, same arguments and statuses)."""
    dq = (q - q_n).ravel()
    m = F.shape[0]
    for j in range(m):
        if dq[j] != 0.0 and slot[j] < 0:
            return STATUS_MISSING_COLUMNS
    for i in range(m):
        F[i] = delta[i] - delta_y[i]
    add_flexibility_product(ST, slot, dq, F)
    return _force_norm(wk, F, err, info)
