"""Tests of the parametric masonry wall generators (generators.walls.masonry_wall_2d and
generators.walls3d.masonry_wall_3d).

Sources:
- simplified micro-model: units expanded by the joint thickness, zero-thickness interfaces on every
  bed, head and collar joint, and optionally a potential crack in the middle of each unit (Lourenco
  1996, PhD thesis TU Delft, ch. 6; Lourenco & Rots 1997, J. Eng. Mech. 123(7) 660-668, fig. 2);
  Tzamtzis & Asteris, sec. 3.3: every block is a separate continuum joined to its
  neighbours only through joint elements;
- bond patterns: Hendry, Sinha & Davies, "Design of Masonry Structures" (3rd ed. 1997), ch. 1;
  Brick Industry Association Technical Notes 10 and 30: stretcher (running) bond with half units at
  the ends of alternate courses; English bond = alternate courses of stretchers and headers, queen
  closer next to the quoin header; Flemish bond = headers and stretchers alternating in each course,
  each header centred on the stretcher below;
- Eindhoven wall geometry: Raijmakers & Vermeltfoort (1992) (990 mm long, bricks 210 x 52 x
  100 mm, 10 mm joints: expanded units 220 x 62 x 110 mm, 4.5 units per course);
- expected interface counts: combinatorics of the structured grid (generators/grid.py,
  generators/grid3d.py: every interval between block edges split into ceil(interval / size)
  equal elements; size = min(expanded unit dimensions) / elements_per_unit);
- uniform compression: elementary elasticity; under a uniform top pressure p on a wall supported so
  that the homogeneous state is admissible (base: vertical only; one end: along the wall; 3D: front
  face across), sigma_vertical = -p everywhere, the other stresses vanish, bed joints carry t_n = -p
  and nothing else carries load (the joints' uniform closure is a rigid shift of the courses above).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import generators
import masonrydam
from generators import walls, walls3d
from generators.walls import masonry_wall_2d
from generators.walls3d import masonry_wall_3d
from masonrydam.errors import SceneError

# Eindhoven bricks (Raijmakers & Vermeltfoort 1992): 210 x 52 x 100 mm, 10 mm joints
BRICK = dict(unit_length=0.21, unit_height=0.052, unit_width=0.1, joint_thickness=0.01)
LU, HU, WU = 0.22, 0.062, 0.11  # expanded unit length, height, width (m)


# ------------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------------
def n_el(interval, size):
    """Elements along one grid interval (generators/grid.py: ceil(interval / size), 1e-9 slack)."""
    return max(1, math.ceil(interval / size - 1e-9))


def counts(mesh):
    return {j.name: len(j.cells) for j in mesh.joints}


def components(mesh):
    """Connected bodies of the continuum elements through shared nodes (interfaces ignored):
    (number, label of each node)."""
    rows, cols = [], []
    for b in mesh.blocks:
        c = b.cells
        rows.append(np.repeat(c[:, :1], c.shape[1], axis=1).ravel())
        cols.append(c.ravel())
    r, c = np.concatenate(rows), np.concatenate(cols)
    g = coo_matrix((np.ones(len(r)), (r, c)), shape=(mesh.n_nodes, mesh.n_nodes))
    return connected_components(g, directed=False)


def measures(mesh, block):
    """Areas (2D) or volumes (3D) of the cells of a block: the elements are axis-aligned rectangles
    / boxes, so the measure is the product of the extents of their corner nodes."""
    nc = 4 if mesh.dim == 2 else 8
    p = mesh.points[block.cells[:, :nc]]
    return np.prod(np.ptp(p, axis=1), axis=1)


def group_measure(mesh):
    out = {}
    for b in mesh.blocks:
        out[b.name] = out.get(b.name, 0.0) + measures(mesh, b).sum()
    return out


def check_bodies_joined_only_by_interfaces(mesh):
    """Every interface joins two different bodies, each face within one body."""
    _, label = components(mesh)
    for j in mesh.joints:
        ns = j.cells.shape[1] // 2
        bot, top = label[j.cells[:, :ns]], label[j.cells[:, ns:]]
        assert (bot == bot[:, :1]).all() and (top == top[:, :1]).all()
        assert (bot[:, 0] != top[:, 0]).all(), f"an interface of '{j.name}' joins a body to itself"
        assert np.allclose(mesh.points[j.cells[:, :ns]], mesh.points[j.cells[:, ns:]], atol=1e-12)


def same_mesh(a, b):
    assert np.array_equal(a.points, b.points)
    assert [(x.name, x.type) for x in a.blocks + a.joints] == [(x.name, x.type) for x in b.blocks + b.joints]
    for x, y in zip(a.blocks + a.joints, b.blocks + b.joints):
        assert np.array_equal(x.cells, y.cells)
    assert list(a.node_sets) == list(b.node_sets) and list(a.facet_sets) == list(b.facet_sets)
    for k in a.node_sets:
        assert np.array_equal(a.node_sets[k], b.node_sets[k])
    for k in a.facet_sets:
        assert np.array_equal(a.facet_sets[k].facets, b.facet_sets[k].facets)


# ------------------------------------------------------------------------------------------------
# analytic interface counts
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("n, m, epu, order, element", [(4, 3, 1, 1, "quad"), (5, 4, 2, 1, "quad"),
                                                        (3, 2, 1, 2, "quad9"), (4, 3, 2, 1, "tri")])
def test_running_bond_2d_counts_with_unit_cracks(n, m, epu, order, element):
    """n courses x m units (length m * LU), running bond, a crack in every whole unit.

    Grid lines along x every LU / 2 (head joints of both course types and the unit mid-lines
    coincide): n_x = 2 m n_el(LU / 2) elements along a bed joint; n_z = n_el(HU) along a head joint.
    Even courses: m whole units (m - 1 head joints, m cracks); odd courses: half, m - 1 whole, half
    (m head joints, m - 1 cracks)."""
    mesh = masonry_wall_2d(length=m * LU, height=n * HU, bond="running", elements_per_unit=epu, order=order,
                           element=element, unit_cracks=True, **{k: v for k, v in BRICK.items() if k != "unit_width"})
    s = min(LU, HU) / epu
    n_x, n_z = 2 * m * n_el(LU / 2, s), n_el(HU, s)
    even, odd = (n + 1) // 2, n // 2
    assert counts(mesh) == {"bed_joints": (n - 1) * n_x,
                            "head_joints": (even * (m - 1) + odd * m) * n_z,
                            "unit_cracks": (even * m + odd * (m - 1)) * n_z}
    n_bodies, _ = components(mesh)
    assert n_bodies == 2 * (even * m + odd * (m - 1)) + 2 * odd  # two halves per whole unit + half units
    check_bodies_joined_only_by_interfaces(mesh)


@pytest.mark.parametrize("m, n", [(3, 4), (4, 3)])
def test_english_bond_2d_counts(m, n):
    """English bond in elevation, length m LU = 2 m WU: stretcher courses of m units; header courses
    H, Q (queen closer, WU / 2), 2m - 2 headers, and a header cut to WU / 2 at the right end: 2m + 1
    pieces. With cracks (mid-face of whole units) grid lines fall every WU / 2, so a bed joint has
    4 m n_el(WU / 2) elements."""
    mesh = masonry_wall_2d(length=m * LU, height=n * HU, bond="english", elements_per_unit=1, unit_cracks=True,
                           **BRICK)
    s = min(LU, HU, WU)
    n_x, n_z = 4 * m * n_el(WU / 2, s), n_el(HU, s)
    st, hd = (n + 1) // 2, n // 2
    assert counts(mesh) == {"bed_joints": (n - 1) * n_x,
                            "head_joints": (st * (m - 1) + hd * 2 * m) * n_z,
                            "unit_cracks": (st * m + hd * (2 * m - 1)) * n_z}
    check_bodies_joined_only_by_interfaces(mesh)


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("n, m, epu", [(3, 3, 1), (4, 2, 2)])
def test_stretcher_bond_3d_counts(n, m, epu, order):
    """Single-wythe 3D stretcher wall (thickness WU): the 2D counts times n_y = n_el(WU)."""
    mesh = masonry_wall_3d(length=m * LU, height=n * HU, bond="stretcher", elements_per_unit=epu, order=order,
                           unit_cracks=True, **BRICK)
    s = min(LU, HU, WU) / epu
    n_x, n_y, n_z = 2 * m * n_el(LU / 2, s), n_el(WU, s), n_el(HU, s)
    even, odd = (n + 1) // 2, n // 2
    assert counts(mesh) == {"bed_joints": (n - 1) * n_x * n_y,
                            "head_joints": (even * (m - 1) + odd * m) * n_y * n_z,
                            "unit_cracks": (even * m + odd * (m - 1)) * n_y * n_z}
    assert {j.type for j in mesh.joints} == {"interface_quad4" if order == 1 else "interface_quad8"}
    check_bodies_joined_only_by_interfaces(mesh)


def test_english_bond_3d_counts_with_collar_joints():
    """English bond one brick thick (T = LU = 2 WU), length m LU, n courses, cracks on.

    x grid lines: 0, WU, then every WU / 2 (queen closer and header joints, stretcher joints and
    mid-lines): n_x = n_el(WU) + (2 (2m - 1)) n_el(WU / 2). y: the collar plane (and the headers'
    crack plane) at WU: n_y = n_el(WU) per wythe. Stretcher courses: m stretchers per wythe, head
    joints (m - 1) x 2 wythes, a collar joint along the whole course, 2m cracks (planes normal to
    x). Header courses: 2m + 1 pieces through the thickness (2m head joints over 2 n_y), 2m - 1 whole
    headers each with a crack normal to y (n_el(WU / 2) x 2 elements along x)."""
    m, n = 3, 4
    mesh = masonry_wall_3d(length=m * LU, height=n * HU, bond="english", unit_cracks=True, **BRICK)
    s = min(LU, HU, WU)
    n_x = n_el(WU, s) + 2 * (2 * m - 1) * n_el(WU / 2, s)
    n_y, n_z = n_el(WU, s), n_el(HU, s)
    st, hd = (n + 1) // 2, n // 2
    assert counts(mesh) == {
        "bed_joints": (n - 1) * n_x * 2 * n_y,
        "head_joints": st * (m - 1) * 2 * n_y * n_z + hd * 2 * m * 2 * n_y * n_z,
        "collar_joints": st * n_x * n_z,
        "unit_cracks": st * 2 * m * n_y * n_z + hd * (2 * m - 1) * 2 * n_el(WU / 2, s) * n_z,
    }
    # bodies: stretcher courses 2 wythes x m units x 2 halves; header courses 2 halves per whole
    # header + the closer + the cut header
    n_bodies, _ = components(mesh)
    assert n_bodies == st * 2 * m * 2 + hd * (2 * (2 * m - 1) + 2)
    check_bodies_joined_only_by_interfaces(mesh)
    # collar joints: normal +y, in stretcher courses only (z within even courses)
    c = next(j for j in mesh.joints if j.name == "collar_joints")
    p = mesh.points[c.cells[:, :4]]
    assert np.allclose(p[..., 1], WU)
    course = np.floor(p[..., 2].mean(axis=1) / HU).astype(int)
    assert (course % 2 == 0).all()


def test_two_wythe_stack_bond_collar_count():
    """Stack bond two wythes thick (thickness = 2 WU): one collar joint over the whole elevation."""
    m, n = 3, 2
    mesh = masonry_wall_3d(length=m * LU, height=n * HU, bond="stack", thickness=2 * WU, **BRICK)
    s = min(LU, HU, WU)
    n_x, n_y, n_z = m * n_el(LU, s), n_el(WU, s), n_el(HU, s)
    assert counts(mesh) == {"bed_joints": (n - 1) * n_x * 2 * n_y, "head_joints": n * (m - 1) * 2 * n_y * n_z,
                            "collar_joints": n * n_x * n_z}
    assert components(mesh)[0] == 2 * m * n


# ------------------------------------------------------------------------------------------------
# bonds as built: half units and closers at the ends, one body per unit
# ------------------------------------------------------------------------------------------------
@pytest.mark.reference
def test_eindhoven_wall_half_units_alternate_ends():
    """990 mm = 4.5 expanded units: every course has 4 whole units and a half unit, at the right end
    in even courses and at the left end in odd courses (the Eindhoven walls, 16 free courses)."""
    mesh = masonry_wall_2d(length=0.99, height=16 * HU, bond="running", elements_per_unit=1,
                           **{k: v for k, v in BRICK.items() if k != "unit_width"})
    n_bodies, label = components(mesh)
    assert n_bodies == 16 * 5
    (units,) = mesh.blocks
    lab, a = label[units.cells[:, 0]], measures(mesh, units)
    centre = mesh.points[units.cells[:, :4]].mean(axis=1)
    area = np.bincount(lab, weights=a, minlength=n_bodies)
    cx = np.bincount(lab, weights=a * centre[:, 0], minlength=n_bodies) / area
    cy = np.bincount(lab, weights=a * centre[:, 1], minlength=n_bodies) / area
    half = np.isclose(area, LU * HU / 2)
    assert half.sum() == 16 and np.isclose(area, LU * HU).sum() == 64
    course = np.floor(cy[half] / HU).astype(int)
    assert np.allclose(cx[half], np.where(course % 2 == 0, 0.99 - LU / 4, LU / 4))


@pytest.mark.parametrize("bond", ["header", "english", "flemish"])
def test_3d_bonds_volumes_bodies_and_flush_ends(bond):
    """One-brick-thick bonds: the units fill the wall's volume exactly, each unit (closers and cut
    units too) is its own body, and both end faces are flush (covered by units over the whole
    end area: the end facet set has the area height x thickness)."""
    m, n = 4, 4
    L, H = m * LU, n * HU
    mesh = masonry_wall_3d(length=L, height=H, bond=bond, **BRICK)
    assert group_measure(mesh) == pytest.approx({"units": L * H * LU}, rel=1e-12)
    check_bodies_joined_only_by_interfaces(mesh)
    for face in ("left_face", "right_face"):
        f = mesh.facet_sets[face].facets
        assert np.prod(np.ptp(mesh.points[f], axis=1)[:, 1:], axis=1).sum() == pytest.approx(H * LU, rel=1e-12)
    slots = [walls.course_slots(bond, c, L, LU, WU) for c in range(n)]
    expected = sum(2 if s.role in ("S", "half") else 1 for course in slots for s in course)  # stretchers: 2 wythes
    assert components(mesh)[0] == expected


def test_flemish_headers_centred_on_stretchers_below():
    """Flemish bond (BIA TN 30; Hendry et al.): in every course headers and stretchers alternate, and
    every header not at the end of the wall is centred on a stretcher of the course below."""
    L = 10 * LU
    for c in range(1, 4):
        below = walls.course_slots("flemish", c - 1, L, LU, WU)
        here = walls.course_slots("flemish", c, L, LU, WU)
        centred = 0
        for h in here:
            if h.role != "H" or not h.full or h.x0 == 0.0:
                continue
            mid = 0.5 * (h.x0 + h.x1)
            under = [s for s in below if s.x0 < mid < s.x1]
            assert under and under[0].role == "S" and under[0].full
            assert 0.5 * (under[0].x0 + under[0].x1) == pytest.approx(mid, abs=1e-12)
            centred += 1
        assert centred >= 2


def test_english_header_course_has_queen_closer_after_quoin_header():
    """English bond: header course = quoin header, queen closer (WU / 2), headers; the quarter-unit
    lap: no head joint of a header course lies on a head joint of a stretcher course."""
    L = 4 * LU
    st = walls.course_slots("english", 0, L, LU, WU)
    hd = walls.course_slots("english", 1, L, LU, WU)
    assert [s.role for s in hd[:3]] == ["H", "Q", "H"]
    assert hd[1].x1 - hd[1].x0 == pytest.approx(WU / 2)
    joints_st = {round(s.x1, 9) for s in st[:-1]}
    joints_hd = {round(s.x1, 9) for s in hd[:-1]}
    assert not joints_st & joints_hd


# ------------------------------------------------------------------------------------------------
# openings, lintels, beams
# ------------------------------------------------------------------------------------------------
OPENINGS_2D = [dict(x0=0.3, y0=0.1, width=0.4, height=0.25),  # cuts units mid-course (L-shaped leftovers)
               dict(x0=0.84, y0=0.5, width=0.04, height=0.1)]  # splits one unit in two


def test_openings_trim_units_into_separate_bodies():
    """Running bond 1.0 x 0.7 m (units 0.2 x 0.1 m): counted by hand, course by course (bottom up):
    5; 4 (two units in the hole); 4 (one in the hole, two trimmed); 6 (two L-trimmed to strips);
    5; 6 + 1 (the narrow opening splits a unit in two); 5 = 36 bodies."""
    mesh = masonry_wall_2d(length=1.0, height=0.7, unit_length=0.2, unit_height=0.1, bond="running",
                           elements_per_unit=2, openings=OPENINGS_2D)
    assert components(mesh)[0] == 36
    assert group_measure(mesh) == pytest.approx({"units": 0.7 - 0.4 * 0.25 - 0.04 * 0.1}, rel=1e-12)
    check_bodies_joined_only_by_interfaces(mesh)
    # opening facet sets: the hole's perimeter, edges oriented out of the material (into the hole)
    for i, op in enumerate(OPENINGS_2D):
        f = mesh.facet_sets[f"opening_{i}"]
        assert f.type == "line2"
        p = mesh.points[f.facets]
        length = np.linalg.norm(p[:, 1] - p[:, 0], axis=1)
        assert length.sum() == pytest.approx(2 * (op["width"] + op["height"]), rel=1e-12)
        t = p[:, 1] - p[:, 0]
        normal = np.stack([t[:, 1], -t[:, 0]], axis=1)
        centre = np.array([op["x0"] + op["width"] / 2, op["y0"] + op["height"] / 2])
        assert ((centre - p.mean(axis=1)) * normal).sum(axis=1).min() > 0


@pytest.mark.parametrize("dim", [2, 3])
def test_window_with_lintel_and_beams(dim):
    """A window with a lintel bearing on both sides, in a wall between a base and a top beam: group
    areas / volumes equal the geometry; the lintel is its own body joined through 'lintel_joints'
    (on its underside bearings, its ends and its top); opening set around the hole."""
    L, n, zb, zt = 6 * LU, 10, 0.1, 0.08
    H = n * HU
    op = {"x0": 2 * LU, "width": 2 * LU, "height": 4 * HU, "lintel_height": HU, "lintel_bearing": LU / 2,
          ("y0" if dim == 2 else "z0"): 3 * HU}
    kw = dict(length=L, height=H, bond="english", openings=[op], base_beam_height=zb, top_beam_height=zt, **BRICK)
    mesh = masonry_wall_2d(**kw) if dim == 2 else masonry_wall_3d(**kw, unit_cracks=True)
    T = 1.0 if dim == 2 else LU
    lintel = (op["width"] + 2 * op["lintel_bearing"]) * op["lintel_height"]
    assert group_measure(mesh) == pytest.approx({
        "base_beam": L * zb * T, "top_beam": L * zt * T, "lintels": lintel * T,
        "units": (L * H - op["width"] * op["height"] - lintel) * T}, rel=1e-12)
    names = set(counts(mesh))
    assert {"bed_joints", "head_joints", "lintel_joints", "base_joint", "top_joint"} <= names
    check_bodies_joined_only_by_interfaces(mesh)
    lj = next(j for j in mesh.joints if j.name == "lintel_joints")
    ns = lj.cells.shape[1] // 2
    zc = mesh.points[lj.cells[:, :ns], dim - 1].mean(axis=1)
    z_lintel0 = zb + op[("y0" if dim == 2 else "z0")] + op["height"]
    # underside bearings, top, and ends (vertical joints spanning the lintel height)
    assert np.isclose(zc, z_lintel0).any() and np.isclose(zc, z_lintel0 + HU).any()
    assert ((zc > z_lintel0 + 1e-9) & (zc < z_lintel0 + HU - 1e-9)).any()
    f = mesh.facet_sets["opening_0"].facets
    p = mesh.points[f]
    if dim == 2:
        total = np.linalg.norm(p[:, 1] - p[:, 0], axis=1).sum()
        assert total == pytest.approx(2 * (op["width"] + op["height"]), rel=1e-12)
    else:
        area = np.sort(np.ptp(p, axis=1), axis=1)[:, 1:].prod(axis=1).sum()
        assert area == pytest.approx(2 * (op["width"] + op["height"]) * T, rel=1e-12)
    assert "beams" in mesh.node_sets
    beam_nodes = np.unique(np.concatenate([b.cells.ravel() for b in mesh.blocks if b.name.endswith("_beam")]))
    assert np.array_equal(mesh.node_sets["beams"], beam_nodes)


def test_door_on_the_base_beam_3d():
    """A door (z0 = 0) in a 3D stretcher wall on a base beam: the door's sill is the beam's top."""
    op = {"x0": LU, "z0": 0.0, "width": LU, "height": 3 * HU, "lintel_height": HU, "lintel_bearing": LU / 4}
    mesh = masonry_wall_3d(length=4 * LU, height=5 * HU, bond="stretcher", openings=[op], base_beam_height=0.1,
                           **BRICK)
    f = mesh.facet_sets["opening_0"].facets
    area = np.sort(np.ptp(mesh.points[f], axis=1), axis=1)[:, 1:].prod(axis=1).sum()
    assert area == pytest.approx(2 * (LU + 3 * HU) * WU, rel=1e-12)
    check_bodies_joined_only_by_interfaces(mesh)


# ------------------------------------------------------------------------------------------------
# uniform top pressure: homogeneous state
# ------------------------------------------------------------------------------------------------
E, NU, P = 16.7e9, 0.15, 0.3e6
JOINT = {"normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3"}


def _scene(dim, generator, params, joint_sets):
    joints = {n: dict(JOINT, law="linear") for n in joint_sets}
    joints["bed_joints"] = dict(JOINT, law="mohr_coulomb", friction_angle=36.87)
    if dim == 2:
        model = {"hypothesis": "plane_stress", "thickness": 0.1}
        supports = [{"set": "base", "components": ["y"]}, {"set": "left", "components": ["x"]}]
        load = {"type": "edge_pressure", "set": "top_edge", "pressure": P}
    else:
        model = {"dimension": 3}
        supports = [{"set": "base", "components": ["z"]}, {"set": "left", "components": ["x"]},
                    {"set": "front", "components": ["y"]}]
        load = {"type": "pressure", "set": "top_face", "pressure": P}
    return {"model": model, "mesh": {"generator": generator, "parameters": params},
            "materials": {"units": {"youngs_modulus": E, "poisson_ratio": NU, "density": 0.0}},
            "joints": joints, "supports": supports,
            "stages": [{"name": "press", "loads": [load]}], "output": {"nodes": "all", "joints": "all"}}


def _element_stresses(mesh, u):
    """Stresses of each element from its nodal displacements: affine fit u = a + G x (exact for the
    homogeneous field), then Hooke (plane stress in 2D). Returns (n_elem, dim, dim)."""
    out = []
    dim = mesh.dim
    for b in mesh.blocks:
        X = mesh.points[b.cells]  # (ne, nen, dim)
        U = u[b.cells]
        A = np.concatenate([np.ones(X.shape[:2] + (1,)), X], axis=2)
        coef = np.linalg.pinv(A) @ U  # (ne, dim + 1, dim)
        grad = np.swapaxes(coef[:, 1:, :], 1, 2)  # du_i / dx_j
        eps = 0.5 * (grad + np.swapaxes(grad, 1, 2))
        tr = np.trace(eps, axis1=1, axis2=2)
        if dim == 2:
            lam = E * NU / (1 - NU**2)  # plane stress
        else:
            lam = E * NU / ((1 + NU) * (1 - 2 * NU))
        mu = E / (2 * (1 + NU))
        out.append(lam * tr[:, None, None] * np.eye(dim) + 2 * mu * eps)
    return np.concatenate(out)


def _check_homogeneous(ds, mesh):
    dim = mesh.dim
    names = json.loads(ds.joint_set.attrs["set_names"])
    sets = np.array(names)[ds.joint_set.values]
    tn = ds.joint_traction_normal.isel(step=-1).values
    ts = ds.joint_traction_shear.isel(step=-1).values
    bed = sets == "bed_joints"
    assert bed.any() and (~bed).any()
    np.testing.assert_allclose(tn[bed], -P, rtol=1e-7)
    assert np.abs(tn[~bed]).max() < 1e-7 * P, "head, collar and crack joints carry no normal traction"
    assert np.abs(ts).max() < 1e-7 * P, "no spurious shear"
    u = ds.displacement.isel(step=-1).values
    sig = _element_stresses(mesh, u)
    target = np.zeros((dim, dim))
    target[-1, -1] = -P
    np.testing.assert_allclose(sig, np.broadcast_to(target, sig.shape), atol=1e-6 * P)
    top = mesh.node_sets["top"]
    uz = u[top, dim - 1]
    assert np.ptp(uz) < 1e-8 * np.abs(uz).max(), "uniform vertical displacement of the top"


@pytest.mark.parametrize("bond", ["running", "english"])
def test_uniform_top_pressure_2d(bond):
    params = dict(length=3 * LU, height=4 * HU, bond=bond, elements_per_unit=1, unit_cracks=True, **BRICK)
    if bond == "running":
        params.pop("unit_width")
    sets = ["head_joints", "unit_cracks"]
    ds = masonrydam.run(_scene(2, "masonry_wall_2d", params, sets))
    _check_homogeneous(ds, masonry_wall_2d(**params))


@pytest.mark.parametrize("bond, cracks", [("english", True), ("flemish", False)])
def test_uniform_top_pressure_3d(monkeypatch, bond, cracks):
    """3D one-brick-thick walls with collar joints (and in English bond unit cracks normal to x and
    to y) under a uniform top pressure."""
    monkeypatch.setitem(generators.GENERATORS, "masonry_wall_3d", masonry_wall_3d)
    params = dict(length=3 * LU, height=3 * HU, bond=bond, unit_cracks=cracks, **BRICK)
    mesh = masonry_wall_3d(**params)
    sets = [n for n in mesh.joint_set_names() if n != "bed_joints"]
    assert "collar_joints" in sets
    ds = masonrydam.run(_scene(3, "masonry_wall_3d", params, sets))
    _check_homogeneous(ds, mesh)


# ------------------------------------------------------------------------------------------------
# determinism and scenes
# ------------------------------------------------------------------------------------------------
def test_generation_is_deterministic():
    kw2 = dict(length=1.0, height=0.7, unit_length=0.2, unit_height=0.1, unit_cracks=True, openings=OPENINGS_2D,
               base_beam_height=0.1, top_beam_height=0.1)
    same_mesh(masonry_wall_2d(**kw2), masonry_wall_2d(**kw2))
    op = {"x0": 2 * LU, "z0": HU, "width": LU, "height": 2 * HU, "lintel_height": HU, "lintel_bearing": 0.05}
    kw3 = dict(length=5 * LU, height=5 * HU, bond="flemish", unit_cracks=True, openings=[op], order=2, **BRICK)
    same_mesh(masonry_wall_3d(**kw3), masonry_wall_3d(**kw3))


def test_scene_parameters_with_units():
    """Scene parameters are converted by the schema (lengths as strings); opening values too."""
    from masonrydam.scene import build_mesh
    from masonrydam.scene.schema import normalize

    sc = _scene(2, "masonry_wall_2d", dict(length="660 mm", height="248 mm", unit_length="210 mm",
                                           unit_height="52 mm", unit_width="100 mm", joint_thickness="10 mm",
                                           bond="flemish", unit_cracks=True,
                                           openings=[{"x0": "220 mm", "y0": "62 mm", "width": "110 mm",
                                                      "height": "62 mm"}]), ["head_joints", "unit_cracks"])
    mesh = build_mesh(normalize(sc), None)
    assert components(mesh)[0] > 0 and "opening_0" in mesh.facet_sets
    assert group_measure(mesh)["units"] == pytest.approx(0.66 * 0.248 - 0.11 * 0.062, rel=1e-12)


# ------------------------------------------------------------------------------------------------
# bad input: a clear error naming the parameter, before any meshing
# ------------------------------------------------------------------------------------------------
def _no_meshing(monkeypatch):
    def fail(*a, **k):
        raise AssertionError("meshing started before the input was checked")

    monkeypatch.setattr(walls, "rectangles_to_mesh", fail)
    monkeypatch.setattr(walls3d, "boxes_to_mesh", fail)


BASE2 = dict(length=0.66, height=0.248, bond="running", **{k: v for k, v in BRICK.items() if k != "unit_width"})
BASE3 = dict(length=0.66, height=0.248, bond="stretcher", **BRICK)


@pytest.mark.parametrize("dim, edits, key, words", [
    (2, {"unit_length": 0.7}, "unit_length", "longer than the wall"),
    (2, {"unit_height": 0.3}, "unit_height", "taller than the wall"),
    (3, {"unit_length": 0.7}, "unit_length", "longer than the wall"),
    (2, {"joint_thickness": 0.06}, "joint_thickness", "thicker than the unit"),
    (3, {"joint_thickness": 0.12}, "joint_thickness", "thicker than the unit"),
    (2, {"bond": "englsh", "unit_width": 0.1}, "bond", "did you mean 'english'"),
    (3, {"bond": "flemmish"}, "bond", "did you mean 'flemish'"),
    (2, {"bond": "english"}, "unit_width", "unit_width"),
    (3, {"bond": "english", "unit_width": 0.09}, "unit_width", "2 (unit_width + joint)"),
    (3, {"bond": "english", "thickness": 0.11}, "thickness", "one unit length thick"),
    (3, {"thickness": 0.15}, "thickness", "whole number of wythes"),
    (2, {"height": 0.25}, "height", "whole number of courses"),
    (2, {"openings": [{"x0": 0.1, "y0": 0.062, "width": 0.1, "height": 0.062},
                      {"x0": 0.15, "y0": 0.1, "width": 0.1, "height": 0.05}]}, "openings[1]", "overlaps"),
    (3, {"openings": [{"x0": 0.1, "z0": 0.0, "width": 0.1, "height": 0.062, "lintel_height": 0.062},
                      {"x0": 0.15, "z0": 0.124, "width": 0.1, "height": 0.062}]}, "openings[1]", "touches"),
    (2, {"openings": [{"x0": 0.0, "y0": 0.062, "width": 0.1, "height": 0.062}]}, "openings[0].x0", "left end"),
    (3, {"openings": [{"x0": 0.5, "z0": 0.062, "width": 0.2, "height": 0.062}]}, "openings[0].width", "right end"),
    (2, {"openings": [{"x0": 0.2, "y0": 0.124, "width": 0.1, "height": 0.124}]}, "openings[0].height", "top"),
    (3, {"openings": [{"x0": 0.2, "z0": 0.062, "width": 0.1, "height": 0.062, "lintel_height": 0.2}]},
     "openings[0].lintel_height", "top"),
    (2, {"openings": [{"x0": 0.05, "y0": 0.062, "width": 0.1, "height": 0.062, "lintel_height": 0.062,
                       "lintel_bearing": 0.1}]}, "openings[0].lintel_bearing", "past the wall's end"),
    (3, {"openings": [{"x0": 0.2, "y0": 0.062, "width": 0.1, "height": 0.062}]}, "openings[0].y0", "did you mean"),
    (2, {"openings": [{"x0": 0.2, "y0": -0.01, "width": 0.1, "height": 0.062}]}, "openings[0].y0", ">= 0"),
    (2, {"openings": [{"x0": 0.2, "y0": 0.0, "width": 0.0, "height": 0.062}]}, "openings[0].width", "> 0"),
    (2, {"elements_per_unit": 0}, "elements_per_unit", ">= 1"),
])
def test_bad_input_names_the_parameter(monkeypatch, dim, edits, key, words):
    _no_meshing(monkeypatch)
    gen = masonry_wall_2d if dim == 2 else masonry_wall_3d
    kw = dict(BASE2 if dim == 2 else BASE3, **edits)
    with pytest.raises(SceneError) as exc:
        gen(**kw)
    assert exc.value.key == f"mesh.parameters.{key}"
    assert words in str(exc.value)
