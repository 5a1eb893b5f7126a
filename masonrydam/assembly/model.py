"""The assembled finite element model: groups, DOF map, sparsity pattern and evaluation.

The linear continuum part is assembled once: a full-DOF CSR matrix gives the continuum internal
forces (``K_c u``, reactions included) and its free-DOF part is scattered once per set of
constraints. Only interfaces are re-evaluated in Newton iterations, so a scene whose joints stick
costs one interface pass and one sparse mat-vec per iteration.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..elements.shapes import ELEMENT_TYPES, reference_nodes, shape_functions
from ..errors import MeshError
from .dofmap import DofMap
from .groups import ContinuumGroup, InterfaceGroup
from .sparsity import build_pattern, scatter_matrix, scatter_vector


def check_corners(coords: np.ndarray, group: ContinuumGroup, rtol: float = 1e-10) -> None:
    """Reject inverted, collapsed, re-entrant or badly distorted elements before any solving.

    The kernels check the Jacobian at the integration points, which misses e.g. a quadrilateral with
    two coincident corners or a slightly re-entrant corner (its Jacobian is still positive at the Gauss
    points). Only the corner nodes are looked at (mid-side nodes of quadratic elements are not).

    - 2D: every corner of every element must turn counter-clockwise: the cross product of its two
      edges, relative to the element size squared, must exceed ``rtol``.
    - hex8 / hex20: the Jacobian determinant of the trilinear map of the 8 corners, evaluated at each
      corner, must exceed ``rtol * size**3``. At a corner it is 1/8 of the triple product of the three
      edges leaving that corner in the +xi, +eta, +zeta directions; all 8 positive is the usual
      corner-Jacobian test of hexahedral mesh quality (P.M. Knupp, "Achieving finite element mesh
      quality via optimization of the Jacobian matrix norm and associated quantities. Part II",
      Int. J. Numer. Methods Eng. 48 (2000) 1165-1185).
    - tet4 / tet10: the signed volume of the 4 corners, ``det[x1 - x0, x2 - x0, x3 - x0] / 6``, must
      exceed ``rtol * size**3``.

    ``size`` is the diagonal of the element's axis-aligned bounding box, m.

    Raises
    ------
    MeshError
        Naming ``group.name`` and the indices (rows of ``group.conn``) of all failing elements.
    """
    et = ELEMENT_TYPES[group.type]
    nc = et.corner_nodes
    x = coords[group.conn[:, :nc]]  # (ne, nc, dim)
    size2 = (np.ptp(x, axis=1) ** 2).sum(axis=1)  # (ne,) squared bounding-box diagonal
    if coords.shape[1] == 2:
        prev, nxt = np.roll(x, 1, axis=1), np.roll(x, -1, axis=1)
        a, b = nxt - x, prev - x
        cross = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
        bad = np.nonzero((cross <= rtol * size2[:, None]).any(axis=1))[0]
        if len(bad):
            raise MeshError("inverted, collapsed or re-entrant element (corners must be counter-clockwise and "
                            "convex)", group.name, bad)
        return
    if coords.shape[1] != 3:
        return
    size3 = size2**1.5
    if et.family == "hex":
        # J[e, p, i, j] = sum_a dN_a/dxi_i (corner p) x_aj for the trilinear corner map
        _, dN = shape_functions("hex8", reference_nodes("hex8"))  # (8 points, 3, 8 nodes)
        J = np.einsum("pia,eaj->epij", dN, x)
        det = np.linalg.det(J)  # (ne, 8)
        bad = np.nonzero((det <= rtol * size3[:, None]).any(axis=1))[0]
        what = ("inverted, collapsed or badly distorted hexahedron (the Jacobian determinant of the corner "
                "map must be positive at all 8 corners)")
    elif et.family == "tet":
        e = x[:, 1:, :] - x[:, :1, :]
        vol = np.einsum("ei,ei->e", e[:, 0], np.cross(e[:, 1], e[:, 2])) / 6.0
        bad = np.nonzero(vol <= rtol * size3)[0]
        what = "inverted or collapsed tetrahedron (the signed volume of the corners must be positive)"
    else:
        return
    if len(bad):
        raise MeshError(what, group.name, bad)


class Model:
    """Finite element model.

    coords (n_nodes, dim) m; cgroups: continuum groups; igroups: interface groups (joint sets).
    """

    def __init__(self, coords: np.ndarray, cgroups: list[ContinuumGroup], igroups: list[InterfaceGroup]):
        self.coords = np.ascontiguousarray(coords, dtype=np.float64)
        self.dim = self.coords.shape[1]
        self.n_nodes = len(self.coords)
        self.n_dof = self.n_nodes * self.dim
        self.cgroups, self.igroups = cgroups, igroups
        self._continuum_force = None  # (u, K_continuum @ u) of the last evaluate (see continuum_force)
        used = np.zeros(self.n_nodes, dtype=bool)
        for g in list(cgroups) + list(igroups):
            used[g.conn.ravel()] = True
        if not used.all():
            bad = np.nonzero(~used)[0]
            raise MeshError(f"{len(bad)} node(s) belong to no element, e.g. node {bad[0]} at {self.coords[bad[0]].tolist()}")
        for g in cgroups:
            check_corners(self.coords, g)
        # full-DOF continuum stiffness (constant for linear elastic blocks)
        rows, cols, vals = [], [], []
        for g in cgroups:
            if g.nonlinear:  # evaluated at every iteration (evaluate), not part of the linear stiffness
                continue
            ke = g.stiffness(self.coords)
            nd = g.n_edof
            rows.append(np.repeat(g.dofs, nd, axis=1).ravel())
            cols.append(np.tile(g.dofs, (1, nd)).ravel())
            vals.append(ke.reshape(len(ke), -1).ravel())
        self.K_continuum = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(self.n_dof, self.n_dof)
        ) if vals else sp.csr_matrix((self.n_dof, self.n_dof))
        self.K_continuum.sum_duplicates()
        self.dofmap: DofMap | None = None
        #: node sets whose DOFs are coupled all to all beyond the elements (e.g. the wetted face under a
        #: reservoir condensed on it): (1, n_nodes * dim) DOF arrays, part of the sparsity pattern
        self.couplings: list[np.ndarray] = []
        #: tied node sets (:meth:`add_tie`): ((1, n_tie_dofs) DOFs, (1, n_tie_dofs, n_tie_dofs) penalty stiffness)
        self.ties: list[tuple[np.ndarray, np.ndarray]] = []
        #: time (s) of the step being solved, seen by rate-dependent (Perzyna) laws of elasto-plastic
        #: groups; 0 is a rate-independent step (the solvers set it: the dynamic step, a static stage's
        #: time per load step)
        self.time_step = 0.0

    @property
    def nonlinear(self) -> bool:
        return any(g.nonlinear for g in self.igroups) or self.continuum_nonlinear or self.large

    @property
    def plastic(self) -> bool:
        """Some continuum group is elasto-plastic: the blocks are not linear (no joint-space condensation)."""
        return any(g.plastic for g in self.cgroups)

    @property
    def large(self) -> bool:
        """Large kinematics (``[model] kinematics = "large"``): total Lagrangian blocks and joints whose
        frame turns with them."""
        return any(g.large for g in self.cgroups) or any(g.kinematics == "large" for g in self.igroups)

    @property
    def joint_space_capable(self) -> bool:
        """Every joint set follows a law that the joint-space kernels carry (``JointLaw.joint_space``: the
        Mohr-Coulomb law of Tzamtzis & Asteris, :mod:`masonrydam.solvers.joint_space.kernels`)."""
        return all(g.joint_law.joint_space for g in self.igroups)

    @property
    def rate_dependent(self) -> bool:
        """Some elasto-plastic group has Perzyna viscosity: its forces depend on :attr:`time_step`, not on the
        displacement alone."""
        return (any(g.viscous for g in self.cgroups)
                or any(g.relaxation_time > 0 for g in self.igroups))

    @property
    def continuum_nonlinear(self) -> bool:
        """Some continuum group is evaluated at every iteration (plastic or large kinematics)."""
        return any(g.nonlinear for g in self.cgroups)

    @property
    def condensable(self) -> bool:
        """Linear blocks and small kinematics: the tangent of sticking joints is the constant elastic one,
        so the joint-space condensation and the all-stick factorization apply."""
        return not (self.continuum_nonlinear or self.large)

    def continuum_energy(self, u: np.ndarray) -> float:
        """Elastic energy of the blocks (J) at ``u``: ``u K_c u / 2`` of the linear groups plus the St.
        Venant-Kirchhoff energy of large-kinematics groups (from their last evaluation if it was at ``u``,
        else evaluated). Elasto-plastic groups are not included (their work is integrated by the caller)."""
        cached = self._continuum_force
        if self.large and not (cached is not None and np.array_equal(cached[0], u) and cached[2] == self.time_step):
            self.continuum_force(u)
        e = 0.5 * float(u @ (self.K_continuum @ u))
        return e + sum(float(g.energy.sum()) for g in self.cgroups if g.large)

    def add_coupling(self, nodes: np.ndarray) -> None:
        """Couple every DOF of ``nodes`` with every other in the sparsity pattern (a dense block, e.g.
        the reservoir condensed on the wetted face); the pattern is rebuilt at the next
        :meth:`set_constraints`."""
        nodes = np.unique(np.asarray(nodes, dtype=np.int64))
        dofs = (nodes[:, None] * self.dim + np.arange(self.dim)).reshape(1, -1)
        if any(np.array_equal(c, dofs) for c in self.couplings):
            return
        self.couplings.append(dofs)
        self.dofmap = None

    def add_tie(self, nodes: np.ndarray, components, stiffness: float | None = None) -> float:
        """Make ``nodes`` share one displacement in each of ``components`` (indices 0..dim-1), free to
        translate together: a rigid loading beam guided to stay level. Penalty: the energy
        ``k/2 sum_i (u_i - mean(u))^2`` per component, i.e. the stiffness ``k (I - 1 1^T / n)`` on the
        component's DOFs of the nodes, which resists no common translation. ``k`` (N/m, default 1e4 times
        the largest diagonal of the blocks' initial elastic stiffness at those DOFs, nonlinear groups
        included) keeps the relative differences of the tied displacements near 1e-4 of the blocks' own
        deformation there. A constant linear term: it goes into ``K_continuum`` (forces) and into the
        tangent pattern (a coupling, :meth:`add_coupling`). In a dynamic stage it also enters
        stiffness-proportional Rayleigh damping and the explicit stability limit, as any stiff part does.
        Returns ``k``; ValueError for fewer than two nodes or a stiffness that is not positive."""
        nodes = np.unique(np.asarray(nodes, dtype=np.int64))
        n, dim = len(nodes), self.dim
        if n < 2:
            raise ValueError("a tie needs at least two nodes")
        comps = sorted(set(int(c) for c in components))
        dofs = (nodes[:, None] * dim + np.arange(dim)).ravel()
        if stiffness is None:
            diag = self.K_continuum_elastic.diagonal()
            stiffness = 1e4 * float(max(diag[nodes * dim + c].max() for c in comps))
        if not (np.isfinite(stiffness) and stiffness > 0):
            raise ValueError(f"the tie's penalty stiffness must be positive, got {stiffness!r} (do the nodes belong "
                             "to blocks?)")
        block = np.zeros((n * dim, n * dim))
        share = np.eye(n) - np.full((n, n), 1.0 / n)
        for c in comps:
            idx = np.arange(n) * dim + c
            block[np.ix_(idx, idx)] += stiffness * share
        self.K_continuum = (self.K_continuum + sp.csr_matrix(
            (block.ravel(), (np.repeat(dofs, len(dofs)), np.tile(dofs, len(dofs)))), shape=(self.n_dof, self.n_dof)
        )).tocsr()
        self._K_elastic_full = None
        self._elastic_data = None
        self._continuum_force = None
        self.ties.append((dofs.reshape(1, -1), block[None]))
        self.add_coupling(nodes)
        self.dofmap = None  # (the tangent pattern and K_linear_data are rebuilt with the tie)
        return stiffness

    def set_constraints(self, constrained: np.ndarray) -> None:
        """Build the DOF map, sparsity pattern and scatter maps for a set of constrained DOFs."""
        if self.dofmap is not None and np.array_equal(self.dofmap.constrained, constrained):
            return
        self.dofmap = dm = DofMap(self.n_nodes, self.dim, constrained)
        groups = list(self.cgroups) + list(self.igroups)
        self.indptr, self.indices, scatters = build_pattern([g.dofs for g in groups] + self.couplings, dm.eq_of_dof,
                                                            dm.n_eq, dim=self.dim)
        for g, s in zip(groups, scatters):
            g.scatter = s
        coupling_scatter = dict(zip((c.tobytes() for c in self.couplings), scatters[len(groups):]))
        self.K_linear_data = np.zeros(len(self.indices))
        for dofs, block in self.ties:  # (each tie's DOFs are one of the couplings)
            scatter_matrix(block, coupling_scatter[dofs.tobytes()], self.K_linear_data)
        for g in self.cgroups:
            if not g.nonlinear:
                scatter_matrix(g.stiffness(self.coords), g.scatter, self.K_linear_data)

    def elastic_continuum_data(self) -> np.ndarray:
        """Free-DOF values (pattern) of the blocks' initial elastic stiffness: ``K_linear_data`` plus the
        small-strain stiffness of the nonlinear groups (their tangent at rest), for the matrices that
        stand for "the elastic structure" (Rayleigh damping, the all-stick reference factorization,
        modal analysis). ``K_linear_data`` itself when every group is linear."""
        if not self.continuum_nonlinear:
            return self.K_linear_data
        cached = getattr(self, "_elastic_data", None)
        if cached is not None and cached[0] is self.dofmap:
            return cached[1]
        data = self.K_linear_data.copy()
        for g in self.cgroups:
            if g.nonlinear:
                scatter_matrix(g.stiffness(self.coords), g.scatter, data)
        self._elastic_data = (self.dofmap, data)
        return data

    @property
    def K_continuum_elastic(self) -> sp.csr_matrix:
        """Full-DOF initial elastic stiffness of all blocks (``K_continuum`` when every group is linear)."""
        if not self.continuum_nonlinear:
            return self.K_continuum
        cached = getattr(self, "_K_elastic_full", None)
        if cached is None:
            rows, cols, vals = [], [], []
            for g in self.cgroups:
                if g.nonlinear:
                    ke = g.stiffness(self.coords)
                    nd = g.n_edof
                    rows.append(np.repeat(g.dofs, nd, axis=1).ravel())
                    cols.append(np.tile(g.dofs, (1, nd)).ravel())
                    vals.append(ke.reshape(len(ke), -1).ravel())
            extra = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                  shape=(self.n_dof, self.n_dof))
            cached = self._K_elastic_full = (self.K_continuum + extra).tocsr()
        return cached

    def evaluate(self, u: np.ndarray, want_tangent: bool = True):
        """Internal forces (n_dof,) N at all DOFs and the free-DOF tangent (CSR) at displacement ``u``.

        Interfaces are evaluated from their committed state (trial state updated).
        """
        fc = self.K_continuum @ u
        data = self.K_linear_data.copy() if want_tangent else None
        for g in self.cgroups:
            if g.nonlinear:
                g.evaluate(self.coords, u, want_tangent, self.time_step)
                scatter_vector(g.fe, g.dofs, fc)
                if want_tangent:
                    scatter_matrix(g.ke, g.scatter, data)
        self._continuum_force = (u.copy(), fc, self.time_step)
        f = fc.copy()
        for g in self.igroups:
            g.evaluate(self.coords, u, want_tangent, self.time_step)
            scatter_vector(g.fe, g.dofs, f)
            if want_tangent:
                scatter_matrix(g.ke, g.scatter, data)
        K = None
        if want_tangent:
            n = self.dofmap.n_eq
            K = sp.csr_matrix((data, self.indices, self.indptr), shape=(n, n))
        return f, K

    def use_stored_frames(self) -> None:
        """Forces-only evaluations (``evaluate(u, want_tangent=False)``) of the joints read the reference frames
        and weights computed when the model was built (``InterfaceGroup.forces_from_stored_frames``): the
        dynamic solver's choice, where they come every step (the compiled step loop uses the same kernel)."""
        for g in self.igroups:
            g.forces_from_stored_frames = True

    def tangent_product(self, x: np.ndarray) -> np.ndarray:
        """``K x`` (n_dof,) with the full-DOF tangent of the last evaluation with tangents (the linear blocks'
        constant stiffness, the element tangents of nonlinear blocks and joints), for any ``x`` (n_dof,),
        prescribed DOFs included: e.g. the load a prescribed displacement increment puts on the free DOFs
        (arc-length control)."""
        y = self.K_continuum @ x
        for g in [g for g in self.cgroups if g.nonlinear] + list(self.igroups):
            scatter_vector(np.einsum("eij,ej->ei", g.ke, x[g.dofs]), g.dofs, y)
        return y

    def continuum_force(self, u: np.ndarray) -> np.ndarray:
        """The blocks' internal forces (n_dof,) N at ``u`` (``K_continuum @ u`` plus the nonlinear groups'
        forces): the ones :meth:`evaluate` computed if it was called last at this very ``u`` (a comparison
        instead of a sparse product), else computed (nonlinear groups evaluated, forces only). The array
        is shared: do not modify."""
        cached = self._continuum_force
        if cached is not None and np.array_equal(cached[0], u) and cached[2] == self.time_step:
            return cached[1]
        fc = self.K_continuum @ u
        for g in self.cgroups:
            if g.nonlinear:
                g.evaluate(self.coords, u, False, self.time_step)
                scatter_vector(g.fe, g.dofs, fc)
        return fc

    def set_open_tangent(self, factor: float) -> None:
        """Tangent factor of open joint points (0: consistent; 1: initial stiffness). Residuals unchanged."""
        for g in self.igroups:
            g.set_open_tangent(factor)

    def commit(self) -> None:
        for g in self.cgroups:
            g.commit()
        for g in self.igroups:
            g.commit()

    def revert(self) -> None:
        for g in self.cgroups:
            g.revert()
        for g in self.igroups:
            g.revert()

    def far_slips(self) -> list[str]:
        """Joint sets whose points have slid farther than the length of their element (committed plastic slip):
        a node-to-node joint keeps the partners it was meshed with (no contact search re-pairs them), which
        holds only approximately, and only while the faces stay on one straight (plane), rigid line. One
        text per such set."""
        out = []
        for g in self.igroups:
            face = g.jw.sum(axis=1)  # (ne,) element length (2D) or area (3D)
            size = face if self.dim == 2 else np.sqrt(face)  # m
            # the committed plastic slip (a failed attempt's trial values do not count), (ne, nip) m
            slip = np.linalg.norm(g.plastic_slip(), axis=2)
            ratio = slip / size[:, None]
            if ratio.size and ratio.max() > 1.0:
                e, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
                out.append(f"joint set '{g.name}': points slid up to {ratio.max():.3g} element lengths ({slip[e, i]:.4g} "
                           f"m at element {e}); node-to-node joints keep the partners they were meshed with, so the "
                           "contact forces still act between those partners (a sound approximation on a straight, "
                           "rigid joint only: there is no contact search)")
        return out

    def latch_broken_bonds(self) -> int:
        return sum(g.latch_broken_bonds() for g in self.igroups if g.nonlinear)

    def state_signature(self) -> bytes:
        """Bytes that change whenever any joint changes state (stick/slip/open)."""
        return b"".join(g.state_codes(trial=True).tobytes() for g in self.igroups if g.nonlinear)
