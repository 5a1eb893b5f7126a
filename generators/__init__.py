"""Parametric model generators for masonrydam.

- :mod:`generators.grid`: conformal structured meshes of axis-aligned rectangular blocks (fast, no gmsh);
- :mod:`generators.walls`: 2D masonry walls (running or stack bond) with optional beams.

Every generator returns a :class:`masonrydam.mesh.Mesh` with interfaces already inserted on the joints.
"""
from .grid import Rect, rectangles_to_mesh
from .walls import masonry_wall_2d

GENERATORS = {"masonry_wall_2d": masonry_wall_2d}

__all__ = ["Rect", "rectangles_to_mesh", "masonry_wall_2d", "GENERATORS"]
