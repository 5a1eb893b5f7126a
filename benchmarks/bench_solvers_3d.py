"""Linear solvers on 3D elastic models up to ~400 000 DOFs: sparse direct (PARDISO, SuperLU)
against algebraic multigrid preconditioned Krylov (``AMGSolver``, pyamg smoothed aggregation).

    /work/venv/bin/python benchmarks/bench_solvers_3d.py [--max-dof N] [--families box,blocks]
                                                          [--solvers pardiso,superlu,amg] [--no-penalty-sweep]

Two families of models, both built here with the package's numba kernels (hex8 tables from
``masonrydam.elements.shapes`` when it has ``hex8``, otherwise the trilinear tables of Hughes 2000,
sec. 3.5, built below; the element kernels are dimension-generic):

* ``box``: a plain continuum box (shared nodes), ``n x n x n`` hex8 elements on a 2 x 1 x 1 m box
  (``2n x n x n``), E = 20 GPa, nu = 0.2, base fixed, self-weight (2400 kg/m3) plus a horizontal
  traction on one side (so that the solution is not dominated by one direction);
* ``blocks``: a dry-stone block dam: ``bx x by x bz`` cubic ashlar blocks of 0.5 m (stack bond), each
  meshed with ``e^3`` hex8 (e = 4) and its own nodes, joined across every shared face by zero-thickness
  quad4 interface elements (the package's interface kernel, nodal "lumped" rule, law "linear":
  kn = ks = ratio * E / h with h the element size). ``ratio = kn h / E`` is 100 for the main sweep
  (a stiff penalty joint) and is swept from 0.1 to 1e4 on a fixed model in the last table (does the
  multigrid degrade when the blocks hang on stiff springs?).

For every model the free-DOF stiffness K and the load vector b are saved, and every solver runs in a
subprocess of its own so that the peak RSS it reports (VmHWM of the child, plus the RSS sampled
every 5 ms during setup + solve) is its own:

* ``pardiso``: ``Factorization(K, "pardiso")`` - MKL PARDISO, general LU, 1 MKL thread (as the package);
* ``superlu``: ``Factorization(K, "superlu")`` - SciPy SuperLU with COLAMD ordering (as the package);
* ``amg``: ``AMGSolver(K, rigid_body_modes(...), dof_coords=..., dof_nodes=...)`` - as the static solver
  builds it: pyamg smoothed aggregation with the rigid-body near-nullspace, tied interface node pairs
  collapsed, other joint springs left out of the first strength graph (masonrydam/solvers/linear/iterative.py),
  CG (FGMRES for a non-symmetric tangent) to a relative residual of 1e-10 (the package default);
* ``amg-plain`` (penalty sweep and joint states only): ``AMGSolver(K, rigid_body_modes(...))`` without
  node positions, i.e. plain smoothed aggregation with the rigid-body modes.

Columns: setup = factorization (direct) or AMG hierarchy construction including the near-nullspace
(amg); solve = one solve; total = setup + solve; iterations (amg); peak RSS of the child (VmHWM,
MiB, including the loaded system) and "delta", its sampled peak during setup + solve minus its RSS
before.
A solver is skipped at a size when its peak memory, extrapolated from the two largest sizes it has
solved with a power law in the number of equations, would exceed ``MEM_LIMIT_GB`` (18 GB; the machine
has 24 GB), or its time would exceed ``TIME_LIMIT_S``; the table says so.

This is a benchmark, not a test: it prints tables and never fails on a slow figure.
"""
from __future__ import annotations

import os

for _k in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_k, "1")

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import RssSampler, cpu_model, peak_rss_mib  # noqa: E402  (benchmarks/ is sys.path[0] when run as a script)

E_BLOCK = 20e9
NU_BLOCK = 0.2
DENSITY = 2400.0
G = 9.80665
SIDE_TRACTION = 0.2e6  # Pa, horizontal, on the x = 0 face
BLOCK_SIZE = 0.5  # m, cubic ashlar blocks
ELEMS_PER_BLOCK = 4  # per block edge
MAIN_RATIO = 100.0  # kn * h / E of the main "blocks" sweep

#: peak memory (GB) above which a solver is not run at a size (predicted from smaller sizes)
MEM_LIMIT_GB = 18.0
#: predicted setup + solve time above which a solver is not run, and the hard timeout of one child
TIME_LIMIT_S = 1500.0

# box: n (the box has 2n x n x n elements); blocks: (bx, by, bz) blocks of ELEMS_PER_BLOCK^3 elements
BOX_SIZES = [8, 10, 12, 14, 16, 20, 25, 30, 36, 40]
BLOCK_SIZES = [(4, 2, 2), (5, 3, 2), (6, 3, 3), (8, 4, 4), (10, 5, 5), (12, 6, 6), (14, 7, 7), (16, 8, 7), (18, 9, 8)]
PENALTY_MODEL = (8, 4, 4)
STATES_MODELS = [(8, 4, 4), (12, 6, 6)]
PENALTY_RATIOS = [0.1, 1.0, 10.0, 100.0, 1e3, 1e4]

HEX_CORNERS = np.array(
    [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float
)


# -----------------------------------------------------------------------------------------------
# model construction
# -----------------------------------------------------------------------------------------------


def hex8_tables():
    """N (8 gp, 8), dN (8, 3, 8), w (8,) of the trilinear hex8 at 2x2x2 Gauss points (Hughes 2000,
    sec. 3.5); the package's own tables when ``shapes.ELEMENT_TYPES`` has ``hex8``."""
    from masonrydam.elements import shapes

    if "hex8" in shapes.ELEMENT_TYPES:
        from masonrydam.elements.continuum import element_tables

        return element_tables("hex8")
    from masonrydam.elements.quadrature import tensor_rule

    pts, w = tensor_rule("gauss", 2, 3)
    c = HEX_CORNERS
    f = 1 + pts[:, None, :] * c[None, :, :]
    N = 0.125 * f.prod(axis=2)
    dN = np.empty((len(pts), 3, 8))
    for i in range(3):
        j, k = [m for m in range(3) if m != i]
        dN[:, i, :] = 0.125 * c[None, :, i] * f[:, :, j] * f[:, :, k]
    return np.ascontiguousarray(N), np.ascontiguousarray(dN), np.ascontiguousarray(w)


def grid_hex(nx, ny, nz, origin, size):
    """Structured hex8 grid: coords ((nx+1)(ny+1)(nz+1), 3), conn (nx ny nz, 8) in the VTK / gmsh
    hex order, and the node-index array gid (nx+1, ny+1, nz+1)."""
    xs = [origin[d] + np.linspace(0.0, size[d], n + 1) for d, n in enumerate((nx, ny, nz))]
    X, Y, Z = np.meshgrid(*xs, indexing="ij")
    coords = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    gid = np.arange(len(coords)).reshape(nx + 1, ny + 1, nz + 1)
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    off = ((HEX_CORNERS + 1) / 2).astype(int)
    conn = np.stack([gid[i + a, j + b, k + c].ravel() for a, b, c in off], axis=1)
    return coords, conn.astype(np.int64), gid


def _coo_to_csr(blocks, n):
    """Sum of element matrices: blocks = [(dofs (ne, nd) int, ke (ne, nd, nd))] -> (n x n) CSR."""
    rows, cols, vals = [], [], []
    for dofs, ke in blocks:
        nd = dofs.shape[1]
        d = dofs.astype(np.int32)
        rows.append(np.repeat(d, nd, axis=1).ravel())
        cols.append(np.tile(d, (1, nd)).ravel())
        vals.append(ke.reshape(len(ke), -1).ravel())
    K = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    K.sum_duplicates()
    return K


def _continuum(coords, conn):
    from masonrydam.elements.continuum import continuum_body_force, continuum_stiffness
    from masonrydam.materials.elastic import elasticity_matrix

    N, dN, w = hex8_tables()
    ne = len(conn)
    D = np.ascontiguousarray(elasticity_matrix(E_BLOCK, NU_BLOCK, "3d")[None])
    info = np.zeros(1, np.int64)
    ke = np.empty((ne, 24, 24))
    st = continuum_stiffness(coords, conn, dN, w, D, np.zeros(ne, np.int64), np.ones(ne), ke, info)
    assert st == 0, st
    fe = np.empty((ne, 24))
    bf = np.tile([0.0, 0.0, -DENSITY * G], (ne, 1))
    st = continuum_body_force(coords, conn, N, dN, w, bf, np.ones(ne), fe, info)
    assert st == 0, st
    dofs = (conn[:, :, None] * 3 + np.arange(3)).reshape(ne, 24)
    return dofs, ke, fe


def _side_traction(coords, f, h_face):
    """Horizontal traction SIDE_TRACTION (+x) on the x = min face, lumped on the nodes there."""
    xmin = coords[:, 0].min()
    on = np.isclose(coords[:, 0], xmin)
    # nodal area weights of a structured face: h^2, halved on edges, quartered on corners
    yz = coords[on][:, 1:]
    wgt = np.ones(on.sum())
    for d in range(2):
        lo, hi = yz[:, d].min(), yz[:, d].max()
        wgt[np.isclose(yz[:, d], lo) | np.isclose(yz[:, d], hi)] *= 0.5
    f[np.nonzero(on)[0] * 3] += SIDE_TRACTION * h_face**2 * wgt


def build_box(n):
    """Plain continuum box 2 x 1 x 1 m with 2n x n x n hex8, base (z = 0) fixed."""
    h = 1.0 / n
    coords, conn, _ = grid_hex(2 * n, n, n, (0.0, 0.0, 0.0), (2.0, 1.0, 1.0))
    dofs, ke, fe = _continuum(coords, conn)
    n_dof = coords.size
    K = _coo_to_csr([(dofs, ke)], n_dof)
    f = np.bincount(dofs.ravel(), fe.ravel(), minlength=n_dof)
    _side_traction(coords, f, h)
    fixed = np.repeat(np.isclose(coords[:, 2], 0.0), 3)
    info = {"family": "box", "label": f"{2 * n}x{n}x{n} hex8", "n_hex": len(conn), "n_interfaces": 0}
    return coords, K, f, fixed, info


def block_assembly(bx, by, bz, e=ELEMS_PER_BLOCK, a=BLOCK_SIZE):
    """Coordinates, hex8 connectivity and quad4 interface connectivity (bottom face, top face) of
    bx x by x bz cubic blocks of edge a, e^3 elements each, every block with its own nodes."""
    nb = (e + 1) ** 3
    coords, conns, gids = [], [], {}
    for I in range(bx):
        for J in range(by):
            for Kb in range(bz):
                c, conn, gid = grid_hex(e, e, e, (I * a, J * a, Kb * a), (a, a, a))
                base = len(coords) * nb
                coords.append(c)
                conns.append(conn + base)
                gids[I, J, Kb] = gid + base
    coords = np.vstack(coords)
    conn = np.vstack(conns)
    q = np.arange(e)
    A, B = np.meshgrid(q, q, indexing="ij")
    A, B = A.ravel(), B.ravel()

    def face(g, axis, side):
        """(e*e, 4) quad4 node lists on the face axis = side of block node grid g, counter-
        clockwise seen from +axis (so that the interface normal is +axis)."""
        s = 0 if side == "lo" else e
        if axis == 0:  # xi along y, eta along z: y x z = +x
            return np.stack([g[s, A, B], g[s, A + 1, B], g[s, A + 1, B + 1], g[s, A, B + 1]], axis=1)
        if axis == 1:  # xi along z, eta along x: z x x = +y
            return np.stack([g[B, s, A], g[B, s, A + 1], g[B + 1, s, A + 1], g[B + 1, s, A]], axis=1)
        return np.stack([g[A, B, s], g[A + 1, B, s], g[A + 1, B + 1, s], g[A, B + 1, s]], axis=1)  # x x y = +z

    icon = []
    for (I, J, Kb), g in gids.items():
        for axis, nb_key in ((0, (I + 1, J, Kb)), (1, (I, J + 1, Kb)), (2, (I, J, Kb + 1))):
            if nb_key in gids:
                icon.append(np.hstack([face(g, axis, "hi"), face(gids[nb_key], axis, "lo")]))
    return coords, conn, np.vstack(icon).astype(np.int64)


def build_blocks(bx, by, bz, ratio=MAIN_RATIO, e=ELEMS_PER_BLOCK, states=False):
    """Dry-stone block assembly: blocks on a fixed base (z = 0), quad4 interfaces between blocks,
    linear joints with kn = ks = ratio * E / h.

    states: Mohr-Coulomb joints instead (c = 0, phi = 30 deg, no tension, kn = ks as above), and the
    tangent taken at a displacement that puts them in all three states, as in a nonlinear run: in the
    x < L/2 half, the blocks of layers >= bz // 2 are shifted by 1 mm along +x and pressed 1 um down
    (the bed joint below them slips under compression: non-symmetric tangent; they push on the
    other half), and the top-layer blocks are lifted by another 0.1 mm (the bed joint below them
    opens, the vertical joints next to them slip with zero shear stiffness). Open points keep 1e-6 of
    their stiffness in the tangent, as in the static solver (``OPEN_TANGENT_REGULAR``), so the lifted
    blocks hang on nearly nothing vertically."""
    from masonrydam.elements.interface import interface_evaluate, interface_tables
    from masonrydam.materials import mohr_coulomb as mc

    coords, conn, icon = block_assembly(bx, by, bz, e)
    h = BLOCK_SIZE / e
    dofs, ke, fe = _continuum(coords, conn)
    kn = ratio * E_BLOCK / h
    u = np.zeros(coords.size)
    if states:
        params = mc.joint_params(kn, kn, cohesion=0.0, friction_angle_deg=30.0, tensile_strength=0.0)[None].copy()
        params[0, mc.P_OPEN_TANGENT] = 1e-6
        block = np.arange(len(coords)) // (e + 1) ** 3
        layer, column = block % bz, block // (by * bz)
        moved = (layer >= bz // 2) & (column < bx // 2)
        u[0::3] += 1e-3 * moved
        u[2::3] -= 1e-6 * moved
        u[2::3] += 1e-4 * ((layer == bz - 1) & (column < bx // 2))
    else:
        params = mc.joint_params(kn, kn, cohesion=1e300, friction_angle_deg=0.0, tensile_strength=1e300)[None].copy()
    N, dN, w, _ = interface_tables("quad4", "lumped")
    ni, nip = len(icon), len(w)
    st0 = np.zeros((ni, nip, mc.N_JOINT_STATE))
    st1 = st0.copy()
    kei = np.empty((ni, 24, 24))
    fei = np.empty((ni, 24))
    info = np.zeros(1, np.int64)
    status = interface_evaluate(coords, icon, u, N, dN, w, np.ones(ni), params, np.zeros(ni, np.int64), st0, st1,
                                np.zeros((ni, nip, 3)), np.zeros((ni, nip, 3)), fei, kei, True, info)
    assert status == 0, status
    idofs = (icon[:, :, None] * 3 + np.arange(3)).reshape(ni, 24)
    n_dof = coords.size
    K = _coo_to_csr([(dofs, ke), (idofs, kei)], n_dof)
    f = np.bincount(dofs.ravel(), fe.ravel(), minlength=n_dof)
    _side_traction(coords, f, h)
    fixed = np.repeat(np.isclose(coords[:, 2], 0.0), 3)
    info = {"family": "blocks", "label": f"{bx}x{by}x{bz} blocks", "n_hex": len(conn), "n_interfaces": ni,
            "ratio": ratio}
    if states:
        codes = st1[:, :, mc.S_CODE].astype(int).ravel()
        info["states"] = {name: int((codes == c).sum()) for c, name in enumerate(("stick", "slip", "open"))}
    return coords, K, f, fixed, info


def reduce(coords, K, f, fixed):
    free = np.nonzero(~fixed)[0]
    Kf = K[free][:, free].tocsr()
    Kf.sort_indices()
    return Kf, f[free].copy(), free


# -----------------------------------------------------------------------------------------------
# child: one solver on one saved system
# -----------------------------------------------------------------------------------------------




def _warm_up(solver):
    """Library load / JIT on a tiny 3D system (not timed)."""
    coords, K, f, fixed, _ = build_blocks(2, 1, 1, e=2)
    Kf, b, free = reduce(coords, K, f, fixed)
    _run_solver(solver, Kf, b, coords, free)


def _run_solver(solver, K, b, coords, free):
    """(setup s, solve s, x, extra dict) of one solver."""
    from masonrydam.solvers.linear.direct import Factorization

    if solver.startswith("amg"):
        from masonrydam.solvers.linear.iterative import AMGSolver, rigid_body_modes

        t0 = time.perf_counter()
        B = rigid_body_modes(coords, free, 3)
        # amg-plain: pyamg smoothed aggregation with the rigid-body modes only (no node positions:
        # no tied pairs, no joint springs left out of the strength graph)
        kw = {} if solver == "amg-plain" else {"dof_coords": coords[free // 3], "dof_nodes": free // 3}
        s = AMGSolver(K, B, **kw)
        t1 = time.perf_counter()
        x = s.solve(b)
        t2 = time.perf_counter()
        extra = {"iterations": s.last_iterations, "levels": s.level_sizes, "op_complexity": s.operator_complexity,
                 "n_groups": s.n_groups, "residual": s.last_residual, "krylov": s.krylov}
        return t1 - t0, t2 - t1, x, extra
    t0 = time.perf_counter()
    f = Factorization(K, solver)
    t1 = time.perf_counter()
    x = f.solve(b)
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1, x, {"residual": float(np.linalg.norm(K @ x - b) / np.linalg.norm(b))}


def child(solver, npz, limit_bytes, xfile):
    import psutil

    z = np.load(npz)
    K = sp.csr_matrix((z["data"], z["indices"], z["indptr"]), shape=tuple(z["shape"]))
    b, coords, free = z["b"], z["coords"], z["free"]
    t0 = time.perf_counter()
    _warm_up(solver)
    warm = time.perf_counter() - t0
    rss0 = psutil.Process().memory_info().rss / 2**20
    setups, solves, peaks = [], [], []
    t_start = time.perf_counter()
    x = extra = None
    for i in range(5):
        if i and (time.perf_counter() - t_start > REPEAT_BUDGET_S):
            break
        x = None
        with RssSampler(limit_bytes) as smp:
            ts, tv, x, extra = _run_solver(solver, K, b, coords, free)
        setups.append(ts)
        solves.append(tv)
        peaks.append(smp.peak)
    np.save(xfile, x)
    out = {"solver": solver, "warmup_s": warm, "setup_s": min(setups), "solve_s": solves[int(np.argmin(setups))],
           "repeats": len(setups), "rss_before_mib": rss0, "sampled_peak_mib": max(peaks),
           "peak_rss_mib": peak_rss_mib(), **extra}
    print("JSON:" + json.dumps(out), flush=True)


def run_child(solver, npz, limit_bytes, xfile, timeout):
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, __file__, "--child", solver, npz, str(int(limit_bytes)), xfile],
                           capture_output=True, text=True, cwd=ROOT, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"solver": solver, "error": f"timeout ({timeout:.0f} s)"}
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("JSON:")]
    if p.returncode != 0 or not lines:
        if lines:
            return {"solver": solver, **json.loads(lines[-1][5:])}
        tail = (p.stderr or p.stdout).strip().splitlines()[-1:] or [f"exit status {p.returncode}"]
        return {"solver": solver, "error": tail[0][:120]}
    d = json.loads(lines[-1][5:])
    d["process_wall_s"] = time.perf_counter() - t0
    return d


REPEAT_BUDGET_S = 5.0


# -----------------------------------------------------------------------------------------------
# parent
# -----------------------------------------------------------------------------------------------


def predict(history, n):
    """Power-law extrapolation (exponent from the two largest sizes, at least 1) of a list of
    (n_eq, value); None without history."""
    if not history:
        return None
    pts = sorted(history)[-2:]
    if len(pts) == 1:
        (n1, v1), = pts
        return v1 * (n / n1) ** 1.5
    (n1, v1), (n2, v2) = pts
    alpha = max(1.0, np.log(max(v2, 1e-9) / max(v1, 1e-9)) / np.log(n2 / n1)) if n2 > n1 else 1.5
    return v2 * (n / n2) ** alpha


def default_scene_section(every=8):
    """The 2D default scene (masonrydam/scenes/wall_push.toml, 3 310 DOFs, nonlinear joints) run with
    ``linear_solver = "auto"`` (PARDISO) and ``"amg"``; and every ``every``-th tangent of the auto run
    solved by PARDISO and by three AMG variants (iterations per solve, failures)."""
    import tomllib

    import masonrydam
    from masonrydam.solvers.static import stepping as static
    from masonrydam.solvers.linear.iterative import AMGSolver, rigid_body_modes
    from masonrydam.solvers.linear.direct import Factorization, SingularMatrix

    path = ROOT / "masonrydam" / "scenes" / "wall_push.toml"
    captured, count = [], [0]
    orig = static.StaticSolver._linear_solver

    def capture(self, K):
        count[0] += 1
        if count[0] % every == 1:
            m = self.model
            captured.append((K.copy(), m.coords, m.dofmap.free.copy(), m.dim))
        return orig(self, K)

    runs = {}
    for name in ("auto", "amg"):
        data = tomllib.loads(path.read_text())
        data.setdefault("solver", {})["linear_solver"] = name
        static.StaticSolver._linear_solver = capture if name == "auto" else orig
        t0 = time.perf_counter()
        try:
            ds = masonrydam.run(masonrydam.Scene(data, base_dir=path.parent))
        finally:
            static.StaticSolver._linear_solver = orig
        runs[name] = (time.perf_counter() - t0, ds)
    print("\n== 2D default scene (wall_push.toml), full nonlinear run ==")
    print(f"{'linear_solver':<14} {'run s':>7} {'steps':>6} {'Newton its':>10}")
    for name, (t, ds) in runs.items():
        print(f"{name:<14} {t:>7.1f} {ds.sizes['step']:>6} {int(ds.iterations.sum()):>10}")
    a_, b_ = runs["auto"][1], runs["amg"][1]
    la, lb = a_.load_factor.values + a_.stage.values, b_.load_factor.values + b_.stage.values
    common = [(i, int(np.argmin(abs(lb - v)))) for i, v in enumerate(la) if np.isclose(lb, v, rtol=0, atol=1e-12).any()]
    ua, ub = a_.displacement.values, b_.displacement.values
    diffs = [np.abs(ua[i] - ub[j]).max() / np.abs(ua[i]).max() for i, j in common]
    print(f"steps at the same load factor in both runs: {len(common)}, max relative displacement difference there "
          f"{max(diffs):.1e} (the step sequences differ after the first step cut)")

    variants = [("amg (package)", {"coordinates": True}),
                ("amg, coarse_theta = 0", {"coordinates": True, "coarse_theta": 0.0}),
                ("amg-plain (no positions)", {})]
    stats = {label: [] for label, _ in variants}
    fails = {label: 0 for label, _ in variants}
    direct_fail = 0
    for K, coords, free, dim in captured:
        b = np.random.default_rng(0).standard_normal(K.shape[0])
        try:
            Factorization(K, "auto").solve(b)
        except SingularMatrix:
            direct_fail += 1
        B = rigid_body_modes(coords, free, dim)
        for label, kw in variants:
            kw = dict(kw)
            if kw.pop("coordinates", False):
                kw.update(dof_coords=coords[free // dim], dof_nodes=free // dim)
            try:
                s = AMGSolver(K, B, **kw)
                s.solve(b)
                stats[label].append(s.last_iterations)
            except SingularMatrix:
                fails[label] += 1
    print(f"\n{len(captured)} tangents of the auto run (every {every}th; random right-hand side): PARDISO raised "
          f"SingularMatrix on {direct_fail}")
    print(f"{'variant':<28} {'median its':>10} {'90 % its':>9} {'max its':>8} {'failed':>7}")
    for label, _ in variants:
        its = np.sort(stats[label])
        q = (lambda p: int(its[min(len(its) - 1, int(p * len(its)))])) if len(its) else (lambda p: -1)
        print(f"{label:<28} {q(0.5):>10} {q(0.9):>9} {int(its[-1]) if len(its) else -1:>8} {fails[label]:>7}")
    sys.stdout.flush()


def save_system(path, K, b, coords, free):
    np.savez(path, data=K.data, indices=K.indices, indptr=K.indptr, shape=np.array(K.shape), b=b,
             coords=coords, free=free)


def fmt_row(r):
    if "error" in r or "skipped" in r:
        return f"{r['solver']:<10} " + (r.get("skipped") or f"FAILED: {r['error']}")
    its = f"{r['iterations']:>5d}" if "iterations" in r else f"{'-':>5}"
    err = f"{r['x_rel_diff']:.1e}" if r.get("x_rel_diff") is not None else "ref"
    return (f"{r['solver']:<10} {r['setup_s']:>9.2f} {r['solve_s']:>8.2f} {r['setup_s'] + r['solve_s']:>8.2f} {its} "
            f"{r['peak_rss_mib']:>9.0f} {r['sampled_peak_mib'] - r['rss_before_mib']:>8.0f} {r['residual']:>9.1e} "
            f"{err:>8}")


HEADER = (f"{'solver':<10} {'setup s':>9} {'solve s':>8} {'total s':>8} {'its':>5} {'peak MiB':>9} {'delta':>8} "
          f"{'residual':>9} {'|x-x_ref|':>8}")


def run_size(tmp, key, build, solvers, history, mem_limit_gb, time_limit_s):
    import psutil

    t0 = time.perf_counter()
    coords, K, f, fixed, info = build()
    Kf, b, free = reduce(coords, K, f, fixed)
    del K
    info.update(n_eq=Kf.shape[0], nnz=Kf.nnz, build_s=time.perf_counter() - t0)
    npz = str(Path(tmp) / f"{key}.npz")
    save_system(npz, Kf, b, coords, free)
    del Kf, b, coords, free
    rows, xs = [], {}
    n = info["n_eq"]
    for s in solvers:
        pm = predict(history.get((s, "mem")), n)
        pt = predict(history.get((s, "time")), n)
        avail_gb = psutil.virtual_memory().available / 2**30
        limit_gb = min(mem_limit_gb, avail_gb - 2.0)
        if pm is not None and pm / 1024 > limit_gb:
            rows.append({"solver": s, "skipped": f"skipped: predicted peak {pm / 1024:.1f} GB > {limit_gb:.1f} GB"})
            continue
        if pt is not None and pt > time_limit_s:
            rows.append({"solver": s, "skipped": f"skipped: predicted time {pt:.0f} s > {time_limit_s:.0f} s"})
            continue
        xfile = str(Path(tmp) / f"{key}_{s}.npy")
        r = run_child(s, npz, limit_gb * 2**30, xfile, timeout=max(60.0, 1.5 * time_limit_s))
        if "error" not in r:
            history.setdefault((s, "mem"), []).append((n, r["peak_rss_mib"]))
            history.setdefault((s, "time"), []).append((n, r["setup_s"] + r["solve_s"]))
            xs[s] = np.load(xfile)
            os.unlink(xfile)
        rows.append(r)
    ref = next((xs[s] for s in ("pardiso", "superlu") if s in xs), None)
    for r in rows:
        if r["solver"] in xs:
            r["x_rel_diff"] = None if ref is None or xs[r["solver"]] is ref else \
                float(np.linalg.norm(xs[r["solver"]] - ref) / np.linalg.norm(ref))
    os.unlink(npz)
    return info, rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max-dof", type=int, default=500_000, help="largest model (equations)")
    ap.add_argument("--families", default="box,blocks")
    ap.add_argument("--solvers", default="pardiso,superlu,amg")
    ap.add_argument("--no-penalty-sweep", action="store_true")
    ap.add_argument("--no-states", action="store_true", help="skip the Mohr-Coulomb joint-state tangents")
    ap.add_argument("--no-scene", action="store_true", help="skip the 2D default-scene section")
    ap.add_argument("--mem-limit-gb", type=float, default=MEM_LIMIT_GB)
    ap.add_argument("--time-limit-s", type=float, default=TIME_LIMIT_S)
    ap.add_argument("--json", help="write all results to this file")
    ap.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.child[0], a.child[1], int(a.child[2]), a.child[3])
        return

    import psutil
    import pyamg
    import scipy

    solvers = a.solvers.split(",")
    print(f"masonrydam 3D linear solvers | CPU: {cpu_model()} ({os.cpu_count()} logical cores), "
          f"{psutil.virtual_memory().total / 2**30:.1f} GiB | numpy {np.__version__}, scipy {scipy.__version__}, "
          f"pyamg {pyamg.__version__} | 1 thread per solver")
    results = {"box": [], "blocks": [], "penalty": [], "states": []}
    families = {
        "box": [(f"box{n}", (lambda n=n: build_box(n)))
                for n in BOX_SIZES if 3 * (2 * n + 1) * (n + 1) * n <= a.max_dof],
        "blocks": [(f"blocks{bx}x{by}x{bz}", (lambda s=(bx, by, bz): build_blocks(*s)))
                   for bx, by, bz in BLOCK_SIZES if 3 * bx * by * bz * (ELEMS_PER_BLOCK + 1) ** 3 <= a.max_dof],
    }
    with tempfile.TemporaryDirectory(prefix="bench_solvers_3d_") as tmp:
        for fam in [f for f in a.families.split(",") if f]:
            history = {}
            print(f"\n== family '{fam}' ==")
            for key, build in families[fam]:
                info, rows = run_size(tmp, key, build, solvers, history, a.mem_limit_gb, a.time_limit_s)
                print(f"\n{info['label']}: {info['n_eq']:,} equations, nnz {info['nnz']:,}, {info['n_hex']:,} hex8, "
                      f"{info['n_interfaces']:,} quad4 interfaces (build {info['build_s']:.1f} s)")
                print(HEADER)
                for r in rows:
                    print(fmt_row(r))
                results[fam].append({"info": info, "rows": rows})
                sys.stdout.flush()
        if not a.no_penalty_sweep:
            print(f"\n== penalty sweep: {PENALTY_MODEL} blocks, kn = ks = ratio * E / h ==")
            for ratio in PENALTY_RATIOS:
                info, rows = run_size(tmp, f"pen{ratio:g}",
                                      lambda r=ratio: build_blocks(*PENALTY_MODEL, ratio=r),
                                      ["pardiso", "amg", "amg-plain"], {}, a.mem_limit_gb, a.time_limit_s)
                print(f"\nkn h / E = {ratio:g}: {info['n_eq']:,} equations")
                print(HEADER)
                for r in rows:
                    print(fmt_row(r))
                results["penalty"].append({"info": info, "rows": rows})
                sys.stdout.flush()
        if not a.no_states:
            print("\n== Mohr-Coulomb joints in the three states (tangent of a nonlinear iteration, kn h / E = "
                  f"{MAIN_RATIO:g}) ==")
            for model in STATES_MODELS:
                info, rows = run_size(tmp, "states" + "x".join(map(str, model)),
                                      lambda m=model: build_blocks(*m, states=True),
                                      ["pardiso", "amg", "amg-plain"], {}, a.mem_limit_gb, a.time_limit_s)
                st = info["states"]
                print(f"\n{info['label']}: {info['n_eq']:,} equations; joint points stick {st['stick']:,}, slip "
                      f"{st['slip']:,}, open {st['open']:,}")
                print(HEADER)
                for r in rows:
                    print(fmt_row(r))
                results["states"].append({"info": info, "rows": rows})
                sys.stdout.flush()
    if not a.no_scene:
        default_scene_section()
    print("\nsetup = factorization (direct) or near-nullspace + tie detection + AMG hierarchy (amg); solve = one "
          "solve (amg: CG to ||Kx - b|| <= 1e-10 ||b||); peak MiB = high-water RSS (VmHWM) of the solver's process "
          "(incl. the loaded K and the warm-up); delta = sampled peak RSS - RSS before setup; |x-x_ref| relative to "
          "the direct solution.")
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=1, default=float))


if __name__ == "__main__":
    main()
