"""The water on a curved face: the reservoir on the extrados of an arch dam.

The arch is :func:`generators.arch_dam_3d` with a constant radius and vertical faces (x across the valley, y
downstream, z up; the extrados is the circle of radius R about the vertical axis x = 0, y = R, so a node at
angle phi from the crown lies at x = R sin(phi), y = R - R cos(phi)). Its upstream face is a chain of N
plane vertical facets whose nodes lie on that circle: facet k spans the angles phi_k .. phi_k+1, its width is
the chord w_k = 2 R sin(Delta_k / 2) and its outward unit normal the horizontal (sin(m_k), -cos(m_k), 0) at
the mid angle m_k. Every load below acts along the local normal of each facet; the hand integrations are:

- hydrostatics: the horizontal component of the pressure force on a curved surface equals the force on its
  projection on a vertical plane normal to that component (White, *Fluid Mechanics*, 7th ed. 2011, sec. 2.6,
  "hydrostatic forces on curved surfaces"). On the chain, sum_k w_k n_k = (y_N - y_0, -(x_N - x_0), 0) exactly
  (the edge vectors turned by 90 degrees telescope), so for water h_w deep over the base
  F_y = rho g h_w^2 / 2 * 2 R sin(theta / 2) (the chord: the face's projection) and F_x = F_z = 0 to round-off,
  for hex8 and for hex20 (whose quad8 facets are curved: the same telescoping holds on each curve).
- Westergaard's added mass m_a(s) = 7/8 rho_w sqrt(H s) at depth s (Westergaard 1933, Trans. ASCE 98) on the face
  normal, m_a n n^T per unit area (Kuo 1982, UC Berkeley EERC report on added mass for incompressible fluid;
  USACE EM 1110-2-6051, 2003, sec. 3-7): for a rigid translation the total added mass tensor is
  M_ij = int_0^h_w m_a dz * sum_k w_k n_ki n_kj. The depth integral is 7/12 rho_w H^2 (H = h_w, the face from the
  base). With equal angles Delta = theta / N, sum_k cos^2(m_k) = N/2 + sin(theta) / (2 sin(Delta)) (a Dirichlet
  sum of cos(2 m_k)), so M_yy = 7/12 rho_w H^2 * R sin(Delta/2) (N + sin(theta)/sin(Delta)),
  M_xx = 7/12 rho_w H^2 * R sin(Delta/2) (N - sin(theta)/sin(Delta)), M_xy = 0 by symmetry; as N grows these tend
  to the circle's 7/12 rho_w H^2 R (theta +- sin(theta)) / 2 (R int cos^2 and R int sin^2 over the angle).
- the acoustic reservoir: extruded along upstream (-y), it is the prism between the faceted face and the far plane
  y = -L, of volume h_w (L c + sum_k (x_k+1 - x_k)(y_k + y_k+1)/2) (c the chord; the trapezoid rule is exact on
  the straight facets); under a vertical ground acceleration a the water column's exact pressure is
  rho a (h_w - z) (rigid bottom, vertical walls, p = 0 at the surface), which pushes the dam downstream with
  rho a h_w^2 / 2 * c: again the projection.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse.linalg as spla

import generators
import masonrydam
from generators import arch_dam_3d
from masonrydam.effects.reservoir.acoustic import acoustic_matrices, build_fluid_mesh
from masonrydam.effects.reservoir.added_mass import westergaard_mass
from masonrydam.effects.reservoir.hydrostatics import facet_pressure_forces
from masonrydam.elements.quadrature import tensor_rule
from masonrydam.elements.shapes import shape_functions
from masonrydam.mesh.facets import owner_centroids

RHO_W = 1000.0
G = 9.80665  # m/s2, standard gravity (the scenes' default [model] gravity)
HEIGHT, R, THETA_DEG, T = 20.0, 40.0, 100.0, 4.0
THETA = math.radians(THETA_DEG)
CHORD = 2.0 * R * math.sin(THETA / 2.0)


def arch(level=15.0, order=1, n_monoliths=2, element_size=5.0, **kw):
    return arch_dam_3d(height=HEIGHT, crest_radius=R, central_angle_deg=THETA_DEG, crest_thickness=T,
                       n_monoliths=n_monoliths, element_size=element_size, order=order, reservoir_level=level, **kw)


def face(mesh, name="upstream_face"):
    fs = mesh.facet_sets[name]
    facets = np.asarray(fs.facets, dtype=np.int64)
    return fs.type, facets, owner_centroids(mesh, fs.type, facets)


def base_chain(mesh):
    """The extrados nodes on the base (z = 0), ordered by angle: (x, y) (N + 1, 2) and the angles (N + 1,)."""
    nodes = np.unique(mesh.facet_sets["upstream_face"].facets)
    P = mesh.points[nodes]
    P = P[np.abs(P[:, 2]) < 1e-9]
    phi = np.arctan2(P[:, 0], R - P[:, 1])
    _, k = np.unique(np.round(phi, 12), return_index=True)  # sorted; the two faces of a joint once
    return P[k, :2], phi[k]


def resultant(f):
    return f.reshape(-1, 3).sum(axis=0)


def hex8_volumes(nodes, elements):
    """Volumes (m3) of hex8 elements, 2 x 2 x 2 Gauss points (exact: det J is of degree 2 per variable), and
    the smallest det J at those points."""
    pts, w = tensor_rule("gauss", 2, 3)
    _, dN = shape_functions("hex8", pts)
    det = np.linalg.det(np.einsum("qrn,end->eqrd", dN, nodes[elements]))
    return det @ w, det.min()


# ---------------------------------------------------------------------------------------------
# hydrostatics


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("level, node_layer", [(15.0, True), (13.7, False)])
def test_hydrostatic_resultant_is_the_force_on_the_projection(order, level, node_layer):
    """F_y = rho g h_w^2 / 2 * 2 R sin(theta/2), F_x = F_z = 0, with the water line on a node layer (the
    generator's reservoir_level) or across a row of facets (partly wet facets clipped at the level)."""
    mesh = arch(level=level if node_layer else None, order=order)
    ft, facets, inward = face(mesh)
    xy, _ = base_chain(mesh)
    assert np.allclose(np.hypot(xy[:, 0], R - xy[:, 1]), R, rtol=1e-14)  # the nodes lie on the circle
    assert xy[-1, 0] - xy[0, 0] == pytest.approx(CHORD, rel=1e-14)
    f = facet_pressure_forces(mesh.points, ft, facets, inward, surface_level=level, unit_weight=RHO_W * G,
                              vertical_axis=2)
    F = resultant(f)
    expected = RHO_W * G * level**2 / 2.0 * CHORD
    assert F[1] == pytest.approx(expected, rel=1e-12)  # downstream: the water pushes the arch into its abutments
    assert abs(F[0]) <= 1e-12 * expected and abs(F[2]) <= 1e-12 * expected
    # each half of the arch (facets at x > 0) is pushed towards the crown by the force on its own projection
    # on the plane x = 0: rho g h_w^2 / 2 * R (1 - cos(theta/2)) (and along y by half the chord's)
    right = mesh.points[facets].mean(axis=1)[:, 0] > 0.0
    Fr = resultant(facet_pressure_forces(mesh.points, ft, facets[right], inward[right], surface_level=level,
                                         unit_weight=RHO_W * G, vertical_axis=2))
    half = RHO_W * G * level**2 / 2.0 * R
    assert Fr[0] == pytest.approx(-half * (1.0 - math.cos(THETA / 2.0)), rel=1e-12)
    assert Fr[1] == pytest.approx(half * math.sin(THETA / 2.0), rel=1e-12)


def test_hydrostatic_resultant_on_a_benched_valley():
    """Monoliths of a trapezoidal valley stand on benches z_b,i (with the rock below): the projection of the
    wetted face is a row of rectangles, one per monolith, R (sin(phi_i+1) - sin(phi_i)) wide and
    h_w - z_b,i high, so F_y = rho g / 2 sum_i R (sin(phi_i+1) - sin(phi_i)) (h_w - z_b,i)^2 (only monoliths
    whose base is under water), F_x = 0 by symmetry."""
    level, n = 15.0, 6
    mesh = arch(level=level, n_monoliths=n, valley_bottom_width=20.0, foundation_depth=10.0, foundation_extent=5.0)
    ft, facets, inward = face(mesh)
    F = resultant(facet_pressure_forces(mesh.points, ft, facets, inward, surface_level=level, unit_weight=RHO_W * G,
                                        vertical_axis=2))
    X = mesh.points[facets]
    mid = np.arctan2(X[:, :, 0].mean(axis=1), R - X[:, :, 1].mean(axis=1))
    edges = np.linspace(-THETA / 2.0, THETA / 2.0, n + 1)
    which = np.searchsorted(edges, mid) - 1
    zb = np.array([X[which == i][:, :, 2].min() for i in range(n)])
    assert len(np.unique(zb)) >= 3  # benched: the valley floor and at least two bench levels
    depth = np.maximum(level - zb, 0.0)
    expected = RHO_W * G / 2.0 * (R * np.diff(np.sin(edges)) * depth**2).sum()
    assert F[1] == pytest.approx(expected, rel=1e-12)
    assert abs(F[0]) <= 1e-12 * expected and abs(F[2]) <= 1e-12 * expected


# ---------------------------------------------------------------------------------------------
# Westergaard's added mass


def depth_integral(zs, level, lumped):
    """int_0^level m_a dz as the added mass integrates it: a flat strip 1 m wide (normal e_y) on the same
    node layers zs, rigid translation along y."""
    zs = zs[zs <= level + 1e-9]
    pts = np.array([[x, 0.0, z] for z in zs for x in (0.0, 1.0)])
    n = len(zs) - 1
    facets = np.array([[2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2] for i in range(n)])
    M = westergaard_mass(pts, "quad4", facets, level=level, reservoir_depth=level, density=RHO_W, vertical_axis=2,
                         lumped=lumped)
    e = np.zeros(M.shape[0])
    e[1::3] = 1.0
    return float(e @ M @ e)


def polygon_sums(xy):
    """sum_k w_k (n n^T)_ij of the chain: n_k = (e_y, -e_x) / w_k for the edge e_k, w_k = |e_k|."""
    e = np.diff(xy, axis=0)
    w = np.linalg.norm(e, axis=1)
    return (e[:, 1] ** 2 / w).sum(), (e[:, 0] ** 2 / w).sum(), (-e[:, 0] * e[:, 1] / w).sum()


@pytest.mark.parametrize("lumped", [False, True])
def test_westergaard_added_mass_of_a_rigid_translation(lumped):
    """M_yy, M_xx = (depth integral) * sum_k w_k cos^2 / sin^2 (m_k) to round-off, the polygon's closed form,
    M_xy = M_xz = M_yz = M_zz = 0; the depth integral within 1e-4 of 7/12 rho_w H^2 (Gauss points on the square
    root, a node on the water line, three rows of facets under it)."""
    level = 15.0
    mesh = arch(level=level)
    ft, facets, _ = face(mesh)
    M = westergaard_mass(mesh.points, ft, facets, level=level, reservoir_depth=level, density=RHO_W,
                         vertical_axis=2, lumped=lumped)
    iota = np.zeros((M.shape[0], 3))
    for c in range(3):
        iota[c::3, c] = 1.0
    Mr = iota.T @ (M @ iota)  # (3, 3) rigid-body added mass, kg
    xy, phi = base_chain(mesh)
    sxx, syy, sxy = polygon_sums(xy)
    Iz = depth_integral(np.unique(mesh.points[np.unique(facets), 2]), level, lumped)
    assert Iz == pytest.approx(7.0 / 12.0 * RHO_W * level**2, rel=1e-4)  # measured 4.9e-5 (3 rows of facets)
    assert Mr[1, 1] == pytest.approx(Iz * syy, rel=1e-12)
    assert Mr[0, 0] == pytest.approx(Iz * sxx, rel=1e-12)
    assert np.abs(Mr[[0, 0, 1, 2], [1, 2, 2, 2]]).max() <= 1e-12 * Mr[1, 1]
    # the polygon of equal angles Delta = theta / N in closed form
    N = len(phi) - 1
    D = THETA / N
    assert np.allclose(np.diff(phi), D, rtol=1e-12)
    assert syy == pytest.approx(R * math.sin(D / 2) * (N + math.sin(THETA) / math.sin(D)), rel=1e-13)
    assert sxx == pytest.approx(R * math.sin(D / 2) * (N - math.sin(THETA) / math.sin(D)), rel=1e-13)


def test_polygon_sum_converges_to_the_circle():
    """The chain's sums approach R (theta +- sin(theta)) / 2 as the arch is refined, by O(Delta^2): the
    error falls by about 4 when the element size halves."""
    circle_y = R * (THETA + math.sin(THETA)) / 2.0
    circle_x = R * (THETA - math.sin(THETA)) / 2.0
    errs = []
    for h in (10.0, 5.0, 2.5):
        sxx, syy, _ = polygon_sums(base_chain(arch(level=None, element_size=h, n_monoliths=1))[0])
        errs.append((syy / circle_y - 1.0, sxx / circle_x - 1.0))
    errs = np.abs(np.array(errs))
    assert errs[-1].max() < 2e-3
    ratio = errs[:-1] / errs[1:]
    assert np.all((ratio > 3.5) & (ratio < 4.5))


# ---------------------------------------------------------------------------------------------
# the acoustic reservoir extruded along the stream


def test_acoustic_reservoir_is_the_prism_in_front_of_the_arch():
    """The fluid mesh fills the prism between the faceted face and the far plane exactly (no overlap, no
    gap: the element volumes add up to the closed form), every column of fluid nodes runs along -y, and a
    vertical ground acceleration gives the hydrostatic-shaped pressure rho a (h_w - z) and the force
    rho a h_w^2 / 2 * chord downstream on the arch."""
    level, L = 15.0, 30.0
    mesh = arch(level=level)
    ft, facets, inward = face(mesh)
    fm = build_fluid_mesh(mesh.points, ft, facets, inward, level=level, vertical_axis=2, upstream=(0.0, -1.0, 0.0),
                          length=L, element_size=5.0)
    vol, det_min = hex8_volumes(fm.nodes, fm.elements)
    assert det_min > 0.0
    xy, _ = base_chain(mesh)
    trapezoids = (np.diff(xy[:, 0]) * (xy[1:, 1] + xy[:-1, 1]) / 2.0).sum()
    assert vol.sum() == pytest.approx(level * (L * CHORD + trapezoids), rel=1e-12)
    cols = fm.nodes.reshape(fm.n_layers + 1, fm.n_face, 3)
    assert np.allclose(cols[:, :, [0, 2]], cols[:1, :, [0, 2]], atol=1e-12 * R)
    assert np.allclose(cols[-1, :, 1], -L, atol=1e-12 * R)  # the far plane, L upstream of the crown
    A = acoustic_matrices(fm, mesh.points, ft, facets, inward, density=RHO_W, sound_speed=None)
    # the projection again: the fluid's normal (into the dam) integrates to (0, c h_w, 0) over the wet face
    proj = np.asarray(A.Q_all.sum(axis=1)).ravel().reshape(-1, 3).sum(axis=0)
    assert proj[1] == pytest.approx(CHORD * level, rel=1e-12) and abs(proj[0]) <= 1e-12 * CHORD * level
    p = spla.spsolve(A.H.tocsc(), -RHO_W * (A.B @ np.array([0.0, 0.0, 1.0])))
    assert np.allclose(p, RHO_W * (level - fm.nodes[A.free_nodes, 2]), atol=1e-8 * RHO_W * level)
    F = resultant(A.Q @ p)
    assert F[1] == pytest.approx(RHO_W * level**2 / 2.0 * CHORD, rel=1e-9)
    assert abs(F[0]) <= 1e-9 * F[1]


# ---------------------------------------------------------------------------------------------
# a scene: gravity, the reservoir, the modes with the water


def arch_scene(dynamic, level=15.0):
    s = {
        "model": {"name": "arch_water", "dimension": 3},
        "mesh": {"generator": "arch_dam_3d", "parameters": {
            "height": HEIGHT, "crest_radius": R, "central_angle_deg": THETA_DEG, "crest_thickness": T,
            "n_monoliths": 1, "element_size": 5.0, "reservoir_level": level}},
        "materials": {"dam": {"youngs_modulus": "25000 MPa", "poisson_ratio": 0.2, "density": 2400.0}},
        "supports": [{"set": "base", "components": ["x", "y", "z"]},
                     {"set": "dam_ends", "components": ["x", "y", "z"]}],
        "reservoir": {"level": level, "dynamic": dynamic},
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}, {"type": "reservoir"}]},
                   {"name": "modes", "type": "modal", "modes": 3}],
    }
    if dynamic == "acoustic":
        s["reservoir"]["acoustic"] = {"sound_speed": "incompressible"}
    if dynamic == "none":
        del s["reservoir"]["dynamic"]
    return s


@pytest.mark.slow
def test_a_scene_with_water_on_the_arch(monkeypatch):
    """The static water's reactions sum to -rho g h_w^2 / 2 * chord along y; Westergaard's added mass and the
    incompressible acoustic reservoir both lower the arch's frequencies."""
    monkeypatch.setitem(generators.GENERATORS, "arch_dam_3d", arch_dam_3d)
    level = 15.0
    out = {d: masonrydam.run(arch_scene(d, level)) for d in ("none", "westergaard", "acoustic")}
    ds = out["none"]
    Ry = ds.reaction.sel(component="y").values[-1]
    assert Ry.sum() == pytest.approx(-RHO_W * G * level**2 / 2.0 * CHORD, rel=1e-9)  # measured 1e-15
    dry = out["none"].frequency.values
    for d in ("westergaard", "acoustic"):
        wet = out[d].frequency.values
        assert np.all(wet < 0.98 * dry), (d, wet, dry)
    # measured: 14.17, 15.34, 23.37 Hz dry; Westergaard 8.4 to 9.7 % lower, the acoustic water 4.6 to 5.0 %
    # (Westergaard's rigid-dam mass, local to each point of the face, is the larger on these flexible modes)
    assert np.all(out["westergaard"].frequency.values < out["acoustic"].frequency.values)
