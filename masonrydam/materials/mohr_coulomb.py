"""Mohr-Coulomb joint law of Tzamtzis & Asteris (sec. 3.4, eqs. 11-12).

One numba kernel, :func:`mohr_coulomb_point`, evaluates the law at one integration point of a
zero-thickness interface, in 2D (2 local components ``[s, n]``) or 3D (3 components
``[s1, s2, n]``), on scalars; :func:`mohr_coulomb_update` is the same law on the arrays of one point
(parameter, displacement, state, traction and tangent vectors). Conventions (docs/architecture.md): ``delta`` is the relative displacement top minus
bottom in the local frame (m), the normal component ``delta_n`` is positive in opening; tractions
(Pa) are positive in tension, so the contact pressure is ``-t_n``; stiffnesses are per unit area (Pa/m).

Parameter vector (float64, ``N_JOINT_PARAMS``)::

    P_KS                 ks    elastic shear stiffness  (Pa/m), > 0       (Tzamtzis & Asteris eq. 11, k_sx = k_sy)
    P_KN                 kn    normal stiffness         (Pa/m), > 0       (Tzamtzis & Asteris eq. 11, k_nz)
    P_COHESION           c     cohesion (Pa), >= 0                        (Tzamtzis & Asteris eq. 12)
    P_TAN_PHI            tan(phi), >= 0                                   (Tzamtzis & Asteris eq. 12)
    P_TENSILE_STRENGTH   ft    bond tensile strength (Pa), >= 0 (0 = no-tension joint)
    P_KS_RESIDUAL        ks_r  residual shear stiffness while sliding (Pa/m), 0 <= ks_r < ks

State vector (float64, ``N_JOINT_STATE``, one row per integration point)::

    S_CODE          0 stick, 1 slip, 2 open (STICK / SLIP / OPEN)
    S_BOND_BROKEN   0 intact, 1 broken (the joint has opened once: it is a crack, c = ft = 0)
    S_PLASTIC_SLIP  2 columns: plastic (irreversible) shear slip (m); 2D uses the first column only
    S_BACK_STRESS   2 columns: kinematic-hardening back stress (Pa); 2D uses the first column only

Trial / commit / revert: the kernel reads ``state_committed`` (never writes it) and writes
``state_trial``; the solver copies trial to committed when a step converges.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..errors import STATUS_NAN, STATUS_OK

# parameter layout
P_KS = 0
P_KN = 1
P_COHESION = 2
P_TAN_PHI = 3
P_TENSILE_STRENGTH = 4
P_KS_RESIDUAL = 5
#: solver control, not a material property: the tangent of an OPEN point is
#: ``open_tangent * diag(ks, .., kn)`` while its tractions stay zero. 0 (default) is the consistent
#: tangent; the static solver raises it to 1 (initial stiffness for open points, the "stress
#: transfer" iteration of Zienkiewicz, Valliappan & King 1968, Geotechnique 18:56-66) for the rest
#: of a step in which Newton cycles between open and closed states.
P_OPEN_TANGENT = 6
N_JOINT_PARAMS = 7

# state layout
S_CODE = 0
S_BOND_BROKEN = 1
S_PLASTIC_SLIP = 2  # columns 2, 3
S_BACK_STRESS = 4  # columns 4, 5
N_JOINT_STATE = 6

# state codes
STICK = 0
SLIP = 1
OPEN = 2


@njit(cache=True, inline="always")
def mohr_coulomb_point(ks, kn, c, tan_phi, ft, ks_r, open_tangent, ns, d_s1, d_s2, d_n,
                       code0, broken0, slip1, slip2, back1, back2):
    """The law of :func:`mohr_coulomb_update` on scalars: the one implementation, shared by every caller.

    Why scalars: a caller that passes rows of its (points, ...) arrays as views pays a reference
    count per view and per point, which took several times the arithmetic of the law (joint-space
    law pass over 588 points: 52 us through views, against a few us on scalars; the arrays stay in
    the callers, which index them directly). Inlined into the callers (numba IR inlining).

    Inputs: the parameters ``ks, kn, c, tan_phi, ft, ks_r`` (Pa/m, Pa/m, Pa, -, Pa, Pa/m) and the
    open-point tangent factor (see ``P_OPEN_TANGENT``); ``ns`` = 1 (2D) or 2 (3D) shear components;
    the relative displacements ``d_s1, d_s2, d_n`` (m; ``d_s2`` ignored in 2D: pass 0); the
    committed state ``code0, broken0, slip1, slip2, back1, back2`` (the ``N_JOINT_STATE`` layout).

    Returns the tuple ``(status, code, broken, slip1, slip2, back1, back2, tau1, tau2, t_n,
    C11, C12, C21, C22, C1n, C2n, Cnn)``: the trial state in the state layout, the tractions (Pa;
    ``tau2`` is 0 in 2D) and the nonzero entries of the consistent tangent (Pa/m; the normal row is
    ``[0, .., Cnn]``; the ``2`` entries are 0 in 2D). After a non-finite input the status is
    ``STATUS_NAN``, the state is the committed one, the tractions NaN and the tangent zero.
    """
    nan = np.nan
    finite = (math.isfinite(ks) and math.isfinite(kn) and math.isfinite(c) and math.isfinite(tan_phi)
              and math.isfinite(ft) and math.isfinite(ks_r) and math.isfinite(open_tangent)
              and math.isfinite(d_s1) and math.isfinite(d_n) and (ns == 1 or math.isfinite(d_s2))
              and math.isfinite(code0) and math.isfinite(broken0) and math.isfinite(slip1)
              and math.isfinite(slip2) and math.isfinite(back1) and math.isfinite(back2))
    if not finite:
        return (STATUS_NAN, code0, broken0, slip1, slip2, back1, back2, nan, nan if ns == 2 else 0.0, nan,
                0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    if broken0 != 0.0:
        c_eff = 0.0
        ft_eff = 0.0
    else:
        c_eff = c
        ft_eff = ft
    t_n = kn * d_n

    # ---- separation: no traction, no stiffness (Tzamtzis & Asteris sec. 3.4); s_p := d_s, alpha := 0
    if d_n > 0.0 and t_n > ft_eff:
        f_ks = open_tangent * ks if open_tangent != 0.0 else 0.0
        f_kn = open_tangent * kn if open_tangent != 0.0 else 0.0
        return (STATUS_OK, float(OPEN), 1.0, d_s1, d_s2 if ns == 2 else 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                f_ks, 0.0, 0.0, f_ks if ns == 2 else 0.0, 0.0, 0.0, f_kn)

    # ---- contact: elastic trial
    tau_y = c_eff - t_n * tan_phi
    clamped = False
    if tau_y <= 0.0:
        tau_y = 0.0
        clamped = True
    if ks_r > 0.0:
        H = ks * ks_r / (ks - ks_r)
    else:
        H = 0.0
    # relative stress xi = tau_trial - alpha
    tau1 = ks * (d_s1 - slip1)
    xi1 = tau1 - back1
    xi_norm2 = 0.0 + xi1 * xi1
    tau2 = 0.0
    xi2 = 0.0
    if ns == 2:
        tau2 = ks * (d_s2 - slip2)
        xi2 = tau2 - back2
        xi_norm2 += xi2 * xi2
    xi_norm = math.sqrt(xi_norm2)
    f = xi_norm - tau_y

    code = float(STICK)
    C11 = ks
    C12 = 0.0
    C21 = 0.0
    C22 = ks if ns == 2 else 0.0
    C1n = 0.0
    C2n = 0.0
    if f > 0.0:
        # f > 0 and tau_y >= 0 imply xi_norm > 0
        code = float(SLIP)
        dl = f / (ks + H)
        a = ks * ks / (ks + H)
        b = ks * ks * dl / xi_norm
        m1 = xi1 / xi_norm
        slip1 = slip1 + dl * m1
        back1 = back1 + H * dl * m1
        C11 = ks * 1.0 - a * m1 * m1 - b * (1.0 - m1 * m1)
        if not clamped:
            C1n = -ks * kn * tan_phi / (ks + H) * m1
        if ns == 2:
            m2 = xi2 / xi_norm
            slip2 = slip2 + dl * m2
            back2 = back2 + H * dl * m2
            C12 = ks * 0.0 - a * m1 * m2 - b * (0.0 - m1 * m2)
            C21 = ks * 0.0 - a * m2 * m1 - b * (0.0 - m2 * m1)
            C22 = ks * 1.0 - a * m2 * m2 - b * (1.0 - m2 * m2)
            if not clamped:
                C2n = -ks * kn * tan_phi / (ks + H) * m2
            tau2 = tau2 - ks * dl * m2
        tau1 = tau1 - ks * dl * m1

    status = STATUS_OK
    if not (math.isfinite(tau1) and math.isfinite(tau2) and math.isfinite(t_n) and math.isfinite(C11)
            and math.isfinite(C12) and math.isfinite(C21) and math.isfinite(C22) and math.isfinite(C1n)
            and math.isfinite(C2n)):
        status = STATUS_NAN
    return (status, code, broken0, slip1, slip2, back1, back2, tau1, tau2, t_n, C11, C12, C21, C22, C1n, C2n, kn)


@njit(cache=True)
def write_trial(state_trial, traction, ns, code, broken, slip1, slip2, back1, back2, tau1, tau2, t_n):
    """Write the trial state and tractions returned by :func:`mohr_coulomb_point` into one point's
    ``state_trial`` (N_JOINT_STATE,) and ``traction`` (ns+1,) Pa."""
    state_trial[S_CODE] = code
    state_trial[S_BOND_BROKEN] = broken
    state_trial[S_PLASTIC_SLIP] = slip1
    state_trial[S_PLASTIC_SLIP + 1] = slip2
    state_trial[S_BACK_STRESS] = back1
    state_trial[S_BACK_STRESS + 1] = back2
    traction[0] = tau1
    if ns == 2:
        traction[1] = tau2
    traction[ns] = t_n


@njit(cache=True)
def write_tangent(tangent, ns, C11, C12, C21, C22, C1n, C2n, Cnn):
    """Write the tangent entries returned by :func:`mohr_coulomb_point` into ``tangent`` (ns+1, ns+1) Pa/m
    (zero elsewhere: the normal row is ``[0, .., Cnn]``)."""
    for i in range(ns + 1):
        for j in range(ns + 1):
            tangent[i, j] = 0.0
    tangent[0, 0] = C11
    tangent[0, ns] = C1n
    if ns == 2:
        tangent[0, 1] = C12
        tangent[1, 0] = C21
        tangent[1, 1] = C22
        tangent[1, ns] = C2n
    tangent[ns, ns] = Cnn


@njit(cache=True)
def mohr_coulomb_update(params, delta, state_committed, state_trial, traction, tangent):
    """Return-mapping update of the Mohr-Coulomb joint (Tzamtzis & Asteris) at one integration point.

    Parameters
    ----------
    params : float64 (N_JOINT_PARAMS,)
        ``[ks, kn, c, tan_phi, ft, ks_r]`` (see module docstring; units Pa/m, Pa/m, Pa, -, Pa, Pa/m).
    delta : float64 (ncomp,)
        Local relative displacement top minus bottom, ``[d_s1, (d_s2,) d_n]`` (m), ncomp = 2 or 3,
        opening positive.
    state_committed : float64 (N_JOINT_STATE,)
        Converged state of the last committed step; read only.
    state_trial : float64 (N_JOINT_STATE,), out
        Trial state for ``delta``.
    traction : float64 (ncomp,), out
        Local traction ``[tau_1, (tau_2,) t_n]`` (Pa), tension positive.
    tangent : float64 (ncomp, ncomp), out
        Consistent tangent ``d traction / d delta`` (Pa/m); non-symmetric while slipping.

    Returns
    -------
    int
        ``STATUS_OK`` (0), or ``STATUS_NAN`` if an input or output is not finite.

    Law (ns = ncomp - 1 shear components; d_s, tau, plastic slip s_p and back stress alpha are
    ns-vectors; with ks_r = 0 this is the elastic-perfectly-plastic joint of Tzamtzis & Asteris, Fig. 2)
    ----------------------------------------------------------------------------------------------
    Elastic trial (Tzamtzis & Asteris eq. 11, k = diag(ks, [ks,] kn)):
        t_n       = kn * d_n
        tau_trial = ks * (d_s - s_p)
    Bond: while intact ``c_eff = c``, ``ft_eff = ft``; once broken ``c_eff = ft_eff = 0``.
    Separation (Tzamtzis & Asteris sec. 3.4, stage 1: no tension, both stiffnesses zero):
        if d_n > 0 and kn * d_n > ft_eff:
            traction = 0, tangent = 0, code = OPEN, bond broken,
            s_p := d_s  (on re-closure the contact starts free of shear at the new position),
            alpha := 0.
        Contact (stage 2) is restored as soon as d_n <= 0 (or kn d_n <= ft_eff for an intact bond).
        The "new position" is that of the last *committed* open state (the trial state of a step
        that closes the joint starts from the committed s_p), so a joint that opens and closes
        within one step keeps its previous s_p.
    Mohr-Coulomb strength (Tzamtzis & Asteris eq. 12, sigma_n = -t_n the compressive stress):
        tau_y = max(c_eff - t_n tan(phi), 0) = max(c_eff + sigma_n tan(phi), 0)
    Residual shear stiffness (Tzamtzis & Asteris: "a reduced (or residual) shear stiffness is allocated to the
    joint" while sliding) as linear kinematic hardening of modulus
        H = ks ks_r / (ks - ks_r)     so that  ks H / (ks + H) = ks_r,
    yield function f = |xi| - tau_y with the relative stress xi = tau_trial - alpha.
    Stick (f <= 0):  tau = tau_trial;  tangent = diag(ks, [ks,] kn).
    Slip (f > 0), closest-point return mapping (Simo & Hughes 1998, Computational Inelasticity,
    sec. 2.3 / 3.3, radial return for a non-associated friction surface without dilatancy):
        dl    = f / (ks + H),   m = xi / |xi|
        tau   = tau_trial - ks dl m
        s_p  += dl m,           alpha += H dl m       (so that |tau - alpha| = tau_y)
    Consistent tangent (normal row ``[0, .., kn]``):
        d tau / d d_s = ks I - ks^2/(ks+H) m m^T - ks^2 dl/|xi| (I - m m^T)
        d tau / d d_n = -ks kn tan(phi)/(ks+H) m        (0 when tau_y is clamped at 0)
    While sliding monotonically the incremental shear stiffness is therefore ks_r; unloading is
    elastic with ks. The tangent is non-symmetric in slip (non-associated flow, no dilatancy, the
    normal displacement is unaffected by sliding).
    """
    ncomp = delta.shape[0]
    ns = ncomp - 1
    sc = state_committed
    (status, code, broken, slip1, slip2, back1, back2, tau1, tau2, t_n, C11, C12, C21, C22, C1n, C2n, Cnn) = \
        mohr_coulomb_point(params[P_KS], params[P_KN], params[P_COHESION], params[P_TAN_PHI],
                           params[P_TENSILE_STRENGTH], params[P_KS_RESIDUAL], params[P_OPEN_TANGENT], ns,
                           delta[0], delta[1] if ns == 2 else 0.0, delta[ns], sc[S_CODE], sc[S_BOND_BROKEN],
                           sc[S_PLASTIC_SLIP], sc[S_PLASTIC_SLIP + 1], sc[S_BACK_STRESS], sc[S_BACK_STRESS + 1])
    write_trial(state_trial, traction, ns, code, broken, slip1, slip2, back1, back2, tau1, tau2, t_n)
    if status != STATUS_OK and not math.isfinite(t_n):  # a non-finite input or t_n: NaN tractions, zero tangent
        write_tangent(tangent, ns, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        return status
    write_tangent(tangent, ns, C11, C12, C21, C22, C1n, C2n, Cnn)
    return status


def joint_params(
    normal_stiffness: float,
    shear_stiffness: float,
    cohesion: float = 0.0,
    friction_angle_deg: float = 30.0,
    tensile_strength: float = 0.0,
    residual_shear_stiffness: float = 0.0,
) -> np.ndarray:
    """Validated parameter vector for :func:`mohr_coulomb_update`.

    Parameters
    ----------
    normal_stiffness : kn (Pa/m), > 0.
    shear_stiffness : ks (Pa/m), > 0.
    cohesion : c (Pa), >= 0 (Tzamtzis & Asteris eq. 12).
    friction_angle_deg : phi in degrees, 0 <= phi < 90 (Tzamtzis & Asteris eq. 12). Default 30 deg.
    tensile_strength : ft (Pa), >= 0; 0 gives the no-tension joint of Tzamtzis & Asteris.
    residual_shear_stiffness : ks_r (Pa/m), 0 <= ks_r < ks; 0 gives elastic-perfectly-plastic sliding.

    Returns
    -------
    float64 ndarray (N_JOINT_PARAMS,) laid out as
    ``[ks, kn, c, tan(phi), ft, ks_r, open_tangent = 0]``.

    Raises
    ------
    ValueError naming the offending parameter and its value.
    """
    values = {
        "normal_stiffness": normal_stiffness,
        "shear_stiffness": shear_stiffness,
        "cohesion": cohesion,
        "friction_angle_deg": friction_angle_deg,
        "tensile_strength": tensile_strength,
        "residual_shear_stiffness": residual_shear_stiffness,
    }
    checked = {}
    for name, v in values.items():
        try:
            fv = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"joint parameter {name} must be a real number, got {v!r}") from None
        if not math.isfinite(fv):
            raise ValueError(f"joint parameter {name} must be finite, got {v!r}")
        checked[name] = fv
    kn = checked["normal_stiffness"]
    ks = checked["shear_stiffness"]
    c = checked["cohesion"]
    phi = checked["friction_angle_deg"]
    ft = checked["tensile_strength"]
    ks_r = checked["residual_shear_stiffness"]
    if kn <= 0.0:
        raise ValueError(f"joint parameter normal_stiffness must be > 0 (Pa/m), got {kn!r}")
    if ks <= 0.0:
        raise ValueError(f"joint parameter shear_stiffness must be > 0 (Pa/m), got {ks!r}")
    if c < 0.0:
        raise ValueError(f"joint parameter cohesion must be >= 0 (Pa), got {c!r}")
    if not 0.0 <= phi < 90.0:
        raise ValueError(f"joint parameter friction_angle_deg must be in [0, 90) degrees, got {phi!r}")
    if ft < 0.0:
        raise ValueError(f"joint parameter tensile_strength must be >= 0 (Pa), got {ft!r}")
    if not 0.0 <= ks_r < ks:
        raise ValueError(
            f"joint parameter residual_shear_stiffness must satisfy 0 <= ks_r < shear_stiffness = {ks!r}, "
            f"got {ks_r!r}"
        )
    p = np.zeros(N_JOINT_PARAMS, dtype=np.float64)
    p[P_KS] = ks
    p[P_KN] = kn
    p[P_COHESION] = c
    p[P_TAN_PHI] = math.tan(math.radians(phi))
    p[P_TENSILE_STRENGTH] = ft
    p[P_KS_RESIDUAL] = ks_r
    return p
