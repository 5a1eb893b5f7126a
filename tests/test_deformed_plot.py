"""The deformed shape of one step (``masonrydam plot OUT.nc --deformed``, masonrydam/results/deformed.py)
and the connectivity the result file holds for it (``block_cell_nodes``, ``joint_point_nodes``).

The scene: a base block 1.0 x 0.5 m on the support, a block 'left' 0.5 x 0.5 m and a taller block 'right'
0.5 x 1.0 m on it, side by side, on dry joints (no cohesion, no tension). Under self-weight, the top of
'right' is pushed 0.1 mm to the left (it presses on 'left', and the base joints slide), then lifted
0.1 mm: at the last step the joint under 'right' is open, the vertical joint between the blocks slides
(compressed by the push) and the joint under 'left' sticks.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from matplotlib.colors import to_rgba

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import MasonrydamError
from masonrydam.results.deformed import (AUTO_FRACTION, OPENING_WIDTH, STATE_COLOURS, STATE_NAMES, STATE_WIDTHS,
                                         deformed_data, deformed_figure)

BLOCKS = {"base": (0.0, 0.0, 1.0, 0.5), "left": (0.0, 0.5, 0.5, 1.0), "right": (0.5, 0.5, 1.0, 1.5)}
H = 0.25  # element size


def scene():
    joint = {"law": "mohr_coulomb", "normal_stiffness": 1e10, "shear_stiffness": 5e9, "cohesion": 0.0,
             "friction_angle": 30.0, "residual_shear_stiffness": 0.0}
    return {"model": {"name": "lift", "thickness": 0.1},
            "mesh": {"generator": "blocks_2d", "parameters": {"element_size": H, "blocks": [
                {"x0": x0, "y0": y0, "x1": x1, "y1": y1, "group": g} for g, (x0, y0, x1, y1) in BLOCKS.items()]}},
            "materials": {g: {"youngs_modulus": 10e9, "poisson_ratio": 0.2, "density": 2000.0} for g in BLOCKS},
            "joints": {"joints": joint},
            "supports": [{"set": "base", "components": ["x", "y"]}],
            "stages": [{"name": "gravity", "steps": 1, "loads": [{"type": "self_weight"}]},
                       {"name": "push", "steps": 2, "loads": [
                           {"type": "displacement", "set": "top", "components": ["x", "y"], "value": [-1e-4, 0.0]}]},
                       {"name": "lift", "steps": 2, "loads": [
                           {"type": "displacement", "set": "top", "components": ["x", "y"], "value": [0.0, 1e-4]}]}]}


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("deformed") / "lift.nc"
    masonrydam.run(scene(), output=out)
    return out


@pytest.fixture(scope="module")
def ds(result):
    return xr.load_dataset(result)


def node_xy(ds):
    return np.stack([ds.x.values, ds.y.values], axis=1)


def test_block_connectivity_reproduces_the_elements(ds):
    from masonrydam.scene.build import build_mesh
    from masonrydam.scene.scene import as_scene

    sc = as_scene(scene())
    mesh = build_mesh(sc.normalized, sc.base_dir)
    cells = ds.block_cell_nodes.values
    assert cells.dtype == np.int32 and ds.block_cell_group.dtype == np.int32
    for name in ("block_cell_nodes", "block_cell_group", "joint_point_nodes", "joint_point_shape"):
        assert ds[name].attrs["units"] == "1" and ds[name].attrs["long_name"]
    names = json.loads(ds.block_cell_group.attrs["group_names"])
    assert names == ["base", "left", "right"]
    assert json.loads(ds.block_cell_group.attrs["group_types"]) == ["quad4"] * 3
    expected = np.vstack([b.cells for b in mesh.blocks if not b.is_interface])
    np.testing.assert_array_equal(cells, expected)  # quad4: the corners are all the nodes
    assert np.bincount(ds.block_cell_group.values).tolist() == [8, 4, 8]
    np.testing.assert_array_equal(ds.node.values, np.arange(ds.sizes["node"]))
    xy = node_xy(ds)
    for g, name in enumerate(names):
        x0, y0, x1, y1 = BLOCKS[name]
        poly = xy[cells[ds.block_cell_group.values == g]]  # (n, 4, 2)
        assert poly[..., 0].min() == pytest.approx(x0) and poly[..., 0].max() == pytest.approx(x1)
        assert poly[..., 1].min() == pytest.approx(y0) and poly[..., 1].max() == pytest.approx(y1)
        x, y = poly[..., 0], poly[..., 1]  # counter-clockwise corners: positive areas H x H
        area = 0.5 * (x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y).sum(axis=1)
        np.testing.assert_allclose(area, H * H)


def test_joint_point_nodes_interpolate_the_point_and_its_opening(ds):
    nodes, shape = ds.joint_point_nodes.values, ds.joint_point_shape.values
    assert nodes.shape == (ds.sizes["joint_point"], 2, 2) and (nodes >= 0).all()
    xy = node_xy(ds)
    for side in range(2):
        at = np.einsum("pk,pkd->pd", shape, xy[nodes[:, side]])
        np.testing.assert_allclose(at, np.stack([ds.joint_x.values, ds.joint_y.values], axis=1), atol=1e-12)
    u = ds.displacement.values[-1]
    jump = np.einsum("pk,pkd->pd", shape, u[nodes[:, 1]] - u[nodes[:, 0]])
    normal = np.stack([ds.joint_normal_x.values, ds.joint_normal_y.values], axis=1)
    opening = ds.joint_opening.values[-1]
    np.testing.assert_allclose((jump * normal).sum(axis=1), opening, atol=1e-12)
    assert opening.max() > 5e-5  # the lifted block's joint is open


def test_deformed_coordinates_and_automatic_scale(ds):
    xy = node_xy(ds)
    d = deformed_data(ds, step=4, scale=250.0)
    assert d.step == 4 and d.scale == 250.0
    np.testing.assert_allclose(d.deformed, xy + 250.0 * ds.displacement.values[4], rtol=0, atol=1e-15)
    polys = d.cell_polygons()
    assert len(polys) == 20
    np.testing.assert_allclose(polys[7], xy[ds.block_cell_nodes.values[7]] + 250.0 *
                               ds.displacement.values[4][ds.block_cell_nodes.values[7]])
    auto = deformed_data(ds)  # the last step; the largest displacement 5 % of the extent (1.5 m)
    peak = np.linalg.norm(ds.displacement.values[-1], axis=1).max()
    assert auto.step == ds.sizes["step"] - 1
    assert auto.scale * peak == pytest.approx(AUTO_FRACTION * 1.5)
    fig = deformed_figure(ds, step=4, scale=250.0, title="lift.nc")
    ax = fig.axes[0]
    (drawn,) = [c for c in ax.collections if c.get_gid() == "deformed"]
    for path, poly in zip(drawn.get_paths(), polys):
        np.testing.assert_allclose(path.vertices[:4], poly)
    assert "x 250" in ax.get_title() and "step 4" in ax.get_title() and "lift.nc" in ax.get_title()


@pytest.mark.parametrize("step", [1, -1])
def test_joint_segments_and_states(ds, step):
    k = step % ds.sizes["step"]
    state = ds.joint_state.values[k]
    if step == -1:  # the crack pattern of the lift: all three states
        assert sorted(set(state.tolist())) == [0, 1, 2]
    d = deformed_data(ds, step=step, scale=100.0)
    assert sorted(d.joint_point.tolist()) == list(range(ds.sizes["joint_point"]))
    np.testing.assert_array_equal(d.joint_state, state[d.joint_point])
    np.testing.assert_allclose(d.joint_opening, ds.joint_opening.values[k][d.joint_point])
    assert d.counts == {name: int((state == s).sum()) for s, name in enumerate(STATE_NAMES)}
    # the middle vertex: the joint point on the deformed mid-surface (lumped rule: points at the nodes)
    nodes = ds.joint_point_nodes.values[d.joint_point]
    u = ds.displacement.values[k]
    xy = node_xy(ds)
    mid = 0.5 * (xy[nodes[:, 0]] + xy[nodes[:, 1]] + 100.0 * (u[nodes[:, 0]] + u[nodes[:, 1]]))
    corner = np.einsum("pk,pkd->pd", ds.joint_point_shape.values[d.joint_point], mid)
    np.testing.assert_allclose(d.joint_segments[:, 1], corner, atol=1e-12)
    # undeformed (tiny scale), the segments tile the three joint lines of 0.5 m each
    tiny = deformed_data(ds, step=step, scale=1e-9)
    lengths = np.linalg.norm(np.diff(tiny.joint_segments, axis=1), axis=2).sum()
    assert lengths == pytest.approx(1.5, rel=1e-6)
    fig = deformed_figure(ds, step=step, scale=100.0)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    for s, name in enumerate(STATE_NAMES):
        (lines,) = [c for c in ax.collections if c.get_gid() == f"joints_{name}"]
        segs = lines.get_segments()
        assert len(segs) == d.counts[name]
        np.testing.assert_allclose(np.array(segs).reshape(-1, 3, 2), d.joint_segments[d.joint_state == s])
        if segs:
            np.testing.assert_allclose(lines.get_colors()[0], to_rgba(STATE_COLOURS[s]))
        assert f"{name}: {d.counts[name]} joint points" in labels
    if step == -1:  # the most open point is drawn widest
        (lines,) = [c for c in ax.collections if c.get_gid() == "joints_open"]
        opening = d.joint_opening[d.joint_state == 2]
        np.testing.assert_allclose(lines.get_linewidths(), STATE_WIDTHS[2] + OPENING_WIDTH * opening / opening.max())


def test_errors(ds):
    n = ds.sizes["step"]
    with pytest.raises(MasonrydamError, match=rf"--step {n}: not a step of the result \(0 to {n - 1}"):
        deformed_data(ds, step=n)
    with pytest.raises(MasonrydamError, match=rf"--step {-n - 1}: the result has {n} steps"):
        deformed_data(ds, step=-n - 1)
    with pytest.raises(MasonrydamError, match="--scale"):
        deformed_data(ds, scale=0.0)
    with pytest.raises(MasonrydamError, match="older masonrydam"):
        deformed_data(ds.drop_vars("block_cell_nodes"))
    flat = xr.Dataset(coords={"component": ["x", "y", "z"], "step": [0]})
    with pytest.raises(MasonrydamError, match="3D results are not drawn"):
        deformed_data(flat)


def test_cli(result, ds, tmp_path, capsys, monkeypatch):
    from matplotlib.image import imread

    monkeypatch.chdir(tmp_path)
    assert main(["plot", str(result), "--deformed", "--step", "3", "--scale", "200"]) == 0
    out = tmp_path / "lift_deformed.png"
    image = imread(out)
    assert image.shape[:2] == (int(6.5 * 110), int(8.0 * 110))
    assert (np.abs(image[..., :3] - np.array(to_rgba("tab:red"))[:3]).max(axis=-1) < 0.05).sum() > 20  # open joints
    capsys.readouterr()
    assert main(["plot", str(result), "--deformed", "--step", "99", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--step 99" in err and f"0 to {ds.sizes['step'] - 1}" in err
    assert main(["plot", str(result), "--deformed", "--pushover"]) == 2
    assert "--deformed and --pushover" in capsys.readouterr().err
    assert main(["plot", str(result), "--deformed", "--mode", "1"]) == 2
    assert "--deformed and --mode" in capsys.readouterr().err
    assert main(["plot", str(result), "--step", "2"]) == 2
    assert "--step applies to the deformed shape" in capsys.readouterr().err
