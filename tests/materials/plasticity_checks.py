"""Shared helpers of the plasticity law tests (test_von_mises, test_tresca, test_drucker_prager,
test_mohr_coulomb_solid): Voigt <-> tensor conversions with the conventions of
masonrydam/materials/plasticity.py (engineering shear strains, tensor shear stresses), random
rotations, a one-point evaluation that checks the committed state is left alone, the central
finite-difference tangent, and a mixed strain/stress-controlled driver."""
from __future__ import annotations

import numpy as np

VOIGT = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0)]


def strain_tensor(v):
    """3x3 tensor of a 3D engineering strain vector."""
    t = np.zeros((3, 3))
    for i, (a, b) in enumerate(VOIGT):
        t[a, b] = t[b, a] = v[i] if i < 3 else 0.5 * v[i]
    return t


def strain_vector(t):
    return np.array([t[0, 0], t[1, 1], t[2, 2], 2 * t[0, 1], 2 * t[1, 2], 2 * t[2, 0]])


def stress_tensor(v):
    t = np.zeros((3, 3))
    for i, (a, b) in enumerate(VOIGT):
        t[a, b] = t[b, a] = v[i]
    return t


def stress_vector(t):
    return np.array([t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[1, 2], t[2, 0]])


def rotation(seed):
    """A random proper rotation (3, 3)."""
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def point_checks(law_evaluate):
    """``(evaluate, fd_tangent)`` for a law's Python wrapper ``law_evaluate(strain, params, committed, dt)``:
    ``evaluate(strain, params, committed, dt=0)`` -> (stress, tangent, trial state) of one point, asserting
    that ``committed`` is not modified; ``fd_tangent(strain, params, committed, dt=0, rel=1e-6)``: the
    central finite difference of the stress with respect to the strain."""
    def evaluate(strain, params, committed, dt=0.0):
        before = committed.copy()
        s, D, t = law_evaluate(np.atleast_2d(strain), params, committed, dt=dt)
        assert np.array_equal(committed, before)
        return s[0], D[0], t

    def fd_tangent(strain, params, committed, dt=0.0, rel=1e-6):
        strain = np.asarray(strain, dtype=float)
        h = rel * np.max(np.abs(strain))
        ns = strain.shape[0]
        D = np.empty((ns, ns))
        for j in range(ns):
            e = np.zeros(ns)
            e[j] = h
            D[:, j] = (evaluate(strain + e, params, committed, dt)[0]
                       - evaluate(strain - e, params, committed, dt)[0]) / (2 * h)
        return D

    return evaluate, fd_tangent


def mixed_control(evaluate, initial_state, params, drive, path, free, target, scale, state=None, ns=6, tol=1e-10):
    """Strain components ``drive`` follow ``path`` (rows of values); each group of components in ``free``
    (a component, or a tuple of components sharing one unknown, e.g. ``(1, 2)`` for eyy = ezz) is found by
    a Newton with the consistent tangent so that the stress of the group's first component equals
    ``target`` (the other strain components stay zero; convergence at ``tol * scale`` Pa). Returns the
    stresses, the last state and the largest iteration count."""
    state = initial_state(1) if state is None else state
    free = [tuple(g) if isinstance(g, (tuple, list)) else (g,) for g in free]
    rows = [g[0] for g in free]
    x = np.zeros(len(free))
    out, iters = [], 0
    for vals in path:
        for it in range(30):
            eps = np.zeros(ns)
            eps[list(drive)] = vals
            for g, xg in zip(free, x):
                eps[list(g)] = xg
            s, D, trial = evaluate(eps, params, state)
            r = s[rows] - target
            if np.max(np.abs(r)) <= tol * scale:
                break
            J = np.array([[D[i, list(g)].sum() for g in free] for i in rows])
            x -= np.linalg.solve(J, r)
        else:
            raise AssertionError("mixed-control Newton did not converge")
        iters = max(iters, it)
        state = trial
        out.append(s)
    return np.array(out), state, iters
