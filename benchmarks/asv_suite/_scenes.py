"""Scenes of the asv suite: the Koyna section of examples/koyna_el_centro.toml on a coarse mesh."""
from __future__ import annotations

import os
import tomllib
from pathlib import Path

for _name in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # one thread, as every figure in docs/performance.md

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def koyna_coarse(steps: int | None = None, duration: float | None = None, dt="fixed"):
    """The Koyna section (examples/koyna_el_centro.toml: Chopra & Chakrabarti 1973 profile, Mohr-Coulomb lift
    and base joints, El Centro 1940 at 0.5 g) at element_size 12 m (358 DOF, 44 interface elements), its
    dynamic stage with the trapezoidal rule at dt 2.5 ms for ``steps`` steps, or with dt = "auto" (dt_max 10 ms)
    for ``duration`` s; the crest recorded."""
    from masonrydam.scene import Scene
    from masonrydam.scene.schema import set_time_steps

    sc = tomllib.loads((EXAMPLES / "koyna_el_centro.toml").read_text())
    sc["mesh"]["parameters"]["element_size"] = 12.0
    stage = sc["stages"][1]
    if dt == "auto":
        stage = set_time_steps(stage, "auto", duration=duration)
        stage["dt_max"] = 0.01
        stage["output"] = {"dt": 0.01, "nodes": ["crest"]}
    else:
        stage = set_time_steps(stage, 0.0025, steps=steps)
        stage["output"] = {"stride": 10, "nodes": ["crest"]}
    sc["stages"][1] = stage
    stage["integrator"] = "newmark_average"
    stage.pop("alpha", None)
    return Scene(sc, base_dir=EXAMPLES)
