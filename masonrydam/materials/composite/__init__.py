"""The composite ("interface cap") joint law for masonry of Lourenco & Rots, split by what its parts do.

[LR97] P. B. Lourenco, J. G. Rots (1997), "Multisurface interface model for analysis of masonry structures",
J. Eng. Mech. 123(7), 660-668, eqs. 1-9; [L96] P. B. Lourenco (1996), "Computational strategies for masonry
structures", PhD thesis, TU Delft, ch. 4. Three surfaces: a tension cut-off with exponential softening, Coulomb
friction with cohesion softening and dilatancy, and a compression cap; an implicit multisurface return with a
consistent (non-symmetric) tangent, in 2D and 3D. The law in equations, where it simplifies the thesis and how
its return works: docs/masonry_softening.md ("The law in equations").

Conventions (docs/architecture.md): ``delta`` is the relative displacement top minus bottom in the local frame
``[s, n]`` (2D) or ``[s1, s2, n]`` (3D), opening positive (m); tractions ``[tau, (tau2,) t_n]`` are positive
in tension (Pa); stiffnesses are per unit area (Pa/m). The kernels read ``state_committed`` (never write it)
and write ``state_trial``.

Modules:

- ``columns``: the parameter and state rows (columns, names, state codes), the constants of a plastic point;
- ``parameters``: the validated parameter row (:func:`composite_params`), the kernel's check of a row, the
  longest element that softens without snap-back (:func:`snap_back_length`);
- ``compression_cap``: the cap strength ``sigma3(kappa3)`` and the fully softened start of a cap return;
- ``local_system``: the three yield surfaces and the residual of the local system of an active set;
- ``dense_lu``: LU factorisation and solve of the 5x5 local system;
- ``local_newton``: Newton's method on the local system and the admissibility of a return;
- ``viscous_regularisation``: the Duvaut-Lions relaxation towards the inviscid return;
- ``point_law``: :func:`composite_point`, the law at one point (elastic trial, the search over the return
  regions and corners, the consistent tangent), inlined into the interface kernels;
- ``batch``: :func:`composite_update` over rows, its Python wrapper :func:`composite_evaluate`, the virgin
  state :func:`composite_initial_state`.
"""
from __future__ import annotations

from .batch import composite_evaluate, composite_initial_state, composite_update
from .columns import (CAP, CAP_SOFTENING_FACTOR, ELASTIC, N_COMPOSITE_PARAMS, N_COMPOSITE_STATE, P_COHESION, P_CSS,
                      P_DILATANCY_DECAY, P_FC, P_GF_C, P_GF_I, P_GF_II, P_INV_SIGMA_U, P_KAPPA_P, P_KN, P_KS, P_KS2,
                      P_OPEN_TANGENT, P_RELAXATION_TIME, P_TAN_PHI0, P_TAN_PHI_R, P_TAN_PSI0, P_TENSILE_STRENGTH,
                      P_TIME_STEP, PARAM_NAMES, S_CODE, S_CRACKED, S_KAPPA1, S_KAPPA2, S_KAPPA3, S_PLASTIC_OPENING,
                      S_PLASTIC_SLIP, SHEAR, SHEAR_CAP, TENSION, TENSION_SHEAR)
from .parameters import composite_params, snap_back_length
from .point_law import composite_point

__all__ = [
    "CAP", "CAP_SOFTENING_FACTOR", "ELASTIC", "N_COMPOSITE_PARAMS", "N_COMPOSITE_STATE", "P_COHESION", "P_CSS",
    "P_DILATANCY_DECAY", "P_FC", "P_GF_C", "P_GF_I", "P_GF_II", "P_INV_SIGMA_U", "P_KAPPA_P", "P_KN", "P_KS",
    "P_KS2", "P_OPEN_TANGENT", "P_RELAXATION_TIME", "P_TAN_PHI0", "P_TAN_PHI_R", "P_TAN_PSI0",
    "P_TENSILE_STRENGTH", "P_TIME_STEP", "PARAM_NAMES", "S_CODE", "S_CRACKED", "S_KAPPA1", "S_KAPPA2", "S_KAPPA3",
    "S_PLASTIC_OPENING", "S_PLASTIC_SLIP", "SHEAR", "SHEAR_CAP", "TENSION", "TENSION_SHEAR",
    "composite_evaluate", "composite_initial_state", "composite_params", "composite_point", "composite_update",
    "snap_back_length",
]
