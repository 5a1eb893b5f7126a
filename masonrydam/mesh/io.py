"""Mesh input and output through meshio.

Reading (:func:`read_mesh`): any format meshio reads (gmsh .msh, VTU, XDMF, ...). Continuum cells
are grouped by their named physical group (gmsh) or cell set; named lower-dimensional groups become
facet sets and node sets; the facet groups listed as joints get interfaces inserted.

Writing (:func:`to_meshio`): continuum blocks and interfaces as separate cell blocks, so ParaView
shows units and joints; a 2D interface is written as a degenerate (zero-area) quad
``[b0, b1, t1, t0]`` (quadratic interfaces as two such quads), a 3D interface as a zero-volume
hexahedron or wedge (the 16-node interface through its corners). Cell data ``group`` (index into the
sorted group names, listed in ``field_data``) and ``is_joint`` tell the parts apart in single-list
formats such as VTU.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..elements.shapes import ELEMENT_TYPES, MESHIO_TO_TYPE
from ..errors import MeshError, SceneError
from .interfaces import insert_interfaces
from .model import CellBlock, FacetSet, Mesh


def read_mesh(path: str | Path, joints: list[str], dim: int = 2, key: str = "mesh.file") -> Mesh:
    import meshio

    path = Path(path)
    if not path.exists():
        raise SceneError(key, f"mesh file '{path}' does not exist")
    try:
        m = meshio.read(path)
    except Exception as exc:  # meshio raises many types
        raise SceneError(key, f"meshio could not read '{path}': {exc}") from None
    points = m.points[:, :dim].copy()
    if m.points.shape[1] > dim and np.abs(m.points[:, dim:]).max(initial=0) > 0:
        raise SceneError(key, f"'{path}' has non-zero z coordinates but the scene is {dim}D")
    tag_name = {}
    for name, (tag, _gdim) in (m.field_data or {}).items():
        tag_name[int(tag)] = name
    phys = m.cell_data.get("gmsh:physical")
    groups: dict[tuple, list] = {}
    facet_groups: dict[str, list] = {}
    node_sets: dict[str, list] = {}
    for bi, cb in enumerate(m.cells):
        tags = phys[bi] if phys is not None else np.zeros(len(cb.data), dtype=int)
        ctype = MESHIO_TO_TYPE.get(cb.type)
        cdim = ELEMENT_TYPES[ctype].dim if ctype else (0 if cb.type == "vertex" else -1)
        for tag in np.unique(tags):
            sel = cb.data[tags == tag]
            name = tag_name.get(int(tag), f"group{int(tag)}")
            if cdim == 0:
                node_sets.setdefault(name, []).extend(sel.ravel().tolist())
            elif cdim == dim - 1:  # facets: edges in 2D, faces in 3D
                facet_groups.setdefault(name, []).append((ctype, sel))
                node_sets.setdefault(name, []).extend(sel.ravel().tolist())
            elif cdim == dim:
                groups.setdefault((ctype, name), []).append(sel)
            elif cdim == -1:
                raise MeshError(f"'{path}': unsupported cell type '{cb.type}' in group '{name}'")
            # lower-dimensional groups (e.g. curves of a 3D mesh) carry no load or joint here
    for name, ids in (m.point_sets or {}).items():
        node_sets.setdefault(name, []).extend(np.asarray(ids).ravel().tolist())
    blocks = [CellBlock(t, np.vstack(v), name) for (t, name), v in sorted(groups.items())]
    if not blocks:
        raise MeshError(f"'{path}' contains no {dim}D continuum cells")
    facet_sets = {}
    for name, lst in facet_groups.items():
        types = {t for t, _ in lst}
        if len(types) > 1:
            raise MeshError(f"'{path}': facet group '{name}' mixes cell types {sorted(types)}")
        facet_sets[name] = FacetSet(types.pop(), np.vstack([a for _, a in lst]))
    what = "line" if dim == 2 else "surface"
    for j in joints:
        if j not in facet_sets:
            raise SceneError("mesh.joints", f"joint group '{j}' is not a {what} group of '{path}' "
                                            f"({what} groups: {sorted(facet_sets)})")
    mesh = Mesh(points, blocks, [], {k: np.array(v) for k, v in node_sets.items()},
                {k: v for k, v in facet_sets.items() if k not in joints})
    # drop points not used by any cell (gmsh geometry points)
    used = np.zeros(len(points), dtype=bool)
    for b in blocks:
        used[b.cells.ravel()] = True
    if not used.all():
        new = np.cumsum(used) - 1
        mesh = Mesh(points[used], [CellBlock(b.type, new[b.cells], b.name) for b in blocks], [],
                    {k: new[v[used[v]]] for k, v in mesh.node_sets.items()},
                    {k: FacetSet(f.type, new[f.facets]) for k, f in mesh.facet_sets.items()})
    if not joints:
        return mesh
    return insert_interfaces(mesh, {j: facet_sets[j].facets if used.all() else
                                    (np.cumsum(used) - 1)[facet_sets[j].facets] for j in joints})


def to_meshio(mesh: Mesh, point_data=None, cell_data=None):
    """A ``meshio.Mesh`` with one cell block per continuum group and per joint set."""
    import meshio

    from ..elements.shapes import ELEMENT_TYPES

    cells = []
    for b in mesh.blocks:
        cells.append((ELEMENT_TYPES[b.type].meshio_name, b.cells))
    for j in mesh.joints:
        c = j.cells
        if j.type == "interface_line2":
            cells.append(("quad", c[:, [0, 1, 3, 2]]))
        elif j.type == "interface_line3":
            cells.append(("quad", np.vstack([c[:, [0, 2, 5, 3]], c[:, [2, 1, 4, 5]]])))
        elif j.type == "interface_quad4":
            cells.append(("hexahedron", c))  # zero-volume hexahedron: bottom face, then top face
        elif j.type == "interface_tri3":
            cells.append(("wedge", c))
        else:  # interface_quad8: drawn through its corners
            cells.append(("hexahedron", c[:, [0, 1, 2, 3, 8, 9, 10, 11]]))
    pts = mesh.points if mesh.dim == 3 else np.column_stack([mesh.points, np.zeros(mesh.n_nodes)])
    # formats such as VTU keep one cell list: tag every cell with its group (continuum group or joint
    # set) and whether it is a joint, so ParaView can threshold units, beams and joints apart
    names = [b.name for b in mesh.blocks] + [j.name for j in mesh.joints]
    unique = sorted(set(names))
    cell_data = dict(cell_data or {})
    cell_data["group"] = [np.full(len(c), unique.index(n), dtype=np.int32) for (_, c), n in zip(cells, names)]
    cell_data["is_joint"] = [np.full(len(c), int(i >= len(mesh.blocks)), dtype=np.int32) for i, (_, c) in enumerate(cells)]
    # gmsh physical groups (tags from 1), so a .msh file keeps every group and joint set apart
    cell_data["gmsh:physical"] = [g + 1 for g in cell_data["group"]]
    cell_data["gmsh:geometrical"] = [g + 1 for g in cell_data["group"]]
    field_data = {n: np.array([k + 1, mesh.dim]) for k, n in enumerate(unique)}
    return meshio.Mesh(pts, cells, point_data=point_data or {}, cell_data=cell_data, field_data=field_data)


def write_mesh(mesh: Mesh, path: str | Path, point_data=None, cell_data=None) -> None:
    """Write ``mesh`` with meshio, the format from the suffix: ``.vtu`` (ParaView), ``.msh`` (gmsh 2.2
    ASCII with one physical group per element group and joint set), ``.xdmf`` (XDMF + HDF5)."""
    path = Path(path)
    m = to_meshio(mesh, point_data, cell_data)
    if path.suffix == ".msh":
        # physical groups carry the grouping; other cell data as ElementData is not read back by meshio
        m.cell_data = {k: v for k, v in m.cell_data.items() if k.startswith("gmsh:")}
        m.write(path, file_format="gmsh22", binary=False)
        return
    # only gmsh understands the gmsh:* cell data
    m.cell_data.pop("gmsh:physical")
    m.cell_data.pop("gmsh:geometrical")
    m.write(path)
