"""Wall time of ``masonrydam run --default``, cold (fresh numba cache) and warm, in subprocesses.

    /work/venv/bin/python benchmarks/bench_default_scene.py [--cold N] [--warm N]

* cold: ``NUMBA_CACHE_DIR`` points to a fresh, empty temporary directory, so every kernel is compiled;
* warm: the same command again with that cache directory filled by the cold run (what a user sees
  from the second run on).

Each run is ``masonrydam run --default -o <tmp>/wall_push.nc --no-progress`` in a temporary working
directory. Reported: the process wall time (interpreter start, imports, JIT or cache load, build,
solve, netCDF writing, summary) and the figures the run prints itself in its summary ("wall time" = the
process's from its start to the summary (in earlier versions ``masonrydam.run`` from scene to dataset;
"solve" = the static solver), plus steps, iterations and
factorizations, so that a change in the Newton path is visible next to a change in speed.

Before them, ``masonrydam --version`` and ``masonrydam --help`` are timed as whole processes (target:
under 0.3 s on any machine; the commands import the solvers, xarray and numba only when a command needs them).

Then, in this process, one more warm run with a few package functions wrapped (benchmark-only
instrumentation) shows where the time goes: factorizations, solves, joint evaluation + assembly,
and converged versus failed (cut) step attempts.

This is a benchmark, not a test: it prints tables and never fails on a slow figure.
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


from _common import cpu_model  # noqa: E402  (benchmarks/ is sys.path[0] when run as a script)


def command() -> list[str]:
    exe = Path(sys.executable).parent / "masonrydam"
    if exe.exists():
        return [str(exe)]
    return [sys.executable, "-c", "import sys; from masonrydam.cli.main import main; sys.exit(main())"]


def run_once(cache_dir: str) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    with tempfile.TemporaryDirectory(prefix="bench_default_") as wd:
        cmd = command() + ["run", "--default", "-o", str(Path(wd) / "wall_push.nc"), "--no-progress"]
        t0 = time.perf_counter()
        p = subprocess.run(cmd, env=env, cwd=wd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    out = p.stdout
    d = {"process": wall}
    m = re.search(r"wall time\s*:\s*([\d.]+) s \(solve ([\d.]+) s\)", out)
    if m:
        d["run"], d["solve"] = float(m.group(1)), float(m.group(2))
    m = re.search(r"solver\s*:.*?(\d+) factorization\(s\) \[(\w+)[^\]]*\], (\d+) (?:general Newton )?iterations", out)
    if m:
        d["factorizations"], d["backend"], d["iterations"] = int(m.group(1)), m.group(2), int(m.group(3))
    d["steps"] = sum(int(s) for s in re.findall(r"stage\s*:.*?: (\d+) steps", out))
    d["step_cuts"] = sum(int(s) for s in re.findall(r"(\d+) step cuts", out))
    m = re.search(r"model\s*:\s*(.*)", out)
    d["model"] = m.group(1).strip() if m else "?"
    return d


def startup(n: int = 5) -> None:
    """Whole-process wall time of ``masonrydam --version`` and ``--help`` (best and median of ``n``)."""
    for flag in ("--version", "--help"):
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            p = subprocess.run(command() + [flag], capture_output=True, text=True)
            times.append(time.perf_counter() - t0)
            if p.returncode != 0:
                raise RuntimeError(f"masonrydam {flag} failed ({p.returncode}):\n{p.stderr}")
        print(f"masonrydam {flag:<9}: min {min(times):.3f} s, median {statistics.median(times):.3f} s over {n} "
              f"runs (target: under 0.3 s)")


def breakdown():
    """In this process (warm): where a run's time goes, by wrapping a few package functions.

    Wrapped (benchmark-only instrumentation, the package is not modified): ``Factorization.__init__``
    (factorization), ``Factorization.solve``, ``Model.evaluate`` (joint evaluation + assembly) and
    ``StaticSolver._newton`` (one step attempt: converged or cut).
    """
    import masonrydam
    from masonrydam.assembly.model import Model
    from masonrydam.cli.main import default_scene_path
    from masonrydam.solvers.linear import direct as linear
    from masonrydam.solvers.static import stepping as static

    scene = default_scene_path()
    masonrydam.run(scene)  # warm-up (JIT / cache load)
    acc = {"factorize": [0.0, 0], "refactorize": [0.0, 0], "solve": [0.0, 0], "evaluate": [0.0, 0]}
    attempts = []

    def timed(key, fn):
        def w(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                acc[key][0] += time.perf_counter() - t0
                acc[key][1] += 1
        return w

    orig = (linear.Factorization.__init__, linear.Factorization.solve, Model.evaluate, static.StaticSolver._newton,
            linear.Factorization.refactorize)

    def newton(self, u, f_ext, *rest):
        def done():  # general and joint-space Newton iterations
            return self.stats.iterations + getattr(self.stats, "joint_space_iterations", 0)

        it0, t0 = done(), time.perf_counter()
        ok = False
        try:
            res = orig[3](self, u, f_ext, *rest)
            ok = bool(res[0])
            return res
        finally:
            attempts.append((ok, done() - it0, time.perf_counter() - t0))

    linear.Factorization.__init__ = timed("factorize", orig[0])
    linear.Factorization.solve = timed("solve", orig[1])
    Model.evaluate = timed("evaluate", orig[2])
    static.StaticSolver._newton = newton
    linear.Factorization.refactorize = timed("refactorize", orig[4])
    try:
        t0 = time.perf_counter()
        masonrydam.run(scene)
        total = time.perf_counter() - t0
    finally:
        (linear.Factorization.__init__, linear.Factorization.solve, Model.evaluate,
         static.StaticSolver._newton, linear.Factorization.refactorize) = orig
    print("\nWhere the time goes (one warm run in this process, masonrydam.run wall "
          f"{total:.2f} s)")
    print(f"{'part':<54} {'calls':>6} {'time s':>8} {'share':>6}")
    print("-" * 77)
    for key, label in (("factorize", "Factorization (linear.Factorization.__init__)"),
                       ("refactorize", "refactorization with the kept analysis (refactorize)"),
                       ("solve", "Factorization.solve (incl. residual check)"),
                       ("evaluate", "Model.evaluate (joints + assembly, incl. line search)")):
        t, n = acc[key]
        print(f"{label:<54} {n:>6} {t:>8.3f} {t / total:>6.1%}")
    for ok, name in ((True, "converged step attempts"), (False, "failed step attempts (cut)")):
        sel = [a for a in attempts if a[0] == ok]
        print(f"{name:<54} {len(sel):>6} {sum(a[2] for a in sel):>8.3f} "
              f"{sum(a[2] for a in sel) / total:>6.1%}   {sum(a[1] for a in sel)} Newton iterations")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cold", type=int, default=2, help="cold runs, each with its own fresh cache (default 2, at least 1)")
    ap.add_argument("--warm", type=int, default=3, help="warm runs after the first cold run (default 3)")
    ap.add_argument("--no-breakdown", action="store_true", help="skip the in-process time breakdown")
    a = ap.parse_args()
    a.cold = max(a.cold, 1)  # the warm runs use the cache of the first cold run
    print(f"masonrydam run --default | CPU: {cpu_model()} ({os.cpu_count()} logical cores) | {' '.join(command())}")
    startup()
    rows = []
    caches = []
    try:
        for i in range(a.cold):
            c = tempfile.mkdtemp(prefix="numba_cache_")
            caches.append(c)
            rows.append(("cold (fresh NUMBA_CACHE_DIR)", run_once(c)))
        for i in range(a.warm):
            rows.append(("warm (cache filled by cold run 1)", run_once(caches[0])))
    finally:
        for c in caches:
            shutil.rmtree(c, ignore_errors=True)
    print(f"model: {rows[0][1]['model']}")
    hdr = (f"{'run':<36} {'process s':>9} {'run() s':>8} {'solve s':>8} {'outside run() s':>15} {'steps':>6} "
           f"{'cuts':>5} {'iters':>6} {'factor.':>8} {'backend':>8}")
    print(hdr)
    print("-" * len(hdr))
    for name, d in rows:
        print(f"{name:<36} {d['process']:>9.2f} {d.get('run', float('nan')):>8.2f} {d.get('solve', float('nan')):>8.2f} "
              f"{d['process'] - d.get('run', 0):>15.2f} {d['steps']:>6} {d['step_cuts']:>5} {d.get('iterations', -1):>6} "
              f"{d.get('factorizations', -1):>8} {d.get('backend', '?'):>8}")
    for kind in ("cold", "warm"):
        ps = [d["process"] for n, d in rows if n.startswith(kind)]
        if ps:
            print(f"{kind}: process wall min {min(ps):.2f} s, median {statistics.median(ps):.2f} s over {len(ps)} run(s)")
    print("process = whole subprocess, timed here; run() = the 'wall time' the summary prints (now the "
          "process's own clock from its start to the summary, JIT included when cold; before, scene to dataset); "
          "solve = static solver; outside run() = what the summary does not count (fork and exec).")
    if not a.no_breakdown:
        breakdown()


if __name__ == "__main__":
    main()
