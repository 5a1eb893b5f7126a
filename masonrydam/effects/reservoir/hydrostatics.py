"""Consistent nodal forces of hydrostatic water pressure and of a geostatic silt load on boundary
facets (edges in 2D, faces in 3D), integrated over the wetted part of every facet.

:func:`facet_pressure_forces` takes the node coordinates (n_nodes, dim) m, the facets (n, nfn) of one facet
type with a point inside the owner of each (n, dim) m, the surface level (m), the unit weight (N/m3) and, for
silt, the lateral coefficient ``K``, and returns the nodal forces (n_nodes * dim,) N, DOF index
``node * dim + component`` (2D: times the thickness).
:func:`region_points` gives the quadrature points of the part of each facet below a threshold (also used by
the added mass and the uplift). Exact Gauss and collapsed (Duffy) rules on the wet part; warped and curved
faces subdivided with Bernstein bounds. References: White (2011), USACE EM 1110-2-2200 (1995), Farin (2002),
Stroud (1971), Karniadakis & Sherwin (2005).

Theory: docs/water.md, section "Hydrostatic and silt loads on facets".
"""
from __future__ import annotations

from math import comb

import numpy as np

from ...elements.quadrature import collapsed_triangle_rule
from ...elements.shapes import (ELEMENT_TYPES, facet_outward_sign, facet_quadrature, facet_rule, reference_nodes,
                                shape_functions)
from ...mesh.facets import FACET_TYPES

__all__ = ["facet_pressure_forces", "region_points"]

#: polynomial degree of x_v per reference variable (lines, quads) or in total (triangles) on the facet
_GEOM_DEGREE = {"line2": 1, "line3": 2, "tri3": 1, "tri6": 2, "quad4": 1, "quad8": 2, "quad9": 2}
#: total degree of x_v restricted to a (sub-)triangle of the reference facet
_SUBTRI_DEGREE = {"tri3": 1, "tri6": 2, "quad4": 2, "quad8": 3, "quad9": 4}
#: total degree of N_a * d * A on a (sub-)triangle of the reference facet (3D), with d of full degree
_INTEGRAND_TOTAL_DEGREE = {"tri3": 2, "tri6": 6, "quad4": 6, "quad8": 10, "quad9": 14}
#: Gauss points: per direction for lines and quads (full facets, degree 2 / 5 lines, 3 / 7 per variable
#: quads), or the collapsed-rule order n (exact to total degree 2 n - 2) for triangle facets
_FULL_RULE_POINTS = {"line2": 2, "line3": 3, "tri3": 2, "tri6": 4, "quad4": 2, "quad8": 4, "quad9": 4}

#: corners of the reference quadrilateral and triangle
_QUAD_CORNERS = reference_nodes("quad4")
_TRI_CORNERS = reference_nodes("tri3")


def _duffy_points_for_degree(p: int) -> int:
    """Order n of the collapsed rule exact for total degree p: 2 n - 2 >= p."""
    return (p + 3) // 2


def _full_rule(facet_type: str) -> tuple[np.ndarray, np.ndarray]:
    """The rule of an entirely wet facet (and of each wet sub-interval of an edge)."""
    return facet_rule(facet_type, _FULL_RULE_POINTS[facet_type])


# ---------------------------------------------------------------------------------------------
# Bernstein forms (bounds of x_v on a facet or on a sub-triangle)


def _bernstein_1d(t: np.ndarray, p: int) -> np.ndarray:
    """Bernstein polynomials of degree p on [0, 1] at t: (len(t), p + 1)."""
    k = np.arange(p + 1)
    c = np.array([comb(p, i) for i in k], dtype=np.float64)
    return c * t[:, None] ** k * (1.0 - t[:, None]) ** (p - k)


def _triangle_lattice(p: int) -> np.ndarray:
    """Barycentric coordinates (L0, L1, L2) of the degree-p lattice: ((p+1)(p+2)/2, 3); vertices first."""
    idx = [(p, 0, 0), (0, p, 0), (0, 0, p)]
    idx += [(i, j, p - i - j) for i in range(p + 1) for j in range(p + 1 - i) if (i, j, p - i - j) not in idx]
    return np.array(idx, dtype=np.float64) / p


def _bernstein_triangle(L: np.ndarray, p: int) -> np.ndarray:
    """Bernstein polynomials of degree p on a triangle at barycentric points L (m, 3): (m, nb),
    in the order of :func:`_triangle_lattice`."""
    ijk = np.rint(_triangle_lattice(p) * p).astype(int)
    c = np.array([comb(p, i) * comb(p - i, j) for i, j, _ in ijk], dtype=np.float64)
    return c * np.prod(L[:, None, :] ** ijk[None, :, :], axis=2)


def _facet_bernstein_matrix(facet_type: str) -> np.ndarray:
    """Matrix M (nb, nfn): the Bernstein coefficients of a scalar field interpolated by the facet's
    shape functions are ``M @ nodal_values`` (a serendipity quad8 is represented in the biquadratic
    space). Their min / max bound the field on the facet."""
    p = _GEOM_DEGREE[facet_type]
    if facet_type in FACET_TYPES[2]:
        t = np.linspace(0.0, 1.0, p + 1)
        pts = (2.0 * t - 1.0)[:, None]
        V = _bernstein_1d(t, p)
    elif facet_type.startswith("quad"):
        t = np.linspace(0.0, 1.0, p + 1)
        tu, tv = np.meshgrid(t, t, indexing="ij")
        pts = np.stack([2.0 * tu.ravel() - 1.0, 2.0 * tv.ravel() - 1.0], axis=1)
        Bu, Bv = _bernstein_1d(tu.ravel(), p), _bernstein_1d(tv.ravel(), p)
        V = (Bu[:, :, None] * Bv[:, None, :]).reshape(len(pts), -1)
    else:
        L = _triangle_lattice(p)
        pts = L[:, 1:]
        V = _bernstein_triangle(L, p)
    N, _ = shape_functions(facet_type, pts)
    return np.linalg.solve(V, N)


# ---------------------------------------------------------------------------------------------
# traction density and integration at arbitrary points


def _traction_times_area(A, xv, surface_level, unit_weight, axis, K):
    """``t |A|`` for the outward unnormalised normals A (..., dim) at elevations xv (...)."""
    d = np.maximum(surface_level - xv, 0.0)
    if K is None:
        vec = A
    else:
        vec = K * A
        vec[..., axis] = A[..., axis]
    return -unit_weight * d[..., None] * vec


def _scatter(facets, F, n_nodes, dim):
    """Sum nodal forces F (n, nfn, dim) of facets (n, nfn) into a flat (n_nodes*dim,) vector."""
    dofs = facets[:, :, None] * dim + np.arange(dim)
    return np.bincount(dofs.ravel(), weights=F.ravel(), minlength=n_nodes * dim)


# ---------------------------------------------------------------------------------------------
# partly wet facets: quadrature points on the wet part


def _wet_points_lines(facet_type, xv_nodes, surface_level):
    """Wet sub-intervals of partly wet edges. xv_nodes (m, nfn) nodal elevations. Returns
    (local facet index (P,), points (P, 1), weights (P,))."""
    m = len(xv_nodes)
    # f(xi) = s - x_v(xi) = c0 + c1 xi + c2 xi^2 (signed depth)
    if facet_type == "line2":
        v0, v1 = xv_nodes[:, 0], xv_nodes[:, 1]
        c0, c1, c2 = surface_level - 0.5 * (v0 + v1), -0.5 * (v1 - v0), np.zeros(m)
    else:
        v0, v1, vm = xv_nodes[:, 0], xv_nodes[:, 1], xv_nodes[:, 2]
        c0, c1, c2 = surface_level - vm, -0.5 * (v1 - v0), -(0.5 * (v0 + v1) - vm)
    scale = np.abs(c0) + np.abs(c1) + np.abs(c2)
    roots = np.full((m, 2), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        lin = np.abs(c2) <= 1e-14 * scale
        roots[lin, 0] = -c0[lin] / c1[lin]
        q = ~lin
        disc = c1[q] ** 2 - 4.0 * c2[q] * c0[q]
        sq = np.sqrt(np.where(disc >= 0.0, disc, np.nan))
        qq = -0.5 * (c1[q] + np.where(c1[q] >= 0.0, sq, -sq))  # stable: no cancellation
        roots[q, 0] = qq / c2[q]
        roots[q, 1] = c0[q] / qq
    roots = np.where(np.isfinite(roots), np.clip(roots, -1.0, 1.0), 1.0)
    breaks = np.sort(np.column_stack([np.full(m, -1.0), roots, np.full(m, 1.0)]), axis=1)  # (m, 4)
    a, b = breaks[:, :-1], breaks[:, 1:]  # (m, 3) sub-intervals
    mid = 0.5 * (a + b)
    wet = (c0[:, None] + c1[:, None] * mid + c2[:, None] * mid**2 > 0.0) & (b > a)
    xg, wg = _full_rule(facet_type)
    fi, si = np.nonzero(wet)
    half = 0.5 * (b - a)[fi, si]
    pts = mid[fi, si][:, None] + half[:, None] * xg[None, :, 0]  # (k, q)
    wts = half[:, None] * wg[None, :]
    return np.repeat(fi, len(wg)), pts.reshape(-1, 1), wts.ravel()


def _clip_triangles(T, h):
    """Wet part {h > 0} of triangles T (m, 3, 2) with h (m, 3) linear on each: up to two triangles
    per input. Returns (input index (k,), triangles (k, 3, 2))."""
    order = np.argsort(-h, axis=1)
    r = np.arange(len(T))[:, None]
    Ts, hs = T[r, order], h[r, order]  # vertices by decreasing h: A, B, C
    nwet = np.count_nonzero(hs > 0.0, axis=1)
    A, B, C = Ts[:, 0], Ts[:, 1], Ts[:, 2]
    hA, hB, hC = hs[:, 0:1], hs[:, 1:2], hs[:, 2:3]
    out_i, out_T = [], []
    full = nwet == 3
    out_i.append(np.flatnonzero(full))
    out_T.append(T[full])
    one = nwet == 1
    if one.any():
        a, b, c = A[one], B[one], C[one]
        ha, hb, hc = hA[one], hB[one], hC[one]
        pab = a + ha / (ha - hb) * (b - a)
        pac = a + ha / (ha - hc) * (c - a)
        out_i.append(np.flatnonzero(one))
        out_T.append(np.stack([a, pab, pac], axis=1))
    two = nwet == 2
    if two.any():
        a, b, c = A[two], B[two], C[two]
        ha, hb, hc = hA[two], hB[two], hC[two]
        pac = a + ha / (ha - hc) * (c - a)
        pbc = b + hb / (hb - hc) * (c - b)
        idx = np.flatnonzero(two)
        out_i += [idx, idx]
        out_T += [np.stack([a, b, pbc], axis=1), np.stack([a, pbc, pac], axis=1)]
    return np.concatenate(out_i), np.concatenate(out_T, axis=0)


def _triangle_points(owner, T, rule):
    """Map the unit-triangle rule onto triangles T (k, 3, 2) of the reference facet."""
    xr, wr = rule
    e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]
    det = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    pts = T[:, None, 0] + xr[None, :, 0:1] * e1[:, None] + xr[None, :, 1:2] * e2[:, None]
    return np.repeat(owner, len(wr)), pts.reshape(-1, 2), (det[:, None] * wr[None, :]).ravel()


def _wet_points_faces(facet_type, xv_nodes, surface_level, max_subdivision, subdivision_tol):
    """Quadrature points on the wet part of partly wet faces. xv_nodes (m, nfn) nodal elevations.
    Returns (local facet index (P,), points (P, 2), weights (P,))."""
    m = len(xv_nodes)
    rule = collapsed_triangle_rule(_duffy_points_for_degree(_INTEGRAND_TOTAL_DEGREE[facet_type]))
    p = _SUBTRI_DEGREE[facet_type]
    L = _triangle_lattice(p)  # (nl, 3), vertices first
    Binv = np.linalg.inv(_bernstein_triangle(L, p))  # lattice values -> Bernstein coefficients
    if facet_type.startswith("quad"):
        c = _QUAD_CORNERS
        base = np.array([[c[0], c[1], c[2]], [c[0], c[2], c[3]]])
        area_ref, diam_ref = 4.0, 2.0 * np.sqrt(2.0)
    else:
        base = _TRI_CORNERS[None]
        area_ref, diam_ref = 0.5, np.sqrt(2.0)
    owner = np.repeat(np.arange(m), len(base))
    T = np.tile(base, (m, 1, 1))
    xv_abs = np.abs(xv_nodes).max(axis=1)
    xv_spread = xv_nodes.max(axis=1) - xv_nodes.min(axis=1)
    tol = 1e-13 * xv_abs + 1e-11 * xv_spread  # linearity tolerance on x_v (m)
    # error budget of a clipped leaf, per unit of its size: subdivision_tol * int_facet spread / diam
    budget = subdivision_tol * xv_spread * area_ref / diam_ref

    out_o, out_p, out_w = [], [], []

    def emit(o, tris):
        if len(o):
            a, b, c = _triangle_points(o, tris, rule)
            out_o.append(a)
            out_p.append(b)
            out_w.append(c)

    for level in range(max_subdivision + 1):
        if len(owner) == 0:
            break
        lat = np.einsum("lk,nkr->nlr", L, T)  # (n, nl, 2) lattice points in facet coordinates
        Nl, _ = shape_functions(facet_type, lat.reshape(-1, 2))
        vals = np.einsum("nla,na->nl", Nl.reshape(len(T), len(L), -1), xv_nodes[owner])
        bern = vals @ Binv.T
        wet = bern.max(axis=1) <= surface_level
        dry = bern.min(axis=1) >= surface_level
        straddle = ~(wet | dry)
        emit(owner[wet], T[wet])
        # bound of |x_v - x_lin| on the triangle (x_lin its linear interpolant): the Bernstein
        # coefficients of x_lin at degree p are its values at the lattice points
        dev = np.abs(bern - vals[:, :3] @ L.T).max(axis=1)
        clip = straddle & ((dev <= tol[owner]) | (level == max_subdivision))
        est_ok = straddle & ~clip
        if est_ok.any():
            # clipping with the linear interpolant misplaces the water line by at most dev / |grad x_lin|
            # where |s - x_v| <= dev: error of int d <= dev * min(area, h * dev / g) (h the longest edge)
            Ts, vs = T[est_ok], vals[est_ok, :3]
            e1, e2 = Ts[:, 1] - Ts[:, 0], Ts[:, 2] - Ts[:, 0]
            det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
            d1, d2 = vs[:, 1] - vs[:, 0], vs[:, 2] - vs[:, 0]
            grad = np.stack([d1 * e2[:, 1] - d2 * e1[:, 1], d2 * e1[:, 0] - d1 * e2[:, 0]], axis=1) / det[:, None]
            g = np.linalg.norm(grad, axis=1)
            h = np.sqrt(np.maximum(np.maximum((e1**2).sum(1), (e2**2).sum(1)), ((e2 - e1) ** 2).sum(1)))
            dv = dev[est_ok]
            with np.errstate(divide="ignore"):
                est = dv * np.minimum(0.5 * np.abs(det), h * dv / g)
            clip[est_ok] = est <= budget[owner[est_ok]] * h
        if clip.any():
            ci, ct = _clip_triangles(T[clip], surface_level - vals[clip, :3])
            emit(owner[clip][ci], ct)
        split = straddle & ~clip
        if not split.any():
            break
        Ts = T[split]
        m01, m12, m20 = 0.5 * (Ts[:, 0] + Ts[:, 1]), 0.5 * (Ts[:, 1] + Ts[:, 2]), 0.5 * (Ts[:, 2] + Ts[:, 0])
        T = np.concatenate([
            np.stack([Ts[:, 0], m01, m20], axis=1),
            np.stack([m01, Ts[:, 1], m12], axis=1),
            np.stack([m20, m12, Ts[:, 2]], axis=1),
            np.stack([m01, m12, m20], axis=1),
        ])
        owner = np.tile(owner[split], 4)
    if not out_o:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2)), np.zeros(0)
    return np.concatenate(out_o), np.concatenate(out_p), np.concatenate(out_w)


# ---------------------------------------------------------------------------------------------


def facet_pressure_forces(coords, facet_type, facets, inward_points, *, surface_level, unit_weight,
                          vertical_axis, thickness=1.0, lateral_coefficient=None,
                          subdivision_tol=1e-8, max_subdivision=10) -> np.ndarray:
    """Consistent nodal forces of hydrostatic water pressure (or of a geostatic silt load) on facets.

    Parameters
    ----------
    coords : (n_nodes, dim) float, m; ``dim`` 2 or 3.
    facet_type : ``"line2"``, ``"line3"`` (2D edges) or ``"tri3"``, ``"tri6"``, ``"quad4"``, ``"quad8"``,
        ``"quad9"`` (3D faces), node order of :mod:`masonrydam.elements.shapes`.
    facets : (n, nfn) int, node indices of every facet.
    inward_points : (n, dim) float, m: a point inside the body that owns each facet (e.g. the owner
        element's centroid). The outward normal is the one pointing away from it (decided once per
        facet at the centre of its reference domain), so the node order of a facet does not matter.
    surface_level : m, elevation (coordinate ``vertical_axis``) of the free water surface or of the top
        of the silt. Depth ``d(x) = max(surface_level - x[vertical_axis], 0)``.
    unit_weight : N/m3, ``gamma`` (``rho g`` for water, the submerged unit weight for silt).
    vertical_axis : int, index of the upward vertical coordinate (1 in 2D x-y, 2 in 3D usually).
    thickness : m, out-of-plane thickness multiplying the 2D forces (ignored in 3D).
    lateral_coefficient : None for water (traction ``-gamma d n``), or the lateral earth pressure
        coefficient ``K`` of silt (traction ``-gamma d (K n_h + (n . e_v) e_v)``).
    subdivision_tol : relative accuracy of partly wet faces whose elevation is not linear in the
        reference coordinates (warped quad4, curved tri6 / quad8 / quad9), see the module docstring;
        not used elsewhere (everything else is exact).
    max_subdivision : cap on the levels of recursive subdivision of such faces.

    Returns
    -------
    (n_nodes * dim,) float64, N: the nodal forces, DOF index ``node * dim + component``.

    Exact (to round-off) for every fully wet or fully dry facet, for every partly wet edge in 2D
    (line2 and line3, the roots of the quadratic ``x_v(xi)`` are found in closed form) and for partly
    wet faces whose elevation is linear on each half of the reference quadrilateral / on the reference
    triangle (all tri3; planar quad4 faces without a bilinear elevation term, such as parallelograms or
    faces with horizontal / vertical edges). Partly wet faces with non-linear elevation (warped quad4,
    curved quadratic faces) are accurate to the subdivision only (see the module docstring).

    Cost: fully wet facets in one vectorised pass, partly wet ones vectorised too (clipping and
    subdivision level by level); about 12 ms for 5000 planar quad4 faces with one row partly wet,
    30 ms when those faces are warped by 1e-3 of their size (one core, numpy).
    """
    coords = np.asarray(coords, dtype=np.float64)
    if coords.ndim != 2 or coords.shape[1] not in (2, 3):
        raise ValueError(f"coords must have shape (n_nodes, 2 or 3), got {coords.shape}")
    n_nodes, dim = coords.shape
    allowed = FACET_TYPES[dim]
    if facet_type not in allowed:
        raise ValueError(f"facet type {facet_type!r} is not a boundary facet in {dim}D; use one of {allowed}")
    nfn = ELEMENT_TYPES[facet_type].n_nodes
    facets = np.asarray(facets, dtype=np.int64).reshape(-1, nfn)
    n = len(facets)
    inward_points = np.asarray(inward_points, dtype=np.float64).reshape(n, dim)
    axis = int(vertical_axis)
    if not 0 <= axis < dim:
        raise ValueError(f"vertical_axis must be in [0, {dim}), got {vertical_axis}")
    if facets.size and (facets.min() < 0 or facets.max() >= n_nodes):
        raise ValueError("facet node index out of range")
    s = float(surface_level)
    gamma = float(unit_weight)
    K = None if lateral_coefficient is None else float(lateral_coefficient)
    f = np.zeros(n_nodes * dim)
    if n == 0:
        return f
    scale = float(thickness) if dim == 2 else 1.0

    X = coords[facets]  # (n, nfn, dim)
    xv = X[:, :, axis]
    bern = xv @ _facet_bernstein_matrix(facet_type).T
    fully_wet = bern.max(axis=1) <= s
    partial = ~fully_wet & (bern.min(axis=1) < s)

    # outward sign per facet, from the parametric normal at the reference centre
    sign, _ = facet_outward_sign(facet_type, X, inward_points)

    if fully_wet.any():
        pts, w = _full_rule(facet_type)
        fq = facet_quadrature(facet_type, X[fully_wet], pts, w)
        A = fq.area_normal * sign[fully_wet, None, None]  # (n, q, dim), outward
        T = _traction_times_area(A, fq.points[..., axis], s, gamma, axis, K)
        F = np.einsum("q,qa,nqd->nad", w * scale, fq.shape_values, T)
        f += _scatter(facets[fully_wet], F, n_nodes, dim)

    if partial.any():
        idx = np.flatnonzero(partial)
        loc, pts, w = region_points(facet_type, xv[idx], s, max_subdivision=int(max_subdivision),
                                    subdivision_tol=float(subdivision_tol))
        if len(loc):
            gid = idx[loc]
            fq = facet_quadrature(facet_type, X, pts, w, owner=gid)
            A = fq.area_normal * sign[gid][:, None]  # (P, dim), outward
            T = _traction_times_area(A, fq.points[:, axis], s, gamma, axis, K)
            F = np.einsum("p,pa,pd->pad", w * scale, fq.shape_values, T)
            f += _scatter(facets[gid], F, n_nodes, dim)
    return f


def region_points(facet_type, nodal_values, threshold, *, max_subdivision=10, subdivision_tol=1e-8):
    """Quadrature points on the part of each facet where a field interpolated from ``nodal_values``
    (n, nfn) with the facet's shape functions is below ``threshold``: (facet index (P,), reference
    points (P, r), weights (P,)), exact (or, for a field that is not linear on the facet's reference
    triangles, as accurate as the subdivision) for the polynomial integrands of this module. The
    hydrostatic integration uses it with the elevation and the water level; the uplift
    (:mod:`masonrydam.effects.reservoir.uplift`) with the distance along a joint and the drain line, where the
    uplift profile has its kink."""
    v = np.asarray(nodal_values, dtype=np.float64)
    if facet_type in FACET_TYPES[2]:
        return _wet_points_lines(facet_type, v, threshold)
    return _wet_points_faces(facet_type, v, threshold, max_subdivision, subdivision_tol)
