"""Time and memory to generate 3D masonry walls of 10 000 units (generators.walls3d), and the gmsh
alternative that the generators do not use (an OCC boolean fragment of the unit boxes).

    /work/venv/bin/python benchmarks/bench_wall_generation.py [--repeats R] [--gmsh-boxes 500]

Cases (each in a fresh subprocess, so imports start cold the same way and the peak resident memory
is the case's own), Eindhoven bricks 210 x 52 x 100 mm with 10 mm joints (expanded 220 x 62 x 110):

* ``stretcher_2x1x1``: stretcher bond, 100 units x 100 courses (10 050 units: the odd courses
  have half units at both ends), element size 110 mm: 2 x 1 x 1 hex8 per unit;
* ``stretcher_default``: the same wall with the default element size (min unit dimension = 62 mm:
  4 x 2 x 1 hex8 per unit) and a potential crack in every unit;
* ``english_default``: English bond one brick thick, 50 units x 100 courses (10 050 units:
  stretcher courses of 2 x 50, header courses of 101), default element size, unit cracks;
* ``gmsh_fragment``: the gmsh route for comparison: ``--gmsh-boxes`` unit boxes of a stretcher
  wall (20 units per course) added with ``occ.addBox`` and made conformal with one
  ``occ.fragment`` (gmsh run in try/finally with gmsh.finalize()); no meshing, no interfaces.

Printed per case: best wall time of ``--repeats`` calls (first call also shown), peak Python/numpy
allocations of one call (tracemalloc) and the process's peak resident set size (ru_maxrss, the
imports included), model size. A benchmark, not a test. Target: a 3D wall of
10 000 units in under 30 s.
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

BRICK = dict(unit_length=0.21, unit_height=0.052, unit_width=0.1, joint_thickness=0.01)
LU, HU = 0.22, 0.062

CASES = {
    "stretcher_2x1x1": dict(length=100 * LU, height=100 * HU, bond="stretcher", element_size=0.11, **BRICK),
    "stretcher_default": dict(length=100 * LU, height=100 * HU, bond="stretcher", unit_cracks=True, **BRICK),
    "english_default": dict(length=50 * LU, height=100 * HU, bond="english", unit_cracks=True, **BRICK),
}


def _units(kw) -> int:
    from generators.walls import course_slots

    wythes = 2 if kw["bond"] in ("english", "flemish") else 1
    n = round(kw["height"] / HU)
    return sum(wythes if s.role in ("S", "half") else 1
               for c in range(n) for s in course_slots(kw["bond"], c, kw["length"], LU, LU / 2))


def gmsh_fragment(n_boxes: int) -> dict:
    """Add the first ``n_boxes`` unit boxes of a 20-unit stretcher wall and fragment them (OCC)."""
    import gmsh

    from generators.walls import course_slots

    boxes = []
    c = 0
    while len(boxes) < n_boxes:
        for s in course_slots("stretcher", c, 20 * LU, LU, LU / 2):
            boxes.append((s.x0, 0.0, c * HU, s.x1 - s.x0, LU / 2, HU))
        c += 1
    boxes = boxes[:n_boxes]
    gmsh.initialize(["-noenv"], readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("wall")
        t0 = time.perf_counter()
        tags = [(3, gmsh.model.occ.addBox(*b)) for b in boxes]
        t1 = time.perf_counter()
        out, _ = gmsh.model.occ.fragment(tags[:1], tags[1:])
        gmsh.model.occ.synchronize()
        t2 = time.perf_counter()
        n_vol = len(gmsh.model.getEntities(3))
        n_faces = len(gmsh.model.getEntities(2))
    finally:
        gmsh.finalize()
    return {"boxes": n_boxes, "add_s": t1 - t0, "fragment_s": t2 - t1, "volumes": n_vol, "faces": n_faces,
            "gmsh": gmsh.__version__}


def run_case(case: str, repeats: int, gmsh_boxes: int) -> dict:
    if case == "gmsh_fragment":
        r = gmsh_fragment(gmsh_boxes)
        r["maxrss_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        return r
    from generators.walls3d import masonry_wall_3d

    kw, fn = CASES[case], masonry_wall_3d
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        mesh = fn(**kw)
        times.append(time.perf_counter() - t0)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    tracemalloc.start()
    mesh = fn(**kw)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {"case": case, "units": _units(kw), "repeats": repeats, "first_s": times[0], "best_s": min(times),
            "tracemalloc_peak_MB": peak / 2**20, "maxrss_MB": rss,
            "nodes": mesh.n_nodes, "elements": mesh.n_elements(), "interfaces": mesh.n_interfaces(),
            "element_type": mesh.blocks[0].type, "joints": {j.name: len(j.cells) for j in mesh.joints}}


def subprocess_case(case: str, repeats: int, gmsh_boxes: int) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", case, str(repeats), str(gmsh_boxes)],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--gmsh-boxes", type=int, default=500)
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        case, repeats, nb = args.child
        print(json.dumps(run_case(case, int(repeats), int(nb))))
        return
    import numpy

    print(f"CPU: {cpu_model()}; python {sys.version.split()[0]}, numpy {numpy.__version__}")
    for case in CASES:
        r = subprocess_case(case, args.repeats, args.gmsh_boxes)
        print(f"\n[{case}] {r['units']} units: {r['element_type']}, {r['nodes']} nodes, {r['elements']} elements, "
              f"{r['interfaces']} interfaces {r['joints']}")
        print(f"  generation: best {r['best_s']:.2f} s of {r['repeats']} (first call {r['first_s']:.2f} s); "
              f"{1e3 * r['best_s'] / r['units']:.2f} ms per unit")
        print(f"  peak Python/numpy allocations {r['tracemalloc_peak_MB']:.0f} MB; "
              f"process peak RSS {r['maxrss_MB']:.0f} MB")
    r = subprocess_case("gmsh_fragment", 1, args.gmsh_boxes)
    print(f"\n[gmsh_fragment] gmsh {r['gmsh']}: {r['boxes']} boxes: addBox {r['add_s']:.2f} s, one OCC fragment + "
          f"synchronize {r['fragment_s']:.2f} s ({1e3 * r['fragment_s'] / r['boxes']:.1f} ms per box; "
          f"{r['volumes']} volumes, {r['faces']} faces); process peak RSS {r['maxrss_MB']:.0f} MB")


if __name__ == "__main__":
    main()
