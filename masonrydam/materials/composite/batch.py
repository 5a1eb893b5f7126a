"""The composite joint law over arrays of points: the batch kernel :func:`composite_update`, its Python
wrapper :func:`composite_evaluate` (checked shapes, errors raised) and the virgin state rows.

Shapes: ``delta`` (n, ns+1) (m), ``params`` (n, N_COMPOSITE_PARAMS), states (n, N_COMPOSITE_STATE),
tractions (n, ns+1) (Pa), tangents (n, ns+1, ns+1) (Pa/m); ns = 1 (2D) or 2 (3D).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...errors import STATUS_OK, NumericalError
from ..plasticity import STATUS_BAD_MATERIAL
from .columns import N_COMPOSITE_PARAMS, N_COMPOSITE_STATE, PARAM_NAMES
from .parameters import first_bad_column
from .point_law import composite_point


@njit(cache=True)
def composite_update(delta, params, state_committed, state_trial, traction_out, tangent_out, info):
    """Batch update: :func:`composite_point` for every row ``k`` (parameter row ``k``).

    delta float64 (n, ns+1) C-contiguous; params (n, N_COMPOSITE_PARAMS); state_committed,
    state_trial (n, N_COMPOSITE_STATE); traction_out (n, ns+1); tangent_out (n, ns+1, ns+1);
    info int64 (>= 1,): ``info[0]`` = the failing point, ``info[1]`` (if present) = the bad
    parameter column. Returns the status of the first failing point (later points not evaluated).
    """
    n = delta.shape[0]
    ncomp = delta.shape[1]
    ns = ncomp - 1
    d3 = delta.reshape((n, 1, ncomp))
    sc3 = state_committed.reshape((n, 1, N_COMPOSITE_STATE))
    st3 = state_trial.reshape((n, 1, N_COMPOSITE_STATE))
    t3 = traction_out.reshape((n, 1, ncomp))
    for k in range(n):
        status = composite_point(params, k, d3, ns, sc3, st3, k, 0, t3, tangent_out[k])
        if status != STATUS_OK:
            info[0] = k
            if info.shape[0] > 1:
                info[1] = first_bad_column(params, k)
            return status
    return STATUS_OK


def composite_initial_state(n: int) -> np.ndarray:
    """Virgin state rows (n, N_COMPOSITE_STATE): elastic, uncracked, no plastic displacement."""
    return np.zeros((int(n), N_COMPOSITE_STATE), dtype=np.float64)


def composite_evaluate(delta, params, state_committed):
    """Python wrapper of :func:`composite_update`.

    Parameters
    ----------
    delta : (n, ns+1) array (or one point (ns+1,)), ns = 1 (2D) or 2 (3D), m.
    params : (n, N_COMPOSITE_PARAMS) or one row used for every point (:func:`composite_params`).
    state_committed : (n, N_COMPOSITE_STATE); read only.

    Returns
    -------
    (traction (n, ns+1) Pa, tangent (n, ns+1, ns+1) Pa/m, state_trial (n, N_COMPOSITE_STATE)).

    Raises
    ------
    ValueError for a bad shape or parameter; masonrydam.errors.NumericalError for a non-finite
    input or result or a local return mapping that did not converge.
    """
    d = np.ascontiguousarray(delta, dtype=np.float64)
    if d.ndim == 1:
        d = d.reshape(1, -1)
    if d.ndim != 2 or d.shape[1] not in (2, 3):
        raise ValueError(f"delta must have 2 (2D) or 3 (3D) components per point, got shape {np.shape(delta)}")
    n, ncomp = d.shape
    pr = np.ascontiguousarray(params, dtype=np.float64)
    if pr.ndim == 1:
        pr = pr.reshape(1, -1)
    if pr.ndim != 2 or pr.shape[1] != N_COMPOSITE_PARAMS:
        raise ValueError(f"params must have {N_COMPOSITE_PARAMS} columns, got shape {np.shape(params)}")
    if pr.shape[0] == 1 and n != 1:
        pr = np.ascontiguousarray(np.broadcast_to(pr, (n, N_COMPOSITE_PARAMS)))
    if pr.shape[0] != n:
        raise ValueError(f"params must have 1 or {n} rows, got shape {pr.shape}")
    sc = np.ascontiguousarray(state_committed, dtype=np.float64)
    if sc.ndim == 1:
        sc = sc.reshape(1, -1)
    if sc.shape != (n, N_COMPOSITE_STATE):
        raise ValueError(f"state_committed must have shape ({n}, {N_COMPOSITE_STATE}), got {np.shape(state_committed)}")
    st = np.empty_like(sc)
    t = np.empty((n, ncomp))
    C = np.empty((n, ncomp, ncomp))
    info = np.zeros(2, dtype=np.int64)
    status = composite_update(d, pr, sc, st, t, C, info)
    if status == STATUS_BAD_MATERIAL:
        col = int(info[1])
        raise ValueError(f"composite interface: inadmissible {PARAM_NAMES.get(col, col)} at point {int(info[0])}")
    if status != STATUS_OK:
        raise NumericalError(
            f"composite interface: non-finite input or result, or no converged return, at point {int(info[0])}")
    return t, C, st
