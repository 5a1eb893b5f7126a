"""Verification of the 3D solid element types hex8, hex20, tet4, tet10 (``masonrydam.elements.shapes``,
``quadrature.tetrahedron_rule``) with the dimension-generic continuum kernels, and of the 3D branch of
``masonrydam.assembly.model.check_corners``.

Checks and their sources:

- shape functions: Kronecker property, partition of unity, derivatives (Zienkiewicz, Taylor & Zhu,
  *The Finite Element Method: Its Basis and Fundamentals*, 7th ed. 2013, ch. 6; Hughes, *The Finite
  Element Method*, 2000, sec. 3.5);
- quadrature exactness against closed-form monomial integrals: on the unit tetrahedron
  ``int xi^a eta^b zeta^c dV = a! b! c! / (a + b + c + 3)!`` (the Dirichlet integral, e.g. ZTZ 2013
  ch. 6), on [-1, 1]^3 the product of ``int_{-1}^{1} x^k dx = (1 + (-1)^k) / (k + 1)``;
- node orderings against gmsh (API element properties, one generated hex20 and tet10) and meshio (its
  gmsh reader);
- facets: outward normals and closure via the divergence theorem ``V = 1/3 oint x . n dA``;
- patch test on distorted meshes (B.M. Irons & A. Razzaque 1972; R.H. MacNeal & R.L. Harder, "A
  proposed standard set of problems to test finite element accuracy", Finite Elem. Anal. Des. 1 (1985)
  3-20, whose 3D patch is a distorted unit cube with fixed boundary and a linear displacement field);
- rigid-body modes and rank of K (Bathe, *Finite Element Procedures*, 2014, sec. 5.3; Hughes 2000,
  sec. 4.5); spurious modes of reduced integration (D.P. Flanagan & T. Belytschko, IJNME 17 (1981)
  679-706: 12 hourglass modes of one-point hex8);
- K = d f_int / d u (central differences);
- consistent mass in closed form (tet4 ``rho V / 20 (1 + delta_ab)`` and tet10, both from the
  tetrahedron integral ``int L1^a L2^b L3^c L4^d dV = 6 V a! b! c! d! / (a + b + c + d + 3)!``, ZTZ 2013 ch. 6)
  and HRZ lumping (Hinton, Rock & Zienkiewicz, Earthquake Eng. Struct. Dyn. 4 (1976) 245-249);
- cantilever tip deflection vs Euler-Bernoulli + Timoshenko shear correction (S.P. Timoshenko &
  J.M. Gere, *Mechanics of Materials*; Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed. 1970,
  sec. 21 for the shear term; shear coefficient of a rectangle kappa = 10 (1 + nu) / (12 + 11 nu),
  G.R. Cowper, J. Appl. Mech. 33 (1966) 335-340);
- inverted / collapsed elements: kernel status code and ``check_corners``.

Assembly here is a small dense (or scipy.sparse for the cantilever) assembler written in this module.
"""
from __future__ import annotations

import itertools
import math
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from masonrydam.assembly.model import check_corners
from masonrydam.elements import quadrature, shapes
from masonrydam.elements.continuum import (
    continuum_internal_force,
    continuum_mass,
    continuum_stiffness,
    continuum_stress,
    element_tables,
)
from masonrydam.errors import STATUS_BAD_JACOBIAN, STATUS_OK, MeshError
from masonrydam.materials.elastic import elasticity_matrix

TYPES_3D = ("hex8", "hex20", "tet4", "tet10")
LINEAR_OF = {"hex8": "hex8", "hex20": "hex8", "tet4": "tet4", "tet10": "tet4"}
#: consistent-mass rules exact for N_a N_b on affine elements (points per direction / in total)
MASS_RULE = {"hex8": 2, "hex20": 3, "tet4": 4, "tet10": 14}
E_MOD, NU = 30.0e9, 0.3  # Pa, concrete-like


def _D(E=E_MOD, nu=NU):
    return elasticity_matrix(E, nu, "3d")[None].copy()


def _info():
    return np.zeros(1, dtype=np.int64)


def element_dofs(nodes):
    return (np.asarray(nodes)[:, None] * 3 + np.arange(3)).ravel()


def assemble_dense(blocks, conn, n_dof):
    K = np.zeros((n_dof, n_dof))
    for e, nodes in enumerate(conn):
        d = element_dofs(nodes)
        K[np.ix_(d, d)] += blocks[e]
    return K


def assemble_vector(blocks, conn, n_dof):
    f = np.zeros(n_dof)
    for e, nodes in enumerate(conn):
        np.add.at(f, element_dofs(nodes), blocks[e])
    return f


def stiffness(coords, conn, name, n_gauss=None):
    _, dN, w = element_tables(name, n_gauss)
    ne, nen = conn.shape
    ke = np.zeros((ne, 3 * nen, 3 * nen))
    info = _info()
    st = continuum_stiffness(coords, conn, dN, w, _D(), np.zeros(ne, np.int64), np.ones(ne), ke, info)
    return st, ke, info


def internal_force(coords, conn, name, u, n_gauss=None):
    _, dN, w = element_tables(name, n_gauss)
    ne, nen = conn.shape
    fe = np.zeros((ne, 3 * nen))
    st = continuum_internal_force(coords, conn, dN, w, _D(), np.zeros(ne, np.int64), np.ones(ne), u, fe, _info())
    assert st == STATUS_OK
    return fe


def mass(coords, conn, name, rho, lumped, n_gauss=None):
    N, dN, w = element_tables(name, n_gauss)
    ne, nen = conn.shape
    me = np.zeros((ne, 3 * nen, 3 * nen))
    st = continuum_mass(coords, conn, N, dN, w, np.full(ne, rho), np.ones(ne), lumped, me, _info())
    assert st == STATUS_OK
    return me


# --------------------------------------------------------------------------------------------------
# Meshes: structured hex8 grid, Kuhn split into tets, mid-edge nodes for the quadratic types
# --------------------------------------------------------------------------------------------------

#: bits (x, y, z) of the hex8 corners in our (VTK) order
HEX_BITS = ((shapes.reference_nodes("hex8") + 1) / 2).astype(int)


def hex_grid(n, lengths=(1.0, 1.0, 1.0), perturb=0.0, seed=7):
    """Structured hex8 mesh of the box [0, Lx] x [0, Ly] x [0, Lz] with n = (nx, ny, nz) cells;
    interior nodes displaced by up to ``perturb`` times the local cell size in each direction."""
    n = np.broadcast_to(n, 3)
    axes = [np.linspace(0.0, L, k + 1) for L, k in zip(lengths, n)]
    X = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    gid = np.arange(len(X)).reshape(*(n + 1))
    conn = [
        [gid[i + b[0], j + b[1], k + b[2]] for b in HEX_BITS]
        for i in range(n[0])
        for j in range(n[1])
        for k in range(n[2])
    ]
    lo, hi = np.zeros(3), np.asarray(lengths, float)
    tol = 1e-12 * hi.max()
    interior = np.all((X > lo + tol) & (X < hi - tol), axis=1)
    if perturb:
        rng = np.random.default_rng(seed)
        X[interior] += perturb * (hi / n) * rng.uniform(-1.0, 1.0, (interior.sum(), 3))
    return np.ascontiguousarray(X), np.array(conn, dtype=np.int64)


def kuhn_tets(hex_conn):
    """Split every hex8 into 6 tetrahedra around its diagonal 0-6 (Kuhn / Freudenthal subdivision),
    conforming on a structured grid; each tet positively oriented on an undistorted grid."""
    index = {tuple(b): a for a, b in enumerate(HEX_BITS)}
    local = []
    for perm in itertools.permutations(range(3)):
        v = np.zeros(3, int)
        path = [index[tuple(v)]]
        for axis in perm:
            v[axis] = 1
            path.append(index[tuple(v)])
        # volume sign = sign of the axis permutation: swap for odd ones
        inversions = sum(perm[i] > perm[j] for i in range(3) for j in range(i + 1, 3))
        if inversions % 2:
            path[1], path[2] = path[2], path[1]
        local.append(path)
    return np.ascontiguousarray(hex_conn[:, local].reshape(-1, 4))


def add_mid_nodes(coords, conn_lin, quad_type):
    """Quadratic mesh from a linear one: one node at the midpoint of every edge, numbered with the
    ``edges`` table (end, end, mid-node) of ``quad_type``."""
    edges = shapes.ELEMENT_TYPES[quad_type].edges
    nen = shapes.ELEMENT_TYPES[quad_type].n_nodes
    new_coords = list(coords)
    edge_node = {}
    conn = np.zeros((len(conn_lin), nen), dtype=np.int64)
    conn[:, : conn_lin.shape[1]] = conn_lin
    for e, el in enumerate(conn_lin):
        for a, b, m in edges:
            key = (min(el[a], el[b]), max(el[a], el[b]))
            if key not in edge_node:
                edge_node[key] = len(new_coords)
                new_coords.append(0.5 * (coords[el[a]] + coords[el[b]]))
            conn[e, m] = edge_node[key]
    return np.ascontiguousarray(new_coords), conn


def make_mesh(name, n, lengths=(1.0, 1.0, 1.0), perturb=0.0):
    coords, conn = hex_grid(n, lengths, perturb)
    if shapes.ELEMENT_TYPES[name].family == "tet":
        conn = kuhn_tets(conn)
    if shapes.ELEMENT_TYPES[name].order == 2:
        coords, conn = add_mid_nodes(coords, conn, name)
    return coords, conn


def single_element(name):
    """One distorted (non-affine for hexes), positively oriented element with straight edges."""
    if LINEAR_OF[name] == "hex8":
        x = (shapes.reference_nodes("hex8") + 1) / 2 * np.array([1.0, 0.8, 1.3])
        x += np.array([[0.05, 0, 0.02], [0, 0.1, 0], [0.1, 0, -0.05], [0, 0, 0], [0, -0.05, 0.1],
                       [0.1, 0.05, 0], [0, 0, 0.12], [-0.06, 0, 0]])
    else:
        x = np.array([[0.0, 0, 0], [1.0, 0.1, 0], [0.2, 1.1, 0.1], [0.1, 0.2, 1.3]])
    conn = np.arange(len(x), dtype=np.int64)[None]
    if shapes.ELEMENT_TYPES[name].order == 2:
        return add_mid_nodes(x, conn, name)
    return np.ascontiguousarray(x), conn


def rigid_modes(coords):
    """(6, n_dof): 3 unit translations and 3 infinitesimal rotations u = w x (x - x_c)."""
    xc = coords - coords.mean(axis=0)
    modes = []
    for axis in range(3):
        t = np.zeros(3)
        t[axis] = 1.0
        modes.append(np.tile(t, len(coords)))
    for axis in range(3):
        w = np.zeros(3)
        w[axis] = 1.0
        modes.append(np.cross(w, xc).ravel())
    return np.array(modes)


# --------------------------------------------------------------------------------------------------
# Shape functions and quadrature
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", TYPES_3D)
def test_shape_functions(name):
    """N_a(x_b) = delta_ab, sum_a N_a = 1, sum_a dN_a = 0, linear completeness sum_a N_a x_a = x,
    derivatives vs central differences; reference volume from the default weights (8, 1/6)."""
    et = shapes.ELEMENT_TYPES[name]
    X = shapes.reference_nodes(name)
    assert X.shape == (et.n_nodes, 3) and et.dim == 3 and et.family in ("hex", "tet")
    N, dN = shapes.shape_functions(name, X)
    assert np.allclose(N, np.eye(et.n_nodes), rtol=0, atol=1e-14)
    rng = np.random.default_rng(1)
    if et.family == "hex":
        p = rng.uniform(-1, 1, (50, 3))
    else:
        p = rng.dirichlet(np.ones(4), 50)[:, 1:]
    N, dN = shapes.shape_functions(name, p)
    assert N.flags.c_contiguous and dN.flags.c_contiguous and dN.shape == (50, 3, et.n_nodes)
    assert np.allclose(N.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    assert np.allclose(dN.sum(axis=2), 0.0, rtol=0, atol=1e-13)
    assert np.allclose(N @ X, p, rtol=0, atol=1e-14)  # isoparametric completeness
    assert np.allclose(np.einsum("gia,aj->gij", dN, X), np.eye(3), rtol=0, atol=1e-13)
    h = 1e-6
    for i in range(3):
        d = np.zeros(3)
        d[i] = h
        fd = (shapes.shape_functions(name, p + d)[0] - shapes.shape_functions(name, p - d)[0]) / (2 * h)
        assert np.allclose(fd, dN[:, i, :], rtol=0, atol=1e-8)
    _, w = shapes.integration_rule(name)
    assert np.isclose(w.sum(), 8.0 if et.family == "hex" else 1.0 / 6.0, rtol=1e-14)
    assert len(w) == {"hex8": 8, "hex20": 27, "tet4": 1, "tet10": 4}[name]
    # serendipity / quadratic-tet nodal integrals: negative corners (ZTZ 2013 ch. 6; Cook et al. 2002
    # sec. 11.3): hex20 int N_corner = -1, int N_mid = 4/3 on [-1,1]^3; tet10 -1/120 and 1/30 (V = 1/6)
    if et.order == 2:
        p, w = shapes.integration_rule(name, 3 if et.family == "hex" else 14)
        integral = w @ shapes.shape_functions(name, p)[0]
        corner, mid = (-1.0, 4.0 / 3.0) if et.family == "hex" else (-1.0 / 120.0, 1.0 / 30.0)
        assert np.allclose(integral[: et.corner_nodes], corner, rtol=1e-13)
        assert np.allclose(integral[et.corner_nodes :], mid, rtol=1e-13)


def _tet_monomial(a, b, c):
    return math.factorial(a) * math.factorial(b) * math.factorial(c) / math.factorial(a + b + c + 3)


@pytest.mark.parametrize("n_points, degree", [(1, 1), (4, 2), (14, 5)])
def test_tetrahedron_rule_exactness(n_points, degree):
    """All monomials xi^a eta^b zeta^c of total degree <= p are integrated to 1e-14 against
    a! b! c! / (a+b+c+3)!; positive weights, points inside; and the rule is not exact for all of
    degree p + 1 (so the stated degree is the true one)."""
    p, w = quadrature.tetrahedron_rule(n_points)
    assert p.shape == (n_points, 3) and (w > 0).all()
    L = np.column_stack([1 - p.sum(axis=1), p])
    assert (L > 0).all()
    worst_next = 0.0
    for a in range(degree + 2):
        for b in range(degree + 2 - a):
            for c in range(degree + 2 - a - b):
                err = abs(w @ (p[:, 0] ** a * p[:, 1] ** b * p[:, 2] ** c) - _tet_monomial(a, b, c))
                rel = err / _tet_monomial(a, b, c)
                if a + b + c <= degree:
                    assert rel < 1e-13, (a, b, c, rel)
                else:
                    worst_next = max(worst_next, rel)
    assert worst_next > 1e-6
    with pytest.raises(ValueError):
        quadrature.tetrahedron_rule(5)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_hex_tensor_rule_exactness(n):
    """n x n x n Gauss-Legendre is exact for xi^a eta^b zeta^c with a, b, c <= 2n - 1."""
    p, w = shapes.integration_rule("hex8", n)
    assert len(w) == n**3
    for a, b, c in itertools.product(range(2 * n), repeat=3):
        exact = np.prod([(1 + (-1) ** k) / (k + 1) for k in (a, b, c)])
        assert abs(w @ (p[:, 0] ** a * p[:, 1] ** b * p[:, 2] ** c) - exact) < 1e-14


# --------------------------------------------------------------------------------------------------
# Node orderings (gmsh, meshio) and facets
# --------------------------------------------------------------------------------------------------


def test_gmsh_reference_nodes_and_meshio_order(tmp_path):
    """The reference nodes of gmsh's elements permuted by GMSH_TO_MESHIO_ORDER equal ours; one
    hex20 and one tet10 generated with the gmsh API have, after that permutation, their nodes where
    our reference_nodes put them under the corner map; meshio's gmsh reader gives our order directly."""
    gmsh = pytest.importorskip("gmsh")
    meshio = pytest.importorskip("meshio")
    gmsh_type = {"hex8": 5, "hex20": 17, "tet4": 4, "tet10": 11}
    for name, perm in shapes.GMSH_TO_MESHIO_ORDER.items():
        assert sorted(perm) == list(range(shapes.ELEMENT_TYPES[name].n_nodes))
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        for name, t in gmsh_type.items():
            props = gmsh.model.mesh.getElementProperties(t)
            local = np.array(props[4]).reshape(-1, 3)[shapes.GMSH_TO_MESHIO_ORDER[name]]
            assert np.allclose(local, shapes.reference_nodes(name)), name
        generated = {}
        for name, box in (("hex20", (0.3, -0.2, 0.1, 2.0, 3.0, 5.0)), ("tet10", (0.0, 0.0, 0.0, 1.0, 2.0, 0.5))):
            gmsh.model.add(name)
            gmsh.model.occ.addBox(*box)
            gmsh.model.occ.synchronize()
            if name == "hex20":
                for _, tag in gmsh.model.getEntities(1):
                    gmsh.model.mesh.setTransfiniteCurve(tag, 2)
                for _, tag in gmsh.model.getEntities(2):
                    gmsh.model.mesh.setTransfiniteSurface(tag)
                    gmsh.model.mesh.setRecombine(2, tag)
                gmsh.model.mesh.setTransfiniteVolume(1)
            else:
                gmsh.option.setNumber("Mesh.MeshSizeMin", 10.0)
                gmsh.option.setNumber("Mesh.MeshSizeMax", 10.0)
            gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
            gmsh.model.addPhysicalGroup(3, [1], 1)
            gmsh.model.mesh.generate(3)
            gmsh.model.mesh.setOrder(2)
            tags, xyz, _ = gmsh.model.mesh.getNodes()
            pos = dict(zip(tags.tolist(), np.array(xyz).reshape(-1, 3)))
            _, enodes = gmsh.model.mesh.getElementsByType(gmsh_type[name])
            nen = shapes.ELEMENT_TYPES[name].n_nodes
            enodes = np.array(enodes, dtype=np.int64).reshape(-1, nen)
            assert len(enodes) >= 1
            path = tmp_path / f"{name}.msh"
            gmsh.write(str(path))
            generated[name] = (np.array([[pos[k] for k in el] for el in enodes]), path)
    finally:
        gmsh.finalize()
    for name, (xg, path) in generated.items():
        lin = LINEAR_OF[name]
        Nc, _ = shapes.shape_functions(lin, shapes.reference_nodes(name))  # corner map at our nodes
        ours = xg[:, shapes.GMSH_TO_MESHIO_ORDER[name]]
        expected = np.einsum("ka,eaj->ekj", Nc, ours[:, : Nc.shape[1]])
        assert np.allclose(ours, expected, atol=1e-12), name
        assert not np.allclose(xg, expected, atol=1e-12)  # gmsh's own order differs
        m = meshio.read(str(path))
        cells = np.vstack([cb.data for cb in m.cells if cb.type == shapes.ELEMENT_TYPES[name].meshio_name])
        assert shapes.MESHIO_TO_TYPE[shapes.ELEMENT_TYPES[name].meshio_name] == name
        xm = m.points[cells]
        assert np.allclose(xm, np.einsum("ka,eaj->ekj", Nc, xm[:, : Nc.shape[1]]), atol=1e-12), name
        # positively oriented as produced by gmsh
        check_corners(m.points, SimpleNamespace(name=name, type=name, conn=cells))


def _face_integrals(x_face, ftype):
    """oint n dA (3,) and oint x . n dA over one face with its own shape functions (n: right-hand rule)."""
    if ftype.startswith("quad"):
        p, w = quadrature.tensor_rule("gauss", 4, 2)
    else:
        p, w = quadrature.triangle_rule(6)
    N, dN = shapes.shape_functions(ftype, p)
    x = N @ x_face
    t = np.einsum("gia,aj->gij", dN, x_face)
    n_dA = np.cross(t[:, 0], t[:, 1]) * w[:, None]
    return n_dA.sum(axis=0), np.einsum("gj,gj->", x, n_dA)


@pytest.mark.parametrize("name", TYPES_3D)
def test_facets_outward_and_closed(name):
    """Every face normal points out of the element (face centroid - element centroid along n > 0),
    the faces close the element (oint n dA = 0) and the divergence theorem V = 1/3 oint x . n dA gives
    the element volume int det J dV; quadratic faces list their mid-edge nodes in quad8 / tri6 order;
    every element edge lies on exactly two faces, traversed in opposite directions."""
    et = shapes.ELEMENT_TYPES[name]
    n_faces, ftype = {"hex8": (6, "quad4"), "hex20": (6, "quad8"), "tet4": (4, "tri3"), "tet10": (4, "tri6")}[name]
    assert len(et.facets) == n_faces and all(f == ftype for f, _ in et.facets)
    assert len(et.edges) == (12 if et.family == "hex" else 6)
    assert all(len(e) == (2 if et.order == 1 else 3) for e in et.edges)
    x, conn = single_element(name)
    xe = x[conn[0]]
    p, w = shapes.integration_rule(name, 3 if et.family == "hex" else 4)
    _, dN = shapes.shape_functions(name, p)
    volume = w @ np.linalg.det(np.einsum("gia,aj->gij", dN, xe))
    total_n, flux = np.zeros(3), 0.0
    directed = []
    for ft, nodes in et.facets:
        nodes = list(nodes)
        fe = shapes.ELEMENT_TYPES[ft]
        assert len(nodes) == fe.n_nodes
        nA, xn = _face_integrals(xe[nodes], ft)
        assert (xe[nodes].mean(axis=0) - xe.mean(axis=0)) @ nA > 0
        total_n += nA
        flux += xn
        nc = fe.corner_nodes
        for k in range(nc):
            directed.append((nodes[k], nodes[(k + 1) % nc]))
            if fe.order == 2:  # mid-edge node of face edge k is the element's mid-node of that edge
                mid = [m for a, b, m in et.edges if {a, b} == {nodes[k], nodes[(k + 1) % nc]}]
                assert mid == [nodes[nc + k]]
    assert np.allclose(total_n, 0.0, atol=1e-13)
    assert np.isclose(flux / 3.0, volume, rtol=1e-12)
    assert len(set(directed)) == len(directed) == 2 * len(et.edges)
    assert all((b, a) in directed for a, b in directed)
    assert {frozenset(e[:2]) for e in et.edges} == {frozenset(d) for d in directed}


def test_facets_2d_are_the_edges():
    """2D facets: the edges, as line2 / line3, with the outward normal on the right of the
    counter-clockwise edge direction (divergence theorem A = 1/2 oint x . n ds)."""
    for name in shapes.CONTINUUM_TYPES_2D:
        et = shapes.ELEMENT_TYPES[name]
        assert [nodes for _, nodes in et.facets] == [tuple(e) for e in et.edges]
        assert {f for f, _ in et.facets} == {"line2" if et.order == 1 else "line3"}
        X = shapes.reference_nodes(name)
        p, w = quadrature.line_rule("gauss", 3)
        flux = 0.0
        for ft, nodes in et.facets:
            N, dN = shapes.shape_functions(ft, p)
            t = dN[:, 0, :] @ X[list(nodes)]
            n_ds = np.column_stack([t[:, 1], -t[:, 0]]) * w[:, None]  # outward: tangent turned clockwise
            flux += np.einsum("gj,gj->", N @ X[list(nodes)], n_ds)
        area = 0.5 if et.family == "tri" else 4.0
        assert np.isclose(flux / 2.0, area, rtol=1e-14), name
    assert shapes.CONTINUUM_TYPES_3D == TYPES_3D
    for name in TYPES_3D:
        assert shapes.MESHIO_TO_TYPE[shapes.ELEMENT_TYPES[name].meshio_name] == name


# --------------------------------------------------------------------------------------------------
# Patch test, rigid modes, K = df/du
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", TYPES_3D)
def test_patch_test_distorted(name):
    """MacNeal & Harder (1985) style 3D patch: unit cube, 3x3x3 cells with all 8 interior grid nodes
    moved (tets: Kuhn split of the same grid; quadratic: straight edges, mid-nodes at midpoints).
    A linear field u = c + A x imposed on the boundary nodes must be reproduced at all interior nodes
    and give the exact constant stress D eps(A) at every integration point (1e-10 relative)."""
    coords, conn = make_mesh(name, 3, perturb=0.25)
    check_corners(coords, SimpleNamespace(name="patch", type=name, conn=conn))  # valid mesh
    n_dof = coords.size
    st, ke, _ = stiffness(coords, conn, name)
    assert st == STATUS_OK
    K = assemble_dense(ke, conn, n_dof)
    A = 1e-3 * np.array([[1.0, 0.5, 0.2], [0.3, -1.0, 0.4], [0.1, 0.6, 2.0]])
    c = np.array([1e-3, -2e-3, 0.5e-3])
    u_exact = (c + coords @ A.T).ravel()
    bnd = np.any((coords < 1e-12) | (coords > 1 - 1e-12), axis=1)
    assert (~bnd).sum() >= (8 if shapes.ELEMENT_TYPES[name].order == 1 else 40)
    fixed = np.repeat(bnd, 3)
    u = u_exact.copy()
    u[~fixed] = np.linalg.solve(K[np.ix_(~fixed, ~fixed)], -K[np.ix_(~fixed, fixed)] @ u_exact[fixed])
    assert np.abs(u - u_exact).max() <= 1e-10 * np.abs(u_exact).max()
    eps = np.array([A[0, 0], A[1, 1], A[2, 2], A[0, 1] + A[1, 0], A[1, 2] + A[2, 1], A[2, 0] + A[0, 2]])
    D = _D()
    sig_exact = D[0] @ eps
    _, dN, w = element_tables(name)
    sig = np.zeros((len(conn), len(w), 6))
    assert continuum_stress(coords, conn, dN, D, np.zeros(len(conn), np.int64), u, sig, _info()) == STATUS_OK
    assert np.abs(sig - sig_exact).max() <= 1e-10 * np.abs(sig_exact).max()
    # interior equilibrium: no residual force at free dofs
    f = assemble_vector(internal_force(coords, conn, name, u), conn, n_dof)
    assert np.abs(f[~fixed]).max() <= 1e-10 * np.abs(f).max()


@pytest.mark.parametrize("name, n_gauss, n_zero", [
    ("hex8", None, 6), ("hex20", None, 6), ("tet4", None, 6), ("tet10", None, 6),
    ("hex8", 1, 18),  # 6 rigid + 12 hourglass modes (Flanagan & Belytschko 1981)
    ("hex20", 2, 12),  # 2x2x2: rank <= 6 x 8 = 48 of 60 dofs -> 6 spurious modes
])
def test_rigid_modes_and_rank(name, n_gauss, n_zero):
    """Single distorted element: 3 translations + 3 infinitesimal rotations give zero internal force;
    K is symmetric positive semi-definite with exactly 6 zero eigenvalues under full integration
    (more with reduced integration: rank K <= 6 n_gp)."""
    x, conn = single_element(name)
    st, ke, _ = stiffness(x, conn, name, n_gauss)
    assert st == STATUS_OK
    k = ke[0]
    assert np.array_equal(k, k.T)
    lam = np.linalg.eigvalsh(k)
    tol = 1e-10 * lam.max()
    assert lam.min() > -tol
    assert np.sum(lam < tol) == n_zero
    for mode in rigid_modes(x):
        f = internal_force(x, conn, name, mode, n_gauss)[0]
        assert np.abs(f).max() <= 1e-10 * lam.max() * np.abs(mode).max()
        assert np.abs(k @ mode).max() <= 1e-10 * lam.max() * np.abs(mode).max()


@pytest.mark.parametrize("name", TYPES_3D)
def test_stiffness_is_derivative_of_internal_force(name):
    """K u == f_int(u) and every column of K equals the central difference of f_int (linear elasticity,
    so the difference quotient is exact up to rounding)."""
    x, conn = single_element(name)
    _, ke, _ = stiffness(x, conn, name)
    rng = np.random.default_rng(5)
    u = 1e-3 * rng.standard_normal(x.size)
    f = internal_force(x, conn, name, u)[0]
    scale = np.abs(ke[0]).max()
    assert np.allclose(f, ke[0] @ u, rtol=0, atol=1e-12 * scale * np.abs(u).max())
    h = 1e-6
    fd = np.empty_like(ke[0])
    for j in range(x.size):
        du = np.zeros(x.size)
        du[j] = h
        fd[:, j] = (internal_force(x, conn, name, u + du)[0] - internal_force(x, conn, name, u - du)[0]) / (2 * h)
    assert np.allclose(fd, ke[0], rtol=0, atol=1e-7 * scale)


# --------------------------------------------------------------------------------------------------
# Mass
# --------------------------------------------------------------------------------------------------


def tet10_mass_closed_form(volume, rho):
    """Consistent tet10 mass (per direction) from int L1^a L2^b L3^c L4^d dV = 6V a!b!c!d!/(a+b+c+d+3)!:
    times rho V / 420: corner diagonal 6, corner-corner 1, corner / mid-node of an edge through that
    corner -4, corner / opposite mid-node -6, mid diagonal 32, mid-mids sharing a vertex 16, else 8."""
    edges = [set(e[:2]) for e in shapes.ELEMENT_TYPES["tet10"].edges]
    M = np.empty((10, 10))
    for a in range(10):
        for b in range(10):
            if a < 4 and b < 4:
                M[a, b] = 6 if a == b else 1
            elif a >= 4 and b >= 4:
                M[a, b] = 32 if a == b else (16 if edges[a - 4] & edges[b - 4] else 8)
            else:
                c, m = (a, b) if a < 4 else (b, a)
                M[a, b] = -4 if c in edges[m - 4] else -6
    return M * rho * volume / 420.0


def _tet_volume(x):
    return np.linalg.det(x[1:4] - x[0]) / 6.0


@pytest.mark.parametrize("name", TYPES_3D)
def test_consistent_mass(name):
    """Consistent mass (rule exact for N_a N_b): total per direction rho V, no coupling between
    directions, and the closed forms: tet4 rho V/20 (1 + delta_ab), tet10 above; hexes: the default
    rule equals a higher one on a parallelepiped; nodal row sums of the quadratic types are negative
    at the corners (hex20: -1/8 rho V on a parallelepiped, tet10: -1/20 rho V), which is why HRZ is used."""
    rho = 2400.0
    x, conn = single_element(name)
    if shapes.ELEMENT_TYPES[name].family == "hex":
        # parallelepiped (affine): sheared box
        X = shapes.reference_nodes(name)
        x = np.ascontiguousarray(((X + 1) / 2) @ np.array([[1.0, 0.1, 0.0], [0.2, 0.8, 0.1], [0.1, 0.0, 1.3]]))
        V = np.linalg.det(np.array([[1.0, 0.1, 0.0], [0.2, 0.8, 0.1], [0.1, 0.0, 1.3]]))
    else:
        V = _tet_volume(x[:4])
    me = mass(x, conn, name, rho, False, MASS_RULE[name])[0]
    nen = conn.shape[1]
    m = me[0::3, 0::3]
    assert np.allclose(me[1::3, 1::3], m) and np.allclose(me[2::3, 2::3], m)
    assert np.abs(me[0::3, 1::3]).max() == 0.0
    assert np.isclose(m.sum(), rho * V, rtol=1e-13)
    if name == "tet4":
        assert np.allclose(m, rho * V / 20 * (np.ones((4, 4)) + np.eye(4)), rtol=1e-13)
    elif name == "tet10":
        assert np.allclose(m, tet10_mass_closed_form(V, rho), rtol=1e-12, atol=1e-13 * rho * V)
        assert np.allclose(m.sum(axis=1)[:4], -rho * V / 20, rtol=1e-12)
    else:
        m_hi = mass(x, conn, name, rho, False, MASS_RULE[name] + 2)[0][0::3, 0::3]
        assert np.allclose(m, m_hi, rtol=1e-12, atol=1e-14 * rho * V)
        if name == "hex20":
            assert np.allclose(m.sum(axis=1)[:8], -rho * V / 8, rtol=1e-12)
    assert m.shape == (nen, nen)


@pytest.mark.parametrize("name", TYPES_3D)
def test_hrz_lumped_mass(name):
    """HRZ lumped mass: diagonal, positive at every node (also the hex20 / tet10 corners whose row-sum
    masses are negative), total rho V per direction, and the exact nodal fractions: hex8 1/8, tet4 1/4;
    tet10 corners 1/36, mid-nodes 4/27 (int N_c^2 = V/70, int N_m^2 = 8V/105 from the tetrahedron
    integral formula); hex20 on a parallelepiped corners 7/248, mid-nodes 2/31 (int N_c^2 = 28/135,
    int N_m^2 = 64/135 on [-1,1]^3, from 1D moments int_0^2 u^k du = 2^(k+1)/(k+1) after u = 1 + xi)."""
    rho = 2400.0
    x, conn = single_element(name)
    et = shapes.ELEMENT_TYPES[name]
    if et.family == "hex":  # distorted element: positivity and total; fractions below on a box
        N, dN, w = element_tables(name)
        V = w @ np.linalg.det(np.einsum("gia,aj->gij", dN, x[conn[0]]))
    else:
        V = _tet_volume(x[:4])
    me = mass(x, conn, name, rho, True, MASS_RULE[name])[0]
    assert np.count_nonzero(me - np.diag(np.diag(me))) == 0
    d = np.diag(me)
    assert (d > 0).all()
    assert np.allclose(d[0::3], d[1::3]) and np.allclose(d[0::3], d[2::3])
    assert np.isclose(d[0::3].sum(), rho * V, rtol=1e-12)
    frac = {"hex8": (1 / 8, None), "hex20": (7 / 248, 2 / 31), "tet4": (1 / 4, None), "tet10": (1 / 36, 4 / 27)}[name]
    if et.family == "hex":
        x = np.ascontiguousarray((shapes.reference_nodes(name) + 1) / 2 * np.array([1.0, 0.5, 2.0]))
        V = 1.0
        d = np.diag(mass(x, conn, name, rho, True)[0])
    nc = et.corner_nodes
    assert np.allclose(d[0 : 3 * nc : 3], frac[0] * rho * V, rtol=1e-12)
    if frac[1] is not None:
        assert np.allclose(d[3 * nc :: 3], frac[1] * rho * V, rtol=1e-12)


# --------------------------------------------------------------------------------------------------
# Cantilever
# --------------------------------------------------------------------------------------------------

L_B, B_B, H_B = 1.0, 0.1, 0.1  # m: length (x), width (y), depth (z)
P_B = -1.0e3  # N, tip shear in z


def cantilever_tip(name, n):
    """Work-conjugate tip deflection f . u / P of a cantilever clamped at x = 0 (all dofs) with a
    uniform shear traction P / (b h) in z on the end face x = L (consistent nodal loads integrated on
    the x+ facet of the end elements with the facet's own shape functions)."""
    coords, conn = make_mesh(name, n, (L_B, B_B, H_B))
    n_dof = coords.size
    st, ke, _ = stiffness(coords, conn, name)
    assert st == STATUS_OK
    nd = ke.shape[1]
    dofs = np.stack([element_dofs(c) for c in conn])
    K = sp.csr_matrix(
        (ke.ravel(), (np.repeat(dofs, nd, axis=1).ravel(), np.tile(dofs, (1, nd)).ravel())), shape=(n_dof, n_dof)
    )
    ftype, face = shapes.ELEMENT_TYPES[name].facets[1]  # x+ face of the hexes
    p, w = quadrature.tensor_rule("gauss", 3, 2)
    Nf, dNf = shapes.shape_functions(ftype, p)
    f = np.zeros(n_dof)
    area = np.zeros(3)
    for el in conn:
        nodes = el[list(face)]
        xf = coords[nodes]
        if not np.allclose(xf[:, 0], L_B):
            continue
        t = np.einsum("gia,aj->gij", dNf, xf)
        nA = np.cross(t[:, 0], t[:, 1]) * w[:, None]
        area += nA.sum(axis=0)
        np.add.at(f, nodes * 3 + 2, Nf.T @ (np.linalg.norm(nA, axis=1) * P_B / (B_B * H_B)))
    assert np.allclose(area, [B_B * H_B, 0, 0], rtol=1e-12, atol=1e-15)  # outward normal +x
    assert np.isclose(f.sum(), P_B, rtol=1e-12)
    free = np.repeat(coords[:, 0] > 1e-12, 3)
    u = np.zeros(n_dof)
    u[free] = spla.spsolve(K[free][:, free].tocsc(), f[free])
    return f @ u / P_B


def beam_reference():
    """Euler-Bernoulli + Timoshenko shear: P L^3/(3 E I) + P L/(kappa G A), I = b h^3/12,
    kappa = 10 (1 + nu)/(12 + 11 nu) (Cowper 1966)."""
    I = B_B * H_B**3 / 12
    G = E_MOD / (2 * (1 + NU))
    kappa = 10 * (1 + NU) / (12 + 11 * NU)
    return P_B * L_B**3 / (3 * E_MOD * I) + P_B * L_B / (kappa * G * B_B * H_B)


@pytest.mark.parametrize("name, meshes, final_tol", [
    ("hex20", [(4, 1, 1), (8, 1, 1), (16, 2, 2)], 0.02),
    ("hex8", [(10, 1, 1), (20, 2, 2), (40, 4, 4)], None),
])
def test_cantilever_convergence(name, meshes, final_tol):
    """3D cantilever 1 x 0.1 x 0.1 m, full clamp, tip shear: hex20 converges to beam theory with shear
    correction within 2 %; hex8 (full integration, shear locking in bending: too stiff on coarse
    meshes) only has to converge monotonically from below."""
    ref = beam_reference()
    tips = np.array([cantilever_tip(name, n) for n in meshes])
    errors = np.abs(tips - ref) / abs(ref)
    assert (np.diff(errors) < 0).all(), errors
    assert (np.diff(tips / ref) > 0).all(), tips / ref  # displacement FE: compliance grows with refinement
    if final_tol is not None:
        assert errors[-1] <= final_tol, errors


# --------------------------------------------------------------------------------------------------
# Inverted / collapsed elements
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["hex8", "tet4", "hex20", "tet10"])
def test_inverted_element_rejected(name):
    """Two elements, the second with mirrored node order: the kernel reports STATUS_BAD_JACOBIAN at
    index 1 and check_corners raises MeshError naming the group and element 1 (only)."""
    coords, conn = make_mesh(name, (2, 1, 1))
    if shapes.ELEMENT_TYPES[name].family == "tet":
        conn = conn[[0, 6]].copy()  # one tet from each hex
    conn = np.ascontiguousarray(conn[:2])
    et = shapes.ELEMENT_TYPES[name]
    # mirror element 1: hexes swap bottom and top faces (and their mid-edge nodes), tets nodes 1 and 2
    if et.family == "hex":
        perm = [4, 5, 6, 7, 0, 1, 2, 3] + ([12, 13, 14, 15, 8, 9, 10, 11, 16, 17, 18, 19] if et.order == 2 else [])
    else:
        perm = [0, 2, 1, 3] + ([6, 5, 4, 7, 9, 8] if et.order == 2 else [])
    conn[1] = conn[1, perm]
    st, _, info = stiffness(coords, conn, name)
    assert st == STATUS_BAD_JACOBIAN and info[0] == 1
    group = SimpleNamespace(name="blocks", type=name, conn=conn)
    with pytest.raises(MeshError) as exc:
        check_corners(coords, group)
    assert exc.value.elements == [1] and exc.value.group == "blocks"
    assert "element(s) 1" in str(exc.value)
    check_corners(coords, SimpleNamespace(name="ok", type=name, conn=conn[:1]))


def test_collapsed_hex_caught_by_corners_only():
    """A hex8 with the top corner 6 moved onto corner 2 (a collapsed edge, wedge-like shape) still has
    det J > 0 at the 2x2x2 Gauss points, so the kernel accepts it; the corner test rejects it
    (det J = 0 at corners 2 and 6). Likewise a flat tetrahedron (4 coplanar corners) is rejected."""
    x = np.ascontiguousarray((shapes.reference_nodes("hex8") + 1) / 2)
    x[6] = x[2]
    conn = np.arange(8, dtype=np.int64)[None]
    st, _, _ = stiffness(x, conn, "hex8")
    assert st == STATUS_OK
    with pytest.raises(MeshError) as exc:
        check_corners(x, SimpleNamespace(name="g", type="hex8", conn=conn))
    assert exc.value.elements == [0]
    flat = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0]])
    with pytest.raises(MeshError):
        check_corners(flat, SimpleNamespace(name="g", type="tet4", conn=np.arange(4, dtype=np.int64)[None]))
