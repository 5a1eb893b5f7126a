"""Figures and tables of an ensemble dataset: IDA curves and fragility curves.

- :func:`ida_figure`: incremental dynamic analysis curves (Vamvatsikos & Cornell 2002, "Incremental
  dynamic analysis", Earthquake Engng Struct. Dyn. 31, 491-514): the demand against the intensity for
  every record (and sample), one colour per parameter combination, the median over records, and the
  collapses (a dotted line from the last point that stood to a cross at the right edge, at the
  intensity that brought it down).
- :func:`fragility_figure`: the fraction of runs failing at each intensity (markers, with the counts),
  the fitted lognormal fragility of each parameter combination and its median with the confidence band.
- :func:`ensemble_report`: the fragility table as text lines and both figures; :func:`write_table_csv`
  writes the table as CSV.

Intensities in m/s2 (PGA, Sa) are plotted in g (divided by 9.80665, as the axis label says). The figures
use matplotlib's object API on the Agg canvas: the global pyplot state and backend are left alone.
Every curve carries a ``gid`` naming what it draws (``"ida:record=...;p_x=..."``, ``"collapse:..."``,
``"numerical:..."``, ``"median:..."``, ``"fraction:..."``, ``"fit:..."``), so that scripts and tests can
find it.
"""
from __future__ import annotations

import csv
import math
import textwrap
from pathlib import Path

import numpy as np

from .fragility import (G, INTENSITY_DIM, STATUS_COLLAPSE, STATUS_COMPLETED, STATUS_NOT_RUN, STATUS_NUMERICAL,
                        FragilityError, FragilityRow, as_dataset, at_parameters, check_ensemble_dataset,
                        demand_variables, failure_definition, fragility_table, intensity_units, parameter_combinations,
                        parameter_dims, run_dims)

#: demands tried in this order when an IDA figure is asked for without one
DEFAULT_DEMANDS = ("peak_drift", "peak_displacement")


# ------------------------------------------------------------------------------------------------------
# labels
# ------------------------------------------------------------------------------------------------------

def intensity_axis(ds) -> tuple[float, str]:
    """``(scale, label)``: the factor from the dataset's intensities to the plotted ones and the axis
    label (m/s2 is plotted in g, and the label says so)."""
    coord = ds[INTENSITY_DIM]
    measure = str(coord.attrs.get("measure", "")).lower()
    units = str(coord.attrs.get("units", ""))
    if measure == "pga":
        name = "PGA"
    elif measure == "sa":
        period, damping = coord.attrs.get("period"), coord.attrs.get("damping")
        inside = []
        if period is not None:
            inside.append(f"T = {float(period):g} s")
        if damping is not None:
            inside.append(f"{100 * float(damping):g} % damping")
        name = f"Sa({', '.join(inside)})" if inside else "Sa"
    else:
        name = str(coord.attrs.get("long_name", measure or "intensity"))
    if units == "m/s2":
        return 1.0 / G, f"{name} [g] (m/s2 divided by 9.80665)"
    return 1.0, f"{name} [{units}]" if units else name


def demand_label(ds, demand: str) -> str:
    """``long_name [units]`` of a demand variable (``[-]`` for a ratio)."""
    attrs = ds[demand].attrs
    units = str(attrs.get("units", ""))
    units = "-" if units in ("", "1") else units
    return f"{attrs.get('long_name', demand)} [{units}]"


def _format_value(v) -> str:
    v = v.item() if hasattr(v, "item") else v
    return f"{v:g}" if isinstance(v, float) else str(v)


def dim_key(ds, dim: str) -> str:
    """The scene key a parameter dim varies (its ``scene_key`` attr), else the dim's name."""
    return str(ds[dim].attrs.get("scene_key", dim)) if dim in ds.coords else dim


def combination_label(ds, params: dict) -> str:
    """``scene.key = value, ...`` of a parameter combination."""
    return ", ".join(f"{dim_key(ds, d)} = {_format_value(v)}" for d, v in params.items()) or "all runs"


def _gid(kind: str, params: dict, **more) -> str:
    items = [f"{k}={_format_value(v)}" for k, v in (*more.items(), *params.items())]
    return f"{kind}:" + ";".join(items)


def _colors(k: int):
    if k <= 10:
        return [f"C{i}" for i in range(k)]
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    return [cmap(i / max(k - 1, 1)) for i in range(k)]


def _new_figure(width=9.0, height=5.5):
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots()


def default_demand(ds) -> str | None:
    """The demand an IDA figure shows by default: ``peak_drift``, else ``peak_displacement``, else the
    first demand variable (None if there is none)."""
    names = demand_variables(ds)
    for d in DEFAULT_DEMANDS:
        if d in names:
            return d
    return names[0] if names else None


# ------------------------------------------------------------------------------------------------------
# IDA curves
# ------------------------------------------------------------------------------------------------------

def ida_curves(ds, demand: str, params: dict | None = None):
    """The IDA curves of one parameter combination: a list of dicts, one per run (record, sample), each
    with ``record`` (and ``sample``), ``im`` and ``demand`` (the points that stood, in increasing
    intensity, up to the first collapse; numerical failures and NaN demands left out), ``collapse_im``
    (the lowest intensity that collapsed the run, or None), ``numerical_im``/``numerical_demand``
    (numerical failures below it). Intensities in the dataset's units. Runs that stood again above the
    first collapse ("structural resurrection") end at the first collapse, as in Vamvatsikos & Cornell."""
    params = params or {}
    st = at_parameters(ds["status"], params)
    dv = at_parameters(ds[demand].broadcast_like(ds["status"]), params)
    runs = run_dims(ds)
    st = st.transpose(*runs, INTENSITY_DIM)
    dv = dv.transpose(*runs, INTENSITY_DIM)
    im = np.asarray(st[INTENSITY_DIM].values, dtype=float)
    order = np.argsort(im)
    curves = []
    for idx in np.ndindex(*[st.sizes[d] for d in runs]):
        s = np.asarray(st.values[idx])[order]
        y = np.asarray(dv.values[idx], dtype=float)[order]
        x = im[order]
        hit = np.flatnonzero(s == STATUS_COLLAPSE)
        stop = int(hit[0]) if hit.size else s.size
        ok = (s[:stop] == STATUS_COMPLETED) & np.isfinite(y[:stop])
        num = (s[:stop] == STATUS_NUMERICAL) & np.isfinite(y[:stop])
        curve = {d: st[d].values[i] if d in st.coords else i for d, i in zip(runs, idx)}
        curve.update(im=x[:stop][ok], demand=y[:stop][ok], collapse_im=float(x[stop]) if hit.size else None,
                     numerical_im=x[:stop][num], numerical_demand=y[:stop][num])
        curves.append(curve)
    return curves


def median_ida(ds, demand: str, params: dict | None = None):
    """``(im, median)``: the median demand over the runs at each intensity (a collapsed run, and a run
    above its first collapse, counts as infinite demand; numerical failures are left out), up to the
    last intensity where the median is finite (less than half the runs collapsed)."""
    curves = ida_curves(ds, demand, params)
    im = np.unique(np.asarray(ds[INTENSITY_DIM].values, dtype=float))
    table = np.full((len(curves), im.size), np.nan)
    for r, c in enumerate(curves):
        pos = np.searchsorted(im, c["im"])
        table[r, pos] = c["demand"]
        if c["collapse_im"] is not None:
            table[r, im >= c["collapse_im"]] = np.inf
    counted = np.isfinite(table) | np.isinf(table)
    med = np.full(im.size, np.nan)
    for j in range(im.size):
        if counted[:, j].any():
            med[j] = np.median(table[counted[:, j], j])
    keep = np.isfinite(med)
    last = np.flatnonzero(np.isinf(med))
    if last.size:
        keep &= np.arange(im.size) < last[0]
    return im[keep], med[keep]


def ida_figure(ds, demand: str | None = None, title: str | None = None):
    """IDA curves of ``demand`` (a data variable; default :func:`default_demand`): demand (x) against
    intensity (y, in g for PGA and Sa in m/s2), one thin line per record (and sample) and parameter
    combination (a colour each), the median over the records (thick), collapses as a dotted line from
    the last point that stood to a cross at the right edge at the collapse intensity, and numerical
    failures as open circles at the demand they reached. Returns a matplotlib Figure (Agg)."""
    ds = as_dataset(ds)
    check_ensemble_dataset(ds)
    if demand is None:
        demand = default_demand(ds)
        if demand is None:
            raise FragilityError("the ensemble dataset has no demand variable to draw IDA curves of")
    if demand not in ds.data_vars:
        raise FragilityError(f"demand '{demand}' is not a variable of the ensemble dataset "
                             f"(demands: {', '.join(demand_variables(ds)) or 'none'})")
    scale, ylabel = intensity_axis(ds)
    combos = parameter_combinations(ds)
    colors = _colors(len(combos))
    all_curves = [ida_curves(ds, demand, p) for p in combos]
    stood = [c["demand"] for curves in all_curves for c in curves] + \
            [c["numerical_demand"] for curves in all_curves for c in curves]
    stood = np.concatenate(stood) if stood else np.zeros(0)
    stood = stood[np.isfinite(stood)]
    x_left = min(0.0, float(stood.min())) if stood.size else 0.0
    top = float(stood.max()) if stood.size else 1.0
    x_edge = top + 0.1 * (top - x_left) if top > x_left else x_left + 1.0  # the "collapse" edge

    fig, ax = _new_figure()
    n_collapse = n_numerical = 0
    for params, curves, color in zip(combos, all_curves, colors):
        label = combination_label(ds, params)
        for c in curves:
            run = {d: c[d] for d in run_dims(ds)}
            ax.plot(c["demand"], c["im"] * scale, color=color, lw=0.8, alpha=0.55, marker=".", ms=3,
                    gid=_gid("ida", params, **run))
            if c["collapse_im"] is not None:
                n_collapse += 1
                x0, y0 = (c["demand"][-1], c["im"][-1]) if c["im"].size else (x_left, c["collapse_im"])
                ax.plot([x0, x_edge], [y0 * scale, c["collapse_im"] * scale], color=color, lw=0.8, ls=":",
                        alpha=0.7, marker="x", markevery=[1], ms=6, gid=_gid("collapse", params, **run))
            if c["numerical_im"].size:
                n_numerical += c["numerical_im"].size
                ax.plot(c["numerical_demand"], c["numerical_im"] * scale, ls="none", marker="o", mfc="none",
                        color=color, ms=5, gid=_gid("numerical", params, **run))
        im_m, d_m = median_ida(ds, demand, params)
        what = f"median of {len(curves)} " + ("runs (records x samples)" if "sample" in run_dims(ds) else "records")
        ax.plot(d_m, im_m * scale, color=color, lw=2.4, gid=_gid("median", params),
                label=f"{label}: {what}" if params else what)
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib.lines import Line2D

    handles, labels = ax.get_legend_handles_labels()
    handles.append(Line2D([], [], color="0.3", lw=0.8, alpha=0.6))
    labels.append("one record" if "sample" not in run_dims(ds) else "one record and sample")
    if n_collapse:
        handles.append(Line2D([], [], color="0.3", ls=":", marker="x"))
        labels.append(f"collapse ({n_collapse}): at the cross's intensity")
    if n_numerical:
        handles.append(Line2D([], [], color="0.3", ls="none", marker="o", mfc="none"))
        labels.append(f"numerical failure ({n_numerical}), left out")
    ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    ax.set_xlim(x_left, x_edge + 0.03 * (x_edge - x_left))
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel(demand_label(ds, demand))
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.set_title(title or f"IDA curves: {ds[demand].attrs.get('long_name', demand)}", fontsize=10)
    return fig


# ------------------------------------------------------------------------------------------------------
# fragility curves
# ------------------------------------------------------------------------------------------------------

def fragility_figure(ds, demand: str | None = None, limit: float | None = None, level: float = 0.9,
                     rows: list[FragilityRow] | None = None, title: str | None = None):
    """Fragility curves: for each parameter combination the fraction of usable runs that fail at each
    intensity (markers, annotated ``failures/runs``), the fitted lognormal CDF, and its median (a
    diamond at P = 0.5) with the ``level`` confidence band (shaded; an open side reaches the axis edge).
    The title gives the definition of failure (collapse, or ``demand > limit`` or collapse) and the runs
    excluded. ``rows``: a :func:`~masonrydam.ensemble.fragility.fragility_table` already computed.
    Returns a matplotlib Figure (Agg)."""
    ds = as_dataset(ds)
    rows = fragility_table(ds, demand, limit, level) if rows is None else rows
    scale, xlabel = intensity_axis(ds)
    units = intensity_units(ds)
    unit_txt = "g" if scale != 1.0 else units
    colors = _colors(len(rows))
    ims = np.concatenate([r.im[r.n > 0] for r in rows if r.n is not None and (r.n > 0).any()] or [np.ones(1)])
    x_max = float(ims.max())  # in the dataset's units until scaled below
    for r in rows:
        if r.fit.identifiable:
            x_max = max(x_max, min(float(r.fit.quantile(0.98)), 2.0 * float(ims.max())))
    x_max *= 1.05 * scale  # plotted units from here on
    fig, ax = _new_figure(8.0, 6.5)
    grid = np.linspace(x_max / 400.0, x_max, 400)
    for k, (r, color) in enumerate(zip(rows, colors)):
        label = combination_label(ds, r.params)
        key = r.params
        have = r.n > 0
        frac = r.failed[have] / r.n[have]
        ax.plot(r.im[have] * scale, frac, ls="none", marker="o", color=color, ms=6, mfc="white", mew=1.5,
                gid=_gid("fraction", key))
        for x, y, z, n in zip(r.im[have] * scale, frac, r.failed[have], r.n[have]):
            ax.annotate(f"{int(z)}/{int(n)}", (x, y), textcoords="offset points",
                        xytext=(4, (-10 - 8 * k) if y > 0.5 else (5 + 8 * k)),
                        fontsize=7, color=color)
        f = r.fit
        if f.identifiable:
            lo, hi = f.median_ci
            hi_txt = "inf" if not math.isfinite(hi) else f"{hi * scale:.3g}"
            text = (f"median {f.median * scale:.3g} {unit_txt} [{lo * scale:.3g}, {hi_txt}], "
                    f"beta {f.dispersion:.2f}")
            ax.plot(grid, f.probability(grid / scale), color=color, lw=1.8, gid=_gid("fit", key),
                    label=f"{label}: {text}" if r.params else text)
            ax.axvspan(lo * scale, min(hi * scale, x_max * 1.2), color=color, alpha=0.12, lw=0,
                       gid=_gid("median_band", key))
            ax.plot([f.median * scale], [0.5], marker="D", color=color, ms=6, ls="none", gid=_gid("median", key))
        else:
            ax.plot([], [], ls="none", marker="o", color=color, mfc="white",
                    label=f"{label}: not identifiable ({f.reason.split(':')[0]})" if r.params
                    else f"not identifiable ({f.reason.split(':')[0]})")
    ax.set_xlim(0.0, x_max)
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("probability of failure")
    ax.grid(True, alpha=0.3)
    excluded = sum(r.n_excluded for r in rows)
    total = FragilityRow(params={}, fit=rows[0].fit, n_runs=0, n_failures=0, n_excluded=excluded,
                         n_numerical=sum(r.n_numerical for r in rows), n_not_run=sum(r.n_not_run for r in rows))
    head = failure_definition(ds, demand, limit)
    sub = (f"markers: failed/runs at each intensity; lines: lognormal MLE; band: {100 * level:g} % interval of "
           f"the median ({_ci_method(rows)})")
    if excluded:
        sub += f"; {excluded} run{'s' if excluded != 1 else ''} excluded ({total.excluded_text})"
    ax.set_title(title or head + "\n" + "\n".join(textwrap.wrap(sub, 110)), fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=8, frameon=False)
    return fig


# ------------------------------------------------------------------------------------------------------
# tables and the report
# ------------------------------------------------------------------------------------------------------

def _ci_method(rows) -> str:
    return next((r.fit.ci_method for r in rows if r.fit.ci_method), "profile likelihood")


def _cell(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return "inf" if math.isinf(v) else f"{v:.4g}"
    return str(v)


def table_lines(rows: list[FragilityRow]) -> list[str]:
    """The fragility table as aligned text lines (a header, one line per row; notes after the table)."""
    if not rows:
        return []
    dicts = [r.as_dict() for r in rows]
    cols = [c for c in dicts[0] if c not in ("note", "level")]
    cells = [[_cell(d[c]) for c in cols] for d in dicts]
    width = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(cols)]
    out = ["  ".join(c.rjust(w) for c, w in zip(cols, width))]
    out += ["  ".join(v.rjust(w) for v, w in zip(row, width)) for row in cells]
    for k, d in enumerate(dicts, 1):
        if d["note"]:
            out.append(f"row {k}: {d['note']}")
    return out


def write_table_csv(rows, path) -> Path:
    """Write the fragility table (:class:`FragilityRow` objects or their ``as_dict()``) to ``path`` (CSV;
    an empty cell for a value a non-identifiable fit has not); return the path."""
    dicts = [r.as_dict() if isinstance(r, FragilityRow) else dict(r) for r in rows]
    path = Path(path)
    cols = list(dicts[0]) if dicts else []
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for d in dicts:
            w.writerow({k: ("" if v is None else repr(v) if isinstance(v, float) else v) for k, v in d.items()})
    return path


def status_lines(ds) -> list[str]:
    """Counts of completed, collapsed and numerically failed runs (with the reasons of the latter)."""
    st = ds["status"].values.ravel()
    out = [f"runs: {st.size}: {int((st == STATUS_COMPLETED).sum())} completed, "
           f"{int((st == STATUS_COLLAPSE).sum())} collapsed (status 1), "
           f"{int((st == STATUS_NUMERICAL).sum())} failed numerically (status 2, excluded from the fits)"
           + (f", {int((st == STATUS_NOT_RUN).sum())} not run (status -1, excluded)" if (st == STATUS_NOT_RUN).any()
              else "")]
    if "status_reason" in ds and (st == STATUS_NUMERICAL).any():
        reasons = np.asarray(ds["status_reason"].broadcast_like(ds["status"]).values).ravel()[st == STATUS_NUMERICAL]
        values, counts = np.unique(reasons.astype(str), return_counts=True)
        for v, c in sorted(zip(values, counts), key=lambda t: -t[1]):
            out.append(f"  numerical failure x{c}: {v}")
    return out


def ensemble_report(ds, demand: str | None = None, limit: float | None = None, level: float = 0.9,
                    ida_demand: str | None = None):
    """``(lines, figures)``: the report of an ensemble dataset (or its netCDF path).

    lines: the dataset's shape and intensity measure, the run status counts, the definition of failure
    and the fragility table (:func:`table_lines`); figures: ``{"fragility": ..., "ida": ...}``
    (matplotlib Figures; the IDA curves of ``ida_demand``, default ``demand`` or
    :func:`default_demand`, left out when the dataset has no demand variable). Write the table as CSV
    with ``write_table_csv(fragility_table(ds, demand, limit, level), path)``."""
    ds = as_dataset(ds)
    check_ensemble_dataset(ds)
    rows = fragility_table(ds, demand, limit, level)
    scale, im_label = intensity_axis(ds)
    shape = [f"{ds.sizes['record']} records", f"{ds.sizes[INTENSITY_DIM]} intensities"]
    shape += [f"{ds.sizes[d]} values of {dim_key(ds, d)}" for d in parameter_dims(ds)]
    if "sample" in ds["status"].dims:
        shape.append(f"{ds.sizes['sample']} samples")
    levels = ", ".join(f"{v * scale:.3g}" for v in np.unique(ds[INTENSITY_DIM].values))
    lines = ["ensemble: " + " x ".join(shape), f"intensity measure: {im_label}; levels {levels}"]
    lines += status_lines(ds)
    lines.append(failure_definition(ds, demand, limit))
    lines.append(f"lognormal fragility by maximum likelihood (Baker 2015, eq. 11), {100 * level:g} % intervals "
                 f"from the {_ci_method(rows)}; intensities in {intensity_units(ds) or '-'}")
    lines += table_lines(rows)
    figures = {"fragility": fragility_figure(ds, demand, limit, level, rows=rows)}
    which = ida_demand or demand or default_demand(ds)
    if which is not None:
        figures["ida"] = ida_figure(ds, which)
    return lines, figures
