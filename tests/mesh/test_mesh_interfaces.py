"""Tests of interface insertion (masonrydam.mesh.interfaces), the wall generator
(generators.walls.masonry_wall_2d) and mesh export (masonrydam.mesh.io.to_meshio).

Sources:
- simplified micro-model of masonry: expanded units joined by zero-thickness interfaces on every bed
  and head joint (Lourenco 1996, PhD thesis TU Delft, sec. 6; Lourenco & Rots 1997, J. Eng. Mech.
  123(7)); Tzamtzis & Asteris, sec. 3.3: a joint element joins the two faces of a joint,
  so each block is a separate continuum connected to its neighbours only through interfaces;
- interface node order and orientation: docs/architecture.md ("Interface orientation (2D)": nodes
  [bottom.., top..] in line2/line3 order, normal = tangent rotated +90 deg, top face on the +n side)
  and the orientation rule in masonrydam/mesh/interfaces.py (normal +y for horizontal, +x for
  vertical joints);
- expected counts are plain combinatorics of the structured grid described in generators/grid.py
  (every interval between grid lines split into equal elements no longer than the element size,
  element size = min(expanded unit length, height) / elements_per_unit, generators/walls.py).
"""
from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from generators import masonry_wall_2d
from masonrydam.errors import MeshError
from masonrydam.mesh.interfaces import insert_interfaces
from masonrydam.mesh.io import read_mesh, to_meshio
from masonrydam.mesh.model import CellBlock, FacetSet, Mesh

LU, HU = 0.2, 0.1  # unit length and height (m), no joint thickness: expanded unit = unit


# ------------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------------
def wall(n_courses, m_units, bond="running", epu=2, **kw):
    return masonry_wall_2d(length=m_units * LU, height=n_courses * HU, unit_length=LU, unit_height=HU,
                           bond=bond, elements_per_unit=epu, **kw)


def pieces_per_course(n_courses, m_units, bond):
    """Units per course: stack bond m everywhere; running bond m in even courses and m + 1 (two
    half units at the ends, as built) in odd courses."""
    if bond == "stack":
        return [m_units] * n_courses
    return [m_units if c % 2 == 0 else m_units + 1 for c in range(n_courses)]


def polygon_area(xy):
    """Shoelace area of polygons xy (n, k, 2) with counter-clockwise vertices."""
    x, y = xy[..., 0], xy[..., 1]
    return 0.5 * (x * np.roll(y, -1, axis=-1) - np.roll(x, -1, axis=-1) * y).sum(axis=-1)


def element_areas(mesh, block):
    """Areas of the cells of a continuum block from their corner nodes (straight-sided elements)."""
    n_corner = 3 if block.type.startswith("tri") else 4
    return polygon_area(mesh.points[block.cells[:, :n_corner]])


def continuum_components(mesh):
    """Connected components of the graph joining the nodes of each continuum cell (interfaces ignored)."""
    rows, cols = [], []
    for b in mesh.blocks:
        c = b.cells
        rows.append(np.repeat(c[:, :1], c.shape[1], axis=1).ravel())
        cols.append(c.ravel())
    r, c = np.concatenate(rows), np.concatenate(cols)
    g = coo_matrix((np.ones(len(r)), (r, c)), shape=(mesh.n_nodes, mesh.n_nodes))
    return connected_components(g, directed=False)


def node_owner_centroids(mesh):
    """node -> list of centroids of the continuum cells that contain it."""
    out = {}
    for b in mesh.blocks:
        cent = mesh.points[b.cells].mean(axis=1)
        for e, cell in enumerate(b.cells):
            for n in cell:
                out.setdefault(int(n), []).append(cent[e])
    return out


def copies_by_location(mesh, decimals=9):
    """Number of nodes at each (rounded) location."""
    return Counter(map(tuple, np.round(mesh.points, decimals)))


def joint(mesh, name):
    blocks = [j for j in mesh.joints if j.name == name]
    assert len(blocks) == 1, f"expected one interface block for joint set '{name}'"
    return blocks[0]


def edges_of_cells(mesh):
    """Set of sorted corner-node pairs of all continuum element edges."""
    from masonrydam.elements.shapes import ELEMENT_TYPES

    out = set()
    for b in mesh.blocks:
        for edge in ELEMENT_TYPES[b.type].edges:
            for a, c in b.cells[:, [edge[0], edge[1]]]:
                out.add((min(int(a), int(c)), max(int(a), int(c))))
    return out


# ------------------------------------------------------------------------------------------------
# masonry_wall_2d: counts, areas, connectivity
# ------------------------------------------------------------------------------------------------
WALL_CASES = [
    # bond, courses n, units per course m, elements_per_unit, order, element
    ("stack", 3, 4, 2, 1, "quad"),
    ("running", 3, 4, 2, 1, "quad"),
    ("running", 4, 3, 1, 1, "quad"),
    ("stack", 2, 2, 3, 1, "quad"),
    ("running", 3, 2, 2, 2, "quad"),
    ("stack", 2, 3, 1, 2, "quad9"),
    ("running", 2, 3, 1, 1, "tri"),
    ("stack", 2, 2, 2, 2, "tri"),
]


@pytest.mark.parametrize("bond,n,m,epu,order,element", WALL_CASES)
def test_wall_interface_counts_match_analytic(bond, n, m, epu, order, element):
    mesh = wall(n, m, bond, epu, order=order, element=element)
    size = min(LU, HU) / epu
    along_length = round(m * LU / size)  # interface elements along one bed joint
    per_height = round(HU / size)  # interface elements along one head joint
    expected_bed = (n - 1) * along_length
    expected_head = sum((p - 1) * per_height for p in pieces_per_course(n, m, bond))
    assert mesh.joint_set_names() == ["bed_joints", "head_joints"]
    assert len(joint(mesh, "bed_joints").cells) == expected_bed
    assert len(joint(mesh, "head_joints").cells) == expected_head
    assert mesh.n_interfaces() == expected_bed + expected_head
    itype = "interface_line2" if order == 1 else "interface_line3"
    assert {j.type for j in mesh.joints} == {itype}


@pytest.mark.parametrize("bond,n,m,epu,order,element", WALL_CASES)
def test_wall_element_areas_equal_geometry(bond, n, m, epu, order, element):
    mesh = wall(n, m, bond, epu, order=order, element=element)
    assert mesh.group_names() == ["units"]
    (units,) = mesh.blocks
    a = element_areas(mesh, units)
    assert (a > 0).all(), "every element must be counter-clockwise with positive area"
    assert a.sum() == pytest.approx(n * HU * m * LU, rel=1e-12)


def test_wall_with_beams_group_areas_and_joint_sets():
    L, beam_b, beam_t = 3 * LU, 0.05, 0.1
    mesh = wall(2, 3, "running", 2, base_beam_height=beam_b, top_beam_height=beam_t)
    assert mesh.group_names() == ["base_beam", "top_beam", "units"]
    assert mesh.joint_set_names() == ["base_joint", "bed_joints", "head_joints", "top_joint"]
    areas = {b.name: element_areas(mesh, b).sum() for b in mesh.blocks}
    assert areas["base_beam"] == pytest.approx(L * beam_b, rel=1e-12)
    assert areas["top_beam"] == pytest.approx(L * beam_t, rel=1e-12)
    assert areas["units"] == pytest.approx(L * 2 * HU, rel=1e-12)
    size = min(LU, HU) / 2
    n_along = round(L / size)
    # one bed joint between the two courses; the beam joints run along the whole length
    assert len(joint(mesh, "bed_joints").cells) == n_along
    assert len(joint(mesh, "base_joint").cells) == n_along
    assert len(joint(mesh, "top_joint").cells) == n_along
    # base joint at the top of the base beam, top joint under the top beam
    y_base = mesh.points[joint(mesh, "base_joint").cells].reshape(-1, 2)[:, 1]
    y_top = mesh.points[joint(mesh, "top_joint").cells].reshape(-1, 2)[:, 1]
    assert np.allclose(y_base, beam_b) and np.allclose(y_top, beam_b + 2 * HU)


def test_wall_beams_glued_without_beam_joints():
    mesh = wall(2, 2, "stack", 1, base_beam_height=0.05, top_beam_height=0.05, beam_joints=False)
    assert mesh.joint_set_names() == ["bed_joints", "head_joints"]
    n_comp, _ = continuum_components(mesh)
    # 4 units and 2 beams; each beam is glued to both units of its course (2 courses), so the
    # continuum forms 2 bodies: base beam + lower course, top beam + upper course
    assert n_comp == 2


@pytest.mark.parametrize("bond,n,m,epu,order,element", WALL_CASES)
def test_every_unit_is_a_separate_body(bond, n, m, epu, order, element):
    """Units touch each other only through interfaces: the continuum-only graph has one connected
    component per unit, and each component is a rectangle of one unit (Tzamtzis & Asteris sec. 3.3)."""
    mesh = wall(n, m, bond, epu, order=order, element=element)
    n_units = sum(pieces_per_course(n, m, bond))
    n_comp, label = continuum_components(mesh)
    assert n_comp == n_units
    (units,) = mesh.blocks
    areas = element_areas(mesh, units)
    comp_area = np.bincount(label[units.cells[:, 0]], weights=areas, minlength=n_comp)
    if bond == "stack":
        assert np.allclose(comp_area, LU * HU)
    else:  # half units at the ends of odd courses
        n_half = 2 * (n // 2)
        assert np.isclose(comp_area, LU * HU / 2).sum() == n_half
        assert np.isclose(comp_area, LU * HU).sum() == n_units - n_half
    # every interface joins two different bodies, one per face
    for j in mesh.joints:
        ns = j.cells.shape[1] // 2
        bot, top = label[j.cells[:, :ns]], label[j.cells[:, ns:]]
        assert (bot == bot[:, :1]).all() and (top == top[:, :1]).all()
        assert (bot[:, 0] != top[:, 0]).all()


def test_wall_with_beams_components_are_units_plus_beams():
    mesh = wall(3, 3, "running", 1, base_beam_height=0.1, top_beam_height=0.1)
    n_comp, _ = continuum_components(mesh)
    assert n_comp == sum(pieces_per_course(3, 3, "running")) + 2


def test_no_node_shared_between_units_or_isolated():
    mesh = wall(3, 4, "running", 2)
    used = np.zeros(mesh.n_nodes, dtype=bool)
    for b in mesh.blocks:
        used[b.cells.ravel()] = True
    assert used.all(), "every node (original or copy) must belong to a continuum element"
    for j in mesh.joints:
        ns = j.cells.shape[1] // 2
        # zero thickness: bottom and top nodes coincide in space but are different nodes
        assert np.allclose(mesh.points[j.cells[:, :ns]], mesh.points[j.cells[:, ns:]], atol=1e-14)
        assert (j.cells[:, :ns] != j.cells[:, ns:]).all()


# ------------------------------------------------------------------------------------------------
# node copies at junctions
# ------------------------------------------------------------------------------------------------
def test_stack_bond_cross_junction_has_four_copies():
    n, m = 3, 3
    mesh = wall(n, m, "stack", 2)
    copies = copies_by_location(mesh)
    for c in range(1, n):
        for k in range(1, m):
            assert copies[(round(k * LU, 9), round(c * HU, 9))] == 4, "interior cross point of stack bond"
    # a head joint reaching the base or the top (T on the boundary): 2 copies
    assert copies[(round(LU, 9), 0.0)] == 2
    assert copies[(round(LU, 9), round(n * HU, 9))] == 2
    # a bed joint reaching the side of the wall: 2 copies; outer corners of the wall: 1
    assert copies[(0.0, round(HU, 9))] == 2
    assert copies[(0.0, 0.0)] == 1
    # an interior point of a bed joint (not at a head joint): 2 copies
    assert copies[(round(LU / 2, 9), round(HU, 9))] == 2
    # an interior point of a unit: 1
    size = min(LU, HU) / 2
    assert copies[(round(size, 9), round(size, 9))] == 1


def test_running_bond_t_junction_has_three_copies():
    n, m = 3, 3
    mesh = wall(n, m, "running", 2)
    copies = copies_by_location(mesh)
    # head joints of even courses at x = k*LU, of odd courses at x = (k + 1/2)*LU; each meets the
    # bed joints above/below in a T (never a cross): 3 copies
    for c in range(1, n):
        for k in range(1, m):
            assert copies[(round(k * LU, 9), round(c * HU, 9))] == 3
        for k in range(m):
            assert copies[(round((k + 0.5) * LU, 9), round(c * HU, 9))] == 3
    # no point of a running-bond wall has 4 copies
    assert max(copies.values()) == 3
    # total node count: each unit (full: (2*epu+1) x (epu+1) grid nodes, half: (epu+1) x (epu+1))
    epu = 2
    n_full, n_half = 0, 0
    for c, p in enumerate(pieces_per_course(n, m, "running")):
        if c % 2:
            n_full += p - 2
            n_half += 2
        else:
            n_full += p
    assert mesh.n_nodes == n_full * (2 * epu + 1) * (epu + 1) + n_half * (epu + 1) ** 2


@pytest.mark.parametrize("element", ["quad", "quad9"])
def test_quadratic_stack_bond_copies(element):
    mesh = wall(2, 2, "stack", 1, order=2, element=element)
    copies = copies_by_location(mesh)
    assert copies[(round(LU, 9), round(HU, 9))] == 4  # cross point
    # mid-side node of an element edge on the bed joint: 2 copies
    size = min(LU, HU)
    assert copies[(round(size / 2, 9), round(HU, 9))] == 2
    # mid-side node on the head joint: 2 copies
    assert copies[(round(LU, 9), round(HU / 2, 9))] == 2


# ------------------------------------------------------------------------------------------------
# orientation
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("bond", ["stack", "running"])
@pytest.mark.parametrize("order,element", [(1, "quad"), (2, "quad"), (2, "quad9"), (1, "tri")])
def test_interface_orientation(bond, order, element):
    """docs/architecture.md: normal = e_t rotated +90 deg; top face on the +n side. Bed joints:
    normal +y and the top face belongs to the upper unit; head joints: normal +x, top face in the
    right-hand unit."""
    mesh = wall(3, 3, bond, 1, order=order, element=element)
    owners = node_owner_centroids(mesh)
    for name, normal in (("bed_joints", np.array([0.0, 1.0])), ("head_joints", np.array([1.0, 0.0]))):
        j = joint(mesh, name)
        ns = j.cells.shape[1] // 2
        for cell in j.cells:
            b0, b1 = mesh.points[cell[0]], mesh.points[cell[1]]
            t = (b1 - b0) / np.linalg.norm(b1 - b0)
            n = np.array([-t[1], t[0]])
            assert np.allclose(n, normal, atol=1e-12)
            mid = 0.5 * (b0 + b1)
            for node in cell[ns:]:  # top face: its elements lie on the +n side
                assert all(np.dot(c - mid, normal) > 0 for c in owners[int(node)])
            for node in cell[:ns]:  # bottom face: on the -n side
                assert all(np.dot(c - mid, normal) < 0 for c in owners[int(node)])


@pytest.mark.parametrize("element", ["quad", "quad9"])
def test_quadratic_interfaces_have_six_nodes_mid_at_midpoint(element):
    mesh = wall(2, 2, "running", 2, order=2, element=element)
    expected_type = "quad8" if element == "quad" else "quad9"
    assert [b.type for b in mesh.blocks] == [expected_type]
    for j in mesh.joints:
        assert j.type == "interface_line3"
        assert j.cells.shape[1] == 6
        p = mesh.points
        # [b0, b1, b_mid, t0, t1, t_mid]
        assert np.allclose(p[j.cells[:, 2]], 0.5 * (p[j.cells[:, 0]] + p[j.cells[:, 1]]), atol=1e-14)
        assert np.allclose(p[j.cells[:, 5]], 0.5 * (p[j.cells[:, 3]] + p[j.cells[:, 4]]), atol=1e-14)
        assert all(len(set(c.tolist())) == 6 for c in j.cells), "six distinct nodes per interface"


@pytest.mark.parametrize("kw", [dict(bond="running", epu=2), dict(bond="stack", epu=1, order=2),
                                dict(bond="running", epu=1, base_beam_height=0.1, top_beam_height=0.05)])
def test_generator_is_deterministic(kw):
    kw = dict(kw)
    bond, epu = kw.pop("bond"), kw.pop("epu")
    a = wall(3, 3, bond, epu, **kw)
    b = wall(3, 3, bond, epu, **kw)
    assert np.array_equal(a.points, b.points)
    assert [(x.name, x.type) for x in a.blocks] == [(x.name, x.type) for x in b.blocks]
    assert [(x.name, x.type) for x in a.joints] == [(x.name, x.type) for x in b.joints]
    for x, y in zip(a.blocks + a.joints, b.blocks + b.joints):
        assert np.array_equal(x.cells, y.cells)
    assert a.node_sets.keys() == b.node_sets.keys()
    for k in a.node_sets:
        assert np.array_equal(a.node_sets[k], b.node_sets[k])
    for k in a.facet_sets:
        assert np.array_equal(a.facet_sets[k].facets, b.facet_sets[k].facets)


def test_wall_node_and_facet_sets_follow_the_copies():
    mesh = wall(3, 3, "stack", 2)
    ymin, ymax = mesh.points[:, 1].min(), mesh.points[:, 1].max()
    # the base set holds every node (all copies) on the base line, and nothing else
    assert np.array_equal(mesh.node_sets["base"], np.nonzero(np.isclose(mesh.points[:, 1], ymin))[0])
    assert np.array_equal(mesh.node_sets["top"], np.nonzero(np.isclose(mesh.points[:, 1], ymax))[0])
    # boundary facets are edges of the elements of the new (split) mesh
    edges = edges_of_cells(mesh)
    for name in ("base_edge", "top_edge", "left_edge", "right_edge"):
        fs = mesh.facet_sets[name]
        for a, b in fs.facets[:, :2]:
            assert (min(a, b), max(a, b)) in edges, f"{name}: facet {a}-{b} is not an element edge"
    size = min(LU, HU) / 2
    assert len(mesh.facet_sets["base_edge"].facets) == round(3 * LU / size)
    assert len(mesh.facet_sets["left_edge"].facets) == round(3 * HU / size)


# ------------------------------------------------------------------------------------------------
# insert_interfaces on a hand-made conformal mesh
# ------------------------------------------------------------------------------------------------
def grid_2x2():
    """2 x 2 quad4 grid of unit squares, nodes

        6 7 8
        3 4 5
        0 1 2
    """
    pts = np.array([[x, y] for y in range(3) for x in range(3)], dtype=float)
    cells = np.array([[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]])
    node_sets = {"centre": [4], "base": [0, 1, 2]}
    facet_sets = {"left_edge": FacetSet("line2", [[0, 3], [3, 6]]), "top_edge": FacetSet("line2", [[6, 7], [7, 8]])}
    return Mesh(pts, [CellBlock("quad4", cells, "blocks")], [], node_sets, facet_sets)


def node_sets_of_elements(mesh):
    return [set(c.tolist()) for c in mesh.blocks[0].cells]


def test_insert_cross_joint_counts_and_no_shared_nodes():
    mesh = grid_2x2()
    # facet order is irrelevant (docstring of insert_interfaces)
    out = insert_interfaces(mesh, {"h": np.array([[4, 3], [4, 5]]), "v": np.array([[1, 4], [7, 4]])})
    # node 4 (cross) -> 4 copies; nodes 1, 3, 5, 7 (a joint meeting the boundary) -> 2 copies each
    assert out.n_nodes == 9 + 3 + 4
    assert out.n_interfaces() == 4
    assert {j.name: len(j.cells) for j in out.joints} == {"h": 2, "v": 2}
    assert {j.type for j in out.joints} == {"interface_line2"}
    elems = node_sets_of_elements(out)
    for a in range(4):
        for b in range(a + 1, 4):
            assert not (elems[a] & elems[b]), f"elements {a} and {b} still share nodes across a joint"
    copies = copies_by_location(out)
    assert copies[(1.0, 1.0)] == 4
    assert copies[(1.0, 0.0)] == copies[(0.0, 1.0)] == copies[(2.0, 1.0)] == copies[(1.0, 2.0)] == 2
    assert copies[(0.0, 0.0)] == 1
    # the input mesh is not modified
    assert mesh.n_nodes == 9 and mesh.blocks[0].cells.max() == 8
    # each interface joins two elements: bottom nodes all in one element, top nodes in another
    for j in out.joints:
        for cell in j.cells:
            owner_b = [i for i, s in enumerate(elems) if set(cell[:2].tolist()) <= s]
            owner_t = [i for i, s in enumerate(elems) if set(cell[2:].tolist()) <= s]
            assert len(owner_b) == 1 and len(owner_t) == 1 and owner_b != owner_t
            assert np.allclose(out.points[cell[:2]], out.points[cell[2:]])
    # node sets contain every copy; boundary facets follow their owning element
    assert len(out.node_sets["centre"]) == 4
    assert np.allclose(out.points[out.node_sets["centre"]], [1.0, 1.0])
    assert len(out.node_sets["base"]) == 4  # 0, 2 and both copies of 1
    edges = edges_of_cells(out)
    for fs in out.facet_sets.values():
        for a, b in fs.facets:
            assert (min(a, b), max(a, b)) in edges


def test_insert_single_joint_keeps_sides_connected():
    out = insert_interfaces(grid_2x2(), {"bed": np.array([[3, 4], [4, 5]])})
    assert out.n_nodes == 9 + 3
    elems = node_sets_of_elements(out)
    # across the joint: nothing shared; along each side: the vertical edge 1-4 / 4-7 stays shared
    assert not (elems[0] & elems[2]) and not (elems[1] & elems[3])
    assert len(elems[0] & elems[1]) == 2 and len(elems[2] & elems[3]) == 2
    (j,) = out.joints
    # horizontal joint: normal +y, bottom face in the lower elements
    for cell in j.cells:
        assert out.points[cell[1], 0] > out.points[cell[0], 0]
        assert set(cell[:2].tolist()) <= elems[0] | elems[1]
        assert set(cell[2:].tolist()) <= elems[2] | elems[3]


def test_insert_t_junction_three_copies():
    out = insert_interfaces(grid_2x2(), {"bed": np.array([[3, 4], [4, 5]]), "head": np.array([[4, 7]])})
    copies = copies_by_location(out)
    assert copies[(1.0, 1.0)] == 3
    assert copies[(1.0, 0.0)] == 1  # the lower vertical edge is not a joint
    assert out.n_nodes == 9 + 2 + 1 + 1 + 1
    (head,) = [j for j in out.joints if j.name == "head"]
    # vertical joint: normal +x, the top face belongs to the right element
    elems = node_sets_of_elements(out)
    (cell,) = head.cells
    assert out.points[cell[1], 1] < out.points[cell[0], 1]  # ordered downward so e_t rotated +90 = +x
    assert set(cell[2:].tolist()) <= elems[3] and set(cell[:2].tolist()) <= elems[2]


def test_insert_boundary_facet_is_an_error_naming_the_set():
    with pytest.raises(MeshError, match="my_joints") as ei:
        insert_interfaces(grid_2x2(), {"my_joints": np.array([[0, 1]])})
    assert "boundary" in str(ei.value)


def test_insert_facet_not_in_mesh_is_an_error():
    with pytest.raises(MeshError, match="bed") as ei:
        insert_interfaces(grid_2x2(), {"bed": np.array([[0, 4]])})  # a diagonal, not an element edge
    assert "not an edge" in str(ei.value)


def test_insert_facet_in_two_sets_is_an_error():
    with pytest.raises(MeshError, match="'a' and 'b'"):
        insert_interfaces(grid_2x2(), {"a": np.array([[3, 4]]), "b": np.array([[4, 3]])})


def test_insert_malformed_facets_is_an_error():
    with pytest.raises(MeshError, match="bed"):
        insert_interfaces(grid_2x2(), {"bed": np.array([3, 4])})


# ------------------------------------------------------------------------------------------------
# export
# ------------------------------------------------------------------------------------------------
def expected_export_blocks(mesh):
    """(meshio cell type, count) of each block written by to_meshio: a 2D interface is one
    degenerate quad, a quadratic interface two (docstring of masonrydam.mesh.io)."""
    from masonrydam.elements.shapes import ELEMENT_TYPES

    out = [(ELEMENT_TYPES[b.type].meshio_name, len(b.cells)) for b in mesh.blocks]
    out += [("quad", len(j.cells) * (1 if j.type == "interface_line2" else 2)) for j in mesh.joints]
    return out


@pytest.mark.parametrize("order", [1, 2])
def test_to_meshio_blocks_and_vtu_total(tmp_path, order):
    import meshio

    mesh = wall(2, 3, "running", 1, order=order, base_beam_height=0.05)
    mm = to_meshio(mesh)
    assert [(c.type, len(c.data)) for c in mm.cells] == expected_export_blocks(mesh)
    assert mm.points.shape == (mesh.n_nodes, 3) and np.all(mm.points[:, 2] == 0)
    # interface quads are degenerate (zero area): [b0, b1, t1, t0] with t = b in space
    for cb in mm.cells[len(mesh.blocks):]:
        assert np.allclose(polygon_area(mm.points[cb.data][:, :, :2]), 0.0, atol=1e-15)
    path = tmp_path / "mesh.vtu"
    mm.write(path)
    back = meshio.read(path)
    assert back.points.shape == mm.points.shape
    assert sum(len(c.data) for c in back.cells) == sum(n for _, n in expected_export_blocks(mesh))
    by_type = Counter()
    for c in back.cells:
        by_type[c.type] += len(c.data)
    want = Counter()
    for t, n in expected_export_blocks(mesh):
        want[t] += n
    assert by_type == want


def test_vtu_export_keeps_units_and_joints_apart(tmp_path):
    """docs/cli.md: export-mesh 'writes units and joints as separate cell blocks for ParaView'. After a
    .vtu round trip the blocks must be recoverable, either as separate cell blocks or through an
    integer cell-data array that tags each cell with its block."""
    import meshio

    mesh = wall(2, 3, "running", 1, base_beam_height=0.05)
    path = tmp_path / "mesh.vtu"
    to_meshio(mesh).write(path)
    back = meshio.read(path)
    want = sorted(n for _, n in expected_export_blocks(mesh))
    if sorted(len(c.data) for c in back.cells) == want:
        return
    for arrays in back.cell_data.values():
        tags = np.concatenate([np.asarray(a).ravel() for a in arrays])
        if np.issubdtype(tags.dtype, np.integer) and sorted(Counter(tags.tolist()).values()) == want:
            return
    pytest.fail("the .vtu file does not tell units, beams and joints apart")


def test_read_mesh_vtu_round_trip_without_joints(tmp_path):
    """A plain conformal mesh written to .vtu and read back by read_mesh (no gmsh tags: one group)."""
    import meshio

    from generators import Rect, rectangles_to_mesh

    m0 = rectangles_to_mesh([Rect(0.0, 0.0, 0.4, 0.2, "units")], element_size=0.1)
    assert m0.n_interfaces() == 0
    path = tmp_path / "plain.vtu"
    to_meshio(m0).write(path)
    m1 = read_mesh(path, [], 2)
    assert m1.n_nodes == m0.n_nodes
    assert [b.type for b in m1.blocks] == ["quad4"]
    assert m1.n_elements() == m0.n_elements() == 8
    assert element_areas(m1, m1.blocks[0]).sum() == pytest.approx(0.08, rel=1e-12)
    assert math.isclose(float(np.abs(meshio.read(path).points[:, 2]).max()), 0.0)
