"""Shared configuration of the test suite.

The tests are grouped by room (tests/materials, tests/elements, tests/solvers, ...). This file lives in
tests/ and has no ``__init__.py`` beside it, so pytest's default ``prepend`` import mode puts tests/ on
``sys.path``: the helper modules here (``repository_paths``) are importable from every room
folder by their plain name. Test file names are unique across the folders (pytest imports them by
basename in this mode).
"""
