"""The documentation site builds with every warning an error (mkdocs.yml sets ``strict``): a page missing from the
navigation, a link to a page or an anchor that does not exist, a figure that is not there, or a docstring of the
API reference that mkdocstrings cannot render fails the test suite."""
from __future__ import annotations

import os
import subprocess
import sys

from repository_paths import REPOSITORY_ROOT


def test_docs_site_builds_strict(tmp_path):
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                          cwd=REPOSITORY_ROOT, env=env, capture_output=True, text=True, timeout=600)
    warnings = [line for line in done.stderr.splitlines() if "WARNING" in line or "ERROR" in line]
    assert done.returncode == 0, "mkdocs build --strict failed:\n" + "\n".join(warnings or done.stderr.splitlines()[-20:])
    assert (tmp_path / "site" / "index.html").exists()
    api = (tmp_path / "site" / "api" / "index.html").read_text(encoding="utf-8")
    assert "open_result" in api and "masonry_wall_2d" in api  # the API reference was rendered from the docstrings
