"""What the water costs on a 3D dam: ``examples/dam_3d_reservoir.toml`` (20 monoliths x 10 lifts across
a valley, reservoir at 57 m, tailwater, uplift with drains in the base and lift joints: 140 joint
lines) against the same dam without water (no ``[reservoir]``, the gravity stage alone).

    . .venv/bin/activate
    python benchmarks/bench_dam_3d_water.py                          # the example as it is
    python benchmarks/bench_dam_3d_water.py --linear-solver amg      # another [solver] linear_solver
    python benchmarks/bench_dam_3d_water.py --element-size 8         # a coarser mesh (quicker)

Target: the run with reservoir and uplift statically in under 2x the dry run. Printed per
run (each in a subprocess of its own, one thread for numba, OpenMP, MKL and OpenBLAS, after an
untimed warm-up run of a small 2D dam with water that compiles the kernels):

* the model: DOF, joint points, joint lines assessed;
* ``run s`` (``masonrydam.run``: mesh, build, solve, output) and ``solve s`` (the static solver);
  steps, Newton iterations (general and joint space) and step cuts per stage;
* ``water s``: the time spent computing water loads (face pressures once per increment, pore
  pressures and their forces at every iteration: the calls of ``StageWater.external`` and
  ``StageWater.pore``), and how many calls;
* the ratio wet / dry of the run and of the solve.

This is a benchmark, not a test: it never fails on a slow figure.
"""
from __future__ import annotations

from _common import child_result, pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import json
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "dam_3d_reservoir.toml"

def child(scene_json: str) -> None:
    """Run one scene (JSON) with the water calls timed; print a JSON line of figures."""
    import tempfile
    import time

    import masonrydam
    from masonrydam.effects import reservoir as R

    counters = {"water_s": 0.0, "external_calls": 0, "pore_calls": 0}

    def timed(name, fn):
        def wrapper(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                counters["water_s"] += time.perf_counter() - t0
                counters[name] += 1
        return wrapper

    R.StageWater.external = timed("external_calls", R.StageWater.external)
    R.StageWater.pore = timed("pore_calls", R.StageWater.pore)
    # warm-up: a small 2D dam with water (kernels compiled, PARDISO loaded)
    warm = {"model": {"name": "warm", "hypothesis": "plane_strain"},
            "mesh": {"generator": "gravity_dam_2d", "parameters": {"height": 20.0, "crest_width": 4.0,
                                                                  "foundation_width": 50.0, "foundation_depth": 5.0,
                                                                  "element_size": 4.0}},
            "materials": {"dam": {"youngs_modulus": 25e9, "poisson_ratio": 0.2, "density": 2400.0},
                          "foundation": {"youngs_modulus": 25e9, "poisson_ratio": 0.2, "density": 0.0}},
            "joints": {"base_joint": {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": 45.0}},
            "reservoir": {"level": 18.0, "uplift": {"joints": ["base_joint"]}},
            "supports": [{"set": "foundation_bottom"}],
            "stages": [{"loads": [{"type": "self_weight"}]}, {"name": "water", "loads": [{"type": "reservoir"}]}]}
    masonrydam.run(warm)
    counters.update(water_s=0.0, external_calls=0, pore_calls=0)
    scene = json.loads(scene_json)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        ds = masonrydam.run(scene, output=Path(tmp) / "out.nc")
        run_s = time.perf_counter() - t0
        a = ds.attrs
        out = {"run_s": run_s, "solve_s": float(a["solve_wall_time_s"]), "per_stage": json.loads(a["per_stage"]),
               "dof": int(ds.sizes["node"]) * int(ds.sizes["component"]), "joint_points": int(ds.sizes["joint_point"]),
               "sections": int(ds.sizes.get("section", 0)), "backend": json.loads(a["solver_settings"])["linear_solver_backend"],
               "factorizations": int(a["factorizations"]), **counters}
        if "sliding_safety_factor" in ds:
            sf = ds.sliding_safety_factor.isel(step=-1).values
            out["min_sliding_factor"] = float(sf.min())
            out["max_cracked_ratio"] = float(ds.cracked_length_ratio.isel(step=-1).max())
        ds.close()
    print("RESULT " + json.dumps(out))


def scenes(args):
    wet = tomllib.loads(EXAMPLE.read_text())
    wet["mesh"]["parameters"]["element_size"] = args.element_size
    if args.linear_solver:
        wet.setdefault("solver", {})["linear_solver"] = args.linear_solver
    if args.steps:
        wet["stages"][1]["steps"] = args.steps
    dry = json.loads(json.dumps(wet))
    del dry["reservoir"]
    dry["stages"] = dry["stages"][:1]
    return dry, wet


def run_child(scene) -> dict:
    return child_result([sys.executable, __file__, "--child", json.dumps(scene)])


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--element-size", type=float, default=6.0)
    p.add_argument("--linear-solver", help="[solver] linear_solver (default: the example's)")
    p.add_argument("--steps", type=int, help="steps of the reservoir stage (default: the example's)")
    p.add_argument("--child", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.child:
        child(args.child)
        return
    from _common import cpu_model

    print(f"bench_dam_3d_water: {EXAMPLE.name}, element_size {args.element_size:g} m, one thread, {cpu_model()}")
    dry, wet = scenes(args)
    res = {}
    for name, scene in (("dry", dry), ("wet", wet)):
        r = res[name] = run_child(scene)
        stages = "; ".join(f"{s['stage']}: {s['steps']} steps, {s['iterations']} it, {s['step_cuts']} cuts"
                           for s in r["per_stage"])
        print(f"{name}: {r['dof']} DOF, {r['joint_points']} joint points, {r['sections']} joint lines, "
              f"backend {r['backend']}; run {r['run_s']:.1f} s, solve {r['solve_s']:.1f} s, "
              f"{r['factorizations']} factorizations; {stages}")
        if name == "wet":
            print(f"     water {r['water_s']:.2f} s ({r['external_calls']} face-load calls, {r['pore_calls']} "
                  f"pore-pressure calls); lowest sliding factor {r.get('min_sliding_factor', float('nan')):.3g}, "
                  f"largest cracked ratio {r.get('max_cracked_ratio', float('nan')):.3g}")
    print(f"wet / dry: run {res['wet']['run_s'] / res['dry']['run_s']:.2f}, "
          f"solve {res['wet']['solve_s'] / res['dry']['solve_s']:.2f} (target: under 2)")


if __name__ == "__main__":
    main()
