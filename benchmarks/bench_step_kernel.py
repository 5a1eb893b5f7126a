"""What a dynamic step costs against its arithmetic: the compiled step loop (masonrydam.solvers.dynamic.compiled_loop),
the compiled joint-space step alone (masonrydam.solvers.joint_space.step_kernel) and the Python loop they replace, on the Koyna section of examples/koyna_el_centro.toml (Chopra &
Chakrabarti 1973 profile, Mohr-Coulomb lift and base joints, El Centro 1940 at 0.5 g).

    python benchmarks/bench_step_kernel.py [--cases coarse_fixed coarse_auto example] [--example-duration 4]
                                          [--repeats 2]

Cases: ``coarse_fixed`` the section at element_size 12 m (358 DOF, 88 joint points), trapezoidal rule at dt
2.5 ms, 2 000 steps; ``coarse_auto`` the same with dt = "auto" (dt_max 10 ms) over 1.5 s; ``example`` the
example itself (element_size 1.45 m, about 7 500 DOF, 588 joint points, dt = "auto") over its first
``--example-duration`` s of record. Each case runs on the three paths in turn, ``--repeats`` times (the machine's
timing noise is about 10 %), and prints per path: ms a step of the dynamic stage, the joint-space solve's share
(not separable inside the loop) and whether the datasets are equal bit for bit.

Then, for the coarse section, the floor a step is measured against (target 1): one substitution with
the all-stick factor plus one pass of the joint law over every point, timed here, and the step's cost as a
multiple of it; and the step's own joint-space arithmetic (the compiled kernel's time: capacitance LU
factorizations and updates, law passes of the line search) as a multiple of the same floor. For the example,
the floor of target 2: the substitutions and the full joint-law passes its steps made (counted in the Python
loop), each at its cost timed on the example's own factor and points, against the dynamic stage's wall time
(``--example-duration 40`` for the whole record). A benchmark, not a test: it never fails on a slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import tomllib  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402

EXAMPLES = ROOT / "examples"


def scene(case: str, example_duration: float):
    from masonrydam.scene import Scene
    from masonrydam.scene.schema import set_time_steps

    sc = tomllib.loads((EXAMPLES / "koyna_el_centro.toml").read_text())
    stage = sc["stages"][1]
    if case == "example":
        stage["duration"] = example_duration
        stage["output"] = {"dt": 0.02, "nodes": ["crest"]}
        return Scene(sc, base_dir=EXAMPLES)
    sc["mesh"]["parameters"]["element_size"] = 12.0
    if case == "coarse_auto":
        stage = set_time_steps(stage, "auto", duration=1.5)
        stage["dt_max"] = 0.01
        stage["output"] = {"dt": 0.01, "nodes": ["crest"]}
    else:
        stage = set_time_steps(stage, 0.0025, steps=2000)
        stage["output"] = {"stride": 10, "nodes": ["crest"]}
    stage["integrator"] = "newmark_average"
    stage.pop("alpha", None)
    sc["stages"][1] = stage
    return Scene(sc, base_dir=EXAMPLES)


class Recorder:
    """Times every joint-space solve of a run and keeps the last joint-space system (its factor and point
    arrays, for the floor). In the Python loop it also counts the work the floor is made of: the substitutions
    with the all-stick factor (the predictor, and the recovery of the displacements where the stored columns
    are not used) and the full passes of the joint law over every point (``joint_points_evaluate``; the passes
    over the few points whose held flag changed are counted apart, as ``partial``). The compiled step does the
    same arithmetic (the datasets are equal bit for bit), so these are its counts too."""

    def __init__(self):
        from masonrydam.solvers.joint_space import condensation
        from masonrydam.solvers.linear import direct

        self.module = condensation
        self.original = condensation.JointSpace.solve_step
        self.seconds, self.calls, self.last = 0.0, 0, None
        self.substitutions = self.law_passes = self.partial_passes = 0
        self._in_step = False
        rec = self

        def timed(js, *args, **kwargs):
            t0 = time.perf_counter()
            rec._in_step = True
            try:
                return rec.original(js, *args, **kwargs)
            finally:
                rec._in_step = False
                rec.seconds += time.perf_counter() - t0
                rec.calls += 1
                rec.last = js

        condensation.JointSpace.solve_step = timed

        from masonrydam.solvers.dynamic import compiled_loop

        self.loop_seconds = 0.0
        loop_call = compiled_loop.CompiledLoop._call

        def timed_loop(loop, *args, **kwargs):
            t0 = time.perf_counter()
            try:
                return loop_call(loop, *args, **kwargs)
            finally:
                rec.loop_seconds += time.perf_counter() - t0

        compiled_loop.CompiledLoop._call = timed_loop

        def counted(original, attribute):
            def wrapper(*args, **kwargs):
                if rec._in_step:
                    setattr(rec, attribute, getattr(rec, attribute) + 1)
                return original(*args, **kwargs)
            return wrapper

        direct.SymmetricFactorization.solve = counted(direct.SymmetricFactorization.solve, "substitutions")
        condensation.joint_points_evaluate = counted(condensation.joint_points_evaluate, "law_passes")
        condensation.joint_space_reevaluate_points = counted(condensation.joint_space_reevaluate_points,
                                                             "partial_passes")

    def reset(self):
        self.seconds, self.calls, self.loop_seconds = 0.0, 0, 0.0
        self.substitutions = self.law_passes = self.partial_passes = 0


#: the paths compared: the compiled step loop (many steps a call), the compiled joint-space step alone (one call a
#: step, the rest of the step in Python), and the Python loop
PATHS = ("loop", "kernel", "python")


def run(case, path, rec, example_duration):
    import masonrydam
    from masonrydam.solvers.dynamic import compiled_loop

    rec.module.COMPILED_STEP = path != "python"
    compiled_loop.COMPILED_LOOP = path == "loop"
    rec.reset()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = masonrydam.run(scene(case, example_duration))
    steps = int(ds.attrs["dynamic_steps"])
    return ds, {"ms_per_step": 1e3 * float(ds.attrs["dynamic_wall_time_s"]) / steps,
                "loop_steps": int(ds.attrs["dynamic_compiled_loop_steps"]), "loop_s": rec.loop_seconds,
                "js_ms_per_step": 1e3 * rec.seconds / steps, "steps": steps, "attempts": rec.calls,
                "wall_s": float(ds.attrs["dynamic_wall_time_s"]), "substitutions": rec.substitutions,
                "law_passes": rec.law_passes, "partial_passes": rec.partial_passes}


def same(a, b) -> bool:
    for name in a.data_vars:
        x, y = a[name].values, b[name].values
        if not np.array_equal(x, y, equal_nan=x.dtype.kind == "f"):
            return False
    return True


def floor_us(js, repeats=2000):
    """(one substitution with the all-stick factor, one pass of the joint law over every point), in us."""
    from masonrydam.solvers.joint_space.kernels import joint_points_evaluate
    from masonrydam.solvers.linear.ldlt_kernels import ldlt_solve_vector

    Lp, Li, Lx, d, perm = js.fact.factor_arrays
    n = len(d)
    b, x, w = np.random.default_rng(0).standard_normal(n), np.empty(n), np.empty(n)
    delta = np.zeros((js.n_points, js.dim))
    ldlt_solve_vector(Lp, Li, Lx, d, perm, b, x, w)
    t0 = time.perf_counter()
    for _ in range(repeats):
        ldlt_solve_vector(Lp, Li, Lx, d, perm, b, x, w)
    sub = (time.perf_counter() - t0) / repeats
    args = (js.params_table, js.param_index, js.weight, delta, js.base, js.trial.copy(), js.traction.copy(),
            js.q.copy(), js.qt.copy(), js.codes.copy(), js.info, np.zeros(js.n_points, dtype=np.int8))
    joint_points_evaluate(*args)
    t0 = time.perf_counter()
    for _ in range(repeats):
        joint_points_evaluate(*args)
    law = (time.perf_counter() - t0) / repeats
    return 1e6 * sub, 1e6 * law


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", nargs="+", default=["coarse_fixed", "coarse_auto", "example"],
                    choices=["coarse_fixed", "coarse_auto", "example"])
    ap.add_argument("--example-duration", type=float, default=4.0)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    rec = Recorder()
    print(f"# dynamic steps: the compiled step loop, the compiled joint-space step alone and the Python loop "
          f"({cpu_model()}, 1 thread)")
    run("coarse_fixed", "loop", rec, 0.1)  # numba's caches loaded (or compiled) outside the timings
    for case in args.cases:
        figures = {path: [] for path in PATHS}
        datasets = {}
        for _ in range(args.repeats):
            for path in PATHS:
                ds, f = run(case, path, rec, args.example_duration)
                figures[path].append(f)
                datasets[path] = ds
        equal = all(same(datasets[path], datasets["python"]) for path in PATHS)
        print(f"\n[{case}] {figures['python'][0]['steps']} steps, {figures['python'][0]['attempts']} joint-space "
              f"attempts; {figures['loop'][0]['loop_steps']} steps in the compiled loop; datasets "
              f"{'equal bit for bit' if equal else 'DIFFER'}")
        for path in PATHS:
            ms = sorted(f["ms_per_step"] for f in figures[path])
            js = sorted(f["js_ms_per_step"] for f in figures[path])
            print(f"  {path:7s}: {ms[0]:.3f}-{ms[-1]:.3f} ms/step"
                  + (f", of which the joint-space solve {js[0]:.3f}-{js[-1]:.3f} ms" if path != "loop" else ""))
        if rec.last is None:
            continue
        sub, law = floor_us(rec.last, 2000 if case.startswith("coarse") else 200)
        if case.startswith("coarse"):
            step = 1e3 * min(f["ms_per_step"] for f in figures["loop"])
            step_kernel = 1e3 * min(f["ms_per_step"] for f in figures["kernel"])
            solve = 1e3 * min(f["js_ms_per_step"] for f in figures["kernel"])
            base = sub + law
            loop_steps = figures["loop"][0]["loop_steps"]
            own = 1e6 * min(f["loop_s"] for f in figures["loop"]) / max(loop_steps, 1)
            print(f"  floor: one substitution {sub:.1f} us + one joint-law pass {law:.1f} us = {base:.1f} us; "
                  f"a step of the compiled loop costs {step / base:.0f}x it (target 10x), with the joint-space "
                  f"step alone compiled {step_kernel / base:.0f}x, the joint-space solve itself {solve / base:.0f}x"
                  + (f"; the {loop_steps} steps the loop took themselves {own:.0f} us each = {own / base:.1f}x (its "
                     "calls with their Python, records excluded; the rest is the steps handed back and halved)"
                     if loop_steps else ""))
        else:
            # target 2: the run against the substitutions and law passes its steps made (counted in
            # the Python loop, which does the same arithmetic), each at its cost timed here
            counts = figures["python"][0]
            floor_s = 1e-6 * (counts["substitutions"] * sub + counts["law_passes"] * law)
            wall = min(f["wall_s"] for f in figures["loop"])
            js = min(f["js_ms_per_step"] for f in figures["kernel"]) * 1e-3 * counts["steps"]
            print(f"  floor: {counts['substitutions']} substitutions x {sub:.0f} us + {counts['law_passes']} full "
                  f"joint-law passes x {law:.1f} us = {floor_s:.2f} s ({counts['partial_passes']} passes over a few "
                  f"points not counted); the compiled run's dynamic stage took {wall:.2f} s = {wall / floor_s:.2f}x "
                  f"it (target 4x), its joint-space solves {js:.2f} s = {js / floor_s:.2f}x")


if __name__ == "__main__":
    main()
