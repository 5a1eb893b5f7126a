"""The compressible (acoustic) reservoir with the explicit scheme (``integrator = "central_difference"``):
the water stepped with the dam's central difference (masonrydam/solvers/dynamic/fluid.py, ExplicitAcoustic),
its stable step and its energy.

References:
- the coupled pressure formulation G p'' + L p' + H p = -rho (Q^T u'' + B a_g), water force Q p (Zienkiewicz &
  Bettess 1978, IJNME 13:1-16; Chopra & Chakrabarti 1981, EESD 9:363-383), here with central difference in
  velocity form (Hughes 2000, *The Finite Element Method*, sec. 9.1.2; Belytschko, Liu & Moran 2000, Box 6.1)
  applied to the coupled system, whose mass matrix is block lower triangular: the partitioned explicit scheme of
  Belytschko & Mullen (1978, IJNME 12:1575-1586) and Felippa & Park (1980, CMAME 24:61-111);
- its stable step: omega_max h <= 2 (Hughes 2000, sec. 9.1.2) with omega_max the highest frequency of the coupled
  undamped dam-water system (masonrydam/solvers/dynamic/stability.py, coupled_highest_frequency);
- Westergaard (1933), Trans. ASCE 98:418-433: on a rigid vertical face under a slowly varying ground acceleration
  a, the pressure tends to the incompressible series: base
  0.7425 rho a H, resultant 0.5428 rho a H^2;
- the discrete energy balance of central difference (Hughes 2000, sec. 9.1.4), with the water's work on the dam
  as its ``hydrodynamic`` term, as in the implicit stages (masonrydam/solvers/dynamic/energy.py).

The scenes are those of tests/effects/test_acoustic_dynamic.py (``rigid_dam``: a block fixed at its base with the
reservoir on its face x = 0), made flexible where the dam and the water should interact.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import masonrydam
import masonrydam.solvers.dynamic.solver as solver_module
from masonrydam.errors import NumericalError, SceneError
from test_acoustic_dynamic import RHO_W, rigid_dam

H = 10.0  # m, the dam's height and the water's depth


def flexible_dam(integrator="central_difference", dt="auto", youngs_modulus=2e10, duration=0.3, bottom_reflection=1.0,
                 output_dt=0.002):
    """A 10 m square dam on 1 m elements (2000 kg/m3, E = ``youngs_modulus``), water 10 m deep (c = 1440 m/s, 30 m
    long, Sommerfeld far end, ``bottom_reflection``), under one sine cycle of 3 m/s2 lasting 0.1 s along x."""
    dt_g = 0.002
    t = np.arange(0.0, duration + 1e-12, dt_g)
    acc = np.where(t < 0.1, np.sin(2 * np.pi * t / 0.1), 0.0) * 3.0
    s = rigid_dam(sound_speed=1440.0, height=H, level=H, size=1.0, ground={"values": acc.tolist(), "dt": dt_g}, dt=dt,
                  integrator=integrator, extra={"bottom_reflection": bottom_reflection})
    s["materials"]["block"]["youngs_modulus"] = youngs_modulus
    quake = s["stages"][1]
    quake["duration"] = duration
    if integrator == "central_difference":
        quake["mass"] = "lumped"
        if output_dt is not None:
            quake["output"]["dt"] = output_dt
    return s


def histories(ds):
    """Time from the quake's start (s), the heel pressure (Pa), the crest displacement along x (m), the
    dynamic part of ``ds``."""
    d = ds.where(ds.stage == 1, drop=True)
    heel = int(np.argmin((ds.face_z if "face_z" in ds else ds.face_y).values))  # the lowest face node
    return (d.time.values - d.time.values[0], d.face_pressure.values[:, heel],
            d.displacement.sel(component="x").values.mean(axis=1), d)


def largest_difference(t, y, t_ref, y_ref):
    """max |y - y_ref| over the history ``t`` (y_ref interpolated), relative to the peak of y_ref."""
    return float(np.abs(y - np.interp(t, t_ref, y_ref)).max() / np.abs(y_ref).max())


def per_stage(ds):
    return json.loads(ds.attrs["dynamic_per_stage"])[0]


@pytest.fixture(scope="module")
def explicit_and_implicit():
    return masonrydam.run(flexible_dam()), masonrydam.run(flexible_dam("newmark_average", 1e-4))


def test_explicit_water_agrees_with_the_implicit_path(explicit_and_implicit):
    """The same dam and water, explicit (dt = "auto": 0.25 ms) against the implicit trapezoidal rule at 0.1 ms
    (its pressures condensed into the step, consistent G): the heel pressure history within 3 % of its peak
    and the crest displacement within 0.6 % (measured 2.0 and 0.35 %).

    Tolerances from a study of this scene (run once): the difference is the explicit path's lumped capacity G
    (docs/dam_reservoir_foundation.md, "The water in the explicit step"), not the coupling or the time step:
    explicit steps with the consistent G and L factorized gave 0.14 % (pressure) and 0.005 % (crest); the
    lumped ones 2.2 % and 0.4 % at 0.25 ms and at 0.05 ms alike; the implicit path itself moves 0.4 % between
    0.1 and 0.025 ms. Against the mesh-converged answer (0.25 m elements) the lumped and the consistent water
    are 3.1 and 2.1 % off in pressure, 1.9 and 2.0 % in the crest displacement."""
    ex, im = explicit_and_implicit
    stage = per_stage(ex)
    assert stage["integrator"] == "central_difference" and stage["dt"] == pytest.approx(2.5e-4)
    te, pe, ue, _ = histories(ex)
    ti, pi, ui, _ = histories(im)
    assert np.abs(pi).max() > 2e4 and np.abs(ui).max() > 1e-4  # the water pushes and the dam moves
    assert largest_difference(te, pe, ti, pi) < 0.03
    assert largest_difference(te, ue, ti, ui) < 0.006
    assert "acoustic elements" in ex.attrs["simulated_effects"]


def test_explicit_energy_balance_closes_with_the_water(explicit_and_implicit):
    """The energy balance of the explicit stage with the water closes to round-off (1e-12 of its largest term;
    measured 7e-15, the implicit path's 1.7e-14): the water's work on the dam (``hydrodynamic``, the
    trapezoidal work of Q p on the wetted DOFs) is counted as the implicit path counts it, and it is a large
    term here (its peak 23 % of the ground's input) that agrees with the implicit path's to 1 % (measured
    0.4 %)."""
    ex, im = explicit_and_implicit
    _, _, _, de = histories(ex)
    _, _, _, di = histories(im)
    scale = max(float(np.abs(de[k]).max()) for k in ("energy_input", "energy_kinetic", "energy_strain"))
    assert float(np.abs(de.energy_error).max()) < 1e-12 * scale
    hydro_e, hydro_i = float(np.abs(de.energy_hydrodynamic).max()), float(np.abs(di.energy_hydrodynamic).max())
    assert hydro_e > 0.1 * float(np.abs(de.energy_input).max())
    assert hydro_e == pytest.approx(hydro_i, rel=0.01)


@pytest.mark.reference
def test_slow_ground_acceleration_on_a_stiff_dam_gives_westergaard():
    """A ground acceleration rising smoothly to 2 m/s2 over 0.2 s (against H / c = 7 ms and the water's first
    period of 28 ms) on a stiff dam (E = 1e11 Pa), explicit: the face pressure tends to Westergaard's series,
    base 0.7425 rho a H and resultant 0.5428 rho a H^2 (2 %, the tolerance of the
    implicit path's test in test_acoustic_dynamic.py; measured 0.1 and 0.7 %), and along the face the series
    at each node's depth (0.02 rho a H)."""
    dtg, ramp = 0.005, 0.2
    t = np.arange(0.0, ramp + 0.05 + 1e-12, dtg)
    acc = np.where(t < ramp, 0.5 * (1 - np.cos(np.pi * t / ramp)), 1.0) * 2.0
    s = rigid_dam(sound_speed=1440.0, height=H, level=H, size=1.0, ground={"values": acc.tolist(), "dt": dtg},
                  dt="auto", integrator="central_difference")
    s["materials"]["block"]["youngs_modulus"] = 1e11
    s["stages"][1].update(mass="lumped")
    s["stages"][1]["output"]["dt"] = dtg
    ds = masonrydam.run(s)
    last = ds.isel(step=-1)
    a = float(last.ground_acceleration.sel(component="x"))
    assert a == pytest.approx(2.0)
    # accelerating +x pulls the face (outward normal -x) away from the water: suction, force toward -x
    assert -float(last.hydrodynamic_force.values[0]) / (RHO_W * a * H**2) == pytest.approx(0.5428, rel=0.02)
    p = last.face_pressure.values
    assert -float(p[int(np.argmin(ds.face_y.values))]) / (RHO_W * a * H) == pytest.approx(0.7425, rel=0.02)
    z = H - ds.face_y.values
    m = np.arange(1, 2001, 2)
    exact = 8.0 / np.pi**2 * np.sum(np.sin(m[None, :] * np.pi * z[:, None] / (2 * H)) / m[None, :] ** 2, axis=1)
    np.testing.assert_allclose(-p / (RHO_W * a * H), exact, atol=0.02)


# ----------------------------------------------------------------------------------------------
# the stable step of the dam and its water together
# ----------------------------------------------------------------------------------------------

SOFT = 2e9  # Pa: a soft dam, whose water sets the stable step


@pytest.fixture(scope="module")
def soft_dam_auto():
    return masonrydam.run(flexible_dam(youngs_modulus=SOFT, duration=0.2, bottom_reflection=0.0))


def test_auto_step_is_set_by_the_water_and_stays_stable(soft_dam_auto):
    """dt = "auto" on a soft dam: the step is the largest below 0.9 x the critical step of the coupled system, the
    run summary says that the water set it, and the response after the pulse does not grow (central difference
    is stable for omega_max h <= 2, Hughes 2000 sec. 9.1.2; the fully absorbing bottom, alpha = 0, radiates).

    The coupled highest frequency (545 Hz) lies above both the dam's alone (325 Hz) and the water's alone on a
    rigid dam (459 Hz): the compressibility of the first layer of water acts on the wetted face as a spring."""
    stage = per_stage(soft_dam_auto)
    dt, dtc = stage["dt"], stage["dt_critical"]
    n = round(0.002 / dt)
    assert dt == pytest.approx(0.002 / n, rel=1e-12) and dt <= 0.9 * dtc < 0.002 / (n - 1)
    reason = stage["dt_reason"]
    assert "dt = auto" in reason and "the water's elements (their Courant limit) set it" in reason
    hz = [float(x.split(" Hz")[0].split()[-1]) for x in reason.split("frequency ")[1:2] + reason.split("alone")[1:]]
    coupled, dam, water = hz
    assert coupled > water > dam  # what the summary says: the water, lifted by the coupling
    assert 2 * np.pi * coupled * dtc == pytest.approx(2.0, rel=2e-4)  # (the summary gives 4 digits)
    _, p, u, d = histories(soft_dam_auto)
    assert np.isfinite(p).all()
    after = d.time.values - d.time.values[0] > 0.15
    assert np.abs(p[after]).max() < np.abs(p).max()
    scale = max(float(np.abs(d[k]).max()) for k in ("energy_input", "energy_kinetic", "energy_strain"))
    assert float(np.abs(d.energy_error).max()) < 1e-12 * scale


def test_dt_above_the_coupled_step_is_refused(soft_dam_auto):
    """A fixed dt below 0.9 x the dam's own critical step but above 0.9 x the coupled one is refused with one line
    that names ``stages[1].dt`` and the bound, and says that the water set it."""
    stage = per_stage(soft_dam_auto)
    dtc = stage["dt_critical"]
    dam_hz = float(stage["dt_reason"].split("the dam alone ")[1].split(" Hz")[0])
    dt = 0.8e-3
    assert 0.9 * dtc < dt < 0.9 * 2.0 / (2 * np.pi * dam_hz)  # the dam alone would take it
    with pytest.raises(SceneError, match=r"dt <= " + f"{0.9 * dtc:.4g}".replace(".", r"\.")) as err:
        masonrydam.run(flexible_dam(dt=dt, youngs_modulus=SOFT, duration=0.01, bottom_reflection=0.0, output_dt=None))
    assert err.value.key == "stages[1].dt"
    assert "water" in str(err.value) and "\n" not in str(err.value)


def test_coupled_critical_step_is_the_schemes_limit(soft_dam_auto, monkeypatch):
    """The computed bound is the staggered scheme's true limit (measured, safety factor lifted): at 0.99 dt_crit
    the response stays that of the stable run, at 1.01 dt_crit it grows without bound (the amplification of the
    top mode is |lambda| = 1.33 a step at Omega = 2.02; Hughes 2000, sec. 9.1.2), with the radiation of the
    fully absorbing bottom in the water (taken at the end-of-step rate, it leaves the bound alone)."""
    dtc = per_stage(soft_dam_auto)["dt_critical"]
    check = solver_module.check_time_step

    def lifted(equations, settings, backend, stats):
        settings.stability_safety = 1.1
        return check(equations, settings, backend, stats)

    monkeypatch.setattr(solver_module, "check_time_step", lifted)
    peak_stable = np.abs(histories(soft_dam_auto)[1]).max()
    below = masonrydam.run(flexible_dam(dt=0.99 * dtc, youngs_modulus=SOFT, duration=0.15, bottom_reflection=0.0,
                                        output_dt=None))
    assert np.abs(histories(below)[1]).max() == pytest.approx(peak_stable, rel=0.05)
    try:
        above = masonrydam.run(flexible_dam(dt=1.01 * dtc, youngs_modulus=SOFT, duration=0.15, bottom_reflection=0.0,
                                            output_dt=None))
    except NumericalError:
        return
    assert not np.abs(histories(above)[1]).max() < 1e6 * peak_stable


# ----------------------------------------------------------------------------------------------
# 3D
# ----------------------------------------------------------------------------------------------

def block_dam_3d(integrator="central_difference", dt="auto"):
    """A 2 x 2 x 4 m concrete block (hex8 of 1 m, E = 25 GPa, 2400 kg/m3) fixed at its base with water 3.5 m deep
    on its face x = 0 (acoustic, c = 1440 m/s, 10.5 m long), 0.08 s from a 0.02 s half-sine pulse of 2 m/s2 along x."""
    keys = ("x0", "y0", "z0", "x1", "y1", "z1")
    return {"model": {"name": "block_dam_3d", "dimension": 3},
            "mesh": {"generator": "blocks_3d", "parameters": {"element_size": 1.0, "blocks": [
                dict(zip(keys, (0, 0, 0, 2, 2, 4)), group="block")]}},
            "materials": {"block": {"youngs_modulus": 25e9, "poisson_ratio": 0.2, "density": 2400.0}},
            "reservoir": {"level": 3.5, "face": "left_face", "dynamic": "acoustic",
                          "acoustic": {"sound_speed": 1440.0}},
            "supports": [{"set": "base"}],
            "stages": [{"name": "water", "loads": [{"type": "reservoir"}]},
                       {"name": "quake", "type": "dynamic", "integrator": integrator, "dt": dt, "duration": 0.08,
                        "mass": "lumped",
                        "ground_motion": {"x": {"pulse": {"shape": "half_sine", "amplitude": 2.0, "duration": 0.02}}},
                        "output": {"dt": 0.001, "nodes": ["top"]} if dt == "auto" else {"nodes": ["top"]}}]}


def test_3d_block_dam_with_acoustic_water_runs_explicitly():
    """A 3D block dam with acoustic water (hex8 pressure elements), explicit (320 steps): its heel pressure
    follows the implicit path's (trapezoidal rule at 0.1 ms) within 8 % of its peak and its crest displacement
    within 1 %, and the energy balance closes to round-off.

    Tolerances from a study of this scene (run once, against the implicit path at 0.025 ms): the explicit
    heel pressure differs by 5.4 % (0.6 % at 0.05 ms: the same), the crest by 0.4 %; explicit steps with the
    consistent G and L factorized by 0.24 % and 0.03 %: the difference is the lumped capacity on 3.5 elements
    over the water's depth, and it halves with the mesh (2.8 % and 0.2 % on 0.5 m elements)."""
    ex = masonrydam.run(block_dam_3d())
    im = masonrydam.run(block_dam_3d("newmark_average", 1e-4))
    stage = per_stage(ex)
    assert 200 <= stage["steps"] <= 1000
    te, pe, ue, de = histories(ex)
    ti, pi, ui, _ = histories(im)
    assert np.abs(pi).max() > 1e3 and np.abs(ui).max() > 1e-7
    assert largest_difference(te, pe, ti, pi) < 0.08
    assert largest_difference(te, ue, ti, ui) < 0.01
    scale = max(float(np.abs(de[k]).max()) for k in ("energy_input", "energy_kinetic", "energy_strain"))
    assert float(np.abs(de.energy_error).max()) < 1e-12 * scale
