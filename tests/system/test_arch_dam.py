"""Arch dams end to end: modes of a small arch under mesh refinement, the reservoir's
added mass on its curved face, and a short explicit run through a record with the contraction joints.

No published frequencies of a reproducible arch geometry are at hand, so the modal tests check the model
against itself and against two theorems:

- convergence: for a smooth elastic problem the error of the lowest frequency of trilinear hexahedra falls
  as h^2 (Strang & Fix, An Analysis of the Finite Element Method, 1973, ch. 6: eigenvalue error of order
  h^(2(k+1-m)) with k = 1, m = 1), so on sizes halving the successive differences shrink about 4-fold and
  Aitken's (Richardson's) extrapolation of three sizes estimates the limit; the quadratic hex20 must lie
  closer to that limit on a coarser grid;
- the water's added mass: by Rayleigh's principle the lowest eigenvalue of (K, M + M_a) is at most the
  Rayleigh quotient of any trial vector, so with the empty dam's first mode phi (phi^T M phi = 1) as trial,
  f_full <= f_empty / sqrt(1 + phi^T M_a phi). The added mass lowers the frequency (Westergaard 1933;
  Kuo 1982 for m_a n n^T on a curved face); where the mode shape barely changes the bound is nearly
  attained (the quotient's error is second order in the change of shape).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

import masonrydam
from generators.arch_dams import arch_dam_3d
from masonrydam.effects.reservoir.added_mass import westergaard_mass

E, NU, RHO, RHO_W = 25e9, 0.2, 2400.0, 1000.0
#: a stubby arch, so that three halvings stay small: 8 m high, extrados radius 12 m, 100 deg, 4 m thick,
#: two monoliths (one radial contraction joint at the crown)
SMALL = dict(height=8.0, crest_radius=12.0, central_angle_deg=100.0, crest_thickness=4.0, n_monoliths=2)
LINEAR = {"law": "linear", "normal_stiffness": 1e11, "shear_stiffness": 1e11}


def _modal(params, water_level=None, modes=2):
    """The modal scene of the arch ``params`` on a rigid base with linear (sticking) joints; with
    ``water_level``, a static reservoir stage and Westergaard's added mass on the extrados."""
    p = dict(params)
    sc = {"model": {"name": "arch_modes", "dimension": 3},
          "mesh": {"generator": "arch_dam_3d", "parameters": p},
          "materials": {"dam": {"youngs_modulus": E, "poisson_ratio": NU, "density": RHO}},
          "joints": {"contraction_joints": dict(LINEAR)},
          "supports": [{"set": "base"}],
          "stages": [{"name": "modes", "type": "modal", "modes": modes}]}
    if params.get("lift_spacing"):
        sc["joints"]["lift_joints"] = dict(LINEAR)
    if water_level is not None:
        p["reservoir_level"] = water_level
        sc["reservoir"] = {"level": water_level, "density": RHO_W, "face": "upstream_face", "dynamic": "westergaard"}
        sc["stages"].insert(0, {"name": "reservoir", "loads": [{"type": "reservoir"}]})
    return masonrydam.run(sc)


@pytest.mark.slow
def test_first_frequency_of_a_small_arch_converges_under_refinement():
    """hex8 at h = 2, 1, 0.5 m (2, 4, 8 elements through the 4 m thickness): f1 falls monotonically
    (a conforming displacement model is too stiff: its frequencies converge from above) and the
    successive differences shrink by at least 2.5 (h^2 would give 4; measured 3.3: 33.45, 32.20, 31.82 Hz); the hex20 result at
    h = 1 m lies between Aitken's extrapolation of the hex8 sizes and the finest hex8 result, i.e. it is
    closer to the limit than hex8 with eight times the elements."""
    f8 = [float(_modal({**SMALL, "element_size": h}).frequency.values[0]) for h in (2.0, 1.0, 0.5)]
    f20 = float(_modal({**SMALL, "element_size": 1.0, "order": 2}).frequency.values[0])
    d1, d2 = f8[0] - f8[1], f8[1] - f8[2]
    assert d1 > 0.0 and d2 > 0.0
    assert d1 / d2 > 2.5
    limit = f8[2] - d2 * d2 / (d1 - d2)
    assert limit < f20 < f8[2]
    # the extrapolation is a small correction of the finest result: the mesh is in the asymptotic range
    assert f8[2] - limit < 0.02 * limit


def test_full_reservoir_lowers_the_first_frequency_by_its_added_mass():
    """Westergaard's added mass on the wetted extrados, reservoir to the crest (hex20, h = 2 m): the first
    frequency falls (added mass), at most to Rayleigh's bound f_empty / sqrt(1 + phi^T M_a phi) with the
    empty dam's mass-normalised first mode (exact principle: it cannot be exceeded), and by no more than
    2 % below it (the mode shape changes little: measured 0.15 %). M_a is built here from the generator's
    wetted facets with the library's Westergaard matrix, the same as the run's."""
    params = {**SMALL, "element_size": 2.0, "order": 2}
    H = params["height"]
    empty = _modal(params)
    full = _modal(params, water_level=H)
    f0, f1 = float(empty.frequency.values[0]), float(full.frequency.values[0])
    mesh = arch_dam_3d(**params, reservoir_level=H)
    X = np.column_stack([empty.x.values, empty.y.values, empty.z.values])
    assert X.shape == mesh.points.shape and np.allclose(X, mesh.points)  # the result's nodes are the mesh's
    wet = mesh.facet_sets["upstream_wet"]
    Ma = westergaard_mass(mesh.points, wet.type, wet.facets, level=H, reservoir_depth=H, density=RHO_W,
                          vertical_axis=2)
    phi = empty.mode_shape.isel(mode=0).values.reshape(-1)
    r = float(phi @ (Ma @ phi))
    assert 0.05 < r < 2.0  # the water's share of the mode's mass: a reservoir as deep as the dam is high
    bound = f0 / np.sqrt(1.0 + r)
    assert f1 < f0
    assert f1 <= bound * (1 + 1e-9)
    assert f1 >= 0.98 * bound


def test_a_small_arch_goes_through_a_short_record_explicitly():
    """Four monoliths of two lifts on a fixed base, cohesionless contraction joints: self-weight, then
    0.3 s of the strong part of El Centro 1940 (NS along the stream y, EW across the valley x, 0.5 g,
    cut at the Husid 5 % point) with central difference at dt = "auto" and 5 % local damping. The run
    completes, its result holds every contraction-joint point (4 per quad4 interface), the energy
    balance closes to round-off (the explicit scheme's bookkeeping is exact: docs/dam_3d.md), the damping
    and friction works dissipate, and the shaking moves the crest."""
    params = dict(height=12.0, crest_radius=16.0, central_angle_deg=100.0, crest_thickness=2.0, base_thickness=4.0,
                  n_monoliths=4, lift_spacing=6.0, element_size=2.0)
    joint = {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": 45.0}
    trim = [{"step": "trim"}]
    scene = {"model": {"name": "arch_record", "dimension": 3},
             "mesh": {"generator": "arch_dam_3d", "parameters": params},
             "materials": {"dam": {"youngs_modulus": E, "poisson_ratio": NU, "density": RHO}},
             "joints": {"lift_joints": {**joint, "cohesion": "1 MPa"}, "contraction_joints": {**joint, "cohesion": 0.0}},
             "supports": [{"set": "base"}],
             "stages": [{"name": "gravity", "steps": 2, "loads": [{"type": "self_weight"}]},
                        {"name": "shaking", "type": "dynamic", "integrator": "central_difference", "dt": "auto",
                         "duration": 0.3, "damping": {"model": "local", "ratio": 0.05},
                         "ground_motion": {
                             "y": {"record": "elcentro_1940_ns_ngaw2", "scale_to_pga": "0.5 g", "processing": trim},
                             "x": {"record": "elcentro_1940_ew_ngaw2", "scale_to_pga": "0.5 g", "processing": trim}},
                         "output": {"dt": 0.01}}]}
    ds = masonrydam.run(scene)
    mesh = arch_dam_3d(**params)
    n_cj = sum(len(j.cells) for j in mesh.joints if j.name == "contraction_joints")
    names = json.loads(ds.joint_set.attrs["set_names"])
    cj = ds.joint_set.values == names.index("contraction_joints")
    assert n_cj > 0 and int(cj.sum()) == 4 * n_cj
    stages = json.loads(ds.stage.attrs["stage_names"])
    dyn = np.nonzero(ds.stage.values == stages.index("shaking"))[0]
    assert ds.time.values[dyn[-1]] - ds.time.values[dyn[0]] == pytest.approx(0.3, abs=1e-9)
    opening = ds.joint_opening.values[dyn][:, cj]
    assert np.isfinite(opening).all()
    # energy: the balance closes to round-off of its largest term; local damping and friction dissipate
    assert float(ds.attrs["energy_error_relative"]) < 1e-10
    assert (np.diff(ds.energy_damping.values[dyn]) >= -1e-9 * np.abs(ds.energy_damping.values[dyn]).max()).all()
    assert ds.energy_damping.values[dyn[-1]] > 0.0
    assert ds.energy_joint_friction.values[dyn[-1]] >= 0.0
    assert ds.energy_kinetic.values[dyn].max() > 0.0
    u = ds.displacement.values[dyn]
    z = ds.z.values
    crest = z > z.max() - 1e-6
    assert np.abs(u[:, crest, 1] - u[0, crest, 1]).max() > 1e-5  # the crest moves along the stream (> 0.01 mm)
