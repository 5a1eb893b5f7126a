"""The foundation rock with mass (masonrydam.effects.foundation): viscous absorbing boundaries and
free-field effective forces, against closed forms.

Sources:
- Lysmer & Kuhlemeyer (1969), "Finite dynamic model for infinite media", J. Eng. Mech. Div. ASCE
  95(EM4) 859-877: the boundary traction -rho (c_p n n^T + c_s (I - n n^T)) v, exact for plane waves
  at normal incidence (a 1D column absorbs them completely);
- the 1D free field of vertically propagating S and P waves in a uniform layer with a free surface
  (d'Alembert; Kramer, *Geotechnical Earthquake Engineering*, 1996, sec. 7.2): with the outcrop
  motion o, u(z, t) = 1/2 [o(t - (z - z_b)/c) + o(t - (2 z_top - z_b - z)/c)], the surface moves as
  o(t - H/c); the base force rho c A v_o of a compliant base (Joyner & Chen 1975, BSSA 65 1315-1336);
- free-field forces on the sides (Nielsen 2006, ABAQUS Users' Conference; Løkke & Chopra 2018, EESD 47
  1159-1178): a uniform block with absorbing sides must reproduce the 1D free field at every node;
- a layer on a rigid base (within motion w): u_I(t) + u_I(t - 2H/c) = w(t).

Models: structured quad4 / hex8 blocks of linear elastic rock with lumped mass, integrated with the
Newmark average-acceleration rule (Newmark 1959; Chopra, *Dynamics of Structures*, 2012, sec. 5.4),
written out in this file. The excitation is a Ricker wavelet in displacement (Ricker 1953), whose
acceleration is given to the foundation as the record.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from masonrydam.assembly.dofmap import DofMap
from masonrydam.assembly.groups import ContinuumGroup
from masonrydam.assembly.model import Model
from masonrydam.effects import foundation as F
from masonrydam.errors import SceneError
from masonrydam.materials.elastic import elasticity_matrix
from masonrydam.mesh.facets import boundary_owners
from masonrydam.mesh.model import CellBlock, FacetSet, Mesh
from masonrydam.assembly.mass import MassMatrix

RHO, NU = 2500.0, 0.25
C_S = 1000.0
G_MOD = RHO * C_S**2
E_MOD = 2.0 * G_MOD * (1.0 + NU)
C_P = C_S * math.sqrt(2.0 * (1.0 - NU) / (1.0 - 2.0 * NU))  # sqrt(3) c_s for nu = 1/4
F0, T0 = 8.0, 1.5 / 8.0  # Ricker: central frequency (Hz), time of the peak (s)
AMP = 0.01  # m
DT = 5e-4  # s, record and integration step

MODEL_2D = {"dimension": 2, "hypothesis": "plane_strain", "thickness": 1.0, "gravity": [0.0, -9.81]}


def ricker(t):
    """Displacement (m) of the Ricker wavelet and its acceleration (m/s2)."""
    s = (math.pi * F0) ** 2
    tau = np.asarray(t, dtype=float) - T0
    e = np.exp(-s * tau**2)
    return AMP * (1.0 - 2.0 * s * tau**2) * e, AMP * e * (-6.0 * s + 24.0 * s**2 * tau**2 - 8.0 * s**3 * tau**4)


def record(duration):
    t = DT * np.arange(int(round(duration / DT)) + 1)
    return ricker(t)[1], DT


# ----------------------------------------------------------------------------------------------
# meshes and models


def block_mesh(nx, nz, width, height, z0=0.0, thickness_groups="foundation"):
    """quad4 grid of nx x nz elements on [0, width] x [z0, z0 + height]; node (i, j) = j (nx + 1) + i.
    Facet sets foundation_bottom / foundation_sides / foundation_top / middle (an interior line)."""
    xs, zs = np.linspace(0.0, width, nx + 1), np.linspace(z0, z0 + height, nz + 1)
    X, Z = np.meshgrid(xs, zs)
    pts = np.stack([X.ravel(), Z.ravel()], axis=1)
    nid = lambda i, j: j * (nx + 1) + i  # noqa: E731
    cells = np.array([[nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1)]
                      for j in range(nz) for i in range(nx)])
    bottom = [[nid(i, 0), nid(i + 1, 0)] for i in range(nx)]
    top = [[nid(i + 1, nz), nid(i, nz)] for i in range(nx)]
    sides = [[nid(nx, j), nid(nx, j + 1)] for j in range(nz)] + [[nid(0, j + 1), nid(0, j)] for j in range(nz)]
    middle = [[nid(i, nz // 2), nid(i + 1, nz // 2)] for i in range(nx)]
    fs = {"foundation_bottom": FacetSet("line2", bottom), "foundation_sides": FacetSet("line2", sides),
          "foundation_top": FacetSet("line2", top), "middle": FacetSet("line2", middle)}
    return Mesh(pts, [CellBlock("quad4", cells, thickness_groups)], facet_sets=fs)


def hex_mesh(nx, ny, nz, lx, ly, height):
    """hex8 grid on [0, lx] x [0, ly] x [0, height]; facet sets foundation_bottom / foundation_sides."""
    xs, ys, zs = np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1), np.linspace(0, height, nz + 1)
    Z, Y, X = np.meshgrid(zs, ys, xs, indexing="ij")
    pts = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    nid = lambda i, j, k: (k * (ny + 1) + j) * (nx + 1) + i  # noqa: E731
    cells = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                b = [nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k), nid(i, j + 1, k)]
                t = [nid(i, j, k + 1), nid(i + 1, j, k + 1), nid(i + 1, j + 1, k + 1), nid(i, j + 1, k + 1)]
                cells.append(b + t)
    bottom = [[nid(i, j, 0), nid(i, j + 1, 0), nid(i + 1, j + 1, 0), nid(i + 1, j, 0)]
              for j in range(ny) for i in range(nx)]
    sides = []
    for k in range(nz):
        for j in range(ny):
            sides.append([nid(0, j, k), nid(0, j, k + 1), nid(0, j + 1, k + 1), nid(0, j + 1, k)])
            sides.append([nid(nx, j, k), nid(nx, j + 1, k), nid(nx, j + 1, k + 1), nid(nx, j, k + 1)])
        for i in range(nx):
            sides.append([nid(i, 0, k), nid(i + 1, 0, k), nid(i + 1, 0, k + 1), nid(i, 0, k + 1)])
            sides.append([nid(i, ny, k), nid(i, ny, k + 1), nid(i + 1, ny, k + 1), nid(i + 1, ny, k)])
    fs = {"foundation_bottom": FacetSet("quad4", bottom), "foundation_sides": FacetSet("quad4", sides)}
    return Mesh(pts, [CellBlock("hex8", np.array(cells), "foundation")], facet_sets=fs)


def matrices(mesh, hypothesis="plane_strain", thickness=1.0):
    """Stiffness K (Pa m) and lumped mass M (kg) of a one-group elastic mesh, CSR (n_dof, n_dof)."""
    dim = mesh.dim
    b = mesh.blocks[0]
    ne = len(b.cells)
    D = elasticity_matrix(E_MOD, NU, "3d" if dim == 3 else hypothesis)[None]
    g = ContinuumGroup(b.name, b.type, b.cells, DofMap.node_dofs(b.cells, dim), np.ascontiguousarray(D),
                       np.zeros(ne, dtype=np.int64), np.full(ne, thickness), np.full(ne, RHO))
    model = Model(mesh.points, [g], [])
    return model.K_continuum.tocsr(), MassMatrix(model, lumped=True).full.tocsr()


def newmark(M, C, K, force, n_steps, dt=DT, T=None, base=None):
    """Newmark average acceleration for M a + C v + K u = f(t) from rest, on the generalised DOFs
    q with u = T q (T: (n_dof, n_q) or None = identity); ``base``: (iota (n_dof,), a_g(t)) adds
    -M iota a_g (relative formulation). Returns u (n_steps + 1, n_dof) of the full DOFs."""
    if T is None:
        T = sp.identity(M.shape[0], format="csr")
    Mr, Cr, Kr = (T.T @ A @ T for A in (M, C, K))
    Mr, Cr, Kr = (sp.csc_matrix(A) for A in (Mr, Cr, Kr))

    def f(t):
        out = force(t)
        if base is not None:
            iota, ag = base
            out = out - M @ (iota * ag(t))
        return T.T @ out

    lu = spla.splu(sp.csc_matrix(Kr + 4.0 / dt**2 * Mr + 2.0 / dt * Cr))
    q = np.zeros(Kr.shape[0])
    v = np.zeros_like(q)
    a = spla.spsolve(Mr, f(0.0) - Cr @ v - Kr @ q)
    out = [T @ q]
    for n in range(1, n_steps + 1):
        rhs = f(n * dt) + Mr @ (4.0 / dt**2 * q + 4.0 / dt * v + a) + Cr @ (2.0 / dt * q + v)
        q1 = lu.solve(rhs)
        v1 = 2.0 / dt * (q1 - q) - v
        a = 4.0 / dt**2 * (q1 - q) - 4.0 / dt * v - a
        q, v = q1, v1
        out.append(T @ q)
    return np.array(out)


def boundary(mesh, name):
    fs = mesh.facet_sets[name]
    ok, inward = boundary_owners(mesh, fs.type, fs.facets, "foundation")
    assert ok.all()
    return F.Boundary(name, fs.type, fs.facets, inward)


# ----------------------------------------------------------------------------------------------
# a. the dashpot matrix


def _block(C, node, dim):
    d = node * dim + np.arange(dim)
    return C[d][:, d].toarray()


@pytest.mark.parametrize("ftype", ["line2", "line3"])
def test_dashpots_flat_bottom_2d(ftype):
    """Sum of the vertical (normal) coefficients rho c_p A, horizontal (tangential) rho c_s A; A = L t."""
    L, t, n = 12.0, 2.0, 5
    x = np.linspace(0.0, L, 2 * n + 1)
    coords = np.stack([x, np.zeros_like(x)], axis=1)
    facets = [[2 * i, 2 * i + 2] + ([2 * i + 1] if ftype == "line3" else []) for i in range(n)]
    b = F.Boundary("bottom", ftype, facets, np.tile([0.0, 1.0], (n, 1)))
    C = F.dashpot_matrix(coords, [b], RHO, C_P, C_S, thickness=t)
    d = C.diagonal()
    assert d[1::2].sum() == pytest.approx(RHO * C_P * L * t, rel=1e-12)
    assert d[0::2].sum() == pytest.approx(RHO * C_S * L * t, rel=1e-12)
    assert abs(C - sp.diags(d)).max() < 1e-9 * d.max()  # no coupling on a horizontal facet
    assert (d[[2 * k * 2 + 1 for k in range(n + 1)]] > 0).all()


def test_dashpots_inclined_2d_rotation_invariant():
    """One inclined edge: each node block is rho (c_p n n^T + c_s (I - n n^T)) times L t / 2."""
    L, t, ang = 3.0, 1.5, math.radians(35.0)
    e = np.array([math.cos(ang), math.sin(ang)])
    coords = np.array([[1.0, 2.0], [1.0, 2.0] + L * e])
    n = np.array([e[1], -e[0]])  # outward: away from the inward point
    inward = coords.mean(axis=0) - n
    C = F.dashpot_matrix(coords, [F.Boundary("b", "line2", [[0, 1]], [inward])], RHO, C_P, C_S, thickness=t)
    expect = RHO * (C_P * np.outer(n, n) + C_S * (np.eye(2) - np.outer(n, n))) * L * t / 2
    for node in (0, 1):
        np.testing.assert_allclose(_block(C, node, 2), expect, rtol=1e-12, atol=1e-9 * expect.max())


@pytest.mark.parametrize("ftype", ["quad4", "tri3", "quad8", "quad9", "tri6"])
def test_dashpots_flat_bottom_3d(ftype):
    """3D, a 6 x 4 m horizontal base in quadrilaterals or triangles: sums rho c_p A (z) and rho c_s A
    (x, y); every node's coefficients positive (diagonal scaling for quad8 / tri6)."""
    lx, ly, nx, ny = 6.0, 4.0, 3, 2
    xs, ys = np.linspace(0, lx, 2 * nx + 1), np.linspace(0, ly, 2 * ny + 1)
    Y, X = np.meshgrid(ys, xs, indexing="ij")
    coords = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    nid = lambda i, j: j * (2 * nx + 1) + i  # noqa: E731
    facets = []
    for j in range(0, 2 * ny, 2):
        for i in range(0, 2 * nx, 2):
            c = [nid(i, j), nid(i + 2, j), nid(i + 2, j + 2), nid(i, j + 2)]
            m = [nid(i + 1, j), nid(i + 2, j + 1), nid(i + 1, j + 2), nid(i, j + 1)]
            if ftype == "quad4":
                facets.append(c)
            elif ftype == "quad8":
                facets.append(c + m)
            elif ftype == "quad9":
                facets.append(c + m + [nid(i + 1, j + 1)])
            elif ftype == "tri3":
                facets += [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
            else:
                facets += [[c[0], c[1], c[2], m[0], m[1], nid(i + 1, j + 1)],
                           [c[0], c[2], c[3], nid(i + 1, j + 1), m[2], m[3]]]
    used = np.unique(facets)
    inward = np.tile([0.0, 0.0, 1.0], (len(facets), 1))
    C = F.dashpot_matrix(coords, [F.Boundary("b", ftype, facets, inward)], RHO, C_P, C_S)
    d = C.diagonal()
    A = lx * ly
    assert d[2::3].sum() == pytest.approx(RHO * C_P * A, rel=1e-12)
    assert d[0::3].sum() == pytest.approx(RHO * C_S * A, rel=1e-12)
    assert d[1::3].sum() == pytest.approx(RHO * C_S * A, rel=1e-12)
    assert (d[used * 3 + 2] > 0).all()


def test_dashpots_inclined_3d_rotation_invariant():
    """A rotated parallelogram face (quad4): each node block is rho (c_p n n^T + c_s (I - n n^T)) A / 4."""
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    a, b = 4.0 * Q[:, 0], 2.5 * (Q[:, 1] + 0.3 * Q[:, 0])
    o = np.array([1.0, -2.0, 3.0])
    coords = np.array([o, o + a, o + a + b, o + b])
    n = np.cross(a, b)
    area = np.linalg.norm(n)
    n /= area
    C = F.dashpot_matrix(coords, [F.Boundary("b", "quad4", [[0, 1, 2, 3]], [coords.mean(0) - n])], RHO, C_P, C_S)
    expect = RHO * (C_P * np.outer(n, n) + C_S * (np.eye(3) - np.outer(n, n))) * area / 4
    for node in range(4):
        np.testing.assert_allclose(_block(C, node, 3), expect, rtol=1e-10, atol=1e-9 * abs(expect).max())


# ----------------------------------------------------------------------------------------------
# b. a 1D column: surface motion and absorption at the base


H_COL, NZ_COL = 200.0, 100  # m, elements (h = 2 m: <= 1/25 of the shortest significant wavelength)


@pytest.mark.parametrize("comp", [0, 1], ids=["S_wave", "P_wave"])
def test_column_outcrop(comp):
    """A rock column one element wide, the two nodes of a level tied in the wave's direction and held
    in the other (an exact 1D shear or constrained column), dashpots at the base, the outcrop Ricker
    wavelet entered as the base force: (i) the surface moves as o(t - H/c), (ii) the pulse reflected
    at the surface leaves through the base, (iii) for S (horizontal) and P (vertical) waves."""
    mesh = block_mesh(1, NZ_COL, 2.0, H_COL)
    K, M = matrices(mesh)
    c = C_S if comp == 0 else C_P
    duration = 2 * T0 + 2 * H_COL / c + 0.15
    fnd = F.Foundation(mesh.points, boundary(mesh, "foundation_bottom"), None, youngs_modulus=E_MOD,
                       poisson_ratio=NU, density=RHO, motion="outcrop", records={comp: record(duration)})
    assert fnd.c_s == pytest.approx(C_S) and fnd.c_p == pytest.approx(C_P)
    n_nodes = mesh.n_nodes
    levels = n_nodes // 2
    T = sp.csr_matrix((np.ones(n_nodes), (np.arange(n_nodes) * 2 + comp, np.arange(n_nodes) // 2)),
                      shape=(2 * n_nodes, levels))
    n_steps = int(round(duration / DT))
    u = newmark(M, fnd.dashpots, K, fnd.effective_force, n_steps, T=T)[:, comp::2][:, ::2]  # (steps, levels)
    t = DT * np.arange(n_steps + 1)
    z = mesh.points[::2, 1]
    o_peak = AMP
    # (i) surface = outcrop motion delayed by H/c
    top = u[:, -1]
    delayed = ricker(t - H_COL / c)[0]
    ratio = np.abs(top).max() / o_peak
    err_top = np.abs(top - delayed).max() / o_peak
    # the whole column against the 1D free field
    ff = np.array([fnd.free_field(z, tk, comp)[0] for tk in t])
    err_ff = np.abs(u - ff).max() / o_peak
    # (ii) after the pulse has left: what remains in the column, against the incident amplitude o/2
    late = t > 2 * T0 + 2 * H_COL / c + 0.05
    residual = np.abs(u[late]).max() / (0.5 * o_peak)
    print(f"\n{'S' if comp == 0 else 'P'} column: surface/outcrop peak {ratio:.4f}, surface error {err_top:.4f}, "
          f"free-field error {err_ff:.4f}, residual {residual:.4f} of the incident amplitude")
    assert ratio == pytest.approx(1.0, abs=0.02)
    assert err_top < 0.03
    assert err_ff < 0.03
    assert residual < 0.05
    # energy left in the column against the energy the incident wave brought in
    A = 2.0 * 1.0
    vo = np.gradient(ricker(t)[0], DT)
    e_in = RHO * c * A * np.sum((0.5 * vo) ** 2) * DT
    k_late = np.nonzero(late)[0][-1]
    uu = np.zeros(2 * n_nodes)
    uu[comp::2] = np.repeat(u[k_late], 2)
    vv = np.zeros(2 * n_nodes)
    vv[comp::2] = np.repeat((u[k_late] - u[k_late - 1]) / DT, 2)
    e_left = 0.5 * vv @ (M @ vv) + 0.5 * uu @ (K @ uu)
    print(f"  energy left {e_left / e_in:.2e} of the incident energy")
    assert e_left < 0.05 * e_in


# ----------------------------------------------------------------------------------------------
# c. a wide block: the side free-field forces


@pytest.mark.parametrize("comp", [0, 1], ids=["S_wave", "P_wave"])
def test_block_outcrop_reproduces_free_field(comp):
    """A 20 m wide block (4 elements across) of uniform rock, absorbing bottom and sides, under the
    outcrop Ricker wavelet: every node follows the 1D free field (the motion at a height is the same
    across the width, the other component stays at rest): checks the signs of the side forces."""
    H = 100.0
    mesh = block_mesh(4, 40, 20.0, H)
    K, M = matrices(mesh)
    c = C_S if comp == 0 else C_P
    duration = 2 * T0 + 2 * H / c + 0.1
    spec = F.normalize_section({"mass": True, "motion": "outcrop"}, MODEL_2D)
    fnd = F.build(spec, mesh, {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": RHO}},
                  MODEL_2D, records={"xy"[comp]: record(duration)})
    edge = np.unique(np.concatenate([mesh.facet_sets[s].facets.ravel() for s in ("foundation_bottom",
                                                                                 "foundation_sides")]))
    assert np.array_equal(np.nonzero(fnd.released_dofs[::2])[0], edge)
    n_steps = int(round(duration / DT))
    U = newmark(M, fnd.dashpots, K, fnd.effective_force, n_steps)
    t = DT * np.arange(n_steps + 1)
    u, w = U[:, comp::2], U[:, 1 - comp::2]
    levels = u.reshape(len(t), 41, 5)
    spread = (levels.max(axis=2) - levels.min(axis=2)).max() / AMP
    ff = np.array([fnd.free_field(mesh.points[:, 1], tk, comp)[0] for tk in t])
    err = np.abs(u - ff).max() / AMP
    other = np.abs(w).max() / AMP
    print(f"\n{'S' if comp == 0 else 'P'} block: spread across the width {spread:.4f}, error against the free field "
          f"{err:.4f}, other component {other:.2e} (of the outcrop peak)")
    assert spread < 0.02
    assert err < 0.03
    assert other < 0.01


def test_block_within_reproduces_free_field():
    """Within motion: rigid base carrying w(t) (relative formulation, -M iota a_g), absorbing sides with
    the relative free-field forces: every node follows the free field of the layer on a rigid base."""
    H = 100.0
    mesh = block_mesh(4, 40, 20.0, H)
    K, M = matrices(mesh)
    duration = 0.8
    spec = F.normalize_section({"mass": True, "motion": "within"}, MODEL_2D)
    acc, dt = record(duration)
    fnd = F.build(spec, mesh, {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": RHO}},
                  MODEL_2D, records={"x": (acc, dt)})
    assert fnd.base_excitation
    base = np.unique(mesh.facet_sets["foundation_bottom"].facets)
    sides = np.setdiff1d(np.unique(mesh.facet_sets["foundation_sides"].facets), base)
    assert np.array_equal(np.nonzero(fnd.released_dofs[::2])[0], sides)
    # the free field at the base is w, at the surface traction free
    tt = np.linspace(0.0, duration, 50)
    np.testing.assert_allclose([fnd.free_field(0.0, x, 0, relative=False)[0] for x in tt], ricker(tt)[0] - ricker(0)[0],
                               atol=5e-4 * AMP)  # the trapezoidal integration of the sampled record
    free = np.ones(2 * mesh.n_nodes, dtype=bool)
    free[np.repeat(base, 2) * 2 + np.tile([0, 1], len(base))] = False
    T = sp.identity(2 * mesh.n_nodes, format="csr")[:, np.nonzero(free)[0]]
    iota = np.zeros(2 * mesh.n_nodes)
    iota[0::2] = 1.0
    n_steps = int(round(duration / DT))
    U = newmark(M, fnd.dashpots, K, fnd.effective_force, n_steps, T=T,
                base=(iota, lambda x: np.interp(x, DT * np.arange(len(acc)), acc)))
    t = DT * np.arange(n_steps + 1)
    u = U[:, 0::2]
    ff = np.array([fnd.free_field(mesh.points[:, 1], tk, 0)[0] for tk in t])
    scale = np.abs(ff).max()
    levels = u.reshape(len(t), 41, 5)
    spread = (levels.max(axis=2) - levels.min(axis=2)).max() / scale
    err = np.abs(u - ff).max() / scale
    print(f"\nwithin block: spread across the width {spread:.4f}, error against the free field {err:.4f} "
          f"(of the peak relative free-field displacement)")
    assert spread < 0.02
    assert err < 0.05


@pytest.mark.slow
def test_block_3d_two_horizontal_components():
    """3D (hex8, 2 x 2 elements in plan, quad4 side faces): x and y components at once (S waves) and
    z (P wave): every node follows the 1D free field of each component."""
    H = 60.0
    mesh = hex_mesh(2, 2, 20, 12.0, 12.0, H)
    K, M = matrices(mesh)
    duration = 2 * T0 + 2 * H / C_S + 0.05
    model = {"dimension": 3, "hypothesis": "3d", "thickness": 1.0, "gravity": [0.0, 0.0, -9.81]}
    spec = F.normalize_section({"mass": True, "motion": "outcrop"}, model)
    assert spec["vertical_axis"] == 2
    acc, dt = record(duration)
    fnd = F.build(spec, mesh, {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": RHO}},
                  model, records={"x": (acc, dt), "y": (-0.5 * acc, dt), "z": (0.3 * acc, dt)})
    n_steps = int(round(duration / DT))
    U = newmark(M, fnd.dashpots, K, fnd.effective_force, n_steps)
    t = DT * np.arange(n_steps + 1)
    z = mesh.points[:, 2]
    worst = 0.0
    for c, s in ((0, 1.0), (1, 0.5), (2, 0.3)):
        ff = np.array([fnd.free_field(z, tk, c)[0] for tk in t])
        worst = max(worst, np.abs(U[:, c::3] - ff).max() / (s * AMP))
    print(f"\n3D block: largest error against the free field {worst:.4f} (of each component's outcrop peak)")
    assert worst < 0.05


# ----------------------------------------------------------------------------------------------
# free field, base force, summaries


def test_base_force_is_rho_c_A_v_outcrop():
    """Joyner & Chen (1975): on a horizontal compliant base the effective force per node is
    rho c A_node v_outcrop(t) (c = c_s horizontal, c_p vertical)."""
    mesh = block_mesh(3, 4, 9.0, 8.0, z0=-8.0)
    acc, dt = record(0.5)
    spec = F.normalize_section({"mass": True, "motion": "outcrop"}, MODEL_2D)
    fnd = F.build(spec, mesh, {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": RHO}},
                  {**MODEL_2D, "thickness": 2.0}, records={"x": (acc, dt), "y": (0.5 * acc, dt)})
    assert (fnd.z_b, fnd.z_top) == (-8.0, 0.0)
    inner = np.array([1, 2])  # bottom nodes away from the sides
    for tk in (0.1, 0.19, 0.25):
        f = fnd.effective_force(tk)
        vo = fnd.base_motion("x", tk)[1]
        np.testing.assert_allclose(f[inner * 2], RHO * C_S * 3.0 * 2.0 * vo, rtol=1e-9)
        np.testing.assert_allclose(f[inner * 2 + 1], RHO * C_P * 3.0 * 2.0 * 0.5 * vo, rtol=1e-9)
    assert fnd.node_area[inner] == pytest.approx([6.0, 6.0])
    text = " ".join(fnd.describe())
    assert "c_p 1732 m/s" in text and "c_s 1000 m/s" in text and "outcrop" in text
    scene = {"foundation": spec, "materials": {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU,
                                                              "density": RHO}}, "model": MODEL_2D}
    assert "Lysmer-Kuhlemeyer" in F.describe(scene, None)[0]
    assert F.describe({"foundation": F.normalize_section({}, MODEL_2D)}, None) == []


def test_within_series_layer_on_rigid_base():
    """u_I(t) + u_I(t - 2H/c) = w(t) at the base; the surface is traction free (du/dz = 0)."""
    mesh = block_mesh(1, 10, 2.0, 50.0)
    acc, dt = record(1.0)
    fnd = F.Foundation(mesh.points, boundary(mesh, "foundation_bottom"), boundary(mesh, "foundation_sides"),
                       youngs_modulus=E_MOD, poisson_ratio=NU, density=RHO, motion="within", records={0: (acc, dt)})
    for tk in np.linspace(0.0, 3.0, 31):  # beyond the record: the undamped layer keeps ringing
        u, v, e = fnd.free_field(np.array([0.0, 50.0]), tk, 0, relative=False)
        w, vw = fnd.base_motion(0, tk)
        assert u[0] == pytest.approx(w, abs=1e-9 * AMP)
        assert v[0] == pytest.approx(vw, abs=1e-6 * AMP * F0)
        assert e[1] == pytest.approx(0.0, abs=1e-12)


def _force_difference(fnd, times):
    """max |effective_force - the point-by-point reference| / max |reference| over ``times``."""
    worst, scale = 0.0, 0.0
    for tk in times:
        f, ref = fnd.effective_force(tk), fnd._effective_force_reference(tk)
        assert f.shape == ref.shape == (fnd.n_dof,)
        worst, scale = max(worst, float(np.abs(f - ref).max())), max(scale, float(np.abs(ref).max()))
    assert scale > 0.0
    return worst / scale


@pytest.mark.parametrize("motion", ["outcrop", "within"])
def test_effective_force_kernel_matches_free_field_2d(motion):
    """The kernel path of effective_force (uniform-grid interpolation at the distinct elevations, one
    precomputed operator) gives the forces of free_field / _traction point by point to round-off over the
    whole record and after it (the within grid extended on demand, times out of order), for two
    components on a mesh with uneven element heights; set_motion rebuilds the operator."""
    mesh = block_mesh(3, 12, 9.0, 40.0, z0=-40.0)
    z = mesh.points[:, 1]
    mesh.points[:, 1] = np.where((z > -40.0) & (z < 0.0), z + 0.7 * np.sin(3.1 * z), z)
    acc, dt = record(0.6)
    spec = F.normalize_section({"mass": True, "motion": motion}, MODEL_2D)
    mats = {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": RHO}}
    fnd = F.build(spec, mesh, mats, MODEL_2D, records={"x": (acc, dt), "y": (-0.6 * acc, dt)})
    times = np.concatenate([[5.0, 0.0, -0.01], dt * np.arange(0, int(round(0.75 / dt)), 3),
                            [0.6, 2.3, 1.37 * dt, 11.0]])
    diff = _force_difference(fnd, times)
    print(f"\n{motion}: largest difference {diff:.2e} of the largest force")
    assert diff < 1e-12
    op = fnd._ff_op
    fnd.set_motion({"y": (acc, dt)})
    assert _force_difference(fnd, dt * np.arange(0, 400, 7)) < 1e-12
    assert fnd._ff_op is not op
    fnd.set_motion({})
    assert not fnd.effective_force(0.3).any()


def test_effective_force_kernel_matches_free_field_3d():
    """3D, three components of a within motion (two S waves and a P wave): the kernel path against the
    point-by-point reference, to round-off."""
    mesh = hex_mesh(2, 3, 6, 12.0, 18.0, 30.0)
    model = {"dimension": 3, "hypothesis": "3d", "thickness": 1.0, "gravity": [0.0, 0.0, -9.81]}
    spec = F.normalize_section({"mass": True, "motion": "within"}, model)
    acc, dt = record(0.4)
    fnd = F.build(spec, mesh, {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": RHO}},
                  model, records={"y": (acc, dt), "x": (-0.5 * acc, dt), "z": (0.3 * acc[::-1], dt)})
    assert _force_difference(fnd, dt * np.arange(0, int(round(1.5 / dt)), 5)) < 1e-12


@pytest.mark.parametrize("n", [1, 2, 7, 400])
def test_interp_uniform_is_numpy_interp(n):
    """The kernel's interpolation on the grid dt * arange(n) is numpy.interp(..., left=0.0) bit for bit:
    before the grid, on its points, between them and after its end."""
    from masonrydam.effects.foundation_kernels import interp_uniform
    rng = np.random.default_rng(n)
    dt = 1.0 / 3.0e3 if n > 2 else 0.01
    tg = dt * np.arange(n)
    vals = np.concatenate([rng.normal(size=5), rng.normal(size=n)])  # offset 5 into a packed array
    x = np.concatenate([[-1.0, -1e-300, 0.0, tg[-1], tg[-1] * (1 + 1e-16), tg[-1] + dt, 10.0], tg,
                        tg + dt * 1e-14, tg - dt * 1e-14, rng.uniform(-dt, n * dt * 1.2, 500)])
    want = np.interp(x, tg, vals[5:], left=0.0)
    got = np.array([interp_uniform(xi, vals, 5, n, dt) for xi in x])
    assert np.array_equal(got, want)


# ----------------------------------------------------------------------------------------------
# d. bad input


def test_section_defaults_and_massless():
    out = F.normalize_section({}, MODEL_2D)
    assert out["mass"] is False and out["group"] == "foundation" and out["vertical_axis"] == 1
    assert out["absorbing"] == {"bottom": "foundation_bottom", "sides": "foundation_sides"}
    massless = F.normalize_section({"mass": False, "absorbing": False}, MODEL_2D)
    assert massless["absorbing"] is None
    mesh = block_mesh(2, 2, 4.0, 4.0)
    assert F.build(massless, mesh, {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": 0.0}},
                   MODEL_2D) is None


@pytest.mark.parametrize("section, key, words", [
    ({"mass": True, "motion": "outcrop", "masss": 1}, "foundation.masss", "unknown key"),
    ({"mass": True, "motion": "outcrop", "absorbing": {"bottom": "b", "side": "s"}}, "foundation.absorbing.side",
     "unknown key"),
    ({"mass": True, "motion": "outcrop", "absorbing": False}, "foundation.absorbing", "waves reflect"),
    ({"mass": True}, "foundation.motion", "outcrop"),
    ({"mass": True, "motion": "surface"}, "foundation.motion", "must be one of"),
    ({"mass": "yes"}, "foundation.mass", "true or false"),
    ({"mass": True, "motion": "within", "absorbing": {"bottom": 3}}, "foundation.absorbing.bottom", "facet set"),
])
def test_section_errors(section, key, words):
    with pytest.raises(SceneError) as e:
        F.normalize_section(section, MODEL_2D)
    assert e.value.key == key
    assert words in str(e.value)


def test_builder_errors():
    mesh = block_mesh(2, 4, 4.0, 8.0)
    mats = {"foundation": {"youngs_modulus": E_MOD, "poisson_ratio": NU, "density": RHO}}
    spec = F.normalize_section({"mass": True, "motion": "outcrop"}, MODEL_2D)
    with pytest.raises(SceneError) as e:
        F.build(spec, mesh, {"foundation": {**mats["foundation"], "density": 0.0}}, MODEL_2D)
    assert e.value.key == "materials.foundation.density"
    bad = F.normalize_section({"mass": True, "motion": "outcrop", "absorbing": {"sides": "flanks"}}, MODEL_2D)
    with pytest.raises(SceneError) as e:
        F.build(bad, mesh, mats, MODEL_2D)
    assert e.value.key == "foundation.absorbing.sides"
    assert "flanks" in str(e.value) and "foundation_sides" in str(e.value)  # lists the mesh's facet sets
    inner = F.normalize_section({"mass": True, "motion": "outcrop", "absorbing": {"bottom": "middle"}}, MODEL_2D)
    with pytest.raises(SceneError) as e:
        F.build(inner, mesh, mats, MODEL_2D)
    assert e.value.key == "foundation.absorbing.bottom"
    assert "not on the boundary" in str(e.value)
    other = F.normalize_section({"mass": True, "motion": "outcrop", "group": "rock"}, MODEL_2D)
    with pytest.raises(SceneError) as e:
        F.build(other, mesh, mats, MODEL_2D)
    assert e.value.key == "foundation.group"
    with pytest.raises(SceneError) as e:
        F.normalize_section({"mass": True, "motion": "outcrop"}, {**MODEL_2D, "gravity": [3.0, -9.0]})
    assert e.value.key == "model.gravity"
