"""Insertion of zero-thickness interface elements along named joints of a conformal mesh.

Given a conformal mesh (neighbouring blocks share nodes) and the facets that are joints, every node
on a joint is duplicated once per *side region* around it: the elements containing the node are
grouped by adjacency through facets that contain the node and are not joints; each group gets its
own copy. This is exact at T and cross junctions (masonry head joints meeting bed joints, lift
joints meeting contraction joints) and at quadratic mid-side nodes, in 2D and 3D alike.
Each joint facet then becomes one interface element whose bottom face carries the copies of the
element on the ``-n`` side and whose top face the copies of the element on the ``+n`` side.

Orientation rule (documented in docs/architecture.md): the facet is ordered so that its normal
(2D: tangent rotated +90 degrees) points up (+y), or +x for a vertical joint; "top" is the
element on the +n side. Slip is then positive when the top block moves along +x.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..elements.shapes import ELEMENT_TYPES
from ..errors import MeshError
from .model import CellBlock, FacetSet, Mesh

_INTERFACE_OF_FACE = {"line2": "interface_line2", "line3": "interface_line3"}


def _element_facets(mesh: Mesh):
    """All facets of all continuum elements.

    Returns (facet_nodes list per facet type, element id, local facet id, block index, facet type),
    flattened: nodes (n_f, nfn) for a single facet type (mixed-order meshes are rejected).
    """
    nodes, elem, local, ftype = [], [], [], None
    offset = 0
    for b in mesh.blocks:
        et = ELEMENT_TYPES[b.type]
        if et.dim != mesh.dim:
            raise MeshError(f"element type '{b.type}' is {et.dim}D in a {mesh.dim}D mesh", group=b.name)
        this = "line2" if len(et.edges[0]) == 2 else "line3"
        if ftype is None:
            ftype = this
        elif ftype != this:
            raise MeshError("mixing linear and quadratic elements in one mesh is not supported", group=b.name)
        for k, edge in enumerate(et.edges):
            nodes.append(b.cells[:, list(edge)])
            elem.append(offset + np.arange(len(b.cells)))
            local.append(np.full(len(b.cells), k))
        offset += len(b.cells)
    return np.vstack(nodes), np.concatenate(elem), np.concatenate(local), ftype


def _orient_up(points: np.ndarray, facet: np.ndarray) -> np.ndarray:
    """Order a 2D facet (line2/line3) so that its normal points +y (or +x when vertical)."""
    a, b = points[facet[0]], points[facet[1]]
    t = b - a
    normal = np.array([-t[1], t[0]])
    flip = normal[1] < -1e-12 * np.abs(t).max() or (abs(normal[1]) <= 1e-12 * np.abs(t).max() and normal[0] < 0)
    if flip:
        facet = facet.copy()
        facet[0], facet[1] = facet[1], facet[0]
    return facet


def insert_interfaces(mesh: Mesh, joint_facets: dict[str, np.ndarray]) -> Mesh:
    """Return a new mesh with interfaces inserted along ``joint_facets``.

    joint_facets: joint set name -> (n, nfn) facet node lists of the conformal mesh (corner nodes
    at least; order irrelevant). Node sets are mapped so that a set containing a split node
    contains all of its copies; facet sets follow the element that owns each boundary facet.
    """
    if mesh.dim != 2:
        raise MeshError("interface insertion is implemented for 2D meshes (3D comes with hexahedral blocks)")
    mesh.check()
    facet_nodes, facet_elem, facet_local, ftype = _element_facets(mesh)
    n_corner = 2
    keys = np.sort(facet_nodes[:, :n_corner], axis=1)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    n_unique = len(uniq)
    count = np.bincount(inverse, minlength=n_unique)
    key_index = {tuple(k): i for i, k in enumerate(map(tuple, uniq))}

    # mark joint facets
    joint_of = np.full(n_unique, -1, dtype=np.int64)
    set_names = list(joint_facets)
    for s, name in enumerate(set_names):
        arr = np.asarray(joint_facets[name], dtype=np.int64)
        if arr.ndim != 2 or arr.shape[1] < n_corner:
            raise MeshError(f"joint set '{name}': facets must be an (n, >=2) array of node indices")
        for f in arr:
            k = key_index.get(tuple(sorted(f[:n_corner])))
            if k is None:
                raise MeshError(f"joint set '{name}': facet with nodes {list(f)} is not an edge of any element")
            if count[k] != 2:
                raise MeshError(
                    f"joint set '{name}': facet with nodes {list(f)} lies on the model boundary "
                    "(a joint needs an element on each side)"
                )
            if joint_of[k] >= 0 and joint_of[k] != s:
                raise MeshError(f"facet {list(f)} belongs to joint sets '{set_names[joint_of[k]]}' and '{name}'")
            joint_of[k] = s
    is_joint_facet = joint_of[inverse] >= 0

    # elements' node lists in one flat table (element-major) to address incidences
    conn_list = [b.cells for b in mesh.blocks]
    elem_offsets = np.cumsum([0] + [len(c) for c in conn_list])
    joint_nodes = np.unique(facet_nodes[is_joint_facet])
    on_joint = np.zeros(mesh.n_nodes, dtype=bool)
    on_joint[joint_nodes] = True

    # incidences (element, node) for joint nodes
    inc_e, inc_n, inc_blk, inc_col = [], [], [], []
    for bi, c in enumerate(conn_list):
        e, col = np.nonzero(on_joint[c])
        inc_e.append(e + elem_offsets[bi])
        inc_n.append(c[e, col])
        inc_blk.append(np.full(len(e), bi))
        inc_col.append(col)
    inc_e = np.concatenate(inc_e)
    inc_n = np.concatenate(inc_n)
    inc_blk = np.concatenate(inc_blk)
    inc_col = np.concatenate(inc_col)
    n_inc = len(inc_e)
    inc_key = {(int(e), int(n)): i for i, (e, n) in enumerate(zip(inc_e, inc_n))}

    # union incidences across non-joint facets shared by two elements
    rows, cols = [], []
    order = np.argsort(inverse, kind="stable")
    starts = np.searchsorted(inverse[order], np.arange(n_unique))
    for k in np.nonzero((count == 2) & (joint_of < 0))[0]:
        i0, i1 = order[starts[k]], order[starts[k] + 1]
        e0, e1 = facet_elem[i0], facet_elem[i1]
        for n in facet_nodes[i0]:
            if on_joint[n]:
                rows.append(inc_key[(int(e0), int(n))])
                cols.append(inc_key[(int(e1), int(n))])
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_inc, n_inc))
    n_comp, comp = connected_components(graph, directed=False)

    # one copy per component; the first component of each node keeps the original index
    new_points = [mesh.points]
    copy_of_comp = np.empty(n_comp, dtype=np.int64)
    seen_node = {}
    next_id = mesh.n_nodes
    copies: dict[int, list[int]] = {}
    comp_node = np.empty(n_comp, dtype=np.int64)
    comp_node[comp] = inc_n
    for c in np.argsort(comp_node, kind="stable"):
        n = int(comp_node[c])
        if n not in seen_node:
            seen_node[n] = True
            copy_of_comp[c] = n
            copies[n] = [n]
        else:
            copy_of_comp[c] = next_id
            copies[n].append(next_id)
            new_points.append(mesh.points[n][None, :])
            next_id += 1
    points = np.vstack(new_points)

    new_blocks = [CellBlock(b.type, b.cells.copy(), b.name) for b in mesh.blocks]
    for i in range(n_inc):
        new_blocks[inc_blk[i]].cells[inc_e[i] - elem_offsets[inc_blk[i]], inc_col[i]] = copy_of_comp[comp[i]]

    def elem_cells(e):
        bi = np.searchsorted(elem_offsets, e, side="right") - 1
        return new_blocks[bi].cells[e - elem_offsets[bi]], bi

    def elem_centroid(e):
        c, _ = elem_cells(e)
        return points[c].mean(axis=0)

    # interface elements
    joint_cells: dict[str, list] = {name: [] for name in set_names}
    for k in np.nonzero(joint_of >= 0)[0]:
        i0, i1 = order[starts[k]], order[starts[k] + 1]
        e0, e1 = facet_elem[i0], facet_elem[i1]
        f = _orient_up(mesh.points, facet_nodes[i0])
        a, b = mesh.points[f[0]], mesh.points[f[1]]
        t = b - a
        normal = np.array([-t[1], t[0]])
        mid = 0.5 * (a + b)
        if np.dot(elem_centroid(e0) - mid, normal) > 0:
            e_bot, e_top = e1, e0
        else:
            e_bot, e_top = e0, e1
        bot = [int(copy_of_comp[comp[inc_key[(int(e_bot), int(n))]]]) for n in f]
        top = [int(copy_of_comp[comp[inc_key[(int(e_top), int(n))]]]) for n in f]
        joint_cells[set_names[joint_of[k]]].append(bot + top)
    itype = _INTERFACE_OF_FACE[ftype]
    joints = list(mesh.joints) + [
        CellBlock(itype, np.array(cells, dtype=np.int64).reshape(-1, 2 * facet_nodes.shape[1]), name)
        for name, cells in joint_cells.items()
    ]

    node_sets = {}
    for name, ids in mesh.node_sets.items():
        ids = [c for n in ids for c in copies.get(int(n), [int(n)])]
        node_sets[name] = np.unique(np.array(ids, dtype=np.int64))

    # facet sets: boundary facets follow their single owning element
    facet_sets = {}
    owner = {}
    for k in np.nonzero(count == 1)[0]:
        owner[k] = facet_elem[order[starts[k]]]
    for name, fs in mesh.facet_sets.items():
        out = []
        for f in fs.facets:
            k = key_index.get(tuple(sorted(f[:n_corner])))
            if k is None or k not in owner:
                out.append([int(copies.get(int(n), [int(n)])[0]) for n in f])
                continue
            cells, _ = elem_cells(owner[k])
            cellset = set(cells.tolist())
            mapped = []
            for n in f:
                cand = [c for c in copies.get(int(n), [int(n)]) if c in cellset]
                mapped.append(cand[0] if cand else int(n))
            out.append(mapped)
        facet_sets[name] = FacetSet(fs.type, np.array(out, dtype=np.int64).reshape(-1, fs.facets.shape[1]))

    out_mesh = Mesh(points, new_blocks, joints, node_sets, facet_sets)
    out_mesh.check()
    return out_mesh
