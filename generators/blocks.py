"""2D block models from rectangles, optionally rotated: blocks on joints for reference problems
(block on an incline, direct shear, sliding and rocking blocks)."""
from __future__ import annotations

import math

import numpy as np

from masonrydam.errors import SceneError

from .grid import Rect, rectangles_to_mesh


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
            r = Rect(float(b["x0"]), float(b["y0"]), float(b["x1"]), float(b["y1"]), str(b.get("group", "blocks")), f"b{i}")
        except KeyError as exc:
            raise SceneError(f"{key}.blocks[{i}].{exc.args[0]}", "is required") from None
        if not (r.x1 > r.x0 and r.y1 > r.y0):
            raise SceneError(f"{key}.blocks[{i}]", f"needs x1 > x0 and y1 > y0, got {b}")
        rects.append(r)
    if not element_size > 0:
        raise SceneError(f"{key}.element_size", f"must be > 0, got {element_size}")
    mesh = rectangles_to_mesh(rects, element_size, order=order, element=element,
                              classify_joint=lambda a, b, o: joint_name)
    if rotation_deg:
        a = math.radians(rotation_deg)
        R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        mesh.points = np.ascontiguousarray(mesh.points @ R.T)
    return mesh
