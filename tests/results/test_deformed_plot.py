"""The deformed shape of one step (``masonrydam plot OUT.nc --deformed``, masonrydam/results/deformed.py)
and the connectivity the result file holds for it (``block_cell_nodes``, ``joint_point_nodes``).

The scene: a base block 1.0 x 0.5 m on the support, a block 'left' 0.5 x 0.5 m and a taller block 'right'
0.5 x 1.0 m on it, side by side, on dry joints (no cohesion, no tension). Under self-weight, the top of
'right' is pushed 0.1 mm to the left (it presses on 'left', and the base joints slide), then lifted
0.1 mm: at the last step the joint under 'right' is open, the vertical joint between the blocks slides
(compressed by the push) and the joint under 'left' sticks.

3D results are drawn as a slice (``--slice AXIS=VALUE``): hand-made one-cell results (a unit cube, two
tetrahedra) for the geometry of the cut, and the same three blocks 0.25 m thick (y), one element through the
thickness, for the joints.
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
                                         DeformedSlice, deformed_data, deformed_figure)

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
    from masonrydam.scene import build_mesh
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
    with pytest.raises(MasonrydamError, match=r"--slice y=0.1: slices are for 3D results; this result is 2D"):
        deformed_data(ds, slice="y=0.1")


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


# ---------------------------------------------------------------------------------------------- 3D: slices

CUBE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
#: a tetrahedron cut by z = 0.5 in a triangle, and one cut in a square (an edge along x at z = 0, one along y at z = 1)
TET_TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
TET_SQUARE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 1], [0, 0, 1]], float)


def cells_dataset(solids, u=None):
    """A one-step 3D result with the cells ``solids`` ([(type, corners (k, 3))]), each its own nodes and group,
    without joints; ``u`` (n_node, 3) the displacement (default nil)."""
    xyz = np.vstack([c for _, c in solids])
    cells = np.full((len(solids), 8), -1, np.int32)
    first = 0
    for i, (_, c) in enumerate(solids):
        cells[i, :len(c)] = np.arange(first, first + len(c))
        first += len(c)
    u = np.zeros_like(xyz) if u is None else u
    group = xr.DataArray(np.arange(len(solids), dtype=np.int32), dims="block_cell",
                         attrs={"group_types": json.dumps([t for t, _ in solids]),
                                "group_names": json.dumps([f"g{i}" for i in range(len(solids))])})
    return xr.Dataset({"x": ("node", xyz[:, 0]), "y": ("node", xyz[:, 1]), "z": ("node", xyz[:, 2]),
                       "displacement": (("step", "node", "component"), u[None]),
                       "stage": ("step", [0]), "load_factor": ("step", [1.0]),
                       "block_cell_nodes": (("block_cell", "block_cell_node"), cells), "block_cell_group": group},
                      coords={"node": np.arange(len(xyz)), "component": ["x", "y", "z"], "step": [0]})


def shoelace(poly):
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def test_slice_of_a_hexahedron_and_of_tetrahedra():
    big = 1.0 + 2.0 * CUBE + [0.0, 1.0, 2.0]  # the cube [1, 3] x [2, 4] x [3, 5]
    d = deformed_data(cells_dataset([("hex8", big)]), slice="z=3.5", scale=1.0)
    assert isinstance(d, DeformedSlice) and (d.axis, d.value, d.plane_axes) == ("z", 3.5, ("x", "y"))
    (poly,) = d.cell_polygons(False)
    np.testing.assert_allclose(poly, [[1, 2], [3, 2], [3, 4], [1, 4]])  # counter-clockwise from (1, 2)
    assert shoelace(poly) == pytest.approx(4.0)
    np.testing.assert_array_equal(d.polygon_nodes[0], [[0, 4], [1, 5], [2, 6], [3, 7]])  # the vertical edges
    np.testing.assert_allclose(d.polygon_t[0], 0.25)
    (side,) = deformed_data(cells_dataset([("hex20", big)]), slice="y=2.5").cell_polygons(False)
    np.testing.assert_allclose(side, [[1, 3], [3, 3], [3, 5], [1, 5]])  # x-z
    # default: the mid-plane across the thinnest extent (y: 0.2 m of a 1 x 0.2 x 1 m box)
    auto = deformed_data(cells_dataset([("hex8", CUBE * [1.0, 0.2, 1.0])]))
    assert (auto.axis, auto.value, auto.plane_axes) == ("y", pytest.approx(0.1), ("x", "z"))
    np.testing.assert_allclose(auto.cell_polygons(False)[0], [[0, 0], [1, 0], [1, 1], [0, 1]])

    solids = [("tet4", TET_TRIANGLE), ("tet10", TET_SQUARE + [2.0, 0, 0]), ("hex8", CUBE + [4.0, 0, 0])]
    d = deformed_data(cells_dataset(solids), slice=("z", 0.5))
    assert d.cell.tolist() == [0, 1, 2] and d.cell_group.tolist() == [0, 1, 2]
    tri, square, hex_ = d.cell_polygons(False)
    assert len(tri) == 3 and shoelace(tri) == pytest.approx(0.125)
    np.testing.assert_allclose(sorted(map(tuple, tri)), [(0, 0), (0, 0.5), (0.5, 0)])
    assert len(square) == 4 and shoelace(square) == pytest.approx(0.25)
    np.testing.assert_allclose(sorted(map(tuple, square)), [(2, 0), (2, 0.5), (2.5, 0), (2.5, 0.5)])
    assert shoelace(hex_) == pytest.approx(1.0)
    # z = 1: the cube's top face lies in the plane (drawn), the tetrahedra only touch it at a corner or an edge
    top = deformed_data(cells_dataset(solids), slice="z=1")
    assert top.cell.tolist() == [2] and shoelace(top.cell_polygons(False)[0]) == pytest.approx(1.0)
    # a corner on the plane is a point of the polygon: the triangle tetrahedron by x = 0 is its face x = 0
    face = deformed_data(cells_dataset(solids[:1]), slice="x=0")
    assert shoelace(face.cell_polygons(False)[0]) == pytest.approx(0.5)


def test_slice_polygons_follow_the_interpolated_displacements():
    rng = np.random.default_rng(7)
    u = rng.normal(scale=1e-3, size=(8, 3))
    ds = cells_dataset([("hex8", CUBE)], u)
    d = deformed_data(ds, slice="z=0.3", scale=50.0)
    np.testing.assert_allclose(d.deformed, CUBE + 50.0 * u)
    bottom, top = CUBE[:4] + 50.0 * u[:4], CUBE[4:] + 50.0 * u[4:]
    expected = (0.7 * bottom + 0.3 * top)[:, :2]  # along the vertical edges 0-4, 1-5, 2-6, 3-7
    (poly,) = d.cell_polygons()
    np.testing.assert_allclose(poly, expected, rtol=0, atol=1e-14)
    assert np.abs(poly - CUBE[:4, :2]).max() > 0.02  # (the displacements are drawn)
    # an x-slice: the points on the edges along x at 0.25 from their first node, drawn in y-z
    d = deformed_data(ds, slice="x=0.25", scale=50.0)
    pairs = {(0, 1), (3, 2), (4, 5), (7, 6)}
    assert {tuple(sorted(ab)) for ab in d.polygon_nodes[0].tolist()} == {tuple(sorted(p)) for p in pairs}
    x = CUBE + 50.0 * u
    for ab, t, point in zip(d.polygon_nodes[0], d.polygon_t[0], d.cell_polygons()[0]):
        a, b = sorted(ab, key=lambda n: CUBE[n, 0])  # x = 0, x = 1
        np.testing.assert_allclose(point, (0.75 * x[a] + 0.25 * x[b])[1:], atol=1e-14)
        assert (t if ab[0] == a else 1 - t) == pytest.approx(0.25)
    fig = deformed_figure(ds, slice="z=0.3", scale=50.0)
    ax = fig.axes[0]
    (drawn,) = [c for c in ax.collections if c.get_gid() == "deformed"]
    np.testing.assert_allclose(drawn.get_paths()[0].vertices[:4], expected)
    assert "slice z = 0.3 m" in ax.get_title() and (ax.get_xlabel(), ax.get_ylabel()) == ("x [m]", "y [m]")


def test_slice_errors():
    solids = [("hex8", CUBE), ("hex8", CUBE + [0, 0, 2.0])]  # two cubes, a gap 1 < z < 2
    ds = cells_dataset(solids)
    for bad in ("q=0.5", "y", "y=abc"):
        with pytest.raises(MasonrydamError, match=r"--slice .*x 0 to 1 m, y 0 to 1 m, z 0 to 3 m"):
            deformed_data(ds, slice=bad)
    with pytest.raises(MasonrydamError, match=r"--slice z=3.5: outside the model's range along z \(0 to 3 m\)"):
        deformed_data(ds, slice="z=3.5")
    with pytest.raises(MasonrydamError, match=r"--slice y=-0.1: outside the model's range along y \(0 to 1 m\)"):
        deformed_data(ds, slice="y=-0.1")
    with pytest.raises(MasonrydamError, match=r"--slice z=1.5: the plane cuts none of the blocks .*0 to 3 m along z"):
        deformed_data(ds, slice="z=1.5")
    assert deformed_data(ds, slice="z=2.5").cell.tolist() == [1]


BOXES = {"base": (0.0, 0.0, 0.0, 1.0, 0.25, 0.5), "left": (0.0, 0.0, 0.5, 0.5, 0.25, 1.0),
         "right": (0.5, 0.0, 0.5, 1.0, 0.25, 1.5)}


def scene_3d():
    """The scene above in 3D, 0.25 m thick (y, one element), the top of 'right' held in y."""
    sc = scene()
    sc["model"] = {"name": "lift3d", "dimension": 3}
    sc["mesh"] = {"generator": "blocks_3d", "parameters": {"element_size": H, "blocks": [
        dict(zip(("x0", "y0", "z0", "x1", "y1", "z1"), b), group=g) for g, b in BOXES.items()]}}
    sc["supports"] = [{"set": "base"}]
    for stage, value in zip(sc["stages"][1:], ([-1e-4, 0.0, 0.0], [0.0, 0.0, 1e-4])):
        stage["loads"] = [{"type": "displacement", "set": "top", "components": ["x", "y", "z"], "value": value}]
    return sc


@pytest.fixture(scope="module")
def result_3d(tmp_path_factory):
    out = tmp_path_factory.mktemp("deformed3d") / "lift3d.nc"
    masonrydam.run(scene_3d(), output=out).close()
    return out


@pytest.fixture(scope="module")
def ds3(result_3d):
    return xr.load_dataset(result_3d)


def joint_xyz(ds):
    return np.stack([ds.joint_x.values, ds.joint_y.values, ds.joint_z.values], axis=1)


@pytest.mark.parametrize("step", [1, -1])
def test_slice_joints_of_a_3d_result(ds3, step):
    k = step % ds3.sizes["step"]
    state = ds3.joint_state.values[k]
    jy = ds3.joint_y.values
    assert ds3.sizes["joint_point"] == 24 and sorted(set(jy.tolist())) == [0.0, 0.25]  # lumped: on the nodes
    np.testing.assert_allclose(ds3.joint_weight.values, (H / 2) ** 2)
    if step == -1:  # stick, slip and open
        assert np.bincount(state, minlength=4).tolist() == [4, 8, 12, 0]
    # near the front face: the points on it (their patches reach y = 0.125); near the back: those at the back
    for value, on in (("0.03", 0.0), ("0", 0.0), ("0.2", 0.25)):
        d = deformed_data(ds3, step=step, scale=100.0, slice=f"y={value}")
        near = np.flatnonzero(jy == on)
        assert len(near) == 12 and d.joint_point.tolist() == near.tolist()
        np.testing.assert_array_equal(d.joint_state, state[near])
        np.testing.assert_allclose(d.joint_opening, ds3.joint_opening.values[k][near])
        assert d.counts == {name: int((state[near] == s).sum()) for s, name in enumerate(STATE_NAMES)}
        assert d.plane_axes == ("x", "z") and len(d.cell) == 20
    # the default: the mid-plane y = 0.125, half way between the two nodal layers: both are drawn
    d = deformed_data(ds3, step=step, scale=100.0)
    assert (d.axis, d.value) == ("y", 0.125)
    assert d.joint_point.tolist() == list(range(24))
    assert d.counts == {name: int((state == s).sum()) for s, name in enumerate(STATE_NAMES)}
    np.testing.assert_allclose(np.abs(d.joint_distance), H / 4)
    # segments: sqrt(weight) long along the trace (x on the horizontal joints, z on the vertical one), centred on
    # the patch centre (half way from the node to its face's centre) moved by the mean displacement of the faces
    d = deformed_data(ds3, step=step, scale=100.0, slice="y=0.03")
    seg = d.joint_segments
    np.testing.assert_allclose(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1), H / 2)
    horizontal = np.abs(ds3.joint_normal_z.values[d.joint_point]) > 0.99
    assert horizontal.sum() == 8
    np.testing.assert_allclose(np.abs(seg[horizontal, 1, 0] - seg[horizontal, 0, 0]), H / 2)
    np.testing.assert_allclose(np.abs(seg[~horizontal, 1, 1] - seg[~horizontal, 0, 1]), H / 2)
    xyz = np.stack([ds3.x.values, ds3.y.values, ds3.z.values], axis=1)
    nodes = ds3.joint_point_nodes.values[d.joint_point]  # (p, side, 4)
    shape = ds3.joint_point_shape.values[d.joint_point]
    u = ds3.displacement.values[k]
    centre = 0.5 * (joint_xyz(ds3)[d.joint_point] + xyz[nodes[:, 0]].mean(axis=1))
    moved = centre + 100.0 * 0.5 * np.einsum("pk,pskd->pd", shape, u[nodes])
    np.testing.assert_allclose(seg.mean(axis=1), moved[:, [0, 2]], atol=1e-12)
    # undeformed, the segments tile the three joint lines of 0.5 m: every 1/8 of each covered once
    tiny = deformed_data(ds3, step=step, scale=1e-9, slice="y=0.03")
    mids = np.round(tiny.joint_segments.mean(axis=1) / (H / 4)).astype(int)  # in units of 1/16 m
    assert sorted(map(tuple, mids[horizontal])) == [(i, 8) for i in range(1, 16, 2)]
    assert sorted(map(tuple, mids[~horizontal])) == [(8, j) for j in range(9, 16, 2)]
    # the figure: one segment per drawn point, coloured and counted by state
    fig = deformed_figure(ds3, step=step, scale=100.0, slice="y=0.03", title="lift3d.nc")
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    for s, name in enumerate(STATE_NAMES):
        (lines,) = [c for c in ax.collections if c.get_gid() == f"joints_{name}"]
        assert len(lines.get_segments()) == d.counts[name]
        np.testing.assert_allclose(np.array(lines.get_segments()).reshape(-1, 2, 2), seg[d.joint_state == s])
        if d.counts[name]:
            np.testing.assert_allclose(lines.get_colors()[0], to_rgba(STATE_COLOURS[s]))
        assert f"{name}: {d.counts[name]} joint points" in labels
    if step == -1:
        (lines,) = [c for c in ax.collections if c.get_gid() == "joints_open"]
        opening = d.joint_opening[d.joint_state == 2]
        np.testing.assert_allclose(lines.get_linewidths(), STATE_WIDTHS[2] + OPENING_WIDTH * opening / opening.max())
    title = ax.get_title()
    assert title.startswith("lift3d.nc\nslice y = 0.03 m; step ") and (ax.get_xlabel(), ax.get_ylabel()) == \
        ("x [m]", "z [m]")


def test_slice_skips_joints_parallel_to_the_plane(ds3):
    # x = 0.55: near the vertical joint at x = 0.5 (normal x, no trace in the plane: not drawn) and the
    # points at x = 0.5 of the base joint's elements under 'right' (patch centres at x = 0.5625)
    d = deformed_data(ds3, slice="x=0.55", scale=100.0)
    assert d.plane_axes == ("y", "z") and len(d.cell) == 6  # base 2, right 4
    face_x = ds3.x.values[ds3.joint_point_nodes.values[:, 0]].mean(axis=1)  # centre of the element's face
    expected = np.flatnonzero((ds3.joint_x.values == 0.5) & (np.abs(ds3.joint_normal_z.values) > 0.99)
                              & (face_x > 0.5))
    assert len(expected) == 2 and d.joint_point.tolist() == expected.tolist()
    vertical = np.flatnonzero(np.abs(ds3.joint_normal_x.values) > 0.99)
    assert len(vertical) == 8 and np.all(np.abs(ds3.joint_x.values[vertical] - 0.55) < H / 4)  # near, not drawn
    np.testing.assert_allclose(np.abs(d.joint_segments[:, 1, 0] - d.joint_segments[:, 0, 0]), H / 2)  # along y


def rotated_about_y(ds, degrees):
    """``ds`` with the model turned by ``degrees`` about the y axis (x' = x cos + z sin, z' = -x sin + z cos)."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    out = ds.copy(deep=True)
    for prefix in ("", "joint_", "joint_normal_"):
        x, z = ds[f"{prefix}x"], ds[f"{prefix}z"]
        out[f"{prefix}x"], out[f"{prefix}z"] = c * x + s * z, -s * x + c * z
    u = ds.displacement.values
    turned = u.copy()
    turned[..., 0], turned[..., 2] = c * u[..., 0] + s * u[..., 2], -s * u[..., 0] + c * u[..., 2]
    out["displacement"] = (ds.displacement.dims, turned)
    return out


def test_slice_across_inclined_joints(ds3):
    # turned 20 degrees about y, a horizontal slice meets the joint under 'left' (inclined 20 degrees to it)
    # at x = 0.3 and the vertical joint (70 degrees) at z = 0.5 + 0.2 tan 20: the points whose patches the
    # traces cross are node x = 0.25 of the element [0.25, 0.5] and node z = 0.5 of the element [0.5, 0.75]
    theta = np.radians(20.0)
    turned = rotated_about_y(ds3, 20.0)
    level = 0.5 * np.cos(theta) - 0.3 * np.sin(theta)
    d = deformed_data(turned, slice=f"z={float(level)!r}", scale=1e-9)
    assert d.plane_axes == ("x", "y")
    nodes = ds3.joint_point_nodes.values[:, 0]  # unturned geometry of each point and its face
    face_x, face_z = ds3.x.values[nodes].mean(axis=1), ds3.z.values[nodes].mean(axis=1)
    jx, jz = ds3.joint_x.values, ds3.joint_z.values
    under_left = (jz == 0.5) & (jx == 0.25) & (face_x > 0.25) & (np.abs(ds3.joint_normal_z.values) > 0.99)
    vertical = (jx == 0.5) & (jz == 0.5) & (face_z > 0.5) & (np.abs(ds3.joint_normal_x.values) > 0.99)
    assert under_left.sum() == 2 and vertical.sum() == 2
    assert d.joint_point.tolist() == np.flatnonzero(under_left | vertical).tolist()
    seg = d.joint_segments
    np.testing.assert_allclose(seg[:, 1, 0], seg[:, 0, 0], atol=1e-12)  # along y
    np.testing.assert_allclose(np.abs(seg[:, 1, 1] - seg[:, 0, 1]), H / 2)
    trace_x = np.where(vertical[d.joint_point], 0.5 * np.cos(theta) + (0.5 + 0.2 * np.tan(theta)) * np.sin(theta),
                       0.3 * np.cos(theta) + 0.5 * np.sin(theta))  # the traces' x', on the turned joints
    np.testing.assert_allclose(seg[:, 0, 0], trace_x, atol=1e-9)
    np.testing.assert_allclose(sorted(seg.mean(axis=1)[:, 1]), [H / 4, H / 4, 3 * H / 4, 3 * H / 4], atol=1e-9)
    # a bit higher, the trace leaves the patch of node x = 0.25 for that of node x = 0.5 of the same element
    higher = deformed_data(turned, slice=("z", level - 0.1 * np.sin(theta)), scale=1e-9)
    assert set(jx[higher.joint_point][np.abs(ds3.joint_normal_z.values[higher.joint_point]) > 0.99]) == {0.5}


@pytest.mark.slow
def test_cli_slice(result_3d, ds3, result, tmp_path, capsys, monkeypatch):
    from matplotlib.image import imread

    monkeypatch.chdir(tmp_path)
    assert main(["plot", str(result_3d), "--deformed", "--slice", "y=0.03", "--scale", "200"]) == 0
    image = imread(tmp_path / "lift3d_deformed.png")
    assert image.shape[:2] == (int(6.5 * 110), int(8.0 * 110))
    assert (np.abs(image[..., :3] - np.array(to_rgba("tab:red"))[:3]).max(axis=-1) < 0.05).sum() > 20  # open joints
    assert "wrote lift3d_deformed.png" in capsys.readouterr().out
    assert main(["plot", str(result_3d), "--deformed", "--step", "1", "-o", "mid.png"]) == 0  # default slice
    assert (tmp_path / "mid.png").stat().st_size > 0
    capsys.readouterr()
    for bad, message in (("w=0.1", "the axis must be x, y or z (the model spans x 0 to 1 m, y 0 to 0.25 m, "
                                   "z 0 to 1.5 m)"),
                         ("y=0.3", "--slice y=0.3: outside the model's range along y (0 to 0.25 m)"),
                         ("z=-1", "--slice z=-1: outside the model's range along z (0 to 1.5 m)"),
                         ("0.1", "--slice 0.1: give AXIS=VALUE")):
        assert main(["plot", str(result_3d), "--deformed", "--slice", bad, "-o", "bad.png"]) == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "bad.png").exists()
    assert main(["plot", str(result), "--deformed", "--slice", "y=0.1", "-o", "bad.png"]) == 2
    assert "--slice y=0.1: slices are for 3D results" in capsys.readouterr().err
