"""`self_weight` of some element groups only (`groups = ["dam"]`): a dam's rock carries its own weight before the
dam is built, so a dam analysis loads the dam alone while the rock keeps its mass for the shaking.

Checked on the 2D gravity dam of tests/scenes.dam_with_reservoir (30 m high, 5 m crest, 0.8 : 1 downstream face,
concrete 2400 kg/m3, plane strain, 1 m thick) on a rock block given a density of 2700 kg/m3: the base joint
carries the dam's weight W = rho g (b H + s H^2 / 2) exactly (vertical equilibrium of the block above the joint),
and the state is the one of the same dam on massless rock loaded by the weight of all its groups."""
from __future__ import annotations

import json

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import SceneError
from scenes import DAM_CONCRETE_DENSITY, dam_with_reservoir

G = 9.80665
H, B, S = 30.0, 5.0, 0.8


def gravity_only(rock_density, load):
    scene = dam_with_reservoir(element_size=3.0, stages=[{"name": "gravity", "loads": [load]}],
                               overrides={"materials.foundation.density": rock_density})
    scene.pop("reservoir")  # the weight alone
    return scene


def base_normal_force(ds):
    names = json.loads(ds.joint_set.attrs["set_names"])
    on = ds.joint_set.values == names.index("base_joint")
    tn = ds.joint_traction_normal.isel(step=-1).values[on]
    return float(-(tn * ds.joint_weight.values[on]).sum())


def test_weight_of_the_dam_alone_on_a_heavy_rock():
    weight = DAM_CONCRETE_DENSITY * G * (B * H + 0.5 * S * H * H)
    dam_only = masonrydam.run(gravity_only(2700.0, {"type": "self_weight", "groups": ["dam"]}))
    assert base_normal_force(dam_only) == pytest.approx(weight, rel=1e-6)
    # the same state as the dam on massless rock under the weight of all groups
    massless = masonrydam.run(gravity_only(0.0, {"type": "self_weight"}))
    np.testing.assert_allclose(dam_only.displacement.isel(step=-1).values,
                               massless.displacement.isel(step=-1).values, rtol=0, atol=1e-12)
    # and not the state with the rock's weight too: the 10 m of rock settle by about rho g D^2 / (2 M) = 0.04 mm
    # under it (M the constrained modulus), 6 % of the dam's largest displacement
    both = masonrydam.run(gravity_only(2700.0, {"type": "self_weight"}))
    u_dam = dam_only.displacement.isel(step=-1).values
    assert np.abs(both.displacement.isel(step=-1).values - u_dam).max() > 0.03 * np.abs(u_dam).max()


def test_unknown_group_names_the_key():
    with pytest.raises(SceneError, match=r"stages\[0\]\.loads\[0\]\.groups.*'rock'.*dam"):
        masonrydam.run(gravity_only(2700.0, {"type": "self_weight", "groups": ["rock"]}))
    with pytest.raises(SceneError, match=r"groups"):
        masonrydam.run(gravity_only(2700.0, {"type": "self_weight", "groups": []}))
