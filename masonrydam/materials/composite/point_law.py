"""The composite joint law at one integration point (:func:`composite_point`, inlined into the interface
kernels of :mod:`masonrydam.elements.interface`): the elastic trial, the search over the return regions
(tension cut-off, Coulomb friction, compression cap, the corners tension/shear and shear/cap), the
converged return's tractions and state, and the consistent tangent.

Candidate active sets in this order: the single surfaces violated by the trial, then the corners; the
first whose multipliers are >= 0 and that satisfies the other surfaces is taken. Each is solved from the
trial, then from the fully softened state, and a corner also from the converged shear-only return
(docs/masonry_softening.md, "The law in equations"). Lourenco & Rots (1997), J. Eng. Mech. 123(7)
660-668; Simo & Hughes (1998), Computational Inelasticity, sec. 5.2.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...errors import STATUS_NAN, STATUS_OK
from ..plasticity import STATUS_BAD_MATERIAL
from .columns import (CAP, CAP_SOFTENING_FACTOR, ELASTIC, N_COMPOSITE_STATE, P_COHESION, P_CSS, P_DILATANCY_DECAY,
                      P_FC, P_GF_C, P_GF_I, P_GF_II, P_INV_SIGMA_U, P_KAPPA_P, P_KN, P_KS, P_KS2, P_OPEN_TANGENT,
                      P_RELAXATION_TIME, P_TAN_PHI0, P_TAN_PHI_R, P_TAN_PSI0, P_TENSILE_STRENGTH, P_TIME_STEP,
                      S_CODE, S_CRACKED, S_KAPPA1, S_KAPPA2, S_KAPPA3, S_PLASTIC_OPENING, S_PLASTIC_SLIP, SHEAR,
                      SHEAR_CAP, TENSION, TENSION_SHEAR, W_A1, W_A2, W_C, W_CSS, W_DD, W_DKM, W_FC, W_FT, W_INVSU,
                      W_KAP1, W_KAP2, W_KAP3, W_KN, W_KP, W_KS1, W_KS2, W_SIZE, W_TPHI0, W_TPHIR, W_TPSI0)
from .compression_cap import cap_strength, residual_cap_multiplier
from .dense_lu import lu_factor, lu_solve
from .local_newton import TOL_NEWTON, local_jacobian, local_newton, return_is_admissible
from .local_system import local_residual
from .parameters import first_bad_column
from .viscous_regularisation import duvaut_lions_relaxation

_TOL_ELASTIC = 1e-10  # a trial within this of a surface is elastic


@njit(cache=True)
def _write_failure(state_committed, state_trial, e, g, traction_out, C, ns):
    for j in range(N_COMPOSITE_STATE):
        state_trial[e, g, j] = state_committed[e, g, j]
    for i in range(ns + 1):
        traction_out[e, g, i] = np.nan
        for j in range(ns + 1):
            C[i, j] = 0.0


@njit(cache=True)
def composite_point(params, p, delta, ns, state_committed, state_trial, e, g, traction_out, C, want_tangent=True):
    """The composite interface law at point ``g`` of element ``e``.

    Parameters
    ----------
    params : float64 (n_sets, N_COMPOSITE_PARAMS); p : the row of this point.
    delta : float64 (n_elem, nip, ns+1): local relative displacement ``[s1, (s2,) n]`` (m) read at
        ``[e, g]``.
    ns : 1 (2D) or 2 (3D) shear components.
    state_committed : float64 (n_elem, nip, N_COMPOSITE_STATE), read only at ``[e, g]``.
    state_trial : same shape, written at ``[e, g]``.
    traction_out : float64 (n_elem, nip, ns+1), written at ``[e, g]``: ``[tau1, (tau2,) t_n]`` (Pa).
    C : float64 (ns+1, ns+1), out: the consistent tangent ``d t / d delta`` (Pa/m).
    want_tangent : bool; where False a plastic point's ``C`` is not computed (zeros, or the elastic part of the
        viscous tangent). Why: the consistent tangent is a complex-step Jacobian of the local system and a solve
        per component, and a line search evaluates forces only (the relaxed J4D wall ran 10 % faster without it).

    Returns
    -------
    STATUS_OK; STATUS_NAN for a non-finite input or result or a local return that did not converge;
    ``plasticity.STATUS_BAD_MATERIAL`` for an inadmissible parameter row. On failure the trial state
    is the committed one, the tractions NaN and the tangent zero.
    """
    n = ns + 1
    npar = params.shape[1]
    for j in range(npar):
        if not math.isfinite(params[p, j]):
            _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
    for j in range(n):
        if not math.isfinite(delta[e, g, j]):
            _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
    for j in range(N_COMPOSITE_STATE):
        if not math.isfinite(state_committed[e, g, j]):
            _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
    if first_bad_column(params, p) >= 0:
        _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
        return STATUS_BAD_MATERIAL

    ks1 = params[p, P_KS]
    kn = params[p, P_KN]
    ks2 = params[p, P_KS2] if ns == 2 else ks1
    ft = params[p, P_TENSILE_STRENGTH]
    c = params[p, P_COHESION]
    fc = params[p, P_FC]
    a1 = ft / params[p, P_GF_I] if ft > 0.0 else 0.0
    a2 = c / params[p, P_GF_II] if c > 0.0 else 0.0
    kap1 = state_committed[e, g, S_KAPPA1]
    kap2 = state_committed[e, g, S_KAPPA2]
    kap3 = state_committed[e, g, S_KAPPA3]

    # elastic trial
    tn_tr = kn * (delta[e, g, ns] - state_committed[e, g, S_PLASTIC_OPENING])
    tau1_tr = ks1 * (delta[e, g, 0] - state_committed[e, g, S_PLASTIC_SLIP])
    tau2_tr = ks2 * (delta[e, g, 1] - state_committed[e, g, S_PLASTIC_SLIP + 1]) if ns == 2 else 0.0
    T_tr = math.sqrt(tau1_tr * tau1_tr + tau2_tr * tau2_tr)
    eom = math.exp(-(a1 * kap1 + a2 * kap2))
    tphi = params[p, P_TAN_PHI_R] + (params[p, P_TAN_PHI0] - params[p, P_TAN_PHI_R]) * eom
    f1 = tn_tr - ft * eom
    f2 = T_tr + tn_tr * tphi - c * eom
    f3 = -1.0
    dkm = 0.0
    if fc > 0.0:
        dkm = CAP_SOFTENING_FACTOR * params[p, P_GF_C] / fc
        sb3 = cap_strength(complex(kap3, 0.0), fc, params[p, P_KAPPA_P], dkm).real
        f3 = (tn_tr * tn_tr + params[p, P_CSS] * T_tr * T_tr - sb3 * sb3) / (2.0 * fc)
    sref = max(abs(tn_tr), T_tr, ft, c, fc)
    if not sref > 0.0:
        sref = 1.0
    tol_e = _TOL_ELASTIC * sref
    cracked = state_committed[e, g, S_CRACKED]

    if f1 <= tol_e and f2 <= tol_e and f3 <= tol_e:
        for j in range(N_COMPOSITE_STATE):
            state_trial[e, g, j] = state_committed[e, g, j]
        state_trial[e, g, S_CODE] = float(ELASTIC)
        traction_out[e, g, 0] = tau1_tr
        if ns == 2:
            traction_out[e, g, 1] = tau2_tr
        traction_out[e, g, ns] = tn_tr
        for i in range(n):
            for j in range(n):
                C[i, j] = 0.0
        C[0, 0] = ks1
        if ns == 2:
            C[1, 1] = ks2
        C[ns, ns] = kn
        if not (math.isfinite(tn_tr) and math.isfinite(T_tr)):
            _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
        return STATUS_OK

    # ---- plastic: local constants and scratch
    w = np.empty(W_SIZE)
    w[W_KN] = kn
    w[W_KS1] = ks1
    w[W_KS2] = ks2
    w[W_FT] = ft
    w[W_A1] = a1
    w[W_C] = c
    w[W_A2] = a2
    w[W_TPHI0] = params[p, P_TAN_PHI0]
    w[W_TPHIR] = params[p, P_TAN_PHI_R]
    w[W_TPSI0] = params[p, P_TAN_PSI0]
    w[W_INVSU] = params[p, P_INV_SIGMA_U]
    w[W_DD] = params[p, P_DILATANCY_DECAY]
    w[W_FC] = fc
    w[W_CSS] = params[p, P_CSS] if fc > 0.0 else 0.0
    w[W_KP] = params[p, P_KAPPA_P]
    w[W_DKM] = dkm
    w[W_KAP1] = kap1
    w[W_KAP2] = kap2
    w[W_KAP3] = kap3
    tr = np.empty(3, dtype=np.complex128)
    tr[0] = complex(tau1_tr, 0.0)
    tr[1] = complex(tau2_tr, 0.0)
    tr[2] = complex(tn_tr, 0.0)
    x = np.empty(5)
    dx = np.empty(5)
    xn = np.empty(5)
    J = np.empty((5, 5))
    piv = np.empty(5, dtype=np.int64)
    cx = np.empty(5, dtype=np.complex128)
    R = np.empty(5, dtype=np.complex128)
    tau = np.empty(2, dtype=np.complex128)
    fv = np.empty(3, dtype=np.complex128)

    xs = np.zeros(5)
    have_xs = False
    found = False
    act1 = False
    act2 = False
    act3 = False
    code = ELASTIC
    for cand in range(5):
        if cand == 0:
            if not f1 > tol_e:
                continue
            act1, act2, act3, code = True, False, False, TENSION
        elif cand == 1:
            if not f2 > tol_e:
                continue
            act1, act2, act3, code = False, True, False, SHEAR
        elif cand == 2:
            if not f3 > tol_e:
                continue
            act1, act2, act3, code = False, False, True, CAP
        elif cand == 3:
            if not (f1 > tol_e or f2 > tol_e):
                continue
            act1, act2, act3, code = True, True, False, TENSION_SHEAR
        else:
            if fc <= 0.0 or not (f2 > tol_e or f3 > tol_e):
                continue
            act1, act2, act3, code = False, True, True, SHEAR_CAP
        for start in range(3):
            x[0] = tn_tr
            x[1] = T_tr
            x[2] = 0.0
            x[3] = 0.0
            x[4] = 0.0
            if start == 2:
                # a corner from the converged shear-only return
                if not (have_xs and (act1 or act3)):
                    break
                for i in range(5):
                    x[i] = xs[i]
            elif start == 1:
                # fully softened start (right of the root of a concave softening residual)
                if act3:
                    q = residual_cap_multiplier(tau1_tr, tau2_tr, tn_tr, w, ns)
                    x[0] = tn_tr / (1.0 + q)
                    t1q = tau1_tr / (1.0 + w[W_CSS] * ks1 / kn * q)
                    t2q = tau2_tr / (1.0 + w[W_CSS] * ks2 / kn * q)
                    x[1] = math.sqrt(t1q * t1q + t2q * t2q)
                    x[4] = q * fc
                if act1:
                    x[0] = 0.0
                    x[2] = max(tn_tr, 0.0)
                if act2:
                    x[1] = 0.0 if act1 else max(-tn_tr * w[W_TPHIR], 0.0)
                    x[3] = T_tr - x[1]
            if local_newton(x, tr, w, ns, act1, act2, act3, sref, J, piv, dx, xn, cx, R, tau, fv):
                if act2 and not (act1 or act3) and not have_xs:
                    have_xs = True
                    for i in range(5):
                        xs[i] = x[i]
                if return_is_admissible(x, tr, w, ns, act1, act2, act3, sref, cx, R, tau, fv):
                    found = True
                    break
        if found:
            break
    if not found:
        _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
        return STATUS_NAN

    # ---- converged return: tractions and state
    for i in range(5):
        cx[i] = complex(x[i], 0.0)
    local_residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv)
    tn = x[0]
    t1 = tau[0].real
    t2 = tau[1].real if ns == 2 else 0.0
    lam1 = x[2] / kn if act1 else 0.0
    lam2 = x[3] / ks1 if act2 else 0.0
    lam3 = x[4] / (2.0 * kn * fc) if act3 else 0.0
    k1n = kap1 + lam1
    k2n = kap2 + lam2
    k3n = kap3 + lam3 * 2.0 * math.sqrt(w[W_CSS] ** 2 * x[1] * x[1] + tn * tn)
    state_trial[e, g, S_CODE] = float(code)
    state_trial[e, g, S_CRACKED] = 1.0 if (cracked != 0.0 or k1n > 0.0 or k2n > 0.0) else 0.0
    state_trial[e, g, S_PLASTIC_SLIP] = delta[e, g, 0] - t1 / ks1
    state_trial[e, g, S_PLASTIC_SLIP + 1] = (delta[e, g, 1] - t2 / ks2) if ns == 2 else \
        state_committed[e, g, S_PLASTIC_SLIP + 1]
    state_trial[e, g, S_PLASTIC_OPENING] = delta[e, g, ns] - tn / kn
    state_trial[e, g, S_KAPPA1] = k1n
    state_trial[e, g, S_KAPPA2] = k2n
    state_trial[e, g, S_KAPPA3] = k3n
    traction_out[e, g, 0] = t1
    if ns == 2:
        traction_out[e, g, 1] = t2
    traction_out[e, g, ns] = tn

    # ---- consistent tangent: dx/d delta_j = -J^-1 dR/d delta_j; outputs by directional complex steps
    ot = params[p, P_OPEN_TANGENT]
    is_open = (act1 and abs(tn) <= TOL_NEWTON * sref * 10.0 and abs(x[1]) <= TOL_NEWTON * sref * 10.0)
    if not want_tangent:
        for i in range(n):
            for j in range(n):
                C[i, j] = 0.0
    elif is_open and ot != 0.0:
        for i in range(n):
            for j in range(n):
                C[i, j] = 0.0
        C[0, 0] = ot * ks1
        if ns == 2:
            C[1, 1] = ot * ks2
        C[ns, ns] = ot * kn
    else:
        h = 1e-20 * sref
        local_jacobian(x, tr, w, ns, act1, act2, act3, h, J, cx, R, tau, fv)
        if not lu_factor(J, piv, 5):
            _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
        trc = np.empty(3, dtype=np.complex128)
        for j in range(n):
            # delta_j moves the trial component j by k_j d delta_j; step h / k_j in delta_j
            kj = kn if j == ns else (ks1 if j == 0 else ks2)
            comp = 2 if j == ns else j
            for i in range(3):
                trc[i] = tr[i]
            trc[comp] = complex(tr[comp].real, h)
            for i in range(5):
                cx[i] = complex(x[i], 0.0)
            local_residual(cx, trc, w, ns, act1, act2, act3, R, tau, fv)
            for i in range(5):
                dx[i] = -R[i].imag  # = -h dR/d tr_comp
            lu_solve(J, piv, dx, 5)  # = h dx/d tr_comp
            for i in range(5):
                cx[i] = complex(x[i], dx[i])
            local_residual(cx, trc, w, ns, act1, act2, act3, R, tau, fv)
            C[0, j] = tau[0].imag / h * kj
            if ns == 2:
                C[1, j] = tau[1].imag / h * kj
            C[ns, j] = dx[0] / h * kj
    tau_relax = params[p, P_RELAXATION_TIME]
    dt = params[p, P_TIME_STEP]
    if tau_relax > 0.0:  # (dt = 0: no time to relax, the elastic trial, as Perzyna blocks do)
        duvaut_lions_relaxation(dt / tau_relax, delta, e, g, ns, ks1, ks2, kn, tau1_tr, tau2_tr, tn_tr,
                      state_committed, state_trial, traction_out, C)
    for i in range(n):
        if not math.isfinite(traction_out[e, g, i]):
            _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
        for j in range(n):
            if not math.isfinite(C[i, j]):
                _write_failure(state_committed, state_trial, e, g, traction_out, C, ns)
                return STATUS_NAN
    return STATUS_OK
