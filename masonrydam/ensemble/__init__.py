"""Scenario ensembles: many runs of one base scene over records, intensities and parameters.

An ensemble file (TOML) names a base scene and the axes to sweep: ground-motion records (bundled names,
files, a folder), intensities (``scale_to_pga`` or ``scale_to_sa``), scene keys over lists of values, and
scene keys sampled from distributions in one Latin hypercube. Each member is one run of the base scene
with the member's record, intensity and values; each run is reduced to a few engineering demand
parameters, and the members together form one dataset over the axes.

Modules:

- :mod:`.spec`: the ensemble file, read and checked into an :class:`~.spec.EnsembleSpec` (errors are
  :class:`~masonrydam.errors.SceneError` naming the ensemble key, e.g. ``axes.parameters[1].key``);
- :mod:`.members`: :func:`~.members.enumerate_members` (the Cartesian product record x intensity x grid
  parameters x sample, each a :class:`~.members.Member` with a stable id and its scene) and
  :func:`~.members.member_axes` (the axes and their attributes, the coordinates of the dataset);
- :mod:`.measures`: :func:`~.measures.member_measures`, the demand parameters of one member's result
  (peak and residual joint slip and opening, cracked ratio, drift, dissipated energy, sliding safety
  factor), with their units in :data:`~.measures.MEASURES`;
- ``runner.py``: the execution on dask (a LocalCluster or a running scheduler), the store of the
  members' measures (and, with ``history = true``, their result files), resuming an interrupted
  ensemble, the dataset assembly and the command line;
- ``fragility.py`` / ``report.py``: incremental dynamic analysis (IDA) curves, fragility functions fitted
  to the measures, and the ensemble report.
"""
from .measures import MEASURES, measure_attrs, measure_names, member_measures
from .members import Axis, Member, enumerate_members, member_axes, member_id, sample_coordinates
from .spec import EnsembleSpec, IntensitySpec, ParameterSpec, RecordSpec, load_ensemble, load_spec, parse_ensemble

__all__ = ["EnsembleSpec", "RecordSpec", "IntensitySpec", "ParameterSpec", "load_ensemble", "load_spec", "parse_ensemble",
           "Member", "Axis", "enumerate_members", "member_axes", "member_id", "sample_coordinates",
           "MEASURES", "measure_attrs", "measure_names", "member_measures"]
