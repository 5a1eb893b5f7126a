"""The linear terms of a dynamic stage's equation of motion on the free DOFs: :class:`StageEquations`.

    M u'' + C u' + f_int(u) = f_s - sum_c (M iota_c) a_g,c(t) + f(t) + f_state + f_water

(Chopra, *Dynamics of Structures*, 4th ed. 2012, sec. 9.4 and 13.1; displacements relative to the moving
supports): the mass ``M`` (lumped diagonal or consistent, with the effects' added masses), the damping ``C``
(Rayleigh damping of the blocks, ``exclude_joints``, plus the effects' dashpots), the ground load ``-M iota
a_g`` (with ``M iota`` from the full-DOF mass, supports included), the loads given in time and the state
forces of :class:`~.stage.DynamicTerms`, and the compressible water condensed into an implicit step as a
mass-like block on the wetted DOFs (:mod:`.fluid`; an explicit stage steps it with the dam instead). Vectors are
on the free DOFs (n_eq,) unless said otherwise; matrices are values in the model's CSR pattern (nnz,). See
docs/dynamics.md.
"""
from __future__ import annotations

import struct

import numpy as np
import scipy.sparse as sp

from ...assembly.elastic import elastic_tangent_data
from ...assembly.sparsity import add_to_pattern
from ...errors import SceneError
from ...materials.joint_laws import RESULT_STICK
from .explicit import node_mass_blocks
from .fluid import ExplicitAcoustic
from .kernels import ground_load as ground_load_kernel
from .stage import DynamicTerms

#: effective-matrix values kept per step size before the caches are cleared
MAX_STEP_SIZES_CACHED = 8


class RecentProducts:
    """The last ``size`` results ``y = A x`` of a linear map, found again by the value of ``x``.

    ``x`` is compared by its bytes (a copy and a memcmp: about a microsecond for a few thousand values,
    against 5 us of Python for ``np.array_equal``; some 60 000 look-ups on 4 000 steps of a small dam). Two
    arrays that differ only in the sign of a zero do not match: the product is then computed again."""

    def __init__(self, size: int):
        self.size = size
        self.items = []

    @staticmethod
    def _key(x) -> bytes:
        return x if isinstance(x, bytes) else x.tobytes()

    def get(self, x):
        """``y`` of an ``x`` (an array, or its bytes) among the last ``size``, else None."""
        key = self._key(x)
        for kc, yc in self.items:
            if kc == key:
                return yc
        return None

    def put(self, x, y):
        self.items = [(self._key(x), y), *self.items[:self.size - 1]]


class StageEquations:
    """Mass, damping, loads and effective-matrix values of one dynamic stage on ``model`` (constraints set here
    from ``stage.supports``).

    ``mass``: the :class:`~masonrydam.assembly.mass.MassMatrix`; ``elastic_joints_full()``: the full-DOF elastic
    joint stiffness (N/m, asked for only where Rayleigh damping includes the joints). The constant load of the
    static stages on the free DOFs, :attr:`static_load`, is set by the solver at the stage's start.
    """

    def __init__(self, model, settings, mass, stage, elastic_joints_full):
        m, s = self.model, self.s = model, settings
        self.mass = mass
        m.set_constraints(stage.supports)
        #: (n_eq,) the free DOFs; n: their number
        self.free = free = m.dofmap.free
        self.n = m.dofmap.n_eq
        #: mass and all-stick tangent values in the pattern (kg, N/m)
        self.mass_data = self.mass.for_pattern(m)
        self.elastic_data = elastic_tangent_data(m)
        d = s.damping
        self.damped = d is not None and d.active
        if self.damped:
            Kd = m.elastic_continuum_data() if d.exclude_joints else self.elastic_data
            # mass-proportional damping of the continuum's own mass, not of the water's added mass
            self.damping_data = d.alpha * self.mass.structural_data + d.beta * Kd
            Cf = d.alpha * self.mass.structural_full + d.beta * m.K_continuum_elastic
            if not d.exclude_joints:
                Cf = Cf + d.beta * elastic_joints_full()
            self.damping_full = Cf.tocsr()
            self.damping_free = sp.csr_matrix((self.damping_data, m.indices, m.indptr), shape=(self.n, self.n))
        else:
            self.damping_data = np.zeros_like(self.mass_data)
            self.damping_full = None
            self.damping_free = None
        terms = self.terms = stage.terms if stage.terms is not None else DynamicTerms()
        if terms.dashpots is not None and terms.dashpots.nnz:
            D = sp.csr_matrix(terms.dashpots)
            Cd = np.zeros_like(self.mass_data)
            add_to_pattern(D[free][:, free], m.indptr, m.indices, Cd, "dashpot matrix")
            self.damping_data = self.damping_data + Cd
            self.damping_full = D if self.damping_full is None else (self.damping_full + D).tocsr()
            self.damping_free = sp.csr_matrix((self.damping_data, m.indices, m.indptr), shape=(self.n, self.n))
            self.damped = True
        self.fluid = terms.fluid
        #: the compressible water of an explicit stage (:class:`~.fluid.ExplicitAcoustic`), or None
        self.explicit_water = None
        if self.fluid is not None and s.scheme.explicit:  # the water stepped with the dam
            self.fluid.attach(m.dofmap.eq_of_dof)
            self.explicit_water = ExplicitAcoustic(self.fluid, free)
        elif self.fluid is not None:  # the water condensed into the implicit step
            self.fluid.attach(m.dofmap.eq_of_dof, s.coefficients())
            n_w = len(self.fluid.wet_eq)
            rows = np.repeat(self.fluid.wet_eq, n_w)
            cols = np.tile(self.fluid.wet_eq, n_w)
            self._fluid_pattern = (rows, cols)
        #: the state force of the current step (free DOFs, N; see :meth:`update_state_force`)
        self.step_state_force = np.zeros(self.n)
        #: (n_eq,) kg, the diagonal of a diagonal mass, else None (then ``mass_free``, the free-DOF CSR matrix)
        if self.mass.diagonal:
            self.mass_diagonal = self.mass.free_diag
            self.mass_free = None
        else:
            self.mass_diagonal = None
            self.mass_free = self.mass.free_matrix(m)
        #: an explicit stage's mass that couples only the DOFs of single nodes, as node blocks
        #: (:func:`~.explicit.node_mass_blocks`, found once for the stability check and the steps); [] for a
        #: diagonal mass or an implicit scheme, None where the mass couples DOFs of different nodes
        self.mass_blocks = ([] if self.mass.diagonal or not s.scheme.explicit
                            else node_mass_blocks(self.mass_free, free, m.dim))
        Miota = self.mass.influence(m.dim)  # (dim, n_dof)
        #: (dim, n_eq) kg, ``M iota_c`` on the free DOFs
        self.mass_influence_free = np.ascontiguousarray(Miota[:, free])
        extra = self.mass.extra_influence
        #: (dim, n_eq) kg or None, the load per unit acceleration of the reservoir bottom that is not ``M iota``
        self.bottom_influence_free = None if extra is None else np.ascontiguousarray(extra[:, free])
        #: ground motion components by direction (0, 1, 2)
        self.ground = {g.component: g for g in stage.ground_motion}
        for c in self.ground:
            if c >= m.dim:
                raise SceneError(f"{s.key}ground_motion.{'xyz'[c]}", f"component {'xyz'[c]} in a {m.dim}D model")
        self._add_cache = {}
        self._kel_cache = {}
        # an implicit step keeps the damping force of its end velocity with its state (the energy balance
        # and the next step's constant part take it from there); these remember the products asked for
        # otherwise (a stage's first state, the explicit steps), and the ground loads of a step's two ends,
        # asked for twice
        self._recent_damping_forces = RecentProducts(3)
        self._recent_ground_loads = RecentProducts(2)
        #: operands of the step residual kernels (kernels.newmark_kinematics: the lumped mass
        #: diagonal, or nothing for a consistent mass; no damping: a zero damping force)
        self.kernel_mass_diagonal = self.mass_diagonal if self.mass_diagonal is not None else np.zeros(0)
        self.zeros_free = np.zeros(self.n)
        #: (n_eq,) N, the constant load of the static stages on the free DOFs (set by the solver)
        self.static_load = None

    # -- products and loads ---------------------------------------------------------------------
    def mass_times(self, x):
        """``M x`` on the free DOFs."""
        return self.mass_diagonal * x if self.mass_diagonal is not None else self.mass_free @ x

    def damping_force(self, x):
        """Damping force ``C x`` on the free DOFs (the last three remembered). The returned array is shared:
        callers must not modify it."""
        if not self.damped:
            return np.zeros_like(x)
        y = self._recent_damping_forces.get(x)
        if y is None:
            y = self.damping_free @ x
            self._recent_damping_forces.put(x, y)
        return y

    def ground_at(self, tau):
        """Ground acceleration (dim,) m/s2 at stage time ``tau`` (s)."""
        ag = np.zeros(self.model.dim)
        for c, g in self.ground.items():
            ag[c] = g.at(tau)
        return ag

    def ground_load(self, ag, tau):
        """Earthquake load on the free DOFs at stage time ``tau``: -sum_c (M iota_c) a_g,c with support
        excitation, plus the stage's load given in time (:class:`~.stage.DynamicTerms`; the last two
        remembered). Shared array: do not modify."""
        key = ag.tobytes() + struct.pack("d", tau)
        v = self._recent_ground_loads.get(key)
        if v is None:
            v = np.zeros(self.n)
            if self.terms.support_excitation:
                ground_load_kernel(np.ascontiguousarray(ag, dtype=np.float64), self.mass_influence_free, v)
            if self.bottom_influence_free is not None:  # the reservoir bottom pushing incompressible water
                v = v - self.bottom_at(tau, ag) @ self.bottom_influence_free
            if self.terms.force is not None:
                v = v + self.terms.force(tau)[self.free]
            self._recent_ground_loads.put(key, v)
        return v

    def update_state_force(self):
        """The state force of the step about to start (free DOFs; zero without one)."""
        if self.terms.state_force is not None:
            self.step_state_force = self.terms.state_force()[self.free]
        return self.step_state_force

    def bottom_at(self, tau, ag):
        """Total acceleration (dim,) of the ground under the reservoir at stage time tau."""
        f = self.terms.bottom_acceleration
        return ag if f is None else f(tau)

    def frame_at(self, ag):
        """Acceleration (dim,) of the frame the displacements are measured in: the ground's in the
        relative formulation, zero when they are total."""
        return ag if self.terms.support_excitation else np.zeros_like(ag)

    # -- effective matrices ---------------------------------------------------------------------
    def _fluid_data(self, h):
        """``c_m M_w(h)`` in the pattern's values (the water condensed on the wetted DOFs)."""
        beta, gamma, am, af = self.s.coefficients()
        cm = (1.0 - am) / ((1.0 - af) * beta * h * h)
        data = np.zeros_like(self.mass_data)
        Mw = self.fluid.mass_block(h)
        add_to_pattern(sp.coo_matrix((cm * Mw.ravel(), self._fluid_pattern), shape=(self.n, self.n)),
                       self.model.indptr, self.model.indices, data, "reservoir block")
        return data

    def inertia_damping(self, h):
        """``c_m M + c_c C`` values for step size h (cached per h), ``c_m = (1 - am)/((1 - af) beta h^2)``,
        ``c_c = gamma / (beta h)``."""
        v = self._add_cache.get(h)
        if v is None:
            beta, gamma, am, af = self.s.coefficients()
            cm = (1.0 - am) / ((1.0 - af) * beta * h * h)
            cc = gamma / (beta * h)
            v = cm * self.mass_data + cc * self.damping_data
            if self.fluid is not None:
                v = v + self._fluid_data(h)
            if len(self._add_cache) > MAX_STEP_SIZES_CACHED:
                self._add_cache.clear()
            self._add_cache[h] = v
        return v

    def elastic_effective(self, h):
        """Effective-matrix values with every joint point sticking, for step h (cached)."""
        v = self._kel_cache.get(h)
        if v is None:
            v = self.elastic_data + self.inertia_damping(h)
            if len(self._kel_cache) > MAX_STEP_SIZES_CACHED:
                self._kel_cache.clear()
            self._kel_cache[h] = v
        return v

    def all_stick(self) -> bool:
        """Every point of every nonlinear joint set sticks in the trial state: the tangent is then the
        elastic one, bitwise (the stick tangent depends on nothing but the geometry and ks, kn)."""
        if not self.model.condensable:  # nonlinear blocks or large kinematics: the tangent moves anyway
            return False
        return all((g.result_states(trial=True) == RESULT_STICK).all() for g in self.model.igroups if g.nonlinear)

    # -- reactions --------------------------------------------------------------------------------
    def reaction(self, u, v, a_abs, f_int, f_static, st=None):
        """Support reactions (full-DOF, N; zero at free DOFs): f_int + C v + M a_abs - f_static, less the
        water's force on constrained wetted DOFs (compressible: ``Q p``; incompressible: the push of the
        reservoir bottom) for the step state ``st``."""
        r = f_int - f_static + self.mass.full @ a_abs
        if self.damped:
            r = r + self.damping_full @ v
        if st is not None:
            if self.mass.extra_influence is not None:
                r += self.bottom_at(st.tau, st.ag) @ self.mass.extra_influence
            if self.fluid is not None and st.fluid is not None and len(self.fluid.wet_fixed):
                r[self.fluid.wet_fixed] -= self.fluid.Qc @ st.fluid.p
        r[self.free] = 0.0
        return r
