"""Joint lines: the planes of a dam's base and lifts as the stability checks and the uplift see them.

A joint set of a dam (``base_joint``, ``lift_joints``) holds many planes: each lift of the section in
2D, each lift of each monolith in 3D. :class:`JointLines` splits the integration points of the
interface groups of a few joint sets into those planes ("lines", after the 2D section), and gives
each point its distance ``s`` from the upstream end of its line along the downstream direction, its
elevation and, in 3D, its strip (the points of one line at the same position across the line's
width, which the crack of a cracked-base check grows along).

Lines are the connected pieces of a joint set (interface elements sharing nodes on both faces: the
base joints of two monoliths on one rock block share rock nodes but not dam nodes), merged where two pieces lie at the same elevation and overlap across the width (a gallery or
an opening cuts a lift into pieces that are still one sliding plane); pieces side by side across the
width (monoliths separated by contraction joints) stay separate lines. Names: the joint set's name
for a set with one line, else ``set/k`` with k = 1, 2, ... from the lowest line up (3D: then along
the width), counting the lines closer to horizontal than vertical; the others (the risers of a
benched abutment in a base joint) are ``set/steep-k``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components


class JointLines:
    """The lines of ``groups`` (interface groups, in this order).

    Point arrays cover the integration points of the groups, group after group, each group's
    ``(n_elem, nip)`` points flattened (``slices[i]`` is group i's range):

    - ``line`` (n_points,) int: line index; ``s`` (n_points,) m from the upstream end of the line;
      ``elevation`` (n_points,) m; ``strip`` (n_points,) int (global strip index); ``weight``
      (n_points,) m2: area represented by the point (length x thickness in 2D);
    - per line: ``names``, ``set_names``, ``length`` (m, upstream end to downstream end),
      ``toe_elevation`` and ``heel_elevation`` (m, mean elevation of the nodes at either end),
      ``centre`` (n_lines, dim) m, ``horizontal`` (bool: the line's normal is closer to the vertical than
      to the horizontal; the others, e.g. the risers of a benched abutment, carry no uplift and are not
      assessed).

    downstream: horizontal unit vector from the upstream face to the downstream face (dim,);
    vertical_axis: the index of the vertical coordinate.
    """

    def __init__(self, model, groups, downstream, vertical_axis: int):
        dim = model.dim
        self.groups = list(groups)
        self.downstream = d = np.asarray(downstream, dtype=np.float64)
        self.vertical_axis = vertical_axis
        up = np.zeros(dim)
        up[vertical_axis] = 1.0
        across = np.cross(d, up) if dim == 3 else None
        scale = float(np.ptp(model.coords, axis=0).max()) or 1.0
        tol = 1e-6 * scale
        sizes = [g.n_elem * g.nip for g in self.groups]
        starts = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.slices = [slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:])]
        n = int(starts[-1])
        self.n_points = n
        line = np.empty(n, dtype=np.int64)
        names, set_names, length, heel_z, toe_z, centre = [], [], [], [], [], []
        s = np.empty(n)
        strip = np.empty(n, dtype=np.int64)
        self.elevation = np.empty(n)
        self.weight = np.empty(n)
        self.x = np.empty((n, dim))
        by_set = {}
        for gi, g in enumerate(self.groups):
            by_set.setdefault(g.name, []).append(gi)
        n_lines = 0
        n_strips = 0
        for set_name in sorted(by_set):
            pieces = []  # (group index, element indices)
            for gi in by_set[set_name]:
                g = self.groups[gi]
                ns = g.conn.shape[1] // 2
                rows = np.repeat(np.arange(g.n_elem), ns)
                adjacent = None
                for face in (g.conn[:, :ns], g.conn[:, ns:]):
                    inc = sp.csr_matrix((np.ones(face.size), (rows, face.ravel())), shape=(g.n_elem, model.n_nodes))
                    a = inc @ inc.T
                    adjacent = a if adjacent is None else adjacent.multiply(a)
                k, lab = connected_components(adjacent, directed=False)
                pieces += [(gi, np.nonzero(lab == c)[0]) for c in range(k)]
            # merge pieces at the same elevation whose extents across the width overlap
            info = []
            for gi, el in pieces:
                g = self.groups[gi]
                nodes = np.unique(g.conn[el, : g.conn.shape[1] // 2])
                X = model.coords[nodes]
                z = float(X[:, vertical_axis].mean())
                w = (X @ across) if across is not None else np.zeros(1)
                info.append((z, float(w.min()), float(w.max())))
            parent = list(range(len(pieces)))

            def root(i):
                while parent[i] != i:
                    i = parent[i]
                return i

            for i in range(len(pieces)):
                for j in range(i + 1, len(pieces)):
                    zi, ai, bi = info[i]
                    zj, aj, bj = info[j]
                    same_level = abs(zi - zj) <= tol
                    overlap = across is None or min(bi, bj) - max(ai, aj) > tol
                    if same_level and overlap:
                        parent[root(j)] = root(i)
            groups_of = {}
            for i in range(len(pieces)):
                groups_of.setdefault(root(i), []).append(i)
            merged = sorted(groups_of.values(), key=lambda ids: (round(info[ids[0]][0] / tol), info[ids[0]][1]))
            for k, ids in enumerate(merged):
                li = n_lines + k
                names.append(set_name if len(merged) == 1 else f"{set_name}/{k + 1}")
                set_names.append(set_name)
                node_x = []
                for i in ids:
                    gi, el = pieces[i]
                    g = self.groups[gi]
                    node_x.append(model.coords[np.unique(g.conn[el, : g.conn.shape[1] // 2])])
                node_x = np.vstack(node_x)
                sd = node_x @ d
                s0, s1 = float(sd.min()), float(sd.max())
                length.append(s1 - s0)
                heel_z.append(float(node_x[sd <= s0 + tol, vertical_axis].mean()))
                toe_z.append(float(node_x[sd >= s1 - tol, vertical_axis].mean()))
                centre.append(node_x.mean(axis=0))
                line_points = []
                for i in ids:
                    gi, el = pieces[i]
                    g = self.groups[gi]
                    idx = (self.slices[gi].start + el[:, None] * g.nip + np.arange(g.nip)[None, :]).ravel()
                    line[idx] = li
                    p = g.points[el].reshape(-1, dim)
                    s[idx] = p @ d - s0
                    self.elevation[idx] = p[:, vertical_axis]
                    self.weight[idx] = (g.jw[el] * g.thickness[el][:, None]).ravel()
                    self.x[idx] = p
                    line_points.append(idx)
                idx = np.concatenate(line_points)
                if across is None:
                    strip[idx] = n_strips
                    n_strips += 1
                else:
                    key = np.round((self.x[idx] @ across) / tol).astype(np.int64)
                    _, inv = np.unique(key, return_inverse=True)
                    strip[idx] = n_strips + inv
                    n_strips += int(inv.max()) + 1
            n_lines += len(merged)
        self.line, self.s, self.strip = line, s, strip
        self.names, self.set_names = names, set_names
        self.length = np.array(length)
        self.heel_elevation, self.toe_elevation = np.array(heel_z), np.array(toe_z)
        self.centre = np.array(centre).reshape(-1, dim)
        self.n_lines, self.n_strips = n_lines, n_strips
        # lines closer to horizontal than to vertical (a bench riser of a base joint on a benched abutment
        # is a line of its own, and neither a sliding plane nor a plane uplift acts across)
        nv = np.abs(np.concatenate([g.frame[:, :, dim - 1, vertical_axis].ravel() for g in self.groups])) \
            if n else np.zeros(0)
        w = np.bincount(line, weights=self.weight, minlength=n_lines)
        self.horizontal = np.bincount(line, weights=nv * self.weight, minlength=n_lines) > np.sqrt(0.5) * w
        # numbers count the horizontal lines of a set; the others are named set/steep-k
        for set_name in sorted(set(set_names)):
            ids = [i for i in range(n_lines) if set_names[i] == set_name]
            flat = [i for i in ids if self.horizontal[i]]
            steep = [i for i in ids if not self.horizontal[i]]
            for k, i in enumerate(flat):
                names[i] = set_name if len(flat) == 1 and not steep else f"{set_name}/{k + 1}"
            for k, i in enumerate(steep):
                names[i] = f"{set_name}/steep-{k + 1}"
        # points in (strip, s) order, and where each strip starts in that order (cracks grow from the heel)
        self.order = np.lexsort((s, strip))
        counts = np.bincount(strip, minlength=n_strips)
        self.strip_start = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)

    def gather(self, per_group) -> np.ndarray:
        """One (n_points,) array from per-group arrays (each of ``(n_elem, nip)`` values), in point order."""
        return np.concatenate([np.asarray(a).reshape(-1) for a in per_group]) if per_group else np.zeros(0)

    def leading_open(self, is_open: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The crack from the heel of each strip: ``(cracked, tip)`` with cracked (n_points,) bool, True for
        the open points of the unbroken run of open points that starts at the strip's upstream end, and
        tip (n_strips,) m, the ``s`` of the last of them (-1 where the strip's first point is closed)."""
        o = is_open[self.order]
        closed_seen = np.cumsum(~o)
        before = np.concatenate([[0], closed_seen])[self.strip_start]  # closed points before each strip
        lead_sorted = (closed_seen - before[self.strip[self.order]]) == 0
        cracked = np.zeros(self.n_points, dtype=bool)
        cracked[self.order[lead_sorted]] = True
        tip = np.full(self.n_strips, -1.0)
        if cracked.any():
            np.maximum.at(tip, self.strip[cracked], self.s[cracked])
        return cracked, tip
