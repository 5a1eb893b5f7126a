"""The forces-only interface kernel (`interface_forces`, what an explicit step calls) gives the forces, tractions,
relative displacements and trial states of `interface_evaluate` without a tangent, bit for bit, for the
Mohr-Coulomb joints of the 3D dam and the composite joints of the Eindhoven wall: it reads the reference
frames computed once (`interface_geometry`) where `interface_evaluate` computes them again, so the two must
agree to the last bit for an explicit step to be the same whichever kernel runs."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from masonrydam.elements.interface import interface_evaluate, interface_forces
from masonrydam.scene import build_mesh, build_model
from masonrydam.scene.scene import as_scene

ROOT = Path(__file__).resolve().parents[2]


def example_model(name, **parameters):
    sc = tomllib.loads((ROOT / "examples" / name).read_text())
    sc["mesh"]["parameters"].update(parameters)
    scene = as_scene(sc)
    return build_model(scene.normalized, build_mesh(scene.normalized, scene.base_dir))


@pytest.mark.parametrize("name, parameters, scale", [
    ("dam_3d_gravity.toml", {"element_size": 20.0}, 1e-4),   # Mohr-Coulomb, 3D: slips, opens, sticks
    ("eindhoven_J4D.toml", {}, 2e-5),                       # composite masonry law, 2D
])
def test_forces_only_kernel_is_interface_evaluate_without_tangent(name, parameters, scale):
    model = example_model(name, **parameters)
    rng = np.random.default_rng(7)
    u = rng.normal(scale=scale, size=model.n_dof)
    codes = set()
    for g in model.igroups:
        if g.kinematics != "small" or not g.joint_law.fused:
            continue
        out = {}
        for which in ("evaluate", "forces"):
            g.state_trial[...] = 0.0
            if which == "evaluate":
                st = interface_evaluate(model.coords, g.conn, u, g.N, g.dN, g.weights, g.thickness, g.params_table,
                                        g.param_index, g.state_base, g.state_trial, g.delta, g.traction, g.fe,
                                        np.empty((0, 0, 0)), False, g.info, g.law_id)
            else:
                st = interface_forces(g.conn, u, g.N, g.frame, g.jw, g.thickness, g.params_table, g.param_index,
                                      g.state_base, g.state_trial, g.delta, g.traction, g.fe, g.info, g.law_id)
            assert st == 0
            out[which] = (g.fe.copy(), g.traction.copy(), g.delta.copy(), g.state_trial.copy())
        for a, b in zip(out["evaluate"], out["forces"]):
            np.testing.assert_array_equal(a, b)
        codes |= set(np.unique(out["forces"][3][..., 0]).tolist())
        assert np.abs(out["forces"][0]).max() > 0
    # the displacements put points in more than one state (stick / slip / open), so the law's branches ran
    assert len(codes) >= 2, codes


@pytest.mark.parametrize("time_step", [None, 2.5e-8])
def test_composite_law_forces_do_not_depend_on_whether_the_tangent_is_wanted(time_step):
    """The composite law skips its consistent tangent where none is wanted (a line search's evaluations): the
    forces, tractions and trial states are those of the evaluation with the tangent, bit for bit, inviscid
    (``time_step`` None: the example's relaxation time removed) and with the Duvaut-Lions regularisation
    (the example's 0.0025 ms over a step of a tenth of it)."""
    model = example_model("eindhoven_J4D.toml")
    rng = np.random.default_rng(11)
    u = rng.normal(scale=2e-5, size=model.n_dof)
    codes = set()
    composite = [g for g in model.igroups if g.law_id is not None and g.kinematics == "small"]
    assert composite
    for g in composite:
        if time_step is None:
            g.params_table[:, g.joint_law.relaxation_time_column] = 0.0
        else:
            g.joint_law.set_time_step(g.params_table, time_step)
        out = {}
        for want in (True, False):
            g.state_trial[...] = 0.0
            n = g.conn.shape[1] * model.dim  # (2 ns nodes, dim components each)
            ke = np.empty((g.conn.shape[0], n, n)) if want else np.empty((0, 0, 0))
            st = interface_evaluate(model.coords, g.conn, u, g.N, g.dN, g.weights, g.thickness, g.params_table,
                                    g.param_index, g.state_base, g.state_trial, g.delta, g.traction, g.fe, ke, want,
                                    g.info, g.law_id)
            assert st == 0
            out[want] = (g.fe.copy(), g.traction.copy(), g.delta.copy(), g.state_trial.copy())
        for a, b in zip(out[True], out[False]):
            np.testing.assert_array_equal(a, b)
        codes |= set(np.unique(out[False][3][..., 0]).tolist())
    # plastic returns ran (the codes of tension, shear and their corner among them), where the tangent is skipped
    assert len(codes - {0.0}) >= 2, codes


@pytest.mark.parametrize("threads", [1, 2])
def test_threaded_kernel_is_the_serial_kernel_bit_for_bit(threads):
    """The composite joints' elements shared among numba's threads (`interface_evaluate_threaded`, what a run
    with more than one thread calls) give the serial kernel's forces, tangents, tractions, relative displacements
    and trial states bit for bit, with one thread and with two (each element is computed by the same code on its
    own rows; nothing is summed across elements, so the number of threads cannot change a last bit), on the
    inviscid Eindhoven wall with its points in several states. Where elements fail (a NaN displacement), the
    failing element reported is the serial kernel's: the first one."""
    import numba

    from masonrydam.elements.interface import interface_evaluate_threaded

    model = example_model("eindhoven_J4D.toml")
    rng = np.random.default_rng(5)
    u = rng.normal(scale=3e-5, size=model.n_dof)
    composite = [g for g in model.igroups if g.law_id is not None and g.kinematics == "small"]
    assert composite
    if threads > numba.config.NUMBA_NUM_THREADS:
        pytest.skip(f"numba has {numba.config.NUMBA_NUM_THREADS} thread(s) here (NUMBA_NUM_THREADS)")
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    codes = set()
    try:
        for g in composite:
            g.params_table[:, g.joint_law.relaxation_time_column] = 0.0
            n = g.conn.shape[1] * model.dim
            for want in (True, False):
                out = {}
                for kernel in (interface_evaluate, interface_evaluate_threaded):
                    g.state_trial[...] = 0.0
                    ke = np.full((g.conn.shape[0], n, n), np.nan) if want else np.empty((0, 0, 0))
                    st = kernel(model.coords, g.conn, u, g.N, g.dN, g.weights, g.thickness, g.params_table,
                                g.param_index, g.state_base, g.state_trial, g.delta, g.traction, g.fe, ke, want,
                                g.info, g.law_id)
                    assert st == 0
                    out[kernel] = (g.fe.copy(), ke.copy(), g.traction.copy(), g.delta.copy(), g.state_trial.copy())
                for a, b in zip(out[interface_evaluate], out[interface_evaluate_threaded]):
                    np.testing.assert_array_equal(a, b)
                codes |= set(np.unique(out[interface_evaluate][4][..., 0]).tolist())
            # NaN displacements at the nodes of two elements, the later one first in the threads' order
            bad = u.copy()
            late, early = g.conn[len(g.conn) - 1, 0], g.conn[len(g.conn) // 3, 0]
            bad[late * model.dim] = np.nan
            bad[early * model.dim] = np.nan
            failing = {}
            for kernel in (interface_evaluate, interface_evaluate_threaded):
                g.info[0] = -1
                st = kernel(model.coords, g.conn, bad, g.N, g.dN, g.weights, g.thickness, g.params_table,
                            g.param_index, g.state_base, g.state_trial, g.delta, g.traction, g.fe,
                            np.empty((0, 0, 0)), False, g.info, g.law_id)
                assert st != 0
                failing[kernel] = (st, int(g.info[0]))
            assert failing[interface_evaluate] == failing[interface_evaluate_threaded]
            assert failing[interface_evaluate][1] <= len(g.conn) // 3
    finally:
        numba.set_num_threads(before)
    assert len(codes - {0.0}) >= 2, codes
