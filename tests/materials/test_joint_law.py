"""Tests of the Mohr-Coulomb joint law (masonrydam.materials.mohr_coulomb).

Sources: Tzamtzis & Asteris, sec. 3.4: diagonal joint stiffness (eq. 11), Mohr-Coulomb
strength tau_y = c + sigma_n tan(phi) (eq. 12), reduced/residual shear stiffness while slipping,
separation with both stiffnesses zero until contact is restored; return mapping and consistent
tangent after Simo & Hughes (1998), Computational Inelasticity, ch. 2-3; sign conventions from
docs/architecture.md (opening and tension positive).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from masonrydam.errors import STATUS_NAN, STATUS_OK
from masonrydam.materials.mohr_coulomb import (
    N_JOINT_PARAMS,
    N_JOINT_STATE,
    OPEN,
    P_COHESION,
    P_KN,
    P_KS,
    P_KS_RESIDUAL,
    P_TAN_PHI,
    P_TENSILE_STRENGTH,
    S_BACK_STRESS,
    S_BOND_BROKEN,
    S_CODE,
    S_PLASTIC_SLIP,
    SLIP,
    STICK,
    joint_params,
    mohr_coulomb_update,
)

KN = 2.0e10  # Pa/m
KS = 8.0e9  # Pa/m
C = 2.0e5  # Pa
PHI = 35.0  # deg
TAN_PHI = math.tan(math.radians(PHI))


def update(params, delta, committed=None):
    """Evaluate the law; returns (status, traction, tangent, trial state) and checks that the
    committed state is left untouched (trial/commit/revert protocol, docs/architecture.md)."""
    delta = np.asarray(delta, dtype=np.float64)
    n = delta.shape[0]
    committed = np.zeros(N_JOINT_STATE) if committed is None else np.asarray(committed, dtype=np.float64)
    before = committed.copy()
    trial = np.full(N_JOINT_STATE, -99.0)
    t = np.full(n, -99.0)
    C_ = np.full((n, n), -99.0)
    status = mohr_coulomb_update(params, delta, committed, trial, t, C_)
    assert np.array_equal(committed, before), "kernel modified state_committed"
    return status, t, C_, trial


def fd_tangent(params, delta, committed, h):
    delta = np.asarray(delta, dtype=np.float64)
    n = delta.shape[0]
    D = np.zeros((n, n))
    for j in range(n):
        dp = delta.copy()
        dm = delta.copy()
        dp[j] += h
        dm[j] -= h
        _, tp, _, _ = update(params, dp, committed)
        _, tm, _, _ = update(params, dm, committed)
        D[:, j] = (tp - tm) / (2 * h)
    return D


def slipped_state(ns, slip, back):
    s = np.zeros(N_JOINT_STATE)
    s[S_CODE] = SLIP
    s[S_PLASTIC_SLIP : S_PLASTIC_SLIP + ns] = slip
    s[S_BACK_STRESS : S_BACK_STRESS + ns] = back
    return s


# ------------------------------------------------------------------ parameters


def test_joint_params_layout():
    p = joint_params(KN, KS, C, PHI, 1e5, 1e8)
    assert p.shape == (N_JOINT_PARAMS,) and p.dtype == np.float64
    assert p[P_KN] == KN and p[P_KS] == KS and p[P_COHESION] == C
    assert p[P_TAN_PHI] == pytest.approx(TAN_PHI)
    assert p[P_TENSILE_STRENGTH] == 1e5 and p[P_KS_RESIDUAL] == 1e8


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(normal_stiffness=0.0), "normal_stiffness"),
        (dict(shear_stiffness=-1.0), "shear_stiffness"),
        (dict(cohesion=-1.0), "cohesion"),
        (dict(friction_angle_deg=90.0), "friction_angle_deg"),
        (dict(friction_angle_deg=-1.0), "friction_angle_deg"),
        (dict(tensile_strength=-5.0), "tensile_strength"),
        (dict(residual_shear_stiffness=KS), "residual_shear_stiffness"),
        (dict(residual_shear_stiffness=-1.0), "residual_shear_stiffness"),
        (dict(cohesion=float("nan")), "cohesion"),
    ],
)
def test_joint_params_validation(kwargs, name):
    args = dict(normal_stiffness=KN, shear_stiffness=KS)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        joint_params(**args)


# ------------------------------------------------------------------ consistent tangent vs finite differences


@pytest.mark.parametrize("ncomp", [2, 3])
def test_tangent_stick(ncomp):
    p = joint_params(KN, KS, C, PHI, 0.0, 1e9)
    delta = np.array([1e-6, -2e-6, -1e-5])[-ncomp:]
    st, t, D, trial = update(p, delta)
    assert st == STATUS_OK and trial[S_CODE] == STICK
    np.testing.assert_allclose(D, np.diag([KS] * (ncomp - 1) + [KN]))
    np.testing.assert_allclose(t, D @ delta)
    np.testing.assert_allclose(D, fd_tangent(p, delta, None, 1e-9), rtol=1e-6, atol=1e-6 * KN)


@pytest.mark.parametrize("ks_r", [0.0, 2.0e9])
@pytest.mark.parametrize("ncomp", [2, 3])
def test_tangent_slip(ncomp, ks_r):
    """Slip with friction (d_n coupling), committed plastic slip and back stress; 3D with an oblique
    slip direction, so the (I - m m^T) term of the consistent tangent is exercised."""
    p = joint_params(KN, KS, C, PHI, 0.0, ks_r)
    ns = ncomp - 1
    if ncomp == 3:
        delta = np.array([3.0e-4, -1.7e-4, -2.0e-5])
        committed = slipped_state(2, [4e-5, 1e-5], [1e4, -3e4] if ks_r else [0, 0])
    else:
        delta = np.array([3.0e-4, -2.0e-5])
        committed = slipped_state(1, [4e-5], [1e4] if ks_r else [0])
    st, t, D, trial = update(p, delta, committed)
    assert st == STATUS_OK and trial[S_CODE] == SLIP
    # on the yield surface after the return: |tau - alpha| = tau_y
    tau_y = C - t[-1] * TAN_PHI
    alpha = trial[S_BACK_STRESS : S_BACK_STRESS + ns]
    assert np.linalg.norm(t[:ns] - alpha) == pytest.approx(tau_y, rel=1e-12)
    Dfd = fd_tangent(p, delta, committed, 1e-10)
    np.testing.assert_allclose(D, Dfd, rtol=1e-5, atol=1e-6 * KS)
    # d_n coupling present and the tangent is non-symmetric (non-associated)
    assert np.all(D[:ns, ns] != 0.0)
    assert abs(D[0, ns]) > 1e-3 * KN
    assert D[ns, 0] == 0.0
    if ncomp == 3:
        assert abs(D[0, 1]) > 1e-3 * KS  # off-diagonal shear coupling for an oblique direction


def test_tangent_slip_tension_clamped():
    """Bonded tension so large that tau_y is clamped to 0: no d_n coupling (tau_y does not vary)."""
    p = joint_params(KN, KS, 1e4, PHI, 2e6, 0.0)
    delta = np.array([1e-4, 5e-5])  # t_n = 1 MPa < ft, c - t_n tan(phi) < 0
    st, t, D, trial = update(p, delta)
    assert trial[S_CODE] == SLIP and t[0] == 0.0 and t[1] == pytest.approx(KN * 5e-5)
    assert D[0, 1] == 0.0
    np.testing.assert_allclose(D, fd_tangent(p, delta, None, 1e-10), atol=1e-6 * KS)


@pytest.mark.parametrize("ncomp", [2, 3])
def test_tangent_open(ncomp):
    p = joint_params(KN, KS, C, PHI, 1e5, 1e9)
    delta = np.array([2e-4, 1e-4, 1e-4])[-ncomp:]
    st, t, D, trial = update(p, delta)
    assert st == STATUS_OK and trial[S_CODE] == OPEN
    assert np.all(t == 0.0) and np.all(D == 0.0)
    np.testing.assert_array_equal(fd_tangent(p, delta, None, 1e-9), 0.0)


# ------------------------------------------------------------------ direct shear test (Tzamtzis & Asteris eq. 12)


def direct_shear(p, sigma, path, ncomp=2):
    """Constant normal compression sigma (Pa), shear displacement path; commit every step.
    Returns the shear tractions and the states."""
    d_n = -sigma / p[P_KN]
    committed = np.zeros(N_JOINT_STATE)
    taus, codes = [], []
    for ds in path:
        delta = np.zeros(ncomp)
        delta[0] = ds
        delta[-1] = d_n
        st, t, D, trial = update(p, delta, committed)
        assert st == STATUS_OK
        assert t[-1] == pytest.approx(-sigma)
        taus.append(t[0])
        codes.append(trial[S_CODE])
        committed = trial.copy()  # commit
    return np.array(taus), np.array(codes), committed


@pytest.mark.parametrize("ncomp", [2, 3])
def test_direct_shear_perfectly_plastic(ncomp):
    sigma = 0.5e6
    p = joint_params(KN, KS, C, PHI)
    tau_y = C + sigma * TAN_PHI  # Tzamtzis & Asteris eq. 12
    up = np.linspace(0, 4 * tau_y / KS, 41)[1:]
    taus, codes, _ = direct_shear(p, sigma, up, ncomp)
    assert taus.max() == pytest.approx(tau_y, rel=1e-12)
    plastic = codes == SLIP
    assert plastic.sum() > 20
    np.testing.assert_allclose(taus[plastic], tau_y, rtol=1e-12)  # flat
    elastic = ~plastic
    np.testing.assert_allclose(taus[elastic], KS * up[elastic], rtol=1e-12)


def test_direct_shear_residual_stiffness_unloading_reversal():
    sigma = 0.3e6
    ks_r = 0.1 * KS
    p = joint_params(KN, KS, C, PHI, 0.0, ks_r)
    tau_y = C + sigma * TAN_PHI
    d_y = tau_y / KS
    d_max = 3 * d_y
    up = np.linspace(0, d_max, 31)[1:]
    unload = np.linspace(d_max, -3 * d_y, 61)[1:]
    path = np.concatenate([up, unload])
    taus, codes, committed = direct_shear(p, sigma, path)

    # loading: elastic up to the peak tau_y, then incremental stiffness ks_r
    n_up = len(up)
    tau_up, code_up = taus[:n_up], codes[:n_up]
    first_slip = np.argmax(code_up == SLIP)
    assert np.all(tau_up[:first_slip] <= tau_y * (1 + 1e-12))
    slope = np.diff(tau_up[first_slip:]) / np.diff(up[first_slip:])
    np.testing.assert_allclose(slope, ks_r, rtol=1e-9)
    np.testing.assert_allclose(tau_up[first_slip:], tau_y + ks_r * (up[first_slip:] - d_y), rtol=1e-9)

    # unloading: elastic with ks until the reverse yield tau - alpha = -tau_y
    tau_dn, code_dn = taus[n_up:], codes[n_up:]
    tau_peak = tau_up[-1]
    alpha = tau_peak - tau_y  # back stress at the end of loading
    elastic = code_dn == STICK
    np.testing.assert_allclose(tau_dn[elastic], tau_peak - KS * (d_max - unload[elastic]), rtol=1e-9, atol=1.0)
    assert np.any(code_dn == SLIP)
    rev = np.argmax(code_dn == SLIP)
    # reversal: yields at tau = alpha - tau_y, then continues with slope ks_r
    tau_rev_yield = alpha - tau_y
    d_rev = d_max - (tau_peak - tau_rev_yield) / KS
    np.testing.assert_allclose(
        tau_dn[rev:], tau_rev_yield + ks_r * (unload[rev:] - d_rev), rtol=1e-9
    )
    assert tau_dn[-1] < 0


def test_direct_shear_reversal_perfectly_plastic():
    sigma = 0.3e6
    p = joint_params(KN, KS, 0.0, PHI)
    tau_y = sigma * TAN_PHI
    d_y = tau_y / KS
    path = np.concatenate([np.linspace(0, 3 * d_y, 13)[1:], np.linspace(3 * d_y, -3 * d_y, 25)[1:]])
    taus, codes, committed = direct_shear(p, sigma, path)
    assert taus.max() == pytest.approx(tau_y, rel=1e-12)
    assert taus.min() == pytest.approx(-tau_y, rel=1e-12)
    # residual slip of -3 d_y + d_y at the end (elastic part tau_y / ks recoverable)
    assert committed[S_PLASTIC_SLIP] == pytest.approx(-3 * d_y + d_y, rel=1e-9)


# ------------------------------------------------------------------ tension, bond, re-closure


def test_no_tension_joint_opens_at_zero_plus():
    p = joint_params(KN, KS, C, PHI, 0.0)
    st, t, D, trial = update(p, [1e-5, 1e-15])
    assert st == STATUS_OK and trial[S_CODE] == OPEN and trial[S_BOND_BROKEN] == 1.0
    assert np.all(t == 0.0) and np.all(D == 0.0)
    # exactly closed (d_n = 0) is contact, not separation
    st, t, D, trial = update(p, [1e-6, 0.0])
    assert trial[S_CODE] == STICK and t[1] == 0.0 and t[0] == pytest.approx(KS * 1e-6)


def test_tensile_strength_and_bond_breaking():
    ft = 1.5e5
    p = joint_params(KN, KS, C, PHI, ft)
    d_ft = ft / KN
    # below ft: bonded, carries tension with stiffness kn
    st, t, D, trial = update(p, [0.0, 0.9 * d_ft])
    assert trial[S_CODE] == STICK and trial[S_BOND_BROKEN] == 0.0
    assert t[1] == pytest.approx(0.9 * ft) and D[1, 1] == KN
    # beyond ft: exactly zero traction, bond broken
    st, t, D, trial = update(p, [2e-6, 1.01 * d_ft])
    assert trial[S_CODE] == OPEN and trial[S_BOND_BROKEN] == 1.0
    assert np.all(t == 0.0) and np.all(D == 0.0)
    committed = trial.copy()
    # a crack has no tensile strength any more: a small opening (< ft/kn) stays open
    st, t, D, trial = update(p, [2e-6, 0.5 * d_ft], committed)
    assert trial[S_CODE] == OPEN and np.all(t == 0.0)
    # and no cohesion: under compression sigma the strength is sigma tan(phi) only
    sigma = 1e5
    st, t, D, trial = update(p, [2e-6 + 1e-3, -sigma / KN], committed)
    assert trial[S_CODE] == SLIP
    assert abs(t[0]) == pytest.approx(sigma * TAN_PHI, rel=1e-12)
    # intact joint at the same point would have had c + sigma tan(phi)
    st, t, D, trial = update(p, [1e-3, -sigma / KN])
    assert abs(t[0]) == pytest.approx(C + sigma * TAN_PHI, rel=1e-12)


@pytest.mark.parametrize("ncomp", [2, 3])
def test_reclosure_restores_contact_shear_free(ncomp):
    """After separation, contact returns when d_n <= 0 and the shear starts from zero at the
    shear position where the joint was (last committed) open."""
    p = joint_params(KN, KS, C, PHI, 0.0, 1e9)
    ns = ncomp - 1
    # stick, then commit an open state at a shifted tangential position
    committed = np.zeros(N_JOINT_STATE)
    d_open = np.array([3e-4, -1e-4, 2e-5]) if ncomp == 3 else np.array([3e-4, 2e-5])
    st, t, D, trial = update(p, d_open, committed)
    assert trial[S_CODE] == OPEN
    np.testing.assert_allclose(trial[S_PLASTIC_SLIP : S_PLASTIC_SLIP + ns], d_open[:ns])
    assert np.all(trial[S_BACK_STRESS : S_BACK_STRESS + 2] == 0.0)
    committed = trial.copy()
    # close at the same tangential position: no shear, compression carried
    d_close = d_open.copy()
    d_close[-1] = -1e-6
    st, t, D, trial = update(p, d_close, committed)
    assert trial[S_CODE] == STICK
    np.testing.assert_allclose(t[:ns], 0.0, atol=1e-9)
    assert t[-1] == pytest.approx(-KN * 1e-6)
    np.testing.assert_allclose(D, np.diag([KS] * ns + [KN]))
    # a small further shear is elastic from the new position
    d_close[0] += 1e-7
    st, t, D, trial = update(p, d_close, committed)
    assert t[0] == pytest.approx(KS * 1e-7, rel=1e-9)


def test_state_committed_never_modified_and_trial_is_copy():
    p = joint_params(KN, KS, C, PHI, 1e5, 1e9)
    committed = slipped_state(1, [1e-5], [2e3])
    for delta in ([1e-6, -1e-6], [1e-3, -1e-5], [1e-3, 1e-3]):
        update(p, delta, committed)  # asserts committed is unchanged
    # a stick evaluation reproduces the committed internal variables in the trial state
    st, t, D, trial = update(p, [1e-5 + 1e-7, -1e-6], committed)
    assert trial[S_CODE] == STICK
    np.testing.assert_array_equal(trial[1:], committed[1:])


def test_nan_input_gives_status():
    p = joint_params(KN, KS, C, PHI)
    st, t, D, trial = update(p, [np.nan, -1e-6])
    assert st == STATUS_NAN
    bad = p.copy()
    bad[P_KS] = np.inf
    st, *_ = update(bad, [1e-6, -1e-6])
    assert st == STATUS_NAN
