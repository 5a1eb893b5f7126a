"""Continuum elements whose material is elasto-plastic: internal forces and the consistent
tangent from the point laws of :mod:`masonrydam.materials.von_mises`,
:mod:`masonrydam.materials.drucker_prager`, :mod:`masonrydam.materials.tresca` and
:mod:`masonrydam.materials.mohr_coulomb_solid`, small strains, plane strain (2D, strain [exx, eyy, gxy])
and 3D.

Per element and Gauss point ``g`` (state row ``k = e * n_gp + g``)::

    eps = B u_e,   (sigma, D_t) = law(eps, committed state, dt)
    f_e += B^T sigma w det(J) t,   k_e += B^T D_t B w det(J) t

(the standard displacement element with a path-dependent material: Zienkiewicz & Taylor, *The Finite
Element Method*, vol. 2, 6th ed. 2005, ch. 3; Simo & Hughes 1998, sec. 3.4). ``k_e`` is assembled in
full: the tangent of non-associated Drucker-Prager is not symmetric. The law writes the trial state;
the model commits or reverts it with the joints' protocol.
"""
from __future__ import annotations

import numba
import numpy as np

from ..errors import STATUS_NAN, STATUS_OK, SceneError
from ..materials.continuum_laws import ELASTIC_LAW, continuum_law, continuum_laws
from ..materials.drucker_prager import drucker_prager_point
from ..materials.mohr_coulomb_solid import mohr_coulomb_solid_point
from ..materials.plasticity import WORK_SIZE
from ..materials.tresca import tresca_point
from ..materials.von_mises import von_mises_point
from .continuum import (DETJ_RTOL, element_tables, add_btdb, add_btsigma, bad_det_status, block_finite, dimension_tag,
                        gather_displacements, gather_element, shape_gradients, voigt_map)

#: law identifiers of :func:`continuum_plastic_evaluate` (the branches of ``_plastic_impl``): each plastic law's
#: ``ContinuumLaw.kernel_id`` (:mod:`masonrydam.materials.continuum_laws`): 1 von Mises, 2 Drucker-Prager,
#: 3 Tresca, 4 Mohr-Coulomb
LAW_IDS = {law.name: law.kernel_id for law in continuum_laws() if law.plastic}


@numba.njit(cache=True)
def _plastic_impl(coords, conn, dN_ref, weights, thickness, u, params, param_index, state_committed, state_trial, dt,
                  want_tangent, law, fe_out, ke_out, info, dim_tag):
    n_elem = conn.shape[0]
    nen = conn.shape[1]
    dim = len(dim_tag)
    n_gp = weights.shape[0]
    ns = 3 if dim == 2 else 6
    nd = nen * dim
    V = voigt_map(dim_tag)
    xe = np.empty((nen, dim))
    ue = np.empty((nen, dim))
    J = np.empty((dim, dim))
    dNdx = np.empty((dim, nen))
    B = np.empty((ns, nd))
    eps = np.empty(ns)
    sig = np.empty(ns)
    D = np.empty((ns, ns))
    DB = np.empty((ns, nd))
    work = np.empty(WORK_SIZE)
    for e in range(n_elem):
        h = gather_element(coords, conn, e, xe, dim_tag)
        tol = DETJ_RTOL * h**dim
        gather_displacements(u, conn, e, ue, dim_tag)
        t_e = thickness[e] if dim == 2 else 1.0
        fe = fe_out[e]
        for r in range(nd):
            fe[r] = 0.0
        if want_tangent:
            ke = ke_out[e]
            for r in range(nd):
                for c in range(nd):
                    ke[r, c] = 0.0
        for g in range(n_gp):
            det = shape_gradients(xe, dN_ref, g, tol, J, dNdx, dim_tag)
            if not (det > tol):
                return bad_det_status(det, e, info)
            f = weights[g] * det * t_e
            # B (ns, nd): eps[V(i, j)] = sum_a (u_ai dN_a/dx_j + u_aj dN_a/dx_i) for i < j, u_ai dN_a/dx_i on i = j
            for s in range(ns):
                for c in range(nd):
                    B[s, c] = 0.0
            for a in range(nen):
                for i in range(dim):
                    for j in range(dim):
                        B[V[i, j], a * dim + i] += dNdx[j, a] if i != j else dNdx[i, a]
            for s in range(ns):
                acc = 0.0
                for c in range(nd):
                    acc += B[s, c] * ue[c // dim, c % dim]
                eps[s] = acc
            k = e * n_gp + g
            if law == 1:
                st = von_mises_point(eps, params, param_index[e], state_committed, state_trial, k, dt, want_tangent,
                                     sig, D, work)
            elif law == 2:
                st = drucker_prager_point(eps, params, param_index[e], state_committed, state_trial, k, dt,
                                          want_tangent, sig, D, work)
            elif law == 3:
                st = tresca_point(eps, params, param_index[e], state_committed, state_trial, k, dt, want_tangent, sig,
                                  D, work)
            else:
                st = mohr_coulomb_solid_point(eps, params, param_index[e], state_committed, state_trial, k, dt,
                                              want_tangent, sig, D, work)
            if st != STATUS_OK:
                info[0] = e
                return st
            add_btsigma(B, sig, f, fe)
            if want_tangent:
                add_btdb(B, D, f, DB, ke)
        if not block_finite(fe):
            info[0] = e
            return STATUS_NAN
    return STATUS_OK


def continuum_plastic_evaluate(coords, conn, dN_ref, weights, thickness, u, params, param_index, state_committed,
                               state_trial, dt, want_tangent, law, fe_out, ke_out, info):
    """Internal forces ``fe_out`` (ne, nd) N and, with ``want_tangent``, the consistent tangents ``ke_out``
    (ne, nd, nd) N/m of elasto-plastic elements at the displacement ``u`` (n_dof,) m.

    params (n_mat, P) law parameters, param_index (ne,) row of each element; state_committed,
    state_trial (ne * n_gp, S): the law's state per Gauss point (row ``e * n_gp + g``; the trial rows
    are written); dt (s): the step's time for Perzyna viscosity; law: :data:`LAW_IDS` value. Returns a
    status (the failing element in ``info[0]``; a law's own status, e.g. bad parameters, passes through).
    """
    return _plastic_impl(coords, conn, dN_ref, weights, thickness, u, params, param_index, state_committed,
                         state_trial, float(dt), bool(want_tangent), int(law), fe_out, ke_out, info, dimension_tag(coords))


# -- the parameter table of a group ----------------------------------------------------------------------

def element_sizes(coords: np.ndarray, conn: np.ndarray, type_name: str) -> np.ndarray:
    """Characteristic length of each element (ne,) m: the square root of its area (2D) or the cube root of
    its volume (3D), the crack-band width of a softening element (Bazant & Oh 1983, Mater. Struct. 16)."""
    _, dN, w = element_tables(type_name)
    J = np.einsum("gin,enj->egij", dN, coords[conn])
    size = np.einsum("g,eg->e", w, np.abs(np.linalg.det(J)))
    return size ** (1.0 / coords.shape[1])


def law_parameter_table(m: dict, name: str, dim: int, hypothesis: str, coords=None, conn=None, type_name=None):
    """The parameter table of an elasto-plastic material, None for an elastic one: one row (1, P), or one
    row per element (ne, P) when a softening modulus is regularised by the element size (crack band:
    ``H_e = H l_e / regularisation_length`` keeps the energy dissipated per unit area of a localised band
    independent of the mesh; Bazant & Oh 1983; Pietruszczak & Mroz 1981, IJNME 17, for plasticity)."""
    law = continuum_law(m.get("law", ELASTIC_LAW))
    if not law.plastic:
        return None
    key = f"materials.{name}"
    if dim == 2 and hypothesis != "plane_strain":
        raise SceneError(f"{key}.law", f"\"{law.name}\" needs plane strain in 2D ([model] hypothesis = "
                                       f"\"plane_strain\"; the laws keep the out-of-plane stress), got {hypothesis!r}")
    soft_key, column = law.hardening_key, law.hardening_column

    def row(h, where=""):
        try:
            r = law.parameters(m, h)
        except ValueError as exc:
            raise SceneError(key if not where else f"{key}.{soft_key}", str(exc) + where) from None
        return np.asarray(r, dtype=np.float64)

    h = m[soft_key]
    base = row(h)
    length = m.get("regularisation_length")
    if length is None or h >= 0.0 or conn is None:
        return np.ascontiguousarray(base.reshape(1, -1))
    sizes = element_sizes(coords, conn, type_name)
    big = int(np.argmax(sizes))
    # the steepest softening is that of the largest element: it must not snap back within the element
    row(h * sizes[big] / length, f" (element {big} of '{name}', size {sizes[big]:.4g} m, scaled from "
                                 f"regularisation_length = {length:g} m: refine the mesh there, or soften less)")
    table = np.repeat(base.reshape(1, -1), len(conn), axis=0)
    table[:, column] = h * sizes / length
    return np.ascontiguousarray(table)
