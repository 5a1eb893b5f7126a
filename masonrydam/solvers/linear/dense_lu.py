"""Small dense LU factorizations and the low-rank (Woodbury) update of a reference solution, as numba kernels.

:func:`lu_factor_inplace`, :func:`lu_forward_inplace`, :func:`lu_solve_inplace`: Gaussian elimination with
partial pivoting (Golub & Van Loan, *Matrix Computations*, 4th ed. 2013, Alg. 3.4.1) on a row-major square
matrix (m, m), factors in place, 0-based sequential row swaps in ``piv`` (m,) int64. Written out here
rather than through LAPACK: single-threaded and therefore bitwise reproducible (docs/architecture.md);
on a machine with few cores a multi-threaded BLAS took 14-144 ms for a 250 x 250 solve that takes about
2 ms single-threaded. Used by the joint-space condensation (:mod:`masonrydam.solvers.joint_space`) and the
dynamic solver's effective-matrix updates.

:func:`woodbury_factor` and :func:`woodbury_apply` apply a low-rank (Sherman-Morrison-Woodbury)
correction to a solution of the reference system (Golub & Van Loan 2013, sec. 2.1.4):
with ``K = K_ref + P E P^T`` (``P`` selects the m DOFs ``J``), ``y = K_ref^-1 b`` and the stored
columns ``Z = K_ref^-1 P`` (passed transposed, ``ZT`` (m, n)),

    K^-1 b = y - Z (I + E Z_JJ)^-1 E y_J.

``E`` is given as coordinate triplets (it has a few entries per row: one joint element couples a handful
of DOFs). The factors of ``I + E Z_JJ`` are computed once per (J, E): while the same points slide the same
way the values of E repeat from one iteration and step to the next, and each solve is then O(n m).
"""
from __future__ import annotations

import numba
import numpy as np

from ...errors import STATUS_NAN, STATUS_OK

#: the m x m capacitance matrix ``I + E Z_JJ`` is singular to working precision
STATUS_SINGULAR = 4


@numba.njit(cache=True)
def lu_factor_inplace(A, piv):
    """LU factors of the square matrix ``A`` in place (unit lower L below the diagonal, U on and above),
    partial pivoting with the row swaps in ``piv`` (Golub & Van Loan, *Matrix Computations*, 4th ed.
    2013, Alg. 3.4.1). Returns STATUS_OK, STATUS_SINGULAR (a pivot below 1e-14 x max|A|) or STATUS_NAN."""
    m = A.shape[0]
    scale = 0.0
    for i in range(m):
        for j in range(m):
            a = abs(A[i, j])
            if a > scale:
                scale = a
    if not (scale < np.inf):
        return STATUS_NAN
    tiny = 1e-14 * scale
    for col in range(m):
        p = col
        best = abs(A[col, col])
        for r in range(col + 1, m):
            a = abs(A[r, col])
            if a > best:
                best = a
                p = r
        if not (best > tiny):
            return STATUS_SINGULAR
        piv[col] = p
        if p != col:
            for j in range(m):
                t = A[col, j]
                A[col, j] = A[p, j]
                A[p, j] = t
        d = A[col, col]
        for r in range(col + 1, m):
            f = A[r, col] / d
            A[r, col] = f
            if f != 0.0:
                for j in range(col + 1, m):
                    A[r, j] -= f * A[col, j]
    return STATUS_OK


@numba.njit(cache=True, inline="always")
def lu_forward_inplace(A, piv, w):
    """``w := L^-1 P w`` with the factors of :func:`lu_factor_inplace` or LAPACK's ``getrf`` (0-based
    sequential row swaps ``piv``): the factorization swaps whole rows (multipliers included), so
    ``P A = L U`` with P the product of all the swaps: apply them all to w first, then solve with the
    unit lower triangle, column by column."""
    m = A.shape[0]
    for col in range(m):
        p = piv[col]
        if p != col:
            t = w[col]
            w[col] = w[p]
            w[p] = t
    for col in range(m):
        wc = w[col]
        for r in range(col + 1, m):
            w[r] -= A[r, col] * wc


@numba.njit(cache=True)
def lu_solve_inplace(A, piv, w):
    """Solve with the factors of :func:`lu_factor_inplace`; ``w`` is the right-hand side on entry and
    the solution on exit (row-oriented back substitution: for row-major factors)."""
    m = A.shape[0]
    lu_forward_inplace(A, piv, w)
    for col in range(m - 1, -1, -1):
        acc = w[col]
        for j in range(col + 1, m):
            acc -= A[col, j] * w[j]
        w[col] = acc / A[col, col]


@numba.njit(cache=True)
def woodbury_factor(ZT, J, e_row, e_col, e_val, S, piv):
    """LU factors (partial pivoting, in place in ``S``, row swaps in ``piv``) of the capacitance matrix
    ``I + E Z_JJ``; returns STATUS_OK, STATUS_SINGULAR or STATUS_NAN."""
    m = J.shape[0]
    for i in range(m):
        for j in range(m):
            S[i, j] = 0.0
        S[i, i] = 1.0
    for k in range(e_val.shape[0]):
        r = e_row[k]
        v = e_val[k]
        jc = J[e_col[k]]
        for i in range(m):
            S[r, i] += v * ZT[i, jc]
    return lu_factor_inplace(S, piv)


@numba.njit(cache=True)
def woodbury_apply(ZT, J, e_row, e_col, e_val, S, piv, y, w, x):
    """``x = y - ZT^T (I + E Z_JJ)^-1 E y_J`` with the factors of :func:`woodbury_factor`."""
    m = J.shape[0]
    n = y.shape[0]
    for i in range(m):
        w[i] = 0.0
    for k in range(e_val.shape[0]):
        w[e_row[k]] += e_val[k] * y[J[e_col[k]]]
    lu_solve_inplace(S, piv, w)
    for j in range(n):
        x[j] = y[j]
    for i in range(m):
        wi = w[i]
        if wi != 0.0:
            for j in range(n):
                x[j] -= wi * ZT[i, j]
    for j in range(n):
        if not (abs(x[j]) < np.inf):
            return STATUS_NAN
    return STATUS_OK
