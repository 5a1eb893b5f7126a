"""The Eindhoven wall J4D with its top held (Raijmakers & Vermeltfoort 1992 as modelled by
Lourenco & Rots 1997): how its curve converges as the joints' relaxation time goes to zero.

The example (examples/eindhoven_J4D.toml) regularises its softening joints with Duvaut-Lions viscosity
(Simo & Hughes 1998, sec. 2.7): the traction is ``(t_trial + r t_inviscid) / (1 + r)``, ``r = dt / tau``. The
overstress ``(t_trial - t_inviscid) / (1 + r)`` grows with the joint's elastic stiffness, so the units'
potential cracks (a penalty of 1e6 N/mm3, 12 000 times the mortar joints' 82 N/mm3) carry an overstress that
the mortar joints do not, and that delays the cracking of the units (docs/masonry_softening.md, "What the
relaxation time does to the units' cracks").

Checked here, each against the same wall at a relaxation time ten times smaller (0.0025 and 0.00025 ms, both
runs of 40 push steps):
- up to 2 mm the force is converged: within 3 % (measured 0.3 % on a 2-core AMD EPYC);
- at 4 mm it is not (80 against 69 kN): a strict expected failure, so that a change that makes it converge is
  seen (the test then passes unexpectedly and fails the suite, and the marker must go).

And the inviscid law with ``limit_point = "relax"``, which crosses the limit point where Newton stalls at 1.82 mm
and every later one: the scene of examples/eindhoven_walls.py (the units' cracks at 1e4 N/mm3, 80 push steps)
against the 80-step run with the example file's stiff cracks (1e6 N/mm3), to 4 mm.
"""
from __future__ import annotations

import importlib.util
import json

import pytest

import masonrydam
from masonrydam.results.pushover import pushover_data, value_at_push
from masonrydam.results.wall_cracks import wall_cracks
from masonrydam.scene.scene import Scene, set_key
from repository_paths import EXAMPLES

#: the example's relaxation time and a tenth of it (ms)
RELAXATION_TIMES = ("0.0025 ms", "0.00025 ms")
COMPOSITE_SETS = ("bed_joints", "head_joints", "unit_cracks")


@pytest.fixture(scope="module")
def held_curves():
    """(push, force) of the held J4D wall at both relaxation times: about 2.5 minutes on one core."""
    curves = {}
    for tau in RELAXATION_TIMES:
        data = Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data
        for name in COMPOSITE_SETS:
            set_key(data, f"joints.{name}.relaxation_time", tau)
        ds = masonrydam.run(data)
        assert ds.attrs["completed"] == "true"
        d, f, _ = pushover_data(ds, "x")
        assert d[-1] == pytest.approx(4e-3, abs=1e-8)
        curves[tau] = (d, f)
    return curves


@pytest.mark.slow
@pytest.mark.reference
@pytest.mark.parametrize("push", [1e-3, 2e-3])
def test_held_j4d_force_converged_in_the_relaxation_time_up_to_2_mm(held_curves, push):
    coarse, fine = (value_at_push(*held_curves[tau], push) for tau in RELAXATION_TIMES)
    assert coarse == pytest.approx(fine, rel=0.03)
    # the held top's added vertical force already shows: above the constant-load peak of 30 kN (the strut)
    assert fine > 40e3


@pytest.mark.slow
@pytest.mark.reference
@pytest.mark.xfail(strict=True, reason="known: past 3 mm the held wall's force depends on the relaxation "
                                       "time, through the overstress of the units' penalty-stiff cracks "
                                       "(80 kN at 0.0025 ms, 69 kN at 0.00025 ms; docs/masonry_softening.md)")
def test_held_j4d_force_at_4_mm_converged_in_the_relaxation_time(held_curves):
    coarse, fine = (value_at_push(*held_curves[tau], 4e-3) for tau in RELAXATION_TIMES)
    assert coarse == pytest.approx(fine, rel=0.03)


#: the inviscid held J4D relaxed past its limit points at 80 push steps, with the example file's units' cracks (1e6
#: N/mm3) (docs/masonry_softening.md, "The inviscid wall past its limit points"; 2-core AMD EPYC): the peak (N) and the
#: force (N) at 1, 2, 3 and 4 mm
PEAK_80_STEPS = 55.81e3
FORCE_80_STEPS = {1e-3: 47.25e3, 2e-3: 53.18e3, 3e-3: 45.80e3, 4e-3: 39.98e3}


@pytest.mark.slow
@pytest.mark.reference
def test_inviscid_held_j4d_relaxed_past_its_limit_points_converged_to_4_mm():
    """The inviscid law (no relaxation time) stops at 1.82 mm under displacement control: a limit point of its path
    (docs/masonry_softening.md, "Why the inviscid law stops at 1.82 mm"). With ``limit_point = "relax"`` it crosses
    it and every later one to 4 mm. The scene is the one examples/eindhoven_walls.py builds: the units' cracks, a
    penalty, at 1e4 N/mm3 instead of the example file's 1e6, and 80 push steps. Its curve is the one of the stiff
    cracks in 80 steps within 3 % at the peak and at 1, 2, 3 and 4 mm (measured 0.3 % at the peak and 0.06 to 0.8 %
    at the four points; 160 steps with the soft cracks move it by 0.5 % or less: docs/masonry_softening.md, "The
    units' cracks' penalty"). Past its peak the wall softens, and at 4 mm it shows the diagonal stair-case crack
    through head joints and units that the tests and the micro-model of Lourenço & Rots (1997) show. About a minute
    on one core."""
    spec = importlib.util.spec_from_file_location("eindhoven_walls", EXAMPLES / "eindhoven_walls.py")
    walls = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(walls)
    data = walls.wall_scene("J4D")
    assert "relaxation_time" not in data["joints"]["unit_cracks"] and data["stages"][1]["steps"] == 80
    assert data["joints"]["unit_cracks"]["shear_stiffness"] == "1e4 N/mm3"
    ds = masonrydam.run(data)
    assert ds.attrs["completed"] == "true"
    d, f, _ = pushover_data(ds, "x")
    assert d[-1] == pytest.approx(4e-3, abs=1e-8)
    relaxed = json.loads(ds.attrs["per_stage"])[1]["relaxed_limit_points"]
    # the stall's limit point is crossed by a hold (holds come earlier too, where a quarter step finds no equilibrium)
    assert any(abs(lf * 4e-3 - 1.82e-3) <= 0.03e-3 for lf, _ in relaxed)
    assert f.max() == pytest.approx(PEAK_80_STEPS, rel=0.03)
    for push, force in FORCE_80_STEPS.items():
        assert value_at_push(d, f, push) == pytest.approx(force, rel=0.03), push
    assert f[-1] < 0.8 * f.max()  # past the peak the wall softens
    cracks = wall_cracks(ds, -1)
    assert any(m.startswith("diagonal stair-case cracking") for m in cracks.mechanisms), cracks.words()
    assert cracks.counts["unit_cracks"]["open"] > 0 and "J4D (p = 0.30 MPa): peak" in walls.report("J4D", ds, 0.0)
