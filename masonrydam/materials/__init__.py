"""Material models of masonrydam.

- :mod:`masonrydam.materials.elastic`: linear isotropic elasticity matrices (plane stress,
  plane strain, 3D) for the continuum blocks.
- :mod:`masonrydam.materials.mohr_coulomb`: the seed's joint law (stick, slip, open) for interfaces.
- :mod:`masonrydam.materials.von_mises`, :mod:`masonrydam.materials.drucker_prager` (with shared
  helpers in :mod:`masonrydam.materials.plasticity`): continuum plasticity with hardening and
  softening, implicit return mapping, consistent tangent and optional Perzyna viscosity, as
  point-level kernels (plane strain and 3D). Not yet called by the continuum elements: the element
  integration and the scene keys (``[materials.<group>] law = ...``) are the next step of issue 17.

Kernels follow the conventions of ``docs/architecture.md`` (SI units, engineering shear strains).
"""
