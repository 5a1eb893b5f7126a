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
Blocks of right-hand sides on large factors go by supernodes through BLAS instead
(:func:`ldlt_solve_block_supernodal`).
Single-threaded and deterministic; return STATUS_OK, or STATUS_NAN when the result is not finite.
"""
from __future__ import annotations

import numba
import numpy as np

from ...errors import STATUS_NAN, STATUS_OK

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


@numba.njit(cache=True, inline="always")
def _rows_in_factor_order(B, perm, W):
    """``W = B[perm]`` for a block (n, k): the right-hand sides in the order of the factor."""
    for i in range(B.shape[0]):
        src = B[UNSIGNED(perm[i])]
        dst = W[i]
        for c in range(B.shape[1]):
            dst[c] = src[c]


@numba.njit(cache=True, inline="always")
def _rows_in_matrix_order(W, perm, X):
    """``X[perm] = W`` for a block (n, k), then STATUS_NAN when ``X`` is not finite, else STATUS_OK."""
    n, k = W.shape
    for i in range(n):
        src = W[i]
        dst = X[UNSIGNED(perm[i])]
        for c in range(k):
            dst[c] = src[c]
    for i in range(n):
        for c in range(k):
            if not (abs(X[i, c]) < np.inf):
                return STATUS_NAN
    return STATUS_OK


@numba.njit(cache=True)
def ldlt_solve_block(Lp, Li, Lx, d, perm, B, X, W):
    """``X = A^-1 B`` for a block of right-hand sides: B, X, W (work space) (n, k), C order (the k
    columns of a row are contiguous, so every entry of L updates k values at once)."""
    n, nr = B.shape
    _rows_in_factor_order(B, perm, W)
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
    return _rows_in_matrix_order(W, perm, X)


@numba.njit(cache=True)
def supernode_partition(Lp, Li, max_width):
    """First columns of the fundamental supernodes of ``L`` (Liu, Ng & Peyton 1993), (ns + 1,) int64
    ending with n: column ``j + 1`` joins the supernode of column ``j`` when the structure of column
    ``j`` below the diagonal is ``{j + 1}`` followed by that of column ``j + 1`` and the supernode has
    fewer than ``max_width`` columns (a wider one is cut in pieces, each a supernode). Within a supernode of
    columns ``s .. e-1`` every column ``c`` then holds rows ``c+1 .. e-1`` (its diagonal block) and
    then the rows of column ``e - 1`` (the rows below, shared by all its columns)."""
    n = Lp.shape[0] - 1
    starts = np.empty(n + 1, dtype=np.int64)
    ns = 0
    if n > 0:
        starts[0] = 0
        ns = 1
    for j in range(n - 1):
        a0, a1, b1 = Lp[j], Lp[j + 1], Lp[j + 2]
        same = a1 - a0 == b1 - a1 + 1 and a1 > a0 and Li[a0] == j + 1 and j + 1 - starts[ns - 1] < max_width
        if same:
            for t in range(b1 - a1):
                if Li[a0 + 1 + t] != Li[a1 + t]:
                    same = False
                    break
        if not same:
            starts[ns] = j + 1
            ns += 1
    starts[ns] = n
    return starts[:ns + 1].copy()


@numba.njit(cache=True)
def supernode_panels(Lp, Lx, starts):
    """``(offsets, panels)``: the entries of each supernode's rows below its diagonal block packed as a
    dense (w, nb) row-major array (row t: column ``s + t``), supernode S at ``panels[offsets[S]:
    offsets[S + 1]]`` - the operand of the matrix products of :func:`ldlt_solve_block_supernodal`."""
    ns = starts.shape[0] - 1
    offsets = np.zeros(ns + 1, dtype=np.int64)
    for S in range(ns):
        s, e = starts[S], starts[S + 1]
        offsets[S + 1] = offsets[S] + (e - s) * (Lp[e] - Lp[e - 1])
    panels = np.empty(offsets[ns])
    for S in range(ns):
        s, e = starts[S], starts[S + 1]
        nb = Lp[e] - Lp[e - 1]
        o = offsets[S]
        for t in range(e - s):
            c = s + t
            first = Lp[c] + (e - 1 - c)
            for r in range(nb):
                panels[o + t * nb + r] = Lx[first + r]
    return offsets, panels


@numba.njit(cache=True)
def ldlt_solve_block_supernodal(Lp, Li, Lx, d, perm, starts, offsets, panels, B, X, W, T):
    """``X = A^-1 B`` like :func:`ldlt_solve_block` (same arguments, ``T`` (n * k,) work space), by
    supernodes (:func:`supernode_partition`): the diagonal block of a supernode is substituted entry
    by entry, and its rows below are updated with one dense product ``W[below] -= L_below W[s:e]``
    (forward) or ``W[s:e] -= L_below^T W[below]`` (backward) through BLAS ``dgemm``.

    Why: a block of right-hand sides is what the joint space computes its flexibility columns with
    (:class:`~masonrydam.solvers.joint_space.FlexibilityColumns`), and entry by entry every stored
    entry of L streams a whole row of the block through memory. A product by supernode reads each
    row of the block once per supernode instead of once per entry: on the 3D dam factor (39 744
    equations, 21.8 million entries, supernodes at most 64 wide) a block of 256 took 0.88 s against
    1.94 s; SuperLU's own supernodal solve (scipy) took 5.1 s for the same block."""
    n, k = B.shape
    _rows_in_factor_order(B, perm, W)
    ns = starts.shape[0] - 1
    for S in range(ns):  # forward
        s, e = starts[S], starts[S + 1]
        for c in range(s, e - 1):
            base = Lp[c]
            for t in range(e - 1 - c):
                _subtract_scaled_row(W[c + 1 + t], W[c], Lx[UNSIGNED(base + t)])
        lo, hi = Lp[e - 1], Lp[e]
        nb = hi - lo
        if nb > 0:
            w = e - s
            panel = panels[offsets[S]:offsets[S + 1]].reshape((w, nb))
            prod = T[:nb * k].reshape((nb, k))
            np.dot(panel.T, W[s:e], prod)
            for r in range(nb):
                _subtract_scaled_row(W[UNSIGNED(Li[UNSIGNED(lo + r)])], prod[r], 1.0)
    for j in range(n):
        dj = d[j]
        wj = W[j]
        for c in range(k):
            wj[c] /= dj
    for S in range(ns - 1, -1, -1):  # backward
        s, e = starts[S], starts[S + 1]
        lo, hi = Lp[e - 1], Lp[e]
        nb = hi - lo
        if nb > 0:
            w = e - s
            panel = panels[offsets[S]:offsets[S + 1]].reshape((w, nb))
            gathered = T[:nb * k].reshape((nb, k))
            for r in range(nb):
                src = W[UNSIGNED(Li[UNSIGNED(lo + r)])]
                dst = gathered[r]
                for c in range(k):
                    dst[c] = src[c]
            prod = np.dot(panel, gathered)
            for t in range(w):
                _subtract_scaled_row(W[s + t], prod[t], 1.0)
        for c in range(e - 2, s - 1, -1):
            base = Lp[c]
            for t in range(e - 1 - c):
                _subtract_scaled_row(W[c], W[c + 1 + t], Lx[UNSIGNED(base + t)])
    return _rows_in_matrix_order(W, perm, X)
