"""Drucker-Prager plasticity with cohesion hardening / softening, non-associated flow and optional
Perzyna viscosity, small strains, plane strain and 3D (issue 17, continuum plasticity).

Point-level numba kernels: :func:`drucker_prager_point` (one integration point; what an element
kernel calls), :func:`drucker_prager_update` (a batch) and the Python wrapper
:func:`drucker_prager_evaluate`. Voigt order, tensor conventions and the shared state columns:
:mod:`masonrydam.materials.plasticity`. Stresses are positive in tension; ``p = tr(sigma)/3`` is
the mean stress (negative in compression).

Parameter row (float64, ``N_DP_PARAMS`` columns; build it with :func:`drucker_prager_params`,
which computes the three cone coefficients from the Mohr-Coulomb angles)::

    P_E                      E        Young's modulus (Pa), > 0
    P_NU                     nu       Poisson's ratio, -1 < nu < 0.5
    P_VISCOSITY              eta_v    Perzyna viscosity (Pa s), >= 0; 0 = rate independent
    P_COHESION               c0       initial cohesion (Pa), >= 0
    P_COHESION_HARDENING     H        slope of the cohesion against eps_bar (Pa); < 0 is softening
    P_RESIDUAL_COHESION      c_r      residual cohesion (Pa), 0 <= c_r <= c0: softening stops there
    P_FRICTION_COEF          eta      friction coefficient of the yield cone, >= 0
    P_COHESION_COEF          xi       cohesion coefficient, > 0
    P_DILATANCY_COEF         eta_bar  dilatancy coefficient of the flow potential, 0 <= eta_bar <= eta

State row (float64, ``N_DP_STATE`` columns, zeros is the virgin state): the shared columns
``S_STRESS`` (6), ``S_PLASTIC_STRAIN`` (6), ``S_EQ_PLASTIC_STRAIN`` (the hardening variable
``eps_bar`` below) and ``S_CODE`` (CODE_ELASTIC, CODE_PLASTIC on the cone, CODE_APEX).

Law (de Souza Neto, Peric & Owen 2008, *Computational Methods for Plasticity*, sec. 8.3)
-------------------------------------------------------------------------------------------------
::

    Phi = sqrt(J2(s)) + eta p - xi c(eps_bar)             yield function
    Psi = sqrt(J2(s)) + eta_bar p                         flow potential (eta_bar = eta: associated)
    eps_p_dot = gamma_dot dPsi/dsigma = gamma_dot (s / (2 sqrt(J2)) + eta_bar/3 1)
    eps_bar_dot = xi gamma_dot                            (de Souza Neto et al. sec. 8.3)
    c(eps_bar) = max(c0 + H eps_bar, c_r)
    rate independent: Kuhn-Tucker conditions; Perzyna: gamma_dot = <Phi> / eta_v

Matching Mohr-Coulomb (c, phi, psi) (de Souza Neto et al. sec. 8.3; for the outer and inner
cones eta_bar is the formula of eta with psi in place of phi), ``match`` of
:func:`drucker_prager_coefficients`. Each match is exact only on its own stress paths (the
meridian, or plane-strain collapse); elsewhere the cone and the Mohr-Coulomb pyramid differ::

    "outer" (cone through the compressive meridian, triaxial compression):
        eta = 6 sin(phi) / (sqrt(3) (3 - sin(phi))),  xi = 6 cos(phi) / (sqrt(3) (3 - sin(phi)))
    "inner" (cone through the tensile meridian, triaxial extension):
        eta = 6 sin(phi) / (sqrt(3) (3 + sin(phi))),  xi = 6 cos(phi) / (sqrt(3) (3 + sin(phi)))
    "plane_strain" (same limit load as Mohr-Coulomb in plane strain; the default):
        associated (psi = phi), de Souza Neto et al.:
            eta = 3 tan(phi) / sqrt(9 + 12 tan^2(phi)),   xi = 3 / sqrt(9 + 12 tan^2(phi))
        any 0 <= psi <= phi (derived here, reduces to the above for psi = phi): at plane-strain
        collapse the stress is steady and eps_zz = 0, so eps_p_zz_dot = 0 gives
        s_zz = -2/3 eta_bar sqrt(J2), hence sqrt(J2) = t / sqrt(1 - eta_bar^2/3) and
        p = sigma_m - eta_bar sqrt(J2) / 3 with t = sqrt(((sxx - syy)/2)^2 + sxy^2) and
        sigma_m = (sxx + syy)/2. Phi = 0 then reads
        t (1 - eta eta_bar/3) / sqrt(1 - eta_bar^2/3) + eta sigma_m = xi c, which is Mohr-Coulomb in
        plane strain, t + sigma_m sin(phi) = c cos(phi), and the in-plane dilatancy
        eps_v_dot / (eps_1_dot - eps_3_dot) = sin(psi), when
            eta_bar = sqrt(3) sin(psi) / sqrt(3 + sin^2(psi)),
            eta = sqrt(3) sin(phi) sqrt(3 + sin^2(psi)) / (3 + sin(phi) sin(psi)),
            xi  = sqrt(3) cos(phi) sqrt(3 + sin^2(psi)) / (3 + sin(phi) sin(psi)).
        (psi = 0 gives eta = sin(phi), xi = cos(phi).)

Return mapping (de Souza Neto et al. box 8.8/8.9: cone and apex returns)
------------------------------------------------------------------------------------
::

    trial: s_tr = 2G dev(eps - eps_p_n), p_tr = K tr(eps - eps_p_n), Phi_tr = sqrt(J2_tr) + eta p_tr - xi c_n
    Phi_tr <= 0 (or eta_v > 0 and dt = 0): elastic
    cone:  Phi_tr - (G + K eta eta_bar + eta_v/dt) dgamma - xi (c(eps_bar_n + xi dgamma) - c_n) = 0
           (linear, closed form: dgamma = Phi_tr / (G + K eta eta_bar + xi^2 H + eta_v/dt))
           valid if sqrt(J2_tr) - G dgamma >= 0; then
           s = (1 - G dgamma / sqrt(J2_tr)) s_tr,  p = p_tr - K eta_bar dgamma,  eps_bar += xi dgamma
    apex (cone return not valid): s = 0, p = p_tr - K deps_v,  with the plastic volumetric strain
           deps_v from  eta p - xi c(eps_bar_n + alpha deps_v) = (eta_v/dt) deps_v / eta_bar,
           alpha = xi / eta_bar; rate independent: p - beta c = 0 with beta = xi / eta, i.e.
           deps_v = (p_tr - beta c_n) / (K + alpha beta H)   (de Souza Neto et al. sec. 8.3)

``eta_bar = 0`` (psi = 0) has no apex return in de Souza Neto et al. (alpha = xi / eta_bar is
infinite: the non-dilatant potential cannot take a volumetric plastic strain). Here the apex then
takes the plastic volumetric strain as a tension cut-off with the cone's own volumetric gradient:
``dgamma = sqrt(J2_tr)/G + deps_v/eta`` (the cone multiplier at the cone/apex boundary, plus the
volumetric part), so the update is continuous across the boundary. In general the apex multiplier
is ``dgamma = g0 + deps_v / eta_a`` with ``eta_a = eta_bar`` (``g0 = 0``: de Souza Neto et al.
exactly) or, for ``eta_bar = 0``, ``eta_a = eta`` and ``g0 = sqrt(J2_tr)/G``; then
``eps_bar += xi dgamma`` and ``eta p - xi c = (eta_v/dt) dgamma``.
Softening past the residual cohesion continues with ``H = 0`` (piecewise linear, closed form:
:func:`masonrydam.materials.plasticity.piecewise_root`). Because every relation is linear (linear
overstress, linear hardening, linear cone) the scalar consistency equations of both the rate-
independent and the Perzyna updates are solved exactly in closed form: the scalar Newton of
de Souza Neto et al. sec. 11.5 would converge in one iteration.

Admissible hardening: ``G + K eta eta_bar + xi^2 H > 0`` (cone) and, for eta > 0,
``K eta eta_a + xi^2 H > 0`` (apex); with these the returns are unique.

Consistent tangent (de Souza Neto et al. sec. 8.3, derived again here with the viscous term;
``a = G + K eta eta_bar + xi^2 H + eta_v/dt`` with the H active in the step, ``n = s_tr / |s_tr|``)::

    cone: D = 2G (1 - G dgamma / sqrt(J2_tr)) I_dev + 2G^2 (dgamma / sqrt(J2_tr) - 1/a) n(x)n
              - sqrt(2) G K / a (eta n(x)1 + eta_bar 1(x)n) + K (1 - K eta eta_bar / a) 1(x)1
    apex: D = K 1(x)1 - K/b (eta K 1(x)1 - (xi^2 H + eta_v/dt) sqrt(2) (1 - eta_bar/eta_a) 1(x)n),
          b = eta K + (xi^2 H + eta_v/dt) / eta_a
          (eta_bar > 0: D = K (1 - K / (K + alpha beta H + eta_v/(dt eta eta_bar))) 1(x)1)

non-symmetric on the cone when ``eta_bar != eta`` and at the apex when ``eta_bar = 0`` with hardening
or viscosity (the ``1(x)n`` term).
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
