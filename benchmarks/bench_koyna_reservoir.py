"""What the moving reservoir costs per step: the Koyna section of
``examples/koyna_el_centro.toml`` (El Centro at 0.5 g, nonlinear lift joints, HHT, fixed dt) run with
the reservoir empty and at its 1967 level of 91.75 m with the water's dynamics

- ``empty``: no reservoir (the example as it is);
- ``static``: the water's static pressure only (``dynamic = "none"``);
- ``westergaard``: Westergaard's added mass;
- ``incompressible``: acoustic elements, incompressible (an added mass rho Q H^-1 Q^T on the face);
- ``acoustic``: acoustic elements, c = 1440 m/s, condensed into the implicit step
  (:mod:`masonrydam.solvers.dynamic.fluid`).

    python benchmarks/bench_koyna_reservoir.py [--steps 1000] [--dt 0.005] [--cases empty acoustic ...] [--linear]

Prints ms per step of the dynamic stage (the whole stage's wall time over its steps), Newton and
joint-space iterations per step and the crest's peak displacement, and the ratio of each case to the
empty run, all in one process on one thread. Target: the acoustic run at most 2x the
empty one per step. A benchmark, not a test: it never fails on a slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402

CASES = ("empty", "static", "westergaard", "incompressible", "acoustic")


def scene(case: str, steps: int, dt: float, linear: bool = False) -> dict:
    import tomllib

    from masonrydam.scene.schema import set_time_steps

    sc = tomllib.loads((ROOT / "examples" / "koyna_el_centro.toml").read_text())
    sc["model"]["name"] = f"koyna_{case}"
    set_time_steps(sc["stages"][1], dt, steps=steps)["output"] = {"stride": 50, "nodes": ["crest"]}
    if linear:  # every joint linear with the same stiffnesses: the cost of the water alone
        for name, joint in sc["joints"].items():
            sc["joints"][name] = {"law": "linear", "normal_stiffness": joint["normal_stiffness"],
                                  "shear_stiffness": joint["shear_stiffness"]}
    if case != "empty":
        sc["reservoir"] = {"level": 91.75, "face": "upstream_face"}
        sc["stages"].insert(1, {"name": "reservoir", "steps": 2, "loads": [{"type": "reservoir"}]})
        if case == "westergaard":
            sc["reservoir"]["dynamic"] = "westergaard"
        elif case in ("incompressible", "acoustic"):
            sc["reservoir"]["dynamic"] = "acoustic"
            sc["reservoir"]["acoustic"] = {"sound_speed": "incompressible" if case == "incompressible" else 1440.0}
    return sc


def run_one(case, steps, dt, linear=False):
    import warnings

    import masonrydam

    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the accuracy warnings of dt are not this benchmark's subject)
        t0 = time.perf_counter()
        ds = masonrydam.run(scene(case, steps, dt, linear), output=Path(tmp) / "koyna.nc")
        wall = time.perf_counter() - t0
        a = dict(ds.attrs)
        n = int(a["dynamic_steps"])
        out = {"wall_s": wall, "dyn_s": float(a["dynamic_wall_time_s"]), "ms_per_step": float(a["dynamic_ms_per_step"]),
               "its": int(a["dynamic_newton_iterations"]) / n,
               "js_its": int(a.get("dynamic_joint_space_iterations", 0)) / n,
               "crest": float(np.abs(ds.displacement.sel(component="x")).max()),
               "unknowns": a.get("reservoir_dynamic", "")}
        ds.close()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--dt", type=float, default=0.005)
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    ap.add_argument("--linear", action="store_true", help="every joint linear: the cost of the water alone")
    args = ap.parse_args()
    joints = "linear joints" if args.linear else "Mohr-Coulomb joints"
    print(f"# Koyna section, El Centro at 0.5 g, {joints}, {args.steps} steps of {args.dt} s, HHT ({cpu_model()}, "
          "1 thread)")
    for case in args.cases:  # JIT, numba cache and the fluid set-up code paths outside the timings
        run_one(case, 3, args.dt, args.linear)
    base = None
    for case in args.cases:
        r = run_one(case, args.steps, args.dt, args.linear)
        if case == "empty":
            base = r["ms_per_step"]
        ratio = f"  {r['ms_per_step'] / base:.2f}x empty" if base else ""
        print(f"[{case:14s}] {r['ms_per_step']:.3f} ms/step{ratio}; {r['its']:.2f} Newton + {r['js_its']:.2f} "
              f"joint-space iterations/step; crest peak |u_x| {1e3 * r['crest']:.1f} mm; run {r['wall_s']:.1f} s")
        if r["unknowns"]:
            print(f"    {r['unknowns']}")


if __name__ == "__main__":
    main()
