"""Hard cases of jointed-block analysis (the robustness cases): impacts, chatter, stick-slip, stiff
penalties, floating blocks, lift-off, brittle cascades, non-unique friction, near-collapse statics
and 3D rocking and sliding.

Every case checks three things: no NaN or infinity in the results; the energy never grows beyond
the work put in (dynamic cases: kinetic + strain + joint stored energy never exceeds the work of the
ground motion and of the constant loads by more than 1 % of the largest energy term, from the energy
terms the solver records); and its physical result against a closed form whose source is cited in
the docstring. Cases that show a defect the rules of this suite could not fix are marked
``xfail(strict=True)`` with the measured failure in the reason.

Sources used throughout: Newmark (1965), Geotechnique 15(2):139-160 (rigid sliding block);
Housner (1963), BSSA 53(2):403-417 (rocking block); Klarbring (1990), Ingenieur-Archiv 60:529-541
(non-uniqueness of frictional contact); Schellekens & de Borst (1993), IJNME 36:43-66 (interface
integration); the joint law of Tzamtzis & Asteris (sec. 3.4, eqs. 11-12: tau_y = c - t_n
tan(phi), no tension, open joints carry nothing).
"""
from __future__ import annotations

import contextlib
import math
import signal
import time

import numpy as np
import pytest
import scipy.optimize

import masonrydam
from masonrydam.effects import loads as L
from masonrydam.errors import ConvergenceError, MechanismError
from masonrydam.materials import mohr_coulomb as mc
from masonrydam.solvers.dynamic import DynamicSettings, DynamicSolver, DynamicStage, GroundMotion
from scenes import ROCKING_BLOCK_HEIGHT as H, ROCKING_BLOCK_WIDTH as B, rocking_block_model, sliding_block
from test_system import BASE, BLOCK, _direction_changes, block_scene, top_force

pytestmark = pytest.mark.hard_case

G = 9.80665
#: the energy bound of every dynamic case: growth <= ENERGY_SLACK x the largest energy term
ENERGY_SLACK = 0.01
ENERGY_TERMS = ("input", "external", "kinetic", "strain", "damping", "joint", "joint_stored", "joint_dissipated")


# ------------------------------------------------------------------------------------------------
# shared checks
# ------------------------------------------------------------------------------------------------

def dynamic_steps(ds):
    """Mask of the dynamic steps of a result (time is NaN on static steps)."""
    return np.isfinite(ds.time.values) if "time" in ds.variables else np.zeros(ds.sizes["step"], dtype=bool)


def assert_finite(ds):
    """No NaN or infinity in the nodal and joint fields, nor in the dynamic fields of dynamic steps."""
    for v in ("displacement", "reaction", "joint_opening", "joint_slip", "joint_traction_normal",
              "joint_traction_shear", "load_factor"):
        assert np.isfinite(ds[v].values).all(), f"{v} has NaN or infinity"
    dyn = dynamic_steps(ds)
    if dyn.any():
        for v in ("velocity", "acceleration", "ground_acceleration") + tuple(f"energy_{k}" for k in ENERGY_TERMS):
            assert np.isfinite(ds[v].values[dyn]).all(), f"{v} has NaN or infinity"


def energy_growth(terms: dict) -> tuple[float, float]:
    """(largest growth, largest energy term) of an energy history: growth = kinetic + strain + joint
    stored - input - external (all changes since the start of the dynamic stages; physically <= 0 when
    nothing else stores energy: damping and joint dissipation can only take energy out)."""
    growth = terms["kinetic"] + terms["strain"] + terms["joint_stored"] - terms["input"] - terms["external"]
    scale = max(float(np.abs(terms[k]).max()) for k in ENERGY_TERMS)
    return float(growth.max()), scale


def assert_energy_bounded(ds):
    dyn = dynamic_steps(ds)
    growth, scale = energy_growth({k: ds[f"energy_{k}"].values[dyn] for k in ENERGY_TERMS})
    assert scale > 0
    assert growth <= ENERGY_SLACK * scale, f"energy grew by {growth:.4g} J, {growth / scale:.3g} of {scale:.4g} J"
    return growth / scale


def joint_forces(ds, step=-1):
    """Resultant normal and shear forces (N) of all joint points at a step (traction x weight)."""
    w = ds.joint_weight.values
    return (float((ds.joint_traction_normal.values[step] * w).sum()),
            (ds.joint_traction_shear.values[step] * w[:, None]).sum(axis=0))


def assert_coulomb_admissible(ds, tan_phi, cohesion=0.0, tensile_strength=0.0, rtol=1e-6):
    """Every point of every step: |tau| <= c - t_n tan(phi) (t_n tension positive), t_n <= ft, and an
    open point carries no traction (Tzamtzis & Asteris sec. 3.4)."""
    tn = ds.joint_traction_normal.values
    tau = np.linalg.norm(ds.joint_traction_shear.values, axis=-1)
    scale = max(np.abs(tn).max(), tau.max(), 1.0)
    open_ = ds.joint_state.values == mc.OPEN
    assert (tn <= tensile_strength + rtol * scale).all(), "tension above the tensile strength"
    assert (tau <= cohesion - tn * tan_phi + rtol * scale).all(), "shear traction outside the Coulomb cone"
    assert (tn[open_] == 0).all() and (tau[open_] == 0).all(), "an open point carries traction"


@contextlib.contextmanager
def time_limit(seconds: int):
    """Fail (TimeoutError) instead of hanging when the block takes longer than ``seconds``."""
    def expired(signum, frame):
        raise TimeoutError(f"no answer within {seconds} s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


# ------------------------------------------------------------------------------------------------
# 1. free rocking with repeated impacts
# ------------------------------------------------------------------------------------------------

def free_rocking_history(integrator, dt=5e-4, duration=1.0, theta_ratio=0.02, **kw):
    """The Housner block of test_dynamics (0.3 x 1.5 m, friction 45 deg: mu = 1) released from rest
    tilted by theta0 = theta_ratio * alpha about its toe. Per step: time, tilt (heel minus toe uplift
    over B), horizontal displacement of the block's bottom edge (its slip on the fixed base), largest
    plastic slip of any joint point, and the energy terms."""
    model, supports, block = rocking_block_model()
    x = model.coords
    alpha = math.atan(B / H)
    th0 = theta_ratio * alpha
    u0 = np.zeros(model.n_dof)
    u0[block * 2], u0[block * 2 + 1] = -th0 * x[block, 1], th0 * x[block, 0]
    heel = block[np.argmin((x[block, 0] - B) ** 2 + x[block, 1] ** 2)]
    toe = block[np.argmin(x[block, 0] ** 2 + x[block, 1] ** 2)]
    bottom = block[np.isclose(x[block, 1], 0.0)]
    joints = model.igroups[0]
    rows, energy = [], {k: [] for k in ENERGY_TERMS}

    def on_step(r):
        u = r["u"]
        rows.append((r["t"], (u[heel * 2 + 1] - u[toe * 2 + 1]) / B, u[bottom * 2].mean(),
                     np.abs(joints.state_committed[..., mc.S_PLASTIC_SLIP]).max(), np.isfinite(u).all()))
        for k in ENERGY_TERMS:
            energy[k].append(r["energy"][k])

    s = DynamicSettings(integrator=integrator, dt=dt, **kw)
    DynamicSolver(model, s).run(DynamicStage("rock", duration, supports, [GroundMotion(0, np.zeros(2), 1.0)], s),
                                u0=u0, f_static=L.self_weight(model, [0.0, -G]), equilibrate=False, on_step=on_step)
    rows = np.array(rows)
    return rows, {k: np.array(v) for k, v in energy.items()}, th0, alpha


@pytest.mark.parametrize("integrator", [
    "hht",
    pytest.param("newmark_average", marks=pytest.mark.xfail(
        strict=True, raises=AssertionError,
        reason="trapezoidal rule, dt = 0.5 ms: the undamped penalty-contact vibrations after each impact let the "
               "mu = 1 block slide 5.2 mm (1.7 % of its width B; HHT: 0.53 mm); the first impact keeps 95 % of the "
               "energy (Housner: r^2 = 89 %) and the mechanical energy rises across the 7th and 10th impacts "
               "(+6 %, +8 %); there is no contact damping or restitution parameter to remove the vibrations")),
])
@pytest.mark.slow
def test_free_rocking_repeated_impacts_no_spurious_sliding(integrator):
    """Housner (1963): a rigid block rocking on a rigid base with mu = 1 never slides (the impact impulse
    needs |P_x / P_y| = h (1 - r) / (b (1 + r)) = 0.15 of friction here), and every impact keeps the
    fraction r^2 of the kinetic energy, r = 1 - 1.5 sin^2(alpha) (eq. 12; r^2 = 0.888 for b/h = 0.2).
    Released from theta0 = 0.02 alpha, 1 s (12 impacts): the block's bottom edge slips less than 1 % of
    its width B at every step (HHT reaches 0.18 %); the mechanical energy E0 + (kinetic + strain + joint
    stored - work of gravity), E0 = m g b theta0 the released potential energy (exact for the
    small-displacement model), averaged over each flight between impacts, drops at every impact; the
    first drop is Housner's r^2 within 3 % (HHT: 1.3 %); and the energy never grows beyond E0 by more
    than 1 % of the largest energy term."""
    rows, energy, th0, alpha = free_rocking_history(integrator)
    t, theta, slip, plastic, finite = rows.T
    assert finite.all() and all(np.isfinite(v).all() for v in energy.values())
    growth, scale = energy_growth(energy)
    assert growth <= ENERGY_SLACK * scale
    assert np.abs(slip).max() < 0.01 * B, f"the block slid {np.abs(slip).max() * 1e3:.3g} mm"
    assert plastic.max() < 0.01 * B
    impacts = np.nonzero(np.diff(np.sign(theta)) != 0)[0]
    assert len(impacts) >= 5, "repeated impacts"
    E0 = 2000 * B * H * G * (B / 2) * th0
    E = E0 + energy["kinetic"] + energy["strain"] + energy["joint_stored"] - energy["input"] - energy["external"]
    edges = np.concatenate([[0], impacts, [len(t) - 1]])
    flights = np.array([E[a + 10:b - 10].mean() for a, b in zip(edges[:-1], edges[1:]) if b - a > 40])
    assert (np.diff(flights) < 0).all(), f"mechanical energy per flight: {flights / E0}"
    r = 1 - 1.5 * math.sin(alpha) ** 2
    assert flights[1] / flights[0] == pytest.approx(r**2, rel=0.03)


# ------------------------------------------------------------------------------------------------
# 2. stick-slip reversal under cyclic shear (static)
# ------------------------------------------------------------------------------------------------

def test_stick_slip_reversal_hysteresis_loop_area():
    """A rigid block under a constant normal force N = sigma A on a cohesionless joint (mu = 0.6,
    shear stiffness ks, residual stiffness 0), its top kept horizontal and at its height, pushed to +d,
    back to -d and again to +d (displacement control). Elastic-perfectly-plastic friction (Tzamtzis & Asteris sec. 3.4)
    gives a parallelogram between F = +-mu N with elastic branches of slope ks A: loop area
    4 mu N (d - mu N / (ks A)) (the rigid-plastic 4 mu N d less the elastic travel; here d = 10 mu N /
    (ks A), so the correction is 10 %). Asserted: the trapezoidal area of the closed F(u) loop within
    1 % of that (the code reaches 8e-5), |F| <= mu N at every step, the loop closes, and the energy
    dissipated by slip, mu N sum |delta s_p|, equals the loop area (the work put in) within 0.1 %."""
    mu, sigma, ks, A = 0.6, 0.2e6, 20e9, 2.0
    N = sigma * A
    d = 10 * mu * N / (ks * A)
    joint = {"normal_stiffness": 50e9, "shear_stiffness": ks, "friction_angle": math.degrees(math.atan(mu))}

    def push(v):
        return [{"type": "displacement", "set": "top", "components": ["x", "y"], "value": [v, 0.0]}]

    stages = [{"name": "compress", "loads": [{"type": "edge_pressure", "set": "top_edge", "pressure": sigma}]},
              {"name": "push", "steps": 10, "loads": push(d)},
              {"name": "back", "steps": 20, "loads": push(-2 * d)},
              {"name": "again", "steps": 20, "loads": push(2 * d)}]
    ds = masonrydam.run(block_scene(blocks=[BASE, BLOCK], joint=joint, stages=stages, block_E=1e14, density=0.0))
    assert_finite(ds)
    F = top_force(ds, "x", 1.0)
    u = ds.displacement.sel(component="x").where(np.isclose(ds.y, 1.0)).mean("node").values
    stage = ds.stage.values
    loop = np.concatenate([[np.nonzero(stage == 1)[0][-1]], np.nonzero(stage >= 2)[0]])
    assert u[loop[0]] == pytest.approx(d, rel=1e-9) and u[loop[-1]] == pytest.approx(d, rel=1e-9)
    assert F[loop[-1]] == pytest.approx(F[loop[0]], rel=1e-6), "the loop closes"
    assert np.abs(F).max() <= mu * N * (1 + 1e-6)
    area = float(np.sum(0.5 * (F[loop][1:] + F[loop][:-1]) * np.diff(u[loop])))
    expected = 4 * mu * N * (d - mu * N / (ks * A))
    assert area == pytest.approx(expected, rel=0.01)
    slip_p = ds.joint_plastic_slip.values[loop, :, 0].mean(axis=1)
    assert mu * N * np.abs(np.diff(slip_p)).sum() == pytest.approx(area, rel=1e-3)
    assert_coulomb_admissible(ds, mu)


# ------------------------------------------------------------------------------------------------
# 3. penalty-to-Young's-modulus ratios 1e1 .. 1e6
# ------------------------------------------------------------------------------------------------

RATIOS = [1e1, 1e2, 1e3, 1e4, 1e5, 1e6]


@pytest.mark.slow
def test_penalty_ratio_column_converges_to_the_jointless_answer():
    """A 1 x 4 m column (E = 10 GPa, nu = 0, plane stress, h = 0.25 m elements) with a Mohr-Coulomb
    joint at mid-height, self-weight and a 0.1 MPa top pressure, plus a sideways body force 0.5 g (the
    joint stays closed and sticking). Uniaxial statics with nu = 0: the mean top settlement is
    (p L + rho g L^2 / 2) / E + (p + rho g L / 2) / kn. For kn h / E from 1e1 to 1e6: the FE equals it
    within 1e-9 (the code reaches 2e-10), and the error against the jointless column (run too, equal to
    the first term within 1e-9) falls monotonically: it is E / (kn L) = h / (ratio L) of the settlement,
    within 1 % (the code reaches 0.3 % at 1e6, where the difference is 6e-8 of the settlement)."""
    E, h, rho, p, W, Lc = 10e9, 0.25, 2000.0, 0.1e6, 1.0, 4.0

    def run(ratio):
        if ratio is None:
            blocks = [{"x0": 0, "y0": 0, "x1": W, "y1": Lc, "group": "lower"}]
        else:
            blocks = [{"x0": 0, "y0": 0, "x1": W, "y1": Lc / 2, "group": "lower"},
                      {"x0": 0, "y0": Lc / 2, "x1": W, "y1": Lc, "group": "upper"}]
        kn = (ratio or 1.0) * E / h
        joint = {"normal_stiffness": kn, "shear_stiffness": kn, "friction_angle": 45.0}
        stages = [{"name": "load", "loads": [{"type": "self_weight"},
                                             {"type": "edge_pressure", "set": "top_edge", "pressure": p}]}]
        sc = block_scene(blocks=blocks, joint=joint, gravity=(0.5 * G, -G), stages=stages, element_size=h,
                         block_E=E, density=rho)
        if ratio is None:
            del sc["joints"]
        ds = masonrydam.run(sc)
        assert_finite(ds)
        top = np.isclose(ds.y.values, Lc)
        w = np.where(np.isclose(ds.x.values[top], 0) | np.isclose(ds.x.values[top], W), 0.5, 1.0)
        return ds, float((ds.displacement.sel(component="y").values[-1][top] * w).sum() / w.sum())

    _, u0 = run(None)
    solid = -(p * Lc + rho * G * Lc**2 / 2) / E
    assert u0 == pytest.approx(solid, rel=1e-9)
    errors = []
    for ratio in RATIOS:
        ds, u = run(ratio)
        assert (ds.joint_state.values == mc.STICK).all()
        kn = ratio * E / h
        assert u == pytest.approx(solid - (p + rho * G * Lc / 2) / kn, rel=1e-9)
        errors.append(abs(u - u0) / abs(u0))
    errors = np.array(errors)
    assert (np.diff(errors) < 0).all()
    np.testing.assert_allclose(errors * np.array(RATIOS), h / Lc, rtol=1e-2)


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.reference
def test_penalty_ratio_no_traction_oscillation_with_lumped_integration(ratio):
    """Schellekens & de Borst (1993), as in test_system: two blocks (E = 2 GPa) on a
    stiff cohesive joint that stops at a notch, the right block pulled (1e5 Pa on its 0.4 m end), h =
    0.025 m, kn = ks = ratio E / h. With nodal (lumped) integration the normal traction along the joint
    falls monotonically from the notch tip at every ratio (no direction change), the resultant equals
    the pull (statics, within 1e-8), and the joint stays bonded; the same joint with 2-point Gauss
    integration oscillates (>= 2 direction changes: the check can see an oscillation)."""
    E, h, F = 2e9, 0.025, 1e5

    def notched(integration):
        joint = {"normal_stiffness": ratio * E / h, "shear_stiffness": ratio * E / h, "friction_angle": 45.0,
                 "cohesion": 1e8, "tensile_strength": 1e8, "integration": integration}
        blocks = [{"x0": 0.0, "y0": 0.1, "x1": 1.0, "y1": 0.4, "group": "left"},
                  {"x0": 1.0, "y0": 0.0, "x1": 2.0, "y1": 0.4, "group": "right"}]
        stages = [{"name": "pull", "loads": [{"type": "edge_traction", "set": "right_edge", "traction": [F, 0.0]}]}]
        ds = masonrydam.run(block_scene(blocks=blocks, joint=joint, stages=stages, element_size=h, block_E=E,
                                        density=0.0, supports=[{"set": "left", "components": ["x", "y"]}]))
        assert_finite(ds)
        o = np.argsort(ds.joint_y.values, kind="stable")
        return ds, ds.joint_y.values[o], ds.joint_traction_normal.isel(step=-1).values[o], ds.joint_weight.values[o]

    ds, y, tn, w = notched("lumped")
    assert (ds.joint_state.values == mc.STICK).all()
    assert float((tn * w).sum()) == pytest.approx(F * 0.4, rel=1e-8)
    nodes = np.unique(np.round(y, 9))
    t_nodes = np.array([tn[np.isclose(y, v)].mean() for v in nodes])
    assert _direction_changes(t_nodes) == 0, "lumped tractions fall monotonically from the notch tip"
    _, _, tn_g, _ = notched("gauss")
    assert _direction_changes(tn_g) >= 2


# ------------------------------------------------------------------------------------------------
# 4. floating block
# ------------------------------------------------------------------------------------------------

def floating_scene(stages):
    """A fixed 1 x 0.25 m base and a 1 x 0.5 m block 0.75 m above it: no joint, no support."""
    return {"model": {"name": "floating", "thickness": 1.0},
            "mesh": {"generator": "blocks_2d", "parameters": {"blocks": [
                {"x0": 0, "y0": 0, "x1": 1, "y1": 0.25, "group": "base"},
                {"x0": 0, "y0": 1.0, "x1": 1, "y1": 1.5, "group": "floating"}], "element_size": 0.25}},
            "materials": {g: {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": 2000}
                          for g in ("base", "floating")},
            "supports": [{"set": "base", "components": ["x", "y"]}],
            "stages": stages}


def test_floating_block_static_error_names_the_part(tmp_path):
    """A block with no support and no joint has three rigid-body modes: no static equilibrium exists
    under its weight (statics). The static stage stops before solving with a MechanismError that names
    the stage, the element group of the free part, its free motions and that it has no support, and
    the result file is kept with no step."""
    out = tmp_path / "floating.nc"
    with pytest.raises(MechanismError) as exc:
        masonrydam.run(floating_scene([{"name": "gravity", "loads": [{"type": "self_weight"}]}]), output=out)
    msg = str(exc.value)
    assert "stage 'gravity'" in msg and "before solving" in msg
    assert len(exc.value.parts) == 1
    part = exc.value.parts[0]
    assert "['floating']" in part and "no support" in part
    assert all(m in part for m in ("translation x", "translation y", "rotation"))
    import xarray as xr

    with xr.open_dataset(out) as ds:
        assert ds.attrs["completed"] == "false" and ds.sizes["step"] == 0


def test_floating_block_free_fall_is_exact():
    """The same floating block in a dynamic stage (allowed: the mass makes every step solvable), the
    ground accelerating upwards at a_g = g: relative to the ground the block falls freely, u_y = -g t^2 /
    2 (Newton; relative formulation, Chopra 2012 sec. 1.7), which every Newmark-family scheme integrates
    exactly (constant acceleration). Asserted to 1e-9 of the final drop (the code reaches 7e-12), the
    supports stay put, the block neither deforms nor drifts sideways, and its kinetic energy equals
    the work of the ground motion (input) to 1e-6 of it (the code reaches 4e-9)."""
    T = 0.5
    ds = masonrydam.run(floating_scene([{"name": "fall", "type": "dynamic", "dt": 0.01, "duration": T,
                                         "integrator": "hht", "ground_motion": {"y": {"values": [G, G], "dt": T}}}]))
    assert_finite(ds)
    assert ds.attrs["completed"] == "true"
    t = ds.time.values
    block = np.nonzero(ds.y.values >= 1.0)[0]
    base = np.nonzero(ds.y.values == 0.0)[0]  # the supported nodes
    uy = ds.displacement.sel(component="y").values
    drop = G * T**2 / 2
    np.testing.assert_allclose(uy[:, block], np.broadcast_to(-G * t[:, None] ** 2 / 2, uy[:, block].shape),
                               rtol=0, atol=1e-9 * drop)
    assert np.abs(ds.displacement.values[:, base]).max() == 0.0
    assert np.abs(ds.displacement.sel(component="x").values[:, block]).max() <= 1e-9 * drop
    assert float(ds.energy_kinetic[-1]) == pytest.approx(float(ds.energy_input[-1]), rel=1e-6)
    assert assert_energy_bounded(ds) <= 1e-6


# ------------------------------------------------------------------------------------------------
# 5. time step far above the joint rattle period
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("case", ["stick", "slide"])
def test_time_step_a_hundred_rattle_periods(case):
    """The sliding block of test_dynamics (2 x 0.5 m, 2000 kg, on 2 m2 of joint) with kn = ks = 4e12 Pa/m:
    its rattle period on the joint, 2 pi sqrt(m / (kn A)) = 0.099 ms, is 1/100 of dt = 10 ms. HHT
    (alpha = -0.1) damps the unresolved rattle, and the response to ground motion slow against it is
    right:
    - stick: a half-sine 0.1 g, 1 s long (below the sliding threshold mu g = 0.2 g): quasi-static, the
      joint's shear resultant is -m a_g(t) (d'Alembert) within 1 % of its peak at every step (the code
      reaches 1.3e-4), its normal resultant -m g, every point sticks;
    - slide: Newmark's (1965) rectangular pulse A = 0.4 g for 0.2 s: slip A (A - a_y) t0^2 / (2 a_y),
      a_y = mu g, within 0.5 % (the code reaches 0.12 %; the pulse's ramps span a whole 10 ms step).
    No NaN, and the energy stays bounded."""
    dt, kn, m = 0.01, 4e12, 2000.0 * 2.0 * 0.5
    assert dt / (2 * math.pi * math.sqrt(m / (kn * 2.0))) > 100
    if case == "stick":
        ds = masonrydam.run(sliding_block(shape="half_sine", amplitude=0.1 * G, pulse=1.0, dt=dt, duration=1.0, kn=kn))
        assert_finite(ds)
        dyn = dynamic_steps(ds)
        ag = ds.ground_acceleration.values[dyn][:, 0]
        w = ds.joint_weight.values
        shear = (ds.joint_traction_shear.values[dyn][..., 0] * w).sum(axis=1)
        normal = (ds.joint_traction_normal.values[dyn] * w).sum(axis=1)
        assert np.abs(shear + m * ag).max() <= 0.01 * m * 0.1 * G
        np.testing.assert_allclose(normal, -m * G, rtol=1e-6)
        assert (ds.joint_state.values == mc.STICK).all()
    else:
        A, mu, t0 = 0.4 * G, 0.2, 0.2
        ay = mu * G
        ds = masonrydam.run(sliding_block(dt=dt, duration=0.55, kn=kn))
        assert_finite(ds)
        slip = ds.joint_slip.isel(step=-1).values
        assert -slip.mean() == pytest.approx(A * (A - ay) * t0**2 / (2 * ay), rel=5e-3)
        assert np.ptp(slip) < 1e-3 * abs(slip.mean())
    assert_energy_bounded(ds)


# ------------------------------------------------------------------------------------------------
# 6. lift-off, flight and re-contact
# ------------------------------------------------------------------------------------------------

def ballistic_flight(A, t_ramp, t_hold):
    """Rigid block resting on the ground, ground acceleration a_g(t) going down linearly to -A over
    t_ramp, held t_hold, back to 0 over t_ramp (A > g). The block leaves the ground when a_g = -g
    (contact force m (g + a_g) = 0, at t1 = t_ramp g / A); relative to the ground it then accelerates
    at -g - a_g(t) (piecewise linear, integrated in closed form segment by segment), and after the
    pulse flies ballistically: peak height u_p + v_p^2 / (2 g) at t_p + v_p / g, landing at
    t_p + (v_p + sqrt(v_p^2 + 2 g u_p)) / g. Returns (peak height, landing time)."""
    knots = [0.0, t_ramp, t_ramp + t_hold, 2 * t_ramp + t_hold]
    level = [0.0, A, A, 0.0]

    def a_rel(t):
        return -G + np.interp(t, knots, level)

    t1 = t_ramp * G / A
    u = v = 0.0
    for ta, tb in zip([t1] + knots[1:-1], knots[1:]):
        a0, a1 = a_rel(ta), a_rel(tb)
        tau = tb - ta
        slope = (a1 - a0) / tau
        u += v * tau + a0 * tau**2 / 2 + slope * tau**3 / 6
        v += a0 * tau + slope * tau**2 / 2
    tp = knots[-1]
    return u + v * v / (2 * G), tp + (v + math.sqrt(v * v + 2 * G * u)) / G


@pytest.mark.slow
def test_lift_off_flight_and_recontact_match_the_ballistic_closed_form():
    """The sliding block of test_dynamics (kn = 1e10 Pa/m) after its gravity stage; the ground drops
    with a downward acceleration ramped to 1.5 g in 20 ms, held 80 ms and ramped back: every joint
    point opens (the block flies), lands and bounces. Against the rigid-block ballistic closed form
    (ballistic_flight; Newton's second law piecewise): the peak joint opening within 0.2 % (the code
    reaches 2e-4), the landing (opening back to zero) within 1 ms = dt (the code reaches 0.3 ms);
    during the flight every point is open and carries nothing; no rebound rises higher than the first
    flight (no energy created at re-contact; the missing restitution parameter makes the penalty
    contact bounce back to 99 % of it), and the energy stays bounded."""
    A, t_ramp, t_hold, dt, T = 1.5 * G, 0.02, 0.08, 1e-3, 0.6
    t = np.arange(int(round(T / dt)) + 1) * dt
    ag = -np.interp(t, [0, t_ramp, t_ramp + t_hold, 2 * t_ramp + t_hold], [0, A, A, 0], right=0.0)
    sc = sliding_block(duration=T, dt=dt, integrator="hht")
    sc["stages"][1]["ground_motion"] = {"y": {"values": ag.tolist(), "dt": dt}}
    ds = masonrydam.run(sc)
    assert_finite(ds)
    peak, landing = ballistic_flight(A, t_ramp, t_hold)
    dyn = dynamic_steps(ds)
    tf = ds.time.values[dyn]
    opening = ds.joint_opening.values[dyn].mean(axis=1)
    ip = int(np.argmax(opening))
    assert opening[ip] == pytest.approx(peak, rel=2e-3)
    k = ip + int(np.nonzero(opening[ip:] <= 0)[0][0])
    t_land = tf[k - 1] + (tf[k] - tf[k - 1]) * opening[k - 1] / (opening[k - 1] - opening[k])
    assert abs(t_land - landing) <= dt
    flying = (tf > 0.05) & (tf < landing - 0.05)
    states = ds.joint_state.values[dyn][flying]
    assert (states == mc.OPEN).all()
    assert (ds.joint_traction_normal.values[dyn][flying] == 0).all()
    assert opening[tf > t_land + 0.01].max() <= opening[ip] * (1 + ENERGY_SLACK)
    assert_energy_bounded(ds)


# ------------------------------------------------------------------------------------------------
# 7. brittle cascade through many joints
# ------------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_brittle_cascade_through_ten_joints_crosses_or_stops_quickly(tmp_path):
    """A stack of 11 blocks (1 x 0.25 m, E = 10 GPa, nu = 0, no weight) on 10 cohesive bed joints
    (ft = 0.1 MPa, c = 0.2 MPa, kn = 1e11 Pa/m), pulled at the top (displacement control) to twice the
    peak elongation: every joint carries the same force (statics of a bar), so all ten reach ft A at
    the same load step and break at once (a brittle cascade). Closed form: before the peak F = u / (L /
    (E A) + 10 / (kn A)) (springs in series) exactly; the force never exceeds ft A; after the peak
    the joints are cracked and transmit less. The run must not hang (60 s alarm; it takes < 1 s): it
    either crosses the snap (then every step is admissible: no point above ft, open points carry
    nothing, the same force through every joint, and the final force below half of ft A), or stops with a
    clear error naming the stage whose file keeps the steps up to at least 80 % of the peak. The code
    crosses it (step cuts take it to 95 % of ft A, then partial cracks in several joints carry the
    force down to 3 % of ft A)."""
    E, kn, ft, c, hb, W, n = 10e9, 1e11, 0.1e6, 0.2e6, 0.25, 1.0, 11
    Lc = n * hb
    blocks = [{"x0": 0, "y0": i * hb, "x1": W, "y1": (i + 1) * hb, "group": "units"} for i in range(n)]
    joint = {"normal_stiffness": kn, "shear_stiffness": kn / 2, "friction_angle": 30.0, "cohesion": c,
             "tensile_strength": ft}
    stiffness = 1.0 / (Lc / (E * W) + (n - 1) / (kn * W))
    u_peak = ft * W / stiffness
    stages = [{"name": "pull", "steps": 10,
               "loads": [{"type": "displacement", "set": "top", "components": ["y"], "value": [2 * u_peak]}]}]
    sc = block_scene(blocks=blocks, joint=joint, stages=stages, element_size=0.25, block_E=E, density=0.0,
                     supports=[{"set": "base", "components": ["x", "y"]}, {"set": "top", "components": ["x"]}])
    start = time.perf_counter()
    error, out = None, tmp_path / "cascade.nc"
    with time_limit(60):
        try:
            ds = masonrydam.run(sc, output=out)
        except (ConvergenceError, MechanismError) as exc:
            error = exc
    assert time.perf_counter() - start < 30
    if error is not None:  # a clear stop: named, with the converged steps up to the peak kept
        import xarray as xr

        assert "stage 'pull'" in str(error)
        ds = xr.load_dataset(out)
        assert ds.attrs["completed"] == "false"
    assert_finite(ds)
    F = top_force(ds, "y", Lc)
    u = ds.displacement.sel(component="y").where(np.isclose(ds.y, Lc)).mean("node").values
    assert F.max() <= ft * W * (1 + 1e-6)
    peak = int(np.argmax(F))
    np.testing.assert_allclose(F[:peak + 1], stiffness * u[:peak + 1], rtol=1e-6)
    assert F.max() >= (0.8 if error is not None else 0.9) * ft * W, "the run reaches the peak"
    if error is None:  # crossed: cracked after the peak, statically admissible everywhere
        assert F[-1] < 0.5 * ft * W and (ds.joint_state.values[-1] == mc.OPEN).any()
    jy = np.round(ds.joint_y.values, 9)
    w = ds.joint_weight.values
    per_joint = np.array([[(ds.joint_traction_normal.values[k][jy == y] * w[jy == y]).sum() for y in np.unique(jy)]
                          for k in range(ds.sizes["step"])])
    np.testing.assert_allclose(per_joint, np.broadcast_to(F[:, None], per_joint.shape), rtol=1e-6,
                               atol=1e-6 * ft * W)
    assert_coulomb_admissible(ds, math.tan(math.radians(30.0)), cohesion=c, tensile_strength=ft)


# ------------------------------------------------------------------------------------------------
# 8. friction with non-unique steps (Klarbring 1990)
# ------------------------------------------------------------------------------------------------

def klarbring_model(mu=1.0, kc=1e10, kn_spring=1e8, ks_spring=1e6, spring_line_deg=30.0):
    """Klarbring's (1990) two-degree-of-freedom example built from interface elements: a point A in
    frictional contact (Mohr-Coulomb, c = 0, no tension) with a fixed foundation along x, held by an
    elastic spring whose stiff axis is inclined at 120 deg (a linear joint along a line at 30 deg, its
    normal stiffness kn_spring across the line, ks_spring along it). Each interface element has A
    (node 0) as both of its top nodes, so both of its lumped points act on A and no pair of coincident
    fixed nodes forms a point-like part (which the mechanism check would call free); a fixed quad4
    completes the model (a model needs a continuum group). Returns the model and its supports (every
    DOF but those of A)."""
    from masonrydam.assembly.dofmap import DofMap
    from masonrydam.assembly.groups import ContinuumGroup, InterfaceGroup
    from masonrydam.assembly.model import Model
    from masonrydam.materials.elastic import elasticity_matrix

    g = math.radians(spring_line_deg)
    coords = np.array([[0, 0], [0, 0], [1, 0], [0, 0], [math.cos(g), math.sin(g)],
                       [5, 5], [6, 5], [6, 6], [5, 6]], dtype=float)
    quad = np.array([[5, 6, 7, 8]])
    anchor = ContinuumGroup("anchor", "quad4", quad, DofMap.node_dofs(quad, 2),
                            elasticity_matrix(1e9, 0.0, "plane_stress")[None], np.zeros(1, dtype=np.int64),
                            np.ones(1), np.zeros(1))
    contact = InterfaceGroup("contact", "interface_line2", np.array([[1, 2, 0, 0]]), coords, 2,
                             mc.joint_params(kc, kc, 0.0, math.degrees(math.atan(mu)), 0.0, 0.0), np.ones(1),
                             "mohr_coulomb", "lumped")
    spring = InterfaceGroup("spring", "interface_line2", np.array([[3, 4, 0, 0]]), coords, 2,
                            mc.joint_params(kn_spring, ks_spring, 1e300, 0.0, 1e300, 0.0), np.ones(1), "linear",
                            "lumped")
    model = Model(coords, [anchor], [contact, spring])
    supports = np.ones(model.n_dof, dtype=bool)
    supports[[0, 1]] = False
    return model, supports


def klarbring_solutions(model, F, mu):
    """Every state of one load step from the virgin state that satisfies the joint law, in closed form
    (the law is piecewise linear: one linear system per case). Stick: t = diag(ks, kn) d with
    |tau| <= -mu t_n, t_n <= 0; slip s = +-1: tau = s mu (-t_n), t_n = kn d_n < 0 with s ks d_t > -mu
    t_n (the elastic trial exceeds the cone, return along s); open: d_n > 0, t = 0. d = R u_A is the
    contact's relative displacement (R its frame); the spring adds K_s u_A. Returns {case: u_A}."""
    contact, spring = model.igroups
    Rc, wc = contact.frame[0, 0], contact.jw[0].sum()
    Rs, ws = spring.frame[0, 0], spring.jw[0].sum()
    kn, ks = contact.params_table[0, mc.P_KN], contact.params_table[0, mc.P_KS]
    Ks = ws * Rs.T @ np.diag([spring.params_table[0, mc.P_KS], spring.params_table[0, mc.P_KN]]) @ Rs
    out = {}
    for case, D in (("stick", np.diag([ks, kn])), ("slip+", np.array([[0.0, -mu * kn], [0.0, kn]])),
                    ("slip-", np.array([[0.0, mu * kn], [0.0, kn]])), ("open", np.zeros((2, 2)))):
        u = np.linalg.solve(Ks + wc * Rc.T @ D @ Rc, F)
        d_t, d_n = Rc @ u
        if case == "stick":
            ok = d_n <= 0 and abs(ks * d_t) <= mu * kn * -d_n
        elif case == "open":
            ok = d_n > 0
        else:
            s = 1.0 if case == "slip+" else -1.0
            ok = d_n < 0 and s * ks * d_t > mu * kn * -d_n
        if ok:
            out[case] = u
    return out


@pytest.mark.parametrize("fx_over_mu_p, n_solutions", [(0.5, 1), (0.8, 3), (1.2, 1)])
def test_klarbring_non_unique_friction_step_finds_an_admissible_solution(fx_over_mu_p, n_solutions):
    """Klarbring (1990): a point in frictional contact held by a spring that couples tangential
    and normal motion (coupling b, tangential stiffness a) has several solutions of one load step when
    mu |b| > a (here a / |b| = 0.60 < mu = 1; tan 30 deg for a spring with no stiffness along its line):
    under a load pressing with P and pushing with F_x in [a P / |b|, mu P), sticking, slipping and
    lifting off all satisfy the law (penalty contact, kn = 100 x the spring). The closed-form
    enumeration (klarbring_solutions) finds 3 solutions at F_x = 0.8 mu P and one (stick, resp. open)
    at 0.5 and 1.2 mu P. The static solver, one step from the virgin state, must return one of them
    (to 1e-9), with an admissible joint state (|tau| <= mu (-t_n), no tension, an open point carrying
    nothing) and the load balanced by the contact and spring forces (statics)."""
    from masonrydam.solvers.static.stepping import SolverSettings, StaticSolver, StaticStage

    mu, P = 1.0, 1e4
    model, supports = klarbring_model(mu)
    F = np.array([fx_over_mu_p * mu * P, -P])
    closed = klarbring_solutions(model, F, mu)
    assert len(closed) == n_solutions, sorted(closed)
    f = np.zeros(model.n_dof)
    f[:2] = F
    result = {}

    def on_step(si, stage, lam, u, f_int, f_ext):
        result.update(u=u.copy(), f_int=f_int.copy(), t=model.igroups[0].traction[0].copy(),
                      code=model.igroups[0].state_codes(trial=False)[0].copy())

    StaticSolver(model, SolverSettings(), on_step=on_step).run(
        [StaticStage("push", 1, f, np.zeros(model.n_dof, dtype=bool), np.zeros(model.n_dof), supports)])
    uA = result["u"][:2]
    assert np.isfinite(result["u"]).all()
    match = [k for k, u in closed.items() if np.allclose(uA, u, rtol=1e-9, atol=1e-9 * np.abs(u).max())]
    assert match, f"FE {uA} is none of the closed-form solutions {closed}"
    tau, tn = result["t"][:, 0], result["t"][:, 1]
    assert (tn <= 0).all() and (np.abs(tau) <= mu * -tn * (1 + 1e-9) + 1e-9 * P).all()
    assert (result["t"][result["code"] == mc.OPEN] == 0).all()
    np.testing.assert_allclose(result["f_int"][:2], F, rtol=1e-6, atol=1e-6 * P)


# ------------------------------------------------------------------------------------------------
# 9. static near-collapse under sideways gravity
# ------------------------------------------------------------------------------------------------

#: (block width 2b, height 2h, friction angle, integration) and the closed-form threshold of the
#: seismic coefficient k: sliding at tan(phi), uplift at b/h (rigid block, statics), or with 2-point
#: Gauss integration at (b - d_g)/h, d_g = (1 - 1/sqrt(3)) / 2 x element length (the outermost
#: integration point is the last place the joint can push: the discrete model's uplift threshold)
NEAR_COLLAPSE = {
    "slide": (2.0, 0.5, math.degrees(math.atan(0.25)), "lumped", 0.25, "sliding"),
    "rock": (0.5, 2.0, 45.0, "lumped", 0.25, "rocking"),
    "rock_gauss": (0.5, 2.0, 45.0, "gauss", (0.25 - (1 - 1 / math.sqrt(3)) / 2 * 0.25) / 1.0, "rocking"),
}


def near_collapse_scene(case, k):
    width, height, phi, integration, _, _ = NEAR_COLLAPSE[case]
    blocks = [{"x0": -0.25, "y0": -0.25, "x1": width + 0.25, "y1": 0.0, "group": "base"},
              {"x0": 0.0, "y0": 0.0, "x1": width, "y1": height, "group": "block"}]
    joint = {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": phi, "integration": integration}
    stages = [{"name": "tilt", "loads": [{"type": "self_weight"}]}]
    return block_scene(blocks=blocks, joint=joint, gravity=(k * G, -G), stages=stages,
                       element_size=0.25 if integration == "gauss" else 0.125)


@pytest.mark.parametrize("case, fraction", [(c, f) for c in NEAR_COLLAPSE for f in (0.5, 0.9, 0.98)])
def test_near_collapse_static_converges_below_the_threshold(case, fraction):
    """A block on a cohesionless no-tension joint under its weight and a horizontal body force k W
    (model.gravity = [k g, -g]): for every k below the closed-form threshold (tan(phi) for the wide
    block, b/h = 0.25 for the tall one; with Gauss integration the discrete b/h of NEAR_COLLAPSE) the
    static stage converges, and the joint's resultants satisfy statics: normal force -W, shear +k W
    (slip and shear are top minus bottom; both to 1e-6), the normal force's line of action at
    x_c + k h_c (moment equilibrium about the joint: the resultant moves from the centre line x_c by k
    times the centroid height h_c; to 1e-6 of the width), and every point is Coulomb-admissible."""
    width, height, phi, _, threshold, _ = NEAR_COLLAPSE[case]
    k = fraction * threshold
    ds = masonrydam.run(near_collapse_scene(case, k))
    assert_finite(ds)
    W = 2000.0 * G * width * height
    normal, shear = joint_forces(ds)
    assert normal == pytest.approx(-W, rel=1e-6)
    assert shear[0] == pytest.approx(k * W, rel=1e-6)
    x = ds.joint_x.values
    moment_arm = float((ds.joint_traction_normal.values[-1] * ds.joint_weight.values * x).sum()) / normal
    assert moment_arm == pytest.approx(width / 2 + k * height / 2, abs=1e-6 * width)
    assert_coulomb_admissible(ds, math.tan(math.radians(phi)))


@pytest.mark.xfail(strict=True, raises=ConvergenceError, reason=(
    "static Newton (joint space and general path alike, with or without line search, 200 iterations) cycles "
    "with period 3 between the toe point sticking and sliding ([open, slip, slip, stick] <-> [open, slip, slip, "
    "slip]) and gives up at 0.96 of the threshold; step cuts cannot help under proportional loading (the "
    "cohesionless problem is the same at every load factor). The equilibrium exists: see the docstring"))
def test_near_collapse_coincident_thresholds_stiff_joint_converges():
    """The tall block of NEAR_COLLAPSE with both thresholds equal (b/h = tan(phi) = 0.25) on a stiff joint
    (kn = ks = 1e13 Pa/m, kn h / E = 125), meshed with triangles (tri3, 0.25 m), at k = 0.24 = 0.96 of
    the threshold. Rigid-block statics admit equilibrium (resultant 0.01 m inside the toe, friction
    demand 0.24 < 0.25), and so does the discrete model: the same loads applied as the weight first and
    the sideways force second converge in one step each, and that state satisfies the equations of
    the one-step problem from the virgin state (proportional loading) to 1e-10 of the load (the test
    checks both). Expected: the proportional run converges too, with the statics of
    test_near_collapse_static_converges_below_the_threshold."""
    from masonrydam.scene import build_mesh, build_model, build_stages
    from masonrydam.scene.scene import Scene
    from masonrydam.solvers.static.stepping import SolverSettings, StaticSolver, StaticStage

    k, tan_phi = 0.24, 0.25
    sc = near_collapse_scene("rock", k)
    sc["joints"]["joints"].update(normal_stiffness=1e13, shear_stiffness=1e13,
                                  friction_angle=math.degrees(math.atan(tan_phi)))
    sc["mesh"]["parameters"].update(element="tri", element_size=0.25)

    def fresh():
        scene = Scene(sc)
        mesh = build_mesh(scene.normalized, ".")
        model = build_model(scene.normalized, mesh)
        return model, build_stages(scene.normalized, mesh, model)[0].supports

    model, supports = fresh()
    weight, side = L.self_weight(model, [0.0, -G]), L.self_weight(model, [k * G, 0.0])
    none = np.zeros(model.n_dof, dtype=bool)
    zero = np.zeros(model.n_dof)
    u = StaticSolver(model, SolverSettings()).run([StaticStage("weight", 1, weight, none, zero, supports),
                                                   StaticStage("side", 1, side, none, zero, supports)])
    virgin, _ = fresh()
    virgin.set_constraints(supports)
    f_int, _ = virgin.evaluate(u, want_tangent=False)
    free = virgin.dofmap.free
    assert np.linalg.norm((weight + side - f_int)[free]) <= 1e-10 * np.linalg.norm((weight + side)[free])
    ds = masonrydam.run(sc)  # proportional loading: raises ConvergenceError today
    W = 2000.0 * G * 0.5 * 2.0
    normal, shear = joint_forces(ds)
    assert normal == pytest.approx(-W, rel=1e-6) and shear[0] == pytest.approx(k * W, rel=1e-6)
    assert_coulomb_admissible(ds, tan_phi)


@pytest.mark.parametrize("case", list(NEAR_COLLAPSE))
def test_near_collapse_beyond_the_threshold_names_mechanism_and_part(case):
    """Just beyond the threshold (1.02 x, proportional loading, so no step cut can help) there is no
    equilibrium: the run stops with a ConvergenceError or MechanismError that names the stage, the
    mechanism the closed form predicts (sliding, or rocking about the toe) and the part: the joint set
    and the element groups 'base' and 'block'. For the Gauss-integrated joint the reported failure is
    reproduced: k = 0.20 already fails although b/h = 0.25, because the discrete threshold is
    (b - d_g) / h = 0.197 (NEAR_COLLAPSE), and it fails as rocking."""
    threshold, mechanism = NEAR_COLLAPSE[case][4], NEAR_COLLAPSE[case][5]
    ks = [1.02 * threshold] + ([0.20] if case == "rock_gauss" else [])
    for k in ks:
        with pytest.raises((ConvergenceError, MechanismError)) as exc:
            masonrydam.run(near_collapse_scene(case, k))
        msg = str(exc.value)
        assert "stage 'tilt'" in msg
        assert f"{mechanism}:" in msg, msg
        assert "joint set 'joints' between element groups 'base' and 'block'" in msg, msg


# ------------------------------------------------------------------------------------------------
# 10. 3D: rocking and sliding on 8-node interfaces under two horizontal components
# ------------------------------------------------------------------------------------------------

def block_3d_scene(block, ground_motion, dt, duration=None, kn=1e10, phi=None, E=30e9, element_size=0.25,
                   output=None):
    """A box 'block' on a fixed box 'base' joined by 8-node (4 + 4) quad4 interfaces, self-weight,
    then a dynamic stage (HHT) under ``ground_motion``."""
    x1, y1, z1 = block
    stage = {"name": "quake", "type": "dynamic", "dt": dt, "integrator": "hht", "ground_motion": ground_motion}
    if duration is not None:
        stage["duration"] = duration
    if output:
        stage["output"] = output
    pad = 0.125
    return {"model": {"name": "block3d", "dimension": 3},
            "mesh": {"generator": "blocks_3d", "parameters": {"blocks": [
                {"x0": -pad, "y0": -pad, "z0": -0.25, "x1": x1 + pad, "y1": y1 + pad, "z1": 0.0, "group": "base"},
                {"x0": 0, "y0": 0, "z0": 0, "x1": x1, "y1": y1, "z1": z1, "group": "block"}],
                "element_size": element_size}},
            "materials": {g: {"youngs_modulus": E, "poisson_ratio": 0.2, "density": 2000} for g in ("base", "block")},
            "joints": {"joints": {"normal_stiffness": kn, "shear_stiffness": kn, "friction_angle": phi}},
            "supports": [{"set": "base_nodes"}],
            "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]}, stage]}


def test_3d_mesh_uses_the_8_node_interface():
    """The 3D cases below run on the 8-node surface interface of Tzamtzis & Asteris (4 + 4 nodes, quad4 faces, nodal
    integration), as built by blocks_3d with hexahedra."""
    from masonrydam.scene import build_mesh
    from masonrydam.scene.scene import Scene

    sc = Scene(block_3d_scene((1.0, 1.0, 0.5), {"x": {"values": [0.0, 0.0], "dt": 0.01}}, 0.01, phi=30.0))
    mesh = build_mesh(sc.normalized, ".")
    assert [(j.type, j.cells.shape[1]) for j in mesh.joints] == [("interface_quad4", 8)]
    assert sc.normalized["joints"]["joints"]["integration"] == "lumped"


@pytest.mark.slow
def test_3d_sliding_under_two_horizontal_components_follows_the_input():
    """Newmark (1965) in 3D: a 1 x 1 x 0.5 m block on a cohesionless joint (mu = 0.2) under rectangular
    pulses in x and y together, |a_g| = 0.4 g at 30 deg from x, 0.2 s. Isotropic Coulomb friction (Tzamtzis &
    Asteris sec. 3.4; the return is radial) makes the rigid block slide along -a_g: the slip vector of every
    point points at 210 deg within 0.1 deg and its length is A (A - a_y) t0^2 / (2 a_y) within 0.5 % (the
    code reaches 5e-5); the block sticks again; no point opens (no rocking: b/h = 1 > mu)."""
    A, theta, mu, t0 = 0.4 * G, math.radians(30.0), 0.2, 0.2
    ay = mu * G
    gm = {c: {"pulse": {"shape": "rectangular", "amplitude": A * f(theta), "duration": t0}}
          for c, f in (("x", math.cos), ("y", math.sin))}
    ds = masonrydam.run(block_3d_scene((1.0, 1.0, 0.5), gm, 2e-3, duration=A * t0 / ay + 0.1,
                                       phi=math.degrees(math.atan(mu))))
    assert_finite(ds)
    slip = np.einsum("pk,pkd->pd", ds.joint_slip.isel(step=-1).values, ds.joint_shear_axis.values)
    angle = np.degrees(np.arctan2(slip[:, 1], slip[:, 0])) % 360
    assert np.abs(angle - 210.0).max() < 0.1
    assert np.abs(slip[:, 2]).max() < 1e-9
    assert np.linalg.norm(slip[:, :2], axis=1) == pytest.approx(
        np.full(len(slip), A * (A - ay) * t0**2 / (2 * ay)), rel=5e-3)
    assert (ds.joint_state.isel(step=-1).values == mc.STICK).all()
    assert (ds.joint_state.values != mc.OPEN).all()
    assert_energy_bounded(ds)


@pytest.mark.parametrize("factor, rocks", [(0.98, False), (1.02, True)])
@pytest.mark.slow
@pytest.mark.reference
def test_3d_rocking_onset_under_two_horizontal_components(factor, rocks):
    """Housner's (1963) static rocking criterion for a box with a square base of half-width b and
    centroid height h under a horizontal acceleration k g at angle theta: the resultant of weight and
    inertia leaves the base (whose edges are |x|, |y| = b) when k h max(|cos theta|, |sin theta|) = b.
    A 0.5 x 0.5 x 1.5 m block (b/h = 1/3, mu = 1, kn = 1e12) at theta = 30 deg: ground acceleration
    ramped over 0.5 s (quasi-static) to 0.98 and 1.02 of k_crit = 0.385 and held 0.5 s. Below: uplift
    at the elastic scale (< 1e-4 m, the code reaches 4.7e-6 at the far corner); above: the block tips
    (uplift > 1e-3 m). Neither slides (plastic slip < 1e-5 m); energy bounded."""
    th, bw, hh, dt = math.radians(30.0), 0.5, 1.5, 2e-3
    k_crit = (bw / hh) / max(abs(math.cos(th)), abs(math.sin(th)))
    t = np.arange(int(round(1.0 / dt)) + 1) * dt
    a = factor * k_crit * G * np.minimum(t / 0.5, 1.0)
    gm = {"x": {"values": (a * math.cos(th)).tolist(), "dt": dt},
          "y": {"values": (a * math.sin(th)).tolist(), "dt": dt}}
    ds = masonrydam.run(block_3d_scene((bw, bw, hh), gm, dt, kn=1e12, phi=45.0, E=200e9, element_size=0.125,
                                       output={"stride": 10}))
    assert_finite(ds)
    uplift = ds.joint_opening.values.max()
    if rocks:
        assert uplift > 1e-3
        # the heel x = b lifts: the block tips about the edge x = 0, where the inertia force (along -a_g) points
        heel = ds.joint_x.values[np.argmax(ds.joint_opening.values[-1])]
        assert heel == pytest.approx(bw)
    else:
        assert uplift < 1e-4
    assert np.linalg.norm(ds.joint_plastic_slip.values, axis=-1).max() < 1e-5
    assert_energy_bounded(ds)


# ------------------------------------------------------------------------------------------------
# more hard classes: two-way stick-slip, chatter at a vanishing contact force
# ------------------------------------------------------------------------------------------------

def newmark_two_way(A, omega, a_y, t_end):
    """Newmark's (1965) rigid block on a cohesionless joint, ground a_g = A sin(omega t), two-way
    sliding: the slip s (block minus ground) obeys s'' = -a_g - sgn(s') a_y while sliding; the block
    sticks while |a_g| <= a_y and starts to slide against a_g when |a_g| exceeds a_y. Each slip phase
    is integrated in closed form (elementary integrals of the sine); its start and end (s' = 0) are
    found by root finding. Returns s(t) as a function."""
    def ag(t):
        return A * math.sin(omega * t)

    grid = np.linspace(0.0, t_end, 400001)
    phases, t, s = [], 0.0, 0.0
    while t < t_end:
        beyond = grid[(grid >= t) & (np.abs(A * np.sin(omega * grid)) > a_y)]
        if not len(beyond):
            break
        t1 = beyond[0]
        if t1 > t and abs(ag(t)) < a_y:
            t1 = scipy.optimize.brentq(lambda x: abs(ag(x)) - a_y, max(t, t1 - grid[1]), t1)
        sig = -math.copysign(1.0, ag(beyond[0]))

        def vel(x, t1=t1, sig=sig):
            return A / omega * (np.cos(omega * x) - math.cos(omega * t1)) - sig * a_y * (x - t1)

        xs = grid[grid > t1 + 1e-6]
        stop = np.nonzero(sig * vel(xs) <= 0)[0]
        t2 = t_end if not len(stop) else scipy.optimize.brentq(vel, xs[stop[0] - 1] if stop[0] else t1 + 1e-6,
                                                               xs[stop[0]])
        phases.append((t1, t2, sig, s))
        s += disp_in_phase(A, omega, a_y, t1, sig, t2)
        t = t2

    def s_of_t(x):
        for t1, t2, sig, s0 in phases:
            if x < t1:
                return s0  # sticking before this phase
            if x <= t2:
                return s0 + disp_in_phase(A, omega, a_y, t1, sig, x)
        return s  # sticking after the last phase

    return s_of_t, phases


def disp_in_phase(A, omega, a_y, t1, sig, x):
    """Slip since t1 of a phase sliding in direction sig (closed form)."""
    return (A / omega * ((math.sin(omega * x) - math.sin(omega * t1)) / omega - math.cos(omega * t1) * (x - t1))
            - sig * a_y * (x - t1) ** 2 / 2)


@pytest.mark.parametrize("dt", [
    1e-3,
    pytest.param(2e-3, marks=pytest.mark.xfail(
        strict=True, raises=AssertionError,
        reason="dt = 2 ms: where the block should stop and stick (|a_g| = 0.16 g < mu g at t = 0.287 s) the "
               "Newmark velocity overshoots through zero (-3.8 -> +3.2 mm/s in one step) and the block slides "
               "back at 5-6 mm/s through the whole 11 ms stick window; every later cycle inherits it: slip "
               "history off by 6.7 % of its amplitude (0.09 % at dt = 1 ms)")),
])
@pytest.mark.slow
def test_two_way_stick_slip_under_harmonic_ground_motion(dt):
    """Stick-slip with reversals: the sliding block of test_dynamics (mu = 0.2) under a_g = 0.35 g
    sin(2 pi t / 0.5 s) for three cycles slides 6 times, alternately against the ground's
    acceleration, and sticks between (Newmark's two-way rigid block, newmark_two_way). The slip
    history at every step within 1 % of its amplitude (20 mm), and the same number of reversals."""
    A, T, mu = 0.35 * G, 0.5, 0.2
    omega, duration = 2 * math.pi / T, 3 * T
    s_ref, phases = newmark_two_way(A, omega, mu * G, duration)
    assert len(phases) == 6 and [p[2] for p in phases] == [-1.0, 1.0] * 3
    t = np.arange(int(round(duration / dt)) + 1) * dt
    sc = sliding_block(dt=dt, duration=duration, mu=mu)
    sc["stages"][1]["ground_motion"] = {"x": {"values": (A * np.sin(omega * t)).tolist(), "dt": dt}}
    ds = masonrydam.run(sc)
    assert_finite(ds)
    assert_energy_bounded(ds)
    dyn = dynamic_steps(ds)
    slip = ds.joint_slip.values[dyn].mean(axis=(1, 2))
    ref = np.array([s_ref(x) for x in ds.time.values[dyn]])
    amplitude = np.abs(ref).max()
    steps = np.diff(slip)
    moving = steps[np.abs(steps) > 1e-6 * amplitude]
    assert int((np.diff(np.sign(moving)) != 0).sum()) == len(phases) - 1
    assert np.abs(slip - ref).max() <= 0.01 * amplitude


@pytest.mark.slow
def test_chatter_free_contact_at_a_vanishing_normal_force():
    """Chatter: the sliding block of test_dynamics under a vertical harmonic ground acceleration of
    0.99 g (period 0.2 s, ramped in over 0.2 s): the contact force m (g + a_g) (d'Alembert, rigid
    block: the joint's rattle period of 2 ms is far below the 0.2 s excitation) falls to 1 % of the
    weight every cycle but never reaches zero. The joint must neither open nor rattle: no point opens
    at any step, the normal resultant follows -m (g + a_g(t)) within 1e-3 m g (the code reaches 1.1e-4),
    and the energy stays bounded."""
    A, T, dt, duration, m = 0.99 * G, 0.2, 1e-3, 1.0, 2000.0
    t = np.arange(int(round(duration / dt)) + 1) * dt
    ag = A * np.minimum(t / 0.2, 1.0) * np.sin(2 * math.pi * t / T)
    sc = sliding_block(dt=dt, duration=duration)
    sc["stages"][1]["ground_motion"] = {"y": {"values": ag.tolist(), "dt": dt}}
    ds = masonrydam.run(sc)
    assert_finite(ds)
    dyn = dynamic_steps(ds)
    assert (ds.joint_state.values != mc.OPEN).all()
    normal = (ds.joint_traction_normal.values[dyn] * ds.joint_weight.values).sum(axis=1)
    a_y = ds.ground_acceleration.values[dyn][:, 1]
    assert np.abs(normal + m * (G + a_y)).max() <= 1e-3 * m * G
    assert (-normal).min() < 0.02 * m * G, "the contact force nearly vanishes"
    assert_energy_bounded(ds)

