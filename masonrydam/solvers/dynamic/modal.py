"""Structural matrices for dynamics (mass, elastic joint stiffness, Rayleigh damping) and modal analysis.

Mass
----
Assembled once from the continuum groups (joints carry no mass): consistent
``M = int rho N^T N dV`` or HRZ-lumped (the kernel :func:`masonrydam.elements.continuum.continuum_mass`;
Hinton, Rock & Zienkiewicz 1976). Triangles and tetrahedra need a rule exact for ``N_a N_b``, one
order above the stiffness rule (tri3 -> 3 points, tri6 -> 6, tet4 -> 4, tet10 -> 14); quadrilaterals
and hexahedra use their default rule, exact on parallelograms. :class:`MassMatrix` holds the full-DOF
matrix (for ``M iota`` and reactions) and, once the constraints are known, the free-DOF values laid
out in the model's stiffness pattern (the mass pattern of an element is a subset of its stiffness
pattern), so that an effective matrix ``K + c_m M + c_c C`` is a sum of three value arrays.

Damping
-------
Rayleigh damping ``C = a M + b K`` (Chopra, *Dynamics of Structures*, 4th ed. 2012, sec. 11.4.1):
``zeta(omega) = a / (2 omega) + b omega / 2``; the two coefficients give ``zeta`` at ``f1`` and ``f2``:
``a = 2 zeta w1 w2 / (w1 + w2)``, ``b = 2 zeta / (w1 + w2)`` (Chopra eq. 11.4.9 with zeta_i = zeta_j).

``K`` in ``b K`` is constant: the elastic stiffness, by default the continuum stiffness only
(``exclude_joints = True``). Why: the joint penalty stiffnesses kn, ks are chosen huge so that the
joints stay thin; in ``b K`` they give each joint a dashpot ``b kn`` that (1) damps the very high
joint modes heavily, (2) transmits large damping forces through a joint that opens or slides (the
dashpot keeps pulling the blocks together while the joint has no stiffness), i.e. spurious tension
and shear across a crack, and (3) damps the rigid-body-like rocking and sliding of blocks, which in
the structure is resisted by impact and friction, not viscosity. Hall (2006), "Problems encountered
from the use (or misuse) of Rayleigh damping", Earthquake Eng. Struct. Dyn. 35:525-545, shows that
stiffness-proportional damping on stiff elements that soften or open produces such unrealistic damping
forces and recommends bounding them; here they are removed by keeping joints out of ``b K``. The
Rayleigh frequencies should then be those of the structure (blocks on elastic joints) and the
damping ratio of a joint-dominated mode is lower than ``zeta``: a user who wants the joints damped
sets ``exclude_joints = false``.

Modal analysis
--------------
Generalised eigenproblem ``K phi = omega^2 M phi`` on the free DOFs with the joints at their current
tangent (symmetric part; a sliding point makes the tangent non-symmetric, and a mode is only defined
for the symmetric part), by ARPACK shift-invert Lanczos (``scipy.sparse.linalg.eigsh``) around a
small negative shift, so that a mechanism (an open joint around a block) gives ~0 Hz modes instead of
a singular factorization. Modes are mass-normalised (``phi^T M phi = 1``). Participation factor of
mode n in direction c (Chopra sec. 13.1.3 with the ground-motion influence vector ``iota_c``):
``Gamma_nc = phi_n^T (M iota_c) / phi_n^T M phi_n`` where ``M iota_c`` is taken from the full-DOF
mass (the supports move with the ground); effective modal mass ``M*_nc = (phi_n^T M iota_c)^2 /
phi_n^T M phi_n`` (Chopra eq. 13.2.12); with a lumped mass their sum over all modes is the mass on
the free DOFs (``ModalResult.free_mass``); with a consistent mass it is
``(M iota)_f^T M_ff^-1 (M iota)_f``, slightly different because of the mass coupling to the supports.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...assembly.groups import raise_for_status
from ...assembly.sparsity import scatter_matrix
from ...elements import continuum as ck
from ...elements import interface as ik
from ...errors import MechanismError, SceneError
from ...materials import mohr_coulomb as mc
from ..linear.direct import Factorization, SingularMatrix

#: integration points per element type for a consistent mass (exact for N_a N_b on straight elements)
MASS_RULE = {"tri3": 3, "tri6": 6, "tet4": 4, "tet10": 14}


def rayleigh_coefficients(f1: float, f2: float, zeta: float) -> tuple[float, float]:
    """Rayleigh coefficients ``(a, b)`` (1/s, s) giving damping ratio ``zeta`` at ``f1`` and ``f2`` (Hz).

    ``C = a M + b K`` with ``a = 2 zeta w1 w2 / (w1 + w2)``, ``b = 2 zeta / (w1 + w2)``, ``w = 2 pi f``
    (Chopra 2012, eq. 11.4.9 with equal ratios at both frequencies).
    """
    for name, v in (("f1", f1), ("f2", f2)):
        if not (np.isfinite(v) and v > 0):
            raise SceneError(f"damping.frequencies ({name})", f"must be a positive frequency in Hz, got {v!r}")
    if not f1 < f2:
        raise SceneError("damping.frequencies", f"need f1 < f2, got [{f1!r}, {f2!r}] Hz")
    if not (np.isfinite(zeta) and 0.0 <= zeta < 1.0):
        raise SceneError("damping.ratio", f"must be in [0, 1), got {zeta!r}")
    w1, w2 = 2.0 * np.pi * f1, 2.0 * np.pi * f2
    return 2.0 * zeta * w1 * w2 / (w1 + w2), 2.0 * zeta / (w1 + w2)


@dataclass
class RayleighDamping:
    """``C = alpha M + beta K_el`` (alpha 1/s, beta s); ``K_el`` = continuum only if ``exclude_joints``."""

    alpha: float = 0.0
    beta: float = 0.0
    exclude_joints: bool = True

    @classmethod
    def from_frequencies(cls, f1: float, f2: float, zeta: float, exclude_joints: bool = True) -> "RayleighDamping":
        a, b = rayleigh_coefficients(f1, f2, zeta)
        return cls(a, b, exclude_joints)

    def ratio(self, f_hz):
        """Damping ratio at frequency ``f_hz`` (Chopra eq. 11.4.8)."""
        w = 2.0 * np.pi * np.asarray(f_hz, dtype=np.float64)
        return self.alpha / (2.0 * w) + self.beta * w / 2.0

    @property
    def active(self) -> bool:
        return self.alpha != 0.0 or self.beta != 0.0


def _element_masses(model, lumped: bool, massless=()):
    """(group, me) per continuum group (except the groups named in ``massless``): element mass matrices
    (ne, nd, nd) in kg."""
    out = []
    for g in model.cgroups:
        if g.name in massless:
            continue
        N, dN, w = ck.element_tables(g.type, MASS_RULE.get(g.type))
        me = np.zeros((g.n_elem, g.n_edof, g.n_edof))
        st = ck.continuum_mass(model.coords, g.conn, N, dN, w, np.ascontiguousarray(g.density, dtype=np.float64),
                               np.ascontiguousarray(g.thickness, dtype=np.float64), bool(lumped), me, g.info)
        raise_for_status(st, g.info, g.name, "mass")
        out.append((g, me))
    return out


def _full_matrix(n_dof, parts):
    rows, cols, vals = [], [], []
    for dofs, ke in parts:
        nd = dofs.shape[1]
        rows.append(np.repeat(dofs, nd, axis=1).ravel())
        cols.append(np.tile(dofs, (1, nd)).ravel())
        vals.append(ke.reshape(len(ke), -1).ravel())
    if not rows:
        return sp.csr_matrix((n_dof, n_dof))
    M = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_dof, n_dof))
    M.sum_duplicates()
    return M


def add_to_pattern(A: sp.spmatrix, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, what: str) -> None:
    """Add the free-DOF matrix ``A`` (n_eq, n_eq) into ``data`` (values of the CSR pattern ``indptr``,
    ``indices``, column indices sorted in each row); a ValueError names ``what`` if an entry of ``A``
    lies outside the pattern."""
    A = sp.coo_matrix(A)
    if A.nnz == 0:
        return
    n = len(indptr) - 1
    rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
    keys = rows * n + indices
    want = A.row.astype(np.int64) * n + A.col
    pos = np.searchsorted(keys, want)
    pos = np.minimum(pos, len(keys) - 1)
    if not np.array_equal(keys[pos], want):
        raise ValueError(f"the {what} couples DOFs that the model's sparsity pattern does not (a coupling must "
                         "be declared with Model.add_coupling before set_constraints)")
    np.add.at(data, pos, A.data)


def diagonal_positions(indptr: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Position of the diagonal entry of every row in a CSR ``data`` array (the model's pattern has
    every diagonal entry, see :func:`masonrydam.assembly.sparsity.build_pattern`)."""
    n = len(indptr) - 1
    rows = np.repeat(np.arange(n), np.diff(indptr))
    pos = np.nonzero(indices == rows)[0]
    if len(pos) != n:
        raise ValueError("the stiffness pattern lacks diagonal entries")
    return pos


class MassMatrix:
    """Mass of the continuum groups, assembled once, plus an optional added mass (e.g. the reservoir's,
    :mod:`masonrydam.effects.added_mass`).

    ``lumped``; ``full`` (n_dof, n_dof) CSR; ``diagonal``: the whole matrix is diagonal (lumped element
    masses and an added mass without off-diagonal terms), then ``diag`` (n_dof,) kg and, after
    :meth:`for_pattern`, ``free_diag`` (n_eq,); ``data`` (nnz,) free-DOF values in the model pattern.
    added: (n_dof, n_dof) sparse, kg, or None; its entries must lie in the model's pattern (nodes that
    share an element or a coupling, :meth:`Model.add_coupling`). extra_influence: see the attribute.
    massless: names of element groups without mass (e.g. the foundation rock of ``[foundation] mass =
    false``).
    """

    def __init__(self, model, lumped: bool, added: sp.spmatrix | None = None,
                 extra_influence: np.ndarray | None = None, massless=()):
        self.lumped = bool(lumped)
        #: (dim, n_dof) kg or None: the earthquake load per unit acceleration of the reservoir bottom that is
        #: not ``M iota`` (incompressible acoustic water pushed by the bottom and banks; the dynamic solver
        #: applies ``-extra_influence . a_bottom``)
        self.extra_influence = extra_influence
        self._groups = _element_masses(model, self.lumped, tuple(massless))
        self.n_dof = model.n_dof
        self.added = None if added is None or added.nnz == 0 else sp.csr_matrix(added)
        if self.lumped:
            diag = np.zeros(model.n_dof)
            for g, me in self._groups:
                d = np.einsum("eii->ei", me)
                np.add.at(diag, g.dofs.ravel(), d.ravel())
            self.full = sp.diags(diag).tocsr()
        else:
            self.full = _full_matrix(model.n_dof, [(g.dofs, me) for g, me in self._groups])
        #: the continuum's own mass (what Rayleigh damping is proportional to: the water's added mass is
        #: not a material that dissipates); ``structural_data`` its pattern values after for_pattern
        self.structural_full = self.full
        self.structural_data = None
        if self.added is not None:
            self.full = (self.full + self.added).tocsr()
        offdiag = self.full - sp.diags(self.full.diagonal())
        self.diagonal = self.lumped and offdiag.count_nonzero() == 0
        self.diag = self.full.diagonal().copy() if self.diagonal else None
        self.data = None
        self.free_diag = None
        self._pattern_key = None

    def total(self, dim: int) -> np.ndarray:
        """Total mass per direction (kg), ``iota_c^T M iota_c``."""
        out = np.zeros(dim)
        for c in range(dim):
            iota = np.zeros(self.n_dof)
            iota[c::dim] = 1.0
            out[c] = iota @ (self.full @ iota)
        return out

    def influence(self, dim: int) -> np.ndarray:
        """(dim, n_dof) ``M iota_c`` for a rigid unit translation of everything (supports included) in c."""
        out = np.zeros((dim, self.n_dof))
        for c in range(dim):
            iota = np.zeros(self.n_dof)
            iota[c::dim] = 1.0
            out[c] = self.full @ iota
        return out

    def for_pattern(self, model) -> np.ndarray:
        """Free-DOF mass values in the model's current CSR pattern (``model.set_constraints`` first)."""
        key = (id(model.dofmap), len(model.indices))
        if self._pattern_key == key:
            return self.data
        data = np.zeros(len(model.indices))
        free = model.dofmap.free
        if self.diagonal:
            self.free_diag = self.diag[free].copy()
            data[diagonal_positions(model.indptr, model.indices)] = self.free_diag
        else:
            if self.lumped:
                d = np.zeros(model.n_dof)
                for g, me in self._groups:
                    np.add.at(d, g.dofs.ravel(), np.einsum("eii->ei", me).ravel())
                data[diagonal_positions(model.indptr, model.indices)] = d[free]
            else:
                for g, me in self._groups:
                    scatter_matrix(me, g.scatter, data)
            if self.added is not None:
                self.structural_data = data.copy()
                add_to_pattern(self.added[free][:, free], model.indptr, model.indices, data, "added mass")
        if self.added is None:
            self.structural_data = data
        elif self.diagonal:
            self.structural_data = np.zeros(len(model.indices))
            self.structural_data[diagonal_positions(model.indptr, model.indices)] = \
                self.structural_full.diagonal()[free]
        self.data = data
        self._pattern_key = key
        return data

    def free_matrix(self, model) -> sp.csr_matrix:
        n = model.dofmap.n_eq
        return sp.csr_matrix((self.for_pattern(model), model.indices, model.indptr), shape=(n, n))


def _elastic_joint_parts(model):
    """Element stiffness matrices of every interface group with every point sticking (the initial,
    elastic joint stiffness), from a copy of the parameters with unbreakable bonds and zero states;
    the groups' own states are not touched."""
    parts = []
    for g in model.igroups:
        params = g.params_table.copy()
        if g.law != "composite":  # (the composite law is elastic at zero displacement from a virgin state)
            params[:, mc.P_COHESION] = 1e300
            params[:, mc.P_TENSILE_STRENGTH] = 1e300
        params[:, g.open_tangent_column] = 0.0
        zeros = np.zeros_like(g.state_committed)
        trial = np.zeros_like(g.state_committed)
        delta, traction = np.zeros_like(g.delta), np.zeros_like(g.traction)
        fe, ke = np.zeros_like(g.fe), np.zeros_like(g.ke)
        info = np.zeros(1, dtype=np.int64)
        st = ik.interface_evaluate(model.coords, g.conn, np.zeros(model.n_dof), g.N, g.dN, g.weights, g.thickness,
                                   params, g.param_index, zeros, trial, delta, traction, fe, ke, True, info,
                                   g.law_id)
        raise_for_status(st, info, g.name, "elastic joint stiffness")
        parts.append((g, ke))
    return parts


def elastic_tangent_data(model) -> np.ndarray:
    """Free-DOF values (model pattern) of the tangent with every joint point sticking.

    Summed in the same order as :meth:`Model.evaluate` (continuum values, then each interface group
    scattered in turn), so that a tangent evaluated with all joints sticking is bitwise equal to it.
    """
    data = model.elastic_continuum_data().copy()
    for g, ke in _elastic_joint_parts(model):
        scatter_matrix(ke, g.scatter, data)
    return data


def elastic_joint_full(model) -> sp.csr_matrix:
    """Full-DOF elastic (all sticking) joint stiffness (N/m)."""
    return _full_matrix(model.n_dof, [(g.dofs, ke) for g, ke in _elastic_joint_parts(model)])


@dataclass
class ModalResult:
    """frequencies (k,) Hz; omegas (k,) rad/s; periods (k,) s; modes (n_dof, k) mass-normalised full-DOF
    shapes (zero at constrained DOFs); participation (k, dim) Gamma; effective_mass (k, dim) kg;
    free_mass (dim,) kg: ``iota_f^T M_ff iota_f``, the mass on the free DOFs per direction (the sum of
    all effective masses for a lumped mass)."""

    frequencies: np.ndarray
    omegas: np.ndarray
    periods: np.ndarray
    modes: np.ndarray
    participation: np.ndarray
    effective_mass: np.ndarray
    free_mass: np.ndarray

    @property
    def effective_mass_ratio(self) -> np.ndarray:
        return self.effective_mass / np.where(self.free_mass > 0, self.free_mass, 1.0)


def _stiffness_and_mass(model, u, lumped, mass):
    """(K, M, mass, shift): the symmetric free-DOF tangent at ``u`` (joint trial arrays restored), the
    free-DOF mass, the :class:`MassMatrix` and the scale ``max K_ii / M_ii`` over DOFs with mass."""
    if model.dofmap is None:
        raise SceneError("supports", "modal analysis needs the constraints: call model.set_constraints first")
    saved = [(g.state_trial.copy(), g.delta.copy(), g.traction.copy()) for g in model.igroups]
    plastic = [(g, g.state_trial.copy()) for g in model.cgroups if g.plastic]
    time_step, model.time_step = model.time_step, 0.0  # the tangent of the state as it is, not of a step in time
    try:
        _, K = model.evaluate(np.zeros(model.n_dof) if u is None else np.asarray(u, dtype=np.float64), True)
    finally:
        model.time_step = time_step
        for g, (s, d, t) in zip(model.igroups, saved):
            g.state_trial[:], g.delta[:], g.traction[:] = s, d, t
        for g, s in plastic:
            g.state_trial[:] = s
    K = ((K + K.T) * 0.5).tocsr()
    if mass is None:
        mass = MassMatrix(model, lumped)
    M = mass.free_matrix(model)
    mdiag = M.diagonal()
    if not (mdiag > 0).any() or (mdiag < 0).any():
        raise SceneError("materials", "modal analysis needs mass (a positive density) in the model; massless parts "
                                      "(e.g. rock of density 0) are allowed, they follow the others statically")
    has = mdiag > 0
    return K, M, mass, float(np.max(K.diagonal()[has] / mdiag[has]))


def _modal_result(model, mass, M, lam, phi) -> ModalResult:
    """Sorted, mass-normalised (``phi^T M phi = 1``) modes with their participation and effective masses
    from eigenvalues ``lam`` (k,) rad2/s2 and free-DOF shapes ``phi`` (n_eq, k)."""
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    mm = np.einsum("ik,ik->k", phi, M @ phi)
    phi = phi / np.sqrt(np.where(mm > 0, mm, 1.0))
    omegas = np.sqrt(np.clip(lam, 0.0, None))
    dim = model.dim
    free = model.dofmap.free
    L = phi.T @ mass.influence(dim)[:, free].T  # (k, dim), phi mass-normalised
    free_mass = np.zeros(dim)
    for c in range(dim):
        iota = np.zeros(model.n_dof)
        iota[c::dim] = 1.0
        iota_f = iota[free]
        free_mass[c] = iota_f @ (M @ iota_f)
    modes = np.zeros((model.n_dof, len(lam)))
    modes[free] = phi
    with np.errstate(divide="ignore"):
        periods = np.where(omegas > 0, 2.0 * np.pi / np.where(omegas > 0, omegas, 1.0), np.inf)
    return ModalResult(omegas / (2.0 * np.pi), omegas, periods, modes, L, L**2, free_mass)


def modal_analysis(model, n_modes: int, lumped: bool = False, u: np.ndarray | None = None,
                   mass: MassMatrix | None = None, linear_solver: str = "auto") -> ModalResult:
    """The ``n_modes`` lowest modes of ``model`` on its free DOFs (``model.set_constraints`` first).

    u: displacement at which the joint tangent is taken (default zero: joints sticking; a slipping
    or open joint from a previous analysis enters with its current state). The joints' trial
    arrays are restored afterwards. Returns a :class:`ModalResult`.
    """
    n = model.dofmap.n_eq if model.dofmap is not None else 0
    n_modes = int(n_modes)
    if model.dofmap is not None and not 1 <= n_modes < n:
        raise SceneError("n_modes", f"must be between 1 and {n - 1} (free DOFs), got {n_modes}")
    K, M, mass, scale = _stiffness_and_mass(model, u, lumped, mass)
    # massless DOFs (massless rock) are condensed by the shift-invert solve: M positive semi-definite is
    # enough for ARPACK's mode 3 (the infinite eigenvalues are never near the shift)
    # small negative shift: K - sigma M is positive definite even for a mechanism
    sigma = -1e-9 * scale
    A = (K - sigma * M).tocsr()
    try:
        fact = Factorization(A, linear_solver)
    except SingularMatrix as exc:  # pragma: no cover - K - sigma M is positive definite
        raise MechanismError(f"modal analysis: singular shifted stiffness ({exc})") from None
    OPinv = spla.LinearOperator((n, n), matvec=fact.solve, dtype=np.float64)
    k = min(n_modes, n - 1)
    lam, phi = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=OPinv, tol=1e-10)
    return _modal_result(model, mass, M, lam, phi)


@dataclass
class ModalStage:
    """A modal stage: the ``modes`` lowest modes of the model in the state the static stages left it
    (sticking joint points elastic, open points free), ``lumped`` or consistent mass, with ``supports``
    (n_dof,) bool held (the supports and the DOFs prescribed by the last static stage)."""

    name: str
    modes: int
    lumped: bool
    supports: np.ndarray


def coupled_modal_analysis(model, n_modes: int, fluid, lumped: bool = False, u: np.ndarray | None = None,
                           mass: MassMatrix | None = None) -> ModalResult:
    """The ``n_modes`` lowest modes of the dam coupled with a compressible reservoir of acoustic elements
    (``fluid``: :class:`~masonrydam.solvers.dynamic.fluid.AcousticStep`, radiation damping ``L`` left out):

        [K  -Q] [u]          [M       0] [u]
        [0   H] [p] = w^2    [rho Q^T G] [p]

    (Zienkiewicz & Bettess 1978, IJNME 13:1-16; the pencil is not symmetric but its eigenvalues are
    real and positive). Solved by ARPACK in shift-invert mode on the operator ``(A - sigma B)^-1 B``
    with a sparse LU (SuperLU) of the coupled matrix. The mode shapes are the dam's part, normalised
    with the dam's mass (``phi^T M phi = 1``); the effective masses are the dam's (``(phi^T M iota)^2``),
    so their sum over all modes is the dam's mass, not dam plus water. Returns a :class:`ModalResult`."""
    K, M, mass, scale = _stiffness_and_mass(model, u, lumped, mass)
    n = model.dofmap.n_eq
    n_modes = int(n_modes)
    free = model.dofmap.free
    Qf = sp.csr_matrix(fluid.Q)[free]  # (n, n_p)
    n_p = fluid.n_p
    A = sp.bmat([[K, -Qf], [None, fluid.H]], format="csc")
    B = sp.bmat([[M, None], [fluid.rho * Qf.T, fluid.G]], format="csc")
    sigma = -1e-6 * scale
    lu = spla.splu((A - sigma * B).tocsc())
    op = spla.LinearOperator((n + n_p, n + n_p), matvec=lambda x: lu.solve(B @ x), dtype=np.float64)
    k = min(n_modes, n + n_p - 2)
    nu, vec = spla.eigs(op, k=k, which="LM", tol=1e-10)
    return _modal_result(model, mass, M, (sigma + 1.0 / nu).real, vec[:n].real)
