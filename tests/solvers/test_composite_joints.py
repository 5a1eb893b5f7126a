"""Composite (masonry) joints in scenes: ``[joints.<set>] law = "composite"`` (the
Lourenco-Rots interface law of masonrydam/materials/composite/, tested at point level in
tests/materials/test_composite_interface.py) in the interface elements, and the snap-back a softening joint
gives in series with a long elastic bar, followed by indirect displacement control.

Closed forms (a bar of length L, modulus E, area A, pulled across one joint of normal stiffness kn,
tensile strength ft and mode-I fracture energy GfI; Lourenco 1996, ch. 4, exponential softening):
- the joint's softening: t = ft exp(-(ft / GfI) w_p), w_p the plastic opening, w = w_p + t / kn;
- the pulled end: u(sigma) = sigma L / E + sigma / kn - (GfI / ft) ln(sigma / ft) on the softening branch;
  it snaps back (du/dsigma > 0 at the peak) when L > E (GfI / ft^2 - 1 / kn) (Crisfield 1991, sec. 9.1;
  Bazant & Cedolin, Stability of Structures, 1991, ch. 12).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import SceneError

E, KN, FT, GF = 10e9, 1e11, 0.25e6, 18.0


def bar(L, u, steps=20, control="load", width=0.1, joint=None, duration=None):
    spec = {"law": "composite", "normal_stiffness": KN, "shear_stiffness": KN / 2, "tensile_strength": FT,
            "mode_I_fracture_energy": GF, "cohesion": 0.35e6, "friction_angle": 36.87, "mode_II_fracture_energy": 125.0}
    spec.update(joint or {})
    return {"model": {"name": "bar", "thickness": 1.0, "gravity": [0.0, 0.0]},
            "mesh": {"generator": "blocks_2d", "parameters": {"element_size": width, "blocks": [
                {"x0": 0, "y0": 0, "x1": width, "y1": L, "group": "a"},
                {"x0": 0, "y0": L, "x1": width, "y1": L + width, "group": "b"}]}},
            "materials": {g: {"youngs_modulus": E, "poisson_ratio": 0.0, "density": 0.0} for g in ("a", "b")},
            "joints": {"joints": spec},
            "supports": [{"set": "base", "components": ["x", "y"]}, {"set": "top", "components": ["x"]}],
            "stages": [{"name": "pull", "steps": steps, "control": control, "loads": [
                {"type": "displacement", "set": "top", "components": ["y"], "value": [u]}],
                **({} if duration is None else {"duration": duration})}]}


def end_curve(ds, top_y, width):
    top = ds.y.values > top_y - 1e-9
    sigma = ds.reaction.sel(component="y").values[:, top].sum(axis=1) / width
    u = ds.displacement.sel(component="y").values[:, top].mean(axis=1)
    return u, sigma


@pytest.mark.slow
def test_tension_softening_through_the_joint():
    ds = masonrydam.run(bar(0.1, 5e-4, steps=400))
    u, sigma = end_curve(ds, 0.2, 0.1)
    w = ds.joint_opening.values.mean(axis=1)
    soft = (sigma < 0.99 * FT) & (np.arange(len(u)) > np.argmax(sigma))
    assert soft.sum() > 20 and sigma.max() == pytest.approx(FT, rel=0.05)
    np.testing.assert_allclose(sigma[soft], FT * np.exp(-FT / GF * (w[soft] - sigma[soft] / KN)), rtol=1e-6)
    # the work done on the bar: GfI per unit area of joint (and no elastic energy left at the end)
    work = np.trapezoid(sigma, u) * 0.1
    assert sigma[-1] < 0.01 * FT and work == pytest.approx(GF * 0.1, rel=0.03)
    assert "composite masonry joints" in ds.attrs["simulated_effects"]


@pytest.mark.parametrize("control", ["opening", pytest.param("load", marks=pytest.mark.slow)])
def test_snap_back_followed_by_indirect_displacement_control(control):
    """L = 10 m, four times the snap-back length E (GfI / ft^2 - 1/kn) = 2.8 m: under displacement control
    the end would have to move back after the peak. ``control = "opening"`` follows it from the start;
    the default control stalls at the peak and switches (the global arc fails there, the joints' opening
    does not)."""
    L, width = 10.0, 0.5
    ds = masonrydam.run(bar(L, 1.2e-3, control=control, width=width))
    u, sigma = end_curve(ds, L + width, width)
    k = int(np.argmax(sigma))
    post = np.arange(len(u)) > k
    assert post.sum() >= 5
    assert u[post].min() < u[k] - 5e-5  # the end moved back: a snap-back, traced
    Lt = L + width  # (both blocks stretch)
    closed = sigma[post] * Lt / E + sigma[post] / KN - (GF / FT) * np.log(sigma[post] / FT)
    np.testing.assert_allclose(u[post], closed, rtol=0, atol=1e-9)
    assert u[-1] == pytest.approx(1.2e-3, rel=1e-9)  # the stage reached its end
    assert ds.attrs["arc_length_steps"] > 0
    if control == "load":
        assert ds.attrs["arc_length_switches"] == 1


@pytest.mark.slow
def test_viscous_regularisation_converges_to_the_inviscid_softening_curve():
    """Duvaut-Lions relaxation (``relaxation_time``; Simo & Hughes 1998 sec. 2.7): pulled at a finite rate the
    joint carries an overstress above ft at the peak, and the softening branch departs from the inviscid closed
    form ``t = ft exp(-(ft/GfI) w_p)`` by an amount of order tau / dt: ten times smaller tau, about ten times
    smaller departure."""
    errors, peaks = [], []
    for tau in (1e-3, 1e-4):
        ds = masonrydam.run(bar(0.1, 5e-4, steps=200, duration=1.0, joint={"relaxation_time": tau}))
        u, sigma = end_curve(ds, 0.2, 0.1)
        w = ds.joint_opening.values.mean(axis=1)
        soft = (sigma < 0.9 * FT) & (np.arange(len(u)) > np.argmax(sigma)) & (sigma > 0.05 * FT)
        assert soft.sum() > 20
        closed = FT * np.exp(-FT / GF * (w[soft] - sigma[soft] / KN))
        errors.append(np.abs(sigma[soft] - closed).max() / FT)
        peaks.append(sigma.max() / FT)
        assert ds.attrs["completed"] == "true"
    assert peaks[0] > peaks[1] > 1.0
    assert errors[1] == pytest.approx(0.1 * errors[0], rel=0.3) and errors[1] < 0.03  # first order in tau
    with pytest.raises(SceneError) as err:  # a relaxation time needs the stage's time
        masonrydam.run(bar(0.1, 5e-4, joint={"relaxation_time": 1e-3}))
    assert err.value.key == "stages[0].duration"
    with pytest.raises(SceneError) as err:
        masonrydam.run(bar(0.1, 5e-4, duration=1.0, joint={"relaxation_time": "1 hour"}))
    assert err.value.key == "joints.joints.relaxation_time"


def test_result_states_of_composite_points():
    """``joint_state`` (and what uplift, stability and mechanism checks count): the composite codes elastic,
    shear, tension, cap, tension-shear, shear-cap are stick, slip, open, crush, open, crush; a relaxation time
    of 0 is the inviscid law."""
    from masonrydam.scene import build_mesh, build_model
    from masonrydam.scene.scene import Scene

    sc = Scene(bar(0.1, 1e-4, joint={"relaxation_time": 0}))
    g = build_model(sc.normalized, build_mesh(sc.normalized, sc.base_dir)).igroups[0]
    assert g.relaxation_time == 0.0
    codes = np.resize(np.arange(6.0), g.state_committed.shape[:2])
    g.state_committed[:, :, 0] = codes
    g.state_trial[:, :, 0] = codes[::-1, ::-1] if codes.ndim == 2 else codes
    np.testing.assert_array_equal(g.result_states(), np.array([0, 1, 2, 3, 2, 3])[codes.astype(int)])
    np.testing.assert_array_equal(g.result_states(trial=True), np.array([0, 1, 2, 3, 2, 3])[g.state_trial[:, :, 0].astype(int)])


def test_bad_composite_joints():
    for joint, key in (({"mode_I_fracture_energy": -1.0}, "joints.joints"),
                       ({"mode_I_fracture_energy": 0.1}, "joints.joints"),  # below ft^2 / kn = 0.625 N/m
                       ({"compressive_strength": 0.1e6}, "joints.joints"),  # a cap below the tensile strength
                       ({"residual_shear_stiffness": 1e9}, "joints.joints.residual_shear_stiffness")):
        with pytest.raises(SceneError) as err:
            masonrydam.run(bar(0.1, 1e-4, joint=joint))
        assert err.value.key == key, joint
    with pytest.raises(SceneError) as err:
        s = bar(0.1, 1e-4)
        s["joints"]["joints"]["mode_I_fracture_energy"] = 0.1
        masonrydam.run(s)
    assert "snap back" in str(err.value)
    s = bar(0.1, 1e-4)
    s["joints"]["joints"] = {"law": "mohr_coulomb", "normal_stiffness": KN, "shear_stiffness": KN, "friction_angle": 30,
                             "mode_I_fracture_energy": 10.0}
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "joints.joints.mode_I_fracture_energy"
    s = bar(0.1, 1e-4)
    s["stages"].append({"name": "shake", "type": "dynamic", "dt": 0.01, "steps": 2,
                        "ground_motion": {"x": {"values": [0.0, 1.0, 0.0], "dt": 0.01}}})
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "joints.joints.law" and "static" in str(err.value)
    s = bar(0.1, 1e-4, control="sideways")
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[0].control"


@pytest.mark.parametrize("first_r, predictor", [(1.0, 0.0), ("default", "default")])
def test_a_snap_back_relaxed_lands_on_the_far_branch_at_the_same_end_displacement(monkeypatch, first_r, predictor):
    """``limit_point = "relax"`` (masonrydam/solvers/static/relaxation.py): the bar of the test above pulled under
    displacement control, L = 10 m, four times its snap-back length. At the peak no equilibrium lies near the path;
    held there, the joint relaxes (Duvaut-Lions flow at fixed end displacement) until its traction meets the
    softening curve again: the far root of u(sigma) = u_peak on the softening branch, below the branch's turning
    point sigma* = GfI / (ft (L/E + 1/kn)), where du/dsigma = 0 (closed form in the module docstring). From there the
    pull goes on along the closed form. The hold's schedule (its first pseudo-time step ``R_FIRST``, the start of
    each hold step ``HOLD_PREDICTOR``) changes the way there, not this end state: both the defaults and the plain
    schedule (from r = 1, each step from the last relaxed state) land on the far root."""
    from scipy.optimize import brentq

    from masonrydam.solvers.static import relaxation

    if first_r != "default":
        monkeypatch.setattr(relaxation, "R_FIRST", first_r)
        monkeypatch.setattr(relaxation, "HOLD_PREDICTOR", predictor)

    L, width, u_end = 10.0, 0.5, 1.2e-3
    scene = bar(L, u_end, width=width)
    scene["stages"][0]["limit_point"] = "relax"
    ds = masonrydam.run(scene)
    u, sigma = end_curve(ds, L + width, width)
    Lt = L + width  # (both blocks stretch)

    def u_branch(s):
        return s * Lt / E + s / KN - (GF / FT) * np.log(s / FT)

    k = int(np.argmax(sigma))
    # the last state before the snap: elastic, within the last nominal step below the strength
    assert u[k] == pytest.approx(sigma[k] * (Lt / E + 1 / KN), rel=1e-9) and 0.95 * FT < sigma[k] <= FT
    s_turn = GF / (FT * (Lt / E + 1 / KN))
    s_far = brentq(lambda s: u_branch(s) - u[k + 1], 1e-3 * FT, s_turn)
    # the snap: the force drops over one step, a nominal one (of 20) cut RELAX_AFTER_CUTS = 2 times at most
    assert 0 < u[k + 1] - u[k] <= u_end / 20 / 2 ** relaxation.RELAX_AFTER_CUTS * (1 + 1e-9)
    assert sigma[k + 1] == pytest.approx(s_far, rel=1e-6)
    post = np.arange(len(u)) > k
    np.testing.assert_allclose(u[post], u_branch(sigma[post]), rtol=0, atol=1e-9)
    assert u[-1] == pytest.approx(u_end, rel=1e-9) and ds.attrs["completed"] == "true"
    assert ds.attrs["arc_length_switches"] == 0
    # after the hold the pull goes on with a step as long as the held one, and the steps grow back to the nominal
    steps = np.diff(u)
    assert steps[k + 1] == pytest.approx(steps[k], rel=1e-6)
    assert steps[k + 1:].max() == pytest.approx(u_end / 20, rel=1e-6)
    # the run says where it relaxed: one limit point, at the step after the last elastic one
    (lf, holds), = json.loads(ds.attrs["per_stage"])[0]["relaxed_limit_points"]
    assert holds > 0 and lf * u_end == pytest.approx(u[k + 1], rel=1e-9)


def test_limit_point_relax_is_for_load_control():
    scene = bar(1.0, 1e-4, control="opening")
    scene["stages"][0]["limit_point"] = "relax"
    with pytest.raises(SceneError, match=r'stages\[0\]\.limit_point.*control "load"'):
        masonrydam.run(scene)
