"""Seismic steps of models with large joint sets: the 8 x 4 m dry-joint wall and the 3D dam.

    . .venv/bin/activate
    python benchmarks/bench_large_seismic.py                          # both cases, joint space on (default)
    python benchmarks/bench_large_seismic.py --case wall --duration 4 # the wall's target figure
    python benchmarks/bench_large_seismic.py --case dam3d --joint-space off   # the general Newton path

Cases (each run in a subprocess of its own, one thread for numba, MKL and OpenBLAS, after an untimed
run of a small model that fills the numba cache):

* ``wall``: ``examples/wall_el_centro.toml`` scaled to a wall 8 m long and 4 m high (a
  56 000-DOF, 20 400-joint-point wall), El Centro 1940 NS at 0.7 g with the vertical component, HHT
  with the example's dt = "auto" (or ``--wall-dt``, a fixed step: the earlier figure was at 0.005 s),
  ``--duration`` seconds of the record (default 4, the target's window). Also printed: the dynamic stage's time
  over the flexibility columns' (target for the wall: at most 2x).
* ``dam3d``: ``examples/dam_3d_gravity.toml`` at element_size 6 (42 021 DOF, 8 096 joint points)
  after its gravity stage, El Centro 1940 NS along y (upstream-downstream) and EW along x (the dam
  axis), HHT at dt 0.01 s, 5 % Rayleigh damping at 2 and 10 Hz on the blocks. Two intensities:
  ``--dam-weak-pga`` (default 0.02 g: every joint point sticks, the target's "while joints stick") and
  ``--dam-strong-pga`` (default 0.5 g, strong shaking), over ``--dam-duration`` seconds (default 3).

Printed per run: DOF, joint unknowns, steps, ms per step of the time stepping (the result's
``dynamic_ms_per_step``: the dynamic stage's wall time less its output, divided by its steps; the
set-up of the all-stick factorization and of the joint space included), the set-up alone, steps
solved in joint space, halved steps and steps finished by the general path, joint-space iterations,
flexibility columns computed when first needed and their time, general Newton iterations and
factorizations, peak resident memory, and the peak displacement of the monitored nodes (top of the
wall, dam crest) as a check that the runs compared are the same analysis.

Targets (2-core machine, one thread): the wall at most 40 ms per step over the first 4 s
at 0.7 g (171 ms in an earlier version); the 3D dam at most 100 ms per step while its joints stick and 300 ms
per step in strong shaking (1.27 s in an earlier version). This is a benchmark, not a test: it never fails on a
slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import copy
import json
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _common import RssSampler, cpu_model  # noqa: E402


def wall_scene(duration, joint_space, length=8.0, height=4.0, dt=None):
    """The wall example scaled to ``length`` x ``height`` m, ``duration`` s of El Centro at 0.7 g; ``dt`` a fixed
    step (s), or None for the example's own (dt = "auto")."""
    sc = tomllib.loads((ROOT / "examples" / "wall_el_centro.toml").read_text())
    sc["mesh"]["parameters"].update(length=length, height=height)
    if dt is not None:
        from masonrydam.scene.schema import set_time_steps

        set_time_steps(sc["stages"][1], dt)
    sc["stages"][1]["duration"] = duration
    sc["stages"][1]["joint_space"] = joint_space
    sc["solver"] = dict(sc.get("solver", {}), joint_space=joint_space)
    return sc


def dam_scene(pga, duration, joint_space, element_size=6.0):
    """The 3D dam example after gravity, ``duration`` s of El Centro NS (y) and EW (x) at ``pga`` g."""
    sc = tomllib.loads((ROOT / "examples" / "dam_3d_gravity.toml").read_text())
    sc["mesh"]["parameters"]["element_size"] = element_size
    sc["solver"] = dict(sc.get("solver", {}), joint_space=joint_space)
    sc["stages"].append({
        "name": "el_centro", "type": "dynamic", "dt": 0.01, "duration": duration, "integrator": "hht",
        "alpha": -0.1, "joint_space": joint_space,
        "damping": {"ratio": 0.05, "frequencies": [2.0, 10.0], "exclude_joints": True},
        "ground_motion": {"y": {"record": "elcentro_1940_ns_ngaw2", "scale_to_pga": f"{pga} g"},
                          "x": {"record": "elcentro_1940_ew_ngaw2", "scale_to_pga": f"{pga} g"}},
        "output": {"stride": 10, "nodes": ["crest"]},
    })
    return sc


def child(spec):
    """Run one scene (after a small warm-up) and print its figures as a JSON line."""
    import numpy as np

    import masonrydam

    warm = copy.deepcopy(spec["scene"])
    if spec["case"] == "wall":
        warm["mesh"]["parameters"].update(length=1.0, height=0.6)
    else:
        warm["mesh"]["parameters"]["element_size"] = 20.0
    warm["stages"][-1]["duration"] = 0.05
    masonrydam.run(warm)
    with tempfile.TemporaryDirectory() as tmp, RssSampler() as rss:
        t0 = time.perf_counter()
        ds = masonrydam.run(spec["scene"], Path(tmp) / "out.nc")
        wall_s = time.perf_counter() - t0
        a = dict(ds.attrs)
        disp = ds["displacement"].values if "displacement" in ds else np.zeros(1)
        peak = float(np.abs(disp).max())
        ds.close()
    keys = ("dynamic_steps", "dynamic_ms_per_step", "dynamic_joint_space_size", "dynamic_joint_space_setup_s",
            "dynamic_joint_space_steps", "dynamic_joint_space_splits", "dynamic_joint_space_fallbacks",
            "dynamic_joint_space_iterations", "dynamic_joint_space_flexibility_columns",
            "dynamic_joint_space_flexibility_s", "dynamic_newton_iterations", "dynamic_factorizations",
            "dynamic_substeps", "dynamic_wall_time_s", "completed")
    out = {k: (a[k].item() if hasattr(a.get(k), "item") else a.get(k)) for k in keys}
    out.update(run_s=wall_s, peak_gib=rss.peak / 1024, peak_displacement_m=peak)
    print("JSON:" + json.dumps(out), flush=True)


def run_case(label, case, scene, timeout):
    spec = {"case": case, "scene": scene}
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, __file__, "--child", json.dumps(spec)], capture_output=True, text=True,
                           timeout=timeout)
    except subprocess.TimeoutExpired:
        print(f"[{label}] over the {timeout} s limit", flush=True)
        return None
    lines = [x for x in p.stdout.splitlines() if x.startswith("JSON:")]
    if p.returncode or not lines:
        print(f"[{label}] failed (exit {p.returncode}): {p.stderr.strip().splitlines()[-3:]}", flush=True)
        return None
    r = json.loads(lines[-1][5:])
    print(f"[{label}] {r['dynamic_steps']} steps, {r['dynamic_ms_per_step']:.1f} ms/step "
          f"(joint space: {r['dynamic_joint_space_size']} unknowns, set-up {r['dynamic_joint_space_setup_s']:.2f} s, "
          f"{r['dynamic_joint_space_steps']} steps, {r['dynamic_joint_space_iterations']} iterations, "
          f"{r['dynamic_joint_space_splits']} halved, {r['dynamic_joint_space_fallbacks']} general-path finishes, "
          f"{r['dynamic_joint_space_flexibility_columns']} columns in {r['dynamic_joint_space_flexibility_s']:.2f} s; "
          f"general path {r['dynamic_newton_iterations']} iterations, {r['dynamic_factorizations']} factorizations, "
          f"{r['dynamic_substeps']} sub-step splits); run {r['run_s']:.1f} s, peak {r['peak_gib']:.2f} GiB, "
          f"peak displacement {1e3 * r['peak_displacement_m']:.3f} mm, completed {r['completed']} "
          f"(process {time.perf_counter() - t0:.0f} s)", flush=True)
    if case == "wall" and r["dynamic_joint_space_flexibility_s"]:
        # the target for the wall: its stepping against the flexibility columns it had to compute
        print(f"[{label}] dynamic stage {r['dynamic_wall_time_s']:.1f} s = "
              f"{r['dynamic_wall_time_s'] / r['dynamic_joint_space_flexibility_s']:.2f}x its flexibility-column "
              "work (target: at most 2x)", flush=True)
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", choices=("wall", "dam3d", "both"), default="both")
    ap.add_argument("--joint-space", choices=("auto", "off"), default="auto")
    ap.add_argument("--duration", type=float, default=4.0, help="seconds of the record for the wall")
    ap.add_argument("--wall-dt", type=float, default=None,
                    help="a fixed step for the wall (s; the earlier figure: 0.005); default the example's dt = auto")
    ap.add_argument("--dam-duration", type=float, default=3.0)
    ap.add_argument("--dam-weak-pga", type=float, default=0.02)
    ap.add_argument("--dam-strong-pga", type=float, default=0.5)
    ap.add_argument("--timeout", type=float, default=3600)
    ap.add_argument("--child", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(json.loads(a.child))
        return
    print(f"# seismic steps with large joint sets; {cpu_model()}, 1 thread, joint_space = {a.joint_space}", flush=True)
    if a.case in ("wall", "both"):
        run_case(f"wall 8 x 4 m, 0.7 g, {a.duration:g} s", "wall", wall_scene(a.duration, a.joint_space, dt=a.wall_dt), a.timeout)
    if a.case in ("dam3d", "both"):
        for pga in (a.dam_weak_pga, a.dam_strong_pga):
            run_case(f"3D dam es6, {pga:g} g, {a.dam_duration:g} s", "dam3d",
                     dam_scene(pga, a.dam_duration, a.joint_space), a.timeout)


if __name__ == "__main__":
    main()
