"""Tests of the zero-thickness interface elements (masonrydam.elements.interface).

Sources: Tzamtzis & Asteris, sec. 3.3, eqs. 1-10 (relative displacement top minus
bottom, B = [-N I, N I], K = integral of B^T k B, transformation to global axes) and sec. 3.4
(joint law); Schellekens & de Borst (1993), IJNME 36:43-66 (nodal / Newton-Cotes integration gives
node-pair springs, Gauss integration couples the nodes); conventions of docs/architecture.md.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from masonrydam.elements.interface import (
    interface_evaluate,
    interface_geometry,
    interface_rule,
    interface_tables,
)
from masonrydam.elements.shapes import shape_functions
from masonrydam.errors import STATUS_BAD_GEOMETRY, STATUS_NAN, STATUS_OK
from masonrydam.materials.mohr_coulomb import N_JOINT_STATE, OPEN, S_CODE, SLIP, STICK, joint_params

KN = 5.0e10  # Pa/m
KS = 2.0e10  # Pa/m
PHI = 35.0
TAN_PHI = math.tan(math.radians(PHI))
C = 1.0e5


def rot2(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def rot3(axis, deg):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = math.radians(deg)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(a) * K + (1 - math.cos(a)) * K @ K


def evaluate(coords, conn, u, tables, params, committed=None, thickness=None, want_tangent=True):
    """Run interface_evaluate on a group; returns a dict of outputs and checks the committed state
    is never modified."""
    N, dN, w = tables[:3]
    coords = np.ascontiguousarray(coords, dtype=np.float64)
    conn = np.ascontiguousarray(np.atleast_2d(conn), dtype=np.int64)
    n_elem, dim, nip = conn.shape[0], coords.shape[1], N.shape[0]
    ndof = conn.shape[1] * dim
    params = np.atleast_2d(params)
    committed = np.zeros((n_elem, nip, N_JOINT_STATE)) if committed is None else committed
    before = committed.copy()
    out = dict(
        trial=np.zeros((n_elem, nip, N_JOINT_STATE)),
        delta=np.zeros((n_elem, nip, dim)),
        traction=np.zeros((n_elem, nip, dim)),
        fe=np.full((n_elem, ndof), np.nan),
        ke=np.full((n_elem, ndof, ndof), np.nan) if want_tangent else np.empty((0, 0, 0)),
        info=np.full(1, -1, dtype=np.int64),
    )
    th = np.ones(n_elem) if thickness is None else np.full(n_elem, float(thickness))
    out["status"] = interface_evaluate(
        coords, conn, np.asarray(u, dtype=np.float64), N, dN, w, th, params,
        np.zeros(n_elem, dtype=np.int64), committed, out["trial"], out["delta"], out["traction"],
        out["fe"], out["ke"], want_tangent, out["info"],
    )
    assert np.array_equal(committed, before), "kernel modified state_committed"
    return out


def fd_stiffness(coords, conn, u, tables, params, committed, h):
    u = np.asarray(u, dtype=np.float64)
    dofs = [n * coords.shape[1] + k for n in conn for k in range(coords.shape[1])]
    K = np.zeros((len(dofs), len(dofs)))
    for j, d in enumerate(dofs):
        up = u.copy()
        um = u.copy()
        up[d] += h
        um[d] -= h
        fp = evaluate(coords, conn, up, tables, params, committed, want_tangent=False)["fe"][0]
        fm = evaluate(coords, conn, um, tables, params, committed, want_tangent=False)["fe"][0]
        K[:, j] = (fp - fm) / (2 * h)
    return K


def line_interface(face, p0, p1, curvature_sag=0.0):
    """Single interface element with coincident faces along p0 -> p1 (line3: middle node displaced
    by ``curvature_sag`` along the left normal). Nodes: bottom 0..ns-1, top ns..2ns-1."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    pts = [p0, p1]
    if face == "line3":
        t = (p1 - p0) / np.linalg.norm(p1 - p0)
        pts.append(0.5 * (p0 + p1) + curvature_sag * np.array([-t[1], t[0]]))
    face_nodes = np.array(pts)
    coords = np.vstack([face_nodes, face_nodes])
    ns = len(pts)
    return coords, np.arange(2 * ns)


def set_relative(coords, conn, base_u, rel):
    """Global displacement: bottom nodes base_u(x), top nodes base_u(x) + rel (dim,)."""
    dim = coords.shape[1]
    ns = len(conn) // 2
    u = np.zeros(coords.shape[0] * dim)
    for i, n in enumerate(conn):
        u[n * dim : (n + 1) * dim] = base_u(coords[n]) + (rel if i >= ns else 0.0)
    return u


def set_relative_local(coords, conn, face, d_loc):
    """Top-node displacement = d_loc (local [s, n]) in the frame of each node (so that a curved
    element has the same local relative displacement at every node); bottom nodes fixed."""
    N, dN, w, _ = interface_tables(face, "lumped")  # points on the nodes, in node order
    nip = len(w)
    pts = np.zeros((1, nip, 2))
    frame = np.zeros((1, nip, 2, 2))
    jw = np.zeros((1, nip))
    info = np.zeros(1, np.int64)
    assert interface_geometry(coords, np.asarray(conn, np.int64)[None], N, dN, w, pts, frame, jw, info) == 0
    u = np.zeros(coords.size)
    ns = len(conn) // 2
    for i in range(ns):
        n = conn[ns + i]
        u[2 * n : 2 * n + 2] = frame[0, i].T @ d_loc
    return u


# ------------------------------------------------------------------ rules


def test_rule_weights_simpson_and_lumped():
    p, w = interface_rule("line3", "lobatto")
    np.testing.assert_allclose(p[:, 0], [-1, 0, 1], atol=1e-15)
    np.testing.assert_allclose(w, [1 / 3, 4 / 3, 1 / 3], rtol=1e-14)
    p, w = interface_rule("line3")  # default lumped: node order ends, middle
    np.testing.assert_array_equal(p[:, 0], [-1, 1, 0])
    np.testing.assert_allclose(w, [1 / 3, 1 / 3, 4 / 3], rtol=1e-15)
    # lumped weight = integral of the node's shape function (compare with a high-order Gauss rule)
    for face in ("line2", "line3", "quad4", "tri3"):
        p, w = interface_rule(face, "lumped")
        gp, gw = interface_rule(face, "gauss", 6 if face == "tri3" else 4)
        Ng, _ = shape_functions(face, gp)
        np.testing.assert_allclose(w, Ng.T @ gw, rtol=1e-12)
        # nodal rule: N at the points is the identity
        Np, _ = shape_functions(face, p)
        np.testing.assert_allclose(Np, np.eye(len(w)), atol=1e-14)
    p, w = interface_rule("line2", "gauss")
    np.testing.assert_allclose(np.abs(p[:, 0]), 1 / math.sqrt(3))
    with pytest.raises(ValueError, match="quad8"):
        interface_rule("quad8", "lumped")
    with pytest.raises(ValueError, match="scheme"):
        interface_rule("line2", "simpson")
    with pytest.raises(ValueError, match="face type"):
        interface_rule("hex8")


# ------------------------------------------------------------------ rigid body motion


@pytest.mark.parametrize("face, scheme", [("line2", "lumped"), ("line2", "gauss"), ("line3", "gauss"), ("line3", "lumped")])
def test_rigid_body_motion_zero_force(face, scheme):
    params = joint_params(KN, KS, C, PHI, 1e5)
    tables = interface_tables(face, scheme)
    coords, conn = line_interface(face, [0.3, -0.2], [1.4, 0.5], curvature_sag=0.1)
    for centre in ([0.0, 0.0], [5.0, -3.0], [0.8, 0.1]):
        for theta in (1e-4, -3e-3):
            for trans in ([0.0, 0.0], [1e-3, -2e-3]):
                # infinitesimal rotation theta about `centre` plus a translation, same on both faces
                def base(x, c=np.array(centre), th=theta, tr=np.array(trans)):
                    r = x - c
                    return tr + th * np.array([-r[1], r[0]])

                u = set_relative(coords, conn, base, np.zeros(2))
                out = evaluate(coords, conn, u, tables, params)
                assert out["status"] == STATUS_OK
                np.testing.assert_allclose(out["delta"], 0.0, atol=1e-18)
                np.testing.assert_allclose(out["fe"], 0.0, atol=1e-6)


def test_rigid_body_motion_zero_force_3d():
    params = joint_params(KN, KS, C, PHI)
    tables = interface_tables("quad4", "gauss")
    Q = rot3([1, 2, 0.5], 40)
    face = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], float) @ Q.T
    coords = np.vstack([face, face])
    conn = np.arange(8)
    w = np.array([1e-3, -2e-3, 5e-4])
    u = set_relative(coords, conn, lambda x: np.array([1e-3, 2e-3, -1e-3]) + np.cross(w, x - 1.0), np.zeros(3))
    out = evaluate(coords, conn, u, tables, params)
    assert out["status"] == STATUS_OK
    np.testing.assert_allclose(out["fe"], 0.0, atol=1e-6)


# ------------------------------------------------------------------ patch test


@pytest.mark.parametrize("face, scheme", [("line2", "lumped"), ("line2", "gauss"), ("line3", "lumped"), ("line3", "gauss")])
def test_patch_uniform_traction(face, scheme):
    params = joint_params(KN, KS, 0.0, PHI)
    tables = interface_tables(face, scheme)
    ang = 30.0
    Q = rot2(ang)
    L, h = 0.8, 0.25
    coords, conn = line_interface(face, [0.1, 0.2], np.array([0.1, 0.2]) + L * Q[:, 0])
    d_loc = np.array([2e-6, -3e-6])  # stick, compression
    rel = Q @ d_loc
    u = set_relative(coords, conn, lambda x: np.array([1e-3, 2e-3]), rel)
    out = evaluate(coords, conn, u, tables, params, thickness=h)
    assert out["status"] == STATUS_OK
    t_loc = np.array([KS * d_loc[0], KN * d_loc[1]])
    np.testing.assert_allclose(out["delta"][0], np.tile(d_loc, (len(tables[2]), 1)), rtol=1e-12)
    np.testing.assert_allclose(out["traction"][0], np.tile(t_loc, (len(tables[2]), 1)), rtol=1e-12)
    fe = out["fe"][0].reshape(-1, 2)
    ns = len(conn) // 2
    total = Q @ t_loc * L * h
    np.testing.assert_allclose(fe[ns:].sum(axis=0), total, rtol=1e-12)
    np.testing.assert_allclose(fe[:ns].sum(axis=0), -total, rtol=1e-12)
    # split among the nodes as the integrals of the shape functions (= lumped weights / 2)
    share = interface_rule(face, "lumped")[1] / 2.0
    np.testing.assert_allclose(fe[ns:], np.outer(share, total), rtol=1e-12, atol=1e-12 * abs(total).max())
    if face == "line3":
        np.testing.assert_allclose(share, [1 / 6, 1 / 6, 2 / 3])


# ------------------------------------------------------------------ consistent tangent vs finite differences


def _states(ns_int, code):
    s = np.zeros((1, ns_int, N_JOINT_STATE))
    s[..., S_CODE] = code
    return s


@pytest.mark.parametrize("regime", ["stick", "slip", "slip_residual", "open"])
@pytest.mark.parametrize("face, scheme", [("line2", "lumped"), ("line2", "gauss"), ("line3", "gauss"), ("line3", "lumped")])
def test_tangent_matches_finite_difference(face, scheme, regime):
    ks_r = 0.2 * KS if regime == "slip_residual" else 0.0
    params = joint_params(KN, KS, C, PHI, 2e5, ks_r)
    tables = interface_tables(face, scheme)
    # line3: curved (circular-arc-like) interface, sag 15% of the chord
    coords, conn = line_interface(face, [0.0, 0.0], [1.0, 0.4], curvature_sag=0.15)
    rng = np.random.default_rng(7)
    ns = len(conn) // 2
    if regime == "stick":
        d_loc = np.array([1e-7, -2e-6])
        jitter = 1e-8
    elif regime == "open":
        d_loc = np.array([3e-5, 2e-4])
        jitter = 1e-6
    else:
        d_loc = np.array([3e-4, -2e-6])
        jitter = 2e-7
    u = set_relative_local(coords, conn, face, d_loc)
    u[ns * 2 :] += jitter * rng.standard_normal(ns * 2)  # non-uniform relative displacement
    committed = np.zeros((1, len(tables[2]), N_JOINT_STATE))
    out = evaluate(coords, conn, u, tables, params, committed)
    assert out["status"] == STATUS_OK
    codes = out["trial"][0, :, S_CODE]
    expected = {"stick": STICK, "open": OPEN}.get(regime, SLIP)
    assert np.all(codes == expected), codes
    K_fd = fd_stiffness(coords, conn, u, tables, params, committed, h=1e-11)
    scale = np.abs(out["ke"][0]).max() if regime != "open" else KN
    np.testing.assert_allclose(out["ke"][0], K_fd, rtol=1e-5, atol=1e-6 * scale)
    if regime == "open":
        assert np.all(out["ke"][0] == 0.0) and np.all(out["fe"][0] == 0.0)
    if regime.startswith("slip"):
        assert not np.allclose(out["ke"][0], out["ke"][0].T)  # non-associated friction
    if regime == "stick":
        np.testing.assert_allclose(out["ke"][0], out["ke"][0].T, rtol=1e-12, atol=1e-9 * scale)


def test_tangent_finite_difference_3d_quad4_slip():
    params = joint_params(KN, KS, C, PHI, 0.0, 0.1 * KS)
    tables = interface_tables("quad4", "gauss")
    Q = rot3([0.3, 1, 0.2], 25)
    face = np.array([[0, 0, 0], [1.2, 0.1, 0], [1.0, 0.9, 0.05], [-0.1, 1.0, 0]], float) @ Q.T
    coords = np.vstack([face, face])
    conn = np.arange(8)
    rng = np.random.default_rng(3)
    rel = Q @ np.array([2e-4, -1.5e-4, -5e-5])
    u = set_relative(coords, conn, lambda x: np.zeros(3), rel)
    u[12:] += 1e-7 * rng.standard_normal(12)
    committed = np.zeros((1, 4, N_JOINT_STATE))
    out = evaluate(coords, conn, u, tables, params, committed)
    assert out["status"] == STATUS_OK and np.all(out["trial"][0, :, S_CODE] == SLIP)
    K_fd = fd_stiffness(coords, conn, u, tables, params, committed, h=1e-11)
    np.testing.assert_allclose(out["ke"][0], K_fd, rtol=1e-5, atol=1e-6 * np.abs(out["ke"][0]).max())


# ------------------------------------------------------------------ rotation invariance


@pytest.mark.parametrize("face", ["line2", "line3"])
def test_rotation_invariance(face):
    params = joint_params(KN, KS, C, PHI, 0.0, 0.1 * KS)
    tables = interface_tables(face, "gauss")
    coords0, conn = line_interface(face, [0.0, 0.0], [1.0, 0.0], curvature_sag=0.1)
    rng = np.random.default_rng(11)
    u0 = 1e-4 * rng.standard_normal(coords0.size)
    u0[1::2] -= 2e-4  # mostly compressed, sliding
    ref = evaluate(coords0, conn, u0, tables, params)
    assert ref["status"] == STATUS_OK
    for ang in (0.0, 30.0, 45.0, 90.0, 137.0):
        Q = rot2(ang)
        coords = coords0 @ Q.T + np.array([3.0, -1.0])
        u = (u0.reshape(-1, 2) @ Q.T).ravel()
        out = evaluate(coords, conn, u, tables, params)
        assert out["status"] == STATUS_OK
        np.testing.assert_allclose(out["delta"], ref["delta"], rtol=1e-9, atol=1e-18)
        np.testing.assert_allclose(out["traction"], ref["traction"], rtol=1e-9, atol=1e-3)
        np.testing.assert_array_equal(out["trial"][..., S_CODE], ref["trial"][..., S_CODE])
        fe_rot = (ref["fe"][0].reshape(-1, 2) @ Q.T).ravel()
        np.testing.assert_allclose(out["fe"][0], fe_rot, rtol=1e-9, atol=1e-9 * np.abs(fe_rot).max())
        Qb = np.kron(np.eye(len(conn)), Q)
        np.testing.assert_allclose(out["ke"][0], Qb @ ref["ke"][0] @ Qb.T, rtol=1e-9, atol=1e-9 * np.abs(ref["ke"]).max())


@pytest.mark.parametrize("scheme", ["lumped", "gauss"])
def test_3d_tilted_quad4_same_local_tractions(scheme):
    params = joint_params(KN, KS, C, PHI)
    tables = interface_tables("quad4", scheme)
    flat = np.array([[0, 0, 0], [2, 0, 0], [2, 1.5, 0], [0, 1.5, 0]], float)
    d_loc = np.array([1e-6, -2e-6, -3e-6])  # [s1, s2, n]: stick, compression
    # flat face: e1 = x, n = z, e2 = y
    u_flat = set_relative(np.vstack([flat, flat]), np.arange(8), lambda x: np.zeros(3), d_loc)
    ref = evaluate(np.vstack([flat, flat]), np.arange(8), u_flat, tables, params)
    assert ref["status"] == STATUS_OK
    t_loc = np.array([KS * d_loc[0], KS * d_loc[1], KN * d_loc[2]])
    np.testing.assert_allclose(ref["traction"][0], np.tile(t_loc, (4, 1)), rtol=1e-12)
    fe = ref["fe"][0].reshape(-1, 3)
    np.testing.assert_allclose(fe[4:].sum(axis=0), t_loc * 3.0, rtol=1e-12)  # area 2 x 1.5
    for axis, ang in (([1, 0, 0], 30.0), ([1, 1, 0], 60.0), ([0.2, -0.5, 1], 137.0)):
        Q = rot3(axis, ang)
        face = flat @ Q.T + 1.0
        coords = np.vstack([face, face])
        u = (u_flat.reshape(-1, 3) @ Q.T).ravel()
        out = evaluate(coords, np.arange(8), u, tables, params)
        assert out["status"] == STATUS_OK
        np.testing.assert_allclose(out["traction"], ref["traction"], rtol=1e-9)
        np.testing.assert_allclose(out["fe"][0], (fe @ Q.T).ravel(), rtol=1e-9, atol=1e-9 * np.abs(fe).max())
    # geometry kernel: frame rows = rotated [e1, e2, n], tributary areas sum to the face area
    Q = rot3([0.2, -0.5, 1], 137.0)
    face = flat @ Q.T
    N, dN, w, _ = tables
    pts = np.zeros((1, 4, 3))
    frame = np.zeros((1, 4, 3, 3))
    jw = np.zeros((1, 4))
    info = np.zeros(1, np.int64)
    st = interface_geometry(np.vstack([face, face]), np.arange(8)[None], N, dN, w, pts, frame, jw, info)
    assert st == STATUS_OK
    for g in range(4):
        np.testing.assert_allclose(frame[0, g], Q.T, atol=1e-14)  # rows = Q e_x, Q e_y, Q e_z
    assert jw.sum() == pytest.approx(3.0)


# ------------------------------------------------------------------ integration scheme and coupling pattern


def _elastic_line2_ke(scheme):
    params = joint_params(KN, KS)
    coords, conn = line_interface("line2", [0.0, 0.0], [2.0, 0.0])
    out = evaluate(coords, conn, np.zeros(8), interface_tables("line2", scheme), params, thickness=0.5)
    assert out["status"] == STATUS_OK
    return out["ke"][0]


@pytest.mark.reference
def test_nodal_integration_decouples_node_pairs():
    """Schellekens & de Borst (1993): with nodal (lumped / Newton-Cotes) integration the interface is
    a set of node-pair springs (bottom i couples only with top i); Gauss integration couples
    neighbouring nodes (consistent matrix L/6 [[2, 1], [1, 2]])."""
    L, h = 2.0, 0.5
    k = np.diag([KS, KN])
    # DOF blocks: nodes 0 (bottom 0), 1 (bottom 1), 2 (top 0), 3 (top 1)

    def block(K, a, b):
        return K[2 * a : 2 * a + 2, 2 * b : 2 * b + 2]

    for scheme in ("lumped", "lobatto", "newton-cotes"):
        K = _elastic_line2_ke(scheme)
        pattern = np.array([[np.any(block(K, a, b) != 0.0) for b in range(4)] for a in range(4)])
        expected = np.array([[1, 0, 1, 0], [0, 1, 0, 1], [1, 0, 1, 0], [0, 1, 0, 1]], bool)
        np.testing.assert_array_equal(pattern, expected)
        np.testing.assert_allclose(block(K, 0, 0), k * L * h / 2, rtol=1e-14)
        np.testing.assert_allclose(block(K, 0, 2), -k * L * h / 2, rtol=1e-14)
    K = _elastic_line2_ke("gauss")
    assert np.all([[np.any(block(K, a, b) != 0.0) for b in range(4)] for a in range(4)])
    np.testing.assert_allclose(block(K, 0, 0), k * L * h / 6 * 2, rtol=1e-12)
    np.testing.assert_allclose(block(K, 0, 1), k * L * h / 6 * 1, rtol=1e-12)
    np.testing.assert_allclose(block(K, 0, 3), -k * L * h / 6 * 1, rtol=1e-12)


def test_line3_simpson_nodal_springs():
    params = joint_params(KN, KS)
    coords, conn = line_interface("line3", [0.0, 0.0], [3.0, 0.0])
    out = evaluate(coords, conn, np.zeros(12), interface_tables("line3", "lobatto"), params)
    K = out["ke"][0]
    # bottom node i couples only with itself and top node i; springs L/6, L/6, 2L/3
    for i, frac in enumerate([1 / 6, 1 / 6, 2 / 3]):
        row = K[2 * i : 2 * i + 2]
        nz = {j // 2 for j in np.nonzero(np.any(row != 0, axis=0))[0]}
        assert nz == {i, 3 + i}
        np.testing.assert_allclose(row[:, 2 * i : 2 * i + 2], np.diag([KS, KN]) * 3.0 * frac, rtol=1e-12)


# ------------------------------------------------------------------ geometry, statuses, multiple elements


def test_geometry_line3_arc_length_and_frame():
    N, dN, w, _ = interface_tables("line3", "gauss", 5)
    R = 2.0
    a = math.radians(40)
    ends = [np.array([R * math.cos(-a), R * math.sin(-a)]), np.array([R * math.cos(a), R * math.sin(a)])]
    mid = np.array([R, 0.0])
    face = np.array([ends[0], ends[1], mid])
    coords = np.vstack([face, face])
    pts = np.zeros((1, 5, 2))
    frame = np.zeros((1, 5, 2, 2))
    jw = np.zeros((1, 5))
    info = np.zeros(1, np.int64)
    assert interface_geometry(coords, np.arange(6)[None], N, dN, w, pts, frame, jw, info) == STATUS_OK
    # length of the parabola through the three nodes (fine polyline) and of the arc it approximates
    xi = np.linspace(-1, 1, 20001)[:, None]
    curve = shape_functions("line3", xi)[0] @ face
    assert jw.sum() == pytest.approx(np.linalg.norm(np.diff(curve, axis=0), axis=1).sum(), rel=1e-6)
    assert jw.sum() == pytest.approx(R * 2 * a, rel=5e-3)
    np.testing.assert_allclose(pts[0], shape_functions("line3", interface_rule("line3", "gauss", 5)[0])[0] @ face)
    for g in range(5):
        e_t, e_n = frame[0, g]
        np.testing.assert_allclose(e_n, [-e_t[1], e_t[0]])  # +90 deg CCW
        np.testing.assert_allclose(np.linalg.norm(e_t), 1.0)
        # normal of a CCW arc points to the centre (left of the tangent)
        assert np.dot(e_n, pts[0, g]) < 0


def test_bad_geometry_and_nan_status():
    params = joint_params(KN, KS)
    tables = interface_tables("line2")
    coords = np.array([[0, 0], [1, 0], [0, 0], [1, 0], [2, 0], [2, 0]], float)
    conn = np.array([[0, 1, 2, 3], [4, 5, 4, 5]])  # element 1 has zero length
    out = evaluate(coords, conn, np.zeros(12), tables, params)
    assert out["status"] == STATUS_BAD_GEOMETRY and out["info"][0] == 1
    u = np.zeros(8)
    u[5] = np.nan
    out = evaluate(coords[:4], conn[:1], u, tables, params)
    assert out["status"] == STATUS_NAN and out["info"][0] == 0


def test_multiple_elements_and_parameter_sets():
    """Vectorised group: two elements with different parameter sets and thicknesses."""
    N, dN, w, _ = interface_tables("line2")
    coords = np.array([[0, 0], [1, 0], [0, 0], [1, 0], [2, 0], [2, 0]], float)
    conn = np.array([[0, 1, 2, 3], [1, 4, 3, 5]], np.int64)
    table = np.vstack([joint_params(KN, KS), joint_params(2 * KN, 2 * KS)])
    u = np.zeros(12)
    u[1::2][[2, 3, 5]] = -1e-6  # top nodes pressed down by 1 micron
    nip = 2
    sc = np.zeros((2, nip, N_JOINT_STATE))
    st = np.zeros_like(sc)
    d = np.zeros((2, nip, 2))
    t = np.zeros((2, nip, 2))
    fe = np.zeros((2, 8))
    ke = np.zeros((2, 8, 8))
    info = np.zeros(1, np.int64)
    status = interface_evaluate(coords, conn, u, N, dN, w, np.array([0.5, 0.2]), table,
                                np.array([0, 1]), sc, st, d, t, fe, ke, True, info)
    assert status == STATUS_OK
    np.testing.assert_allclose(t[0, :, 1], -KN * 1e-6)
    np.testing.assert_allclose(t[1, :, 1], -2 * KN * 1e-6)
    np.testing.assert_allclose(fe[0, 5::2].sum(), -KN * 1e-6 * 1.0 * 0.5)
    np.testing.assert_allclose(fe[1, 5::2].sum(), -2 * KN * 1e-6 * 1.0 * 0.2)
    np.testing.assert_allclose(ke[0] @ np.r_[0, 0, 0, 0, 0, -1e-6, 0, -1e-6], fe[0])
