"""The facet module (masonrydam.mesh.facets): facet types and corner counts of every element type, facet
keys, owner centroids and the boundary check, on meshes small enough to count by hand."""
from __future__ import annotations

import numpy as np
import pytest

from masonrydam.elements.shapes import CONTINUUM_TYPES_2D, CONTINUUM_TYPES_3D, ELEMENT_TYPES, reference_nodes
from masonrydam.mesh.facets import (FACET_CORNERS, FACET_TYPES, FacetTable, boundary_owners, element_facets,
                                    facet_keys, owner_centroids)
from masonrydam.mesh.model import CellBlock, Mesh

#: facet type and number of facets of every element type (edges in 2D, faces in 3D)
EXPECTED_FACETS = {"tri3": ("line2", 3), "tri6": ("line3", 3), "quad4": ("line2", 4), "quad8": ("line3", 4),
                   "quad9": ("line3", 4), "hex8": ("quad4", 6), "hex20": ("quad8", 6), "tet4": ("tri3", 4),
                   "tet10": ("tri6", 4)}


def test_corner_counts_of_every_facet_type():
    assert FACET_CORNERS == {"line2": 2, "line3": 2, "tri3": 3, "tri6": 3, "quad4": 4, "quad8": 4, "quad9": 4}
    assert set(FACET_CORNERS) == set(FACET_TYPES[2]) | set(FACET_TYPES[3])


@pytest.mark.parametrize("element_type", CONTINUUM_TYPES_2D + CONTINUUM_TYPES_3D)
def test_facets_of_every_element_type(element_type):
    """Each element type's facets: the expected type and number, a boundary facet type of its dimension,
    with the facet type's corner count of the element's corner nodes first (the key of a facet)."""
    assert set(EXPECTED_FACETS) == set(CONTINUUM_TYPES_2D + CONTINUUM_TYPES_3D)
    et = ELEMENT_TYPES[element_type]
    facets = element_facets(element_type)
    ftype, count = EXPECTED_FACETS[element_type]
    assert [t for t, _ in facets] == [ftype] * count
    assert ftype in FACET_TYPES[et.dim]
    nc = FACET_CORNERS[ftype]
    for _, local in facets:
        assert len(local) == ELEMENT_TYPES[ftype].n_nodes
        assert all(i < et.corner_nodes for i in local[:nc])  # corners first
        assert all(i >= et.corner_nodes for i in local[nc:])  # then mid-side nodes
    # every corner of the element is a corner of as many facets as meet there (2 in 2D, 3 on a hex or tet)
    corner_use = np.bincount([i for _, local in facets for i in local[:nc]], minlength=et.corner_nodes)
    assert (corner_use == (2 if et.dim == 2 else 3)).all()


def test_facet_keys_ignore_node_order_and_mid_side_nodes():
    a = facet_keys(np.array([[7, 3, 5, 11, 12, 13]]), "tri6")
    b = facet_keys(np.array([[5, 7, 3, 99, 98, 97]]), "tri6")
    np.testing.assert_array_equal(a, [[3, 5, 7, -1]])
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(facet_keys(np.array([[4, 1, 2, 3, 9, 9, 9, 9, 9]]), "quad9"), [[1, 2, 3, 4]])
    np.testing.assert_array_equal(facet_keys(np.array([[8, 2, 5]]), "line3"), [[2, 8, -1, -1]])


def two_squares():
    """Two unit quad4 elements side by side in two groups: 'left' on [0, 1] x [0, 1], 'right' on [1, 2]."""
    points = np.array([[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [2, 1]], dtype=float)
    return Mesh(points, [CellBlock("quad4", [[0, 1, 4, 3]], "left"), CellBlock("quad4", [[1, 2, 5, 4]], "right")])


def test_owner_centroids_and_boundary_check_in_2d():
    mesh = two_squares()
    # bottom of the left square (reversed), the shared edge, bottom of the right square, and no edge at all
    edges = np.array([[1, 0], [1, 4], [2, 1], [0, 5]])
    np.testing.assert_array_equal(owner_centroids(mesh, "line2", edges),
                                  [[0.5, 0.5], [0.5, 0.5], [1.5, 0.5], [0.0, 0.0]])
    ok, centre = boundary_owners(mesh, "line2", edges)
    np.testing.assert_array_equal(ok, [True, False, True, False])
    np.testing.assert_array_equal(centre, [[0.5, 0.5], [0.0, 0.0], [1.5, 0.5], [0.0, 0.0]])
    ok, centre = boundary_owners(mesh, "line2", edges, group="right")
    np.testing.assert_array_equal(ok, [False, False, True, False])
    np.testing.assert_array_equal(centre[2], [1.5, 0.5])
    table = FacetTable(mesh)
    assert table.n_elements == 2 and len(table.unique_keys) == 7 and table.count.sum() == 8


@pytest.mark.parametrize("facet_type", ["quad4", "quad8", "quad9"])
def test_owner_of_a_face_given_with_any_quadrilateral_type(facet_type):
    """A 3D face set of type quad9 (or quad8) on a hex8 block is found by its four corners."""
    points = (reference_nodes("hex8") + 1.0) / 2.0 + np.array([10.0, 0.0, 0.0])
    mesh = Mesh(points, [CellBlock("hex8", [np.arange(8)], "box")])
    top = [4, 5, 6, 7]
    face = np.array([top + [0] * (ELEMENT_TYPES[facet_type].n_nodes - 4)])  # the extra nodes are not looked at
    np.testing.assert_allclose(owner_centroids(mesh, facet_type, face), [[10.5, 0.5, 0.5]])
    ok, centre = boundary_owners(mesh, facet_type, face, group="box")
    assert ok.all()
    np.testing.assert_allclose(centre, [[10.5, 0.5, 0.5]])
