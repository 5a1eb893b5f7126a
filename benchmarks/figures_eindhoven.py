"""Figures of the Eindhoven wall J4D for docs/masonry_softening.md (issue 18): the load-displacement curves of
examples/eindhoven_J4D.toml with the top beam held at its height (the reference loading) and free to rise
(constant vertical load), the crack patterns of the held wall at its first peak and at the end, and the
hysteresis of examples/eindhoven_J4D_cyclic.py.

    python benchmarks/figures_eindhoven.py [--out docs/figures]

Writes eindhoven_J4D_curves.png, eindhoven_J4D_cracks_peak.png, eindhoven_J4D_cracks_end.png and
eindhoven_J4D_cyclic.png, and prints the runs' figures (peak, plateau, wall time).
"""
from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import time
from pathlib import Path

import numpy as np

import masonrydam
from masonrydam.results.deformed import deformed_figure
from masonrydam.results.pushover import pushover_data, pushover_figure
from masonrydam.scene.scene import Scene, set_key

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run(data, label):
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        ds = masonrydam.run(data)
    print(f"{label}: {time.perf_counter() - t0:.1f} s", flush=True)
    return ds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs" / "figures"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    held = run(Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data, "J4D, top held")
    free = Scene.from_toml(EXAMPLES / "eindhoven_J4D.toml").data
    set_key(free, "stages[1].loads[0].components", ["x"])
    set_key(free, "stages[1].loads[0].value", ["4 mm"])
    free = run(free, "J4D, constant vertical load")
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for ds, label in ((held, "top held at its height (reference loading)"), (free, "constant vertical load")):
        d, f, _ = pushover_data(ds)
        ax.plot(d * 1e3, f / 1e3, "-o", ms=2.5, lw=1.2, label=label)
        k = int(np.argmax(f))
        print(f"  {label}: peak {f[k] / 1e3:.2f} kN at {d[k] * 1e3:.2f} mm, end {f[-1] / 1e3:.2f} kN")
    ax.axhline(22.3, color="0.4", ls="--", lw=1, label="tan(phi) p A = 22.3 kN")
    ax.set_xlabel("horizontal displacement of the top beam (mm)")
    ax.set_ylabel("horizontal force (kN)")
    ax.set_title("Eindhoven wall J4D, p = 0.30 MPa")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "eindhoven_J4D_curves.png", dpi=90)
    d, f, steps = pushover_data(held)
    first_peak = int(steps[np.flatnonzero(np.diff(f) < 0)[0]])  # the first drop of the force
    for step, name, scale in ((first_peak, "peak", 100.0), (-1, "end", 30.0)):
        fig = deformed_figure(held, step=step, scale=scale, title=f"J4D, top held: {name}")
        fig.savefig(out / f"eindhoven_J4D_cracks_{name}.png", dpi=90)
    spec = importlib.util.spec_from_file_location("cyclic", EXAMPLES / "eindhoven_J4D_cyclic.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    cyc = run(mod.cyclic_scene(), "J4D cyclic, constant vertical load")
    fig = pushover_figure(cyc, "x", title="Eindhoven J4D, constant vertical load, cyclic push")
    fig.savefig(out / "eindhoven_J4D_cyclic.png", dpi=90)
    print(f"wrote the figures in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
