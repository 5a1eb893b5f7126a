"""Accuracy against cost of the seismic analyses: what each knob that trades accuracy
for speed buys, measured against converged references or closed forms.

    python benchmarks/accuracy_cost.py                 # the full study (about 15 min on one core)
    python benchmarks/accuracy_cost.py --quick         # a few runs of each kind (under a minute; tests)
    python benchmarks/accuracy_cost.py --cases koyna_linear sliding_block

Cases (scenes built from the bundled examples and test models):
- ``sliding_block``: Newmark (1965) rectangular pulse (examples/sliding_block_pulse.toml): permanent slip
  against the rigid-block closed form ``A (A - a_y) t0^2 / (2 a_y)`` and against the dt-converged
  elastic model (fixed dt = 1e-4 s; 0.27 % above the rigid block, see tests/solvers/test_time_steps_and_energy.py);
  knobs: dt, integrator, dt = "auto" tolerance, joint stiffness kn (1e9 to 1e12 Pa/m);
- ``rocking_block``: a 0.3 x 1.5 m block released at 0.02 alpha on a stiff no-tension joint (Housner
  1963): the time of the first impact against ``T/4 = acosh(1 / (1 - theta0/alpha)) / p``; knobs: dt,
  integrator;
- ``koyna_linear``: the Koyna section of examples/koyna_el_centro.toml with every joint linear (same
  stiffness), the first ``--duration`` s of El Centro at 0.5 g: crest displacement history (RMS and
  peak) against the finest run of its mesh (dt = 3.125e-4 s); knobs: dt, integrator, dt = "auto"
  tolerance, mesh size (three levels, against the finest mesh), element order, interface integration;
- ``koyna_mc``: the same with the example's Mohr-Coulomb joints: crest peak, residual base slip and
  largest residual lift-joint opening. The answer is path sensitive (brittle bonds, friction), so every
  setting is an ensemble of runs with dt nudged by -1 %, 0 and +1 % (and the Newton tolerance nudged),
  reported as median and spread against the median of the finest ensemble; knobs: dt, dt = "auto"
  tolerance, Newton force tolerance;
- ``wall``: the masonry wall of examples/wall_el_centro.toml: top displacement history and residual
  base slip against its finest dt, ensembles as for koyna_mc.

Cost is the solver's wall time per simulated second (output excluded: the ``dynamic_wall_time_s``
attribute), one BLAS thread, on this machine. Results go to ``--json`` (default
benchmarks/results/accuracy_cost.json) and the figures (error against cost, one curve per knob, log
axes) to ``--figures`` (default docs/figures/); the table printed at the end is the one in
docs/accuracy.md. The energy balance is recorded for each run but is no error estimate: it closes to
round-off at every dt (the numerical dissipation and the contact events are named terms).
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
# tests/ holds the scene builders (scenes.py), tests/solvers the free-rocking helper of test_dynamics
for p in (ROOT, ROOT / "tests", ROOT / "tests" / "solvers", Path(__file__).resolve().parent):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

from _common import cpu_model, pin_one_thread  # noqa: E402

from masonrydam.scene.schema import set_time_steps  # noqa: E402

G = 9.80665
EXAMPLES = ROOT / "examples"


# ---------------------------------------------------------------------------------------------- scenes
def _example(name: str) -> dict:
    return tomllib.loads((EXAMPLES / name).read_text())


def koyna_scene(law="mohr_coulomb", dt=0.01, duration=8.0, element_size=1.45, order=1, integration=None,
                integrator="hht", force_tolerance=None, kn=None, **stage) -> dict:
    """examples/koyna_el_centro.toml, first ``duration`` s, crest output every 0.01 s (or every step)."""
    sc = _example("koyna_el_centro.toml")
    sc["mesh"]["parameters"]["element_size"] = element_size
    if order != 1:
        sc["mesh"]["parameters"]["order"] = order
    for name, joint in sc["joints"].items():
        if law == "linear":
            joint = {"law": "linear", "normal_stiffness": joint["normal_stiffness"],
                     "shear_stiffness": joint["shear_stiffness"]}
        if kn is not None:
            joint["normal_stiffness"] = joint["shear_stiffness"] = kn
        if integration is not None:
            joint["integration"] = integration
        sc["joints"][name] = joint
    st = set_time_steps(sc["stages"][1], dt, duration=duration)
    st["integrator"] = integrator
    if integrator != "hht":
        st.pop("alpha", None)
    if force_tolerance is not None:
        st["force_tolerance"] = force_tolerance
    grid = 0.01 if dt == "auto" or abs(0.01 / dt - round(0.01 / dt)) < 1e-9 else dt
    st["output"] = {"dt": grid, "nodes": ["crest"]}
    if dt == "auto":
        st.setdefault("dt_max", 0.01)
    st.update(stage)
    return sc


def wall_scene(dt=0.005, duration=None, force_tolerance=None, **stage) -> dict:
    sc = _example("wall_el_centro.toml")
    st = set_time_steps(sc["stages"][-1], dt, duration=duration)
    if force_tolerance is not None:
        st["force_tolerance"] = force_tolerance
    st["output"] = {"dt": 0.01 if dt == "auto" else dt * max(1, round(0.01 / dt)), "nodes": ["top"]}
    if dt == "auto":
        st.setdefault("dt_max", 0.01)
    st.update(stage)
    return sc


# ---------------------------------------------------------------------------------------------- runs
def run_scene(sc: dict) -> tuple:
    """(dataset, record of cost and energy)."""
    import masonrydam
    from masonrydam.scene.scene import Scene

    t0 = time.perf_counter()
    ds = masonrydam.run(Scene(sc, base_dir=EXAMPLES), output=None)
    wall = time.perf_counter() - t0
    a = ds.attrs
    stage = json.loads(a["dynamic_per_stage"])[-1]
    dyn = ds.isel(step=np.flatnonzero(ds.stage.values == ds.stage.values.max()))
    simulated = float(dyn.time.values[-1] - dyn.time.values[0])
    rec = {"wall_s": round(wall, 3), "solve_s": round(float(a["dynamic_wall_time_s"]), 3),
           "s_per_simulated_s": float(a["dynamic_wall_time_s"]) / simulated, "steps": int(a["dynamic_steps"]),
           "rejected": int(a.get("dynamic_steps_rejected", 0)), "dt_smallest": float(a["dynamic_dt_smallest"]),
           "energy_error": float(a["energy_error_relative"]),
           "energy_numerical": float(a["energy_numerical_relative"]),
           "energy_contact": float(a["energy_contact_relative"]), "warnings": a["energy_warnings"],
           "stage": stage}
    return dyn, rec


def crest_history(dyn) -> tuple:
    """(time (s), horizontal displacement (m)) of the recorded node that moves most, on the output grid."""
    ux = dyn.displacement.sel(component="x").values  # (step, node)
    return dyn.time.values - dyn.time.values[0], ux[:, int(np.argmax(np.abs(ux).max(axis=0)))]


def joint_residuals(dyn) -> dict:
    """Residual (last step) base-joint slip (m, mean over its points) and largest lift-joint opening."""
    names = json.loads(dyn.joint_set.attrs["set_names"])
    last = dyn.isel(step=-1)
    out = {}
    for k, name in enumerate(names):
        sel = dyn.joint_set.values == k
        if not sel.any():
            continue
        slip = last.joint_slip.values[sel, 0]
        opening = last.joint_opening.values[sel]
        out[f"{name}_slip"] = float(np.mean(slip))
        out[f"{name}_opening_max"] = float(np.max(opening))
    return out


def rms_error(hist, ref) -> float:
    """RMS of the difference of two (time, value) histories over the RMS of the reference, on the
    reference's times (the other interpolated linearly: runs with a nudged dt have other grids)."""
    (t, u), (tr, ur) = hist, ref
    keep = tr <= t[-1] + 1e-9
    ui = np.interp(tr[keep], t, u)
    return float(math.sqrt(np.mean((ui - ur[keep]) ** 2) / np.mean(ur[keep] ** 2)))


# ---------------------------------------------------------------------------------------------- cases
def case_sliding_block(quick: bool) -> list:
    from scenes import sliding_block

    A, mu, t0 = 0.4 * G, 0.2, 0.2
    ay = mu * G
    rigid = A * (A - ay) * t0**2 / (2 * ay)

    def one(knob, value, **kw):
        sc = sliding_block(shape="rectangular", amplitude=A, pulse=t0, mu=mu, duration=0.5, **kw)
        dyn, rec = run_scene(sc)
        s = -float(dyn.joint_slip.isel(step=-1).values.mean())
        rec.update(case="sliding_block", knob=knob, value=value, slip=s)
        return rec

    out = []
    ref = one("reference", "dt = 1e-4 s", dt=1e-4, output={"dt": 0.05})
    out.append(ref)
    dts = [0.01, 0.0025] if quick else [0.02, 0.01, 0.005, 0.0025, 0.00125, 0.000625, 0.0003125]
    for dt in dts:
        out.append(one("dt", dt, dt=dt))
    for integ in (["newmark_average"] if quick else ["newmark_average", "generalized_alpha"]):
        for dt in ([0.0025] if quick else [0.01, 0.0025, 0.000625]):
            out.append(one(f"integrator {integ}", dt, dt=dt, integrator=integ))
    if not quick:
        for dt in [5e-5, 2.5e-5, 1.25e-5]:  # central difference: dt below the critical step (6.3e-5 s)
            out.append(one("integrator central_difference", dt, dt=dt, integrator="central_difference",
                           output={"dt": 0.01}))
    for tol in ([1e-4] if quick else [1e-2, 1e-3, 1e-4, 1e-5, 1e-6]):
        out.append(one("dt auto tolerance", tol, dt="auto", tolerance=tol, dt_max=0.05, output={"dt": 0.05}))
    if not quick:
        for kn in [1e9, 1e10, 1e11, 1e12]:
            out.append(one("kn (dt auto 1e-5)", kn, dt="auto", tolerance=1e-5, dt_max=0.05, output={"dt": 0.05}, kn=kn))
    for r in out:
        r["error_vs_converged"] = abs(r["slip"] - ref["slip"]) / ref["slip"]
        r["error_vs_rigid"] = abs(r["slip"] - rigid) / rigid
        # the penalty stiffness changes the model: its runs are measured against the rigid block
        r["error"] = r["error_vs_rigid"] if r["knob"].startswith("kn") else r["error_vs_converged"]
        r["measure"] = "permanent slip" + (" vs rigid block" if r["knob"].startswith("kn") else "")
    return out


def case_rocking_block(quick: bool) -> list:
    from test_dynamics import B, H, free_rocking

    out = []
    R = math.hypot(B / 2, H / 2)
    p = math.sqrt(3 * G / (4 * R))
    settings = [("dt", "hht", dt) for dt in ([2e-3, 5e-4] if quick else [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4])]
    if not quick:
        settings += [("integrator newmark_average", "newmark_average", dt) for dt in [2e-3, 5e-4]]
        settings += [("integrator generalized_alpha", "generalized_alpha", dt) for dt in [2e-3, 5e-4]]
    for knob, integ, dt in settings:
        t0 = time.perf_counter()
        kw = {"alpha": -0.1} if integ == "hht" else {}
        t, th, e_mech, th0, alpha = free_rocking(integ, dt, duration=0.2, **kw)
        wall = time.perf_counter() - t0
        T4 = math.acosh(1 / (1 - th0 / alpha)) / p
        i = np.nonzero(th <= 0)[0][0]
        tc = t[i - 1] + (t[i] - t[i - 1]) * th[i - 1] / (th[i - 1] - th[i])
        # against Housner's T/4 for the rigid block; the small-displacement model itself is 0.3 % off it
        # at this theta0 (tests/solvers/test_dynamics.py): errors below that say nothing more
        out.append({"case": "rocking_block", "knob": knob, "value": dt, "measure": "time of first impact",
                    "error": abs(tc - T4) / T4, "wall_s": wall, "solve_s": wall, "s_per_simulated_s": wall / 0.2,
                    "steps": int(round(0.2 / dt)), "energy_growth": float(e_mech.max())})
    return out


def case_koyna_linear(quick: bool, duration: float) -> list:
    dur = 2.0 if quick else duration
    out = []

    def one(knob, value, ref_key, **kw):
        dyn, rec = run_scene(koyna_scene("linear", duration=dur, **kw))
        rec.update(case="koyna_linear", knob=knob, value=value, ref=ref_key, crest=crest_history(dyn))
        out.append(rec)
        return rec

    coarse = 2.9 if quick else 1.45
    ref = one("reference", "dt = 3.125e-4 s" if not quick else "dt = 1.25e-3 s", "dt",
              dt=3.125e-4 if not quick else 1.25e-3, element_size=coarse)
    for dt in ([0.01, 0.005] if quick else [0.02, 0.01, 0.005, 0.0025, 0.00125, 0.000625]):
        one("dt", dt, "dt", dt=dt, element_size=coarse)
    if not quick:
        for integ in ["newmark_average", "generalized_alpha"]:
            for dt in [0.01, 0.0025]:
                one(f"integrator {integ}", dt, "dt", dt=dt, integrator=integ, element_size=coarse)
        for tol in [1e-3, 1e-4, 1e-5, 1e-6]:
            one("dt auto tolerance", tol, "dt", dt="auto", tolerance=tol, element_size=coarse)
        one("dt auto tolerance", "default", "dt", dt="auto", element_size=coarse)
        # space, at dt = 1.25e-3 s, against the most accurate discretization tried: quadratic elements
        # on the 1.45 m mesh (the linear elements on a 0.725 m mesh are 0.5 % from it, those on 2.9 m
        # quadratic elements 0.4 %: measured in this study)
        fine = one("reference mesh", "order 2, element_size 1.45 m", "mesh", dt=0.00125, element_size=1.45, order=2)
        for h in [2.9, 1.45, 0.725]:
            one("mesh size", h, "mesh", dt=0.00125, element_size=h)
        one("element order 2", 2.9, "mesh", dt=0.00125, element_size=2.9, order=2)
        one("interface integration gauss", 1.45, "mesh", dt=0.00125, element_size=1.45, integration="gauss")
    else:
        fine = None
    for r in out:
        base = ref if r["ref"] == "dt" else fine
        r["error"] = rms_error(r["crest"], base["crest"])
        peak, peak_ref = np.abs(r["crest"][1]).max(), np.abs(base["crest"][1]).max()
        r["error_peak"] = float(abs(peak - peak_ref) / peak_ref)
        r["peak_mm"] = 1e3 * float(peak)
        r["measure"] = "crest displacement RMS"
    return out


def case_path_sensitive(name: str, quick: bool, duration: float) -> list:
    """koyna_mc or wall: ensembles of 3 runs per setting (dt nudged by -1 %, 0, +1 %)."""
    nudges = [1.0] if quick else [0.99, 1.0, 1.01]
    out = []

    def member(nudge, **kw):
        dt = kw.pop("dt")
        dt_run = dt * nudge if dt != "auto" else "auto"
        extra = {}
        if dt == "auto":
            extra["tolerance"] = kw.pop("tolerance") * nudge
        if name == "koyna_mc":
            sc = koyna_scene("mohr_coulomb", dt=dt_run, duration=2.0 if quick else duration, **kw, **extra)
        else:
            sc = wall_scene(dt=dt_run, duration=2.0 if quick else None, **kw, **extra)
        dyn, rec = run_scene(sc)
        rec.update(crest=crest_history(dyn), **joint_residuals(dyn))
        rec["peak_mm"] = 1e3 * float(np.abs(rec["crest"][1]).max())
        return rec

    def setting(knob, value, **kw):
        ms = [member(n, **kw) for n in nudges]
        out.append({"case": name, "knob": knob, "value": value, "members": ms,
                    "s_per_simulated_s": statistics.median(m["s_per_simulated_s"] for m in ms),
                    "solve_s": statistics.median(m["solve_s"] for m in ms),
                    "steps": statistics.median(m["steps"] for m in ms)})

    base_dt = 0.01 if name == "koyna_mc" else 0.005
    dts = [base_dt, base_dt / 2] if quick else [base_dt, base_dt / 2, base_dt / 4, base_dt / 8, base_dt / 16]
    for dt in dts:
        setting("dt", dt, dt=dt)
    if not quick:
        for tol in [1e-4, 1e-5]:
            setting("dt auto tolerance", tol, dt="auto", tolerance=tol)
        for ft in [1e-3, 1e-4, 1e-8]:
            setting("Newton force_tolerance", ft, dt=base_dt / 4, force_tolerance=ft)
    ref = [r for r in out if r["knob"] == "dt"][-1]  # the finest dt
    measures = ["peak_mm", "steps"] + sorted(k for k in ref["members"][0] if k.endswith("_slip") or k.endswith("_opening_max"))
    for r in out:
        r["measure"] = ("crest" if name == "koyna_mc" else "top") + " displacement RMS (ensemble median)"
        errs = [rms_error(m["crest"], ref_m["crest"]) for m in r["members"] for ref_m in ref["members"]]
        r["error"] = statistics.median(errs)
        r["summary"] = {}
        for key in measures:
            vals = [m.get(key, float("nan")) for m in r["members"]]
            r["summary"][key] = {"median": statistics.median(vals), "min": min(vals), "max": max(vals)}
    return out


# ---------------------------------------------------------------------------------------------- report
def figures(results: list, folder: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    cases = sorted({r["case"] for r in results})
    paths = []
    for case in cases:
        rs = [r for r in results if r["case"] == case and not r["knob"].startswith("reference")]
        fig, ax = plt.subplots(figsize=(6.4, 4.4))
        for knob in sorted({r["knob"] for r in rs}):
            pts = sorted(((r["s_per_simulated_s"], max(r["error"], 1e-7), r["value"]) for r in rs if r["knob"] == knob),
                         key=lambda x: x[0])
            if not pts:
                continue
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=knob)
            for x, y, v in pts:
                ax.annotate(f"{v:g}" if isinstance(v, float) else str(v), (x, y), fontsize=6, xytext=(2, 2),
                            textcoords="offset points")
        ax.set_xlabel("solver wall time per simulated second [s/s]")
        ax.set_ylabel(f"relative error ({rs[0]['measure'] if rs else ''})")
        ax.set_title(f"{case}: error against cost")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        fig.tight_layout()
        path = folder / f"accuracy_{case}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def table(results: list) -> str:
    """Markdown: every setting with its error and cost, and for each case the cheapest setting that
    reaches 10 %, 5 %, 1 % and 0.1 %."""
    lines = ["| case | knob | value | error | measure | steps | s per simulated s |", "|---|---|---|---|---|---|---|"]
    for r in results:
        if r["knob"].startswith("reference"):
            continue
        lines.append(f"| {r['case']} | {r['knob']} | {r['value']} | {100 * r['error']:.3g} % | {r['measure']} | "
                     f"{r['steps']:g} | {r['s_per_simulated_s']:.3g} |")
    lines += ["", "| to get | on | use | it costs (s per simulated s) |", "|---|---|---|---|"]
    for case in sorted({r["case"] for r in results}):
        rs = [r for r in results if r["case"] == case and not r["knob"].startswith("reference")]
        for target in (0.10, 0.05, 0.01, 0.001):
            ok = [r for r in rs if r["error"] <= target]
            if ok:
                best = min(ok, key=lambda r: r["s_per_simulated_s"])
                lines.append(f"| {100 * target:g} % | {case} ({best['measure']}) | {best['knob']} = {best['value']} | "
                             f"{best['s_per_simulated_s']:.3g} |")
            else:
                lines.append(f"| {100 * target:g} % | {case} | not reached by the settings tried | |")
    return "\n".join(lines)


def ensemble_table(results: list) -> str:
    lines = ["| case | knob | value | measure | median | spread (min to max) |", "|---|---|---|---|---|---|"]
    for r in results:
        for key, s in r.get("summary", {}).items():
            lines.append(f"| {r['case']} | {r['knob']} | {r['value']} | {key} | {s['median']:.4g} | "
                         f"{s['min']:.4g} to {s['max']:.4g} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a few runs of each kind (under a minute)")
    ap.add_argument("--cases", nargs="+", default=["sliding_block", "rocking_block", "koyna_linear", "koyna_mc", "wall"])
    ap.add_argument("--duration", type=float, default=8.0, help="seconds of El Centro for the Koyna cases (default 8)")
    ap.add_argument("--json", type=Path, default=ROOT / "benchmarks" / "results" / "accuracy_cost.json")
    ap.add_argument("--figures", type=Path, default=ROOT / "docs" / "figures")
    args = ap.parse_args(argv)
    pin_one_thread()
    print(f"# accuracy against cost ({'quick' if args.quick else 'full'}), {cpu_model()}", flush=True)
    results = []
    for case in args.cases:
        t0 = time.perf_counter()
        if case == "sliding_block":
            rs = case_sliding_block(args.quick)
        elif case == "rocking_block":
            rs = case_rocking_block(args.quick)
        elif case == "koyna_linear":
            rs = case_koyna_linear(args.quick, args.duration)
        elif case in ("koyna_mc", "wall"):
            rs = case_path_sensitive(case, args.quick, args.duration)
        else:
            raise SystemExit(f"unknown case {case!r}")
        results += rs
        print(f"## {case}: {len(rs)} settings in {time.perf_counter() - t0:.1f} s", flush=True)
        for r in rs:
            print(f"   {r['knob']:32s} {str(r['value']):22s} error {100 * r['error']:9.4g} %  "
                  f"{r['s_per_simulated_s']:8.3g} s/s  steps {r['steps']:g}", flush=True)
    print()
    print(table(results))
    print()
    print(ensemble_table(results))
    if not args.quick:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        slim = [{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items() if k != "crest"}
                for r in results]
        for r in slim:
            for m in r.get("members", []):
                m.pop("crest", None)
        # the cases not run this time keep their earlier results (a study can be redone case by case)
        done = {r["case"] for r in slim}
        if args.json.exists():
            slim = [r for r in json.loads(args.json.read_text()) if r["case"] not in done] + slim
        args.json.write_text(json.dumps(slim, indent=1, default=str))
        for p in figures(slim, args.figures):
            print(f"figure: {p}")
        print()
        print(table(slim))
    return results


if __name__ == "__main__":
    main()
