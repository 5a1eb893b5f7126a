"""Filling the reservoir of a 3D dam: the static reservoir stage against the gravity stage.

    . .venv/bin/activate
    python benchmarks/bench_dam_3d_reservoir_fill.py                 # the 8-monolith dam, then the 20-monolith one
    python benchmarks/bench_dam_3d_reservoir_fill.py --only fill8    # one of them
    python benchmarks/bench_dam_3d_reservoir_fill.py --only fill8_large   # fill8 at element_size 3 (~9 min)

``fill8``: ``examples/dam_3d_gravity.toml`` (8 monoliths, about 42 000 DOF, 8 096 joint points) with the
``[reservoir]`` of ``examples/dam_3d_reservoir.toml`` (level 57 m, tailwater 3 m, uplift with drains, full head in
cracks) and its second stage (``reservoir``, 2 steps). Earlier versions stopped at about 51-52 m with "no
convergence" while every joint line held with margin (lowest sliding factor 5.3): points at the tip of the crack
in the cohesive dam-rock joint flipped between open (bond broken, no shear) and closed (bond intact, shear up to
c) from one joint-space iteration to the next. ``reservoir20``: ``examples/dam_3d_reservoir.toml`` as it is (20
monoliths, about 63 000 DOF). ``fill8_large`` (asked for by name only): ``fill8`` at element_size 3 (166 068 DOF,
22 488 joint points), whose static stages take the general Newton path with AMG (no joint space). Target: the water reaches 57 m (or a physical limit), the reservoir stage costs at
most 1.5x the gravity stage.

Printed per run (each in a subprocess of its own, one thread for numba, OpenMP, MKL and OpenBLAS, after an
untimed warm-up run of a small 3D dam with water that compiles the kernels): the model, the level reached and
the limit (if any), the wall time of each stage (from the start of the static solve to its last converged step),
its steps, Newton iterations (joint space and general) and step cuts, the joint-space splits, holds and bond
latches, the lowest sliding factor, and the ratio reservoir / gravity.

With ``--reference`` each scene is run a second time with ``force_tolerance`` 1e-9, ``energy_tolerance`` 1e-14,
100 iterations a step and 8 step cuts (as ``bench_dam_3d_gravity.py --reference``; then 1e-8 / 1e-13 if that does
not converge), and the final joint states and displacements are compared with it: the number of joint points in
another state and max_i |u_i - u_ref,i| / max_i |u_ref,i| over the nodes (Euclidean norms per node);
``--reference-dir`` keeps and reuses the reference runs.

The figures before (``BEFORE``) are printed with those measured now: in an earlier version the 8-monolith dam
stopped at about 51-52 m; after the joint space's bond latch was added it filled in 9 steps, 807 iterations, 8 cuts and 8
joint-space splits (reservoir 101.5 s against gravity 28.5 s); the 20-monolith scene took 192 s dry and 515 s wet.

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
#: figures measured before (one thread): in an earlier version, and with the bond latch of the joint space
BEFORE = {
    "fill8": ["earlier version: stopped at about 51-52 m, 'no convergence' (lowest sliding factor 5.3)",
              "with the bond latch: level 57 m; gravity 28.5 s; reservoir 101.5 s, 9 steps, 807 it, 8 cuts, 8 joint-space splits "
              "(ratio 3.57)"],
    "reservoir20": ["earlier version: gravity 192 s, reservoir 515 s (ratio 2.68)"],
    "fill8_large": ["earlier version: the reservoir's first step cut at 30 iterations, its halves converging by 10-25 % an "
                    "iteration: not at the shaking after 13 minutes (gravity 119.5-122.6 s)"],
}
#: solver settings of the tight-tolerance reference runs, tightest first (the first that converges is used)
REFERENCE_SOLVERS = [{"force_tolerance": 1e-9, "energy_tolerance": 1e-14, "max_iterations": 100, "max_step_cuts": 8},
                     {"force_tolerance": 1e-8, "energy_tolerance": 1e-13, "max_iterations": 100, "max_step_cuts": 8}]
GRAVITY = ROOT / "examples" / "dam_3d_gravity.toml"
RESERVOIR = ROOT / "examples" / "dam_3d_reservoir.toml"


def scene_of(name: str) -> dict:
    """The scene ``fill8``, ``fill8_large`` or ``reservoir20`` (see the module docstring)."""
    wet = tomllib.loads(RESERVOIR.read_text())
    if name == "reservoir20":
        return wet
    scene = tomllib.loads(GRAVITY.read_text())
    scene["reservoir"] = wet["reservoir"]
    scene["stages"].append({"name": "reservoir", "steps": 2, "loads": [{"type": "reservoir"}]})
    if name == "fill8_large":
        scene["mesh"]["parameters"]["element_size"] = 3.0
    return scene


def child(name: str, solver: dict | None = None, arrays: str | None = None) -> None:
    """Run one scene (with ``solver`` settings merged into its ``[solver]``) with its stages timed; print a JSON
    line of figures; with ``arrays``, save the final joint states and displacements there (.npz)."""
    import importlib
    import time
    import warnings

    import numpy as np

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
    if solver:
        scene.setdefault("solver", {}).update(solver)
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
        if arrays:
            np.savez(arrays, state=ds.joint_state.isel(step=-1).values.astype(np.int8),
                     u=ds.displacement.isel(step=-1).values, level=out["level"])
    print("RESULT " + json.dumps(out, default=str))


def run_child(name: str, solver: dict | None = None, arrays: str | None = None) -> dict:
    cmd = [sys.executable, __file__, "--child", name, "--solver", json.dumps(solver or {})]
    return child_result(cmd + (["--arrays", arrays] if arrays else []))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", choices=("fill8", "reservoir20", "fill8_large"))
    p.add_argument("--reference", action="store_true", help="also run (or read) the tight-tolerance reference and compare")
    p.add_argument("--reference-dir", default=None, help="keep the reference results here and reuse them")
    p.add_argument("--child", help=argparse.SUPPRESS)
    p.add_argument("--solver", default="{}", help=argparse.SUPPRESS)
    p.add_argument("--arrays", default=None, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.child:
        child(args.child, json.loads(args.solver), args.arrays)
        return
    import tempfile

    from _common import cpu_model

    print(f"bench_dam_3d_reservoir_fill: one thread, {cpu_model()}")
    tmp = tempfile.TemporaryDirectory(prefix="reservoir_fill_")
    for name in ([args.only] if args.only else ["fill8", "reservoir20"]):
        for line in BEFORE[name]:
            print(f"{name} before, {line}")
        now = str(Path(tmp.name) / f"{name}.npz")
        r = run_child(name, arrays=now)
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
        if args.reference:
            compare(name, now, reference(name, args.reference_dir, tmp.name))


def reference(name: str, store_dir: str | None, tmp: str) -> str | None:
    """Path of the .npz of the tight-tolerance reference run of ``name`` (run now, or read from ``store_dir``)."""
    import hashlib

    key = hashlib.sha256(json.dumps(scene_of(name), sort_keys=True, default=str).encode()).hexdigest()[:16]
    if store_dir:
        store = Path(store_dir) / f"reservoir_fill_ref_{name}_{key}.npz"
        if store.exists():
            print(f"     reference read from {store}")
            return str(store)
    for solver in REFERENCE_SOLVERS:
        path = str(Path(store_dir or tmp) / f"reservoir_fill_ref_{name}_{key}.npz")
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        r = run_child(name, solver, path)
        if not r["error"] and r.get("completed") in (True, "true", "True", 1):
            print(f"     reference (force_tolerance {solver['force_tolerance']:g}): {r['run_s']:.1f} s, "
                  + "; ".join(f"{s['stage']} {s['steps']} steps, {s['iterations']} it, {s['step_cuts']} cuts"
                              for s in r["per_stage"]))
            return path
        print(f"     reference at force_tolerance {solver['force_tolerance']:g} failed: {r['error'] or r.get('limit_state')}")
    return None


def compare(name: str, now: str, ref: str | None) -> None:
    """Final joint states and displacements of this run against the reference."""
    import numpy as np

    if ref is None or not Path(now).exists():
        print(f"     {name}: no comparison (no reference or no result)")
        return
    a, b = np.load(now), np.load(ref)
    if a["state"].shape != b["state"].shape:
        print(f"     {name}: not comparable ({a['state'].shape} against {b['state'].shape} joint points)")
        return
    diff = int((a["state"] != b["state"]).sum())
    du = np.linalg.norm(a["u"] - b["u"], axis=1).max() / np.linalg.norm(b["u"], axis=1).max()
    print(f"     against the reference: {diff} of {a['state'].size} joint points in another final state; "
          f"max |u - u_ref| / max |u_ref| = {du:.2e} (max |u_ref| = {np.linalg.norm(b['u'], axis=1).max() * 1e3:.2f} mm)")


if __name__ == "__main__":
    main()
