"""Mass of the continuum groups (joints carry no mass) and added masses, assembled once: :class:`MassMatrix`.

Assembled once from the continuum groups (joints carry no mass): consistent
``M = int rho N^T N dV`` or HRZ-lumped (the kernel :func:`masonrydam.elements.continuum.continuum_mass`;
Hinton, Rock & Zienkiewicz 1976). Triangles and tetrahedra need a rule exact for ``N_a N_b``, one
order above the stiffness rule (tri3 -> 3 points, tri6 -> 6, tet4 -> 4, tet10 -> 14); quadrilaterals
and hexahedra use their default rule, exact on parallelograms. :class:`MassMatrix` holds the full-DOF
matrix (for ``M iota`` and reactions) and, once the constraints are known, the free-DOF values laid
out in the model's stiffness pattern (the mass pattern of an element is a subset of its stiffness
pattern), so that an effective matrix ``K + c_m M + c_c C`` is a sum of three value arrays.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..elements import continuum as ck
from .groups import raise_for_status
from .sparsity import add_to_pattern, diagonal_positions, full_matrix, scatter_matrix

#: integration points per element type for a consistent mass (exact for N_a N_b on straight elements)
MASS_RULE = {"tri3": 3, "tri6": 6, "tet4": 4, "tet10": 14}


def element_masses(model, lumped: bool, massless=()):
    """(group, me) per continuum group (except the groups named in ``massless``): element mass matrices
    (ne, nd, nd) in kg."""
    out = []
    for g in model.cgroups:
        if g.name in massless:
            continue
        N, dN, w = ck.element_tables(g.type, MASS_RULE.get(g.type))
        me = np.zeros((g.n_elem, g.n_edof, g.n_edof))
        st = ck.continuum_mass(model.coords, g.conn, N, dN, w, np.ascontiguousarray(g.density, dtype=np.float64),
                               np.ascontiguousarray(g.thickness, dtype=np.float64), bool(lumped), me, g.info)
        raise_for_status(st, g.info, g.name, "mass")
        out.append((g, me))
    return out


class MassMatrix:
    """Mass of the continuum groups, assembled once, plus an optional added mass (e.g. the reservoir's,
    :mod:`masonrydam.effects.reservoir.added_mass`).

    ``lumped``; ``full`` (n_dof, n_dof) CSR; ``diagonal``: the whole matrix is diagonal (lumped element
    masses and an added mass without off-diagonal terms), then ``diag`` (n_dof,) kg and, after
    :meth:`for_pattern`, ``free_diag`` (n_eq,); ``data`` (nnz,) free-DOF values in the model pattern.
    added: (n_dof, n_dof) sparse, kg, or None; its entries must lie in the model's pattern (nodes that
    share an element or a coupling, :meth:`Model.add_coupling`). extra_influence: see the attribute.
    massless: names of element groups without mass (e.g. the foundation rock of ``[foundation] mass =
    false``).
    """

    def __init__(self, model, lumped: bool, added: sp.spmatrix | None = None,
                 extra_influence: np.ndarray | None = None, massless=()):
        self.lumped = bool(lumped)
        #: (dim, n_dof) kg or None: the earthquake load per unit acceleration of the reservoir bottom that is
        #: not ``M iota`` (incompressible acoustic water pushed by the bottom and banks; the dynamic solver
        #: applies ``-extra_influence . a_bottom``)
        self.extra_influence = extra_influence
        #: names of the element groups left without mass
        self.massless = tuple(massless)
        self._groups = element_masses(model, self.lumped, self.massless)
        self.n_dof = model.n_dof
        self.added = None if added is None or added.nnz == 0 else sp.csr_matrix(added)
        if self.lumped:
            diag = np.zeros(model.n_dof)
            for g, me in self._groups:
                d = np.einsum("eii->ei", me)
                np.add.at(diag, g.dofs.ravel(), d.ravel())
            self.full = sp.diags(diag).tocsr()
        else:
            self.full = full_matrix(model.n_dof, [(g.dofs, me) for g, me in self._groups])
        #: the continuum's own mass (what Rayleigh damping is proportional to: the water's added mass is
        #: not a material that dissipates); ``structural_data`` its pattern values after for_pattern
        self.structural_full = self.full
        self.structural_data = None
        if self.added is not None:
            self.full = (self.full + self.added).tocsr()
        offdiag = self.full - sp.diags(self.full.diagonal())
        self.diagonal = self.lumped and offdiag.count_nonzero() == 0
        self.diag = self.full.diagonal().copy() if self.diagonal else None
        self.data = None
        self.free_diag = None
        self._pattern_key = None

    def total(self, dim: int) -> np.ndarray:
        """Total mass per direction (kg), ``iota_c^T M iota_c``."""
        out = np.zeros(dim)
        for c in range(dim):
            iota = np.zeros(self.n_dof)
            iota[c::dim] = 1.0
            out[c] = iota @ (self.full @ iota)
        return out

    def influence(self, dim: int) -> np.ndarray:
        """(dim, n_dof) ``M iota_c`` for a rigid unit translation of everything (supports included) in c."""
        out = np.zeros((dim, self.n_dof))
        for c in range(dim):
            iota = np.zeros(self.n_dof)
            iota[c::dim] = 1.0
            out[c] = self.full @ iota
        return out

    def for_pattern(self, model) -> np.ndarray:
        """Free-DOF mass values in the model's current CSR pattern (``model.set_constraints`` first)."""
        key = (id(model.dofmap), len(model.indices))
        if self._pattern_key == key:
            return self.data
        data = np.zeros(len(model.indices))
        free = model.dofmap.free
        if self.diagonal:
            self.free_diag = self.diag[free].copy()
            data[diagonal_positions(model.indptr, model.indices)] = self.free_diag
        else:
            if self.lumped:
                d = np.zeros(model.n_dof)
                for g, me in self._groups:
                    np.add.at(d, g.dofs.ravel(), np.einsum("eii->ei", me).ravel())
                data[diagonal_positions(model.indptr, model.indices)] = d[free]
            else:
                for g, me in self._groups:
                    scatter_matrix(me, g.scatter, data)
            if self.added is not None:
                self.structural_data = data.copy()
                add_to_pattern(self.added[free][:, free], model.indptr, model.indices, data, "added mass")
        if self.added is None:
            self.structural_data = data
        elif self.diagonal:
            self.structural_data = np.zeros(len(model.indices))
            self.structural_data[diagonal_positions(model.indptr, model.indices)] = \
                self.structural_full.diagonal()[free]
        self.data = data
        self._pattern_key = key
        return data

    def free_matrix(self, model) -> sp.csr_matrix:
        n = model.dofmap.n_eq
        return sp.csr_matrix((self.for_pattern(model), model.indices, model.indptr), shape=(n, n))
