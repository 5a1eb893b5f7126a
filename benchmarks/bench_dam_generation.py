"""Time and memory to generate gravity dam models (generators.dams).

    /work/venv/bin/python benchmarks/bench_dam_generation.py [--repeats R] [--size3d H] [--dof 7500]

Cases (each run in a fresh subprocess, so gmsh, numpy and the imports start cold the same way and
the peak resident memory is the case's own):

* ``3d``: the Koyna benchmark section (Chopra & Chakrabarti 1973) as 20 monoliths of 20 m across a trapezoidal
  valley 100 m wide at the base and 400 m at the crest, 10 lifts of 10.3 m, a rock foundation
  250 m (upstream-downstream) x 100 m deep, hexahedra of ``--size3d`` m (default 5 m);
* ``2d``: the Koyna section with 10 lifts on no foundation, at the element size that gives about
  ``--dof`` degrees of freedom (2 per node, interface copies included; the seismic benchmark's
  model): the size is found first by a scan, then timed.

Printed per case: best wall time of ``--repeats`` calls (the first, cold call also shown), peak
Python/numpy allocations during one call (tracemalloc) and the process's peak resident set size
(ru_maxrss: includes gmsh's C++ memory and the imports), model size. A benchmark, not a test.
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import cpu_model  # noqa: E402

KOYNA_LIFT = 10.3  # 103 m / 10 lifts


def case_kwargs(case: str, size: float) -> tuple[str, dict]:
    if case == "3d":
        return "gravity_dam_3d", dict(valley_bottom_width=100.0, valley_top_width=400.0, n_monoliths=20, preset="koyna",
                                      lift_spacing=KOYNA_LIFT, foundation_width=250.0, foundation_depth=100.0,
                                      element_size=size)
    return "gravity_dam_2d", dict(preset="koyna", lift_spacing=KOYNA_LIFT, element_size=size)


def run_case(case: str, size: float, repeats: int) -> dict:
    """In this process: time ``repeats`` generations, then one more under tracemalloc."""
    from generators import dams

    name, kw = case_kwargs(case, size)
    fn = getattr(dams, name)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        mesh = fn(**kw)
        times.append(time.perf_counter() - t0)
    tracemalloc.start()
    mesh = fn(**kw)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {"case": case, "element_size": size, "first_s": times[0], "best_s": min(times),
            "tracemalloc_peak_MB": peak / 2**20, "maxrss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "nodes": mesh.n_nodes, "dof": mesh.n_nodes * mesh.dim, "elements": mesh.n_elements(),
            "interfaces": mesh.n_interfaces(), "element_type": mesh.blocks[0].type,
            "joints": {j.name: len(j.cells) for j in mesh.joints}}


def find_size_2d(target_dof: int) -> tuple[float, int, list]:
    """Scan element sizes of the 2D Koyna section for the one whose DOF count is closest to the target."""
    from generators import dams

    table = []
    for size in [round(0.70 + 0.02 * k, 2) for k in range(41)]:
        mesh = dams.gravity_dam_2d(**case_kwargs("2d", size)[1])
        table.append((size, 2 * mesh.n_nodes, mesh.n_elements()))
    best = min(table, key=lambda r: abs(r[1] - target_dof))
    return best[0], best[1], table


def subprocess_case(case: str, size: float, repeats: int) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", case, str(size), str(repeats)],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--size3d", type=float, default=5.0)
    ap.add_argument("--dof", type=int, default=7500)
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        case, size, repeats = args.child
        print(json.dumps(run_case(case, float(size), int(repeats))))
        return
    import gmsh
    import numpy

    print(f"CPU: {cpu_model()}; python {sys.version.split()[0]}, numpy {numpy.__version__}, gmsh {gmsh.__version__}")
    size2d, dof, table = find_size_2d(args.dof)
    print("2D Koyna, 10 lifts: element size -> DOF (2 per node, interface copies included):")
    print("  " + ", ".join(f"{s:g} m: {d}" for s, d, _ in table if abs(d - args.dof) < 0.15 * args.dof))
    print(f"  closest to {args.dof} DOF: element_size = {size2d:g} m ({dof} DOF)")
    for case, size in (("2d", size2d), ("3d", args.size3d)):
        r = subprocess_case(case, size, args.repeats)
        print(f"\n[{case}] element_size {size:g} m: {r['element_type']}, {r['nodes']} nodes ({r['dof']} DOF), "
              f"{r['elements']} elements, {r['interfaces']} interfaces {r['joints']}")
        print(f"  generation: best {r['best_s']:.3f} s of {args.repeats} (first call {r['first_s']:.3f} s)")
        print(f"  peak Python/numpy allocations {r['tracemalloc_peak_MB']:.1f} MB; process peak RSS {r['maxrss_MB']:.0f} MB")


if __name__ == "__main__":
    main()
