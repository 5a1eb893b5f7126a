"""The error raised by the ground-motion record tools."""
from __future__ import annotations

from ..errors import MasonrydamError


class RecordError(MasonrydamError, ValueError):
    """A record that cannot be read, or a processing step or measure that cannot be applied.

    The message says what was found (file, format, header lines, columns, units) and what is
    missing, so that the user can fix the input; masonrydam never guesses a format, a unit or a
    time step.
    """
