"""A mesh written by ``export-mesh`` in gmsh format reads back as a scene mesh.

The .msh file holds the mesh as gmsh would give it before interface insertion (masonrydam.mesh.io):
the node copies of each interface merged, joints as named line (2D) or surface (3D) physical
groups, facet sets as named line/surface groups, node sets as named vertex groups. A scene that
reads it with ``[mesh] file = ..., joints = [...]`` and the same materials, joints, supports and
stages must give the results of the generated scene: the same nodes, DOFs, interfaces and joint
points, the same final joint states and the same displacements (nodes matched through the
elements that hold them, so a renumbering would not matter).
"""
from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import MasonrydamError, MeshError
from masonrydam.mesh.interfaces import insert_interfaces, merge_map, partial_node_sets, remove_interfaces
from masonrydam.mesh.io import read_mesh, write_mesh
from masonrydam.scene import build_mesh, build_model
from masonrydam.scene.scene import Scene

RTOL = 1e-9

WALL_TOML = """
[model]
name = "roundtrip_wall"
thickness = 0.1

{mesh}

[materials.units]
youngs_modulus = "16.7 GPa"
poisson_ratio = 0.15
density = 1800.0

[materials.base_beam]
youngs_modulus = "210 GPa"
poisson_ratio = 0.3
density = 7850.0

[materials.top_beam]
youngs_modulus = "210 GPa"
poisson_ratio = 0.3
density = 7850.0

{joints}

[[supports]]
set = "base"
components = ["x", "y"]

[[stages]]
name = "gravity"
loads = [{{ type = "self_weight" }}]

[[stages]]
name = "push"
steps = 4
loads = [{{ type = "displacement", set = "top", components = ["x"], value = [2e-5] }}]
"""

WALL_MESH = """
[mesh]
generator = "masonry_wall_2d"
[mesh.parameters]
length = 0.4
height = 0.3
unit_length = 0.2
unit_height = 0.1
elements_per_unit = 1
base_beam_height = 0.05
top_beam_height = 0.05
"""

JOINT_SETS = ["base_joint", "bed_joints", "head_joints", "top_joint"]


def _joint_tables(names):
    return "\n".join(f"""[joints.{n}]
normal_stiffness = "82 N/mm3"
shear_stiffness = "36 N/mm3"
cohesion = 0.0
tensile_strength = 0.0
friction_angle = 35.0
""" for n in names)


# ------------------------------------------------------------------------------------------------
# comparison of two meshes and two results
# ------------------------------------------------------------------------------------------------
def node_map(m0, m1):
    """Index in m1 of every node of m0: elements matched by group, type and centroid, nodes by their
    place in the matched elements (coincident copies of a split node are told apart this way)."""
    mp = np.full(m0.n_nodes, -1)
    assert sorted((b.name, b.type, len(b.cells)) for b in m0.blocks) == \
        sorted((b.name, b.type, len(b.cells)) for b in m1.blocks)
    size = float(np.ptp(m0.points, axis=0).max())
    for b0 in m0.blocks:
        (b1,) = [b for b in m1.blocks if (b.name, b.type) == (b0.name, b0.type)]
        c0, c1 = m0.points[b0.cells].mean(axis=1), m1.points[b1.cells].mean(axis=1)
        o0 = np.lexsort(np.round(c0 / size, 9).T[::-1])
        o1 = np.lexsort(np.round(c1 / size, 9).T[::-1])
        np.testing.assert_allclose(c0[o0], c1[o1], rtol=0, atol=1e-12 * size)
        a, b = b0.cells[o0].ravel(), b1.cells[o1].ravel()
        seen = mp[a] >= 0
        assert (mp[a][seen] == b[seen]).all(), "a node maps to two nodes"
        mp[a] = b
    assert (mp >= 0).all() and len(np.unique(mp)) == m0.n_nodes
    np.testing.assert_array_equal(m0.points, m1.points[mp])
    return mp


def joint_element_map(m0, m1, mp, exact=True):
    """(set name, element index within the set) of m0 -> the same in m1, interfaces matched by their
    (mapped) node lists; the node order, and so the orientation, must be the same (``exact``), or
    else the same bottom and top faces (node order free)."""
    def rows(m, nodes=None):
        out = {}
        for name in m.joint_set_names():
            cells = np.vstack([j.cells for j in m.joints if j.name == name])
            half = cells.shape[1] // 2
            for e, c in enumerate(cells if nodes is None else nodes[cells]):
                key = tuple(c.tolist()) if exact else (frozenset(c[:half].tolist()), frozenset(c[half:].tolist()))
                out[(name, key)] = e
        return out
    r0, r1 = rows(m0, mp), rows(m1)
    assert r0.keys() == r1.keys()
    return {(name, e0): (name, r1[(name, key)]) for (name, key), e0 in r0.items()}


def point_index(ds):
    names = json.loads(ds.joint_set.attrs["set_names"])  # JSON list (masonrydam.results.writer)
    return {(names[int(s)], int(e), int(k)): i for i, (s, e, k) in
            enumerate(zip(ds.joint_set.values, ds.joint_element.values, ds.joint_integration_point.values))}


def assert_same_results(scene0, base0, scene1, base1, ds0, ds1):
    m0 = build_mesh(scene0.normalized, base0)
    m1 = build_mesh(scene1.normalized, base1)
    mp = node_map(m0, m1)
    assert m1.n_nodes == m0.n_nodes and m1.n_interfaces() == m0.n_interfaces()
    assert build_model(scene1.normalized, m1).n_dof == build_model(scene0.normalized, m0).n_dof
    jmap = joint_element_map(m0, m1, mp)
    # joint points: (set, element, point) keys mapped through the interface map
    p0, p1 = point_index(ds0), point_index(ds1)
    assert len(p0) == len(p1) == ds0.sizes["joint_point"] == ds1.sizes["joint_point"]
    perm = np.array([p1[jmap[(s, e)] + (k,)] for (s, e, k) in sorted(p0, key=p0.get)])
    assert ds1.sizes["step"] == ds0.sizes["step"]
    np.testing.assert_array_equal(ds1.joint_state.values[:, perm], ds0.joint_state.values)
    for v in ("joint_opening", "joint_slip", "joint_traction_normal", "joint_traction_shear"):
        a, b = ds0[v].values, ds1[v].values[:, perm]
        np.testing.assert_allclose(b, a, rtol=RTOL, atol=RTOL * np.abs(a).max(), err_msg=v)
    u0 = ds0.displacement.values
    u1 = ds1.displacement.values[:, mp]
    np.testing.assert_allclose(u1, u0, rtol=RTOL, atol=RTOL * np.abs(u0).max())
    r0 = ds0.reaction.values
    np.testing.assert_allclose(ds1.reaction.values[:, mp], r0, rtol=RTOL, atol=RTOL * np.abs(r0).max())
    return m0, m1, mp


def scene_node_set(m, name):
    """The nodes a scene gets for a set name: the node set, else the nodes of the facet set."""
    return m.node_sets[name] if name in m.node_sets else np.unique(m.facet_sets[name].facets)


def assert_same_mesh(m0, m1, mp):
    """Same blocks (by the node map), node sets, facet sets and interfaces. A node set holding only
    some copies of a split node comes back with every copy ("lossy", returned), unless it is the
    nodes of the facet set of its name: then it is left out of the file and a scene naming it gets
    the facet set's nodes, the same ones."""
    partial = partial_node_sets(m0, merge_map(m0)[0])
    via_facets = {n for n in partial if n in m0.facet_sets
                  and np.array_equal(np.unique(m0.facet_sets[n].facets), m0.node_sets[n])}
    lossy = sorted(set(partial) - via_facets)
    assert sorted(m1.node_sets) == sorted(set(m0.node_sets) - via_facets)
    for name, ids in m0.node_sets.items():
        if name in lossy:
            assert set(mp[ids]) < set(m1.node_sets[name].tolist())
        else:
            np.testing.assert_array_equal(np.sort(mp[ids]), scene_node_set(m1, name), err_msg=name)
    assert sorted(m1.facet_sets) == sorted(m0.facet_sets)
    for name, fs in m0.facet_sets.items():
        assert m1.facet_sets[name].type == fs.type
        assert sorted(map(tuple, mp[fs.facets].tolist())) == sorted(map(tuple, m1.facet_sets[name].facets.tolist()))
    assert sorted((j.name, j.type, len(j.cells)) for j in m0.joints) == \
        sorted((j.name, j.type, len(j.cells)) for j in m1.joints)
    return lossy


# ------------------------------------------------------------------------------------------------
# 2D: masonry wall with base and top beams, exported through the command line
# ------------------------------------------------------------------------------------------------
def test_wall_2d_exported_to_gmsh_gives_the_same_results(tmp_path, capsys):
    scene0_path = tmp_path / "wall.toml"
    scene0_path.write_text(WALL_TOML.format(mesh=WALL_MESH, joints=_joint_tables(JOINT_SETS)))
    msh = tmp_path / "wall.msh"
    assert main(["export-mesh", str(scene0_path), "-o", str(msh)]) == 0
    # 'beams' (nodes of the beam elements) holds only the beam's copies of the nodes on the beam
    # joints: written before interface insertion, it comes back with the units' copies too; the
    # command line says so in one line
    warned = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("masonrydam: warning:")]
    assert len(warned) == 1 and "'beams'" in warned[0]
    mesh_file = f'[mesh]\nfile = "{msh.name}"\njoints = {json.dumps(JOINT_SETS)}\n'
    scene1_path = tmp_path / "wall_from_file.toml"
    scene1_path.write_text(WALL_TOML.format(mesh=mesh_file, joints=_joint_tables(JOINT_SETS)))

    ds0 = masonrydam.run(scene0_path)
    ds1 = masonrydam.run(scene1_path)
    state = ds0.joint_state.isel(step=-1).values
    assert (state == 1).any() and (state == 2).any(), "the push should make joints slip and open"
    sc0, sc1 = Scene.from_toml(scene0_path), Scene.from_toml(scene1_path)
    m0, m1, mp = assert_same_results(sc0, sc0.base_dir, sc1, sc1.base_dir, ds0, ds1)
    assert assert_same_mesh(m0, m1, mp) == ["beams"]
    # the merged mesh keeps the generator's numbering, and insertion gives the same interfaces back
    np.testing.assert_array_equal(mp, np.arange(m0.n_nodes))


# ------------------------------------------------------------------------------------------------
# 3D: a base box and two boxes side by side on it (bed and head joints), pushed sideways
# ------------------------------------------------------------------------------------------------
def _boxes_scene(mesh):
    return {
        "model": {"name": "roundtrip_boxes", "dimension": 3},
        "mesh": mesh,
        "materials": {g: {"youngs_modulus": "30 GPa", "poisson_ratio": 0.2, "density": 2000.0}
                      for g in ("base", "left", "right")},
        "joints": {"joints": {"normal_stiffness": 1e10, "shear_stiffness": 1e10, "friction_angle": 30.0,
                              "cohesion": 0.0, "tensile_strength": 0.0}},
        "supports": [{"set": "base"}],  # the z = 0 plane (base_nodes would hold the base block's copies only)
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "push", "steps": 3,
                    "loads": [{"type": "displacement", "set": "top", "components": ["x", "z"],
                               "value": [4e-5, 0.0]}]}],
    }


BOXES = [{"x0": 0, "y0": 0, "z0": 0, "x1": 1.0, "y1": 0.5, "z1": 0.25, "group": "base"},
         {"x0": 0, "y0": 0, "z0": 0.25, "x1": 0.5, "y1": 0.5, "z1": 0.75, "group": "left"},
         {"x0": 0.5, "y0": 0, "z0": 0.25, "x1": 1.0, "y1": 0.5, "z1": 0.75, "group": "right"}]


def test_boxes_3d_exported_to_gmsh_give_the_same_results(tmp_path):
    scene0 = _boxes_scene({"generator": "blocks_3d", "parameters": {"blocks": BOXES, "element_size": 0.25}})
    sc0 = Scene(scene0)
    mesh0 = build_mesh(sc0.normalized, tmp_path)
    msh = tmp_path / "boxes.msh"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # base_nodes, left_nodes, right_nodes: the block's copies only
        write_mesh(mesh0, msh)
    scene1 = _boxes_scene({"file": str(msh), "joints": ["joints"]})
    sc1 = Scene(scene1)
    ds0 = masonrydam.run(scene0)
    ds1 = masonrydam.run(scene1)
    state = ds0.joint_state.isel(step=-1).values
    assert (state == 1).any() and (state == 2).any(), "the push should make the bed joint slip and the head joint open"
    m0, m1, mp = assert_same_results(sc0, tmp_path, sc1, tmp_path, ds0, ds1)
    # 'base' is both a block and a node set (the z = 0 plane): gmsh names groups per dimension
    assert "base" in m1.node_sets and "base" in m1.group_names()
    partial = assert_same_mesh(m0, m1, mp)
    assert set(partial) == {"base_nodes", "left_nodes", "right_nodes"}


@pytest.mark.parametrize("case", ["quad8", "tri6", "hex20", "rotated_hex8"])
def test_quadratic_and_rotated_meshes_read_back_exactly(tmp_path, case):
    """Without running: line3, quad8 and triangle faces, and coordinates of a rotated model, come back
    bit for bit, with the same interfaces after insertion."""
    from generators import blocks_3d, masonry_wall_2d

    if case in ("quad8", "tri6"):
        mesh = masonry_wall_2d(length=0.6, height=0.2, unit_length=0.2, unit_height=0.1, elements_per_unit=1,
                               order=2, element="quad" if case == "quad8" else "tri", base_beam_height=0.05)
    else:
        mesh = blocks_3d(BOXES, 0.25, order=2 if case == "hex20" else 1,
                         rotation_deg=[20.0, -35.0, 10.0] if case == "rotated_hex8" else None)
    path = tmp_path / "m.msh"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        write_mesh(mesh, path)
    back = read_mesh(path, mesh.joint_set_names(), mesh.dim)
    mp = node_map(mesh, back)
    # blocks_3d aligns the first shear axis of each face with +x before it rotates the model; read
    # back, the rotated faces get the rule applied in the rotated frame (corners cycled)
    joint_element_map(mesh, back, mp, exact=case != "rotated_hex8")
    assert_same_mesh(mesh, back, mp)


@pytest.mark.parametrize("dim", [2, 3])
def test_dam_sets_read_back(tmp_path, dim):
    """Gravity dams (gmsh-meshed): their face node sets are the nodes of the facet set of the same name,
    the owner's copies only (foundation_top: not the dam's); they are left out of the file and a scene
    naming them gets the same nodes through the facet set; nothing is lost, no warning."""
    from generators import gravity_dam_2d, gravity_dam_3d

    if dim == 2:
        mesh = gravity_dam_2d(preset="koyna", lift_spacing=20.6, element_size=8.0, foundation_width=120.0,
                              foundation_depth=30.0, reservoir_level=80.0)
    else:
        mesh = gravity_dam_3d(valley_bottom_width=40, valley_top_width=120, n_monoliths=3, height=40, crest_width=6,
                              lift_spacing=20, element_size=8.0, foundation_width=60, foundation_depth=10,
                              reservoir_level=35)
    path = tmp_path / "dam.msh"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_mesh(mesh, path)
    back = read_mesh(path, mesh.joint_set_names(), dim)
    mp = node_map(mesh, back)
    joint_element_map(mesh, back, mp)
    assert "foundation_top" in partial_node_sets(mesh, merge_map(mesh)[0])
    assert assert_same_mesh(mesh, back, mp) == []


def test_remove_interfaces_inverts_insert_interfaces():
    from generators import masonry_wall_2d

    mesh = masonry_wall_2d(length=0.6, height=0.3, unit_length=0.2, unit_height=0.1, elements_per_unit=2)
    conformal, faces = remove_interfaces(mesh)
    assert conformal.n_interfaces() == 0 and conformal.n_nodes < mesh.n_nodes
    joints = {}
    for name, fs in faces:
        joints.setdefault(name, []).append(fs.facets)
    again = insert_interfaces(conformal, {k: np.vstack(v) for k, v in joints.items()})
    np.testing.assert_array_equal(again.points, mesh.points)
    for a, b in zip(sorted(mesh.joints, key=lambda j: j.name), sorted(again.joints, key=lambda j: j.name)):
        np.testing.assert_array_equal(a.cells, b.cells)


def test_gmsh_file_reopened_and_saved_by_gmsh_reads_back(tmp_path):
    """Edited in gmsh: gmsh opens the file (names per dimension kept) and saves it in its own format
    (MSH 4.1, nodes renumbered); the scene mesh is still the same."""
    gmsh = pytest.importorskip("gmsh")
    from generators import masonry_wall_2d

    mesh = masonry_wall_2d(length=0.6, height=0.3, unit_length=0.2, unit_height=0.1, elements_per_unit=1)
    path, saved = tmp_path / "w.msh", tmp_path / "w_gmsh.msh"
    write_mesh(mesh, path)
    gmsh.initialize(["-noenv"])
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        names = {gmsh.model.getPhysicalName(d, t) for d, t in gmsh.model.getPhysicalGroups()}
        gmsh.write(str(saved))
    finally:
        gmsh.finalize()
    assert names == set(mesh.group_names()) | set(mesh.joint_set_names()) | set(mesh.node_sets) | set(mesh.facet_sets)
    back = read_mesh(saved, mesh.joint_set_names(), 2)
    mp = node_map(mesh, back)
    joint_element_map(mesh, back, mp)
    assert assert_same_mesh(mesh, back, mp) == []


# ------------------------------------------------------------------------------------------------
# errors
# ------------------------------------------------------------------------------------------------
def test_unknown_extension_lists_what_meshio_writes(tmp_path, capsys):
    from generators import masonry_wall_2d

    mesh = masonry_wall_2d(length=0.4, height=0.2, unit_length=0.2, unit_height=0.1, elements_per_unit=1)
    with pytest.raises(MasonrydamError) as err:
        write_mesh(mesh, tmp_path / "mesh.foo")
    msg = str(err.value)
    assert "'.foo'" in msg and ".vtu" in msg and ".msh" in msg and ".xdmf" in msg
    assert not (tmp_path / "mesh.foo").exists()
    with pytest.raises(MasonrydamError, match="does not exist") as err:
        write_mesh(mesh, tmp_path / "missing" / "mesh.msh")
    assert str(tmp_path / "missing") in str(err.value)
    # the command line: one line, exit code 2, before the scene is even read
    code = main(["export-mesh", str(tmp_path / "no_scene.toml"), "-o", str(tmp_path / "mesh.foo")])
    err_text = capsys.readouterr().err
    assert code == 2 and "unknown extension '.foo'" in err_text and ".msh" in err_text
    assert len(err_text.strip().splitlines()) == 1


def test_msh_output_takes_no_data_and_needs_zero_thickness_joints(tmp_path):
    from generators import masonry_wall_2d

    mesh = masonry_wall_2d(length=0.4, height=0.2, unit_length=0.2, unit_height=0.1, elements_per_unit=1)
    with pytest.raises(MeshError, match="without node or cell data"):
        write_mesh(mesh, tmp_path / "m.msh", point_data={"u": np.zeros((mesh.n_nodes, 2))})
    j = mesh.joints[0]
    mesh.points[j.cells[0, -1]] += 1e-3  # a top node off its bottom partner
    with pytest.raises(MeshError, match="zero-thickness"):
        write_mesh(mesh, tmp_path / "m.msh")
