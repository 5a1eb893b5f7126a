"""The records of a dynamic stage: what it is given (:class:`DynamicStage`, with the linear terms of the effects,
:class:`DynamicTerms`), the state it hands on (:class:`DynamicState`), the state of a step (:class:`StepState`) and
the counts a run reports (:class:`DynamicStats`).

Arrays are full-DOF (n_dof,) unless said otherwise; SI units (m, s, N, J).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.sparse as sp

from ...errors import SceneError
from .settings import DynamicSettings


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
    fluid: :class:`~.fluid.AcousticStep` (a compressible reservoir condensed on the
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
    """A dynamic stage: ``duration`` s under ``ground_motion`` (list of :class:`~.ground_motion.GroundMotion`, may be
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
    #: the compressible reservoir's state (:class:`~.fluid.FluidState`) and its force on
    #: the free wetted DOFs, carried into the next dynamic stage
    fluid: object = None
    fluid_force: np.ndarray | None = None


@dataclass
class DynamicStats:
    """Counts, extremes and times of the dynamic stages of a run (the ``dynamic_*`` result attributes); per stage
    in ``per_stage``."""

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
    #: highest circular frequency (rad/s) with every joint sticking, where a stable step was computed (of the dam
    #: and its compressible water together in an explicit stage with one), and what set it (words)
    omega_max: float = 0.0
    dt_limit: str = ""
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
    #: joint-space step attempts solved by the compiled kernel (masonrydam.solvers.joint_space.step_kernel) and by
    #: the Python loop (static-style latching, flexibility columns computed as needed, another factorization)
    joint_space_compiled_steps: int = 0
    joint_space_python_steps: int = 0
    #: steps taken whole by the compiled step loop (:mod:`.compiled_loop`: loads, joint-space step, forces, energy
    #: balance and commit in one call for many steps), steps it handed back to the Python step (they left its
    #: common path after their joint-space call), and why a stage did not use it ("": it did, or no implicit stage)
    compiled_loop_steps: int = 0
    compiled_loop_handbacks: int = 0
    compiled_loop_off: str = ""
    #: the solvers of the all-stick effective matrices: "ldlt", "pardiso" or "superlu"
    reference_solvers: set = field(default_factory=set)
    per_stage: list = field(default_factory=list)

    def as_dict(self):
        return asdict(self)


class StepState:
    """The state at the end of a converged step (free and constrained DOFs, relative to the ground): ``t`` (s,
    since the first stage), ``tau`` (s, stage time), ``u`` (m), ``v`` (m/s), ``a`` (m/s2) (n_dof,), ``f_int``
    (n_dof,) N, ``Kdata`` the tangent's values in the model's pattern (None: the all-stick tangent), ``ag`` (dim,)
    m/s2 the ground acceleration; ``Kc_u`` (n_dof,) N the blocks' forces, ``energy`` (dict, J), ``joints`` the
    joint sets' (delta, traction, state) copies, ``fluid`` and ``fw`` the compressible water's state and force."""

    __slots__ = ("t", "tau", "u", "v", "a", "f_int", "Kdata", "ag", "Kc_u", "energy", "joints", "fluid", "fw", "cv",
                 "_free", "_on_free")

    def __init__(self, t, tau, u, v, a, f_int, Kdata, ag):
        self.t, self.tau, self.u, self.v, self.a = t, tau, u, v, a
        self.f_int, self.Kdata, self.ag = f_int, Kdata, ag
        self.Kc_u = None
        self.fluid = self.fw = None
        self.energy = None
        self.joints = ()  # (delta, traction, state) copies per joint set (see EnergyBalance.joint_snapshot)
        #: (n_eq,) N the damping force ``C v`` on the free DOFs where the step that ended here computed it, else None
        self.cv = None
        self._free, self._on_free = None, (None, None, None)

    def keep_free_values(self, free, v, a):
        """Keep ``v``, ``a`` (n_eq,), the step's own arrays, as this state's values on the free DOFs ``free``
        (``u[free]`` is gathered when asked for). A state is not changed after its step, so they stay its values."""
        self._free, self._on_free = free, (None, v, a)

    def free_values(self, free):
        """``(u[free], v[free], a[free])``, each gathered once and kept."""
        if self._free is not free:
            self._free, self._on_free = free, (None, None, None)
        u, v, a = self._on_free
        if u is None or v is None or a is None:
            u = self.u[free] if u is None else u
            v = self.v[free] if v is None else v
            a = self.a[free] if a is None else a
            self._on_free = (u, v, a)
        return u, v, a
