"""Seismic benchmark: a 2D gravity-dam section (the Koyna benchmark section, Chopra & Chakrabarti 1973)
cut by 10 lift joints and a dam-foundation joint, about 7 500 DOF, self-weight then El Centro
(NGA-West2 RSN6 horizontal component) scaled to a PGA of 0.5 g, 4 000 steps of 0.01 s with nonlinear
Mohr-Coulomb joints; and the same with every joint linear.

    /work/venv/bin/python benchmarks/bench_koyna_seismic.py [--steps 4000] [--element-size 1.3]

Prints wall time, ms per step, Newton iterations per step, factorizations and the joint states at
the end, for both runs. Target: under 5 ms per step for the nonlinear run on one core.
A benchmark, not a test: it never fails on a slow figure.

The scene is ``examples/koyna_el_centro.toml`` (its header gives the data and their sources); the
linear run replaces every joint by a linear one with the same stiffnesses.
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


SCENE_FILE = ROOT / "examples" / "koyna_el_centro.toml"


def scene(law: str, steps: int, element_size: float) -> dict:
    """The scene of ``examples/koyna_el_centro.toml`` with ``steps`` dynamic steps, the mesh size
    ``element_size`` (m) and, for ``law = "linear"``, every joint linear with the same stiffnesses."""
    import tomllib

    from masonrydam.scene.schema import set_time_steps

    sc = tomllib.loads(SCENE_FILE.read_text())
    sc["model"]["name"] = f"koyna_{law}"
    sc["mesh"]["parameters"]["element_size"] = element_size
    # the example's dt = "auto": fixed steps here
    set_time_steps(sc["stages"][1], 0.01, steps=steps)["output"] = {"stride": 10, "nodes": ["crest"]}
    if law == "linear":
        for name, joint in sc["joints"].items():
            sc["joints"][name] = {"law": "linear", "normal_stiffness": joint["normal_stiffness"],
                                  "shear_stiffness": joint["shear_stiffness"]}
    elif law != "mohr_coulomb":
        raise ValueError(f"law must be 'mohr_coulomb' or 'linear', got {law!r}")
    return sc


def run_one(law, steps, element_size, joint_space="auto"):
    import masonrydam

    sc = scene(law, steps, element_size)
    sc["stages"][1]["joint_space"] = joint_space
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        ds = masonrydam.run(sc, output=Path(tmp) / "koyna.nc")
        wall = time.perf_counter() - t0
        attrs = dict(ds.attrs)
        state = ds.joint_state.isel(step=-1).values
        steps = int(attrs["dynamic_steps"])
        out = {
            "wall_s": wall,
            "dyn_s": float(attrs["dynamic_wall_time_s"]),
            "ms_per_step": float(attrs["dynamic_ms_per_step"]),
            "its_per_step": int(attrs["dynamic_newton_iterations"]) / steps,
            "factorizations": int(attrs["dynamic_factorizations"]),
            "substeps": int(attrs["dynamic_substeps"]),
            "low_rank": int(attrs.get("dynamic_low_rank_solves", 0)),
            "reference_solver": str(attrs.get("dynamic_reference_solver", "")),
            "js_size": int(attrs.get("dynamic_joint_space_size", 0)),
            "js_setup": float(attrs.get("dynamic_joint_space_setup_s", 0.0)),
            "js_steps": int(attrs.get("dynamic_joint_space_steps", 0)),
            "js_its": int(attrs.get("dynamic_joint_space_iterations", 0)),
            "js_lu": int(attrs.get("dynamic_joint_space_dense_factorizations", 0)),
            "js_fallbacks": int(attrs.get("dynamic_joint_space_fallbacks", 0)),
            "states": np.bincount(state.astype(int), minlength=3).tolist(),
            "crest_max_ux": float(np.abs(ds.displacement.sel(component="x")).max()),
        }
        ds.close()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--element-size", type=float, default=1.45)
    ap.add_argument("--joint-space", nargs="+", default=["auto", "off"], choices=["auto", "on", "off"],
                    help="joint-space settings of the nonlinear runs (default: auto, then off for comparison)")
    args = ap.parse_args()
    from masonrydam.scene import build_mesh
    from masonrydam.scene.scene import Scene

    sc = Scene(scene("linear", 1, args.element_size))
    mesh = build_mesh(sc.normalized, sc.base_dir)
    print(f"# Koyna section, El Centro at 0.5 g, {args.steps} steps of 0.01 s ({cpu_model()}, 1 thread)")
    print(f"model: {mesh.n_nodes * 2} DOF, {mesh.n_elements()} elements, {mesh.n_interfaces()} interfaces "
          f"({', '.join(f'{j.name} {len(j.cells)}' for j in mesh.joints)})")
    run_one("linear", 5, args.element_size)  # JIT and numba cache outside the timings
    run_one("mohr_coulomb", 5, args.element_size)
    runs = [("linear", "auto")] + [("mohr_coulomb", js) for js in args.joint_space]
    for law, js in runs:
        r = run_one(law, args.steps, args.element_size, js)
        name = law if law == "linear" else f"{law}, joint_space = {js}"
        print(f"\n[{name}] dynamic stage {r['dyn_s']:.1f} s = {r['ms_per_step']:.2f} ms/step; "
              f"{r['its_per_step']:.2f} general Newton iterations/step, {r['factorizations']} factorizations, "
              f"{r['substeps']} sub-steps, {r['low_rank']} low-rank solves, all-stick matrix by "
              f"{r['reference_solver']}; whole run {r['wall_s']:.1f} s; "
              f"final joint states stick/slip/open {r['states']}; max |u_x| at the crest {r['crest_max_ux'] * 1e3:.1f} mm")
        if r["js_size"]:
            per_step = 1e3 * (r["dyn_s"] - r["js_setup"]) / max(args.steps, 1)
            print(f"  joint space: {r['js_size']} unknowns, set-up {r['js_setup']:.2f} s (included above; without it "
                  f"{per_step:.2f} ms/step); {r['js_steps']} steps solved "
                  f"there, {r['js_its'] / max(r['js_steps'] + r['js_fallbacks'], 1):.2f} iterations/step, "
                  f"{r['js_lu']} dense LU, {r['js_fallbacks']} steps finished by the general path")

if __name__ == "__main__":
    main()
