"""A result file (netCDF) as a ParaView time series (``masonrydam export-results OUT.nc -o OUT.xdmf``).

:func:`export_results` writes a result dataset to ``.xdmf`` (XDMF 3 with the arrays in ``OUT.h5``, meshio's
``TimeSeriesWriter``) or ``.pvd`` (a ParaView collection and one ``OUT_<step>.vtu`` per exported step), with
``OUT.units.json`` beside it (units, long names, components and the names of the integer fields). The geometry
is the undeformed recorded nodes (three coordinates, z = 0 in 2D, m) with block cells (corner nodes) and one
interface cell per interface element (``joints``: ``"deformed"``, ``"shrunk"`` to :data:`SHRINK_FACTOR` or
``"both"``); point data are the nodal vectors (``displacement`` m, ``reaction`` N, velocities and
accelerations), cell data the element stress (Pa) and the means of the joint points' variables. ``every``,
``steps`` and ``time`` select the steps and their time values; :class:`ExportSummary` says what was written and
left out.

Reference (what is written, in which units, and how to open it): docs/paraview.md.
"""
from __future__ import annotations

import json
import os
import time as _time
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import h5py
import meshio
import numpy as np
from meshio.xdmf import TimeSeriesWriter

from ..elements.shapes import ELEMENT_TYPES
from ..errors import MasonrydamError, OutputError

#: output suffixes and their formats
FORMATS = {".xdmf": "XDMF 3 + HDF5 (meshio TimeSeriesWriter)", ".pvd": "ParaView collection + one .vtu per step"}
#: ``--joints`` choices
JOINT_VIEWS = ("deformed", "shrunk", "both")
#: time value choices
TIME_CHOICES = ("auto", "step")
#: distance of a shrunk interface cell's nodes from its centroid, as a fraction of the true distance
SHRINK_FACTOR = 0.8
#: values of the cell data ``part``
PART_NAMES = {0: "block", 1: "interface", 2: "interface (shrunk)", 3: "node in no cell"}
#: joint states (``joint_state``)
STATE_NAMES = {0: "stick", 1: "slip", 2: "open", 3: "crush"}
#: meshio cell type of a continuum element family (ELEMENT_TYPES[...].family)
_FAMILY_CELL = {"quad": "quad", "tri": "triangle", "hex": "hexahedron", "tet": "tetra"}
#: joint variables on (step, joint_point, shear_direction) whose per-point magnitude is also written
_MAGNITUDES = ("joint_slip", "joint_plastic_slip", "joint_traction_shear")


@dataclass
class ExportSummary:
    """What :func:`export_results` wrote.

    path: the output (.xdmf or .pvd); files: every file written (the output, its .h5 or .vtu files, the
    units sidecar); steps: the step numbers exported; times: their time values; time_unit: ``"s"`` or
    ``"1"`` (step numbers); n_points, n_block_cells, n_joint_cells: the mesh written (interface cells of
    both views counted); left_out: counts of what was left out (``block_cells``, ``joint_elements``
    with unrecorded nodes, ``static_steps`` of a dynamic result, and for an XDMF output
    ``nodes_without_cell``, see :func:`xdmf_cells`); seconds: wall time of the export."""

    path: Path
    files: list
    steps: np.ndarray
    times: np.ndarray
    time_unit: str
    n_points: int
    n_block_cells: int
    n_joint_cells: int
    left_out: dict = field(default_factory=dict)
    seconds: float = 0.0


def units_path(output) -> Path:
    """The units sidecar of an output: ``OUT.units.json`` for ``OUT.xdmf`` or ``OUT.pvd``."""
    p = Path(output)
    return p.with_name(f"{p.stem}.units.json")


def check_options(output, joints: str = "deformed", every: int = 1, steps=None, time: str = "auto") -> str:
    """Check the export options before any work; returns the output suffix (``.xdmf`` or ``.pvd``).
    :class:`~masonrydam.errors.MasonrydamError` naming the option (``-o``, ``--joints``, ``--every``,
    ``--steps``, ``--time``)."""
    suffix = Path(output).suffix.lower()
    if suffix not in FORMATS:
        raise MasonrydamError(f"-o {str(output)!r}: the suffix must be one of {', '.join(FORMATS)} "
                              f"(got {Path(output).suffix or 'none'!r})")
    if joints not in JOINT_VIEWS:
        raise MasonrydamError(f"--joints must be one of {', '.join(JOINT_VIEWS)}, got {joints!r}")
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise MasonrydamError(f"--every must be a whole number of 1 or more (keep every K-th step), got {every!r}")
    if time not in TIME_CHOICES:
        raise MasonrydamError(f"--time must be one of {', '.join(TIME_CHOICES)}, got {time!r}")
    parse_steps(steps)
    return suffix


def parse_steps(text) -> slice:
    """``--steps A:B`` as a slice over the step numbers (A included, B excluded, either may be empty,
    negative from the end); None or "" selects every step; a slice passes through."""
    if text is None or text == "":
        return slice(None)
    if isinstance(text, slice):
        return text
    parts = str(text).split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        a, b = (int(p) if p.strip() else None for p in parts)
    except ValueError:
        raise MasonrydamError(f"--steps must be A:B (step numbers, A included, B excluded, either may be empty "
                              f"or negative from the end), got {text!r}") from None
    return slice(a, b)


def select_steps(ds, every: int = 1, steps=None, time: str = "auto"):
    """Positions along ``step`` to export, their time values and the time unit, and the number of static
    steps left out (see the module docstring)."""
    n = int(ds.sizes.get("step", 0))
    if n == 0:
        raise MasonrydamError(f"the result has no steps (status '{ds.attrs.get('status', '?')}': the run stopped "
                              "before its first converged step)")
    pos = np.arange(n)[parse_steps(steps)]
    if not len(pos):
        raise MasonrydamError(f"--steps {steps}: selects none of the result's {n} steps (0 to {n - 1})")
    t = np.asarray(ds["time"].values, dtype=float) if "time" in ds.variables else np.full(n, np.nan)
    dynamic = bool(np.isfinite(t).any())
    static_left = 0
    if dynamic and time == "auto":
        keep = np.isfinite(t[pos])
        static_left = int(np.sum(~keep))
        pos = pos[keep]
        if not len(pos):
            raise MasonrydamError(f"--steps {steps}: selects only static steps of a dynamic result; give "
                                  "--time step to export them (with the step number as time)")
        values, unit = t[pos], "s"
    else:
        values, unit = np.asarray(ds["step"].values, dtype=float)[pos], "1"
    sel = np.arange(0, len(pos), every)
    if sel[-1] != len(pos) - 1:  # the last selected step is kept
        sel = np.append(sel, len(pos) - 1)
    return pos[sel], values[sel], unit, static_left


def _positions(node_ids: np.ndarray, model_nodes: np.ndarray) -> np.ndarray:
    """Positions along ``node`` (recorded ids ``node_ids``) of model node indices; -1 for padding and
    unrecorded nodes."""
    model_nodes = np.asarray(model_nodes, dtype=np.int64)
    top = int(max(node_ids.max(initial=-1), model_nodes.max(initial=-1))) + 1
    lookup = np.full(top + 1, -1, dtype=np.int64)  # the last entry takes the -1 padding
    lookup[node_ids] = np.arange(len(node_ids))
    return lookup[np.where(model_nodes < 0, top, model_nodes)]


@dataclass
class _Geometry:
    """The static part of an export: points, cells and the maps from the result's arrays to them."""

    points: np.ndarray  # (n_points, 3)
    point_source: np.ndarray  # (n_points,) position along node of the node each point shows
    cells: list  # [(meshio type, (n, k) int array)]
    part: np.ndarray  # per cell, concatenated in the order of ``cells``
    block_index: np.ndarray  # block_cell position of the block cells, in output order
    n_joint_cells: int
    joint_order: np.ndarray  # joint points sorted by (set, element), those of exported elements
    joint_starts: np.ndarray  # start of each exported element in joint_order
    joint_view_count: int  # 1 or 2: interface cells written once or twice (both)
    static_cell_data: dict
    left_out: dict


def _block_cells(ds, node_ids, dim):
    """(meshio type, block_cell positions, point positions (n, k)) per cell type, and the number left out."""
    if "block_cell_nodes" not in ds.variables or not ds.sizes.get("block_cell", 0):
        return [], 0
    model = np.asarray(ds.block_cell_nodes.values).astype(np.int64)
    pos = _positions(node_ids, model)
    group = np.asarray(ds.block_cell_group.values).astype(np.int64)
    types = json.loads(ds.block_cell_group.attrs.get("group_types", "[]"))
    n_corner = np.sum(model >= 0, axis=1)
    kinds = np.empty(len(model), dtype=object)
    for i in range(len(model)):
        g = int(group[i])
        et = ELEMENT_TYPES.get(types[g]) if 0 <= g < len(types) else None
        if et is not None:
            kinds[i] = _FAMILY_CELL[et.family]
        else:  # by the number of corners
            kinds[i] = {3: "triangle", 4: "quad" if dim == 2 else "tetra", 8: "hexahedron"}.get(int(n_corner[i]))
    complete = np.all((pos >= 0) | (model < 0), axis=1) & (kinds != None)  # noqa: E711
    out = []
    for kind in dict.fromkeys(kinds[complete]):
        idx = np.flatnonzero(complete & (kinds == kind))
        k = {"triangle": 3, "quad": 4, "tetra": 4, "hexahedron": 8}[kind]
        out.append((kind, idx, pos[idx, :k]))
    return out, int(np.sum(~complete))


def _joint_cells(ds, node_ids, dim):
    """The interface elements: joint point order (sorted by set, element), element starts, per element
    its meshio type and the bottom and top corner positions (n_el, 2, k), its set and element index;
    and the number of elements left out (unrecorded face nodes)."""
    njp = int(ds.sizes.get("joint_point", 0))
    if not njp or "joint_point_nodes" not in ds.variables:
        return None, 0
    jset = np.asarray(ds.joint_set.values).astype(np.int64)
    jel = np.asarray(ds.joint_element.values).astype(np.int64)
    order = np.lexsort((np.arange(njp), jel, jset))
    key_sorted = np.stack([jset[order], jel[order]], axis=1)
    new = np.ones(njp, dtype=bool)
    new[1:] = np.any(key_sorted[1:] != key_sorted[:-1], axis=1)
    starts = np.flatnonzero(new)
    first = order[starts]  # one joint point of each element
    model = np.asarray(ds.joint_point_nodes.values).astype(np.int64)[first]  # (n_el, 2, n_face)
    pos = _positions(node_ids, model)
    n_face = np.sum(model[:, 0] >= 0, axis=1)
    if dim == 2:
        n_corner = np.full(len(first), 2)
    else:
        n_corner = np.where((n_face == 3) | (n_face == 6), 3, 4)
    corner_ok = np.arange(model.shape[2])[None, :] < n_corner[:, None]
    ok = np.all((pos >= 0) | (model < 0), axis=(1, 2)) & (n_face >= n_corner) & np.all(
        ~corner_ok[:, None, :] | (model >= 0), axis=(1, 2))
    elements = []
    for nc in (2, 3, 4):
        sel = np.flatnonzero(ok & (n_corner == nc))
        if not len(sel):
            continue
        b, t = pos[sel, 0, :nc], pos[sel, 1, :nc]
        if nc == 2:  # face order: bottom from end 0 to end 1, normal (+90 deg) toward the top
            kind, conn = "quad", np.stack([b[:, 0], b[:, 1], t[:, 1], t[:, 0]], axis=1)
        else:  # the bottom face's right-hand normal points to the top face: a positive Jacobian in VTK's
            # hexahedron and wedge (checked with VTK 9.7's InterpolateDerivs for an open joint)
            kind = "hexahedron" if nc == 4 else "wedge"
            conn = np.concatenate([b, t], axis=1)
        elements.append((kind, sel, conn))
    info = {"order": order, "starts": starts, "set": jset[first], "element": jel[first], "elements": elements}
    return info, int(np.sum(~ok))


def build_geometry(ds, joints: str = "deformed") -> _Geometry:
    """Points and cells of the export of ``ds`` (see the module docstring)."""
    comps = [str(c) for c in ds.component.values]
    dim = len(comps)
    node_ids = np.asarray(ds.node.values).astype(np.int64)
    xyz = np.zeros((len(node_ids), 3))
    for k, c in enumerate(comps):
        xyz[:, k] = np.asarray(ds[c].values, dtype=float)
    points, source = [xyz], [np.arange(len(node_ids))]
    n_points = len(node_ids)
    cells, part, group, element, j_set, j_el = [], [], [], [], [], []
    blocks, blocks_left = _block_cells(ds, node_ids, dim)
    block_group = np.asarray(ds.block_cell_group.values).astype(np.int64) if blocks else None
    block_index = []
    for kind, idx, conn in blocks:
        cells.append((kind, conn))
        block_index.append(idx)
        n = len(idx)
        part.append(np.zeros(n, np.int8))
        group.append(block_group[idx])
        element.append(idx)
        j_set.append(np.full(n, -1))
        j_el.append(np.full(n, -1))
    info, joints_left = _joint_cells(ds, node_ids, dim)
    n_joint_cells, views = 0, 0
    order, starts = np.zeros(0, np.int64), np.zeros(0, np.int64)
    if info is not None and info["elements"]:
        views = {"deformed": (1,), "shrunk": (2,), "both": (1, 2)}[joints]
        kept = np.concatenate([sel for _, sel, _ in info["elements"]])  # element positions, output order
        # the joint points of the exported elements, in output order, and where each element starts
        counts = np.diff(np.append(info["starts"], len(info["order"])))
        order = np.concatenate([info["order"][info["starts"][e]:info["starts"][e] + counts[e]] for e in kept])
        starts = np.concatenate([[0], np.cumsum(counts[kept])[:-1]])
        for view in views:
            for kind, sel, conn in info["elements"]:
                if view == 2:  # own copies of the nodes, toward the centroid
                    corners = xyz[conn]  # (n, k, 3)
                    centre = corners.mean(axis=1, keepdims=True)
                    shrunk = centre + SHRINK_FACTOR * (corners - centre)
                    points.append(shrunk.reshape(-1, 3))
                    source.append(conn.reshape(-1))
                    conn = n_points + np.arange(conn.size).reshape(conn.shape)
                    n_points += conn.size
                cells.append((kind, conn))
                n = len(sel)
                part.append(np.full(n, view, np.int8))
                group.append(np.full(n, -1))
                element.append(np.full(n, -1))
                j_set.append(info["set"][sel])
                j_el.append(info["element"][sel])
                n_joint_cells += n
    # recorded nodes in no cell (a result that records some nodes only): vertex cells, so they show
    used = np.zeros(len(node_ids), dtype=bool)
    all_sources = np.concatenate(source)
    for _, conn in cells:
        used[all_sources[conn.reshape(-1)]] = True
    lone = np.flatnonzero(~used)
    if len(lone):
        cells.append(("vertex", lone[:, None]))
        n = len(lone)
        part.append(np.full(n, 3, np.int8))
        group.append(np.full(n, -1))
        element.append(np.full(n, -1))
        j_set.append(np.full(n, -1))
        j_el.append(np.full(n, -1))
    if not cells:
        raise MasonrydamError("the result has no nodes to export")
    cat = (lambda arrs, dt: np.concatenate(arrs).astype(dt))
    static = {"part": cat(part, np.int8), "group": cat(group, np.int32), "element": cat(element, np.int32),
              "joint_set": cat(j_set, np.int32), "joint_element": cat(j_el, np.int32)}
    return _Geometry(np.vstack(points), np.concatenate(source), [(k, np.ascontiguousarray(c, dtype=np.int64))
                                                                 for k, c in cells],
                     static["part"], np.concatenate(block_index) if block_index else np.zeros(0, np.int64),
                     n_joint_cells, order, starts, max(len(views) if views else 1, 1), static,
                     {"block_cells": blocks_left, "joint_elements": joints_left})


def _field_catalogue(ds):
    """The step variables exported: (point vectors, element variables, joint variables)."""
    point, element, joint = [], [], []
    for name, v in ds.data_vars.items():
        dims = v.dims
        if dims == ("step", "node", "component"):
            point.append(name)
        elif dims[:2] == ("step", "element") and len(dims) <= 3:
            element.append(name)
        elif dims[:2] == ("step", "joint_point") and len(dims) <= 3:
            joint.append(name)
    return point, element, joint


def _split_names(ds, name):
    """Component names of a variable's third dimension (its coordinate values, or 0, 1, ...)."""
    d = ds[name].dims[2]
    if d in ds.coords or d in ds.variables:
        return [str(c) for c in ds[d].values]
    return [str(i) for i in range(ds.sizes[d])]


def _units(ds, dim, time_unit) -> dict:
    """The units sidecar's contents (besides the output and source names)."""
    point, element, joint = _field_catalogue(ds)
    fields = {}
    xyz = ["x", "y", "z"]

    def entry(assoc, name, unit=None, long_name=None, components=None, **extra):
        v = ds[name] if name in ds.variables else None
        e = {"association": assoc, "unit": unit if unit is not None else str(v.attrs.get("units", "1")),
             "long_name": long_name if long_name is not None else str(v.attrs.get("long_name", ""))}
        if components:
            e["components"] = components
        e.update(extra)
        return e

    for name in point:
        fields[name] = entry("point", name, components=xyz,
                             note="three components always (z = 0 in 2D); NaN on static steps for dynamic-only "
                                  "fields" if name != "displacement" else "three components always (z = 0 in 2D)")
    fields["node"] = entry("point", "node", "1", "model node index (the result's node coordinate)")
    fields["part"] = entry("cell", "part", "1", "0 block, 1 interface cell, 2 shrunk interface cell, 3 vertex "
                                                "(a recorded node in no cell)",
                           values={str(k): v for k, v in PART_NAMES.items()})
    fields["group"] = entry("cell", "group", "1", "element group of the block (block_cell_group); -1 on "
                                                  "interface cells",
                            names=json.loads(ds.block_cell_group.attrs.get("group_names", "[]"))
                            if "block_cell_group" in ds.variables else [])
    fields["element"] = entry("cell", "element", "1", "position of the block along block_cell (the element "
                                                      "number of the result's element dimension); -1 on "
                                                      "interface cells")
    fields["joint_set"] = entry("cell", "joint_set", "1", "joint set of the interface element; -1 on blocks",
                                names=json.loads(ds.joint_set.attrs.get("set_names", "[]"))
                                if "joint_set" in ds.variables else [])
    fields["joint_element"] = entry("cell", "joint_element", "1", "interface element index within its joint "
                                                                  "set; -1 on blocks")
    for name in element:
        if ds[name].ndim == 3:
            for c in _split_names(ds, name):
                fields[f"{name}_{c}"] = entry("cell", name, long_name=f"{ds[name].attrs.get('long_name', '')}, "
                                                                      f"component {c}; NaN on interface cells")
            if name == "stress" and dim == 3:
                fields["stress"] = entry("cell", name, components=_split_names(ds, name),
                                         note="symmetric tensor in VTK order (xx, yy, zz, xy, yz, zx); NaN on "
                                              "interface cells")
        else:
            fields[name] = entry("cell", name, note="NaN on interface cells")
    for name in joint:
        v = ds[name]
        if name == "joint_state":
            fields[name] = entry("cell", name, "1", "most severe state of the element's joint points (the "
                                                   "largest): 0 stick, 1 slip, 2 open, 3 crush; -1 on blocks",
                                 values={str(k): s for k, s in STATE_NAMES.items()})
        elif v.ndim == 2:
            fields[name] = entry("cell", name, long_name=f"{v.attrs.get('long_name', '')}: mean over the "
                                                         "element's joint points; NaN on blocks")
        else:
            for c in _split_names(ds, name):
                fields[f"{name}_{c}"] = entry("cell", name, long_name=f"{v.attrs.get('long_name', '')}, "
                                                                      f"direction {c} (joint_shear_axis): mean "
                                                                      "over the element's joint points; NaN on "
                                                                      "blocks")
            if name in _MAGNITUDES:
                fields[f"{name}_magnitude"] = entry("cell", name, long_name=f"magnitude of "
                                                                            f"{v.attrs.get('long_name', '')}: "
                                                                            "mean over the element's joint "
                                                                            "points of the magnitudes; NaN on "
                                                                            "blocks")
    return {"time": {"unit": time_unit,
                     "long_name": "time since the start of the first dynamic stage" if time_unit == "s"
                     else "step number (the result's step coordinate)"},
            "fields": fields,
            "joint_states": {str(k): s for k, s in STATE_NAMES.items()},
            "shrink_factor": SHRINK_FACTOR}


class _StepData:
    """Point and cell data of one step, from arrays loaded once."""

    def __init__(self, ds, geom: _Geometry):
        self.geom = geom
        self.dim = ds.sizes["component"]
        point, element, joint = _field_catalogue(ds)
        self.point = {name: np.asarray(ds[name].transpose("step", "node", "component").values) for name in point}
        n_el = ds.sizes.get("element", 0)
        n_block = ds.sizes.get("block_cell", 0)
        # stress on element is in the order of block_cell; another count cannot be placed on the cells
        self.element = {name: np.asarray(ds[name].values) for name in element if n_el == n_block}
        self.element_names = {name: _split_names(ds, name) for name in self.element if ds[name].ndim == 3}
        self.joint = {name: np.asarray(ds[name].values) for name in joint}
        self.joint_names = {name: _split_names(ds, name) for name in self.joint if ds[name].ndim == 3}
        self.n_cells = len(geom.part)
        self.n_block_out = len(geom.block_index)
        self.node_ids = np.asarray(ds.node.values).astype(np.int64)

    def __call__(self, k: int):
        g = self.geom
        pd = {}
        for name, arr in self.point.items():
            v = np.zeros((len(g.point_source), 3))
            v[:, :self.dim] = arr[k][g.point_source]
            if self.dim == 2:  # NaN (a dynamic field on a static step) stays NaN in z
                v[np.isnan(v[:, 0]), 2] = np.nan
            pd[name] = v
        pd["node"] = self.node_ids[g.point_source]
        cd = {name: a for name, a in g.static_cell_data.items()}
        nb = self.n_block_out
        for name, arr in self.element.items():
            val = np.asarray(arr[k], dtype=float)[g.block_index]
            if val.ndim == 1:
                cd[name] = self._blocks_only(val)
            else:
                for j, c in enumerate(self.element_names[name]):
                    cd[f"{name}_{c}"] = self._blocks_only(val[:, j])
                if name == "stress" and self.dim == 3 and val.shape[1] == 6:
                    full = np.full((self.n_cells, 6), np.nan)
                    full[:nb] = val
                    cd["stress"] = full
        if len(g.joint_order):
            st = g.joint_starts
            counts = np.diff(np.append(st, len(g.joint_order)))
            for name, arr in self.joint.items():
                val = arr[k][g.joint_order]
                if name == "joint_state":
                    cd[name] = self._joints_only(np.maximum.reduceat(val.astype(np.int8), st), np.int8, -1)
                elif val.ndim == 1:
                    cd[name] = self._joints_only(np.add.reduceat(val.astype(float), st) / counts)
                else:
                    mean = np.add.reduceat(val.astype(float), st, axis=0) / counts[:, None]
                    for j, c in enumerate(self.joint_names[name]):
                        cd[f"{name}_{c}"] = self._joints_only(mean[:, j])
                    if name in _MAGNITUDES:
                        mag = np.add.reduceat(np.linalg.norm(val.astype(float), axis=1), st) / counts
                        cd[f"{name}_magnitude"] = self._joints_only(mag)
        else:
            for name, arr in self.joint.items():  # no interface cells: the fields stay, empty of values
                names = [name] if arr.ndim == 2 else [f"{name}_{c}" for c in self.joint_names[name]] + (
                    [f"{name}_magnitude"] if name in _MAGNITUDES else [])
                for n in names:
                    cd[n] = (np.full(self.n_cells, -1, np.int8) if name == "joint_state"
                             else np.full(self.n_cells, np.nan))
        return pd, cd

    def _blocks_only(self, val):
        out = np.full(self.n_cells, np.nan)
        out[:self.n_block_out] = val
        return out

    def _joints_only(self, val, dtype=float, fill=np.nan):
        out = np.full(self.n_cells, fill, dtype=dtype)
        # the interface cells follow the blocks, once per view
        nb, n = self.n_block_out, len(val)
        for v in range(self.geom.joint_view_count):
            out[nb + v * n: nb + (v + 1) * n] = val
        return out


def _split(cells: list, cd: dict) -> dict:
    """Cell data as meshio wants it: per name, one array per cell block of ``cells`` (the first blocks of
    the geometry's)."""
    bounds = np.cumsum([0] + [len(c) for _, c in cells])
    return {name: [a[bounds[i]:bounds[i + 1]] for i in range(len(cells))] for name, a in cd.items()}


def xdmf_cells(geom: _Geometry) -> list:
    """The cell blocks an XDMF output holds: those of the geometry, less the vertex cells when there are
    others. meshio 5.3 writes vertex cells in a Mixed topology without the node count that XDMF wants
    after a Polyvertex's type (as it does for lines), and ParaView's reader does not read it; a topology
    of vertex cells alone is a Polyvertex, which it reads."""
    if len(geom.cells) > 1 and geom.cells[-1][0] == "vertex":
        return geom.cells[:-1]
    return geom.cells


def export_results(ds, output, joints: str = "deformed", every: int = 1, steps=None, time: str = "auto",
                   source: str | None = None) -> ExportSummary:
    """Write the result ``ds`` (an ``xarray.Dataset`` of a result file, :func:`masonrydam.results.files.open_result`)
    to ``output`` (``.xdmf`` or ``.pvd``) as a ParaView time series, with ``OUT.units.json`` beside it (see
    the module docstring). ``joints``: ``"deformed"``, ``"shrunk"`` or ``"both"``; ``every``: keep every
    K-th step (and the last); ``steps``: ``"A:B"`` or a slice over the step numbers; ``time``: ``"auto"``
    or ``"step"``; ``source``: the result's file name, for the sidecar. Errors
    (:class:`~masonrydam.errors.MasonrydamError`) name the option."""
    t0 = _time.perf_counter()
    output = Path(output)
    suffix = check_options(output, joints, every, steps, time)
    positions, times, unit, static_left = select_steps(ds, every, steps, time)
    geom = build_geometry(ds, joints)
    data = _StepData(ds, geom)
    files = []
    if suffix == ".xdmf":
        files += _write_xdmf(output, geom, data, positions, times, source)
        lone = sum(len(c) for _, c in geom.cells) - sum(len(c) for _, c in xdmf_cells(geom))
    else:
        files += _write_pvd(output, geom, data, positions, times, np.asarray(ds["step"].values)[positions])
    side = units_path(output)
    numbers = np.asarray(ds["step"].values)[positions]
    meta = {"output": output.name, "source": source, "steps": [int(s) for s in numbers],
            "times": [float(t) for t in times], **_units(ds, data.dim, unit)}
    side.write_text(json.dumps(meta, indent=1) + "\n")
    files.append(side)
    left = dict(geom.left_out)
    if suffix == ".xdmf" and lone:
        left["nodes_without_cell"] = lone
    left["static_steps"] = static_left
    return ExportSummary(output, files, numbers, times, unit, len(geom.points),
                         len(geom.block_index), geom.n_joint_cells, left, _time.perf_counter() - t0)


def _write_xdmf(output: Path, geom, data, positions, times, source):
    """XDMF + HDF5 through meshio's TimeSeriesWriter. meshio 5.3 opens the HDF5 file as ``stem + ".h5"``
    in the current folder while the XDMF refers to it relative to the XDMF file; the HDF5 file is opened
    here beside the output instead (same name, so the reference holds wherever the output goes)."""
    h5 = output.with_suffix(".h5")
    if source is not None and Path(source).resolve() == h5.resolve():
        raise MasonrydamError(f"-o {str(output)!r}: its HDF5 file {str(h5)!r} would replace the result file; "
                              "give another name")

    class _Writer(TimeSeriesWriter):
        def __enter__(self):
            self.h5_filename = str(h5)
            try:
                self.h5_file = h5py.File(self.h5_filename, "w")
            except OSError as exc:  # open in another program (HDF5's lock), no permission
                first = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
                raise OutputError(f"-o {str(output)!r}: cannot write its HDF5 file {str(h5)!r} ({first}); close "
                                  "it in ParaView or give another name") from None
            return self

    cells = xdmf_cells(geom)
    with _Writer(output) as w:
        w.write_points_cells(geom.points, [(k, c) for k, c in cells])
        for k, t in zip(positions, times):
            pd, cd = data(int(k))
            w.write_data(float(t), point_data=pd, cell_data=_split(cells, cd))
    return [output, h5]


def vtu_name(output: Path, step: int, width: int = 4) -> str:
    """File name of the ``.vtu`` of step number ``step`` of a ``.pvd`` output: ``OUT_0003.vtu``."""
    return f"{output.stem}_{int(step):0{width}d}.vtu"


def _write_pvd(output: Path, geom, data, positions, times, step_numbers):
    width = max(4, len(str(int(np.max(step_numbers)))))
    cells = [(k, c) for k, c in geom.cells]
    files, lines = [], []
    for k, t, s in zip(positions, times, step_numbers):
        pd, cd = data(int(k))
        name = vtu_name(output, s, width)
        meshio.write(output.with_name(name), meshio.Mesh(geom.points, cells, point_data=pd,
                                                         cell_data=_split(geom.cells, cd)), file_format="vtu")
        files.append(output.with_name(name))
        lines.append(f'    <DataSet timestep="{float(t)!r}" group="" part="0" file={quoteattr(name)}/>')
    text = ('<?xml version="1.0"?>\n'
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            '  <Collection>\n' + "\n".join(lines) + '\n  </Collection>\n</VTKFile>\n')
    tmp = output.with_name(output.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, output)
    return [output] + files
