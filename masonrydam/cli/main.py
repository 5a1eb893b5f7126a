"""``masonrydam`` command line.

    masonrydam run SCENE.toml -o OUT.nc      run a scene, print a summary, write netCDF
    masonrydam run --default -o OUT.nc       run the bundled default scene
    masonrydam check SCENE.toml              validate a scene and build its model, without solving
    masonrydam export-mesh SCENE.toml -o M.vtu   write the scene's mesh (units and joints) for ParaView
    masonrydam records list                  the bundled ground-motion records
    masonrydam records show NAME [-o PNG]    a record's measures (PGA, PGV, PGD, Arias, D5-95, CAV) and plot
    masonrydam plot OUT.nc [--nodes N ..] [--joints J ..] -o PNG   histories from a result file
    masonrydam plot OUT.nc --mode N [--scale S] -o PNG   mode shape N of a result with a modal stage
    masonrydam plot OUT.nc --deformed [--step N] [--scale S] -o PNG   deformed blocks and joint states (2D)
    masonrydam assess OUT.nc [--step N] [--condition C] [--csv F]  stability of the joint lines (dams)
"""
from __future__ import annotations

import argparse
import os
import sys
import warnings
from importlib import resources
from pathlib import Path

from ..errors import MasonrydamError, RunStopped


def default_scene_path() -> Path:
    return Path(str(resources.files("masonrydam") / "scenes" / "wall_push.toml"))


def _scene_arg(args):
    if getattr(args, "default", False) or args.scene is None:
        return default_scene_path()
    return Path(args.scene)


def _cmd_run(args):
    from ..results.files import check_output_path
    from ..scene.run import run

    from ..scene.scene import with_overrides

    scene = _scene_arg(args)
    out = check_output_path(args.output or (scene.stem + ".nc"), "-o")
    run(with_overrides(scene, args.set), output=out, progress=not args.no_progress, summary=True)
    return 0


def _cmd_check(args):
    from ..scene.build import build_mesh, build_model, build_stages, effects
    from ..scene.scene import Scene
    from ..solvers.static import check_mechanisms

    sc = Scene.from_toml(_scene_arg(args))
    mesh = build_mesh(sc.normalized, sc.base_dir)
    model = build_model(sc.normalized, mesh)
    stages = build_stages(sc.normalized, mesh, model, sc.base_dir)
    check_mechanisms(model, stages)  # the solver's own check before each static stage (MechanismError)
    print(f"scene '{sc.name}' is valid: {model.n_nodes} nodes, {model.n_dof} DOFs, "
          f"{mesh.n_elements()} elements, {mesh.n_interfaces()} interfaces")
    for e in effects(sc.normalized, model):
        print("  effect:", e)
    return 0


def _cmd_export(args):
    from ..mesh.io import check_mesh_output, write_mesh
    from ..scene.build import build_mesh
    from ..scene.scene import Scene

    check_mesh_output(args.output, "-o")  # an extension meshio writes, an existing folder: before any work
    sc = Scene.from_toml(_scene_arg(args))
    mesh = build_mesh(sc.normalized, sc.base_dir)
    write_mesh(mesh, args.output)
    print(f"wrote {args.output}: {mesh.n_elements()} elements, {mesh.n_interfaces()} interfaces")
    return 0


def _cmd_records(args):
    from .. import records as rec

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
    from ..records.plotting import plot_record
    from ..results.files import check_output_path

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
    """Time histories (dynamic results) or step histories (static results) of a result file, as PNG
    (:func:`history_figure`); with ``--mode N`` the mode shape N of a result with a modal stage
    (:func:`masonrydam.results.mode_plot.mode_figure`); with ``--deformed`` the deformed blocks and joint
    states of one step (:func:`masonrydam.results.deformed.deformed_figure`)."""
    from ..results.files import check_output_path, open_result

    path = Path(args.result)
    if args.deformed:
        for opt, given in (("pushover", args.pushover), ("mode", args.mode is not None)):
            if given:
                raise MasonrydamError(f"--deformed and --{opt} draw different figures: give one of them")
        for opt in ("nodes", "joints", "component"):
            if getattr(args, opt) is not None:
                raise MasonrydamError(f"--{opt} applies to histories, not to the deformed shape (--deformed)")
        from ..results.deformed import deformed_figure

        out = check_output_path(args.output or f"{path.stem}_deformed.png", "-o")
        fig = deformed_figure(open_result(path), step=args.step, scale=args.scale, title=path.name)
        fig.savefig(out, dpi=110)
        print(f"wrote {out}")
        return 0
    if args.step is not None:
        raise MasonrydamError("--step applies to the deformed shape; give --deformed as well")
    if args.pushover and args.mode is not None:
        raise MasonrydamError("--pushover and --mode draw different figures: give one of them")
    if args.pushover:
        for opt in ("nodes", "joints", "scale"):
            if getattr(args, opt) is not None:
                raise MasonrydamError(f"--{opt} does not apply to a pushover curve (--pushover)")
        from ..results.files import check_output_path, open_result
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
    default = f"{path.stem}.png" if args.mode is None else f"{path.stem}_mode{args.mode}.png"
    out = check_output_path(args.output or default, "-o")
    ds = open_result(path)  # an incomplete result warns (one line on the command line)
    if args.mode is not None:
        from ..results.mode_plot import mode_figure

        fig = mode_figure(ds, args.mode, scale=args.scale, title=path.name)
    else:
        fig = history_figure(ds, path.name, args.component or "x", args.nodes, args.joints)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    return 0


def _cmd_assess(args):
    """Stability table of the joint lines of a result with a reservoir, at one step, against the criteria
    of a load condition (:func:`masonrydam.results.assess.assessment_report`); exit code 0 whether or not
    the sections meet them."""
    from ..results import assess
    from ..results.files import check_output_path, open_result

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


#: energy terms drawn by ``masonrydam plot`` (those that are not zero throughout)
PLOTTED_ENERGIES = ("input", "external", "kinetic", "strain", "damping", "joint_stored", "joint_friction",
                    "joint_bond_break", "joint_contact", "numerical", "error")


def history_figure(ds, title: str, comp: str = "x", nodes=None, joints=None):
    """The figure of ``masonrydam plot`` (a matplotlib Figure, not drawn to screen): ground acceleration
    (dynamic results), relative displacement of ``nodes`` (node numbers; default: the recorded node that
    moves most) in component ``comp``, slip and opening of the ``joints`` (joint point indices; default:
    the one that slips most) and the energy balance (the terms of :data:`PLOTTED_ENERGIES` that are not
    zero throughout), against time (dynamic) or the step number (static). Errors name the bad option."""
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if not ds.sizes["step"]:
        raise MasonrydamError(f"'{title}' has no steps to plot (status '{ds.attrs.get('status', '?')}': the run "
                              "stopped before its first converged step)")
    if comp not in ds.component.values:
        raise MasonrydamError(f"--component must be one of {list(ds.component.values)}, got {comp!r}")
    dynamic = "time" in ds.variables and np.isfinite(ds.time.values).any()
    if dynamic:
        ds = ds.isel(step=np.nonzero(np.isfinite(ds.time.values))[0])
        x, xlabel = ds.time.values, "time [s]"
    else:
        x, xlabel = np.arange(ds.sizes["step"]), "step"
    u = ds.displacement.sel(component=comp)
    if nodes:
        pos = []
        for n in nodes:
            hit = np.nonzero(ds.node.values == n)[0]
            if not len(hit):
                raise MasonrydamError(f"--nodes: node {n} is not in the file (recorded nodes: "
                                      f"{ds.node.values[:10].tolist()}{' ...' if ds.sizes['node'] > 10 else ''})")
            pos.append(int(hit[0]))
    else:
        pos = [int(np.argmax(np.abs(u.values).max(axis=0)))] if ds.sizes["node"] else []
    njp = ds.sizes.get("joint_point", 0)
    if joints:
        bad = [j for j in joints if not 0 <= j < njp]
        if bad:
            raise MasonrydamError(f"--joints: joint point(s) {bad} not in the file (0 to {njp - 1})")
        jpos = list(joints)
    elif njp:
        jpos = [int(np.argmax(np.abs(ds.joint_slip.values).max(axis=(0, 2))))]
    else:
        jpos = []
    panels = (["ground"] if dynamic else []) + ["disp"] + (["joint"] if jpos else []) + (["energy"] if dynamic else [])
    fig = Figure(figsize=(8.0, 2.6 * len(panels)), layout="constrained")
    FigureCanvasAgg(fig)
    axs = fig.subplots(len(panels), 1, squeeze=False)[:, 0]
    for ax, kind in zip(axs, panels):
        if kind == "ground":
            for c in ds.component.values:
                ax.plot(x, ds.ground_acceleration.sel(component=c).values, lw=0.8, label=f"a_g,{c}")
            ax.set_ylabel("ground acc. [m/s2]")
        elif kind == "disp":
            for p in pos:
                ax.plot(x, u.values[:, p], lw=0.8, label=f"node {int(ds.node.values[p])}")
            ax.set_ylabel(f"u_{comp} [m]" + (" (relative)" if dynamic else ""))
        elif kind == "joint":
            for j in jpos:
                ax.plot(x, ds.joint_slip.values[:, j, 0], lw=0.8, label=f"slip, point {j}")
                ax.plot(x, ds.joint_opening.values[:, j], lw=0.8, ls="--", label=f"opening, point {j}")
            ax.set_ylabel("joint [m]")
        else:
            for name in PLOTTED_ENERGIES:
                v = ds.get(f"energy_{name}")
                if v is not None and np.abs(v.values).max() > 0:
                    ax.plot(x, v.values, lw=0.8, label=name)
            ax.set_ylabel("energy [J]")
        ax.set_xlabel(xlabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(f"{title}: {ds.attrs.get('scene_name', '')} (completed = {ds.attrs.get('completed', '?')})")
    return fig


def main(argv=None) -> int:
    from .._version import __version__

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
    c.set_defaults(func=_cmd_check)
    e = sub.add_parser("export-mesh", help="write the scene's mesh (meshio formats: .vtu, .msh, .xdmf)")
    e.add_argument("scene", nargs="?")
    e.add_argument("--default", action="store_true")
    e.add_argument("-o", "--output", required=True)
    e.set_defaults(func=_cmd_export)
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
    pl = sub.add_parser("plot", help="plot histories (or, with --mode, a mode shape; with --pushover, the pushover "
                                     "curve; with --deformed, the deformed shape) from a result file (netCDF) to PNG")
    pl.add_argument("result", help="result file written by `masonrydam run`")
    pl.add_argument("--nodes", type=int, nargs="+", help="node numbers, as in the file's node coordinate (default: the recorded node that moves most)")
    pl.add_argument("--joints", type=int, nargs="+", help="joint point indices along joint_point (default: the one that slips most)")
    pl.add_argument("--component", help="displacement component (default x)")
    pl.add_argument("--mode", type=int, metavar="N",
                    help="draw mode shape N (1-based, as the file's mode coordinate) of a result with a modal "
                         "stage instead of the histories: undeformed nodes and joints grey, deformed nodes "
                         "coloured; 3D results in a 3D view")
    pl.add_argument("--pushover", action="store_true",
                    help="draw the pushover curve of a static result: the force on the DOFs a stage drives by "
                         "prescribed displacements against their displacement (--component, default x)")
    pl.add_argument("--deformed", action="store_true",
                    help="draw the deformed blocks and the joints of one step (2D results): stick grey, slip "
                         "orange, open red (wider the more open), crushed purple, with the count of each state")
    pl.add_argument("--step", type=int, metavar="N",
                    help="with --deformed: step, as in the file's step coordinate; negative: from the end "
                         "(default: the last step)")
    pl.add_argument("--scale", type=float, metavar="S",
                    help="with --mode: drawn displacement = S x mass-normalised shape (default: the largest "
                         "displacement is 10 %% of the model's largest extent); with --deformed: drawn "
                         "displacement = S x displacement (default: the largest is 5 %% of the extent)")
    pl.add_argument("-o", "--output", help="PNG file (default: RESULT.png, with --mode N RESULT_modeN.png, "
                                           "with --deformed RESULT_deformed.png, in the current folder)")
    pl.set_defaults(func=_cmd_plot)
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
    args = p.parse_args(argv)
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
