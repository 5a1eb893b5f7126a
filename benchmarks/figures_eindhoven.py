"""Figures of the Eindhoven wall J4D for docs/masonry_softening.md: the load-displacement curves of
examples/eindhoven_J4D.toml with the top beam held at its height (the reference loading) and free to rise
(constant vertical load), the crack patterns of the held wall at its first peak and at the end, and the
hysteresis of examples/eindhoven_J4D_cyclic.py.

    python benchmarks/figures_eindhoven.py [--out docs/figures]
    python benchmarks/figures_eindhoven.py --relaxed [--results DIR] [--out docs/figures]

Writes eindhoven_J4D_curves.png, eindhoven_J4D_cracks_peak.png, eindhoven_J4D_cracks_end.png,
eindhoven_J4D_cyclic.png, and for the higher precompressions of J6D and J7D eindhoven_walls_curves.png
(the three held walls at the example's relaxation time and at a tenth of it) and eindhoven_J6D_cracks_peak.png,
eindhoven_J6D_cracks_end.png, eindhoven_J7D_cracks_peak.png, eindhoven_J7D_cracks_end.png; prints the runs' figures (peak, plateau, wall time).

With ``--relaxed``, only the held walls J4D, J6D and J7D with the inviscid law relaxed past their limit points
(examples/eindhoven_walls.py, the converged curves): eindhoven_walls_relaxed_curves.png, with J4D's
regularised example curve for comparison, and eindhoven_<wall>_relaxed_cracks_peak.png and _end.png (at the
largest force and at 4 mm); ``--results DIR`` reads the walls' eindhoven_<wall>.nc written by that example instead
of running them (J4D, J6D and J7D take about 5.5, 12 and 19 minutes on one core).
"""
from __future__ import annotations

import argparse
import contextlib
import io
import time
from pathlib import Path

import numpy as np
from _common import example_module  # benchmarks/ is sys.path[0] when run as a script

import masonrydam
from masonrydam.results.deformed import deformed_figure
from masonrydam.results.pushover import pushover_data, pushover_figure, value_at_push
from masonrydam.scene.scene import Scene, set_key

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run(data, label):
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        ds = masonrydam.run(data)
    print(f"{label}: {time.perf_counter() - t0:.1f} s", flush=True)
    return ds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs" / "figures"))
    ap.add_argument("--relaxed", action="store_true", help="only the walls relaxed past their limit points")
    ap.add_argument("--results", help="with --relaxed: a folder with the walls' eindhoven_<wall>.nc to read")
    args = ap.parse_args(argv)
    out = Path(args.out)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if args.relaxed:
        _relaxed_walls(out, plt, None if args.results is None else Path(args.results))
        print(f"wrote the figures in {out}")
        return 0

    held = run(Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data, "J4D, top held")
    free = Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data
    set_key(free, "stages[1].loads[0].components", ["x"])
    set_key(free, "stages[1].loads[0].value", ["4 mm"])
    free = run(free, "J4D, constant vertical load")
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for ds, label in ((held, "top held at its height (reference loading)"), (free, "constant vertical load")):
        d, f, _ = pushover_data(ds)
        ax.plot(d * 1e3, f / 1e3, "-o", ms=2.5, lw=1.2, label=label)
        k = int(np.argmax(f))
        print(f"  {label}: peak {f[k] / 1e3:.2f} kN at {d[k] * 1e3:.2f} mm, end {f[-1] / 1e3:.2f} kN")
    ax.axhline(22.3, color="0.4", ls="--", lw=1, label="tan(phi) p A = 22.3 kN")
    _save_curves(fig, ax, "Eindhoven wall J4D, p = 0.30 MPa", out / "eindhoven_J4D_curves.png")
    _crack_figures(held, "J4D", out)
    _higher_precompressions(held, out, plt)
    cyc = run(example_module("eindhoven_J4D_cyclic").cyclic_scene(), "J4D cyclic, constant vertical load")
    fig = pushover_figure(cyc, "x", title="Eindhoven J4D, constant vertical load, cyclic push")
    fig.savefig(out / "eindhoven_J4D_cyclic.png", dpi=90)
    print(f"wrote the figures in {out}")
    return 0


#: the walls of the series besides J4D (J5D repeats J4D's 0.30 MPa): their precompressions (Raijmakers & Vermeltfoort 1992)
HIGHER_PRECOMPRESSIONS = {"J6D": "1.21 MPa", "J7D": "2.12 MPa"}


#: the relaxation time the walls' curves are drawn at besides the example's, a tenth of it (past 3 mm
#: the held walls' force depends on it; docs/masonry_softening.md)
FINER_RELAXATION_TIME = "0.00025 ms"


def _higher_precompressions(held_j4d, out, plt):
    """The example with the precompressions of J6D and J7D: the held walls' curves beside
    J4D's (eindhoven_walls_curves.png), at the example's relaxation time (solid) and at a tenth of it (dashed),
    and each wall's cracks at its peak (the force's first drop, or the end where it never drops) and at 4 mm
    (eindhoven_J6D_cracks_peak.png ...), at the example's relaxation time."""
    pressures = {"J4D": "0.30 MPa", **HIGHER_PRECOMPRESSIONS}

    def held_wall(wall, relaxation_time=None):
        data = Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data
        set_key(data, "stages[0].loads[1].pressure", pressures[wall])
        label = f"{wall}, top held, p = {pressures[wall]}"
        if relaxation_time is not None:
            for name in ("bed_joints", "head_joints", "unit_cracks"):
                set_key(data, f"joints.{name}.relaxation_time", relaxation_time)
            label += f", relaxation time {relaxation_time}"
        return run(data, label)

    runs = {"J4D": held_j4d, **{wall: held_wall(wall) for wall in HIGHER_PRECOMPRESSIONS}}
    finer = {wall: held_wall(wall, FINER_RELAXATION_TIME) for wall in pressures}
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for wall, ds in runs.items():
        d, f, _ = pushover_data(ds)
        line, = ax.plot(d * 1e3, f / 1e3, "-o", ms=2.5, lw=1.2, label=f"{wall}, p = {pressures[wall]}, tau 0.0025 ms")
        d2, f2, _ = pushover_data(finer[wall])
        ax.plot(d2 * 1e3, f2 / 1e3, "--", lw=1.2, color=line.get_color(), label=f"{wall}, tau {FINER_RELAXATION_TIME}")
        for label, dd, ff in (("", d, f), (f", tau {FINER_RELAXATION_TIME}", d2, f2)):
            k = int(np.argmax(ff))
            print(f"  {wall}{label}: peak {ff[k] / 1e3:.2f} kN at {dd[k] * 1e3:.2f} mm, at 2 mm "
                  f"{value_at_push(dd, ff, 2e-3) / 1e3:.2f} kN, at 4 mm {ff[-1] / 1e3:.2f} kN")
        if wall != "J4D":  # J4D's are drawn with its own figures
            _crack_figures(ds, wall, out)
    _save_curves(fig, ax, "Eindhoven walls, top held at its height (model only)", out / "eindhoven_walls_curves.png")


def _relaxed_walls(out, plt, results):
    """The held walls with the inviscid law relaxed past their limit points (examples/eindhoven_walls.py): their
    curves beside J4D's regularised example, and each wall's cracks at its largest force and at 4 mm."""
    import xarray as xr

    walls = example_module("eindhoven_walls")
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for wall in walls.PRECOMPRESSION:
        path = None if results is None else results / f"eindhoven_{wall}.nc"
        if path is not None and path.exists():
            ds = xr.load_dataset(path)
        else:
            t0 = time.perf_counter()
            ds = run(walls.wall_scene(wall), f"{wall}, top held, inviscid, relaxed past its limit points")
            print(walls.report(wall, ds, time.perf_counter() - t0))
        d, f, steps = pushover_data(ds)
        ax.plot(d * 1e3, f / 1e3, "-", lw=1.4, label=f"{wall}, p = {walls.PRECOMPRESSION[wall]}, inviscid, relaxed")
        peak = int(steps[int(np.argmax(f))])
        for step, name, scale in ((peak, "peak", 100.0), (-1, "end", 30.0)):
            crack_fig = deformed_figure(ds, step=step, scale=scale, title=f"{wall}, top held, inviscid: {name}")
            crack_fig.savefig(out / f"eindhoven_{wall}_relaxed_cracks_{name}.png", dpi=90)
            plt.close(crack_fig)
    example = run(Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data, "J4D, the example (tau 0.0025 ms)")
    d, f, _ = pushover_data(example)
    ax.plot(d * 1e3, f / 1e3, ":", color="0.4", lw=1.2, label="J4D, the example's regularised law (tau 0.0025 ms)")
    _save_curves(fig, ax, "Eindhoven walls, top held at its height (model only)",
                 out / "eindhoven_walls_relaxed_curves.png")


def _save_curves(fig, ax, title, path):
    """Axes, title, grid and legend of a load-displacement figure, written to ``path``."""
    ax.set_xlabel("horizontal displacement of the top beam (mm)")
    ax.set_ylabel("horizontal force (kN)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def _crack_figures(ds, wall, out):
    """A held wall's cracks at its peak (the force's first drop, or the end where it never drops), displacements
    x 100, and at the end, x 30: eindhoven_<wall>_cracks_peak.png and eindhoven_<wall>_cracks_end.png."""
    d, f, steps = pushover_data(ds)
    drops = np.flatnonzero(np.diff(f) < 0)
    peak = int(steps[drops[0]]) if len(drops) else int(steps[-1])
    for step, name, scale in ((peak, "peak", 100.0), (-1, "end", 30.0)):
        fig = deformed_figure(ds, step=step, scale=scale, title=f"{wall}, top held: {name}")
        fig.savefig(out / f"eindhoven_{wall}_cracks_{name}.png", dpi=90)


if __name__ == "__main__":
    raise SystemExit(main())
