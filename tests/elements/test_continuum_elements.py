"""Verification of the isoparametric continuum kernels (``masonrydam.elements.continuum``) and of the
linear elastic material (``masonrydam.materials.elastic``).

Checks and their sources:

- patch test (B.M. Irons & A. Razzaque 1972; R.H. MacNeal & R.L. Harder, "A proposed standard set of
  problems to test finite element accuracy", Finite Elem. Anal. Des. 1 (1985) 3-20, Fig. 2 patch);
- rigid-body modes, symmetry and rank of the stiffness (Bathe, *Finite Element Procedures*, 2014,
  sec. 5.3; Hughes, *The Finite Element Method*, 2000, sec. 4.5);
- stiffness = derivative of the internal force (central differences);
- consistent nodal loads of a body force and the known nodal fractions of quad8 / quad9 / tri6
  (Cook, Malkus, Plesha & Witt, *Concepts and Applications of FEA*, 4th ed. 2002, sec. 6.6 and 7.4);
- consistent and HRZ-lumped mass (Hinton, Rock & Zienkiewicz, Earthquake Eng. Struct. Dyn. 4 (1976)
  245-249; fractions 3/76, 16/76 for quad8 and 3/57, 16/57 for tri6, Cook et al. 2002, sec. 11.3);
- bad Jacobians (inverted, degenerate) and NaN status codes (``masonrydam.errors``);
- convergence for the end-loaded cantilever against the exact plane-stress elasticity solution of
  Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed. 1970, sec. 21 (in the form of Augarde & Deeks,
  Finite Elem. Anal. Des. 44 (2008) 595-601, eq. 1-2);
- a light 3D check (hex8 / tet4 tables built here) that the same kernels work in 3D.

All assembly here is a small dense (or scipy.sparse for the cantilever) assembler written in this
module, independent of the package's assembly code.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from masonrydam.elements import quadrature, shapes
from masonrydam.elements.continuum import (
    continuum_body_force,
    continuum_internal_force,
    continuum_mass,
    continuum_stiffness,
    continuum_stress,
    element_tables,
)
from masonrydam.errors import STATUS_BAD_JACOBIAN, STATUS_NAN, STATUS_OK
from masonrydam.materials.elastic import elasticity_matrix

TYPES_2D = ("tri3", "tri6", "quad4", "quad8", "quad9")
HYPOTHESES_2D = ("plane_stress", "plane_strain")
QUADRATIC = ("tri6", "quad8", "quad9")
#: rules exact for N_a N_b on straight-sided elements (consistent mass)
MASS_RULE = {"tri3": 3, "tri6": 6, "quad4": None, "quad8": None, "quad9": None}


# --------------------------------------------------------------------------------------------------
# Small helpers: kernel calls and a dense assembler
# --------------------------------------------------------------------------------------------------


def _D(hypothesis, E=1.0e6, nu=0.25):
    return elasticity_matrix(E, nu, hypothesis)[None].copy()


def _info():
    return np.zeros(1, dtype=np.int64)


def stiffness(coords, conn, name, D, thickness=1.0, n_gauss=None):
    _, dN, w = element_tables(name, n_gauss)
    ne, nen = conn.shape
    nd = nen * coords.shape[1]
    ke = np.zeros((ne, nd, nd))
    info = _info()
    st = continuum_stiffness(coords, conn, dN, w, D, np.zeros(ne, np.int64), np.full(ne, thickness), ke, info)
    return st, ke, info


def internal_force(coords, conn, name, D, u, thickness=1.0):
    _, dN, w = element_tables(name)
    ne, nen = conn.shape
    fe = np.zeros((ne, nen * coords.shape[1]))
    info = _info()
    st = continuum_internal_force(
        coords, conn, dN, w, D, np.zeros(ne, np.int64), np.full(ne, thickness), u, fe, info
    )
    return st, fe, info


def element_dofs(nodes, dim):
    return (np.asarray(nodes)[:, None] * dim + np.arange(dim)).ravel()


def assemble_matrix(blocks, conn, n_dof, dim):
    K = np.zeros((n_dof, n_dof))
    for e, nodes in enumerate(conn):
        d = element_dofs(nodes, dim)
        K[np.ix_(d, d)] += blocks[e]
    return K


def assemble_vector(blocks, conn, n_dof, dim):
    f = np.zeros(n_dof)
    for e, nodes in enumerate(conn):
        np.add.at(f, element_dofs(nodes, dim), blocks[e])
    return f


def jacobian_dets(coords, conn, name, n_gauss=None):
    """det J at the integration points, computed here with numpy (independent of the kernels)."""
    _, dN, _ = element_tables(name, n_gauss)
    xe = coords[conn]  # (ne, nen, dim)
    J = np.einsum("gia,eaj->egij", dN, xe)
    return np.linalg.det(J)


# --------------------------------------------------------------------------------------------------
# Geometries
# --------------------------------------------------------------------------------------------------

#: MacNeal & Harder (1985) patch: 0.24 x 0.12 rectangle, four distorted interior nodes.
MH_CORNERS = np.array([[0.0, 0.0], [0.24, 0.0], [0.24, 0.12], [0.0, 0.12]])
MH_INTERIOR = np.array([[0.04, 0.02], [0.18, 0.03], [0.16, 0.08], [0.08, 0.08]])
MH_QUADS = np.array([[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [4, 5, 6, 7]])
MH_W, MH_H = 0.24, 0.12


def _add_mid_nodes(coords, conn_lin, edges_local, centre=False, curve=0.0):
    """Quadratic connectivity from a linear one: one node per edge (at the midpoint, shifted by
    ``curve`` times the edge length normal to interior edges), optional centre node (quad9)."""
    coords = [tuple(c) for c in coords]
    edge_node = {}
    is_boundary = {}
    # count element sharing of each edge: an edge seen once is a boundary edge
    count = {}
    for el in conn_lin:
        for a, b in edges_local:
            key = tuple(sorted((el[a], el[b])))
            count[key] = count.get(key, 0) + 1
    out = []
    for el in conn_lin:
        row = list(el)
        for a, b in edges_local:
            key = tuple(sorted((el[a], el[b])))
            if key not in edge_node:
                pa, pb = np.array(coords[key[0]]), np.array(coords[key[1]])
                mid = 0.5 * (pa + pb)
                if count[key] > 1 and curve:
                    t = pb - pa
                    mid = mid + curve * np.array([-t[1], t[0]])
                edge_node[key] = len(coords)
                is_boundary[key] = count[key] == 1
                coords.append(tuple(mid))
            row.append(edge_node[key])
        if centre:
            # centre of the bilinear map = mean of the corners (plus the curve offset of the mids)
            corners = np.array([coords[n] for n in el])
            mids = np.array([coords[n] for n in row[4:8]])
            c = 0.5 * mids.mean(axis=0) + 0.5 * corners.mean(axis=0) if curve else corners.mean(axis=0)
            coords.append(tuple(c))
            row.append(len(coords) - 1)
        out.append(row)
    return np.ascontiguousarray(coords, dtype=np.float64), np.ascontiguousarray(out, dtype=np.int64)


def mh_patch(name, curve=0.0):
    """MacNeal-Harder patch meshed with element type ``name`` (triangles: each quad split in two)."""
    coords = np.vstack([MH_CORNERS, MH_INTERIOR])
    quads = MH_QUADS
    if name in ("tri3", "tri6"):
        lin = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        if name == "tri3":
            return np.ascontiguousarray(coords), np.ascontiguousarray(lin, dtype=np.int64)
        return _add_mid_nodes(coords, lin, ((0, 1), (1, 2), (2, 0)), curve=curve)
    if name == "quad4":
        return np.ascontiguousarray(coords), np.ascontiguousarray(quads, dtype=np.int64)
    edges = ((0, 1), (1, 2), (2, 3), (3, 0))
    return _add_mid_nodes(coords, quads, edges, centre=(name == "quad9"), curve=curve)


def single_element(name):
    """One distorted element of type ``name`` (reference nodes through a bilinear map)."""
    ref = shapes.reference_nodes(name)
    xi, eta = ref[:, 0], ref[:, 1]
    x = 1.0 + 2.0 * xi + 0.3 * eta + 0.2 * xi * eta
    y = 0.5 + 0.1 * xi + 1.5 * eta - 0.15 * xi * eta
    coords = np.ascontiguousarray(np.stack([x, y], axis=1))
    return coords, np.arange(len(ref), dtype=np.int64)[None, :]


def boundary_mask(coords, w=MH_W, h=MH_H, tol=1e-12):
    x, y = coords[:, 0], coords[:, 1]
    return (np.abs(x) < tol) | (np.abs(x - w) < tol) | (np.abs(y) < tol) | (np.abs(y - h) < tol)


def linear_field(coords):
    """MacNeal & Harder (1985) patch field plus a translation: u = 1e-3 (1 + x + y/2), v = 1e-3 (2 + y + x/2)."""
    x, y = coords[:, 0], coords[:, 1]
    u = 1e-3 * (1.0 + x + 0.5 * y)
    v = 1e-3 * (2.0 + y + 0.5 * x)
    return np.stack([u, v], axis=1).ravel()


LINEAR_STRAIN = np.array([1e-3, 1e-3, 1e-3])  # exx, eyy, gxy of linear_field


# --------------------------------------------------------------------------------------------------
# Material
# --------------------------------------------------------------------------------------------------


def test_elasticity_matrix_forms():
    """Plane strain = rows/columns (xx, yy, xy) of the 3D matrix; plane stress = 3D matrix with
    szz = 0 condensed out (Zienkiewicz, Taylor & Zhu 2013, sec. 6.2)."""
    E, nu = 30e9, 0.2
    D3 = elasticity_matrix(E, nu, "3d")
    assert D3.shape == (6, 6) and np.allclose(D3, D3.T)
    idx = [0, 1, 3]
    assert np.allclose(elasticity_matrix(E, nu, "plane_strain"), D3[np.ix_(idx, idx)], rtol=1e-14)
    cond = D3[np.ix_(idx, idx)] - np.outer(D3[idx, 2], D3[2, idx]) / D3[2, 2]
    assert np.allclose(elasticity_matrix(E, nu, "plane_stress"), cond, rtol=1e-13)
    G = E / (2 * (1 + nu))
    assert np.isclose(D3[3, 3], G) and np.isclose(elasticity_matrix(E, nu, "plane_stress")[2, 2], G)
    # uniaxial stress: sigma = E eps_xx with eps_yy = -nu eps_xx (plane stress)
    s = elasticity_matrix(E, nu, "plane_stress") @ np.array([1e-4, -nu * 1e-4, 0.0])
    assert np.allclose(s, [E * 1e-4, 0.0, 0.0], atol=1e-6)


@pytest.mark.parametrize(
    "E, nu, hyp, word",
    [
        (0.0, 0.2, "plane_stress", "youngs_modulus"),
        (-1.0, 0.2, "3d", "youngs_modulus"),
        (float("nan"), 0.2, "3d", "youngs_modulus"),
        (1.0, 0.5, "plane_strain", "poisson_ratio"),
        (1.0, 0.5, "plane_stress", "poisson_ratio"),
        (1.0, -1.0, "3d", "poisson_ratio"),
        (1.0, 0.2, "axisymmetric", "hypothesis"),
    ],
)
def test_elasticity_matrix_validation(E, nu, hyp, word):
    with pytest.raises(ValueError, match=word):
        elasticity_matrix(E, nu, hyp)


def test_element_tables():
    for name in TYPES_2D:
        N, dN, w = element_tables(name)
        area = 0.5 if name.startswith("tri") else 4.0
        assert np.isclose(w.sum(), area)
        assert np.allclose(N.sum(axis=1), 1.0) and np.allclose(dN.sum(axis=2), 0.0, atol=1e-13)
        assert N.flags.c_contiguous and dN.flags.c_contiguous and dN.shape[1] == 2


# --------------------------------------------------------------------------------------------------
# Patch test, rigid-body modes, rank, symmetry, finite differences
# --------------------------------------------------------------------------------------------------


def _patch_cases():
    cases = []
    for name in TYPES_2D:
        for hyp in HYPOTHESES_2D:
            cases.append((name, hyp, 0.0))
            if name in QUADRATIC:
                cases.append((name, hyp, 0.04))  # curved interior edges (isoparametric)
    return cases


@pytest.mark.parametrize("name, hyp, curve", _patch_cases())
def test_patch_test(name, hyp, curve):
    """Irons patch test on the MacNeal-Harder patch: the linear field imposed on the boundary is
    reproduced at the interior nodes and the stress is constant (= D eps) at every Gauss point.
    ``curve = 0``: straight edges, mid-nodes at midpoints; ``curve > 0``: curved interior edges."""
    coords, conn = mh_patch(name, curve)
    assert (jacobian_dets(coords, conn, name) > 0).all()
    D = _D(hyp)
    st, ke, _ = stiffness(coords, conn, name, D, thickness=0.001)
    assert st == STATUS_OK
    n_dof = coords.size
    K = assemble_matrix(ke, conn, n_dof, 2)
    u_exact = linear_field(coords)
    fixed = np.repeat(boundary_mask(coords), 2)
    free = ~fixed
    assert free.sum() >= 8  # interior nodes exist
    u = u_exact.copy()
    u[free] = np.linalg.solve(K[np.ix_(free, free)], -K[np.ix_(free, fixed)] @ u_exact[fixed])
    assert np.max(np.abs(u - u_exact)) <= 1e-10 * np.max(np.abs(u_exact))
    # constant stress at the Gauss points
    _, dN, _ = element_tables(name)
    sig = np.zeros((conn.shape[0], dN.shape[0], 3))
    info = _info()
    assert continuum_stress(coords, conn, dN, D, np.zeros(len(conn), np.int64), u, sig, info) == STATUS_OK
    s_exact = D[0] @ LINEAR_STRAIN
    assert np.allclose(sig, s_exact, rtol=0, atol=1e-10 * np.abs(s_exact).max())
    # interior nodes are in equilibrium with no external load
    st, fe, _ = internal_force(coords, conn, name, D, u, thickness=0.001)
    f = assemble_vector(fe, conn, n_dof, 2)
    assert np.max(np.abs(f[free])) <= 1e-10 * np.max(np.abs(f))


def _rigid_modes(coords, theta=1e-3):
    x, y = coords[:, 0], coords[:, 1]
    tx = np.stack([np.ones_like(x), np.zeros_like(x)], 1).ravel()
    ty = np.stack([np.zeros_like(x), np.ones_like(x)], 1).ravel()
    rot = (theta * np.stack([-y, x], 1)).ravel()
    return tx, ty, rot


@pytest.mark.parametrize("hyp", HYPOTHESES_2D)
@pytest.mark.parametrize("name", TYPES_2D)
def test_rigid_body_zero_force(name, hyp):
    """Two translations and the infinitesimal rotation u = theta (-y, x) produce no strain, hence no
    internal force (single distorted element and the MacNeal-Harder patch)."""
    D = _D(hyp)
    for coords, conn in (single_element(name), mh_patch(name)):
        st, ke, _ = stiffness(coords, conn, name, D)
        K = assemble_matrix(ke, conn, coords.size, 2)
        for u in _rigid_modes(coords):
            st, fe, _ = internal_force(coords, conn, name, D, u)
            assert st == STATUS_OK
            f = assemble_vector(fe, conn, coords.size, 2)
            scale = np.abs(K).max() * np.abs(u).max()
            assert np.abs(f).max() <= 1e-10 * scale
            assert np.abs(K @ u).max() <= 1e-10 * scale


@pytest.mark.parametrize("hyp", HYPOTHESES_2D)
@pytest.mark.parametrize("name", TYPES_2D)
def test_stiffness_symmetry_and_rank(name, hyp):
    """Full integration: K symmetric, positive semi-definite with exactly 3 zero eigenvalues in 2D
    (the rigid-body modes; Hughes 2000, sec. 4.5)."""
    coords, conn = single_element(name)
    st, ke, _ = stiffness(coords, conn, name, _D(hyp))
    assert st == STATUS_OK
    K = ke[0]
    assert np.array_equal(K, K.T)
    lam = np.linalg.eigvalsh(K)
    assert lam.min() > -1e-10 * lam.max()
    assert np.sum(np.abs(lam) < 1e-10 * lam.max()) == 3
    # thickness scales the 2D stiffness linearly
    st, ke2, _ = stiffness(coords, conn, name, _D(hyp), thickness=0.3)
    assert np.allclose(ke2, 0.3 * ke, rtol=1e-13, atol=1e-13 * np.abs(ke).max())


@pytest.mark.parametrize("hyp", HYPOTHESES_2D)
@pytest.mark.parametrize("name", TYPES_2D)
def test_stiffness_is_derivative_of_internal_force(name, hyp):
    """K[:, j] = (f(u + h e_j) - f(u - h e_j)) / 2h (central differences), and f = K u."""
    coords, conn = mh_patch(name, curve=0.05 if name in QUADRATIC else 0.0)
    D = _D(hyp)
    rng = np.random.default_rng(1)
    n_dof = coords.size
    u0 = 1e-3 * rng.standard_normal(n_dof)
    st, ke, _ = stiffness(coords, conn, name, D)
    K = assemble_matrix(ke, conn, n_dof, 2)
    _, fe, _ = internal_force(coords, conn, name, D, u0)
    assert np.allclose(assemble_vector(fe, conn, n_dof, 2), K @ u0, rtol=0, atol=1e-12 * np.abs(K).max() * 1e-3)
    h = 1e-6
    Kfd = np.zeros_like(K)
    for j in range(n_dof):
        up, um = u0.copy(), u0.copy()
        up[j] += h
        um[j] -= h
        _, fp, _ = internal_force(coords, conn, name, D, up)
        _, fm, _ = internal_force(coords, conn, name, D, um)
        Kfd[:, j] = (assemble_vector(fp, conn, n_dof, 2) - assemble_vector(fm, conn, n_dof, 2)) / (2 * h)
    assert np.abs(Kfd - K).max() <= 1e-6 * np.abs(K).max()


def test_kernels_are_deterministic():
    coords, conn = mh_patch("quad8", curve=0.05)
    D = _D("plane_stress")
    _, ke1, _ = stiffness(coords, conn, "quad8", D)
    _, ke2, _ = stiffness(coords, conn, "quad8", D)
    assert np.array_equal(ke1, ke2)


def test_material_index_selects_D():
    coords, conn = mh_patch("quad4")
    N, dN, w = element_tables("quad4")
    D = np.concatenate([_D("plane_stress", E=1.0), _D("plane_stress", E=7.0)])
    mi = np.array([0, 1, 0, 1, 1], dtype=np.int64)
    ke = np.zeros((5, 8, 8))
    assert continuum_stiffness(coords, conn, dN, w, D, mi, np.ones(5), ke, _info()) == STATUS_OK
    _, ke1, _ = stiffness(coords, conn, "quad4", D[:1])
    assert np.allclose(ke, ke1 * np.where(mi == 1, 7.0, 1.0)[:, None, None], rtol=1e-13)


# --------------------------------------------------------------------------------------------------
# Body force and mass
# --------------------------------------------------------------------------------------------------

#: consistent nodal fractions of a uniform body force on a straight-sided element (Cook et al. 2002)
BODY_FRACTIONS = {
    "tri3": [1 / 3] * 3,
    "tri6": [0.0] * 3 + [1 / 3] * 3,
    "quad4": [1 / 4] * 4,
    "quad8": [-1 / 12] * 4 + [1 / 3] * 4,
    "quad9": [1 / 36] * 4 + [1 / 9] * 4 + [4 / 9],
}


@pytest.mark.parametrize("name", TYPES_2D)
def test_body_force(name):
    """Gravity rho g on the patch: total nodal load = rho g A t; nodal fractions of one
    parallelogram element match the textbook values."""
    rho, g, t = 2400.0, 9.81, 0.35
    coords, conn = mh_patch(name)
    N, dN, w = element_tables(name)
    ne, nen = conn.shape
    bf = np.tile([0.0, -rho * g], (ne, 1))
    fe = np.zeros((ne, nen * 2))
    st = continuum_body_force(coords, conn, N, dN, w, bf, np.full(ne, t), fe, _info())
    assert st == STATUS_OK
    f = assemble_vector(fe, conn, coords.size, 2)
    W = rho * g * MH_W * MH_H * t
    assert np.isclose(f[1::2].sum(), -W, rtol=1e-12)
    assert abs(f[0::2].sum()) <= 1e-12 * W
    # one parallelogram element (affine map of the reference element): known nodal fractions
    ref = shapes.reference_nodes(name)
    c1 = np.ascontiguousarray(ref @ np.array([[2.0, 0.1], [0.4, 1.5]]))
    conn1 = np.arange(nen, dtype=np.int64)[None]
    area = abs(np.linalg.det([[2.0, 0.1], [0.4, 1.5]])) * (0.5 if name.startswith("tri") else 4.0)
    fe1 = np.zeros((1, nen * 2))
    st = continuum_body_force(c1, conn1, N, dN, w, np.array([[0.0, -rho * g]]), np.array([t]), fe1, _info())
    assert st == STATUS_OK
    assert np.allclose(fe1[0, 1::2], -rho * g * area * t * np.array(BODY_FRACTIONS[name]), rtol=1e-12, atol=1e-9)


#: HRZ lumped fractions on straight-sided elements (Hinton, Rock & Zienkiewicz 1976; Cook et al. 2002)
HRZ_FRACTIONS = {
    "tri3": [1 / 3] * 3,
    "tri6": [3 / 57] * 3 + [16 / 57] * 3,
    "quad4": [1 / 4] * 4,
    "quad8": [3 / 76] * 4 + [16 / 76] * 4,
    "quad9": [1 / 36] * 4 + [1 / 9] * 4 + [4 / 9],
}


@pytest.mark.parametrize("name", TYPES_2D)
def test_mass(name):
    """Consistent mass: symmetric, positive definite, total rho A t per direction, no x-y coupling.
    HRZ lumped: diagonal, all positive (quad8 corners too), total rho A t per direction, nodal
    fractions as published."""
    rho, t = 2400.0, 0.35
    coords, conn = mh_patch(name)
    N, dN, w = element_tables(name, MASS_RULE[name])
    ne, nen = conn.shape
    nd = 2 * nen
    mass = rho * MH_W * MH_H * t
    out = {}
    for lumped in (False, True):
        me = np.zeros((ne, nd, nd))
        st = continuum_mass(coords, conn, N, dN, w, np.full(ne, rho), np.full(ne, t), lumped, me, _info())
        assert st == STATUS_OK
        M = assemble_matrix(me, conn, coords.size, 2)
        assert np.array_equal(M, M.T)
        assert np.isclose(M[0::2, 0::2].sum(), mass, rtol=1e-12)
        assert np.isclose(M[1::2, 1::2].sum(), mass, rtol=1e-12)
        assert np.abs(M[0::2, 1::2]).max() == 0.0
        out[lumped] = (me, M)
    me_c, M_c = out[False]
    assert np.linalg.eigvalsh(M_c).min() > 0
    me_l, M_l = out[True]
    assert np.count_nonzero(M_l - np.diag(np.diag(M_l))) == 0
    assert (np.diag(M_l) > 0).all()
    # HRZ per element: proportional to the consistent diagonal
    for e in range(ne):
        dc, dl = np.diag(me_c[e]), np.diag(me_l[e])
        assert np.allclose(dl / dl.sum(), dc / dc.sum(), rtol=1e-12)
    # published fractions on one parallelogram element
    ref = shapes.reference_nodes(name)
    c1 = np.ascontiguousarray(ref @ np.array([[2.0, 0.1], [0.4, 1.5]]))
    me1 = np.zeros((1, nd, nd))
    conn1 = np.arange(nen, dtype=np.int64)[None]
    st = continuum_mass(c1, conn1, N, dN, w, np.array([rho]), np.array([t]), True, me1, _info())
    d = np.diag(me1[0])[0::2]
    assert np.allclose(d / d.sum(), HRZ_FRACTIONS[name], rtol=1e-12)


# --------------------------------------------------------------------------------------------------
# Bad Jacobians and NaN
# --------------------------------------------------------------------------------------------------


def _three_elements_with_bad_one(name, kind):
    """Three copies of a valid element; element 1 is mirrored (``kind="inverted"``: clockwise node
    order), collapsed to a line (``"collapsed"``), nearly collapsed (``"sliver"``, det J ~ 1e-14 h^2)
    or left valid (any other ``kind``)."""
    c, conn = single_element(name)
    nen = c.shape[0]
    bad = c.copy()
    if kind == "inverted":
        bad[:, 0] = -bad[:, 0]
    elif kind == "collapsed":
        bad[:, 1] = 0.0
    elif kind == "sliver":
        bad[:, 1] = 1e-14 * bad[:, 1]
    coords = np.ascontiguousarray(np.vstack([c, bad, c + 5.0]))
    conn3 = np.ascontiguousarray(np.vstack([conn, conn + nen, conn + 2 * nen]))
    return coords, conn3


def _call_all_kernels(coords, conn, name):
    N, dN, w = element_tables(name)
    ne, nen = conn.shape
    nd = 2 * nen
    D = _D("plane_stress")
    mi, th = np.zeros(ne, np.int64), np.ones(ne)
    u = np.zeros(coords.size)
    res = []
    info = _info()
    res.append((continuum_stiffness(coords, conn, dN, w, D, mi, th, np.zeros((ne, nd, nd)), info), info[0]))
    info = _info()
    res.append((continuum_internal_force(coords, conn, dN, w, D, mi, th, u, np.zeros((ne, nd)), info), info[0]))
    info = _info()
    bf = np.ones((ne, 2))
    res.append((continuum_body_force(coords, conn, N, dN, w, bf, th, np.zeros((ne, nd)), info), info[0]))
    for lumped in (False, True):
        info = _info()
        me = np.zeros((ne, nd, nd))
        res.append((continuum_mass(coords, conn, N, dN, w, np.ones(ne), th, lumped, me, info), info[0]))
    info = _info()
    sig = np.zeros((ne, dN.shape[0], 3))
    res.append((continuum_stress(coords, conn, dN, D, mi, u, sig, info), info[0]))
    return res


@pytest.mark.parametrize("kind", ["inverted", "collapsed", "sliver"])
@pytest.mark.parametrize("name", TYPES_2D)
def test_bad_jacobian(name, kind):
    coords, conn = _three_elements_with_bad_one(name, kind)
    for status, index in _call_all_kernels(coords, conn, name):
        assert status == STATUS_BAD_JACOBIAN
        assert index == 1


def test_nan_status():
    coords, conn = _three_elements_with_bad_one("quad4", "valid")
    coords[conn[2, 1], 0] = np.nan
    for status, index in _call_all_kernels(coords, conn, "quad4"):
        assert status == STATUS_NAN and index == 2
    # NaN in the material data: caught in the output block
    coords, conn = _three_elements_with_bad_one("quad4", "valid")
    _, dN, w = element_tables("quad4")
    D = np.concatenate([_D("plane_stress"), _D("plane_stress")])
    D[1, 0, 1] = D[1, 1, 0] = np.nan
    info = _info()
    st = continuum_stiffness(
        coords, conn, dN, w, D, np.array([0, 0, 1], np.int64), np.ones(3), np.zeros((3, 8, 8)), info
    )
    assert st == STATUS_NAN and info[0] == 2


# --------------------------------------------------------------------------------------------------
# Cantilever convergence (Timoshenko & Goodier exact solution)
# --------------------------------------------------------------------------------------------------

L_BEAM, H_BEAM, E_BEAM, NU_BEAM, P_BEAM = 10.0, 1.0, 1000.0, 0.25, 1.0
I_BEAM = H_BEAM**3 / 12.0  # t = 1


def beam_exact(x, y):
    """Exact plane-stress displacements of the cantilever x in [0, L], y in [-h/2, h/2] with an end
    shear P (parabolic traction at x = L; Timoshenko & Goodier 1970, sec. 21; Augarde & Deeks 2008):

    u = -P y / (6 E I) [(6 L - 3 x) x + (2 + nu)(y^2 - h^2/4)]
    v =  P / (6 E I) [3 nu y^2 (L - x) + (4 + 5 nu) h^2 x / 4 + (3 L - x) x^2]

    so that v(L, 0) = P L^3 / (3 E I) + (4 + 5 nu) P L / (2 E h) (bending + shear).
    """
    P, E, I, nu, L, h = P_BEAM, E_BEAM, I_BEAM, NU_BEAM, L_BEAM, H_BEAM
    u = -P * y / (6 * E * I) * ((6 * L - 3 * x) * x + (2 + nu) * (y**2 - h**2 / 4))
    v = P / (6 * E * I) * (3 * nu * y**2 * (L - x) + (4 + 5 * nu) * h**2 * x / 4 + (3 * L - x) * x**2)
    return u, v


def beam_shear_traction(y):
    """t_y = tau_xy(L, y) = P / (2 I) (h^2/4 - y^2); integrates to P over the end face."""
    return P_BEAM / (2 * I_BEAM) * (H_BEAM**2 / 4 - y**2)


def test_beam_exact_solution_is_consistent():
    """The closed form satisfies the plane-stress Hooke law with the stresses
    sxx = -P (L - x) y / I, syy = 0, sxy = tau (checked by finite differences)."""
    D = elasticity_matrix(E_BEAM, NU_BEAM, "plane_stress")
    rng = np.random.default_rng(0)
    for x, y in zip(rng.uniform(0, L_BEAM, 5), rng.uniform(-0.5, 0.5, 5)):
        h = 1e-5
        ux = (np.array(beam_exact(x + h, y)) - np.array(beam_exact(x - h, y))) / (2 * h)
        uy = (np.array(beam_exact(x, y + h)) - np.array(beam_exact(x, y - h))) / (2 * h)
        eps = np.array([ux[0], uy[1], uy[0] + ux[1]])
        sig = D @ eps
        expected = [-P_BEAM * (L_BEAM - x) * y / I_BEAM, 0.0, beam_shear_traction(y)]
        assert np.allclose(sig, expected, atol=1e-6)
    xg, wg = np.polynomial.legendre.leggauss(3)  # exact for the quadratic traction on [-h/2, h/2]
    assert np.isclose(beam_shear_traction(xg * H_BEAM / 2) @ (wg * H_BEAM / 2), P_BEAM)


def beam_mesh(name, nx, ny):
    """Structured quad4 / quad8 mesh of [0, L] x [-h/2, h/2]; returns coords, conn, tip edges
    (line2 / line3 node order) and the node at (L, 0)."""
    step = 1 if name == "quad4" else 2
    gx, gy = step * nx + 1, step * ny + 1
    X, Y = np.meshgrid(np.linspace(0, L_BEAM, gx), np.linspace(-H_BEAM / 2, H_BEAM / 2, gy), indexing="ij")
    gid = np.arange(gx * gy).reshape(gx, gy)
    conn, edges = [], []
    for i in range(nx):
        for j in range(ny):
            a, b = step * i, step * j
            s = step
            corners = [gid[a, b], gid[a + s, b], gid[a + s, b + s], gid[a, b + s]]
            if name == "quad4":
                conn.append(corners)
                if i == nx - 1:
                    edges.append([gid[a + s, b], gid[a + s, b + s]])
            else:
                mids = [gid[a + 1, b], gid[a + 2, b + 1], gid[a + 1, b + 2], gid[a, b + 1]]
                conn.append(corners + mids)
                if i == nx - 1:
                    edges.append([gid[a + 2, b], gid[a + 2, b + 2], gid[a + 2, b + 1]])
    conn = np.array(conn)
    used, inv = np.unique(conn, return_inverse=True)
    remap = np.full(gx * gy, -1)
    remap[used] = np.arange(len(used))
    coords = np.ascontiguousarray(np.stack([X.ravel()[used], Y.ravel()[used]], 1))
    tip = remap[gid[-1, (gy - 1) // 2]]
    assert abs(coords[tip, 0] - L_BEAM) < 1e-12 and abs(coords[tip, 1]) < 1e-12
    return coords, remap[conn].astype(np.int64), remap[np.array(edges)], tip


def beam_tip_deflection(name, nx, ny):
    coords, conn, edges, tip = beam_mesh(name, nx, ny)
    D = elasticity_matrix(E_BEAM, NU_BEAM, "plane_stress")[None].copy()
    st, ke, _ = stiffness(coords, conn, name, D, thickness=1.0)
    assert st == STATUS_OK
    n_dof = coords.size
    dofs = np.stack([element_dofs(c, 2) for c in conn])
    nd = dofs.shape[1]
    K = sp.coo_matrix(
        (ke.ravel(), (np.repeat(dofs, nd, axis=1).ravel(), np.tile(dofs, (1, nd)).ravel())), shape=(n_dof, n_dof)
    ).tocsr()
    # consistent nodal loads of the parabolic end traction (4-point Gauss along each edge)
    f = np.zeros(n_dof)
    line = "line2" if name == "quad4" else "line3"
    xg, wg = quadrature.line_rule("gauss", 4)
    Nl, dNl = shapes.shape_functions(line, xg)
    for edge in edges:
        ye = coords[edge, 1]
        yg = Nl @ ye
        ds = np.abs(dNl[:, 0, :] @ ye)
        np.add.at(f, edge * 2 + 1, Nl.T @ (wg * ds * beam_shear_traction(yg)))
    assert np.isclose(f.sum(), P_BEAM, rtol=1e-12)
    # exact displacements imposed at x = 0 (all dofs there prescribed)
    u = np.zeros(n_dof)
    fixed_nodes = np.flatnonzero(np.abs(coords[:, 0]) < 1e-12)
    ux0, uy0 = beam_exact(coords[fixed_nodes, 0], coords[fixed_nodes, 1])
    u[2 * fixed_nodes], u[2 * fixed_nodes + 1] = ux0, uy0
    fixed = np.zeros(n_dof, bool)
    fixed[2 * fixed_nodes] = fixed[2 * fixed_nodes + 1] = True
    free = ~fixed
    rhs = f[free] - K[free][:, fixed] @ u[fixed]
    u[free] = spla.spsolve(K[free][:, free].tocsc(), rhs)
    return u[2 * tip + 1]


@pytest.mark.parametrize(
    "name, base, min_order, final_tol",
    [("quad4", (10, 2), 1.8, 0.01), ("quad8", (4, 1), 3.0, 0.005)],
)
def test_cantilever_convergence(name, base, min_order, final_tol):
    """Tip deflection v(L, 0) on 4 meshes (h halved 3 times) vs the exact solution
    v = P L^3/(3EI) + (4 + 5 nu) P L/(2 E h) (Timoshenko & Goodier 1970, sec. 21). Theory (Strang & Fix;
    Hughes 2000, sec. 4.1): displacement-type output errors of order h^2 for quad4 and at least h^3
    for quad8 (h^4 for energy-like quantities); the last mesh pair must show the asymptotic rate."""
    exact = beam_exact(L_BEAM, 0.0)[1]
    assert np.isclose(
        exact, P_BEAM * L_BEAM**3 / (3 * E_BEAM * I_BEAM) + (4 + 5 * NU_BEAM) * P_BEAM * L_BEAM / (2 * E_BEAM * H_BEAM)
    )
    errors = []
    for k in range(4):
        nx, ny = base[0] * 2**k, base[1] * 2**k
        errors.append(abs(beam_tip_deflection(name, nx, ny) - exact) / abs(exact))
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert (np.diff(errors) < 0).all(), errors
    assert orders[-1] >= min_order, (errors, orders)
    assert errors[-1] <= final_tol, errors


# --------------------------------------------------------------------------------------------------
# 3D: the same kernels with hex8 / tet4 tables built here
# --------------------------------------------------------------------------------------------------

HEX_CORNERS = np.array(
    [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float
)


def hex8_tables():
    """Trilinear hex8 (Hughes 2000, sec. 3.5) at 2x2x2 Gauss points."""
    pts, w = quadrature.tensor_rule("gauss", 2, 3)
    c = HEX_CORNERS
    f = 1 + pts[:, None, :] * c[None, :, :]  # (g, a, 3)
    N = 0.125 * f.prod(axis=2)
    dN = np.empty((len(pts), 3, 8))
    for i in range(3):
        others = [j for j in range(3) if j != i]
        dN[:, i, :] = 0.125 * c[None, :, i] * f[:, :, others[0]] * f[:, :, others[1]]
    return np.ascontiguousarray(N), np.ascontiguousarray(dN), np.ascontiguousarray(w)


def tet4_tables():
    """Linear tetrahedron, one point (volume of the reference tet 1/6)."""
    N = np.full((1, 4), 0.25)
    dN = np.array([[[-1.0, 1, 0, 0], [-1.0, 0, 1, 0], [-1.0, 0, 0, 1]]])
    return N, dN, np.array([1 / 6])


def hex_cube_mesh(n=2, perturb=0.12):
    """n^3 hex8 mesh of the unit cube; interior nodes displaced (distorted patch)."""
    g = np.linspace(0, 1, n + 1)
    X, Y, Z = np.meshgrid(g, g, g, indexing="ij")
    coords = np.stack([X.ravel(), Y.ravel(), Z.ravel()], 1)
    gid = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)
    conn = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                conn.append(
                    [gid[i + di, j + dj, k + dk] for (di, dj, dk) in ((HEX_CORNERS + 1) / 2).astype(int)]
                )
    interior = np.all((coords > 1e-12) & (coords < 1 - 1e-12), axis=1)
    rng = np.random.default_rng(3)
    coords[interior] += perturb / n * rng.uniform(-1, 1, (interior.sum(), 3))
    return np.ascontiguousarray(coords), np.array(conn, dtype=np.int64), ~interior


def test_3d_hex8_and_tet4():
    """Same kernels in 3D: patch test with distorted interior nodes, 6 rigid modes, symmetry,
    volume / mass / body-force totals, inverted element detection."""
    D = elasticity_matrix(1e6, 0.3, "3d")[None].copy()
    N, dN, w = hex8_tables()
    coords, conn, bnd = hex_cube_mesh()
    ne = len(conn)
    mi, th = np.zeros(ne, np.int64), np.ones(ne)
    ke = np.zeros((ne, 24, 24))
    assert continuum_stiffness(coords, conn, dN, w, D, mi, th, ke, _info()) == STATUS_OK
    assert all(np.array_equal(k, k.T) for k in ke)
    lam = np.linalg.eigvalsh(ke[0])
    assert np.sum(np.abs(lam) < 1e-10 * lam.max()) == 6
    K = assemble_matrix(ke, conn, coords.size, 3)
    # patch test: linear field on the boundary, interior node solved
    B = 1e-3 * np.array([[1.0, 0.5, 0.2], [0.3, -1.0, 0.4], [0.1, 0.6, 2.0]])
    u_exact = (1e-3 + coords @ B.T).ravel()
    fixed = np.repeat(bnd, 3)
    u = u_exact.copy()
    u[~fixed] = np.linalg.solve(K[np.ix_(~fixed, ~fixed)], -K[np.ix_(~fixed, fixed)] @ u_exact[fixed])
    assert np.abs(u - u_exact).max() <= 1e-10 * np.abs(u_exact).max()
    eps = np.array([B[0, 0], B[1, 1], B[2, 2], B[0, 1] + B[1, 0], B[1, 2] + B[2, 1], B[2, 0] + B[0, 2]])
    sig = np.zeros((ne, 8, 6))
    assert continuum_stress(coords, conn, dN, D, mi, u, sig, _info()) == STATUS_OK
    assert np.allclose(sig, D[0] @ eps, rtol=0, atol=1e-10 * np.abs(D[0] @ eps).max())
    # rigid modes: 3 translations + 3 infinitesimal rotations
    theta = 1e-3
    for axis in range(3):
        t = np.zeros(3)
        t[axis] = 1.0
        W = np.zeros((3, 3))
        i, j = [(0, 1), (1, 2), (2, 0)][axis]
        W[i, j], W[j, i] = -theta, theta
        for umode in (np.tile(t, len(coords)), (coords @ W.T).ravel()):
            fe = np.zeros((ne, 24))
            assert continuum_internal_force(coords, conn, dN, w, D, mi, th, umode, fe, _info()) == STATUS_OK
            assert np.abs(assemble_vector(fe, conn, coords.size, 3)).max() <= 1e-10 * np.abs(K).max()
    # mass and body force totals (volume 1); thickness ignored in 3D
    for lumped in (False, True):
        me = np.zeros((ne, 24, 24))
        assert continuum_mass(coords, conn, N, dN, w, np.full(ne, 2.0), np.full(ne, 9.0), lumped, me, _info()) == 0
        M = assemble_matrix(me, conn, coords.size, 3)
        assert np.isclose(M[2::3, 2::3].sum(), 2.0, rtol=1e-12)
    fe = np.zeros((ne, 24))
    bf = np.tile([0.0, 0.0, -3.0], (ne, 1))
    assert continuum_body_force(coords, conn, N, dN, w, bf, np.full(ne, 9.0), fe, _info()) == STATUS_OK
    assert np.isclose(fe[:, 2::3].sum(), -3.0, rtol=1e-12)
    # inverted hex (mirror) -> bad Jacobian at its index
    c2 = coords.copy()
    c2[:, 2] *= -1
    info = _info()
    assert continuum_stiffness(c2, conn, dN, w, D, mi, th, ke, info) == STATUS_BAD_JACOBIAN and info[0] == 0
    # tet4: constant strain element, 6 zero eigenvalues, K from an affine tet
    Nt, dNt, wt = tet4_tables()
    ct = np.array([[0.0, 0, 0], [1.0, 0.1, 0], [0.2, 1.0, 0.1], [0.1, 0.2, 1.3]])
    kt = np.zeros((1, 12, 12))
    assert continuum_stiffness(ct, np.arange(4)[None], dNt, wt, D, mi[:1], th[:1], kt, _info()) == STATUS_OK
    lam = np.linalg.eigvalsh(kt[0])
    assert np.sum(np.abs(lam) < 1e-10 * lam.max()) == 6 and lam.min() > -1e-10 * lam.max()
