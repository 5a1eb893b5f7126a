"""Joint-space Newton: the implicit step condensed on the relative displacements of the nonlinear joints.

:class:`JointSpace` holds, for one step size, the joint operator ``B`` (m, n_dof) with ``m`` = points x dim of
the nonlinear joint sets (:func:`joint_operator`, :func:`joint_space_size`), the tributary areas (m2) and the
flexibility ``S = B K_ref^-1 B^T`` (m, m), m/N, of the all-stick effective matrix (dense up to
:data:`JOINT_SPACE_MAX` unknowns, else :class:`FlexibilityColumns` computed as steps need them), and solves a
step's joint equations ``F(delta) = delta - delta_y + S (q(delta) - q_n) = 0`` (relative displacements in m)
with small dense LU factorizations of the active components, then recovers the displacements (n_dof,) m. The
flexibility formulation of contact problems: Francavilla & Zienkiewicz (1975); the joint law and ``B``:
Tzamtzis & Asteris (eqs. 1-6, 10, 11).

Theory: docs/dynamics.md, section "The joint-space step in equations" (under "Fast path").
"""
from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
from scipy.linalg.lapack import dgetrf

from ...errors import STATUS_NAN, STATUS_OK
from ...materials.joint_laws import RESULT_OPEN
from ..linear.dense_lu import STATUS_SINGULAR
from ..linear.common import SingularMatrix
from . import step_kernel
from .signals import stop_signals_held
from .kernels import (active_components, add_flexibility_product, apply_correction, capacitance_assemble,
                                  capacitance_update_solve, condensed_residual, joint_points_evaluate,
                                  joint_space_correction, joint_space_reevaluate_points, state_key,
                                  subtract_columns_product)

#: largest number of joint components (points x dim) condensed by ``joint_space = "auto"``: the dense
#: flexibility takes 8 m^2 bytes (288 MB at 6 000) and m substitutions to set up
JOINT_SPACE_MAX = 6000
#: Newton iterations in joint space before the initial-stiffness iterations
MAX_JOINT_SPACE_ITERATIONS = 25
#: iterations with the initial (elastic) stiffness at every point that follow a Newton phase that did
#: not converge: a stress-transfer fixed point (Zienkiewicz, Valliappan & King 1968) that needs no
#: factorization, converges linearly and does not cycle
MAX_INITIAL_STIFFNESS_ITERATIONS = 60
#: the same when the step can still be halved instead
SPLIT_INITIAL_STIFFNESS_ITERATIONS = 10
#: state changes of a point within a step after which it is held sticking until the others converge
FLIPS_BEFORE_HOLD = 3
#: releases of held points after which Newton gets a fresh budget of MAX_JOINT_SPACE_ITERATIONS (see _solve_step)
FRESH_BUDGET_RELEASES = 3
#: a point that has changed state this many times in a step after its bond broke in one of the step's iterates
#: (it opened: the cohesion is gone) while its committed bond is intact gets its bond latched broken for the
#: rest of the step instead of being held (see :meth:`JointSpace._solve_step`); None: never
FLIPS_BEFORE_LATCH = FLIPS_BEFORE_HOLD
#: the reference LU of the capacitance matrix is updated (not refactorized) while at most
#: max(UPDATE_MIN_CHANGES, (rows of the reference + current rows) / UPDATE_CHANGE_FRACTION) rows changed:
#: an update costs about 2 |D| n^2 against 2/3 n^3 for a new LU
UPDATE_MIN_CHANGES = 4
UPDATE_CHANGE_FRACTION = 40
#: step lengths tried by the backtracking line search, in order
LINE_SEARCH_STEPS = (1.0, 0.5, 0.25)
#: columns of ``K_ref^-1 B^T`` computed per multi-right-hand-side substitution while setting up S
_COLUMN_BLOCK = 256
#: above JOINT_SPACE_MAX joint unknowns the columns of S are computed when an iteration first needs
#: them (the components that slide or open, and those whose force changed) and kept in a store of at
#: most this many bytes (8 m bytes a column); see :class:`FlexibilityColumns`
FLEXIBILITY_MEMORY_MAX = 2 * 2**30
#: a fetch of fewer columns than this is filled up to it with neighbours (not yet stored) of the
#: columns asked for (:meth:`FlexibilityColumns._neighbours`): a block of 32 costs about what 4 do
#: (the substitution is bound by reading the factor); 128 gave no gain on the 8 x 4 m wall
PREFETCH_COLUMNS = 32
#: the columns ``X = K_ref^-1 B_f^T`` (n_eq, m) of the set-up are kept (as ``XT``, 8 n_eq m bytes) when
#: they take at most this many bytes: then a converged step recovers its displacements as
#: ``u = y - X dq`` from the few nonzero entries of ``dq`` instead of a second substitution
RECOVERY_MEMORY_MAX = 256 * 2**20
#: ... while ``dq`` has at most this many nonzero entries per ``nnz(L) / n_eq`` of the factor: a column
#: costs ``2 n_eq`` flops streamed from memory, a substitution ``4 nnz(L)`` indexed ones. On the Koyna
#: matrix (n_eq = 7 464, nnz(L) / n_eq = 41) a column took about 6 us and a substitution 0.31 ms (about
#: 50 columns; benchmarks/bench_koyna_seismic.py)
RECOVERY_COLUMNS_PER_FILL = 1.5
#: ... and at least this many (on a small model the columns stay in cache and a substitution costs mostly
#: its call; on Koyna this floor applies: 1.5 x 41 = 61 < 64)
RECOVERY_COLUMNS_MIN = 64


#: a pivot of the capacitance LU below this fraction of max |J| is a singular matrix
SINGULAR_PIVOT = 1e-14
#: a step (dynamic or static) is solved by the compiled kernel (:mod:`.step_kernel`) where it applies (every
#: column of the flexibility stored, an ``L D L^T`` reference factorization); False: always the Python loop of
#: :meth:`JointSpace._solve_step` (the reference the kernel is tested against)
COMPILED_STEP = True
#: which static joint spaces take the compiled kernel: "cached" those of a run in which it needs no compiling
#: (:func:`.step_kernel.compiled_already`: a dynamic stage compiled it, now or in an earlier run), "always" every
#: one, "never" none (the Python loop, which can be stopped between its iterations). Why not always: a
#: static-only scene would compile it on its first run, 8 s of the default scene's first run on the 2-core AMD
#: EPYC (27.7 -> 36.0 s), for a saving of about 1 ms a joint-space iteration (0.1-0.15 s of its warm runs,
#: docs/performance.md)
STATIC_COMPILED_STEP = "cached"


def capacitance_lu(ST, slot, rows, qt):
    """``(status, J, piv)``: LU factors of the capacitance matrix ``I + Qt_a S_:a`` of the active
    components ``rows`` (see :func:`.kernels.capacitance_assemble`), in ``J`` (na, na),
    Fortran order, with the 0-based row swaps ``piv`` (na,) int64 in LAPACK's order, for
    :func:`.kernels.joint_space_correction`.

    The factorization is LAPACK's ``dgetrf`` (partial pivoting; Golub & Van Loan 2013, Alg. 3.4.1),
    not a loop written out in numba: it is blocked and about 9x faster at the sizes met here (0.29 ms
    against 2.7 ms at na = 200 on one core). The dynamic solver pins BLAS to one thread while it
    runs, which keeps it bitwise reproducible (with two threads OpenBLAS gave different last bits and
    was slower). status: STATUS_OK, STATUS_NAN, or STATUS_SINGULAR (a pivot below
    :data:`SINGULAR_PIVOT` x max |J|)."""
    na = rows.shape[0]
    J = np.empty((na, na), order="F")
    scale = np.zeros(1)
    st = capacitance_assemble(ST, slot, rows, qt, J, scale)
    if st != STATUS_OK:
        return st, J, np.zeros(na, dtype=np.int64)
    J, piv, info = dgetrf(J, overwrite_a=1)
    piv = piv.astype(np.int64)
    if info < 0:  # pragma: no cover - an argument error would be a bug here
        raise ValueError(f"dgetrf: illegal argument {-info}")
    # J was finite on entry (checked while assembling), so an overflow in the elimination shows in the
    # pivots; anything else non-finite is caught by the correction kernels' checks of their results
    pivots = np.abs(np.diagonal(J))
    if not np.isfinite(pivots).all():
        return STATUS_NAN, J, piv
    if info > 0 or not (pivots.min(initial=np.inf) > SINGULAR_PIVOT * scale[0]):
        return STATUS_SINGULAR, J, piv
    return STATUS_OK, J, piv


def joint_space_size(model) -> int:
    """Number of joint unknowns ``m`` (points x dim) of the nonlinear joint sets of ``model``."""
    return sum(g.n_elem * g.nip * model.dim for g in model.igroups if g.nonlinear)


def lazy_flexibility(m: int) -> bool:
    """Whether the flexibility of ``m`` joint unknowns is computed column by column as iterations need it
    (above :data:`JOINT_SPACE_MAX`) rather than set up dense at once."""
    return m > JOINT_SPACE_MAX


def joint_operator(model) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray, np.ndarray]:
    """``(B, weight, params_table, param_index)`` of the nonlinear joint sets of ``model``.

    B : CSR (m, n_dof): local relative displacement ``delta = B u`` (m) at every point, rows
        ``(point * dim + component)``, points in group order then element-major (the order of the
        groups' ``(n_elem, nip)`` state arrays), components ``[s1, (s2,) n]``; entries
        ``+-N_a(xi_ip) R[c, k]`` (top +, bottom -; Tzamtzis & Asteris eqs. 4-6, 10, as in
        :func:`~masonrydam.elements.interface.interface_evaluate`).
    weight : (P,) tributary area ``j w h`` (m^2; 2D: length x thickness).
    params_table : (n_sets, N_JOINT_PARAMS), param_index : (P,) int64 — the law parameters per point.
    """
    dim = model.dim
    rows, cols, vals, weights, tables, index = [], [], [], [], [], []
    off_row, off_tab = 0, 0
    for g in (g for g in model.igroups if g.nonlinear):
        ne, nip, ns = g.n_elem, g.nip, g.N.shape[1]
        # coef[e, ip, c, a, k] = N[ip, a] * R[e, ip, c, k]
        coef = g.N[None, :, None, :, None] * g.frame[:, :, :, None, :]
        r = off_row + np.arange(ne * nip * dim).reshape(ne, nip, dim)
        r = np.broadcast_to(r[:, :, :, None, None], coef.shape)
        bot = g.conn[:, :ns][:, None, None, :, None] * dim + np.arange(dim)[None, None, None, None, :]
        top = g.conn[:, ns:][:, None, None, :, None] * dim + np.arange(dim)[None, None, None, None, :]
        bot = np.broadcast_to(bot, coef.shape)
        top = np.broadcast_to(top, coef.shape)
        rows += [r.ravel(), r.ravel()]
        cols += [top.ravel(), bot.ravel()]
        vals += [coef.ravel(), -coef.ravel()]
        weights.append((g.jw * g.thickness[:, None]).ravel())
        tables.append(g.params_table)
        index.append(np.repeat(g.param_index, nip) + off_tab)
        off_row += ne * nip * dim
        off_tab += len(g.params_table)
    B = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(off_row, model.n_dof))
    B.sum_duplicates()
    B.eliminate_zeros()
    return (B, np.ascontiguousarray(np.concatenate(weights)), np.ascontiguousarray(np.concatenate(tables)),
            np.ascontiguousarray(np.concatenate(index), dtype=np.int64))


#: the compiled step's arguments where there is no reference LU (a Fortran-order matrix, as getrf's)
_NO_LU = np.zeros((2, 2), order="F")
_NO_PIVOTS = np.zeros(0, dtype=np.int64)
_NO_ROWS = np.zeros(0, dtype=np.int64)


class ColumnStoreFull(Exception):
    """A step needs more columns of the joint flexibility than :class:`FlexibilityColumns` can hold."""


class FlexibilityColumns:
    """Columns of the joint flexibility ``S = B_f K_ref^-1 B_f^T`` (m x m, m/N), as rows of ``ST``
    (capacity, m) with ``slot`` (m,) int64 (column ``j`` is ``ST[slot[j]]``, ``-1``: not stored; the
    layout of :mod:`.kernels`).

    Why: the dense S takes ``8 m^2`` bytes and ``m`` substitutions to set up (4.7 GB and about 24 000
    substitutions for the 3D dam of ``examples/dam_3d_gravity.toml``), but an iteration reads only
    the columns of the components that slide or open and of those whose joint force changed: a
    step whose joints all stick reads none. With ``lazy`` (the joint space's choice above
    :data:`JOINT_SPACE_MAX` unknowns) a column is computed (multi-right-hand-side substitutions in
    blocks of :data:`_COLUMN_BLOCK`) the first time :meth:`ensure` asks for it, and kept across
    steps (``K_ref`` does not change); when the store is full, the columns used longest ago (not in
    the current step, see :meth:`new_step`) make room, and a step that needs more columns than the
    store holds raises :class:`ColumnStoreFull`.

    fact : ``solve(b)`` for ``K_ref`` (a vector or an (n_eq, k) block); Bf : CSR (m, n_eq) and
    Bf_T : CSC (n_eq, m), ``B`` on the free DOFs; capacity : columns held when ``lazy``; not
    ``lazy``: all ``m`` columns, computed at once, and XT : None, or an (m, n_eq) array that receives
    the columns of ``X = K_ref^-1 B_f^T`` as its rows.
    """

    def __init__(self, fact, Bf, Bf_T, capacity, lazy, XT=None):
        m = Bf.shape[0]
        self.fact, self.Bf, self.Bf_T, self.m = fact, Bf, Bf_T, m
        self.capacity = capacity = int(min(capacity, m)) if lazy else m
        self.lazy = lazy
        self.ST = np.empty((capacity, m))
        self.slot = np.full(m, -1, dtype=np.int64)
        #: column held by each row of ST (-1: free), and the step that last used it
        self.owner = np.full(capacity, -1, dtype=np.int64)
        self.stamp = np.zeros(capacity, dtype=np.int64)
        self.epoch = 0
        self.n_free = capacity
        #: columns computed by :meth:`ensure` (lazy store; statistics), and the seconds that took
        self.computed = 0
        self.seconds = 0.0
        if not self.lazy:
            self._compute(np.arange(m, dtype=np.int64), np.arange(m, dtype=np.int64), XT)

    def _compute(self, cols, slots, XT=None):
        """Columns ``cols`` of S into the rows ``slots`` of ST (and of X into XT's rows ``cols``)."""
        n_eq = self.Bf_T.shape[0]
        for k0 in range(0, len(cols), _COLUMN_BLOCK):
            c, r = cols[k0:k0 + _COLUMN_BLOCK], slots[k0:k0 + _COLUMN_BLOCK]
            X = np.asarray(self.fact.solve(self.Bf_T[:, c].toarray())).reshape(n_eq, len(c))
            self.ST[r] = (self.Bf @ X).T
            if XT is not None:
                XT[c] = X.T
        self.slot[cols] = slots
        self.owner[slots] = cols

    def new_step(self):
        """Columns used from now on belong to a new step (those of earlier steps may be evicted)."""
        self.epoch += 1

    def ensure(self, cols):
        """Make the columns ``cols`` (int array, any order, repeats allowed) available in ``ST``;
        raises :class:`ColumnStoreFull` when the current step would need more than ``capacity``."""
        if not self.lazy or len(cols) == 0:
            return
        slots = self.slot[cols]
        self.stamp[slots[slots >= 0]] = self.epoch
        missing = np.unique(cols[slots < 0])
        if len(missing) == 0:
            return
        if len(missing) > self.n_free:
            # evict the columns used longest ago, none of the current step's
            old = np.flatnonzero((self.owner >= 0) & (self.stamp < self.epoch))
            need = len(missing) - self.n_free
            if len(old) < need:
                raise ColumnStoreFull(f"the step needs more than {self.capacity} columns of the joint flexibility "
                                      f"(FLEXIBILITY_MEMORY_MAX = {FLEXIBILITY_MEMORY_MAX} bytes)")
            out = old[np.argsort(self.stamp[old], kind="stable")[:need]]
            self.slot[self.owner[out]] = -1
            self.owner[out] = -1
            self.n_free += need
        n_new = len(missing)
        extra = self._neighbours(missing, min(PREFETCH_COLUMNS, self.n_free) - n_new)
        cols_new = np.concatenate([missing, extra])
        free = np.flatnonzero(self.owner < 0)[:len(cols_new)]
        t0 = time.perf_counter()
        self._compute(cols_new, free)
        self.seconds += time.perf_counter() - t0
        self.computed += len(cols_new)
        self.stamp[free[:n_new]] = self.epoch
        self.stamp[free[n_new:]] = self.epoch - 1  # fetched ahead: evictable within this step
        self.n_free -= len(cols_new)

    def _neighbours(self, cols, count):
        """Up to ``count`` columns not stored, nearest first in the joint-point order to ``cols``: the
        points of a joint set are numbered along it, and a crack or a slip runs along a joint, so the
        next step tends to need the neighbours of the columns it needs now."""
        if count <= 0:
            return np.zeros(0, dtype=np.int64)
        offsets = np.stack([np.arange(1, PREFETCH_COLUMNS + 1), -np.arange(1, PREFETCH_COLUMNS + 1)], axis=1).ravel()
        cand = (cols[None, :] + offsets[:, None]).ravel()
        cand = cand[(cand >= 0) & (cand < self.m)]
        cand = cand[self.slot[cand] < 0]
        cand = cand[~np.isin(cand, cols)]
        _, first = np.unique(cand, return_index=True)
        return cand[np.sort(first)[:count]]


class JointSpace:
    """The condensed joint-space system of one reference factorization (one step size).

    model : the :class:`~masonrydam.assembly.model.Model` (constraints set); factorization : an object
    with ``solve(b)`` for ``K_ref`` on the free DOFs (a vector or an (n_eq, k) block) and, to allow the
    recovery from stored columns, ``nnz_factor`` (entries of its triangular factor);
    store_columns : keep ``X = K_ref^-1 B_f^T`` for the recovery of the displacements of a step (see
    :data:`RECOVERY_MEMORY_MAX`; the dynamic solver asks for it at the nominal step size only);
    column_memory_share : the store of flexibility columns above JOINT_SPACE_MAX unknowns takes at most
    this fraction of :data:`FLEXIBILITY_MEMORY_MAX` bytes.
    """

    def __init__(self, model, factorization, store_columns=True, column_memory_share=1.0, static=False):
        self.model = model
        #: a static stage's joint space: points flipping across the cohesion jump get their bond latched broken
        #: (:meth:`_bond_chatter`) and Newton a fresh budget after a release (:data:`FRESH_BUDGET_RELEASES`).
        #: Dynamic steps keep the hold-and-release of before: their inertia already regularises the step, and
        #: the latch would change the histories of cracking sections (the Koyna section at dt = 0.01 s: the
        #: energy its contact events create, -20 % of the largest term, became a +4 % loss)
        self.static = bool(static)
        #: called (no arguments) before every iteration of a step; it raises (``StepInterrupted``) where the run
        #: was asked to stop: the step is then abandoned with the groups' states untouched. None: never asked
        self.stop_check = None
        self.dim = dim = model.dim
        self.groups = [g for g in model.igroups if g.nonlinear]
        #: the joint law of the points: the one the joint-space kernels carry (``JointLaw.joint_space``, the
        #: Mohr-Coulomb law of Tzamtzis & Asteris; Model.joint_space_capable), None without points
        laws = list({id(g.joint_law): g.joint_law for g in self.groups}.values())
        if len(laws) > 1 or not all(law.joint_space for law in laws):
            raise ValueError(f"the joint-space kernels carry one law, not {[law.name for law in laws]}")
        self.law = laws[0] if laws else None
        self.B, self.weight, params, self.param_index = joint_operator(model)
        self.params_table = params.copy()  # own copy: the open-tangent factor is not used here
        self.m = m = self.B.shape[0]
        self.n_points = m // dim
        free = model.dofmap.free
        self.fact = factorization
        Bf_T = self.B[:, free].T.tocsc()  # (n_eq, m)
        n_eq = len(free)
        nnz_factor = getattr(factorization, "nnz_factor", 0)
        #: the store is dense (every column computed now) up to JOINT_SPACE_MAX unknowns, else lazy
        lazy = lazy_flexibility(m)
        capacity = max(1, int(column_memory_share * FLEXIBILITY_MEMORY_MAX) // (8 * m)) if lazy else m
        #: (m, n_eq) the transpose of X = K_ref^-1 B_f^T, or None (not kept: too big, not asked for, or a
        #: factorization that does not report its fill)
        self.XT = None
        #: largest number of nonzero entries of dq recovered from XT (above it: a substitution)
        self.recovery_columns_max = 0
        if store_columns and nnz_factor and not lazy and 8 * n_eq * m <= RECOVERY_MEMORY_MAX:
            self.XT = np.empty((m, n_eq))
            self.recovery_columns_max = max(RECOVERY_COLUMNS_MIN,
                                            int(RECOVERY_COLUMNS_PER_FILL * nnz_factor / max(n_eq, 1)))
        # columns of S = B_f K_ref^-1 B_f^T (K_ref is symmetric, so S is too; ST is kept as the
        # transpose anyway, so that nothing depends on it)
        self.columns = FlexibilityColumns(factorization, self.B[:, free].tocsr(), Bf_T, capacity, lazy, self.XT)
        self.ST, self.slot = self.columns.ST, self.columns.slot
        self._u_free = np.empty(n_eq)
        self.Bf_T = Bf_T.tocsr()
        P, ns = self.n_points, (self.law.state_size if self.law is not None else 0)
        self.base = np.zeros((P, ns))
        self.trial = np.zeros((P, ns))
        self.traction = np.zeros((P, dim))
        self.q = np.zeros((P, dim))
        self.qt = np.zeros((P, dim, dim))
        self.codes = np.zeros(P, dtype=np.int8)
        #: points held sticking in the current iteration (see solve_step), and none (the committed state)
        self.held = np.zeros(P, dtype=np.int8)
        self._none_held = np.zeros(P, dtype=np.int8)
        self.info = np.zeros(1, dtype=np.int64)
        self.F = np.zeros(m)
        self._err = np.zeros(1)
        self.step = np.zeros(m)
        self.J = np.zeros((0, 0))
        self.piv = np.zeros(0, dtype=np.int64)
        self.z = np.zeros(0)
        self._lu_key = None
        self._dq_last = None  # the converged q - q_n of the last step (an extrapolation of the next)
        self._ref = None  # (rows, qt rows) of the capacitance matrix whose LU is in self.J
        #: dense LU factorizations of capacitance matrices, and low-rank updates of them (statistics)
        self.factorizations = 0
        self.updates = 0
        #: points held sticking within a step because their state kept flipping (statistics)
        self.hold_events = 0
        #: points whose bond was latched broken within a step because they kept flipping across the cohesion
        #: jump (statistics; see _bond_chatter)
        self.bond_latches = 0
        #: releases of held points after which Newton started a fresh budget (a static step; statistics)
        self.fresh_budgets = 0
        #: converged steps whose displacements came from the stored columns, not a substitution (statistics)
        self.column_recoveries = 0
        #: the last step needed more columns of S than the store holds
        self.store_full = False
        # the consistent tangent of open points; the elastic stiffness [ks, (ks,) kn] of every point (Pa/m)
        k0 = np.zeros((P, dim))
        if self.law is not None:
            self.law.set_open_tangent(self.params_table, 0.0)
            k0 = self.law.elastic_stiffness(self.params_table[self.param_index], dim)
        #: (m,) N/m: elastic stiffness times area of every component (a displacement error to a force)
        self.wk = (k0 * self.weight[:, None]).ravel()
        #: steps solved by the compiled kernel (:mod:`.step_kernel`) and by the Python loop (statistics)
        self.compiled_steps = 0
        self.python_steps = 0
        #: :meth:`solve_step` runs the compiled kernel (:data:`COMPILED_STEP`), decided once: every column of the
        #: flexibility stored and an ``L D L^T`` reference factorization. A joint space never mixes the two codes,
        #: so the Python loop's LU key (``_lu_key``) is not kept by the compiled one
        self.compiled = (COMPILED_STEP and step_kernel.AVAILABLE and not self.columns.lazy
                         and self.law is not None and getattr(self.fact, "factor_arrays", None) is not None
                         and (not self.static or STATIC_COMPILED_STEP == "always"
                              or (STATIC_COMPILED_STEP == "cached" and step_kernel.compiled_already())))
        if self.compiled:
            self._prepare_kernel()

    def _prepare_kernel(self):
        """The arrays :func:`.step_kernel.joint_space_step` takes that do not change from step to step."""
        B, Bf_T, free = self.B, self.Bf_T, self.model.dofmap.free
        law = self.law
        # (codes,) bool: the law's state codes whose result state is open
        open_code = law.result_states_of(np.arange(len(law.result_state_map), dtype=np.int8)) == RESULT_OPEN
        self._kernel_args = (
            *self.fact.factor_arrays, B.indptr.astype(np.int64), B.indices.astype(np.int64), B.data,
            Bf_T.indptr.astype(np.int64), Bf_T.indices.astype(np.int64), Bf_T.data, np.asarray(free, dtype=np.int64),
            self.XT if self.XT is not None else np.zeros((0, len(free))), int(self.recovery_columns_max))
        self._open_code = open_code
        self._latch_column = int(law.bond_column) if (law.latches_bonds and law.bond_column is not None) else -1
        self._counts = np.zeros(step_kernel.N_COUNTS, dtype=np.int64)
        self._dq_out = np.zeros(self.m)
        self._err_out = np.zeros(1)
        # relative displacements at the step's start, of the iterate and of the start guess: flat, and (P, dim)
        # views of the same memory
        work = [np.zeros((self.n_points, self.dim)) for _ in range(3)]
        self._work = tuple(x for w in work for x in (w.reshape(-1), w))

    # ------------------------------------------------------------------------------------------
    def _load_base(self):
        k = 0
        for g in self.groups:
            n = g.n_elem * g.nip
            self.base[k:k + n] = g.state_base.reshape(n, -1)
            k += n

    def _store_latched_bonds(self):
        k = 0
        for g in self.groups:
            n = g.n_elem * g.nip
            self.law.keep_latched_bonds(g.state_base.reshape(n, -1), self.base[k:k + n])
            k += n

    def _evaluate(self, delta, delta_y, q_n):
        """The joint law at ``delta`` (into the point arrays), the condensed residual ``self.F`` there and
        its force error ``|W D0 F|`` (N), which is returned."""
        self._raise_on(joint_points_evaluate(
            self.params_table, self.param_index, self.weight, delta.reshape(-1, self.dim), self.base, self.trial,
            self.traction, self.q, self.qt, self.codes, self.info, self.held))
        if self.columns.lazy:  # the columns of the forces that changed (and marked as used in this step)
            self.columns.ensure(np.flatnonzero((self.q != q_n).ravel()))
        self._raise_on(condensed_residual(delta, delta_y, self.q, q_n, self.ST, self.slot, self.wk, self.F,
                                          self._err, self.info))
        return float(self._err[0])

    def _reevaluate(self, points, delta):
        """The law again at ``points`` only (their held flag changed; ``delta`` unchanged), ``self.F`` updated
        by the change of their joint forces; returns the force error (see :meth:`_evaluate`)."""
        points = points.astype(np.int64)
        self.columns.ensure((points[:, None] * self.dim + np.arange(self.dim)).ravel())
        self._raise_on(joint_space_reevaluate_points(
            points, self.params_table, self.param_index, self.weight, delta, self.base, self.trial, self.traction,
            self.q, self.qt, self.codes, self.info, self.held, self.ST, self.slot, self.wk, self.F, self._err))
        return float(self._err[0])

    def _raise_on(self, status):
        """FloatingPointError for a status of the law and residual kernels other than STATUS_OK (the point
        in ``self.info[0]``, or -1 for a non-finite residual)."""
        if status == STATUS_NAN and self.info[0] < 0:
            raise FloatingPointError("NaN in the joint-space residual")
        if status != STATUS_OK:
            raise FloatingPointError(f"joint point {int(self.info[0])} returned status {status}")

    def _law_arrays(self):
        """The arrays :meth:`_evaluate` writes: law state, tractions, q, Qt, codes, residual."""
        return self.trial, self.traction, self.q, self.qt, self.codes, self.F

    def _snapshot(self):
        """Copies of :meth:`_law_arrays`."""
        return tuple(x.copy() for x in self._law_arrays())

    def _restore(self, snapshot):
        """Put back what :meth:`_snapshot` saved (instead of evaluating the law again at the same point)."""
        for dst, src in zip(self._law_arrays(), snapshot):
            dst[...] = src

    def _line_search(self, delta, delta_y, q_n, err):
        """``delta += lam * step`` with the first ``lam`` of :data:`LINE_SEARCH_STEPS` that does not raise the
        force error ``err``, else the best of them (backtracking on a non-smooth law: a full step can
        cross many stick/slip/open switches; each try costs a law pass and no substitution).
        Returns the force error at the new ``delta``, with the law and ``self.F`` evaluated there."""
        delta_old = delta.copy()
        best = None
        for lam in LINE_SEARCH_STEPS:
            np.add(delta_old, lam * self.step, out=delta)
            e_try = self._evaluate(delta, delta_y, q_n)
            if best is None or e_try < best[0]:
                best = (e_try, lam)
            if e_try <= err:
                return e_try
        if best[1] != lam:
            np.add(delta_old, best[1] * self.step, out=delta)
            return self._evaluate(delta, delta_y, q_n)
        return best[0]

    def _correction(self, rows, qt_rows):
        """Newton correction into ``self.step`` for the active components ``rows`` (their Qt rows
        ``qt_rows``): with the LU of the reference capacitance matrix when it is the same matrix, by a
        low-rank update of it when at most a fifth of the rows changed (cheaper than a new LU of the
        size of the union), else with a new LU, which becomes the reference. Returns a status."""
        na = len(rows)
        if na == 0:  # initial stiffness everywhere: D = -F (the reference LU is kept)
            return apply_correction(self.ST, self.slot, self.F, rows, self.z, self.step)
        self.columns.ensure(rows)
        if self.z.shape[0] < na:
            self.z = np.zeros(max(na, 2 * self.z.shape[0], 16))
        key = rows.tobytes() + qt_rows.tobytes()
        if key == self._lu_key:
            return joint_space_correction(self.ST, self.slot, self.F, rows, self.qt, self.J, self.piv, self.z,
                                          self.step)
        if self._ref is not None and not self._columns_fit(self._ref[0]):
            self._lu_key, self._ref = None, None  # no room for the reference's columns: a new LU instead
        if self._ref is not None:
            ref_rows, ref_qt = self._ref
            max_changes = max(UPDATE_MIN_CHANGES, (len(ref_rows) + na) // UPDATE_CHANGE_FRACTION)
            st = capacitance_update_solve(self.ST, self.slot, ref_rows, ref_qt, self.J, self.piv, rows, qt_rows, self.F,
                                          max_changes, self.z)
            if st == STATUS_OK:
                self.updates += 1
                return apply_correction(self.ST, self.slot, self.F, rows, self.z, self.step)
        self._lu_key, self._ref = None, None
        st, self.J, self.piv = capacitance_lu(self.ST, self.slot, rows, self.qt)
        if st != STATUS_OK:
            return st
        self._lu_key, self._ref = key, (rows, qt_rows)
        self.factorizations += 1
        return joint_space_correction(self.ST, self.slot, self.F, rows, self.qt, self.J, self.piv, self.z,
                                      self.step)

    def _columns_fit(self, cols):
        """Fetch the columns ``cols`` for an optional device (a low-rank update, a start guess): True when
        they are in the store, False when the store has no room for them in this step."""
        try:
            self.columns.ensure(cols)
        except ColumnStoreFull:
            return False
        return True

    def _state_key(self):
        """Per point: state code and the sign of the first shear traction (a friction direction that
        flips is a state change too)."""
        key = np.empty(self.n_points, dtype=np.int8)
        state_key(self.codes, self.traction, key)
        return key

    def _latches(self) -> bool:
        """Whether this joint space latches the bonds of flipping points (:meth:`_bond_chatter`): a static one with
        a law whose bonds latch."""
        return FLIPS_BEFORE_LATCH is not None and self.static and self.law.latches_bonds

    def _bond_chatter(self, flips, broke):
        """(P,) bool: the points to latch broken (:data:`FLIPS_BEFORE_LATCH`): they have changed state that
        many times in the step, their bond broke in one of its iterates (``broke``: state rows whose bond
        column holds the bonds broken so far; None where the step does not latch, :meth:`_latches`) and is intact in
        ``self.base``.

        Why: with cohesion ``c`` and no tensile strength a point whose normal traction is about zero sits on
        a jump of the law: closed, its bond carries a shear up to ``c``; open, it breaks and carries nothing.
        At the tip of a crack (the dam-rock joint under the reservoir) the intact bond's shear pulls the
        point open, the broken one lets it close, and Newton flips it from one iterate to the next; held
        sticking it carries its elastic shear, far from either side, and the true law refuses the held
        solution. A bond that broke stays broken: the law is then continuous at the point (friction alone,
        ``tau_y = -t_n tan(phi)``, zero at ``t_n = 0``), and Newton converges. This is the latching of the
        chatter guard (:mod:`masonrydam.solvers.chatter`), per point instead of the whole pattern, which
        must repeat exactly (on 8 096 points it seldom did). Bond failure is irreversible (the law's
        ``S_BOND_BROKEN``: a joint that has opened once is a crack, ``c = ft = 0``; Tzamtzis & Asteris sec.
        3.4), so a bond that an iterate of the step broke is an admissible state of the step's end; the
        converged iterate satisfies the law with that bond broken (never a held state)."""
        if broke is None:
            return np.zeros(self.n_points, dtype=bool)
        return ((flips >= FLIPS_BEFORE_LATCH) & self.law.bond_broken(broke) & ~self.law.bond_broken(self.base))

    def solve_step(self, u_n, R_n, force_tolerance, initial_stiffness_iterations=None):
        """Solve one step in joint space (see :meth:`_solve_step`); no point is held on entry, and none is
        left held on any exit (return, non-convergence, NaN or an exception). A step that needs more
        columns of S than the store holds (:class:`ColumnStoreFull`) returns ``(None, 0, False, why)``
        and sets ``self.store_full`` (a halved step would need about as many columns)."""
        self.held[:] = 0
        self.columns.new_step()
        self.store_full = False
        try:
            if self.compiled:
                if self.stop_check is not None:  # (the kernel cannot ask within the step: asked before it)
                    self.stop_check()
                return self._solve_step_compiled(u_n, R_n, force_tolerance, initial_stiffness_iterations)
            self.python_steps += 1
            return self._solve_step(u_n, R_n, force_tolerance, initial_stiffness_iterations)
        except ColumnStoreFull as exc:  # the groups' states are untouched until a u is returned
            self._lu_key, self._ref, self._dq_last = None, None, None
            self.store_full = True
            return None, 0, False, str(exc)
        finally:
            self.held[:] = 0

    def _solve_step_compiled(self, u_n, R_n, force_tolerance, initial_stiffness_iterations=None):
        """:meth:`_solve_step` in one call of :func:`.step_kernel.joint_space_step` (the same arithmetic, bit for
        bit; a static step's bond latching and fresh Newton budgets included); the same returns and exceptions."""
        self._load_base()
        n_fixed = MAX_INITIAL_STIFFNESS_ITERATIONS if initial_stiffness_iterations is None else initial_stiffness_iterations
        has_dq = self._dq_last is not None
        if self._ref is not None:
            J, piv, (ref_rows, ref_qt), has_ref = self.J, self.piv, self._ref, True
        else:
            J, piv, ref_rows, ref_qt, has_ref = _NO_LU, _NO_PIVOTS, _NO_ROWS, np.zeros((0, self.dim)), False
        u = np.empty_like(u_n)
        with stop_signals_held():
            status, JT, piv, ref_rows, ref_qt, has_ref = step_kernel.joint_space_step(
                *self._kernel_args, self.params_table, self.param_index, self.weight, self.base, self.trial,
                self.traction, self.q, self.qt, self.codes, self.info, self.held, self.ST, self.slot, self.wk,
                np.ascontiguousarray(u_n, dtype=np.float64), np.ascontiguousarray(R_n, dtype=np.float64),
                float(force_tolerance), self._dq_last if has_dq else self._dq_out, has_dq, J.T, piv, ref_rows,
                ref_qt, has_ref, MAX_JOINT_SPACE_ITERATIONS, int(n_fixed), FLIPS_BEFORE_HOLD, UPDATE_MIN_CHANGES,
                UPDATE_CHANGE_FRACTION, SINGULAR_PIVOT, self._latch_column, self._open_code, self._latches(),
                FLIPS_BEFORE_LATCH if FLIPS_BEFORE_LATCH is not None else 0,
                FRESH_BUDGET_RELEASES if self.static else 0, *self._work, u,
                self._dq_out, self._counts, self._err_out)
        return self._compiled_outcome(status, JT, piv, ref_rows, ref_qt, has_ref, u, n_fixed)

    def kernel_arguments(self):
        """What :func:`.step_kernel.joint_space_step` takes from this joint space for a dynamic step, for a caller
        that calls it from compiled code (:mod:`masonrydam.solvers.dynamic.loop_kernel`): a dict of the fixed
        arguments, the point arrays, the reference LU, the constants and the work and output arrays."""
        if self._ref is not None:
            J, piv, (ref_rows, ref_qt), has_ref = self.J, self.piv, self._ref, True
        else:
            J, piv, ref_rows, ref_qt, has_ref = _NO_LU, _NO_PIVOTS, _NO_ROWS, np.zeros((0, self.dim)), False
        return {"fixed": self._kernel_args, "JT": J.T, "piv": piv, "ref_rows": ref_rows, "ref_qt": ref_qt,
                "has_ref": has_ref, "dq_last": self._dq_last if self._dq_last is not None else np.zeros(self.m),
                "has_dq": self._dq_last is not None, "work": self._work, "counts": self._counts,
                "dq_out": self._dq_out, "err_out": self._err_out, "latch_column": self._latch_column,
                "open_code": self._open_code, "max_newton": MAX_JOINT_SPACE_ITERATIONS,
                "flips_before_hold": FLIPS_BEFORE_HOLD, "update_min_changes": UPDATE_MIN_CHANGES,
                "update_change_fraction": UPDATE_CHANGE_FRACTION, "singular_pivot": SINGULAR_PIVOT}

    def keep_compiled_steps(self, steps, totals, JT, piv, ref_rows, ref_qt, has_ref, dq_last, has_dq):
        """After ``steps`` dynamic steps solved by the kernel from compiled code: their counts ``totals``
        (:data:`masonrydam.solvers.dynamic.loop_kernel.N_TOTALS`), the reference LU and the last force change the
        kernel left (``dq_last`` where ``has_dq``)."""
        self.factorizations += int(totals[2])
        self.updates += int(totals[3])
        self.hold_events += int(totals[4])
        self.column_recoveries += int(totals[5])
        self.compiled_steps += steps
        self.columns.epoch += steps
        if has_ref:
            self.J, self.piv, self._ref = JT.T, piv, (ref_rows, ref_qt)
        else:
            self._ref = None
        self._dq_last = dq_last.copy() if has_dq else None

    def finish_compiled_step(self, status, JT, piv, ref_rows, ref_qt, has_ref, u, n_fixed):
        """What :meth:`solve_step` returns (or raises) for a step whose kernel call compiled code made (the step
        handed back by :func:`masonrydam.solvers.dynamic.loop_kernel.implicit_steps`): its status and the
        arrays the call returned and wrote (``self._counts``, ``self._dq_out``, ``self._err_out``, ``u``)."""
        self.columns.new_step()
        self.store_full = False
        try:
            return self._compiled_outcome(status, JT, piv, ref_rows, ref_qt, has_ref, u, n_fixed)
        finally:
            self.held[:] = 0

    def _compiled_outcome(self, status, JT, piv, ref_rows, ref_qt, has_ref, u, n_fixed):
        """The returns and exceptions of :meth:`_solve_step` for a kernel call that ended in ``status``."""
        c = self._counts
        it = int(c[0])
        self.factorizations += int(c[1])
        self.updates += int(c[2])
        self.hold_events += int(c[3])
        self.column_recoveries += int(c[4])
        self.bond_latches += int(c[7])
        self.fresh_budgets += int(c[8])
        self.compiled_steps += 1
        if has_ref:
            self.J, self.piv, self._ref = JT.T, piv, (ref_rows, ref_qt)
        else:
            self._ref = None
        if status == step_kernel.STEP_FACTOR_NAN:
            raise SingularMatrix("solution contains NaN or infinity")
        if status == step_kernel.STEP_LAW_NAN:
            self._raise_on(STATUS_NAN)
        if status == step_kernel.STEP_SINGULAR:
            return None, it, False, f"singular joint-space iteration matrix ({int(c[6])} active components)"
        if status == step_kernel.STEP_CORRECTION_NAN:
            return None, it, False, "NaN in the joint-space correction"
        if status == step_kernel.STEP_RECOVERY_NAN:
            return None, it, False, "NaN in the recovered displacements"
        if c[5]:  # the predictor is the solution
            self._dq_last = None
            return u, 0, True, ""
        why = ""
        if status == step_kernel.STEP_NOT_CONVERGED:
            why = (f"joint-space iteration: force error {self._err_out[0]:.3g} N after {it} iterations "
                   f"({MAX_JOINT_SPACE_ITERATIONS} Newton, {n_fixed} with the initial stiffness)")
        self._dq_last = self._dq_out.copy() if not why else None
        self._store_latched_bonds()
        return u, it, not why, why

    def _solve_step(self, u_n, R_n, force_tolerance, initial_stiffness_iterations=None):
        """Solve one step in joint space.

        u_n : (n_dof,) m — start of the step (committed state); R_n : (n_eq,) N — the step's residual
        at ``u_n``; force_tolerance : N — bound on the joint force error ``|W D0 F|``;
        initial_stiffness_iterations: limit of the initial-stiffness phase (default
        :data:`MAX_INITIAL_STIFFNESS_ITERATIONS`; less when the caller can halve the step instead).
        Returns ``(u, iterations, converged, why)``: u (n_dof,) m - the last iterate when the iteration
        did not converge within its limits (``why`` says how far it got; the caller goes on from it
        with the general Newton path) - or None after a singular matrix or NaN (the groups' states
        are then untouched). The bonds latched broken in the step are written to the groups'
        ``state_base`` whenever u is returned.

        Iteration control. Newton with the consistent tangent and a backtracking line search on the
        force error. A point whose state (code or friction direction) has changed
        :data:`FLIPS_BEFORE_HOLD` times in the step is *held sticking* (``self.held``: elastic
        traction from its committed plastic slip, in the residual and in the tangent) while Newton
        converges on the others - an active-set device in the spirit of the contact literature
        (Wriggers 2006, *Computational Contact Mechanics*, 2nd ed.): semismooth Newton on a point
        that sits on the stick/slip boundary flips it every iteration, and with stiff joints
        (``w ks`` much larger than the blocks' stiffness at the point) giving it the initial
        stiffness instead converges by about 1 % per iteration. When the held problem has converged
        the true law is evaluated: if it agrees, the step is done; if not, the held points are let
        go for the rest of the step (never held again, so this terminates) and Newton goes on, with a
        fresh budget of :data:`MAX_JOINT_SPACE_ITERATIONS` and the flip counts cleared (at most
        :data:`FRESH_BUDGET_RELEASES` times a step, while in the Newton phase): the release changes the
        active set, and semismooth Newton on a contact law converges locally from its active set
        (Alart & Curnier 1991, *CMAME* 92; Hintermueller, Ito & Kunisch 2002, *SIAM J. Optim.* 13: the
        active-set strategy is a semismooth Newton method), so its iterations count from there. On the
        8-monolith dam filling to 57 m (benchmarks/bench_dam_3d_reservoir_fill.py) the true law
        disagreed by 2-9e6 N after releases at iterations 16-24, and the 1-9 Newton iterations left
        before the initial-stiffness phase (about 3 % a step) never got there: 8 halved steps and 9
        steps in all, against 2 steps and no cut with the fresh budget. A
        held state is never accepted: the iterate returned as converged always satisfies the true
        law. On the Koyna benchmark this took 42 % fewer iterations (4.2 instead of 6.9 per step)
        and 4-5 halved steps instead of 139 than the per-point initial stiffness it replaced. A state
        pattern that comes back gives every open point its initial (elastic) stiffness in the
        iteration matrix and latches broken bonds (the static solver's remedy, Zienkiewicz,
        Valliappan & King 1968)."""
        dim, free, P = self.dim, self.model.dofmap.free, self.n_points
        self._load_base()
        # elastic predictor y = u_n - K_ref^-1 R_n
        u_y = u_n.copy()
        u_y[free] -= self.fact.solve(R_n)
        delta_n = self.B @ u_n
        delta_y = self.B @ u_y
        self._raise_on(joint_points_evaluate(
            self.params_table, self.param_index, self.weight, delta_n.reshape(-1, dim), self.base, self.trial,
            self.traction, self.q, self.qt, self.codes, self.info, self._none_held))
        q_n = self.q.copy()
        delta = delta_y.copy()
        err = self._evaluate(delta, delta_y, q_n)
        if np.array_equal(self.q, q_n):
            self._dq_last = None
            return u_y, 0, True, ""  # every point kept its elastic state: the predictor is the solution
        if self._dq_last is not None:
            # start from the joint forces changing as in the last step (a joint sliding on keeps
            # sliding at about the same rate): delta = delta_y - S dq_last, if that is closer
            if self._columns_fit(np.flatnonzero(self._dq_last)):  # else no room to spare for a guess
                s_dq = np.zeros(self.m)
                add_flexibility_product(self.ST, self.slot, self._dq_last, s_dq)
                trial = delta - s_dq
                at_predictor = self._snapshot()
                e_trial = self._evaluate(trial, delta_y, q_n)
                if e_trial < err:
                    delta, err = trial, e_trial
                else:  # back to the predictor: its law arrays and residual, saved above
                    self._restore(at_predictor)
        flips = np.zeros(P, dtype=np.int64)
        released = np.zeros(P, dtype=bool)  # held once in this step and let go: never held again
        # the bonds broken in any iterate of the step (the law's bond column, accumulated): see FLIPS_BEFORE_LATCH;
        # not kept where the step does not latch (dynamic steps)
        broke = None
        if self._latches():
            broke = np.zeros_like(self.trial)
            self.law.keep_latched_bonds(broke, self.base)
        seen, prev_sig, prev_key, stabilized, same = set(), None, None, False, 0
        it, why = 0, ""
        newton_start, restarts = 0, 0  # the iteration of the last release with a fresh budget, and their number
        n_fixed = MAX_INITIAL_STIFFNESS_ITERATIONS if initial_stiffness_iterations is None else initial_stiffness_iterations
        while True:  # err and self.F are those of delta on entry to every iteration
            key = self._state_key()
            sig = key.tobytes()
            if err <= force_tolerance:
                if not self.held.any():
                    break
                # converged with some points held sticking: the true law decides. If it agrees the
                # step is done; otherwise the held points are let go (for good) and Newton goes on
                was_held = self.held != 0
                self.held[:] = 0
                err = self._reevaluate(np.flatnonzero(was_held), delta)
                if err <= force_tolerance:
                    break
                released |= was_held
                flips[was_held] = 0
                if self.static and restarts < FRESH_BUDGET_RELEASES and it - newton_start < MAX_JOINT_SPACE_ITERATIONS:
                    restarts += 1
                    self.fresh_budgets += 1
                    newton_start = it
                    flips[:] = 0
                key = self._state_key()
                sig = key.tobytes()
                prev_key = None
            if it - newton_start >= MAX_JOINT_SPACE_ITERATIONS + n_fixed:
                if self.held.any():  # hand back an iterate of the true law, not of the held problem
                    self.held[:] = 0
                    err = self._evaluate(delta, delta_y, q_n)
                    if err <= force_tolerance:
                        break
                why = (f"joint-space iteration: force error {err:.3g} N after {it} iterations "
                       f"({MAX_JOINT_SPACE_ITERATIONS} Newton, {n_fixed} with the initial stiffness)")
                break
            fixed_point = it - newton_start >= MAX_JOINT_SPACE_ITERATIONS
            if broke is not None:
                self.law.keep_latched_bonds(broke, self.trial)
            if prev_key is not None:
                changed_state = key != prev_key
                same = 0 if changed_state.any() else same + 1
                if same >= 2 and stabilized:
                    # the pattern has settled: the consistent tangent again (quadratic convergence;
                    # the initial stiffness converges only linearly)
                    flips[:] = 0
                    stabilized = False
                    seen = set()
                else:
                    flips += changed_state
                    hold = (flips >= FLIPS_BEFORE_HOLD) & ~released & (self.held == 0)
                    crack = self._bond_chatter(flips, broke)
                    if crack.any():
                        # flipping across the cohesion jump: the bond stays broken for the step
                        sub = self.base[crack]
                        self.law.keep_latched_bonds(sub, broke[crack])
                        self.base[crack] = sub
                        self.bond_latches += int(crack.sum())
                        flips[crack] = 0
                        hold &= ~crack
                    if hold.any() or crack.any():
                        # points that keep flipping are held sticking (residual and tangent) while
                        # the others converge
                        self.held[hold] = 1
                        self.hold_events += int(hold.sum())
                        err = self._reevaluate(np.flatnonzero(hold | crack), delta)
                        if err <= force_tolerance:
                            continue  # the held problem is solved already: let the true law decide
                        key = self._state_key()
                        sig = key.tobytes()
            if not stabilized and sig != prev_sig and sig in seen:
                stabilized = True
                self.law.latch_broken_bonds(self.base, self.trial)
                err = self._evaluate(delta, delta_y, q_n)
            seen.add(sig)
            prev_sig, prev_key = sig, key
            if stabilized:
                self.qt[self.law.result_states_of(self.codes) == RESULT_OPEN] = 0.0
            if fixed_point:
                self.qt[:] = 0.0
            if self.stop_check is not None:  # a stop asked for: abandon the step (the finally of solve_step
                self.stop_check()            # lets the held points go; the groups' states are untouched)
            rows, qt_rows = active_components(self.qt)
            st = self._correction(rows, qt_rows)
            if st == STATUS_SINGULAR:
                return None, it, False, f"singular joint-space iteration matrix ({len(rows)} active components)"
            it += 1
            if st != STATUS_OK:
                return None, it, False, "NaN in the joint-space correction"
            err = self._line_search(delta, delta_y, q_n, err)
        dq = (self.q - q_n).ravel()
        self._dq_last = dq.copy() if not why else None
        u = u_y
        nz = np.flatnonzero(dq)
        if len(nz):
            u = u_y.copy()
            if len(nz) <= self.recovery_columns_max:
                # u = y - X dq from the stored columns of X (cheaper than a substitution for a few)
                uf = self._u_free
                uf[:] = u_y[free]
                if subtract_columns_product(self.XT, nz, dq[nz], uf) != STATUS_OK:
                    return None, it, False, "NaN in the recovered displacements"
                u[free] = uf
                self.column_recoveries += 1
            else:
                u[free] -= self.fact.solve(self.Bf_T @ dq)
        self._store_latched_bonds()
        return u, it, not why, why
