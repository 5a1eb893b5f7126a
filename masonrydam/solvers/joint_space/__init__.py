"""Joint space (a room of :mod:`masonrydam.solvers`): a Newton step condensed on the relative displacements of
the nonlinear joint points, used by the static stepping and the implicit dynamic step alike.

- :mod:`.condensation`: the condensed system (:class:`JointSpace`), the flexibility columns
  (:class:`FlexibilityColumns`, dense up to :data:`JOINT_SPACE_MAX` joint unknowns, lazily above), the joint
  operator ``B`` and the capacitance LU; the theory is in that module's docstring;
- :mod:`.kernels`: its numba kernels (joint law at the points, condensed residual, capacitance assembly and
  updates, recovery of the displacements).

Imports the linear room (:mod:`masonrydam.solvers.linear.dense_lu`, ``ldlt_kernels``); imports neither the static
nor the dynamic room.
"""
from .condensation import (JOINT_SPACE_MAX, MAX_INITIAL_STIFFNESS_ITERATIONS, MAX_JOINT_SPACE_ITERATIONS,
                           SPLIT_INITIAL_STIFFNESS_ITERATIONS, ColumnStoreFull, FlexibilityColumns, JointSpace,
                           capacitance_lu, joint_operator, joint_space_size, lazy_flexibility)

__all__ = ["JOINT_SPACE_MAX", "MAX_INITIAL_STIFFNESS_ITERATIONS", "MAX_JOINT_SPACE_ITERATIONS",
           "SPLIT_INITIAL_STIFFNESS_ITERATIONS", "ColumnStoreFull", "FlexibilityColumns", "JointSpace",
           "capacitance_lu", "joint_operator", "joint_space_size", "lazy_flexibility"]
