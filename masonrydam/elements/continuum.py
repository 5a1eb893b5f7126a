"""Isoparametric continuum (solid) element kernels: stiffness, internal force, body force, mass, stress.

All kernels are dimension-generic (``dim = coords.shape[1]``, 2 or 3, equal to ``dN_ref.shape[1]``); element
types enter only through the tables ``N_ref`` / ``dN_ref`` / ``weights`` of :func:`element_tables`. Units:
coordinates m, displacements m, ``D`` Pa, thickness m, body force N/m^3, density kg/m^3; stiffness N/m,
forces N, mass kg, stresses Pa; element DOFs node-major, global DOF ``n * dim + c``. Status codes
(``masonrydam.errors``): a kernel stops at the first failing element (its index in ``info[0]``; outputs at
and after it undefined) with ``STATUS_BAD_JACOBIAN`` (inverted or degenerate at an integration point) or
``STATUS_NAN``. Preconditions, not checked by the kernels: float64 C-contiguous arrays, int64 ``conn`` /
``material_index`` with valid indices, ``D_table`` symmetric. Formulation: Bathe (2014), Hughes (2000),
Zienkiewicz, Taylor & Zhu (2013).

Theory: docs/elements.md, section "Formulation and the Jacobian check" (under "Continuum (linear elastic
blocks)").
"""
from __future__ import annotations

import numba
import numpy as np

from ..errors import STATUS_BAD_JACOBIAN, STATUS_NAN, STATUS_OK
from . import shapes

#: Relative tolerance of the degenerate-Jacobian test: ``det J <= DETJ_RTOL * h**dim`` is rejected.
DETJ_RTOL = 1e-12

__all__ = [
    "DETJ_RTOL",
    "element_tables",
    "continuum_stiffness",
    "continuum_internal_force",
    "continuum_body_force",
    "continuum_mass",
    "continuum_stress",
]


def element_tables(type_name: str, n_gauss: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shape-function tables at the integration points of element type ``type_name``.

    Parameters
    ----------
    type_name : str
        A key of ``shapes.ELEMENT_TYPES`` (e.g. ``"quad4"``, ``"tri6"``, ``"hex20"``, ``"tet10"``).
    n_gauss : int, optional
        Points per direction (quadrilaterals, hexahedra) or in total (triangles: 1, 3 or 6;
        tetrahedra: 1, 4 or 14); default is the type's full-integration rule
        (``shapes.integration_rule``: hex8 2x2x2, hex20 3x3x3, tet4 1, tet10 4). For consistent mass
        matrices use a rule exact for ``N_a N_b``: tri3 -> 3, tri6 -> 6, tet4 -> 4, tet10 -> 14; the
        quadrilateral and hexahedron defaults (hex8 2x2x2, hex20 3x3x3) are exact on parallelograms
        and parallelepipeds.

    Returns
    -------
    N_ref : (n_gp, nen) float64
        Shape functions at the points.
    dN_ref : (n_gp, dim, nen) float64
        Derivatives with respect to the natural coordinates.
    weights : (n_gp,) float64
        Integration weights on the reference element (sum 4 for quads, 1/2 for triangles, 8 for
        hexahedra, 1/6 for tetrahedra).
    """
    points, weights = shapes.integration_rule(type_name, n_gauss)
    N, dN = shapes.shape_functions(type_name, points)
    return (
        np.ascontiguousarray(N, dtype=np.float64),
        np.ascontiguousarray(dN, dtype=np.float64),
        np.ascontiguousarray(weights, dtype=np.float64),
    )


# ----------------------------------------------------------------------------------------------
# Internal helpers (compiled; called once per element or per integration point).
# ----------------------------------------------------------------------------------------------


@numba.njit(cache=True)
def voigt_map(dim_tag):
    """(dim, dim) int64 table V with V[i, j] = Voigt index of the strain component (i, j)."""
    dim = len(dim_tag)
    V = np.empty((dim, dim), dtype=np.int64)
    if dim == 2:
        V[0, 0] = 0
        V[1, 1] = 1
        V[0, 1] = 2
        V[1, 0] = 2
    else:
        V[0, 0] = 0
        V[1, 1] = 1
        V[2, 2] = 2
        V[0, 1] = 3
        V[1, 0] = 3
        V[1, 2] = 4
        V[2, 1] = 4
        V[2, 0] = 5
        V[0, 2] = 5
    return V


@numba.njit(cache=True)
def gather_element(coords, conn, e, xe, dim_tag):
    """Copy the node coordinates of element ``e`` into ``xe`` (nen, dim); return the size ``h``
    (largest edge of the bounding box)."""
    nen = xe.shape[0]
    dim = len(dim_tag)
    h = 0.0
    for j in range(dim):
        lo = coords[conn[e, 0], j]
        hi = lo
        for a in range(nen):
            x = coords[conn[e, a], j]
            xe[a, j] = x
            if x < lo:
                lo = x
            if x > hi:
                hi = x
        if hi - lo > h:
            h = hi - lo
    return h


@numba.njit(cache=True)
def gather_displacements(u, conn, e, ue, dim_tag):
    """Copy the displacements of element ``e``'s nodes from ``u`` (n_dof,) into ``ue`` (nen, dim)."""
    dim = len(dim_tag)
    for a in range(ue.shape[0]):
        base = conn[e, a] * dim
        for k in range(dim):
            ue[a, k] = u[base + k]


@numba.njit(cache=True)
def shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag):
    """Jacobian at point ``g`` and, if ``det J > tol``, the physical gradients ``dNdx`` (dim, nen).

    ``J[i, j] = sum_a dN_ref[g, i, a] xe[a, j]``; ``dNdx[j, a] = sum_i Jinv[j, i] dN_ref[g, i, a]``.
    Returns ``det J`` (the gradients are left untouched when ``det J <= tol`` or NaN).
    """
    nen = xe.shape[0]
    dim = len(dim_tag)
    for i in range(dim):
        for j in range(dim):
            s = 0.0
            for a in range(nen):
                s += dN_ref[g, i, a] * xe[a, j]
            J[i, j] = s
    if dim == 2:
        det = J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
        if not (det > tol):
            return det
        r = 1.0 / det
        i00 = J[1, 1] * r
        i01 = -J[0, 1] * r
        i10 = -J[1, 0] * r
        i11 = J[0, 0] * r
        for a in range(nen):
            d0 = dN_ref[g, 0, a]
            d1 = dN_ref[g, 1, a]
            dNdx[0, a] = i00 * d0 + i01 * d1
            dNdx[1, a] = i10 * d0 + i11 * d1
    else:
        c00 = J[1, 1] * J[2, 2] - J[1, 2] * J[2, 1]
        c01 = J[1, 2] * J[2, 0] - J[1, 0] * J[2, 2]
        c02 = J[1, 0] * J[2, 1] - J[1, 1] * J[2, 0]
        det = J[0, 0] * c00 + J[0, 1] * c01 + J[0, 2] * c02
        if not (det > tol):
            return det
        r = 1.0 / det
        # inverse = adjugate / det; adj[j, i] = cofactor[i, j]
        i00 = c00 * r
        i10 = c01 * r
        i20 = c02 * r
        i01 = (J[0, 2] * J[2, 1] - J[0, 1] * J[2, 2]) * r
        i11 = (J[0, 0] * J[2, 2] - J[0, 2] * J[2, 0]) * r
        i21 = (J[0, 1] * J[2, 0] - J[0, 0] * J[2, 1]) * r
        i02 = (J[0, 1] * J[1, 2] - J[0, 2] * J[1, 1]) * r
        i12 = (J[0, 2] * J[1, 0] - J[0, 0] * J[1, 2]) * r
        i22 = (J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]) * r
        for a in range(nen):
            d0 = dN_ref[g, 0, a]
            d1 = dN_ref[g, 1, a]
            d2 = dN_ref[g, 2, a]
            dNdx[0, a] = i00 * d0 + i01 * d1 + i02 * d2
            dNdx[1, a] = i10 * d0 + i11 * d1 + i12 * d2
            dNdx[2, a] = i20 * d0 + i21 * d1 + i22 * d2
    return det


@numba.njit(cache=True)
def bad_det_status(det, e, info):
    """Status for a rejected ``det J`` (NaN -> STATUS_NAN, else STATUS_BAD_JACOBIAN)."""
    info[0] = e
    if det != det:
        return STATUS_NAN
    return STATUS_BAD_JACOBIAN


@numba.njit(cache=True)
def _strain_stress(ue, dNdx, V, D, mat, eps, sig, dim_tag):
    """Small strain (engineering shear) and stress ``sig = D[mat] eps`` from element displacements."""
    nen = ue.shape[0]
    dim = len(dim_tag)
    n_strain = eps.shape[0]
    for k in range(dim):
        for j in range(k, dim):
            s = 0.0
            for a in range(nen):
                s += ue[a, k] * dNdx[j, a]
                if j != k:
                    s += ue[a, j] * dNdx[k, a]
            eps[V[k, j]] = s
    for s_ in range(n_strain):
        acc = 0.0
        for t in range(n_strain):
            acc += D[mat, s_, t] * eps[t]
        sig[s_] = acc


@numba.njit(cache=True)
def add_btsigma(B, sig, f, fe):
    """``fe[c] += f sum_s B[s, c] sig[s]``: a Gauss point's internal force, B (ns, nd), sig (ns,)."""
    for c in range(B.shape[1]):
        acc = 0.0
        for s in range(B.shape[0]):
            acc += B[s, c] * sig[s]
        fe[c] += f * acc


@numba.njit(cache=True)
def add_btdb(B, D, f, DB, ke):
    """``ke += f B^T D B`` with ``D`` (ns, ns) in full (non-symmetric tangents too); DB (ns, nd) scratch."""
    ns, nd = B.shape
    for s in range(ns):
        for c in range(nd):
            acc = 0.0
            for t in range(ns):
                acc += D[s, t] * B[t, c]
            DB[s, c] = acc
    for r in range(nd):
        for c in range(nd):
            acc = 0.0
            for s in range(ns):
                acc += B[s, r] * DB[s, c]
            ke[r, c] += f * acc


@numba.njit(cache=True)
def block_finite(block):
    """True when every entry of the array ``block`` is finite (sum trick: inf - inf = nan, nan != 0)."""
    s = 0.0
    for v in block.flat:
        s += v
    return s - s == 0.0


# ----------------------------------------------------------------------------------------------
# Kernels. Each public kernel dispatches on ``coords.shape[1]`` to one generic implementation,
# compiled once per dimension: ``dim_tag`` is the tuple ``(0, 0)`` or ``(0, 0, 0)``, and
# ``dim = len(dim_tag)`` is a compile-time constant in each specialization, so the short loops over
# the spatial dimension are unrolled by LLVM (about 2.5x faster than a run-time ``dim``). The public
# functions are plain Python: a numba dispatcher with both calls in it compiled both dimensions on
# first use (the 2D default scene compiled the 3D kernels too: about 3 s of its first run).
# ----------------------------------------------------------------------------------------------


def dimension_tag(coords):
    """``(0, 0)`` for 2D coordinates, ``(0, 0, 0)`` for 3D: the compile-time dimension of the kernels."""
    return (0, 0) if coords.shape[1] == 2 else (0, 0, 0)


@numba.njit(cache=True)
def _stiffness_impl(coords, conn, dN_ref, weights, D_table, material_index, thickness, ke_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_gp = weights.shape[0]
    ndof = nen * dim
    V = voigt_map(dim_tag)
    xe = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    C = np.empty((dim, dim, dim, dim))
    T = np.empty((dim, dim, nen, dim))
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        mat = material_index[e]
        # C[i, l, k, j] = D[V(i, l), V(k, j)]: the elasticity tensor in index form
        for i in range(dim):
            for l in range(dim):
                for k in range(dim):
                    for j in range(dim):
                        C[i, l, k, j] = D_table[mat, V[i, l], V[k, j]]
        t_e = thickness[e] if dim == 2 else 1.0
        ke = ke_out[e]
        for r in range(ndof):
            for c in range(ndof):
                ke[r, c] = 0.0
        for g in range(n_gp):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            f = weights[g] * det * t_e
            # T[i, l, b, k] = f * sum_j C[i, l, k, j] dN_b/dx_j   (= f * D B_b in index form)
            for i in range(dim):
                for l in range(dim):
                    for b in range(nen):
                        for k in range(dim):
                            s = 0.0
                            for j in range(dim):
                                s += C[i, l, k, j] * dNdx[j, b]
                            T[i, l, b, k] = f * s
            # upper triangle: K[a*dim+i, b*dim+k] += sum_l dN_a/dx_l T[i, l, b, k]  (= B_a^T D B_b)
            for a in range(nen):
                for i in range(dim):
                    r = a * dim + i
                    for b in range(a, nen):
                        k0 = i if b == a else 0
                        for k in range(k0, dim):
                            s = 0.0
                            for l in range(dim):
                                s += dNdx[l, a] * T[i, l, b, k]
                            ke[r, b * dim + k] += s
        for r in range(ndof):
            for c in range(r + 1, ndof):
                ke[c, r] = ke[r, c]
        if not block_finite(ke):
            info[0] = e
            return STATUS_NAN
    return STATUS_OK


def continuum_stiffness(coords, conn, dN_ref, weights, D_table, material_index, thickness, ke_out, info):
    """Linear elastic element stiffness matrices ``K_e = int B^T D B dV``.

    Parameters
    ----------
    coords : (n_nodes, dim) float64
        Node coordinates, m; ``dim`` is 2 or 3.
    conn : (n_elem, nen) int64
        Element connectivity in the node order of the shape tables.
    dN_ref : (n_gp, dim, nen) float64
        Natural derivatives of the shape functions at the integration points.
    weights : (n_gp,) float64
        Integration weights.
    D_table : (n_mat, n_strain, n_strain) float64
        Symmetric constitutive matrices (Pa), ``n_strain`` = 3 (2D) or 6 (3D).
    material_index : (n_elem,) int64
        Row of ``D_table`` of each element.
    thickness : (n_elem,) float64
        Out-of-plane thickness, m; multiplies the integrand in 2D, ignored in 3D (pass ones).
    ke_out : (n_elem, nen*dim, nen*dim) float64
        Output, N/m; node-major element dofs. Symmetric by construction (upper triangle mirrored).
    info : (1,) int64
        Receives the failing element index.

    Returns
    -------
    int
        ``STATUS_OK``, ``STATUS_BAD_JACOBIAN`` or ``STATUS_NAN`` (see module docstring).
    """
    return _stiffness_impl(
        coords, conn, dN_ref, weights, D_table, material_index, thickness, ke_out, info, dimension_tag(coords)
    )


@numba.njit(cache=True)
def _internal_force_impl(coords, conn, dN_ref, weights, D_table, material_index, thickness, u, fe_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_gp = weights.shape[0]
    n_strain = D_table.shape[1]
    V = voigt_map(dim_tag)
    xe = np.empty((nen, dim))
    ue = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    eps = np.empty(n_strain)
    sig = np.empty(n_strain)
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        gather_displacements(u, conn, e, ue, dim_tag)
        mat = material_index[e]
        t_e = thickness[e] if dim == 2 else 1.0
        fe = fe_out[e]
        for r in range(nen * dim):
            fe[r] = 0.0
        for g in range(n_gp):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            f = weights[g] * det * t_e
            _strain_stress(ue, dNdx, V, D_table, mat, eps, sig, dim_tag)
            # f_a[i] += f * sum_l dN_a/dx_l sigma[V(i, l)]   (= B_a^T sigma)
            for a in range(nen):
                for i in range(dim):
                    s = 0.0
                    for l in range(dim):
                        s += dNdx[l, a] * sig[V[i, l]]
                    fe[a * dim + i] += f * s
        if not block_finite(fe):
            info[0] = e
            return STATUS_NAN
    return STATUS_OK


def continuum_internal_force(coords, conn, dN_ref, weights, D_table, material_index, thickness, u, fe_out, info):
    """Linear elastic internal force vectors ``f_e = int B^T sigma dV``, ``sigma = D B u_e`` (N).

    Parameters as in :func:`continuum_stiffness`, plus

    u : (n_dof,) float64
        Global displacement vector, m, ``dof = node * dim + component``.
    fe_out : (n_elem, nen*dim) float64
        Output, N; node-major element dofs.

    Consistent with the stiffness: ``fe_out[e] == ke_out[e] @ u_e`` up to rounding.
    Returns a status code (see module docstring).
    """
    return _internal_force_impl(
        coords, conn, dN_ref, weights, D_table, material_index, thickness, u, fe_out, info, dimension_tag(coords)
    )


@numba.njit(cache=True)
def _body_force_impl(coords, conn, N_ref, dN_ref, weights, body_force, thickness, fe_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_gp = weights.shape[0]
    xe = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        t_e = thickness[e] if dim == 2 else 1.0
        fe = fe_out[e]
        for r in range(nen * dim):
            fe[r] = 0.0
        for g in range(n_gp):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            f = weights[g] * det * t_e
            for a in range(nen):
                fN = f * N_ref[g, a]
                for k in range(dim):
                    fe[a * dim + k] += fN * body_force[e, k]
        if not block_finite(fe):
            info[0] = e
            return STATUS_NAN
    return STATUS_OK


def continuum_body_force(coords, conn, N_ref, dN_ref, weights, body_force, thickness, fe_out, info):
    """Consistent nodal loads of a constant body force per element, ``f_a = int N_a b dV`` (N).

    Parameters
    ----------
    coords, conn, dN_ref, weights, thickness : as in :func:`continuum_stiffness`.
    N_ref : (n_gp, nen) float64
        Shape functions at the integration points.
    body_force : (n_elem, dim) float64
        Body force per unit volume, N/m^3 (e.g. ``(0, -rho g)``), constant over each element.
    fe_out : (n_elem, nen*dim) float64
        Output, N; node-major element dofs.

    Returns a status code (see module docstring).
    """
    return _body_force_impl(
        coords, conn, N_ref, dN_ref, weights, body_force, thickness, fe_out, info, dimension_tag(coords)
    )


@numba.njit(cache=True)
def _mass_impl(coords, conn, N_ref, dN_ref, weights, density, thickness, lumped, me_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_gp = weights.shape[0]
    ndof = nen * dim
    xe = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    m = np.empty((nen, nen))
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        t_e = thickness[e] if dim == 2 else 1.0
        rho = density[e]
        for a in range(nen):
            for b in range(nen):
                m[a, b] = 0.0
        m_total = 0.0
        for g in range(n_gp):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            f = weights[g] * det * t_e * rho
            m_total += f
            for a in range(nen):
                fN = f * N_ref[g, a]
                for b in range(a, nen):
                    m[a, b] += fN * N_ref[g, b]
        me = me_out[e]
        for r in range(ndof):
            for c in range(ndof):
                me[r, c] = 0.0
        if lumped:
            # HRZ: diagonal of the consistent matrix scaled to the element mass
            diag_sum = 0.0
            for a in range(nen):
                diag_sum += m[a, a]
            scale = m_total / diag_sum if diag_sum != 0.0 else 0.0
            for a in range(nen):
                ma = m[a, a] * scale
                for k in range(dim):
                    me[a * dim + k, a * dim + k] = ma
        else:
            for a in range(nen):
                for b in range(a, nen):
                    mab = m[a, b]
                    for k in range(dim):
                        me[a * dim + k, b * dim + k] = mab
                        me[b * dim + k, a * dim + k] = mab
        if not block_finite(me):
            info[0] = e
            return STATUS_NAN
    return STATUS_OK


def continuum_mass(coords, conn, N_ref, dN_ref, weights, density, thickness, lumped, me_out, info):
    """Element mass matrices, consistent ``M_ab = int rho N_a N_b dV I_dim`` or HRZ-lumped (kg).

    Parameters
    ----------
    coords, conn, dN_ref, weights, thickness : as in :func:`continuum_stiffness`.
    N_ref : (n_gp, nen) float64
        Shape functions at the integration points (use a rule exact for ``N_a N_b``, see
        :func:`element_tables`).
    density : (n_elem,) float64
        Mass density, kg/m^3.
    lumped : bool
        False: consistent mass. True: HRZ diagonal scaling (Hinton, Rock & Zienkiewicz 1976,
        Earthquake Eng. Struct. Dyn. 4, 245-249; Cook et al. 2002, sec. 11.3): the lumped mass of
        node ``a`` is ``M_aa * m_e / sum_b M_bb`` with ``m_e = int rho dV`` the element mass, the same
        in every direction. All entries are positive (also at the corners of quad8, where row-sum
        lumping gives negative masses) and the total per direction equals ``m_e``. An element with
        zero density gets a zero matrix.
    me_out : (n_elem, nen*dim, nen*dim) float64
        Output, kg; node-major element dofs (diagonal only when ``lumped``).

    Returns a status code (see module docstring).
    """
    return _mass_impl(
        coords, conn, N_ref, dN_ref, weights, density, thickness, lumped, me_out, info, dimension_tag(coords)
    )


@numba.njit(cache=True)
def _stress_impl(coords, conn, dN_ref, D_table, material_index, u, stress_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_pt = dN_ref.shape[0]
    n_strain = D_table.shape[1]
    V = voigt_map(dim_tag)
    xe = np.empty((nen, dim))
    ue = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    eps = np.empty(n_strain)
    sig = np.empty(n_strain)
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        gather_displacements(u, conn, e, ue, dim_tag)
        mat = material_index[e]
        for g in range(n_pt):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            _strain_stress(ue, dNdx, V, D_table, mat, eps, sig, dim_tag)
            for s in range(n_strain):
                stress_out[e, g, s] = sig[s]
        if not block_finite(stress_out[e]):
            info[0] = e
            return STATUS_NAN
    return STATUS_OK


def continuum_stress(coords, conn, dN_ref, D_table, material_index, u, stress_out, info):
    """Linear elastic stresses ``sigma = D B u_e`` (Pa) at the points of the tables.

    Parameters
    ----------
    coords, conn, D_table, material_index, u : as in :func:`continuum_internal_force`.
    dN_ref : (n_pt, dim, nen) float64
        Natural derivatives at the output points (integration points, or nodes for plotting).
    stress_out : (n_elem, n_pt, n_strain) float64
        Output, Pa: 2D ``[sxx, syy, sxy]`` (plane strain ``szz`` is not included),
        3D ``[sxx, syy, szz, sxy, syz, szx]``.

    Returns a status code (see module docstring; the Jacobian test applies at the output points).
    """
    return _stress_impl(coords, conn, dN_ref, D_table, material_index, u, stress_out, info, dimension_tag(coords))
