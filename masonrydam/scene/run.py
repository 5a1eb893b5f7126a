"""Run a scene end to end: build, solve in stages, stream results, print a summary.

The run knows no physical effect by name: every effect the scene asks for joins it through the registry
(:func:`masonrydam.effects.activate`) as an :class:`~masonrydam.effects.base.EffectRun`, whose hooks add
its result variables, its terms of the dynamic stages, its mass and its diagnosis of a failed stage.
What is recorded besides is :mod:`.recording`; the statistics and the summary are :mod:`.summary`.
"""
from __future__ import annotations

import dataclasses
import json
import os
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import xarray as xr

from ..assembly.mass import MassMatrix
from ..checks import check_output_path
from ..effects import RunContext, activate
from ..errors import AccuracyWarning, ConvergenceError, MechanismError, OutputError, RunStopped
from ..results.files import claim_working_file, partial_path, settle_partial
from ..results.writer import OutputOptions, ResultWriter
from ..solvers.dynamic import DynamicSolver, DynamicStage, DynamicTerms, ModalStage, modal_analysis
from ..solvers.linear.direct import resolve_backend
from ..solvers.static.stepping import SolverSettings, StaticSolver
from .build import build_mesh, build_model, effects
from .progress import DynamicProgress, Progress
from .recording import (block_cells, driven_dofs, dynamic_attrs, element_info, ground_records, joint_points,
                        joint_results, output_selection, pushover_stages)
from .scene import as_scene
from .stages import build_stages
from .stopping import StopRequests
from .summary import print_summary, stats_attrs

#: a kept result file larger than this (bytes) is returned opened lazily instead of loaded (see :func:`run`)
LOAD_IN_MEMORY_MAX = 256 * 2**20


def run(scene, output: str | os.PathLike | None = None, progress: bool = False, summary: bool = False,
        started: float | None = None):
    """Run ``scene`` (a :class:`Scene`, a dict or a TOML path) and return the results as an
    ``xarray.Dataset``.

    With ``output`` the netCDF file is kept there. The run writes to ``NAME.partial.nc`` beside it
    and moves that file over ``output`` (an atomic rename) only when it completes, so an earlier
    result is never truncated and a reader holding it open keeps its contents. A run that ends early
    keeps every converged step, marked ``completed = "false"`` with a ``status`` (``"failed"``,
    ``"interrupted"`` for Ctrl-C, ``"terminated"`` for SIGTERM) and a ``status_reason``: at
    ``output`` when no file is there when the run ends, in ``NAME.partial.nc`` otherwise (the earlier
    result stays byte for byte); the error says where. Ctrl-C or SIGTERM stops the run at the end of the current step with
    :class:`~masonrydam.errors.RunStopped`; a second one stops it at once. A killed process leaves
    ``NAME.partial.nc`` with ``status = "running"``.

    The dataset is loaded in memory, except a kept file larger than :data:`LOAD_IN_MEMORY_MAX` bytes,
    which is opened lazily (values read when used; close it with ``ds.close()`` before writing the
    same file again), so that the memory of a long time history does not grow with the record.

    ``started``: a ``time.perf_counter()`` value from which the run's wall time counts (default: the
    call). The command line passes its process's start, so that the summary's wall time is what
    ``time masonrydam run`` shows, imports and reading the result back included.
    """
    t_start = time.perf_counter() if started is None else started
    target = None if output is None else check_output_path(output, "output")
    sc = as_scene(scene)
    job = _Run(sc, t_start)
    work = job.open_writer(target)
    stats = job.solve(work, target, progress)
    path = work if target is None else target
    if target is not None and os.path.getsize(path) > LOAD_IN_MEMORY_MAX:
        ds = xr.open_dataset(path)
    else:
        ds = xr.load_dataset(path)
    if target is None:
        os.unlink(work)
    if summary:
        print_summary(sc, job.mesh, job.model, job.effect_lines, job.solver, stats, target, ds,
                      dyn_solvers=job.dyn_solvers, effects=job.effects, t_start=t_start)
    for text in filter(None, (stats.get("energy_warnings", "") + " | " + stats.get("joint_slip_warnings", "")).split(" | ")):
        warnings.warn(text, AccuracyWarning, stacklevel=2)
    return ds


class _Run:
    """One run of a scene: the model, its stages, the active effects, the result writer and the solvers."""

    def __init__(self, sc, t_start: float):
        self.sc, self.t_start = sc, t_start
        s = self.scene = sc.normalized
        self.mesh = mesh = build_mesh(s, sc.base_dir)
        self.model = model = build_model(s, mesh)
        self.stages = stages = build_stages(s, mesh, model, sc.base_dir)
        self.static_stages = [st for st in stages if not isinstance(st, (DynamicStage, ModalStage))]
        self.dyn_stages = [st for st in stages if isinstance(st, DynamicStage)]
        self.modal_stage = next((st for st in stages if isinstance(st, ModalStage)), None)
        self.settings = SolverSettings(**s["solver"])
        self.effect_lines = effects(s, model)
        self.nodes, self.jgroups, self.set_names = output_selection(s, mesh, model)
        context = RunContext(s, sc.base_dir, mesh, model, stages, self.static_stages, self.dyn_stages,
                             self.modal_stage, self.jgroups)
        #: what the effects the scene asks for add to this run (registry order)
        self.effects = activate(context)
        self.solver = None
        self.dyn_solvers = []
        self.writer = None
        self.stopper = StopRequests()
        self._iterations_written = 0

    # -- the result file -----------------------------------------------------------------------------

    def attributes(self) -> dict:
        s, sc = self.scene, self.sc
        backend = resolve_backend(self.settings.linear_solver, n_dof=self.model.n_dof, dim=self.mesh.dim)
        attrs = {
            "title": f"masonrydam: {sc.name}",
            "scene_name": sc.name,
            "scene_source": sc.source,
            "scene_hash": sc.hash,
            "scene": json.dumps(s, sort_keys=True),
            "solver_settings": json.dumps(dict(self.settings.as_dict(), linear_solver_backend=backend), sort_keys=True),
            "simulated_effects": "; ".join(self.effect_lines),
            "stage_names": [st.name for st in self.stages],
            "dimension": self.mesh.dim,
            "sign_conventions": "joint opening and normal traction positive in tension; slip = top minus bottom along "
                                "the joint tangent (normal rotated -90 deg)",
        }
        if self.dyn_stages:
            attrs.update(dynamic_attrs(self.stages))
        for e in self.effects:
            attrs.update(e.attrs())
        attrs["pushover_stages"] = pushover_stages(self.static_stages, self.model)
        return attrs

    def open_writer(self, target) -> Path:
        """Create the working result file (a temporary file without ``target``) and its writer."""
        if target is None:
            fd, tmp = tempfile.mkstemp(suffix=".nc", prefix="masonrydam_")
            os.close(fd)
            work = Path(tmp)
        else:
            work = partial_path(target)
        attrs = self.attributes()
        if target is not None:
            claim_working_file(work)
        s, model, dim = self.scene, self.model, self.mesh.dim
        options = OutputOptions(**{f.name: s["output"][f.name] for f in dataclasses.fields(OutputOptions)})
        try:
            self.writer = ResultWriter(work, self.mesh.points, self.nodes, joint_points(self.jgroups, self.set_names, dim),
                                       dim, attrs, dynamic=bool(self.dyn_stages), options=options,
                                       elements=element_info(model) if s["output"]["stress"] == "element" else None,
                                       modes=None if self.modal_stage is None else self.modal_stage.modes,
                                       driven=driven_dofs(self.static_stages, model), blocks=block_cells(model),
                                       variables=[v for e in self.effects for v in e.result_variables()])
            if self.dyn_stages:
                self.writer.write_ground_records(ground_records(self.dyn_stages))
        except OSError as exc:  # e.g. another run holds the working file (HDF5 file lock), disk full
            if target is None:
                os.unlink(work)
            raise OutputError(f"cannot write the result file '{work}': {exc.strerror or exc}") from None
        return work

    def stress(self, u) -> dict:
        """The continuum stress where the scene asks for it (``[output] stress``)."""
        if self.scene["output"]["stress"] == "none":
            return {}
        return {"stress": np.concatenate([g.stress(self.model.coords, u).mean(axis=1) for g in self.model.cgroups])}

    def _iterations_since_last(self) -> int:
        done = self.solver.stats.iterations + self.solver.stats.joint_space_iterations  # general and joint-space
        iters = done - self._iterations_written
        self._iterations_written = done
        return iters

    def on_static_step(self, si, st, lam, u, f_int, f_ext):
        """Record a converged static step and stop at its end if a stop was asked for."""
        dim, nodes = self.mesh.dim, self.nodes
        r = f_int - f_ext
        r[~(st.supports | st.prescribed)] = 0.0
        iters = self._iterations_since_last()
        extra = {}
        for e in self.effects:
            extra.update(e.static_values(st, lam))
        extra.update(self.stress(u))
        with self.stopper.writing():
            self.writer.write_step(si, lam, iters, u.reshape(-1, dim)[nodes], r.reshape(-1, dim)[nodes],
                                   joint_results(self.jgroups, dim), extra=extra)
        status = self.stopper.requested()
        end_of_run = si == len(self.static_stages) - 1 and lam >= 1.0 - 1e-12 and not self.dyn_stages
        if status is not None and not end_of_run:
            raise RunStopped(status, f"after {self.writer.n} recorded steps (load factor {lam:.4g} of stage '{st.name}')")

    def diagnosis(self):
        """``(kind, text)`` of the first active effect that has something to say about a failed stage, or None."""
        for e in self.effects:
            found = e.diagnosis()
            if found is not None:
                return found
        return None

    # -- solving -----------------------------------------------------------------------------------------

    def solve(self, work, target, progress) -> dict:
        """Solve the stages, recording every converged step, and close the result file; returns the
        statistics. From the first step on the working file is closed and kept (or removed) whatever happens."""
        model, stopper = self.model, self.stopper
        bar = None
        try:
            stopper.install()
            bar = Progress(len(self.stages), progress)
            self.solver = solver = StaticSolver(model, self.settings, on_step=self.on_static_step, progress=bar,
                                                stop_requested=stopper.requested)
            u = solver.run(self.static_stages) if self.static_stages else np.zeros(model.n_dof)
            for e in self.effects:
                e.after_static(model, u)
            if self.modal_stage is not None and solver.limit is None:
                bar.status(f"{self.modal_stage.name}: the {self.modal_stage.modes} lowest modes", force=True)
                self.run_modal(u)
                bar(self.stages.index(self.modal_stage), 1.0)
            if self.dyn_stages and solver.limit is None:
                self.run_dynamic(u, bar)
            with stopper.closing():  # solved: a request from here on changes nothing
                bar.close()
                stats = stats_attrs(solver, self.t_start, self.dyn_solvers)
                if self.modal_stage is not None and solver.limit is None:
                    stats["modal_stage"] = self.modal_stage.name
                found = self.diagnosis() if solver.limit is not None else None
                if found is not None:
                    stats["limit_kind"], text = found
                    stats["limit_state"] += "; " + text
                self.writer.close(True, "completed", stats)
                if target is not None:
                    os.replace(work, target)
        except BaseException as exc:
            if isinstance(exc, (ConvergenceError, MechanismError)):
                found = self.diagnosis()
                if found is not None:
                    exc.add_note(found[1])
            with stopper.closing():
                if bar is not None:
                    bar.close()
                replacement = _end_early(exc, stopper, self.writer, work, target,
                                         lambda: stats_attrs(self.solver, self.t_start, self.dyn_solvers)
                                         if self.solver else {})
            stopper.restore()
            if replacement is not None:
                raise replacement from None
            raise
        stopper.restore()
        return stats

    def mass(self, lumped: bool, effects=None) -> MassMatrix:
        """The mass matrix with what the active ``effects`` (default: all) add to it."""
        added = influence = None
        massless = ()
        for e in self.effects if effects is None else effects:
            terms = e.mass_terms(lumped)
            massless += tuple(terms.get("massless", ()))
            if terms.get("added") is not None:
                added = terms["added"] if added is None else sp.csr_matrix(added + terms["added"])
            if terms.get("extra_influence") is not None:
                influence = terms["extra_influence"] if influence is None else influence + terms["extra_influence"]
        if added is None and influence is None:
            return MassMatrix(self.model, lumped, massless=massless)
        return MassMatrix(self.model, lumped, added=added, extra_influence=influence, massless=massless)

    def run_modal(self, u):
        """The modes of the static state ``u`` (joint states as committed), written to the result file: an
        effect's own modal analysis (the coupled dam-water modes of a compressible reservoir) or the plain
        one with every effect's mass."""
        model, stage, dim = self.model, self.modal_stage, self.mesh.dim
        model.set_constraints(stage.supports)
        res = None
        for e in self.effects:
            others = [x for x in self.effects if x is not e]
            res = e.modal_analysis(model, stage, u, lambda others=others: self.mass(stage.lumped, others))
            if res is not None:
                break
        if res is None:
            res = modal_analysis(model, stage.modes, lumped=stage.lumped, u=u, mass=self.mass(stage.lumped))
        self.writer.write_modes(res.frequencies, res.periods,
                                res.modes.T.reshape(len(res.frequencies), -1, dim)[:, self.nodes],
                                res.effective_mass, res.effective_mass_ratio)

    def _state_force(self):
        """One function of the forces that follow the committed joint states, or None."""
        forces = [f for f in (e.state_force() for e in self.effects) if f is not None]
        if len(forces) <= 1:
            return forces[0] if forces else None
        return lambda: sum(f() for f in forces)

    def run_dynamic(self, u, bar):
        """Run the dynamic stages from the static state ``u`` (and the joint state committed in the model);
        the stop requests are asked after every step; the effects' loads of the static state stay applied."""
        model, dim, stopper = self.model, self.mesh.dim, self.stopper
        f_static = np.zeros(model.n_dof)
        for st in self.static_stages:
            f_static += st.force
        for e in self.effects:
            e.carried_static_force(model, u, f_static)
        state_force = self._state_force()
        masses = {}
        v = energy = fluid = None
        t = 0.0
        for k, st in enumerate(self.dyn_stages):
            si = self.stages.index(st)
            lumped = st.settings.mass == "lumped"
            if lumped not in masses:
                masses[lumped] = self.mass(lumped)
            if st.terms is None:
                st.terms = DynamicTerms(state_force=state_force)
                for e in self.effects:
                    e.dynamic_terms(st, st.terms)
            status = stopper.requested()
            if k and status is not None:
                raise RunStopped(status, f"after stage '{self.dyn_stages[k - 1].name}'")
            solver = DynamicSolver(model, st.settings, mass=masses[lumped], stop_requested=stopper.requested)
            solver.progress = DynamicProgress(bar, si, st, solver, t)
            self.dyn_solvers.append(solver)
            if st.initial_velocity is not None:  # the stage starts with these velocities where they are given
                given = ~np.isnan(st.initial_velocity) & ~st.supports
                v = np.zeros(model.n_dof) if v is None else v.copy()
                v[given] = st.initial_velocity[given]
            state = solver.run(st, u0=u, v0=v, a0=None, f_static=f_static, equilibrate=(k == 0), t0=t,
                               energy0=energy, on_step=self._dynamic_recorder(si, masses[lumped]),
                               record_initial=(k == 0), fluid0=fluid)
            u, v, t, energy, fluid = state.u, state.v, state.t, state.energy, state.fluid

    def _dynamic_recorder(self, si: int, mass):
        """The ``on_step`` of the dynamic stage ``si``: records a step with what the effects add to it."""
        dim, nodes = self.mesh.dim, self.nodes

        def on_step(rec):
            extra = {}
            for e in self.effects:
                extra.update(e.dynamic_values(rec, mass))
            extra.update(self.stress(rec["u"]))
            with self.stopper.writing():
                self.writer.write_step(si, rec["stage_fraction"], rec["iterations"], rec["u"].reshape(-1, dim)[nodes],
                                       rec["reaction"].reshape(-1, dim)[nodes], joint_results(self.jgroups, dim),
                                       dynamic={"time": rec["t"], "velocity": rec["v"].reshape(-1, dim)[nodes],
                                                "acceleration": rec["a"].reshape(-1, dim)[nodes],
                                                "acceleration_absolute": rec["a_abs"].reshape(-1, dim)[nodes],
                                                "ground_acceleration": rec["ag"], "energy": rec["energy"]},
                                       extra=extra)

        return on_step


def _end_early(exc, stopper, writer, work, target, stats):
    """Close the result file of a run that ended early with ``exc``, keep it (see :func:`run`) and say
    where in ``exc``: a :class:`RunStopped` gets its status and file, any other error a note. A run
    without an output file removes its temporary file. Returns the exception to raise instead of
    ``exc`` (a :class:`RunStopped` for a ``KeyboardInterrupt``), or None."""
    if isinstance(exc, RunStopped):
        status, reason = exc.status, f"stopped {exc.where}"
    elif isinstance(exc, KeyboardInterrupt):  # a second request, or Ctrl-C where no handler of ours ran
        status = stopper.status or "interrupted"
        where = "at once (a second request) during a step" if stopper.status else "by KeyboardInterrupt during a step"
        reason = f"stopped {where}"
    else:
        status, reason = "failed", f"{type(exc).__name__}: {exc}"
    try:
        extra = stats()
    except Exception:  # the statistics must never hide the error that ended the run
        extra = {}
    try:
        writer.close(False, status, extra, reason)
    except Exception as close_exc:  # e.g. a full disk: the blocks written so far stay readable
        exc.add_note(f"the result file '{work}' could not be closed cleanly ({close_exc}); the steps written "
                     "before stay readable")
    kept = None
    if target is None:
        if work.exists():
            os.unlink(work)
    else:
        kept = settle_partial(work, target)
    steps = writer.n
    if isinstance(exc, RunStopped):
        exc.kept, exc.steps = kept, steps
    elif isinstance(exc, KeyboardInterrupt):
        stopped = RunStopped(status, where, kept, steps)
        for note in getattr(exc, "__notes__", []):
            stopped.add_note(note)
        return stopped
    elif kept is not None:
        where = (f"; the earlier result in {target} is unchanged" if kept != target else "")
        exc.add_note(f"results of {steps} converged step(s) were kept in {kept} (completed = false){where}")
    return None
