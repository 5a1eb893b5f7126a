"""The compiled joint-space step (masonrydam.solvers.joint_space.step_kernel) against the Python loop it replaces.

Both solve a dynamic step condensed on the joints with the same algorithm (Francavilla & Zienkiewicz 1975
flexibility formulation, the Mohr-Coulomb joints of Tzamtzis & Asteris, Newton with held points and line
search): the kernel performs the Python loop's floating-point operations in the same order with the same
kernels and LAPACK routine, so a whole run must give the same dataset bit for bit, energies and statistics
included, with fixed steps and with dt = "auto" (where a step refused by the error control is retried: any
difference of one bit would change the step sizes). Checked on a sliding block (Newmark 1965, every step of the
pulse slides), a rocking block (Housner 1963: opening, impact, re-closure, points held), the Koyna section
(cracking lift joints, El Centro 1940 at 0.5 g) and a 3D block sliding along an oblique direction; and, for static
steps (bond latching, fresh Newton budgets), the Koyna section pushed at its crest and filled with its reservoir.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import masonrydam
from masonrydam.solvers.joint_space import capacitance_lu
from masonrydam.solvers.joint_space import condensation as js_module
from masonrydam.solvers.joint_space.step_kernel import capacitance_getrf
from scenes import ROCKING_BLOCK_HEIGHT, ROCKING_BLOCK_WIDTH, koyna_el_centro, rocking_block, sliding_block

G = 9.80665


def _rocking(dt):
    B, H = ROCKING_BLOCK_WIDTH, ROCKING_BLOCK_HEIGHT
    stage = {"name": "pulse", "type": "dynamic", "duration": 0.3, "integrator": "hht", "joint_space": "on",
             "ground_motion": {"x": {"pulse": {"shape": "half_sine", "amplitude": 1.5 * G * B / H,
                                               "duration": 0.15}}}}
    if dt == "auto":
        stage.update({"dt": "auto", "dt_max": 2e-3})
    else:
        stage["dt"] = dt
    return rocking_block([{"name": "gravity", "loads": [{"type": "self_weight"}]}, stage])


def _koyna(dt):
    output = {"stride": 10, "nodes": ["crest"]}
    if dt == "auto":
        sc = koyna_el_centro(element_size=12.0, dt="auto", duration=3.0, output={"dt": 0.01, "nodes": ["crest"]})
        sc["stages"][1]["dt_max"] = 0.01
        return sc
    return koyna_el_centro(element_size=12.0, dt=dt, steps=1200, output=output)


def _sliding(dt):
    if dt == "auto":
        return sliding_block(duration=0.4, dt="auto", joint_space="on")
    return sliding_block(duration=0.4, dt=dt, joint_space="on")


def _sliding_3d(dt):
    """A 1 x 1 x 0.5 m block on a 1 x 1 x 0.25 m base (hex8 of 0.25 m), a Coulomb joint of mu = 0.2, a rectangular
    ground pulse of 0.4 g along x and 0.3 g along y: the block slides along an oblique direction (two shear
    components at every point)."""
    stage = {"name": "pulse", "type": "dynamic", "duration": 0.3, "integrator": "hht", "joint_space": "on",
             "ground_motion": {"x": {"pulse": {"shape": "rectangular", "amplitude": 0.4 * G, "duration": 0.2}},
                               "y": {"pulse": {"shape": "rectangular", "amplitude": 0.3 * G, "duration": 0.2}}}}
    stage.update({"dt": "auto", "dt_max": 4e-3} if dt == "auto" else {"dt": dt})
    return {"model": {"name": "slide3d", "dimension": 3},
            "mesh": {"generator": "blocks_3d", "parameters": {"element_size": 0.25, "blocks": [
                {"x0": 0.0, "y0": 0.0, "z0": -0.25, "x1": 1.0, "y1": 1.0, "z1": 0.0, "group": "base"},
                {"x0": 0.0, "y0": 0.0, "z0": 0.0, "x1": 1.0, "y1": 1.0, "z1": 0.5, "group": "block"}]}},
            "materials": {g: {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2000.0} for g in ("base", "block")},
            "joints": {"joints": {"normal_stiffness": 1e10, "shear_stiffness": 1e10, "friction_angle": 11.309932474}},
            "supports": [{"set": "base"}],
            "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]}, stage]}


CASES = {"sliding block": _sliding, "rocking block": _rocking, "Koyna section": _koyna, "3D sliding block": _sliding_3d}


def _run(scene, compiled, monkeypatch):
    monkeypatch.setattr(js_module, "COMPILED_STEP", compiled)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the energy notes of a coarse dt are not this test's business
        return masonrydam.run(scene)


@pytest.mark.parametrize("dt", ["fixed", "auto"])
@pytest.mark.parametrize("case", list(CASES))
def test_compiled_step_gives_the_python_loops_run_bit_for_bit(case, dt, monkeypatch):
    make = CASES[case]
    fixed = {"sliding block": 2e-3, "rocking block": 1e-3, "Koyna section": 0.0025, "3D sliding block": 2e-3}[case]
    scene_dt = "auto" if dt == "auto" else fixed
    compiled = _run(make(scene_dt), True, monkeypatch)
    python = _run(make(scene_dt), False, monkeypatch)
    a, b = compiled.attrs, python.attrs
    assert a["dynamic_joint_space_compiled_steps"] > 0 and a["dynamic_joint_space_python_steps"] == 0
    assert b["dynamic_joint_space_compiled_steps"] == 0 and b["dynamic_joint_space_python_steps"] > 0
    assert a["dynamic_joint_space_iterations"] > 0, "the case must iterate in joint space"
    for name in compiled.data_vars:
        x, y = compiled[name].values, python[name].values
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
    skip = ("history", "dynamic_joint_space_compiled_steps", "dynamic_joint_space_python_steps",
            "joint_space_compiled_steps", "joint_space_python_steps",  # (static stages' steps: the switch too)
            "dynamic_compiled_loop_steps", "dynamic_compiled_loop_handbacks", "dynamic_compiled_loop_off")
    for key, value in a.items():
        if key in skip or key.endswith("_s") or "time" in key or "ms_per_step" in key:
            continue
        assert value == b[key] if not isinstance(value, np.ndarray) else np.array_equal(value, b[key]), key


def _koyna_push():
    """The Koyna section at element_size 6 m (320 joint unknowns) under self-weight, its crest then pushed 0.1 m
    downstream in 4 steps, the lift and base joints given a weak bond (c = 0.3 MPa, ft = 0.2 MPa): points at the
    tips of the opening cracks flip across the cohesion jump, so the static step holds them and latches their
    bonds broken (``JointSpace._bond_chatter``)."""
    overrides = {"joints.lift_joints.cohesion": 0.3e6, "joints.lift_joints.tensile_strength": 0.2e6,
                 "joints.base_joint.cohesion": 0.3e6, "joints.base_joint.tensile_strength": 0.2e6}
    sc = koyna_el_centro(element_size=6.0, dt=0.01, steps=1, overrides=overrides)
    sc["stages"] = [sc["stages"][0], {"name": "push", "steps": 4, "loads": [
        {"type": "displacement", "set": "crest", "components": ["x"], "value": [0.1]}]}]
    sc["output"] = {"nodes": ["crest"]}
    return sc


def _koyna_reservoir():
    """examples/koyna_reservoir.toml (self-weight, the reservoir filled to 91.75 m with uplift, then a flood that
    raises the water until a joint slides): a release of held points in one step starts a fresh Newton budget
    (``FRESH_BUDGET_RELEASES``)."""
    import tomllib

    from masonrydam.scene import Scene
    from repository_paths import EXAMPLES

    sc = tomllib.loads((EXAMPLES / "koyna_reservoir.toml").read_text())
    return Scene(sc, base_dir=EXAMPLES)


#: static cases and the statistic each must show (the part of the static step it exercises)
STATIC_CASES = {"Koyna push, bonds latched": (_koyna_push, "joint_space_bond_latches"),
                "Koyna reservoir filling, a fresh Newton budget": (_koyna_reservoir, "joint_space_fresh_budgets")}


@pytest.mark.parametrize("case", list(STATIC_CASES))
def test_compiled_static_step_gives_the_python_loops_run_bit_for_bit(case, monkeypatch):
    """A static step condensed on the joints does what a dynamic one does, plus the latching of bonds at points
    that flip across the cohesion jump and a fresh Newton budget after a release of held points: the kernel
    must do both as the Python loop does (same datasets, same counts of holds, latches and fresh budgets)."""
    make, exercised = STATIC_CASES[case]
    monkeypatch.setattr(js_module, "STATIC_COMPILED_STEP", "always")
    compiled = _run(make(), True, monkeypatch)
    python = _run(make(), False, monkeypatch)
    a, b = compiled.attrs, python.attrs
    assert a["joint_space_compiled_steps"] > 0 and a["joint_space_python_steps"] == 0
    assert b["joint_space_compiled_steps"] == 0 and b["joint_space_python_steps"] > 0
    assert a[exercised] > 0 and a["joint_space_holds"] > 0, "the case must exercise what it is here for"
    for name in compiled.data_vars:
        x, y = compiled[name].values, python[name].values
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
    skip = ("history", "joint_space_compiled_steps", "joint_space_python_steps")
    for key, value in a.items():
        if key in skip or key.endswith("_s") or "time" in key:
            continue
        assert value == b[key] if not isinstance(value, np.ndarray) else np.array_equal(value, b[key]), key


def test_static_stages_take_the_kernel_only_where_it_is_compiled_already(monkeypatch):
    """With STATIC_COMPILED_STEP = "cached" a static stage does not compile the kernel (seconds of a static-only
    scene's first run): where it is not compiled yet the static steps take the Python loop and a dynamic stage
    still takes the kernel; once it is, the static steps take it too."""
    from masonrydam.solvers.joint_space import step_kernel

    monkeypatch.setattr(js_module, "STATIC_COMPILED_STEP", "cached")
    monkeypatch.setattr(step_kernel, "compiled_already", lambda: False)
    ds = _run(_sliding(2e-3), True, monkeypatch)
    assert ds.attrs["joint_space_compiled_steps"] == 0 and ds.attrs["joint_space_python_steps"] > 0
    assert ds.attrs["dynamic_joint_space_compiled_steps"] > 0
    monkeypatch.setattr(step_kernel, "compiled_already", lambda: True)
    ds = _run(_sliding(2e-3), True, monkeypatch)
    assert ds.attrs["joint_space_compiled_steps"] > 0 and ds.attrs["joint_space_python_steps"] == 0


def test_compiled_already_answers_from_this_process():
    """After a call (the tests above compile or load it) the kernel counts as compiled: no numba internals asked."""
    from masonrydam.solvers.joint_space import step_kernel

    masonrydam.run(_sliding(2e-3))
    assert step_kernel.joint_space_step.signatures and step_kernel.compiled_already()


def test_rocking_block_holds_points_in_the_compiled_step(monkeypatch):
    """The rocking block's impacts make joint points flip between open and closed: the compiled step holds them
    as the Python loop does (same count), so the held-point logic is exercised by the comparison above."""
    ds = _run(_rocking(1e-3), True, monkeypatch)
    assert ds.attrs["dynamic_joint_space_holds"] > 0


def test_the_compiled_step_is_available():
    """numba's LAPACK binding is found (else every dynamic step would take the Python loop, silently slower)."""
    from masonrydam.solvers.joint_space import step_kernel

    assert step_kernel.AVAILABLE


def test_capacitance_getrf_equals_the_python_factorization():
    """The compiled capacitance LU (numba's binding of LAPACK dgetrf) gives the factors, row swaps and status of
    :func:`~masonrydam.solvers.joint_space.condensation.capacitance_lu` (scipy's binding of the same routine),
    bit for bit, and the same singular status for a singular matrix."""
    rng = np.random.default_rng(7)
    P, dim = 40, 2
    m = P * dim
    A = rng.standard_normal((m, m))
    S = A @ A.T / m  # a symmetric positive definite flexibility
    ST = np.ascontiguousarray(S.T)
    slot = np.arange(m, dtype=np.int64)
    qt = rng.standard_normal((P, dim, dim)) * 0.3
    qt[::3] = 0.0  # sticking points: no row
    flat = qt.reshape(-1, dim)
    rows = np.flatnonzero(flat.any(axis=1)).astype(np.int64)
    st1, J1, piv1 = capacitance_lu(ST, slot, rows, qt)
    st2, J2, piv2 = capacitance_getrf(ST, slot, rows, qt, js_module.SINGULAR_PIVOT)
    assert st1 == st2 == 0
    assert np.array_equal(J1, J2) and np.array_equal(piv1, piv2)
    # a singular capacitance matrix: Qt = -S^-1 on one point makes I + Qt S singular in its rows
    qt_s = np.zeros((P, dim, dim))
    qt_s[0] = -np.linalg.inv(S[:dim, :dim])
    rows_s = np.arange(dim, dtype=np.int64)
    assert capacitance_lu(ST, slot, rows_s, qt_s)[0] == capacitance_getrf(ST, slot, rows_s, qt_s,
                                                                           js_module.SINGULAR_PIVOT)[0] != 0


def test_summary_says_which_code_solved_the_joint_space_steps():
    from masonrydam.scene.summary import _kernel_note

    assert _kernel_note(120, 0) == "; every step compiled (one call a step)"
    assert _kernel_note(0, 7) == "; every step in the Python loop"
    assert _kernel_note(5, 2) == "; 5 steps compiled (one call a step), 2 in the Python loop"
    assert _kernel_note(0, 0) == ""
