"""What ``masonrydam plot OUT.nc`` draws (masonrydam/results/histories.py), checked on the
matplotlib Figure objects (lines, their data, axis labels), not on the PNG:

- dynamic results: the ground acceleration at the record's own sampling rate (the result keeps each
  record, ``ground_acceleration_record_<c>`` on its own time), so its peak between two output steps is
  drawn; panels with nothing to draw are left out; legends stand outside the axes;
- static results: the default figure is the pushover curve when the result has driven DOFs, else the
  histories against the load factor of the stages;
- ``--quantity VAR --select DIM=VALUE``: any step variable, one line per value left, errors that name the
  variable, dimension or value and list the choices.
"""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import MasonrydamError
from masonrydam.results.histories import (MAX_LINES, default_figure, history_figure, parse_selection,
                                          quantity_figure, step_axis)
from masonrydam.results.pushover import pushover_data
from scenes import sliding_block

#: the x record of the shaking stage: 0.2 m/s2 with a spike of 3 m/s2 at t = 0.015 s (between two output
#: steps, every 0.01 s), 151 samples at 1 ms of which the 0.1 s stage uses 101 (2.5 m/s2 at 0.12 s is after it)
REC_X = np.full(151, 0.2)
REC_X[15:20] = [3.0, 1.5, 0.8, 0.4, 0.2]
REC_X[120] = 2.5
DT_X = 0.001
#: the y record: one sine period of 0.5 m/s2, 41 samples at 2.5 ms (its peak at 0.025 s, between output steps)
REC_Y = 0.5 * np.sin(np.linspace(0.0, 2.0 * np.pi, 41))
DT_Y = 0.0025
#: the x record of the second dynamic stage (0.05 s, starting at 0.1 s)
REC_X2 = np.linspace(0.0, -1.0, 11)
DT_X2 = 0.005


def record_scene():
    """The sliding block of scenes.sliding_block (mu = 0.2) shaken by the two-component record REC_X, REC_Y,
    then by an aftershock REC_X2 at another sampling rate."""
    return sliding_block(overrides={
        "model.name": "record_block",
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "shake", "type": "dynamic", "dt": 0.002, "duration": 0.1,
                    "ground_motion": {"x": {"values": REC_X.tolist(), "dt": DT_X},
                                      "y": {"values": REC_Y.tolist(), "dt": DT_Y}},
                    "output": {"stride": 5}},
                   {"name": "aftershock", "type": "dynamic", "dt": 0.005, "duration": 0.05,
                    "ground_motion": {"x": {"values": REC_X2.tolist(), "dt": DT_X2}}}]})


@pytest.fixture(scope="module")
def dyn_nc(tmp_path_factory):
    out = tmp_path_factory.mktemp("dyn") / "shake.nc"
    masonrydam.run(record_scene(), output=out)
    return out


@pytest.fixture(scope="module")
def dyn(dyn_nc):
    return xr.load_dataset(dyn_nc)


@pytest.fixture(scope="module")
def wall_nc(default_scene_result):
    return default_scene_result  # gravity and precompression, then a 1 mm push


@pytest.fixture(scope="module")
def wall(wall_nc):
    return xr.load_dataset(wall_nc)


@pytest.fixture
def drawn(monkeypatch):
    """The figures the CLI saves (Figure.savefig captured, nothing written)."""
    figures = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: figures.append(self))
    return figures


def lines_by_label(ax):
    return {line.get_label(): line for line in ax.get_lines()}


def dynamic_steps(ds):
    return np.flatnonzero(np.isfinite(ds.time.values))


# ----------------------------------------------------------------------------------------------
# the ground-acceleration record in the result
# ----------------------------------------------------------------------------------------------

def test_result_keeps_each_record_at_its_own_rate(dyn):
    rx, ry = dyn.ground_acceleration_record_x, dyn.ground_acceleration_record_y
    for r, c in ((rx, "x"), (ry, "y")):
        assert r.attrs["units"] == "m/s2" and "own sampling rate" in r.attrs["long_name"]
        assert r.dims == (f"ground_record_{c}",)
        t = r[f"ground_record_time_{c}"]  # its own time, a coordinate of the variable
        assert t.attrs["units"] == "s" and "first dynamic stage" in t.attrs["long_name"]
    # x: 101 samples of the 0.1 s stage (the record's 151 are cut at the stage's end), a NaN between the
    # stages, then the second stage's 11 samples from its start at 0.1 s
    tx = rx.ground_record_time_x.values
    assert rx.size == 101 + 1 + 11 == dyn.attrs["stage2_ground_motion_x_npts"] + 102
    np.testing.assert_allclose(tx[:101], np.arange(101) * DT_X, atol=1e-12)
    np.testing.assert_array_equal(rx.values[:101], REC_X[:101])
    assert np.isnan(rx.values[101])
    np.testing.assert_allclose(tx[102:], 0.1 + np.arange(11) * DT_X2, atol=1e-12)
    np.testing.assert_array_equal(rx.values[102:], REC_X2)
    # y: the whole record (41 samples over 0.1 s), the second stage has no y motion
    assert ry.size == 41 == dyn.attrs["stage1_ground_motion_y_npts"]
    np.testing.assert_array_equal(ry.values, REC_Y)
    # the output steps (every 0.01 s) miss both peaks: the reason the figure draws the records
    assert np.nanmax(dyn.ground_acceleration.sel(component="x").values) == pytest.approx(0.2)
    assert np.nanmax(dyn.ground_acceleration.sel(component="y").values) < 0.49


# ----------------------------------------------------------------------------------------------
# dynamic histories
# ----------------------------------------------------------------------------------------------

def test_dynamic_figure_draws_the_records_with_their_peaks(dyn):
    fig = history_figure(dyn, "shake.nc")
    ground, disp, joint, energy = fig.axes
    assert ground.get_ylabel() == "ground acc. [m/s2]"
    lines = lines_by_label(ground)
    assert set(lines) == {"a_g,x", "a_g,y"}
    x, y = lines["a_g,x"].get_xdata(), lines["a_g,x"].get_ydata()
    np.testing.assert_array_equal(x, dyn.ground_record_time_x.values)
    np.testing.assert_array_equal(y, dyn.ground_acceleration_record_x.values)
    assert np.nanmax(y) == dyn.attrs["stage1_ground_motion_x_pga_m_s2"] == 3.0  # the spike, at its full height
    assert np.isfinite(y).sum() == 101 + 11  # every sample of both stages
    yy = lines["a_g,y"].get_ydata()
    assert len(yy) == dyn.attrs["stage1_ground_motion_y_npts"] == 41
    assert np.max(yy) == pytest.approx(dyn.attrs["stage1_ground_motion_y_pga_m_s2"]) == pytest.approx(0.5)
    # the response panels: against the time of the dynamic steps, one time range for every panel
    t = dyn.time.values[dynamic_steps(dyn)]
    for ax in fig.axes:
        assert ax.get_xlabel() == "time [s]"
        assert ax.get_xlim() == pytest.approx((t[0], t[-1]))
    for ax in (disp, joint, energy):
        for line in ax.get_lines():
            np.testing.assert_array_equal(line.get_xdata(), t)
    assert disp.get_ylabel() == "u_x [m] (relative)" and "[m]" in joint.get_ylabel()
    assert energy.get_ylabel() == "energy [J]"
    for line in energy.get_lines():  # no flat lines of zeros
        assert np.abs(line.get_ydata()).max() > 0
    assert "joint_bond_break" not in lines_by_label(energy)


def test_legends_stand_outside_the_axes(dyn):
    fig = history_figure(dyn, "shake.nc")
    fig.canvas.draw()
    for ax in fig.axes:
        legend = ax.get_legend()
        assert legend is not None and legend.get_texts()
        assert legend.get_window_extent().x0 >= ax.get_window_extent().x1 - 1e-6


def test_file_without_records_and_result_without_motion(dyn):
    old = dyn.drop_vars([v for v in dyn.variables if "record" in str(v)])  # a file written before the records
    fig = history_figure(old, "old.nc")
    lines = lines_by_label(fig.axes[0])
    assert set(lines) == {"a_g,x (output steps)", "a_g,y (output steps)"}  # said so in the legend
    steps = dynamic_steps(dyn)
    np.testing.assert_array_equal(lines["a_g,x (output steps)"].get_ydata(),
                                  dyn.ground_acceleration.sel(component="x").values[steps])
    # no ground motion at all (e.g. an initial-velocity stage): the panel is left out, not drawn as zeros
    still = old.assign(ground_acceleration=old.ground_acceleration * 0.0)
    fig = history_figure(still, "still.nc")
    assert len(fig.axes) == 3 and "ground" not in " ".join(ax.get_ylabel() for ax in fig.axes)


@pytest.mark.slow
def test_history_figure_still_importable_from_the_cli(dyn):
    from masonrydam.cli.main import history_figure as from_cli

    fig = from_cli(dyn, "shake.nc", "x", None, [0])
    same = history_figure(dyn, "s", "x", None, [0])
    assert [ax.get_ylabel() for ax in fig.axes] == [ax.get_ylabel() for ax in same.axes]
    assert {"slip, point 0"} <= set(lines_by_label(fig.axes[2]))


def synthetic_3d(n_steps=6):
    """A small static 3D result (two stages; 2 nodes, 2 joint points) with known joint slips."""
    t = np.linspace(0.0, 1.0, n_steps)
    slip = np.zeros((n_steps, 2, 2))
    slip[:, 1, 0] = 3e-4 * t
    slip[:, 1, 1] = -4e-4 * t  # |slip| = 5e-4 t
    opening = np.zeros((n_steps, 2))
    opening[:, 1] = 1e-5 * t
    disp = np.zeros((n_steps, 2, 3))
    disp[:, 1, 0] = 1e-3 * t
    stage = np.array([0, 0, 0, 1, 1, 1])
    lam = np.array([1 / 3, 2 / 3, 1.0, 1 / 3, 2 / 3, 1.0])
    ds = xr.Dataset(
        {"displacement": (("step", "node", "component"), disp, {"units": "m", "long_name": "nodal displacement"}),
         "joint_slip": (("step", "joint_point", "shear_direction"), slip, {"units": "m", "long_name": "slip"}),
         "joint_opening": (("step", "joint_point"), opening, {"units": "m", "long_name": "opening"}),
         "load_factor": (("step",), lam), "stage": (("step",), stage, {"stage_names": '["dead", "push"]'})},
        coords={"step": np.arange(n_steps), "node": [4, 9], "component": ["x", "y", "z"],
                "joint_point": [0, 1], "shear_direction": ["t1", "t2"]})
    return ds


def test_3d_joint_slip_as_magnitude_and_components():
    ds = synthetic_3d()
    fig = history_figure(ds, "block3d.nc")
    disp, joint = fig.axes
    lines = lines_by_label(joint)
    assert set(lines) == {"|slip|, point 1", "slip t1, point 1", "slip t2, point 1", "opening, point 1"}
    np.testing.assert_allclose(lines["|slip|, point 1"].get_ydata(), 5e-4 * np.linspace(0.0, 1.0, 6))
    np.testing.assert_array_equal(lines["slip t2, point 1"].get_ydata(), ds.joint_slip.values[:, 1, 1])
    # point 0 never moves: asked for, it is drawn as one line (its slip), not as four lines of zeros
    fig = history_figure(ds, "block3d.nc", joints=[0, 1])
    assert [k for k in lines_by_label(fig.axes[1]) if "point 0" in k] == ["|slip|, point 0"]


# ----------------------------------------------------------------------------------------------
# static results: the pushover by default, else the load factor on the x axis
# ----------------------------------------------------------------------------------------------

def test_static_default_figure_is_the_pushover(wall, wall_nc, tmp_path, drawn):
    d, f, _ = pushover_data(wall, "x")
    fig = default_figure(wall, "wall.nc")
    (ax,) = fig.axes
    curve = ax.get_lines()[0]
    np.testing.assert_allclose(curve.get_xdata(), d * 1e3)  # the driven DOFs' displacement, mm
    np.testing.assert_allclose(curve.get_ydata(), f / 1e3)
    assert ax.get_xlabel() == "prescribed displacement, x (mm)" and "(kN)" in ax.get_ylabel()
    # the command line draws the same figure without options
    assert main(["plot", str(wall_nc), "-o", str(tmp_path / "w.png")]) == 0
    np.testing.assert_allclose(drawn[-1].axes[0].get_lines()[0].get_xdata(), d * 1e3)
    # histories when nodes are asked for
    assert main(["plot", str(wall_nc), "--nodes", str(int(wall.node.values[0])), "-o", str(tmp_path / "n.png")]) == 0
    assert "load factor" in drawn[-1].axes[0].get_xlabel()


def test_static_histories_against_the_load_factor(wall):
    ds = wall.drop_vars("driven")  # no pushover: histories
    fig = default_figure(ds, "wall.nc")
    lam, stage = ds.load_factor.values, ds.stage.values
    x = stage + lam  # the two stages span 0-1 and 1-2, each with its load factor
    for ax in fig.axes:
        assert ax.get_xlabel().startswith("load factor within each stage")
        for line in ax.get_lines():
            np.testing.assert_allclose(line.get_xdata(), x)
        names = [t.get_text() for t in ax.get_xticklabels(minor=True)]
        assert names == ["gravity_and_precompression", "lateral_push"]
    disp = fig.axes[0]
    (line,) = disp.get_lines()
    u = ds.displacement.sel(component="x").values
    k = int(np.argmax(np.abs(u).max(axis=0)))
    np.testing.assert_array_equal(line.get_ydata(), u[:, k])
    assert disp.get_ylabel() == "u_x [m]"
    # one stage: its own load factor, from 0 to 1
    push = ds.isel(step=np.flatnonzero(stage == 1))
    fig = history_figure(push, "push")
    assert fig.axes[0].get_xlabel() == "load factor of stage 'lateral_push' (0 to 1)"
    np.testing.assert_array_equal(fig.axes[0].get_lines()[0].get_xdata(), push.load_factor.values)
    # a load factor that goes back (arc length): the step number
    back = ds.assign(load_factor=ds.load_factor.where(ds.step != ds.step[-2], 0.1))
    axis = step_axis(back)
    assert axis.kind == "step" and "arc length" in axis.label
    np.testing.assert_array_equal(axis.x, np.arange(ds.sizes["step"]))


# ----------------------------------------------------------------------------------------------
# --quantity VAR --select DIM=VALUE
# ----------------------------------------------------------------------------------------------

def test_quantity_with_selections(dyn):
    steps = dynamic_steps(dyn)
    t = dyn.time.values[steps]
    fig = quantity_figure(dyn, "joint_opening", parse_selection(["joint_point=12"]), title="shake.nc")
    (ax,) = fig.axes
    (line,) = ax.get_lines()
    np.testing.assert_array_equal(line.get_xdata(), t)
    np.testing.assert_array_equal(line.get_ydata(), dyn.joint_opening.sel(joint_point=12).values[steps])
    assert ax.get_xlabel() == "time [s]"
    assert ax.get_ylabel().replace("\n", " ") == f"{dyn.joint_opening.attrs['long_name']} [m]"
    assert "joint_point=12" in ax.get_title()
    node = int(dyn.node.values[3])
    fig = quantity_figure(dyn, "displacement", {"component": "x", "node": str(node)})
    (line,) = fig.axes[0].get_lines()
    np.testing.assert_array_equal(line.get_ydata(), dyn.displacement.sel(component="x", node=node).values[steps])
    # what is left after the selection: one line per value, labelled with it
    nodes = dyn.node.values[:2]
    fig = quantity_figure(dyn, "velocity", {"node": f"{nodes[0]},{nodes[1]}"})
    lines = lines_by_label(fig.axes[0])
    assert len(lines) == 4 and f"node={nodes[1]}, component=y" in lines
    np.testing.assert_array_equal(lines[f"node={nodes[1]}, component=y"].get_ydata(),
                                  dyn.velocity.sel(node=nodes[1], component="y").values[steps])
    assert "[m/s]" in fig.axes[0].get_ylabel() and fig.axes[0].get_legend() is not None
    # a record against its own time
    fig = quantity_figure(dyn, "ground_acceleration_record_y")
    (line,) = fig.axes[0].get_lines()
    assert len(line.get_xdata()) == 41 and np.max(line.get_ydata()) == pytest.approx(0.5)
    assert "[m/s2]" in fig.axes[0].get_ylabel()


def test_quantity_of_a_static_result_against_the_load_factor(wall):
    fig = quantity_figure(wall, "reaction", {"component": "y", "node": str(int(wall.node.values[0]))})
    (ax,) = fig.axes
    np.testing.assert_allclose(ax.get_lines()[0].get_xdata(), wall.stage.values + wall.load_factor.values)
    assert ax.get_xlabel().startswith("load factor") and "[N]" in ax.get_ylabel()


def test_quantity_errors_name_the_choices(dyn):
    with pytest.raises(MasonrydamError, match=r"--quantity 'joint_openng': no such variable.*joint_opening"):
        quantity_figure(dyn, "joint_openng")
    with pytest.raises(MasonrydamError, match=r"'joint_x' has no step dimension.*joint_opening"):
        quantity_figure(dyn, "joint_x")
    n = dyn.sizes["joint_point"]
    assert n > MAX_LINES
    with pytest.raises(MasonrydamError, match=rf"{n} lines after the selection, more than {MAX_LINES}: select "
                                              rf"along joint_point \({n} values\), shear_direction"):
        quantity_figure(dyn, "joint_slip")
    with pytest.raises(MasonrydamError, match=r"has no dimension 'node'; its dimensions to select: joint_point"):
        quantity_figure(dyn, "joint_opening", {"node": "3"})
    with pytest.raises(MasonrydamError, match=rf"'99' is not a value of 'joint_point'.*0 to {n - 1}"):
        quantity_figure(dyn, "joint_opening", {"joint_point": "99"})
    with pytest.raises(MasonrydamError, match=r"'a' is not a value of 'joint_point'"):
        quantity_figure(dyn, "joint_opening", {"joint_point": "a"})
    with pytest.raises(MasonrydamError, match=r"'w' is not a value of 'component'.*x, y"):
        quantity_figure(dyn, "displacement", {"component": "w"})
    with pytest.raises(MasonrydamError, match=r"'step' is the x axis"):
        quantity_figure(dyn, "joint_opening", {"step": "3"})
    with pytest.raises(MasonrydamError, match="DIM=VALUE"):
        parse_selection(["joint_point"])


def test_quantity_on_the_command_line(dyn_nc, tmp_path, monkeypatch, capsys, drawn):
    monkeypatch.chdir(tmp_path)
    assert main(["plot", str(dyn_nc), "--quantity", "joint_opening", "--select", "joint_point=12"]) == 0
    assert "wrote shake_joint_opening.png" in capsys.readouterr().out
    (line,) = drawn[-1].axes[0].get_lines()
    assert len(line.get_xdata()) == len(dynamic_steps(xr.load_dataset(dyn_nc)))
    assert main(["plot", str(dyn_nc), "--quantity", "displacement", "--select", "component=x", "node=27"]) == 0
    assert len(drawn[-1].axes[0].get_lines()) == 1
    for argv, text in [
        (["--quantity", "nothing"], "no such variable"),
        (["--quantity", "joint_slip"], "select along joint_point"),
        (["--quantity", "joint_opening", "--select", "joint_point=1000"], "not a value of 'joint_point'"),
        (["--select", "joint_point=1"], "--select applies to --quantity"),
        (["--quantity", "joint_opening", "--nodes", "27"], "--select node=VALUE"),
        (["--quantity", "joint_opening", "--mode", "1"], "--mode and --quantity draw different figures"),
    ]:
        assert main(["plot", str(dyn_nc), *argv]) == 2, argv
        assert text in capsys.readouterr().err, argv
