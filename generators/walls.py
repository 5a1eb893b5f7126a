"""Masonry wall generators: bond patterns, openings with lintels, beams and potential unit cracks
for the simplified micro-model (2D here; 3D in :mod:`generators.walls3d`, which shares the layout).

Simplified micro-model (Lourenco 1996, PhD thesis TU Delft, ch. 6; Lourenco & Rots 1997, J. Eng.
Mech. 123(7) 660-668): every unit is expanded by the joint thickness ``t`` (unit_length + t,
unit_height + t, unit_width + t) and the expanded units meet at zero-thickness interfaces (bed,
head and, in multi-wythe walls, collar joints). Optionally a potential crack interface runs through
the middle of every whole unit (Lourenco & Rots 1997, fig. 2: "potential cracks in units").

Conventions: 2D: x along the wall, y up (the elevation, plane stress); 3D: x along the wall, y across
the thickness (front face y = 0), z up. Lengths in m.

Bond patterns (definitions: Hendry, Sinha & Davies, "Design of Masonry Structures", 3rd ed., E & FN
Spon 1997, ch. 1; Brick Industry Association, Technical Notes on Brick Construction 10,
"Dimensioning and Estimating Brick Masonry", and 30, "Bonds and Patterns in Brickwork"). Every
course is set out from the left end (x = 0) of the wall, with the closers of the bond there, and
is cut at the right end (x = length), so both ends are flush; the last unit of a course is a cut
unit (bat) unless the length fits the bond. ``S`` stretcher (face = expanded unit
length ``lu``), ``H`` header (face = expanded unit width ``wu``), ``Q`` queen closer (a unit halved
lengthwise, face ``wu / 2``), ``half`` half-stretcher bat (face ``lu / 2``):

====================  ======================================  =====================================
bond                  even courses (0, 2, ...)                odd courses
====================  ======================================  =====================================
stretcher / running   S S S ...                               half S S ... (half unit at the ends)
stack                 S S S ...                               S S S ...
header                H H H ...                               Q H H ... (lap of half a header)
english               S S S ... (stretcher course)            H Q H H H ... (header course)
flemish               H S H S ...                             H Q H S H S ... (each header centred
                                                              on the stretcher below)
====================  ======================================  =====================================

2D walls show the elevation (front face) of the pattern. In 3D, stretchers of one-brick-thick bonds
(english, flemish) are pairs of units in two wythes (front and back) with a collar joint between
them; headers and closers cross the whole thickness (wall thickness = expanded unit length).
Bonds with headers need ``unit_length + t = 2 (unit_width + t)`` (bricks are made so: e.g.
210 x 100 mm with 10 mm joints), so that a header fills the thickness of two stretchers.

Openings (windows, doors) are rectangles through the wall; the units they cut are trimmed (cut
units, each remaining connected piece a separate unit) and a lintel (element group ``lintels``,
joints to the masonry in the joint set ``lintel_joints``, so they can have their own properties)
bears ``lintel_bearing`` on each side. Each opening ``i`` gets the facet set ``opening_<i>``: the
edges (2D) or faces (3D) of the masonry, lintel and beams around the hole (jambs, sill, soffit).

Design choice: meshes are built on conformal structured grids (:mod:`generators.grid`,
:mod:`generators.grid3d`), not with gmsh. Units, beams, lintels and openings are axis-aligned
rectangles / boxes, so the grid is exact, deterministic and conformal by construction, and it is
orders of magnitude faster than a boolean fragment. Measured with
``benchmarks/bench_wall_generation.py`` (2-core AMD EPYC VM, gmsh 4.15.2): one OCC ``fragment``
of the unit boxes of a stretcher wall takes 0.8 s for 125 boxes, 2.9 s for 250, 13 s for 500 and
94 s for 1000 (~26 ms per box at 500 and growing about quadratically, before any meshing), while
this generator builds a complete 3D wall of 10 050 units, hexahedra and interfaces included, in
0.9 s (2 x 1 x 1 hex8 per unit) to 4.3 s (English bond, 8 hex8 per unit and unit cracks): 0.1 to
0.4 ms per unit.
"""
from __future__ import annotations

import difflib
import numbers
from dataclasses import dataclass

import numpy as np

from masonrydam.errors import SceneError
from masonrydam.mesh.facets import element_facets
from masonrydam.mesh.model import FacetSet
from masonrydam.units import quantity

from .grid import Rect, rectangles_to_mesh

#: accepted bond names (``running`` is the 2D generator's original name of the stretcher bond)
BONDS = ("stretcher", "running", "stack", "header", "english", "flemish")
_ALIASES = {"running": "stretcher"}
#: bonds whose courses contain headers (they need unit_width and lu = 2 wu)
HEADER_BONDS = ("header", "english", "flemish")
#: (start, repeat) of the slot sequence of even and odd courses (module docstring)
_SEQUENCES = {
    "stretcher": (((), ("S",)), (("half",), ("S",))),
    "stack": (((), ("S",)), ((), ("S",))),
    "header": (((), ("H",)), (("Q",), ("H",))),
    "english": (((), ("S",)), (("H", "Q"), ("H",))),
    "flemish": (((), ("H", "S")), (("H", "Q"), ("H", "S"))),
}
_OPENING_KEYS = ("x0", "width", "height", "lintel_height", "lintel_bearing")


@dataclass(frozen=True)
class Slot:
    """One unit position of a course along the wall: [x0, x1], role 'S', 'H', 'Q' or 'half', and
    whether it is a whole (uncut) stretcher or header (those get the potential unit crack)."""

    x0: float
    x1: float
    role: str
    full: bool


@dataclass(frozen=True)
class Opening:
    """A rectangular hole [x0, x0 + width] x [z0, z0 + height] through the wall, measured from the
    left end and from the underside of the masonry (top of the base beam); z0 = 0 is a door. The
    lintel spans [x0 - lintel_bearing, x0 + width + lintel_bearing] x [z1, z1 + lintel_height]."""

    x0: float
    z0: float
    width: float
    height: float
    lintel_height: float = 0.0
    lintel_bearing: float = 0.0

    @property
    def x1(self):
        return self.x0 + self.width

    @property
    def z1(self):
        return self.z0 + self.height

    def hole(self):
        return (self.x0, self.z0, self.x1, self.z1)

    def lintel(self):
        if self.lintel_height <= 0:
            return None
        return (self.x0 - self.lintel_bearing, self.z1, self.x1 + self.lintel_bearing, self.z1 + self.lintel_height)

    def footprint(self):
        """Rectangles removed from the masonry: the hole and the lintel."""
        return [r for r in (self.hole(), self.lintel()) if r is not None]


@dataclass(frozen=True)
class WallSpec:
    """Validated wall parameters shared by the 2D and 3D generators (expanded unit sizes)."""

    length: float
    height: float
    lu: float
    hu: float
    wu: float
    bond: str
    n_courses: int
    openings: tuple
    base_beam_height: float
    top_beam_height: float


# ------------------------------------------------------------------------------------------------
# validation (every error names the parameter, before any meshing)
# ------------------------------------------------------------------------------------------------
def check_bond(bond, key: str) -> str:
    """Canonical bond name; unknown names raise a SceneError with a did-you-mean hint."""
    if not isinstance(bond, str):
        raise SceneError(f"{key}.bond", f"expected a bond name, got {bond!r}")
    b = bond.strip().lower()
    if b not in BONDS:
        close = difflib.get_close_matches(b, BONDS, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise SceneError(f"{key}.bond", f"unknown bond {bond!r}{hint} (bonds: {', '.join(BONDS)})")
    return _ALIASES.get(b, b)


def _length_value(v, key: str) -> float:
    return quantity(v, "length", key)


def parse_openings(openings, length: float, height: float, key: str, vertical: str = "y0") -> tuple:
    """Validate ``openings`` (list of dicts with x0, ``vertical`` (y0 in 2D, z0 in 3D), width,
    height and optional lintel_height, lintel_bearing; numbers in m or unit strings) against a
    wall of ``length`` x ``height`` of masonry. Openings (with their lintels) may not cross or
    touch the wall's ends or top, nor overlap or touch each other."""
    if openings is None:
        return ()
    if not isinstance(openings, (list, tuple)):
        raise SceneError(f"{key}.openings", f"expected a list of openings (tables), got {openings!r}")
    allowed = ("x0", vertical) + _OPENING_KEYS[1:]
    out = []
    for i, o in enumerate(openings):
        ok = f"{key}.openings[{i}]"
        if not isinstance(o, dict):
            raise SceneError(ok, f"expected a table with {', '.join(allowed)}, got {o!r}")
        for k in o:
            if k not in allowed:
                other = {"y0": "z0", "z0": "y0"}.get(k)
                close = [vertical] if other == vertical else difflib.get_close_matches(str(k), allowed, n=1)
                hint = f"; did you mean '{close[0]}'?" if close else f"; known keys: {', '.join(allowed)}"
                if other == vertical:
                    hint += " (2D: y up; 3D: z up, y across the thickness)"
                raise SceneError(f"{ok}.{k}", f"unknown key{hint}")
        for k in ("x0", vertical, "width", "height"):
            if k not in o:
                raise SceneError(f"{ok}.{k}", "is required")
        v = {k: _length_value(o.get(k, 0.0), f"{ok}.{k}") for k in allowed}
        for k in ("width", "height"):
            if not v[k] > 0:
                raise SceneError(f"{ok}.{k}", f"must be > 0, got {o[k]!r}")
        for k in ("lintel_height", "lintel_bearing"):
            if v[k] < 0:
                raise SceneError(f"{ok}.{k}", f"must be >= 0, got {o[k]!r}")
        if v["lintel_bearing"] > 0 and v["lintel_height"] == 0:
            raise SceneError(f"{ok}.lintel_bearing", "a lintel bearing needs a lintel: give lintel_height > 0")
        op = Opening(v["x0"], v[vertical], v["width"], v["height"], v["lintel_height"], v["lintel_bearing"])
        tol = 1e-9 * max(length, height)
        if op.x0 <= tol:
            raise SceneError(f"{ok}.x0", f"the opening must lie inside the wall: x0 = {op.x0:g} m reaches the wall's "
                                         "left end (x0 > 0)")
        if op.x1 >= length - tol:
            raise SceneError(f"{ok}.width", f"the opening x0 + width = {op.x1:g} m reaches the wall's right end "
                                            f"(length {length:g} m)")
        if op.z0 < -tol:
            raise SceneError(f"{ok}.{vertical}", f"must be >= 0 (measured from the underside of the masonry), "
                                                 f"got {op.z0:g} m")
        top = op.z1 + op.lintel_height
        if top > height + tol or (op.lintel_height == 0 and op.z1 >= height - tol):
            name = "lintel_height" if op.lintel_height > 0 else "height"
            raise SceneError(f"{ok}.{name}", f"the opening{' with its lintel' if op.lintel_height > 0 else ''} "
                                             f"reaches {top:g} m, through the wall's top (masonry height {height:g} m)")
        if op.lintel_bearing > 0 and (op.x0 - op.lintel_bearing < -tol or op.x1 + op.lintel_bearing > length + tol):
            raise SceneError(f"{ok}.lintel_bearing", f"the lintel ({op.x0 - op.lintel_bearing:g} to "
                                                     f"{op.x1 + op.lintel_bearing:g} m) runs past the wall's end")
        for j, prev in enumerate(out):
            if _rects_touch(_bbox(op.footprint()), _bbox(prev.footprint()), tol):
                raise SceneError(ok, f"overlaps or touches openings[{j}] (openings and their lintels must be "
                                     "separated by masonry)")
        out.append(op)
    return tuple(out)


def _bbox(rects):
    return (min(r[0] for r in rects), min(r[1] for r in rects), max(r[2] for r in rects), max(r[3] for r in rects))


def _rects_touch(a, b, tol) -> bool:
    """True if the closed rectangles a, b = (x0, z0, x1, z1) overlap or touch."""
    return a[0] <= b[2] + tol and b[0] <= a[2] + tol and a[1] <= b[3] + tol and b[1] <= a[3] + tol


def _positive(name, v, key):
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not v > 0:
        raise SceneError(f"{key}.{name}", f"must be > 0, got {v!r}")


def wall_spec(length, height, unit_length, unit_height, unit_width, joint_thickness, bond, openings,
              base_beam_height, top_beam_height, key, dim, vertical="y0") -> WallSpec:
    """Check the parameters shared by the 2D and 3D wall generators and return the expanded sizes."""
    for name, v in (("length", length), ("height", height), ("unit_length", unit_length),
                    ("unit_height", unit_height)):
        _positive(name, v, key)
    bond = check_bond(bond, key)
    needs_width = dim == 3 or bond in HEADER_BONDS
    if needs_width:
        if not unit_width:
            why = "the 3D wall needs the unit width" if dim == 3 else \
                f"bond '{bond}' shows headers in elevation, whose face is the unit width"
            raise SceneError(f"{key}.unit_width", f"{why}: give unit_width > 0 (e.g. '100 mm')")
        _positive("unit_width", unit_width, key)
    for name, v in (("base_beam_height", base_beam_height), ("top_beam_height", top_beam_height)):
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or v < 0:
            raise SceneError(f"{key}.{name}", f"must be >= 0, got {v!r}")
    sizes = {"unit_length": unit_length, "unit_height": unit_height}
    if needs_width:
        sizes["unit_width"] = unit_width
    smallest = min(sizes, key=sizes.get)
    if isinstance(joint_thickness, bool) or not isinstance(joint_thickness, numbers.Real) or joint_thickness < 0 \
            or joint_thickness >= sizes[smallest]:
        raise SceneError(f"{key}.joint_thickness", f"must be in [0, {smallest} = {sizes[smallest]:g} m): a joint "
                                                   f"cannot be thicker than the unit, got {joint_thickness!r}")
    t = float(joint_thickness)
    lu, hu = unit_length + t, unit_height + t
    wu = unit_width + t if needs_width else 0.0
    if bond in HEADER_BONDS and abs(lu - 2 * wu) > 1e-6 * lu:
        raise SceneError(f"{key}.unit_width", f"bond '{bond}' needs unit_length + joint = 2 (unit_width + joint) "
                                              f"(a header spans two stretcher wythes), i.e. unit_width = "
                                              f"{(lu / 2 - t):g} m for these units, got {unit_width:g} m")
    if lu > length * (1 + 1e-12):
        raise SceneError(f"{key}.unit_length", f"the expanded unit ({lu:g} m = unit_length + joint_thickness) is "
                                               f"longer than the wall ({length:g} m)")
    if hu > height * (1 + 1e-12):
        raise SceneError(f"{key}.unit_height", f"the expanded unit ({hu:g} m = unit_height + joint_thickness) is "
                                               f"taller than the wall ({height:g} m)")
    n_courses = int(round(height / hu))
    if abs(n_courses * hu - height) > 1e-6 * height:
        raise SceneError(f"{key}.height", f"{height} m is not a whole number of courses of {hu} m "
                                          f"(unit_height + joint_thickness); e.g. {max(n_courses, 1) * hu:g} m")
    ops = parse_openings(openings, length, height, key, vertical)
    return WallSpec(float(length), float(height), lu, hu, wu, bond, n_courses, ops,
                    float(base_beam_height), float(top_beam_height))


def check_mesh_options(order, elements_per_unit, element_size, key):
    if isinstance(order, bool) or order not in (1, 2):
        raise SceneError(f"{key}.order", f"must be 1 or 2, got {order!r}")
    if isinstance(elements_per_unit, bool) or not isinstance(elements_per_unit, numbers.Integral) \
            or elements_per_unit < 1:
        raise SceneError(f"{key}.elements_per_unit", f"must be an integer >= 1, got {elements_per_unit!r}")
    if isinstance(element_size, bool) or not isinstance(element_size, numbers.Real) or element_size < 0:
        raise SceneError(f"{key}.element_size",
                         f"must be >= 0 (0: unit size / elements_per_unit), got {element_size!r}")


# ------------------------------------------------------------------------------------------------
# layout
# ------------------------------------------------------------------------------------------------
def course_slots(bond: str, course: int, length: float, lu: float, wu: float) -> list[Slot]:
    """Unit positions of ``course`` (0 = bottom) of a wall of ``length`` in ``bond`` (module
    docstring): set out from x = 0, cut at x = length."""
    nominal = {"S": lu, "H": wu, "Q": 0.5 * wu, "half": 0.5 * lu}
    start, repeat = _SEQUENCES[bond][course % 2]
    tol = 1e-9 * length
    out, x, k = [], 0.0, 0
    while x < length - tol:
        role = start[k] if k < len(start) else repeat[(k - len(start)) % len(repeat)]
        x1 = x + nominal[role]
        if x1 > length - tol:
            x1 = length
        full = role in ("S", "H") and abs((x1 - x) - nominal[role]) <= tol
        out.append(Slot(round(x, 12), round(x1, 12), role, full))
        x, k = x1, k + 1
    return out


def subtract_rects(rect, cutters):
    """Connected pieces of ``rect`` = (x0, z0, x1, z1) minus the rectangles ``cutters``: a list of
    components, each a list of rectangles (cells of the local grid of all edges)."""
    x0, z0, x1, z1 = rect
    eps = 1e-9 * max(x1 - x0, z1 - z0)
    cs = [c for c in cutters if c[0] < x1 - eps and c[2] > x0 + eps and c[1] < z1 - eps and c[3] > z0 + eps]
    if not cs:
        return [[rect]]
    tol = eps
    xs = sorted({x0, x1} | {v for c in cs for v in (c[0], c[2]) if x0 + tol < v < x1 - tol})
    zs = sorted({z0, z1} | {v for c in cs for v in (c[1], c[3]) if z0 + tol < v < z1 - tol})
    keep = {}
    for i in range(len(xs) - 1):
        for j in range(len(zs) - 1):
            xc, zc = 0.5 * (xs[i] + xs[i + 1]), 0.5 * (zs[j] + zs[j + 1])
            if not any(c[0] < xc < c[2] and c[1] < zc < c[3] for c in cs):
                keep[(i, j)] = (xs[i], zs[j], xs[i + 1], zs[j + 1])
    comps, seen = [], set()
    for cell in sorted(keep):
        if cell in seen:
            continue
        stack, comp = [cell], []
        seen.add(cell)
        while stack:
            c = stack.pop()
            comp.append(c)
            for d in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                nb = (c[0] + d[0], c[1] + d[1])
                if nb in keep and nb not in seen:
                    seen.add(nb)
                    stack.append(nb)
        comps.append([keep[c] for c in sorted(comp)])
    return comps


@dataclass(frozen=True)
class Part:
    """A rectangle (2D: x0, z0, x1, z1) of the wall with its group and joint-classification kind:
    'u<id>' (a unit), 'u<id>.<h>' (half h of a unit with a potential crack), 'lintel<i>', 'beam'."""

    x0: float
    z0: float
    x1: float
    z1: float
    group: str
    kind: str
    role: str = ""
    y0: float = 0.0  # 3D: extent across the thickness
    y1: float = 0.0


def wall_parts(spec: WallSpec, unit_cracks: bool, wythes_of) -> list[Part]:
    """All parts of the wall (units, lintels, beams) in wall coordinates (z up, from the bottom of
    the base beam). ``wythes_of(slot)`` -> list of (y0, y1, crack_axis) for each unit of the slot
    across the thickness (2D: one, y ignored); crack_axis 'x' (split at mid-length along x), 'y'
    (split at mid-width along y) or None."""
    parts: list[Part] = []
    zb = spec.base_beam_height
    cut = [tuple(round(v, 12) for v in (x0, z0 + zb, x1, z1 + zb))
           for op in spec.openings for (x0, z0, x1, z1) in op.footprint()]
    top = zb + spec.n_courses * spec.hu
    if zb > 0:
        parts.append(Part(0.0, 0.0, spec.length, zb, "base_beam", "beam", "beam", *wythes_of(None)[0][:2]))
    uid = 0
    for c in range(spec.n_courses):
        z0 = round(zb + c * spec.hu, 12)
        z1 = round(zb + (c + 1) * spec.hu, 12) if c < spec.n_courses - 1 else round(top, 12)
        for slot in course_slots(spec.bond, c, spec.length, spec.lu, spec.wu):
            for y0, y1, crack in wythes_of(slot):
                comps = subtract_rects((slot.x0, z0, slot.x1, z1), cut)
                whole = len(comps) == 1 and len(comps[0]) == 1 and comps[0][0] == (slot.x0, z0, slot.x1, z1)
                if whole and unit_cracks and slot.full and crack == "x":
                    xm = round(0.5 * (slot.x0 + slot.x1), 12)
                    parts.append(Part(slot.x0, z0, xm, z1, "units", f"u{uid}.0", slot.role, y0, y1))
                    parts.append(Part(xm, z0, slot.x1, z1, "units", f"u{uid}.1", slot.role, y0, y1))
                    uid += 1
                    continue
                if whole and unit_cracks and slot.full and crack == "y":
                    ym = round(0.5 * (y0 + y1), 12)
                    parts.append(Part(slot.x0, z0, slot.x1, z1, "units", f"u{uid}.0", slot.role, y0, ym))
                    parts.append(Part(slot.x0, z0, slot.x1, z1, "units", f"u{uid}.1", slot.role, ym, y1))
                    uid += 1
                    continue
                for comp in comps:
                    for r in comp:
                        parts.append(Part(*r, "units", f"u{uid}", slot.role, y0, y1))
                    uid += 1
    for i, op in enumerate(spec.openings):
        lt = op.lintel()
        if lt is not None:
            y0, y1 = wythes_of(None)[0][:2]
            x0, z0, x1, z1 = (round(v, 12) for v in (lt[0], lt[1] + zb, lt[2], lt[3] + zb))
            parts.append(Part(x0, z0, x1, z1, "lintels", f"lintel{i}", "lintel", y0, y1))
    if spec.top_beam_height > 0:
        y0, y1 = wythes_of(None)[0][:2]
        parts.append(Part(0.0, top, spec.length, top + spec.top_beam_height, "top_beam", "beam", "beam", y0, y1))
    return parts


def joint_classifier(beam_joints: bool):
    """classify(kind_a, group_a, kind_b, group_b, axis) -> joint set name or None (glued).

    axis: 'z' (normal up: bed joints), 'x' (normal along the wall: head joints), 'y' (normal across
    the thickness: collar joints). Pieces of one unit (same id) are glued, its two halves are joined
    by a 'unit_cracks' interface; beams by 'base_joint' / 'top_joint' (or glued without
    ``beam_joints``); lintels by 'lintel_joints'."""
    names = {"z": "bed_joints", "x": "head_joints", "y": "collar_joints"}

    def classify(ka, ga, kb, gb, axis):
        if ka == "beam" or kb == "beam":
            if not beam_joints:
                return None
            return "base_joint" if "base_beam" in (ga, gb) else "top_joint"
        if ka.startswith("lintel") or kb.startswith("lintel"):
            return "lintel_joints"
        ua, _, ha = ka.partition(".")
        ub, _, hb = kb.partition(".")
        if ua == ub:
            return "unit_cracks" if ha != hb else None
        return names[axis]

    return classify


def opening_facets(mesh, spec: WallSpec):
    """Facet sets ``opening_<i>``: the element facets (edges in 2D, faces in 3D) on the boundary of
    each hole (x = x0 or x1 for z in [z0, z1]; z = z0 or z1 for x in [x0, x1]), oriented outward
    from the material (into the hole)."""
    dim = mesh.dim
    zc = dim - 1  # vertical axis
    zb = spec.base_beam_height
    span = float(np.ptp(mesh.points, axis=0).max())
    tol = 1e-9 * span
    out = {}
    for i, op in enumerate(spec.openings):
        x0, x1, z0, z1 = op.x0, op.x1, op.z0 + zb, op.z1 + zb
        found, ftype = [], None
        for b in mesh.blocks:
            for ft, local in element_facets(b.type):
                nodes = b.cells[:, list(local)]
                p = mesh.points[nodes]  # (n, k, dim)
                x, z = p[..., 0], p[..., zc]
                in_x = ((x >= x0 - tol) & (x <= x1 + tol)).all(axis=1)
                in_z = ((z >= z0 - tol) & (z <= z1 + tol)).all(axis=1)
                on = np.zeros(len(nodes), dtype=bool)
                for axis_vals, val, other in ((x, x0, in_z), (x, x1, in_z), (z, z0, in_x), (z, z1, in_x)):
                    on |= (np.abs(axis_vals - val) < tol).all(axis=1) & other
                if on.any():
                    found.append(nodes[on])
                    ftype = ft
        if found:
            out[f"opening_{i}"] = FacetSet(ftype, np.vstack(found))
    return out


def add_common_sets(mesh, spec: WallSpec):
    """Node set 'beams' (nodes of both beams) and the opening facet sets."""
    beam_nodes = [b.cells.ravel() for b in mesh.blocks if b.name in ("base_beam", "top_beam")]
    if beam_nodes:
        mesh.node_sets["beams"] = np.unique(np.concatenate(beam_nodes))
    mesh.facet_sets.update(opening_facets(mesh, spec))
    return mesh


# ------------------------------------------------------------------------------------------------
# 2D generator
# ------------------------------------------------------------------------------------------------
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
    unit_width: float = 0.0,
    unit_cracks: bool = False,
    openings: list | None = None,
    element_size: float = 0.0,
    key: str = "mesh.parameters",
):
    """A 2D wall (plane stress or plane strain: the scene's ``[model] hypothesis``) of
    ``height / (unit_height + joint_thickness)`` courses on optional steel / concrete beams.

    Lengths in m. Expanded unit size = unit size + joint_thickness (simplified micro-model).
    ``bond``: 'running' (= 'stretcher': half-unit offset, half units at the ends as built), 'stack',
    'header', 'english' or 'flemish' (the front elevation of the bond; the last three need
    ``unit_width``, the header's face). ``unit_cracks``: a potential crack interface at mid-length of
    every whole unit (set 'unit_cracks'). ``openings``: list of {x0, y0, width, height,
    lintel_height=0, lintel_bearing=0}, y0 measured from the underside of the masonry.
    Element size: ``element_size`` if > 0, else min(expanded unit length, height, and width for
    header bonds) / elements_per_unit. ``element``: 'quad' (quad4/quad8), 'quad9' or 'tri'.

    Element groups: 'units', 'lintels', 'base_beam', 'top_beam'. Joint sets: 'bed_joints',
    'head_joints', 'unit_cracks', 'lintel_joints', and with ``beam_joints`` 'base_joint' and
    'top_joint' between the beams and the wall (otherwise the beams are glued).
    Node sets: base, top, left, right, beams; facet sets base_edge, top_edge, left_edge,
    right_edge, opening_<i>.
    """
    spec = wall_spec(length, height, unit_length, unit_height, unit_width, joint_thickness, bond, openings,
                     base_beam_height, top_beam_height, key, dim=2, vertical="y0")
    if element not in ("quad", "quad9", "tri"):
        raise SceneError(f"{key}.element", f"must be 'quad', 'quad9' or 'tri', got {element!r}")
    check_mesh_options(order, elements_per_unit, element_size, key)
    parts = wall_parts(spec, unit_cracks, lambda slot: [(0.0, 0.0, "x")])
    rects = [Rect(p.x0, p.z0, p.x1, p.z1, p.group, p.kind) for p in parts]
    cls = joint_classifier(beam_joints)
    axis = {"horizontal": "z", "vertical": "x"}

    def classify(a: Rect, b: Rect, orientation: str):
        return cls(a.kind, a.group, b.kind, b.group, axis[orientation])

    dims = [spec.lu, spec.hu] + ([spec.wu] if spec.bond in HEADER_BONDS else [])
    size = element_size if element_size > 0 else min(dims) / elements_per_unit
    mesh = rectangles_to_mesh(rects, element_size=size, order=order, element=element, classify_joint=classify)
    return add_common_sets(mesh, spec)
