"""``masonrydam plot OUT.nc --mode N`` (masonrydam.cli.main, masonrydam.results.mode_plot): the mode shape
of a result with a modal stage.

What is drawn is read back from the figure's artists: the deformed nodes (the PathCollection with
``gid="deformed"``) lie at ``coords + scale * mode_shape`` of the chosen mode, with ``scale`` given or
automatic (largest nodal displacement 10 % of the largest extent of the model); the undeformed nodes and
the joints (undeformed) are there; the title gives the dataset's frequency, period and effective mass
ratios. A result without modes, a mode number out of range and NaN modes (a modal stage that did not run)
are errors of the CLI (exit code 2, message naming --mode).

Scenes: the rigid block on an elastic joint of tests/test_modal_stage.py (2D, 4 modes), and a 3D
block on a base (3 modes).
"""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import MasonrydamError
from masonrydam.results.mode_plot import AUTO_FRACTION, mode_figure

from scenes import ELASTIC_JOINT_BLOCK, block_on_elastic_joint  # the rigid block on a joint of the modal stage tests

B, KN, KS, RHO = (ELASTIC_JOINT_BLOCK.width, ELASTIC_JOINT_BLOCK.normal_stiffness, ELASTIC_JOINT_BLOCK.shear_stiffness,
                  ELASTIC_JOINT_BLOCK.density)

N_MODES = 4


def scene(modes=N_MODES):
    """The modal stage's test scene with ``modes`` modes, or without a modal stage (``modes = 0``)."""
    s = block_on_elastic_joint(modes=modes or 1)
    if not modes:
        s["stages"] = s["stages"][:1]
    return s


def scene_3d():
    return {
        "model": {"name": "block_modes_3d", "dimension": 3},
        "mesh": {"generator": "blocks_3d", "parameters": {
            "blocks": [{"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 0.25, "group": "base"},
                       {"x0": 0, "y0": 0, "z0": 0.25, "x1": 1, "y1": 0.5, "z1": 1.0, "group": "block"}],
            "element_size": 0.25}},
        "materials": {g: {"youngs_modulus": "200 GPa", "poisson_ratio": 0.0, "density": RHO}
                      for g in ("base", "block")},
        "joints": {"joints": {"law": "linear", "normal_stiffness": KN, "shear_stiffness": KS}},
        "supports": [{"set": "base_nodes"}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "modes", "type": "modal", "modes": 3}],
    }


def _write(tmp_path_factory, name, sc):
    path = tmp_path_factory.mktemp(name) / f"{name}.nc"
    masonrydam.run(sc, output=path).close()
    return path


@pytest.fixture(scope="module")
def modal_nc(tmp_path_factory):
    return _write(tmp_path_factory, "modal", scene())


@pytest.fixture(scope="module")
def ds(modal_nc):
    with xr.open_dataset(modal_nc) as d:
        return d.load()


def coords_of(ds):
    return np.stack([ds[str(c)].values for c in ds.component.values], axis=1)


def shape_of(ds, mode):
    return ds.mode_shape.sel(mode=mode).transpose("node", "component").values


def artist(fig, gid, kind="collections"):
    ax = fig.axes[0]
    hits = [a for a in getattr(ax, kind) if a.get_gid() == gid]
    assert hits, f"no artist with gid {gid!r}"
    return hits


def run_cli(capsys, *args):
    rc = main(["plot", *map(str, args)])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


@pytest.mark.parametrize("mode", [1, 2, N_MODES])
def test_deformed_nodes_are_coords_plus_scaled_shape(ds, mode):
    fig = mode_figure(ds, mode, scale=0.5)
    x = coords_of(ds)
    np.testing.assert_allclose(artist(fig, "deformed")[0].get_offsets(), x + 0.5 * shape_of(ds, mode),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(artist(fig, "undeformed")[0].get_offsets(), x, rtol=0, atol=0)
    # a negative scale flips the (arbitrary) sign of the shape
    fig = mode_figure(ds, mode, scale=-2.0)
    np.testing.assert_allclose(artist(fig, "deformed")[0].get_offsets(), x - 2.0 * shape_of(ds, mode),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("mode", [1, 3])
def test_automatic_scale(ds, mode):
    x = coords_of(ds)
    phi = shape_of(ds, mode)
    extent = max(np.ptp(x[:, 0]), np.ptp(x[:, 1]))
    assert extent == pytest.approx(B)  # the block is 2 m wide, 1.5 m high with its base
    drawn = np.asarray(artist(mode_figure(ds, mode), "deformed")[0].get_offsets()) - x
    # the largest nodal displacement drawn is 10 % of the largest extent ...
    assert np.linalg.norm(drawn, axis=1).max() == pytest.approx(AUTO_FRACTION * extent, rel=1e-12)
    # ... and the drawing is the shape times one factor
    s = AUTO_FRACTION * extent / np.linalg.norm(phi, axis=1).max()
    np.testing.assert_allclose(drawn, s * phi, rtol=0, atol=1e-12)


def test_joints_are_drawn_undeformed(ds):
    lines = artist(mode_figure(ds, 1), "joints", "lines")
    pts = np.vstack([np.column_stack(ln.get_data()) for ln in lines])
    jp = np.column_stack([ds.joint_x.values, ds.joint_y.values])
    assert len(pts) == len(jp)
    np.testing.assert_array_equal(np.unique(pts, axis=0), np.unique(jp, axis=0))
    assert all(np.ptp(np.column_stack(ln.get_data())[:, 1]) == 0 for ln in lines)  # the bed joint is horizontal


def test_title_gives_frequency_period_and_mass_ratios(ds):
    for mode in (1, 2):
        k = mode - 1
        title = mode_figure(ds, mode, title="modal.nc").axes[0].get_title()
        f, period = float(ds.frequency.values[k]), float(ds.period.values[k])
        rx, ry = 100 * ds.effective_mass_ratio.values[k]
        assert title.startswith("modal.nc\n")
        assert f"mode {mode}:" in title
        assert f"f = {f:.4g} Hz" in title
        assert f"T = {period:.4g} s" in title
        assert f"x {rx:.1f} %" in title and f"y {ry:.1f} %" in title
    # the sliding mode (first, horizontal) carries a good part of the mass in x
    assert 100 * ds.effective_mass_ratio.values[0, 0] > 10


def test_figure_errors(ds):
    with pytest.raises(MasonrydamError, match=r"--mode 0: .* give a mode number from 1 to 4"):
        mode_figure(ds, 0)
    with pytest.raises(MasonrydamError, match="--scale"):
        mode_figure(ds, 1, scale=0.0)
    with pytest.raises(MasonrydamError, match="--scale"):
        mode_figure(ds, 1, scale=float("nan"))


@pytest.mark.slow
def test_cli_writes_png(modal_nc, tmp_path, capsys, monkeypatch):
    png = tmp_path / "m2.png"
    rc, out, err = run_cli(capsys, modal_nc, "--mode", 2, "-o", png)
    assert rc == 0, err
    assert f"wrote {png}" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    monkeypatch.chdir(tmp_path)  # default name: RESULT_modeN.png in the current folder
    rc, out, err = run_cli(capsys, modal_nc, "--mode", 1, "--scale", 0.1)
    assert rc == 0, err
    assert (tmp_path / "modal_mode1.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_result_without_modes(tmp_path_factory, tmp_path, capsys):
    path = _write(tmp_path_factory, "static", scene(modes=None))
    png = tmp_path / "x.png"
    rc, out, err = run_cli(capsys, path, "--mode", 1, "-o", png)
    assert rc == 2 and out == ""
    assert "--mode" in err and "has no modal stage" in err
    assert 'add { type = "modal", modes = N } to [[stages]]' in err
    assert not png.exists()


@pytest.mark.parametrize("mode", [0, N_MODES + 1, -1])
def test_cli_mode_out_of_range(modal_nc, tmp_path, capsys, mode):
    rc, out, err = run_cli(capsys, modal_nc, "--mode", mode, "-o", tmp_path / "x.png")
    assert rc == 2 and out == ""
    assert f"--mode {mode}" in err and f"from 1 to {N_MODES}" in err
    assert not (tmp_path / "x.png").exists()


def test_cli_nan_modes(tmp_path, capsys):
    """A run that fails before its modal stage (the block is lifted off its joint) leaves the modes at
    their NaN fill value."""
    sc = scene()
    sc["joints"]["joints"] = {"normal_stiffness": KN, "shear_stiffness": KS, "friction_angle": 30.0}
    sc["stages"].insert(1, {"name": "lift", "steps": 2, "loads": [
        {"type": "edge_traction", "set": "top_edge", "traction": [0.0, 1e5]}]})  # 200 kN up, 39 kN weight
    path = tmp_path / "failed.nc"
    with pytest.raises(MasonrydamError):
        masonrydam.run(sc, output=path)
    with xr.open_dataset(path) as d:
        assert d.attrs["status"] == "failed" and np.isnan(d.frequency.values).all()
    rc, out, err = run_cli(capsys, path, "--mode", 1, "-o", tmp_path / "x.png")
    assert rc == 2 and out == ""
    assert "warning:" in err and "incomplete result" in err  # open_result's one-line note
    assert "--mode 1" in err and "NaN" in err and "modal stage did not run" in err and "status 'failed'" in err
    assert not (tmp_path / "x.png").exists()


def test_cli_options_for_histories_only(modal_nc, tmp_path, capsys):
    rc, _, err = run_cli(capsys, modal_nc, "--mode", 1, "--nodes", 3, "-o", tmp_path / "x.png")
    assert rc == 2 and "--nodes" in err
    rc, _, err = run_cli(capsys, modal_nc, "--scale", 2.0, "-o", tmp_path / "x.png")
    assert rc == 2 and "--scale" in err and "--mode" in err


@pytest.mark.slow
def test_3d_mode_shape(tmp_path_factory):
    path = _write(tmp_path_factory, "modal3d", scene_3d())
    with xr.open_dataset(path) as d:
        d3 = d.load()
    assert d3.sizes["component"] == 3
    fig = mode_figure(d3, 2, scale=0.25)
    ax = fig.axes[0]
    assert ax.name == "3d"
    x = coords_of(d3)
    # Path3DCollection keeps the data coordinates in _offsets3d (get_offsets gives the 2D projection)
    drawn = np.column_stack([np.asarray(v, dtype=float) for v in artist(fig, "deformed")[0]._offsets3d])
    np.testing.assert_allclose(drawn, x + 0.25 * shape_of(d3, 2), rtol=0, atol=1e-12)
    drawn = np.column_stack([np.asarray(v, dtype=float) for v in artist(mode_figure(d3, 1), "deformed")[0]._offsets3d])
    assert np.linalg.norm(drawn - x, axis=1).max() == pytest.approx(AUTO_FRACTION * 1.0, rel=1e-12)
    f = float(d3.frequency.values[1])
    assert f"f = {f:.4g} Hz" in ax.get_title() and "z " in ax.get_title()
    fig.savefig(tmp_path_factory.mktemp("png") / "m3d.png")
