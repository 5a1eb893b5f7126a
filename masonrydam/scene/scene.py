"""The :class:`Scene`: what to analyse, from a TOML file or a Python dictionary."""
from __future__ import annotations

import hashlib
import json
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
        if not path.exists():
            raise SceneError("scene", f"scene file '{path}' does not exist")
        if path.is_dir():
            raise SceneError("scene", f"'{path}' is a folder; give a scene TOML file (e.g. one in examples/)")
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise SceneError("scene", f"cannot read '{path}': {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise SceneError("scene", f"'{path}' is not a text file (not UTF-8); a scene is a TOML file") from None
        except tomllib.TOMLDecodeError as exc:
            raise SceneError("scene", f"'{path}' is not valid TOML: {exc}") from None
        return cls(data, base_dir=path.parent, source=str(path))

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


def as_scene(scene) -> Scene:
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return Scene(scene)
    if isinstance(scene, (str, Path)):
        return Scene.from_toml(scene)
    raise TypeError(f"expected a Scene, a dict or a path to a TOML file, got {type(scene).__name__}")
