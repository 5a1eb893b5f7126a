"""Gravity dam generators: a 2D section (plane strain) and a 3D dam of monoliths across a valley.

Coordinates (m):

- 2D section: x from upstream to downstream (the heel of a parametric section at x = 0), y up
  (the dam base at y = 0 for a parametric section; a polyline keeps its own coordinates);
- 3D dam: x along the dam axis (across the valley, from one bank at x = 0 to the other at
  x = ``valley_top_width``), y from upstream to downstream (the 2D section's x), z up (the 2D
  section's y). This is the generators' convention (docs/architecture.md).

The section is given by a few numbers (:func:`gravity_dam_2d`: height, crest width, elevation of
the downstream kink, slopes), by a polyline, or by a named preset (``"koyna"``: the Koyna benchmark
section, the non-overflow monolith of Koyna dam; Chopra & Chakrabarti 1973, BSSA 63(2), fig. 1).
Lift joints are horizontal, at a spacing or at listed heights; an optional foundation block lies under
the dam (a dam-foundation joint between them); galleries are rectangular openings.

Meshing: gmsh with the OpenCASCADE kernel (no display, deterministic options, always finalised:
:mod:`generators._gmsh`). The section is cut by the lift planes into lift pieces (boolean
intersections with horizontal slabs, galleries cut out first), the pieces and the foundation are
fragmented together so that every joint line is one curve shared by the pieces on both sides, and
the whole model is meshed at once: the meshes on both faces of every joint are conformal. Every
curve gets a fixed number of elements (from its length and ``element_size``; an even number for
quadrilaterals, which gmsh's full-quad recombination needs). A piece with four geometric corners
whose opposite sides get the same number of elements (rectangular lifts of a vertical-faced dam,
the foundation block, whose free bottom and sides are matched to the top) is meshed with a
structured (transfinite) grid; the other pieces (trapezoidal lifts, whose top and bottom joints
differ in length, the lift with the kink, lifts with galleries) with unstructured quadrilaterals
(Frontal-Delaunay for quads and full-quad recombination: every element is a quadrilateral) or
triangles. Order 2 gives 8-node quadrilaterals (serendipity) or 6-node triangles. The mesh is read
back from the gmsh API, oriented counter-clockwise, and interfaces are inserted by
:func:`masonrydam.mesh.interfaces.insert_interfaces` on the facets between different bodies.

3D: the 2D section mesh (quadrilaterals) is extruded along the dam axis in numpy into hexahedra
(hex8, or hex20 from 8-node quadrilaterals), with a column of element layers per monolith. Each
monolith keeps the part of the section above its base; the base of a monolith is the elevation of
the trapezoidal valley profile at the monolith's centre line (the midpoint rule: benched
abutments), snapped to a lift joint or to another monolith's base when closer than a quarter of
an element. The section mesh is cut at those base levels too, so every monolith is made of whole
hexahedra and neighbouring monoliths share the nodes of their common face before the joints are
split. The rock is the foundation block below the valley floor plus, on the banks, the ground
under each monolith up to its base over the foundation's width (a stepped valley). This is the
simplest robust way to get an all-hexahedral, conformal, deterministic model: gmsh meshes only the
2D section (seconds at most), the extrusion and the 3D joint insertion are vectorised numpy.
Extruding inside gmsh (``extrude(..., recombine=True)``) would give the same hexahedra but would need
one 3D boolean fragment per monolith and base level and the 3D mesh read back from gmsh.

Named sets (facet sets: edges in 2D, faces in 3D, oriented outwards; a node set of the same name
holds their nodes, all copies at split joint nodes):

- ``upstream_face``, ``downstream_face``, ``crest``; ``upstream_wet``: the upstream face below the
  reservoir level (a mesh node is put at that level); node set ``waterline``: the upstream-face
  nodes at the reservoir level; node set ``crest_upstream``: the upstream crest corner (a line in
  3D);
- without a foundation: ``base`` (the dam base, and in 3D the abutment steps: the support set);
  with one: ``foundation_bottom``, ``foundation_sides`` (supports), ``foundation_top`` (the free
  ground surface);
- ``gallery_<i>``: the edges (faces) of gallery ``i``; 3D: ``dam_ends``, the end faces of the dam at
  the valley banks (x = 0 and x = ``valley_top_width``; free unless the scene supports them).

Element groups: ``dam`` and ``foundation``. Joint sets: ``lift_joints``, ``base_joint``
(dam-foundation, only with a foundation; in 3D also the vertical abutment steps) and, in 3D,
``contraction_joints``. Every lift of every monolith is a separate body joined to the others only
through interfaces; the foundation rock is one body. Joints follow the orientation rule of
:mod:`masonrydam.mesh.interfaces`: the normal of a lift joint points up (+y in 2D, +z in 3D), that
of a contraction joint along +x.

Bad input (a non-positive size, a lift spacing not smaller than the height, a kink above the
crest, a negative slope that overhangs a face and makes the base narrower than the crest, a
self-intersecting polyline, galleries overlapping each other or the faces, a foundation narrower
than the dam) raises :class:`masonrydam.errors.SceneError` naming the parameter, before gmsh runs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from masonrydam.elements.shapes import ELEMENT_TYPES
from masonrydam.errors import MeshError, SceneError
from masonrydam.mesh.facets import element_facets
from masonrydam.mesh.interfaces import insert_interfaces
from masonrydam.mesh.model import CellBlock, FacetSet, Mesh
from masonrydam.units import quantity

from ._gmsh import entity_elements, get_nodes, gmsh_session, tags_to_index

#: Named sections. Koyna dam, non-overflow monolith: Chopra & Chakrabarti (1973), "The Koyna
#: earthquake and the damage to Koyna dam", BSSA 63(2) 381-397, fig. 1; the same profile in
#: Bhattacharjee & Leger (1993) EESD 22 and Lee & Fenves (1998) EESD 27. Reservoir level at the 1967 earthquake: 91.75 m.
PRESETS = {
    "koyna": {
        "polyline": [(0.0, 0.0), (70.0, 0.0), (19.25, 66.5), (14.8, 103.0), (0.0, 103.0)],
        "reservoir_level": 91.75,
    },
}
#: the default downstream slope (horizontal : vertical), typical of concrete gravity dams
DEFAULT_DOWNSTREAM_SLOPE = 0.8
#: largest model a generator call may create (elements), against a mistyped element size
MAX_ELEMENTS = 3_000_000
_CORNER_ANGLE = math.radians(10.0)


# ----------------------------------------------------------------------------------------------
# input checking (no gmsh)
# ----------------------------------------------------------------------------------------------


def _err(key, name, msg):
    return SceneError(f"{key}.{name}" if name else key, msg)


def _number(value, name, key, *, positive=False, nonneg=False, dimension="length"):
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        v = quantity(value, dimension, f"{key}.{name}")
    else:
        raise _err(key, name, f"expected a number, got {value!r}")
    if not math.isfinite(v):
        raise _err(key, name, f"must be finite, got {value!r}")
    if positive and not v > 0:
        raise _err(key, name, f"must be > 0, got {value!r}")
    if nonneg and v < 0:
        raise _err(key, name, f"must be >= 0, got {value!r}")
    return v


def _ratio(value, name, key):
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _err(key, name, f"expected a finite number (horizontal : vertical), got {value!r}")
    return float(value)


def _shoelace(v: np.ndarray) -> float:
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _seg_intersect(p1, p2, q1, q2, tol) -> bool:
    """Closed segments p1p2 and q1q2 intersect (touching counts)."""

    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return 0 if abs(v) <= tol else (1 if v > 0 else -1)

    def on_seg(a, b, c):
        return min(a[0], b[0]) - tol <= c[0] <= max(a[0], b[0]) + tol and min(a[1], b[1]) - tol <= c[1] <= max(a[1], b[1]) + tol

    o1, o2, o3, o4 = orient(p1, p2, q1), orient(p1, p2, q2), orient(q1, q2, p1), orient(q1, q2, p2)
    if o1 != o2 and o3 != o4 and 0 not in (o1, o2, o3, o4):
        return True
    return ((o1 == 0 and on_seg(p1, p2, q1)) or (o2 == 0 and on_seg(p1, p2, q2))
            or (o3 == 0 and on_seg(q1, q2, p1)) or (o4 == 0 and on_seg(q1, q2, p2)))


def _inside(poly: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Ray-casting point-in-polygon test (points on the boundary may go either way)."""
    x, y = pts[:, 0][:, None], pts[:, 1][:, None]
    a, b = poly, np.roll(poly, -1, axis=0)
    cond = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (cond & (x < xc)).sum(axis=1) % 2 == 1


@dataclass
class _Section:
    """A dam section: counter-clockwise vertices from the heel, and the label of each edge
    (edge i runs from vertex i to vertex i + 1): base, downstream_face, crest, upstream_face."""

    vertices: np.ndarray
    labels: list
    y0: float
    height: float
    reservoir_level: float | None = None

    @property
    def scale(self) -> float:
        return float(np.ptp(self.vertices, axis=0).max())

    @property
    def base_x(self) -> tuple[float, float]:
        return float(self.vertices[0, 0]), float(self.vertices[1, 0])

    @property
    def upstream_crest(self) -> np.ndarray:
        """The upstream end of the crest edge."""
        i = self.labels.index("crest")
        return self.vertices[(i + 1) % len(self.vertices)]

    @property
    def area(self) -> float:
        return _shoelace(self.vertices)

    def edges(self):
        v = self.vertices
        return [(v[i], v[(i + 1) % len(v)], self.labels[i]) for i in range(len(v))]


def _section_from_parameters(height, crest_width, crest_kink_height, upstream_slope, downstream_slope,
                             downstream_upper_slope, key) -> _Section:
    H = _number(height, "height", key, positive=True)
    b = _number(crest_width, "crest_width", key, positive=True)
    hk = H if crest_kink_height is None else _number(crest_kink_height, "crest_kink_height", key)
    if not 0.0 <= hk <= H:
        raise _err(key, "crest_kink_height", f"the downstream kink must lie between the base and the crest "
                                             f"(0 <= crest_kink_height <= height = {H:g} m), got {hk:g} m")
    mu = _ratio(upstream_slope, "upstream_slope", key)
    md = _ratio(downstream_slope, "downstream_slope", key)
    mdu = _ratio(downstream_upper_slope, "downstream_upper_slope", key)
    for name, m in (("upstream_slope", mu), ("downstream_slope", md), ("downstream_upper_slope", mdu)):
        if m < 0:
            raise _err(key, name, f"must be >= 0 (horizontal : vertical), got {m:g}: a negative slope overhangs "
                                  "the face and makes the section narrower at its base than at its crest")
    x_uc = mu * H
    x_dc = x_uc + b
    x_k = x_dc + mdu * (H - hk)
    x_toe = x_k + md * hk
    verts = [(0.0, 0.0), (x_toe, 0.0)]
    labels = ["base"]
    if 0.0 < hk < H:
        verts.append((x_k, hk))
        labels.append("downstream_face")
    verts += [(x_dc, H), (x_uc, H)]
    labels += ["downstream_face", "crest", "upstream_face"]
    return _Section(np.array(verts, dtype=np.float64), labels, 0.0, H)


def _section_from_polyline(polyline, key) -> _Section:
    name = "polyline"
    if not isinstance(polyline, (list, tuple, np.ndarray)) or len(polyline) < 3:
        raise _err(key, name, f"expected a list of at least 3 [x, y] vertices of the section, got {polyline!r}")
    pts = []
    for i, p in enumerate(polyline):
        if not isinstance(p, (list, tuple, np.ndarray)) or len(p) != 2:
            raise _err(key, f"{name}[{i}]", f"expected [x, y], got {p!r}")
        pts.append((_number(p[0], f"{name}[{i}][0]", key), _number(p[1], f"{name}[{i}][1]", key)))
    v = np.array(pts, dtype=np.float64)
    if np.allclose(v[0], v[-1]):
        v = v[:-1]
    scale = float(np.ptp(v, axis=0).max()) if len(v) else 0.0
    tol = 1e-9 * max(scale, 1.0)
    keep = np.ones(len(v), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(v, axis=0), axis=1) > tol
    v = v[keep]
    n = len(v)
    if n < 3 or scale <= 0:
        raise _err(key, name, "needs at least 3 distinct vertices")
    for i in range(n):
        for j in range(i + 1, n):
            if j == i + 1 or (i == 0 and j == n - 1):
                continue
            if _seg_intersect(v[i], v[(i + 1) % n], v[j], v[(j + 1) % n], tol * scale):
                raise _err(key, name, f"the section self-intersects: edges {i} ({v[i].tolist()} -> {v[(i + 1) % n].tolist()}) "
                                      f"and {j} ({v[j].tolist()} -> {v[(j + 1) % n].tolist()}) cross")
    area = _shoelace(v)
    if abs(area) <= tol * scale:
        raise _err(key, name, "the section has zero area")
    if area < 0:
        v = v[::-1]
    ymin, ymax = v[:, 1].min(), v[:, 1].max()
    low = np.nonzero(np.abs(v[:, 1] - ymin) <= tol)[0]
    top = np.nonzero(np.abs(v[:, 1] - ymax) <= tol)[0]
    if len(low) != 2 or abs(low[1] - low[0]) not in (1, n - 1):
        raise _err(key, name, "the section needs one horizontal base edge at its lowest elevation (two vertices at the lowest y)")
    if len(top) != 2 or abs(top[1] - top[0]) not in (1, n - 1):
        raise _err(key, name, "the section needs one horizontal crest edge at its highest elevation (two vertices at the highest y)")
    heel = low[np.argmin(v[low, 0])]
    v = np.roll(v, -heel, axis=0)
    v[np.abs(v[:, 1] - ymin) <= tol, 1] = ymin
    v[np.abs(v[:, 1] - ymax) <= tol, 1] = ymax
    # counter-clockwise from the heel: base (heel -> toe), downstream face up to the crest, the
    # crest, the upstream face down to the heel
    labels = []
    i_dc = int(np.nonzero(v[:, 1] == ymax)[0].min())
    for i in range(n):
        if i == 0:
            labels.append("base")
        elif i < i_dc:
            labels.append("downstream_face")
        elif i == i_dc:
            labels.append("crest")
        else:
            labels.append("upstream_face")
    y = v[:, 1]
    if np.any(np.diff(y[1:i_dc + 1]) < -tol) or np.any(np.diff(np.append(y[i_dc + 1:], ymin)) > tol):
        raise _err(key, name, "the faces must rise monotonically from the base to the crest (every horizontal "
                              "line must cut the section once)")
    return _Section(v, labels, float(ymin), float(ymax - ymin))


def _section(height, crest_width, crest_kink_height, upstream_slope, downstream_slope, downstream_upper_slope,
             polyline, preset, reservoir_level, key) -> _Section:
    if preset is not None:
        if not isinstance(preset, str) or preset.lower() not in PRESETS:
            raise _err(key, "preset", f"unknown preset {preset!r}; known presets: {sorted(PRESETS)}")
        clash = [n for n, v in (("height", height), ("crest_width", crest_width),
                                ("crest_kink_height", crest_kink_height), ("polyline", polyline)) if v is not None]
        clash += [n for n, v, d in (("upstream_slope", upstream_slope, 0.0),
                                    ("downstream_slope", downstream_slope, DEFAULT_DOWNSTREAM_SLOPE),
                                    ("downstream_upper_slope", downstream_upper_slope, 0.0)) if v != d]
        if clash:
            raise _err(key, "preset", f"a preset fixes the section; remove {clash}")
        p = PRESETS[preset.lower()]
        sec = _section_from_polyline(p["polyline"], key)
        if reservoir_level is None:
            reservoir_level = p.get("reservoir_level")
    elif polyline is not None:
        clash = [n for n, v in (("height", height), ("crest_width", crest_width), ("crest_kink_height", crest_kink_height))
                 if v is not None]
        if clash:
            raise _err(key, "polyline", f"a polyline fixes the section; remove {clash}")
        sec = _section_from_polyline(polyline, key)
    else:
        for n, v in (("height", height), ("crest_width", crest_width)):
            if v is None:
                raise _err(key, n, "is required (or give 'polyline' or 'preset')")
        sec = _section_from_parameters(height, crest_width, crest_kink_height, upstream_slope, downstream_slope,
                                       downstream_upper_slope, key)
    if reservoir_level is not None:
        lvl = _number(reservoir_level, "reservoir_level", key)
        if not 0.0 < lvl <= sec.height * (1 + 1e-12):
            raise _err(key, "reservoir_level", f"must be in (0, height = {sec.height:g} m] above the dam base, got {lvl:g} m")
        sec.reservoir_level = sec.y0 + lvl
        _insert_waterline_vertex(sec)
    return sec


def _insert_waterline_vertex(sec: _Section) -> None:
    """Put a vertex on the upstream face at the reservoir level (so a mesh node lies there)."""
    v, lab = sec.vertices, sec.labels
    yr = sec.reservoir_level
    tol = 1e-9 * sec.scale
    n = len(v)
    on_face = np.array([lab[i] == "upstream_face" or lab[i - 1] == "upstream_face" for i in range(n)])
    if np.any(on_face & (np.abs(v[:, 1] - yr) <= tol)):
        return
    for i in range(n):
        if lab[i] != "upstream_face":
            continue
        a, b = v[i], v[(i + 1) % n]
        if (a[1] - yr) * (b[1] - yr) < 0:
            t = (yr - a[1]) / (b[1] - a[1])
            p = a + t * (b - a)
            sec.vertices = np.insert(v, i + 1, p, axis=0)
            sec.labels = lab[:i + 1] + ["upstream_face"] + lab[i + 1:]
            return


def _lift_levels(sec: _Section, lift_spacing, lift_heights, key) -> np.ndarray:
    """Absolute elevations of the lift joints (strictly between the base and the crest)."""
    H = sec.height
    if lift_spacing is not None and lift_heights is not None:
        raise _err(key, "lift_heights", "give either 'lift_spacing' or 'lift_heights', not both")
    if lift_spacing is not None:
        s = _number(lift_spacing, "lift_spacing", key, positive=True)
        if s >= H * (1 - 1e-9):
            raise _err(key, "lift_spacing", f"must be smaller than the dam height ({H:g} m), got {s:g} m")
        k = np.arange(1, int(math.floor(H / s)) + 1)
        levels = k * s
        levels = levels[levels < H * (1 - 1e-9)]
        return sec.y0 + levels
    if lift_heights is not None:
        if not isinstance(lift_heights, (list, tuple, np.ndarray)):
            raise _err(key, "lift_heights", f"expected a list of heights above the dam base, got {lift_heights!r}")
        hs = np.array([_number(h, f"lift_heights[{i}]", key) for i, h in enumerate(lift_heights)], dtype=np.float64)
        for i, h in enumerate(hs):
            if not 0.0 < h < H:
                raise _err(key, f"lift_heights[{i}]", f"must lie strictly between the base and the crest (0, {H:g}) m, got {h:g} m")
        hs = np.sort(hs)
        if len(hs) > 1 and np.min(np.diff(hs)) <= 1e-9 * H:
            raise _err(key, "lift_heights", "contains the same height twice")
        return sec.y0 + hs
    return np.zeros(0)


@dataclass
class _Gallery:
    x0: float
    y0: float
    x1: float
    y1: float


def _galleries(galleries, sec: _Section, key) -> list[_Gallery]:
    if galleries is None:
        return []
    if not isinstance(galleries, (list, tuple)):
        raise _err(key, "galleries", f"expected a list of {{x, y, width, height}} tables, got {galleries!r}")
    out = []
    poly = sec.vertices
    tol = 1e-9 * sec.scale
    for i, g in enumerate(galleries):
        gk = f"galleries[{i}]"
        if not isinstance(g, dict):
            raise _err(key, gk, f"expected a table {{x, y, width, height}}, got {g!r}")
        for k in g:
            if k not in ("x", "y", "width", "height"):
                raise _err(key, f"{gk}.{k}", "unknown key (use x, y: lower-left corner; width, height)")
        try:
            x, y = _number(g["x"], f"{gk}.x", key), _number(g["y"], f"{gk}.y", key)
            w = _number(g["width"], f"{gk}.width", key, positive=True)
            h = _number(g["height"], f"{gk}.height", key, positive=True)
        except KeyError as exc:
            raise _err(key, f"{gk}.{exc.args[0]}", "is required") from None
        r = _Gallery(x, y, x + w, y + h)
        corners = np.array([[r.x0, r.y0], [r.x1, r.y0], [r.x1, r.y1], [r.x0, r.y1]])
        bad = not _inside(poly, corners).all()
        if not bad:
            for p, q, _ in sec.edges():
                for a in range(4):
                    if _seg_intersect(p, q, corners[a], corners[(a + 1) % 4], tol * sec.scale):
                        bad = True
                        break
                if bad:
                    break
        if bad:
            raise _err(key, gk, f"the opening [{r.x0:g}, {r.x1:g}] x [{r.y0:g}, {r.y1:g}] m is not strictly inside the "
                                "dam section (it overlaps or touches a face, the base or the crest)")
        for j, o in enumerate(out):
            if r.x0 <= o.x1 + tol and o.x0 <= r.x1 + tol and r.y0 <= o.y1 + tol and o.y0 <= r.y1 + tol:
                raise _err(key, gk, f"overlaps or touches galleries[{j}]")
        out.append(r)
    return out


def _foundation(foundation_width, foundation_depth, sec: _Section, key):
    """(x0, x1, y_bottom) of the foundation block centred under the base, or None."""
    fw = _number(foundation_width, "foundation_width", key, nonneg=True)
    fd = _number(foundation_depth, "foundation_depth", key, nonneg=True)
    if fw == 0.0 and fd == 0.0:
        return None
    if fd == 0.0:
        raise _err(key, "foundation_depth", "must be > 0 when foundation_width is given")
    if fw == 0.0:
        raise _err(key, "foundation_width", "must be > 0 when foundation_depth is given")
    xh, xt = sec.base_x
    xc = 0.5 * (xh + xt)
    x0, x1 = xc - 0.5 * fw, xc + 0.5 * fw
    xmin, xmax = sec.vertices[:, 0].min(), sec.vertices[:, 0].max()
    tol = 1e-9 * sec.scale
    if x0 > xmin + tol or x1 < xmax - tol:
        need = 2.0 * max(xc - xmin, xmax - xc)
        raise _err(key, "foundation_width", f"{fw:g} m is narrower than the dam, whose base is {xt - xh:g} m wide "
                                            f"(the foundation is centred under the base; it must be at least {need:g} m wide)")
    return (x0, x1, sec.y0 - fd)


def _check_common(element_size, order, sec: _Section, key):
    if element_size is None:
        h = sec.height / 20.0
    else:
        h = _number(element_size, "element_size", key, positive=True)
    if isinstance(order, bool) or order not in (1, 2):
        raise _err(key, "order", f"must be 1 or 2, got {order!r}")
    return h


# ----------------------------------------------------------------------------------------------
# gmsh: the 2D section mesh
# ----------------------------------------------------------------------------------------------


@dataclass
class _Piece:
    kind: str  # 'dam', 'bank' (rock beside the dam, 3D), 'foundation'
    lift: int  # lift index of a dam piece (-1 otherwise)
    y_lo: float
    y_hi: float


@dataclass
class _SectionMesh:
    points: np.ndarray  # (n, 2)
    etype: str
    cells: np.ndarray  # (ne, k), counter-clockwise
    piece: np.ndarray  # (ne,) index into pieces
    pieces: list


def _count(length, h):
    """Number of elements of a curve of ``length`` for elements at most ``h`` long."""
    return max(1, int(math.ceil(length / h - 1e-9)))


def _mesh_section(sec: _Section, lift_levels, cut_levels, galleries, foundation, band_levels, h, order, element) -> _SectionMesh:
    """Mesh the dam section cut at ``cut_levels`` (lift joints and, in 3D, monolith bases), the
    foundation block, and the rock bands beside the dam between ``band_levels`` (3D)."""
    quads = element == "quad"
    opts = {"Mesh.Algorithm": 8 if quads else 6, "Mesh.RecombineAll": 1 if quads else 0,
            "Mesh.RecombinationAlgorithm": 2, "Mesh.MeshSizeMax": h, "Mesh.MeshSizeFromPoints": 0,
            "Mesh.SecondOrderIncomplete": 1, "Mesh.ElementOrder": 1}
    v = sec.vertices
    xmin, xmax = v[:, 0].min(), v[:, 0].max()
    pad = 0.1 * sec.scale + 1.0
    levels = np.concatenate([[sec.y0], np.asarray(cut_levels, dtype=np.float64), [sec.y0 + sec.height]])
    with gmsh_session("dam_section", opts) as gmsh:
        occ = gmsh.model.occ

        def polygon(vs):
            pts = [occ.addPoint(float(x), float(y), 0.0) for x, y in vs]
            lines = [occ.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
            return occ.addPlaneSurface([occ.addCurveLoop(lines)])

        # every boolean operation consumes copies (gmsh may give a result the tag of an unchanged
        # input), so the originals can be removed at the end without touching any piece
        full = polygon(v)
        if galleries:
            dam, _ = occ.cut(occ.copy([(2, full)]),
                             [(2, occ.addRectangle(g.x0, g.y0, 0.0, g.x1 - g.x0, g.y1 - g.y0)) for g in galleries])
        else:
            dam = occ.copy([(2, full)])
        inputs: list = []
        meta: list[_Piece] = []
        for k in range(len(levels) - 1):
            a, b = float(levels[k]), float(levels[k + 1])
            slab = occ.addRectangle(xmin - pad, a, 0.0, xmax - xmin + 2 * pad, b - a)
            out, _ = occ.intersect(occ.copy(dam), [(2, slab)])
            lift = int(np.searchsorted(lift_levels, a + 1e-9 * sec.scale, side="right"))
            for dt in out:
                inputs.append(dt)
                meta.append(_Piece("dam", lift, a, b))
        if foundation is not None:
            fx0, fx1, fy = foundation
            for k in range(len(band_levels) - 1):
                a, b = float(band_levels[k]), float(band_levels[k + 1])
                band = occ.addRectangle(fx0, a, 0.0, fx1 - fx0, b - a)
                out, _ = occ.cut([(2, band)], occ.copy([(2, full)]))
                for dt in out:
                    inputs.append(dt)
                    meta.append(_Piece("bank", -1, a, b))
            inputs.append((2, occ.addRectangle(fx0, fy, 0.0, fx1 - fx0, sec.y0 - fy)))
            meta.append(_Piece("foundation", -1, fy, sec.y0))
        occ.remove(dam + [(2, full)], recursive=True)
        if len(inputs) > 1:
            _, omap = occ.fragment(inputs[:1], inputs[1:])
        else:
            omap = [inputs]
        occ.synchronize()
        surfaces, smeta = [], []
        for children, m in zip(omap, meta):
            for d, t in children:
                if d == 2:
                    surfaces.append(t)
                    smeta.append(m)
        if len(set(surfaces)) != len(surfaces):
            raise MeshError("internal: pieces of the dam model overlap after the boolean fragment")
        _structure(gmsh, surfaces, h, quads)
        gmsh.model.mesh.generate(2)
        if order == 2:
            gmsh.model.mesh.setOrder(2)
        tags, coords = get_nodes(gmsh)
        cells, piece = [], []
        etype = None
        for i, s in enumerate(surfaces):
            for tname, conn, _ in entity_elements(gmsh, 2, s):
                if etype is None:
                    etype = tname
                if tname != etype:
                    raise MeshError(f"gmsh produced mixed element types ({etype}, {tname}) in the dam section; "
                                    "try another element_size")
                cells.append(tags_to_index(tags, conn))
                piece.append(np.full(len(conn), i))
    cells = np.vstack(cells)
    piece = np.concatenate(piece)
    used = np.zeros(len(tags), dtype=bool)
    used[cells.ravel()] = True
    new = np.cumsum(used) - 1
    points = coords[used, :2].copy()
    cells = new[cells]
    cells = _counter_clockwise(points, cells, etype)
    return _SectionMesh(points, etype, cells, piece, smeta)


def _four_sides(model, s):
    """The four sides (lists of curves) and corner points of a single-loop surface with four
    geometric corners, or None."""
    loops, _ = model.occ.getCurveLoops(s)
    if len(loops) != 1:
        return None
    bnd = [abs(t) for _, t in model.getBoundary([(2, s)], combined=False, oriented=False)]
    pts = {t: [q for _, q in model.getBoundary([(1, t)], oriented=False)] for t in bnd}
    if any(len(p) != 2 for p in pts.values()):
        return None
    # chain the curves head to tail (the orientation signs of OCC wires are not used)
    chain = [bnd[0]]
    ends = {bnd[0]: tuple(pts[bnd[0]])}
    while len(chain) < len(bnd):
        tail = ends[chain[-1]][1]
        nxt = [t for t in bnd if t not in ends and tail in pts[t]]
        if not nxt:
            return None
        t = nxt[0]
        ends[t] = (tail, pts[t][1] if pts[t][0] == tail else pts[t][0])
        chain.append(t)
    if ends[chain[-1]][1] != ends[chain[0]][0]:
        return None
    xyz = {p: np.array(model.getValue(0, p, [])) for t in chain for p in ends[t]}
    direction = [xyz[ends[t][1]] - xyz[ends[t][0]] for t in chain]
    corners = []
    for i in range(len(chain)):
        d0, d1 = direction[i - 1], direction[i]
        if float(np.dot(d0, d1) / (np.linalg.norm(d0) * np.linalg.norm(d1))) < math.cos(_CORNER_ANGLE):
            corners.append(i)
    if len(corners) != 4:
        return None
    n = len(chain)
    sides = [[chain[j % n] for j in range(corners[k], corners[k + 1] if k < 3 else corners[0] + n)] for k in range(4)]
    return sides, [ends[chain[i]][0] for i in corners]


def _structure(gmsh, surfaces, h, quads):
    """Fix the number of elements of every curve (about ``h`` long); make the pieces with four
    corners transfinite where opposite sides can get the same number of elements.

    A side that is a single curve on the model boundary (no other piece) is adjusted to match its
    opposite side. Gmsh's full-quad recombination of the unstructured pieces needs an even number
    of elements on their curves: those curves are rounded up to even, which may unbalance a
    transfinite piece next to them; that piece is then meshed unstructured too (a fixpoint)."""
    model = gmsh.model
    curves = sorted({abs(t) for _, t in model.getBoundary([(2, s) for s in surfaces], combined=False, oriented=False)})
    base = {c: _count(model.occ.getMass(1, c), h) for c in curves}
    free = {c for c in curves if len(model.getAdjacencies(1, c)[0]) == 1}
    candidates = {s: q for s in surfaces if (q := _four_sides(model, s)) is not None}
    boundary = {s: {abs(t) for _, t in model.getBoundary([(2, s)], combined=False, oriented=False)} for s in surfaces}
    even: set = set()
    while True:  # ``even`` grows at every pass: at most one pass per curve
        count = {c: n + (n % 2 if c in even else 0) for c, n in base.items()}
        transfinite = []
        for s, (sides, corner_pts) in candidates.items():
            trial = dict(count)
            ok = True
            for a, b in ((0, 2), (1, 3)):
                ta, tb = (sum(trial[c] for c in sides[k]) for k in (a, b))
                if ta == tb:
                    continue
                ok = False
                for x, y in ((a, b), (b, a)):
                    c = sides[x][0]
                    target = sum(trial[t] for t in sides[y])
                    if len(sides[x]) == 1 and c in free and not (c in even and target % 2):
                        trial[c] = target
                        ok = True
                        break
                if not ok:
                    break
            if ok:
                count.update({c: trial[c] for c in boundary[s]})
                transfinite.append((s, corner_pts))
        tf = {s for s, _ in transfinite}
        need = {c for s in surfaces if s not in tf for c in boundary[s]} if quads else set()
        if need <= even:
            break
        even |= need
    for c in curves:
        model.mesh.setTransfiniteCurve(c, count[c] + 1)
    for s, corner_pts in transfinite:
        model.mesh.setTransfiniteSurface(s, "Left", corner_pts)
        if quads:
            model.mesh.setRecombine(2, s)


_FLIP = {"quad4": [0, 3, 2, 1], "quad8": [0, 3, 2, 1, 7, 6, 5, 4], "quad9": [0, 3, 2, 1, 7, 6, 5, 4, 8],
         "tri3": [0, 2, 1], "tri6": [0, 2, 1, 5, 4, 3]}


def _counter_clockwise(points, cells, etype):
    nc = ELEMENT_TYPES[etype].corner_nodes
    x = points[cells[:, :nc]]
    area = 0.5 * (x[:, :, 0] * np.roll(x[:, :, 1], -1, axis=1) - np.roll(x[:, :, 0], -1, axis=1) * x[:, :, 1]).sum(1)
    if (area == 0).any():
        raise MeshError("gmsh produced a degenerate element in the dam section", elements=np.nonzero(area == 0)[0])
    flip = area < 0
    if flip.any():
        cells = cells.copy()
        cells[flip] = cells[flip][:, _FLIP[etype]]
    return cells


# ----------------------------------------------------------------------------------------------
# facets, joints and named sets (numpy)
# ----------------------------------------------------------------------------------------------


@dataclass
class _Facets:
    nodes: np.ndarray  # (nf, nfn) node lists of the unique facets, as seen from ``elem_a`` (outward)
    elem_a: np.ndarray  # (nf,)
    elem_b: np.ndarray  # (nf,) second element, -1 on the boundary
    ftype: str


def _facets(cells: np.ndarray, etype: str) -> _Facets:
    fac = element_facets(etype)
    ftype = fac[0][0]
    local = np.array([list(lc) for _, lc in fac])
    nf, nfn = local.shape
    nodes = cells[:, local].reshape(-1, nfn)
    elem = np.repeat(np.arange(len(cells)), nf)
    nc = ELEMENT_TYPES[ftype].corner_nodes
    key = np.sort(nodes[:, :nc], axis=1)
    order = np.lexsort(key.T[::-1])
    sk = key[order]
    new = np.ones(len(sk), dtype=bool)
    new[1:] = np.any(sk[1:] != sk[:-1], axis=1)
    starts = np.nonzero(new)[0]
    counts = np.diff(np.append(starts, len(sk)))
    if counts.max(initial=0) > 2:
        raise MeshError("a facet is shared by more than two elements (non-manifold mesh)")
    first = order[starts]
    second = np.where(counts == 2, order[np.minimum(starts + 1, len(order) - 1)], -1)
    return _Facets(nodes[first], elem[first], np.where(second >= 0, elem[np.maximum(second, 0)], -1), ftype)


def _segment_labels(points: np.ndarray, segments: list, tol: float) -> np.ndarray:
    """Index of the first segment (a, b, label) on which each point lies, -1 if none."""
    out = np.full(len(points), -1, dtype=np.int64)
    for i, (a, b, _) in enumerate(segments):
        ab = b - a
        L2 = float(ab @ ab)
        t = np.clip(((points - a) @ ab) / L2, 0.0, 1.0)
        d = np.linalg.norm(points - (a + t[:, None] * ab), axis=1)
        hit = (d <= tol) & (out < 0)
        out[hit] = i
    return out


def _geometry_segments(sec: _Section, galleries, foundation):
    """Labelled straight segments of the 2D geometry's boundaries (first match wins)."""
    segs = []
    for i, g in enumerate(galleries):
        c = np.array([[g.x0, g.y0], [g.x1, g.y0], [g.x1, g.y1], [g.x0, g.y1]])
        segs += [(c[k], c[(k + 1) % 4], f"gallery_{i}") for k in range(4)]
    segs += [(np.asarray(a, float), np.asarray(b, float), lab) for a, b, lab in sec.edges()]
    if foundation is not None:
        x0, x1, yb = foundation
        top = sec.y0 + sec.height
        segs += [(np.array([x0, yb]), np.array([x1, yb]), "foundation_bottom"),
                 (np.array([x0, yb]), np.array([x0, top]), "foundation_sides"),
                 (np.array([x1, yb]), np.array([x1, top]), "foundation_sides")]
    return segs


def _facet_centroids(points, nodes, ftype):
    nc = ELEMENT_TYPES[ftype].corner_nodes
    return points[nodes[:, :nc]].mean(axis=1)


def _named_node_sets(mesh: Mesh, sec: _Section, vertical_axis: int, upstream_crest) -> None:
    """Node sets of the same names as the facet sets, plus 'waterline' and 'crest_upstream'."""
    for name, fs in mesh.facet_sets.items():
        mesh.node_sets[name] = np.unique(fs.facets)
    tol = 1e-7 * sec.scale
    if sec.reservoir_level is not None and "upstream_face" in mesh.node_sets:
        ids = mesh.node_sets["upstream_face"]
        mesh.node_sets["waterline"] = ids[np.abs(mesh.points[ids, vertical_axis] - sec.reservoir_level) <= tol]
    if "crest" in mesh.node_sets:
        ids = mesh.node_sets["crest"]
        d = np.linalg.norm(mesh.points[ids][:, upstream_crest[0]] - upstream_crest[1], axis=1)
        mesh.node_sets["crest_upstream"] = ids[d <= tol]


def _estimate(n, what, key):
    if n > MAX_ELEMENTS:
        raise _err(key, "element_size", f"would create about {n:.3g} {what} (limit {MAX_ELEMENTS:.3g}); "
                                        "use a larger element size")


# ----------------------------------------------------------------------------------------------
# generators
# ----------------------------------------------------------------------------------------------


def gravity_dam_2d(
    height: float | None = None,
    crest_width: float | None = None,
    crest_kink_height: float | None = None,
    upstream_slope: float = 0.0,
    downstream_slope: float = DEFAULT_DOWNSTREAM_SLOPE,
    downstream_upper_slope: float = 0.0,
    polyline: list | None = None,
    preset: str | None = None,
    lift_spacing: float | None = None,
    lift_heights: list | None = None,
    foundation_width: float = 0.0,
    foundation_depth: float = 0.0,
    galleries: list | None = None,
    element_size: float | None = None,
    order: int = 1,
    element: str = "quad",
    reservoir_level: float | None = None,
    key: str = "mesh.parameters",
) -> Mesh:
    """A 2D gravity dam section (x upstream -> downstream, y up; plane strain is the scene's choice).

    Section, one of:

    - parameters (m): ``height``; ``crest_width``; ``crest_kink_height``, the elevation above the base
      of the kink of the downstream face (default: ``height``, a single downstream slope);
      ``upstream_slope`` (horizontal : vertical, the heel upstream of the crest), ``downstream_slope``
      below the kink and ``downstream_upper_slope`` above it. The heel is at (0, 0);
    - ``polyline``: the section's vertices [[x, y], ...] (either orientation), with a horizontal base
      edge at the lowest y and a horizontal crest edge at the highest y, faces rising monotonically;
    - ``preset``: ``"koyna"`` (the Koyna benchmark section; its reservoir level 91.75 m is the default
      ``reservoir_level``).

    Lift joints at every multiple of ``lift_spacing`` below the crest, or at ``lift_heights`` (m
    above the base). ``foundation_width`` x ``foundation_depth`` (m): a rock block centred under the
    base with a ``base_joint`` (without it the base is the support set ``base``). ``galleries``: list
    of ``{x, y, width, height}`` openings (x, y: lower-left corner). ``element_size`` (m; default
    height / 20), ``order`` 1 or 2, ``element`` 'quad' (quad4 / quad8) or 'tri' (tri3 / tri6).
    ``reservoir_level`` (m above the base) defines the facet set ``upstream_wet``.
    Named sets: see the module docstring.
    """
    sec = _section(height, crest_width, crest_kink_height, upstream_slope, downstream_slope, downstream_upper_slope,
                   polyline, preset, reservoir_level, key)
    levels = _lift_levels(sec, lift_spacing, lift_heights, key)
    h = _check_common(element_size, order, sec, key)
    if element not in ("quad", "tri"):
        raise _err(key, "element", f"must be 'quad' or 'tri', got {element!r}")
    gals = _galleries(galleries, sec, key)
    found = _foundation(foundation_width, foundation_depth, sec, key)
    _check_gallery_levels(gals, levels, h, key)
    area = sec.area + (0.0 if found is None else (found[1] - found[0]) * (sec.y0 - found[2]))
    _estimate(area / h ** 2 * (2 if element == "tri" else 1), "elements", key)

    sm = _mesh_section(sec, levels, levels, gals, found, [], h, order, element)
    kind = np.array([p.kind for p in sm.pieces])[sm.piece]
    body = np.array([p.lift for p in sm.pieces])[sm.piece]
    is_dam = kind == "dam"
    f = _facets(sm.cells, sm.etype)
    segs = _geometry_segments(sec, gals, found)
    return _assemble(sm.points, sm.etype, sm.cells, is_dam, body, f, sec, segs, found,
                     lambda fa, bnd: None, vertical_axis=1, upstream_crest=([0, 1], sec.upstream_crest))


def _check_gallery_levels(gals, levels, h, key):
    for i, g in enumerate(gals):
        for y in (g.y0, g.y1):
            d = np.abs(np.asarray(levels) - y)
            if d.size and 0 < d.min() < 0.1 * h:
                raise _err(key, f"galleries[{i}]", f"its edge at y = {y:g} m is {d.min():.3g} m from a lift joint: "
                                                   "put it on the joint or at least a tenth of an element away")


def _assemble(points, etype, cells, is_dam, body, f: _Facets, sec: _Section, segs, found, extra_label,
              vertical_axis, upstream_crest, joint_kind=None, profile_axes=(0, 1)) -> Mesh:
    """Classify facets (joints between bodies, labelled boundary facets), insert the interfaces."""
    ea, eb = f.elem_a, f.elem_b
    interior = eb >= 0
    tol = 1e-7 * sec.scale
    # joints: facets between different bodies (the rock, body -1, is one glued body)
    eb0 = np.maximum(eb, 0)
    diff = interior & (body[ea] != body[eb0])
    both_dam = diff & is_dam[ea] & is_dam[eb0]
    one_dam = diff & (is_dam[ea] != is_dam[eb0])
    joints = {}
    if joint_kind is None:
        lift = both_dam
        contraction = np.zeros_like(lift)
    else:
        contraction = both_dam & joint_kind(ea, eb0)
        lift = both_dam & ~contraction
    for name, sel in (("lift_joints", lift), ("contraction_joints", contraction), ("base_joint", one_dam)):
        if sel.any():
            joints[name] = f.nodes[sel]
    # boundary facets: labelled by the geometry they lie on
    bnd = np.nonzero(~interior)[0]
    cen = _facet_centroids(points, f.nodes[bnd], f.ftype)
    labels = np.full(len(bnd), "", dtype=object)
    special = extra_label(f, bnd)  # 3D: labels of the faces normal to the dam axis
    plane = np.ones(len(bnd), dtype=bool) if special is None else special == ""
    idx = _segment_labels(cen[plane][:, list(profile_axes)], segs, tol)
    lab_plane = np.array([segs[i][2] if i >= 0 else "" for i in idx], dtype=object)
    labels[plane] = lab_plane
    if special is not None:
        labels[~plane] = special[~plane]
    dam_b = is_dam[ea[bnd]]
    gallery = np.array([lab.startswith("gallery_") for lab in labels], dtype=bool)
    dam_names = ["upstream_face", "downstream_face", "crest", "dam_ends", "base"]
    rock_names = ["foundation_bottom", "foundation_sides", "foundation_top"]
    # a dam facet on no face is its base (on no foundation) or an abutment step; a rock facet on
    # none of the foundation's sides is the ground surface
    labels[dam_b & ~gallery & ~np.isin(labels, dam_names)] = "base"
    labels[~dam_b & ~gallery & ~np.isin(labels, rock_names)] = "foundation_top"
    if found is not None and np.any(dam_b & (labels == "base")):
        raise MeshError("internal: a dam facet on the foundation side is not a joint")
    facet_sets = {}
    for name in sorted(set(labels)):
        facet_sets[name] = FacetSet(f.ftype, f.nodes[bnd[labels == name]])
    if sec.reservoir_level is not None and "upstream_face" in facet_sets:
        up = bnd[labels == "upstream_face"]
        zc = cen[labels == "upstream_face", vertical_axis]
        wet = up[zc < sec.reservoir_level]
        if len(wet):
            facet_sets["upstream_wet"] = FacetSet(f.ftype, f.nodes[wet])
    blocks = []
    for name, sel in (("dam", is_dam), ("foundation", ~is_dam)):
        if sel.any():
            blocks.append(CellBlock(etype, cells[sel], name))
    # element order in the mesh = blocks order: facet node lists do not depend on it
    mesh = Mesh(points, blocks, [], {}, facet_sets)
    out = insert_interfaces(mesh, joints) if joints else mesh
    _named_node_sets(out, sec, vertical_axis, upstream_crest)
    out.check()
    return out


def _snap_bases(rise, known, height, h, key) -> np.ndarray:
    """Base elevations (n,) m of monoliths whose centre lines meet the valley at ``rise`` (n,) m above the
    floor: each within a quarter element ``h`` of a level in ``known`` (the floor and the lift joints, m above
    the floor) or of another monolith's base is snapped to it, so no sliver lift is meshed; the error names
    ``<key>.n_monoliths`` where a bank monolith would be less than half an element high under ``height``."""
    known = list(known)
    zb = np.empty(len(rise))
    for i, z in enumerate(rise):
        d = [abs(z - k) for k in known]
        j = int(np.argmin(d))
        if d[j] < 0.25 * h:
            zb[i] = known[j]
        else:
            zb[i] = z
            known.append(z)
    if np.any(height - zb < 0.5 * h):
        i = int(np.argmax(zb))
        raise _err(key, "n_monoliths", f"monolith {i} on the bank would be only {height - zb[i]:.3g} m high (less than "
                                       "half an element): use fewer monoliths, a wider valley bottom or a smaller "
                                       "element_size")
    return zb


def _valley_bases(sec: _Section, lift_levels, B_b, B_t, n, h, key):
    """Monolith boundaries along x and the base elevation of each monolith."""
    X = np.linspace(0.0, B_t, n + 1)
    xc = 0.5 * (X[1:] + X[:-1])
    H = sec.height
    if B_t > B_b:
        bank = 0.5 * (B_t - B_b)
        rise = np.clip((np.abs(xc - 0.5 * B_t) - 0.5 * B_b) / bank, 0.0, 1.0) * H
    else:
        rise = np.zeros(n)
    zb = _snap_bases(rise, [0.0] + list(np.asarray(lift_levels) - sec.y0), H, h, key)
    return X, sec.y0 + zb


def gravity_dam_3d(
    valley_bottom_width: float,
    valley_top_width: float,
    n_monoliths: int,
    height: float | None = None,
    crest_width: float | None = None,
    crest_kink_height: float | None = None,
    upstream_slope: float = 0.0,
    downstream_slope: float = DEFAULT_DOWNSTREAM_SLOPE,
    downstream_upper_slope: float = 0.0,
    polyline: list | None = None,
    preset: str | None = None,
    lift_spacing: float | None = None,
    lift_heights: list | None = None,
    foundation_width: float = 0.0,
    foundation_depth: float = 0.0,
    galleries: list | None = None,
    element_size: float | None = None,
    order: int = 1,
    reservoir_level: float | None = None,
    key: str = "mesh.parameters",
) -> Mesh:
    """A 3D gravity dam of ``n_monoliths`` equal monoliths across a trapezoidal valley.

    x along the dam axis (0 to ``valley_top_width``), y upstream -> downstream, z up. The valley is
    ``valley_bottom_width`` wide at the dam base (z = base) and ``valley_top_width`` at the crest,
    symmetric about x = valley_top_width / 2; vertical contraction joints (normal +x) separate the
    monoliths; each monolith stands on the valley profile at its centre line (benched abutments).
    The section (parameters, polyline or preset), lifts, foundation (``foundation_width`` along y,
    ``foundation_depth`` below the valley floor, spanning the whole valley along x; the rock rises
    under each bank monolith to its base), galleries (extruded along the axis) and reservoir level
    are as in :func:`gravity_dam_2d`. Elements: hex8 (``order`` 1) or hex20 (``order`` 2).
    Joint sets ``lift_joints``, ``contraction_joints``, ``base_joint``; named sets: see the module
    docstring.
    """
    sec = _section(height, crest_width, crest_kink_height, upstream_slope, downstream_slope, downstream_upper_slope,
                   polyline, preset, reservoir_level, key)
    levels = _lift_levels(sec, lift_spacing, lift_heights, key)
    h = _check_common(element_size, order, sec, key)
    B_b = _number(valley_bottom_width, "valley_bottom_width", key, nonneg=True)
    B_t = _number(valley_top_width, "valley_top_width", key, positive=True)
    if B_t < B_b:
        raise _err(key, "valley_top_width", f"must be >= valley_bottom_width ({B_b:g} m), got {B_t:g} m")
    if isinstance(n_monoliths, bool) or not isinstance(n_monoliths, (int, np.integer)) or n_monoliths < 1:
        raise _err(key, "n_monoliths", f"must be an integer >= 1, got {n_monoliths!r}")
    n = int(n_monoliths)
    gals = _galleries(galleries, sec, key)
    found = _foundation(foundation_width, foundation_depth, sec, key)
    _check_gallery_levels(gals, levels, h, key)
    X, zb = _valley_bases(sec, levels, B_b, B_t, n, h, key)
    vol = B_t * sec.area + (0.0 if found is None else B_t * (found[1] - found[0]) * (zb.max() - found[2]))
    _estimate(vol / h ** 3, "elements", key)

    steps = np.unique(zb[zb > sec.y0])
    cut = np.unique(np.concatenate([levels, steps]))
    band = np.concatenate([[sec.y0], steps]) if (found is not None and len(steps)) else np.zeros(0)
    sm = _mesh_section(sec, levels, cut, gals, found, band, h, order, "quad")
    return _extrude(sm, sec, X, zb, h, order, found, gals, len(levels) + 1)


def _extrude(sm: _SectionMesh, sec: _Section, X, zb, h, order, found, gals, n_lifts) -> Mesh:
    n2 = len(sm.points)
    n = len(X) - 1
    m = max(1, int(math.ceil((X[1] - X[0]) / h - 1e-9)))  # layers per monolith
    xs = np.concatenate([np.linspace(X[i], X[i + 1], m * order + 1)[:-1] for i in range(n)] + [[X[-1]]])
    kind = np.array([p.kind for p in sm.pieces])[sm.piece]
    lift = np.array([p.lift for p in sm.pieces])[sm.piece]
    ymid = np.array([0.5 * (p.y_lo + p.y_hi) for p in sm.pieces])[sm.piece]
    C = sm.cells
    cells, body, dam = [], [], []
    for i in range(n):
        is_dam = (kind == "dam") & (ymid > zb[i])
        rock = np.zeros(len(C), dtype=bool)
        if found is not None:
            rock = (kind == "foundation") | ((kind != "foundation") & (ymid < zb[i]))
        sel = np.nonzero(is_dam | rock)[0]
        c = C[sel]
        for layer in range(i * m, (i + 1) * m):
            s0 = layer * order
            if order == 1:
                hexes = np.hstack([c + s0 * n2, c + (s0 + 1) * n2])
            else:
                c4, mid = c[:, :4], c[:, 4:8]
                hexes = np.hstack([c4 + s0 * n2, c4 + (s0 + 2) * n2, mid + s0 * n2, mid + (s0 + 2) * n2, c4 + (s0 + 1) * n2])
            cells.append(hexes)
            body.append(np.where(is_dam[sel], i * n_lifts + lift[sel], -1))
            dam.append(is_dam[sel])
    cells = np.vstack(cells)
    body = np.concatenate(body)
    dam = np.concatenate(dam)
    etype = "hex8" if order == 1 else "hex20"
    # 3D points: (x, y = section x, z = section y); drop nodes no element uses
    used = np.zeros(len(xs) * n2, dtype=bool)
    used[cells.ravel()] = True
    new = np.cumsum(used) - 1
    ids = np.nonzero(used)[0]
    points = np.column_stack([xs[ids // n2], sm.points[ids % n2, 0], sm.points[ids % n2, 1]])
    cells = new[cells]
    f = _facets(cells, etype)
    segs = _geometry_segments(sec, gals, found)
    tol = 1e-7 * max(sec.scale, X[-1])

    def x_faces(fa: _Facets, bnd):
        nc = 4
        x = points[fa.nodes[bnd, :nc]]
        normal = np.cross(x[:, 1] - x[:, 0], x[:, 3] - x[:, 0])
        along = np.abs(normal[:, 0]) > 0.9 * np.linalg.norm(normal, axis=1)
        xc = x[:, :, 0].mean(axis=1)
        end = (np.abs(xc) <= tol) | (np.abs(xc - X[-1]) <= tol)
        out = np.full(len(bnd), "", dtype=object)
        dam_b = dam[fa.elem_a[bnd]]
        out[along & dam_b & end] = "dam_ends"
        out[along & dam_b & ~end] = "base"  # abutment step on no foundation
        out[along & ~dam_b & end] = "foundation_sides"
        out[along & ~dam_b & ~end] = "foundation_top"
        return out

    def contraction(ea, eb):
        return (body[ea] // n_lifts) != (body[eb] // n_lifts)

    crest_up = sec.upstream_crest
    return _assemble(points, etype, cells, dam, body, f, sec, segs, found, x_faces, vertical_axis=2,
                     upstream_crest=([1, 2], crest_up), joint_kind=contraction, profile_axes=(1, 2))
