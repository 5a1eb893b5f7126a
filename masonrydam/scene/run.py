"""Run a scene end to end: build, solve in stages, stream results, print a summary."""
from __future__ import annotations

import dataclasses
import json
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from .._version import __version__
from ..errors import AccuracyWarning, OutputError, RunStopped
from ..materials import mohr_coulomb as mc
from ..results.files import check_output_path, claim_working_file, partial_path, settle_partial
from ..results.writer import OutputOptions, ResultWriter
from ..solvers.linear.direct import resolve_backend
from ..solvers.dynamic import DynamicStage
from ..solvers.static.stepping import SolverSettings, StaticSolver
from .build import build_mesh, build_model, build_stages, effects
from .scene import as_scene
from .stopping import StopRequests


def _output_selection(scene, mesh, model):
    """Recorded nodes and joint groups: the ``[output]`` section, or the ``output`` of a dynamic stage
    (which then applies to the whole file)."""
    scene = dict(scene, output=dict(scene["output"]))
    for st in scene["stages"]:
        if st["type"] == "dynamic":
            for k in ("nodes", "joints"):
                if st["output"][k] is not None:
                    scene["output"][k] = st["output"][k]
    sel = scene["output"]["nodes"]
    if sel == "all":
        nodes = np.arange(model.n_nodes)
    else:
        from .build import _node_set

        nodes = np.unique(np.concatenate([_node_set(mesh, s, "output.nodes") for s in sel]))
    jsel = scene["output"]["joints"]
    names = sorted({g.name for g in model.igroups})
    if jsel != "all":
        for s in jsel:
            if s not in names:
                from ..errors import SceneError

                raise SceneError("output.joints", f"no joint set '{s}' (joint sets: {names})")
    groups = [g for g in model.igroups if jsel == "all" or g.name in jsel]
    return nodes, groups, names


def _joint_points(groups, set_names, dim):
    xs, sets, elems, pts, normals, axes, weights = [], [], [], [], [], [], []
    for g in groups:
        ne, nip = g.n_elem, g.nip
        xs.append(g.points.reshape(-1, dim))
        sets.append(np.full(ne * nip, set_names.index(g.name)))
        elems.append(np.repeat(np.arange(ne), nip))
        pts.append(np.tile(np.arange(nip), ne))
        normals.append(g.frame[:, :, dim - 1, :].reshape(-1, dim))
        axes.append(g.frame[:, :, : dim - 1, :].reshape(-1, dim - 1, dim))
        weights.append((g.jw * g.thickness[:, None]).ravel())
    if not groups:
        z = np.zeros((0, dim))
        return {"x": z, "set": np.zeros(0, int), "set_names": set_names, "element": np.zeros(0, int),
                "point": np.zeros(0, int), "normal": z, "shear_axes": np.zeros((0, dim - 1, dim)), "weight": np.zeros(0),
                "nodes": np.zeros((0, 2, 1), int), "shape": np.zeros((0, 1))}
    n_face = max(g.conn.shape[1] // 2 for g in groups)
    nodes = np.full((sum(g.n_elem * g.nip for g in groups), 2, n_face), -1, dtype=np.int64)
    shape = np.zeros((len(nodes), n_face))
    k = 0
    for g in groups:  # each point: the faces of its element (conn: bottom face nodes, then top face nodes)
        ns, n = g.conn.shape[1] // 2, g.n_elem * g.nip
        nodes[k:k + n, :, :ns] = np.repeat(g.conn.reshape(g.n_elem, 2, ns), g.nip, axis=0)
        shape[k:k + n, :ns] = np.tile(g.N, (g.n_elem, 1))
        k += n
    return {"x": np.vstack(xs), "set": np.concatenate(sets), "set_names": set_names, "element": np.concatenate(elems),
            "point": np.concatenate(pts), "normal": np.vstack(normals), "shear_axes": np.concatenate(axes),
            "weight": np.concatenate(weights), "nodes": nodes, "shape": shape}


def _joint_results(groups, dim):
    if not groups:
        z = np.zeros(0)
        return {"opening": z, "slip": z.reshape(0, dim - 1), "plastic_slip": z.reshape(0, dim - 1),
                "t_normal": z, "t_shear": z.reshape(0, dim - 1), "state": z.astype(np.int8)}
    d = np.concatenate([g.delta.reshape(-1, dim) for g in groups])
    t = np.concatenate([g.traction.reshape(-1, dim) for g in groups])
    # (the laws share the code and plastic-slip columns; the composite law has more after them)
    st = np.concatenate([g.state_committed[:, :, :mc.N_JOINT_STATE].reshape(-1, mc.N_JOINT_STATE) for g in groups])
    return {"opening": d[:, -1], "slip": d[:, :-1], "plastic_slip": st[:, mc.S_PLASTIC_SLIP:mc.S_PLASTIC_SLIP + dim - 1],
            "t_normal": t[:, -1], "t_shear": t[:, :-1], "state": np.concatenate([g.result_states().ravel() for g in groups])}


class _Progress:
    """The progress bar of a run: the stages done (``__call__``) and, for a long static step, what it
    is doing (``status``: load factor, iteration, residual, cuts), so that a run stuck in its first
    step is visibly alive."""

    def __init__(self, n_stages, enabled):
        self.bar = None
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=n_stages, unit="stage",
                            bar_format="{l_bar}{bar}| {n:.2f}/{total} stages [{elapsed}]{postfix}",
                            file=sys.stderr, leave=True)
        self.done = 0.0
        self._shown = 0.0

    def __call__(self, stage_index, lam):
        if self.bar is not None:
            pos = stage_index + lam
            self.bar.update(pos - self.done)
            self.done = pos

    def status(self, text: str):
        if self.bar is not None:
            now = time.monotonic()
            refresh = now - self._shown >= 0.5  # at most twice a second: a Newton iteration can take 1 ms
            self.bar.set_postfix_str(text, refresh=refresh)
            if refresh:
                self._shown = now

    def close(self):
        if self.bar is not None:
            self.bar.close()


#: a kept result file larger than this (bytes) is returned opened lazily instead of loaded (see :func:`run`)
LOAD_IN_MEMORY_MAX = 256 * 2**20


def run(scene, output: str | os.PathLike | None = None, progress: bool = False, summary: bool = False):
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
    """
    import xarray as xr

    t_start = time.perf_counter()
    target = None if output is None else check_output_path(output, "output")
    sc = as_scene(scene)
    s = sc.normalized
    mesh = build_mesh(s, sc.base_dir)
    model = build_model(s, mesh)
    stages = build_stages(s, mesh, model, sc.base_dir)
    from ..solvers.dynamic import ModalStage

    static_stages = [st for st in stages if not isinstance(st, (DynamicStage, ModalStage))]
    dyn_stages = [st for st in stages if isinstance(st, DynamicStage)]
    modal_stage = next((st for st in stages if isinstance(st, ModalStage)), None)
    settings = SolverSettings(**s["solver"])
    backend = resolve_backend(settings.linear_solver, n_dof=model.n_dof, dim=mesh.dim)
    eff = effects(s, model)
    nodes, jgroups, set_names = _output_selection(s, mesh, model)
    dim = mesh.dim
    if target is None:
        fd, tmp = tempfile.mkstemp(suffix=".nc", prefix="masonrydam_")
        os.close(fd)
        work = Path(tmp)
    else:
        work = partial_path(target)
    solver_attrs = dict(settings.as_dict(), linear_solver_backend=backend)
    attrs = {
        "title": f"masonrydam: {sc.name}",
        "scene_name": sc.name,
        "scene_source": sc.source,
        "scene_hash": sc.hash,
        "scene": json.dumps(s, sort_keys=True),
        "solver_settings": json.dumps(solver_attrs, sort_keys=True),
        "simulated_effects": "; ".join(eff),
        "stage_names": [st.name for st in stages],
        "dimension": dim,
        "sign_conventions": "joint opening and normal traction positive in tension; slip = top minus bottom along "
                            "the joint tangent (normal rotated -90 deg)",
    }
    if dyn_stages:
        attrs.update(_dynamic_attrs(stages))
    if target is not None:
        claim_working_file(work)
    options = OutputOptions(**{f.name: s["output"][f.name] for f in dataclasses.fields(OutputOptions)})
    water = _Water(model, static_stages, jgroups)
    if water.reservoir is not None:
        attrs["reservoir_downstream_direction"] = [float(v) for v in water.reservoir.downstream]
    moving = _dynamic_water(s, mesh, model, water) if (dyn_stages or modal_stage is not None) else None
    if moving is not None:
        attrs["reservoir_dynamic"] = moving.describe()
    rock = _foundation(s, mesh) if dyn_stages else None
    if rock is not None:
        attrs["foundation"] = "; ".join(rock.describe())
        if not rock.base_excitation:
            attrs["time_history_conventions_foundation"] = (
                "with [foundation] mass = true and an outcrop motion the ground motion enters as free-field forces "
                "at the compliant base: displacement, velocity and acceleration of the dynamic steps are total, not "
                "relative to the ground (acceleration_absolute = acceleration)")
    attrs["pushover_stages"] = _pushover_stages(static_stages, model)
    try:
        writer = ResultWriter(work, mesh.points, nodes, _joint_points(jgroups, set_names, dim), dim, attrs,
                              dynamic=bool(dyn_stages), options=options, sections=water.section_info(),
                              water=water.reservoir is not None, pore_pressure=water.uplift is not None,
                              elements=_element_info(model) if s["output"]["stress"] == "element" else None,
                              modes=None if modal_stage is None else modal_stage.modes,
                              hydrodynamic=None if moving is None or not dyn_stages else
                              {"nodes": moving.nodes, "coords": model.coords[moving.nodes]},
                              driven=_driven(static_stages, model), blocks=_block_cells(model))
        if dyn_stages:
            writer.write_ground_records(_ground_records(dyn_stages))
    except OSError as exc:  # e.g. another run holds the working file (HDF5 file lock), disk full
        if target is None:
            os.unlink(work)
        raise OutputError(f"cannot write the result file '{work}': {exc.strerror or exc}") from None
    last_iters = {"n": 0}
    stopper = StopRequests()

    def stress(u):  # the continuum stress where the scene asks for it ([output] stress)
        if s["output"]["stress"] == "none":
            return {}
        return {"stress": np.concatenate([g.stress(model.coords, u).mean(axis=1) for g in model.cgroups])}

    n_static = len(static_stages)

    def on_step(si, st, lam, u, f_int, f_ext):
        r = f_int - f_ext
        r[~(st.supports | st.prescribed)] = 0.0
        done = solver.stats.iterations + solver.stats.joint_space_iterations  # general and joint-space Newton
        iters = done - last_iters["n"]
        last_iters["n"] = done
        with stopper.writing():
            writer.write_step(si, lam, iters, u.reshape(-1, dim)[nodes], r.reshape(-1, dim)[nodes],
                              _joint_results(jgroups, dim), extra=dict(water.extra(st, lam), **stress(u)))
        status = stopper.requested()
        end_of_run = si == n_static - 1 and lam >= 1.0 - 1e-12 and not dyn_stages
        if status is not None and not end_of_run:
            raise RunStopped(status, f"after {writer.n} recorded steps (load factor {lam:.4g} of stage '{st.name}')")

    bar = solver = None
    dyn_solvers = []
    try:  # from here on the working file is closed and kept (or removed) whatever happens
        stopper.install()
        bar = _Progress(len(stages), progress)
        solver = StaticSolver(model, settings, on_step=on_step, progress=bar)
        u = solver.run(static_stages) if static_stages else np.zeros(model.n_dof)
        if moving is not None and moving.coupled_nodes is not None:
            model.add_coupling(moving.coupled_nodes)  # the water condensed on the wetted face
        if modal_stage is not None and solver.limit is None:
            _run_modal(model, modal_stage, u, writer, nodes, dim, moving, _massless(s))
            bar(stages.index(modal_stage), 1.0)
        if dyn_stages and solver.limit is None:
            _run_dynamic(model, static_stages, dyn_stages, stages, u, writer, nodes, jgroups, dim, bar, dyn_solvers,
                         stopper, water, stress, moving, rock, _massless(s))
        with stopper.closing():  # solved: a request from here on changes nothing
            bar.close()
            stats = _stats_attrs(solver, t_start, dyn_solvers)
            if modal_stage is not None and solver.limit is None:
                stats["modal_stage"] = modal_stage.name
            if solver.limit is not None and water.last_measures is not None:
                stats["limit_kind"], text = water.diagnosis()
                stats["limit_state"] += "; " + text
            writer.close(True, "completed", stats)
            if target is not None:
                os.replace(work, target)
    except BaseException as exc:
        from ..errors import ConvergenceError, MechanismError

        if isinstance(exc, (ConvergenceError, MechanismError)) and water.last_measures is not None:
            exc.add_note(water.diagnosis()[1])
        with stopper.closing():
            if bar is not None:
                bar.close()
            replacement = _end_early(exc, stopper, writer, work, target,
                                     lambda: _stats_attrs(solver, t_start, dyn_solvers) if solver else {})
        stopper.restore()
        if replacement is not None:
            raise replacement from None
        raise
    stopper.restore()
    path = work if target is None else target
    if target is not None and os.path.getsize(path) > LOAD_IN_MEMORY_MAX:
        ds = xr.open_dataset(path)
    else:
        ds = xr.load_dataset(path)
    if target is None:
        os.unlink(work)
    if summary:
        print_summary(sc, mesh, model, eff, solver, stats, target, ds, dyn_solvers=dyn_solvers)
    for text in filter(None, (stats.get("energy_warnings", "") + " | " + stats.get("joint_slip_warnings", "")).split(" | ")):
        warnings.warn(text, AccuracyWarning, stacklevel=2)
    return ds


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


def _pushover_stages(static_stages, model) -> str:
    """JSON ``{component: [stage indices]}``: for each component, the static stages that prescribe a non-zero
    displacement increment of a DOF the last driving stage drives (a cyclic test's successive pushes), in
    order: the steps of a pushover or hysteresis curve (:func:`masonrydam.results.pushover.pushover_data`)."""
    driven = _driven(static_stages, model)
    out = {}
    if driven is None:
        return json.dumps(out)
    for c in range(model.dim):
        last = int(driven[:, c].max())
        if last == 0:
            continue
        dofs = np.flatnonzero(driven[:, c] == last) * model.dim + c
        out["xyz"[c]] = [i for i, st in enumerate(static_stages)
                         if (st.prescribed[dofs] & (st.increment[dofs] != 0.0)).any()]
    return json.dumps(out)


def _driven(static_stages, model):
    """(n_nodes, dim) int: 1 + the index of the last static stage that prescribes a non-zero displacement
    increment of each DOF (0: none), the actuator of a pushover; None when no stage does."""
    out = np.zeros(model.n_dof, dtype=np.int32)
    for i, st in enumerate(static_stages):
        out[st.prescribed & (st.increment != 0.0)] = i + 1
    return out.reshape(-1, model.dim) if out.any() else None


def _dynamic_attrs(stages) -> dict:
    """Ground-motion provenance and integrator settings of the dynamic stages, as netCDF attributes."""
    out = {}
    for i, st in enumerate(stages):
        if not isinstance(st, DynamicStage):
            continue
        out[f"stage{i}_dynamic_settings"] = json.dumps(st.settings.as_dict(), sort_keys=True)
        out[f"stage{i}_duration_s"] = float(st.duration)
        out[f"stage{i}_output_stride"] = int(st.output_stride)
        for g in st.ground_motion:
            c = "xyz"[g.component]
            prefix = f"stage{i}_ground_motion_{c}_"
            out[prefix + "name"] = g.name
            out[prefix + "pga_m_s2"] = float(np.max(np.abs(g.values)))
            for k, v in g.attrs.items():
                out[prefix + k] = v
    out["time_history_conventions"] = ("displacement, velocity and acceleration are relative to the ground "
                                       "(supports); acceleration_absolute = acceleration + ground_acceleration; "
                                       "time is NaN for static steps")
    return out


def _ground_records(dyn_stages) -> dict:
    """``{component letter: (time (n,), acceleration (n,))}``: the ground-acceleration samples the dynamic
    stages use, at the records' own rate (:meth:`~masonrydam.results.writer.ResultWriter.write_ground_records`):
    each stage's samples within its duration, at the stage's start time plus ``i dt`` (time since the start of
    the first dynamic stage, the result's ``time``); a NaN value (at the next stage's first time) between two
    stages' records of one component, so that no line joins them."""
    out = {}
    t0 = 0.0
    for st in dyn_stages:
        for g in st.ground_motion:
            n = min(len(g.values), int(np.floor(st.duration / g.dt * (1.0 + 1e-12))) + 1)
            t = t0 + np.arange(n) * g.dt
            parts = out.setdefault("xyz"[g.component], [])
            if parts:
                parts.append((t[:1], np.array([np.nan])))
            parts.append((t, g.values[:n]))
        t0 += st.duration
    return {c: (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))
            for c, parts in out.items()}


def _dynamic_water(s, mesh, model, water):
    """The reservoir moving with the dam (:mod:`masonrydam.effects.dynamic_water`), or None."""
    spec = s.get("reservoir")
    if not spec or spec["dynamic"] == "none":
        return None
    from ..effects.dynamic_water import DynamicWater

    level = water.stages[-1].water.levels(1.0)[0]
    return DynamicWater(spec, water.reservoir, model, level, s["model"]["thickness"], mesh)


def _foundation(s, mesh):
    """The foundation rock with mass and absorbing boundaries (:mod:`masonrydam.effects.foundation`), or None."""
    spec = s.get("foundation")
    if not spec or not spec["mass"]:
        return None
    from ..effects.foundation import build

    return build(spec, mesh, s["materials"], s["model"])


def _massless(s) -> tuple:
    """Element groups without mass: the rock of ``[foundation] mass = false``."""
    spec = s.get("foundation")
    return (spec["group"],) if spec and not spec["mass"] else ()


def _mass(model, lumped, moving, massless=()):
    from ..assembly.mass import MassMatrix

    if moving is None:
        return MassMatrix(model, lumped, massless=massless)
    return MassMatrix(model, lumped, added=moving.added_mass(lumped), extra_influence=moving.extra_influence,
                      massless=massless)


def _earthquake_uplift(water):
    """Uplift during the shaking (``uplift.earthquake``): a function () -> (n_dof,) N of the change of the
    pore forces from the state the static stages left (the same reference for every dynamic stage), or
    None (``"static"``: the static pore forces stay as they were)."""
    if water.uplift is None:
        return None
    level, tail, _ = water.stages[-1].water.levels(1.0)
    pore = water.uplift.earthquake_force(level, tail)
    if pore is None:
        return None
    static_pore = pore()
    return lambda: pore() - static_pore


def _dynamic_terms(moving, rock, stage, state_force):
    """What the effects add to the dynamic ``stage`` (:class:`~masonrydam.solvers.dynamic.DynamicTerms`);
    with a foundation of mass, the stage's supports lose the DOFs of the absorbing boundaries (each
    stage's free field starts with its own record at its start: waves of the stage before that are still
    travelling outside the model are not carried over)."""
    from ..solvers.dynamic import DynamicTerms

    terms = DynamicTerms(state_force=state_force)
    if moving is not None:
        terms.fluid = moving.fluid_step()
    if rock is not None:
        rock.set_motion({g.component: (g.values, g.dt) for g in stage.ground_motion})
        terms.dashpots = rock.dashpots
        terms.force = rock.effective_force
        terms.support_excitation = rock.base_excitation
        terms.bottom_acceleration = rock.surface_acceleration
        stage.supports = stage.supports & ~rock.released_dofs
    if stage.loads is not None:  # loads given in time (effects.dynamic_loads), with the free field if any
        free_field, loads = terms.force, stage.loads
        terms.force = loads if free_field is None else (lambda tau: free_field(tau) + loads(tau))
    return terms


def _run_dynamic(model, static_stages, dyn_stages, stages, u, writer, nodes, jgroups, dim, bar, dyn_solvers, stopper,
                 water, stress, moving=None, rock=None, massless=()):
    """Run the dynamic stages from the static state ``u`` (and the joint state committed in the model);
    ``stopper`` (:class:`StopRequests`) is asked after every step; ``water``: the run's :class:`_Water`
    (the static water and pore forces stay applied); ``moving``: the reservoir moving with the dam
    (:class:`~masonrydam.effects.dynamic_water.DynamicWater`) or None; ``rock``: the foundation with mass
    (:class:`~masonrydam.effects.foundation.Foundation`) or None; ``massless``: groups without mass."""
    from ..solvers.dynamic import DynamicSolver

    f_static = np.zeros(model.n_dof)
    for st in static_stages:
        f_static += st.force
    f_static += water.static_force()
    if rock is not None:
        # the supports the absorbing boundaries replace keep their static reactions as constant loads
        # (every dynamic stage, not only the first, which takes its constant load from f_int)
        f_int, _ = model.evaluate(u, want_tangent=False)
        rel = rock.released_dofs
        f_static[rel] = f_int[rel]
    state_force = _earthquake_uplift(water)
    masses = {}
    v = energy = fluid = None
    t = 0.0
    for k, st in enumerate(dyn_stages):
        si = stages.index(st)
        lumped = st.settings.mass == "lumped"
        if lumped not in masses:
            masses[lumped] = _mass(model, lumped, moving, massless)
        if st.terms is None:
            st.terms = _dynamic_terms(moving, rock, st, state_force)

        def prog(fraction, si=si):
            bar(si, fraction)

        status = stopper.requested()
        if k and status is not None:
            raise RunStopped(status, f"after stage '{dyn_stages[k - 1].name}'")
        ds = DynamicSolver(model, st.settings, mass=masses[lumped], progress=prog, stop_requested=stopper.requested)
        dyn_solvers.append(ds)

        def on_step(rec, si=si, mass=masses[lumped]):
            extra = dict(water.extra(None, None), **stress(rec["u"]))
            if moving is not None:
                extra.update(moving.outputs(rec["a_abs"], rec["bottom_acceleration"], rec["fluid"], mass))
            with stopper.writing():
                writer.write_step(si, rec["stage_fraction"], rec["iterations"], rec["u"].reshape(-1, dim)[nodes],
                                  rec["reaction"].reshape(-1, dim)[nodes], _joint_results(jgroups, dim),
                                  dynamic={"time": rec["t"], "velocity": rec["v"].reshape(-1, dim)[nodes],
                                           "acceleration": rec["a"].reshape(-1, dim)[nodes],
                                           "acceleration_absolute": rec["a_abs"].reshape(-1, dim)[nodes],
                                           "ground_acceleration": rec["ag"], "energy": rec["energy"]},
                                  extra=extra)

        if st.initial_velocity is not None:  # the stage starts with these velocities where they are given
            given = ~np.isnan(st.initial_velocity) & ~st.supports
            v = np.zeros(model.n_dof) if v is None else v.copy()
            v[given] = st.initial_velocity[given]
        state = ds.run(st, u0=u, v0=v, a0=None, f_static=f_static, equilibrate=(k == 0), t0=t, energy0=energy,
                       on_step=on_step, record_initial=(k == 0), fluid0=fluid)
        u, v, t, energy, fluid = state.u, state.v, state.t, state.energy, state.fluid


def _run_modal(model, stage, u, writer, nodes, dim, moving=None, massless=()):
    """The modes of the static state ``u`` (joint states as committed), written to the result file;
    with the reservoir moving with the dam (``moving``) its added mass, or the coupled dam-water modes
    of a compressible reservoir."""
    from ..solvers.dynamic import coupled_modal_analysis, modal_analysis

    model.set_constraints(stage.supports)
    if moving is not None and moving.fluid_step() is not None:
        res = coupled_modal_analysis(model, stage.modes, moving.fluid_step(), lumped=stage.lumped, u=u,
                                     mass=_mass(model, stage.lumped, None, massless))
    else:
        res = modal_analysis(model, stage.modes, lumped=stage.lumped, u=u, mass=_mass(model, stage.lumped, moving,
                                                                                     massless))
    writer.write_modes(res.frequencies, res.periods, res.modes.T.reshape(len(res.frequencies), -1, dim)[:, nodes],
                       res.effective_mass, res.effective_mass_ratio)


def _block_cells(model) -> dict:
    """Corner nodes of every continuum element (element group after group), -1 padded to the largest
    count, with each element's group: the connectivity of the result file (``block_cell_nodes``)."""
    from ..elements.shapes import ELEMENT_TYPES

    corners = [g.conn[:, :ELEMENT_TYPES[g.type].corner_nodes] for g in model.cgroups]
    nodes = np.full((sum(len(c) for c in corners), max((c.shape[1] for c in corners), default=1)), -1, np.int64)
    k = 0
    for c in corners:
        nodes[k:k + len(c), :c.shape[1]] = c
        k += len(c)
    return {"nodes": nodes, "group": np.repeat(np.arange(len(corners)), [len(c) for c in corners]),
            "group_names": [g.name for g in model.cgroups], "group_types": [g.type for g in model.cgroups]}


def _element_info(model) -> dict:
    """Groups and centroids of the continuum elements, for ``[output] stress = "element"``."""
    return {"group": np.concatenate([np.full(g.n_elem, i) for i, g in enumerate(model.cgroups)]),
            "group_names": [g.name for g in model.cgroups],
            "centroid": np.vstack([model.coords[g.conn].mean(axis=1) for g in model.cgroups])}


class _Water:
    """What a run records of the water of its scene (:mod:`masonrydam.effects.reservoir`): the levels,
    the pore pressures of the recorded joints and the stability measures of the joint lines
    (:mod:`masonrydam.results.assess`). A scene without a reservoir records none of them."""

    def __init__(self, model, static_stages, jgroups):
        from ..results.assess import SectionAssessment, assessed_lines

        self.stages = [st for st in static_stages if st.water is not None]
        self.reservoir = self.stages[0].water.reservoir if self.stages else None
        self.uplift = None if self.reservoir is None else self.reservoir.uplift
        self.last = None  # (stage, load factor) of the last static step with water
        self.assessment = None
        self.last_measures = None  # the section measures of the last recorded step
        #: per recorded joint group, its index in the model and its number of points
        self._record_groups = [(model.igroups.index(g), g.n_elem * g.nip) for g in jgroups]
        if self.reservoir is not None:
            lines = assessed_lines(model, self.reservoir)
            if lines is not None and lines.horizontal.any():
                self.assessment = SectionAssessment(model, lines)

    def section_info(self):
        a = self.assessment
        if a is None:
            return None
        L, k = a.lines, a.keep
        return {"names": a.names, "set_names": [L.set_names[i] for i in k], "length": L.length[k],
                "centre": L.centre[k]}

    def extra(self, st, lam) -> dict:
        """Step values for the writer; ``st``/``lam``: the static stage and load factor (None: a dynamic
        step, which keeps the water of the last static step)."""
        if self.reservoir is None:
            return {}
        if st is not None and st.water is not None:
            self.last = (st, lam)
        if self.last is None:  # a static stage before the water (the water persists once applied)
            return self._values((self.reservoir.face.bottom, None, None))
        stage, lam = self.last
        return self._values(stage.water.levels(lam))

    def _values(self, levels) -> dict:
        out = {"reservoir_level": levels[0], "tailwater_level": np.nan if levels[1] is None else levels[1]}
        up = self.uplift
        if up is not None:
            pressures = [up.group_pressure(i) for i, _ in self._record_groups]
            out["joint_pore_pressure"] = np.concatenate(
                [np.zeros(0)] + [np.zeros(n) if p is None else p for p, (_, n) in zip(pressures, self._record_groups)])
        if self.assessment is not None:
            lines_up = up is not None and self.assessment.lines is up.lines
            self.last_measures = self.assessment.measures(up.line_forces() if lines_up else None)
            out.update(self.last_measures)
        return out

    def diagnosis(self) -> tuple[str, str]:
        """What the joint lines say about a stage that found no equilibrium, from the last converged
        state (the recorded section measures): ``(kind, text)`` with kind ``"sliding"`` (a line's sliding
        factor within 5 % of 1), ``"overturning"`` (a line open over 90 % of its length or its resultant
        within 5 % of its toe), ``"crack"`` (in the failed attempt a crack grew over more than a fifth
        of its line: unstable crack growth) or ``"convergence"`` (none of these: every line still holds
        with margin, so the stage most likely stopped because the joint iterations did not converge, not
        because the dam failed)."""
        m = self.last_measures  # (the tractions of the model are those of the failed attempt)
        names = self.assessment.names
        sf, cr = m["sliding_safety_factor"], m["cracked_length_ratio"]
        where = m["resultant_position"] / np.maximum(self.assessment.lines.length[self.assessment.keep], 1e-300)
        k, j = int(np.argmin(sf)), int(np.argmax(cr))
        text = (f"at the last converged step the lowest sliding factor is {sf[k]:.3g} ('{names[k]}') and the "
                f"largest cracked length {100 * cr[j]:.0f} % ('{names[j]}')")
        failed = [st.water.last_failure for st in self.stages if st.water.last_failure is not None]
        grow = failed[-1] if failed else None
        if sf[k] < 1.05:
            return "sliding", text + f": '{names[k]}' slides"
        if cr[j] > 0.9 or np.nanmax(where) > 0.95:
            i = j if cr[j] > 0.9 else int(np.nanargmax(where))
            return "overturning", text + f": the resultant on '{names[i]}' reaches its toe"
        if grow is not None and grow["open_after"] - grow["open_before"] > 0.2:
            return "crack", text + (f"; in the failed attempt the crack of '{grow['line']}' ran from "
                                    f"{100 * grow['open_before']:.0f} % to {100 * grow['open_after']:.0f} % of its "
                                    "length in one small increment: unstable crack growth (with uplift in the "
                                    "crack), a failure of the section")
        return "convergence", text + ("; every joint line still holds with margin: the stage most likely stopped "
                                      "because the joint iterations did not converge (joints on tiny tractions "
                                      "changing state), not because the dam failed; more steps or other "
                                      "solver settings may pass it")

    def static_force(self):
        """The water and pore forces (n_dof,) N at the end of the static stages (committed joint states)."""
        if not self.stages:
            return 0.0
        return self.stages[-1].water.total(1.0, trial=False)


def _stats_attrs(solver, t_start, dyn_solvers=()):
    st = solver.stats
    out = {"steps": st.steps, "newton_iterations": st.iterations, "factorizations": st.factorizations,
           "symbolic_analyses": st.analyses, "joint_space_size": st.joint_space_size,
           "joint_space_steps": st.joint_space_steps, "joint_space_iterations": st.joint_space_iterations,
           "joint_space_splits": st.joint_space_splits,
           "joint_space_setup_s": round(st.joint_space_setup_s, 4),
           "joint_space_flexibility_columns": st.joint_space_flexibility_columns,
           "joint_space_flexibility_s": round(st.joint_space_flexibility_s, 4),
           "step_cuts": st.step_cuts, "arc_length_steps": st.arc_length_steps,
           "arc_length_switches": st.arc_length_switches, "solve_wall_time_s": round(st.wall_time_s, 4),
           "total_wall_time_s": round(time.perf_counter() - t_start, 4), "per_stage": json.dumps(st.per_stage)}
    far = solver.model.far_slips()
    if far:
        out["joint_slip_warnings"] = " | ".join(far)
    if solver.limit is not None:
        out["limit_state"] = _limit_text(solver)
        out["limit_load_factor"] = float(solver.limit["load_factor"])
        if "water_level" in solver.limit:
            out["limit_reservoir_level"] = float(solver.limit["water_level"])
    if dyn_solvers:
        d = [x.stats for x in dyn_solvers]
        steps = sum(x.steps for x in d)
        wall = sum(x.wall_time_s - x.output_time_s for x in d)
        out.update({
            "dynamic_steps": steps, "dynamic_substeps": sum(x.substeps for x in d),
            "dynamic_steps_rejected": sum(x.steps_rejected for x in d),
            # the smallest step taken: by dt = "auto" where a stage had it, else the smallest fixed dt
            "dynamic_dt_smallest": float(min([x.dt_smallest for x in d if x.dt_largest > 0]
                                             + [s.s.dt for s in dyn_solvers if not s.s.adaptive],
                                             default=float("nan"))),  # nan: no step was taken
            "dynamic_newton_iterations": sum(x.iterations for x in d),
            "dynamic_factorizations": sum(x.factorizations for x in d),
            "dynamic_reference_solver": ",".join(sorted(set().union(*(x.reference_solvers for x in d)))),
            "dynamic_exact_reuse_solves": sum(x.exact_solves for x in d),
            "dynamic_low_rank_solves": sum(x.low_rank_solves for x in d),
            "dynamic_low_rank_columns": sum(x.low_rank_columns for x in d),
            "dynamic_max_low_rank": max(x.max_rank for x in d),
            "dynamic_stabilized_steps": sum(x.stabilized_steps for x in d),
            "dynamic_joint_space_size": max(x.joint_space_size for x in d),
            "dynamic_joint_space_steps": sum(x.joint_space_steps for x in d),
            "dynamic_joint_space_iterations": sum(x.joint_space_iterations for x in d),
            "dynamic_joint_space_fallbacks": sum(x.joint_space_fallbacks for x in d),
            "dynamic_joint_space_splits": sum(x.joint_space_splits for x in d),
            "dynamic_joint_space_dense_factorizations": sum(x.joint_space_dense_factorizations for x in d),
            "dynamic_joint_space_dense_updates": sum(x.joint_space_dense_updates for x in d),
            "dynamic_joint_space_holds": sum(x.joint_space_holds for x in d),
            "dynamic_joint_space_column_recoveries": sum(x.joint_space_column_recoveries for x in d),
            "dynamic_joint_space_column_memory_MB": round(max(x.joint_space_column_bytes for x in d) / 2**20, 2),
            "dynamic_joint_space_setup_s": round(sum(x.joint_space_setup_s for x in d), 4),
            "dynamic_joint_space_flexibility_columns": sum(x.joint_space_flexibility_columns for x in d),
            "dynamic_joint_space_flexibility_s": round(sum(x.joint_space_flexibility_s for x in d), 4),
            "dynamic_joint_space_store_full": sum(x.joint_space_store_full for x in d),
            "dynamic_wall_time_s": round(wall, 4),
            "dynamic_output_time_s": round(sum(x.output_time_s for x in d), 4),
            "dynamic_ms_per_step": round(1e3 * wall / max(steps, 1), 4),
            "energy_error_max_J": float(max(x.energy_error_max for x in d)),
            "energy_error_relative": float(max(x.energy_error_relative for x in d)),
            "energy_numerical_relative": float(d[-1].energy_numerical / d[-1].energy_scale
                                               if d[-1].energy_scale > 0 else 0.0),
            "energy_contact_relative": float(d[-1].energy_contact / d[-1].energy_scale
                                             if d[-1].energy_scale > 0 else 0.0),
            "energy_warnings": " | ".join(_energy_warnings(dyn_solvers)),
            "static_residual_carried": float(d[0].static_residual),
            "dynamic_per_stage": json.dumps([p for x in d for p in x.per_stage]),
        })
    return out


def _limit_text(solver) -> str:
    """Where a stage with ``until_failure`` found no equilibrium, in words (with the water level)."""
    lim = solver.limit
    text = (f"stage '{lim['stage']}': no equilibrium beyond load factor {lim['load_factor']:.6g} "
            f"(tried {lim['failed_at']:.6g}): {lim['reason']}")
    if "water_level" in lim:
        text += f"; reservoir level reached {lim['water_level']:.6g} m (tried {lim['water_level_tried']:.6g} m)"
    return text


def _energy_warnings(dyn_solvers):
    """The energy warnings of the run (:func:`~masonrydam.solvers.dynamic.energy_warnings`): the energy
    terms are cumulative over the dynamic stages, so the last stage's solver speaks for the run, with the
    largest balance error of any stage."""
    from ..solvers.dynamic import energy_warnings

    if not dyn_solvers:
        return []
    last = dyn_solvers[-1]
    stats = dataclasses.replace(last.stats, energy_error_max=max(x.stats.energy_error_max for x in dyn_solvers))
    s = last.s
    dt = f"auto (tolerance {s.tolerance:g}, dt_min {s.dt_min:g} s)" if s.adaptive else f"{s.dt:g} s"
    return energy_warnings(stats, s.integrator, dt)


def _columns_note(columns, seconds, store_full=0):
    """The summary's note on the flexibility columns computed as steps needed them (large joint sets)."""
    if not columns:
        return ""
    full = f", {store_full} step(s) needed more than the store holds" if store_full else ""
    return f"; {columns} flexibility columns computed when first needed ({seconds:.3g} s{full})"


def print_summary(sc, mesh, model, eff, solver, stats, path, ds, file=None, dyn_solvers=()):
    file = file or sys.stdout
    n_ip = sum(g.n_elem * g.nip for g in model.igroups)
    types = {}
    for b in mesh.blocks:
        types[b.type] = types.get(b.type, 0) + len(b.cells)
    jsets = {}
    for g in model.igroups:
        jsets[g.name] = jsets.get(g.name, 0) + g.n_elem
    w = 72
    lines = ["=" * w, f"masonrydam {__version__} | scene '{sc.name}' ({sc.source})", "-" * w,
             f"model      : {mesh.dim}D, {model.n_nodes} nodes, {model.n_dof} DOFs, "
             + ", ".join(f"{n} {t}" for t, n in sorted(types.items())),
             f"joints     : " + (", ".join(f"{k} {v} el." for k, v in sorted(jsets.items())) or "none")
             + f" ({n_ip} integration points)",
             "effects    : " + eff[0]]
    lines += ["             " + e for e in eff[1:]]
    for ps in solver.stats.per_stage:
        lines.append(f"stage      : {ps['stage']}: {ps['steps']} steps, {ps['iterations']} Newton iterations, "
                     f"{ps['step_cuts']} step cuts"
                     + (f"; in its {ps['dissipation_control_steps']} steps under dissipation control the joints "
                        f"dissipated {ps['joint_dissipation_J']:.4g} J" if "joint_dissipation_J" in ps else ""))
    lines.append(f"solver     : {solver.s.method}, {stats['factorizations']} factorization(s) "
                 f"[{resolve_backend(solver.s.linear_solver, n_dof=model.n_dof, dim=model.dim)}; "
                 f"{stats['symbolic_analyses']} symbolic analyses], {stats['newton_iterations']} general Newton "
                 "iterations")
    if stats["arc_length_steps"]:
        lines.append(f"arc length : {stats['arc_length_steps']} steps under path-following control (Crisfield's arc, "
                     "crack opening or joint dissipation)"
                     + (f", {stats['arc_length_switches']} switch(es) to it or between its controls where a "
                        "control stalled"
                        if stats["arc_length_switches"] else ""))
    if stats["joint_space_size"]:
        lines.append(f"joint space: static steps on {stats['joint_space_size']} joint unknowns (set-up "
                     f"{stats['joint_space_setup_s']:.3g} s): {stats['joint_space_steps']} step attempts converged "
                     f"there in {stats['joint_space_iterations']} iterations, {stats['joint_space_splits']} cut "
                     "where it did not converge"
                     + _columns_note(stats['joint_space_flexibility_columns'], stats['joint_space_flexibility_s']))
    for dsol in dyn_solvers:
        for p in dsol.stats.per_stage:
            crit = f", dt_crit {p['dt_critical']:.3g} s" if p.get("dt_critical") else ""
            if p["dt"] == "auto":
                lines.append(f"dynamic    : {p['stage']}: {p['steps']} steps, dt = auto ({p['dt_smallest']:.3g} to "
                             f"{p['dt_largest']:.3g} s, tolerance {p['tolerance']:g}), {p['steps_rejected']} "
                             f"refused and retried smaller ({p['integrator']})")
            else:
                lines.append(f"dynamic    : {p['stage']}: {p['steps']} steps of {p['dt']:g} s ({p['integrator']}{crit})")
    if dyn_solvers:
        lines.append(f"dynamics   : {stats['dynamic_newton_iterations']} general Newton iterations, {stats['dynamic_substeps']} "
                     f"sub-step splits, {stats['dynamic_factorizations']} factorization(s) "
                     f"[all-stick matrix: {stats['dynamic_reference_solver'] or '-'}], "
                     f"{stats['dynamic_low_rank_solves']} low-rank solves, {stats['dynamic_ms_per_step']:.3g} ms/step")
        if stats["dynamic_joint_space_size"]:
            lines.append(f"joint space: {stats['dynamic_joint_space_size']} joint unknowns condensed (set-up "
                         f"{stats['dynamic_joint_space_setup_s']:.3g} s); {stats['dynamic_joint_space_steps']} steps "
                         f"solved there in {stats['dynamic_joint_space_iterations']} iterations "
                         f"({stats['dynamic_joint_space_dense_factorizations']} dense LU, "
                         f"{stats['dynamic_joint_space_dense_updates']} low-rank updates of them, "
                         f"{stats['dynamic_joint_space_holds']} flipping points held sticking, "
                         f"{stats['dynamic_joint_space_column_recoveries']} recoveries from "
                         f"{stats['dynamic_joint_space_column_memory_MB']:.3g} MB of stored columns), "
                         f"{stats['dynamic_joint_space_splits']} halved, "
                         f"{stats['dynamic_joint_space_fallbacks']} finished by the general path"
                         + _columns_note(stats['dynamic_joint_space_flexibility_columns'],
                                         stats['dynamic_joint_space_flexibility_s'],
                                         stats['dynamic_joint_space_store_full']))
        else:
            why = ("the blocks are nonlinear (plastic or large kinematics): every iteration is general"
                   if not model.condensable else
                   "no nonlinear joints, an explicit scheme, or joint_space = 'off'")
            lines.append(f"joint space: off ({why})")
        lines.append(f"energy     : balance error {stats['energy_error_max_J']:.3g} J "
                     f"({100 * stats['energy_error_relative']:.3g} % of the largest energy term); numerical "
                     f"dissipation {100 * stats['energy_numerical_relative']:.3g} %, contact events "
                     f"{100 * stats['energy_contact_relative']:.3g} %")
    if "joint_state" in ds and ds.sizes.get("joint_point", 0):
        last = ds.joint_state.isel(step=-1).values
        crushed = int((last == 3).sum())
        lines.append(f"joints end : {int((last == 0).sum())} stick, {int((last == 1).sum())} slip, "
                     f"{int((last == 2).sum())} open" + (f", {crushed} crushed" if crushed else ""))
    if "limit_state" in stats:
        lines.append(f"limit      : {stats['limit_state']}")
    if "frequency" in ds:
        comps = [str(c) for c in ds.component.values]
        lines.append(f"modes      : stage '{stats.get('modal_stage', '')}', effective mass ratio (% of the free mass) "
                     "per direction")
        lines.append("             mode  f (Hz)    T (s)    " + "  ".join(f"{c:>6}" for c in comps))
        for k in range(ds.sizes["mode"]):
            r = ds.effective_mass_ratio.values[k]
            lines.append(f"             {k + 1:4d}  {float(ds.frequency[k]):8.4g}  {float(ds.period[k]):7.4g}  "
                         + "  ".join(f"{100 * v:6.2f}" for v in r))
    if "section" in ds.dims and ds.sizes.get("step", 0):
        last = ds.isel(step=-1)
        sf = last.sliding_safety_factor.values
        k = int(np.nanargmin(np.where(np.isfinite(sf), sf, np.inf)))
        lines.append(f"stability  : {ds.sizes['section']} joint lines; lowest sliding factor {sf[k]:.3g} on "
                     f"'{str(last.section.values[k])}', largest cracked ratio "
                     f"{float(np.nanmax(last.cracked_length_ratio.values)):.3g} (masonrydam assess FILE)")
    u = ds.displacement.isel(step=-1)
    umax = float(np.abs(u).max())
    lines.append(f"max |u|    : {umax:.4g} m")
    lines.append(f"wall time  : {stats['total_wall_time_s']:.2f} s (solve {stats['solve_wall_time_s']:.2f} s)")
    if path:
        lines.append(f"results    : {path}")
    lines.append("=" * w)
    print("\n".join(lines), file=file)
