"""Large displacements (the total Lagrangian description of Tzamtzis & Asteris): the effect ``[model] kinematics =
"large"``, with ``[joints.<set>] frame``.

Schema fragment: :data:`~masonrydam.assembly.groups.KINEMATICS`, :data:`~masonrydam.assembly.groups.JOINT_FRAMES`
(the groups interpret them); model contribution: total Lagrangian
blocks (:mod:`masonrydam.elements.continuum_large`) and joints whose frame turns with them
(:mod:`masonrydam.elements.interface_large`), chosen per group by the scene builder; reference and tests:
:data:`EFFECTS` (docs/continuum_nonlinearity.md).
"""
from __future__ import annotations

from .base import Effect


def _describe(scene: dict, model) -> list[str]:
    if not model.large:
        return []
    frames = sorted({g.frame_surface.replace("_", "-") for g in model.igroups})
    joints = f" (joint frames: {', '.join(frames)})" if frames else ""
    return ["large displacements: total Lagrangian St. Venant-Kirchhoff blocks (Green-Lagrange strain, second "
            "Piola-Kirchhoff stress; Bathe 1996 sec. 6.2.3) and joints whose frame turns with their current "
            "mid-surface or bottom face" + joints]


def _effects():
    return [Effect("large_kinematics", "[model] kinematics = \"large\"", __name__,
                   "total Lagrangian formulation (Bathe, Finite Element Procedures, 1996, sec. 6.2.3; Belytschko, Liu "
                   "& Moran 2000, sec. 4.9); co-rotational interface frame (Crisfield 1991, ch. 7)",
                   "tests/elements/test_large_kinematics.py", _describe)]


EFFECTS = _effects()
