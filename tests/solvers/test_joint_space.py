"""Joint-space (condensed) Newton of the dynamic solver, masonrydam.solvers.joint_space.

The condensed step must reproduce the general Newton path: both solve the same discrete equations
(HHT step of Hilber, Hughes & Taylor 1977 with the Mohr-Coulomb joints of Tzamtzis & Asteris), so
the two time histories agree to the Newton tolerance. Checked on Newmark's (1965) sliding block (the
permanent slip of the rectangular pulse within 0.05 % of the closed form, as tests/solvers/test_dynamics.py
checks for the general path) and Housner's (1963) rocking block (opening, impact and re-closure). The pieces
are checked against their definitions: ``delta = B u`` against the interface kernel at random displacements on
inclined 2D and 3D joints, and the block-triangular Newton correction against a dense solve of
``(I + S Qt) D = -F``.
"""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import STATUS_NAN, SceneError
from masonrydam.scene import build_mesh, build_model, build_stages
from masonrydam.scene.scene import Scene
from masonrydam.solvers.linear.dense_lu import STATUS_SINGULAR, woodbury_apply, woodbury_factor
from masonrydam.solvers.joint_space import capacitance_lu, joint_operator, joint_space_size
from masonrydam.solvers.joint_space.kernels import (STATUS_TOO_MANY_CHANGES, apply_correction,
                                            capacitance_update_solve, joint_space_correction)
from scenes import ROCKING_BLOCK_HEIGHT, ROCKING_BLOCK_WIDTH, koyna_el_centro, rocking_block, sliding_block

G = 9.80665
#: what the Koyna runs record: every 50th step, the crest
KOYNA_OUTPUT = {"stride": 50, "nodes": ["crest"]}


def _model(scene):
    sc = Scene(scene)
    mesh = build_mesh(sc.normalized, ".")
    model = build_model(sc.normalized, mesh)
    build_stages(sc.normalized, mesh, model)
    return model


def _inclined_2d(angle_deg):
    """Two blocks whose joint is inclined at angle_deg (the mesh rotated as a whole)."""
    return {"model": {"name": "incl", "thickness": 0.7},
            "mesh": {"generator": "blocks_2d", "parameters": {"blocks": [
                {"x0": 0, "y0": 0, "x1": 1.0, "y1": 0.4, "group": "base"},
                {"x0": 0, "y0": 0.4, "x1": 1.0, "y1": 0.9, "group": "block"}], "element_size": 0.2,
                "rotation_deg": angle_deg}},
            "materials": {g: {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": 2000} for g in ("base", "block")},
            "joints": {"joints": {"normal_stiffness": 1e10, "shear_stiffness": 1e10, "friction_angle": 30.0}},
            "supports": [{"set": "base"}],
            "stages": [{"name": "g", "loads": [{"type": "self_weight"}]}]}


def _oblique_3d():
    return {"model": {"dimension": 3},
            "mesh": {"generator": "blocks_3d", "parameters": {
                "blocks": [{"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 0.2, "group": "base"},
                           {"x0": 0, "y0": 0, "z0": 0.2, "x1": 1, "y1": 1, "z1": 0.5, "group": "block"}],
                "element_size": 0.25, "rotation_deg": [20.0, -35.0, 10.0]}},
            "materials": {g: {"youngs_modulus": "30 GPa", "poisson_ratio": 0.2, "density": 2000.0} for g in ("base", "block")},
            "joints": {"joints": {"normal_stiffness": 1e10, "shear_stiffness": 1e10, "friction_angle": 30.0}},
            "supports": [{"set": "base_nodes"}],
            "stages": [{"name": "g", "loads": [{"type": "self_weight"}]}]}


@pytest.mark.parametrize("scene", [_inclined_2d(0.0), _inclined_2d(37.0), _oblique_3d()],
                         ids=["2d-flat", "2d-37deg", "3d-oblique"])
def test_joint_operator_gives_the_kernel_relative_displacements_and_forces(scene):
    """B u equals the local relative displacements of the interface kernel (Tzamtzis & Asteris eqs. 4-6, 10) at a
    random displacement field, and B^T (w t) its nodal forces, on flat, inclined and oblique joints."""
    model = _model(scene)
    rng = np.random.default_rng(3)
    u = 1e-4 * rng.standard_normal(model.n_dof)
    B, weight, _, _ = joint_operator(model)
    assert B.shape == (joint_space_size(model), model.n_dof)
    f, _ = model.evaluate(u, want_tangent=False)
    f_joint = f - model.K_continuum @ u
    (g,) = model.igroups
    delta = g.delta.reshape(-1, model.dim)
    np.testing.assert_allclose((B @ u).reshape(-1, model.dim), delta, rtol=0, atol=1e-12 * np.abs(delta).max())
    forces = B.T @ (weight[:, None] * g.traction.reshape(-1, model.dim)).ravel()
    np.testing.assert_allclose(forces, f_joint, rtol=0, atol=1e-9 * np.abs(f_joint).max())


def _dense_newton_correction(S, qt, F):
    """Reference: D = -(I + S Qt)^-1 F with Qt block diagonal from qt (P, dim, dim)."""
    P, dim = qt.shape[0], qt.shape[1]
    Qt = np.zeros((P * dim, P * dim))
    for p in range(P):
        Qt[p * dim:(p + 1) * dim, p * dim:(p + 1) * dim] = qt[p]
    return np.linalg.solve(np.eye(P * dim) + S @ Qt, -F)


def test_condensed_correction_equals_the_dense_newton_solve():
    """The block-triangular correction D = -F - S_:a z, (I + Qt_a S_:a) z = -Qt_a F is the solution of
    (I + S Qt) D = -F for a block-diagonal Qt that is zero at sticking points and has zero rows
    (a point sliding without hardening: normal row zero)."""
    rng = np.random.default_rng(7)
    dim, P = 2, 9
    m = dim * P
    A = rng.standard_normal((m, m))
    S = A @ A.T / m + np.eye(m) + 0.3 * (A - A.T) / m  # not symmetric: checks rows against columns
    qt = np.zeros((P, dim, dim))
    qt[1] = -np.diag([3.0, 5.0])                      # open: -w D0
    qt[4] = [[-2.0, -0.7], [0.0, 0.0]]                # sliding: shear row only
    qt[6] = rng.standard_normal((dim, dim))           # anything
    F = rng.standard_normal(m)
    expected = _dense_newton_correction(S, qt, F)
    rows = np.flatnonzero(qt.reshape(m, dim).any(axis=1)).astype(np.int64)
    assert len(rows) == 5
    z, step = np.zeros(8), np.zeros(m)
    # the columns stored in a shuffled order (slot[j]: the row of column j), as a lazy store keeps them
    slot = rng.permutation(m).astype(np.int64)
    ST = np.empty((m, m))
    ST[slot] = S.T
    st, J, piv = capacitance_lu(ST, slot, rows, qt)
    assert st == 0
    assert joint_space_correction(ST, slot, F, rows, qt, J, piv, z, step) == 0
    np.testing.assert_allclose(step, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    # a singular capacitance matrix is reported, not solved: Qt = -S^-1 on one point's block
    qs = np.zeros((P, dim, dim))
    qs[2] = -np.linalg.inv(S[4:6, 4:6])
    rows2 = np.array([4, 5], dtype=np.int64)
    assert capacitance_lu(ST, slot, rows2, qs)[0] == STATUS_SINGULAR
    # and a NaN in the law's tangent is reported before LAPACK sees it
    qn = qt.copy()
    qn[4, 0, 0] = np.nan
    assert capacitance_lu(ST, slot, rows, qn)[0] == STATUS_NAN


def test_capacitance_update_equals_the_dense_newton_solve():
    """The LU of one active set (reference) updated to another by Sherman-Morrison-Woodbury on the
    union of their rows (Golub & Van Loan 2013, sec. 2.1.4): a point that closed, one that opened,
    one whose friction direction flipped and an unchanged pair give the dense Newton correction; with
    fewer allowed changes than there are, the kernel declines (status 5) instead of solving."""
    rng = np.random.default_rng(5)
    dim, P = 2, 12
    m = dim * P
    A = rng.standard_normal((m, m))
    S = A @ A.T / m + np.eye(m) + 0.3 * (A - A.T) / m  # not symmetric: checks rows against columns
    slot = rng.permutation(m).astype(np.int64)  # columns in a shuffled order, as in a lazy store
    ST = np.empty((m, m))
    ST[slot] = S.T
    kinds = {"open": -np.diag([3.0, 5.0]), "slip+": np.array([[-2.0, -0.7], [0.0, 0.0]]),
             "slip-": np.array([[-2.0, 0.7], [0.0, 0.0]])}

    def qt_of(points):
        qt = np.zeros((P, dim, dim))
        for p, kind in points.items():
            qt[p] = kinds[kind]
        return qt

    q_ref = qt_of({1: "open", 3: "slip+", 5: "open", 8: "slip+"})
    q_cur = qt_of({1: "open", 3: "slip-", 6: "slip+", 8: "slip+", 10: "open"})
    F = rng.standard_normal(m)
    expected = _dense_newton_correction(S, q_cur, F)
    r_ref = np.flatnonzero(q_ref.reshape(m, dim).any(axis=1)).astype(np.int64)
    r_cur = np.flatnonzero(q_cur.reshape(m, dim).any(axis=1)).astype(np.int64)
    st, J, piv = capacitance_lu(ST, slot, r_ref, q_ref)
    assert st == 0
    z, step = np.zeros(16), np.zeros(m)
    args = (ST, slot, r_ref, np.ascontiguousarray(q_ref.reshape(m, dim)[r_ref]), J, piv, r_cur,
            np.ascontiguousarray(q_cur.reshape(m, dim)[r_cur]), F)
    assert capacitance_update_solve(*args, 100, z) == 0
    assert apply_correction(ST, slot, F, r_cur, z, step) == 0
    np.testing.assert_allclose(step, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    assert capacitance_update_solve(*args, 2, z) == STATUS_TOO_MANY_CHANGES


def test_woodbury_update_equals_the_dense_solve():
    """Sherman-Morrison-Woodbury (Golub & Van Loan 2013, sec. 2.1.4) as used by the general path's
    low-rank updates: K = K_ref + P E P^T solved from K_ref^-1 columns, with a capacitance matrix that
    needs row pivoting."""
    rng = np.random.default_rng(11)
    n = 14
    A = rng.standard_normal((n, n))
    K_ref = A @ A.T + n * np.eye(n)
    Jd = np.array([2, 5, 6, 11], dtype=np.int64)
    E = rng.standard_normal((4, 4)) * 40.0
    K = K_ref.copy()
    K[np.ix_(Jd, Jd)] += E
    b = rng.standard_normal(n)
    ZT = np.ascontiguousarray(np.linalg.solve(K_ref, np.eye(n)[:, Jd]).T)
    e_row, e_col = (a.ravel().astype(np.int64) for a in np.meshgrid(np.arange(4), np.arange(4), indexing="ij"))
    e_val = np.ascontiguousarray(E.ravel())
    Sm, piv = np.empty((4, 4)), np.empty(4, dtype=np.int64)
    assert woodbury_factor(ZT, Jd, e_row, e_col, e_val, Sm, piv) == 0
    assert (piv != np.arange(4)).any(), "the test must exercise pivoting"
    x, w = np.empty(n), np.empty(4)
    assert woodbury_apply(ZT, Jd, e_row, e_col, e_val, Sm, piv, np.linalg.solve(K_ref, b), w, x) == 0
    np.testing.assert_allclose(x, np.linalg.solve(K, b), rtol=1e-10, atol=1e-12)


@pytest.mark.reference
def test_sliding_block_same_history_as_the_general_path_and_newmark_slip():
    """Newmark (1965): rectangular pulse A = 0.4 g for 0.2 s on a joint with mu = 0.2. Permanent
    slip of a rigid block (Newmark 1965): s = A t_p^2 (A - a_y) / (2 a_y) with a_y = mu g. The condensed
    and the general Newton paths give the same history (to 1e-6 of the slip), and the condensed path
    solved every step itself."""
    hist = {}
    for mode in ("on", "off"):
        ds = masonrydam.run(sliding_block(duration=0.5, joint_space=mode))
        top = np.nonzero(np.isclose(ds.y.values, 0.75))[0]
        hist[mode] = ds.displacement.sel(component="x").isel(node=top).mean(axis=1).values
        if mode == "on":
            assert int(ds.attrs["dynamic_joint_space_steps"]) == int(ds.attrs["dynamic_steps"])
            assert int(ds.attrs["dynamic_joint_space_fallbacks"]) == 0
            assert int(ds.attrs["dynamic_factorizations"]) == 1
        else:
            assert int(ds.attrs["dynamic_joint_space_size"]) == 0
    A, tp, ay = 0.4 * G, 0.2, 0.2 * G
    slip = A * tp**2 * (A - ay) / (2 * ay)
    assert -hist["on"][-1] == pytest.approx(slip, rel=5e-4)  # the block lags behind the ground
    np.testing.assert_allclose(hist["on"], hist["off"], rtol=0, atol=1e-6 * slip)


def test_recovery_from_stored_columns_equals_the_substitution(monkeypatch):
    """The displacements of a converged joint-space step, ``u = y - K_ref^-1 B^T (q - q_n)``, recovered
    from the stored columns of ``K_ref^-1 B^T`` (the default) equal those of a second substitution
    (columns not stored) to round-off, on Newmark's sliding block (every step of the
    pulse slides); the run reports the recoveries and the memory of the columns."""
    from masonrydam.solvers.joint_space import condensation as js

    hist, attrs = {}, {}
    for stored in (True, False):
        if not stored:
            monkeypatch.setattr(js, "RECOVERY_MEMORY_MAX", 0)
        ds = masonrydam.run(sliding_block(duration=0.3, joint_space="on"))
        hist[stored] = ds.displacement.values
        attrs[stored] = ds.attrs
    assert int(attrs[True]["dynamic_joint_space_column_recoveries"]) > 50
    assert float(attrs[True]["dynamic_joint_space_column_memory_MB"]) > 0
    assert int(attrs[False]["dynamic_joint_space_column_recoveries"]) == 0
    assert float(attrs[False]["dynamic_joint_space_column_memory_MB"]) == 0
    scale = np.abs(hist[False]).max()
    np.testing.assert_allclose(hist[True], hist[False], rtol=0, atol=1e-9 * scale)


def test_sticking_steps_take_no_joint_space_iteration():
    """Below the sliding threshold (A = 0.1 g < mu g) every point sticks: each step is the elastic
    predictor (one substitution), with no iteration and the single factorization of the stage."""
    ds = masonrydam.run(sliding_block(amplitude=0.1 * G, duration=0.1, joint_space="on"))
    a = ds.attrs
    assert int(a["dynamic_joint_space_steps"]) == int(a["dynamic_steps"]) == 50
    assert int(a["dynamic_joint_space_iterations"]) == 0
    assert int(a["dynamic_newton_iterations"]) == 0
    assert int(a["dynamic_factorizations"]) == 1


@pytest.mark.slow
def test_rocking_block_same_history_as_the_general_path():
    """Housner (1963): the block 0.3 x 1.5 m on a no-tension joint under a
    half-sine ground pulse of 1.5 g b/h lifts off (joint points open), rocks on its toe and lands on
    its heel. Until that first impact the joint-space path gives the general path's uplift history to
    1e-6 of the peak uplift (about 1 mm). After it the histories part: the impact of a stiff block
    (kn = 1e12 Pa/m, dt = 1 ms) is resolved by step splitting driven by the energy check, which
    rounds differently in the two paths."""
    B, H = ROCKING_BLOCK_WIDTH, ROCKING_BLOCK_HEIGHT
    out = {}
    for mode in ("on", "off"):
        scene = rocking_block([{"name": "gravity", "loads": [{"type": "self_weight"}]},
                               {"name": "pulse", "type": "dynamic", "dt": 1e-3, "duration": 0.4, "integrator": "hht",
                                "joint_space": mode,
                                "ground_motion": {"x": {"pulse": {"shape": "half_sine", "amplitude": 1.5 * G * B / H,
                                                                  "duration": 0.15}}}}])
        ds = masonrydam.run(scene)
        heel = np.nonzero(np.isclose(ds.x.values, B) & np.isclose(ds.y.values, 0.0))[0]
        out[mode] = ds.displacement.sel(component="y").isel(node=heel).max(axis=1).values
        if mode == "on":
            assert int(ds.attrs["dynamic_joint_space_steps"]) > 0.9 * int(ds.attrs["dynamic_steps"])
    peak = out["off"].max()
    assert peak > 1e-3, "the block rocks"
    top = int(np.argmax(out["off"]))
    impact = top + int(np.argmax(out["off"][top:] < 1e-6))  # first re-contact of the heel
    assert impact > top
    np.testing.assert_allclose(out["on"][:impact], out["off"][:impact], rtol=0, atol=1e-6 * peak)


def test_joint_space_key_is_checked():
    sc = sliding_block(duration=0.5, joint_space="sometimes")
    with pytest.raises(SceneError, match=r"stages\[1\]\.joint_space"):
        masonrydam.run(sc)


def test_held_points_stick_whatever_their_displacement():
    """The iteration device of ``JointSpace.solve_step``: a held point gets the elastic traction
    ``D0 (delta - s_p)`` from its committed plastic slip and the sticking ``q = -w ks s_p``, ``qt = 0``
    (Tzamtzis & Asteris eq. 11), in the residual as in the tangent, however far its displacement has gone into
    slip or opening; the same points not held follow the Mohr-Coulomb law (Tzamtzis & Asteris sec. 3.4)."""
    from masonrydam.materials import mohr_coulomb as mc
    from masonrydam.solvers.joint_space.kernels import joint_points_evaluate

    ks, kn, tan_phi, w = 2e10, 5e10, 0.6, 0.25
    params = np.zeros((1, mc.N_JOINT_PARAMS))
    params[0, mc.P_KS], params[0, mc.P_KN], params[0, mc.P_TAN_PHI] = ks, kn, tan_phi
    # point 0 slides (|tau_trial| > -tan_phi sigma), point 1 opens, point 2 sticks
    delta = np.array([[3e-5, -1e-5], [1e-6, 2e-6], [1e-7, -1e-5]])
    base = np.zeros((3, mc.N_JOINT_STATE))
    base[:, mc.S_PLASTIC_SLIP] = [4e-6, 0.0, -2e-7]
    base[:, mc.S_BOND_BROKEN] = 1.0
    weight = np.full(3, w)
    out = {}
    for held in (np.zeros(3, dtype=np.int8), np.ones(3, dtype=np.int8)):
        trial, traction = np.zeros_like(base), np.zeros((3, 2))
        q, qt, codes = np.zeros((3, 2)), np.zeros((3, 2, 2)), np.zeros(3, dtype=np.int8)
        assert joint_points_evaluate(params, np.zeros(3, dtype=np.int64), weight, delta, base, trial, traction, q, qt,
                                     codes, np.zeros(1, dtype=np.int64), held) == 0
        out[int(held[0])] = (codes.copy(), traction.copy(), q.copy(), qt.copy(), trial.copy())
    codes, traction, q, qt, trial = out[0]
    assert codes.tolist() == [mc.SLIP, mc.OPEN, mc.STICK]
    assert np.abs(qt[0]).max() > 0 and np.abs(qt[1]).max() > 0
    codes, traction, q, qt, trial = out[1]
    assert codes.tolist() == [mc.STICK] * 3
    np.testing.assert_allclose(traction[:, 0], ks * (delta[:, 0] - base[:, mc.S_PLASTIC_SLIP]), rtol=1e-15)
    np.testing.assert_allclose(traction[:, 1], kn * delta[:, 1], rtol=1e-15)
    np.testing.assert_allclose(q[:, 0], -w * ks * base[:, mc.S_PLASTIC_SLIP], rtol=1e-15)
    assert not q[:, 1].any() and not qt.any()
    np.testing.assert_array_equal(trial[:, mc.S_PLASTIC_SLIP], base[:, mc.S_PLASTIC_SLIP])
    # the sticking point is the same either way
    np.testing.assert_array_equal(out[0][1][2], out[1][1][2])


def test_reevaluating_some_points_equals_a_full_residual_evaluation():
    """``joint_space_reevaluate_points`` (the law again at the points whose held flag changed, the
    condensed residual ``F = delta - delta_y + S (q - q_n)`` updated by their change of joint force)
    equals a full ``joint_space_evaluate_residual`` with the new flags, for a mix of sliding, open and
    sticking points (Tzamtzis & Asteris eqs. 11-12, sec. 3.4) and a non-symmetric S."""
    from masonrydam.materials import mohr_coulomb as mc
    from masonrydam.solvers.joint_space.kernels import joint_space_evaluate_residual, joint_space_reevaluate_points

    rng = np.random.default_rng(11)
    P, dim = 40, 2
    m = P * dim
    ks, kn, tan_phi = 2e10, 5e10, 0.6
    params = np.zeros((1, mc.N_JOINT_PARAMS))
    params[0, mc.P_KS], params[0, mc.P_KN], params[0, mc.P_TAN_PHI] = ks, kn, tan_phi
    params[0, mc.P_COHESION] = 1e5
    index = np.zeros(P, dtype=np.int64)
    weight = rng.uniform(0.1, 0.5, P)
    base = np.zeros((P, mc.N_JOINT_STATE))
    base[:, mc.S_PLASTIC_SLIP] = rng.normal(0.0, 1e-6, P)
    delta = np.column_stack([rng.normal(0.0, 2e-5, P), rng.normal(-5e-6, 8e-6, P)]).ravel()
    delta_y = delta + rng.normal(0.0, 1e-6, m)
    wk = np.repeat(weight, dim) * np.tile([ks, kn], P)
    ST = rng.normal(0.0, 1e-11, (m, m))
    slot = np.arange(m, dtype=np.int64)
    q_n = rng.normal(0.0, 1e3, (P, dim))

    def arrays():
        return (np.zeros_like(base), np.zeros((P, dim)), np.zeros((P, dim)), np.zeros((P, dim, dim)),
                np.zeros(P, dtype=np.int8), np.zeros(1, dtype=np.int64))

    def full(held):
        trial, traction, q, qt, codes, info = out = arrays()
        F, err = np.zeros(m), np.zeros(1)
        assert joint_space_evaluate_residual(params, index, weight, delta, base, trial, traction, q, qt, codes, info,
                                             held, ST, slot, delta_y, q_n, wk, F, err) == 0
        return out, F, err[0]

    held0 = np.zeros(P, dtype=np.int8)
    held0[::5] = 1
    (trial, traction, q, qt, codes, info), F, err = full(held0)
    assert {mc.STICK, mc.SLIP, mc.OPEN} <= set(codes.tolist())
    held1 = held0.copy()
    changed = np.array([0, 3, 7, 10, 21, 33], dtype=np.int64)  # some released, some newly held
    held1[changed] = 1 - held1[changed]
    e1 = np.zeros(1)
    assert joint_space_reevaluate_points(changed, params, index, weight, delta, base, trial, traction, q, qt, codes,
                                         info, held1, ST, slot, wk, F, e1) == 0
    (trial_r, traction_r, q_r, qt_r, codes_r, _), F_r, err_r = full(held1)
    assert not np.array_equal(codes_r, full(held0)[0][4])  # the flags made a difference
    np.testing.assert_array_equal(codes, codes_r)
    np.testing.assert_array_equal(q, q_r)
    np.testing.assert_array_equal(qt, qt_r)
    np.testing.assert_array_equal(traction, traction_r)
    np.testing.assert_allclose(F, F_r, rtol=0, atol=1e-12 * np.abs(F_r).max())
    assert e1[0] == pytest.approx(err_r, rel=1e-12)


@pytest.mark.slow
def test_holding_flipping_points_cuts_the_iterations_of_a_cracking_dam(monkeypatch):
    """When the neck of the Koyna section cracks (first 3 s of El Centro at 0.5 g), points on the
    stick/slip and open/closed boundaries flip state from one Newton iteration to the next. Holding
    them sticking until the others converge, then letting the true law decide, must take far fewer
    iterations and halved steps than plain Newton with line search (FLIPS_BEFORE_HOLD made
    unreachable), and every step must still converge in joint space: a held state is never
    accepted (the caller checks every step against the full residual with the true law)."""
    import masonrydam.solvers.joint_space.condensation as js_module

    held = masonrydam.run(koyna_el_centro(element_size=3.0, dt=0.01, steps=300, output=KOYNA_OUTPUT)).attrs
    monkeypatch.setattr(js_module, "FLIPS_BEFORE_HOLD", 10**9)
    plain = masonrydam.run(koyna_el_centro(element_size=3.0, dt=0.01, steps=300, output=KOYNA_OUTPUT)).attrs
    assert held["dynamic_joint_space_holds"] > 0 and plain["dynamic_joint_space_holds"] == 0
    assert held["dynamic_joint_space_fallbacks"] == 0
    assert held["dynamic_joint_space_steps"] >= 300
    assert held["dynamic_joint_space_iterations"] < 0.5 * plain["dynamic_joint_space_iterations"]
    assert held["dynamic_joint_space_splits"] < plain["dynamic_joint_space_splits"]


def test_no_point_stays_held_after_a_step():
    """Held points are an iteration device of one step: ``solve_step`` starts with none held and leaves
    none held whatever way the step ends (here the iteration raises half-way with points held), so a
    later step never starts from a held law."""
    from types import SimpleNamespace

    from masonrydam.solvers.joint_space import JointSpace

    seen = {}

    def failing_step(*args):
        seen["held_on_entry"] = fake.held.copy()
        fake.held[1:3] = 1
        raise FloatingPointError("NaN in the joint-space residual")

    fake = SimpleNamespace(held=np.ones(4, dtype=np.int8), _solve_step=failing_step, compiled=False, python_steps=0,
                           columns=SimpleNamespace(new_step=lambda: None))
    with pytest.raises(FloatingPointError):
        JointSpace.solve_step(fake, None, None, 1.0)
    assert not seen["held_on_entry"].any()
    assert not fake.held.any()
