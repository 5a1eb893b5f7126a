"""Tests of the von Mises (J2) plasticity law (masonrydam.materials.von_mises).

Sources: radial return and consistent tangent after Simo & Taylor (1985), CMAME 48:101-118, and
Simo & Hughes (1998), Computational Inelasticity, box 3.2 / sec. 3.3; de Souza Neto, Peric & Owen
(2008), Computational Methods for Plasticity, ch. 7; the one-dimensional
combined-hardening model and its closed-form return of Simo & Hughes ch. 1; Perzyna
viscoplasticity after Simo & Hughes sec. 2.7 and de Souza Neto et al. sec. 11.5.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from plasticity_checks import point_checks, rotation, strain_tensor, strain_vector, stress_tensor, stress_vector

from masonrydam.errors import STATUS_NAN, STATUS_OK, NumericalError
from masonrydam.materials.plasticity import CODE_ELASTIC, CODE_PLASTIC, STATUS_BAD_MATERIAL
from masonrydam.materials.von_mises import (
    N_VM_PARAMS,
    N_VM_STATE,
    P_H_ISO,
    P_SIGMA_Y,
    P_VISCOSITY,
    S_BACK_STRESS,
    S_CODE,
    S_EQ_PLASTIC_STRAIN,
    S_PLASTIC_STRAIN,
    S_STRESS,
    von_mises_evaluate,
    von_mises_initial_state,
    von_mises_params,
    von_mises_update,
)

E = 30.0e9  # Pa
NU = 0.2
SY = 20.0e6  # Pa
G = E / (2 * (1 + NU))
K = E / (3 * (1 - 2 * NU))
EPS_Y = SY / E

# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------



evaluate, fd_tangent = point_checks(von_mises_evaluate)


def uniaxial_stress_path(params, exx_path, dt=0.0):
    """3D uniaxial stress driven by exx: a Newton on (eyy, ezz) with the consistent tangent makes
    syy = szz = 0 at every step (the shear strains stay zero). Returns the axial stresses, the
    states and the largest number of Newton iterations taken."""
    state = von_mises_initial_state(1)
    lat = np.zeros(2)
    out, states, iters = [], [], 0
    for exx in exx_path:
        for it in range(20):
            eps = np.array([exx, lat[0], lat[1], 0.0, 0.0, 0.0])
            s, D, trial = evaluate(eps, params, state, dt)
            r = s[1:3]
            if np.max(np.abs(r)) <= 1e-9 * SY:
                break
            lat -= np.linalg.solve(D[1:3, 1:3], r)
        else:
            raise AssertionError("lateral Newton did not converge")
        iters = max(iters, it)
        state = trial
        out.append(s[0])
        states.append(trial[0].copy())
    return np.array(out), states, iters


def one_d_reference(exx_path, sy0, h_iso, h_kin, sy_res=0.0):
    """Closed-form 1D return mapping with combined linear hardening (Simo & Hughes 1998,
    ch. 1), with the isotropic part stopped at the residual yield stress: the uniaxial stress
    response of J2 plasticity (uniaxial plastic modulus H_iso + H_kin, axial modulus E)."""
    ep, alpha, back = 0.0, 0.0, 0.0
    out = []
    for eps in exx_path:
        sig_tr = E * (eps - ep)
        xi = sig_tr - back
        r = max(sy0 + h_iso * alpha, sy_res)
        f = abs(xi) - r
        if f > 0:
            a1 = E + h_iso + h_kin
            a2 = E + h_kin
            if h_iso < 0:
                xk = max((sy_res - sy0) / h_iso - alpha, 0.0)
            else:
                xk = math.inf
            dg = f / a1 if f <= a1 * xk else xk + (f - a1 * xk) / a2
            sgn = math.copysign(1.0, xi)
            ep += dg * sgn
            back += h_kin * dg * sgn
            alpha += dg
            sig_tr -= E * dg * sgn
        out.append(sig_tr)
    return np.array(out)


def cycle(peak, trough, end, n=12):
    """0 -> peak -> trough -> end in steps of about peak / n."""
    step = peak / n
    legs = [np.arange(step, peak + 0.5 * step, step)]
    legs.append(np.arange(peak - step, trough - 0.5 * step, -step))
    legs.append(np.arange(trough + step, end + 0.5 * step, step))
    return np.concatenate(legs)


# ---------------------------------------------------------------------------------------------
# uniaxial stress
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "h_iso, h_kin, sy_res",
    [(0.0, 0.0, 0.0), (0.1 * E, 0.0, 0.0), (0.0, 0.1 * E, 0.0), (0.05 * E, 0.08 * E, 0.0), (-0.02 * E, 0.0, 0.5 * SY)],
    ids=["perfect", "isotropic", "kinematic", "combined", "softening"],
)
def test_uniaxial_stress_cycle_matches_closed_form(h_iso, h_kin, sy_res):
    """Uniaxial stress (syy = szz = 0 by a Newton on the lateral strains) through loading,
    unloading and reverse yielding equals the 1D closed form of Simo & Hughes ch. 1 (relative
    1e-9 of sigma_y; measured ~1e-15); the lateral Newton converges quadratically (<= 3 iterations)
    with the consistent tangent."""
    params = von_mises_params(E, NU, SY, h_iso, h_kin, sy_res)
    path = cycle(8 * EPS_Y, -8 * EPS_Y, 4 * EPS_Y)
    sxx, states, iters = uniaxial_stress_path(params, path)
    ref = one_d_reference(path, SY, h_iso, h_kin, sy_res)
    assert np.max(np.abs(sxx - ref)) <= 1e-9 * SY
    assert iters <= 3
    # the plastic strain of uniaxial stress is axial with -1/2 laterally, and alpha = sum |d eps_p|
    ep = states[-1][S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6]
    assert ep[1] == pytest.approx(-0.5 * ep[0], rel=1e-9)
    assert abs(sum(ep[:3])) <= 1e-12 * abs(ep[0])


def test_uniaxial_explicit_values():
    """Hand values of the uniaxial curve (Simo & Hughes ch. 1): first yield at sigma_y, slope
    E H / (E + H), Bauschinger reverse yield at sigma_max - 2 sigma_y (kinematic) and at -sigma_max
    (isotropic)."""
    H = 0.1 * E
    path = np.array([EPS_Y, 5 * EPS_Y])
    for kind in ("iso", "kin"):
        params = von_mises_params(E, NU, SY, H if kind == "iso" else 0.0, H if kind == "kin" else 0.0)
        s, _, _ = uniaxial_stress_path(params, path)
        assert s[0] == pytest.approx(SY, rel=1e-12)
        smax = SY + E * H / (E + H) * 4 * EPS_Y
        assert s[1] == pytest.approx(smax, rel=1e-12)
        # reverse: elastic down to the reverse yield stress, then plastic
        rev_yield = smax - 2 * SY if kind == "kin" else -smax
        e_rev = 5 * EPS_Y - (smax - rev_yield) / E  # strain at reverse yield
        s2, _, _ = uniaxial_stress_path(params, np.concatenate([path, [e_rev + 1e-3 * EPS_Y, e_rev - EPS_Y]]))
        assert s2[2] == pytest.approx(rev_yield + 1e-3 * EPS_Y * E, rel=1e-9)  # still elastic
        assert s2[3] == pytest.approx(rev_yield - E * H / (E + H) * EPS_Y, rel=1e-9)


# ---------------------------------------------------------------------------------------------
# pure shear, plane strain
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("ns", [3, 6])
def test_pure_shear_yields_at_sigma_y_over_sqrt3(ns):
    """Pure shear (only gxy): elastic tau = G gamma up to tau = sigma_y / sqrt(3), then constant
    (perfect plasticity); all normal stresses stay zero."""
    params = von_mises_params(E, NU, SY)
    state = von_mises_initial_state(1)
    g_y = SY / math.sqrt(3) / G
    ixy = 2 if ns == 3 else 3
    for gam in np.linspace(0.1, 5.0, 30) * g_y:
        eps = np.zeros(ns)
        eps[ixy] = gam
        s, _, state = evaluate(eps, params, state)
        expected = min(G * gam, SY / math.sqrt(3))
        assert s[ixy] == pytest.approx(expected, rel=1e-12)
        assert np.max(np.abs(np.delete(s, ixy))) <= 1e-9 * SY
        assert np.max(np.abs(state[0, S_STRESS:S_STRESS + 3])) <= 1e-9 * SY


def test_plane_strain_out_of_plane_stress_and_incompressibility():
    """Plane strain: szz = nu (sxx + syy) while elastic; once plastic the plastic strain has zero
    trace (J2 flow is deviatoric) and the plane-strain result is the 3D result with ezz = 0."""
    params = von_mises_params(E, NU, SY, 0.03 * E, 0.02 * E)
    eps = np.array([0.3, -0.1, 0.2]) * EPS_Y
    s, _, t = evaluate(eps, params, von_mises_initial_state(1))
    assert t[0, S_CODE] == CODE_ELASTIC
    assert t[0, S_STRESS + 2] == pytest.approx(NU * (s[0] + s[1]), rel=1e-12)

    state2, state3 = von_mises_initial_state(1), von_mises_initial_state(1)
    for fac in np.linspace(0.5, 6.0, 12):
        eps = np.array([1.0, -0.6, 0.8]) * fac * EPS_Y
        s2, D2, state2 = evaluate(eps, params, state2)
        s3, D3, state3 = evaluate(np.array([eps[0], eps[1], 0.0, eps[2], 0.0, 0.0]), params, state3)
        idx = [0, 1, 3]
        assert np.allclose(s2, s3[idx], rtol=0, atol=1e-9 * SY)
        assert np.allclose(D2, D3[np.ix_(idx, idx)], rtol=0, atol=1e-9 * E)
        assert np.allclose(state2, state3, rtol=0, atol=1e-12 * SY)
    assert state2[0, S_CODE] == CODE_PLASTIC
    ep = state2[0, S_PLASTIC_STRAIN:S_PLASTIC_STRAIN + 6]
    assert np.max(np.abs(ep)) > EPS_Y
    assert abs(ep[0] + ep[1] + ep[2]) <= 1e-12 * np.max(np.abs(ep))
    assert ep[2] != 0.0  # the plastic flow has an out-of-plane part, kept in the state
    # szz from the state equals Hooke's law on the elastic strain (ezz = 0)
    ee = np.array([eps[0], eps[1], 0.0]) - ep[:3]
    assert state2[0, S_STRESS + 2] == pytest.approx(K * ee.sum() + 2 * G * (ee[2] - ee.sum() / 3), rel=1e-10)


# ---------------------------------------------------------------------------------------------
# consistent tangent
# ---------------------------------------------------------------------------------------------


def _loaded_state(params, ns, seed):
    """A committed state after two plastic steps along different directions (non-zero plastic
    strain, alpha and back stress) and the strain of a third, plastic, step."""
    rng = np.random.default_rng(seed)
    state = von_mises_initial_state(1)
    for _ in range(2):
        eps = rng.normal(size=ns) * 3 * EPS_Y
        _, _, state = evaluate(eps, params, state)
    eps = eps + rng.normal(size=ns) * 2 * EPS_Y
    return eps, state


@pytest.mark.parametrize("ns", [3, 6])
@pytest.mark.parametrize(
    "h_iso, h_kin, sy_res, eta, dt",
    [
        (0.0, 0.0, 0.0, 0.0, 0.0),
        (0.04 * E, 0.03 * E, 0.0, 0.0, 0.0),
        (-0.01 * E, 0.02 * E, 0.2 * SY, 0.0, 0.0),  # softening, before the residual
        (-0.2 * E, 0.0, 0.9 * SY, 0.0, 0.0),  # softening, past the residual (H = 0 active)
        (0.02 * E, 0.01 * E, 0.0, 0.5 * G, 1.0),  # Perzyna
    ],
    ids=["perfect", "hardening", "softening", "residual", "perzyna"],
)
def test_consistent_tangent_equals_finite_difference(ns, h_iso, h_kin, sy_res, eta, dt):
    """Consistent tangent vs. a central difference of the stress update on a plastic step
    (relative 1e-6 of max |D|; measured 3e-11 to 2e-10)."""
    params = von_mises_params(E, NU, SY, h_iso, h_kin, sy_res, eta)
    eps, state = _loaded_state(params, ns, seed=ns * 7 + int(1e3 * abs(h_iso) / E))
    _, D, trial = evaluate(eps, params, state, dt)
    assert trial[0, S_CODE] == CODE_PLASTIC
    if sy_res == 0.9 * SY:
        assert trial[0, S_EQ_PLASTIC_STRAIN] > (0.9 * SY - SY) / h_iso  # on the residual branch
    Dfd = fd_tangent(eps, params, state, dt)
    assert np.max(np.abs(D - Dfd)) <= 1e-6 * np.max(np.abs(D))
    assert np.allclose(D, D.T, rtol=0, atol=1e-9 * np.max(np.abs(D)))


def test_elastic_step_returns_elastic_matrix():
    from masonrydam.materials.elastic import elasticity_matrix

    params = von_mises_params(E, NU, SY)
    _, D3, _ = evaluate(np.array([1e-5, 2e-6, -3e-6, 1e-6, 0, 0]), params, von_mises_initial_state(1))
    assert np.allclose(D3, elasticity_matrix(E, NU, "3d"), rtol=1e-13, atol=0)
    _, D2, _ = evaluate(np.array([1e-5, 2e-6, 1e-6]), params, von_mises_initial_state(1))
    assert np.allclose(D2, elasticity_matrix(E, NU, "plane_strain"), rtol=1e-13, atol=0)


# ---------------------------------------------------------------------------------------------
# isotropy
# ---------------------------------------------------------------------------------------------


def test_rotating_the_strain_rotates_the_stress():
    """Isotropy: a rotated strain history (and therefore rotated plastic strain and back stress)
    gives the rotated stress: sigma(R eps R^T) = R sigma(eps) R^T (relative 1e-10)."""
    params = von_mises_params(E, NU, SY, 0.03 * E, 0.05 * E)
    R = rotation(3)
    rng = np.random.default_rng(11)
    st_a = von_mises_initial_state(1)
    st_b = von_mises_initial_state(1)
    for _ in range(4):
        eps = rng.normal(size=6) * 4 * EPS_Y
        eps_rot = strain_vector(R @ strain_tensor(eps) @ R.T)
        sa, Da, st_a = evaluate(eps, params, st_a)
        sb, Db, st_b = evaluate(eps_rot, params, st_b)
        assert np.allclose(stress_vector(R @ stress_tensor(sa) @ R.T), sb, rtol=0, atol=1e-10 * SY)
        back_a = st_a[0, S_BACK_STRESS:S_BACK_STRESS + 6]
        assert np.allclose(stress_vector(R @ stress_tensor(back_a) @ R.T), st_b[0, S_BACK_STRESS:S_BACK_STRESS + 6],
                           rtol=0, atol=1e-10 * SY)
        assert st_a[0, S_EQ_PLASTIC_STRAIN] == pytest.approx(st_b[0, S_EQ_PLASTIC_STRAIN], rel=1e-10)
    assert st_a[0, S_EQ_PLASTIC_STRAIN] > 0


# ---------------------------------------------------------------------------------------------
# Perzyna
# ---------------------------------------------------------------------------------------------


def _overstress(state, params):
    s = state[0, S_STRESS:S_STRESS + 6].copy()
    s[:3] -= s[:3].mean()
    xi = s - state[0, S_BACK_STRESS:S_BACK_STRESS + 6]
    q = math.sqrt(1.5 * (np.sum(xi[:3] ** 2) + 2 * np.sum(xi[3:] ** 2)))
    return q - (params[P_SIGMA_Y] + params[P_H_ISO] * state[0, S_EQ_PLASTIC_STRAIN])


def test_perzyna_relaxation_at_constant_strain():
    """Stress relaxation at constant strain. At fixed strain the direction n is fixed,
    d q / dt = -(3G + H_kin) gamma_dot and d sigma_y / dt = H_iso gamma_dot with gamma_dot = f / eta,
    so the overstress obeys df/dt = -(3G + H) f / eta, f = f0 exp(-(3G + H) t / eta)
    (Simo & Hughes sec. 2.7). Backward Euler gives f_k = f0 / (1 + dt (3G + H) / eta)^k exactly
    (relative 1e-9) and tends to the exponential as dt -> 0 (first order: relative error
    0.5 (dt/tau)^1 t/tau; checked 2e-3 at dt = tau/1000). A strain jump with dt = 0 is elastic, and
    the long-time limit is the rate-independent return."""
    h_iso, h_kin = 0.02 * E, 0.03 * E
    eta = 1.0e9  # Pa s
    params = von_mises_params(E, NU, SY, h_iso, h_kin, viscosity=eta)
    a = 3 * G + h_iso + h_kin
    tau = eta / a
    eps = np.array([3.0, -1.0, -0.5, 2.0, 0.7, -0.4]) * EPS_Y
    s0, _, state = evaluate(eps, params, von_mises_initial_state(1), dt=0.0)
    assert state[0, S_CODE] == CODE_ELASTIC  # instantaneous response is elastic
    f0 = _overstress(state, params)
    assert f0 > 0.5 * SY
    for n_steps, tol in ((1000, 2.5e-3), (10, None)):
        dt = 2 * tau / n_steps
        st = state.copy()
        t = 0.0
        for k in range(1, n_steps + 1):
            _, _, st = evaluate(eps, params, st, dt=dt)
            t += dt
            f = _overstress(st, params)
            assert f == pytest.approx(f0 / (1 + dt / tau) ** k, rel=1e-9)
        if tol is not None:
            assert f == pytest.approx(f0 * math.exp(-t / tau), rel=tol)
            assert abs(f / (f0 * math.exp(-t / tau)) - 1) > 1e-4  # first-order error is there
    # long time: the rate-independent return
    rate_indep = von_mises_params(E, NU, SY, h_iso, h_kin)
    s_ri, _, _ = evaluate(eps, rate_indep, von_mises_initial_state(1))
    st = state.copy()
    for _ in range(40):
        s_v, _, st = evaluate(eps, params, st, dt=2 * tau)
    assert np.allclose(s_v, s_ri, rtol=0, atol=1e-9 * SY)


def test_perzyna_tends_to_rate_independent():
    """One plastic step: the viscous stress differs from the rate-independent one in proportion to
    eta/dt (f_(n+1) = eta dgamma / dt) and tends to it as eta -> 0."""
    eps = np.array([4.0, -1.0, 0.5, 2.0, 0.0, 1.0]) * EPS_Y
    s_ri, D_ri, _ = evaluate(eps, von_mises_params(E, NU, SY, 0.05 * E), von_mises_initial_state(1))
    diffs = []
    for eta in (1e7, 1e5, 1e3, 1e1):
        s_v, D_v, _ = evaluate(eps, von_mises_params(E, NU, SY, 0.05 * E, viscosity=eta), von_mises_initial_state(1),
                               dt=1.0)
        diffs.append(np.max(np.abs(s_v - s_ri)))
        assert np.max(np.abs(D_v - D_ri)) <= 10 * eta / (3 * G) * np.max(np.abs(D_ri))
    assert diffs[-1] <= 1e-8 * SY
    for d1, d2 in zip(diffs, diffs[1:]):
        assert d2 == pytest.approx(d1 / 100, rel=1e-2)  # linear in eta


# ---------------------------------------------------------------------------------------------
# errors, protocol
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(yield_stress=0.0), "yield_stress"),
        (dict(yield_stress=-1.0), "yield_stress"),
        (dict(viscosity=-1.0), "viscosity"),
        (dict(isotropic_hardening=-3 * G), "isotropic_hardening"),
        (dict(isotropic_hardening=-4 * G, kinematic_hardening=0.5 * G), "isotropic_hardening"),
        (dict(kinematic_hardening=-1.0), "kinematic_hardening"),
        (dict(residual_yield_stress=2 * SY), "residual_yield_stress"),
        (dict(residual_yield_stress=-1.0), "residual_yield_stress"),
        (dict(poisson_ratio=0.5), "poisson_ratio"),
        (dict(youngs_modulus=0.0), "youngs_modulus"),
        (dict(yield_stress=float("nan")), "yield_stress"),
        (dict(yield_stress="x"), "yield_stress"),
    ],
)
def test_bad_parameters_raise_named_errors(kwargs, name):
    args = dict(youngs_modulus=E, poisson_ratio=NU, yield_stress=SY)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        von_mises_params(**args)


def test_bad_table_dt_and_shapes_raise():
    params = von_mises_params(E, NU, SY)
    bad = np.tile(params, (3, 1))
    bad[2, P_VISCOSITY] = -5.0
    with pytest.raises(ValueError, match=r"viscosity.*row 2"):
        von_mises_evaluate(np.zeros((3, 6)), bad, von_mises_initial_state(3))
    with pytest.raises(ValueError, match="dt"):
        von_mises_evaluate(np.zeros((1, 6)), params, von_mises_initial_state(1), dt=-1.0)
    with pytest.raises(ValueError, match="components"):
        von_mises_evaluate(np.zeros((1, 4)), params, von_mises_initial_state(1))
    with pytest.raises(ValueError, match="state_committed"):
        von_mises_evaluate(np.zeros((2, 6)), params, von_mises_initial_state(1))


def test_kernel_status_for_nan_and_bad_material():
    """The kernel never raises: a NaN strain gives STATUS_NAN with the point in info[0], its trial
    state = committed, NaN stress and a zero tangent; a bad parameter bypassing the wrapper gives
    STATUS_BAD_MATERIAL with the column in info[1]. The wrapper raises NumericalError."""
    params = np.tile(von_mises_params(E, NU, SY), (3, 1))
    committed = von_mises_initial_state(3)
    committed[:, S_EQ_PLASTIC_STRAIN] = 0.01
    strain = np.full((3, 3), 1e-5)
    strain[1, 2] = np.nan
    trial = np.full((3, N_VM_STATE), -7.0)
    stress = np.zeros((3, 3))
    tangent = np.ones((3, 3, 3))
    info = np.zeros(2, dtype=np.int64)
    status = von_mises_update(strain, params, committed, trial, stress, tangent, 0.0, True, info)
    assert status == STATUS_NAN and info[0] == 1
    assert np.array_equal(trial[1], committed[1])
    assert np.all(np.isnan(stress[1])) and np.all(tangent[1] == 0.0)
    with pytest.raises(NumericalError, match="point 1"):
        von_mises_evaluate(strain, params, committed)

    strain[1, 2] = 1e-5
    params[2, P_SIGMA_Y] = -1.0
    info[:] = 0
    status = von_mises_update(strain, params, committed, trial, stress, tangent, 0.0, True, info)
    assert status == STATUS_BAD_MATERIAL and info[0] == 2 and info[1] == P_SIGMA_Y
    params[2, P_SIGMA_Y] = SY
    status = von_mises_update(strain, params, committed, trial, stress, tangent, -1.0, True, info)
    assert status == STATUS_BAD_MATERIAL and info[1] == -1
    status = von_mises_update(strain, params, committed, trial, stress, tangent, 0.0, True, info)
    assert status == STATUS_OK


def test_batch_without_tangent_and_layout():
    """A batch mixes plane-strain points in one call; want_tangent=False leaves out the tangent and
    gives the same stresses and states."""
    params = von_mises_params(E, NU, SY, 0.01 * E)
    assert params.shape == (N_VM_PARAMS,)
    strain = np.array([[0.1, 0.0, 0.0], [3.0, -1.0, 2.0], [-4.0, 1.0, 0.0]]) * EPS_Y
    st = von_mises_initial_state(3)
    s1, D1, t1 = von_mises_evaluate(strain, params, st)
    s2, D2, t2 = von_mises_evaluate(strain, params, st, want_tangent=False)
    assert D2 is None and D1.shape == (3, 3, 3)
    assert np.array_equal(s1, s2) and np.array_equal(t1, t2)
    assert list(t1[:, S_CODE]) == [CODE_ELASTIC, CODE_PLASTIC, CODE_PLASTIC]
