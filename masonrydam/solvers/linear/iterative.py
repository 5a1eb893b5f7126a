"""Algebraic multigrid preconditioned Krylov solver with the interface of :class:`Factorization`.

:class:`AMGSolver` takes a sparse (n, n) matrix ``K``, the near-nullspace (n, k) (the rigid-body modes of
:func:`rigid_body_modes`) and optionally the node position (n, dim) m and node of every row, and solves
``K x = b`` to ``||K x - b|| <= 1e-10 ||b||`` or raises ``SingularMatrix``: smoothed-aggregation AMG (pyamg;
Vanek, Mandel & Brezina 1996) preconditioning conjugate gradients (symmetric ``K``) or flexible GMRES (Saad
1993), with an extra first level that collapses tied interface node pairs (:func:`tied_groups`, block
Gauss-Seidel) so that stiff penalty joints do not slow it down, and joint springs that are not tied left out of
the first aggregation graph. Stopping at the rounding floor: Arioli, Duff & Ruiz (1992).

Theory and measured figures: docs/performance.md, section "How the AMG solver works" (under "Linear solvers in
3D: direct vs AMG").
"""
from __future__ import annotations

import copy
import time
import warnings

import numba
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import LinearOperator, splu

from .common import SingularMatrix

#: relative distance (to the model size) below which two DOF positions coincide
COINCIDENT_RTOL = 1e-9
#: iterations between true-residual checks near convergence (best iterate kept)
_TRUE_RESIDUAL_EVERY = 5
#: seed of numpy's global generator while pyamg builds a hierarchy (restored afterwards)
_PYAMG_SEED = 20240601


class _Stop(Exception):
    pass


def rigid_body_modes(coords: np.ndarray, dof_index: np.ndarray, dim: int) -> np.ndarray:
    """Rigid-body modes restricted to a set of DOFs: the near-nullspace of an elastic stiffness.

    Parameters
    ----------
    coords : (n_nodes, dim) float64, m
        Node coordinates.
    dof_index : (n_free,) int
        Full-model DOF numbers (``node * dim + component``) of the rows of the matrix, e.g.
        ``model.dofmap.free``.
    dim : 2 or 3

    Returns
    -------
    (n_free, 3) in 2D or (n_free, 6) in 3D float64: the unit translations along each axis, then the
    infinitesimal rotations ``u = omega x (x - x_c)`` about the centroid x_c of the nodes concerned
    (2D: about z; 3D: about x, y, z). The rotation columns are divided by the RMS distance of the
    nodes from the centroid, so that all columns have comparable norms.
    """
    coords = np.asarray(coords, dtype=np.float64)
    dof_index = np.asarray(dof_index, dtype=np.int64)
    if dim not in (2, 3) or coords.ndim != 2 or coords.shape[1] != dim:
        raise ValueError(f"coords must be (n_nodes, dim) with dim 2 or 3, got {coords.shape} and dim={dim}")
    node, comp = np.divmod(dof_index, dim)
    n = len(dof_index)
    ncol = 3 if dim == 2 else 6
    if n == 0:
        return np.zeros((0, ncol))
    x = coords[node] - coords[np.unique(node)].mean(axis=0)
    scale = float(np.sqrt((x**2).sum(axis=1).mean())) or 1.0
    x /= scale
    B = np.zeros((n, ncol))
    for d in range(dim):
        B[comp == d, d] = 1.0
    if dim == 2:
        B[:, 2] = np.where(comp == 0, -x[:, 1], x[:, 0])  # about z: (-y, x)
        return B
    X, Y, Z = x[:, 0], x[:, 1], x[:, 2]
    B[:, 3] = np.select([comp == 1, comp == 2], [-Z, Y], 0.0)  # about x: (0, -z, y)
    B[:, 4] = np.select([comp == 0, comp == 2], [Z, -X], 0.0)  # about y: (z, 0, -x)
    B[:, 5] = np.select([comp == 0, comp == 1], [-Y, X], 0.0)  # about z: (-y, x, 0)
    return B


def is_symmetric(K, rtol: float = 1e-12) -> bool:
    """``max |K - K^T| <= rtol * max |K|``. Compares the data arrays of K and K^T when their
    sparsity patterns are equal (always so for assembled FE matrices), else takes the sparse
    difference."""
    K = sp.csr_matrix(K)
    if K.shape[0] != K.shape[1]:
        return False
    if K.nnz == 0:
        return True
    amax = float(np.abs(K.data).max())
    Ks = K if K.has_sorted_indices else K.sorted_indices()
    Kt = K.T.tocsr()
    Kt.sort_indices()
    if np.array_equal(Ks.indptr, Kt.indptr) and np.array_equal(Ks.indices, Kt.indices):
        diff = float(np.abs(Ks.data - Kt.data).max())
    else:
        d = (Ks - Kt).tocsr()
        diff = float(np.abs(d.data).max()) if d.nnz else 0.0
    return diff <= rtol * amax


def coincidence_keys(dof_coords: np.ndarray, near_nullspace: np.ndarray | None = None) -> np.ndarray:
    """(n,) int64: equal for DOFs of coincident nodes (positions equal on a grid of
    ``COINCIDENT_RTOL`` times the model size; interface generators duplicate nodes with identical
    coordinates) and, with ``near_nullspace``, equal near-nullspace rows (the same component)."""
    X = np.asarray(dof_coords, dtype=np.float64)
    n = len(X)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    X = X.reshape(n, -1)
    size = float(np.ptp(X, axis=0).max()) or 1.0
    cols = [np.round((X - X.min(axis=0)) / (COINCIDENT_RTOL * size))]
    if near_nullspace is not None:
        cols.append(np.asarray(near_nullspace, dtype=np.float64).reshape(n, -1))
    _, key = np.unique(np.column_stack(cols), axis=0, return_inverse=True)
    return key.ravel().astype(np.int64)


#: the last results of :func:`coincident_entries` (a Newton iteration sets up multigrid for tangents of one pattern:
#: 0.3 s a call at 166k DOF, twice per set-up)
_COINCIDENT_CACHE: list = []


def clear_pattern_caches() -> None:
    """Let the kept results of :func:`coincident_entries` go (at the end of a static solve)."""
    _COINCIDENT_CACHE.clear()


def _same_arrays(a, b) -> bool:
    if a is b:
        return True
    if a is None or b is None:
        return False
    return a.shape == b.shape and np.array_equal(a, b)


def coincident_entries(K, key: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
    """Positions in ``K.data`` (CSR) of the off-diagonal entries that couple two DOFs with the same
    coincidence key (:func:`coincidence_keys`) and, with ``nodes`` (the node of each DOF), of two
    different nodes: the node-pair springs of zero-thickness interfaces. They depend on the pattern of K alone:
    the last two results are kept and returned for the same pattern, keys and nodes."""
    for entry in _COINCIDENT_CACHE:
        if all(_same_arrays(a, b) for a, b in zip(entry[:4], (K.indptr, K.indices, key, nodes))):
            return entry[4]
    pos = _coincident_entries(K, key, nodes)
    _COINCIDENT_CACHE.insert(0, (K.indptr.copy(), K.indices.copy(), np.array(key, copy=True),
                                 None if nodes is None else np.array(nodes, copy=True), pos))
    del _COINCIDENT_CACHE[2:]
    return pos


def _coincident_entries(K, key, nodes):
    n = K.shape[0]
    dup = np.nonzero(np.bincount(key, minlength=key.max() + 1 if n else 0)[key] > 1)[0]
    if len(dup) == 0:
        return np.zeros(0, dtype=np.int64)
    starts, counts = K.indptr[dup], np.diff(K.indptr)[dup]
    pos = np.repeat(starts - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts) + np.arange(counts.sum())
    rows = np.repeat(dup, counts)
    cols = K.indices[pos]
    keep = (cols != rows) & (key[cols] == key[rows])
    if nodes is not None:
        keep &= nodes[cols] != nodes[rows]
    return pos[keep].astype(np.int64)


def tied_groups(K, near_nullspace: np.ndarray, dof_coords: np.ndarray, threshold: float = 0.25, key=None):
    """Groups of DOFs tied by strong springs between coincident nodes (see the module docstring).

    Returns ``(n_groups, label)``: label (n,) int64, the group of each DOF, numbered in order of
    the groups' first DOF. DOFs i != j are tied when their positions coincide, their near-nullspace
    rows are equal (same component) and ``|k_ij| >= threshold * sqrt(k_ii k_jj)``.
    """
    K = sp.csr_matrix(K)
    n = K.shape[0]
    if key is None:
        key = coincidence_keys(dof_coords, near_nullspace)
    pos = coincident_entries(K, key)
    row = np.searchsorted(K.indptr, pos, side="right") - 1
    col = K.indices[pos].astype(np.int64)
    d = np.abs(K.diagonal())
    strong = np.abs(K.data[pos]) >= threshold * np.sqrt(d[row] * d[col])
    row, col = row[strong], col[strong]
    if len(row) == 0:
        return n, np.arange(n, dtype=np.int64)
    G = sp.csr_matrix((np.ones(len(row)), (row, col)), shape=(n, n))
    ng, label = connected_components(G, directed=False)
    # renumber in order of first appearance (a natural ordering for the Gauss-Seidel sweeps)
    first = np.full(ng, n, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n))
    rank = np.empty(ng, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(ng)
    return int(ng), rank[label]


@numba.njit(cache=True)
def _asymmetric(data, perm, tol):
    """Whether ``|data[i] - data[perm[i]]| > tol`` for some i (``perm``: the transpose permutation of a CSR
    pattern); stops at the first such entry (a tangent with sliding joints is not symmetric)."""
    for i in range(data.shape[0]):
        if abs(data[i] - data[perm[i]]) > tol:
            return True
    return False


@numba.njit(cache=True)
def _block_inverses(indptr, indices, data, members, ptr, inv, inv_ptr):
    """Inverse of the diagonal block of every group (dense, row major, into ``inv``); returns the
    index of the first singular block or -1."""
    ng = len(ptr) - 1
    for g in range(ng):
        g0, g1 = ptr[g], ptr[g + 1]
        m = g1 - g0
        blk = np.zeros((m, m))
        for a in range(m):
            i = members[g0 + a]
            for p in range(indptr[i], indptr[i + 1]):
                j = indices[p]
                for c in range(m):
                    if members[g0 + c] == j:
                        blk[a, c] += data[p]
        if m == 1:
            if blk[0, 0] == 0.0:
                return g
            inv[inv_ptr[g]] = 1.0 / blk[0, 0]
            continue
        if np.linalg.cond(blk) > 1e14:
            return g
        bi = np.linalg.inv(blk)
        for a in range(m):
            for c in range(m):
                inv[inv_ptr[g] + a * m + c] = bi[a, c]
    return -1


@numba.njit(cache=True)
def _block_gauss_seidel(indptr, indices, data, x, b, members, ptr, inv, inv_ptr, forward, work):
    """One block Gauss-Seidel sweep over the groups (forward or backward), x updated in place."""
    ng = len(ptr) - 1
    for k in range(ng):
        g = k if forward else ng - 1 - k
        g0, g1 = ptr[g], ptr[g + 1]
        m = g1 - g0
        for a in range(m):
            i = members[g0 + a]
            s = b[i]
            for p in range(indptr[i], indptr[i + 1]):
                s -= data[p] * x[indices[p]]
            work[a] = s
        q = inv_ptr[g]
        for a in range(m):
            acc = 0.0
            for c in range(m):
                acc += inv[q + a * m + c] * work[c]
            x[members[g0 + a]] += acc


class AMGSolver:
    """Smoothed-aggregation AMG preconditioned CG (symmetric K) or FGMRES (non-symmetric K).

    Same interface as :class:`~masonrydam.solvers.linear.direct.Factorization`: ``solve(b)`` returns x
    with ``||K x - b|| <= tol ||b||`` or raises ``SingularMatrix``.

    Parameters
    ----------
    K : (n, n) sparse matrix (CSR preferred; not modified)
    near_nullspace : (n, k) array, optional
        Near-nullspace candidates, normally :func:`rigid_body_modes`; default: the constant vector
        (right for scalar problems only).
    residual_check : float
        As in ``Factorization``: a solution whose relative residual is above it is never returned.
        A solution between ``tol`` and ``residual_check`` is returned only at the rounding floor
        (the iteration stopped, or a restart no longer reduced the true residual), never after
        ``maxiter`` iterations.
    dof_coords : (n, dim) array, optional
        Position of the node of each row (m); needed to find the node pairs of interfaces.
    dof_nodes : (n,) int array, optional
        Node of each row; with it, joint springs between different components of a node pair
        (friction coupling of a sliding joint) are told from the couplings inside one node.
    tol : float
        Relative residual tolerance, default 1e-10.
    maxiter : int
        Iteration limit per solve (all restarts together).
    restart : int
        FGMRES restart length (non-symmetric K).
    symmetric : bool, optional
        Skip the symmetry test and use this.
    tie_threshold : float
        Strength ``|k_ij| / sqrt(k_ii k_jj)`` above which coincident DOFs are tied; ``None``: never.
    coarse_theta : float
        Strength-of-connection threshold (pyamg "symmetric") of the coarse levels when the model has
        joint springs that are not tied; the first level uses theta = 0 without those springs.
    max_coarse : int
        pyamg's ``max_coarse``: coarsening stops at this many aggregates (coarse levels have one
        block of ``k`` unknowns per aggregate, k = columns of the near-nullspace); the coarsest
        level is factorized by SuperLU.
    stagnation_window : int
        A solve stops when the residual has not halved over this many iterations (rounding floor,
        or a singular system); the best iterate is returned if it passes ``residual_check``, else
        SingularMatrix is raised.
    backward_tol : float
        A solve also stops when the normwise backward error ``||r|| / (||K||_inf ||x|| + ||b||)``
        (Rigal & Gaches 1967; Arioli, Duff & Ruiz 1992, SIAM J. Matrix Anal. Appl. 13:138-144) is
        below it: the rounding floor of a nearly singular system (a block held only by open joints),
        where ``tol`` is out of reach and further iterations lose accuracy. Such a solution is
        returned when its relative residual is below ``residual_check``, as a direct solver's is.
    sa_options : dict, optional
        Extra keyword arguments of ``pyamg.smoothed_aggregation_solver`` (e.g. ``strength``,
        ``smooth``, ``improve_candidates``), for experiments.

    Attributes
    ----------
    backend = "amg"; K; symmetric (bool); krylov ("cg" or "fgmres"); n_groups (tied groups; = n
    when nothing is tied); setup_time_s; levels (number of levels, the tied level included);
    level_sizes; operator_complexity (of the pyamg hierarchy); last_iterations, last_residual,
    last_solve_time_s, last_backward_error (of the last solve); iterations, solve_times_s (lists, one
    entry per solve).
    """

    backend = "amg"

    def __init__(self, K, near_nullspace: np.ndarray | None = None, residual_check: float = 1e-6, *,
                 dof_coords: np.ndarray | None = None, dof_nodes: np.ndarray | None = None, tol: float = 1e-10,
                 maxiter: int = 1000, restart: int = 50, symmetric: bool | None = None,
                 tie_threshold: float | None = 0.25, max_coarse: int = 100,
                 coarse_theta: float = 0.1, stagnation_window: int = 50, backward_tol: float = 1e-17,
                 sa_options: dict | None = None):

        t0 = time.perf_counter()
        K = sp.csr_matrix(K)
        if K.shape[0] != K.shape[1]:
            raise ValueError(f"K must be square, got {K.shape}")
        if not K.has_sorted_indices:
            K = K.sorted_indices()
        self.K = K
        self.residual_check = residual_check
        self.tol = float(tol)
        self.maxiter = int(maxiter)
        self.restart = int(restart)
        self.max_coarse = int(max_coarse)
        self.sa_options = dict(sa_options or {})
        self.coarse_theta = float(coarse_theta)
        self.stagnation_window = int(stagnation_window)
        self.backward_tol = float(backward_tol)
        self.last_backward_error = float("nan")
        self.iterations: list[int] = []
        self.solve_times_s: list[float] = []
        self.last_iterations = 0
        self.last_residual = float("nan")
        self.last_solve_time_s = 0.0
        n = K.shape[0]
        if not np.isfinite(K.data).all():
            raise SingularMatrix("stiffness matrix contains NaN or infinity")
        diag = K.diagonal()
        if n and not (diag > 0).all():
            bad = int(np.nonzero(~(diag > 0))[0][0])
            what = "an empty row" if K.indptr[bad + 1] == K.indptr[bad] else "a zero or negative diagonal entry"
            raise SingularMatrix(f"stiffness matrix has {what} (equation {bad}); the AMG solver needs a positive "
                                 "diagonal")
        self._normA = float(np.abs(K).sum(axis=1).max()) if n else 0.0  # ||K||_inf
        self.symmetric = is_symmetric(K) if symmetric is None else bool(symmetric)
        self.krylov = "cg" if self.symmetric else "fgmres"
        if near_nullspace is None:
            B = np.ones((n, 1))
        else:
            B = np.asarray(near_nullspace, dtype=np.float64)
            if B.ndim == 1:
                B = B[:, None]
            if B.shape[0] != n:
                raise ValueError(f"near_nullspace has {B.shape[0]} rows, the matrix {n}")
            B = np.ascontiguousarray(B)
        self.n_groups = n
        key, nodes = None, None
        if near_nullspace is not None and dof_coords is not None and n:
            if dof_nodes is not None:  # every joint spring, between any components of two nodes
                key, nodes = coincidence_keys(dof_coords), np.asarray(dof_nodes, dtype=np.int64)
            else:  # the same component only (the DOFs of one node are not told apart otherwise)
                key = coincidence_keys(dof_coords, B)
            if tie_threshold is not None:
                self.n_groups, label = tied_groups(K, B, dof_coords, tie_threshold)
        if self.n_groups < n:
            self._setup_tied(K, B, label, key, nodes)
        else:
            self._ml = self._sa(K, B, key, nodes)
            self._M = self._ml.aspreconditioner(cycle="V")
            self._M @ np.ones(n)  # pyamg sets the coarse solver up at the first cycle: count it in the setup
            self.level_sizes = [lv.A.shape[0] for lv in self._ml.levels]
        self.levels = len(self.level_sizes)
        self.operator_complexity = float(self._ml.operator_complexity())
        self.setup_time_s = time.perf_counter() - t0

    # -- setup --------------------------------------------------------------------------------------
    def _sa(self, A, B, key=None, nodes=None):
        """pyamg smoothed-aggregation hierarchy, with the singularity check of its coarsest level.
        With coincidence keys, the first level's strength graph leaves out the joint springs that
        are not tied (open, sliding or soft joints), so that no aggregate spans such a joint."""
        # pyamg (0.07 s to import) only when an AMG solver is built: 3D models of 50 000 equations or more
        import pyamg
        from pyamg.strength import symmetric_strength_of_connection


        # one forward Gauss-Seidel sweep before the coarse grid and one backward after it (a symmetric V-cycle, so
        # still a CG preconditioner) instead of pyamg's symmetric sweeps on both sides: half the smoothing of the
        # coarse levels per cycle for the same Krylov iterations (14.3-14.5 per Newton correction on the 8-monolith
        # dam's gravity; docs/performance.md)
        opts = {"coarse_solver": "splu", "improve_candidates": None,
                "presmoother": ("gauss_seidel", {"sweep": "forward"}),
                "postsmoother": ("gauss_seidel", {"sweep": "backward"})}
        self.joint_links_dropped = 0
        if key is not None and "strength" not in self.sa_options:
            A = sp.csr_matrix(A)
            pos = coincident_entries(A, key, nodes)
            if len(pos):
                C = sp.csr_matrix((np.abs(A.data), A.indices.copy(), A.indptr.copy()), shape=A.shape)
                C.data[pos] = 0.0
                C.eliminate_zeros()
                C = symmetric_strength_of_connection(C.maximum(C.T).tocsr(), theta=0.0)
                opts["strength"] = [("predefined", {"C": C}), ("symmetric", {"theta": self.coarse_theta})]
                self.joint_links_dropped = len(pos)
        # pyamg estimates spectral radii (Jacobi prolongation smoothing) from np.random initial vectors:
        # a fixed seed makes the hierarchy, and so a nonlinear run, reproducible; the caller's global
        # random state is restored
        rng_state = np.random.get_state()
        np.random.seed(_PYAMG_SEED)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sp.SparseEfficiencyWarning)
                ml = pyamg.smoothed_aggregation_solver(
                    A, B=B, symmetry="hermitian" if self.symmetric else "nonsymmetric", max_coarse=self.max_coarse,
                    **{**opts, **self.sa_options})
        finally:
            np.random.set_state(rng_state)
        Ac = ml.levels[-1].A
        if Ac.shape[0] <= 5000:
            Ac = sp.csr_matrix(Ac, copy=True)  # a one-level hierarchy holds K itself
            Ac.eliminate_zeros()
            keep = np.diff(Ac.indptr) > 0  # exactly empty rows: aggregates of isolated DOFs
            Ad = Ac[keep][:, keep].tocsc()
            if Ad.shape[0]:
                # pivots of an LU with partial pivoting (SuperLU; single-threaded, unlike a dense LAPACK
                # LU, which oversubscribes a busy machine), as a direct solver reports them
                try:
                    piv = np.abs(splu(Ad, permc_spec="COLAMD", diag_pivot_thresh=1.0).U.diagonal())
                except RuntimeError:  # exactly singular
                    piv = np.zeros(1)
                pmax, pmin = float(piv.max()), float(piv.min())
                if pmax == 0.0 or pmin <= 1e-13 * pmax:
                    raise SingularMatrix(
                        f"the stiffness matrix is singular: the coarsest level of the multigrid hierarchy "
                        f"({Ac.shape[0]} equations, built from {A.shape[0]}) has an LU pivot of "
                        f"{pmin / pmax if pmax else 0.0:.1e} times the largest, i.e. a part of the model can move as "
                        "a rigid body (0 iterations run)")
        return ml

    def _setup_tied(self, K, B, label, key, nodes):

        n, ng = K.shape[0], self.n_groups
        label = label.astype(np.int64)
        counts = np.bincount(label, minlength=ng)
        self._label = label
        self._counts = counts
        # K_c = Q^T K Q by relabelling rows and columns (duplicates summed)
        row = np.repeat(label, np.diff(K.indptr))
        Kc = sp.csr_matrix((K.data, (row, label[K.indices])), shape=(ng, ng))
        Kc.sum_duplicates()
        Kc.eliminate_zeros()
        Bc = np.zeros((ng, B.shape[1]))
        np.add.at(Bc, label, B)
        Bc /= counts[:, None]
        keyc = nodesc = None
        if key is not None:  # tied DOFs share their key; a group gets the node of one of its DOFs
            keyc = np.zeros(ng, dtype=np.int64)
            keyc[label] = key
            if nodes is not None:
                nodesc = np.zeros(ng, dtype=np.int64)
                nodesc[label] = nodes
        self._ml = self._sa(Kc, Bc, keyc, nodesc)
        self._Mc = self._ml.aspreconditioner(cycle="V")
        # block Gauss-Seidel data: members of each group, inverse diagonal blocks
        self._members = np.argsort(label, kind="stable").astype(np.int64)
        self._ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self._inv_ptr = np.concatenate([[0], np.cumsum(counts**2)]).astype(np.int64)
        self._inv = np.empty(int(self._inv_ptr[-1]))
        bad = _block_inverses(K.indptr, K.indices, K.data, self._members, self._ptr, self._inv, self._inv_ptr)
        if bad >= 0:
            dofs = self._members[self._ptr[bad]:self._ptr[bad + 1]].tolist()
            raise SingularMatrix(f"singular diagonal block of tied equations {dofs}")
        self._work = np.empty(int(counts.max()))
        #: the fine level's entries in single precision for the smoother alone (the sweeps read K once each and are
        #: bound by memory traffic; the residuals and the Krylov products keep K in double precision)
        self._smoother_data = K.data.astype(np.float32)
        self.level_sizes = [n] + [lv.A.shape[0] for lv in self._ml.levels]
        self._M = LinearOperator((n, n), matvec=self._two_level, dtype=np.float64)
        self._M @ np.ones(n)  # pyamg sets the coarse solver up at the first cycle: count it in the setup

    def _two_level(self, r):
        K = self.K
        r = np.ascontiguousarray(np.asarray(r, dtype=np.float64).ravel())
        x = np.zeros_like(r)
        _block_gauss_seidel(K.indptr, K.indices, self._smoother_data, x, r, self._members, self._ptr, self._inv,
                            self._inv_ptr, True, self._work)
        rc = np.bincount(self._label, weights=r - K @ x, minlength=self.n_groups)
        x += (self._Mc @ rc)[self._label]
        _block_gauss_seidel(K.indptr, K.indices, self._smoother_data, x, r, self._members, self._ptr, self._inv,
                            self._inv_ptr, False, self._work)
        return x

    def for_matrix(self, K, symmetric: bool | None = None) -> "AMGSolver":
        """A solver of ``K`` (the same size and DOFs, e.g. the next Newton tangent) preconditioned by this
        solver's hierarchy and smoother, which stay those of the matrix they were set up for: no setup (on the
        166k-DOF dam of examples/dam_3d_gravity.toml at element_size 3 a setup takes about 6 s, a solve to 1e-10
        about as long). The Krylov method is CG where both matrices are symmetric (the preconditioner is then
        symmetric positive definite), else FGMRES, which takes any preconditioner. The iteration count grows as
        ``K`` departs from the hierarchy's matrix; the caller sets up a new solver when it has grown too far
        (:attr:`convergence_factor`)."""
        K = sp.csr_matrix(K)
        if K.shape != self.K.shape:
            raise ValueError(f"K has shape {K.shape}, the hierarchy was set up for {self.K.shape}")
        if not K.has_sorted_indices:
            K = K.sorted_indices()
        if not np.isfinite(K.data).all():
            raise SingularMatrix("stiffness matrix contains NaN or infinity")
        new = copy.copy(self)  # shares the hierarchy, the smoother's data and the preconditioner operator
        new.K = K
        new._normA = float(np.add.reduceat(np.abs(K.data), K.indptr[:-1]).max()) if K.nnz else 0.0
        sym = self.is_symmetric_like(K) if symmetric is None else bool(symmetric)
        new.symmetric = sym and self.symmetric
        new.krylov = "cg" if new.symmetric else "fgmres"
        new.iterations, new.solve_times_s = [], []
        new.setup_time_s = 0.0
        new.reused = True
        return new

    #: a solver built by :meth:`for_matrix` (its hierarchy set up for another matrix)
    reused = False
    _transpose_perm = None

    def is_symmetric_like(self, K) -> bool:
        """:func:`is_symmetric` for a matrix ``K`` (sorted CSR), by the transpose permutation of this solver's
        matrix where ``K`` has its pattern (a Newton tangent of the same model: K^T's entries are K's, permuted)."""
        if K.shape == self.K.shape and np.array_equal(K.indptr, self.K.indptr) \
                and np.array_equal(K.indices, self.K.indices):
            perm = self._transpose_permutation()
            if perm is not None:
                amax = max(float(K.data.max(initial=0.0)), -float(K.data.min(initial=0.0)))
                return not _asymmetric(K.data, perm, 1e-12 * amax)
        return is_symmetric(K)

    def _transpose_permutation(self):
        """(nnz,) int: ``K^T.data == K.data[perm]`` for every matrix of K's pattern (sorted CSR), or None where the
        pattern is not symmetric; computed once per hierarchy and shared by the solvers reusing it (the symmetry
        test of a 166k-DOF tangent took 0.49 s, this one 0.05 s)."""
        if self._transpose_perm is None:
            K = self.K
            idx = sp.csr_matrix((np.arange(K.nnz, dtype=np.float64), K.indices, K.indptr), shape=K.shape)
            T = idx.T.tocsr()
            T.sort_indices()
            ok = np.array_equal(T.indptr, K.indptr) and np.array_equal(T.indices, K.indices)
            self._transpose_perm = T.data.astype(np.int64) if ok else np.zeros(0, dtype=np.int64)
        return self._transpose_perm if len(self._transpose_perm) == self.K.nnz else None

    @property
    def convergence_factor(self) -> float:
        """The mean residual reduction per iteration of the last solve, ``rel^(1/its)`` (0 for none, NaN before
        the first solve): the measure by which a caller decides to set a hierarchy up again."""
        if not self.iterations:
            return float("nan")
        its = self.last_iterations
        if its == 0 or not self.last_residual > 0.0:
            return 0.0
        return float(self.last_residual ** (1.0 / its))

    # -- solve --------------------------------------------------------------------------------------
    def _krylov(self, b, x0, maxiter, res, nb, tol):
        """One Krylov run; returns (x, flag, stop) with stop None, "floor" or "stagnated".

        Once the recursive residual is below ``residual_check``, the true residual is computed every
        ``_TRUE_RESIDUAL_EVERY`` iterations and the best iterate kept: past the rounding floor of a
        nearly singular system CG loses orthogonality and its iterates can diverge, and a stop then
        returns the best iterate seen."""
        # pyamg (0.07 s to import) only when an AMG solver is built: 3D models of 50 000 equations or more
        from pyamg.krylov import cg, fgmres

        window, eta_tol, normA, K = self.stagnation_window, self.backward_tol, self._normA, self.K
        best = {"r": float("inf"), "x": None}

        def keep_best(xk):
            r = float(np.linalg.norm(K @ xk - b))
            if r < best["r"]:
                best["r"], best["x"] = r, xk.copy()

        def watch(xk):
            k = len(res)
            if res[-1] <= self.residual_check * nb and k % _TRUE_RESIDUAL_EVERY == 0:
                keep_best(xk)
            # normwise backward error at the rounding level: iterating on only loses accuracy
            if res[-1] <= eta_tol * (normA * np.linalg.norm(xk) + nb):
                keep_best(xk)
                raise _Stop("floor")
            # no halving of the residual over the last `window` iterations: the rounding floor of a
            # nearly singular system, an inconsistent (singular) one, or a preconditioner that fails
            if k > window and res[-1] > 0.5 * min(res[: k - window]):
                keep_best(xk)
                raise _Stop("stagnated")

        try:
            with warnings.catch_warnings(record=True):  # pyamg warns on breakdown; handled by the caller
                if self.symmetric:
                    x, flag = cg(self.K, b, x0=x0, tol=tol, maxiter=maxiter, M=self._M, residuals=res,
                                 callback=watch)
                else:
                    outer = max(1, -(-maxiter // self.restart))
                    x, flag = fgmres(self.K, b, x0=x0, tol=tol, restart=self.restart, maxiter=outer, M=self._M,
                                     residuals=res, callback=watch)
        except _Stop as stop:
            return best["x"], 0, str(stop)
        except (ValueError, np.linalg.LinAlgError, ArithmeticError):  # NaN / singular Hessenberg inside
            return best["x"], -1, None
        if best["x"] is not None and np.isfinite(x).all():
            keep_best(x)
            x = best["x"]
        return x, flag, None

    def solve(self, b: np.ndarray, rtol: float | None = None) -> np.ndarray:
        """x with ``||K x - b|| <= tol ||b||``; ``rtol``, where given, loosens ``tol`` for this solve (an inexact
        Newton correction, whose forcing term the caller chooses: Eisenstat & Walker 1996, SIAM J. Sci. Comput.
        17:16-32); it is never tighter than ``tol``."""

        t0 = time.perf_counter()
        b = np.asarray(b, dtype=np.float64)
        if b.shape != (self.K.shape[0],):
            raise ValueError(f"b must have shape ({self.K.shape[0]},), got {b.shape}")
        if not np.isfinite(b).all():
            raise SingularMatrix("right-hand side contains NaN or infinity")
        nb = float(np.linalg.norm(b))
        if nb == 0.0:
            self._record(0, 0.0, t0)
            return np.zeros_like(b)
        tol = self.tol if rtol is None else max(float(rtol), self.tol)
        its, x, rel, eta, flag, stop = 0, None, float("inf"), float("inf"), 0, None
        name = f"AMG-preconditioned {self.krylov.upper()}"
        for _attempt in range(4):  # restarts from the last iterate when the recursive residual drifted
            res: list[float] = []
            x_new, flag, stop = self._krylov(b, x, self.maxiter - its, res, nb, tol)
            its += max(len(res) - 1, 0)
            if x_new is None or not np.isfinite(x_new).all():
                last = res[-1] / nb if res else float("nan")
                self._record(its, last, t0)
                raise SingularMatrix(
                    f"{name} produced NaN or infinity after {its} iterations (relative residual {last:.2e}); the "
                    "stiffness matrix is singular or nearly so (a part of the model may move as a rigid body)")
            x = x_new
            prev = rel
            r = float(np.linalg.norm(self.K @ x - b))
            rel, eta = r / nb, r / (self._normA * float(np.linalg.norm(x)) + nb)
            # a restart from x on the true residual (iterative refinement) helps after a drift of the
            # recursive residual, and after a stop at the rounding floor; not after stagnation
            if rel <= tol or stop == "stagnated" or flag != 0 or rel > 0.5 * prev or its >= self.maxiter:
                break
        self._record(its, rel, t0)
        self.last_backward_error = eta
        # accepted: the tolerance, or the residual check of the direct solvers once the iteration
        # can do no better (rounding floor of a nearly singular system: stop, breakdown, no progress
        # on restart); never after maxiter iterations
        if rel <= tol or (rel <= self.residual_check and flag <= 0):
            return x
        if stop == "stagnated":
            why = f"stagnated after {its} iterations"
        elif flag < 0:
            why = f"broke down after {its} iterations (indefinite matrix or preconditioner)"
        elif flag > 0:
            why = f"did not converge in {its} iterations"
        else:
            why = f"stopped after {its} iterations"
        raise SingularMatrix(
            f"{name} {why}: relative residual {rel:.2e} (tolerance {tol:.0e}, residual check "
            f"{self.residual_check:.0e}), backward error {eta:.1e}; the stiffness matrix is singular or nearly so "
            "(a part of the model may move as a rigid body)")

    def _record(self, its, rel, t0):
        self.last_iterations = int(its)
        self.last_residual = float(rel)
        self.last_solve_time_s = time.perf_counter() - t0
        self.iterations.append(self.last_iterations)
        self.solve_times_s.append(self.last_solve_time_s)
