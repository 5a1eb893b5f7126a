"""Results: streaming netCDF4 writer and xarray access."""
from .writer import ResultWriter

__all__ = ["ResultWriter"]
