"""Scenes: what to analyse (TOML or Python), validation, model building (:mod:`.build`), stage building
(:mod:`.stages`) and running (:mod:`.run`, with :mod:`.recording`, :mod:`.summary`, :mod:`.progress`)."""
from .build import build_mesh, build_model, effects
from .run import run
from .scene import Scene
from .stages import build_stages

__all__ = ["Scene", "build_mesh", "build_model", "build_stages", "effects", "run"]
