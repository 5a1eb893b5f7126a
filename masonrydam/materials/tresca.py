"""Tresca plasticity with linear isotropic hardening / softening and optional Perzyna viscosity,
small strains, plane strain and 3D (continuum plasticity).

Point-level numba kernels: :func:`tresca_point` (one integration point; what an element kernel
calls, with the signature of :func:`masonrydam.materials.von_mises.von_mises_point`),
:func:`tresca_update` (a batch) and the Python wrapper :func:`tresca_evaluate`. Parameter row: float64,
``N_TRESCA_PARAMS`` columns in SI units, built by :func:`tresca_params`; state row: float64,
``N_TRESCA_STATE`` columns, the shared ones of :mod:`masonrydam.materials.plasticity` (codes CODE_ELASTIC,
CODE_PLASTIC, CODE_EDGE_RIGHT, CODE_EDGE_LEFT). The return mapping is the principal-space return of
:mod:`masonrydam.materials.mohr_coulomb_solid` with ``phi = psi = 0`` and ``2c = sigma_y`` (de Souza Neto,
Peric & Owen 2008, sec. 8.1; Chen & Han 1988).

Theory: docs/continuum_nonlinearity.md, section "Tresca" (under "The plastic laws in equations").
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import STATUS_OK
from .mohr_coulomb_solid import mohr_coulomb_return, return_stiffnesses
from .plasticity import (
    CODE_EDGE_LEFT, CODE_EDGE_RIGHT, CODE_ELASTIC, CODE_PLASTIC, N_COMMON_PARAMS, N_COMMON_STATE, P_E, P_NU,
    P_VISCOSITY, S_CODE, S_EQ_PLASTIC_STRAIN, S_PLASTIC_STRAIN, S_STRESS, PlasticLaw, bad_common_column,
    batch_update, check_param_table, copy_state_row, elastic_moduli, evaluate, finish_point, initial_state,
    param_row, point_inputs_status, point_moduli, point_trial, real_parameters, viscous_term,
)

__all__ = [
    "P_E", "P_NU", "P_VISCOSITY", "P_SIGMA_Y", "P_H_ISO", "P_SIGMA_Y_RES", "N_TRESCA_PARAMS",
    "S_STRESS", "S_PLASTIC_STRAIN", "S_EQ_PLASTIC_STRAIN", "S_CODE", "N_TRESCA_STATE",
    "CODE_ELASTIC", "CODE_PLASTIC", "CODE_EDGE_RIGHT", "CODE_EDGE_LEFT",
    "tresca_point", "tresca_update", "tresca_evaluate", "tresca_params", "check_tresca_params",
    "tresca_initial_state",
]

P_SIGMA_Y = N_COMMON_PARAMS
P_H_ISO = N_COMMON_PARAMS + 1
P_SIGMA_Y_RES = N_COMMON_PARAMS + 2
N_TRESCA_PARAMS = N_COMMON_PARAMS + 3

N_TRESCA_STATE = N_COMMON_STATE

PARAM_NAMES = {
    P_E: "youngs_modulus",
    P_NU: "poisson_ratio",
    P_VISCOSITY: "viscosity",
    P_SIGMA_Y: "yield_stress",
    P_H_ISO: "isotropic_hardening",
    P_SIGMA_Y_RES: "residual_yield_stress",
}


@njit(cache=True)
def _bad_column(params, p):
    """First inadmissible parameter column of row ``p``, or -2 if all are fine."""
    bad = bad_common_column(params, p)
    if bad != -2:
        return bad
    sy0 = params[p, P_SIGMA_Y]
    if not sy0 > 0.0:
        return P_SIGMA_Y
    _, G = point_moduli(params, p)
    if not 3.0 * G + params[p, P_H_ISO] > 0.0:
        return P_H_ISO
    if not (0.0 <= params[p, P_SIGMA_Y_RES] <= sy0):
        return P_SIGMA_Y_RES
    return -2


@njit(cache=True)
def tresca_point(eps, params, p, state_committed, state_trial, k, dt, want_tangent, sig, D, work):
    """Return mapping of the Tresca law at one integration point (module docstring).

    Arguments, outputs and status as :func:`masonrydam.materials.von_mises.von_mises_point`, with
    ``params`` (m, N_TRESCA_PARAMS) and states (n, N_TRESCA_STATE).
    """
    status = point_inputs_status(eps, params, p, N_TRESCA_PARAMS, state_committed, state_trial, k, N_TRESCA_STATE, dt,
                                 _bad_column(params, p), want_tangent, sig, D, work)
    if status != STATUS_OK:
        return status
    K, G, p_tr = point_trial(eps, params, p, state_committed, k, work)
    flow, eta_dt = viscous_term(params[p, P_VISCOSITY], dt)
    copy_state_row(state_committed, state_trial, k, N_TRESCA_STATE)
    mohr_coulomb_return(work, state_committed, state_trial, k, K, G, p_tr, 0.0, 0.0, 1.0, 1.0, params[p, P_SIGMA_Y],
                     params[p, P_H_ISO], params[p, P_SIGMA_Y_RES], flow, eta_dt, want_tangent)
    return finish_point(work, state_committed, state_trial, k, N_TRESCA_STATE, want_tangent, sig, D)


@njit(cache=True)
def tresca_update(strain, params, state_committed, state_trial, stress_out, tangent_out, dt, want_tangent, info):
    """Batch Tresca update: :func:`tresca_point` for every row.

    Arguments (those of :func:`masonrydam.materials.plasticity.batch_update` less ``point``) and
    return value as :func:`masonrydam.materials.von_mises.von_mises_update`, with ``params``
    (n, N_TRESCA_PARAMS) and states (n, N_TRESCA_STATE).
    """
    return batch_update(tresca_point, strain, params, state_committed, state_trial, stress_out, tangent_out, dt,
                        want_tangent, info)


# ----------------------------------------------------------------------------------------------
# Python side
# ----------------------------------------------------------------------------------------------

_LAW = "Tresca"
_TABLES = PlasticLaw(_LAW, N_TRESCA_PARAMS, N_TRESCA_STATE, PARAM_NAMES)


def _check_plastic(E, nu, sy0, h, sy_res, eta, where=""):
    K, G = elastic_moduli(E, nu)
    if not sy0 > 0.0:
        raise ValueError(f"{_LAW} parameter yield_stress must be > 0 (Pa){where}, got {sy0!r}")
    a_min = min(return_stiffnesses(K, G, 0.0, 0.0)[:3])  # 3G (the edge returns)
    if not a_min + h > 0.0:
        raise ValueError(
            f"{_LAW} parameter isotropic_hardening = {h!r} Pa is too steep a softening{where}: "
            f"3G + isotropic_hardening must be > 0 (3G = {a_min!r} Pa)"
        )
    if not 0.0 <= sy_res <= sy0:
        raise ValueError(
            f"{_LAW} parameter residual_yield_stress must satisfy 0 <= residual_yield_stress <= yield_stress "
            f"= {sy0!r} Pa{where}, got {sy_res!r}"
        )
    if not eta >= 0.0:
        raise ValueError(f"{_LAW} parameter viscosity must be >= 0 (Pa s){where}, got {eta!r}")


def check_tresca_params(params) -> np.ndarray:
    """Validate a parameter table (n, N_TRESCA_PARAMS) or row; returns it as a float64 2D array.
    Raises ValueError naming the parameter, the row and the value."""
    return check_param_table(_TABLES, params, _check_row)


def _check_row(row, where):
    _check_plastic(*(float(row[c]) for c in (P_E, P_NU, P_SIGMA_Y, P_H_ISO, P_SIGMA_Y_RES, P_VISCOSITY)), where)


def tresca_params(
    youngs_modulus: float,
    poisson_ratio: float,
    yield_stress: float,
    isotropic_hardening: float = 0.0,
    residual_yield_stress: float = 0.0,
    viscosity: float = 0.0,
) -> np.ndarray:
    """Validated parameter row (N_TRESCA_PARAMS,) of the Tresca law.

    Parameters
    ----------
    youngs_modulus : E (Pa), > 0.
    poisson_ratio : nu, -1 < nu < 0.5.
    yield_stress : initial uniaxial yield stress sigma_y0 (Pa), > 0; the shear yield stress is sigma_y0 / 2.
    isotropic_hardening : H (Pa), slope of the uniaxial yield stress against the uniaxial plastic
        strain; negative for softening, with ``3G + H > 0``.
    residual_yield_stress : sigma_r (Pa), ``0 <= sigma_r <= sigma_y0``; softening stops there.
    viscosity : Perzyna viscosity eta (Pa s), >= 0; 0 is rate independent.

    Raises
    ------
    ValueError naming the parameter and its value.
    """
    v = real_parameters(_TABLES, {
        "youngs_modulus": youngs_modulus,
        "poisson_ratio": poisson_ratio,
        "yield_stress": yield_stress,
        "isotropic_hardening": isotropic_hardening,
        "residual_yield_stress": residual_yield_stress,
        "viscosity": viscosity,
    })
    _check_plastic(v["youngs_modulus"], v["poisson_ratio"], v["yield_stress"], v["isotropic_hardening"],
                   v["residual_yield_stress"], v["viscosity"])
    return param_row(_TABLES, {col: v[name] for col, name in PARAM_NAMES.items()})


def tresca_initial_state(n: int) -> np.ndarray:
    """Virgin state (n, N_TRESCA_STATE)."""
    return initial_state(_TABLES, n)


def tresca_evaluate(strain, params, state_committed, dt: float = 0.0, want_tangent: bool = True):
    """Python wrapper of :func:`tresca_update` (as :func:`masonrydam.materials.von_mises.von_mises_evaluate`):
    returns ``(stress (n, ns), tangent (n, ns, ns) or None, state_trial (n, N_TRESCA_STATE))``.

    Raises ValueError for a bad shape, parameter or dt, masonrydam.errors.NumericalError for a
    non-finite strain, state or result."""
    return evaluate(_TABLES, tresca_update, check_tresca_params, strain, params, state_committed, dt, want_tangent)
