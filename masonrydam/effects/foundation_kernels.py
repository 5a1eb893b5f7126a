"""Numba kernel of the free-field effective force of the foundation rock with mass (one call per time step).

The 1D free field of a component at elevation ``z`` and time ``t`` is the upgoing wave at the base
evaluated at two delays, ``v_I(t - (z - z_b) / c) + v_I(t - (2 z_top - z_b - z) / c)`` (Kramer 1996,
Wolf 1985); the effective force is linear in the strains ``(v_2 - v_1) / c`` at the traction points and
in the velocities at the absorbing nodes (Nielsen 2006, Løkke & Chopra 2018), so
:class:`~masonrydam.effects.foundation.Foundation` precomputes one sparse operator ``K`` (rows: the DOFs
that get a force; columns: one per component and distinct elevation) and the kernel evaluates the
free-field values at the distinct elevations and the product ``K w``.

The velocity of the upgoing wave is tabulated on a uniform grid ``t_j = dt * j`` (j = 0..n-1, the
record's step) and interpolated linearly with exactly the arithmetic of ``numpy.interp(x, t_j, v_j,
left=0.0)`` (zero before 0, the last value after the end), so the values are those of
:meth:`~masonrydam.effects.foundation.Foundation.free_field` to the last bit. Units: s, m/s, m, N.

Theory: docs/dam_reservoir_foundation.md, section "The foundation rock with mass".
"""
from __future__ import annotations

import numba
import numpy as np

from ..errors import STATUS_OK

__all__ = ["interp_uniform", "free_field_force"]


@numba.njit(cache=True)
def interp_uniform(x, values, offset, n, dt):
    """``numpy.interp(x, dt * arange(n), values[offset:offset + n], left=0.0)`` for a scalar x (s),
    found by index arithmetic (``floor(x / dt)``, corrected against the grid points ``dt * j`` so that
    the interval is the one numpy's search finds) and evaluated with numpy's formula ``slope * (x - x_j)
    + v_j``, ``slope = (v_{j+1} - v_j) / (x_{j+1} - x_j)``; ``v_j`` exactly when ``x == x_j``."""
    if x != x:  # NaN
        return x
    if x < 0.0:
        return 0.0
    last = n - 1
    q = x / dt
    j = last if q >= last else int(q)  # x >= 0: truncation is the floor
    while j > 0 and dt * j > x:
        j -= 1
    while j < last and dt * (j + 1) <= x:
        j += 1
    if j == last:
        return values[offset + last]
    xj = dt * j
    vj = values[offset + j]
    if xj == x:
        return vj
    slope = (values[offset + j + 1] - vj) / (dt * (j + 1) - xj)
    return slope * (x - xj) + vj


@numba.njit(cache=True)
def free_field_force(t, grids, grid_offset, grid_length, base_offset, base_length, dt, scale, speed,
                     delay_1, delay_2, n_strain, indptr, indices, data, w, out):
    """Free-field values and the effective force ``out = K w`` at time ``t`` (s).

    Parameters (c: the ``n_comp`` components with a record, in the operator's order; e: the ``n_z``
    distinct elevations, first the ``n_strain`` of the traction points, then those of the absorbing
    nodes):

    grids : (m,) float64, the upgoing-wave velocity grids (m/s) and the base velocity grids, packed.
    grid_offset, grid_length : (n_comp,) int64, where component c's upgoing-wave grid lies in ``grids``.
    base_offset, base_length : (n_comp,) int64, its base-motion velocity grid (length 0: no base motion
        subtracted, the outcrop case).
    dt : (n_comp,) float64 s, the grid step (the record's).
    scale : (n_comp,) float64, the factor of the interpolated grid value (0.5: half the outcrop record is
        upgoing; 1.0: the within series).
    speed : (n_comp,) float64 m/s, wave speed of the component (c_p vertical, c_s horizontal).
    delay_1, delay_2 : (n_comp, n_z) float64 s, ``(z - z_b) / c`` and ``(2 z_top - z_b - z) / c``.
    indptr, indices, data : CSR of ``K`` (n_rows, n_comp * n_z), N per (1/1 strain or m/s).
    w : (n_comp * n_z,) float64 output: strain ``(v_2 - v_1) / c`` (-) for e < n_strain, else the
        velocity ``v_1 + v_2`` (minus the base velocity when given), m/s; column ``c * n_z + e``.
    out : (n_rows,) float64 output, N.

    Returns STATUS_OK.
    """
    n_comp, n_z = delay_1.shape
    for c in range(n_comp):
        off, n, h, s, sp = grid_offset[c], grid_length[c], dt[c], scale[c], speed[c]
        vb = 0.0
        has_base = base_length[c] > 0
        if has_base:
            vb = interp_uniform(t, grids, base_offset[c], base_length[c], h)
        for e in range(n_z):
            v1 = s * interp_uniform(t - delay_1[c, e], grids, off, n, h)
            v2 = s * interp_uniform(t - delay_2[c, e], grids, off, n, h)
            if e < n_strain:
                w[c * n_z + e] = (v2 - v1) / sp
            elif has_base:
                w[c * n_z + e] = (v1 + v2) - vb
            else:
                w[c * n_z + e] = v1 + v2
    for r in range(len(out)):
        acc = 0.0
        for k in range(indptr[r], indptr[r + 1]):
            acc += data[k] * w[indices[k]]
        out[r] = acc
    return STATUS_OK
