"""Material models of masonrydam.

- :mod:`masonrydam.materials.elastic`: linear isotropic elasticity matrices (plane stress,
  plane strain, 3D) for the continuum blocks.

Kernels follow the conventions of ``docs/architecture.md`` (SI units, engineering shear strains).
"""
