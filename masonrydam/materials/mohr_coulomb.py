"""Mohr-Coulomb joint law of the seed paper (Tzamtzis & Asteris, sec. 3.4, eqs. 11-12).

One numba kernel, :func:`mohr_coulomb_update`, evaluates the law at one integration point of a
zero-thickness interface, in 2D (2 local components ``[s, n]``) or 3D (3 components
``[s1, s2, n]``). Conventions (docs/architecture.md): ``delta`` is the relative displacement top minus
bottom in the local frame (m), the normal component ``delta_n`` is positive in opening; tractions
(Pa) are positive in tension, so the contact pressure is ``-t_n``; stiffnesses are per unit area (Pa/m).

Parameter vector (float64, ``N_JOINT_PARAMS``)::

    P_KS                 ks    elastic shear stiffness  (Pa/m), > 0       (seed eq. 11, k_sx = k_sy)
    P_KN                 kn    normal stiffness         (Pa/m), > 0       (seed eq. 11, k_nz)
    P_COHESION           c     cohesion (Pa), >= 0                        (seed eq. 12)
    P_TAN_PHI            tan(phi), >= 0                                   (seed eq. 12)
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


# inlined into its callers (numba IR inlining): the call with six array arguments cost as much as the
# law itself; inlined, the joint-space law pass over 588 points took 24 us instead of 43 us
# (interleaved timing, min of 60 blocks)
@njit(cache=True, inline="always")
def mohr_coulomb_update(params, delta, state_committed, state_trial, traction, tangent):
    """Return-mapping update of the seed's Mohr-Coulomb joint at one integration point.

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
    ns-vectors; with ks_r = 0 this is the elastic-perfectly-plastic joint of the seed, Fig. 2)
    ----------------------------------------------------------------------------------------------
    Elastic trial (seed eq. 11, k = diag(ks, [ks,] kn)):
        t_n       = kn * d_n
        tau_trial = ks * (d_s - s_p)
    Bond: while intact ``c_eff = c``, ``ft_eff = ft``; once broken ``c_eff = ft_eff = 0``.
    Separation (seed sec. 3.4, stage 1: no tension, both stiffnesses zero):
        if d_n > 0 and kn * d_n > ft_eff:
            traction = 0, tangent = 0, code = OPEN, bond broken,
            s_p := d_s  (on re-closure the contact starts free of shear at the new position),
            alpha := 0.
        Contact (stage 2) is restored as soon as d_n <= 0 (or kn d_n <= ft_eff for an intact bond).
        The "new position" is that of the last *committed* open state (the trial state of a step
        that closes the joint starts from the committed s_p), so a joint that opens and closes
        within one step keeps its previous s_p.
    Mohr-Coulomb strength (seed eq. 12, sigma_n = -t_n the compressive stress):
        tau_y = max(c_eff - t_n tan(phi), 0) = max(c_eff + sigma_n tan(phi), 0)
    Residual shear stiffness (seed: "a reduced (or residual) shear stiffness is allocated to the
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

    # copy the committed state into the trial state first (the law then edits the trial copy)
    for k in range(state_committed.shape[0]):
        state_trial[k] = state_committed[k]
    for i in range(ncomp):
        traction[i] = 0.0
        for j in range(ncomp):
            tangent[i, j] = 0.0

    finite = True
    for k in range(params.shape[0]):
        if not math.isfinite(params[k]):
            finite = False
    for k in range(ncomp):
        if not math.isfinite(delta[k]):
            finite = False
    for k in range(state_committed.shape[0]):
        if not math.isfinite(state_committed[k]):
            finite = False
    if not finite:
        for i in range(ncomp):
            traction[i] = np.nan
        return STATUS_NAN

    ks = params[P_KS]
    kn = params[P_KN]
    c = params[P_COHESION]
    tan_phi = params[P_TAN_PHI]
    ft = params[P_TENSILE_STRENGTH]
    ks_r = params[P_KS_RESIDUAL]

    broken = state_committed[S_BOND_BROKEN] != 0.0
    if broken:
        c_eff = 0.0
        ft_eff = 0.0
    else:
        c_eff = c
        ft_eff = ft

    d_n = delta[ns]
    t_n = kn * d_n

    # ---- separation: no traction, no stiffness (seed sec. 3.4)
    if d_n > 0.0 and t_n > ft_eff:
        state_trial[S_CODE] = OPEN
        state_trial[S_BOND_BROKEN] = 1.0
        for k in range(2):
            state_trial[S_PLASTIC_SLIP + k] = 0.0
            state_trial[S_BACK_STRESS + k] = 0.0
        for k in range(ns):
            state_trial[S_PLASTIC_SLIP + k] = delta[k]
        f_open = params[P_OPEN_TANGENT]
        if f_open != 0.0:
            for k in range(ns):
                tangent[k, k] = f_open * ks
            tangent[ns, ns] = f_open * kn
        return STATUS_OK

    # ---- contact: elastic trial
    traction[ns] = t_n
    tangent[ns, ns] = kn
    tau_y = c_eff - t_n * tan_phi
    clamped = False
    if tau_y <= 0.0:
        tau_y = 0.0
        clamped = True
    if ks_r > 0.0:
        H = ks * ks_r / (ks - ks_r)
    else:
        H = 0.0

    # relative stress xi = tau_trial - alpha; tau_trial stored in traction[:ns]
    xi_norm2 = 0.0
    for k in range(ns):
        tau_tr = ks * (delta[k] - state_committed[S_PLASTIC_SLIP + k])
        traction[k] = tau_tr
        xi = tau_tr - state_committed[S_BACK_STRESS + k]
        xi_norm2 += xi * xi
    xi_norm = math.sqrt(xi_norm2)
    f = xi_norm - tau_y

    if f <= 0.0:
        state_trial[S_CODE] = STICK
        for k in range(ns):
            tangent[k, k] = ks
    else:
        # f > 0 and tau_y >= 0 imply xi_norm > 0
        state_trial[S_CODE] = SLIP
        dl = f / (ks + H)
        a = ks * ks / (ks + H)
        b = ks * ks * dl / xi_norm
        for k in range(ns):
            mk = (traction[k] - state_committed[S_BACK_STRESS + k]) / xi_norm
            state_trial[S_PLASTIC_SLIP + k] = state_committed[S_PLASTIC_SLIP + k] + dl * mk
            state_trial[S_BACK_STRESS + k] = state_committed[S_BACK_STRESS + k] + H * dl * mk
        for k in range(ns):
            mk = (traction[k] - state_committed[S_BACK_STRESS + k]) / xi_norm
            for j in range(ns):
                mj = (traction[j] - state_committed[S_BACK_STRESS + j]) / xi_norm
                delta_kj = 1.0 if k == j else 0.0
                tangent[k, j] = ks * delta_kj - a * mk * mj - b * (delta_kj - mk * mj)
            if not clamped:
                tangent[k, ns] = -ks * kn * tan_phi / (ks + H) * mk
        # traction update last (m above is computed from the trial traction)
        for k in range(ns):
            mk = (traction[k] - state_committed[S_BACK_STRESS + k]) / xi_norm
            traction[k] = traction[k] - ks * dl * mk

    for i in range(ncomp):
        if not math.isfinite(traction[i]):
            return STATUS_NAN
        for j in range(ncomp):
            if not math.isfinite(tangent[i, j]):
                return STATUS_NAN
    return STATUS_OK


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
    cohesion : c (Pa), >= 0 (seed eq. 12).
    friction_angle_deg : phi in degrees, 0 <= phi < 90 (seed eq. 12). Default 30 deg.
    tensile_strength : ft (Pa), >= 0; 0 gives the seed's no-tension joint.
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
