"""End-to-end physics checks of the static engine against closed forms.

Each test builds a scene with the ``blocks_2d`` generator and runs it through ``masonrydam.run``.
Sources: the block on an incline (static, closed form); interface integration (Schellekens & de Borst
1993, IJNME 36:43-66); the joint law of Tzamtzis & Asteris (sec. 3.4, eqs. 11-12).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam

G = 9.80665


def block_scene(*, blocks, joint, rotation=0.0, gravity=(0.0, -G), stages, element_size=0.25, supports=None,
                block_E=20e9, nu=0.0, density=2000.0, thickness=1.0, solver=None):
    groups = sorted({b["group"] for b in blocks})
    sc = {
        "model": {"name": "blocks", "thickness": thickness, "gravity": list(gravity)},
        "mesh": {"generator": "blocks_2d",
                 "parameters": {"blocks": blocks, "element_size": element_size, "rotation_deg": rotation}},
        "materials": {g: {"youngs_modulus": block_E, "poisson_ratio": nu, "density": density} for g in groups},
        "joints": {"joints": joint},
        "supports": supports if supports is not None else [{"set": "base", "components": ["x", "y"]}],
        "stages": stages,
    }
    if solver:
        sc["solver"] = solver
    return sc


BASE = {"x0": 0.0, "y0": 0.0, "x1": 2.0, "y1": 0.5, "group": "base"}
BLOCK = {"x0": 0.0, "y0": 0.5, "x1": 2.0, "y1": 1.0, "group": "block"}


def top_force(ds, component, y_top):
    """Sum of reactions at the nodes on the (unrotated) top edge."""
    return ds.reaction.sel(component=component).where(np.isclose(ds.y, y_top)).sum("node").values


@pytest.mark.parametrize("beta_deg, c", [(10.0, 0.0), (20.0, 0.0), (10.0, 1e3)])
@pytest.mark.reference
def test_block_on_incline_horizontal_push(beta_deg, c):
    """Block on an incline: horizontal force that pushes a block up a slope beta, friction phi,
    cohesion c on the contact area A: P = (W sin b + mu W cos b + c A) / (cos b - mu sin b),
    = W tan(beta + phi) for c = 0. The FE plateau force must match within 1 %."""
    phi = 30.0
    mu = math.tan(math.radians(phi))
    b = math.radians(beta_deg)
    # a wide, low block (2 x 0.1 m) on a fixed base, the whole model rotated by beta; the top edge
    # is pushed horizontally (global x) by a prescribed displacement, its y free. The block is low
    # so that the push's moment does not open the heel (which would break the bond there).
    blocks = [BASE, {**BLOCK, "y1": 0.6}]
    joint = {"normal_stiffness": 1e12, "shear_stiffness": 1e12, "friction_angle": phi, "cohesion": c}
    stages = [{"name": "gravity", "loads": [{"type": "self_weight"}]},
              {"name": "push", "steps": 8,
               "loads": [{"type": "displacement", "set": "top", "components": ["x"], "value": [2e-4]}]}]
    sc = block_scene(blocks=blocks, joint=joint, rotation=beta_deg, stages=stages, block_E=200e9)
    ds = masonrydam.run(sc)
    W = 2000.0 * G * 2.0 * 0.1 * 1.0
    A = 2.0 * 1.0
    expected = (W * math.sin(b) + mu * W * math.cos(b) + c * A) / (math.cos(b) - mu * math.sin(b))
    if c == 0:
        assert expected == pytest.approx(W * math.tan(b + math.radians(phi)), rel=1e-12)
    # nodes of the top edge of the unrotated model (y = 0.6)
    top_nodes = _rotated_top_nodes(ds, beta_deg, 0.6)
    P = ds.reaction.sel(component="x").isel(node=top_nodes).sum("node").values
    assert ds.joint_state.isel(step=-1).values.tolist().count(1) == ds.sizes["joint_point"], "every point slides"
    assert P[-1] == pytest.approx(expected, rel=0.01)
    assert P[-2] == pytest.approx(P[-1], rel=1e-6), "plateau (perfectly plastic sliding)"


def _rotated_top_nodes(ds, beta_deg, y_top):
    a = math.radians(beta_deg)
    y_unrot = -math.sin(a) * ds.x.values + math.cos(a) * ds.y.values
    return np.nonzero(np.isclose(y_unrot, y_top, atol=1e-9))[0]


@pytest.mark.reference
def test_block_on_incline_slides_under_self_weight_only_if_tan_beta_exceeds_mu():
    """Block on an incline: with c = 0 a block slides under its own weight iff tan(beta) > mu."""
    joint = {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": 30.0}
    stages = [{"name": "gravity", "steps": 2, "loads": [{"type": "self_weight"}]}]
    stable = masonrydam.run(block_scene(blocks=[BASE, BLOCK], joint=joint, rotation=25.0, stages=stages))
    # no sliding of the block as a whole: slip stays at the elastic scale (local slip near the
    # ends, where the weight's moment unloads the joint, is allowed)
    W = 2000.0 * G * 2.0 * 0.5
    elastic_scale = W / (1e11 * 2.0)
    assert np.abs(stable.joint_slip.isel(step=-1).values).max() < 2 * elastic_scale
    assert not (stable.joint_state.isel(step=-1).values == 1).all()
    with pytest.raises((masonrydam.ConvergenceError, masonrydam.MechanismError)):
        masonrydam.run(block_scene(blocks=[BASE, BLOCK], joint=joint, rotation=35.0, stages=stages,
                                   solver={"max_step_cuts": 3}))


def test_direct_shear_peak_and_residual_stiffness():
    """Direct shear of a joint under constant normal stress sigma: peak tau = c + sigma tan(phi)
    (Tzamtzis & Asteris eq. 12), then the incremental shear stiffness is the residual one (Tzamtzis & Asteris sec. 3.4)."""
    c, phi, sigma, ks, ksr = 0.2e6, 35.0, 0.5e6, 50e9, 0.5e9
    A = 2.0
    joint = {"normal_stiffness": 100e9, "shear_stiffness": ks, "friction_angle": phi, "cohesion": c,
             "residual_shear_stiffness": ksr}
    stages = [{"name": "compress", "loads": [{"type": "edge_pressure", "set": "top_edge", "pressure": sigma}]},
              {"name": "shear", "steps": 20,
               "loads": [{"type": "displacement", "set": "top", "components": ["x", "y"], "value": [1e-4, 0.0]}]}]
    # very stiff blocks so that the joint governs; no weight. As in a shear box, the top platen is
    # kept from rotating and at its height (no dilatancy, so sigma stays constant while shearing).
    ds = masonrydam.run(block_scene(blocks=[BASE, BLOCK], joint=joint, stages=stages, block_E=1e14, density=0.0))
    tau = top_force(ds, "x", 1.0) / A
    peak = c + sigma * math.tan(math.radians(phi))
    shear_steps = ds.stage.values == 1
    tau_s = tau[shear_steps]
    u_top = ds.displacement.sel(component="x").where(np.isclose(ds.y, 1.0)).mean("node").values[shear_steps]
    sliding = ds.joint_state.values[shear_steps].min(axis=1) == 1
    assert sliding.any() and (~sliding).any()
    # elastic part: tau = ks * u (blocks rigid); sliding part: slope ks_r, line through the peak
    slope = np.diff(tau_s[sliding]) / np.diff(u_top[sliding])
    assert slope == pytest.approx(np.full(len(slope), ksr), rel=1e-3)
    u_yield = peak / ks
    assert tau_s[sliding] == pytest.approx(peak + ksr * (u_top[sliding] - u_yield), rel=2e-3)
    stick = ~sliding
    assert tau_s[stick] == pytest.approx(ks * u_top[stick], rel=2e-3)


def test_tension_opens_joint_with_zero_traction_and_recovers_contact():
    """Tzamtzis & Asteris sec. 3.4: a joint pulled apart carries no traction (both stiffnesses zero); contact is
    restored when the gap closes. Blocks with nu = 0 in plane stress are uniaxial, so the closed
    joint and the two blocks act as springs in series: F = d / (1/(kn A) + (h1 + h2)/(E A))."""
    kn, E, A = 50e9, 30e9, 2.0
    joint = {"normal_stiffness": kn, "shear_stiffness": 20e9, "friction_angle": 30.0, "cohesion": 0.1e6}
    stages = [{"name": "pull", "steps": 2,
               "loads": [{"type": "displacement", "set": "top", "components": ["y"], "value": [1e-3]}]},
              {"name": "push_back", "steps": 3,
               "loads": [{"type": "displacement", "set": "top", "components": ["y"], "value": [-1.5e-3]}]}]
    ds = masonrydam.run(block_scene(blocks=[BASE, BLOCK], joint=joint, stages=stages, block_E=E, density=0.0,
                                    supports=[{"set": "base", "components": ["x", "y"]},
                                              {"set": "top", "components": ["x"]}]))
    Fy = top_force(ds, "y", 1.0)
    pulled = ds.stage.values == 0
    overlap = 0.5e-3
    F = overlap / (1 / (kn * A) + 1.0 / (E * A))
    # zero up to the solver's force tolerance (1e-6 of the step's first residual, here ~ kn A x 0.5 mm)
    assert np.all(np.abs(Fy[pulled]) <= 1e-5 * F), "an open joint transmits nothing"
    assert (ds.joint_state.values[pulled] == 2).all()
    assert (ds.joint_traction_normal.values[pulled] == 0).all() and (ds.joint_traction_shear.values[pulled] == 0).all()
    final = ds.isel(step=-1)
    assert (final.joint_state.values == 0).all(), "contact restored"
    assert -Fy[-1] == pytest.approx(F, rel=1e-6)
    assert final.joint_traction_normal.values == pytest.approx(np.full(final.sizes["joint_point"], -F / A), rel=1e-6)


@pytest.mark.parametrize("angle", [30.0, 45.0, 90.0])
def test_rotation_invariance_of_joint_tractions(angle):
    """The same block-on-joint problem rotated by 0, 30, 45, 90 degrees (geometry and loads
    rotated together) gives the same local joint tractions and states, sticking and sliding."""
    joint = {"normal_stiffness": 80e9, "shear_stiffness": 30e9, "friction_angle": 30.0, "cohesion": 5e3,
             "residual_shear_stiffness": 3e9}

    def run(rot):
        a = math.radians(rot)
        g = (G * math.sin(a) * 3.0 - 0.0, -G * math.cos(a) * 3.0)
        # tangential edge traction on the block's top edge (along the rotated x axis)
        t = 20e3
        trac = [t * math.cos(a), t * math.sin(a)]
        stages = [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                  {"name": "shear", "steps": 4, "loads": [{"type": "edge_traction", "set": "top_edge", "traction": trac}]}]
        return masonrydam.run(block_scene(blocks=[BASE, BLOCK], joint=joint, rotation=rot, gravity=g, stages=stages,
                                          element_size=0.25))

    ref, rot = run(0.0), run(angle)
    for v in ("joint_traction_normal", "joint_traction_shear", "joint_opening", "joint_slip"):
        scale = np.abs(ref[v].values).max()
        np.testing.assert_allclose(rot[v].values, ref[v].values, atol=1e-7 * scale, rtol=1e-7)
    assert (rot.joint_state.values == ref.joint_state.values).all()
    assert set(np.unique(ref.joint_state.values)) >= {0, 1}, "the test exercises stick and slip"


def _notched_joint_tractions(integration):
    """Two blocks joined by a stiff linear vertical joint that stops at a notch (the left block
    leaves a 0.1 m gap at the bottom), the right block pulled at its free end: the normal traction
    has a steep gradient at the notch tip (Schellekens & de Borst 1993,
    notched beam). Returns the joint points' heights and normal tractions, sorted by height."""
    joint = {"law": "linear", "normal_stiffness": 1e15, "shear_stiffness": 1e15, "integration": integration}
    blocks = [{"x0": 0.0, "y0": 0.1, "x1": 1.0, "y1": 0.4, "group": "left"},
              {"x0": 1.0, "y0": 0.0, "x1": 2.0, "y1": 0.4, "group": "right"}]
    stages = [{"name": "pull", "loads": [{"type": "edge_traction", "set": "right_edge", "traction": [1e5, 0.0]}]}]
    ds = masonrydam.run(block_scene(blocks=blocks, joint=joint, stages=stages, element_size=0.025, block_E=30e9,
                                    density=0.0, supports=[{"set": "left", "components": ["x", "y"]}]))
    order = np.argsort(ds.joint_y.values, kind="stable")
    return ds.joint_y.values[order], ds.joint_traction_normal.isel(step=-1).values[order]


def _direction_changes(values):
    d = np.diff(values)
    d = d[np.abs(d) > 1e-9 * np.abs(values).max()]
    return int((np.sign(d[1:]) != np.sign(d[:-1])).sum())


@pytest.mark.reference
def test_gauss_integration_oscillates_lumped_does_not():
    """Schellekens & de Borst (1993): with a stiff interface, Gauss integration couples the nodes and the
    tractions oscillate from point to point near a steep gradient; nodal (lumped) integration gives
    a smooth, monotonic distribution. Both integrate the same resultant."""
    y_l, t_l = _notched_joint_tractions("lumped")
    y_g, t_g = _notched_joint_tractions("gauss")
    near_tip = 0.25  # the 6 elements above the notch tip at y = 0.1
    # lumped: the two points at a node (one from each neighbouring element) are equal; average them
    ys = np.unique(np.round(y_l, 9))
    t_nodes = np.array([t_l[np.isclose(y_l, v)].mean() for v in ys])
    assert _direction_changes(t_nodes[ys < near_tip]) == 0, "lumped tractions decay monotonically from the tip"
    assert _direction_changes(t_g[y_g < near_tip]) >= 2, "Gauss tractions oscillate near the tip"
    # same resultant: sum of traction x tributary length (weights 1/2 per point for line2 rules)
    assert np.sum(t_l) == pytest.approx(np.sum(t_g), rel=2e-2)


def test_linear_scene_uses_one_factorization():
    """A scene whose joints are linear is linear: one factorization for every step, and the
    displacements scale with the load factor."""
    joint = {"law": "linear", "normal_stiffness": 1e11, "shear_stiffness": 4e10}
    stages = [{"name": "load", "steps": 5, "loads": [{"type": "self_weight"},
                                                     {"type": "edge_traction", "set": "top_edge", "traction": [2e4, -1e4]}]}]
    ds = masonrydam.run(block_scene(blocks=[BASE, BLOCK], joint=joint, stages=stages))
    assert ds.attrs["factorizations"] == 1
    u = ds.displacement.values
    lf = ds.load_factor.values
    np.testing.assert_allclose(u / lf[:, None, None], np.broadcast_to(u[-1], u.shape), rtol=1e-9, atol=1e-18)


@pytest.mark.parametrize("bad_corner, what", [((1.0, 1.0), "re-entrant"), ((0.0, 0.0), "collapsed"),
                                              ((-0.5, 1.2), "inverted")])
def test_bad_elements_rejected_before_solving(bad_corner, what):
    """An inverted, collapsed or re-entrant quad is named (group and element) before any solve."""
    from masonrydam.assembly.groups import ContinuumGroup
    from masonrydam.assembly.dofmap import DofMap
    from masonrydam.assembly.model import Model

    # quad corners (0,0) (2,0) (2,2) and a moved fourth corner
    coords = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], list(bad_corner)])
    coords[3] = bad_corner if what != "re-entrant" else (1.0, 1.0)
    conn = np.array([[0, 1, 2, 3]])
    if what == "inverted":
        conn = np.array([[0, 3, 2, 1]])
        coords[3] = (0.0, 2.0)
    g = ContinuumGroup("units", "quad4", conn, DofMap.node_dofs(conn, 2), np.eye(3)[None] * 1e9,
                       np.zeros(1, dtype=np.int64), np.ones(1), np.ones(1))
    with pytest.raises(masonrydam.MeshError, match=r"units.*element\(s\) 0"):
        Model(coords, [g], [])


def test_modified_newton_reaches_the_full_newton_answer():
    """Modified (initial-stiffness) Newton and full Newton converge to the same sliding solution
    (the residual is the same; only the iteration matrix differs), modified Newton with fewer
    factorizations and more iterations; so does Newton on the joint unknowns (joint_space = "auto")."""
    joint = {"normal_stiffness": 1e10, "shear_stiffness": 1e10, "friction_angle": 30.0, "cohesion": 2e3,
             "residual_shear_stiffness": 2e9}
    stages = [{"name": "gravity", "loads": [{"type": "self_weight"}]},
              {"name": "push", "steps": 4,
               "loads": [{"type": "displacement", "set": "top", "components": ["x", "y"], "value": [5e-5, 0.0]}]}]
    runs = {}
    for method, js in (("newton", "off"), ("modified_newton", "off"), ("newton", "auto")):
        sc = block_scene(blocks=[BASE, BLOCK], joint=joint, stages=stages,
                         solver={"method": method, "max_iterations": 300, "force_tolerance": 1e-7,
                                 "joint_space": js})
        runs[method if js == "off" else "joint_space"] = masonrydam.run(sc)
    a, b = runs["newton"], runs["modified_newton"]
    # and the steps solved on the joint unknowns (condensed from the all-stick stiffness) reach it too
    c = runs["joint_space"]
    assert int(c.attrs["joint_space_steps"]) >= 4 and int(c.attrs["newton_iterations"]) == 0
    np.testing.assert_allclose(c.displacement.isel(step=-1).values, a.displacement.isel(step=-1).values,
                               rtol=1e-6, atol=1e-6 * np.abs(a.displacement.values).max())
    assert top_force(c, "x", 1.0)[-1] == pytest.approx(top_force(a, "x", 1.0)[-1], rel=1e-6)
    assert (b.joint_state.isel(step=-1).values == 1).all()
    np.testing.assert_allclose(b.displacement.isel(step=-1).values, a.displacement.isel(step=-1).values,
                               rtol=1e-6, atol=1e-6 * np.abs(a.displacement.values).max())
    assert top_force(b, "x", 1.0)[-1] == pytest.approx(top_force(a, "x", 1.0)[-1], rel=1e-6)
    assert b.attrs["factorizations"] < a.attrs["factorizations"]
    assert b.attrs["newton_iterations"] > a.attrs["newton_iterations"]
