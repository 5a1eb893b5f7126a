"""Static push of the Koyna section with lift joints: self-weight, then the crest pushed
downstream under displacement control until lifts slide; the cost of a static Newton iteration on
the joint unknowns against one substitution of the all-stick matrix.

    python benchmarks/bench_koyna_static_push.py [--push 0.05] [--steps 40] [--element-size 1.45]
                                                 [--kernel compiled|python]

The scene is ``examples/koyna_el_centro.toml`` (the Koyna benchmark section, Chopra & Chakrabarti 1973) with its
dynamic stage replaced by a static stage that moves the ``crest`` nodes by ``--push`` m in x. Runs
the push with ``joint_space = "auto"`` (steps solved on the joint unknowns, condensed from the
all-stick stiffness) and ``"off"`` (the general Newton path, a tangent factorization per
iteration) and prints, for each: wall time of the static solve, steps, cuts, iterations (general
and joint-space), factorizations, time per iteration, the joint states at the end and the reaction
at the crest. Then times one substitution (L D L^T) of the all-stick matrix. Target:
the time per iteration at most 3x one substitution. A benchmark, not a test: it never fails on a
slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402

SCENE_FILE = ROOT / "examples" / "koyna_el_centro.toml"


def scene(push: float, steps: int, element_size: float, joint_space: str) -> dict:
    sc = tomllib.loads(SCENE_FILE.read_text())
    sc["model"]["name"] = "koyna_static_push"
    sc["mesh"]["parameters"]["element_size"] = element_size
    sc["stages"] = [sc["stages"][0], {"name": "push", "steps": steps, "loads": [
        {"type": "displacement", "set": "crest", "components": ["x"], "value": [push]}]}]
    sc["solver"] = {"joint_space": joint_space}
    sc["output"] = {"nodes": ["crest"]}
    return sc


def substitution_time(element_size: float) -> tuple[float, int]:
    """Seconds of one L D L^T substitution of the all-stick stiffness (free DOFs), and its size."""
    import scipy.sparse as sp

    from masonrydam.scene import build_mesh, build_model, build_stages
    from masonrydam.scene.scene import Scene
    from masonrydam.solvers.linear.direct import SymmetricFactorization
    from masonrydam.assembly.elastic import elastic_tangent_data

    sc = Scene(scene(0.01, 1, element_size, "auto"))
    mesh = build_mesh(sc.normalized, sc.base_dir)
    model = build_model(sc.normalized, mesh)
    st = build_stages(sc.normalized, mesh, model, sc.base_dir)[1]
    model.set_constraints(st.supports | st.prescribed)
    n = len(model.dofmap.free)
    K = sp.csr_matrix((elastic_tangent_data(model), model.indices, model.indptr), shape=(n, n))
    fact = SymmetricFactorization(K)
    b = np.random.default_rng(0).standard_normal(n)
    fact.solve(b)
    reps = 200
    t0 = time.perf_counter()
    for _ in range(reps):
        fact.solve(b)
    return (time.perf_counter() - t0) / reps, n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--push", type=float, default=0.05, help="crest displacement (m)")
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--element-size", type=float, default=1.45)
    ap.add_argument("--kernel", choices=["compiled", "python"], default="compiled",
                    help="the joint-space steps in the compiled kernel or in the Python loop")
    args = ap.parse_args()
    import masonrydam

    print(f"# Koyna static push ({cpu_model()}, 1 thread): crest moved {args.push} m in {args.steps} steps")
    from masonrydam.solvers.joint_space import condensation as js_module

    # the compiled joint-space step ("always": compiled here if no run has, as a dynamic stage would) or the Python
    # loop ("never"); a run's own default, "cached", takes the kernel where it needs no compiling
    js_module.STATIC_COMPILED_STEP = "always" if args.kernel == "compiled" else "never"
    print(f"# the static joint-space steps in the {args.kernel} code")
    masonrydam.run(scene(0.001, 2, 6.0, "auto"))  # JIT and numba cache outside the timings
    # the joint-space systems' set-ups (one per stage) and solves, timed here: the result's joint_space_setup_s
    # counts the set-ups of the static solver's own stats
    from masonrydam.solvers.joint_space import condensation

    clock = {"setup": 0.0, "solve": 0.0}

    def timed(method, key):
        def wrapper(*a, **k):
            t = time.perf_counter()
            try:
                return method(*a, **k)
            finally:
                clock[key] += time.perf_counter() - t
        return wrapper

    condensation.JointSpace.__init__ = timed(condensation.JointSpace.__init__, "setup")
    condensation.JointSpace.solve_step = timed(condensation.JointSpace.solve_step, "solve")
    per_iteration = {}
    for js in ("auto", "off"):
        clock["setup"] = clock["solve"] = 0.0
        t0 = time.perf_counter()
        try:
            ds = masonrydam.run(scene(args.push, args.steps, args.element_size, js))
        except masonrydam.MasonrydamError as exc:
            print(f"\n[joint_space = {js}] failed after {time.perf_counter() - t0:.1f} s: {exc}")
            continue
        wall = time.perf_counter() - t0
        a = ds.attrs
        general, jsi = int(a["newton_iterations"]), int(a["joint_space_iterations"])
        solve = float(a["solve_wall_time_s"])
        state = np.bincount(ds.joint_state.isel(step=-1).values.astype(int), minlength=3)
        rx = float(ds.reaction.sel(component="x").isel(step=-1).sum())
        print(f"\n[joint_space = {js}] run {wall:.2f} s, static solve {solve:.2f} s; {a['steps']} steps, "
              f"{a['step_cuts']} cuts; {general} general Newton iterations, {jsi} joint-space iterations "
              f"({a['joint_space_steps']} steps converged there, set-up {float(a['joint_space_setup_s']):.2f} s, "
              f"{a['joint_space_size']} unknowns); {a['factorizations']} factorizations")
        per_it = per_iteration[js] = (solve - clock["setup"]) / max(general + jsi, 1)
        print(f"  {1e3 * per_it:.3f} ms per iteration (the static solve less the joint-space set-ups, "
              f"{clock['setup']:.2f} s timed here); joint states stick/slip/open {state.tolist()}; crest reaction "
              f"{rx / 1e6:.3f} MN")
        if jsi:
            per_iteration["solve"] = clock["solve"] / jsi
            print(f"  the joint-space solves alone: {clock['solve']:.3f} s, {1e3 * clock['solve'] / jsi:.3f} ms per "
                  "iteration")
    t_sub, n = substitution_time(args.element_size)
    print(f"\none L D L^T substitution of the all-stick matrix ({n} equations): {1e3 * t_sub:.3f} ms")
    if "auto" in per_iteration:
        print(f"an iteration of the push (joint_space = auto) costs {per_iteration['auto'] / t_sub:.1f}x one "
              f"substitution, its joint-space solve alone {per_iteration.get('solve', 0.0) / t_sub:.1f}x "
              "(target: at most 3x)")


if __name__ == "__main__":
    main()
