"""The house rules of docs/architecture.md that a change can break: the rooms import only rooms
below them (the import-linter contracts of pyproject.toml), no module grows past what one person holds in
mind, and no code outside ``materials/`` and the numba kernels tests a law by name or reads a law's
state and parameter columns (the law descriptors of ``materials/joint_laws.py`` and
``materials/continuum_laws.py`` say what a caller needs)."""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "masonrydam"
#: the longest module allowed in masonrydam/ (lines)
MAX_MODULE_LINES = 900
#: where law names and law columns belong: the laws themselves and the numba kernels that inline them
LAW_ROOMS = ("materials/", "elements/", "solvers/joint_space/kernels.py")
#: the Mohr-Coulomb law's state and parameter columns (masonrydam/materials/mohr_coulomb.py)
MOHR_COULOMB_COLUMNS = ("P_KS", "P_KN", "P_COHESION", "P_TAN_PHI", "P_TENSILE_STRENGTH", "P_KS_RESIDUAL",
                        "P_OPEN_TANGENT", "N_JOINT_PARAMS", "S_CODE", "S_BOND_BROKEN", "S_PLASTIC_SLIP",
                        "S_BACK_STRESS", "N_JOINT_STATE")


def _modules():
    return sorted(PACKAGE.rglob("*.py"))


def test_the_import_linter_contracts_hold():
    exe = shutil.which("lint-imports") or str(Path(sys.executable).with_name("lint-imports"))
    if not Path(exe).exists():
        pytest.fail("import-linter is not installed: pip install '.[test]'")
    done = subprocess.run([exe, "--config", str(ROOT / "pyproject.toml")], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert "0 broken" in done.stdout


def test_no_module_is_longer_than_one_person_holds_in_mind():
    long = {str(p.relative_to(ROOT)): n for p in _modules() if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES}
    assert not long, f"split these modules by what their parts do (docs/architecture.md): {long}"


def _lines_outside_the_law_rooms(pattern) -> list[str]:
    """``path:line: text`` of every line of masonrydam/ outside :data:`LAW_ROOMS` that ``pattern`` matches."""
    found = []
    for p in _modules():
        rel = p.relative_to(PACKAGE).as_posix()
        if rel.startswith(LAW_ROOMS):
            continue
        found += [f"{rel}:{k}: {line.strip()}" for k, line in enumerate(p.read_text().splitlines(), 1)
                  if pattern.search(line)]
    return found


def test_no_law_is_tested_by_name_outside_the_laws():
    by_name = re.compile(r"""(law|\.name)\s*(==|!=)\s*["'](composite|mohr_coulomb|linear|von_mises|tresca|"""
                         r"""drucker_prager)["']|law\s+(not\s+)?in\s*\(""")
    found = _lines_outside_the_law_rooms(by_name)
    assert not found, "ask the law's descriptor instead:\n" + "\n".join(found)


def test_no_law_column_is_read_outside_the_laws():
    column = re.compile(r"\b(mc\.(%s)|from \S*mohr_coulomb import)" % "|".join(MOHR_COULOMB_COLUMNS))
    found = _lines_outside_the_law_rooms(column)
    assert not found, "ask the law's descriptor or the joint group instead:\n" + "\n".join(found)


def test_every_effect_names_its_module_and_test_files_that_exist():
    """The registry is the map of the effects (docs/architecture.md): each entry's module imports and each of
    its test files exists, so that a reader can go from a line of ``simulated_effects`` to the code and the
    checks."""
    import importlib

    from masonrydam.effects import registry

    for name, effect in registry().items():
        importlib.import_module(effect.module)
        for path in (p.strip() for p in effect.tests.split(",")):
            assert (ROOT / path).is_file(), f"effect '{name}' names a missing test file {path!r}"
