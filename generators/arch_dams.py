"""Arch dam generator: a single-centre arch of cantilever monoliths, meshed with hexahedra (3D),
optionally double-curvature (a crown cantilever curved in the vertical plane, overhanging upstream).

Coordinates (m), the generators' convention (docs/architecture.md): x along the dam axis, across
the valley (the dam is symmetric about x = 0); y from upstream to downstream; z up, with z = 0 at the
dam base (the valley floor). The arch is convex upstream (towards -y).

Geometry (:func:`arch_dam_3d`). Every horizontal arch at elevation z (0 <= z <= H, H = ``height``)
is a circular annular sector of full central angle theta = ``central_angle_deg``, the same at every
elevation (the angle is constant; only a constant-angle arch whose radius follows the valley would
vary it, which this generator does not do). Its two faces are concentric about the vertical line
through the arch centre (0, y_c(z)):

- extrados (upstream face) radius R_e(z), linear from ``base_radius`` at z = 0 to ``crest_radius`` at
  z = H (``base_radius`` defaults to ``crest_radius``: a constant-radius arch);
- thickness t(z), linear from ``base_thickness`` to ``crest_thickness`` (default: uniform);
  intrados (downstream face) radius R_i = R_e - t, mean radius R_m = R_e - t/2 (the dam axis);
- centre y_c(z) = y_u(z) + R_e(z), in the plane x = 0, where y_u(z) is the crown's extrados: the
  arch sits with its crown's upstream face at (0, y_u(z)). Without an overhang (``crown_overhang``
  a = 0, the default) y_u = 0: the crown's extrados is the vertical line x = y = 0 and y_c = R_e (a
  constant-radius arch has the one vertical axis x = 0, y = R). With a > 0 (double curvature) the
  crown's upstream face is the parabola with its vertex at z_o = ``overhang_height`` (default
  0.45 H, strictly between 0 and H):
  y_u(z) = -a (1 - ((z - z_o) / (H - z_o))^2),
  so y_u(H) = 0 at the crest, the largest upstream offset y_u(z_o) = -a, and at the base
  y_u(0) = -a (1 - (z_o / (H - z_o))^2) (for z_o < H/2 the base lies downstream of the overhang: the
  crown cantilever's upstream face undercuts towards the base). Every horizontal arch keeps its radii
  and thickness; only its centre moves with the crown;
- a point at angle phi (-theta/2 <= phi <= theta/2, phi = 0 at the crown, phi > 0 towards +x) and
  radius r is at x = r sin(phi), y = y_c(z) - r cos(phi).

Exact closed forms the tests use: the annular sector at z has the area theta R_m(z) t(z), so the
dam's volume over a rectangular valley is V = theta H [R_m0 t0 + (R_m0 dt + dR t0)/2 + dR dt/3]
(R_m = R_m0 + dR z/H, t = t0 + dt z/H); the crest arc along the extrados is R_e(H) theta long.
The overhang changes none of these: it moves each horizontal section by y_u(z) along y, a shear
(x, y, z) -> (x, y + y_u(z), z) of unit determinant, so every section's area and the volume are
unchanged. The mesh keeps this exactly: every node of an elevation layer moves by the same y_u(z), and
within an element z depends on the elevation coordinate zeta alone, so the shift only adds to
dy/dzeta and the Jacobian determinant dz/dzeta (dx/dxi dy/deta - dx/deta dy/dxi) is the same at every
point as without the overhang (the meshed volume too, hex8 and hex20). No overhang can therefore
invert an element; the generator still checks every hexahedron's Jacobian at its nodes (an arc
segment spanning a half circle makes a flat hex8: that error names ``element_size``).

Valley. ``valley_bottom_width`` b (optional) makes the valley trapezoidal and symmetric: its walls
are the vertical-strike planes |x| = b/2 + (L - b)/2 z/H, with L = 2 R_m(H) sin(theta/2) the crest
chord of the dam axis (the arch spans the full central angle at the crest). Each monolith stands on
the valley at its centre line (the dam axis at its mid angle phi_c, x_c(z) = R_m(z) |sin(phi_c)|):
its base z_b is where x_c(z) meets the wall, the root of a linear equation (or 0 where the centre
line reaches the valley floor), as :func:`generators.dams.gravity_dam_3d` benches its monoliths. A
base within a quarter element of a lift joint, of the valley floor or of another monolith's base is
snapped to it. Without ``valley_bottom_width`` every monolith is full height (a rectangular valley).

Joints (interfaces inserted by :func:`masonrydam.mesh.interfaces.insert_interfaces`): the
``n_monoliths`` monoliths of equal angle theta / n are separated by radial vertical
``contraction_joints`` (their normal is the horizontal (cos phi, sin phi, 0), signed by the
interfaces' orientation rule); horizontal ``lift_joints`` at every multiple of ``lift_spacing`` above
the base (normal +z); ``base_joint`` between dam and rock (on the monolith bases, normal +z, and on
the vertical abutment steps between monoliths of different bases) when there is a foundation.
Every lift of every monolith is a body of its own; the rock is one body.

Foundation (``foundation_depth`` D > 0): rock from z = -D up to the valley floor under the dam's
plan, widened by ``foundation_extent`` e radially (upstream of the extrados and downstream of the
intrados, measured along the radius; not beyond the dam ends), plus, under each bank monolith, the
bank rock up to the monolith's base over the same radial width (a stepped valley, as in
gravity_dam_3d). Below z = 0 the rock's node columns are vertical, with the plan of the base arch
(including its overhang offset y_u(0)); the bank rock above z = 0 shares the dam's grid and follows
the arch centre y_c(z) up to each monolith's base, so the base joints stay conformal.

Mesh. A mapped (structured) hexahedral grid in (through-thickness, angle, height) coordinates
built with numpy: each node is placed on the exact geometry (mid-edge nodes of the 20-node
hexahedra on the arcs), the grid is shared by all monoliths, lifts and the rock so every joint is
conformal, and the result is deterministic and fast (tens of milliseconds for tens of thousands of
nodes). This parametric body needs no mesher; the gravity dam generator, by contrast, meshes its
arbitrary 2D section with gmsh and extrudes it in numpy. ``element_size`` h sets the divisions:
ceil(R_e,max theta / (n h)) per monolith along the arc, ceil(t_max / h) (at least 2) through the
thickness, and ceil(dz / h) in each height band between the base, the lift joints, the monolith
bases, the reservoir level and the crest (and ceil(D / h), ceil(e / h) in the rock).
Elements: hex8 (``order`` 1) or hex20 (``order`` 2); groups ``dam`` and ``foundation``.

Named sets (facet sets oriented outwards; a node set of the same name holds their nodes):
``upstream_face`` (extrados), ``downstream_face`` (intrados), ``crest``; ``dam_ends``: the two radial
end faces of the arch at phi = +-theta/2 (above the rock, free unless the scene supports them);
without a foundation ``base``: the monolith bases and the abutment steps (the support set); with one
``foundation_bottom``, ``foundation_sides`` (the rock's radial and angular end faces),
``foundation_top`` (the free ground surface). With ``reservoir_level`` (m above the base, a node
layer is put there): ``upstream_wet``, the upstream face below it, and node set ``waterline``. Node
set ``crest_upstream``: the crest nodes on the extrados (the upstream crest arc).

References: the geometry is elementary (circular annular sectors). The parameters (crest radius
and central angle of the crest arch, crest and base thickness, height) are those a preliminary
arch layout is given by in Boggs, H.L., "Guide for Preliminary Design of Arch Dams", USBR
Engineering Monograph 36 (1966; reprinted 1977), whose empirical thickness formulas are not
implemented here. The same monograph lays out the crown cantilever of a double-curvature arch with an
upstream overhang of its upstream face near 0.45 H above the base, the shape (not the numbers) that
``crown_overhang`` and the default ``overhang_height`` follow; the parabola is this generator's choice.

Bad input raises :class:`masonrydam.errors.SceneError` naming ``<key>.<parameter>`` and the bound.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from masonrydam.elements.shapes import ELEMENT_TYPES, reference_nodes, shape_functions
from masonrydam.errors import MeshError
from masonrydam.mesh.interfaces import insert_interfaces
from masonrydam.mesh.model import CellBlock, FacetSet, Mesh

from .dams import _err, _estimate, _facets, _number, _snap_bases

__all__ = ["arch_dam_3d"]

#: largest central angle accepted (degrees): beyond a half circle the arch would wrap around its centre
MAX_CENTRAL_ANGLE_DEG = 180.0


@dataclass(frozen=True)
class _Arch:
    """Geometry of the arch: height H (m), full central angle theta (rad), extrados radius and
    thickness at the base (``Re0``, ``t0``) and at the crest (``ReH``, ``tH``), m. Functions of the
    elevation z (m above the base, array or scalar) return m."""

    H: float
    theta: float
    Re0: float
    ReH: float
    t0: float
    tH: float
    overhang: float = 0.0  # crown_overhang a (m)
    z_o: float = 0.0  # overhang_height (m above the base)

    def extrados(self, z):
        return self.Re0 + (self.ReH - self.Re0) * np.asarray(z) / self.H

    def thickness(self, z):
        return self.t0 + (self.tH - self.t0) * np.asarray(z) / self.H

    def intrados(self, z):
        return self.extrados(z) - self.thickness(z)

    def mean_radius(self, z):
        return self.extrados(z) - 0.5 * self.thickness(z)

    def upstream_y(self, z):
        """y of the crown's extrados at elevation z: the parabola y_u = -a (1 - ((z - z_o) / (H - z_o))^2)
        (0 at the crest, -a at z_o); 0 at every elevation without an overhang."""
        if self.overhang == 0.0:
            return np.zeros_like(np.asarray(z, dtype=np.float64))
        s = (np.asarray(z) - self.z_o) / (self.H - self.z_o)
        return -self.overhang * (1.0 - s * s)

    def centre_y(self, z):
        """y of the arch centre at elevation z: y_c = y_u + R_e (without an overhang the crown's extrados
        stays at y = 0, and y_c = R_e bit for bit)."""
        if self.overhang == 0.0:
            return self.extrados(z)
        return self.upstream_y(z) + self.extrados(z)

    @property
    def scale(self) -> float:
        return max(self.H, self.Re0, self.ReH)


def _int_at_least(value, name, key, low):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise _err(key, name, f"must be an integer >= {low}, got {value!r}")
    return int(value)


def _check_arch(height, crest_radius, central_angle_deg, crest_thickness, base_thickness, base_radius, key,
                crown_overhang=0.0, overhang_height=None) -> _Arch:
    H = _number(height, "height", key, positive=True)
    ReH = _number(crest_radius, "crest_radius", key, positive=True)
    Re0 = ReH if base_radius is None else _number(base_radius, "base_radius", key, positive=True)
    ang = _number(central_angle_deg, "central_angle_deg", key, positive=True, dimension="angle")
    if ang > MAX_CENTRAL_ANGLE_DEG:
        raise _err(key, "central_angle_deg", f"must be in (0, {MAX_CENTRAL_ANGLE_DEG:g}] degrees, got {ang:g}")
    tH = _number(crest_thickness, "crest_thickness", key, positive=True)
    t0 = tH if base_thickness is None else _number(base_thickness, "base_thickness", key, positive=True)
    if tH >= ReH:
        raise _err(key, "crest_thickness", f"must be smaller than crest_radius ({ReH:g} m: the intrados radius "
                                           f"R_e - t must stay > 0), got {tH:g} m")
    if t0 >= Re0:
        raise _err(key, "base_thickness", f"must be smaller than the base extrados radius ({Re0:g} m: the intrados "
                                          f"radius R_e - t must stay > 0), got {t0:g} m")
    a = _number(crown_overhang, "crown_overhang", key, nonneg=True)
    z_o = 0.45 * H
    if overhang_height is not None:
        z_o = _number(overhang_height, "overhang_height", key)
        if not 0.0 < z_o < H:
            raise _err(key, "overhang_height", f"must be strictly between 0 and height = {H:g} m (the crown's "
                                               f"upstream-face parabola has its vertex there), got {z_o:g} m")
    return _Arch(H, math.radians(ang), Re0, ReH, t0, tH, a, z_o)


def _check_jacobians(points, cells, etype, key) -> None:
    """Every hexahedron's Jacobian determinant at its nodes must be > 0 (none inverted or flat).

    The crown overhang never fails this: it moves every node of an elevation layer by the same
    y-shift y_u(z), and within an element z depends on the elevation coordinate zeta alone (the grid is
    mapped), so the shift only adds to dy/dzeta and det J = dz/dzeta (dx/dxi dy/deta - dx/deta dy/dxi)
    is unchanged. What can fail is an arc segment spanning (nearly) a half circle: its chord element
    is flat (hex8 at d = 180 degrees) or its parabolic edges fold (hex20)."""
    _, dN = shape_functions(etype, reference_nodes(etype))  # (nen, 3, nen)
    nen = dN.shape[0]
    J = (dN.reshape(3 * nen, nen) @ points[cells]).reshape(len(cells), nen, 3, 3)  # J[e, q, a, b] = dx_b / dxi_a
    det = (J[..., 0, 0] * (J[..., 1, 1] * J[..., 2, 2] - J[..., 1, 2] * J[..., 2, 1])
           - J[..., 0, 1] * (J[..., 1, 0] * J[..., 2, 2] - J[..., 1, 2] * J[..., 2, 0])
           + J[..., 0, 2] * (J[..., 1, 0] * J[..., 2, 1] - J[..., 1, 1] * J[..., 2, 0]))
    bad = det <= 1e-12 * np.abs(det).max()
    if bad.any():
        e = int(np.nonzero(bad.any(axis=1))[0][0])
        raise _err(key, "element_size", f"gives arc segments too wide for {etype} elements: {int(bad.any(axis=1).sum())} "
                                        f"hexahedra have a Jacobian determinant <= 0 at a node (element {e}, smallest "
                                        f"{det.min():.3g}); use a smaller element_size or more monoliths")


def _lift_levels(arch: _Arch, lift_spacing, key) -> np.ndarray:
    """Elevations (m above the base) of the lift joints, strictly between the base and the crest."""
    if lift_spacing is None:
        return np.zeros(0)
    s = _number(lift_spacing, "lift_spacing", key, positive=True)
    if s >= arch.H * (1 - 1e-9):
        raise _err(key, "lift_spacing", f"must be smaller than the dam height ({arch.H:g} m), got {s:g} m")
    levels = s * np.arange(1, int(math.floor(arch.H / s)) + 1)
    return levels[levels < arch.H * (1 - 1e-9)]


def _monolith_bases(arch: _Arch, n, valley_bottom_width, lift_levels, h, key):
    """Angles of the n + 1 monolith boundaries (rad) and the base elevation of each monolith (m).

    Trapezoidal valley: the wall |x| = b/2 + (L - b)/2 z/H meets the monolith's centre line
    x_c(z) = R_m(z) |sin(phi_c)| where f(z) = wall - x_c, linear in z, vanishes:
    z_b = H (-f(0)) / (f(H) - f(0)), or 0 where f(0) >= 0 (f(H) > 0: every centre line reaches the crest
    inside the valley)."""
    H = arch.H
    phi = np.linspace(-0.5 * arch.theta, 0.5 * arch.theta, n + 1)
    if n % 2 == 0:
        phi[n // 2] = 0.0  # the crown joint exactly at phi = 0
    if valley_bottom_width is None:
        return phi, np.zeros(n)
    b = _number(valley_bottom_width, "valley_bottom_width", key, nonneg=True)
    L = 2.0 * arch.mean_radius(H) * math.sin(0.5 * arch.theta)
    if b > L * (1 + 1e-12):
        raise _err(key, "valley_bottom_width", f"must be <= the crest chord of the dam axis, 2 R_m sin(theta/2) = "
                                               f"{L:.6g} m, got {b:g} m")
    s = np.abs(np.sin(0.5 * (phi[1:] + phi[:-1])))
    f0 = 0.5 * b - arch.mean_radius(0.0) * s
    fH = 0.5 * L - arch.mean_radius(H) * s
    rise = np.where(f0 >= 0.0, 0.0, H * (-f0) / (fH - f0))
    return phi, _snap_bases(rise, [0.0] + list(lift_levels), H, h, key)


def _divide(breaks, h):
    """Nodes along a line cut at ``breaks`` (sorted), every piece in ceil(length / h) equal elements."""
    pieces = [np.linspace(a, b, max(1, int(math.ceil((b - a) / h - 1e-9))) + 1)[:-1] for a, b in zip(breaks[:-1], breaks[1:])]
    return np.concatenate(pieces + [[breaks[-1]]])


def _refine(nodes, order):
    """Order 2: the midpoints inserted between consecutive nodes (the mid-edge node stations)."""
    if order == 1:
        return np.asarray(nodes, dtype=np.float64)
    nodes = np.asarray(nodes, dtype=np.float64)
    out = np.empty(2 * len(nodes) - 1, dtype=nodes.dtype)
    out[0::2] = nodes
    out[1::2] = 0.5 * (nodes[1:] + nodes[:-1])
    return out


def arch_dam_3d(
    height: float,
    crest_radius: float,
    central_angle_deg: float,
    crest_thickness: float,
    n_monoliths: int,
    base_thickness: float | None = None,
    base_radius: float | None = None,
    valley_bottom_width: float | None = None,
    lift_spacing: float | None = None,
    foundation_depth: float = 0.0,
    foundation_extent: float = 0.0,
    element_size: float | None = None,
    order: int = 1,
    reservoir_level: float | None = None,
    crown_overhang: float = 0.0,
    overhang_height: float | None = None,
    key: str = "mesh.parameters",
) -> Mesh:
    """A single-centre arch dam of ``n_monoliths`` cantilever monoliths (see the module docstring).

    height (m); crest_radius: extrados radius of the crest arch (m); central_angle_deg: full central
    angle of every arch (degrees, (0, 180]); crest_thickness, base_thickness (m; default uniform);
    base_radius: extrados radius at the base (m; default crest_radius); n_monoliths: equal-angle
    monoliths separated by radial ``contraction_joints``; valley_bottom_width (m; default none: all
    monoliths full height): a trapezoidal valley whose top width is the crest chord of the dam axis;
    lift_spacing (m): horizontal ``lift_joints``; foundation_depth, foundation_extent (m): the rock
    block below the valley floor and its radial widening; element_size (m; default height / 20);
    order 1 (hex8) or 2 (hex20); reservoir_level (m above the base): the ``upstream_wet`` set;
    crown_overhang (m, >= 0; default 0: the vertical crown) and overhang_height (m above the base, in
    (0, height); default 0.45 height): the double curvature, the crown's upstream face the parabola
    through the crest's extrados with its largest upstream offset crown_overhang at overhang_height.
    Returns a :class:`masonrydam.mesh.Mesh` (points (n, 3) m) with the interfaces inserted.
    """
    arch = _check_arch(height, crest_radius, central_angle_deg, crest_thickness, base_thickness, base_radius, key,
                       crown_overhang, overhang_height)
    H, theta = arch.H, arch.theta
    n = _int_at_least(n_monoliths, "n_monoliths", key, 1)
    h = H / 20.0 if element_size is None else _number(element_size, "element_size", key, positive=True)
    if isinstance(order, bool) or order not in (1, 2):
        raise _err(key, "order", f"must be 1 or 2, got {order!r}")
    lifts = _lift_levels(arch, lift_spacing, key)
    D = _number(foundation_depth, "foundation_depth", key, nonneg=True)
    e = _number(foundation_extent, "foundation_extent", key, nonneg=True)
    if e > 0.0 and D == 0.0:
        raise _err(key, "foundation_depth", "must be > 0 when foundation_extent is given")
    r_min = min(arch.intrados(0.0), arch.intrados(H))
    if D > 0.0 and e >= r_min:
        raise _err(key, "foundation_extent", f"must be smaller than the smallest intrados radius ({r_min:.6g} m: the "
                                             f"rock downstream of the arch stops short of its centre), got {e:g} m")
    level = None
    if reservoir_level is not None:
        level = _number(reservoir_level, "reservoir_level", key)
        if not 0.0 < level <= H * (1 + 1e-12):
            raise _err(key, "reservoir_level", f"must be in (0, height = {H:g} m] above the dam base, got {level:g} m")
        level = min(level, H)
    # element counts along the three grid directions, checked before any array is made
    n_arc = max(1, int(math.ceil(max(arch.Re0, arch.ReH) * theta / n / h - 1e-9)))
    n_thick = max(2, int(math.ceil(max(arch.t0, arch.tH) / h - 1e-9)))
    n_ext = int(math.ceil(e / h - 1e-9)) if D > 0.0 else 0
    n_depth = int(math.ceil(D / h - 1e-9)) if D > 0.0 else 0
    n_z = int(math.ceil(H / h - 1e-9)) + len(lifts) + n + 2 + n_depth
    _estimate(float(n * n_arc) * n_z * (n_thick + 2 * n_ext), "elements", key)
    phi_edges, zb = _monolith_bases(arch, n, valley_bottom_width, lifts, h, key)

    # coarse grid stations: angle, elevation, radial (r = R_i(z) + a t(z) + b)
    phi_c = np.concatenate([np.linspace(phi_edges[i], phi_edges[i + 1], n_arc + 1)[:-1] for i in range(n)]
                           + [[phi_edges[-1]]])
    tol_z = 1e-9 * arch.scale
    breaks = np.unique(np.concatenate([[0.0, H], lifts, zb, [] if level is None else [level]]))
    breaks = breaks[np.concatenate([[True], np.diff(breaks) > tol_z])]
    z_c = _divide(breaks, h)
    if D > 0.0:
        z_c = np.concatenate([np.linspace(-D, 0.0, n_depth + 1)[:-1], z_c])
    k_ext = np.arange(n_ext, 0, -1) / max(n_ext, 1)
    a_c = np.concatenate([np.zeros(n_ext), np.linspace(0.0, 1.0, n_thick + 1), np.ones(n_ext)])
    b_c = np.concatenate([-e * k_ext, np.zeros(n_thick + 1), e * k_ext[::-1]])

    # active cells: (angle, elevation, radial) coarse indices
    Np, Nz, Nr = len(phi_c) - 1, len(z_c) - 1, len(a_c) - 1
    mono = np.arange(Np) // n_arc  # monolith of each angular cell
    zmid = 0.5 * (z_c[1:] + z_c[:-1])
    in_dam_r = (np.arange(Nr) >= n_ext) & (np.arange(Nr) < n_ext + n_thick)
    above = zmid[None, :] > zb[mono][:, None]  # (Np, Nz)
    dam = above[:, :, None] & in_dam_r[None, None, :]  # (z_b >= 0: no dam below the valley floor)
    rock = np.zeros_like(dam)
    if D > 0.0:
        rock = np.broadcast_to(~above[:, :, None], dam.shape).copy()
    cp, cz, cr = np.nonzero(dam | rock)
    is_dam = dam[cp, cz, cr]
    lift_of = np.searchsorted(lifts, zmid[cz])
    body = np.where(is_dam, mono[cp] * (len(lifts) + 1) + lift_of, -1)

    # nodes of the fine grid (order 2: mid-edge stations), numbered (angle, elevation, radial)
    phi_f, z_f, a_f, b_f = (_refine(v, order) for v in (phi_c, z_c, a_c, b_c))
    nzf, nrf = len(z_f), len(a_f)
    etype = "hex8" if order == 1 else "hex20"
    ref = np.rint((reference_nodes(etype) + 1.0) * order / 2).astype(np.int64)  # (nen, 3): radial, angle, elevation
    ir = order * cr[:, None] + ref[None, :, 0]
    ip = order * cp[:, None] + ref[None, :, 1]
    iz = order * cz[:, None] + ref[None, :, 2]
    grid_ids = (ip * nzf + iz) * nrf + ir
    used, cells = np.unique(grid_ids, return_inverse=True)
    cells = cells.reshape(grid_ids.shape)
    gp, rem = np.divmod(used, nzf * nrf)
    gz, gr = np.divmod(rem, nrf)
    zz = z_f[gz]
    zg = np.clip(zz, 0.0, H)
    r = arch.intrados(zg) + a_f[gr] * arch.thickness(zg) + b_f[gr]
    points = np.column_stack([r * np.sin(phi_f[gp]), arch.centre_y(zg) - r * np.cos(phi_f[gp]), zz])
    _check_jacobians(points, cells, etype, key)

    # facets: joints between bodies and labelled boundary facets, by their grid plane
    f = _facets(cells, etype)
    nc = ELEMENT_TYPES[f.ftype].corner_nodes
    corner = f.nodes[:, :nc]
    fp, fz, fr = gp[corner], gz[corner], gr[corner]
    on_p = (fp == fp[:, :1]).all(1)
    on_z = (fz == fz[:, :1]).all(1)
    on_r = (fr == fr[:, :1]).all(1)
    ea, eb = f.elem_a, f.elem_b
    interior = eb >= 0
    eb0 = np.maximum(eb, 0)
    diff = interior & (body[ea] != body[eb0])
    both = diff & is_dam[ea] & is_dam[eb0]
    joints = {}
    for name, sel in (("lift_joints", both & on_z), ("contraction_joints", both & on_p),
                      ("base_joint", diff & (is_dam[ea] != is_dam[eb0]))):
        if sel.any():
            joints[name] = f.nodes[sel]
    if (both & on_r).any():
        raise MeshError("internal: a joint between two dam bodies on a radial grid plane")
    bnd = ~interior
    own_dam = is_dam[ea]
    p0, z0, r0 = fp[:, 0], fz[:, 0], fr[:, 0]
    top, last_p, last_r = nzf - 1, len(phi_f) - 1, nrf - 1
    r_down, r_up = order * n_ext, order * (n_ext + n_thick)
    labels = np.full(len(ea), "", dtype=object)
    dam_b, rock_b = bnd & own_dam, bnd & ~own_dam
    labels[dam_b & on_r & (r0 == r_up)] = "upstream_face"
    labels[dam_b & on_r & (r0 == r_down)] = "downstream_face"
    labels[dam_b & on_z & (z0 == top)] = "crest"
    labels[dam_b & on_p & ((p0 == 0) | (p0 == last_p))] = "dam_ends"
    labels[dam_b & (labels == "")] = "base"  # a monolith base or an abutment step on no rock
    labels[rock_b & on_z & (z0 == 0)] = "foundation_bottom"
    labels[rock_b & ((on_r & ((r0 == 0) | (r0 == last_r))) | (on_p & ((p0 == 0) | (p0 == last_p))))] = "foundation_sides"
    labels[rock_b & (labels == "")] = "foundation_top"
    if D > 0.0 and np.any(labels == "base"):
        raise MeshError("internal: a dam facet on the rock is not a joint")
    facet_sets = {name: FacetSet(f.ftype, f.nodes[labels == name]) for name in sorted(set(labels[bnd]))}
    if level is not None:
        up = labels == "upstream_face"
        wet = up & (points[corner, 2].mean(axis=1) < level)
        if wet.any():
            facet_sets["upstream_wet"] = FacetSet(f.ftype, f.nodes[wet])
    blocks = [CellBlock(etype, cells[sel], name) for name, sel in (("dam", is_dam), ("foundation", ~is_dam)) if sel.any()]
    mesh = Mesh(points, blocks, [], {}, facet_sets)
    out = insert_interfaces(mesh, joints) if joints else mesh
    _node_sets(out, arch, level)
    out.check()
    return out


def _node_sets(mesh: Mesh, arch: _Arch, level) -> None:
    """Node sets of the facet sets' names, ``waterline`` and ``crest_upstream``."""
    for name, fs in mesh.facet_sets.items():
        mesh.node_sets[name] = np.unique(fs.facets)
    tol = 1e-7 * arch.scale
    x = mesh.points
    if level is not None and "upstream_face" in mesh.node_sets:
        ids = mesh.node_sets["upstream_face"]
        mesh.node_sets["waterline"] = ids[np.abs(x[ids, 2] - level) <= tol]
    ids = mesh.node_sets["crest"]
    r = np.hypot(x[ids, 0], x[ids, 1] - arch.centre_y(arch.H))
    mesh.node_sets["crest_upstream"] = ids[np.abs(r - arch.ReH) <= tol]
