"""The local system of the composite law's return mapping: the three yield surfaces and the residual of an
active set.

Tension cut-off with exponential softening ``f1 = t_n - ft exp(-omega)`` ([LR97] eq. 3); Coulomb friction
with cohesion and friction softening and dilatancy ``f2 = T + t_n tan(phi) - c exp(-omega)``
([LR97] eqs. 5-7, [L96] sec. 4.3); compression cap ``f3`` ([LR97] eq. 8,
:mod:`~masonrydam.materials.composite.compression_cap`); the shared exponent
``omega = (ft / GfI) kappa1 + (c / GfII) kappa2``. Backward Euler ([SH98] sec. 5.2) in the unknowns
``[t_n, T, L1, L2, L3]`` (Pa), complex so that the Jacobian and the tangent are complex-step derivatives
[MSA03]. The equations: docs/masonry_softening.md ("The law in equations").

[LR97] Lourenco & Rots (1997), J. Eng. Mech. 123(7) 660-668; [L96] Lourenco (1996), PhD thesis, TU Delft,
ch. 4; [SH98] Simo & Hughes (1998), Computational Inelasticity, sec. 5.2; [MSA03] Martins, Sturdza &
Alonso (2003), ACM TOMS 29(3) 245-262.
"""
from __future__ import annotations

import cmath
import math

from numba import njit

from .columns import (W_A1, W_A2, W_C, W_CSS, W_DD, W_DKM, W_FC, W_FT, W_INVSU, W_KAP1, W_KAP2, W_KAP3, W_KN,
                      W_KP, W_KS1, W_KS2, W_TPHI0, W_TPHIR, W_TPSI0)
from .compression_cap import cap_strength


@njit(cache=True)
def local_residual(x, tr, w, ns, act1, act2, act3, R, tau, fv):
    """Residual of the local system of the active set ``(act1, act2, act3)``.

    ``x`` complex (5,): ``[t_n, T, L1, L2, L3]`` with the scaled multipliers ``L1 = kn lambda1``,
    ``L2 = ks1 lambda2``, ``L3 = 2 kn fc lambda3`` (all in Pa); ``tr`` complex (3,): trial
    ``[tau1, tau2, t_n]``. Writes ``R`` (5,) (Pa; an inactive multiplier has the row ``L_a = 0``),
    the shear tractions ``tau`` (2,) and the three yield functions ``fv`` (3,) (f3 / (2 fc); -1
    without a cap). Returns False where the shear denominators are not positive."""
    kn = w[W_KN]
    ks1 = w[W_KS1]
    ks2 = w[W_KS2]
    fc = w[W_FC]
    css = w[W_CSS]
    tn = x[0]
    T = x[1]
    L1 = x[2]
    L2 = x[3]
    L3 = x[4]
    lam1 = L1 / kn
    lam2 = L2 / ks1
    q3 = L3 / fc if fc > 0.0 else 0.0 * L3  # = 2 kn lambda3
    kap1 = w[W_KAP1] + lam1
    kap2 = w[W_KAP2] + lam2
    eom = cmath.exp(-(w[W_A1] * kap1 + w[W_A2] * kap2))
    s1 = w[W_FT] * eom
    s2 = w[W_C] * eom
    tphi = w[W_TPHIR] + (w[W_TPHI0] - w[W_TPHIR]) * eom
    gfac = 1.0 + tn * w[W_INVSU]
    if gfac.real <= 0.0:
        gfac = 0.0 * gfac
    tpsi = w[W_TPSI0] * gfac * cmath.exp(-w[W_DD] * kap2)

    ok = True
    e1 = 1.0 + css * (ks1 / kn) * q3
    e2 = 1.0 + css * (ks2 / kn) * q3
    zero_trial = tr[0].real == 0.0 and (ns == 1 or tr[1].real == 0.0)
    if act2:
        D1 = T * e1 + L2
        D2 = T * e2 + (ks2 / ks1) * L2
        if not (D1.real > 0.0 and (ns == 1 or D2.real > 0.0)):
            ok = False
        tau[0] = tr[0] * T / D1
        tau[1] = tr[1] * T / D2 if ns == 2 else 0.0 * T
        if zero_trial:
            G = -D1
        elif ns == 1:
            G = cmath.sqrt(tr[0] * tr[0]) - D1
        else:
            r2 = tr[1] * D1 / D2
            G = cmath.sqrt(tr[0] * tr[0] + r2 * r2) - D1
    else:
        tau[0] = tr[0] / e1
        tau[1] = tr[1] / e2 if ns == 2 else 0.0 * T
        if zero_trial:
            G = -T * e1
        elif ns == 1:
            G = cmath.sqrt(tr[0] * tr[0]) - T * e1
        else:
            r2 = tr[1] * e1 / e2
            G = cmath.sqrt(tr[0] * tr[0] + r2 * r2) - T * e1

    R[0] = tn - tr[2] + L1 + (kn / ks1) * L2 * tpsi + q3 * tn
    R[1] = G
    fv[0] = tn - s1
    fv[1] = T + tn * tphi - s2
    if fc > 0.0:
        lam3 = q3 / (2.0 * kn)
        kap3 = w[W_KAP3] + lam3 * 2.0 * cmath.sqrt(css * css * T * T + tn * tn)
        sb3 = cap_strength(kap3, fc, w[W_KP], w[W_DKM])
        fv[2] = (tn * tn + css * T * T - sb3 * sb3) / (2.0 * fc)
    else:
        fv[2] = -1.0 + 0.0 * tn
    R[2] = fv[0] if act1 else L1
    R[3] = fv[1] if act2 else L2
    R[4] = fv[2] if act3 else L3
    for i in range(5):
        if not (math.isfinite(R[i].real) and math.isfinite(R[i].imag)):
            ok = False
    return ok
