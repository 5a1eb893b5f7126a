"""Conformal structured hexahedral meshes of axis-aligned boxes with interfaces on the joints (3D).

The 3D counterpart of :mod:`generators.grid`: all box faces become grid planes; every interval
between grid planes is split into equal elements no longer than ``element_size``; grid cells are
assigned to the box containing their centre (cells outside every box are holes). Faces between
cells of different boxes are joints, classified by a user function into named joint sets; then
interfaces are inserted by :func:`masonrydam.mesh.interfaces.insert_interfaces`.

Axes: x along the wall (or dam axis), y across (thickness), z up. Elements: hex8 (order 1) or
hex20 (order 2), node order as meshio / VTK (masonrydam.elements.shapes).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from masonrydam.errors import MeshError
from masonrydam.mesh.facets import element_facets
from masonrydam.mesh.interfaces import insert_interfaces
from masonrydam.mesh.model import CellBlock, FacetSet, Mesh

from .grid import grid_lines

#: hex8 corner offsets (i, j, k) in units of the element step, VTK order
_HEX_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])
#: hex20 mid-edge nodes: VTK edges 0-1, 1-2, 2-3, 3-0, 4-5, 5-6, 6-7, 7-4, 0-4, 1-5, 2-6, 3-7
_HEX_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]
AXES = "xyz"


@dataclass(frozen=True)
class Box:
    """Axis-aligned block [x0, x1] x [y0, y1] x [z0, z1] (m) in material group ``group`` with a
    ``kind`` tag used to classify joints (e.g. 'unit', 'beam')."""

    x0: float
    y0: float
    z0: float
    x1: float
    y1: float
    z1: float
    group: str
    kind: str = "unit"

    def lo(self):
        return (self.x0, self.y0, self.z0)

    def hi(self):
        return (self.x1, self.y1, self.z1)


def boxes_to_mesh(
    boxes: list[Box],
    element_size: float,
    order: int = 1,
    classify_joint: Callable[[Box, Box, str], str | None] | None = None,
) -> Mesh:
    """Mesh boxes conformally with hexahedra and insert interfaces between different boxes.

    element_size: largest element edge (m); order: 1 (hex8) or 2 (hex20).
    classify_joint(lower_box, upper_box, axis in {'x', 'y', 'z'}) returns the joint set name for
    the faces between two boxes that touch across a plane normal to ``axis`` (lower_box on the
    low side), or None to glue them (no interface). Default: 'bed' for axis z, 'head' for x,
    'collar' for y.

    Named node sets: base / top (z min / max), left / right (x), front / back (y) of the model's
    bounding box, and ``<group>_nodes`` with the nodes of each material group; facet sets (quad4 or quad8 faces) base_face, top_face, left_face, right_face,
    front_face, back_face. Returns a 3D :class:`Mesh`.
    """
    if not element_size > 0:
        raise MeshError(f"element_size must be > 0, got {element_size}")
    if order not in (1, 2):
        raise MeshError(f"element order must be 1 or 2, got {order}")
    if not boxes:
        raise MeshError("no boxes to mesh")
    for k, b in enumerate(boxes):
        if not all(h > lo for lo, h in zip(b.lo(), b.hi())):
            raise MeshError(f"box {k} ({b.group}) has a non-positive edge: {b}")
    default = {"z": "bed", "x": "head", "y": "collar"}
    classify_joint = classify_joint or (lambda a, b, axis: default[axis])
    lo = np.array([b.lo() for b in boxes])
    hi = np.array([b.hi() for b in boxes])
    lines = [grid_lines(np.concatenate([lo[:, a], hi[:, a]]), element_size) for a in range(3)]
    nc = [len(g) - 1 for g in lines]
    centres = [0.5 * (g[1:] + g[:-1]) for g in lines]

    # owner box of every grid cell; a box covers a contiguous index range along each axis
    owner = np.full(nc, -1, dtype=np.int64)
    for k in range(len(boxes)):
        r = [np.nonzero((centres[a] > lo[k, a]) & (centres[a] < hi[k, a]))[0] for a in range(3)]
        if any(len(x) == 0 for x in r):
            raise MeshError(f"box {k} ({boxes[k].group}) is thinner than the grid can resolve")
        sl = tuple(slice(x[0], x[-1] + 1) for x in r)
        sub = owner[sl]
        if (sub >= 0).any():
            raise MeshError(f"box {k} ({boxes[k].group}) overlaps box {int(sub[sub >= 0][0])}")
        owner[sl] = k

    # node grid (with 2x resolution for quadratic elements)
    s = order
    g = [np.concatenate([np.linspace(L[i], L[i + 1], s + 1)[:-1] for i in range(len(L) - 1)] + [[L[-1]]]) for L in lines]
    nx, ny, nz = (len(x) for x in g)
    X, Y, Z = np.meshgrid(g[0], g[1], g[2], indexing="ij")
    points = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)  # node id = (i*ny + j)*nz + k

    def nid(i, j, k):
        return (i * ny + j) * nz + k

    ci, cj, ck = np.nonzero(owner >= 0)
    own = owner[ci, cj, ck]
    corner_ids = [nid(s * ci + o[0] * s, s * cj + o[1] * s, s * ck + o[2] * s) for o in _HEX_CORNERS]
    cols = list(corner_ids)
    if order == 2:
        for a, b in _HEX_EDGES:
            o = (_HEX_CORNERS[a] + _HEX_CORNERS[b])  # in half-steps: 0, 1 or 2
            cols.append(nid(s * ci + o[0], s * cj + o[1], s * ck + o[2]))
    conn = np.stack(cols, axis=1).astype(np.int64)
    etype = "hex8" if order == 1 else "hex20"
    groups = np.array([b.group for b in boxes])
    blocks = [CellBlock(etype, conn[groups[own] == name], str(name)) for name in sorted(set(groups[own].tolist()))]

    # joint faces between cells of different boxes, classified once per pair of boxes
    joint_facets: dict[str, list] = {}
    for axis in range(3):
        a_idx = [slice(None)] * 3
        b_idx = [slice(None)] * 3
        a_idx[axis] = slice(0, nc[axis] - 1)
        b_idx[axis] = slice(1, nc[axis])
        oa, ob = owner[tuple(a_idx)], owner[tuple(b_idx)]
        hit = (oa >= 0) & (ob >= 0) & (oa != ob)
        ii, jj, kk = np.nonzero(hit)
        pa, pb = oa[hit], ob[hit]
        idx = [ii, jj, kk]
        idx[axis] = idx[axis] + 1  # the face lies on the low plane of the upper cell
        base = [s * x for x in idx]
        other = [d for d in range(3) if d != axis]
        quad = []
        for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
            c = list(base)
            c[other[0]] = c[other[0]] + du * s
            c[other[1]] = c[other[1]] + dv * s
            quad.append(nid(*c))
        faces = np.stack(quad, axis=1)
        pairs, inv = np.unique(np.stack([pa, pb], axis=1), axis=0, return_inverse=True)
        inv = inv.ravel()
        # classify each pair of boxes once, then select the faces of each joint set with one mask
        names = [classify_joint(boxes[ka], boxes[kb], AXES[axis]) for ka, kb in pairs]
        labels = sorted({n for n in names if n})
        code = np.array([labels.index(n) if n else -1 for n in names], dtype=np.int64)[inv]
        for k, name in enumerate(labels):
            joint_facets.setdefault(name, []).append(faces[code == k])

    # compact unused nodes
    used = np.zeros(len(points), dtype=bool)
    for b in blocks:
        used[b.cells.ravel()] = True
    new_index = np.cumsum(used) - 1
    points = points[used]
    for b in blocks:
        b.cells = new_index[b.cells]
    joint_facets = {k: new_index[np.vstack(joint_facets[k])] for k in sorted(joint_facets)}  # sets in name order

    lo_b, hi_b = points.min(axis=0), points.max(axis=0)
    tol = 1e-9 * float((hi_b - lo_b).max())
    planes = {"base": (2, lo_b[2]), "top": (2, hi_b[2]), "left": (0, lo_b[0]), "right": (0, hi_b[0]),
              "front": (1, lo_b[1]), "back": (1, hi_b[1])}
    node_sets = {name: np.nonzero(np.abs(points[:, a] - v) < tol)[0] for name, (a, v) in planes.items()}
    ftype = "quad4" if order == 1 else "quad8"
    facet_sets = {}
    for name, (a, v) in planes.items():
        faces = []
        for b in blocks:
            for ft, local in element_facets(b.type):
                nodes = b.cells[:, list(local)]
                on = np.all(np.abs(points[nodes, a] - v) < tol, axis=1)
                faces.append(nodes[on])
        facet_sets[f"{name}_face"] = FacetSet(ftype, np.vstack(faces))
    mesh = Mesh(points, blocks, [], node_sets, facet_sets)
    if joint_facets:
        mesh = insert_interfaces(mesh, joint_facets)
    # nodes of each material group (after insertion, so a group owns only its own copies)
    for b in mesh.blocks:
        key = f"{b.name}_nodes"
        prev = mesh.node_sets.get(key, np.zeros(0, dtype=np.int64))
        mesh.node_sets[key] = np.unique(np.concatenate([prev, b.cells.ravel()]))
    return mesh


def rotation_matrix(angles_deg) -> np.ndarray:
    """Rotation matrix of successive rotations about x, then y, then z (degrees, right-hand rule)."""
    ax, ay, az = np.radians(np.asarray(angles_deg, dtype=np.float64))
    Rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    Ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    Rz = np.array([[np.cos(az), -np.sin(az), 0], [np.sin(az), np.cos(az), 0], [0, 0, 1]])
    return Rz @ Ry @ Rx
