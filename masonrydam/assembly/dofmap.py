"""Degree-of-freedom map: node-major numbering, supports and prescribed displacements."""
from __future__ import annotations

import numpy as np

COMPONENTS = {"x": 0, "y": 1, "z": 2}


class DofMap:
    """DOFs ``node * dim + component``; constrained DOFs carry a prescribed value (m).

    Attributes: dim, n_nodes, n_dof, constrained (n_dof,) bool, eq_of_dof (n_dof,) int64
    (-1 for constrained), free (n_eq,) int64, n_eq.
    """

    def __init__(self, n_nodes: int, dim: int, constrained: np.ndarray):
        self.dim, self.n_nodes = dim, n_nodes
        self.n_dof = n_nodes * dim
        self.constrained = np.asarray(constrained, dtype=bool).copy()
        self.free = np.nonzero(~self.constrained)[0]
        self.fixed = np.nonzero(self.constrained)[0]
        self.n_eq = len(self.free)
        self.eq_of_dof = np.full(self.n_dof, -1, dtype=np.int64)
        self.eq_of_dof[self.free] = np.arange(self.n_eq)

    @staticmethod
    def node_dofs(nodes: np.ndarray, dim: int) -> np.ndarray:
        """(n, nen) node indices -> (n, nen*dim) DOFs, node-major."""
        nodes = np.asarray(nodes, dtype=np.int64)
        return (nodes[..., None] * dim + np.arange(dim)).reshape(nodes.shape[0], -1)
