"""Filling the reservoir of a 3D dam (issue 33, item 1): the static reservoir stage against the gravity stage.

    . .venv/bin/activate
    python benchmarks/bench_dam_3d_reservoir_fill.py                 # the 8-monolith dam, then the 20-monolith one
    python benchmarks/bench_dam_3d_reservoir_fill.py --only fill8    # one of them

``fill8``: ``examples/dam_3d_gravity.toml`` (8 monoliths, about 42 000 DOF, 8 096 joint points) with the
``[reservoir]`` of ``examples/dam_3d_reservoir.toml`` (level 57 m, tailwater 3 m, uplift with drains, full head in
cracks) and its second stage (``reservoir``, 2 steps). Before issue 33 it stopped at about 51-52 m with "no
convergence" while every joint line held with margin (lowest sliding factor 5.3): points at the tip of the crack
in the cohesive dam-rock joint flipped between open (bond broken, no shear) and closed (bond intact, shear up to
c) from one joint-space iteration to the next. ``reservoir20``: ``examples/dam_3d_reservoir.toml`` as it is (20
monoliths, about 63 000 DOF). Target: the water reaches 57 m (or a physical limit), the reservoir stage costs at
most 1.5x the gravity stage.

Printed per run (each in a subprocess of its own, one thread for numba, OpenMP, MKL and OpenBLAS, after an
untimed warm-up run of a small 3D dam with water that compiles the kernels): the model, the level reached and
the limit (if any), the wall time of each stage (from the start of the static solve to its last converged step),
its steps, Newton iterations (joint space and general) and step cuts, the joint-space splits, holds and bond
latches, the lowest sliding factor, and the ratio reservoir / gravity.

This is a benchmark, not a test: it never fails on a slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import json
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GRAVITY = ROOT / "examples" / "dam_3d_gravity.toml"
RESERVOIR = ROOT / "examples" / "dam_3d_reservoir.toml"


def scene_of(name: str) -> dict:
    """The scene ``fill8`` or ``reservoir20`` (see the module docstring)."""
    wet = tomllib.loads(RESERVOIR.read_text())
    if name == "reservoir20":
        return wet
    scene = tomllib.loads(GRAVITY.read_text())
    scene["reservoir"] = wet["reservoir"]
    scene["stages"].append({"name": "reservoir", "steps": 2, "loads": [{"type": "reservoir"}]})
    return scene


def child(name: str) -> None:
    """Run one scene with its stages timed; print a JSON line of figures."""
    import importlib
    import time
    import warnings

    import masonrydam
    from masonrydam.solvers.static.stepping import StaticSolver

    warm = {"model": {"name": "warm", "dimension": 3},
            "mesh": {"generator": "gravity_dam_3d", "parameters": {
                "valley_bottom_width": 20.0, "valley_top_width": 40.0, "n_monoliths": 2, "height": 60.0,
                "crest_width": 6.0, "downstream_slope": 0.8, "lift_spacing": 6.0, "foundation_width": 120.0,
                "foundation_depth": 20.0, "element_size": 12.0}},
            "materials": {"dam": {"youngs_modulus": 25e9, "poisson_ratio": 0.2, "density": 2400.0},
                          "foundation": {"youngs_modulus": 20e9, "poisson_ratio": 0.25, "density": 0.0}},
            "joints": {j: {"normal_stiffness": 1e11, "shear_stiffness": 1e11, "friction_angle": 45.0}
                       for j in ("lift_joints", "base_joint", "contraction_joints")},
            "reservoir": {"level": 57.0, "uplift": {"joints": ["base_joint", "lift_joints"]}},
            "supports": [{"set": "foundation_bottom"}],
            "stages": [{"loads": [{"type": "self_weight"}]}, {"name": "water", "loads": [{"type": "reservoir"}]}]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        masonrydam.run(warm)

    marks = {"start": None, "stage_end": {}}
    holds = {"holds": 0, "latches": 0}
    solve = StaticSolver.run

    def timed_run(self, *a, **k):
        marks["start"] = time.perf_counter()
        try:
            return solve(self, *a, **k)
        finally:
            marks["end"] = time.perf_counter()

    start_js = StaticSolver._joint_space_start

    def counted_start(self, js, *a, **k):  # (the solver drops its joint space when it ends)
        try:
            return start_js(self, js, *a, **k)
        finally:
            holds["holds"], holds["latches"] = js.hold_events, getattr(js, "bond_latches", 0)

    StaticSolver.run = timed_run
    StaticSolver._joint_space_start = counted_start
    run_module = importlib.import_module("masonrydam.scene.run")  # (masonrydam.scene.run is also the function)
    on_step = run_module._Run.on_static_step

    def timed_step(self, si, st, lam, *a, **k):
        marks["stage_end"][st.name] = time.perf_counter()
        return on_step(self, si, st, lam, *a, **k)

    run_module._Run.on_static_step = timed_step
    scene = scene_of(name)
    t0 = time.perf_counter()
    error = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = masonrydam.run(scene)
        a = dict(ds.attrs)
    except Exception as exc:  # a run that stops: its figures so far
        error, ds, a = str(exc).splitlines()[0][:300], None, {}
    run_s = time.perf_counter() - t0
    ends, prev, stage_s = marks["stage_end"], marks["start"], {}
    for stage in (s["name"] for s in scene["stages"]):
        if stage in ends:
            stage_s[stage] = ends[stage] - prev
            prev = ends[stage]
    out = {"run_s": run_s, "stage_s": stage_s, "error": error, **holds}
    if ds is not None:
        out.update(per_stage=json.loads(a["per_stage"]), completed=a.get("completed"),
                   limit_kind=a.get("limit_kind"), limit_state=a.get("limit_state"),
                   dof=int(ds.sizes["node"]) * int(ds.sizes["component"]), joint_points=int(ds.sizes["joint_point"]),
                   splits=int(a["joint_space_splits"]), factorizations=int(a["factorizations"]),
                   level=float(ds.reservoir_level.values[-1]))
        if "sliding_safety_factor" in ds:
            out["min_sliding_factor"] = float(ds.sliding_safety_factor.isel(step=-1).min())
    print("RESULT " + json.dumps(out, default=str))


def run_child(name: str) -> dict:
    proc = subprocess.run([sys.executable, __file__, "--child", name], capture_output=True, text=True)
    for line in proc.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    raise RuntimeError(f"run failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", choices=("fill8", "reservoir20"))
    p.add_argument("--child", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.child:
        child(args.child)
        return
    from _common import cpu_model

    print(f"bench_dam_3d_reservoir_fill: one thread, {cpu_model()}")
    for name in ([args.only] if args.only else ["fill8", "reservoir20"]):
        r = run_child(name)
        if r["error"]:
            print(f"{name}: stopped: {r['error']} (stages timed: {r['stage_s']})")
            continue
        stages = "; ".join(f"{s['stage']}: {r['stage_s'].get(s['stage'], float('nan')):.1f} s, {s['steps']} steps, "
                           f"{s['iterations']} it, {s['step_cuts']} cuts" for s in r["per_stage"])
        print(f"{name}: {r['dof']} DOF, {r['joint_points']} joint points; level reached {r['level']:.4g} m, "
              f"completed {r['completed']}, limit {r['limit_kind'] or '-'}; run {r['run_s']:.1f} s; {stages}; "
              f"{r['splits']} joint-space splits, {r['holds']} holds, {r['latches']} bond latches, "
              f"{r['factorizations']} factorizations; lowest sliding factor {r.get('min_sliding_factor', float('nan')):.3g}")
        times = r["stage_s"]
        if "gravity" in times and "reservoir" in times:
            print(f"     reservoir / gravity stage time: {times['reservoir'] / times['gravity']:.2f} (target: at most 1.5)")


if __name__ == "__main__":
    main()
