"""Gravity dam generators (generators.dams): geometry, bodies and joints, named sets, self-weight
equilibrium, determinism, bad input and gmsh hygiene.

Sources: the Koyna benchmark section (Chopra &
Chakrabarti 1973, BSSA 63(2), fig. 1: heel (0, 0), toe (70, 0), downstream kink (19.25, 66.5),
crest (14.8, 103) and (0, 103); concrete rho = 2643 kg/m3, E = 31 027 MPa, nu = 0.2); elementary
geometry (shoelace areas of the section clipped between lift planes, prism volumes); statics
(the base reactions of a body under self-weight sum to its weight rho g A t).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import generators
import masonrydam
from masonrydam.errors import SceneError

gmsh = pytest.importorskip("gmsh")

from generators import dams  # noqa: E402
from generators._gmsh import gmsh_session  # noqa: E402

G = 9.80665
KOYNA = [(0.0, 0.0), (70.0, 0.0), (19.25, 66.5), (14.8, 103.0), (0.0, 103.0)]
#: Koyna section area from the published dimensions: a trapezoid 70 -> 19.25 m wide over the
#: lower 66.5 m and one 19.25 -> 14.8 m wide over the upper 36.5 m
KOYNA_AREA = 0.5 * (70.0 + 19.25) * 66.5 + 0.5 * (19.25 + 14.8) * 36.5  # 3588.975 m2


# ---------------------------------------------------------------------------------------------
# independent geometry helpers
# ---------------------------------------------------------------------------------------------


def shoelace(v):
    v = np.asarray(v, dtype=float)
    return 0.5 * abs(np.dot(v[:, 0], np.roll(v[:, 1], -1)) - np.dot(np.roll(v[:, 0], -1), v[:, 1]))


def clip(poly, y_lo, y_hi):
    """Sutherland-Hodgman clip of a polygon to the slab y_lo <= y <= y_hi."""

    def half(pts, inside, cross):
        out = []
        for i in range(len(pts)):
            a, b = pts[i - 1], pts[i]
            if inside(b):
                if not inside(a):
                    out.append(cross(a, b))
                out.append(b)
            elif inside(a):
                out.append(cross(a, b))
        return out

    def at(y0):
        return lambda a, b: (a[0] + (y0 - a[1]) * (b[0] - a[0]) / (b[1] - a[1]), y0)

    pts = [tuple(p) for p in poly]
    pts = half(pts, lambda p: p[1] >= y_lo, at(y_lo))
    pts = half(pts, lambda p: p[1] <= y_hi, at(y_hi))
    return pts


def element_areas(mesh, block):
    c = mesh.points[block.cells[:, :3 if block.type.startswith("tri") else 4]]
    return 0.5 * np.abs((c[:, :, 0] * np.roll(c[:, :, 1], -1, axis=1) - np.roll(c[:, :, 0], -1, axis=1) * c[:, :, 1]).sum(1))


def hex_volumes(mesh, block):
    """Volumes of hexahedra with planar faces, from their corners (divergence theorem on the six
    faces split into triangles about the face centre)."""
    from masonrydam.mesh.facets import element_facets

    x = mesh.points
    vol = np.zeros(len(block.cells))
    for _, loc in element_facets(block.type):
        f = x[block.cells[:, list(loc[:4])]]
        c = f.mean(axis=1)
        for k in range(4):
            a, b = f[:, k], f[:, (k + 1) % 4]
            vol += np.einsum("ij,ij->i", c, np.cross(a, b)) / 6.0
    return vol


def bodies(mesh):
    """Connected components of the continuum elements through shared nodes (interfaces excluded)
    and the component of each element, blocks in order."""
    rows, cols, off = [], [], 0
    for b in mesh.blocks:
        rows.append(np.repeat(np.arange(len(b.cells)) + off, b.cells.shape[1]))
        cols.append(b.cells.ravel())
        off += len(b.cells)
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    inc = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(off, mesh.n_nodes)).tocsr()
    return connected_components(inc @ inc.T, directed=False)


def node_body(mesh, labels):
    nb = np.full(mesh.n_nodes, -1)
    off = 0
    for b in mesh.blocks:
        nb[b.cells] = labels[off:off + len(b.cells)][:, None]
        off += len(b.cells)
    return nb


def check_interfaces(mesh, labels):
    """Every interface joins two different bodies through coincident node pairs."""
    nb = node_body(mesh, labels)
    for j in mesh.joints:
        half = j.cells.shape[1] // 2
        bot, top = j.cells[:, :half], j.cells[:, half:]
        assert np.allclose(mesh.points[bot], mesh.points[top]), j.name
        assert (nb[bot] != nb[top]).all(), j.name
        assert (nb[bot] == nb[bot][:, :1]).all() and (nb[top] == nb[top][:, :1]).all(), j.name


def interface_normals(mesh, joint):
    """Normals of the interfaces of a joint block from the node order (the kernels' convention:
    2D tangent node 0 -> 1 turned +90 degrees; 3D right-hand normal of the bottom face)."""
    x = mesh.points
    c = joint.cells
    if mesh.dim == 2:
        t = x[c[:, 1]] - x[c[:, 0]]
        n = np.stack([-t[:, 1], t[:, 0]], axis=1)
    else:
        n = np.cross(x[c[:, 1]] - x[c[:, 0]], x[c[:, 3]] - x[c[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


# ---------------------------------------------------------------------------------------------
# 2D
# ---------------------------------------------------------------------------------------------


@pytest.mark.reference
def test_koyna_preset_is_the_published_section():
    """The preset's polygon is the Koyna benchmark section's, its area the value computed from the published
    dimensions; the same section from parameters (slopes from the published vertices) is identical."""
    mesh = dams.gravity_dam_2d(preset="koyna", element_size=5.0)
    area = sum(element_areas(mesh, b).sum() for b in mesh.blocks)
    assert KOYNA_AREA == pytest.approx(3588.975, abs=1e-9)
    assert area == pytest.approx(KOYNA_AREA, rel=1e-12)
    assert shoelace(KOYNA) == pytest.approx(KOYNA_AREA, rel=1e-14)
    para = dams.gravity_dam_2d(height=103.0, crest_width=14.8, crest_kink_height=66.5,
                               downstream_upper_slope=(19.25 - 14.8) / (103.0 - 66.5),
                               downstream_slope=(70.0 - 19.25) / 66.5, element_size=5.0, reservoir_level=91.75)
    assert np.allclose(para.points, mesh.points, atol=1e-9)
    # the named set of the waterline: the upstream face node at the 1967 reservoir level, 91.75 m
    assert mesh.points[mesh.node_sets["waterline"]].tolist() == [[0.0, 91.75]]
    assert mesh.points[mesh.node_sets["crest_upstream"]].tolist() == [[0.0, 103.0]]


@pytest.mark.parametrize("order, element", [(1, "quad"), (2, "quad"), (1, "tri"), (2, "tri")])
def test_lift_areas_equal_the_clipped_section(order, element):
    """Each lift block's area equals the shoelace area of the section clipped between its lift
    planes (less a gallery's area); the foundation's is width x depth."""
    H, s = 103.0, 10.3 * 1.5
    gal = {"x": 4.0, "y": 20.0, "width": 2.5, "height": 3.5}
    mesh = dams.gravity_dam_2d(preset="koyna", lift_spacing=s, element_size=4.0, order=order, element=element,
                               galleries=[gal], foundation_width=160.0, foundation_depth=40.0)
    etype = {("quad", 1): "quad4", ("quad", 2): "quad8", ("tri", 1): "tri3", ("tri", 2): "tri6"}[(element, order)]
    assert {b.type for b in mesh.blocks} == {etype}
    n, lab = bodies(mesh)
    levels = [0.0] + [k * s for k in range(1, math.floor(H / s) + 1)] + [H]
    assert n == len(levels) - 1 + 1  # the lifts and the foundation
    off = 0
    found = None
    for b in mesh.blocks:
        a = element_areas(mesh, b)
        cy = mesh.points[b.cells[:, :3]][:, :, 1].mean(axis=1)
        lb = lab[off:off + len(b.cells)]
        off += len(b.cells)
        if b.name == "foundation":
            found = a.sum()
            assert len(np.unique(lb)) == 1
            continue
        for y0, y1 in zip(levels[:-1], levels[1:]):
            sel = (cy > y0) & (cy < y1)
            assert len(np.unique(lb[sel])) == 1, "one body per lift"
            expected = shoelace(clip(KOYNA, y0, y1))
            if y0 <= gal["y"] and gal["y"] + gal["height"] <= y1:
                expected -= gal["width"] * gal["height"]
            assert a[sel].sum() == pytest.approx(expected, rel=1e-10)
    assert found == pytest.approx(160.0 * 40.0, rel=1e-12)
    check_interfaces(mesh, lab)
    nodes_per_face = 2 if order == 1 else 3
    assert {j.cells.shape[1] for j in mesh.joints} == {2 * nodes_per_face}
    # the gallery's edges: its whole perimeter
    g = mesh.facet_sets["gallery_0"].facets
    length = np.linalg.norm(mesh.points[g[:, 1]] - mesh.points[g[:, 0]], axis=1).sum()
    assert length == pytest.approx(2 * (gal["width"] + gal["height"]), rel=1e-12)


@pytest.mark.parametrize("spacing", [7.0, 10.3 * 1.5, 30.0])
def test_number_of_lift_joints_and_normals(spacing):
    """floor(H / s) lift joints (H / s not an integer) at multiples of s; every interface normal
    points up (+y)."""
    H = 103.0
    mesh = dams.gravity_dam_2d(preset="koyna", lift_spacing=spacing, element_size=5.0)
    (lifts,) = [j for j in mesh.joints if j.name == "lift_joints"]
    y = np.unique(np.round(mesh.points[lifts.cells[:, :2]][:, :, 1], 9))
    assert len(y) == math.floor(H / spacing)
    assert np.allclose(y, spacing * np.arange(1, len(y) + 1))
    n = interface_normals(mesh, lifts)
    assert np.allclose(n, [0.0, 1.0])
    # the lift joints span the whole section: joint length = section width at each level
    x = mesh.points[lifts.cells[:, :2]]
    for yl in y:
        sel = np.isclose(x[:, 0, 1], yl)
        width = np.abs(x[sel, 1, 0] - x[sel, 0, 0]).sum()
        assert width == pytest.approx(np.ptp(np.array(clip(KOYNA, yl, yl + 1e-9))[:, 0]), rel=1e-9)


def test_listed_lift_heights_and_base_joint():
    mesh = dams.gravity_dam_2d(height=40.0, crest_width=6.0, downstream_slope=0.75, upstream_slope=0.05,
                               lift_heights=[25.0, 5.0, 12.5], foundation_width=60.0, foundation_depth=20.0,
                               element_size=2.0, order=2)
    names = {j.name: j for j in mesh.joints}
    assert set(names) == {"lift_joints", "base_joint"}
    y = np.unique(np.round(mesh.points[names["lift_joints"].cells[:, :3]][:, :, 1], 9))
    assert y.tolist() == [5.0, 12.5, 25.0]
    base = mesh.points[names["base_joint"].cells]
    assert np.allclose(base[:, :, 1], 0.0)
    # base joint length = base width: toe at 0.05 * 40 + 6 + 0.75 * 40
    assert np.abs(base[:, 1, 0] - base[:, 0, 0]).sum() == pytest.approx(2.0 + 6.0 + 30.0, rel=1e-12)
    assert np.allclose(interface_normals(mesh, names["base_joint"]), [0.0, 1.0])
    n, lab = bodies(mesh)
    assert n == 4 + 1
    check_interfaces(mesh, lab)
    for s in ("foundation_bottom", "foundation_sides", "foundation_top", "upstream_face", "downstream_face", "crest"):
        assert s in mesh.facet_sets and s in mesh.node_sets
    assert "base" not in mesh.facet_sets  # the base is a joint, the supports are the foundation's
    assert np.allclose(mesh.points[mesh.node_sets["foundation_bottom"], 1], -20.0)


def test_named_faces_2d_are_outward_and_wet_below_the_reservoir():
    mesh = dams.gravity_dam_2d(preset="koyna", lift_spacing=10.3, element_size=3.0, reservoir_level=80.0)
    x = mesh.points

    def outward(name):
        f = mesh.facet_sets[name].facets
        t = x[f[:, 1]] - x[f[:, 0]]
        return np.stack([t[:, 1], -t[:, 0]], axis=1) / np.linalg.norm(t, axis=1)[:, None], f

    n, f = outward("upstream_face")
    assert np.allclose(n, [-1.0, 0.0]) and np.allclose(x[f, 0], 0.0)
    n, f = outward("crest")
    assert np.allclose(n, [0.0, 1.0]) and np.allclose(x[f, 1], 103.0)
    n, f = outward("base")
    assert np.allclose(n, [0.0, -1.0]) and np.allclose(x[f, 1], 0.0)
    n, f = outward("downstream_face")
    assert (n[:, 0] > 0).all() and (n[:, 1] > 0).all()
    wet = mesh.facet_sets["upstream_wet"].facets
    assert x[wet, 1].max() == pytest.approx(80.0) and x[wet, 1].min() == pytest.approx(0.0)
    assert np.abs(x[wet[:, 1], 1] - x[wet[:, 0], 1]).sum() == pytest.approx(80.0, rel=1e-12)


@pytest.mark.reference
def test_self_weight_of_koyna_section_through_a_scene(monkeypatch):
    """Plane strain, 1 m thick, base fixed, lifts on stiff linear joints: the base reactions sum to
    the section's weight rho g A (A from the published dimensions) and have no horizontal resultant."""
    monkeypatch.setitem(generators.GENERATORS, "gravity_dam_2d", dams.gravity_dam_2d)
    rho = 2643.0
    scene = {
        "model": {"name": "koyna_gravity", "thickness": 1.0, "hypothesis": "plane_strain"},
        "mesh": {"generator": "gravity_dam_2d", "parameters": {"preset": "koyna", "lift_spacing": "10.3 m",
                                                                "element_size": 4.0}},
        "materials": {"dam": {"youngs_modulus": "31027 MPa", "poisson_ratio": 0.2, "density": rho}},
        "joints": {"lift_joints": {"law": "linear", "normal_stiffness": 1e12, "shear_stiffness": 1e12}},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]}],
    }
    ds = masonrydam.run(scene)
    Ry = ds.reaction.sel(component="y").values[-1]
    Rx = ds.reaction.sel(component="x").values[-1]
    W = rho * G * KOYNA_AREA * 1.0
    assert Ry.sum() == pytest.approx(W, rel=1e-6)
    assert abs(Rx.sum()) < 1e-6 * W
    on_base = np.isclose(ds.y.values, 0.0)
    assert np.abs(Ry[~on_base]).max() < 1e-9 * W


def test_generation_is_deterministic():
    kw = dict(preset="koyna", lift_spacing=10.3, element_size=3.0, foundation_width=150.0, foundation_depth=30.0,
              galleries=[{"x": 5.0, "y": 12.0, "width": 2.5, "height": 3.0}], order=2)
    a, b = dams.gravity_dam_2d(**kw), dams.gravity_dam_2d(**kw)
    _same(a, b)
    kw3 = dict(valley_bottom_width=30.0, valley_top_width=90.0, n_monoliths=3, preset="koyna", lift_spacing=35.0,
               element_size=15.0, foundation_width=120.0, foundation_depth=20.0)
    _same(dams.gravity_dam_3d(**kw3), dams.gravity_dam_3d(**kw3))


def _same(a, b):
    assert np.array_equal(a.points, b.points)
    assert [(x.name, x.type) for x in a.blocks + a.joints] == [(x.name, x.type) for x in b.blocks + b.joints]
    for x, y in zip(a.blocks + a.joints, b.blocks + b.joints):
        assert np.array_equal(x.cells, y.cells)
    assert a.node_sets.keys() == b.node_sets.keys() and a.facet_sets.keys() == b.facet_sets.keys()
    for k in a.node_sets:
        assert np.array_equal(a.node_sets[k], b.node_sets[k])
    for k in a.facet_sets:
        assert np.array_equal(a.facet_sets[k].facets, b.facet_sets[k].facets)


def test_vertical_faced_dam_is_structured():
    """Rectangular lifts (vertical faces) and the foundation are meshed by transfinite grids: every
    interior node has four quadrilaterals around it and the element count is the grid's."""
    mesh = dams.gravity_dam_2d(height=12.0, crest_width=4.0, downstream_slope=0.0, lift_spacing=3.0,
                               foundation_width=10.0, foundation_depth=4.0, element_size=1.0)
    counts = {b.name: len(b.cells) for b in mesh.blocks}
    assert counts == {"dam": 4 * 12, "foundation": 10 * 4}
    a = np.concatenate([element_areas(mesh, b) for b in mesh.blocks])
    assert np.allclose(a, 1.0)


# ---------------------------------------------------------------------------------------------
# 3D
# ---------------------------------------------------------------------------------------------


def koyna_area_above(z):
    """Area of the Koyna section above elevation z (closed form: trapezoids)."""
    return shoelace(clip(KOYNA, z, 103.0))


@pytest.mark.parametrize("order", [1, 2])
def test_3d_monolith_volumes_bodies_and_joints(order):
    """Monolith i, of width B/n, stands on the valley profile at its centre line x_c: its volume is
    (B/n) A(z_b) with z_b = 103 (|x_c - B/2| - b/2) / ((B - b)/2) clipped to [0, 103] (A: the
    section's area above z_b), less the longitudinal gallery where the monolith contains it. Every
    lift of every monolith is a body of its own; lift joints point up, contraction joints along
    +x; the rock volume is the stepped valley's (with the gallery where it runs through rock)."""
    b, B, nm, s = 40.0, 100.0, 4, 37.0
    fw, fd = 110.0, 20.0
    gal = {"x": 6.0, "y": 4.0, "width": 3.0, "height": 4.0}
    ga = gal["width"] * gal["height"]
    mesh = dams.gravity_dam_3d(b, B, nm, preset="koyna", lift_spacing=s, element_size=13.0, order=order,
                               foundation_width=fw, foundation_depth=fd, galleries=[gal])
    assert {bl.type for bl in mesh.blocks} == {"hex8" if order == 1 else "hex20"}
    X = np.linspace(0.0, B, nm + 1)
    xc = 0.5 * (X[1:] + X[:-1])
    zb = np.clip((np.abs(xc - B / 2) - b / 2) / ((B - b) / 2), 0.0, 1.0) * 103.0
    # (the centre-line elevations 55.6 m are more than a quarter element from the lift levels: no snapping)
    assert np.allclose(zb, [103 * 17.5 / 30, 0, 0, 103 * 17.5 / 30])
    (dam,) = [bl for bl in mesh.blocks if bl.name == "dam"]
    (rock,) = [bl for bl in mesh.blocks if bl.name == "foundation"]
    vol = hex_volumes(mesh, dam)
    assert (vol > 0).all() and (hex_volumes(mesh, rock) > 0).all()
    cx = mesh.points[dam.cells[:, :8]][:, :, 0].mean(axis=1)
    for i in range(nm):
        sel = (cx > X[i]) & (cx < X[i + 1])
        in_dam = zb[i] < gal["y"]
        assert vol[sel].sum() == pytest.approx((B / nm) * (koyna_area_above(zb[i]) - ga * in_dam), rel=1e-10)
    rock_expected = B * fw * fd + sum((B / nm) * (fw * z - ga * (z > gal["y"])) for z in zb)
    assert hex_volumes(mesh, rock).sum() == pytest.approx(rock_expected, rel=1e-10)
    n, lab = bodies(mesh)
    lifts_in = [len([k for k in range(3) if (k + 1) * s > z]) for z in zb]  # lifts (0, 37, 74, 103) above z_b
    assert n == sum(lifts_in) + 1
    check_interfaces(mesh, lab)
    joints = {j.name: j for j in mesh.joints}
    assert set(joints) == {"lift_joints", "contraction_joints", "base_joint"}
    assert np.allclose(interface_normals(mesh, joints["lift_joints"]), [0, 0, 1])
    assert np.allclose(interface_normals(mesh, joints["contraction_joints"]), [1, 0, 0])
    nb = interface_normals(mesh, joints["base_joint"])
    assert np.all(np.isclose(nb, [0, 0, 1]).all(1) | np.isclose(np.abs(nb), [1, 0, 0]).all(1))
    # contraction joints lie on the monolith boundaries and cover the common part of neighbours
    xj = mesh.points[joints["contraction_joints"].cells[:, :4], 0]
    assert np.all(np.isclose(xj[:, :1], X[1:-1]).any(axis=1))
    c = joints["contraction_joints"].cells
    p = mesh.points
    area = np.linalg.norm(np.cross(p[c[:, 2]] - p[c[:, 0]], p[c[:, 3]] - p[c[:, 1]]), axis=1).sum() / 2  # planar quads
    expected = sum(koyna_area_above(max(zb[i], zb[i + 1])) - ga * (max(zb[i], zb[i + 1]) < gal["y"]) for i in range(nm - 1))
    assert area == pytest.approx(expected, rel=1e-10)
    for name in ("lift_joints", "contraction_joints", "base_joint", "upstream_face", "downstream_face", "crest",
                 "foundation_bottom", "foundation_sides"):
        assert name in {j.name for j in mesh.joints} | set(mesh.facet_sets)
    assert np.allclose(mesh.points[mesh.node_sets["foundation_bottom"], 2], -fd)
    assert np.allclose(mesh.points[mesh.node_sets["crest"], 2], 103.0)
    # the gallery runs along the whole dam axis: its faces cover perimeter x length
    gf = mesh.facet_sets["gallery_0"].facets[:, :4]
    p = mesh.points
    garea = np.linalg.norm(np.cross(p[gf[:, 2]] - p[gf[:, 0]], p[gf[:, 3]] - p[gf[:, 1]]), axis=1).sum() / 2
    assert garea == pytest.approx(2 * (gal["width"] + gal["height"]) * B, rel=1e-10)


def test_3d_without_foundation_is_supported_on_its_stepped_base(monkeypatch):
    """No foundation: the base set holds the monolith bases and the abutment steps; a self-weight
    run through a scene gives base reactions summing to rho g V (V: the analytic monolith volumes)."""
    monkeypatch.setitem(generators.GENERATORS, "gravity_dam_3d", dams.gravity_dam_3d)
    b, B, nm = 40.0, 100.0, 4
    params = {"valley_bottom_width": b, "valley_top_width": B, "n_monoliths": nm, "preset": "koyna",
              "lift_spacing": 30.0, "element_size": 12.0}
    mesh = dams.gravity_dam_3d(**params)
    assert {j.name for j in mesh.joints} == {"lift_joints", "contraction_joints"}
    X = np.linspace(0.0, B, nm + 1)
    xc = 0.5 * (X[1:] + X[:-1])
    zb = np.clip((np.abs(xc - B / 2) - b / 2) / ((B - b) / 2), 0.0, 1.0) * 103.0
    zb = np.where(np.abs(zb - 60.0) < 0.25 * 12.0, 60.0, zb)  # snapped to the lift joint at 60 m
    V = sum((B / nm) * koyna_area_above(z) for z in zb)
    rho = 2643.0
    scene = {
        "model": {"name": "dam3d", "dimension": 3},
        "mesh": {"generator": "gravity_dam_3d", "parameters": params},
        "materials": {"dam": {"youngs_modulus": "31027 MPa", "poisson_ratio": 0.2, "density": rho}},
        "joints": {n: {"law": "linear", "normal_stiffness": 1e12, "shear_stiffness": 1e12}
                   for n in ("lift_joints", "contraction_joints")},
        "supports": [{"set": "base", "components": ["x", "y", "z"]}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]}],
    }
    ds = masonrydam.run(scene)
    Rz = ds.reaction.sel(component="z").values[-1]
    assert Rz.sum() == pytest.approx(rho * G * V, rel=1e-6)


# ---------------------------------------------------------------------------------------------
# bad input, gmsh hygiene, export
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs, key", [
    (dict(height=-10.0, crest_width=5.0), "height"),
    (dict(height=30.0, crest_width=0.0), "crest_width"),
    (dict(height=30.0, crest_width=5.0, element_size=0.0), "element_size"),
    (dict(height=30.0, crest_width=5.0, lift_spacing=30.0), "lift_spacing"),
    (dict(height=30.0, crest_width=5.0, lift_spacing=45.0), "lift_spacing"),
    (dict(height=30.0, crest_width=5.0, lift_heights=[10.0, 31.0]), "lift_heights[1]"),
    (dict(height=30.0, crest_width=5.0, crest_kink_height=35.0), "crest_kink_height"),
    (dict(height=30.0, crest_width=5.0, downstream_slope=-0.3), "downstream_slope"),
    (dict(height=30.0, crest_width=5.0, upstream_slope=-0.1), "upstream_slope"),
    (dict(polyline=[(0, 0), (10, 0), (0, 10), (10, 10)]), "polyline"),
    (dict(height=30.0, crest_width=5.0, galleries=[{"x": -1.0, "y": 5.0, "width": 2.0, "height": 2.0}]), "galleries[0]"),
    (dict(height=30.0, crest_width=5.0, galleries=[{"x": 2.0, "y": 5.0, "width": 2.0, "height": 2.0},
                                                     {"x": 3.0, "y": 6.0, "width": 2.0, "height": 2.0}]), "galleries[1]"),
    (dict(height=30.0, crest_width=5.0, foundation_width=20.0, foundation_depth=10.0), "foundation_width"),
    (dict(height=30.0, crest_width=5.0, foundation_width=80.0), "foundation_depth"),
    (dict(preset="koyna", height=50.0), "preset"),
    (dict(preset="hoover"), "preset"),
    (dict(height=30.0, crest_width=5.0, reservoir_level=40.0), "reservoir_level"),
    (dict(height=30.0, crest_width=5.0, element="hex"), "element"),
    (dict(height=30.0, crest_width=5.0, element_size=1e-4), "element_size"),
])
def test_bad_input_names_the_parameter_before_gmsh(kwargs, key, monkeypatch):
    def no_gmsh(*a, **k):
        raise AssertionError("gmsh was called")

    monkeypatch.setattr(dams, "gmsh_session", no_gmsh)
    with pytest.raises(SceneError) as exc:
        dams.gravity_dam_2d(**kwargs, key="mesh.parameters")
    assert exc.value.key == f"mesh.parameters.{key}"


@pytest.mark.parametrize("kwargs, key", [
    (dict(valley_bottom_width=50.0, valley_top_width=40.0, n_monoliths=3), "valley_top_width"),
    (dict(valley_bottom_width=10.0, valley_top_width=100.0, n_monoliths=0), "n_monoliths"),
    (dict(valley_bottom_width=0.0, valley_top_width=100.0, n_monoliths=60), "n_monoliths"),
])
def test_bad_3d_input(kwargs, key, monkeypatch):
    monkeypatch.setattr(dams, "gmsh_session", lambda *a, **k: (_ for _ in ()).throw(AssertionError("gmsh called")))
    with pytest.raises(SceneError) as exc:
        dams.gravity_dam_3d(**kwargs, height=30.0, crest_width=5.0, element_size=2.0)
    assert exc.value.key == f"mesh.parameters.{key}"


def test_gmsh_is_finalized_after_an_error_and_a_user_session_survives(monkeypatch):
    assert not gmsh.isInitialized()
    with pytest.raises(Exception):
        with gmsh_session():
            gmsh.model.mesh.setTransfiniteCurve(12345, 3)  # no such curve: gmsh raises
    assert not gmsh.isInitialized()
    mesh = dams.gravity_dam_2d(height=10.0, crest_width=3.0, element_size=2.0)
    assert mesh.n_elements() > 0 and not gmsh.isInitialized()
    # a failure in the middle of a generator's gmsh work (after the geometry is built)

    def broken(*args, **kwargs):
        raise RuntimeError("meshing failed")

    with monkeypatch.context() as mp:
        mp.setattr(dams, "_structure", broken)
        with pytest.raises(RuntimeError, match="meshing failed"):
            dams.gravity_dam_2d(height=10.0, crest_width=3.0, element_size=2.0)
    assert not gmsh.isInitialized()
    assert np.array_equal(dams.gravity_dam_2d(height=10.0, crest_width=3.0, element_size=2.0).points, mesh.points)
    # inside a caller's own gmsh session: the caller's model and options are left as they were
    gmsh.initialize([], readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("user_model")
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.37)
        again = dams.gravity_dam_2d(height=10.0, crest_width=3.0, element_size=2.0)
        assert gmsh.isInitialized() and gmsh.model.getCurrent() == "user_model"
        assert gmsh.model.getEntities(3) == [(3, 1)]
        assert gmsh.option.getNumber("Mesh.MeshSizeMax") == 0.37
        assert np.array_equal(again.points, mesh.points)
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("dim", [2, 3])
def test_gmsh_helpers_return_meshio_order(dim):
    """Quadratic elements read from the gmsh API by physical group: after the GMSH_TO_MESHIO_ORDER
    permutation every mid-edge node is the midpoint of its VTK edge (masonrydam.elements.shapes)."""
    from masonrydam.elements.shapes import ELEMENT_TYPES

    from generators._gmsh import get_nodes, physical_group_elements, tags_to_index

    with gmsh_session(options={"Mesh.SecondOrderIncomplete": 1, "Mesh.RecombineAll": 1}) as g:
        occ = g.model.occ
        if dim == 2:
            tag = occ.addRectangle(0, 0, 0, 2.0, 1.0)
        else:
            tag = occ.addBox(0, 0, 0, 2.0, 1.0, 1.5)
        occ.synchronize()
        for _, c in g.model.getEntities(1):
            g.model.mesh.setTransfiniteCurve(c, 3)
        for _, sf in g.model.getEntities(2):
            g.model.mesh.setTransfiniteSurface(sf)
        if dim == 3:
            g.model.mesh.setTransfiniteVolume(tag)
        g.model.addPhysicalGroup(dim, [tag], name="body")
        g.model.mesh.generate(dim)
        g.model.mesh.setOrder(2)
        tags, xyz = get_nodes(g)
        elems = physical_group_elements(g, dim, "body")
    name = "quad8" if dim == 2 else "hex20"
    assert list(elems) == [name]
    conn = tags_to_index(tags, elems[name])
    assert len(conn) == (4 if dim == 2 else 8)
    for e in ELEMENT_TYPES[name].edges:
        a, b, mid = e
        assert np.allclose(xyz[conn[:, mid]], 0.5 * (xyz[conn[:, a]] + xyz[conn[:, b]]))
    assert not gmsh.isInitialized()


def test_export_through_meshio_keeps_joints_as_their_own_blocks(tmp_path):
    import meshio

    from masonrydam.mesh.io import to_meshio

    mesh = dams.gravity_dam_2d(preset="koyna", lift_spacing=20.6, element_size=8.0, foundation_width=120.0,
                               foundation_depth=30.0)
    m = to_meshio(mesh)
    assert len(m.cells) == len(mesh.blocks) + len(mesh.joints)
    meshio.write(tmp_path / "dam.vtu", m)
    back = meshio.read(tmp_path / "dam.vtu")
    n_joint_cells = sum(len(j.cells) for j in mesh.joints)
    assert int(np.concatenate(back.cell_data["is_joint"]).sum()) == n_joint_cells
