"""Tests of the Tresca plasticity law (masonrydam.materials.tresca).

Sources: de Souza Neto, Peric & Owen (2008), Computational Methods for Plasticity: the Tresca
return mapping in principal stresses (sec. 8.1: main plane, right and left edges),
its consistent tangent and the tangent of isotropic tensor functions (appendix A, box A.6);
Simo & Hughes (1998), Computational Inelasticity: the one-dimensional model with linear isotropic
hardening and its closed-form return (ch. 1), Perzyna viscoplasticity (sec. 2.7; de Souza Neto et
al. sec. 11.5); Chen & Han (1988), Plasticity for Structural Engineers, ch. 2: Tresca limit
states (uniaxial yield sigma_y, pure shear sigma_y / 2, sigma_1 - sigma_3 = sigma_y).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from plasticity_checks import point_checks, rotation, strain_tensor, strain_vector, stress_tensor, stress_vector

from masonrydam.errors import STATUS_NAN, STATUS_OK, NumericalError
from masonrydam.materials.mohr_coulomb_solid import (
    mohr_coulomb_solid_evaluate,
    mohr_coulomb_solid_initial_state,
    mohr_coulomb_solid_params,
)
from masonrydam.materials.plasticity import (
    CODE_EDGE_LEFT, CODE_EDGE_RIGHT, CODE_ELASTIC, CODE_PLASTIC, STATUS_BAD_MATERIAL,
)
from masonrydam.materials.principal_return import principal_stresses
from masonrydam.materials.tresca import (
    N_TRESCA_PARAMS,
    N_TRESCA_STATE,
    P_H_ISO,
    P_SIGMA_Y,
    P_VISCOSITY,
    S_CODE,
    S_EQ_PLASTIC_STRAIN,
    S_PLASTIC_STRAIN,
    S_STRESS,
    tresca_evaluate,
    tresca_initial_state,
    tresca_params,
    tresca_update,
)

E = 30.0e9  # Pa
NU = 0.25
SY = 20.0e6  # Pa
G = E / (2 * (1 + NU))
K = E / (3 * (1 - 2 * NU))
EPS_Y = SY / E
EPS_S = SY / G  # a strain of the order of the elastic limit in shear
PS = [0, 1, 3]


M3, M2 = [0.0, 0.0, 0.0, 4.0, 0.4, 0.2], [0.6, -0.6, 4.0]  # main plane
R3, R2 = [3.0, -1.35, -1.65, 0.15, 0.0, 0.0], [2.0, 0.4, 0.6]  # right edge (sigma_2 = sigma_3)
L3, L2 = [3.3, 2.7, -6.0, 0.0, 0.3, 0.0], [-4.0, 2.0, 0.5]  # left edge (sigma_1 = sigma_2)


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


evaluate, fd_tangent = point_checks(tresca_evaluate)


def axisymmetric_path(prm, axial_path, lateral, dt=0.0):
    """Axisymmetric stress driven by exx: the tied lateral strains eyy = ezz are found by a Newton with
    the consistent tangent so that syy = szz = ``lateral`` (on an edge sigma_2 = sigma_3 holds
    whatever the strain, so the two lateral strains are tied to keep the Jacobian regular). Returns the
    axial stresses, the states and the largest iteration count."""
    state = tresca_initial_state(1)
    x = 0.0
    out, states, iters = [], [], 0
    for exx in axial_path:
        for it in range(30):
            eps = np.array([exx, x, x, 0.0, 0.0, 0.0])
            s, D, trial = evaluate(eps, prm, state, dt)
            r = s[1] - lateral
            if abs(r) <= 1e-9 * SY:
                break
            x -= r / (D[1, 1] + D[1, 2])
        else:
            raise AssertionError("lateral Newton did not converge")
        iters = max(iters, it)
        state = trial
        out.append(s[0])
        states.append(trial[0].copy())
    return np.array(out), states, iters


def one_d_reference(path, sy0, h, sy_res=0.0):
    """Closed-form 1D return with linear isotropic hardening stopped at a residual (Simo & Hughes
    1998, ch. 1): the uniaxial response of Tresca with H the slope against the uniaxial plastic strain."""
    ep, alpha, out = 0.0, 0.0, []
    for eps in path:
        sig = E * (eps - ep)
        r = max(sy0 + h * alpha, sy_res)
        f = abs(sig) - r
        if f > 0:
            xk = max((sy_res - sy0) / h - alpha, 0.0) if h < 0 else math.inf
            a1, a2 = E + h, E
            dg = f / a1 if f <= a1 * xk else xk + (f - a1 * xk) / a2
            ep += dg * math.copysign(1.0, sig)
            alpha += dg
            sig -= E * dg * math.copysign(1.0, sig)
        out.append(sig)
    return np.array(out)


def overstress(state, prm):
    s1, _, s3 = principal_stresses(state[0, S_STRESS:S_STRESS + 6])
    return s1 - s3 - max(prm[P_SIGMA_Y] + prm[P_H_ISO] * state[0, S_EQ_PLASTIC_STRAIN], 0.0)


# ---------------------------------------------------------------------------------------------
# closed forms
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "h, sy_res",
    [(0.0, 0.0), (0.1 * E, 0.0), (-0.02 * E, 0.5 * SY)],
    ids=["perfect", "hardening", "softening"],
)
def test_uniaxial_cycle_matches_closed_form(h, sy_res):
    """Uniaxial stress through tension, reverse compression and reloading equals the 1D closed form
    with isotropic hardening (Simo & Hughes 1998, ch. 1; relative 1e-9 of sigma_y): first yield at
    |sigma| = sigma_y, slope E H / (E + H), kappa = the accumulated uniaxial plastic strain. Tension
    returns to the right edge (sigma_2 = sigma_3 = 0), compression to the left edge; the plastic
    strain is (1, -1/2, -1/2) times the axial one (isochoric)."""
    prm = tresca_params(E, NU, SY, h, sy_res)
    step = EPS_Y / 4
    path = np.concatenate([np.arange(step, 6 * EPS_Y, step), np.arange(6 * EPS_Y, -6 * EPS_Y, -step),
                           np.arange(-6 * EPS_Y, 2 * EPS_Y, step)])
    sxx, states, iters = axisymmetric_path(prm, path, 0.0)
    ref = one_d_reference(path, SY, h, sy_res)
    assert np.max(np.abs(sxx - ref)) <= 1e-9 * SY
    assert iters <= 4
    codes = {int(st[S_CODE]) for st in states}
    assert {CODE_EDGE_RIGHT, CODE_EDGE_LEFT, CODE_ELASTIC} <= codes
    ep = states[-1][S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 3]
    assert ep[1] == pytest.approx(-0.5 * ep[0], rel=1e-9)
    assert abs(ep.sum()) <= 1e-12 * abs(ep[0])


@pytest.mark.parametrize("ns", [3, 6])
def test_pure_shear_yields_at_half_sigma_y(ns):
    """Pure shear (only gxy): tau = G gamma up to tau = sigma_y / 2 (Tresca: sigma_1 - sigma_3 = 2 tau),
    then constant; the normal stresses stay zero (main plane: sigma_2 = szz = 0 between +-tau)."""
    prm = tresca_params(E, NU, SY)
    ixy = 2 if ns == 3 else 3
    state = tresca_initial_state(1)
    for g in np.linspace(0.1, 3.0, 25) * EPS_S:
        eps = np.zeros(ns)
        eps[ixy] = g
        s, _, state = evaluate(eps, prm, state)
        assert s[ixy] == pytest.approx(min(G * g, SY / 2), rel=1e-12)
        assert np.max(np.abs(state[0, S_STRESS:S_STRESS + 3])) <= 1e-9 * SY
    assert state[0, S_CODE] == CODE_PLASTIC


@pytest.mark.parametrize("p0", [0.0, 3.0 * SY, 30.0 * SY])
@pytest.mark.parametrize("sign", [-1.0, 1.0], ids=["compression", "extension"])
def test_triaxial_strength_does_not_depend_on_confinement(sign, p0):
    """Triaxial compression and extension at confinement p0: |sigma_axial + p0| = sigma_y whatever p0
    (Chen & Han 1988; pressure insensitive), on the left edge (compression) or the right edge
    (extension)."""
    prm = tresca_params(E, NU, SY)
    e0 = -p0 / (3 * K)
    path = [e0] + [e0 + sign * f * EPS_Y for f in np.linspace(0.25, 5.0, 20)]
    sxx, states, _ = axisymmetric_path(prm, path, -p0)
    assert sxx[0] == pytest.approx(-p0, rel=1e-12, abs=1e-6)
    assert sxx[-1] + p0 == pytest.approx(sign * SY, rel=1e-10)
    assert states[-1][S_CODE] == (CODE_EDGE_LEFT if sign < 0 else CODE_EDGE_RIGHT)


def test_hydrostatic_stress_never_yields():
    """The Tresca prism is open along the hydrostatic axis: no apex."""
    prm = tresca_params(E, NU, SY)
    for ev in (-1.0, 1.0):
        s, D, t = evaluate(np.array([ev, ev, ev, 0, 0, 0]) * 100 * EPS_Y, prm, tresca_initial_state(1))
        assert t[0, S_CODE] == CODE_ELASTIC
        assert s[0] == pytest.approx(3 * K * ev * 100 * EPS_Y, rel=1e-14)


@pytest.mark.parametrize("direction, code", [(M3, CODE_PLASTIC), (R3, CODE_EDGE_RIGHT), (L3, CODE_EDGE_LEFT)],
                         ids=["main", "right", "left"])
def test_returns_land_on_their_planes(direction, code):
    """Each return (de Souza Neto et al. sec. 8.1) in a rotated frame: sigma_1 - sigma_3 =
    sigma_y, and sigma_2 strictly between (main), = sigma_3 (right) or = sigma_1 (left); the plastic
    strain has zero trace and kappa = the sum of the multipliers = the largest principal plastic
    strain magnitude of the step, (eps_p_1 - eps_p_3) / 2 on the main plane."""
    prm = tresca_params(E, NU, SY)
    R = rotation(4)
    eps = strain_vector(R @ strain_tensor(np.array(direction) * EPS_S) @ R.T)
    s, _, t = evaluate(eps, prm, tresca_initial_state(1))
    assert t[0, S_CODE] == code
    s1, s2, s3 = principal_stresses(s)
    tol = 1e-9 * SY
    assert s1 - s3 == pytest.approx(SY, abs=tol)
    if code == CODE_PLASTIC:
        assert s1 - s2 > 1e-3 * SY and s2 - s3 > 1e-3 * SY
    elif code == CODE_EDGE_RIGHT:
        assert abs(s2 - s3) <= tol
    else:
        assert abs(s1 - s2) <= tol
    ep = np.linalg.eigvalsh(strain_tensor(t[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6]))[::-1]
    assert abs(ep.sum()) <= 1e-12 * np.max(np.abs(ep))
    kappa = t[0, S_EQ_PLASTIC_STRAIN]
    assert kappa == pytest.approx(max(ep[0], -ep[2]), rel=1e-10)
    if code == CODE_PLASTIC:
        assert kappa == pytest.approx(0.5 * (ep[0] - ep[2]), rel=1e-10)


def test_equals_mohr_coulomb_without_friction():
    """Tresca(sigma_y, H) is Mohr-Coulomb with phi = psi = 0, c = sigma_y / 2 and cohesion hardening H / 4
    (eps_bar = 2 cos(phi) gamma = 2 kappa): same stresses, tangents and plastic strains along a history."""
    h = 0.05 * E
    prm_t = tresca_params(E, NU, SY, h, viscosity=1e7)
    prm_m = mohr_coulomb_solid_params(E, NU, SY / 2, 0.0, 0.0, cohesion_hardening=h / 4, viscosity=1e7)
    st_t, st_m = tresca_initial_state(1), mohr_coulomb_solid_initial_state(1)
    for e3 in (M3, R3, L3, [-2, 1, 0.1, 4, 1, 1]):
        eps = np.atleast_2d(np.array(e3) * EPS_S)
        s_t, D_t, st_t = tresca_evaluate(eps, prm_t, st_t, dt=0.1)
        s_m, D_m, st_m = mohr_coulomb_solid_evaluate(eps, prm_m, st_m, dt=0.1)
        assert np.allclose(s_t, s_m, rtol=0, atol=1e-9 * SY)
        assert np.allclose(D_t, D_m, rtol=0, atol=1e-9 * E)
        assert np.allclose(st_t[0, :S_EQ_PLASTIC_STRAIN], st_m[0, :S_EQ_PLASTIC_STRAIN], rtol=0, atol=1e-9 * SY)
        assert st_m[0, S_EQ_PLASTIC_STRAIN] == pytest.approx(2 * st_t[0, S_EQ_PLASTIC_STRAIN], rel=1e-10)
        assert st_t[0, S_CODE] == st_m[0, S_CODE]


def test_plane_strain_equals_3d():
    """A plane-strain point equals a 3D point with ezz = gyz = gzx = 0 (stress, tangent block, state)
    on the main plane and both edges."""
    prm = tresca_params(E, NU, SY, 0.02 * E)

    def both(eps, st2, st3):
        s2, D2, st2 = evaluate(eps, prm, st2)
        s3, D3, st3 = evaluate(np.array([eps[0], eps[1], 0, eps[2], 0, 0]), prm, st3)
        assert np.allclose(s2, s3[PS], rtol=0, atol=1e-9 * SY)
        assert np.allclose(D2, D3[np.ix_(PS, PS)], rtol=0, atol=1e-9 * E)
        assert np.allclose(st2, st3, rtol=0, atol=1e-12 * SY)
        return st2, st3

    codes = set()
    for e2 in (M2, R2, L2):
        st2, _ = both(np.array(e2) * EPS_S, tresca_initial_state(1), tresca_initial_state(1))
        codes.add(int(st2[0, S_CODE]))
    assert codes == {CODE_PLASTIC, CODE_EDGE_RIGHT, CODE_EDGE_LEFT}
    st2, st3 = tresca_initial_state(1), tresca_initial_state(1)
    for e2 in (M2, R2, L2, [-6.0, -1.0, 3.0]):
        st2, st3 = both(np.array(e2) * EPS_S, st2, st3)


# ---------------------------------------------------------------------------------------------
# consistent tangent, isotropy
# ---------------------------------------------------------------------------------------------

TANGENT_CASES = {
    # name: (H / E, sigma_r / sigma_y, eta / G (s), dt, 3D strain, plane-strain strain (times EPS_S), code)
    "main_perfect": (0.0, 0.0, 0.0, 0.0, M3, M2, CODE_PLASTIC),
    "main_hardening": (0.05, 0.0, 0.0, 0.0, M3, M2, CODE_PLASTIC),
    "main_softening": (-0.01, 0.2, 0.0, 0.0, M3, M2, CODE_PLASTIC),
    "main_residual": (-0.3, 0.9, 0.0, 0.0, M3, M2, CODE_PLASTIC),  # increments from a sheared state
    "main_perzyna": (0.02, 0.0, 0.3, 1.0, M3, M2, CODE_PLASTIC),
    "right_perfect": (0.0, 0.0, 0.0, 0.0, R3, R2, CODE_EDGE_RIGHT),
    "right_softening": (-0.01, 0.2, 0.0, 0.0, R3, R2, CODE_EDGE_RIGHT),
    "right_perzyna": (0.02, 0.0, 0.3, 1.0, R3, R2, CODE_EDGE_RIGHT),
    "left_hardening": (0.05, 0.0, 0.0, 0.0, L3, L2, CODE_EDGE_LEFT),
    "left_residual": (-0.3, 0.9, 0.0, 0.0, L3, L2, CODE_EDGE_LEFT),
    "left_perzyna": (0.0, 0.0, 0.3, 1.0, L3, L2, CODE_EDGE_LEFT),
}


@pytest.mark.parametrize("ns", [3, 6])
@pytest.mark.parametrize("case", list(TANGENT_CASES))
def test_consistent_tangent_equals_finite_difference(case, ns):
    """Consistent tangent on the main plane and both edges (perfect, hardening, softening, past the
    residual, Perzyna), 3D and plane strain, a strain increment from a committed plastic state in
    shear, vs a central difference
    of the stress update (relative 1e-6 of max |D|); symmetric (associated flow)."""
    h, r, eta, dt, e3, e2, code = TANGENT_CASES[case]
    prm = tresca_params(E, NU, SY, h * E, r * SY, eta * G)
    first = (np.array([0.0, 0.0, 0.0, 3.0, 0, 0]) if ns == 6 else np.array([0.0, 0.0, 3.0])) * EPS_S
    _, _, state = evaluate(first, prm, tresca_initial_state(1), dt)
    assert state[0, S_EQ_PLASTIC_STRAIN] > 0
    eps = first + 0.5 * np.array(e3 if ns == 6 else e2) * EPS_S
    _, D, trial = evaluate(eps, prm, state, dt)
    assert trial[0, S_CODE] == code
    if r == 0.9:
        assert SY + h * E * trial[0, S_EQ_PLASTIC_STRAIN] < r * SY  # past the residual kink
    Dfd = fd_tangent(eps, prm, state, dt)
    scale = np.max(np.abs(D))
    assert np.max(np.abs(D - Dfd)) <= 1e-6 * scale
    assert np.max(np.abs(D - D.T)) <= 1e-10 * scale


def test_rotating_the_strain_rotates_the_stress():
    """Isotropy: sigma(R eps R^T) = R sigma(eps) R^T over a non-proportional history (relative 1e-10),
    the plastic strain likewise."""
    prm = tresca_params(E, NU, SY, 0.02 * E)
    R = rotation(9)
    sa, sb = tresca_initial_state(1), tresca_initial_state(1)
    codes = set()
    for e3 in (M3, [-2, 1, 0.1, 4, 1, 1], R3, L3, [-3, -2, 1, 0, 2, 3]):
        eps = np.array(e3, dtype=float) * EPS_S
        s1, _, sa = evaluate(eps, prm, sa)
        s2, _, sb = evaluate(strain_vector(R @ strain_tensor(eps) @ R.T), prm, sb)
        assert np.allclose(stress_vector(R @ stress_tensor(s1) @ R.T), s2, rtol=0, atol=1e-10 * SY)
        ep_a = strain_tensor(sa[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6])
        ep_b = strain_tensor(sb[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6])
        assert np.allclose(R @ ep_a @ R.T, ep_b, rtol=0, atol=1e-10 * np.max(np.abs(ep_a)))
        assert sa[0, S_EQ_PLASTIC_STRAIN] == pytest.approx(sb[0, S_EQ_PLASTIC_STRAIN], rel=1e-10)
        codes.add(int(sa[0, S_CODE]))
    assert len(codes) >= 2


# ---------------------------------------------------------------------------------------------
# Perzyna
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("region, a", [("main", 4.0), ("right", 3.0)])
def test_perzyna_relaxation_at_constant_strain(region, a):
    """At constant strain the overstress relaxes as Phi0 exp(-(a G + H) t / eta) with a G = 4G on the
    main plane (d(sigma_1 - sigma_3) = -4G d gamma) and 3G on an edge ((a + b) / 2 with a = 4G,
    b = 2G the coupling of the two planes); backward Euler gives Phi_k = Phi_k0 / (1 + dt (aG + H) / eta)^(k - k0)
    exactly (relative 1e-9) and the exponential to first order (3e-3 at dt = tau / 500). On the edge a
    first long step (20 tau) brings the stress onto sigma_2 = sigma_3 (k0 = 1). The long-time limit is
    the rate-independent return."""
    eta, h = 1.0e9, 0.02 * E
    prm = tresca_params(E, NU, SY, h, viscosity=eta)
    tau = eta / (a * G + h)
    eps = np.array(M3 if region == "main" else R3) * EPS_S
    code = CODE_PLASTIC if region == "main" else CODE_EDGE_RIGHT
    _, _, st0 = evaluate(eps, prm, tresca_initial_state(1), dt=0.0)
    assert st0[0, S_CODE] == CODE_ELASTIC
    n = 1000
    dt = 2 * tau / n
    k0 = 0 if region == "main" else 1
    _, _, st = evaluate(eps, prm, st0, dt=dt if k0 == 0 else 20 * tau)
    assert st[0, S_CODE] == code
    f0 = overstress(st0 if k0 == 0 else st, prm)
    assert f0 > (0.5 if k0 == 0 else 0.01) * SY
    for k in range(2, n + 1):
        _, _, st = evaluate(eps, prm, st, dt=dt)
        assert st[0, S_CODE] == code
        assert overstress(st, prm) == pytest.approx(f0 / (1 + dt / tau) ** (k - k0), rel=1e-9)
    assert overstress(st, prm) == pytest.approx(f0 * math.exp(-(n - k0) * dt / tau), rel=3e-3)
    s_ri, _, _ = evaluate(eps, tresca_params(E, NU, SY, h), tresca_initial_state(1))
    for _ in range(40):
        s_v, _, st = evaluate(eps, prm, st, dt=2 * tau)
    assert np.allclose(s_v, s_ri, rtol=0, atol=1e-9 * SY)


@pytest.mark.parametrize("direction", [M3, R3, L3], ids=["main", "right", "left"])
def test_perzyna_tends_to_rate_independent(direction):
    """One viscous step tends to the rate-independent return, linearly in eta / dt, in each region."""
    eps = np.array(direction) * EPS_S
    s_ri, D_ri, t_ri = evaluate(eps, tresca_params(E, NU, SY, 0.05 * E), tresca_initial_state(1))
    diffs = []
    for eta in (1e7, 1e5, 1e3):
        s_v, D_v, t_v = evaluate(eps, tresca_params(E, NU, SY, 0.05 * E, viscosity=eta), tresca_initial_state(1),
                                 dt=1.0)
        assert t_v[0, S_CODE] == t_ri[0, S_CODE]
        diffs.append(np.max(np.abs(s_v - s_ri)))
        assert np.max(np.abs(D_v - D_ri)) <= 10 * eta / (3 * G) * np.max(np.abs(D_ri))
    assert diffs[-1] <= 1e-6 * SY
    for d1, d2 in zip(diffs, diffs[1:]):
        assert d2 == pytest.approx(d1 / 100, rel=1e-2)


# ---------------------------------------------------------------------------------------------
# errors, kernel protocol
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(yield_stress=0.0), "yield_stress"),
        (dict(yield_stress=-1.0), "yield_stress"),
        (dict(yield_stress="x"), "yield_stress"),
        (dict(viscosity=-1.0), "viscosity"),
        (dict(isotropic_hardening=-3 * G), "isotropic_hardening"),
        (dict(residual_yield_stress=2 * SY), "residual_yield_stress"),
        (dict(residual_yield_stress=-1.0), "residual_yield_stress"),
        (dict(poisson_ratio=0.5), "poisson_ratio"),
        (dict(youngs_modulus=-1.0), "youngs_modulus"),
        (dict(isotropic_hardening=float("inf")), "isotropic_hardening"),
    ],
)
def test_bad_parameters_raise_named_errors(kwargs, name):
    args = dict(youngs_modulus=E, poisson_ratio=NU, yield_stress=SY)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        tresca_params(**args)


def test_softening_limit_is_3g():
    tresca_params(E, NU, SY, -2.99 * G, 0.1 * SY)
    with pytest.raises(ValueError, match="3G"):
        tresca_params(E, NU, SY, -3.0 * G)


def test_kernel_status_and_table_errors():
    """NaN strain -> STATUS_NAN (trial state = committed, NaN stress, zero tangent); a bad column
    bypassing the wrapper -> STATUS_BAD_MATERIAL with the column; the wrapper raises NumericalError /
    ValueError naming the parameter and the row."""
    prm = np.tile(tresca_params(E, NU, SY), (3, 1))
    assert prm.shape == (3, N_TRESCA_PARAMS)
    committed = tresca_initial_state(3)
    strain = np.full((3, 3), 1e-6)
    strain[1, 2] = np.nan
    trial = np.full((3, N_TRESCA_STATE), -7.0)
    stress = np.zeros((3, 3))
    tangent = np.ones((3, 3, 3))
    info = np.zeros(2, dtype=np.int64)
    status = tresca_update(strain, prm, committed, trial, stress, tangent, 0.0, True, info)
    assert status == STATUS_NAN and info[0] == 1
    assert np.array_equal(trial[1], committed[1]) and np.all(np.isnan(stress[1])) and np.all(tangent[1] == 0)
    with pytest.raises(NumericalError, match="point 1"):
        tresca_evaluate(strain, prm, committed)
    strain[1, 2] = 1e-6
    for col, value in ((P_SIGMA_Y, -1.0), (P_H_ISO, -4 * G), (P_VISCOSITY, -1.0)):
        bad = prm.copy()
        bad[2, col] = value
        status = tresca_update(strain, bad, committed, trial, stress, tangent, 0.0, True, info)
        assert status == STATUS_BAD_MATERIAL and info[0] == 2 and info[1] == col
        with pytest.raises(ValueError, match="row 2"):
            tresca_evaluate(strain, bad, committed)
    assert tresca_update(strain, prm, committed, trial, stress, tangent, -1.0, True, info) == STATUS_BAD_MATERIAL
    assert info[1] == -1
    assert tresca_update(strain, prm, committed, trial, stress, tangent, 0.0, True, info) == STATUS_OK


def test_batch_without_tangent_and_elastic_matrix():
    from masonrydam.materials.elastic import elasticity_matrix

    prm = tresca_params(E, NU, SY, 0.01 * E)
    strain = np.array([np.array(d) * EPS_S for d in (M3, R3, L3)] + [[1e-2 * EPS_Y, 0, 0, 0, 0, 0]])
    st = tresca_initial_state(4)
    s1, D1, t1 = tresca_evaluate(strain, prm, st)
    s2, D2, t2 = tresca_evaluate(strain, prm, st, want_tangent=False)
    assert D2 is None and D1.shape == (4, 6, 6)
    assert np.array_equal(s1, s2) and np.array_equal(t1, t2)
    assert list(t1[:, S_CODE]) == [CODE_PLASTIC, CODE_EDGE_RIGHT, CODE_EDGE_LEFT, CODE_ELASTIC]
    assert np.allclose(D1[3], elasticity_matrix(E, NU, "3d"), rtol=1e-13, atol=0)
