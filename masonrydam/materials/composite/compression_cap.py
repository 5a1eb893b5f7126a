"""The compression cap of the composite joint law: its strength curve and the fully softened start of a
cap return.

Cap ([LR97] eq. 8, [L96] with ``Cnn = 1``, ``Cn = 0``): ``f3 = t_n^2 + Css T^2 - sigma3(kappa3)^2`` (Pa^2),
with ``sigma_i = fc/3``, ``sigma_p = fc``, ``sigma_m = fc/2``, ``sigma_r = fc/7`` and kappa3 (m)::

    kappa < kp        : sigma_i + (sigma_p - sigma_i) (2 x - x^2),     x = kappa / kp
    kp <= kappa < km  : sigma_p + (sigma_m - sigma_p) y^2,             y = (kappa - kp) / (km - kp)
    kappa >= km       : sigma_r + (sigma_m - sigma_r) exp(m (kappa - km) / (sigma_m - sigma_r)),
                        m = 2 (sigma_m - sigma_p) / (km - kp)

(the thesis' ``sqrt(2x - x^2)`` hardening replaced by the parabola; ``km - kp`` from Gfc:
docs/masonry_softening.md, "The law in equations"). [LR97] Lourenco & Rots (1997), J. Eng. Mech. 123(7)
660-668; [L96] Lourenco (1996), PhD thesis, TU Delft, ch. 4.
"""
from __future__ import annotations

import cmath

from numba import njit

from .columns import W_CSS, W_FC, W_KN, W_KS1, W_KS2


@njit(cache=True)
def cap_strength(kap, fc, kp, dkm):
    """Cap strength sigma3(kappa3) (the module docstring); complex argument for complex-step derivatives."""
    si = fc / 3.0
    sp = fc
    sm = 0.5 * fc
    sr = fc / 7.0
    if kap.real < 0.0:
        # continuation below 0 (only met by Newton iterates): positive, C1 at 0, so that no
        # spurious root with kappa3 < 0 exists
        return si * cmath.exp(2.0 * (sp - si) / si * kap / kp)
    if kap.real < kp:
        x = kap / kp
        return si + (sp - si) * (2.0 * x - x * x)
    if kap.real < kp + dkm:
        y = (kap - kp) / dkm
        return sp + (sm - sp) * y * y
    m = 2.0 * (sm - sp) / dkm
    return sr + (sm - sr) * cmath.exp(m * (kap - kp - dkm) / (sm - sr))


@njit(cache=True)
def residual_cap_multiplier(tau1_tr, tau2_tr, tn_tr, w, ns):
    """``q = 2 kn lambda3`` of the cap-only return onto the residual cap ``sigma3 = fc/7`` (bisection
    on the decreasing ``t_n(q)^2 + Css T(q)^2 - sigma_r^2``): the fully softened start of a cap
    return."""
    css = w[W_CSS]
    r1 = css * w[W_KS1] / w[W_KN]
    r2 = css * w[W_KS2] / w[W_KN]
    sr2 = (w[W_FC] / 7.0) ** 2
    lo = 0.0
    hi = 1.0
    for it in range(200):
        a = tn_tr / (1.0 + hi)
        b1 = tau1_tr / (1.0 + r1 * hi)
        b2 = tau2_tr / (1.0 + r2 * hi)
        if a * a + css * (b1 * b1 + b2 * b2) <= sr2:
            break
        lo = hi
        hi *= 2.0
    for it in range(100):
        q = 0.5 * (lo + hi)
        a = tn_tr / (1.0 + q)
        b1 = tau1_tr / (1.0 + r1 * q)
        b2 = tau2_tr / (1.0 + r2 * q)
        if a * a + css * (b1 * b1 + b2 * b2) > sr2:
            lo = q
        else:
            hi = q
    return 0.5 * (lo + hi)
