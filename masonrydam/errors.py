"""Exceptions raised by masonrydam.

Every error names the offending scene key, value, element or part of the model, so that a user can
fix the input without reading a traceback.
"""
from __future__ import annotations


class MasonrydamError(Exception):
    """Base class of all masonrydam errors."""


class SceneError(MasonrydamError, ValueError):
    """Invalid scene input. ``key`` is the dotted path of the offending entry (e.g. ``joints.bed.friction_angle``)."""

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(f"scene key '{key}': {message}")


class MeshError(MasonrydamError, ValueError):
    """Invalid mesh: degenerate or inverted elements, unknown cell types, missing sets."""

    def __init__(self, message: str, group: str | None = None, elements=None):
        self.group = group
        self.elements = None if elements is None else list(elements)
        where = ""
        if group is not None:
            where += f"element group '{group}'"
        if self.elements:
            shown = ", ".join(str(e) for e in self.elements[:10])
            more = f" (+{len(self.elements) - 10} more)" if len(self.elements) > 10 else ""
            where += f" element(s) {shown}{more}"
        super().__init__(f"{where}: {message}" if where else message)


class MechanismError(MasonrydamError, RuntimeError):
    """The structure (or a part of it) can move as a rigid body: missing supports or a floating block.

    ``parts`` is a list of human-readable descriptions of the free parts.
    """

    def __init__(self, message: str, parts=None):
        self.parts = list(parts or [])
        detail = "".join(f"\n  - {p}" for p in self.parts)
        super().__init__(message + detail)


class ConvergenceError(MasonrydamError, RuntimeError):
    """A step could not be converged even after the allowed step cuts."""


class NumericalError(MasonrydamError, FloatingPointError):
    """A NaN or infinity appeared in a residual, a stiffness or a solution."""


# Status codes returned by numba kernels (kernels never raise; Python turns codes into exceptions).
STATUS_OK = 0
STATUS_BAD_JACOBIAN = 1  # non-positive or tiny Jacobian determinant; info[0] = element index
STATUS_NAN = 2  # NaN/inf produced; info[0] = element index
STATUS_BAD_GEOMETRY = 3  # degenerate interface (zero length / area); info[0] = element index


class OutputError(MasonrydamError, OSError):
    """An output file or folder that cannot be written (a folder where a file is expected, a missing or
    read-only folder), or an input file that is not what it should be. Raised before any work is done."""


class MissingDependencyError(MasonrydamError, ImportError):
    """A library that a part of masonrydam needs is not installed or cannot load (gmsh without the system libraries
    it links to on a headless machine): the message names what to install."""


class AccuracyWarning(UserWarning):
    """A finished run whose numbers say it is not converged (an energy balance whose error exceeds 1 % of
    its largest term, or that needs energy created at contact events to close): the results are kept,
    the warning names the likely cause and the result attributes record it."""


class SceneWarning(UserWarning):
    """A valid scene that is probably not what was meant (a dynamic stage that runs on long after its record has
    ended): the message names the scene key and the value it was compared with; the run goes on."""


class RunStopped(KeyboardInterrupt):
    """A run stopped on request: Ctrl-C (SIGINT) or SIGTERM, at the end of a converged step, or at once
    on a second request. Every converged step is kept (see :func:`masonrydam.run`).

    Derived from ``KeyboardInterrupt``, not from :class:`MasonrydamError`, so that a loop that catches
    analysis errors (``except MasonrydamError``) still stops when the user asks it to.

    status: ``"interrupted"`` (SIGINT) or ``"terminated"`` (SIGTERM); exit_code: 130 or 143 (128 + the
    signal number, the shell's convention); where: the step it stopped at, in words; kept: the file
    that holds the converged steps (None for a run without an output file); steps: how many.
    """

    def __init__(self, status: str, where: str, kept=None, steps: int = 0):
        self.status, self.where, self.kept, self.steps = status, where, kept, steps
        self.exit_code = 143 if status == "terminated" else 130
        super().__init__(self.message())

    def message(self) -> str:
        text = f"stopped {self.where}"
        if self.kept is not None:
            text += f"; {self.steps} recorded step{'s' if self.steps != 1 else ''} kept in {self.kept}"
        return text

    def __str__(self) -> str:
        return self.message()


class StepInterrupted(KeyboardInterrupt):
    """A stop requested within a step (between two Newton or joint-space iterations): the solver abandons
    the step, reverts the joints' trial states and keeps the last converged step; it then raises
    :class:`RunStopped`. A ``KeyboardInterrupt``, so that no handler of failed steps retries it.
    status: ``"interrupted"`` or ``"terminated"``."""

    def __init__(self, status: str):
        super().__init__(status)
        self.status = status
