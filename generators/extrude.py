"""Extrusion of a 2D jointed model into a 3D slab.

A 2D model in the (x, y) plane (y up) becomes a 3D model with x kept, the 2D y axis as the 3D z
axis (up) and the thickness along 3D y in ``[0, depth]``. quad4 elements become hex8, 2-node line
interfaces become 8-node (4 + 4) surface interfaces (Tzamtzis & Asteris). The interface faces are ordered so
that the 3D local frame is the 2D one extended: normal = the 2D normal, first shear direction = the
2D tangent (so ``t1`` is the in-plane slip of the 2D model) and second shear direction = +y (out of
plane). With the out-of-plane displacement held on both faces, the slab is in plane strain and must
reproduce the 2D plane-strain answer (tested in tests/elements/test_interface3d.py).
"""
from __future__ import annotations

import numpy as np

from masonrydam.errors import MeshError, SceneError
from masonrydam.mesh.model import CellBlock, FacetSet, Mesh


def extrude_2d(mesh: Mesh, depth: float, layers: int = 1) -> Mesh:
    """Extrude a 2D linear mesh (quad4 blocks, interface_line2 joints) into hex8 / interface_quad4.

    depth: slab thickness (m) along 3D y; layers: elements through the thickness.
    Node sets are extruded (all layers) and gain 'front' (y = 0) and 'back' (y = depth); 2D edge
    facet sets become quad4 face sets; facet sets 'front_face' and 'back_face' are added.
    """
    if mesh.dim != 2:
        raise MeshError(f"extrude_2d needs a 2D mesh, got {mesh.dim}D")
    if not depth > 0 or int(layers) < 1:
        raise MeshError(f"extrude_2d: depth must be > 0 and layers >= 1, got depth={depth}, layers={layers}")
    layers = int(layers)
    n2 = mesh.n_nodes
    ys = np.linspace(0.0, depth, layers + 1)
    points = np.vstack([np.column_stack([mesh.points[:, 0], np.full(n2, y), mesh.points[:, 1]]) for y in ys])

    def at(nodes, k):
        return nodes + k * n2

    blocks = []
    for b in mesh.blocks:
        if b.type != "quad4":
            raise MeshError(f"extrude_2d supports quad4 blocks only, got '{b.type}'", group=b.name)
        c = b.cells
        # the upper layer first keeps the hexahedron right-handed: (x1-x0, x3-x0, x4-x0) = (+x, +z, -y)
        cells = [np.hstack([at(c, k + 1), at(c, k)]) for k in range(layers)]
        blocks.append(CellBlock("hex8", np.vstack(cells), b.name))
    joints = []
    for j in mesh.joints:
        if j.type != "interface_line2":
            raise MeshError(f"extrude_2d supports interface_line2 joints only, got '{j.type}'", group=j.name)
        b0, b1, t0, t1 = (j.cells[:, i] for i in range(4))
        cells = []
        for k in range(layers):
            # face (0 -> 1 along the 2D tangent, 1 -> 2 along +y): normal = tangent x (+y) = 2D normal
            bot = np.stack([at(b0, k), at(b1, k), at(b1, k + 1), at(b0, k + 1)], axis=1)
            top = np.stack([at(t0, k), at(t1, k), at(t1, k + 1), at(t0, k + 1)], axis=1)
            cells.append(np.hstack([bot, top]))
        joints.append(CellBlock("interface_quad4", np.vstack(cells), j.name))
    node_sets = {name: np.concatenate([at(ids, k) for k in range(layers + 1)]) for name, ids in mesh.node_sets.items()}
    node_sets["front"] = np.arange(n2)
    node_sets["back"] = np.arange(n2) + layers * n2
    facet_sets = {}
    for name, fs in mesh.facet_sets.items():
        if fs.type != "line2":
            raise MeshError(f"extrude_2d supports line2 facet sets only, got '{fs.type}' in '{name}'")
        a, b = fs.facets[:, 0], fs.facets[:, 1]
        # outward for a counter-clockwise 2D boundary: tangent x (-y) = the 2D outward normal
        facet_sets[name] = FacetSet("quad4", np.vstack([np.stack([at(a, k + 1), at(b, k + 1), at(b, k), at(a, k)], axis=1)
                                                       for k in range(layers)]))
    front, back = [], []
    for b in mesh.blocks:
        front.append(b.cells)  # counter-clockwise in (x, z): normal x-dir cross z-dir = -y, outward at y = 0
        back.append(at(b.cells[:, ::-1], layers))  # reversed: +y, outward at y = depth
    facet_sets["front_face"] = FacetSet("quad4", np.vstack(front))
    facet_sets["back_face"] = FacetSet("quad4", np.vstack(back))
    out = Mesh(points, blocks, joints, node_sets, facet_sets)
    out.check()
    return out


def extruded(generator: str, parameters: dict, depth: float, layers: int = 1, key: str = "mesh.parameters") -> Mesh:
    """Scene generator: run the 2D ``generator`` with ``parameters`` (plain SI numbers) and
    extrude its model to a slab of thickness ``depth`` (m) along y with ``layers`` elements through it."""
    # generators/__init__.py builds GENERATORS from the modules, this one among them: looked up when called
    from . import GENERATORS

    if generator not in GENERATORS or generator == "extruded":
        raise SceneError(f"{key}.generator", f"unknown 2D generator {generator!r}; use one of "
                                             f"{sorted(g for g in GENERATORS if g != 'extruded')}")
    if not isinstance(parameters, dict):
        raise SceneError(f"{key}.parameters", f"expected a table of the 2D generator's parameters, got {parameters!r}")
    try:
        mesh2d = GENERATORS[generator](**parameters)
    except TypeError as exc:
        raise SceneError(f"{key}.parameters", f"{generator}: {exc}") from None
    return extrude_2d(mesh2d, depth, layers)
