"""What nonlinear blocks cost per dynamic step: the Koyna section of
``examples/koyna_el_centro.toml`` (103 m, 10 lift joints and the dam-rock joint with Mohr-Coulomb
joints, quad4, about 7 700 DOF; El Centro 1940 at 0.5 g, HHT) on a short window of the record, with

- ``elastic``: the scene as it is (linear blocks, small kinematics; the joint-space solver);
- ``elastic_newton``: the same with ``joint_space = "off"``: the general Newton path, the one that
  nonlinear blocks have to take (they turn the joint-space condensation off);
- ``drucker_prager``: the dam's concrete (group ``dam``) elasto-plastic, Drucker-Prager matched to
  Mohr-Coulomb in plane strain, c = 2.5 MPa, phi = 40 deg (associated flow, no hardening): a concrete
  that yields only where the section is most strained;
- ``von_mises``: (not run by default) the dam von Mises with a high yield stress (20 MPa);
- ``large``: ``[model] kinematics = "large"`` (total Lagrangian blocks, co-rotational joints), elastic.

The record is cut to keep every run short: El Centro (NGA-West2 RSN6, 180 deg) from ``--start`` s
(default 1.3 s, before it the record is below 5 % of its PGA) with a 0.1 s cosine ramp, scaled by the
factor that takes the whole record to a PGA of 0.5 g; ``--steps`` steps of ``--dt`` (default 200 of
5 ms: 1.0 s, over the record's peak at 2.1 s). Every case runs once first with 3 steps (numba JIT and
cache, joint-space set-up code) outside the timings.

    python benchmarks/bench_continuum_nonlinear.py [--steps 200] [--dt 0.005] [--start 1.3]
        [--cases elastic elastic_newton drucker_prager large] [--reference-steps 2000]

Prints ms per step of the dynamic stage (its wall time over its steps; for the joint-space solver also
without its one-off set-up), Newton iterations, factorizations and step cuts per step, the crest's peak
displacement and how far its history departs from the elastic run, the joint points that slid or
opened, and for plastic cases the Gauss points that yielded. ``--reference-steps N`` also runs the
``empty`` case of ``bench_koyna_reservoir.py`` (the whole record from t = 0, N steps of 5 ms), whose
figure docs/dam_reservoir_foundation.md gives (3.75 ms/step for 2 000 steps): a scene without
plastic or large blocks must not have become slower. All in one process on one thread. A benchmark,
not a test: it never fails on a slow figure.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import importlib
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402

CASES = ("elastic", "elastic_newton", "drucker_prager", "von_mises", "large")
DEFAULT_CASES = ("elastic", "elastic_newton", "drucker_prager", "large")
RECORD = "elcentro_1940_ns_ngaw2"
PGA_G = 0.5
#: the dam's concrete for the plastic cases ([materials.dam] keys); E, nu, density stay the example's
PLASTIC = {"drucker_prager": {"law": "drucker_prager", "cohesion": 2.5e6, "friction_angle": 40.0,
                              "match": "plane_strain"},
           "von_mises": {"law": "von_mises", "yield_stress": 20e6}}
#: documented figure of bench_koyna_reservoir.py's empty case (docs/dam_reservoir_foundation.md: 2 000
#: steps of 5 ms, Mohr-Coulomb joints, one thread on this project's 2-core AMD EPYC)
REFERENCE_MS = 3.75


def ground_motion(start: float, duration: float) -> dict:
    """The ground-motion table: El Centro from ``start`` s for ``duration`` s (plus a margin), a 0.1 s
    cosine ramp at its start, scaled by the factor of the whole record to ``PGA_G``."""
    from masonrydam import records

    tr = records.load_record(RECORD)  # m/s2
    dt = tr.stats.delta
    a = np.asarray(tr.data, dtype=float)
    factor = PGA_G * records.G / np.abs(a).max()
    i0 = int(round(start / dt))
    seg = a[i0:i0 + int(np.ceil(duration / dt)) + 3].copy()
    n_ramp = min(len(seg), int(round(0.1 / dt)))
    seg[:n_ramp] *= 0.5 * (1.0 - np.cos(np.pi * np.arange(n_ramp) / n_ramp))
    return {"x": {"values": [float(v) for v in factor * seg], "dt": dt, "units": "m/s2"}}


def scene(case: str, steps: int, dt: float, start: float) -> dict:
    import tomllib

    from masonrydam.scene.schema import set_time_steps

    sc = tomllib.loads((ROOT / "examples" / "koyna_el_centro.toml").read_text())
    sc["model"]["name"] = f"koyna_{case}"
    dyn = set_time_steps(sc["stages"][1], dt, steps=steps)
    dyn["output"] = {"stride": 5, "nodes": ["crest"]}
    dyn["ground_motion"] = ground_motion(start, steps * dt)
    if case == "elastic_newton":
        dyn["joint_space"] = "off"
    elif case in PLASTIC:
        sc["materials"]["dam"].update(PLASTIC[case])
    elif case == "large":
        sc["model"]["kinematics"] = "large"
    elif case != "elastic":
        raise ValueError(f"unknown case {case!r}")
    return sc


class _ModelTap:
    """Keeps the model that ``masonrydam.run`` builds (the Gauss points' plastic state is not in the
    result file): wraps ``build_model`` in the run module of this process for the ``with`` block."""

    def __enter__(self):
        self.mod = importlib.import_module("masonrydam.scene.run")
        self.orig = self.mod.build_model
        self.model = None

        def build_model(*args, **kwargs):
            self.model = self.orig(*args, **kwargs)
            return self.model

        self.mod.build_model = build_model
        return self

    def __exit__(self, *exc):
        self.mod.build_model = self.orig


def _yielded(model) -> dict | None:
    """Gauss points of the plastic groups that have yielded (equivalent plastic strain > 0) at the end."""
    from masonrydam.materials.plasticity import S_EQ_PLASTIC_STRAIN

    groups = [g for g in model.cgroups if g.plastic]
    if not groups:
        return None
    kappa = np.concatenate([g.state_committed[:, S_EQ_PLASTIC_STRAIN] for g in groups])
    elems = np.concatenate([(g.state_committed[:, S_EQ_PLASTIC_STRAIN].reshape(g.n_elem, -1) > 0).any(axis=1)
                            for g in groups])
    return {"points": int((kappa > 0).sum()), "of": kappa.size, "elements": int(elems.sum()), "of_elements": elems.size,
            "max_kappa": float(kappa.max())}


def run_one(case, steps, dt, start):
    import warnings

    import masonrydam

    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings(), _ModelTap() as tap:
        warnings.simplefilter("ignore")  # (the accuracy warnings of dt are not this benchmark's subject)
        t0 = time.perf_counter()
        try:
            ds = masonrydam.run(scene(case, steps, dt, start), output=Path(tmp) / "koyna.nc")
        except Exception as exc:  # reported, not worked around
            return {"error": f"{type(exc).__name__}: {exc}", "wall_s": time.perf_counter() - t0,
                    "trace": traceback.format_exc(limit=3)}
        wall = time.perf_counter() - t0
        a = dict(ds.attrs)
        n = int(a["dynamic_steps"])
        dyn_s = float(a["dynamic_wall_time_s"])
        setup = float(a.get("dynamic_joint_space_setup_s", 0.0))
        dyn = ds.stage.values == ds.stage.values.max()  # the dynamic stage's recorded steps
        ux = ds.displacement.sel(component="x").values[dyn]  # (steps, crest nodes)
        model = tap.model
        out = {"wall_s": wall, "dyn_s": dyn_s, "ms_per_step": float(a["dynamic_ms_per_step"]),
               "ms_no_setup": 1e3 * (dyn_s - setup) / n, "setup_s": setup, "steps": n,
               "its": int(a["dynamic_newton_iterations"]) / n,
               "js_its": int(a.get("dynamic_joint_space_iterations", 0)) / n,
               "facts": int(a["dynamic_factorizations"]) / n,
               "substeps": int(a.get("dynamic_substeps", 0)), "rejected": int(a.get("dynamic_steps_rejected", 0)),
               "crest": float(np.abs(ux).max()), "crest_history": ux,
               "slid": int((ds.joint_state.values == 1).any(axis=0).sum()),
               "opened": int((ds.joint_state.values == 2).any(axis=0).sum()), "joint_points": ds.sizes["joint_point"],
               "n_dof": model.n_dof, "elements": sum(g.n_elem for g in model.cgroups),
               "element_types": sorted({g.type for g in model.cgroups}), "yield": _yielded(model)}
        ds.close()
    return out


def reference(steps: int):
    """``bench_koyna_reservoir.py``'s empty case (the example's record from t = 0, 5 ms steps)."""
    import bench_koyna_reservoir as bkr

    bkr.run_one("empty", 3, 0.005)  # warm
    return bkr.run_one("empty", steps, 0.005)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--dt", type=float, default=0.005)
    ap.add_argument("--start", type=float, default=1.3, help="where the record is cut (s)")
    ap.add_argument("--cases", nargs="+", default=list(DEFAULT_CASES), choices=CASES)
    ap.add_argument("--reference-steps", type=int, default=2000,
                    help="steps of bench_koyna_reservoir.py's empty case (0: not run)")
    args = ap.parse_args()
    t_end = args.start + args.steps * args.dt
    print(f"# Koyna section (examples/koyna_el_centro.toml), Mohr-Coulomb joints, HHT alpha = -0.1 ({cpu_model()}, "
          f"1 thread)\n# SHORTENED RECORD: El Centro {args.start:g}-{t_end:g} s only (0.1 s ramp in, scaled to "
          f"{PGA_G:g} g with the whole record's factor), {args.steps} steps of {args.dt:g} s per case; "
          "the example runs 40 s")
    print("# warm-up: every case once with 3 steps first (numba JIT / cache), not timed")
    for case in args.cases:
        run_one(case, 3, args.dt, args.start)
    results = {}
    for case in args.cases:
        r = results[case] = run_one(case, args.steps, args.dt, args.start)
        if "error" in r:
            print(f"[{case:15s}] FAILED after {r['wall_s']:.1f} s: {r['error']}\n{r['trace']}")
            continue
        print(f"[{case:15s}] {r['ms_per_step']:.2f} ms/step; {r['its']:.2f} Newton + {r['js_its']:.2f} joint-space "
              f"its/step; run {r['wall_s']:.1f} s")
    first = next(iter(results.values()))
    if "error" not in first:
        print(f"# mesh: {first['elements']} {'/'.join(first['element_types'])} elements, {first['n_dof']} DOF, "
              f"{first['joint_points']} joint points")
    ref = None
    if args.reference_steps > 0:
        ref = reference(args.reference_steps)

    base = results.get("elastic")
    base = None if base is None or "error" in base else base
    newton = results.get("elastic_newton")
    newton = None if newton is None or "error" in newton else newton
    print()
    print(f"{'case':15s} {'ms/step':>8s} {'w/o setup':>9s} {'x elastic':>9s} {'Newton/st':>9s} {'js-its/st':>9s} "
          f"{'fact/st':>7s} {'cuts':>4s} {'crest mm':>8s} {'|du| mm':>7s} {'|duN| mm':>8s} {'slid':>5s} {'open':>5s} "
          f"{'yielded GP':>11s}")
    for case, r in results.items():
        if "error" in r:
            print(f"{case:15s} FAILED: {r['error'].splitlines()[0][:100]}")
            continue
        ratio = f"{r['ms_no_setup'] / base['ms_no_setup']:.1f}" if base else "-"
        diff, diff_n = "-", "-"
        if base is not None and base["crest_history"].shape == r["crest_history"].shape:
            diff = f"{1e3 * np.abs(r['crest_history'] - base['crest_history']).max():.2f}"
        if newton is not None and newton["crest_history"].shape == r["crest_history"].shape:
            diff_n = f"{1e3 * np.abs(r['crest_history'] - newton['crest_history']).max():.2f}"
        y = r["yield"]
        ytxt = "-" if y is None else f"{y['points']}/{y['of']}"
        print(f"{case:15s} {r['ms_per_step']:8.2f} {r['ms_no_setup']:9.2f} {ratio:>9s} {r['its']:9.2f} "
              f"{r['js_its']:9.2f} {r['facts']:7.2f} {r['substeps']:4d} {1e3 * r['crest']:8.2f} {diff:>7s} "
              f"{diff_n:>8s} {r['slid']:5d} {r['opened']:5d} {ytxt:>11s}")
    print("(ms/step: dynamic stage wall time / steps; w/o setup: less the joint-space set-up; x elastic: ratio of "
          "the w/o-setup figures; fact/st: factorizations per step; cuts: halved steps (dynamic_substeps); crest "
          "mm: peak |u_x| of the crest nodes in the dynamic stage, relative to the ground, the self-weight's "
          "included; |du|, |duN|: largest difference of the crest nodes' u_x histories (every 5th step) from the "
          "elastic and the elastic_newton run; slid / open: joint points that slid / opened at a recorded step; "
          "yielded GP: Gauss points with equivalent plastic strain > 0 at the end)")
    for case, r in results.items():
        if "error" not in r and r["yield"] is not None:
            y = r["yield"]
            print(f"  {case}: {y['points']} of {y['of']} Gauss points ({y['elements']} of {y['of_elements']} dam "
                  f"elements) yielded, largest equivalent plastic strain {y['max_kappa']:.3g}")
    if ref is not None:
        print(f"\nno plastic / large blocks, bench_koyna_reservoir.py 'empty' ({args.reference_steps} steps of 5 ms "
              f"from t = 0): {ref['ms_per_step']:.2f} ms/step, {ref['js_its']:.2f} joint-space its/step "
              f"(docs/dam_reservoir_foundation.md: {REFERENCE_MS} ms/step for 2 000 steps; "
              f"{ref['ms_per_step'] / REFERENCE_MS:.2f}x); run {ref['wall_s']:.1f} s")


if __name__ == "__main__":
    main()
