"""Pushover curves of static results: the force of the actuator against its displacement.

The actuator is the set of DOFs a static stage drives by prescribed displacements (the result's
``driven`` variable, 1 + the stage index). Its force is the sum of the reactions at those DOFs along the
chosen component (N, the force the actuator applies to the structure), its displacement their mean
(m). ``masonrydam plot OUT.nc --pushover`` draws it; :func:`pushover_data` gives the numbers and
:func:`value_at_push` reads a curve at a given displacement.
"""
from __future__ import annotations

import json

import numpy as np

from ..errors import MasonrydamError


def pushover_data(ds, component: str = "x", stage: int | None = None):
    """``(displacement (n,), force (n,), steps (n,))`` of the actuator in ``component``: the steps of the
    driving stage, from the step before it (the state it starts from). Default: the last stage that drives
    this component, with every earlier stage that drives the same DOFs (attribute ``pushover_stages``: the
    successive pushes of a cyclic test, whose curve is the hysteresis). Raises MasonrydamError naming what is
    missing."""
    if "driven" not in ds:
        raise MasonrydamError("the result has no prescribed-displacement stage (variable 'driven'): a pushover "
                              "curve needs a static stage with a load of type \"displacement\"")
    comps = list(ds.component.values)
    if component not in comps:
        raise MasonrydamError(f"--component {component!r}: the result has components {comps}")
    driven = ds.driven.sel(component=component).values  # (node,)
    stages = sorted(set(int(v) for v in driven if v > 0))
    if not stages:
        raise MasonrydamError(f"no static stage drives component {component!r} (variable 'driven')")
    s = stages[-1] if stage is None else int(stage) + 1
    if s not in stages:
        raise MasonrydamError(f"stage {s - 1} does not drive component {component!r}; stages that do: "
                              f"{[k - 1 for k in stages]}")
    nodes = driven == s
    stages_used = [s - 1]
    if stage is None and "pushover_stages" in ds.attrs:
        stages_used = json.loads(ds.attrs["pushover_stages"]).get(component, stages_used)
    steps = np.flatnonzero(np.isin(ds.stage.values, stages_used))
    if len(steps) == 0:
        raise MasonrydamError(f"the result has no converged step of stage {s - 1}")
    if steps[0] > 0:
        steps = np.concatenate([[steps[0] - 1], steps])
    d = ds.displacement.sel(component=component).values[steps][:, nodes].mean(axis=1)
    f = ds.reaction.sel(component=component).values[steps][:, nodes].sum(axis=1)
    return d, f, steps


def pushover_figure(ds, component: str = "x", title: str | None = None):
    """The pushover curve (force in kN against displacement in mm) of :func:`pushover_data` as a
    matplotlib Figure; the peak is marked and labelled."""
    # matplotlib (a second to import) only when a figure is drawn
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d, f, _ = pushover_data(ds, component)
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    # draw the first push to the right and its force upwards (a hysteresis keeps the orientation of its first
    # excursion; the force on the driven DOFs does positive work on the way out)
    moved = np.flatnonzero(np.abs(d - d[0]) > 1e-3 * max(np.abs(d - d[0]).max(), 1e-300))
    k1 = moved[0] if len(moved) else len(d) - 1
    sd = -1.0 if d[k1] < d[0] else 1.0
    sign = -1.0 if (f[k1] - f[0]) * (d[k1] - d[0]) < 0 else 1.0
    sign *= sd
    ax.plot(sd * d * 1e3, sign * f / 1e3, "-o", ms=2.5, lw=1.2, color="C0", label="actuator force")
    k = int(np.argmax(sign * f))
    ax.plot(sd * d[k] * 1e3, sign * f[k] / 1e3, "v", color="C3",
            label=f"peak {sign * f[k] / 1e3:.3g} kN at {sd * d[k] * 1e3:.3g} mm")
    ax.set_xlabel(f"prescribed displacement, {component} (mm)")
    ax.set_ylabel(f"force at the prescribed displacements, {component} (kN)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig


def value_at_push(d: np.ndarray, values: np.ndarray, x: float) -> float:
    """``values`` (n,) (a force, N, or any quantity recorded with the push) where the push ``d`` (n,) m first
    reaches ``x`` m, linear between the recorded steps; NaN where it never does. The first crossing: the steps a
    stalled run records in its path-following attempts can go back, and an interpolation over the whole record
    would then read them."""
    reached = np.flatnonzero(d >= x - 1e-9)
    if len(reached) == 0:
        return float("nan")
    i = int(reached[0])
    if i == 0 or d[i] == d[i - 1]:
        return float(values[i])
    return float(values[i - 1] + (values[i] - values[i - 1]) * (x - d[i - 1]) / (d[i] - d[i - 1]))
