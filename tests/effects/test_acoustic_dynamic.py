"""The acoustic reservoir in the dynamic stages (``[reservoir] dynamic = "acoustic"``), end to end through the scene.

References: the exact rigid-wall solution of Westergaard (1933), Trans. ASCE 98:418-433, as a series:
incompressible base pressure 0.7425 rho a H and resultant 0.5428 rho a H^2; under harmonic excitation
each term of the series divided by c_m = sqrt(1 - (w / w_m)^2), w_m = m pi c / (2 H) (Chopra 1967, J. Eng.
Mech. Div. ASCE 93(EM6):205-223).
The matrices themselves are checked in tests/test_acoustic.py; here the time integration of the
coupled dam-water system (masonrydam/solvers/dynamic/fluid.py) is.
"""
from __future__ import annotations

import numpy as np
import pytest

import masonrydam

RHO_W = 1000.0


def rigid_dam(dynamic="acoustic", sound_speed=1440.0, height=1.0, level=0.75, size=0.125, ground=None, dt=0.01,
              integrator="newmark_average", extra=None):
    """A stiff block fixed at its base (no joints: a rigid dam) with the reservoir on its face x = 0."""
    s = {
        "model": {"name": "rigid_dam", "thickness": 1.0},
        "mesh": {"generator": "blocks_2d", "parameters": {"element_size": size, "blocks": [
            {"x0": 0.0, "y0": 0.0, "x1": height, "y1": height, "group": "block"}]}},
        "materials": {"block": {"youngs_modulus": 1e14, "poisson_ratio": 0.2, "density": 2000.0}},
        "reservoir": {"level": level, "face": "left_edge", "dynamic": dynamic},
        "supports": [{"set": "base"}],
        "stages": [{"name": "water", "loads": [{"type": "reservoir"}]},
                   {"name": "quake", "type": "dynamic", "dt": dt, "integrator": integrator,
                    "ground_motion": {"x": ground}, "output": {"nodes": ["top"]}}],
    }
    if dynamic == "acoustic":
        s["reservoir"]["acoustic"] = dict({"sound_speed": sound_speed}, **(extra or {}))
    return s


def series_resultant(omega, c, H, terms=2001):
    """Resultant / (rho a H^2) of the rigid-wall series, every term divided by c_m (c None: incompressible)."""
    m = np.arange(1, terms, 2)
    cm = np.ones_like(m, dtype=float) if c is None else np.sqrt(1.0 - (omega / (m * np.pi * c / (2 * H))) ** 2)
    return float(np.sum(16.0 / (np.pi**3 * m**3) / cm))


@pytest.mark.parametrize("c", ["incompressible", 1440.0])
@pytest.mark.reference
def test_slowly_varying_acceleration_gives_the_exact_series(c):
    """A ground acceleration rising slowly (0.5 s against H / c = 0.5 ms) on a rigid dam: the pressure on
    the face tends to the incompressible series, base 0.7425 rho a H, resultant 0.5428 rho a H^2 (2 %)."""
    acc = np.linspace(0.0, 2.0, 51)
    ds = masonrydam.run(rigid_dam(sound_speed=c, ground={"values": acc.tolist(), "dt": 0.01}))
    last = ds.isel(step=-1)
    a, H = float(last.ground_acceleration.sel(component="x")), 0.75
    F = last.hydrodynamic_force.values
    # accelerating +x pulls the face (outward normal -x) away from the water: suction, force toward -x
    assert -F[0] / (RHO_W * a * H**2) == pytest.approx(0.5428, rel=0.02)
    base = int(np.argmin(ds.face_y.values))
    assert -float(last.face_pressure.values[base]) / (RHO_W * a * H) == pytest.approx(0.7425, rel=0.02)
    # the pressure along the face: the series at each node's depth (the water line: zero)
    z = H - ds.face_y.values
    m = np.arange(1, 2001, 2)
    exact = 8.0 / np.pi**2 * np.sum(np.sin(m[None, :] * np.pi * z[:, None] / (2 * H)) / m[None, :] ** 2, axis=1)
    np.testing.assert_allclose(-last.face_pressure.values / (RHO_W * a * H), exact, atol=0.02)
    assert "acoustic elements" in ds.attrs["simulated_effects"]


@pytest.mark.reference
def test_harmonic_excitation_follows_the_compressible_series():
    """Harmonic ground acceleration at half the reservoir's first frequency c / (4 H) on a rigid dam
    (H = 10 m, c = 1440 m/s: f_1 = 36 Hz): the steady amplitude of the resultant is the series with the
    c_m factors (3 %), 15 % above the incompressible one, and the pressure is in phase with the ground
    acceleration (no radiation below the first frequency)."""
    H, c = 10.0, 1440.0
    f1 = c / (4 * H)
    f = 0.5 * f1
    dt = 1.0 / (f * 40)
    t = np.arange(0.0, 1.2, dt)
    envelope = np.where(t < 10 / f, 0.5 * (1 - np.cos(np.pi * t * f / 10)), 1.0)
    acc = envelope * np.sin(2 * np.pi * f * t)
    s = rigid_dam(sound_speed=c, height=H, level=H, size=1.0, ground={"values": acc.tolist(), "dt": dt}, dt=dt,
                  extra={"length": 5 * H})
    ds = masonrydam.run(s)
    dyn = ds.where(~np.isnan(ds.time), drop=True)
    tt = dyn.time.values
    F = dyn.hydrodynamic_force.sel(component="x").values
    ag = dyn.ground_acceleration.sel(component="x").values
    late = tt > tt[-1] - 6 / f
    ratio = -np.polyfit(ag[late], F[late], 1)[0] / (RHO_W * H**2)  # in phase: F = -k a
    expected = series_resultant(2 * np.pi * f, c, H)
    assert ratio == pytest.approx(expected, rel=0.03)
    assert expected / series_resultant(0.0, None, H) == pytest.approx(1.148, abs=0.001)
    resid = F[late] + ratio * RHO_W * H**2 * ag[late]
    assert np.abs(resid).max() < 0.05 * np.abs(F[late]).max()


@pytest.mark.parametrize("integrator", ["newmark_average", "hht", "generalized_alpha"])
def test_condensed_step_tends_to_the_added_mass(integrator):
    """The compressible path (water condensed into each step, solvers/dynamic/fluid.py) with a very fast sound
    speed gives the incompressible added mass's answer, on a flexible block sliding on a joint (the
    joint-space path with the water in its flexibility), for each implicit integrator."""
    def scene(c):
        s = rigid_dam(sound_speed=c, ground={"pulse": {"shape": "half_sine", "amplitude": -6.0, "duration": 0.1}},
                      dt=0.002, integrator=integrator)
        s["mesh"]["parameters"]["blocks"] = [{"x0": 0.0, "y0": -0.25, "x1": 1.0, "y1": 0.0, "group": "base"},
                                             {"x0": 0.0, "y0": 0.0, "x1": 1.0, "y1": 1.0, "group": "block"}]
        s["materials"] = {g: {"youngs_modulus": 2e9, "poisson_ratio": 0.2, "density": 2000.0} for g in ("base", "block")}
        s["joints"] = {"joints": {"normal_stiffness": 1e10, "shear_stiffness": 1e10, "friction_angle": 30.0}}
        s["stages"][0]["loads"] = [{"type": "self_weight"}, {"type": "reservoir"}]
        s["stages"][1]["duration"] = 0.2
        return s
    a = masonrydam.run(scene("incompressible"))
    b = masonrydam.run(scene(1e6))
    ua = a.displacement.sel(component="x").values
    ub = b.displacement.sel(component="x").values
    assert np.abs(ua).max() > 1e-3  # it slides
    np.testing.assert_allclose(ub, ua, atol=2e-3 * np.abs(ua).max())
    assert float(np.abs(b.energy_error).max()) < 1e-6 * float(np.abs(b.energy_input).max())
