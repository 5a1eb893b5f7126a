"""Numba kernels of the dynamic solver: Newmark kinematics and residual of a step, the works and energies
of a step (Hughes, *The Finite Element Method*, 2000, sec. 9.1; Newmark 1959).

The small dense LU and the low-rank (Woodbury) update the dynamic solver also uses are in
:mod:`masonrydam.solvers.linear.dense_lu`.
"""
from __future__ import annotations

import math

import numba
import numpy as np

from ...errors import STATUS_NAN, STATUS_OK


@numba.njit(cache=True)
def euclidean_norm(x) -> float:
    """``||x||`` (x (n,) float64), summed in index order. numpy's ``np.linalg.norm`` of a vector is BLAS's
    ``ddot``, whose order depends on the BLAS build (numba's ``np.dot`` calls scipy's BLAS, numpy calls its own,
    and the two differ in the last bits); the implicit step's Python loop and its compiled loop
    (:mod:`.step_loop`) both call this one, so their convergence decisions are the same bit for bit."""
    acc = 0.0
    for i in range(x.shape[0]):
        acc += x[i] * x[i]
    return math.sqrt(acc)


@numba.njit(cache=True)
def free_norm(x, free) -> float:
    """``||x[free]||`` (x (n_dof,), ``free`` (n,) int), as :func:`euclidean_norm` without the gathered copy."""
    acc = 0.0
    for i in range(free.shape[0]):
        v = x[free[i]]
        acc += v * v
    return math.sqrt(acc)


@numba.njit(cache=True)
def difference_norm(x, y) -> float:
    """``||x - y||`` (both (n,) float64), as :func:`euclidean_norm` of the difference without forming it."""
    acc = 0.0
    for i in range(x.shape[0]):
        d = x[i] - y[i]
        acc += d * d
    return math.sqrt(acc)


@numba.njit(cache=True)
def dot_product(x, y) -> float:
    """``x . y`` (both (n,) float64) summed in index order (see :func:`euclidean_norm` for why not BLAS)."""
    acc = 0.0
    for i in range(x.shape[0]):
        acc += x[i] * y[i]
    return acc


@numba.njit(cache=True)
def ground_load(ag, influence, out):
    """``out = -(a_g . M iota)`` (n,) N from the ground acceleration ``ag`` (dim,) m/s2 and ``influence`` (dim, n)
    kg, the directions summed in order (numpy's ``ag @ influence`` is BLAS's ``gemv``, whose order differs between
    the BLAS numpy ships and the one numba calls; see :func:`euclidean_norm`)."""
    dim, n = influence.shape
    for i in range(n):
        acc = ag[0] * influence[0, i]
        for c in range(1, dim):
            acc += ag[c] * influence[c, i]
        out[i] = -acc


@numba.njit(cache=True)
def newmark_kinematics(u, free, un, vn, an, h, beta, gamma, mass_diag, a1, v1, Ma):
    """End-of-step acceleration and velocity of an implicit Newmark-family step (Newmark 1959; Hughes
    2000, *The Finite Element Method*, sec. 9.1) from the end-of-step displacements ``u`` (n_dof,) m on
    the ``free`` (n,) DOFs, with ``un, vn, an`` (n,) the start of the step:

        a1 = (u - u_n - h v_n - h^2 (1/2 - beta) a_n) / (beta h^2),   v1 = v_n + h ((1 - gamma) a_n + gamma a1)

    into ``a1``, ``v1`` (n,), and ``Ma = mass_diag a1`` when ``mass_diag`` has n entries (lumped mass;
    a consistent mass is multiplied by the caller). One pass instead of a dozen numpy temporaries;
    the sparse products stay with scipy, whose CSR product was 1.6x faster than one written here."""
    n = un.shape[0]
    hh = h * h * (0.5 - beta)
    bh2 = beta * h * h
    for i in range(n):
        a1[i] = (((u[free[i]] - un[i]) - h * vn[i]) - hh * an[i]) / bh2
        v1[i] = vn[i] + h * ((1.0 - gamma) * an[i] + gamma * a1[i])
    if mass_diag.shape[0] == n:
        for i in range(n):
            Ma[i] = mass_diag[i] * a1[i]


@numba.njit(cache=True)
def newmark_residual(Ma, w_m, Cv, f_int, free, const, R):
    """Step residual ``R = w_m M a1 + C v1 + f_int + const`` (N) on the ``free`` (n,) DOFs from the
    products ``Ma = M a1`` (scaled by ``w_m`` in place: the HHT/generalized-alpha weight) and ``Cv``
    (n,), the internal forces ``f_int`` (n_dof,) and the step's constant part ``const`` (n,) (loads,
    alpha-weighted terms). Returns STATUS_OK, or STATUS_NAN when R is not finite."""
    status = STATUS_OK
    for i in range(R.shape[0]):
        m = w_m * Ma[i]
        Ma[i] = m
        r = ((m + Cv[i]) + f_int[free[i]]) + const[i]
        R[i] = r
        if not (abs(r) < np.inf):
            status = STATUS_NAN
    return status


@numba.njit(cache=True)
def step_loads(static_load, ground_end, ground_start, state_force, p1, pn, pg1, pg0):
    """The loads of an implicit step on its free DOFs (n,) N from the constant load of the static stages
    ``static_load``, the ground (and time-given) loads at the step's end and start ``ground_end``,
    ``ground_start`` and the state force ``state_force``: ``p1 = (static_load + ground_end) + state_force``,
    ``pn`` the same at the start, and the earthquake loads of the energy balance ``pg1 = ground_end +
    state_force``, ``pg0`` (:meth:`~masonrydam.solvers.dynamic.energy.EnergyBalance.record`). Each entry is
    the sum numpy forms in that order, so the values are bit for bit those of the expressions; one pass
    instead of six temporaries of n entries."""
    for i in range(p1.shape[0]):
        s = state_force[i]
        p1[i] = (static_load[i] + ground_end[i]) + s
        pn[i] = (static_load[i] + ground_start[i]) + s
        pg1[i] = ground_end[i] + s
        pg0[i] = ground_start[i] + s


@numba.njit(cache=True)
def step_constant(p1, pn, mass_diag, ma_n, an, weight_m, cv_n, f_int, free, weight_f, const):
    """The constant part of an implicit step's residual (N, free DOFs (n,); Chung & Hulbert 1993, see
    :mod:`~masonrydam.solvers.dynamic.implicit`):

        const = -p1 + weight_m M a_n + weight_f ((C v_n + f_int(u_n)) - p_n)

    with ``weight_m = am / (1 - af)`` and ``weight_f = af / (1 - af)``; a zero weight leaves its term out (not
    added as zero: the sign of a zero stays that of -p1). ``M a_n`` is ``mass_diag a_n`` when ``mass_diag``
    has n entries (lumped mass), else ``ma_n`` from the caller; ``f_int`` (n_dof,) is gathered at ``free``.
    The operations are numpy's for ``const = -p1; const = const + weight_m * (M a_n); const = const + weight_f
    * ((C v_n + f_int[free]) - p_n)``, in that order: the same bits."""
    n = p1.shape[0]
    lumped = mass_diag.shape[0] == n
    for i in range(n):
        c = -p1[i]
        if weight_m != 0.0:
            m = mass_diag[i] * an[i] if lumped else ma_n[i]
            c = c + weight_m * m
        if weight_f != 0.0:
            c = c + weight_f * ((cv_n[i] + f_int[free[i]]) - pn[i])
        const[i] = c


@numba.njit(cache=True)
def step_works(free, u0, u1, pg0, pg1, fs, cv0, cv1, f0, f1, kc0, kc1, v1, mass_diag, mv1, a0, a1, ma0, ma1, out):
    """Trapezoidal works of one step on the ``free`` (n,) DOFs (the energy balance of
    :meth:`~masonrydam.solvers.dynamic.energy.EnergyBalance.record`; Hughes 2000, sec. 9.1.4), with
    ``du = u1 - u0`` (n_dof arrays ``u0, u1, f0, f1, kc0, kc1, a0, a1``; (n,) arrays ``pg*, fs, cv*, v1``):

        out[0] = du . (pg0 + pg1) / 2          work of the earthquake loads (J)
        out[1] = du . fs                       work of the constant loads
        out[2] = du . (cv0 + cv1) / 2          damping work (C v at both ends)
        out[3] = du . (fj0 + fj1) / 2          joint work, fj = f_int - K_continuum u
        out[4] = v1 . M v1 / 2                 kinetic energy at the end (M = diag(mass_diag) when it has
                                               n entries, else ``mv1`` = M v1 from the caller)
        out[5] = du . M (a0 + a1) / 2          inertia work (M a from ``ma0``, ``ma1`` for a full mass)
        out[6] = du . M (a1 - a0)
        out[7] = du . (f1 - f0)                change of the internal forces (continuum and joints)
        out[8] = du . (cv1 - cv0)
        out[9] = du . (pg1 - pg0)

    out[5:] are the terms of the integrator's numerical dissipation (see :meth:`~.energy.EnergyBalance.record`).
    One pass instead of a few dozen indexed copies."""
    n = free.shape[0]
    w_in = 0.0
    w_ext = 0.0
    w_damp = 0.0
    w_joint = 0.0
    kin = 0.0
    w_inertia = 0.0
    w_da = 0.0
    w_df = 0.0
    w_dcv = 0.0
    w_dpg = 0.0
    lumped = mass_diag.shape[0] == n
    for i in range(n):
        j = free[i]
        du = u1[j] - u0[j]
        w_in += (pg0[i] + pg1[i]) * du
        w_ext += fs[i] * du
        w_damp += (cv0[i] + cv1[i]) * du
        w_joint += ((f0[j] - kc0[j]) + (f1[j] - kc1[j])) * du
        if lumped:
            kin += v1[i] * mass_diag[i] * v1[i]
            m0 = mass_diag[i] * a0[j]
            m1 = mass_diag[i] * a1[j]
        else:
            kin += v1[i] * mv1[i]
            m0 = ma0[i]
            m1 = ma1[i]
        w_inertia += (m0 + m1) * du
        w_da += (m1 - m0) * du
        w_df += (f1[j] - f0[j]) * du
        w_dcv += (cv1[i] - cv0[i]) * du
        w_dpg += (pg1[i] - pg0[i]) * du
    out[0] = 0.5 * w_in
    out[1] = w_ext
    out[2] = 0.5 * w_damp
    out[3] = 0.5 * w_joint
    out[4] = 0.5 * kin
    out[5] = 0.5 * w_inertia
    out[6] = w_da
    out[7] = w_df
    out[8] = w_dcv
    out[9] = w_dpg


@numba.njit(cache=True)
def joint_step_energy(delta0, traction0, state0, delta1, traction1, state1, weight, out):
    """Where the work of one joint set over a step went (J), point by point; arrays (n_elem, nip, dim)
    for the relative displacements ``delta*`` (m) and tractions ``traction*`` (Pa) at the start (0)
    and the end (1) of the step, (n_elem, nip, N_JOINT_STATE) for the law's states, (n_elem, nip)
    ``weight`` (m2: integration weight x thickness).

    A point's trapezoidal work ``W = w (t0 + t1) . (delta1 - delta0) / 2`` is split into

        out[0] += W_slip  = w (tau0 + tau1) . (s_p1 - s_p0) / 2      friction (plastic slip s_p)
        out[1] += bond    = W - dPsi - W_slip  if the bond broke in the step
        out[2] += contact = W - dPsi - W_slip  if the point opened or closed in the step (not a bond
                                               break): lost at an impact, gained (negative) at a release
        out[3] += W - dPsi - W_slip            at the other points (zero up to round-off: checks the split)
        out[4] += W

    with the stored energy ``Psi = w (t_n^2 / kn + |tau|^2 / ks) / 2`` (kn, ks implied by the law:
    ``t_n = kn delta_n`` and ``tau = ks (delta_s - s_p)`` at a closed point, Psi = 0 at an open one,
    see :mod:`masonrydam.materials.mohr_coulomb`): with those relations the shear work of a closed
    point is exactly dPsi_s + W_slip and the normal work exactly dPsi_n, so only a point whose
    contact state changes leaves a remainder - the energy the trapezoidal rule cannot see in a jump of
    the normal traction (Laursen & Chawla 1997, IJNME 40:863-886). Evaluated without kn and ks:
    ``Psi_n = t_n delta_n / 2`` and ``Psi_s = tau . (delta_s - s_p) / 2``."""
    ne, nip, dim = delta0.shape
    ns = dim - 1
    for i in range(ne):
        for g in range(nip):
            w = weight[i, g]
            work = 0.0
            psi0 = 0.0
            psi1 = 0.0
            slip_work = 0.0
            for c in range(dim):
                work += (traction0[i, g, c] + traction1[i, g, c]) * (delta1[i, g, c] - delta0[i, g, c])
            work *= 0.5 * w
            open0 = state0[i, g, 0] == 2.0
            open1 = state1[i, g, 0] == 2.0
            if not open0:
                psi0 += traction0[i, g, dim - 1] * delta0[i, g, dim - 1]
                for c in range(ns):
                    psi0 += traction0[i, g, c] * (delta0[i, g, c] - state0[i, g, 2 + c])
            if not open1:
                psi1 += traction1[i, g, dim - 1] * delta1[i, g, dim - 1]
                for c in range(ns):
                    psi1 += traction1[i, g, c] * (delta1[i, g, c] - state1[i, g, 2 + c])
            for c in range(ns):
                slip_work += (traction0[i, g, c] + traction1[i, g, c]) * (state1[i, g, 2 + c] - state0[i, g, 2 + c])
            slip_work *= 0.5 * w
            rest = work - 0.5 * w * (psi1 - psi0) - slip_work
            out[0] += slip_work
            if state0[i, g, 1] == 0.0 and state1[i, g, 1] != 0.0:
                out[1] += rest
            elif open0 != open1:
                out[2] += rest
            else:
                out[3] += rest
            out[4] += work


@numba.njit(cache=True)
def joint_stored_energy_range(traction, compliance_n, compliance_s, first, end):
    """:func:`joint_stored_energy` over the elements ``first`` .. ``end - 1`` of the arrays: one joint set of
    several laid one after the other (:mod:`.loop_kernel`), summed as the set's own call sums it."""
    dim = traction.shape[2]
    nip = traction.shape[1]
    e = 0.0
    for i in range(first, end):
        for g in range(nip):
            tn = traction[i, g, dim - 1]
            ts2 = 0.0
            for c in range(dim - 1):
                ts2 += traction[i, g, c] * traction[i, g, c]
            e += compliance_n[i, g] * tn * tn + compliance_s[i, g] * ts2
    return e


@numba.njit(cache=True)
def joint_stored_energy(traction, compliance_n, compliance_s):
    """Elastic energy stored in one joint set (J): ``sum (cn t_n^2 + cs |tau|^2)`` over its points, with
    ``traction`` (n_elem, nip, dim) Pa (shear components first, normal last) and the compliances
    ``compliance_n = w / (2 kn)``, ``compliance_s = w / (2 ks)`` (n_elem, nip) m^3/N (w the point's
    area). An open point has zero traction and stores nothing. One pass instead of a handful of
    numpy reductions per set and step."""
    return joint_stored_energy_range(traction, compliance_n, compliance_s, 0, traction.shape[0])
