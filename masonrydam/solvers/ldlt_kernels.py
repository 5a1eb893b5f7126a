"""Numba kernels: substitutions with a sparse ``L D L^T`` factorization (:class:`.linear.SymmetricFactorization`).

``L`` is unit lower triangular, stored without its diagonal in compressed sparse columns (``Lp``
(n+1,), ``Li`` (nnz,) row indices, ``Lx`` (nnz,) values), ``d`` (n,) the pivots, ``perm`` (n,) the
fill-reducing order: ``A[perm][:, perm] = L D L^T``. A solve of ``A x = b`` is ``w = b[perm]``,
``L y = w`` (column-oriented forward substitution), ``y /= d``, ``L^T z = y`` (a dot product with each
column of L, backwards, summed in four interleaved partial sums), ``x[perm] = z`` (Golub & Van Loan
2013, sec. 4.1.2 and 3.1). Both passes read each stored entry once, so a solve costs ``4 nnz(L)``
flops and two sweeps over the factor. Subscripts taken from the index arrays are cast to unsigned
(``UNSIGNED``), which halves the time of a solve (0.31 ms on the Koyna factor). A supernodal copy of the
factor (relaxed supernodes of up to 8 columns, unsigned subscripts; Liu, Ng & Peyton 1993, Ashcraft &
Grimes 1989) took 0.16 ms; it was not adopted for its size: a written-out branch per supernode width.
Single-threaded and deterministic; return STATUS_OK, or STATUS_NAN when the result is not finite.
"""
from __future__ import annotations

import numba
import numpy as np

from ..errors import STATUS_NAN, STATUS_OK

#: subscripts read from index arrays are cast to this unsigned type: numba adds a wrap-around test
#: for negative values (a compare and a conditional move) to every subscript of a signed integer,
#: which made the substitution about twice as slow (0.69 against 0.31 ms on the Koyna factor, the
#: same bits); the indices of a factor are never negative
UNSIGNED = np.uint64


@numba.njit(cache=True)
def ldlt_solve_vector(Lp, Li, Lx, d, perm, b, x, w):
    """``x = A^-1 b`` for one right-hand side: b, x, w (work space) (n,)."""
    n = b.shape[0]
    for i in range(n):
        w[i] = b[UNSIGNED(perm[i])]
    for j in range(n):
        wj = w[j]
        if wj != 0.0:
            for k in range(Lp[j], Lp[j + 1]):
                w[UNSIGNED(Li[UNSIGNED(k)])] -= Lx[UNSIGNED(k)] * wj
    for j in range(n):
        w[j] /= d[j]
    for j in range(n - 1, -1, -1):
        # four partial sums: one running sum waits on each multiply-add in turn (a latency chain of
        # nnz(L) x 4 cycles); four independent ones overlap (15 % faster on the Koyna factor)
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
        k = Lp[j]
        end = Lp[j + 1]
        while k + 3 < end:
            a0 += Lx[UNSIGNED(k)] * w[UNSIGNED(Li[UNSIGNED(k)])]
            a1 += Lx[UNSIGNED(k + 1)] * w[UNSIGNED(Li[UNSIGNED(k + 1)])]
            a2 += Lx[UNSIGNED(k + 2)] * w[UNSIGNED(Li[UNSIGNED(k + 2)])]
            a3 += Lx[UNSIGNED(k + 3)] * w[UNSIGNED(Li[UNSIGNED(k + 3)])]
            k += 4
        while k < end:
            a0 += Lx[UNSIGNED(k)] * w[UNSIGNED(Li[UNSIGNED(k)])]
            k += 1
        w[j] -= (a0 + a1) + (a2 + a3)
    for i in range(n):
        x[UNSIGNED(perm[i])] = w[i]
    for i in range(n):
        if not (abs(x[i]) < np.inf):
            return STATUS_NAN
    return STATUS_OK


@numba.njit(cache=True, inline="always")
def _subtract_scaled_row(dst, src, l):
    """``dst -= l src`` for two rows (k,) of a block of right-hand sides."""
    for c in range(dst.shape[0]):
        dst[c] -= l * src[c]


@numba.njit(cache=True)
def ldlt_solve_block(Lp, Li, Lx, d, perm, B, X, W):
    """``X = A^-1 B`` for a block of right-hand sides: B, X, W (work space) (n, k), C order (the k
    columns of a row are contiguous, so every entry of L updates k values at once)."""
    n, nr = B.shape
    for i in range(n):
        src = B[UNSIGNED(perm[i])]
        dst = W[i]
        for c in range(nr):
            dst[c] = src[c]
    for j in range(n):  # forward: row j updates the rows below it
        for k in range(Lp[j], Lp[j + 1]):
            _subtract_scaled_row(W[UNSIGNED(Li[UNSIGNED(k)])], W[j], Lx[UNSIGNED(k)])
    for j in range(n):
        dj = d[j]
        wj = W[j]
        for c in range(nr):
            wj[c] /= dj
    for j in range(n - 1, -1, -1):  # backward: row j gathers from the rows below it
        for k in range(Lp[j], Lp[j + 1]):
            _subtract_scaled_row(W[j], W[UNSIGNED(Li[UNSIGNED(k)])], Lx[UNSIGNED(k)])
    for i in range(n):
        src = W[i]
        dst = X[UNSIGNED(perm[i])]
        for c in range(nr):
            dst[c] = src[c]
    for i in range(n):
        for c in range(nr):
            if not (abs(X[i, c]) < np.inf):
                return STATUS_NAN
    return STATUS_OK
