"""Dimension-agnostic mesh data model.

A :class:`Mesh` holds node coordinates, continuum cell blocks (each a named group that a scene
assigns a material to), interface cell blocks (each belonging to a named joint set), named node sets
and named facet sets (boundary edges/faces for pressure loads, or joint facets before interfaces are
inserted). Arrays are plain numpy so they can be handed to numba kernels without conversion.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..elements.shapes import ELEMENT_TYPES
from ..errors import MeshError

#: interface element type -> face type of each side. 2D: 2+2 and 3+3 node line interfaces;
#: 3D: the 8-node (4+4) surface interface of Tzamtzis & Asteris, its 16-node (8+8) quadratic form for 20-node
#: hexahedra, and the 6-node (3+3) triangular interface for tetrahedral meshes.
INTERFACE_FACE_TYPE = {
    "interface_line2": "line2",
    "interface_line3": "line3",
    "interface_quad4": "quad4",
    "interface_quad8": "quad8",
    "interface_tri3": "tri3",
}
#: face type -> interface element type
INTERFACE_OF_FACE = {face: itype for itype, face in INTERFACE_FACE_TYPE.items()}


@dataclass
class CellBlock:
    """Cells of one element type in one named group.

    type: element type name (``quad4``, ``interface_line2``, ...);
    cells: (n_cells, n_nodes_per_cell) int64 node indices;
    name: group name (material group for continuum blocks, joint set for interfaces).
    """

    type: str
    cells: np.ndarray
    name: str

    def __post_init__(self):
        self.cells = np.ascontiguousarray(self.cells, dtype=np.int64)
        if self.cells.ndim != 2:
            raise MeshError(f"cells of block '{self.name}' must be a 2D array, got shape {self.cells.shape}")

    @property
    def is_interface(self) -> bool:
        return self.type in INTERFACE_FACE_TYPE


@dataclass
class FacetSet:
    """Named set of facets (edges in 2D, faces in 3D): ``type`` is the facet type (line2/line3 in
    2D; tri3/tri6/quad4/quad8/quad9 in 3D: :data:`masonrydam.mesh.facets.FACET_TYPES`), ``facets``
    (n, nfn) node lists in that type's order."""

    type: str
    facets: np.ndarray

    def __post_init__(self):
        self.facets = np.ascontiguousarray(self.facets, dtype=np.int64)


@dataclass
class Mesh:
    """Mesh of continuum blocks and zero-thickness interfaces.

    points: (n_nodes, dim) float64 coordinates in m;
    blocks: continuum cell blocks; joints: interface cell blocks;
    node_sets: name -> (k,) int64 node indices; facet_sets: name -> FacetSet.
    """

    points: np.ndarray
    blocks: list[CellBlock]
    joints: list[CellBlock] = field(default_factory=list)
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    facet_sets: dict[str, FacetSet] = field(default_factory=dict)

    def __post_init__(self):
        self.points = np.ascontiguousarray(self.points, dtype=np.float64)
        if self.points.ndim != 2 or self.points.shape[1] not in (2, 3):
            raise MeshError(f"points must have shape (n, 2) or (n, 3), got {self.points.shape}")
        self.node_sets = {k: np.unique(np.asarray(v, dtype=np.int64)) for k, v in self.node_sets.items()}

    @property
    def dim(self) -> int:
        return self.points.shape[1]

    @property
    def n_nodes(self) -> int:
        return self.points.shape[0]

    def group_names(self) -> list[str]:
        return sorted({b.name for b in self.blocks})

    def joint_set_names(self) -> list[str]:
        return sorted({b.name for b in self.joints})

    def n_elements(self) -> int:
        return sum(len(b.cells) for b in self.blocks)

    def n_interfaces(self) -> int:
        return sum(len(b.cells) for b in self.joints)

    def check(self) -> None:
        """Check indices and element types; raise :class:`MeshError` naming the block."""
        n = self.n_nodes
        for b in self.blocks + self.joints:
            if not b.is_interface and b.type not in ELEMENT_TYPES:
                raise MeshError(f"unknown element type '{b.type}'", group=b.name)
            if b.is_interface:
                nfn = ELEMENT_TYPES[INTERFACE_FACE_TYPE[b.type]].n_nodes
                expected = 2 * nfn
            else:
                expected = ELEMENT_TYPES[b.type].n_nodes
            if b.cells.shape[1] != expected:
                raise MeshError(f"type '{b.type}' needs {expected} nodes per cell, got {b.cells.shape[1]}", group=b.name)
            if b.cells.size and (b.cells.min() < 0 or b.cells.max() >= n):
                bad = np.where((b.cells < 0).any(1) | (b.cells >= n).any(1))[0]
                raise MeshError(f"node index out of range [0, {n})", group=b.name, elements=bad)
        for name, ids in self.node_sets.items():
            if ids.size and (ids.min() < 0 or ids.max() >= n):
                raise MeshError(f"node set '{name}' has node indices out of range [0, {n})")

    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        return self.points.min(axis=0), self.points.max(axis=0)
