"""What a time step costs: the coarse Koyna section (358 DOF) with the trapezoidal rule, at a fixed
dt of 2.5 ms and with dt = "auto". The figures are the run's own (``dynamic_wall_time_s`` over
``dynamic_steps``: the steps, not the model's build or the output), in ms a step."""
from __future__ import annotations

import warnings

from ._scenes import koyna_coarse


def _ms_per_step(scene) -> float:
    import masonrydam

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the energy balance's notes are not the benchmark's business
        ds = masonrydam.run(scene)
    return 1e3 * float(ds.attrs["dynamic_wall_time_s"]) / int(ds.attrs["dynamic_steps"])


class KoynaCoarseSteps:
    """ms a step on the coarse Koyna section; ``setup`` runs 20 steps first (numba's cache loaded)."""

    timeout = 600
    number = 1
    repeat = 3
    warmup_time = 0

    def setup(self):
        _ms_per_step(koyna_coarse(steps=20))

    def track_fixed_dt_ms_per_step(self):
        return _ms_per_step(koyna_coarse(steps=2000))

    track_fixed_dt_ms_per_step.unit = "ms"

    def track_auto_dt_ms_per_step(self):
        return _ms_per_step(koyna_coarse(duration=1.5, dt="auto"))

    track_auto_dt_ms_per_step.unit = "ms"
