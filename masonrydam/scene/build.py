"""Build the model of a normalised scene: mesh, element groups and ties (the stages: :mod:`.stages`).

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
from ..errors import MasonrydamError, SceneError
from ..materials.continuum_laws import ELASTIC_LAW, continuum_law
from ..materials.joint_laws import joint_law, joint_laws
from ..materials.elastic import elasticity_matrix
from ..effects import simulated
from ..elements.continuum_plastic import law_parameter_table
from ..mesh.io import read_mesh
from ..mesh.model import Mesh
from ..mesh.sets import node_set

def build_mesh(scene: dict, base_dir: Path) -> Mesh:
    spec = scene["mesh"]
    if "generator" in spec:
        # (generators imports masonrydam, whose __init__ imports this module: a top-level import would be a cycle)
        from generators import GENERATORS

        try:
            return GENERATORS[spec["generator"]](**spec["parameters"])
        except MasonrydamError:
            raise
        except (MemoryError, OverflowError, ValueError) as exc:  # numbers the generator could not mesh
            raise SceneError("mesh.parameters", f"generator '{spec['generator']}' cannot mesh these parameters "
                                                f"({type(exc).__name__}: {exc}): a size far too small or too large?"
                             ) from exc
    path = Path(spec["file"])
    if not path.is_absolute():
        path = base_dir / path
    return read_mesh(path, spec["joints"], scene["model"]["dimension"])


def joint_param_vector(spec: dict, key: str = "joints") -> np.ndarray:
    """Parameter row of the joint law of a normalised joint spec (``JointLaw.parameters`` of
    :mod:`masonrydam.materials.joint_laws`); SceneError naming ``key`` for inadmissible values."""
    try:
        return np.asarray(joint_law(spec["law"]).parameters(spec), dtype=np.float64)
    except ValueError as exc:
        raise SceneError(key, str(exc)) from None


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
    kinematics = scene["model"].get("kinematics", "small")
    cgroups = []
    for b in mesh.blocks:
        m = mats[b.name]
        D = elasticity_matrix(m["youngs_modulus"], m["poisson_ratio"], hyp)[None, :, :]
        ne = len(b.cells)
        law = m.get("law", ELASTIC_LAW)
        if kinematics == "large" and continuum_law(law).plastic:
            raise SceneError(f"materials.{b.name}.law", f"\"{law}\" is a small-strain law: with [model] kinematics = "
                                                        "\"large\" the blocks must be elastic (St. Venant-Kirchhoff); "
                                                        "use kinematics = \"small\" for elasto-plastic blocks")
        law_params = law_parameter_table(m, b.name, dim, hyp, mesh.points, b.cells, b.type)
        try:
            cgroups.append(ContinuumGroup(b.name, b.type, b.cells, DofMap.node_dofs(b.cells, dim),
                                          np.ascontiguousarray(D), np.zeros(ne, dtype=np.int64), np.full(ne, t),
                                          np.full(ne, m["density"]), law=law, law_params=law_params,
                                          kinematics=kinematics, integration=m.get("integration", "full")))
        except ValueError as exc:
            raise SceneError(f"materials.{b.name}.integration", str(exc)) from None
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
        if "frame" in spec and kinematics != "large":
            raise SceneError(f"joints.{j.name}.frame", "chooses the turning frame of large kinematics; with [model] "
                                                       "kinematics = \"small\" the frame is the reference one "
                                                       "(remove it, or set kinematics = \"large\")")
        scheme = spec["integration"]
        if j.type == "interface_quad8" and scheme == "lumped" and not spec.get("integration_given", True):
            scheme = "lobatto"  # 3x3 Newton-Cotes: the lumped corner weights of quad8 are negative
        params = joint_param_vector(spec, f"joints.{j.name}")
        if kinematics == "large" and not joint_law(spec["law"]).large_kinematics:
            raise SceneError(f"joints.{j.name}.law", f"\"{spec['law']}\" has no large-displacement interface kernel: "
                                                     "with [model] kinematics = \"large\" use a built-in joint law, "
                                                     "or kinematics = \"small\"")
        try:
            igroups.append(InterfaceGroup(j.name, j.type, j.cells, mesh.points, dim, params,
                                          np.full(len(j.cells), t), spec["law"], scheme, spec.get("points"),
                                          kinematics=kinematics, frame=spec.get("frame", "mid_surface")))
        except ValueError as exc:
            raise SceneError(f"joints.{j.name}.integration", str(exc)) from None
    model = Model(mesh.points, cgroups, igroups)
    for i, s in enumerate(scene["supports"]):
        if s["kind"] == "tied":  # the set moves as one in these components (a loading beam kept level)
            nodes = node_set(mesh, s["set"], f"supports[{i}].set")
            if len(np.unique(nodes)) < 2:
                raise SceneError(f"supports[{i}].set", f"set '{s['set']}' has {len(np.unique(nodes))} node: a tie "
                                                       "needs at least two")
            try:
                model.add_tie(nodes, ["xyz".index(c) for c in s["components"]])
            except ValueError as exc:
                raise SceneError(f"supports[{i}]", str(exc)) from None
    return model


def effects(scene: dict, model: Model) -> list[str]:
    """Human-readable list of what the run simulates."""
    m = scene["model"]
    groups = ', '.join(sorted({g.name for g in model.cgroups if not g.plastic}))
    out = []
    kind = "elastic (St. Venant-Kirchhoff)" if model.large else "linear elastic"
    if groups:
        if model.dim == 2:
            out = [f"{m['hypothesis'].replace('_', ' ')} {kind} continuum ({groups}; thickness {m['thickness']:g} m)"]
        else:
            out = [f"3D {kind} continuum ({groups})"]
    for law in joint_laws():
        sets = sorted({g.name for g in model.igroups if g.joint_law is law})
        if sets:
            out.append(f"{law.summary}: " + ", ".join(sets))
    relaxing = [f"{g.name} {g.relaxation_time * 1e3:g} ms" for g in model.igroups if g.relaxation_time > 0]
    if relaxing:
        out.append("viscous regularisation of the composite joints (Duvaut-Lions; an approximation of the "
                   "inviscid law, to be converged in the relaxation time): " + ", ".join(relaxing))
    tied = [f"{s['set']} ({', '.join(s['components'])})" for s in scene["supports"] if s["kind"] == "tied"]
    if tied:
        out.append("tied supports (the set moves as one in these components): " + ", ".join(tied))
    controls = sorted({st.get("control", "load") for st in scene["stages"] if st["type"] == "static"} - {"load"})
    if controls:
        out.append("static path following: " + ", ".join(
            {"arc_length": "arc-length control (Crisfield's cylindrical)",
             "opening": "indirect displacement control on the opening of the cracking joints (de Borst 1987)",
             "dissipation": "dissipation-based arc-length control on the joints' plastic work (Gutierrez 2004; "
                            "Verhoosel et al. 2009)"}[c]
            for c in controls))
    return out + simulated(scene, model)
