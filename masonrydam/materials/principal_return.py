"""Shared pieces of the plasticity laws whose return mapping is done in principal stresses
(:mod:`.mohr_coulomb_solid`, :mod:`.tresca`; de Souza Neto, Peric & Owen 2008, sec. 8.1 and appendix A):

- :func:`sym_eig3`: eigenvalues and orthonormal eigenvectors of a symmetric 3x3 matrix (cyclic
  Jacobi rotations; exact orthogonality, repeated eigenvalues need no special case, no allocation,
  deterministic);
- :func:`principal_trial`: the trial stress of :func:`masonrydam.materials.plasticity.point_trial`
  decomposed, eigenvalues sorted ``sigma_1 >= sigma_2 >= sigma_3`` (tension positive);
- :func:`principal_stress_out`, :func:`principal_plastic_strain`: back to Voigt vectors (the stress,
  and the plastic strain increment ``-C^-1 : (sigma - sigma_tr)``);
- :func:`principal_tangent`: the consistent tangent of the isotropic tensor function from the
  principal-space tangent (Carlson & Hoger 1986; Miehe 1993), including repeated eigenvalues;
- Voigt <-> tensor conversions in the conventions of :mod:`masonrydam.materials.plasticity`.

Scratch slots ``W_PR_*`` in the float64 ``work`` array of plasticity.py. Theory and the scratch layout:
docs/continuum_nonlinearity.md, section "Returns in principal stresses" (under "The plastic laws in equations").
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .plasticity import W_D, W_EPS, W_SCRATCH, W_SIG

__all__ = [
    "W_PR_TRIAL", "W_PR_NEW", "W_PR_DSIG", "W_PR_VEC", "W_PR_JAC", "REPEATED_TOL", "VOIGT_I", "VOIGT_J",
    "sym_eig3", "principal_trial", "principal_stress_out", "principal_plastic_strain", "principal_tangent",
    "stress_voigt_to_tensor", "strain_voigt_to_tensor", "tensor_to_stress_voigt", "tensor_to_strain_voigt",
    "principal_stresses",
]

W_PR_TRIAL = W_EPS  # 3
W_PR_NEW = W_EPS + 3  # 3
W_PR_DSIG = W_SIG  # 9 (W_SIG and the first 3 of W_N)
W_PR_VEC = W_SCRATCH  # 9
W_PR_JAC = W_D  # 9

#: relative gap below which two principal trial stresses count as repeated in :func:`principal_tangent`
REPEATED_TOL = 1.0e-8

#: tensor indices (i, j) of the Voigt components [xx, yy, zz, xy, yz, zx]
VOIGT_I = (0, 1, 2, 0, 1, 2)
VOIGT_J = (0, 1, 2, 1, 2, 0)

_MAX_SWEEPS = 50


# ----------------------------------------------------------------------------------------------
# Voigt <-> tensor (numba and Python)
# ----------------------------------------------------------------------------------------------


@njit(cache=True)
def stress_voigt_to_tensor(v, T):
    """Symmetric 3x3 ``T`` (out) of a stress-like Voigt 6-vector ``v`` (tensor components)."""
    for c in range(6):
        i = VOIGT_I[c]
        j = VOIGT_J[c]
        T[i, j] = v[c]
        T[j, i] = v[c]


@njit(cache=True)
def strain_voigt_to_tensor(v, T):
    """Symmetric 3x3 ``T`` (out) of a strain-like Voigt 6-vector ``v`` (engineering shear)."""
    for c in range(6):
        i = VOIGT_I[c]
        j = VOIGT_J[c]
        x = v[c] if c < 3 else 0.5 * v[c]
        T[i, j] = x
        T[j, i] = x


@njit(cache=True)
def tensor_to_stress_voigt(T, v):
    """Stress-like Voigt 6-vector ``v`` (out, tensor components) of a symmetric 3x3 ``T``."""
    for c in range(6):
        v[c] = T[VOIGT_I[c], VOIGT_J[c]]


@njit(cache=True)
def tensor_to_strain_voigt(T, v):
    """Strain-like Voigt 6-vector ``v`` (out, engineering shear) of a symmetric 3x3 ``T``."""
    for c in range(6):
        x = T[VOIGT_I[c], VOIGT_J[c]]
        v[c] = x if c < 3 else 2.0 * x


# ----------------------------------------------------------------------------------------------
# eigen-decomposition
# ----------------------------------------------------------------------------------------------


@njit(cache=True)
def sym_eig3(work, a_off, v_off):
    """Eigen-decomposition of the symmetric 3x3 matrix ``A = work[a_off:a_off+9]`` (row-major, both
    triangles set) by cyclic Jacobi rotations (Golub & Van Loan 2013, *Matrix Computations*,
    sec. 8.5). On return the diagonal of ``A`` holds the eigenvalues (unsorted; the off-diagonal
    entries are ~0) and ``work[v_off + 3 i + a]`` is component i of the unit eigenvector of the
    a-th diagonal entry (an orthogonal matrix to rounding). Repeated eigenvalues need no special
    treatment (any orthonormal basis of their eigenspace is returned). Returns the number of sweeps.
    """
    for i in range(3):
        for j in range(3):
            work[v_off + 3 * i + j] = 1.0 if i == j else 0.0
    sweeps = 0
    for sweep in range(_MAX_SWEEPS):
        off = 0.0
        tot = 0.0
        for i in range(3):
            for j in range(3):
                x = work[a_off + 3 * i + j] * work[a_off + 3 * i + j]
                tot += x
                if i != j:
                    off += x
        if off == 0.0 or off <= 1.0e-36 * tot:
            break
        sweeps = sweep + 1
        for pair in range(3):
            if pair == 0:
                p, q, r = 0, 1, 2
            elif pair == 1:
                p, q, r = 0, 2, 1
            else:
                p, q, r = 1, 2, 0
            apq = work[a_off + 3 * p + q]
            if apq == 0.0:
                continue
            app = work[a_off + 3 * p + p]
            aqq = work[a_off + 3 * q + q]
            # rotation angle phi with tan(2 phi) = 2 apq / (app - aqq): t = tan(phi), the smaller root
            theta = (aqq - app) / (2.0 * apq)
            if abs(theta) > 1.0e150:
                t = 0.5 / theta
            else:
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
            c = 1.0 / math.sqrt(t * t + 1.0)
            s = t * c
            arp = work[a_off + 3 * r + p]
            arq = work[a_off + 3 * r + q]
            work[a_off + 3 * p + p] = app - t * apq
            work[a_off + 3 * q + q] = aqq + t * apq
            work[a_off + 3 * p + q] = 0.0
            work[a_off + 3 * q + p] = 0.0
            nrp = c * arp - s * arq
            nrq = s * arp + c * arq
            work[a_off + 3 * r + p] = nrp
            work[a_off + 3 * p + r] = nrp
            work[a_off + 3 * r + q] = nrq
            work[a_off + 3 * q + r] = nrq
            for i in range(3):
                vip = work[v_off + 3 * i + p]
                viq = work[v_off + 3 * i + q]
                work[v_off + 3 * i + p] = c * vip - s * viq
                work[v_off + 3 * i + q] = s * vip + c * viq
    return sweeps


@njit(cache=True)
def _swap_columns(work, a, b):
    t = work[W_PR_TRIAL + a]
    work[W_PR_TRIAL + a] = work[W_PR_TRIAL + b]
    work[W_PR_TRIAL + b] = t
    for i in range(3):
        t = work[W_PR_VEC + 3 * i + a]
        work[W_PR_VEC + 3 * i + a] = work[W_PR_VEC + 3 * i + b]
        work[W_PR_VEC + 3 * i + b] = t


@njit(cache=True)
def principal_trial(work, p_tr):
    """Principal trial stresses and directions of the trial stress ``s_tr + p_tr 1`` (``s_tr`` the
    trial deviator in ``work[W_SIG:]`` written by
    :func:`masonrydam.materials.plasticity.point_trial`, tensor components; ``p_tr`` Pa).

    Writes ``work[W_PR_TRIAL:+3]`` = ``sigma_tr_1 >= sigma_tr_2 >= sigma_tr_3`` and the matching unit
    eigenvectors in ``work[W_PR_VEC:+9]``; uses ``W_PR_JAC`` (inside ``W_D``) as scratch and leaves
    ``W_SIG`` as it was."""
    for c in range(6):
        i = VOIGT_I[c]
        j = VOIGT_J[c]
        x = work[W_SIG + c] + (p_tr if c < 3 else 0.0)
        work[W_PR_JAC + 3 * i + j] = x
        work[W_PR_JAC + 3 * j + i] = x
    sym_eig3(work, W_PR_JAC, W_PR_VEC)
    for a in range(3):
        work[W_PR_TRIAL + a] = work[W_PR_JAC + 4 * a]
    # sort descending (three compare-swaps)
    if work[W_PR_TRIAL + 0] < work[W_PR_TRIAL + 1]:
        _swap_columns(work, 0, 1)
    if work[W_PR_TRIAL + 1] < work[W_PR_TRIAL + 2]:
        _swap_columns(work, 1, 2)
    if work[W_PR_TRIAL + 0] < work[W_PR_TRIAL + 1]:
        _swap_columns(work, 0, 1)


@njit(cache=True)
def principal_stress_out(work, off, out_off):
    """``work[out_off:out_off+6]`` := the stress-like Voigt vector of ``sum_a y_a v_a (x) v_a`` with
    ``y_a = work[off + a]`` and the eigenvectors of ``W_PR_VEC``."""
    for c in range(6):
        i = VOIGT_I[c]
        j = VOIGT_J[c]
        x = 0.0
        for a in range(3):
            x += work[off + a] * work[W_PR_VEC + 3 * i + a] * work[W_PR_VEC + 3 * j + a]
        work[out_off + c] = x


@njit(cache=True)
def principal_plastic_strain(work, state_trial, k, col, K, G):
    """Adds the plastic strain increment ``d eps_p = -C^-1 : (sigma - sigma_tr)`` to
    ``state_trial[k, col:col+6]`` (engineering shear), from the principal trial and returned stresses
    (``W_PR_TRIAL``, ``W_PR_NEW``) and the eigenvectors: with total strain fixed,
    ``sigma - sigma_tr = -C : d eps_p`` (de Souza Neto et al. sec. 8.1). ``C^-1 = 1/(9K) 1(x)1 +
    1/(2G) I_dev``."""
    d0 = work[W_PR_NEW + 0] - work[W_PR_TRIAL + 0]
    d1 = work[W_PR_NEW + 1] - work[W_PR_TRIAL + 1]
    d2 = work[W_PR_NEW + 2] - work[W_PR_TRIAL + 2]
    m = (d0 + d1 + d2) / 3.0
    e0 = -(m / (3.0 * K) + (d0 - m) / (2.0 * G))
    e1 = -(m / (3.0 * K) + (d1 - m) / (2.0 * G))
    e2 = -(m / (3.0 * K) + (d2 - m) / (2.0 * G))
    for c in range(6):
        i = VOIGT_I[c]
        j = VOIGT_J[c]
        x = (e0 * work[W_PR_VEC + 3 * i] * work[W_PR_VEC + 3 * j]
             + e1 * work[W_PR_VEC + 3 * i + 1] * work[W_PR_VEC + 3 * j + 1]
             + e2 * work[W_PR_VEC + 3 * i + 2] * work[W_PR_VEC + 3 * j + 2])
        state_trial[k, col + c] += x if c < 3 else 2.0 * x


# ----------------------------------------------------------------------------------------------
# consistent tangent
# ----------------------------------------------------------------------------------------------


@njit(cache=True)
def principal_tangent(work, K, G):
    """Consistent tangent (6x6, ``work[W_D:W_D+36]``, row-major) of the isotropic stress function
    from the principal-space derivative ``Dsig[a, b] = d sigma_a / d sigma_tr_b`` in ``W_PR_DSIG``
    (module docstring; de Souza Neto et al. 2008, appendix A, box A.6, eqs. A.46-A.48).

    Needs ``W_PR_TRIAL``, ``W_PR_NEW`` and ``W_PR_VEC``; replaces ``W_PR_DSIG`` by
    ``Dp = Dsig . De`` (Pa). Any Voigt column ordering of the eigenvectors is fine."""
    lam = K - 2.0 * G / 3.0
    # Dp = Dsig . De, De = lam 1(x)1 + 2G I (principal space), row by row in place
    for a in range(3):
        r0 = work[W_PR_DSIG + 3 * a + 0]
        r1 = work[W_PR_DSIG + 3 * a + 1]
        r2 = work[W_PR_DSIG + 3 * a + 2]
        sr = lam * (r0 + r1 + r2)
        work[W_PR_DSIG + 3 * a + 0] = sr + 2.0 * G * r0
        work[W_PR_DSIG + 3 * a + 1] = sr + 2.0 * G * r1
        work[W_PR_DSIG + 3 * a + 2] = sr + 2.0 * G * r2
    scale = 0.0
    for a in range(3):
        x = abs(work[W_PR_TRIAL + a])
        if x > scale:
            scale = x
    th01 = _theta(work, 0, 1, G, scale)
    th02 = _theta(work, 0, 2, G, scale)
    th12 = _theta(work, 1, 2, G, scale)
    for I in range(6):
        i = VOIGT_I[I]
        j = VOIGT_J[I]
        for J in range(6):
            k = VOIGT_I[J]
            l = VOIGT_J[J]
            x = 0.0
            for a in range(3):
                ea = work[W_PR_VEC + 3 * i + a] * work[W_PR_VEC + 3 * j + a]
                if ea == 0.0:
                    continue
                for b in range(3):
                    eb = work[W_PR_VEC + 3 * k + b] * work[W_PR_VEC + 3 * l + b]
                    x += work[W_PR_DSIG + 3 * a + b] * ea * eb
            x += 2.0 * th01 * _s_ab(work, 0, 1, i, j) * _s_ab(work, 0, 1, k, l)
            x += 2.0 * th02 * _s_ab(work, 0, 2, i, j) * _s_ab(work, 0, 2, k, l)
            x += 2.0 * th12 * _s_ab(work, 1, 2, i, j) * _s_ab(work, 1, 2, k, l)
            work[W_D + 6 * I + J] = x


@njit(cache=True)
def _s_ab(work, a, b, i, j):
    """Component (i, j) of S_ab = (v_a (x) v_b + v_b (x) v_a) / 2."""
    return 0.5 * (work[W_PR_VEC + 3 * i + a] * work[W_PR_VEC + 3 * j + b]
                  + work[W_PR_VEC + 3 * i + b] * work[W_PR_VEC + 3 * j + a])


@njit(cache=True)
def _theta(work, a, b, G, scale):
    """theta_ab of the module docstring (Pa): the quotient for distinct principal trial stresses,
    the limit from ``Dp`` (already in ``W_PR_DSIG``) for repeated ones."""
    gap = work[W_PR_TRIAL + a] - work[W_PR_TRIAL + b]
    if abs(gap) > REPEATED_TOL * scale:
        return 2.0 * G * (work[W_PR_NEW + a] - work[W_PR_NEW + b]) / gap
    return 0.5 * (work[W_PR_DSIG + 4 * a] - work[W_PR_DSIG + 3 * a + b] + work[W_PR_DSIG + 4 * b]
                  - work[W_PR_DSIG + 3 * b + a])


def principal_stresses(stress) -> np.ndarray:
    """Python helper: principal stresses (descending) of a stress-like Voigt 6-vector."""
    T = np.zeros((3, 3))
    stress_voigt_to_tensor(np.ascontiguousarray(stress, dtype=np.float64), T)
    return np.linalg.eigvalsh(T)[::-1].copy()
