"""Large displacements (``[model] kinematics = "large"``): total Lagrangian St.
Venant-Kirchhoff blocks (:mod:`masonrydam.elements.continuum_large`) and joints whose frame turns with
their current mid-surface (:mod:`masonrydam.elements.interface_large`).

Closed forms used:
- rigid motion ``x = Q X + c`` gives ``F = Q``, Green-Lagrange strain 0, no stress and no force (Bathe,
  Finite Element Procedures, 1996, sec. 6.2.2); a homogeneous stretch gives ``S = D E`` with
  ``E = (F^T F - I) / 2`` and Cauchy ``sigma = F S F^T / det F``;
- pure bending of a cantilever by an end rotation theta: the axis rolls into an arc of radius L / theta
  (a full circle at 2 pi) with end moment E I theta / L (Euler's elastica under an end moment; e.g.
  Bisshopp & Drucker 1945, Q. Appl. Math. 3; the classic benchmark of Simo & Vu-Quoc 1986, CMAME 49);
- Housner (1963) free rocking of a rigid block about its corners, the nonlinear equation of motion
  ``theta'' = -(3 g / 4 R) sin(alpha - theta)`` (Housner,
  BSSA 53(2) 1963); its linearisation is what small kinematics gives;
- tilt-table toppling of a block that cannot slide: the resultant of weight and a horizontal body
  force leaves the base at tan(alpha) = b / h (statics of a rigid block, e.g. Housner 1963 sec. 2).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import masonrydam
from masonrydam.elements.continuum import element_tables
from masonrydam.elements.continuum_large import continuum_cauchy_stress, continuum_large_evaluate
from masonrydam.elements.interface import interface_evaluate, interface_tables
from masonrydam.elements.interface_large import interface_large_evaluate
from masonrydam.elements.shapes import reference_nodes
from masonrydam.errors import SceneError
from masonrydam.materials import mohr_coulomb as mc
from masonrydam.materials.elastic import elasticity_matrix
from scenes import tilted_block

G = 9.80665


def _rotation(dim, theta, axis=2):
    c, s = math.cos(theta), math.sin(theta)
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    Q = np.eye(3)
    i, j = [k for k in range(3) if k != axis]
    Q[i, i], Q[i, j], Q[j, i], Q[j, j] = c, -s, s, c
    return Q


# ---- continuum element --------------------------------------------------------------------------------
def _solid(typ, dim, rng):
    X = reference_nodes(typ).astype(float) * 0.7 + rng.normal(0.0, 0.03, (len(reference_nodes(typ)), dim))
    D = np.ascontiguousarray(elasticity_matrix(2e9, 0.25, "plane_strain" if dim == 2 else "3d")[None])
    N, dN, w = element_tables(typ)
    conn = np.arange(len(X))[None, :]

    def evaluate(u):
        nd = X.size
        fe, ke, en, info = np.zeros((1, nd)), np.zeros((1, nd, nd)), np.zeros(1), np.zeros(2, np.int64)
        assert continuum_large_evaluate(X, conn, dN, w, D, np.zeros(1, np.int64), np.ones(1), u, True, fe, ke, en,
                                        info) == 0
        return fe[0], ke[0], en[0]

    def cauchy(u):
        out = np.zeros((1, len(w), 3 if dim == 2 else 6))
        assert continuum_cauchy_stress(X, conn, dN, D, np.zeros(1, np.int64), u, out, np.zeros(2, np.int64)) == 0
        return out[0]

    return X, D, evaluate, cauchy


@pytest.mark.parametrize("typ,dim", [("quad4", 2), ("quad8", 2), ("tri6", 2), ("hex8", 3), ("tet10", 3), ("hex20", 3)])
def test_solid_tangent_energy_and_rigid_rotation(typ, dim):
    rng = np.random.default_rng(7)
    X, D, evaluate, cauchy = _solid(typ, dim, rng)
    u = rng.normal(0.0, 0.05, X.size)  # strains of several per cent and rotations
    f, K, _ = evaluate(u)
    h = 1e-7
    K_fd, grad = np.zeros_like(K), np.zeros(X.size)
    for j in range(X.size):
        up, um = u.copy(), u.copy()
        up[j] += h
        um[j] -= h
        (fp, _, ep), (fm, _, em) = evaluate(up), evaluate(um)
        K_fd[:, j] = (fp - fm) / (2 * h)
        grad[j] = (ep - em) / (2 * h)
    assert np.abs(K - K_fd).max() < 1e-6 * np.abs(K).max()  # tangent = derivative of the force
    assert np.abs(f - grad).max() < 1e-6 * np.abs(f).max()  # force = gradient of the energy (hyperelastic)
    assert np.allclose(K, K.T, atol=1e-9 * np.abs(K).max())
    # a block rotated rigidly by 90 degrees (and moved) has no strain: no force, energy, stress
    Q = _rotation(dim, math.pi / 2)
    u_rigid = (X @ Q.T - X + 0.3).ravel()
    f_r, _, e_r = evaluate(u_rigid)
    assert np.abs(f_r).max() < 1e-12 * np.abs(f).max() and abs(e_r) < 1e-20
    assert np.abs(cauchy(u_rigid)).max() < 1e-14 * 2e9  # Pa: round-off of E = 2e9 Pa
    # the small-strain element is the limit at small displacements
    from masonrydam.elements.continuum import continuum_internal_force

    N, dN, w = element_tables(typ)
    us = 1e-7 * rng.normal(size=X.size)
    fl = np.zeros((1, X.size))
    continuum_internal_force(X, np.arange(len(X))[None, :], dN, w, D, np.zeros(1, np.int64), np.ones(1), us, fl,
                             np.zeros(2, np.int64))
    assert np.abs(evaluate(us)[0] - fl[0]).max() < 1e-5 * np.abs(fl).max()


def test_homogeneous_stretch_and_rotation_gives_the_closed_form_cauchy_stress():
    rng = np.random.default_rng(3)
    X, D, evaluate, cauchy = _solid("quad4", 2, rng)
    lam = 1.2
    Q = _rotation(2, 0.7)
    F = Q @ np.diag([lam, 1.0])
    u = (X @ F.T - X).ravel()
    E = 0.5 * (F.T @ F - np.eye(2))
    S_voigt = D[0] @ np.array([E[0, 0], E[1, 1], 2 * E[0, 1]])
    S = np.array([[S_voigt[0], S_voigt[2]], [S_voigt[2], S_voigt[1]]])
    sigma = F @ S @ F.T / np.linalg.det(F)
    got = cauchy(u)
    for g in range(got.shape[0]):
        np.testing.assert_allclose(got[g], [sigma[0, 0], sigma[1, 1], sigma[0, 1]], rtol=1e-10, atol=1e-3)


# ---- interfaces -------------------------------------------------------------------------------------
FACES = [("line2", 2, "lumped"), ("line3", 2, "gauss"), ("quad4", 3, "lumped"), ("tri3", 3, "gauss"),
         ("quad8", 3, "gauss")]


def _joint(face, dim, scheme, cohesion, ks_r, top_weight=0.5):
    N, dN, w, _ = interface_tables(face, scheme)
    ref = reference_nodes(face).astype(float)
    Xf = np.c_[ref[:, 0] * 0.6, 0.1 * ref[:, 0] ** 2] if dim == 2 else np.c_[ref * 0.5, 0.05 * ref[:, 0] * ref[:, 1]]
    X = np.vstack([Xf, Xf])
    conn = np.arange(len(X))[None, :]
    params = np.ascontiguousarray(mc.joint_params(1e9, 4e8, cohesion, 30.0, cohesion, ks_r)[None, :])
    params[:, mc.P_OPEN_TANGENT] = 0.0
    committed = np.zeros((1, len(w), mc.N_JOINT_STATE))

    def evaluate(u, kernel=interface_large_evaluate):
        trial = np.zeros_like(committed)
        d, t = np.zeros((1, len(w), dim)), np.zeros((1, len(w), dim))
        fe, ke = np.zeros((1, X.size)), np.zeros((1, X.size, X.size))
        extra = (top_weight,) if kernel is interface_large_evaluate else ()
        assert kernel(X, conn, u, N, dN, w, np.ones(1), params, np.zeros(1, np.int64), committed, trial, d, t, fe, ke,
                      True, np.zeros(1, np.int64), *extra) == 0
        return fe[0], ke[0], d[0], trial[0, :, mc.S_CODE]

    return X, evaluate


@pytest.mark.parametrize("face,dim,scheme", FACES)
@pytest.mark.parametrize("cohesion,ks_r", [(1e9, 0.0), (0.0, 1e6)])  # sticking; slipping and open points
@pytest.mark.parametrize("top_weight", [0.5, 0.0])  # frame on the mid-surface; on the bottom face
def test_joint_tangent_rigid_rotation_and_small_limit(face, dim, scheme, cohesion, ks_r, top_weight):
    rng = np.random.default_rng(1)
    X, evaluate = _joint(face, dim, scheme, cohesion, ks_r, top_weight)
    u = rng.normal(0.0, 1e-3, X.size)
    f, K, _, codes = evaluate(u)
    if cohesion == 0.0:
        assert (codes != mc.STICK).any()
    h = 1e-9
    K_fd = np.zeros_like(K)
    for j in range(X.size):
        up, um = u.copy(), u.copy()
        up[j] += h
        um[j] -= h
        K_fd[:, j] = (evaluate(up)[0] - evaluate(um)[0]) / (2 * h)
    if np.abs(K).max() > 0:
        assert np.abs(K - K_fd).max() < 1e-6 * np.abs(K).max()
    # 90 degrees about z (3D) with a translation: no relative displacement, no force
    Q = _rotation(dim, math.pi / 2)
    f_r, _, d_r, _ = evaluate((X @ Q.T - X + 0.2).ravel())
    assert np.abs(d_r).max() < 1e-15 and np.abs(f_r).max() < 1e-7
    # at small displacements the frame is the reference one: the small-displacement interface
    us = rng.normal(0.0, 1e-9, X.size)
    d_large, d_small = evaluate(us)[2], evaluate(us, interface_evaluate)[2]
    assert np.abs(d_large - d_small).max() < 1e-6 * np.abs(d_small).max()


@pytest.mark.parametrize("theta", [0.3, 1.2, 2.5])
def test_joint_opening_and_slip_are_measured_across_the_turned_joint(theta):
    """A 2D joint turned by theta with its top face moved by (s, n) in the turned frame reads slip s and
    opening n at every inclination (rotation invariance at large angles)."""
    X, evaluate = _joint("line2", 2, "lumped", 0.0, 1e6)
    Q = _rotation(2, theta)
    s, n = 2e-3, 5e-3
    x = X @ Q.T
    x[2:] += Q @ np.array([s, n])
    _, _, d, codes = evaluate((x - X).ravel())
    np.testing.assert_allclose(d, [[s, n], [s, n]], rtol=1e-10)
    assert (codes == mc.OPEN).all()


# ---- structures -------------------------------------------------------------------------------------
def _model(scene):
    from masonrydam.scene import build_mesh, build_model
    from masonrydam.scene.scene import as_scene

    sc = as_scene(scene)
    mesh = build_mesh(sc.normalized, sc.base_dir)
    return mesh, build_model(sc.normalized, mesh)


def _node_dofs(nodes, dim):
    return (np.asarray(nodes)[:, None] * dim + np.arange(dim)).ravel()


@pytest.mark.slow
def test_cantilever_under_an_end_rotation_rolls_into_a_circle():
    """A plane-strain cantilever (nu = 0) whose end section is turned by theta up to 2 pi: the axis is an
    arc of radius L / theta, a full circle at the end, with the end moment E I theta / L."""
    from masonrydam.solvers.static.stepping import SolverSettings, StaticSolver, StaticStage

    L, h, E = 5.0, 0.1, 1e9
    scene = {"model": {"name": "cantilever", "thickness": 1.0, "kinematics": "large", "hypothesis": "plane_strain"},
             "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.05, "order": 2, "blocks": [
                 {"x0": 0.0, "y0": 0.0, "x1": L, "y1": h, "group": "beam"}]}},
             "materials": {"beam": {"youngs_modulus": E, "poisson_ratio": 0.0, "density": 1000.0}},
             "joints": {}, "stages": [{"name": "s"}]}
    mesh, model = _model(scene)
    X = model.coords
    left = np.nonzero(np.abs(X[:, 0]) < 1e-9)[0]
    right = np.nonzero(np.abs(X[:, 0] - L) < 1e-9)[0]
    yc = h / 2

    def end_position(theta):
        eta = X[right, 1] - yc
        if theta == 0.0:
            return X[right].copy()
        k = theta / L
        return np.c_[math.sin(theta) / k - eta * math.sin(theta),
                     yc + (1 - math.cos(theta)) / k + eta * math.cos(theta)]

    supports = np.zeros(model.n_dof, bool)
    supports[_node_dofs(left, 2)] = True
    prescribed = np.zeros(model.n_dof, bool)
    prescribed[_node_dofs(right, 2)] = True
    n_stages = 40
    thetas = np.linspace(0.0, 2 * math.pi, n_stages + 1)
    stages = []
    for k in range(1, n_stages + 1):
        inc = np.zeros(model.n_dof)
        inc[_node_dofs(right, 2)] = (end_position(thetas[k]) - end_position(thetas[k - 1])).ravel()
        stages.append(StaticStage(f"turn{k}", 1, np.zeros(model.n_dof), prescribed, inc, supports))
    solver = StaticSolver(model, SolverSettings(joint_space="off"))
    u = solver.run(stages)
    u = u[0] if isinstance(u, tuple) else u
    x = X + u.reshape(-1, 2)
    axis = np.nonzero(np.abs(X[:, 1] - yc) < 1e-9)[0]
    R = L / (2 * math.pi)
    centre = np.array([0.0, yc + R])
    radius = np.linalg.norm(x[axis] - centre, axis=1)
    # (within 0.5 %: the end held on the inextensible-axis circle takes the small axial force of the St.
    # Venant-Kirchhoff section, whose lever arm makes the curvature vary by a few tenths of a per cent)
    assert np.abs(radius / R - 1).max() < 5e-3
    mid = axis[np.argmin(np.abs(X[axis, 0] - L / 2))]
    np.testing.assert_allclose(x[mid], [0.0, yc + 2 * R], atol=1e-2 * R)  # diametrically opposite the clamp
    # the end moment about the end section's centre: sum of (x - x_c) x f over the end nodes
    f_int, _ = model.evaluate(u, want_tangent=False)
    fr = f_int.reshape(-1, 2)[right]
    xc = x[right][np.argmin(np.abs(X[right, 1] - yc))]
    r = x[right] - xc
    moment = float(np.sum(r[:, 0] * fr[:, 1] - r[:, 1] * fr[:, 0]))
    assert moment == pytest.approx(E * h**3 / 12 * 2 * math.pi / L, rel=0.02)


def _rocking_scene(kinematics, dt, duration, w0, frame="mid_surface"):
    return {"model": {"name": "rocking", "thickness": 1.0, "kinematics": kinematics},
            "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
                {"x0": 0.0, "y0": -0.25, "x1": 0.5, "y1": 0.0, "group": "base"},
                {"x0": 0.0, "y0": 0.0, "x1": 0.5, "y1": 2.0, "group": "block"}]}},
            "materials": {g: {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2400.0}
                          for g in ("base", "block")},
            "joints": {"joints": dict({"normal_stiffness": 1e12, "shear_stiffness": 1e12, "friction_angle": 60.0},
                                      **({"frame": frame} if kinematics == "large" else {}))},
            "supports": [{"set": "base"}],
            "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                       {"name": "rock", "type": "dynamic", "dt": dt, "duration": duration,
                        "integrator": "newmark_average", "mass": "consistent",
                        "initial_velocity": {"groups": ["block"], "angular_velocity": w0,
                                             "rotation_center": [0.0, 0.0]},
                        "output": {"stride": 1}}]}


def _half_cycle(ds):
    """Time (s) from the launch until the block is upright again, and its largest rotation (rad)."""
    dyn = ds.where(~np.isnan(ds.time), drop=True)
    x, y = ds.x.values, ds.y.values
    corners = [np.nonzero((np.abs(x - xc) < 1e-9) & (np.abs(y) < 1e-9))[0] for xc in (0.0, 0.5)]
    d = dyn.displacement.values
    # block nodes of the two bottom corners: the one of each pair that moves most
    left = corners[0][np.argmax(np.abs(d[:, corners[0], 1]).max(axis=0))]
    right = corners[1][np.argmax(np.abs(d[:, corners[1], 1]).max(axis=0))]
    theta = np.arctan2(d[:, right, 1] - d[:, left, 1], 0.5 + d[:, right, 0] - d[:, left, 0])
    t = dyn.time.values - dyn.time.values[0]
    k = int(np.argmax(theta))
    j = k + int(np.argmax(theta[k:] <= 0.0))
    assert j > k, "the block did not come back upright"
    return t[j - 1] + (t[j] - t[j - 1]) * theta[j - 1] / (theta[j - 1] - theta[j]), float(theta.max())


@pytest.mark.parametrize("frame", ["mid_surface", "bottom"])
@pytest.mark.slow
@pytest.mark.reference
def test_housner_free_rocking_half_cycle(frame):
    """Housner (1963): a 0.5 x 2.0 m block launched about its corner so that it reaches half its
    slenderness angle comes back upright within 3 % of the nonlinear equation of motion (1 % asserted, at two
    time steps); with small kinematics the same block comes back about a third too early."""
    b, h = 0.25, 1.0
    R, alpha = math.hypot(b, h), math.atan(b / h)
    p2 = 3 * G / (4 * R)
    w0 = math.sqrt(2 * p2 * (math.cos(alpha / 2) - math.cos(alpha)))  # energy to reach alpha / 2

    def upright(t, y):
        return y[0]
    upright.terminal, upright.direction = True, -1
    sol = solve_ivp(lambda t, y: [y[1], -p2 * math.sin(alpha - y[0])], [0.0, 5.0], [0.0, w0], events=upright,
                    rtol=1e-12, atol=1e-14, first_step=1e-6)
    t_ref = float(sol.t_events[0][0])
    errors = []
    for dt in (0.005, 0.0025):
        t_half, theta_max = _half_cycle(masonrydam.run(_rocking_scene("large", dt, 1.05 * t_ref, w0, frame)))
        errors.append(abs(t_half / t_ref - 1))
        assert t_half == pytest.approx(t_ref, rel=0.01)  # (3 % is the acceptance; measured 0.14 %)
        assert theta_max == pytest.approx(alpha / 2, rel=0.01)
    assert abs(errors[1] - errors[0]) < 0.005  # the same at half the step: converged in dt
    t_small, _ = _half_cycle(masonrydam.run(_rocking_scene("small", 0.005, 1.05 * t_ref, w0)))
    assert t_small < 0.8 * t_ref  # linearised rotation: the error of small kinematics


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.slow
@pytest.mark.reference
def test_tilt_table_toppling_when_sliding_is_prevented(dim):
    """Weight plus a horizontal body force lambda g (a table tilted by tan(alpha) = lambda): a block that
    cannot slide (tan(phi) = 5.7 > b/h) topples at tan(alpha) = b/h = 0.25 (2D, and a 0.5 x 0.5 x 2 m
    prism on 8-node joints in 3D)."""
    ds = masonrydam.run(tilted_block("large", dim))
    tan_alpha = 0.5 * ds.attrs["limit_load_factor"]
    assert tan_alpha == pytest.approx(0.25, rel=0.01)
    assert "no equilibrium" in ds.attrs["limit_state"]
    if dim == 2:  # (the 2D diagnosis names the mechanism)
        assert "rocking" in ds.attrs["limit_state"]
    assert "large displacements" in ds.attrs["simulated_effects"]


def test_bad_large_kinematics_input():
    s = tilted_block("huge")
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "model.kinematics"
    s = tilted_block("large")
    s["model"]["hypothesis"] = "plane_strain"
    s["materials"]["block"].update({"law": "von_mises", "yield_stress": 1e7})
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.block.law" and "small-strain" in str(err.value)
    s = tilted_block("small")
    s["joints"]["joints"]["frame"] = "bottom"
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "joints.joints.frame"
    s = tilted_block("large")
    s["joints"]["joints"]["frame"] = "top"
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "joints.joints.frame"
    s = tilted_block("large")
    s["materials"]["block"]["integration"] = "reduced"  # quad4: one point, hourglass modes
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.block.integration" and "hourglass" in str(err.value)


def _sliding_scene(kinematics, v0, frame="bottom"):
    return {"model": {"name": "far_slide", "thickness": 1.0, "kinematics": kinematics},
            "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
                {"x0": 0.0, "y0": -0.25, "x1": 3.0, "y1": 0.0, "group": "base"},
                {"x0": 0.0, "y0": 0.0, "x1": 1.0, "y1": 0.5, "group": "block"}]}},
            "materials": {g: {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": 2400.0}
                          for g in ("base", "block")},
            "joints": {"joints": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": 30.0,
                                  "frame": frame}},
            "supports": [{"set": "base"}],
            "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                       {"name": "slide", "type": "dynamic", "dt": 0.0025, "duration": 0.6, "integrator": "hht",
                        "initial_velocity": {"groups": ["block"], "velocity": [v0, 0.0]}, "output": {"stride": 10}}]}


@pytest.mark.slow
def test_block_sliding_far_on_a_long_joint():
    """A block launched at 3 m/s on a rigid, straight Coulomb joint (tan(phi) = 0.577) slides
    v0^2 / (2 g tan(phi)) = 0.795 m, three element lengths, without turning (Newton's second law with Coulomb
    friction). With the frame on the supporting (bottom) face, 0.5 % farther at dt = 2.5 ms (the
    integrator's error; small kinematics the same). With the mid-surface frame the node pairs, 0.8 m apart
    by then, turn the normal force into a couple on the block: it tips by about 2 degrees and slides 1.6 %
    farther (the reason for ``frame = "bottom"``). The node-to-node joint keeps the partners it was meshed
    with; the run says so (a warning names the joint set and how far it slid)."""
    v0 = 3.0
    d = v0**2 / (2 * G * math.tan(math.radians(30.0)))
    with pytest.warns(masonrydam.errors.AccuracyWarning, match="slid up to 3"):
        ds = masonrydam.run(_sliding_scene("large", v0))
    top = ds.y.values > 0.49
    u = ds.displacement.sel(component="x").values[-1, top]
    assert u.mean() == pytest.approx(d, rel=0.01)
    assert np.ptp(u) < 1e-6 * d  # no turning: the top edge moved as one
    assert "joint_slip_warnings" in ds.attrs
    with pytest.warns(masonrydam.errors.AccuracyWarning):
        tipped = masonrydam.run(_sliding_scene("large", v0, frame="mid_surface"))
    u = tipped.displacement.sel(component="x").values[-1, top]
    assert np.ptp(u) > 1e-4  # m: the top edge of a block turned by ~2 degrees shortens by ~0.5 mm


@pytest.mark.parametrize("top_weight", [0.5, 0.0])
def test_joint_recloses_after_a_large_relative_rotation(top_weight):
    """A 2D joint whose top face is swung open by 60 degrees about one end reads at the other end the gap
    across its turned frame, and when the face comes back pressed by 1e-5 m it is in contact again with
    the compressive traction kn 1e-5 at both ends: re-contact from a large relative rotation."""
    X, _ = _joint("line2", 2, "lumped", 0.0, 1e6)
    X = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0], [1.0, 0.0]])
    N, dN, w, _ = interface_tables("line2", "lumped")
    params = np.ascontiguousarray(mc.joint_params(1e9, 4e8, 0.0, 30.0, 0.0, 1e6)[None, :])
    conn = np.arange(4)[None, :]

    def evaluate(u, committed):
        trial = np.zeros_like(committed)
        d, t = np.zeros((1, 2, 2)), np.zeros((1, 2, 2))
        fe, ke = np.zeros((1, 8)), np.zeros((1, 8, 8))
        assert interface_large_evaluate(X, conn, u, N, dN, w, np.ones(1), params, np.zeros(1, np.int64), committed,
                                        trial, d, t, fe, ke, True, np.zeros(1, np.int64), top_weight) == 0
        return d[0], t[0], trial

    Q = _rotation(2, math.radians(60.0))
    x = X.copy()
    x[2:] = X[2:] @ Q.T  # the top face turned about the common end (0, 0)
    d, t, state = evaluate((x - X).ravel(), np.zeros((1, 2, mc.N_JOINT_STATE)))
    # the far end: the mid-surface frame (turned by 30 deg) reads the chord 2 L sin(30 deg) = L as opening and no
    # slip; the bottom-face frame reads L sin(60 deg) of opening and L (cos(60 deg) - 1) of slip
    assert state[0, 1, mc.S_CODE] == mc.OPEN and np.abs(t[1]).max() == 0.0
    if top_weight == 0.5:
        np.testing.assert_allclose(d[1], [0.0, 1.0], atol=1e-12)
    else:
        np.testing.assert_allclose(d[1], [-0.5, math.sqrt(3) / 2], atol=1e-12)
    u_back = np.zeros(8)
    u_back[5] = u_back[7] = -1e-5  # back down and pressed
    d, t, state = evaluate(u_back, state)
    assert (state[0, :, mc.S_CODE] != mc.OPEN).all()  # in contact (the far end slides back to where it opened)
    np.testing.assert_allclose(t[:, 1], -1e9 * 1e-5, rtol=1e-9)
