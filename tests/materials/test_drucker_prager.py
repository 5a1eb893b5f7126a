"""Tests of the Drucker-Prager plasticity law (masonrydam.materials.drucker_prager).

Sources: de Souza Neto, Peric & Owen (2008), Computational Methods for Plasticity: the cone
matches of Mohr-Coulomb, the return to the cone and to the apex (box 8.8/8.9) and their
consistent tangents (sec. 8.3); Perzyna viscoplasticity after
Simo & Hughes (1998), Computational Inelasticity, sec. 2.7, and de Souza Neto et al. sec. 11.5;
Mohr-Coulomb limit states in plane strain and triaxial tests (tension positive:
t + sigma_m sin(phi) = c cos(phi) with t, sigma_m the radius and centre of the major Mohr circle).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from plasticity_checks import point_checks, strain_tensor, strain_vector, stress_tensor, stress_vector
from plasticity_checks import mixed_control as _mixed_control

from masonrydam.errors import STATUS_NAN, NumericalError
from masonrydam.materials.drucker_prager import (
    N_DP_PARAMS,
    N_DP_STATE,
    P_COHESION_COEF,
    P_DILATANCY_COEF,
    P_FRICTION_COEF,
    S_CODE,
    S_EQ_PLASTIC_STRAIN,
    S_PLASTIC_STRAIN,
    S_STRESS,
    drucker_prager_coefficients,
    drucker_prager_evaluate,
    drucker_prager_initial_state,
    drucker_prager_params,
    drucker_prager_update,
)
from masonrydam.materials.plasticity import CODE_APEX, CODE_ELASTIC, CODE_PLASTIC

E = 20.0e9  # Pa
NU = 0.2
C = 1.0e6  # Pa
PHI = 35.0  # deg
G = E / (2 * (1 + NU))
K = E / (3 * (1 - 2 * NU))
EPS_C = C / G  # a strain of the order of the elastic limit in shear
SIN, COS = math.sin(math.radians(PHI)), math.cos(math.radians(PHI))



# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


evaluate, fd_tangent = point_checks(drucker_prager_evaluate)


def mixed_control(params, drive, path, free, target, state=None, ns=6):
    """:func:`plasticity_checks.mixed_control` for this law (stress tolerance 1e-10 C)."""
    return _mixed_control(evaluate, drucker_prager_initial_state, params, drive, path, free, target, C, state, ns)


def sqrt_j2(s6):
    d = s6.copy()
    d[:3] -= d[:3].mean()
    return math.sqrt(0.5 * (np.sum(d[:3] ** 2) + 2 * np.sum(d[3:] ** 2)))


# ---------------------------------------------------------------------------------------------
# matching Mohr-Coulomb
# ---------------------------------------------------------------------------------------------


def test_coefficients_formulas():
    """Cone coefficients of de Souza Neto et al. sec. 8.3 (outer, inner, plane strain);
    the plane-strain match with psi = phi is their 3 tan(phi)/sqrt(9 + 12 tan^2 phi) form, and with
    psi = 0 it is (sin phi, cos phi)."""
    t = math.tan(math.radians(PHI))
    eta, xi, etab = drucker_prager_coefficients(PHI, None, "plane_strain")
    assert eta == pytest.approx(3 * t / math.sqrt(9 + 12 * t * t), rel=1e-14)
    assert xi == pytest.approx(3 / math.sqrt(9 + 12 * t * t), rel=1e-14)
    assert etab == pytest.approx(eta, rel=1e-14)
    eta, xi, etab = drucker_prager_coefficients(PHI, 0.0, "plane_strain")
    assert (eta, xi, etab) == pytest.approx((SIN, COS, 0.0), rel=1e-14)
    eta, xi, etab = drucker_prager_coefficients(PHI, 10.0, "outer")
    assert eta == pytest.approx(6 * SIN / (math.sqrt(3) * (3 - SIN)), rel=1e-14)
    assert xi == pytest.approx(6 * COS / (math.sqrt(3) * (3 - SIN)), rel=1e-14)
    s10 = math.sin(math.radians(10.0))
    assert etab == pytest.approx(6 * s10 / (math.sqrt(3) * (3 - s10)), rel=1e-14)
    eta, xi, _ = drucker_prager_coefficients(PHI, 0.0, "inner")
    assert eta == pytest.approx(6 * SIN / (math.sqrt(3) * (3 + SIN)), rel=1e-14)
    assert xi == pytest.approx(6 * COS / (math.sqrt(3) * (3 + SIN)), rel=1e-14)


@pytest.mark.parametrize("match", ["outer", "inner", "plane_strain"])
@pytest.mark.parametrize("psi", [0.0, 20.0])
def test_pure_shear_strength_at_zero_pressure(match, psi):
    """Pure shear at zero mean stress: the shear strength is tau = sqrt(J2) = xi c (Phi = 0 with
    p = 0) for each match, e.g. c cos(phi) for the non-dilatant plane-strain match. With dilation
    the mean stress is held at zero by a Newton on the volumetric strain (e = exx = eyy = ezz)."""
    params = drucker_prager_params(E, NU, C, PHI, psi, match=match)
    xi = params[P_COHESION_COEF]
    path = [[g] for g in np.linspace(0.2, 4.0, 20) * EPS_C]
    # drive gxy; free exx, eyy, ezz with sxx = syy = szz = 0 (so p = 0 and no normal deviator)
    s, state, iters = mixed_control(params, [3], path, [0, 1, 2], np.zeros(3))
    assert s[-1, 3] == pytest.approx(xi * C, rel=1e-10)
    assert state[0, S_CODE] == CODE_PLASTIC
    assert iters <= 4
    if match == "plane_strain" and psi == 0.0:
        assert s[-1, 3] == pytest.approx(C * COS, rel=1e-10)
    if psi == 0.0:  # no dilation: the plain shear strain path keeps p = 0 by itself
        st = drucker_prager_initial_state(1)
        for g in np.linspace(0.2, 4.0, 20) * EPS_C:
            s2, _, st = evaluate(np.array([0, 0, 0, g, 0, 0]), params, st)
        assert s2[3] == pytest.approx(xi * C, rel=1e-12)


@pytest.mark.parametrize("match, kind", [("outer", "compression"), ("inner", "extension")])
@pytest.mark.parametrize("psi", [0.0, PHI])
def test_triaxial_limits_match_mohr_coulomb_on_the_meridians(match, kind, psi):
    """The outer cone passes through the compressive meridian: the triaxial-compression strength
    sigma_a = -(2 c cos(phi) + p0 (1 + sin(phi))) / (1 - sin(phi)) equals Mohr-Coulomb's; the inner
    cone through the tensile meridian: triaxial extension sigma_a = (2 c cos(phi) -
    p0 (1 - sin(phi))) / (1 + sin(phi)). Lateral stresses held at -p0 by Newton (relative 1e-9)."""
    p0 = 2.0 * C
    params = drucker_prager_params(E, NU, C, PHI, psi, match=match)
    # hydrostatic -p0 first (elastic), then axial strain
    e0 = -p0 / (3 * K)
    sign = -1.0 if kind == "compression" else 1.0
    path = [[e0]] + [[e0 + sign * f * EPS_C] for f in np.linspace(0.2, 20.0, 40)]
    s, state, _ = mixed_control(params, [0], path, [1, 2], np.array([-p0, -p0]))
    assert s[0] == pytest.approx([-p0, -p0, -p0, 0, 0, 0], rel=1e-12)
    if kind == "compression":
        expected = -(2 * C * COS + p0 * (1 + SIN)) / (1 - SIN)
    else:
        expected = (2 * C * COS - p0 * (1 - SIN)) / (1 + SIN)
    assert s[-1, 0] == pytest.approx(expected, rel=1e-9)
    assert state[0, S_CODE] == CODE_PLASTIC


@pytest.mark.parametrize("psi", [0.0, 15.0, PHI])
def test_plane_strain_collapse_matches_mohr_coulomb(psi):
    """Plane strain (ns = 3): biaxial compression with syy = -p0 held by Newton and exx driven far
    into the plastic range. At the steady limit state the in-plane stresses satisfy Mohr-Coulomb,
    t + sigma_m sin(phi) = c cos(phi) (relative 1e-8 of c), for the plane-strain match with the
    same dilatancy (the eps_p_zz = 0 derivation of the module docstring; de Souza Neto et al.
    sec. 8.3 for psi = phi)."""
    p0 = 1.5 * C
    params = drucker_prager_params(E, NU, C, PHI, psi, match="plane_strain")
    e0 = -p0 / (2 * (K + G / 3))  # exx = eyy = e0 gives sxx = syy = -p0 in plane strain
    path = [[e0]] + [[e0 - f * EPS_C] for f in np.concatenate([np.linspace(0.1, 10, 30), np.linspace(12, 400, 40)])]
    s, state, _ = mixed_control(params, [0], path, [1], np.array([-p0]), ns=3)
    sxx, syy, sxy = s[-1]
    t = math.sqrt((0.5 * (sxx - syy)) ** 2 + sxy**2)
    sm = 0.5 * (sxx + syy)
    assert abs(t + sm * SIN - C * COS) <= 1e-8 * C
    assert abs(s[-1, 0] - s[-2, 0]) <= 1e-9 * C  # steady
    szz = state[0, S_STRESS + 2]
    assert min(sxx, syy) < szz < max(sxx, syy)  # szz is the intermediate principal stress (sxy = 0)


def test_plane_strain_elastic_szz_and_3d_equivalence():
    """szz = nu (sxx + syy) in the elastic range; a plane-strain point equals a 3D point with
    ezz = gyz = gzx = 0 on the cone and at the apex (stress, tangent block, state)."""
    params = drucker_prager_params(E, NU, C, PHI, 10.0, cohesion_hardening=0.02 * G)
    s, _, t = evaluate(np.array([-1.0, 0.3, 0.2]) * 1e-5, params, drucker_prager_initial_state(1))
    assert t[0, S_CODE] == CODE_ELASTIC
    assert t[0, S_STRESS + 2] == pytest.approx(NU * (s[0] + s[1]), rel=1e-12)
    idx = [0, 1, 3]
    st2, st3 = drucker_prager_initial_state(1), drucker_prager_initial_state(1)
    codes = set()
    for eps in (np.array([-1.0, 0.3, 2.0]), np.array([-3.0, 0.5, 4.0]), np.array([4.0, 5.0, 0.1]),
                np.array([-2.0, -1.0, 3.0])):
        eps = eps * EPS_C
        s2, D2, st2 = evaluate(eps, params, st2)
        s3, D3, st3 = evaluate(np.array([eps[0], eps[1], 0, eps[2], 0, 0]), params, st3)
        assert np.allclose(s2, s3[idx], rtol=0, atol=1e-9 * C)
        assert np.allclose(D2, D3[np.ix_(idx, idx)], rtol=0, atol=1e-9 * E)
        assert np.allclose(st2, st3, rtol=0, atol=1e-12 * C)
        codes.add(int(st2[0, S_CODE]))
    assert {CODE_PLASTIC, CODE_APEX} <= codes


# ---------------------------------------------------------------------------------------------
# apex
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("psi, H", [(PHI, 0.0), (PHI, 0.05 * K), (10.0, 0.05 * K), (0.0, 0.05 * K),
                                    (10.0, -0.002 * K)])
def test_hydrostatic_tension_returns_to_apex(psi, H):
    """Hydrostatic tension beyond the apex returns to s = 0 with the apex pressure (3D: hydrostatic
    strain; plane strain: exx = eyy, ezz = 0). Without hardening p = xi c / eta; with hardening
    (de Souza Neto et al. sec. 8.3) deps_v = (p_tr - beta c) / (K + alpha beta H),
    alpha = xi / eta_a, beta = xi / eta, p = p_tr - K deps_v, with eta_a = eta_bar (psi > 0), or
    eta for psi = 0 where c is the cohesion after the cone multiplier g0 = sqrt(J2_tr) / G (the
    tension cut-off of the module docstring). The plastic strain takes the whole trial deviator
    and the volumetric deps_v."""
    params = drucker_prager_params(E, NU, C, PHI, psi, cohesion_hardening=H, match="outer")
    eta, xi, etab = params[P_FRICTION_COEF], params[P_COHESION_COEF], params[P_DILATANCY_COEF]
    ea = etab if etab > 0 else eta
    p_apex = xi * C / eta
    ev = 3 * p_apex / K  # a trial pressure of three times the apex pressure
    for ns in (3, 6):
        if ns == 3:  # plane strain: hydrostatic strain is not possible, use exx = eyy, ezz = 0
            eps = np.array([ev / 2, ev / 2, 0.0])
        else:
            eps = np.array([ev / 3] * 3 + [0.0] * 3)
        s, D, t = evaluate(eps, params, drucker_prager_initial_state(1))
        assert t[0, S_CODE] == CODE_APEX
        p_tr = K * ev
        # the plane-strain trial has a deviator: with psi = 0 its cone multiplier g0 = sqrt(J2_tr)/G
        # enters the hardening (module docstring); g0 = 0 for psi > 0 and for a hydrostatic trial
        e3 = np.array([eps[0], eps[1], 0.0] if ns == 3 else eps[:3])
        g0 = (1 - etab / ea) * math.sqrt(0.5 * np.sum((2 * G * (e3 - e3.mean())) ** 2)) / G
        dev = (p_tr - xi / eta * (C + H * xi * g0)) / (K + xi * xi / (eta * ea) * H)
        p = p_tr - K * dev
        if H == 0.0:
            assert p == pytest.approx(p_apex, rel=1e-14)
        s6 = t[0, S_STRESS:S_STRESS + 6]
        assert np.allclose(s6, [p, p, p, 0, 0, 0], rtol=1e-12, atol=1e-9 * C)
        ep = t[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6]
        # the trial deviator (plane strain) goes into the plastic strain as well
        e_el = np.array([eps[0], eps[1], 0.0] if ns == 3 else eps[:3])
        assert np.allclose(ep[:3], e_el - p / (3 * K), rtol=1e-10, atol=1e-16)
        assert sum(ep[:3]) == pytest.approx(dev, rel=1e-10)
        # the yield condition holds at the apex with the updated cohesion
        c_new = C + H * t[0, S_EQ_PLASTIC_STRAIN]
        assert eta * p == pytest.approx(xi * c_new, rel=1e-10)


# ---------------------------------------------------------------------------------------------
# consistent tangent
# ---------------------------------------------------------------------------------------------

TANGENT_CASES = {
    # name: (psi, H, c_res, eta_v, dt, strain direction (3D), expected code)
    "cone_assoc": (PHI, 0.0, 0.0, 0.0, 0.0, [-3.0, 1.0, 0.5, 2.0, 1.0, -0.5], CODE_PLASTIC),
    "cone_nonassoc": (5.0, 0.03 * G, 0.0, 0.0, 0.0, [-3.0, 1.0, 0.5, 2.0, 1.0, -0.5], CODE_PLASTIC),
    "cone_psi0_soft": (0.0, -0.02 * G, 0.2 * C, 0.0, 0.0, [-3.0, 1.0, 0.5, 2.0, 1.0, -0.5], CODE_PLASTIC),
    "cone_residual": (10.0, -0.05 * G, 0.8 * C, 0.0, 0.0, [-3.0, 1.0, 0.5, 6.0, 1.0, -0.5], CODE_PLASTIC),
    "cone_perzyna": (10.0, 0.02 * G, 0.0, 0.3 * G, 1.0, [-3.0, 1.0, 0.5, 2.0, 1.0, -0.5], CODE_PLASTIC),
    "apex_assoc_hard": (PHI, 0.05 * G, 0.0, 0.0, 0.0, [3.0, 2.5, 2.8, 0.2, -0.1, 0.1], CODE_APEX),
    "apex_nonassoc_hard": (12.0, 0.05 * G, 0.0, 0.0, 0.0, [3.0, 2.5, 2.8, 0.2, -0.1, 0.1], CODE_APEX),
    "apex_psi0_hard": (0.0, 0.05 * G, 0.0, 0.0, 0.0, [3.0, 2.5, 2.8, 0.2, -0.1, 0.1], CODE_APEX),
    "apex_psi0_perzyna": (0.0, 0.01 * G, 0.0, 0.2 * G, 1.0, [3.0, 2.5, 2.8, 0.2, -0.1, 0.1], CODE_APEX),
    "apex_nonassoc_perzyna": (12.0, 0.0, 0.0, 0.2 * G, 1.0, [3.0, 2.5, 2.8, 0.2, -0.1, 0.1], CODE_APEX),
}


@pytest.mark.parametrize("ns", [3, 6])
@pytest.mark.parametrize("case", list(TANGENT_CASES))
def test_consistent_tangent_equals_finite_difference(case, ns):
    """Consistent tangent (cone and apex, associated and not, hardening, softening, residual,
    Perzyna) vs. a central difference of the stress update, from a committed plastic state
    (relative 1e-6 of max |D|; measured <= 1e-8). Non-associated cone tangents are not symmetric."""
    psi, H, c_res, eta_v, dt, direction, code = TANGENT_CASES[case]
    params = drucker_prager_params(E, NU, C, PHI, psi, cohesion_hardening=H, residual_cohesion=c_res,
                                   viscosity=eta_v, match="inner")
    d = np.array(direction)
    if ns == 3:
        d = d[[0, 1, 3]]
    # committed state: a first plastic (cone) step in shear with some compression
    first = (np.array([-1.0, -0.5, 0.0, 3.0, 0, 0]) if ns == 6 else np.array([-1.0, -0.5, 3.0])) * EPS_C
    _, _, state = evaluate(first, params, drucker_prager_initial_state(1), dt)
    assert state[0, S_CODE] == CODE_PLASTIC
    eps = first + d * EPS_C
    if code == CODE_APEX:
        eps = d * 3 * EPS_C
    _, D, trial = evaluate(eps, params, state, dt)
    assert trial[0, S_CODE] == code
    if case == "cone_residual":
        assert C + H * trial[0, S_EQ_PLASTIC_STRAIN] < c_res  # past the residual kink
    Dfd = fd_tangent(eps, params, state, dt)
    scale = np.max(np.abs(D))
    assert np.max(np.abs(D - Dfd)) <= 1e-6 * scale
    asym = np.max(np.abs(D - D.T)) / scale
    if code == CODE_PLASTIC and psi != PHI:
        assert asym > 1e-3
    if psi == PHI:
        assert asym <= 1e-12


# ---------------------------------------------------------------------------------------------
# isotropy, softening
# ---------------------------------------------------------------------------------------------


def test_rotating_the_strain_rotates_the_stress():
    """Isotropy: sigma(R eps R^T) = R sigma(eps) R^T over a non-proportional history through the
    cone and the apex (relative 1e-10)."""
    params = drucker_prager_params(E, NU, C, PHI, 10.0, cohesion_hardening=0.01 * G)
    rng = np.random.default_rng(5)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    R = q @ np.diag(np.sign(np.diag(r)))
    sa, sb = drucker_prager_initial_state(1), drucker_prager_initial_state(1)
    codes = set()
    for eps in ([-1, 0.5, 0.2, 3, -1, 0.5], [-2, 1, 0.1, 4, 1, 1], [4, 3, 3.5, 0.3, 0, 0.1], [-3, -2, 1, 0, 2, 3]):
        eps = np.array(eps, dtype=float) * EPS_C
        s1, _, sa = evaluate(eps, params, sa)
        s2, _, sb = evaluate(strain_vector(R @ strain_tensor(eps) @ R.T), params, sb)
        assert np.allclose(stress_vector(R @ stress_tensor(s1) @ R.T), s2, rtol=0, atol=1e-10 * C)
        assert sa[0, S_EQ_PLASTIC_STRAIN] == pytest.approx(sb[0, S_EQ_PLASTIC_STRAIN], rel=1e-10)
        codes.add(int(sa[0, S_CODE]))
    assert {CODE_PLASTIC, CODE_APEX} <= codes


def test_softening_in_shear_follows_closed_form():
    """Non-dilatant pure shear (p = 0) with linear cohesion softening down to a residual: on the
    cone tau = xi c(eps_bar), eps_bar = xi gamma_p, gamma_p = gamma - tau / G, so
    tau = xi (c0 + H xi gamma) / (1 + xi^2 H / G) until c reaches c_r, then tau = xi c_r."""
    H, c_r = -0.01 * G, 0.4 * C
    params = drucker_prager_params(E, NU, C, PHI, 0.0, cohesion_hardening=H, residual_cohesion=c_r)
    xi = params[P_COHESION_COEF]
    st = drucker_prager_initial_state(1)
    seen_soft = seen_res = False
    for g in np.linspace(0.1, 120.0, 80) * EPS_C:
        s, _, st = evaluate(np.array([0, 0, 0, g, 0, 0]), params, st)
        tau = s[3]
        if G * g <= xi * C:
            expected = G * g
        else:
            expected = max(xi * (C + H * xi * g) / (1 + xi * xi * H / G), xi * c_r)
            seen_soft |= expected > xi * c_r
            seen_res |= expected == xi * c_r
        assert tau == pytest.approx(expected, rel=1e-12)
    assert seen_soft and seen_res


# ---------------------------------------------------------------------------------------------
# Perzyna
# ---------------------------------------------------------------------------------------------


def test_perzyna_relaxation_on_the_cone():
    """At constant strain d sqrt(J2)/dt = -G gamma_dot, dp/dt = -K eta_bar gamma_dot and
    dc/dt = xi H gamma_dot, so Phi relaxes as Phi0 exp(-(G + K eta eta_bar + xi^2 H) t / eta_v);
    backward Euler gives Phi_k = Phi0 / (1 + dt a / eta_v)^k exactly (relative 1e-9) and the
    exponential to first order in dt (relative 3e-3 at dt = tau / 500)."""
    eta_v = 2.0e8
    H = 0.02 * G
    params = drucker_prager_params(E, NU, C, PHI, 10.0, cohesion_hardening=H, viscosity=eta_v)
    eta, xi, etab = params[P_FRICTION_COEF], params[P_COHESION_COEF], params[P_DILATANCY_COEF]
    a = G + K * eta * etab + xi * xi * H
    tau = eta_v / a
    eps = np.array([-1.0, -0.5, 0.2, 5.0, 1.0, 0.0]) * EPS_C

    def phi(st):
        s6 = st[0, S_STRESS:S_STRESS + 6]
        return sqrt_j2(s6) + eta * s6[:3].mean() - xi * (C + H * st[0, S_EQ_PLASTIC_STRAIN])

    _, _, st0 = evaluate(eps, params, drucker_prager_initial_state(1), dt=0.0)
    assert st0[0, S_CODE] == CODE_ELASTIC
    f0 = phi(st0)
    assert f0 > 0.5 * C
    n = 1000
    dt = 2 * tau / n
    st = st0
    for k in range(1, n + 1):
        _, _, st = evaluate(eps, params, st, dt=dt)
        assert phi(st) == pytest.approx(f0 / (1 + dt / tau) ** k, rel=1e-9)
    assert phi(st) == pytest.approx(f0 * math.exp(-2.0), rel=3e-3)


@pytest.mark.parametrize("strain", [[-1.0, -0.5, 0.2, 5.0, 1.0, 0.0], [3.0, 2.5, 2.8, 0.2, -0.1, 0.1]],
                         ids=["cone", "apex"])
def test_perzyna_tends_to_rate_independent(strain):
    """The Perzyna step tends to the rate-independent return as eta_v -> 0, linearly in eta_v/dt,
    on the cone and at the apex (psi = 0 uses the tension cut-off apex)."""
    eps = np.array(strain) * EPS_C * (3 if strain[0] > 0 else 1)
    ri = drucker_prager_params(E, NU, C, PHI, 0.0, cohesion_hardening=0.01 * G)
    s_ri, D_ri, t_ri = evaluate(eps, ri, drucker_prager_initial_state(1))
    diffs = []
    for eta_v in (1e6, 1e4, 1e2):
        pv = drucker_prager_params(E, NU, C, PHI, 0.0, cohesion_hardening=0.01 * G, viscosity=eta_v)
        s_v, D_v, t_v = evaluate(eps, pv, drucker_prager_initial_state(1), dt=1.0)
        assert t_v[0, S_CODE] == t_ri[0, S_CODE]
        diffs.append(np.max(np.abs(s_v - s_ri)))
    assert diffs[-1] <= 1e-5 * C  # eta_v / dt = 1e-4 c: measured 4e-8 c (cone), 9e-7 c (apex)
    for d1, d2 in zip(diffs, diffs[1:]):
        assert d2 == pytest.approx(d1 / 100, rel=2e-2)


# ---------------------------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(friction_angle_deg=90.0), "friction_angle"),
        (dict(friction_angle_deg=-1.0), "friction_angle"),
        (dict(dilation_angle_deg=PHI + 1.0), "dilation_angle"),
        (dict(dilation_angle_deg=-1.0), "dilation_angle"),
        (dict(viscosity=-1.0), "viscosity"),
        (dict(cohesion=-1.0), "cohesion"),
        (dict(cohesion=0.0, friction_angle_deg=0.0, dilation_angle_deg=0.0), "cohesion"),
        (dict(residual_cohesion=2 * C), "residual_cohesion"),
        (dict(cohesion_hardening=-10 * G), "cohesion_hardening"),  # cone condition
        (dict(dilation_angle_deg=1.0, cohesion_hardening=-0.05 * G), "cohesion_hardening"),  # apex condition
        (dict(match="circumscribed"), "match"),
        (dict(poisson_ratio=-1.0), "poisson_ratio"),
        (dict(youngs_modulus=-1.0), "youngs_modulus"),
        (dict(cohesion=float("inf")), "cohesion"),
    ],
)
def test_bad_parameters_raise_named_errors(kwargs, name):
    args = dict(youngs_modulus=E, poisson_ratio=NU, cohesion=C, friction_angle_deg=PHI, dilation_angle_deg=0.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        drucker_prager_params(**args)


def test_softening_limit_depends_on_dilation():
    """The apex condition K eta eta_a + xi^2 H > 0 is the binding one: a softening accepted with
    psi = 0 (eta_a = eta) is rejected for a small psi > 0 (eta_a = eta_bar) and accepted again for
    psi = phi."""
    H = -0.05 * G
    drucker_prager_params(E, NU, C, PHI, 0.0, cohesion_hardening=H)
    with pytest.raises(ValueError, match="apex"):
        drucker_prager_params(E, NU, C, PHI, 1.0, cohesion_hardening=H)
    drucker_prager_params(E, NU, C, PHI, PHI, cohesion_hardening=H)


def test_nan_and_table_errors():
    params = np.tile(drucker_prager_params(E, NU, C, PHI, 5.0), (2, 1))
    assert params.shape == (2, N_DP_PARAMS)
    strain = np.zeros((2, 6))
    strain[1, 4] = np.inf
    committed = drucker_prager_initial_state(2)
    with pytest.raises(NumericalError, match="point 1"):
        drucker_prager_evaluate(strain, params, committed)
    trial = np.full((2, N_DP_STATE), 3.0)
    info = np.zeros(2, dtype=np.int64)
    status = drucker_prager_update(strain, params, committed, trial, np.zeros((2, 6)), np.zeros((2, 6, 6)), 0.0, True,
                                   info)
    assert status == STATUS_NAN and info[0] == 1 and np.array_equal(trial[1], committed[1])
    bad = params.copy()
    bad[1, P_DILATANCY_COEF] = 2 * bad[1, P_FRICTION_COEF]
    with pytest.raises(ValueError, match=r"eta_bar.*row 1"):
        drucker_prager_evaluate(np.zeros((2, 6)), bad, committed)


@pytest.mark.parametrize("phi", [20.0, 25.0, 30.0, 35.0, 40.0, 45.0])
def test_associated_plane_strain_match_builds_for_every_angle(phi):
    """Associated flow (psi = phi) with the plane-strain match: eta_bar equals eta exactly (30 and 40 deg
    failed the eta_bar <= eta check by one rounding bit)."""
    row = drucker_prager_params(3e10, 0.2, 1e6, phi)
    assert row[P_DILATANCY_COEF] == row[P_FRICTION_COEF]
