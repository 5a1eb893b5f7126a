"""Tests of masonrydam.effects.reservoir.hydrostatics.facet_pressure_forces against closed forms.

Sources:
- hydrostatics: F. M. White, *Fluid Mechanics*, 7th ed. 2011, ch. 2 (secs. 2.3-2.5, 2.7): pressure
  ``p = gamma d``; the horizontal force on a submerged face is the force on its vertical projection,
  ``gamma h^2 / 2`` per unit width acting ``h / 3`` above the base; the vertical force is the weight of
  the water above the face; on a plane face the resultant is ``gamma h_c A`` along the normal
  (``h_c`` the depth of the wetted area's centroid);
- silt: USACE EM 1110-2-2200, *Gravity Dam Design* (1995), sec. 3-5 "Silt pressure": horizontal silt
  pressure as an equivalent fluid of unit weight ``K gamma'`` (``K`` the lateral coefficient,
  ``gamma'`` the submerged unit weight), vertical load = submerged weight of the silt above an inclined
  face;
- consistent loads of a linearly varying pressure on a 2-node edge of length L:
  ``f1 = L (2 q1 + q2) / 6``, ``f2 = L (q1 + 2 q2) / 6`` (Zienkiewicz, Taylor & Zhu, *The Finite Element
  Method: Its Basis and Fundamentals*, 7th ed. 2013, ch. 6; Cook et al., *Concepts and Applications of
  FEA*, 4th ed. 2002, sec. 3.10).

Moments: consistent nodal forces of an isoparametric facet reproduce every first moment of the
traction exactly, ``sum_i x_i f_i = int x t dA`` (``sum_a N_a x_a = x``), so the line of action is
checked through nodal moments.

All meshes are built by hand: coordinates, facet node lists and a point inside the body for each facet.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad_vec

from masonrydam.effects.reservoir.hydrostatics import facet_pressure_forces
from masonrydam.elements.quadrature import collapsed_triangle_rule
from masonrydam.elements.shapes import shape_functions

GAMMA = 9810.0  # N/m3, water
RTOL = 1e-12


def _forces(*args, **kw):
    f = facet_pressure_forces(*args, **kw)
    dim = np.asarray(args[0]).shape[1]
    return f.reshape(-1, dim)


# ---------------------------------------------------------------------------------------------
# 2D helpers


def _polyline(points, quadratic=False, mids=None):
    """line2 (or line3 with the given mid points) facets along a polyline: coords, facets."""
    points = np.asarray(points, dtype=np.float64)
    n = len(points) - 1
    if not quadratic:
        return points, np.column_stack([np.arange(n), np.arange(1, n + 1)])
    coords = np.vstack([points, mids])
    return coords, np.column_stack([np.arange(n), np.arange(1, n + 1), len(points) + np.arange(n)])


def _inward_right(coords, facets, offset=0.3):
    """Points to the right of each facet (walking from its first to its second node), i.e. the body
    lies on the right: for upward-running upstream faces the body is on the +x side."""
    a, b = coords[facets[:, 0]], coords[facets[:, 1]]
    t = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    return 0.5 * (a + b) + offset * np.column_stack([t[:, 1], -t[:, 0]])


# ---------------------------------------------------------------------------------------------
# 1. vertical face, 2D


@pytest.mark.parametrize("level", [7.3, 12.0, -0.5, 10.0, 0.0, 6.0])
def test_vertical_face_2d_resultant_and_line_of_action(level):
    """Vertical face x = 0, 0 <= y <= 10, five line2 elements, body on +x, thickness 1.5 m: horizontal
    force gamma h^2 t / 2 (h the wet depth) acting h / 3 above the base, no vertical force; nodes above
    the water carry nothing except the upper node of the partly wet element. Levels inside an element,
    above the top (all wet), below the base (nothing), exactly at the top, the base and a node."""
    ys = np.linspace(0.0, 10.0, 6)
    coords, facets = _polyline(np.column_stack([np.zeros(6), ys]))
    inward = _inward_right(coords, facets)
    t = 1.5
    F = _forces(coords, "line2", facets, inward, surface_level=level, unit_weight=GAMMA, vertical_axis=1,
                thickness=t)
    h = min(max(level, 0.0), 10.0)
    top = max(level - 10.0, 0.0)  # depth at the top of the face when overtopped
    # pressure trapezoid from gamma (top + 10) at the base to gamma top at the top, or triangle
    if level >= 10.0:
        fx = GAMMA * t * 10.0 * (top + 5.0)
        my = GAMMA * t * (top * 50.0 + 1000.0 / 6.0)  # int y (level - y) dy over [0, 10]
    else:
        fx = 0.5 * GAMMA * h * h * t
        my = fx * h / 3.0
    np.testing.assert_allclose(F[:, 0].sum(), fx, rtol=RTOL, atol=1e-9)
    np.testing.assert_allclose((F[:, 0] * ys).sum(), my, rtol=RTOL, atol=1e-9)
    np.testing.assert_array_equal(F[:, 1], 0.0)
    assert np.all(F[:, 0] >= 0.0)  # pushes into the body (+x)
    if 0.0 < level < 10.0:
        # nodes strictly above the first node at or above the water carry nothing
        first_dry = int(np.searchsorted(ys, level, side="left"))
        assert np.all(F[first_dry + 1:, 0] == 0.0)
        if level not in ys:
            assert F[first_dry, 0] > 0.0
    if level <= 0.0:
        assert np.all(F == 0.0)


def test_partly_wet_line2_nodal_values():
    """One line2 element from y = 6 to y = 8, water at 7.3: f_a = int N_a gamma (7.3 - y) dy over the
    wet part [6, 7.3], N_1 = (8 - y) / 2, N_2 = (y - 6) / 2 (polynomials integrated exactly)."""
    coords = np.array([[0.0, 6.0], [0.0, 8.0]])
    facets = np.array([[0, 1]])
    F = _forces(coords, "line2", facets, [[1.0, 7.0]], surface_level=7.3, unit_weight=GAMMA, vertical_axis=1)
    P = np.polynomial.Polynomial
    q = GAMMA * P([7.3, -1.0])
    f1 = ((P([8.0, -1.0]) / 2) * q).integ()
    f2 = ((P([-6.0, 1.0]) / 2) * q).integ()
    np.testing.assert_allclose(F[:, 0], [f1(7.3) - f1(6.0), f2(7.3) - f2(6.0)], rtol=RTOL)
    np.testing.assert_array_equal(F[:, 1], 0.0)


# ---------------------------------------------------------------------------------------------
# 8. consistent distribution of a linear pressure on one element


def test_linear_element_fully_wet_consistent_distribution():
    """Inclined line2 edge of length L fully wet: f1 = L (2 q1 + q2) / 6, f2 = L (q1 + 2 q2) / 6 along the
    inward normal (q = gamma d at the nodes)."""
    a, b = np.array([0.0, 1.0]), np.array([1.2, 2.6])
    coords = np.array([a, b])
    facets = np.array([[0, 1]])
    inward = _inward_right(coords, facets)
    s, t = 5.0, 0.8
    F = _forces(coords, "line2", facets, inward, surface_level=s, unit_weight=GAMMA, vertical_axis=1, thickness=t)
    L = np.linalg.norm(b - a)
    q1, q2 = GAMMA * (s - a[1]), GAMMA * (s - b[1])
    tang = (b - a) / L
    n_in = -np.array([-tang[1], tang[0]])  # outward = left of the upward tangent (water side)
    np.testing.assert_allclose(F[0], t * L * (2 * q1 + q2) / 6.0 * n_in, rtol=RTOL)
    np.testing.assert_allclose(F[1], t * L * (q1 + 2 * q2) / 6.0 * n_in, rtol=RTOL)


# ---------------------------------------------------------------------------------------------
# 2. inclined upstream face (batter)


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("level", [6.1, 4.0, 10.0])
def test_battered_face_2d(reverse, level):
    """Face from the toe (0, 0) to (a, H), a = 3, H = 10, body on the +x side, four line2 elements:
    horizontal gamma h^2 / 2 at h / 3, vertical = -gamma x weight of the water triangle (0,0),
    (x_w, h), (0, h) with x_w = a h / H, acting at x_w / 3. Facets listed in either node order give the
    same forces (the inward points decide)."""
    a, H = 3.0, 10.0
    s_ = np.linspace(0.0, 1.0, 5)
    coords, facets = _polyline(np.column_stack([a * s_, H * s_]))
    inward = _inward_right(coords, facets)
    if reverse:
        facets = facets[:, ::-1].copy()
    F = _forces(coords, "line2", facets, inward, surface_level=level, unit_weight=GAMMA, vertical_axis=1)
    h = level
    xw = a * h / H
    W = GAMMA * 0.5 * h * xw
    np.testing.assert_allclose(F[:, 0].sum(), 0.5 * GAMMA * h * h, rtol=RTOL)
    np.testing.assert_allclose(F[:, 1].sum(), -W, rtol=RTOL)
    np.testing.assert_allclose((F[:, 0] * coords[:, 1]).sum(), 0.5 * GAMMA * h * h * h / 3.0, rtol=RTOL)
    np.testing.assert_allclose((F[:, 1] * coords[:, 0]).sum(), -W * xw / 3.0, rtol=RTOL)


def test_battered_face_orientation_independent():
    """Same face, both node orders, identical nodal force vectors."""
    s_ = np.linspace(0.0, 1.0, 4)
    coords, facets = _polyline(np.column_stack([2.0 * s_, 9.0 * s_]))
    inward = _inward_right(coords, facets)
    kw = dict(surface_level=5.5, unit_weight=GAMMA, vertical_axis=1)
    f1 = facet_pressure_forces(coords, "line2", facets, inward, **kw)
    f2 = facet_pressure_forces(coords, "line2", facets[:, ::-1], inward, **kw)
    np.testing.assert_allclose(f1, f2, rtol=0, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# 3. stepped face


@pytest.mark.parametrize("level", [7.5, 6.0, 4.2, 11.0])
def test_stepped_face_2d(level):
    """Upstream face in steps, body on +x: risers x = 0 (0 <= y <= 3), x = 1 (3..6), x = 2 (6..9), treads
    y = 3 (0 <= x <= 1) and y = 6 (1 <= x <= 2), each segment split into line2 elements. Horizontal
    force gamma h^2 / 2 at h / 3 (risers: the vertical projection), vertical force = weight of the water
    on the treads gamma (h - 3) + gamma (h - 6) (where wet), acting at the tread centres."""
    pts = [(0, 0), (0, 1.5), (0, 3), (0.5, 3), (1, 3), (1, 4), (1, 5), (1, 6), (1.5, 6), (2, 6), (2, 7.5), (2, 9)]
    coords, facets = _polyline(np.array(pts, dtype=np.float64))
    inward = _inward_right(coords, facets)
    F = _forces(coords, "line2", facets, inward, surface_level=level, unit_weight=GAMMA, vertical_axis=1)
    h = level
    if h <= 9.0:
        fx, my = 0.5 * GAMMA * h * h, GAMMA * h**3 / 6.0
    else:  # overtopped: trapezoid over the 9 m of risers
        fx = GAMMA * 9.0 * (h - 4.5)
        my = GAMMA * (h * 81.0 / 2.0 - 729.0 / 3.0)
    w1, w2 = GAMMA * max(h - 3.0, 0.0), GAMMA * max(h - 6.0, 0.0)
    np.testing.assert_allclose(F[:, 0].sum(), fx, rtol=RTOL)
    np.testing.assert_allclose((F[:, 0] * coords[:, 1]).sum(), my, rtol=RTOL)
    np.testing.assert_allclose(F[:, 1].sum(), -(w1 + w2), rtol=RTOL, atol=1e-9)
    np.testing.assert_allclose((F[:, 1] * coords[:, 0]).sum(), -(0.5 * w1 + 1.5 * w2), rtol=RTOL, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# 4. curved line3 faces


@pytest.mark.parametrize("level", [5.5, 3.3, 8.0])
def test_parabolic_face_line3(level):
    """Upstream face x = c y^2, 0 <= y <= 8 (c = 0.05), four line3 elements with mid nodes on the
    parabola (represented exactly: y linear, x quadratic in xi), body on +x. Horizontal force
    gamma h^2 / 2 (projection) with moment gamma h^3 / 6; vertical force = weight of the water between
    the curve and the vertical through the toe, gamma c h^3 / 3, with moment int x dA = c^2 h^5 / 10.
    Levels in the middle of an element and at a node."""
    c, H = 0.05, 8.0
    yc = np.linspace(0.0, H, 5)
    ym = 0.5 * (yc[1:] + yc[:-1])
    coords, facets = _polyline(np.column_stack([c * yc**2, yc]), True, np.column_stack([c * ym**2, ym]))
    inward = _inward_right(coords, facets)
    F = _forces(coords, "line3", facets, inward, surface_level=level, unit_weight=GAMMA, vertical_axis=1)
    h = level
    rt = 1e-10
    np.testing.assert_allclose(F[:, 0].sum(), 0.5 * GAMMA * h * h, rtol=rt)
    np.testing.assert_allclose((F[:, 0] * coords[:, 1]).sum(), GAMMA * h**3 / 6.0, rtol=rt)
    np.testing.assert_allclose(F[:, 1].sum(), -GAMMA * c * h**3 / 3.0, rtol=rt)
    np.testing.assert_allclose((F[:, 1] * coords[:, 0]).sum(), -GAMMA * c * c * h**5 / 10.0, rtol=rt)


@pytest.mark.parametrize("level", [1.0, 0.4, 1.9])
def test_line3_hump_two_water_crossings(level):
    """One line3 edge y = 2 (1 - xi^2), x = 1 + xi (a submerged hump on a body below it) crossed twice by
    the water line: the wet parts are |x - 1| > u0 = sqrt(1 - s / 2). Closed forms (s the level):
    vertical force -gamma int (s - y) dx over the wet parts = -2 gamma [s (1 - u0) - 2 ((1 - u0) -
    (1 - u0^3) / 3)]; horizontal forces of the two flanks cancel; their moment
    int x t_x = -2 gamma int_0^s (s - y) sqrt(1 - y / 2) dy."""
    coords = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 2.0]])
    facets = np.array([[0, 1, 2]])
    inward = np.array([[1.0, 0.5]])  # body below the arch
    s = level
    F = _forces(coords, "line3", facets, inward, surface_level=s, unit_weight=GAMMA, vertical_axis=1)
    u0 = math.sqrt(1.0 - s / 2.0)
    area = 2.0 * (s * (1.0 - u0) - 2.0 * ((1.0 - u0) - (1.0 - u0**3) / 3.0))  # int (s - 2 (1 - u^2)) du
    w0 = 1.0 - s / 2.0  # int_0^s (s - y) sqrt(1 - y/2) dy with w = 1 - y / 2
    prim = lambda w: 2.0 * ((s - 2.0) * 2.0 / 3.0 * w**1.5 + 2.0 * 2.0 / 5.0 * w**2.5)
    mxx = -2.0 * GAMMA * (prim(1.0) - prim(w0))
    np.testing.assert_allclose(F[:, 1].sum(), -GAMMA * area, rtol=1e-10)
    np.testing.assert_allclose(F[:, 0].sum(), 0.0, atol=1e-9 * GAMMA)
    np.testing.assert_allclose((F[:, 0] * coords[:, 0]).sum(), mxx, rtol=1e-10)


# ---------------------------------------------------------------------------------------------
# 3D helpers


def _grid_surface(fun, nu, nv, facet_type):
    """Facets of type facet_type on the parametric surface X = fun(u, v), u, v in [0, 1], nu x nv cells.
    Nodes on the (2 nu + 1) x (2 nv + 1) grid (corner types leave the mid nodes unused).
    Returns coords (n, 3), facets (m, nfn)."""
    U, V = np.meshgrid(np.linspace(0, 1, 2 * nu + 1), np.linspace(0, 1, 2 * nv + 1), indexing="ij")
    coords = np.array([fun(u, v) for u, v in zip(U.ravel(), V.ravel())], dtype=np.float64)
    nid = np.arange(coords.shape[0]).reshape(U.shape)
    facets = []
    for i in range(nu):
        for j in range(nv):
            I, J = 2 * i, 2 * j
            c = [nid[I, J], nid[I + 2, J], nid[I + 2, J + 2], nid[I, J + 2]]
            m = [nid[I + 1, J], nid[I + 2, J + 1], nid[I + 1, J + 2], nid[I, J + 1]]
            if facet_type == "quad4":
                facets.append(c)
            elif facet_type == "quad8":
                facets.append(c + m)
            elif facet_type == "quad9":
                facets.append(c + m + [nid[I + 1, J + 1]])
            elif facet_type == "tri3":  # alternate diagonals
                if (i + j) % 2:
                    facets += [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
                else:
                    facets += [[c[0], c[1], c[3]], [c[1], c[2], c[3]]]
            elif facet_type == "tri6":
                ce = nid[I + 1, J + 1]
                facets += [[c[0], c[1], c[2], m[0], m[1], ce], [c[0], c[2], c[3], ce, m[2], m[3]]]
    return coords, np.array(facets, dtype=np.int64)


def _inward_from_normal(coords, facets, n_out, offset=0.5):
    return coords[facets].mean(axis=1) - offset * np.asarray(n_out)[None, :]


def _moments(coords, F):
    """sum_i x_i (x) f_i: (3, 3), entry (j, k) = sum x_j f_k."""
    return coords.T @ F


# ---------------------------------------------------------------------------------------------
# 5. 3D plane faces


@pytest.mark.parametrize("facet_type", ["quad4", "quad8", "quad9", "tri3", "tri6"])
@pytest.mark.parametrize("level", [4.3, 7.0, 9.5, -1.0])
def test_vertical_rectangle_3d(facet_type, level):
    """Vertical rectangle x = 0, 0 <= y <= b = 5, 0 <= z <= H = 8 (body on +x) in 3 x 4 cells: force
    gamma b h^2 / 2 along +x acting h / 3 above the base (sum z f_x = gamma b h^3 / 6), centred in y
    (sum y f_x = b / 2 F), no other components. Levels inside elements (4.3, 9.5 overtopping is 8 m
    of face plus 1.5 m of water above: trapezoid), at a node row, below the base."""
    b, H = 5.0, 8.0
    coords, facets = _grid_surface(lambda u, v: (0.0, b * u, H * v), 3, 4, facet_type)
    inward = _inward_from_normal(coords, facets, [-1.0, 0.0, 0.0])
    F = _forces(coords, facet_type, facets, inward, surface_level=level, unit_weight=GAMMA, vertical_axis=2)
    if level >= H:
        fx = GAMMA * b * H * (level - H / 2)
        mz = GAMMA * b * (level * H * H / 2 - H**3 / 3)
    else:
        h = max(level, 0.0)
        fx, mz = 0.5 * GAMMA * b * h * h, GAMMA * b * h**3 / 6.0
    M = _moments(coords, F)
    np.testing.assert_allclose(F[:, 0].sum(), fx, rtol=RTOL, atol=1e-9)
    np.testing.assert_allclose(M[2, 0], mz, rtol=RTOL, atol=1e-9)
    np.testing.assert_allclose(M[1, 0], 0.5 * b * fx, rtol=RTOL, atol=1e-9)
    np.testing.assert_allclose(F[:, 1:], 0.0, atol=1e-9 * GAMMA)


@pytest.mark.parametrize("facet_type", ["quad4", "quad8", "tri3", "tri6"])
def test_battered_plane_3d(facet_type):
    """Inclined plane face x = m z (m = 0.4), 0 <= y <= b = 6, 0 <= z <= H = 10, body on +x, water 6.7 m:
    horizontal gamma b h^2 / 2 at h / 3, vertical = -gamma x the water prism above the face
    b m h^2 / 2, acting at x = m h / 3."""
    m, b, H, h = 0.4, 6.0, 10.0, 6.7
    coords, facets = _grid_surface(lambda u, v: (m * H * v, b * u, H * v), 2, 3, facet_type)
    n_out = np.array([-1.0, 0.0, m]) / math.hypot(1.0, m)
    inward = _inward_from_normal(coords, facets, n_out)
    F = _forces(coords, facet_type, facets, inward, surface_level=h, unit_weight=GAMMA, vertical_axis=2)
    W = GAMMA * b * m * h * h / 2.0
    M = _moments(coords, F)
    np.testing.assert_allclose(F[:, 0].sum(), GAMMA * b * h * h / 2.0, rtol=RTOL)
    np.testing.assert_allclose(F[:, 2].sum(), -W, rtol=RTOL)
    np.testing.assert_allclose(F[:, 1].sum(), 0.0, atol=1e-9 * GAMMA)
    np.testing.assert_allclose(M[2, 0], GAMMA * b * h**3 / 6.0, rtol=RTOL)
    np.testing.assert_allclose(M[0, 2], -W * m * h / 3.0, rtol=RTOL)


def _oblique_parallelogram_closed_form(s):
    """Face X = alpha U + beta V with z = alpha + 2 beta (U_z = 1, V_z = 2), alpha, beta in [0, 1],
    depth d = s - alpha - 2 beta. For s = 1.5 the wet part {alpha + 2 beta < s} is, with c = s - alpha
    (from 1.5 down to 0.5), 0 <= beta <= c / 2: I0 = int d = int c^2 / 4 dalpha,
    I_alpha = int alpha d = int (s - c) c^2 / 4 dc, I_beta = int beta d = int c^3 / 24 dalpha
    (per unit reference area; times |U x V| for the physical area)."""
    assert s == 1.5
    c0, c1 = 0.5, 1.5
    I0 = (c1**3 - c0**3) / 12.0
    I_alpha = (s * (c1**3 - c0**3) / 12.0) - (c1**4 - c0**4) / 16.0  # alpha = s - c
    I_beta = (c1**4 - c0**4) / 96.0
    return I0, I_alpha, I_beta


@pytest.mark.parametrize("facet_type", ["quad4", "quad8", "quad9", "tri3", "tri6"])
@pytest.mark.parametrize("reverse", [False, True])
def test_oblique_parallelogram_water_line_across_elements(facet_type, reverse):
    """Plane parallelogram face X = alpha U + beta V, U = (0.3, 2, 1), V = (-0.5, 0.4, 2), in 3 x 4
    cells; the water line alpha + 2 beta = 1.5 crosses elements obliquely. Resultant
    -gamma |U x V| I0 n_out and first moments -gamma |U x V| (U I_alpha + V I_beta) (x) n_out, with the
    polynomial integrals of :func:`_oblique_parallelogram_closed_form` (plane face: White 2011 sec. 2.5).
    Node order reversed: same forces."""
    U, V = np.array([0.3, 2.0, 1.0]), np.array([-0.5, 0.4, 2.0])
    coords, facets = _grid_surface(lambda a, b: a * U + b * V, 3, 4, facet_type)
    cr = np.cross(U, V)
    n_out = cr / np.linalg.norm(cr)
    inward = _inward_from_normal(coords, facets, n_out)
    if reverse:
        rev = {"quad4": [0, 3, 2, 1], "quad8": [0, 3, 2, 1, 7, 6, 5, 4], "quad9": [0, 3, 2, 1, 7, 6, 5, 4, 8],
               "tri3": [0, 2, 1], "tri6": [0, 2, 1, 5, 4, 3]}[facet_type]
        facets = facets[:, rev]
    F = _forces(coords, facet_type, facets, inward, surface_level=1.5, unit_weight=GAMMA, vertical_axis=2)
    I0, Ia, Ib = _oblique_parallelogram_closed_form(1.5)
    J = np.linalg.norm(cr)
    np.testing.assert_allclose(F.sum(axis=0), -GAMMA * J * I0 * n_out, rtol=RTOL, atol=1e-9)
    np.testing.assert_allclose(_moments(coords, F), -GAMMA * J * np.outer(U * Ia + V * Ib, n_out),
                               rtol=RTOL, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# 6. silt


def test_silt_vertical_face_2d_and_3d():
    """Silt (K = 0.4, gamma' = 9000 N/m3) to 3.7 m on a vertical face: horizontal K gamma' h^2 / 2 at
    h / 3, no vertical load (EM 1110-2-2200 sec. 3-5); 2D (line2, thickness 2) and 3D (quad4, b = 4)."""
    K, gs, h = 0.4, 9000.0, 3.7
    ys = np.linspace(0.0, 10.0, 6)
    coords, facets = _polyline(np.column_stack([np.zeros(6), ys]))
    F = _forces(coords, "line2", facets, _inward_right(coords, facets), surface_level=h, unit_weight=gs,
                vertical_axis=1, thickness=2.0, lateral_coefficient=K)
    np.testing.assert_allclose(F[:, 0].sum(), 2.0 * K * gs * h * h / 2.0, rtol=RTOL)
    np.testing.assert_allclose((F[:, 0] * ys).sum(), 2.0 * K * gs * h**3 / 6.0, rtol=RTOL)
    np.testing.assert_array_equal(F[:, 1], 0.0)
    b = 4.0
    coords, facets = _grid_surface(lambda u, v: (0.0, b * u, 10.0 * v), 2, 5, "quad4")
    F = _forces(coords, "quad4", facets, _inward_from_normal(coords, facets, [-1, 0, 0]), surface_level=h,
                unit_weight=gs, vertical_axis=2, lateral_coefficient=K)
    np.testing.assert_allclose(F[:, 0].sum(), K * gs * b * h * h / 2.0, rtol=RTOL)
    np.testing.assert_allclose(_moments(coords, F)[2, 0], K * gs * b * h**3 / 6.0, rtol=RTOL)
    np.testing.assert_allclose(F[:, 1:], 0.0, atol=1e-9 * gs)


def test_silt_inclined_face_2d_and_3d():
    """Silt on a battered face x = m z (m = 0.3), level 4.45 m, K = 0.5, gamma' = 8500 N/m3: horizontal
    K gamma' h^2 / 2, vertical -gamma' x area (2D, m h^2 / 2) or volume (3D, b m h^2 / 2) of the silt
    above the face (EM 1110-2-2200 sec. 3-5)."""
    K, gs, h, m, H = 0.5, 8500.0, 4.45, 0.3, 10.0
    s_ = np.linspace(0.0, 1.0, 5)
    coords, facets = _polyline(np.column_stack([m * H * s_, H * s_]))
    F = _forces(coords, "line2", facets, _inward_right(coords, facets), surface_level=h, unit_weight=gs,
                vertical_axis=1, lateral_coefficient=K)
    np.testing.assert_allclose(F[:, 0].sum(), K * gs * h * h / 2.0, rtol=RTOL)
    np.testing.assert_allclose(F[:, 1].sum(), -gs * m * h * h / 2.0, rtol=RTOL)
    np.testing.assert_allclose((F[:, 1] * coords[:, 0]).sum(), -gs * m * h * h / 2.0 * m * h / 3.0, rtol=RTOL)
    b = 3.0
    for ft in ("quad4", "tri3", "quad8"):
        coords, facets = _grid_surface(lambda u, v: (m * H * v, b * u, H * v), 2, 3, ft)
        n_out = np.array([-1.0, 0.0, m]) / math.hypot(1.0, m)
        F = _forces(coords, ft, facets, _inward_from_normal(coords, facets, n_out), surface_level=h,
                    unit_weight=gs, vertical_axis=2, lateral_coefficient=K)
        np.testing.assert_allclose(F[:, 0].sum(), K * gs * b * h * h / 2.0, rtol=RTOL)
        np.testing.assert_allclose(F[:, 2].sum(), -gs * b * m * h * h / 2.0, rtol=RTOL)
        np.testing.assert_allclose(F[:, 1].sum(), 0.0, atol=1e-9 * gs)


def test_silt_with_unit_coefficient_equals_water():
    """K = 1 makes the geostatic stress isotropic: the same forces as water of the same unit weight."""
    U, V = np.array([0.3, 2.0, 1.0]), np.array([-0.5, 0.4, 2.0])
    coords, facets = _grid_surface(lambda a, b: a * U + b * V, 3, 4, "quad8")
    cr = np.cross(U, V)
    inward = _inward_from_normal(coords, facets, cr / np.linalg.norm(cr))
    kw = dict(surface_level=1.2, unit_weight=7000.0, vertical_axis=2)
    np.testing.assert_allclose(facet_pressure_forces(coords, "quad8", facets, inward, lateral_coefficient=1.0, **kw),
                               facet_pressure_forces(coords, "quad8", facets, inward, **kw), rtol=0, atol=1e-8)


# ---------------------------------------------------------------------------------------------
# 7. non-linear elevation on a face: subdivision, compared with an accurate reference


def _reference_face_forces(facet_type, X, sign, s, gamma, axis=2):
    """Nodal forces (nfn, 3) of water on one face by iterated integration: for each xi the elevation
    is a polynomial of degree <= 2 in eta, whose roots give the wet eta-intervals exactly (8-point Gauss
    on each: exact in eta); the outer integral over xi by adaptive quadrature (scipy quad_vec,
    epsrel 1e-14) with break points where the water line meets the edges eta = +-1."""
    xg, wg = np.polynomial.legendre.leggauss(8)

    def zeta(xi, eta):
        N, _ = shape_functions(facet_type, np.column_stack([np.full_like(eta, xi), eta]))
        return N @ X[:, axis]

    def inner(xi):
        z = zeta(xi, np.array([-1.0, 0.0, 1.0]))
        c0, c1, c2 = z[1], 0.5 * (z[2] - z[0]), 0.5 * (z[2] + z[0]) - z[1]
        poly = [c2, c1, c0 - s] if abs(c2) > 1e-14 * (abs(c1) + abs(c0) + 1.0) else [c1, c0 - s]
        r = np.roots(poly)
        r = np.sort(r[np.isreal(r)].real)
        br = np.concatenate([[-1.0], r[(r > -1.0) & (r < 1.0)], [1.0]])
        out = np.zeros((X.shape[0], 3))
        for a, b in zip(br[:-1], br[1:]):
            mid = 0.5 * (a + b)
            if c0 + c1 * mid + c2 * mid * mid >= s:
                continue
            eta = mid + 0.5 * (b - a) * xg
            pts = np.column_stack([np.full_like(eta, xi), eta])
            N, dN = shape_functions(facet_type, pts)
            x = N @ X
            A = sign * np.cross(dN[:, 0] @ X, dN[:, 1] @ X)
            d = np.maximum(s - x[:, axis], 0.0)
            out += np.einsum("q,qa,qd->ad", 0.5 * (b - a) * wg, N, -gamma * d[:, None] * A)
        return out.ravel()

    # break points in xi: the water line crossing the edges eta = -1, +1 (quadratic in xi)
    bps = []
    for e in (-1.0, 1.0):
        z = [zeta(x, np.array([e]))[0] for x in (-1.0, 0.0, 1.0)]
        c0, c1, c2 = z[1], 0.5 * (z[2] - z[0]), 0.5 * (z[2] + z[0]) - z[1]
        r = np.roots([c2, c1, c0 - s] if abs(c2) > 1e-14 else [c1, c0 - s])
        bps += [float(v.real) for v in r if abs(v.imag) < 1e-14 and -1.0 < v.real < 1.0]
    res, _ = quad_vec(inner, -1.0, 1.0, epsabs=0.0, epsrel=1e-14, points=sorted(bps) or None, limit=2000)
    return res.reshape(X.shape[0], 3)


_WARPED_QUAD4 = np.array([[0.0, 0.0, 0.0], [3.0, 0.2, 1.0], [3.4, 2.6, 5.0], [0.3, 2.2, 1.0]])
_CURVED_QUAD8 = np.array([
    [0.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 2.0, 2.0], [0.0, 0.0, 2.0],
    [0.1, 1.0, -0.3], [0.4, 2.0, 1.0], [-0.1, 1.0, 2.4], [-0.2, 0.0, 1.0],
])


@pytest.mark.parametrize("facet_type, X, level, tol", [
    ("quad4", _WARPED_QUAD4, 2.0, 3e-9),
    ("quad4", _WARPED_QUAD4, 3.7, 3e-9),
    ("quad8", _CURVED_QUAD8, 1.3, 3e-9),
    ("quad8", _CURVED_QUAD8, 2.3, 3e-9),
    ("quad8", _CURVED_QUAD8, 0.2, 5e-8),
])
def test_nonlinear_elevation_face_against_reference(facet_type, X, level, tol):
    """A warped quad4 (elevation bilinear, twist term 0.75 m against a 5 m range) and a curved quad8
    (mid nodes moved in and out of the plane), partly wet, against an iterated-integral reference
    (exact in eta, adaptive in xi: :func:`_reference_face_forces`; it agrees with the exact fully wet
    result to 1e-15 and with the tightest subdivision to 1e-13). Measured error, max-norm of the nodal
    force difference over the largest reference nodal force:

    ===================  ======================  ======================
    case                 subdivision_tol = 1e-8  subdivision_tol = 1e-11
    ===================  ======================  ======================
    quad4, level 2.0     9.6e-10                 2.9e-13
    quad4, level 3.7     4.0e-10                 9.8e-14
    quad8, level 1.3     7.8e-10                 6.6e-13
    quad8, level 2.3     5.2e-10                 1.9e-13
    quad8, level 0.2     1.6e-8 (barely wet)     1.0e-11
    ===================  ======================  ======================

    Asserted with a margin of about 3: the default tolerance and 1e-11 (where the error must also be
    smaller than at the default)."""
    facets = np.arange(len(X))[None, :]
    inward = X.mean(axis=0, keepdims=True) + np.array([[1.0, 0.0, 0.0]])
    Nc, dNc = shape_functions(facet_type, np.zeros((1, 2)))
    Ac = np.cross(dNc[0, 0] @ X, dNc[0, 1] @ X)
    sign = -1.0 if Ac @ (inward[0] - Nc[0] @ X) > 0 else 1.0
    ref = _reference_face_forces(facet_type, X, sign, level, GAMMA)
    kw = dict(surface_level=level, unit_weight=GAMMA, vertical_axis=2)
    F = _forces(X, facet_type, facets, inward, **kw)
    err = np.abs(F - ref).max() / np.abs(ref).max()
    assert err < tol
    Ft = _forces(X, facet_type, facets, inward, subdivision_tol=1e-11, **kw)
    err_t = np.abs(Ft - ref).max() / np.abs(ref).max()
    assert err_t < 3e-11 and err_t < err


def test_nonlinear_elevation_fully_wet_is_exact():
    """The same warped / curved faces entirely under water go through the one-pass Gauss rule: equal to
    the iterated-integral reference to round-off (1e-13)."""
    for facet_type, X in (("quad4", _WARPED_QUAD4), ("quad8", _CURVED_QUAD8)):
        facets = np.arange(len(X))[None, :]
        inward = X.mean(axis=0, keepdims=True) + np.array([[1.0, 0.0, 0.0]])
        Nc, dNc = shape_functions(facet_type, np.zeros((1, 2)))
        Ac = np.cross(dNc[0, 0] @ X, dNc[0, 1] @ X)
        sign = -1.0 if Ac @ (inward[0] - Nc[0] @ X) > 0 else 1.0
        ref = _reference_face_forces(facet_type, X, sign, 10.0, GAMMA)
        F = _forces(X, facet_type, facets, inward, surface_level=10.0, unit_weight=GAMMA, vertical_axis=2)
        assert np.abs(F - ref).max() / np.abs(ref).max() < 1e-13


@pytest.mark.slow
def test_curved_tri6_and_quad9_subdivision_converges():
    """Curved tri6 and quad9 faces (mid / centre nodes moved out of the plane and up or down), partly
    wet: the default result agrees with a 1e-12 subdivision to 1e-8 of the largest nodal force; a level
    below the face (-1 m) gives nothing."""
    tri6 = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.5], [0.5, 0.3, 2.0],
                     [1.0, 0.2, -0.2], [1.3, 0.5, 1.5], [0.2, -0.3, 1.1]])
    quad9 = np.vstack([_CURVED_QUAD8, [[0.3, 1.0, 0.8]]])
    for facet_type, X, level in (("tri6", tri6, 0.9), ("quad9", quad9, 1.1)):
        facets = np.arange(len(X))[None, :]
        inward = X.mean(axis=0, keepdims=True) + np.array([[1.0, 0.0, 0.0]])
        kw = dict(unit_weight=GAMMA, vertical_axis=2)
        F = _forces(X, facet_type, facets, inward, surface_level=level, **kw)
        Ft = _forces(X, facet_type, facets, inward, surface_level=level, subdivision_tol=1e-12, **kw)
        assert np.abs(F - Ft).max() < 1e-8 * np.abs(Ft).max()
        assert np.abs(Ft).max() > 0.0
        lo = _forces(X, facet_type, facets, inward, surface_level=-1.0, **kw)
        assert not lo.any()


# ---------------------------------------------------------------------------------------------
# helpers and edge cases


def test_collapsed_triangle_rule_exactness():
    """int_T xi^a eta^b = a! b! / (a + b + 2)! on the unit triangle for a + b <= 2 n - 2."""
    for n in (2, 4, 6):
        p, w = collapsed_triangle_rule(n)
        for a in range(2 * n - 1):
            for b in range(2 * n - 1 - a):
                exact = math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)
                np.testing.assert_allclose((w * p[:, 0] ** a * p[:, 1] ** b).sum(), exact, rtol=1e-13)


def test_empty_and_invalid_input():
    coords = np.zeros((3, 2))
    f = facet_pressure_forces(coords, "line2", np.zeros((0, 2), dtype=int), np.zeros((0, 2)), surface_level=1.0,
                              unit_weight=GAMMA, vertical_axis=1)
    assert f.shape == (6,) and not f.any()
    with pytest.raises(ValueError):
        facet_pressure_forces(coords, "quad4", [[0, 1, 2, 0]], [[0, 0]], surface_level=1.0, unit_weight=GAMMA,
                              vertical_axis=1)
    with pytest.raises(ValueError):
        facet_pressure_forces(coords, "line2", [[0, 1]], [[0, 0]], surface_level=1.0, unit_weight=GAMMA,
                              vertical_axis=2)
