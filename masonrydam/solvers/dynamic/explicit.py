"""The explicit scheme: central difference in velocity form, one joint evaluation per step.

    v_{n+1/2} = v_n + h/2 a_n,   u_{n+1} = u_n + h v_{n+1/2},
    M a_{n+1} = p_{n+1} - f_int(u_{n+1}) - f_d(v_{n+1/2}),   v_{n+1} = v_{n+1/2} + h/2 a_{n+1}

(Hughes 2000, sec. 9.1.2; Belytschko, Liu & Moran 2000, Box 6.1): lumped mass only (diagonal, or node blocks:
:func:`node_mass_blocks`), dt below the
critical step (:mod:`.stability`; dt = "auto" takes the largest stable step that divides the output interval).
The damping force, lagged half a step, is the viscous ``C v_{n+1/2}`` (a diagonal C, mass-proportional, costs
a product of two vectors; dashpots or a stiffness part a sparse product) plus the local damping of Cundall
(``alpha_L |f_int - f_s| sign(v)``, :func:`~masonrydam.assembly.damping.local_damping_coefficient`), which
damps every mode by the same ratio and leaves the stable step alone. A step costs the blocks' sparse product,
the joint kernels and two fused passes over the DOFs (:mod:`.explicit_kernels`), which also give the step's
works: the energy balance of an explicit stage closes to round-off. A compressible reservoir (acoustic
elements) is stepped with the dam where the stage has one (:class:`~.fluid.ExplicitAcoustic`: its pressures
advance with the dam's predictor, its force on the dam enters the corrector, its pressure acceleration follows
the dam's); its work on the dam is ``hydrodynamic``, as in the implicit stages. Vectors on the free DOFs (n_eq,),
SI units. See docs/dynamics.md, docs/dam_3d.md and docs/dam_reservoir_foundation.md.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...assembly.damping import local_damping_coefficient
from ...errors import STATUS_OK, NumericalError
from .explicit_kernels import central_difference_correct, central_difference_predict
from .stage import StepState
from .step_control import step_end


def _diagonal_damping(equations):
    """The diagonal of C (n_eq,) N s/m where C is diagonal (mass-proportional Rayleigh damping alone), else
    None (a sparse product per step)."""
    C = equations.damping_free
    if C is None:
        return None
    d = C.diagonal()
    off = C - sp.diags(d, format="csr")
    off.eliminate_zeros()
    return np.ascontiguousarray(d) if off.nnz == 0 else None


def node_mass_blocks(mass_free, free, dim):
    """The node blocks of a mass that couples the DOFs of one node only: Westergaard's added mass ``m_a n n^T``
    lumped at the nodes of a curved face (an arch dam's extrados, where the normal is off the axes), the only
    non-diagonal mass an explicit stage takes. ``mass_free`` (n, n) CSR kg on the free DOFs ``free`` (n,)
    (model DOF ``node * dim + component``).

    Returns a list of ``(idx, M_b, M_b_inv)`` per block size s: ``idx`` (n_b, s) the free-equation indices of
    the DOFs of each coupled node, ``M_b`` (n_b, s, s) kg its block and ``M_b_inv`` its inverse (empty for a
    diagonal mass); None where the mass couples DOFs of different nodes (a consistent added mass, the
    incompressible acoustic water). The explicit step then solves ``M_b a_b = r_b`` at each coupled node: the
    scheme stays explicit (Belytschko, Liu & Moran 2000, sec. 6.2: a block-diagonal mass is inverted node by
    node)."""
    M = sp.csr_matrix(mass_free)
    coo = M.tocoo()
    off = (coo.row != coo.col) & (coo.data != 0.0)
    node = np.asarray(free) // dim
    rows, cols = coo.row[off], coo.col[off]
    if np.any(node[rows] != node[cols]):
        return None
    if not len(rows):
        return []
    coupled = np.isin(node, np.unique(node[rows]))
    eqs = np.flatnonzero(coupled)
    order = np.argsort(node[eqs], kind="stable")
    eqs = eqs[order]
    starts = np.flatnonzero(np.r_[True, np.diff(node[eqs]) != 0])
    groups = np.split(eqs, starts[1:])
    out = []
    for size in sorted({len(g) for g in groups}):
        idx = np.array([g for g in groups if len(g) == size], dtype=np.int64)
        Mb = np.asarray(M[idx.ravel()][:, idx.ravel()].todense()).reshape(len(idx), size, len(idx), size)
        Mb = np.ascontiguousarray(Mb[np.arange(len(idx)), :, np.arange(len(idx)), :])  # (n_b, s, s)
        out.append((idx, Mb, np.linalg.inv(Mb)))
    return out


def _solve_node_blocks(blocks, md, free, h, v_half, u0, u1, a0, a1, v1, works):
    """After the fused correction, which divided each DOF's force by the diagonal ``md`` (n,) kg: the
    accelerations and velocities of the coupled nodes from their blocks (``M_b a = r``, r = md a_diag), and the
    kinetic energy and inertia work of the step (``works[4]``, ``works[5]``) with the blocks instead of their
    diagonals. a0, a1, v1, u0, u1 (n_dof,); v_half (n,)."""
    for idx, Mb, Minv in blocks:
        dofs = free[idx]  # (n_b, s) model DOFs
        m_d = md[idx]
        a_diag, v_diag = a1[dofs], v1[dofs]
        a = np.einsum("bij,bj->bi", Minv, m_d * a_diag)
        v = v_half[idx] + 0.5 * h * a
        du = u1[dofs] - u0[dofs]
        works[4] += 0.5 * (np.einsum("bi,bij,bj->", v, Mb, v) - float(np.sum(m_d * v_diag * v_diag)))
        works[5] += 0.5 * (np.einsum("bi,bij,bj->", a0[dofs] + a, Mb, du) - float(np.sum(m_d * (a0[dofs] + a_diag) * du)))
        a1[dofs] = a
        v1[dofs] = v


def run_central_difference(model, settings, equations, energy, stats, stage, st, record_step, fail):
    """Integrate ``stage`` from the state ``st`` (a :class:`~.stage.StepState`) by central difference; returns
    the last state. Every step's joint states are committed; ``record_step(stage, k, st, n_steps)`` is called
    after each, ``fail(stage, st, exc)`` records the last state and raises."""
    m, s, eq = model, settings, equations
    free = eq.free
    n = eq.n
    md = eq.mass_diagonal
    blocks = []
    if md is None:  # a mass that couples the DOFs of single nodes (stability.check_time_step refused any other)
        blocks = eq.mass_blocks
        md = np.ascontiguousarray(eq.mass_free.diagonal())
    n_steps = stage.n_steps
    local_alpha = local_damping_coefficient(s.local_damping) if s.local_damping > 0.0 else 0.0
    empty = np.zeros(0)
    c_diag = _diagonal_damping(eq) if eq.damped else None
    viscous_sparse = eq.damped and c_diag is None
    if viscous_sparse:  # the stage's C lives in the model's pattern: keep its nonzeros only (dashpots on the
        # boundary nodes of a foundation are a small fraction of it)
        C = eq.damping_free.copy()
        C.eliminate_zeros()
    c_diag = empty if c_diag is None else c_diag
    # the damping force of the initial state, as the initial acceleration took it (its viscous part)
    fd0 = eq.damping_force(st.v[free]).copy() if eq.damped else np.zeros(n)
    pg0 = eq.ground_load(st.ag, st.tau).copy()
    water = eq.explicit_water
    if water is not None:  # the compressible reservoir, stepped with the dam
        wet, wet_dofs = eq.fluid.wet_eq, water.wet_dofs
        st.fluid = water.start(st.fluid, st.a[wet_dofs], eq.frame_at(st.ag), eq.bottom_at(st.tau, st.ag))
        pg0[wet] += st.fw
    hydro = 0.0
    works = np.zeros(10)
    for k in range(1, n_steps + 1):
        t_end, h = step_end(k, n_steps, s.dt, stage.duration, st.tau)
        if h <= 1e-9 * s.dt:
            break
        u = np.empty(m.n_dof)
        v_half = np.empty(n)
        central_difference_predict(free, st.u, st.v, st.a, h, u, v_half)
        m.time_step = h
        f_int, _ = m.evaluate(u, want_tangent=False)
        kc = m.continuum_force(u)
        ag1 = eq.ground_at(t_end)
        pg1 = eq.ground_load(ag1, t_end).copy()
        if water is not None:  # the water force of the predicted pressures acts on the dam at the step's end
            p1, pd_half = water.predict(st.fluid, h)
            fw1 = water.force(p1)
            pg1[wet] += fw1
        state_force = eq.update_state_force()
        cv = C @ v_half if viscous_sparse else empty
        v1 = np.zeros(m.n_dof)
        a1 = np.zeros(m.n_dof)
        fd1 = np.empty(n)
        status = central_difference_correct(free, h, md, eq.static_load, pg0, pg1, state_force, st.f_int, f_int,
                                            st.Kc_u, kc, st.u, u, st.a, v_half, cv, c_diag, local_alpha, fd0, fd1,
                                            v1, a1, works)
        if blocks and status == STATUS_OK:
            _solve_node_blocks(blocks, md, free, h, v_half, st.u, u, st.a, a1, v1, works)
        fluid1 = None
        if water is not None and status == STATUS_OK:  # the water's acceleration from the dam's
            fluid1 = water.correct(p1, pd_half, a1[wet_dofs], eq.frame_at(ag1), eq.bottom_at(t_end, ag1), h)
            # the water's work on the dam (counted in the kernel's input work): hydrodynamic
            hydro = 0.5 * float((st.fw + fw1) @ (u[wet_dofs] - st.u[wet_dofs]))
        if status != STATUS_OK or (water is not None and fluid1 is None):
            fail(stage, st, NumericalError(
                f"dynamic stage '{stage.name}': NaN or infinity at t = {st.t + h:.6g} s (central difference, "
                f"dt = {h:.4g} s; dt_crit = {stats.dt_critical:.4g} s)"))
        m.commit()
        new = StepState(st.t - st.tau + t_end, t_end, u, v1, a1, f_int, None, ag1)
        new.Kc_u = kc
        if water is not None:
            new.fluid, new.fw = fluid1, fw1
        energy.record_works(new, st, works, hydro)
        energy.accept(new)
        st = new
        fd0, pg0 = fd1, pg1
        stats.steps += 1
        record_step(stage, k, st, n_steps)
    return st
