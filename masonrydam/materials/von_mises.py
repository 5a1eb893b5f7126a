"""von Mises (J2) plasticity with linear isotropic and kinematic hardening and optional Perzyna
viscosity, small strains, plane strain and 3D (continuum plasticity).

Point-level numba kernels: :func:`von_mises_point` evaluates one integration point (the function an
element kernel calls per point), :func:`von_mises_update` a batch of points, and
:func:`von_mises_evaluate` is the Python wrapper (shape and parameter checks, exceptions). Parameter
row: float64, ``N_VM_PARAMS`` columns in SI units, built by :func:`von_mises_params`; state row: float64,
``N_VM_STATE`` columns (the shared ones of :mod:`masonrydam.materials.plasticity`, then the back stress
``S_BACK_STRESS``, 6, Pa), zeros the virgin state. Radial return in closed form with its consistent tangent
(de Souza Neto, Peric & Owen 2008, ch. 6-7; Simo & Hughes 1998, box 3.2; Simo & Taylor 1985).

Theory: docs/continuum_nonlinearity.md, section "von Mises" (under "The plastic laws in equations").
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
