"""Westergaard's added mass of the reservoir on the dam face (``[reservoir] dynamic = "westergaard"``).

:func:`westergaard_mass` gives the added-mass matrix (n_dof, n_dof) CSR, kg, DOF index ``node * dim + component``,
of the wetted part of a face: ``m_a(z) = 7/8 rho_w sqrt(H z)`` (kg/m2) on the face normal, ``m_a n n^T`` per unit
area, consistent or HRZ-lumped; coordinates and levels in m, density in kg/m3. It enters the mass matrix of the
dynamic and modal stages (:class:`masonrydam.assembly.mass.MassMatrix`). References: Westergaard (1933), Kuo
(1982), USACE EM 1110-2-6051 (2003), Hinton, Rock & Zienkiewicz (1976).

Theory: docs/dam_reservoir_foundation.md, section "Westergaard's added mass".
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...elements.shapes import ELEMENT_TYPES, facet_outward_sign, facet_quadrature, facet_rule
from .hydrostatics import region_points

#: Gauss points per direction on a fully wet facet (the integrand has sqrt(depth))
POINTS_PER_DIRECTION = 8


def westergaard_coefficient(depth, reservoir_depth, density):
    """Added mass per unit area (kg/m2) at ``depth`` (m, >= 0) below the surface of a reservoir
    ``reservoir_depth`` (m) deep: ``7/8 rho sqrt(H z)`` (Westergaard 1933)."""
    return 0.875 * density * np.sqrt(np.maximum(reservoir_depth * np.asarray(depth, dtype=np.float64), 0.0))


def _points(facet_type, X, level, axis):
    """Quadrature on the wet part of every facet: (facet index (P,), reference points (P, r), weights (P,))."""
    xv = X[:, :, axis]
    wet = xv.max(axis=1) <= level
    pts, w = facet_rule(facet_type, POINTS_PER_DIRECTION)
    full = np.flatnonzero(wet)
    owner = [np.repeat(full, len(w))]
    points = [np.tile(pts, (len(full), 1))]
    weights = [np.tile(w, len(full))]
    part = np.flatnonzero(~wet & (xv.min(axis=1) < level))
    if len(part):
        loc, p, wt = region_points(facet_type, xv[part], level)
        owner.append(part[loc])
        points.append(p)
        weights.append(wt)
    return np.concatenate(owner), np.concatenate(points), np.concatenate(weights)


def westergaard_mass(coords, facet_type, facets, *, level, reservoir_depth, density, vertical_axis,
                     thickness=1.0, lumped=False) -> sp.csr_matrix:
    """Added-mass matrix (n_dof, n_dof) CSR, kg, of the wetted part of ``facets``.

    coords (n_nodes, dim) m; facet_type one of line2, line3 (2D), tri3, tri6, quad4, quad8, quad9 (3D);
    facets (n, nfn) node indices; level: the water surface (m on ``vertical_axis``); reservoir_depth:
    ``H`` (m) in ``7/8 rho sqrt(H z)``; density: rho_w (kg/m3); thickness: 2D out-of-plane (m);
    lumped: HRZ-lumped node blocks instead of the consistent matrix."""
    coords = np.asarray(coords, dtype=np.float64)
    n_nodes, dim = coords.shape
    facets = np.asarray(facets, dtype=np.int64).reshape(-1, ELEMENT_TYPES[facet_type].n_nodes)
    X = coords[facets]
    owner, pts, w = _points(facet_type, X, float(level), int(vertical_axis))
    n_dof = n_nodes * dim
    if len(owner) == 0:
        return sp.csr_matrix((n_dof, n_dof))
    fq = facet_quadrature(facet_type, X, pts, w, owner=owner)
    N, x, A, jac = fq.shape_values, fq.points, fq.area_normal, fq.jacobian  # (P, nfn), (P, dim), (P, dim), (P,)
    nrm = A / jac[:, None]
    depth = float(level) - x[:, int(vertical_axis)]
    scale = float(thickness) if dim == 2 else 1.0
    mw = westergaard_coefficient(depth, float(reservoir_depth), float(density)) * jac * w * scale  # (P,) kg
    nn = np.einsum("pi,pj->pij", nrm, nrm)
    nfn = facets.shape[1]
    n_f = len(facets)
    if lumped:
        # HRZ: diagonal N_a^2 terms scaled so that each facet keeps its total added mass tensor
        diag = np.zeros((n_f, nfn, dim, dim))
        np.add.at(diag, owner, np.einsum("p,pa,pij->paij", mw, N * N, nn))
        total = np.zeros((n_f, dim, dim))
        np.add.at(total, owner, np.einsum("p,pij->pij", mw, nn))
        tr_diag = np.einsum("faii->f", diag)
        tr_total = np.einsum("fii->f", total)
        s = np.divide(tr_total, tr_diag, out=np.zeros(n_f), where=tr_diag > 0)
        blocks = diag * s[:, None, None, None]
        nodes = np.repeat(facets, dim * dim, axis=1).reshape(n_f, nfn, dim, dim)
        rows = nodes * dim + np.arange(dim)[None, None, :, None]
        cols = nodes * dim + np.arange(dim)[None, None, None, :]
        M = sp.csr_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(n_dof, n_dof))
    else:
        me = np.zeros((n_f, nfn, dim, nfn, dim))
        np.add.at(me, owner, np.einsum("p,pa,pb,pij->paibj", mw, N, N, nn))
        dofs = (facets[:, :, None] * dim + np.arange(dim)).reshape(n_f, -1)  # (n_f, nfn*dim)
        nd = nfn * dim
        rows = np.repeat(dofs, nd, axis=1)
        cols = np.tile(dofs, (1, nd))
        M = sp.csr_matrix((me.reshape(n_f, -1).ravel(), (rows.ravel(), cols.ravel())), shape=(n_dof, n_dof))
    M.sum_duplicates()
    M.eliminate_zeros()
    return M


def face_nodes(facets, coords, level, vertical_axis):
    """Sorted node indices of ``facets`` at or below ``level`` (the nodes that carry hydrodynamic
    pressure)."""
    nodes = np.unique(np.asarray(facets))
    return nodes[np.asarray(coords)[nodes, int(vertical_axis)] <= level + 1e-9 * max(1.0, abs(level))]


def nodal_normals(coords, facet_type, facets, inward_points, nodes):
    """Unit outward normals (len(nodes), dim) of the face at ``nodes``: the area-weighted average of the
    normals of the facets around each node (for the face pressure from a nodal acceleration)."""
    coords = np.asarray(coords, dtype=np.float64)
    facets = np.asarray(facets, dtype=np.int64)
    sign, A = facet_outward_sign(facet_type, coords[facets], inward_points)
    A = A * sign[:, None]
    acc = np.zeros_like(coords)
    np.add.at(acc, facets.ravel(), np.repeat(A, facets.shape[1], axis=0))
    out = acc[np.asarray(nodes)]
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-300)
