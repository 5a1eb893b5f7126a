"""The Eindhoven walls J4D to J7D (examples/eindhoven_J4D.toml; Lourenco & Rots 1997): what their curves cost
and how they converge: the relaxation time of the joints' viscous regularisation, the number
of push steps and the mesh, for both vertical conditions of the top beam:

- ``held``: the reference loading (Lourenco & Rots 1997): the top beam kept level and at its
  height, so the vertical force grows as the wall rocks;
- ``constant``: the top beam kept level but free to rise, the vertical load constant (0.30 MPa): the wall
  peaks and slides on a bed joint at H = tan(phi) N (22.9 kN here).

Each case is the example with ``--set`` style changes: ``relaxation_time`` of the three composite joint sets
(0: the inviscid law), the push's ``steps``, the generator's ``elements_per_unit`` and the push's ``control``
(``load``: displacement control with the automatic switches; ``dissipation``: dissipation-based path
following; ``--limit-points relax``: displacement control that relaxes the joints past a limit point,
``[[stages]] limit_point = "relax"``), and the precompression of the wall (``--walls``): J4D and J5D 0.30 MPa (two specimens of one
wall: the model cannot tell them apart), J6D 1.21 MPa, J7D 2.12 MPa (Raijmakers & Vermeltfoort 1992, as
modelled by Lourenco & Rots 1997). The first case runs once before the timings (numba compilation and cache).

    python benchmarks/bench_eindhoven.py [--walls J4D J6D J7D] [--cases held constant]
        [--taus 0.25 0.025 0.0025 0] [--steps 40 80] [--elements 2 4] [--controls load dissipation]
        [--limit-points follow relax] [--force-tolerances 1e-6 1e-5 1e-4] [--crack-stiffnesses 1e6 1e4]
        [--numba-threads 2]

``--crack-stiffnesses``: the normal and shear stiffness of the units' potential cracks, N/mm3 (default: the example
file's, 1e6); a penalty, rigid until the cracks open or slip. The converged walls of examples/eindhoven_walls.py are
``--taus 0 --limit-points relax --steps 80 --crack-stiffnesses 1e4`` (docs/masonry_softening.md, "The units' cracks'
penalty").

``--force-tolerances``: the solver's ``force_tolerance`` (default 1e-6), its ``energy_tolerance`` 1e-4 times that
(the defaults' ratio): how tightly each Newton solve is converged, a knob that trades accuracy for time.

Prints per case: the peak force and its displacement, the force at 1, 2, 3 and 4 mm, how far the run got (with the
force tolerance and the cracks' stiffness, ``file`` for the example file's), the Newton iterations of the run (all
its solves, those that failed included), the wall time of the run, the failure mechanisms at the peak and at the end
(:mod:`masonrydam.results.wall_cracks`: diagonal cracking, toe crushing, sliding), and the peak's change against the
case with the smallest relaxation time of the same steps and mesh. One process, one thread (``--numba-threads N``: N
for numba). A benchmark, not a test: it never fails on a slow figure.
"""
from __future__ import annotations

import os
import sys

from _common import cpu_model, pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()
#: ``--numba-threads N``: numba's threads (the composite joints' kernel shares its elements among them,
#: masonrydam.elements.interface.interface_evaluate_threaded, bit for bit the same); read here, before numba loads
for _i, _word in enumerate(sys.argv[1:], 1):
    if _word == "--numba-threads" and _i + 1 < len(sys.argv):
        os.environ["NUMBA_NUM_THREADS"] = sys.argv[_i + 1]
    elif _word.startswith("--numba-threads="):
        os.environ["NUMBA_NUM_THREADS"] = _word.split("=", 1)[1]

import argparse
import contextlib
import io
import itertools
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

import masonrydam
from masonrydam.results.pushover import pushover_data, value_at_push
from masonrydam.results.wall_cracks import wall_cracks
from masonrydam.scene.scene import Scene, set_key

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "eindhoven_J4D.toml"
JOINT_SETS = ("bed_joints", "head_joints", "unit_cracks")
#: the walls' vertical precompression (Raijmakers & Vermeltfoort 1992; Lourenco & Rots 1997)
PRECOMPRESSION = {"J4D": "0.30 MPa", "J5D": "0.30 MPa", "J6D": "1.21 MPa", "J7D": "2.12 MPa"}
#: ``--force-tolerances``: the energy tolerance that goes with a force tolerance (the solver's defaults, 1e-10 and
#: 1e-6, have this ratio)
ENERGY_PER_FORCE_TOLERANCE = 1e-4


def scene(case: str, tau_ms: float, steps: int, elements: int, control: str = "load", wall: str = "J4D",
          limit_point: str = "follow", force_tolerance: float = 1e-6, crack_stiffness: float | None = None) -> dict:
    data = Scene.from_toml(EXAMPLE).data
    if crack_stiffness is not None:
        for key in ("normal_stiffness", "shear_stiffness"):
            set_key(data, f"joints.unit_cracks.{key}", f"{crack_stiffness:g} N/mm3")
    set_key(data, "solver.force_tolerance", force_tolerance)
    set_key(data, "solver.energy_tolerance", ENERGY_PER_FORCE_TOLERANCE * force_tolerance)
    set_key(data, "stages[0].loads[1].pressure", PRECOMPRESSION[wall])
    set_key(data, "stages[1].control", control)
    set_key(data, "stages[1].limit_point", limit_point)
    for name in JOINT_SETS:
        if tau_ms > 0:
            set_key(data, f"joints.{name}.relaxation_time", f"{tau_ms:g} ms")
        else:
            data["joints"][name].pop("relaxation_time", None)
    set_key(data, "stages[1].steps", steps)
    set_key(data, "mesh.parameters.elements_per_unit", elements)
    if case == "constant":
        set_key(data, "stages[1].loads[0].components", ["x"])
        set_key(data, "stages[1].loads[0].value", ["4 mm"])
    return data


def run_case(data: dict, folder: str) -> dict:
    out = os.path.join(folder, "j4d.nc")
    t0 = time.perf_counter()
    status = "completed"
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            masonrydam.run(data, output=out)
    except masonrydam.MasonrydamError as exc:
        status = type(exc).__name__
        out = out.replace(".nc", ".partial.nc") if os.path.exists(out.replace(".nc", ".partial.nc")) else out
    wall = time.perf_counter() - t0
    import xarray as xr

    with xr.open_dataset(out) as ds:
        d, f, steps = pushover_data(ds)
        iterations = int(ds["iterations"].sum())
        k = int(np.argmax(f))
        mechanisms = {when: wall_cracks(ds, step).mechanisms for when, step in (("peak", int(steps[k])), ("end", -1))}
    at = [value_at_push(d, f, x) for x in (1e-3, 2e-3, 3e-3, 4e-3)]
    return {"peak": f[k], "d_peak": d[k], "at": at, "reached": d.max(), "wall": wall, "status": status,
            "mechanisms": mechanisms, "iterations": iterations}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--walls", nargs="+", default=["J4D"], choices=list(PRECOMPRESSION))
    ap.add_argument("--cases", nargs="+", default=["constant", "held"], choices=["constant", "held"])
    ap.add_argument("--taus", nargs="+", type=float, default=[0.25, 0.025, 0.0025, 0.0], help="relaxation times, ms")
    ap.add_argument("--steps", nargs="+", type=int, default=[40])
    ap.add_argument("--elements", nargs="+", type=int, default=[2])
    ap.add_argument("--controls", nargs="+", default=["load"], choices=["load", "dissipation"])
    ap.add_argument("--limit-points", nargs="+", default=["follow"], choices=["follow", "relax"],
                    help="control load: where a step finds no equilibrium, follow the path or relax the joints")
    ap.add_argument("--force-tolerances", nargs="+", type=float, default=[1e-6],
                    help="the solver's force_tolerance (default 1e-6, the solver's own); the energy tolerance is "
                         "1e-4 times it")
    ap.add_argument("--crack-stiffnesses", nargs="+", type=float, default=[None],
                    help="normal and shear stiffness of the units' potential cracks, N/mm3 (default: the example "
                         "file's)")
    ap.add_argument("--numba-threads", type=int, default=1,
                    help="numba's threads (the composite joints' elements are shared among them); MKL and "
                         "OpenBLAS keep one")
    args = ap.parse_args(argv)
    if args.numba_threads != numba.config.NUMBA_NUM_THREADS:  # e.g. main(argv) called with the option: too late
        ap.error(f"--numba-threads {args.numba_threads}: numba has loaded with {numba.config.NUMBA_NUM_THREADS} "
                 "thread(s); give the option on the command line of this script")
    print(f"bench_eindhoven: {numba.config.NUMBA_NUM_THREADS} numba thread(s), one MKL / OpenBLAS thread, "
          f"{cpu_model()}", flush=True)
    with tempfile.TemporaryDirectory() as folder:
        warm = scene(args.cases[0], 0.025, 4, 2)
        set_key(warm, "stages[1].loads[0].value", ["0.4 mm"] if args.cases[0] == "constant" else ["0.4 mm", "0 mm"])
        run_case(warm, folder)
        print(f"{'wall':4s} {'case':9s} {'control':11s} {'tau ms':>7s} {'steps':>5s} {'el/unit':>7s} {'peak kN':>8s} {'at mm':>6s} "
              f"{'F(1) kN':>8s} {'F(2)':>6s} {'F(3)':>6s} {'F(4)':>6s} {'reached':>8s} {'ftol':>7s} {'k_crack':>8s} "
              f"{'Newton':>7s} {'wall s':>7s} {'peak vs smallest tau':>21s}  status")
        for wall, case, control, limit, steps, elements, ftol, kc in itertools.product(
                args.walls, args.cases, args.controls, args.limit_points, args.steps, args.elements,
                args.force_tolerances, args.crack_stiffnesses):
            if control != "load" and limit != "follow":
                continue
            rows = []
            for tau in sorted(args.taus, reverse=True):
                r = run_case(scene(case, tau, steps, elements, control, wall, limit, ftol, kc), folder)
                rows.append((tau, r))
            ref = rows[-1][1]["peak"]
            for tau, r in rows:
                at = " ".join(f"{v / 1e3:6.2f}" for v in r["at"])
                print(f"{wall:4s} {case:9s} {control + ('+relax' if limit == 'relax' else ''):11s} {tau:7.4g} {steps:5d} {elements:7d} {r['peak'] / 1e3:8.2f} {r['d_peak'] * 1e3:6.2f} "
                      f"{at:>29s} {r['reached'] * 1e3:6.2f}mm {ftol:7.0e} {'file' if kc is None else f'{kc:.0e}':>8s} "
                      f"{r['iterations']:7d} {r['wall']:7.1f} "
                      f"{100 * (r['peak'] / ref - 1):+20.2f}%  "
                      f"{r['status']}", flush=True)
                for when, names in r["mechanisms"].items():
                    print(f"     at the {when}: {'; '.join(names) or 'no failure mechanism'}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
