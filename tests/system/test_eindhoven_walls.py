"""The Eindhoven shear wall J4D (Raijmakers & Vermeltfoort 1992, modelled
as Lourenco & Rots 1997): the bundled example examples/eindhoven_J4D.toml and its cyclic variant
examples/eindhoven_J4D_cyclic.py.

Closed form checked: under a constant vertical load, once a bed joint has lost its
cohesion and slides (no dilatancy), the horizontal force is Coulomb's, H = tan(phi) N, N the vertical force
on that joint: the precompression p A (0.30 MPa x 99 000 mm2 = 29.7 kN; 22.3 kN of friction) plus the
weight above it (top beam and courses). In a cyclic push the loop is then a parallelogram between the plateaus H = +/- tan(phi) N.
"""
from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

import masonrydam
from masonrydam.results.pushover import pushover_data
from masonrydam.scene.scene import Scene, set_key
from repository_paths import EXAMPLES

TAN_PHI = 0.75
P, LENGTH, THICKNESS = 0.30e6, 0.99, 0.1
G = 9.80665
STEEL, BRICK = 7850.0, 1800.0
BEAM_HEIGHT, COURSE = 0.1, 0.062


def j4d(**changes) -> dict:
    data = Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data
    for key, value in changes.items():
        set_key(data, key, value)
    return data


def weight_above(y_joint: float, top: float) -> float:
    """N of the wall's weight above a bed joint at height ``y_joint`` (masonry up to ``top``, then the beam)."""
    return (BRICK * (top - y_joint) + STEEL * BEAM_HEIGHT) * LENGTH * THICKNESS * G


def sliding_row(ds):
    """Height of the bed-joint row that slid most at the last step, and its normal force (N)."""
    names = json.loads(ds.joint_set.attrs["set_names"]) if "set_names" in ds.joint_set.attrs else ds.attrs["set_names"]
    bed = ds.joint_set.values == list(names).index("bed_joints")
    y = np.round(ds.joint_y.values[bed], 6)
    slip = np.abs(ds.joint_plastic_slip.values[-1, bed, 0])
    rows = np.unique(y)
    k = int(np.argmax([slip[y == r].mean() for r in rows]))
    normal = -(ds.joint_traction_normal.values[-1, bed] * ds.joint_weight.values[bed])[y == rows[k]].sum()
    return rows[k], normal


@pytest.mark.slow
@pytest.mark.reference
def test_constant_load_j4d_slides_at_coulomb_friction():
    ds = masonrydam.run(j4d(**{"stages[1].loads[0].components": ["x"], "stages[1].loads[0].value": ["4 mm"]}))
    d, f, _ = pushover_data(ds)
    assert d[-1] == pytest.approx(4e-3, abs=1e-8)  # (+ the precompression's lateral expansion)
    k = int(np.argmax(f))
    assert 0.3e-3 < d[k] < 1.5e-3 and f[k] > 1.2 * TAN_PHI * P * LENGTH * THICKNESS  # a bonded peak, then
    y, normal = sliding_row(ds)
    top = ds.y.values.max() - BEAM_HEIGHT  # the top of the masonry
    expected = TAN_PHI * (P * LENGTH * THICKNESS + weight_above(y, top))
    assert normal == pytest.approx(P * LENGTH * THICKNESS + weight_above(y, top), rel=1e-3)
    # the plateau: within 0.5 % of Coulomb (what remains is the relaxation and the last cohesion)
    assert f[-1] == pytest.approx(expected, rel=5e-3)
    assert f[-1] > expected  # cohesion and overstress only add
    # the top beam stayed level (tied) and rose (free vertically)
    top_nodes = ds.driven.sel(component="x").values > 0
    uy = ds.displacement.sel(component="y").values[-1, top_nodes]
    assert np.ptp(uy) <= 1e-4 * np.abs(uy).max()


@pytest.mark.slow
def test_dissipation_control_follows_the_displacement_controlled_j4d_curve():
    """``control = "dissipation"`` (Verhoosel, Remmers & Gutierrez 2009): the same equilibrium path as
    displacement control where that converges (constant vertical load: no snap-back at the wall's scale),
    its steps placed by the joints' dissipation, and the joints' total dissipation reported."""
    loads = {"stages[1].loads[0].components": ["x"], "stages[1].loads[0].value": ["4 mm"]}
    curves = []
    for control in ("load", "dissipation"):
        ds = masonrydam.run(j4d(**loads, **{"stages[1].control": control}))
        d, f, _ = pushover_data(ds)
        curves.append((d, f, ds))
    (d0, f0, _), (d1, f1, ds) = curves
    assert d1[-1] == pytest.approx(d0[-1], abs=1e-9) and ds.attrs["completed"] == "true"
    assert f1.max() == pytest.approx(f0.max(), rel=5e-3)
    at = np.array([1e-3, 2e-3, 3e-3, 4e-3])
    np.testing.assert_allclose(np.interp(at, d1, f1), np.interp(at, d0, f0), rtol=5e-3)
    dissipated = json.loads(ds.attrs["per_stage"])[1]["joint_dissipation_J"]
    # at least the friction work of the last 2 mm of sliding on the plateau (H ~ tan(phi) N)
    assert dissipated > 2e-3 * TAN_PHI * P * LENGTH * THICKNESS


@pytest.mark.slow
@pytest.mark.reference
def test_cyclic_j4d_hysteresis_plateaus_are_coulomb_friction():
    spec = importlib.util.spec_from_file_location("cyclic", EXAMPLES / "eindhoven_J4D_cyclic.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    ds = masonrydam.run(mod.cyclic_scene(((1.0, 10), (-1.5, 25), (1.5, 30))))
    d, f, steps = pushover_data(ds)
    assert len(steps) >= 66 and d[-1] == pytest.approx(1.5e-3, abs=1e-8)
    _, normal = sliding_row(ds)
    coulomb = TAN_PHI * normal
    backward = (ds.stage.values[steps] == 2) & (d < -1.0e-3)
    forward = (ds.stage.values[steps] == 3) & (d > 0.9e-3)
    assert backward.sum() >= 3 and forward.sum() >= 5
    # within 1.5 %: the cohesion left decays with the slip (exp(-c/GfII kappa2)), so |H| falls to Coulomb's
    np.testing.assert_allclose(f[backward], -coulomb, rtol=0.015)
    np.testing.assert_allclose(f[forward], coulomb, rtol=0.015)
    assert (np.abs(f[backward]) >= coulomb).all() and np.all(np.diff(np.abs(f[backward])) <= 0)
    assert json.loads(ds.attrs["pushover_stages"])["x"] == [1, 2, 3]
