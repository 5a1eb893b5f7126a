"""The physical effects a scene can ask for, one module each, and their registry.

Each effect module holds its part of the scene schema (a section such as ``[reservoir]`` or a load
type such as ``{ type = "self_weight" }``), what it adds to the model (load vectors, pore pressures,
...), the reference it follows and the words that go into the run's list of simulated effects. A
scene that does not name an effect pays nothing for it: nothing of it is assembled or allocated,
and the result attribute ``simulated_effects`` lists only what the scene asked for.

Adding an effect: write its module (schema fragment, model contribution, :class:`Effect` entries
with reference and test file), add the module to :data:`_MODULES`. The scene schema takes the
sections and load types from here (:data:`SECTIONS`, :data:`LOAD_TYPES`); nothing in the solvers
changes unless the effect needs a new kind of term.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Effect:
    """One physical effect.

    name: registry key; asked_by: how a scene asks for it (the keys); module: where it lives;
    reference: the source of its formulas; tests: the test file that checks it against closed forms
    or published data; describe(scene, model) -> list of lines for ``simulated_effects`` (empty when
    the normalised scene does not ask for it)."""

    name: str
    asked_by: str
    module: str
    reference: str
    tests: str
    describe: Callable[[dict, object], list]


def _modules():
    from . import (dynamic_loads, dynamic_water, foundation, ground_motion, large_kinematics, loads, plasticity,
                   reservoir, uplift)

    return (plasticity, large_kinematics, loads, reservoir, uplift, ground_motion, dynamic_loads, dynamic_water,
            foundation)


def registry() -> dict[str, Effect]:
    """name -> :class:`Effect`, in the order the effects are listed in a run's summary."""
    out = {}
    for mod in _modules():
        for e in mod.EFFECTS:
            if e.name in out:
                raise RuntimeError(f"effect '{e.name}' registered twice ({out[e.name].module}, {e.module})")
            out[e.name] = e
    return out


def sections() -> dict[str, Callable]:
    """Top-level scene sections owned by effects: section name -> normaliser ``(raw, model_section) -> dict``."""
    out = {}
    for mod in _modules():
        out.update(getattr(mod, "SECTIONS", {}))
    return out


def load_types() -> dict[str, Callable]:
    """Static load types: ``type`` -> normaliser ``(raw, key, dim) -> dict``."""
    out = {}
    for mod in _modules():
        out.update(getattr(mod, "LOAD_TYPES", {}))
    return out


def simulated(scene: dict, model) -> list[str]:
    """The lines of every effect the normalised ``scene`` asks for (registry order)."""
    lines = []
    for e in registry().values():
        lines += e.describe(scene, model)
    return lines
