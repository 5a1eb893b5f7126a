"""Run every example scene and the default scene, and compare two such sets of results variable by variable.

A refactoring that must not change results is checked with it: run the scenes on the code before
the change and on the code after it, then compare.

    python benchmarks/regression_datasets.py run OUT_DIR [--only NAME ...]
    python benchmarks/regression_datasets.py compare BEFORE_DIR AFTER_DIR

``run`` writes ``OUT_DIR/NAME.nc`` for each scene and ``OUT_DIR/times.json`` (wall time of each run, s, with the
CPU model). ``compare`` prints, for every variable and coordinate of every result, whether it is bit for bit
the same, and otherwise the largest absolute and relative difference; attributes that hold wall times or
counts of time are skipped, every other attribute is compared as text. It exits with 1 when anything differs.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from _common import cpu_model  # benchmarks/ is sys.path[0] when run as a script

ROOT = Path(__file__).resolve().parents[1]

#: example scenes (``examples/NAME.toml``) that are scenes, not ensembles
SCENES = ["block_3d_oblique", "block_on_incline", "dam_3d_gravity", "dam_3d_reservoir", "eindhoven_J4D",
          "housner_rocking", "koyna_el_centro", "koyna_full_reservoir", "koyna_reservoir", "sliding_block_pulse",
          "wall_3d_english", "wall_el_centro"]


def run(out: Path, only=None) -> None:
    import warnings

    import masonrydam
    from masonrydam.cli.main import default_scene_path

    out.mkdir(parents=True, exist_ok=True)
    times = {"cpu": cpu_model(), "masonrydam": str(Path(masonrydam.__file__).parent)}
    todo = [("wall_push", default_scene_path())] + [(n, ROOT / "examples" / f"{n}.toml") for n in SCENES]
    for name, path in todo:
        if only and name not in only:
            continue
        t0 = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                masonrydam.run(path, output=out / f"{name}.nc")
            status = "ok"
        except Exception as exc:  # a failing example is a result too: it is compared by its partial file
            status = f"{type(exc).__name__}: {exc}"
        times[name] = {"seconds": round(time.perf_counter() - t0, 2), "status": status}
        print(f"{name:24s} {times[name]['seconds']:8.2f} s  {status}", flush=True)
    prev = out / "times.json"
    if prev.exists():
        times = {**json.loads(prev.read_text()), **times}
    prev.write_text(json.dumps(times, indent=1))


def _attrs_equal(a: dict, b: dict) -> list[str]:
    bad = []
    for k in sorted(set(a) | set(b)):
        if any(t in k for t in ("wall_time", "setup_s", "flexibility_s", "output_time", "ms_per_step",
                                "history", "software_version", "scene_source")):
            continue
        va, vb = a.get(k), b.get(k)
        if k in ("per_stage", "dynamic_per_stage") and va is not None and vb is not None:
            va, vb = _strip_times(va), _strip_times(vb)
        if str(va) != str(vb):
            bad.append(f"attribute {k}: {str(va)[:120]!r} != {str(vb)[:120]!r}")
    return bad


def _strip_times(text):
    try:
        rows = json.loads(text)
    except (TypeError, ValueError):
        return text
    if isinstance(rows, list):
        rows = [{k: v for k, v in r.items() if not k.endswith("_s")} if isinstance(r, dict) else r for r in rows]
    return json.dumps(rows, sort_keys=True)


def compare(before: Path, after: Path) -> int:
    import xarray as xr

    differ = 0
    for fa in sorted(before.glob("*.nc")):
        fb = after / fa.name
        if not fb.exists():
            print(f"{fa.stem}: missing in {after}")
            differ += 1
            continue
        a, b = xr.open_dataset(fa), xr.open_dataset(fb)
        lines = _attrs_equal(dict(a.attrs), dict(b.attrs))
        for name in sorted(set(a.variables) | set(b.variables)):
            if name not in a.variables or name not in b.variables:
                lines.append(f"{name}: only in {'before' if name in a.variables else 'after'}")
                continue
            va, vb = a[name], b[name]
            lines += [f"{name}: {m}" for m in _attrs_equal(dict(va.attrs), dict(vb.attrs))]
            if va.shape != vb.shape:
                lines.append(f"{name}: shape {va.shape} != {vb.shape}")
                continue
            x, y = va.values, vb.values
            if x.dtype.kind in "fc":
                same = np.array_equal(x, y, equal_nan=True)
                if not same:
                    d = np.abs(x - y)
                    scale = np.nanmax(np.abs(x)) if x.size else 0.0
                    dmax = float(np.nanmax(d)) if np.isfinite(d).any() else float("nan")
                    lines.append(f"{name}: max |diff| {dmax:.3g} (relative to its largest value {dmax / scale:.3g})"
                                 if scale else f"{name}: differs")
            elif not np.array_equal(x, y):
                lines.append(f"{name}: differs ({int((x != y).sum())} of {x.size} values)")
        if lines:
            differ += 1
            print(f"{fa.stem}: DIFFERS")
            for line in lines:
                print("   ", line)
        else:
            print(f"{fa.stem}: bit for bit the same ({len(a.variables)} variables and coordinates, all attributes)")
    ta, tb = before / "times.json", after / "times.json"
    if ta.exists() and tb.exists():
        A, B = json.loads(ta.read_text()), json.loads(tb.read_text())
        print(f"wall time (s), before on {A.get('cpu')}, after on {B.get('cpu')}:")
        for k in A:
            if isinstance(A[k], dict) and isinstance(B.get(k), dict):
                print(f"    {k:24s} {A[k]['seconds']:8.2f} {B[k]['seconds']:8.2f}")
    return 1 if differ else 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("out", type=Path)
    r.add_argument("--only", nargs="*")
    c = sub.add_parser("compare")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    a = p.parse_args(argv)
    if a.cmd == "run":
        run(a.out, a.only)
        return 0
    return compare(a.before, a.after)


if __name__ == "__main__":
    sys.exit(main())
