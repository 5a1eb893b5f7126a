"""masonrydam: nonlinear static and seismic analysis of jointed masonry walls and block dams.

Continuum blocks joined by zero-thickness interface elements that stick, slide (Mohr-Coulomb with
residual shear stiffness) and open (no tension) and close again, after Tzamtzis & Asteris.

>>> import masonrydam
>>> ds = masonrydam.run("examples/wall_push.toml")   # doctest: +SKIP
"""
from ._version import __version__
from .errors import ConvergenceError, MasonrydamError, MechanismError, MeshError, NumericalError, SceneError
from .results.files import open_result
from .scene import Scene, run

__all__ = ["__version__", "Scene", "run", "open_result", "MasonrydamError", "SceneError", "MeshError", "MechanismError",
           "ConvergenceError", "NumericalError"]
