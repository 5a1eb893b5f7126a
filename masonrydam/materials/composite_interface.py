"""Composite interface ("interface cap") law for masonry joints of Lourenco & Rots.

References
----------
[LR97] P. B. Lourenco, J. G. Rots (1997), "Multisurface interface model for analysis of masonry
       structures", J. Eng. Mech. 123(7), 660-668.
[L96]  P. B. Lourenco (1996), "Computational strategies for masonry structures", PhD thesis, TU Delft,
       ch. 4 (interface cap model).
[SH98] J. C. Simo, T. J. R. Hughes (1998), Computational Inelasticity, Springer, sec. 5.2
       (multisurface return mapping, active-set search by the signs of the multipliers).
[GB04] Y. F. Gao, A. F. Bower (2004), "A simple technique for avoiding convergence problems in finite
       element simulations of crack nucleation and growth on cohesive interfaces", Modelling Simul.
       Mater. Sci. Eng. 12, 453-463 (viscous regularisation of softening interfaces).
[MSA03] J. R. R. A. Martins, P. Sturdza, J. J. Alonso (2003), "The complex-step derivative
       approximation", ACM TOMS 29(3), 245-262 (derivatives exact to rounding, used for the Jacobian of
       the local Newton iteration and for the consistent tangent).

Conventions (docs/architecture.md): ``delta`` is the relative displacement top minus bottom in the
local frame ``[s, n]`` (2D) or ``[s1, s2, n]`` (3D), opening positive (m); tractions
``[tau, (tau2,) t_n]`` are positive in tension (Pa); stiffnesses are per unit area (Pa/m). Trial /
commit / revert: the kernel reads ``state_committed`` (never writes it) and writes ``state_trial``.

The law
-------
Elasticity ``t = K (delta - delta_p)``, ``K = diag(ks1, (ks2,) kn)`` (ks2 may differ from ks1 in 3D).
``T = |tau|`` is the magnitude of the shear traction vector. Three yield surfaces ([LR97] eqs. 1-9,
[L96] sec. 4.3):

1. Tension cut-off ([LR97] eq. 3), associated flow ``m1 = [0, .., 1]``, ``d kappa1 = d lambda1``::

       f1 = t_n - sigma1,                      sigma1 = ft exp(-omega)

2. Coulomb friction ([LR97] eqs. 5-7), non-associated, ``m2 = [tau / T, tan(psi)]``,
   ``d kappa2 = d lambda2`` (= the plastic slip magnitude)::

       f2 = T + t_n tan(phi) - sigma2,         sigma2 = c exp(-omega)
       tan(phi) = tan(phi0) + (tan(phi_r) - tan(phi0)) (c - sigma2) / c
                = tan(phi_r) + (tan(phi0) - tan(phi_r)) exp(-omega)     (friction softens with the
                                                                         cohesion lost, [LR97] eq. 7)
       tan(psi) = tan(psi0) (1 + t_n / sigma_u) exp(-delta_d kappa2)   if t_n > -sigma_u, else 0
                                                                        ([L96] sec. 4.3, dilatancy
                                                                         decaying with the normal
                                                                         compression and the slip)

   (``sigma_u > 0`` is the compressive normal stress at which the dilatancy vanishes; the thesis writes
   ``1 - sigma / sigma_u`` with ``sigma_u < 0``. In tension the factor exceeds 1, as in the thesis.)

3. Compression cap ([LR97] eq. 8, [L96] with ``Cnn = 1``, ``Cn = 0``), associated, ``m3 = df3/dt``,
   ``d kappa3 = d lambda3 |m3|`` (= the norm of the plastic displacement increment)::

       f3 = t_n^2 + Css T^2 - sigma3(kappa3)^2

   sigma3 (``sigma_i = fc/3``, ``sigma_p = fc``, ``sigma_m = fc/2``, ``sigma_r = fc/7``, [L96])::

       kappa < kp        : sigma_i + (sigma_p - sigma_i) (2 x - x^2),     x = kappa / kp
       kp <= kappa < km  : sigma_p + (sigma_m - sigma_p) y^2,             y = (kappa - kp) / (km - kp)
       kappa >= km       : sigma_r + (sigma_m - sigma_r) exp(m (kappa - km) / (sigma_m - sigma_r)),
                           m = 2 (sigma_m - sigma_p) / (km - kp)

Coupled softening of tension and shear. The exponent is shared,
``omega = (ft / GfI) kappa1 + (c / GfII) kappa2``, so that both strengths decrease by the same factor
(the isotropic-softening assumption of [LR97]/[L96] for the tension/shear corner, written so that
pure mode I gives ``sigma1 = ft exp(-(ft/GfI) kappa1)`` and pure mode II
``sigma2 = c exp(-(c/GfII) kappa2)`` exactly, with dissipated energies GfI and GfII). A joint that opens
loses its cohesion and one that slides loses its tensile strength, as the seed's Mohr-Coulomb joint
does (a broken bond has ``c = ft = 0``). ``ft = 0`` sets the first term to 0 and ``c = 0`` the second.

Simplifications with respect to the thesis (said exactly):

* the cap hardening branch ``sqrt(2x - x^2)`` of [L96] is replaced by the parabola ``2x - x^2`` (same
  end values fc/3 and fc, same zero slope at the peak, but a finite slope at ``kappa3 = 0`` so that
  the local Newton iteration is regular at first yield);
* ``km - kp`` follows from the compressive fracture energy defined here as the area above the residual
  strength after the peak, ``Gfc = int_{kp}^{inf} (sigma3 - sigma_r) d kappa3``, which for the curve
  above gives ``km - kp = (588 / 481) Gfc / fc`` (the thesis fixes ``km`` from Gfc with its own
  definition of the area);
* ``Cnn = 1``, ``Cn = 0`` (the values of [LR97] for the masonry examples); only ``Css`` is a
  parameter;
* the coupling of tension and shear softening is the shared exponent above (the cap is not coupled);
* the dilatancy enters the flow direction ``m2`` directly (``tan(psi)`` is not differentiated as a
  potential with respect to ``t_n``).

Return mapping ([SH98] sec. 5.2, backward Euler). Unknowns ``t_n``, ``T`` and the multipliers of the
active set; the shear traction vector follows in closed form, also for ``ks1 != ks2``::

    tau_i = tau_trial_i T / D_i,  D_i = T (1 + 2 Css ks_i lambda3) + ks_i lambda2

(the shear rows of ``t = t_trial - K sum_a lambda_a m_a``), with the magnitude condition
``|tau| = T`` written as ``sqrt(sum_i (tau_trial_i D_1 / D_i)^2) - D_1 = 0`` (linear in the
isotropic case, regular at the apex ``T = 0``). The normal row is
``t_n = t_n_trial - kn (lambda1 + lambda2 tan(psi) + 2 lambda3 t_n)``. Candidate active sets, in this
order: the single surfaces violated by the trial, then the corners tension/shear and shear/cap; the
first whose multipliers are >= 0 and that satisfies the other surfaces is taken. The local system is
solved by Newton's method with a backtracking line search, from the trial state and, if that fails
(steep softening, i.e. snap-back at the point), from the fully softened state (for the cap: the
return onto the residual cap fc/7), and for a corner also from the converged shear-only return.
A return whose active sets all fail gives ``STATUS_NAN`` (the caller cuts the step).

Cost: an elastic point allocates nothing; a plastic point allocates a few small scratch arrays and
takes about 10-30 us (complex-step Jacobians of the 5x5 local system). The Jacobian and the
consistent tangent ``dt/d delta = [J^-1]`` (non-symmetric) are obtained by complex-step
differentiation [MSA03] of the same residual, so they are the exact linearisation of the algorithm.

Parameter row (float64, ``N_COMPOSITE_PARAMS``; built by :func:`composite_params`)::

    P_KS                    0  ks1 shear stiffness (Pa/m) > 0        (same column as mohr_coulomb.P_KS)
    P_KN                    1  kn normal stiffness (Pa/m) > 0        (same column as mohr_coulomb.P_KN)
    P_KS2                   2  ks2 second shear stiffness (3D) (Pa/m) > 0
    P_TENSILE_STRENGTH      3  ft (Pa) >= 0
    P_GF_I                  4  GfI mode I fracture energy (J/m2) > 0 (if ft > 0)
    P_COHESION              5  c (Pa) >= 0, > ft max(tan phi0, tan phi_r) if ft > 0
    P_TAN_PHI0              6  tan(phi0) >= 0
    P_TAN_PHI_R             7  tan(phi_r) >= 0 (residual friction)
    P_TAN_PSI0              8  tan(psi0) >= 0 (dilatancy)
    P_INV_SIGMA_U           9  1 / sigma_u (1/Pa) >= 0 (0: no decay of dilatancy with compression)
    P_DILATANCY_DECAY      10  delta_d (1/m) >= 0
    P_GF_II                11  GfII mode II fracture energy (J/m2) > 0 (if c > 0)
    P_FC                   12  fc (Pa) >= 0 (0: no cap)
    P_CSS                  13  Css > 0
    P_GF_C                 14  Gfc compressive fracture energy (J/m2) > 0 (if fc > 0)
    P_KAPPA_P              15  kp plastic relative displacement at the cap peak (m) > 0 (if fc > 0)
    P_OPEN_TANGENT         16  solver control as mohr_coulomb.P_OPEN_TANGENT: the tangent of a point
                               whose tractions are zero (fully softened and open) is
                               ``open_tangent * K``; 0 (default) is the consistent tangent (zero)
    P_RELAXATION_TIME  17  tau (s) of the Duvaut-Lions regularisation, 0: inviscid (:func:`_duvaut_lions`)
    P_TIME_STEP        18  the evaluation's time step dt (s), written by the assembly before each
                               evaluation (not a material constant)

State row (float64, ``N_COMPOSITE_STATE``)::

    S_CODE              0  ELASTIC 0, SHEAR 1, TENSION 2, CAP 3, TENSION_SHEAR 4, SHEAR_CAP 5
    S_CRACKED           1  1.0 once kappa1 > 0 or kappa2 > 0 (same column as mohr_coulomb.S_BOND_BROKEN)
    S_PLASTIC_SLIP      2  2 columns: plastic shear displacement (m) (2D uses the first)
    S_PLASTIC_OPENING   4  plastic normal displacement (m), opening positive
    S_KAPPA1            5  kappa1 (m)
    S_KAPPA2            6  kappa2 (m)
    S_KAPPA3            7  kappa3 (m)

Re-closure: as in [LR97] the plastic opening is permanent, so a crack re-closes (compressive
traction) when ``delta_n < delta_p_n``, not at ``delta_n = 0`` as in the seed's Mohr-Coulomb joint.
"""
from __future__ import annotations

import cmath
import math

import numpy as np
from numba import njit

from ..errors import STATUS_NAN, STATUS_OK, NumericalError
from .plasticity import STATUS_BAD_MATERIAL, real_parameter

# ---- parameter columns
P_KS = 0
P_KN = 1
P_KS2 = 2
P_TENSILE_STRENGTH = 3
P_GF_I = 4
P_COHESION = 5
P_TAN_PHI0 = 6
P_TAN_PHI_R = 7
P_TAN_PSI0 = 8
P_INV_SIGMA_U = 9
P_DILATANCY_DECAY = 10
P_GF_II = 11
P_FC = 12
P_CSS = 13
P_GF_C = 14
P_KAPPA_P = 15
P_OPEN_TANGENT = 16
P_RELAXATION_TIME = 17
#: the time step (s) of the evaluation: not a material constant but a per-step input the assembly writes
#: into the row before each evaluation (:meth:`masonrydam.assembly.groups.InterfaceGroup.evaluate`), so that
#: the interface kernels keep one law-agnostic signature; 0 is a rate-independent step
P_TIME_STEP = 18
N_COMPOSITE_PARAMS = 19

PARAM_NAMES = {
    P_KS: "shear_stiffness",
    P_KN: "normal_stiffness",
    P_KS2: "shear_stiffness_2",
    P_TENSILE_STRENGTH: "tensile_strength",
    P_GF_I: "mode_I_fracture_energy",
    P_COHESION: "cohesion",
    P_TAN_PHI0: "friction_angle",
    P_TAN_PHI_R: "residual_friction_angle",
    P_TAN_PSI0: "dilatancy_angle",
    P_INV_SIGMA_U: "dilatancy_confinement",
    P_DILATANCY_DECAY: "dilatancy_decay",
    P_GF_II: "mode_II_fracture_energy",
    P_FC: "compressive_strength",
    P_CSS: "cap_shear_factor",
    P_GF_C: "cap_fracture_energy",
    P_KAPPA_P: "cap_peak_plastic_strain",
    P_OPEN_TANGENT: "open_tangent",
    P_RELAXATION_TIME: "relaxation_time",
    P_TIME_STEP: "time_step",
}

# ---- state columns
S_CODE = 0
S_CRACKED = 1
S_PLASTIC_SLIP = 2  # columns 2, 3
S_PLASTIC_OPENING = 4
S_KAPPA1 = 5
S_KAPPA2 = 6
S_KAPPA3 = 7
N_COMPOSITE_STATE = 8

# ---- codes (S_CODE)
ELASTIC = 0
SHEAR = 1
TENSION = 2
CAP = 3
TENSION_SHEAR = 4
SHEAR_CAP = 5

#: km - kp = CAP_SOFTENING_FACTOR * Gfc / fc (see the module docstring)
CAP_SOFTENING_FACTOR = 588.0 / 481.0

# ---- constants vector of a point (internal)
_W_KN = 0
_W_KS1 = 1
_W_KS2 = 2
_W_FT = 3
_W_A1 = 4
_W_C = 5
_W_A2 = 6
_W_TPHI0 = 7
_W_TPHIR = 8
_W_TPSI0 = 9
_W_INVSU = 10
_W_DD = 11
_W_FC = 12
_W_CSS = 13
_W_KP = 14
_W_DKM = 15
_W_KAP1 = 16
_W_KAP2 = 17
_W_KAP3 = 18
_W_SIZE = 19

_MAX_IT = 60
_TOL_NEWTON = 1e-12  # relative to the traction scale
_TOL_ELASTIC = 1e-10  # a trial within this of a surface is elastic
_TOL_KKT = 1e-8  # inactive surfaces and multipliers at an accepted return


@njit(cache=True)
def _sigma3(kap, fc, kp, dkm):
    """Cap strength sigma3(kappa3) (module docstring); complex argument for complex-step derivatives."""
    si = fc / 3.0
    sp = fc
    sm = 0.5 * fc
    sr = fc / 7.0
    if kap.real < 0.0:
        # continuation below 0 (only met by Newton iterates): positive, C1 at 0, so that no
        # spurious root with kappa3 < 0 exists
        return si * cmath.exp(2.0 * (sp - si) / si * kap / kp)
    if kap.real < kp:
        x = kap / kp
        return si + (sp - si) * (2.0 * x - x * x)
    if kap.real < kp + dkm:
        y = (kap - kp) / dkm
        return sp + (sm - sp) * y * y
    m = 2.0 * (sm - sp) / dkm
    return sr + (sm - sr) * cmath.exp(m * (kap - kp - dkm) / (sm - sr))


@njit(cache=True)
def _residual(x, tr, w, ns, act1, act2, act3, R, tau, fv):
    """Residual of the local system of the active set ``(act1, act2, act3)``.

    ``x`` complex (5,): ``[t_n, T, L1, L2, L3]`` with the scaled multipliers ``L1 = kn lambda1``,
    ``L2 = ks1 lambda2``, ``L3 = 2 kn fc lambda3`` (all in Pa); ``tr`` complex (3,): trial
    ``[tau1, tau2, t_n]``. Writes ``R`` (5,) (Pa; an inactive multiplier has the row ``L_a = 0``),
    the shear tractions ``tau`` (2,) and the three yield functions ``fv`` (3,) (f3 / (2 fc); -1
    without a cap). Returns False where the shear denominators are not positive."""
    kn = w[_W_KN]
    ks1 = w[_W_KS1]
    ks2 = w[_W_KS2]
    fc = w[_W_FC]
    css = w[_W_CSS]
    tn = x[0]
    T = x[1]
    L1 = x[2]
    L2 = x[3]
    L3 = x[4]
    lam1 = L1 / kn
    lam2 = L2 / ks1
    q3 = L3 / fc if fc > 0.0 else 0.0 * L3  # = 2 kn lambda3
    kap1 = w[_W_KAP1] + lam1
    kap2 = w[_W_KAP2] + lam2
    eom = cmath.exp(-(w[_W_A1] * kap1 + w[_W_A2] * kap2))
    s1 = w[_W_FT] * eom
    s2 = w[_W_C] * eom
    tphi = w[_W_TPHIR] + (w[_W_TPHI0] - w[_W_TPHIR]) * eom
    gfac = 1.0 + tn * w[_W_INVSU]
    if gfac.real <= 0.0:
        gfac = 0.0 * gfac
    tpsi = w[_W_TPSI0] * gfac * cmath.exp(-w[_W_DD] * kap2)

    ok = True
    e1 = 1.0 + css * (ks1 / kn) * q3
    e2 = 1.0 + css * (ks2 / kn) * q3
    zero_trial = tr[0].real == 0.0 and (ns == 1 or tr[1].real == 0.0)
    if act2:
        D1 = T * e1 + L2
        D2 = T * e2 + (ks2 / ks1) * L2
        if not (D1.real > 0.0 and (ns == 1 or D2.real > 0.0)):
            ok = False
        tau[0] = tr[0] * T / D1
        tau[1] = tr[1] * T / D2 if ns == 2 else 0.0 * T
        if zero_trial:
            G = -D1
        elif ns == 1:
            G = cmath.sqrt(tr[0] * tr[0]) - D1
        else:
            r2 = tr[1] * D1 / D2
            G = cmath.sqrt(tr[0] * tr[0] + r2 * r2) - D1
    else:
        tau[0] = tr[0] / e1
        tau[1] = tr[1] / e2 if ns == 2 else 0.0 * T
        if zero_trial:
            G = -T * e1
        elif ns == 1:
            G = cmath.sqrt(tr[0] * tr[0]) - T * e1
        else:
            r2 = tr[1] * e1 / e2
            G = cmath.sqrt(tr[0] * tr[0] + r2 * r2) - T * e1

    R[0] = tn - tr[2] + L1 + (kn / ks1) * L2 * tpsi + q3 * tn
    R[1] = G
    fv[0] = tn - s1
    fv[1] = T + tn * tphi - s2
    if fc > 0.0:
        lam3 = q3 / (2.0 * kn)
        kap3 = w[_W_KAP3] + lam3 * 2.0 * cmath.sqrt(css * css * T * T + tn * tn)
        sb3 = _sigma3(kap3, fc, w[_W_KP], w[_W_DKM])
        fv[2] = (tn * tn + css * T * T - sb3 * sb3) / (2.0 * fc)
    else:
        fv[2] = -1.0 + 0.0 * tn
    R[2] = fv[0] if act1 else L1
    R[3] = fv[1] if act2 else L2
    R[4] = fv[2] if act3 else L3
    for i in range(5):
        if not (math.isfinite(R[i].real) and math.isfinite(R[i].imag)):
            ok = False
    return ok


@njit(cache=True)
def _lu(A, piv, n):
    """In-place LU factorisation with partial pivoting of ``A[:n, :n]``; False if singular."""
    for k in range(n):
        p = k
        amax = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > amax:
                amax = abs(A[i, k])
                p = i
        if not amax > 0.0 or not math.isfinite(amax):
            return False
        piv[k] = p
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        for i in range(k + 1, n):
            A[i, k] /= A[k, k]
            lik = A[i, k]
            for j in range(k + 1, n):
                A[i, j] -= lik * A[k, j]
    return True


@njit(cache=True)
def _lu_solve(A, piv, b, n):
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= A[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= A[i, j] * b[j]
        b[i] = s / A[i, i]


@njit(cache=True)
def _norm_R(R):
    s = 0.0
    for i in range(5):
        s += R[i].real * R[i].real
    return math.sqrt(s)


@njit(cache=True)
def _jacobian(x, tr, w, ns, act1, act2, act3, h, J, cx, R, tau, fv):
    """J[:, j] = d R / d x_j by complex steps of size ``h``."""
    for j in range(5):
        for i in range(5):
            cx[i] = complex(x[i], 0.0)
        cx[j] = complex(x[j], h)
        _residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv)
        for i in range(5):
            J[i, j] = R[i].imag / h


@njit(cache=True)
def _newton(x, tr, w, ns, act1, act2, act3, sref, J, piv, dx, xn, cx, R, tau, fv):
    """Newton iteration with backtracking on |R| from ``x`` (overwritten by the solution); True when
    converged."""
    tol = _TOL_NEWTON * sref
    h = 1e-20 * sref
    for i in range(5):
        cx[i] = complex(x[i], 0.0)
    if not _residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv):
        return False
    r0 = _norm_R(R)
    for it in range(_MAX_IT):
        if r0 <= tol:
            return True
        for i in range(5):
            dx[i] = -R[i].real
        _jacobian(x, tr, w, ns, act1, act2, act3, h, J, cx, R, tau, fv)
        if not _lu(J, piv, 5):
            return False
        _lu_solve(J, piv, dx, 5)
        alpha = 1.0
        accepted = False
        r1 = r0
        for ls in range(40):
            for i in range(5):
                xn[i] = x[i] + alpha * dx[i]
                cx[i] = complex(xn[i], 0.0)
            if _residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv):
                r1 = _norm_R(R)
                if r1 <= tol or r1 < (1.0 - 1e-4 * alpha) * r0:
                    accepted = True
                    break
            alpha *= 0.5
        if not accepted:
            return False
        for i in range(5):
            x[i] = xn[i]
        r0 = r1
    return r0 <= tol


@njit(cache=True)
def _kkt_ok(x, tr, w, ns, act1, act2, act3, sref, cx, R, tau, fv):
    """Is the converged return admissible: multipliers of the active set >= 0, T >= 0, the other
    surfaces not violated?"""
    tol = _TOL_KKT * sref
    for i in range(5):
        cx[i] = complex(x[i], 0.0)
    _residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv)
    if x[1] < -tol:
        return False
    if (act1 and x[2] < -tol) or (act2 and x[3] < -tol) or (act3 and x[4] < -tol):
        return False
    if (not act1 and fv[0].real > tol) or (not act2 and fv[1].real > tol) or (not act3 and fv[2].real > tol):
        return False
    return True


@njit(cache=True)
def _cap_start(tau1_tr, tau2_tr, tn_tr, w, ns):
    """``q = 2 kn lambda3`` of the cap-only return onto the residual cap ``sigma3 = fc/7`` (bisection
    on the decreasing ``t_n(q)^2 + Css T(q)^2 - sigma_r^2``): the fully softened start of a cap
    return."""
    css = w[_W_CSS]
    r1 = css * w[_W_KS1] / w[_W_KN]
    r2 = css * w[_W_KS2] / w[_W_KN]
    sr2 = (w[_W_FC] / 7.0) ** 2
    lo = 0.0
    hi = 1.0
    for it in range(200):
        a = tn_tr / (1.0 + hi)
        b1 = tau1_tr / (1.0 + r1 * hi)
        b2 = tau2_tr / (1.0 + r2 * hi)
        if a * a + css * (b1 * b1 + b2 * b2) <= sr2:
            break
        lo = hi
        hi *= 2.0
    for it in range(100):
        q = 0.5 * (lo + hi)
        a = tn_tr / (1.0 + q)
        b1 = tau1_tr / (1.0 + r1 * q)
        b2 = tau2_tr / (1.0 + r2 * q)
        if a * a + css * (b1 * b1 + b2 * b2) > sr2:
            lo = q
        else:
            hi = q
    return 0.5 * (lo + hi)


@njit(cache=True)
def _bad_column(params, p):
    """First inadmissible parameter column of row ``p`` (the kernel's check; the builder's checks
    are stricter and name the values), or -1."""
    if not params[p, P_KS] > 0.0:
        return P_KS
    if not params[p, P_KN] > 0.0:
        return P_KN
    if not params[p, P_KS2] > 0.0:
        return P_KS2
    ft = params[p, P_TENSILE_STRENGTH]
    if not ft >= 0.0:
        return P_TENSILE_STRENGTH
    if not (params[p, P_GF_I] > 0.0 or (ft == 0.0 and params[p, P_GF_I] >= 0.0)):
        return P_GF_I
    c = params[p, P_COHESION]
    if not c >= 0.0:
        return P_COHESION
    for col in (P_TAN_PHI0, P_TAN_PHI_R, P_TAN_PSI0, P_INV_SIGMA_U, P_DILATANCY_DECAY):
        if not params[p, col] >= 0.0:
            return col
    if not (params[p, P_GF_II] > 0.0 or (c == 0.0 and params[p, P_GF_II] >= 0.0)):
        return P_GF_II
    if ft > 0.0 and not c > ft * max(params[p, P_TAN_PHI0], params[p, P_TAN_PHI_R]):
        return P_COHESION
    fc = params[p, P_FC]
    if not fc >= 0.0:
        return P_FC
    if fc > 0.0:
        if not fc > ft:
            return P_FC
        if not params[p, P_CSS] > 0.0:
            return P_CSS
        if not params[p, P_GF_C] > 0.0:
            return P_GF_C
        if not params[p, P_KAPPA_P] > 0.0:
            return P_KAPPA_P
    if not params[p, P_RELAXATION_TIME] >= 0.0:
        return P_RELAXATION_TIME
    if not params[p, P_TIME_STEP] >= 0.0:
        return P_TIME_STEP
    return -1


@njit(cache=True)
def _fail(state_committed, state_trial, e, g, traction_out, C, ns):
    for j in range(N_COMPOSITE_STATE):
        state_trial[e, g, j] = state_committed[e, g, j]
    for i in range(ns + 1):
        traction_out[e, g, i] = np.nan
        for j in range(ns + 1):
            C[i, j] = 0.0


@njit(cache=True)
def _duvaut_lions(ratio, delta, e, g, ns, ks1, ks2, kn, tau1_tr, tau2_tr, tn_tr, state_committed, state_trial,
                  traction_out, C):
    """Viscous regularisation of Duvaut and Lions ([SH98] sec. 2.7; for cohesive interfaces
    [GB04]): over a step ``dt`` the tractions and internal variables relax towards the inviscid return
    (already in ``traction_out``, ``state_trial`` and ``C``) with the relaxation time ``tau``, by
    backward Euler::

        t = (t_trial + r t_inf) / (1 + r),   kappa = (kappa_n + r kappa_inf) / (1 + r),   r = dt / tau
        C = (K + r C_inf) / (1 + r)

    (``C`` is exact: ``t_trial = K (delta - delta_p,n)``). The plastic displacements follow from the
    tractions, ``delta_p = delta - K^-1 t``. As ``tau / dt -> 0`` this is the inviscid law; for a finite
    ``tau`` the tangent tends to the elastic one as ``dt`` shrinks, so a step cut makes the joint stable
    where a softening point would make the structure's tangent singular. The code and the cracked flag
    are the inviscid return's (the surface the point is flowing to)."""
    a = 1.0 / (1.0 + ratio)
    b = ratio * a
    k = (ks1, ks2, kn)
    t1 = a * tau1_tr + b * traction_out[e, g, 0]
    traction_out[e, g, 0] = t1
    state_trial[e, g, S_PLASTIC_SLIP] = delta[e, g, 0] - t1 / ks1
    if ns == 2:
        t2 = a * tau2_tr + b * traction_out[e, g, 1]
        traction_out[e, g, 1] = t2
        state_trial[e, g, S_PLASTIC_SLIP + 1] = delta[e, g, 1] - t2 / ks2
    tn = a * tn_tr + b * traction_out[e, g, ns]
    traction_out[e, g, ns] = tn
    state_trial[e, g, S_PLASTIC_OPENING] = delta[e, g, ns] - tn / kn
    for col in (S_KAPPA1, S_KAPPA2, S_KAPPA3):
        state_trial[e, g, col] = a * state_committed[e, g, col] + b * state_trial[e, g, col]
    for i in range(ns + 1):
        for j in range(ns + 1):
            C[i, j] *= b
        C[i, i] += a * (kn if i == ns else k[i])


@njit(cache=True)
def composite_point(params, p, delta, ns, state_committed, state_trial, e, g, traction_out, C):
    """The composite interface law at point ``g`` of element ``e``.

    Parameters
    ----------
    params : float64 (n_sets, N_COMPOSITE_PARAMS); p : the row of this point.
    delta : float64 (n_elem, nip, ns+1): local relative displacement ``[s1, (s2,) n]`` (m) read at
        ``[e, g]``.
    ns : 1 (2D) or 2 (3D) shear components.
    state_committed : float64 (n_elem, nip, N_COMPOSITE_STATE), read only at ``[e, g]``.
    state_trial : same shape, written at ``[e, g]``.
    traction_out : float64 (n_elem, nip, ns+1), written at ``[e, g]``: ``[tau1, (tau2,) t_n]`` (Pa).
    C : float64 (ns+1, ns+1), out: the consistent tangent ``d t / d delta`` (Pa/m).

    Returns
    -------
    STATUS_OK; STATUS_NAN for a non-finite input or result or a local return that did not converge;
    ``plasticity.STATUS_BAD_MATERIAL`` for an inadmissible parameter row. On failure the trial state
    is the committed one, the tractions NaN and the tangent zero.
    """
    n = ns + 1
    npar = params.shape[1]
    for j in range(npar):
        if not math.isfinite(params[p, j]):
            _fail(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
    for j in range(n):
        if not math.isfinite(delta[e, g, j]):
            _fail(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
    for j in range(N_COMPOSITE_STATE):
        if not math.isfinite(state_committed[e, g, j]):
            _fail(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
    if _bad_column(params, p) >= 0:
        _fail(state_committed, state_trial, e, g, traction_out, C, ns)
        return STATUS_BAD_MATERIAL

    ks1 = params[p, P_KS]
    kn = params[p, P_KN]
    ks2 = params[p, P_KS2] if ns == 2 else ks1
    ft = params[p, P_TENSILE_STRENGTH]
    c = params[p, P_COHESION]
    fc = params[p, P_FC]
    a1 = ft / params[p, P_GF_I] if ft > 0.0 else 0.0
    a2 = c / params[p, P_GF_II] if c > 0.0 else 0.0
    kap1 = state_committed[e, g, S_KAPPA1]
    kap2 = state_committed[e, g, S_KAPPA2]
    kap3 = state_committed[e, g, S_KAPPA3]

    # elastic trial
    tn_tr = kn * (delta[e, g, ns] - state_committed[e, g, S_PLASTIC_OPENING])
    tau1_tr = ks1 * (delta[e, g, 0] - state_committed[e, g, S_PLASTIC_SLIP])
    tau2_tr = ks2 * (delta[e, g, 1] - state_committed[e, g, S_PLASTIC_SLIP + 1]) if ns == 2 else 0.0
    T_tr = math.sqrt(tau1_tr * tau1_tr + tau2_tr * tau2_tr)
    eom = math.exp(-(a1 * kap1 + a2 * kap2))
    tphi = params[p, P_TAN_PHI_R] + (params[p, P_TAN_PHI0] - params[p, P_TAN_PHI_R]) * eom
    f1 = tn_tr - ft * eom
    f2 = T_tr + tn_tr * tphi - c * eom
    f3 = -1.0
    dkm = 0.0
    if fc > 0.0:
        dkm = CAP_SOFTENING_FACTOR * params[p, P_GF_C] / fc
        sb3 = _sigma3(complex(kap3, 0.0), fc, params[p, P_KAPPA_P], dkm).real
        f3 = (tn_tr * tn_tr + params[p, P_CSS] * T_tr * T_tr - sb3 * sb3) / (2.0 * fc)
    sref = max(abs(tn_tr), T_tr, ft, c, fc)
    if not sref > 0.0:
        sref = 1.0
    tol_e = _TOL_ELASTIC * sref
    cracked = state_committed[e, g, S_CRACKED]

    if f1 <= tol_e and f2 <= tol_e and f3 <= tol_e:
        for j in range(N_COMPOSITE_STATE):
            state_trial[e, g, j] = state_committed[e, g, j]
        state_trial[e, g, S_CODE] = float(ELASTIC)
        traction_out[e, g, 0] = tau1_tr
        if ns == 2:
            traction_out[e, g, 1] = tau2_tr
        traction_out[e, g, ns] = tn_tr
        for i in range(n):
            for j in range(n):
                C[i, j] = 0.0
        C[0, 0] = ks1
        if ns == 2:
            C[1, 1] = ks2
        C[ns, ns] = kn
        if not (math.isfinite(tn_tr) and math.isfinite(T_tr)):
            _fail(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
        return STATUS_OK

    # ---- plastic: local constants and scratch
    w = np.empty(_W_SIZE)
    w[_W_KN] = kn
    w[_W_KS1] = ks1
    w[_W_KS2] = ks2
    w[_W_FT] = ft
    w[_W_A1] = a1
    w[_W_C] = c
    w[_W_A2] = a2
    w[_W_TPHI0] = params[p, P_TAN_PHI0]
    w[_W_TPHIR] = params[p, P_TAN_PHI_R]
    w[_W_TPSI0] = params[p, P_TAN_PSI0]
    w[_W_INVSU] = params[p, P_INV_SIGMA_U]
    w[_W_DD] = params[p, P_DILATANCY_DECAY]
    w[_W_FC] = fc
    w[_W_CSS] = params[p, P_CSS] if fc > 0.0 else 0.0
    w[_W_KP] = params[p, P_KAPPA_P]
    w[_W_DKM] = dkm
    w[_W_KAP1] = kap1
    w[_W_KAP2] = kap2
    w[_W_KAP3] = kap3
    tr = np.empty(3, dtype=np.complex128)
    tr[0] = complex(tau1_tr, 0.0)
    tr[1] = complex(tau2_tr, 0.0)
    tr[2] = complex(tn_tr, 0.0)
    x = np.empty(5)
    dx = np.empty(5)
    xn = np.empty(5)
    J = np.empty((5, 5))
    piv = np.empty(5, dtype=np.int64)
    cx = np.empty(5, dtype=np.complex128)
    R = np.empty(5, dtype=np.complex128)
    tau = np.empty(2, dtype=np.complex128)
    fv = np.empty(3, dtype=np.complex128)

    xs = np.zeros(5)
    have_xs = False
    found = False
    act1 = False
    act2 = False
    act3 = False
    code = ELASTIC
    for cand in range(5):
        if cand == 0:
            if not f1 > tol_e:
                continue
            act1, act2, act3, code = True, False, False, TENSION
        elif cand == 1:
            if not f2 > tol_e:
                continue
            act1, act2, act3, code = False, True, False, SHEAR
        elif cand == 2:
            if not f3 > tol_e:
                continue
            act1, act2, act3, code = False, False, True, CAP
        elif cand == 3:
            if not (f1 > tol_e or f2 > tol_e):
                continue
            act1, act2, act3, code = True, True, False, TENSION_SHEAR
        else:
            if fc <= 0.0 or not (f2 > tol_e or f3 > tol_e):
                continue
            act1, act2, act3, code = False, True, True, SHEAR_CAP
        for start in range(3):
            x[0] = tn_tr
            x[1] = T_tr
            x[2] = 0.0
            x[3] = 0.0
            x[4] = 0.0
            if start == 2:
                # a corner from the converged shear-only return
                if not (have_xs and (act1 or act3)):
                    break
                for i in range(5):
                    x[i] = xs[i]
            elif start == 1:
                # fully softened start (right of the root of a concave softening residual)
                if act3:
                    q = _cap_start(tau1_tr, tau2_tr, tn_tr, w, ns)
                    x[0] = tn_tr / (1.0 + q)
                    t1q = tau1_tr / (1.0 + w[_W_CSS] * ks1 / kn * q)
                    t2q = tau2_tr / (1.0 + w[_W_CSS] * ks2 / kn * q)
                    x[1] = math.sqrt(t1q * t1q + t2q * t2q)
                    x[4] = q * fc
                if act1:
                    x[0] = 0.0
                    x[2] = max(tn_tr, 0.0)
                if act2:
                    x[1] = 0.0 if act1 else max(-tn_tr * w[_W_TPHIR], 0.0)
                    x[3] = T_tr - x[1]
            if _newton(x, tr, w, ns, act1, act2, act3, sref, J, piv, dx, xn, cx, R, tau, fv):
                if act2 and not (act1 or act3) and not have_xs:
                    have_xs = True
                    for i in range(5):
                        xs[i] = x[i]
                if _kkt_ok(x, tr, w, ns, act1, act2, act3, sref, cx, R, tau, fv):
                    found = True
                    break
        if found:
            break
    if not found:
        _fail(state_committed, state_trial, e, g, traction_out, C, ns)
        return STATUS_NAN

    # ---- converged return: tractions and state
    for i in range(5):
        cx[i] = complex(x[i], 0.0)
    _residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv)
    tn = x[0]
    t1 = tau[0].real
    t2 = tau[1].real if ns == 2 else 0.0
    lam1 = x[2] / kn if act1 else 0.0
    lam2 = x[3] / ks1 if act2 else 0.0
    lam3 = x[4] / (2.0 * kn * fc) if act3 else 0.0
    k1n = kap1 + lam1
    k2n = kap2 + lam2
    k3n = kap3 + lam3 * 2.0 * math.sqrt(w[_W_CSS] ** 2 * x[1] * x[1] + tn * tn)
    state_trial[e, g, S_CODE] = float(code)
    state_trial[e, g, S_CRACKED] = 1.0 if (cracked != 0.0 or k1n > 0.0 or k2n > 0.0) else 0.0
    state_trial[e, g, S_PLASTIC_SLIP] = delta[e, g, 0] - t1 / ks1
    state_trial[e, g, S_PLASTIC_SLIP + 1] = (delta[e, g, 1] - t2 / ks2) if ns == 2 else \
        state_committed[e, g, S_PLASTIC_SLIP + 1]
    state_trial[e, g, S_PLASTIC_OPENING] = delta[e, g, ns] - tn / kn
    state_trial[e, g, S_KAPPA1] = k1n
    state_trial[e, g, S_KAPPA2] = k2n
    state_trial[e, g, S_KAPPA3] = k3n
    traction_out[e, g, 0] = t1
    if ns == 2:
        traction_out[e, g, 1] = t2
    traction_out[e, g, ns] = tn

    # ---- consistent tangent: dx/d delta_j = -J^-1 dR/d delta_j; outputs by directional complex steps
    ot = params[p, P_OPEN_TANGENT]
    is_open = (act1 and abs(tn) <= _TOL_NEWTON * sref * 10.0 and abs(x[1]) <= _TOL_NEWTON * sref * 10.0)
    if is_open and ot != 0.0:
        for i in range(n):
            for j in range(n):
                C[i, j] = 0.0
        C[0, 0] = ot * ks1
        if ns == 2:
            C[1, 1] = ot * ks2
        C[ns, ns] = ot * kn
    else:
        h = 1e-20 * sref
        _jacobian(x, tr, w, ns, act1, act2, act3, h, J, cx, R, tau, fv)
        if not _lu(J, piv, 5):
            _fail(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
        trc = np.empty(3, dtype=np.complex128)
        for j in range(n):
            # delta_j moves the trial component j by k_j d delta_j; step h / k_j in delta_j
            kj = kn if j == ns else (ks1 if j == 0 else ks2)
            comp = 2 if j == ns else j
            for i in range(3):
                trc[i] = tr[i]
            trc[comp] = complex(tr[comp].real, h)
            for i in range(5):
                cx[i] = complex(x[i], 0.0)
            _residual(cx, trc, w, ns, act1, act2, act3, R, tau, fv)
            for i in range(5):
                dx[i] = -R[i].imag  # = -h dR/d tr_comp
            _lu_solve(J, piv, dx, 5)  # = h dx/d tr_comp
            for i in range(5):
                cx[i] = complex(x[i], dx[i])
            _residual(cx, trc, w, ns, act1, act2, act3, R, tau, fv)
            C[0, j] = tau[0].imag / h * kj
            if ns == 2:
                C[1, j] = tau[1].imag / h * kj
            C[ns, j] = dx[0] / h * kj
    tau_relax = params[p, P_RELAXATION_TIME]
    dt = params[p, P_TIME_STEP]
    if tau_relax > 0.0:  # (dt = 0: no time to relax, the elastic trial, as Perzyna blocks do)
        _duvaut_lions(dt / tau_relax, delta, e, g, ns, ks1, ks2, kn, tau1_tr, tau2_tr, tn_tr,
                      state_committed, state_trial, traction_out, C)
    for i in range(n):
        if not math.isfinite(traction_out[e, g, i]):
            _fail(state_committed, state_trial, e, g, traction_out, C, ns)
            return STATUS_NAN
        for j in range(n):
            if not math.isfinite(C[i, j]):
                _fail(state_committed, state_trial, e, g, traction_out, C, ns)
                return STATUS_NAN
    return STATUS_OK


@njit(cache=True)
def composite_update(delta, params, state_committed, state_trial, traction_out, tangent_out, info):
    """Batch update: :func:`composite_point` for every row ``k`` (parameter row ``k``).

    delta float64 (n, ns+1) C-contiguous; params (n, N_COMPOSITE_PARAMS); state_committed,
    state_trial (n, N_COMPOSITE_STATE); traction_out (n, ns+1); tangent_out (n, ns+1, ns+1);
    info int64 (>= 1,): ``info[0]`` = the failing point, ``info[1]`` (if present) = the bad
    parameter column. Returns the status of the first failing point (later points not evaluated).
    """
    n = delta.shape[0]
    ncomp = delta.shape[1]
    ns = ncomp - 1
    d3 = delta.reshape((n, 1, ncomp))
    sc3 = state_committed.reshape((n, 1, N_COMPOSITE_STATE))
    st3 = state_trial.reshape((n, 1, N_COMPOSITE_STATE))
    t3 = traction_out.reshape((n, 1, ncomp))
    for k in range(n):
        status = composite_point(params, k, d3, ns, sc3, st3, k, 0, t3, tangent_out[k])
        if status != STATUS_OK:
            info[0] = k
            if info.shape[0] > 1:
                info[1] = _bad_column(params, k)
            return status
    return STATUS_OK


# ----------------------------------------------------------------------------------------------
# Python side
# ----------------------------------------------------------------------------------------------


def composite_initial_state(n: int) -> np.ndarray:
    """Virgin state rows (n, N_COMPOSITE_STATE): elastic, uncracked, no plastic displacement."""
    return np.zeros((int(n), N_COMPOSITE_STATE), dtype=np.float64)


def composite_evaluate(delta, params, state_committed):
    """Python wrapper of :func:`composite_update`.

    Parameters
    ----------
    delta : (n, ns+1) array (or one point (ns+1,)), ns = 1 (2D) or 2 (3D), m.
    params : (n, N_COMPOSITE_PARAMS) or one row used for every point (:func:`composite_params`).
    state_committed : (n, N_COMPOSITE_STATE); read only.

    Returns
    -------
    (traction (n, ns+1) Pa, tangent (n, ns+1, ns+1) Pa/m, state_trial (n, N_COMPOSITE_STATE)).

    Raises
    ------
    ValueError for a bad shape or parameter; masonrydam.errors.NumericalError for a non-finite
    input or result or a local return mapping that did not converge.
    """
    d = np.ascontiguousarray(delta, dtype=np.float64)
    if d.ndim == 1:
        d = d.reshape(1, -1)
    if d.ndim != 2 or d.shape[1] not in (2, 3):
        raise ValueError(f"delta must have 2 (2D) or 3 (3D) components per point, got shape {np.shape(delta)}")
    n, ncomp = d.shape
    pr = np.ascontiguousarray(params, dtype=np.float64)
    if pr.ndim == 1:
        pr = pr.reshape(1, -1)
    if pr.ndim != 2 or pr.shape[1] != N_COMPOSITE_PARAMS:
        raise ValueError(f"params must have {N_COMPOSITE_PARAMS} columns, got shape {np.shape(params)}")
    if pr.shape[0] == 1 and n != 1:
        pr = np.ascontiguousarray(np.broadcast_to(pr, (n, N_COMPOSITE_PARAMS)))
    if pr.shape[0] != n:
        raise ValueError(f"params must have 1 or {n} rows, got shape {pr.shape}")
    sc = np.ascontiguousarray(state_committed, dtype=np.float64)
    if sc.ndim == 1:
        sc = sc.reshape(1, -1)
    if sc.shape != (n, N_COMPOSITE_STATE):
        raise ValueError(f"state_committed must have shape ({n}, {N_COMPOSITE_STATE}), got {np.shape(state_committed)}")
    st = np.empty_like(sc)
    t = np.empty((n, ncomp))
    C = np.empty((n, ncomp, ncomp))
    info = np.zeros(2, dtype=np.int64)
    status = composite_update(d, pr, sc, st, t, C, info)
    if status == STATUS_BAD_MATERIAL:
        col = int(info[1])
        raise ValueError(f"composite interface: inadmissible {PARAM_NAMES.get(col, col)} at point {int(info[0])}")
    if status != STATUS_OK:
        raise NumericalError(
            f"composite interface: non-finite input or result, or no converged return, at point {int(info[0])}")
    return t, C, st


def _real(name, value):
    return real_parameter("composite interface", name, value)


def composite_params(
    normal_stiffness: float,
    shear_stiffness: float,
    tensile_strength: float,
    mode_I_fracture_energy: float,
    cohesion: float,
    friction_angle: float,
    *,
    mode_II_fracture_energy: float,
    residual_friction_angle: float | None = None,
    dilatancy_angle: float = 0.0,
    dilatancy_confinement: float | None = None,
    dilatancy_decay: float = 0.0,
    compressive_strength: float | None = None,
    cap_shear_factor: float = 9.0,
    cap_fracture_energy: float | None = None,
    cap_peak_plastic_strain: float | None = None,
    shear_stiffness_2: float | None = None,
    relaxation_time: float = 0.0,
) -> np.ndarray:
    """Validated parameter row (N_COMPOSITE_PARAMS,) of the composite interface law.

    Parameters (SI; angles in degrees)
    ----------------------------------
    normal_stiffness, shear_stiffness : kn, ks (Pa/m), > 0.
    tensile_strength : ft (Pa), >= 0 (0: no tension).
    mode_I_fracture_energy : GfI (J/m2), > 0 when ft > 0 (>= 0 otherwise).
    cohesion : c (Pa), >= 0; when ft > 0, c > ft tan(phi) for both friction angles (the tension
        cut-off cuts the Coulomb surface below its apex, the geometry of [LR97]).
    friction_angle : phi0 (deg), [0, 90).
    mode_II_fracture_energy : GfII (J/m2), > 0 when c > 0 (>= 0 otherwise). Keyword only.
    residual_friction_angle : phi_r (deg), [0, 90); None: phi0 (no friction softening).
    dilatancy_angle : psi0 (deg), [0, 90).
    dilatancy_confinement : sigma_u (Pa) > 0, the compression at which the dilatancy vanishes;
        None: no decay with the normal stress.
    dilatancy_decay : delta_d (1/m) >= 0, decay of the dilatancy with the plastic slip.
    compressive_strength : fc (Pa) > ft; None: no cap.
    cap_shear_factor : Css > 0 (default 9, [LR97]).
    cap_fracture_energy : Gfc (J/m2) > 0, required with a cap.
    cap_peak_plastic_strain : kp (m) > 0, plastic relative displacement at the cap peak, required
        with a cap.
    shear_stiffness_2 : ks2 (Pa/m) > 0 of the second shear direction (3D); None: ks.
    relaxation_time : tau (s) >= 0 of the Duvaut-Lions viscous regularisation (:func:`_duvaut_lions`);
        0: the inviscid law. A step without time (``P_TIME_STEP`` = 0, e.g. a modal stage's tangent) is then
        the elastic trial from the committed state (no time to relax).

    Raises
    ------
    ValueError naming the offending parameter and its value.
    """
    kn = _real("normal_stiffness", normal_stiffness)
    ks = _real("shear_stiffness", shear_stiffness)
    ks2 = ks if shear_stiffness_2 is None else _real("shear_stiffness_2", shear_stiffness_2)
    ft = _real("tensile_strength", tensile_strength)
    gf1 = _real("mode_I_fracture_energy", mode_I_fracture_energy)
    c = _real("cohesion", cohesion)
    phi = _real("friction_angle", friction_angle)
    gf2 = _real("mode_II_fracture_energy", mode_II_fracture_energy)
    phir = phi if residual_friction_angle is None else _real("residual_friction_angle", residual_friction_angle)
    psi = _real("dilatancy_angle", dilatancy_angle)
    dd = _real("dilatancy_decay", dilatancy_decay)
    css = _real("cap_shear_factor", cap_shear_factor)
    tau_relax = _real("relaxation_time", relaxation_time)

    def bad(name, value, rule):
        raise ValueError(f"composite interface parameter {name} {rule}, got {value!r}")

    if not kn > 0.0:
        bad("normal_stiffness", kn, "must be > 0 (Pa/m)")
    if not ks > 0.0:
        bad("shear_stiffness", ks, "must be > 0 (Pa/m)")
    if not ks2 > 0.0:
        bad("shear_stiffness_2", ks2, "must be > 0 (Pa/m)")
    if ft < 0.0:
        bad("tensile_strength", ft, "must be >= 0 (Pa)")
    if gf1 < 0.0:
        bad("mode_I_fracture_energy", gf1, "must be >= 0 (J/m2)")
    if ft > 0.0 and not gf1 > 0.0:
        bad("mode_I_fracture_energy", gf1, "must be > 0 (J/m2) when tensile_strength > 0")
    if c < 0.0:
        bad("cohesion", c, "must be >= 0 (Pa)")
    if gf2 < 0.0:
        bad("mode_II_fracture_energy", gf2, "must be >= 0 (J/m2)")
    if c > 0.0 and not gf2 > 0.0:
        bad("mode_II_fracture_energy", gf2, "must be > 0 (J/m2) when cohesion > 0")
    for name, v in (("friction_angle", phi), ("residual_friction_angle", phir), ("dilatancy_angle", psi)):
        if not 0.0 <= v < 90.0:
            bad(name, v, "must be in [0, 90) degrees")
    tphi = math.tan(math.radians(phi))
    tphir = math.tan(math.radians(phir))
    if ft > 0.0 and not c > ft * max(tphi, tphir):
        bad("cohesion", c, f"must exceed tensile_strength * tan(friction angle) = {ft * max(tphi, tphir)!r} "
            "(the tension cut-off must cut the Coulomb surface below its apex)")
    inv_su = 0.0
    if dilatancy_confinement is not None:
        su = _real("dilatancy_confinement", dilatancy_confinement)
        if not su > 0.0:
            bad("dilatancy_confinement", su, "must be > 0 (Pa, a compressive stress magnitude)")
        inv_su = 1.0 / su
    if dd < 0.0:
        bad("dilatancy_decay", dd, "must be >= 0 (1/m)")
    if tau_relax < 0.0:
        bad("relaxation_time", tau_relax, "must be >= 0 (s)")
    fc = 0.0
    gfc = 0.0
    kp = 0.0
    if compressive_strength is not None:
        fc = _real("compressive_strength", compressive_strength)
        if not fc > ft:
            bad("compressive_strength", fc, f"must exceed the tensile strength {ft!r} (a cap below the "
                "tensile strength)")
        if not css > 0.0:
            bad("cap_shear_factor", css, "must be > 0")
        if cap_fracture_energy is None:
            bad("cap_fracture_energy", None, "is required with a compressive_strength (J/m2)")
        gfc = _real("cap_fracture_energy", cap_fracture_energy)
        if not gfc > 0.0:
            bad("cap_fracture_energy", gfc, "must be > 0 (J/m2)")
        if cap_peak_plastic_strain is None:
            bad("cap_peak_plastic_strain", None, "is required with a compressive_strength (m)")
        kp = _real("cap_peak_plastic_strain", cap_peak_plastic_strain)
        if not kp > 0.0:
            bad("cap_peak_plastic_strain", kp, "must be > 0 (m)")
        tcorner = max(c - ft * min(tphi, tphir), 0.0)
        if not ft * ft + css * tcorner * tcorner < (fc / 7.0) ** 2:
            bad("compressive_strength", fc, "is too low: the residual cap (fc/7) must enclose the "
                "tension/shear corner (ft, c - ft tan(phi))")
    row = np.zeros(N_COMPOSITE_PARAMS, dtype=np.float64)
    row[P_KS] = ks
    row[P_KN] = kn
    row[P_KS2] = ks2
    row[P_TENSILE_STRENGTH] = ft
    row[P_GF_I] = gf1
    row[P_COHESION] = c
    row[P_TAN_PHI0] = tphi
    row[P_TAN_PHI_R] = tphir
    row[P_TAN_PSI0] = math.tan(math.radians(psi))
    row[P_INV_SIGMA_U] = inv_su
    row[P_DILATANCY_DECAY] = dd
    row[P_GF_II] = gf2
    row[P_FC] = fc
    row[P_CSS] = css
    row[P_GF_C] = gfc
    row[P_KAPPA_P] = kp
    row[P_OPEN_TANGENT] = 0.0
    row[P_RELAXATION_TIME] = tau_relax
    return row


def snap_back_length(params, youngs_modulus: float, shear_modulus: float) -> tuple[float, float]:
    """Largest length ``L`` of an elastic continuum (element length normal to the joint) in series
    with the joint for which the softening branch has no snap-back: ``(L_I, L_II)`` (m), for mode I
    and for mode II at zero normal stress.

    Derivation (mode I): a bar of length L and modulus E in series with the joint, loaded by a
    displacement u at its far end, carries the stress sigma = t_n. On the softening branch
    ``sigma = ft exp(-(ft/GfI) kappa1)`` and the joint opening is ``kappa1 + sigma/kn``, so
    ``u(sigma) = sigma L / E + sigma / kn - (GfI / ft) ln(sigma / ft)`` and
    ``du/dsigma = L/E + 1/kn - GfI / (ft sigma)``. The branch has no snap-back when
    ``du/dsigma <= 0`` for all ``0 < sigma <= ft``; the worst case is ``sigma = ft``::

        L_I = E (GfI / ft^2 - 1 / kn)

    i.e. the elastic energy per unit area stored at the peak, ``ft^2 L / (2E) + ft^2 / (2 kn)``, must
    not exceed ``GfI / 2`` (the exponential curve starts with the slope ``-ft^2/GfI``, twice that of a
    linear softening with the same energy). Mode II at zero normal stress is the same with
    ``(G, ks, c, GfII)``: ``L_II = G (GfII / c^2 - 1 / ks)``. Under a normal compression ``p`` the shear
    softening is steeper when ``tan(phi_r) < tan(phi0)`` and ``L_II`` smaller. A result 0.0 means that
    the joint alone snaps back (``GfI < ft^2 / kn``); ``inf`` means no softening (ft = 0 or c = 0).
    """
    row = np.asarray(params, dtype=np.float64).reshape(-1)
    if row.shape[0] != N_COMPOSITE_PARAMS:
        raise ValueError(f"params must be one row of {N_COMPOSITE_PARAMS} columns, got shape {np.shape(params)}")
    E = _real("youngs_modulus", youngs_modulus)
    G = _real("shear_modulus", shear_modulus)
    if not E > 0.0:
        raise ValueError(f"youngs_modulus must be > 0 (Pa), got {E!r}")
    if not G > 0.0:
        raise ValueError(f"shear_modulus must be > 0 (Pa), got {G!r}")
    ft = row[P_TENSILE_STRENGTH]
    c = row[P_COHESION]
    if ft > 0.0:
        l1 = max(E * (row[P_GF_I] / ft**2 - 1.0 / row[P_KN]), 0.0)
    else:
        l1 = math.inf
    if c > 0.0:
        l2 = max(G * (row[P_GF_II] / c**2 - 1.0 / row[P_KS]), 0.0)
    else:
        l2 = math.inf
    return l1, l2
