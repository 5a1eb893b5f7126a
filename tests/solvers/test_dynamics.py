"""Dynamics: mass, modal analysis, Rayleigh damping, time integration, base excitation, energy balance.

Every test compares with a closed form or published data (source in the docstring):
- single mass on a spring (one quad4 element in simple shear, top nodes guided: an exact SDOF for a
  uniform horizontal base motion) against the exact harmonic response (Chopra, *Dynamics of
  Structures*, 4th ed. 2012, eqs. 3.2.1-3.2.4) and the exact response to the El Centro 1940 NS record
  (piecewise-linear excitation, Chopra sec. 5.2, Table 5.2.1; peak deformation 2.67 in for T = 0.5 s,
  2 % damping, Chopra Fig. 6.4.1);
- integrator properties (Newmark 1959; Hilber, Hughes & Taylor 1977; Chung & Hulbert 1993;
  Hughes, *The Finite Element Method* 2000, ch. 9);
- cantilever modal frequencies against Euler-Bernoulli beam theory (Chopra sec. 16.3, Blevins 1979);
- Newmark (1965) sliding block, Housner (1963) rocking block (closed forms).
"""
from __future__ import annotations

import math
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import scipy.optimize

import masonrydam
from masonrydam.effects import loads as L
from masonrydam.assembly.dofmap import DofMap
from masonrydam.assembly.groups import ContinuumGroup
from masonrydam.assembly.model import Model
from masonrydam.materials.elastic import elasticity_matrix
from masonrydam.scene import build_mesh, build_model, build_stages
from masonrydam.scene.scene import Scene
from masonrydam.assembly.damping import RayleighDamping, rayleigh_coefficients
from masonrydam.solvers.dynamic import DynamicSettings, DynamicSolver, DynamicStage, GroundMotion, modal_analysis
from repository_paths import TESTS
from scenes import ROCKING_BLOCK_HEIGHT, ROCKING_BLOCK_WIDTH, rocking_block, rocking_block_model, sliding_block

G = 9.80665


# ----------------------------------------------------------------------------------------------
# single degree of freedom: one quad4 in simple shear
# ----------------------------------------------------------------------------------------------

def sdof(omega: float, rho: float = 2000.0):
    """One 1 x 1 m quad4 (thickness 1 m, nu = 0), base fixed, top nodes free in x only. With lumped
    mass the two top nodes carry m = rho/2 and the uniform shear mode (u_x = gamma y, exact for the
    bilinear element) has k = G A / h: an exact SDOF for a horizontal base motion (the other mode,
    stretching of the top edge, is orthogonal to it and not excited)."""
    m = rho / 2.0
    Gmod = omega**2 * m  # k = G * 1 * 1 / 1
    coords = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    conn = np.array([[0, 1, 2, 3]])
    D = elasticity_matrix(2.0 * Gmod, 0.0, "plane_stress")[None]
    g = ContinuumGroup("spring", "quad4", conn, DofMap.node_dofs(conn, 2), np.ascontiguousarray(D),
                       np.zeros(1, dtype=np.int64), np.ones(1), np.full(1, rho))
    model = Model(coords, [g], [])
    supports = np.zeros(8, dtype=bool)
    supports[[0, 1, 2, 3, 5, 7]] = True  # base nodes x, y; top nodes y
    return model, supports, m


def run_sdof(omega, settings, ground, duration, u0=None):
    model, supports, _ = sdof(omega)
    stage = DynamicStage("sdof", duration, supports, ground, settings)
    out = []
    solver = DynamicSolver(model, settings)
    x0 = None
    if u0 is not None:
        x0 = np.zeros(model.n_dof)
        x0[[4, 6]] = u0
    solver.run(stage, u0=x0, equilibrate=u0 is None,
               on_step=lambda r: out.append((r["t"], r["u"][4], r["u"][6], r["energy"]["error"])))
    out = np.array(out)
    np.testing.assert_allclose(out[:, 1], out[:, 2], rtol=1e-9, atol=1e-15)  # the top nodes move together
    return out[:, 0], out[:, 1], solver


def chopra_recurrence(p, dt, omega, zeta, m=1.0):
    """Exact response of m u'' + c u' + k u = p(t) for p linear between samples (Chopra 2012, sec. 5.2,
    Table 5.2.1), zero initial conditions."""
    k = m * omega**2
    wd = omega * math.sqrt(1 - zeta**2)
    e = math.exp(-zeta * omega * dt)
    s, c = math.sin(wd * dt), math.cos(wd * dt)
    r = zeta / math.sqrt(1 - zeta**2)
    A = e * (r * s + c)
    B = e * s / wd
    C = (2 * zeta / (omega * dt) + e * (((1 - 2 * zeta**2) / (wd * dt) - r) * s - (1 + 2 * zeta / (omega * dt)) * c)) / k
    D = (1 - 2 * zeta / (omega * dt) + e * ((2 * zeta**2 - 1) / (wd * dt) * s + 2 * zeta / (omega * dt) * c)) / k
    Ap = -e * omega / math.sqrt(1 - zeta**2) * s
    Bp = e * (c - r * s)
    Cp = (-1 / dt + e * ((omega / math.sqrt(1 - zeta**2) + zeta / (dt * math.sqrt(1 - zeta**2))) * s + c / dt)) / k
    Dp = (1 - e * (r * s + c)) / (k * dt)
    u = np.zeros(len(p))
    v = 0.0
    for i in range(len(p) - 1):
        u[i + 1] = A * u[i] + B * v + C * p[i] + D * p[i + 1]
        v = Ap * u[i] + Bp * v + Cp * p[i] + Dp * p[i + 1]
    return u


def test_sdof_harmonic_base_motion_matches_exact_solution():
    """Chopra (2012) eqs. 3.2.1-3.2.4: p = -m A sin(w t) from rest, 5 % damping (mass-proportional
    Rayleigh damping a = 2 zeta omega gives exactly zeta for the SDOF). Newmark average acceleration
    with 200 steps per period: the whole history within 1 % of the peak."""
    omega, zeta, Ag = 2 * math.pi * 2.0, 0.05, 3.0
    wg = 0.8 * omega
    dt = (2 * math.pi / omega) / 200
    t_rec = np.arange(0, 3.0 + dt / 2, dt)
    gm = GroundMotion(0, Ag * np.sin(wg * t_rec), dt)
    s = DynamicSettings(integrator="newmark_average", dt=dt, damping=RayleighDamping(2 * zeta * omega, 0.0))
    t, u, _ = run_sdof(omega, s, [gm], 3.0)
    r = wg / omega
    p0 = -Ag  # per unit mass
    den = (1 - r**2) ** 2 + (2 * zeta * r) ** 2
    Cc, Dc = p0 / omega**2 * (1 - r**2) / den, p0 / omega**2 * (-2 * zeta * r) / den
    wd = omega * math.sqrt(1 - zeta**2)
    A = -Dc
    B = (zeta * omega * A - wg * Cc) / wd
    exact = np.exp(-zeta * omega * t) * (A * np.cos(wd * t) + B * np.sin(wd * t)) + Cc * np.sin(wg * t) + Dc * np.cos(wg * t)
    assert np.abs(u - exact).max() <= 0.01 * np.abs(exact).max()


@pytest.mark.parametrize("integrator", [pytest.param("newmark_average", marks=pytest.mark.slow), "central_difference"])
def test_sdof_el_centro_matches_exact_piecewise_linear_solution(integrator):
    """El Centro 1940 NS (bundled Peknold record, dt = 0.02 s), T = 0.5 s, 2 % damping. The exact
    solution for an excitation linear between samples (Chopra 2012, Table 5.2.1) on the analysis
    grid (record interpolated to dt = 0.002 s) against the FE SDOF: the first 10 s within 1 % of the
    peak. The peak deformation agrees with Chopra's published 2.67 in (Fig. 6.4.1) within 1 %."""
    from masonrydam import records

    tr = records.load_record("elcentro_1940_ns_peknold")
    omega, zeta, dt = 2 * math.pi / 0.5, 0.02, 0.002
    gm = GroundMotion(0, tr.data, tr.stats.delta)
    s = DynamicSettings(integrator=integrator, dt=dt, damping=RayleighDamping(2 * zeta * omega, 0.0))
    t, u, solver = run_sdof(omega, s, [gm], 10.0)
    ag = np.array([gm.at(x) for x in t])
    exact = chopra_recurrence(-ag, dt, omega, zeta)
    peak = np.abs(exact).max()
    assert np.abs(u - exact).max() <= 0.01 * peak
    assert np.abs(u).max() == pytest.approx(2.67 * 0.0254, rel=0.01)
    if integrator == "central_difference":
        # Hughes (2000) sec. 9.1.2: with viscous damping xi at omega_max, Omega_crit = 2 (sqrt(1 + xi^2) - xi)
        w_max = sdof_max_omega(omega)
        xi = 2 * zeta * omega / (2 * w_max)
        assert solver.stats.dt_critical == pytest.approx(2 * (math.sqrt(1 + xi**2) - xi) / w_max, rel=1e-4)


def sdof_max_omega(omega):
    """Largest circular frequency of the free DOFs of the SDOF model (numpy eigenvalues of M^-1 K)."""
    model, supports, m = sdof(omega)
    free = ~supports
    K = model.K_continuum.toarray()[np.ix_(free, free)]
    return math.sqrt(np.linalg.eigvals(K / (1000.0 / 2.0)).real.max())


@pytest.mark.parametrize("mass_form", ["lumped", "consistent"])
def test_step_residual_kernels_are_the_newmark_residual(mass_form):
    """``solvers.dynamic.kernels.newmark_kinematics`` and ``newmark_residual`` against the Newmark (1959)
    relations written out with numpy (Hughes 2000, *The Finite Element Method*, sec. 9.1; HHT weight
    w_m): a1 = (u - u_n - h v_n - h^2 (1/2 - beta) a_n) / (beta h^2), v1 = v_n + h ((1 - gamma) a_n +
    gamma a1), R = w_m M a1 + C v1 + f_int + const, for a lumped (diagonal) and a consistent (sparse)
    mass; a NaN in the forces is reported."""
    import scipy.sparse as sp

    from masonrydam.solvers.dynamic.kernels import newmark_kinematics, newmark_residual

    rng = np.random.default_rng(5)
    n_dof, n = 14, 10
    free = np.sort(rng.choice(n_dof, n, replace=False))
    A = sp.random(n, n, density=0.3, random_state=1, format="csr") + sp.eye(n, format="csr")
    M = (A @ A.T).tocsr()
    C = (0.3 * M + sp.random(n, n, density=0.2, random_state=2)).tocsr()
    u, f_int = rng.normal(size=n_dof), rng.normal(size=n_dof)
    un, vn, an, const = (rng.normal(size=n) for _ in range(4))
    h, beta, gamma, w_m = 0.01, 0.3025, 0.6, 1.0 / 1.1
    mdiag = np.asarray(M.sum(axis=1)).ravel()
    a1, v1, Ma, R = (np.full(n, np.nan) for _ in range(4))
    newmark_kinematics(u, free, un, vn, an, h, beta, gamma, mdiag if mass_form == "lumped" else np.zeros(0), a1, v1, Ma)
    if mass_form == "consistent":
        assert np.isnan(Ma).all()  # left to the caller (a scipy product)
        Ma = M @ a1
    Cv = C @ v1
    assert newmark_residual(Ma, w_m, Cv, f_int, free, const, R) == 0
    a_ref = (u[free] - un - h * vn - h * h * (0.5 - beta) * an) / (beta * h * h)
    v_ref = vn + h * ((1.0 - gamma) * an + gamma * a_ref)
    Mx = mdiag * a_ref if mass_form == "lumped" else M @ a_ref
    R_ref = w_m * Mx + C @ v_ref + f_int[free] + const
    np.testing.assert_allclose(a1, a_ref, rtol=1e-13)
    np.testing.assert_allclose(v1, v_ref, rtol=1e-13)
    np.testing.assert_allclose(Ma, w_m * Mx, rtol=1e-13)
    np.testing.assert_allclose(R, R_ref, rtol=1e-12, atol=1e-12 * np.abs(R_ref).max())
    f_int[free[3]] = np.nan
    assert newmark_residual(Ma, w_m, Cv, f_int, free, const, R) != 0


@pytest.mark.parametrize("lumped", [True, False])
def test_step_works_kernel_is_the_trapezoidal_rule(lumped):
    """``solvers.dynamic.kernels.step_works`` against the trapezoidal works of a step written out with numpy
    (energy balance of Hughes 2000, *The Finite Element Method*, sec. 9.1.4): W = du . (f0 + f1) / 2 for
    the earthquake, damping and joint forces (fj = f_int - K_continuum u), du . fs for the constant
    loads, and the kinetic energy v . M v / 2 with a diagonal or a full mass product."""
    from masonrydam.solvers.dynamic.kernels import step_works

    rng = np.random.default_rng(9)
    n_dof, n = 12, 9
    free = np.sort(rng.choice(n_dof, n, replace=False))
    u0, u1, f0, f1, kc0, kc1, a0, a1 = (rng.normal(size=n_dof) for _ in range(8))
    pg0, pg1, fs, cv0, cv1, v1, mdiag, mv1 = (rng.normal(size=n) for _ in range(8))
    M = np.diag(mdiag) if lumped else np.eye(n) + 0.1 * rng.normal(size=(n, n))
    ma0, ma1 = M @ a0[free], M @ a1[free]
    out = np.empty(10)
    step_works(free, u0, u1, pg0, pg1, fs, cv0, cv1, f0, f1, kc0, kc1, v1, mdiag if lumped else np.zeros(0), mv1,
               a0, a1, ma0, ma1, out)
    du = u1[free] - u0[free]
    ref = [0.5 * (pg0 + pg1) @ du, fs @ du, 0.5 * (cv0 + cv1) @ du,
           0.5 * ((f0 - kc0)[free] + (f1 - kc1)[free]) @ du, 0.5 * v1 @ (mdiag * v1 if lumped else mv1),
           0.5 * (ma0 + ma1) @ du, (ma1 - ma0) @ du, (f1 - f0)[free] @ du, (cv1 - cv0) @ du, (pg1 - pg0) @ du]
    np.testing.assert_allclose(out, ref, rtol=1e-12)


def test_central_difference_refuses_an_unstable_time_step():
    """Central difference is stable for omega_max dt <= 2 (Hughes 2000, sec. 9.1.2). The solver computes
    dt_crit from the largest eigenvalue of M^-1 K and refuses dt > 0.9 dt_crit with a SceneError that
    gives dt_crit; with stiff joints the joint springs set omega_max."""
    omega = 2 * math.pi * 2.0
    dt_crit = 2.0 / sdof_max_omega(omega)
    gm = GroundMotion(0, np.zeros(3), 0.01)
    model, supports, _ = sdof(omega)
    s = DynamicSettings(integrator="central_difference", dt=0.95 * dt_crit)
    with pytest.raises(masonrydam.SceneError, match=r"dt_crit = .* s") as exc:
        DynamicSolver(model, s).run(DynamicStage("cd", 0.1, supports, [gm], s))
    assert f"{dt_crit:.4g}" in str(exc.value)
    s = DynamicSettings(integrator="central_difference", dt=0.85 * dt_crit)
    DynamicSolver(model, s).run(DynamicStage("cd", 0.01, supports, [gm], s))
    # a block on stiff joints: the joint penalty (kn = 1e12 Pa/m) limits dt far below the block's own
    sc = Scene(sliding_block(integrator="central_difference", dt=1e-3, kn=1e12, duration=0.01))
    with pytest.raises(masonrydam.SceneError, match=r"stages\[1\]\.dt.*dt_crit"):
        masonrydam.run(sc)


# ----------------------------------------------------------------------------------------------
# integrator properties
# ----------------------------------------------------------------------------------------------

def amplification(beta, gamma, am, af, Om):
    """Amplification matrix of the generalized-alpha family for u'' + u = 0 with h = Om (Chung & Hulbert
    1993, eqs. 2-4 and 10), state (u, v, a), built from the defining equations."""
    h = Om
    A = np.zeros((3, 3))
    for j in range(3):
        u, v, a = np.eye(3)[j]
        # (1-am) a1 + am a + (1-af) u1 + af u = 0 with u1 = u + h v + h^2 ((1/2-beta) a + beta a1)
        pred = u + h * v + h * h * (0.5 - beta) * a
        a1 = -(am * a + (1 - af) * pred + af * u) / ((1 - am) + (1 - af) * beta * h * h)
        u1 = pred + beta * h * h * a1
        v1 = v + h * ((1 - gamma) * a + gamma * a1)
        A[:, j] = u1, v1, a1
    return A


def principal_root(roots):
    roots = np.asarray(roots, dtype=complex)
    return roots[np.argmax(np.abs(roots.imag))]


def measured_root(u):
    """Principal root of the displacement sequence of a linear 3-state recurrence: u_{n+1} = p u_n +
    q u_{n-1} + r u_{n-2} fitted by least squares (exact for the discrete system)."""
    X = np.column_stack([u[2:-1], u[1:-2], u[:-3]])
    p, q, r = np.linalg.lstsq(X, u[3:], rcond=None)[0]
    return principal_root(np.roots([1.0, -p, -q, -r]))


@pytest.mark.parametrize("integrator, param", [("newmark_average", None), ("newmark_linear", None),
                                               ("hht", -0.1), ("hht", -0.3), ("generalized_alpha", 0.8),
                                               ("generalized_alpha", 0.5), ("central_difference", None)])
def test_period_elongation_and_algorithmic_damping(integrator, param):
    """Free vibration of the SDOF at Omega = omega h = 0.3: the numerical frequency and damping measured
    from the FE history equal those of the published algorithm's amplification matrix (to 1e-6), and
    - trapezoidal rule: Tbar/T = Omega / (2 atan(Omega/2)), no damping (Hughes 2000, sec. 9.3);
    - linear acceleration: cos(Omega_bar) = 1 - Omega^2 / (2 (1 + Omega^2/6)), no damping (Newmark 1959);
    - central difference: Omega_bar = 2 asin(Omega / 2) (period shortening), no damping (Hughes 2000,
      sec. 9.3; Newmark beta = 0, gamma = 1/2);
    - HHT and generalized-alpha: positive algorithmic damping that grows with -alpha (HHT 1977) or with
      1 - rho_inf (Chung & Hulbert 1993), and a period error below 1 %."""
    omega = 2 * math.pi
    Om = 0.3
    kw = {}
    if integrator == "hht":
        kw["alpha"] = param
    elif integrator == "generalized_alpha":
        kw["rho_inf"] = param
    s = DynamicSettings(integrator=integrator, dt=Om / omega, **kw)
    _, u, _ = run_sdof(omega, s, [GroundMotion(0, np.zeros(2), 1.0)], 60 * s.dt, u0=1e-3)
    lam = measured_root(u)
    # central difference is Newmark's beta = 0, gamma = 1/2 (Hughes 2000, sec. 9.1)
    coefficients = (0.0, 0.5, 0.0, 0.0) if integrator == "central_difference" else s.coefficients()
    lam_ref = principal_root(np.linalg.eigvals(amplification(*coefficients, Om)))
    assert abs(lam - lam_ref) <= 1e-6 * abs(lam_ref)
    Om_bar = abs(np.angle(lam))
    xi_bar = -math.log(abs(lam)) / Om_bar
    elong = Om / Om_bar
    if integrator == "newmark_average":
        assert elong == pytest.approx(Om / (2 * math.atan(Om / 2)), rel=1e-9)
        assert abs(xi_bar) < 1e-9
    elif integrator == "newmark_linear":
        assert Om_bar == pytest.approx(math.acos(1 - Om**2 / (2 * (1 + Om**2 / 6))), rel=1e-9)
        assert abs(xi_bar) < 1e-9
    elif integrator == "central_difference":
        assert Om_bar == pytest.approx(2 * math.asin(Om / 2), rel=1e-9)
        assert abs(xi_bar) < 1e-9
    else:
        assert 0 < xi_bar < 0.05 and 1.0 < elong < 1.02
        weaker = DynamicSettings(integrator=integrator, dt=s.dt, **({"alpha": param / 2} if integrator == "hht"
                                                                    else {"rho_inf": (1 + param) / 2}))
        lam_w = principal_root(np.linalg.eigvals(amplification(*weaker.coefficients(), Om)))
        assert -math.log(abs(lam_w)) / abs(np.angle(lam_w)) < xi_bar


@pytest.mark.parametrize("integrator, param", [("hht", -0.1), ("hht", -1.0 / 3.0), ("generalized_alpha", 0.6),
                                               ("generalized_alpha", 0.0)])
def test_high_frequency_spectral_radius(integrator, param):
    """Spectral radius for Omega -> infinity: HHT (1 + alpha)/(1 - alpha) (Hilber, Hughes & Taylor 1977;
    Hughes 2000 sec. 9.3.3), generalized-alpha rho_inf by construction (Chung & Hulbert 1993, eq. 25).
    Measured from a free vibration with dt = 1e5 periods (Omega = 6.3e5): the largest root of the
    recurrence fitted to the FE displacements."""
    omega = 2 * math.pi
    kw = {"alpha": param} if integrator == "hht" else {"rho_inf": param}
    s = DynamicSettings(integrator=integrator, dt=1e5 * 2 * math.pi / omega, **kw)
    _, u, _ = run_sdof(omega, s, [GroundMotion(0, np.zeros(2), 1.0)], 30 * s.dt, u0=1e-3)
    expected = (1 + param) / (1 - param) if integrator == "hht" else param
    if expected == 0.0:  # asymptotic annihilation: the response vanishes after a few steps
        assert np.abs(u[3:]).max() <= 1e-6 * abs(u[0])
        return
    X = np.column_stack([u[2:-1], u[1:-2], u[:-3]])
    p, q, r = np.linalg.lstsq(X, u[3:], rcond=None)[0]
    assert np.abs(np.roots([1.0, -p, -q, -r])).max() == pytest.approx(expected, rel=1e-3)


# ----------------------------------------------------------------------------------------------
# modal analysis
# ----------------------------------------------------------------------------------------------

def cantilever(element_size, L=2.0, H=0.1, E=30e9, rho=2500.0, t=0.2):
    sc = Scene({"model": {"thickness": t, "hypothesis": "plane_stress"},
                "mesh": {"generator": "blocks_2d", "parameters": {"blocks": [{"x0": 0, "y0": 0, "x1": L, "y1": H,
                                                                            "group": "beam"}],
                                                                 "element_size": element_size, "order": 2}},
                "materials": {"beam": {"youngs_modulus": E, "poisson_ratio": 0.0, "density": rho}},
                "supports": [{"set": "left", "components": ["x", "y"]}],
                "stages": [{"name": "none", "loads": []}]})
    mesh = build_mesh(sc.normalized, ".")
    model = build_model(sc.normalized, mesh)
    st = build_stages(sc.normalized, mesh, model)
    model.set_constraints(st[0].supports)
    return model


def timoshenko_cantilever_frequencies(L, H, E, nu, rho, t, f_max, kappa):
    """Natural frequencies (Hz) of a clamped-free Timoshenko beam below f_max (Timoshenko 1921): harmonic
    solutions of kGA (w'' - psi') + rho A w^2 w = 0, EI psi'' + kGA (w' - psi) + rho I w^2 psi = 0 written
    as y' = M y, y = [w, w', psi, psi'], propagated with expm(M L); clamped at 0 (w = psi = 0), free at L
    (psi' = 0, w' - psi = 0); roots of the 2 x 2 determinant."""
    import scipy.linalg

    A, I, Gm = t * H, t * H**3 / 12, E / (2 * (1 + nu))

    def det(f):
        w2 = (2 * math.pi * f) ** 2
        M = np.array([[0, 1, 0, 0], [-rho * w2 / (kappa * Gm), 0, 0, 1], [0, 0, 0, 1],
                      [0, -kappa * Gm * A / (E * I), (kappa * Gm * A - rho * I * w2) / (E * I), 0]])
        Y = scipy.linalg.expm(M * L)[:, [1, 3]]
        return np.linalg.det(np.array([Y[3], Y[1] - Y[2]]))

    fs = np.linspace(0.5, f_max, 800)
    d = [det(f) for f in fs]
    return [scipy.optimize.brentq(det, fs[i], fs[i + 1]) for i in range(len(fs) - 1) if np.sign(d[i]) != np.sign(d[i + 1])]


@pytest.mark.slow
def test_cantilever_modal_frequencies_converge_to_beam_theory():
    """Cantilever L/H = 20 (quad8, plane stress, nu = 0, consistent mass), clamped at x = 0, against
    - Timoshenko beam theory with Cowper's (1966) shear coefficient kappa = 10 (1 + nu) / (12 + 11 nu)
      (frequency equation solved in the test): the two lowest bending frequencies; the consistent-mass
      FE converges monotonically from above (Rayleigh-Ritz upper bound) to within 1e-4;
    - Euler-Bernoulli (f = lambda^2 / (2 pi L^2) sqrt(EI / (rho A)), lambda_1 = 1.8751, lambda_2 =
      4.6941; Chopra 2012 sec. 16.3): 0.16 % and 1.1 % below, the shear and rotary-inertia corrections;
    - the first axial mode of a bar, f = sqrt(E / rho) / (4 L), within 1e-6 (exact for nu = 0);
    - the effective modal mass of the first bending mode, 0.613 of the beam mass for Euler-Bernoulli
      (Chopra 2012, ch. 17, effective modal mass of the first mode of a uniform cantilever), within 1 %."""
    L, H, E, rho, t = 2.0, 0.1, 30e9, 2500.0, 0.2
    EI, mA = E * t * H**3 / 12, rho * t * H
    f_eb = [lam**2 / (2 * math.pi * L**2) * math.sqrt(EI / mA) for lam in (1.87510407, 4.69409113)]
    f_tim = timoshenko_cantilever_frequencies(L, H, E, 0.0, rho, t, 100.0, 10.0 / 12.0)
    f_ax = math.sqrt(E / rho) / (4 * L)
    rows = []
    for size in (0.1, 0.05, 0.025):
        model = cantilever(size, L, H, E, rho, t)
        res = modal_analysis(model, 6, lumped=False)
        bend = [k for k in range(6) if res.effective_mass[k, 1] > 1e-3 * res.free_mass[1]]
        axial = [k for k in range(6) if res.effective_mass[k, 0] > 0.5 * res.free_mass[0]]
        rows.append((res.frequencies[bend[0]], res.frequencies[bend[1]], res.frequencies[axial[0]],
                     res.effective_mass_ratio[bend[0], 1]))
    rows = np.array(rows)
    for mode in (0, 1):
        err = rows[:, mode] / f_tim[mode] - 1
        assert (err > 0).all() and (np.diff(err) < 0).all(), "monotone convergence from above"
        assert err[-1] < 1e-4
    assert rows[-1, 0] / f_eb[0] - 1 == pytest.approx(-0.0016, abs=3e-4)
    assert rows[-1, 1] / f_eb[1] - 1 == pytest.approx(-0.011, abs=1e-3)
    assert rows[-1, 2] == pytest.approx(f_ax, rel=1e-6)
    assert rows[-1, 3] == pytest.approx(0.613, rel=0.01)


def test_rayleigh_coefficients_give_the_ratio_at_both_frequencies():
    """Chopra (2012) eqs. 11.4.8-11.4.9: zeta(f) = a/(2w) + b w/2 equals zeta at f1 and f2 and is
    smaller in between."""
    a, b = rayleigh_coefficients(2.0, 10.0, 0.05)
    d = RayleighDamping(a, b)
    assert d.ratio([2.0, 10.0]) == pytest.approx([0.05, 0.05], rel=1e-12)
    assert d.ratio(5.0) < 0.05
    with pytest.raises(masonrydam.SceneError, match="f1 < f2"):
        rayleigh_coefficients(10.0, 2.0, 0.05)


# ----------------------------------------------------------------------------------------------
# Newmark (1965) sliding block
# ----------------------------------------------------------------------------------------------

def newmark_half_sine_slip(A, ay, tp):
    """Newmark (1965) rigid block, one-directional sliding, a_g = A sin(pi t/tp) on [0, tp]: s'' = a_g - a_y
    from the onset t1 = asin(a_y/A) tp/pi until s' = 0 (elementary integrals)."""
    w = math.pi / tp
    t1 = math.asin(ay / A) / w

    def vel(t):
        if t <= tp:
            return A / w * (math.cos(w * t1) - math.cos(w * t)) - ay * (t - t1)
        return vel(tp) - ay * (t - tp)

    def disp(t):
        if t <= tp:
            return A / w * (math.cos(w * t1) * (t - t1) - (math.sin(w * t) - math.sin(w * t1)) / w) - ay * (t - t1) ** 2 / 2
        return disp(tp) + vel(tp) * (t - tp) - ay * (t - tp) ** 2 / 2

    t_stop = scipy.optimize.brentq(vel, tp / 2, tp + A / ay * tp)  # s' > 0 at the pulse peak
    return disp(t_stop), t_stop


@pytest.mark.parametrize("shape", ["rectangular", "half_sine"])
@pytest.mark.reference
def test_newmark_sliding_block_permanent_slip(shape):
    """Newmark (1965) sliding block: an elastic block on a Mohr-Coulomb joint (c = 0, mu = 0.2,
    kn = ks = 1e10 Pa/m) after a gravity stage, horizontal pulse of amplitude A = 0.4 g.
    Rectangular pulse (t0 = 0.2 s): s = A (A - a_y) t0^2 / (2 a_y), stop at A t0 / a_y. Half-sine
    (tp = 0.4 s): closed form by integration. Permanent slip within 0.05 % of the closed form (the
    block slides the other way from the ground: slip = top minus bottom < 0). The code reaches
    5e-5 (rectangular) and 1.5e-4 (half-sine) at dt = 2 ms: the elastic block on penalty springs is
    not quite Newmark's rigid block; the bound leaves room for round-off, not for a solver error."""
    A, mu = 0.4 * G, 0.2
    ay = mu * G
    if shape == "rectangular":
        t0 = 0.2
        expected, t_stop = A * (A - ay) * t0**2 / (2 * ay), A * t0 / ay
        ds = masonrydam.run(sliding_block(shape="rectangular", amplitude=A, pulse=t0, mu=mu, duration=t_stop + 0.15))
    else:
        tp = 0.4
        expected, t_stop = newmark_half_sine_slip(A, ay, tp)
        ds = masonrydam.run(sliding_block(shape="half_sine", amplitude=A, pulse=tp, mu=mu, duration=t_stop + 0.15))
    slip = ds.joint_slip.isel(step=-1).values
    assert (slip < 0).all()
    assert -slip.mean() == pytest.approx(expected, rel=5e-4)
    assert np.ptp(slip) < 1e-3 * abs(slip.mean())  # the block slides as a whole
    assert (ds.joint_state.isel(step=-1).values == 0).all(), "the block sticks again after the pulse"
    # sliding stops at t_stop: after it the slip is constant; 0.05 s before it the rigid block still has
    # a_y (0.05 s)^2 / 2 to slide (decelerating at a_y); at least half of that remains in the FE history
    dyn = ds.where(ds.stage == 1, drop=True)
    s_hist = -dyn.joint_slip.mean(("joint_point", "shear_direction")).values
    t = dyn.time.values
    assert s_hist[t > t_stop + 0.02].std() < 1e-4 * expected
    assert s_hist[np.searchsorted(t, t_stop - 0.05)] < expected - 0.5 * ay * 0.05**2 / 2


@pytest.mark.slow
@pytest.mark.reference
def test_central_difference_sliding_block():
    """Explicit central difference with the joints evaluated once per step: the rectangular-pulse
    sliding block (Newmark 1965) within 0.5 % (the code reaches 2.7e-3: the joint law evaluated once
    per step lags the onset and end of sliding by up to a step), and an energy balance error below
    1e-3 of the input (second-order scheme, dt below the critical step of the joint springs)."""
    A, mu, t0 = 0.4 * G, 0.2, 0.2
    ay = mu * G
    expected = A * (A - ay) * t0**2 / (2 * ay)
    sc = sliding_block(integrator="central_difference", dt=5e-5, duration=A * t0 / ay + 0.05,
                       output={"stride": 200})
    ds = masonrydam.run(sc)
    assert -ds.joint_slip.isel(step=-1).values.mean() == pytest.approx(expected, rel=5e-3)
    assert ds.attrs["energy_error_relative"] < 1e-3
    assert ds.attrs["dynamic_factorizations"] == 0


def test_stiffness_proportional_damping_excludes_joints_by_default():
    """Hall (2006), EESD 35:525-545: stiffness-proportional damping on stiff elements that slide or open
    produces large spurious damping forces. With beta K on the continuum only (default), a rigid
    sliding block feels no damping force and slides as Newmark's block (within 0.05 %); with the joint
    penalty stiffness in beta K the joint dashpot holds the block back."""
    A, mu, t0 = 0.4 * G, 0.2, 0.2
    ay = mu * G
    expected = A * (A - ay) * t0**2 / (2 * ay)
    damping = {"alpha": 0.0, "beta": 0.002}
    ds = masonrydam.run(sliding_block(duration=0.55, damping=damping))
    assert -ds.joint_slip.isel(step=-1).values.mean() == pytest.approx(expected, rel=5e-4)
    ds2 = masonrydam.run(sliding_block(duration=0.55, damping=dict(damping, exclude_joints=False)))
    assert -ds2.joint_slip.isel(step=-1).values.mean() < 0.5 * expected


# ----------------------------------------------------------------------------------------------
# Housner (1963) rocking block
# ----------------------------------------------------------------------------------------------

B, H = ROCKING_BLOCK_WIDTH, ROCKING_BLOCK_HEIGHT  # block width 2b and height 2h: b/h = 0.2


@pytest.mark.parametrize("factor, rocks", [(0.98, False), (1.02, True)])
@pytest.mark.reference
def test_housner_rocking_starts_at_g_b_over_h(factor, rocks):
    """Housner (1963): a block on a no-tension frictional joint starts to rock when
    the base acceleration exceeds g b/h. A ground acceleration raised slowly (0.5 s, quasi-static for
    the block on its stiff joint) to 0.98 g b/h and held 0.5 s leaves the heel down (uplift at the
    elastic scale, < 1e-5 m); to 1.02 g b/h, the block tips over the toe (uplift > 1e-3 m)."""
    dt = 2e-3
    a = factor * G * B / H
    t = np.arange(int(round(1.0 / dt)) + 1) * dt
    vals = a * np.minimum(t / 0.5, 1.0)
    stages = [{"name": "gravity", "loads": [{"type": "self_weight"}]},
              {"name": "ramp", "type": "dynamic", "dt": dt, "integrator": "hht",
               "ground_motion": {"x": {"values": vals.tolist(), "dt": dt}}, "output": {"stride": 10}}]
    ds = masonrydam.run(rocking_block(stages))
    heel = np.nonzero(np.isclose(ds.x.values, B) & np.isclose(ds.y.values, 0.0))[0]
    uplift = ds.displacement.sel(component="y").isel(node=heel).values.max()
    if rocks:
        assert uplift > 1e-3
    else:
        assert uplift < 1e-5


def free_rocking(integrator, dt, theta_ratio=0.02, duration=0.3, **kw):
    """Release the block from rest, tilted about its toe by theta0 = theta_ratio * alpha."""
    model, supports, block = rocking_block_model()
    x = model.coords
    alpha = math.atan(B / H)
    th0 = theta_ratio * alpha
    u0 = np.zeros(model.n_dof)
    u0[block * 2], u0[block * 2 + 1] = -th0 * x[block, 1], th0 * x[block, 0]  # rigid rotation about (0, 0)
    heel = block[np.argmin((x[block, 0] - B) ** 2 + x[block, 1] ** 2)]
    toe = block[np.argmin(x[block, 0] ** 2 + x[block, 1] ** 2)]
    s = DynamicSettings(integrator=integrator, dt=dt, **kw)
    rec = []

    def on_step(r):
        e = r["energy"]
        rec.append((r["t"], (r["u"][heel * 2 + 1] - r["u"][toe * 2 + 1]) / B,
                    e["kinetic"] + e["strain"] + e["joint_stored"] - e["external"] - e["input"] + e["damping"]))

    DynamicSolver(model, s).run(DynamicStage("rock", duration, supports, [GroundMotion(0, np.zeros(2), 1.0)], s),
                                u0=u0, f_static=L.self_weight(model, [0.0, -G]), equilibrate=False, on_step=on_step)
    rec = np.array(rec)
    return rec[:, 0], rec[:, 1], rec[:, 2], th0, alpha


@pytest.mark.reference
def test_housner_free_rocking_quarter_period_impact_and_energy():
    """Housner (1963) free rocking, block 0.3 x 1.5 m released from theta0 = 0.02 alpha:
    - time to the first impact T/4 = acosh(1 / (1 - theta0/alpha)) / p, p = sqrt(3 g / (4 R)), within
      1 % (the code reaches 0.41 %: masonrydam is small-displacement, the restoring moment is m g b
      instead of m g R sin(alpha - theta), which changes T/4 by 0.3 % at this theta0);
    - angular velocity ratio at impact r = 1 - 1.5 sin^2(alpha) within 2.5 % (the code reaches 1.5 %;
      velocities from parabolic fits of theta(t) over 20 ms before and 16 ms after the impact, HHT
      alpha = -0.1; the fits themselves are good to about 1 %);
    - without damping the mechanical energy (kinetic + elastic + joint stored - work of gravity) never
      exceeds its initial value by more than 1e-3 of the released potential energy m g b theta0."""
    t, th, e_mech, th0, alpha = free_rocking("hht", 5e-4, alpha=-0.1)
    R = math.hypot(B / 2, H / 2)
    p = math.sqrt(3 * G / (4 * R))
    T4 = math.acosh(1 / (1 - th0 / alpha)) / p
    i = np.nonzero(th <= 0)[0][0]
    tc = t[i - 1] + (t[i] - t[i - 1]) * th[i - 1] / (th[i - 1] - th[i])
    assert tc == pytest.approx(T4, rel=0.01)
    acc = p**2 * math.sin(alpha)  # linearised angular acceleration about a corner
    before = (t > tc - 0.02) & (t < tc - 0.002)
    after = (t > tc + 0.004) & (t < tc + 0.02)
    w_b = np.polyfit(t[before] - tc, th[before] + 0.5 * acc * (t[before] - tc) ** 2, 1)[0]
    w_a = np.polyfit(t[after] - tc, th[after] - 0.5 * acc * (t[after] - tc) ** 2, 1)[0]
    assert w_a / w_b == pytest.approx(1 - 1.5 * math.sin(alpha) ** 2, rel=0.025)
    E0 = 2000 * B * H * G * (B / 2) * th0
    assert e_mech.max() <= 1e-3 * E0
    assert e_mech[-1] < -0.05 * E0, "impacts dissipate energy"


def test_energy_never_grows_at_impacts_with_the_trapezoidal_rule():
    """Newmark average acceleration conserves the discrete energy with trapezoidal work, but the work
    of a joint point that opens or closes within a step is not its stored energy (Armero & Petocz
    1998; Laursen & Chawla 1997), so impacts can create energy. The solver splits such steps: the
    free-rocking block's mechanical energy never exceeds its initial value by 1e-3 of m g b theta0."""
    t, th, e_mech, th0, alpha = free_rocking("newmark_average", 5e-4, duration=0.25)
    E0 = 2000 * B * H * G * (B / 2) * th0
    assert (th < 0).any() and (np.diff(np.sign(th)) != 0).sum() >= 1, "at least one impact"
    assert e_mech.max() <= 1e-3 * E0


# ----------------------------------------------------------------------------------------------
# scenes, results, failures
# ----------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_time_history_file_stride_selection_energy_and_provenance(tmp_path):
    """The netCDF file of a dynamic scene: time coordinate (NaN for static steps), every stride-th step,
    the selected nodes and joints, velocity / acceleration relative and absolute (absolute = relative +
    ground), energies with the balance error (Newmark average acceleration: energy conserved to the
    Newton tolerance, Hughes 2000 sec. 9.3), the record's provenance, completed = true."""
    out = tmp_path / "slide.nc"
    sc = sliding_block(integrator="newmark_average", duration=0.1, dt=0.002,
                       output={"stride": 5, "nodes": ["top"], "joints": ["joints"]})
    ds = run_to_file(sc, out)
    assert ds.attrs["completed"] == "true"
    dyn = ds.where(ds.stage == 1, drop=True)
    assert np.isnan(ds.time.values[ds.stage.values == 0]).all()
    assert np.isnan(ds.ground_acceleration.values[ds.stage.values == 0]).all()
    assert np.isnan(ds.energy_input.values[ds.stage.values == 0]).all()
    np.testing.assert_allclose(dyn.time.values, np.arange(0, 0.1 + 1e-9, 0.01), atol=1e-12)
    assert ds.sizes["node"] == 9  # the top edge of the 2 m block, 0.25 m elements
    a_abs = dyn.acceleration + dyn.ground_acceleration
    np.testing.assert_allclose(dyn.acceleration_absolute.values, a_abs.transpose(*dyn.acceleration_absolute.dims).values,
                               atol=1e-9)
    for v in ("velocity", "acceleration", "acceleration_absolute", "ground_acceleration", "energy_input",
              "energy_kinetic", "energy_strain", "energy_damping", "energy_joint", "energy_error"):
        assert ds[v].attrs["units"] and ds[v].attrs["long_name"]
    assert "relative" in ds.velocity.attrs["long_name"] and "absolute" in ds.acceleration_absolute.attrs["long_name"]
    assert np.abs(dyn.energy_error.values).max() <= 1e-6 * np.abs(dyn.energy_input.values).max()
    assert ds.attrs["stage1_ground_motion_x_name"] == "rectangular_pulse"
    assert "define" in ds.attrs["stage1_ground_motion_x_provenance"]
    assert ds.attrs["dynamic_factorizations"] >= 1 and ds.attrs["dynamic_steps"] == 50
    # the plot command reads it
    from masonrydam.cli.main import main

    png = tmp_path / "slide.png"
    assert main(["plot", str(out), "--joints", "0", "-o", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # what is drawn: four panels against time, each line the file's data
    from masonrydam.cli.main import history_figure

    fig = history_figure(ds, "slide.nc", "x", None, [0])
    ground, disp, joint, energy = fig.axes
    t = dyn.time.values
    for ax in fig.axes:
        assert ax.get_xlabel() == "time [s]"
    for ax in (disp, joint, energy):
        for line in ax.get_lines():
            np.testing.assert_array_equal(line.get_xdata(), t)
    (ag_x,) = ground.get_lines()  # the record at its own rate; no y motion: no line of zeros
    np.testing.assert_array_equal(ag_x.get_xdata(), ds.ground_record_time_x.values)
    np.testing.assert_array_equal(ag_x.get_ydata(), ds.ground_acceleration_record_x.values)
    assert np.max(ag_x.get_ydata()) == pytest.approx(0.4 * G)  # the pulse, at its full amplitude
    (moving,) = disp.get_lines()
    k = int(np.argmax(np.abs(dyn.displacement.sel(component="x").values).max(axis=0)))
    np.testing.assert_array_equal(moving.get_ydata(), dyn.displacement.sel(component="x").values[:, k])
    assert moving.get_label() == f"node {int(ds.node.values[k])}" and disp.get_ylabel() == "u_x [m] (relative)"
    slip, opening = joint.get_lines()
    np.testing.assert_array_equal(slip.get_ydata(), dyn.joint_slip.values[:, 0, 0])
    assert slip.get_label() == "slip, point 0" and opening.get_label() == "opening, point 0"
    drawn = {line.get_label(): line.get_ydata() for line in energy.get_lines()}
    assert {"input", "kinetic", "joint_friction"} <= set(drawn)
    assert "joint_bond_break" not in drawn  # zero throughout: not drawn
    np.testing.assert_array_equal(drawn["joint_friction"], dyn.energy_joint_friction.values)


def run_to_file(scene, path):
    masonrydam.run(scene, output=path)
    import xarray as xr

    return xr.load_dataset(path)


def test_linear_scene_factorizes_once_for_the_whole_record():
    """Fast path: with linear joints the effective matrix never changes: one factorization for every
    step, one substitution per step."""
    sc = sliding_block(duration=0.2, dt=0.002)
    sc["joints"]["joints"] = {"law": "linear", "normal_stiffness": 1e10, "shear_stiffness": 1e10}
    ds = masonrydam.run(sc)
    assert ds.attrs["dynamic_factorizations"] == 1
    assert ds.attrs["dynamic_newton_iterations"] <= ds.attrs["dynamic_steps"]
    # the all-stick matrix is factorized as L D L^T with numba substitutions by default; a named
    # backend is used as given, and both give the same history (to round-off: both solves are
    # backward stable on this positive definite matrix)
    assert ds.attrs["dynamic_reference_solver"] == "ldlt"
    sc["solver"] = {"linear_solver": "superlu"}
    ref = masonrydam.run(sc)
    assert ref.attrs["dynamic_reference_solver"] == "superlu"
    u, u_ref = ds.displacement.values, ref.displacement.values
    assert np.abs(u - u_ref).max() <= 1e-9 * np.abs(u_ref).max()


def test_non_converging_step_raises_with_time_and_keeps_the_file(tmp_path):
    """A step that cannot converge (here: one Newton iteration allowed, no sub-steps, and the block
    starts to slide) raises ConvergenceError naming the time; the file keeps every converged step and
    is marked completed = false."""
    out = tmp_path / "fail.nc"
    # the general Newton path (joint_space = "off"): the joint-space path would solve this step
    sc = sliding_block(duration=0.2, dt=0.002, max_iterations=1, max_substeps=0, joint_space="off")
    with pytest.raises(masonrydam.ConvergenceError, match=r"from t = [0-9.e-]+ s to [0-9.e-]+ s"):
        masonrydam.run(sc, output=out)
    import xarray as xr

    ds = xr.load_dataset(out)
    assert ds.attrs["completed"] == "false" and ds.attrs["status"] == "failed"
    assert "ConvergenceError" in ds.attrs["status_reason"]
    assert ds.sizes["step"] >= 2 and np.isfinite(ds.displacement.values).all()


@pytest.mark.slow
def test_killed_run_leaves_a_readable_incomplete_file(tmp_path):
    """A run killed halfway (SIGKILL) leaves its working file (killed.partial.nc) that xarray reads,
    with the steps written (each one flushed) and completed = false, status = running; the target
    file is never created by an unfinished run."""
    out = tmp_path / "killed.nc"
    work = tmp_path / "killed.partial.nc"
    code = ("import sys; sys.path.insert(0, %r); import masonrydam; from scenes import sliding_block; "
            "masonrydam.run(sliding_block(duration=60.0, dt=0.002, integrator='newmark_average'), output=%r)"
            % (str(TESTS), str(out)))
    proc = subprocess.Popen([sys.executable, "-c", code])
    try:
        deadline = time.time() + 90
        while time.time() < deadline and (not work.exists() or work.stat().st_size < 200_000):
            assert proc.poll() is None, "the run stopped by itself"
            time.sleep(0.2)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    import xarray as xr

    assert not out.exists()
    ds = xr.load_dataset(work)
    assert ds.attrs["completed"] == "false" and ds.attrs["status"] == "running"
    n = ds.sizes["step"]
    assert n >= 5 and np.isfinite(ds.displacement.values).all()
    assert np.isfinite(ds.time.values[1:]).all() and (np.diff(ds.time.values[1:]) > 0).all()


def test_dynamic_scene_errors_name_the_key():
    """Scene validation of dynamic stages: unknown keys, missing ground motion, static after dynamic,
    integrator parameters."""
    base = sliding_block()
    bad = sliding_block(integrator="hht", rho_inf=0.5)
    with pytest.raises(masonrydam.SceneError, match=r"stages\[1\]\.rho_inf"):
        Scene(bad)
    bad = sliding_block()
    del bad["stages"][1]["ground_motion"]
    with pytest.raises(masonrydam.SceneError, match=r"stages\[1\]\.ground_motion"):
        Scene(bad)
    bad = sliding_block()
    bad["stages"].append({"name": "after", "loads": []})
    with pytest.raises(masonrydam.SceneError, match=r"stages\[2\]\.type.*before"):
        Scene(bad)
    bad = sliding_block()
    bad["stages"][1]["ground_motion"]["x"] = {"record": "elcentro_1940_ns_peknold", "units": "g"}
    with pytest.raises(masonrydam.SceneError, match=r"ground_motion\.x\.units"):
        Scene(bad)
    bad = sliding_block()
    bad["stages"][1]["ground_motion"]["x"] = {"record": "no_such_record"}
    with pytest.raises(masonrydam.SceneError, match=r"ground_motion\.x.*unknown record"):
        masonrydam.run(bad)
    Scene(base)


def test_effects_list_dynamics_only_for_dynamic_scenes():
    """What a scene does not ask for is not assembled or listed: a static scene has no inertia."""
    from masonrydam.scene import effects

    sc = Scene(sliding_block())
    mesh = build_mesh(sc.normalized, ".")
    model = build_model(sc.normalized, mesh)
    eff = effects(sc.normalized, model)
    assert any("HHT" in e for e in eff) and any("base excitation" in e for e in eff)
    static = sliding_block()
    static["stages"] = static["stages"][:1]
    sc = Scene(static)
    eff = effects(sc.normalized, build_model(sc.normalized, build_mesh(sc.normalized, ".")))
    assert not any("dynamic" in e for e in eff) and eff[-1].startswith("static analysis")


def _top_slip(ds):
    """Mean horizontal displacement of the block's top nodes at the last step (m): its slip on the joint."""
    top = np.nonzero(np.isclose(ds.y.values, 0.75))[0]
    return float(ds.displacement.sel(component="x").isel(node=top, step=-1).mean())


def test_static_state_carried_into_the_dynamic_stage():
    """With no ground motion the gravity state carried over is an equilibrium: the dynamic stage keeps
    the static displacements exactly and the block stays at rest (Newton's first law)."""
    sc = sliding_block(duration=0.05, dt=0.002, integrator="newmark_average")
    sc["stages"][1]["ground_motion"] = {"x": {"values": [0.0, 0.0], "dt": 0.01}}
    ds = masonrydam.run(sc)
    stage = ds.stage.values
    u_static = ds.displacement.values[stage == 0][-1]
    assert np.abs(u_static).max() > 1e-7  # the block has settled under its weight
    u_dynamic = ds.displacement.values[stage == 1]
    np.testing.assert_allclose(u_dynamic, np.broadcast_to(u_static, u_dynamic.shape), rtol=0,
                               atol=1e-12 * np.abs(u_static).max())
    assert np.nanmax(np.abs(ds.velocity.values)) < 1e-12


def test_horizontal_and_vertical_ground_motion_together():
    """Newmark's (1965) sliding block with a vertical component: the ground accelerates downwards at 0.5 g (ramped
    in over 0.2 s, slowly against the block's vertical period of 2 ms), then a rectangular horizontal
    pulse A = 0.15 g for 0.2 s. The joint's yield acceleration is mu (g - 0.5 g) = 0.1 g, and Newmark's
    (1965) rigid-block slip A t_p^2 (A - a_y) / (2 a_y) holds within 0.05 % (the code reaches 1.5e-4);
    without the vertical component
    (a_y = 0.2 g > A) the block does not slide."""
    dt, A, tp = 0.002, 0.15 * G, 0.2
    n_pre, n_pulse, n_post = 150, 100, 150
    x = [0.0] * n_pre + [A] * n_pulse + [0.0] * n_post
    y = [-0.5 * G * min(1.0, k * dt / 0.2) for k in range(n_pre + n_pulse + n_post)]
    slips = {}
    for vertical in (True, False):
        sc = sliding_block(duration=(len(x) - 1) * dt, dt=dt, integrator="hht")
        gm = {"x": {"values": x, "dt": dt}}
        if vertical:
            gm["y"] = {"values": y, "dt": dt}
        sc["stages"][1]["ground_motion"] = gm
        ds = masonrydam.run(sc)
        slips[vertical] = -_top_slip(ds) + _top_slip(ds.isel(step=[n_pre - 1]))  # from the start of the pulse
    ay = 0.2 * (G - 0.5 * G)
    assert slips[True] == pytest.approx(A * tp**2 * (A - ay) / (2 * ay), rel=5e-4)
    assert abs(slips[False]) < 1e-3 * slips[True]


def test_substeps_rescue_steps_that_do_not_converge():
    """The general Newton path with two iterations allowed per step cannot follow the onset of sliding in
    one step; halving the step (automatic sub-steps) finishes the run, and the slip is Newmark's (1965)
    rigid-block value A t_p^2 (A - a_y) / (2 a_y) within 0.05 %."""
    ds = masonrydam.run(sliding_block(duration=0.55, dt=0.002, max_iterations=2, max_substeps=6, joint_space="off"))
    assert ds.attrs["completed"] == "true" and int(ds.attrs["dynamic_substeps"]) > 0
    A, ay, tp = 0.4 * G, 0.2 * G, 0.2
    assert -_top_slip(ds) == pytest.approx(A * tp**2 * (A - ay) / (2 * ay), rel=5e-4)


def test_consistent_mass_time_history():
    """A time history with the consistent mass matrix (Newmark's sliding block, HHT): Newmark's (1965)
    rigid-block slip within 0.05 %, as with the lumped mass."""
    ds = masonrydam.run(sliding_block(duration=0.55, mass="consistent"))
    A, ay, tp = 0.4 * G, 0.2 * G, 0.2
    assert -_top_slip(ds) == pytest.approx(A * tp**2 * (A - ay) / (2 * ay), rel=5e-4)


def test_a_long_result_file_is_returned_lazily(tmp_path, monkeypatch):
    """A kept result file above LOAD_IN_MEMORY_MAX comes back opened lazily (memory does not grow with
    the record), with the same values as a loaded one."""
    import xarray as xr

    import importlib

    monkeypatch.setattr(importlib.import_module("masonrydam.scene.run"), "LOAD_IN_MEMORY_MAX", 0)
    out = tmp_path / "lazy.nc"
    ds = masonrydam.run(sliding_block(duration=0.1), output=out)
    assert not ds.displacement.variable._in_memory
    ref = xr.load_dataset(out)
    np.testing.assert_array_equal(ds.displacement.values, ref.displacement.values)
    ds.close()
