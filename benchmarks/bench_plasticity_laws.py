"""Throughput of the continuum plasticity laws (issue 17 sec. 3): points per second of the point
kernels (von Mises and Drucker-Prager, plane strain and 3D, with the consistent tangent), on strains
that put every point in the plastic range (a return mapping at each), and of the elasto-plastic element
(quad8 in plane strain, 9 Gauss points) on a block of elements.

    python benchmarks/bench_plasticity_laws.py [--points 200000]

One thread. A benchmark, not a test: it never fails on a slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402


def _time(fn, repeat=5):
    fn()  # compile / warm the numba cache
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def laws(n):
    from masonrydam.materials import drucker_prager as dp
    from masonrydam.materials import von_mises as vm
    from masonrydam.materials.plasticity import S_CODE

    rng = np.random.default_rng(0)
    cases = [("von Mises", vm, vm.von_mises_params(2e11, 0.3, 2.5e8, 1e9, 1e9), vm.N_VM_STATE, vm.von_mises_update),
             ("Drucker-Prager", dp, dp.drucker_prager_params(3e10, 0.2, 2e6, 30.0, 10.0), dp.N_DP_STATE,
              dp.drucker_prager_update)]
    for name, _, row, n_state, update in cases:
        for ns, label in ((3, "plane strain"), (6, "3D")):
            strain = 5e-3 * rng.standard_normal((n, ns))
            params = np.tile(row, (n, 1))
            sc, st = np.zeros((n, n_state)), np.zeros((n, n_state))
            stress, tangent = np.empty((n, ns)), np.empty((n, ns, ns))
            info = np.zeros(2, dtype=np.int64)
            t = _time(lambda: update(strain, params, sc, st, stress, tangent, 0.0, True, info))
            plastic = float(np.mean(st[:, S_CODE] > 0))
            print(f"{name:15s} {label:12s}: {n / t / 1e6:6.2f} M points/s with the tangent ({1e9 * t / n:.0f} ns per "
                  f"point; {100 * plastic:.0f} % of the points plastic)")


def element(n_side):
    from masonrydam.scene import Scene
    from masonrydam.scene.build import build_mesh, build_model

    sc = Scene({"model": {"name": "b", "hypothesis": "plane_strain", "gravity": [0.0, 0.0]},
                "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 1.0 / n_side, "order": 2, "blocks": [
                    {"x0": 0, "y0": 0, "x1": 1, "y1": 1, "group": "s"}]}},
                "materials": {"s": {"youngs_modulus": 2e11, "poisson_ratio": 0.3, "law": "von_mises",
                                    "yield_stress": 2.5e8}},
                "supports": [{"set": "base"}], "stages": [{"loads": []}]})
    model = build_model(sc.normalized, build_mesh(sc.normalized, sc.base_dir))
    g = model.cgroups[0]
    u = np.zeros(model.n_dof)
    u[0::2] = 0.004 * model.coords[:, 0]
    u[1::2] = -0.006 * model.coords[:, 1]
    t = _time(lambda: g.evaluate(model.coords, u, True))
    pts = g.n_elem * len(g.weights)
    print(f"quad8 element, von Mises: {g.n_elem} elements ({pts} points) in {1e3 * t:.2f} ms = "
          f"{pts / t / 1e6:.2f} M points/s with forces and tangents")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=int, default=200_000)
    args = ap.parse_args()
    print(f"# plasticity laws ({cpu_model()}, 1 thread)")
    laws(args.points)
    element(60)


if __name__ == "__main__":
    main()
