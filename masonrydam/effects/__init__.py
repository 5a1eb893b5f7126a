"""The physical effects a scene can ask for, one module (or package) each, and their registry.

Each effect holds its part of the scene schema (a section such as ``[reservoir]`` or a load type such as
``{ type = "self_weight" }``), what it adds to a run (:class:`~masonrydam.effects.base.EffectRun`: loads,
mass, dashpots, forces in time, coupled fields, result variables, the diagnosis of a failed stage), the
reference it follows and the words that go into the run's list of simulated effects. A scene that does
not name an effect pays nothing for it: nothing of it is assembled or allocated, and the result attribute
``simulated_effects`` lists only what the scene asked for.

Adding an effect: write its module with :class:`Effect` entries (schema fragment, ``describe``,
``activate`` returning an :class:`~masonrydam.effects.base.EffectRun`, reference, test file) in a list
``EFFECTS`` and add the module to :func:`_modules`; or, from outside the package, :func:`register` the
entries. Nothing in ``scene/``, ``results/`` or ``solvers/`` changes (docs/architecture.md).
"""
from __future__ import annotations

from typing import Callable

from ..errors import SceneError
from .base import DynamicStageParts, Effect, EffectRun, ModelContext, RunContext, StaticStageLoads, add_force

__all__ = ["DynamicStageParts", "Effect", "EffectRun", "ModelContext", "RunContext", "StaticStageLoads", "activate",
           "add_force", "check_scene", "effect_reference", "effect_sections_meaning", "load_types",
           "normalize_dynamic_load", "register", "registry", "sections", "simulated", "unregister"]

#: effects registered from outside the package (:func:`register`), after the built-in ones
_REGISTERED: list[Effect] = []


def _modules():
    # the effect modules (obspy, the reservoir) at the first registry look-up: keeps 'import masonrydam' 0.15 s shorter
    from . import dynamic_loads, foundation, ground_motion, large_kinematics, loads, plasticity, reservoir

    # (the reservoir is one package; its entries keep their places in the summary's order)
    return (plasticity, large_kinematics, loads, reservoir.water, reservoir.uplift, ground_motion, dynamic_loads,
            reservoir.moving, foundation)


def register(effect: Effect) -> None:
    """Add ``effect`` to the registry (after the built-in effects, in the order of registration); its
    ``sections`` and ``load_types`` join the scene schema. A name already registered is an error."""
    if effect.name in registry():
        raise ValueError(f"effect '{effect.name}' is already registered")
    _REGISTERED.append(effect)


def unregister(name: str) -> None:
    """Remove an effect added with :func:`register` (a built-in effect cannot be removed)."""
    for k, e in enumerate(_REGISTERED):
        if e.name == name:
            del _REGISTERED[k]
            return
    raise ValueError(f"no effect '{name}' was registered with register()")


def registry() -> dict[str, Effect]:
    """name -> :class:`Effect`, in the order the effects are listed in a run's summary."""
    out = {}
    entries = [e for mod in _modules() for e in mod.EFFECTS] + list(_REGISTERED)
    for e in entries:
        if e.name in out:
            raise RuntimeError(f"effect '{e.name}' registered twice ({out[e.name].module}, {e.module})")
        out[e.name] = e
    return out


def sections() -> dict[str, Callable]:
    """Top-level scene sections owned by effects: section name -> normaliser ``(raw, model_section) -> dict``."""
    out = {}
    for mod in _modules():
        out.update(getattr(mod, "SECTIONS", {}))
    for e in registry().values():
        out.update(e.sections)
    return out


def load_types() -> dict[str, Callable]:
    """Static load types: ``type`` -> normaliser ``(raw, key, dim) -> dict``."""
    out = {}
    for mod in _modules():
        out.update(getattr(mod, "LOAD_TYPES", {}))
    for e in registry().values():
        out.update(e.load_types)
    return out


def stage_load_builders() -> dict[str, Callable]:
    """Static load types: ``type`` -> ``(model_context, stage_loads, load, key) -> None`` (what the load adds to a
    :class:`~masonrydam.effects.base.StaticStageLoads`)."""
    out = {}
    for e in registry().values():
        out.update(e.stage_loads)
    return out


def _hooks(field_name: str) -> list[Callable]:
    """The given hooks ``field_name`` (a callable field of :class:`Effect`) of the registered effects, in
    registry order."""
    return [hook for hook in (getattr(e, field_name) for e in registry().values()) if hook is not None]


def finish_static_stage(context: ModelContext, stage_loads: StaticStageLoads) -> None:
    """Let every effect finish a static stage's loads (:attr:`Effect.finish_stage`), in registry order."""
    for hook in _hooks("finish_stage"):
        hook(context, stage_loads)


def build_dynamic_stage(context: ModelContext, spec: dict, index: int, parts: DynamicStageParts) -> None:
    """Let every effect add its part to a dynamic stage being built (:attr:`Effect.dynamic_stage`): ground
    motions, forces in time."""
    for hook in _hooks("dynamic_stage"):
        hook(context, spec, index, parts)


def normalize_dynamic_load(raw, key: str, dim: int) -> dict:
    """One entry of a dynamic stage's ``loads``, normalised by the effect that owns them
    (:attr:`Effect.dynamic_loads`)."""
    owners = _hooks("dynamic_loads")
    if not owners:
        raise SceneError(key, "no registered effect takes loads in dynamic stages")
    return owners[0](raw, key, dim)


def effect_reference(place: str) -> tuple:
    """The scene-reference tables (:class:`~masonrydam.keys.Section`) the effects place at ``place``
    (:attr:`Effect.scene_keys_place`), in registry order."""
    return tuple(section for e in registry().values() if e.scene_keys_place == place for section in e.scene_keys)


def effect_sections_meaning() -> dict:
    """Top-level section name -> one line, for every section an effect owns (registry order)."""
    out = {}
    for e in registry().values():
        out.update(e.section_meanings)
    return out


def check_scene(stages: list, sections: dict) -> None:
    """Every effect's checks across the normalised scene (:attr:`Effect.check_scene`), in registry order."""
    for hook in _hooks("check_scene"):
        hook(stages, sections)


def simulated(scene: dict, model) -> list[str]:
    """The lines of every effect the normalised ``scene`` asks for (registry order)."""
    lines = []
    for e in registry().values():
        lines += e.describe(scene, model)
    return lines


def activate(context: RunContext) -> list[EffectRun]:
    """The :class:`~masonrydam.effects.base.EffectRun` of every effect the run's scene asks for, in registry
    order (an effect whose ``activate`` gives None adds nothing to the run)."""
    out = []
    for e in registry().values():
        run = None if e.activate is None else e.activate(context)
        if run is not None:
            run.name = e.name
            out.append(run)
    return out
