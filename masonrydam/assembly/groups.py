"""Element groups as struct-of-arrays, ready for the numba kernels.

A :class:`ContinuumGroup` is one element type with one or more materials; an
:class:`InterfaceGroup` is one joint set (one law, one integration rule). Python checks shapes once
here and turns kernel status codes into exceptions that name the group and the element.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np

from ..elements import continuum as ck
from ..elements import interface as ik
from ..elements.continuum_large import continuum_cauchy_stress, continuum_large_evaluate
from ..elements.continuum_plastic import continuum_plastic_evaluate
from ..elements.interface_large import interface_large_evaluate
from ..elements.shapes import shape_functions
from ..errors import STATUS_BAD_GEOMETRY, STATUS_BAD_JACOBIAN, STATUS_NAN, MeshError, NumericalError
from ..materials.continuum_laws import continuum_law
from ..materials.joint_laws import RESULT_OPEN, joint_law
from ..materials.plasticity import P_VISCOSITY
from ..mesh.model import INTERFACE_FACE_TYPE
from .dofmap import DofMap

#: [model] kinematics: small displacements (linear) or large (total Lagrangian, rotating joint frames)
KINEMATICS = ("small", "large")
#: [joints.<set>] frame with large kinematics: the surface whose current direction is the joint's frame
JOINT_FRAMES = ("mid_surface", "bottom")


def raise_for_status(status: int, info: np.ndarray, group: str, what: str, element_ids=None):
    """Turn a kernel status code into an exception naming the group and element."""
    if status == 0:
        return
    e = int(info[0])
    label = int(element_ids[e]) if element_ids is not None and 0 <= e < len(element_ids) else e
    if status == STATUS_BAD_JACOBIAN:
        raise MeshError(f"{what}: inverted or degenerate element (non-positive Jacobian determinant)", group, [label])
    if status == STATUS_BAD_GEOMETRY:
        raise MeshError(f"{what}: degenerate interface (zero length or area)", group, [label])
    if status == STATUS_NAN:
        raise NumericalError(f"{what}: NaN or infinity in element group '{group}', element {label}")
    raise NumericalError(f"{what}: kernel status {status} in element group '{group}', element {label}")


#: points per direction of the reduced rules: the serendipity quad8 and hex20 with 2 x 2 (x 2) Gauss
#: points (CPE8R / C3D20R in common codes) do not lock under plastic incompressibility (Nagtegaal, Parks &
#: Rice 1974, CMAME 4) and have no spreading zero-energy mode in a mesh of more than one element (Zienkiewicz
#: & Taylor, The Finite Element Method, vol. 1, 6th ed. 2005, sec. 9.10). The mass keeps the full rule.
REDUCED_RULES = {"quad8": 2, "hex20": 2}


@dataclass
class ContinuumGroup:
    """Continuum elements of one type.

    name: element group (scene material group); type: element type; conn (ne, nen);
    dofs (ne, nen*dim); D_table (n_mat, ns, ns) Pa; material_index (ne,); thickness (ne,) m;
    density (ne,) kg/m3; tables N (ngp, nen), dN (ngp, dim, nen), weights (ngp,).
    """

    name: str
    type: str
    conn: np.ndarray
    dofs: np.ndarray
    D_table: np.ndarray
    material_index: np.ndarray
    thickness: np.ndarray
    density: np.ndarray
    N: np.ndarray = field(init=False)
    dN: np.ndarray = field(init=False)
    weights: np.ndarray = field(init=False)
    scatter: np.ndarray | None = None
    #: "elastic", or an elasto-plastic law of :mod:`masonrydam.elements.continuum_plastic` ("von_mises",
    #: "drucker_prager") with its parameter table (1, P) (:mod:`masonrydam.materials.von_mises`, ...)
    law: str = "elastic"
    law_params: np.ndarray | None = None
    #: "small" (linear kinematics) or "large": total Lagrangian St. Venant-Kirchhoff elements
    #: (:mod:`masonrydam.elements.continuum_large`), evaluated at every iteration like a plastic group
    kinematics: str = "small"
    #: "full" (the type's default rule) or "reduced" (quad8 2 x 2, hex20 2 x 2 x 2: :data:`REDUCED_RULES`)
    integration: str = "full"

    def __post_init__(self):
        if self.integration == "reduced" and self.type not in REDUCED_RULES:
            raise ValueError(f"reduced integration is available for {sorted(REDUCED_RULES)} elements, not "
                             f"{self.type} (its one-point rule has hourglass modes)")
        self.N, self.dN, self.weights = ck.element_tables(
            self.type, REDUCED_RULES[self.type] if self.integration == "reduced" else None)
        self.info = np.zeros(2, dtype=np.int64)
        if self.large:
            self.fe = np.zeros((self.n_elem, self.n_edof))
            self.ke = np.zeros((self.n_elem, self.n_edof, self.n_edof))
            #: elastic energy (ne,) J of the last evaluation
            self.energy = np.zeros(self.n_elem)
        if self.plastic:
            n_state = self.continuum_law.state_size
            n = self.n_elem * len(self.weights)
            self.state_committed = np.zeros((n, n_state))
            self.state_trial = np.zeros((n, n_state))
            # one parameter row for the group, or one per element (a softening modulus scaled by the size)
            per_element = self.law_params.shape[0] == self.n_elem and self.n_elem > 1
            self.param_index = np.arange(self.n_elem) if per_element else np.zeros(self.n_elem, dtype=np.int64)
            self.fe = np.zeros((self.n_elem, self.n_edof))
            self.ke = np.zeros((self.n_elem, self.n_edof, self.n_edof))

    @property
    def continuum_law(self):
        """The law's descriptor (:class:`masonrydam.materials.continuum_laws.ContinuumLaw`)."""
        return continuum_law(self.law)

    @property
    def plastic(self) -> bool:
        return self.continuum_law.plastic

    @property
    def viscous(self) -> bool:
        """An elasto-plastic law with Perzyna viscosity > 0 in some element: its forces depend on the time step."""
        return self.plastic and bool((self.law_params[:, P_VISCOSITY] > 0).any())

    @property
    def large(self) -> bool:
        return self.kinematics == "large"

    @property
    def nonlinear(self) -> bool:
        """Evaluated at every iteration (elasto-plastic or large kinematics), not part of the constant
        linear stiffness."""
        return self.plastic or self.large

    def evaluate(self, coords, u, want_tangent=True, dt=0.0):
        """Nonlinear groups: internal forces ``fe`` and tangents ``ke`` at ``u``: elasto-plastic from the
        committed state (trial state written), :mod:`masonrydam.elements.continuum_plastic`; large
        kinematics, :mod:`masonrydam.elements.continuum_large` (``energy`` written too)."""
        if self.large:
            st = continuum_large_evaluate(coords, self.conn, self.dN, self.weights, self.D_table, self.material_index,
                                          self.thickness, u, want_tangent, self.fe, self.ke, self.energy, self.info)
            raise_for_status(st, self.info, self.name, "large-displacement element")
            return
        st = continuum_plastic_evaluate(coords, self.conn, self.dN, self.weights, self.thickness, u, self.law_params,
                                        self.param_index, self.state_committed, self.state_trial, dt, want_tangent,
                                        self.continuum_law.kernel_id, self.fe, self.ke, self.info)
        raise_for_status(st, self.info, self.name, f"{self.law.replace('_', ' ')} material")

    def commit(self):
        if self.plastic:
            self.state_committed[:] = self.state_trial

    def revert(self):
        if self.plastic:
            self.state_trial[:] = self.state_committed

    @property
    def n_elem(self) -> int:
        return len(self.conn)

    @property
    def n_edof(self) -> int:
        return self.dofs.shape[1]

    def stiffness(self, coords: np.ndarray) -> np.ndarray:
        ke = np.empty((self.n_elem, self.n_edof, self.n_edof))
        st = ck.continuum_stiffness(coords, self.conn, self.dN, self.weights, self.D_table, self.material_index,
                                    self.thickness, ke, self.info)
        raise_for_status(st, self.info, self.name, "stiffness")
        return ke

    def body_force(self, coords: np.ndarray, accel: np.ndarray) -> np.ndarray:
        """Consistent nodal forces (ne, n_edof) of the body force density ``density * accel`` (N/m3)."""
        b = np.ascontiguousarray(self.density[:, None] * np.asarray(accel, dtype=np.float64)[None, :])
        fe = np.empty((self.n_elem, self.n_edof))
        st = ck.continuum_body_force(coords, self.conn, self.N, self.dN, self.weights, b, self.thickness, fe, self.info)
        raise_for_status(st, self.info, self.name, "body force")
        return fe

    def stress(self, coords: np.ndarray, u: np.ndarray) -> np.ndarray:
        ns = self.D_table.shape[1]
        if self.plastic:  # the law's stress of the last evaluation (trial = committed after a step)
            cols = [0, 1, 3] if ns == 3 else [0, 1, 2, 3, 4, 5]
            return self.state_trial[:, cols].reshape(self.n_elem, len(self.weights), ns).copy()
        out = np.empty((self.n_elem, len(self.weights), ns))
        if self.large:  # Cauchy stress of the current configuration
            st = continuum_cauchy_stress(coords, self.conn, self.dN, self.D_table, self.material_index, u, out,
                                         self.info)
            raise_for_status(st, self.info, self.name, "stress (inverted deformation, det F <= 0)")
            return out
        st = ck.continuum_stress(coords, self.conn, self.dN, self.D_table, self.material_index, u, out, self.info)
        raise_for_status(st, self.info, self.name, "stress")
        return out


class InterfaceGroup:
    """One joint set: interface elements with one law and one integration rule.

    conn (ne, 2*ns): bottom face nodes then top face nodes; params (n_params,) the law's parameter row;
    state_committed / state_trial (ne, nip, n_state); delta / traction (ne, nip, dim).
    law: the name of a registered joint law (:func:`masonrydam.materials.joint_laws.joint_law`), whose
    descriptor is :attr:`joint_law`. A law with a fused kernel (the built-in ones) is evaluated by
    :func:`~masonrydam.elements.interface.interface_evaluate`; another one (a plug-in) on the generic path:
    relative displacements, its point law, assembly (``tangent`` (ne, nip, dim, dim) holds its point tangents).
    ValueError for a plug-in law with large kinematics (the large-displacement kernel is fused).
    """

    def __init__(self, name, type_, conn, coords, dim, params, thickness, law, scheme, n_points=None,
                 kinematics="small", frame="mid_surface"):
        self.name, self.type, self.law, self.scheme = name, type_, law, scheme
        #: "small" (frame of the reference mid-surface) or "large" (frame of the current mid-surface or
        #: bottom face, ``frame_surface``: :mod:`masonrydam.elements.interface_large`)
        self.kinematics, self.frame_surface = kinematics, frame
        self.conn = np.ascontiguousarray(conn, dtype=np.int64)
        self.dofs = DofMap.node_dofs(self.conn, dim)
        face = INTERFACE_FACE_TYPE[type_]
        pts, self.weights = ik.interface_rule(face, scheme, n_points)
        self.N, self.dN = shape_functions(face, pts)
        self.weights = np.ascontiguousarray(self.weights, dtype=np.float64)
        self.nip = len(self.weights)
        ne = len(self.conn)
        self.params_table = np.ascontiguousarray(np.asarray(params, dtype=np.float64)[None, :])
        self.param_index = np.zeros(ne, dtype=np.int64)
        self.thickness = np.ascontiguousarray(thickness, dtype=np.float64)
        self.joint_law = joint_law(law)
        if kinematics == "large" and not self.joint_law.large_kinematics:
            raise ValueError(f"the {self.joint_law.title} joint law has no large-displacement kernel (use "
                             "kinematics = \"small\")")
        #: the fused kernel's law argument (``JointLaw.kernel_id``)
        self.law_id = self.joint_law.kernel_id
        n_state = self.joint_law.state_size
        # trial / commit / revert: ``state_committed`` is the last converged state; ``state_base`` is
        # what the kernel reads in this step: the committed state plus bonds latched broken in
        # earlier iterations of the step (see :meth:`latch_broken_bonds`); ``state_trial`` is written.
        self.state_committed = np.zeros((ne, self.nip, n_state))
        self.state_base = np.zeros_like(self.state_committed)
        self.state_trial = np.zeros_like(self.state_committed)
        self.delta = np.zeros((ne, self.nip, dim))
        self.traction = np.zeros((ne, self.nip, dim))
        self.fe = np.zeros((ne, self.dofs.shape[1]))
        self.ke = np.zeros((ne, self.dofs.shape[1], self.dofs.shape[1]))
        self.info = np.zeros(1, dtype=np.int64)
        #: point tangents of the generic path (a law without a fused kernel); None on the fused path
        self.tangent = None if self.joint_law.fused else np.zeros((ne, self.nip, dim, dim))
        self.scatter = None
        self.points = np.zeros((ne, self.nip, dim))
        self.frame = np.zeros((ne, self.nip, dim, dim))
        self.jw = np.zeros((ne, self.nip))
        st = ik.interface_geometry(coords, self.conn, self.N, self.dN, self.weights, self.points, self.frame, self.jw, self.info)
        raise_for_status(st, self.info, name, "interface geometry")
        #: a forces-only evaluation reads the reference frames and weights computed here
        #: (:func:`~masonrydam.elements.interface.interface_forces`) instead of computing them again
        #: (``interface_evaluate`` without tangents): set by :meth:`Model.use_stored_frames` for time stepping,
        #: where forces-only evaluations come every step. A static run evaluates forces a few times a step
        #: and does not compile that second kernel (about 2 s of the default scene's first run, AMD EPYC).
        self.forces_from_stored_frames = False

    @property
    def n_elem(self) -> int:
        return len(self.conn)

    @property
    def nonlinear(self) -> bool:
        """The joint's state changes (else its stiffness is the elastic one for good)."""
        return self.joint_law.nonlinear

    @property
    def relaxation_time(self) -> float:
        """Relaxation time (s) of the law's viscous regularisation (0: none, or a rate-independent law)."""
        return self.joint_law.relaxation_time(self.params_table)

    def evaluate(self, coords, u, want_tangent=True, dt=0.0):
        """Evaluate tractions, nodal forces and (optionally) tangents from the committed state; ``dt`` (s):
        the step's time, seen by a law with a relaxation time."""
        self.joint_law.set_time_step(self.params_table, dt)
        if not self.joint_law.fused:
            self._evaluate_generic(u, want_tangent, dt)
            return
        args = (coords, self.conn, u, self.N, self.dN, self.weights, self.thickness, self.params_table,
                self.param_index, self.state_base, self.state_trial, self.delta, self.traction, self.fe, self.ke,
                want_tangent, self.info)
        if self.kinematics == "large":
            st = interface_large_evaluate(*args, 0.0 if self.frame_surface == "bottom" else 0.5, self.law_id)
        elif not want_tangent and self.forces_from_stored_frames:  # forces only: the reference frames computed once
            st = ik.interface_forces(self.conn, u, self.N, self.frame, self.jw, self.thickness, self.params_table,
                                     self.param_index, self.state_base, self.state_trial, self.delta, self.traction,
                                     self.fe, self.info, self.law_id)
        else:
            st = self._evaluate_kernel()(*args, self.law_id)
        raise_for_status(st, self.info, self.name, "joint evaluation")

    def _evaluate_kernel(self):
        """The small-displacement kernel that evaluates this group: ``interface_evaluate``, or, for a law other
        than Mohr-Coulomb (the composite law: a local return per plastic point) where numba has more than one thread,
        ``interface_evaluate_threaded`` (:mod:`masonrydam.elements.interface`), the same bit for bit with the
        elements shared among the threads. On the inviscid Eindhoven wall J4D (2-core AMD EPYC) a call took 0.66
        instead of 1.18 ms, and the converged run 156 s instead of 181 s, with the solve without refinement
        (:meth:`~masonrydam.solvers.linear.direct.Factorization.solve`)."""
        if self.law_id is not None and numba.get_num_threads() > 1:
            return ik.interface_evaluate_threaded
        return ik.interface_evaluate

    def _evaluate_generic(self, u, want_tangent, dt):
        """The generic path of a law without a fused kernel: kinematics, the law's point law, assembly."""
        st = ik.interface_relative_displacements(self.conn, u, self.N, self.frame, self.delta, self.info)
        raise_for_status(st, self.info, self.name, "joint relative displacements")
        st = self._point_law(self.state_base, self.state_trial, self.traction, self.tangent, dt)
        raise_for_status(st, self.info, self.name, f"{self.joint_law.title} joint law")
        st = ik.interface_assemble(self.N, self.frame, self.jw, self.thickness, self.traction, self.tangent,
                                   want_tangent, self.fe, self.ke, self.info)
        raise_for_status(st, self.info, self.name, "joint evaluation")

    def _point_law(self, state_base, state_trial, traction, tangent, dt):
        return int(self.joint_law.point_law(self.params_table, self.param_index, state_base, self.delta, dt,
                                            state_trial, traction, tangent, self.info))

    def point_tangents(self) -> np.ndarray:
        """The law's tangent ``dt/d delta`` (ne, nip, dim, dim) Pa/m (local axes) at every point, for the relative
        displacements of the last evaluation from the state that evaluation read: that of the assembled
        stiffness, kept per point (dissipation-based path following). The group's state is not changed."""
        dim = self.delta.shape[2]
        kt = np.empty(self.delta.shape + (dim,))
        scratch_state, scratch_traction = np.empty_like(self.state_trial), np.empty_like(self.traction)
        if self.joint_law.fused:
            st = ik.interface_point_tangents(self.params_table, self.param_index, self.state_base, self.delta, dim,
                                             self.law_id, scratch_state, scratch_traction, kt, self.info)
        else:
            st = self._point_law(self.state_base, scratch_state, scratch_traction, kt, 0.0)
        raise_for_status(st, self.info, self.name, "joint tangents")
        return kt

    def elastic_tangents(self, coords, n_dof: int) -> np.ndarray:
        """Element stiffness matrices (ne, n_edof, n_edof) N/m with every point at rest: the initial, elastic
        joint stiffness (``JointLaw.elastic_parameters``, zero relative displacement, virgin state). The
        group's own state and arrays are not touched."""
        params = self.joint_law.elastic_parameters(self.params_table)
        zeros = np.zeros_like(self.state_committed)
        trial = np.zeros_like(self.state_committed)
        delta, traction = np.zeros_like(self.delta), np.zeros_like(self.traction)
        fe, ke = np.zeros_like(self.fe), np.zeros_like(self.ke)
        info = np.zeros(1, dtype=np.int64)
        if self.joint_law.fused:
            st = self._evaluate_kernel()(coords, self.conn, np.zeros(n_dof), self.N, self.dN, self.weights,
                                         self.thickness, params, self.param_index, zeros, trial, delta, traction, fe,
                                         ke, True, info, self.law_id)
        else:
            tangent = np.zeros_like(self.tangent)
            st = int(self.joint_law.point_law(params, self.param_index, zeros, delta, 0.0, trial, traction, tangent,
                                              info))
            if st == 0:
                st = ik.interface_assemble(self.N, self.frame, self.jw, self.thickness, traction, tangent, True, fe,
                                           ke, info)
        raise_for_status(st, info, self.name, "elastic joint stiffness")
        return ke

    def set_open_tangent(self, factor: float) -> None:
        """Tangent factor of open points (0: consistent; 1: initial stiffness), for a law that has one."""
        self.joint_law.set_open_tangent(self.params_table, factor)

    def elastic_stiffness(self) -> np.ndarray:
        """(ne, dim) elastic stiffness ``[ks1, (ks2,) kn]`` (Pa/m) of each element's parameters."""
        return self.joint_law.elastic_stiffness(self.params_table, self.delta.shape[2])[self.param_index]

    def compliance(self) -> np.ndarray:
        """(ne, dim) elastic compliance ``[1/ks1, (1/ks2,) 1/kn]`` (m/Pa) of each element's parameters."""
        return self.joint_law.compliance(self.params_table, self.delta.shape[2])[self.param_index]

    def friction_strength(self) -> tuple:
        """``(cohesion (ne,) Pa, tan_phi (ne,))`` of each element's Coulomb limit (inf, 0 where the law has none)."""
        c, t = self.joint_law.friction_strength(self.params_table)
        return c[self.param_index], t[self.param_index]

    def commit(self):
        self.state_committed[:] = self.state_trial
        self.state_base[:] = self.state_trial

    def revert(self):
        """Discard everything since the last commit (trial state and latched bonds)."""
        self.state_base[:] = self.state_committed
        self.state_trial[:] = self.state_committed

    def latch_broken_bonds(self) -> int:
        """Keep bonds that broke in the last evaluation broken for the rest of the step.

        Bond failure is irreversible, and with cohesion the shear traction drops from up to c to 0
        when a point opens; letting an iteration "un-break" a bond makes Newton chatter between the
        two sides of that jump. Returns the number of newly latched points.
        """
        # (a law without a bond jump, e.g. a softening one, latches nothing: JointLaw.latches_bonds)
        return self.joint_law.latch_broken_bonds(self.state_base, self.state_trial)

    def state_codes(self, trial=True) -> np.ndarray:
        """(ne, nip) int8: the law's own state codes (trial, or committed)."""
        return self.joint_law.codes(self.state_trial if trial else self.state_committed)

    def result_states(self, trial=False) -> np.ndarray:
        """(ne, nip) int8 state (committed, or the trial one) in the result's terms (``joint_state``, and what
        uplift, stability and mechanism checks count as open or sliding): 0 stick, 1 slip, 2 open, 3 crush
        (``JointLaw.result_state_map``: the Mohr-Coulomb codes are these; the composite law's elastic, shear,
        tension, cap, tension-shear, shear-cap map to stick, slip, open, crush, open, crush)."""
        return self.joint_law.result_states(self.state_trial if trial else self.state_committed)

    def is_open(self, trial=False) -> np.ndarray:
        """(ne, nip) bool: the point is open (committed, or the trial state)."""
        return self.result_states(trial=trial) == RESULT_OPEN

    def plastic_slip(self, trial=False) -> np.ndarray:
        """(ne, nip, dim-1) m: the irreversible slip (committed, or the trial state; zero for a law without)."""
        return self.joint_law.plastic_slip(self.state_trial if trial else self.state_committed, self.delta.shape[2])

    def bond_broken(self, trial=False) -> np.ndarray:
        """(ne, nip) bool: the bond has broken (committed, or the trial state)."""
        return self.joint_law.bond_broken(self.state_trial if trial else self.state_committed)
