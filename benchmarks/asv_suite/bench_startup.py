"""Start-up of the command line and a warm run of the default scene as a user times them: whole
processes, numba's cache filled by ``setup_cache``."""
from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

_CLI = [sys.executable, "-c", "import sys; from masonrydam.cli.main import main; sys.exit(main())"]


def _run(*args, cwd=None):
    subprocess.run(_CLI + list(args), check=True, capture_output=True, cwd=cwd)


class CommandLine:
    """``masonrydam --version`` and ``--help`` (target: under 0.3 s), and ``masonrydam run --default``."""

    timeout = 600
    number = 1
    repeat = 5
    warmup_time = 0

    def setup_cache(self):
        with tempfile.TemporaryDirectory() as wd:  # fills numba's cache: the runs below are warm
            _run("run", "--default", "-o", str(Path(wd) / "w.nc"), "--no-progress", cwd=wd)

    def time_version(self):
        _run("--version")

    def time_help(self):
        _run("--help")

    def time_default_scene_warm(self):
        with tempfile.TemporaryDirectory() as wd:
            _run("run", "--default", "-o", str(Path(wd) / "w.nc"), "--no-progress", cwd=wd)

    time_default_scene_warm.repeat = 3
