"""The compiled step loop (masonrydam.solvers.dynamic.compiled_loop) against the Python step it replaces.

The loop's kernel (masonrydam.solvers.dynamic.loop_kernel) performs the implicit step's floating-point operations
in the Python step's order with the same kernels (loads, residuals, the joint-space step, the joints' forces, the
energy balance and its refusal test), so a run must give the same dataset bit for bit, energies and statistics
included; the steps it hands back (the joint-space iteration did not converge, the residual test or the energy
test failed) are finished by the Python step from the same joint-space result, and halved where they fail. Checked
on the cases of tests/solvers/test_compiled_joint_space.py: a sliding block (Newmark 1965), a rocking block
(Housner 1963: opening, impact, re-closure; steps handed back and halved), the Koyna section (cracking lift
joints, El Centro 1940 at 0.5 g) and a 3D block sliding along an oblique direction (a third of its steps handed
back).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scenes import sliding_block
from test_compiled_joint_space import CASES

import masonrydam
from masonrydam.solvers.dynamic import compiled_loop
from masonrydam.solvers.joint_space import condensation as js_module

FIXED_DT = {"sliding block": 2e-3, "rocking block": 1e-3, "Koyna section": 0.0025, "3D sliding block": 2e-3}
LOOP_KEYS = ("dynamic_compiled_loop_steps", "dynamic_compiled_loop_handbacks", "dynamic_compiled_loop_off")


def _run(scene, loop, monkeypatch):
    monkeypatch.setattr(compiled_loop, "COMPILED_LOOP", loop)
    # the static stages in the Python loop either way: "cached" would take the joint-space kernel in the second run
    # only where the first compiled it (a fresh numba cache), and their counters would differ
    monkeypatch.setattr(js_module, "STATIC_COMPILED_STEP", "never")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the energy notes of a coarse dt are not this test's business
        return masonrydam.run(scene)


@pytest.mark.parametrize("dt", ["fixed", "auto"])
@pytest.mark.parametrize("case", list(CASES))
def test_compiled_loop_gives_the_python_steps_run_bit_for_bit(case, dt, monkeypatch):
    make = CASES[case]
    scene_dt = FIXED_DT[case] if dt == "fixed" else "auto"
    _assert_same_run(_run(make(scene_dt), True, monkeypatch), _run(make(scene_dt), False, monkeypatch), dt)


@pytest.mark.parametrize("dt", ["fixed", "auto"])
def test_compiled_loop_with_a_consistent_mass_and_generalized_alpha(dt, monkeypatch):
    """A consistent mass (sparse products with M, some of them carried from one step to the next inside the loop)
    under the generalized-alpha scheme (Chung & Hulbert 1993: alpha_m != 0, so the step's constant part holds
    ``M a_n``), with Rayleigh damping: the sliding block of Newmark (1965), the same run bit for bit."""
    def scene():
        return sliding_block(duration=0.3, dt=2e-3 if dt == "fixed" else "auto", joint_space="on",
                             integrator="generalized_alpha", mass="consistent",
                             damping={"ratio": 0.05, "frequencies": [5.0, 50.0]},
                             output={"stride": 10})  # ten steps a call: the products carried between steps
    _assert_same_run(_run(scene(), True, monkeypatch), _run(scene(), False, monkeypatch), dt)


def _assert_same_run(loop, python, dt):
    a, b = loop.attrs, python.attrs
    assert a["dynamic_compiled_loop_steps"] > 0 and a["dynamic_compiled_loop_off"] == ""
    assert b["dynamic_compiled_loop_steps"] == 0 and "switched off" in b["dynamic_compiled_loop_off"]
    if dt == "fixed":  # (with dt = "auto" a step handed back may be refused and retried smaller)
        assert a["dynamic_compiled_loop_steps"] + a["dynamic_compiled_loop_handbacks"] <= a["dynamic_steps"]
    for name in loop.data_vars:
        x, y = loop[name].values, python[name].values
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
    for key, value in a.items():
        if key in ("history", *LOOP_KEYS) or key.endswith("_s") or "time" in key or "ms_per_step" in key:
            continue
        assert value == b[key] if not isinstance(value, np.ndarray) else np.array_equal(value, b[key]), key


def test_rocking_block_hands_steps_back_and_halves_them(monkeypatch):
    """At dt = 1 ms the rocking block's impacts give steps whose joint-space iteration does not converge or that gain
    energy: the loop hands them back and the Python step halves them (the comparison above covers the hand-back)."""
    ds = _run(CASES["rocking block"](FIXED_DT["rocking block"]), True, monkeypatch)
    assert ds.attrs["dynamic_compiled_loop_handbacks"] > 0
    assert ds.attrs["dynamic_substeps"] > 0
    assert ds.attrs["dynamic_compiled_loop_steps"] > 0.9 * ds.attrs["dynamic_steps"]


def test_stages_off_the_common_path_say_why(monkeypatch):
    from scenes import sliding_block

    ds = _run(sliding_block(duration=0.1, dt=2e-3, joint_space="off"), True, monkeypatch)
    assert ds.attrs["dynamic_compiled_loop_steps"] == 0
    assert "no compiled joint-space step" in ds.attrs["dynamic_compiled_loop_off"]


def test_summary_says_which_path_took_the_steps():
    from masonrydam.scene.summary import _loop_note

    assert _loop_note(0, 0, 10, "a compressible reservoir") == "every step in Python (a compressible reservoir)"
    assert _loop_note(8, 2, 10, "").startswith("8 of 10 steps in the compiled loop, 2 handed back")
