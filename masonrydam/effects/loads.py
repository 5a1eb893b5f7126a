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
from ..elements.shapes import facet_quadrature, facet_rule
from ..errors import SceneError
from ..mesh.facets import owner_centroids
from ..mesh.sets import facet_set, node_set
from ..units import quantity
from .base import Effect


def self_weight(model, gravity, groups=None) -> np.ndarray:
    """Consistent nodal forces (n_dof,) of the self-weight under ``gravity`` (m/s2, vector), of the element
    groups named in ``groups`` only (None: all)."""
    f = np.zeros(model.n_dof)
    g = np.asarray(gravity, dtype=np.float64)
    for grp in model.cgroups:
        if groups is None or grp.name in groups:
            scatter_vector(grp.body_force(model.coords, g), grp.dofs, f)
    return f


def nodal_force(model, nodes: np.ndarray, force) -> np.ndarray:
    """Force vector (N) applied at every node of ``nodes``."""
    f = np.zeros(model.n_dof)
    force = np.asarray(force, dtype=np.float64)
    for k in range(model.dim):
        f[np.asarray(nodes) * model.dim + k] += force[k]
    return f


def facet_traction(model, facet_type: str, facets: np.ndarray, thickness: float = 1.0, traction=None,
                   pressure: float | None = None, owner_centroids: np.ndarray | None = None) -> np.ndarray:
    """Consistent nodal forces (n_dof,) of a traction on boundary facets: edges in 2D, faces in 3D.

    facets: (n, nfn) node lists in the facet type's order (line2/line3 in 2D; tri3/tri6/quad4/quad8/quad9
    in 3D: :data:`masonrydam.mesh.facets.FACET_TYPES`); thickness: m (2D only); traction: (dim,) Pa, or
    pressure: Pa along the inward normal.
    The inward side is taken from ``owner_centroids`` (n, dim) when given; otherwise the facet's
    own normal is taken as outward (2D: tangent turned -90 degrees, i.e. counter-clockwise
    boundaries; 3D: right-hand rule).
    """
    dim = model.dim
    # Gauss rule exact for the products of shape functions and a linear Jacobian: line 3 points,
    # quadrilateral 3x3, triangle 6 points (degree 4)
    pts, wg = facet_rule(facet_type, 3, triangle="symmetric")
    f = np.zeros(model.n_dof)
    facets = np.asarray(facets, dtype=np.int64)
    fq = facet_quadrature(facet_type, model.coords[facets], pts, wg)
    N = fq.shape_values
    scale = thickness if dim == 2 else 1.0
    for q in range(len(wg)):
        normal = fq.area_normal[:, q]
        jac = fq.jacobian[:, q]
        if pressure is not None:
            outward = normal / jac[:, None]
            if owner_centroids is not None:
                mid = fq.points[:, q]
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
    check_keys(d, {"type", "factor", "acceleration", "groups"}, key)
    out = {"type": "self_weight", "factor": number(d.get("factor", 1.0), f"{key}.factor")}
    if "groups" in d:  # the weight of some groups only: a foundation's rock carries its own weight before the
        # dam is built, so a dam analysis loads the dam alone (the rock may still have mass for shaking)
        gs = d["groups"]
        if isinstance(gs, str):
            gs = [gs]
        if not isinstance(gs, list) or not gs or not all(isinstance(x, str) and x for x in gs):
            raise SceneError(f"{key}.groups", f"expected a list of element group names, got {d['groups']!r}")
        out["groups"] = list(gs)
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


# ---------------------------------------------------------------------------------------------
# what each load type adds to a static stage (masonrydam.effects.base.StaticStageLoads)


def load_vector(context, ld: dict, key: str) -> np.ndarray:
    """Consistent nodal force vector (n_dof,) N of a normalised ``nodal``, ``traction`` or ``pressure`` load
    (``context``: :class:`~masonrydam.effects.base.ModelContext`; ``key``: the load's scene key for errors)."""
    mesh, model = context.mesh, context.model
    if ld["type"] == "nodal":
        return nodal_force(model, node_set(mesh, ld["set"], f"{key}.set"), ld["force"])
    fs = facet_set(mesh, ld["set"], f"{key}.set")
    thickness = context.scene["model"]["thickness"]
    if ld["type"] == "traction":
        return facet_traction(model, fs.type, fs.facets, thickness, traction=ld["traction"])
    return facet_traction(model, fs.type, fs.facets, thickness, pressure=ld["pressure"],
                          owner_centroids=owner_centroids(mesh, fs.type, fs.facets))


def _add_self_weight(context, stage, ld, key):
    """Self-weight: the scene's gravity (one vector for all stages), or a body force in its own direction; of
    all groups, or of the ``groups`` named."""
    groups = ld.get("groups")
    if groups is not None:
        known = [g.name for g in context.model.cgroups]
        for name in groups:
            if name not in known:
                raise SceneError(f"{key}.groups", f"no element group {name!r}; the model's groups: {known}")
    if "acceleration" in ld:
        stage.force += ld["factor"] * self_weight(context.model, ld["acceleration"], groups)
        return
    name = "self_weight" if groups is None else "self_weight:" + ",".join(sorted(groups))
    if name not in stage.carried:
        stage.carried[name] = self_weight(context.model, context.scene["model"]["gravity"], groups)
    stage.force += ld["factor"] * stage.carried[name]


def _add_force(context, stage, ld, key):
    stage.force += load_vector(context, ld, key)


def _add_displacement(context, stage, ld, key):
    """Prescribed displacement increments of a node set (displacement control)."""
    dim = context.mesh.dim
    nodes = node_set(context.mesh, ld["set"], f"{key}.set")
    for c, v in zip(ld["components"], ld["value"]):
        d = nodes * dim + "xyz".index(c)
        if stage.supports[d].any():
            raise SceneError(f"{key}.set", f"prescribes component {c} on nodes that are supports")
        stage.prescribed[d] = True
        stage.increment[d] = v


def _effects():
    ref = "consistent nodal forces (Zienkiewicz & Taylor, The Finite Element Method, vol. 1, ch. 6)"
    rows = [("displacement", "prescribed displacements (displacement control)", "load type 'displacement'"),
            ("nodal", "nodal forces", "load type 'nodal'"),
            ("pressure", "{facet} pressures", "load type 'pressure' (or 'edge_pressure')"),
            ("self_weight", "self-weight", "load type 'self_weight' (gravity of [model], or its acceleration)"),
            ("traction", "{facet} tractions", "load type 'traction' (or 'edge_traction')")]
    builders = {"displacement": {"displacement": _add_displacement}, "nodal": {"nodal": _add_force},
                "pressure": {"pressure": _add_force}, "self_weight": {"self_weight": _add_self_weight},
                "traction": {"traction": _add_force}}
    return [Effect(name, asked, __name__, ref, "tests/system/test_system.py, tests/elements/test_solid3d.py", _describe(name, text),
                   stage_loads=builders[name])
            for name, text, asked in rows]


EFFECTS = _effects()
