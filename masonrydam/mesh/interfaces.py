"""Insertion of zero-thickness interface elements along named joints of a conformal mesh (2D and 3D).

Given a conformal mesh (neighbouring blocks share nodes) and the facets that are joints (edges in
2D, faces in 3D), every node on a joint is duplicated once per *side region* around it: the
elements containing the node are grouped by adjacency through facets that contain the node and are
not joints; each group gets its own copy. This is exact at T and cross junctions (masonry head
joints meeting bed joints, lift joints meeting contraction joints, collar joints meeting both) and
at quadratic mid-side nodes. Each joint facet then becomes one interface element whose bottom face
carries the copies of the element on the ``-n`` side and whose top face the copies of the element
on the ``+n`` side.

Orientation rule (docs/architecture.md): the interface normal points "up": along the last axis
(+y in 2D, +z in 3D) when it has a component along it, else along the next axis down (+x in 2D;
+y, then +x in 3D). "Top" is the element on the +n side, so an opening is positive and, in 2D,
slip is positive when the top block moves along +x (along +y for a vertical joint... see below).
The local frame of the element kernels (masonrydam.elements.interface) is built from the face's
node order: in 2D the tangent runs from face node 0 to node 1 and the normal is the tangent turned
+90 degrees; in 3D the first tangent follows the face's xi direction (node 0 to node 1) and the
normal is the right-hand-rule normal of the face. In 3D the face's corners are also rotated
cyclically so that the first tangent is as close as possible to global +x (or to +z when the
joint is normal to x), so the first shear component of a bed joint is its x-slip.

The algorithm is vectorised with numpy (no per-facet Python loops), which matters for 3D walls of
thousands of units.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..elements.shapes import ELEMENT_TYPES
from ..errors import MeshError
from .facets import FACET_CORNERS, FacetTable, corner_keys
from .model import INTERFACE_FACE_TYPE, INTERFACE_OF_FACE, CellBlock, FacetSet, Mesh

#: cyclic rotation by one corner of each 3D facet type (new position k takes old node perm[k])
_ROTATE_ONE = {
    "quad4": [1, 2, 3, 0],
    "quad8": [1, 2, 3, 0, 5, 6, 7, 4],
    "tri3": [1, 2, 0],
    "tri6": [1, 2, 0, 4, 5, 3],
}


def _facet_normals(points: np.ndarray, nodes: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Normal of each facet (not normalised): 2D edge tangent turned -90 degrees (outward for a
    counter-clockwise element); 3D Newell normal of the corner polygon (right-hand rule)."""
    dim = points.shape[1]
    if dim == 2:
        t = points[nodes[:, 1]] - points[nodes[:, 0]]
        return np.stack([t[:, 1], -t[:, 0]], axis=1)
    n = np.zeros((len(nodes), 3))
    for nc in np.unique(corners):
        sel = np.nonzero(corners == nc)[0]
        x = points[nodes[sel, :nc]]  # (k, nc, 3)
        xn = np.roll(x, -1, axis=1)
        n[sel] = np.cross(x, xn).sum(axis=1) * 0.5
    return n


def _up_score(normal: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Signed "upness" of each normal: its last component if not negligible, else the one before."""
    dim = normal.shape[1]
    tol = 1e-9 * size
    score = np.zeros(len(normal))
    decided = np.zeros(len(normal), dtype=bool)
    for k in range(dim - 1, -1, -1):
        use = ~decided & (np.abs(normal[:, k]) > tol)
        score[use] = normal[use, k]
        decided |= use
    return score


def _align_first_tangent(points, faces, types, type_index):
    """Rotate 3D face node lists cyclically so that edge 0->1 is closest to +x (or +z when the face
    is normal to x). faces: (n, w) padded; returns a new array."""
    out = faces.copy()
    for ti, ftype in enumerate(types):
        sel = np.nonzero(type_index == ti)[0]
        if not len(sel):
            continue
        nc = FACET_CORNERS[ftype]
        nn = len(_ROTATE_ONE[ftype])
        f = out[sel, :nn]
        x = points[f[:, :nc]]
        normal = np.cross(x[:, 1] - x[:, 0], x[:, nc - 1] - x[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        ref = np.zeros_like(normal)
        ref[:, 0] = 1.0
        proj = ref - (ref * normal).sum(1, keepdims=True) * normal
        weak = np.linalg.norm(proj, axis=1) < 0.5
        ref2 = np.zeros_like(normal)
        ref2[:, 2] = 1.0
        proj[weak] = ref2[weak] - (ref2[weak] * normal[weak]).sum(1, keepdims=True) * normal[weak]
        best = np.full(len(sel), -np.inf)
        best_f = f.copy()
        cur = f.copy()
        for _ in range(nc):
            e = points[cur[:, 1]] - points[cur[:, 0]]
            score = (e * proj).sum(1) / np.linalg.norm(e, axis=1)
            better = score > best + 1e-12
            best[better] = score[better]
            best_f[better] = cur[better]
            cur = cur[:, _ROTATE_ONE[ftype]]
        out[sel, :nn] = best_f
    return out


def insert_interfaces(mesh: Mesh, joint_facets: dict[str, np.ndarray]) -> Mesh:
    """Return a new mesh with interfaces inserted along ``joint_facets`` (2D or 3D).

    joint_facets: joint set name -> (n, nfn) facet node lists of the conformal mesh (all nodes of
    the facet, or at least its corners; order irrelevant): edges in 2D, faces (3 or 4 corners) in
    3D. Node sets are mapped so that a set containing a split node contains all of its copies;
    facet sets follow the element that owns each boundary facet.
    """
    mesh.check()
    dim = mesh.dim
    ft = FacetTable(mesh)
    n_unique = len(ft.unique_keys)

    # mark joint facets
    joint_of = np.full(n_unique, -1, dtype=np.int64)
    set_names = list(joint_facets)
    for s, name in enumerate(set_names):
        arr = np.asarray(joint_facets[name], dtype=np.int64)
        if arr.ndim != 2 or (dim == 2 and arr.shape[1] < 2) or (dim == 3 and arr.shape[1] < 3):
            raise MeshError(f"joint set '{name}': facets must be an (n, >={dim}) array of node indices")
        if dim == 2:
            nc = 2
        else:
            nc = {3: 3, 6: 3, 4: 4, 8: 4}.get(arr.shape[1])
            if nc is None:
                raise MeshError(f"joint set '{name}': a 3D facet has 3, 4, 6 or 8 nodes, got {arr.shape[1]}")
        k = ft.lookup(corner_keys(arr, np.full(len(arr), nc)))
        if (k < 0).any():
            f = arr[np.nonzero(k < 0)[0][0]]
            what = "an edge" if dim == 2 else "a face"
            raise MeshError(f"joint set '{name}': facet with nodes {f.tolist()} is not {what} of any element")
        boundary = ft.count[k] != 2
        if boundary.any():
            f = arr[np.nonzero(boundary)[0][0]]
            raise MeshError(f"joint set '{name}': facet with nodes {f.tolist()} lies on the model boundary "
                            "(a joint needs an element on each side)")
        clash = (joint_of[k] >= 0) & (joint_of[k] != s)
        if clash.any():
            i = np.nonzero(clash)[0][0]
            raise MeshError(f"facet {arr[i].tolist()} belongs to joint sets '{set_names[joint_of[k[i]]]}' and '{name}'")
        joint_of[k] = s
    is_joint_facet = joint_of[ft.inverse] >= 0

    # incidences (element, node) of joint nodes, addressed by the key element*n_nodes + node
    conn_list = [b.cells for b in mesh.blocks]
    elem_offsets = np.cumsum([0] + [len(c) for c in conn_list])
    jn = ft.nodes[is_joint_facet]
    joint_nodes = np.unique(jn[jn >= 0])
    on_joint = np.zeros(mesh.n_nodes, dtype=bool)
    on_joint[joint_nodes] = True
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
    nn = np.int64(mesh.n_nodes)
    inc_code = inc_e * nn + inc_n
    inc_sort = np.argsort(inc_code)
    inc_code_sorted = inc_code[inc_sort]

    def incidence(e, n):
        return inc_sort[np.searchsorted(inc_code_sorted, e * nn + n)]

    # union incidences across non-joint facets shared by two elements
    shared = np.nonzero((ft.count == 2) & (joint_of < 0))[0]
    i0, i1 = ft.first[shared], ft.second[shared]
    rows, cols = [], []
    for c in range(ft.width):
        n = ft.nodes[i0, c]
        ok = n >= 0
        ok[ok] = on_joint[n[ok]]
        rows.append(incidence(ft.elem[i0[ok]], n[ok]))
        cols.append(incidence(ft.elem[i1[ok]], n[ok]))
    rows = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    cols = np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_inc, n_inc))
    n_comp, comp = connected_components(graph, directed=False)

    # one copy per component; per node, the component met first keeps the original index
    comp_node = np.empty(n_comp, dtype=np.int64)
    comp_node[comp] = inc_n
    by_node = np.lexsort((np.arange(n_comp), comp_node))
    first_of_node = np.ones(n_comp, dtype=bool)
    first_of_node[1:] = comp_node[by_node][1:] != comp_node[by_node][:-1]
    copy_of_comp = np.empty(n_comp, dtype=np.int64)
    extra = by_node[~first_of_node]
    copy_of_comp[by_node[first_of_node]] = comp_node[by_node[first_of_node]]
    copy_of_comp[extra] = mesh.n_nodes + np.arange(len(extra))
    points = np.vstack([mesh.points, mesh.points[comp_node[extra]]])
    inc_copy = copy_of_comp[comp]  # new node index of each incidence

    new_blocks = [CellBlock(b.type, b.cells.copy(), b.name) for b in mesh.blocks]
    for bi in range(len(new_blocks)):
        sel = inc_blk == bi
        new_blocks[bi].cells[inc_e[sel] - elem_offsets[bi], inc_col[sel]] = inc_copy[sel]

    # interface elements: bottom = element whose outward facet normal points up
    jf = np.nonzero(joint_of >= 0)[0]
    a, b = ft.first[jf], ft.second[jf]
    normal_a = _facet_normals(mesh.points, ft.nodes[a], ft.corners[a])
    size = np.abs(normal_a).max(axis=1)
    a_is_bottom = _up_score(normal_a, size) > 0
    bottom_f = np.where(a_is_bottom, a, b)
    top_f = np.where(a_is_bottom, b, a)
    # 3D: the bottom element's face order has its right-hand normal pointing into the top element;
    # 2D: the top element's edge order has its tangent turned +90 degrees pointing up
    face = ft.nodes[bottom_f] if dim == 3 else ft.nodes[top_f]
    tindex = ft.type_index[bottom_f]
    if dim == 3:
        face = _align_first_tangent(mesh.points, face, ft.types, tindex)
    joints = list(mesh.joints)
    for s, name in enumerate(set_names):
        in_set = joint_of[jf] == s
        present = np.unique(tindex[in_set]) if in_set.any() else np.array([0])
        for ti in present:
            ftype = ft.types[ti]
            if ftype not in INTERFACE_OF_FACE:
                raise MeshError(f"joint set '{name}': no interface element for facets of type '{ftype}' "
                                f"(supported: {sorted(INTERFACE_OF_FACE)})")
            nfn = ELEMENT_TYPES[ftype].n_nodes
            sel = np.nonzero(in_set & (tindex == ti))[0]
            f = face[sel, :nfn]
            eb = np.broadcast_to(ft.elem[bottom_f[sel]][:, None], f.shape)
            etop = np.broadcast_to(ft.elem[top_f[sel]][:, None], f.shape)
            bot = inc_copy[incidence(eb, f)] if len(sel) else np.zeros((0, nfn), dtype=np.int64)
            top = inc_copy[incidence(etop, f)] if len(sel) else np.zeros((0, nfn), dtype=np.int64)
            joints.append(CellBlock(INTERFACE_OF_FACE[ftype], np.hstack([bot, top]).reshape(-1, 2 * nfn), name))

    node_sets = {}
    split = comp_node[extra]  # original node of each extra copy
    for name, ids in mesh.node_sets.items():
        ids = np.asarray(ids, dtype=np.int64)
        add = (mesh.n_nodes + np.arange(len(extra)))[np.isin(split, ids)]
        node_sets[name] = np.unique(np.concatenate([ids, add]))

    # facet sets: boundary facets follow their single owning element
    facet_sets = {}
    all_cells = [nb.cells for nb in new_blocks]
    old_cells = conn_list
    for name, fs in mesh.facet_sets.items():
        arr = fs.facets
        nc = FACET_CORNERS.get(fs.type, dim)
        k = ft.lookup(corner_keys(arr, np.full(len(arr), nc)))
        owner = np.where((k >= 0), ft.elem[ft.first[np.maximum(k, 0)]], -1)
        owner[(k >= 0) & (ft.count[np.maximum(k, 0)] != 1)] = -1
        out = arr.copy()
        for bi in range(len(new_blocks)):
            sel = np.nonzero((owner >= elem_offsets[bi]) & (owner < elem_offsets[bi + 1]))[0]
            if not len(sel):
                continue
            old = old_cells[bi][owner[sel] - elem_offsets[bi]]  # (k, nen)
            new = all_cells[bi][owner[sel] - elem_offsets[bi]]
            for c in range(arr.shape[1]):
                match = old == arr[sel, c][:, None]
                has = match.any(axis=1)
                col = match.argmax(axis=1)
                out[sel[has], c] = new[has, col[has]]
        facet_sets[name] = FacetSet(fs.type, out)

    out_mesh = Mesh(points, new_blocks, joints, node_sets, facet_sets)
    out_mesh.check()
    return out_mesh


def remove_interfaces(mesh: Mesh) -> tuple[Mesh, list[tuple[str, FacetSet]]]:
    """The conformal mesh before interface insertion: the inverse of :func:`insert_interfaces`.

    Every node copy that an interface joins to another (bottom face node k with top face node k) is
    merged back into one node, by the interface connectivity (not by coordinates; the copies of a
    zero-thickness joint coincide in the undeformed configuration, which is checked). A merged node
    takes the smallest index among its copies and the nodes keep their order, so a mesh made by
    :func:`insert_interfaces` gets its original numbering back. Continuum blocks, node sets and facet
    sets are mapped onto the merged numbering (a node set holding one copy of a split node holds
    the merged node).

    Returns the mesh without joints and, for each interface block, ``(joint set name, FacetSet)``:
    the joint facets (edges in 2D, faces in 3D) in the face order of the interface, which
    :func:`insert_interfaces` takes back.
    """
    new, keep = merge_map(mesh)
    points = mesh.points[keep]
    blocks = [CellBlock(blk.type, new[blk.cells], blk.name) for blk in mesh.blocks]
    node_sets = {name: new[np.asarray(ids, dtype=np.int64)] for name, ids in mesh.node_sets.items()}
    facet_sets = {name: FacetSet(fs.type, new[fs.facets]) for name, fs in mesh.facet_sets.items()}
    faces = []
    for j in mesh.joints:
        nfn = j.cells.shape[1] // 2
        faces.append((j.name, FacetSet(INTERFACE_FACE_TYPE[j.type], new[j.cells[:, :nfn]])))
    return Mesh(points, blocks, [], node_sets, facet_sets), faces


def merge_map(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """``(new, keep)``: the merged index of every node when the node copies joined by interfaces are
    merged (see :func:`remove_interfaces`), and the node kept for each merged node (its smallest copy).
    Raises :class:`MeshError` when joined copies do not coincide."""
    mesh.check()
    n = mesh.n_nodes
    a, b = [], []
    for j in mesh.joints:
        nfn = j.cells.shape[1] // 2
        a.append(j.cells[:, :nfn].ravel())
        b.append(j.cells[:, nfn:].ravel())
    a = np.concatenate(a) if a else np.zeros(0, dtype=np.int64)
    b = np.concatenate(b) if b else np.zeros(0, dtype=np.int64)
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    n_comp, comp = connected_components(graph, directed=False)
    rep = np.full(n_comp, n, dtype=np.int64)
    np.minimum.at(rep, comp, np.arange(n, dtype=np.int64))  # smallest node of each component
    keep = np.sort(rep)
    rank = np.empty(n_comp, dtype=np.int64)
    rank[np.argsort(rep)] = np.arange(n_comp)
    new = rank[comp]
    if n:
        extent = float(np.ptp(mesh.points, axis=0).max())
        gap = np.linalg.norm(mesh.points - mesh.points[keep[new]], axis=1)
        if gap.max() > 1e-9 * max(extent, 1e-300):
            i = int(np.argmax(gap))
            raise MeshError(f"node {i} and its interface partner {int(keep[new[i]])} are {gap[i]:.3g} m apart: "
                            "only zero-thickness joints (coincident faces) can be merged into a conformal mesh")
    return new, keep


def partial_node_sets(mesh: Mesh, new: np.ndarray) -> list[str]:
    """Names of the node sets that hold some but not all copies of a node split by joints (``new``
    from :func:`merge_map`): merged, such a set holds the whole node, and insertion gives it every copy."""
    copies = np.bincount(new, minlength=int(new.max(initial=-1)) + 1)
    out = []
    for name, ids in mesh.node_sets.items():
        ids = np.unique(np.asarray(ids, dtype=np.int64))
        held = np.bincount(new[ids], minlength=len(copies))
        if ((held > 0) & (held < copies)).any():
            out.append(name)
    return sorted(out)
