"""Zero-thickness interfaces whose frame rotates with the joint (``[model] kinematics =
"large"``): the interface of Tzamtzis & Asteris (sec. 3.3) with the local frame taken on the
mid-surface of the *current* configuration, so that gap and slip are measured across the joint as it
is now, at any rotation of the blocks it joins.

:func:`interface_large_evaluate` takes the node coordinates (m) and displacements (m), the face tables and the
joint law's parameter and state rows, and returns the forces (N) and tangents (N/m) of each element, exact
gradients of the joint's work (a co-rotational formulation: Crisfield 1991, ch. 7; Wriggers 2006, sec. 4.2);
the frame surface is the mid-surface or, with ``[joints.<set>] frame = "bottom"``, the bottom face.

Theory: docs/elements.md, section "Large kinematics: a frame that turns with the joint" (under "Zero-thickness
interfaces").
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..errors import STATUS_BAD_GEOMETRY, STATUS_NAN, STATUS_OK
from .interface import GEOM_TOL, local_frame, mid_surface_derivatives, joint_law_at

#: relative step of the central difference of B in 3D (times the element size)
FD_STEP_3D = 1e-6


@njit(cache=True)
def _element_arrays(coords, conn, u, e, ns, dim, top_weight, xm0, xm, gap):
    """Reference mid-surface ``xm0`` (ns, dim), the current frame surface ``xm`` (the mid-surface for
    ``top_weight`` 0.5, the bottom face for 0: ``x_bot + w (x_top - x_bot)``) and current node-pair gaps
    ``gap`` (ns, dim) = x_top - x_bot of element e; returns the reference face size (m)."""
    size = mid_surface_derivatives(coords, conn, e, ns, dim, xm0)
    for a in range(ns):
        b = conn[e, a]
        t = conn[e, ns + a]
        for k in range(dim):
            ub = u[b * dim + k]
            ut = u[t * dim + k]
            xm[a, k] = (coords[b, k] + ub) + top_weight * (coords[t, k] + ut - coords[b, k] - ub)
            gap[a, k] = coords[t, k] + ut - coords[b, k] - ub
    return size


@njit(cache=True)
def _b_matrix_3d(xm, gap, N, dN, g, top_weight, B, R, dvec):
    """Frame R (3, 3) of the current mid-surface, gap vector d (3,) and B = d(R d)/dq (3, n_q) at point g
    (3D). Returns |a_1 x a_2| (> 0), or 0.0 for a degenerate point."""
    ns = xm.shape[0]
    a1 = np.zeros(3)
    a2 = np.zeros(3)
    for a in range(ns):
        for k in range(3):
            a1[k] += dN[g, 0, a] * xm[a, k]
            a2[k] += dN[g, 1, a] * xm[a, k]
    for k in range(3):
        s = 0.0
        for a in range(ns):
            s += N[g, a] * gap[a, k]
        dvec[k] = s
    c = np.empty(3)
    c[0] = a1[1] * a2[2] - a1[2] * a2[1]
    c[1] = a1[2] * a2[0] - a1[0] * a2[2]
    c[2] = a1[0] * a2[1] - a1[1] * a2[0]
    lc = math.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    l1 = math.sqrt(a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2])
    if not (lc > 0.0 and l1 > 0.0):
        return 0.0
    e1 = a1 / l1
    n = c / lc
    e2 = np.empty(3)
    e2[0] = n[1] * e1[2] - n[2] * e1[1]
    e2[1] = n[2] * e1[0] - n[0] * e1[2]
    e2[2] = n[0] * e1[1] - n[1] * e1[0]
    for k in range(3):
        R[0, k] = e1[k]
        R[1, k] = e2[k]
        R[2, k] = n[k]
    da1 = np.zeros(3)
    da2 = np.zeros(3)
    de1 = np.empty(3)
    dc = np.empty(3)
    dn = np.empty(3)
    de2 = np.empty(3)
    for side in range(2):
        sgn = -1.0 if side == 0 else 1.0
        wside = 1.0 - top_weight if side == 0 else top_weight  # d x_frame / d u of this side
        for a in range(ns):
            for k in range(3):
                col = side * ns * 3 + a * 3 + k
                for m in range(3):
                    da1[m] = 0.0
                    da2[m] = 0.0
                da1[k] = wside * dN[g, 0, a]
                da2[k] = wside * dN[g, 1, a]
                # d e1 = (da1 - e1 (e1 . da1)) / |a1|
                p = e1[0] * da1[0] + e1[1] * da1[1] + e1[2] * da1[2]
                for m in range(3):
                    de1[m] = (da1[m] - e1[m] * p) / l1
                # d c = da1 x a2 + a1 x da2;  d n = (dc - n (n . dc)) / |c|
                dc[0] = da1[1] * a2[2] - da1[2] * a2[1] + a1[1] * da2[2] - a1[2] * da2[1]
                dc[1] = da1[2] * a2[0] - da1[0] * a2[2] + a1[2] * da2[0] - a1[0] * da2[2]
                dc[2] = da1[0] * a2[1] - da1[1] * a2[0] + a1[0] * da2[1] - a1[1] * da2[0]
                p = n[0] * dc[0] + n[1] * dc[1] + n[2] * dc[2]
                for m in range(3):
                    dn[m] = (dc[m] - n[m] * p) / lc
                # d e2 = dn x e1 + n x de1
                de2[0] = dn[1] * e1[2] - dn[2] * e1[1] + n[1] * de1[2] - n[2] * de1[1]
                de2[1] = dn[2] * e1[0] - dn[0] * e1[2] + n[2] * de1[0] - n[0] * de1[2]
                de2[2] = dn[0] * e1[1] - dn[1] * e1[0] + n[0] * de1[1] - n[1] * de1[0]
                dd = sgn * N[g, a]  # d d / d q_col = dd e_k
                B[0, col] = e1[k] * dd + de1[0] * dvec[0] + de1[1] * dvec[1] + de1[2] * dvec[2]
                B[1, col] = e2[k] * dd + de2[0] * dvec[0] + de2[1] * dvec[1] + de2[2] * dvec[2]
                B[2, col] = n[k] * dd + dn[0] * dvec[0] + dn[1] * dvec[1] + dn[2] * dvec[2]
    return lc


@njit(cache=True)
def _b_matrix_2d(xm, gap, N, dN, g, top_weight, B, R, dvec, P, A, Gt, Gn):
    """2D: frame R, gap d, B = d delta / dq (2, n_q) and the vectors P, A, G_t, G_n (n_q,) of the second
    derivatives (module docstring). Returns |a| (> 0) or 0.0 for a degenerate point."""
    ns = xm.shape[0]
    ax = 0.0
    ay = 0.0
    dx = 0.0
    dy = 0.0
    for a in range(ns):
        ax += dN[g, 0, a] * xm[a, 0]
        ay += dN[g, 0, a] * xm[a, 1]
        dx += N[g, a] * gap[a, 0]
        dy += N[g, a] * gap[a, 1]
    la = math.sqrt(ax * ax + ay * ay)
    if not (la > 0.0):
        return 0.0
    tx = ax / la
    ty = ay / la
    nx = -ty
    ny = tx
    R[0, 0] = tx
    R[0, 1] = ty
    R[1, 0] = nx
    R[1, 1] = ny
    dvec[0] = dx
    dvec[1] = dy
    d_t = tx * dx + ty * dy
    d_n = nx * dx + ny * dy
    for side in range(2):
        sgn = -1.0 if side == 0 else 1.0
        wside = 1.0 - top_weight if side == 0 else top_weight
        for a in range(ns):
            h = wside * dN[g, 0, a] / la
            col = side * ns * 2 + a * 2
            # component x then y of node a
            P[col] = nx * h
            P[col + 1] = ny * h
            A[col] = tx * h
            A[col + 1] = ty * h
            Gt[col] = sgn * N[g, a] * tx
            Gt[col + 1] = sgn * N[g, a] * ty
            Gn[col] = sgn * N[g, a] * nx
            Gn[col + 1] = sgn * N[g, a] * ny
    for c in range(P.shape[0]):
        B[0, c] = Gt[c] + d_n * P[c]
        B[1, c] = Gn[c] - d_t * P[c]
    return la


@njit(cache=True)
def interface_large_evaluate(coords, conn, u, N, dN, weights, thickness, params_table, param_index, state_committed,
                             state_trial, delta_out, traction_out, fe_out, ke_out, want_tangent, info,
                             top_weight=0.5, law=None):
    """Co-rotational interface elements: the arguments, outputs and status codes of
    :func:`masonrydam.elements.interface.interface_evaluate` (shapes, units), with the frame of the
    current mid-surface (module docstring). ``delta_out`` holds ``[slip(s), opening]`` in that frame."""
    n_elem = conn.shape[0]
    dim = coords.shape[1]
    nip = N.shape[0]
    ns = N.shape[1]
    nq = 2 * ns * dim
    xm0 = np.empty((ns, dim))
    xm = np.empty((ns, dim))
    gap = np.empty((ns, dim))
    gap0 = np.empty((ns, dim))
    R0 = np.zeros((dim, dim))
    R = np.zeros((dim, dim))
    B = np.zeros((dim, nq))
    Bp = np.zeros((dim, nq))
    Bm = np.zeros((dim, nq))
    dvec = np.zeros(dim)
    d0 = np.zeros(dim)
    delta0 = np.zeros(dim)
    P = np.zeros(nq)
    A = np.zeros(nq)
    Gt = np.zeros(nq)
    Gn = np.zeros(nq)
    C = np.empty((dim, dim))
    CB = np.empty((dim, nq))
    Rs = np.zeros((dim, dim))
    ds = np.zeros(dim)
    xmp = np.empty((ns, dim))
    gapp = np.empty((ns, dim))
    xf0 = np.empty((ns, dim))
    for e in range(n_elem):
        for r in range(nq):
            fe_out[e, r] = 0.0
        if want_tangent:
            for r in range(nq):
                for c in range(nq):
                    ke_out[e, r, c] = 0.0
        size = _element_arrays(coords, conn, u, e, ns, dim, top_weight, xm0, xm, gap)
        for a in range(ns):
            for k in range(dim):
                gap0[a, k] = coords[conn[e, ns + a], k] - coords[conn[e, a], k]
                xf0[a, k] = coords[conn[e, a], k] + top_weight * gap0[a, k]  # the frame surface at rest
        h = thickness[e]
        pidx = param_index[e]
        for g in range(nip):
            j0 = local_frame(xm0, dN, g, dim, R0, size)
            if top_weight != 0.5:  # the frame at rest of a surface other than the mid-surface (areas stay)
                local_frame(xf0, dN, g, dim, R0, size)
            if not math.isfinite(j0):
                info[0] = e
                return STATUS_NAN
            if j0 == 0.0:
                info[0] = e
                return STATUS_BAD_GEOMETRY
            # the reference local gap R0 d0 (zero for coincident faces)
            for k in range(dim):
                s = 0.0
                for a in range(ns):
                    s += N[g, a] * gap0[a, k]
                d0[k] = s
            for r in range(dim):
                s = 0.0
                for k in range(dim):
                    s += R0[r, k] * d0[k]
                delta0[r] = s
            if dim == 2:
                jc = _b_matrix_2d(xm, gap, N, dN, g, top_weight, B, R, dvec, P, A, Gt, Gn)
            else:
                jc = _b_matrix_3d(xm, gap, N, dN, g, top_weight, B, R, dvec)
            if not math.isfinite(jc):
                info[0] = e
                return STATUS_NAN
            if not (jc > GEOM_TOL * size ** (dim - 1)):
                info[0] = e
                return STATUS_BAD_GEOMETRY
            for r in range(dim):
                s = 0.0
                for k in range(dim):
                    s += R[r, k] * dvec[k]
                delta_out[e, g, r] = s - delta0[r]
            status = joint_law_at(params_table, pidx, state_committed, state_trial, delta_out, traction_out, e, g,
                                  dim, C, law, want_tangent)
            if status != STATUS_OK:
                info[0] = e
                return status
            jwh = j0 * weights[g] * h
            for c in range(nq):
                s = 0.0
                for r in range(dim):
                    s += B[r, c] * traction_out[e, g, r]
                fe_out[e, c] += s * jwh
            if not want_tangent:
                continue
            for r in range(dim):
                for c in range(nq):
                    s = 0.0
                    for q in range(dim):
                        s += C[r, q] * B[q, c]
                    CB[r, c] = s
            for r in range(nq):
                for c in range(nq):
                    s = 0.0
                    for q in range(dim):
                        s += B[q, r] * CB[q, c]
                    ke_out[e, r, c] += s * jwh
            # the frame's rotation: sum_r t_r d^2 delta_r / dq^2
            if dim == 2:
                ts = traction_out[e, g, 0]
                tn = traction_out[e, g, 1]
                d_t = R[0, 0] * dvec[0] + R[0, 1] * dvec[1]
                d_n = R[1, 0] * dvec[0] + R[1, 1] * dvec[1]
                for r in range(nq):
                    for c in range(nq):
                        hs = (Gn[r] * P[c] + P[r] * Gn[c] - d_t * P[r] * P[c]
                              - d_n * (A[r] * P[c] + P[r] * A[c]))
                        hn = (-Gt[r] * P[c] - P[r] * Gt[c] - d_n * P[r] * P[c]
                              + d_t * (A[r] * P[c] + P[r] * A[c]))
                        ke_out[e, r, c] += (ts * hs + tn * hn) * jwh
            else:
                step = FD_STEP_3D * size
                for c in range(nq):
                    side = c // (ns * 3)
                    a = (c % (ns * 3)) // 3
                    k = c % 3
                    sgn = -1.0 if side == 0 else 1.0
                    for sign in range(2):
                        eps = step if sign == 0 else -step
                        xmp[:, :] = xm
                        gapp[:, :] = gap
                        xmp[a, k] += (top_weight if side == 1 else 1.0 - top_weight) * eps
                        gapp[a, k] += sgn * eps
                        _b_matrix_3d(xmp, gapp, N, dN, g, top_weight, Bp if sign == 0 else Bm, Rs, ds)
                    for r in range(nq):
                        s = 0.0
                        for q in range(3):
                            s += traction_out[e, g, q] * (Bp[q, r] - Bm[q, r])
                        ke_out[e, r, c] += s / (2.0 * step) * jwh
        for r in range(nq):
            if not math.isfinite(fe_out[e, r]):
                info[0] = e
                return STATUS_NAN
    return STATUS_OK
