"""External loads as full-DOF force vectors (N).

- self-weight: consistent body forces ``rho * g`` of every continuum group (kernel in
  :mod:`masonrydam.elements.continuum`);
- nodal forces on a node set (N per node);
- edge tractions on a facet set (Pa), given as a vector or as a normal pressure (positive pushes
  into the body), integrated consistently with the edge's shape functions and the thickness.
"""
from __future__ import annotations

import numpy as np

from ..assembly.sparsity import scatter_vector
from ..elements.quadrature import gauss_legendre_1d
from ..elements.shapes import shape_functions


def self_weight(model, gravity) -> np.ndarray:
    """Consistent nodal forces (n_dof,) of the self-weight under ``gravity`` (m/s2, vector)."""
    f = np.zeros(model.n_dof)
    g = np.asarray(gravity, dtype=np.float64)
    for grp in model.cgroups:
        scatter_vector(grp.body_force(model.coords, g), grp.dofs, f)
    return f


def nodal_force(model, nodes: np.ndarray, force) -> np.ndarray:
    """Force vector (N) applied at every node of ``nodes``."""
    f = np.zeros(model.n_dof)
    force = np.asarray(force, dtype=np.float64)
    for k in range(model.dim):
        f[np.asarray(nodes) * model.dim + k] += force[k]
    return f


def edge_traction(model, facet_type: str, facets: np.ndarray, thickness: float, traction=None,
                  pressure: float | None = None, owner_centroids: np.ndarray | None = None) -> np.ndarray:
    """Consistent nodal forces (n_dof,) of a traction on 2D edges.

    facets: (n, 2|3) node lists (line2 / line3 order); thickness: m; traction: (2,) Pa, or
    pressure: Pa along the inward normal. The inward side is taken from ``owner_centroids``
    (n, 2) when given, else the normal is the edge tangent rotated -90 degrees (outward for
    counter-clockwise boundaries).
    """
    if model.dim != 2:
        raise NotImplementedError("edge tractions are 2D; 3D face tractions come with 3D elements")
    xg, wg = gauss_legendre_1d(3)
    N, dN = shape_functions(facet_type, xg[:, None])
    f = np.zeros(model.n_dof)
    X = model.coords[facets]  # (n, nfn, 2)
    for q in range(len(wg)):
        x_xi = np.einsum("j,njk->nk", dN[q, 0], X)
        jac = np.linalg.norm(x_xi, axis=1)
        if pressure is not None:
            outward = np.stack([x_xi[:, 1], -x_xi[:, 0]], axis=1) / jac[:, None]
            if owner_centroids is not None:
                mid = np.einsum("j,njk->nk", N[q], X)
                flip = np.einsum("nk,nk->n", owner_centroids - mid, outward) > 0
                outward[flip] *= -1
            t = -pressure * outward
        else:
            t = np.broadcast_to(np.asarray(traction, dtype=np.float64), (len(facets), 2))
        for a in range(facets.shape[1]):
            for k in range(2):
                np.add.at(f, facets[:, a] * 2 + k, N[q, a] * t[:, k] * jac * wg[q] * thickness)
    return f
