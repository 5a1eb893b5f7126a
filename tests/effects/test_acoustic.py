"""Tests of masonrydam.effects.reservoir.acoustic (the reservoir as pressure finite elements) against closed forms.

Sources:
- Westergaard, H. M. (1933), "Water pressures on dams during earthquakes", Trans. ASCE 98, 418-433:
  rigid vertical face, incompressible water, horizontal ground acceleration ``a`` toward the reservoir,
  exact series (Westergaard 1933; ``d`` the depth below the surface)
  ``p(d) = (8 rho a H / pi^2) sum_{m odd} sin(m pi d / (2H)) / m^2``; base pressure
  ``(8 / pi^2) G rho a H = 0.7425 rho a H`` (G Catalan's constant), resultant per unit width
  ``(16 rho a H^2 / pi^3) sum_{m odd} 1 / m^3 = 0.5428 rho a H^2``;
- compressible water, harmonic acceleration ``a e^{i w t}``: every term divided by
  ``c_m = sqrt(1 - (w / w_m)^2)``, ``w_m = m pi c / (2H)`` (also written with the bulk
  modulus K and the period T; A. K. Chopra, "Hydrodynamic pressures on dams during earthquakes",
  J. Eng. Mech. Div. ASCE 93 (1967) 205-223): the response is unbounded at the first cut-off
  ``w_1 = pi c / (2H)`` (``f = c / 4H``) for a rigid bottom;
- bottom absorption: G. Fenves, A. K. Chopra, Earthquake Eng. Struct. Dyn. 12 (1984) 663-680: a bottom
  with reflection coefficient ``alpha < 1`` dissipates energy, so the resonant peak is bounded and falls
  as ``alpha`` falls;
- Sommerfeld radiation and the semi-discrete equations: O. C. Zienkiewicz, P. Bettess, Int. J. Numer.
  Methods Eng. 13 (1978) 1-16;
- geometry: ``int_S n dS`` over a plane region is its area times its unit normal; the functions ``N_p``
  of all fluid nodes sum to one, so the column sums of ``Q_all`` over one component are that integral
  (divergence theorem / partition of unity).

Sign convention checked throughout: ``p`` positive in compression; a ground acceleration toward the
reservoir (along ``upstream``) gives ``p > 0`` on the face and a face force ``Q p`` pointing downstream.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from masonrydam.effects.reservoir.acoustic import acoustic_matrices, build_fluid_mesh
from masonrydam.elements.shapes import reference_nodes

RHO = 1000.0  # kg/m3
C = 1440.0  # m/s
H = 10.0  # m, reservoir depth


# ---------------------------------------------------------------------------------------------
# closed forms (Westergaard 1933; compressible: Chopra 1967)


def series_pressure(d, w=0.0, c=C, depth=H, terms=4000):
    """Pressure / (rho a) at depths d (m) below the surface on a rigid vertical face."""
    m = np.arange(1, 2 * terms, 2)
    cm = np.sqrt(1.0 - (w / (m * np.pi * c / (2.0 * depth))) ** 2)
    d = np.atleast_1d(d)[:, None]
    return 8.0 * depth / np.pi**2 * np.sum(np.sin(m * np.pi * d / (2.0 * depth)) / (m**2 * cm), axis=1)


def series_force(w=0.0, c=C, depth=H, terms=4000):
    """Resultant per unit width / (rho a): the series integrated over the depth."""
    m = np.arange(1, 2 * terms, 2)
    cm = np.sqrt(1.0 - (w / (m * np.pi * c / (2.0 * depth))) ** 2)
    return 16.0 * depth**2 / np.pi**3 * np.sum(1.0 / (m**3 * cm))


@pytest.mark.reference
def test_series_values():
    # the series' numbers: base 0.7425 rho a H, resultant 0.5428 rho a H^2
    assert series_pressure(H)[0] / H == pytest.approx(0.7425, abs=1e-4)
    assert series_force() / H**2 == pytest.approx(0.5428, abs=1e-4)


# ---------------------------------------------------------------------------------------------
# faces made by hand


def wall_2d(zs, xs=None, quadratic=False):
    """Dam face along the nodes (x, z) (x = 0 unless given), line2 (or straight line3) facets; the dam at
    x > face (inward points at x + 1), the reservoir at x < face: upstream = (-1, 0)."""
    zs = np.asarray(zs, dtype=float)
    n = len(zs) - 1
    xs = np.zeros(n + 1) if xs is None else np.asarray(xs, dtype=float)
    coords = np.column_stack([xs, zs])
    facets = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    if quadratic:
        coords = np.vstack([coords, 0.5 * (coords[facets[:, 0]] + coords[facets[:, 1]])])
        facets = np.column_stack([facets, n + 1 + np.arange(n)])
    inward = coords[facets[:, :2]].mean(axis=1) + np.array([1.0, 0.0])
    return coords, facets, inward


def wall_3d(ys, zs, shift=None):
    """quad4 facets on the plane x = 0 (or x = shift(y, z)), z up, the dam at x > face."""
    Y, Z = np.meshgrid(ys, zs, indexing="ij")
    X = np.zeros_like(Y) if shift is None else shift(Y, Z)
    coords = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    idx = np.arange(Y.size).reshape(Y.shape)
    facets = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1).reshape(-1, 4)
    inward = coords[facets].mean(axis=1) + np.array([1.0, 0.0, 0.0])
    return coords, facets, inward


def matrices(coords, ftype, facets, inward, level=H, length=3 * H, c=None, alpha=1.0, thickness=1.0,
             element_size=None, max_element_size=None):
    dim = coords.shape[1]
    up = (-1.0, 0.0) if dim == 2 else (-1.0, 0.0, 0.0)
    mesh = build_fluid_mesh(coords, ftype, facets, inward, level=level, vertical_axis=dim - 1, upstream=up,
                            length=length, element_size=element_size, max_element_size=max_element_size)
    return acoustic_matrices(mesh, coords, ftype, facets, inward, density=RHO, sound_speed=c,
                             bottom_reflection=alpha, thickness=thickness)


def harmonic(A, w, a_g):
    """Pressure amplitudes of (H + i w L - w^2 G) p = -rho B a_g and the face force Q p."""
    K = (A.H + 1j * w * A.L - w**2 * A.G).tocsc()
    p = spla.spsolve(K, -RHO * (A.B @ np.asarray(a_g, dtype=float)))
    return p, A.Q @ p


def toward_reservoir(dim):
    """Unit ground acceleration toward the reservoir (along upstream = -x)."""
    a = np.zeros(dim)
    a[0] = -1.0
    return a


# ---------------------------------------------------------------------------------------------
# 1. rigid vertical wall, incompressible water: Westergaard's exact series


@pytest.mark.parametrize("ftype, n, length", [("line2", 20, 3 * H), ("line2", 20, 5 * H), ("line3", 10, 3 * H)])
@pytest.mark.reference
def test_westergaard_rigid_wall_2d(ftype, n, length):
    coords, facets, inward = wall_2d(np.linspace(0.0, H, n + 1), quadratic=ftype == "line3")
    t = 0.7
    A = matrices(coords, ftype, facets, inward, length=length, thickness=t)
    assert A.G.nnz == 0 and A.L.nnz == 0  # incompressible
    p, f = harmonic(A, 0.0, toward_reservoir(2))
    assert np.abs(p.imag).max() == 0.0
    p, f = p.real, f.real
    assert (p > 0).all()  # compression
    F = f[0::2].sum()  # x: downstream, into the dam
    assert F > 0.0
    # 20 line2 facets: F = 0.54205 (3H), 0.54197 (5H); 10 line3 (a 20-segment chain): 0.54123 rho a H^2
    assert F / (t * RHO) == pytest.approx(series_force(), rel=0.02)
    assert f[1::2].sum() == pytest.approx(0.0, abs=1e-9 * F)  # vertical face: no vertical force
    # the face force's x-resultant is B . p (rigid face, horizontal bottom)
    assert F == pytest.approx(A.B[:, 0] @ p, rel=1e-12)
    # pressure distribution: base 0.74258 rho a H for 20 line2 facets (series 0.74245); along the face
    # within 0.02 % down to d = 0.1 H (d = 0.05 H: 0.6 %)
    pf = A.face_pressure(p) / RHO
    d = H - coords[A.face_nodes, 1]
    exact = series_pressure(d)
    assert pf[np.argmax(d)] == pytest.approx(0.7425 * H, rel=0.02)
    for depth in (0.25 * H, 0.5 * H, 0.75 * H, H):
        k = np.argmin(np.abs(d - depth))
        assert pf[k] == pytest.approx(exact[k], rel=0.02)
    assert pf[d == 0.0] == pytest.approx(0.0, abs=0.0)  # free surface
    # added mass of the incompressible water: iota_x^T M_a iota_x = F / a
    iota = np.zeros(coords.size)
    iota[0::2] = 1.0
    assert iota @ (A.added_mass() @ iota) == pytest.approx(F, rel=1e-9)


def test_matrix_properties_2d():
    coords, facets, inward = wall_2d(np.linspace(0.0, H, 11))
    A = matrices(coords, "line2", facets, inward, c=C, alpha=0.6)
    for M in (A.G, A.H, A.L, A.L_far, A.L_bottom):
        assert abs(M - M.T).max() <= 1e-12 * abs(M).max()
    assert np.linalg.eigvalsh(A.H.toarray()).min() > 0.0  # free surface removed: H is definite
    # sums of the reduced matrices: int (sum of the free nodes' N)^2, where that sum is 1 except in the top
    # row of elements (height h = 1 m), where it falls linearly to 0 at the surface: H - 2h/3 per unit
    # of horizontal extent. L_far: (1/c) over the far plane; L_bottom: q over the bottom (3H long, away
    # from the surface); G: (1/c^2) over the 3H x H rectangle
    mesh = A.mesh
    q = (1 - 0.6) / ((1 + 0.6) * C)
    h = 1.0
    assert A.L_far.sum() == pytest.approx((H - 2 * h / 3) / C, rel=1e-12)
    assert A.L_bottom.sum() == pytest.approx(q * 3 * H, rel=1e-12)
    assert A.G.sum() == pytest.approx(3 * H * (H - 2 * h / 3) / C**2, rel=1e-12)
    # every fluid node at the level is a free-surface node and nothing else
    assert set(mesh.free_surface) == set(np.flatnonzero(np.isclose(mesh.nodes[:, 1], H)))


# ---------------------------------------------------------------------------------------------
# 2. compressible water, harmonic ground acceleration


def test_compressible_harmonic_2d():
    coords, facets, inward = wall_2d(np.linspace(0.0, H, 21))
    w1 = np.pi * C / (2 * H)
    A = matrices(coords, "line2", facets, inward, c=C, alpha=1.0)
    for r in (0.5, 0.8):
        _, f = harmonic(A, r * w1, toward_reservoir(2))
        F = f[0::2].sum() / RHO
        # 0.5 w1: 0.62221 vs 0.62288 (0.1 %); 0.8 w1: 0.88465 - 0.0057 i vs 0.88756 (0.7 %), rho a H^2
        assert abs(F - series_force(r * w1)) <= 0.03 * series_force(r * w1)
    # the incompressible limit
    _, f = harmonic(A, 1e-6 * w1, toward_reservoir(2))
    assert f[0::2].sum().real / RHO == pytest.approx(series_force(), rel=0.02)


@pytest.mark.slow
def test_resonance_and_bottom_absorption_2d():
    """Peak of |F(w)| at the first cut-off w_1 = pi c / (2H) (f = c / 4H) for a rigid bottom; with the far
    plane at 5H the truncation moves it up by 2 % (measured: 1.02 w_1 on this scan; 3H: 4.6 %, 10H:
    0.5 %). A bottom with alpha < 1 bounds and lowers the peak, monotonically in alpha."""
    coords, facets, inward = wall_2d(np.linspace(0.0, H, 21))
    w1 = np.pi * C / (2 * H)
    ws = np.linspace(0.9, 1.1, 41) * w1
    mesh = build_fluid_mesh(coords, "line2", facets, inward, level=H, vertical_axis=1, upstream=(-1.0, 0.0),
                            length=5 * H)
    peaks = []
    for alpha in (1.0, 0.9, 0.75, 0.5, 0.0):
        A = acoustic_matrices(mesh, coords, "line2", facets, inward, density=RHO, sound_speed=C,
                              bottom_reflection=alpha)
        F = np.array([abs(harmonic(A, w, toward_reservoir(2))[1][0::2].sum()) for w in ws]) / (RHO * H**2)
        peaks.append(F.max())
        if alpha == 1.0:
            w_peak = ws[np.argmax(F)]
            assert w_peak / w1 == pytest.approx(1.0, abs=0.03)
            assert F.max() > 10 * series_force() / H**2  # a sharp resonance (13.2 vs 0.54 static)
    assert np.all(np.diff(peaks) < 0.0), peaks  # 13.2, 2.18, 1.24, 0.82, 0.51 rho a H^2
    assert peaks[-1] < series_force(0.9 * w1) / H**2  # fully absorbing: below the rigid value at 0.9 w1


# ---------------------------------------------------------------------------------------------
# 3. 3D prismatic reservoir


def test_prismatic_3d_equals_2d():
    W = 4.0
    zs = np.linspace(0.0, H, 21)
    c2, f2, i2 = wall_2d(zs)
    c3, f3, i3 = wall_3d(np.linspace(0.0, W, 3), zs)
    h = 0.5  # the same layers along the reservoir in both
    w1 = np.pi * C / (2 * H)
    for c, w in ((None, 0.0), (C, 0.8 * w1)):
        A2 = matrices(c2, "line2", f2, i2, c=c, element_size=h)
        A3 = matrices(c3, "quad4", f3, i3, c=c, element_size=h)
        p2, g2 = harmonic(A2, w, toward_reservoir(2))
        p3, g3 = harmonic(A3, w, toward_reservoir(3))
        F2, F3 = g2[0::2].sum(), g3[0::3].sum() / W
        assert abs(F3 - F2) <= 1e-6 * abs(F2)  # measured 1e-14
        assert abs(g3[1::3].sum()) <= 1e-9 * abs(F3) and abs(g3[2::3].sum()) <= 1e-9 * abs(F3)
        # base pressure at mid-width
        pf = A3.face_pressure(p3) / RHO
        xyz = c3[A3.face_nodes]
        k = np.flatnonzero(np.isclose(xyz[:, 1], W / 2) & np.isclose(xyz[:, 2], 0.0))[0]
        assert abs(pf[k] - series_pressure(H, w)[0]) <= 0.02 * series_pressure(H, w)[0]  # 0.7426 / 1.2767
    # banks are rigid walls: the reservoir's lateral motion with the ground loads the water (pressure
    # antisymmetric about the mid-width), but not the face in x (incompressible)
    A3 = matrices(c3, "quad4", f3, i3, element_size=h)
    p, g = harmonic(A3, 0.0, [0.0, 1.0, 0.0])
    full = A3.full_pressure(p.real)
    nodes = A3.mesh.nodes
    mirror = nodes * np.array([1.0, -1.0, 1.0]) + np.array([0.0, W, 0.0])
    order = np.lexsort(np.round(nodes, 9).T)
    order_m = np.lexsort(np.round(mirror, 9).T)
    assert np.allclose(full[order], -full[order_m], atol=1e-9 * RHO * W)
    assert full[np.argmin(nodes[:, 1] + nodes[:, 2])] > 0.0  # the bank at y = 0 pushes toward +y
    assert abs(g[0::3].sum()) <= 1e-9 * RHO * H * W
    # vertical ground acceleration (up): the bottom pushes the water, p = rho a (level - z)
    p, g = harmonic(A3, 0.0, [0.0, 0.0, 1.0])
    assert np.allclose(p.real, RHO * (H - A3.mesh.nodes[A3.free_nodes, 2]), atol=1e-8 * RHO * H)
    assert g[0::3].sum().real == pytest.approx(RHO * H**2 / 2 * W, rel=1e-9)  # hydrostatic-like push


# ---------------------------------------------------------------------------------------------
# 4. partly wet facets, exact coupling integrals, joints, graded layers


def test_partly_wet_facets_2d():
    """Facets of 1.3 m with the level at 10 m inside one: the same resultant as facets ending at the
    level (0.5404 vs 0.5400 rho a H^2, 0.09 % apart), both close to the series (0.5428)."""
    t = 2.0
    res = []
    for zs in (np.arange(9) * 1.3, np.linspace(0.0, H, 9)):
        coords, facets, inward = wall_2d(zs)
        A = matrices(coords, "line2", facets, inward, thickness=t, element_size=0.5)
        p, f = harmonic(A, 0.0, toward_reservoir(2))
        res.append(f[0::2].sum().real / (t * RHO))
    assert res[0] == pytest.approx(res[1], rel=0.01)
    assert res[0] == pytest.approx(series_force(), rel=0.02)


def test_partly_wet_facets_3d():
    W = 2.0
    res = []
    for zs in (np.arange(9) * 1.3, np.linspace(0.0, H, 9)):
        c3, f3, i3 = wall_3d(np.linspace(0.0, W, 3), zs)
        A = matrices(c3, "quad4", f3, i3, element_size=0.5)
        p, f = harmonic(A, 0.0, toward_reservoir(3))
        res.append(f[0::3].sum().real / (W * RHO))
    assert res[0] == pytest.approx(res[1], rel=0.01)
    assert res[0] == pytest.approx(series_force(), rel=0.02)


@pytest.mark.parametrize("ftype", ["line2", "line3"])
def test_coupling_exact_inclined_2d(ftype):
    """Inclined face x = -0.2 z, level 7.77 m cutting a 1.3 m facet: int n_f dS = thickness * 7.77 (1, 0.2)
    (the fluid normal points into the dam, +x), to round-off."""
    zs = np.arange(10) * 1.3
    coords, facets, inward = wall_2d(zs, -0.2 * zs, quadratic=ftype == "line3")
    t = 2.0
    A = matrices(coords, ftype, facets, inward, level=7.77, c=C, thickness=t)
    iota = np.zeros((coords.size, 2))
    iota[0::2, 0] = iota[1::2, 1] = 1.0
    total = (A.Q_all.T @ iota).sum(axis=0)
    exact = t * 7.77 * np.array([1.0, 0.2])
    assert np.abs(total - exact).max() <= 1e-12 * np.linalg.norm(exact)


def test_coupling_exact_curved_line3():
    """Curved line3 facets: the horizontal component of int n_f dS is the wetted height (the vertical
    projection), exactly, whatever the curve; the free surface cuts a curved facet at its exact root."""
    zs = np.arange(9) * 1.3
    coords, facets, inward = wall_2d(zs, -0.02 * zs**2, quadratic=True)
    mid = facets[:, 2]
    coords[mid, 0] += 0.15  # bow every facet
    A = matrices(coords, "line3", facets, inward, level=7.77, c=C)
    iota = np.zeros(coords.size)
    iota[0::2] = 1.0
    assert (A.Q_all.T @ iota).sum() == pytest.approx(7.77, rel=1e-12)
    assert np.all(np.abs(A.mesh.nodes[A.mesh.free_surface, 1] - 7.77) <= 1e-12)


def _skewed_plane(ftype, ny=3, nz=8, W=4.0, h=1.3):
    """Planar face x = -0.3 z - 0.2 y on a skewed grid (z = z' + 0.3 y): parallelogram facets that the
    level crosses obliquely (triangles, quads and pentagons are cut off). Returns coords, facets."""
    def phys(y, zp):
        z = zp + 0.3 * y
        return np.stack([-0.3 * z - 0.2 * y, y, z], axis=-1)

    ys, zs = np.linspace(0.0, W, ny + 1), np.arange(nz + 1) * h
    ref = reference_nodes("quad4" if ftype == "tri3" else ftype)
    pts, fac = [], []
    for i in range(ny):
        for j in range(nz):
            y = ys[i] + 0.5 * (ref[:, 0] + 1.0) * (ys[i + 1] - ys[i])
            zp = zs[j] + 0.5 * (ref[:, 1] + 1.0) * h
            fac.append(len(pts) + np.arange(len(ref)))
            pts.extend(phys(y, zp))
    coords, inv = np.unique(np.round(np.array(pts), 9), axis=0, return_inverse=True)
    facets = inv.ravel()[np.array(fac)]
    if ftype == "tri3":
        facets = np.vstack([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]])
    return coords, facets


@pytest.mark.parametrize("ftype", ["quad4", "tri3", "quad8", "quad9"])
def test_coupling_exact_inclined_3d(ftype):
    """int n_f dS over the wet part of the plane: its area in the (y, z) plane,
    int_0^W (7.77 - 0.3 y) dy = 28.68 m^2, times (1, 0.2, 0.3) (the unnormalised normal of
    x + 0.3 z + 0.2 y = 0 has the length of the area factor), to round-off."""
    coords, facets = _skewed_plane(ftype)
    inward = coords[facets].mean(axis=1) + np.array([1.0, 0.0, 0.0])
    A = matrices(coords, ftype, facets, inward, level=7.77, length=20.0, c=C, alpha=0.5)
    iota = np.zeros((coords.size, 3))
    for k in range(3):
        iota[k::3, k] = 1.0
    total = (A.Q_all.T @ iota).sum(axis=0)
    exact = (7.77 * 4.0 - 0.15 * 16.0) * np.array([1.0, 0.2, 0.3])
    assert np.abs(total - exact).max() <= 1e-12 * np.linalg.norm(exact)
    # a vertical ground acceleration gives p = rho a (level - z) exactly (linear field: the bilinear
    # fluid elements and the interpolation to every structural face node, mid-nodes included, are exact)
    B = matrices(coords, ftype, facets, inward, level=7.77, length=20.0)
    p, _ = harmonic(B, 0.0, [0.0, 0.0, 1.0])
    pf = B.face_pressure(p.real)
    z = coords[B.face_nodes, 2]
    assert np.allclose(pf, RHO * np.maximum(7.77 - z, 0.0), rtol=0.0, atol=1e-9 * RHO * 7.77)


def test_joint_duplicate_nodes_share_fluid_nodes():
    """The two faces of a joint (coincident nodes on the face) are one fluid node: the same pressure
    field as the continuous face (a jointed dam's water is continuous)."""
    zs = np.linspace(0.0, H, 11)
    c1, f1, i1 = wall_2d(zs)
    # duplicate node 5 (z = 5 m): facet 5 starts at the copy
    c2 = np.vstack([c1, c1[5]])
    f2 = f1.copy()
    f2[5, 0] = len(c1)
    A1 = matrices(c1, "line2", f1, i1, c=C)
    A2 = matrices(c2, "line2", f2, i1, c=C)
    assert A2.mesh.n_nodes == A1.mesh.n_nodes and len(A2.mesh.bottom_facets) == len(A1.mesh.bottom_facets)
    w = 0.5 * np.pi * C / (2 * H)
    p1, g1 = harmonic(A1, w, toward_reservoir(2))
    p2, g2 = harmonic(A2, w, toward_reservoir(2))
    pf = A2.face_pressure(p2)
    assert pf[A2.face_nodes == len(c1)] == pytest.approx(pf[A2.face_nodes == 5], rel=1e-12)
    assert pf[A2.face_nodes == 5] == pytest.approx(A1.face_pressure(p1)[A1.face_nodes == 5], rel=1e-12)
    assert g2[0::2].sum() == pytest.approx(g1[0::2].sum(), rel=1e-12)
    assert g2[2 * len(c1)] + g2[10] == pytest.approx(g1[10], rel=1e-12)  # the joint's two nodes share the load


def test_graded_layers_and_far_plane():
    """Inclined face: the layers grow by 1.2 from element_size up to max_element_size along the longest
    line (from the heel), the other lines have the same layers scaled by their length (no layer larger
    than asked anywhere), and the far boundary is the plane at `length` upstream of the most upstream
    wet point."""
    zs = np.arange(9) * 1.3
    coords, facets, inward = wall_2d(zs, -0.3 * zs)
    mesh = build_fluid_mesh(coords, "line2", facets, inward, level=9.0, vertical_axis=1, upstream=(-1.0, 0.0),
                            length=30.0, element_size=0.5, max_element_size=3.0)
    sizes = np.diff(mesh.offsets, axis=1)  # (n_face, n_layers)
    assert np.all(sizes <= np.array([0.5] + [3.0] * (mesh.n_layers - 1)) * (1 + 1e-12))
    assert np.all(sizes[:, 1:] / sizes[:, :-1] <= 1.2 + 1e-9) and np.all(sizes > 0.0)
    line = np.diff(mesh.offsets[np.argmax(mesh.nodes[:mesh.n_face, 0])])  # the heel's line, the longest
    assert line[0] == pytest.approx(0.5, rel=0.05) and line.max() == pytest.approx(3.0, rel=0.05)
    x_far = mesh.nodes[-mesh.n_face:, 0]
    assert x_far == pytest.approx(np.full(mesh.n_face, -0.3 * 9.0 - 30.0), abs=1e-9)
    # the force with the graded mesh agrees with the uniform one (incompressible, 1 %)
    A1 = acoustic_matrices(mesh, coords, "line2", facets, inward, density=RHO, sound_speed=None)
    A2 = matrices(coords, "line2", facets, inward, level=9.0, length=30.0, element_size=0.5)
    F1 = harmonic(A1, 0.0, toward_reservoir(2))[1][0::2].sum().real
    F2 = harmonic(A2, 0.0, toward_reservoir(2))[1][0::2].sum().real
    assert F1 == pytest.approx(F2, rel=0.01)


# ---------------------------------------------------------------------------------------------
# 5. bad input


def test_bad_input_messages():
    coords, facets, inward = wall_2d(np.linspace(0.0, H, 6))
    kw = dict(vertical_axis=1, upstream=(-1.0, 0.0), length=30.0)

    def build(**over):
        k = dict(kw, level=5.0)
        k.update(over)
        return build_fluid_mesh(coords, "line2", facets, inward, **k)

    for level in (0.0, -1.0):
        with pytest.raises(ValueError, match="level .* not above the lowest point"):
            build(level=level)
    with pytest.raises(ValueError, match="level .* above the highest point"):
        build(level=11.0)
    for length in (0.0, -3.0):
        with pytest.raises(ValueError, match="length must be a positive number"):
            build(length=length)
    with pytest.raises(ValueError, match="upstream must be horizontal"):
        build(upstream=(-1.0, 0.1))
    with pytest.raises(ValueError, match="do not look upstream"):
        build(upstream=(1.0, 0.0))
    with pytest.raises(ValueError, match="element_size must be a positive number"):
        build(element_size=-1.0)
    mesh = build()
    for alpha in (-1.0, 1.5, -3.0):
        with pytest.raises(ValueError, match=r"bottom_reflection must lie in \(-1, 1\]"):
            acoustic_matrices(mesh, coords, "line2", facets, inward, density=RHO, sound_speed=C,
                              bottom_reflection=alpha)
    for c in (0.0, -1440.0):
        with pytest.raises(ValueError, match="sound_speed must be a positive number"):
            acoustic_matrices(mesh, coords, "line2", facets, inward, density=RHO, sound_speed=c)
    with pytest.raises(ValueError, match="density must be a positive number"):
        acoustic_matrices(mesh, coords, "line2", facets, inward, density=0.0, sound_speed=C)
    with pytest.raises(ValueError, match="facet_type"):
        build_fluid_mesh(coords, "quad4", facets, inward, level=5.0, **kw)
