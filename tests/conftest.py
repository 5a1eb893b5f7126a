"""Shared configuration of the test suite.

The tests are grouped by room (tests/materials, tests/elements, tests/solvers, ...). This file lives in
tests/ and has no ``__init__.py`` beside it, so pytest's default ``prepend`` import mode puts tests/ on
``sys.path``: the helper modules here (``repository_paths``) are importable from every room
folder by their plain name (``scenes``, ``repository_paths``). Test file names are unique across the
folders (pytest imports them by basename in this mode).

Scene dictionaries of the closed-form and published problems come from ``scenes.py`` (builders with overrides); the
fixtures here are the ones that several rooms use.
"""
from __future__ import annotations

import pytest


@pytest.fixture
def no_solve(monkeypatch):
    """Make any attempt to solve a static stage fail loudly: for tests that assert an error comes before
    solving (scene validation)."""
    from masonrydam.solvers.static import stepping as static

    def _forbidden(self, *a, **k):
        raise AssertionError("the solver was started although the scene is invalid")

    monkeypatch.setattr(static.StaticSolver, "run", _forbidden)


@pytest.fixture(scope="session")
def default_scene_result(tmp_path_factory):
    """The result file (netCDF) of the default scene (``masonrydam run --default``: a running-bond wall under
    self-weight and precompression, then pushed 1 mm at its top beam), run once for the session. Read it;
    do not change it."""
    import masonrydam
    from masonrydam.cli.main import default_scene_path

    out = tmp_path_factory.mktemp("default_scene") / "wall.nc"
    masonrydam.run(default_scene_path(), output=out)
    return out
