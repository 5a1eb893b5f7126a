"""Drucker-Prager plasticity with cohesion hardening / softening, non-associated flow and optional
Perzyna viscosity, small strains, plane strain and 3D (continuum plasticity).

Point-level numba kernels: :func:`drucker_prager_point` (one integration point; what an element
kernel calls), :func:`drucker_prager_update` (a batch) and the Python wrapper
:func:`drucker_prager_evaluate`. Parameter row: float64, ``N_DP_PARAMS`` columns in SI units, built by
:func:`drucker_prager_params`, which computes the three cone coefficients from the Mohr-Coulomb angles
(``match`` of :func:`drucker_prager_coefficients`: outer, inner or plane-strain cone); state row: float64,
``N_DP_STATE`` columns, the shared ones of :mod:`masonrydam.materials.plasticity` (codes CODE_ELASTIC,
CODE_PLASTIC on the cone, CODE_APEX). Cone and apex returns in closed form with their consistent tangent
(de Souza Neto, Peric & Owen 2008, sec. 8.3, boxes 8.8-8.9).

Theory: docs/continuum_nonlinearity.md, section "Drucker-Prager" (under "The plastic laws in equations").
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..errors import STATUS_OK
from .plasticity import (
    CODE_APEX, CODE_ELASTIC, CODE_PLASTIC, N_COMMON_PARAMS, N_COMMON_STATE, P_E, P_NU, P_VISCOSITY, S_CODE,
    S_EQ_PLASTIC_STRAIN, S_PLASTIC_STRAIN, S_STRESS, SQRT2, SQRT3, W_D, W_N, W_SIG, PlasticLaw, bad_common_column,
    batch_update, check_param_table, copy_state_row, elastic_moduli, evaluate, finish_point, initial_state,
    isotropic_tangent, kink_distance, param_row, piecewise_root, point_inputs_status, point_moduli, point_trial,
    real_parameter, real_parameters, tensor_norm, viscous_term,
)

__all__ = [
    "P_E", "P_NU", "P_VISCOSITY", "P_COHESION", "P_COHESION_HARDENING", "P_RESIDUAL_COHESION",
    "P_FRICTION_COEF", "P_COHESION_COEF", "P_DILATANCY_COEF", "N_DP_PARAMS",
    "S_STRESS", "S_PLASTIC_STRAIN", "S_EQ_PLASTIC_STRAIN", "S_CODE", "N_DP_STATE",
    "CODE_ELASTIC", "CODE_PLASTIC", "CODE_APEX", "MATCHES",
    "drucker_prager_point", "drucker_prager_update", "drucker_prager_evaluate", "drucker_prager_params",
    "drucker_prager_coefficients", "check_drucker_prager_params", "drucker_prager_initial_state",
]

P_COHESION = N_COMMON_PARAMS
P_COHESION_HARDENING = N_COMMON_PARAMS + 1
P_RESIDUAL_COHESION = N_COMMON_PARAMS + 2
P_FRICTION_COEF = N_COMMON_PARAMS + 3
P_COHESION_COEF = N_COMMON_PARAMS + 4
P_DILATANCY_COEF = N_COMMON_PARAMS + 5
N_DP_PARAMS = N_COMMON_PARAMS + 6

N_DP_STATE = N_COMMON_STATE

MATCHES = ("outer", "inner", "plane_strain")

PARAM_NAMES = {
    P_E: "youngs_modulus",
    P_NU: "poisson_ratio",
    P_VISCOSITY: "viscosity",
    P_COHESION: "cohesion",
    P_COHESION_HARDENING: "cohesion_hardening",
    P_RESIDUAL_COHESION: "residual_cohesion",
    P_FRICTION_COEF: "friction coefficient eta (friction_angle)",
    P_COHESION_COEF: "cohesion coefficient xi (friction_angle)",
    P_DILATANCY_COEF: "dilatancy coefficient eta_bar (dilation_angle)",
}


@njit(cache=True)
def _bad_column(params, p):
    """First inadmissible parameter column of row ``p``, or -2 if all are fine."""
    bad = bad_common_column(params, p)
    if bad != -2:
        return bad
    c0 = params[p, P_COHESION]
    eta = params[p, P_FRICTION_COEF]
    xi = params[p, P_COHESION_COEF]
    etab = params[p, P_DILATANCY_COEF]
    h = params[p, P_COHESION_HARDENING]
    if not eta >= 0.0:
        return P_FRICTION_COEF
    if not xi > 0.0:
        return P_COHESION_COEF
    if not (0.0 <= etab <= eta):
        return P_DILATANCY_COEF
    if not (c0 >= 0.0 and (c0 > 0.0 or eta > 0.0)):
        return P_COHESION
    if not (0.0 <= params[p, P_RESIDUAL_COHESION] <= c0):
        return P_RESIDUAL_COHESION
    K, G = point_moduli(params, p)
    if not (G + K * eta * etab + xi * xi * h > 0.0):
        return P_COHESION_HARDENING
    if eta > 0.0:
        ea = etab if etab > 0.0 else eta
        if not (K * eta * ea + xi * xi * h > 0.0):
            return P_COHESION_HARDENING
    return -2


@njit(cache=True)
def drucker_prager_point(eps, params, p, state_committed, state_trial, k, dt, want_tangent, sig, D, work):
    """Return mapping of the Drucker-Prager law at one integration point (module docstring).

    Arguments, outputs and status as :func:`masonrydam.materials.von_mises.von_mises_point`, with
    ``params`` (m, N_DP_PARAMS) and states (n, N_DP_STATE); the tangent ``D`` is non-symmetric on the
    cone for non-associated flow.
    """
    status = point_inputs_status(eps, params, p, N_DP_PARAMS, state_committed, state_trial, k, N_DP_STATE, dt,
                                 _bad_column(params, p), want_tangent, sig, D, work)
    if status != STATUS_OK:
        return status

    c0 = params[p, P_COHESION]
    h = params[p, P_COHESION_HARDENING]
    c_res = params[p, P_RESIDUAL_COHESION]
    eta = params[p, P_FRICTION_COEF]
    xi = params[p, P_COHESION_COEF]
    etab = params[p, P_DILATANCY_COEF]
    K, G, p_tr = point_trial(eps, params, p, state_committed, k, work)
    G2 = 2.0 * G
    s_norm = tensor_norm(work, W_SIG)
    sj = s_norm / SQRT2  # sqrt(J2) of the trial
    eb_n = state_committed[k, S_EQ_PLASTIC_STRAIN]
    c_n = c0 + h * eb_n
    if c_n < c_res:
        c_n = c_res
    phi_tr = sj + eta * p_tr - xi * c_n
    flow, eta_dt = viscous_term(params[p, P_VISCOSITY], dt)
    # unit deviatoric direction of the trial (0 for a hydrostatic trial)
    inv = 1.0 / s_norm if s_norm > 0.0 else 0.0
    for i in range(6):
        work[W_N + i] = work[W_SIG + i] * inv

    copy_state_row(state_committed, state_trial, k, N_DP_STATE)
    if flow and phi_tr > 0.0:
        a2 = G + K * eta * etab + eta_dt
        a1 = a2 + xi * xi * h
        dg, first = piecewise_root(phi_tr, a1, a2, kink_distance(h, c0, c_res, eb_n) / xi)
        if eta <= 0.0 or sj - G * dg >= 0.0:
            # ---- return to the smooth cone
            a = a1 if first else a2
            theta = 1.0 - G * dg / sj  # sj > 0 here (sj >= G dg > 0, or eta = 0 and sj > xi c >= 0)
            pn = p_tr - K * etab * dg
            c_n_eps = dg / SQRT2  # d eps_p = dg (s_tr / (2 sqrt(J2_tr)) + etab/3 1) = dg (n / sqrt(2) + etab/3 1)
            for i in range(6):
                n_i = work[W_N + i]
                if i < 3:
                    state_trial[k, S_PLASTIC_STRAIN + i] += c_n_eps * n_i + dg * etab / 3.0
                else:
                    state_trial[k, S_PLASTIC_STRAIN + i] += 2.0 * c_n_eps * n_i
                work[W_SIG + i] *= theta
            for i in range(3):
                work[W_SIG + i] += pn
            state_trial[k, S_EQ_PLASTIC_STRAIN] = eb_n + xi * dg
            state_trial[k, S_CODE] = CODE_PLASTIC
            if want_tangent:
                isotropic_tangent(work, K, G2 * theta)
                cnn = 2.0 * G * G * (dg / sj - 1.0 / a)
                cn1 = -SQRT2 * G * K / a
                c11 = -K * K * eta * etab / a
                for i in range(6):
                    n_i = work[W_N + i]
                    one_i = 1.0 if i < 3 else 0.0
                    for j in range(6):
                        n_j = work[W_N + j]
                        one_j = 1.0 if j < 3 else 0.0
                        work[W_D + 6 * i + j] += (cnn * n_i * n_j + cn1 * (eta * n_i * one_j + etab * one_i * n_j)
                                                  + c11 * one_i * one_j)
        else:
            # ---- return to the apex
            ea = etab if etab > 0.0 else eta
            g0 = sj * (1.0 - etab / ea) / G
            eb0 = eb_n + xi * g0
            c_0 = c0 + h * eb0
            if c_0 < c_res:
                c_0 = c_res
            r0 = eta * p_tr - xi * c_0 - eta_dt * g0
            b2 = eta * K + eta_dt / ea
            b1 = b2 + xi * xi * h / ea
            xk = kink_distance(h, c0, c_res, eb0) * ea / xi
            if r0 > 0.0:
                x, first = piecewise_root(r0, b1, b2, xk)
            else:  # only by rounding: the trial lies on the apex
                x = 0.0
                first = xk > 0.0
            b = b1 if first else b2
            h_eff = h if first else 0.0
            pn = p_tr - K * x
            for i in range(6):
                if i < 3:
                    state_trial[k, S_PLASTIC_STRAIN + i] += work[W_SIG + i] / G2 + x / 3.0
                else:
                    state_trial[k, S_PLASTIC_STRAIN + i] += work[W_SIG + i] / G
                work[W_SIG + i] = pn if i < 3 else 0.0
            state_trial[k, S_EQ_PLASTIC_STRAIN] = eb0 + xi * x / ea
            state_trial[k, S_CODE] = CODE_APEX
            if want_tangent:
                c11 = K - K * eta * K / b
                c1n = K / b * (xi * xi * h_eff + eta_dt) * SQRT2 * (1.0 - etab / ea)
                for i in range(6):
                    one_i = 1.0 if i < 3 else 0.0
                    for j in range(6):
                        one_j = 1.0 if j < 3 else 0.0
                        work[W_D + 6 * i + j] = c11 * one_i * one_j + c1n * one_i * work[W_N + j]
    else:
        for i in range(3):
            work[W_SIG + i] += p_tr
        state_trial[k, S_CODE] = CODE_ELASTIC
        if want_tangent:
            isotropic_tangent(work, K, G2)
    return finish_point(work, state_committed, state_trial, k, N_DP_STATE, want_tangent, sig, D)


@njit(cache=True)
def drucker_prager_update(strain, params, state_committed, state_trial, stress_out, tangent_out, dt, want_tangent,
                          info):
    """Batch Drucker-Prager update: :func:`drucker_prager_point` for every row.

    Arguments (those of :func:`masonrydam.materials.plasticity.batch_update` less ``point``) and
    return value as :func:`masonrydam.materials.von_mises.von_mises_update`, with ``params``
    (n, N_DP_PARAMS) and states (n, N_DP_STATE).
    """
    return batch_update(drucker_prager_point, strain, params, state_committed, state_trial, stress_out, tangent_out,
                        dt, want_tangent, info)


# ----------------------------------------------------------------------------------------------
# Python side
# ----------------------------------------------------------------------------------------------

_LAW = "Drucker-Prager"
_TABLES = PlasticLaw(_LAW, N_DP_PARAMS, N_DP_STATE, PARAM_NAMES)


def drucker_prager_coefficients(friction_angle_deg: float, dilation_angle_deg: float | None = None,
                                match: str = "plane_strain") -> tuple[float, float, float]:
    """Cone coefficients ``(eta, xi, eta_bar)`` matching Mohr-Coulomb (module docstring; de Souza Neto,
    Peric & Owen 2008, sec. 8.3).

    Parameters
    ----------
    friction_angle_deg : phi (degrees), 0 <= phi < 90.
    dilation_angle_deg : psi (degrees), 0 <= psi <= phi; None = phi (associated flow).
    match : "outer" (compressive meridian), "inner" (tensile meridian) or "plane_strain" (same
        plane-strain collapse load as Mohr-Coulomb, for the given psi).
    """
    phi = real_parameter(_LAW, "friction_angle", friction_angle_deg)
    psi = phi if dilation_angle_deg is None else real_parameter(_LAW, "dilation_angle", dilation_angle_deg)
    if not 0.0 <= phi < 90.0:
        raise ValueError(f"{_LAW} parameter friction_angle must be in [0, 90) degrees, got {phi!r}")
    if not 0.0 <= psi <= phi:
        raise ValueError(
            f"{_LAW} parameter dilation_angle must satisfy 0 <= dilation_angle <= friction_angle = {phi!r} "
            f"degrees, got {psi!r}"
        )
    if match not in MATCHES:
        raise ValueError(f"{_LAW} parameter match must be one of {MATCHES}, got {match!r}")
    sp, cp = math.sin(math.radians(phi)), math.cos(math.radians(phi))
    ss = math.sin(math.radians(psi))
    if match == "outer":
        return 6.0 * sp / (SQRT3 * (3.0 - sp)), 6.0 * cp / (SQRT3 * (3.0 - sp)), 6.0 * ss / (SQRT3 * (3.0 - ss))
    if match == "inner":
        return 6.0 * sp / (SQRT3 * (3.0 + sp)), 6.0 * cp / (SQRT3 * (3.0 + sp)), 6.0 * ss / (SQRT3 * (3.0 + ss))
    r = math.sqrt(3.0 + ss * ss)
    d = 3.0 + sp * ss
    eta = SQRT3 * sp * r / d
    # associated flow: eta_bar = eta exactly (the two formulas agree on paper, not always in the last bit)
    return eta, SQRT3 * cp * r / d, eta if psi == phi else SQRT3 * ss / r


def _check_plastic(E, nu, c0, h, c_res, eta_v, eta, xi, etab, where=""):
    K, G = elastic_moduli(E, nu)
    if not c0 >= 0.0:
        raise ValueError(f"{_LAW} parameter cohesion must be >= 0 (Pa){where}, got {c0!r}")
    if not eta >= 0.0:
        raise ValueError(f"{_LAW} parameter friction coefficient eta must be >= 0{where}, got {eta!r}")
    if not xi > 0.0:
        raise ValueError(f"{_LAW} parameter cohesion coefficient xi must be > 0{where}, got {xi!r}")
    if not 0.0 <= etab <= eta:
        raise ValueError(
            f"{_LAW} parameter dilatancy coefficient eta_bar must satisfy 0 <= eta_bar <= eta = {eta!r} "
            f"(dilation_angle <= friction_angle){where}, got {etab!r}"
        )
    if c0 == 0.0 and eta == 0.0:
        raise ValueError(f"{_LAW} parameter cohesion must be > 0 when the friction angle is 0 (no strength){where}")
    if not 0.0 <= c_res <= c0:
        raise ValueError(
            f"{_LAW} parameter residual_cohesion must satisfy 0 <= residual_cohesion <= cohesion = {c0!r} Pa"
            f"{where}, got {c_res!r}"
        )
    if not G + K * eta * etab + xi * xi * h > 0.0:
        raise ValueError(
            f"{_LAW} parameter cohesion_hardening = {h!r} Pa is too steep a softening{where}: "
            f"G + K eta eta_bar + xi^2 cohesion_hardening must be > 0 (cone return)"
        )
    if eta > 0.0:
        ea = etab if etab > 0.0 else eta
        if not K * eta * ea + xi * xi * h > 0.0:
            raise ValueError(
                f"{_LAW} parameter cohesion_hardening = {h!r} Pa is too steep a softening{where}: "
                f"K eta eta_a + xi^2 cohesion_hardening must be > 0 (apex return; eta_a = eta_bar, or eta "
                f"when the dilation angle is 0), i.e. cohesion_hardening > {-K * eta * ea / (xi * xi)!r} Pa"
            )
    if not eta_v >= 0.0:
        raise ValueError(f"{_LAW} parameter viscosity must be >= 0 (Pa s){where}, got {eta_v!r}")


def check_drucker_prager_params(params) -> np.ndarray:
    """Validate a parameter table (n, N_DP_PARAMS) or row; returns it as a float64 2D array.
    Raises ValueError naming the parameter (and the row of a table)."""
    return check_param_table(_TABLES, params, _check_row)


def _check_row(row, where):
    _check_plastic(*(float(row[c]) for c in (P_E, P_NU, P_COHESION, P_COHESION_HARDENING, P_RESIDUAL_COHESION,
                                              P_VISCOSITY, P_FRICTION_COEF, P_COHESION_COEF, P_DILATANCY_COEF)),
                   where)


def drucker_prager_params(
    youngs_modulus: float,
    poisson_ratio: float,
    cohesion: float,
    friction_angle_deg: float,
    dilation_angle_deg: float | None = None,
    cohesion_hardening: float = 0.0,
    residual_cohesion: float = 0.0,
    viscosity: float = 0.0,
    match: str = "plane_strain",
) -> np.ndarray:
    """Validated parameter row (N_DP_PARAMS,) of the Drucker-Prager law.

    Parameters
    ----------
    youngs_modulus : E (Pa), > 0.
    poisson_ratio : nu, -1 < nu < 0.5.
    cohesion : Mohr-Coulomb cohesion c (Pa), >= 0 (> 0 when phi = 0).
    friction_angle_deg : phi (degrees), 0 <= phi < 90.
    dilation_angle_deg : psi (degrees), 0 <= psi <= phi; None = phi (associated flow).
    cohesion_hardening : H (Pa), slope of c against the hardening variable eps_bar (eps_bar_dot =
        xi gamma_dot); negative for softening, with the limits of the module docstring.
    residual_cohesion : c_r (Pa), 0 <= c_r <= c; softening stops there.
    viscosity : Perzyna viscosity eta_v (Pa s), >= 0; 0 is rate independent.
    match : Mohr-Coulomb match of the cone, "plane_strain" (default), "outer" or "inner".

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
    eta, xi, etab = drucker_prager_coefficients(friction_angle_deg, dilation_angle_deg, match)
    _check_plastic(v["youngs_modulus"], v["poisson_ratio"], v["cohesion"], v["cohesion_hardening"],
                   v["residual_cohesion"], v["viscosity"], eta, xi, etab)
    cols = {col: v[name] for col, name in PARAM_NAMES.items() if name in v}  # all but the cone coefficients
    cols.update({P_FRICTION_COEF: eta, P_COHESION_COEF: xi, P_DILATANCY_COEF: etab})
    return param_row(_TABLES, cols)


def drucker_prager_initial_state(n: int) -> np.ndarray:
    """Virgin state (n, N_DP_STATE)."""
    return initial_state(_TABLES, n)


def drucker_prager_evaluate(strain, params, state_committed, dt: float = 0.0, want_tangent: bool = True):
    """Python wrapper of :func:`drucker_prager_update` (as
    :func:`masonrydam.materials.von_mises.von_mises_evaluate`): returns
    ``(stress (n, ns), tangent (n, ns, ns) or None, state_trial (n, N_DP_STATE))``.

    Raises ValueError for a bad shape, parameter or dt, masonrydam.errors.NumericalError for a
    non-finite strain, state or result."""
    return evaluate(_TABLES, drucker_prager_update, check_drucker_prager_params, strain, params, state_committed, dt,
                    want_tangent)
