"""Structural closed-form checks of the elasto-plastic blocks
(masonrydam/elements/continuum_plastic.py with the point law masonrydam/materials/von_mises.py).

1. Thick-walled cylinder under internal pressure, von Mises, plane strain, perfectly plastic: inner radius
   a = 100 mm, outer b = 200 mm, E = 210 GPa, nu = 0.3, sigma_y = 240 MPa (the benchmark of de Souza Neto,
   Peric & Owen 2008, *Computational Methods for Plasticity*, sec. 7.5.1), a quarter ring with symmetry
   supports. Closed forms (Hill 1950, *The Mathematical Theory of Plasticity*, ch. V; Lame):

   - elastic (Lame, plane strain): sigma_r = A - B / r^2, sigma_t = A + B / r^2, sigma_z = 2 nu A with
     A = p a^2 / (b^2 - a^2), B = p a^2 b^2 / (b^2 - a^2); outer radial displacement
     u_b = 2 (1 - nu^2) p a^2 b / (E (b^2 - a^2));
   - first yield at r = a: q^2 = 3 B^2 / r^4 + (1 - 2 nu)^2 A^2 (von Mises with the plane-strain sigma_z),
     p_y = sigma_y (b^2 - a^2) / sqrt(3 b^4 + (1 - 2 nu)^2 a^4) (103.75 MPa);
   - elasto-plastic range, plastic front at r = c (Hill's solution, sigma_t - sigma_r = 2k in a <= r <= c,
     k = sigma_y / sqrt(3)): p = k (1 - c^2 / b^2 + 2 ln(c / a)), u_b = 2 (1 - nu^2) k c^2 / (E b) (exact for
     nu = 1/2; de Souza Neto et al. compare their finite elements with it at nu = 0.3);
   - limit (c = b): p_lim = (2 / sqrt(3)) sigma_y ln(b / a) (192.09 MPa).

   The limit is found by load control with ``until_failure = true`` (masonrydam/solvers/static/stepping.py,
   ``StaticStage.until_failure``): the stage ends at the last converged load factor and the result records
   ``limit_load_factor`` and ``limit_state`` (masonrydam/scene/run.py ``_stats_attrs``).

   Element choice: the ring is meshed with 6-node triangles (3 Gauss points). The quad8 element of the
   package (full 3 x 3 Gauss integration) locks in this contained, volume-preserving plastic flow (Nagtegaal,
   Parks & Rice 1974, CMAME 4:153-177: 9 incompressibility constraints per element against about 6 degrees of
   freedom): the ring carries any pressure (4 x 4 elements: 100 p_lim converged, all Gauss points on the
   yield surface with a growing hydrostatic stress), so no limit is found. With ``[materials.<group>]
   integration = "reduced"`` (2 x 2, as de Souza Neto et al. use) the quad8 mesh finds the limit; both are
   checked below.

2. Perzyna viscoplasticity (``viscosity`` eta, Pa s) at element level, the group's evaluation
   ``ContinuumGroup.evaluate(coords, u, want_tangent, dt)`` (masonrydam/assembly/groups.py) driven directly
   with physical time steps, and in a scene whose static stages give their ``duration`` (s; required with
   viscous blocks, each load step then lasts ``duration`` times its load-factor increment). Closed forms (Perzyna 1966; Simo & Hughes 1998, *Computational
   Inelasticity*, sec. 2.7; de Souza Neto et al. 2008, sec. 11.5), gamma_dot = <f> / eta, f = q(s - beta)
   - sigma_y(alpha):

   - relaxation at a constant strain imposed instantly (first response elastic, the trial state): the
     overstress decays as f(t) = f_0 exp(-(3G + H) t / eta), H = H_iso + H_kin, along the fixed direction n,
     so the von Mises stress is q(t) = q_0 - 3G alpha(t), alpha(t) = f_0 / (3G + H) (1 - exp(-(3G + H) t /
     eta)), pressure unchanged; backward Euler gives exactly f_n = f_0 (1 + (3G + H) dt / eta)^(-n);
   - creep under a constant uniaxial stress sigma > sigma_y (3D): alpha = eps_p(t) = (sigma - sigma_y) / H
     (1 - exp(-H t / eta)) (H > 0), (sigma - sigma_y) t / eta (H = 0, steady creep); backward Euler:
     (1 + H dt / eta)^(-n) for the remaining overstress, exact for H = 0.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import SceneError
from masonrydam.materials.von_mises import CODE_PLASTIC, S_CODE, S_EQ_PLASTIC_STRAIN, S_STRESS

E, NU, SY = 2.1e11, 0.3, 2.4e8
A, B = 0.1, 0.2
K_SHEAR = SY / math.sqrt(3.0)
G_SHEAR = E / (2.0 * (1.0 + NU))
P_YIELD = SY * (B**2 - A**2) / math.sqrt(3.0 * B**4 + (1.0 - 2.0 * NU) ** 2 * A**4)
P_LIMIT = 2.0 / math.sqrt(3.0) * SY * math.log(B / A)


# --------------------------------------------------------------------------------------------------
# thick-walled cylinder
# --------------------------------------------------------------------------------------------------

def _ring_mesh(path, n_r=6, n_t=6, quads=False, first=None):
    """Quarter ring a <= r <= b, 0 <= theta <= pi/2 (gmsh, structured, second order: tri6, or quad8 with
    ``quads``); ``first``: radial size of the first layer at r = a (geometric progression), else uniform.
    Facet sets inner (r = a), outer (r = b), bottom (y = 0), left (x = 0); elements in the group ring."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("ring")
        g = gmsh.model.geo
        c = g.addPoint(0, 0, 0)
        p1, p2, p3, p4 = g.addPoint(A, 0, 0), g.addPoint(B, 0, 0), g.addPoint(0, B, 0), g.addPoint(0, A, 0)
        bottom, outer = g.addLine(p1, p2), g.addCircleArc(p2, c, p3)
        left, inner = g.addLine(p3, p4), g.addCircleArc(p4, c, p1)
        s = g.addPlaneSurface([g.addCurveLoop([bottom, outer, left, inner])])
        q = 1.0
        if first is not None:  # h1 (q^n - 1) / (q - 1) = b - a
            from scipy.optimize import brentq

            q = brentq(lambda x: first * (x**n_r - 1.0) / (x - 1.0) - (B - A), 1.0 + 1e-9, 3.0)
        g.mesh.setTransfiniteCurve(bottom, n_r + 1, "Progression", q)
        g.mesh.setTransfiniteCurve(left, n_r + 1, "Progression", 1.0 / q)
        g.mesh.setTransfiniteCurve(outer, n_t + 1)
        g.mesh.setTransfiniteCurve(inner, n_t + 1)
        g.mesh.setTransfiniteSurface(s, "Alternate")
        if quads:
            g.mesh.setRecombine(2, s)
        g.synchronize()
        for name, line in (("bottom", bottom), ("outer", outer), ("left", left), ("inner", inner)):
            gmsh.model.addPhysicalGroup(1, [line], name=name)
        gmsh.model.addPhysicalGroup(2, [s], name="ring")
        gmsh.option.setNumber("Mesh.ElementOrder", 2)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def _cylinder(path, stages, **mesh):
    _ring_mesh(path, **mesh)
    return {"model": {"name": "thick_cylinder", "hypothesis": "plane_strain", "thickness": 1.0, "gravity": [0.0, 0.0]},
            "mesh": {"file": str(path)},
            "materials": {"ring": {"youngs_modulus": E, "poisson_ratio": NU, "density": 0.0, "law": "von_mises",
                                   "yield_stress": SY}},
            "supports": [{"set": "bottom", "components": ["y"]}, {"set": "left", "components": ["x"]}],
            "stages": stages}


def _lame_outer(p):
    return 2.0 * (1.0 - NU**2) * p * A**2 * B / (E * (B**2 - A**2))


def _hill_outer(p):
    """Outer radial displacement of Hill's elasto-plastic solution at the pressure p (p_y' <= p < p_lim)."""
    from scipy.optimize import brentq

    c = brentq(lambda c: K_SHEAR * (1.0 - c**2 / B**2 + 2.0 * math.log(c / A)) - p, A, B)
    return 2.0 * (1.0 - NU**2) * K_SHEAR * c**2 / (E * B)


def _outer_radial(ds):
    """Radial displacement (step, node) of the nodes on r = b."""
    x, y = ds.x.values, ds.y.values
    on = np.abs(np.hypot(x, y) - B) < 1e-9
    assert on.sum() >= 7
    u = ds.displacement.values  # (step, node, component)
    return (u[:, on, 0] * x[on] + u[:, on, 1] * y[on]) / B


@pytest.mark.reference
def test_thick_cylinder_first_yield(tmp_path):
    """No Gauss point yields at 0.99 p_y; at 1.02 p_y points yield, all in the first layer at r = a (2 mm;
    its innermost Gauss points lie 0.24 mm off the bore, where q is 0.5 % below q(a)). The first-yield
    pressure of the elastic solution, 0.99 p_y sigma_y / max q (measured 1.0056 p_y), is p_y within 1 %."""
    from masonrydam.scene import Scene
    from masonrydam.scene import build_mesh, build_model, build_stages
    from masonrydam.solvers.static.stepping import SolverSettings, StaticSolver

    h1 = 0.002
    stages = [{"name": name, "steps": 1, "loads": [{"type": "pressure", "set": "inner", "pressure": dp * P_YIELD}]}
              for name, dp in (("below", 0.99), ("above", 0.03))]
    sc = Scene(_cylinder(tmp_path / "ring.msh", stages, n_t=12, first=h1))
    s = sc.normalized
    mesh = build_mesh(s, sc.base_dir)
    model = build_model(s, mesh)
    g = model.cgroups[0]
    points = np.einsum("gn,enk->egk", g.N, model.coords[g.conn]).reshape(-1, 2)  # Gauss points (e * n_gp + g)
    r = np.hypot(points[:, 0], points[:, 1])
    plastic, q_max = [], []

    def on_step(si, st, lam, u, f_int, f_ext):
        sx, sy, sz, txy = g.state_committed[:, S_STRESS:S_STRESS + 4].T
        q_max.append(float(np.sqrt(0.5 * ((sx - sy) ** 2 + (sy - sz) ** 2 + (sz - sx) ** 2) + 3.0 * txy**2).max()))
        plastic.append((g.state_committed[:, S_CODE] == CODE_PLASTIC).copy())

    StaticSolver(model, SolverSettings(**s["solver"]), on_step=on_step).run(build_stages(s, mesh, model))
    assert len(plastic) == 2
    assert not plastic[0].any()
    assert 0.99 * P_YIELD * SY / q_max[0] == pytest.approx(P_YIELD, rel=0.01)
    assert plastic[1].any()
    assert r[plastic[1]].max() < A + h1
    assert q_max[1] == pytest.approx(SY, rel=1e-9)


@pytest.mark.reference
def test_thick_cylinder_limit_pressure(tmp_path):
    """Pressure raised in steps of 0.05 p_lim towards 1.2 p_lim; the stage stops at the limit (no
    equilibrium beyond it: the tangent of the fully plastic ring is singular)."""
    P = 1.2 * P_LIMIT
    ds = masonrydam.run(_cylinder(tmp_path / "ring.msh", [
        {"name": "pressurise", "steps": 24, "until_failure": True,
         "loads": [{"type": "pressure", "set": "inner", "pressure": P}]}]))
    p = ds.load_factor.values * P
    ub = _outer_radial(ds)
    # elastic range (p < p_y = 0.54 p_lim): Lame at every node of the outer surface
    elastic = p < 0.99 * P_YIELD
    assert elastic.sum() == 10
    np.testing.assert_allclose(ub[elastic], np.broadcast_to(_lame_outer(p[elastic])[:, None], ub[elastic].shape),
                               rtol=0.01)
    # elasto-plastic range: Hill's solution (plastic front c = 0.134 m at 0.75 p_lim, 0.150 m at 0.9 p_lim)
    for frac in (0.75, 0.9):
        i = int(np.flatnonzero(np.isclose(p, frac * P_LIMIT, rtol=1e-9))[0])
        assert ub[i].mean() == pytest.approx(_hill_outer(p[i]), rel=0.02)
        assert ub[i].mean() > 1.05 * _lame_outer(p[i])  # visibly plastic
    # the limit: reported by the stage, within 3 % of (2 / sqrt(3)) sigma_y ln(b / a)
    assert "limit_load_factor" in ds.attrs, "the stage reached 1.2 p_lim: no limit found"
    lam = float(ds.attrs["limit_load_factor"])
    assert "no equilibrium" in ds.attrs["limit_state"]
    assert lam == pytest.approx(ds.load_factor.values[-1])
    assert lam * P / P_LIMIT == pytest.approx(1.0, rel=0.03)
    # and the displacement runs away towards it: the last converged steps are far softer than elastic
    assert ub[-1].mean() > 2.0 * _lame_outer(p[-1])
    slope = (p[-1] - p[-2]) / (ub[-1].mean() - ub[-2].mean())
    assert slope < 0.05 * p[0] / ub[0].mean()


def _cylinder_quad8(tmp_path, integration, P):
    s = _cylinder(tmp_path / "ring.msh", [
        {"name": "pressurise", "steps": 10, "until_failure": True,
         "loads": [{"type": "pressure", "set": "inner", "pressure": P}]}], n_r=4, n_t=4, quads=True)
    s["materials"]["ring"]["integration"] = integration
    return masonrydam.run(s)


@pytest.mark.reference
def test_thick_cylinder_limit_pressure_quad8_reduced(tmp_path):
    """quad8 with the reduced 2 x 2 rule (``integration = "reduced"``) finds the limit pressure; with the
    full 3 x 3 rule it locks (Nagtegaal, Parks & Rice 1974) and carries 1.5 p_lim."""
    P = 1.5 * P_LIMIT
    ds = _cylinder_quad8(tmp_path, "reduced", P)
    assert "limit_load_factor" in ds.attrs
    assert float(ds.attrs["limit_load_factor"]) * P / P_LIMIT == pytest.approx(1.0, rel=0.03)
    locked = _cylinder_quad8(tmp_path, "full", P)
    assert "limit_load_factor" not in locked.attrs and locked.load_factor.values[-1] == pytest.approx(1.0)


# --------------------------------------------------------------------------------------------------
# Perzyna relaxation and creep (element level, physical time steps)
# --------------------------------------------------------------------------------------------------

def _block_group(dim, material):
    """The model and the plastic group of one unit element (quad4 in plane strain, hex8 in 3D)."""
    from masonrydam.scene import Scene
    from masonrydam.scene import build_mesh, build_model

    if dim == 2:
        mesh = {"generator": "blocks_2d", "parameters": {"element_size": 1.0, "blocks": [
            {"x0": 0, "y0": 0, "x1": 1, "y1": 1, "group": "solid"}]}}
        model = {"name": "block", "hypothesis": "plane_strain", "thickness": 1.0, "gravity": [0.0, 0.0]}
    else:
        mesh = {"generator": "blocks_3d", "parameters": {"element_size": 1.0, "blocks": [
            {"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 1, "group": "solid"}]}}
        model = {"name": "block", "dimension": 3, "gravity": [0.0, 0.0, 0.0]}
    sc = Scene({"model": model, "mesh": mesh,
                "materials": {"solid": dict({"youngs_modulus": E, "poisson_ratio": NU, "density": 0.0,
                                             "law": "von_mises", "yield_stress": SY}, **material)},
                "stages": [{"name": "none", "loads": []}]})
    m = build_model(sc.normalized, build_mesh(sc.normalized, sc.base_dir))
    assert len(m.cgroups) == 1 and m.cgroups[0].n_elem == 1 and m.cgroups[0].plastic
    return m, m.cgroups[0]


@pytest.mark.parametrize("h_iso, h_kin", [(0.0, 0.0), (2e10, 1e10)])
def test_perzyna_relaxation_at_constant_strain(h_iso, h_kin):
    """Plane strain, the strain exx = 4 eps_y, eyy = -eps_y, gxy = eps_y imposed at every node at once, then
    held: the stress relaxes from the elastic trial towards the yield surface with the time constant
    tau = eta / (3G + H); checked at the Gauss points and as the force on the face x = 1."""
    eta = 1e12  # Pa s
    model, g = _block_group(2, {"isotropic_hardening": h_iso, "kinematic_hardening": h_kin, "viscosity": eta})
    H = h_iso + h_kin
    tau = eta / (3.0 * G_SHEAR + H)
    ey = SY / E
    strain = np.array([4.0 * ey, -ey, ey])  # exx, eyy, gxy
    x, y = model.coords[:, 0], model.coords[:, 1]
    u = np.zeros(model.n_dof)
    u[0::2] = strain[0] * x + 0.5 * strain[2] * y
    u[1::2] = strain[1] * y + 0.5 * strain[2] * x
    right = np.flatnonzero(np.abs(x - 1.0) < 1e-12)
    dofs = g.dofs[0]

    def state():
        s = g.state_committed
        sig = s[:, S_STRESS:S_STRESS + 6]
        assert np.ptp(sig, axis=0).max() < 1e-6 * SY  # homogeneous
        fx = sum(g.fe[0][list(dofs).index(2 * n)] for n in right)  # force on the face x = 1 (1 m2)
        return sig[0], float(fx)

    # instant loading: no time, no viscous flow: the elastic trial stress
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), G_SHEAR
    g.evaluate(model.coords, u, True, dt=0.0)
    g.commit()
    sig0, fx0 = state()
    tr = strain[0] + strain[1]
    assert sig0[0] == pytest.approx(lam * tr + 2 * mu * strain[0], rel=1e-12)
    assert sig0[2] == pytest.approx(lam * tr, rel=1e-12)
    assert sig0[3] == pytest.approx(mu * strain[2], rel=1e-12)
    assert fx0 == pytest.approx(sig0[0], rel=1e-12)
    p0 = sig0[:3].mean()
    s0 = sig0 - np.r_[p0, p0, p0, 0, 0, 0]
    q0 = math.sqrt(1.5 * (s0[:3] @ s0[:3] + 2 * s0[3:] @ s0[3:]))
    f0 = q0 - SY
    assert f0 > 2.0 * SY

    # held: backward Euler steps of tau / 50 over 4 tau
    dt, n = tau / 50.0, 200
    for k in range(1, n + 1):
        g.evaluate(model.coords, u, True, dt=dt)
        g.commit()
        sig, fx = state()
        alpha = g.state_committed[0, S_EQ_PLASTIC_STRAIN]
        f = f0 - (3.0 * G_SHEAR + H) * alpha  # overstress from the plastic multiplier
        # the discrete decay of the implicit update, exactly
        assert f == pytest.approx(f0 * (1.0 + dt / tau) ** (-k), rel=1e-9)
        t = k * dt
        alpha_exact = f0 / (3.0 * G_SHEAR + H) * (1.0 - math.exp(-t / tau))
        q_exact = q0 - 3.0 * G_SHEAR * alpha_exact
        sig_exact = np.r_[p0, p0, p0, 0, 0, 0] + s0 * q_exact / q0
        # converges to the continuous relaxation (first order in dt / tau: 1 % of the overstress at most)
        np.testing.assert_allclose(sig, sig_exact, rtol=0, atol=0.01 * f0)
        assert fx == pytest.approx(sig[0], rel=1e-12)
    q_end = q0 - 3.0 * G_SHEAR * alpha
    assert q_end - (SY + H * alpha) == pytest.approx(f0 * math.exp(-4.0), rel=0.05)
    # long after: on the yield surface (sigma_y itself without hardening)
    g.evaluate(model.coords, u, True, dt=1e3 * tau)
    g.commit()
    alpha = g.state_committed[0, S_EQ_PLASTIC_STRAIN]
    q_inf = q0 - 3.0 * G_SHEAR * f0 / (3.0 * G_SHEAR + H)
    assert q0 - 3.0 * G_SHEAR * alpha == pytest.approx(q_inf, rel=1e-3 * f0 / q_inf)
    if H == 0.0:
        assert q_inf == pytest.approx(SY, rel=1e-12)


@pytest.mark.parametrize("h_iso, h_kin", [(0.0, 0.0), (1.5e10, 0.5e10)])
def test_perzyna_creep_under_constant_stress(h_iso, h_kin):
    """3D, one hex8 under a constant uniaxial tension 1.5 sigma_y on its top face (symmetry supports), applied at
    once and held: the strain creeps by eps_p(t) = (sigma - sigma_y) / H (1 - exp(-H t / eta)), linear in t
    for H = 0 (time constant eta / H under load control, against eta / (3G + H) at a held strain)."""
    eta = 1e12
    model, g = _block_group(3, {"isotropic_hardening": h_iso, "kinematic_hardening": h_kin, "viscosity": eta})
    H = h_iso + h_kin
    sig = 1.5 * SY
    c = model.coords
    nd = model.n_dof
    fixed = np.zeros(nd, dtype=bool)
    fixed[0::3] = c[:, 0] < 1e-12
    fixed[1::3] = c[:, 1] < 1e-12
    fixed[2::3] = c[:, 2] < 1e-12
    free = np.flatnonzero(~fixed)
    f_ext = np.zeros(nd)
    f_ext[2::3][c[:, 2] > 1 - 1e-12] = sig / 4.0  # the four corners of the 1 m2 top face
    dofs = g.dofs[0]

    def solve(u, dt):
        for _ in range(30):
            g.evaluate(c, u, True, dt=dt)
            f = np.zeros(nd)
            K = np.zeros((nd, nd))
            np.add.at(f, dofs, g.fe[0])
            K[np.ix_(dofs, dofs)] += g.ke[0]
            r = (f_ext - f)[free]
            if np.linalg.norm(r) <= 1e-10 * sig:
                g.commit()
                return u
            u = u.copy()
            u[free] += np.linalg.solve(K[np.ix_(free, free)], r)
        raise AssertionError("no convergence")

    top = c[:, 2] > 1 - 1e-12
    u = solve(np.zeros(nd), 0.0)  # instant loading: elastic
    assert u[2::3][top] == pytest.approx(sig / E, rel=1e-10)
    tau = eta / H if H > 0 else eta / (3.0 * G_SHEAR)  # the scale of the steps only, for H = 0
    dt, n = tau / 40.0, 120
    for k in range(1, n + 1):
        u = solve(u, dt)
        t = k * dt
        ez = u[2::3][top]
        assert np.ptp(ez) < 1e-9 * ez.mean()
        sz = g.state_committed[:, S_STRESS + 2]
        assert sz == pytest.approx(sig, rel=1e-9)  # the load is carried by the same stress, uniaxial
        ep = ez.mean() - sig / E
        if H == 0.0:  # steady creep: backward Euler is exact
            assert ep == pytest.approx((sig - SY) * t / eta, rel=1e-8)
        else:
            assert ep == pytest.approx((sig - SY) / H * (1.0 - (1.0 + dt * H / eta) ** (-k)), rel=1e-8)
            # converges to the continuous creep curve (first order in dt H / eta: 1 % of its end value at most)
            assert ep == pytest.approx((sig - SY) / H * (1.0 - math.exp(-H * t / eta)), abs=0.01 * (sig - SY) / H)
    # lateral contraction: elastic nu plus plastic 1/2 (plastic incompressibility)
    right = c[:, 0] > 1 - 1e-12
    assert u[0::3][right] == pytest.approx(-NU * sig / E - 0.5 * ep, rel=1e-8)


def test_perzyna_creep_in_a_scene_with_stage_durations():
    """A 3D block loaded at once (a stage of 1 microsecond) to a uniaxial 1.5 sigma_y, then held for 100 s:
    perfect Perzyna plasticity creeps at (sigma - sigma_y) / eta, exactly under backward Euler; a static
    stage without a duration is refused for viscous blocks."""
    eta = 1.25e12  # Pa s: 1 % plastic strain in 100 s at 0.5 sigma_y of overstress
    sigma = 1.5 * SY
    scene = {"model": {"name": "creep", "dimension": 3, "gravity": [0.0, 0.0, 0.0]},
             "mesh": {"generator": "blocks_3d", "parameters": {"element_size": 1.0, "blocks": [
                 {"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 1, "group": "solid"}]}},
             "materials": {"solid": {"youngs_modulus": E, "poisson_ratio": NU, "density": 0.0, "law": "von_mises",
                                     "yield_stress": SY, "viscosity": eta}},
             "supports": [{"set": "base", "components": ["z"]}, {"set": "left", "components": ["x"]},
                          {"set": "front", "components": ["y"]}],
             "stages": [{"name": "load", "steps": 1, "duration": 1e-6,
                         "loads": [{"type": "pressure", "set": "top_face", "pressure": sigma}]},
                        {"name": "hold", "steps": 10, "duration": 100.0, "loads": []}]}
    ds = masonrydam.run(scene)
    top = ds.z.values > 1 - 1e-9
    w = -ds.displacement.sel(component="z").values[:, top].mean(axis=1)
    assert w[0] == pytest.approx(sigma / E, rel=1e-4)  # instant load: elastic
    t = np.arange(len(w)) * 10.0  # s: the hold's steps
    # (atol: the loading stage's own microsecond of creep, 1e-10)
    np.testing.assert_allclose(w - sigma / E, (sigma - SY) * t / eta, rtol=1e-6, atol=2e-10)
    del scene["stages"][1]["duration"]
    with pytest.raises(SceneError) as err:
        masonrydam.run(scene)
    assert err.value.key == "stages[1].duration"


def test_perzyna_creep_goes_on_in_a_dynamic_stage_at_rest():
    """The block of the scene test above, loaded at once in a static stage, then held by a dynamic stage
    with no ground motion for 20 s: a viscous block creeps at (sigma - sigma_y) / eta in dynamic steps
    too, also in steps whose predictor is already in equilibrium (the law's time, not the displacement,
    drives it). A light block (density 10 kg/m3) keeps the inertia negligible."""
    eta = 1.25e12
    sigma = 1.5 * SY
    scene = {"model": {"name": "creep_dynamic", "dimension": 3, "gravity": [0.0, 0.0, 0.0]},
             "mesh": {"generator": "blocks_3d", "parameters": {"element_size": 1.0, "blocks": [
                 {"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 1, "group": "solid"}]}},
             "materials": {"solid": {"youngs_modulus": E, "poisson_ratio": NU, "density": 10.0, "law": "von_mises",
                                     "yield_stress": SY, "viscosity": eta}},
             "supports": [{"set": "base", "components": ["z"]}, {"set": "left", "components": ["x"]},
                          {"set": "front", "components": ["y"]}],
             "stages": [{"name": "load", "steps": 1, "duration": 1e-6,
                         "loads": [{"type": "pressure", "set": "top_face", "pressure": sigma}]},
                        {"name": "hold", "type": "dynamic", "dt": 1.0, "duration": 20.0, "integrator": "hht",
                         "initial_velocity": {"groups": ["solid"], "velocity": [0.0, 0.0, 0.0]}}]}
    ds = masonrydam.run(scene)
    top = ds.z.values > 1 - 1e-9
    dyn = ds.where(~np.isnan(ds.time), drop=True)
    w = -dyn.displacement.sel(component="z").values[:, top].mean(axis=1)
    t = dyn.time.values - dyn.time.values[0]
    np.testing.assert_allclose(w - w[0], (sigma - SY) * t / eta, rtol=1e-3, atol=1e-9)
    assert w[-1] - w[0] == pytest.approx((sigma - SY) * 20.0 / eta, rel=1e-3)
