"""Linear static solve of a jointed 2D masonry wall of about 200 000 DOFs: time split and solvers.

    /work/venv/bin/python benchmarks/bench_linear_solve.py [--no-sweep] [--no-spsolve]

The model is the default scene (``masonrydam/scenes/wall_push.toml``) scaled up with
``generators.masonry_wall_2d``: a 4.4 m x 2.48 m running-bond wall (40 courses, units 210 x 52 mm,
10 mm joints) on a base beam and under a top beam, ``elements_per_unit = 5``; all joint sets use
law ``"linear"``; one stage (self-weight + 0.30 MPa precompression) with the base fixed.

It is built with the pieces of ``masonrydam.scene`` (``build_mesh`` / ``build_model`` /
``build_stages`` on the normalised scene), then ``Model.set_constraints`` (CSR pattern and scatter
maps) and ``Model.evaluate`` (joints + assembly of the free-DOF tangent). The tangent and the
right-hand side are saved, and every linear solver runs in its own subprocess so that its peak
memory is its own:

* ``superlu``: ``masonrydam.solvers.linear.direct.Factorization(K, "superlu")`` (SciPy SuperLU, MMD on A^T+A);
* ``pardiso``: ``Factorization(K, "pardiso")`` (MKL PARDISO, pinned to 1 MKL thread by the package);
* ``pardiso-2thr``: the same, with the benchmark overriding the pin to 2 MKL threads (NOT what the
  package does; labelled in the tables);
* ``pardiso-refactor``: PARDISO (1 thread, same settings) with the analysis phase (reordering and
  symbolic factorization, phase 11) done once, untimed, and only the numeric factorization (phase
  22) and solve (phase 33) timed: what a Newton iteration would cost if the analysis were reused
  while the CSR pattern stays the same (the package runs the full analysis at every factorization);
* ``superlu-colamd``: ``scipy.sparse.linalg.splu(K.tocsc(), permc_spec="COLAMD")`` (SuperLU with
  SciPy's default column ordering instead of the package's MMD on A^T+A), reference;
* ``spsolve``: ``scipy.sparse.linalg.spsolve`` (SuperLU with its default COLAMD ordering), reference.

A library warm-up (a 100 x 100 system) runs before the timed factorization, so the times exclude
loading MKL. A smaller-model sweep (default on) locates the crossover between the backends.

This is a benchmark, not a test: it prints tables and never fails on a slow figure.
"""
from __future__ import annotations

import os

for _k in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_k, "1")

import argparse
import copy
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

SCENE = ROOT / "masonrydam" / "scenes" / "wall_push.toml"
#: a child stops repeating once this much time is spent (at least one factorization always runs)
REPEAT_BUDGET_S = 5.0
#: wall-clock limit of one solver subprocess (main model / sweep)
TIMEOUT_MAIN_S = 300
TIMEOUT_SWEEP_S = 45

BACKENDS = ("superlu", "pardiso", "pardiso-2thr", "pardiso-refactor", "superlu-colamd", "spsolve")

# (length m, height m, elements_per_unit): the main model and the sweep (smallest = the default scene)
MAIN = (4.4, 2.48, 5)
SWEEP = [(1.0, 0.62, 2), (2.2, 1.24, 2), (2.2, 1.24, 4), (4.4, 2.48, 3), MAIN]


from _common import RssSampler, cpu_model, peak_rss_mib  # noqa: E402  (benchmarks/ is sys.path[0] when run as a script)




def scene_dict(length, height, epu):
    """The default scene, scaled, with linear joints and one gravity + precompression stage."""
    import tomllib

    data = tomllib.loads(SCENE.read_text())
    data = copy.deepcopy(data)
    data["model"]["name"] = f"bench_wall_{length}x{height}_epu{epu}"
    p = data["mesh"]["parameters"]
    p["length"] = f"{length} m"
    p["height"] = f"{height} m"
    p["elements_per_unit"] = epu
    for j in data["joints"].values():
        j["law"] = "linear"
        for k in ("cohesion", "friction_angle", "residual_shear_stiffness", "tensile_strength"):
            j.pop(k, None)
    data["stages"] = [data["stages"][0]]
    data["stages"][0]["steps"] = 1
    return data


def build(length, height, epu):
    """Build the model; returns (timings dict, K, b, info)."""
    from masonrydam.scene import build_mesh, build_model, build_stages
    from masonrydam.scene.scene import Scene

    t = {}
    t0 = time.perf_counter()
    sc = Scene(scene_dict(length, height, epu), base_dir=SCENE.parent)
    s = sc.normalized
    t["scene normalise"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    mesh = build_mesh(s, sc.base_dir)
    t["mesh generation (masonry_wall_2d)"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    model = build_model(s, mesh)
    t["model build (groups + continuum K, COO->CSR)"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    stages = build_stages(s, mesh, model)
    t["stage load vectors"] = time.perf_counter() - t0
    st = stages[0]

    t0 = time.perf_counter()
    model.set_constraints(st.supports | st.prescribed)
    t["pattern + scatter maps (set_constraints)"] = time.perf_counter() - t0

    u = np.zeros(model.n_dof)
    t0 = time.perf_counter()
    f_int, K = model.evaluate(u, want_tangent=True)
    t["joint evaluation + tangent assembly (evaluate)"] = time.perf_counter() - t0
    b = (st.force - f_int)[model.dofmap.free]

    # sub-timings, measured again on their own (build_model and set_constraints include them)
    sub = {}
    t0 = time.perf_counter()
    for g in model.cgroups:
        g.stiffness(model.coords)
    sub["continuum element stiffness kernel (all groups)"] = time.perf_counter() - t0
    info = {
        "n_dof": model.n_dof,
        "n_eq": model.dofmap.n_eq,
        "nnz": K.nnz,
        "n_quad4": sum(g.n_elem for g in model.cgroups),
        "n_interfaces": sum(g.n_elem for g in model.igroups),
        "peak_rss_build_mib": peak_rss_mib(),
    }
    return t, sub, K, b, info


# -----------------------------------------------------------------------------------------------
# child: one backend
# -----------------------------------------------------------------------------------------------


def child(backend: str, npz: str, repeats: int):
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from masonrydam.solvers.linear import direct as lin

    if backend == "pardiso-2thr":
        orig = lin._new_pardiso

        def _new_pardiso_mt(mtype=11):
            import ctypes

            ps = orig(mtype)
            ps.libmkl.MKL_Set_Num_Threads(ctypes.c_int(2))
            return ps

        lin._new_pardiso = _new_pardiso_mt

    z = np.load(npz)
    K = sp.csr_matrix((z["data"], z["indices"], z["indptr"]), shape=tuple(z["shape"]))
    b = z["b"]

    analysed = {}

    def factor_solve(A, rhs):
        if backend == "spsolve":
            t0 = time.perf_counter()
            x = spla.spsolve(A.tocsc(), rhs)
            return None, time.perf_counter() - t0, 0.0, x
        if backend == "pardiso-refactor":
            # analysis (phase 11: reordering + symbolic factorization) once per matrix, untimed;
            # then the timed numeric factorization (phase 22) and solve (phase 33), i.e. what a
            # Newton iteration would cost if the package reused the analysis (the CSR pattern of
            # the tangent is fixed for a constraint set). Same solver settings as Factorization.
            ps = analysed.get(id(A))
            if ps is None:
                ps = lin._new_pardiso(11)
                ps.set_iparm(10, 13)
                ps.set_statistical_info_off()
                ps._check_A(A)
                ps.set_phase(11)
                ps._call_pardiso(A, np.zeros((A.shape[0], 1)))
                analysed[id(A)] = ps
            t0 = time.perf_counter()
            ps._check_A(A)
            ps.set_phase(22)
            ps._call_pardiso(A, np.zeros((A.shape[0], 1)))
            if ps.get_iparm(14) > 0:
                raise lin.SingularMatrix("perturbed pivots")
            t1 = time.perf_counter()
            ps.set_phase(33)
            x = ps._call_pardiso(A, np.asfortranarray(rhs[:, None]))[:, 0]
            return None, t1 - t0, time.perf_counter() - t1, x
        if backend == "superlu-colamd":
            t0 = time.perf_counter()
            f = spla.splu(A.tocsc(), permc_spec="COLAMD")
            t1 = time.perf_counter()
            x = f.solve(rhs)
            return f, t1 - t0, time.perf_counter() - t1, x
        name = "pardiso" if backend.startswith("pardiso") else backend
        t0 = time.perf_counter()
        f = lin.Factorization(A, name)
        t1 = time.perf_counter()
        x = f.solve(rhs)
        t2 = time.perf_counter()
        return f, t1 - t0, t2 - t1, x

    # warm-up (library load, thread pools)
    t0 = time.perf_counter()
    n = 100
    A = sp.diags([-np.ones(n - 1), 4 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csr")
    f, *_ = factor_solve(A, np.ones(n))
    del f
    warm = time.perf_counter() - t0
    mkl_threads = None
    if backend.startswith("pardiso"):
        ps = lin._new_pardiso()
        try:
            mkl_threads = int(ps.libmkl.MKL_Get_Max_Threads())
        except AttributeError:
            pass
        del ps

    import psutil

    rss0 = psutil.Process().memory_info().rss / 2**20
    facts, solves, peaks = [], [], []
    x = None
    t_start = time.perf_counter()
    for i in range(repeats):
        if i and time.perf_counter() - t_start > REPEAT_BUDGET_S:
            break
        x = None
        with RssSampler() as smp:
            f, tf, ts, x = factor_solve(K, b)
        facts.append(tf)
        solves.append(ts)
        peaks.append(smp.peak)
        del f
    res = float(np.linalg.norm(K @ x - b) / np.linalg.norm(b))
    out = {
        "backend": backend,
        "warmup_s": warm,
        "mkl_threads": mkl_threads,
        "factorize_s": facts,
        "solve_s": solves,
        "residual": res,
        "rss_before_mib": rss0,
        "sampled_peak_mib": max(peaks),
        "ru_maxrss_mib": peak_rss_mib(),
        "x_norm": float(np.linalg.norm(x)),
        "x_checksum": float(x.sum()),
    }
    print("JSON:" + json.dumps(out))


def run_child(backend, npz, repeats, timeout):
    env = dict(os.environ)
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, __file__, "--child", backend, npz, str(repeats)], env=env,
                           capture_output=True, text=True, cwd=ROOT, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"backend": backend, "error": f"timeout: factorization + solve did not finish in {timeout} s",
                "timeout": timeout}
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        return {"backend": backend, "error": (p.stderr or p.stdout).strip().splitlines()[-1:]}
    d = json.loads([ln for ln in p.stdout.splitlines() if ln.startswith("JSON:")][-1][5:])
    d["process_wall_s"] = wall
    return d


def save(K, b, path):
    np.savez(path, data=K.data, indices=K.indices, indptr=K.indptr, shape=np.array(K.shape), b=b)


LABELS = {
    "superlu": "superlu (Factorization, MMD_AT_PLUS_A)",
    "pardiso": "pardiso (Factorization, 1 MKL thread = package)",
    "pardiso-2thr": "pardiso, 2 MKL threads (override, not package)",
    "pardiso-refactor": "pardiso numeric refactor only (not package)",
    "superlu-colamd": "scipy splu, COLAMD (reference, not package)",
    "spsolve": "scipy spsolve (SuperLU, COLAMD; reference)",
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--no-sweep", action="store_true", help="only the ~200k-DOF model")
    ap.add_argument("--no-spsolve", action="store_true", help="skip scipy spsolve")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.child[0], a.child[1], int(a.child[2]))
        return

    import scipy

    backends = [bk for bk in BACKENDS if not (a.no_spsolve and bk == "spsolve")]
    print(f"masonrydam linear solve | CPU: {cpu_model()} ({os.cpu_count()} logical cores) | numpy {np.__version__}, "
          f"scipy {scipy.__version__}")

    # JIT / cache load of the kernels on the default scene first, so that the build timings below
    # do not include compilation
    t0 = time.perf_counter()
    build(1.0, 0.62, 2)
    print(f"warm-up build of the default-size model (JIT or cache load): {time.perf_counter() - t0:.2f} s")

    with tempfile.TemporaryDirectory(prefix="bench_linear_") as tmp:
        L, H, epu = MAIN
        t, sub, K, b, info = build(L, H, epu)
        print(f"\nModel: {L} m x {H} m running-bond wall, elements_per_unit = {epu}, linear joints: "
              f"{info['n_dof']:,} DOFs ({info['n_eq']:,} free), {info['n_quad4']:,} quad4, "
              f"{info['n_interfaces']:,} line2 interfaces, K nnz {info['nnz']:,}")
        print(f"\n{'build phase':<52} {'time s':>8}")
        print("-" * 61)
        for k, v in t.items():
            print(f"{k:<52} {v:>8.3f}")
        print(f"{'total build':<52} {sum(t.values()):>8.3f}")
        for k, v in sub.items():
            print(f"  (re-timed alone: {k}: {v:.3f} s; it runs once in build_model and again in set_constraints)")
        print(f"peak RSS of the build process (ru_maxrss, incl. the warm-up build): {info['peak_rss_build_mib']:.0f} MiB")

        npz = str(Path(tmp) / "main.npz")
        save(K, b, npz)
        n_eq = info["n_eq"]
        del K
        results = [run_child(bk, npz, 2, TIMEOUT_MAIN_S) for bk in backends]
        print(f"\nLinear solvers on the {n_eq:,}-equation tangent (each in its own process; best of up to 2 factorizations, 1 when the first takes > {REPEAT_BUDGET_S:g} s)")
        hdr = (f"{'backend':<48} {'factorize s':>11} {'solve s':>8} {'rel. residual':>13} {'RSS before':>10} "
               f"{'peak RSS':>9} {'delta':>7}")
        print(hdr)
        print("-" * len(hdr))
        for r in results:
            if "error" in r:
                print(f"{LABELS[r['backend']]:<48} FAILED: {r['error']}")
                continue
            fs = min(r["factorize_s"])
            ss = min(r["solve_s"])
            peak = max(r["sampled_peak_mib"], 0)
            print(f"{LABELS[r['backend']]:<48} {fs:>11.3f} {ss if r['backend'] != 'spsolve' else float('nan'):>8.3f} "
                  f"{r['residual']:>13.1e} {r['rss_before_mib']:>8.0f}Mi {peak:>7.0f}Mi {peak - r['rss_before_mib']:>5.0f}Mi")
        print("spsolve: factorize column = factorization + solve in one call. RSS in MiB: 'peak' sampled every 5 ms "
              "during factorize + solve, 'delta' = peak - RSS before.")
        for r in results:
            if "error" not in r and r.get("mkl_threads") is not None:
                print(f"  {r['backend']}: MKL_Get_Max_Threads() = {r['mkl_threads']}")
        ok = [r for r in results if "error" not in r]
        xs = {r["backend"]: r["x_norm"] for r in ok}
        print("  |x| per backend: " + ", ".join(f"{k} {v:.10e}" for k, v in xs.items()))

        if a.no_sweep:
            return
        print("\nSize sweep (factorize + one solve, best of N; crossover)")
        hdr = f"{'L x H m, epu':<18} {'DOFs':>8} {'nnz':>10}  " + "  ".join(f"{bk:>14}" for bk in backends) + "   fastest"
        print(hdr)
        print("-" * len(hdr))
        main_info = info
        for (L, H, epu) in SWEEP:
            if (L, H, epu) == MAIN:  # reuse the runs above
                info, rs = main_info, results
            else:
                _, _, K, b, info = build(L, H, epu)
                p = str(Path(tmp) / f"s_{L}_{H}_{epu}.npz")
                save(K, b, p)
                del K
                reps = 20 if info["n_eq"] < 20_000 else (5 if info["n_eq"] < 100_000 else 2)
                rs = [run_child(bk, p, reps, TIMEOUT_SWEEP_S) for bk in backends]
                os.unlink(p)
            cells, text = {}, {}
            for r in rs:
                bk = r["backend"]
                if "error" in r:
                    cells[bk] = float("inf")
                    text[bk] = f"> {r['timeout']} s" if "timeout" in r else "failed"
                else:
                    cells[bk] = min(f + s for f, s in zip(r["factorize_s"], r["solve_s"]))
                    text[bk] = f"{cells[bk] * 1e3:.1f} ms"
            best = min((v, k) for k, v in cells.items())[1]
            print(f"{f'{L} x {H}, {epu}':<18} {info['n_dof']:>8,} {info['nnz']:>10,}  "
                  + "  ".join(f"{text[bk]:>14}" for bk in backends) + f"   {best}")
        print(f"times: factorization + one solve, best of up to 20 (< 20k eq.), 5 (< 100k) or 2 repeats (repeats stop "
              f"after {REPEAT_BUDGET_S:g} s); '> N s' = the subprocess was stopped after N s.")


if __name__ == "__main__":
    main()
