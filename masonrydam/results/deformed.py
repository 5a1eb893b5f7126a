"""The deformed shape and crack pattern of one step (``masonrydam plot OUT.nc --deformed``).

A result file holds the connectivity needed to draw it (:class:`masonrydam.results.writer.ResultWriter`):
``block_cell_nodes`` (block_cell, block_cell_node), the corner nodes of each continuum element as model
node indices (the values of the ``node`` coordinate, -1 padding), and for each joint integration point
the faces of its interface element, ``joint_point_nodes`` (joint_point, joint_side, joint_face_node),
with the face shape functions at the point, ``joint_point_shape`` (joint_point, joint_face_node).

:func:`deformed_data` computes what is drawn (2D results; m unless stated):

- the recorded nodes at ``x + scale * u`` (``u`` the displacement at the step), and the blocks as the
  polygons of their corner nodes (elements with a corner node that is not recorded are left out);
- each joint point as a polyline of three points on the deformed mid-surface of its interface element
  (the mean of the deformed bottom and top faces): from half way to the previous point of the element (or
  the element's first end) through the point to half way to the next one (or the element's other end),
  so that the points of a joint line tile it. Its state (0 stick, 1 slip, 2 open, 3 crush) and opening are those
  of ``joint_state`` and ``joint_opening`` at the step.

The gap of an open joint appears in the blocks themselves (the faces of a joint are distinct nodes,
drawn with the same exaggeration). :func:`deformed_figure` draws the data with matplotlib's object API
on the Agg canvas (the global backend is left alone).
"""
from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from ..errors import MasonrydamError

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


def select_step(ds, step: int | None, option: str = "--step") -> int:
    """Position along ``step`` of ``step`` (:func:`masonrydam.results.files.step_position`)."""
    from .files import step_position

    return step_position(ds, step, option)


def _positions(ds, model_nodes: np.ndarray) -> np.ndarray:
    """Positions along ``node`` of model node indices (same shape); -1 for padding and unrecorded nodes."""
    recorded = np.asarray(ds.node.values).astype(np.int64)
    top = int(max(recorded.max(initial=-1), model_nodes.max(initial=-1))) + 1
    lookup = np.full(top + 1, -1, dtype=np.int64)  # (the last entry takes the -1 padding)
    lookup[recorded] = np.arange(len(recorded))
    return lookup[np.where(model_nodes < 0, top, model_nodes)]


def deformed_data(ds, step: int | None = -1, scale: float | None = None) -> DeformedShape:
    """The deformed shape of ``step`` (a value of the ``step`` coordinate or a negative index from the end;
    None: the last) of a 2D result ``ds``, magnified by ``scale`` (default: the largest nodal displacement
    drawn as :data:`AUTO_FRACTION` of the model's largest extent). Errors
    (:class:`~masonrydam.errors.MasonrydamError`): a 3D result, a file without connectivity, a step not in
    the file, a bad scale, a result that records none of the blocks' nodes."""
    from .mode_plot import auto_scale, node_coordinates

    comps = [str(c) for c in ds.component.values]
    if len(comps) != 2:
        raise MasonrydamError("--deformed: 3D results are not drawn yet (the deformed shape is drawn for 2D "
                              "results); open the result in ParaView or plot its histories")
    if "block_cell_nodes" not in ds.variables or (ds.sizes.get("joint_point", 0)
                                                   and "joint_point_nodes" not in ds.variables):
        raise MasonrydamError("--deformed: the result has no block connectivity (block_cell_nodes, "
                              "joint_point_nodes): it was written by an older masonrydam; run the scene again")
    k = select_step(ds, -1 if step is None else step)
    coords = node_coordinates(ds)
    u = np.asarray(ds.displacement.isel(step=k).transpose("node", "component").values, dtype=float)
    if scale is None:
        scale = auto_scale(coords, u, AUTO_FRACTION)
    elif not (np.isfinite(scale) and scale > 0):
        raise MasonrydamError(f"--scale must be a positive finite number, got {scale!r}")
    scale = float(scale)
    deformed = coords + scale * u

    model_cells = np.asarray(ds.block_cell_nodes.values).astype(np.int64)
    cells = _positions(ds, model_cells)
    complete = np.all((cells >= 0) | (model_cells < 0), axis=1)
    if not complete.any():
        raise MasonrydamError("--deformed: the result records none of the blocks' nodes; record them all "
                              "([output] nodes = \"all\") and run the scene again")
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


def deformed_figure(ds, step: int | None = -1, scale: float | None = None, title: str | None = None):
    """The figure of ``masonrydam plot OUT.nc --deformed`` (a matplotlib Figure, not drawn to screen): the
    data of :func:`deformed_data` in an x-y axes with equal scales: the undeformed blocks faint
    (``gid="undeformed"``), the deformed blocks (``gid="deformed"``), and the joint points of each state
    on them (``gid="joints_stick"``, ``"joints_slip"``, ``"joints_open"``, ``"joints_crush"``: stick thin grey, slip
    orange, open red, crushed (on a composite joint's compression cap) purple; the line width grows with the opening, by up to :data:`OPENING_WIDTH` pt for the most open
    point). The legend gives the number of points in each state, the title the step, its stage and load
    factor and the scale. ``title``: an optional first line of the title (the file name on the command
    line)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.figure import Figure

    d = deformed_data(ds, step, scale)
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
    comps = [str(c) for c in ds.component.values]
    ax.set_xlabel(f"{comps[0]} [m]")
    ax.set_ylabel(f"{comps[1]} [m]")
    ax.legend(fontsize=7, loc="best")
    ax.set_title(deformed_title(ds, d, title), fontsize=9)
    return fig


def deformed_title(ds, d: DeformedShape, title: str | None = None) -> str:
    """``title`` (if any) on its own line, then the step, its stage and load factor and the scale."""
    stage = int(ds.stage.values[d.step])
    names = json.loads(ds.stage.attrs.get("stage_names", "[]"))
    name = f" '{names[stage]}'" if 0 <= stage < len(names) else ""
    line = (f"step {int(ds.step.values[d.step])}: stage {stage}{name}, load factor "
            f"{float(ds.load_factor.values[d.step]):.3g}; displacements x {d.scale:.3g}")
    return f"{title}\n{line}" if title else line
