"""Element-level verification of the 3D zero-thickness surface interfaces (quad4 = the 8-node
element of Tzamtzis & Asteris, quad8 = 16-node, tri3 = 6-node) of masonrydam.elements.interface with the Mohr-Coulomb
law of masonrydam.materials.mohr_coulomb.

Sources
-------
- Tzamtzis & Asteris, sec. 3.3, eqs. 1-10 (relative displacement top minus bottom
  interpolated with the face shape functions, N = [-B_1 .. -B_4, B_1 .. B_4], K' = int N^T k N dA with
  dA = det J dxi deta, transformation to global axes K = H^T K' H) and eq. 11 (k = diag(ks_x, ks_y,
  kn)); sec. 3.4 / eq. 12 (Mohr-Coulomb slip tau_y = c + sigma_n tan(phi) with a residual shear
  stiffness, separation with zero normal and shear stiffness, contact restored on closing).
- Schellekens, J.C.J. & de Borst, R. (1993), "On the numerical integration of interface elements",
  IJNME 36:43-66: Gauss integration of stiff
  interfaces couples the nodes and makes tractions oscillate; nodal / Newton-Cotes (Lobatto)
  integration gives node-pair springs and smooth tractions.
- Simo & Hughes (1998), Computational Inelasticity, sec. 2.3 / 3.3: closest-point (radial) return
  for an isotropic yield surface - the return direction is that of the trial (relative) stress.
- Differential geometry of a parametrised surface (e.g. do Carmo 1976, Differential Geometry of
  Curves and Surfaces, sec. 2.5 / 2.8): area = int |x_xi x x_eta| dxi deta, right-hand normal
  x_xi x x_eta / |x_xi x x_eta|.
- Area of a parabolic segment = 2/3 chord x height (Archimedes, Quadrature of the Parabola).

Reference quantities (shape functions, areas, frames) are computed in this file independently of
masonrydam.elements.shapes (Zienkiewicz, Taylor & Zhu 2013, The Finite Element Method: Its Basis and
Fundamentals, 7th ed., ch. 6: bilinear quad4, serendipity quad8, linear triangle).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from masonrydam.elements.interface import interface_evaluate, interface_geometry, interface_rule, interface_tables
from masonrydam.errors import STATUS_OK
from masonrydam.materials.mohr_coulomb import (
    N_JOINT_STATE,
    OPEN,
    P_OPEN_TANGENT,
    S_BOND_BROKEN,
    S_CODE,
    S_PLASTIC_SLIP,
    SLIP,
    STICK,
    joint_params,
)

KN = 5.0e10  # Pa/m
KS = 2.0e10  # Pa/m
C = 1.0e5  # Pa
PHI = 35.0  # deg
TAN_PHI = math.tan(math.radians(PHI))

#: the applicable (face, scheme) pairs of the 3D faces (quad8 has no lumped rule)
COMBOS = [
    ("quad4", "lumped"),
    ("quad4", "lobatto"),
    ("quad4", "gauss"),
    ("quad8", "lobatto"),
    ("quad8", "gauss"),
    ("tri3", "lumped"),
    ("tri3", "gauss"),
]
NS = {"quad4": 4, "quad8": 8, "tri3": 3}

#: a fixed, generic orientation and position for the elements of the tests
Q0 = Rotation.from_rotvec([0.45, -0.8, 0.6]).as_matrix()
X0 = np.array([2.0, -1.0, 3.5])


def linear_params(kn=KN, ks=KS):
    """A joint that never slips or opens (as the scene's law = 'linear')."""
    return joint_params(kn, ks, cohesion=1e300, friction_angle_deg=0.0, tensile_strength=1e300)


# ------------------------------------------------------------------ independent shape functions

_QC = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
_QM = np.array([[0, -1], [1, 0], [0, 1], [-1, 0]], float)


def shape(face, xi, eta):
    """N (ns,) and dN (2, ns) at (xi, eta): bilinear quad4, serendipity quad8 (corners then mid-edges
    0-1, 1-2, 2-3, 3-0), linear tri3 (area coordinates); ZTZ 2013 ch. 6."""
    if face == "tri3":
        return np.array([1 - xi - eta, xi, eta]), np.array([[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])
    if face == "quad4":
        a, b = _QC[:, 0], _QC[:, 1]
        N = (1 + a * xi) * (1 + b * eta) / 4
        dN = np.array([a * (1 + b * eta) / 4, b * (1 + a * xi) / 4])
        return N, dN
    N = np.zeros(8)
    dN = np.zeros((2, 8))
    for i, (a, b) in enumerate(_QC):
        x0, e0 = a * xi, b * eta
        N[i] = (1 + x0) * (1 + e0) * (x0 + e0 - 1) / 4
        dN[0, i] = a * (1 + e0) * (2 * x0 + e0) / 4
        dN[1, i] = b * (1 + x0) * (x0 + 2 * e0) / 4
    for k, (a, b) in enumerate(_QM):
        i = 4 + k
        if a == 0:
            N[i] = (1 - xi**2) * (1 + b * eta) / 2
            dN[0, i] = -xi * (1 + b * eta)
            dN[1, i] = b * (1 - xi**2) / 2
        else:
            N[i] = (1 + a * xi) * (1 - eta**2) / 2
            dN[0, i] = a * (1 - eta**2) / 2
            dN[1, i] = -eta * (1 + a * xi)
    return N, dN


def surface_frame(face, xn, xi, eta):
    """Covariant base vectors and the frame [e1, e2, n] (rows) of face nodes xn (ns, 3) at (xi, eta)."""
    _, dN = shape(face, xi, eta)
    a1, a2 = dN @ xn
    n = np.cross(a1, a2)
    j = np.linalg.norm(n)
    n /= j
    e1 = a1 / np.linalg.norm(a1)
    return np.array([e1, np.cross(n, e1), n]), j


def fine_area(face, xn, n=40):
    """int |x_xi x x_eta| over the reference face with an n x n Gauss-Legendre tensor rule
    (triangles: collapsed (Duffy) square)."""
    x, w = np.polynomial.legendre.leggauss(n)
    area = 0.0
    for xa, wa in zip(x, w):
        for xb, wb in zip(x, w):
            if face == "tri3":
                u, v = (xa + 1) / 2, (xb + 1) / 2
                xi, eta, jac = u, v * (1 - u), (1 - u) / 4
            else:
                xi, eta, jac = xa, xb, 1.0
            area += wa * wb * jac * surface_frame(face, xn, xi, eta)[1]
    return area


def centre(face):
    return (1 / 3, 1 / 3) if face == "tri3" else (0.0, 0.0)


# ------------------------------------------------------------------ geometries

_QUAD_CORNERS_2D = np.array([[0.0, 0.0], [1.3, 0.1], [1.1, 0.9], [-0.2, 1.0]])  # general convex quad
_QUAD8_CORNERS_2D = np.array([[0.0, 0.0], [1.2, 0.0], [1.3, 1.0], [0.1, 0.9]])
_QUAD8_MID_INPLANE = np.array([[0.02, -0.05], [0.04, 0.01], [-0.01, 0.05], [-0.04, 0.0]])  # curved edges in plane
_QUAD8_MID_OUTPLANE = np.array([0.02, -0.015, 0.02, 0.01])
_TRI_2D = np.array([[0.0, 0.0], [1.1, 0.2], [0.3, 0.9]])


def face_template(face, planar):
    """Face nodes (ns, 3) in a local frame before the rotation: planar (z = 0) of arbitrary shape,
    or warped (quad4: corner 2 lifted by 0.06 out of the plane of the others) / curved (quad8: mid-nodes
    off the chord, in and out of the plane). tri3 is always planar."""
    if face == "quad4":
        x = np.c_[_QUAD_CORNERS_2D, np.zeros(4)]
        if not planar:
            x[2, 2] = 0.06
        return x
    if face == "tri3":
        return np.c_[_TRI_2D, np.zeros(3)]
    c = _QUAD8_CORNERS_2D
    mids = 0.5 * (c + np.roll(c, -1, axis=0)) + _QUAD8_MID_INPLANE
    x = np.c_[np.vstack([c, mids]), np.zeros(8)]
    if not planar:
        x[4:, 2] = _QUAD8_MID_OUTPLANE
    return x


def quad8_planar_area():
    """Planar quad8 with parabolic edges: polygon (shoelace) + signed parabolic segments 2/3 L h_perp."""
    c = _QUAD8_CORNERS_2D
    x, y = c[:, 0], c[:, 1]
    area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    for k in range(4):
        a, b = c[k], c[(k + 1) % 4]
        L = np.linalg.norm(b - a)
        out = np.array([b[1] - a[1], a[0] - b[0]]) / L  # outward normal of a counter-clockwise polygon
        area += 2.0 / 3.0 * L * _QUAD8_MID_INPLANE[k] @ out
    return area


def planar_area(face):
    """Independent area of the planar template faces."""
    x = face_template(face, planar=True)
    if face == "tri3":
        return 0.5 * np.linalg.norm(np.cross(x[1] - x[0], x[2] - x[0]))
    if face == "quad4":  # half the cross product of the diagonals
        return 0.5 * np.linalg.norm(np.cross(x[2] - x[0], x[3] - x[1]))
    return quad8_planar_area()


def element(face, planar=False, Q=Q0, shift=X0, gap=None):
    """One interface element: coincident bottom and top faces (nodes 0..ns-1 bottom, ns..2ns-1 top)
    placed by x -> Q x + shift. ``gap`` (3,): top face offset (non-coincident faces)."""
    xf = face_template(face, planar) @ Q.T + shift
    top = xf if gap is None else xf + gap
    return np.vstack([xf, top]), np.arange(2 * len(xf))


# ------------------------------------------------------------------ kernel drivers


def evaluate(coords, conn, u, tables, params, committed=None, want_tangent=True):
    N, dN, w = tables[:3]
    coords = np.ascontiguousarray(coords, dtype=np.float64)
    conn = np.ascontiguousarray(np.atleast_2d(conn), dtype=np.int64)
    n_elem, dim, nip = conn.shape[0], coords.shape[1], N.shape[0]
    ndof = conn.shape[1] * dim
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
    out["status"] = interface_evaluate(
        coords, conn, np.asarray(u, dtype=np.float64), N, dN, w, np.ones(n_elem), np.atleast_2d(params),
        np.zeros(n_elem, dtype=np.int64), committed, out["trial"], out["delta"], out["traction"],
        out["fe"], out["ke"], want_tangent, out["info"],
    )
    assert out["status"] == STATUS_OK
    assert np.array_equal(committed, before), "kernel modified state_committed"
    return out


def geometry(coords, conn, tables):
    N, dN, w = tables[:3]
    conn = np.ascontiguousarray(np.atleast_2d(conn), dtype=np.int64)
    ne, nip = conn.shape[0], len(w)
    pts = np.zeros((ne, nip, 3))
    frame = np.zeros((ne, nip, 3, 3))
    jw = np.zeros((ne, nip))
    info = np.zeros(1, np.int64)
    st = interface_geometry(np.ascontiguousarray(coords, dtype=np.float64), conn, N, dN, w, pts, frame, jw, info)
    assert st == STATUS_OK
    return pts, frame, jw


def fd_stiffness(coords, conn, u, tables, params, committed, h):
    """Central finite difference of the element internal force."""
    K = np.zeros((u.size, u.size))
    for d in range(u.size):
        up, um = u.copy(), u.copy()
        up[d] += h
        um[d] -= h
        fp = evaluate(coords, conn, up, tables, params, committed, want_tangent=False)["fe"][0]
        fm = evaluate(coords, conn, um, tables, params, committed, want_tangent=False)["fe"][0]
        K[:, d] = (fp - fm) / (2 * h)
    return K


def relative_u(coords, ns, rel, base=None):
    """Bottom nodes: base(x) (default 0); top nodes: base(x) + rel (global, (3,) or (ns, 3))."""
    u = np.zeros_like(coords)
    if base is not None:
        u[:] = [base(x) for x in coords]
    u[ns:] += rel
    return u.ravel()


def centre_frame(coords, face):
    ns = NS[face]
    return surface_frame(face, coords[:ns], *centre(face))[0]


def global_traction(frame, traction):
    """R^T t at every integration point: (nip, 3)."""
    return np.einsum("gij,gi->gj", frame, traction)


# ------------------------------------------------------------------ rules


def test_quad8_lumped_rule_refused_with_reason():
    """Row-sum lumping of the serendipity quad8 gives negative corner weights (int N_corner = -1/3 on
    [-1, 1]^2; ZTZ 2013 ch. 6), i.e. negative node-pair springs: the rule must be refused, saying why."""
    with pytest.raises(ValueError, match="negative"):
        interface_rule("quad8", "lumped")
    with pytest.raises(ValueError, match="quad8"):
        interface_tables("quad8", "lumped")
    # the reason itself: the corner integrals really are -1/3 (fine Gauss rule, own shape functions)
    x, w = np.polynomial.legendre.leggauss(4)
    integ = sum(wa * wb * shape("quad8", a, b)[0] for a, wa in zip(x, w) for b, wb in zip(x, w))
    np.testing.assert_allclose(integ[:4], -1 / 3, rtol=1e-12)
    np.testing.assert_allclose(integ[4:], 4 / 3, rtol=1e-12)


# ------------------------------------------------------------------ 1a. rigid-body motion


def _rigid_modes(coords, centre_pt):
    """The 6 rigid-body modes (3 translations, 3 infinitesimal rotations about centre_pt), applied to
    both faces; (6, n_dof)."""
    modes = []
    for k in range(3):
        m = np.zeros_like(coords)
        m[:, k] = 1e-3
        modes.append(m.ravel())
    for k in range(3):
        w = np.zeros(3)
        w[k] = 2e-4
        modes.append(np.cross(w, coords - centre_pt).ravel())
    return np.array(modes)


@pytest.mark.parametrize("face, scheme", COMBOS)
def test_rigid_body_motion_gives_zero_force(face, scheme):
    """Tzamtzis & Asteris eqs. 4-5: the element strains only through the relative displacement top minus bottom, so
    a rigid-body motion of both (coincident) faces gives zero relative displacement, zero force,
    lies in the null space of the tangent, and superposed on a deformed (sliding) state changes
    nothing. Warped quad4 / curved quad8, generic orientation. In stick the tangent has exactly
    3 ns non-zero singular values (the null space is 'same motion of both faces')."""
    params = joint_params(KN, KS, C, PHI, 1e5, 0.1 * KS)
    tables = interface_tables(face, scheme)
    coords, conn = element(face, planar=False)
    ns = NS[face]
    modes = _rigid_modes(coords, np.array([0.7, 3.0, -2.0]))
    combo = modes.sum(axis=0)
    for q in list(modes) + [combo]:
        out = evaluate(coords, conn, q, tables, params)
        np.testing.assert_array_equal(out["delta"], 0.0)
        np.testing.assert_array_equal(out["fe"], 0.0)
        assert np.all(out["trial"][..., S_CODE] == STICK)
        # tangent annihilates the rigid mode
        assert np.abs(out["ke"][0] @ q).max() <= 1e-12 * np.abs(out["ke"][0]).max() * np.abs(q).max()
    # rank of the stick tangent: 3 ns (B q = 0 only for equal motion of the two faces)
    sv = np.linalg.svd(out["ke"][0], compute_uv=False)
    assert sv[3 * ns - 1] > 1e-6 * sv[0]
    assert sv[3 * ns] < 1e-12 * sv[0]
    # superposed on a sliding state: identical force, state and traction
    R = centre_frame(coords, face)
    u0 = relative_u(coords, ns, R.T @ np.array([2e-4, -1.5e-4, -5e-5]))
    ref = evaluate(coords, conn, u0, tables, params)
    assert np.all(ref["trial"][..., S_CODE] == SLIP)
    out = evaluate(coords, conn, u0 + combo, tables, params)
    np.testing.assert_allclose(out["fe"], ref["fe"], rtol=1e-12, atol=1e-12 * np.abs(ref["fe"]).max())
    np.testing.assert_allclose(out["traction"], ref["traction"], rtol=1e-12, atol=1e-6)
    np.testing.assert_array_equal(out["trial"][..., S_CODE], ref["trial"][..., S_CODE])
    assert np.abs(ref["ke"][0] @ combo).max() <= 1e-12 * np.abs(ref["ke"][0]).max() * np.abs(combo).max()


# ------------------------------------------------------------------ 1b. patch test


@pytest.mark.parametrize("face, scheme", COMBOS)
def test_patch_uniform_relative_displacement(face, scheme):
    """Tzamtzis & Asteris eqs. 7-11: a uniform relative displacement d (top face translated rigidly with respect to
    the bottom, stick, linear law) gives at every point delta = R d, t = k delta with
    k = diag(ks, ks, kn), hence the uniform global traction ks d + (kn - ks)(d.n) n, and the nodal
    forces on the top face add up to that traction times the face area (independent area: half the
    cross product of the diagonals of a planar quad, half the cross product of two triangle edges,
    polygon + parabolic segments 2/3 L h for a planar quad8 with curved edges); the bottom face gets
    the opposite. Planar elements of arbitrary shape and orientation."""
    params = linear_params()
    tables = interface_tables(face, scheme)
    ns = NS[face]
    area = planar_area(face)
    for seed in (0, 1, 2):
        Q = Q0 if seed == 0 else Rotation.random(rng=np.random.default_rng(100 + seed)).as_matrix()
        coords, conn = element(face, planar=True, Q=Q, shift=X0 * seed)
        n = Q[:, 2]  # the template lies in z = 0 with counter-clockwise nodes: right-hand normal = Q e_z
        d = Q @ np.array([3e-6, -2e-6, -4e-6]) + 1e-6 * np.array([1.0, 0.5, -0.3])
        u = relative_u(coords, ns, d, base=lambda x: np.array([1e-3, -2e-3, 5e-4]))
        out = evaluate(coords, conn, u, tables, params)
        _, frame, jw = geometry(coords, conn, tables)
        assert np.all(out["trial"][..., S_CODE] == STICK)
        np.testing.assert_allclose(frame[0, :, 2, :], np.tile(n, (len(jw[0]), 1)), atol=1e-13)
        dn = d @ n
        np.testing.assert_allclose(out["delta"][0, :, 2], dn, rtol=1e-11)
        np.testing.assert_allclose(np.linalg.norm(out["delta"][0, :, :2], axis=1), np.linalg.norm(d - dn * n), rtol=1e-11)
        np.testing.assert_allclose(out["traction"][0], out["delta"][0] * [KS, KS, KN], rtol=1e-13)
        tg_expected = KS * d + (KN - KS) * dn * n
        np.testing.assert_allclose(global_traction(frame[0], out["traction"][0]), np.tile(tg_expected, (len(jw[0]), 1)),
                                   rtol=1e-10, atol=1e-10 * np.abs(tg_expected).max())
        fe = out["fe"][0].reshape(-1, 3)
        np.testing.assert_allclose(fe[ns:].sum(axis=0), tg_expected * area, rtol=1e-11,
                                   atol=1e-11 * np.abs(tg_expected).max() * area)
        np.testing.assert_allclose(fe[:ns].sum(axis=0), -tg_expected * area, rtol=1e-11,
                                   atol=1e-11 * np.abs(tg_expected).max() * area)
        assert jw.sum() == pytest.approx(area, rel=1e-13)


# ------------------------------------------------------------------ 1c. consistent tangent


REGIMES = {
    # local [s1, s2, n] at the element centre (m); oblique shear: both components non-zero
    "stick": (np.array([1e-6, -0.6e-6, -5e-5]), 0.0),
    "slip": (np.array([1.6e-4, -1.2e-4, -5e-5]), 0.0),
    "slip_residual": (np.array([1.6e-4, -1.2e-4, -5e-5]), 0.15 * KS),
    "open": (np.array([3e-5, 2e-5, 2e-4]), 0.0),
}
EXPECTED_CODE = {"stick": STICK, "slip": SLIP, "slip_residual": SLIP, "open": OPEN}


@pytest.mark.parametrize("regime", list(REGIMES))
@pytest.mark.parametrize("face, scheme", COMBOS)
def test_tangent_equals_central_difference(face, scheme, regime):
    """The element tangent ke = sum B^T C B j w (Tzamtzis & Asteris eqs. 7-10 with the consistent tangent C of the
    Mohr-Coulomb return mapping, Simo & Hughes 1998 sec. 3.3) is the derivative of the internal
    force: compared with a central difference (relative error 1e-6) on a warped quad4 / curved quad8 /
    tilted tri3, with a non-uniform relative displacement, in stick, slip (cohesion and friction,
    oblique slip direction, with and without residual shear stiffness: non-symmetric tangent) and
    open (zero tangent: no stiffness in separation, Tzamtzis & Asteris sec. 3.4). The perturbation (1e-9 m) changes
    a traction by ~20 Pa, far from the yield (margin > 1e5 Pa) and opening kinks."""
    d_loc, ks_r = REGIMES[regime]
    params = joint_params(KN, KS, C, PHI, 0.0, ks_r)
    tables = interface_tables(face, scheme)
    coords, conn = element(face, planar=False)
    ns = NS[face]
    R = centre_frame(coords, face)
    rng = np.random.default_rng(42)
    jitter = 0.02 * np.abs(d_loc).min() * rng.standard_normal((ns, 3))
    u = relative_u(coords, ns, R.T @ d_loc + jitter)
    committed = np.zeros((1, len(tables[2]), N_JOINT_STATE))
    out = evaluate(coords, conn, u, tables, params, committed)
    assert np.all(out["trial"][0, :, S_CODE] == EXPECTED_CODE[regime]), out["trial"][0, :, S_CODE]
    K = out["ke"][0]
    K_fd = fd_stiffness(coords, conn, u, tables, params, committed, h=1e-9)
    if regime == "open":
        np.testing.assert_array_equal(K, 0.0)
        np.testing.assert_array_equal(K_fd, 0.0)
        np.testing.assert_array_equal(out["fe"], 0.0)
        return
    err = np.abs(K - K_fd).max() / np.abs(K).max()
    assert err < 1e-7, err  # observed <= 5e-11: h = 1e-9 m is 1e-5 of the smallest displacement component
    asym = np.abs(K - K.T).max() / np.abs(K).max()
    if regime == "stick":
        assert asym < 1e-13
    else:
        assert asym > 1e-3  # non-associated friction: d tau / d delta_n != 0 but d t_n / d delta_s = 0
        # both shear components are active at every point
        assert np.all(np.abs(out["traction"][0, :, :2]) > 1e-2 * np.abs(out["traction"][0, :, :2]).max())


# ------------------------------------------------------------------ 2. rotation invariance


@pytest.mark.parametrize("regime", ["stick", "slip"])
@pytest.mark.parametrize("face, scheme", [("quad4", "gauss"), ("quad4", "lumped"), ("quad8", "gauss"), ("tri3", "gauss")])
def test_rotation_invariance(face, scheme, regime):
    """The local frame is built from the element's own geometry (Tzamtzis & Asteris eq. 10: K = H^T K' H with the
    element's direction cosines), so the same joint problem (element and displacement field) under
    a rigid rotation x -> Q x, u -> Q u gives the same local relative displacements, tractions and
    state codes and rotated nodal forces (f -> Q f) and tangent (K -> Q K Q^T). Seeded random
    rotations; stick and slip (with residual stiffness)."""
    params = joint_params(KN, KS, C, PHI, 0.0, 0.1 * KS)
    tables = interface_tables(face, scheme)
    coords0, conn = element(face, planar=False, Q=np.eye(3), shift=np.zeros(3))
    ns = NS[face]
    d_loc = REGIMES[regime][0]
    R = centre_frame(coords0, face)
    rng = np.random.default_rng(5)
    u0 = (1e-3 * rng.standard_normal((2 * ns, 3)))  # arbitrary motion of both faces ...
    u0[ns:] = u0[:ns] + R.T @ d_loc + 0.05 * np.abs(d_loc).min() * rng.standard_normal((ns, 3))  # ... + relative
    u0 = u0.ravel()
    ref = evaluate(coords0, conn, u0, tables, params)
    assert np.all(ref["trial"][..., S_CODE] == (STICK if regime == "stick" else SLIP))
    fscale = np.abs(ref["fe"]).max()
    kscale = np.abs(ref["ke"]).max()
    tscale = np.abs(ref["traction"]).max()
    for Q in Rotation.random(4, rng=np.random.default_rng(2024)).as_matrix():
        coords = coords0 @ Q.T + np.array([10.0, -4.0, 7.0])
        u = (u0.reshape(-1, 3) @ Q.T).ravel()
        out = evaluate(coords, conn, u, tables, params)
        np.testing.assert_array_equal(out["trial"][..., S_CODE], ref["trial"][..., S_CODE])
        np.testing.assert_allclose(out["delta"], ref["delta"], rtol=1e-8, atol=1e-10 * np.abs(ref["delta"]).max())
        np.testing.assert_allclose(out["traction"], ref["traction"], rtol=1e-8, atol=1e-9 * tscale)
        np.testing.assert_allclose(out["fe"][0], (ref["fe"][0].reshape(-1, 3) @ Q.T).ravel(), atol=1e-9 * fscale)
        Qb = np.kron(np.eye(2 * ns), Q)
        np.testing.assert_allclose(out["ke"][0], Qb @ ref["ke"][0] @ Qb.T, atol=1e-9 * kscale)


# ------------------------------------------------------------------ 3. slip direction in 3D


@pytest.mark.parametrize("face, scheme", [("quad4", "lumped"), ("quad4", "gauss"), ("tri3", "gauss"), ("quad8", "lobatto")])
def test_slip_along_trial_shear_traction(face, scheme):
    """Isotropic Mohr-Coulomb in the joint plane (Tzamtzis & Asteris eqs. 11-12 with ks_x = ks_y; radial return of
    Simo & Hughes 1998 sec. 2.3): (a) an oblique shear relative displacement beyond yield with
    ks_r = 0 gives a shear traction vector parallel to the applied shear relative displacement, of
    magnitude tau_y = c - t_n tan(phi) (t_n = kn delta_n < 0 in compression, so tau_y = c + sigma_n
    tan(phi)); (b) from that committed slipped state, a further increment in another direction gives
    a shear traction parallel to the trial traction ks (d_s - s_p), of magnitude tau_y, and a plastic
    slip increment parallel to the traction (no slip component across the traction)."""
    params = joint_params(KN, KS, C, PHI, 0.0, 0.0)
    tables = interface_tables(face, scheme)
    coords, conn = element(face, planar=True)
    ns = NS[face]
    n = Q0[:, 2]
    area = planar_area(face)
    _, frame, jw = geometry(coords, conn, tables)
    # in-plane direction at 37 deg from the first edge (not aligned with any local axis)
    e1 = (coords[1] - coords[0]) / np.linalg.norm(coords[1] - coords[0])
    e2 = np.cross(n, e1)
    a = math.radians(37.0)
    s_dir = math.cos(a) * e1 + math.sin(a) * e2
    d_n = -4e-5
    t_n = KN * d_n
    tau_y = C - t_n * TAN_PHI
    ds = 3.0 * tau_y / KS * s_dir  # trial shear 3 tau_y
    u1 = relative_u(coords, ns, ds + d_n * n)
    out = evaluate(coords, conn, u1, tables, params)
    assert np.all(out["trial"][0, :, S_CODE] == SLIP)
    np.testing.assert_allclose(out["traction"][0, :, 2], t_n, rtol=1e-12)
    tau_g = global_traction(frame[0], out["traction"][0]) - t_n * n  # global shear traction vectors
    np.testing.assert_allclose(np.linalg.norm(tau_g, axis=1), tau_y, rtol=1e-11)
    np.testing.assert_allclose(tau_g / tau_y, np.tile(s_dir, (len(jw[0]), 1)), atol=1e-11)  # parallel, same sense
    fe = out["fe"][0].reshape(-1, 3)
    np.testing.assert_allclose(fe[ns:].sum(axis=0), (tau_y * s_dir + t_n * n) * area, rtol=1e-10,
                               atol=1e-10 * tau_y * area)
    # (b) second step from the committed slipped state
    committed = out["trial"].copy()
    sp1 = np.einsum("gij,gi->gj", frame[0][:, :2, :], committed[0, :, S_PLASTIC_SLIP:S_PLASTIC_SLIP + 2])
    np.testing.assert_allclose(sp1, np.tile(2.0 * tau_y / KS * s_dir, (len(jw[0]), 1)), atol=1e-12 * np.abs(ds).max())
    b = math.radians(37.0 + 110.0)
    inc = 2.5 * tau_y / KS * (math.cos(b) * e1 + math.sin(b) * e2)
    u2 = relative_u(coords, ns, ds + inc + d_n * n)
    out2 = evaluate(coords, conn, u2, tables, params, committed)
    assert np.all(out2["trial"][0, :, S_CODE] == SLIP)
    tau2 = global_traction(frame[0], out2["traction"][0]) - t_n * n
    trial = KS * (ds + inc - sp1)  # (nip, 3) global trial shear traction
    m = trial / np.linalg.norm(trial, axis=1)[:, None]
    np.testing.assert_allclose(np.linalg.norm(tau2, axis=1), tau_y, rtol=1e-11)
    np.testing.assert_allclose(tau2 / tau_y, m, atol=1e-11)
    assert np.all(np.abs(m @ s_dir) < 0.99)  # genuinely a new direction
    sp2 = np.einsum("gij,gi->gj", frame[0][:, :2, :], out2["trial"][0, :, S_PLASTIC_SLIP:S_PLASTIC_SLIP + 2])
    dsp = sp2 - sp1
    np.testing.assert_allclose(np.cross(dsp, m), 0.0, atol=1e-12 * np.abs(dsp).max())
    assert np.all(np.einsum("gi,gi->g", dsp, m) > 0)


# ------------------------------------------------------------------ 4. separation and re-contact


@pytest.mark.parametrize("face, scheme", COMBOS)
def test_separation_and_recontact(face, scheme):
    """Tzamtzis & Asteris sec. 3.4: in separation both stiffnesses are zero and no traction is transmitted
    (the optional solver regularisation P_OPEN_TANGENT = 1 gives the elastic tangent but still zero
    traction); on closing, contact is restored with the elastic stiffness diag(ks, ks, kn) (the same
    element tangent as a virgin joint) and the shear starts from zero at the position where the joint
    was (committed) open; a further small shear is elastic (ks) from there. The bond is broken
    (cohesion lost) after opening."""
    params = joint_params(KN, KS, C, PHI, 0.0, 0.0)
    tables = interface_tables(face, scheme)
    coords, conn = element(face, planar=True)
    ns = NS[face]
    n = Q0[:, 2]
    area = planar_area(face)
    _, frame, jw = geometry(coords, conn, tables)
    nip = len(jw[0])
    e1 = (coords[1] - coords[0]) / np.linalg.norm(coords[1] - coords[0])
    s_dir = (0.6 * e1 + 0.8 * np.cross(n, e1))
    K_virgin = evaluate(coords, conn, np.zeros(coords.size), tables, params)["ke"][0]

    # A: stick under compression with some shear, committed
    uA = relative_u(coords, ns, 1e-6 * s_dir - 1e-5 * n)
    A = evaluate(coords, conn, uA, tables, params)
    assert np.all(A["trial"][0, :, S_CODE] == STICK)
    # B: open with a large tangential shift
    shift = 3e-4 * s_dir
    uB = relative_u(coords, ns, shift + 5e-5 * n)
    B = evaluate(coords, conn, uB, tables, params, A["trial"])
    assert np.all(B["trial"][0, :, S_CODE] == OPEN)
    assert np.all(B["trial"][0, :, S_BOND_BROKEN] == 1.0)
    np.testing.assert_array_equal(B["traction"], 0.0)
    np.testing.assert_array_equal(B["fe"], 0.0)
    np.testing.assert_array_equal(B["ke"], 0.0)
    p_reg = params.copy()
    p_reg[P_OPEN_TANGENT] = 1.0
    Breg = evaluate(coords, conn, uB, tables, p_reg, A["trial"])
    np.testing.assert_array_equal(Breg["traction"], 0.0)
    np.testing.assert_array_equal(Breg["fe"], 0.0)
    np.testing.assert_allclose(Breg["ke"][0], K_virgin, rtol=1e-13, atol=1e-13 * np.abs(K_virgin).max())
    committed = B["trial"].copy()
    # C: close again at the shifted position: compression, no shear, elastic stiffness restored
    d_n = -1e-5
    uC = relative_u(coords, ns, shift + d_n * n)
    Cst = evaluate(coords, conn, uC, tables, params, committed)
    assert np.all(Cst["trial"][0, :, S_CODE] == STICK)
    np.testing.assert_allclose(Cst["traction"][0, :, :2], 0.0, atol=1e-9 * KN * abs(d_n))
    np.testing.assert_allclose(Cst["traction"][0, :, 2], KN * d_n, rtol=1e-12)
    np.testing.assert_allclose(Cst["ke"][0], K_virgin, rtol=1e-13, atol=1e-13 * np.abs(K_virgin).max())
    fe = Cst["fe"][0].reshape(-1, 3)
    np.testing.assert_allclose(fe[ns:].sum(axis=0), KN * d_n * area * n, rtol=1e-10, atol=1e-10 * KN * abs(d_n) * area)
    # the normal response from first contact (d_n = 0, zero force) to C is the secant kn: K (uC - u0) = f(C)
    u_touch = relative_u(coords, ns, shift)
    touch = evaluate(coords, conn, u_touch, tables, params, committed)
    np.testing.assert_allclose(touch["fe"], 0.0, atol=1e-9 * KN * abs(d_n) * area)
    np.testing.assert_allclose(Cst["ke"][0] @ (uC - u_touch), Cst["fe"][0], rtol=1e-10,
                               atol=1e-10 * KN * abs(d_n) * area)
    # D: a small further shear from the new position is elastic, ks times the increment
    ds = 2e-7 * np.cross(n, s_dir)
    uD = relative_u(coords, ns, shift + ds + d_n * n)
    D = evaluate(coords, conn, uD, tables, params, committed)
    assert np.all(D["trial"][0, :, S_CODE] == STICK)
    tau_g = global_traction(frame[0], D["traction"][0]) - KN * d_n * n
    np.testing.assert_allclose(tau_g, np.tile(KS * ds, (nip, 1)), rtol=1e-8, atol=1e-8 * KS * np.abs(ds).max())
    # ... whereas without the opening history the same displacement would slip (crack: c = 0 now)
    virgin = evaluate(coords, conn, uD, tables, params, A["trial"])
    assert np.all(virgin["trial"][0, :, S_CODE] == SLIP)
    # cohesion lost: the crack's strength is -t_n tan(phi) only
    big = 1e-4 * np.cross(n, s_dir)
    E = evaluate(coords, conn, relative_u(coords, ns, shift + big + d_n * n), tables, params, committed)
    assert np.all(E["trial"][0, :, S_CODE] == SLIP)
    np.testing.assert_allclose(np.linalg.norm(E["traction"][0, :, :2], axis=1), -KN * d_n * TAN_PHI, rtol=1e-12)


# ------------------------------------------------------------------ 5. interface integration in 3D


def _strip(n_el, h, width):
    """A row of n_el quad4 interface elements along x (element length h, width `width`), bottom face
    nodes 0..2(n_el+1)-1, top face nodes after them, coincident, normal +z."""
    nx = n_el + 1
    xy = np.array([[i * h, j * width, 0.0] for j in range(2) for i in range(nx)])
    coords = np.vstack([xy, xy])
    nb = 2 * nx

    def node(i, j):
        return j * nx + i

    conn = []
    for i in range(n_el):
        face = [node(i, 0), node(i + 1, 0), node(i + 1, 1), node(i, 1)]
        conn.append(face + [nb + a for a in face])
    return coords, np.array(conn, np.int64), nb


def _strip_solution(scheme, n_el=10, h=0.1, width=0.1, ell=0.03, F=1e4):
    """Bottom face fixed; normal forces F exp(-x / ell) on the top nodes (a steep, notch-tip-like
    load transferred by a bar much softer than the joint); linear stiff joint kn = 1e15 Pa/m.
    Solve K_tt u_t = f and return the integration points' x, normal tractions, jw, the top nodal
    internal forces and the applied forces."""
    params = linear_params(kn=1e15, ks=1e15)
    tables = interface_tables("quad4", scheme)
    coords, conn, nb = _strip(n_el, h, width)
    ndof = coords.size
    K = np.zeros((ndof, ndof))
    out = evaluate(coords, conn, np.zeros(ndof), tables, params)
    for e, row in enumerate(conn):
        dofs = (3 * row[:, None] + np.arange(3)).ravel()
        K[np.ix_(dofs, dofs)] += out["ke"][e]
    f = np.zeros(ndof)
    top = np.arange(nb, coords.shape[0])
    f[3 * top + 2] = F * np.exp(-coords[top, 0] / ell)
    free = (3 * top[:, None] + np.arange(3)).ravel()
    u = np.zeros(ndof)
    u[free] = np.linalg.solve(K[np.ix_(free, free)], f[free])
    res = evaluate(coords, conn, u, tables, params)
    fint = np.zeros(ndof)
    for e, row in enumerate(conn):
        fint[(3 * row[:, None] + np.arange(3)).ravel()] += res["fe"][e]
    pts, _, jw = geometry(coords, conn, tables)
    return pts[..., 0].ravel(), res["traction"][..., 2].ravel(), jw.ravel(), fint[free], f[free]


def _along_x(x, t):
    """Point values averaged over the points with the same x (both rows; at a node, both elements)."""
    xs = np.unique(np.round(x, 12))
    return xs, np.array([t[np.isclose(x, v)].mean() for v in xs])


@pytest.mark.reference
def test_gauss_tractions_oscillate_nodal_integration_does_not():
    """Interface integration (Schellekens & de Borst 1993, IJNME 36:43-66) in 3D with quad4 faces: a
    stiff linear joint (kn = 1e15 Pa/m) under a sharply varying normal load (notch tip). Gauss (2x2)
    integration couples neighbouring nodes (consistent 'mass-like' matrix), and the normal tractions
    alternate in sign from element to element; nodal (lumped) and Newton-Cotes (2x2 Lobatto)
    integration give uncoupled node-pair springs and monotonically decaying tractions,
    t_i = f_i / (kn-independent tributary area). All schemes are in equilibrium with the same
    resultant."""
    results = {s: _strip_solution(s) for s in ("gauss", "lumped", "lobatto")}
    total = results["gauss"][4].sum()
    for scheme, (x, t, jw, fint, f) in results.items():
        # equilibrium: internal forces = applied; resultant of the tractions = applied resultant
        np.testing.assert_allclose(fint, f, rtol=1e-9, atol=1e-9 * np.abs(f).max())
        assert np.sum(t * jw) == pytest.approx(total, rel=1e-9)
    xg, tg = _along_x(*results["gauss"][:2])
    sign_changes = int(np.sum(np.sign(tg[1:]) != np.sign(tg[:-1])))
    assert sign_changes >= 4, f"Gauss tractions should oscillate in sign near the tip: {tg}"
    assert tg.min() < -0.05 * tg.max(), "spurious compression of a joint loaded only in tension"
    for scheme in ("lumped", "lobatto"):
        x, t = results[scheme][:2]
        xs, tn = _along_x(x, t)
        # the two points at one node (neighbouring elements) carry the same traction: node-pair springs
        for v in xs:
            vals = t[np.isclose(x, v)]
            np.testing.assert_allclose(vals, vals[0], rtol=1e-10)
        assert np.all(tn >= 0.0), f"{scheme}: no compression anywhere"
        assert np.all(np.diff(tn) <= 0.0), f"{scheme}: tractions decay monotonically from the tip: {tn}"
        # node-pair spring: traction = nodal force / tributary area (h w / 4 per element and node:
        # h w / 4 at the ends of the row, h w / 2 inside)
        f = results[scheme][4][2::3]
        trib = np.r_[0.5, np.ones(9), 0.5] * 0.1 * 0.1 / 2
        np.testing.assert_allclose(tn, f[:11] / trib, rtol=1e-9)
    # nodal (lumped) and 2x2 Newton-Cotes rules have the same points and weights (different order)
    np.testing.assert_allclose(_along_x(*results["lumped"][:2])[1], _along_x(*results["lobatto"][:2])[1], rtol=1e-12)


# ------------------------------------------------------------------ 6. geometry


GEOM_CASES = [
    ("quad4", "lumped", None), ("quad4", "lobatto", None), ("quad4", "gauss", None), ("quad4", "gauss", 10),
    ("quad8", "lobatto", None), ("quad8", "gauss", None), ("quad8", "gauss", 10),
    ("tri3", "lumped", None), ("tri3", "gauss", None), ("tri3", "gauss", 1), ("tri3", "gauss", 6),
]


@pytest.mark.parametrize("face, scheme, n", GEOM_CASES)
def test_geometry_area_and_frame(face, scheme, n):
    """interface_geometry: jw sums to the face area (do Carmo: int |x_xi x x_eta|; reference by a
    40 x 40 Gauss rule with shape functions written here) for the warped quad4 and curved quad8
    (exact to 1e-10 with 10 x 10 points; the default rules approximate the non-polynomial Jacobian of
    a non-planar face, within 1e-3 for these mildly warped faces) and exactly for tri3; the frame rows
    are orthonormal and right-handed, the first tangent is along x_xi (node 0 -> 1 at node 0), the
    normal is the right-hand-rule normal x_xi x x_eta of the face; points = sum N x_mid. The frame
    and area are those of the mid-surface when the faces are not coincident."""
    tables = interface_tables(face, scheme, n)
    pts_ref = interface_rule(face, scheme, n)[0]
    gap = np.array([0.004, -0.003, 0.005])
    coords, conn = element(face, planar=False, gap=gap)
    ns = NS[face]
    xmid = 0.5 * (coords[:ns] + coords[ns:])
    pts, frame, jw = geometry(coords, conn, tables)
    area = fine_area(face, xmid)
    if face == "tri3":
        assert area == pytest.approx(0.5 * np.linalg.norm(np.cross(xmid[1] - xmid[0], xmid[2] - xmid[0])), rel=1e-13)
        assert jw.sum() == pytest.approx(area, rel=1e-13)
    elif n is not None:
        assert jw.sum() == pytest.approx(area, rel=1e-10)
    else:
        assert jw.sum() == pytest.approx(area, rel=1e-3)
    for g, (xi, eta) in enumerate(pts_ref):
        R = frame[0, g]
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
        R_ref, j = surface_frame(face, xmid, xi, eta)
        np.testing.assert_allclose(R, R_ref, atol=1e-13)
        N, _ = shape(face, xi, eta)
        np.testing.assert_allclose(pts[0, g], N @ xmid, atol=1e-14)
        np.testing.assert_allclose(jw[0, g], j * interface_rule(face, scheme, n)[1][g], rtol=1e-13)
    # at node 0 (nodal rules): first tangent along the edge 0 -> 1, normal = right-hand normal there
    if scheme != "gauss":
        g0 = int(np.argmin(np.abs(pts_ref - ([0, 0] if face == "tri3" else [-1, -1])).sum(axis=1)))
        if face == "quad8":
            t1 = -1.5 * xmid[0] - 0.5 * xmid[1] + 2.0 * xmid[4]  # line3 end derivative along edge 0-4-1
            t2 = -1.5 * xmid[0] - 0.5 * xmid[3] + 2.0 * xmid[7]
        else:
            t1 = xmid[1] - xmid[0]
            t2 = xmid[3 if face == "quad4" else 2] - xmid[0]
        nrm = np.cross(t1, t2)
        np.testing.assert_allclose(frame[0, g0, 0], t1 / np.linalg.norm(t1), atol=1e-13)
        np.testing.assert_allclose(frame[0, g0, 2], nrm / np.linalg.norm(nrm), atol=1e-13)
    # the normal points to the side of the template's +z (counter-clockwise nodes seen from +z)
    assert np.all(frame[0, :, 2] @ Q0[:, 2] > 0.9)
