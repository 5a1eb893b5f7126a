"""Dynamics (a room of :mod:`masonrydam.solvers`): time integration of dynamic stages, modes, the acoustic reservoir.

- :mod:`.integration`: the dynamic stages (:class:`DynamicStage`, :class:`DynamicSolver`): Newmark, HHT,
  generalized-alpha and central difference, error-controlled steps, the energy balance;
- :mod:`.kernels`: the numba kernels of a step (Newmark kinematics and residual, works and energies);
- :mod:`.modal`: the modal stage and modal analysis (uncoupled and coupled with a compressible reservoir);
- :mod:`.fluid`: the compressible reservoir's acoustic step condensed on the wetted face.

Code above the solvers imports the names below from this package, not from its modules. The mass, Rayleigh
damping and elastic tangents are assembly's (:mod:`masonrydam.assembly`); the joint-space condensation is
:mod:`masonrydam.solvers.joint_space`. Imports the linear and joint-space rooms; not the static one.
"""
from .fluid import AcousticStep, FluidState
from .integration import (ADAPTIVE_DEFAULT_LEVELS, INTEGRATORS, JOINT_SPACE_MODES, DynamicSettings, DynamicSolver,
                          DynamicStage, DynamicState, DynamicStats, DynamicTerms, GroundMotion, critical_time_step,
                          energy_warnings)
from .modal import ModalResult, ModalStage, coupled_modal_analysis, modal_analysis

__all__ = ["ADAPTIVE_DEFAULT_LEVELS", "INTEGRATORS", "JOINT_SPACE_MODES", "AcousticStep", "DynamicSettings",
           "DynamicSolver", "DynamicStage", "DynamicState", "DynamicStats", "DynamicTerms", "FluidState",
           "GroundMotion", "ModalResult", "ModalStage", "coupled_modal_analysis", "critical_time_step",
           "energy_warnings", "modal_analysis"]
