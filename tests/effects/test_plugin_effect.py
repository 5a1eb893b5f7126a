"""An effect added from this file alone, through the public registry: a harmonic force on the
nodes of a set, ``[shaker] set = "top_edge", force = [0, -F], frequency = f``, with its own result variable
``shaker_force`` (the applied resultant per recorded step, N).

Physics: the undamped oscillator of tests/effects/test_dynamic_loads.py (a stiff 1 x 1 m block of 1000 kg on
a linear joint, k = kn = 1e9 N/m, omega = 1000 rad/s) under F sin(Omega t) from rest moves as
u = F/k / (1 - b^2) (sin(Omega t) - b sin(omega t)), b = Omega / omega (Chopra, Dynamics of Structures, 4th
ed., 2012, eq. 3.1.6). The plug-in's force on the top edge's nodes is F / n per node, the same resultant as
the built-in loads given in time apply; nothing in masonrydam/ names it.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
import scenes
from masonrydam.checks import check_keys, number, vector
from masonrydam.effects import Effect, EffectRun, add_force, register, unregister
from masonrydam.effects.loads import nodal_force
from masonrydam.errors import SceneError
from masonrydam.mesh.sets import node_set
from masonrydam.results.variables import ResultVariable

KN, RHO, F = 1.0e9, 1000.0, 1.0e5  # Pa/m, kg/m3, N: k = 1e9 N/m, m = 1000 kg
OMEGA = math.sqrt(KN / RHO)  # 1000 rad/s
B = 0.5  # forcing over natural frequency


def _normalize(raw, model_section):
    """The ``[shaker]`` section: a node or facet set, the force amplitude vector (N, shared by its nodes)
    and the frequency (Hz)."""
    check_keys(raw, {"set", "force", "frequency"}, "shaker")
    if not isinstance(raw.get("set"), str):
        raise SceneError("shaker.set", "is required: the node or facet set the shaker drives")
    return {"set": raw["set"], "force": vector(raw.get("force"), "force", "shaker.force", len(model_section["gravity"])),
            "frequency": number(raw.get("frequency"), "shaker.frequency", 0.0, open_min=True)}


class ShakerRun(EffectRun):
    """Adds F sin(2 pi f t) to the dynamic stages and records the applied resultant."""

    def __init__(self, context):
        spec = context.scene["shaker"]
        nodes = node_set(context.mesh, spec["set"], "shaker.set")
        self.amplitude = nodal_force(context.model, nodes, np.asarray(spec["force"]) / len(nodes))
        self.omega = 2.0 * math.pi * spec["frequency"]
        self.dim = context.model.dim

    def force(self, t):
        return math.sin(self.omega * t) * self.amplitude

    def dynamic_terms(self, stage, terms):
        add_force(terms, self.force)

    def result_variables(self):
        return [ResultVariable("shaker_force", ("step", "component"), "N",
                               "resultant of the shaker's force (test plug-in)", dynamic_only=True)]

    def dynamic_values(self, record, mass):
        return {"shaker_force": self.force(record["t"]).reshape(-1, self.dim).sum(axis=0)}


def _describe(scene, model):
    s = scene.get("shaker")
    return [] if not s else [f"shaker on '{s['set']}' at {s['frequency']:g} Hz (test plug-in)"]


SHAKER = Effect("shaker", "[shaker]", __name__, "Chopra (2012) eq. 3.1.6", __file__, _describe,
                activate=lambda context: ShakerRun(context) if context.scene.get("shaker") else None,
                sections={"shaker": _normalize})


@pytest.fixture
def shaker():
    register(SHAKER)
    yield SHAKER
    unregister("shaker")


def oscillator(steps=400, dt=6e-5, shaker=True):
    # still ground: a dynamic stage needs an excitation the schema knows of; this one adds 0
    scene = scenes.oscillator({"name": "shake", "dt": dt, "steps": steps, "integrator": "newmark_average",
                               "ground_motion": {"x": {"values": [0.0, 0.0], "dt": 1.0, "units": "m/s2"}}},
                              normal_stiffness=KN, density=RHO)
    if shaker:
        scene["shaker"] = {"set": "top_edge", "force": [0.0, -F], "frequency": B * OMEGA / (2 * math.pi)}
    return scene


def test_a_plugin_effect_runs_end_to_end(shaker):
    ds = masonrydam.run(oscillator())
    assert "shaker on 'top_edge'" in ds.attrs["simulated_effects"]
    assert ds.shaker_force.attrs["units"] == "N"
    dyn = np.isfinite(ds.time.values)
    t = ds.time.values[dyn]
    np.testing.assert_allclose(ds.shaker_force.sel(component="y").values[dyn], -F * np.sin(B * OMEGA * t),
                               atol=1e-9 * F)
    assert np.isnan(ds.shaker_force.values[~dyn]).all()  # static steps: not applied, not recorded
    top = ds.y.values > 1.0 - 1e-9
    u = -ds.displacement.sel(component="y").values[dyn][:, top].mean(axis=1)
    closed = F / KN / (1 - B * B) * (np.sin(B * OMEGA * t) - B * np.sin(OMEGA * t))
    assert np.abs(u - closed).max() <= 0.01 * np.abs(closed).max()


def test_a_scene_without_the_section_pays_nothing(shaker):
    ds = masonrydam.run(oscillator(steps=5, shaker=False))
    assert "shaker_force" not in ds
    assert "shaker" not in ds.attrs["simulated_effects"]


def test_the_section_is_unknown_once_unregistered():
    with pytest.raises(SceneError, match="shaker"):
        masonrydam.run(oscillator(steps=5))


def test_bad_plugin_input_names_its_key(shaker):
    scene = oscillator(steps=5)
    scene["shaker"]["set"] = "nowhere"
    with pytest.raises(SceneError) as err:
        masonrydam.run(scene)
    assert err.value.key == "shaker.set"
