"""The effects registry (masonrydam/effects/__init__.py): every physical effect a scene can ask for is
one module with its schema fragment, its reference and its tests, and a scene that does not ask for an
effect gets no line for it in ``simulated_effects``."""
from __future__ import annotations

import importlib
from pathlib import Path

from masonrydam.effects import load_types, registry, sections
from masonrydam.scene import Scene
from masonrydam.scene import build_mesh, build_model, effects
from repository_paths import TESTS


def test_every_effect_names_its_module_reference_and_tests():
    reg = registry()
    # The registry names test files; tests/ groups them in room folders, so a file is found by its name
    # (test file names are unique across the folders).
    test_files = {p.name for p in TESTS.rglob("test_*.py")}
    assert {"self_weight", "reservoir", "uplift", "ground_motion", "inertia", "damping"} <= set(reg)
    for name, e in reg.items():
        assert importlib.import_module(e.module).EFFECTS, name
        assert len(e.reference) > 10 and e.asked_by, name
        for path in e.tests.split(", "):
            assert Path(path).name in test_files, f"{name}: {path}"


def test_scene_sections_and_load_types_come_from_the_effects():
    assert set(sections()) == {"reservoir", "foundation"}
    assert {"self_weight", "nodal", "traction", "pressure", "displacement", "reservoir"} <= set(load_types())


def test_a_scene_lists_only_what_it_asks_for():
    scene = {"model": {"name": "b"},
             "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.5, "blocks": [
                 {"x0": 0, "y0": 0, "x1": 1, "y1": 1, "group": "a"}]}},
             "materials": {"a": {"youngs_modulus": 1e9, "poisson_ratio": 0.2, "density": 1000.0}},
             "supports": [{"set": "base"}],
             "stages": [{"loads": [{"type": "self_weight"}]}]}
    sc = Scene(scene)
    model = build_model(sc.normalized, build_mesh(sc.normalized, "."))
    lines = effects(sc.normalized, model)
    assert lines[-2:] == ["self-weight", "static analysis (no inertia, no damping)"]
    for name, e in registry().items():
        if name not in ("self_weight", "static"):
            assert e.describe(sc.normalized, model) == [], name


def test_a_static_scene_loads_no_record_reader_and_compiles_no_time_stepping_kernel():
    """A scene without a ground motion or a dynamic stage pays nothing for them: the default static scene neither
    imports obspy (the records' reader, about 35 ms of start-up, AMD EPYC) nor compiles the joints' forces-only
    kernel of time stepping (``interface_forces``, about 2 s of a first run with a fresh numba cache: a static
    step's forces-only evaluations use ``interface_evaluate``, already compiled for its tangents). In a fresh
    process, since both would be loaded for good by any earlier test."""
    import subprocess
    import sys

    code = ("import sys\n"
            "import masonrydam\n"
            "from masonrydam.cli.main import default_scene_path\n"
            "from masonrydam.elements import interface\n"
            "ds = masonrydam.run(default_scene_path())\n"
            "print('OBSPY', 'obspy' in sys.modules)\n"
            "print('FORCES_KERNEL', len(interface.interface_forces.signatures))\n"
            "print('STEPS', int(ds.sizes['step']))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "OBSPY False" in out, out
    assert "FORCES_KERNEL 0" in out, out
    assert "STEPS" in out and "STEPS 0" not in out, out
