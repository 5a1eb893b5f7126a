"""A stop asked for within an implicit step (Ctrl-C or SIGTERM between two Newton iterations) abandons the step and
keeps the last converged one (a step of a large 3D model in the general Newton path can take
minutes, and the run must end within seconds).

The scene is the Newmark sliding block of tests/scenes.sliding_block on the general Newton path (joint_space =
"off", so that every step iterates); the stop is asked for from the 40th Newton iteration on. The run raises
RunStopped naming the step it was within, the file keeps the steps converged before it, and they equal those of
an uninterrupted run of the same scene (the kernels are deterministic)."""
from __future__ import annotations

import sys
import warnings

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import RunStopped
from masonrydam.results.files import IncompleteResultWarning, open_result
from masonrydam.cli.main import default_scene_path
from masonrydam.scene.scene import Scene
from masonrydam.scene.stopping import StopRequests
from scenes import sliding_block


def test_stop_within_an_implicit_step_keeps_the_last_converged_step(tmp_path, monkeypatch):
    scene = sliding_block(duration=0.4, dt=0.002, integrator="hht", joint_space="off")
    monkeypatch.setattr(StopRequests, "requested", _stop_at(40))
    out = tmp_path / "out.nc"
    with pytest.raises(RunStopped) as err:
        masonrydam.run(scene, output=out)
    assert "within the step after it (abandoned)" in str(err.value)
    monkeypatch.undo()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IncompleteResultWarning)
        ds = open_result(out)
    assert ds.attrs["status"] == "interrupted"
    t = ds.time.values
    t_last = float(t[-1])
    assert 0.0 < t_last < 0.4
    assert t_last == pytest.approx(0.002 * round(t_last / 0.002))  # a converged step's time, not a trial's
    ref = masonrydam.run(sliding_block(duration=t_last, dt=0.002, integrator="hht", joint_space="off"))
    assert ref.sizes["step"] == ds.sizes["step"]
    np.testing.assert_allclose(ds.displacement.values, ref.displacement.values, rtol=0,
                               atol=1e-10 * np.abs(ref.displacement.values).max())
    np.testing.assert_array_equal(ds.joint_state.values, ref.joint_state.values)


def _stop_at(count: int, where: str | None = None):
    """A ``StopRequests.requested`` that answers "interrupted" from the ``count``-th time it is asked within a step
    (by ``_stop_within_step``), called from ``where`` (``"_solve_step"`` for the joint-space iteration in Python,
    ``"solve_step"`` before a compiled joint-space step,
    ``"tell_progress"`` for a Newton iteration of the static general path; None: from anywhere), and None
    otherwise; the number of such calls is in its ``calls``."""
    calls = {"n": 0}

    def requested(self):
        caller = sys._getframe(1)
        if caller.f_code.co_name == "_stop_within_step" and where in (None, caller.f_back.f_code.co_name):
            calls["n"] += 1
            if calls["n"] >= count:
                return "interrupted"
        return None

    requested.calls = calls
    return requested


def _kept(out):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IncompleteResultWarning)
        return open_result(out)


@pytest.mark.parametrize("joint_space, where, count", [("auto", "_solve_step", 60), ("off", "tell_progress", 20)])
def test_stop_within_a_static_step_keeps_the_converged_steps(tmp_path, monkeypatch, default_scene_result, joint_space,
                                                             where, count):
    """The default scene (a wall pushed at its top; its static steps are solved in joint space, by the Python loop
    here, which asks between its iterations, or with ``joint_space = "off"`` by the general Newton path) stopped
    within a step: the run raises RunStopped naming the last converged step and the abandoned one; the file keeps
    the steps converged before, and they are those of the uninterrupted run (bit for bit on the same path; on the general path within 1e-5 of the largest
    displacement: the two paths solve the same frictional steps to their tolerances, docs/performance.md)."""
    from masonrydam.solvers.joint_space import condensation

    monkeypatch.setattr(condensation, "STATIC_COMPILED_STEP", "never")  # (the compiled step asks before its call only)
    scene = Scene.from_toml(default_scene_path()).data
    scene.setdefault("solver", {})["joint_space"] = joint_space
    requested = _stop_at(count, where)
    monkeypatch.setattr(StopRequests, "requested", requested)
    out = tmp_path / "out.nc"
    with pytest.raises(RunStopped) as err:
        masonrydam.run(Scene(scene, base_dir=default_scene_path().parent), output=out)
    monkeypatch.undo()
    assert requested.calls["n"] == count  # the stop came from within a step, on the path asked for
    assert "within the next step" in str(err.value) and "abandoned" in str(err.value)
    ds = _kept(out)
    full = open_result(default_scene_result)
    assert ds.attrs["status"] == "interrupted"
    n = ds.sizes["step"]
    assert 0 < n < full.sizes["step"]
    np.testing.assert_array_equal(ds.load_factor.values, full.load_factor.values[:n])
    if joint_space == "auto":
        np.testing.assert_array_equal(ds.displacement.values, full.displacement.values[:n])
        np.testing.assert_array_equal(ds.joint_state.values, full.joint_state.values[:n])
    else:
        np.testing.assert_allclose(ds.displacement.values, full.displacement.values[:n], rtol=0,
                                   atol=1e-5 * np.abs(full.displacement.values[:n]).max())


def test_stop_within_a_dynamic_joint_space_attempt(tmp_path, monkeypatch):
    """The sliding block with its dynamic steps solved in joint space, stopped at the start of a joint-space attempt
    (the compiled step, masonrydam.solvers.joint_space.step_kernel, is one call of microseconds: the stop is asked
    for before it; the compiled step loop, which asks between its calls, is switched off): the attempt is abandoned
    and the steps before it kept, equal to an uninterrupted run's."""
    from masonrydam.solvers.dynamic import compiled_loop

    scene = sliding_block(duration=0.4, dt=0.002, integrator="hht")
    requested = _stop_at(30, "solve_step")
    monkeypatch.setattr(StopRequests, "requested", requested)
    monkeypatch.setattr(compiled_loop, "COMPILED_LOOP", False)  # (the loop's steps are asked between its calls)
    out = tmp_path / "out.nc"
    with pytest.raises(RunStopped) as err:
        masonrydam.run(scene, output=out)
    monkeypatch.undo()
    assert requested.calls["n"] == 30
    assert "within the step after it (abandoned)" in str(err.value)
    ds = _kept(out)
    t_last = float(ds.time.values[-1])
    assert 0.0 < t_last < 0.4
    ref = masonrydam.run(sliding_block(duration=t_last, dt=0.002, integrator="hht"))
    assert ref.sizes["step"] == ds.sizes["step"]
    np.testing.assert_allclose(ds.displacement.values, ref.displacement.values, rtol=0,
                               atol=1e-10 * np.abs(ref.displacement.values).max())
    np.testing.assert_array_equal(ds.joint_state.values, ref.joint_state.values)


def test_stop_between_calls_of_the_compiled_step_loop(tmp_path, monkeypatch):
    """The sliding block's steps in the compiled step loop (masonrydam.solvers.dynamic.compiled_loop), a stop asked
    for at the 5th record (the loop asks between its calls, that is at every record): the run stops there with the
    steps taken so far kept, equal to an uninterrupted run's."""
    scene = sliding_block(duration=0.4, dt=0.002, integrator="hht", output={"stride": 10})
    asked = {"n": 0}

    def requested(self):
        if sys._getframe(1).f_code.co_name == "_maybe_emit":
            asked["n"] += 1
            return "interrupted" if asked["n"] >= 5 else None
        return None

    monkeypatch.setattr(StopRequests, "requested", requested)
    out = tmp_path / "out.nc"
    with pytest.raises(RunStopped) as err:
        masonrydam.run(scene, output=out)
    monkeypatch.undo()
    assert "at step 50 of 200" in str(err.value)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IncompleteResultWarning)
        ds = open_result(out)
    ref = masonrydam.run(sliding_block(duration=0.1, dt=0.002, integrator="hht", output={"stride": 10}))
    assert ref.attrs["dynamic_compiled_loop_steps"] > 0
    assert ds.sizes["step"] == ref.sizes["step"]
    np.testing.assert_array_equal(ds.time.values, ref.time.values)
    np.testing.assert_array_equal(ds.displacement.values, ref.displacement.values)


def test_stop_between_calls_of_the_compiled_step_loop_with_dt_auto(tmp_path, monkeypatch):
    """The same with dt = "auto" (output every 0.02 s): calls of the loop end at records, where a step takes another
    size and where a step is handed back; a stop asked for from the 12th question on (records and the questions
    between calls alike) stops the run, which keeps the records before it, equal to an uninterrupted run's."""
    scene = sliding_block(duration=0.4, dt="auto", integrator="hht", output={"dt": 0.02})
    asked = {"n": 0}

    def requested(self):
        if sys._getframe(1).f_code.co_name in ("_maybe_emit", "between_calls"):
            asked["n"] += 1
            return "interrupted" if asked["n"] >= 12 else None
        return None

    monkeypatch.setattr(StopRequests, "requested", requested)
    out = tmp_path / "out.nc"
    with pytest.raises(RunStopped):
        masonrydam.run(scene, output=out)
    monkeypatch.undo()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IncompleteResultWarning)
        ds = open_result(out)
    full = masonrydam.run(sliding_block(duration=0.4, dt="auto", integrator="hht", output={"dt": 0.02}))
    assert full.attrs["dynamic_compiled_loop_steps"] > 0
    n = ds.sizes["step"] - 1  # (the last record is the state the run stopped at)
    assert 0 < n < full.sizes["step"]
    np.testing.assert_array_equal(ds.time.values[:n], full.time.values[:n])
    np.testing.assert_array_equal(ds.displacement.values[:n], full.displacement.values[:n])
