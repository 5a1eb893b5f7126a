"""The foundation rock with mass for earthquake analysis of dams: viscous absorbing boundaries and the
ground motion entered as free-field effective forces.

Scene: ``[foundation]`` with ``mass``, ``group``, ``absorbing = { bottom, sides }`` (facet sets) and ``motion``
(``"outcrop"`` or ``"within"``). :func:`build` returns a :class:`Foundation` (None for massless rock): its
dashpots (n_dof, n_dof) CSR, N s/m, the released DOFs (n_dof,) bool and the effective force
:meth:`Foundation.effective_force` (n_dof,), N, at a time in s, from records of acceleration (m/s2) per
component. References: Lysmer & Kuhlemeyer (1969) for the dashpots; Kramer (1996) and Wolf (1985) for the 1D
free field; Joyner & Chen (1975), Nielsen (2006) and Løkke & Chopra (2018) for the effective forces.

Theory: docs/dam_reservoir_foundation.md, section "The foundation rock with mass".
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..checks import boolean, check_keys, choice
from ..elements.shapes import ELEMENT_TYPES, facet_outward_sign, facet_quadrature, facet_rule
from ..errors import STATUS_OK, SceneError
from ..keys import Section
from ..keys import key as row
from ..mesh.facets import FACET_TYPES, boundary_owners
from .base import Effect, EffectRun, add_force
from .foundation_kernels import free_field_force

__all__ = ["normalize_section", "build", "Foundation", "Boundary", "wave_speeds", "dashpot_matrix", "describe",
           "DEFAULT_GROUP", "DEFAULT_BOTTOM", "DEFAULT_SIDES", "MOTIONS"]

DEFAULT_GROUP = "foundation"
DEFAULT_BOTTOM = "foundation_bottom"
DEFAULT_SIDES = "foundation_sides"
#: what the ground motion record is: at a rock outcrop (or deconvolved to one) / inside the rock at the base
MOTIONS = ("outcrop", "within")

#: facet types whose row-sum lumping has non-positive corner weights: diagonal scaling instead
_HRZ_TYPES = ("tri6", "quad8")
_AXES = "xyz"


# ---------------------------------------------------------------------------------------------
# scene section


def normalize_section(d, model: dict) -> dict:
    """The ``[foundation]`` section; ``model``: the normalised ``[model]`` section (dimension, gravity).

    Returns ``{"mass": bool, "group": str, "absorbing": {"bottom": str, "sides": str} | None,
    "motion": "outcrop" | "within" | None, "vertical_axis": int}``. With ``mass = false`` the other
    keys are checked for their form but change nothing.
    """
    key = "foundation"
    if d is None:
        d = {}
    check_keys(d, {"mass", "group", "absorbing", "motion"}, key)
    mass = boolean(d.get("mass", False), f"{key}.mass")
    group = d.get("group", DEFAULT_GROUP)
    if not isinstance(group, str) or not group:
        raise SceneError(f"{key}.group", f"expected the name of an element group, got {group!r}")
    ab = d.get("absorbing", True)
    absorbing = None
    if isinstance(ab, bool):
        if ab:
            absorbing = {"bottom": DEFAULT_BOTTOM, "sides": DEFAULT_SIDES}
    elif isinstance(ab, dict):
        check_keys(ab, {"bottom", "sides"}, f"{key}.absorbing")
        absorbing = {}
        for part, default in (("bottom", DEFAULT_BOTTOM), ("sides", DEFAULT_SIDES)):
            name = ab.get(part, default)
            names = [name] if isinstance(name, str) else name
            if not isinstance(names, list) or not names or not all(isinstance(n, str) and n for n in names):
                raise SceneError(f"{key}.absorbing.{part}", f"expected the name of a facet set (or a list of them), "
                                                            f"got {name!r}")
            absorbing[part] = name if isinstance(name, str) else list(names)
    else:
        raise SceneError(f"{key}.absorbing", "expected a table { bottom = \"<facet set>\", sides = \"<facet set>\" } "
                                             f"or false, got {ab!r}")
    motion = d.get("motion")
    if motion is not None:
        motion = choice(motion, MOTIONS, f"{key}.motion")
    if mass and absorbing is None:
        raise SceneError(f"{key}.absorbing",
                         "a foundation with mass needs absorbing boundaries (viscous dashpots on its bottom and "
                         "sides), else waves reflect at the truncated boundaries and stay trapped in the rock; remove "
                         "'absorbing = false' or set mass = false")
    if mass and motion is None:
        raise SceneError(f"{key}.motion", "is required for a foundation with mass: \"outcrop\" if the record is the "
                                          "motion at a rock outcrop (or deconvolved to one: the base gets half of it "
                                          "as an upgoing wave), \"within\" if it is the motion inside the rock at the "
                                          "base (a rigid base that carries it)")
    dim = int(model.get("dimension", len(model.get("gravity", (0.0, -1.0)))))
    g = np.asarray(model.get("gravity", [0.0] * (dim - 1) + [-1.0]), dtype=float)
    gnorm = float(np.linalg.norm(g))
    axis = dim - 1 if gnorm == 0.0 else int(np.argmax(np.abs(g)))
    if mass and gnorm > 0.0 and np.linalg.norm(np.delete(g, axis)) > 1e-9 * gnorm:
        raise SceneError("model.gravity", f"a foundation with mass needs gravity along a coordinate axis (the vertical "
                                          f"the waves travel along), got {model['gravity']}")
    return {"mass": mass, "group": group, "absorbing": absorbing, "motion": motion, "vertical_axis": axis}


SECTIONS = {"foundation": normalize_section}


# ---------------------------------------------------------------------------------------------
# material


def wave_speeds(youngs_modulus: float, poisson_ratio: float, density: float, hypothesis: str) -> dict:
    """Moduli (Pa) and body-wave speeds (m/s) of the rock for a hypothesis ('plane_strain', '3d',
    'plane_stress'): ``{"G", "lam", "M", "c_s", "c_p"}``; ``M = lam + 2 G`` is the constrained
    (P-wave) modulus. Plane stress uses the plate moduli ``lam* = E nu / (1 - nu^2)``, ``M = E / (1 -
    nu^2)`` (the moduli of the plane stress elements)."""
    E, nu, rho = float(youngs_modulus), float(poisson_ratio), float(density)
    if not (E > 0.0 and rho > 0.0 and -1.0 < nu < 0.5):
        raise ValueError(f"need E > 0, rho > 0, -1 < nu < 0.5; got E={E}, nu={nu}, rho={rho}")
    G = E / (2.0 * (1.0 + nu))
    if hypothesis in ("plane_strain", "3d"):
        lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    elif hypothesis == "plane_stress":
        lam = E * nu / (1.0 - nu * nu)
    else:
        raise ValueError(f"unknown hypothesis {hypothesis!r}")
    M = lam + 2.0 * G
    return {"G": G, "lam": lam, "M": M, "c_s": float(np.sqrt(G / rho)), "c_p": float(np.sqrt(M / rho))}


# ---------------------------------------------------------------------------------------------
# facet geometry and dashpots


@dataclass
class Boundary:
    """A set of boundary facets of the rock: ``name`` (facet set), ``type`` (line2/line3 in 2D;
    tri3/tri6/quad4/quad8/quad9 in 3D), ``facets`` (n, nfn) node indices, ``inward`` (n, dim) m: a point
    inside the rock for each facet (the centroid of its element), which orients the normal outward."""

    name: str
    type: str
    facets: np.ndarray
    inward: np.ndarray

    def __post_init__(self):
        nfn = ELEMENT_TYPES[self.type].n_nodes
        self.facets = np.asarray(self.facets, dtype=np.int64).reshape(-1, nfn)
        self.inward = np.asarray(self.inward, dtype=np.float64).reshape(len(self.facets), -1)


@dataclass
class _FacetPoints:
    """Integration points of a boundary: x (n, q, dim) m, normal (n, q, dim) outward unit, dA (n, q) m2
    (times the thickness in 2D), N (q, nfn), lumped weights W (n, q, nfn) m2 (sum over q and a: the
    facet's area), facets (n, nfn)."""

    x: np.ndarray
    normal: np.ndarray
    dA: np.ndarray
    N: np.ndarray
    W: np.ndarray
    facets: np.ndarray


def _facet_points(coords, b: Boundary, thickness: float) -> _FacetPoints:
    dim = coords.shape[1]
    if b.type not in FACET_TYPES[dim]:
        raise ValueError(f"facet set '{b.name}': type {b.type!r} is not a boundary facet in {dim}D "
                         f"(use one of {FACET_TYPES[dim]})")
    pts, w = facet_rule(b.type, 3, triangle="symmetric")  # line 3 points, quadrilateral 3x3, triangle 6 points
    X = coords[b.facets]  # (n, nfn, dim)
    fq = facet_quadrature(b.type, X, pts, w)
    N, x, A, J = fq.shape_values, fq.points, fq.area_normal, fq.jacobian  # (q, nfn), (n, q, dim), (n, q, dim), (n, q)
    sign, _ = facet_outward_sign(b.type, X, b.inward)
    if len(J) and not (J > 0).all():
        bad = int(np.nonzero((J <= 0).any(axis=1))[0][0])
        raise ValueError(f"facet set '{b.name}': degenerate facet {bad} (nodes {b.facets[bad].tolist()})")
    normal = A * (sign[:, None, None] / np.where(J > 0, J, 1.0)[..., None])
    scale = float(thickness) if dim == 2 else 1.0
    dA = J * w[None, :] * scale
    if b.type in _HRZ_TYPES:  # diagonal scaling: weights proportional to N_a^2, summing to the area
        W = dA[:, :, None] * (N * N)[None]
        W *= (dA.sum(axis=1) / W.sum(axis=(1, 2)))[:, None, None]
    else:  # row sums of the consistent matrix: sum_b N_a N_b = N_a
        W = dA[:, :, None] * N[None]
    return _FacetPoints(x, normal, dA, N, W, b.facets)


def _dashpot_blocks(fp: _FacetPoints, rho, c_p, c_s):
    """Node blocks (n, nfn, dim, dim) N s/m: sum_q W_qa rho (c_p n n^T + c_s (I - n n^T))."""
    dim = fp.normal.shape[-1]
    nn = np.einsum("nqi,nqj->nqij", fp.normal, fp.normal)
    D = rho * (c_p * nn + c_s * (np.eye(dim) - nn))
    return np.einsum("nqa,nqij->naij", fp.W, D)


def _assemble_blocks(facets, blocks, n_nodes, dim):
    rows = facets[:, :, None, None] * dim + np.arange(dim)[:, None]
    cols = facets[:, :, None, None] * dim + np.arange(dim)[None, :]
    rows, cols = np.broadcast_to(rows, blocks.shape), np.broadcast_to(cols, blocks.shape)
    C = sp.coo_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(n_nodes * dim, n_nodes * dim)).tocsr()
    C.sum_duplicates()
    return C


def dashpot_matrix(coords, boundaries, density, c_p, c_s, thickness=1.0) -> sp.csr_matrix:
    """Lysmer-Kuhlemeyer dashpots (n_dof, n_dof) CSR, N s/m, of the facets of ``boundaries`` (a list of
    :class:`Boundary`): on each facet ``t = -rho (c_p n n^T + c_s (I - n n^T)) v``, integrated with the
    facet shape functions and lumped per node (blocks dim x dim; DOF ``node * dim + component``).
    ``coords`` (n_nodes, dim) m; ``density`` kg/m3; ``c_p``, ``c_s`` m/s; ``thickness`` m (2D)."""
    coords = np.asarray(coords, dtype=np.float64)
    n_nodes, dim = coords.shape
    C = sp.csr_matrix((n_nodes * dim, n_nodes * dim))
    for b in boundaries:
        if len(b.facets):
            fp = _facet_points(coords, b, thickness)
            C = C + _assemble_blocks(fp.facets, _dashpot_blocks(fp, density, c_p, c_s), n_nodes, dim)
    C.sum_duplicates()
    return C.tocsr()


# ---------------------------------------------------------------------------------------------
# records and the 1D free field


class _Record:
    """One component's acceleration record (n,) m/s2 at step dt (s), integrated from rest with the
    trapezoidal rule: velocity (m/s) and displacement (m) at any time (zero before 0; after the end
    the acceleration is zero)."""

    def __init__(self, acc, dt):
        a = np.asarray(acc, dtype=np.float64).ravel()
        dt = float(dt)
        if not len(a) or not np.isfinite(a).all():
            raise ValueError("an acceleration record needs at least one finite sample")
        if not dt > 0.0:
            raise ValueError(f"the record's time step must be > 0, got {dt}")
        self.dt, self.a = dt, a
        self.v = np.concatenate([[0.0], np.cumsum(0.5 * dt * (a[1:] + a[:-1]))])
        self.d = np.concatenate([[0.0], np.cumsum(0.5 * dt * (self.v[1:] + self.v[:-1]))])
        self.t = dt * np.arange(len(a))
        self.t_end = float(self.t[-1])

    def velocity(self, t):
        return np.interp(t, self.t, self.v, left=0.0)

    def displacement(self, t):
        t = np.asarray(t, dtype=np.float64)
        d = np.interp(t, self.t, self.d, left=0.0)
        return d + self.v[-1] * np.maximum(t - self.t_end, 0.0)


class _Upgoing:
    """The upgoing wave at the base, ``u_I(t)`` and ``v_I(t)``, of one component.

    outcrop: ``u_I = o / 2``; within (layer on a rigid base, ``2 T = 2 H_f / c``): ``u_I(t) = sum_k
    (-1)^k w(t - 2 k T)``, evaluated exactly on a uniform grid of the record's step (extended on demand)
    and interpolated linearly."""

    def __init__(self, record: _Record, motion: str, two_T: float):
        self.rec, self.motion, self.two_T = record, motion, float(two_T)
        self._grid_end = -1.0
        self._tg = self._ug = self._vg = None

    def _extend(self, t_need):
        rec = self.rec
        t_end = max(2.0 * t_need, rec.t_end + 4.0 * self.two_T, 1.0)
        n = int(np.ceil(t_end / rec.dt)) + 1
        tg = rec.dt * np.arange(n)
        ug, vg = np.zeros(n), np.zeros(n)
        k = 0
        while k * self.two_T <= tg[-1]:
            s = tg - k * self.two_T
            on = s >= 0.0
            sign = -1.0 if k % 2 else 1.0
            ug[on] += sign * rec.displacement(s[on])
            vg[on] += sign * rec.velocity(s[on])
            k += 1
        self._tg, self._ug, self._vg, self._grid_end = tg, ug, vg, float(tg[-1])

    def __call__(self, t):
        """(u_I, v_I) at times t (any shape), m and m/s."""
        t = np.asarray(t, dtype=np.float64)
        if self.motion == "outcrop":
            return 0.5 * self.rec.displacement(t), 0.5 * self.rec.velocity(t)
        tmax = float(t.max()) if t.size else 0.0
        if tmax > self._grid_end:
            self._extend(tmax)
        return (np.interp(t, self._tg, self._ug, left=0.0), np.interp(t, self._tg, self._vg, left=0.0))


@dataclass(eq=False)
class _FreeFieldOperator:
    """What :meth:`Foundation.effective_force` precomputes for one set of records: ``K`` (CSR of its
    ``rows`` (n_rows,) DOFs x n_comp * n_z columns, N per unit strain or per m/s) maps the free-field values
    at the distinct elevations to the force; the delays (n_comp, n_z) s; the packed velocity grids
    (see :func:`~masonrydam.effects.foundation_kernels.free_field_force`); ``w`` (n_comp * n_z,) and
    ``out`` (n_rows,) the kernel's outputs."""

    records: dict
    upgoing: list
    rows: np.ndarray
    n_strain: int
    delay_1: np.ndarray
    delay_2: np.ndarray
    delay_min: np.ndarray
    dt: np.ndarray
    scale: np.ndarray
    speed: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    data: np.ndarray
    w: np.ndarray
    out: np.ndarray
    grids: np.ndarray = None
    grid_offset: np.ndarray = None
    grid_length: np.ndarray = None
    base_offset: np.ndarray = None
    base_length: np.ndarray = None
    sources: list = None


# ---------------------------------------------------------------------------------------------
# the foundation


class Foundation:
    """The rock with mass: dashpots, released supports and free-field effective forces.

    Parameters
    ----------
    coords : (n_nodes, dim) m, the model's node coordinates (DOF ``node * dim + component``).
    bottom : :class:`Boundary`, the base of the rock (its lowest elevation is ``z_b``).
    sides : :class:`Boundary` or None, the lateral boundaries (None or empty: a column without sides).
    youngs_modulus, poisson_ratio, density : the rock's E (Pa), nu, rho (kg/m3, > 0).
    motion : "outcrop" or "within" (see the module docstring).
    hypothesis : "plane_strain", "plane_stress" (2D) or "3d".
    thickness : m, out-of-plane thickness in 2D (ignored in 3D).
    vertical_axis : index of the vertical coordinate (the waves travel along it).
    z_top, z_bottom : m, elevations of the rock's free surface and base (defaults: the highest node of
        ``coords`` and the lowest node of ``bottom``; :func:`build` takes the highest node of the rock's
        group and the lowest node of the bottom facet set).
    group : the element group's name (for the summary).
    records : optional ``{component: (acceleration (n,) m/s2, dt s)}``, component "x"/"y"/"z" or an
        index; see :meth:`set_motion`.

    Hooks for the dynamic solver
    ----------------------------
    :attr:`dashpots` (n_dof, n_dof) CSR N s/m: added to the damping matrix (acts on the solver's
    velocity: absolute for outcrop, relative to the base for within). :attr:`released_dofs` (n_dof,)
    bool: supports the dynamic stage frees (keeping their static reactions as constant forces).
    :meth:`effective_force` (t) -> (n_dof,) N: added to the external force at time t.
    :attr:`base_excitation` bool: whether the solver also applies ``-M iota a_g`` (within: yes, with
    the same record; outcrop: NO).
    """

    def __init__(self, coords, bottom: Boundary, sides: Boundary | None, *, youngs_modulus, poisson_ratio,
                 density, motion, hypothesis="plane_strain", thickness=1.0, vertical_axis=None, z_top=None,
                 z_bottom=None, group=DEFAULT_GROUP, records=None):
        self.coords = np.ascontiguousarray(coords, dtype=np.float64)
        self.n_nodes, self.dim = self.coords.shape
        self.n_dof = self.n_nodes * self.dim
        dim = self.dim
        if motion not in MOTIONS:
            raise ValueError(f"motion must be one of {MOTIONS}, got {motion!r}")
        self.motion, self.group = motion, group
        self.hypothesis = "3d" if dim == 3 else hypothesis
        self.thickness = float(thickness) if dim == 2 else 1.0
        self.axis = ax = dim - 1 if vertical_axis is None else int(vertical_axis)
        self.rho = float(density)
        self.moduli = wave_speeds(youngs_modulus, poisson_ratio, density, self.hypothesis)
        self.c_s, self.c_p = self.moduli["c_s"], self.moduli["c_p"]
        self.bottom = bottom
        self.sides = sides if sides is not None and len(sides.facets) else None
        zb_nodes = self.coords[np.unique(bottom.facets), ax]
        self.z_b = float(zb_nodes.min()) if z_bottom is None else float(z_bottom)
        self.z_top = float(self.coords[:, ax].max()) if z_top is None else float(z_top)
        if not self.z_top > self.z_b:
            raise ValueError(f"the rock's free surface z_top = {self.z_top:g} m must lie above its base z_b = "
                             f"{self.z_b:g} m")
        self.H = self.z_top - self.z_b
        #: wave speed per component (S for horizontal, P for the vertical one)
        self.speed = np.array([self.c_p if c == ax else self.c_s for c in range(dim)])

        # the boundaries that get dashpots and effective forces
        parts = [bottom] if motion == "outcrop" else []
        if self.sides is not None:
            parts.append(self.sides)
        self._points = [_facet_points(self.coords, b, self.thickness) for b in parts]
        self.dashpots = sp.csr_matrix((self.n_dof, self.n_dof))
        for fp in self._points:
            blocks = _dashpot_blocks(fp, self.rho, self.c_p, self.c_s)
            self.dashpots = self.dashpots + _assemble_blocks(fp.facets, blocks, self.n_nodes, dim)
        self.dashpots = self.dashpots.tocsr()
        self.dashpots.sum_duplicates()
        #: the nodes with dashpots (absorbing nodes)
        self.absorbing_nodes = np.unique(np.concatenate([fp.facets.ravel() for fp in self._points])) \
            if self._points else np.zeros(0, dtype=np.int64)
        #: lumped facet area per node (m2; times the thickness in 2D)
        self.node_area = np.zeros(self.n_nodes)
        for fp in self._points:
            np.add.at(self.node_area, fp.facets.ravel(), fp.W.sum(axis=1).ravel())

        released = np.zeros(self.n_nodes, dtype=bool)
        if motion == "outcrop":
            released[self.absorbing_nodes] = True
        elif self.sides is not None:
            released[np.unique(self.sides.facets)] = True
            released[np.unique(bottom.facets)] = False  # the rigid base keeps its nodes
        #: (n_dof,) bool: the support DOFs that the dynamic stage releases
        self.released_dofs = np.repeat(released, dim)
        #: whether the solver applies the record as uniform support excitation -M iota a_g (within only)
        self.base_excitation = motion == "within"

        # stress part of the effective force: nodal force = S @ traction (P * dim,)
        if self._points:
            xs = np.concatenate([fp.x.reshape(-1, dim) for fp in self._points])
            ns = np.concatenate([fp.normal.reshape(-1, dim) for fp in self._points])
            rows, cols, vals = [], [], []
            off = 0
            for fp in self._points:
                n, q = fp.dA.shape
                nfn = fp.facets.shape[1]
                p = off + np.arange(n * q).reshape(n, q)  # point index
                wN = fp.dA[:, :, None] * fp.N[None]  # (n, q, nfn) consistent weights
                for i in range(dim):
                    rows.append(np.broadcast_to(fp.facets[:, None, :] * dim + i, (n, q, nfn)).ravel())
                    cols.append(np.broadcast_to(p[:, :, None] * dim + i, (n, q, nfn)).ravel())
                    vals.append(wN.ravel())
                off += n * q
            self._S = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                    shape=(self.n_dof, off * dim))
            self._S.sum_duplicates()
        else:
            xs, ns = np.zeros((0, dim)), np.zeros((0, dim))
            self._S = sp.csr_matrix((self.n_dof, 0))
        self._xs, self._ns = xs, ns
        self._records: dict[int, _Upgoing] = {}
        self._ff_op: _FreeFieldOperator | None = None
        if records is not None:
            self.set_motion(records)

    # -- ground motion ----------------------------------------------------------------------

    def set_motion(self, records: dict) -> None:
        """Set the ground motion: ``{component: (acceleration (n,) m/s2, dt s)}`` (component "x"/"y"/"z"
        or an index < dim; missing components are at rest). outcrop: the record at a rock outcrop;
        within: the motion of the rigid base (the same record the solver applies as -M iota a_g)."""
        self._records = {}
        for c, (acc, dt) in dict(records).items():
            ci = _AXES.index(c) if isinstance(c, str) else int(c)
            if not 0 <= ci < self.dim:
                raise ValueError(f"component {c!r} is not one of {list(_AXES[:self.dim])}")
            self._records[ci] = _Upgoing(_Record(acc, dt), self.motion, 2.0 * self.H / self.speed[ci])

    def base_motion(self, component, t):
        """Displacement and velocity (m, m/s) of the base record ``o`` / ``w`` of a component at times t."""
        ci = _AXES.index(component) if isinstance(component, str) else int(component)
        up = self._records.get(ci)
        t = np.asarray(t, dtype=np.float64)
        if up is None:
            return np.zeros_like(t), np.zeros_like(t)
        return up.rec.displacement(t), up.rec.velocity(t)

    def surface_acceleration(self, t: float) -> np.ndarray:
        """Total acceleration (dim,) m/s2 of the free field at the rock's free surface ``z_top`` at time t:
        the motion of the bottom of a reservoir resting on the rock (a central difference of the
        free-field velocity over 0.1 ms; the velocity is piecewise linear between record samples)."""
        out = np.zeros(self.dim)
        d = 1e-4
        for ci in self._records:
            _, vp, _ = self.free_field(self.z_top, t + d, ci, relative=False)
            _, vm, _ = self.free_field(self.z_top, t - d, ci, relative=False)
            out[ci] = (float(vp) - float(vm)) / (2.0 * d)
        return out

    def free_field(self, z, t, component, relative=None):
        """The 1D free field of one component at elevations z (m) and time t (s): displacement (m),
        velocity (m/s), strain du/dz (-), arrays of z's shape. ``relative`` (default: True for within,
        False for outcrop) subtracts the base motion from the displacement and the velocity."""
        ci = _AXES.index(component) if isinstance(component, str) else int(component)
        z = np.asarray(z, dtype=np.float64)
        up = self._records.get(ci)
        if up is None:
            zero = np.zeros_like(z)
            return zero, zero.copy(), zero.copy()
        c = self.speed[ci]
        u1, v1 = up(t - (z - self.z_b) / c)
        u2, v2 = up(t - (2.0 * self.z_top - self.z_b - z) / c)
        u, v, dudz = u1 + u2, v1 + v2, (v2 - v1) / c
        if self.motion == "within" if relative is None else relative:
            ug, vg = self.base_motion(ci, t)
            u, v = u - ug, v - vg
        return u, v, dudz

    def _traction(self, t):
        """Free-field traction sigma_ff n (P, dim) Pa at the integration points at time t."""
        dim, ax = self.dim, self.axis
        m = self.moduli
        T = np.zeros_like(self._ns)
        if not len(T):
            return T
        z, n = self._xs[:, ax], self._ns
        for ci in self._records:
            _, _, e = self.free_field(z, t, ci)
            if ci == ax:  # P wave: sigma_zz = M e, sigma_hh = lam e
                for h in range(dim):
                    T[:, h] += (m["M"] if h == ax else m["lam"]) * e * n[:, h]
            else:  # S wave: sigma_hz = sigma_zh = G e
                T[:, ci] += m["G"] * e * n[:, ax]
                T[:, ax] += m["G"] * e * n[:, ci]
        return T

    def effective_force(self, t: float) -> np.ndarray:
        """Free-field effective force (n_dof,) N at time t (s): ``int N^T sigma_ff n dA + C_dashpot
        v_ff(nodes)``, with ``v_ff`` relative to the base motion for within. Zero with no record set.

        One kernel call (:func:`~masonrydam.effects.foundation_kernels.free_field_force`) on an operator
        built at the first call after :meth:`set_motion`: the values of :meth:`_effective_force_reference`
        (the same interpolations of :meth:`free_field`) to round-off of the sums."""
        if not self._records or not self._points:
            return np.zeros(self.n_dof)
        t = float(t)
        op = self._operator()
        for k, up in enumerate(op.upgoing):  # the within grid must reach the latest time the kernel reads
            if up.motion == "within" and t - op.delay_min[k] > up._grid_end:
                up._extend(t - op.delay_min[k])
            if op.sources[k] is not (up.rec.v if up.motion == "outcrop" else up._vg):
                self._pack_grids(op)
        status = free_field_force(t, op.grids, op.grid_offset, op.grid_length, op.base_offset, op.base_length,
                                  op.dt, op.scale, op.speed, op.delay_1, op.delay_2, op.n_strain, op.indptr,
                                  op.indices, op.data, op.w, op.out)
        if status != STATUS_OK:  # pragma: no cover - the kernel has no failing case
            raise RuntimeError(f"free_field_force returned status {status}")
        f = np.zeros(self.n_dof)
        f[op.rows] = op.out
        return f

    def _operator(self) -> "_FreeFieldOperator":
        """The operator of :meth:`effective_force` for the records of the last :meth:`set_motion`."""
        op = getattr(self, "_ff_op", None)
        if op is not None and op.records is self._records:
            return op
        dim, ax = self.dim, self.axis
        comps = list(self._records)
        nc = len(comps)
        z_pts, i_pts = np.unique(self._xs[:, ax], return_inverse=True)
        nodes = self.absorbing_nodes
        z_nodes, i_nodes = np.unique(self.coords[nodes, ax], return_inverse=True)
        z = np.concatenate([z_pts, z_nodes])
        nzt, nz = len(z_pts), len(z)
        # the delays exactly as free_field forms them
        delay_1 = np.array([(z - self.z_b) / self.speed[ci] for ci in comps]).reshape(nc, nz)
        delay_2 = np.array([(2.0 * self.z_top - self.z_b - z) / self.speed[ci] for ci in comps]).reshape(nc, nz)
        # traction T (P, dim) = sum_c a_c (P, dim) * strain_c(z_p) (the stress of _traction); V on the nodes
        m, n, P = self.moduli, self._ns, len(self._xs)
        pts = np.arange(P)
        rows_a, cols_a, vals_a, rows_b, cols_b = [], [], [], [], []
        for k, ci in enumerate(comps):
            a = np.zeros((P, dim))
            if ci == ax:  # P wave: sigma_zz = M e, sigma_hh = lam e
                for h in range(dim):
                    a[:, h] = (m["M"] if h == ax else m["lam"]) * n[:, h]
            else:  # S wave: sigma_hz = sigma_zh = G e
                a[:, ci] += m["G"] * n[:, ax]
                a[:, ax] += m["G"] * n[:, ci]
            for h in range(dim):
                rows_a.append(pts * dim + h)
                cols_a.append(k * nz + i_pts)
                vals_a.append(a[:, h])
            rows_b.append(nodes * dim + ci)
            cols_b.append(k * nz + nzt + i_nodes)
        A = sp.csr_matrix((np.concatenate(vals_a), (np.concatenate(rows_a), np.concatenate(cols_a))),
                          shape=(P * dim, nc * nz))
        rb = np.concatenate(rows_b)
        B = sp.csr_matrix((np.ones(len(rb)), (rb, np.concatenate(cols_b))), shape=(self.n_dof, nc * nz))
        K = (self._S @ A + self.dashpots @ B).tocsr()
        K.sum_duplicates()
        rows = np.flatnonzero(np.diff(K.indptr))
        K = K[rows]
        up = [self._records[ci] for ci in comps]
        op = _FreeFieldOperator(
            records=self._records, upgoing=up, rows=rows.astype(np.int64), n_strain=nzt,
            delay_1=np.ascontiguousarray(delay_1), delay_2=np.ascontiguousarray(delay_2),
            delay_min=np.minimum(delay_1, delay_2).min(axis=1) if nz else np.zeros(nc),
            dt=np.array([u.rec.dt for u in up]), scale=np.array([0.5 if u.motion == "outcrop" else 1.0 for u in up]),
            speed=np.array([float(self.speed[ci]) for ci in comps]),
            indptr=K.indptr.astype(np.int64), indices=K.indices.astype(np.int64), data=np.ascontiguousarray(K.data),
            w=np.zeros(nc * nz), out=np.zeros(len(rows)))
        self._pack_grids(op)
        self._ff_op = op
        return op

    @staticmethod
    def _pack_grids(op: "_FreeFieldOperator") -> None:
        """Pack the velocity grids of the operator's components (upgoing wave, then base motion) into one
        array (after :meth:`set_motion` and whenever a within grid was extended)."""
        parts, off, goff, glen, boff, blen, sources = [], 0, [], [], [], [], []
        for u in op.upgoing:
            g = u.rec.v if u.motion == "outcrop" else u._vg
            if g is None:  # a within grid not built yet
                u._extend(0.0)
                g = u._vg
            sources.append(g)
            parts.append(g)
            goff.append(off)
            glen.append(len(g))
            off += len(g)
        for u in op.upgoing:
            if u.motion == "within":  # free_field subtracts the base motion (relative) for within
                parts.append(u.rec.v)
                boff.append(off)
                blen.append(len(u.rec.v))
                off += len(u.rec.v)
            else:
                boff.append(0)
                blen.append(0)
        op.grids = np.concatenate(parts) if parts else np.zeros(0)
        op.grid_offset, op.grid_length = np.array(goff, dtype=np.int64), np.array(glen, dtype=np.int64)
        op.base_offset, op.base_length = np.array(boff, dtype=np.int64), np.array(blen, dtype=np.int64)
        op.sources = sources

    def _effective_force_reference(self, t: float) -> np.ndarray:
        """:meth:`effective_force` evaluated point by point with :meth:`free_field` and :meth:`_traction`
        (the reference the tests compare the kernel with)."""
        f = np.zeros(self.n_dof)
        if not self._records or not self._points:
            return f
        f += self._S @ self._traction(float(t)).ravel()
        V = np.zeros(self.n_dof)
        nodes = self.absorbing_nodes
        z = self.coords[nodes, self.axis]
        for ci in self._records:
            V[nodes * self.dim + ci] = self.free_field(z, float(t), ci)[1]
        return f + self.dashpots @ V

    # -- summary ----------------------------------------------------------------------------

    def describe(self) -> list[str]:
        """Lines for the run summary: what is simulated."""
        where = (f"'{self.bottom.name}'" + (f" and '{self.sides.name}'" if self.sides else "")
                 if self.motion == "outcrop" else (f"'{self.sides.name}'" if self.sides else "no facets"))
        lines = [f"foundation rock with mass: group '{self.group}', density {self.rho:g} kg/m3, "
                 f"c_p {self.c_p:.0f} m/s, c_s {self.c_s:.0f} m/s ({self.hypothesis.replace('_', ' ')}), "
                 f"from the base at {self.z_b:g} m to the free surface at {self.z_top:g} m",
                 f"absorbing boundaries: Lysmer-Kuhlemeyer (1969) viscous dashpots on {where} "
                 f"({len(self.absorbing_nodes)} nodes)"]
        if self.motion == "outcrop":
            lines.append("ground motion: outcrop motion, half of it as an upgoing wave at a compliant base (Joyner & "
                         "Chen 1975), free-field effective forces on the base and sides (1D vertical S/P waves; "
                         "Nielsen 2006, Lokke & Chopra 2018); bottom and side supports released, no uniform base "
                         "excitation")
        else:
            lines.append("ground motion: within-rock motion at a rigid base (uniform base excitation, relative "
                         "formulation), free-field effective forces on the sides from the layer on a rigid base "
                         "(1D vertical S/P waves; Nielsen 2006, Lokke & Chopra 2018); side supports released")
        return lines


# ---------------------------------------------------------------------------------------------
# from the mesh


def _boundary(mesh, name, key, group):
    """The :class:`Boundary` of the facet set ``name`` (or of a list of facet sets of one facet type)."""
    names = [name] if isinstance(name, str) else list(name)
    for n in names:
        if n not in mesh.facet_sets:
            what = "edge" if mesh.dim == 2 else "face"
            raise SceneError(key, f"no facet ({what}) set '{n}' in the mesh (facet sets: {sorted(mesh.facet_sets)})")
    types = {mesh.facet_sets[n].type for n in names}
    if len(types) > 1:
        raise SceneError(key, f"the facet sets {names} have different facet types {sorted(types)}")
    fs = mesh.facet_sets[names[0]]
    facets = np.concatenate([np.asarray(mesh.facet_sets[n].facets, dtype=np.int64) for n in names])
    name = "+".join(names)
    if not len(facets):
        raise SceneError(key, f"the facet set '{name}' is empty")
    ok, inward = boundary_owners(mesh, fs.type, facets, group)
    if not ok.all():
        bad = np.nonzero(~ok)[0]
        raise SceneError(key, f"{len(bad)} facet(s) of '{name}' are not on the boundary of the element group '{group}' "
                              f"(e.g. facet {int(bad[0])}, nodes {facets[bad[0]].tolist()}): absorbing boundaries go "
                              "on the outer bottom and sides of the rock")
    return Boundary(name, fs.type, facets, inward)


def build(spec: dict, mesh, materials: dict, model: dict, records=None) -> Foundation | None:
    """The :class:`Foundation` of a normalised ``[foundation]`` section on ``mesh``; None when
    ``spec`` is None or ``mass = false`` (nothing changes). ``materials``: the normalised
    ``[materials]`` section; ``model``: the normalised ``[model]`` section (hypothesis, thickness);
    ``records``: see :meth:`Foundation.set_motion`. Raises SceneError naming the key for a density
    <= 0, a missing facet set, or absorbing facets not on the boundary of the rock's group."""
    if not spec or not spec.get("mass"):
        return None
    group = spec["group"]
    if group not in mesh.group_names():
        raise SceneError("foundation.group", f"no element group '{group}' in the mesh (groups: {mesh.group_names()})")
    if group not in materials:
        raise SceneError(f"materials.{group}", "is required: the rock of a foundation with mass needs E, nu and "
                                               "density")
    mat = materials[group]
    rho = float(mat.get("density", 0.0))
    if not rho > 0.0:
        raise SceneError(f"materials.{group}.density", f"must be > 0 for a foundation with mass (foundation.mass = "
                                                       f"true), got {rho:g}")
    ab = spec["absorbing"]
    bottom = _boundary(mesh, ab["bottom"], "foundation.absorbing.bottom", group)
    sides = _boundary(mesh, ab["sides"], "foundation.absorbing.sides", group)
    ax = int(spec.get("vertical_axis", mesh.dim - 1))
    nodes = np.unique(np.concatenate([b.cells.ravel() for b in mesh.blocks if b.name == group and not b.is_interface]))
    z_top = float(mesh.points[nodes, ax].max())
    z_b = float(mesh.points[np.unique(bottom.facets), ax].min())
    return Foundation(mesh.points, bottom, sides, youngs_modulus=mat["youngs_modulus"],
                      poisson_ratio=mat["poisson_ratio"], density=rho, motion=spec["motion"],
                      hypothesis=model.get("hypothesis", "plane_strain"), thickness=model.get("thickness", 1.0),
                      vertical_axis=ax, z_top=z_top, z_bottom=z_b, group=group, records=records)


class FoundationRun(EffectRun):
    """What ``[foundation]`` adds to a run: with ``mass = false`` a massless rock group; with ``mass = true``
    and dynamic stages the :class:`Foundation` (dashpots, free-field forces, released supports)."""

    def __init__(self, context):
        spec = context.scene["foundation"]
        self.massless = () if spec["mass"] else (spec["group"],)
        self.rock = None
        if spec["mass"] and context.dynamic_stages:
            self.rock = build(spec, context.mesh, context.scene["materials"], context.scene["model"])

    def attrs(self) -> dict:
        if self.rock is None:
            return {}
        out = {"foundation": "; ".join(self.rock.describe())}
        if not self.rock.base_excitation:
            out["time_history_conventions_foundation"] = (
                "with [foundation] mass = true and an outcrop motion the ground motion enters as free-field forces "
                "at the compliant base: displacement, velocity and acceleration of the dynamic steps are total, not "
                "relative to the ground (acceleration_absolute = acceleration)")
        return out

    def mass_terms(self, lumped: bool) -> dict:
        return {"massless": self.massless} if self.massless else {}

    def carried_static_force(self, model, u, f_static) -> None:
        if self.rock is None:
            return
        # the supports the absorbing boundaries replace keep their static reactions as constant loads
        # (every dynamic stage, not only the first, which takes its constant load from f_int)
        f_int, _ = model.evaluate(u, want_tangent=False)
        released = self.rock.released_dofs
        f_static[released] = f_int[released]

    def dynamic_terms(self, stage, terms) -> None:
        """Dashpots, free-field forces and the released supports; each stage's free field starts with its own
        record at its start (waves of the stage before that still travel outside the model are not carried
        over)."""
        rock = self.rock
        if rock is None:
            return
        rock.set_motion({g.component: (g.values, g.dt) for g in stage.ground_motion})
        terms.dashpots = rock.dashpots
        add_force(terms, rock.effective_force)
        terms.support_excitation = rock.base_excitation
        terms.bottom_acceleration = rock.surface_acceleration
        stage.supports = stage.supports & ~rock.released_dofs


def activate(context):
    """The :class:`FoundationRun` of a scene with a ``[foundation]`` section, or None."""
    return FoundationRun(context) if context.scene.get("foundation") else None


# ---------------------------------------------------------------------------------------------
# registry entry


def describe(scene, model) -> list[str]:
    """Summary lines from the normalised scene alone (the mesh-dependent numbers are in
    :meth:`Foundation.describe`)."""
    f = scene.get("foundation")
    if not f or not f.get("mass"):
        return []
    mat = scene.get("materials", {}).get(f["group"], {})
    hyp = scene.get("model", {}).get("hypothesis", "plane_strain")
    speeds = ""
    try:
        w = wave_speeds(mat["youngs_modulus"], mat["poisson_ratio"], mat["density"], hyp)
        speeds = f", c_p {w['c_p']:.0f} m/s, c_s {w['c_s']:.0f} m/s"
    except (KeyError, ValueError):
        pass
    ab = f["absorbing"]
    if f["motion"] == "outcrop":
        how = (f"outcrop motion as free-field effective forces on '{ab['bottom']}' (compliant base, half the outcrop "
               f"motion upgoing) and '{ab['sides']}'")
    else:
        how = (f"within-rock motion at a rigid base '{ab['bottom']}' (uniform base excitation) with free-field "
               f"effective forces on '{ab['sides']}'")
    return [f"foundation rock with mass (group '{f['group']}'{speeds}): Lysmer-Kuhlemeyer viscous absorbing "
            f"boundaries; {how}"]


# -- the rows of its scene keys in the scene reference (docs/scene.md) ----------------------------------------
_FOUNDATION = Section("[foundation]", "The rock under a dam (an element group of the mesh).", (
    row("foundation.mass", "bool", "false: massless rock; true: rock with mass, absorbing boundaries and a `motion`",
       default=False),
    row("foundation.group", "string", "the rock's element group", default=DEFAULT_GROUP),
    row("foundation.absorbing", "bool or table", "Lysmer-Kuhlemeyer dashpots `{ bottom, sides }` (true: the default "
       "sets; false: none)", default_text="`true`: the two sets below"),
    row("foundation.motion", "string", "mass = true: the record is an outcrop motion (free-field forces at a "
       "compliant base) or a within-rock motion (a rigid base)", default_text="required with mass", choices=MOTIONS),
    row("foundation.absorbing.bottom", "string or list", "facet set(s) of the bottom", default=DEFAULT_BOTTOM),
    row("foundation.absorbing.sides", "string or list", "facet set(s) of the sides", default=DEFAULT_SIDES),
))


def _effects():
    return [Effect("foundation", "[foundation] with mass = true", __name__,
                   "Lysmer & Kuhlemeyer 1969 (ASCE J. Eng. Mech. Div. 95(EM4)); Joyner & Chen 1975 (BSSA 65); "
                   "Nielsen 2006 (ABAQUS Users' Conf.); Lokke & Chopra 2018 (EESD 47)", "tests/effects/test_foundation.py",
                   describe, activate=activate, scene_keys=(_FOUNDATION,),
                   section_meanings={"foundation": "the rock under a dam: massless, or with mass and absorbing "
                                                   "boundaries"})]


EFFECTS = _effects()
