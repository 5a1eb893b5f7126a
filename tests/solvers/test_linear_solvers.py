"""Linear solver backends: the AMG-preconditioned Krylov solver against the direct solvers.

Sources: smoothed aggregation AMG with the rigid-body near-nullspace (Vanek, Mandel & Brezina 1996,
Computing 56:179-196; pyamg), CG for symmetric and FGMRES for non-symmetric matrices (Saad 2003,
Iterative Methods for Sparse Linear Systems, alg. 9.1 and sec. 9.4.1); the tied-node collapse for
penalty interfaces is described in masonrydam/solvers/linear/iterative.py. The reference answer of every
test is the direct solve of the same matrix (PARDISO, or SuperLU where PARDISO cannot load).
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import masonrydam
from masonrydam.assembly.dofmap import DofMap
from masonrydam.assembly.groups import ContinuumGroup
from masonrydam.assembly.model import Model
from masonrydam.elements import shapes
from masonrydam.elements.continuum import continuum_stiffness
from masonrydam.elements.interface import interface_evaluate, interface_tables
from masonrydam.elements.quadrature import tensor_rule
from masonrydam.materials import mohr_coulomb as mc
from masonrydam.materials.elastic import elasticity_matrix
from masonrydam.scene import build_mesh, build_model, build_stages
from masonrydam.scene.scene import Scene
from masonrydam.solvers.linear import direct as linear
from masonrydam.solvers.linear.iterative import AMGSolver, is_symmetric, rigid_body_modes, tied_groups
from masonrydam.solvers.linear.direct import Factorization, SingularMatrix, make_solver, resolve_backend
from scenes import small_wall

pytest.importorskip("pyamg")

RTOL = 1e-8


def direct(K, b):
    return Factorization(K, "auto").solve(b)


def rel_err(x, ref):
    return np.linalg.norm(x - ref) / np.linalg.norm(ref)


def model_system(scene_dict, u=None):
    """(model, K, b, free) of the first stage at displacement u (default 0)."""
    sc = Scene(scene_dict)
    s = sc.normalized
    mesh = build_mesh(s, sc.base_dir)
    model = build_model(s, mesh)
    st = build_stages(s, mesh, model)[0]
    model.set_constraints(st.supports | st.prescribed)
    u = np.zeros(model.n_dof) if u is None else u
    f_int, K = model.evaluate(u, want_tangent=True)
    free = model.dofmap.free
    return model, K, (st.force - f_int)[free], free


def amg_for(model, K, **kw):
    free = model.dofmap.free
    return AMGSolver(K, rigid_body_modes(model.coords, free, model.dim),
                     dof_coords=model.coords[free // model.dim], dof_nodes=free // model.dim, **kw)


# ------------------------------------------------------------------------------------------------
# near-nullspace and helpers
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("dim", [2, 3])
def test_rigid_body_modes_are_the_nullspace_of_an_unconstrained_stiffness(dim):
    rng = np.random.default_rng(0)
    coords = rng.uniform(0, 3, (7, dim))
    B = rigid_body_modes(coords, np.arange(coords.size), dim)
    assert B.shape == (coords.size, 3 if dim == 2 else 6)
    # every column is a rigid motion: the distance between any two nodes is unchanged to first order
    for k in range(B.shape[1]):
        u = B[:, k].reshape(-1, dim)
        for i in range(7):
            for j in range(i):
                d = coords[i] - coords[j]
                assert abs(d @ (u[i] - u[j])) <= 1e-12 * np.linalg.norm(d)
    assert np.linalg.matrix_rank(B) == B.shape[1]
    norms = np.linalg.norm(B, axis=0)
    assert norms.max() / norms.min() < 3.0, "columns of comparable norms"
    # restriction to a subset of DOFs = rows of the full set
    sub = np.array([1, 4, 5, coords.size - 1])
    Bs = rigid_body_modes(coords, sub, dim)
    assert Bs.shape == (4, B.shape[1])


def test_symmetry_check_and_tied_groups():
    A = sp.csr_matrix(np.array([[4.0, -1, 0], [-1, 4, -2], [0, -2, 4]]))
    assert is_symmetric(A)
    N = A.tolil()
    N[0, 1] = -1.1
    assert not is_symmetric(N.tocsr())
    # two coincident DOFs joined by a stiff spring form one group; a far one does not
    K = sp.csr_matrix(np.array([[101.0, -100, -1], [-100, 101, 0], [-1, 0, 2]]))
    X = np.array([[0.0, 0], [0, 0], [1, 0]])
    B = np.ones((3, 1))
    ng, lab = tied_groups(K, B, X)
    assert ng == 2 and lab[0] == lab[1] != lab[2]
    Xfar = np.array([[0.0, 0], [0.5, 0], [1, 0]])
    assert tied_groups(K, B, Xfar)[0] == 3


# ------------------------------------------------------------------------------------------------
# AMG solves to the direct solution
# ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kn_scale", [1.0, 1e3])
def test_amg_2d_jointed_wall(kn_scale):
    """2D running-bond wall with line2 interfaces: soft (Lourenco & Rots) and 1000x stiffer joints."""
    kn, ks = f"{82 * kn_scale} N/mm3", f"{36 * kn_scale} N/mm3"
    model, K, b, free = model_system(small_wall(normal_stiffness=kn, shear_stiffness=ks))
    ref = direct(K, b)
    s = amg_for(model, K)
    assert s.backend == "amg" and s.krylov == "cg" and s.symmetric
    x = s.solve(b)
    assert rel_err(x, ref) <= RTOL
    assert s.last_residual <= 1e-10 and 0 < s.last_iterations < 60
    assert s.setup_time_s > 0 and s.iterations == [s.last_iterations]
    if kn_scale > 1:
        assert s.n_groups < K.shape[0], "stiff joints: coincident node pairs tied"
    else:
        assert s.joint_links_dropped > 0, "soft joints: left out of the first strength graph"


def hex8_tables():
    """Trilinear hex8 at 2x2x2 Gauss points (Hughes 2000, sec. 3.5), if shapes has no hex8."""
    if "hex8" in shapes.ELEMENT_TYPES:
        from masonrydam.elements.continuum import element_tables

        return element_tables("hex8")
    c = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                  [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
    pts, w = tensor_rule("gauss", 2, 3)
    f = 1 + pts[:, None, :] * c[None, :, :]
    dN = np.empty((len(pts), 3, 8))
    for i in range(3):
        j, k = [m for m in range(3) if m != i]
        dN[:, i, :] = 0.125 * c[None, :, i] * f[:, :, j] * f[:, :, k]
    return 0.125 * f.prod(axis=2), np.ascontiguousarray(dN), w


def hex_box(nx, ny, nz, origin=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0)):
    xs = [origin[d] + np.linspace(0, size[d], n + 1) for d, n in enumerate((nx, ny, nz))]
    X, Y, Z = np.meshgrid(*xs, indexing="ij")
    coords = np.stack([X.ravel(), Y.ravel(), Z.ravel()], 1)
    gid = np.arange(len(coords)).reshape(nx + 1, ny + 1, nz + 1)
    i, j, k = [a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")]
    off = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    conn = np.stack([gid[i + a, j + b_, k + c] for a, b_, c in off], 1).astype(np.int64)
    return coords, conn, gid


def assemble(blocks, n):
    rows, cols, vals = [], [], []
    for dofs, ke in blocks:
        nd = dofs.shape[1]
        rows.append(np.repeat(dofs, nd, 1).ravel())
        cols.append(np.tile(dofs, (1, nd)).ravel())
        vals.append(ke.ravel())
    K = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    K.sum_duplicates()
    return K


def hex_stiffness(coords, conn, E=20e9, nu=0.2):
    _, dN, w = hex8_tables()
    ne = len(conn)
    D = np.ascontiguousarray(elasticity_matrix(E, nu, "3d")[None])
    ke = np.empty((ne, 24, 24))
    assert continuum_stiffness(coords, conn, dN, w, D, np.zeros(ne, np.int64), np.ones(ne), ke,
                               np.zeros(1, np.int64)) == 0
    return DofMap.node_dofs(conn, 3), ke


def reduce_base_fixed(coords, K, rng):
    fixed = np.repeat(np.isclose(coords[:, 2], 0.0), 3)
    free = np.nonzero(~fixed)[0]
    return K[free][:, free].tocsr(), rng.standard_normal(len(free)), free


def test_amg_3d_hex8_block():
    """3D elastic hex8 block (2 x 1 x 1 m, 8 x 4 x 4 elements), base fixed."""
    coords, conn, _ = hex_box(8, 4, 4, size=(2.0, 1.0, 1.0))
    if "hex8" in shapes.ELEMENT_TYPES:  # through the Model, as the solver sees it
        D = np.ascontiguousarray(elasticity_matrix(20e9, 0.2, "3d")[None])
        ne = len(conn)
        g = ContinuumGroup("block", "hex8", conn, DofMap.node_dofs(conn, 3), D, np.zeros(ne, np.int64),
                           np.ones(ne), np.full(ne, 2400.0))
        model = Model(coords, [g], [])
        model.set_constraints(np.repeat(np.isclose(coords[:, 2], 0.0), 3))
        _, K = model.evaluate(np.zeros(model.n_dof))
        free = model.dofmap.free
    else:
        K, _, free = reduce_base_fixed(coords, assemble([hex_stiffness(coords, conn)], coords.size),
                                       np.random.default_rng(0))
    b = np.random.default_rng(1).standard_normal(K.shape[0])
    ref = direct(K, b)
    s = make_solver(K, "amg", near_nullspace=rigid_body_modes(coords, free, 3), dof_coords=coords[free // 3],
                    dof_nodes=free // 3)
    assert isinstance(s, AMGSolver) and s.levels >= 2
    x = s.solve(b)
    assert rel_err(x, ref) <= RTOL
    assert s.last_iterations < 40
    # without the rotations in the near-nullspace the same solve needs many more iterations
    s1 = AMGSolver(K, rigid_body_modes(coords, free, 3)[:, :3])
    s1.solve(b)
    assert s1.last_iterations > s.last_iterations


def two_blocks_3d(ratio, e=3):
    """Two unit cubes stacked in z, e^3 hex8 each, joined by e^2 quad4 interfaces (nodal rule, linear
    joint kn = ks = ratio * E / h); base fixed. Returns coords, K (free DOFs), free."""
    c1, k1, g1 = hex_box(e, e, e)
    c2, k2, g2 = hex_box(e, e, e, origin=(0.0, 0.0, 1.0))
    coords = np.vstack([c1, c2])
    n1 = len(c1)
    conn = np.vstack([k1, k2 + n1])
    g2 = g2 + n1
    q = np.arange(e)
    A, B = [a.ravel() for a in np.meshgrid(q, q, indexing="ij")]
    bot = np.stack([g1[A, B, e], g1[A + 1, B, e], g1[A + 1, B + 1, e], g1[A, B + 1, e]], 1)
    top = np.stack([g2[A, B, 0], g2[A + 1, B, 0], g2[A + 1, B + 1, 0], g2[A, B + 1, 0]], 1)
    icon = np.hstack([bot, top]).astype(np.int64)
    E = 20e9
    kn = ratio * E * e
    params = mc.joint_params(kn, kn, cohesion=1e300, friction_angle_deg=0.0, tensile_strength=1e300)[None].copy()
    N, dN, w, _ = interface_tables("quad4", "lumped")
    ni, nip = len(icon), len(w)
    st = np.zeros((ni, nip, mc.N_JOINT_STATE))
    kei = np.empty((ni, 24, 24))
    assert interface_evaluate(coords, icon, np.zeros(coords.size), N, dN, w, np.ones(ni), params,
                              np.zeros(ni, np.int64), st, st.copy(), np.zeros((ni, nip, 3)), np.zeros((ni, nip, 3)),
                              np.empty((ni, 24)), kei, True, np.zeros(1, np.int64)) == 0
    K = assemble([hex_stiffness(coords, conn, E), (DofMap.node_dofs(icon, 3), kei)], coords.size)
    fixed = np.repeat(np.isclose(coords[:, 2], 0.0), 3)
    free = np.nonzero(~fixed)[0]
    return coords, K[free][:, free].tocsr(), free


@pytest.mark.parametrize("ratio", [1.0, 1e4])
def test_amg_3d_blocks_on_penalty_interfaces(ratio):
    """Stiff penalty joints (kn h / E up to 1e4) are tied and do not slow the solver down."""
    coords, K, free = two_blocks_3d(ratio)
    b = np.random.default_rng(2).standard_normal(K.shape[0])
    ref = direct(K, b)
    s = AMGSolver(K, rigid_body_modes(coords, free, 3), dof_coords=coords[free // 3], dof_nodes=free // 3)
    x = s.solve(b)
    assert rel_err(x, ref) <= RTOL
    assert s.n_groups < K.shape[0] and s.last_iterations < 30


def test_amg_hierarchy_of_one_tangent_preconditions_the_next():
    """The static AMG path reuses the multigrid hierarchy of an earlier tangent (AMGSolver.for_matrix): the joints
    between two blocks softened 100 times (as where points slide or open) are solved to the same tolerance with the
    hierarchy of the stiff ones, without a setup, and the original solver is left as it was."""
    coords, K1, free = two_blocks_3d(1.0)
    _, K2, _ = two_blocks_3d(1e-2)
    assert np.array_equal(K1.indptr, K2.indptr) and not np.allclose(K1.data, K2.data)
    b = np.random.default_rng(5).standard_normal(K1.shape[0])
    s1 = AMGSolver(K1, rigid_body_modes(coords, free, 3), dof_coords=coords[free // 3], dof_nodes=free // 3)
    s2 = s1.for_matrix(K2)
    assert s2.reused and not s1.reused and s2.setup_time_s == 0.0 and np.array_equal(s1.K.data, K1.data)
    x2 = s2.solve(b)
    assert rel_err(x2, direct(K2, b)) <= RTOL and s2.last_residual <= 1e-10
    assert 0.0 < s2.convergence_factor < 1.0
    assert rel_err(s1.solve(b), direct(K1, b)) <= RTOL  # s1 still solves its own matrix
    assert s2.krylov == "cg"
    # a non-symmetric tangent (friction couples the shear and normal jumps of a sliding point) takes FGMRES
    K3 = K2.copy()
    rows = np.repeat(np.arange(K3.shape[0]), np.diff(K3.indptr))
    k = int(np.flatnonzero(K3.indices != rows)[0])
    K3.data[k] *= 1.01
    s3 = s1.for_matrix(K3)
    assert s3.krylov == "fgmres" and not s3.symmetric
    assert rel_err(s3.solve(b), direct(K3, b)) <= RTOL


def test_amg_inexact_solve_stops_at_the_requested_residual():
    """``solve(b, rtol)`` (an inexact Newton correction, Eisenstat & Walker 1996) stops once the true relative
    residual is below rtol, in fewer iterations than the full solve; rtol never tightens the solver's own tol."""
    coords, K, free = two_blocks_3d(1.0)
    b = np.random.default_rng(6).standard_normal(K.shape[0])
    s = AMGSolver(K, rigid_body_modes(coords, free, 3), dof_coords=coords[free // 3], dof_nodes=free // 3)
    x = s.solve(b, rtol=1e-3)
    rel = np.linalg.norm(K @ x - b) / np.linalg.norm(b)
    assert rel <= 1e-3 and s.last_residual == pytest.approx(rel)
    loose = s.last_iterations
    s.solve(b)
    assert s.last_residual <= 1e-10 and s.last_iterations > loose
    s.solve(b, rtol=1e-14)
    assert s.last_residual <= 1e-10


def test_amg_block_held_by_open_joints():
    """An open joint keeps 1e-6 of its stiffness in the tangent (static.OPEN_TANGENT_REGULAR): the
    upper block is nearly free, 1e-10 is out of reach, and the solve stops at the rounding floor
    (backward error), with the residual check of the direct solvers."""
    coords, K, free = two_blocks_3d(1e-6)
    b = np.random.default_rng(4).standard_normal(K.shape[0])
    ref = direct(K, b)
    s = AMGSolver(K, rigid_body_modes(coords, free, 3), dof_coords=coords[free // 3], dof_nodes=free // 3)
    x = s.solve(b)
    assert rel_err(x, ref) <= 1e-6
    assert s.last_residual <= 1e-6 and s.last_backward_error <= 1e-14


def test_amg_nonsymmetric_sliding_joint_uses_fgmres():
    """A block sliding with friction on its bed joint: the consistent tangent is not symmetric."""
    bed = {"normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3", "cohesion": 0.0,
           "friction_angle": 30.0, "tensile_strength": 0.0, "residual_shear_stiffness": "3.6 N/mm3"}
    sc = small_wall(bed_joints=bed, length=0.4, height=0.2, elements_per_unit=3)
    model, _, _, _ = model_system(sc)
    # the upper course pressed down onto the lower one and pushed sideways (nodes are not shared
    # across the joints: every course moves as a rigid body)
    u = np.zeros(model.n_dof)
    g = model.cgroups[0]
    upper = np.unique(g.conn[model.coords[g.conn, 1].mean(axis=1) > 0.1])
    u[2 * upper] = 2e-4
    u[2 * upper + 1] = -1e-6
    f_int, K = model.evaluate(u)
    codes = np.concatenate([g.state_codes(trial=True).ravel() for g in model.igroups if g.nonlinear])
    assert (codes == 1).any(), "some bed joint points slip"
    assert not is_symmetric(K)
    b = np.random.default_rng(3).standard_normal(K.shape[0])
    ref = direct(K, b)
    s = amg_for(model, K)
    assert s.krylov == "fgmres" and not s.symmetric
    x = s.solve(b)
    assert rel_err(x, ref) <= RTOL
    assert s.last_residual <= 1e-10


def two_units_without_joint(pin: bool):
    """Two 0.2 x 0.1 m units stacked (stack bond) with no joint between them: the lower one is on
    the fixed base, the upper one floats (pin: one of its nodes held, so that only its rotation
    about that node is free)."""
    sc = small_wall(length=0.2, height=0.2, elements_per_unit=6, bond="stack")
    del sc["joints"]["head_joints"]  # one unit per course
    model, _, _, _ = model_system(sc)
    m = Model(model.coords, model.cgroups, [])
    constrained = model.dofmap.constrained.copy()
    if pin:
        g = model.cgroups[0]
        upper = np.unique(g.conn[model.coords[g.conn, 1].mean(axis=1) > 0.1])
        constrained[2 * upper[0]:2 * upper[0] + 2] = True
    m.set_constraints(constrained)
    _, K = m.evaluate(np.zeros(m.n_dof))
    b = np.zeros(m.n_dof)
    b[0::2] = 1.0  # a horizontal load on every node
    return m, K, b[m.dofmap.free]


@pytest.mark.parametrize("pin", [False, True])
def test_singular_floating_block_raises(pin):
    model, K, b = two_units_without_joint(pin)
    with pytest.raises(SingularMatrix):
        Factorization(K, "auto").solve(b)
    # the coarsest multigrid level inherits the rigid-body modes of the floating unit
    with pytest.raises(SingularMatrix, match=r"singular.*rigid body"):
        amg_for(model, K)
    if pin:
        # only the rotation is free, and a near-nullspace without rotations does not see it on the
        # coarse level: the Krylov iteration stagnates or breaks down; the message gives iterations
        # and residual
        free = model.dofmap.free
        s = AMGSolver(K, rigid_body_modes(model.coords, free, 2)[:, :2], stagnation_window=30, maxiter=400)
        pattern = r"(stagnated|broke down) after \d+ iterations.*relative residual [0-9.e+-]+"
        with pytest.raises(SingularMatrix, match=pattern):
            s.solve(b)


def test_amg_is_deterministic_and_keeps_the_global_random_state():
    """pyamg draws random start vectors; the solver seeds them, so a nonlinear run is reproducible,
    and restores numpy's global generator."""
    model, K, b, _ = model_system(small_wall(length=0.4, height=0.2, elements_per_unit=3))
    xs = []
    for seed in (1, 2):
        np.random.seed(seed)
        xs.append(amg_for(model, K).solve(b))
        assert np.random.rand() == np.random.RandomState(seed).rand()
    assert np.array_equal(xs[0], xs[1])


@pytest.mark.parametrize("size", ["one level", "multilevel"])
def test_amg_does_not_modify_the_matrix(size):
    """K may share its arrays with the model (Model.evaluate): the solver must not touch them,
    explicit zeros of the tangent pattern included."""
    model, K, b, _ = model_system(small_wall(length=0.4, height=0.2, elements_per_unit=3))
    assert (K.data == 0).any(), "the interface pattern stores explicit zeros"
    before = (K.data.copy(), K.indices.copy(), K.indptr.copy())
    one = {"max_coarse": 10**6, "tie_threshold": None} if size == "one level" else {}
    s = amg_for(model, K, **one)
    assert (s.levels == 1) == (size == "one level")
    s.solve(b)
    for a, c in zip(before, (K.data, K.indices, K.indptr)):
        assert np.array_equal(a, c)


def test_non_convergence_and_nan_raise():
    model, K, b, free = model_system(small_wall(length=0.4, height=0.2, elements_per_unit=2))
    s = amg_for(model, K, maxiter=2)
    with pytest.raises(SingularMatrix, match=r"did not converge in 2 iterations: relative residual"):
        s.solve(b)
    bad = K.copy()
    bad.data[0] = np.nan
    with pytest.raises(SingularMatrix, match="NaN"):
        amg_for(model, bad)


# ------------------------------------------------------------------------------------------------
# backend selection and the static solver
# ------------------------------------------------------------------------------------------------


def test_backend_names_and_auto_rule(monkeypatch):
    assert "amg" in linear.LINEAR_SOLVERS
    direct_name = resolve_backend("auto")
    assert direct_name in ("pardiso", "superlu")
    assert resolve_backend("auto", n_dof=10**7, dim=2) == direct_name, "2D: always direct"
    monkeypatch.setattr(linear, "AUTO_ITERATIVE_MIN_DOF", 1000)
    assert resolve_backend("auto", n_dof=999, dim=3) == direct_name
    assert resolve_backend("auto", n_dof=1000, dim=3) == "amg"
    assert resolve_backend("amg") == "amg"
    with pytest.raises(ValueError, match="unknown linear solver"):
        resolve_backend("cholmod")
    with pytest.raises(ValueError, match="make_solver"):
        Factorization(sp.identity(3, format="csr"), "amg")
    K = sp.diags([-np.ones(1999), 2.5 * np.ones(2000), -np.ones(1999)], [-1, 0, 1], format="csr")
    modes = np.ones((2000, 6))
    assert isinstance(make_solver(K, "auto", modes, dim=3), AMGSolver)
    assert isinstance(make_solver(K, "auto", modes), AMGSolver), "6 modes: 3D"
    assert isinstance(make_solver(K, "auto", dim=3), Factorization), "no near-nullspace: direct"
    assert isinstance(make_solver(K, "auto", modes[:, :3], dim=2), Factorization)
    assert isinstance(make_solver(K, "amg"), AMGSolver)
    assert isinstance(make_solver(K, "superlu"), Factorization)


def test_static_solver_amg_matches_auto():
    """A block pushed along its Mohr-Coulomb bed joint on a fixed base (blocks_2d, about 1100 DOFs):
    sticking, then sliding (non-symmetric tangents, FGMRES); the static solver with the AMG backend
    gives the answer of the direct one."""
    blocks = [{"x0": 0.0, "y0": 0.0, "x1": 2.0, "y1": 0.5, "group": "base"},
              {"x0": 0.0, "y0": 0.5, "x1": 2.0, "y1": 0.6, "group": "block"}]
    stages = [{"name": "gravity", "steps": 1, "loads": [{"type": "self_weight"}]},
              {"name": "push", "steps": 4,
               "loads": [{"type": "displacement", "set": "top", "components": ["x"], "value": [2e-4]}]}]
    runs = {}
    for name in ("auto", "amg"):
        sc = {"model": {"name": "blocks", "thickness": 1.0, "gravity": [0.0, -9.80665]},
              "mesh": {"generator": "blocks_2d", "parameters": {"blocks": blocks, "element_size": 0.05,
                                                                "rotation_deg": 10.0}},
              "materials": {g: {"youngs_modulus": 200e9, "poisson_ratio": 0.2, "density": 2000.0}
                            for g in ("base", "block")},
              "joints": {"joints": {"normal_stiffness": 1e12, "shear_stiffness": 1e12, "friction_angle": 30.0,
                                    "cohesion": 0.0}},
              "supports": [{"set": "base", "components": ["x", "y"]}],
              "stages": stages, "solver": {"linear_solver": name, "joint_space": "off"}}
        runs[name] = masonrydam.run(sc)
    assert runs["amg"].attrs.get("linear_solver_backend", "amg") == "amg"
    u_ref = runs["auto"].displacement.values
    u_amg = runs["amg"].displacement.values
    assert np.abs(u_amg - u_ref).max() <= 1e-7 * np.abs(u_ref).max()
    assert (runs["amg"].joint_state.isel(step=-1).values == 1).all(), "the push makes the joint slide"
    assert np.array_equal(runs["amg"].joint_state.values, runs["auto"].joint_state.values)
    # the AMG path solves each correction inexactly (Eisenstat & Walker's forcing term) and reuses multigrid
    # hierarchies: more Newton iterations than the direct path's exact ones can be, never the answer
    assert runs["amg"].attrs["krylov_iterations"] > 0


# ------------------------------------------------------------------------------------------------
# sparse L D L^T with numba substitutions (the dynamic solver's all-stick matrices)
# ------------------------------------------------------------------------------------------------


def test_symmetric_factorization_equals_the_direct_solve_on_a_jointed_wall():
    """``L D L^T`` of the stiffness of a jointed wall (stiff penalty joints, a wide spread of pivots)
    plus a mass-like diagonal, as in an effective matrix: one and many right-hand sides give the
    general direct solve's answer (both are backward stable on an SPD matrix; Higham 2002, Thm. 10.3),
    and the factor has no more entries than a dense lower triangle."""
    model, K, b, free = model_system(small_wall(elements_per_unit=2))
    Kf = (K + sp.diags(np.full(K.shape[0], 1e-3 * K.diagonal().max()))).tocsr()
    bf = b + 1e-6 * np.linalg.norm(b)  # no zero entries
    f = linear.SymmetricFactorization(Kf)
    assert f.backend == "ldlt"
    ref = direct(Kf, bf)
    assert rel_err(f.solve(bf), ref) < 1e-10
    B = np.column_stack([bf, np.roll(bf, 7), -2.0 * bf])
    X = f.solve(B)
    assert X.shape == B.shape
    for c in range(3):
        assert rel_err(X[:, c], direct(Kf, B[:, c])) < 1e-10
    # the same substitutions up to the order of the backward sums (four partial sums in the vector kernel)
    assert rel_err(X[:, 0], f.solve(bf)) < 1e-13
    n = Kf.shape[0]
    assert n < f.nnz_factor < n * (n + 1) // 2


@pytest.mark.parametrize("max_width", [1, 3, 64])
def test_supernodal_block_solve_equals_the_entry_by_entry_one(monkeypatch, max_width):
    """The block substitution by supernodes (dense products through BLAS; Liu, Ng & Peyton 1993) gives
    the entry-by-entry substitution's answer to round-off on the jointed wall's effective matrix,
    whatever the widest supernode allowed; every supernode it uses is a true one (each column holds
    the rows of its diagonal block and then those of the supernode's last column)."""
    from masonrydam.solvers.linear.ldlt_kernels import supernode_partition

    model, K, b, free = model_system(small_wall(elements_per_unit=2))
    Kf = (K + sp.diags(np.full(K.shape[0], 1e-3 * K.diagonal().max()))).tocsr()
    rng = np.random.default_rng(2)
    B = rng.standard_normal((Kf.shape[0], 5))
    f = linear.SymmetricFactorization(Kf)
    X_entries = f.solve(B)
    assert f._supernodes is None  # a small factor keeps the entry-by-entry kernel
    monkeypatch.setattr(linear, "SUPERNODAL_MIN_FACTOR", 0)
    monkeypatch.setattr(linear, "SUPERNODE_MAX_WIDTH", max_width)
    X_super = f.solve(B)
    starts = f._supernodes[0]
    np.testing.assert_allclose(X_super, X_entries, rtol=0, atol=1e-12 * np.abs(X_entries).max())
    assert rel_err(X_super[:, 0], direct(Kf, B[:, 0])) < 1e-10
    widths = np.diff(starts)
    assert widths.max() <= max_width and widths.sum() == Kf.shape[0]
    if max_width > 1:
        assert widths.max() > 1, "the wall's factor has supernodes wider than one column"
    Lp, Li = f._Lp, f._Li
    for s, e in zip(starts[:-1], starts[1:]):
        below = Li[Lp[e - 1]:Lp[e]]
        for c in range(s, e):
            np.testing.assert_array_equal(Li[Lp[c]:Lp[c + 1]], np.concatenate([np.arange(c + 1, e), below]))
    assert np.array_equal(supernode_partition(Lp, Li, max_width), starts)


def test_symmetric_factorization_refuses_what_it_cannot_factorize():
    """Not symmetric: ValueError (the caller falls back to LU); indefinite or singular (a pivot that is
    not positive): SingularMatrix naming the pivots; non-finite entries: SingularMatrix; a right-hand
    side that overflows: SingularMatrix, never a NaN handed back."""
    A = sp.diags([-1.0, 4.0, -1.0], [-1, 0, 1], shape=(6, 6), format="csr")
    with pytest.raises(ValueError, match="symmetric"):
        linear.SymmetricFactorization((A + sp.csr_matrix(([0.5], ([0], [3])), shape=(6, 6))).tocsr())
    with pytest.raises(SingularMatrix, match="not positive"):
        linear.SymmetricFactorization((-A).tocsr())  # negative definite: every pivot negative
    bad = A.copy()
    bad.data[0] = np.nan
    with pytest.raises(SingularMatrix, match="NaN"):
        linear.SymmetricFactorization(bad)
    f = linear.SymmetricFactorization(A)
    x = f.solve(np.arange(6.0))
    np.testing.assert_allclose(A @ x, np.arange(6.0), rtol=1e-14, atol=1e-14)
    tiny = linear.SymmetricFactorization((1e-300 * A).tocsr())
    with pytest.raises(SingularMatrix, match="NaN or infinity"):
        tiny.solve(np.full(6, 1e10))  # the solution is about 1e310


@pytest.mark.skipif(resolve_backend("auto") != "pardiso", reason="PARDISO is not available here")
def test_refactorization_with_the_kept_analysis_solves_the_new_matrix():
    """A matrix of the same pattern with other values (a joint stiffness changed by six orders, as when
    a joint opens) is refactorized with the kept symbolic analysis and solves to the accuracy of a
    fresh factorization; another pattern, and SuperLU, are refused."""
    rng = np.random.default_rng(3)
    n = 400
    A = sp.random(n, n, density=0.01, random_state=rng, format="csr")
    K = (A + A.T + sp.identity(n) * 10.0).tocsr()
    K.sort_indices()
    fact = Factorization(K, "pardiso")
    K2 = K.copy()
    K2.data = K.data * rng.uniform(0.5, 2.0, K.nnz)
    K2 = ((K2 + K2.T) * 0.5).tocsr()
    K2.sort_indices()
    K2.data[K2.indices == 7] *= 1e-6  # a softened column (non-symmetric now)
    assert np.array_equal(K2.indptr, K.indptr) and np.array_equal(K2.indices, K.indices)
    b = rng.standard_normal(n)
    assert fact.refactorize(K2)
    x = fact.solve(b)
    ref = Factorization(K2, "superlu").solve(b)
    assert np.linalg.norm(K2 @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert rel_err(x, ref) < 1e-9 and fact.analyses == 1
    other = (K + sp.eye(n, k=5)).tocsr()
    assert not fact.refactorize(other)
    assert not Factorization(K, "superlu").refactorize(K2)


@pytest.mark.slow
def test_static_run_reuses_the_symbolic_analysis():
    """A nonlinear static run with PARDISO analyses the tangent pattern once per constraint set (and
    again only where the kept matching perturbs pivots), not once per factorization, and reports both
    counts; the answer is that of a run that analyses every
    time (the same Newton path to the solver tolerance)."""
    from masonrydam.solvers.static import stepping as static

    if resolve_backend("auto") != "pardiso":
        pytest.skip("PARDISO is not available here")
    import tomllib

    from masonrydam.cli.main import default_scene_path

    data = tomllib.loads(default_scene_path().read_text())
    data["stages"][1]["steps"] = 6
    data["solver"] = {"joint_space": "off"}  # the general Newton path: a tangent factorization per iteration
    ds = masonrydam.run(data)
    fact, analyses = int(ds.attrs["factorizations"]), int(ds.attrs["symbolic_analyses"])
    assert fact > 20 and analyses <= 0.05 * fact, (fact, analyses)
    original = static.StaticSolver._factorize

    def fresh(self, K):  # the old behaviour: a new factorization (analysis included) every time
        self._fact = None
        return original(self, K)

    static.StaticSolver._factorize = fresh
    try:
        ref = masonrydam.run(data)
    finally:
        static.StaticSolver._factorize = original
    assert int(ref.attrs["symbolic_analyses"]) == int(ref.attrs["factorizations"])
    u, u_ref = ds.displacement.values[-1], ref.displacement.values[-1]
    assert np.abs(u - u_ref).max() <= 1e-6 * np.abs(u_ref).max()
