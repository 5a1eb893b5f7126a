"""What a dynamic step costs against its arithmetic: the compiled joint-space step (masonrydam.solvers.joint_space.
step_kernel) against the Python loop it replaces, on the Koyna section of examples/koyna_el_centro.toml (Chopra &
Chakrabarti 1973 profile, Mohr-Coulomb lift and base joints, El Centro 1940 at 0.5 g).

    python benchmarks/bench_step_kernel.py [--cases coarse_fixed coarse_auto example] [--example-duration 4]
                                          [--repeats 2]

Cases: ``coarse_fixed`` the section at element_size 12 m (358 DOF, 88 joint points), trapezoidal rule at dt
2.5 ms, 2 000 steps; ``coarse_auto`` the same with dt = "auto" (dt_max 10 ms) over 1.5 s; ``example`` the
example itself (element_size 1.45 m, about 7 500 DOF, 588 joint points, dt = "auto") over its first
``--example-duration`` s of record. Each case runs with the compiled step and with the Python loop, alternately
``--repeats`` times (the machine's timing noise is about 10 %), and prints per path: ms a step of the dynamic
stage, the joint-space solve's share, and whether the two datasets are equal bit for bit.

Then, for the coarse section, the floor the issue measures against (issue 35, target 1): one substitution with
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
        self.seconds, self.calls = 0.0, 0
        self.substitutions = self.law_passes = self.partial_passes = 0


def run(case, compiled, rec, example_duration):
    import masonrydam

    rec.module.COMPILED_STEP = compiled
    rec.reset()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = masonrydam.run(scene(case, example_duration))
    steps = int(ds.attrs["dynamic_steps"])
    return ds, {"ms_per_step": 1e3 * float(ds.attrs["dynamic_wall_time_s"]) / steps,
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
    print(f"# dynamic steps, compiled joint-space step against the Python loop ({cpu_model()}, 1 thread)")
    run("coarse_fixed", True, rec, 0.1)  # numba's caches loaded (or compiled) outside the timings
    for case in args.cases:
        figures = {True: [], False: []}
        datasets = {}
        for _ in range(args.repeats):
            for compiled in (True, False):
                ds, f = run(case, compiled, rec, args.example_duration)
                figures[compiled].append(f)
                datasets[compiled] = ds
        equal = same(datasets[True], datasets[False])
        print(f"\n[{case}] {figures[True][0]['steps']} steps, {figures[True][0]['attempts']} joint-space attempts; "
              f"datasets {'equal bit for bit' if equal else 'DIFFER'}")
        for compiled in (True, False):
            ms = sorted(f["ms_per_step"] for f in figures[compiled])
            js = sorted(f["js_ms_per_step"] for f in figures[compiled])
            print(f"  {'compiled' if compiled else 'python  '}: {ms[0]:.3f}-{ms[-1]:.3f} ms/step, of which the "
                  f"joint-space solve {js[0]:.3f}-{js[-1]:.3f} ms")
        if rec.last is None:
            continue
        sub, law = floor_us(rec.last, 2000 if case.startswith("coarse") else 200)
        if case.startswith("coarse"):
            step = 1e3 * min(f["ms_per_step"] for f in figures[True])
            solve = 1e3 * min(f["js_ms_per_step"] for f in figures[True])
            base = sub + law
            print(f"  floor: one substitution {sub:.1f} us + one joint-law pass {law:.1f} us = {base:.1f} us; "
                  f"a compiled step costs {step / base:.0f}x it (target 10x), its joint-space solve alone "
                  f"{solve / base:.0f}x")
        else:
            # issue 35, target 2: the run against the substitutions and law passes its steps made (counted in
            # the Python loop, which does the same arithmetic), each at its cost timed here
            counts = figures[False][0]
            floor_s = 1e-6 * (counts["substitutions"] * sub + counts["law_passes"] * law)
            wall = min(f["wall_s"] for f in figures[True])
            js = min(f["js_ms_per_step"] for f in figures[True]) * 1e-3 * counts["steps"]
            print(f"  floor: {counts['substitutions']} substitutions x {sub:.0f} us + {counts['law_passes']} full "
                  f"joint-law passes x {law:.1f} us = {floor_s:.2f} s ({counts['partial_passes']} passes over a few "
                  f"points not counted); the compiled run's dynamic stage took {wall:.2f} s = {wall / floor_s:.2f}x "
                  f"it (target 4x), its joint-space solves {js:.2f} s = {js / floor_s:.2f}x")


if __name__ == "__main__":
    main()
