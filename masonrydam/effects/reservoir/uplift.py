"""Uplift: the pore pressure of the reservoir water inside the joints of a dam.

The scene asks for it in ``[reservoir] uplift = { joints, drains = { distance, efficiency }, cracked }``.
:class:`Uplift` computes the pore pressure (Pa) at the integration points of the named joint sets from a
piezometric head (m) linear along each joint line (heel, drain line, toe; full head in a crack open from the
heel with ``cracked = "full_head"``) and adds its forces, ``+-N_a p n w`` on the two faces (N), to the external
forces; the unit weight ``rho_w g`` is in N/m3. References: USBR, Design of Small Dams (1987), sec. 5.7; USACE
EM 1110-2-2200 (1995), secs. 3-3 and 4-4; FERC Engineering Guidelines ch. 3 (2016).

Theory: docs/water.md, section "Uplift in the joints".
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...assembly.joint_lines import JointLines
from ...checks import check_keys, choice, number, positive
from ...elements.shapes import facet_quadrature
from ...errors import SceneError
from ...materials.joint_laws import RESULT_OPEN
from ...mesh.model import INTERFACE_FACE_TYPE
from ..base import Effect
from .hydrostatics import region_points

CRACKED = ("full_head", "unchanged", "none")
#: uplift during the dynamic stages (the options of CADAM3D, Leclerc, Leger & Tinawi 2003, Adv. Eng. Softw.
#: 34:583-601, and its user's manual sec. 3.6; FERC Engineering Guidelines ch. 3 sec. 3-8.2): "static" keeps the
#: pore pressures of the end of the static stages; "full_head" lets the full reservoir pressure into the
#: parts of a joint that open (from the heel); "none" takes it out of them (the water has no time to enter)
EARTHQUAKE = ("static", "full_head", "none")


def normalize(d, key: str) -> dict:
    """The ``uplift`` table of ``[reservoir]``."""
    check_keys(d, {"joints", "drains", "cracked", "earthquake"}, key)
    joints = d.get("joints")
    if isinstance(joints, str):
        joints = [joints]
    if not isinstance(joints, list) or not joints or not all(isinstance(j, str) for j in joints):
        raise SceneError(f"{key}.joints", f"expected a list of joint set names, e.g. [\"base_joint\", \"lift_joints\"], "
                                          f"got {d.get('joints')!r}")
    out = {"joints": list(joints), "cracked": choice(d.get("cracked", "full_head"), CRACKED, f"{key}.cracked"),
           "earthquake": choice(d.get("earthquake", "static"), EARTHQUAKE, f"{key}.earthquake"), "drains": None}
    if "drains" in d:
        dk = f"{key}.drains"
        dr = d["drains"]
        check_keys(dr, {"distance", "efficiency"}, dk)
        for req in ("distance", "efficiency"):
            if req not in dr:
                raise SceneError(f"{dk}.{req}", "is required (distance of the drain line from the upstream face, m; "
                                                "efficiency from 0 to 1)")
        out["drains"] = {"distance": positive(dr["distance"], "length", f"{dk}.distance"),
                         "efficiency": number(dr["efficiency"], f"{dk}.efficiency", 0.0, 1.0)}
    return out


class Uplift:
    """Pore pressures in the joint sets named by ``spec`` (normalised ``uplift`` table) of ``model``.

    unit_weight: rho_w g (N/m3); vertical_axis; downstream: horizontal unit vector (dim,); key: the
    scene key of the table (for errors); upstream_face: the upstream face's nodes and horizontal normals
    in 3D, from which each joint line takes its own frame (:class:`JointLines`; an arch's cantilevers
    are measured radially), or None."""

    def __init__(self, spec: dict, model, unit_weight: float, vertical_axis: int, downstream, key: str,
                 upstream_face=None):
        names = sorted({g.name for g in model.igroups})
        for j in spec["joints"]:
            if j not in names:
                raise SceneError(f"{key}.joints", f"'{j}' is not a joint set of the mesh (joint sets: {names})")
        self.spec = spec
        self.gamma = float(unit_weight)
        self.group_index = [i for i, g in enumerate(model.igroups) if g.name in spec["joints"]]
        self.lines = JointLines(model, [model.igroups[i] for i in self.group_index], downstream, vertical_axis,
                                upstream_face)
        self._samples(model)
        self.pressure = np.zeros(self.lines.n_points)  # the last computed pore pressures at the joint points (Pa)
        self.sample_pressure = np.zeros(len(self.samples["s"]))  # and at the samples
        self._latch_step, self._latched_tip = None, None  # the crack tips filled in this step attempt

    def _samples(self, model):
        """Where the pore pressure is integrated into nodal forces: Gauss points on each interface face,
        the faces that the drain line crosses split along it (:func:`~.hydrostatics.region_points`), so
        that the piecewise-linear profile is integrated exactly (the joint's own lumped points would
        misplace the uplift's moment by O(h^2), and a kink inside an element its resultant).

        Sets ``self.matrix`` (n_dof, n_samples): nodal forces of a unit pressure at each sample (``N_a w
        n`` on the top face, minus that on the bottom face), and the samples' ``s``, ``elevation``,
        ``line``, ``strip`` and ``weight`` (m2)."""
        L, dim = self.lines, model.dim
        drains = self.spec["drains"]
        rows, cols, vals = [], [], []
        parts = {k: [] for k in ("s", "elevation", "line", "strip", "weight")}
        n_samples = 0
        for gi, sl in zip(self.group_index, L.slices):
            g = model.igroups[gi]
            ns = g.conn.shape[1] // 2
            face = INTERFACE_FACE_TYPE[g.type]
            X = model.coords[g.conn[:, :ns]]  # (ne, ns, dim) bottom face
            pts_line = L.line[sl].reshape(g.n_elem, g.nip)
            pts_x = L.x[sl].reshape(g.n_elem, g.nip, dim)
            # the nodes' s in their line's frame (a curved line's s is radial: the split along the drain line
            # is then linear between the nodes, as the element's own geometry)
            s_nodes = L.coordinates(X.reshape(-1, dim), np.repeat(pts_line[:, 0], ns))[0].reshape(g.n_elem, ns)
            if drains is None:
                pieces = [region_points(face, s_nodes, float(s_nodes.max()) + 1.0)]
            else:
                pieces = [region_points(face, s_nodes, drains["distance"]),
                          region_points(face, -s_nodes, -drains["distance"])]
            for e, xi, w in pieces:
                if len(e) == 0:
                    continue
                fq = facet_quadrature(face, X, xi, w, owner=e)
                N, x, A, J = fq.shape_values, fq.points, fq.area_normal, fq.jacobian  # (P, ns), (P, dim), (P, dim), (P,)
                n = A / J[:, None]
                n *= np.sign(np.einsum("pd,pd->p", n, g.frame[e, 0, dim - 1, :]))[:, None]  # bottom to top
                wt = w * J * g.thickness[e]
                idx = n_samples + np.arange(len(e))
                n_samples += len(e)
                for a in range(ns):
                    for side, sign in ((g.conn[e, ns + a], 1.0), (g.conn[e, a], -1.0)):
                        for k in range(dim):
                            v = sign * N[:, a] * wt * n[:, k]
                            keep = v != 0.0
                            rows.append((side * dim + k)[keep])
                            cols.append(idx[keep])
                            vals.append(v[keep])
                s_x, across_x = L.coordinates(x, pts_line[e, 0])
                parts["s"].append(s_x)
                parts["elevation"].append(x[:, L.vertical_axis])
                parts["line"].append(pts_line[e, 0])
                parts["weight"].append(wt)
                if dim == 2:
                    parts["strip"].append(L.strip[sl].reshape(g.n_elem, g.nip)[e, 0])
                else:  # the strip of the element's point nearest across the line
                    t_pts = L.coordinates(pts_x[e].reshape(-1, dim), np.repeat(pts_line[e, 0], g.nip))[1]
                    t_pts = t_pts.reshape(len(e), g.nip)  # (P, nip)
                    near = np.argmin(np.abs(t_pts - across_x[:, None]), axis=1)
                    parts["strip"].append(L.strip[sl].reshape(g.n_elem, g.nip)[e, near])
        self.samples = {k: np.concatenate(v) for k, v in parts.items()}
        self.matrix = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                    shape=(model.n_dof, n_samples))

    def _heads(self, level: float, tail: float | None):
        L = self.lines
        h_up = np.full(L.n_lines, float(level))
        h_tail = L.toe_elevation.copy() if tail is None else np.maximum(L.toe_elevation, float(tail))
        return h_up, h_tail

    def _profile(self, s, length, h_up, h_tail, start):
        """Head (m) at distance ``s`` of lines of ``length`` whose profile starts (full head ``h_up``) at
        ``start`` (0, or the crack tip) and ends at the toe with ``h_tail``; through the drain line where
        it lies past ``start`` and before the toe."""
        span = np.maximum(length - start, 1e-300)
        f = np.clip((s - start) / span, 0.0, 1.0)
        h = h_up + (h_tail - h_up) * f
        dr = self.spec["drains"]
        if dr is None:
            return h
        d = dr["distance"]
        h_drain = h_tail + (1.0 - dr["efficiency"]) * (h_up - h_tail)
        active = (d > start) & (d < length)
        up = np.clip((s - start) / np.maximum(d - start, 1e-300), 0.0, 1.0)
        down = np.clip((s - d) / np.maximum(length - d, 1e-300), 0.0, 1.0)
        h_drained = np.where(s <= d, h_up + (h_drain - h_up) * up, h_drain + (h_tail - h_drain) * down)
        return np.where(active, h_drained, h)

    def _pressure_at(self, s, elevation, line, strip, h_up, h_tail, tip, cracked, rule):
        """Pore pressure (Pa) at points of distance ``s``, ``elevation``, ``line`` and ``strip``; ``tip``
        (n_strips,) the crack tips (-1: none), ``cracked`` (bool per point) the points in a crack;
        ``rule``: "full_head" or "none" (see the module docstring)."""
        L = self.lines
        h = self._profile(s, L.length[line], h_up[line], h_tail[line], 0.0)
        if tip is not None:
            if rule == "full_head":
                t = tip[strip]
                behind = (t >= 0) & ~cracked
                h = np.where(behind, self._profile(s, L.length[line], h_up[line], h_tail[line], np.maximum(t, 0.0)), h)
                h = np.where(cracked, h_up[line], h)
            else:  # "none": a drained crack
                h = np.where(cracked, -np.inf, h)
        return np.where(L.horizontal[line], self.gamma * np.maximum(h - elevation, 0.0), 0.0)

    def pore_pressure(self, level: float, tail: float | None, trial: bool = True, step=None,
                      rule: str | None = None) -> np.ndarray:
        """Pore pressures for the reservoir ``level`` and tailwater ``tail`` (m; None: no tailwater), with
        the cracks of the joints' trial (or committed) states: at the samples (returned; see
        :meth:`force`) and at the joint points (kept in ``self.pressure``, for the results).

        ``step``: a key of the step attempt being iterated (its load factor). Within one attempt a crack
        that water has entered stays filled (its tip never moves back), so that the fixed-point
        iteration on the pore pressure, which jumps where a point opens, is monotone in the crack's
        extent and cannot cycle between two tips. The next attempt starts from the crack of the
        converged state.

        ``rule``: the crack rule, default the scene's ``cracked``; the dynamic stages pass the
        ``earthquake`` option (:meth:`earthquake_force`)."""
        L, S = self.lines, self.samples
        rule = self.spec["cracked"] if rule is None else rule
        h_up, h_tail = self._heads(level, tail)
        tip = cracked = None
        if rule != "unchanged":
            codes = L.gather([g.result_states(trial=trial) for g in L.groups])
            cracked, tip = L.leading_open(codes == RESULT_OPEN)
            if trial and step is not None:
                if step == self._latch_step:
                    tip = np.maximum(tip, self._latched_tip)
                    cracked = (tip[L.strip] >= 0) & (L.s <= tip[L.strip])
                self._latch_step, self._latched_tip = step, tip
            if not cracked.any():
                tip = cracked = None
        self.pressure = self._pressure_at(L.s, L.elevation, L.line, L.strip, h_up, h_tail, tip, cracked, rule)
        in_crack = None if tip is None else (tip[S["strip"]] >= 0) & (S["s"] <= tip[S["strip"]])
        self.sample_pressure = self._pressure_at(S["s"], S["elevation"], S["line"], S["strip"], h_up, h_tail, tip,
                                                 in_crack, rule)
        return self.sample_pressure

    def earthquake_force(self, level: float, tail: float | None):
        """For the dynamic stages: a function ``() -> (n_dof,)`` N of the pore forces of the committed
        joint states under the scene's ``earthquake`` option ("full_head": full reservoir pressure in
        the parts of a joint open from the heel; "none": none there), or None for "static" (the pore
        forces of the end of the static stages stay, as part of the static load). The dynamic solver
        evaluates it at the start of every step and holds it over the step: the water follows the crack
        one step late (an explicit update: the pore pressure jumps where a point opens, which Newton
        could not differentiate)."""
        rule = self.spec["earthquake"]
        if rule == "static":
            return None
        return lambda: self.force(self.pore_pressure(level, tail, trial=False, rule=rule))

    def force(self, pressure: np.ndarray) -> np.ndarray:
        """Nodal forces (n_dof,) N of the pore pressures ``pressure`` at the samples."""
        return self.matrix @ pressure

    def line_forces(self) -> np.ndarray:
        """Resultant (n_lines,) N of the last computed pore pressures on each line."""
        S = self.samples
        return np.bincount(S["line"], weights=self.sample_pressure * S["weight"], minlength=self.lines.n_lines)

    def group_pressure(self, igroup_index: int) -> np.ndarray | None:
        """The last computed pore pressures of interface group ``igroup_index`` of the model, (n_elem * nip,),
        or None for a group without uplift."""
        if igroup_index not in self.group_index:
            return None
        return self.pressure[self.lines.slices[self.group_index.index(igroup_index)]]


def describe(scene, model) -> list[str]:
    r = scene.get("reservoir")
    if not r or not r.get("uplift"):
        return []
    u = r["uplift"]
    drains = ("no drains" if u["drains"] is None else
              f"drain line {u['drains']['distance']:g} m from the upstream face, efficiency {u['drains']['efficiency']:g}")
    crack = {"full_head": "full reservoir head in cracks from the heel, updated as they grow",
             "unchanged": "cracks keep the intact profile", "none": "no pressure in cracks (drained)"}[u["cracked"]]
    return [f"uplift: pore pressure in joint sets {', '.join(u['joints'])} (effective normal traction in the joint "
            f"law), linear from reservoir to tailwater head, {drains}; {crack} (USBR 1987, USACE EM 1110-2-2200)"]


def _describe_earthquake(scene, model) -> list[str]:
    r = scene.get("reservoir")
    if not r or not r.get("uplift") or not any(st["type"] == "dynamic" for st in scene["stages"]):
        return []
    rule = r["uplift"]["earthquake"]
    words = {"static": "held at its value at the end of the static stages",
             "full_head": "full reservoir pressure entering the joints as they open (updated every step)",
             "none": "no pressure in the parts of the joints that open (updated every step)"}
    return [f"uplift in the dynamic stages: {words[rule]} (CADAM3D options; Leclerc, Leger & Tinawi 2003)"]


def _effects():
    return [Effect("uplift", "[reservoir] uplift = { joints = [...] }", __name__,
                   "USBR Design of Small Dams (1987) sec. 5.7; USACE EM 1110-2-2200 (1995) sec. 3-3, 4-4; FERC "
                   "Engineering Guidelines ch. 3 (2016)", "tests/effects/test_reservoir.py", describe),
            Effect("earthquake_uplift", "[reservoir] uplift.earthquake with a dynamic stage", __name__,
                   "CADAM3D user's manual (Leclerc, Leger & Tinawi 2003) sec. 3.6; FERC Engineering Guidelines ch. 3 "
                   "sec. 3-8.2", "tests/effects/test_earthquake_water.py", _describe_earthquake)]


EFFECTS = _effects()
