"""Shared pieces of the continuum plasticity laws (:mod:`.von_mises`, :mod:`.drucker_prager`).

Small strains, isotropic linear elasticity, Voigt vectors with engineering shear strains
(docs/architecture.md): 2D plane strain ``[exx, eyy, gxy]`` (``ezz = gyz = gzx = 0``) and 3D
``[exx, eyy, ezz, gxy, gyz, gzx]``; stresses ``[sxx, syy, (szz,) sxy, (syz, szx)]``, tension
positive. The laws work on the full 3D stress internally; a plane-strain point embeds its strain in
3D, returns the in-plane stress ``[sxx, syy, sxy]`` and the 3x3 block (rows and columns xx, yy, xy)
of the 6x6 tangent, and keeps ``szz`` in its state.

Tensor conventions used by the kernels (Simo & Hughes 1998, *Computational Inelasticity*, ch. 3;
de Souza Neto, Peric & Owen 2008, *Computational Methods for Plasticity*, ch. 7):
stress-like Voigt vectors (stress, back stress, deviatoric unit normals) hold tensor components;
strain-like vectors (total and plastic strain) hold engineering shear components (twice the
tensor component). With these, ``a : b = sum_i a_i b_i`` for a stress-like ``a`` and a strain-like
``b``, and a 4th-order tensor ``C`` acting on a strain is the Voigt matrix ``D[i, j] = C_(i)(j)``
(``D[i, j] = d sigma_i / d eps_j`` with engineering ``eps_j``): the identity on symmetric tensors is
``diag(1, 1, 1, 1/2, 1/2, 1/2)``, ``1 (x) 1`` has ones in the normal block, and ``n (x) m`` is
``n_i m_j`` with the tensor components of both.

State columns shared by both laws (float64 rows, one per integration point; the laws append their
own columns after ``N_COMMON_STATE``)::

    S_STRESS              6 columns: stress [sxx, syy, szz, sxy, syz, szx] (Pa), the full 3D stress
                          also in plane strain (szz is kept there)
    S_PLASTIC_STRAIN      6 columns: plastic strain [exx, eyy, ezz, gxy, gyz, gzx] (engineering shear)
    S_EQ_PLASTIC_STRAIN   the hardening variable of the law (see each law), >= 0
    S_CODE                what the last update did: CODE_ELASTIC, CODE_PLASTIC, CODE_APEX (DP only)

Parameter columns shared by both laws (the laws append theirs after ``N_COMMON_PARAMS``)::

    P_E           Young's modulus E (Pa), > 0
    P_NU          Poisson's ratio nu, -1 < nu < 0.5
    P_VISCOSITY   Perzyna viscosity eta (Pa s), >= 0; 0 is rate independent (see each law)

Trial / commit / revert (docs/architecture.md): a kernel reads ``state_committed`` (never writes
it) and writes ``state_trial``; the solver copies trial to committed when a step converges. The
update is in total form, ``sigma = C : (eps - eps_p_committed)`` for the trial, so repeated
evaluations within a step never drift.
"""
from __future__ import annotations

import math

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
