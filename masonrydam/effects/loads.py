"""External loads as full-DOF force vectors (N): the load types of a static stage.

- self-weight: consistent body forces ``rho * g`` of every continuum group (kernel in
  :mod:`masonrydam.elements.continuum`);
- nodal forces on a node set (N per node);
- tractions on a facet set (edges in 2D, faces in 3D; Pa), given as a vector or as a normal pressure
  (positive pushes into the body), integrated consistently with the facet's shape functions (and
  the thickness in 2D).
"""
from __future__ import annotations

import numpy as np

from ..assembly.sparsity import scatter_vector
from ..checks import check_keys, components, number, vector
from ..elements.quadrature import gauss_legendre_1d
from ..elements.shapes import facet_area_normal, shape_functions
from ..errors import SceneError
from ..units import quantity


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


def _facet_rule(facet_type: str):
    """Gauss rule on the reference facet, exact for the products of shape functions and a linear
    Jacobian: line 3 points, quadrilateral 3x3, triangle 6 points."""
    from ..elements.quadrature import tensor_rule, triangle_rule

    if facet_type in ("line2", "line3"):
        xg, wg = gauss_legendre_1d(3)
        return xg[:, None], wg
    if facet_type in ("quad4", "quad8", "quad9"):
        return tensor_rule("gauss", 3, 2)
    if facet_type in ("tri3", "tri6"):
        return triangle_rule(6)
    raise ValueError(f"no traction rule for facet type '{facet_type}'")


def facet_traction(model, facet_type: str, facets: np.ndarray, thickness: float = 1.0, traction=None,
                   pressure: float | None = None, owner_centroids: np.ndarray | None = None) -> np.ndarray:
    """Consistent nodal forces (n_dof,) of a traction on boundary facets: edges in 2D, faces in 3D.

    facets: (n, nfn) node lists in the facet type's order (line2/line3 in 2D; quad4/quad8/tri3/tri6
    in 3D); thickness: m (2D only); traction: (dim,) Pa, or pressure: Pa along the inward normal.
    The inward side is taken from ``owner_centroids`` (n, dim) when given; otherwise the facet's
    own normal is taken as outward (2D: tangent turned -90 degrees, i.e. counter-clockwise
    boundaries; 3D: right-hand rule).
    """
    dim = model.dim
    pts, wg = _facet_rule(facet_type)
    N, dN = shape_functions(facet_type, pts)
    f = np.zeros(model.n_dof)
    facets = np.asarray(facets, dtype=np.int64)
    X = model.coords[facets]  # (n, nfn, dim)
    scale = thickness if dim == 2 else 1.0
    for q in range(len(wg)):
        normal = facet_area_normal(dN[q], X)
        jac = np.linalg.norm(normal, axis=1)
        if pressure is not None:
            outward = normal / jac[:, None]
            if owner_centroids is not None:
                mid = np.einsum("j,njk->nk", N[q], X)
                flip = np.einsum("nk,nk->n", owner_centroids - mid, outward) > 0
                outward[flip] *= -1
            t = -pressure * outward
        else:
            t = np.broadcast_to(np.asarray(traction, dtype=np.float64), (len(facets), dim))
        for a in range(facets.shape[1]):
            for k in range(dim):
                np.add.at(f, facets[:, a] * dim + k, N[q, a] * t[:, k] * jac * wg[q] * scale)
    return f


def edge_traction(model, facet_type: str, facets: np.ndarray, thickness: float, traction=None,
                  pressure: float | None = None, owner_centroids: np.ndarray | None = None) -> np.ndarray:
    """2D name of :func:`facet_traction` (kept for existing callers)."""
    return facet_traction(model, facet_type, facets, thickness, traction, pressure, owner_centroids)


# -- scene schema: the load types of a static stage ([[stages.loads]]) ----------------------------------
def _self_weight(d, key, dim):
    check_keys(d, {"type", "factor", "acceleration"}, key)
    out = {"type": "self_weight", "factor": number(d.get("factor", 1.0), f"{key}.factor")}
    if "acceleration" in d:  # a body force rho a in another direction than gravity (pseudo-static seismic
        # coefficient, a tilt-table test): replaces [model] gravity for this load
        out["acceleration"] = vector(d["acceleration"], "acceleration", f"{key}.acceleration", dim)
    return out


def _needs_set(d, key):
    if "set" not in d:
        raise SceneError(f"{key}.set", "is required")
    return str(d["set"])


def _nodal(d, key, dim):
    check_keys(d, {"type", "set", "force"}, key)
    return {"type": "nodal", "set": _needs_set(d, key), "force": vector(d.get("force"), "force", f"{key}.force", dim)}


def _traction(d, key, dim):
    check_keys(d, {"type", "set", "traction"}, key)
    return {"type": "traction", "set": _needs_set(d, key),
            "traction": vector(d.get("traction"), "stress", f"{key}.traction", dim)}


def _pressure(d, key, dim):
    check_keys(d, {"type", "set", "pressure"}, key)
    s = _needs_set(d, key)
    if "pressure" not in d:
        raise SceneError(f"{key}.pressure", "is required (Pa, positive pushes into the body)")
    return {"type": "pressure", "set": s, "pressure": quantity(d["pressure"], "stress", f"{key}.pressure")}


def _displacement(d, key, dim):
    check_keys(d, {"type", "set", "components", "value"}, key)
    s = _needs_set(d, key)
    comps = components(d.get("components"), f"{key}.components", dim)
    val = d.get("value")
    if not isinstance(val, (list, tuple)) or len(val) != len(comps):
        raise SceneError(f"{key}.value", f"expected {len(comps)} value(s) for components {comps}, got {val!r}")
    return {"type": "displacement", "set": s, "components": comps,
            "value": [quantity(v, "length", f"{key}.value[{i}]") for i, v in enumerate(val)]}


#: load type -> normaliser (``edge_traction`` and ``edge_pressure``: the 2D names of the facet loads)
LOAD_TYPES = {"self_weight": _self_weight, "nodal": _nodal, "traction": _traction, "pressure": _pressure,
              "edge_traction": _traction, "edge_pressure": _pressure, "displacement": _displacement}


def _load_kinds(scene):
    return {ld["type"] for st in scene["stages"] if st["type"] == "static" for ld in st["loads"]}


def _describe(kind, text):
    def describe(scene, model):
        if kind not in _load_kinds(scene):
            return []
        return [text.format(facet="edge" if model.dim == 2 else "face")]
    return describe


def _effects():
    from . import Effect

    ref = "consistent nodal forces (Zienkiewicz & Taylor, The Finite Element Method, vol. 1, ch. 6)"
    rows = [("displacement", "prescribed displacements (displacement control)", "load type 'displacement'"),
            ("nodal", "nodal forces", "load type 'nodal'"),
            ("pressure", "{facet} pressures", "load type 'pressure' (or 'edge_pressure')"),
            ("self_weight", "self-weight", "load type 'self_weight' (gravity of [model], or its acceleration)"),
            ("traction", "{facet} tractions", "load type 'traction' (or 'edge_traction')")]
    return [Effect(name, asked, __name__, ref, "tests/test_system.py, tests/test_solid3d.py", _describe(name, text))
            for name, text, asked in rows]


EFFECTS = _effects()
