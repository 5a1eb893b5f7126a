"""von Mises (J2) plasticity with linear isotropic and kinematic hardening and optional Perzyna
viscosity, small strains, plane strain and 3D (issue 17, continuum plasticity).

Point-level numba kernels: :func:`von_mises_point` evaluates one integration point (the function an
element kernel calls per point), :func:`von_mises_update` a batch of points, and
:func:`von_mises_evaluate` is the Python wrapper (shape and parameter checks, exceptions). Voigt
order, tensor conventions and the shared state columns: :mod:`masonrydam.materials.plasticity`.

Parameter row (float64, ``N_VM_PARAMS`` columns; build it with :func:`von_mises_params`)::

    P_E              E        Young's modulus (Pa), > 0
    P_NU             nu       Poisson's ratio, -1 < nu < 0.5
    P_VISCOSITY      eta      Perzyna viscosity (Pa s), >= 0; 0 = rate independent
    P_SIGMA_Y        sigma_y0 initial uniaxial yield stress (Pa), > 0
    P_H_ISO          H_iso    linear isotropic hardening modulus (Pa); < 0 is softening
    P_H_KIN          H_kin    linear kinematic (Prager) hardening modulus (Pa), >= 0
    P_SIGMA_Y_RES    sigma_r  residual yield stress (Pa), 0 <= sigma_r <= sigma_y0: softening stops there

``H_iso`` and ``H_kin`` are the slopes of the uniaxial stress against the uniaxial plastic strain,
so a monotonic uniaxial test has the elastoplastic modulus ``E H / (E + H)``, ``H = H_iso + H_kin``.
Admissible: ``3G + H_iso + H_kin > 0`` (the return mapping is unique and the local
stress-strain curve in shear has no snap-back; G the shear modulus).

State row (float64, ``N_VM_STATE`` columns; zeros is the virgin state)::

    S_STRESS              6: stress [sxx, syy, szz, sxy, syz, szx] (Pa), szz kept in plane strain
    S_PLASTIC_STRAIN      6: plastic strain (engineering shear), trace zero (plastic incompressibility)
    S_EQ_PLASTIC_STRAIN   accumulated equivalent plastic strain alpha = int sqrt(2/3 eps_p_dot : eps_p_dot) dt
    S_CODE                CODE_ELASTIC or CODE_PLASTIC (what the last update did)
    S_BACK_STRESS         6: back stress beta (Pa, deviatoric, tensor components)

Law (de Souza Neto, Peric & Owen 2008, *Computational Methods for Plasticity*, ch. 6-7;
Simo & Hughes 1998, *Computational Inelasticity*, box 3.2 and sec. 3.3)
-----------------------------------------------------------------------------------------
::

    sigma = K tr(eps_e) 1 + 2G dev(eps_e),   eps_e = eps - eps_p
    f     = q(xi) - sigma_y(alpha),   xi = s - beta,   q(xi) = sqrt(3/2) |xi|
    sigma_y(alpha) = max(sigma_y0 + H_iso alpha, sigma_r)
    eps_p_dot = gamma_dot sqrt(3/2) n,   n = xi / |xi|,   alpha_dot = gamma_dot
    beta_dot  = 2/3 H_kin eps_p_dot = sqrt(2/3) H_kin gamma_dot n          (Prager's rule)
    rate independent: gamma_dot >= 0, f <= 0, gamma_dot f = 0
    Perzyna:          gamma_dot = <f> / eta                                (linear overstress)

Return mapping (radial return, closed form for linear hardening; de Souza Neto et al. ch. 7,
with the kinematic term of Simo & Hughes box 3.2)::

    trial:  s_tr = 2G dev(eps - eps_p_n),  p_tr = K tr(eps - eps_p_n),  xi_tr = s_tr - beta_n
            f_tr = sqrt(3/2) |xi_tr| - sigma_y(alpha_n)
    f_tr <= 0 (or eta > 0 and dt = 0): elastic, sigma = s_tr + p_tr 1
    else    n = xi_tr / |xi_tr| (unchanged by the return),
            f_(n+1) = f_tr - (3G + H_kin + H_iso) dgamma = (eta / dt) dgamma    (eta = 0: f_(n+1) = 0)
            dgamma = f_tr / (3G + H_iso + H_kin + eta/dt)
            sigma  = sigma_tr - 2G sqrt(3/2) dgamma n
            eps_p += sqrt(3/2) dgamma n,  beta += sqrt(2/3) H_kin dgamma n,  alpha += dgamma

The Perzyna update is the backward-Euler integration of ``gamma_dot = f/eta`` (Simo & Hughes sec.
2.7, de Souza Neto et al. sec. 11.5): ``f_(n+1) = eta dgamma / dt`` adds ``eta/dt`` to the
denominator, so it tends to the rate-independent return as ``eta/dt -> 0`` and to the elastic
trial as ``eta/dt -> inf``. At constant strain it relaxes the overstress as
``f(t) = f(0) exp(-(3G + H) t / eta)`` (``d q / dt = -(3G + H_kin) gamma_dot``,
``d sigma_y / dt = H_iso gamma_dot``, ``gamma_dot = f / eta``).
Softening past the residual yield stress (``alpha`` beyond ``(sigma_r - sigma_y0) / H_iso``) continues
with ``H_iso = 0``; the consistency condition is then piecewise linear in dgamma and still solved in
closed form (:func:`masonrydam.materials.plasticity.piecewise_root`).

Consistent (algorithmic) tangent (Simo & Taylor 1985, CMAME 48:101-118; Simo & Hughes box 3.2;
de Souza Neto et al. ch. 7), with ``H`` the hardening active in the step::

    D = K 1(x)1 + 2G (1 - 3G dgamma / q_tr) I_dev + 6G^2 (dgamma / q_tr - 1/(3G + H + eta/dt)) n(x)n

symmetric; elastic steps return the elastic matrix.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import STATUS_OK
from .plasticity import (
    CODE_ELASTIC, CODE_PLASTIC, N_COMMON_PARAMS, N_COMMON_STATE, P_E, P_NU, P_VISCOSITY, S_CODE,
    S_EQ_PLASTIC_STRAIN, S_PLASTIC_STRAIN, S_STRESS, SQRT_2_3, SQRT_3_2, W_D, W_N, W_SIG, PlasticLaw,
    bad_common_column, batch_update, check_param_table, copy_state_row, elastic_moduli, evaluate, finish_point,
    initial_state, isotropic_tangent, kink_distance, param_row, piecewise_root, point_inputs_status, point_trial,
    real_parameters, tensor_norm, viscous_term,
)

__all__ = [
    "P_E", "P_NU", "P_VISCOSITY", "P_SIGMA_Y", "P_H_ISO", "P_H_KIN", "P_SIGMA_Y_RES", "N_VM_PARAMS",
    "S_STRESS", "S_PLASTIC_STRAIN", "S_EQ_PLASTIC_STRAIN", "S_CODE", "S_BACK_STRESS", "N_VM_STATE",
    "CODE_ELASTIC", "CODE_PLASTIC", "von_mises_point", "von_mises_update", "von_mises_evaluate",
    "von_mises_params", "check_von_mises_params", "von_mises_initial_state",
]

# parameter columns (after the shared E, nu, viscosity)
P_SIGMA_Y = N_COMMON_PARAMS
P_H_ISO = N_COMMON_PARAMS + 1
P_H_KIN = N_COMMON_PARAMS + 2
P_SIGMA_Y_RES = N_COMMON_PARAMS + 3
N_VM_PARAMS = N_COMMON_PARAMS + 4

# state columns (after the shared stress, plastic strain, alpha, code)
S_BACK_STRESS = N_COMMON_STATE  # 6 columns
N_VM_STATE = N_COMMON_STATE + 6

PARAM_NAMES = {
    P_E: "youngs_modulus",
    P_NU: "poisson_ratio",
    P_VISCOSITY: "viscosity",
    P_SIGMA_Y: "yield_stress",
    P_H_ISO: "isotropic_hardening",
    P_H_KIN: "kinematic_hardening",
    P_SIGMA_Y_RES: "residual_yield_stress",
}


@njit(cache=True)
def _bad_column(params, p):
    """First inadmissible parameter column of row ``p``, or -2 if all are fine."""
    bad = bad_common_column(params, p)
    if bad != -2:
        return bad
    E = params[p, P_E]
    nu = params[p, P_NU]
    sy0 = params[p, P_SIGMA_Y]
    if not sy0 > 0.0:
        return P_SIGMA_Y
    if not params[p, P_H_KIN] >= 0.0:
        return P_H_KIN
    if not (1.5 * E / (1.0 + nu) + params[p, P_H_ISO] + params[p, P_H_KIN] > 0.0):
        return P_H_ISO
    if not (0.0 <= params[p, P_SIGMA_Y_RES] <= sy0):
        return P_SIGMA_Y_RES
    return -2


@njit(cache=True)
def von_mises_point(eps, params, p, state_committed, state_trial, k, dt, want_tangent, sig, D, work):
    """Return mapping of the von Mises law at one integration point (module docstring).

    Parameters
    ----------
    eps : float64 (ns,)
        Total strain of the point, ns = 3 (plane strain ``[exx, eyy, gxy]``) or 6 (3D).
    params : float64 (m, N_VM_PARAMS); p : int
        Parameter table and the row of this point (a per-point or a per-material table).
    state_committed : float64 (n, N_VM_STATE), read only; state_trial : float64 (n, N_VM_STATE), out
        State rows; row ``k`` is this point.
    dt : float
        Time step (s), >= 0; only used when the viscosity is > 0.
    want_tangent : bool
        Fill ``D`` (otherwise ``D`` is not touched).
    sig : float64 (ns,), out
        Stress (Pa) ``[sxx, syy, sxy]`` or ``[sxx, syy, szz, sxy, syz, szx]``.
    D : float64 (ns, ns), out
        Consistent tangent ``d sig / d eps`` (Pa), symmetric.
    work : float64 (>= WORK_SIZE,)
        Scratch.

    Returns
    -------
    int
        ``STATUS_OK``; ``STATUS_NAN`` for a non-finite input or result (trial state = committed,
        stress NaN, tangent 0); ``STATUS_BAD_MATERIAL`` for an inadmissible parameter or ``dt < 0``
        (same outputs; ``work[W_SCRATCH]`` holds the parameter column, -1 for dt).
    """
    status = point_inputs_status(eps, params, p, N_VM_PARAMS, state_committed, state_trial, k, N_VM_STATE, dt,
                                 _bad_column(params, p), want_tangent, sig, D, work)
    if status != STATUS_OK:
        return status

    sy0 = params[p, P_SIGMA_Y]
    h_iso = params[p, P_H_ISO]
    h_kin = params[p, P_H_KIN]
    sy_res = params[p, P_SIGMA_Y_RES]
    K, G, p_tr = point_trial(eps, params, p, state_committed, k, work)
    G2 = 2.0 * G
    # relative stress xi_tr = s_tr - beta_n  -> W_N
    for i in range(6):
        work[W_N + i] = work[W_SIG + i] - state_committed[k, S_BACK_STRESS + i]
    xi_norm = tensor_norm(work, W_N)
    q_tr = SQRT_3_2 * xi_norm
    alpha_n = state_committed[k, S_EQ_PLASTIC_STRAIN]
    sy = sy0 + h_iso * alpha_n
    if sy < sy_res:
        sy = sy_res
    f_tr = q_tr - sy
    flow, eta_dt = viscous_term(params[p, P_VISCOSITY], dt)

    copy_state_row(state_committed, state_trial, k, N_VM_STATE)
    if flow and f_tr > 0.0:
        # f_tr > 0 and sy >= 0 give q_tr > 0
        a2 = 3.0 * G + h_kin + eta_dt
        a1 = a2 + h_iso
        dg, first = piecewise_root(f_tr, a1, a2, kink_distance(h_iso, sy0, sy_res, alpha_n))
        a = a1 if first else a2
        inv = 1.0 / xi_norm
        c_eps = SQRT_3_2 * dg
        c_beta = SQRT_2_3 * h_kin * dg
        for i in range(6):
            n_i = work[W_N + i] * inv
            work[W_N + i] = n_i
            state_trial[k, S_PLASTIC_STRAIN + i] += (c_eps if i < 3 else 2.0 * c_eps) * n_i
            state_trial[k, S_BACK_STRESS + i] += c_beta * n_i
            work[W_SIG + i] -= G2 * c_eps * n_i
        state_trial[k, S_EQ_PLASTIC_STRAIN] = alpha_n + dg
        state_trial[k, S_CODE] = CODE_PLASTIC
        if want_tangent:
            isotropic_tangent(work, K, G2 * (1.0 - 3.0 * G * dg / q_tr))
            cn = 6.0 * G * G * (dg / q_tr - 1.0 / a)
            for i in range(6):
                for j in range(6):
                    work[W_D + 6 * i + j] += cn * work[W_N + i] * work[W_N + j]
    else:
        state_trial[k, S_CODE] = CODE_ELASTIC
        if want_tangent:
            isotropic_tangent(work, K, G2)
    for i in range(3):
        work[W_SIG + i] += p_tr
    return finish_point(work, state_committed, state_trial, k, N_VM_STATE, want_tangent, sig, D)


@njit(cache=True)
def von_mises_update(strain, params, state_committed, state_trial, stress_out, tangent_out, dt, want_tangent, info):
    """Batch von Mises update: :func:`von_mises_point` for every row.

    The loop of :func:`masonrydam.materials.plasticity.batch_update`, whose docstring gives the
    arguments (less ``point``) and the return value, here with ``params`` float64 (n, N_VM_PARAMS)
    and ``state_committed``, ``state_trial`` float64 (n, N_VM_STATE): ``strain`` (n, ns) with
    ns = 3 (plane strain) or 6 (3D), ``stress_out`` (n, ns) and ``tangent_out`` (n, ns, ns) in Pa,
    ``dt`` (s), ``info`` int64 (>= 1,); returns the status of the first failing point (the later
    points are not evaluated), else STATUS_OK.
    """
    return batch_update(von_mises_point, strain, params, state_committed, state_trial, stress_out, tangent_out, dt,
                        want_tangent, info)


# ----------------------------------------------------------------------------------------------
# Python side
# ----------------------------------------------------------------------------------------------

_LAW = "von Mises"
_TABLES = PlasticLaw(_LAW, N_VM_PARAMS, N_VM_STATE, PARAM_NAMES)


def check_von_mises_params(params) -> np.ndarray:
    """Validate a parameter table (n, N_VM_PARAMS) or row; returns it as a float64 2D array.

    Raises ValueError naming the parameter, the row and the value (the admissible ranges are those
    of the module docstring)."""
    return check_param_table(_TABLES, params, _check_row)


def _check_row(row, where):
    _check_plastic(*(float(row[c]) for c in (P_E, P_NU, P_SIGMA_Y, P_H_ISO, P_H_KIN, P_SIGMA_Y_RES, P_VISCOSITY)),
                   where)


def _check_plastic(E, nu, sy0, h_iso, h_kin, sy_res, eta, where=""):
    _, G = elastic_moduli(E, nu)
    if not sy0 > 0.0:
        raise ValueError(f"{_LAW} parameter yield_stress must be > 0 (Pa){where}, got {sy0!r}")
    if not h_kin >= 0.0:
        raise ValueError(f"{_LAW} parameter kinematic_hardening must be >= 0 (Pa){where}, got {h_kin!r}")
    if not 3.0 * G + h_iso + h_kin > 0.0:
        raise ValueError(
            f"{_LAW} parameter isotropic_hardening = {h_iso!r} Pa is too steep a softening{where}: "
            f"3G + isotropic_hardening + kinematic_hardening must be > 0 (3G = {3.0 * G!r} Pa)"
        )
    if not 0.0 <= sy_res <= sy0:
        raise ValueError(
            f"{_LAW} parameter residual_yield_stress must satisfy 0 <= residual_yield_stress <= yield_stress "
            f"= {sy0!r} Pa{where}, got {sy_res!r}"
        )
    if not eta >= 0.0:
        raise ValueError(f"{_LAW} parameter viscosity must be >= 0 (Pa s){where}, got {eta!r}")


def von_mises_params(
    youngs_modulus: float,
    poisson_ratio: float,
    yield_stress: float,
    isotropic_hardening: float = 0.0,
    kinematic_hardening: float = 0.0,
    residual_yield_stress: float = 0.0,
    viscosity: float = 0.0,
) -> np.ndarray:
    """Validated parameter row (N_VM_PARAMS,) of the von Mises law.

    Parameters
    ----------
    youngs_modulus : E (Pa), > 0.
    poisson_ratio : nu, -1 < nu < 0.5.
    yield_stress : initial uniaxial yield stress sigma_y0 (Pa), > 0.
    isotropic_hardening : H_iso (Pa), slope of the uniaxial yield stress against the uniaxial plastic
        strain; negative for softening, with ``3G + H_iso + H_kin > 0``.
    kinematic_hardening : H_kin (Pa), >= 0 (linear Prager hardening).
    residual_yield_stress : sigma_r (Pa), ``0 <= sigma_r <= sigma_y0``; softening stops there.
    viscosity : Perzyna viscosity eta (Pa s), >= 0; 0 is rate independent. The overstress relaxes
        with the time constant ``eta / (3G + H_iso + H_kin)``.

    Raises
    ------
    ValueError naming the parameter and its value.
    """
    v = real_parameters(_TABLES, {
        "youngs_modulus": youngs_modulus,
        "poisson_ratio": poisson_ratio,
        "yield_stress": yield_stress,
        "isotropic_hardening": isotropic_hardening,
        "kinematic_hardening": kinematic_hardening,
        "residual_yield_stress": residual_yield_stress,
        "viscosity": viscosity,
    })
    _check_plastic(v["youngs_modulus"], v["poisson_ratio"], v["yield_stress"], v["isotropic_hardening"],
                   v["kinematic_hardening"], v["residual_yield_stress"], v["viscosity"])
    # every column is named by PARAM_NAMES with the keyword of its argument
    return param_row(_TABLES, {col: v[name] for col, name in PARAM_NAMES.items()})


def von_mises_initial_state(n: int) -> np.ndarray:
    """Virgin state (n, N_VM_STATE): zero stress, plastic strain, alpha and back stress."""
    return initial_state(_TABLES, n)


def von_mises_evaluate(strain, params, state_committed, dt: float = 0.0, want_tangent: bool = True):
    """Python wrapper of :func:`von_mises_update`: checks shapes and parameters once, runs the kernel
    and turns its status into an exception.

    Parameters
    ----------
    strain : (n, ns) array, ns = 3 (plane strain) or 6 (3D), engineering shear (a single point is (1, ns)).
    params : (n, N_VM_PARAMS) or one row (N_VM_PARAMS,) used for every point.
    state_committed : (n, N_VM_STATE); read only.
    dt : time step (s), >= 0 (Perzyna only).
    want_tangent : also return the consistent tangent.

    Returns
    -------
    (stress (n, ns), tangent (n, ns, ns) or None, state_trial (n, N_VM_STATE))

    Raises
    ------
    ValueError for a bad shape, parameter or dt; masonrydam.errors.NumericalError for a non-finite
    strain, state or result.
    """
    return evaluate(_TABLES, von_mises_update, check_von_mises_params, strain, params, state_committed, dt, want_tangent)
