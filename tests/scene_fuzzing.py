"""Mutated scenes and the property every one of them must have (the fuzzed scene suite,
tests/scene/test_scene_fuzz.py, and its longer run, benchmarks/fuzz_scenes.py).

A mutation starts from a small valid scene (a bundled example or a scene of this suite) and changes it the way a
user's slip would: a key dropped, a key added that the language does not know, a value of another type, zero,
negative, NaN or infinite, a number ten times too large or too small (a unit slipped), a facet set, group or record
that does not exist, a stage removed, duplicated, moved or turned into another type, a modal-only scene, an output
stride beyond the steps.

The property (:func:`outcome`): ``masonrydam check`` and ``masonrydam run`` either succeed or refuse with a
:class:`~masonrydam.errors.MasonrydamError`, which the command line prints as one line and exit status 2 (a
:class:`~masonrydam.errors.SceneError` names its scene key). Never another exception (a traceback), never a NaN
in a completed result, never a result file that was there before changed by a run that failed.
"""
from __future__ import annotations

import copy
import hashlib
import json
import math
import tomllib
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

import masonrydam
from masonrydam.cli.main import check_scene, default_scene_path
from masonrydam.errors import MasonrydamError, RunStopped, SceneError

from repository_paths import EXAMPLES
from scenes import small_wall

DEFAULT_SCENE = default_scene_path()


def _load(path: Path) -> dict:
    with open(path, "rb") as f:
        return tomllib.load(f)


def _example(name: str) -> dict:
    return _load(EXAMPLES / name)


def tiny_wall() -> dict:
    """A 3-course, 2-unit wall (scenes.small_wall: units 0.2 x 0.1 m, one element per unit height) with dry
    Mohr-Coulomb bed joints, pressed in two steps, then its modes."""
    bed = {"law": "mohr_coulomb", "normal_stiffness": "82 N/mm3", "shear_stiffness": "36 N/mm3", "cohesion": 0.0,
           "friction_angle": 36.87, "residual_shear_stiffness": 0.0}
    stages = [{"name": "gravity", "steps": 1, "loads": [{"type": "self_weight"}]},
              {"name": "press", "steps": 2, "loads": [{"type": "edge_pressure", "set": "top_edge", "pressure": "0.1 MPa"}]},
              {"name": "modes", "type": "modal", "modes": 3}]
    return small_wall(length=0.4, height=0.3, elements_per_unit=1, bed_joints=bed, stages=stages)


#: the scenes mutations start from: the default scene and small bundled examples (2D and 3D, static, dynamic and
#: rocking), each solved in one to three seconds with a warm numba cache
BASE_SCENES = {
    "block_on_incline": lambda: _example("block_on_incline.toml"),
    "sliding_block_pulse": lambda: _example("sliding_block_pulse.toml"),
    "housner_rocking": lambda: _example("housner_rocking.toml"),
    "block_3d_oblique": lambda: _example("block_3d_oblique.toml"),
    "default_wall_push": lambda: _load(DEFAULT_SCENE),
    "tiny_wall": tiny_wall,
}

#: values a leaf is replaced by: another type, zero, negative, NaN, infinite, a unit of the wrong kind
ODD_VALUES = (0, -1, -0.5, 0.0, 1e30, -1e30, 1e-30, math.nan, math.inf, -math.inf, "", "abc", "1 kg", "1 MPa", "2 m",
              "3 s", True, [], {}, [1.0, 2.0], {"bogus": 1})
#: names that exist nowhere (facet sets, groups, records, materials)
MISSING_NAME = "nowhere"
#: what a mutation does; :func:`mutate` takes an index into this
OPERATIONS = ("drop", "odd_value", "scale_up", "scale_down", "unknown_key", "missing_name", "stage_drop",
              "stage_duplicate", "stage_reverse", "stage_retype", "modal_only", "stride_beyond")
#: leaf keys that size the work (steps, element counts, durations): never scaled up, so that a mutated run stays
#: seconds long (a scene of a thousand times the steps is valid, only slow); nothing under ``mesh`` is scaled either
#: (a wall a thousand times as long has a million units)
WORK_KEYS = {"steps", "duration", "modes", "elements_per_unit", "max_iterations", "max_substeps", "stride"}
SIZE_KEYS = {"element_size", "dt", "dt_min"}  # never scaled down, for the same reason


def _paths(node, prefix=()):
    """Every (path, value) below ``node`` (dicts and lists), depth first."""
    out = []
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for k, v in items:
        out.append((prefix + (k,), v))
        out += _paths(v, prefix + (k,))
    return out


def _parent(scene, path):
    node = scene
    for k in path[:-1]:
        node = node[k]
    return node


def path_text(path) -> str:
    """``("stages", 1, "loads")`` as ``stages[1].loads``."""
    text = ""
    for k in path:
        text += f"[{k}]" if isinstance(k, int) else (f".{k}" if text else k)
    return text


def mutate(scene: dict, operation: str, pick: int, value_pick: int = 0) -> str:
    """Apply ``operation`` to ``scene`` (in place) at the ``pick``-th eligible place (modulo their count), with the
    ``value_pick``-th odd value; returns what was done, in words (or ``""`` where nothing was eligible)."""
    paths = _paths(scene)
    stages = scene.get("stages") if isinstance(scene.get("stages"), list) else None
    if operation == "drop":
        if not paths:
            return ""
        path = paths[pick % len(paths)][0]
        parent = _parent(scene, path)
        del parent[path[-1]]
        return f"dropped {path_text(path)}"
    if operation == "odd_value":
        path = paths[pick % len(paths)][0]
        value = ODD_VALUES[value_pick % len(ODD_VALUES)]
        _parent(scene, path)[path[-1]] = copy.deepcopy(value)
        return f"{path_text(path)} = {value!r}"
    if operation in ("scale_up", "scale_down"):
        up = operation == "scale_up"
        numbers = [p for p, v in paths if isinstance(v, (int, float)) and not isinstance(v, bool) and p[0] != "mesh"
                   and not (up and p[-1] in WORK_KEYS) and not (not up and p[-1] in SIZE_KEYS)]
        if not numbers:
            return ""
        path = numbers[pick % len(numbers)]
        parent = _parent(scene, path)
        parent[path[-1]] = parent[path[-1]] * (10 if up else 0.1)
        return f"{path_text(path)} x {10 if up else 0.1}"
    if operation == "unknown_key":
        dicts = [()] + [p for p, v in paths if isinstance(v, dict)]
        path = dicts[pick % len(dicts)]
        node = scene if not path else _parent(scene, path)[path[-1]]
        node["bogus_key"] = 1
        return f"{path_text(path + ('bogus_key',))} added"
    if operation == "missing_name":
        names = [p for p, v in paths if isinstance(v, str) and p[-1] in ("set", "record", "group", "groups", "name")]
        names += [p for p, v in paths if isinstance(v, list) and p[-1] == "groups"]
        if not names:
            return ""
        path = names[pick % len(names)]
        old = _parent(scene, path)[path[-1]]
        _parent(scene, path)[path[-1]] = [MISSING_NAME] if isinstance(old, list) else MISSING_NAME
        return f"{path_text(path)} = {MISSING_NAME!r}"
    if stages is None or not stages:
        return ""
    i = pick % len(stages)
    if operation == "stage_drop":
        del stages[i]
        return f"stages[{i}] dropped"
    if operation == "stage_duplicate":
        stages.insert(i, copy.deepcopy(stages[i]))
        return f"stages[{i}] duplicated"
    if operation == "stage_reverse":
        stages.reverse()
        return "stages reversed"
    if operation in ("stage_retype", "stride_beyond") and not isinstance(stages[i], dict):
        return ""
    if operation == "stage_retype":
        kind = ("modal", "dynamic", "static")[value_pick % 3]
        stages[i]["type"] = kind
        return f"stages[{i}].type = {kind!r}"
    if operation == "modal_only":
        scene["stages"] = [{"type": "modal"}]
        return "the only stage a modal one"
    if operation == "stride_beyond":
        stages[i]["output"] = {"stride": 10**6}
        return f"stages[{i}].output.stride = 1e6"
    raise ValueError(operation)


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _one_line(exc: BaseException) -> str:
    """The first line the command line prints for ``exc``; fails where a scene error is not one line naming its key
    (a mechanism's error lists its free parts on further lines, as the command line prints them)."""
    text = str(exc)
    assert text.strip(), f"{type(exc).__name__} without a message"
    assert "Traceback" not in text, f"{type(exc).__name__} carries a traceback: {text!r}"
    if isinstance(exc, SceneError):
        assert "\n" not in text, f"a scene error of more than one line: {text!r}"
        assert exc.key and f"scene key '{exc.key}'" in text, f"a scene error that names no key: {text!r}"
    return f"{type(exc).__name__}: {text.splitlines()[0]}"


def assert_no_nan(ds) -> None:
    """No NaN in a completed result: the displacements at every step, every variable at the steps of dynamic stages
    (finite ``time``) and every variable without a step. (A static step has no time, velocity or energy terms of the
    dynamic stages: they are NaN there by design, the writer's fill; a ground record has one NaN between the records of
    two dynamic stages.)"""
    dynamic = np.isfinite(ds.time.values) if "time" in ds.coords else np.zeros(ds.sizes.get("step", 0), bool)
    stages = json.loads(ds.attrs.get("scene", "{}")).get("stages", [])
    separators = max(sum(st.get("type") == "dynamic" for st in stages) - 1, 0)
    for name, var in ds.variables.items():
        if var.dtype.kind != "f" or not var.size:
            continue
        if name.startswith(("ground_acceleration_record_", "ground_record_time_")):
            # the records of successive dynamic stages, one NaN between two (the writer's pen-up)
            assert int(np.isnan(var.values).sum()) <= separators, f"NaN in the completed result's {name!r}"
            continue
        values = var.values
        if "step" in var.dims and name != "displacement":
            values = var.isel(step=np.nonzero(dynamic)[0]).values
        assert not np.isnan(values).any(), f"NaN in the completed result's {name!r}"


def outcome(scene: dict, folder: Path) -> str:
    """Check and run ``scene`` as the command line does and assert the property of the module docstring; returns
    what happened in one line (``valid, completed``, ``refused by check: ...``, ``stopped: ...``)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_scene(copy.deepcopy(scene))
    except MasonrydamError as exc:
        return f"refused by check: {_one_line(exc)}"
    out = folder / "result.nc"
    xr.Dataset({"earlier": ("x", np.arange(3.0))}).to_netcdf(out)  # an earlier result a failed run must keep
    before = _digest(out)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = masonrydam.run(copy.deepcopy(scene), output=out)
    except (MasonrydamError, RunStopped) as exc:
        assert _digest(out) == before, "a run that failed changed the result file that was there before"
        return f"run stopped: {_one_line(exc)}"
    try:
        if ds.attrs.get("completed") == "true":
            assert_no_nan(ds)
    finally:
        ds.close()
    return f"valid, completed {ds.attrs.get('completed')}"
