"""3D dams in strong shaking: the explicit step against a sparse product, the water and
the rock against the dry dam, the example's 20 s, and how converged the answer is.

    . .venv/bin/activate
    python benchmarks/bench_dam_3d_earthquake.py step        # ms per explicit step vs one sparse product (~3 min)
    python benchmarks/bench_dam_3d_earthquake.py water       # dry / Westergaard + rock with mass, per simulated s (~4 min)
    python benchmarks/bench_dam_3d_earthquake.py acoustic    # no water / Westergaard / acoustic water, explicit (~5 min)
    python benchmarks/bench_dam_3d_earthquake.py example     # examples/dam_3d_earthquake.toml as it is (~10 min)
    python benchmarks/bench_dam_3d_earthquake.py large       # element_size 3 (166 000 DOF): gravity, explicit steps (~15 min)
    python benchmarks/bench_dam_3d_earthquake.py accuracy    # dt_auto, dt_auto/2, dt_auto/4 over the strong part (~25 min)
    python benchmarks/bench_dam_3d_earthquake.py schemes     # explicit vs implicit trapezoidal rule, weak shaking (over 1 h:
                                                             # the implicit steps take about 1 s each at element_size 10)

All cases are ``examples/dam_3d_earthquake.toml`` (8 monoliths, 42 021 DOF, 8 096 joint points at element_size
6: gravity of the dam, the reservoir at 57 m with uplift, its modes, El Centro 1940 NS along y and EW along x at
0.5 g and the vertical at 1/3 g, central difference with dt = "auto" and 5 % local damping, Westergaard's added
mass, rock with mass and absorbing boundaries, motion within the rock), changed as each case says. Each run is a
subprocess of its own with one thread for numba, OpenMP, MKL and OpenBLAS, after an untimed run of the same scene
on a coarse mesh that fills the numba cache.

Printed: the CPU model, then per case the figures and the target it answers, with the figure
of an earlier version (on the 2-core EPYC of docs/performance.md, or on a 2-core Xeon at 2.5 GHz
where marked, about 2.6x slower).

* ``step``: the dry dam (no water in the shaking, rock with density on a fixed base, no damping: the target's case),
  0.5 s of shaking: ms per step of the explicit loop (its set-up excluded), the time of one product of the blocks'
  stiffness K_c and of the all-stick stiffness K (blocks and joints, free DOFs) with a vector, measured in the same
  process, and the ratio. Then the same with 5 % local damping (no effect on the step) and with 5 % Rayleigh
  damping at 2 and 10 Hz (its stiffness part cuts the stable step; the program's step and its reason).
* ``water``: seconds of wall per simulated second, dry (as ``step``) and with the example's water and rock (the
  target: "water at most 2x the dry cost").
* ``acoustic``: seconds of wall per simulated second of the example's shaking (its rock with mass and absorbing
  boundaries, local damping) with no water in the shaking (``dynamic = "none"``: the static pressure stays),
  with Westergaard's added mass (the example) and with the acoustic reservoir (compressible water, c = 1440 m/s,
  3 H long, Sommerfeld far end, rigid bottom) stepped with the dam's central difference
  (masonrydam/solvers/dynamic/fluid.py, ExplicitAcoustic); the stable step and its reason for each (target: the
  water at most 2x the dry cost per simulated second).
* ``example``: the whole example: wall time per stage, total, peak memory (target: at most 10 minutes).
* ``large``: the dry dam at element_size 3 (about 166 000 DOF): the gravity stage's time and the run's peak memory,
  then ``--large-duration`` s (default 0.1) of the shaking: ms per step and the 20 s record projected.
* ``accuracy``: the first ``--window`` s (default 4) of the example's shaking at the program's step, at half of it
  and at a quarter: the crest's largest displacement along the stream and across, and the largest opening of a
  contraction joint; the differences of the crest history (largest over the window, relative to its peak) and of
  the largest opening against the quarter step. The energy balance error is printed for each.
* ``schemes``: a weak record (El Centro at ``--weak-pga`` g, default 0.05, along y only, first 3 s) on the same dam
  meshed at ``--schemes-element-size`` (default 10 m: the implicit steps cost 0.5 s each at 6 m), with 2 %
  mass-proportional damping and no local damping: central difference at its stable step against the
  implicit trapezoidal rule (newmark_average, no numerical damping) at dt 0.0025 and 0.00125 s: the crest history
  difference; on this record both converge (the implicit pair shows its own convergence).

This is a benchmark, not a test: it never fails on a slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import copy
import json
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _common import RssSampler, cpu_model  # noqa: E402

EXAMPLE = ROOT / "examples" / "dam_3d_earthquake.toml"


def example_scene() -> dict:
    return tomllib.loads(EXAMPLE.read_text())


def dry(scene: dict) -> dict:
    """No water in the shaking, the rock's mass on a fixed base (no [foundation]), no damping."""
    sc = copy.deepcopy(scene)
    sc["reservoir"]["dynamic"] = "none"
    sc.pop("foundation", None)
    sc["stages"][-1].pop("damping", None)
    return sc


def acoustic(scene: dict) -> dict:
    """The example's reservoir as acoustic elements (compressible water, c = 1440 m/s, the defaults otherwise:
    3 H long with a Sommerfeld far end, rigid bottom) instead of Westergaard's added mass."""
    sc = copy.deepcopy(scene)
    sc["reservoir"]["dynamic"] = "acoustic"
    sc["reservoir"]["acoustic"] = {"sound_speed": 1440.0}
    return sc


def shaking(scene: dict, duration: float, **stage) -> dict:
    """The scene with its modal stage left out and its last stage ``duration`` s long (stage keys replaced)."""
    sc = copy.deepcopy(scene)
    sc["stages"] = [s for s in sc["stages"] if s.get("type") != "modal"]
    sc["stages"][-1]["duration"] = duration
    sc["stages"][-1].update(stage)
    return sc


def child(spec):
    """Run one scene (after a warm-up on a coarse mesh) and print its figures as a JSON line."""
    import numpy as np
    import scipy.sparse as sp

    import masonrydam
    import masonrydam.solvers.dynamic.solver as solver_module
    from masonrydam.assembly.elastic import elastic_tangent_data

    warm = copy.deepcopy(spec["scene"])
    warm["mesh"]["parameters"]["element_size"] = 20.0
    warm["stages"] = [s for s in warm["stages"] if s.get("type") != "modal"]
    warm["stages"][-1]["duration"] = 0.02
    masonrydam.run(warm)

    loop = {}
    run_explicit = solver_module.run_central_difference

    def timed(model, settings, eq, energy, stats, stage, st, *rest):
        t0, n0 = time.perf_counter(), stats.steps
        out = run_explicit(model, settings, eq, energy, stats, stage, st, *rest)
        loop.update(loop_s=time.perf_counter() - t0, steps=stats.steps - n0, dt=settings.dt)
        if spec.get("products"):
            x = np.random.default_rng(0).random(model.n_dof)
            Kc = model.K_continuum
            K = sp.csr_matrix((elastic_tangent_data(model), model.indices, model.indptr),
                              shape=(eq.n, eq.n))
            xf = x[eq.free]
            for name, A, v in (("Kc", Kc, x), ("K", K, xf)):
                A @ v
                t0 = time.perf_counter()
                for _ in range(100):
                    A @ v
                loop[f"product_{name}_ms"] = (time.perf_counter() - t0) * 10.0
                loop[f"product_{name}_nnz"] = int(A.nnz)
        return out

    solver_module.run_central_difference = timed
    with tempfile.TemporaryDirectory() as tmp, RssSampler() as rss:
        t0 = time.perf_counter()
        ds = masonrydam.run(spec["scene"], Path(tmp) / "out.nc")
        wall = time.perf_counter() - t0
        a = dict(ds.attrs)
        out = {"wall_s": wall, "peak_gib": rss.peak / 2**30, "n_dof": None}  # in bytes inside the block (MiB after it)
        stage_names = json.loads(ds.stage.attrs["stage_names"])
        dyn = int(np.max(ds.stage.values))
        steps = ds.stage.values == dyn
        t = ds.time.values[steps]
        crest = ds.displacement.values[steps]  # (step, node, component)
        out.update(time=t.tolist(), crest_y=crest[:, :, 1].mean(axis=1).tolist(),
                   crest_x=crest[:, :, 0].mean(axis=1).tolist())
        set_names = json.loads(ds.joint_set.attrs["set_names"])
        cj = ds.joint_set.values == set_names.index("contraction_joints")
        out["max_contraction_opening_m"] = float(np.nanmax(ds.joint_opening.values[steps][:, cj]))
        for k in ("dynamic_steps", "dynamic_ms_per_step", "dynamic_wall_time_s", "dynamic_energy_error_relative",
                  "energy_error_relative", "solve_wall_time_s", "total_wall_time_s", "dynamic_per_stage",
                  "per_stage", "completed", "energy_warnings"):
            v = a.get(k)
            out[k] = v.item() if hasattr(v, "item") else v
        out["stages"] = stage_names
        ds.close()
    out.update(loop)
    print("JSON:" + json.dumps(out), flush=True)


def run(label, scene, timeout=7200, products=False):
    spec = {"scene": scene, "products": products}
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, __file__, "--child", json.dumps(spec)], capture_output=True, text=True,
                       timeout=timeout)
    lines = [x for x in p.stdout.splitlines() if x.startswith("JSON:")]
    if p.returncode or not lines:
        print(f"[{label}] failed (exit {p.returncode}): {p.stderr.strip().splitlines()[-3:]}", flush=True)
        return None
    r = json.loads(lines[-1][5:])
    r["process_s"] = time.perf_counter() - t0
    return r


def step_line(label, r, before=""):
    ms = 1e3 * r["loop_s"] / max(r["steps"], 1)
    reason = json.loads(r["dynamic_per_stage"])[-1].get("dt_reason", "") if r.get("dynamic_per_stage") else ""
    s = (f"[{label}] {r['steps']} steps of {r['dt']:.4g} s: {ms:.2f} ms/step (loop), "
         f"{ms / (r['dt'] * 1e3):.1f} s of wall per simulated s")
    if "product_Kc_ms" in r:
        s += (f"; one product K_c x {r['product_Kc_ms']:.2f} ms (nnz {r['product_Kc_nnz']}), K x "
              f"{r['product_K_ms']:.2f} ms (nnz {r['product_K_nnz']}): step = {ms / r['product_K_ms']:.2f} x K x")
    print(s + (f" | before: {before}" if before else ""), flush=True)
    if reason:
        print(f"    {reason}", flush=True)
    return ms


def case_step(a):
    sc = dry(example_scene())
    r = run("dry", shaking(sc, a.duration), products=True)
    if r:
        step_line("explicit, dry dam, no damping", r, "(Xeon) 40.5 ms/step at dt_crit 1.96e-4 s, 238 s of wall per "
                  "simulated s, about 7 sparse products")
    r = run("local", shaking(sc, a.duration, damping={"model": "local", "ratio": 0.05}))
    if r:
        step_line("explicit, dry dam, 5 % local damping", r)
    r = run("rayleigh", shaking(sc, a.duration, damping={"ratio": 0.05, "frequencies": [2.0, 10.0]}))
    if r:
        step_line("explicit, dry dam, 5 % Rayleigh at 2 and 10 Hz", r, "(Xeon) dt_crit fell to 2.1e-5 s with "
                  "stiffness-proportional Rayleigh damping")


def case_water(a):
    sc = example_scene()
    r_dry = run("dry", shaking(dry(sc), a.duration, damping={"model": "local", "ratio": 0.05}))
    r_wet = run("wet", shaking(sc, a.duration))
    if r_dry and r_wet:
        ms_dry = step_line("dry dam, local damping", r_dry)
        ms_wet = step_line("Westergaard water + rock with mass and absorbing boundaries, local damping", r_wet)
        per_s_dry, per_s_wet = ms_dry / r_dry["dt"] / 1e3, ms_wet / r_wet["dt"] / 1e3
        print(f"[water] {per_s_wet:.1f} against {per_s_dry:.1f} s of wall per simulated s: {per_s_wet / per_s_dry:.2f}x "
              "the dry cost (target: at most 2x)", flush=True)


def case_acoustic(a):
    sc = example_scene()
    no_water = copy.deepcopy(sc)
    no_water["reservoir"]["dynamic"] = "none"
    per_s = {}
    for label, scene in (("no water in the shaking", no_water), ("Westergaard's added mass", sc),
                         ("acoustic water (explicit)", acoustic(sc))):
        r = run(label, shaking(scene, a.duration))
        if r:
            ms = step_line(f"{label}, rock with mass, local damping", r)
            per_s[label] = ms / r["dt"] / 1e3
    dry_s = per_s.get("no water in the shaking")
    if dry_s:
        for label, x in per_s.items():
            print(f"[acoustic] {label}: {x:.1f} s of wall per simulated s, {x / dry_s:.2f}x the cost without water "
                  "(target for the water: at most 2x)", flush=True)


def case_example(a):
    r = run("example", example_scene())
    if r:
        per = json.loads(r["per_stage"]) if r.get("per_stage") else []
        print(f"[example] {r['wall_s']:.0f} s in all (process {r['process_s']:.0f} s), peak {r['peak_gib']:.2f} GiB, "
              f"completed {r['completed']}; dynamic {r['dynamic_wall_time_s']:.0f} s for {r['dynamic_steps']} steps "
              f"({r['dynamic_ms_per_step']:.2f} ms/step with set-up and output); static stages "
              f"{r.get('solve_wall_time_s') or float('nan'):.0f} s ("
              + ", ".join(f"{p.get('stage')}: {p.get('steps')} steps, {p.get('iterations')} iterations" for p in per)
              + ") | before: the strong record did not finish (implicit: minutes per step from t = 1.75 s)", flush=True)
        print(f"    largest contraction-joint opening {1e3 * r['max_contraction_opening_m']:.2f} mm; energy balance "
              f"error {r.get('energy_error_relative')}; warnings: {r.get('energy_warnings') or 'none'}", flush=True)


def _compare(runs, reference_label):
    import numpy as np

    ref = runs[reference_label]
    tr = np.asarray(ref["time"])
    for label, r in runs.items():
        t = np.asarray(r["time"])
        line = (f"[{label}] dt {r['dt']:.4g} s: crest peak y {1e3 * np.abs(r['crest_y']).max():.3f} mm, "
                f"x {1e3 * np.abs(r['crest_x']).max():.3f} mm, largest contraction opening "
                f"{1e3 * r['max_contraction_opening_m']:.3f} mm, energy error {r.get('energy_error_relative')}, "
                f"{1e3 * r['loop_s'] / r['steps']:.2f} ms/step, {r['loop_s']:.0f} s")
        if label != reference_label:
            parts = []
            for comp in ("crest_y", "crest_x"):
                yr = np.interp(t, tr, ref[comp])
                parts.append(f"{comp} history differs by {100 * np.abs(np.asarray(r[comp]) - yr).max() / np.abs(yr).max():.2f} %"
                             " of its peak")
            ro = ref["max_contraction_opening_m"]
            parts.append(f"largest opening by {100 * (r['max_contraction_opening_m'] - ro) / ro:+.2f} %")
            line += f" | against {reference_label}: " + ", ".join(parts)
        print(line, flush=True)


def case_large(a):
    if a.wet:
        # the example as it is (gravity, the reservoir with uplift and full head in cracks, Westergaard water, the
        # rock with mass and absorbing sides, local damping) at element_size 3, without its modal stage
        sc = shaking(example_scene(), a.large_duration, output={"dt": 0.02, "nodes": ["crest"]})
        sc["mesh"]["parameters"]["element_size"] = 3.0
        r = run("large, wet", sc, products=True)
        if r:
            ms = step_line("explicit, the example's wet dam at element_size 3", r, "not run before")
            stages = "; ".join(f"{x['stage']}: {x['steps']} steps, {x['iterations']} iterations, {x['step_cuts']} cuts"
                               for x in json.loads(r["per_stage"]))
            print(f"[large, wet] static stages {r.get('solve_wall_time_s') or float('nan'):.0f} s ({stages}); "
                  f"run {r['wall_s']:.0f} s in all, peak {r['peak_gib']:.2f} GiB; 20 s of shaking at this step: "
                  f"{20 * ms / r['dt'] / 1e3 / 60:.0f} min projected (target: the whole run in at most 1 hour)",
                  flush=True)
        return
    sc = dry(example_scene())
    sc["mesh"]["parameters"]["element_size"] = 3.0
    sc.pop("reservoir")
    sc["stages"] = [sc["stages"][0], dict(sc["stages"][-1], duration=a.large_duration,
                                          output={"dt": 0.02, "nodes": ["crest"]})]
    r = run("large", sc, products=True)
    if r:
        grav = r.get("solve_wall_time_s") or float("nan")  # the static stages: gravity alone here
        ms = step_line("explicit, dry dam at element_size 3", r, "not measured before")
        print(f"[large] gravity stage {grav:.0f} s, run peak {r['peak_gib']:.2f} GiB | before: gravity 469 s, 9.3 GiB "
              f"(target: under 2 minutes and 8 GB); 20 s of shaking at this step: {20 * ms / r['dt'] / 1e3 / 60:.0f} "
              "min projected (target: at most 1 hour)", flush=True)


def case_accuracy(a):
    sc = example_scene()
    runs = {}
    first = run("auto", shaking(sc, a.window, output={"dt": 0.01, "nodes": ["crest"]}))
    if not first:
        return
    runs["dt_auto"] = first
    h = first["dt"]
    for k in (2, 4):
        r = run(f"dt/{k}", shaking(sc, a.window, dt=h / k, output={"dt": 0.01, "nodes": ["crest"]}))
        if r:
            runs[f"dt_auto/{k}"] = r
    _compare(runs, "dt_auto/4" if "dt_auto/4" in runs else "dt_auto/2")


def case_schemes(a):
    sc = example_scene()
    sc["mesh"]["parameters"]["element_size"] = a.schemes_element_size  # the implicit runs cost 0.5 s a step at 6
    sc["reservoir"]["dynamic"] = "none"
    sc.pop("foundation", None)
    gm = {"y": {"record": "elcentro_1940_ns_ngaw2", "scale_to_pga": f"{a.weak_pga} g"}}
    damping = {"alpha": a.mass_damping, "beta": 0.0}
    out = {"dt": 0.01, "nodes": ["crest"]}
    runs = {}
    r = run("explicit", shaking(sc, 3.0, ground_motion=gm, damping=damping, output=out))
    if r:
        runs["central_difference"] = r
    for dt in (0.0025, 0.00125):
        r = run(f"implicit {dt}", shaking(sc, 3.0, integrator="newmark_average", dt=dt, ground_motion=gm,
                                          damping=damping, output=out))
        if r:
            r.setdefault("loop_s", r.get("dynamic_wall_time_s") or 0.0)
            r.setdefault("steps", r.get("dynamic_steps") or 1)
            r.setdefault("dt", dt)
            runs[f"newmark_average {dt}"] = r
    if runs:
        _compare(runs, "newmark_average 0.00125" if "newmark_average 0.00125" in runs else next(iter(runs)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", nargs="*", help="step, water (the default), acoustic, example, large, accuracy, schemes")
    ap.add_argument("--duration", type=float, default=0.5, help="seconds of shaking for step, water and acoustic")
    ap.add_argument("--window", type=float, default=4.0, help="seconds of shaking for accuracy")
    ap.add_argument("--large-duration", type=float, default=0.1, help="seconds of shaking for large")
    ap.add_argument("--wet", action="store_true", help="large: the example's wet dam (reservoir with uplift, Westergaard "
                    "water, the rock with mass and absorbing sides, local damping) instead of the dry one")
    ap.add_argument("--weak-pga", type=float, default=0.05)
    ap.add_argument("--schemes-element-size", type=float, default=10.0)
    ap.add_argument("--mass-damping", type=float, default=0.02 * 2 * 3.14159 * 5.4,
                    help="alpha of C = alpha M for schemes (1/s; default 2 %% at the first mode, 5.4 Hz)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(json.loads(a.child))
        return
    cases = a.case or ["step", "water"]
    known = ("step", "water", "acoustic", "example", "large", "accuracy", "schemes")
    for c in cases:
        if c not in known:
            ap.error(f"unknown case {c!r}: one of {', '.join(known)}")
    print(f"# 3D dam in an earthquake; {cpu_model()}, 1 thread", flush=True)
    for c in cases:
        {"step": case_step, "water": case_water, "acoustic": case_acoustic, "example": case_example,
         "large": case_large, "accuracy": case_accuracy, "schemes": case_schemes}[c](a)


if __name__ == "__main__":
    main()
