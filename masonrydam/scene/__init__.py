"""Scenes: what to analyse (TOML or Python), validation, model building and running."""
from .run import run
from .scene import Scene

__all__ = ["Scene", "run"]
