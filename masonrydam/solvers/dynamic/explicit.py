"""The explicit scheme: central difference in velocity form, one joint evaluation per step.

    v_{n+1/2} = v_n + h/2 a_n,   u_{n+1} = u_n + h v_{n+1/2},
    M a_{n+1} = p_{n+1} - f_int(u_{n+1}) - C v_{n+1/2},   v_{n+1} = v_{n+1/2} + h/2 a_{n+1}

(Hughes 2000, sec. 9.1.2; Belytschko, Liu & Moran 2000, Box 6.1): lumped (diagonal) mass only, the damping
force lagged half a step, dt below the critical step (:mod:`.stability`). Vectors on the free DOFs (n_eq,),
SI units. See docs/dynamics.md.
"""
from __future__ import annotations

import numpy as np

from ...errors import NumericalError
from .stage import StepState
from .step_control import step_end


def run_central_difference(model, settings, equations, energy, stats, stage, st, record_step, fail):
    """Integrate ``stage`` from the state ``st`` (a :class:`~.stage.StepState`) by central difference; returns
    the last state. Every step's joint states are committed; ``record_step(stage, k, st, n_steps)`` is called
    after each, ``fail(stage, st, exc)`` records the last state and raises."""
    m, s, eq = model, settings, equations
    free = eq.free
    md = eq.mass_diagonal
    n_steps = stage.n_steps
    for k in range(1, n_steps + 1):
        t_end, h = step_end(k, n_steps, s.dt, stage.duration, st.tau)
        if h <= 1e-9 * s.dt:
            break
        v_half = st.v[free] + 0.5 * h * st.a[free]
        m.time_step = h
        u = st.u.copy()
        u[free] += h * v_half
        f_int, _ = m.evaluate(u, want_tangent=False)
        ag1 = eq.ground_at(t_end)
        rhs = eq.static_load + eq.ground_load(ag1, t_end) + eq.update_state_force() - f_int[free] \
            - eq.damping_force(v_half)
        a1 = rhs / md
        if not np.isfinite(a1).all():
            fail(stage, st, NumericalError(
                f"dynamic stage '{stage.name}': NaN or infinity at t = {st.t + h:.6g} s (central difference)"))
        m.commit()
        new = StepState(st.t - st.tau + t_end, t_end, u, np.zeros_like(st.v), np.zeros_like(st.a), f_int, None, ag1)
        new.a[free] = a1
        new.v[free] = v_half + 0.5 * h * a1
        new.Kc_u = m.continuum_force(u)
        energy.record(new, st)
        energy.accept(new)
        st = new
        stats.steps += 1
        record_step(stage, k, st, n_steps)
    return st
