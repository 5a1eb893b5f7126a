"""Stability of the conditionally stable schemes: the critical time step and the check of a stage's dt.

A scheme with a stability bound ``Omega_crit`` (:attr:`~.schemes.Scheme.stability_bound`: central difference 2,
Newmark linear acceleration sqrt(12); Hughes 2000, sec. 9.1.2 and Table 9.1.1) is stable for
``omega_max h <= Omega_crit``, with ``omega_max`` (rad/s) the highest circular frequency of the model with every
joint sticking (the joint penalty springs usually set it); viscous damping lowers the bound. With a compressible
reservoir stepped explicitly (:class:`~.fluid.ExplicitAcoustic`) ``omega_max`` is that of the coupled dam-water
system (:func:`coupled_highest_frequency`): the water's own highest frequency (its elements' Courant limit) and
the compressibility of the first layer of water, a spring on the wetted face, both enter it.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...assembly.damping import RayleighDamping
from ...errors import SceneError
from ..linear.direct import Factorization


def critical_time_step(K: sp.csr_matrix, mass_diag: np.ndarray | None = None, M: sp.csr_matrix | None = None,
                       damping: RayleighDamping | None = None, omega_crit: float = 2.0, linear_solver="auto"):
    """(dt_crit, omega_max): largest circular frequency of ``K phi = omega^2 M phi`` (Lanczos, ARPACK
    largest algebraic) and the critical step ``Omega_crit / omega_max``; with Rayleigh damping the
    central-difference bound ``Omega_crit = 2 (sqrt(1 + xi^2) - xi)`` at omega_max (Hughes 2000, sec. 9.1.2)."""
    n = K.shape[0]
    Ks = ((K + K.T) * 0.5).tocsr()
    if mass_diag is not None:
        s = 1.0 / np.sqrt(mass_diag)
        A = sp.diags(s) @ Ks @ sp.diags(s)
        try:
            lam = spla.eigsh(A, k=1, which="LA", tol=1e-8, return_eigenvectors=False, ncv=min(n, 40))[0]
        except Exception:  # pragma: no cover - ARPACK failure: Gershgorin bound (safe, larger)
            lam = float(np.max(np.asarray(abs(A).sum(axis=1)).ravel()))
    else:
        fm = Factorization(M.tocsr(), linear_solver)
        Minv = spla.LinearOperator((n, n), matvec=fm.solve, dtype=np.float64)
        lam = spla.eigsh(Ks, k=1, M=M, Minv=Minv, which="LA", tol=1e-8, return_eigenvectors=False,
                         ncv=min(n, 40))[0]
    w = math.sqrt(max(float(lam), 0.0)) * (1.0 + 1e-6)  # Lanczos converges from below
    return _step_bound(w, damping, omega_crit), w


def _step_bound(w: float, damping: RayleighDamping | None, omega_crit: float) -> float:
    """The critical step (s) at the highest circular frequency ``w`` (rad/s): ``Omega_crit / w``, with Rayleigh
    damping ``Omega_crit 2 (sqrt(1 + xi^2) - xi) / 2`` at ``w`` (Hughes 2000, sec. 9.1.2)."""
    if w == 0:
        return math.inf
    Oc = omega_crit
    if damping is not None and damping.active:
        xi = damping.alpha / (2 * w) + damping.beta * w / 2
        Oc = omega_crit * (math.sqrt(1 + xi * xi) - xi)
    return Oc / w


def _largest_eigenvalue(A, n: int) -> float:
    """The largest algebraic eigenvalue of the symmetric ``A`` (Lanczos, ARPACK; Gershgorin's bound, safe and
    larger, where ARPACK fails)."""
    try:
        return float(spla.eigsh(A, k=1, which="LA", tol=1e-8, return_eigenvectors=False, ncv=min(n, 40))[0])
    except Exception:  # pragma: no cover - ARPACK failure
        return float(np.max(np.asarray(abs(A).sum(axis=1)).ravel()))


def coupled_highest_frequency(K: sp.csr_matrix, mass_diag: np.ndarray, water) -> tuple[float, float]:
    """(omega_max, omega_water) rad/s: the highest circular frequency of the undamped coupled dam-water system of
    an explicit stage and the water's own on a rigid dam.

    ``K`` (n, n) N/m the all-stick stiffness and ``mass_diag`` (n,) kg the lumped mass on the free DOFs;
    ``water``: the stage's :class:`~.fluid.ExplicitAcoustic` (lumped capacity ``g`` (n_p,), ``H``, the coupling
    ``Q`` (n, n_p) on the free DOFs, density rho). The coupled eigenproblem (the one
    :func:`~.modal.coupled_modal_analysis` solves, with the lumped matrices)

        [K  -Q] [u]          [M       0] [u]
        [0   H] [p] = w^2    [rho Q^T g] [p]

    has real eigenvalues although it is not symmetric: ``A = M_c^-1 K_c`` is self-adjoint in the inner product
    of ``S = diag(K, g / rho)`` (``S A = [K; -Q^T] M^-1 [K, -Q] + diag(0, H / rho)``, symmetric), and is bounded
    by ``w^2 <= lambda_max(M^-1 (K + rho Q g^-1 Q^T)) + lambda_max(g^-1 H)`` (the Rayleigh quotient of each
    term of ``S A`` over ``S``). It is found by Arnoldi (ARPACK ``eigs``, largest magnitude) on ``A`` scaled
    by ``diag(M^1/2, (g / rho)^1/2)``; that bound, larger, is taken where ARPACK fails. ``omega_water``: the
    largest eigenvalue of ``g^-1/2 H g^-1/2`` (Lanczos)."""
    n = K.shape[0]
    fluid = water.fluid
    n_p = fluid.n_p
    rho = fluid.rho
    coo = fluid.Qw.tocoo()  # (n_w, n_p), rows at the free wetted DOFs wet_eq
    Q = sp.csr_matrix((coo.data, (np.asarray(fluid.wet_eq)[coo.row], coo.col)), shape=(n, n_p))
    H = sp.csr_matrix(fluid.H)
    g = water.capacity
    sm, sg = np.sqrt(mass_diag), np.sqrt(g / rho)
    # the water alone on a rigid dam: its elements' Courant limit
    Hs = (sp.diags(1.0 / np.sqrt(g)) @ H @ sp.diags(1.0 / np.sqrt(g))).tocsr()
    lam_water = max(_largest_eigenvalue(Hs, n_p), 0.0)
    Ks = ((K + K.T) * 0.5).tocsr()
    QT = sp.csr_matrix(Q.T)

    def matvec(x):  # D A D^-1 x with D = diag(M^1/2, (g / rho)^1/2)
        u = x[:n] / sm
        p = x[n:] / sg
        yu = (Ks @ u - Q @ p) / mass_diag
        yp = (H @ p - rho * (QT @ yu)) / g
        return np.concatenate([sm * yu, sg * yp])

    op = spla.LinearOperator((n + n_p, n + n_p), matvec=matvec, dtype=np.float64)
    try:
        lam = spla.eigs(op, k=1, which="LM", tol=1e-8, return_eigenvectors=False, ncv=min(n + n_p - 1, 40))
        lam = float(np.abs(lam).max())
    except Exception:  # pragma: no cover - ARPACK failure: the bound
        s = 1.0 / sm
        A = sp.diags(s) @ (Ks + rho * (Q @ sp.diags(1.0 / g) @ QT)) @ sp.diags(s)
        lam = _largest_eigenvalue(A.tocsr(), n) + lam_water
    return math.sqrt(max(lam, 0.0)) * (1.0 + 1e-6), math.sqrt(lam_water) * (1.0 + 1e-6)


def check_time_step(equations, settings, backend, stats):
    """Refuse a time step above ``stability_safety`` x the critical one of a conditionally stable scheme
    (``equations``: the stage's :class:`~.equations.StageEquations`; ``backend``: the linear solver of a
    consistent mass); returns dt_crit (s, also in ``stats.dt_critical``) or None for an unconditionally stable
    scheme."""
    s = settings
    scheme = s.scheme
    if scheme.stability_bound is None:
        return None
    Oc = scheme.stability_bound
    model, mass = equations.model, equations.mass
    K = sp.csr_matrix((equations.elastic_data, model.indices, model.indptr), shape=(equations.n, equations.n))
    node_blocks = False  # a mass coupling only the DOFs of single nodes (Westergaard's on a curved face, lumped)
    if scheme.explicit and not mass.diagonal:
        node_blocks = equations.mass_blocks is not None
        if not node_blocks or equations.explicit_water is not None:
            raise SceneError(f"{s.key}integrator", f"{scheme.name} needs a lumped mass (diagonal, or coupling "
                                                   "only the DOFs of one node); the reservoir's added mass couples "
                                                   "DOFs of different nodes (a consistent added mass, or the "
                                                   "incompressible acoustic water's rho Q H^-1 Q^T over the whole "
                                                   "face): use an implicit integrator (e.g. hht)")
    if mass.diagonal or node_blocks:
        md = mass.free_diag if mass.diagonal else equations.mass_free.diagonal()
        if not (md > 0).all():
            bad = int(equations.free[np.nonzero(~(md > 0))[0][0]])
            node = bad // model.dim
            owners = [g.name for g in model.cgroups if (g.conn == node).any()]
            where = f"node {node} (DOF {bad})" + (f", in element group(s) {owners}" if owners else ", in no element")
            key = (f"{s.key}integrator" if not owners else "foundation.mass" if owners[0] in mass.massless
                   else f"materials.{owners[0]}.density")
            raise SceneError(key, f"{s.integrator} (explicit) needs a positive mass at every free DOF: {where} has "
                                  "none (density 0, or [foundation] mass = false); give the region a density > 0 "
                                  "(for rock under a dam: [foundation] mass = true), or use an implicit integrator")
        if mass.diagonal:
            dtc, w = critical_time_step(K, mass_diag=md, damping=s.damping, omega_crit=Oc)
        else:
            dtc, w = critical_time_step(K, M=equations.mass_free, damping=s.damping, omega_crit=Oc,
                                        linear_solver=backend)
    else:
        dtc, w = critical_time_step(K, M=equations.mass_free, damping=s.damping, omega_crit=Oc,
                                    linear_solver=backend)
    hz = 1.0 / (2 * math.pi)
    stats.dt_limit = f"set by the highest frequency {w * hz:.4g} Hz with every joint sticking"
    if equations.explicit_water is not None:  # the dam and its compressible water together
        w_dam = w
        w, w_water = coupled_highest_frequency(K, md, equations.explicit_water)
        dtc = _step_bound(w, s.damping, Oc)
        what = "the water's elements (their Courant limit)" if w_water >= w_dam else "the dam"
        stats.dt_limit = (f"set by the highest frequency {w * hz:.4g} Hz of the dam and its water together (the dam "
                          f"alone {w_dam * hz:.4g} Hz with every joint sticking, the water alone on a rigid dam "
                          f"{w_water * hz:.4g} Hz): {what} set it")
    stats.dt_critical = dtc
    stats.omega_max = w
    if s.stable_step:
        return dtc
    if s.dt > s.stability_safety * dtc:
        raise SceneError(f"{s.key}dt", f"dt = {s.dt:.4g} s is above {s.stability_safety:g} x the critical time "
                                       f"step of {s.integrator}: dt_crit = {dtc:.4g} s ({stats.dt_limit}"
                                       + ("" if equations.explicit_water is not None else
                                          "; the joint penalty stiffnesses usually set it") + "). Use "
                                       f"dt <= {s.stability_safety * dtc:.4g} s or an implicit integrator")
    return dtc


def stable_step(interval: float, dt_critical: float, safety: float) -> tuple[float, int]:
    """The explicit step the program chooses (dt = "auto"): the largest ``h = interval / n`` (n whole) with
    ``h <= safety x dt_critical``, so that the steps land on the output grid ``interval`` (s). Returns (h, n)."""
    n = max(1, int(math.ceil(interval / (safety * dt_critical) - 1e-12)))
    return interval / n, n
