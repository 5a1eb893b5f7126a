"""Build the stages of a normalised scene: static stages (their loads through the registry's load types),
modal and dynamic stages (their ground motions and loads in time through the registry's effects).

A stage asks the effects for what its loads add (:func:`masonrydam.effects.stage_load_builders`,
:func:`masonrydam.effects.build_dynamic_stage`); this module names no effect.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..assembly.damping import RayleighDamping
from ..assembly.model import Model
from ..effects import DynamicStageParts, ModelContext, StaticStageLoads, build_dynamic_stage, finish_static_stage
from ..effects import stage_load_builders
from ..errors import SceneError, SceneWarning
from ..mesh.model import Mesh
from ..mesh.sets import node_set
from ..solvers.dynamic import ADAPTIVE_DEFAULT_LEVELS, DynamicSettings, DynamicStage, ModalStage
from ..solvers.linear.direct import DIRECT_SOLVERS
from ..solvers.static.stepping import StaticStage
from .schema import MAX_DYNAMIC_STEPS


def build_stages(scene: dict, mesh: Mesh, model: Model, base_dir: Path | None = None) -> list:
    """Stage objects in scene order: :class:`StaticStage`, :class:`~masonrydam.solvers.dynamic.ModalStage` and
    :class:`~masonrydam.solvers.dynamic.DynamicStage`.

    A dynamic stage keeps the supports and holds the DOFs prescribed by the last static stage at their
    values (they move with the ground); its ground motion is read and scaled here."""
    dim = mesh.dim
    context = ModelContext(scene, base_dir, mesh, model)
    builders = stage_load_builders()
    supports = np.zeros(model.n_dof, dtype=bool)
    for i, s in enumerate(scene["supports"]):
        if s["kind"] != "fixed":
            continue
        nodes = node_set(mesh, s["set"], f"supports[{i}].set")
        for c in s["components"]:
            supports[nodes * dim + "xyz".index(c)] = True
    stages = []
    held = np.zeros(model.n_dof, dtype=bool)
    carried = {}  # what the load types keep from one static stage to the next (e.g. the water level)
    for i, st in enumerate(scene["stages"]):
        if st["type"] == "modal":
            check_mode_count(model, st["modes"], supports | held, f"stages[{i}].modes")
            check_modal_mass(model, scene)
            stages.append(ModalStage(st["name"], st["modes"], st["mass"] == "lumped", supports | held))
            continue
        if st["type"] == "dynamic":
            stages.append(_dynamic_stage(context, st, i, supports | held))
            continue
        loads = StaticStageLoads(i, st, np.zeros(model.n_dof), np.zeros(model.n_dof, dtype=bool),
                                 np.zeros(model.n_dof), supports, carried)
        for j, ld in enumerate(st["loads"]):
            key = f"stages[{i}].loads[{j}]"
            if ld["type"] not in builders:  # a registered load type whose effect gives no stage_loads
                raise SceneError(f"{key}.type", f"load type {ld['type']!r} has no effect that applies it in a static "
                                                f"stage (types applied: {sorted(builders)})")
            builders[ld["type"]](context, loads, ld, key)
        finish_static_stage(context, loads)
        viscous = [g.name for g in model.cgroups if g.viscous]
        if viscous and "duration" not in st:
            raise SceneError(f"stages[{i}].duration", f"blocks {viscous} have Perzyna viscosity: a static stage needs "
                                                      "its duration (s), the time over which its load is applied (set "
                                                      "viscosity = 0 for a rate-independent law)")
        relaxing = [g.name for g in model.igroups if g.relaxation_time > 0]
        if relaxing and "duration" not in st:
            raise SceneError(f"stages[{i}].duration", f"joint sets {relaxing} have a relaxation_time (viscous "
                                                      "regularisation): a static stage needs its duration (s), the "
                                                      "time over which its load is applied")
        if st.get("control") == "dissipation":
            softening = [g for g in model.igroups if g.nonlinear]
            large = [g.name for g in softening if g.kinematics != "small"]
            unfollowed = [g.name for g in softening if not g.joint_law.dissipation_control]
            if unfollowed:
                raise SceneError(f"stages[{i}].control", f"\"dissipation\" cannot follow the laws of joint sets "
                                 f"{unfollowed} (their law does not support dissipation control; use "
                                 "\"arc_length\" or \"opening\")")
            if not softening or large:
                raise SceneError(f"stages[{i}].control", "\"dissipation\" follows the energy dissipated by joints "
                                 "that crack or slip with small displacements: " + (
                                     f"joint sets {large} use large kinematics" if large else
                                     "this model has no composite or Mohr-Coulomb joint set")
                                 + " (use \"arc_length\")")
        stages.append(StaticStage(st["name"], st["steps"], loads.force, loads.prescribed, loads.increment,
                                  supports.copy(), varying=loads.varying,
                                  until_failure=st.get("until_failure", False), duration=st.get("duration", 0.0),
                                  control=st.get("control", "load"), limit_point=st.get("limit_point", "follow")))
        held = loads.prescribed.copy()
    return stages


def _dynamic_stage(context: ModelContext, st: dict, i: int, supports: np.ndarray) -> DynamicStage:
    """A dynamic stage with what the effects add to it (ground motions, loads in time)."""
    model = context.model
    settings = dynamic_settings(st, i, context.scene["solver"]["linear_solver"])
    # a pulse is sampled at the analysis step (dt = "auto": at its smallest, so that the steps,
    # not the samples, decide how sharply its start and end are resolved; an explicit dt = "auto", whose
    # step is chosen by the solver below the critical one, at the output interval / 2^ADAPTIVE_DEFAULT_LEVELS)
    sample_dt = (settings.dt_min if settings.adaptive else
                 st["dt"] / 2 ** ADAPTIVE_DEFAULT_LEVELS if settings.stable_step else st["dt"])
    parts = DynamicStageParts(settings, sample_dt)
    build_dynamic_stage(context, st, i, parts)
    gms = parts.ground_motion
    if st["steps"] is not None:
        duration = st["steps"] * st["dt"]
    elif st["duration"] is not None:
        duration = st["duration"]
    else:
        duration = max(g.duration for g in gms)
    length_key = f"stages[{i}].{'steps' if st['steps'] is not None else 'duration'}"
    fewest = duration / settings.dt  # steps of dt (fixed), or of dt_max (dt = "auto": it takes no fewer)
    if not fewest <= MAX_DYNAMIC_STEPS:
        raise SceneError(length_key, f"a stage of {duration:.4g} s in steps of {settings.dt:.3g} s takes at least "
                                     f"{fewest:.3g} steps, more than {MAX_DYNAMIC_STEPS:.0e}: a unit slipped?")
    warn_long_past_records(duration, gms, length_key)
    v0 = None if st.get("initial_velocity") is None else \
        initial_velocity_field(model, st["initial_velocity"], f"stages[{i}].initial_velocity")
    u0 = None if st.get("initial_displacement") is None else \
        initial_velocity_field(model, st["initial_displacement"], f"stages[{i}].initial_displacement",
                               "displacement", "rotation")
    return DynamicStage(st["name"], duration, supports, gms, settings, st["output"]["stride"], initial_velocity=v0,
                        loads=parts.loads, initial_displacement=u0)


#: a dynamic stage that runs longer than this many times its longest ground motion is warned about (a sliding block
#: after a pulse runs on for 3 times the pulse, free vibration after a record for a fraction of it)
LONG_PAST_RECORD_FACTOR = 10.0


def check_mode_count(model: Model, modes: int, held: np.ndarray, key: str) -> None:
    """A modal stage's ``modes`` against the free DOFs it has (``held`` (n_dof,) bool: the supports and the DOFs the
    last static stage prescribed), before any stage runs (the eigensolver finds at most one fewer)."""
    n_free = int(np.count_nonzero(~held))
    if not 1 <= modes < n_free:
        raise SceneError(key, f"asks for {modes} modes, but the model has {n_free} free DOFs at this stage: "
                              f"ask for 1 to {max(n_free - 1, 1)}")


def check_modal_mass(model: Model, scene: dict) -> None:
    """A modal stage needs mass: refused before any stage where no element group has a density and no reservoir
    adds its water's mass (the modal analysis would refuse it after the static stages)."""
    water = (scene.get("reservoir") or {}).get("dynamic", "none") != "none"
    if not water and not any((np.asarray(g.density) > 0).any() for g in model.cgroups):
        raise SceneError("materials", "a modal stage needs mass: give the materials their density (kg/m3); "
                                      "massless parts are allowed beside parts with mass")


def warn_long_past_records(duration: float, ground_motions: list, key: str) -> None:
    """A :class:`~masonrydam.errors.SceneWarning` where a dynamic stage of ``duration`` (s) runs on for more than
    :data:`LONG_PAST_RECORD_FACTOR` times its longest ground motion (free vibration after a record is fine, a
    stage a thousand times as long is a slip: it steps on at rest); none without ground motions."""
    if not ground_motions:
        return
    end = max(g.duration for g in ground_motions)
    if end > 0 and duration > LONG_PAST_RECORD_FACTOR * end:
        warnings.warn(f"scene key '{key}': the stage runs {duration:.4g} s, but its ground motion ends at {end:.4g} s; "
                      f"after that it steps on at rest (free vibration). Set the stage's duration near the record's "
                      f"end unless that is meant", SceneWarning, stacklevel=2)


def dynamic_settings(st: dict, index: int, linear_solver: str = "auto"):
    """DynamicSettings of a normalised dynamic stage; ``linear_solver``: the scene's ``solver.linear_solver``
    (an iterative choice applies to the static stages; dynamic stages use a direct solver)."""
    if linear_solver not in DIRECT_SOLVERS:
        linear_solver = "auto"

    d = st["damping"]
    damping = None
    local_ratio = 0.0
    if d is not None and d.get("model") == "local":
        local_ratio = d["ratio"]
    elif d is not None:
        if "ratio" in d:
            damping = RayleighDamping.from_frequencies(d["frequencies"][0], d["frequencies"][1], d["ratio"],
                                                       d["exclude_joints"])
        else:
            damping = RayleighDamping(d["alpha"], d["beta"], d["exclude_joints"])
    return DynamicSettings(integrator=st["integrator"], dt=st["dt"], alpha=st["alpha"], rho_inf=st["rho_inf"],
                           max_iterations=st["max_iterations"], force_tolerance=st["force_tolerance"],
                           energy_tolerance=st["energy_tolerance"], max_substeps=st["max_substeps"], mass=st["mass"],
                           damping=damping, linear_solver=linear_solver, low_rank_max=st["low_rank_max"],
                           joint_space=st["joint_space"], adaptive=st["adaptive"], tolerance=st["tolerance"],
                           dt_min=st["dt_min"], local_damping=local_ratio,
                           stable_step=st.get("stable_step", False), key=f"stages[{index}].")


def initial_velocity_field(model: Model, items: list, key: str, translation="velocity",
                           rotation="angular_velocity") -> np.ndarray:
    """(n_dof,) m/s: the initial velocities of a dynamic stage (normalised ``initial_velocity`` items) at
    the nodes of their element groups, NaN elsewhere; a rotation is ``v = w x (x - c)`` (small-rotation
    rigid motion). With ``translation="displacement", rotation="rotation"`` the initial displacements (m) of
    ``initial_displacement`` items, ``u = theta x (x - c)`` for a (small) rotation."""
    dim = model.dim
    v = np.full(model.n_dof, np.nan)
    names = sorted({g.name for g in model.cgroups})
    for j, it in enumerate(items):
        nodes = []
        for name in it["groups"]:
            found = [g for g in model.cgroups if g.name == name]
            if not found:
                raise SceneError(f"{key}.groups" if len(items) == 1 else f"{key}[{j}].groups",
                                 f"no element group '{name}' (groups: {names})")
            nodes += [np.unique(g.conn) for g in found]
        nodes = np.unique(np.concatenate(nodes))
        if translation in it:
            vel = np.tile(np.asarray(it[translation], dtype=float), (len(nodes), 1))
        else:
            r = model.coords[nodes] - np.asarray(it["rotation_center"], dtype=float)
            w = it[rotation]
            vel = (np.stack([-w * r[:, 1], w * r[:, 0]], axis=1) if dim == 2 else
                   np.cross(np.asarray(w, dtype=float), r))
        v[(nodes[:, None] * dim + np.arange(dim)).ravel()] = vel.ravel()
    return v
