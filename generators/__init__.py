"""Parametric model generators for masonrydam.

- :mod:`generators.grid`: conformal structured meshes of axis-aligned rectangular blocks (fast, no gmsh);
- :mod:`generators.walls`, :mod:`generators.walls3d`: masonry walls in 2D and 3D (stretcher, stack,
  header, English and Flemish bonds; openings with lintels; beams; Lourenço's unit cracks);
- :mod:`generators.grid3d`: the same for axis-aligned boxes with hexahedra (3D);
- :mod:`generators.blocks`: named rectangular blocks or boxes, optionally rotated (sliding, rocking and incline checks);
- :mod:`generators.extrude`: a 2D jointed model extruded into a 3D slab;
- :mod:`generators.dams`: gravity dam sections (2D; Koyna preset) and dams of monoliths across a
  valley (3D), with lift, base and contraction joints, meshed with gmsh;
- :mod:`generators.arch_dams`: single-centre arch dams of cantilever monoliths (3D) in a trapezoidal
  valley, with lift, contraction and base joints and an optional foundation (a mapped hexahedral grid
  built in numpy, no gmsh).

Every generator returns a :class:`masonrydam.mesh.Mesh` with interfaces already inserted on the joints.
"""
from .arch_dams import arch_dam_3d
from .blocks import blocks_2d, blocks_3d
from .dams import gravity_dam_2d, gravity_dam_3d
from .extrude import extrude_2d, extruded
from .grid import Rect, rectangles_to_mesh
from .grid3d import Box, boxes_to_mesh
from .walls import masonry_wall_2d
from .walls3d import masonry_wall_3d

GENERATORS = {"masonry_wall_2d": masonry_wall_2d, "masonry_wall_3d": masonry_wall_3d, "blocks_2d": blocks_2d, "blocks_3d": blocks_3d,
              "extruded": extruded, "gravity_dam_2d": gravity_dam_2d, "gravity_dam_3d": gravity_dam_3d,
              "arch_dam_3d": arch_dam_3d}

__all__ = ["Rect", "rectangles_to_mesh", "Box", "boxes_to_mesh", "masonry_wall_2d", "masonry_wall_3d", "blocks_2d", "blocks_3d",
           "extrude_2d", "extruded", "gravity_dam_2d", "gravity_dam_3d", "arch_dam_3d", "GENERATORS"]
