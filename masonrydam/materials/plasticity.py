"""Shared pieces of the continuum plasticity laws (:mod:`.von_mises`, :mod:`.drucker_prager`, :mod:`.tresca`,
:mod:`.mohr_coulomb_solid`): conventions, the shared columns and the parts around a law's return mapping.

Small strains, plane strain and 3D; Voigt strains with engineering shear, stresses in Pa, tension positive.
Rows are float64, one per integration point: a state row starts with the ``N_COMMON_STATE`` shared columns
(``S_STRESS`` 6, ``S_PLASTIC_STRAIN`` 6, ``S_EQ_PLASTIC_STRAIN``, ``S_CODE``), a parameter row with ``P_E`` (Pa),
``P_NU`` and ``P_VISCOSITY`` (Pa s) (Simo & Hughes 1998; de Souza Neto, Peric & Owen 2008).

A law module keeps its own columns, the admissibility of its parameters and its return mapping. Here: the
input checks and final stores of a point kernel (:func:`point_inputs_status`, :func:`point_trial`,
:func:`finish_point`), the batch loop (:func:`batch_update`, inlined into each law's ``*_update``), and on the
Python side the parameter-table check (:func:`check_param_table`), the parameter row (:func:`real_parameters`,
:func:`param_row`), the virgin state (:func:`initial_state`) and the evaluate wrapper (:func:`evaluate`), each
told the law's tables by a :class:`PlasticLaw`.

Theory: docs/continuum_nonlinearity.md, section "Conventions and shared columns" (under "The plastic laws in
equations").
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numba import njit

from ..errors import STATUS_NAN, STATUS_OK, NumericalError

# ---- parameter columns shared by the laws
P_E = 0
P_NU = 1
P_VISCOSITY = 2
N_COMMON_PARAMS = 3

# ---- state columns shared by the laws
S_STRESS = 0  # 6 columns
S_PLASTIC_STRAIN = 6  # 6 columns
S_EQ_PLASTIC_STRAIN = 12
S_CODE = 13
N_COMMON_STATE = 14

# ---- values of the S_CODE column
CODE_ELASTIC = 0
CODE_PLASTIC = 1  # smooth part of the surface (von Mises cylinder, Drucker-Prager cone)
CODE_APEX = 2  # Drucker-Prager apex
CODE_EDGE_RIGHT = 3  # Mohr-Coulomb / Tresca edge sigma_2 = sigma_3 (planes 1-3 and 1-2 active)
CODE_EDGE_LEFT = 4  # Mohr-Coulomb / Tresca edge sigma_1 = sigma_2 (planes 1-3 and 2-3 active)

#: Status of a kernel that met an inadmissible material parameter or time step (``info[0]`` = the
#: point, ``info[1]`` = the parameter column, -1 for ``dt``). Local to the plasticity kernels: the
#: Python wrappers validate the parameters first, so it only reaches a caller that bypasses them.
#: Chosen outside the range used by masonrydam.errors (0-3) so it cannot be confused with those.
STATUS_BAD_MATERIAL = 10

#: length of the scratch array ``work`` of the point functions
WORK_SIZE = 64
W_EPS = 0  # 6: 3D strain of the point
W_SIG = 6  # 6: 3D stress
W_N = 12  # 6: unit deviatoric direction (tensor components)
W_D = 18  # 36: 6x6 tangent, row-major
W_SCRATCH = 54  # 10 free

SQRT2 = math.sqrt(2.0)
SQRT3 = math.sqrt(3.0)
SQRT_2_3 = math.sqrt(2.0 / 3.0)
SQRT_3_2 = math.sqrt(1.5)

# indices of the plane-strain components [xx, yy, xy] in the 6-vector
PLANE_IDX = (0, 1, 3)


# ----------------------------------------------------------------------------------------------
# compiled helpers
# ----------------------------------------------------------------------------------------------


@njit(cache=True)
def embed_strain(eps, work):
    """Copy the point strain ``eps`` (3 plane strain or 6 3D components) into ``work[W_EPS:W_EPS+6]``
    as a 3D engineering strain (plane strain: ``ezz = gyz = gzx = 0``)."""
    if eps.shape[0] == 3:
        work[W_EPS + 0] = eps[0]
        work[W_EPS + 1] = eps[1]
        work[W_EPS + 2] = 0.0
        work[W_EPS + 3] = eps[2]
        work[W_EPS + 4] = 0.0
        work[W_EPS + 5] = 0.0
    else:
        for i in range(6):
            work[W_EPS + i] = eps[i]


@njit(cache=True)
def extract_stress(work, sig):
    """Point stress ``sig`` (3 or 6 components) from the 3D stress ``work[W_SIG:W_SIG+6]``."""
    if sig.shape[0] == 3:
        sig[0] = work[W_SIG + 0]
        sig[1] = work[W_SIG + 1]
        sig[2] = work[W_SIG + 3]
    else:
        for i in range(6):
            sig[i] = work[W_SIG + i]


@njit(cache=True)
def extract_tangent(work, D):
    """Point tangent ``D`` (3x3 or 6x6) from the 6x6 tangent in ``work[W_D:W_D+36]``; in plane
    strain the rows and columns xx, yy, xy (``ezz = 0`` is imposed, so no condensation)."""
    ns = D.shape[0]
    if ns == 3:
        for a in range(3):
            ia = PLANE_IDX[a]
            for b in range(3):
                D[a, b] = work[W_D + 6 * ia + PLANE_IDX[b]]
    else:
        for i in range(6):
            for j in range(6):
                D[i, j] = work[W_D + 6 * i + j]


@njit(cache=True)
def isotropic_tangent(work, K, G2theta):
    """``work`` 6x6 tangent := ``K 1(x)1 + G2theta (I - 1/3 1(x)1)`` (Voigt, engineering strain
    columns): the elastic tangent for ``G2theta = 2G``."""
    for i in range(6):
        for j in range(6):
            work[W_D + 6 * i + j] = 0.0
    for i in range(3):
        for j in range(3):
            work[W_D + 6 * i + j] = K + G2theta * ((1.0 if i == j else 0.0) - 1.0 / 3.0)
    for i in range(3, 6):
        work[W_D + 6 * i + i] = 0.5 * G2theta


@njit(cache=True)
def trial_split(work, state_committed, k, K, G2):
    """Elastic trial from the 3D strain in ``work``: returns ``(p_trial, tr)`` and writes the trial
    deviatoric stress ``s_trial = 2G dev(eps - eps_p)`` (tensor components) into ``work[W_SIG:]``.

    ``tr`` is the trial elastic volumetric strain, ``p_trial = K tr`` the trial mean stress
    (tension positive)."""
    e0 = work[W_EPS + 0] - state_committed[k, S_PLASTIC_STRAIN + 0]
    e1 = work[W_EPS + 1] - state_committed[k, S_PLASTIC_STRAIN + 1]
    e2 = work[W_EPS + 2] - state_committed[k, S_PLASTIC_STRAIN + 2]
    tr = e0 + e1 + e2
    m = tr / 3.0
    work[W_SIG + 0] = G2 * (e0 - m)
    work[W_SIG + 1] = G2 * (e1 - m)
    work[W_SIG + 2] = G2 * (e2 - m)
    for i in range(3, 6):  # tensor shear strain = engineering / 2
        work[W_SIG + i] = 0.5 * G2 * (work[W_EPS + i] - state_committed[k, S_PLASTIC_STRAIN + i])
    return K * tr, tr


@njit(cache=True)
def tensor_norm(work, off):
    """Frobenius norm of the symmetric tensor whose Voigt tensor components are ``work[off:off+6]``."""
    s = 0.0
    for i in range(3):
        s += work[off + i] * work[off + i]
    for i in range(3, 6):
        s += 2.0 * work[off + i] * work[off + i]
    return math.sqrt(s)


@njit(cache=True)
def viscous_term(eta, dt):
    """The Perzyna term of the discrete consistency condition: returns ``(flow, eta_dt)``.

    Backward Euler on ``gamma_dot = <f> / eta`` over ``dt`` gives ``f_(n+1) = eta/dt * dgamma``
    (Simo & Hughes 1998, sec. 2.7; de Souza Neto et al. 2008, sec. 11.5): the rate-independent
    return with ``eta/dt`` added to its denominator. ``eta = 0``: rate independent, ``eta_dt = 0``.
    ``eta > 0`` with ``dt = 0``: no time for viscous flow, ``flow = False`` (elastic response).
    """
    if eta > 0.0:
        if dt > 0.0:
            return True, eta / dt
        return False, 0.0
    return True, 0.0


@njit(cache=True)
def piecewise_root(r0, a1, a2, x_kink):
    """Root ``x >= 0`` of ``r(x) = r0 - a1 x`` (``x <= x_kink``), continued with slope ``-a2`` past
    ``x_kink`` (``r0 > 0``, ``a1, a2 > 0``): the consistency condition of a linear hardening law
    that stops at a residual value (``a2`` is the slope without hardening). Returns
    ``(x, on_first_segment)``; ``x_kink = inf`` for a law without a kink."""
    if a1 > 0.0 and r0 <= a1 * x_kink:
        return r0 / a1, True
    return x_kink + (r0 - a1 * x_kink) / a2, False


@njit(cache=True)
def kink_distance(h, y0, y_res, kappa_n):
    """Distance ``kappa_k - kappa_n >= 0`` in the hardening variable to the point where the linear
    law ``y0 + h kappa`` reaches the residual value ``y_res`` (``inf`` unless ``h < 0``)."""
    if h < 0.0:
        d = (y_res - y0) / h - kappa_n
        return d if d > 0.0 else 0.0
    return np.inf


@njit(cache=True)
def copy_state_row(state_committed, state_trial, k, n_state):
    for j in range(n_state):
        state_trial[k, j] = state_committed[k, j]


@njit(cache=True)
def fail_point(state_committed, state_trial, k, sig, D, want_tangent, n_state):
    """Outputs of a point that could not be evaluated: trial state = committed, stress NaN,
    tangent zero."""
    copy_state_row(state_committed, state_trial, k, n_state)
    for i in range(sig.shape[0]):
        sig[i] = np.nan
    if want_tangent:
        for i in range(D.shape[0]):
            for j in range(D.shape[1]):
                D[i, j] = 0.0


@njit(cache=True)
def row_finite(a, k, n):
    for j in range(n):
        if not math.isfinite(a[k, j]):
            return False
    return True


@njit(cache=True)
def vec_finite(a):
    for j in range(a.shape[0]):
        if not math.isfinite(a[j]):
            return False
    return True


@njit(cache=True)
def outputs_finite(sig, D, want_tangent):
    if not vec_finite(sig):
        return False
    if want_tangent:
        for i in range(D.shape[0]):
            for j in range(D.shape[1]):
                if not math.isfinite(D[i, j]):
                    return False
    return True


@njit(cache=True)
def point_moduli(params, p):
    """Bulk and shear moduli ``(K, G)`` (Pa) of parameter row ``p`` (columns ``P_E``, ``P_NU``)."""
    E = params[p, P_E]
    nu = params[p, P_NU]
    return E / (3.0 * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


@njit(cache=True)
def bad_common_column(params, p):
    """First inadmissible shared parameter column of row ``p`` (``P_E``: E > 0, ``P_NU``:
    -1 < nu < 0.5, ``P_VISCOSITY``: eta >= 0), or -2 if these are fine. A law's own check of its
    columns follows (then ``dt >= 0``, column -1, in :func:`point_inputs_status`)."""
    if not params[p, P_E] > 0.0:
        return P_E
    if not (-1.0 < params[p, P_NU] < 0.5):
        return P_NU
    if not params[p, P_VISCOSITY] >= 0.0:
        return P_VISCOSITY
    return -2


@njit(cache=True)
def point_inputs_status(eps, params, p, n_params, state_committed, state_trial, k, n_state, dt, bad, want_tangent,
                        sig, D, work):
    """Input check at the start of a point kernel: ``STATUS_NAN`` for a non-finite strain, parameter
    row ``p`` (``n_params`` columns), committed state row ``k`` (``n_state`` columns) or ``dt``;
    else ``STATUS_BAD_MATERIAL`` when ``bad`` (the law's first inadmissible parameter column, -2 for
    none) is not -2 or, after the parameters, ``dt < 0`` (column -1), with ``work[W_SCRATCH]`` = the
    column; else ``STATUS_OK``. On failure the outputs are those of :func:`fail_point`."""
    if not (vec_finite(eps) and row_finite(params, p, n_params) and row_finite(state_committed, k, n_state)
            and math.isfinite(dt)):
        fail_point(state_committed, state_trial, k, sig, D, want_tangent, n_state)
        return STATUS_NAN
    if bad == -2 and not dt >= 0.0:
        bad = -1
    if bad != -2:
        fail_point(state_committed, state_trial, k, sig, D, want_tangent, n_state)
        work[W_SCRATCH] = bad
        return STATUS_BAD_MATERIAL
    return STATUS_OK


@njit(cache=True)
def point_trial(eps, params, p, state_committed, k, work):
    """Elastic trial of a point: returns ``(K, G, p_trial)`` (moduli of row ``p``, trial mean stress,
    Pa), with the 3D strain in ``work[W_EPS:]`` (:func:`embed_strain`) and the trial deviatoric stress
    in ``work[W_SIG:]`` (:func:`trial_split`)."""
    K, G = point_moduli(params, p)
    embed_strain(eps, work)
    p_tr, _ = trial_split(work, state_committed, k, K, 2.0 * G)
    return K, G, p_tr


@njit(cache=True)
def finish_point(work, state_committed, state_trial, k, n_state, want_tangent, sig, D):
    """End of a point kernel: stores the 3D stress ``work[W_SIG:]`` in ``state_trial[k, S_STRESS:]``,
    writes ``sig`` and (``want_tangent``) ``D`` from ``work`` and returns ``STATUS_OK``, or
    ``STATUS_NAN`` with the outputs of :func:`fail_point` when a result is not finite."""
    for i in range(6):
        state_trial[k, S_STRESS + i] = work[W_SIG + i]
    extract_stress(work, sig)
    if want_tangent:
        extract_tangent(work, D)
    if not (outputs_finite(sig, D, want_tangent) and row_finite(state_trial, k, n_state)):
        fail_point(state_committed, state_trial, k, sig, D, want_tangent, n_state)
        return STATUS_NAN
    return STATUS_OK


@njit(cache=True, inline="always")
def batch_update(point, strain, params, state_committed, state_trial, stress_out, tangent_out, dt, want_tangent, info):
    """Batch update of a law: its point kernel ``point`` (e.g.
    :func:`masonrydam.materials.von_mises.von_mises_point`) for every row, point ``k`` with
    parameter row ``k`` and state row ``k``.

    Inlined (numba IR inlining) into each law's ``*_update``, which passes its point kernel: there
    ``point`` is a compile-time constant, so the law's batch function stays cachable (a jitted
    function passed across a compiled call, or captured by a closure, would not be).

    Parameters
    ----------
    point : jitted point kernel with the signature of
        :func:`masonrydam.materials.von_mises.von_mises_point`.
    strain : float64 (n, ns)
        Total strains, ns = 3 (plane strain) or 6 (3D), engineering shear.
    params : float64 (n, n_params)
        One parameter row per point.
    state_committed : float64 (n, n_state)
        Read only.
    state_trial : float64 (n, n_state), out
    stress_out : float64 (n, ns), out
        Stress (Pa).
    tangent_out : float64 (n, ns, ns), out
        Consistent tangent (Pa); not touched when ``want_tangent`` is False (any first dimension).
    dt : float
        Time step (s), >= 0 (Perzyna only).
    want_tangent : bool
    info : int64 (>= 1,), out
        ``info[0]`` = the failing point; ``info[1]`` (if present) = the bad parameter column (-1 dt).

    Returns
    -------
    int
        Status of the first failing point (the later points are not evaluated), else STATUS_OK.
    """
    n = strain.shape[0]
    ns = strain.shape[1]
    work = np.empty(WORK_SIZE)
    eps = np.empty(ns)
    sig = np.empty(ns)
    D = np.empty((ns, ns))
    for k in range(n):
        for i in range(ns):
            eps[i] = strain[k, i]
        status = point(eps, params, k, state_committed, state_trial, k, dt, want_tangent, sig, D, work)
        for i in range(ns):
            stress_out[k, i] = sig[i]
        if want_tangent:
            for i in range(ns):
                for j in range(ns):
                    tangent_out[k, i, j] = D[i, j]
        if status != STATUS_OK:
            info[0] = k
            if status == STATUS_BAD_MATERIAL and info.shape[0] > 1:
                info[1] = int(work[W_SCRATCH])
            return status
    return STATUS_OK


# ----------------------------------------------------------------------------------------------
# Python side: shape checks and status -> exception
# ----------------------------------------------------------------------------------------------


def as_float_table(name: str, value, ncol: int | None = None, nrow: int | None = None) -> np.ndarray:
    """``value`` as a C-contiguous float64 2D array, checking the column and row counts."""
    a = np.ascontiguousarray(value, dtype=np.float64)
    if a.ndim == 1 and ncol is not None and a.shape[0] == ncol:
        a = a.reshape(1, ncol)
    if a.ndim != 2:
        raise ValueError(f"{name} must be a 2D array (points, columns), got shape {np.shape(value)}")
    if ncol is not None and a.shape[1] != ncol:
        raise ValueError(f"{name} must have {ncol} columns, got shape {a.shape}")
    if nrow is not None and a.shape[0] != nrow:
        raise ValueError(f"{name} must have {nrow} rows (one per point), got shape {a.shape}")
    return a


def check_batch(strain, params, state_committed, n_params: int, n_state: int):
    """Validated ``(strain, params, state_committed)`` arrays of a batch update; ``params`` may be
    one row (broadcast to all points)."""
    strain = as_float_table("strain", strain)
    n, ns = strain.shape
    if ns not in (3, 6):
        raise ValueError(f"strain must have 3 (plane strain) or 6 (3D) components, got shape {strain.shape}")
    params = as_float_table("params", params, ncol=n_params)
    if params.shape[0] == 1 and n != 1:
        params = np.ascontiguousarray(np.broadcast_to(params, (n, n_params)))
    if params.shape[0] != n:
        raise ValueError(f"params must have 1 or {n} rows (one per point), got shape {params.shape}")
    state_committed = as_float_table("state_committed", state_committed, ncol=n_state, nrow=n)
    return strain, params, state_committed


def check_dt(dt) -> float:
    try:
        dt = float(dt)
    except (TypeError, ValueError):
        raise ValueError(f"dt must be a real number >= 0 (s), got {dt!r}") from None
    if not (math.isfinite(dt) and dt >= 0.0):
        raise ValueError(f"dt must be finite and >= 0 (s), got {dt!r}")
    return dt


def raise_for_status(status: int, info: np.ndarray, law: str, param_names: dict) -> None:
    """Turn a kernel status into an exception (NumericalError for non-finite values, ValueError
    naming the parameter for an inadmissible one)."""
    if status == STATUS_OK:
        return
    point = int(info[0])
    if status == STATUS_NAN:
        raise NumericalError(f"{law}: non-finite strain, parameter, state or result at point {point}")
    if status == STATUS_BAD_MATERIAL:
        col = int(info[1])
        name = "dt" if col < 0 else param_names.get(col, f"column {col}")
        raise ValueError(f"{law}: inadmissible {name} at point {point}")
    raise NumericalError(f"{law}: kernel status {status} at point {point}")


def real_parameter(law: str, name: str, value) -> float:
    """``float(value)``, finite, or a ValueError naming the parameter."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{law} parameter {name} must be a real number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{law} parameter {name} must be finite, got {value!r}")
    return v


def elastic_moduli(E: float, nu: float) -> tuple[float, float]:
    """Bulk and shear moduli ``(K, G)`` of ``E, nu`` (Pa)."""
    return E / (3.0 * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


def check_elastic(law: str, E: float, nu: float, where: str = "") -> None:
    if not E > 0.0:
        raise ValueError(f"{law} parameter youngs_modulus must be > 0 (Pa){where}, got {E!r}")
    if not -1.0 < nu < 0.5:
        raise ValueError(f"{law} parameter poisson_ratio must satisfy -1 < nu < 0.5{where}, got {nu!r}")


@dataclass(frozen=True)
class PlasticLaw:
    """What the shared Python helpers need to know of a law's tables."""

    name: str  #: the law in messages, e.g. "von Mises"
    n_params: int  #: columns of a parameter row
    n_state: int  #: columns of a state row
    param_names: dict  #: parameter column -> name in messages (every column)


def check_param_table(law: PlasticLaw, params, check_row: Callable[[np.ndarray, str], None]) -> np.ndarray:
    """Validate a parameter table (n, law.n_params) or row; returns it as a float64 2D array.

    Row by row: every column finite, then :func:`check_elastic`, then ``check_row(row, where)``, the
    law's own checks (``where`` names the row of a table with more than one, else ""). Raises
    ValueError naming the parameter, the row and the value."""
    t = as_float_table("params", params, ncol=law.n_params)
    for r in range(t.shape[0]):
        row = t[r]
        where = f" (row {r})" if t.shape[0] > 1 else ""
        for col, name in law.param_names.items():
            if not math.isfinite(row[col]):
                raise ValueError(f"{law.name} parameter {name} must be finite{where}, got {row[col]!r}")
        check_elastic(law.name, row[P_E], row[P_NU], where)
        check_row(row, where)
    return t


def real_parameters(law: PlasticLaw, values: dict) -> dict:
    """``{name: float}`` of the named parameter values (:func:`real_parameter`), checked with
    :func:`check_elastic` (``values`` holds "youngs_modulus" and "poisson_ratio")."""
    v = {name: real_parameter(law.name, name, x) for name, x in values.items()}
    check_elastic(law.name, v["youngs_modulus"], v["poisson_ratio"])
    return v


def param_row(law: PlasticLaw, columns: dict) -> np.ndarray:
    """Parameter row (law.n_params,) with ``row[col] = value`` for each ``col: value`` of ``columns``
    (the other columns 0)."""
    row = np.zeros(law.n_params)
    for col, value in columns.items():
        row[col] = value
    return row


def initial_state(law: PlasticLaw, n: int) -> np.ndarray:
    """Virgin state (n, law.n_state): all columns zero (no stress, no plastic strain, CODE_ELASTIC)."""
    return np.zeros((int(n), law.n_state))


def evaluate(law: PlasticLaw, update, check_params, strain, params, state_committed, dt, want_tangent):
    """The Python wrapper of a law's batch kernel ``update`` (signature of :func:`batch_update` less
    ``point``): checks shapes (:func:`check_batch`), parameters (``check_params``, the law's table
    check) and ``dt`` once, runs the kernel and turns its status into an exception
    (:func:`raise_for_status`).

    Returns ``(stress (n, ns), tangent (n, ns, ns) or None, state_trial (n, law.n_state))``; the
    shapes and exceptions are those documented by
    :func:`masonrydam.materials.von_mises.von_mises_evaluate`."""
    strain, params, state_committed = check_batch(strain, params, state_committed, law.n_params, law.n_state)
    params = check_params(params)
    dt = check_dt(dt)
    n, ns = strain.shape
    stress = np.empty((n, ns))
    tangent = np.empty((n if want_tangent else 0, ns, ns))
    state_trial = np.empty((n, law.n_state))
    info = np.zeros(2, dtype=np.int64)
    status = update(strain, params, state_committed, state_trial, stress, tangent, dt, bool(want_tangent), info)
    raise_for_status(status, info, law.name, law.param_names)
    return stress, (tangent if want_tangent else None), state_trial
