"""Failure diagnosis in words: which part of the model is free to move as a rigid body, and where a Newton
iteration that did not converge is out of balance.

Nodes are joined by continuum elements and by interface elements that still transmit force (not
every integration point open). Each connected part must have its rigid-body modes (2D: two
translations and a rotation) restrained by constrained DOFs; a part where they are not is named
with its element groups, its bounding box and the joint sets around it that opened.

A static step whose Newton iterations do not converge is described by :func:`newton_stall`: the DOF its last
iterate leaves most out of balance and the joint points whose state its next correction would switch, the
signature of Newton cycling between joint-state patterns at a non-smooth point of a joint law (the Eindhoven
wall's inviscid stall at a softened unit crack, docs/masonry_softening.md).
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..errors import NumericalError
from ..materials.joint_laws import RESULT_STATE_NAMES
from .linear.direct import SingularMatrix



def _components(model, use_joint_state: bool):
    rows, cols = [], []
    for g in model.cgroups:
        c = g.conn
        rows.append(np.repeat(c[:, :1], c.shape[1], axis=1).ravel())
        cols.append(c.ravel())
    for g in model.igroups:
        ns = g.conn.shape[1] // 2
        active = np.ones(g.n_elem, dtype=bool)
        if use_joint_state and g.nonlinear:
            active = ~g.is_open(trial=True).all(axis=1)
        c = g.conn[active]
        rows.append(c[:, :ns].ravel())
        cols.append(c[:, ns:].ravel())
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(r)), (r, c)), shape=(model.n_nodes, model.n_nodes))
    return connected_components(graph, directed=False)


def _rigid_modes(coords: np.ndarray) -> np.ndarray:
    """(n*dim, n_modes) rigid-body modes of a point cloud (2D: tx, ty, rz; 3D: 3 + 3)."""
    n, dim = coords.shape
    x = coords - coords.mean(axis=0)
    scale = max(np.abs(x).max(), 1e-30)
    x = x / scale
    if dim == 2:
        R = np.zeros((n, 2, 3))
        R[:, 0, 0] = 1
        R[:, 1, 1] = 1
        R[:, 0, 2] = -x[:, 1]
        R[:, 1, 2] = x[:, 0]
    else:
        R = np.zeros((n, 3, 6))
        for k in range(3):
            R[:, k, k] = 1
        R[:, 1, 3], R[:, 2, 3] = -x[:, 2], x[:, 1]
        R[:, 0, 4], R[:, 2, 4] = x[:, 2], -x[:, 0]
        R[:, 0, 5], R[:, 1, 5] = -x[:, 1], x[:, 0]
    return R.reshape(n * dim, -1)


_MODE_NAMES = {2: ["translation x", "translation y", "rotation"],
               3: ["translation x", "translation y", "translation z", "rotation x", "rotation y", "rotation z"]}


def find_free_parts(model, constrained: np.ndarray, use_joint_state: bool = True) -> list[str]:
    """Descriptions of the parts of ``model`` that can move as rigid bodies (empty if none)."""
    n_comp, label = _components(model, use_joint_state)
    dim = model.dim
    node_group = {}
    for g in model.cgroups:
        for n in np.unique(g.conn):
            node_group.setdefault(int(n), set()).add(g.name)
    parts = []
    for c in range(n_comp):
        nodes = np.nonzero(label == c)[0]
        R = _rigid_modes(model.coords[nodes])
        dofs = (nodes[:, None] * dim + np.arange(dim)).ravel()
        Rc = R[constrained[dofs]]
        n_modes = R.shape[1]
        if Rc.shape[0] == 0:
            rank, free_modes = 0, list(range(n_modes))
        else:
            s = np.linalg.svd(Rc, compute_uv=False)
            rank = int((s > 1e-8 * max(s.max(), 1e-30)).sum())
            _, _, vt = np.linalg.svd(Rc)
            null = vt[rank:]
            free_modes = [int(np.argmax(np.abs(v))) for v in null]
        if rank >= n_modes:
            continue
        groups = sorted({gname for n in nodes for gname in node_group.get(int(n), ())})
        lo, hi = model.coords[nodes].min(axis=0), model.coords[nodes].max(axis=0)
        opened = []
        for g in model.igroups:
            if not g.nonlinear:
                continue
            touches = np.isin(g.conn, nodes).any(axis=1)
            is_open = g.is_open(trial=True).all(axis=1)
            if (touches & is_open).any():
                opened.append(f"{g.name} ({int((touches & is_open).sum())} element(s) open)")
        box = ", ".join(f"{'xyz'[k]} in [{lo[k]:.4g}, {hi[k]:.4g}] m" for k in range(dim))
        modes = ", ".join(sorted({_MODE_NAMES[dim][m] for m in free_modes}))
        text = (f"part of element group(s) {groups} with {len(nodes)} node(s) (e.g. node {int(nodes[0])}), {box}: "
                f"free rigid-body motion ({modes})")
        if opened:
            text += "; joints around it that opened: " + ", ".join(opened)
        elif Rc.shape[0] == 0:
            text += "; it has no support"
        parts.append(text)
    return parts


def _joint_states(model) -> list[tuple[object, np.ndarray, np.ndarray]]:
    """Per nonlinear interface group: the group, its law's own trial state codes and the result's states,
    (ne, nip) each."""
    return [(g, g.state_codes(trial=True).copy(), g.result_states(trial=True).copy())
            for g in model.igroups if g.nonlinear]


def newton_stall(model, u: np.ndarray, residual, solve=None) -> str:
    """Where the last iterate ``u`` (n_dof,) m of a static step that did not converge is out of balance, in words
    to add to the failure's message (empty where it cannot be evaluated).

    ``residual(v, tangent)`` gives (r, K): the residual (N) on the free DOFs at ``v`` and, with ``tangent``, the
    tangent there; ``solve(K, r)`` the correction (None: the next correction is not looked at, e.g. where a
    factorization is too costly). Names the free DOF with the largest residual (node, position, component, N)
    and, from the next Newton correction, how many joint points it would switch to another state of their law
    (per joint set) and the switching point nearest that node, with its states before and after. Leaves the
    joints' trial state at ``u`` or past it: the caller reverts it."""
    free = model.dofmap.free
    try:
        r, K = residual(u, solve is not None)
        before = _joint_states(model)
        after = None
        if solve is not None:
            v = u.copy()
            v[free] += solve(K, r)
            residual(v, False)
            after = _joint_states(model)
    except (NumericalError, SingularMatrix, ValueError):
        return ""
    if len(r) == 0 or not np.isfinite(r).all():
        return ""
    dim = model.dim
    k = int(np.argmax(np.abs(r)))
    node, comp = divmod(int(free[k]), dim)
    at = model.coords[node]
    text = (f"; the last iterate is out of balance most at node {node} ("
            + ", ".join(f"{c:.4g}" for c in at) + f") m, by {abs(r[k]):.3g} N in {'xyz'[comp]}")
    if after is None:
        return text
    counts, nearest = [], None
    for (g, codes0, res0), (_, codes1, res1) in zip(before, after):
        switched = codes0 != codes1
        if not switched.any():
            continue
        counts.append(f"{g.name} {int(switched.sum())}")
        pts = g.points[switched].reshape(-1, dim)
        d = np.linalg.norm(pts - at, axis=1)
        i = int(np.argmin(d))
        if nearest is None or d[i] < nearest[0]:
            nearest = (d[i], g.name, pts[i], RESULT_STATE_NAMES[res0[switched][i]],
                       RESULT_STATE_NAMES[res1[switched][i]])
    if nearest is None:
        return text + "; its next correction switches no joint point's state"
    _, name, where, s0, s1 = nearest
    return (text + f"; its next correction would switch the state of joint points ({', '.join(counts)}), the "
            f"nearest at (" + ", ".join(f"{c:.4g}" for c in where) + f") m in joint set '{name}' ({s0} to {s1}): "
            "Newton may be cycling at a corner of the joint law there")
