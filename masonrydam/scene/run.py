"""Run a scene end to end: build, solve in stages, stream results, print a summary."""
from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .._version import __version__
from ..errors import MasonrydamError
from ..materials import mohr_coulomb as mc
from ..results.writer import ResultWriter
from ..solvers.linear import resolve_backend
from ..solvers.static import SolverSettings, StaticSolver
from .build import build_mesh, build_model, build_stages, effects
from .scene import as_scene


def _output_selection(scene, mesh, model):
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
                "point": np.zeros(0, int), "normal": z, "shear_axes": np.zeros((0, dim - 1, dim)), "weight": np.zeros(0)}
    return {"x": np.vstack(xs), "set": np.concatenate(sets), "set_names": set_names, "element": np.concatenate(elems),
            "point": np.concatenate(pts), "normal": np.vstack(normals), "shear_axes": np.concatenate(axes),
            "weight": np.concatenate(weights)}


def _joint_results(groups, dim):
    if not groups:
        z = np.zeros(0)
        return {"opening": z, "slip": z.reshape(0, dim - 1), "plastic_slip": z.reshape(0, dim - 1),
                "t_normal": z, "t_shear": z.reshape(0, dim - 1), "state": z.astype(np.int8)}
    d = np.concatenate([g.delta.reshape(-1, dim) for g in groups])
    t = np.concatenate([g.traction.reshape(-1, dim) for g in groups])
    st = np.concatenate([g.state_committed.reshape(-1, mc.N_JOINT_STATE) for g in groups])
    return {"opening": d[:, -1], "slip": d[:, :-1], "plastic_slip": st[:, mc.S_PLASTIC_SLIP:mc.S_PLASTIC_SLIP + dim - 1],
            "t_normal": t[:, -1], "t_shear": t[:, :-1], "state": st[:, mc.S_CODE].astype(np.int8)}


class _Progress:
    def __init__(self, n_stages, enabled):
        self.bar = None
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=n_stages, unit="stage", bar_format="{l_bar}{bar}| {n:.2f}/{total} stages [{elapsed}]",
                            file=sys.stderr, leave=True)
        self.done = 0.0

    def __call__(self, stage_index, lam):
        if self.bar is not None:
            pos = stage_index + lam
            self.bar.update(pos - self.done)
            self.done = pos

    def close(self):
        if self.bar is not None:
            self.bar.close()


def run(scene, output: str | os.PathLike | None = None, progress: bool = False, summary: bool = False):
    """Run ``scene`` (a :class:`Scene`, a dict or a TOML path) and return the results as an
    ``xarray.Dataset`` (loaded in memory). With ``output`` the netCDF file is kept there; a run
    that fails keeps every converged step in that file (``completed = "false"``) and re-raises.
    """
    import xarray as xr

    t_start = time.perf_counter()
    sc = as_scene(scene)
    s = sc.normalized
    mesh = build_mesh(s, sc.base_dir)
    model = build_model(s, mesh)
    stages = build_stages(s, mesh, model)
    settings = SolverSettings(**s["solver"])
    backend = resolve_backend(settings.linear_solver)
    eff = effects(s, model)
    nodes, jgroups, set_names = _output_selection(s, mesh, model)
    dim = mesh.dim
    tmp = None
    if output is None:
        fd, tmp = tempfile.mkstemp(suffix=".nc", prefix="masonrydam_")
        os.close(fd)
        path = tmp
    else:
        path = str(output)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
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
    writer = ResultWriter(path, mesh.points, nodes, _joint_points(jgroups, set_names, dim), dim, attrs)
    bar = _Progress(len(stages), progress)
    last_iters = {"n": 0}

    def on_step(si, st, lam, u, f_int, f_ext):
        r = f_int - f_ext
        r[~(st.supports | st.prescribed)] = 0.0
        iters = solver.stats.iterations - last_iters["n"]
        last_iters["n"] = solver.stats.iterations
        writer.write_step(si, lam, iters, u.reshape(-1, dim)[nodes], r.reshape(-1, dim)[nodes], _joint_results(jgroups, dim))

    solver = StaticSolver(model, settings, on_step=on_step, progress=bar)
    try:
        solver.run(stages)
    except (MasonrydamError, KeyboardInterrupt) as exc:
        bar.close()
        writer.close(False, f"stopped: {type(exc).__name__}: {exc}", _stats_attrs(solver, t_start))
        if tmp is not None:
            os.unlink(tmp)
        else:
            exc.add_note(f"results of {writer.n} converged step(s) were kept in {path} (completed = false)")
        raise
    bar.close()
    stats = _stats_attrs(solver, t_start)
    writer.close(True, "completed", stats)
    ds = xr.load_dataset(path)
    if tmp is not None:
        os.unlink(tmp)
    if summary:
        print_summary(sc, mesh, model, eff, solver, stats, path if tmp is None else None, ds)
    return ds


def _stats_attrs(solver, t_start):
    st = solver.stats
    return {"steps": st.steps, "newton_iterations": st.iterations, "factorizations": st.factorizations,
            "step_cuts": st.step_cuts, "solve_wall_time_s": round(st.wall_time_s, 4),
            "total_wall_time_s": round(time.perf_counter() - t_start, 4), "per_stage": json.dumps(st.per_stage)}


def print_summary(sc, mesh, model, eff, solver, stats, path, ds, file=None):
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
                     f"{ps['step_cuts']} step cuts")
    lines.append(f"solver     : {solver.s.method}, {stats['factorizations']} factorization(s) "
                 f"[{resolve_backend(solver.s.linear_solver)}], {stats['newton_iterations']} iterations in total")
    if "joint_state" in ds and ds.sizes.get("joint_point", 0):
        last = ds.joint_state.isel(step=-1).values
        lines.append(f"joints end : {int((last == 0).sum())} stick, {int((last == 1).sum())} slip, "
                     f"{int((last == 2).sum())} open")
    u = ds.displacement.isel(step=-1)
    umax = float(np.abs(u).max())
    lines.append(f"max |u|    : {umax:.4g} m")
    lines.append(f"wall time  : {stats['total_wall_time_s']:.2f} s (solve {stats['solve_wall_time_s']:.2f} s)")
    if path:
        lines.append(f"results    : {path}")
    lines.append("=" * w)
    print("\n".join(lines), file=file)
