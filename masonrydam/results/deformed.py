"""The deformed shape and crack pattern of one step (``masonrydam plot OUT.nc --deformed``).

:func:`deformed_data` turns a result dataset (its ``block_cell_nodes``, ``joint_point_nodes`` and
``joint_point_shape`` connectivity, written by :class:`masonrydam.results.writer.ResultWriter`) and a step into
what is drawn, in m: a :class:`DeformedShape` (2D: the blocks as polygons at ``x + scale * u``, each joint
point as a polyline on the deformed mid-surface with its state 0-3 and opening) or a :class:`DeformedSlice`
(3D: the cells and joint points cut by the plane ``--slice AXIS=VALUE``, in its two axes).
:func:`deformed_figure` draws it with matplotlib's object API on the Agg canvas.

What is drawn and how a 3D result is sliced: docs/plots.md.
"""
from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from ..elements.shapes import ELEMENT_TYPES
from ..errors import MasonrydamError
from .files import step_position
from .mode_plot import auto_scale, node_coordinates

#: the automatic scale makes the largest drawn nodal displacement this fraction of the model's largest extent
AUTO_FRACTION = 0.05
#: joint states as in ``joint_state`` (flag_values 0, 1, 2, 3; 3 only with composite joints) and how they are drawn: colour, line width (pt)
STATE_NAMES = ("stick", "slip", "open", "crush")
STATE_COLOURS = ("0.6", "tab:orange", "tab:red", "tab:purple")
STATE_WIDTHS = (0.6, 1.6, 1.6, 1.6)
#: extra line width (pt) of the most open joint point of the step (proportional to the opening)
OPENING_WIDTH = 3.0


@dataclass
class DeformedShape:
    """What :func:`deformed_figure` draws for one step of a 2D result.

    step: position along ``step``; scale: displacement magnification (1); coords, deformed (n_node, 2):
    undeformed and drawn (``coords + scale * u``) node positions, m; cells (n_cell, n_corner): positions
    along ``node`` of the corner nodes of the drawn blocks (-1 padding); cell_group (n_cell,): their
    ``block_cell_group``; joint_point (n_seg,): the joint points drawn (positions along ``joint_point``);
    joint_segments (n_seg, 3, 2): their polylines on the deformed shape, m; joint_state (n_seg,): 0 stick,
    1 slip, 2 open, 3 crush; joint_opening (n_seg,): m; counts: drawn points per state name.
    """

    step: int
    scale: float
    coords: np.ndarray
    deformed: np.ndarray
    cells: np.ndarray
    cell_group: np.ndarray
    joint_point: np.ndarray
    joint_segments: np.ndarray
    joint_state: np.ndarray
    joint_opening: np.ndarray
    counts: dict

    def cell_polygons(self, deformed: bool = True) -> list:
        """The block outlines, one (n_corner, 2) array (m) per cell, deformed or undeformed."""
        xy = self.deformed if deformed else self.coords
        return [xy[c[c >= 0]] for c in self.cells]


@dataclass
class DeformedSlice:
    """What :func:`deformed_figure` draws for one step of a 3D result: the slice of the model by the plane
    ``axis = value``, drawn in the plane's axes ``plane_axes`` (the two other components, in the order of
    ``component``).

    step, scale: as :class:`DeformedShape`; axis: ``"x"``, ``"y"`` or ``"z"``; value: m; plane_axes: the names
    of the drawn axes; coords, deformed (n_node, 3): undeformed and ``coords + scale * u`` node positions, m;
    cell (n_poly,): the cut cells (positions along ``block_cell``); cell_group (n_poly,): their
    ``block_cell_group``; polygon_nodes: per cut cell a (k, 2) array of the positions along ``node`` of the
    two end nodes of the edge each polygon point lies on (the same node twice for a corner on the plane);
    polygon_t: per cut cell a (k,) array of where on that edge (0 at the first node, 1 at the second): the
    point is ``(1 - t) p[a] + t p[b]`` with p the undeformed or deformed positions; the points are ordered
    around their undeformed centroid (counter-clockwise in the plane's axes). joint_point (n_seg,): the joint
    points drawn (positions along ``joint_point``, ascending); joint_segments (n_seg, 2, 2): their segments in
    the plane's axes, m; joint_distance (n_seg,): signed distance (m) of the centre of each point's tributary
    patch from the plane; joint_state, joint_opening, counts: as :class:`DeformedShape`.
    """

    step: int
    scale: float
    axis: str
    value: float
    plane_axes: tuple
    coords: np.ndarray
    deformed: np.ndarray
    cell: np.ndarray
    cell_group: np.ndarray
    polygon_nodes: list
    polygon_t: list
    joint_point: np.ndarray
    joint_segments: np.ndarray
    joint_distance: np.ndarray
    joint_state: np.ndarray
    joint_opening: np.ndarray
    counts: dict

    def cell_polygons(self, deformed: bool = True) -> list:
        """The cut cells' outlines, one (k, 2) array (m, in the plane's axes) per cut cell, deformed or
        undeformed."""
        xyz = self.deformed if deformed else self.coords
        cols = [COMPONENTS.index(c) for c in self.plane_axes]
        out = []
        for ab, t in zip(self.polygon_nodes, self.polygon_t):
            p = (1.0 - t)[:, None] * xyz[ab[:, 0]] + t[:, None] * xyz[ab[:, 1]]
            out.append(p[:, cols])
        return out


#: the components of a 3D result, in order
COMPONENTS = ("x", "y", "z")


def select_step(ds, step: int | None, option: str = "--step") -> int:
    """Position along ``step`` of ``step`` (:func:`masonrydam.results.files.step_position`)."""
    return step_position(ds, step, option)


def _positions(ds, model_nodes: np.ndarray) -> np.ndarray:
    """Positions along ``node`` of model node indices (same shape); -1 for padding and unrecorded nodes."""
    recorded = np.asarray(ds.node.values).astype(np.int64)
    top = int(max(recorded.max(initial=-1), model_nodes.max(initial=-1))) + 1
    lookup = np.full(top + 1, -1, dtype=np.int64)  # (the last entry takes the -1 padding)
    lookup[recorded] = np.arange(len(recorded))
    return lookup[np.where(model_nodes < 0, top, model_nodes)]


def deformed_data(ds, step: int | None = -1, scale: float | None = None,
                  slice=None) -> DeformedShape | DeformedSlice:  # noqa: A002 (the option's name)
    """The deformed shape of ``step`` (a value of the ``step`` coordinate or a negative index from the end;
    None: the last) of a result ``ds``, magnified by ``scale`` (default: the largest nodal displacement
    drawn as :data:`AUTO_FRACTION` of the model's largest extent): a :class:`DeformedShape` for a 2D result,
    a :class:`DeformedSlice` for a 3D one, cut by the plane ``slice``: ``"AXIS=VALUE"`` (e.g. ``"y=0.05"``) or
    ``(axis, value)``; None: the mid-plane across the model's thinnest extent (see the module docstring).
    Errors (:class:`~masonrydam.errors.MasonrydamError`): a file without connectivity, a step not in the
    file, a bad scale, a result that records none of the blocks' nodes; ``slice`` given for a 2D result, a
    bad axis, a value outside the model's range or a plane that cuts no block (naming ``--slice``)."""
    comps = [str(c) for c in ds.component.values]
    if len(comps) == 3:
        return _slice_data(ds, step, scale, slice)
    if slice is not None:
        raise MasonrydamError(f"--slice {_slice_text(slice)}: slices are for 3D results; this result is 2D "
                              f"({', '.join(comps)}): draw it without --slice")
    _check_connectivity(ds)
    coords = node_coordinates(ds)
    k, scale, u = _step_and_scale(ds, step, scale, coords)
    deformed = coords + scale * u

    cells, complete = _drawable_cells(ds)
    points, segments = _joint_segments(ds, coords, deformed)
    state = np.asarray(ds.joint_state.isel(step=k).values).astype(np.int8)[points]
    opening = np.asarray(ds.joint_opening.isel(step=k).values, dtype=float)[points]
    counts = {name: int(np.sum(state == s)) for s, name in enumerate(STATE_NAMES)}
    return DeformedShape(k, scale, coords, deformed, cells[complete],
                         np.asarray(ds.block_cell_group.values)[complete], points, segments, state, opening, counts)


def _joint_segments(ds, coords: np.ndarray, deformed: np.ndarray):
    """Joint points whose face nodes are all recorded (positions along ``joint_point``) and their polylines
    (n, 3, 2) on the deformed mid-surface (see the module docstring)."""
    if not ds.sizes.get("joint_point", 0):
        return np.zeros(0, np.int64), np.zeros((0, 3, 2))
    model_nodes = np.asarray(ds.joint_point_nodes.values).astype(np.int64)  # (jp, side, face node)
    pos = _positions(ds, model_nodes)
    ok = np.all((pos >= 0) | (model_nodes < 0), axis=(1, 2))
    points = np.flatnonzero(ok)
    pos = np.where(pos < 0, 0, pos)[points]  # padding: weight 0
    shape = np.asarray(ds.joint_point_shape.values, dtype=float)[points]
    # the deformed point and the element's two ends (face nodes 0 and 1), on the mid-surface
    mid = 0.5 * np.einsum("pk,pskd->pd", shape, deformed[pos])
    ends = 0.5 * deformed[pos[:, :, :2]].sum(axis=1)  # (p, 2 ends, dim)
    # order the points along each element by their undeformed position between its ends
    x0 = np.stack([ds[f"joint_{c}"].values for c in ds.component.values], axis=1)[points]
    undeformed_ends = coords[pos[:, 0, :2]]
    chord = undeformed_ends[:, 1] - undeformed_ends[:, 0]
    t = np.einsum("pd,pd->p", x0 - undeformed_ends[:, 0], chord) / np.einsum("pd,pd->p", chord, chord)
    elem = np.stack([ds.joint_set.values[points], ds.joint_element.values[points]], axis=1)
    order = np.lexsort((t, elem[:, 1], elem[:, 0]))
    same_next = np.all(elem[order][1:] == elem[order][:-1], axis=1)  # (n-1,) next point in the same element
    m = mid[order]
    start, end = ends[order, 0].copy(), ends[order, 1].copy()
    halfway = 0.5 * (m[1:] + m[:-1])
    start[1:][same_next] = halfway[same_next]
    end[:-1][same_next] = halfway[same_next]
    return points[order], np.stack([start, m, end], axis=1)


def _drawable_cells(ds):
    """``(cells, complete)``: the corner nodes of every block cell as positions along ``node`` (-1 where a node is
    not recorded, or padding) and which cells have all their nodes recorded; MasonrydamError when none has."""
    model_cells = np.asarray(ds.block_cell_nodes.values).astype(np.int64)
    cells = _positions(ds, model_cells)
    complete = np.all((cells >= 0) | (model_cells < 0), axis=1)
    if not complete.any():
        raise MasonrydamError("--deformed: the result records none of the blocks' nodes; record them all "
                              "([output] nodes = \"all\") and run the scene again")
    return cells, complete


def _check_connectivity(ds):
    joint_vars = ("joint_point_nodes", "joint_point_shape")
    if "block_cell_nodes" not in ds.variables or (ds.sizes.get("joint_point", 0)
                                                   and any(v not in ds.variables for v in joint_vars)):
        raise MasonrydamError("--deformed: the result has no block connectivity (block_cell_nodes, "
                              "joint_point_nodes): it was written by an older masonrydam; run the scene again")


def _step_and_scale(ds, step, scale, coords):
    k = select_step(ds, -1 if step is None else step)
    u = np.asarray(ds.displacement.isel(step=k).transpose("node", "component").values, dtype=float)
    if scale is None:
        scale = auto_scale(coords, u, AUTO_FRACTION)
    elif not (np.isfinite(scale) and scale > 0):
        raise MasonrydamError(f"--scale must be a positive finite number, got {scale!r}")
    return k, float(scale), u


def _slice_text(plane) -> str:
    if isinstance(plane, str):
        return plane
    try:
        axis, value = plane
        return f"{axis}={value}"
    except (TypeError, ValueError):
        return repr(plane)


def _ranges_text(lo, hi) -> str:
    return ", ".join(f"{c} {a:.6g} to {b:.6g} m" for c, a, b in zip(COMPONENTS, lo, hi))


def slice_plane(plane, coords: np.ndarray) -> tuple:
    """``(axis index, value)`` of ``plane`` (``"AXIS=VALUE"``, ``(axis, value)`` or None: the mid-plane across the
    smallest extent of ``coords`` (n, 3), the first such axis on a tie), checked against the range of
    ``coords`` along the axis (MasonrydamError naming ``--slice`` and the ranges)."""
    lo, hi = coords.min(axis=0), coords.max(axis=0)
    if plane is None:
        a = int(np.argmin(hi - lo))
        return a, float(0.5 * (lo[a] + hi[a]))
    ranges = _ranges_text(lo, hi)
    text = _slice_text(plane)
    if isinstance(plane, str):
        axis, sep, value = plane.partition("=")
        if not sep:
            raise MasonrydamError(f"--slice {text}: give AXIS=VALUE, e.g. --slice y=0.05 (the model spans "
                                  f"{ranges})")
    else:
        try:
            axis, value = plane
        except (TypeError, ValueError):
            raise MasonrydamError(f"--slice {text}: give AXIS=VALUE (the model spans {ranges})") from None
    axis = str(axis).strip().lower()
    if axis not in COMPONENTS:
        raise MasonrydamError(f"--slice {text}: the axis must be x, y or z (the model spans {ranges})")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise MasonrydamError(f"--slice {text}: the value must be a number in m (the model spans {ranges})") from None
    a = COMPONENTS.index(axis)
    tol = 1e-9 * max(float(np.max(hi - lo)), 1e-300)
    if not (np.isfinite(v) and lo[a] - tol <= v <= hi[a] + tol):
        raise MasonrydamError(f"--slice {text}: outside the model's range along {axis} ({lo[a]:.6g} to "
                              f"{hi[a]:.6g} m)")
    return a, v


def _slice_data(ds, step, scale, plane) -> DeformedSlice:
    _check_connectivity(ds)
    coords = node_coordinates(ds)
    a, value = slice_plane(plane, coords)
    axis = COMPONENTS[a]
    k, scale, u = _step_and_scale(ds, step, scale, coords)
    deformed = coords + scale * u
    cols = [c for c in range(3) if c != a]
    tol = 1e-9 * max(float(np.max(coords.max(axis=0) - coords.min(axis=0))), 1e-300)

    cells, complete = _drawable_cells(ds)
    groups = np.asarray(ds.block_cell_group.values).astype(np.int64)
    types = json.loads(ds.block_cell_group.attrs.get("group_types", "[]"))
    cut_cells, polygon_nodes, polygon_t, edge_lengths = [], [], [], []
    for g, name in enumerate(types):
        et = ELEMENT_TYPES.get(name)
        sel = np.flatnonzero(complete & (groups == g))
        if et is None or et.dim != 3 or not len(sel):
            continue
        conn = cells[sel, :et.corner_nodes]  # (n, corners) positions along node
        edges = np.array([e[:2] for e in et.edges], dtype=np.int64)  # (E, 2) local corners
        dist = coords[conn, a] - value  # (n, corners)
        on = np.abs(dist) <= tol
        da, db = dist[:, edges[:, 0]], dist[:, edges[:, 1]]  # (n, E)
        cross = ((da < -tol) & (db > tol)) | ((da > tol) & (db < -tol))
        edge_lengths.append(np.linalg.norm(coords[conn[:, edges[:, 1]]] - coords[conn[:, edges[:, 0]]], axis=2).ravel())
        for i in np.flatnonzero(cross.sum(axis=1) + on.sum(axis=1) >= 3):
            e = np.flatnonzero(cross[i])
            ends = conn[i][edges[e]]  # (m, 2)
            t = da[i, e] / (da[i, e] - db[i, e])
            corner = conn[i][on[i]]
            ab = np.concatenate([ends, np.stack([corner, corner], axis=1)]).astype(np.int64)
            tt = np.concatenate([t, np.zeros(len(corner))])
            p = ((1.0 - tt)[:, None] * coords[ab[:, 0]] + tt[:, None] * coords[ab[:, 1]])[:, cols]
            c = p.mean(axis=0)
            order = np.argsort(np.arctan2(p[:, 1] - c[1], p[:, 0] - c[0]), kind="stable")
            pp = p[order]
            area = 0.5 * np.sum(pp[:, 0] * np.roll(pp[:, 1], -1) - np.roll(pp[:, 0], -1) * pp[:, 1])
            if not area > tol * tol:  # the plane touches the cell at an edge
                continue
            cut_cells.append(sel[i])
            polygon_nodes.append(ab[order])
            polygon_t.append(tt[order])
    lo, hi = coords.min(axis=0), coords.max(axis=0)
    if not cut_cells:
        raise MasonrydamError(f"--slice {axis}={value:g}: the plane cuts none of the blocks (the model spans "
                              f"{lo[a]:.6g} to {hi[a]:.6g} m along {axis}; {_ranges_text(lo, hi)})")
    order = np.argsort(cut_cells, kind="stable")
    cut = np.asarray(cut_cells, dtype=np.int64)[order]
    cell_size = float(np.median(np.concatenate(edge_lengths))) if edge_lengths else 1.0
    points, segments, distance = _slice_joints(ds, coords, u, scale, a, value, cols, cell_size, tol)
    state = np.asarray(ds.joint_state.isel(step=k).values).astype(np.int8)[points] if len(points) else \
        np.zeros(0, np.int8)
    opening = np.asarray(ds.joint_opening.isel(step=k).values, dtype=float)[points] if len(points) else \
        np.zeros(0)
    counts = {name: int(np.sum(state == s)) for s, name in enumerate(STATE_NAMES)}
    return DeformedSlice(k, scale, axis, value, tuple(COMPONENTS[c] for c in cols), coords, deformed, cut,
                         groups[cut], [polygon_nodes[i] for i in order], [polygon_t[i] for i in order], points,
                         segments, distance, state, opening, counts)


def _slice_joints(ds, coords, u, scale, a, value, cols, cell_size, tol):
    """The joint points drawn in the slice ``coords[:, a] = value`` (positions along ``joint_point``), their
    segments (n, 2, 2) in the plane's axes ``cols`` and the signed distances of their patch centres (see the
    module docstring; ``cell_size`` is the patch side where ``joint_weight`` is missing or nil)."""
    empty = np.zeros(0, np.int64), np.zeros((0, 2, 2)), np.zeros(0)
    if not ds.sizes.get("joint_point", 0):
        return empty
    model_nodes = np.asarray(ds.joint_point_nodes.values).astype(np.int64)  # (jp, side, face node)
    pos = _positions(ds, model_nodes)
    valid = model_nodes >= 0
    ok = np.all((pos >= 0) | ~valid, axis=(1, 2))
    pos = np.where(pos < 0, 0, pos)
    shape = np.asarray(ds.joint_point_shape.values, dtype=float)
    x0 = np.stack([np.asarray(ds[f"joint_{c}"].values, dtype=float) for c in COMPONENTS], axis=1)
    normal = np.stack([np.asarray(ds[f"joint_normal_{c}"].values, dtype=float) for c in COMPONENTS], axis=1)
    weight = np.asarray(ds.joint_weight.values, dtype=float) if "joint_weight" in ds.variables \
        else np.zeros(len(x0))
    side = np.where(weight > 0, np.sqrt(np.where(weight > 0, weight, 0.0)), cell_size)
    # the patch centre: the point, or half way to its face's centroid for a point on a face node
    n_face = np.maximum(valid[:, 0].sum(axis=1), 1)
    centroid = (coords[pos[:, 0]] * valid[:, 0, :, None]).sum(axis=1) / n_face[:, None]
    nodal = shape.max(axis=1, initial=0.0) > 1.0 - 1e-6
    centre = np.where(nodal[:, None], 0.5 * (x0 + centroid), x0)
    distance = centre[:, a] - value
    plane_normal = np.zeros(3)
    plane_normal[a] = 1.0
    trace = np.cross(normal, plane_normal)
    length = np.linalg.norm(trace, axis=1)  # sine of the angle between the joint and the plane
    # the trace meets the patch where the centre, moved within the joint plane to the slice, stays in the
    # patch: the move is |distance| / sine (the distance itself for a joint across the plane)
    near = ok & (np.abs(distance) <= 0.5 * side * length * (1.0 + 1e-9) + tol) & (length > 1e-6)
    points = np.flatnonzero(near)
    if not len(points):
        return empty
    p = points
    towards = plane_normal - (normal[p] @ plane_normal)[:, None] * normal[p]  # in the joint plane, |.| = sine
    on_trace = centre[p] - (distance[p] / length[p] ** 2)[:, None] * towards
    jump_mean = 0.5 * np.einsum("pk,pskd->pd", shape[p], u[pos[p]])  # mean of the bottom and top faces
    mid = (on_trace + scale * jump_mean)[:, cols]
    direction = (trace[p] / length[p, None])[:, cols]
    half = 0.5 * side[p, None] * direction
    return points, np.stack([mid - half, mid + half], axis=1), distance[p]


def deformed_figure(ds, step: int | None = -1, scale: float | None = None, title: str | None = None,
                    slice=None):  # noqa: A002 (the option's name)
    """The figure of ``masonrydam plot OUT.nc --deformed`` (a matplotlib Figure, not drawn to screen): the
    data of :func:`deformed_data` in an x-y axes (3D: the slice ``slice`` in its plane's axes, e.g. x-z for a
    y-slice) with equal scales: the undeformed blocks faint (``gid="undeformed"``), the deformed blocks
    (``gid="deformed"``), and the joint points of each state on them (``gid="joints_stick"``,
    ``"joints_slip"``, ``"joints_open"``, ``"joints_crush"``: stick thin grey, slip orange, open red, crushed
    (on a composite joint's compression cap) purple; the line width grows with the opening, by up to
    :data:`OPENING_WIDTH` pt for the most open point). The legend gives the number of points in each state,
    the title the slice (3D), the step, its stage and load factor and the scale. ``title``: an optional first
    line of the title (the file name on the command line)."""
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.figure import Figure

    d = deformed_data(ds, step, scale, slice)
    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.add_collection(PolyCollection(d.cell_polygons(False), facecolors="none", edgecolors="0.85", linewidths=0.4,
                                     gid="undeformed", label="undeformed", zorder=1))
    ax.add_collection(PolyCollection(d.cell_polygons(True), facecolors="0.93", edgecolors="0.35", linewidths=0.3,
                                     gid="deformed", label=f"deformed (displacements x {d.scale:.3g})", zorder=2))
    widest = max(float(d.joint_opening.max(initial=0.0)), 0.0)
    for s, name in enumerate(STATE_NAMES):
        sel = d.joint_state == s
        widths = STATE_WIDTHS[s] + OPENING_WIDTH * np.clip(d.joint_opening[sel], 0.0, None) / (widest or 1.0)
        ax.add_collection(LineCollection(list(d.joint_segments[sel]), colors=STATE_COLOURS[s],
                                         linewidths=widths if sel.any() else STATE_WIDTHS[s], gid=f"joints_{name}",
                                         label=f"{name}: {d.counts[name]} joint points", zorder=3 + s, capstyle="butt"))
    ax.margins(0.03)
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    comps = list(d.plane_axes) if isinstance(d, DeformedSlice) else [str(c) for c in ds.component.values]
    ax.set_xlabel(f"{comps[0]} [m]")
    ax.set_ylabel(f"{comps[1]} [m]")
    ax.legend(fontsize=7, loc="best")
    ax.set_title(deformed_title(ds, d, title), fontsize=9)
    return fig


def deformed_title(ds, d: DeformedShape | DeformedSlice, title: str | None = None) -> str:
    """``title`` (if any) on its own line, then the slice (3D: ``slice y = 0.05 m; ``), the step, its stage and
    load factor and the scale."""
    stage = int(ds.stage.values[d.step])
    names = json.loads(ds.stage.attrs.get("stage_names", "[]"))
    name = f" '{names[stage]}'" if 0 <= stage < len(names) else ""
    where = f"slice {d.axis} = {d.value:.6g} m; " if isinstance(d, DeformedSlice) else ""
    line = (f"{where}step {int(ds.step.values[d.step])}: stage {stage}{name}, load factor "
            f"{float(ds.load_factor.values[d.step]):.3g}; displacements x {d.scale:.3g}")
    return f"{title}\n{line}" if title else line
