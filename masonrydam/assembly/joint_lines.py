"""Joint lines: the planes of a dam's base and lifts as the stability checks and the uplift see them.

A joint set of a dam (``base_joint``, ``lift_joints``) holds many planes: each lift of the section in
2D, each lift of each monolith in 3D. :class:`JointLines` splits the integration points of the
interface groups of a few joint sets into those planes ("lines", after the 2D section), and gives
each point its distance ``s`` from the upstream end of its line along the downstream direction, its
elevation and, in 3D, its strip (the points of one line at the same position across the line's
width, which the crack of a cracked-base check grows along).

Each line has its own frame. In 2D, and in 3D where the upstream face is not known, it is the dam's
one downstream direction. In 3D with the upstream face's nodes and normals (``upstream_face``), a line
takes the way its own heel faces: the horizontal normals of the upstream face at the nodes the line
shares with it.
- Where those normals are parallel (a gravity monolith, or any plane face), the line is straight:
  ``s`` is the distance along that direction.
- Where they turn (an arch: every monolith faces radially), the line is curved: its centre in plan is
  that of the circle through its heel nodes, and ``s`` is the radial distance from the line's
  upstream end, with strips along the radii.
So each cantilever of an arch is measured through its own thickness, and not along the valley's one
downstream direction.

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
    vertical_axis: the index of the vertical coordinate; upstream_face: None, or (3D) the upstream
    face's nodes (m, dim) m and their horizontal outward unit normals (m, dim) (see the module
    docstring). Per line: ``direction`` (n_lines, dim), the horizontal unit vector downstream at the
    line's middle, and ``curved`` (n_lines,) bool, with ``plan_centre`` (n_lines, dim) m for the curved ones.
    """

    def __init__(self, model, groups, downstream, vertical_axis: int, upstream_face=None):
        dim = model.dim
        self.groups = list(groups)
        self.downstream = d = np.asarray(downstream, dtype=np.float64)
        self.vertical_axis = vertical_axis
        up = np.zeros(dim)
        up[vertical_axis] = 1.0
        across = np.cross(d, up) if dim == 3 else None
        scale = float(np.ptp(model.coords, axis=0).max()) or 1.0
        tol = 1e-6 * scale
        dam_frame = _Frame(d, up)
        heel_finder = None
        if upstream_face is not None and dim == 3:
            heel_finder = _HeelFinder(upstream_face, d, up, tol)
        sizes = [g.n_elem * g.nip for g in self.groups]
        starts = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.slices = [slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:])]
        n = int(starts[-1])
        self.n_points = n
        line = np.empty(n, dtype=np.int64)
        names, set_names, length, heel_z, toe_z, centre, frames, origins = [], [], [], [], [], [], [], []
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
            # each piece's nodes, elevation and own frame (None: it does not reach the upstream face)
            info = []
            for gi, el in pieces:
                g = self.groups[gi]
                X = model.coords[np.unique(g.conn[el, : g.conn.shape[1] // 2])]
                frame = None if heel_finder is None else heel_finder.frame(X)
                info.append((float(X[:, vertical_axis].mean()), frame, X))
            # merge pieces at the same elevation, in one frame, whose extents across the width overlap
            parent = list(range(len(pieces)))

            def root(i):
                while parent[i] != i:
                    i = parent[i]
                return i

            for i in range(len(pieces)):
                for j in range(i + 1, len(pieces)):
                    (zi, fi, Xi), (zj, fj, Xj) = info[i], info[j]
                    if abs(zi - zj) > tol:
                        continue
                    if across is None:
                        parent[root(j)] = root(i)
                        continue
                    if fi is not None and fj is not None and not fi.same(fj, tol):
                        continue
                    f = fi or fj or dam_frame
                    ai, aj = f.coordinates(Xi)[1], f.coordinates(Xj)[1]
                    if min(ai.max(), aj.max()) - max(ai.min(), aj.min()) > tol:
                        parent[root(j)] = root(i)
            groups_of = {}
            for i in range(len(pieces)):
                groups_of.setdefault(root(i), []).append(i)
            # lines from the lowest up, then along the dam's axis
            width = [float((info[ids[0]][2] @ across).min()) if across is not None else 0.0
                     for ids in groups_of.values()]
            merged = [ids for _, ids in sorted(zip(width, groups_of.values()),
                                               key=lambda wi: (round(info[wi[1][0]][0] / tol), wi[0]))]
            for k, ids in enumerate(merged):
                li = n_lines + k
                frame = next((info[i][1] for i in ids if info[i][1] is not None), dam_frame)
                frames.append(frame)
                names.append(set_name if len(merged) == 1 else f"{set_name}/{k + 1}")
                set_names.append(set_name)
                node_x = np.vstack([info[i][2] for i in ids])
                sd = frame.coordinates(node_x)[0]
                s0, s1 = float(sd.min()), float(sd.max())
                origins.append(s0)
                length.append(s1 - s0)
                end = frame.end_tolerance(tol, s1 - s0)
                heel_z.append(float(node_x[sd <= s0 + end, vertical_axis].mean()))
                toe_z.append(float(node_x[sd >= s1 - end, vertical_axis].mean()))
                centre.append(node_x.mean(axis=0))
                line_points = []
                for i in ids:
                    gi, el = pieces[i]
                    g = self.groups[gi]
                    idx = (self.slices[gi].start + el[:, None] * g.nip + np.arange(g.nip)[None, :]).ravel()
                    line[idx] = li
                    p = g.points[el].reshape(-1, dim)
                    s[idx] = frame.coordinates(p)[0] - s0
                    self.elevation[idx] = p[:, vertical_axis]
                    self.weight[idx] = (g.jw[el] * g.thickness[el][:, None]).ravel()
                    self.x[idx] = p
                    line_points.append(idx)
                idx = np.concatenate(line_points)
                if across is None:
                    strip[idx] = n_strips
                    n_strips += 1
                else:
                    inv = frame.strips(self.x[idx], tol)
                    strip[idx] = n_strips + inv
                    n_strips += int(inv.max()) + 1
            n_lines += len(merged)
        self.frames = frames
        self.direction = np.array([f.direction for f in frames]).reshape(-1, dim)
        self.curved = np.array([f.centre is not None for f in frames], dtype=bool)
        self.plan_centre = np.array([f.centre if f.centre is not None else np.full(dim, np.nan)
                                     for f in frames]).reshape(-1, dim)
        #: per line, how close two values of ``s`` are to count as one row of points (heel, toe), m
        self.end_tolerance = np.array([f.end_tolerance(tol, L) for f, L in zip(frames, length)])
        self.line, self.s, self.strip = line, s, strip
        self.names, self.set_names = names, set_names
        self.length = np.array(length)
        self.heel_elevation, self.toe_elevation = np.array(heel_z), np.array(toe_z)
        self.centre = np.array(centre).reshape(-1, dim)
        self.n_lines, self.n_strips = n_lines, n_strips
        self._origin = np.array(origins)  # per line, the frame's s at the line's upstream end
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

    def coordinates(self, x: np.ndarray, line: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(s, across)`` (m) of points ``x`` (n, dim) on lines ``line`` (n,): the distance from each line's
        upstream end in the line's frame (as ``s``), and the position across the line's width (arc length
        on the heel's circle for a curved line; zeros in 2D)."""
        x = np.asarray(x, dtype=np.float64).reshape(-1, len(self.downstream))
        line = np.asarray(line, dtype=np.int64).reshape(-1)
        s = np.empty(len(x))
        a = np.empty(len(x))
        for li in np.unique(line):
            at = line == li
            s[at], a[at] = self.frames[li].coordinates(x[at])
            s[at] -= self._origin[li]
        return s, a

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


class _Frame:
    """How one joint line measures its points.

    Straight (``centre`` None): ``s`` along the horizontal unit vector ``direction`` (dim,), and across
    the line along ``direction x up``. Curved: about the vertical axis through ``centre`` (dim,) m
    (its vertical component zero), ``s`` the radial distance from the heel (towards the centre for
    ``sign`` +1, an arch whose centre lies downstream; away from it for -1), and across the line the
    arc length at ``radius`` (m, the heel's mean radius); ``direction`` is then the downstream radial
    direction at the middle of the heel."""

    def __init__(self, direction, up, centre=None, sign: float = 1.0, radius: float = 0.0):
        self.direction = np.asarray(direction, dtype=np.float64)
        self.up = up
        self.across_axis = np.cross(self.direction, up) if len(up) == 3 else None
        self.centre, self.sign, self.radius = centre, float(sign), float(radius)

    def coordinates(self, x):
        """``(s_raw, across)`` (m) of points ``x`` (n, dim): ``s_raw`` grows downstream (the line's ``s``
        is it less its value at the line's upstream end)."""
        x = np.asarray(x, dtype=np.float64)
        if self.centre is None:
            a = x @ self.across_axis if self.across_axis is not None else np.zeros(len(x))
            return x @ self.direction, a
        rel = x - self.centre
        rel -= np.outer(rel @ self.up, self.up)
        r = np.linalg.norm(rel, axis=1)
        angle = np.arctan2(rel @ self.across_axis, rel @ (-self.sign * self.direction))
        return -self.sign * r, self.sign * angle * self.radius

    def same(self, other, tol: float) -> bool:
        """Whether ``other`` measures as this frame does (pieces of one line: a lift cut by a gallery)."""
        if (self.centre is None) != (other.centre is None):
            return False
        if self.centre is None:
            return bool(np.abs(self.direction - other.direction).max() <= 1e-9)
        return bool(np.linalg.norm(self.centre - other.centre) <= max(tol, 1e-3 * self.radius)
                    and self.sign == other.sign)

    def end_tolerance(self, tol: float, length: float) -> float:
        """How close two values of ``s`` are to be one row of points (m): ``tol`` on a straight line; on a
        curved one 1e-3 of the line's length, as its centre is fitted to a faceted heel."""
        return tol if self.centre is None else max(tol, 1e-3 * length)

    def strips(self, x, tol: float) -> np.ndarray:
        """Strip index (0, 1, ...) of points ``x`` (n, dim) of one line, in order across it: the points at
        one position across the line (rounded to ``tol``; on a curved line, points at one angle about
        its centre, whose positions, with a fitted centre, agree to within a small part of the gap between
        two strips)."""
        a = self.coordinates(x)[1]
        if self.centre is None:
            _, inv = np.unique(np.round(a / tol).astype(np.int64), return_inverse=True)
            return inv
        order = np.argsort(a, kind="stable")
        gaps = np.diff(a[order])
        new = gaps > max(tol, 1e-2 * (gaps.max() if len(gaps) else 0.0))
        inv = np.empty(len(a), dtype=np.int64)
        inv[order] = np.concatenate([[0], np.cumsum(new)])
        return inv


class _HeelFinder:
    """The frame of a piece of a joint line from the upstream face it meets.

    upstream_face: the face's nodes (m, dim) m and their horizontal outward unit normals (m, dim);
    downstream: the dam's downstream unit vector (dim,), which a straight piece facing that way keeps
    exactly; up: the vertical unit vector; tol: m, how close a piece's node is to be a face node."""

    #: 1 - cos of the largest angle between the heel's normals for the heel to count as straight
    STRAIGHT = 1e-10

    def __init__(self, upstream_face, downstream, up, tol):
        from scipy.spatial import cKDTree

        points, normals = (np.asarray(a, dtype=np.float64) for a in upstream_face)
        keep = np.linalg.norm(normals, axis=1) > 0.5  # nodes where the face is not horizontal
        self.points, self.normals = points[keep], normals[keep]
        self.tree = cKDTree(self.points) if len(self.points) else None
        self.downstream, self.up, self.tol = downstream, up, tol

    def frame(self, X):
        """The :class:`_Frame` of a piece with nodes ``X`` (n, dim), or None where none of them lies on the face."""
        if self.tree is None:
            return None
        dist, at = self.tree.query(X, distance_upper_bound=self.tol)
        at = at[np.isfinite(dist)]
        if len(at) == 0:
            return None
        n, p = self.normals[at], self.points[at]
        mean = n.sum(axis=0)
        if np.linalg.norm(mean) == 0.0:
            return None
        outward = mean / np.linalg.norm(mean)
        if len(at) < 3 or 1.0 - float((n @ outward).min()) <= self.STRAIGHT:
            direction = -outward
            if np.abs(direction - self.downstream).max() <= 1e-9:
                direction = self.downstream  # a face of the dam's own direction: measured exactly as the dam
            return _Frame(direction, self.up)
        # a turning heel: the circle through its nodes in plan (algebraic least squares, Kasa 1976, IEEE
        # Trans. Instrum. Meas. 25:8-14), exact for the nodes of a circular arc
        e1 = np.cross(self.up, outward)
        u, v = p @ e1, p @ outward
        A = np.column_stack([u, v, np.ones(len(u))])
        (cu, cv, k), *_ = np.linalg.lstsq(A, u * u + v * v, rcond=None)
        cu, cv = 0.5 * cu, 0.5 * cv
        radius = float(np.sqrt(max(k + cu * cu + cv * cv, 0.0)))
        centre = cu * e1 + cv * outward
        sign = 1.0 if float((centre - p.mean(axis=0)) @ outward) < 0.0 else -1.0
        # downstream along the radius through the middle of the heel's arc
        ref = sign * outward  # from the centre towards the heel, roughly
        side = np.cross(self.up, ref)
        rel = p - centre
        angle = np.arctan2(rel @ side, rel @ ref)
        mid = 0.5 * (angle.min() + angle.max())
        to_heel = np.cos(mid) * ref + np.sin(mid) * side
        return _Frame(-sign * to_heel, self.up, centre=centre, sign=sign, radius=radius)
