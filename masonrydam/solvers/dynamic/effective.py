"""The effective-matrix solver of the implicit steps' general path: :class:`EffectiveSolver`.

Solves ``K_eff x = b`` for effective matrices ``K_eff = K_T + c_m M + c_c C`` (n_eq, n_eq) given by their values
in the model's CSR pattern. ``K_eff`` changes only where joint points leave the elastic (stick) state, so every
solve takes the first of these that applies (docs/dynamics.md, "General path"):

1. a cached factorization of this very matrix (the all-stick matrix of a step size is named by a key and
   never compared): one substitution;
2. a low-rank update of a cached factorization: ``K_eff = K_ref + P E P^T`` with ``P`` selecting the m DOFs
   ``J`` of the points that slide or opened, solved by the Sherman-Morrison-Woodbury identity
   ``x = y - Z (I + E Z_JJ)^-1 E y_J``, ``y = K_ref^-1 b``, ``Z = K_ref^-1 P`` (Golub & Van Loan, *Matrix
   Computations*, 4th ed. 2013, sec. 2.1.4; kernels in :mod:`masonrydam.solvers.linear.dense_lu`), the columns
   of ``Z`` kept per reference;
3. a new factorization, cached (up to :data:`MAX_CACHED`, the pinned all-stick one included).

All choices depend on counts, not timings, so that runs are bitwise reproducible.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..linear.dense_lu import woodbury_apply, woodbury_factor
from ..linear.direct import Factorization, SingularMatrix, SymmetricFactorization
from .stage import DynamicStats

#: factorizations of effective matrices kept (the all-stick one of the nominal step included)
MAX_CACHED = 3


def low_rank_column_budget(n_eq: int) -> int:
    """New columns of ``Z`` (one substitution each) allowed for one low-rank update before a
    refactorization is preferred: about half the cost ratio of a factorization to a substitution.
    The ratio grows like sqrt(n) for 2D meshes; measured 33 ms against 0.65 ms (ratio 50) at 7 048
    equations (PARDISO, one thread), hence ``0.3 sqrt(n)``. Counts, not timings, so that the choice -
    and with it the last bits of every solution, which a nonlinear joint analysis amplifies - is
    the same in every run."""
    return max(8, int(0.3 * math.sqrt(max(n_eq, 1))))


class EffectiveSolver:
    """Solves ``K_eff x = b`` for effective matrices given by their values in one CSR pattern.

    See the module docstring and docs/dynamics.md (the general path). ``max_rank``: largest Woodbury rank;
    ``max_cached``: factorizations kept (the pinned one included).
    """

    class _Ref:
        def __init__(self, data, fact, n):
            self.data = data
            self.fact = fact
            self.zidx = np.full(n, -1, dtype=np.int64)
            self.zrows = np.zeros((0, n))
            self.nz = 0
            self.pinned = False
            self.jkey = None
            self.ZT = None
            self.key = None
            self.ekey = None
            self.S = None
            self.piv = None
            self.columns_computed = 0

    def __init__(self, indptr, indices, n, backend="auto", max_rank=256, max_cached=MAX_CACHED, stats=None,
                 symmetric_fast=False, reuse_analysis=False):
        self.indptr, self.indices, self.n = indptr, indices, n
        self.symmetric_fast = symmetric_fast
        self.reuse_analysis = reuse_analysis
        self.rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
        self.cols = indices.astype(np.int64)
        self.backend = backend
        self.max_rank = int(max_rank)
        self.max_cached = max(1, int(max_cached))
        self.refs: list[EffectiveSolver._Ref] = []
        self.stats = stats if stats is not None else DynamicStats()
        self.column_budget = low_rank_column_budget(n)
        self.low_rank_off = False
        self._loc = np.full(n, -1, dtype=np.int64)

    def _matrix(self, data):
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def factorize(self, data, pin=False, key=None, symmetric=False):
        """Factorize the effective matrix of values ``data`` and cache it (``pin``: never evicted).
        ``symmetric``: the matrix is a symmetric positive definite one (the all-stick matrix of a step
        size) that will be solved many times: with ``self.symmetric_fast`` it gets a sparse
        ``L D L^T`` with fast substitutions (:class:`~masonrydam.solvers.linear.direct.SymmetricFactorization`),
        falling back to the general backend should that refuse it."""
        fact = None
        if symmetric and self.symmetric_fast:
            try:
                fact = SymmetricFactorization(self._matrix(data.copy()))
            except (ValueError, SingularMatrix):
                fact = None
        if fact is None and self.reuse_analysis and len(self.refs) >= self.max_cached:
            fact = self._refactorize_oldest(data)
        if fact is None:
            fact = Factorization(self._matrix(data.copy()), self.backend)
        if symmetric:
            self.stats.reference_solvers.add(fact.backend)
        ps = getattr(fact, "_ps", None)
        if ps is not None:
            # PARDISO's default two steps of iterative refinement make each substitution ~7x slower
            # (4.5 ms against 0.64 ms on the 7 000-DOF wall); they only matter with perturbed pivots,
            # which Factorization rejects, and every solve's residual is checked (and Newton
            # recomputes the true residual), so they are switched off (iparm(8) = 0).
            ps.set_iparm(8, 0)
        self.stats.factorizations += 1
        ref = EffectiveSolver._Ref(data.copy(), fact, self.n)
        ref.pinned = pin
        ref.key = key
        self.refs.insert(0, ref)
        while len(self.refs) > self.max_cached:
            for k in range(len(self.refs) - 1, -1, -1):
                if not self.refs[k].pinned:
                    del self.refs[k]
                    break
            else:
                break
        return ref

    def _refactorize_oldest(self, data):
        """The factorization the cache would evict next, refactorized with ``data`` on its kept symbolic
        analysis (:meth:`~masonrydam.solvers.linear.direct.Factorization.refactorize`) and taken out of the cache;
        None where there is none (pinned, symmetric L D L^T, another backend)."""
        for k in range(len(self.refs) - 1, -1, -1):
            ref = self.refs[k]
            if ref.pinned or not isinstance(ref.fact, Factorization):
                continue
            # out of the cache before its factorization changes: a refactorization that raises (singular)
            # must not leave an entry whose values no longer match its factors
            del self.refs[k]
            return ref.fact if ref.fact.refactorize(self._matrix(data.copy())) else None
        return None

    def _substitute(self, ref, b):
        return ref.fact.solve(b)

    def solve(self, data, b, allow_inexact=False, key=None):
        """``(x, kind)``: kind "exact" (a cached factorization of this very matrix), "low_rank"
        (Woodbury update of a cached one: exact up to round-off), "modified" (the most recent
        factorization as an approximate iteration matrix; only if ``allow_inexact``) or "factorized".
        ``key``: a name for a matrix known to be the same whenever the key is (the all-stick matrix
        of a step size), which spares comparing the values."""
        for k, ref in enumerate(self.refs):
            if (key is not None and ref.key == key) or np.array_equal(ref.data, data):
                self.stats.exact_solves += 1
                if k:
                    self.refs.insert(0, self.refs.pop(k))
                return self._substitute(ref, b), "exact"
        if self.max_rank > 0 and self.refs:
            best = None
            for ref in self.refs:
                nz = np.flatnonzero(data != ref.data)
                r = self.rows[nz]  # ascending: the entries are in CSR order
                if len(r) and 1 + np.count_nonzero(r[1:] != r[:-1]) > self.max_rank:
                    # J holds at least the distinct rows: more than max_rank, refused without forming J (np.union1d
                    # of a cracking step's changed entries took 5 ms a cached matrix on the Koyna example, 1.5 s
                    # of its first 3 s of record); the same decision as below
                    continue
                J = np.union1d(r, self.cols[nz])
                if len(J) > self.max_rank:
                    continue
                # cost: the columns of Z not cached yet, one substitution each
                missing = int((ref.zidx[J] < 0).sum()) if ref.jkey != J.tobytes() else 0
                if best is None or missing < best[3]:
                    best = (ref, J, nz, missing)
            # new columns of one update within the budget; and low-rank updates stop for the rest of
            # the stage when their columns are not reused (many points switching state in every
            # iteration: fewer than one solve per 4 columns after 16 budgets of columns)
            if self.stats.low_rank_columns > 16 * self.column_budget and \
                    4 * self.stats.low_rank_solves < self.stats.low_rank_columns:
                self.low_rank_off = True
            if best is not None and not self.low_rank_off and best[3] <= self.column_budget:
                x = self._woodbury(best[0], best[1], best[2], data, b)
                if x is not None:
                    return x, "low_rank"
        if allow_inexact and self.refs:
            self.stats.modified_solves += 1
            return self._substitute(self.refs[0], b), "modified"
        ref = self.factorize(data, key=key, symmetric=key is not None)  # keys name all-stick matrices
        return self._substitute(ref, b), "factorized"

    def _woodbury(self, ref, J, nz, data, b):
        J = J.astype(np.int64)
        m = len(J)
        loc = self._loc
        loc[J] = np.arange(m)
        e_row = loc[self.rows[nz]]
        e_col = loc[self.cols[nz]]
        loc[J] = -1
        e_val = data[nz] - ref.data[nz]
        key = J.tobytes()
        if ref.jkey != key:
            missing = J[ref.zidx[J] < 0]
            if len(missing):
                if ref.nz + len(missing) > 4 * max(self.max_rank, 1):  # reset the column cache
                    ref.zidx[:] = -1
                    ref.nz = 0
                    missing = J
                B = np.zeros((self.n, len(missing)), order="F")
                B[missing, np.arange(len(missing))] = 1.0
                Z = np.asarray(ref.fact.solve(B)).reshape(self.n, len(missing))
                self.stats.low_rank_columns += len(missing)
                ref.columns_computed += len(missing)
                need = ref.nz + len(missing)
                if need > ref.zrows.shape[0]:
                    grown = np.zeros((max(need, 2 * ref.zrows.shape[0]), self.n))
                    grown[: ref.nz] = ref.zrows[: ref.nz]
                    ref.zrows = grown
                ref.zrows[ref.nz:need] = Z.T
                ref.zidx[missing] = np.arange(ref.nz, need)
                ref.nz = need
            ref.ZT = np.ascontiguousarray(ref.zrows[ref.zidx[J]])  # (m, n): row i = K_ref^-1 e_{J_i}
            ref.jkey = key
        e_val = np.ascontiguousarray(e_val)
        # the m x m factors depend on (J, E) only: kept while the same points slide the same way
        ekey = (key, e_row.tobytes(), e_col.tobytes(), e_val.tobytes())
        if ref.ekey != ekey:
            S = np.empty((m, m))
            piv = np.empty(m, dtype=np.int64)
            if woodbury_factor(ref.ZT, J, e_row, e_col, e_val, S, piv) != 0:
                ref.ekey = None
                return None
            ref.S, ref.piv, ref.ekey = S, piv, ekey
        y = np.ascontiguousarray(self._substitute(ref, b), dtype=np.float64)
        x = np.empty(self.n)
        w = np.empty(m)
        if woodbury_apply(ref.ZT, J, e_row, e_col, e_val, ref.S, ref.piv, y, w, x) != 0:
            return None
        nb = np.linalg.norm(b)
        if nb > 0 and np.linalg.norm(self._matrix(data) @ x - b) > 1e-6 * nb:
            return None
        self.stats.low_rank_solves += 1
        self.stats.max_rank = max(self.stats.max_rank, m)
        return x
