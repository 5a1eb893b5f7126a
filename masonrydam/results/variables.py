"""Result dimensions and variables that an effect declares (:meth:`masonrydam.effects.base.EffectRun.result_variables`)
and the :class:`~masonrydam.results.writer.ResultWriter` creates: the writer knows no effect, it writes what it
is given, each variable with its units and long name."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class ResultDimension:
    """A netCDF dimension of the result file (``size`` > 0: fixed)."""

    name: str
    size: int


@dataclass(frozen=True)
class ResultVariable:
    """One variable of the result file.

    dims: its dimensions; a variable whose first dimension is ``step`` is a step variable (one value per
    recorded step, given by the effect's ``static_values`` / ``dynamic_values`` under ``name``); any other
    variable is written once from ``values``. dtype: a netCDF type (``"f8"``, ``"i4"``, ...) or ``str`` for
    a string coordinate; units and long_name: SI units and the description every variable carries;
    fill_value: the value of steps that do not set it (NaN for floating step variables that static steps
    leave empty); dynamic_only: a step variable that static steps leave NaN; attrs: further netCDF
    attributes (str, numbers or arrays)."""

    name: str
    dims: tuple
    units: str
    long_name: str
    dtype: object = "f8"
    values: np.ndarray | list | None = None
    fill_value: float | None = None
    dynamic_only: bool = False
    attrs: dict = field(default_factory=dict)

    @property
    def per_step(self) -> bool:
        return self.dims[:1] == ("step",)
