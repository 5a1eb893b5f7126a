"""A joint law added from outside the package, through the public registry.

The toy law, written here alone, is a linear spring ``t = diag(ks, (ks,) kn) delta`` whose state never
changes. It is registered with :func:`masonrydam.materials.joint_laws.register_joint_law` and used by a scene
(``[joints.<set>] law = "toy_spring"``) run end to end with :func:`masonrydam.run`: a block on a base, one
joint element of two nodal points, self-weight and then a lateral load at the top. Two points make the joint
statically determinate, so the closed form of its tractions is equilibrium alone (with W the block's weight, H
the lateral load at height h above the joint, A = L t the joint's area, L its length, the points at the ends):

    gravity only:   t_n = -W / A at both points,              t_s = 0
    with H:         t_n(left), t_n(right) = (-W + k H) / A, (-W - k H) / A with k = 2 h / L,
                    t_s(left) + t_s(right) = 2 H / A,         delta = t / (ks, kn)

The scene, the law and the checks need no change in masonrydam/. Also checked: the generic evaluation path
(kinematics, point law, assembly) gives the fused kernel's numbers, bit for bit, when its point law is the
Mohr-Coulomb law of Tzamtzis & Asteris; and what a plug-in law does not support is refused by key.
"""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam
from masonrydam.assembly.groups import InterfaceGroup
from masonrydam.errors import STATUS_OK, SceneError
from masonrydam.materials import mohr_coulomb as mc
from masonrydam.materials.joint_laws import (RESULT_STICK, JointLaw, LawKey, joint_law, joint_laws,
                                             register_joint_law, unregister_joint_law)
from masonrydam.scene.schema import normalize

GRAVITY = 9.80665
DENSITY = 2000.0  # kg/m3
LENGTH, BLOCK_HEIGHT, THICKNESS = 1.0, 0.5, 1.0  # m
KS, KN = 2e8, 5e8  # Pa/m
NODAL_FORCE = 1.0e3  # N on each of the two top nodes of the block


# ---- the toy law ---------------------------------------------------------------------------------------
def linear_spring_points(params_table, param_index, state_committed, delta, time_step, state_trial, traction_out,
                         tangent_out, info):
    """``t = diag(ks, (ks,) kn) delta`` at every point; the state (one column, the code: stick) is kept."""
    rows = params_table[param_index]  # (ne, 2): ks, kn (Pa/m)
    dim = delta.shape[2]
    stiffness = np.empty(delta.shape)
    stiffness[:, :, :-1] = rows[:, None, 0:1]
    stiffness[:, :, -1] = rows[:, None, 1]
    traction_out[...] = stiffness * delta
    tangent_out[...] = 0.0
    for i in range(dim):
        tangent_out[:, :, i, i] = stiffness[:, :, i]
    state_trial[...] = state_committed
    return STATUS_OK


def spring_parameters(spec):
    factor = spec["stiffness_factor"]
    return np.array([factor * spec["shear_stiffness"], factor * spec["normal_stiffness"]])


TOY = JointLaw(
    name="toy_spring", title="toy spring", description="a linear spring (a test's plug-in)",
    summary="toy linear-spring joints", reference="a closed form of statics",
    parameters=spring_parameters, state_size=1, point_law=linear_spring_points,
    keys=(LawKey("stiffness_factor", None, "factor on both stiffnesses", 1.0, minimum=0.0),),
    stiffness_columns=(0, 0, 1), nonlinear=False)


@pytest.fixture
def toy_law():
    register_joint_law(TOY)
    yield TOY
    unregister_joint_law(TOY.name)


def block_scene(lateral=True, **joint):
    stages = [{"name": "gravity", "loads": [{"type": "self_weight"}]}]
    if lateral:
        stages.append({"name": "push", "loads": [{"type": "nodal", "set": "top", "force": [NODAL_FORCE, 0.0]}]})
    material = {"youngs_modulus": "200 GPa", "poisson_ratio": 0.0, "density": DENSITY}
    return {
        "model": {"name": "toy_joint", "hypothesis": "plane_stress", "thickness": THICKNESS},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 1.0, "blocks": [
            {"x0": 0.0, "y0": 0.0, "x1": LENGTH, "y1": 0.5, "group": "base"},
            {"x0": 0.0, "y0": 0.5, "x1": LENGTH, "y1": 0.5 + BLOCK_HEIGHT, "group": "block"}]}},
        "materials": {"base": dict(material), "block": dict(material)},
        "joints": {"joints": {"law": "toy_spring", "normal_stiffness": KN, "shear_stiffness": KS, **joint}},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": stages,
    }


def _last_step_of(ds, stage_index):
    steps = np.nonzero(ds["stage"].values == stage_index)[0]
    return int(steps[-1])


# ---- tests ---------------------------------------------------------------------------------------------
def test_the_registry_lists_the_builtin_laws_and_the_plugin(toy_law):
    names = [law.name for law in joint_laws()]
    assert names[:3] == ["mohr_coulomb", "linear", "composite"]
    assert joint_law("toy_spring") is toy_law and not toy_law.fused
    with pytest.raises(ValueError, match="registered already"):
        register_joint_law(TOY)


def test_a_toy_spring_runs_end_to_end_and_gives_the_closed_form(toy_law):
    ds = masonrydam.run(block_scene())
    assert "toy linear-spring joints: joints" in ds.attrs["simulated_effects"]
    area = LENGTH * THICKNESS  # two points, each with half of it
    weight = DENSITY * GRAVITY * LENGTH * BLOCK_HEIGHT * THICKNESS
    push = 2 * NODAL_FORCE
    x = ds["joint_x"].values
    left, right = int(np.argmin(x)), int(np.argmax(x))

    step = _last_step_of(ds, 0)  # gravity: a uniform joint
    t_n, t_s = ds["joint_traction_normal"].values[step], ds["joint_traction_shear"].values[step, :, 0]
    np.testing.assert_allclose(t_n, -weight / area, rtol=1e-9)
    np.testing.assert_allclose(t_s, 0.0, atol=1e-9 * weight / area)

    step = _last_step_of(ds, 1)  # self-weight and the lateral load at the block's top
    t_n, t_s = ds["joint_traction_normal"].values[step], ds["joint_traction_shear"].values[step, :, 0]
    lever = 2 * BLOCK_HEIGHT / LENGTH
    np.testing.assert_allclose(t_n[left], (-weight + lever * push) / area, rtol=1e-9)
    np.testing.assert_allclose(t_n[right], (-weight - lever * push) / area, rtol=1e-9)
    np.testing.assert_allclose(t_s.mean(), push / area, rtol=1e-9)
    # a block far stiffer than the joint: both points slide alike (to the block's compliance)
    np.testing.assert_allclose(t_s, push / area, rtol=1e-3)
    # the law itself: delta = t / k at every point, and the state never changes (stick)
    np.testing.assert_allclose(ds["joint_opening"].values[step], t_n / KN, rtol=1e-12)
    np.testing.assert_allclose(ds["joint_slip"].values[step, :, 0], t_s / KS, rtol=1e-12)
    assert (ds["joint_state"].values == RESULT_STICK).all()
    assert (ds["joint_plastic_slip"].values == 0.0).all()


def test_the_plugin_reads_its_own_keys(toy_law):
    scene = normalize(block_scene(lateral=False, stiffness_factor=2.0))
    assert scene["joints"]["joints"]["stiffness_factor"] == 2.0
    assert normalize(block_scene(lateral=False))["joints"]["joints"]["stiffness_factor"] == 1.0
    with pytest.raises(SceneError) as err:
        normalize(block_scene(lateral=False, stiffness_factor=-1.0))
    assert err.value.key == "joints.joints.stiffness_factor"
    with pytest.raises(SceneError) as err:  # a key of another law
        normalize(block_scene(lateral=False, cohesion=1e5))
    assert err.value.key == "joints.joints.cohesion"


def test_what_a_plugin_law_does_not_support_is_refused_by_key(toy_law):
    scene = block_scene()
    scene["model"]["kinematics"] = "large"
    with pytest.raises(SceneError) as err:
        masonrydam.run(scene)
    assert err.value.key == "joints.joints.law"
    scene = block_scene(lateral=False)
    scene["stages"].append({"name": "soften", "steps": 2, "control": "dissipation",
                            "loads": [{"type": "nodal", "set": "top", "force": [NODAL_FORCE, 0.0]}]})
    with pytest.raises(SceneError) as err:
        masonrydam.run(scene)
    assert err.value.key == "stages[1].control"


def test_without_registration_the_law_is_unknown():
    with pytest.raises(SceneError) as err:
        normalize(block_scene())
    assert err.value.key == "joints.joints.law"


# ---- the generic path against the fused kernel ----------------------------------------------------------
def mohr_coulomb_points(params_table, param_index, state_committed, delta, time_step, state_trial, traction_out,
                        tangent_out, info):
    """The Mohr-Coulomb law (:func:`~masonrydam.materials.mohr_coulomb.mohr_coulomb_update`) point by point."""
    for e in range(delta.shape[0]):
        for g in range(delta.shape[1]):
            status = mc.mohr_coulomb_update(params_table[param_index[e]], delta[e, g], state_committed[e, g],
                                            state_trial[e, g], traction_out[e, g], tangent_out[e, g])
            if status != STATUS_OK:
                info[0] = e
                return status
    return STATUS_OK


MOHR_COULOMB_GENERIC = JointLaw(
    name="mohr_coulomb_generic", title="Mohr-Coulomb (generic path)", description="a test's plug-in",
    summary="Mohr-Coulomb joints on the generic path", reference="Tzamtzis & Asteris, sec. 3.4",
    parameters=joint_law("mohr_coulomb").parameters, state_size=mc.N_JOINT_STATE, point_law=mohr_coulomb_points,
    keys=joint_law("mohr_coulomb").keys, code_column=mc.S_CODE, result_state_map=(0, 1, 2),
    plastic_slip_column=mc.S_PLASTIC_SLIP, bond_column=mc.S_BOND_BROKEN,
    stiffness_columns=(mc.P_KS, mc.P_KS, mc.P_KN), open_tangent_column=mc.P_OPEN_TANGENT,
    at_rest=joint_law("mohr_coulomb").at_rest)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_generic_path_gives_the_fused_kernels_numbers(dim):
    register_joint_law(MOHR_COULOMB_GENERIC)
    try:
        rng = np.random.default_rng(7)
        if dim == 2:  # two line2 interfaces along a slightly inclined line
            coords = np.array([[0.0, 0.0], [1.0, 0.1], [2.0, 0.15], [0.0, 0.0], [1.0, 0.1], [2.0, 0.15]])
            conn = np.array([[0, 1, 3, 4], [1, 2, 4, 5]])
            type_ = "interface_line2"
        else:  # one quad4 interface
            base = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.05], [1.0, 1.0, 0.1], [0.0, 1.0, 0.0]])
            coords = np.vstack([base, base])
            conn = np.array([[0, 1, 2, 3, 4, 5, 6, 7]])
            type_ = "interface_quad4"
        params = mc.joint_params(1e9, 4e8, cohesion=2e4, friction_angle_deg=30.0, tensile_strength=1e4,
                                 residual_shear_stiffness=1e7)
        groups = [InterfaceGroup("j", type_, conn, coords, dim, params, np.full(len(conn), 0.3), law, "lumped")
                  for law in ("mohr_coulomb", "mohr_coulomb_generic")]
        fused, generic = groups
        assert fused.joint_law.fused and not generic.joint_law.fused
        for _ in range(6):  # sticking, sliding, opening and closing points, with a committed history
            u = rng.normal(scale=2e-4, size=coords.size)
            for g in groups:
                g.evaluate(coords, u, True)
            for name in ("delta", "traction", "state_trial", "fe", "ke"):
                np.testing.assert_array_equal(getattr(generic, name), getattr(fused, name), err_msg=name)
            np.testing.assert_array_equal(generic.point_tangents(), fused.point_tangents())
            for g in groups:
                g.commit()
        assert len(set(fused.result_states().ravel().tolist())) > 1
        np.testing.assert_array_equal(generic.elastic_tangents(coords, coords.size),
                                      fused.elastic_tangents(coords, coords.size))
    finally:
        unregister_joint_law(MOHR_COULOMB_GENERIC.name)
