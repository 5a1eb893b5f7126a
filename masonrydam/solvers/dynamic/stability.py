"""Stability of the conditionally stable schemes: the critical time step and the check of a stage's dt.

A scheme with a stability bound ``Omega_crit`` (:attr:`~.schemes.Scheme.stability_bound`: central difference 2,
Newmark linear acceleration sqrt(12); Hughes 2000, sec. 9.1.2 and Table 9.1.1) is stable for
``omega_max h <= Omega_crit``, with ``omega_max`` (rad/s) the highest circular frequency of the model with every
joint sticking (the joint penalty springs usually set it); viscous damping lowers the bound.
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
    if w == 0:
        return math.inf, 0.0
    Oc = omega_crit
    if damping is not None and damping.active:
        xi = damping.alpha / (2 * w) + damping.beta * w / 2
        Oc = omega_crit * (math.sqrt(1 + xi * xi) - xi)
    return Oc / w, w



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
    if scheme.explicit and not mass.diagonal:
        raise SceneError(f"{s.key}integrator", f"{scheme.name} needs a diagonal mass matrix; the reservoir's "
                                               "added mass couples DOFs (Westergaard's m_a n n^T on an inclined "
                                               "face, or the acoustic water's rho Q H^-1 Q^T over the whole "
                                               "face): use an implicit integrator (e.g. hht)")
    if mass.diagonal:
        md = mass.free_diag
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
        dtc, w = critical_time_step(K, mass_diag=md, damping=s.damping, omega_crit=Oc)
    else:
        dtc, w = critical_time_step(K, M=equations.mass_free, damping=s.damping, omega_crit=Oc,
                                    linear_solver=backend)
    stats.dt_critical = dtc
    stats.omega_max = w
    if s.stable_step:
        return dtc
    if s.dt > s.stability_safety * dtc:
        raise SceneError(f"{s.key}dt", f"dt = {s.dt:.4g} s is above {s.stability_safety:g} x the critical time "
                                       f"step of {s.integrator}: dt_crit = {dtc:.4g} s (highest frequency "
                                       f"{w / (2 * math.pi):.4g} Hz with every joint sticking; the joint "
                                       f"penalty stiffnesses usually set it). Use dt <= "
                                       f"{s.stability_safety * dtc:.4g} s or an implicit integrator")
    return dtc


def stable_step(interval: float, dt_critical: float, safety: float) -> tuple[float, int]:
    """The explicit step the program chooses (dt = "auto"): the largest ``h = interval / n`` (n whole) with
    ``h <= safety x dt_critical``, so that the steps land on the output grid ``interval`` (s). Returns (h, n)."""
    n = max(1, int(math.ceil(interval / (safety * dt_critical) - 1e-12)))
    return interval / n, n
