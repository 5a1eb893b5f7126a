"""Conformal structured meshes of axis-aligned rectangular blocks with interfaces on the joints.

All block edges become grid lines; every interval between grid lines is split into equal elements
no longer than ``element_size``. Grid cells are assigned to the block containing their centre
(cells outside every block are holes). Edges between cells of different blocks are joints; they are
classified by a user function into named joint sets, then interfaces are inserted by
:func:`masonrydam.mesh.interfaces.insert_interfaces`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from masonrydam.elements.shapes import ELEMENT_TYPES
from masonrydam.errors import MeshError
from masonrydam.mesh.interfaces import insert_interfaces
from masonrydam.mesh.model import CellBlock, FacetSet, Mesh


@dataclass(frozen=True)
class Rect:
    """Axis-aligned block [x0, x1] x [y0, y1] (m) in material group ``group`` with a ``kind`` tag
    used to classify joints (e.g. 'unit', 'beam')."""

    x0: float
    y0: float
    x1: float
    y1: float
    group: str
    kind: str = "unit"


def grid_lines(values, element_size):
    """The block edge coordinates ``values`` (sorted, duplicates removed) with lines added between them so
    that no cell is wider than ``element_size``."""
    vals = np.unique(np.round(np.asarray(values, dtype=np.float64), 12))
    out = [vals[0]]
    for a, b in zip(vals[:-1], vals[1:]):
        n = max(1, int(np.ceil((b - a) / element_size - 1e-9)))
        out.extend(list(a + (b - a) * np.arange(1, n + 1) / n))
    return np.array(out)


def rectangles_to_mesh(
    rects: list[Rect],
    element_size: float,
    order: int = 1,
    element: str = "quad",
    classify_joint: Callable[[Rect, Rect, str], str | None] | None = None,
) -> Mesh:
    """Mesh rectangles conformally and insert interfaces between different rectangles.

    element_size: largest element edge (m); order: 1 or 2; element: 'quad' (quad4 / quad8 / quad9
    with ``element='quad9'``) or 'tri' (tri3 / tri6). classify_joint(lower_or_left, upper_or_right,
    orientation in {'horizontal', 'vertical'}) returns the joint set name, or None to glue the two
    blocks (no interface). Default: 'bed' for horizontal, 'head' for vertical joints.

    Named node sets: base, top, left, right (model bounding box); facet sets base_edge, top_edge,
    left_edge, right_edge. Returns a 2D :class:`Mesh`.
    """
    if element_size <= 0:
        raise MeshError(f"element_size must be > 0, got {element_size}")
    if order not in (1, 2):
        raise MeshError(f"element order must be 1 or 2, got {order}")
    for r in rects:
        if not (r.x1 > r.x0 and r.y1 > r.y0):
            raise MeshError(f"block {r} has non-positive width or height")
    classify_joint = classify_joint or (lambda a, b, o: "bed" if o == "horizontal" else "head")
    xs = grid_lines([v for r in rects for v in (r.x0, r.x1)], element_size)
    ys = grid_lines([v for r in rects for v in (r.y0, r.y1)], element_size)
    ncx, ncy = len(xs) - 1, len(ys) - 1
    xc, yc = 0.5 * (xs[1:] + xs[:-1]), 0.5 * (ys[1:] + ys[:-1])
    owner = np.full((ncx, ncy), -1, dtype=np.int64)
    for k, r in enumerate(rects):
        ix = (xc > r.x0) & (xc < r.x1)
        iy = (yc > r.y0) & (yc < r.y1)
        sub = owner[np.ix_(ix, iy)]
        if (sub >= 0).any():
            raise MeshError(f"block {k} ({r.group}) overlaps block {int(sub[sub >= 0][0])}")
        owner[np.ix_(ix, iy)] = k

    # node grid with 2x resolution for quadratic elements
    s = order
    gx = np.concatenate([np.linspace(xs[i], xs[i + 1], s + 1)[:-1] for i in range(ncx)] + [[xs[-1]]])
    gy = np.concatenate([np.linspace(ys[j], ys[j + 1], s + 1)[:-1] for j in range(ncy)] + [[ys[-1]]])
    nx = len(gx)
    node_id = lambda i, j: j * nx + i  # noqa: E731
    X, Y = np.meshgrid(gx, gy, indexing="xy")
    points = np.stack([X.ravel(), Y.ravel()], axis=1)

    cells_by_group: dict[str, list] = {}
    tri = element == "tri"
    for ci in range(ncx):
        for cj in range(ncy):
            k = owner[ci, cj]
            if k < 0:
                continue
            i0, j0 = s * ci, s * cj
            c = [node_id(i0, j0), node_id(i0 + s, j0), node_id(i0 + s, j0 + s), node_id(i0, j0 + s)]
            if order == 2:
                mids = [node_id(i0 + 1, j0), node_id(i0 + 2, j0 + 1), node_id(i0 + 1, j0 + 2), node_id(i0, j0 + 1)]
                centre = node_id(i0 + 1, j0 + 1)
            lst = cells_by_group.setdefault(rects[k].group, [])
            if tri and order == 1:
                lst.append([c[0], c[1], c[2]])
                lst.append([c[0], c[2], c[3]])
            elif tri:
                lst.append([c[0], c[1], c[2], mids[0], mids[1], centre])
                lst.append([c[0], c[2], c[3], centre, mids[2], mids[3]])
            elif order == 1:
                lst.append(c)
            elif element == "quad9":
                lst.append(c + mids + [centre])
            else:
                lst.append(c + mids)
    etype = {("quad", 1): "quad4", ("quad", 2): "quad8", ("quad9", 2): "quad9", ("quad9", 1): "quad4",
             ("tri", 1): "tri3", ("tri", 2): "tri6"}[(element, order)]
    blocks = [CellBlock(etype, np.array(v), g) for g, v in sorted(cells_by_group.items())]

    # joint facets between different blocks
    joint_facets: dict[str, list] = {}
    for ci in range(ncx):
        for cj in range(ncy):
            a = owner[ci, cj]
            if a < 0:
                continue
            if ci + 1 < ncx and owner[ci + 1, cj] >= 0 and owner[ci + 1, cj] != a:
                name = classify_joint(rects[a], rects[owner[ci + 1, cj]], "vertical")
                if name:
                    i, j0 = s * (ci + 1), s * cj
                    f = [node_id(i, j0), node_id(i, j0 + s)] + ([node_id(i, j0 + 1)] if order == 2 else [])
                    joint_facets.setdefault(name, []).append(f)
            if cj + 1 < ncy and owner[ci, cj + 1] >= 0 and owner[ci, cj + 1] != a:
                name = classify_joint(rects[a], rects[owner[ci, cj + 1]], "horizontal")
                if name:
                    i0, j = s * ci, s * (cj + 1)
                    f = [node_id(i0, j), node_id(i0 + s, j)] + ([node_id(i0 + 1, j)] if order == 2 else [])
                    joint_facets.setdefault(name, []).append(f)

    # compact unused nodes (quad8 centres, holes)
    used = np.zeros(len(points), dtype=bool)
    for b in blocks:
        used[b.cells.ravel()] = True
    new_index = np.cumsum(used) - 1
    points = points[used]
    for b in blocks:
        b.cells = new_index[b.cells]
    joint_facets = {k: new_index[np.array(v)] for k, v in joint_facets.items()}

    xmin, ymin = points.min(axis=0)
    xmax, ymax = points.max(axis=0)
    tol = 1e-9 * max(xmax - xmin, ymax - ymin)
    node_sets = {
        "base": np.nonzero(np.abs(points[:, 1] - ymin) < tol)[0],
        "top": np.nonzero(np.abs(points[:, 1] - ymax) < tol)[0],
        "left": np.nonzero(np.abs(points[:, 0] - xmin) < tol)[0],
        "right": np.nonzero(np.abs(points[:, 0] - xmax) < tol)[0],
    }
    ftype = "line2" if order == 1 else "line3"
    facet_sets = {}
    for name, axis, val in (("base_edge", 1, ymin), ("top_edge", 1, ymax), ("left_edge", 0, xmin), ("right_edge", 0, xmax)):
        facets = []
        for b in blocks:
            for edge in ELEMENT_TYPES[b.type].edges:
                nodes = b.cells[:, list(edge)]
                on = np.all(np.abs(points[nodes, axis] - val) < tol, axis=1)
                facets.extend(nodes[on].tolist())
        facet_sets[name] = FacetSet(ftype, np.array(facets, dtype=np.int64).reshape(-1, 2 if order == 1 else 3))
    mesh = Mesh(points, blocks, [], node_sets, facet_sets)
    if not joint_facets:
        return mesh
    return insert_interfaces(mesh, joint_facets)
