"""masonrydam: nonlinear static and seismic analysis of jointed masonry walls and block dams.

Continuum blocks joined by zero-thickness interface elements that stick, slide (Mohr-Coulomb with
residual shear stiffness) and open (no tension) and close again, after Tzamtzis & Asteris.

>>> import masonrydam
>>> ds = masonrydam.run("examples/wall_push.toml")   # doctest: +SKIP
"""
from ._version import __version__
from .errors import ConvergenceError, MasonrydamError, MechanismError, MeshError, NumericalError, SceneError

# The package's entry points that need xarray, numba and the solvers are loaded on first use (PEP 562), so
# that ``import masonrydam.units`` or ``masonrydam --version`` does not pay a second of imports for them.
_LAZY = {"open_result": "masonrydam.results.files", "Scene": "masonrydam.scene", "run": "masonrydam.scene"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'masonrydam' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


__all__ = ["__version__", "Scene", "run", "open_result", "MasonrydamError", "SceneError", "MeshError", "MechanismError",
           "ConvergenceError", "NumericalError"]
