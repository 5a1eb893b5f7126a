"""Cyclic push of the Eindhoven wall J4D under a constant precompression, with its hysteresis plotted.

The scene is examples/eindhoven_J4D.toml with the top beam free to rise (kept level, so the vertical load
stays 0.30 MPa) and the push replaced by reversed displacements of growing amplitude: +1, -1, +2, -2 mm and
back to 0. Once the bed joint under the top course has lost its cohesion the wall slides on it and the
loop is Coulomb's parallelogram (elastic branches between the plateaus), H = +/- tan(phi) N with N = 30.6 kN (precompression, top beam and top course):
+/- 22.9 kN (tests/system/test_eindhoven_walls.py checks it).

Run:   python examples/eindhoven_J4D_cyclic.py            (writes j4d_cyclic.nc and j4d_cyclic.png; ~30 s)
"""
from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import masonrydam
from masonrydam.results.pushover import pushover_figure

#: (top displacement to reach, mm; steps) of the successive pushes
CYCLES = ((1.0, 10), (-1.0, 20), (2.0, 30), (-2.0, 40), (0.0, 20))


def cyclic_scene(cycles=CYCLES) -> dict:
    scene = tomllib.loads(Path(__file__).with_name("eindhoven_J4D.toml").read_text())
    scene["model"]["name"] = "eindhoven_J4D_cyclic"
    push = scene["stages"][1]
    stages, here = [], 0.0
    for k, (target, steps) in enumerate(cycles):
        stage = dict(push, name=f"push{k + 1}", steps=steps, duration=steps / push["steps"] * push["duration"])
        stage["loads"] = [{"type": "displacement", "set": "top", "components": ["x"],
                           "value": [f"{target - here:.6g} mm"]}]
        stages.append(stage)
        here = target
    scene["stages"][1:] = stages
    return scene


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "j4d_cyclic.nc")
    ds = masonrydam.run(cyclic_scene(), output=out, progress=True, summary=True)
    fig = pushover_figure(ds, "x", title="Eindhoven J4D, constant precompression, cyclic push")
    fig.savefig(out.with_suffix(".png"), dpi=120)
    print(f"wrote {out} and {out.with_suffix('.png')}")
