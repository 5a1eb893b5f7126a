"""3D element throughput, single thread, after JIT: H8 stiffness and the 8-node surface
interface of Tzamtzis & Asteris (4 + 4 nodes), evaluation and assembly into the CSR pattern as the solver does it.

    /work/venv/bin/python benchmarks/bench_element_throughput_3d.py [--units NX NY NZ] [--repeats R]

Model: a running-bond block wall of NX x NY x NZ boxes (0.2 x 0.1 x 0.05 m, 2 x 1 x 1 hex8 per box)
from ``generators.grid3d.boxes_to_mesh``, so the interfaces are the ones a real model has (bed,
head and collar joints, at T and cross junctions). Measured:

* H8 continuum stiffness (``ContinuumGroup.stiffness``: ``continuum_stiffness`` with 2x2x2 Gauss)
  alone and with ``scatter_matrix`` into the CSR data array;
* quad4 interfaces with the Mohr-Coulomb law (``InterfaceGroup.evaluate``) with the tangent, for
  lumped (nodal, 4 points) and Gauss 2x2 integration, alone and with the scatter of the tangent
  and the forces (what ``Model.evaluate`` does per Newton iteration), in a mixed stick / slip /
  open state.

Prints elements per second. A benchmark, not a test: it never fails on a slow figure.
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


def wall_boxes(nx, ny, nz, L=0.2, T=0.1, H=0.05):
    from generators.grid3d import Box

    boxes = []
    for k in range(nz):
        off = 0.0 if k % 2 == 0 else L / 2
        xs = sorted({0.0, nx * L, *[off + L * i for i in range(nx + 1) if 0 < off + L * i < nx * L]})
        for x0, x1 in zip(xs[:-1], xs[1:]):
            for j in range(ny):
                boxes.append(Box(x0, j * T, k * H, x1, (j + 1) * T, (k + 1) * H, "units"))
    return boxes


def timed(fn, repeats):
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return min(ts)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--units", nargs=3, type=int, default=[40, 3, 60], metavar=("NX", "NY", "NZ"))
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()

    from generators.grid3d import boxes_to_mesh
    from masonrydam.assembly.dofmap import DofMap
    from masonrydam.assembly.groups import ContinuumGroup, InterfaceGroup
    from masonrydam.assembly.sparsity import build_pattern, scatter_matrix, scatter_vector
    from masonrydam.materials import mohr_coulomb as mc
    from masonrydam.materials.elastic import elasticity_matrix

    t0 = time.perf_counter()
    mesh = boxes_to_mesh(wall_boxes(*args.units), element_size=0.1)
    t_mesh = time.perf_counter() - t0
    b = mesh.blocks[0]
    ne = len(b.cells)
    D = np.ascontiguousarray(elasticity_matrix(16.7e9, 0.15, "3d")[None])
    cg = ContinuumGroup("units", "hex8", b.cells, DofMap.node_dofs(b.cells, 3), D, np.zeros(ne, dtype=np.int64),
                        np.ones(ne), np.full(ne, 1800.0))
    params = mc.joint_params(82e9, 36e9, 0.35e6, 36.87, 0.25e6, 0.0)
    igroups = {}
    for scheme in ("lumped", "gauss"):
        gs = [InterfaceGroup(j.name, j.type, j.cells, mesh.points, 3, params, np.ones(len(j.cells)), "mohr_coulomb", scheme)
              for j in mesh.joints]
        igroups[scheme] = gs
    n_if = sum(g.n_elem for g in igroups["lumped"])
    n_dof = mesh.n_nodes * 3
    dm = DofMap(mesh.n_nodes, 3, np.zeros(n_dof, dtype=bool))
    t0 = time.perf_counter()
    indptr, indices, scat = build_pattern([cg.dofs] + [g.dofs for g in igroups["lumped"]], dm.eq_of_dof, dm.n_eq, dim=3)
    t_pattern = time.perf_counter() - t0
    cg.scatter = scat[0]
    for scheme in igroups:
        for g, s in zip(igroups[scheme], scat[1:]):
            g.scatter = s
    data = np.zeros(len(indices))
    f = np.zeros(n_dof)

    # a displacement field with stick, slip and open points: a smooth random field on the nodes
    rng = np.random.default_rng(7)
    u = np.zeros(n_dof)
    for k in range(3):
        u[k::3] = 2e-6 * np.sin(37.0 * mesh.points[:, 0] + 11.0 * mesh.points[:, 2] + rng.uniform(0, 6, 1))
    u += 1e-6 * rng.standard_normal(n_dof)

    # JIT outside the timings
    cg.stiffness(mesh.points)
    for gs in igroups.values():
        for g in gs:
            g.evaluate(mesh.points, u, True)

    def h8_eval():
        cg.stiffness(mesh.points)

    def h8_eval_scatter():
        data[:] = 0.0
        scatter_matrix(cg.stiffness(mesh.points), cg.scatter, data)

    rows = [("H8 stiffness (2x2x2 Gauss)", ne, timed(h8_eval, args.repeats)),
            ("H8 stiffness + CSR assembly", ne, timed(h8_eval_scatter, args.repeats))]
    for scheme, gs in igroups.items():
        def if_eval(gs=gs):
            for g in gs:
                g.evaluate(mesh.points, u, True)

        def if_eval_scatter(gs=gs):
            data[:] = 0.0
            f[:] = 0.0
            for g in gs:
                g.evaluate(mesh.points, u, True)
                scatter_matrix(g.ke, g.scatter, data)
                scatter_vector(g.fe, g.dofs, f)

        rows.append((f"quad4 interface, {scheme} ({gs[0].nip} pts), law + tangent", n_if, timed(if_eval, args.repeats)))
        rows.append((f"quad4 interface, {scheme}, + CSR/force assembly", n_if, timed(if_eval_scatter, args.repeats)))
    codes = np.concatenate([g.state_codes().ravel() for g in igroups["lumped"]])
    counts = np.bincount(codes, minlength=3)

    print(f"# 3D element throughput ({cpu_model()}, 1 thread)")
    print(f"wall {args.units[0]} x {args.units[1]} x {args.units[2]} units: {ne} hex8, {n_if} quad4 interfaces, "
          f"{n_dof} DOFs, nnz {len(indices)}; mesh + interface insertion {t_mesh:.2f} s, pattern {t_pattern:.2f} s")
    print(f"joint points (lumped): {counts[0]} stick, {counts[1]} slip, {counts[2]} open")
    print(f"{'kernel':58s} {'elements':>9s} {'time':>9s} {'rate':>12s}")
    for name, n, t in rows:
        print(f"{name:58s} {n:9d} {t * 1e3:7.1f} ms {n / t / 1e6:8.3f} M/s")


if __name__ == "__main__":
    main()
