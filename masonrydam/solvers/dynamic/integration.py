"""Nonlinear dynamic analysis under uniform base excitation (relative formulation).

Equation of motion on the free DOFs, displacements ``u`` relative to the moving supports
(Chopra, *Dynamics of Structures*, 4th ed. 2012, sec. 9.4 and 13.1):

    M u'' + C u' + f_int(u) = f_s - sum_c (M iota_c) a_g,c(t)

``iota_c`` is the rigid unit translation in direction c of every node, supports included (``M iota_c``
is taken from the full-DOF mass, so a consistent mass couples the supports correctly); ``f_s`` is the
constant load of the static stages before (gravity), ``a_g,c`` the ground acceleration components
(horizontal and vertical together). Velocities and accelerations in the results are relative to the
ground unless named ``absolute``.

Effects add linear terms through :class:`DynamicTerms` (per stage): viscous boundaries (damping),
loads given in time (free-field forces, which replace ``-M iota a_g`` at a compliant base: the
displacements are then total), state forces held over a step (pore pressure entering opening
joints), and a compressible reservoir condensed into each step as a mass-like block on the wetted DOFs
(:mod:`.fluid`); constant added masses are in the mass matrix (:class:`~.modal.MassMatrix`).

Integrators
-----------
One implicit engine for the generalized-alpha family (Chung & Hulbert 1993, J. Appl. Mech. 60:371-375)

    (1 - am) M a_{n+1} + am M a_n + (1 - af) (C v_{n+1} + f_int(u_{n+1})) + af (C v_n + f_int(u_n))
        = (1 - af) p_{n+1} + af p_n

with Newmark's updates (Newmark 1959, J. Eng. Mech. Div. ASCE 85(EM3):67-94)
``u_{n+1} = u_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})``, ``v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1})``:

- ``newmark_average``: beta = 1/4, gamma = 1/2, am = af = 0 (trapezoidal rule; unconditionally stable,
  no numerical damping, period elongation ``Omega / (2 atan(Omega / 2))``, Hughes 2000 sec. 9.3);
- ``newmark_linear``: beta = 1/6, gamma = 1/2 (conditionally stable, ``Omega = omega h <= sqrt(12)``,
  Hughes 2000 Table 9.1.1; a larger dt is refused like for central difference);
- ``hht``: Hilber, Hughes & Taylor (1977), Earthquake Eng. Struct. Dyn. 5:283-292, alpha in [-1/3, 0]:
  am = 0, af = -alpha, gamma = (1 - 2 alpha)/2, beta = (1 - alpha)^2/4; spectral radius at infinity
  ``(1 + alpha)/(1 - alpha)``; internal forces interpolated between the ends of the step (the form for
  nonlinear problems, also used by Hughes 2000 sec. 9.3.3);
- ``generalized_alpha``: Chung & Hulbert (1993) eqs. 25, 17 and 20 with the user's rho_inf in [0, 1]:
  am = (2 rho - 1)/(rho + 1), af = rho/(rho + 1), gamma = 1/2 - am + af, beta = (1 - am + af)^2/4;
- ``central_difference`` (explicit; Hughes 2000 sec. 9.1.2 as the velocity form, Belytschko, Liu & Moran
  2000 Box 6.1): ``v_{n+1/2} = v_n + h/2 a_n``, ``u_{n+1} = u_n + h v_{n+1/2}``,
  ``M a_{n+1} = p_{n+1} - f_int(u_{n+1}) - C v_{n+1/2}`` (damping lagged half a step), ``v_{n+1} = v_{n+1/2}
  + h/2 a_{n+1}``. Lumped mass only. The critical step ``dt_crit = Omega_crit / omega_max`` with
  ``Omega_crit = 2 (sqrt(1 + xi^2) - xi)`` (Hughes 2000 sec. 9.1.2, viscous damping xi at omega_max;
  2 without damping) uses the largest eigenvalue of ``M^-1 K`` with every joint sticking (the joint
  penalty springs usually set it), found by Lanczos (ARPACK ``eigsh``, largest algebraic) on
  ``M^-1/2 K M^-1/2``; dt > ``stability_safety`` (0.9) x dt_crit is refused with a
  :class:`~masonrydam.errors.SceneError` that gives dt_crit.

Newton per step
---------------
The residual above divided by (1 - af), unknown u_{n+1}, iteration matrix
``K_eff = K_T + c_m M + c_c C`` with ``c_m = (1 - am)/((1 - af) beta h^2)``, ``c_c = gamma/(beta h)``.
Predictor: u_{n+1} = u_n with the tangent of the last converged iterate. Convergence: the force
residual ``||R|| <= force_tolerance * max(||M_eff a||, ||f_int||, ||p||, ||R_0||)`` and the work of
the last correction against the new residual ``|du . R_{k+1}| <= energy_tolerance |du_0 . R_0|``
(after an exact linear solve the new residual is zero, so a linear step takes one solve). Joint
laws are non-smooth, so: a backtracking line search on ||R|| (steps 1, 1/2, 1/4) when a full step
does not reduce it; a chatter guard as in the static solver (a joint-state pattern that comes back:
open points get their initial stiffness in the iteration matrix and broken bonds stay broken, until
the pattern has settled for two iterations, then the consistent tangent again); and a damping of
the correction when the residual norm repeats every other iteration (a pivot point whose friction
direction flips).

Sub-stepping: a step that does not converge (iteration limit, singular matrix, NaN) is reverted
(trial joint state discarded) and split in two halves, recursively, with the ground motion
interpolated linearly between record samples, to at most ``max_substeps`` halvings (2^max_substeps
sub-steps); then a :class:`~masonrydam.errors.ConvergenceError` names the time, the sub-step and
what failed, after the last converged state has been recorded. Every converged (sub-)step is
committed and kept; the run never continues past a step that did not converge.

Energy
------
Per step, trapezoidal works on the relative displacement increment: input ``-(M iota a_g) . du``,
external (constant static loads), damping ``C v . du``, joints ``f_joint . du`` (f_joint = f_int -
K_continuum u), plus kinetic ``v M v / 2`` and continuum strain ``u K_c u / 2`` energies and the
elastic energy stored in the joints (``(t_n^2/kn + |tau|^2/ks) A / 2`` over contact points). The joint
work is split point by point into stored energy, friction (traction times plastic slip), bond breaks
and contact events (:func:`~.kernels.joint_step_energy`: a point that opens or closes within
a step leaves a remainder, the trapezoidal work of the jump of its contact traction, which is lost at
an impact and *created* where a compressed point opens; Laursen & Chawla 1997, IJNME 40:863-886;
Armero & Petocz 1998, CMAME 158:269-300), and the integrator's numerical dissipation (HHT,
generalized-alpha) is computed from the scheme's own equations (:meth:`DynamicSolver._record_energy`).
Balance error = input + external - (kinetic + strain + damping + joint stored + friction + bond breaks
+ contact + numerical): the Newton tolerance and round-off (and, for central difference, the half step
its damping force lags). On the Koyna example at dt =
0.01 s the error of the old balance (14 % of its largest term) was numerical dissipation (36 % in the
first 8 s) less energy created at contact events (53 %); at dt = 1.25 ms they are 0.6 % and +2.2 %
(a net loss). :func:`energy_warnings` reports an error above 1 % and energy created at contact events
above 1 %. A step that lifts the mechanical energy (kinetic + elastic + joint stored - works of the
loads) above ``energy_growth_tolerance`` x the largest energy term is split like a non-converged one
(accepted at the last halving and reported in ``stats.energy_growth_max``).

Error-controlled steps (``dt = "auto"``)
----------------------------------------
:meth:`DynamicSolver._run_adaptive`: steps of dt_max / 2^k chosen by the larger of three local errors
(:meth:`DynamicSolver._step_error`: the Zienkiewicz-Xie estimate, the ground motion between a step's
ends, the energy of contact events) against ``tolerance``; refused steps are retried smaller, steps
never cross a multiple of dt_max (the output grid), and a step that does not converge at dt_min is
halved up to ``max_substeps`` more times. What the tolerance buys, against converged references, is
in docs/accuracy.md.

Fast path (how a step with sticking joints costs about as much as a linear step)
--------------------------------------------------------------------------------
The continuum is linear, so the nonlinearity of a step sits in the joint law alone. At the nominal
step size a step is first solved in *joint space* (:mod:`masonrydam.solvers.joint_space`, ``joint_space = "auto"``):
the step's equations condensed on the local relative displacements of the nonlinear joint points
through the dense flexibility ``S = B K_ref^-1 B^T`` of the all-stick effective matrix (set up once
per stage: one multi-right-hand-side substitution per joint unknown). A step whose points all stick
is then one substitution (the elastic predictor), exactly like a linear step; a step with sliding or
open points iterates on the joint unknowns with small dense LU factorizations of the active
components and costs one more substitution at the end; no sparse matrix is factorized. The result
is accepted by the same full-residual test as any Newton iterate. A step that the joint-space
iteration does not converge within its limits is halved like a failed step (each sub-step size
gets its own joint-space system, set up the first time it is needed); at the last halving it goes
on from its last iterate in the general path below. ``"auto"`` (the same as ``"on"``) condenses any
number of joint unknowns: up to ``JOINT_SPACE_MAX`` the flexibility S is set up at once (8 m^2
bytes), above it its columns are computed when a step first needs them and kept in a bounded store
(:class:`~masonrydam.solvers.joint_space.FlexibilityColumns`); ``"off"`` forces the general path.

Because the all-stick matrix is symmetric positive definite and solved once or twice per step for
the whole record, it is factorized as a sparse ``L D L^T`` with numba substitutions
(:class:`~masonrydam.solvers.linear.direct.SymmetricFactorization`, when the scene's ``linear_solver`` is
``"auto"``; about 2-3x faster per solve than PARDISO's solve phase on the Koyna section), and the
dense LU of the joint-space iterations is LAPACK's, with BLAS pinned to one thread during the stage
(threadpoolctl) so that runs stay bitwise reproducible. ``dynamic_reference_solver`` in the result
attributes and the run summary say which factorization the all-stick matrix got.

General path. ``K_eff`` changes only where joint points leave the elastic (stick)
state. :class:`EffectiveSolver` keeps up to three LU factorizations of ``K_eff`` (the all-stick
matrix of the nominal step, factorized once at the start and pinned, and the latest others). Every
Newton iteration takes the first that applies:

1. All joint points stick (checked on the trial state codes; the stick tangent depends on nothing
   else, so the tangent is then bitwise the elastic one): the interface pass computes forces only
   and the pinned factorization is used by name. Otherwise the tangent's values are compared with
   the cached matrices (``np.array_equal``). A match costs one forward/back substitution. A linear
   scene therefore factorizes once for the whole record, and a scene whose joints stick costs one
   interface pass more per iteration than a linear one.
2. The difference from a cached matrix is confined to the DOFs ``J`` of the points that slide or
   opened: ``K_eff = K_ref + P E P^T`` (E m x m, m = |J| <= ``low_rank_max``) and the
   Sherman-Morrison-Woodbury identity ``x = y - Z (I + E Z_JJ)^-1 E y_J`` with ``y = K_ref^-1 b``,
   ``Z = K_ref^-1 P`` (Golub & Van Loan, *Matrix Computations*, 4th ed. 2013, sec. 2.1.4) gives the
   exact Newton correction from the old factorization (numba kernels in
   :mod:`.kernels`, single-threaded and deterministic). Columns of Z are computed once per
   DOF (a multi-RHS substitution) and kept with their reference; the m x m factors are kept while
   (J, E) repeat (the same points sliding the same way). An update may ask for at most
   :func:`low_rank_column_budget` (``0.3 sqrt(n)``, about half a factorization) new columns; the
   solution is checked (relative residual <= 1e-6 with the true matrix). When columns are not being
   reused (fewer than one solve per 4 columns after 16 budgets: states change everywhere at once)
   low-rank updates are switched off for the rest of the stage. All choices depend on counts, not
   timings, so runs are reproducible bitwise.
3. Otherwise the current ``K_eff`` is factorized and cached.

Modified Newton with the old factorization (the static solver's option, ``modified_newton = True``
here) was measured and is off by default: on the 7 048-equation wall below with dry head joints it
doubled the iterations, triggered the chatter guard 38 times and ran at 130 ms/step against 64 for
full Newton; on the sliding block it saved nothing (the sliding tangent, once factorized, repeats).
Each factorization's PARDISO iterative refinement is switched off (``iparm(8) = 0``): two
refinement steps made each substitution 7x slower (4.5 ms against 0.64 ms at 7 048 equations) and
serve only perturbed pivots, which :class:`~masonrydam.solvers.linear.direct.Factorization` rejects.

Measured for the general path alone, before the joint-space path existed and before a row-swap error
in the Woodbury solves was fixed (failed updates were caught by the residual check and refactorized,
so the low-rank figures below understate that path; one PARDISO thread, 2-core shared machine, HHT
alpha = -0.1, dt = 5 ms, El Centro 1940 NS at
0.7 g with the vertical component, 600 steps; wall of ``examples/wall_el_centro.toml`` enlarged to
2.4 x 1.6 m: 7 048 equations, 2 464 joint points, solver time without output):

==========================================  =========  ==============  ===================
joints                                      ms/step    factorizations  low-rank solves
==========================================  =========  ==============  ===================
all linear                                  3.0 - 5.6  1               0
Mohr-Coulomb, all sticking (0.2 g)          3.4 - 5.6  1               0
cohesive bed/head joints, dry base slides   7.7 - 10   1               355 (rank <= 254)
  same, refactorizing on every change       14 - 17    194             0
all joints dry (head joints at zero normal  64         307             65 (then off)
stress switch state everywhere), 0.3 g
  same, refactorizing on every change       53 - 62    341             0
==========================================  =========  ==============  ===================

(ranges: repeated runs on the shared machine). The sticking case stays within 10 % of the linear
one; confined sliding costs about 2x a linear step instead of 4x; when the nonlinearity is
everywhere, a factorization per changed iteration (~26 ms here) dominates and low-rank updates
cannot help (they switch themselves off). Reusing PARDISO's symbolic analysis between
factorizations of the same pattern (22 ms of the 38 ms measured for a factorization here) would
roughly halve that case; it belongs in :class:`~masonrydam.solvers.linear.direct.Factorization`.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from threadpoolctl import threadpool_limits

from ...errors import ConvergenceError, NumericalError, RunStopped, SceneError
from ...assembly.damping import RayleighDamping
from ...assembly.elastic import elastic_joint_full, elastic_tangent_data
from ...assembly.mass import MassMatrix
from ...assembly.sparsity import add_to_pattern
from .kernels import joint_step_energy, joint_stored_energy, newmark_kinematics, newmark_residual, step_works
from ..chatter import ChatterGuard
from ..joint_space import (MAX_INITIAL_STIFFNESS_ITERATIONS, SPLIT_INITIAL_STIFFNESS_ITERATIONS, JointSpace,
                          joint_space_size)
from ..linear.dense_lu import woodbury_apply, woodbury_factor
from ..linear.direct import DIRECT_SOLVERS, Factorization, SingularMatrix, SymmetricFactorization, resolve_backend

JOINT_SPACE_MODES = ("auto", "on", "off")
INTEGRATORS = ("newmark_average", "newmark_linear", "hht", "generalized_alpha", "central_difference")

#: open-joint tangent factor in dynamics: 0 (consistent; the mass keeps K_eff regular)
OPEN_TANGENT_DYNAMIC = 0.0
#: a modified-Newton iteration (old factorization) is repeated only if it reduced the residual norm
#: at least by this factor; otherwise the next iteration refactorizes (or uses a low-rank update)
MODIFIED_NEWTON_CONTRACTION = 0.25

def low_rank_column_budget(n_eq: int) -> int:
    """New columns of ``Z`` (one substitution each) allowed for one low-rank update before a
    refactorization is preferred: about half the cost ratio of a factorization to a substitution.
    The ratio grows like sqrt(n) for 2D meshes; measured 33 ms against 0.65 ms (ratio 50) at 7 048
    equations (PARDISO, one thread), hence ``0.3 sqrt(n)``. Counts, not timings, so that the choice -
    and with it the last bits of every solution, which a nonlinear joint analysis amplifies - is
    the same in every run."""
    return max(8, int(0.3 * math.sqrt(max(n_eq, 1))))

#: dt = "auto": the smallest step by default is dt_max / 2^ADAPTIVE_DEFAULT_LEVELS
ADAPTIVE_DEFAULT_LEVELS = 10
#: dt = "auto": a step is taken one level larger when its error is below this fraction of the tolerance
#: (the Zienkiewicz-Xie estimate goes like h^3 on a smooth response: doubling h multiplies it by 8)
ADAPTIVE_GROW_FRACTION = 0.1
#: dt = "auto": steps taken at a level after a refusal before the step may grow again (a step that grows
#: straight back into the event that refused it is refused again: measured on the Koyna example at
#: tolerance 1e-5, 36 874 refusals for 80 809 steps without this hold)
ADAPTIVE_HOLD_STEPS = 4
#: dt = "auto": RMS displacement (m) below which the Zienkiewicz-Xie error is measured absolutely
ADAPTIVE_DISPLACEMENT_FLOOR = 1e-4

#: a Newton iterate whose force residual is below this fraction of the force tolerance is converged
#: whatever the work test says (round-off level)
ROUNDOFF_FRACTION = 1e-3

#: factorizations of effective matrices kept (the all-stick one of the nominal step included)
MAX_CACHED = 3
#: the joint-space Newton converges to this fraction of the step's force tolerance, so that the check
#: against the full residual, which adds the round-off of two substitutions, passes
JOINT_SPACE_FORCE_FRACTION = 0.5


@dataclass
class DynamicSettings:
    """Settings of one dynamic stage.

    integrator: one of :data:`INTEGRATORS`; dt: analysis time step (s); alpha: HHT parameter in
    [-1/3, 0]; rho_inf: generalized-alpha spectral radius at infinity in [0, 1]; max_iterations:
    Newton iterations per step; force_tolerance, energy_tolerance: convergence (dimensionless);
    max_substeps: halvings of a failing step; mass: "lumped" | "consistent"; damping: Rayleigh
    damping or None; linear_solver: backend of :class:`Factorization`; low_rank_max: largest rank of a
    Woodbury update before refactorizing (0: refactorize whenever the matrix changes);
    stability_safety: fraction of the critical step allowed for conditionally stable schemes;
    joint_space: "auto" | "on" | "off" - Newton condensed on the nonlinear joints
    (:mod:`masonrydam.solvers.joint_space`; "auto" and "on": whenever the model has nonlinear joints);
    adaptive: dt = "auto" (``dt`` is then the largest step, ``tolerance`` the relative local error per step
    and ``dt_min`` (s) the smallest step, default dt / 2^ADAPTIVE_DEFAULT_LEVELS; see
    :meth:`DynamicSolver._run_adaptive`);
    key: scene key prefix used in error messages (e.g. ``"stages[1]."``).
    """

    integrator: str = "hht"
    dt: float = 0.01
    alpha: float = -0.1
    rho_inf: float = 0.8
    max_iterations: int = 25
    force_tolerance: float = 1e-6
    energy_tolerance: float = 1e-8
    max_substeps: int = 4
    mass: str = "lumped"
    damping: RayleighDamping | None = None
    linear_solver: str = "auto"
    low_rank_max: int = 256
    modified_newton: bool = False
    line_search: bool = True
    energy_growth_tolerance: float = 1e-3
    stability_safety: float = 0.9
    joint_space: str = "auto"
    #: error-controlled steps (``dt = "auto"``): ``dt`` is then the largest step, the steps are dt / 2^k
    #: down to ``dt_min``, and ``tolerance`` bounds each step's local error (see :meth:`DynamicSolver._step_error`)
    adaptive: bool = False
    tolerance: float = 1e-5
    dt_min: float | None = None
    key: str = ""

    def __post_init__(self):
        k = self.key
        if self.integrator not in INTEGRATORS:
            raise SceneError(f"{k}integrator", f"must be one of {list(INTEGRATORS)}, got {self.integrator!r}")
        if not (math.isfinite(self.dt) and self.dt > 0):
            raise SceneError(f"{k}dt", f"must be a positive time step in s, got {self.dt!r}")
        if not (-1.0 / 3.0 - 1e-12 <= self.alpha <= 0.0):
            raise SceneError(f"{k}alpha", f"HHT alpha must be in [-1/3, 0], got {self.alpha!r}")
        if not (0.0 <= self.rho_inf <= 1.0):
            raise SceneError(f"{k}rho_inf", f"must be in [0, 1], got {self.rho_inf!r}")
        if self.mass not in ("lumped", "consistent"):
            raise SceneError(f"{k}mass", f"must be 'lumped' or 'consistent', got {self.mass!r}")
        if self.integrator == "central_difference" and self.mass != "lumped":
            raise SceneError(f"{k}mass", "central difference is explicit and needs mass = 'lumped'")
        if int(self.max_iterations) < 1:
            raise SceneError(f"{k}max_iterations", f"must be >= 1, got {self.max_iterations!r}")
        if int(self.max_substeps) < 0:
            raise SceneError(f"{k}max_substeps", f"must be >= 0, got {self.max_substeps!r}")
        for name in ("force_tolerance", "energy_tolerance"):
            v = getattr(self, name)
            if not 0.0 < v < 1.0:
                raise SceneError(f"{k}{name}", f"must be in (0, 1), got {v!r}")
        if self.adaptive:
            if self.integrator == "central_difference":
                raise SceneError(f"{k}dt", "dt = 'auto' needs an implicit integrator (central difference is bound to "
                                           "its critical step)")
            if self.integrator == "newmark_linear":
                raise SceneError(f"{k}dt", "dt = 'auto' estimates the error from beta - 1/6, which is zero for "
                                           "newmark_linear: use hht, newmark_average or generalized_alpha")
            if not 0.0 < self.tolerance < 1.0:
                raise SceneError(f"{k}tolerance", f"must be a relative local error in (0, 1), got {self.tolerance!r}")
            if self.dt_min is None:
                self.dt_min = self.dt / 2 ** ADAPTIVE_DEFAULT_LEVELS
            if not (math.isfinite(self.dt_min) and 0.0 < self.dt_min <= self.dt):
                raise SceneError(f"{k}dt_min", f"must be in (0, dt_max = {self.dt:g} s], got {self.dt_min!r}")
        if self.joint_space not in JOINT_SPACE_MODES:
            raise SceneError(f"{k}joint_space", f"must be one of {list(JOINT_SPACE_MODES)}, got {self.joint_space!r}")
        if self.linear_solver not in ("auto",) + DIRECT_SOLVERS:
            raise SceneError(f"{k}linear_solver", f"dynamic stages use a direct solver (the fast path reuses and "
                                                  f"updates factorizations): one of {('auto',) + DIRECT_SOLVERS}, "
                                                  f"got {self.linear_solver!r}")

    def coefficients(self):
        """(beta, gamma, alpha_m, alpha_f) of the implicit scheme."""
        i = self.integrator
        if i == "newmark_average":
            return 0.25, 0.5, 0.0, 0.0
        if i == "newmark_linear":
            return 1.0 / 6.0, 0.5, 0.0, 0.0
        if i == "hht":
            a = self.alpha
            return (1.0 - a) ** 2 / 4.0, (1.0 - 2.0 * a) / 2.0, 0.0, -a
        if i == "generalized_alpha":
            r = self.rho_inf
            am, af = (2.0 * r - 1.0) / (r + 1.0), r / (r + 1.0)
            return (1.0 - am + af) ** 2 / 4.0, 0.5 - am + af, am, af
        raise ValueError(f"{i} is explicit")

    def as_dict(self):
        d = asdict(self)
        d["damping"] = None if self.damping is None else asdict(self.damping)
        return d


@dataclass
class GroundMotion:
    """One ground acceleration component: samples ``values`` (m/s2) every ``dt`` s from the stage start,
    interpolated linearly in between and zero after the last sample. ``attrs``: provenance (netCDF
    attributes)."""

    component: int
    values: np.ndarray
    dt: float
    name: str = ""
    attrs: dict = field(default_factory=dict)

    def __post_init__(self):
        self.values = np.ascontiguousarray(self.values, dtype=np.float64)
        if self.values.ndim != 1 or len(self.values) < 2:
            raise SceneError(f"ground_motion.{'xyz'[self.component]}", "a record needs at least 2 samples")
        if not np.isfinite(self.values).all():
            raise SceneError(f"ground_motion.{'xyz'[self.component]}", "the record contains NaN or infinity")
        if not (math.isfinite(self.dt) and self.dt > 0):
            raise SceneError(f"ground_motion.{'xyz'[self.component]}.dt", f"must be > 0, got {self.dt!r}")
        self._times = np.arange(len(self.values)) * self.dt

    @property
    def duration(self) -> float:
        return (len(self.values) - 1) * self.dt

    def at(self, t: float) -> float:
        if t < 0.0 or t > self._times[-1] * (1 + 1e-12):
            return 0.0
        return float(np.interp(t, self._times, self.values))

    @property
    def peak_velocity(self) -> float:
        """Peak ground velocity (m/s) of the record as given (trapezoidal integral from rest)."""
        if not hasattr(self, "_pgv"):
            v = np.concatenate(([0.0], np.cumsum(0.5 * (self.values[1:] + self.values[:-1]) * self.dt)))
            self._pgv = float(np.max(np.abs(v)))
        return self._pgv

    def chord_error(self, t0: float, t1: float) -> float:
        """Integral over [t0, t1] of |a_g(t) - chord| (m/s), the chord being the straight line between
        a_g(t0) and a_g(t1): the velocity a step from t0 to t1 misses by taking the ground load as linear
        over the step (the implicit schemes see its ends only). Exact for the piecewise-linear record,
        including its jump to zero after the last sample. Zero when the record is linear over the step."""
        if t1 <= t0:
            return 0.0
        t_end = self._times[-1] * (1 + 1e-12)
        a0, a1 = self.at(t0), self.at(t1)
        # breakpoints of a_g inside the step: samples, and the record's end (a jump to zero)
        i0 = int(math.floor(t0 / self.dt)) + 1
        i1 = min(int(math.ceil(t1 / self.dt)) - 1, len(self.values) - 1)
        t_in = np.arange(i0, i1 + 1) * self.dt if i1 >= i0 else np.zeros(0)
        t_in = t_in[(t_in > t0) & (t_in < t1)]
        jump = t0 <= t_end < t1 and self.values[-1] != 0.0
        if len(t_in) == 0 and not jump:
            return 0.0
        tt = np.concatenate(([t0], t_in, [t1]))
        f = np.concatenate(([a0], np.interp(t_in, self._times, self.values), [a1]))
        if jump:  # a_g falls from the last sample to zero at t_end: split the segment there
            k = int(np.searchsorted(tt, t_end, side="right"))
            tt = np.concatenate((tt[:k], [t_end, t_end], tt[k:]))
            f = np.concatenate((f[:k], [self.values[-1], 0.0], f[k:]))
        d = f - (a0 + (a1 - a0) * (tt - t0) / (t1 - t0))
        # |d| is linear on each piece: integrated exactly, also where d changes sign inside it (one pass
        # in numpy: a step of dt_max over a pulse sampled at dt_min holds a thousand samples)
        da, db, h = d[:-1], d[1:], np.diff(tt)
        same = da * db >= 0.0
        width = np.abs(da) + np.abs(db)
        piece = np.where(same, 0.5 * width, 0.5 * (da * da + db * db) / np.where(same, 1.0, width))
        return float(np.sum(piece * h))


@dataclass
class DynamicTerms:
    """Linear terms that effects other than the blocks and joints add to a dynamic stage (all optional).

    dashpots: (n_dof, n_dof) sparse, N s/m: viscous boundaries added to the damping matrix (e.g. the
    foundation's absorbing boundaries, :mod:`masonrydam.effects.foundation`); their entries must lie in
    the model's pattern (node blocks).
    force: ``force(tau) -> (n_dof,)`` N, a load given in time (stage time tau, s): e.g. free-field
    effective forces; its work is counted as ``input``.
    state_force: ``state_force() -> (n_dof,)`` N from the committed joint states, evaluated at the start
    of every step and held over it (e.g. the change of the pore pressure as cracks open, zero at the
    static state); counted as ``input``.
    bottom_acceleration: ``bottom_acceleration(tau) -> (dim,)`` m/s2, the total acceleration of the
    ground under the reservoir (the free field at the rock's surface with a foundation of mass);
    default the ground motion.
    fluid: :class:`~masonrydam.solvers.dynamic.fluid.AcousticStep` (a compressible reservoir condensed on the
    wetted DOFs, which must be coupled in the pattern); its work on the dam is ``hydrodynamic``.
    support_excitation: apply the ground motion as ``-M iota a_g`` (the relative formulation); False
    when the ground motion enters through ``force`` (a compliant base): displacements are then total.
    """

    dashpots: sp.spmatrix | None = None
    force: object = None
    state_force: object = None
    fluid: object = None
    support_excitation: bool = True
    bottom_acceleration: object = None


@dataclass
class DynamicStage:
    """A dynamic stage: ``duration`` s under ``ground_motion`` (list of :class:`GroundMotion`, may be
    empty), with ``supports`` (n_dof,) bool (DOFs moving with the ground), ``settings`` and
    ``output_stride`` (record every k-th step; the first and last are always recorded);
    ``initial_velocity`` (n_dof,) m/s, NaN where not given: the velocity the stage starts with at those
    DOFs (relative to the ground)."""

    name: str
    duration: float
    supports: np.ndarray
    ground_motion: list
    settings: DynamicSettings
    output_stride: int = 1
    terms: DynamicTerms | None = None
    initial_velocity: np.ndarray | None = None
    #: ``loads(tau) -> (n_dof,)`` N: the stage's loads given in time (stage time tau, s), or None
    loads: object = None
    #: (n_dof,) m, NaN where not given: a displacement added to the state the stage starts from (at rest in
    #: equilibrium there), so that it starts out of equilibrium: released from a deformed shape
    initial_displacement: np.ndarray | None = None

    def __post_init__(self):
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise SceneError(f"{self.settings.key}duration", f"must be > 0 s, got {self.duration!r}")
        if int(self.output_stride) < 1:
            raise SceneError(f"{self.settings.key}output.stride", f"must be >= 1, got {self.output_stride!r}")
        comps = [g.component for g in self.ground_motion]
        if len(set(comps)) != len(comps):
            raise SceneError(f"{self.settings.key}ground_motion", "a component is given twice")

    @property
    def n_steps(self) -> int:
        """Steps of dt (with dt = "auto": of the largest step, the grid the output lands on)."""
        return max(1, int(math.ceil(self.duration / self.settings.dt - 1e-9)))

    @property
    def levels(self) -> int:
        """dt = "auto": the smallest step is dt / 2^levels, the smallest such step not below dt_min (0 for
        fixed steps)."""
        s = self.settings
        return int(math.floor(math.log2(s.dt / s.dt_min) + 1e-9)) if s.adaptive else 0


@dataclass
class DynamicState:
    """Full-DOF state at time ``t`` (relative to the ground): u (m), v (m/s), a (m/s2); ``energy``:
    cumulative energies (J) since the start of the first dynamic stage."""

    t: float
    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    energy: dict = field(default_factory=dict)
    #: the compressible reservoir's state (:class:`~masonrydam.solvers.dynamic.fluid.FluidState`) and its force on
    #: the free wetted DOFs, carried into the next dynamic stage
    fluid: object = None
    fluid_force: np.ndarray | None = None


ENERGY_KEYS = ("input", "external", "hydrodynamic", "kinetic", "strain", "damping", "joint", "joint_stored",
               "joint_dissipated", "joint_friction", "joint_bond_break", "joint_contact", "numerical", "error")
#: the terms whose largest magnitude so far scales the balance ("% of the largest energy term")
ENERGY_SCALE_KEYS = ("input", "external", "kinetic", "strain", "joint", "damping")


@dataclass
class DynamicStats:
    steps: int = 0
    substeps: int = 0
    #: dt = "auto": steps refused and retried smaller (by the error control, or because Newton or the
    #: energy-growth check refused them; their work is in the iteration counts), and the smallest and
    #: largest steps taken (s)
    steps_rejected: int = 0
    dt_smallest: float = math.inf
    dt_largest: float = 0.0
    iterations: int = 0
    factorizations: int = 0
    exact_solves: int = 0
    low_rank_solves: int = 0
    low_rank_columns: int = 0
    modified_solves: int = 0
    max_rank: int = 0
    stabilized_steps: int = 0
    damped_iterations: int = 0
    line_searches: int = 0
    wall_time_s: float = 0.0
    output_time_s: float = 0.0
    energy_error_max: float = 0.0
    energy_growth_max: float = 0.0
    energy_rejections: int = 0
    energy_error_relative: float = 0.0
    #: largest energy term so far (J) and the final cumulative numerical dissipation, contact and bond-break
    #: energies (J), for :func:`energy_warnings`
    energy_scale: float = 0.0
    energy_numerical: float = 0.0
    energy_contact: float = 0.0
    energy_bond_break: float = 0.0
    dt_critical: float | None = None
    static_residual: float = 0.0
    joint_space_size: int = 0
    joint_space_setup_s: float = 0.0
    joint_space_steps: int = 0
    joint_space_iterations: int = 0
    joint_space_fallbacks: int = 0
    joint_space_splits: int = 0
    joint_space_dense_factorizations: int = 0
    joint_space_dense_updates: int = 0
    joint_space_holds: int = 0
    #: converged joint-space steps whose displacements came from the stored columns of K_ref^-1 B^T
    joint_space_column_recoveries: int = 0
    #: bytes of those stored columns (all step sizes)
    joint_space_column_bytes: int = 0
    #: columns of the joint flexibility computed as steps needed them (above JOINT_SPACE_MAX unknowns),
    #: and the seconds they took
    joint_space_flexibility_columns: int = 0
    joint_space_flexibility_s: float = 0.0
    #: step attempts that needed more flexibility columns than the store holds (general path instead)
    joint_space_store_full: int = 0
    #: the solvers of the all-stick effective matrices: "ldlt", "pardiso" or "superlu"
    reference_solvers: set = field(default_factory=set)
    per_stage: list = field(default_factory=list)

    def as_dict(self):
        return asdict(self)


class EffectiveSolver:
    """Solves ``K_eff x = b`` for effective matrices given by their values in one CSR pattern.

    See the module docstring (fast path). ``max_rank``: largest Woodbury rank; ``max_cached``:
    factorizations kept (the pinned one included).
    """

    class _Ref:
        def __init__(self, data, fact, n):
            self.data = data
            self.fact = fact
            self.zidx = np.full(n, -1, dtype=np.int64)
            self.zrows = np.zeros((0, n))
            self.nz = 0
            self.pinned = False
            self.jkey = None
            self.ZT = None
            self.key = None
            self.ekey = None
            self.S = None
            self.piv = None
            self.columns_computed = 0

    def __init__(self, indptr, indices, n, backend="auto", max_rank=256, max_cached=MAX_CACHED, stats=None,
                 symmetric_fast=False, reuse_analysis=False):
        self.indptr, self.indices, self.n = indptr, indices, n
        self.symmetric_fast = symmetric_fast
        self.reuse_analysis = reuse_analysis
        self.rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
        self.cols = indices.astype(np.int64)
        self.backend = backend
        self.max_rank = int(max_rank)
        self.max_cached = max(1, int(max_cached))
        self.refs: list[EffectiveSolver._Ref] = []
        self.stats = stats if stats is not None else DynamicStats()
        self.column_budget = low_rank_column_budget(n)
        self.low_rank_off = False
        self._loc = np.full(n, -1, dtype=np.int64)

    def _matrix(self, data):
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def factorize(self, data, pin=False, key=None, symmetric=False):
        """Factorize the effective matrix of values ``data`` and cache it (``pin``: never evicted).
        ``symmetric``: the matrix is a symmetric positive definite one (the all-stick matrix of a step
        size) that will be solved many times: with ``self.symmetric_fast`` it gets a sparse
        ``L D L^T`` with fast substitutions (:class:`~masonrydam.solvers.linear.direct.SymmetricFactorization`),
        falling back to the general backend should that refuse it."""
        fact = None
        if symmetric and self.symmetric_fast:
            try:
                fact = SymmetricFactorization(self._matrix(data.copy()))
            except (ValueError, SingularMatrix):
                fact = None
        if fact is None and self.reuse_analysis and len(self.refs) >= self.max_cached:
            fact = self._refactorize_oldest(data)
        if fact is None:
            fact = Factorization(self._matrix(data.copy()), self.backend)
        if symmetric:
            self.stats.reference_solvers.add(fact.backend)
        ps = getattr(fact, "_ps", None)
        if ps is not None:
            # PARDISO's default two steps of iterative refinement make each substitution ~7x slower
            # (4.5 ms against 0.64 ms on the 7 000-DOF wall); they only matter with perturbed pivots,
            # which Factorization rejects, and every solve's residual is checked (and Newton
            # recomputes the true residual), so they are switched off (iparm(8) = 0).
            ps.set_iparm(8, 0)
        self.stats.factorizations += 1
        ref = EffectiveSolver._Ref(data.copy(), fact, self.n)
        ref.pinned = pin
        ref.key = key
        self.refs.insert(0, ref)
        while len(self.refs) > self.max_cached:
            for k in range(len(self.refs) - 1, -1, -1):
                if not self.refs[k].pinned:
                    del self.refs[k]
                    break
            else:
                break
        return ref

    def _refactorize_oldest(self, data):
        """The factorization the cache would evict next, refactorized with ``data`` on its kept symbolic
        analysis (:meth:`~masonrydam.solvers.linear.direct.Factorization.refactorize`) and taken out of the cache;
        None where there is none (pinned, symmetric L D L^T, another backend)."""
        for k in range(len(self.refs) - 1, -1, -1):
            ref = self.refs[k]
            if ref.pinned or not isinstance(ref.fact, Factorization):
                continue
            # out of the cache before its factorization changes: a refactorization that raises (singular)
            # must not leave an entry whose values no longer match its factors
            del self.refs[k]
            return ref.fact if ref.fact.refactorize(self._matrix(data.copy())) else None
        return None

    def _substitute(self, ref, b):
        return ref.fact.solve(b)

    def solve(self, data, b, allow_inexact=False, key=None):
        """``(x, kind)``: kind "exact" (a cached factorization of this very matrix), "low_rank"
        (Woodbury update of a cached one: exact up to round-off), "modified" (the most recent
        factorization as an approximate iteration matrix; only if ``allow_inexact``) or "factorized".
        ``key``: a name for a matrix known to be the same whenever the key is (the all-stick matrix
        of a step size), which spares comparing the values."""
        for k, ref in enumerate(self.refs):
            if (key is not None and ref.key == key) or np.array_equal(ref.data, data):
                self.stats.exact_solves += 1
                if k:
                    self.refs.insert(0, self.refs.pop(k))
                return self._substitute(ref, b), "exact"
        if self.max_rank > 0 and self.refs:
            best = None
            for ref in self.refs:
                nz = np.flatnonzero(data != ref.data)
                J = np.union1d(self.rows[nz], self.cols[nz])
                if len(J) > self.max_rank:
                    continue
                # cost: the columns of Z not cached yet, one substitution each
                missing = int((ref.zidx[J] < 0).sum()) if ref.jkey != J.tobytes() else 0
                if best is None or missing < best[3]:
                    best = (ref, J, nz, missing)
            # new columns of one update within the budget; and low-rank updates stop for the rest of
            # the stage when their columns are not reused (many points switching state in every
            # iteration: fewer than one solve per 4 columns after 16 budgets of columns)
            if self.stats.low_rank_columns > 16 * self.column_budget and \
                    4 * self.stats.low_rank_solves < self.stats.low_rank_columns:
                self.low_rank_off = True
            if best is not None and not self.low_rank_off and best[3] <= self.column_budget:
                x = self._woodbury(best[0], best[1], best[2], data, b)
                if x is not None:
                    return x, "low_rank"
        if allow_inexact and self.refs:
            self.stats.modified_solves += 1
            return self._substitute(self.refs[0], b), "modified"
        ref = self.factorize(data, key=key, symmetric=key is not None)  # keys name all-stick matrices
        return self._substitute(ref, b), "factorized"

    def _woodbury(self, ref, J, nz, data, b):
        J = J.astype(np.int64)
        m = len(J)
        loc = self._loc
        loc[J] = np.arange(m)
        e_row = loc[self.rows[nz]]
        e_col = loc[self.cols[nz]]
        loc[J] = -1
        e_val = data[nz] - ref.data[nz]
        key = J.tobytes()
        if ref.jkey != key:
            missing = J[ref.zidx[J] < 0]
            if len(missing):
                if ref.nz + len(missing) > 4 * max(self.max_rank, 1):  # reset the column cache
                    ref.zidx[:] = -1
                    ref.nz = 0
                    missing = J
                B = np.zeros((self.n, len(missing)), order="F")
                B[missing, np.arange(len(missing))] = 1.0
                Z = np.asarray(ref.fact.solve(B)).reshape(self.n, len(missing))
                self.stats.low_rank_columns += len(missing)
                ref.columns_computed += len(missing)
                need = ref.nz + len(missing)
                if need > ref.zrows.shape[0]:
                    grown = np.zeros((max(need, 2 * ref.zrows.shape[0]), self.n))
                    grown[: ref.nz] = ref.zrows[: ref.nz]
                    ref.zrows = grown
                ref.zrows[ref.nz:need] = Z.T
                ref.zidx[missing] = np.arange(ref.nz, need)
                ref.nz = need
            ref.ZT = np.ascontiguousarray(ref.zrows[ref.zidx[J]])  # (m, n): row i = K_ref^-1 e_{J_i}
            ref.jkey = key
        e_val = np.ascontiguousarray(e_val)
        # the m x m factors depend on (J, E) only: kept while the same points slide the same way
        ekey = (key, e_row.tobytes(), e_col.tobytes(), e_val.tobytes())
        if ref.ekey != ekey:
            S = np.empty((m, m))
            piv = np.empty(m, dtype=np.int64)
            if woodbury_factor(ref.ZT, J, e_row, e_col, e_val, S, piv) != 0:
                ref.ekey = None
                return None
            ref.S, ref.piv, ref.ekey = S, piv, ekey
        y = np.ascontiguousarray(self._substitute(ref, b), dtype=np.float64)
        x = np.empty(self.n)
        w = np.empty(m)
        if woodbury_apply(ref.ZT, J, e_row, e_col, e_val, ref.S, ref.piv, y, w, x) != 0:
            return None
        nb = np.linalg.norm(b)
        if nb > 0 and np.linalg.norm(self._matrix(data) @ x - b) > 1e-6 * nb:
            return None
        self.stats.low_rank_solves += 1
        self.stats.max_rank = max(self.stats.max_rank, m)
        return x


class _RecentProducts:
    """The last ``size`` results ``y = A x`` of a linear map, found again by the value of ``x`` (comparing
    a few thousand values costs a tenth of a sparse product)."""

    def __init__(self, size: int):
        self.size = size
        self.items = []

    def get(self, x):
        for xc, yc in self.items:
            if np.array_equal(xc, x):
                return yc
        return None

    def put(self, x, y):
        self.items = [(x.copy(), y), *self.items[:self.size - 1]]


def critical_time_step(K: sp.csr_matrix, mass_diag: np.ndarray | None = None, M: sp.csr_matrix | None = None,
                       damping: RayleighDamping | None = None, omega_crit: float = 2.0, linear_solver="auto"):
    """(dt_crit, omega_max): largest circular frequency of ``K phi = omega^2 M phi`` (Lanczos, ARPACK
    largest algebraic) and the critical step ``Omega_crit / omega_max``; with Rayleigh damping the
    central-difference bound ``Omega_crit = 2 (sqrt(1 + xi^2) - xi)`` at omega_max (Hughes 2000, sec. 9.1.2)."""
    n = K.shape[0]
    Ks = ((K + K.T) * 0.5).tocsr()
    if mass_diag is not None:
        s = 1.0 / np.sqrt(mass_diag)
        A = sp.diags(s) @ Ks @ sp.diags(s)
        try:
            lam = spla.eigsh(A, k=1, which="LA", tol=1e-8, return_eigenvectors=False, ncv=min(n, 40))[0]
        except Exception:  # pragma: no cover - ARPACK failure: Gershgorin bound (safe, larger)
            lam = float(np.max(np.asarray(abs(A).sum(axis=1)).ravel()))
    else:
        fm = Factorization(M.tocsr(), linear_solver)
        Minv = spla.LinearOperator((n, n), matvec=fm.solve, dtype=np.float64)
        lam = spla.eigsh(Ks, k=1, M=M, Minv=Minv, which="LA", tol=1e-8, return_eigenvectors=False,
                         ncv=min(n, 40))[0]
    w = math.sqrt(max(float(lam), 0.0)) * (1.0 + 1e-6)  # Lanczos converges from below
    if w == 0:
        return math.inf, 0.0
    Oc = omega_crit
    if damping is not None and damping.active:
        xi = damping.alpha / (2 * w) + damping.beta * w / 2
        Oc = omega_crit * (math.sqrt(1 + xi * xi) - xi)
    return Oc / w, w


#: an energy balance whose error, or whose energy created at contact events, exceeds this fraction of its
#: largest term is reported (issue 14: "every example closes to 1 %")
ENERGY_WARNING_FRACTION = 0.01
#: how a step refused by dt = "auto"'s error control says so
_ERROR_REFUSAL = "local error"


def energy_warnings(stats: "DynamicStats", integrator: str, dt: str) -> list[str]:
    """The energy balance's warnings for a finished run (empty when it closes): the unexplained error
    above :data:`ENERGY_WARNING_FRACTION` of the largest term (Newton tolerance), energy *created* at
    contact events (compressed joint points that open within a step: the trapezoidal work of a jump in
    the contact traction, Laursen & Chawla 1997) above the same fraction. Each names the likely cause.
    The numerical dissipation is reported (result attributes, run summary), not warned about: with
    stiff joints the integrator damps their rattle after every impact even at a converged dt (a free
    rocking block at dt = 0.5 ms: 9 % of the input), which is how the model's impacts lose energy."""
    scale = stats.energy_scale
    if not scale > 0:
        return []
    out = []
    err = stats.energy_error_max / scale
    if err > ENERGY_WARNING_FRACTION:
        cause = ("central difference lags the damping force half a step: dt is too large for the damping"
                 if integrator == "central_difference" else
                 "the Newton tolerances (force_tolerance, energy_tolerance) are too loose for this run, or steps "
                 "were accepted at their last halving")
        out.append(f"the energy balance misses by {100 * err:.3g} % of its largest term ({stats.energy_error_max:.3g} "
                   f"J): {cause}")
    created = -stats.energy_contact / scale
    if created > ENERGY_WARNING_FRACTION:
        out.append(f"joint contact events created {100 * created:.3g} % of the largest energy term "
                   f"({-stats.energy_contact:.3g} J: compressed points opening within a step): dt = {dt} is "
                   f"too large for the joint stiffness and contact events are stepped over ({integrator}); "
                   "converge dt (a smaller dt, or dt = \"auto\"; docs/accuracy.md)")
    return out


def _step_end(k: int, n_steps: int, dt: float, duration: float, tau: float) -> tuple[float, float]:
    """End time and size of step ``k`` (1-based) of a stage: nominal steps use h = dt exactly (the
    cached effective matrix is keyed by its values); the last step ends at the stage's duration."""
    t_end = min(k * dt, duration) if k == n_steps else k * dt
    h = dt if k < n_steps or abs(t_end - tau - dt) <= 1e-9 * dt else t_end - tau
    return t_end, h


class DynamicSolver:
    """Time integration of a :class:`~masonrydam.assembly.model.Model` through a :class:`DynamicStage`.

    ``run(stage, u0, ...)`` continues from the displacement ``u0`` and the joint state committed in
    the model (the static state) and returns the final :class:`DynamicState`. ``on_step(rec)`` is
    called for every recorded step with a dict: ``step`` (index within the stage), ``t`` (s), ``u``,
    ``v``, ``a`` (relative, full-DOF), ``a_abs`` (absolute), ``ag`` (dim,) m/s2, ``energy`` (dict, J),
    ``iterations`` (Newton iterations since the last record), ``reaction`` (full-DOF, N, at the
    constrained DOFs; zero elsewhere), ``final`` (bool).

    ``stop_requested()``, when given, is asked after every converged step; a status it returns (e.g.
    ``"interrupted"``) records that step (if the stride skipped it) and raises
    :class:`~masonrydam.errors.RunStopped` naming the step and the time.
    """

    def __init__(self, model, settings: DynamicSettings, mass: MassMatrix | None = None, progress=None,
                 stop_requested=None):
        self.model, self.s = model, settings
        self.mass = mass if mass is not None else MassMatrix(model, settings.mass == "lumped")
        if self.mass.lumped != (settings.mass == "lumped"):
            raise ValueError("the mass matrix passed does not match settings.mass")
        self.progress = progress
        self.stop_requested = stop_requested
        self.stats = DynamicStats()
        self.backend = resolve_backend(settings.linear_solver)
        self._Kj_full = None
        self._js_by_h = {}  # joint-space systems by step size (empty: the path is off)

    # ------------------------------------------------------------------------------------------
    def _setup(self, stage):
        m, s = self.model, self.s
        composite = [g.name for g in m.igroups if g.law == "composite"]
        if composite:
            raise SceneError(f"joints.{composite[0]}.law", "the composite (softening) joint law is available in static "
                                                           "stages only so far (its energy split and joint-space "
                                                           "kernels are not written); use law = \"mohr_coulomb\" for a "
                                                           "dynamic analysis")
        m.set_constraints(stage.supports)
        self.free = free = m.dofmap.free
        self.n = m.dofmap.n_eq
        self.Mdata = self.mass.for_pattern(m)
        self.Kel = elastic_tangent_data(m)
        d = s.damping
        self.damped = d is not None and d.active
        if self.damped:
            Kd = m.elastic_continuum_data() if d.exclude_joints else self.Kel
            # mass-proportional damping of the continuum's own mass, not of the water's added mass
            self.Cdata = d.alpha * self.mass.structural_data + d.beta * Kd
            Cf = d.alpha * self.mass.structural_full + d.beta * m.K_continuum_elastic
            if not d.exclude_joints:
                if self._Kj_full is None:
                    self._Kj_full = elastic_joint_full(m)
                Cf = Cf + d.beta * self._Kj_full
            self.C_full = Cf.tocsr()
            self.C_free = sp.csr_matrix((self.Cdata, m.indices, m.indptr), shape=(self.n, self.n))
        else:
            self.Cdata = np.zeros_like(self.Mdata)
            self.C_full = None
            self.C_free = None
        terms = self.terms = stage.terms if stage.terms is not None else DynamicTerms()
        if terms.dashpots is not None and terms.dashpots.nnz:
            D = sp.csr_matrix(terms.dashpots)
            Cd = np.zeros_like(self.Mdata)
            add_to_pattern(D[free][:, free], m.indptr, m.indices, Cd, "dashpot matrix")
            self.Cdata = self.Cdata + Cd
            self.C_full = D if self.C_full is None else (self.C_full + D).tocsr()
            self.C_free = sp.csr_matrix((self.Cdata, m.indices, m.indptr), shape=(self.n, self.n))
            self.damped = True
        self.fluid = terms.fluid
        if self.fluid is not None:
            if s.integrator == "central_difference":
                raise SceneError(f"{s.key}integrator", "the acoustic reservoir needs an implicit integrator (its "
                                                       "pressures are condensed into the implicit step); use hht")
            self.fluid.attach(m.dofmap.eq_of_dof, s.coefficients())
            n_w = len(self.fluid.wet_eq)
            rows = np.repeat(self.fluid.wet_eq, n_w)
            cols = np.tile(self.fluid.wet_eq, n_w)
            self._fluid_pattern = (rows, cols)
        self._sf = np.zeros(self.n)  # the state force of the current step (free DOFs)
        if self.mass.diagonal:
            self.mdiag = self.mass.free_diag
            self.M_free = None
        else:
            self.mdiag = None
            self.M_free = self.mass.free_matrix(m)
        self.Miota = self.mass.influence(m.dim)  # (dim, n_dof)
        self.Miota_f = np.ascontiguousarray(self.Miota[:, free])
        extra = self.mass.extra_influence
        self.extra_f = None if extra is None else np.ascontiguousarray(extra[:, free])
        self.ground = {g.component: g for g in stage.ground_motion}
        for c in self.ground:
            if c >= m.dim:
                raise SceneError(f"{s.key}ground_motion.{'xyz'[c]}", f"component {'xyz'[c]} in a {m.dim}D model")
        self._add_cache = {}
        self._kel_cache = {}
        # a step asks for the damping force of the same velocity up to five times (the step constant,
        # the residual at the accepted iterate, the energy balance of this step and of the next; the
        # joint-space path evaluates the residual at two velocities, so two remembered products would
        # lose the start-of-step one), and for the ground load of its two ends twice
        self._recent_Cv = _RecentProducts(3)
        self._recent_pg = _RecentProducts(2)
        self._joint_compliance = None
        self._joint_weight = None
        # operands of the step residual kernels (kernels.newmark_kinematics: the lumped mass
        # diagonal, or nothing for a consistent mass; no damping: a zero damping force)
        self._mass_diag = self.mdiag if self.mdiag is not None else np.zeros(0)
        self._zeros_free = np.zeros(self.n)

    def _Mf(self, x):
        return self.mdiag * x if self.mdiag is not None else self.M_free @ x

    def _Cf(self, x):
        """Damping force ``C x`` on the free DOFs (the last three remembered, see :meth:`_setup`). The
        returned array is shared: callers must not modify it."""
        if not self.damped:
            return np.zeros_like(x)
        y = self._recent_Cv.get(x)
        if y is None:
            y = self.C_free @ x
            self._recent_Cv.put(x, y)
        return y

    def ground_at(self, tau):
        ag = np.zeros(self.model.dim)
        for c, g in self.ground.items():
            ag[c] = g.at(tau)
        return ag

    def _pg_f(self, ag, tau):
        """Earthquake load on the free DOFs at stage time ``tau``: -sum_c (M iota_c) a_g,c with support
        excitation, plus the stage's load given in time (:class:`DynamicTerms`; the last two remembered).
        Shared array: do not modify."""
        key = np.append(ag, tau)
        v = self._recent_pg.get(key)
        if v is None:
            v = -(ag @ self.Miota_f) if self.terms.support_excitation else np.zeros(self.n)
            if self.extra_f is not None:  # the reservoir bottom pushing incompressible water
                v = v - self.bottom_at(tau, ag) @ self.extra_f
            if self.terms.force is not None:
                v = v + self.terms.force(tau)[self.free]
            self._recent_pg.put(key, v)
        return v

    def _state_force(self):
        """The state force of the step about to start (free DOFs; zero without one)."""
        if self.terms.state_force is not None:
            self._sf = self.terms.state_force()[self.free]
        return self._sf

    def _fluid_data(self, h):
        """``c_m M_w(h)`` in the pattern's values (the water condensed on the wetted DOFs)."""
        beta, gamma, am, af = self.s.coefficients()
        cm = (1.0 - am) / ((1.0 - af) * beta * h * h)
        data = np.zeros_like(self.Mdata)
        Mw = self.fluid.mass_block(h)
        add_to_pattern(sp.coo_matrix((cm * Mw.ravel(), self._fluid_pattern), shape=(self.n, self.n)),
                       self.model.indptr, self.model.indices, data, "reservoir block")
        return data

    def _elastic_eff(self, h):
        """Effective-matrix values with every joint point sticking, for step h (cached)."""
        v = self._kel_cache.get(h)
        if v is None:
            v = self.Kel + self._add(h)
            if len(self._kel_cache) > 8:
                self._kel_cache.clear()
            self._kel_cache[h] = v
        return v

    def _all_stick(self) -> bool:
        """Every point of every Mohr-Coulomb joint set sticks in the trial state: the tangent is then the
        elastic one, bitwise (the stick tangent depends on nothing but the geometry and ks, kn)."""
        from ...materials.mohr_coulomb import S_CODE, STICK

        if not self.model.condensable:  # nonlinear blocks or large kinematics: the tangent moves anyway
            return False
        return all((g.state_trial[:, :, S_CODE] == STICK).all() for g in self.model.igroups if g.nonlinear)

    def _add(self, h):
        """c_m M + c_c C values for sub-step h (cached per h)."""
        v = self._add_cache.get(h)
        if v is None:
            beta, gamma, am, af = self.s.coefficients()
            cm = (1.0 - am) / ((1.0 - af) * beta * h * h)
            cc = gamma / (beta * h)
            v = cm * self.Mdata + cc * self.Cdata
            if self.fluid is not None:
                v = v + self._fluid_data(h)
            if len(self._add_cache) > 8:
                self._add_cache.clear()
            self._add_cache[h] = v
        return v

    # ------------------------------------------------------------------------------------------
    def check_stability(self):
        """Refuse a time step above ``stability_safety`` x the critical one (explicit and linear-acceleration
        schemes); returns dt_crit or None for unconditionally stable schemes."""
        s = self.s
        if s.integrator == "central_difference":
            Oc = 2.0
        elif s.integrator == "newmark_linear":
            Oc = math.sqrt(12.0)
        else:
            return None
        K = sp.csr_matrix((self.Kel, self.model.indices, self.model.indptr), shape=(self.n, self.n))
        if s.integrator == "central_difference" and not self.mass.diagonal:
            raise SceneError(f"{s.key}integrator", "central_difference needs a diagonal mass matrix; the reservoir's "
                                                   "added mass couples DOFs (Westergaard's m_a n n^T on an inclined "
                                                   "face, or the acoustic water's rho Q H^-1 Q^T over the whole "
                                                   "face): use an implicit integrator (e.g. hht)")
        if self.mass.diagonal:
            md = self.mass.free_diag
            if not (md > 0).all():
                bad = int(self.free[np.nonzero(~(md > 0))[0][0]])
                raise SceneError(f"{s.key}integrator", f"{s.integrator} needs a positive mass at every free DOF; "
                                                       f"DOF {bad} (node {bad // self.model.dim}) has none (density 0?)")
            dtc, w = critical_time_step(K, mass_diag=md, damping=s.damping, omega_crit=Oc)
        else:
            dtc, w = critical_time_step(K, M=self.M_free, damping=s.damping, omega_crit=Oc,
                                        linear_solver=self.backend)
        self.stats.dt_critical = dtc
        if s.dt > s.stability_safety * dtc:
            raise SceneError(f"{s.key}dt", f"dt = {s.dt:.4g} s is above {s.stability_safety:g} x the critical time "
                                           f"step of {s.integrator}: dt_crit = {dtc:.4g} s (highest frequency "
                                           f"{w / (2 * math.pi):.4g} Hz with every joint sticking; the joint "
                                           f"penalty stiffnesses usually set it). Use dt <= "
                                           f"{s.stability_safety * dtc:.4g} s or an implicit integrator")
        return dtc

    # ------------------------------------------------------------------------------------------
    def reaction(self, u, v, a_abs, f_int, f_static, st=None):
        """Support reactions (full-DOF, N; zero at free DOFs): f_int + C v + M a_abs - f_static, less the
        water's force on constrained wetted DOFs (compressible: ``Q p``; incompressible: the push of the
        reservoir bottom) for the step state ``st``."""
        r = f_int - f_static + self.mass.full @ a_abs
        if self.damped:
            r = r + self.C_full @ v
        if st is not None:
            if self.mass.extra_influence is not None:
                r += self.bottom_at(st.tau, st.ag) @ self.mass.extra_influence
            if self.fluid is not None and st.fluid is not None and len(self.fluid.wet_fixed):
                r[self.fluid.wet_fixed] -= self.fluid.Qc @ st.fluid.p
        r[self.free] = 0.0
        return r

    def bottom_at(self, tau, ag):
        """Total acceleration (dim,) of the ground under the reservoir at stage time tau."""
        f = self.terms.bottom_acceleration
        return ag if f is None else f(tau)

    def frame_at(self, ag):
        """Acceleration (dim,) of the frame the displacements are measured in: the ground's in the
        relative formulation, zero when they are total."""
        return ag if self.terms.support_excitation else np.zeros_like(ag)

    def _joint_stored(self):
        """Elastic energy stored in the joints (J): sum over contact points of (t_n^2/kn + |tau|^2/ks)/2
        times the point's area; open points store nothing. Back stresses of the residual-stiffness
        hardening are counted as dissipated."""
        from ...materials import mohr_coulomb as mc

        if self._joint_compliance is None:  # w / (2 kn) and w / (2 ks) per point (m^3/N), once per stage
            self._joint_compliance = []
            for g in self.model.igroups:
                p = g.params_table[g.param_index]  # (ne, P)
                w = g.jw * g.thickness[:, None]
                self._joint_compliance.append((np.ascontiguousarray(0.5 * w / p[:, mc.P_KN][:, None]),
                                                np.ascontiguousarray(0.5 * w / p[:, mc.P_KS][:, None])))
        return sum((joint_stored_energy(g.traction, cn, cs) for g, (cn, cs) in zip(self.model.igroups,
                                                                                   self._joint_compliance)), 0.0)

    # ------------------------------------------------------------------------------------------
    def run(self, stage: DynamicStage, u0=None, v0=None, a0=None, f_static=None, equilibrate=True, t0=0.0,
            energy0=None, on_step=None, record_initial=True, fluid0=None) -> DynamicState:
        """Integrate ``stage`` from ``u0`` (m, full-DOF; default zero) and ``v0`` (m/s; default zero) at
        time ``t0``; the joints start from the state committed in the model.

        f_static: constant external load (full-DOF, N; default zero): the loads of the static stages.
        equilibrate: take the constant load on the free DOFs as ``f_int(u0)`` (the static state carried
        over exactly, the structure starts at rest in equilibrium; the difference from ``f_static``
        (the static solver's tolerance) is reported in ``stats.static_residual``). Pass False to start
        from a state that is not in equilibrium (e.g. a block released from a tilted position).
        a0: initial acceleration (default: from the equation of motion at t0).
        fluid0: the compressible reservoir's state at t0 (default: at rest), e.g. ``state.fluid`` of the
        stage before.
        """
        t_wall = time.perf_counter()
        m, s = self.model, self.s
        steps_before, rejected_before = self.stats.steps, self.stats.steps_rejected
        self._dt_range = [math.inf, 0.0]
        self.on_step = on_step or (lambda rec: None)
        self._setup(stage)
        free = self.free
        u = np.zeros(m.n_dof) if u0 is None else np.array(u0, dtype=np.float64)
        v = np.zeros(m.n_dof) if v0 is None else np.array(v0, dtype=np.float64)
        self.f_static = np.zeros(m.n_dof) if f_static is None else np.asarray(f_static, dtype=np.float64).copy()
        dtc = self.check_stability()
        m.set_open_tangent(OPEN_TANGENT_DYNAMIC)
        m.time_step = 0.0  # the state carried over, not a step in time
        try:
            f_int, K = m.evaluate(u, want_tangent=True)
            fs = self.f_static[free].copy()
            if equilibrate:
                diff = f_int[free] - fs
                scale = max(np.linalg.norm(fs), np.linalg.norm(f_int[free]), 1e-30)
                self.stats.static_residual = float(np.linalg.norm(diff) / scale)
                fs = f_int[free].copy()
            self.fs_f = fs
            if stage.initial_displacement is not None:  # released from a displaced state (the loads stay those
                # of the state it was displaced from, so the displacement is out of equilibrium)
                shift = np.where(np.isnan(stage.initial_displacement), 0.0, stage.initial_displacement)
                shift[~np.isin(np.arange(m.n_dof), free)] = 0.0
                u = u + shift
                f_int, K = m.evaluate(u, want_tangent=True)
                m.commit()  # the displaced state is where the stage starts: its joint states (slip) included
            ag0 = self.ground_at(0.0)
            if a0 is None:
                # (the pressure of a compressible reservoir is a state: its force at t0 is that of the
                # water carried over from the stage before, zero for water at rest)
                rhs = fs + self._pg_f(ag0, 0.0) + self._state_force() - f_int[free] - self._Cf(v[free])
                if self.fluid is not None and fluid0 is not None:
                    rhs = rhs.copy()
                    rhs[self.fluid.wet_eq] += self.fluid.force(fluid0)
                a = np.zeros(m.n_dof)
                if self.mdiag is not None:
                    with np.errstate(divide="ignore", invalid="ignore"):
                        a[free] = np.where(self.mdiag > 0, rhs / np.where(self.mdiag > 0, self.mdiag, 1.0), 0.0)
                else:
                    # DOFs without mass (massless rock) start with zero acceleration: their rows of the
                    # positive semi-definite M are zero, the rest is solved on its own
                    has = self.M_free.diagonal() > 0
                    if has.all():
                        a[free] = Factorization(self.M_free, self.backend).solve(rhs)
                    elif has.any():
                        Mh = self.M_free[has][:, has].tocsr()
                        a[free[has]] = Factorization(Mh, self.backend).solve(rhs[has])
            else:
                a = np.array(a0, dtype=np.float64)
            st = _StepState(t0, 0.0, u, v, a, f_int, None if np.array_equal(K.data, self.Kel) else K.data.copy(), ag0)
            st.Kc_u = m.continuum_force(u)
            st.joints = self._joint_snapshot()
            if self.fluid is not None:  # the water from the stage before, or at rest
                st.fluid = fluid0 if fluid0 is not None else self.fluid.initial_state()
                st.fw = self.fluid.force(st.fluid)
            en = dict.fromkeys(ENERGY_KEYS, 0.0) if energy0 is None else dict(energy0)
            self._en_ref = {"kinetic0": 0.5 * float(v[free] @ self._Mf(v[free])) - en.get("kinetic", 0.0),
                            "strain0": self._strain_energy(u, st.Kc_u) - en.get("strain", 0.0),
                            "stored0": self._joint_stored() - en.get("joint_stored", 0.0)}
            st.energy = en
            # (with the kinetic energy the stage starts with: a launched block's energy terms are changes of it)
            self._energy_scale = max([abs(en.get(key, 0.0)) for key in ENERGY_SCALE_KEYS]
                                     + [0.5 * float(v[free] @ self._Mf(v[free]))])
            self._iters_since_record = 0
            self._last_emitted_t = None if record_initial else st.t
            if record_initial:
                self._emit(stage, 0, st, final=False)
            if s.integrator == "central_difference":
                st = self._run_explicit(stage, st)
            else:
                # "auto": the all-stick matrices get the L D L^T with fast substitutions (linear/direct.py)
                # nonlinear blocks change every entry of the tangent in every iteration: no low-rank
                # updates (their search costs and never pays), and a new factorization reuses the
                # symbolic analysis of the one it evicts (same pattern; PARDISO phase 22)
                self.eff = EffectiveSolver(m.indptr, m.indices, self.n, self.backend,
                                           s.low_rank_max if m.condensable else 0, max_cached=MAX_CACHED,
                                           stats=self.stats, symmetric_fast=s.linear_solver == "auto",
                                           reuse_analysis=not m.condensable)
                ref = self.eff.factorize(self._elastic_eff(s.dt), pin=True, key=("elastic", s.dt), symmetric=True)
                self._setup_joint_space(ref)
                try:
                    # one BLAS thread: the dense LU of the joint-space solver (LAPACK) must be bitwise
                    # reproducible, and with few cores threads only slowed these small systems down
                    with threadpool_limits(limits=1, user_api="blas"):
                        st = (self._run_adaptive if s.adaptive else self._run_implicit)(stage, st)
                finally:
                    for js in self._js_by_h.values():
                        self.stats.joint_space_dense_factorizations += js.factorizations
                        self.stats.joint_space_dense_updates += js.updates
                        self.stats.joint_space_holds += js.hold_events
                        self.stats.joint_space_column_recoveries += js.column_recoveries
                        self.stats.joint_space_flexibility_columns += js.columns.computed
                        self.stats.joint_space_flexibility_s += js.columns.seconds
                    self.stats.joint_space_column_bytes = max(
                        self.stats.joint_space_column_bytes,
                        sum(js.XT.nbytes for js in self._js_by_h.values() if js.XT is not None))
                    self._js_by_h = {}  # their factors and columns: each stage sets up its own
        finally:
            m.set_open_tangent(1e-6)  # the static solver's regularisation (solvers.static.stepping.OPEN_TANGENT_REGULAR)
            self.stats.wall_time_s += time.perf_counter() - t_wall
        entry = {"stage": stage.name, "steps": self.stats.steps - steps_before, "dt": s.dt, "integrator": s.integrator,
                 "dt_critical": dtc}
        if s.adaptive:
            entry.update({"dt": "auto", "dt_max": s.dt, "dt_min": s.dt_min, "tolerance": s.tolerance,
                          "steps_rejected": self.stats.steps_rejected - rejected_before,
                          "dt_smallest": self._dt_range[0], "dt_largest": self._dt_range[1]})
        self.stats.per_stage.append(entry)
        return DynamicState(st.t, st.u, st.v, st.a, st.energy, st.fluid, st.fw)

    def _setup_joint_space(self, ref):
        """Condense the nominal step on the nonlinear joints (:mod:`masonrydam.solvers.joint_space`) if the settings and
        the size allow (``self._js_by_h`` stays empty otherwise)."""
        self._js_by_h = {}
        s, m = self.s, self.model
        if s.joint_space == "off" or not m.nonlinear or not m.condensable:
            return
        size = joint_space_size(m)
        self._new_joint_space(ref, s.dt)
        self.stats.joint_space_size = size

    def _new_joint_space(self, ref, h):
        t0 = time.perf_counter()
        # the stored recovery columns (n_eq x m) only at the nominal step size, and a quarter of the
        # memory for flexibility columns at a sub-step size: sub-steps are rare
        nominal = h == self.s.dt
        js = self._js_by_h[h] = JointSpace(self.model, ref.fact, store_columns=nominal,
                                           column_memory_share=1.0 if nominal else 0.25)
        self.stats.joint_space_setup_s += time.perf_counter() - t0
        return js

    def _joint_space_for(self, h):
        """The joint-space system of step size h: the nominal one, or one of a sub-step size (its
        all-stick matrix factorized and pinned, and its flexibility set up, when first needed; not
        for a large joint set, whose sub-steps take the general path, see :meth:`_implicit_try`)."""
        if not self._js_by_h:
            return None
        js = self._js_by_h.get(h)
        if js is None:
            levels = self.s.max_substeps + (self._levels if self.s.adaptive else 0)
            if not any(h == self.s.dt / 2 ** k for k in range(1, levels + 1)):
                return None  # e.g. a shorter last step of the stage: not worth a set-up
            if self._js_by_h[self.s.dt].columns.lazy:
                return None
            ref = self.eff.factorize(self._elastic_eff(h), pin=True, key=("elastic", h), symmetric=True)
            js = self._new_joint_space(ref, h)
        return js

    # ------------------------------------------------------------------------------------------
    def _joint_snapshot(self):
        """Copies of every joint set's (delta, traction, state) after the last evaluation: the end of a
        step for the energy split of :meth:`_record_energy` (and the start of the next)."""
        return [(g.delta.copy(), g.traction.copy(), g.state_trial.copy()) for g in self.model.igroups]

    def _restore_joint_fields(self, st):
        """After a refused step: the joints' relative displacements and tractions of the committed state
        ``st`` (``revert`` restores the law's state only), so that a retry accepted without a new
        evaluation (residual within tolerance at the predictor) records the right joint energies."""
        for g, (d, t, _) in zip(self.model.igroups, st.joints):
            g.delta[...] = d
            g.traction[...] = t

    def _record_energy(self, st, prev):
        """Accumulate the works of the step prev -> st (Hughes 2000, sec. 9.1.4) and the balance error.

        Terms (J, cumulative): the trapezoidal works of the loads, damping and joints; kinetic, strain and
        joint stored energies; the joint work split by :func:`~.kernels.joint_step_energy` into
        friction, bond breaks and contact events; and the integrator's numerical dissipation
        ``numerical = du . M (a0 + a1)/2 - dT - du . T_alpha`` with ``T_alpha = (am - 1/2) M da +
        (af - 1/2) (C dv + df - dp)``: the generalized-alpha equation of the step differs from the
        trapezoidal average of the equations at its two ends by exactly ``T_alpha`` (write both out), and
        the Newmark updates with gamma != 1/2 make the inertia work differ from the change of kinetic
        energy dT. Both vanish for the trapezoidal rule (beta = 1/4, gamma = 1/2, am = af = 0); for HHT and
        generalized-alpha their sum is the energy the scheme takes out of the high modes (its cumulative
        value is the dissipation plus a bounded "algorithmic energy" of order h^2 a.M a; Krenk 2006, Comput.
        Methods Appl. Mech. Eng. 195:6110-6124). For central difference ``numerical`` is the kinematic
        part ``-h^2/8 d(a.M a)`` alone (its damping force lags half a step; that lag stays in ``error``).
        What is left, ``error``, is the Newton tolerance and round-off (and central difference's damping lag)."""
        free = self.free
        e = dict(prev.energy)
        v0f, v1f = prev.v[free], st.v[free]
        cv0, cv1 = (self._Cf(v0f), self._Cf(v1f)) if self.damped else (self._zeros_free, self._zeros_free)
        if self.mdiag is not None:
            mv1 = ma0 = ma1 = self._zeros_free
        else:
            mv1, ma0, ma1 = self._Mf(v1f), self._Mf(prev.a[free]), self._Mf(st.a[free])
        w = np.empty(10)
        pg0, pg1 = self._pg_f(prev.ag, prev.tau) + self._sf, self._pg_f(st.ag, st.tau) + self._sf
        hydro = 0.0
        if self.fluid is not None:
            wet = self.fluid.wet_eq
            pg0, pg1 = pg0.copy(), pg1.copy()
            pg0[wet] += prev.fw
            pg1[wet] += st.fw
            hydro = 0.5 * float((prev.fw + st.fw) @ (st.u[free][wet] - prev.u[free][wet]))
        step_works(free, prev.u, st.u, pg0, pg1, self.fs_f, cv0, cv1, prev.f_int, st.f_int, prev.Kc_u, st.Kc_u, v1f,
                   self._mass_diag, mv1, prev.a, st.a, ma0, ma1, w)
        e["input"] += float(w[0]) - hydro
        e["hydrodynamic"] = e.get("hydrodynamic", 0.0) + hydro
        e["external"] += float(w[1])
        e["damping"] += float(w[2])
        e["joint"] += float(w[3])
        kinetic_before = e["kinetic"]
        e["kinetic"] = float(w[4]) - self._en_ref["kinetic0"]
        if self.model.plastic:  # the blocks' work, trapezoidal: stored energy and plastic dissipation together
            e["strain"] = prev.energy["strain"] + 0.5 * float((st.u - prev.u) @ (prev.Kc_u + st.Kc_u))
        else:
            e["strain"] = self._strain_energy(st.u, st.Kc_u) - self._en_ref["strain0"]
        numerical = float(w[5]) - (e["kinetic"] - kinetic_before)
        if self.s.integrator != "central_difference":
            _, _, am, af = self.s.coefficients()
            numerical -= (am - 0.5) * float(w[6]) + (af - 0.5) * (float(w[8]) + float(w[7]) - float(w[9]))
        e["numerical"] = e.get("numerical", 0.0) + numerical
        if self.model.igroups:
            e["joint_stored"] = self._joint_stored() - self._en_ref["stored0"]
            st.joints = self._joint_snapshot()
            split = np.zeros(5)
            for (d0, t0, s0), (d1, t1, s1), wt in zip(prev.joints, st.joints, self._joint_weights()):
                joint_step_energy(d0, t0, s0, d1, t1, s1, wt, split)
            for key, x in zip(("joint_friction", "joint_bond_break", "joint_contact"), split[:3]):
                e[key] = e.get(key, 0.0) + float(x)
        e["joint_dissipated"] = e["joint"] - e["joint_stored"]
        e["error"] = e["input"] + e["external"] + e["hydrodynamic"] - (e["kinetic"] + e["strain"] + e["damping"] + e["joint_stored"]
                                                   + e["joint_friction"] + e["joint_bond_break"]
                                                   + e["joint_contact"] + e["numerical"])
        st.energy = e

    def _strain_energy(self, u, Kc_u) -> float:
        """The blocks' elastic energy (J) at ``u`` (``Kc_u`` their forces there): ``u K_c u / 2`` for linear
        blocks, plus the exact St. Venant-Kirchhoff energy of large-kinematics groups."""
        if self.model.large:
            return self.model.continuum_energy(u)
        return 0.5 * float(u @ Kc_u)

    def _joint_weights(self):
        if self._joint_weight is None:
            self._joint_weight = [np.ascontiguousarray(g.jw * g.thickness[:, None]) for g in self.model.igroups]
        return self._joint_weight

    def _energy_growth(self, e) -> float:
        """Mechanical energy gained beyond what the loads supplied (J): kinetic + strain + joint stored
        + damping - external - input. Physically <= 0."""
        return (e["kinetic"] + e["strain"] + e["joint_stored"] + e["damping"] - e["external"] - e["input"]
                - e.get("hydrodynamic", 0.0))

    def _accept_energy(self, st):
        e = st.energy
        self._energy_scale = max([self._energy_scale] + [abs(e[key]) for key in ENERGY_SCALE_KEYS])
        g = self._energy_growth(e)
        if g > self.stats.energy_growth_max:
            self.stats.energy_growth_max = g
        err = abs(e["error"])
        self.stats.energy_error_max = max(self.stats.energy_error_max, err)
        if self._energy_scale > 0:  # largest error over the largest energy term, both so far
            self.stats.energy_error_relative = self.stats.energy_error_max / self._energy_scale
        self.stats.energy_scale = self._energy_scale
        self.stats.energy_numerical = e["numerical"]
        self.stats.energy_contact = e["joint_contact"]
        self.stats.energy_bond_break = e["joint_bond_break"]

    def _emit(self, stage, k, st, final):
        m = self.model
        a_abs = st.a.copy()
        if self.terms.support_excitation:  # else the motion is total already
            for c in range(m.dim):
                a_abs[c::m.dim] += st.ag[c]
        rec = {"step": k, "t": st.t, "u": st.u, "v": st.v, "a": st.a, "a_abs": a_abs, "ag": st.ag.copy(),
               "energy": dict(st.energy), "iterations": self._iters_since_record, "final": final,
               "stage_fraction": min(1.0, st.tau / stage.duration),
               "reaction": self.reaction(st.u, st.v, a_abs, st.f_int, self.f_static, st),
               "bottom_acceleration": self.bottom_at(st.tau, st.ag),
               "fluid": getattr(st, "fluid", None)}
        self._iters_since_record = 0
        self._last_emitted_t = st.t
        t0 = time.perf_counter()
        self.on_step(rec)
        self.stats.output_time_s += time.perf_counter() - t0

    def _maybe_emit(self, stage, k, st, n_steps):
        last = k == n_steps
        if last or k % stage.output_stride == 0:
            self._emit(stage, k, st, final=last)
        if self.progress is not None:
            self.progress(st.tau / stage.duration)
        status = self.stop_requested() if self.stop_requested is not None else None
        if status is not None and not last:
            self._fail(stage, st, RunStopped(status, f"at step {k} of {n_steps} (t = {st.t:.4g} s) of stage "
                                                     f"'{stage.name}'"))

    def _fail(self, stage, st, exc):
        """Record the last converged state (if not yet recorded) and raise."""
        if self._last_emitted_t != st.t:
            self._emit(stage, -1, st, final=True)
        raise exc

    # ------------------------------------------------------------------------------------------
    def _run_implicit(self, stage, st):
        s = self.s
        n_steps = stage.n_steps
        for k in range(1, n_steps + 1):
            t_end, h = _step_end(k, n_steps, s.dt, stage.duration, st.tau)
            if h <= 1e-9 * s.dt:
                break
            st = self._advance(stage, st, t_end, h, 0)
            self.stats.steps += 1
            self._maybe_emit(stage, k, st, n_steps)
        return st

    def _run_adaptive(self, stage, st):
        """dt = "auto": steps of dt / 2^level, the level set by the local error of each step
        (:meth:`_step_error`): a step above the tolerance is refused and retried smaller, one well below
        it lets the next step double. Steps never cross a multiple of dt (the largest step), so the
        output, every ``output_stride`` multiples of dt, lands on a regular grid without interpolation,
        and the effective matrices and joint-space systems exist for a few step sizes only (each set up
        the first time it is used). A step that does not converge is retried smaller like a refused one;
        below dt_min (and ``max_substeps`` further halvings) the run stops with a ConvergenceError after
        recording the last converged state."""
        s = self.s
        n_steps, top = stage.n_steps, stage.levels
        self._levels = top
        self._u_stage0 = st.u[self.free].copy()
        self._u_peak = self._v_peak = 0.0
        self._pgv = max((g.peak_velocity for g in self.ground.values()), default=0.0)
        self._last_error, self._error_levels = 0.0, 0
        level = hold = 0
        last_level = top + s.max_substeps
        for k in range(1, n_steps + 1):
            t_grid = min(k * s.dt, stage.duration)
            while t_grid - st.tau > 1e-9 * s.dt:
                h = s.dt / 2 ** level
                t_end = st.tau + h
                if t_end > t_grid - 1e-9 * s.dt:  # the step that reaches the grid point (or the stage's end)
                    if abs(t_grid - t_end) > 1e-9 * s.dt:
                        h = t_grid - st.tau  # a shorter last step of the stage
                    t_end = t_grid

                def check(new, old, h, enforce=level < top):
                    return self._step_error(new, old, h, enforce)

                # a joint-space iteration that does not converge goes on in the general path at every
                # level (the error decides the step size); below dt_min a step is halved for Newton's sake only
                ok, new, why = self._implicit_try(st, t_end, h, can_split=level < top, error_check=check,
                                                  split_joint_space=False)
                if not ok:
                    self.model.revert()
                    self._restore_joint_fields(st)
                    self.stats.steps_rejected += 1
                    if level >= last_level:
                        self._fail(stage, st, ConvergenceError(
                            f"dynamic stage '{stage.name}': no convergence in the step from t = {st.t:.6g} s to "
                            f"{st.t + h:.6g} s (step {h:.4g} s: dt_min = {s.dt_min:.4g} s and max_substeps = "
                            f"{s.max_substeps} further halvings): {why}. Every converged step before t = "
                            f"{st.t:.6g} s was kept"))
                    if why.startswith(_ERROR_REFUSAL):
                        level = min(level + self._error_levels, top)
                    else:
                        level += 1
                    hold = ADAPTIVE_HOLD_STEPS
                    continue
                st = new
                self.stats.steps += 1
                self._dt_range[0] = min(self._dt_range[0], h)
                self._dt_range[1] = max(self._dt_range[1], h)
                self.stats.dt_smallest = min(self.stats.dt_smallest, h)
                self.stats.dt_largest = max(self.stats.dt_largest, h)
                hold -= 1
                if level > 0 and hold <= 0 and self._last_error < ADAPTIVE_GROW_FRACTION * s.tolerance:
                    # one level up where the larger step stays on its own grid (steps never cross a
                    # multiple of dt, and a step of dt / 2^(level-1) starts at one of its multiples)
                    h_up = s.dt / 2 ** (level - 1)
                    if abs(st.tau / h_up - round(st.tau / h_up)) < 1e-6:
                        level -= 1
                elif level > top:
                    level = top  # a halving below dt_min for convergence: back to dt_min
            self._maybe_emit(stage, k, st, n_steps)
        return st

    def _step_error(self, new, st, h, enforce=True):
        """Local error of the step st -> new for dt = "auto" (None when it is within the tolerance,
        else why not). Three measures, the largest counts:

        - the Zienkiewicz-Xie estimate of the Newmark family, ``e = h^2 (beta - 1/6) (a_{n+1} - a_n)``
          (Zienkiewicz & Xie 1991, Earthquake Eng. Struct. Dyn. 20:871-887: the difference between the
          scheme's displacement and a third-order Taylor expansion), as ``||e|| / U`` (Euclidean norms
          over the free DOFs), U the largest ``||u - u_0||`` since the stage began (this step included;
          at least :data:`ADAPTIVE_DISPLACEMENT_FLOOR` per DOF, so that the first steps of a quiet
          record are not driven to dt_min);
        - the ground motion: the velocity the step misses by taking the ground acceleration as linear
          between its ends (:meth:`GroundMotion.chord_error`: a pulse that ends, or record samples inside
          a step longer than the record's interval) over the larger of the peak ground velocity and the
          largest relative velocity so far. The displacement estimate above cannot see it: the velocity
          error it leaves grows into the displacement over the rest of the record;
        - events: the energy a contact event leaves unaccounted by the trapezoidal rule (the step's
          change of ``joint_contact``, see :func:`~.kernels.joint_step_energy`: a joint point
          that opens or closes within the step) over the largest energy term so far. It shrinks as the
          event is resolved (the penetration stepped over goes like h), so steps are refined where
          joints open and close; sliding that starts or stops shows in the first measure as the
          jump of the acceleration.
        """
        s = self.s
        beta = s.coefficients()[0]
        free = self.free
        # Euclidean norms over the free DOFs, as Zienkiewicz & Xie: a joint's rattle, a few DOFs with
        # large accelerations, weighs by its share of the motion, not as much as the whole structure
        e_zx = h * h * abs(beta - 1.0 / 6.0) * float(np.linalg.norm(new.a[free] - st.a[free]))
        u_peak = max(self._u_peak, float(np.linalg.norm(new.u[free] - self._u_stage0)))
        eta_zx = e_zx / max(u_peak, ADAPTIVE_DISPLACEMENT_FLOOR * math.sqrt(len(free)))
        # the ground load between the step's ends: the velocity missed, over the velocity scale
        v_peak = max(self._v_peak, float(np.max(np.abs(new.v[free]), initial=0.0)))
        miss = max((g.chord_error(st.tau, new.tau) for g in self.ground.values()), default=0.0)
        eta_input = miss / max(v_peak, self._pgv, 1e-300) if miss > 0 else 0.0
        scale = max(self._energy_scale, abs(new.energy["input"]), abs(new.energy["external"]), 1e-300)
        eta_event = abs(new.energy["joint_contact"] - st.energy["joint_contact"]) / scale
        if self._energy_scale <= 0:
            eta_event = 0.0
        eta = max(eta_zx, eta_input, eta_event)
        self._last_error = eta
        if eta <= s.tolerance or not enforce:  # at dt_min the step is taken whatever its error
            self._error_levels = 0
            self._u_peak, self._v_peak = u_peak, v_peak  # the peaks of accepted steps only
            return None
        # error ~ h^3: the level that should bring it within 0.8 x the tolerance
        self._error_levels = max(1, int(math.ceil(math.log2((eta / (0.8 * s.tolerance)) ** (1.0 / 3.0)))))
        what = ("contact events" if eta_event >= eta else "ground motion between the step's ends" if eta_input >= eta
                else "Zienkiewicz-Xie estimate")
        return f"{_ERROR_REFUSAL} {eta:.3g} > tolerance {s.tolerance:g} ({what})"

    def _advance(self, stage, st, t_end, h, level):
        """Advance the committed state ``st`` by ``h`` to stage time ``t_end``, halving on failure."""
        ok, new, why = self._implicit_try(st, t_end, h, can_split=level < self.s.max_substeps)
        if ok:
            return new
        self.model.revert()
        self._restore_joint_fields(st)
        if level >= self.s.max_substeps:
            self._fail(stage, st, ConvergenceError(
                f"dynamic stage '{stage.name}': no convergence in the step from t = {st.t:.6g} s to "
                f"{st.t + h:.6g} s (sub-step {h:.4g} s after {level} halving(s) of dt = {self.s.dt:g} s; "
                f"max_substeps = {self.s.max_substeps}): {why}. Every converged step before t = {st.t:.6g} s "
                "was kept"))
        self.stats.substeps += 1
        st = self._advance(stage, st, st.tau + 0.5 * h, 0.5 * h, level + 1)
        return self._advance(stage, st, t_end, 0.5 * h, level + 1)

    def _implicit_try(self, st, t_end, h, can_split=True, error_check=None, split_joint_space=True):
        """One step of size ``h`` from the committed state ``st`` to stage time ``t_end``; returns
        (ok, new_state, why). ``can_split``: the caller can still halve the step, so a joint-space
        iteration that does not converge and a step that gains energy are refused (ok False) rather
        than finished in the general path or accepted. ``error_check(new, st, h)``: dt = "auto"'s local
        error test before the step is committed (a reason string refuses it). ``split_joint_space``
        False: a joint-space iteration that does not converge goes on in the general path at this step
        size even where the step could be halved (dt = "auto": the error decides the step size; halving
        for the joint-space iteration's sake took 2 484 of 2 801 refusals on the Koyna example at
        tolerance 1e-5 and held the steps small after them)."""
        m, s = self.model, self.s
        m.time_step = h  # (Perzyna laws of elasto-plastic blocks)
        free = self.free
        beta, gamma, am, af = s.coefficients()
        w_m = (1.0 - am) / (1.0 - af)
        ag1 = self.ground_at(t_end)
        sf = self._state_force()
        p1 = self.fs_f + self._pg_f(ag1, t_end) + sf
        pn = self.fs_f + self._pg_f(st.ag, st.tau) + sf
        un, vn, an = st.u[free], st.v[free], st.a[free]
        fluid = self.fluid
        if fluid is not None:
            # the water's force at the end of the step, less its M_w a1 part (added in residual below)
            wet = fluid.wet_eq
            g_w, fluid_ctx = fluid.start(st.fluid, h, an[wet], self.frame_at(st.ag), self.frame_at(ag1),
                                         self.bottom_at(st.tau, st.ag), self.bottom_at(t_end, ag1))
            Mw = fluid.mass_block(h)
            p1 = p1.copy()
            p1[wet] += g_w
            pn = pn.copy()
            pn[wet] += st.fw
        const = -p1
        if am != 0.0:
            const = const + (am / (1.0 - af)) * self._Mf(an)
        if af != 0.0:
            const = const + (af / (1.0 - af)) * (self._Cf(vn) + st.f_int[free] - pn)
        add = self._add(h)
        nonlinear = m.nonlinear
        p1_norm = float(np.linalg.norm(p1))

        def force_scale(ma_norm, f_int, r0=0.0):
            """Force scale of the convergence test (N)."""
            return max(ma_norm, float(np.linalg.norm(f_int[free])), p1_norm, r0, 1e-30)

        def residual(u, f_int):
            n = len(un)
            R, a1, v1, Ma = (np.empty(n) for _ in range(4))
            newmark_kinematics(u, free, un, vn, an, h, beta, gamma, self._mass_diag, a1, v1, Ma)
            if self.mdiag is None:
                Ma = self.M_free @ a1
            if fluid is not None:
                Ma[wet] += Mw @ a1[wet]
            if self.damped:  # a new velocity: the product without looking it up, then remembered
                Cv = self.C_free @ v1
                self._recent_Cv.put(v1, Cv)
            else:
                Cv = self._zeros_free
            if newmark_residual(Ma, w_m, Cv, f_int, free, const, R) != 0:
                raise NumericalError("NaN or infinity in the dynamic residual")
            return R, a1, v1, float(np.linalg.norm(Ma))

        def evaluate(u):
            """(f_int, tangent values or None for the all-stick tangent)."""
            if nonlinear:
                if hint[0] and not guard.stabilized:
                    # joints sticking so far: forces only, and the elastic tangent if all still stick
                    f, _ = m.evaluate(u, want_tangent=False)
                    if self._all_stick():
                        return f, None
                f, K = m.evaluate(u, want_tangent=True)
                if guard.stabilized:
                    m.latch_broken_bonds()
                hint[0] = False
                return f, K.data
            f, _ = m.evaluate(u, want_tangent=False)
            return f, None

        u = st.u.copy()
        f_int, Kdata = st.f_int, st.Kdata
        hint = [Kdata is None]  # the step starts with every joint sticking
        guard = ChatterGuard(m, OPEN_TANGENT_DYNAMIC)
        if m.rate_dependent:  # viscous blocks relax over the step even where u does not move: their force
            f_int, Kdata = evaluate(u)  # at the predictor is not the one the step started with
        kind_prev, rn_prev, allow_modified = None, math.inf, s.modified_newton
        hist, damping = [], 1.0
        e0 = None
        it = 0
        try:
            R, a1, v1, ma_norm = residual(u, f_int)
            r0 = float(np.linalg.norm(R))
            js = self._joint_space_for(h)
            if js is not None:
                # condensed on the joints (masonrydam.solvers.joint_space): the step's solution from one or two
                # substitutions; verified below against the full residual like any Newton iterate
                ref = force_scale(ma_norm, f_int)
                try:
                    u_js, its, converged, why = js.solve_step(
                        u, R, JOINT_SPACE_FORCE_FRACTION * s.force_tolerance * ref,
                        SPLIT_INITIAL_STIFFNESS_ITERATIONS if can_split and split_joint_space
                        else MAX_INITIAL_STIFFNESS_ITERATIONS)
                except FloatingPointError:
                    u_js, its, converged = None, 0, False
                self.stats.joint_space_iterations += its
                self.stats.joint_space_store_full += js.store_full
                self._iters_since_record += its
                if u_js is not None:
                    # go on from the joint-space solution (or its last iterate): the loop below accepts
                    # it at once when the full residual is within tolerance, and otherwise iterates on
                    f_j, _ = m.evaluate(u_js, want_tangent=False)
                    u, f_int, Kdata = u_js, f_j, None
                    hint[0] = True
                    R, a1, v1, ma_norm = residual(u, f_int)
                    ref = force_scale(ma_norm, f_int)
                    converged = converged and float(np.linalg.norm(R)) <= s.force_tolerance * ref
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
                    return False, None, f"the joint-space iteration did not converge ({why})"
                else:
                    self.stats.joint_space_fallbacks += 1
            while True:
                rn = float(np.linalg.norm(R))
                ref = force_scale(ma_norm, f_int, r0 if it > 0 else 0.0)
                force_ok = rn <= s.force_tolerance * ref
                # the work test compares the last correction with the first; once the force residual is
                # down to round-off (1e-3 of the tolerance) it has nothing left to say, and with very
                # small steps (dt = "auto" near an event) it could not be met: round-off limited
                energy_ok = (it == 0 or e0 == 0.0 or e_last <= s.energy_tolerance * e0
                             or rn <= ROUNDOFF_FRACTION * s.force_tolerance * ref)
                if force_ok and energy_ok:
                    break
                if it >= s.max_iterations:
                    why = (f"Newton residual {rn / ref:.3g} of the force scale (tolerance {s.force_tolerance:g}) "
                           f"after {it} iterations")
                    if nonlinear:
                        nchg = sum(int((g.state_codes(trial=True) != g.state_codes(trial=False)).sum())
                                   for g in m.igroups if g.nonlinear)
                        why += f"; {nchg} joint point(s) changed state in the step"
                    return False, None, why
                if nonlinear:
                    # cycling: the stabilized iteration; settled: back to the consistent tangent (the
                    # guard's module docstring); either way the iteration matrix and residual again
                    action = guard.observe()
                    if action is not None:
                        self.stats.stabilized_steps += action == "stabilize"
                        f_int, Kdata = evaluate(u)
                        R, a1, v1, ma_norm = residual(u, f_int)
                        rn = float(np.linalg.norm(R))
                # modified Newton (the latest factorization, only with modified_newton) while it
                # contracts well; once it does not, exact iteration matrices for the rest of the step
                if kind_prev == "modified" and rn > MODIFIED_NEWTON_CONTRACTION * rn_prev:
                    allow_modified = False
                if Kdata is None:
                    dx, kind_prev = self.eff.solve(self._elastic_eff(h), -R, allow_inexact=allow_modified,
                                                   key=("elastic", h))
                else:
                    dx, kind_prev = self.eff.solve(Kdata + add, -R, allow_inexact=allow_modified)
                rn_prev = rn
                # a two-cycle (e.g. the friction direction of a pivot point flipping from one iterate
                # to the next: the state codes repeat, the residual norm comes back): damp the correction
                hist.append(rn)
                if len(hist) >= 3 and abs(hist[-1] - hist[-3]) <= 1e-6 * hist[-1] and hist[-1] > 0:
                    damping = max(damping * 0.5, 1.0 / 64.0)
                    self.stats.damped_iterations += 1
                dx = damping * dx
                if e0 is None:
                    e0 = abs(float(dx @ R))
                # backtracking line search on the residual norm (joint laws are non-smooth: a full
                # Newton step can jump across many stick/slip/open switches and cycle)
                step = 1.0
                u_try = u.copy()
                u_try[free] += dx
                f_try, K_try = evaluate(u_try)
                R_try, a_try, v_try, ma_try = residual(u_try, f_try)
                if nonlinear and s.line_search and float(np.linalg.norm(R_try)) > rn:
                    best = (float(np.linalg.norm(R_try)), 1.0)
                    for trial_step in (0.5, 0.25):
                        u_s = u.copy()
                        u_s[free] += trial_step * dx
                        f_s, K_s = evaluate(u_s)
                        R_s, a_s, v_s, ma_s = residual(u_s, f_s)
                        rs = float(np.linalg.norm(R_s))
                        if rs < best[0]:
                            best = (rs, trial_step)
                        if rs <= rn:
                            break
                    step = best[1]
                    if step != 1.0:
                        self.stats.line_searches += 1
                        if step != trial_step:  # re-evaluate at the chosen step (joint trial state)
                            u_s = u.copy()
                            u_s[free] += step * dx
                            f_s, K_s = evaluate(u_s)
                            R_s, a_s, v_s, ma_s = residual(u_s, f_s)
                        u_try, f_try, K_try, R_try, a_try, v_try, ma_try = u_s, f_s, K_s, R_s, a_s, v_s, ma_s
                    else:
                        u_try = u.copy()
                        u_try[free] += dx
                        f_try, K_try = evaluate(u_try)
                        R_try, a_try, v_try, ma_try = residual(u_try, f_try)
                u, f_int, Kdata, R, a1, v1, ma_norm = u_try, f_try, K_try, R_try, a_try, v_try, ma_try
                e_last = abs(float(step * (dx @ R)))
                it += 1
                self.stats.iterations += 1
                self._iters_since_record += 1
        except SingularMatrix as exc:
            return False, None, f"singular effective matrix ({exc})"
        except NumericalError as exc:
            return False, None, str(exc)
        finally:
            if guard.stabilized:
                m.set_open_tangent(OPEN_TANGENT_DYNAMIC)
        retangent = guard.stabilized  # tangent for the next step's predictor with the ordinary open tangent
        new = _StepState(st.t - st.tau + t_end, t_end, u, np.zeros_like(st.v), np.zeros_like(st.a), f_int,
                         Kdata.copy() if Kdata is not None else None, ag1)
        new.v[free] = v1
        new.a[free] = a1
        new.Kc_u = m.continuum_force(u)
        if fluid is not None:
            new.fluid = fluid.finish(fluid_ctx, a1[wet])
            new.fw = fluid.force(new.fluid)
        self._record_energy(new, st)
        if can_split and nonlinear and s.energy_growth_tolerance > 0:
            # the trapezoidal work of a joint point that opens or closes within the step is not the
            # change of its stored energy (Armero & Petocz 1998, Comput. Methods Appl. Mech. Eng. 158;
            # Laursen & Chawla 1997, IJNME 40): with an implicit scheme an impact can create energy.
            # A step that raises the mechanical energy above what the loads supplied (cumulative,
            # beyond energy_growth_tolerance x the largest energy term) is split; at the last halving
            # it is accepted and counted (stats.energy_growth_max).
            g = self._energy_growth(new.energy)
            cap = s.energy_growth_tolerance * self._energy_scale
            allowed = max(cap, self._energy_growth(st.energy) + 0.01 * cap)
            if g > allowed and self._energy_scale > 0:
                self.stats.energy_rejections += 1
                return False, None, (f"the step raised the mechanical energy to {g:.3g} J above the work of the "
                                     f"loads (joint impact; allowed {allowed:.3g} J)")
        if error_check is not None:
            why = error_check(new, st, h)
            if why:
                return False, None, why
        m.commit()
        if retangent:
            _, K = m.evaluate(u, want_tangent=True)
            new.Kdata = None if self._all_stick() else K.data.copy()
        self._accept_energy(new)
        return True, new, ""

    # ------------------------------------------------------------------------------------------
    def _run_explicit(self, stage, st):
        """Central difference (velocity form), lumped mass; joints evaluated once per step and committed."""
        m, s = self.model, self.s
        free = self.free
        md = self.mdiag
        n_steps = stage.n_steps
        for k in range(1, n_steps + 1):
            t_end, h = _step_end(k, n_steps, s.dt, stage.duration, st.tau)
            if h <= 1e-9 * s.dt:
                break
            v_half = st.v[free] + 0.5 * h * st.a[free]
            m.time_step = h
            u = st.u.copy()
            u[free] += h * v_half
            f_int, _ = m.evaluate(u, want_tangent=False)
            ag1 = self.ground_at(t_end)
            rhs = self.fs_f + self._pg_f(ag1, t_end) + self._state_force() - f_int[free] - self._Cf(v_half)
            a1 = rhs / md
            if not np.isfinite(a1).all():
                self._fail(stage, st, NumericalError(
                    f"dynamic stage '{stage.name}': NaN or infinity at t = {st.t + h:.6g} s (central difference)"))
            m.commit()
            new = _StepState(st.t - st.tau + t_end, t_end, u, np.zeros_like(st.v), np.zeros_like(st.a), f_int, None, ag1)
            new.a[free] = a1
            new.v[free] = v_half + 0.5 * h * a1
            new.Kc_u = m.continuum_force(u)
            self._record_energy(new, st)
            self._accept_energy(new)
            st = new
            self.stats.steps += 1
            self._maybe_emit(stage, k, st, n_steps)
        return st


class _StepState:
    __slots__ = ("t", "tau", "u", "v", "a", "f_int", "Kdata", "ag", "Kc_u", "energy", "joints", "fluid", "fw")

    def __init__(self, t, tau, u, v, a, f_int, Kdata, ag):
        self.t, self.tau, self.u, self.v, self.a = t, tau, u, v, a
        self.f_int, self.Kdata, self.ag = f_int, Kdata, ag
        self.Kc_u = None
        self.fluid = self.fw = None
        self.energy = None
        self.joints = ()  # (delta, traction, state) copies per joint set (see DynamicSolver._joint_snapshot)
