"""The reservoir as acoustic (pressure) finite elements coupled to the wetted face of a dam: the mesh
of the water and the matrices of the coupled problem (a pure module: no scene, no solver; the time
integration assembles the coupled system from what :func:`acoustic_matrices` returns).

:func:`build_fluid_mesh` extrudes the wetted face upstream into quad4 (2D) / hex8 (3D) pressure elements
(:class:`FluidMesh`); :func:`acoustic_matrices` gives :class:`AcousticMatrices` on the free pressure
unknowns: ``G`` (s2/m2), ``H``, ``L`` (s/m) (n_free, n_free), the coupling ``Q`` (n_dof, n_free) and the
ground-motion load ``B`` (n_free, dim), for ``G p'' + L p' + H p = -rho (Q^T u''_rel + B a_g)``; SI units
(m, s, kg, Pa), pressure positive in compression, 2D matrices per the out-of-plane thickness. References:
Zienkiewicz & Bettess (1978), Chopra & Chakrabarti (1981), Fenves & Chopra (1984), Westergaard (1933).

Theory: docs/dam_reservoir_foundation.md, section "The acoustic reservoir".
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

from ...elements.quadrature import tensor_rule
from ...elements.shapes import (ELEMENT_TYPES, facet_area_normal, facet_outward_sign, facet_quadrature, facet_rule,
                               reference_nodes, shape_functions)
from ...mesh.facets import FACET_CORNERS, FACET_TYPES

__all__ = ["FluidMesh", "AcousticMatrices", "build_fluid_mesh", "acoustic_matrices", "reflection_damping"]

#: geometric growth of the layers of the extrusion away from the face
GROWTH_RATIO = 1.2
#: Gauss points per direction of the coupling integral on a wet piece (exact to degree 7)
_COUPLING_POINTS = 4
_MAX_LAYERS = 20000


# ---------------------------------------------------------------------------------------------
# data


@dataclass
class FluidMesh:
    """The water of the reservoir as a mesh of pressure elements.

    nodes : (n_f, dim) float, m. The first ``n_face`` nodes are the fluid nodes on the dam face (layer
        0); node ``k * n_face + i`` is face node ``i`` moved ``offsets[i, k]`` along ``upstream``.
    elements : (ne, 4) quad4 (2D) or (ne, 8) hex8 (3D) node indices (shapes-module order), positive
        Jacobian at every Gauss point; collapsed ones repeat a node (pair). Element ``k * n_pieces + j``
        is wet piece ``j`` extruded through layer ``k``.
    far_facets : (n_far, 2 | 4) line2 / quad4 facets of the upstream truncation plane, ordered so that
        :func:`facet_area_normal` points out of the water (upstream).
    bottom_facets : (n_bottom, 2 | 4) line2 / quad4 facets of the reservoir bottom and banks (the
        extrusion of the face's wetted boundary off the water line), normal out of the water.
    free_surface : (n_s,) int, the nodes at the water level (p = 0).
    piece_facet : (n_pieces,) int, the structural facet (row of ``facets``) of every wet piece.
    piece_nodes : (n_pieces, 2 | 4) int, the fluid face nodes of the piece (2D: a segment; 3D: a quad4,
        a collapsed one repeating its last node for a triangle), in the order of ``piece_ref``.
    piece_ref : (n_pieces, 2 | 4, r) float, the piece's corners in the structural facet's reference
        coordinates (r = 1 in 2D, 2 in 3D): the piece is ``xi(s) = sum_k N_k(s) piece_ref[k]`` with
        ``N_k`` the line2 / quad4 functions of its own coordinates ``s``, and the fluid pressure on it
        ``p(s) = sum_k N_k(s) p[piece_nodes[k]]``.
    face_structure_node : (n_face,) int, a structural node at each fluid face node (-1 for the points
        where the water line crosses a facet edge).
    offsets : (n_face, n_layers + 1) float, m, distance of each layer from the face node.
    facet_type, level (m), vertical_axis, upstream ((dim,) unit vector), length (m), element_size (m,
    the first layer), max_element_size (m).
    """

    nodes: np.ndarray
    elements: np.ndarray
    far_facets: np.ndarray
    bottom_facets: np.ndarray
    free_surface: np.ndarray
    piece_facet: np.ndarray
    piece_nodes: np.ndarray
    piece_ref: np.ndarray
    face_structure_node: np.ndarray
    offsets: np.ndarray
    facet_type: str
    level: float
    vertical_axis: int
    upstream: np.ndarray
    length: float
    element_size: float
    max_element_size: float

    @property
    def dim(self) -> int:
        return self.nodes.shape[1]

    @property
    def n_face(self) -> int:
        return len(self.face_structure_node)

    @property
    def n_layers(self) -> int:
        return self.offsets.shape[1] - 1

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)


# ---------------------------------------------------------------------------------------------
# input checks


def _positive(value, name, unit):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number ({unit}), got {value!r}") from None
    if not (np.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a positive number ({unit}), got {value!r}")
    return v


def _face_input(coords, facet_type, facets, inward_points, vertical_axis):
    coords = np.asarray(coords, dtype=np.float64)
    if coords.ndim != 2 or coords.shape[1] not in (2, 3):
        raise ValueError(f"coords must have shape (n_nodes, 2 or 3), got {coords.shape}")
    dim = coords.shape[1]
    allowed = FACET_TYPES[dim]
    if facet_type not in allowed:
        raise ValueError(f"facet_type {facet_type!r} is not a face type in {dim}D; use one of {allowed}")
    nfn = ELEMENT_TYPES[facet_type].n_nodes
    facets = np.asarray(facets, dtype=np.int64).reshape(-1, nfn)
    if len(facets) == 0:
        raise ValueError("facets: the wetted face has no facets")
    if facets.min() < 0 or facets.max() >= len(coords):
        raise ValueError("facets: node index out of range of coords")
    inward = np.asarray(inward_points, dtype=np.float64).reshape(len(facets), dim)
    axis = int(vertical_axis)
    if not 0 <= axis < dim:
        raise ValueError(f"vertical_axis must be in [0, {dim}), got {vertical_axis}")
    return coords, facets, inward, dim, axis


def reflection_damping(bottom_reflection, sound_speed) -> float:
    """Absorption coefficient ``q = (1 - alpha) / ((1 + alpha) c)`` (s/m) of a reservoir bottom with the
    wave reflection coefficient ``alpha`` in (-1, 1] (Fenves & Chopra 1984, eq. for the bottom boundary
    condition ``dp/dn = -rho a_n - q p_t``); 0 for incompressible water (``sound_speed=None``)."""
    try:
        alpha = float(bottom_reflection)
    except (TypeError, ValueError):
        raise ValueError(f"bottom_reflection must be a number in (-1, 1], got {bottom_reflection!r}") from None
    if not (-1.0 < alpha <= 1.0):
        raise ValueError(f"bottom_reflection must lie in (-1, 1] (wave reflection coefficient: 1 rigid bottom, "
                         f"0 fully absorbing), got {bottom_reflection!r}")
    if sound_speed is None:
        return 0.0
    c = _positive(sound_speed, "sound_speed", "m/s; None for incompressible water")
    return (1.0 - alpha) / ((1.0 + alpha) * c)


# ---------------------------------------------------------------------------------------------
# wet pieces of the face


class _FaceNodes:
    """Registry of the fluid face nodes: structural nodes and water-line crossings (by key)."""

    def __init__(self):
        self.struct = {}
        self.cross = {}
        self.pos = []
        self.snode = []

    def node(self, s, x):
        i = self.struct.get(s)
        if i is None:
            i = self.struct[s] = len(self.pos)
            self.pos.append(x)
            self.snode.append(s)
        return i

    def crossing(self, key, x):
        i = self.cross.get(key)
        if i is None:
            i = self.cross[key] = len(self.pos)
            self.pos.append(x)
            self.snode.append(-1)
        return i


def _pieces_2d(facet_type, coords, facets, level, axis, tol, reg):
    """Wet sub-intervals of every edge (line3: each half separately, the facet as a chain of two
    segments), cut at the exact roots of the elevation (linear / quadratic in xi)."""
    line3 = facet_type == "line3"
    fixed = [-1.0, 0.0, 1.0] if line3 else [-1.0, 1.0]
    local_at = {-1.0: 0, 1.0: 1, 0.0: 2}
    out_f, out_n, out_r = [], [], []
    for f, nodes in enumerate(facets):
        X = coords[nodes]
        d = level - X[:, axis]
        d[np.abs(d) <= tol] = 0.0
        if line3:  # d(xi) = c0 + c1 xi + c2 xi^2 through the node values
            c2, c1, c0 = 0.5 * (d[0] + d[1]) - d[2], 0.5 * (d[1] - d[0]), d[2]
        else:
            c2, c1, c0 = 0.0, 0.5 * (d[1] - d[0]), 0.5 * (d[0] + d[1])
        if np.all(d <= 0.0) and c2 >= 0.0:
            continue  # dry: all nodes at or above the level and the depth convex (its maximum at the ends)
        roots = np.roots([c2, c1, c0]) if (c2 or c1) else np.zeros(0)
        roots = roots.real[(np.abs(roots.imag) <= 1e-12) & (np.abs(roots.real) < 1.0)]
        br = list(fixed)
        for r in roots:
            if min(abs(r - b) for b in br) > 1e-10:
                br.append(float(r))
        br.sort()
        for a, b in zip(br[:-1], br[1:]):
            m = 0.5 * (a + b)
            if b - a <= 1e-12 or c0 + c1 * m + c2 * m * m <= 0.0:
                continue
            ids = []
            for t in (a, b):
                if t in local_at and (line3 or t != 0.0):
                    s = int(nodes[local_at[t]])
                    ids.append(reg.node(s, coords[s]))
                else:
                    N, _ = shape_functions(facet_type, np.array([[t]]))
                    x = N[0] @ X
                    x[axis] = level
                    ids.append(reg.crossing(("x", f, round(t, 12)), x))
            out_f.append(f)
            out_n.append(ids)
            out_r.append([[a], [b]])
    return out_f, out_n, out_r


def _pieces_3d(facet_type, coords, facets, level, axis, tol, reg):
    """Wet polygons of every face, clipped at the level along its corner edges (corner elevations
    interpolated linearly along each edge), cut into quads / collapsed quads (triangles)."""
    nc = FACET_CORNERS[facet_type]
    R = reference_nodes(facet_type)[:nc]
    corners = facets[:, :nc]
    d = level - coords[corners][:, :, axis]
    d[np.abs(d) <= tol] = 0.0
    any_under = (d > 0.0).any(axis=1)
    full = any_under & (d >= 0.0).all(axis=1)
    partial = any_under & ~full
    # entirely wet facets at once: the piece is the facet's corner polygon
    fw = np.flatnonzero(full)
    ids = np.array([reg.node(int(s), coords[s]) for s in np.unique(corners[fw])], dtype=np.int64)
    local = np.searchsorted(np.unique(corners[fw]), corners[fw])
    q = [0, 1, 2, 3] if nc == 4 else [0, 1, 2, 2]
    out_f, out_n, out_r = list(fw), list(ids[local][:, q]), list(np.broadcast_to(R[q], (len(fw), 4, 2)))
    for f in np.flatnonzero(partial):  # the row of facets along the water line
        nodes = corners[f]
        poly = []  # (fluid node, reference point)
        for i in range(nc):
            j = (i + 1) % nc
            if d[f, i] >= 0.0:
                s = int(nodes[i])
                poly.append((reg.node(s, coords[s]), R[i]))
            if d[f, i] * d[f, j] < 0.0:
                t = d[f, i] / (d[f, i] - d[f, j])
                a, b = (i, j) if nodes[i] < nodes[j] else (j, i)
                ta = d[f, a] / (d[f, a] - d[f, b])  # from the lower node number: the same on both facets
                x = coords[nodes[a]] + ta * (coords[nodes[b]] - coords[nodes[a]])
                x[axis] = level
                poly.append((reg.crossing(("e", int(nodes[a]), int(nodes[b])), x), R[i] + t * (R[j] - R[i])))
        k = len(poly)
        if k < 3:
            continue
        # fan from the first vertex into quads and a last collapsed quad (triangle) if k is odd
        cut = [(0, 1, 2, 3)] if k == 4 else [(0, 1, 2, 2)] if k == 3 else \
            [(0, 1, 2, 3), (0, 3, 4, 4)] if k == 5 else [(0, 1, 2, 3), (0, 3, 4, 5)]
        if k > 6:
            raise ValueError(f"facet {f}: the water line cuts it into a {k}-gon (a saddle-shaped facet); "
                             "refine the face near the level")
        for q in cut:
            out_f.append(int(f))
            out_n.append([poly[v][0] for v in q])
            out_r.append([poly[v][1] for v in q])
    return out_f, out_n, out_r


def _merge_coincident(P, tol):
    """Representative index of every point (coincident points, e.g. the two faces of a joint, merged)."""
    # scipy.spatial (0.1 s to import) only when an acoustic reservoir is built: keeps every run's start-up short
    from scipy.spatial import cKDTree

    rep = np.arange(len(P))
    pairs = cKDTree(P).query_pairs(tol, output_type="ndarray")
    if len(pairs):
        g = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(P), len(P)))
        _, lab = connected_components(g, directed=False)
        first = np.full(lab.max() + 1, len(P))
        np.minimum.at(first, lab, np.arange(len(P)))
        rep = first[lab]
    return rep


def _layer_offsets(length, h0, hmax):
    """Offsets 0 = t_0 < ... < t_n = length of the layers: sizes h0, h0 r, h0 r^2 ... (r = 1.2) capped at
    hmax, as many as needed to reach ``length``, then scaled down uniformly to end exactly at ``length``
    (so no layer is larger than asked and the growth ratio is kept)."""
    h0 = min(h0, hmax)
    sizes, total, h = [], 0.0, h0
    while total < length * (1.0 - 1e-9):
        sizes.append(h)
        total += h
        h = min(h * GROWTH_RATIO, hmax)
        if len(sizes) > _MAX_LAYERS:
            raise ValueError(f"element_size {h0:g} m and max_element_size {hmax:g} m need more than "
                             f"{_MAX_LAYERS} layers over the reservoir length {length:g} m")
    sizes = np.array(sizes) * (length / total)
    return np.concatenate([[0.0], np.cumsum(sizes)])


def build_fluid_mesh(coords, facet_type, facets, inward_points, *, level, vertical_axis, upstream, length,
                     element_size=None, max_element_size=None) -> FluidMesh:
    """Mesh of the reservoir: the wetted part of the dam face extruded along ``upstream``.

    Parameters
    ----------
    coords : (n_nodes, dim) float, m, the structure's nodes (dim 2 or 3).
    facet_type : the face's facet type: ``"line2"``, ``"line3"`` (2D) or ``"quad4"``, ``"quad8"``,
        ``"quad9"``, ``"tri3"``, ``"tri6"`` (3D), node order of :mod:`masonrydam.elements.shapes`.
    facets : (n, nfn) int, the facets of the dam's upstream face (only their part below ``level`` is wet).
    inward_points : (n, dim) float, m, a point inside the dam for each facet (its owner element's
        centroid): the dam's outward normal points away from it.
    level : m, elevation (coordinate ``vertical_axis``) of the water surface; above the face's lowest
        point and not above its highest.
    vertical_axis : int, index of the upward vertical coordinate.
    upstream : (dim,) horizontal vector pointing from the dam into the reservoir (normalised here).
    length : m, the reservoir's length from the most upstream wetted point of the face to the far
        (truncation) plane; the caller's default is 3 times the depth.
    element_size : m, the size along ``upstream`` of the first layer of fluid elements (default: the
        median size of the wetted facets: length of an edge in 2D, square root of the area in 3D).
    max_element_size : m, the largest layer (default ``element_size``: uniform layers); the layers grow
        by the factor 1.2 from ``element_size`` up to it. If smaller than ``element_size`` it is used
        for all layers. A good value is ``c / (10 f_max)`` (ten elements per wave length).
        The layers are laid out along the longest line (from the most downstream wet face node to the
        far plane) and scaled down to fill it exactly; the lines of the other face nodes have the same
        layers scaled by their length over the longest: every layer is at most the size asked for
        (on an inclined face the first layer at the most upstream node is ``element_size`` times
        ``length / longest line``).

    Returns
    -------
    :class:`FluidMesh`. Raises ``ValueError`` (naming the parameter) for bad input, and for a face that
    does not look upstream everywhere (a facet whose outward normal has no positive component along
    ``upstream``).
    """
    coords, facets, inward, dim, axis = _face_input(coords, facet_type, facets, inward_points, vertical_axis)
    u = np.asarray(upstream, dtype=np.float64).reshape(-1)
    if u.shape != (dim,) or not np.all(np.isfinite(u)) or np.linalg.norm(u) == 0.0:
        raise ValueError(f"upstream must be a non-zero vector of {dim} components, got {upstream!r}")
    u = u / np.linalg.norm(u)
    if abs(u[axis]) > 1e-9:
        raise ValueError(f"upstream must be horizontal (no component along vertical_axis {axis}), got {upstream!r}")
    try:
        level = float(level)
    except (TypeError, ValueError):
        raise ValueError(f"level must be a number (m), got {level!r}") from None
    if not np.isfinite(level):
        raise ValueError(f"level must be finite, got {level!r}")
    length = _positive(length, "length", "m, reservoir length upstream of the face")

    used = np.unique(facets)
    z = coords[used, axis]
    extent = float(np.ptp(coords[used], axis=0).max())
    tol = 1e-9 * max(extent, abs(level), 1.0)
    zmin, zmax = float(z.min()), float(z.max())
    if level <= zmin + tol:
        raise ValueError(f"level {level:g} m is not above the lowest point of the face ({zmin:g} m on axis "
                         f"{axis}): no water touches it")
    if level > zmax + tol:
        raise ValueError(f"level {level:g} m is above the highest point of the face ({zmax:g} m): an overtopped "
                         "face is not modelled")

    reg = _FaceNodes()
    pieces = (_pieces_2d if dim == 2 else _pieces_3d)(facet_type, coords, facets, level, axis, tol, reg)
    piece_facet = np.asarray(pieces[0], dtype=np.int64)
    piece_nodes = np.asarray(pieces[1], dtype=np.int64)
    piece_ref = np.asarray(pieces[2], dtype=np.float64)
    if len(piece_facet) == 0:
        raise ValueError(f"level {level:g} m wets no facet of the face")

    # the face must look upstream: dam outward normal . upstream > 0 on every wetted facet
    wet = np.unique(piece_facet)
    sign, Ac = facet_outward_sign(facet_type, coords[facets[wet]], inward[wet])
    cosine = sign * (Ac @ u) / np.linalg.norm(Ac, axis=1)
    if (cosine <= 1e-6).any():
        bad = wet[cosine <= 1e-6]
        raise ValueError(f"facets {bad[:10].tolist()} of the wetted face do not look upstream (their outward normal "
                         f"has no positive component along upstream={upstream!r}): the reservoir mesh extrudes the "
                         "face along upstream, so the face must be seen entirely from upstream (no overhang, no "
                         "horizontal step); check upstream and inward_points")

    # fluid face nodes, coincident ones merged
    P = np.asarray(reg.pos, dtype=np.float64)
    snode = np.asarray(reg.snode, dtype=np.int64)
    rep = _merge_coincident(P, 1e-8 * max(extent, 1.0))
    keep = np.unique(rep)
    new = np.full(len(P), -1, dtype=np.int64)
    new[keep] = np.arange(len(keep))
    remap = new[rep]
    P, face_snode = P[keep], snode[keep]
    piece_nodes = remap[piece_nodes]
    n_face = len(P)

    # layers
    if element_size is None:
        Xw = coords[facets[wet][:, :FACET_CORNERS[facet_type]]]
        if dim == 2:
            sizes = np.linalg.norm(Xw[:, 1] - Xw[:, 0], axis=1)
        elif facet_type.startswith("quad"):
            sizes = np.sqrt(0.5 * np.linalg.norm(np.cross(Xw[:, 2] - Xw[:, 0], Xw[:, 3] - Xw[:, 1]), axis=1))
        else:
            sizes = np.sqrt(0.5 * np.linalg.norm(np.cross(Xw[:, 1] - Xw[:, 0], Xw[:, 2] - Xw[:, 0]), axis=1))
        h0 = float(np.median(sizes))
    else:
        h0 = _positive(element_size, "element_size", "m")
    hmax = h0 if max_element_size is None else _positive(max_element_size, "max_element_size", "m")
    s = P @ u
    D = s.max() + length - s  # distance of each face node to the far plane, >= length
    # layers graded along the longest node line (the most downstream face node); the other lines are
    # the same layers scaled by D / D.max() <= 1: no layer anywhere larger than asked, ratio kept
    t_ref = _layer_offsets(D.max(), h0, hmax)
    offsets = t_ref[None, :] * (D / D.max())[:, None]
    n_layers = len(t_ref) - 1
    nodes = (P[None, :, :] + offsets.T[:, :, None] * u).reshape(-1, dim)

    # elements: orient each piece's fluid face so that the extrusion has a positive Jacobian
    n_pieces = len(piece_facet)
    Pf = P[piece_nodes]
    if dim == 2:
        e = Pf[:, 1] - Pf[:, 0]
        cr = e[:, 0] * u[1] - e[:, 1] * u[0]
        face_el = np.where((cr < 0.0)[:, None], piece_nodes[:, ::-1], piece_nodes)
        layer = np.arange(n_layers)[:, None, None] * n_face
        elements = np.concatenate([face_el[None] + layer, face_el[None, :, ::-1] + layer + n_face], axis=2)
    else:
        Nc, dNc = shape_functions("quad4", np.zeros((1, 2)))
        t = dNc[0] @ Pf  # (np, 2, 3)
        cr = np.cross(t[:, 0], t[:, 1]) @ u
        face_el = np.where((cr < 0.0)[:, None], piece_nodes[:, [0, 3, 2, 1]], piece_nodes)
        layer = np.arange(n_layers)[:, None, None] * n_face
        elements = np.concatenate([face_el[None] + layer, face_el[None] + layer + n_face], axis=2)
    elements = elements.reshape(-1, elements.shape[-1])

    # free surface
    on = np.abs(P[:, axis] - level) <= tol
    free_surface = (np.flatnonzero(on)[None, :] + n_face * np.arange(n_layers + 1)[:, None]).ravel()
    free_surface.sort()

    # far boundary: the last layer's faces; bottom and banks: the extruded boundary of the wet face
    if dim == 2:
        far = face_el[:, ::-1] + n_layers * n_face
        ends = piece_nodes.ravel()
        cnt = np.bincount(ends, minlength=n_face)
        owner_of = np.zeros(n_face, dtype=np.int64)
        owner_of[ends] = np.repeat(np.arange(n_pieces), 2)
        bnodes = np.flatnonzero((cnt == 1) & ~on)
        k = np.arange(n_layers)
        bottom = np.stack([bnodes[None, :] + n_face * k[:, None], bnodes[None, :] + n_face * (k[:, None] + 1)],
                          axis=2).reshape(-1, 2)
        bowner = (owner_of[bnodes][None, :] + n_pieces * k[:, None]).ravel()
    else:
        far = face_el + n_layers * n_face
        ed = np.stack([piece_nodes, np.roll(piece_nodes, -1, axis=1)], axis=2).reshape(-1, 2)
        eown = np.repeat(np.arange(n_pieces), 4)
        ok = ed[:, 0] != ed[:, 1]
        ed, eown = ed[ok], eown[ok]
        key = np.sort(ed, axis=1)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        bnd = (cnt[inv.ravel()] == 1) & ~(on[ed[:, 0]] & on[ed[:, 1]])
        ed, eown = ed[bnd], eown[bnd]
        k = np.arange(n_layers)[:, None]
        a, b = ed[None, :, 0] + n_face * k, ed[None, :, 1] + n_face * k
        bottom = np.stack([a, b, b + n_face, a + n_face], axis=2).reshape(-1, 4)
        bowner = (eown[None, :] + n_pieces * k).ravel()
    far_owner = np.arange(n_pieces) + n_pieces * (n_layers - 1)
    far = _orient_outward(nodes, far, elements[far_owner])
    bottom = _orient_outward(nodes, bottom, elements[bowner]) if len(bottom) else bottom.reshape(0, 2 * (dim - 1))

    _jacobians(nodes, elements)
    return FluidMesh(nodes=nodes, elements=elements, far_facets=far, bottom_facets=bottom,
                     free_surface=free_surface, piece_facet=piece_facet, piece_nodes=piece_nodes,
                     piece_ref=piece_ref, face_structure_node=face_snode, offsets=offsets, facet_type=facet_type,
                     level=level, vertical_axis=axis, upstream=u, length=length, element_size=min(h0, hmax),
                     max_element_size=hmax)


def _orient_outward(nodes, bf, owner_elements):
    """Reverse the boundary facets ``bf`` (line2 / quad4) whose facet_area_normal points into their
    owner element (centroid test)."""
    ftype = "line2" if bf.shape[1] == 2 else "quad4"
    centre = np.zeros((1, 1)) if ftype == "line2" else np.zeros((1, 2))
    Nc, dNc = shape_functions(ftype, centre)
    X = nodes[bf]
    A = facet_area_normal(dNc[0], X)
    xc = np.einsum("a,nad->nd", Nc[0], X)
    inside = nodes[owner_elements].mean(axis=1)
    flip = np.einsum("nd,nd->n", xc - inside, A) < 0.0
    out = bf.copy()
    out[flip] = bf[flip][:, ::-1] if ftype == "line2" else bf[flip][:, [0, 3, 2, 1]]
    return out


# ---------------------------------------------------------------------------------------------
# matrices


def _jacobians(nodes, elements):
    """Gauss rule (2 per direction), shape functions and Jacobians ``J[e, q, r, d] = dx_d / dxi_r`` of the
    quad4 / hex8 elements with their determinants; a ValueError if any is not positive."""
    dim = nodes.shape[1]
    pts, w = tensor_rule("gauss", 2, dim)
    N, dN = shape_functions("quad4" if dim == 2 else "hex8", pts)
    J = np.einsum("qrn,end->eqrd", dN, nodes[elements])
    det = np.linalg.det(J)
    if not (det > 0.0).all():
        bad = np.unique(np.nonzero(~(det > 0.0))[0])
        raise ValueError(f"fluid elements {bad[:10].tolist()} have a non-positive Jacobian: the face folds over "
                         "itself seen from upstream")
    return w, N, dN, J, det


def _element_matrices(nodes, elements):
    """Consistent 'mass' int N^T N dV and 'stiffness' int grad N^T grad N dV of quad4 / hex8 elements
    (2 Gauss points per direction): (ne, nen, nen) each."""
    w, N, dN, J, det = _jacobians(nodes, elements)
    grad = np.linalg.solve(J, np.broadcast_to(dN, J.shape[:2] + dN.shape[1:]))  # (e, q, dim, nen)
    wd = w[None, :] * det
    M = np.einsum("eq,qa,qb->eab", wd, N, N)
    K = np.einsum("eq,eqda,eqdb->eab", wd, grad, grad)
    return M, K


def _boundary_mass(nodes, bf):
    """int N^T N dS (nb, nfn, nfn) and int N n dS (nb, nfn, dim) of line2 / quad4 boundary facets
    (n = facet_area_normal direction; 2 Gauss points per direction: exact on parallelograms)."""
    ftype = "line2" if bf.shape[1] == 2 else "quad4"
    pts, w = facet_rule(ftype, 2)
    fq = facet_quadrature(ftype, nodes[bf], pts, w)
    N, A, dA = fq.shape_values, fq.area_normal, fq.jacobian  # (q, nfn), (nb, q, dim), (nb, q)
    M = np.einsum("q,nq,qa,qb->nab", w, dA, N, N)
    Nn = np.einsum("q,qa,nqd->nad", w, N, A)
    return M, Nn


def _assemble(conn, mats, n):
    r = np.broadcast_to(conn[:, :, None], mats.shape).ravel()
    c = np.broadcast_to(conn[:, None, :], mats.shape).ravel()
    return sp.csr_matrix((mats.ravel(), (r, c)), shape=(n, n))


def _piece_points(mesh):
    """Gauss points of the coupling integral on every wet piece: piece-coordinate functions N_k (q, nk),
    weights (q,), facet reference points xi (np, q, r), Jacobian of the piece map (np, q)."""
    r = mesh.piece_ref.shape[2]
    ptype = "line2" if r == 1 else "quad4"
    pts, w = tensor_rule("gauss", _COUPLING_POINTS, r)
    Np, dNp = shape_functions(ptype, pts)
    xi = np.einsum("qk,pkr->pqr", Np, mesh.piece_ref)
    dxi = np.einsum("qsk,pkr->pqsr", dNp, mesh.piece_ref)
    j = np.linalg.det(dxi)
    return Np, w, xi, j


class AcousticMatrices:
    """Matrices of the acoustic reservoir on the free pressure unknowns (see the module docstring).

    Attributes
    ----------
    mesh : the :class:`FluidMesh`.
    free_nodes : (n_free,) int, the fluid node of every pressure unknown (all but the free surface).
    G : (n_free, n_free) CSR, ``(1/c^2) int N^T N dV`` (zero for incompressible water).
    H : (n_free, n_free) CSR, ``int grad N^T grad N dV`` (symmetric positive definite).
    L : (n_free, n_free) CSR, ``L_far + L_bottom`` (zero for incompressible water).
    L_far, L_bottom : the two parts of ``L``.
    Q : (n_dof, n_free) CSR, ``int_face N_u^T n_f N_p dS``; the water's force on the dam is ``Q @ p``.
    Q_all : (n_dof, n_f) CSR, the same on every fluid node (free surface included): its column sums
        over the DOFs of component ``c`` add up to ``int_face n_f . e_c dS`` (the functions ``N_p`` of all
        nodes sum to 1).
    B : (n_free, dim) float, the ground-motion load: the right-hand side is ``-density * B @ a_g``.
    density (kg/m3), sound_speed (m/s, None: incompressible), q_bottom (s/m), thickness (m; 1 in 3D).
    face_nodes : (n_fn,) int, the structural nodes of the face (every node of ``facets``), for
        :meth:`face_pressure`.

    In 2D all matrices are per the ``thickness`` (multiplied by it).
    """

    def __init__(self, mesh, coords, facet_type, facets, inward_points, *, density, sound_speed,
                 bottom_reflection=1.0, thickness=1.0, vertical_axis=None):
        axis = mesh.vertical_axis if vertical_axis is None else vertical_axis
        coords, facets, inward, dim, axis = _face_input(coords, facet_type, facets, inward_points, axis)
        if facet_type != mesh.facet_type or dim != mesh.dim or axis != mesh.vertical_axis or \
                mesh.piece_facet.max() >= len(facets):
            raise ValueError("the fluid mesh was built for another face (facet type, dimension, vertical axis "
                             "or facets differ)")
        self.mesh = mesh
        self.density = _positive(density, "density", "kg/m3")
        self.q_bottom = reflection_damping(bottom_reflection, sound_speed)
        self.sound_speed = None if sound_speed is None else _positive(sound_speed, "sound_speed", "m/s")
        self.bottom_reflection = float(bottom_reflection)
        self.thickness = _positive(thickness, "thickness", "m") if dim == 2 else 1.0
        th = self.thickness
        nf = mesh.n_nodes
        n_dof = coords.shape[0] * dim

        fixed = np.zeros(nf, dtype=bool)
        fixed[mesh.free_surface] = True
        self.free_nodes = np.flatnonzero(~fixed)
        self.n_free = len(self.free_nodes)
        sel = self.free_nodes

        Me, Ke = _element_matrices(mesh.nodes, mesh.elements)
        self.H = (th * _assemble(mesh.elements, Ke, nf))[sel][:, sel].tocsr()
        zero = sp.csr_matrix((self.n_free, self.n_free))
        Mf, _ = _boundary_mass(mesh.nodes, mesh.far_facets)
        bf = mesh.bottom_facets
        if len(bf):
            Mb, Nnb = _boundary_mass(mesh.nodes, bf)
        else:
            Mb, Nnb = np.zeros((0, bf.shape[1], bf.shape[1])), np.zeros((0, bf.shape[1], dim))
        if self.sound_speed is None:
            self.G, self.L_far, self.L_bottom = zero, zero.copy(), zero.copy()
        else:
            c = self.sound_speed
            self.G = (th / c**2 * _assemble(mesh.elements, Me, nf))[sel][:, sel].tocsr()
            self.L_far = (th / c * _assemble(mesh.far_facets, Mf, nf))[sel][:, sel].tocsr()
            self.L_bottom = (th * self.q_bottom * _assemble(bf, Mb, nf))[sel][:, sel].tocsr() if len(bf) else zero
        self.L = (self.L_far + self.L_bottom).tocsr()

        # coupling
        Np, w, xi, j = _piece_points(mesh)
        npc, nq, r = xi.shape
        F = facets[mesh.piece_facet]
        X = coords[F]
        sign, _ = facet_outward_sign(facet_type, X, inward[mesh.piece_facet])
        Nu, dNu = shape_functions(facet_type, xi.reshape(-1, r))
        Nu = Nu.reshape(npc, nq, -1)
        dNu = dNu.reshape(npc, nq, r, -1)
        nfl = -sign[:, None, None] * facet_area_normal(dNu, X[:, None])  # fluid outward normal * dS/dxi
        Qe = th * np.einsum("q,pq,pqa,pqc,qk->pack", w, j, Nu, nfl, Np)  # (np, nfn, dim, nk)
        rows = np.broadcast_to((F[:, :, None] * dim + np.arange(dim))[..., None], Qe.shape)
        cols = np.broadcast_to(mesh.piece_nodes[:, None, None, :], Qe.shape)
        Qfull = sp.csr_matrix((Qe.ravel(), (rows.ravel(), cols.ravel())), shape=(n_dof, nf))
        self.Q_all = Qfull
        self.Q = Qfull[:, sel].tocsr()
        iota = np.zeros((n_dof, dim))
        for cmp in range(dim):
            iota[cmp::dim, cmp] = 1.0
        Bfull = Qfull.T @ iota
        #: the part of B from the face translating with the ground (``Q^T iota``) and the rest, the
        #: reservoir bottom and banks (they move with the ground surface, which a foundation of mass
        #: separates from the frame of the dam's displacements)
        self.B_face = np.ascontiguousarray(Bfull[sel])
        if len(bf):
            Bfull += th * np.stack([np.bincount(bf.ravel(), weights=Nnb[:, :, cmp].ravel(), minlength=nf)
                                    for cmp in range(dim)], axis=1)
        self.B = np.ascontiguousarray(Bfull[sel])
        self.B_bottom = self.B - self.B_face
        self._H_factor = None

        self.face_nodes = np.unique(facets)
        self._face_interp = _face_interpolation(mesh, coords, facet_type, facets, self.face_nodes, sel)

    # -- helpers for the caller -----------------------------------------------------------------

    def full_pressure(self, p) -> np.ndarray:
        """Pressure (Pa) at every fluid node, (n_f,) or (n_f, k) for p (n_free,) / (n_free, k): zero at
        the free surface."""
        p = np.asarray(p)
        out = np.zeros((self.mesh.n_nodes,) + p.shape[1:], dtype=p.dtype)
        out[self.free_nodes] = p
        return out

    def face_pressure(self, p) -> np.ndarray:
        """Pressure (Pa) at the structural face nodes ``face_nodes`` from the unknowns ``p`` (n_free,)
        or (n_free, k): the fluid field interpolated at each node (0 above the water)."""
        return self._face_interp @ np.asarray(p)

    def face_force(self, p) -> np.ndarray:
        """The water's nodal forces on the dam, N: ``Q @ p``, (n_dof,)."""
        return self.Q @ np.asarray(p)

    def added_mass(self):
        """Incompressible added mass ``rho Q H^-1 Q^T`` (n_dof, n_dof) CSR, kg, non-zero on the face DOFs
        only (Zienkiewicz & Bettess 1978; with a rigid vertical face it is Westergaard's exact series).
        Only meaningful as the whole water effect for incompressible water (it ignores G and L). It acts on
        the face's total acceleration; the push of the bottom and banks moving with the ground (vertical
        or cross-valley ground motion) comes on top, as the force ``-rho Q H^-1 (B - Q^T iota) a_g``.
        Dense over the face DOFs (n_face_dof^2 numbers: fine in 2D, large for fine 3D faces)."""
        rows = np.flatnonzero(np.diff(self.Q.indptr))
        Qr = self.Q[rows]
        X = self.solve_H(Qr.T.toarray())
        Ma = self.density * (Qr @ X)
        Ma = 0.5 * (Ma + Ma.T)
        out = sp.coo_matrix(Ma)
        return sp.csr_matrix((out.data, (rows[out.row], rows[out.col])), shape=(self.Q.shape[0],) * 2)

    def solve_H(self, rhs) -> np.ndarray:
        """``H^-1 rhs`` (n_free,) or (n_free, k), with one sparse LU of ``H`` kept for later calls."""
        if self._H_factor is None:
            self._H_factor = spla.splu(self.H.tocsc())
        return self._H_factor.solve(np.asarray(rhs, dtype=np.float64))

    def bottom_influence(self) -> np.ndarray | None:
        """Incompressible water: the force on the dam per unit acceleration of the reservoir bottom and
        banks, ``rho Q H^-1 B_bottom`` as (dim, n_dof) kg (the load is ``-bottom_influence . a_bottom``),
        or None where the bottom cannot push the water (a flat bottom under horizontal motion only has a
        zero column, all zero: None)."""
        if not np.abs(self.B_bottom).max(initial=0.0) > 0.0:
            return None
        return self.density * np.asarray(self.Q @ self.solve_H(self.B_bottom)).T


def acoustic_matrices(fluid_mesh, coords, facet_type, facets, inward_points, *, density, sound_speed,
                      bottom_reflection=1.0, thickness=1.0, vertical_axis=None) -> AcousticMatrices:
    """Matrices of the acoustic reservoir of ``fluid_mesh`` coupled to the face it was built on.

    Parameters
    ----------
    fluid_mesh : :class:`FluidMesh` from :func:`build_fluid_mesh` with the same face.
    coords, facet_type, facets, inward_points : the structure's nodes and the face, as given to
        :func:`build_fluid_mesh`.
    density : kg/m3, water density ``rho``.
    sound_speed : m/s, speed of sound ``c`` in the water, or None for incompressible water (``G = L = 0``).
    bottom_reflection : wave reflection coefficient ``alpha`` of the bottom and banks, -1 < alpha <= 1
        (1: rigid, 0: fully absorbing; Fenves & Chopra 1984 use 0.5 to 0.95 for real reservoirs).
    thickness : m, out-of-plane thickness of a 2D model (every matrix is multiplied by it; ignored in 3D).
    vertical_axis : must match the mesh's (default: the mesh's).

    Returns
    -------
    :class:`AcousticMatrices` with ``G, H, L, Q, B, free_nodes`` and :meth:`~AcousticMatrices.face_pressure`.
    """
    return AcousticMatrices(fluid_mesh, coords, facet_type, facets, inward_points, density=density,
                            sound_speed=sound_speed, bottom_reflection=bottom_reflection, thickness=thickness,
                            vertical_axis=vertical_axis)


def _face_interpolation(mesh, coords, facet_type, facets, face_nodes, sel):
    """Sparse (len(face_nodes), n_free) interpolation of the fluid pressure at the structural face nodes:
    a node that is a fluid face node takes its value; another wet node (a mid-node of a quadratic 3D
    facet) is located in a wet piece of one of its facets (inverse of the piece map, Newton; the nearest
    piece, clamped, if none contains it) and interpolated there; dry nodes and nodes on the water line
    get 0."""
    nf = mesh.n_nodes
    axis, level = mesh.vertical_axis, mesh.level
    row_of = np.full(len(coords), -1, dtype=np.int64)
    row_of[face_nodes] = np.arange(len(face_nodes))
    tol = 1e-9 * max(float(np.ptp(coords[face_nodes], axis=0).max()), abs(level), 1.0)
    fs = mesh.face_structure_node
    direct = np.flatnonzero(fs >= 0)
    rows, cols, vals = [row_of[fs[direct]]], [direct], [np.ones(len(direct))]
    done = np.zeros(len(coords), dtype=bool)
    done[fs[direct]] = True
    # remaining wet nodes: locate them in the pieces of the first wet facet that holds them
    wet_facets = np.unique(mesh.piece_facet)
    flat = facets[wet_facets].ravel()
    want = ~done[flat] & (level - coords[flat, axis] > tol)
    if want.any():
        nodes_needed, first = np.unique(flat[want], return_index=True)
        k = np.flatnonzero(want)[first]
        f_of, a_of = wet_facets[k // facets.shape[1]], k % facets.shape[1]
        order = np.argsort(mesh.piece_facet, kind="stable")
        lo = np.searchsorted(mesh.piece_facet[order], f_of)
        hi = np.searchsorted(mesh.piece_facet[order], f_of, side="right")
        cnt = hi - lo
        item_node = np.repeat(np.arange(len(nodes_needed)), cnt)
        pc = order[np.concatenate([np.arange(a, b) for a, b in zip(lo, hi)])]
        target = reference_nodes(facet_type)[np.repeat(a_of, cnt)]
        R = mesh.piece_ref[pc]
        r = R.shape[2]
        ptype = "line2" if r == 1 else "quad4"
        sv = np.zeros((len(pc), r))
        for _ in range(30):  # Newton on the linear / bilinear piece map
            N, dN = shape_functions(ptype, sv)
            res = np.einsum("ik,ikr->ir", N, R) - target
            J = np.einsum("isk,ikr->irs", dN, R)
            ok = np.abs(np.linalg.det(J)) > 1e-14
            step = np.zeros_like(sv)
            step[ok] = np.linalg.solve(J[ok], res[ok][..., None])[..., 0]
            sv = np.clip(sv - step, -1.5, 1.5)
        viol = np.clip(np.abs(sv) - 1.0, 0.0, None).max(axis=1)
        pick = np.lexsort((viol, item_node))  # by node, least violation first
        best = pick[np.r_[True, item_node[pick][1:] != item_node[pick][:-1]]]
        N, _ = shape_functions(ptype, np.clip(sv[best], -1.0, 1.0))
        rows.append(np.repeat(row_of[nodes_needed[item_node[best]]], N.shape[1]))
        cols.append(mesh.piece_nodes[pc[best]].ravel())
        vals.append(N.ravel())
    A = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(len(face_nodes), nf))
    A.sum_duplicates()
    return A[:, sel].tocsr()
