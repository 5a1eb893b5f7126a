"""Water on a dam (masonrydam.effects.reservoir, .uplift; masonrydam.results.assess) against the gravity
method worked by hand.

Sources: the gravity method of USBR, Design of Small Dams (1987), sec. 5.7-5.11, and USACE EM
1110-2-2200, Gravity Dam Design (1995), ch. 3-4: the water thrust 0.5 gamma_w h^2 at h/3, the uplift
linear from headwater to tailwater (or through the drain line, head there = tail + (1 - E)(head -
tail)), the normal force W - U, the shear-friction factor N tan(phi) / T (c = 0), the resultant
position from the moments; the cracked base of EM 1110-2-2200 sec. 4-4 (full head in the crack,
linear from the crack tip to the toe, crack grown until the uncracked part is all in compression:
compressed length = 3 x the resultant's distance from the toe), iterated to its fixed point.

Section used throughout (2D, plane strain, thickness 1 m): vertical upstream face, crest width cw,
downstream face of slope m (horizontal : vertical) from the crest to the toe, height H, base B = cw
+ m H, on a rock block with a Mohr-Coulomb base joint (c = 0, no tension); concrete 2400 kg/m3.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import SceneError
from repository_paths import EXAMPLES
from scenes import DAM_CONCRETE_DENSITY, dam_with_reservoir

pytest.importorskip("gmsh")

G = 9.80665
GW = 1000.0 * G  # unit weight of water, N/m3
RHO_C = DAM_CONCRETE_DENSITY


def section(H, cw, m):
    """Weight (N per m) and its lever arm from the heel (m) of the section, and its base B (m)."""
    B = cw + m * H
    a1, x1 = cw * H, cw / 2.0
    a2, x2 = 0.5 * (B - cw) * H, (2.0 * cw + B) / 3.0
    return RHO_C * G * (a1 + a2), (a1 * x1 + a2 * x2) / (a1 + a2), B


def profile_forces(B, heads_at):
    """Resultant (N/m) and its lever arm from the heel of a piecewise-linear uplift through the points
    ``heads_at`` [(s, pressure), ...] from s = 0 to B (trapezoids)."""
    U = M = 0.0
    for (s0, p0), (s1, p1) in zip(heads_at, heads_at[1:]):
        L = s1 - s0
        U += 0.5 * (p0 + p1) * L
        M += L * L * (p0 / 6.0 + p1 / 3.0) + s0 * 0.5 * (p0 + p1) * L  # first moment about the heel
    return U, M / U


def last(ds, name):
    return float(ds[name].isel(step=-1, section=0))


def test_gravity_method_linear_uplift():
    """Normal force W - U and shear force = water thrust to 0.1 %, sliding factor and resultant position
    to 0.5 % (measured: 1e-13 and 1e-12; the consistent pore forces make the uplift moment exact)."""
    H, cw, m, h, phi = 30.0, 5.0, 0.8, 28.0, 45.0
    ds = masonrydam.run(dam_with_reservoir(height=H, crest_width=cw, downstream_slope=m, level=h, friction_angle=phi))
    W, xW, B = section(H, cw, m)
    P = 0.5 * GW * h * h
    U, xU = profile_forces(B, [(0.0, GW * h), (B, 0.0)])
    N = W - U
    e = (W * xW - U * xU + P * h / 3.0) / N  # moments about the heel
    assert last(ds, "normal_force") == pytest.approx(N, rel=1e-3)
    assert last(ds, "shear_force") == pytest.approx(P, rel=1e-3)
    assert last(ds, "uplift_force") == pytest.approx(U, rel=1e-3)
    assert last(ds, "sliding_safety_factor") == pytest.approx(N * math.tan(math.radians(phi)) / P, rel=5e-3)
    assert last(ds, "resultant_position") == pytest.approx(e, rel=5e-3)
    assert float(ds.section_length[0]) == pytest.approx(B)
    # the water rose from the heel (empty reservoir) to the level over the stage's 4 increments
    np.testing.assert_allclose(ds.reservoir_level.values, [0.0, 7.0, 14.0, 21.0, 28.0])
    # the pore pressure at the heel point is the full head, at the toe zero
    p = ds.joint_pore_pressure.isel(step=-1).values
    x = ds.joint_x.values
    assert p[np.argmin(x)] == pytest.approx(GW * h, rel=1e-12)
    assert p[np.argmax(x)] == pytest.approx(0.0, abs=1e-6)


def test_gravity_method_drains_and_tailwater():
    """Drain line 5 m from the heel at efficiency 0.67 (head there = tail + 0.33 (head - tail), USBR
    1987 sec. 5.7), tailwater 4 m on the inclined downstream face (its horizontal thrust and the weight
    of the water wedge above the face): N, T to 0.1 %, factor and resultant position to 0.5 %."""
    H, cw, m, h, ht, phi = 30.0, 5.0, 0.8, 28.0, 4.0, 45.0
    extra = {"tailwater": {"level": ht}, "uplift": {"joints": ["base_joint"],
                                                     "drains": {"distance": 5.0, "efficiency": 0.67}}}
    ds = masonrydam.run(dam_with_reservoir(height=H, crest_width=cw, downstream_slope=m, level=h, friction_angle=phi,
                                           overrides={"reservoir": extra}))
    W, xW, B = section(H, cw, m)
    P, Pt = 0.5 * GW * h * h, 0.5 * GW * ht * ht
    wedge = 0.5 * (m * ht) * ht  # water above the downstream face below the tail level (m2)
    Vt, xVt = GW * wedge, B - m * ht / 3.0
    h_drain = ht + (1.0 - 0.67) * (h - ht)
    U, xU = profile_forces(B, [(0.0, GW * h), (5.0, GW * h_drain), (B, GW * ht)])
    N = W + Vt - U
    T = P - Pt
    e = (W * xW + Vt * xVt - U * xU + P * h / 3.0 - Pt * ht / 3.0) / N
    assert last(ds, "normal_force") == pytest.approx(N, rel=1e-3)
    assert last(ds, "shear_force") == pytest.approx(T, rel=1e-3)
    assert last(ds, "sliding_safety_factor") == pytest.approx(N * math.tan(math.radians(phi)) / T, rel=5e-3)
    assert last(ds, "resultant_position") == pytest.approx(e, rel=5e-3)
    assert float(ds.tailwater_level.isel(step=-1)) == pytest.approx(ht)


def classic_cracked_base(H, cw, m, h):
    """Crack length (m) of the cracked-base iteration (EM 1110-2-2200 sec. 4-4), and N, e."""
    W, xW, B = section(H, cw, m)
    P = 0.5 * GW * h * h
    Lc = 0.0
    for _ in range(500):
        U, xU = profile_forces(B, [(0.0, GW * h)] + ([(Lc, GW * h)] if Lc > 0 else []) + [(B, 0.0)])
        N = W - U
        e = (W * xW - U * xU + P * h / 3.0) / N
        new = B - 3.0 * (B - e) if e > 2.0 * B / 3.0 else 0.0
        if abs(new - Lc) < 1e-12:
            break
        Lc = new
    return Lc, N, e


@pytest.mark.slow
def test_cracked_base_against_the_classic_iteration():
    """A slender section (crest 5 m, slope 0.5, water at the crest) whose base cracks: with full head in
    the crack (cracked = "full_head", the crack grown at every iteration) the cracked length is that of
    the classic iteration to 2 % (8.00 m of a 20 m base; measured 7.9 m, the node spacing of 0.2 m
    sets the resolution). The dam and rock are made rigid against the joint (E = 1e13 Pa, kn = 1e9
    Pa/m), so that the effective stress over the uncracked part is linear, as the method assumes."""
    H, cw, m, h = 30.0, 5.0, 0.5, 30.0
    Lc, N, e = classic_cracked_base(H, cw, m, h)
    assert Lc == pytest.approx(8.0, rel=1e-6)  # the fixed point of this section
    scene = dam_with_reservoir(height=H, crest_width=cw, downstream_slope=m, level=h, element_size=0.2,
                               friction_angle=55.0, youngs_modulus=1e13, joint_stiffness=1e9)
    scene["stages"][1]["steps"] = 10
    ds = masonrydam.run(scene)
    B = float(ds.section_length[0])
    assert last(ds, "cracked_length_ratio") * B == pytest.approx(Lc, rel=0.02)
    assert last(ds, "normal_force") == pytest.approx(N, rel=0.02)
    assert last(ds, "resultant_position") == pytest.approx(e, rel=0.02)
    # the crack carries the full head: every open point of the base has the heel's pore pressure
    state = ds.joint_state.isel(step=-1).values
    p = ds.joint_pore_pressure.isel(step=-1).values
    assert (state == 2).sum() > 10
    np.testing.assert_allclose(p[state == 2], GW * h, rtol=1e-12)


def test_flood_until_the_base_slides():
    """A flood stage raises the water from 20 m until the base slides (until_failure): with c = 0,
    phi = 25 deg and the intact uplift profile (cracked = "unchanged"), (W - gamma_w h B / 2) tan(phi)
    = gamma_w h^2 / 2 gives h = 27.70 m; the run ends at that level to 0.5 %, with the sliding
    factor of the last converged step at 1 within 1 %, and says so."""
    H, cw, m, phi = 30.0, 5.0, 0.8, 25.0
    W, _, B = section(H, cw, m)
    t = math.tan(math.radians(phi))
    # 0.5 gw h^2 + 0.5 gw B t h - W t = 0
    a, b, c = 0.5 * GW, 0.5 * GW * B * t, -W * t
    h_slide = (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)
    assert 27.0 < h_slide < 28.0
    stages = [{"name": "gravity", "loads": [{"type": "self_weight"}]},
              {"name": "fill", "steps": 2, "loads": [{"type": "reservoir"}]},
              {"name": "flood", "steps": 15, "until_failure": True, "loads": [{"type": "reservoir", "level": 35.0}]}]
    scene = dam_with_reservoir(height=H, crest_width=cw, downstream_slope=m, friction_angle=phi, level=20.0,
                               stages=stages, overrides={"reservoir.uplift": {"joints": ["base_joint"], "cracked": "unchanged"}})
    ds = masonrydam.run(scene)
    assert ds.attrs["limit_reservoir_level"] == pytest.approx(h_slide, rel=5e-3)
    assert "sliding" in ds.attrs["limit_state"] and "reservoir level reached" in ds.attrs["limit_state"]
    assert float(ds.reservoir_level.isel(step=-1)) == pytest.approx(ds.attrs["limit_reservoir_level"])
    assert last(ds, "sliding_safety_factor") == pytest.approx(1.0, rel=0.01)
    assert ds.attrs["limit_kind"] == "sliding"


def test_no_reservoir_pays_nothing():
    """A dam scene without [reservoir] has no water variables, sections or pore pressures, and its
    effects list names no water."""
    scene = dam_with_reservoir()
    del scene["reservoir"]
    scene["stages"] = scene["stages"][:1]
    ds = masonrydam.run(scene)
    for name in ("reservoir_level", "joint_pore_pressure", "sliding_safety_factor"):
        assert name not in ds
    assert "section" not in ds.dims
    eff = ds.attrs["simulated_effects"]
    assert "reservoir" not in eff and "uplift" not in eff
    ds = masonrydam.run(dam_with_reservoir())
    assert "reservoir: hydrostatic pressure" in ds.attrs["simulated_effects"]
    assert "uplift: pore pressure in joint sets base_joint" in ds.attrs["simulated_effects"]


@pytest.mark.parametrize("change, key", [
    (lambda s: s["reservoir"].update(level=-5.0), "reservoir.level"),
    (lambda s: s["reservoir"].update(face="upstream_wall"), "reservoir.face"),
    (lambda s: s["reservoir"].update(uplift={"joints": ["lift_joints"]}), "reservoir.uplift.joints"),
    (lambda s: s["reservoir"].update(uplift={"joints": ["base_joint"],
                                             "drains": {"distance": 5.0, "efficiency": 1.2}}),
     "reservoir.uplift.drains.efficiency"),
    (lambda s: s["reservoir"].update(density=-1000.0), "reservoir.density"),
    (lambda s: s["reservoir"].update(tailwater={"level": -1.0}), "reservoir.tailwater.level"),
    (lambda s: s["reservoir"].update(silt={"level": 40.0, "submerged_density": 1100.0}), "reservoir.silt.level"),
    (lambda s: s["reservoir"].update(uplift={"joints": ["base_joint"], "cracked": "full"}), "reservoir.uplift.cracked"),
    (lambda s: s["stages"][1].update(loads=[{"type": "self_weight"}]), "reservoir"),
    (lambda s: s.pop("reservoir"), "stages[1].loads[0].type"),
])
def test_bad_water_input_names_the_key(change, key):
    scene = dam_with_reservoir()
    change(scene)
    with pytest.raises(SceneError) as err:
        masonrydam.run(scene)
    assert err.value.key == key, str(err.value)


def test_joint_lines_of_a_lifted_section_and_a_3d_dam():
    """The sections are named by joint set and counted from the bottom (2D lifts); in 3D each monolith's
    base and lift are lines of their own (contraction joints are not assessed)."""
    from masonrydam.assembly.joint_lines import JointLines
    from masonrydam.scene import Scene
    from masonrydam.scene import build_mesh, build_model

    s = dam_with_reservoir(element_size=2.0)
    s["mesh"]["parameters"]["lift_spacing"] = 10.0
    s["joints"]["lift_joints"] = dict(s["joints"]["base_joint"])
    sc = Scene(s)
    model = build_model(sc.normalized, build_mesh(sc.normalized, "."))
    lines = JointLines(model, [g for g in model.igroups if g.name == "lift_joints"], [1.0, 0.0], 1)
    assert lines.names == ["lift_joints/1", "lift_joints/2"]
    z = [lines.elevation[lines.line == k].mean() for k in range(2)]
    np.testing.assert_allclose(z, [10.0, 20.0])
    # lift 1 at y = 10: the section is cw + m (H - 10) wide
    assert lines.length[0] == pytest.approx(5.0 + 0.8 * 20.0)


def test_gravity_method_3d_monolith():
    """One 3D monolith (a prism 10 m wide: valley bottom = top width) of the 2D section on a rock block:
    the base line's N = (W - U) b and T = P b to 0.1 %, factor and resultant position to 0.5 %, with
    the drain profile (the drain line crosses hex faces, which the uplift integration splits)."""
    H, cw, m, h, phi, b = 30.0, 5.0, 0.8, 28.0, 45.0, 10.0
    scene = dam_with_reservoir(height=H, crest_width=cw, downstream_slope=m, level=h, friction_angle=phi,
                               element_size=3.0, overrides={"reservoir.uplift": {
                                   "joints": ["base_joint"], "drains": {"distance": 5.0, "efficiency": 0.67}}})
    scene["model"] = {"name": "dam3d", "dimension": 3}
    scene["mesh"]["generator"] = "gravity_dam_3d"
    scene["mesh"]["parameters"].update(valley_bottom_width=b, valley_top_width=b, n_monoliths=1)
    ds = masonrydam.run(scene)
    W, xW, B = section(H, cw, m)
    P = 0.5 * GW * h * h
    h_drain = (1.0 - 0.67) * h
    U, xU = profile_forces(B, [(0.0, GW * h), (5.0, GW * h_drain), (B, 0.0)])
    N = W - U
    e = (W * xW - U * xU + P * h / 3.0) / N
    assert list(ds.section.values) == ["base_joint"]
    assert last(ds, "normal_force") == pytest.approx(N * b, rel=1e-3)
    assert last(ds, "shear_force") == pytest.approx(P * b, rel=1e-3)
    assert last(ds, "uplift_force") == pytest.approx(U * b, rel=1e-3)
    assert last(ds, "sliding_safety_factor") == pytest.approx(N * math.tan(math.radians(phi)) / P, rel=5e-3)
    assert last(ds, "resultant_position") == pytest.approx(e, rel=5e-3)


def test_continuum_stress_output_satisfies_the_virial_identity():
    """``[output] stress = "element"`` writes the continuum stress per element. Check: for a body in
    equilibrium, int sigma_yy dV = int t_y y dS + int b_y y dV (the virial theorem, e.g. Gurtin, An
    Introduction to Continuum Mechanics, 1981, sec. 14), which the finite element solution satisfies
    exactly because v = (0, y) is in its space. A block of 2 x 1 m on a base joint at y = 0.5 under its
    weight (rectangular elements: the element mean is the Gauss-weighted mean): int sigma_yy dA =
    -rho g B int (y - 0.5) dy over the block = -rho g B H^2 / 2 about the joint's elevation."""
    rho, B, H = 2000.0, 2.0, 0.5
    scene = {
        "model": {"name": "blocks"},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.125, "blocks": [
            {"x0": 0.0, "y0": 0.0, "x1": B, "y1": 0.5, "group": "base"},
            {"x0": 0.0, "y0": 0.5, "x1": B, "y1": 0.5 + H, "group": "block"}]}},
        "materials": {"base": {"youngs_modulus": 20e9, "poisson_ratio": 0.2, "density": 0.0},
                      "block": {"youngs_modulus": 20e9, "poisson_ratio": 0.2, "density": rho}},
        "joints": {"joints": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": 40.0}},
        "supports": [{"set": "base"}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]}],
        "output": {"stress": "element"},
    }
    ds = masonrydam.run(scene)
    names = __import__("json").loads(ds.element_group.attrs["group_names"])
    block = ds.element_group.values == names.index("block")
    area = 0.125 ** 2
    syy = ds.stress.sel(stress_component="yy").isel(step=-1).values[block]
    assert syy.sum() * area == pytest.approx(-rho * G * B * H * H / 2.0, rel=1e-9)
    assert ds.stress.attrs["units"] == "Pa"
    # the scene that does not ask for stresses has none
    del scene["output"]
    assert "stress" not in masonrydam.run(scene)


def _example(name):
    import tomllib
    from pathlib import Path

    return tomllib.loads((EXAMPLES / name).read_text())


@pytest.mark.slow
@pytest.mark.reference
def test_koyna_reservoir_example_on_a_coarse_mesh():
    """examples/koyna_reservoir.toml at element size 2.9 m: at the 1967 level (91.75 m) every joint line
    is closed and meets the usual sliding criterion (no cohesion on the lifts); the flood stage ends
    where the section finds no equilibrium, above the 1967 level, with the level and the joint lines
    that gave way in the message (the example's own mesh: 103.25 m, docs/water.md)."""
    sc = _example("koyna_reservoir.toml")
    sc["mesh"]["parameters"]["element_size"] = 2.9
    ds = masonrydam.run(sc)
    full = ds.where(ds.reservoir_level == 91.75, drop=True).isel(step=-1)
    assert float(full.cracked_length_ratio.max()) == 0.0
    assert float(full.sliding_safety_factor.min()) > 1.5
    assert len(ds.section) == 11 and str(ds.section.values[1]) == "lift_joints/1"
    level = ds.attrs["limit_reservoir_level"]
    assert 95.0 < level < 131.75
    assert f"reservoir level reached {level:.6g} m" in ds.attrs["limit_state"]
    assert "joint line 'lift_joints/" in ds.attrs["limit_state"]
    # a failure of the section (its crack runs, it slides or overturns), not a stalled iteration
    assert ds.attrs["limit_kind"] in ("crack", "sliding", "overturning"), ds.attrs["limit_state"]


def test_dam_3d_reservoir_example_is_valid():
    """examples/dam_3d_reservoir.toml validates (the run itself is benchmarks/bench_dam_3d_water.py)."""
    from masonrydam.scene import Scene

    s = Scene(_example("dam_3d_reservoir.toml")).normalized
    assert s["reservoir"]["uplift"]["joints"] == ["base_joint", "lift_joints"]
    assert s["mesh"]["parameters"]["n_monoliths"] == 20


def test_static_water_stays_applied_in_a_dynamic_stage():
    """The dynamic stages keep the static water and pore forces: with a ground motion of zero the dam
    stays where the reservoir stage left it (a missing water force would set it swinging by the
    thrust over the stiffness, about the static displacement itself), and the pore pressures and the
    level are carried into the dynamic steps unchanged."""
    scene = dam_with_reservoir(element_size=3.0)
    scene["stages"].append({"name": "still", "type": "dynamic", "dt": 0.01, "steps": 20,
                            "ground_motion": {"x": {"values": [0.0, 0.0], "dt": 0.01}}})
    ds = masonrydam.run(scene)
    static = ds.where(ds.stage == 1, drop=True).isel(step=-1)
    dyn = ds.where(ds.stage == 2, drop=True)
    u0 = static.displacement.values
    drift = np.abs(dyn.displacement.values - u0[None]).max()
    assert np.abs(u0).max() > 1e-4
    assert drift < 1e-6 * np.abs(u0).max()
    np.testing.assert_allclose(dyn.joint_pore_pressure.values, static.joint_pore_pressure.values[None].repeat(
        dyn.sizes["step"], axis=0), rtol=0, atol=0)
    assert (dyn.reservoir_level.values == 28.0).all()
    np.testing.assert_allclose(dyn.sliding_safety_factor.values[-1], static.sliding_safety_factor.values, rtol=1e-6)


@pytest.mark.slow
def test_each_monolith_base_is_a_section_of_its_own():
    """Two monoliths side by side on one rock block: their base joints share rock nodes but not dam
    nodes, so each is a line of its own (counted along the dam axis), each carrying half the prism's
    W - U (no uplift here: N = W b per monolith, b = 10 m)."""
    H, cw, m = 30.0, 5.0, 0.8
    scene = dam_with_reservoir(height=H, crest_width=cw, downstream_slope=m, element_size=3.0)
    del scene["reservoir"]["uplift"]
    scene["model"] = {"name": "dam3d", "dimension": 3}
    scene["mesh"]["generator"] = "gravity_dam_3d"
    scene["mesh"]["parameters"].update(valley_bottom_width=20.0, valley_top_width=20.0, n_monoliths=2)
    scene["joints"]["contraction_joints"] = dict(scene["joints"]["base_joint"])
    ds = masonrydam.run(scene)
    W, _, _ = section(H, cw, m)
    assert list(ds.section.values) == ["base_joint/1", "base_joint/2"]
    np.testing.assert_allclose(ds.section_x.values, [5.0, 15.0])
    np.testing.assert_allclose(ds.normal_force.isel(step=-1).values, W * 10.0, rtol=1e-3)


@pytest.mark.parametrize("control", ["arc_length", "dissipation"])
def test_path_following_is_refused_where_it_would_drop_the_water(control):
    """Path following ramps one load factor (masonrydam/solvers/static/arc_length.py) and does not carry the
    reservoir's loads, which follow the level and the cracks: a stage with water under it is refused by name,
    the stage that raises the water and a later one alike, rather than run without its water."""
    for index, stages in ((1, [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                               {"name": "water", "steps": 4, "control": control, "loads": [{"type": "reservoir"}]}]),
                          (2, [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                               {"name": "water", "steps": 4, "loads": [{"type": "reservoir"}]},
                               {"name": "push", "control": control, "loads": [
                                   {"type": "self_weight", "acceleration": [0.5, 0.0], "factor": 1.0}]}])):
        with pytest.raises(SceneError) as err:
            masonrydam.run(dam_with_reservoir(stages=stages))
        assert err.value.key == f"stages[{index}].control" and "water" in str(err.value)
