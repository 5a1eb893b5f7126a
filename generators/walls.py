"""2D masonry wall generator (simplified micro-model: units expanded by the joint thickness,
joints of zero thickness; Lourenco 1996, PhD thesis TU Delft, sec. 6).
"""
from __future__ import annotations

import numpy as np

from masonrydam.errors import SceneError

from .grid import Rect, rectangles_to_mesh


def masonry_wall_2d(
    length: float,
    height: float,
    unit_length: float,
    unit_height: float,
    joint_thickness: float = 0.0,
    bond: str = "running",
    elements_per_unit: int = 2,
    order: int = 1,
    element: str = "quad",
    base_beam_height: float = 0.0,
    top_beam_height: float = 0.0,
    beam_joints: bool = True,
    key: str = "mesh.parameters",
):
    """A wall of ``height / (unit_height + joint_thickness)`` courses on optional steel/concrete beams.

    Lengths in m. Expanded unit size = unit size + joint_thickness. ``bond``: 'running' (half-unit
    offset, half units at the ends as built) or 'stack'. Element groups: 'units', 'base_beam',
    'top_beam'. Joint sets: 'bed_joints', 'head_joints', and with ``beam_joints`` 'base_joint' and
    'top_joint' between the beams and the wall (otherwise the beams are glued).
    Node sets: base, top, left, right; facet sets base_edge, top_edge, left_edge, right_edge.
    """
    lu, hu = unit_length + joint_thickness, unit_height + joint_thickness
    checks = {"length": length, "height": height, "unit_length": unit_length, "unit_height": unit_height}
    for name, v in checks.items():
        if not v > 0:
            raise SceneError(f"{key}.{name}", f"must be > 0, got {v}")
    if joint_thickness < 0 or joint_thickness >= min(unit_length, unit_height):
        raise SceneError(f"{key}.joint_thickness", f"must be in [0, unit size), got {joint_thickness}")
    if lu > length + 1e-12 or hu > height + 1e-12:
        raise SceneError(f"{key}.unit_length", f"expanded unit {lu} x {hu} m is larger than the wall {length} x {height} m")
    if bond not in ("running", "stack"):
        raise SceneError(f"{key}.bond", f"unknown bond {bond!r} for the 2D wall; use 'running' or 'stack'")
    if element not in ("quad", "quad9", "tri"):
        raise SceneError(f"{key}.element", f"must be 'quad', 'quad9' or 'tri', got {element!r}")
    if order not in (1, 2):
        raise SceneError(f"{key}.order", f"must be 1 or 2, got {order!r}")
    if elements_per_unit < 1:
        raise SceneError(f"{key}.elements_per_unit", f"must be >= 1, got {elements_per_unit}")
    n_courses = int(round(height / hu))
    if abs(n_courses * hu - height) > 1e-6 * height:
        raise SceneError(f"{key}.height", f"{height} m is not a whole number of courses of {hu} m")
    rects = []
    y = base_beam_height
    if base_beam_height > 0:
        rects.append(Rect(0.0, 0.0, length, base_beam_height, "base_beam", "beam"))
    for c in range(n_courses):
        offset = 0.5 * lu if (bond == "running" and c % 2 == 1) else 0.0
        edges = [0.0]
        x = offset if offset > 0 else lu
        while x < length - 1e-9:
            edges.append(x)
            x += lu
        edges.append(length)
        edges = np.array(edges)
        for a, b in zip(edges[:-1], edges[1:]):
            rects.append(Rect(float(a), y, float(b), y + hu, "units", "unit"))
        y += hu
    if top_beam_height > 0:
        rects.append(Rect(0.0, y, length, y + top_beam_height, "top_beam", "beam"))

    def classify(a: Rect, b: Rect, orientation: str):
        if a.kind == "beam" or b.kind == "beam":
            if not beam_joints:
                return None
            return "base_joint" if min(a.y0, b.y0) < base_beam_height + 1e-12 and base_beam_height > 0 and (a.group == "base_beam" or b.group == "base_beam") else "top_joint"
        return "bed_joints" if orientation == "horizontal" else "head_joints"

    size = min(lu, hu) / elements_per_unit
    return rectangles_to_mesh(rects, element_size=size, order=order, element=element, classify_joint=classify)
