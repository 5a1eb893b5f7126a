"""Newton's method on the composite law's local system of one active set, and the admissibility of a
converged return.

The Jacobian of the residual (:func:`~masonrydam.materials.composite.local_system.local_residual`, 5x5) is
taken by complex steps of size ``h`` (Martins, Sturdza & Alonso 2003, ACM TOMS 29(3) 245-262), so it is
exact to rounding; the step is damped by backtracking on ``|R|`` (Pa). A return is admissible where the
multipliers of its active set are >= 0, ``T >= 0`` and no other surface is violated (Simo & Hughes 1998,
Computational Inelasticity, sec. 5.2).
"""
from __future__ import annotations

import math

from numba import njit

from .dense_lu import lu_factor, lu_solve
from .local_system import local_residual

_MAX_ITERATIONS = 60
TOL_NEWTON = 1e-12  # relative to the traction scale
_TOL_KKT = 1e-8  # inactive surfaces and multipliers at an accepted return


@njit(cache=True)
def _residual_norm(R):
    s = 0.0
    for i in range(5):
        s += R[i].real * R[i].real
    return math.sqrt(s)


@njit(cache=True)
def local_jacobian(x, tr, w, ns, act1, act2, act3, h, J, cx, R, tau, fv):
    """J[:, j] = d R / d x_j by complex steps of size ``h``. The column of a multiplier whose surface is not active
    is the unit column: its row is ``L_j = 0``, so the Newton step's and ``dx / d tr``'s component ``j`` is 0 and
    the rest of the column multiplies zero (a complex residual saved per inactive surface)."""
    for j in range(5):
        if (j == 2 and not act1) or (j == 3 and not act2) or (j == 4 and not act3):
            for i in range(5):
                J[i, j] = 0.0
            J[j, j] = 1.0
            continue
        for i in range(5):
            cx[i] = complex(x[i], 0.0)
        cx[j] = complex(x[j], h)
        local_residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv)
        for i in range(5):
            J[i, j] = R[i].imag / h


@njit(cache=True)
def local_newton(x, tr, w, ns, act1, act2, act3, sref, J, piv, dx, xn, cx, R, tau, fv):
    """Newton iteration with backtracking on |R| from ``x`` (overwritten by the solution); True when
    converged."""
    tol = TOL_NEWTON * sref
    h = 1e-20 * sref
    for i in range(5):
        cx[i] = complex(x[i], 0.0)
    if not local_residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv):
        return False
    r0 = _residual_norm(R)
    for it in range(_MAX_ITERATIONS):
        if r0 <= tol:
            return True
        for i in range(5):
            dx[i] = -R[i].real
        local_jacobian(x, tr, w, ns, act1, act2, act3, h, J, cx, R, tau, fv)
        if not lu_factor(J, piv, 5):
            return False
        lu_solve(J, piv, dx, 5)
        alpha = 1.0
        accepted = False
        r1 = r0
        for ls in range(40):
            for i in range(5):
                xn[i] = x[i] + alpha * dx[i]
                cx[i] = complex(xn[i], 0.0)
            if local_residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv):
                r1 = _residual_norm(R)
                if r1 <= tol or r1 < (1.0 - 1e-4 * alpha) * r0:
                    accepted = True
                    break
            alpha *= 0.5
        if not accepted:
            return False
        for i in range(5):
            x[i] = xn[i]
        r0 = r1
    return r0 <= tol


@njit(cache=True)
def return_is_admissible(x, tr, w, ns, act1, act2, act3, sref, cx, R, tau, fv):
    """Is the converged return admissible: multipliers of the active set >= 0, T >= 0, the other
    surfaces not violated?"""
    tol = _TOL_KKT * sref
    for i in range(5):
        cx[i] = complex(x[i], 0.0)
    local_residual(cx, tr, w, ns, act1, act2, act3, R, tau, fv)
    if x[1] < -tol:
        return False
    if (act1 and x[2] < -tol) or (act2 and x[3] < -tol) or (act3 and x[4] < -tol):
        return False
    if (not act1 and fv[0].real > tol) or (not act2 and fv[1].real > tol) or (not act3 and fv[2].real > tol):
        return False
    return True
