"""Elastic tangents: the stiffness with every joint point sticking (the initial, elastic joint stiffness).

:func:`elastic_tangent_data` gives its free-DOF values in the model's CSR pattern (the reference matrix of the
joint-space condensation and of the dynamic solver's effective matrix), :func:`elastic_joint_full` the full-DOF
joint part (N/m; Rayleigh damping with ``exclude_joints = false``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..elements import interface as ik
from ..materials import mohr_coulomb as mc
from .groups import raise_for_status
from .sparsity import full_matrix, scatter_matrix


def _elastic_joint_parts(model):
    """Element stiffness matrices of every interface group with every point sticking (the initial,
    elastic joint stiffness), from a copy of the parameters with unbreakable bonds and zero states;
    the groups' own states are not touched."""
    parts = []
    for g in model.igroups:
        params = g.params_table.copy()
        if g.law != "composite":  # (the composite law is elastic at zero displacement from a virgin state)
            params[:, mc.P_COHESION] = 1e300
            params[:, mc.P_TENSILE_STRENGTH] = 1e300
        params[:, g.open_tangent_column] = 0.0
        zeros = np.zeros_like(g.state_committed)
        trial = np.zeros_like(g.state_committed)
        delta, traction = np.zeros_like(g.delta), np.zeros_like(g.traction)
        fe, ke = np.zeros_like(g.fe), np.zeros_like(g.ke)
        info = np.zeros(1, dtype=np.int64)
        st = ik.interface_evaluate(model.coords, g.conn, np.zeros(model.n_dof), g.N, g.dN, g.weights, g.thickness,
                                   params, g.param_index, zeros, trial, delta, traction, fe, ke, True, info,
                                   g.law_id)
        raise_for_status(st, info, g.name, "elastic joint stiffness")
        parts.append((g, ke))
    return parts


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
