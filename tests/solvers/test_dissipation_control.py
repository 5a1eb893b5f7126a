"""Dissipation-based path following (``control = "dissipation"``): every step dissipates a
chosen energy in the joints (Gutierrez 2004, Commun. Numer. Meth. Eng. 20:19-29; Verhoosel, Remmers &
Gutierrez 2009, Int. J. Numer. Meth. Eng. 77:1290-1321), the joints' plastic work measured point by point
(masonrydam/solvers/static/dissipation.py).

Closed forms:
- a joint's plastic work: its traction on the plastic relative displacement ``p = delta - C_e t``; an
  elastic step (unloading) dissipates nothing;
- a bar pulled across one softening joint (tests/test_composite_joints.py): on the softening branch the
  pulled end is at ``u(sigma) = sigma L / E + sigma / kn - (GfI / ft) ln(sigma / ft)``, a snap-back for
  L = 10 m; once the crack is open the joint has dissipated its fracture energy, ``GfI A`` (Lourenco 1996,
  ch. 4: exponential softening, ``int t dw_p = GfI``).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import ConvergenceError, SceneError
from masonrydam.scene import build_mesh, build_model
from masonrydam.scene.scene import Scene
from masonrydam.solvers.static import arc_length
from masonrydam.solvers.static.dissipation import JointDissipation

from test_composite_joints import E, FT, GF, KN, bar, end_curve


MOHR_COULOMB = {"law": "mohr_coulomb", "normal_stiffness": KN, "shear_stiffness": KN / 2, "cohesion": 0.0,
                "friction_angle": 30.0, "tensile_strength": 0.0}


def bar_model(joint=None, law_spec=None):
    s = bar(0.1, 1e-4, joint=joint)
    if law_spec is not None:
        s["joints"]["joints"] = dict(law_spec)
    sc = Scene(s)
    mesh = build_mesh(sc.normalized, sc.base_dir)
    return build_model(sc.normalized, mesh), mesh


def moved(model, mesh, slide, opening):
    """Displacements with the upper block moved by (slide, opening) over the lower one (m)."""
    u = np.zeros(model.n_dof)
    g = model.igroups[0]
    upper = mesh.points[:, 1] > 0.1 + 1e-9
    upper[g.conn[:, g.conn.shape[1] // 2:]] = True  # the joint's top face: the upper block's nodes
    u[np.flatnonzero(upper) * 2] = slide
    u[np.flatnonzero(upper) * 2 + 1] = opening
    return u


def dissipation_at(model, meter, u, want_gradient=True):
    model.evaluate(u, want_tangent=False)
    return meter.of_step(want_gradient)


def gradient_is_central_differences(model, meter, u1, grad, size, rel, seed, directions):
    """``grad . v`` against ``(D(u1 + v) - D(u1 - v)) / 2`` along random nodal displacements ``v`` of rms
    ``size`` (m)."""
    rng = np.random.default_rng(seed)
    for _ in range(directions):
        v = rng.standard_normal(model.n_dof) * size
        dp, _ = dissipation_at(model, meter, u1 + v, False)
        dm, _ = dissipation_at(model, meter, u1 - v, False)
        assert float(grad @ v) == pytest.approx((dp - dm) / 2.0, rel=rel)


@pytest.mark.parametrize("slide", [0.0, 2e-6, 4e-5])
def test_dissipation_gradient_equals_finite_differences(slide):
    """Cracking (and sliding) joint points: the assembled derivative of the step's dissipation equals central
    differences of the dissipation itself, along the displacements of every node."""
    model, mesh = bar_model({"cohesion": 0.5e6})
    meter = JointDissipation(model, "test")
    u0 = moved(model, mesh, 0.5 * slide, 1.5 * FT / KN)  # past the peak: a crack that has begun
    model.evaluate(u0, want_tangent=False)
    model.commit()
    meter.mark_start()
    u1 = moved(model, mesh, slide, 1.5 * FT / KN + 3e-6)
    d, grad = dissipation_at(model, meter, u1)
    assert d > 0
    gradient_is_central_differences(model, meter, u1, grad, size=1e-10, rel=1e-5, seed=7, directions=3)


def test_sliding_mohr_coulomb_joint_dissipates_friction_work():
    """The Mohr-Coulomb law of Tzamtzis & Asteris (no cohesion): a joint compressed by sigma slides by ds; the
    step dissipates the friction work tan(phi) sigma ds A (its elastic energy does not change), and the gradient
    equals central differences."""
    model, mesh = bar_model(law_spec=MOHR_COULOMB)
    meter = JointDissipation(model, "test")
    closing = -1e-6  # m: sigma = kn 1e-6 = 0.1 MPa
    sigma = KN * 1e-6
    slip_elastic = np.tan(np.radians(30.0)) * sigma / (KN / 2)
    model.evaluate(moved(model, mesh, 2 * slip_elastic, closing), want_tangent=False)
    model.commit()
    meter.mark_start()
    ds = 1e-6
    u1 = moved(model, mesh, 2 * slip_elastic + ds, closing)
    d, grad = dissipation_at(model, meter, u1)
    assert d == pytest.approx(np.tan(np.radians(30.0)) * sigma * ds * 0.1, rel=1e-9)
    gradient_is_central_differences(model, meter, u1, grad, size=1e-10, rel=1e-6, seed=3, directions=1)


def test_elastic_step_dissipates_nothing_and_plastic_work_is_the_closed_form():
    model, mesh = bar_model()
    meter = JointDissipation(model, "test")
    area = 0.1 * 1.0
    w0 = 1.5 * FT / KN
    model.evaluate(moved(model, mesh, 0.0, w0), want_tangent=False)
    model.commit()
    meter.mark_start()
    t0 = model.igroups[0].traction[..., -1].mean()
    # unloading: elastic, no dissipation, no gradient
    d, grad = dissipation_at(model, meter, moved(model, mesh, 0.0, 0.5 * w0))
    assert abs(d) <= 1e-12 * FT * w0 * area and np.abs(grad).max() <= 1e-9 * FT * area
    # a small opening increment: the trapezoid of the traction over the plastic opening
    w1 = w0 + 1e-7
    d, _ = dissipation_at(model, meter, moved(model, mesh, 0.0, w1))
    t1 = model.igroups[0].traction[..., -1].mean()
    p0, p1 = w0 - t0 / KN, w1 - t1 / KN
    exact = GF * (np.exp(-FT * p0 / GF) - np.exp(-FT * p1 / GF)) * area  # int t dw_p of the exponential law
    assert d == pytest.approx(0.5 * (t0 + t1) * (p1 - p0) * area, rel=1e-12)
    assert d == pytest.approx(exact, rel=1e-6)


@pytest.mark.slow
def test_snap_back_followed_by_dissipation_control():
    """L = 10 m (a snap-back): the traced branch is the closed form, and the joint's dissipation adds up to
    GfI A, converging as the stage's steps (its resolution) grow."""
    L, width = 10.0, 0.5
    errors = []
    for steps in (20, 80):
        ds = masonrydam.run(bar(L, 1.2e-3, control="dissipation", width=width, steps=steps))
        u, sigma = end_curve(ds, L + width, width)
        k = int(np.argmax(sigma))
        post = np.arange(len(u)) > k
        assert post.sum() >= 10 and u[post].min() < u[k] - 5e-5  # the end moved back: traced
        closed = sigma[post] * (L + width) / E + sigma[post] / KN - (GF / FT) * np.log(sigma[post] / FT)
        np.testing.assert_allclose(u[post], closed, rtol=0, atol=1e-9)
        assert u[-1] == pytest.approx(1.2e-3, rel=1e-9) and ds.attrs["completed"] == "true"
        dissipated = json.loads(ds.attrs["per_stage"])[0]["joint_dissipation_J"]
        errors.append(abs(dissipated / (GF * width) - 1.0))
        assert "dissipation-based arc-length" in ds.attrs["simulated_effects"]
        assert ds.attrs["arc_length_switches"] == 0  # dissipation control got through on its own
    assert errors[1] < 0.005 and errors[1] < 0.25 * errors[0]


def _on_the_snap_back_closed_form(ds, L, width):
    u, sigma = end_curve(ds, L + width, width)
    k = int(np.argmax(sigma))
    post = np.arange(len(u)) > k
    closed = sigma[post] * (L + width) / E + sigma[post] / KN - (GF / FT) * np.log(sigma[post] / FT)
    np.testing.assert_allclose(u[post], closed, rtol=0, atol=1e-9)
    assert post.sum() >= 5 and u[-1] == pytest.approx(1.2e-3, rel=1e-9) and ds.attrs["completed"] == "true"
    return u, sigma


def test_a_failing_control_hands_its_last_state_to_the_next(monkeypatch):
    """The chosen control (Crisfield's arc) and then the next (the cracks' opening) are made to fail after three
    steps each: each hands the state it reached to the next, and dissipation control finishes the stage through
    the snap-back. A control restarted from an earlier state would record the elastic rise again after the
    peak, off the closed form of the softening branch."""
    taken = {"cylindrical": 0, "opening": 0}
    step = arc_length.ArcLengthStage._step

    def failing_after_three(self, dl):
        if taken.get(self.mode, 0) >= 3:
            return False, None, None, 0, None, None
        out = step(self, dl)
        if out[0] and self.mode in taken:
            taken[self.mode] += 1
        return out

    monkeypatch.setattr(arc_length.ArcLengthStage, "_step", failing_after_three)
    L, width = 10.0, 0.5
    ds = masonrydam.run(bar(L, 1.2e-3, control="arc_length", width=width))
    u, sigma = _on_the_snap_back_closed_form(ds, L, width)
    k = int(np.argmax(sigma))
    assert np.all(np.diff(u[:k + 1]) > 0)  # one rise to the peak
    stage = json.loads(ds.attrs["per_stage"])[0]
    assert taken == {"cylindrical": 3, "opening": 3} and stage["dissipation_control_steps"] > 5
    assert stage["steps"] == len(u)  # every converged step of the three controls, recorded once


@pytest.mark.slow
def test_dissipation_control_takes_over_where_the_other_controls_fail(monkeypatch):
    """Load control stalls at the bar's peak; the cylindrical arc and the opening control are made to fail at
    once, so dissipation control starts from the stalled state (its first target from the work done so far)
    and traces the snap-back."""
    run = arc_length.ArcLengthStage.run

    def only_dissipation(self):
        if self.mode != "dissipation":
            raise ConvergenceError(f"{self.mode} made to fail")
        return run(self)

    monkeypatch.setattr(arc_length.ArcLengthStage, "run", only_dissipation)
    L, width = 10.0, 0.5
    ds = masonrydam.run(bar(L, 1.2e-3, control="load", width=width))
    _on_the_snap_back_closed_form(ds, L, width)
    stage = json.loads(ds.attrs["per_stage"])[0]
    assert stage["dissipation_control_steps"] > 10 and ds.attrs["arc_length_switches"] == 1


def test_dissipation_control_needs_softening_joints():
    s = bar(0.1, 1e-4, control="dissipation", joint={"law": "linear"})
    for k in ("tensile_strength", "mode_I_fracture_energy", "cohesion", "friction_angle", "mode_II_fracture_energy"):
        s["joints"]["joints"].pop(k)
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "stages[0].control" and "no composite or Mohr-Coulomb" in str(err.value)
