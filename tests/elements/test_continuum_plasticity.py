"""Elasto-plastic blocks (``[materials.<group>] law = "von_mises" | "drucker_prager"``):
the element integration of the point laws (masonrydam/elements/continuum_plastic.py; the laws are
tested in tests/test_von_mises.py and tests/test_drucker_prager.py) in static stages.

Closed forms (perfect plasticity, homogeneous stress, so the finite-element answer is exact):
- a block pressed vertically with free lateral expansion: 3D, the uniaxial yield stress sigma_y
  (von Mises) and, for Drucker-Prager matched to the outer Mohr-Coulomb cone, the Mohr-Coulomb uniaxial
  compressive strength 2 c cos(phi) / (1 - sin(phi)) (de Souza Neto, Peric & Owen 2008, sec. 8.3);
  plane strain, von Mises: the out-of-plane stress tends to half the axial one (plastic
  incompressibility), so the axial stress tends to 2 sigma_y / sqrt(3) (Hill, The Mathematical Theory of
  Plasticity, 1950, ch. VI);
- the elastic start: E / (1 - nu^2) in plane strain, E in 3D.
Element checks (the project's standard): zero force under a rigid translation, and the tangent equal
to a finite difference of the internal force in the plastic range.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import SceneError

E, NU, SY = 2e11, 0.3, 2.5e8


def pressed_block(dim, material, steps=20, strain=0.01):
    if dim == 2:
        mesh = {"generator": "blocks_2d", "parameters": {"element_size": 0.5, "blocks": [
            {"x0": 0, "y0": 0, "x1": 1, "y1": 1, "group": "solid"}]}}
        model = {"name": "pressed", "hypothesis": "plane_strain", "thickness": 1.0, "gravity": [0.0, 0.0]}
        supports = [{"set": "base", "components": ["y"]}, {"set": "left", "components": ["x"]}]
        load = {"type": "displacement", "set": "top", "components": ["y"], "value": [-strain]}
    else:
        mesh = {"generator": "blocks_3d", "parameters": {"element_size": 0.5, "blocks": [
            {"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 1, "group": "solid"}]}}
        model = {"name": "pressed", "dimension": 3, "gravity": [0.0, 0.0, 0.0]}
        supports = [{"set": "base", "components": ["z"]}, {"set": "left", "components": ["x"]},
                    {"set": "front", "components": ["y"]}]
        load = {"type": "displacement", "set": "top", "components": ["z"], "value": [-strain]}
    return {"model": model, "mesh": mesh,
            "materials": {"solid": dict({"youngs_modulus": E, "poisson_ratio": NU, "density": 0.0}, **material)},
            "supports": supports, "stages": [{"name": "press", "steps": steps, "loads": [load]}]}


def axial_stress(ds, dim):
    comp = "y" if dim == 2 else "z"
    coord = ds.y.values if dim == 2 else ds.z.values
    top = coord > coord.max() - 1e-9
    return -ds.reaction.sel(component=comp).values[:, top].sum(axis=1)  # area 1 m2 (1 m thick in 2D)


def test_plane_strain_von_mises_tends_to_two_over_root_three():
    ds = masonrydam.run(pressed_block(2, {"law": "von_mises", "yield_stress": SY}))
    s = axial_stress(ds, 2)
    assert s[0] == pytest.approx(E / (1 - NU**2) * 0.01 / 20, rel=1e-9)  # elastic first step
    assert s[-1] == pytest.approx(2 * SY / math.sqrt(3), rel=1e-6)
    assert np.all(np.diff(s) > 0)  # hardening towards the limit, never above it
    assert s.max() <= 2 * SY / math.sqrt(3) * (1 + 1e-9)


def test_3d_von_mises_yields_at_sigma_y():
    ds = masonrydam.run(pressed_block(3, {"law": "von_mises", "yield_stress": SY}, steps=10))
    s = axial_stress(ds, 3)
    assert s[0] == pytest.approx(E * 0.001, rel=1e-9)
    assert s[-1] == pytest.approx(SY, rel=1e-9)


def test_3d_drucker_prager_outer_cone_gives_the_mohr_coulomb_strength():
    c, phi = 5e6, 30.0
    ds = masonrydam.run(pressed_block(3, {"law": "drucker_prager", "cohesion": c, "friction_angle": phi,
                                          "match": "outer"}, steps=10, strain=0.002))
    s = axial_stress(ds, 3)
    p = math.radians(phi)
    assert s[-1] == pytest.approx(2 * c * math.cos(p) / (1 - math.sin(p)), rel=1e-6)


def test_plane_strain_mohr_coulomb_and_tresca_strengths():
    """Plane strain, lateral face free: the out-of-plane stress stays the intermediate principal stress, so
    the main-plane return of Mohr-Coulomb gives the uniaxial strength 2 c cos(phi) / (1 - sin(phi)) and
    Tresca sigma_y (de Souza Neto et al. 2008, sec. 8.1; Chen & Han, Plasticity for Structural Engineers,
    1988, ch. 2). (A 3D cube pressed with free lateral faces sits on the edge sigma_1 = sigma_2 of both
    laws, where associated flow leaves the lateral split undetermined: its tangent is singular.)"""
    c, phi = 5e6, 30.0
    ds = masonrydam.run(pressed_block(2, {"law": "mohr_coulomb", "cohesion": c, "friction_angle": phi},
                                      steps=10, strain=0.002))
    p = math.radians(phi)
    assert axial_stress(ds, 2)[-1] == pytest.approx(2 * c * math.cos(p) / (1 - math.sin(p)), rel=1e-6)
    assert "Mohr-Coulomb" in ds.attrs["simulated_effects"]
    ds = masonrydam.run(pressed_block(2, {"law": "tresca", "yield_stress": SY}, steps=10))
    assert axial_stress(ds, 2)[-1] == pytest.approx(SY, rel=1e-9)


def test_element_rigid_translation_and_consistent_tangent():
    from masonrydam.scene import Scene
    from masonrydam.scene import build_mesh, build_model

    sc = Scene(pressed_block(2, {"law": "von_mises", "yield_stress": SY, "isotropic_hardening": 1e10}))
    model = build_model(sc.normalized, build_mesh(sc.normalized, sc.base_dir))
    g = model.cgroups[0]
    u = np.zeros(model.n_dof)
    u[0::2], u[1::2] = 0.3, -0.2  # a rigid translation: no strain, no force
    g.evaluate(model.coords, u, True)
    assert np.abs(g.fe).max() < 1e-15 * E  # round-off of u = 0.3 m: strains of 1e-17
    rng = np.random.default_rng(3)
    x, y = model.coords[:, 0], model.coords[:, 1]
    u = np.zeros(model.n_dof)
    u[0::2] = 0.004 * x + 1e-4 * rng.standard_normal(len(x))  # well past yield (eps_y = 1.25e-3)
    u[1::2] = -0.006 * y + 1e-4 * rng.standard_normal(len(x))
    g.evaluate(model.coords, u, True)
    K = g.ke.copy()
    dofs = g.dofs[0]
    h = 1e-9
    for j in range(len(dofs)):
        up, um = u.copy(), u.copy()
        up[dofs[j]] += h
        um[dofs[j]] -= h
        g.evaluate(model.coords, up, False)
        fp = g.fe[0].copy()
        g.evaluate(model.coords, um, False)
        fm = g.fe[0].copy()
        np.testing.assert_allclose(K[0][:, j], (fp - fm) / (2 * h), rtol=1e-5, atol=1e-6 * np.abs(K[0]).max())


def test_bad_plastic_materials():
    s = pressed_block(2, {"law": "von_mises"})
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.solid.yield_stress"
    s = pressed_block(2, {"law": "von_mises", "yield_stress": SY, "isotropic_hardening": -1e9})
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.solid.isotropic_hardening" and "regularisation" in str(err.value)
    s = pressed_block(2, {"law": "von_mises", "yield_stress": SY, "viscosity": -1.0})
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.solid.viscosity"
    s = pressed_block(2, {"law": "von_mises", "yield_stress": SY})
    s["model"]["hypothesis"] = "plane_stress"
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.solid.law"
    s = pressed_block(2, {"law": "plasticity"})
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.solid.law"
    s = pressed_block(2, {"law": "von_mises", "yield_stress": SY, "cohesion": 1e6})
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "materials.solid.cohesion"


def test_plastic_block_sliding_on_a_joint():
    """A (von Mises, still elastic) block on a cohesionless joint, pushed sideways at its top: the push
    levels off at the friction force tan(phi) W (Coulomb). The model mixes a plastic group with joints,
    so the static solver takes the general Newton path (no joint-space condensation)."""
    phi, rho, g = 30.0, 2400.0, 9.80665
    s = {"model": {"name": "pushed", "thickness": 1.0, "hypothesis": "plane_strain"},
         "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
             {"x0": 0.0, "y0": -0.25, "x1": 1.0, "y1": 0.0, "group": "base"},
             {"x0": 0.0, "y0": 0.0, "x1": 1.0, "y1": 0.5, "group": "block"}]}},
         "materials": {"base": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": rho},
                       "block": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "density": rho, "law": "von_mises",
                                 "yield_stress": 3e7}},
         "joints": {"joints": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": phi}},
         "supports": [{"set": "base"}],
         "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                    {"name": "push", "steps": 10, "loads": [{"type": "displacement", "set": "top", "components": ["x"],
                                                              "value": [2e-4]}]}]}
    ds = masonrydam.run(s)
    top = ds.y.values > 0.49
    push = ds.reaction.sel(component="x").values[:, top].sum(axis=1)
    W = rho * g * 1.0 * 0.5
    assert push[-1] == pytest.approx(math.tan(math.radians(phi)) * W, rel=1e-6)
    assert ds.attrs.get("joint_space_size", 0) in (0, "0")


def _punch_mesh(path, h_fine=0.02, h_coarse=0.3, L=3.0, D=2.0, b=0.5):
    """Half of a plane-strain soil block under a smooth punch of half-width b (gmsh, quad8, refined at the
    punch), physical groups punch, sym, bottom, far and the surface soil."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("punch")
        o = gmsh.model.occ
        p = [o.addPoint(0, 0, 0, h_fine), o.addPoint(b, 0, 0, h_fine), o.addPoint(L, 0, 0, h_coarse),
             o.addPoint(L, -D, 0, h_coarse), o.addPoint(0, -D, 0, h_coarse)]
        lines = [o.addLine(p[i], p[(i + 1) % 5]) for i in range(5)]
        s = o.addPlaneSurface([o.addCurveLoop([-line for line in reversed(lines)])])
        o.synchronize()
        for name, line in (("punch", lines[0]), ("far", lines[2]), ("bottom", lines[3]), ("sym", lines[4])):
            gmsh.model.addPhysicalGroup(1, [line], name=name)
        gmsh.model.addPhysicalGroup(2, [s], name="soil")
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.Algorithm", 8)
        gmsh.option.setNumber("Mesh.ElementOrder", 2)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("law,integration", [("von_mises", "full"), ("tresca", "reduced")])
@pytest.mark.slow
@pytest.mark.reference
def test_prandtl_punch(tmp_path, law, integration):
    """A smooth rigid strip footing on a von Mises or Tresca half-space (plane strain): the limit pressure
    is (2 + pi) k, k the shear strength, sigma_y / sqrt(3) for von Mises and sigma_y / 2 for Tresca
    (Prandtl 1920; Hill 1950, ch. VIII). With quad8 elements of 0.02 B at the punch edge (B the footing
    width) the pressure levels off within 3 % of it (von Mises, full 3 x 3 rule: 1.7 % above; 4.2 % with
    0.05 B); quad4 elements lock (plastic incompressibility) and overshoot by 37 % and more, still rising."""
    _punch_mesh(tmp_path / "punch.msh")
    sy = 1e6
    k = sy / math.sqrt(3) if law == "von_mises" else sy / 2
    s = {"model": {"name": "punch", "hypothesis": "plane_strain", "thickness": 1.0, "gravity": [0.0, 0.0]},
         "mesh": {"file": str(tmp_path / "punch.msh")},
         "materials": {"soil": {"youngs_modulus": 1e9, "poisson_ratio": 0.3, "density": 0.0, "law": law,
                                "yield_stress": sy, "integration": integration}},
         "supports": [{"set": "sym", "components": ["x"]}, {"set": "bottom"}, {"set": "far", "components": ["x"]}],
         "solver": {"max_iterations": 60},
         "stages": [{"name": "press", "steps": 40, "loads": [{"type": "displacement", "set": "punch",
                                                              "components": ["y"], "value": [-0.02]}]}]}
    ds = masonrydam.run(s)
    x, y = ds.x.values, ds.y.values
    under = (np.abs(y) < 1e-9) & (x < 0.5 + 1e-9)
    q = -ds.reaction.sel(component="y").values[:, under].sum(axis=1) / 0.5
    assert q[-1] / k == pytest.approx(2 + math.pi, rel=0.03)
    assert q[-1] / q[-10] - 1 < 0.002  # a plateau, not a locked, still rising curve


@pytest.mark.slow
def test_plastic_block_under_an_impact_dynamic():
    """Dynamic stage with an elasto-plastic block: a von Mises cube (massless, uniaxial stress, E A / L =
    k, yield force F_y = sigma_y A) stopping a mass M launched at v0. Energy: M v0^2 / 2 = F_y u_y / 2 +
    F_y (u_max - u_y), so u_max = 3 u_y for the v0 chosen; the mass then vibrates elastically about the
    permanent set u_max - u_y = 2 u_y (elastic-perfectly plastic oscillator, Chopra, Dynamics of
    Structures, 4th ed. 2012, sec. 7.3). The energy balance closes with the blocks' work (stored and
    plastic together, trapezoidal)."""
    rho, t_top = 1.0e4, 0.25  # the mass: a stiff, dense plate on the plastic cube
    M, k, Fy = rho * t_top, E, SY
    uy = Fy / k
    v0 = math.sqrt(2 * Fy * (3 * uy - uy / 2) / M)
    T = 2 * math.pi * math.sqrt(M / k)
    scene = {"model": {"name": "plastic_spring", "dimension": 3, "gravity": [0.0, 0.0, 0.0]},
             "mesh": {"generator": "blocks_3d", "parameters": {"element_size": 1.0, "blocks": [
                 {"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 1, "group": "spring"},
                 {"x0": 0, "y0": 0, "z0": 1, "x1": 1, "y1": 1, "z1": 1 + t_top, "group": "mass"}]}},
             "materials": {"spring": {"youngs_modulus": E, "poisson_ratio": NU, "density": 0.0, "law": "von_mises",
                                      "yield_stress": SY},
                           "mass": {"youngs_modulus": 1e12, "poisson_ratio": 0.0, "density": rho}},
             # stiff across, nearly free along: the plate does not hold the cube's lateral (plastic) expansion
             "joints": {"joints": {"law": "linear", "normal_stiffness": 1e14, "shear_stiffness": 1e6}},
             "supports": [{"set": "base", "components": ["z"]}, {"set": "left", "components": ["x"]},
                          {"set": "front", "components": ["y"]}],
             "stages": [{"name": "impact", "type": "dynamic", "dt": T / 200, "duration": 2.0 * T,
                         "integrator": "newmark_average", "mass": "consistent",
                         "initial_velocity": {"groups": ["mass"], "velocity": [0.0, 0.0, -v0]},
                         "output": {"stride": 1}}]}
    ds = masonrydam.run(scene)
    dyn = ds.where(~np.isnan(ds.time), drop=True)
    top = np.abs(ds.z.values - 1 - t_top) < 1e-9
    w = -dyn.displacement.sel(component="z").values[:, top].mean(axis=1)
    assert w.max() == pytest.approx(3 * uy, rel=0.01)  # (the plate's and joint's own compliance: 0.7 %)
    assert w[len(w) // 2:].mean() == pytest.approx(2 * uy, rel=0.01)
    assert abs(float(dyn.energy_error[-1])) < 1e-9 * float(dyn.energy_strain[-1])
    # the cube's work: the plastic dissipation F_y (u_max - u_y) plus at most its elastic energy F_y u_y / 2
    stored = float(dyn.energy_strain[-1]) - Fy * (w.max() - uy)
    assert 0.0 <= stored <= 0.5 * Fy * uy * 1.01


def _softening_bar(h, regularisation_length, H=-5e9):
    """A 3D bar 0.1 x 0.1 x 1 m pulled at its top; a band one element thick at mid-height yields first
    (0.99 sigma_y). The band's faces slide freely on the bar (shear-soft linear joints), so its stress
    stays uniaxial."""
    def material(sy):
        return {"youngs_modulus": E, "poisson_ratio": NU, "density": 0.0, "law": "von_mises", "yield_stress": sy,
                "isotropic_hardening": H, "regularisation_length": regularisation_length}
    return {"model": {"name": "softening_bar", "dimension": 3, "gravity": [0.0, 0.0, 0.0]},
            "mesh": {"generator": "blocks_3d", "parameters": {"element_size": h, "blocks": [
                {"x0": 0, "y0": 0, "z0": 0, "x1": 0.1, "y1": 0.1, "z1": 0.5 - h / 2, "group": "bar"},
                {"x0": 0, "y0": 0, "z0": 0.5 - h / 2, "x1": 0.1, "y1": 0.1, "z1": 0.5 + h / 2, "group": "band"},
                {"x0": 0, "y0": 0, "z0": 0.5 + h / 2, "x1": 0.1, "y1": 0.1, "z1": 1.0, "group": "bar"}]}},
            "materials": {"bar": material(SY), "band": material(0.99 * SY)},
            "joints": {"joints": {"law": "linear", "normal_stiffness": 1e15, "shear_stiffness": 1e6}},
            "supports": [{"set": "base", "components": ["z"]}, {"set": "left", "components": ["x"]},
                         {"set": "front", "components": ["y"]}],
            "stages": [{"name": "pull", "steps": 40, "loads": [{"type": "displacement", "set": "top",
                                                                 "components": ["z"], "value": [8e-3]}]}]}


@pytest.mark.slow
def test_regularised_softening_is_mesh_objective():
    """Crack-band regularisation (Bazant & Oh 1983; Pietruszczak & Mroz 1981): each element softens with
    H_e = H l_e / l_ref, so a band of any thickness l_e dissipates the same energy and the bar's softening
    branch does not depend on the mesh. Closed form (uniaxial stress, elastic bar of length L, band
    softening linearly to zero): w = sigma L / E + (sigma_b - sigma) l_ref / |H|, zero load at
    w = sigma_b l_ref / |H|. Without the scaling (l_ref = l_e) the branch moves with the mesh."""
    H, l_ref, L = -5e9, 0.1, 1.0
    sb = 0.99 * SY
    branches = []
    for h in (0.1, 0.05):
        ds = masonrydam.run(_softening_bar(h, l_ref, H))
        top = ds.z.values > 1 - 1e-9
        F = ds.reaction.sel(component="z").values[:, top].sum(axis=1) / 0.01  # average stress, Pa
        w = ds.displacement.sel(component="z").values[:, top].mean(axis=1)
        soft = (w > 2e-3) & (w < 4.5e-3)
        expected = (w[soft] - sb * l_ref / abs(H)) / (L / E - l_ref / abs(H))
        np.testing.assert_allclose(F[soft], expected, rtol=0.02, atol=0.01 * SY)
        assert np.abs(F[w > 5.1e-3]).max() < 1e-3 * SY  # fully softened: no load
        branches.append(F)
    # not regularised (the modulus of each mesh's own element size): the finer band dissipates half
    ds = masonrydam.run(_softening_bar(0.05, 0.05, H))
    top = ds.z.values > 1 - 1e-9
    F = ds.reaction.sel(component="z").values[:, top].sum(axis=1) / 0.01
    w = ds.displacement.sel(component="z").values[:, top].mean(axis=1)
    assert np.abs(F[w > 2.6e-3]).max() < 1e-3 * SY  # at zero load already at sigma_b l_e / |H| = 2.5 mm
    with pytest.raises(SceneError) as err:  # the largest element would snap back
        masonrydam.run(_softening_bar(0.1, 1e-4, H))
    assert err.value.key in ("materials.bar.isotropic_hardening", "materials.band.isotropic_hardening")
    assert "snap" in str(err.value) or "too steep" in str(err.value)
