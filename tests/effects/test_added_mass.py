"""Westergaard's added mass (``[reservoir] dynamic = "westergaard"``).

References: Westergaard (1933), Trans. ASCE 98:418-433: on a rigid vertical face accelerating with a
the pressure is p(z) = 7/8 rho a sqrt(H z) and its resultant 7/12 rho a H^2; the generalised form m_a n n^T on
inclined faces (Kuo 1982, UCB/EERC-82/10).
The rigid block on a joint follows tests/test_modal_stage.py (Chopra, Dynamics of Structures, sec. 10.2)
with the added mass integrated in closed form over the wetted face.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import masonrydam
from masonrydam.effects.reservoir.added_mass import westergaard_mass
from masonrydam.errors import SceneError
from scenes import ELASTIC_JOINT_BLOCK as BLOCK, block_on_elastic_joint

RHO_W = 1000.0


def _column(H, n, order=1, x=0.0):
    """A vertical face at x from z = 0 to H: coords (2D) and line facets."""
    if order == 1:
        z = np.linspace(0.0, H, n + 1)
        return np.c_[np.full_like(z, x), z], np.c_[np.arange(n), np.arange(1, n + 1)], "line2"
    z = np.linspace(0.0, H, 2 * n + 1)
    return (np.c_[np.full_like(z, x), z],
            np.c_[np.arange(0, 2 * n, 2), np.arange(2, 2 * n + 1, 2), np.arange(1, 2 * n, 2)], "line3")


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("lumped", [False, True])
@pytest.mark.parametrize("level", [10.0, 8.7])
@pytest.mark.reference
def test_resultant_on_a_rigid_vertical_face(order, lumped, level):
    """A rigid translation a of the face: the force -M_a iota a has the resultant 7/12 rho a H^2, with the
    water line on a node or inside a facet."""
    coords, facets, ft = _column(10.0, 10, order)
    M = westergaard_mass(coords, ft, facets, level=level, reservoir_depth=level, density=RHO_W, vertical_axis=1,
                         lumped=lumped)
    iota = np.zeros(M.shape[0])
    iota[0::2] = 1.0
    assert float(iota @ (M @ iota)) == pytest.approx(7.0 / 12.0 * RHO_W * level**2, rel=3e-4)
    # n n^T with n = x: nothing vertical
    iota_z = np.zeros(M.shape[0])
    iota_z[1::2] = 1.0
    assert abs(float(iota_z @ (M @ iota_z))) < 1e-12 * RHO_W * level**2
    np.testing.assert_allclose((M - M.T).toarray(), 0.0, atol=1e-9)


@pytest.mark.reference
def test_pressure_parabola_at_the_nodes():
    """Lumped (HRZ) added mass per node over the node's tributary length tends to 7/8 rho sqrt(H z)."""
    H = 10.0
    coords, facets, ft = _column(H, 200)
    M = westergaard_mass(coords, ft, facets, level=H, reservoir_depth=H, density=RHO_W, vertical_axis=1, lumped=True)
    d = M.diagonal()[0::2]
    trib = np.full(len(d), H / 200)
    trib[[0, -1]] *= 0.5
    z = H - coords[:, 1]
    inner = slice(20, -20)  # away from the base and the surface (sqrt), where the tributary averaging is O(h^2)
    np.testing.assert_allclose(d[inner] / trib[inner], 0.875 * RHO_W * np.sqrt(H * z[inner]), rtol=1e-3)


@pytest.mark.parametrize("angle", [0.0, 17.0, 90.0, 233.0])
def test_inclined_and_rotated_faces(angle):
    """Rotation invariance: a sloping face (1 horizontal : 2 vertical) turned about the vertical axis in
    3D: the added mass along the face normal is the same, and nothing acts along the face."""
    H, W = 10.0, 3.0
    ny, nz = 3, 10
    s = np.linspace(0.0, 1.0, nz + 1)
    y = np.linspace(0.0, W, ny + 1)
    # face x = 0.5 (H - z) (leaning downstream), quads, then rotated about z by `angle`
    Z, Y = np.meshgrid(H * s, y, indexing="ij")
    X = 0.5 * (H - Z)
    pts = np.c_[X.ravel(), Y.ravel(), Z.ravel()]
    a = np.radians(angle)
    R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    pts = pts @ R.T
    idx = np.arange(len(pts)).reshape(nz + 1, ny + 1)
    quads = np.array([[idx[i, j], idx[i, j + 1], idx[i + 1, j + 1], idx[i + 1, j]]
                      for i in range(nz) for j in range(ny)])
    M = westergaard_mass(pts, "quad4", quads, level=H, reservoir_depth=H, density=RHO_W, vertical_axis=2)
    n = R @ (np.array([1.0, 0.0, 0.5]) / np.sqrt(1.25))
    t = R @ np.array([0.0, 1.0, 0.0])
    un = np.tile(n, len(pts))
    ut = np.tile(t, len(pts))
    # the sloping face is sqrt(1.25) times longer than H per unit height: m_a integrated over the slope
    expected = 7.0 / 12.0 * RHO_W * H**2 * W * np.sqrt(1.25)
    assert float(un @ (M @ un)) == pytest.approx(expected, rel=1e-4)
    assert abs(float(ut @ (M @ ut))) < 1e-10 * expected
    assert abs(float(ut @ (M @ un))) < 1e-10 * expected


B, HB, RHO, T, HE = BLOCK.width, BLOCK.height, BLOCK.density, BLOCK.thickness, BLOCK.element_size
KN, KS = BLOCK.normal_stiffness, BLOCK.shear_stiffness
LEVEL = 0.75


def block_scene(dynamic="westergaard", mass="consistent"):
    """The rigid block on an elastic joint of the modal stage tests with water at LEVEL on its face x = 0
    (``[reservoir] dynamic``), the reservoir's static load in the gravity stage, and 4 modes."""
    return block_on_elastic_joint(modes=4, mass=mass, overrides={
        "model.name": "block_water",
        "reservoir": {"level": LEVEL, "face": "left_edge", "dynamic": dynamic},
        "stages.0.loads": [{"type": "self_weight"}, {"type": "reservoir"}]})


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_rigid_block_with_westergaard_water(mass):
    """Sliding-rocking modes of a rigid block on a joint with the reservoir on its upstream face: the
    rigid-body mass matrix gains int m_a [1, y; y, y^2] dy (y above the joint, water depth H measured
    from the face's lowest point, y = -0.5 m), in closed form."""
    ds = masonrydam.run(block_scene(mass=mass))
    m = RHO * B * HB * T
    A = B * T
    x = np.arange(0.0, B + 1e-9, HE)
    w = np.full(len(x), HE * T)
    w[[0, -1]] *= 0.5
    k_theta = KN * float(np.sum(w * (x - B / 2) ** 2))
    J = m * (B * B + HB * HB) / 12.0
    if mass == "lumped":
        y = np.arange(0.0, HB + 1e-9, HE)
        wy = np.full(len(y), HE)
        wy[[0, -1]] *= 0.5
        J = RHO * T * float(np.sum(np.outer(w / T, wy) * ((x[:, None] - B / 2) ** 2 + (y[None, :] - HB / 2) ** 2)))
    M2 = np.array([[m, m * HB / 2], [m * HB / 2, J + m * HB * HB / 4]])
    # added mass on the block's face, y from 0 to h = LEVEL, depth s = h - y, m_a = 7/8 rho sqrt(Hd s)
    Hd, h, c = LEVEL + 0.5, LEVEL, 0.875 * 1000.0
    m0 = c * np.sqrt(Hd) * h**1.5 * 2.0 / 3.0
    m1 = c * np.sqrt(Hd) * h**2.5 * 4.0 / 15.0
    m2 = c * np.sqrt(Hd) * h**3.5 * 16.0 / 105.0
    M2 = M2 + T * np.array([[m0, m1], [m1, m2]])
    K2 = np.diag([KS * A, k_theta])
    w2 = np.sqrt(scipy.linalg.eigh(K2, M2, eigvals_only=True))
    expected = np.sort(np.concatenate([w2 / (2 * np.pi), [np.sqrt(KN * A / m) / (2 * np.pi)]]))
    # lumped: the HRZ node masses carry the moment of the added mass only to O(h^2)
    np.testing.assert_allclose(ds.frequency.values[:3], expected, rtol=2e-4 if mass == "consistent" else 3e-3)
    dry = masonrydam.run(block_scene(dynamic="none", mass=mass))
    assert ds.frequency.values[0] < dry.frequency.values[0]  # water makes it slower
    assert "Westergaard" in ds.attrs["reservoir_dynamic"]


@pytest.mark.reference
def test_rigid_face_pressure_and_resultant_in_time():
    """A stiff block fixed at its base (no joint) under a slowly rising ground acceleration: the
    hydrodynamic force is -7/12 rho a H^2 T and the face pressure the 7/8 parabola (Westergaard 1933)."""
    s = block_scene()
    s["joints"] = {}
    s["mesh"]["parameters"]["blocks"] = [{"x0": 0.0, "y0": 0.0, "x1": B, "y1": HB, "group": "block"}]
    s["materials"] = {"block": {"youngs_modulus": 1e14, "poisson_ratio": 0.2, "density": RHO}}
    s["reservoir"]["level"] = 0.75
    dt, n = 0.01, 50
    acc = np.linspace(0.0, 2.0, n + 1)  # m/s2, slow against the block's frequencies (rigid: no relative motion)
    s["stages"] = [s["stages"][0],
                   {"name": "quake", "type": "dynamic", "dt": dt, "integrator": "newmark_average",
                    "ground_motion": {"x": {"values": acc.tolist(), "dt": dt}}}]
    ds = masonrydam.run(s)
    last = ds.isel(step=-1)
    a = float(last.ground_acceleration.sel(component="x"))
    H = 0.75
    F = last.hydrodynamic_force.values
    assert F[0] == pytest.approx(-7.0 / 12.0 * 1000.0 * a * H**2 * T, rel=1e-3)
    assert abs(F[1]) < 1e-6 * abs(F[0])
    z = H - ds.face_y.values
    # the face is on the upstream side (outward normal -x): accelerating +x pulls it away from the water
    np.testing.assert_allclose(last.face_pressure.values, -0.875 * 1000.0 * a * np.sqrt(H * z), rtol=1e-3, atol=1e-6)
    assert np.isnan(ds.isel(step=0).hydrodynamic_force.values).all()  # static steps: none


def test_bad_input():
    s = block_scene()
    s["reservoir"]["dynamic"] = "added_mass"
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "reservoir.dynamic"
    s = block_scene()
    s["stages"] = s["stages"][:1]
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "reservoir.dynamic" and "neither" in str(err.value)
    s = block_scene()
    s["reservoir"]["acoustic"] = {"sound_speed": 1440.0}
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "reservoir.acoustic"
    s = block_scene(dynamic="acoustic")
    s["reservoir"]["acoustic"] = {"bottom_reflection": 1.5}
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "reservoir.acoustic.bottom_reflection"


def test_acoustic_needs_a_level_and_a_boundary_face():
    s = block_scene(dynamic="acoustic")
    del s["reservoir"]["level"]
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "reservoir.level"
    # a face through the inside of a block: the facets between two elements of one body
    from types import SimpleNamespace

    from masonrydam.effects.reservoir.moving import _check_on_boundary
    from masonrydam.scene import Scene
    from masonrydam.scene import build_mesh

    sc = Scene(block_scene())
    mesh = build_mesh(sc.normalized, sc.base_dir)
    pts = mesh.points
    inner = np.flatnonzero(np.isclose(pts[:, 0], 1.0) & (pts[:, 1] > 0.01))
    inner = inner[np.argsort(pts[inner, 1])]
    facets = np.c_[inner[:-1], inner[1:]]
    with pytest.raises(SceneError) as err:
        _check_on_boundary(mesh, SimpleNamespace(type="line2", facets=facets, name="middle"))
    assert err.value.key == "reservoir.face" and "not on the boundary" in str(err.value)
    left = mesh.facet_sets["left_edge"].facets
    _check_on_boundary(mesh, SimpleNamespace(type="line2", facets=np.asarray(left), name="left_edge"))  # the real face passes


def test_acoustic_water_above_the_crest_is_a_named_error():
    s = block_scene(dynamic="acoustic")
    s["reservoir"]["level"] = 1.2  # the block's face ends at 1.0 m: the water would overtop it
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "reservoir.level" and "cannot be built" in str(err.value)
