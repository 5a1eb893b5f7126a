"""Block models from rectangles (2D) or boxes (3D), optionally rotated: blocks on joints for
closed-form checks (block on an incline, direct shear, sliding and rocking blocks)."""
from __future__ import annotations

import math

import numpy as np

from masonrydam.errors import SceneError
from masonrydam.units import quantity

from .grid import Rect, rectangles_to_mesh
from .grid3d import Box, boxes_to_mesh, rotation_matrix


#: the most cells a block model may have (about a gigabyte of mesh arrays): more is an element size slipped by
#: orders of magnitude (1e-30 m), refused before any array is sized
MAX_CELLS = 10_000_000


def _check_cell_count(extents, element_size: float, key: str) -> None:
    """Refuse an ``element_size`` (m) that would cut the model's ``extents`` (m, one per axis) into more than
    :data:`MAX_CELLS` cells."""
    cells = math.prod(max(1.0, math.ceil(e / element_size)) for e in extents)
    if not cells <= MAX_CELLS:
        raise SceneError(f"{key}.element_size", f"{element_size:.3g} m cuts the {' x '.join(f'{e:.3g}' for e in extents)} "
                                                f"m model into about {cells:.3g} elements, more than {MAX_CELLS:.0e}: "
                                                "a unit slipped?")


def _coordinate(block: dict, name: str, key: str) -> float:
    """A block coordinate (m, or a length with its unit): finite and plausible, errors name the key."""
    return quantity(block[name], "length", f"{key}.{name}")


def blocks_2d(
    blocks: list,
    element_size: float,
    order: int = 1,
    element: str = "quad",
    rotation_deg: float = 0.0,
    joint_name: str = "joints",
    key: str = "mesh.parameters",
):
    """Axis-aligned rectangular blocks meshed conformally, interfaces between different blocks.

    blocks: list of ``{x0, y0, x1, y1, group}`` tables (m); each block is its own body; element
    group = ``group``. element_size: largest element edge (m). rotation_deg: the whole model is
    rotated counter-clockwise about the origin (node and facet sets keep their meaning:
    'base', 'top', 'left', 'right' refer to the unrotated model). All joints go to ``joint_name``.
    """
    if not isinstance(blocks, list) or not blocks:
        raise SceneError(f"{key}.blocks", "give a list of blocks {x0, y0, x1, y1, group}")
    rects = []
    for i, b in enumerate(blocks):
        if not isinstance(b, dict):
            raise SceneError(f"{key}.blocks[{i}]", f"expected a table, got {b!r}")
        for k in b:
            if k not in ("x0", "y0", "x1", "y1", "group"):
                raise SceneError(f"{key}.blocks[{i}].{k}", "unknown key (use x0, y0, x1, y1, group)")
        try:
            r = Rect(*(_coordinate(b, k, f"{key}.blocks[{i}]") for k in ("x0", "y0", "x1", "y1")),
                     str(b.get("group", "blocks")), f"b{i}")
        except KeyError as exc:
            raise SceneError(f"{key}.blocks[{i}].{exc.args[0]}", "is required") from None
        if not (r.x1 > r.x0 and r.y1 > r.y0):
            raise SceneError(f"{key}.blocks[{i}]", f"needs x1 > x0 and y1 > y0, got {b}")
        rects.append(r)
    if not element_size > 0:
        raise SceneError(f"{key}.element_size", f"must be > 0, got {element_size}")
    _check_cell_count([max(r.x1 for r in rects) - min(r.x0 for r in rects),
                       max(r.y1 for r in rects) - min(r.y0 for r in rects)], element_size, key)
    mesh = rectangles_to_mesh(rects, element_size, order=order, element=element,
                              classify_joint=lambda a, b, o: joint_name)
    if rotation_deg:
        a = math.radians(rotation_deg)
        R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        mesh.points = np.ascontiguousarray(mesh.points @ R.T)
    return mesh


_BOX_KEYS = ("x0", "y0", "z0", "x1", "y1", "z1", "group")


def blocks_3d(
    blocks: list,
    element_size: float,
    order: int = 1,
    rotation_deg: list = None,
    joint_name: str = "joints",
    key: str = "mesh.parameters",
):
    """Axis-aligned boxes meshed conformally with hexahedra (hex8, or hex20 for ``order = 2``),
    8-node (16-node) surface interfaces between different boxes.

    blocks: list of ``{x0, y0, z0, x1, y1, z1, group}`` tables (m); each box is its own body.
    rotation_deg: ``[about_x, about_y, about_z]`` rotations (degrees, applied in that order about
    the origin) of the whole model; node and facet sets keep their unrotated meaning ('base',
    'top', ..., '<group>_nodes'). All joints go to ``joint_name``.
    """
    if not isinstance(blocks, list) or not blocks:
        raise SceneError(f"{key}.blocks", "give a list of boxes {x0, y0, z0, x1, y1, z1, group}")
    boxes = []
    for i, b in enumerate(blocks):
        if not isinstance(b, dict):
            raise SceneError(f"{key}.blocks[{i}]", f"expected a table, got {b!r}")
        for k in b:
            if k not in _BOX_KEYS:
                raise SceneError(f"{key}.blocks[{i}].{k}", f"unknown key (use {', '.join(_BOX_KEYS)})")
        try:
            box = Box(*(_coordinate(b, k, f"{key}.blocks[{i}]") for k in _BOX_KEYS[:6]), str(b.get("group", "blocks")),
                      f"b{i}")
        except KeyError as exc:
            raise SceneError(f"{key}.blocks[{i}].{exc.args[0]}", "is required") from None
        if not all(h > lo for lo, h in zip(box.lo(), box.hi())):
            raise SceneError(f"{key}.blocks[{i}]", f"needs x1 > x0, y1 > y0 and z1 > z0, got {b}")
        boxes.append(box)
    if not element_size > 0:
        raise SceneError(f"{key}.element_size", f"must be > 0, got {element_size}")
    _check_cell_count([max(b.hi()[a] for b in boxes) - min(b.lo()[a] for b in boxes) for a in range(3)],
                      element_size, key)
    mesh = boxes_to_mesh(boxes, element_size, order=order, classify_joint=lambda a, b, axis: joint_name)
    if rotation_deg is not None:
        if not isinstance(rotation_deg, (list, tuple)) or len(rotation_deg) != 3:
            raise SceneError(f"{key}.rotation_deg", f"expected [about_x, about_y, about_z] in degrees, got {rotation_deg!r}")
        R = rotation_matrix([quantity(a, "angle", f"{key}.rotation_deg[{j}]") for j, a in enumerate(rotation_deg)])
        mesh.points = np.ascontiguousarray(mesh.points @ R.T)
    return mesh
