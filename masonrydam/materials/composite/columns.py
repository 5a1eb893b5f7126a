"""The rows of the composite joint law: parameter and state columns, state codes, and the constants
vector ``w`` of a plastic point.

Parameter row (float64, ``N_COMPOSITE_PARAMS``; built by
:func:`~masonrydam.materials.composite.parameters.composite_params`)::

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
    P_RELAXATION_TIME      17  tau (s) of the Duvaut-Lions regularisation, 0: inviscid (viscous_regularisation.py)
    P_TIME_STEP            18  the evaluation's time step dt (s), written by the assembly before each
                               evaluation (not a material constant)

State row (float64, ``N_COMPOSITE_STATE``)::

    S_CODE              0  ELASTIC 0, SHEAR 1, TENSION 2, CAP 3, TENSION_SHEAR 4, SHEAR_CAP 5
    S_CRACKED           1  1.0 once kappa1 > 0 or kappa2 > 0 (same column as mohr_coulomb.S_BOND_BROKEN)
    S_PLASTIC_SLIP      2  2 columns: plastic shear displacement (m) (2D uses the first)
    S_PLASTIC_OPENING   4  plastic normal displacement (m), opening positive
    S_KAPPA1            5  kappa1 (m)
    S_KAPPA2            6  kappa2 (m)
    S_KAPPA3            7  kappa3 (m)

Symbols as in Lourenco & Rots (1997), J. Eng. Mech. 123(7) 660-668, eqs. 1-9, and
docs/masonry_softening.md ("The law in equations").
"""
from __future__ import annotations

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

#: km - kp = CAP_SOFTENING_FACTOR * Gfc / fc (docs/masonry_softening.md, "The law in equations")
CAP_SOFTENING_FACTOR = 588.0 / 481.0

# ---- the constants vector ``w`` (float64, W_SIZE) of a plastic point: filled once per point by
# point_law.composite_point, read by the local system and the cap start
W_KN = 0  # kn (Pa/m)
W_KS1 = 1  # ks1 (Pa/m)
W_KS2 = 2  # ks2 (Pa/m)
W_FT = 3  # ft (Pa)
W_A1 = 4  # ft / GfI (1/m): the rate of kappa1 in the shared softening exponent
W_C = 5  # c (Pa)
W_A2 = 6  # c / GfII (1/m): the rate of kappa2 in the shared softening exponent
W_TPHI0 = 7  # tan(phi0)
W_TPHIR = 8  # tan(phi_r)
W_TPSI0 = 9  # tan(psi0)
W_INVSU = 10  # 1 / sigma_u (1/Pa)
W_DD = 11  # delta_d, the decay of the dilatancy with the slip (1/m)
W_FC = 12  # fc (Pa); 0: no cap
W_CSS = 13  # Css (0 without a cap)
W_KP = 14  # kp, the plastic relative displacement at the cap peak (m)
W_DKM = 15  # km - kp (m)
W_KAP1 = 16  # committed kappa1 (m)
W_KAP2 = 17  # committed kappa2 (m)
W_KAP3 = 18  # committed kappa3 (m)
W_SIZE = 19
