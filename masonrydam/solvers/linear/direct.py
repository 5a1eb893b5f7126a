"""Linear solvers behind one interface: sparse direct (PARDISO, SuperLU) and AMG-preconditioned Krylov.

Backends: ``"pardiso"`` (Intel MKL PARDISO through pypardiso, supernodal LU, pinned to one thread for
reproducibility) and
``"superlu"`` (scipy's SuperLU). ``"auto"`` picks pardiso where it can be loaded: on the
benchmark in ``benchmarks/bench_linear_solve.py`` it factorizes a 197 000-DOF jointed wall in 1.3 s
against 4.5 s for SuperLU with COLAMD ordering, and is the fastest at every size measured (no
crossover; figures in docs/performance.md). Tangents with sliding joints are
non-symmetric, so both backends are used as general (unsymmetric) LU solvers.

Singularity is never silent: SuperLU raises on an exactly singular matrix and PARDISO reports
perturbed pivots; both are turned into :class:`SingularMatrix`, and every solve is checked for
non-finite entries and a large relative residual.

For a symmetric positive definite matrix that is solved very many times (the dynamic solver's
all-stick effective matrix) :class:`SymmetricFactorization` adds a sparse ``L D L^T`` (SuperLU's
symmetric mode) whose substitutions are numba kernels (:mod:`.ldlt_kernels`), 2-3x faster per solve
than PARDISO's solve phase at 7 500 equations.

Iterative backend ``"amg"``: :class:`~masonrydam.solvers.linear.iterative.AMGSolver`, smoothed-aggregation
algebraic multigrid (pyamg) with the rigid-body near-nullspace as the preconditioner of CG (or of
FGMRES for a non-symmetric tangent), solved to a relative residual of 1e-10. :func:`make_solver`
returns a :class:`Factorization` or an ``AMGSolver`` behind the same interface (``solve(b)``, ``K``,
``backend``). ``"auto"`` takes AMG for 3D models of ``AUTO_ITERATIVE_MIN_DOF`` (50 000) equations or
more, from the crossover measured by ``benchmarks/bench_solvers_3d.py`` (docs/performance.md, "Linear
solvers in 3D: direct vs AMG"), and a direct solver otherwise. 2D models always get a direct
solver: 2D fill grows slowly (PARDISO factorizes the 197 000-DOF wall in 1.3 s), and a full run of
the default scene takes 3.4x longer with AMG.
"""
from __future__ import annotations

import ctypes
import glob
import os
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .common import SingularMatrix  # noqa: F401  (raised here; importable from this module too)
from .iterative import AMGSolver, is_symmetric
from .ldlt_kernels import (ldlt_solve_block, ldlt_solve_block_supernodal, ldlt_solve_vector, supernode_panels,
                           supernode_partition)

LINEAR_SOLVERS = ("auto", "pardiso", "superlu", "amg")
DIRECT_SOLVERS = ("pardiso", "superlu")

#: "auto" uses the AMG solver for 3D models with at least this many equations (free DOFs), a direct
#: solver below. Measured (docs/performance.md, "Linear solvers in 3D: direct vs AMG"): for one
#: factorization + one solve AMG overtakes PARDISO at 7 000-12 000 equations on elastic and tied-joint
#: tangents, but a nonlinear tangent (sliding and open joints) needs 3-6x more iterations and only
#: breaks even at ~45 000, and a reused factorization is worth 3.5-6.5 AMG solves at 27 000-52 000;
#: from 50 000 on AMG wins on every tangent measured (1.9-16x, with 2.7-6.7x less peak memory).
AUTO_ITERATIVE_MIN_DOF = 50_000




_PARDISO_OK: bool | None = None


def _point_pypardiso_at_mkl() -> None:
    """Tell pypardiso where MKL's ``libmkl_rt`` is (``PYPARDISO_MKL_RT``) when it sits where pip puts
    it, ``sys.prefix/lib``: on import pypardiso otherwise runs ``ctypes.util.find_library`` and a
    recursive glob over ``sys.prefix/lib*``, site-packages included, which took 0.24 s of the default
    scene's start-up (``python -X importtime``)."""
    if "PYPARDISO_MKL_RT" in os.environ:
        return
    found = sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")), key=len)
    if found:
        os.environ["PYPARDISO_MKL_RT"] = found[0]


def _new_pardiso(mtype: int = 11):
    """A PyPardisoSolver; the MKL library path found by the first one is reused (finding it costs
    about 0.15 s per solver otherwise)."""
    _point_pypardiso_at_mkl()
    # an optional, platform-bound dependency (MKL), loaded once the MKL path is set: 0.4 s, not at import
    import pypardiso

    ps = pypardiso.PyPardisoSolver(mtype=mtype)
    # one MKL thread: multithreaded PARDISO is not bitwise reproducible, and a nonlinear joint
    # analysis amplifies last-bit differences into different slip/open paths. Kernels and runs
    # must be deterministic (docs/architecture.md).
    try:
        ps.libmkl.MKL_Set_Num_Threads(ctypes.c_int(1))
    except AttributeError:  # pragma: no cover - very old MKL
        pass
    name = getattr(ps.libmkl, "_name", None)
    if name and "PYPARDISO_MKL_RT" not in os.environ:
        os.environ["PYPARDISO_MKL_RT"] = name
    return ps


def _pardiso_available() -> bool:
    global _PARDISO_OK
    if _PARDISO_OK is None:
        try:
            _new_pardiso()
            _PARDISO_OK = True
        except Exception:
            _PARDISO_OK = False
    return _PARDISO_OK


_PYAMG_OK: bool | None = None


def _pyamg_available() -> bool:
    global _PYAMG_OK
    if _PYAMG_OK is None:
        try:
            # whether pyamg is installed, asked only where a 3D model might take the AMG solver
            import pyamg  # noqa: F401

            _PYAMG_OK = True
        except ImportError:
            _PYAMG_OK = False
    return _PYAMG_OK


def resolve_backend(name: str, n_dof: int | None = None, dim: int | None = None) -> str:
    """The backend that ``name`` stands for: ``"auto"`` -> ``"amg"`` for a 3D model (``dim == 3``)
    with ``n_dof >= AUTO_ITERATIVE_MIN_DOF`` equations (when pyamg is installed), else ``"pardiso"``
    where it can be loaded, else ``"superlu"``. Without ``n_dof`` and ``dim``, ``"auto"`` is a direct
    solver."""
    if name not in LINEAR_SOLVERS:
        raise ValueError(f"unknown linear solver {name!r}; use one of {LINEAR_SOLVERS}")
    if name == "auto":
        if dim == 3 and n_dof is not None and n_dof >= AUTO_ITERATIVE_MIN_DOF and _pyamg_available():
            return "amg"
        return "pardiso" if _pardiso_available() else "superlu"
    if name == "amg" and not _pyamg_available():
        raise ValueError("linear solver 'amg' needs the pyamg package (pip install pyamg)")
    return name


def make_solver(K: sp.csr_matrix, backend: str = "auto", near_nullspace: np.ndarray | None = None,
                residual_check: float = 1e-6, *, dim: int | None = None, dof_coords: np.ndarray | None = None,
                dof_nodes: np.ndarray | None = None, **amg_options):
    """A linear solver for K behind one interface: ``solve(b)``, ``K``, ``backend``.

    backend: one of ``LINEAR_SOLVERS``; ``"auto"`` is resolved by :func:`resolve_backend` with the
    size of K and ``dim`` (or, without ``dim``, the dimension implied by the near-nullspace: 3
    columns 2D, 6 columns 3D). near_nullspace (n, k), dof_coords (n, dim) and dof_nodes (n,): the
    rigid-body modes (``masonrydam.solvers.linear.iterative.rigid_body_modes``), the position and the node of
    each row, used by ``"amg"`` only (the positions find the node pairs of interfaces); amg_options:
    keyword arguments of :class:`~masonrydam.solvers.linear.iterative.AMGSolver` (``tol``, ``maxiter``, ...).

    Returns a :class:`Factorization` (``"pardiso"``, ``"superlu"``) or an ``AMGSolver`` (``"amg"``).
    ``"auto"`` never picks AMG without a near-nullspace (with the constant vector alone it converges
    badly on elasticity).
    """
    if dim is None and near_nullspace is not None:
        dim = {3: 2, 6: 3}.get(np.shape(near_nullspace)[1] if np.ndim(near_nullspace) == 2 else 0)
    name = resolve_backend(backend, n_dof=K.shape[0], dim=dim if near_nullspace is not None else None)
    if name == "amg":
        return AMGSolver(K, near_nullspace, residual_check, dof_coords=dof_coords, dof_nodes=dof_nodes, **amg_options)
    return Factorization(K, name, residual_check)


def _check_matrix_finite(K: sp.spmatrix) -> None:
    if not np.isfinite(K.data).all():
        raise SingularMatrix("stiffness matrix contains NaN or infinity")


def _check_solution(K: sp.spmatrix, x: np.ndarray, b: np.ndarray, residual_check: float) -> None:
    """Raise SingularMatrix when the solution of ``K x = b`` is not finite or its relative residual
    exceeds ``residual_check``."""
    if not np.isfinite(x).all():
        raise SingularMatrix("solution contains NaN or infinity")
    nb = np.linalg.norm(b)
    if nb > 0:
        res = np.linalg.norm(K @ x - b) / nb
        if res > residual_check:
            raise SingularMatrix(f"relative residual of the linear solve is {res:.2e}")


class Factorization:
    """LU factorization of a square CSR matrix; ``solve(b)`` returns x with K x = b.

    residual_check: relative residual above which the solution is declared singular.
    """

    def __init__(self, K: sp.csr_matrix, backend: str = "auto", residual_check: float = 1e-6):
        if backend not in DIRECT_SOLVERS and backend != "auto":
            if backend in LINEAR_SOLVERS:
                raise ValueError(f"Factorization is a direct solver ({DIRECT_SOLVERS}); "
                                 f"use make_solver() for {backend!r}")
            resolve_backend(backend)  # raises: unknown name
        self.backend = resolve_backend(backend)
        self.K = K
        self.residual_check = residual_check
        self.analyses = 1  # symbolic analyses (fill-reducing order, scaling): see refactorize
        _check_matrix_finite(K)
        if self.backend == "superlu":
            try:
                self._lu = spla.splu(K.tocsc(), permc_spec="COLAMD")  # MMD_AT_PLUS_A took minutes at 40k DOF (docs/performance.md)
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise SingularMatrix(str(exc)) from None
        else:
            self._ps = _new_pardiso(mtype=11)
            self._ps.set_statistical_info_off()
            self._Kcopy = K.copy()
            if not np.diff(K.indptr).all():
                raise SingularMatrix("stiffness matrix has an empty row")
            self._ps.factorize(self._Kcopy)
            if self._ps.get_iparm(14) > 0:
                raise SingularMatrix(f"{self._ps.get_iparm(14)} pivot(s) perturbed during factorization")

    def refactorize(self, K: sp.csr_matrix) -> bool:
        """Factorize ``K``, a matrix with the same sparsity pattern as the one factorized, reusing the
        symbolic analysis (PARDISO phase 22: numerical factorization with the kept fill-reducing order,
        scaling and matching). Returns False, changing nothing, where that cannot be done: another
        backend (scipy's SuperLU always analyses), another pattern. A factorization that perturbs
        pivots (the kept matching no longer fits the values) is redone with a new analysis (phase 12);
        ``analyses`` counts the analyses of this object.

        Why: a Newton iteration of a jointed model changes only the joint entries of the tangent; on the
        default scene (general path) a refactorization took 4.3 ms against 10-12 ms for a factorization
        with its analysis (docs/performance.md, "Output in blocks and static refactorization")."""
        if self.backend != "pardiso" or K.shape != self.K.shape or K.nnz != self._Kcopy.nnz \
                or not (np.array_equal(K.indptr, self._Kcopy.indptr) and np.array_equal(K.indices, self._Kcopy.indices)):
            return False
        _check_matrix_finite(K)
        self.K = K
        self._Kcopy.data[:] = K.data
        ps = self._ps
        ps.factorized_A = ""  # until phase 22 has succeeded nothing counts as factorized (a hash that never matches)
        try:
            ps.set_phase(22)
            ps._call_pardiso(self._Kcopy, np.zeros((K.shape[0], 1)))
            ps.factorized_A = self._Kcopy  # pypardiso's record of what it factorized: solve() takes phase 33
        except AttributeError:  # pragma: no cover - a pypardiso without these (private) calls: new analysis
            ps.factorize(self._Kcopy)
            self.analyses += 1
        if ps.get_iparm(14) > 0:  # perturbed pivots: analyse again with the current values
            ps.factorize(self._Kcopy)
            self.analyses += 1
            if ps.get_iparm(14) > 0:
                raise SingularMatrix(f"{ps.get_iparm(14)} pivot(s) perturbed during factorization")
        return True

    def __del__(self):
        ps = getattr(self, "_ps", None)
        if ps is not None:
            try:
                ps.free_memory(everything=True)
            except Exception:
                pass

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.backend == "superlu":
            x = self._lu.solve(b)
        else:
            # no iterative refinement (iparm(8) = 0: PARDISO then refines only where it perturbed pivots, and such
            # a factorization is not kept, see refactorize). Why: its two default steps (a product with K and a
            # substitution each) doubled the solve, 1.5 ms against 0.7 ms on the Eindhoven wall's 5 452 equations,
            # for a relative residual of 7.3e-12 instead of 7.7e-12 (the solution is checked below in any case).
            # Set before each solve: the first call of a new solver object fills iparm with PARDISO's defaults
            self._ps.set_iparm(8, 0)
            x = self._ps.solve(self._Kcopy, b)
        _check_solution(self.K, x, b, self.residual_check)
        return x


#: a block of right-hand sides is solved by supernodes (dense products through BLAS,
#: :func:`.ldlt_kernels.ldlt_solve_block_supernodal`) when the factor has at least this many entries:
#: there the entry-by-entry substitution streams the block through memory once per entry (3D dam,
#: 21.8 million entries: 3.5 instead of 7.4 ms a right-hand side in blocks of 256); a smaller factor
#: keeps the entry-by-entry kernel (the Koyna section's 0.3 million: its results stay bit for bit)
SUPERNODAL_MIN_FACTOR = 2_000_000
#: widest supernode of that solve (wider fundamental supernodes are cut: their diagonal blocks then
#: go through the dense products too; 16 to 128 measured within 10 % of each other)
SUPERNODE_MAX_WIDTH = 64


def _strictly_lower(L: sp.csc_matrix) -> sp.csc_matrix:
    """The strictly lower part of a lower triangular CSC matrix, indices sorted: what
    ``sp.tril(L, -1, format="csc")`` gives, without its COO round trip (1.95 s against 0.2 s for the
    21.8 million entries of the 3D dam's factor at element_size 6)."""
    L = L.tocsc()
    n = L.shape[1]
    counts = np.diff(L.indptr)
    col = np.repeat(np.arange(n, dtype=L.indices.dtype), counts)
    keep = L.indices > col
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(col[keep], minlength=n), out=indptr[1:])
    out = sp.csc_matrix((L.data[keep], L.indices[keep], indptr), shape=L.shape)
    out.sort_indices()
    return out


class SymmetricFactorization:
    """Sparse ``L D L^T`` factorization of a symmetric positive definite CSR matrix, with fast
    substitutions; the same interface as :class:`Factorization` (``solve(b)``, ``K``, ``backend``).

    For the matrices a time integration solves hundreds of thousands of times (the effective matrix
    of a step size, :mod:`.dynamic`): the factorization is SuperLU's (scipy) in its symmetric mode, a
    minimum-degree order of ``A + A^T`` and no row pivoting (``diag_pivot_thresh = 0``; then
    ``U = D L^T``); the substitutions are written out in numba (:mod:`.ldlt_kernels`) because they
    are where such a run spends its time: on the 7 464-equation Koyna matrix one solve takes 0.6 ms
    against 2-5 ms for PARDISO's (single-threaded) and 1.1 ms for SuperLU's own.

    Raises :class:`SingularMatrix` (NaN or infinity in the matrix, an empty row, a pivot that is not
    positive: the matrix is not positive definite) or ``ValueError`` (not symmetric, or SuperLU
    pivoted after all); the caller then falls back to :class:`Factorization`. Without pivoting,
    ``L D L^T`` of a positive definite matrix is backward stable, like Cholesky (Higham, *Accuracy and
    Stability of Numerical Algorithms*, 2nd ed. 2002, Thm. 10.3 and sec. 10.4), so each solve is
    checked for non-finite entries and only the first one, as a test of the whole chain, for its
    relative residual.
    """

    backend = "ldlt"

    def __init__(self, K: sp.csr_matrix, residual_check: float = 1e-6):
        self._vector, self._block = ldlt_solve_vector, ldlt_solve_block
        self.K = K
        self.residual_check = residual_check
        _check_matrix_finite(K)
        if not np.diff(K.indptr).all():
            raise SingularMatrix("stiffness matrix has an empty row")
        if not is_symmetric(K):
            raise ValueError("SymmetricFactorization needs a symmetric matrix")
        try:
            lu = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
        except RuntimeError as exc:
            raise SingularMatrix(str(exc)) from None
        if not np.array_equal(lu.perm_r, lu.perm_c):
            raise ValueError("SuperLU pivoted rows: no L D L^T factorization")
        d = np.ascontiguousarray(lu.U.diagonal())
        if not (d > 0.0).all():
            raise SingularMatrix(f"{int((d <= 0.0).sum())} pivot(s) of the L D L^T factorization are not "
                                 "positive: the matrix is not positive definite")
        L = _strictly_lower(lu.L)
        self._Lp = L.indptr.astype(np.int64)
        self._Li = L.indices.astype(np.int32)
        self._Lx = np.ascontiguousarray(L.data)
        self._d = d
        # superlu: row i of A is row perm_r[i] of the factorized matrix; perm lists A's rows in factor order
        self._perm = np.empty(K.shape[0], dtype=np.int64)
        self._perm[lu.perm_r] = np.arange(K.shape[0])
        self.nnz_factor = int(L.nnz + K.shape[0])
        self._checked = False
        self._w = np.empty(K.shape[0])
        self._supernodes = None  # (starts, offsets, panels), built at the first large block solve

    @property
    def factor_arrays(self):
        """``(Lp, Li, Lx, d, perm)``: the factor as :func:`.ldlt_kernels.ldlt_solve_vector` takes it, for kernels
        that substitute inside a compiled loop."""
        return self._Lp, self._Li, self._Lx, self._d, self._perm

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=np.float64)
        if b.ndim == 1:
            x = np.empty_like(b)
            st = self._vector(self._Lp, self._Li, self._Lx, self._d, self._perm, np.ascontiguousarray(b), x, self._w)
        elif self.nnz_factor >= SUPERNODAL_MIN_FACTOR:
            if self._supernodes is None:
                starts = supernode_partition(self._Lp, self._Li, SUPERNODE_MAX_WIDTH)
                self._supernodes = (starts, *supernode_panels(self._Lp, self._Lx, starts))
            B = np.ascontiguousarray(b)
            x = np.empty_like(B)
            st = ldlt_solve_block_supernodal(self._Lp, self._Li, self._Lx, self._d, self._perm, *self._supernodes, B,
                                             x, np.empty_like(B), np.empty(B.size))
        else:
            B = np.ascontiguousarray(b)
            x = np.empty_like(B)
            st = self._block(self._Lp, self._Li, self._Lx, self._d, self._perm, B, x, np.empty_like(B))
        if st != 0:
            raise SingularMatrix("solution contains NaN or infinity")
        if not self._checked:
            _check_solution(self.K, x, b, self.residual_check)
            self._checked = True
        return x
