"""Linear solvers (a room of :mod:`masonrydam.solvers`): factorizations and iterative solvers of the tangent.

- :mod:`.direct`: sparse direct factorizations (MKL PARDISO through pypardiso, SciPy SuperLU), their choice
  (``make_solver``, ``resolve_backend``) and reuse of the symbolic analysis;
- :mod:`.iterative`: preconditioned conjugate gradients with smoothed-aggregation AMG (pyamg) and the rigid-body
  modes it needs, for large 3D models;
- :mod:`.ldlt_kernels`: numba forward/backward substitutions of an LDL^T factor;
- :mod:`.dense_lu`: numba LU of small dense matrices and the low-rank (Woodbury) update of a reference solve;
- :mod:`.common`: the singular-matrix exception both raise.

Nothing here imports the other solver rooms.
"""
