"""Dense LU factorisation with partial pivoting and its solve, in place, for the composite law's 5x5 local
system (float64 ``A`` (n, n), ``piv`` int64 (n,), ``b`` (n,); no allocation inside a numba kernel).
"""
from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def lu_factor(A, piv, n):
    """In-place LU factorisation with partial pivoting of ``A[:n, :n]``; False if singular."""
    for k in range(n):
        p = k
        amax = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > amax:
                amax = abs(A[i, k])
                p = i
        if not amax > 0.0 or not math.isfinite(amax):
            return False
        piv[k] = p
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        for i in range(k + 1, n):
            A[i, k] /= A[k, k]
            lik = A[i, k]
            for j in range(k + 1, n):
                A[i, j] -= lik * A[k, j]
    return True


@njit(cache=True)
def lu_solve(A, piv, b, n):
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= A[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= A[i, j] * b[j]
        b[i] = s / A[i, i]
