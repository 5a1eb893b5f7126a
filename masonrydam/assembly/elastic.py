"""Elastic tangents: the stiffness with every joint point sticking (the initial, elastic joint stiffness).

:func:`elastic_tangent_data` gives its free-DOF values in the model's CSR pattern (the reference matrix of the
joint-space condensation and of the dynamic solver's effective matrix), :func:`elastic_joint_full` the full-DOF
joint part (N/m; Rayleigh damping with ``exclude_joints = false``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .sparsity import full_matrix, scatter_matrix


def _elastic_joint_parts(model):
    """Element stiffness matrices of every interface group with every point sticking (the initial,
    elastic joint stiffness: :meth:`~masonrydam.assembly.groups.InterfaceGroup.elastic_tangents`, the law at
    rest from its ``JointLaw.elastic_parameters`` and zero states); the groups' own states are not touched."""
    return [(g, g.elastic_tangents(model.coords, model.n_dof)) for g in model.igroups]


def elastic_tangent_data(model) -> np.ndarray:
    """Free-DOF values (model pattern) of the tangent with every joint point sticking.

    Summed in the same order as :meth:`Model.evaluate` (continuum values, then each interface group
    scattered in turn), so that a tangent evaluated with all joints sticking is bitwise equal to it.
    """
    data = model.elastic_continuum_data().copy()
    for g, ke in _elastic_joint_parts(model):
        scatter_matrix(ke, g.scatter, data)
    return data


def elastic_joint_full(model) -> sp.csr_matrix:
    """Full-DOF elastic (all sticking) joint stiffness (N/m)."""
    return full_matrix(model.n_dof, [(g.dofs, ke) for g, ke in _elastic_joint_parts(model)])
