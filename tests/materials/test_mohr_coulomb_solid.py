"""Tests of the Mohr-Coulomb plasticity law of solids (masonrydam.materials.mohr_coulomb_solid) and
of the principal-space helpers it uses (masonrydam.materials.principal_return).

Sources: de Souza Neto, Peric & Owen (2008), Computational Methods for Plasticity: the Mohr-Coulomb
planes, the return to the main plane, the edges and the apex (sec. 8.2.2, boxes 8.4-8.5), the
hardening variable eps_bar_dot = 2 cos(phi) gamma_dot, the consistent tangent (sec. 8.2) and the
tangent of isotropic tensor functions (appendix A, box A.6, eqs. A.46-A.48); Perzyna viscoplasticity
after Simo & Hughes (1998), Computational Inelasticity, sec. 2.7, and de Souza Neto et al.
sec. 11.5; closed-form strengths after Chen & Han (1988), Plasticity for Structural Engineers,
ch. 2 (tension positive: uniaxial compressive strength 2 c cos(phi) / (1 - sin(phi)), tensile
strength 2 c cos(phi) / (1 + sin(phi)), triaxial compression |sigma_3| = p0 (1 + sin phi) /
(1 - sin phi) + 2 c cos(phi) / (1 - sin(phi)), plane strain t + sigma_m sin(phi) = c cos(phi)).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from plasticity_checks import point_checks, rotation, strain_tensor, strain_vector, stress_tensor, stress_vector
from plasticity_checks import mixed_control as _mixed_control

from masonrydam.errors import STATUS_NAN, STATUS_OK, NumericalError
from masonrydam.materials.mohr_coulomb_solid import (
    N_MC_PARAMS,
    N_MC_STATE,
    P_COHESION,
    P_COS_PHI,
    P_SIN_PHI,
    P_SIN_PSI,
    S_CODE,
    S_EQ_PLASTIC_STRAIN,
    S_PLASTIC_STRAIN,
    S_STRESS,
    mohr_coulomb_solid_evaluate,
    mohr_coulomb_solid_initial_state,
    mohr_coulomb_solid_params,
    mohr_coulomb_solid_update,
    return_stiffnesses,
)
from masonrydam.materials.plasticity import (
    CODE_APEX, CODE_EDGE_LEFT, CODE_EDGE_RIGHT, CODE_ELASTIC, CODE_PLASTIC, STATUS_BAD_MATERIAL, WORK_SIZE,
)
from masonrydam.materials.principal_return import (
    W_PR_JAC, W_PR_VEC, principal_stresses, stress_voigt_to_tensor, strain_voigt_to_tensor, sym_eig3,
    tensor_to_strain_voigt, tensor_to_stress_voigt,
)

E = 20.0e9  # Pa
NU = 0.2
C = 1.0e6  # Pa
PHI = 30.0  # deg
G = E / (2 * (1 + NU))
K = E / (3 * (1 - 2 * NU))
EPS_C = C / G  # a strain of the order of the elastic limit in shear
SIN, COS = math.sin(math.radians(PHI)), math.cos(math.radians(PHI))
F_C = 2 * C * COS / (1 - SIN)  # uniaxial compressive strength (Chen & Han 1988)
F_T = 2 * C * COS / (1 + SIN)  # uniaxial tensile strength

PS = [0, 1, 3]  # plane-strain components in the 3D vector


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


def params(psi=PHI, H=0.0, c_res=0.0, eta=0.0, c=C, phi=PHI):
    return mohr_coulomb_solid_params(E, NU, c, phi, psi, cohesion_hardening=H, residual_cohesion=c_res, viscosity=eta)


evaluate, fd_tangent = point_checks(mohr_coulomb_solid_evaluate)


def mixed_control(prm, drive, path, free, target, state=None, ns=6, tol=1e-10):
    """:func:`plasticity_checks.mixed_control` for this law (stress tolerance relative to C). Tying lateral
    strains, e.g. ``free = [(1, 2)]`` for eyy = ezz, keeps an axisymmetric test's Jacobian regular: on a
    Mohr-Coulomb edge sigma_1 = sigma_2 (or sigma_2 = sigma_3) holds whatever the strain, so
    d(syy - szz)/d(eyy - ezz) = 0."""
    return _mixed_control(evaluate, mohr_coulomb_solid_initial_state, prm, drive, path, free, target, C, state, ns, tol)


def planes(sig6, c, sphi=SIN, cphi=COS):
    """(Phi_13, Phi_12, Phi_23) of de Souza Neto et al. sec. 8.2 at the principal stresses of sig6."""
    s1, s2, s3 = principal_stresses(sig6)

    def phi(a, b):
        return a - b + (a + b) * sphi - 2 * c * cphi

    return phi(s1, s3), phi(s1, s2), phi(s2, s3)


def principal_frame(strain6):
    """Eigenvectors (columns, descending eigenvalues) of the strain tensor: the principal frame of
    the elastic trial from a virgin state."""
    w, V = np.linalg.eigh(strain_tensor(strain6))
    return V[:, ::-1]


# ---------------------------------------------------------------------------------------------
# principal_return helpers
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("eigs", [(3.0, -1.0, 0.5), (2.0, 2.0, -1.0), (1.0, 1.0, 1.0), (5.0, 5.0 + 1e-12, -4.0),
                                  (0.0, 0.0, 0.0), (1e9, -1e-3, 2e-3)])
def test_sym_eig3_reconstructs_matrix(eigs):
    """Jacobi eigen-decomposition: A = V diag(l) V^T with V orthogonal to 1e-15, distinct and
    repeated eigenvalues alike, and the eigenvalues of numpy.linalg.eigvalsh."""
    R = rotation(int(10 * abs(eigs[0])) % 7)
    A = R @ np.diag(eigs) @ R.T
    A = 0.5 * (A + A.T)
    work = np.zeros(WORK_SIZE)
    work[W_PR_JAC:W_PR_JAC + 9] = A.ravel()
    sym_eig3(work, W_PR_JAC, W_PR_VEC)
    lam = work[W_PR_JAC:W_PR_JAC + 9].reshape(3, 3).diagonal().copy()
    V = work[W_PR_VEC:W_PR_VEC + 9].reshape(3, 3)
    scale = max(np.max(np.abs(eigs)), 1.0)
    assert np.allclose(V.T @ V, np.eye(3), rtol=0, atol=1e-15 * 10)
    assert np.allclose(V @ np.diag(lam) @ V.T, A, rtol=0, atol=1e-14 * scale)
    assert np.allclose(np.sort(lam), np.linalg.eigvalsh(A), rtol=0, atol=1e-14 * scale)


def test_voigt_tensor_round_trips():
    v = np.array([1.0, -2.0, 3.0, 0.4, -0.5, 0.6])
    T = np.zeros((3, 3))
    stress_voigt_to_tensor(v, T)
    assert np.array_equal(T, stress_tensor(v))
    back = np.zeros(6)
    tensor_to_stress_voigt(T, back)
    assert np.array_equal(back, v)
    strain_voigt_to_tensor(v, T)
    assert np.array_equal(T, strain_tensor(v))
    tensor_to_strain_voigt(T, back)
    assert np.allclose(back, v, rtol=1e-15, atol=0)


# ---------------------------------------------------------------------------------------------
# closed-form strengths
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("psi", [0.0, 10.0, PHI])
def test_uniaxial_strengths(psi):
    """Uniaxial stress (syy = szz = 0 by a Newton on the tied lateral strains eyy = ezz with the
    consistent tangent):
    compression yields at -2 c cos(phi) / (1 - sin(phi)) on the left edge (sigma_1 = sigma_2 = 0),
    tension at 2 c cos(phi) / (1 + sin(phi)) on the right edge (sigma_2 = sigma_3 = 0), relative
    1e-10; both principal tangents have repeated trial eigenvalues (exact lateral symmetry)."""
    prm = params(psi)
    for sign, strength, code in ((-1.0, -F_C, CODE_EDGE_LEFT), (1.0, F_T, CODE_EDGE_RIGHT)):
        e_y = abs(strength) / E
        path = [[sign * f * e_y] for f in np.linspace(0.25, 6.0, 24)]
        s, state, iters = mixed_control(prm, [0], path, [(1, 2)], np.zeros(1))
        assert s[-1, 0] == pytest.approx(strength, rel=1e-10)
        assert s[1, 0] == pytest.approx(sign * 0.5 * E * e_y, rel=1e-10)  # elastic before yield
        assert state[0, S_CODE] == code
        assert iters <= 6
        ep = state[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 3]
        # plastic dilatancy of the edges: d eps_v / |d eps_1| = 2 sin(psi) / (1 + sin(psi)) (tension), /(1 - sin psi)
        # (compression), with eps_v the trace
        spsi = math.sin(math.radians(psi))
        ratio = 2 * spsi / (1 + spsi) if sign > 0 else 2 * spsi / (1 - spsi)
        assert ep.sum() == pytest.approx(ratio * abs(ep[0]), rel=1e-8, abs=1e-12 * abs(ep[0]))


@pytest.mark.parametrize("psi", [0.0, PHI])
@pytest.mark.parametrize("kind", ["compression", "extension"])
def test_triaxial_strengths(kind, psi):
    """Triaxial tests at confinement p0 (lateral stresses held at -p0 by Newton): compression
    (sigma_1 = sigma_2 = -p0 > sigma_3, left edge) fails at sigma_3 = -(p0 (1 + sin phi) +
    2 c cos phi) / (1 - sin phi) (Chen & Han 1988; compression-positive sigma_1 = sigma_3 (1 + sin
    phi) / (1 - sin phi) + 2 c cos(phi) / (1 - sin(phi))), extension (sigma_1 > sigma_2 = sigma_3 =
    -p0, right edge) at sigma_1 = (2 c cos(phi) - p0 (1 - sin(phi))) / (1 + sin(phi)); relative 1e-10."""
    p0 = 2.0 * C
    prm = params(psi)
    e0 = -p0 / (3 * K)
    sign = -1.0 if kind == "compression" else 1.0
    path = [[e0]] + [[e0 + sign * f * EPS_C] for f in np.linspace(0.2, 12.0, 30)]
    s, state, _ = mixed_control(prm, [0], path, [(1, 2)], np.array([-p0]))
    assert s[0] == pytest.approx([-p0, -p0, -p0, 0, 0, 0], rel=1e-12, abs=1e-6)
    if kind == "compression":
        expected = -(p0 * (1 + SIN) + 2 * C * COS) / (1 - SIN)
        assert state[0, S_CODE] == CODE_EDGE_LEFT
    else:
        expected = (2 * C * COS - p0 * (1 - SIN)) / (1 + SIN)
        assert state[0, S_CODE] == CODE_EDGE_RIGHT
    assert s[-1, 0] == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("ns", [3, 6])
def test_simple_shear_non_dilatant(ns):
    """Simple shear (only gxy, all normal strains zero) with psi = 0: the plastic flow
    N = (1, 0, -1) in the principal frame (+-45 degrees in the xy plane) is isochoric with no zz part,
    so the normal stresses stay zero, sigma_2 = szz = 0 is intermediate (main plane) and the shear
    strength is tau = c cos(phi) (Mohr-Coulomb with sigma_m = 0)."""
    prm = params(0.0)
    ixy = 2 if ns == 3 else 3
    state = mohr_coulomb_solid_initial_state(1)
    for g in np.linspace(0.1, 5.0, 25) * EPS_C:
        eps = np.zeros(ns)
        eps[ixy] = g
        s, _, state = evaluate(eps, prm, state)
        assert s[ixy] == pytest.approx(min(G * g, C * COS), rel=1e-12)
        assert np.max(np.abs(state[0, S_STRESS:S_STRESS + 3])) <= 1e-9 * C
    assert state[0, S_CODE] == CODE_PLASTIC


@pytest.mark.parametrize("psi", [0.0, 10.0, PHI])
def test_plane_strain_pure_shear_with_free_normal_strains(psi):
    """Plane strain (ns = 3), gxy driven, sxx = syy = 0 held by a Newton on exx, eyy: the in-plane Mohr
    circle has centre sigma_m = 0 and radius tau, and szz = nu (sxx + syy) = 0 stays the intermediate
    principal stress (the main-plane flow N = (1 + sin psi, 0, -(1 - sin psi)) has no part along z, so
    eps_e_zz = 0), hence Phi_13 = 2 tau - 2 c cos(phi) = 0: tau = c cos(phi) for every psi (Chen & Han
    1988: t + sigma_m sin(phi) = c cos(phi)). The dilatancy goes into the free normal strains: the
    plastic volume change per engineering plastic shear is d eps_v / d gamma_p = sin(psi) (principal
    plastic strains dgamma (1 + sin psi, 0, -(1 - sin psi)) at +-45 degrees)."""
    prm = params(psi)
    path = [[g] for g in np.linspace(0.2, 6.0, 30) * EPS_C]
    s, state, iters = mixed_control(prm, [2], path, [0, 1], np.zeros(2), ns=3)
    assert s[-1, 2] == pytest.approx(C * COS, rel=1e-10)
    assert state[0, S_CODE] == CODE_PLASTIC
    assert iters <= 4
    ep = state[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6]
    assert ep[2] == pytest.approx(0.0, abs=1e-13 * abs(ep[3]))
    assert ep[:3].sum() == pytest.approx(math.sin(math.radians(psi)) * ep[3], rel=1e-9, abs=1e-13 * abs(ep[3]))


@pytest.mark.parametrize("psi", [0.0, 10.0, PHI])
def test_plane_strain_collapse(psi):
    """Plane strain (ns = 3), syy = -p0 held, exx compressed far into the plastic range: the in-plane
    stresses satisfy t + sigma_m sin(phi) = c cos(phi) (Chen & Han 1988; de Souza Neto et al.
    sec. 8.2) with szz the intermediate principal stress (main plane), for any dilatancy: the main
    plane flow has no component along the intermediate direction z, so eps_p_zz = 0 and the limit is
    that of the plane Mohr circle."""
    p0 = 1.5 * C
    prm = params(psi)
    e0 = -p0 / (2 * (K + G / 3))  # exx = eyy = e0: sxx = syy = -p0 in plane strain
    path = [[e0]] + [[e0 - f * EPS_C] for f in np.linspace(0.1, 30.0, 40)]
    s, state, _ = mixed_control(prm, [0], path, [1], np.array([-p0]), ns=3)
    sxx, syy, sxy = s[-1]
    t = math.sqrt((0.5 * (sxx - syy)) ** 2 + sxy**2)
    sm = 0.5 * (sxx + syy)
    assert abs(t + sm * SIN - C * COS) <= 1e-9 * C
    assert state[0, S_CODE] == CODE_PLASTIC
    szz = state[0, S_STRESS + 2]
    assert min(sxx, syy) < szz < max(sxx, syy)
    assert szz == pytest.approx(NU * (sxx + syy), rel=1e-9)  # eps_p_zz = 0: elastic relation holds
    assert state[0, S_PLASTIC_STRAIN + 2] == pytest.approx(0.0, abs=1e-12 * np.max(np.abs(state[0, 6:12])))


# ---------------------------------------------------------------------------------------------
# the four returns
# ---------------------------------------------------------------------------------------------

RETURNS = {
    # name: (strain direction (3D, from a virgin state, times EPS_C), expected code)
    "main": ([-1.0, -0.2, 0.6, 0.3, 0.1, 0.0], CODE_PLASTIC),
    "right_edge": ([2.0, -0.9, -1.1, 0.1, 0.0, 0.0], CODE_EDGE_RIGHT),
    "left_edge": ([1.1, 0.9, -2.0, 0.0, 0.1, 0.0], CODE_EDGE_LEFT),
    "apex": ([4.0, 3.5, 3.8, 0.2, -0.1, 0.1], CODE_APEX),
}


@pytest.mark.parametrize("psi", [0.0, 10.0, PHI])
@pytest.mark.parametrize("name", list(RETURNS))
def test_returns_land_on_their_planes(name, psi):
    """Each return region (de Souza Neto et al. box 8.5) from a virgin state, rotated into a general
    frame: the code, the stress on the active planes (1e-9 c) and the flow rule. Main plane:
    Phi_13 = 0, sigma_1 > sigma_2 > sigma_3; right edge: Phi_13 = Phi_12 = 0 (sigma_2 = sigma_3); left
    edge: Phi_13 = Phi_23 = 0 (sigma_1 = sigma_2); apex: sigma = c cot(phi) 1. In the principal frame
    of the trial the plastic strain is d_13 N_13 + d_b N_b with d >= 0 (Koiter) and eps_bar =
    2 cos(phi) (d_13 + d_b); at the apex eps_bar = cos(phi) / sin(psi) d eps_v (psi > 0)."""
    direction, code = RETURNS[name]
    prm = params(psi)
    spsi = math.sin(math.radians(psi))
    R = rotation(2)
    eps = strain_vector(R @ strain_tensor(np.array(direction) * 3 * EPS_C) @ R.T)
    s, _, t = evaluate(eps, prm, mohr_coulomb_solid_initial_state(1))
    assert t[0, S_CODE] == code
    p13, p12, p23 = planes(s, C)
    s1, s2, s3 = principal_stresses(s)
    tol = 1e-9 * C
    if code == CODE_APEX:
        assert np.allclose(s, [C * COS / SIN] * 3 + [0.0] * 3, rtol=0, atol=tol)
    else:
        assert abs(p13) <= tol
        if code == CODE_PLASTIC:
            assert s1 - s2 > 1e-3 * C and s2 - s3 > 1e-3 * C
        elif code == CODE_EDGE_RIGHT:
            assert abs(p12) <= tol and abs(s2 - s3) <= tol
        else:
            assert abs(p23) <= tol and abs(s1 - s2) <= tol
    # flow rule in the principal frame of the trial (the eigenvectors of eps)
    V = principal_frame(eps)
    ep = V.T @ strain_tensor(t[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6]) @ V
    assert np.max(np.abs(ep - np.diag(np.diag(ep)))) <= 1e-10 * np.max(np.abs(ep))
    d = np.diag(ep)
    eb = t[0, S_EQ_PLASTIC_STRAIN]
    if code == CODE_APEX:
        if psi > 0:
            assert eb == pytest.approx(COS / spsi * d.sum(), rel=1e-10)
        return

    def N(i, j):
        v = np.zeros(3)
        v[i], v[j] = 1 + spsi, -(1 - spsi)
        return v

    cols = [N(0, 2)] + ([] if code == CODE_PLASTIC else [N(0, 1) if code == CODE_EDGE_RIGHT else N(1, 2)])
    A = np.array(cols).T
    mult, *_ = np.linalg.lstsq(A, d, rcond=None)
    assert np.allclose(A @ mult, d, rtol=0, atol=1e-10 * np.max(np.abs(d)))
    assert np.all(mult > 0)
    assert eb == pytest.approx(2 * COS * mult.sum(), rel=1e-10)


def test_plane_strain_equals_3d_in_every_region():
    """A plane-strain point equals a 3D point with ezz = gyz = gzx = 0 (stress, tangent block, state)
    in each region from a virgin state and along a history through them."""
    prm = params(10.0, H=0.01 * G)

    def both(eps, st2, st3):
        s2, D2, st2 = evaluate(eps, prm, st2)
        s3, D3, st3 = evaluate(np.array([eps[0], eps[1], 0, eps[2], 0, 0]), prm, st3)
        assert np.allclose(s2, s3[PS], rtol=0, atol=1e-9 * C)
        assert np.allclose(D2, D3[np.ix_(PS, PS)], rtol=0, atol=1e-9 * E)
        assert np.allclose(st2, st3, rtol=0, atol=1e-12 * C)
        return st2, st3

    codes = set()
    for e2 in (M2, R2, L2, A2):
        st2, _ = both(np.array(e2) * EPS_C, mohr_coulomb_solid_initial_state(1), mohr_coulomb_solid_initial_state(1))
        codes.add(int(st2[0, S_CODE]))
    assert codes == {CODE_PLASTIC, CODE_EDGE_RIGHT, CODE_EDGE_LEFT, CODE_APEX}
    st2, st3 = mohr_coulomb_solid_initial_state(1), mohr_coulomb_solid_initial_state(1)
    for e2 in (M2, R2, L2, A2, [-6.0, -1.0, 3.0]):
        st2, st3 = both(np.array(e2) * EPS_C, st2, st3)


def test_elastic_step_returns_elastic_matrix():
    from masonrydam.materials.elastic import elasticity_matrix

    prm = params(10.0)
    _, D3, t = evaluate(np.array([1e-5, 2e-6, -3e-6, 1e-6, 0, 0]) * 0.1, prm, mohr_coulomb_solid_initial_state(1))
    assert t[0, S_CODE] == CODE_ELASTIC
    assert np.allclose(D3, elasticity_matrix(E, NU, "3d"), rtol=1e-13, atol=0)
    _, D2, _ = evaluate(np.array([1e-5, 2e-6, 1e-6]) * 0.1, prm, mohr_coulomb_solid_initial_state(1))
    assert np.allclose(D2, elasticity_matrix(E, NU, "plane_strain"), rtol=1e-13, atol=0)
    # a large hydrostatic compression is elastic (the pyramid is open towards compression)
    s, _, t = evaluate(np.array([-1.0, -1.0, -1.0, 0, 0, 0]) * 1e-2, prm, mohr_coulomb_solid_initial_state(1))
    assert t[0, S_CODE] == CODE_ELASTIC


# ---------------------------------------------------------------------------------------------
# consistent tangent
# ---------------------------------------------------------------------------------------------

M3, M2 = [-3.0, -0.6, 1.8, 0.9, 0.3, 0.0], [-3.0, 0.9, 6.0]  # main plane
R3, R2 = [3.0, -1.35, -1.65, 0.15, 0.0, 0.0], [1.0, 0.2, 0.3]  # right edge
L3, L2 = [3.3, 2.7, -6.0, 0.0, 0.3, 0.0], [-9.0, 1.5, 12.0]  # left edge
A3, A2 = [12.0, 10.5, 11.4, 0.6, -0.3, 0.3], [12.0, 15.0, 0.3]  # apex

TANGENT_CASES = {
    # name: (psi, H / G, c_res / C, eta / G (s), dt, 3D strain, plane-strain strain (times EPS_C), code)
    "main_assoc": (PHI, 0.0, 0.0, 0.0, 0.0, M3, M2, CODE_PLASTIC),
    "main_nonassoc_hard": (10.0, 0.02, 0.0, 0.0, 0.0, M3, M2, CODE_PLASTIC),
    "main_psi0_soft": (0.0, -0.01, 0.2, 0.0, 0.0, M3, M2, CODE_PLASTIC),
    "main_residual": (10.0, -0.05, 0.8, 0.0, 0.0, [-6.0, -1.2, 3.6, 1.8, 0.6, 0.0], [-6.0, 6.0, 0.0], CODE_PLASTIC),
    "main_perzyna": (10.0, 0.02, 0.0, 0.3, 1.0, M3, M2, CODE_PLASTIC),
    "right_assoc": (PHI, 0.0, 0.0, 0.0, 0.0, R3, R2, CODE_EDGE_RIGHT),
    "right_nonassoc_soft": (10.0, -0.01, 0.3, 0.0, 0.0, R3, R2, CODE_EDGE_RIGHT),
    "right_perzyna": (0.0, 0.02, 0.0, 0.3, 1.0, R3, R2, CODE_EDGE_RIGHT),
    "left_assoc_hard": (PHI, 0.03, 0.0, 0.0, 0.0, L3, L2, CODE_EDGE_LEFT),
    "left_residual": (10.0, -0.05, 0.8, 0.0, 0.0, [6.6, 5.4, -12.0, 0.0, 0.6, 0.0], [-18.0, 3.0, 24.0],
                      CODE_EDGE_LEFT),
    "left_perzyna": (10.0, 0.0, 0.0, 0.3, 1.0, L3, L2, CODE_EDGE_LEFT),
    "apex_assoc_hard": (PHI, 0.05, 0.0, 0.0, 0.0, A3, A2, CODE_APEX),
    "apex_nonassoc_soft": (10.0, -0.002, 0.5, 0.0, 0.0, A3, A2, CODE_APEX),
    "apex_psi0_hard": (0.0, 0.05, 0.0, 0.0, 0.0, A3, A2, CODE_APEX),
    "apex_psi0_perzyna": (0.0, 0.01, 0.0, 0.2, 1.0, A3, A2, CODE_APEX),
    "apex_perzyna": (10.0, 0.0, 0.0, 0.2, 1.0, A3, A2, CODE_APEX),
}


@pytest.mark.parametrize("ns", [3, 6])
@pytest.mark.parametrize("case", list(TANGENT_CASES))
def test_consistent_tangent_equals_finite_difference(case, ns):
    """Consistent tangent in every return region (main plane, both edges, apex; associated and not;
    hardening, softening, residual, Perzyna), 3D and plane strain, from a committed plastic state,
    vs a central difference of the stress update (relative 1e-6 of max |D|; measured <= 1e-8).
    Associated returns give a symmetric tangent, non-associated ones do not."""
    psi, H, c_res, eta, dt, e3, e2, code = TANGENT_CASES[case]
    prm = params(psi, H * G, c_res * C, eta * G)
    first = (np.array([-1.0, -0.5, 0.0, 3.0, 0, 0]) if ns == 6 else np.array([-1.0, -0.5, 3.0])) * EPS_C
    _, _, state = evaluate(first, prm, mohr_coulomb_solid_initial_state(1), dt)
    assert state[0, S_EQ_PLASTIC_STRAIN] > 0
    eps = np.array(e3 if ns == 6 else e2) * EPS_C
    _, D, trial = evaluate(eps, prm, state, dt)
    assert trial[0, S_CODE] == code
    if c_res == 0.8:  # past the residual kink
        assert C + H * G * trial[0, S_EQ_PLASTIC_STRAIN] < c_res * C
    elif H < 0:
        assert C + H * G * trial[0, S_EQ_PLASTIC_STRAIN] > c_res * C
    Dfd = fd_tangent(eps, prm, state, dt)
    scale = np.max(np.abs(D))
    assert np.max(np.abs(D - Dfd)) <= 1e-6 * scale
    asym = np.max(np.abs(D - D.T)) / scale
    if psi == PHI:
        assert asym <= 1e-10
    elif code != CODE_APEX:
        assert asym > 1e-4


@pytest.mark.parametrize("direction, code", [([3.0, -1.0, -1.0, 0, 0, 0], CODE_EDGE_RIGHT),
                                             ([1.0, 1.0, -2.5, 0, 0, 0], CODE_EDGE_LEFT),
                                             ([-1.0, 0.2, 0.2, 0, 0, 0], CODE_EDGE_LEFT)])
def test_tangent_with_repeated_trial_eigenvalues(direction, code):
    """A trial with two equal principal stresses (eqs. A.47-A.48 of de Souza Neto et al.: the limit
    form of the spin term): the tangent still equals the central difference, the shear in the plane of
    the repeated pair included (relative 1e-6)."""
    prm = params(10.0, 0.01 * G)
    eps = np.array(direction) * 3 * EPS_C
    st = mohr_coulomb_solid_initial_state(1)
    _, D, t = evaluate(eps, prm, st)
    assert t[0, S_CODE] == code
    assert np.max(np.abs(D - fd_tangent(eps, prm, st))) <= 1e-6 * np.max(np.abs(D))


# ---------------------------------------------------------------------------------------------
# isotropy, softening
# ---------------------------------------------------------------------------------------------


def test_rotating_the_strain_rotates_the_stress():
    """Isotropy: sigma(R eps R^T) = R sigma(eps) R^T (and the same for the plastic strain), in each
    region from a virgin state and over a non-proportional history (relative 1e-10)."""
    prm = params(10.0, H=0.01 * G)
    R = rotation(5)

    def both(eps, sa, sb):
        s1, _, sa = evaluate(eps, prm, sa)
        s2, _, sb = evaluate(strain_vector(R @ strain_tensor(eps) @ R.T), prm, sb)
        assert np.allclose(stress_vector(R @ stress_tensor(s1) @ R.T), s2, rtol=0, atol=1e-10 * C)
        ep_a = strain_tensor(sa[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6])
        ep_b = strain_tensor(sb[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6])
        assert np.allclose(R @ ep_a @ R.T, ep_b, rtol=0, atol=1e-10 * max(np.max(np.abs(ep_a)), EPS_C))
        assert sa[0, S_EQ_PLASTIC_STRAIN] == pytest.approx(sb[0, S_EQ_PLASTIC_STRAIN], rel=1e-10)
        assert sa[0, S_CODE] == sb[0, S_CODE]
        return sa, sb

    codes = set()
    for e3 in (M3, R3, L3, A3):
        sa, _ = both(np.array(e3) * EPS_C, mohr_coulomb_solid_initial_state(1), mohr_coulomb_solid_initial_state(1))
        codes.add(int(sa[0, S_CODE]))
    assert codes == {CODE_PLASTIC, CODE_EDGE_RIGHT, CODE_EDGE_LEFT, CODE_APEX}
    sa, sb = mohr_coulomb_solid_initial_state(1), mohr_coulomb_solid_initial_state(1)
    for e3 in (M3, [-2, 1, 0.1, 4, 1, 1], R3, L3, A3, [-3, -2, 1, 0, 2, 3]):
        sa, sb = both(np.array(e3, dtype=float) * EPS_C, sa, sb)


def test_softening_in_simple_shear_follows_closed_form():
    """Non-dilatant simple shear (main plane, a = 4G) with linear cohesion softening down to a
    residual: the engineering plastic shear is gamma_p = 2 dgamma, eps_bar = 2 cos(phi) dgamma =
    cos(phi) gamma_p, tau = G (gamma - gamma_p) = cos(phi) c(eps_bar), so
    tau = cos(phi) (c0 + H cos(phi) gamma) / (1 + cos^2(phi) H / G) until c reaches c_r, then
    tau = cos(phi) c_r."""
    H, c_r = -0.01 * G, 0.4 * C
    prm = params(0.0, H, c_r)
    st = mohr_coulomb_solid_initial_state(1)
    seen_soft = seen_res = False
    for g in np.linspace(0.1, 150.0, 80) * EPS_C:
        s, _, st = evaluate(np.array([0, 0, 0, g, 0, 0]), prm, st)
        if G * g <= COS * C:
            expected = G * g
        else:
            expected = max(COS * (C + H * COS * g) / (1 + COS * COS * H / G), COS * c_r)
            seen_soft |= expected > COS * c_r
            seen_res |= expected == COS * c_r
        assert s[3] == pytest.approx(expected, rel=1e-11)
    assert seen_soft and seen_res


def test_apex_closed_form_with_hardening():
    """Hydrostatic tension beyond the apex (de Souza Neto et al. sec. 8.2.2, apex return):
    d eps_v = (p_tr - c cot(phi)) / (K + cos^2(phi) H / (sin(phi) sin(psi))), p = p_tr - K d eps_v,
    eps_bar = cos(phi) / sin(psi) d eps_v; with psi = 0 (tension cut-off of the module docstring,
    hydrostatic trial: g0 = 0) sin(phi) replaces sin(psi). The plastic strain is hydrostatic."""
    H = 0.05 * G
    for psi in (PHI, 10.0, 0.0):
        prm = params(psi, H)
        s_a = math.sin(math.radians(psi)) if psi > 0 else SIN
        ev = 3 * 3 * C * COS / SIN / K
        eps = np.array([ev / 3] * 3 + [0.0] * 3)
        s, _, t = evaluate(eps, prm, mohr_coulomb_solid_initial_state(1))
        assert t[0, S_CODE] == CODE_APEX
        p_tr = K * ev
        dev = (p_tr - C * COS / SIN) / (K + COS**2 * H / (SIN * s_a))
        p = p_tr - K * dev
        assert np.allclose(s, [p, p, p, 0, 0, 0], rtol=1e-12, atol=1e-9 * C)
        assert t[0, S_EQ_PLASTIC_STRAIN] == pytest.approx(COS / s_a * dev, rel=1e-10)
        ep = t[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6]
        assert np.allclose(ep, [dev / 3] * 3 + [0] * 3, rtol=1e-10, atol=1e-14)
        assert p * SIN == pytest.approx(COS * (C + H * t[0, S_EQ_PLASTIC_STRAIN]), rel=1e-10)


# ---------------------------------------------------------------------------------------------
# Perzyna
# ---------------------------------------------------------------------------------------------


def _overstress(state, c0, H):
    return planes(state[0, S_STRESS:S_STRESS + 6], c0 + H * state[0, S_EQ_PLASTIC_STRAIN])[0]


@pytest.mark.parametrize("region", ["main", "right_edge"])
def test_perzyna_relaxation_at_constant_strain(region):
    """At constant strain on the main plane d Phi / dt = -(a + 4 cos^2(phi) H) gamma_dot with
    gamma_dot = Phi / eta, a = 4G (1 + sin(phi) sin(psi) / 3) + 4K sin(phi) sin(psi) (de Souza Neto
    et al. box 8.4), so Phi = Phi0 exp(-(a + 4 cos^2 phi H) t / eta); on the right edge the same with
    a_edge = (a + b_right) / 2 (Phi_13 = Phi_12 all along). Backward Euler gives
    Phi_k = Phi_k0 / (1 + dt a_tot / eta)^(k - k0) exactly (relative 1e-9; k0 = 0 on the plane; on
    the edge k0 = 1, after a first long step of 20 tau that moves the stress onto sigma_2 = sigma_3) and the
    exponential to first order in dt (relative 3e-3 at dt = tau / 500). The long-time limit is the
    rate-independent return."""
    eta, H, psi = 2.0e8, 0.02 * G, 10.0
    prm = params(psi, H, eta=eta)
    a_m, a_r, _, _, _ = return_stiffnesses(K, G, SIN, math.sin(math.radians(psi)))
    spsi = math.sin(math.radians(psi))
    assert a_m == pytest.approx(4 * G * (1 + SIN * spsi / 3) + 4 * K * SIN * spsi, rel=1e-14)
    a_tot = (a_m if region == "main" else a_r) + 4 * COS**2 * H
    tau = eta / a_tot
    direction, code = RETURNS[region]
    eps = np.array(direction) * 3 * EPS_C
    _, _, st0 = evaluate(eps, prm, mohr_coulomb_solid_initial_state(1), dt=0.0)
    assert st0[0, S_CODE] == CODE_ELASTIC  # no time for viscous flow
    n = 1000
    dt = 2 * tau / n
    # the edge: a first long step (20 tau) brings the stress onto sigma_2 = sigma_3
    _, _, st = evaluate(eps, prm, st0, dt=dt if region == "main" else 20 * tau)
    assert st[0, S_CODE] == code
    k0 = 0 if region == "main" else 1
    f0 = _overstress(st0 if k0 == 0 else st, C, H)
    assert f0 > (0.5 if k0 == 0 else 0.01) * C
    for k in range(2, n + 1):
        _, _, st = evaluate(eps, prm, st, dt=dt)
        assert st[0, S_CODE] == code
        assert _overstress(st, C, H) == pytest.approx(f0 / (1 + dt / tau) ** (k - k0), rel=1e-9)
    assert _overstress(st, C, H) == pytest.approx(f0 * math.exp(-(n - 1) * dt / tau) if k0 else
                                                  f0 * math.exp(-n * dt / tau), rel=3e-3)
    s_ri, _, _ = evaluate(eps, params(psi, H), mohr_coulomb_solid_initial_state(1))
    for _ in range(40):
        s_v, _, st = evaluate(eps, prm, st, dt=2 * tau)
    assert np.allclose(s_v, s_ri, rtol=0, atol=1e-9 * C)


@pytest.mark.parametrize("region", list(RETURNS))
def test_perzyna_tends_to_rate_independent(region):
    """One viscous step tends to the rate-independent return as eta -> 0, linearly in eta / dt, in
    every region (same code), the tangent too."""
    direction, code = RETURNS[region]
    eps = np.array(direction) * 3 * EPS_C
    s_ri, D_ri, t_ri = evaluate(eps, params(10.0, 0.01 * G), mohr_coulomb_solid_initial_state(1))
    assert t_ri[0, S_CODE] == code
    diffs, ddiffs = [], []
    for eta in (1e6, 1e4, 1e2):
        s_v, D_v, t_v = evaluate(eps, params(10.0, 0.01 * G, eta=eta), mohr_coulomb_solid_initial_state(1), dt=1.0)
        assert t_v[0, S_CODE] == code
        diffs.append(np.max(np.abs(s_v - s_ri)))
        ddiffs.append(np.max(np.abs(D_v - D_ri)))
    assert diffs[-1] <= 1e-5 * C
    assert ddiffs[-1] <= 1e-5 * np.max(np.abs(D_ri))
    for d1, d2 in zip(diffs, diffs[1:]):
        assert d2 == pytest.approx(d1 / 100, rel=2e-2)
    for d1, d2 in zip(ddiffs, ddiffs[1:]):
        assert d2 == pytest.approx(d1 / 100, rel=5e-2)


def test_viscous_jump_with_zero_dt_is_elastic():
    prm = params(10.0, eta=1e8)
    eps = np.array(RETURNS["main"][0]) * 3 * EPS_C
    s, _, t = evaluate(eps, prm, mohr_coulomb_solid_initial_state(1), dt=0.0)
    assert t[0, S_CODE] == CODE_ELASTIC
    assert np.all(t[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6] == 0)


# ---------------------------------------------------------------------------------------------
# errors, kernel protocol
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(cohesion=-1.0), "cohesion"),
        (dict(cohesion=0.0, friction_angle_deg=0.0, dilation_angle_deg=0.0), "cohesion"),
        (dict(friction_angle_deg=90.0), "friction_angle"),
        (dict(friction_angle_deg=-1.0), "friction_angle"),
        (dict(friction_angle_deg="x"), "friction_angle"),
        (dict(dilation_angle_deg=PHI + 1.0), "dilation_angle"),
        (dict(dilation_angle_deg=-1.0), "dilation_angle"),
        (dict(viscosity=-1.0), "viscosity"),
        (dict(residual_cohesion=2 * C), "residual_cohesion"),
        (dict(residual_cohesion=-1.0), "residual_cohesion"),
        (dict(cohesion_hardening=-10 * G), "cohesion_hardening"),  # plane / edge condition
        (dict(dilation_angle_deg=1.0, cohesion_hardening=-0.05 * G), "cohesion_hardening"),  # apex condition
        (dict(poisson_ratio=0.5), "poisson_ratio"),
        (dict(youngs_modulus=0.0), "youngs_modulus"),
        (dict(cohesion=float("nan")), "cohesion"),
    ],
)
def test_bad_parameters_raise_named_errors(kwargs, name):
    args = dict(youngs_modulus=E, poisson_ratio=NU, cohesion=C, friction_angle_deg=PHI, dilation_angle_deg=10.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        mohr_coulomb_solid_params(**args)


def test_softening_limits():
    """The apex condition 2 sin(phi) K + 2 cos^2(phi) H / s_a > 0 binds for a small dilation angle;
    without friction there is no apex and the left edge a_left + 4 H > 0 is the limit (3G for
    Tresca-like phi = psi = 0)."""
    H = -0.05 * G
    mohr_coulomb_solid_params(E, NU, C, PHI, PHI, cohesion_hardening=H)
    with pytest.raises(ValueError, match="apex"):
        mohr_coulomb_solid_params(E, NU, C, PHI, 1.0, cohesion_hardening=H)
    a_m, a_r, a_l, _, _ = return_stiffnesses(K, G, 0.0, 0.0)
    assert (a_m, a_r, a_l) == pytest.approx((4 * G, 3 * G, 3 * G), rel=1e-14)
    mohr_coulomb_solid_params(E, NU, C, 0.0, 0.0, cohesion_hardening=-0.74 * G)
    with pytest.raises(ValueError, match="cohesion_hardening"):
        mohr_coulomb_solid_params(E, NU, C, 0.0, 0.0, cohesion_hardening=-0.76 * G)


def test_kernel_status_nan_bad_material_and_table_errors():
    """The kernel never raises: NaN strain -> STATUS_NAN with info[0] the point (trial state =
    committed); an inadmissible column bypassing the wrapper -> STATUS_BAD_MATERIAL with the column in
    info[1]; the wrapper raises NumericalError / ValueError naming the parameter and the row."""
    prm = np.tile(params(10.0), (3, 1))
    assert prm.shape == (3, N_MC_PARAMS)
    committed = mohr_coulomb_solid_initial_state(3)
    strain = np.full((3, 6), 1e-6)
    strain[1, 4] = np.nan
    trial = np.full((3, N_MC_STATE), -7.0)
    stress = np.zeros((3, 6))
    tangent = np.ones((3, 6, 6))
    info = np.zeros(2, dtype=np.int64)
    status = mohr_coulomb_solid_update(strain, prm, committed, trial, stress, tangent, 0.0, True, info)
    assert status == STATUS_NAN and info[0] == 1
    assert np.array_equal(trial[1], committed[1]) and np.all(np.isnan(stress[1])) and np.all(tangent[1] == 0)
    with pytest.raises(NumericalError, match="point 1"):
        mohr_coulomb_solid_evaluate(strain, prm, committed)
    strain[1, 4] = 1e-6
    for col, value in ((P_SIN_PSI, 0.9), (P_COS_PHI, 0.5), (P_COHESION, -1.0), (P_SIN_PHI, 1.0)):
        bad = prm.copy()
        bad[2, col] = value
        info[:] = 0
        status = mohr_coulomb_solid_update(strain, bad, committed, trial, stress, tangent, 0.0, True, info)
        assert status == STATUS_BAD_MATERIAL and info[0] == 2 and info[1] == col
        with pytest.raises(ValueError, match="row 2"):
            mohr_coulomb_solid_evaluate(strain, bad, committed)
    status = mohr_coulomb_solid_update(strain, prm, committed, trial, stress, tangent, -1.0, True, info)
    assert status == STATUS_BAD_MATERIAL and info[1] == -1
    with pytest.raises(ValueError, match="dt"):
        mohr_coulomb_solid_evaluate(strain, prm, committed, dt=-1.0)
    status = mohr_coulomb_solid_update(strain, prm, committed, trial, stress, tangent, 0.0, True, info)
    assert status == STATUS_OK


def test_params_layout_and_batch_without_tangent():
    row = mohr_coulomb_solid_params(E, NU, C, PHI, 10.0)
    assert row.shape == (N_MC_PARAMS,)
    assert row[P_SIN_PHI] == pytest.approx(SIN, rel=1e-15) and row[P_COS_PHI] == pytest.approx(COS, rel=1e-15)
    assert row[P_SIN_PSI] == pytest.approx(math.sin(math.radians(10.0)), rel=1e-15)
    assert mohr_coulomb_solid_params(E, NU, C, PHI)[P_SIN_PSI] == row[P_SIN_PHI]  # associated by default
    strain = np.array([np.array(d) * 3 * EPS_C for d, _ in RETURNS.values()] + [[1e-7, 0, 0, 0, 0, 0]])
    st = mohr_coulomb_solid_initial_state(5)
    s1, D1, t1 = mohr_coulomb_solid_evaluate(strain, row, st)
    s2, D2, t2 = mohr_coulomb_solid_evaluate(strain, row, st, want_tangent=False)
    assert D2 is None and D1.shape == (5, 6, 6)
    assert np.array_equal(s1, s2) and np.array_equal(t1, t2)
    assert list(t1[:, S_CODE]) == [CODE_PLASTIC, CODE_EDGE_RIGHT, CODE_EDGE_LEFT, CODE_APEX, CODE_ELASTIC]
