"""Dynamics (a room of :mod:`masonrydam.solvers`): time integration of dynamic stages, modes, the acoustic reservoir.

- :mod:`.schemes`: the integrators as one table (:data:`SCHEMES`: parameters, stability bound, error
  constant, display name);
- :mod:`.settings`: a stage's settings (:class:`DynamicSettings`); :mod:`.ground_motion`: a ground acceleration
  record (:class:`GroundMotion`); :mod:`.stage`: the stage, its effects' linear terms, its states and the counts
  of a run (:class:`DynamicStage`, :class:`DynamicTerms`, :class:`DynamicState`, :class:`DynamicStats`);
- :mod:`.solver`: :class:`DynamicSolver`, which sets up a stage and drives :mod:`.equations` (mass, damping,
  loads of the stage), :mod:`.stability` (the critical step), :mod:`.energy` (the energy balance,
  :func:`energy_warnings`), :mod:`.step_control` (fixed and error-controlled steps), :mod:`.implicit` (one
  implicit step: joint-space start, Newton) with :mod:`.effective` (the effective-matrix solver) and
  :mod:`.explicit` (central difference);
- :mod:`.kernels`: the numba kernels of a step (Newmark kinematics and residual, works and energies);
- :mod:`.modal`: the modal stage and modal analysis (uncoupled and coupled with a compressible reservoir);
- :mod:`.fluid`: the compressible reservoir's acoustic step condensed on the wetted face.

The theory and its references are in docs/dynamics.md. Code above the solvers imports the names below from
this package, not from its modules. The mass, Rayleigh damping and elastic tangents are assembly's
(:mod:`masonrydam.assembly`); the joint-space condensation is :mod:`masonrydam.solvers.joint_space` and the
Newton parts shared with the static stepping are :mod:`masonrydam.solvers.newton`. Imports the linear and
joint-space rooms; not the static one.
"""
from .energy import ENERGY_KEYS, energy_warnings
from .fluid import AcousticStep, FluidState
from .ground_motion import GroundMotion
from .modal import ModalResult, ModalStage, coupled_modal_analysis, modal_analysis
from .schemes import INTEGRATORS, SCHEMES, Scheme, scheme_named
from .settings import ADAPTIVE_DEFAULT_LEVELS, JOINT_SPACE_MODES, DynamicSettings
from .solver import DynamicSolver
from .stability import critical_time_step
from .stage import DynamicStage, DynamicState, DynamicStats, DynamicTerms

__all__ = ["ADAPTIVE_DEFAULT_LEVELS", "ENERGY_KEYS", "INTEGRATORS", "JOINT_SPACE_MODES", "SCHEMES", "AcousticStep",
           "DynamicSettings", "DynamicSolver", "DynamicStage", "DynamicState", "DynamicStats", "DynamicTerms",
           "FluidState", "GroundMotion", "ModalResult", "ModalStage", "Scheme", "coupled_modal_analysis",
           "critical_time_step", "energy_warnings", "modal_analysis", "scheme_named"]
