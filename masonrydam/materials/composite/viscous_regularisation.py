"""The Duvaut-Lions viscous regularisation of the composite joint law: over a step ``dt`` (s) the
tractions (Pa) and internal variables (m) of a point relax towards the inviscid return with the
relaxation time ``tau`` (s), by backward Euler; the tangent (Pa/m) likewise.

Simo & Hughes (1998), Computational Inelasticity, sec. 2.7; for cohesive interfaces Gao & Bower (2004),
Modelling Simul. Mater. Sci. Eng. 12, 453-463.
"""
from __future__ import annotations

from numba import njit

from .columns import S_KAPPA1, S_KAPPA2, S_KAPPA3, S_PLASTIC_OPENING, S_PLASTIC_SLIP


@njit(cache=True)
def duvaut_lions_relaxation(ratio, delta, e, g, ns, ks1, ks2, kn, tau1_tr, tau2_tr, tn_tr, state_committed, state_trial,
                  traction_out, C):
    """Viscous regularisation of Duvaut and Lions ([SH98] sec. 2.7; for cohesive interfaces
    [GB04]): over a step ``dt`` the tractions and internal variables relax towards the inviscid return
    (already in ``traction_out``, ``state_trial`` and ``C``) with the relaxation time ``tau``, by
    backward Euler::

        t = (t_trial + r t_inf) / (1 + r),   kappa = (kappa_n + r kappa_inf) / (1 + r),   r = dt / tau
        C = (K + r C_inf) / (1 + r)

    (``C`` is exact: ``t_trial = K (delta - delta_p,n)``). The plastic displacements follow from the
    tractions, ``delta_p = delta - K^-1 t``. As ``tau / dt -> 0`` this is the inviscid law; for a finite
    ``tau`` the tangent tends to the elastic one as ``dt`` shrinks, so a step cut makes the joint stable
    where a softening point would make the structure's tangent singular. The code and the cracked flag
    are the inviscid return's (the surface the point is flowing to)."""
    a = 1.0 / (1.0 + ratio)
    b = ratio * a
    k = (ks1, ks2, kn)
    t1 = a * tau1_tr + b * traction_out[e, g, 0]
    traction_out[e, g, 0] = t1
    state_trial[e, g, S_PLASTIC_SLIP] = delta[e, g, 0] - t1 / ks1
    if ns == 2:
        t2 = a * tau2_tr + b * traction_out[e, g, 1]
        traction_out[e, g, 1] = t2
        state_trial[e, g, S_PLASTIC_SLIP + 1] = delta[e, g, 1] - t2 / ks2
    tn = a * tn_tr + b * traction_out[e, g, ns]
    traction_out[e, g, ns] = tn
    state_trial[e, g, S_PLASTIC_OPENING] = delta[e, g, ns] - tn / kn
    for col in (S_KAPPA1, S_KAPPA2, S_KAPPA3):
        state_trial[e, g, col] = a * state_committed[e, g, col] + b * state_trial[e, g, col]
    for i in range(ns + 1):
        for j in range(ns + 1):
            C[i, j] *= b
        C[i, i] += a * (kn if i == ns else k[i])
