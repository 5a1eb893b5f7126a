"""Arc-length control of a static stage: following a load-displacement path past limit points,
snap-throughs and snap-backs, where load or displacement control stalls.

:class:`ArcLengthStage` runs a static stage whose loading is one parameter ``lambda`` (forces ``f_base +
lambda F`` in N, prescribed displacements ``u_start,p + lambda Delta_p`` in m) with the free displacements
(n_free,) m and ``lambda`` as unknowns, closed by one of three constraints (``mode``): Crisfield's cylindrical
arc length ``|Delta u_f| = Delta l`` (Crisfield 1981; Crisfield 1991, vol. 1, sec. 9.3), the opening of the
softening joints (``"opening"``, de Borst 1987), or the energy the joints dissipate per step
(``"dissipation"``, :mod:`.dissipation`; Gutierrez 2004; Verhoosel, Remmers & Gutierrez 2009). It ends at
``lambda = 1``, below 0, or after :data:`MAX_STEPS_PER_NOMINAL` times the stage's steps.

Theory: docs/masonry_softening.md, section "The arc-length stage in equations" (under "Following the path past
the peak").
"""
from __future__ import annotations

import math

import numpy as np

from ...errors import ConvergenceError, NumericalError
from ..linear.direct import SingularMatrix
from .dissipation import JointDissipation

#: an arc-length stage may take this many times its nominal steps before it gives up
MAX_STEPS_PER_NOMINAL = 20
#: the arc may grow to this many times the first one (a stiff structure's elastic increment is tiny next to
#: the rotation or sliding of a mechanism that follows its peak)
DL_MAX_FACTOR = 1e6
#: iterations an arc-length step aims at (Delta l grows or shrinks with sqrt(target / iterations)); indirect
#: displacement control of many softening joints takes more per step and aims higher, or its steps stall
TARGET_ITERATIONS = {"cylindrical": 6, "opening": 10, "dissipation": 8}
#: dissipation control starts after the first step whose joints dissipate more than this part of the work done
#: on the model in that step (before it the stage's own control follows an all but elastic path)
DISSIPATION_SWITCH = 0.01
#: a dissipation step is converged when its joints dissipate the target within this part of it (and the
#: residual is within the solver's force tolerance)
DISSIPATION_TOLERANCE = 0.05
#: where the stage's own control stalls before any dissipation was measured, the first target is this part of
#: the work done on the model in the stage so far
DISSIPATION_START_FRACTION = 1e-3
#: a dissipation step that raises the load factor by more than a nominal step is retried with a target this many
#: times at most (in proportion), then taken under the stage's own control
MAX_SHRINKS = 3
#: a step under the stage's own control that dissipates more than this many targets passed over a snap-back
#: (it found an equilibrium on another branch): dissipation control takes it instead
JUMP_FACTOR = 4.0
#: a dissipation step halves its target this many times at most before the stage's own control is tried with
#: its cuts (a point where neither goes on is left to the other path-following controls, see
#: :meth:`~.stepping.StaticSolver._run`)
DISSIPATION_CUTS = 4


class ArcLengthStage:
    """One static stage run under arc-length control by ``solver`` (a :class:`~.static.StaticSolver`)
    from ``u`` at ``lam0``: ``run()`` returns (u, lam, steps). ``f_base``: the loads of the earlier
    stages (N, full DOF); ``u_start``: the displacements at the start of the stage (the prescribed
    increments are measured from it); ``dl0``: the first arc length (m), or None to take that of one
    nominal increment; ``record(u, lam, f_int, f_ext)``: called after every converged step."""

    def __init__(self, solver, stage, u, u_start, f_base, lam0, record, dl0=None, direction=None,
                 mode="cylindrical", direction_dlam=None):
        self.solver, self.st = solver, stage
        self.m = solver.model
        self.u, self.u_start, self.f_base, self.lam = u.copy(), u_start, f_base, lam0
        self.record = record
        self.free = self.m.dofmap.free
        self.delta_p = np.where(stage.prescribed, stage.increment, 0.0)
        self.dl0 = dl0
        self.prev = direction  # the last converged increment of u_f (its direction steers the predictor)
        self.prev_dlam = direction_dlam  # and of the load factor, where known
        #: "cylindrical" (|Delta u_f| = Delta l), "opening" (indirect displacement control: the opening of
        #: the joints that crack grows by Delta l per step, :meth:`_opening_vector`) or "dissipation"
        self.mode = mode
        self.c = None

    def _state(self, u_f, lam):
        u = self.u.copy()
        u[self.free] = u_f
        st = self.st
        u[st.prescribed] = self.u_start[st.prescribed] + lam * st.increment[st.prescribed]
        return u, self.f_base + lam * st.force

    def _q(self):
        """dr/dlambda on the free DOFs at the last evaluation (its tangents)."""
        q = self.st.force.copy()
        if self.st.prescribed.any():
            q -= self.m.tangent_product(self.delta_p)
        return q[self.free]

    def _opening_vector(self, all_points=False):
        """``c`` (free DOFs): ``c . u`` is the area-weighted mean normal opening (m) of the joint points that
        are opening (cracking), or else in tension, in the last converged state:
        the quantity indirect displacement control makes grow (de Borst 1987, Comput. Struct. 25:211-224;
        the crack opening of a softening joint grows monotonically through a snap-back, where the global
        displacement norm turns back). ``all_points``: every point of the nonlinear joints where none
        qualifies (a stage that starts unloaded). None when there is none."""
        m, dim = self.m, self.m.dim
        c = np.zeros(m.n_dof)
        found, total = False, 0.0
        for g in m.igroups:
            if not g.nonlinear:
                continue
            # cracking points: open in the last converged state (Mohr-Coulomb's OPEN; the composite law's tension
            # and tension-shear corner)
            active = g.is_open(trial=False)
            if not active.any():
                active = g.traction[:, :, dim - 1] > 0.0  # else those in tension
            if not active.any():
                if not all_points:
                    continue
                active = np.ones_like(active)
            found = True
            ns = g.conn.shape[1] // 2
            w = g.jw * g.thickness[:, None]  # (ne, nip) m2
            for e, q in zip(*np.nonzero(active)):
                total += w[e, q]
                n = g.frame[e, q, dim - 1]
                for a in range(ns):
                    coef = w[e, q] * g.N[q, a] * n
                    c[g.conn[e, ns + a] * dim:(g.conn[e, ns + a] + 1) * dim] += coef
                    c[g.conn[e, a] * dim:(g.conn[e, a] + 1) * dim] -= coef
        if not found:
            return None
        return c[self.free] / total

    def _first_arc(self):
        """The length of one nominal increment: the free-DOF part of a tangent (elastic) step."""
        u, _ = self._state(self.u[self.free], self.lam)
        _, K = self.m.evaluate(u, want_tangent=True)
        dq = self.solver._factorize(K).solve(self._q())
        self.m.revert()
        return float(np.linalg.norm(dq)) / self.st.steps, dq

    def run(self):
        if self.mode == "dissipation":
            return self._run_dissipation()
        s, m, free = self.solver.s, self.m, self.free
        if self.dl0 is None:
            self.dl0, dq = self._first_arc()
            if self.prev is None:
                self.prev = dq
        if self.mode == "opening":
            self.c = self._opening_vector(all_points=True)
            if self.c is None:
                raise NumericalError(f"stage '{self.st.name}': indirect displacement control found no joint "
                                     "point cracking, slipping or in tension to follow")
            grow = abs(float(self.c @ self.prev)) if self.prev is not None else 0.0
            self.dl0 = grow if grow > 0 else 1e-6  # the last step's mean opening, or 1 um
        if not self.dl0 > 0:
            raise NumericalError(f"stage '{self.st.name}': arc-length control found no displacement to follow")
        dl = self.dl0
        dl_min, dl_max = self.dl0 / 2.0 ** s.max_step_cuts, DL_MAX_FACTOR * self.dl0
        steps = 0
        self.peak = self.lam
        while self.lam < 1.0 - 1e-12:
            if steps >= MAX_STEPS_PER_NOMINAL * self.st.steps:
                if self.st.until_failure:
                    break
                raise ConvergenceError(f"stage '{self.st.name}': arc-length control took {steps} steps and reached "
                                       f"load factor {self.lam:.4g} of 1; the path winds back (a snap-back "
                                       "cascade) or the arc is too short")
            if self.mode == "opening" and steps:  # the points that crack now
                c = self._opening_vector()
                self.c = self.c if c is None else c
            ok, u_f, lam, its, f_int, f_ext = self._step(dl)
            if not ok:
                m.revert()
                dl /= 2.0
                self.solver.stats.step_cuts += 1
                if dl < dl_min:
                    raise ConvergenceError(f"stage '{self.st.name}': arc-length control found no equilibrium "
                                           f"beyond load factor {self.lam:.4g} (arc {dl * 2:.3g} m after "
                                           f"{s.max_step_cuts} cuts)")
                continue
            if lam > 1.0:  # past the end of the stage: the last step onto lambda = 1, controlled
                m.revert()
                ok, u1, its1, f_int1, f_ext1 = self._controlled(1.0)
                if ok:
                    u_f, lam, its, f_int, f_ext = u1[free], 1.0, its1, f_int1, f_ext1
                else:
                    m.revert()
                    dl /= 2.0
                    continue
            steps += 1
            self._accept(u_f, lam, f_int, f_ext)
            dl = float(np.clip(dl * math.sqrt(TARGET_ITERATIONS[self.mode] / max(its, 1)), dl / 2.0, 2.0 * dl))
            dl = min(max(dl, dl_min), dl_max)
            if lam < 0.0:  # unloaded completely: the rest of the stage is not on this path
                break
        return self.u, self.lam, steps

    def _accept(self, u_f, lam, f_int, f_ext, on_commit=None):
        """Take a converged step onto ``(u_f, lam)``: its increment kept as the next predictor's direction, the
        model's state committed (then ``on_commit()``, before anything reads the state again), the step
        counted and recorded."""
        self.prev, self.prev_dlam = u_f - self.u[self.free], lam - self.lam
        self.u, _ = self._state(u_f, lam)
        self.lam = lam
        self.peak = max(self.peak, lam)
        self.m.commit()
        if on_commit is not None:
            on_commit()
        self.solver.stats.steps += 1
        self.solver.stats.arc_length_steps += 1
        self.record(self.u, lam, f_int, f_ext)

    def _controlled(self, lam):
        """A step onto ``lam`` under the stage's own (load or displacement) control."""
        u, f_ext = self._state(self.u[self.free], lam)
        ok, u_new, its, f_int = self.solver._newton_plain(u, f_ext)
        return ok, u_new, its, f_int, f_ext

    def _iterate(self, u_f, lam, it):
        """The residual at an iterate of a step: (f_int, K, f_ext, r, |r|, force scale), or None where a law
        gives up at an iterate past the first (one far off the path: the step is cut)."""
        u, f_ext = self._state(u_f, lam)
        try:
            f_int, K = self.m.evaluate(u, want_tangent=True)
        except NumericalError:
            if it == 0:
                raise
            return None
        r = (f_ext - f_int)[self.free]
        if not np.isfinite(r).all():
            raise NumericalError("NaN or infinity in the residual (check loads and stiffnesses)")
        ref = max(float(np.linalg.norm(f_ext)), float(np.linalg.norm(f_int)), 1e-30)
        return f_int, K, f_ext, r, float(np.linalg.norm(r)), ref

    def _solve_pair(self, K, r):
        """``(K^-1 r, K^-1 q)`` with one factorization (q: :meth:`_q`), or None where K is singular."""
        try:
            fact = self.solver._factorize(K)
            pair = fact.solve(r), fact.solve(self._q())
        except SingularMatrix:
            return None
        self.solver.stats.iterations += 1
        return pair

    def _step(self, dl):
        """One arc-length step of length ``dl``: (ok, u_f, lambda, iterations, f_int, f_ext)."""
        s, free = self.solver.s, self.free
        u0_f = self.u[free].copy()
        u_f, lam = u0_f.copy(), self.lam
        Du = np.zeros_like(u0_f)
        ref0 = None
        for it in range(s.max_iterations + 1):
            at = self._iterate(u_f, lam, it)
            if at is None:
                return False, None, None, it, None, None  # an iterate far off the path: the arc is cut
            f_int, K, f_ext, r, rn, ref = at
            ref0 = rn if ref0 is None else ref0
            if it > 0 and rn <= s.force_tolerance * max(ref, ref0):
                return True, u_f, lam, it, f_int, f_ext
            if it == s.max_iterations:
                break
            pair = self._solve_pair(K, r)
            if pair is None:
                return False, None, None, it, None, None
            du_r, du_q = pair
            if self.mode == "opening":  # linear constraint c . Delta u = dl: dlambda in closed form
                cq = float(self.c @ du_q)
                if cq == 0.0:
                    return False, None, None, it, None, None
                target = dl if it == 0 else dl - float(self.c @ Du)
                dlam = (target - float(self.c @ du_r)) / cq
                du = du_r + dlam * du_q
            elif it == 0:
                nq = float(np.linalg.norm(du_q))
                if not nq > 0:
                    return False, None, None, it, None, None
                sign = 1.0 if self.prev is None or float(self.prev @ du_q) >= 0.0 else -1.0
                dlam = sign * dl / nq
                du = dlam * du_q  # (r = 0 at a converged start)
                du += du_r
            else:
                w = Du + du_r
                a = float(du_q @ du_q)
                b = 2.0 * float(du_q @ w)
                c = float(w @ w) - dl * dl
                disc = b * b - 4.0 * a * c
                if not (a > 0 and disc >= 0.0):
                    return False, None, None, it, None, None
                root = math.sqrt(disc)
                cands = [(-b + root) / (2.0 * a), (-b - root) / (2.0 * a)]
                # Crisfield's choice: the new increment closest in direction to the one before
                dlam = max(cands, key=lambda x: float((w + x * du_q) @ Du))
                du = du_r + dlam * du_q
            Du = Du + du
            u_f = u_f + du
            lam = lam + dlam
        return False, None, None, s.max_iterations, None, None

    # -- dissipation-based control ----------------------------------------------------------------------
    def _run_dissipation(self):
        """The stage under dissipation-based control (module docstring); returns (u, lam, steps).

        Two ways of stepping, ``by_dissipation`` or not (the stage's own control, load-factor increment ``h``).
        The stage's own control runs until a step dissipates (more than :data:`DISSIPATION_SWITCH` of its work)
        or fails. Dissipation control then runs until a step would raise the load factor by more than a
        nominal step even with a target shrunk in proportion (the joints dissipate next to nothing: elastic
        reloading, the tail of an open crack); the stage's own control takes over again until it fails or
        jumps (dissipates more than :data:`JUMP_FACTOR` targets in a step: it passed over a snap-back). Where
        a dissipation step fails, a step under the stage's own control is tried once (accepted unless it
        jumps), then the target is halved; below its least value the stage's own control takes over with its
        own cuts, and where that fails too the stage ends with an error."""
        s, m, free, st = self.solver.s, self.m, self.free, self.st
        meter = JointDissipation(m, f"stage '{st.name}'")
        u0, _ = self._state(self.u[free], self.lam)
        # the converged state's tractions start the first step: evaluated with no time, so that a viscous joint
        # (Duvaut-Lions) gives its committed traction, not one relaxed further
        dt, m.time_step = m.time_step, 0.0
        try:
            f_int_prev, _ = m.evaluate(u0, want_tangent=False)
        finally:
            m.time_step = dt
        m.revert()
        meter.mark_start()
        nominal = 1.0 / st.steps
        h_min = nominal / 2.0 ** s.max_step_cuts
        h = nominal
        by_dissipation = switched = False
        tau = tau_min = None  # the target dissipation per step (J), once measured
        d_prev, dlam_prev = None, self.prev_dlam  # (the last step of the control that handed over, if any)
        # the work done on the model in the stage (J); where this control takes over part-way (a fallback), an
        # estimate of what came before, from which a first target can be set
        work_stage = 0.5 * abs(float(f_int_prev @ (u0 - self.u_start)))
        shrinks, own_tried, failed_at, cuts_here = 0, False, None, 0
        steps = 0
        self.peak = self.lam
        self.dissipated = 0.0
        self.steps_taken = 0

        def own(target):
            """A step onto ``target`` under the stage's own control: (ok, u_f, lam, its, f_int, f_ext, D)."""
            ok, u1, its, f_int, f_ext = self._controlled(target)
            if not ok:
                m.revert()
                return (False,) + (None,) * 6
            return True, u1[free], target, its, f_int, f_ext, meter.of_step(want_gradient=False)[0]

        while self.lam < 1.0 - 1e-12:
            if steps >= MAX_STEPS_PER_NOMINAL * st.steps:
                if st.until_failure:
                    break
                raise ConvergenceError(f"stage '{st.name}': dissipation control took {steps} steps and reached "
                                       f"load factor {self.lam:.4g} of 1")
            longest = min(nominal, 1.0 - self.lam)
            if by_dissipation:
                step = self._dissipation_step(meter, tau, d_prev, dlam_prev)
                controlled = False
                if step[0] and step[2] - self.lam > longest * (1.0 + 1e-9):
                    # little dissipation per unit load, or past the end of the stage: a target smaller in
                    # proportion; where that is below the least one, the stage's own control
                    m.revert()
                    smaller = 0.9 * tau * longest / (step[2] - self.lam)
                    if smaller >= tau_min and shrinks < MAX_SHRINKS:
                        tau, shrinks = smaller, shrinks + 1
                    else:  # (a step from here is not sent back to dissipation control, whatever it dissipates)
                        by_dissipation, h, failed_at = False, longest, self.lam
                    continue
                if not step[0]:
                    m.revert()
                    if not own_tried:  # the stage's own control, once, where it does not jump
                        own_tried = True
                        step = own(self.lam + min(h, longest))
                        controlled = True
                        if step[0] and step[6] > JUMP_FACTOR * tau:
                            m.revert()
                            step = (False,)
                    if not step[0]:
                        tau /= 2.0
                        cuts_here += 1
                        self.solver.stats.step_cuts += 1
                        if tau < tau_min or cuts_here > DISSIPATION_CUTS:  # the stage's own control, with its cuts
                            by_dissipation, tau, h, failed_at = False, 2.0 * tau, longest, self.lam
                        continue
            else:
                step = own(self.lam + min(h, longest))
                controlled = True
                if step[0] and switched and step[6] > JUMP_FACTOR * tau and failed_at != self.lam:
                    m.revert()  # it passed over a snap-back: dissipation control
                    by_dissipation = True
                    continue
                if not step[0]:
                    if failed_at == self.lam or (tau is None and not work_stage > 0):
                        h /= 2.0
                        self.solver.stats.step_cuts += 1
                        if h < h_min:
                            raise ConvergenceError(
                                f"stage '{st.name}': no equilibrium beyond load factor {self.lam:.4g} under "
                                "dissipation control or the stage's own control"
                                + ("" if tau is not None else " (and no work done yet to set a dissipation target)"))
                        continue
                    if tau is None:  # stalled before the joints dissipated: a target from the work done so far
                        tau = DISSIPATION_START_FRACTION * work_stage
                        tau_min = tau / 2.0 ** s.max_step_cuts
                    by_dissipation = switched = True
                    continue
            _, u_f, lam, its, f_int, f_ext, d = step
            work = 0.5 * float((f_int_prev + f_int) @ (self._state(u_f, lam)[0] - self.u))
            work_stage += work
            steps += 1
            self.steps_taken = steps
            dlam_prev, d_prev = lam - self.lam, d
            self.dissipated += d
            f_int_prev = f_int
            self._accept(u_f, lam, f_int, f_ext, on_commit=meter.mark_start)
            shrinks, own_tried, failed_at, cuts_here = 0, False, None, 0
            if not controlled:
                tau = float(np.clip(tau * math.sqrt(TARGET_ITERATIONS["dissipation"] / max(its, 1)),
                                    tau / 2.0, 2.0 * tau))
                # the stage's steps set the resolution: a step dissipates at most that part of the energy the
                # model has taken in the stage (a long snap-back in few steps misses the curve's shape)
                tau = max(min(tau, max(work_stage, self.dissipated) / st.steps), tau_min)
            else:
                h = min(nominal, 2.0 * h)
                # (against the stage's work too: a step that does next to no work dissipates round-off)
                if not switched and work_stage > 0 and d > DISSIPATION_SWITCH * max(abs(work), 1e-6 * work_stage):
                    # the joints dissipate: from now on every step dissipates about as much
                    tau, tau_min = d, d / 2.0 ** s.max_step_cuts
                    by_dissipation = switched = True
            if lam < 0.0:  # unloaded completely
                break
        return self.u, self.lam, steps

    def _dissipation_step(self, meter, tau, d_prev, dlam_prev):
        """One step whose joints dissipate ``tau`` (J): (ok, u_f, lambda, iterations, f_int, f_ext, D).
        Each iteration solves ``K du_r = r``, ``K du_q = q`` and takes ``dlambda`` from the linearised
        constraint ``D + g . (du_r + dlambda du_q) + dlambda g_p . Delta_p = tau`` (g: :meth:`JointDissipation
        .of_step`'s gradient, its prescribed part moving with lambda). Where the linearisation cannot steer
        the first iteration (every joint point elastic at the start, so g = 0, or a load-factor increment of
        more than one nominal step), the predictor is the last step's increment scaled by ``tau / D_last``, or,
        for the first step after another control handed over, the point of the tangent path
        ``du_r + dlambda du_q`` nearest to that control's last increment."""
        s, free, st = self.solver.s, self.free, self.st
        u0_f = self.u[free].copy()
        u_f, lam = u0_f.copy(), self.lam
        prescribed = st.prescribed
        nominal = 1.0 / st.steps
        ref0 = None
        for it in range(s.max_iterations + 1):
            at = self._iterate(u_f, lam, it)
            if at is None:
                return False, None, None, it, None, None, None
            f_int, K, f_ext, r, rn, ref = at
            d, grad = meter.of_step(want_gradient=True)
            ref0 = rn if ref0 is None else ref0
            if it > 0 and rn <= s.force_tolerance * max(ref, ref0) and abs(d - tau) <= DISSIPATION_TOLERANCE * tau:
                return True, u_f, lam, it, f_int, f_ext, d
            if it == s.max_iterations:
                break
            pair = self._solve_pair(K, r)
            if pair is None:
                return False, None, None, it, None, None, None
            du_r, du_q = pair
            g_q = float(grad[free] @ du_q) + float(grad[prescribed] @ self.delta_p[prescribed])
            g_r = float(grad[free] @ du_r)
            dlam = (tau - d - g_r) / g_q if g_q != 0.0 else math.inf
            if it == 0 and not abs(dlam) <= nominal and self.prev is not None and dlam_prev is not None:
                # (a last step that dissipated next to nothing: its own increment)
                scale = tau / d_prev if d_prev is not None and d_prev > DISSIPATION_SWITCH * tau else 1.0
                du, dlam = scale * self.prev, scale * dlam_prev
            elif it == 0 and not abs(dlam) <= nominal and self.prev is not None:
                # handed over by another control (its last increment, but not its load factor's): the point of
                # the tangent path nearest to that increment
                nq = float(du_q @ du_q)
                if not nq > 0:
                    return False, None, None, it, None, None, None
                dlam = float((self.prev - du_r) @ du_q) / nq
                du = du_r + dlam * du_q
            elif not math.isfinite(dlam):
                return False, None, None, it, None, None, None
            else:
                du = du_r + dlam * du_q
            u_f = u_f + du
            lam = lam + dlam
        return False, None, None, s.max_iterations, None, None, None
