"""Folders of the repository that tests read (examples, docs, benchmarks), located from this file so that a
test finds them whichever room folder of tests/ it lives in."""
from __future__ import annotations

from pathlib import Path

REPOSITORY_ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = REPOSITORY_ROOT / "examples"
DOCS = REPOSITORY_ROOT / "docs"
BENCHMARKS = REPOSITORY_ROOT / "benchmarks"
TESTS = REPOSITORY_ROOT / "tests"
