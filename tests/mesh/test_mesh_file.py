"""A scene whose mesh comes from a gmsh file through meshio, with a joint inserted along a named
physical line: a block sliding on a frictional joint (a block on an incline with beta = 0: the
horizontal force at sliding is mu W)."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import masonrydam

gmsh = pytest.importorskip("gmsh")


def _write_two_blocks(path):
    gmsh.initialize(["-noenv"])
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("two_blocks")
        occ = gmsh.model.occ
        lower = occ.addRectangle(0, 0, 0, 2.0, 0.5)
        upper = occ.addRectangle(0, 0.5, 0, 2.0, 0.5)
        occ.fragment([(2, lower)], [(2, upper)])
        occ.synchronize()
        curves = gmsh.model.getEntities(1)

        def curves_at(y):
            out = []
            for _, c in curves:
                xmin, ymin, _, xmax, ymax, _ = gmsh.model.getBoundingBox(1, c)
                if abs(ymin - y) < 1e-6 and abs(ymax - y) < 1e-6:
                    out.append(c)
            return out

        gmsh.model.addPhysicalGroup(2, [lower], name="base")
        gmsh.model.addPhysicalGroup(2, [upper], name="block")
        gmsh.model.addPhysicalGroup(1, curves_at(0.5), name="joint")
        gmsh.model.addPhysicalGroup(1, curves_at(0.0), name="bottom")
        gmsh.model.addPhysicalGroup(1, curves_at(1.0), name="top")
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
        gmsh.option.setNumber("Mesh.Algorithm", 8)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


@pytest.mark.reference
def test_block_from_gmsh_file_slides_at_mu_w(tmp_path):
    msh = tmp_path / "two_blocks.msh"
    _write_two_blocks(msh)
    phi, rho = 30.0, 2000.0
    scene = {
        "model": {"name": "file_block", "thickness": 1.0},
        "mesh": {"file": str(msh), "joints": ["joint"]},
        "materials": {"base": {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": rho},
                      "block": {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": rho}},
        "joints": {"joint": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": phi}},
        "supports": [{"set": "bottom", "components": ["x", "y"]}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "push", "steps": 5,
                    "loads": [{"type": "displacement", "set": "top", "components": ["x", "y"], "value": [1e-4, 0.0]}]}],
    }
    ds = masonrydam.run(scene)
    W = rho * 9.80665 * 2.0 * 0.5
    top = np.isclose(ds.y.values, 1.0)
    H = ds.reaction.sel(component="x").values[-1][top].sum()
    assert ds.sizes["joint_point"] > 0
    assert (ds.joint_state.isel(step=-1).values == 1).all()
    assert H == pytest.approx(math.tan(math.radians(phi)) * W, rel=1e-3)


def _write_two_boxes_tet(path, order=1):
    """Two stacked boxes meshed with unstructured tetrahedra by gmsh, the shared face a joint."""
    gmsh.initialize(["-noenv"])
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("two_boxes")
        occ = gmsh.model.occ
        lower = occ.addBox(0, 0, 0, 1.0, 1.0, 0.4)
        upper = occ.addBox(0, 0, 0.4, 1.0, 1.0, 0.3)
        occ.fragment([(3, lower)], [(3, upper)])
        occ.synchronize()

        def faces_at(z):
            out = []
            for _, s in gmsh.model.getEntities(2):
                _, _, zmin, _, _, zmax = gmsh.model.getBoundingBox(2, s)
                if abs(zmin - z) < 1e-6 and abs(zmax - z) < 1e-6:
                    out.append(s)
            return out

        gmsh.model.addPhysicalGroup(3, [lower], name="base")
        gmsh.model.addPhysicalGroup(3, [upper], name="block")
        gmsh.model.addPhysicalGroup(2, faces_at(0.4), name="joint")
        gmsh.model.addPhysicalGroup(2, faces_at(0.0), name="bottom")
        gmsh.model.addPhysicalGroup(2, faces_at(0.7), name="top")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
        gmsh.model.mesh.generate(3)
        if order == 2:
            gmsh.model.mesh.setOrder(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


@pytest.mark.reference
def test_tetrahedral_gmsh_file_with_triangular_interfaces_slides_at_mu_w(tmp_path):
    """3D: a gmsh tetrahedral mesh read through meshio gets 6-node (3 + 3) triangular interfaces on
    the joint surface; a block pushed horizontally (oblique, in x and y) slides at mu W along the
    push (block on an incline, beta = 0)."""
    msh = tmp_path / "two_boxes.msh"
    _write_two_boxes_tet(msh)
    phi, rho = 30.0, 2000.0
    c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    d = 1e-4
    scene = {
        "model": {"name": "file_tets", "dimension": 3},
        "mesh": {"file": str(msh), "joints": ["joint"]},
        "materials": {g: {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": rho} for g in ("base", "block")},
        "joints": {"joint": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": phi}},
        "supports": [{"set": "bottom"}],
        "stages": [{"name": "gravity", "loads": [{"type": "self_weight"}]},
                   {"name": "push", "steps": 4,
                    "loads": [{"type": "displacement", "set": "top", "components": ["x", "y", "z"],
                               "value": [d * c, d * s, 0.0]}]}],
    }
    from masonrydam.scene import build_mesh
    from masonrydam.scene.scene import Scene

    mesh = build_mesh(Scene(scene).normalized, tmp_path)
    assert {j.type for j in mesh.joints} == {"interface_tri3"}
    assert {b.type for b in mesh.blocks} == {"tet4"}
    ds = masonrydam.run(scene)
    W = rho * 9.80665 * 1.0 * 1.0 * 0.3
    top = np.isclose(ds.z.values, 0.7)
    R = ds.reaction.isel(step=-1).values[top].sum(axis=0)
    assert (ds.joint_state.isel(step=-1).values == 1).all()
    mu = math.tan(math.radians(phi))
    assert math.hypot(R[0], R[1]) == pytest.approx(mu * W, rel=2e-3)
    assert math.atan2(R[1], R[0]) == pytest.approx(math.radians(30.0), abs=1e-3)
    assert float(ds.joint_weight.sum()) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("suffix", [".msh", ".vtu", ".xdmf"])
def test_export_keeps_groups_and_joints_apart(tmp_path, suffix):
    """Export for ParaView / gmsh: every continuum group and joint set stays identifiable after a
    round trip through the file (gmsh physical groups in .msh; 'group' and 'is_joint' cell data in
    VTU and XDMF), and the cell counts are the mesh's."""
    import meshio

    from generators import blocks_3d
    from masonrydam.mesh.io import write_mesh

    boxes = [{"x0": 0, "y0": 0, "z0": 0, "x1": 1, "y1": 1, "z1": 0.5, "group": "base"},
             {"x0": 0, "y0": 0, "z0": 0.5, "x1": 1, "y1": 1, "z1": 1.0, "group": "block"}]
    mesh = blocks_3d(boxes, 0.5, joint_name="bed")
    path = tmp_path / f"m{suffix}"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # base_nodes, block_nodes: only the block's copies (test_mesh_roundtrip)
        write_mesh(mesh, path)
    back = meshio.read(path)
    if suffix == ".msh":
        # the mesh before interface insertion: the joint as quadrangles (dimension 2), besides the
        # node sets (vertices) and facet sets; meshio's field_data names the highest dimension of a
        # name used twice (block 'base' and node set 'base')
        tags = np.concatenate(back.cell_data["gmsh:physical"])
        names = {name: int(v[0]) for name, v in back.field_data.items() if name in ("base", "block", "bed")}
        assert {name: int(back.field_data[name][1]) for name in names} == {"base": 3, "block": 3, "bed": 2}
        counts = {name: int((tags == t).sum()) for name, t in names.items()}
    else:
        group = np.concatenate(back.cell_data["group"])
        is_joint = np.concatenate(back.cell_data["is_joint"])
        unique = sorted({b.name for b in mesh.blocks} | {j.name for j in mesh.joints})
        counts = {name: int((group == k).sum()) for k, name in enumerate(unique)}
        assert int(is_joint.sum()) == mesh.n_interfaces()
    assert counts == {"base": 4, "block": 4, "bed": 4}
