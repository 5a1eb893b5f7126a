"""The law descriptors (masonrydam.materials.joint_laws, masonrydam.materials.continuum_laws) against the laws
they describe: parameter rows, state columns, result states, compliance, the kernels' ids."""
from __future__ import annotations

import numpy as np
import pytest

from masonrydam.elements.continuum_plastic import LAW_IDS
from masonrydam.errors import SceneError
from masonrydam.materials import composite as ci
from masonrydam.materials import mohr_coulomb as mc
from masonrydam.materials.continuum_laws import continuum_law, continuum_laws
from masonrydam.materials.joint_laws import (FUSED_KERNELS, RESULT_CRUSHED, RESULT_OPEN, RESULT_SLIP, RESULT_STICK,
                                             JointLaw, LawKey, joint_law, joint_laws, register_joint_law)

COMPOSITE_SPEC = {"normal_stiffness": 8.2e10, "shear_stiffness": 3.6e10, "tensile_strength": 1.6e5,
                  "mode_I_fracture_energy": 12.0, "cohesion": 2.24e5, "friction_angle": 36.87,
                  "mode_II_fracture_energy": 50.0, "shear_stiffness_2": 3.0e10}


def test_the_builtin_joint_laws_and_their_kernels():
    assert [law.name for law in joint_laws()][:3] == ["mohr_coulomb", "linear", "composite"]
    for law in joint_laws()[:3]:
        assert law.fused and law.kernel_id in FUSED_KERNELS
    assert joint_law("mohr_coulomb").kernel_id is None  # (None prunes the composite branch of the kernels)
    assert joint_law("composite").state_size == ci.N_COMPOSITE_STATE
    assert joint_law("mohr_coulomb").state_size == joint_law("linear").state_size == mc.N_JOINT_STATE
    with pytest.raises(ValueError, match="unknown joint law"):
        joint_law("nonsense")


def test_parameter_rows_are_those_of_the_law_modules():
    spec = {"normal_stiffness": 1e10, "shear_stiffness": 4e9, "cohesion": 1e5, "friction_angle": 30.0,
            "tensile_strength": 5e4, "residual_shear_stiffness": 1e8}
    np.testing.assert_array_equal(joint_law("mohr_coulomb").parameters(spec),
                                  mc.joint_params(1e10, 4e9, 1e5, 30.0, 5e4, 1e8))
    linear = joint_law("linear").parameters({"normal_stiffness": 1e10, "shear_stiffness": 4e9})
    assert linear[mc.P_COHESION] > 1e299 and linear[mc.P_TENSILE_STRENGTH] > 1e299
    row = joint_law("composite").parameters(COMPOSITE_SPEC)
    assert row.shape == (ci.N_COMPOSITE_PARAMS,) and row[ci.P_KS2] == 3.0e10
    with pytest.raises(ValueError, match="snap back"):
        joint_law("composite").parameters({**COMPOSITE_SPEC, "mode_I_fracture_energy": 0.1})


def test_result_states_and_state_columns():
    composite = joint_law("composite")
    state = np.zeros((6, ci.N_COMPOSITE_STATE))
    state[:, ci.S_CODE] = np.arange(6)  # elastic, shear, tension, cap, tension-shear, shear-cap
    assert composite.result_states(state).tolist() == [RESULT_STICK, RESULT_SLIP, RESULT_OPEN, RESULT_CRUSHED,
                                                       RESULT_OPEN, RESULT_CRUSHED]
    mc_law = joint_law("mohr_coulomb")
    state = np.zeros((2, 3, mc.N_JOINT_STATE))
    state[..., mc.S_CODE] = [[mc.STICK, mc.SLIP, mc.OPEN], [mc.OPEN, mc.STICK, mc.SLIP]]
    state[..., mc.S_PLASTIC_SLIP] = 1e-3
    state[0, 2, mc.S_BOND_BROKEN] = 1.0
    assert mc_law.result_states(state).dtype == np.int8
    np.testing.assert_array_equal(mc_law.result_states(state), state[..., mc.S_CODE])
    assert mc_law.plastic_slip(state, 2).shape == (2, 3, 1) and (mc_law.plastic_slip(state, 2) == 1e-3).all()
    assert mc_law.bond_broken(state).sum() == 1


def test_bonds_latch_for_the_mohr_coulomb_law_only():
    base, trial = np.zeros((4, mc.N_JOINT_STATE)), np.zeros((4, mc.N_JOINT_STATE))
    trial[[1, 3], mc.S_BOND_BROKEN] = 1.0
    assert joint_law("composite").latch_broken_bonds(base, trial) == 0
    assert joint_law("mohr_coulomb").latch_broken_bonds(base, trial) == 2
    assert base[:, mc.S_BOND_BROKEN].tolist() == [0.0, 1.0, 0.0, 1.0]
    assert joint_law("mohr_coulomb").latch_broken_bonds(base, trial) == 0  # (latched already)


@pytest.mark.parametrize("dim", [2, 3])
def test_compliance_and_elastic_stiffness(dim):
    rows = mc.joint_params(1e10, 4e9, 0.0, 30.0)[None, :]
    np.testing.assert_array_equal(joint_law("mohr_coulomb").compliance(rows, dim),
                                  1.0 / rows[:, [mc.P_KS] * (dim - 1) + [mc.P_KN]])
    row = joint_law("composite").parameters(COMPOSITE_SPEC)[None, :]
    expected = [3.6e10, 3.0e10, 8.2e10] if dim == 3 else [3.6e10, 8.2e10]
    np.testing.assert_array_equal(joint_law("composite").elastic_stiffness(row, dim)[0], expected)


def test_elastic_parameters_and_solver_controls_work_on_copies():
    law = joint_law("mohr_coulomb")
    rows = mc.joint_params(1e10, 4e9, 0.0, 30.0)[None, :]
    law.set_open_tangent(rows, 1.0)
    assert rows[0, mc.P_OPEN_TANGENT] == 1.0
    at_rest = law.elastic_parameters(rows)
    assert at_rest[0, mc.P_OPEN_TANGENT] == 0.0 and at_rest[0, mc.P_COHESION] > 1e299
    assert rows[0, mc.P_COHESION] == 0.0  # (a copy)
    row = joint_law("composite").parameters({**COMPOSITE_SPEC, "relaxation_time": 1e-3})[None, :]
    assert joint_law("composite").relaxation_time(row) == 1e-3 and law.relaxation_time(rows) == 0.0
    joint_law("composite").set_time_step(row, 0.25)
    assert row[0, ci.P_TIME_STEP] == 0.25


def test_scene_keys_are_read_and_checked_by_the_descriptor():
    mc_law = joint_law("mohr_coulomb")
    out = mc_law.normalize({"friction_angle": "30 deg", "cohesion": "0.1 MPa"}, "joints.j", 1e9)
    assert out == {"friction_angle": 30.0, "cohesion": 1e5, "tensile_strength": 0.0, "residual_shear_stiffness": 0.0}
    for table, key in (({}, "joints.j.friction_angle"), ({"friction_angle": 90.0}, "joints.j.friction_angle"),
                       ({"friction_angle": 30.0, "cohesion": -1.0}, "joints.j.cohesion"),
                       ({"friction_angle": 30.0, "residual_shear_stiffness": 2e9},
                        "joints.j.residual_shear_stiffness")):
        with pytest.raises(SceneError) as err:
            mc_law.normalize(table, "joints.j", 1e9)
        assert err.value.key == key
    # the composite law keeps only what is given (its parameter builder has the defaults)
    given = {"tensile_strength": 1e5, "mode_I_fracture_energy": 10.0, "cohesion": 2e5, "friction_angle": 30.0,
             "mode_II_fracture_energy": 50.0, "relaxation_time": "1 ms"}
    assert joint_law("composite").normalize(given, "joints.j", 1e9) == {**given, "relaxation_time": 1e-3}


def test_a_descriptor_that_cannot_work_is_refused():
    with pytest.raises(ValueError, match="no point_law"):
        register_joint_law(JointLaw("broken", "broken", "", "", "", lambda spec: np.zeros(2), 1))
    with pytest.raises(ValueError, match="every joint set"):
        register_joint_law(JointLaw("clash", "clash", "", "", "", lambda spec: np.zeros(2), 1,
                                    point_law=lambda *a: 0, keys=(LawKey("normal_stiffness", "stiffness", "kn"),)))
    with pytest.raises(ValueError, match="registered already"):
        register_joint_law(joint_law("mohr_coulomb"))


def test_continuum_descriptors_match_the_kernel_and_the_laws():
    names = [law.name for law in continuum_laws()]
    assert names == ["elastic", "von_mises", "drucker_prager", "tresca", "mohr_coulomb"]
    assert not continuum_law("elastic").plastic and continuum_law("elastic").state_size == 0
    assert LAW_IDS == {law.name: law.kernel_id for law in continuum_laws() if law.plastic}
    assert sorted(LAW_IDS.values()) == [1, 2, 3, 4]
    material = {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "yield_stress": 1e7, "kinematic_hardening": 0.0,
                "residual_yield_stress": 0.0, "viscosity": 0.0, "cohesion": 1e6, "friction_angle": 30.0,
                "dilation_angle": None, "residual_cohesion": 0.0, "match": "plane_strain"}
    for law in continuum_laws()[1:]:
        row = law.parameters(material, -1e8)
        assert row[law.hardening_column] == -1e8, law.name
        assert law.hardening_key in law.keys
    with pytest.raises(ValueError, match="unknown continuum law"):
        continuum_law("nonsense")
