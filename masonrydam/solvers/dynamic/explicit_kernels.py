"""Numba kernels of the explicit (central difference) step: the predictor, and the corrector fused with the
works of the step (Hughes, *The Finite Element Method*, 2000, sec. 9.1.2 and 9.1.4; Belytschko, Liu & Moran
2000, Box 6.1; local damping: Cundall 1987, Itasca 3DEC manual).

Why written here: an explicit step of a 42 000-DOF dam costs about one sparse product (1.7 ms) plus the joint
kernels; numpy's dozen temporaries per step and a second pass for the energy balance cost as much again. Each
kernel is one pass over the free DOFs, writes into preallocated outputs and returns a status code.
"""
from __future__ import annotations

import numba
import numpy as np

from ...errors import STATUS_NAN, STATUS_OK


@numba.njit(cache=True)
def central_difference_predict(free, u0, v0, a0, h, u1, v_half):
    """Displacements at the end of the step and the mid-step velocity:

        v_{n+1/2} = v_n + h/2 a_n,    u_{n+1} = u_n + h v_{n+1/2}

    ``u0, v0, a0`` (n_dof,) m, m/s, m/s2 at the start; ``u1`` (n_dof,) out (u0 at the constrained DOFs);
    ``v_half`` (n,) m/s out, on the ``free`` (n,) DOFs; ``h`` s. Returns STATUS_OK."""
    for j in range(u0.shape[0]):
        u1[j] = u0[j]
    for i in range(free.shape[0]):
        j = free[i]
        vh = v0[j] + 0.5 * h * a0[j]
        v_half[i] = vh
        u1[j] = u0[j] + h * vh
    return STATUS_OK


@numba.njit(cache=True)
def central_difference_correct(free, h, mass_diag, static_load, pg0, pg1, state_force, f0, f1, kc0, kc1, u0, u1,
                               a0, v_half, damping_half, damping_diag, local_alpha, fd0, fd1, v1, a1, works):
    """Acceleration and velocity at the end of an explicit step, and the works of the step, in one pass.

    On the ``free`` (n,) DOFs with the lumped mass ``mass_diag`` (n,) kg:

        M a_{n+1} = f_s + p_{n+1} + f_state - f_int(u_{n+1}) - f_d,    v_{n+1} = v_{n+1/2} + h/2 a_{n+1}

    with the damping force ``f_d = C v_{n+1/2} + alpha_L |f_int(u_{n+1}) - f_s| sign(v_{n+1/2})``: the viscous
    part is ``damping_diag * v_half`` when ``damping_diag`` has n entries (a diagonal C), else
    ``damping_half`` (n,), the product ``C v_half`` from the caller (empty: no viscous damping); the local part
    (Cundall's local damping, ``local_alpha`` = alpha_L) is driven by the change of the internal force from
    the static state, so that the ground motion carried by the frame is not damped. ``static_load`` (n,) N
    the constant load ``f_s``; ``pg0``, ``pg1`` (n,) N the loads in time at both ends (ground, loads in
    time), ``state_force`` (n,) N held over the step; ``f0``, ``f1`` (n_dof,) N the internal forces and
    ``kc0``, ``kc1`` (n_dof,) N the blocks' forces at both ends; ``u0``, ``u1``, ``a0`` (n_dof,); ``fd0`` (n,)
    N the damping force of the step before; ``fd1``, ``v1``, ``a1`` out (``fd1`` (n,), ``v1``, ``a1``
    (n_dof,), zero at the constrained DOFs set by the caller).

    ``works`` (10,) J out, in the order of :func:`~.kernels.step_works`: [input ``du . (pg0 + pg1)/2 + du .
    f_state``, external ``du . f_s``, damping ``du . (fd0 + fd1)/2``, joints ``du . (fj0 + fj1)/2`` with
    ``fj = f_int - kc``, kinetic ``v1 . M v1 / 2``, inertia ``du . M (a0 + a1)/2``, 0, 0, 0, 0]. With the
    damping work taken from the forces the step applied, the balance of a central-difference step closes to
    round-off (the inertia work is then exactly the trapezoidal work of those forces).

    Returns STATUS_OK, or STATUS_NAN where an acceleration is not finite (the outputs are then partial)."""
    n = free.shape[0]
    diag = damping_diag.shape[0] == n
    viscous = damping_half.shape[0] == n
    local = local_alpha > 0.0
    w_in = 0.0
    w_ext = 0.0
    w_damp = 0.0
    w_joint = 0.0
    kin = 0.0
    w_inertia = 0.0
    status = STATUS_OK
    for i in range(n):
        j = free[i]
        vh = v_half[i]
        fd = 0.0
        if diag:
            fd = damping_diag[i] * vh
        elif viscous:
            fd = damping_half[i]
        if local:
            r = f1[j] - static_load[i]
            if vh > 0.0:
                fd += local_alpha * abs(r)
            elif vh < 0.0:
                fd -= local_alpha * abs(r)
        fd1[i] = fd
        m = mass_diag[i]
        acc = (((static_load[i] + pg1[i]) + state_force[i]) - f1[j] - fd) / m
        if not (abs(acc) < np.inf):
            status = STATUS_NAN
        a1[j] = acc
        vel = vh + 0.5 * h * acc
        v1[j] = vel
        du = u1[j] - u0[j]
        w_in += (0.5 * (pg0[i] + pg1[i]) + state_force[i]) * du
        w_ext += static_load[i] * du
        w_damp += (fd0[i] + fd) * du
        w_joint += ((f0[j] - kc0[j]) + (f1[j] - kc1[j])) * du
        kin += vel * m * vel
        w_inertia += m * (a0[j] + acc) * du
    works[0] = w_in
    works[1] = w_ext
    works[2] = 0.5 * w_damp
    works[3] = 0.5 * w_joint
    works[4] = 0.5 * kin
    works[5] = 0.5 * w_inertia
    for k in range(6, works.shape[0]):
        works[k] = 0.0
    return status


@numba.njit(cache=True)
def acoustic_predict(p0, pd0, pdd0, h, p1, pd_half):
    """The water's pressures at the end of an explicit step and their mid-step rate (the dam's predictor):

        p'_{n+1/2} = p'_n + h/2 p''_n,    p_{n+1} = p_n + h p'_{n+1/2}

    ``p0, pd0, pdd0`` (n_p,) Pa, Pa/s, Pa/s2 at the start; ``p1``, ``pd_half`` (n_p,) out; ``h`` s.
    Returns STATUS_OK."""
    for i in range(p0.shape[0]):
        rate = pd0[i] + 0.5 * h * pdd0[i]
        pd_half[i] = rate
        p1[i] = p0[i] + h * rate
    return STATUS_OK


@numba.njit(cache=True)
def acoustic_correct(h_p, q_a, pd_half, b_face, frame, b_bottom, bottom, capacity, radiation, rho, h, pdd1, pd1):
    """The water's pressure acceleration and rate at the end of an explicit step, in one pass:

        (g + h/2 l) p''_{n+1} = -H p_{n+1} - l p'_{n+1/2} - rho (Q_w^T a_{n+1} + B_face a_frame + B_bottom a_bottom)
        p'_{n+1} = p'_{n+1/2} + h/2 p''_{n+1}

    i.e. ``g p'' + l p' + H p = -rho (...)`` at the end of the step with the radiation term at the end-of-step
    rate ``p'_{n+1}`` (central difference as Newmark's beta = 0, gamma = 1/2, whose stable step viscous damping
    does not lower; Hughes 2000, sec. 9.1.2). ``h_p`` (n_p,) the product ``H p_{n+1}`` (Pa m) and ``q_a``
    (n_p,) ``Q_w^T a_{n+1}`` (m3/s2) from the caller (scipy's CSR product is about twice as fast as a loop
    written here, measured on the 3D dam's water: 0.16 against 0.29-0.37 ms); ``pd_half`` (n_p,) Pa/s from
    :func:`acoustic_predict`; ``b_face``, ``b_bottom`` (n_p, dim) m2 with ``frame``, ``bottom`` (dim,) m/s2
    the accelerations of the dam's frame and of the reservoir bottom; ``capacity`` g (s2 m) and ``radiation``
    l (s m2) (n_p,) the lumped G and L; ``rho`` kg/m3; ``h`` s; ``pdd1``, ``pd1`` (n_p,) out.

    Returns STATUS_OK, or STATUS_NAN where a pressure acceleration is not finite."""
    status = STATUS_OK
    dim = frame.shape[0]
    for i in range(h_p.shape[0]):
        load = q_a[i]
        for c in range(dim):
            load += b_face[i, c] * frame[c] + b_bottom[i, c] * bottom[c]
        acc = (-h_p[i] - rho * load - radiation[i] * pd_half[i]) / (capacity[i] + 0.5 * h * radiation[i])
        if not (abs(acc) < np.inf):
            status = STATUS_NAN
        pdd1[i] = acc
        pd1[i] = pd_half[i] + 0.5 * h * acc
    return status
