"""masonrydam: nonlinear static and seismic analysis of jointed masonry walls and block dams.

Continuum blocks joined by zero-thickness interface elements that stick, slide (Mohr-Coulomb with
residual shear stiffness) and open (no tension) and close again, after Tzamtzis & Asteris.

>>> import masonrydam
>>> ds = masonrydam.run("examples/block_on_incline.toml")   # doctest: +SKIP
"""
import time as _time

#: ``time.perf_counter()`` at the package's first import: the clock of a command-line run's summary. The console
#: script imports the package first, so this is the process's start less the interpreter's own (a few tens of ms).
#: Not the process's start from /proc: a shell that runs a command last (``bash -c "pip install . && masonrydam
#: run ..."``) execs it in its own process, whose start is then the shell's, before the install.
IMPORTED_AT = _time.perf_counter()

from ._version import __version__  # noqa: E402
from .errors import ConvergenceError, MasonrydamError, MechanismError, MeshError, NumericalError, SceneError  # noqa: E402

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
