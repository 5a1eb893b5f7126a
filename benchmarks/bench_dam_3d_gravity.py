"""Gravity stage of a 3D gravity dam of monoliths: ``examples/dam_3d_gravity.toml``, a 60 m
dam of 8 monoliths across a valley 60 m wide at the base and 160 m at the crest, lifts every 6 m, a
rock foundation block, Mohr-Coulomb lift, base and contraction joints, self-weight in 4 steps.

    . .venv/bin/activate
    python benchmarks/bench_dam_3d_gravity.py                       # element_size 6 (42 021 DOF, 8 096 joint points)
    python benchmarks/bench_dam_3d_gravity.py --element-size 6 3    # and 3 (166 068 DOF, 22 488 joint points)
    python benchmarks/bench_dam_3d_gravity.py --reference           # also a tight-tolerance reference run
    python benchmarks/bench_dam_3d_gravity.py --reference --reference-dir /tmp/dam3d_ref   # keep / reuse it

Targets: the gravity stage under 20 s at element_size 6 and under 2 minutes and 8 GB at
element_size 3, with the same final joint states as a tight-tolerance reference run. Measured in an
earlier version (one core): 273 s at element_size 6 (204 Newton iterations, 5 step cuts, one
PARDISO factorization each); at element_size 3 (AMG) no load step had converged after 20 minutes,
at 14.5 GB peak.

Every run goes in a subprocess of its own (so its peak memory is its own), with one thread for
numba, OpenMP, MKL and OpenBLAS. The subprocess first runs the same scene at element_size 20
(untimed: imports, numba cache, PARDISO load), then the scene at the requested size through
``masonrydam.run`` with the result written to a temporary netCDF file. Printed per run:

* the model: DOF, joint points (per joint set), the linear solver backend the run used;
* ``run s``: the ``masonrydam.run`` call (mesh generation, model build, solve, output); ``solve s``:
  the static solver alone (the result's ``solve_wall_time_s``); Newton iterations, factorizations,
  symbolic analyses (``symbolic_analyses``, absent from old results: shown as ``-``), step cuts and
  converged steps; where the static step was solved on the joint unknowns first (``[solver]
  joint_space``, models with few joint unknowns), the joint-space steps and iterations;
* ``peak GiB``: the subprocess's high-water resident memory (VmHWM; it includes the imports and the
  small warm-up run), and ``run GiB``, the resident memory sampled every 5 ms during the timed run;
* the final joint states (stick / slip / open, in total and per joint set), with where the open and
  slipping points are: their number on horizontal (normal along z) and vertical (normal along x)
  faces and the ranges of x (dam axis), y (upstream -> downstream) and z;
* with ``--reference``: the same scene with ``force_tolerance`` 1e-9 and ``energy_tolerance`` 1e-14
  (then 1e-8 / 1e-13 and 1e-7 / 1e-12 if the tighter one does not converge; ``--reference-tolerances``),
  100 iterations a step and 8 step cuts at most: the number of joint points whose final state differs
  from the reference (per set) and max_i |u_i - u_ref,i| / max_i |u_ref,i| over the nodes (Euclidean
  norms per node). Without a converged reference there is no comparison (the run's figures still print).

A run that exceeds ``--timeout`` (default 1800 s) gets SIGTERM (the run stops at the end of its
current step and reports its statistics) and, 60 s later, SIGKILL; a run whose resident memory
passes ``--mem-limit-gb`` (default: the available memory less 2 GiB) is stopped. How far it got is
read back from its (partial) result file. This is a benchmark, not a test: it never fails on a slow
figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import hashlib
import json
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import RssSampler, cpu_model, peak_rss_mib  # noqa: E402

SCENE_FILE = ROOT / "examples" / "dam_3d_gravity.toml"
STATES = ("stick", "slip", "open")
#: reference tolerances (force, energy), tightest first; the first that converges is used
REFERENCE_TOLERANCES = [(1e-9, 1e-14), (1e-8, 1e-13), (1e-7, 1e-12)]
REFERENCE_MAX_ITERATIONS = 100
REFERENCE_MAX_STEP_CUTS = 8
WARMUP_ELEMENT_SIZE = 20.0
#: arrays of a run kept with a stored reference
ARRAYS = ("state", "u", "joint_set", "jx", "jn")


def scene(element_size: float, steps: int | None = None, solver: dict | None = None) -> dict:
    """The scene of ``examples/dam_3d_gravity.toml`` at ``element_size`` (m), with ``steps`` load
    steps in the gravity stage and ``solver`` settings merged into its ``[solver]`` table."""
    import tomllib

    sc = tomllib.loads(SCENE_FILE.read_text())
    sc["mesh"]["parameters"]["element_size"] = float(element_size)
    if steps is not None:
        sc["stages"][0]["steps"] = int(steps)
    if solver:
        sc.setdefault("solver", {}).update(solver)
    return sc


def scene_key(sc: dict) -> str:
    """Hash of everything but the solver settings (a stored reference is reused only for the same model and loads)."""
    d = {k: v for k, v in sc.items() if k != "solver"}
    return hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()[:16]


# -----------------------------------------------------------------------------------------------
# child: one run
# -----------------------------------------------------------------------------------------------


def _heartbeat(label, every, stop):
    import psutil

    proc, t0 = psutil.Process(), time.perf_counter()
    while not stop.wait(every):
        print(f"  [{label}] {time.perf_counter() - t0:.0f} s, RSS {proc.memory_info().rss / 2**30:.2f} GiB",
              file=sys.stderr, flush=True)


def read_result(path: Path) -> dict:
    """Figures of a (possibly partial) result file: statistics, steps, final joint states, displacement."""
    import xarray as xr

    out = {}
    if not path.exists():
        return out
    with xr.open_dataset(path) as ds:
        a = dict(ds.attrs)
        settings = json.loads(a.get("solver_settings", "{}"))
        out["backend"] = settings.get("linear_solver_backend", "?")
        out["status"] = str(a.get("status", "?"))
        out["status_reason"] = str(a.get("status_reason", ""))
        for k in ("newton_iterations", "factorizations", "symbolic_analyses", "step_cuts", "steps",
                  "solve_wall_time_s", "total_wall_time_s", "joint_space_size", "joint_space_steps",
                  "joint_space_iterations", "joint_space_setup_s"):
            if k in a:
                out[k] = float(a[k]) if k.endswith("_s") else int(a[k])
        n = ds.sizes.get("step", 0)
        out["recorded_steps"] = int(n)
        if n:
            out["last_load_factor"] = float(ds.load_factor.values[-1])
            out["iterations_recorded"] = int(ds.iterations.values.sum())
            out["state"] = ds.joint_state.isel(step=-1).values.astype(np.int8)
            out["u"] = ds.displacement.isel(step=-1).values
        out["joint_set"] = ds.joint_set.values
        out["set_names"] = json.loads(ds.joint_set.attrs.get("set_names", "[]"))
        out["jx"] = np.column_stack([ds[f"joint_{c}"].values for c in "xyz"]) if "joint_x" in ds else None
        out["jn"] = np.column_stack([ds[f"joint_normal_{c}"].values for c in "xyz"]) if "joint_normal_x" in ds else None
    return out


def child(spec: dict) -> None:
    import masonrydam
    from masonrydam.errors import MasonrydamError

    label = spec["label"]
    if not spec.get("no_warmup"):
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="dam3d_warm_") as tmp:
            masonrydam.run(scene(WARMUP_ELEMENT_SIZE, spec["steps"], spec["solver"]), output=Path(tmp) / "w.nc").close()
        print(f"  [{label}] warm-up (element_size {WARMUP_ELEMENT_SIZE:g}) {time.perf_counter() - t0:.1f} s",
              file=sys.stderr, flush=True)
    sc = scene(spec["element_size"], spec["steps"], spec["solver"])
    out_nc = Path(spec["output"])
    stop = threading.Event()
    if spec.get("heartbeat", 0) > 0:
        threading.Thread(target=_heartbeat, args=(label, spec["heartbeat"], stop), daemon=True).start()
    error = None
    t0 = time.perf_counter()
    with RssSampler(spec["mem_limit_bytes"]) as smp:
        try:
            masonrydam.run(sc, output=out_nc).close()
        except MasonrydamError as exc:  # ConvergenceError, MechanismError, RunStopped (SIGTERM)
            error = f"{type(exc).__name__}: {exc}"
    wall = time.perf_counter() - t0
    stop.set()
    res = {"run_s": wall, "run_peak_mib": smp.peak, "peak_rss_mib": peak_rss_mib()}
    if error:
        res["error"] = error
    print("JSON:" + json.dumps(res), flush=True)


# -----------------------------------------------------------------------------------------------
# parent
# -----------------------------------------------------------------------------------------------


def run_case(label, element_size, steps, solver, tmp, timeout, mem_limit_gb, heartbeat, no_warmup) -> dict:
    """Run one case in a subprocess; its figures, merged with those of its result file."""
    import psutil

    avail = psutil.virtual_memory().available / 2**30
    limit_gb = min(mem_limit_gb, avail - 2.0) if mem_limit_gb else avail - 2.0
    out_nc = Path(tmp) / f"{label}.nc"
    spec = {"label": label, "element_size": element_size, "steps": steps, "solver": solver, "output": str(out_nc),
            "mem_limit_bytes": int(limit_gb * 2**30), "heartbeat": heartbeat, "no_warmup": no_warmup}
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, __file__, "--child", json.dumps(spec)], stdout=subprocess.PIPE, text=True,
                         cwd=ROOT)
    timed_out = False
    try:
        stdout, _ = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        timed_out = True
        p.send_signal(signal.SIGTERM)  # the run stops at the end of its current step and writes its statistics
        try:
            stdout, _ = p.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            p.kill()
            stdout, _ = p.communicate()
    r = {"label": label, "element_size": element_size, "process_s": time.perf_counter() - t0,
         "mem_limit_gb": limit_gb}
    lines = [ln for ln in (stdout or "").splitlines() if ln.startswith("JSON:")]
    if lines:
        r.update(json.loads(lines[-1][5:]))
    if timed_out:
        r["error"] = f"timeout ({timeout:.0f} s)" + (f"; {r['error']}" if "error" in r else "")
    elif p.returncode != 0 and "error" not in r:
        r["error"] = f"exit status {p.returncode}"
    path = out_nc if out_nc.exists() else out_nc.with_name(out_nc.stem + ".partial.nc")
    try:
        r.update(read_result(path))
    except Exception as exc:  # a file killed before its first block is written
        r.setdefault("error", f"result file unreadable: {exc}")
    return r


def reference(element_size, steps, tmp, args) -> dict:
    """The tight-tolerance reference run (the first tolerance pair of REFERENCE_TOLERANCES that converges),
    reused from / stored in ``--reference-dir`` when given."""
    key = scene_key(scene(element_size, steps))
    store = Path(args.reference_dir) / f"dam3d_ref_es{element_size:g}_{key}.npz" if args.reference_dir else None
    if store is not None and store.exists():
        z = np.load(store, allow_pickle=False)
        meta = json.loads(str(z["meta"]))
        print(f"  reference for element_size {element_size:g} read from {store}")
        return {**meta, **{k: z[k] for k in ARRAYS if k in z.files}, "stored": str(store)}
    r = None
    for ft, et in args.reference_tolerances:
        solver = {"force_tolerance": ft, "energy_tolerance": et, "max_iterations": REFERENCE_MAX_ITERATIONS,
                  "max_step_cuts": REFERENCE_MAX_STEP_CUTS}
        if args.reference_linear_solver:
            solver["linear_solver"] = args.reference_linear_solver
        r = run_case(f"ref_es{element_size:g}_ft{ft:g}", element_size, steps, solver, tmp, args.reference_timeout,
                     args.mem_limit_gb, args.heartbeat, args.no_warmup)
        r["tolerances"] = [ft, et]
        if "error" not in r:
            break
        print(f"  reference at force_tolerance {ft:g} failed: {r['error'][:200]}")
    if store is not None and "error" not in r:
        store.parent.mkdir(parents=True, exist_ok=True)
        meta = {k: v for k, v in r.items() if not isinstance(v, np.ndarray)}
        np.savez(store, meta=json.dumps(meta, default=float), **{k: r[k] for k in ARRAYS if r.get(k) is not None})
    return r


def _where(r, sel):
    """Where the selected joint points are: per orientation (horizontal: normal along z; vertical:
    normal along x), their number and the ranges of x (along the axis), y (upstream -> downstream) and z."""
    if r.get("jx") is None or not sel.any():
        return ""
    horizontal = np.abs(r["jn"][:, 2]) > 0.9 if r.get("jn") is not None else np.ones(len(sel), bool)
    parts = []
    for name, o in (("horizontal", horizontal), ("vertical", ~horizontal)):
        m = sel & o
        if m.any():
            x = r["jx"][m]
            parts.append(f"{m.sum()} {name} at x {x[:, 0].min():.0f}..{x[:, 0].max():.0f}, y {x[:, 1].min():.0f}.."
                         f"{x[:, 1].max():.0f}, z {x[:, 2].min():.0f}..{x[:, 2].max():.0f} m")
    return " (" + "; ".join(parts) + ")"


def report(r, ref=None):
    tag = r["label"]
    if "error" in r:
        print(f"[{tag}] DID NOT FINISH: {r['error'][:400]}")
    an = r.get("symbolic_analyses")
    print(f"[{tag}] backend {r.get('backend', '?')}; run {r.get('run_s', float('nan')):.1f} s, solve "
          f"{r.get('solve_wall_time_s', float('nan')):.1f} s (process {r['process_s']:.1f} s incl. start-up and warm-up); "
          f"{r.get('newton_iterations', r.get('iterations_recorded', '?'))} Newton iterations, "
          f"{r.get('factorizations', '?')} factorizations, {an if an is not None else '-'} symbolic analyses, "
          f"{r.get('step_cuts', '?')} step cuts, {r.get('steps', r.get('recorded_steps', '?'))} steps "
          f"(last load factor {r.get('last_load_factor', float('nan')):.4g}); peak {r.get('peak_rss_mib', float('nan')) / 1024:.2f} GiB, "
          f"run {r.get('run_peak_mib', float('nan')) / 1024:.2f} GiB")
    if r.get("joint_space_size"):
        print(f"[{tag}] static joint space: {r['joint_space_size']} unknowns, {r.get('joint_space_steps', 0)} steps "
              f"solved there, {r.get('joint_space_iterations', 0)} joint-space iterations, set-up "
              f"{r.get('joint_space_setup_s', 0.0):.2f} s")
    if "state" not in r:
        return
    st, js, names = r["state"], r["joint_set"], r["set_names"]
    counts = np.bincount(st.astype(int), minlength=3)
    print(f"[{tag}] final joint states stick/slip/open {counts.tolist()} of {len(st)}")
    for i, name in enumerate(names):
        m = js == i
        c = np.bincount(st[m].astype(int), minlength=3)
        print(f"    {name:<20} {m.sum():>6} points: {c[0]} stick, {c[1]} slip, {c[2]} open")
        for s in (1, 2):
            if c[s]:
                print(f"      {STATES[s]}{_where(r, m & (st == s))}")
    if ref is not None and "state" in ref:
        if len(ref["state"]) != len(st):
            print(f"[{tag}] reference has {len(ref['state'])} joint points, this run {len(st)}: not comparable")
            return
        diff = ref["state"] != st
        per = ", ".join(f"{name} {int((diff & (js == i)).sum())}" for i, name in enumerate(names))
        du = np.linalg.norm(r["u"] - ref["u"], axis=1).max() / np.linalg.norm(ref["u"], axis=1).max()
        print(f"[{tag}] against the reference (tolerances {ref.get('tolerances')}): {int(diff.sum())} joint points in "
              f"another final state ({per}); max |u - u_ref| / max |u_ref| = {du:.2e} "
              f"(max |u_ref| = {np.linalg.norm(ref['u'], axis=1).max() * 1e3:.2f} mm)")


def model_size(element_size):
    """DOF, elements and joint points per set of the model at ``element_size`` (built as ``masonrydam check`` does)."""
    from masonrydam.scene import build_mesh, build_model
    from masonrydam.scene.scene import Scene

    sc = Scene(scene(element_size))
    mesh = build_mesh(sc.normalized, sc.base_dir)
    model = build_model(sc.normalized, mesh)
    ip = {}
    for g in model.igroups:
        ip[g.name] = ip.get(g.name, 0) + g.n_elem * g.nip
    return model.n_dof, mesh.n_elements(), ip


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--element-size", type=float, nargs="+", default=[6.0], help="element sizes (m) to run (default 6)")
    ap.add_argument("--steps", type=int, default=None, help="load steps of the gravity stage (default: the example's, 4)")
    ap.add_argument("--linear-solver", default=None, help="override solver.linear_solver of the timed run (auto, pardiso, superlu, amg)")
    ap.add_argument("--reference", action="store_true", help="also run (or read) the tight-tolerance reference and compare")
    ap.add_argument("--reference-only", action="store_true", help="run only the reference (e.g. to fill --reference-dir)")
    ap.add_argument("--reference-dir", default=None, help="store the reference results here and reuse them (keyed by the scene)")
    ap.add_argument("--reference-tolerances", default=",".join(f"{f:g}:{e:g}" for f, e in REFERENCE_TOLERANCES),
                    help="force:energy tolerance pairs of the reference, tightest first (default %(default)s)")
    ap.add_argument("--reference-linear-solver", default=None, help="linear solver of the reference (default: as the scene, auto)")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per timed run (default 1800)")
    ap.add_argument("--reference-timeout", type=float, default=3600.0, help="seconds per reference run (default 3600)")
    ap.add_argument("--mem-limit-gb", type=float, default=None, help="stop a run whose RSS passes this (default: available - 2 GiB)")
    ap.add_argument("--heartbeat", type=float, default=60.0, help="print elapsed time and RSS of a running case every N s (0: never)")
    ap.add_argument("--no-warmup", action="store_true", help="skip the untimed element_size-20 run in each subprocess")
    ap.add_argument("--json", default=None, help="write the figures to this file")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(json.loads(args.child))
        return
    args.reference_tolerances = [tuple(float(v) for v in pair.split(":")) for pair in args.reference_tolerances.split(",")]
    import psutil

    print(f"# 3D gravity dam (examples/dam_3d_gravity.toml), gravity stage; {cpu_model()}, "
          f"{psutil.virtual_memory().total / 2**30:.0f} GiB, 1 thread")
    results = []
    with tempfile.TemporaryDirectory(prefix="bench_dam3d_") as tmp:
        for h in args.element_size:
            dof, ne, ip = model_size(h)
            print(f"\nelement_size {h:g} m: {dof:,} DOF, {ne:,} elements, {sum(ip.values()):,} joint points "
                  f"({', '.join(f'{k} {v:,}' for k, v in ip.items())})", flush=True)
            ref = None
            if args.reference or args.reference_only:
                ref = reference(h, args.steps, tmp, args)
                report(ref)
                results.append({k: v for k, v in ref.items() if not isinstance(v, np.ndarray)})
            if args.reference_only:
                continue
            solver = {"linear_solver": args.linear_solver} if args.linear_solver else {}
            r = run_case(f"es{h:g}", h, args.steps, solver, tmp, args.timeout, args.mem_limit_gb, args.heartbeat,
                         args.no_warmup)
            report(r, ref)
            results.append({k: v for k, v in r.items() if not isinstance(v, np.ndarray)})
            sys.stdout.flush()
    print("\ntargets: solve under 20 s at element_size 6, under 120 s and 8 GB at element_size 3, "
          "with the reference's final joint states")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1, default=float))


if __name__ == "__main__":
    main()
