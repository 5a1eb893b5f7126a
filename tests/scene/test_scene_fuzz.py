"""The fuzzed scene suite: small valid scenes mutated by hypothesis (tests/scene_fuzzing.py says how) must be
checked and run to a success or to a one-line refusal that names its scene key, never a traceback, a NaN in a
completed result or an earlier result file changed. Seeded and a fixed number of examples, so the suite is
repeatable; ``benchmarks/fuzz_scenes.py`` runs many more and prints what it found.

The four cases found by hand before the suite existed are kept as tests of their own below.
"""
from __future__ import annotations

import copy
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

import masonrydam
from masonrydam.cli.main import check_scene
from masonrydam.errors import SceneError, SceneWarning
from masonrydam.scene.progress import DynamicProgress, dynamic_status
from scene_fuzzing import BASE_SCENES, OPERATIONS, mutate, outcome, tiny_wall
from scenes import merged

#: examples the seeded suite tries (most are refused by the check in milliseconds; the runs take a second or two)
FUZZ_EXAMPLES = 100

mutations = st.lists(st.tuples(st.sampled_from(OPERATIONS), st.integers(0, 10**6), st.integers(0, 10**6)),
                     min_size=1, max_size=3)


@pytest.mark.slow
@seed(20261207)
@settings(max_examples=FUZZ_EXAMPLES, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(base=st.sampled_from(sorted(BASE_SCENES)), changes=mutations)
def test_a_mutated_scene_is_run_or_refused_in_one_line(base, changes, tmp_path):
    scene = BASE_SCENES[base]()
    for operation, pick, value in changes:
        mutate(scene, operation, pick, value)
    outcome(scene, tmp_path)  # asserts the property


def test_a_modal_only_scene_runs_and_is_summarised(tmp_path, capsys):
    """A scene whose only stage is modal: its modes are written and the summary says no step was taken (it used to
    end in an IndexError in the summary). The frequencies are those of the wall held at its base."""
    scene = tiny_wall()
    scene["stages"] = [{"type": "modal", "modes": 3}]
    ds = masonrydam.run(scene, output=tmp_path / "modes.nc", summary=True)
    assert ds.sizes.get("step", 0) == 0
    f = ds.frequency.values
    assert len(f) == 3 and np.all(np.diff(f) >= 0) and f[0] > 0
    text = capsys.readouterr().out
    assert "steps      : none (modes only" in text and "max |u|" not in text


def test_too_many_modes_are_refused_before_the_first_stage(no_solve):
    """``modes`` against the free DOFs at the modal stage, named by its scene key, before any static stage runs
    (it used to be refused after them, as 'n_modes')."""
    scene = tiny_wall()
    scene["stages"][2]["modes"] = 5000
    with pytest.raises(SceneError) as ei:
        check_scene(scene)
    assert ei.value.key == "stages[2].modes"
    assert "5000 modes" in str(ei.value) and "free DOFs" in str(ei.value)
    with pytest.raises(SceneError):
        masonrydam.run(scene)  # no_solve: the static solver is never started


def test_a_stage_long_past_its_record_is_warned_about():
    """A dynamic stage of 100 s on a pulse of 0.2 s: a warning that names the key and the record's end (it used to
    be accepted silently and stepped on at rest). The example's own 0.6 s (three times the pulse: the block slides
    on after it) is not warned about, and one of 1e9 s (1e11 steps at its dt_max) is refused."""
    scene = BASE_SCENES["sliding_block_pulse"]()
    dynamic = next(i for i, s in enumerate(scene["stages"]) if s.get("type") == "dynamic")
    with warnings.catch_warnings():
        warnings.simplefilter("error", SceneWarning)
        check_scene(copy.deepcopy(scene))
    scene["stages"][dynamic]["duration"] = 100.0
    with pytest.warns(SceneWarning, match=rf"stages\[{dynamic}\]\.duration.*ends at 0\.2 s"):
        check_scene(copy.deepcopy(scene))
    scene["stages"][dynamic]["duration"] = 1e9
    with pytest.raises(SceneError, match=r"at least 1e\+11 steps"):
        check_scene(scene)


class _FakeBar:
    enabled = True

    def __init__(self):
        self.texts, self.positions = [], []

    def __call__(self, stage_index, fraction):
        self.positions.append(stage_index + fraction)

    def status(self, text, force=False):
        self.texts.append(text)


def test_the_progress_of_a_dynamic_stage_tells_its_name_time_step_refusals_and_time_left():
    """The words after the bar in a dynamic stage (they used to keep the last static stage's words for the whole
    earthquake): its name, simulated time against the stage's end, the recent step, the refused steps, the time
    left at the recent rate (here 1 % of the stage in 2 s of wall time, 49 % left: 98 s)."""
    from types import SimpleNamespace

    stage = SimpleNamespace(name="el_centro", duration=40.0, settings=SimpleNamespace(adaptive=True))
    solver = SimpleNamespace(stats=SimpleNamespace(steps=0, steps_rejected=0), _last_converged=None)
    clock = iter([100.0, 102.0])
    bar = _FakeBar()
    progress = DynamicProgress(bar, 1, stage, solver, 10.0, clock=lambda: next(clock))
    assert bar.texts[-1] == "el_centro: t = 10 of 50 s, 0 refused"
    solver._last_converged = (0, SimpleNamespace(t=30.0))
    solver.stats.steps, solver.stats.steps_rejected = 4000, 3
    progress(0.5)
    solver._last_converged = (0, SimpleNamespace(t=30.4))
    solver.stats.steps = 4080
    progress(0.51)
    assert bar.positions == [1.5, 1.51]
    assert bar.texts[-1] == "el_centro: t = 30.4 of 50 s, dt 0.005 s, 3 refused, about 1m38s left"
    assert dynamic_status("quake", 1.0, 2.0, None, None, None) == "quake: t = 1 of 2 s"


#: the defects the fuzzing found (benchmarks/fuzz_scenes.py, seeds 3 to 9), each a scene that used to end in a
#: traceback or to be refused only by the run, now refused by the check in one line naming its key: (base scene, the
#: changes as scenes.merged takes them, the key)
FOUND_BY_FUZZING = [
    # ValueError "Maximum allowed size exceeded" while meshing 1e60 elements
    ("block_on_incline", {"mesh.parameters.element_size": 1e-30}, "mesh.parameters.element_size"),
    ("block_3d_oblique", {"mesh.parameters.element_size": 1e-30}, "mesh.parameters.element_size"),
    # OverflowError sampling a pulse at a step of 1e-30 s
    ("sliding_block_pulse", {"stages.1.dt_max": 1e-30}, "stages[1].dt_max"),
    ("sliding_block_pulse", {"stages.1.dt_min": 1e-30}, "stages[1].dt_min"),
    # ValueError "need at least one array to concatenate": no node set recorded
    ("sliding_block_pulse", {"stages.1.output.nodes": []}, "stages[1].output.nodes"),
    ("tiny_wall", {"output.joints": []}, "output.joints"),
    # a static stage of a billion steps (it would run for days)
    ("block_on_incline", {"stages.1.steps": 10**9}, "stages[1].steps"),
    # a recorded node set that does not exist: refused by the run, not by the check
    ("tiny_wall", {"output.nodes": ["nowhere"]}, "output.nodes"),
    # modes of a model without mass: refused by the modal analysis after the static stages, not by the check
    ("tiny_wall", {"materials.units.density": 0.0}, "materials"),
]


@pytest.mark.parametrize("base, changes, key", FOUND_BY_FUZZING,
                         ids=[f"{b}-{next(iter(c))}" for b, c, _ in FOUND_BY_FUZZING])
def test_a_defect_the_fuzzing_found_is_refused_by_the_check(base, changes, key):
    scene = merged(BASE_SCENES[base](), changes)
    with pytest.raises(SceneError) as ei:
        check_scene(scene)
    assert ei.value.key == key and "\n" not in str(ei.value)


def test_modes_of_a_model_with_a_massless_block_fail_in_words(tmp_path):
    """The fuzzing's ARPACK error (a block whose density was dropped, a modal stage alone): a NumericalError that names
    the element group without mass; the run exits 2 in one line (it used to end in scipy's ArpackError)."""
    from masonrydam.errors import NumericalError

    scene = BASE_SCENES["sliding_block_pulse"]()
    scene["stages"] = [{"type": "modal"}]
    del scene["materials"]["block"]["density"]
    with pytest.raises(NumericalError, match=r"element groups \['block'\] have no mass"):
        masonrydam.run(scene, output=tmp_path / "m.nc")


@pytest.mark.slow
def test_a_run_shows_its_dynamic_stage_on_the_progress_bar(capsys):
    """End to end: the words after the bar during the sliding block's pulse stage name it and its simulated time
    against its end (0.6 s), not the gravity stage's last Newton iteration."""
    masonrydam.run(BASE_SCENES["sliding_block_pulse"](), progress=True)
    err = capsys.readouterr().err.replace("\r", "\n")
    dynamic = [ln for ln in err.splitlines() if "pulse: t = " in ln]
    assert dynamic and all("of 0.6 s" in ln for ln in dynamic)
    assert "refused" in dynamic[-1] and "gravity:" not in dynamic[-1]
