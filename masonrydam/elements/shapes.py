"""Element types and their shape functions on the reference element.

Node orderings follow gmsh / meshio / VTK so that meshes read through meshio need no reordering:

- ``line2``: ends at xi = -1, +1;  ``line3``: ends, then the middle node (xi = 0);
- ``tri3``: (0,0), (1,0), (0,1);  ``tri6``: corners then mid-edges 0-1, 1-2, 2-0;
- ``quad4``: (-1,-1), (1,-1), (1,1), (-1,1) counter-clockwise;
- ``quad8``: corners then mid-edges 0-1, 1-2, 2-3, 3-0 (serendipity);  ``quad9``: quad8 plus centre.

``shape_functions(name, points)`` returns ``N`` of shape ``(n_points, n_nodes)`` and
``dN`` of shape ``(n_points, dim_ref, n_nodes)`` (derivatives with respect to the natural coordinates).
These tables are evaluated once in Python and passed to the numba kernels.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .quadrature import tensor_rule, triangle_rule


@dataclass(frozen=True)
class ElementType:
    """Static description of an element topology.

    name: our name; meshio_name: the meshio cell type; dim: reference dimension;
    n_nodes: nodes per element; order: polynomial order; family: 'line', 'tri', 'quad';
    corner_nodes: number of vertex nodes; edges: local node lists of each edge (for facets),
    in the line2 / line3 ordering; default_gauss: points per direction (tensor families) or
    total points (triangles) of the full integration rule.
    """

    name: str
    meshio_name: str
    dim: int
    n_nodes: int
    order: int
    family: str
    corner_nodes: int
    edges: tuple
    default_gauss: int


ELEMENT_TYPES: dict[str, ElementType] = {
    "line2": ElementType("line2", "line", 1, 2, 1, "line", 2, ((0, 1),), 2),
    "line3": ElementType("line3", "line3", 1, 3, 2, "line", 2, ((0, 1, 2),), 3),
    "tri3": ElementType("tri3", "triangle", 2, 3, 1, "tri", 3, ((0, 1), (1, 2), (2, 0)), 1),
    "tri6": ElementType("tri6", "triangle6", 2, 6, 2, "tri", 3, ((0, 1, 3), (1, 2, 4), (2, 0, 5)), 3),
    "quad4": ElementType("quad4", "quad", 2, 4, 1, "quad", 4, ((0, 1), (1, 2), (2, 3), (3, 0)), 2),
    "quad8": ElementType(
        "quad8", "quad8", 2, 8, 2, "quad", 4, ((0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7)), 3
    ),
    "quad9": ElementType(
        "quad9", "quad9", 2, 9, 2, "quad", 4, ((0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7)), 3
    ),
}
MESHIO_TO_TYPE = {t.meshio_name: t.name for t in ELEMENT_TYPES.values()}
CONTINUUM_TYPES_2D = ("tri3", "tri6", "quad4", "quad8", "quad9")

_QUAD_CORNERS = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=np.float64)


def _line(points: np.ndarray, n_nodes: int):
    x = points[:, 0]
    if n_nodes == 2:
        N = np.stack([(1 - x) / 2, (1 + x) / 2], axis=1)
        dN = np.stack([np.full_like(x, -0.5), np.full_like(x, 0.5)], axis=1)
    else:
        N = np.stack([x * (x - 1) / 2, x * (x + 1) / 2, 1 - x * x], axis=1)
        dN = np.stack([x - 0.5, x + 0.5, -2 * x], axis=1)
    return N, dN[:, None, :]


def _tri(points: np.ndarray, n_nodes: int):
    r, s = points[:, 0], points[:, 1]
    t = 1 - r - s
    one = np.ones_like(r)
    if n_nodes == 3:
        N = np.stack([t, r, s], axis=1)
        dr = np.stack([-one, one, 0 * one], axis=1)
        ds = np.stack([-one, 0 * one, one], axis=1)
    else:
        N = np.stack([t * (2 * t - 1), r * (2 * r - 1), s * (2 * s - 1), 4 * r * t, 4 * r * s, 4 * s * t], axis=1)
        dr = np.stack([-(4 * t - 1), 4 * r - 1, 0 * r, 4 * (t - r), 4 * s, -4 * s], axis=1)
        ds = np.stack([-(4 * t - 1), 0 * r, 4 * s - 1, -4 * r, 4 * r, 4 * (t - s)], axis=1)
    return N, np.stack([dr, ds], axis=1)


def _quad(points: np.ndarray, n_nodes: int):
    x, y = points[:, 0], points[:, 1]
    xi_c, eta_c = _QUAD_CORNERS[:, 0], _QUAD_CORNERS[:, 1]
    if n_nodes == 4:
        N = 0.25 * (1 + np.outer(x, xi_c)) * (1 + np.outer(y, eta_c))
        dx = 0.25 * xi_c * (1 + np.outer(y, eta_c))
        dy = 0.25 * eta_c * (1 + np.outer(x, xi_c))
        return N, np.stack([dx, dy], axis=1)
    if n_nodes == 9:
        # Lagrange product of 1D quadratic functions; 1D node index per quad9 node.
        ix = [0, 1, 1, 0, 2, 1, 2, 0, 2]
        iy = [0, 0, 1, 1, 0, 2, 1, 2, 2]
        Lx, dLx = _line(points[:, :1], 3)
        Ly, dLy = _line(points[:, 1:2], 3)
        N = Lx[:, ix] * Ly[:, iy]
        dx = dLx[:, 0, ix] * Ly[:, iy]
        dy = Lx[:, ix] * dLy[:, 0, iy]
        return N, np.stack([dx, dy], axis=1)
    # 8-node serendipity
    N = np.zeros((len(x), 8))
    dx = np.zeros((len(x), 8))
    dy = np.zeros((len(x), 8))
    for a in range(4):
        xa, ya = xi_c[a], eta_c[a]
        N[:, a] = 0.25 * (1 + xa * x) * (1 + ya * y) * (xa * x + ya * y - 1)
        dx[:, a] = 0.25 * xa * (1 + ya * y) * (2 * xa * x + ya * y)
        dy[:, a] = 0.25 * ya * (1 + xa * x) * (xa * x + 2 * ya * y)
    # mid-side nodes 4 (eta=-1), 5 (xi=+1), 6 (eta=+1), 7 (xi=-1)
    for a, (xa, ya) in zip(range(4, 8), [(0, -1), (1, 0), (0, 1), (-1, 0)]):
        if xa == 0:
            N[:, a] = 0.5 * (1 - x * x) * (1 + ya * y)
            dx[:, a] = -x * (1 + ya * y)
            dy[:, a] = 0.5 * ya * (1 - x * x)
        else:
            N[:, a] = 0.5 * (1 + xa * x) * (1 - y * y)
            dx[:, a] = 0.5 * xa * (1 - y * y)
            dy[:, a] = -y * (1 + xa * x)
    return N, np.stack([dx, dy], axis=1)


def shape_functions(name: str, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape functions of element type ``name`` at natural ``points`` (n, dim_ref).

    Returns ``N`` (n, n_nodes) and ``dN`` (n, dim_ref, n_nodes), float64, C-contiguous.
    """
    et = ELEMENT_TYPES[name]
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    if points.shape[1] != et.dim:
        raise ValueError(f"{name}: points must have {et.dim} natural coordinates, got {points.shape[1]}")
    fn = {"line": _line, "tri": _tri, "quad": _quad}[et.family]
    N, dN = fn(points, et.n_nodes)
    return np.ascontiguousarray(N, dtype=np.float64), np.ascontiguousarray(dN, dtype=np.float64)


def reference_nodes(name: str) -> np.ndarray:
    """Natural coordinates of the nodes of element type ``name``: (n_nodes, dim_ref)."""
    if name == "line2":
        return np.array([[-1.0], [1.0]])
    if name == "line3":
        return np.array([[-1.0], [1.0], [0.0]])
    if name == "tri3":
        return np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    if name == "tri6":
        return np.array([[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]], dtype=np.float64)
    mids = np.array([[0, -1], [1, 0], [0, 1], [-1, 0]], dtype=np.float64)
    if name == "quad4":
        return _QUAD_CORNERS.copy()
    if name == "quad8":
        return np.vstack([_QUAD_CORNERS, mids])
    if name == "quad9":
        return np.vstack([_QUAD_CORNERS, mids, [[0.0, 0.0]]])
    raise KeyError(name)


def integration_rule(name: str, n: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Gauss rule for continuum element ``name``: ``n`` points per direction (tensor families)
    or ``n`` points in total (triangles); default: full integration."""
    et = ELEMENT_TYPES[name]
    n = et.default_gauss if n is None else n
    if et.family == "tri":
        return triangle_rule(n)
    return tensor_rule("gauss", n, et.dim)
