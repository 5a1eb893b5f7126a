"""Pushover curves (``masonrydam plot OUT.nc --pushover``, masonrydam/results/pushover.py): the force of
the DOFs a static stage drives by prescribed displacements against their displacement. Checked on the
default scene (the wall pushed 1 mm at its top beam): the curve's points are the driven nodes' mean
displacement and summed reaction at every step of the push, starting from the state before it, and
the force equals the horizontal reaction of the base with the opposite sign (statics: no horizontal
load); once the dry bed joints slide it stays on a plateau."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from masonrydam.errors import MasonrydamError
from masonrydam.results.pushover import pushover_data, pushover_figure, value_at_push


@pytest.fixture(scope="module")
def wall(default_scene_result):
    return default_scene_result


def test_pushover_data_and_figure(wall):
    ds = xr.load_dataset(wall)
    d, f, steps = pushover_data(ds)
    driven = ds.driven.sel(component="x").values > 0
    assert driven.sum() > 0 and (ds.stage.values[steps[1:]] == 1).all() and ds.stage.values[steps[0]] == 0
    np.testing.assert_allclose(d[-1], 1e-3, rtol=1e-3)  # the push: 1 mm
    np.testing.assert_allclose(f, ds.reaction.sel(component="x").values[steps][:, driven].sum(axis=1))
    assert f[-1] == pytest.approx(f[-2], rel=1e-6)  # a plateau (the bed joints slide), not a rising curve
    # statics: no horizontal load, so the actuator's force is what the base support takes back
    base = ds.reaction.sel(component="x").values[steps][:, ~driven].sum(axis=1)
    np.testing.assert_allclose(f, -base, rtol=1e-6, atol=1e-6 * abs(f).max())
    fig = pushover_figure(ds)
    ax = fig.axes[0]
    x, y = ax.lines[0].get_data()
    np.testing.assert_allclose(x, d * 1e3)
    np.testing.assert_allclose(y, f / 1e3)
    assert "kN" in ax.get_ylabel() and "mm" in ax.get_xlabel()
    assert "peak" in ax.get_legend().get_texts()[1].get_text()


@pytest.mark.slow
def test_pushover_cli_and_errors(wall, tmp_path):
    out = tmp_path / "push.png"
    r = subprocess.run([sys.executable, "-c", "import sys; from masonrydam.cli.main import main; sys.exit(main())",
                        "plot", str(wall), "--pushover", "-o", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert out.stat().st_size > 1000
    ds = xr.load_dataset(wall)
    with pytest.raises(MasonrydamError, match="components"):
        pushover_data(ds, "z")
    with pytest.raises(MasonrydamError, match="driven"):
        pushover_data(ds.drop_vars("driven"))


def test_value_at_push_reads_the_first_crossing():
    """Linear between the recorded steps where the push first reaches x; a record that goes back afterwards (the
    path-following attempts of a stalled run) is not read; NaN where the push never gets there."""
    d = np.array([0.0, 1.0, 2.0, 3.0, 1.5])
    f = np.array([0.0, 10.0, 20.0, 30.0, -5.0])
    assert value_at_push(d, f, 1.5) == pytest.approx(15.0, rel=1e-12)  # not -5 from the last record
    assert value_at_push(d, f, 3.0) == 30.0
    assert value_at_push(d, f, 0.0) == 0.0
    assert np.isnan(value_at_push(d, f, 3.5))
