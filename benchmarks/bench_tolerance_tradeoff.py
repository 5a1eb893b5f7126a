"""Accuracy versus time of the solver and model knobs on the default scene (wall_push.toml).

    /work/venv/bin/python benchmarks/bench_tolerance_tradeoff.py [--epu 1 2 3] [--tol 1e-3 1e-4 1e-6 1e-8]

Knobs (all combinations): ``solver.force_tolerance`` in {1e-3, 1e-4, 1e-6, 1e-8}; ``integration`` of
``joints.bed_joints`` in {lumped, gauss}; ``mesh.parameters.elements_per_unit`` in {1, 2, 3}.
The scene is loaded with ``Scene.from_toml``, ``.data`` is modified and a new ``Scene(data,
base_dir=...)`` is run in process with ``masonrydam.run`` (kernels compiled / loaded by a warm-up
run first, which is not reported).

``--energy-tolerance`` also sets ``solver.energy_tolerance`` (default: left at 1e-10). Convergence
needs both the force and the energy criterion, so with the default energy tolerance the force
tolerance may not decide anything; ``--energy-tolerance 0.5`` makes the force criterion the one
that ends the iterations.

Reported per run: wall time of ``masonrydam.run``, steps, step cuts, Newton iterations,
factorizations, and the final top lateral force ``H = sum(reaction.sel(component='x'))`` over the
nodes at the top (max y). Errors are relative to two references:

* ``err vs tight``: the run with the same mesh and integration and the tightest tolerance (1e-8)
  -> the error due to the tolerance alone;
* ``err vs ref``: the finest and tightest run (elements_per_unit = max, tolerance = min,
  lumped integration, the default) -> the total error, discretisation included.

This is a benchmark, not a test: it prints tables and never fails on a slow figure; a run that
fails is reported with its error.
"""
from __future__ import annotations

import os

for _k in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_k, "1")

import argparse
import copy
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

SCENE = ROOT / "masonrydam" / "scenes" / "wall_push.toml"


from _common import cpu_model  # noqa: E402  (benchmarks/ is sys.path[0] when run as a script)


def top_lateral_force(ds) -> float:
    y = ds["y"].values
    top = np.abs(y - y.max()) <= 1e-9 * max(1.0, abs(y.max()))
    rx = ds.reaction.isel(step=-1).sel(component="x").values
    return float(rx[top].sum())


def run_case(base, tol, scheme, epu, energy_tol=None):
    import masonrydam
    from masonrydam.scene.scene import Scene

    data = copy.deepcopy(base.data)
    data.setdefault("solver", {})["force_tolerance"] = tol
    if energy_tol is not None:
        data["solver"]["energy_tolerance"] = energy_tol
    data["joints"]["bed_joints"]["integration"] = scheme
    data["mesh"]["parameters"]["elements_per_unit"] = epu
    sc = Scene(data, base_dir=base.base_dir)
    t0 = time.perf_counter()
    try:
        ds = masonrydam.run(sc)
    except Exception as exc:  # report, do not stop the benchmark
        return {"error": f"{type(exc).__name__}: {str(exc).splitlines()[0][:90]}", "time": time.perf_counter() - t0}
    wall = time.perf_counter() - t0
    a = ds.attrs
    lf = float(ds.load_factor.values[-1])
    return {
        "time": wall,
        "steps": int(a["steps"]),
        "cuts": int(a["step_cuts"]),
        "iters": int(a["newton_iterations"]),
        "facts": int(a["factorizations"]),
        "H": top_lateral_force(ds),
        "dofs": int(ds.sizes["node"]) * 2,
        "completed": str(a.get("completed", "?")),
        "last_load_factor": lf,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tol", type=float, nargs="+", default=[1e-3, 1e-4, 1e-6, 1e-8])
    ap.add_argument("--schemes", nargs="+", default=["lumped", "gauss"])
    ap.add_argument("--epu", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--energy-tolerance", type=float, default=None,
                    help="also set solver.energy_tolerance (default: the scene's, i.e. 1e-10); e.g. 0.5 makes "
                         "the force criterion the one that decides convergence")
    a = ap.parse_args()

    from masonrydam.scene.scene import Scene

    base = Scene.from_toml(SCENE)
    print(f"masonrydam tolerance / integration / mesh trade-off on {SCENE.name} | CPU: {cpu_model()} "
          f"({os.cpu_count()} logical cores)")
    t0 = time.perf_counter()
    run_case(base, 1e-3, "lumped", 1)  # warm-up: JIT or cache load, library loads
    print(f"warm-up run (not reported): {time.perf_counter() - t0:.2f} s")

    results = {}
    t_all = time.perf_counter()
    for epu in a.epu:
        for scheme in a.schemes:
            for tol in a.tol:
                results[(epu, scheme, tol)] = run_case(base, tol, scheme, epu, a.energy_tolerance)
    t_all = time.perf_counter() - t_all

    tight = min(a.tol)
    ref_key = (max(a.epu), "lumped" if "lumped" in a.schemes else a.schemes[0], tight)
    H_ref = results[ref_key].get("H", float("nan"))
    et = a.energy_tolerance if a.energy_tolerance is not None else "default (1e-10)"
    print(f"\nsolver.energy_tolerance: {et}")
    print(f"reference: elements_per_unit={ref_key[0]}, bed_joints integration={ref_key[1]}, force_tolerance={ref_key[2]:g}"
          f" -> H_ref = {H_ref:.2f} N")
    hdr = (f"{'epu':>3} {'DOFs':>6} {'bed int.':>8} {'f_tol':>7} {'time s':>7} {'steps':>5} {'cuts':>4} {'iters':>6} "
           f"{'facts':>5} {'H (N)':>11} {'err vs tight':>12} {'err vs ref':>10}")
    print(hdr)
    print("-" * len(hdr))
    for (epu, scheme, tol), r in results.items():
        if "error" in r:
            print(f"{epu:>3} {'':>6} {scheme:>8} {tol:>7.0e} {r['time']:>7.2f}  FAILED: {r['error']}")
            continue
        tight_r = results.get((epu, scheme, tight), {})
        Ht = tight_r.get("H", float("nan"))
        e_t = abs(r["H"] - Ht) / abs(Ht) if Ht == Ht and Ht != 0 else float("nan")
        e_r = abs(r["H"] - H_ref) / abs(H_ref) if H_ref == H_ref and H_ref != 0 else float("nan")
        print(f"{epu:>3} {r['dofs']:>6} {scheme:>8} {tol:>7.0e} {r['time']:>7.2f} {r['steps']:>5} {r['cuts']:>4} "
              f"{r['iters']:>6} {r['facts']:>5} {r['H']:>11.2f} {e_t:>12.2e} {e_r:>10.2e}")
    print(f"total benchmark time {t_all:.1f} s. time = masonrydam.run wall (build + solve + netCDF to a temporary file); "
          "iters = Newton iterations; facts = factorizations.")


if __name__ == "__main__":
    main()
