"""A stop asked for within an implicit step (Ctrl-C or SIGTERM between two Newton iterations) abandons the step and
keeps the last converged one (issue 33, item 5: a step of a large 3D model in the general Newton path can take
minutes, and the run must end within seconds).

The scene is the Newmark sliding block of tests/scenes.sliding_block on the general Newton path (joint_space =
"off", so that every step iterates); the stop is asked for from the 40th Newton iteration on. The run raises
RunStopped naming the step it was within, the file keeps the steps converged before it, and they equal those of
an uninterrupted run of the same scene (the kernels are deterministic)."""
from __future__ import annotations

import inspect
import warnings

import numpy as np
import pytest

import masonrydam
from masonrydam.errors import RunStopped
from masonrydam.results.files import IncompleteResultWarning, open_result
from masonrydam.scene.stopping import StopRequests
from scenes import sliding_block


def test_stop_within_an_implicit_step_keeps_the_last_converged_step(tmp_path, monkeypatch):
    scene = sliding_block(duration=0.4, dt=0.002, integrator="hht", joint_space="off")
    calls = {"within": 0}

    def requested(self):
        if inspect.stack()[1].function == "_stop_within_step":
            calls["within"] += 1
            if calls["within"] >= 40:
                return "interrupted"
        return None

    monkeypatch.setattr(StopRequests, "requested", requested)
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
