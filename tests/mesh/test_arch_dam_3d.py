"""The arch dam generator (generators.arch_dams.arch_dam_3d): geometry against closed forms, joints,
named sets, bad input and one self-weight run.

Closed forms (elementary geometry, the module docstring's convention: crown extrados at x = y = 0,
arch centre at (0, R_e(z)), angle phi from the crown towards +x):

- an annular sector of angle theta between radii R_i and R_e has the area theta R_m t (R_m the mean
  radius, t = R_e - R_i), so with R_m and t linear in z the dam's volume is
  V = theta H [R_m0 t0 + (R_m0 dt + dR t0)/2 + dR dt/3];
- the mesh replaces each arc of angle d (a grid segment) by a chord (hex8) or by the parabola through
  its ends and midpoint (hex20, straight radial and vertical edges). Every horizontal cross-section of
  such an element is exactly that polygon or parabolic figure (the nodes move linearly with z), so
  the meshed volume is the exact one times k(d), with no other error:
  hex8  k = sin(d) / d                                      = 1 - d^2/6 + ...  (chords),
  hex20 k = (2/d) [sin(d)/2 + (4/3) sin(d/2) (1 - cos(d/2))] = 1 + O(d^4)      (parabolic segment
  2/3 chord x rise added to the chord polygon);
- the crest arc of radius R and angle theta cut into n equal chords has the length 2 R n sin(theta/2n);
- double curvature (crown_overhang a, overhang_height z_o): the crown's extrados is the parabola
  y_u(z) = -a (1 - ((z - z_o) / (H - z_o))^2) and each arch's centre is at (0, y_u + R_e). The shift
  y_u(z) along y is a shear of unit determinant, so every closed form above holds unchanged; in the mesh
  z depends on the elevation coordinate alone within an element, so det J (hence the meshed volume,
  kappa V) is the same as without the overhang at every point.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
from generators.arch_dams import arch_dam_3d
from masonrydam.elements.shapes import reference_nodes, shape_functions
from masonrydam.errors import SceneError
from test_dams import bodies as element_bodies  # tests/mesh is on sys.path (pytest's rootdir-relative import)

G = 9.80665
#: a constant-angle arch whose radius and thickness both vary with height (R 80 -> 100 m, t 12 -> 5 m)
VARYING = dict(height=60.0, crest_radius=100.0, base_radius=80.0, central_angle_deg=120.0, crest_thickness=5.0,
               base_thickness=12.0)


def kappa(d, order):
    """Meshed / exact area of an annular sector whose arcs are split into segments of angle d (rad)."""
    if order == 1:
        return math.sin(d) / d
    return (2.0 / d) * (0.5 * math.sin(d) + (4.0 / 3.0) * math.sin(d / 2) * (1.0 - math.cos(d / 2)))


def sector_volume(theta, R_m0, R_mH, t0, tH, H, z0=0.0):
    """Exact volume (m3) of the annular sector of angle theta between elevations z0 and H, R_m and t
    linear in z from (R_m0, t0) at z = 0 to (R_mH, tH) at z = H: theta * integral of R_m t dz."""
    dR, dt = R_mH - R_m0, tH - t0

    def F(z):  # antiderivative of R_m(z) t(z)
        s = z / H
        return H * (R_m0 * t0 * s + (R_m0 * dt + dR * t0) * s ** 2 / 2 + dR * dt * s ** 3 / 3)

    return theta * (F(H) - F(z0))


def element_volumes(points, block, n_gauss=4):
    """Volume of each hexahedron (hex8 / hex20) by Gauss quadrature of det J; also the smallest det J."""
    g, w = np.polynomial.legendre.leggauss(n_gauss)
    xi = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
    wt = np.einsum("i,j,k->ijk", w, w, w).ravel()
    _, dN = shape_functions(block.type, xi)  # (q, 3, nen)
    X = points[block.cells]  # (e, nen, 3)
    J = np.einsum("qan,enb->eqab", dN, X)
    det = np.linalg.det(J)
    return det @ wt, det.min()


def dam_block(mesh):
    (dam,) = [b for b in mesh.blocks if b.name == "dam"]
    return dam


def segments_per_monolith(R_max, theta, n, h):
    """The generator's documented rule: ceil(R_e,max theta / (n h)) elements along each monolith's arc."""
    return math.ceil(R_max * theta / n / h - 1e-9)


def unique_points(x, tol=1e-9):
    """One of each group of coincident points (the copies of a node split by joints), unrounded."""
    _, first = np.unique(np.round(x / tol), axis=0, return_index=True)
    return x[np.sort(first)]


def bodies(mesh):
    """Connected components of the continuum elements through shared nodes (interfaces excluded, as
    tests/mesh/test_dams.py finds them), and the body of each node."""
    n, lab = element_bodies(mesh)
    node_body = np.full(mesh.n_nodes, -1)
    off = 0
    for b in mesh.blocks:
        node_body[b.cells] = lab[off:off + len(b.cells)][:, None]
        off += len(b.cells)
    return n, node_body


def assert_joints_conformal(mesh):
    """Every interface joins coincident node pairs, each side's nodes in one body, the two sides in two."""
    _, node_body = bodies(mesh)
    for j in mesh.joints:
        half = j.cells.shape[1] // 2
        bot, top = j.cells[:, :half], j.cells[:, half:]
        assert np.allclose(mesh.points[bot], mesh.points[top], atol=1e-12), j.name
        assert (node_body[bot] != node_body[top]).all(), j.name
        assert (node_body[bot] == node_body[bot][:, :1]).all() and (node_body[top] == node_body[top][:, :1]).all()


def crown_upstream_y(z, a, z_o, H):
    """The crown's extrados y_u(z) = -a (1 - ((z - z_o) / (H - z_o))^2) (m)."""
    return -a * (1.0 - ((np.asarray(z) - z_o) / (H - z_o)) ** 2)


def nodal_jacobians(points, block):
    """det J of every hexahedron at its own nodes: (e, nen)."""
    _, dN = shape_functions(block.type, reference_nodes(block.type))
    return np.linalg.det(np.einsum("qan,enb->eqab", dN, points[block.cells]))


def face_normals(points, facets):
    """Unit normals (right-hand rule of the corner order: outward for the generator's facet sets) and
    centroids of quadrilateral facets."""
    c = points[facets[:, :4]]
    n = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
    return n / np.linalg.norm(n, axis=1, keepdims=True), c.mean(axis=1)


def quad_areas(points, facets):
    """Areas of planar quadrilaterals from their corners (half the cross product of the diagonals)."""
    c = points[facets[:, :4]]
    return 0.5 * np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), axis=1)


# ---------------------------------------------------------------------------------------------
# volume and crest length
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("order", [1, 2])
def test_volume_is_the_annular_sector_times_the_chord_factor(order):
    """Rectangular valley, R and t linear in z: the meshed volume is kappa(d) V exactly (d = theta / (n m),
    m the documented segments per monolith), every Jacobian is positive, and the error kappa - 1 shrinks
    as d^2 (hex8) or d^4 (hex20) when the element size halves."""
    theta = math.radians(120.0)
    n, h = 4, 8.0
    V = sector_volume(theta, 80.0 - 6.0, 100.0 - 2.5, 12.0, 5.0, 60.0)
    assert V == pytest.approx(theta * 60.0 * (74.0 * 12.0 + (74.0 * -7.0 + 23.5 * 12.0) / 2 + 23.5 * -7.0 / 3), rel=1e-14)
    errors = []
    for size in (h, h / 2):
        mesh = arch_dam_3d(**VARYING, n_monoliths=n, lift_spacing=20.0, element_size=size, order=order)
        vol, det_min = element_volumes(mesh.points, dam_block(mesh))
        assert det_min > 0
        m = segments_per_monolith(100.0, theta, n, size)
        d = theta / (n * m)
        assert vol.sum() == pytest.approx(kappa(d, order) * V, rel=1e-11)
        errors.append(abs(vol.sum() / V - 1.0))
    assert errors[1] < errors[0] / (3.5 if order == 1 else 12.0)
    assert dam_block(mesh).type == ("hex8" if order == 1 else "hex20")


def test_crest_arc_is_on_the_extrados_and_its_chords_sum_to_the_polygon_length():
    """crest_upstream: nodes on the circle of radius R_e(H) about (0, R_e(H)) spanning the full central
    angle; the chords between consecutive nodes sum to 2 R n sin(theta / 2n) (n = 2 m per monolith for
    hex20, whose mid-edge nodes are on the arc too), which tends to R theta."""
    theta = math.radians(120.0)
    for order in (1, 2):
        mesh = arch_dam_3d(**VARYING, n_monoliths=3, element_size=10.0, order=order)
        x = unique_points(mesh.points[mesh.node_sets["crest_upstream"]])
        assert np.allclose(x[:, 2], 60.0)
        r = np.hypot(x[:, 0], x[:, 1] - 100.0)
        assert np.allclose(r, 100.0, rtol=1e-12)
        ang = np.sort(np.arctan2(x[:, 0], 100.0 - x[:, 1]))
        assert ang[0] == pytest.approx(-theta / 2, abs=1e-12) and ang[-1] == pytest.approx(theta / 2, abs=1e-12)
        nseg = order * 3 * segments_per_monolith(100.0, theta, 3, 10.0)
        assert len(x) == nseg + 1
        p = x[np.argsort(np.arctan2(x[:, 0], 100.0 - x[:, 1]))]
        length = np.linalg.norm(np.diff(p, axis=0), axis=1).sum()
        assert length == pytest.approx(2 * 100.0 * nseg * math.sin(theta / (2 * nseg)), rel=1e-12)
        assert abs(length - 100.0 * theta) < 100.0 * theta ** 3 / (24 * nseg ** 2) * 1.0001  # R theta^3 / 24 n^2
    # the crown's extrados is the vertical line x = y = 0, the crest chord 2 R sin(theta/2)
    up = mesh.points[mesh.node_sets["upstream_face"]]
    crown = np.abs(up[:, 0]) < 1e-9
    assert crown.any() and np.allclose(up[crown, 1], 0.0, atol=1e-9)
    assert np.ptp(x[:, 0]) == pytest.approx(2 * 100.0 * math.sin(theta / 2), rel=1e-12)


# ---------------------------------------------------------------------------------------------
# joints
# ---------------------------------------------------------------------------------------------


def test_joints_are_matching_facets_with_counts_areas_and_normals_of_the_grid():
    """Rectangular valley, constant radius and thickness, n monoliths, lifts every 15 m of a 45 m arch:
    n x 3 bodies; every interface joins coincident node pairs of two different bodies; counts:
    contraction (n - 1) x (z elements) x (thickness elements), lift 2 levels x n m x (thickness
    elements); areas: contraction joints (n - 1) H t (planar radial rectangles), each lift level
    kappa(d) theta R_m t; normals: lift +z, contraction +-(cos phi_j, sin phi_j, 0) at the joint angles."""
    R, t, H, n, h = 50.0, 4.0, 45.0, 4, 5.0
    theta = math.radians(100.0)
    mesh = arch_dam_3d(height=H, crest_radius=R, central_angle_deg=100.0, crest_thickness=t, n_monoliths=n,
                       lift_spacing=15.0, element_size=h)
    nb, _ = bodies(mesh)
    assert nb == n * 3
    assert_joints_conformal(mesh)
    joints = {j.name: j for j in mesh.joints}
    assert set(joints) == {"lift_joints", "contraction_joints"}
    m = segments_per_monolith(R, theta, n, h)
    nt, nz = 2, 9  # thickness: max(2, ceil(4 / 5)); height: 3 lifts of ceil(15 / 5)
    assert len(joints["contraction_joints"].cells) == (n - 1) * nz * nt
    assert len(joints["lift_joints"].cells) == 2 * n * m * nt
    p = mesh.points
    c = joints["contraction_joints"].cells
    assert quad_areas(p, c).sum() == pytest.approx((n - 1) * H * t, rel=1e-12)
    lift_area = quad_areas(p, joints["lift_joints"].cells).sum()
    assert lift_area == pytest.approx(2 * kappa(theta / (n * m), 1) * theta * (R - t / 2) * t, rel=1e-12)
    normals, cen = face_normals(p, joints["lift_joints"].cells)
    assert np.allclose(normals, [0, 0, 1])
    normals, cen = face_normals(p, c)
    phi_j = np.arctan2(cen[:, 0], R - cen[:, 1])
    expected = np.column_stack([np.cos(phi_j), np.sin(phi_j), np.zeros(len(c))])
    assert np.allclose(np.abs((normals * expected).sum(1)), 1.0)
    assert np.allclose(np.sort(np.unique(np.round(phi_j, 9))), np.round(np.linspace(-theta / 2, theta / 2, n + 1)[1:-1], 9))


def test_benched_valley_monolith_volumes_and_foundation():
    """Trapezoidal valley (bottom width b, top: the crest chord of the axis L): monolith i stands at
    z_b where its centre line x_c(z) = R_m |sin phi_c| meets the wall b/2 + (L - b)/2 z/H (found here by
    bisection); its volume is kappa (theta/n) t R_m (H - z_b). Constant R and t: the rock volume is
    kappa (1/2)[(R + e)^2 - (R - t - e)^2] [theta D + sum (theta/n) z_b]. The bodies are the lifts above
    each base plus the rock; every dam-rock facet is a base_joint (horizontal bases, vertical steps)."""
    R, t, H, n, h, b = 60.0, 6.0, 40.0, 6, 5.0, 30.0
    D, e = 15.0, 8.0
    theta = math.radians(110.0)
    Rm = R - t / 2
    mesh = arch_dam_3d(height=H, crest_radius=R, central_angle_deg=110.0, crest_thickness=t, n_monoliths=n,
                       valley_bottom_width=b, lift_spacing=12.0, foundation_depth=D, foundation_extent=e,
                       element_size=h, reservoir_level=35.0)
    L = 2 * Rm * math.sin(theta / 2)
    edges = np.linspace(-theta / 2, theta / 2, n + 1)
    zb = []
    for pc in 0.5 * (edges[1:] + edges[:-1]):
        def gap(z):  # wall minus centre line
            return b / 2 + (L - b) / 2 * z / H - Rm * abs(math.sin(pc))
        lo, hi = 0.0, H
        if gap(lo) >= 0:
            zb.append(0.0)
            continue
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if gap(mid) >= 0 else (mid, hi)
        zb.append(0.5 * (lo + hi))
    zb = np.array(zb)
    assert zb[0] == zb[-1] > 0 and zb[2] == zb[3] == 0.0
    # no base is within a quarter element of a lift level (12, 24, 36) or another base: no snapping
    assert all(min(abs(z - k) for k in (0.0, 12.0, 24.0, 36.0)) > h / 4 or z == 0 for z in zb)
    m = segments_per_monolith(R, theta, n, h)
    k = kappa(theta / (n * m), 1)
    dam = dam_block(mesh)
    vol, _ = element_volumes(mesh.points, dam)
    cen = mesh.points[dam.cells].mean(axis=1)
    ang = np.arctan2(cen[:, 0], R - cen[:, 1])
    for i in range(n):
        sel = (ang > edges[i]) & (ang < edges[i + 1])
        assert vol[sel].sum() == pytest.approx(k * theta / n * Rm * t * (H - zb[i]), rel=1e-10)
        assert cen[sel, 2].min() > zb[i]
    (rock,) = [bl for bl in mesh.blocks if bl.name == "foundation"]
    rvol, det_min = element_volumes(mesh.points, rock)
    assert det_min > 0
    expected = k * 0.5 * ((R + e) ** 2 - (R - t - e) ** 2) * (theta * D + (theta / n) * zb.sum())
    assert rvol.sum() == pytest.approx(expected, rel=1e-10)
    nb, node_body = bodies(mesh)
    lift_tops = (12.0, 24.0, 36.0, H)
    assert nb == sum(len([top for top in lift_tops if top > z]) for z in zb) + 1 == 2 * 2 + 2 * 3 + 2 * 4 + 1
    joints = {j.name: j for j in mesh.joints}
    assert set(joints) == {"lift_joints", "contraction_joints", "base_joint"}
    nrm, c = face_normals(mesh.points, joints["base_joint"].cells)
    horizontal = np.isclose(nrm[:, 2], 1.0)
    assert np.allclose(nrm[~horizontal, 2], 0.0) and (~horizontal).any()
    # the horizontal base joint: the dam's footprint at each base, kappa (theta/n) R_m t per monolith
    assert quad_areas(mesh.points, joints["base_joint"].cells[horizontal]).sum() == pytest.approx(k * theta * Rm * t, rel=1e-10)
    x = mesh.points
    assert np.allclose(x[mesh.node_sets["foundation_bottom"], 2], -D)
    assert set(mesh.facet_sets) >= {"foundation_bottom", "foundation_sides", "foundation_top", "dam_ends", "crest",
                                    "upstream_face", "downstream_face", "upstream_wet"}
    assert "base" not in mesh.facet_sets
    # the rock's sides: at r = R + e, r = R - t - e (the base plan) or on the end radial planes
    s = unique_points(x[mesh.node_sets["foundation_sides"]])
    r = np.hypot(s[:, 0], R - s[:, 1])
    a = np.abs(np.arctan2(s[:, 0], R - s[:, 1]))
    assert np.all(np.isclose(r, R + e) | np.isclose(r, R - t - e) | np.isclose(a, theta / 2))
    # dam ends: the radial planes at +-theta/2 from the end monoliths' bases to the crest
    d = x[mesh.node_sets["dam_ends"]]
    assert np.allclose(np.abs(np.arctan2(d[:, 0], R - d[:, 1])), theta / 2)
    assert d[:, 2].min() == pytest.approx(zb[0]) and d[:, 2].max() == pytest.approx(H)


# ---------------------------------------------------------------------------------------------
# faces and the reservoir
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("order", [1, 2])
def test_faces_point_outwards_and_the_wet_face_lies_below_the_reservoir(order):
    """Upstream facets point away from the arch centre (their horizontal normal is the radial direction
    (sin phi, -cos phi)), downstream ones towards it, the crest up; upstream_wet is the upstream face
    below the reservoir level: for a constant radius its area is the extrados polygon's perimeter times
    the level, 2 R N sin(theta / 2N) z_w (N chords); the waterline nodes lie at z_w on the extrados."""
    R, t, H, zw, n, h = 50.0, 4.0, 30.0, 22.5, 3, 5.0
    theta = math.radians(90.0)
    mesh = arch_dam_3d(height=H, crest_radius=R, central_angle_deg=90.0, crest_thickness=t, n_monoliths=n,
                       lift_spacing=10.0, element_size=h, reservoir_level=zw, order=order)
    x = mesh.points
    for name, sign in (("upstream_face", 1.0), ("downstream_face", -1.0)):
        nrm, cen = face_normals(x, mesh.facet_sets[name].facets)
        phi = np.arctan2(cen[:, 0], R - cen[:, 1])
        radial = np.column_stack([np.sin(phi), -np.cos(phi), np.zeros(len(phi))])
        assert np.allclose(sign * (nrm * radial).sum(1), 1.0, atol=1e-12), name
    nrm, _ = face_normals(x, mesh.facet_sets["crest"].facets)
    assert np.allclose(nrm, [0, 0, 1])
    assert np.allclose(x[mesh.node_sets["crest"], 2], H)
    wet = mesh.facet_sets["upstream_wet"].facets
    assert x[wet, 2].max() == pytest.approx(zw)
    up = mesh.facet_sets["upstream_face"].facets
    wet_keys = {tuple(sorted(f[:4])) for f in wet}
    assert wet_keys <= {tuple(sorted(f[:4])) for f in up}
    dry = np.array([f for f in up if tuple(sorted(f[:4])) not in wet_keys])
    assert len(dry) + len(wet) == len(up) and x[dry, 2].min() == pytest.approx(zw)
    N = n * segments_per_monolith(R, theta, n, h)
    if order == 1:
        assert quad_areas(x, wet).sum() == pytest.approx(2 * R * N * math.sin(theta / (2 * N)) * zw, rel=1e-12)
    wl = x[mesh.node_sets["waterline"]]
    assert np.allclose(wl[:, 2], zw) and np.allclose(np.hypot(wl[:, 0], R - wl[:, 1]), R)
    assert len(unique_points(wl)) == order * N + 1


# ---------------------------------------------------------------------------------------------
# bad input, determinism, a run
# ---------------------------------------------------------------------------------------------

BASE = dict(height=30.0, crest_radius=50.0, central_angle_deg=100.0, crest_thickness=4.0, n_monoliths=3, element_size=5.0)


@pytest.mark.parametrize("change, key", [
    (dict(height=-1.0), "height"),
    (dict(crest_radius=0.0), "crest_radius"),
    (dict(central_angle_deg=200.0), "central_angle_deg"),
    (dict(central_angle_deg="1 m"), "central_angle_deg"),
    (dict(crest_thickness=50.0), "crest_thickness"),
    (dict(base_radius=20.0, base_thickness=25.0), "base_thickness"),
    (dict(n_monoliths=0), "n_monoliths"),
    (dict(n_monoliths=2.0), "n_monoliths"),
    (dict(valley_bottom_width=120.0), "valley_bottom_width"),
    (dict(valley_bottom_width=0.0, n_monoliths=40, element_size=2.0), "n_monoliths"),
    (dict(lift_spacing=30.0), "lift_spacing"),
    (dict(foundation_extent=5.0), "foundation_depth"),
    (dict(foundation_depth=10.0, foundation_extent=46.0), "foundation_extent"),
    (dict(element_size=0.0), "element_size"),
    (dict(element_size=0.01), "element_size"),
    (dict(order=3), "order"),
    (dict(reservoir_level=31.0), "reservoir_level"),
    (dict(crown_overhang=-1.0), "crown_overhang"),
    (dict(crown_overhang="x"), "crown_overhang"),
    (dict(crown_overhang=3.0, overhang_height=0.0), "overhang_height"),
    (dict(crown_overhang=3.0, overhang_height=30.0), "overhang_height"),
    (dict(crown_overhang=3.0, overhang_height=-5.0), "overhang_height"),
    (dict(overhang_height=31.0), "overhang_height"),
    # one hex8 across a half circle: a flat element (det J = 0 at its nodes)
    (dict(central_angle_deg=180.0, n_monoliths=1, element_size=200.0), "element_size"),
])
def test_bad_input_names_the_parameter(change, key):
    with pytest.raises(SceneError) as exc:
        arch_dam_3d(**{**BASE, **change})
    assert exc.value.key == f"mesh.parameters.{key}"
    assert f"mesh.parameters.{key}" in str(exc.value)


def test_generation_is_deterministic():
    kw = dict(BASE, valley_bottom_width=20.0, lift_spacing=10.0, foundation_depth=10.0, foundation_extent=5.0,
              reservoir_level=25.0, order=2)
    a, b = arch_dam_3d(**kw), arch_dam_3d(**kw)
    assert np.array_equal(a.points, b.points)
    for x, y in zip(a.blocks + a.joints, b.blocks + b.joints):
        assert (x.name, x.type) == (y.name, y.type) and np.array_equal(x.cells, y.cells)
    assert all(np.array_equal(a.node_sets[k], b.node_sets[k]) for k in a.node_sets)


def test_a_scene_runs_self_weight_on_a_tiny_arch():
    """(The generator is registered for this test: its scene-reference rows come with its registration.)
    Two monoliths of two lifts on a fixed base, linear joints, self-weight in 3 steps: the run
    converges, the result holds the joints' points (4 per quad4 interface) and the vertical reactions sum
    to rho g V with V = kappa theta H [R_m0 t0 + ...] (the meshed volume)."""
    params = {"height": 20.0, "crest_radius": 40.0, "central_angle_deg": 100.0, "crest_thickness": 3.0,
              "base_thickness": 5.0, "n_monoliths": 2, "lift_spacing": 10.0, "element_size": 10.0}
    rho = 2400.0
    scene = {
        "model": {"name": "arch", "dimension": 3},
        "mesh": {"generator": "arch_dam_3d", "parameters": params},
        "materials": {"dam": {"youngs_modulus": "25000 MPa", "poisson_ratio": 0.2, "density": rho}},
        "joints": {n: {"law": "linear", "normal_stiffness": 1e11, "shear_stiffness": 1e11}
                   for n in ("lift_joints", "contraction_joints")},
        "supports": [{"set": "base", "components": ["x", "y", "z"]}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}], "steps": 3}],
    }
    ds = masonrydam.run(scene)
    mesh = arch_dam_3d(**params)
    assert ds.sizes["joint_point"] == 4 * mesh.n_interfaces() > 0
    assert np.isfinite(ds.joint_opening.values).all()
    theta = math.radians(100.0)
    m = segments_per_monolith(40.0, theta, 2, 10.0)
    V = kappa(theta / (2 * m), 1) * sector_volume(theta, 37.5, 38.5, 5.0, 3.0, 20.0)
    Rz = ds.reaction.sel(component="z").values[-1]
    assert Rz.sum() == pytest.approx(rho * G * V, rel=1e-6)


# ---------------------------------------------------------------------------------------------
# double curvature: the crown overhang
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("order", [1, 2])
def test_overhang_is_a_shear_volume_and_jacobians_unchanged(order):
    """With an overhang a every node moves by exactly y_u(z) along y (x and z bit for bit the same), the
    meshed volume is still kappa(d) V, and det J at every element node equals the vertical arch's to
    round-off, also for an overhang as large as the height (crest slope 2a / (H - z_o) = 3.6): an
    overhang cannot invert an element, so the generator accepts it."""
    theta, n, h, H = math.radians(120.0), 4, 8.0, 60.0
    V = sector_volume(theta, 80.0 - 6.0, 100.0 - 2.5, 12.0, 5.0, H)
    d = theta / (n * segments_per_monolith(100.0, theta, n, h))
    plain = arch_dam_3d(**VARYING, n_monoliths=n, lift_spacing=20.0, element_size=h, order=order)
    det0 = nodal_jacobians(plain.points, dam_block(plain))
    assert det0.min() > 0
    for a in (8.0, H):
        mesh = arch_dam_3d(**VARYING, n_monoliths=n, lift_spacing=20.0, element_size=h, order=order, crown_overhang=a)
        x, x0 = mesh.points, plain.points
        assert np.array_equal(x[:, [0, 2]], x0[:, [0, 2]])
        assert np.allclose(x[:, 1] - x0[:, 1], crown_upstream_y(x[:, 2], a, 0.45 * H, H), rtol=0, atol=1e-12 * H)
        vol, det_min = element_volumes(x, dam_block(mesh))
        assert det_min > 0
        assert vol.sum() == pytest.approx(kappa(d, order) * V, rel=1e-11)
        det = nodal_jacobians(x, dam_block(mesh))
        assert np.allclose(det, det0, rtol=0, atol=1e-12 * np.abs(det0).max() * a / 8.0)


def test_crown_upstream_nodes_lie_on_the_parabola():
    """Even n: the crown joint is at phi = 0, so the upstream crown nodes (x = 0) sample the extrados
    y_u(z) = -a (1 - ((z - z_o) / (H - z_o))^2) at every node layer: 0 at the crest, -a at z_o (a node
    layer here: z_o = 0.45 x 60 = 27 m, a multiple of the 3 m element size), and
    -a (1 - (z_o / (H - z_o))^2) = -a (1 - (27/33)^2) at the base; the crest arc is where it was."""
    H, a, z_o = 60.0, 6.0, 27.0
    for order, extra in ((1, {}), (2, dict(overhang_height=z_o))):
        mesh = arch_dam_3d(height=H, crest_radius=100.0, base_radius=80.0, central_angle_deg=120.0,
                           crest_thickness=5.0, base_thickness=12.0, n_monoliths=4, element_size=3.0, order=order,
                           crown_overhang=a, **extra)
        up = unique_points(mesh.points[mesh.node_sets["upstream_face"]])
        crown = up[np.abs(up[:, 0]) < 1e-9]
        crown = crown[np.argsort(crown[:, 2])]
        assert len(crown) == order * 20 + 1
        assert np.allclose(crown[:, 1], crown_upstream_y(crown[:, 2], a, z_o, H), rtol=0, atol=1e-12 * H)
        assert crown[-1, 2] == H and crown[-1, 1] == pytest.approx(0.0, abs=1e-12 * H)
        k = int(np.argmin(crown[:, 1]))
        assert crown[k, 2] == pytest.approx(z_o, abs=1e-12 * H) and crown[k, 1] == pytest.approx(-a, rel=1e-12)
        assert crown[0, 2] == 0.0 and crown[0, 1] == pytest.approx(-a * (1 - (z_o / (H - z_o)) ** 2), rel=1e-12)
        assert crown[0, 1] > crown[k, 1]  # the base lies downstream of the overhang
        # every upstream node is on its arch's extrados, about the moved centre (0, y_u + R_e)
        Re = 80.0 + 20.0 * up[:, 2] / H
        r = np.hypot(up[:, 0], up[:, 1] - (crown_upstream_y(up[:, 2], a, z_o, H) + Re))
        assert np.allclose(r, Re, rtol=1e-12)
        x = unique_points(mesh.points[mesh.node_sets["crest_upstream"]])
        assert np.allclose(np.hypot(x[:, 0], x[:, 1] - 100.0), 100.0, rtol=1e-12)


def test_default_overhang_gives_todays_nodes_bit_for_bit():
    """crown_overhang omitted, 0 or 0.0 (with or without an overhang_height) gives the same arrays, and
    the crown's extrados is exactly y = 0 as before the overhang existed."""
    kw = dict(BASE, valley_bottom_width=20.0, lift_spacing=10.0, foundation_depth=10.0, foundation_extent=5.0,
              reservoir_level=25.0, n_monoliths=4)
    ref = arch_dam_3d(**kw)
    for extra in (dict(crown_overhang=0.0), dict(crown_overhang=0), dict(crown_overhang=0.0, overhang_height=5.0)):
        m = arch_dam_3d(**kw, **extra)
        assert np.array_equal(m.points, ref.points)
        for x, y in zip(m.blocks + m.joints, ref.blocks + ref.joints):
            assert (x.name, x.type) == (y.name, y.type) and np.array_equal(x.cells, y.cells)
        assert all(np.array_equal(m.node_sets[k], ref.node_sets[k]) for k in ref.node_sets)
    up = ref.points[ref.node_sets["upstream_face"]]
    assert (up[up[:, 0] == 0.0, 1] == 0.0).all() and (up[:, 0] == 0.0).sum() > 0


@pytest.mark.parametrize("order", [1, 2])
def test_overhanging_arch_on_a_benched_valley_keeps_its_joints_conformal(order):
    """An overhanging arch with lifts, a benched valley and a widened foundation: the joints join
    coincident nodes of different bodies; the dam's and the rock's volumes and the bodies are those of
    the vertical arch; the rock below the valley floor is at the base arch's plan: its nodes lie between
    the radii R - t - e and R + e about (0, y_u(0) + R)."""
    R, t, H, D, e, a = 60.0, 6.0, 40.0, 15.0, 8.0, 5.0
    kw = dict(height=H, crest_radius=R, central_angle_deg=110.0, crest_thickness=t, n_monoliths=6,
              valley_bottom_width=30.0, lift_spacing=12.0, foundation_depth=D, foundation_extent=e, element_size=5.0,
              reservoir_level=35.0, order=order)
    mesh = arch_dam_3d(**kw, crown_overhang=a)
    plain = arch_dam_3d(**kw)
    assert_joints_conformal(mesh)
    assert {j.name: len(j.cells) for j in mesh.joints} == {j.name: len(j.cells) for j in plain.joints}
    assert bodies(mesh)[0] == bodies(plain)[0] == 2 * 2 + 2 * 3 + 2 * 4 + 1
    for b, b0 in zip(mesh.blocks, plain.blocks):
        vol, det_min = element_volumes(mesh.points, b)
        assert det_min > 0 and vol.sum() == pytest.approx(element_volumes(plain.points, b0)[0].sum(), rel=1e-12)
    x = mesh.points
    below = x[x[:, 2] < 0.0]
    r = np.hypot(below[:, 0], below[:, 1] - (crown_upstream_y(0.0, a, 0.45 * H, H) + R))
    assert r.min() == pytest.approx(R - t - e, rel=1e-12) and r.max() == pytest.approx(R + e, rel=1e-12)
    assert np.allclose(x[mesh.node_sets["foundation_bottom"], 2], -D)
