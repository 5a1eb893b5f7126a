"""Facets of a mesh (edges in 2D, faces in 3D): the one place for what the code knows about them.

- :data:`FACET_TYPES`: the facet types a boundary facet set may have, by dimension;
- :data:`FACET_CORNERS`: the number of corner (vertex) nodes of each facet type, taken from
  :data:`masonrydam.elements.shapes.ELEMENT_TYPES`; a facet is identified by its sorted corner nodes
  (:func:`facet_keys`), whatever its node order and its mid-side nodes;
- :func:`element_facets`: which facets (type and local nodes) each element type has;
- :class:`FacetTable`: all facets of all continuum elements of a mesh, keyed by their corners, with
  the elements that share each;
- :func:`owner_centroids`: the centroid of the element that owns each facet of a set (a point inside
  the body, which orients pressures and normals);
- :func:`boundary_owners`: whether each facet of a set bounds exactly one element (of a group), and
  that element's centroid.

The quadrature on facets (points, Jacobians, normals) is
:func:`masonrydam.elements.shapes.facet_quadrature`, their orientation against the owning body
:func:`masonrydam.elements.shapes.facet_outward_sign`.
"""
from __future__ import annotations

import numpy as np

from ..elements.shapes import ELEMENT_TYPES
from ..errors import MeshError
from .model import Mesh

__all__ = ["FACET_TYPES", "FACET_CORNERS", "element_facets", "corner_keys", "facet_keys", "FacetTable",
           "element_centroids", "owner_centroids", "boundary_owners"]

#: facet types of a boundary facet set: edges in 2D, faces in 3D (node orders of
#: :mod:`masonrydam.elements.shapes`)
FACET_TYPES = {2: ("line2", "line3"), 3: ("tri3", "tri6", "quad4", "quad8", "quad9")}
#: number of corner nodes of each facet type: 2 (line2, line3), 3 (tri3, tri6), 4 (quad4, quad8, quad9)
FACET_CORNERS = {t: ELEMENT_TYPES[t].corner_nodes for types in FACET_TYPES.values() for t in types}


def element_facets(element_type: str) -> tuple:
    """``((facet_type, local_nodes), ...)`` of an element type: edges in 2D, faces in 3D.

    Facets are ordered so that their outward normal follows the right-hand rule (3D) or is the
    edge tangent turned -90 degrees (2D, counter-clockwise elements).
    """
    et = ELEMENT_TYPES[element_type]
    facets = getattr(et, "facets", None)
    if facets:
        return tuple(facets)
    ftype = "line2" if len(et.edges[0]) == 2 else "line3"
    return tuple((ftype, tuple(e)) for e in et.edges)


def corner_keys(nodes: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Keys of facets with ``corners`` (n,) corner nodes each, first in ``nodes`` (n, w): their sorted
    corner nodes padded with -1 to 4 columns, (n, 4) int64."""
    k = np.full((len(nodes), 4), -1, dtype=np.int64)
    for nc in np.unique(corners):
        sel = corners == nc
        k[sel, :nc] = np.sort(nodes[sel, :nc], axis=1)
    return k


def facet_keys(facets: np.ndarray, facet_type: str) -> np.ndarray:
    """Keys (n, 4) int64 of facets (n, nfn) of one ``facet_type``: their sorted corner nodes padded with -1."""
    facets = np.asarray(facets, dtype=np.int64)
    return corner_keys(facets, np.full(len(facets), FACET_CORNERS[facet_type]))


class FacetTable:
    """All facets of all continuum elements, padded to a common width with -1.

    nodes (n_f, w); type_index (n_f,) into ``types``; elem (n_f,) global element index (blocks in
    order); key (n_f, 4) sorted corner nodes padded with -1; inverse (n_f,) unique-facet index;
    count (n_unique,) how many elements share each unique facet; first / second (n_unique,) the
    table rows of its first and second occurrence (second -1 when it has one).
    Raises :class:`~masonrydam.errors.MeshError` for an element of another dimension than the mesh,
    or for linear and quadratic elements in one mesh.
    """

    def __init__(self, mesh: Mesh):
        self.types: list[str] = []
        nodes, tidx, elem = [], [], []
        offset = 0
        width = 0
        for b in mesh.blocks:
            et = ELEMENT_TYPES[b.type]
            if et.dim != mesh.dim:
                raise MeshError(f"element type '{b.type}' is {et.dim}D in a {mesh.dim}D mesh", group=b.name)
            for ftype, local in element_facets(b.type):
                if ftype not in self.types:
                    self.types.append(ftype)
                nodes.append(b.cells[:, list(local)])
                tidx.append(np.full(len(b.cells), self.types.index(ftype)))
                elem.append(offset + np.arange(len(b.cells)))
                width = max(width, len(local))
            offset += len(b.cells)
        linear = {t for t in self.types if t in ("line2", "tri3", "quad4")}
        quadratic = set(self.types) - linear
        if linear and quadratic:
            raise MeshError("mixing linear and quadratic elements in one mesh is not supported "
                            f"(facet types {sorted(self.types)})")
        self.width = width
        self.nodes = np.vstack([np.pad(n, ((0, 0), (0, width - n.shape[1])), constant_values=-1) for n in nodes])
        self.type_index = np.concatenate(tidx)
        self.elem = np.concatenate(elem)
        self.n_elements = offset
        self.corners = np.array([FACET_CORNERS[t] for t in self.types])[self.type_index]
        self.key = corner_keys(self.nodes, self.corners)
        uniq, inverse = np.unique(self.key, axis=0, return_inverse=True)
        self.unique_keys = uniq
        self.inverse = inverse.ravel()
        self.count = np.bincount(self.inverse, minlength=len(uniq))
        # first and second occurrence of each unique facet
        order = np.argsort(self.inverse, kind="stable")
        starts = np.searchsorted(self.inverse[order], np.arange(len(uniq)))
        self.first = order[starts]
        second = np.minimum(starts + 1, len(order) - 1)
        self.second = np.where(self.count >= 2, order[second], -1)

    def lookup(self, keys: np.ndarray) -> np.ndarray:
        """Unique-facet index of each key row (n, 4), -1 where the key is not a facet of the mesh."""
        uk = self.unique_keys
        # lexicographic search through a structured view
        view = np.ascontiguousarray(uk).view([("", np.int64)] * 4).ravel()
        q = np.ascontiguousarray(keys, dtype=np.int64).view([("", np.int64)] * 4).ravel()
        pos = np.searchsorted(view, q)
        pos = np.minimum(pos, len(view) - 1)
        found = view[pos] == q
        return np.where(found, pos, -1)


def element_centroids(mesh: Mesh) -> np.ndarray:
    """Centroid (mean of the nodes) of every continuum element, blocks in order: (n_elements, dim) m."""
    return np.vstack([mesh.points[b.cells].mean(axis=1) for b in mesh.blocks])


def owner_centroids(mesh: Mesh, facet_type: str, facets: np.ndarray) -> np.ndarray:
    """Centroid (n, dim) m of the element owning each facet (n, nfn) of ``facet_type``: a point inside the
    body, which orients pressures and normals inward (:func:`masonrydam.elements.shapes.facet_outward_sign`).

    A facet shared by two elements takes the first of them; a facet of no element keeps the origin (its
    own normal is then used)."""
    facets = np.asarray(facets, dtype=np.int64)
    table = FacetTable(mesh)
    k = table.lookup(facet_keys(facets, facet_type))
    cents = element_centroids(mesh)
    out = np.zeros((len(facets), mesh.dim))
    ok = k >= 0
    out[ok] = cents[table.elem[table.first[k[ok]]]]
    return out


def boundary_owners(mesh: Mesh, facet_type: str, facets: np.ndarray, group: str | None = None):
    """The boundary check of a facet set: ``(on_boundary (n,) bool, centroid (n, dim) m)``.

    ``on_boundary``: the facet bounds exactly one continuum element of the mesh (it is on the model's
    outer surface, not inside it nor on no element) and, with ``group``, that element belongs to the
    element group ``group``. ``centroid``: that element's centroid where ``on_boundary``, else zero."""
    facets = np.asarray(facets, dtype=np.int64)
    table = FacetTable(mesh)
    k = table.lookup(facet_keys(facets, facet_type))
    found = k >= 0
    kk = np.maximum(k, 0)
    ok = found & (table.count[kk] == 1)
    owner = table.elem[table.first[kk]]
    if group is not None and len(owner):
        block_of = np.repeat(np.arange(len(mesh.blocks)), [len(b.cells) for b in mesh.blocks])
        in_group = np.array([b.name == group for b in mesh.blocks], dtype=bool)
        ok &= in_group[block_of[owner]]
    out = np.zeros((len(facets), mesh.dim))
    out[ok] = element_centroids(mesh)[owner[ok]]
    return ok, out
