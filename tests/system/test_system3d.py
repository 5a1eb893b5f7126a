"""3D models end to end: interface insertion, the 8-node surface interface in a full analysis,
closed forms and the 2D plane-strain limit.

Sources: the block on an incline (static, closed form) extended to an
oblique push (Coulomb friction is isotropic in the joint plane: sliding when the tangential force
reaches mu times the normal force, along the tangential force); the 8-node interface
of Tzamtzis & Asteris (eqs. 1-11) and joint law (sec. 3.4); elementary elasticity for the uniform
compression of a stack of blocks.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import masonrydam
from generators.grid3d import Box, boxes_to_mesh, rotation_matrix
from repository_paths import EXAMPLES

G = 9.80665


def _components(mesh):
    """Connected bodies of the continuum elements (shared nodes only, interfaces excluded)."""
    rows, cols = [], []
    off = 0
    for b in mesh.blocks:
        e = np.repeat(np.arange(len(b.cells)) + off, b.cells.shape[1])
        rows.append(e)
        cols.append(b.cells.ravel())
        off += len(b.cells)
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    inc = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(off, mesh.n_nodes)).tocsr()
    n, lab = connected_components(inc @ inc.T, directed=False)
    return n, lab


@pytest.mark.parametrize("order", [1, 2])
def test_insert_interfaces_3d_cross_junction(order):
    """Four columns of two boxes each on a base: bed joints meet head and 'collar' joints in a
    cross along the vertical line x = y = 0.5. Every box must become its own body; the node on the
    cross line in the middle of the column stack is shared by 8 boxes and so has 8 copies; the
    count of interface elements follows from the grid (element size 0.25)."""
    boxes = [Box(0, 0, 0, 1, 1, 0.5, "base")]
    for k, (x0, y0) in enumerate([(0, 0), (0.5, 0), (0, 0.5), (0.5, 0.5)]):
        for z0 in (0.5, 1.0):
            boxes.append(Box(x0, y0, z0, x0 + 0.5, y0 + 0.5, z0 + 0.5, "unit"))
    mesh = boxes_to_mesh(boxes, 0.25, order=order)
    n_bodies, _ = _components(mesh)
    assert n_bodies == len(boxes)
    # bed joints: base/lower row (1 x 1 m -> 16 faces) + lower/upper row (16); head (normal x) and
    # collar (normal y) planes: 2 rows x 2 half-planes x (0.5 x 0.5 -> 4 faces) = 16 each
    counts = {j.name: len(j.cells) for j in mesh.joints}
    assert counts == {"bed": 32, "head": 16, "collar": 16}
    itype = "interface_quad4" if order == 1 else "interface_quad8"
    assert {j.type for j in mesh.joints} == {itype}
    # copies of the cross-line node at (0.5, 0.5, 1.0): 4 columns x (below, above) = 8
    at = np.nonzero(np.all(np.isclose(mesh.points, [0.5, 0.5, 1.0]), axis=1))[0]
    assert len(at) == 8
    if order == 2:
        mid = np.nonzero(np.all(np.isclose(mesh.points, [0.5, 0.5, 0.875]), axis=1))[0]
        assert len(mid) == 4  # a mid-edge node on the vertical cross line, between 4 boxes
    # orientation: normals point +z (bed), +x (head), +y (collar); top nodes lie on the +n side of
    # the element's bottom face nodes' body: the bottom node's element centroid is below the joint
    from masonrydam.assembly.groups import InterfaceGroup
    from masonrydam.materials import mohr_coulomb as mc

    expect = {"bed": [0, 0, 1], "head": [1, 0, 0], "collar": [0, 1, 0]}
    scheme = "lumped" if order == 1 else "lobatto"
    for j in mesh.joints:
        g = InterfaceGroup(j.name, j.type, j.cells, mesh.points, 3, mc.joint_params(1e9, 1e9, 0.0, 30.0),
                           np.ones(len(j.cells)), "mohr_coulomb", scheme)
        np.testing.assert_allclose(g.frame[:, :, 2, :].reshape(-1, 3), np.tile(expect[j.name], (g.frame.shape[0] * g.nip, 1)),
                                   atol=1e-12)
        assert np.isclose(g.jw.sum(), counts[j.name] * 0.0625)
    # bottom copies belong to elements below the joint plane, top copies to elements above
    node_elem_centroid = {}
    for b in mesh.blocks:
        cen = mesh.points[b.cells].mean(axis=1)
        for e, cell in enumerate(b.cells):
            for n in cell:
                node_elem_centroid[int(n)] = cen[e]
    bed = next(j for j in mesh.joints if j.name == "bed")
    ns = bed.cells.shape[1] // 2
    for cell in bed.cells[:10]:
        z = mesh.points[cell[0], 2]
        assert node_elem_centroid[int(cell[0])][2] < z < node_elem_centroid[int(cell[ns])][2]


def _incline_scene(beta_deg, k, theta_deg, ks_r=0.0, steps=4, phi=30.0):
    """A thin block (1 x 1 x 0.05 m) on a base, the model tilted by beta about y; body force
    rho * g * (k cos(theta), k sin(theta), -1) applied proportionally (pseudo-static seismic push
    in the oblique horizontal direction theta)."""
    g_vec = [G * k * math.cos(math.radians(theta_deg)), G * k * math.sin(math.radians(theta_deg)), -G]
    joint = {"normal_stiffness": 1e12, "shear_stiffness": 1e12, "friction_angle": phi,
             "residual_shear_stiffness": ks_r}
    return {
        "model": {"dimension": 3, "gravity": g_vec},
        "mesh": {"generator": "blocks_3d", "parameters": {
            "blocks": [{"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 0.1, "group": "base"},
                       {"x0": 0, "y0": 0, "z0": 0.1, "x1": 1, "y1": 1, "z1": 0.15, "group": "block"}],
            "element_size": 0.25, "rotation_deg": [0.0, -beta_deg, 0.0]}},
        "materials": {g: {"youngs_modulus": "200 GPa", "poisson_ratio": 0.0, "density": 2000.0} for g in ("base", "block")},
        "joints": {"joints": joint},
        "supports": [{"set": "base_nodes"}],
        "stages": [{"name": "push", "steps": steps, "loads": [{"type": "self_weight"}]}],
        "solver": {"max_step_cuts": 3},
    }


def _critical_k(beta_deg, theta_deg, phi=30.0):
    """Closed form: the body force F ~ (k cos t, k sin t, -1) slides the block when its component in
    the joint plane reaches tan(phi) times its normal (compressive) component."""
    n = rotation_matrix([0.0, -beta_deg, 0.0]) @ np.array([0.0, 0.0, 1.0])
    mu = math.tan(math.radians(phi))

    def excess(k):
        f = np.array([k * math.cos(math.radians(theta_deg)), k * math.sin(math.radians(theta_deg)), -1.0])
        fn = f @ n
        return np.linalg.norm(f - fn * n) - mu * (-fn)

    return brentq(excess, 0.0, 2.0), n


@pytest.mark.parametrize("beta_deg, theta_deg", [(10.0, 60.0), (15.0, 135.0)])
@pytest.mark.reference
def test_block_on_incline_oblique_push_slides_at_closed_form_load(beta_deg, theta_deg):
    """Block on an incline in 3D with an oblique horizontal push (perfectly plastic joint): the
    block holds at 97 % of the closed-form seismic coefficient and slides (no equilibrium) at
    103 %."""
    k_crit, _ = _critical_k(beta_deg, theta_deg)
    ds = masonrydam.run(_incline_scene(beta_deg, 0.97 * k_crit, theta_deg))
    assert (ds.joint_state.isel(step=-1).values != 2).all(), "no point opens"
    W_scale = 2000 * G * 0.05 / 1e12  # elastic slip scale (m)
    slip = np.linalg.norm(ds.joint_slip.isel(step=-1).values, axis=1)
    assert slip.max() < 3 * W_scale, "held: slip stays elastic"
    with pytest.raises((masonrydam.ConvergenceError, masonrydam.MechanismError)):
        masonrydam.run(_incline_scene(beta_deg, 1.03 * k_crit, theta_deg))


def test_block_on_incline_oblique_push_slides_along_applied_shear():
    """With a residual shear stiffness the block keeps equilibrium past the sliding load; under
    proportional loading the slip vector of every joint point is parallel to the tangential part
    of the applied force (isotropic Coulomb friction, Tzamtzis & Asteris sec. 3.4), and every point slides."""
    beta, theta = 10.0, 60.0
    k_crit, n = _critical_k(beta, theta)
    k = 1.3 * k_crit
    ds = masonrydam.run(_incline_scene(beta, k, theta, ks_r=1e10))
    assert (ds.joint_state.isel(step=-1).values == 1).all()
    f = np.array([k * math.cos(math.radians(theta)), k * math.sin(math.radians(theta)), -1.0])
    f_t = f - (f @ n) * n
    f_t /= np.linalg.norm(f_t)
    frame = ds.joint_shear_axis.values  # (njp, 2, 3)
    slip_local = ds.joint_slip.isel(step=-1).values  # (njp, 2)
    slip_global = np.einsum("pk,pkd->pd", slip_local, frame)
    cosang = slip_global @ f_t / np.linalg.norm(slip_global, axis=1)
    assert cosang.min() > math.cos(math.radians(1.0)), "slip within 1 degree of the applied shear"
    # far beyond the elastic slip: it really slides
    assert np.linalg.norm(slip_global, axis=1).min() > 10 * 2000 * G * 0.05 / 1e12


def test_extruded_plane_strain_slab_matches_2d():
    """A 2D plane-strain block on an incline pushed past sliding, and the same model extruded into a
    3D slab (hex8 + 8-node interfaces, out-of-plane displacement held on both faces): the push force
    per unit depth and the joint tractions must agree (plane strain is the 3D slab with eps_yy = 0)."""
    blocks = [{"x0": 0.0, "y0": 0.0, "x1": 2.0, "y1": 0.5, "group": "base"},
              {"x0": 0.0, "y0": 0.5, "x1": 2.0, "y1": 0.6, "group": "block"}]
    params = {"blocks": blocks, "element_size": 0.25, "rotation_deg": 10.0}
    # dry, perfectly plastic joint: with cohesion the first slip breaks the bond brittly, and a
    # residual stiffness ks_r * slip of the order of the friction force tips the block over
    joint = {"normal_stiffness": 1e12, "shear_stiffness": 1e12, "friction_angle": 30.0}
    mats = {g: {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": 2000.0} for g in ("base", "block")}
    push = [{"name": "gravity", "loads": [{"type": "self_weight"}]},
            {"name": "push", "steps": 6, "loads": [{"type": "displacement", "set": "top", "components": ["x"],
                                                    "value": [2e-4]}]}]
    sc2 = {"model": {"hypothesis": "plane_strain", "thickness": 1.0}, "mesh": {"generator": "blocks_2d", "parameters": params},
           "materials": mats, "joints": {"joints": joint}, "supports": [{"set": "base", "components": ["x", "y"]}],
           "stages": push}
    depth = 0.4
    sc3 = {"model": {"dimension": 3, "gravity": [0.0, 0.0, -G]},
           "mesh": {"generator": "extruded", "parameters": {"generator": "blocks_2d", "parameters": params,
                                                            "depth": depth, "layers": 1}},
           "materials": mats, "joints": {"joints": joint},
           "supports": [{"set": "base", "components": ["x", "z"]}, {"set": "front", "components": ["y"]},
                        {"set": "back", "components": ["y"]}],
           "stages": [push[0], {**push[1], "loads": [{**push[1]["loads"][0]}]}]}
    # the 2D "base" and "top" node sets are extruded; the 3D supports fix x, z on the base
    sc3["supports"][1]["set"] = "front"
    ds2 = masonrydam.run(sc2)
    ds3 = masonrydam.run(sc3)
    a = math.radians(10.0)
    top2 = np.isclose(-math.sin(a) * ds2.x + math.cos(a) * ds2.y, 0.6)
    top3 = np.isclose(-math.sin(a) * ds3.x + math.cos(a) * ds3.z, 0.6)
    P2 = ds2.reaction.sel(component="x").where(top2).sum("node").values
    P3 = ds3.reaction.sel(component="x").where(top3).sum("node").values / depth
    np.testing.assert_allclose(P3, P2, rtol=1e-6)
    assert (ds2.joint_state.isel(step=-1).values == 1).all()
    # joint tractions at matching points (the 3D slab has one point per 2D point on each face)
    key2 = np.round(ds2.joint_x.values, 9)
    for face_y in (0.0, depth):
        on = np.isclose(ds3.joint_y.values, face_y)
        key3 = np.round(ds3.joint_x.values[on], 9)
        o2, o3 = np.lexsort((ds2.joint_y.values, key2)), np.lexsort((ds3.joint_z.values[on], key3))
        tn2 = ds2.joint_traction_normal.isel(step=-1).values[o2]
        tn3 = ds3.joint_traction_normal.isel(step=-1).values[on][o3]
        np.testing.assert_allclose(tn3, tn2, rtol=1e-6, atol=1e-6 * np.abs(tn2).max())
        ts2 = ds2.joint_traction_shear.isel(step=-1, shear_direction=0).values[o2]
        ts3 = ds3.joint_traction_shear.isel(step=-1).values[on][o3]
        np.testing.assert_allclose(ts3[:, 0], ts2, rtol=1e-6, atol=1e-6 * np.abs(ts2).max())
        assert np.abs(ts3[:, 1]).max() < 1e-6 * np.abs(ts2).max(), "no out-of-plane shear"


def test_stack_of_blocks_under_top_pressure_is_uniform():
    """A 3D running-bond stack of blocks (bed, head and collar joints) under a uniform top pressure p,
    supported so that the exact solution is the homogeneous one (base: z, left face: x, front
    face: y): sigma_zz = -p in every block, bed joints carry t_n = -p with no shear, head and collar
    joints carry nothing (elementary elasticity; the joints do not disturb a homogeneous state)."""
    boxes = []
    L, H, T = 0.4, 0.1, 0.2
    for course in range(3):
        off = 0.0 if course % 2 == 0 else L / 2
        xs = [0.0] + [off + L * i for i in range(4) if 0 < off + L * i < 1.2] + [1.2]
        xs = sorted(set(np.round(xs, 12)))
        for x0, x1 in zip(xs[:-1], xs[1:]):
            for y0 in (0.0, T):  # two wythes: a collar joint at y = T
                boxes.append({"x0": x0, "y0": y0, "z0": course * H, "x1": x1, "y1": y0 + T, "z1": (course + 1) * H,
                              "group": "units"})
    p = 0.5e6
    sc = {"model": {"dimension": 3},
          "mesh": {"generator": "blocks_3d", "parameters": {"blocks": boxes, "element_size": 0.1}},
          "materials": {"units": {"youngs_modulus": 10e9, "poisson_ratio": 0.2, "density": 0.0}},
          "joints": {"joints": {"normal_stiffness": 5e10, "shear_stiffness": 2e10, "friction_angle": 35.0}},
          "supports": [{"set": "base", "components": ["z"]}, {"set": "left", "components": ["x"]},
                       {"set": "front", "components": ["y"]}],
          "stages": [{"name": "press", "loads": [{"type": "pressure", "set": "top_face", "pressure": p}]}]}
    ds = masonrydam.run(sc)
    n = np.stack([ds.joint_normal_x.values, ds.joint_normal_y.values, ds.joint_normal_z.values], axis=1)
    tn = ds.joint_traction_normal.isel(step=-1).values
    ts = ds.joint_traction_shear.isel(step=-1).values
    bed = np.isclose(n[:, 2], 1.0)
    assert bed.sum() > 0 and (~bed).sum() > 0
    np.testing.assert_allclose(tn[bed], -p, rtol=1e-8)
    assert np.abs(tn[~bed]).max() < 1e-8 * p
    assert np.abs(ts).max() < 1e-8 * p
    # the top rises nowhere differently: uniform vertical displacement of the top face
    uz_top = ds.displacement.isel(step=-1).sel(component="z").values[np.isclose(ds.z.values, 0.3)]
    assert np.ptp(uz_top) < 1e-9 * np.abs(uz_top).max()
    # three courses of continuum plus two bed joints (the bottom course sits on the support)
    expected = -p * 0.3 / 10e9 - 2 * p / 5e10
    np.testing.assert_allclose(uz_top.mean(), expected, rtol=1e-8)


@pytest.mark.slow
def test_dam_3d_gravity_general_newton_converges_where_joints_stay_open():
    """The 3D dam example (gravity only, element_size 20): contraction joints and abutment steps open
    under self-weight and stay open. The general Newton path must converge quadratically there: a
    pattern of joint states that stays the same from one iteration to the next is convergence, not
    chatter (the guard once took it for chatter, gave open points their initial stiffness and
    stalled Newton at 1-4 % per iteration, so that this stage failed). Checks: global equilibrium
    (the vertical reactions carry the dam's weight) and the same final joint states as the steps
    solved on the joint unknowns."""
    import tomllib
    from pathlib import Path

    text = (EXAMPLES / "dam_3d_gravity.toml").read_text()
    runs = {}
    for js in ("off", "auto"):
        sc = tomllib.loads(text)
        sc["mesh"]["parameters"]["element_size"] = 20.0
        sc["solver"] = {"joint_space": js}
        runs[js] = masonrydam.run(sc)
    general, condensed = runs["off"], runs["auto"]
    assert int(condensed.attrs["joint_space_steps"]) == 4 and int(general.attrs["joint_space_size"]) == 0
    assert int(general.attrs["newton_iterations"]) <= 40 and int(general.attrs["step_cuts"]) == 0
    last = general.isel(step=-1)
    assert (last.joint_state.values == 2).sum() > 50, "abutment steps and contraction joints open"
    # equilibrium: the reactions at the foundation bottom carry the weight of the dam (rho g V)
    sc = masonrydam.Scene(tomllib.loads(text.replace("element_size = 6.0", "element_size = 20.0")))
    from masonrydam.scene import build_mesh, build_model, build_stages

    mesh = build_mesh(sc.normalized, sc.base_dir)
    model = build_model(sc.normalized, mesh)
    weight = -build_stages(sc.normalized, mesh, model, sc.base_dir)[0].force.reshape(-1, 3)[:, 2].sum()
    assert weight > 1e8
    assert float(last.reaction.sel(component="z").sum()) == pytest.approx(weight, rel=1e-6)
    np.testing.assert_array_equal(general.joint_state.values[-1], condensed.joint_state.values[-1])
    u = general.displacement.values[-1]
    assert np.abs(condensed.displacement.values[-1] - u).max() <= 1e-6 * np.abs(u).max()
