"""Nonlinear static solution in stages.

Each stage ramps its own loads with a load factor lambda from 0 to 1 on top of the loads reached at the end of the
previous stages (load control). Prescribed displacements are ramped the same way as increments from the stage's start
(displacement control); their reactions are the load.

Per step: full Newton (consistent tangent) or modified Newton (the initial elastic stiffness, factorized once for the
whole analysis), each with an optional line search (Crisfield 1991, Non-linear Finite Element Analysis of Solids and
Structures, vol. 1, sec. 9.3). A step that does not converge is cut in half and retried, and the step length grows
back after successes; a stage fails when a step would become shorter than ``1 / (steps * 2**max_step_cuts)``.
Convergence needs both the force residual ``||r|| <= force_tolerance * max(||f_ext||, ||f_int||, ||r_0||)`` (r_0: the
step's first residual, so that a state with no force at all, such as an open joint, still has a scale) and the energy
of the last correction ``|du . r| <= energy_tolerance * |du_0 . r_0|``. The iterations run in the Newton loop shared
with the dynamic steps (:func:`masonrydam.solvers.newton.newton_iterations`, over :class:`LoadStepNewton`), with its
convergence test, secant line search and step cutting.

A factorization is reused while the tangent is unchanged (same values): a scene whose joints stay linear is therefore
solved with a single factorization; a changed tangent is refactorized with the kept symbolic analysis (PARDISO).

Joint space (``joint_space = "auto"``, full Newton): the blocks are linear, so each step is first solved on the
relative displacements of the nonlinear joints, condensed from the all-stick stiffness
(:mod:`masonrydam.solvers.joint_space`, as the dynamic solver does), which needs no sparse factorization per
iteration; the general Newton iterations then check the result against the full residual and go on from it where
needed, or solve the step from its start where the joint-space iteration did not converge.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from ...assembly.elastic import elastic_tangent_data
from ...errors import ConvergenceError, MechanismError, NumericalError, RunStopped, StepInterrupted
from ...materials.joint_laws import RESULT_OPEN, RESULT_SLIP
from ..chatter import ChatterGuard
from ..diagnostics import find_free_parts, newton_stall
from ..joint_space import MAX_INITIAL_STIFFNESS_ITERATIONS, JointSpace, joint_space_size, lazy_flexibility
from ..linear.iterative import clear_pattern_caches, rigid_body_modes
from ..linear.direct import SingularMatrix, SymmetricFactorization, make_solver, resolve_backend
from ..newton import ConvergenceTest, IterationFailed, StepCutting, force_scale, newton_iterations, within_step_stop
from .arc_length import ArcLengthStage
from . import line_search, relaxation

#: tangent factor of open joint points in ordinary Newton iterations: a tiny stiffness in the
#: tangent only (tractions stay zero) so that a block resting on a single contact point does not make
#: the tangent singular; the converged solution does not depend on it.
OPEN_TANGENT_REGULAR = 1e-6
#: the joint-space iteration of a step converges to this fraction of the force tolerance: the general
#: path then accepts its solution on the force residual alone (its energy test needs an iteration), so
#: the solution is converged this much further, as far as the general path's energy test takes it
#: (on the default scene the full residual at the joint-space solutions was 1e-13 to 8e-10 relative)
JOINT_SPACE_FORCE_FRACTION = 1e-3


@dataclass
class SolverSettings:
    """Settings of the static solver (all dimensionless)."""

    method: str = "newton"  # "newton" | "modified_newton"
    line_search: bool = True
    max_iterations: int = 30
    force_tolerance: float = 1e-6
    energy_tolerance: float = 1e-10
    max_step_cuts: int = 8
    linear_solver: str = "auto"
    joint_space: str = "auto"  # "auto" | "off": steps solved on the joint unknowns first (see _joint_space)

    def as_dict(self):
        return asdict(self)


@dataclass
class StaticStage:
    """A load stage.

    name; steps: nominal number of increments; force: (n_dof,) N applied in full at lambda = 1;
    prescribed: (n_dof,) bool DOFs driven in this stage; increment: (n_dof,) m displacement increment
    of those DOFs over the stage; supports: (n_dof,) bool DOFs held at zero.

    varying: loads that are not proportional to the load factor, made by an effect (e.g. rising water,
    :class:`~masonrydam.effects.reservoir.StageWater`), or None: ``external(lam)`` (n_dof,) N, computed once
    per increment; ``state_load(lam)`` (n_dof,) N, forces that follow the joints' trial states, computed at
    every iteration where ``state_dependent``; ``failure_hint()`` words on a failed step; ``limit(lam, target)``
    the result attributes and words of a stage limit at ``lam`` (``target`` tried);
    until_failure: a step that finds no equilibrium ends the stage and the analysis (the load factor
    reached is the limit, :attr:`StaticSolver.limit`) instead of failing it.
    """

    name: str
    steps: int
    force: np.ndarray
    prescribed: np.ndarray
    increment: np.ndarray
    supports: np.ndarray
    varying: object = None
    until_failure: bool = False
    #: physical time of the stage (s): a load step of load-factor increment d_lambda lasts
    #: ``duration * d_lambda``, the time step of rate-dependent (Perzyna) blocks; 0: no time (instantaneous)
    duration: float = 0.0
    #: "load": the stage's own control (loads, prescribed displacements), switching to arc-length control
    #: where a step finds no equilibrium after its cuts; "arc_length": arc-length control from the start
    #: (:mod:`.arc_length`); "opening": indirect displacement control on the opening of the cracking joints;
    #: "dissipation": every step dissipates a chosen energy in the joints (:mod:`.dissipation`)
    control: str = "load"
    #: where control "load" finds no equilibrium: "follow" the path (arc length) or "relax" (:mod:`.relaxation`)
    limit_point: str = "follow"


#: a static stage whose joint set is too large for the dense flexibility (JOINT_SPACE_MAX) is condensed
#: with columns computed as needed only from this many equations: a refactorization of a smaller model
#: costs less than the columns a step needs (the 3D English-bond wall example, 8 778 DOF: 0.53 s
#: in 5 general iterations, 2.2 s condensed with 1 954 columns; the 3D dam example, 39 744 equations:
#: 63 s general, 20 s condensed)
STATIC_COLUMNS_MIN_EQUATIONS = 20_000
#: with ``linear_solver = "auto"`` a static stage is condensed on its joints up to this many equations also where
#: the general path takes AMG (from AUTO_ITERATIVE_MIN_DOF): the condensation needs one L D L^T factorization of
#: the all-stick stiffness per constraint set, and AMG on a tangent with sliding and open joints converges 3-6x
#: slower than on an elastic one (docs/performance.md). On the 20-monolith dam of examples/dam_3d_reservoir.toml
#: (60 258 equations, 42 912 joint unknowns) the factor has 39 M entries (20 s, 3.1 GB peak with the column store)
#: and the reservoir stage took 54 s condensed against more than 900 s (not finished) on the general AMG path
STATIC_JOINT_SPACE_AUTO_MAX_EQUATIONS = 80_000


#: the AMG general path (3D models from AUTO_ITERATIVE_MIN_DOF equations) solves each Newton correction inexactly: to
#: the forcing term of Eisenstat & Walker (1996, SIAM J. Sci. Comput. 17:16-32, choice 2 with gamma = 0.9 and
#: alpha = 2, and their safeguard), at most this relative residual, and never tighter than a tenth of what the
#: force tolerance still asks of the step. On the 166k-DOF dam of examples/dam_3d_gravity.toml at element_size 3
#: every correction was solved to 1e-10 (25 FGMRES iterations, 5.8 s of 12.1 s per Newton iteration); see
#: docs/performance.md for what the inexact corrections and the reused hierarchies changed
AMG_FORCING_MAX = 1e-2
#: a hierarchy set up for one tangent preconditions the next ones (:meth:`AMGSolver.for_matrix`; a setup took 6.3 s
#: of the 12.1 s above) until a solve converges this many times slower per decade of residual than the first solve
#: with it; the next correction then sets one up for its own tangent
AMG_REUSE_SLOWDOWN = 4.0

#: path-following controls (:mod:`.arc_length`), in the order tried where load control stalls: the global arc
#: first, then the cracks' opening, then the joints' dissipation
ARC_MODES = ("cylindrical", "opening", "dissipation")

#: (JointSpace counter, SolveStats field) pairs: what each joint-space step adds to the static solver's statistics
JOINT_SPACE_COUNTS = (("compiled_steps", "joint_space_compiled_steps"), ("python_steps", "joint_space_python_steps"),
                      ("hold_events", "joint_space_holds"), ("bond_latches", "joint_space_bond_latches"),
                      ("fresh_budgets", "joint_space_fresh_budgets"))


@dataclass
class SolveStats:
    steps: int = 0
    iterations: int = 0
    factorizations: int = 0
    analyses: int = 0  # symbolic analyses among the factorizations (a refactorization reuses one)
    joint_space_size: int = 0  # joint unknowns condensed (0: the joint-space start was not used)
    joint_space_steps: int = 0  # step attempts whose joint-space iteration converged
    joint_space_iterations: int = 0  # joint-space Newton iterations
    joint_space_splits: int = 0  # step attempts cut because their joint-space iteration did not converge
    joint_space_setup_s: float = 0.0
    #: columns of the joint flexibility computed as steps needed them (above JOINT_SPACE_MAX unknowns),
    #: and the seconds they took
    joint_space_flexibility_columns: int = 0
    joint_space_flexibility_s: float = 0.0
    #: joint-space step attempts solved by the compiled kernel (masonrydam.solvers.joint_space.step_kernel) and by
    #: the Python loop (flexibility columns computed as needed, another factorization); points held sticking
    #: because their state kept flipping, bonds latched broken at points flipping across the cohesion jump, and
    #: releases of held points after which Newton started a fresh budget
    joint_space_compiled_steps: int = 0
    joint_space_python_steps: int = 0
    joint_space_holds: int = 0
    joint_space_bond_latches: int = 0
    joint_space_fresh_budgets: int = 0
    #: Newton corrections of the AMG general path solved with a hierarchy set up for an earlier tangent, and the
    #: Krylov iterations of all its corrections
    preconditioner_reuses: int = 0
    krylov_iterations: int = 0
    step_cuts: int = 0
    line_searches: int = 0
    stabilized_steps: int = 0
    arc_length_steps: int = 0  # steps taken under path-following control (arc length, opening, dissipation)
    #: hand-overs where a control stalled: from load control to path following, or from an explicitly chosen
    #: path-following control to the others
    arc_length_switches: int = 0
    wall_time_s: float = 0.0
    per_stage: list = field(default_factory=list)


def check_mechanism(model, stage: StaticStage) -> None:
    """Raise MechanismError if a part of ``model`` can move as a rigid body under the supports and
    prescribed DOFs of ``stage`` (missing supports, a floating block), judged with the model's current
    joint states (fully open joints do not connect). The solver calls it at the start of each stage;
    ``masonrydam check`` calls it (:func:`check_mechanisms`) on the model as built."""
    parts = find_free_parts(model, stage.supports | stage.prescribed, use_joint_state=True)
    if parts:
        raise MechanismError(f"stage '{stage.name}': the model is a mechanism before solving", parts)


def check_mechanisms(model, stages) -> None:
    """:func:`check_mechanism` for each static stage of ``stages`` (dynamic stages are skipped), all
    with the joint states of ``model`` as they are: what the solver finds before the first stage, and
    before a later one if the earlier stages opened no joint."""
    for st in stages:
        if isinstance(st, StaticStage):
            check_mechanism(model, st)


def joint_mechanisms(model, limit: int = 4) -> list[str]:
    """The joints that no longer hold a part in place in the trial joint state of ``model`` (the failed
    attempt of a step), in words that name the mechanism and the part: per joint set and pair of
    element groups it joins, "sliding" where no point sticks and at least one slides, "rocking" where
    at least half the points are open and those still in contact (the hinge) lie within a quarter of
    the joint's extent. At most ``limit`` entries (the most open first), then how many more. Empty if
    no joint is in such a state (a joint whose points are all open leaves a free part, which
    :func:`find_free_parts` names)."""
    names = [g.name for g in model.cgroups] + ["?"]
    owner = np.full(model.n_nodes, len(model.cgroups))  # element group of each node (interfaces split nodes)
    for i in range(len(model.cgroups) - 1, -1, -1):
        owner[model.cgroups[i].conn.ravel()] = i
    found = []
    for g in model.igroups:
        if not g.nonlinear:
            continue
        ns = g.conn.shape[1] // 2
        codes = g.result_states(trial=True)  # (ne, nip)
        below, above = owner[g.conn[:, 0]], owner[g.conn[:, ns]]
        for b, a in sorted(set(zip(below.tolist(), above.tolist()))):
            elems = (below == b) & (above == a)
            c = codes[elems].ravel()
            x = g.points[elems].reshape(-1, model.dim)
            n_open, n_slip = int((c == RESULT_OPEN).sum()), int((c == RESULT_SLIP).sum())
            n_touch = len(c) - n_open
            where = f"joint set '{g.name}' between element groups '{names[b]}' and '{names[a]}'"
            if n_touch == 0:
                continue
            if n_touch == n_slip:
                found.append((n_open / len(c), f"sliding: every point of {where} that still touches slides "
                                                f"({n_slip} sliding, {n_open} open of {len(c)})"))
                continue
            touching = x[c != RESULT_OPEN]
            if 2 * n_open >= len(c) and np.ptp(touching, axis=0).max() <= 0.25 * np.ptp(x, axis=0).max():
                hinge = ", ".join(f"{v:.4g}" for v in touching.mean(axis=0))
                found.append((n_open / len(c), f"rocking: {n_open} of {len(c)} points of {where} are open; the "
                                                f"part turns about the {n_touch} point(s) still in contact near "
                                                f"({hinge}) m"))
    found.sort(key=lambda item: -item[0])
    out = [text for _, text in found[:limit]]
    if len(found) > limit:
        out.append(f"and {len(found) - limit} more joint(s) in such a state")
    return out


class LoadStepIterate:
    """A Newton iterate of a load step: ``u`` (n_dof,) m, ``f_int`` (n_dof,) N, the tangent ``K`` (None where it was
    not asked for), the residual ``r`` (n_eq,) N on the free DOFs and its norm, and the norms of the external
    (with the state-dependent loads) and internal forces (N)."""

    __slots__ = ("u", "f_int", "K", "r", "residual_norm", "f_ext_norm", "f_int_norm")

    def __init__(self, u, f_int, K, r, f_ext_norm, f_int_norm):
        self.u, self.f_int, self.K, self.r = u, f_int, K, r
        self.residual_norm = float(np.linalg.norm(r))
        self.f_ext_norm, self.f_int_norm = f_ext_norm, f_int_norm


class LoadStepNewton:
    """The Newton step of one load step of ``solver`` (a :class:`StaticSolver`) under the external forces
    ``f_ext`` (n_dof,) N, for :func:`masonrydam.solvers.newton.newton_iterations`: full Newton (the tangent
    factorized, :meth:`StaticSolver._factorize`) or modified Newton (the initial tangent), the secant line search
    on the work of the correction, bonds latched while the chatter ``guard`` stabilizes.

    ``r0_norm``: the norm of the step's first residual (N), the force scale of a step with no load.
    """

    def __init__(self, solver, f_ext, guard):
        self.solver, self.model, self.s = solver, solver.model, solver.s
        self.f_ext, self.guard = f_ext, guard
        self.free = solver.model.dofmap.free
        self.r0_norm = None
        self._last_residual_norm = None  # the residual norm and forcing term of the last inexact correction
        self._last_forcing = None

    def evaluate(self, u, latch=True) -> LoadStepIterate:
        """The iterate at ``u``; :class:`~masonrydam.solvers.newton.IterationFailed` where a law's return mapping
        gives up there (an iterate far off the path, or a trial increment too large for it: the attempt failed and
        the step is cut like one that does not converge; the last such message goes into the error if the cuts
        do not help). ``latch`` False: the bonds the iterate breaks are not latched while the guard stabilizes."""
        m, solver = self.model, self.solver
        want_K = self.s.method == "newton" or solver._initial is None
        try:
            f_int, K = m.evaluate(u, want_tangent=want_K)
        except NumericalError as exc:
            solver._law_failure = str(exc)
            raise IterationFailed(str(exc)) from None
        if self.guard.stabilized and latch:
            m.latch_broken_bonds()
        f_now = solver._with_state_load(self.f_ext)
        r_full = f_now - f_int
        if not np.isfinite(r_full).all():
            raise NumericalError("NaN or infinity in the residual (check loads and stiffnesses)")
        return LoadStepIterate(u, f_int, K, r_full[self.free], np.linalg.norm(f_now), np.linalg.norm(f_int))

    def force_scale(self, iterate, iteration):
        """``max(||f_ext||, ||f_int||, ||r_0||)`` (N; see the module docstring)."""
        return force_scale(iterate.f_ext_norm, iterate.f_int_norm, self.r0_norm)

    def after_guard(self, iterate, action):
        """The tangent and residual again at the same displacements (the open points' tangent changed)."""
        m, solver = self.model, self.solver
        solver.stats.stabilized_steps += action == "stabilize"
        f_int, K = m.evaluate(iterate.u, want_tangent=True)
        r = (solver._with_state_load(self.f_ext) - f_int)[self.free]
        return LoadStepIterate(iterate.u, f_int, K, r, iterate.f_ext_norm, iterate.f_int_norm)

    def correction(self, iterate):
        """``K^-1 r`` with the tangent's factorization, or the initial one (modified Newton); on the AMG path inexactly,
        with the hierarchy of an earlier tangent while it serves (:meth:`StaticSolver._amg_correction`)."""
        solver = self.solver
        if self.s.method == "modified_newton":
            if solver._initial is None:
                solver._initial = solver._linear_solver(iterate.K)
                solver.stats.factorizations += 1
                solver.stats.analyses += 1
            fact = solver._initial
        elif solver._amg_path():
            solver.stats.iterations += 1
            return solver._amg_correction(iterate.K, iterate.r, self._forcing(iterate))
        else:
            fact = solver._factorize(iterate.K)
        du = fact.solve(iterate.r)
        solver.stats.iterations += 1
        return du

    def _forcing(self, iterate) -> float:
        """The relative residual to which the AMG general path solves this correction (AMG_FORCING_MAX): Eisenstat
        & Walker's choice 2, ``0.9 (||r_k|| / ||r_k-1||)^2``, safeguarded by ``0.9 eta_k-1^2`` where that exceeds
        0.1, at most AMG_FORCING_MAX, and at least a tenth of ``force_tolerance * scale / ||r_k||`` (no solve
        tighter than what the step's convergence test can see)."""
        rn = iterate.residual_norm
        if self._last_residual_norm is None or self._last_residual_norm <= 0.0:
            eta = AMG_FORCING_MAX
        else:
            eta = 0.9 * (rn / self._last_residual_norm) ** 2
            safeguard = 0.9 * self._last_forcing ** 2
            if safeguard > 0.1:
                eta = max(eta, safeguard)
        eta = min(eta, AMG_FORCING_MAX)
        if rn > 0.0:
            scale = force_scale(iterate.f_ext_norm, iterate.f_int_norm, self.r0_norm)
            eta = max(eta, min(0.1, 0.1 * self.s.force_tolerance * scale / rn))
        self._last_residual_norm, self._last_forcing = rn, eta
        return eta

    def advance(self, iterate, du):
        """The iterate at ``u + s du``, ``s`` from the secant line search (1 without); the work ``|s du . r|``
        (:func:`.line_search.advance`)."""
        return line_search.advance(self, iterate, du)


class StaticSolver:
    """Drives a :class:`~masonrydam.assembly.model.Model` through static stages.

    ``on_step(stage_index, stage, load_factor, u, f_int, f_ext)`` is called after each converged
    step (the recorder writes it to disk there, so a later failure never loses it).

    ``stop_requested()``, when given, is asked between two Newton iterations of a step and before every
    joint-space iteration; where it returns a status (``"interrupted"``, ``"terminated"``) the step is
    abandoned, the joints' trial states reverted, and :class:`~masonrydam.errors.RunStopped` raised naming the
    last converged step (the steps recorded before stay). A stop asked for between steps is the caller's
    (``on_step``) to act on.
    """

    def __init__(self, model, settings: SolverSettings, on_step=None, progress=None, stop_requested=None):
        self.model, self.s = model, settings
        self._on_step = on_step or (lambda *a: None)
        self.progress = progress
        #: raises StepInterrupted between two iterations where a stop was asked for (None without stop requests; an
        #: iteration of the 166k-DOF dam on the AMG path takes a few seconds, a step up to a minute)
        self._stop_within_step = within_step_stop(stop_requested)
        #: where set, makes the ``give_up`` test of each Newton solve
        #: (:func:`~masonrydam.solvers.newton.newton_iterations`); :mod:`.relaxation` sets it for the solves whose
        #: failure is held or cut anyway
        self.give_up = None
        #: where set, an iterate whose residual is below this fraction of the force tolerance passes the work test
        #: (:class:`~masonrydam.solvers.newton.ConvergenceTest`); :mod:`.relaxation` sets it with ``give_up``
        self.roundoff_fraction = None
        #: (stage name, load factor) of the last converged step, None before the first
        self._committed = None
        self._iterations_before = 0  # Newton iterations before the running stage (its per-stage count)
        self.stats = SolveStats()
        self._fact = None
        self._fact_data = None
        self._where = ""  # the step being solved, in words (progress display)
        self._js = None  # joint-space system of the constraint set self._js_dofmap (see _joint_space)
        self._js_dofmap = None
        self._initial = None  # modified Newton: initial stiffness factorization per constraint set
        self._initial_dofmap = None
        #: the AMG general path: the hierarchy in use (an AMGSolver), its constraint set, the convergence factor of
        #: its first solve, and whether it has stopped serving (see _amg_correction)
        self._amg, self._amg_dofmap, self._amg_factor, self._amg_stale = None, None, 0.5, False
        self._state_load = None  # forces that follow the joint states in the current step (see _newton)
        self._law_failure = None  # the last message of a law that gave up in an attempt of the current step
        #: where a stage with ``until_failure`` found no equilibrium: dict stage, load_factor (the last
        #: converged), failed_at (the load factor tried), reason; None if none did
        self.limit = None

    def on_step(self, si, st, lam, u, f_int, f_ext):
        """A converged step: remembered (where a stop within the next step says it stopped) and recorded."""
        self._committed = (st.name, lam)
        self._on_step(si, st, lam, u, f_int, f_ext)

    # -- linear algebra -------------------------------------------------------------------------
    def _factorize(self, K):
        """A factorization of K: the last one when K is unchanged, else the last one refactorized with
        its symbolic analysis (same pattern, direct solver: :meth:`Factorization.refactorize`), else a
        new one. ``stats.factorizations`` counts numerical factorizations, ``stats.analyses`` the
        symbolic analyses among them."""
        fact = self._fact
        if fact is not None and self._fact_data is not None and len(self._fact_data) == len(K.data) \
                and fact.K.shape == K.shape and np.array_equal(self._fact_data, K.data):
            return fact
        before = getattr(fact, "analyses", 0)
        try:
            reused = fact is not None and hasattr(fact, "refactorize") and fact.refactorize(K)
        except BaseException:
            self._fact = None  # refactorize changed it: never hand it out again
            self.stats.analyses += getattr(fact, "analyses", 0) - before
            raise
        if not reused:
            fact = self._fact = self._linear_solver(K)
            before = 0
        self.stats.analyses += getattr(fact, "analyses", 1) - before
        self._fact_data = K.data.copy()
        self.stats.factorizations += 1
        return fact

    def _amg_path(self) -> bool:
        """Whether the general path of the current constraint set takes the AMG solver (inexact corrections, reused
        hierarchies, a secant predictor)."""
        return resolve_backend(self.s.linear_solver, n_dof=len(self.model.dofmap.free), dim=self.model.dim) == "amg"

    def _amg_correction(self, K, r, rtol):
        """``K^-1 r`` to the relative residual ``rtol`` with the AMG solver: preconditioned by the hierarchy of an
        earlier tangent of the same constraint set while it serves (AMG_REUSE_SLOWDOWN), else by one set up for
        K (counted as a factorization and a symbolic analysis). A reused hierarchy that fails (stagnation) is
        replaced at once."""
        m, stats = self.model, self.stats
        base = self._amg
        if base is not None and not self._amg_stale and self._amg_dofmap is m.dofmap and base.K.shape == K.shape:
            solver = base.for_matrix(K)
            try:
                du = solver.solve(r, rtol=rtol)
            except SingularMatrix:
                solver = None
            if solver is not None:
                stats.preconditioner_reuses += 1
                stats.krylov_iterations += solver.last_iterations
                f = solver.convergence_factor
                self._amg_stale = not f <= self._amg_factor ** (1.0 / AMG_REUSE_SLOWDOWN)
                return du
        # a tangent of the pattern of the old hierarchy's: the symmetry test by its transpose permutation (0.05
        # instead of 0.5 s at 166k DOF), which the new hierarchy keeps
        same = base is not None and base.K.shape == K.shape and np.array_equal(base.K.indptr, K.indptr) \
            and np.array_equal(base.K.indices, K.indices)
        sym = base.is_symmetric_like(K) if same else None
        perm = base._transpose_perm if same else None
        self._amg = base = None  # the old hierarchy's memory first
        solver = self._amg = self._linear_solver(K, symmetric=sym)
        if perm is not None:
            solver._transpose_perm = perm
        self._amg_dofmap = m.dofmap
        stats.factorizations += 1
        stats.analyses += 1
        du = solver.solve(r, rtol=rtol)
        stats.krylov_iterations += solver.last_iterations
        f = solver.convergence_factor
        self._amg_factor = f if 0.0 < f < 1.0 else 0.5
        self._amg_stale = False
        return du

    def _linear_solver(self, K, **amg_options):
        """make_solver for K; for the AMG backend with the rigid-body modes, positions and nodes of
        the free DOFs (computed once per constraint set, only when AMG is used)."""
        m = self.model
        backend = resolve_backend(self.s.linear_solver, n_dof=K.shape[0], dim=m.dim)
        if backend != "amg":
            return make_solver(K, backend)
        dm = m.dofmap
        if getattr(self, "_modes_dofmap", None) is not dm:
            self._modes = rigid_body_modes(m.coords, dm.free, m.dim)
            self._dof_nodes = dm.free // m.dim
            self._modes_dofmap = dm
        return make_solver(K, backend, near_nullspace=self._modes, dof_coords=m.coords[self._dof_nodes],
                           dof_nodes=self._dof_nodes, **amg_options)

    # -- one step ---------------------------------------------------------------------------------
    def _newton(self, u, f_ext, can_cut=False, state_load=None):
        """One step from the trial state ``u``: in joint space first (where it applies), then by the
        general Newton iterations; with ``can_cut``, a step whose joint-space iteration does not
        converge is given up at once (the caller halves it, which is cheaper than the general path's
        tangent factorizations, as in the dynamic solver). ``state_load()``: external forces that
        follow the joints' trial states (pore pressures in cracks), added to ``f_ext`` after each
        evaluation; the tangent does not see them (a fixed-point iteration on them)."""
        self._state_load = state_load
        self.model.set_open_tangent(OPEN_TANGENT_REGULAR)
        try:
            js = self._joint_space()
            r0_norm = None
            if js is not None:
                u_js, r0_norm = self._joint_space_start(js, u, f_ext)
                if u_js is u and can_cut and not js.store_full:  # a halved step needs about as many columns
                    self.stats.joint_space_splits += 1
                    return False, u, 0, None
                u = u_js
            return self._newton_iterations(u, f_ext, r0_norm)
        finally:
            self.model.set_open_tangent(OPEN_TANGENT_REGULAR)

    def _status(self, text: str) -> None:
        """Tell the progress display what the current step is doing (see ``self._where``)."""
        status = getattr(self.progress, "status", None)
        if status is not None:
            status(f"{self._where}, {text}")

    def _joint_space(self):
        """The joint-space system (:class:`~masonrydam.solvers.joint_space.JointSpace`) of the current
        constraint set, set up when first needed; None where it does not apply.

        Why: the blocks are linear elastic, so a load step is nonlinear only in the joint law, and the
        step can be solved on the relative displacements of the nonlinear joints, condensed from the
        all-stick stiffness ``K_ref`` (factorized once per constraint set, L D L^T), as the dynamic
        solver does with its effective matrix (:mod:`masonrydam.solvers.joint_space`): no sparse factorization per
        iteration. It applies with ``joint_space = "auto"``, full Newton, a direct solver (or ``"auto"`` up to
        STATIC_JOINT_SPACE_AUTO_MAX_EQUATIONS equations, where the general path takes AMG) and nonlinear
        joints (above JOINT_SPACE_MAX joint unknowns the columns of the flexibility are computed as the
        iterations need them, :class:`~masonrydam.solvers.joint_space.FlexibilityColumns`, in models of
        at least STATIC_COLUMNS_MIN_EQUATIONS equations)."""
        m, s = self.model, self.s
        if s.joint_space == "off" or s.method != "newton" or not m.nonlinear or not m.condensable \
                or not m.joint_space_capable:
            return None  # (elasto-plastic blocks, large kinematics: the condensation needs linear blocks)
        if self._js_dofmap is m.dofmap:
            return self._js
        self._js, self._js_dofmap = None, m.dofmap
        n_eq = len(m.dofmap.free)
        if resolve_backend(s.linear_solver, n_dof=n_eq, dim=m.dim) == "amg" \
                and (s.linear_solver != "auto" or n_eq > STATIC_JOINT_SPACE_AUTO_MAX_EQUATIONS):
            return None
        if (lazy_flexibility(joint_space_size(m))
                and len(m.dofmap.free) < STATIC_COLUMNS_MIN_EQUATIONS):
            return None
        t0 = time.perf_counter()
        n = len(m.dofmap.free)
        K_ref = sp.csr_matrix((elastic_tangent_data(m), m.indices, m.indptr), shape=(n, n))
        try:
            ref = SymmetricFactorization(K_ref)
        except (SingularMatrix, ValueError):  # not positive definite (e.g. a mechanism): the general path
            return None
        self.stats.factorizations += 1
        self.stats.analyses += 1
        self._js = JointSpace(m, ref, static=True)
        self._js.stop_check = self._stop_within_step
        self.stats.joint_space_size = max(self.stats.joint_space_size, joint_space_size(m))
        self.stats.joint_space_setup_s += time.perf_counter() - t0
        return self._js

    def _joint_space_start(self, js, u, f_ext):
        """The step solved in joint space from ``u`` (the trial state with the step's prescribed
        displacements), and the norm of the step's residual at ``u`` (its force scale). The solution is
        returned where the joint-space iteration converged (the general Newton iterations check it
        against the full residual and go on from it if needed), else ``u`` itself, with the joint
        states as committed."""
        m, free = self.model, self.model.dofmap.free
        f_int, _ = m.evaluate(u, want_tangent=False)
        R = (f_int - self._with_state_load(f_ext))[free]
        r0_norm = float(np.linalg.norm(R))
        ref = force_scale(float(np.linalg.norm(f_ext[free])), float(np.linalg.norm(f_int[free])), r0_norm)
        cols0, secs0 = js.columns.computed, js.columns.seconds
        before = [getattr(js, name) for name, _ in JOINT_SPACE_COUNTS]
        try:
            u_js, its, converged, _ = js.solve_step(u, R, JOINT_SPACE_FORCE_FRACTION * self.s.force_tolerance * ref,
                                                    MAX_INITIAL_STIFFNESS_ITERATIONS)
        except FloatingPointError:
            u_js, its, converged = None, 0, False
        self.stats.joint_space_flexibility_columns += js.columns.computed - cols0
        self.stats.joint_space_flexibility_s += js.columns.seconds - secs0
        for (name, stat), n0 in zip(JOINT_SPACE_COUNTS, before):
            setattr(self.stats, stat, getattr(self.stats, stat) + getattr(js, name) - n0)
        self.stats.joint_space_iterations += its
        self._status(f"{its} joint-space iterations" + ("" if converged else ", not converged"))
        if u_js is None or not converged:
            m.revert()  # bonds the joint-space iterations latched broken: not for the general path
            return u, r0_norm
        self.stats.joint_space_steps += 1
        return u_js, r0_norm

    def _newton_iterations(self, u, f_ext, r0_norm=None):
        """Newton iterations of one step from the committed state; ``r0_norm``: the norm of the step's
        first residual (the force scale of a step with no load, see the module docstring), where the
        iterations start from a later iterate (the joint-space solution).

        Chatter guard (:class:`~masonrydam.solvers.chatter.ChatterGuard`, shared with the dynamic solver):
        where the joint-state pattern cycles, open points get their initial stiffness in the tangent and bonds
        that break stay broken, until the pattern settles. Where the residual stagnates (not halved over
        STAGNATION_WINDOW iterations) while the pattern keeps moving without an exact repeat, the bonds broken in
        the iterate are latched and the consistent tangent kept (the guard's ``stagnation`` trigger). Bonds are
        not latched before chatter or stagnation is seen, so transient tension in early iterates does not
        destroy cohesion.
        """
        m, s = self.model, self.s
        guard = ChatterGuard(m, OPEN_TANGENT_REGULAR, stagnation=True)
        step = LoadStepNewton(self, f_ext, guard)
        try:
            start = step.evaluate(u)
        except IterationFailed:
            return False, u, 0, None
        step.r0_norm = start.residual_norm if r0_norm is None else r0_norm

        def tell_progress(it, rn, ref):
            self._status(f"iteration {it}, residual {rn / ref:.1e}")
            if self._stop_within_step is not None:
                self._stop_within_step()

        test = ConvergenceTest(s.force_tolerance, s.energy_tolerance, self.roundoff_fraction)
        result = newton_iterations(step, start, test, s.max_iterations, guard=guard if m.nonlinear else None,
                                   on_check=tell_progress, give_up=None if self.give_up is None else self.give_up())
        last = result.iterate
        if result.converged:
            return True, last.u, result.iterations, last.f_int
        return False, u if last is None else last.u, result.iterations, None

    def _arc_length(self, si, st, u, u_start, f_base, lam, stage_stats, dl0, direction, mode="cylindrical",
                    direction_dlam=None):
        """The stage from ``lam`` under arc-length control (:class:`~.arc_length.ArcLengthStage`); returns
        (u, lam) where it ended (lam >= 1: the stage is done). Every converged step is recorded."""
        def record(u_now, lam_now, f_int, f_ext):
            stage_stats["steps"] += 1
            self.on_step(si, st, lam_now, u_now, f_int, f_ext)
            if self.progress is not None:
                self.progress(si, max(0.0, min(lam_now, 1.0)))

        self._where = f"{st.name}: arc-length control from load factor {lam:.4g}"
        # the pseudo-time of an arc step (rate-dependent laws): the stage's nominal step, whatever the arc's
        # load-factor increment (which is an unknown of the step and may be negative past a peak)
        self.model.time_step = st.duration / st.steps
        arc = ArcLengthStage(self, st, u, u_start, f_base, lam, record, dl0=dl0, direction=direction, mode=mode,
                             direction_dlam=direction_dlam)
        try:
            u, lam, _ = arc.run()
        except (ConvergenceError, NumericalError, SingularMatrix) as exc:
            # its last converged (committed) state and increment (free DOFs, load factor)
            exc.reached = (arc.u, arc.lam, arc.prev, arc.prev_dlam)
            raise
        finally:
            if mode == "dissipation":  # the joints' plastic work in the steps of dissipation control (J)
                stage_stats["joint_dissipation_J"] = (stage_stats.get("joint_dissipation_J", 0.0)
                                                      + getattr(arc, "dissipated", 0.0))
                stage_stats["dissipation_control_steps"] = (stage_stats.get("dissipation_control_steps", 0)
                                                            + getattr(arc, "steps_taken", 0))
        if lam < 1.0 - 1e-12:  # the path peaked below 1 and came down: the stage's end is not on it
            what = (f"arc-length control: the load factor peaked at {arc.peak:.4g} and came back to {lam:.4g} "
                    "along the descending branch")
            if not st.until_failure:
                exc = ConvergenceError(f"stage '{st.name}': {what} before reaching 1 (set until_failure = true "
                                       "to record the branch and keep the peak as the limit)")
                exc.reached = (u, lam, arc.prev, arc.prev_dlam)
                raise exc
            self.limit = {"stage": st.name, "load_factor": arc.peak, "failed_at": lam, "reason": what}
            self.stats.per_stage.append(dict(stage_stats, iterations=self.stats.iterations
                                             + self.stats.joint_space_iterations - self._iterations_before))
        return u, max(lam, 1.0) if lam >= 1.0 - 1e-12 else lam

    def _other_arcs(self, si, st, u, u_start, f_base, lam, stage_stats, last_du, modes, last_dlam=None):
        """The stage from ``(u, lam)`` (a converged, committed state; ``last_du`` its last free-DOF increment,
        ``last_dlam`` that of the load factor)
        under the path-following controls ``modes`` in turn, the first that gets through: (u, lam, None), or
        (u, lam, failures) where none does (each failure a line). A control that took steps before it failed
        hands the next one its last converged state (the model's committed state is that one, and its steps
        are recorded)."""
        failures = []
        for mode in modes:
            try:
                u_end, lam_end = self._arc_length(si, st, u, u_start, f_base, lam, stage_stats,
                                                  float(np.linalg.norm(last_du)) / 2.0, last_du, mode, last_dlam)
                return u_end, lam_end, None
            except (ConvergenceError, NumericalError, SingularMatrix) as exc:
                self.model.revert()
                failures.append(f"{mode}: {exc}")
                u_r, lam_r, du_r, dlam_r = getattr(exc, "reached", (None, lam, None, None))
                if u_r is not None and du_r is not None and float(np.linalg.norm(du_r)) > 0 \
                        and (lam_r != lam or not np.array_equal(u_r, u)):
                    u, lam, last_du, last_dlam = u_r, lam_r, du_r, dlam_r
        return u, lam, failures

    def _newton_plain(self, u, f_ext):
        """General Newton iterations of one step from the committed state, with no joint-space start and no
        state-dependent load, the open points' tangent regular before and after: a step of the stage's own
        control inside path following (:mod:`.arc_length`)."""
        self._state_load = None
        self.model.set_open_tangent(OPEN_TANGENT_REGULAR)
        try:
            return self._newton_iterations(u, f_ext)
        finally:
            self.model.set_open_tangent(OPEN_TANGENT_REGULAR)

    def _stall_hint(self, u, f_ext) -> str:
        """Where a failed step's last iterate ``u`` is out of balance (:func:`~..diagnostics.newton_stall`)."""
        def residual(v, tangent):
            f_int, K = self.model.evaluate(v, want_tangent=tangent)
            return (self._with_state_load(f_ext) - f_int)[self.model.dofmap.free], K
        solve = None if self._amg_path() else (lambda K, r: self._factorize(K).solve(r))  # (no AMG solve for a message)
        return newton_stall(self.model, u, residual, solve)

    def _with_state_load(self, f_ext):
        """``f_ext`` plus the forces that follow the joints' trial states (see :meth:`_newton`)."""
        return f_ext if self._state_load is None else f_ext + self._state_load()

    # -- stages -----------------------------------------------------------------------------------
    def run(self, stages: list[StaticStage], u0: np.ndarray | None = None):
        t0 = time.perf_counter()
        try:
            # one BLAS thread, as in the dynamic solver: the dense LU of the joint-space iteration
            # (LAPACK) must be bitwise reproducible, and on two cores a second thread only waits
            with threadpool_limits(limits=1, user_api="blas"):
                return self._run(stages, u0)
        except StepInterrupted as stop:  # within a step: back to the last converged one, which is recorded
            self.model.revert()
            last = ("before the first converged step" if self._committed is None
                    else "after load factor {1:.4g} of stage '{0}'".format(*self._committed))
            raise RunStopped(stop.status, f"{last}, within the next step ({self._where}; abandoned)") from None
        finally:
            self.stats.wall_time_s = time.perf_counter() - t0
            self._js, self._js_dofmap = None, None  # its factor and columns: not for the dynamic stages
            self._amg = self._amg_dofmap = None
            clear_pattern_caches()

    def _run(self, stages, u0):
        m, s = self.model, self.s
        u = np.zeros(m.n_dof) if u0 is None else u0.copy()
        f_base = np.zeros(m.n_dof)
        for si, st in enumerate(stages):
            constrained = st.supports | st.prescribed
            m.set_constraints(constrained)
            if self._initial_dofmap is not m.dofmap:  # modified Newton: initial stiffness of this constraint set
                self._initial, self._initial_dofmap = None, m.dofmap
            check_mechanism(m, st)
            u_start = u.copy()
            u[st.supports] = 0.0
            lam, nominal = 0.0, 1.0 / st.steps
            dlam = nominal
            cuts = 0
            cutting = StepCutting.from_nominal(s.max_step_cuts, nominal)
            stage_stats = {"stage": st.name, "steps": 0, "iterations": 0, "step_cuts": 0}
            it_before = self.stats.iterations + self.stats.joint_space_iterations
            self._iterations_before = it_before
            # the free-DOF and load-factor increments of the last converged step (arc-length's direction)
            last_du = last_dlam = None
            if st.control in ("arc_length", "opening", "dissipation"):
                mode = {"arc_length": "cylindrical"}.get(st.control, st.control)
                try:
                    u, lam = self._arc_length(si, st, u, u_start, f_base, lam, stage_stats, None, None, mode)
                except (ConvergenceError, NumericalError, SingularMatrix) as exc:
                    u_r, lam_r, du_r, dlam_r = getattr(exc, "reached", (None, lam, None, None))
                    if u_r is None or du_r is None or not float(np.linalg.norm(du_r)) > 0:
                        raise
                    # where the chosen control cannot go on, the other path-following controls from its last
                    # converged state (as where load control stalls)
                    m.revert()
                    self.stats.arc_length_switches += 1
                    u, lam, failures = self._other_arcs(si, st, u_r, u_start, f_base, lam_r, stage_stats, du_r,
                                                        [x for x in ARC_MODES if x != mode], dlam_r)
                    if failures is not None:
                        raise ConvergenceError(f"{exc}; from load factor {lam_r:.4g} the other path-following "
                                               "controls did not get through either (" + "; ".join(failures) + ")"
                                               ) from exc
                if self.limit is not None:
                    return u
            while lam < 1.0 - 1e-12:
                dl = min(dlam, 1.0 - lam)
                target = lam + dl
                trial = u.copy()
                m.time_step = st.duration * dl
                if last_du is not None and self._amg_path():
                    # the AMG path starts a step from the last converged increment, scaled to this one (a secant
                    # predictor): on the 8-monolith dam the gravity steps after the first took 4 iterations instead
                    # of 6, and their corrections half the Krylov iterations (docs/performance.md)
                    trial[m.dofmap.free] += (dl / last_dlam) * last_du
                trial[st.prescribed] = u_start[st.prescribed] + target * st.increment[st.prescribed]
                f_ext = f_base + target * st.force
                state_load = None
                if st.varying is not None:  # not proportional to the load factor: recomputed per increment
                    f_ext = f_ext + st.varying.external(target)
                    if st.varying.state_dependent:
                        state_load = (lambda target=target: st.varying.state_load(target))
                singular = None
                try:
                    # a step that can still be cut is cut where its joint-space iteration fails
                    can_cut = cutting.can_cut(cuts, dl)
                    self._where = f"{st.name}: load factor {target:.4g}" + (f" ({cuts} cuts)" if cuts else "")
                    step_start = trial.copy()
                    ok, u_new, iters, f_int = relaxation.attempt(self, st, dl, nominal, can_cut, trial, f_ext,
                                                                 state_load)
                except SingularMatrix as exc:
                    ok, singular = False, exc
                relax_failure = ""
                if not ok and relaxation.holds(st, dl, nominal, cutting.can_cut(cuts, dl)):
                    m.revert()
                    ok, u_new, f_int, relax_failure = relaxation.relax_past_limit(self, st, u, step_start, f_ext,
                                                                                  target, stage_stats)
                    dlam = dl / 2.0 if ok else dlam  # after a snap the next step is as long (doubled below)
                if ok:
                    last_du, last_dlam = (u_new - u)[m.dofmap.free], target - lam
                    u = u_new
                    if state_load is not None:  # (the trial states are those of the converged solution)
                        f_ext = f_ext + state_load()
                    m.commit()
                    lam = target
                    self.stats.steps += 1
                    stage_stats["steps"] += 1
                    self.on_step(si, st, lam, u, f_int, f_ext)
                    if self.progress is not None:
                        self.progress(si, lam)
                    dlam = min(nominal, 2.0 * dlam)
                    cuts = 0
                    self._law_failure = None
                    continue
                # failure: cut the step, after reverting the trial state and latched bonds
                self.stats.step_cuts += 1
                stage_stats["step_cuts"] += 1
                final = not cutting.can_cut(cuts, dl)
                cuts += 1
                # a part that floats in the failed attempt (every joint around it open) is named
                parts = find_free_parts(m, constrained, use_joint_state=True) if final else []
                # otherwise the joints that gave way in that attempt name the mechanism and the part
                hint = "" if parts or not final else "".join(f"; in the last attempt {t}"
                                                             for t in joint_mechanisms(m))
                if final and st.varying is not None:
                    hint += st.varying.failure_hint()
                if final and self._law_failure:
                    hint += f"; in an attempt the joint or block law gave up: {self._law_failure}"
                if final and (relax_failure or not parts and singular is None and m.nonlinear):
                    hint += f"; {relax_failure}" if relax_failure else self._stall_hint(u_new, f_ext)
                m.revert()
                if final and st.until_failure:
                    what = ("a part lost every support" if parts else "singular stiffness" if singular is not None
                            else "no convergence") + hint
                    self.limit = {"stage": st.name, "load_factor": lam, "failed_at": target, "reason": what}
                    if st.varying is not None:  # e.g. the water level reached and the one tried
                        self.limit["attrs"], self.limit["text"] = st.varying.limit(lam, target)
                    self.stats.per_stage.append(dict(stage_stats, iterations=self.stats.iterations
                                                     + self.stats.joint_space_iterations - it_before))
                    return u
                if final and not parts and st.varying is None and last_du is not None and not relax_failure \
                        and float(np.linalg.norm(last_du)) > 0:
                    # load control stalled (a limit point, a snap): the rest of the stage under arc-length
                    # control from the last converged state, with the arc of its last increment
                    self.stats.arc_length_switches += 1
                    u, lam, tried = self._other_arcs(si, st, u, u_start, f_base, lam, stage_stats, last_du,
                                                     ARC_MODES, last_dlam)
                    if tried is not None:
                        hint += (f"; arc-length control from load factor {lam:.4g} did not get through either ("
                                 + "; ".join(tried) + ")")
                    else:
                        if self.limit is not None:
                            return u
                        cuts = 0
                        continue
                if final:
                    if parts:
                        raise MechanismError(
                            f"stage '{st.name}' at load factor {target:.4g}: no equilibrium; in the last attempt "
                            "a part lost every support", parts)
                    if singular is not None:
                        raise MechanismError(
                            f"stage '{st.name}' at load factor {target:.4g}: singular stiffness ({singular}); "
                            "a block may be rotating about a point contact or the load exceeds the collapse load"
                            + hint)
                    raise ConvergenceError(
                        f"stage '{st.name}': no convergence at load factor {target:.6g} after "
                        f"{s.max_step_cuts} step cuts (last increment {dl:.3g}); the structure may have reached "
                        "its collapse load under load control — use prescribed displacements, or more steps" + hint)
                dlam = dl / 2.0
            # general and joint-space Newton iterations, as the result file's ``iterations``
            stage_stats["iterations"] = self.stats.iterations + self.stats.joint_space_iterations - it_before
            self.stats.per_stage.append(stage_stats)
            f_base = f_base + st.force
        return u
