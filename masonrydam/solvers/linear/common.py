"""What the direct (:mod:`.direct`) and iterative (:mod:`.iterative`) solvers share: the exception of a
singular matrix. Its own module so that neither solver module imports the other for it (no import cycle)."""
from __future__ import annotations


class SingularMatrix(Exception):
    """The matrix is singular or numerically singular (a mechanism)."""
