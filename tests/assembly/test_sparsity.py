"""The node-pair sparsity route gives exactly the DOF-pair route's pattern and scatter maps, with
supports that constrain some components of some nodes (the node route's offsets depend on them)."""
from __future__ import annotations

import numpy as np
import pytest

from masonrydam.assembly.dofmap import DofMap
from masonrydam.assembly.sparsity import _build_pattern_dofs, _build_pattern_nodal, build_pattern


@pytest.mark.parametrize("dim", [2, 3])
def test_nodal_route_equals_dof_route(dim):
    rng = np.random.default_rng(3)
    n_nodes = 60
    groups = [rng.integers(0, n_nodes, size=(40, 4)), rng.integers(0, n_nodes, size=(25, 8))]
    # make every node used and avoid repeated nodes within an element
    groups = [np.array([rng.permutation(n_nodes)[:g.shape[1]] for _ in range(len(g))]) for g in groups]
    groups.append(np.arange(n_nodes).reshape(-1, 4))
    constrained = rng.random(n_nodes * dim) < 0.2
    dm = DofMap(n_nodes, dim, constrained)
    dofs = [DofMap.node_dofs(g, dim) for g in groups]
    a = _build_pattern_dofs(dofs, dm.eq_of_dof, dm.n_eq)
    b = _build_pattern_nodal(dofs, dm.eq_of_dof, dm.n_eq, dim)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    for sa, sb in zip(a[2], b[2]):
        np.testing.assert_array_equal(sa, sb)
    # the public entry point takes the node route for node-major DOFs
    c = build_pattern(dofs, dm.eq_of_dof, dm.n_eq, dim=dim)
    np.testing.assert_array_equal(c[1], a[1])
