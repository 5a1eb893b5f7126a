"""Modal analysis: the lowest modes of the model on its free DOFs (:func:`modal_analysis`), of the dam coupled
with a compressible reservoir (:func:`coupled_modal_analysis`), and the modal stage (:class:`ModalStage`).

The mass, Rayleigh damping and elastic tangents it uses are assembly's (:mod:`masonrydam.assembly.mass`,
:mod:`masonrydam.assembly.damping`, :mod:`masonrydam.assembly.elastic`).

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

from ...assembly.mass import MassMatrix
from ...errors import MechanismError, NumericalError, SceneError
from ..linear.direct import Factorization, SingularMatrix


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
    try:
        lam, phi = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=OPinv, tol=1e-10)
    except (spla.ArpackError, spla.ArpackNoConvergence) as exc:
        raise NumericalError(_eigensolver_failure(model, k, exc)) from None
    return _modal_result(model, mass, M, lam, phi)


def _eigensolver_failure(model, k: int, exc: Exception) -> str:
    """Why the eigensolver may have found no modes, in words: its own error's first sentence, and the element groups
    without mass (their infinite eigenvalues make the shift-invert iteration fragile)."""
    massless = sorted({g.name for g in model.cgroups if not (np.asarray(g.density) > 0).any()})
    first = str(exc).split(". ")[0].rstrip(".")
    return (f"modal analysis: the eigensolver (ARPACK) did not find the {k} lowest modes ({first})"
            + (f"; element groups {massless} have no mass (density 0): give them their density, or ask for fewer "
               "modes" if massless else "; ask for fewer modes"))


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
    try:
        nu, vec = spla.eigs(op, k=k, which="LM", tol=1e-10)
    except (spla.ArpackError, spla.ArpackNoConvergence) as exc:
        raise NumericalError(_eigensolver_failure(model, k, exc)) from None
    return _modal_result(model, mass, M, (sigma + 1.0 / nu).real, vec[:n].real)
