"""Parametric model generators for masonrydam.

- :mod:`generators.grid`: conformal structured meshes of axis-aligned rectangular blocks (fast, no gmsh);
- :mod:`generators.walls`: 2D masonry walls (running or stack bond) with optional beams;
- :mod:`generators.blocks`: named rectangular blocks, optionally rotated (reference problems).

Every generator returns a :class:`masonrydam.mesh.Mesh` with interfaces already inserted on the joints.
"""
from .blocks import blocks_2d
from .grid import Rect, rectangles_to_mesh
from .walls import masonry_wall_2d

GENERATORS = {"masonry_wall_2d": masonry_wall_2d, "blocks_2d": blocks_2d}

__all__ = ["Rect", "rectangles_to_mesh", "masonry_wall_2d", "blocks_2d", "GENERATORS"]
