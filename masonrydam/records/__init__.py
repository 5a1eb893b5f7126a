"""Ground-motion records: reading, the bundled library, processing with provenance, and measures.

>>> from masonrydam import records
>>> tr = records.load_record("elcentro_1940_ns_peknold")          # obspy.Trace in m/s2
>>> tr = records.bandpass(records.baseline_correct(tr), 0.1, 25.0)
>>> records.measures.summary(tr)["pga"] / records.G                # doctest: +SKIP
>>> Sa, Sv, Sd = records.response_spectrum(tr, None, [0.2, 0.5, 1.0], [0.05])

Modules: :mod:`.readers` (files -> obspy Stream in SI units), :mod:`.catalog` (the bundled library),
:mod:`.processing` (steps recorded in ``stats.masonrydam.provenance``), :mod:`.measures` (PGA, PGV,
PGD, Arias, D5-95, CAV, elastic response spectra with a numba kernel).
"""
from . import catalog, measures, processing, readers
from .catalog import library_dir, list_records, load_catalog, load_record, record_info, record_names, record_path
from .errors import RecordError
from .measures import (arias_intensity, cav, husid, husid_times, pga, pgd, pgv, response_spectrum,
                       significant_duration, spectral_acceleration, summary)
from .processing import (bandpass, baseline_correct, provenance_attrs, resample, scale, scale_to_pga,
                         scale_to_sa, taper, trim_significant_duration)
from .readers import G, parse_units, read_record, read_trace

__all__ = [
    "RecordError", "G", "read_record", "read_trace", "parse_units",
    "library_dir", "list_records", "load_catalog", "load_record", "record_info", "record_names", "record_path",
    "baseline_correct", "taper", "bandpass", "resample", "trim_significant_duration", "scale", "scale_to_pga",
    "scale_to_sa", "provenance_attrs",
    "pga", "pgv", "pgd", "arias_intensity", "husid", "husid_times", "significant_duration", "cav",
    "response_spectrum", "spectral_acceleration", "summary",
    "catalog", "measures", "processing", "readers",
]
