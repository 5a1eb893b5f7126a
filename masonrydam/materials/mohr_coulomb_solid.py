"""Mohr-Coulomb plasticity of solids with cohesion hardening / softening, non-associated flow and
optional Perzyna viscosity, small strains, plane strain and 3D (continuum plasticity).

Not the joint law of :mod:`masonrydam.materials.mohr_coulomb` (interfaces): this is the continuum
law of rock, concrete and masonry treated as a continuum. Point-level numba kernels:
:func:`mohr_coulomb_solid_point` (one integration point; what an element kernel calls, with the
signature of :func:`masonrydam.materials.von_mises.von_mises_point`),
:func:`mohr_coulomb_solid_update` (a batch) and the Python wrapper :func:`mohr_coulomb_solid_evaluate`.
Parameter row: float64, ``N_MC_PARAMS`` columns in SI units, built by :func:`mohr_coulomb_solid_params`
(angles in degrees); state row: float64, ``N_MC_STATE`` columns, the shared ones of
:mod:`masonrydam.materials.plasticity` (codes CODE_ELASTIC, CODE_PLASTIC, CODE_APEX, CODE_EDGE_RIGHT,
CODE_EDGE_LEFT). Returns to the main plane, the two edges and the apex in principal stresses, in closed form
(de Souza Neto, Peric & Owen 2008, sec. 6.4.3 and 8.2; Chen & Han 1988), with the machinery of
:mod:`masonrydam.materials.principal_return`.

Theory: docs/continuum_nonlinearity.md, section "Mohr-Coulomb" (under "The plastic laws in equations").
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..errors import STATUS_OK
from .plasticity import (
    CODE_APEX, CODE_EDGE_LEFT, CODE_EDGE_RIGHT, CODE_ELASTIC, CODE_PLASTIC, N_COMMON_PARAMS, N_COMMON_STATE, P_E,
    P_NU, P_VISCOSITY, S_CODE, S_EQ_PLASTIC_STRAIN, S_PLASTIC_STRAIN, S_STRESS, W_SIG, PlasticLaw,
    bad_common_column, batch_update, check_param_table, copy_state_row, elastic_moduli, evaluate, finish_point,
    initial_state, isotropic_tangent, kink_distance, param_row, piecewise_root, point_inputs_status, point_moduli,
    point_trial, real_parameter, real_parameters, viscous_term,
)
from .principal_return import (
    W_PR_DSIG, W_PR_NEW, W_PR_TRIAL, principal_plastic_strain, principal_stress_out, principal_tangent,
    principal_trial,
)

__all__ = [
    "P_E", "P_NU", "P_VISCOSITY", "P_COHESION", "P_COHESION_HARDENING", "P_RESIDUAL_COHESION", "P_SIN_PHI",
    "P_COS_PHI", "P_SIN_PSI", "N_MC_PARAMS",
    "S_STRESS", "S_PLASTIC_STRAIN", "S_EQ_PLASTIC_STRAIN", "S_CODE", "N_MC_STATE",
    "CODE_ELASTIC", "CODE_PLASTIC", "CODE_APEX", "CODE_EDGE_RIGHT", "CODE_EDGE_LEFT",
    "mohr_coulomb_solid_point", "mohr_coulomb_solid_update", "mohr_coulomb_solid_evaluate",
    "mohr_coulomb_solid_params", "check_mohr_coulomb_solid_params", "mohr_coulomb_solid_initial_state",
    "return_stiffnesses", "mohr_coulomb_return",
]

P_COHESION = N_COMMON_PARAMS
P_COHESION_HARDENING = N_COMMON_PARAMS + 1
P_RESIDUAL_COHESION = N_COMMON_PARAMS + 2
P_SIN_PHI = N_COMMON_PARAMS + 3
P_COS_PHI = N_COMMON_PARAMS + 4
P_SIN_PSI = N_COMMON_PARAMS + 5
N_MC_PARAMS = N_COMMON_PARAMS + 6

N_MC_STATE = N_COMMON_STATE

PARAM_NAMES = {
    P_E: "youngs_modulus",
    P_NU: "poisson_ratio",
    P_VISCOSITY: "viscosity",
    P_COHESION: "cohesion",
    P_COHESION_HARDENING: "cohesion_hardening",
    P_RESIDUAL_COHESION: "residual_cohesion",
    P_SIN_PHI: "sin(friction_angle)",
    P_COS_PHI: "cos(friction_angle)",
    P_SIN_PSI: "sin(dilation_angle)",
}


# ----------------------------------------------------------------------------------------------
# principal-space return shared with the Tresca law
# ----------------------------------------------------------------------------------------------


@njit(cache=True)
def _plane(i, j, s):
    """Vector (1 + s) e_i - (1 - s) e_j of R^3 as a tuple."""
    v0 = 0.0
    v1 = 0.0
    v2 = 0.0
    if i == 0:
        v0 = 1.0 + s
    elif i == 1:
        v1 = 1.0 + s
    else:
        v2 = 1.0 + s
    if j == 0:
        v0 = -(1.0 - s)
    elif j == 1:
        v1 = -(1.0 - s)
    else:
        v2 = -(1.0 - s)
    return v0, v1, v2


@njit(cache=True)
def _de(N, K, G):
    """De N in principal space: K tr(N) 1 + 2G dev(N)."""
    lam_tr = (K - 2.0 * G / 3.0) * (N[0] + N[1] + N[2])
    return lam_tr + 2.0 * G * N[0], lam_tr + 2.0 * G * N[1], lam_tr + 2.0 * G * N[2]


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def return_stiffnesses(K, G, sphi, spsi):
    """Stiffnesses ``(a_main, a_right, a_left, b_apex, s_a)`` (Pa) of the returns (module docstring):
    the derivative of Phi with respect to the multiplier without hardening and viscosity
    (``a_R = 1 / w``), ``b_apex = 2 sin(phi) K`` and ``s_a`` (sin(psi), or sin(phi) for psi = 0).
    Admissible hardening H: ``a_R + k H > 0`` and, if sin(phi) > 0, ``b_apex + k H / (2 s_a) > 0``,
    with ``k = 4 cos^2(phi)`` (Mohr-Coulomb) or 1 (Tresca)."""
    n13 = _plane(0, 2, sphi)
    r13 = _de(_plane(0, 2, spsi), K, G)
    a = _dot(n13, r13)
    out_r = 0.0
    out_l = 0.0
    for side in range(2):
        if side == 0:
            nb = _plane(0, 1, sphi)
            rb = _de(_plane(0, 1, spsi), K, G)
        else:
            nb = _plane(1, 2, sphi)
            rb = _de(_plane(1, 2, spsi), K, G)
        a00 = a
        a01 = _dot(n13, rb)
        a10 = _dot(nb, r13)
        a11 = _dot(nb, rb)
        det = a00 * a11 - a01 * a10
        w = (a11 - a01 - a10 + a00) / det
        if side == 0:
            out_r = 1.0 / w
        else:
            out_l = 1.0 / w
    s_a = spsi if spsi > 0.0 else sphi
    return a, out_r, out_l, 2.0 * sphi * K, s_a


@njit(cache=True)
def _elastic_out(work, p_tr, K, G, want_tangent):
    for i in range(3):
        work[W_SIG + i] += p_tr
    if want_tangent:
        isotropic_tangent(work, K, 2.0 * G)


@njit(cache=True)
def mohr_coulomb_return(work, state_committed, state_trial, k, K, G, p_tr, sphi, spsi, k_y, k_k, y0, h, y_res, flow,
                     eta_dt, want_tangent):
    """Return mapping of the Mohr-Coulomb pyramid in principal stresses (module docstring), shared
    with :mod:`masonrydam.materials.tresca`.

    The yield planes are ``Phi_ij = (1 + sphi) sigma_i - (1 - sphi) sigma_j - k_y y(kappa)``, the
    strength ``y(kappa) = max(y0 + h kappa, y_res)`` and ``kappa_dot = k_k gamma_dot`` (Mohr-Coulomb:
    y = c, k_y = k_k = 2 cos(phi); Tresca: y = sigma_y, k_y = k_k = 1, sphi = spsi = 0).

    Call after :func:`masonrydam.materials.plasticity.point_trial` (trial deviator in ``work[W_SIG:]``,
    mean stress ``p_tr``) and ``copy_state_row``; ``flow, eta_dt`` from ``viscous_term``. Writes the
    3D stress to ``work[W_SIG:]``, the tangent (``want_tangent``) to ``work[W_D:]``, and the plastic
    strain, ``kappa`` (``S_EQ_PLASTIC_STRAIN``) and ``S_CODE`` to ``state_trial[k]``. Returns the code.
    """
    kappa_n = state_committed[k, S_EQ_PLASTIC_STRAIN]
    y_n = y0 + h * kappa_n
    if y_n < y_res:
        y_n = y_res
    principal_trial(work, p_tr)
    t0 = work[W_PR_TRIAL + 0]
    t1 = work[W_PR_TRIAL + 1]
    t2 = work[W_PR_TRIAL + 2]
    n13 = _plane(0, 2, sphi)
    f_tr = n13[0] * t0 + n13[2] * t2 - k_y * y_n
    if not (flow and f_tr > 0.0):
        state_trial[k, S_CODE] = CODE_ELASTIC
        _elastic_out(work, p_tr, K, G, want_tangent)
        return CODE_ELASTIC

    v = eta_dt
    kh = k_y * k_k
    r13 = _de(_plane(0, 2, spsi), K, G)
    a = _dot(n13, r13)
    s_kink = kink_distance(h, y0, y_res, kappa_n) / k_k
    code = CODE_PLASTIC
    # ---- main plane
    s, first = piecewise_root(f_tr, a + v + kh * h, a + v, s_kink)
    hv = (kh * h if first else 0.0) + v
    n0 = t0 - s * r13[0]
    n1 = t1 - s * r13[1]
    n2 = t2 - s * r13[2]
    dgam = s
    if n0 >= n1 and n1 >= n2:
        work[W_PR_NEW + 0] = n0
        work[W_PR_NEW + 1] = n1
        work[W_PR_NEW + 2] = n2
        if want_tangent:
            d = 1.0 / (a + hv)
            for i in range(3):
                for j in range(3):
                    work[W_PR_DSIG + 3 * i + j] = (1.0 if i == j else 0.0) - r13[i] * n13[j] * d
    else:
        # ---- edge
        right = (1.0 - spsi) * t0 - 2.0 * t1 + (1.0 + spsi) * t2 > 0.0
        if right:
            nb = _plane(0, 1, sphi)
            rb = _de(_plane(0, 1, spsi), K, G)
        else:
            nb = _plane(1, 2, sphi)
            rb = _de(_plane(1, 2, spsi), K, G)
        fb = nb[0] * t0 + nb[1] * t1 + nb[2] * t2 - k_y * y_n
        a00 = a
        a01 = _dot(n13, rb)
        a10 = _dot(nb, r13)
        a11 = _dot(nb, rb)
        det = a00 * a11 - a01 * a10
        # u = A^-1 1, z = A^-1 Phi_tr
        u0 = (a11 - a01) / det
        u1 = (a00 - a10) / det
        z0 = (a11 * f_tr - a01 * fb) / det
        z1 = (a00 * fb - a10 * f_tr) / det
        w = u0 + u1
        r0 = (z0 + z1) / w
        if r0 > 0.0:
            s, first = piecewise_root(r0, 1.0 / w + v + kh * h, 1.0 / w + v, s_kink)
        else:  # only by rounding
            s = 0.0
            first = s_kink > 0.0
        y_new = y_n + h * k_k * s if first else y_res
        cterm = k_y * (y_new - y_n) + v * s
        x0 = z0 - cterm * u0
        x1 = z1 - cterm * u1
        n0 = t0 - x0 * r13[0] - x1 * rb[0]
        n1 = t1 - x0 * r13[1] - x1 * rb[1]
        n2 = t2 - x0 * r13[2] - x1 * rb[2]
        # valid: sigma_1 stays the largest (right edge, sigma_2 = sigma_3) or sigma_3 the smallest (left
        # edge, sigma_1 = sigma_2); phi = 0 has no apex and every edge return is valid
        if right:
            valid = n0 >= n1 and n0 >= n2
        else:
            valid = n2 <= n0 and n2 <= n1
        if valid or sphi <= 0.0:
            code = CODE_EDGE_RIGHT if right else CODE_EDGE_LEFT
            dgam = s
            hv = (kh * h if first else 0.0) + v
            work[W_PR_NEW + 0] = n0
            work[W_PR_NEW + 1] = n1
            work[W_PR_NEW + 2] = n2
            if want_tangent:
                # M = A + hv 1 1^T; Dsig = I - R M^-1 N^T
                m00 = a00 + hv
                m01 = a01 + hv
                m10 = a10 + hv
                m11 = a11 + hv
                dm = m00 * m11 - m01 * m10
                i00 = m11 / dm
                i01 = -m01 / dm
                i10 = -m10 / dm
                i11 = m00 / dm
                for i in range(3):
                    c0 = r13[i] * i00 + rb[i] * i10
                    c1 = r13[i] * i01 + rb[i] * i11
                    for j in range(3):
                        work[W_PR_DSIG + 3 * i + j] = (1.0 if i == j else 0.0) - c0 * n13[j] - c1 * nb[j]
        else:
            # ---- apex (sphi > 0)
            code = CODE_APEX
            s_a = spsi if spsi > 0.0 else sphi
            g0 = 0.0
            dg0 = (0.0, 0.0, 0.0)
            if not spsi > 0.0:
                g_r = (t0 - p_tr) / (2.0 * G)
                g_l = (p_tr - t2) / (2.0 * G)
                if g_r >= g_l:
                    g0 = g_r
                    dg0 = ((1.0 - 1.0 / 3.0) / (2.0 * G), (-1.0 / 3.0) / (2.0 * G), (-1.0 / 3.0) / (2.0 * G))
                else:
                    g0 = g_l
                    dg0 = ((1.0 / 3.0) / (2.0 * G), (1.0 / 3.0) / (2.0 * G), (1.0 / 3.0 - 1.0) / (2.0 * G))
            kappa0 = kappa_n + k_k * g0
            y_0 = y0 + h * kappa0
            if y_0 < y_res:
                y_0 = y_res
            r0 = 2.0 * sphi * p_tr - k_y * y_0 - v * g0
            b2 = 2.0 * sphi * K + v / (2.0 * s_a)
            b1 = b2 + kh * h / (2.0 * s_a)
            xk = kink_distance(h, y0, y_res, kappa0) * 2.0 * s_a / k_k
            if r0 > 0.0:
                x, first = piecewise_root(r0, b1, b2, xk)
            else:  # only by rounding: the trial is on the apex
                x = 0.0
                first = xk > 0.0
            p_new = p_tr - K * x
            dgam = g0 + x / (2.0 * s_a)
            work[W_PR_NEW + 0] = p_new
            work[W_PR_NEW + 1] = p_new
            work[W_PR_NEW + 2] = p_new
            if want_tangent:
                b = b1 if first else b2
                q = (kh * h if first else 0.0) + v
                for j in range(3):
                    dx = (2.0 * sphi / 3.0 - q * dg0[j]) / b
                    dp = 1.0 / 3.0 - K * dx
                    for i in range(3):
                        work[W_PR_DSIG + 3 * i + j] = dp

    principal_plastic_strain(work, state_trial, k, S_PLASTIC_STRAIN, K, G)
    state_trial[k, S_EQ_PLASTIC_STRAIN] = kappa_n + k_k * dgam
    state_trial[k, S_CODE] = code
    if want_tangent:
        principal_tangent(work, K, G)  # reads W_PR_DSIG (inside W_SIG): before the stress is written
    principal_stress_out(work, W_PR_NEW, W_SIG)
    return code


# ----------------------------------------------------------------------------------------------
# point and batch kernels
# ----------------------------------------------------------------------------------------------


@njit(cache=True)
def _bad_column(params, p):
    """First inadmissible parameter column of row ``p``, or -2 if all are fine."""
    bad = bad_common_column(params, p)
    if bad != -2:
        return bad
    c0 = params[p, P_COHESION]
    h = params[p, P_COHESION_HARDENING]
    sphi = params[p, P_SIN_PHI]
    cphi = params[p, P_COS_PHI]
    spsi = params[p, P_SIN_PSI]
    if not (0.0 <= sphi < 1.0):
        return P_SIN_PHI
    if not (cphi > 0.0 and abs(sphi * sphi + cphi * cphi - 1.0) <= 1.0e-12):
        return P_COS_PHI
    if not (0.0 <= spsi <= sphi):
        return P_SIN_PSI
    if not (c0 >= 0.0 and (c0 > 0.0 or sphi > 0.0)):
        return P_COHESION
    if not (0.0 <= params[p, P_RESIDUAL_COHESION] <= c0):
        return P_RESIDUAL_COHESION
    K, G = point_moduli(params, p)
    a_m, a_r, a_l, b_ap, s_a = return_stiffnesses(K, G, sphi, spsi)
    kh = 4.0 * cphi * cphi * h
    if not (a_m + kh > 0.0 and a_r + kh > 0.0 and a_l + kh > 0.0):
        return P_COHESION_HARDENING
    if sphi > 0.0 and not (b_ap + kh / (2.0 * s_a) > 0.0):
        return P_COHESION_HARDENING
    return -2


@njit(cache=True)
def mohr_coulomb_solid_point(eps, params, p, state_committed, state_trial, k, dt, want_tangent, sig, D, work):
    """Return mapping of the Mohr-Coulomb law at one integration point (module docstring).

    Arguments, outputs and status as :func:`masonrydam.materials.von_mises.von_mises_point`, with
    ``params`` (m, N_MC_PARAMS) and states (n, N_MC_STATE); the tangent ``D`` is non-symmetric for
    non-associated flow.
    """
    status = point_inputs_status(eps, params, p, N_MC_PARAMS, state_committed, state_trial, k, N_MC_STATE, dt,
                                 _bad_column(params, p), want_tangent, sig, D, work)
    if status != STATUS_OK:
        return status
    K, G, p_tr = point_trial(eps, params, p, state_committed, k, work)
    flow, eta_dt = viscous_term(params[p, P_VISCOSITY], dt)
    copy_state_row(state_committed, state_trial, k, N_MC_STATE)
    k2 = 2.0 * params[p, P_COS_PHI]
    mohr_coulomb_return(work, state_committed, state_trial, k, K, G, p_tr, params[p, P_SIN_PHI], params[p, P_SIN_PSI],
                     k2, k2, params[p, P_COHESION], params[p, P_COHESION_HARDENING], params[p, P_RESIDUAL_COHESION],
                     flow, eta_dt, want_tangent)
    return finish_point(work, state_committed, state_trial, k, N_MC_STATE, want_tangent, sig, D)


@njit(cache=True)
def mohr_coulomb_solid_update(strain, params, state_committed, state_trial, stress_out, tangent_out, dt, want_tangent,
                              info):
    """Batch Mohr-Coulomb update: :func:`mohr_coulomb_solid_point` for every row.

    Arguments (those of :func:`masonrydam.materials.plasticity.batch_update` less ``point``) and
    return value as :func:`masonrydam.materials.von_mises.von_mises_update`, with ``params``
    (n, N_MC_PARAMS) and states (n, N_MC_STATE).
    """
    return batch_update(mohr_coulomb_solid_point, strain, params, state_committed, state_trial, stress_out,
                        tangent_out, dt, want_tangent, info)


# ----------------------------------------------------------------------------------------------
# Python side
# ----------------------------------------------------------------------------------------------

_LAW = "Mohr-Coulomb (solid)"
_TABLES = PlasticLaw(_LAW, N_MC_PARAMS, N_MC_STATE, PARAM_NAMES)


def _check_plastic(E, nu, c0, h, c_res, eta_v, sphi, cphi, spsi, where=""):
    K, G = elastic_moduli(E, nu)
    if not 0.0 <= sphi < 1.0:
        raise ValueError(f"{_LAW} parameter friction_angle must be in [0, 90) degrees{where} "
                         f"(sin(friction_angle) = {sphi!r})")
    if not (cphi > 0.0 and abs(sphi * sphi + cphi * cphi - 1.0) <= 1.0e-12):
        raise ValueError(f"{_LAW} parameter friction_angle: cos(friction_angle) = {cphi!r} does not match "
                         f"sin(friction_angle) = {sphi!r}{where}")
    if not 0.0 <= spsi <= sphi:
        raise ValueError(f"{_LAW} parameter dilation_angle must satisfy 0 <= dilation_angle <= friction_angle"
                         f"{where} (sin(dilation_angle) = {spsi!r}, sin(friction_angle) = {sphi!r})")
    if not c0 >= 0.0:
        raise ValueError(f"{_LAW} parameter cohesion must be >= 0 (Pa){where}, got {c0!r}")
    if c0 == 0.0 and sphi == 0.0:
        raise ValueError(f"{_LAW} parameter cohesion must be > 0 when the friction angle is 0 (no strength){where}")
    if not 0.0 <= c_res <= c0:
        raise ValueError(
            f"{_LAW} parameter residual_cohesion must satisfy 0 <= residual_cohesion <= cohesion = {c0!r} Pa"
            f"{where}, got {c_res!r}"
        )
    a_m, a_r, a_l, b_ap, s_a = return_stiffnesses(K, G, sphi, spsi)
    k = 4.0 * cphi * cphi
    a_min = min(a_m, a_r, a_l)
    if not a_min + k * h > 0.0:
        raise ValueError(
            f"{_LAW} parameter cohesion_hardening = {h!r} Pa is too steep a softening{where}: "
            f"a + 4 cos^2(phi) cohesion_hardening must be > 0 for the plane and edge returns, i.e. "
            f"cohesion_hardening > {-a_min / k!r} Pa"
        )
    if sphi > 0.0 and not b_ap + k * h / (2.0 * s_a) > 0.0:
        raise ValueError(
            f"{_LAW} parameter cohesion_hardening = {h!r} Pa is too steep a softening{where}: "
            f"2 sin(phi) K + 2 cos^2(phi) cohesion_hardening / s_a must be > 0 (apex return; s_a = sin(psi), "
            f"or sin(phi) when the dilation angle is 0), i.e. cohesion_hardening > {-b_ap * 2.0 * s_a / k!r} Pa"
        )
    if not eta_v >= 0.0:
        raise ValueError(f"{_LAW} parameter viscosity must be >= 0 (Pa s){where}, got {eta_v!r}")


def check_mohr_coulomb_solid_params(params) -> np.ndarray:
    """Validate a parameter table (n, N_MC_PARAMS) or row; returns it as a float64 2D array.
    Raises ValueError naming the parameter (and the row of a table)."""
    return check_param_table(_TABLES, params, _check_row)


def _check_row(row, where):
    _check_plastic(*(float(row[c]) for c in (P_E, P_NU, P_COHESION, P_COHESION_HARDENING, P_RESIDUAL_COHESION,
                                              P_VISCOSITY, P_SIN_PHI, P_COS_PHI, P_SIN_PSI)), where)


def mohr_coulomb_solid_params(
    youngs_modulus: float,
    poisson_ratio: float,
    cohesion: float,
    friction_angle_deg: float,
    dilation_angle_deg: float | None = None,
    cohesion_hardening: float = 0.0,
    residual_cohesion: float = 0.0,
    viscosity: float = 0.0,
) -> np.ndarray:
    """Validated parameter row (N_MC_PARAMS,) of the Mohr-Coulomb solid law.

    Parameters
    ----------
    youngs_modulus : E (Pa), > 0.
    poisson_ratio : nu, -1 < nu < 0.5.
    cohesion : c (Pa), >= 0 (> 0 when phi = 0).
    friction_angle_deg : phi (degrees), 0 <= phi < 90.
    dilation_angle_deg : psi (degrees), 0 <= psi <= phi; None = phi (associated flow).
    cohesion_hardening : H (Pa), slope of c against eps_bar (eps_bar_dot = 2 cos(phi) gamma_dot);
        negative for softening, with the limits of the module docstring.
    residual_cohesion : c_r (Pa), 0 <= c_r <= c; softening stops there.
    viscosity : Perzyna viscosity eta (Pa s), >= 0; 0 is rate independent.

    Raises
    ------
    ValueError naming the parameter and its value.
    """
    v = real_parameters(_TABLES, {
        "youngs_modulus": youngs_modulus,
        "poisson_ratio": poisson_ratio,
        "cohesion": cohesion,
        "cohesion_hardening": cohesion_hardening,
        "residual_cohesion": residual_cohesion,
        "viscosity": viscosity,
    })
    phi = real_parameter(_LAW, "friction_angle", friction_angle_deg)
    psi = phi if dilation_angle_deg is None else real_parameter(_LAW, "dilation_angle", dilation_angle_deg)
    if not 0.0 <= phi < 90.0:
        raise ValueError(f"{_LAW} parameter friction_angle must be in [0, 90) degrees, got {phi!r}")
    if not 0.0 <= psi <= phi:
        raise ValueError(
            f"{_LAW} parameter dilation_angle must satisfy 0 <= dilation_angle <= friction_angle = {phi!r} "
            f"degrees, got {psi!r}"
        )
    sphi, cphi = math.sin(math.radians(phi)), math.cos(math.radians(phi))
    spsi = sphi if psi == phi else math.sin(math.radians(psi))
    _check_plastic(v["youngs_modulus"], v["poisson_ratio"], v["cohesion"], v["cohesion_hardening"],
                   v["residual_cohesion"], v["viscosity"], sphi, cphi, spsi)
    cols = {col: v[name] for col, name in PARAM_NAMES.items() if name in v}
    cols.update({P_SIN_PHI: sphi, P_COS_PHI: cphi, P_SIN_PSI: spsi})
    return param_row(_TABLES, cols)


def mohr_coulomb_solid_initial_state(n: int) -> np.ndarray:
    """Virgin state (n, N_MC_STATE)."""
    return initial_state(_TABLES, n)


def mohr_coulomb_solid_evaluate(strain, params, state_committed, dt: float = 0.0, want_tangent: bool = True):
    """Python wrapper of :func:`mohr_coulomb_solid_update` (as
    :func:`masonrydam.materials.von_mises.von_mises_evaluate`): returns
    ``(stress (n, ns), tangent (n, ns, ns) or None, state_trial (n, N_MC_STATE))``.

    Raises ValueError for a bad shape, parameter or dt, masonrydam.errors.NumericalError for a
    non-finite strain, state or result."""
    return evaluate(_TABLES, mohr_coulomb_solid_update, check_mohr_coulomb_solid_params, strain, params,
                    state_committed, dt, want_tangent)
