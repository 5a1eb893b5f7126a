"""Mesh input and output through meshio.

Reading (:func:`read_mesh`): any format meshio reads (gmsh .msh, VTU, XDMF, ...). Continuum cells
are grouped by their named physical group (gmsh) or cell set; named groups one dimension lower
(lines in 2D, surfaces in 3D) become facet sets, and those listed as joints get interfaces inserted;
named vertex groups (and curve groups of a 3D mesh, and meshio point sets) become node sets (a scene
that names a facet set where it wants nodes gets the facet set's nodes, after insertion). A gmsh group
is named by its dimension and tag (``$PhysicalNames``), so one name may be used in several dimensions
(a block ``base`` and a node set ``base``).

Writing (:func:`write_mesh`), the format from the file's extension:

- ``.msh``: gmsh 2.2 ASCII, the mesh as gmsh would give it *before* interface insertion
  (:func:`to_gmsh`): the node copies of every interface merged back into one node, continuum blocks,
  joint sets (line elements in 2D, triangles/quadrangles in 3D) and facet sets as named physical
  groups, node sets as named physical groups of vertex elements. It reads back as a scene mesh
  (``[mesh] file = ..., joints = [...]``) with the same blocks, node sets, facet sets and interfaces,
  so a generated model can be edited in gmsh and analysed (a node set holding only one block's copies
  of the nodes on a joint is the exception: see :func:`to_gmsh`).
- anything else (``.vtu``, ``.xdmf``, ...): the ParaView view of :func:`to_meshio`: continuum blocks
  and interfaces as separate cell blocks; a 2D interface is written as a degenerate (zero-area) quad
  ``[b0, b1, t1, t0]`` (quadratic interfaces as two such quads), a 3D interface as a zero-volume
  hexahedron or wedge (the 16-node interface through its corners). Cell data ``group`` (index into the
  sorted group names, listed in ``field_data``) and ``is_joint`` tell the parts apart in single-list
  formats such as VTU.

An extension meshio does not write or a missing folder is a :class:`MasonrydamError` before any work
(:func:`check_mesh_output`).
"""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from ..checks import check_output_path
from ..elements.shapes import ELEMENT_TYPES, MESHIO_TO_TYPE
from ..errors import MasonrydamError, MeshError, SceneError
from .interfaces import insert_interfaces, merge_map, partial_node_sets, remove_interfaces
from .model import CellBlock, FacetSet, Mesh


def _gmsh_physical_names(path: Path) -> dict[tuple[int, int], str]:
    """``(dim, tag) -> name`` from the ``$PhysicalNames`` section of a gmsh file (ASCII in both the
    ASCII and the binary formats, before the nodes). meshio's ``field_data`` keeps one entry per
    name, which loses a name used in two dimensions."""
    out = {}
    with open(path, "rb") as f:
        for raw in f:
            head = raw.strip()
            if head == b"$PhysicalNames":
                for _ in range(int(f.readline())):
                    m = re.match(r'\s*(\d+)\s+(\d+)\s+"(.*)"\s*$', f.readline().decode("utf-8", "replace"))
                    if m:
                        out[(int(m[1]), int(m[2]))] = m[3]
                break
            if head in (b"$Entities", b"$Nodes", b"$Elements"):
                break
    return out


def read_mesh(path: str | Path, joints: list[str], dim: int = 2, key: str = "mesh.file") -> Mesh:
    # meshio (0.1 s to import) only for a scene with a mesh file: keeps a generated scene's start-up short
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
    names: dict[tuple[int, int], str] = {}
    for name, value in (m.field_data or {}).items():
        value = np.asarray(value).ravel()
        if len(value) >= 2:
            names[(int(value[1]), int(value[0]))] = name
    if path.suffix.lower() == ".msh":
        try:
            names.update(_gmsh_physical_names(path))
        except (OSError, ValueError):
            pass  # meshio's field_data then
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
            name = names.get((cdim, int(tag)), f"group{int(tag)}")
            if cdim == -1:
                raise MeshError(f"'{path}': unsupported cell type '{cb.type}' in group '{name}'")
            if cdim == dim:
                groups.setdefault((ctype, name), []).append(sel)
            elif cdim == dim - 1:  # facets: edges in 2D, faces in 3D
                facet_groups.setdefault(name, []).append((ctype, sel))
            elif cdim <= dim - 2:  # vertices (and curves of a 3D mesh): node sets
                node_sets.setdefault(name, []).extend(sel.ravel().tolist())
    for (gdim, _tag), name in names.items():
        if gdim == 0:
            node_sets.setdefault(name, [])  # a named vertex group without nodes: an empty node set
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
    node_sets = {k: np.array(v, dtype=np.int64) for k, v in node_sets.items()}
    # drop points not used by any cell (gmsh geometry points)
    used = np.zeros(len(points), dtype=bool)
    for b in blocks:
        used[b.cells.ravel()] = True
    new = np.cumsum(used) - 1
    if not used.all():
        points = points[used]
        blocks = [CellBlock(b.type, new[b.cells], b.name) for b in blocks]
        node_sets = {k: new[v[used[v]]] for k, v in node_sets.items()}
        facet_sets = {k: FacetSet(f.type, new[f.facets]) for k, f in facet_sets.items()}
    mesh = Mesh(points, blocks, [], node_sets, {k: v for k, v in facet_sets.items() if k not in joints})
    if not joints:
        return mesh
    return insert_interfaces(mesh, {j: facet_sets[j].facets for j in joints})


def to_meshio(mesh: Mesh, point_data=None, cell_data=None):
    """A ``meshio.Mesh`` for ParaView with one cell block per continuum group and per joint set
    (interfaces as degenerate cells; see the module docstring)."""
    # meshio (0.1 s to import) only for exports: keeps 'masonrydam run' start-up short
    import meshio

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
    field_data = {n: np.array([k + 1, mesh.dim]) for k, n in enumerate(unique)}
    return meshio.Mesh(pts, cells, point_data=point_data or {}, cell_data=cell_data, field_data=field_data)


def to_gmsh(mesh: Mesh):
    """``(meshio.Mesh, physical_names)``: the mesh as gmsh would give it before interface insertion.

    The node copies joined by interfaces are merged (:func:`masonrydam.mesh.interfaces.remove_interfaces`);
    each continuum group (dimension ``dim``), joint set and facet set (``dim - 1``: line2/line3 in 2D;
    triangles, quadrangles, quad8 in 3D) and node set (vertex elements, one per node, so overlapping
    sets each keep their nodes) is one physical group. ``physical_names`` lists ``(dim, tag, name)``;
    tags are unique over all dimensions and are also the elementary (geometrical) tags. The cell data
    ``gmsh:physical`` and ``gmsh:geometrical`` carry the tags.

    A node set that holds some but not all copies of a node split by joints (e.g. the nodes of one
    block) cannot be written before insertion: if it is the nodes of the facet set of its name it is
    left out (a scene naming it gets the facet set's nodes, the same ones), else it is written whole
    (read back, it holds every copy) with a warning. Raises :class:`MeshError` for joints of non-zero
    thickness, a facet set named like a joint set, or a name gmsh cannot hold.
    """
    # meshio (0.1 s to import) only for exports: keeps 'masonrydam run' start-up short
    import meshio

    conformal, faces = remove_interfaces(mesh)
    dim = mesh.dim
    for name in {b.name for b in conformal.blocks} | {n for n, _ in faces} | set(conformal.facet_sets) \
            | set(conformal.node_sets):
        if '"' in name or "\n" in name:
            raise MeshError(f"group name {name!r}: a gmsh physical name cannot hold a double quote or a line break")
    joint_names = {name for name, _ in faces}
    clash = sorted(joint_names & set(conformal.facet_sets))
    if clash:
        raise MeshError(f"facet set(s) {clash} have the name of a joint set: a gmsh file cannot tell them apart")
    tags: dict[tuple[int, str], int] = {}
    cells, phys = [], []

    def add(ctype: str, data: np.ndarray, gdim: int, name: str) -> None:
        tag = tags.setdefault((gdim, name), len(tags) + 1)
        if len(data):
            cells.append((ctype, np.asarray(data, dtype=np.int64)))
            phys.append(np.full(len(data), tag, dtype=np.int32))

    for b in conformal.blocks:
        add(ELEMENT_TYPES[b.type].meshio_name, b.cells, dim, b.name)
    for name, fs in faces:
        add(ELEMENT_TYPES[fs.type].meshio_name, fs.facets, dim - 1, name)
    for name, fs in conformal.facet_sets.items():
        add(ELEMENT_TYPES[fs.type].meshio_name, fs.facets, dim - 1, name)
    # a node set holding some but not all copies of a split node cannot be written before insertion
    # (read back, it gets every copy). One that is the nodes of the facet set of its name (as the dam
    # generators make them) is left out: a scene naming it gets that facet set's nodes, the same ones.
    lossy, via_facets = [], set()
    for name in partial_node_sets(mesh, merge_map(mesh)[0]):
        fs = mesh.facet_sets.get(name)
        if fs is not None and np.array_equal(np.unique(fs.facets), np.unique(mesh.node_sets[name])):
            via_facets.add(name)
        else:
            lossy.append(name)
    if lossy:
        warnings.warn(f"node set(s) {lossy} hold only some copies of nodes split by joints; the gmsh file holds "
                      "the mesh before interface insertion, which gives them every copy", stacklevel=3)
    for name, ids in conformal.node_sets.items():
        if name not in via_facets:
            add("vertex", np.unique(ids)[:, None], 0, name)
    pts = conformal.points if dim == 3 else np.column_stack([conformal.points, np.zeros(conformal.n_nodes)])
    m = meshio.Mesh(pts, cells, cell_data={"gmsh:physical": phys, "gmsh:geometrical": [p.copy() for p in phys]})
    return m, sorted((gdim, tag, name) for (gdim, name), tag in tags.items())


def writable_extensions() -> list[str]:
    """File extensions that meshio writes (from its registry), sorted."""
    # meshio (0.1 s to import) only for exports: keeps 'masonrydam run' start-up short
    import meshio

    registry = getattr(meshio, "extension_to_filetypes", None)
    if registry is None:
        # (a meshio that does not export its registry at the top keeps it in meshio._helpers)
        from meshio import _helpers as registry_module

        registry = registry_module.extension_to_filetypes
    writers = getattr(getattr(meshio, "_helpers", None), "_writer_map", None)
    return sorted(ext for ext, types in registry.items() if writers is None or any(t in writers for t in types))


def _extension(path: Path) -> str | None:
    """The (possibly compound, e.g. ``.vol.gz``) extension of ``path`` that meshio writes, else None."""
    exts = set(writable_extensions())
    ext = ""
    for suffix in reversed(path.suffixes):
        ext = (suffix + ext).lower()
        if ext in exts:
            return ext
    return None


def check_mesh_output(path: str | Path, option: str = "mesh file") -> Path:
    """Check that a mesh can be written to ``path`` (before any work): an extension meshio writes, and
    a writable folder (:func:`~masonrydam.checks.check_output_path`; errors name ``option``).
    Raises :class:`MasonrydamError` saying what is wrong."""
    path = Path(path)
    if _extension(path) is None:
        what = f"unknown extension '{path.suffix}'" if path.suffix else "no extension"
        raise MasonrydamError(f"cannot write mesh file '{path}': {what}; meshio writes "
                              + ", ".join(writable_extensions()))
    return check_output_path(path, option)


def write_mesh(mesh: Mesh, path: str | Path, point_data=None, cell_data=None) -> None:
    """Write ``mesh`` with meshio, the format from the extension: ``.msh`` (gmsh 2.2 ASCII before
    interface insertion, readable as a scene mesh; see :func:`to_gmsh`), ``.vtu`` (ParaView),
    ``.xdmf`` (XDMF + HDF5) or any other extension meshio writes (:func:`to_meshio`).

    ``point_data`` and ``cell_data`` (per node and per cell of :func:`to_meshio`) go to the ParaView
    formats; a ``.msh`` file holds the mesh only. Raises :class:`MasonrydamError` for an extension meshio
    does not write, a missing directory, or a write that fails.
    """
    path = check_mesh_output(path)
    ext = _extension(path)
    if ext == ".msh":
        if point_data or cell_data:
            raise MeshError("a .msh file holds the mesh before interface insertion, without node or cell data; "
                            "write data to .vtu or .xdmf")
        m, physical_names = to_gmsh(mesh)
        _write(m, path, "gmsh22", binary=False)
        _insert_physical_names(path, physical_names)
        return
    _write(to_meshio(mesh, point_data, cell_data), path, None)


def _write(m, path: Path, file_format: str | None, **kwargs) -> None:
    try:
        m.write(path, file_format=file_format, **kwargs)
    except OSError as exc:
        raise MasonrydamError(f"cannot write mesh file '{path}': {exc.strerror or exc}") from None
    except Exception as exc:  # meshio raises many types (WriteError, KeyError, ValueError, ...)
        raise MasonrydamError(f"meshio could not write '{path}': {type(exc).__name__}: {exc}") from exc


def _insert_physical_names(path: Path, physical_names) -> None:
    """Put a ``$PhysicalNames`` section after ``$MeshFormat`` of the gmsh file meshio wrote: gmsh keys
    names by dimension and tag, so a name may appear in several dimensions (meshio's ``field_data``
    cannot hold that). Entries go by dimension, so meshio's reader, which keeps the last entry of a name,
    names a tag of the highest dimension."""
    if not physical_names:
        return
    lines = [f"{len(physical_names)}"] + [f'{d} {t} "{n}"' for d, t, n in physical_names]
    section = ("$PhysicalNames\n" + "\n".join(lines) + "\n$EndPhysicalNames\n").encode()
    data = path.read_bytes()
    marker = b"$EndMeshFormat\n"
    at = data.index(marker) + len(marker)
    path.write_bytes(data[:at] + section + data[at:])
