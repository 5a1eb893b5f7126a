"""One implicit step of the generalized-alpha family: :class:`ImplicitStep` (one attempt at one step size) and
the joint-space systems it starts from (:class:`JointSpaces`).

The step's residual, divided by (1 - af), with the end-of-step displacements ``u`` (n_dof,) m as unknowns,

    R(u) = (1 - am)/(1 - af) M a1 + C v1 + f_int(u) + const,
    const = -p_{n+1} + am/(1 - af) M a_n + af/(1 - af) (C v_n + f_int(u_n) - p_n),

``a1``, ``v1`` from Newmark's updates (:func:`~.kernels.newmark_kinematics`; Chung & Hulbert 1993, Newmark 1959),
is solved first in joint space (:mod:`masonrydam.solvers.joint_space`), then by Newton iterations with the
iteration matrix ``K_eff = K_T + c_m M + c_c C`` (:class:`~.effective.EffectiveSolver`), the shared convergence
test, backtracking line search and cycle damping of :mod:`masonrydam.solvers.newton` and the chatter guard of
:mod:`masonrydam.solvers.chatter`. A step that gains mechanical energy, or whose local error is above the
tolerance (dt = "auto"), is refused before it is committed. Vectors named ``*_free`` or of length n_eq are on
the free DOFs. See docs/dynamics.md ("Newton per step", "Fast path").
"""
from __future__ import annotations

import math
import time
from operator import attrgetter

import numpy as np

from ...errors import NumericalError
from ..chatter import ChatterGuard
from ..joint_space import (MAX_INITIAL_STIFFNESS_ITERATIONS, SPLIT_INITIAL_STIFFNESS_ITERATIONS, JointSpace,
                           joint_space_size)
from ..linear.direct import SingularMatrix
from ..newton import ConvergenceTest, CycleDamping, backtracking_line_search, force_scale, newton_iterations
from .energy import energy_growth
from .kernels import euclidean_norm, free_norm, newmark_kinematics, newmark_residual, step_constant, step_loads
from .settings import OPEN_TANGENT_DYNAMIC
from .stage import StepState

#: a Newton iterate whose force residual is below this fraction of the force tolerance is converged
#: whatever the work test says (round-off level)
ROUNDOFF_FRACTION = 1e-3
#: a modified-Newton iteration (old factorization) is repeated only if it reduced the residual norm
#: at least by this factor; otherwise the next iteration refactorizes (or uses a low-rank update)
MODIFIED_NEWTON_CONTRACTION = 0.25
#: the joint-space Newton converges to this fraction of the step's force tolerance, so that the check
#: against the full residual, which adds the round-off of two substitutions, passes
JOINT_SPACE_FORCE_FRACTION = 0.5


class JointSpaces:
    """The joint-space systems of one stage, by step size: the nominal one (set up at the stage's start where
    the settings and the model allow, else none at all) and those of sub-step sizes, set up when first needed.

    ``effective``: the stage's :class:`~.effective.EffectiveSolver` (it factorizes and pins the all-stick matrix
    of a sub-step size); ``extra_levels``: the halvings of dt = "auto" (the stage's levels) on top of
    ``max_substeps``.
    """

    def __init__(self, model, settings, equations, effective, stats, extra_levels=0, stop_check=None):
        self.model, self.s, self.eq, self.effective, self.stats = model, settings, equations, effective, stats
        self.extra_levels = extra_levels
        #: asked before every joint-space iteration (:attr:`JointSpace.stop_check`); None: never
        self.stop_check = stop_check
        self.by_step = {}

    def set_up(self, reference):
        """Condense the nominal step on the nonlinear joints from the all-stick factorization ``reference`` if
        the settings and the model allow."""
        s, m = self.s, self.model
        if s.joint_space == "off" or not m.nonlinear or not m.condensable:
            return
        size = joint_space_size(m)
        self._new(reference, s.dt)
        self.stats.joint_space_size = size

    def _new(self, reference, h):
        t0 = time.perf_counter()
        # the stored recovery columns (n_eq x m) only at the nominal step size, and a quarter of the
        # memory for flexibility columns at a sub-step size: sub-steps are rare
        nominal = h == self.s.dt
        js = self.by_step[h] = JointSpace(self.model, reference.fact, store_columns=nominal,
                                          column_memory_share=1.0 if nominal else 0.25)
        js.stop_check = self.stop_check
        self.stats.joint_space_setup_s += time.perf_counter() - t0
        return js

    def for_step(self, h):
        """The joint-space system of step size h: the nominal one, or one of a sub-step size (its
        all-stick matrix factorized and pinned, and its flexibility set up, when first needed; not
        for a large joint set, whose sub-steps take the general path); None where there is none."""
        if not self.by_step:
            return None
        js = self.by_step.get(h)
        if js is None:
            levels = self.s.max_substeps + self.extra_levels
            if not any(h == self.s.dt / 2 ** k for k in range(1, levels + 1)):
                return None  # e.g. a shorter last step of the stage: not worth a set-up
            if self.by_step[self.s.dt].columns.lazy:
                return None
            ref = self.effective.factorize(self.eq.elastic_effective(h), pin=True, key=("elastic", h),
                                           symmetric=True)
            js = self._new(ref, h)
        return js

    def close(self):
        """Add the systems' counts to the stats and let their factors and columns go (each stage sets up its
        own)."""
        for js in self.by_step.values():
            self.stats.joint_space_dense_factorizations += js.factorizations
            self.stats.joint_space_dense_updates += js.updates
            self.stats.joint_space_holds += js.hold_events
            self.stats.joint_space_column_recoveries += js.column_recoveries
            self.stats.joint_space_flexibility_columns += js.columns.computed
            self.stats.joint_space_flexibility_s += js.columns.seconds
            self.stats.joint_space_compiled_steps += js.compiled_steps
            self.stats.joint_space_python_steps += js.python_steps
        self.stats.joint_space_column_bytes = max(
            self.stats.joint_space_column_bytes,
            sum(js.XT.nbytes for js in self.by_step.values() if js.XT is not None))
        self.by_step = {}


class Iterate:
    """A Newton iterate of the step: ``u`` (n_dof,) m, ``f_int`` (n_dof,) N, ``Kdata`` the tangent's values (None:
    the all-stick tangent), the residual ``R`` (n_eq,) N, ``a1`` (n_eq,) m/s2 and ``v1`` (n_eq,) m/s at the step's
    end, ``Cv`` (n_eq,) N the damping force ``C v1`` (kept with the state the step ends in: the energy balance
    and the next step's constant part use it), and ``ma_norm`` the norm of the inertia force (N)."""

    __slots__ = ("u", "f_int", "Kdata", "R", "a1", "v1", "Cv", "ma_norm", "_f_norm", "_r_norm")

    def __init__(self, u, f_int, Kdata, R, a1, v1, Cv, ma_norm):
        self.u, self.f_int, self.Kdata = u, f_int, Kdata
        self.R, self.a1, self.v1, self.Cv, self.ma_norm = R, a1, v1, Cv, ma_norm
        self._f_norm = self._r_norm = None

    def internal_force_norm(self, free) -> float:
        """The norm of the internal forces on the free DOFs ``free`` (N), computed once."""
        if self._f_norm is None:
            self._f_norm = free_norm(self.f_int, free)
        return self._f_norm

    @property
    def residual_norm(self) -> float:
        """``||R||`` (N), computed once (an iterate is not changed after its evaluation)."""
        if self._r_norm is None:
            self._r_norm = euclidean_norm(self.R)
        return self._r_norm


class ImplicitStep:
    """One attempt at one implicit step of size ``h`` from the committed state ``st`` (a
    :class:`~.stage.StepState`) to stage time ``t_end``; :meth:`solve` runs it.

    The collaborators are the stage's: ``equations`` (:class:`~.equations.StageEquations`), ``effective``
    (:class:`~.effective.EffectiveSolver`), ``energy`` (:class:`~.energy.EnergyBalance`), ``joint_spaces``
    (:class:`JointSpaces`) and ``stats``; ``count_iterations(n)`` is told of every iteration taken.
    """

    def __init__(self, model, settings, equations, effective, energy, joint_spaces, stats, count_iterations,
                 st, t_end, h, stop_check=None):
        #: called before every general Newton iteration (None: never); raises to stop within the step
        self.stop_check = stop_check
        self.model, self.s, self.eq, self.effective = model, settings, equations, effective
        self.energy, self.joint_spaces, self.stats = energy, joint_spaces, stats
        self.count_iterations = count_iterations
        self.st, self.t_end, self.h = st, t_end, h
        m, s, eq = model, settings, equations
        m.time_step = h  # (Perzyna laws of elasto-plastic blocks)
        free = self.free = eq.free
        beta, gamma, am, af = s.coefficients()
        self.beta, self.gamma = beta, gamma
        self.w_m = (1.0 - am) / (1.0 - af)
        ag1 = self.ag1 = eq.ground_at(t_end)
        sf = eq.update_state_force()
        n = eq.n
        p1, pn = np.empty(n), np.empty(n)
        #: the earthquake loads (ground, time-given and state forces) at the step's ends, for the energy balance
        self.pg1, self.pg0 = np.empty(n), np.empty(n)
        step_loads(eq.static_load, eq.ground_load(ag1, t_end), eq.ground_load(st.ag, st.tau), sf, p1, pn,
                   self.pg1, self.pg0)
        un, vn, an = st.free_values(free)
        self.un, self.vn, self.an = un, vn, an
        fluid = self.fluid = eq.fluid
        if fluid is not None:
            # the water's force at the end of the step, less its M_w a1 part (added in residual below)
            wet = self.wet = fluid.wet_eq
            g_w, self.fluid_context = fluid.start(st.fluid, h, an[wet], eq.frame_at(st.ag), eq.frame_at(ag1),
                                                  eq.bottom_at(st.tau, st.ag), eq.bottom_at(t_end, ag1))
            self.water_mass = fluid.mass_block(h)
            p1[wet] += g_w
            pn[wet] += st.fw
        const = np.empty(n)
        weight_m, weight_f = am / (1.0 - af), af / (1.0 - af)
        step_constant(p1, pn, eq.kernel_mass_diagonal,
                      eq.mass_free @ an if am != 0.0 and eq.mass_diagonal is None else eq.zeros_free, an, weight_m,
                      self._damping_force_at_start() if af != 0.0 else eq.zeros_free, st.f_int, free, weight_f,
                      const)
        self.const = const
        self.inertia_damping = eq.inertia_damping(h)
        self.nonlinear = m.nonlinear
        self.p1_norm = euclidean_norm(p1)
        #: every joint point has stuck at the iterates so far (the step started so): forces only, and the
        #: elastic tangent while they all still stick
        self.sticking_so_far = st.Kdata is None
        self.guard = ChatterGuard(m, OPEN_TANGENT_DYNAMIC)
        self.test = ConvergenceTest(s.force_tolerance, s.energy_tolerance, ROUNDOFF_FRACTION)
        #: the norm of the step's first residual (N), the Newton state of the effective-matrix solves
        self.r0 = 0.0
        self.kind_prev, self.rn_prev, self.allow_modified = None, math.inf, s.modified_newton
        self.damping = CycleDamping()

    def _damping_force_at_start(self):
        """``C v_n`` (n_eq,) N: the one the step that ended in the start state computed, else the product."""
        cv = self.st.cv
        return cv if cv is not None else self.eq.damping_force(self.vn)

    # -- the step's equations -----------------------------------------------------------------------
    def residual(self, u, f_int):
        """(R, a1, v1, C v1, ||M a1||) at the displacements ``u`` with internal forces ``f_int``."""
        eq, free = self.eq, self.free
        n = len(self.un)
        R, a1, v1, Ma = (np.empty(n) for _ in range(4))
        newmark_kinematics(u, free, self.un, self.vn, self.an, self.h, self.beta, self.gamma, eq.kernel_mass_diagonal,
                           a1, v1, Ma)
        if eq.mass_diagonal is None:
            Ma = eq.mass_free @ a1
        if self.fluid is not None:
            Ma[self.wet] += self.water_mass @ a1[self.wet]
        if eq.damped:  # a new velocity: the product, kept with the iterate
            Cv = eq.damping_free @ v1
        else:
            Cv = eq.zeros_free
        if newmark_residual(Ma, self.w_m, Cv, f_int, free, self.const, R) != 0:
            raise NumericalError("NaN or infinity in the dynamic residual")
        return R, a1, v1, Cv, euclidean_norm(Ma)

    def evaluate(self, u):
        """(f_int, tangent values or None for the all-stick tangent) at ``u``."""
        m = self.model
        if self.nonlinear:
            if self.sticking_so_far and not self.guard.stabilized:
                # joints sticking so far: forces only, and the elastic tangent if all still stick
                f, _ = m.evaluate(u, want_tangent=False)
                if self.eq.all_stick():
                    return f, None
            f, K = m.evaluate(u, want_tangent=True)
            if self.guard.stabilized:
                m.latch_broken_bonds()
            self.sticking_so_far = False
            return f, K.data
        f, _ = m.evaluate(u, want_tangent=False)
        return f, None

    def iterate_at(self, u, f_int=None, Kdata=None):
        """The :class:`Iterate` at ``u``, evaluated there unless its forces ``f_int`` (and tangent) are given."""
        if f_int is None:
            f_int, Kdata = self.evaluate(u)
        R, a1, v1, Cv, ma_norm = self.residual(u, f_int)
        return Iterate(u, f_int, Kdata, R, a1, v1, Cv, ma_norm)

    # -- the attempt ----------------------------------------------------------------------------------
    def solve(self, can_split=True, error_check=None, split_joint_space=True, joint_space_result=None):
        """Returns (ok, new_state, why). ``can_split``: the caller can still halve the step, so a joint-space
        iteration that does not converge and a step that gains energy are refused (ok False) rather than
        finished in the general path or accepted. ``error_check(new, st, h)``: dt = "auto"'s local error test
        before the step is committed (a reason string refuses it). ``split_joint_space`` False: a joint-space
        iteration that does not converge goes on in the general path at this step size even where the step
        could be halved (dt = "auto": the error decides the step size; halving for the joint-space iteration's
        sake took 2 484 of 2 801 refusals on the Koyna example at tolerance 1e-5 and held the steps small
        after them). ``joint_space_result``: called in place of the joint space's ``solve_step`` (the result of a
        joint-space call the compiled loop made for this step, :mod:`.compiled_loop`)."""
        m, st = self.model, self.st
        u, f_int, Kdata = st.u.copy(), st.f_int, st.Kdata
        if m.rate_dependent:  # viscous blocks relax over the step even where u does not move: their force
            f_int, Kdata = self.evaluate(u)  # at the predictor is not the one the step started with
        try:
            current = self.iterate_at(u, f_int, Kdata)
            r0 = current.residual_norm
            js = self.joint_spaces.for_step(self.h)
            if js is not None:
                current, why = self._joint_space_start(js, current, can_split, split_joint_space, joint_space_result)
                if current is None:
                    return False, None, why
            current, why = self._newton(current, r0)
            if current is None:
                return False, None, why
        except SingularMatrix as exc:
            return False, None, f"singular effective matrix ({exc})"
        except NumericalError as exc:
            return False, None, str(exc)
        finally:
            if self.guard.stabilized:
                m.set_open_tangent(OPEN_TANGENT_DYNAMIC)
        return self._finish(current, can_split, error_check)

    def _joint_space_start(self, js, current, can_split, split_joint_space, joint_space_result=None):
        """The step condensed on the joints (:mod:`masonrydam.solvers.joint_space`): its solution from one or
        two substitutions, or its last iterate, as the iterate the Newton iterations go on from (they accept
        it at once when the full residual is within tolerance); (None, why) where the step is to be halved."""
        s, m = self.s, self.model
        ref = self.force_scale(current)
        try:
            u_js, its, converged, why = (joint_space_result or js.solve_step)(
                current.u, current.R, JOINT_SPACE_FORCE_FRACTION * s.force_tolerance * ref,
                SPLIT_INITIAL_STIFFNESS_ITERATIONS if can_split and split_joint_space
                else MAX_INITIAL_STIFFNESS_ITERATIONS)
        except FloatingPointError:
            u_js, its, converged = None, 0, False
        self.stats.joint_space_iterations += its
        self.stats.joint_space_store_full += js.store_full
        self.count_iterations(its)
        if u_js is not None:
            f_j, _ = m.evaluate(u_js, want_tangent=False)
            self.sticking_so_far = True
            current = self.iterate_at(u_js, f_j, None)
            ref = self.force_scale(current)
            converged = converged and current.residual_norm <= s.force_tolerance * ref
        if converged:
            self.stats.joint_space_steps += 1
        elif can_split and split_joint_space and not js.columns.lazy:
            # halve the step (the joint-space systems of the halves are set up once): cheaper
            # than finishing it in the general path, which refactorizes at state changes. Not
            # with a large joint set (flexibility columns computed as needed): a sub-step size
            # would need its own L D L^T and thousands of columns (7 s and 5 000 columns on
            # the 3D dam example at element_size 6), and a step that needed more columns than
            # the store holds would need about as many halved; the general path goes on from
            # the last joint-space iterate instead
            self.stats.joint_space_splits += 1
            return None, f"the joint-space iteration did not converge ({why})"
        else:
            self.stats.joint_space_fallbacks += 1
        return current, ""

    def _newton(self, current, r0):
        """Newton iterations from ``current`` (``r0``: the norm of the step's first residual); returns (the
        converged iterate, "") or (None, why)."""
        m, s = self.model, self.s
        self.r0 = r0
        self.kind_prev, self.rn_prev, self.allow_modified = None, math.inf, s.modified_newton
        self.damping = CycleDamping()
        result = newton_iterations(self, current, self.test, s.max_iterations,
                                   guard=self.guard if self.nonlinear else None,
                                   on_check=None if self.stop_check is None else lambda it, rn, scale: self.stop_check())
        if result.converged:
            return result.iterate, ""
        last = result.iterate
        why = (f"Newton residual {last.residual_norm / self.force_scale(last, result.iterations):.3g} of the force "
               f"scale (tolerance {s.force_tolerance:g}) after {result.iterations} iterations")
        if self.nonlinear:
            nchg = sum(int((g.state_codes(trial=True) != g.state_codes(trial=False)).sum())
                       for g in m.igroups if g.nonlinear)
            why += f"; {nchg} joint point(s) changed state in the step"
        return None, why

    # -- the Newton step (masonrydam.solvers.newton.NewtonStep) -----------------------------------------
    def force_scale(self, iterate, iteration=0):
        """Force scale of the convergence test (N): the inertia, internal and end-of-step external forces and,
        after the first iteration, the step's first residual."""
        return force_scale(iterate.ma_norm, iterate.internal_force_norm(self.free), self.p1_norm,
                           self.r0 if iteration > 0 else 0.0)

    def after_guard(self, iterate, action):
        self.stats.stabilized_steps += action == "stabilize"
        return self.iterate_at(iterate.u)

    def correction(self, iterate):
        """The correction from the effective-matrix solver: modified Newton (the latest factorization, only
        with ``modified_newton``) while it contracts well, once it does not exact iteration matrices for the
        rest of the step; damped while the residual norm comes back every other iteration."""
        rn = iterate.residual_norm
        if self.kind_prev == "modified" and rn > MODIFIED_NEWTON_CONTRACTION * self.rn_prev:
            self.allow_modified = False
        if iterate.Kdata is None:
            dx, self.kind_prev = self.effective.solve(self.eq.elastic_effective(self.h), -iterate.R,
                                                      allow_inexact=self.allow_modified, key=("elastic", self.h))
        else:
            dx, self.kind_prev = self.effective.solve(iterate.Kdata + self.inertia_damping, -iterate.R,
                                                      allow_inexact=self.allow_modified)
        self.rn_prev = rn
        if self.damping.observe(rn):
            self.stats.damped_iterations += 1
        return self.damping.factor * dx

    def advance(self, iterate, dx):
        """The iterate along ``dx``: the full step, or a shorter one of the backtracking line search on the
        residual norm where the full step does not reduce it (joint laws are non-smooth: a full Newton step can
        jump across many stick/slip/open switches and cycle)."""
        free, u, rn = self.free, iterate.u, iterate.residual_norm
        work_here = abs(float(dx @ iterate.R))

        def iterate_along(step):
            u_s = u.copy()
            u_s[free] += step * dx
            return self.iterate_at(u_s)

        u_try = u.copy()
        u_try[free] += dx
        step, new = 1.0, self.iterate_at(u_try)
        if self.nonlinear and self.s.line_search and new.residual_norm > rn:
            step, new = backtracking_line_search(iterate_along, attrgetter("residual_norm"), new.residual_norm, rn)
            if step != 1.0:
                self.stats.line_searches += 1
        self.stats.iterations += 1
        self.count_iterations(1)
        return new, work_here, abs(float(step * (dx @ new.R)))

    def _finish(self, current, can_split, error_check):
        """The converged iterate as the step's end state: its energy balance, the refusals of a step that
        gains energy or whose local error is too large, then the commit. Returns (ok, new_state, why)."""
        m, s, st, free = self.model, self.s, self.st, self.free
        retangent = self.guard.stabilized  # tangent for the next step's predictor with the ordinary open tangent
        u = current.u
        Kdata = current.Kdata
        new = StepState(st.t - st.tau + self.t_end, self.t_end, u, np.zeros_like(st.v), np.zeros_like(st.a),
                        current.f_int, Kdata.copy() if Kdata is not None else None, self.ag1)
        new.v[free] = current.v1
        new.a[free] = current.a1
        new.keep_free_values(free, current.v1, current.a1)
        new.cv = current.Cv
        new.Kc_u = m.continuum_force(u)
        if self.fluid is not None:
            new.fluid = self.fluid.finish(self.fluid_context, current.a1[self.wet])
            new.fw = self.fluid.force(new.fluid)
        self.energy.record(new, st, self.pg0, self.pg1)
        if can_split and self.nonlinear and s.energy_growth_tolerance > 0:
            # the trapezoidal work of a joint point that opens or closes within the step is not the
            # change of its stored energy (Armero & Petocz 1998, Comput. Methods Appl. Mech. Eng. 158;
            # Laursen & Chawla 1997, IJNME 40): with an implicit scheme an impact can create energy.
            # A step that raises the mechanical energy above what the loads supplied (cumulative,
            # beyond energy_growth_tolerance x the largest energy term) is split; at the last halving
            # it is accepted and counted (stats.energy_growth_max).
            g = energy_growth(new.energy)
            cap = s.energy_growth_tolerance * self.energy.scale
            allowed = max(cap, energy_growth(st.energy) + 0.01 * cap)
            if g > allowed and self.energy.scale > 0:
                self.stats.energy_rejections += 1
                return False, None, (f"the step raised the mechanical energy to {g:.3g} J above the work of the "
                                     f"loads (joint impact; allowed {allowed:.3g} J)")
        if error_check is not None:
            why = error_check(new, st, self.h)
            if why:
                return False, None, why
        m.commit()
        if retangent:
            _, K = m.evaluate(u, want_tangent=True)
            new.Kdata = None if self.eq.all_stick() else K.data.copy()
        self.energy.accept(new)
        return True, new, ""
