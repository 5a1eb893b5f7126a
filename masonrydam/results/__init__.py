"""Results: streaming netCDF4 writer and xarray access."""
from .files import IncompleteResultWarning, open_result
from .writer import ResultWriter

__all__ = ["IncompleteResultWarning", "ResultWriter", "open_result"]
