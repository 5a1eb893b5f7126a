"""The run's statistics (result attributes) and the one-screen summary printed after a run."""
from __future__ import annotations

import dataclasses
import json
import sys
import time

import numpy as np

from .._version import __version__
from ..solvers.dynamic import energy_warnings as dynamic_energy_warnings
from ..solvers.linear.direct import resolve_backend


def stats_attrs(solver, t_start, dyn_solvers=()):
    st = solver.stats
    out = {"steps": st.steps, "newton_iterations": st.iterations, "factorizations": st.factorizations,
           "symbolic_analyses": st.analyses, "preconditioner_reuses": st.preconditioner_reuses,
           "krylov_iterations": st.krylov_iterations, "joint_space_size": st.joint_space_size,
           "joint_space_steps": st.joint_space_steps, "joint_space_iterations": st.joint_space_iterations,
           "joint_space_splits": st.joint_space_splits,
           "joint_space_setup_s": round(st.joint_space_setup_s, 4),
           "joint_space_flexibility_columns": st.joint_space_flexibility_columns,
           "joint_space_flexibility_s": round(st.joint_space_flexibility_s, 4),
           "joint_space_compiled_steps": st.joint_space_compiled_steps,
           "joint_space_python_steps": st.joint_space_python_steps, "joint_space_holds": st.joint_space_holds,
           "joint_space_bond_latches": st.joint_space_bond_latches,
           "joint_space_fresh_budgets": st.joint_space_fresh_budgets,
           "step_cuts": st.step_cuts, "arc_length_steps": st.arc_length_steps,
           "arc_length_switches": st.arc_length_switches, "solve_wall_time_s": round(st.wall_time_s, 4),
           "total_wall_time_s": round(time.perf_counter() - t_start, 4), "per_stage": json.dumps(st.per_stage)}
    far = solver.model.far_slips()
    if far:
        out["joint_slip_warnings"] = " | ".join(far)
    if solver.limit is not None:
        out["limit_state"] = _limit_text(solver)
        out["limit_load_factor"] = float(solver.limit["load_factor"])
        out.update(solver.limit.get("attrs", {}))
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
            "dynamic_joint_space_compiled_steps": sum(x.joint_space_compiled_steps for x in d),
            "dynamic_joint_space_python_steps": sum(x.joint_space_python_steps for x in d),
            "dynamic_compiled_loop_steps": sum(x.compiled_loop_steps for x in d),
            "dynamic_compiled_loop_handbacks": sum(x.compiled_loop_handbacks for x in d),
            "dynamic_compiled_loop_off": "; ".join(sorted({x.compiled_loop_off for x in d if x.compiled_loop_off})),
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
    if lim.get("text"):
        text += "; " + lim["text"]
    return text


def _energy_warnings(dyn_solvers):
    """The energy warnings of the run (:func:`~masonrydam.solvers.dynamic.energy_warnings`): the energy
    terms are cumulative over the dynamic stages, so the last stage's solver speaks for the run, with the
    largest balance error of any stage."""
    if not dyn_solvers:
        return []
    last = dyn_solvers[-1]
    stats = dataclasses.replace(last.stats, energy_error_max=max(x.stats.energy_error_max for x in dyn_solvers))
    s = last.s
    dt = f"auto (tolerance {s.tolerance:g}, dt_min {s.dt_min:g} s)" if s.adaptive else f"{s.dt:g} s"
    return dynamic_energy_warnings(stats, s.integrator, dt)


def _kernel_note(compiled: int, python: int) -> str:
    """Which code solved the joint-space steps: the compiled step (one call a step) or the Python loop."""
    if not compiled and not python:
        return ""
    if not python:
        return "; every step compiled (one call a step)"
    if not compiled:
        return "; every step in the Python loop"
    return f"; {compiled} steps compiled (one call a step), {python} in the Python loop"


def _loop_note(compiled: int, handed_back: int, steps: int, off: str) -> str:
    """Which path took the dynamic steps: the compiled step loop (masonrydam.solvers.dynamic.compiled_loop) or the
    Python step, and why not the compiled loop where it was off."""
    if not compiled:
        return f"every step in Python ({off})" if off else "every step in Python"
    note = f"{compiled} of {steps} steps in the compiled loop"
    if handed_back:
        note += f", {handed_back} handed back to the Python step (they left its common path)"
    if off:
        note += f"; off in stages with {off}"
    return note


def _columns_note(columns, seconds, store_full=0):
    """The summary's note on the flexibility columns computed as steps needed them (large joint sets)."""
    if not columns:
        return ""
    full = f", {store_full} step(s) needed more than the store holds" if store_full else ""
    return f"; {columns} flexibility columns computed when first needed ({seconds:.3g} s{full})"


def print_summary(sc, mesh, model, eff, solver, stats, path, ds, file=None, dyn_solvers=(), effects=(),
                  t_start=None):
    """Print the one-screen summary of a run: the model and what it simulates, the static stages and the
    solver, the dynamic stages, the end state (joints, limit, modes, what the active ``effects`` report) and
    the wall time. ``eff``: the lines of ``simulated_effects``; ``stats``: :func:`stats_attrs`; ``ds``: the
    result dataset; ``path``: where it was kept (None: not kept); ``t_start``: the ``perf_counter`` value the
    wall time counts from, read as the summary is printed (None: the file's ``total_wall_time_s``, which
    ends when the writer closes)."""
    w = 72
    lines = (["=" * w, f"masonrydam {__version__} | scene '{sc.name}' ({sc.source})", "-" * w]
             + _model_lines(mesh, model, eff) + _static_lines(solver, stats, model)
             + _dynamic_lines(dyn_solvers, stats, model) + _end_lines(ds, stats, effects))
    wall = stats["total_wall_time_s"] if t_start is None else time.perf_counter() - t_start
    lines.append(f"wall time  : {wall:.2f} s (solve {stats['solve_wall_time_s']:.2f} s)")
    if path:
        lines.append(f"results    : {path}")
    lines.append("=" * w)
    print("\n".join(lines), file=file or sys.stdout)


def _model_lines(mesh, model, eff) -> list[str]:
    n_ip = sum(g.n_elem * g.nip for g in model.igroups)
    types = {}
    for b in mesh.blocks:
        types[b.type] = types.get(b.type, 0) + len(b.cells)
    jsets = {}
    for g in model.igroups:
        jsets[g.name] = jsets.get(g.name, 0) + g.n_elem
    lines = [f"model      : {mesh.dim}D, {model.n_nodes} nodes, {model.n_dof} DOFs, "
             + ", ".join(f"{n} {t}" for t, n in sorted(types.items())),
             "joints     : " + (", ".join(f"{k} {v} el." for k, v in sorted(jsets.items())) or "none")
             + f" ({n_ip} integration points)",
             "effects    : " + eff[0]]
    return lines + ["             " + e for e in eff[1:]]


def _relaxed_words(points) -> str:
    """The limit points a stage crossed by relaxing its joints (``[[stages]] limit_point = "relax"``), in words."""
    at = ", ".join(f"{lf:.4g}" for lf, _ in points[:4]) + (", ..." if len(points) > 4 else "")
    return (f"; past {len(points)} limit point(s) by relaxing the joints (at load factors {at}; "
            f"{sum(n for _, n in points)} hold steps)")


def _static_lines(solver, stats, model) -> list[str]:
    lines = []
    for ps in solver.stats.per_stage:
        lines.append(f"stage      : {ps['stage']}: {ps['steps']} steps, {ps['iterations']} Newton iterations, "
                     f"{ps['step_cuts']} step cuts"
                     + (f"; in its {ps['dissipation_control_steps']} steps under dissipation control the joints "
                        f"dissipated {ps['joint_dissipation_J']:.4g} J" if "joint_dissipation_J" in ps else "")
                     + (_relaxed_words(ps["relaxed_limit_points"]) if "relaxed_limit_points" in ps else ""))
    backend = resolve_backend(solver.s.linear_solver, n_dof=model.n_dof, dim=model.dim)
    if backend == "amg" and stats["newton_iterations"] and solver.s.method == "newton":
        lines.append(f"solver     : {solver.s.method}, {stats['newton_iterations']} general Newton iterations solved "
                     f"by AMG-preconditioned Krylov iterations ({stats['krylov_iterations']} in all, each correction "
                     f"to its inexact-Newton tolerance), {stats['factorizations']} multigrid set-up(s); "
                     f"{stats['preconditioner_reuses']} corrections used an earlier iteration's multigrid")
    else:
        lines.append(f"solver     : {solver.s.method}, {stats['factorizations']} factorization(s) "
                     f"[{backend}; {stats['symbolic_analyses']} symbolic analyses], {stats['newton_iterations']} "
                     "general Newton iterations")
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
                     + _columns_note(stats['joint_space_flexibility_columns'], stats['joint_space_flexibility_s'])
                     + _kernel_note(stats['joint_space_compiled_steps'], stats['joint_space_python_steps']))
    return lines


def _dynamic_lines(dyn_solvers, stats, model) -> list[str]:
    lines = []
    for dsol in dyn_solvers:
        for p in dsol.stats.per_stage:
            crit = f", dt_crit {p['dt_critical']:.3g} s" if p.get("dt_critical") else ""
            if p["dt"] == "auto":
                lines.append(f"dynamic    : {p['stage']}: {p['steps']} steps, dt = auto ({p['dt_smallest']:.3g} to "
                             f"{p['dt_largest']:.3g} s, tolerance {p['tolerance']:g}), {p['steps_rejected']} "
                             f"refused and retried smaller ({p['integrator']})")
            else:
                lines.append(f"dynamic    : {p['stage']}: {p['steps']} steps of {p['dt']:.4g} s ({p['integrator']}{crit})")
                if p.get("dt_reason"):
                    lines.append(f"             {p['dt_reason']}")
    if dyn_solvers:
        lines.append(f"dynamics   : {stats['dynamic_newton_iterations']} general Newton iterations, {stats['dynamic_substeps']} "
                     f"sub-step splits, {stats['dynamic_factorizations']} factorization(s) "
                     f"[all-stick matrix: {stats['dynamic_reference_solver'] or '-'}], "
                     f"{stats['dynamic_low_rank_solves']} low-rank solves, {stats['dynamic_ms_per_step']:.3g} ms/step")
        lines.append("step loop  : " + _loop_note(stats["dynamic_compiled_loop_steps"],
                                                  stats["dynamic_compiled_loop_handbacks"], stats["dynamic_steps"],
                                                  stats["dynamic_compiled_loop_off"]))
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
                         + _kernel_note(stats['dynamic_joint_space_compiled_steps'],
                                        stats['dynamic_joint_space_python_steps'])
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
    return lines


def _end_lines(ds, stats, effects) -> list[str]:
    lines = []
    stepped = ds.sizes.get("step", 0) > 0  # (a scene of modal stages alone records modes, no step)
    if stepped and "joint_state" in ds and ds.sizes.get("joint_point", 0):
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
    for effect in effects:
        lines += effect.summary_lines(ds)
    if stepped:
        umax = float(np.abs(ds.displacement.isel(step=-1)).max())
        lines.append(f"max |u|    : {umax:.4g} m")
    else:
        lines.append("steps      : none (modes only; the model at rest, joints as built)")
    return lines
