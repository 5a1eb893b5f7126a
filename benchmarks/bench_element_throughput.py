"""Element throughput of the numba kernels, single thread, after JIT.

    /work/venv/bin/python benchmarks/bench_element_throughput.py [--q4 N] [--interfaces N] [--repeats R]

Measures elements per second for

* Q4 continuum stiffness (``continuum_stiffness`` with ``element_tables('quad4')``) on a structured
  ``n x n`` grid (default ~1e6 elements), evaluation alone and evaluation + assembly into the CSR
  ``data`` array (``build_pattern`` once, then ``data[:] = 0`` + ``scatter_matrix`` per evaluation);
* 2D line2 interfaces (``interface_evaluate``, called as ``InterfaceGroup.evaluate`` does, with
  ``joint_params`` parameters) on ~2e5 elements, evaluation alone (with and without tangent) and
  evaluation + assembly (tangent into CSR with ``scatter_matrix`` and forces with
  ``scatter_vector``, as ``Model.evaluate`` does per Newton iteration);

and the cold-start JIT cost, in subprocesses with ``NUMBA_CACHE_DIR`` pointed to a fresh temporary
directory (first call = compile, second call = run), then again with that cache filled.

Target: >= 1 million Q4 elements per second including assembly.

This is a benchmark, not a test: it prints tables and never fails on a slow figure.
"""
from __future__ import annotations

import os

# single thread everywhere, before numpy / numba are imported
from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

TARGET_Q4_PER_S = 1.0e6


from _common import cpu_model  # noqa: E402  (benchmarks/ is sys.path[0] when run as a script)


def q4_grid(n: int, h: float = 0.01):
    """Structured n x n grid of quad4 (counter-clockwise), coords (n+1)^2 x 2, conn n^2 x 4."""
    x = np.arange(n + 1) * h
    X, Y = np.meshgrid(x, x, indexing="xy")
    coords = np.ascontiguousarray(np.stack([X.ravel(), Y.ravel()], axis=1))
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="xy")
    n0 = (j * (n + 1) + i).ravel()
    conn = np.ascontiguousarray(np.stack([n0, n0 + 1, n0 + n + 2, n0 + n + 1], axis=1).astype(np.int64))
    return coords, conn


def interface_rows(n_elem: int, per_row: int = 1000, h: float = 0.01, gap: float = 0.05):
    """Rows of horizontal line2 interfaces with coincident bottom / top nodes.

    Each row has ``per_row`` elements; bottom nodes then top nodes of a row are separate nodes at
    the same position. conn rows are [bottom_0, bottom_1, top_0, top_1] (architecture.md order).
    """
    n_rows = max(1, math.ceil(n_elem / per_row))
    npr = per_row + 1
    xs = np.arange(npr) * h
    coords = []
    conn = []
    for r in range(n_rows):
        base = 2 * npr * r
        y = r * gap
        coords.append(np.stack([xs, np.full(npr, y)], axis=1))  # bottom
        coords.append(np.stack([xs, np.full(npr, y)], axis=1))  # top
        i = np.arange(per_row)
        conn.append(np.stack([base + i, base + i + 1, base + npr + i, base + npr + i + 1], axis=1))
    coords = np.ascontiguousarray(np.vstack(coords), dtype=np.float64)
    conn = np.ascontiguousarray(np.vstack(conn)[:n_elem], dtype=np.int64)
    return coords, conn, n_rows


def timed(fn, repeats: int):
    ts = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return min(ts), float(np.median(ts)), out


def fmt_rate(r):
    return f"{r / 1e6:8.3f} M/s"


# -----------------------------------------------------------------------------------------------
# Q4 continuum
# -----------------------------------------------------------------------------------------------


def bench_q4(n: int, repeats: int):
    from masonrydam.assembly.dofmap import DofMap
    from masonrydam.assembly.sparsity import build_pattern, scatter_matrix
    from masonrydam.elements.continuum import continuum_stiffness, element_tables
    from masonrydam.materials.elastic import elasticity_matrix

    coords, conn = q4_grid(n)
    ne = len(conn)
    _, dN, w = element_tables("quad4")
    D = np.ascontiguousarray(elasticity_matrix(16.7e9, 0.15, "plane_stress")[None, :, :])
    mat = np.zeros(ne, dtype=np.int64)
    thick = np.full(ne, 0.1)
    info = np.zeros(1, dtype=np.int64)
    ke = np.empty((ne, 8, 8))

    # JIT (or cache load) outside the timings
    small_c, small_conn = q4_grid(2)
    kes = np.empty((4, 8, 8))
    continuum_stiffness(small_c, small_conn, dN, w, D, np.zeros(4, np.int64), np.ones(4), kes, info)

    dofs = DofMap.node_dofs(conn, 2)
    n_dof = len(coords) * 2
    constrained = np.zeros(n_dof, dtype=bool)
    constrained[: 2 * (n + 1)] = True  # bottom row of nodes fixed in x and y
    dm = DofMap(len(coords), 2, constrained)
    t0 = time.perf_counter()
    indptr, indices, (scat,) = build_pattern([dofs], dm.eq_of_dof, dm.n_eq)
    t_pattern = time.perf_counter() - t0
    data = np.zeros(len(indices))
    scatter_matrix(kes, scat[:4], np.zeros(len(indices)))  # JIT

    def ev():
        st = continuum_stiffness(coords, conn, dN, w, D, mat, thick, ke, info)
        assert st == 0, st

    def sc():
        data[:] = 0.0
        st = scatter_matrix(ke, scat, data)
        assert st == 0, st

    def ev_sc():
        ev()
        sc()

    rows = []
    t_ev, m_ev, _ = timed(ev, repeats)
    rows.append(("Q4 stiffness evaluation only", ne, t_ev, m_ev))
    t_sc, m_sc, _ = timed(sc, repeats)
    rows.append(("Q4 scatter only (zero data + scatter_matrix)", ne, t_sc, m_sc))
    t_all, m_all, _ = timed(ev_sc, repeats)
    rows.append(("Q4 evaluation + assembly into CSR", ne, t_all, m_all))

    # sanity: the assembled matrix is symmetric and the rigid-body-free part is positive on a test vector
    import scipy.sparse as sp

    K = sp.csr_matrix((data, indices.astype(np.int64), indptr), shape=(dm.n_eq, dm.n_eq))
    asym = abs(K - K.T).max() / abs(K).max()
    info_extra = {
        "n_elem": ne,
        "n_dof": n_dof,
        "n_eq": dm.n_eq,
        "nnz": len(indices),
        "pattern_s": t_pattern,
        "asym": float(asym),
        "scatter_MB": scat.nbytes / 2**20,
        "ke_MB": ke.nbytes / 2**20,
    }
    return rows, info_extra


# -----------------------------------------------------------------------------------------------
# line2 interfaces
# -----------------------------------------------------------------------------------------------


def bench_interfaces(n_elem: int, repeats: int):
    from masonrydam.assembly.dofmap import DofMap
    from masonrydam.assembly.sparsity import build_pattern, scatter_matrix, scatter_vector
    from masonrydam.elements.interface import interface_evaluate, interface_rule
    from masonrydam.elements.shapes import shape_functions
    from masonrydam.materials import mohr_coulomb as mc

    coords, conn, n_rows = interface_rows(n_elem)
    ne = len(conn)
    dim = 2
    n_dof = len(coords) * dim
    dofs = DofMap.node_dofs(conn, dim)
    dm = DofMap(len(coords), dim, np.zeros(n_dof, dtype=bool))
    t0 = time.perf_counter()
    indptr, indices, (scat,) = build_pattern([dofs], dm.eq_of_dof, dm.n_eq)
    t_pattern = time.perf_counter() - t0
    data = np.zeros(len(indices))
    f = np.zeros(n_dof)

    # a displacement field that puts the Mohr-Coulomb points in a mix of stick / slip / open:
    # top nodes get a relative shear slip and a relative normal displacement (mostly closing)
    rng = np.random.default_rng(12345)
    u = np.zeros(n_dof)
    top_nodes = np.unique(conn[:, 2:])
    u[top_nodes * 2 + 0] = rng.uniform(-2e-5, 2e-5, len(top_nodes))
    u[top_nodes * 2 + 1] = rng.uniform(-1e-5, 2e-6, len(top_nodes))

    params_mc = mc.joint_params(82e9, 36e9, cohesion=0.0, friction_angle_deg=36.87, tensile_strength=0.0)
    params_lin = mc.joint_params(82e9, 36e9, cohesion=1e300, friction_angle_deg=0.0, tensile_strength=1e300)
    rows = []
    states = {}
    for law, params in (("mohr_coulomb", params_mc), ("linear", params_lin)):
        for scheme in ("lumped", "gauss"):
            pts, wts = interface_rule("line2", scheme)
            N, dN = shape_functions("line2", pts)
            N = np.ascontiguousarray(N, dtype=np.float64)
            dN = np.ascontiguousarray(dN, dtype=np.float64)
            wts = np.ascontiguousarray(wts, dtype=np.float64)
            nip = len(wts)
            thick = np.full(ne, 0.1)
            ptab = np.ascontiguousarray(params[None, :])
            pidx = np.zeros(ne, dtype=np.int64)
            s_base = np.zeros((ne, nip, mc.N_JOINT_STATE))
            s_trial = np.zeros_like(s_base)
            delta = np.zeros((ne, nip, dim))
            trac = np.zeros((ne, nip, dim))
            fe = np.zeros((ne, 8))
            ke = np.zeros((ne, 8, 8))
            info = np.zeros(1, dtype=np.int64)

            def ev(want=True):
                st = interface_evaluate(coords, conn, u, N, dN, wts, thick, ptab, pidx, s_base, s_trial,
                                        delta, trac, fe, ke, want, info)
                assert st == 0, (st, info)

            ev()  # JIT / warm-up
            ev(False)
            scatter_matrix(ke[:2], scat[:2], np.zeros(len(indices)))
            scatter_vector(fe[:2], dofs[:2], np.zeros(n_dof))

            def ev_asm():
                ev(True)
                data[:] = 0.0
                f[:] = 0.0
                st = scatter_matrix(ke, scat, data)
                assert st == 0
                scatter_vector(fe, dofs, f)

            tag = f"{law}, {scheme} ({nip} pts)"
            t1, m1, _ = timed(lambda: ev(False), repeats)
            rows.append((f"line2 {tag}: forces only (no tangent)", ne, t1, m1))
            t2, m2, _ = timed(lambda: ev(True), repeats)
            rows.append((f"line2 {tag}: forces + tangent", ne, t2, m2))
            t3, m3, _ = timed(ev_asm, repeats)
            rows.append((f"line2 {tag}: forces + tangent + assembly", ne, t3, m3))
            codes = s_trial[:, :, mc.S_CODE].ravel()
            states[tag] = {name: float((codes == c).mean()) for name, c in (("stick", 0), ("slip", 1), ("open", 2))}
    info_extra = {"n_elem": ne, "n_rows": n_rows, "n_dof": n_dof, "nnz": len(indices), "pattern_s": t_pattern,
                  "states": states}
    return rows, info_extra


# -----------------------------------------------------------------------------------------------
# cold-start JIT (child process)
# -----------------------------------------------------------------------------------------------


def jit_child():
    """Run in a subprocess: time imports and first / second calls of each kernel on a tiny model."""
    out = {}
    t0 = time.perf_counter()
    import numba  # noqa: F401

    out["import numba"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    from masonrydam.assembly.dofmap import DofMap
    from masonrydam.assembly.sparsity import build_pattern, scatter_matrix, scatter_vector
    from masonrydam.elements.continuum import continuum_body_force, continuum_stiffness, element_tables
    from masonrydam.elements.interface import interface_evaluate, interface_geometry, interface_rule
    from masonrydam.elements.shapes import shape_functions
    from masonrydam.materials import mohr_coulomb as mc
    from masonrydam.materials.elastic import elasticity_matrix

    out["import masonrydam kernels"] = time.perf_counter() - t0

    coords, conn = q4_grid(4)
    ne = len(conn)
    Nq, dNq, wq = element_tables("quad4")
    D = np.ascontiguousarray(elasticity_matrix(16.7e9, 0.15, "plane_stress")[None, :, :])
    info = np.zeros(1, dtype=np.int64)
    ke = np.empty((ne, 8, 8))
    args_q4 = (coords, conn, dNq, wq, D, np.zeros(ne, np.int64), np.full(ne, 0.1), ke, info)

    ic, iconn, _ = interface_rows(8, per_row=4)
    ni = len(iconn)
    pts, wts = interface_rule("line2", "lumped")
    N, dN = shape_functions("line2", pts)
    N, dN, wts = (np.ascontiguousarray(a, dtype=np.float64) for a in (N, dN, wts))
    params = np.ascontiguousarray(mc.joint_params(82e9, 36e9, 0.0, 36.87, 0.0)[None, :])
    u = np.zeros(len(ic) * 2)
    sb = np.zeros((ni, 2, mc.N_JOINT_STATE))
    args_if = (ic, iconn, u, N, dN, wts, np.full(ni, 0.1), params, np.zeros(ni, np.int64), sb, sb.copy(),
               np.zeros((ni, 2, 2)), np.zeros((ni, 2, 2)), np.zeros((ni, 8)), np.zeros((ni, 8, 8)), True, info)
    dofs = DofMap.node_dofs(conn, 2)
    dm = DofMap(len(coords), 2, np.zeros(len(coords) * 2, bool))
    _, indices, (scat,) = build_pattern([dofs], dm.eq_of_dof, dm.n_eq)
    data = np.zeros(len(indices))
    calls = [
        ("continuum_stiffness (quad4)", lambda: continuum_stiffness(*args_q4)),
        ("continuum_body_force (quad4)", lambda: continuum_body_force(
            coords, conn, Nq, dNq, wq, np.zeros((ne, 2)), np.full(ne, 0.1), np.empty((ne, 8)), info)),
        ("interface_geometry (line2)", lambda: interface_geometry(
            ic, iconn, N, dN, wts, np.zeros((ni, 2, 2)), np.zeros((ni, 2, 2, 2)), np.zeros((ni, 2)), info)),
        ("interface_evaluate (line2)", lambda: interface_evaluate(*args_if)),
        ("scatter_matrix", lambda: scatter_matrix(ke, scat, data)),
        ("scatter_vector", lambda: scatter_vector(np.zeros((ne, 8)), dofs, np.zeros(len(coords) * 2))),
    ]
    kern = {}
    for name, fn in calls:
        t0 = time.perf_counter()
        st = fn()
        t1 = time.perf_counter()
        fn()
        t2 = time.perf_counter()
        assert st == 0, (name, st)
        kern[name] = (t1 - t0, t2 - t1)
    out["kernels"] = kern
    print("JSON:" + json.dumps(out))


def run_jit_child(cache_dir: str) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir, NUMBA_NUM_THREADS="1")
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, __file__, "--jit-child"], env=env, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"JIT child failed:\n{p.stdout}\n{p.stderr}")
    line = [ln for ln in p.stdout.splitlines() if ln.startswith("JSON:")][-1]
    d = json.loads(line[5:])
    d["process wall"] = wall
    return d


# -----------------------------------------------------------------------------------------------


def print_table(title, rows, note=None):
    print(f"\n{title}")
    print(f"{'case':<62} {'elements':>10} {'best s':>9} {'median s':>9} {'elements/s (best)':>18}")
    print("-" * 112)
    for name, ne, tb, tm in rows:
        print(f"{name:<62} {ne:>10d} {tb:>9.4f} {tm:>9.4f} {fmt_rate(ne / tb):>18}")
    if note:
        print(note)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--q4", type=int, default=1000, help="Q4 grid is N x N elements (default 1000 -> 1e6)")
    ap.add_argument("--interfaces", type=int, default=200_000, help="number of line2 interfaces (default 2e5)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--skip-jit", action="store_true", help="skip the cold-start JIT subprocesses")
    ap.add_argument("--jit-child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.jit_child:
        jit_child()
        return

    import numba

    print(f"masonrydam element throughput | CPU: {cpu_model()} ({os.cpu_count()} logical cores) | "
          f"numba {numba.__version__}, numpy {np.__version__} | NUMBA_NUM_THREADS={numba.config.NUMBA_NUM_THREADS}")
    print(f"times: best and median of {a.repeats} repeats after JIT; single thread")

    rows, q = bench_q4(a.q4, a.repeats)
    print_table(
        f"Q4 continuum, {q['n_elem']:,} elements on a {a.q4} x {a.q4} grid, {q['n_eq']:,} equations, nnz {q['nnz']:,}",
        rows,
        f"build_pattern (once): {q['pattern_s']:.2f} s; scatter map {q['scatter_MB']:.0f} MiB, "
        f"element matrices {q['ke_MB']:.0f} MiB; assembled K max|K-K^T|/max|K| = {q['asym']:.1e}",
    )
    best_total = rows[2][1] / rows[2][2]
    verdict = "MET" if best_total >= TARGET_Q4_PER_S else "NOT MET"
    print(f"target >= {TARGET_Q4_PER_S / 1e6:.1f} M Q4 elements/s including assembly: "
          f"{best_total / 1e6:.2f} M/s -> {verdict}")

    rows, it = bench_interfaces(a.interfaces, a.repeats)
    print_table(
        f"line2 interfaces, {it['n_elem']:,} elements in {it['n_rows']} rows, {it['n_dof']:,} DOFs, nnz {it['nnz']:,}",
        rows,
        f"build_pattern (once): {it['pattern_s']:.2f} s; assembly = zero data + scatter_matrix (tangent) + "
        f"scatter_vector (forces)",
    )
    print("integration-point states of the Mohr-Coulomb cases (fractions): "
          + "; ".join(f"{k}: " + ", ".join(f"{s} {v:.2f}" for s, v in d.items())
                      for k, d in it["states"].items() if k.startswith("mohr")))

    if a.skip_jit:
        return
    with tempfile.TemporaryDirectory(prefix="numba_cache_") as tmp:
        cold = run_jit_child(tmp)
        warm = run_jit_child(tmp)
    print("\nCold start (subprocess, fresh NUMBA_CACHE_DIR) vs warm cache (second subprocess, same cache dir)")
    print(f"{'step':<34} {'cold 1st call s':>16} {'cold 2nd call s':>16} {'cached 1st call s':>18}")
    print("-" * 88)
    for k in ("import numba", "import masonrydam kernels"):
        print(f"{k:<34} {cold[k]:>16.3f} {'':>16} {warm[k]:>18.3f}")
    tc = tw = 0.0
    for name, (first, second) in cold["kernels"].items():
        wfirst = warm["kernels"][name][0]
        tc += first
        tw += wfirst
        print(f"{name:<34} {first:>16.3f} {second:>16.6f} {wfirst:>18.4f}")
    print(f"{'sum of first calls':<34} {tc:>16.3f} {'':>16} {tw:>18.4f}")
    print(f"{'whole subprocess wall':<34} {cold['process wall']:>16.3f} {'':>16} {warm['process wall']:>18.3f}")


if __name__ == "__main__":
    main()
