"""The effect contract: what one physical effect gives the scene language and adds to a run.

An effect is a registry entry (:class:`Effect`) and, for a run whose scene asks for it, an
:class:`EffectRun`: the object through which the effect adds its part to the model and the result. The
run (:mod:`masonrydam.scene.run`) knows no effect by name: it asks every registered effect to
:meth:`Effect.activate` itself on a :class:`RunContext`, and then calls the hooks of the active ones in
registry order. A scene that does not name an effect gets no :class:`EffectRun` from it, so nothing of it
is assembled, allocated or stepped.

The hooks, each with a default that adds nothing:

=====================================  ============================================================
hook                                   what the effect adds
=====================================  ============================================================
:meth:`EffectRun.attrs`                result-file attributes (provenance, conventions)
:meth:`EffectRun.result_variables`     result dimensions and variables (:mod:`masonrydam.results.variables`)
:meth:`EffectRun.static_values`        the values of its step variables at a static step
:meth:`EffectRun.dynamic_values`       the values of its step variables at a dynamic step
:meth:`EffectRun.after_static`         model changes once the static stages are solved (coupled DOFs)
:meth:`EffectRun.mass_terms`           added mass, extra influence vectors, massless element groups
:meth:`EffectRun.carried_static_force` the constant loads the dynamic stages keep from the static state
:meth:`EffectRun.state_force`          forces that follow the committed joint states during shaking
:meth:`EffectRun.dynamic_terms`        dashpots, forces in time, coupled fields of a dynamic stage
:meth:`EffectRun.modal_analysis`       a modal analysis of its own (coupled fluid-structure modes)
:meth:`EffectRun.summary_lines`        its lines in the printed summary of a run
:meth:`EffectRun.diagnosis`            what the effect says about a stage that found no equilibrium
=====================================  ============================================================

Static loads enter through load types (:attr:`Effect.load_types` for the scene schema and
:attr:`Effect.stage_loads` for what a load adds to a static stage, :class:`StaticStageLoads`); dynamic
stages get their forces in time through :meth:`EffectRun.dynamic_terms`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np


@dataclass
class ModelContext:
    """What an effect may read while the stages are built.

    scene: the normalised scene (dict); base_dir: the folder relative paths of the scene are taken from;
    mesh: the :class:`~masonrydam.mesh.model.Mesh`; model: the :class:`~masonrydam.assembly.model.Model`."""

    scene: dict
    base_dir: object
    mesh: object
    model: object


@dataclass
class RunContext(ModelContext):
    """What an effect may read when it activates for a run: the :class:`ModelContext` and stages: every
    stage object in scene order; static_stages / dynamic_stages: those of each kind; modal_stage: the
    modal stage or None; recorded_joint_groups: the joint groups whose points the result records (in
    result order)."""

    stages: list = field(default_factory=list)
    static_stages: list = field(default_factory=list)
    dynamic_stages: list = field(default_factory=list)
    modal_stage: object = None
    recorded_joint_groups: list = field(default_factory=list)

    @property
    def has_dynamics(self) -> bool:
        """True when the run has a dynamic or a modal stage (inertia matters)."""
        return bool(self.dynamic_stages) or self.modal_stage is not None


class EffectRun:
    """What one effect adds to one run. Subclasses override the hooks they need; every default adds
    nothing. Shapes: ``n_dof = model.n_nodes * dim`` (DOF ``node * dim + component``); forces in N,
    masses in kg, damping in N s/m."""

    #: registry name of the effect (set by :meth:`Effect.activate`)
    name: str = ""

    def attrs(self) -> dict:
        """Global attributes of the result file (str, int, float or JSON-able values)."""
        return {}

    def result_variables(self) -> list:
        """:class:`~masonrydam.results.variables.ResultDimension` and
        :class:`~masonrydam.results.variables.ResultVariable` items, created in this order."""
        return []

    def static_values(self, stage, load_factor: float) -> dict:
        """Values of this effect's step variables at a converged static step of ``stage`` (name -> array)."""
        return {}

    def dynamic_values(self, record: dict, mass) -> dict:
        """Values of this effect's step variables at a recorded dynamic step. ``record``: the solver's step
        record (``u``, ``v``, ``a``, ``a_abs`` (n_dof,), ``bottom_acceleration`` (dim,), ``fluid``, ``t``);
        ``mass``: the stage's :class:`~masonrydam.assembly.mass.MassMatrix`."""
        return {}

    def after_static(self, model, u: np.ndarray) -> None:
        """Once the static stages are solved (state ``u`` (n_dof,) m), before modal and dynamic stages."""

    def mass_terms(self, lumped: bool) -> dict:
        """What the effect adds to the mass matrix of the dynamic stages and of a modal stage without a
        :meth:`modal_analysis` of its own: ``added`` (n_dof, n_dof) sparse kg, ``extra_influence``
        (n_dof, dim) N s2/m, ``massless`` (names of element groups without mass); any of them may be absent."""
        return {}

    def carried_static_force(self, model, u: np.ndarray, f_static: np.ndarray) -> None:
        """Change ``f_static`` (n_dof,) N, the constant load of the dynamic stages (the static stages'
        loads at their end), in place: add the effect's static loads, or replace entries."""

    def state_force(self):
        """A function ``() -> (n_dof,) N`` of forces that follow the committed joint states during the
        dynamic stages (relative to the static state), or None."""
        return None

    def dynamic_terms(self, stage, terms) -> None:
        """Add the effect's linear terms to the :class:`~masonrydam.solvers.dynamic.DynamicTerms` ``terms``
        of the dynamic ``stage`` (dashpots, ``force(tau)`` added with :func:`add_force`, coupled fluid,
        support excitation, bottom acceleration) and change the stage's supports where it must."""

    def modal_analysis(self, model, stage, u: np.ndarray, mass):
        """A modal analysis of the effect's own (a coupled fluid-structure problem), or None for the plain
        one. ``mass``: a function () -> the structure's :class:`~masonrydam.assembly.mass.MassMatrix` without
        this effect's terms (built only when called)."""
        return None

    def summary_lines(self, ds) -> list[str]:
        """Lines of the run's printed summary from the result dataset ``ds`` (each ``"name       : text"``)."""
        return []

    def diagnosis(self) -> tuple[str, str] | None:
        """``(kind, text)``: what the effect says about the last converged state of a stage that found no
        equilibrium (the limit of a ``until_failure`` stage, a convergence failure), or None."""
        return None


def add_force(terms, force: Callable[[float], np.ndarray]) -> None:
    """Add ``force(tau)`` (n_dof,) N to the forces in time of the dynamic ``terms``."""
    before = terms.force
    terms.force = force if before is None else (lambda tau: before(tau) + force(tau))


@dataclass
class StaticStageLoads:
    """The loads of one static stage as its load types build them (:attr:`Effect.stage_loads`).

    force: (n_dof,) N proportional to the load factor; prescribed: (n_dof,) bool DOFs whose displacement
    the stage prescribes, with the increment (n_dof,) m in ``increment``; supports: (n_dof,) bool fixed
    DOFs (read only); varying: loads not proportional to the load factor (e.g. rising water), or None;
    index: the stage's index in the scene; spec: its normalised scene entry; carried: a dict the effects keep
    from one static stage to the next (keys chosen by each effect)."""

    index: int
    spec: dict
    force: np.ndarray
    prescribed: np.ndarray
    increment: np.ndarray
    supports: np.ndarray
    carried: dict
    varying: object = None


@dataclass
class DynamicStageParts:
    """What effects add to a dynamic stage while it is built (:attr:`Effect.dynamic_stage`).

    settings: the stage's :class:`~masonrydam.solvers.dynamic.DynamicSettings` (read only); sample_dt: the
    time step (s) at which a motion defined by the scene (a pulse) is sampled; ground_motion: the
    :class:`~masonrydam.solvers.dynamic.GroundMotion` of each component; loads: ``force(t)`` (n_dof,) N of
    the loads given in time, or None."""

    settings: object
    sample_dt: float
    ground_motion: list = field(default_factory=list)
    loads: Callable | None = None


@dataclass(frozen=True)
class Effect:
    """One physical effect in the registry.

    name: registry key; asked_by: how a scene asks for it (the keys); module: where it lives;
    reference: the source of its formulas; tests: the test file that checks it against closed forms or
    published data; describe(scene, model) -> list of lines for ``simulated_effects`` (empty when the
    normalised scene does not ask for it); activate(context) -> :class:`EffectRun` or None (None: the
    scene does not ask for it, or it adds nothing to the run beyond its summary line); sections: top-level
    scene sections it owns, name -> normaliser ``(raw, model_section) -> dict``; load_types: static load
    types it owns, ``type`` -> normaliser ``(raw, key, dim) -> dict``; stage_loads: ``type`` ->
    ``(model_context, stage_loads, load, key) -> None`` adding a normalised load to a
    :class:`StaticStageLoads`; finish_stage: ``(model_context, stage_loads) -> None`` called once per static
    stage after its loads (e.g. to turn what the loads asked for into ``varying``); dynamic_stage:
    ``(model_context, stage_spec, index, parts) -> None`` adding to a :class:`DynamicStageParts`;
    dynamic_loads: the normaliser ``(raw, key, dim) -> dict`` of the ``loads`` entries of a dynamic stage,
    for the effect that owns them; scene_keys: the :class:`~masonrydam.keys.Section` tables of its scene keys
    for the scene reference (docs/scene.md); scene_keys_place: where they go there (``"section"``: with the
    top-level sections at the end, ``"dynamic_stage"``: with the keys of dynamic stages); section_meanings:
    one line per top-level section it owns, for the reference's table of sections; check_scene:
    ``(stages, sections) -> None``, checks across the normalised scene (the normalised stages, and the
    effects' sections by name) that no one part can make, e.g. a section needs a load that applies it:
    a SceneError naming the key."""

    name: str
    asked_by: str
    module: str
    reference: str
    tests: str
    describe: Callable[[dict, object], list]
    activate: Callable[[RunContext], EffectRun | None] | None = None
    sections: dict = field(default_factory=dict)
    load_types: dict = field(default_factory=dict)
    stage_loads: dict = field(default_factory=dict)
    finish_stage: Callable | None = None
    dynamic_stage: Callable | None = None
    dynamic_loads: Callable | None = None
    scene_keys: tuple = ()
    scene_keys_place: str = "section"
    section_meanings: dict = field(default_factory=dict)
    check_scene: Callable | None = None
