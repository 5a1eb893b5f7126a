"""Histories of a result file (``masonrydam plot OUT.nc``, ``masonrydam plot OUT.nc --quantity VAR``).

The x axis (:func:`step_axis`):

- dynamic results (a non-NaN ``time``): the time (s) of the dynamic steps; the static steps before
  them are left out;
- static results: the load factor. One stage: its load factor (0 to 1). Several stages: stage ``k``
  (the k-th stage in the file, counted from 0) spans ``k`` to ``k + 1`` with its load factor inside, the
  tick labels are the load factor within the stage (``1|0`` where one stage ends and the next starts)
  and the stage names stand above the axes. A stage whose load factor goes back (arc length) gives
  the step number instead.

:func:`history_figure` draws the default panels (the ground acceleration at its own sampling rate, a
node's displacement, a joint point's slip and opening, the energies); :func:`quantity_figure` draws any
step variable with an xarray-style selection (``--quantity VAR --select DIM=VALUE``). Panels with
nothing to draw are left out, lines without a value are not drawn; legends stand outside the axes, at
their right. The figures are matplotlib :class:`~matplotlib.figure.Figure` objects on the Agg canvas
(the global backend is left alone); the static default of ``masonrydam plot`` with driven DOFs is the
pushover curve (:func:`masonrydam.results.pushover.pushover_figure`, chosen by the CLI).
"""
from __future__ import annotations

import itertools
import json
import textwrap
from dataclasses import dataclass, field

import numpy as np

from ..errors import MasonrydamError
from .pushover import pushover_data, pushover_figure

#: energy terms drawn by ``masonrydam plot`` (those that are not zero throughout)
PLOTTED_ENERGIES = ("input", "external", "kinetic", "strain", "damping", "joint_stored", "joint_friction",
                    "joint_bond_break", "joint_contact", "numerical", "error")
#: most lines one ``--quantity`` figure draws; a selection that leaves more is an error
MAX_LINES = 10
#: legend outside the axes, at their right (constrained layout makes room for it)
LEGEND = dict(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


def is_dynamic(ds) -> bool:
    """Whether ``ds`` has dynamic steps (a ``time`` that is not NaN throughout)."""
    return "time" in ds.variables and bool(np.isfinite(ds["time"].values).any())


def stage_names(ds) -> list:
    """The scene's stage names (attribute ``stage_names`` of ``stage``), [] when the file has none."""
    try:
        return list(json.loads(ds["stage"].attrs.get("stage_names", "[]")))
    except (KeyError, ValueError, TypeError):
        return []


@dataclass
class StepAxis:
    """The x axis of a history: ``steps`` the positions along ``step`` drawn, ``x`` their abscissae,
    ``label`` the axis label, ``kind`` ``"time"``, ``"load_factor"`` or ``"step"``; ``spans`` (static
    results with several stages) ``(x0, x1, stage name)`` of each stage along x."""

    steps: np.ndarray
    x: np.ndarray
    label: str
    kind: str
    spans: list = field(default_factory=list)


def step_axis(ds) -> StepAxis:
    """The x axis of a history of ``ds`` (module docstring)."""
    n = ds.sizes["step"]
    if is_dynamic(ds):
        steps = np.flatnonzero(np.isfinite(ds["time"].values))
        return StepAxis(steps, ds["time"].values[steps], "time [s]", "time")
    steps = np.arange(n)
    if "stage" not in ds or "load_factor" not in ds:
        return StepAxis(steps, steps.astype(float), "step", "step")
    stage = ds["stage"].values.astype(int)
    lam = ds["load_factor"].values.astype(float)
    names = stage_names(ds)
    order = list(dict.fromkeys(stage.tolist()))  # the stages in the file, in order

    def name(k):
        return names[k] if 0 <= k < len(names) else f"stage {k}"

    in_range = bool(np.isfinite(lam).all()) and bool(((lam >= -1e-9) & (lam <= 1.0 + 1e-9)).all())
    monotonic = in_range and all((np.diff(lam[stage == k]) >= -1e-12).all() for k in order)
    contiguous = all((np.diff(np.flatnonzero(stage == k)) == 1).all() for k in order)
    if not (monotonic and contiguous):
        why = ("the load factor goes back or leaves 0 to 1 within a stage: arc length" if not monotonic else
               "a stage's steps are not consecutive")
        return StepAxis(steps, steps.astype(float), f"step ({why})", "step", _step_spans(stage, order, name))
    if len(order) == 1:
        return StepAxis(steps, lam, f"load factor of stage '{name(order[0])}' (0 to 1)", "load_factor")
    pos = {k: i for i, k in enumerate(order)}
    x = np.array([pos[k] for k in stage], dtype=float) + lam
    spans = [(float(i), float(i + 1), name(k)) for i, k in enumerate(order)]
    return StepAxis(steps, x, "load factor within each stage (1|0: one stage ends, the next starts)",
                    "load_factor", spans)


def _step_spans(stage, order, name):
    spans = []
    for k in order:
        at = np.flatnonzero(stage == k)
        spans.append((float(at[0]) - 0.5, float(at[-1]) + 0.5, name(k)))
    return spans


def _decorate_x(ax, axis: StepAxis):
    """Label the x axis; several static stages: a dotted line where one stage ends, the stage names in a
    second row of tick labels under the middle of each stage's span, and (load-factor axis) tick labels
    that give the load factor within the stage."""
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib.ticker import FuncFormatter, MultipleLocator

    ax.set_xlabel(axis.label)
    if not axis.spans:
        return
    if len(axis.spans) > 1:  # a collection, not a Line2D: ax.get_lines() are the data
        ax.vlines([x0 for x0, _, _ in axis.spans[1:]], 0.0, 1.0, transform=ax.get_xaxis_transform(),
                  colors="0.6", lw=0.6, linestyles=":", zorder=0)
    if axis.kind == "load_factor":
        last = len(axis.spans)
        ax.xaxis.set_major_locator(MultipleLocator(0.5 if last <= 4 else 1.0))

        def fmt(v, _pos):
            k = round(v)
            if abs(v - k) < 1e-9:
                return "0" if k <= 0 else "1" if k >= last else "1|0"
            return f"{v - np.floor(v):g}"

        ax.xaxis.set_major_formatter(FuncFormatter(fmt))
    ax.set_xticks([0.5 * (x0 + x1) for x0, x1, _ in axis.spans], [s for _, _, s in axis.spans], minor=True)
    ax.tick_params(axis="x", which="minor", length=0, pad=17, labelsize=7)
    ax.xaxis.remove_overlapping_locs = False  # a stage's middle may be a major tick (0.5)


def _new_figure(n_panels: int, height: float = 2.6):
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.0, height * n_panels), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots(n_panels, 1, squeeze=False)[:, 0]


def ground_records(ds) -> dict:
    """``{component: (time (n,), acceleration (n,))}`` of the ground-acceleration records at their own
    sampling rate (variables ``ground_acceleration_record_<c>`` with their time ``ground_record_time_<c>``,
    written by :meth:`~masonrydam.results.writer.ResultWriter.write_ground_records`); components without a
    record are absent ({} for a file written before these variables)."""
    out = {}
    for c in ds["component"].values:
        name = f"ground_acceleration_record_{c}"
        if name in ds.variables and f"ground_record_time_{c}" in ds.variables:
            out[str(c)] = (ds[f"ground_record_time_{c}"].values, ds[name].values)
    return out


def _has_values(v) -> bool:
    v = np.asarray(v, dtype=float)
    return bool(np.isfinite(v).any() and np.nanmax(np.abs(v)) > 0)


def history_figure(ds, title: str, comp: str = "x", nodes=None, joints=None):
    """The history figure of ``masonrydam plot`` (a matplotlib Figure, not drawn to screen), against
    :func:`step_axis` (time for dynamic results, the load factor for static ones), one panel each for

    - the ground acceleration (dynamic results): each component's record at its own sampling rate
      (:func:`ground_records`; a file without the records: ``ground_acceleration`` at the output steps,
      labelled so), components without motion left out;
    - the displacement (relative to the ground in dynamic results) in component ``comp`` of ``nodes``
      (node numbers; default: the recorded node that moves most);
    - slip and opening of ``joints`` (joint point indices; default: the one that slips most, or else
      opens most); 3D results: the slip's magnitude and both components;
    - the energy balance (dynamic results: the terms of :data:`PLOTTED_ENERGIES` that are not zero).

    A default panel with nothing to draw (no ground motion, nothing moves, no joint slips or opens, no
    energy) is left out. Errors (MasonrydamError) name the bad option."""
    if not ds.sizes["step"]:
        raise MasonrydamError(f"'{title}' has no steps to plot (status '{ds.attrs.get('status', '?')}': the run "
                              "stopped before its first converged step)")
    if comp not in ds["component"].values:
        raise MasonrydamError(f"--component must be one of {list(ds.component.values)}, got {comp!r}")
    axis = step_axis(ds)
    dynamic = axis.kind == "time"
    ds = ds.isel(step=axis.steps)
    x = axis.x
    u = ds["displacement"].sel(component=comp).values
    if nodes:
        pos = []
        for n in nodes:
            hit = np.nonzero(ds["node"].values == n)[0]
            if not len(hit):
                raise MasonrydamError(f"--nodes: node {n} is not in the file (recorded nodes: "
                                      f"{ds.node.values[:10].tolist()}{' ...' if ds.sizes['node'] > 10 else ''})")
            pos.append(int(hit[0]))
    elif ds.sizes["node"] and _has_values(u):
        pos = [int(np.nanargmax(np.nan_to_num(np.abs(u)).max(axis=0)))]
    else:
        pos = []
    njp = ds.sizes.get("joint_point", 0) if "joint_slip" in ds else 0
    if joints:
        bad = [j for j in joints if not 0 <= j < njp]
        if bad:
            raise MasonrydamError(f"--joints: joint point(s) {bad} not in the file "
                                  + (f"(0 to {njp - 1})" if njp else "(it has no joint points)"))
        jpos = list(joints)
    elif njp:
        slip = np.nan_to_num(np.linalg.norm(ds["joint_slip"].values, axis=2))
        opening = np.nan_to_num(np.abs(ds["joint_opening"].values))
        if slip.max() > 0:
            jpos = [int(np.argmax(slip.max(axis=0)))]
        elif opening.max() > 0:
            jpos = [int(np.argmax(opening.max(axis=0)))]
        else:
            jpos = []
    else:
        jpos = []
    ground = {}
    if dynamic:
        ground = {c: (t, a, "") for c, (t, a) in ground_records(ds).items() if _has_values(a)}
        if not ground and "ground_acceleration" in ds:  # a file written before the records were kept
            for c in ds["component"].values:
                a = ds["ground_acceleration"].sel(component=c).values
                if _has_values(a):
                    ground[str(c)] = (x, a, " (output steps)")
    energies = []
    if dynamic:
        for name in PLOTTED_ENERGIES:
            v = ds.get(f"energy_{name}")
            if v is not None and _has_values(v.values):
                energies.append((name, v.values))
    panels = ((["ground"] if ground else []) + (["disp"] if pos else []) + (["joint"] if jpos else [])
              + (["energy"] if energies else []))
    if not panels:
        raise MasonrydamError(f"'{title}': nothing to draw: no node moves, no joint point slips or opens"
                              + (", no ground motion and no energy" if dynamic else "")
                              + "; give --nodes, --joints or --quantity VAR")
    fig, axs = _new_figure(len(panels))
    dim = ds.sizes["component"]
    for ax, kind in zip(axs, panels):
        if kind == "ground":
            for c, (t, a, note) in ground.items():
                ax.plot(t, a, lw=0.7, label=f"a_g,{c}{note}")
            ax.set_ylabel("ground acc. [m/s2]")
        elif kind == "disp":
            for p in pos:
                ax.plot(x, u[:, p], lw=0.8, label=f"node {int(ds.node.values[p])}")
            ax.set_ylabel(f"u_{comp} [m]" + (" (relative)" if dynamic else ""))
        elif kind == "joint":
            slip, opening = ds["joint_slip"].values, ds["joint_opening"].values
            for i, j in enumerate(jpos):
                colour = f"C{i % 10}"
                if dim == 2:
                    lines = [(slip[:, j, 0], "-", 0.9, f"slip, point {j}")]
                else:  # the magnitude and both components
                    lines = [(np.linalg.norm(slip[:, j, :], axis=1), "-", 1.1, f"|slip|, point {j}")]
                    lines += [(slip[:, j, k], ls, 0.7, f"slip {d}, point {j}")
                              for k, (d, ls) in enumerate(zip(ds["shear_direction"].values, (":", "-.")))]
                lines.append((opening[:, j], "--", 0.9, f"opening, point {j}"))
                drawn = [line for line in lines if _has_values(line[0])] or lines[:1]  # no line of zeros
                for y, ls, lw, label in drawn:
                    ax.plot(x, y, lw=lw, ls=ls, color=colour, label=label)
            ax.set_ylabel("joint slip, opening [m]")
        else:
            for name, v in energies:
                ax.plot(x, v, lw=0.8, label=name)
            ax.set_ylabel("energy [J]")
        _decorate_x(ax, axis)
        if dynamic and len(x) > 1:  # one time range for every panel (a record may end before the response)
            ax.set_xlim(x.min(), x.max())
        ax.grid(True, alpha=0.3)
        ax.legend(**LEGEND)
    fig.suptitle(f"{title}: {ds.attrs.get('scene_name', '')} (completed = {ds.attrs.get('completed', '?')})")
    return fig


# ----------------------------------------------------------------------------------------------
# --quantity VAR --select DIM=VALUE
# ----------------------------------------------------------------------------------------------

def parse_selection(items) -> dict:
    """``["dim=value", "dim2=v1,v2"]`` (``--select``) -> ``{"dim": "value", "dim2": "v1,v2"}``; values are
    converted against the file in :func:`select_quantity`."""
    out = {}
    for item in items or ():
        dim, eq, value = str(item).partition("=")
        dim, value = dim.strip(), value.strip()
        if not eq or not dim or not value:
            raise MasonrydamError(f"--select {item!r}: give DIM=VALUE, e.g. --select joint_point=12 component=x")
        if dim in out:
            raise MasonrydamError(f"--select: dimension {dim!r} is given twice (several values: {dim}=A,B)")
        out[dim] = value
    return out


def history_variables(ds) -> list:
    """The variables of ``ds`` that ``--quantity`` can draw: those along ``step`` (except the ``step``
    coordinate itself) and the ground-acceleration records."""
    names = [str(n) for n, v in ds.variables.items() if "step" in v.dims and n != "step"]
    return names + [str(n) for n in ds.variables if str(n).startswith("ground_acceleration_record_")]


def _list_text(values, limit: int = 20) -> str:
    values = list(values)
    if len(values) > 2 and all(isinstance(v, (int, np.integer)) for v in values) \
            and np.array_equal(np.diff(values), np.ones(len(values) - 1)):
        return f"{values[0]} to {values[-1]}"
    shown = ", ".join(str(v) for v in values[:limit])
    return shown + (f", ... ({len(values)} values)" if len(values) > limit else "")


def _x_dim(ds, name):
    """The dimension a history of ``name`` runs along: ``step``, or the dimension of a 1D coordinate in
    seconds (a ground-acceleration record's own time)."""
    var = ds[name]
    if "step" in var.dims:
        return "step", None
    for cname, cvar in var.coords.items():
        if len(cvar.dims) == 1 and cvar.dims[0] in var.dims and cvar.attrs.get("units") == "s":
            return cvar.dims[0], str(cname)
    return None, None


def _convert(ds, name, dim, token):
    """``token`` (text) as a value of ``dim``'s coordinate (or a position along a dimension without one)."""
    has_coord = dim in ds.coords and ds[dim].dims == (dim,)
    values = ds[dim].values if has_coord else np.arange(ds.sizes[dim])
    kind = values.dtype.kind
    try:
        if kind in "iu":
            value = int(token)
        elif kind == "f":
            value = float(token)
        else:
            value = str(token)
    except ValueError:
        value = None
    if value is None or not (values == value).any():
        what = "values" if has_coord else "positions (no coordinate)"
        raise MasonrydamError(f"--select {dim}={token}: {token!r} is not a value of {dim!r} in the file; its "
                              f"{what}: {_list_text([v.item() if hasattr(v, 'item') else v for v in values])}")
    return value, has_coord


def select_quantity(ds, name: str, selection: dict | None = None):
    """``(DataArray, x dimension)``: variable ``name`` of ``ds`` with ``selection`` (``{dim: "value"}`` or
    ``{dim: "v1,v2"}``, values of the dimension's coordinate, or positions along a dimension without
    one) applied. Unknown variable, dimension or value: MasonrydamError naming it and listing the
    choices."""
    choices = history_variables(ds)
    if name not in ds.variables:
        raise MasonrydamError(f"--quantity {name!r}: no such variable in the result; variables with a history: "
                              f"{', '.join(choices)}")
    xdim, _ = _x_dim(ds, name)
    if xdim is None:
        raise MasonrydamError(f"--quantity {name!r} has no step dimension (dimensions {list(ds[name].dims)}): "
                              f"it is not a history; variables with a history: {', '.join(choices)}")
    var = ds[name]
    others = [d for d in var.dims if d != xdim]
    sel, isel = {}, {}
    for dim, text in (selection or {}).items():
        if dim == xdim:
            raise MasonrydamError(f"--select {dim}=...: {dim!r} is the x axis of the history; select along "
                                  + (", ".join(others) if others else "nothing (the variable has one line)"))
        if dim not in var.dims:
            raise MasonrydamError(f"--select {dim}=...: {name} has no dimension {dim!r}; "
                                  + (f"its dimensions to select: {', '.join(others)}" if others else
                                     f"it has no dimension to select (only {xdim})"))
        tokens = [t.strip() for t in text.split(",") if t.strip()]
        converted = [_convert(ds, name, dim, t) for t in tokens]
        values = [v for v, _ in converted]
        target = sel if converted[0][1] else isel
        target[dim] = values[0] if len(values) == 1 else values
    if isel:
        var = var.isel(isel)
    if sel:
        var = var.sel(sel)
    return var, xdim


def quantity_figure(ds, name: str, selection: dict | None = None, title: str | None = None,
                    max_lines: int = MAX_LINES):
    """The history of variable ``name`` with ``selection`` (:func:`select_quantity`) as a matplotlib Figure:
    against :func:`step_axis` (time or load factor), or a ground-acceleration record against its own time;
    one line per value of the dimensions left after the selection, at most ``max_lines`` (else a
    MasonrydamError naming the dimensions to select). The y label is the variable's ``long_name`` with its
    ``units``."""
    if not ds.sizes.get("step", 0):
        raise MasonrydamError(f"'{title or 'the result'}' has no steps to plot (status "
                              f"'{ds.attrs.get('status', '?')}': the run stopped before its first converged step)")
    var, xdim = select_quantity(ds, name, selection)
    others = [d for d in var.dims if d != xdim]
    n_lines = int(np.prod([var.sizes[d] for d in others], dtype=np.int64)) if others else 1
    if n_lines > max_lines:
        sizes = ", ".join(f"{d} ({var.sizes[d]} value{'s' if var.sizes[d] != 1 else ''})" for d in others)
        raise MasonrydamError(f"--quantity {name}: {n_lines} lines after the selection, more than {max_lines}: "
                              f"select along {sizes} with --select DIM=VALUE (several values: DIM=A,B)")
    if xdim == "step":
        axis = step_axis(ds)
        var = var.isel(step=axis.steps)
    else:
        _, tname = _x_dim(ds, name)
        t = ds[tname].values
        axis = StepAxis(np.arange(len(t)), t, "time [s]", "time")
    values = var.transpose(xdim, *others).values.reshape(len(axis.x), n_lines)
    labels = []
    for combo in itertools.product(*[[(d, v) for v in _coord_values(var, d)] for d in others]):
        labels.append(", ".join(f"{d}={v}" for d, v in combo))
    fixed = [f"{d}={v}" for d, v in (selection or {}).items() if d not in others]
    drawn = [(values[:, i], labels[i] if others else name) for i in range(n_lines)
             if np.isfinite(values[:, i].astype(float)).any()]
    if not drawn:
        raise MasonrydamError(f"--quantity {name}: no value at the drawn steps (NaN throughout"
                              + ("; the static steps of a dynamic result are not drawn against time)"
                                 if axis.kind == "time" else ")"))
    fig, (ax,) = _new_figure(1, height=4.2)
    step_style = "steps-post" if var.dtype.kind in "iub" else "default"
    for y, label in drawn:
        ax.plot(axis.x, y, lw=0.9, drawstyle=step_style, label=label)
    ax.set_ylabel(quantity_label(ds[name]))
    _decorate_x(ax, axis)
    ax.grid(True, alpha=0.3)
    if len(drawn) > 1:
        ax.legend(**LEGEND)
    head = f"{title}: " if title else ""
    ax.set_title(f"{head}{name}" + (f" ({', '.join(fixed)})" if fixed else ""), fontsize=9)
    return fig


def quantity_label(var, width: int = 50) -> str:
    """``long_name [units]`` of a variable (its name where it has no long_name), wrapped to ``width``."""
    text = f"{var.attrs.get('long_name') or var.name} [{var.attrs.get('units', '?')}]"
    return "\n".join(textwrap.wrap(text, width))


def _coord_values(var, dim):
    if dim in var.coords and var[dim].dims == (dim,):
        return [_scalar(v) for v in var[dim].values]
    return list(range(var.sizes[dim]))


def _scalar(v):
    v = np.asarray(v)
    return v.item() if v.ndim == 0 else v


# ----------------------------------------------------------------------------------------------
# the default figure of `masonrydam plot OUT.nc`
# ----------------------------------------------------------------------------------------------

def pushover_component(ds, comp: str | None = None):
    """The component whose pushover curve is the default figure of a static result, or None: ``comp``
    when given and a static stage drives it, else the component of the last driving stage (variable
    ``driven``); None for a dynamic result, a result without driven DOFs among the recorded nodes or
    without a converged step of the driving stage."""
    if "driven" not in ds or not ds.sizes.get("step", 0) or is_dynamic(ds):
        return None
    comps = [str(c) for c in ds["component"].values]
    if comp is not None:
        candidates = [comp] if comp in comps else []
    else:
        last = {c: int(ds["driven"].sel(component=c).max()) for c in comps}
        candidates = sorted((c for c in comps if last[c] > 0), key=lambda c: -last[c])
    for c in candidates:
        try:
            pushover_data(ds, c)
        except MasonrydamError:
            continue
        return c
    return None


def default_figure(ds, title: str, comp: str | None = None, nodes=None, joints=None):
    """The figure of ``masonrydam plot OUT.nc``: for a static result with driven DOFs (and no ``nodes`` or
    ``joints`` asked for) the pushover curve of :func:`pushover_component`
    (:func:`masonrydam.results.pushover.pushover_figure`), else :func:`history_figure` (against time, or the
    load factor of the static stages)."""
    if not nodes and not joints:
        c = pushover_component(ds, comp)
        if c is not None:
            return pushover_figure(ds, c, title=title)
    return history_figure(ds, title, comp or "x", nodes, joints)
