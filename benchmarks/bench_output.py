"""What writing results costs: the Koyna example with output stride 10 and stride 1, and a
small jointed dam (the Koyna section meshed at 10 m, about 450 DOF) recording every node at every one
of 4 000 steps.

    python benchmarks/bench_output.py [--steps 4000] [--repeat 1] [--cases koyna small]
                                      [--precision double] [--compression 0]

Prints, per run: the whole run's wall time, the dynamic stage's time, the time spent in the output
callback (``dynamic_output_time_s``: collecting a step's values and writing them), its share of the
run, and the file size. Targets: Koyna at stride 1 at most 10 % slower than at stride 10;
the small dam writes for at most 25 % of its run. A benchmark, not a test: it never fails on a slow
figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402

SCENE_FILE = ROOT / "examples" / "koyna_el_centro.toml"


def koyna(steps: int, stride: int, element_size: float = 1.45, all_nodes: bool = False, output: dict | None = None):
    """The scene of examples/koyna_el_centro.toml with ``steps`` steps, output ``stride``, and every
    node recorded with ``all_nodes`` (the example records the crest only); ``output``: extra keys of
    the scene's [output] section (precision, compression, ...)."""
    sc = tomllib.loads(SCENE_FILE.read_text())
    sc["mesh"]["parameters"]["element_size"] = element_size
    from masonrydam.scene.schema import set_time_steps

    dyn = set_time_steps(sc["stages"][1], 0.01, steps=steps)  # the example's dt = "auto": fixed steps here
    dyn["output"] = {"stride": stride} if all_nodes else {"stride": stride, "nodes": ["crest"]}
    sc["output"] = dict(output or {})
    return sc


def run_one(sc):
    import masonrydam

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "out.nc"
        t0 = time.perf_counter()
        ds = masonrydam.run(sc, output=path)
        wall = time.perf_counter() - t0
        size = path.stat().st_size
        a = dict(ds.attrs)
        ds.close()
    return {"wall": wall, "dyn": float(a["dynamic_wall_time_s"]), "out": float(a["dynamic_output_time_s"]),
            "steps": int(a["dynamic_steps"]), "size_MB": size / 2**20}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--repeat", type=int, default=1, help="runs of each case (the best is printed too)")
    ap.add_argument("--cases", nargs="+", default=["koyna", "small"], choices=["koyna", "small"])
    ap.add_argument("--precision", default=None, choices=["double", "single"])
    ap.add_argument("--compression", type=int, default=None)
    args = ap.parse_args()
    extra = {k: v for k, v in (("precision", args.precision), ("compression", args.compression)) if v is not None}
    print(f"# output cost, {args.steps} steps ({cpu_model()}, 1 thread); [output] {extra or 'defaults'}")
    run_one(koyna(5, 1, output=extra))  # JIT and numba cache outside the timings
    cases = []
    if "koyna" in args.cases:
        cases += [("Koyna, crest nodes + all joint points, stride 10", koyna(args.steps, 10, output=extra)),
                  ("Koyna, crest nodes + all joint points, stride 1", koyna(args.steps, 1, output=extra))]
    if "small" in args.cases:
        cases += [("small dam (10 m mesh), every node, stride 1",
                   koyna(args.steps, 1, element_size=10.0, all_nodes=True, output=extra))]
    for name, sc in cases:
        runs = [run_one(sc) for _ in range(args.repeat)]
        for r in runs:
            print(f"{name}: run {r['wall']:.2f} s, dynamic stage {r['dyn']:.2f} s, output {r['out']:.2f} s "
                  f"({100 * r['out'] / r['wall']:.1f} % of the run, {1e3 * r['out'] / r['steps']:.3f} ms/step), "
                  f"file {r['size_MB']:.1f} MB")
        if len(runs) > 1:
            print(f"  best run {min(r['wall'] for r in runs):.2f} s")


if __name__ == "__main__":
    main()
