"""The error raised by the ground-motion record tools."""
from __future__ import annotations

from ..errors import MasonrydamError


class RecordError(MasonrydamError, ValueError):
    """A record that cannot be read, or a processing step or measure that cannot be applied.

    The message says what was found (file, format, header lines, columns, units) and what is
    missing, so that the user can fix the input; masonrydam never guesses a format, a unit or a
    time step.

    ``option``: where the error is about a value the caller gives (or must give), its generic name
    (``"units"``, ``"dt"``, ``"column"`` or ``"format"``), else None; a caller such as the command
    line or the scene builder uses it to point at its own spelling of that option (``--units``,
    ``stages[1].ground_motion.x.units``).
    """

    def __init__(self, message: str, option: str | None = None):
        self.option = option
        super().__init__(message)
