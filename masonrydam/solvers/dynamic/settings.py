"""Settings of a dynamic stage (:class:`DynamicSettings`) and the constants the dynamic solver shares.

Times in s, tolerances dimensionless. What each setting does is explained in docs/dynamics.md.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ...assembly.damping import RayleighDamping
from ...errors import SceneError
from ..linear.direct import DIRECT_SOLVERS
from .schemes import INTEGRATORS, Scheme, scheme_named

JOINT_SPACE_MODES = ("auto", "on", "off")

#: open-joint tangent factor in dynamics: 0 (consistent; the mass keeps K_eff regular)
OPEN_TANGENT_DYNAMIC = 0.0

#: dt = "auto": the smallest step by default is dt_max / 2^ADAPTIVE_DEFAULT_LEVELS
ADAPTIVE_DEFAULT_LEVELS = 10


@dataclass
class DynamicSettings:
    """Settings of one dynamic stage.

    integrator: one of :data:`~.schemes.INTEGRATORS`; dt: analysis time step (s); alpha: HHT parameter in
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
    :class:`~.step_control.AdaptiveStepping`);
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
    #: down to ``dt_min``, and ``tolerance`` bounds each step's local error (see :mod:`.step_control`)
    adaptive: bool = False
    tolerance: float = 1e-5
    dt_min: float | None = None
    #: local (non-viscous) damping ratio of an explicit step (Cundall 1987; :func:`~masonrydam.assembly.damping.
    #: local_damping_coefficient`): the same ratio at every frequency, no effect on the stable step
    local_damping: float = 0.0
    #: dt = "auto" with an explicit scheme: ``dt`` is the output interval, the step is the largest stable one
    #: (``stability_safety`` x dt_crit) that divides it, chosen by the solver (:func:`.stability.stable_step`)
    stable_step: bool = False
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
        scheme = self.scheme
        if scheme.explicit and self.mass != "lumped":
            raise SceneError(f"{k}mass", f"{scheme.label} is explicit and needs mass = 'lumped'")
        if int(self.max_iterations) < 1:
            raise SceneError(f"{k}max_iterations", f"must be >= 1, got {self.max_iterations!r}")
        if int(self.max_substeps) < 0:
            raise SceneError(f"{k}max_substeps", f"must be >= 0, got {self.max_substeps!r}")
        for name in ("force_tolerance", "energy_tolerance"):
            v = getattr(self, name)
            if not 0.0 < v < 1.0:
                raise SceneError(f"{k}{name}", f"must be in (0, 1), got {v!r}")
        if self.adaptive:
            if scheme.explicit:
                raise SceneError(f"{k}dt", f"dt = 'auto' needs an implicit integrator ({scheme.label} is bound to "
                                           "its critical step)")
            if scheme.error_constant(self.alpha, self.rho_inf) == 0.0:
                raise SceneError(f"{k}dt", "dt = 'auto' estimates the error from beta - 1/6, which is zero for "
                                           f"{scheme.name}: use hht, newmark_average or generalized_alpha")
            if not 0.0 < self.tolerance < 1.0:
                raise SceneError(f"{k}tolerance", f"must be a relative local error in (0, 1), got {self.tolerance!r}")
            if self.dt_min is None:
                self.dt_min = self.dt / 2 ** ADAPTIVE_DEFAULT_LEVELS
            if not (math.isfinite(self.dt_min) and 0.0 < self.dt_min <= self.dt):
                raise SceneError(f"{k}dt_min", f"must be in (0, dt_max = {self.dt:g} s], got {self.dt_min!r}")
        if not (math.isfinite(self.local_damping) and 0.0 <= self.local_damping < 1.0):
            raise SceneError(f"{k}damping.ratio", f"must be in [0, 1), got {self.local_damping!r}")
        if (self.local_damping > 0.0 or self.stable_step) and not scheme.explicit:
            what = "damping.model" if self.local_damping > 0.0 else "dt"
            raise SceneError(f"{k}{what}", f"{'local damping' if self.local_damping > 0 else 'the stable step'} "
                                           f"needs an explicit integrator (central_difference), not {scheme.label}")
        if self.joint_space not in JOINT_SPACE_MODES:
            raise SceneError(f"{k}joint_space", f"must be one of {list(JOINT_SPACE_MODES)}, got {self.joint_space!r}")
        if self.linear_solver not in ("auto",) + DIRECT_SOLVERS:
            raise SceneError(f"{k}linear_solver", f"dynamic stages use a direct solver (the fast path reuses and "
                                                  f"updates factorizations): one of {('auto',) + DIRECT_SOLVERS}, "
                                                  f"got {self.linear_solver!r}")

    @property
    def scheme(self) -> Scheme:
        """The integrator's entry in the table of schemes."""
        return scheme_named(self.integrator)

    def coefficients(self):
        """(beta, gamma, alpha_m, alpha_f) of the implicit scheme."""
        return self.scheme.parameters_of(self.alpha, self.rho_inf)

    def as_dict(self):
        d = asdict(self)
        d["damping"] = None if self.damping is None else asdict(self.damping)
        return d
