"""gmsh missing its system libraries (a headless machine without OpenGL and X11 libraries): the first dam a user
meshes ends in one line that names the packages to install, not in ``OSError: libGLU.so.1`` from deep inside the
gmsh wheel."""
from __future__ import annotations

import builtins

import pytest

from generators import _gmsh
from masonrydam.cli.main import main
from masonrydam.errors import MissingDependencyError


def _without_gmsh(monkeypatch, exc):
    real = builtins.__import__

    def fake(name, *args, **kwargs):
        if name == "gmsh":
            raise exc
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake)


def test_a_library_gmsh_cannot_load_names_the_packages(monkeypatch):
    _without_gmsh(monkeypatch, OSError("libGLU.so.1: cannot open shared object file: No such file or directory"))
    with pytest.raises(MissingDependencyError) as ei:
        _gmsh._import_gmsh()
    text = str(ei.value)
    assert "libGLU.so.1 is missing" in text and "\n" not in text
    assert all(p in text for p in ("libglu1-mesa", "libxcursor1", "libxft2", "libxinerama1"))


def test_gmsh_not_installed_says_pip_install(monkeypatch):
    _without_gmsh(monkeypatch, ModuleNotFoundError("No module named 'gmsh'"))
    with pytest.raises(MissingDependencyError, match="pip install gmsh"):
        _gmsh._import_gmsh()


def test_the_command_line_prints_one_line_and_exits_2(monkeypatch, capsys):
    """`masonrydam check` of a bundled dam example without gmsh's libraries."""
    from repository_paths import EXAMPLES

    _without_gmsh(monkeypatch, OSError("libGLU.so.1: cannot open shared object file: No such file or directory"))
    assert main(["check", str(EXAMPLES / "koyna_el_centro.toml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("masonrydam: error: gmsh") and "apt-get install" in err[0]
