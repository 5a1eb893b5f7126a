"""Continuum elements in the total Lagrangian description (``[model] kinematics = "large"``):
Green-Lagrange strain, second Piola-Kirchhoff stress, the St. Venant-Kirchhoff material (the linear
elastic ``D`` of the group applied to the Green-Lagrange strain), plane strain / plane stress (2D) and
3D, every element type of :mod:`masonrydam.elements.continuum`.

Per Gauss point of the reference configuration (Bathe, *Finite Element Procedures*, 1996, sec. 6.2.3,
table 6.4; Belytschko, Liu & Moran, *Nonlinear Finite Elements for Continua and Structures*, 2000,
sec. 4.9; the total Lagrangian option of Tzamtzis & Asteris, sec. 3)::

    F = I + du/dX                      (dim, dim), F[k, i] = delta_ki + sum_a u_ak dN_a/dX_i
    E = (F^T F - I) / 2                Voigt [E11, E22, (E33,) 2 E12, (2 E23, 2 E31)]
    S = D E                            second Piola-Kirchhoff stress, Voigt [S11, S22, (S33,) S12, ...]
    B_NL[V(i, j), a k] = F[k, i] dN_a/dX_j + F[k, j] dN_a/dX_i   (i != j),   F[k, i] dN_a/dX_i  (i = j)
    f_e = sum_g B_NL^T S w det(J0) t
    k_e = sum_g (B_NL^T D B_NL + G^T S_mat G) w det(J0) t,   (G^T S_mat G)[a k, b l] = delta_kl dN_a . S_mat dN_b

``det(J0)`` is the reference Jacobian, ``t`` the thickness (2D). ``k_e`` is the exact derivative of
``f_e`` (material plus initial-stress part), symmetric. A rigid motion ``x = Q X + c`` gives
``F = Q``, ``E = 0``, ``S = 0``: no force for any rotation. The elastic energy
``sum_g (E . D E / 2) w det(J0) t`` is returned per element for the energy balance; the internal
force is its exact gradient (hyperelastic), so the trapezoidal rule's energy error is that of the
integrator alone (docs/continuum_nonlinearity.md, section "Solvers"
under "Large displacements").

Mass and body forces stay those of the reference configuration (total Lagrangian: ``rho0 dV0``);
loads given as pressures keep their reference direction (dead loads).
"""
from __future__ import annotations

import numba
import numpy as np

from ..errors import STATUS_NAN, STATUS_OK
from .continuum import (DETJ_RTOL, add_btdb, add_btsigma, bad_det_status, block_finite, dimension_tag,
                        gather_displacements, gather_element, shape_gradients, voigt_map)


@numba.njit(cache=True)
def _deformation_gradient(ue, dNdx, F):
    """F (dim, dim) = I + sum_a u_a (x) dN_a/dX."""
    dim = F.shape[0]
    nen = ue.shape[0]
    for k in range(dim):
        for i in range(dim):
            acc = 1.0 if k == i else 0.0
            for a in range(nen):
                acc += ue[a, k] * dNdx[i, a]
            F[k, i] = acc


@numba.njit(cache=True)
def _green_lagrange(F, V, E):
    """Voigt Green-Lagrange strain E (ns,) with engineering shears (2 E_ij)."""
    dim = F.shape[0]
    for i in range(dim):
        for j in range(i, dim):
            c = 0.0
            for k in range(dim):
                c += F[k, i] * F[k, j]
            if i == j:
                E[V[i, i]] = 0.5 * (c - 1.0)
            else:
                E[V[i, j]] = c


@numba.njit(cache=True)
def _svk_point(ue, dNdx, V, D, F, E, S):
    """At one Gauss point: F (dim, dim), the Green-Lagrange strain E (ns,) and the St. Venant-Kirchhoff
    second Piola-Kirchhoff stress S = D E (ns,)."""
    _deformation_gradient(ue, dNdx, F)
    _green_lagrange(F, V, E)
    ns = E.shape[0]
    for s in range(ns):
        acc = 0.0
        for t in range(ns):
            acc += D[s, t] * E[t]
        S[s] = acc


@numba.njit(cache=True)
def _large_impl(coords, conn, dN_ref, weights, D_table, material_index, thickness, u, want_tangent, fe_out, ke_out,
                energy_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_gp = weights.shape[0]
    ns = 3 if dim == 2 else 6
    nd = nen * dim
    V = voigt_map(dim_tag)
    xe = np.empty((nen, dim))
    ue = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    F = np.empty((dim, dim))
    B = np.empty((ns, nd))
    E = np.empty(ns)
    S = np.empty(ns)
    Smat = np.empty((dim, dim))
    DB = np.empty((ns, nd))
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        gather_displacements(u, conn, e, ue, dim_tag)
        t_e = thickness[e] if dim == 2 else 1.0
        D = D_table[material_index[e]]
        fe = fe_out[e]
        for r in range(nd):
            fe[r] = 0.0
        if want_tangent:
            ke = ke_out[e]
            for r in range(nd):
                for c in range(nd):
                    ke[r, c] = 0.0
        w_e = 0.0
        for g in range(n_gp):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            f = weights[g] * det * t_e
            _svk_point(ue, dNdx, V, D, F, E, S)
            en = 0.0
            for s in range(ns):
                en += E[s] * S[s]
            w_e += 0.5 * en * f
            for s in range(ns):
                for c in range(nd):
                    B[s, c] = 0.0
            for a in range(nen):
                for k in range(dim):
                    col = a * dim + k
                    for i in range(dim):
                        B[V[i, i], col] += F[k, i] * dNdx[i, a]
                        for j in range(i + 1, dim):
                            B[V[i, j], col] += F[k, i] * dNdx[j, a] + F[k, j] * dNdx[i, a]
            add_btsigma(B, S, f, fe)
            if want_tangent:
                add_btdb(B, D, f, DB, ke)
                # initial-stress (geometric) part: delta_kl dN_a . S dN_b
                for i in range(dim):
                    for j in range(dim):
                        Smat[i, j] = S[V[i, j]]
                for a in range(nen):
                    for b in range(nen):
                        acc = 0.0
                        for i in range(dim):
                            for j in range(dim):
                                acc += dNdx[i, a] * Smat[i, j] * dNdx[j, b]
                        acc *= f
                        for k in range(dim):
                            ke[a * dim + k, b * dim + k] += acc
        energy_out[e] = w_e
        if not block_finite(fe):
            info[0] = e
            return STATUS_NAN
    return STATUS_OK


def continuum_large_evaluate(coords, conn, dN_ref, weights, D_table, material_index, thickness, u, want_tangent,
                             fe_out, ke_out, energy_out, info):
    """Total Lagrangian internal forces ``fe_out`` (ne, nd) N, tangents ``ke_out`` (ne, nd, nd) N/m (with
    ``want_tangent``) and elastic energies ``energy_out`` (ne,) J of St. Venant-Kirchhoff elements at
    the displacement ``u`` (n_dof,) m from the reference ``coords`` (n_nodes, dim) m.

    D_table (n_mat, ns, ns) Pa, material_index (ne,), thickness (ne,) m (2D; ignored in 3D). Returns a
    status code (the failing element in ``info[0]``): STATUS_BAD_JACOBIAN for a reference element that is
    inverted, STATUS_NAN for a non-finite force.
    """
    return _large_impl(coords, conn, dN_ref, weights, D_table, material_index, thickness, u, bool(want_tangent),
                       fe_out, ke_out, energy_out, info, dimension_tag(coords))


@numba.njit(cache=True)
def _cauchy_impl(coords, conn, dN_ref, D_table, material_index, u, stress_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_gp = dN_ref.shape[0]
    ns = 3 if dim == 2 else 6
    V = voigt_map(dim_tag)
    xe = np.empty((nen, dim))
    ue = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    F = np.empty((dim, dim))
    E = np.empty(ns)
    S = np.empty(ns)
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        gather_displacements(u, conn, e, ue, dim_tag)
        D = D_table[material_index[e]]
        for g in range(n_gp):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            _svk_point(ue, dNdx, V, D, F, E, S)
            if dim == 2:
                detF = F[0, 0] * F[1, 1] - F[0, 1] * F[1, 0]
            else:
                detF = (F[0, 0] * (F[1, 1] * F[2, 2] - F[1, 2] * F[2, 1])
                        - F[0, 1] * (F[1, 0] * F[2, 2] - F[1, 2] * F[2, 0])
                        + F[0, 2] * (F[1, 0] * F[2, 1] - F[1, 1] * F[2, 0]))
            if not (detF > 0.0):
                info[0] = e
                return STATUS_NAN
            # sigma = F S F^T / det F, stored in the element's Voigt order
            for i in range(dim):
                for j in range(i, dim):
                    acc = 0.0
                    for k in range(dim):
                        for m in range(dim):
                            acc += F[i, k] * S[V[k, m]] * F[j, m]
                    stress_out[e, g, V[i, j]] = acc / detF
    return STATUS_OK


def continuum_cauchy_stress(coords, conn, dN_ref, D_table, material_index, u, stress_out, info):
    """Cauchy stress ``sigma = F S F^T / det F`` (ne, n_gp, ns) Pa at the Gauss points of St. Venant-Kirchhoff
    elements (Voigt order of the small-strain stress: [sxx, syy, sxy] / [sxx, syy, szz, sxy, syz, szx], in
    global axes of the current configuration). Status as :func:`continuum_large_evaluate`; an inverted
    deformation (det F <= 0) is STATUS_NAN."""
    return _cauchy_impl(coords, conn, dN_ref, D_table, material_index, u, stress_out, info, dimension_tag(coords))
