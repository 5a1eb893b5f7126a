"""The parameter row of the composite joint law: the validated builder, the kernel's check of a row, and
the longest element that softens without snap-back.

:func:`composite_params` returns one float64 row (``N_COMPOSITE_PARAMS``; columns in
:mod:`~masonrydam.materials.composite.columns`) from SI values (Pa, Pa/m, J/m2, m, s; angles in degrees).
Parameters and their admissible ranges after Lourenco & Rots (1997), J. Eng. Mech. 123(7) 660-668, and
Lourenco (1996), PhD thesis, TU Delft, ch. 4.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..plasticity import real_parameter
from .columns import (N_COMPOSITE_PARAMS, P_COHESION, P_CSS, P_DILATANCY_DECAY, P_FC, P_GF_C, P_GF_I, P_GF_II,
                      P_INV_SIGMA_U, P_KAPPA_P, P_KN, P_KS, P_KS2, P_OPEN_TANGENT, P_RELAXATION_TIME, P_TAN_PHI0,
                      P_TAN_PHI_R, P_TAN_PSI0, P_TENSILE_STRENGTH, P_TIME_STEP)


@njit(cache=True)
def first_bad_column(params, p):
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
    relaxation_time : tau (s) >= 0 of the Duvaut-Lions viscous regularisation (:func:`duvaut_lions_relaxation`);
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
