"""Throughput of the continuum plasticity laws: points per second of the point
kernels (von Mises, Drucker-Prager, Tresca and Mohr-Coulomb, plane strain and 3D, with the consistent
tangent), on random strains that put most points in the plastic range (a return mapping at each; the
share is printed), and of the elasto-plastic element (quad8 in plane strain, 9 Gauss points) on a
block of elements, for each law. Each figure is the best of 5 timed calls after a first untimed call
(numba compile / cache). Tresca and Mohr-Coulomb return in principal space (plane, edges, apex:
:mod:`masonrydam.materials.mohr_coulomb_solid`), so they cost more per point than the two smooth laws.

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


#: the laws' materials, as scene keys ([materials.<group>]): a steel for the two pressure-independent
#: laws, a concrete-like frictional material for the two others (the same for the point kernels and the
#: element)
MATERIALS = {
    "von Mises": {"youngs_modulus": 2e11, "poisson_ratio": 0.3, "law": "von_mises", "yield_stress": 2.5e8,
                  "isotropic_hardening": 1e9, "kinematic_hardening": 1e9},
    "Drucker-Prager": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "law": "drucker_prager", "cohesion": 2e6,
                       "friction_angle": 30.0, "dilation_angle": 10.0},
    "Tresca": {"youngs_modulus": 2e11, "poisson_ratio": 0.3, "law": "tresca", "yield_stress": 2.5e8,
               "isotropic_hardening": 1e9},
    "Mohr-Coulomb": {"youngs_modulus": 3e10, "poisson_ratio": 0.2, "law": "mohr_coulomb", "cohesion": 2e6,
                     "friction_angle": 30.0, "dilation_angle": 10.0},
}


def _kernels():
    """(name, parameter row, state columns, batch update) of each law (parameters of :data:`MATERIALS`)."""
    from masonrydam.materials import drucker_prager as dp
    from masonrydam.materials import mohr_coulomb_solid as mc
    from masonrydam.materials import tresca as tr
    from masonrydam.materials import von_mises as vm

    vm_, dp_, tr_, mc_ = (MATERIALS[k] for k in ("von Mises", "Drucker-Prager", "Tresca", "Mohr-Coulomb"))
    return [("von Mises", vm.von_mises_params(vm_["youngs_modulus"], vm_["poisson_ratio"], vm_["yield_stress"],
                                              vm_["isotropic_hardening"], vm_["kinematic_hardening"]),
             vm.N_VM_STATE, vm.von_mises_update),
            ("Drucker-Prager", dp.drucker_prager_params(dp_["youngs_modulus"], dp_["poisson_ratio"], dp_["cohesion"],
                                                        dp_["friction_angle"], dp_["dilation_angle"]),
             dp.N_DP_STATE, dp.drucker_prager_update),
            ("Tresca", tr.tresca_params(tr_["youngs_modulus"], tr_["poisson_ratio"], tr_["yield_stress"],
                                        tr_["isotropic_hardening"]),
             tr.N_TRESCA_STATE, tr.tresca_update),
            ("Mohr-Coulomb", mc.mohr_coulomb_solid_params(mc_["youngs_modulus"], mc_["poisson_ratio"], mc_["cohesion"],
                                                          mc_["friction_angle"], mc_["dilation_angle"]),
             mc.N_MC_STATE, mc.mohr_coulomb_solid_update)]


def laws(n):
    from masonrydam.materials.plasticity import S_CODE

    rng = np.random.default_rng(0)
    rows = []
    for name, row, n_state, update in _kernels():
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
            rows.append((name, label, n / t / 1e6, 1e9 * t / n, 100 * plastic))
    return rows


def element(n_side, name):
    from masonrydam.materials.plasticity import S_CODE
    from masonrydam.scene import Scene
    from masonrydam.scene import build_mesh, build_model

    sc = Scene({"model": {"name": "b", "hypothesis": "plane_strain", "gravity": [0.0, 0.0]},
                "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 1.0 / n_side, "order": 2, "blocks": [
                    {"x0": 0, "y0": 0, "x1": 1, "y1": 1, "group": "s"}]}},
                "materials": {"s": dict(MATERIALS[name])},
                "supports": [{"set": "base"}], "stages": [{"loads": []}]})
    model = build_model(sc.normalized, build_mesh(sc.normalized, sc.base_dir))
    g = model.cgroups[0]
    u = np.zeros(model.n_dof)
    u[0::2] = 0.004 * model.coords[:, 0]
    u[1::2] = -0.006 * model.coords[:, 1]
    t = _time(lambda: g.evaluate(model.coords, u, True))
    pts = g.n_elem * len(g.weights)
    plastic = 100 * float(np.mean(g.state_trial[:, S_CODE] > 0))
    print(f"quad8 element, {name}: {g.n_elem} elements ({pts} points) in {1e3 * t:.2f} ms = "
          f"{pts / t / 1e6:.2f} M points/s with forces and tangents ({plastic:.0f} % of the points plastic)")
    return name, pts / t / 1e6, plastic


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=int, default=200_000)
    args = ap.parse_args()
    print(f"# plasticity laws ({cpu_model()}, 1 thread; best of 5 after an untimed first call that compiles / "
          f"warms the numba cache; {args.points} random strain states, std 5e-3)")
    rows = laws(args.points)
    elems = {name: element(60, name) for name in MATERIALS}
    print()
    print(f"{'law':15s} {'point, plane strain':>24s} {'point, 3D':>24s} {'quad8 element (plane strain)':>30s}")
    print(f"{'':15s} {'M pts/s  ns/pt  plastic':>24s} {'M pts/s  ns/pt  plastic':>24s} {'M pts/s  plastic':>30s}")
    for name in MATERIALS:
        cells = []
        for label in ("plane strain", "3D"):
            r = next(r for r in rows if r[0] == name and r[1] == label)
            cells.append(f"{r[2]:7.2f} {r[3]:6.0f} {r[4]:7.0f} %")
        _, mps, plastic = elems[name]
        print(f"{name:15s} {cells[0]:>24s} {cells[1]:>24s} {f'{mps:7.2f} {plastic:7.0f} %':>30s}")
    print("(points: every point's update with its consistent tangent; element: internal forces and tangent of "
          "3 600 quad8, 9 Gauss points each, under u = (0.004 x, -0.006 y))")


if __name__ == "__main__":
    main()
