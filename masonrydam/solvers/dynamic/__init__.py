"""Dynamics (a room of :mod:`masonrydam.solvers`): integrators, the joint-space step, mass, damping and modes.

- :mod:`.integration`: the dynamic stages (:class:`~.integration.DynamicStage`, :class:`~.integration.DynamicSolver`):
  Newmark, HHT, generalized-alpha and central difference, error-controlled steps, the energy balance;
- :mod:`.kernels`: the numba kernels of a step (Newmark kinematics and residual, energies, small dense LU);
- :mod:`.joint_space` and :mod:`.joint_space_kernels`: a step condensed on the nonlinear joints' relative
  displacements (also used by the static stepping);
- :mod:`.modal`: mass and Rayleigh damping matrices, elastic tangents and the modal stage;
- :mod:`.fluid`: the compressible reservoir's acoustic step condensed on the wetted face.

Imports the linear room; does not import the static one.
"""
