"""Element types and their shape functions on the reference element.

:data:`ELEMENT_TYPES` holds every type (line2/line3, tri3/tri6, quad4/quad8/quad9, hex8/hex20, tet4/tet10) with
its nodes, ``edges`` and outward-ordered ``facets``; node orders are meshio's / VTK's
(:data:`GMSH_TO_MESHIO_ORDER` for gmsh-API node lists). ``shape_functions(name, points)`` returns ``N`` of shape
``(n_points, n_nodes)`` and ``dN`` of shape ``(n_points, dim_ref, n_nodes)`` (derivatives with respect to the
natural coordinates), evaluated once in Python and passed to the numba kernels; :func:`integration_rule`,
:func:`facet_rule` and :func:`facet_quadrature` give the rules and the facet points, normals and Jacobians
(m, m2). Shape functions: Zienkiewicz, Taylor & Zhu (2013, ch. 6); Hughes (2000, sec. 3.5).

Node orders, edge and face tables and the shape functions: docs/elements.md, section "Node orders, facets and
shape functions".
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .quadrature import collapsed_triangle_rule, tensor_rule, tetrahedron_rule, triangle_rule


@dataclass(frozen=True)
class ElementType:
    """Static description of an element topology.

    name: our name; meshio_name: the meshio cell type; dim: reference dimension;
    n_nodes: nodes per element; order: polynomial order; family: 'line', 'tri', 'quad', 'hex', 'tet';
    corner_nodes: number of vertex nodes; edges: local node lists of each edge, in the line2 / line3
    ordering (in 2D these are also the facets); default_gauss: points per direction (tensor families)
    or total points (triangles, tetrahedra) of the full integration rule; facets: ``(facet_type,
    local_nodes)`` of each facet (2D: the edges as line2 / line3; 3D: the faces as quad4 / quad8 /
    tri3 / tri6 with outward right-hand-rule normals; line types: the two end points as ``"vertex"``).
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
    facets: tuple = ()


_TRI_EDGES = ((0, 1, 3), (1, 2, 4), (2, 0, 5))
_QUAD_EDGES = ((0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7))
#: hex edges in VTK order; edge k of hex20 has the mid-node 8 + k
_HEX_EDGES = (
    (0, 1, 8), (1, 2, 9), (2, 3, 10), (3, 0, 11), (4, 5, 12), (5, 6, 13), (6, 7, 14), (7, 4, 15),
    (0, 4, 16), (1, 5, 17), (2, 6, 18), (3, 7, 19),
)
#: tet edges in VTK order; edge k of tet10 has the mid-node 4 + k
_TET_EDGES = ((0, 1, 4), (1, 2, 5), (2, 0, 6), (0, 3, 7), (1, 3, 8), (2, 3, 9))
#: hex faces (VTK order x-, x+, y-, y+, z-, z+), outward normals; corners then quad8 mid-edge nodes
_HEX_FACES = (
    (0, 4, 7, 3, 16, 15, 19, 11),
    (1, 2, 6, 5, 9, 18, 13, 17),
    (0, 1, 5, 4, 8, 17, 12, 16),
    (3, 7, 6, 2, 19, 14, 18, 10),
    (0, 3, 2, 1, 11, 10, 9, 8),
    (4, 5, 6, 7, 12, 13, 14, 15),
)
#: tet faces (VTK order), outward normals; corners then tri6 mid-edge nodes
_TET_FACES = ((0, 1, 3, 4, 8, 7), (1, 2, 3, 5, 9, 8), (2, 0, 3, 6, 7, 9), (0, 2, 1, 6, 5, 4))


def _facets(kind: str, lists, n: int) -> tuple:
    return tuple((kind, tuple(f[:n])) for f in lists)


ELEMENT_TYPES: dict[str, ElementType] = {
    "line2": ElementType("line2", "line", 1, 2, 1, "line", 2, ((0, 1),), 2, (("vertex", (0,)), ("vertex", (1,)))),
    "line3": ElementType(
        "line3", "line3", 1, 3, 2, "line", 2, ((0, 1, 2),), 3, (("vertex", (0,)), ("vertex", (1,)))
    ),
    "tri3": ElementType(
        "tri3", "triangle", 2, 3, 1, "tri", 3, ((0, 1), (1, 2), (2, 0)), 1, _facets("line2", _TRI_EDGES, 2)
    ),
    "tri6": ElementType("tri6", "triangle6", 2, 6, 2, "tri", 3, _TRI_EDGES, 3, _facets("line3", _TRI_EDGES, 3)),
    "quad4": ElementType(
        "quad4", "quad", 2, 4, 1, "quad", 4, ((0, 1), (1, 2), (2, 3), (3, 0)), 2, _facets("line2", _QUAD_EDGES, 2)
    ),
    "quad8": ElementType("quad8", "quad8", 2, 8, 2, "quad", 4, _QUAD_EDGES, 3, _facets("line3", _QUAD_EDGES, 3)),
    "quad9": ElementType("quad9", "quad9", 2, 9, 2, "quad", 4, _QUAD_EDGES, 3, _facets("line3", _QUAD_EDGES, 3)),
    "hex8": ElementType(
        "hex8", "hexahedron", 3, 8, 1, "hex", 8, tuple(e[:2] for e in _HEX_EDGES), 2, _facets("quad4", _HEX_FACES, 4)
    ),
    "hex20": ElementType("hex20", "hexahedron20", 3, 20, 2, "hex", 8, _HEX_EDGES, 3, _facets("quad8", _HEX_FACES, 8)),
    "tet4": ElementType(
        "tet4", "tetra", 3, 4, 1, "tet", 4, tuple(e[:2] for e in _TET_EDGES), 1, _facets("tri3", _TET_FACES, 3)
    ),
    "tet10": ElementType("tet10", "tetra10", 3, 10, 2, "tet", 4, _TET_EDGES, 4, _facets("tri6", _TET_FACES, 6)),
}
MESHIO_TO_TYPE = {t.meshio_name: t.name for t in ELEMENT_TYPES.values()}
CONTINUUM_TYPES_2D = ("tri3", "tri6", "quad4", "quad8", "quad9")
CONTINUUM_TYPES_3D = ("hex8", "hex20", "tet4", "tet10")

#: Permutation from the gmsh node order (as returned by the gmsh API, e.g.
#: ``gmsh.model.mesh.getElementsByType``) to ours (= meshio / VTK): ``ours = gmsh_nodes[..., perm]``.
#: Identity for all other types. Gmsh numbers the hex20 edges 0-1, 0-3, 0-4, 1-2, 1-5, 2-3, 2-6, 3-7,
#: 4-5, 4-7, 5-6, 6-7 and the tet10 edges 0-1, 1-2, 2-0, 3-0, 3-2, 3-1 (gmsh reference manual,
#: "Node ordering"); checked against the gmsh API in tests/elements/test_solid3d.py.
GMSH_TO_MESHIO_ORDER: dict[str, list[int]] = {
    "line2": [0, 1],
    "line3": [0, 1, 2],
    "tri3": [0, 1, 2],
    "tri6": [0, 1, 2, 3, 4, 5],
    "quad4": [0, 1, 2, 3],
    "quad8": [0, 1, 2, 3, 4, 5, 6, 7],
    "quad9": [0, 1, 2, 3, 4, 5, 6, 7, 8],
    "hex8": [0, 1, 2, 3, 4, 5, 6, 7],
    "hex20": [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15],
    "tet4": [0, 1, 2, 3],
    "tet10": [0, 1, 2, 3, 4, 5, 6, 7, 9, 8],
}

_QUAD_CORNERS = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=np.float64)
_HEX_CORNERS = np.array(
    [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]],
    dtype=np.float64,
)
_TET_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)


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


def _hex(points: np.ndarray, n_nodes: int):
    """hex8 (trilinear) or hex20 (serendipity), ZTZ 2013 ch. 6; derivatives by the product rule."""
    n = len(points)
    N = np.zeros((n, n_nodes))
    dN = np.zeros((n, 3, n_nodes))
    c = _HEX_CORNERS
    # linear factors f_i = 1 + xi_i xi_ai at every corner: (n, 8, 3)
    f = 1.0 + points[:, None, :] * c[None, :, :]
    if n_nodes == 8:
        N[:] = 0.125 * f.prod(axis=2)
        for i in range(3):
            j, k = [m for m in range(3) if m != i]
            dN[:, i, :] = 0.125 * c[None, :, i] * f[:, :, j] * f[:, :, k]
        return N, dN
    # corners: N = f0 f1 f2 (xi0 + eta0 + zeta0 - 2) / 8 with xi0 = xi xi_a, ...
    g = (points[:, None, :] * c[None, :, :]).sum(axis=2) - 2.0  # (n, 8)
    prod = f.prod(axis=2)
    N[:, :8] = 0.125 * prod * g
    for i in range(3):
        j, k = [m for m in range(3) if m != i]
        dN[:, i, :8] = 0.125 * c[None, :, i] * (f[:, :, j] * f[:, :, k] * g + prod)
    # mid-edge nodes: the coordinate along the edge is 0, the other two are +-1
    mids = reference_nodes("hex20")[8:]
    for m, xm in enumerate(mids):
        a = 8 + m
        i = int(np.flatnonzero(xm == 0)[0])  # direction along the edge
        j, k = [q for q in range(3) if q != i]
        bubble = 1.0 - points[:, i] ** 2
        fj = 1.0 + points[:, j] * xm[j]
        fk = 1.0 + points[:, k] * xm[k]
        N[:, a] = 0.25 * bubble * fj * fk
        dN[:, i, a] = -0.5 * points[:, i] * fj * fk
        dN[:, j, a] = 0.25 * bubble * xm[j] * fk
        dN[:, k, a] = 0.25 * bubble * fj * xm[k]
    return N, dN


# d L_a / d xi_i of the volume coordinates L = (1 - xi - eta - zeta, xi, eta, zeta): (3, 4)
_DL_TET = np.array([[-1.0, 1.0, 0.0, 0.0], [-1.0, 0.0, 1.0, 0.0], [-1.0, 0.0, 0.0, 1.0]])


def _tet(points: np.ndarray, n_nodes: int):
    """tet4 / tet10 in volume coordinates (ZTZ 2013 ch. 6; Hughes 2000 sec. 3.5)."""
    L = np.column_stack([1.0 - points.sum(axis=1), points])  # (n, 4)
    if n_nodes == 4:
        return L, np.broadcast_to(_DL_TET, (len(points), 3, 4)).copy()
    N = np.empty((len(points), 10))
    dN = np.empty((len(points), 3, 10))
    N[:, :4] = L * (2.0 * L - 1.0)
    dN[:, :, :4] = (4.0 * L - 1.0)[:, None, :] * _DL_TET[None]
    for k, (i, j, _) in enumerate(_TET_EDGES):
        N[:, 4 + k] = 4.0 * L[:, i] * L[:, j]
        dN[:, :, 4 + k] = 4.0 * (L[:, j, None] * _DL_TET[None, :, i] + L[:, i, None] * _DL_TET[None, :, j])
    return N, dN


def shape_functions(name: str, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape functions of element type ``name`` at natural ``points`` (n, dim_ref).

    Returns ``N`` (n, n_nodes) and ``dN`` (n, dim_ref, n_nodes), float64, C-contiguous.
    """
    et = ELEMENT_TYPES[name]
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    if points.shape[1] != et.dim:
        raise ValueError(f"{name}: points must have {et.dim} natural coordinates, got {points.shape[1]}")
    fn = {"line": _line, "tri": _tri, "quad": _quad, "hex": _hex, "tet": _tet}[et.family]
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
    if name == "hex8":
        return _HEX_CORNERS.copy()
    if name == "hex20":
        c = _HEX_CORNERS
        return np.vstack([c, [(c[i] + c[j]) / 2 for i, j, _ in _HEX_EDGES]])
    if name == "tet4":
        return _TET_CORNERS.copy()
    if name == "tet10":
        c = _TET_CORNERS
        return np.vstack([c, [(c[i] + c[j]) / 2 for i, j, _ in _TET_EDGES]])
    raise KeyError(name)


def integration_rule(name: str, n: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Integration rule for continuum element ``name``: ``n`` Gauss points per direction (line, quad,
    hex) or ``n`` points in total (triangles: 1, 3, 6; tetrahedra: 1, 4, 14); default: full
    integration (hex8 2x2x2, hex20 3x3x3, tet4 1 point, tet10 4 points).

    Returns ``points`` (n_points, dim_ref) and ``weights`` (n_points,) on the reference element
    (weights sum to 2, 4, 8 on [-1, 1]^d, 1/2 on the unit triangle, 1/6 on the unit tetrahedron).
    """
    et = ELEMENT_TYPES[name]
    n = et.default_gauss if n is None else n
    if et.family == "tri":
        return triangle_rule(n)
    if et.family == "tet":
        return tetrahedron_rule(n)
    return tensor_rule("gauss", n, et.dim)


def facet_area_normal(dN: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Unnormalised normal (..., dim) of facets (edges in 2D, faces in 3D) at points of their reference
    element, from the shape function derivatives ``dN`` (..., r, nfn) and the facet node coordinates
    ``X`` (..., nfn, dim) (broadcast as in ``dN @ X``). 2D: the tangent dX/dxi turned by -90 degrees
    (outward on a counter-clockwise boundary); 3D: dX/dxi x dX/deta (right-hand rule). Its length is
    the Jacobian of the facet (length or area per unit of reference measure): the one convention of
    the facet loads, the hydrostatic loads and the uplift."""
    t = dN @ X  # (..., r, dim) tangents
    if t.shape[-1] == 2:
        return np.stack([t[..., 0, 1], -t[..., 0, 0]], axis=-1)
    return np.cross(t[..., 0, :], t[..., 1, :])


def facet_outward_sign(facet_type: str, X: np.ndarray, inward_points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orientation of facets against the bodies that own them.

    X (n, nfn, dim) facet node coordinates; inward_points (n, dim) a point inside the owning body of each
    facet (e.g. its element's centroid). Returns ``(sign (n,), A (n, dim))``: ``A`` the
    :func:`facet_area_normal` at the centre of the reference facet and ``sign`` = +1 where it points
    away from the inward point (outward), -1 where it points in; ``sign * facet_area_normal`` is then
    outward everywhere on the facet, whatever the node order. The one orientation rule of the water
    loads, the added mass, the acoustic coupling and the absorbing boundaries."""
    centre = reference_nodes(facet_type).mean(axis=0, keepdims=True)
    if facet_type in ("tri3", "tri6"):
        centre = np.array([[1.0 / 3.0, 1.0 / 3.0]])
    Nc, dNc = shape_functions(facet_type, centre)
    xc = np.einsum("a,nad->nd", Nc[0], X)
    Ac = facet_area_normal(dNc[0], X)
    sign = np.where(np.einsum("nd,nd->n", np.asarray(inward_points) - xc, Ac) > 0.0, -1.0, 1.0)
    return sign, Ac


#: points of the symmetric triangle rule of total degree ``2 n - 2``, by ``n`` (:func:`facet_rule`)
_SYMMETRIC_TRIANGLE_POINTS = {1: 1, 2: 3, 3: 6}


def facet_rule(facet_type: str, points_per_direction: int,
               triangle: str = "collapsed") -> tuple[np.ndarray, np.ndarray]:
    """Gauss rule on the reference facet of ``facet_type`` (edges line2 / line3, faces tri3 / tri6 /
    quad4 / quad8 / quad9): the one facet rule of the facet loads, the absorbing boundaries, the
    hydrostatic loads and the added mass.

    With ``n = points_per_direction``:

    - lines: ``n``-point Gauss-Legendre on [-1, 1], exact to degree ``2 n - 1``;
    - quadrilaterals: ``n x n`` tensor Gauss on [-1, 1]^2, exact to degree ``2 n - 1`` in each variable;
    - triangles (unit triangle): ``triangle = "collapsed"``: the ``n x n`` collapsed Gauss rule
      (:func:`~masonrydam.elements.quadrature.collapsed_triangle_rule`); ``triangle = "symmetric"``: the
      symmetric rule with fewer points (``n`` = 1, 2, 3: 1, 3 and Dunavant's 6 points,
      :func:`~masonrydam.elements.quadrature.triangle_rule`); both exact to total degree ``2 n - 2``.

    Returns ``points`` (q, r) and ``weights`` (q,) summing to 2, 4 and 1/2 (Abramowitz & Stegun
    25.4.29 for Gauss-Legendre).
    """
    et = ELEMENT_TYPES.get(facet_type)
    if et is None or et.family not in ("line", "quad", "tri"):
        raise ValueError(f"{facet_type!r} is not a facet type (line2, line3, tri3, tri6, quad4, quad8, quad9)")
    n = int(points_per_direction)
    if et.family != "tri":
        return tensor_rule("gauss", n, et.dim)
    if triangle == "collapsed":
        return collapsed_triangle_rule(n)
    if triangle == "symmetric":
        if n not in _SYMMETRIC_TRIANGLE_POINTS:
            raise ValueError(f"no symmetric triangle rule of degree {2 * n - 2} (points_per_direction 1, 2 or 3)")
        return triangle_rule(_SYMMETRIC_TRIANGLE_POINTS[n])
    raise ValueError(f"triangle must be 'collapsed' or 'symmetric', got {triangle!r}")


@dataclass(frozen=True)
class FacetQuadrature:
    """Integration points on facets (edges in 2D, faces in 3D), from :func:`facet_quadrature`.

    The leading shape ``S`` of the arrays is ``(n, q)`` when one reference rule of ``q`` points is used
    on all ``n`` facets, ``(P,)`` when each of ``P`` points lies on its own facet (``owner``).

    shape_values: (q, nfn) or (P, nfn), the facet's shape functions ``N_a`` at the points;
    points: (S..., dim) m, the points ``x = N_a X_a``;
    area_normal: (S..., dim), the unnormalised normal of :func:`facet_area_normal` (2D: the tangent
        turned by -90 degrees, 3D: ``dX/dxi x dX/deta``), whose length is the Jacobian;
    jacobian: (S...), ``|area_normal|``: m per unit reference length (2D) or m2 per unit reference
        area (3D);
    weights: (q,) or (P,), the reference weights; ``jacobian * weights`` is the length (2D, per unit
        thickness) or area (3D) each point stands for.
    """

    shape_values: np.ndarray
    points: np.ndarray
    area_normal: np.ndarray
    jacobian: np.ndarray
    weights: np.ndarray


def facet_quadrature(facet_type: str, X: np.ndarray, points: np.ndarray, weights: np.ndarray,
                     owner: np.ndarray | None = None) -> FacetQuadrature:
    """Points, Jacobians and normals of facets at reference ``points`` (q, r) with ``weights`` (q,), e.g.
    from :func:`facet_rule`: the one facet quadrature of the facet loads, the absorbing boundaries, the
    hydrostatic loads, the added mass, the uplift and the acoustic reservoir's boundary.

    X: (n, nfn, dim) m, the node coordinates of every facet. Without ``owner`` the same points are used
    on every facet (arrays ``(n, q, ...)``); with ``owner`` (P,) int, point ``p`` lies on facet
    ``owner[p]`` (arrays ``(P, ...)``, e.g. the points of
    :func:`masonrydam.effects.reservoir.hydrostatics.region_points` on the wet part of each facet). See
    :class:`FacetQuadrature`.
    """
    N, dN = shape_functions(facet_type, points)
    if owner is None:
        x = np.einsum("qa,nad->nqd", N, X)
        A = facet_area_normal(dN[None], X[:, None])
    else:
        X = X[owner]
        x = np.einsum("pa,pad->pd", N, X)
        A = facet_area_normal(dN, X)
    return FacetQuadrature(N, x, A, np.linalg.norm(A, axis=-1), weights)
