"""Material models of masonrydam.

- :mod:`masonrydam.materials.elastic`: linear isotropic elasticity matrices (plane stress,
  plane strain, 3D) for the continuum blocks.
- :mod:`masonrydam.materials.mohr_coulomb`: the joint law of Tzamtzis & Asteris (stick, slip, open) for interfaces.
- :mod:`masonrydam.materials.von_mises`, :mod:`masonrydam.materials.tresca`,
  :mod:`masonrydam.materials.drucker_prager`, :mod:`masonrydam.materials.mohr_coulomb_solid` (with shared
  helpers in :mod:`masonrydam.materials.plasticity` and, for the principal-space returns of Tresca and
  Mohr-Coulomb, :mod:`masonrydam.materials.principal_return`): continuum plasticity with hardening and
  softening, implicit return mapping, consistent tangent and optional Perzyna viscosity, as point-level
  kernels (plane strain and 3D), integrated by :mod:`masonrydam.elements.continuum_plastic` for the
  scene's ``[materials.<group>] law = ...`` (docs/continuum_nonlinearity.md).

Kernels follow the conventions of ``docs/architecture.md`` (SI units, engineering shear strains).
"""
