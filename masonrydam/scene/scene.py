"""The :class:`Scene`: what to analyse, from a TOML file or a Python dictionary."""
from __future__ import annotations

import hashlib
import json
import re
import tomllib
from pathlib import Path

from ..errors import SceneError
from .schema import normalize, plain


class Scene:
    """A validated scene.

    data: the raw dictionary (as in the TOML file; a copy, with NumPy values made plain Python ones);
    base_dir: folder against which relative mesh paths are resolved; source: where it came from (file path or '<dict>').
    ``normalized`` holds the validated SI form; ``hash`` a SHA-256 of it (plus the mesh file bytes).
    """

    def __init__(self, data: dict, base_dir: str | Path = ".", source: str = "<dict>"):
        self.data = plain(data)  # a deep copy; np.int64(3) -> 3, arrays -> lists (schema.plain)
        self.base_dir = Path(base_dir)
        self.source = source
        self.normalized = normalize(self.data)

    @classmethod
    def from_toml(cls, path: str | Path) -> "Scene":
        path = Path(path)
        return cls(read_toml(path, "scene", "a scene", "(e.g. one in examples/)"), base_dir=path.parent,
                   source=str(path))

    @property
    def name(self) -> str:
        return self.normalized["model"]["name"]

    @property
    def hash(self) -> str:
        h = hashlib.sha256(json.dumps(self.normalized, sort_keys=True).encode())
        mesh = self.normalized["mesh"]
        if "file" in mesh:
            p = Path(mesh["file"])
            p = p if p.is_absolute() else self.base_dir / p
            if p.exists():
                h.update(p.read_bytes())
        return h.hexdigest()


def read_toml(path: Path, key: str, what: str, hint: str = "") -> dict:
    """The TOML file ``path`` as a dict; SceneError with ``key`` for a missing file, a folder, an unreadable
    or non-UTF-8 file or invalid TOML (``what``: "a scene", "an ensemble"; ``hint`` follows the folder message)."""
    if not path.exists():
        raise SceneError(key, f"{what[what.index(' ') + 1:]} file '{path}' does not exist")
    if path.is_dir():
        raise SceneError(key, f"'{path}' is a folder; give {what} TOML file {hint}".rstrip())
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SceneError(key, f"cannot read '{path}': {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise SceneError(key, f"'{path}' is not a text file (not UTF-8); {what} is a TOML file") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(key, f"'{path}' is not valid TOML: {exc}") from None


def path_parts(path: str) -> list:
    """``"stages[1].loads[0].pressure"`` -> ``["stages", 1, "loads", 0, "pressure"]``."""
    parts = []
    for piece in path.split("."):
        m = re.fullmatch(r"([A-Za-z0-9_-]+)((?:\[\d+\])*)", piece)
        if m is None:
            raise SceneError(path, "cannot read the key: write dotted names with list indices, e.g. "
                                   "stages[1].loads[0].pressure")
        parts.append(m.group(1))
        parts += [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
    return parts


def set_key(data: dict, path: str, value) -> None:
    """Set the scene key ``path`` (dotted, with list indices: ``stages[1].loads[0].pressure``) of the raw
    scene ``data`` to ``value``, in place. Tables along the path that do not exist are created; a list index
    must exist. Raises SceneError naming the path where it does not lead anywhere."""
    parts = path_parts(path)
    node = data
    for part, nxt in zip(parts[:-1], parts[1:]):
        if isinstance(part, int):
            if not isinstance(node, list):
                raise SceneError(path, f"index [{part}] applies to a list; the key before it is a "
                                       f"{type(node).__name__}")
            if part >= len(node):
                raise SceneError(path, f"index [{part}] is not in the scene (a list of {len(node)})")
            node = node[part]
        else:
            if not isinstance(node, dict):
                raise SceneError(path, f"'{part}' is not under a table")
            if part not in node:
                if isinstance(nxt, int):
                    raise SceneError(path, f"the scene has no list '{part}'")
                node[part] = {}
            node = node[part]
    last = parts[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise SceneError(path, f"index [{last}] is not in the scene")
    elif not isinstance(node, dict):
        raise SceneError(path, f"'{last}' is not under a table")
    node[last] = value


def parse_assignment(text: str):
    """``"KEY=VALUE"`` -> ``(key, value)``; VALUE is read as a TOML value where it is one (a number, a
    boolean, a quoted string, an array), otherwise taken as a string (``1.21 MPa``)."""
    if "=" not in text:
        raise SceneError("--set", f"expected KEY=VALUE, got {text!r}")
    key, raw = (x.strip() for x in text.split("=", 1))
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key, value


def with_overrides(scene, assignments) -> "Scene":
    """The scene (path, dict or Scene) with ``assignments`` (``"KEY=VALUE"`` strings, :func:`parse_assignment`)
    applied to its raw data, validated again."""
    sc = as_scene(scene)
    if not assignments:
        return sc
    data = plain(sc.data)
    for text in assignments:
        set_key(data, *parse_assignment(text))
    return Scene(data, base_dir=sc.base_dir, source=f"{sc.source} with {' '.join(assignments)}")


def as_scene(scene) -> Scene:
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return Scene(scene)
    if isinstance(scene, (str, Path)):
        return Scene.from_toml(scene)
    raise TypeError(f"expected a Scene, a dict or a path to a TOML file, got {type(scene).__name__}")
