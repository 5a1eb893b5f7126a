"""``masonrydam`` command line.

    masonrydam run SCENE.toml -o OUT.nc [--set KEY=VALUE ..]   run a scene, print a summary, write netCDF
    masonrydam run --default -o OUT.nc       run the bundled default scene
    masonrydam check SCENE.toml [--set KEY=VALUE ..]   validate a scene and build its model, without solving
    masonrydam export-mesh SCENE.toml -o M.vtu   write the scene's mesh (units and joints) for ParaView
    masonrydam export-results OUT.nc -o R.xdmf|R.pvd [--joints V] [--every K]   results as a ParaView time series
    masonrydam records list                  the bundled ground-motion records
    masonrydam records show NAME [-o PNG]    a record's measures (PGA, PGV, PGD, Arias, D5-95, CAV) and plot
    masonrydam plot OUT.nc [--nodes N ..] [--joints J ..] -o PNG   histories (a static push: its pushover curve)
    masonrydam plot OUT.nc --quantity VAR [--select DIM=VALUE ..] -o PNG   history of one variable
    masonrydam plot OUT.nc --mode N [--scale S] -o PNG   mode shape N of a result with a modal stage
    masonrydam plot OUT.nc --deformed [--step N] [--scale S] [--slice y=V] -o PNG   deformed blocks, joint states
    masonrydam assess OUT.nc [--step N] [--condition C] [--csv F]  stability of the joint lines (dams)
    masonrydam ensemble ENSEMBLE.toml -o ENS.nc [--workers N]   records x intensities x parameters on dask, resumable
    masonrydam ensemble-report ENS.nc [--demand VAR --limit X]   IDA and fragility curves of an ensemble
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from importlib import resources
from pathlib import Path

from .. import IMPORTED_AT
from .._version import __version__
from ..errors import MasonrydamError, RunStopped

# Each command imports what it needs (numpy, xarray, numba, the solvers, the scene) inside its function, so that
# `masonrydam --version` and `--help` answer in the interpreter's start-up time instead of a second or more.


#: when this run started (perf_counter seconds): the package's first import, the clock of a command-line run's
#: summary (:data:`masonrydam.IMPORTED_AT`)
PROCESS_START = IMPORTED_AT


def default_scene_path() -> Path:
    return Path(str(resources.files("masonrydam") / "scenes" / "wall_push.toml"))


def _scene_arg(args):
    if getattr(args, "default", False) or args.scene is None:
        return default_scene_path()
    return Path(args.scene)


def _cmd_run(args):
    from ..checks import check_output_path
    from ..scene import run
    from ..scene.scene import with_overrides

    scene = _scene_arg(args)
    out = check_output_path(args.output or (scene.stem + ".nc"), "-o")
    # the summary's wall time is the whole process's (imports and reading the result back included)
    run(with_overrides(scene, args.set), output=out, progress=not args.no_progress, summary=True,
        started=args.started)
    return 0


def check_scene(scene) -> list[str]:
    """What ``masonrydam check`` does with ``scene`` (a :class:`~masonrydam.scene.Scene`, a dict or a TOML path):
    validate it, build its mesh, model and stages and the solver's mechanism check, nothing solved; returns the
    lines it prints. Raises what the run would raise before its first step."""
    from ..scene import build_mesh, build_model, build_stages, effects
    from ..scene.recording import output_selection
    from ..scene.scene import as_scene
    from ..solvers.static.stepping import check_mechanisms

    sc = as_scene(scene)
    mesh = build_mesh(sc.normalized, sc.base_dir)
    model = build_model(sc.normalized, mesh)
    stages = build_stages(sc.normalized, mesh, model, sc.base_dir)
    output_selection(sc.normalized, mesh, model)  # the recorded node and joint sets exist
    check_mechanisms(model, stages)  # the solver's own check before each static stage (MechanismError)
    return ([f"scene '{sc.name}' is valid: {model.n_nodes} nodes, {model.n_dof} DOFs, "
             f"{mesh.n_elements()} elements, {mesh.n_interfaces()} interfaces"]
            + [f"  effect: {e}" for e in effects(sc.normalized, model)])


def _cmd_check(args):
    from ..scene import Scene
    from ..scene.scene import with_overrides

    for line in check_scene(with_overrides(Scene.from_toml(_scene_arg(args)), args.set)):
        print(line)
    return 0


def _cmd_export(args):
    from ..mesh.io import check_mesh_output, write_mesh
    from ..scene import Scene, build_mesh

    check_mesh_output(args.output, "-o")  # an extension meshio writes, an existing folder: before any work
    sc = Scene.from_toml(_scene_arg(args))
    mesh = build_mesh(sc.normalized, sc.base_dir)
    write_mesh(mesh, args.output)
    print(f"wrote {args.output}: {mesh.n_elements()} elements, {mesh.n_interfaces()} interfaces")
    return 0


def _cmd_export_results(args):
    """A result file as a ParaView time series: ``.xdmf`` (+ ``.h5``) or ``.pvd`` (+ one ``.vtu`` per step),
    with ``OUT.units.json`` beside it (:func:`masonrydam.results.paraview.export_results`)."""
    # the ParaView export (meshio, h5py) only for this command: keeps 'masonrydam run' start-up short
    from ..checks import check_output_path
    from ..results import paraview
    from ..results.files import open_result

    path = Path(args.result)
    out = check_output_path(args.output or f"{path.stem}.xdmf", "-o")
    paraview.check_options(out, args.joints, args.every, args.steps, args.time)  # before any work
    s = paraview.export_results(open_result(path), out, joints=args.joints, every=args.every, steps=args.steps,
                                time=args.time, source=str(path))
    unit = "s" if s.time_unit == "s" else "(step numbers)"
    print(f"wrote {out}: {len(s.steps)} steps, time {s.times[0]:g} to {s.times[-1]:g} {unit}; {s.n_points} points, "
          f"{s.n_block_cells} block cells, {s.n_joint_cells} interface cells (joints drawn {args.joints}; the mesh "
          "undeformed: Warp By Vector)")
    left = s.left_out
    if left.get("block_cells") or left.get("joint_elements"):
        print(f"  left out (nodes not recorded): {left['block_cells']} block cells, {left['joint_elements']} "
              "interface elements")
    if left.get("nodes_without_cell"):
        print(f"  {left['nodes_without_cell']} recorded nodes in no cell are points without a cell in XDMF; "
              "export to .pvd to see them")
    if left.get("static_steps"):
        print(f"  left out: {left['static_steps']} static step(s) (no time; --time step keeps them)")
    print(f"  units of the fields: {paraview.units_path(out)}")
    return 0


def _cmd_records(args):
    # obspy only for the records command: keeps 'masonrydam run' start-up short
    from .. import records as rec
    from ..checks import check_output_path
    from ..records.plotting import plot_record

    if args.records_command == "list":
        rows = []
        for e in rec.list_records():
            peak, unit = rec.catalog.peak_value(e)
            pga = f"{peak:.4f}" if unit == "g" else f"- (displacement, PGD {peak:.2f} cm)"
            rows.append((e["name"], e["event"], e["station"], str(e["component"]), str(e["npts"]),
                         f"{e['dt']:g}", pga))
        head = ("name", "event", "station", "comp.", "npts", "dt [s]", "PGA [g]")
        widths = [max(len(r[k]) for r in rows + [head]) for k in range(len(head))]
        for r in [head] + rows:
            print("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
        return 0
    name = args.name
    out = check_output_path(args.output or f"{Path(name).stem}.png", "-o")
    if name in rec.record_names() or not Path(name).is_file():
        for opt in ("format", "units", "dt", "column"):
            if getattr(args, opt) is not None and name in rec.record_names():
                raise MasonrydamError(f"--{opt} applies to a record file; {name!r} is a bundled record (it knows it)")
        tr = rec.load_record(name)
    else:  # errors name the command-line options (--units, --dt, --column), not the Python arguments
        tr = rec.read_trace(name, format=args.format, units=args.units, dt=args.dt, column=args.column,
                            option_names=rec.readers.CLI_OPTION_NAMES)
    m = rec.summary(tr)
    meta = tr.stats.masonrydam
    print(f"{name}: {meta.get('event', '?')}, {meta.get('station', '?')}, component {meta.get('component', '?')}")
    print(f"  npts {m['npts']}, dt {m['dt']:g} s, duration {m['duration']:.2f} s")
    print(f"  PGA    {m['pga']:.4g} m/s2 ({m['pga'] / rec.G:.4f} g)")
    print(f"  PGV    {m['pgv']:.4g} m/s")
    print(f"  PGD    {m['pgd']:.4g} m  (velocity/displacement: trapezoidal integration of the record as given)")
    print(f"  Arias  {m['arias_intensity']:.4g} m/s")
    print(f"  D5-95  {m['d5_95']:.3f} s  ({m['t5']:.2f} s to {m['t95']:.2f} s)")
    print(f"  CAV    {m['cav']:.4g} m/s")
    plot_record(tr, out, damping=args.damping, title=f"{name} ({100 * args.damping:g} % damping)")
    print(f"wrote {out}")
    return 0


def _cmd_plot(args):
    """The default figure of a result file, as PNG (:func:`masonrydam.results.histories.default_figure`):
    time histories (dynamic results), the pushover curve (static results with prescribed displacements) or histories
    against the load factor (other static results); with ``--quantity VAR [--select DIM=VALUE ...]`` the
    history of one variable (:func:`masonrydam.results.histories.quantity_figure`); with ``--pushover`` the
    pushover curve; with ``--mode N`` the mode shape N of a result with a modal stage
    (:func:`masonrydam.results.mode_plot.mode_figure`); with ``--deformed`` the deformed blocks and joint
    states of one step (:func:`masonrydam.results.deformed.deformed_figure`)."""
    from ..checks import check_output_path
    from ..results.files import open_result

    path = Path(args.result)
    quantity, select = getattr(args, "quantity", None), getattr(args, "select", None)
    chosen = [opt for opt, given in (("deformed", args.deformed), ("pushover", args.pushover),
                                      ("mode", args.mode is not None), ("quantity", quantity is not None)) if given]
    if len(chosen) > 1:
        raise MasonrydamError(f"--{chosen[0]} and --{chosen[1]} draw different figures: give one of them")
    if select and quantity is None:
        raise MasonrydamError("--select applies to --quantity VAR; give --quantity as well")
    if args.deformed:
        for opt in ("nodes", "joints", "component"):
            if getattr(args, opt) is not None:
                raise MasonrydamError(f"--{opt} applies to histories, not to the deformed shape (--deformed)")
        # figure modules only for the plot command: keeps 'masonrydam run' start-up short
        from ..results.deformed import deformed_figure

        out = check_output_path(args.output or f"{path.stem}_deformed.png", "-o")
        fig = deformed_figure(open_result(path), step=args.step, scale=args.scale, title=path.name,
                              slice=args.slice)
        fig.savefig(out, dpi=110)
        print(f"wrote {out}")
        return 0
    if args.step is not None:
        raise MasonrydamError("--step applies to the deformed shape; give --deformed as well")
    if args.slice is not None:
        raise MasonrydamError("--slice applies to the deformed shape of a 3D result; give --deformed as well")
    if args.pushover:
        for opt in ("nodes", "joints", "scale"):
            if getattr(args, opt) is not None:
                raise MasonrydamError(f"--{opt} does not apply to a pushover curve (--pushover)")
        # figure modules only for the plot command: keeps 'masonrydam run' start-up short
        from ..results.pushover import pushover_figure

        out = check_output_path(args.output or f"{path.stem}_pushover.png", "-o")
        fig = pushover_figure(open_result(path), args.component or "x", title=path.name)
        fig.savefig(out, dpi=110)
        print(f"wrote {out}")
        return 0
    if args.mode is None and args.scale is not None:
        raise MasonrydamError("--scale applies to a mode shape or the deformed shape; give --mode N or --deformed "
                              "as well")
    if args.mode is not None:
        for opt in ("nodes", "joints", "component"):
            if getattr(args, opt) is not None:
                raise MasonrydamError(f"--{opt} applies to histories, not to a mode shape (--mode)")
    if quantity is not None:
        for opt, dim in (("nodes", "node"), ("joints", "joint_point"), ("component", "component")):
            if getattr(args, opt) is not None:
                raise MasonrydamError(f"--{opt} applies to the default histories; with --quantity select with "
                                      f"--select {dim}=VALUE")
    if args.mode is not None:
        default = f"{path.stem}_mode{args.mode}.png"
    elif quantity is not None:
        default = f"{path.stem}_{quantity}.png"
    else:
        default = f"{path.stem}.png"
    out = check_output_path(args.output or default, "-o")
    ds = open_result(path)  # an incomplete result warns (one line on the command line)
    if args.mode is not None:
        # figure modules only for the plot command: keeps 'masonrydam run' start-up short
        from ..results.mode_plot import mode_figure

        fig = mode_figure(ds, args.mode, scale=args.scale, title=path.name)
    elif quantity is not None:
        # figure modules only for the plot command: keeps 'masonrydam run' start-up short
        from ..results.histories import parse_selection, quantity_figure

        fig = quantity_figure(ds, quantity, parse_selection(select), title=path.name)
    else:
        # figure modules only for the plot command: keeps 'masonrydam run' start-up short
        from ..results.histories import default_figure

        fig = default_figure(ds, path.name, args.component, args.nodes, args.joints)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    return 0


def _cmd_ensemble(args):
    """Run an ensemble file on dask (:func:`masonrydam.ensemble.runner.run_ensemble`): members already in the
    store beside the output are not run again."""
    # the ensemble room only for the ensemble commands: keeps 'masonrydam run' start-up short
    from ..checks import check_output_path
    from ..ensemble.runner import run_ensemble

    path = Path(args.ensemble)
    out = check_output_path(args.output or f"{path.stem}.nc", "-o")
    if args.workers is not None and args.workers < 1:
        raise MasonrydamError(f"--workers must be at least 1, got {args.workers}")
    ds = run_ensemble(path, out, workers=args.workers, scheduler=args.scheduler, progress=not args.no_progress)
    status = ds.status.values
    print(f"ensemble '{path.name}': {status.size} members, {int((status == 0).sum())} completed, "
          f"{int((status == 1).sum())} collapsed, {int((status == 2).sum())} numerical failures; "
          f"{ds.attrs['wall_time_s']:.1f} s on {ds.attrs['workers']} worker(s)")
    print(f"wrote {out} (members' outcomes in {out}.members/)")
    return 0


def _cmd_ensemble_report(args):
    """IDA curves and lognormal fragility curves of an ensemble dataset, as figures and a table
    (:func:`masonrydam.ensemble.report.ensemble_report`)."""
    # scipy.stats (a second to import) only for the ensemble report: keeps 'masonrydam run' start-up short
    import xarray as xr

    from ..ensemble.fragility import fragility_table
    from ..ensemble.report import ensemble_report, write_table_csv

    path = Path(args.result)
    if not path.exists():
        raise MasonrydamError(f"{path}: no such ensemble file")
    with xr.open_dataset(path) as ds:
        ds = ds.load()
    if args.demand is not None and args.demand not in ds.data_vars:
        raise MasonrydamError(f"--demand {args.demand!r}: not a variable of the ensemble (demands: "
                              f"{sorted(v for v in ds.data_vars if v not in ('status', 'status_reason', 'wall_time'))})")
    if args.limit is not None and args.demand is None:
        raise MasonrydamError("--limit needs --demand: the demand whose value above the limit is a failure")
    # --demand alone: the IDA curves of that demand, failure = collapse; with --limit: failure = demand > limit
    failure_demand = args.demand if args.limit is not None else None
    lines, figures = ensemble_report(ds, failure_demand, args.limit, level=args.level, ida_demand=args.demand)
    print("\n".join(lines))
    prefix = Path(args.output) if args.output else path.with_suffix("")
    for name, fig in figures.items():
        target = prefix.with_name(f"{prefix.name}_{name}.png")
        fig.savefig(target, dpi=110)
        print(f"wrote {target}")
    table = prefix.with_name(f"{prefix.name}_fragility.csv")
    write_table_csv(fragility_table(ds, failure_demand, args.limit, level=args.level), table)
    print(f"wrote {table}")
    return 0


def _cmd_assess(args):
    """Stability table of the joint lines of a result with a reservoir, at one step, against the criteria
    of a load condition (:func:`masonrydam.results.assess.assessment_report`); exit code 0 whether or not
    the sections meet them."""
    # the stability assessment only for this command: keeps 'masonrydam run' start-up short
    from ..checks import check_output_path
    from ..results import assess
    from ..results.files import open_result

    path = Path(args.result)
    csv_out = check_output_path(args.csv, "--csv") if args.csv else None
    ds = open_result(path)  # an incomplete result warns (one line on the command line)
    i = assess.select_step(ds, args.step, path.name)
    lines, _ = assess.assessment_report(ds, i, args.condition, path.name)
    print("\n".join(lines))
    if args.all_steps:
        print()
        print("\n".join(assess.over_steps_report(ds, args.condition)))
    if csv_out is not None:
        assess.write_assessment_csv(ds, i, csv_out, args.condition)
        print(f"wrote {csv_out}")
    return 0


def history_figure(ds, title: str, comp: str = "x", nodes=None, joints=None):
    """The history figure of ``masonrydam plot``: :func:`masonrydam.results.histories.history_figure`
    (kept under this name for callers that import it from the command line module)."""
    # figure modules only for the plot command: keeps 'masonrydam run' start-up short
    from ..results.histories import history_figure as figure

    return figure(ds, title, comp, nodes, joints)


def build_parser() -> argparse.ArgumentParser:
    """The command line's parser, with every command and option (the docs' check of the flags they name reads it)."""
    p = argparse.ArgumentParser(prog="masonrydam", description="Nonlinear analysis of jointed masonry and block dams")
    p.add_argument("--version", action="version", version=f"masonrydam {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a scene and write results to netCDF")
    r.add_argument("scene", nargs="?", help="scene TOML file (default: the bundled wall_push scene)")
    r.add_argument("--default", action="store_true", help="run the bundled default scene")
    r.add_argument("-o", "--output", help="output netCDF file (default: SCENE.nc in the current folder)")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a scene key for this run, e.g. --set 'stages[0].loads[1].pressure=1.21 MPa' "
                        "(dotted names, list indices from 0; repeatable)")
    r.set_defaults(func=_cmd_run)
    c = sub.add_parser("check", help="validate a scene and build its model without solving")
    c.add_argument("scene", nargs="?")
    c.add_argument("--default", action="store_true")
    c.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a scene key before checking, as for run")
    c.set_defaults(func=_cmd_check)
    e = sub.add_parser("export-mesh", help="write the scene's mesh (meshio formats: .vtu, .msh, .xdmf)")
    e.add_argument("scene", nargs="?")
    e.add_argument("--default", action="store_true")
    e.add_argument("-o", "--output", required=True)
    e.set_defaults(func=_cmd_export)
    ex = sub.add_parser("export-results", help="write a result file (netCDF) as a ParaView time series: .xdmf "
                                                "(+ .h5) or .pvd (+ one .vtu per step)",
                         description="Blocks and interface elements with the nodal fields (displacement, "
                                     "velocity, ...) and the element and joint fields of each step, on the "
                                     "undeformed mesh (apply Warp By Vector with 'displacement' in ParaView); "
                                     "units in OUT.units.json beside the output (docs/paraview.md).")
    ex.add_argument("result", help="result file written by `masonrydam run`")
    ex.add_argument("-o", "--output", help="OUT.xdmf (XDMF + HDF5 OUT.h5) or OUT.pvd (collection + "
                                            "OUT_<step>.vtu) (default: RESULT.xdmf in the current folder)")
    ex.add_argument("--joints", default="deformed", metavar="VIEW",
                     help="interface cells: deformed (on the blocks' nodes: warped, they show the gap and slip), "
                          "shrunk (own nodes moved toward each cell's centroid to 0.8 of their distance, so "
                          "neighbouring joint elements show as separate strips), or both (default deformed)")
    ex.add_argument("--every", type=int, default=1, metavar="K",
                     help="keep every K-th step (and the last one) (default 1: all)")
    ex.add_argument("--steps", metavar="A:B", help="steps numbered A (included) to B (excluded), as a Python "
                                                    "slice; either may be empty, negative from the end")
    ex.add_argument("--time", default="auto", metavar="T",
                     help="time values: auto (dynamic results: the time in s, static steps left out; static "
                          "results: the step number) or step (the step number, every step kept) (default auto)")
    ex.set_defaults(func=_cmd_export_results)
    rc = sub.add_parser("records", help="the bundled ground-motion records: list them, show one")
    rsub = rc.add_subparsers(dest="records_command", required=True)
    rsub.add_parser("list", help="table of the bundled records")
    rs = rsub.add_parser("show", help="print a record's measures and plot it to PNG")
    rs.add_argument("name", help="record name from `masonrydam records list`, or a record file (PEER AT2, SAC, "
                                 "MiniSEED, text: header lines, an optional time column, value columns)")
    rs.add_argument("-o", "--output", help="PNG file (default: NAME.png in the current folder)")
    rs.add_argument("--damping", type=float, default=0.05, help="damping ratio of the spectrum (default 0.05)")
    rs.add_argument("--format", help="format of a record file (AT2, TEXT, or an obspy format such as SAC, MSEED)")
    rs.add_argument("--units", help="units of the values in a record file whose header does not state them "
                                    "(g, m/s2, cm/s2, gal); checked against the header where it does")
    rs.add_argument("--dt", type=float, help="time step (s) of a text file without a time column; checked "
                                             "against the time column where there is one")
    rs.add_argument("--column", type=int, help="which value column of a text file with several, counted from 0 "
                                               "without the time column (or which trace of a SAC/MiniSEED file)")
    rc.set_defaults(func=_cmd_records)
    pl = sub.add_parser("plot", help="plot histories (a static result with prescribed displacements: its pushover "
                                     "curve; with --quantity, one variable; with --mode, a mode shape; with "
                                     "--deformed, the deformed shape) from a result file (netCDF) to PNG",
                        description="Without options: time histories of a dynamic result (ground acceleration at "
                                    "the record's own rate, displacement, joint slip and opening, energies); the "
                                    "pushover curve of a static result with prescribed displacements; else the "
                                    "histories against the load factor of the static stages.")
    pl.add_argument("result", help="result file written by `masonrydam run`")
    pl.add_argument("--nodes", type=int, nargs="+", help="node numbers, as in the file's node coordinate (default: the recorded node that moves most)")
    pl.add_argument("--joints", type=int, nargs="+", help="joint point indices along joint_point (default: the one "
                                                          "that slips most, or else opens most; 3D: |slip| and its "
                                                          "components)")
    pl.add_argument("--component", help="displacement component (default x; the default pushover curve: the "
                                         "component of the last driving stage)")
    pl.add_argument("--quantity", metavar="VAR",
                    help="draw the history of any step variable of the file instead (e.g. joint_opening, "
                         "displacement, energy_kinetic, ground_acceleration_record_x), against time (dynamic) "
                         "or the load factor (static); one line per value left after --select, at most 10")
    pl.add_argument("--select", nargs="+", action="extend", metavar="DIM=VALUE",
                    help="with --quantity: xarray-style selection by coordinate value (a position along a "
                         "dimension without one), e.g. --select joint_point=12, --select component=x node=27; "
                         "several values: node=27,28")
    pl.add_argument("--mode", type=int, metavar="N",
                    help="draw mode shape N (1-based, as the file's mode coordinate) of a result with a modal "
                         "stage instead of the histories: undeformed nodes and joints grey, deformed nodes "
                         "coloured; 3D results in a 3D view")
    pl.add_argument("--pushover", action="store_true",
                    help="draw the pushover curve of a static result: the force on the DOFs a stage drives by "
                         "prescribed displacements against their displacement (--component, default x)")
    pl.add_argument("--deformed", action="store_true",
                    help="draw the deformed blocks and the joints of one step (3D results: a slice, --slice): "
                         "stick grey, slip orange, open red (wider the more open), crushed purple, with the "
                         "count of each state")
    pl.add_argument("--slice", metavar="AXIS=VALUE",
                    help="with --deformed, 3D results: the plane the model is cut by, e.g. --slice y=0.05 (m); "
                         "drawn in the plane's other two axes (default: the mid-plane across the model's "
                         "thinnest extent, e.g. a wall's mid-thickness)")
    pl.add_argument("--step", type=int, metavar="N",
                    help="with --deformed: step, as in the file's step coordinate; negative: from the end "
                         "(default: the last step)")
    pl.add_argument("--scale", type=float, metavar="S",
                    help="with --mode: drawn displacement = S x mass-normalised shape (default: the largest "
                         "displacement is 10 %% of the model's largest extent); with --deformed: drawn "
                         "displacement = S x displacement (default: the largest is 5 %% of the extent)")
    pl.add_argument("-o", "--output", help="PNG file (default: RESULT.png, with --mode N RESULT_modeN.png, "
                                           "with --deformed RESULT_deformed.png, with --pushover "
                                           "RESULT_pushover.png, with --quantity VAR RESULT_VAR.png, in the "
                                           "current folder)")
    pl.set_defaults(func=_cmd_plot)
    en = sub.add_parser("ensemble", help="run an ensemble of a base scene (records x intensities x parameters) on "
                                         "dask; resumable")
    en.add_argument("ensemble", help="ensemble file (TOML): [ensemble] scene = ..., [axes.records], [axes.intensity], "
                                     "[[axes.parameters]]; docs/ensembles.md")
    en.add_argument("-o", "--output", help="ensemble dataset (netCDF; default ENSEMBLE.nc); the members' outcomes "
                                           "are kept in OUTPUT.members/ and reused by a second call")
    en.add_argument("--workers", type=int, help="local worker processes (default: the file's [execution] workers, "
                                                "else the CPU count)")
    en.add_argument("--scheduler", help="address of a running dask scheduler (tcp://host:8786) instead of a local "
                                        "cluster")
    en.add_argument("--no-progress", action="store_true", help="no progress line")
    en.set_defaults(func=_cmd_ensemble)
    er = sub.add_parser("ensemble-report", help="IDA and fragility curves of an ensemble dataset")
    er.add_argument("result", help="ensemble dataset written by `masonrydam ensemble`")
    er.add_argument("--demand", help="demand variable of the IDA curves (e.g. peak_slip_joints); with --limit also "
                                     "the failure criterion (default: failure = collapse)")
    er.add_argument("--limit", type=float, help="limit of the demand (SI units): a member above it has failed")
    er.add_argument("--level", type=float, default=0.9, help="confidence level of the intervals (default 0.9)")
    er.add_argument("-o", "--output", help="prefix of the figures and the table (default: the dataset's name)")
    er.set_defaults(func=_cmd_ensemble_report)
    a = sub.add_parser("assess", help="stability of a dam's joint lines (sliding, resultant, cracking) at one step",
                       description="Table of the stability sections (base and lift joints) of a result whose "
                                   "scene has a [reservoir], at one step, against the criteria of a load "
                                   "condition (USACE EM 1110-2-2100, 2005): '!' marks a failing value. Exit "
                                   "code 0 when the table is printed, whether or not the criteria are met; "
                                   "2 for a result without sections or a step not in the file.")
    a.add_argument("result", help="result file written by `masonrydam run`")
    a.add_argument("--step", type=int, help="step, as in the file's step coordinate; negative: from the end "
                                            "(default: the last step, -1)")
    a.add_argument("--condition", choices=["usual", "unusual", "extreme"], default="usual",
                   help="load condition whose criteria apply: sliding factor 1.5 / 1.3 / 1.1, resultant in the "
                        "middle third / middle half / the line (default usual)")
    a.add_argument("--csv", metavar="FILE", help="also write the table to FILE (SI units, full precision, flags)")
    a.add_argument("--all-steps", action="store_true", help="also print each section's lowest sliding factor "
                                                             "and largest cracked ratio over all steps, and where")
    a.set_defaults(func=_cmd_assess)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    # the console script: the clock of the summary starts with the process; a call from Python: with this call
    args.started = PROCESS_START if argv is None else time.perf_counter()
    code = _dispatch(args)
    if argv is None and args.command in QUICK_EXIT_COMMANDS:
        _quick_exit(code)
    return code


#: commands whose process, run as the console script, ends without the interpreter's teardown of its modules:
#: the teardown of numba, scipy, xarray and dask takes 0.3-0.4 s (Xeon) after the summary has been printed and
#: every file closed. The ensemble commands (dask's workers and threads) end the usual way.
QUICK_EXIT_COMMANDS = frozenset({"run", "check", "export-mesh", "export-results", "records", "plot", "assess"})


def _quick_exit(code: int) -> None:
    """End the process with ``code`` after the exit handlers (atexit) and the flushing of stdout and stderr,
    without the module teardown (``os._exit``). Our files are closed by then; what registered an exit handler
    (numba, HDF5, logging) still runs it."""
    import atexit

    run_exit_handlers = getattr(atexit, "_run_exitfuncs", None)  # CPython; elsewhere: the usual exit
    if run_exit_handlers is None:
        return
    run_exit_handlers()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: nothing more can be said on it
            pass
    os._exit(code)


def _dispatch(args) -> int:
    """Run the command of ``args``; errors are one line on stderr and an exit code."""
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning
            return args.func(args)
    except MasonrydamError as exc:
        print(f"masonrydam: error: {exc}", file=sys.stderr)
        for note in getattr(exc, "__notes__", []):
            print(f"masonrydam: {note}", file=sys.stderr)
        return 2
    except RunStopped as exc:  # Ctrl-C or SIGTERM during a run: the converged steps are kept
        print(f"masonrydam: {exc}", file=sys.stderr)
        for note in getattr(exc, "__notes__", []):
            print(f"masonrydam: {note}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:  # Ctrl-C outside a run's steps (reading, meshing, plotting): nothing is kept
        print("masonrydam: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the output went to a program that stopped reading (`| head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return 128 + 13  # as if killed by SIGPIPE, the shell's convention


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    """Warnings on the command line: one line each, without the source line that Python shows."""
    print(f"masonrydam: warning: {message}", file=sys.stderr if file is None else file)


if __name__ == "__main__":
    sys.exit(main())
