"""Result files as ParaView time series (``masonrydam export-results OUT.nc -o OUT.xdmf|OUT.pvd``,
masonrydam/results/paraview.py): the files are read back with meshio (``meshio.xdmf.TimeSeriesReader``,
``meshio.read`` of the ``.vtu`` files) and compared with the netCDF result.

Scenes: a 2D static one (a base block and two blocks on it, dry joints, pushed and lifted so that joints
slide and open; element stress recorded), the same recording the top nodes only, a tiny dynamic one (a
block on a frictional joint under a ground pulse) and a tiny 3D one (a block on a base, element stress).
"""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
import xarray as xr

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import MasonrydamError
from masonrydam.results.paraview import SHRINK_FACTOR, export_results, units_path

BLOCKS = {"base": (0.0, 0.0, 1.0, 0.5), "left": (0.0, 0.5, 0.5, 1.0), "right": (0.5, 0.5, 1.0, 1.5)}
JOINT = {"law": "mohr_coulomb", "normal_stiffness": 1e10, "shear_stiffness": 5e9, "cohesion": 0.0,
         "friction_angle": 30.0, "residual_shear_stiffness": 0.0}


def scene_2d(output=None):
    s = {"model": {"name": "lift", "thickness": 0.1},
         "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
             {"x0": x0, "y0": y0, "x1": x1, "y1": y1, "group": g} for g, (x0, y0, x1, y1) in BLOCKS.items()]}},
         "materials": {g: {"youngs_modulus": 10e9, "poisson_ratio": 0.2, "density": 2000.0} for g in BLOCKS},
         "joints": {"joints": JOINT},
         "supports": [{"set": "base", "components": ["x", "y"]}],
         "stages": [{"name": "gravity", "steps": 1, "loads": [{"type": "self_weight"}]},
                    {"name": "push", "steps": 2, "loads": [
                        {"type": "displacement", "set": "top", "components": ["x", "y"], "value": [-1e-4, 0.0]}]},
                    {"name": "lift", "steps": 2, "loads": [
                        {"type": "displacement", "set": "top", "components": ["x", "y"], "value": [0.0, 1e-4]}]}],
         "output": {"stress": "element"}}
    if output:
        s["output"].update(output)
    return s


def scene_dynamic():
    blocks = {"base": (0.0, 0.0, 1.0, 0.25), "block": (0.0, 0.25, 1.0, 0.75)}
    return {"model": {"name": "pulse", "thickness": 1.0},
            "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
                {"x0": x0, "y0": y0, "x1": x1, "y1": y1, "group": g} for g, (x0, y0, x1, y1) in blocks.items()]}},
            "materials": {g: {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": 2000.0} for g in blocks},
            "joints": {"joints": {"law": "mohr_coulomb", "normal_stiffness": 1e10, "shear_stiffness": 1e10,
                                  "friction_angle": 11.31, "cohesion": 0.0}},
            "supports": [{"set": "base", "components": ["x", "y"]}],
            "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                       {"name": "pulse", "type": "dynamic", "dt": 0.005, "duration": 0.02,
                        "ground_motion": {"x": {"pulse": {"shape": "rectangular", "amplitude": "0.4 g",
                                                          "duration": 0.2}}}}]}


def scene_3d():
    blocks = [{"x0": 0.0, "y0": 0.0, "z0": 0.0, "x1": 1.0, "y1": 1.0, "z1": 0.1, "group": "base"},
              {"x0": 0.0, "y0": 0.0, "z0": 0.1, "x1": 1.0, "y1": 1.0, "z1": 0.15, "group": "block"}]
    return {"model": {"name": "block3d", "dimension": 3, "gravity": [1.471, 2.54785, -9.80665]},
            "mesh": {"generator": "blocks_3d", "parameters": {"element_size": 0.5, "rotation_deg": [0.0, -10.0, 0.0],
                                                               "blocks": blocks}},
            "materials": {g: {"youngs_modulus": 200e9, "poisson_ratio": 0.0, "density": 2000.0}
                          for g in ("base", "block")},
            "joints": {"joints": {"law": "mohr_coulomb", "normal_stiffness": 1e12, "shear_stiffness": 1e12,
                                  "friction_angle": 30.0}},
            "supports": [{"set": "base_nodes"}],
            "stages": [{"name": "load", "steps": 2, "loads": [{"type": "self_weight"}]}],
            "output": {"stress": "element"}}


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    d = tmp_path_factory.mktemp("paraview")
    paths = {}
    for name, sc in (("static", scene_2d()), ("top", scene_2d({"nodes": ["top"]})), ("dynamic", scene_dynamic()),
                     ("solid", scene_3d())):
        paths[name] = d / f"{name}.nc"
        masonrydam.run(sc, output=paths[name])
    return paths


def load(path):
    return xr.load_dataset(path)


def read_xdmf(path):
    """points, cells (concatenated connectivity per cell, list), [(t, point_data, cell_data concatenated)]"""
    with meshio.xdmf.TimeSeriesReader(str(path)) as r:
        points, blocks = r.read_points_cells()
        steps = []
        for k in range(r.num_steps):
            t, pd, cd = r.read_data(k)
            steps.append((t, pd, {n: np.concatenate(v) for n, v in cd.items()}))
    cells = [c for b in blocks for c in b.data]
    types = [b.type for b in blocks for _ in b.data]
    return points, cells, types, steps


def read_pvd(path):
    """[(timestep, mesh)] of a .pvd and its .vtu files."""
    root = ET.parse(path).getroot()
    assert root.attrib["type"] == "Collection"
    return [(float(e.attrib["timestep"]), meshio.read(path.parent / e.attrib["file"]), e.attrib["file"])
            for e in root.iter("DataSet")]


def node_coords(ds):
    xyz = np.zeros((ds.sizes["node"], 3))
    for k, c in enumerate(ds.component.values):
        xyz[:, k] = ds[str(c)].values
    return xyz


def padded(u):
    out = np.zeros((u.shape[0], 3))
    out[:, :u.shape[1]] = u
    return out


def element_means(ds, k, name, reduce=np.mean):
    """Per (joint_set, joint_element): the reduction over its joint points of ``name`` at step position k."""
    v = ds[name].values[k]
    out = {}
    for key in set(zip(ds.joint_set.values.tolist(), ds.joint_element.values.tolist())):
        sel = (ds.joint_set.values == key[0]) & (ds.joint_element.values == key[1])
        out[key] = reduce(v[sel], axis=0)
    return out


def check_step(ds, k, points, cells, pd, cd):
    """The point and cell data of one exported step against step position k of the result."""
    n = ds.sizes["node"]
    dim = ds.sizes["component"]
    np.testing.assert_array_equal(pd["node"][:n], ds.node.values)
    np.testing.assert_allclose(points[:n], node_coords(ds), rtol=0, atol=1e-12)
    np.testing.assert_allclose(pd["displacement"][:n], padded(ds.displacement.values[k]), rtol=0, atol=0)
    assert pd["displacement"].shape[1] == 3
    part = cd["part"]
    blocks = np.flatnonzero(part == 0)
    # block cells: their corner nodes (ids) are block_cell_nodes of the element they say they are
    el = cd["element"][blocks]
    assert len(el) == ds.sizes["block_cell"] and sorted(el) == list(range(ds.sizes["block_cell"]))
    for c, e in zip(blocks, el):
        ids = pd["node"][cells[c]]
        ref = ds.block_cell_nodes.values[e]
        np.testing.assert_array_equal(ids, ref[ref >= 0])
    np.testing.assert_array_equal(cd["group"][blocks], ds.block_cell_group.values[el])
    comps = [str(c) for c in ds.stress_component.values]
    for j, c in enumerate(comps):
        np.testing.assert_allclose(cd[f"stress_{c}"][blocks], ds.stress.values[k][el, j], rtol=1e-12, atol=0)
        assert np.isnan(cd[f"stress_{c}"][part != 0]).all()
    # interface cells: means over the element's joint points, the most severe state
    joints = np.flatnonzero(part == 1)
    assert len(joints) == len(set(zip(ds.joint_set.values.tolist(), ds.joint_element.values.tolist())))
    keys = list(zip(cd["joint_set"][joints].tolist(), cd["joint_element"][joints].tolist()))
    opening = element_means(ds, k, "joint_opening")
    tn = element_means(ds, k, "joint_traction_normal")
    slip = element_means(ds, k, "joint_slip")
    state = element_means(ds, k, "joint_state", np.max)
    np.testing.assert_allclose(cd["joint_opening"][joints], [opening[q] for q in keys], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(cd["joint_traction_normal"][joints], [tn[q] for q in keys], rtol=1e-12, atol=1e-6)
    for j, c in enumerate(ds.shear_direction.values):
        np.testing.assert_allclose(cd[f"joint_slip_{c}"][joints], [slip[q][j] for q in keys], rtol=1e-12, atol=1e-18)
    mag = element_means(ds, k, "joint_slip", lambda v, axis: np.mean(np.linalg.norm(v, axis=1)))
    np.testing.assert_allclose(cd["joint_slip_magnitude"][joints], [mag[q] for q in keys], rtol=1e-12, atol=1e-18)
    np.testing.assert_array_equal(cd["joint_state"][joints], [state[q] for q in keys])
    assert (cd["joint_state"][blocks] == -1).all() and np.isnan(cd["joint_opening"][blocks]).all()
    assert (cd["group"][joints] == -1).all() and (cd["element"][joints] == -1).all()
    # the interface cell's nodes are its element's bottom and top face nodes
    for c, q in zip(joints, keys):
        p = np.flatnonzero((ds.joint_set.values == q[0]) & (ds.joint_element.values == q[1]))[0]
        faces = ds.joint_point_nodes.values[p]
        ids = pd["node"][cells[c]]
        if dim == 2:
            np.testing.assert_array_equal(ids, [faces[0, 0], faces[0, 1], faces[1, 1], faces[1, 0]])
        else:
            np.testing.assert_array_equal(ids, np.concatenate([faces[0, :4], faces[1, :4]]))


def test_xdmf_static_2d(results, tmp_path, monkeypatch):
    ds = load(results["static"])
    monkeypatch.chdir(tmp_path)  # the HDF5 file goes beside the output, not to the current folder
    (tmp_path / "out").mkdir()
    out = tmp_path / "out" / "lift.xdmf"
    s = export_results(ds, out, source=str(results["static"]))
    assert (tmp_path / "out" / "lift.h5").exists() and not (tmp_path / "lift.h5").exists()
    points, cells, types, steps = read_xdmf(out)
    n = ds.sizes["step"]
    assert n >= 5 and len(steps) == n  # 5 steps and the step cuts of the lift
    np.testing.assert_array_equal([t for t, _, _ in steps], np.arange(n))  # static: the step number
    np.testing.assert_array_equal(s.steps, np.arange(n))
    assert s.time_unit == "1" and s.left_out == {"block_cells": 0, "joint_elements": 0, "static_steps": 0}
    assert set(types) == {"quad"}
    assert points.shape == (ds.sizes["node"], 3) and (points[:, 2] == 0).all()
    # the joints slide and open at the end: the comparison is not of zeros
    assert (ds.joint_state.values[-1] == 2).any() and (ds.joint_state.values[-1] == 1).any()
    assert np.abs(ds.stress.values[-1]).max() > 1e3
    for k, (_, pd, cd) in enumerate(steps):
        check_step(ds, k, points, cells, pd, cd)
    _, _, cd = steps[-1]
    assert (cd["joint_state"] == 2).any() and np.nanmax(cd["joint_opening"]) > 1e-6
    side = json.loads(units_path(out).read_text())
    f = side["fields"]
    assert f["displacement"]["unit"] == "m" and f["displacement"]["association"] == "point"
    assert f["joint_traction_normal"]["unit"] == "Pa" and f["joint_opening"]["unit"] == "m"
    assert f["stress_xx"]["unit"] == "Pa" and f["stress_xx"]["association"] == "cell"
    assert f["group"]["names"] == json.loads(ds.block_cell_group.attrs["group_names"])
    assert side["time"]["unit"] == "1" and side["steps"] == list(range(n))
    assert side["joint_states"] == {"0": "stick", "1": "slip", "2": "open", "3": "crush"}


def test_pvd_both_views_and_shrunk_geometry(results, tmp_path, capsys):
    ds = load(results["static"])
    out = tmp_path / "lift.pvd"
    assert main(["export-results", str(results["static"]), "-o", str(out), "--joints", "both"]) == 0
    assert "wrote" in capsys.readouterr().out
    series = read_pvd(out)
    n = ds.sizes["step"]
    assert [f for _, _, f in series] == [f"lift_{k:04d}.vtu" for k in range(n)]
    np.testing.assert_array_equal([t for t, _, _ in series], np.arange(float(n)))
    xyz = node_coords(ds)
    for k, (_, mesh, _) in enumerate(series):
        cells = [c for b in mesh.cells for c in b.data]
        cd = {n: np.concatenate(v) for n, v in mesh.cell_data.items()}
        pd = mesh.point_data
        check_step(ds, k, mesh.points, cells, pd, cd)
        one, two = np.flatnonzero(cd["part"] == 1), np.flatnonzero(cd["part"] == 2)
        assert len(one) == len(two) > 0
        for name in ("joint_set", "joint_element", "joint_opening", "joint_state", "joint_slip_t"):
            np.testing.assert_array_equal(cd[name][one], cd[name][two])
        # shrunk cells: own points, at 0.8 of the distance to the centroid, carrying their node's displacement
        n = ds.sizes["node"]
        pos = {int(i): p for p, i in enumerate(ds.node.values)}
        for c1, c2 in zip(one, two):
            assert (cells[c2] >= n).all()
            orig = xyz[[pos[int(i)] for i in pd["node"][cells[c1]]]]
            centre = orig.mean(axis=0)
            np.testing.assert_allclose(mesh.points[cells[c2]], centre + SHRINK_FACTOR * (orig - centre), atol=1e-12)
            np.testing.assert_array_equal(pd["node"][cells[c2]], pd["node"][cells[c1]])
            np.testing.assert_array_equal(pd["displacement"][cells[c2]], pd["displacement"][cells[c1]])


def test_shrunk_only_keeps_blocks_on_model_nodes(results, tmp_path):
    ds = load(results["static"])
    out = tmp_path / "s.pvd"
    s = export_results(ds, out, joints="shrunk")
    mesh = read_pvd(out)[-1][1]
    part = np.concatenate(mesh.cell_data["part"])
    assert set(part.tolist()) == {0, 2} and s.n_joint_cells == np.sum(part == 2)
    assert len(mesh.points) == ds.sizes["node"] + 4 * s.n_joint_cells


@pytest.mark.slow
def test_every_and_steps(results, tmp_path):
    ds = load(results["static"])
    n = ds.sizes["step"]
    assert n == 7
    for kw, expected in (({"every": 2}, [0, 2, 4, 6]), ({"every": 4}, [0, 4, 6]), ({"steps": "1:3"}, [1, 2]),
                         ({"steps": "-2:"}, [5, 6]), ({"steps": ":4", "every": 2}, [0, 2, 3]),
                         ({"every": 10}, [0, 6])):
        out = tmp_path / "e.xdmf"
        s = export_results(ds, out, **kw)
        np.testing.assert_array_equal(s.steps, expected)
        points, cells, _, steps = read_xdmf(out)
        assert [t for t, _, _ in steps] == [float(e) for e in expected]
        for (t, pd, cd) in steps:
            check_step(ds, int(t), points, cells, pd, cd)


def test_dynamic_times_and_velocity(results, tmp_path):
    ds = load(results["dynamic"])
    t = ds.time.values
    dyn = np.flatnonzero(np.isfinite(t))
    assert len(dyn) == 5 and len(dyn) < ds.sizes["step"]  # a static gravity step, then 0 to 0.02 s
    out = tmp_path / "d.xdmf"
    s = export_results(ds, out)
    assert s.time_unit == "s" and s.left_out["static_steps"] == ds.sizes["step"] - len(dyn)
    points, cells, _, steps = read_xdmf(out)
    np.testing.assert_allclose([tt for tt, _, _ in steps], t[dyn], rtol=0, atol=1e-15)
    assert np.abs(ds.velocity.values[dyn[-1]]).max() > 1e-4
    for (_, pd, cd), k in zip(steps, dyn):
        for name in ("displacement", "velocity", "acceleration"):
            np.testing.assert_array_equal(pd[name], padded(ds[name].values[k]))
        opening = element_means(ds, k, "joint_opening")
        joints = np.flatnonzero(cd["part"] == 1)
        keys = zip(cd["joint_set"][joints].tolist(), cd["joint_element"][joints].tolist())
        np.testing.assert_allclose(cd["joint_opening"][joints], [opening[q] for q in keys], rtol=1e-12, atol=1e-18)
    assert json.loads(units_path(out).read_text())["time"]["unit"] == "s"
    # --time step keeps the static step, its velocity NaN
    out = tmp_path / "d.pvd"
    s = export_results(ds, out, time="step")
    series = read_pvd(out)
    assert [tt for tt, _, _ in series] == [float(k) for k in range(ds.sizes["step"])]
    static = np.flatnonzero(~np.isfinite(t))[0]
    assert np.isnan(series[static][1].point_data["velocity"]).all()
    np.testing.assert_array_equal(series[dyn[-1]][1].point_data["velocity"], padded(ds.velocity.values[dyn[-1]]))


def test_solid_3d(results, tmp_path):
    ds = load(results["solid"])
    assert ds.sizes["component"] == 3
    out = tmp_path / "b.xdmf"
    s = export_results(ds, out)
    points, cells, types, steps = read_xdmf(out)
    assert len(steps) == ds.sizes["step"] == 2
    assert set(types) == {"hexahedron"} and all(len(c) == 8 for c in cells)
    assert np.abs(ds.stress.values[-1]).max() > 1.0 and np.abs(ds.joint_traction_normal.values[-1]).max() > 1.0
    for k, (_, pd, cd) in enumerate(steps):
        check_step(ds, k, points, cells, pd, cd)
        blocks = cd["part"] == 0
        np.testing.assert_allclose(cd["stress"][blocks], ds.stress.values[k][cd["element"][blocks]], rtol=1e-12)
    assert s.n_joint_cells == len(set(zip(ds.joint_set.values.tolist(), ds.joint_element.values.tolist())))


def test_unrecorded_nodes_leave_cells_out(results, tmp_path):
    ds = load(results["top"])
    out = tmp_path / "top.pvd"
    s = export_results(ds, out)
    assert s.left_out["block_cells"] == ds.sizes["block_cell"] and s.left_out["joint_elements"] > 0
    mesh = read_pvd(out)[-1][1]
    assert [b.type for b in mesh.cells] == ["vertex"]  # the recorded nodes show as points
    assert len(mesh.points) == ds.sizes["node"]
    np.testing.assert_array_equal(mesh.point_data["displacement"], padded(ds.displacement.values[-1]))


@pytest.mark.parametrize("args, option", [
    (["-o", "{d}/x.vtu"], "-o"),
    (["-o", "{d}/x.xdmf", "--joints", "sideways"], "--joints"),
    (["-o", "{d}/x.xdmf", "--every", "0"], "--every"),
    (["-o", "{d}/x.pvd", "--steps", "3"], "--steps"),
    (["-o", "{d}/x.pvd", "--time", "seconds"], "--time"),
    (["-o", "{d}/nofolder/x.pvd"], "-o"),
])
def test_bad_options_name_the_option(results, tmp_path, capsys, args, option):
    rc = main(["export-results", str(results["static"])] + [a.format(d=tmp_path) for a in args])
    err = capsys.readouterr().err
    assert rc == 2 and f"error: {option} " in err
    assert not list(tmp_path.glob("x*"))


def test_library_errors(results, tmp_path):
    ds = load(results["static"])
    with pytest.raises(MasonrydamError, match="-o .*suffix"):
        export_results(ds, tmp_path / "x.vtk")
    with pytest.raises(MasonrydamError, match="--joints"):
        export_results(ds, tmp_path / "x.xdmf", joints="open")
    with pytest.raises(MasonrydamError, match="--every"):
        export_results(ds, tmp_path / "x.xdmf", every=0)
    with pytest.raises(MasonrydamError, match="--steps"):
        export_results(ds, tmp_path / "x.xdmf", steps="7:9")  # selects no step


def synthetic_tet_pair():
    """Two tetrahedra joined by one tri3 interface element (3 joint points), bottom face (0, 1, 2) at z = 0,
    its right-hand normal +z toward the top tetrahedron; step 1 lifts the top one by 1 mm (opening) and
    shifts it 0.5 mm in x. Padding of the face nodes to 4, as beside quad faces."""
    xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -1], [0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    u = np.zeros((2, 8, 3))
    u[1, 4:] = [5e-4, 0.0, 1e-3]
    faces = np.array([[0, 1, 2, -1], [4, 5, 6, -1]])
    state = np.array([[0, 0, 0], [1, 2, 1]], dtype=np.int8)
    opening = np.array([[0.0, 0.0, 0.0], [1e-3, 1.2e-3, 0.8e-3]])
    ds = xr.Dataset(
        {"x": ("node", xyz[:, 0]), "y": ("node", xyz[:, 1]), "z": ("node", xyz[:, 2]),
         "displacement": (("step", "node", "component"), u),
         "block_cell_nodes": (("block_cell", "block_cell_node"), np.array([[0, 2, 1, 3], [4, 5, 6, 7]])),
         "block_cell_group": ("block_cell", np.array([0, 1]), {"group_names": '["bottom", "top"]',
                                                              "group_types": '["tet4", "tet4"]'}),
         "joint_set": ("joint_point", np.zeros(3, int), {"set_names": '["j"]'}),
         "joint_element": ("joint_point", np.zeros(3, int)),
         "joint_point_nodes": (("joint_point", "joint_side", "joint_face_node"), np.stack([faces] * 3)),
         "joint_opening": (("step", "joint_point"), opening, {"units": "m"}),
         "joint_slip": (("step", "joint_point", "shear_direction"), np.zeros((2, 3, 2)), {"units": "m"}),
         "joint_state": (("step", "joint_point"), state),
         "load_factor": ("step", [0.5, 1.0])},
        coords={"step": [0, 1], "node": np.arange(8), "component": ["x", "y", "z"],
                "shear_direction": ["t1", "t2"]})
    return ds


def test_tetrahedra_and_wedge_interface(tmp_path):
    ds = synthetic_tet_pair()
    out = tmp_path / "tet.pvd"
    s = export_results(ds, out)
    assert s.n_block_cells == 2 and s.n_joint_cells == 1
    mesh = read_pvd(out)[-1][1]
    assert [b.type for b in mesh.cells] == ["tetra", "wedge"]
    wedge = mesh.cells[1].data[0]
    np.testing.assert_array_equal(mesh.point_data["node"][wedge], [0, 1, 2, 4, 5, 6])
    # warped, the wedge has a positive volume (bottom triangle's normal toward the top one, as VTK wants)
    x = mesh.points[wedge] + mesh.point_data["displacement"][wedge]
    normal = np.cross(x[1] - x[0], x[2] - x[0])
    assert np.dot(normal, x[3:].mean(axis=0) - x[:3].mean(axis=0)) > 0
    cd = {n: np.concatenate(v) for n, v in mesh.cell_data.items()}
    assert cd["joint_opening"][2] == pytest.approx(1e-3, rel=1e-12) and cd["joint_state"][2] == 2
    assert np.isnan(cd["joint_opening"][:2]).all() and list(cd["joint_state"][:2]) == [-1, -1]
