"""Build a model from a normalised scene: mesh, element groups, supports and stage load vectors.

Only what the scene asks for is created: no mass, no damping, no joint state for linear joints
(their state never changes), no load vector for a load type that is absent. :func:`effects`
lists what is simulated; it goes into the run summary and the dataset attributes.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..assembly.dofmap import DofMap
from ..assembly.groups import ContinuumGroup, InterfaceGroup
from ..assembly.model import Model
from ..errors import SceneError
from ..materials import mohr_coulomb as mc
from ..materials.elastic import elasticity_matrix
from ..mesh.io import read_mesh
from ..mesh.model import Mesh
from ..solvers.static import StaticStage

#: parameters of a joint that never slips or opens (law = "linear")
_UNBREAKABLE = 1e300


def build_mesh(scene: dict, base_dir: Path) -> Mesh:
    spec = scene["mesh"]
    if "generator" in spec:
        from generators import GENERATORS

        return GENERATORS[spec["generator"]](**spec["parameters"])
    path = Path(spec["file"])
    if not path.is_absolute():
        path = base_dir / path
    return read_mesh(path, spec["joints"], scene["model"]["dimension"])


def joint_param_vector(spec: dict) -> np.ndarray:
    """Parameter vector of :func:`mohr_coulomb_update` for a normalised joint spec."""
    if spec["law"] == "linear":
        return mc.joint_params(spec["normal_stiffness"], spec["shear_stiffness"], cohesion=_UNBREAKABLE,
                               friction_angle_deg=0.0, tensile_strength=_UNBREAKABLE)
    return mc.joint_params(spec["normal_stiffness"], spec["shear_stiffness"], spec["cohesion"], spec["friction_angle"],
                           spec["tensile_strength"], spec["residual_shear_stiffness"])


def build_model(scene: dict, mesh: Mesh) -> Model:
    dim = mesh.dim
    hyp = scene["model"]["hypothesis"]
    t = scene["model"]["thickness"]
    mats = scene["materials"]
    mesh_groups = mesh.group_names()
    for name in mesh_groups:
        if name not in mats:
            raise SceneError("materials", f"element group '{name}' of the mesh has no material; "
                                          f"add [materials.{name}] (mesh groups: {mesh_groups})")
    for name in mats:
        if name not in mesh_groups:
            raise SceneError(f"materials.{name}", f"the mesh has no element group '{name}' (mesh groups: {mesh_groups})")
    cgroups = []
    for b in mesh.blocks:
        m = mats[b.name]
        D = elasticity_matrix(m["youngs_modulus"], m["poisson_ratio"], hyp)[None, :, :]
        ne = len(b.cells)
        cgroups.append(ContinuumGroup(b.name, b.type, b.cells, DofMap.node_dofs(b.cells, dim), np.ascontiguousarray(D),
                                      np.zeros(ne, dtype=np.int64), np.full(ne, t), np.full(ne, m["density"])))
    joint_specs = scene["joints"]
    mesh_joints = mesh.joint_set_names()
    for name in mesh_joints:
        if name not in joint_specs:
            raise SceneError("joints", f"joint set '{name}' of the mesh has no parameters; add [joints.{name}] "
                                       f"(mesh joint sets: {mesh_joints})")
    for name in joint_specs:
        if name not in mesh_joints:
            raise SceneError(f"joints.{name}", f"the mesh has no joint set '{name}' (mesh joint sets: {mesh_joints})")
    igroups = []
    for j in mesh.joints:
        spec = joint_specs[j.name]
        scheme = spec["integration"]
        if j.type == "interface_quad8" and scheme == "lumped" and not spec.get("integration_given", True):
            scheme = "lobatto"  # 3x3 Newton-Cotes: the lumped corner weights of quad8 are negative
        try:
            igroups.append(InterfaceGroup(j.name, j.type, j.cells, mesh.points, dim, joint_param_vector(spec),
                                          np.full(len(j.cells), t), spec["law"], scheme, spec.get("points")))
        except ValueError as exc:
            raise SceneError(f"joints.{j.name}.integration", str(exc)) from None
    return Model(mesh.points, cgroups, igroups)


def _node_set(mesh: Mesh, name: str, key: str) -> np.ndarray:
    if name in mesh.node_sets:
        return mesh.node_sets[name]
    if name in mesh.facet_sets:
        return np.unique(mesh.facet_sets[name].facets)
    raise SceneError(key, f"no node set '{name}' in the mesh (node sets: {sorted(mesh.node_sets)}, "
                          f"facet sets: {sorted(mesh.facet_sets)})")


def _owner_centroids(mesh: Mesh, facets: np.ndarray) -> np.ndarray:
    """Centroid of the element owning each boundary facet (to orient pressures inward), (n, dim).

    Facets that belong to no element keep the origin as "centroid" (their own normal is used)."""
    from ..mesh.interfaces import _FacetTable

    facets = np.asarray(facets, dtype=np.int64)
    table = _FacetTable(mesh)
    nc = 2 if mesh.dim == 2 else {3: 3, 6: 3, 4: 4, 8: 4}[facets.shape[1]]
    k = table.lookup(_FacetTable.keys(facets, np.full(len(facets), nc)))
    cents = np.vstack([mesh.points[b.cells].mean(axis=1) for b in mesh.blocks])
    out = np.zeros((len(facets), mesh.dim))
    ok = k >= 0
    out[ok] = cents[table.elem[table.first[k[ok]]]]
    return out


def build_stages(scene: dict, mesh: Mesh, model: Model) -> list[StaticStage]:
    from .. import loads as L

    dim = mesh.dim
    supports = np.zeros(model.n_dof, dtype=bool)
    for i, s in enumerate(scene["supports"]):
        nodes = _node_set(mesh, s["set"], f"supports[{i}].set")
        for c in s["components"]:
            supports[nodes * dim + "xyz".index(c)] = True
    stages = []
    weight = None
    for i, st in enumerate(scene["stages"]):
        force = np.zeros(model.n_dof)
        presc = np.zeros(model.n_dof, dtype=bool)
        incr = np.zeros(model.n_dof)
        for j, ld in enumerate(st["loads"]):
            key = f"stages[{i}].loads[{j}]"
            if ld["type"] == "self_weight":
                if weight is None:
                    weight = L.self_weight(model, scene["model"]["gravity"])
                force += ld["factor"] * weight
            elif ld["type"] == "nodal":
                force += L.nodal_force(model, _node_set(mesh, ld["set"], f"{key}.set"), ld["force"])
            elif ld["type"] in ("traction", "pressure"):
                if ld["set"] not in mesh.facet_sets:
                    what = "edge" if dim == 2 else "face"
                    raise SceneError(f"{key}.set", f"no facet ({what}) set '{ld['set']}' in the mesh "
                                                   f"(facet sets: {sorted(mesh.facet_sets)})")
                fs = mesh.facet_sets[ld["set"]]
                if ld["type"] == "traction":
                    force += L.facet_traction(model, fs.type, fs.facets, scene["model"]["thickness"], traction=ld["traction"])
                else:
                    force += L.facet_traction(model, fs.type, fs.facets, scene["model"]["thickness"],
                                              pressure=ld["pressure"], owner_centroids=_owner_centroids(mesh, fs.facets))
            else:  # displacement
                nodes = _node_set(mesh, ld["set"], f"{key}.set")
                for c, v in zip(ld["components"], ld["value"]):
                    d = nodes * dim + "xyz".index(c)
                    if supports[d].any():
                        raise SceneError(f"{key}.set", f"prescribes component {c} on nodes that are supports")
                    presc[d] = True
                    incr[d] = v
        stages.append(StaticStage(st["name"], st["steps"], force, presc, incr, supports.copy()))
    return stages


def effects(scene: dict, model: Model) -> list[str]:
    """Human-readable list of what the run simulates."""
    m = scene["model"]
    groups = ', '.join(sorted({g.name for g in model.cgroups}))
    if model.dim == 2:
        out = [f"{m['hypothesis'].replace('_', ' ')} linear elastic continuum ({groups}; thickness {m['thickness']:g} m)"]
    else:
        out = [f"3D linear elastic continuum ({groups})"]
    mc_sets = [g.name for g in model.igroups if g.law == "mohr_coulomb"]
    lin_sets = [g.name for g in model.igroups if g.law == "linear"]
    if mc_sets:
        out.append("Mohr-Coulomb joints with slip, opening and re-contact (seed sec. 3.4): " + ", ".join(sorted(set(mc_sets))))
    if lin_sets:
        out.append("linear elastic joints: " + ", ".join(sorted(set(lin_sets))))
    kinds = {ld["type"] for st in scene["stages"] for ld in st["loads"]}
    facet = "edge" if model.dim == 2 else "face"
    names = {"self_weight": "self-weight", "nodal": "nodal forces", "traction": f"{facet} tractions",
             "pressure": f"{facet} pressures", "displacement": "prescribed displacements (displacement control)"}
    out += [names[k] for k in sorted(kinds)]
    out.append("static analysis (no inertia, no damping)")
    return out
