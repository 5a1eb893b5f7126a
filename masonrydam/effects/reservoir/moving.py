"""The reservoir in the dynamic and modal stages: ``[reservoir] dynamic = "westergaard" | "acoustic"``.

What each choice adds (nothing for ``"none"``, today's behaviour: the static water pressure stays on the
face during the earthquake and the water has no inertia):

- ``"westergaard"``: the added mass of :mod:`.added_mass` (7/8 rho sqrt(H z) n n^T) in the mass matrix of
  the dynamic and modal stages;
- ``"acoustic"`` with ``sound_speed = "incompressible"``: the added mass ``rho Q H^-1 Q^T`` of the
  acoustic elements of :mod:`.acoustic` (the exact incompressible solution of the discretised
  reservoir, for any face shape and reservoir length), with the load of the reservoir bottom moving
  with a vertical ground motion;
- ``"acoustic"`` with a sound speed: the compressible reservoir condensed into the dam's implicit step
  (:class:`masonrydam.solvers.dynamic.fluid.AcousticStep`), which keeps the joint-space fast path, or stepped
  with the dam's central difference in an explicit stage
  (:class:`masonrydam.solvers.dynamic.fluid.ExplicitAcoustic`).

In all three the water level is the one the static stages left (the water must be on the dam before
the earthquake), the reservoir depth ``H`` is measured from the lowest point of the wetted face, and the
results get ``hydrodynamic_force`` (the resultant of the hydrodynamic pressure on the dam, N, per unit
thickness in 2D, per step) and ``face_pressure`` (Pa, positive in compression, at the wetted face
nodes, per step). The static water pressure is not part of them (it is in the static loads).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...errors import SceneError
from ...mesh.facets import boundary_owners
from ...solvers.dynamic import AcousticStep
from ..base import Effect
from . import acoustic as ac
from .added_mass import face_nodes, nodal_normals, westergaard_coefficient, westergaard_mass


def _check_on_boundary(mesh, face) -> None:
    """A SceneError naming ``reservoir.face`` unless every facet of the face bounds exactly one element
    (water moving with the dam acts on the model's outer surface only)."""
    on_boundary, _ = boundary_owners(mesh, face.type, face.facets)
    bad = np.flatnonzero(~on_boundary)
    if len(bad):
        f = face.facets[bad[0]]
        raise SceneError("reservoir.face", f"{len(bad)} facet(s) of '{face.name}' are not on the boundary of the model "
                                           f"(inside it, shared by two elements, or on no element), e.g. the facet on "
                                           f"nodes {f.tolist()} at {mesh.points[f].mean(axis=0).round(3).tolist()}: the "
                                           "water can only move against the outer surface of the dam")


class DynamicWater:
    """The dynamic reservoir of a run. ``spec``: the normalised ``[reservoir]`` section; ``reservoir``:
    the run's :class:`~masonrydam.effects.reservoir.water.Reservoir`; ``level``: the water level (m) at the end
    of the static stages; ``thickness``: the 2D out-of-plane thickness (m)."""

    def __init__(self, spec: dict, reservoir, model, level: float, thickness: float, mesh=None):
        self.kind = spec["dynamic"]
        self.spec = spec
        self.model = model
        face = reservoir.face
        self.face = face
        self.level = float(level)
        self.axis = spec["vertical_axis"]
        self.density = spec["density"]
        self.depth = self.level - face.bottom
        if self.depth <= 0.0:
            raise SceneError("reservoir.dynamic", f"the water is not on the dam at the end of the static stages (level "
                                                  f"{self.level:g} m, face bottom {face.bottom:g} m): there is no "
                                                  "reservoir to move with the dam")
        self.thickness = float(thickness)
        if mesh is not None:
            _check_on_boundary(mesh, face)
        coords = model.coords
        #: the wetted face nodes (sorted) where the face pressure is reported, their outward normals
        self.nodes = face_nodes(face.facets, coords, self.level, self.axis)
        self.normals = nodal_normals(coords, face.type, face.facets, face.inward, self.nodes)
        self.acoustic = None
        self.incompressible = False
        self._added = {}
        self.extra_influence = None
        self._fluid_step = None
        if self.kind == "acoustic":
            self._build_acoustic(spec["acoustic"], reservoir)

    # ------------------------------------------------------------------------------------------
    def _build_acoustic(self, a: dict, reservoir):
        m, f = self.model, self.face
        length = a["length"] if a["length"] is not None else 3.0 * self.depth
        c = a["sound_speed"]
        self.incompressible = c == "incompressible"
        h_face = a["element_size"]
        # compressible: 10 elements per wavelength at max_frequency; incompressible: the pressure decays
        # upstream over about 2 H / pi (Westergaard's series), so the elements may grow to H / 4
        h_max = 0.25 * self.depth if self.incompressible else c / (10.0 * a["max_frequency"])
        if h_face is not None and h_max is not None:
            h_max = max(h_max, h_face)
        try:
            self.mesh = ac.build_fluid_mesh(m.coords, f.type, f.facets, f.inward, level=self.level,
                                            vertical_axis=self.axis, upstream=-np.asarray(reservoir.downstream),
                                            length=length, element_size=h_face, max_element_size=h_max)
            self.acoustic = ac.acoustic_matrices(self.mesh, m.coords, f.type, f.facets, f.inward,
                                                 density=self.density, sound_speed=None if self.incompressible else c,
                                                 bottom_reflection=a["bottom_reflection"],
                                                 thickness=self.thickness, vertical_axis=self.axis)
        except ValueError as exc:  # the face or the water level does not admit the reservoir's mesh
            key = "reservoir.level" if "level" in str(exc) else "reservoir.acoustic"
            raise SceneError(key, f"the acoustic reservoir on '{f.name}' cannot be built: {exc}") from None
        self.length = length
        A = self.acoustic
        if self.incompressible:
            self._incompressible_mass = A.added_mass()
            self.extra_influence = A.bottom_influence()

    @property
    def coupled_nodes(self):
        """Nodes whose DOFs the water couples all to all (acoustic: the wetted face), or None."""
        if self.acoustic is None:
            return None
        wet = np.unique(sp.csr_matrix(self.acoustic.Q).nonzero()[0])
        return np.unique(wet // self.model.dim)

    def added_mass(self, lumped: bool):
        """Full-DOF added mass (kg) for the mass matrix, or None (compressible water)."""
        if self.kind == "westergaard":
            if lumped not in self._added:
                f = self.face
                self._added[lumped] = westergaard_mass(self.model.coords, f.type, f.facets, level=self.level,
                                                       reservoir_depth=self.depth, density=self.density,
                                                       vertical_axis=self.axis, thickness=self.thickness,
                                                       lumped=lumped)
            return self._added[lumped]
        if self.incompressible:
            return self._incompressible_mass
        return None

    def fluid_step(self):
        """:class:`~masonrydam.solvers.dynamic.fluid.AcousticStep` of the compressible reservoir, or None."""
        if self.acoustic is None or self.incompressible:
            return None
        if self._fluid_step is None:
            A = self.acoustic
            self._fluid_step = AcousticStep(A.G, A.H, A.L, A.Q, A.B_face, A.B_bottom, self.density)
        return self._fluid_step

    # ------------------------------------------------------------------------------------------
    def _pressure_incompressible(self, a_abs, a_bottom):
        A = self.acoustic
        return -self.density * A.solve_H(A.Q.T @ a_abs + A.B_bottom @ a_bottom)

    def outputs(self, a_abs: np.ndarray, a_bottom: np.ndarray, fluid_state=None, mass=None) -> dict:
        """Step values for the result: ``hydrodynamic_force`` (dim,) N and ``face_pressure`` (n_nodes,) Pa
        from the absolute acceleration ``a_abs`` (n_dof,), the acceleration of the reservoir bottom
        ``a_bottom`` (dim,) and, compressible, the water's state."""
        dim = self.model.dim
        if self.kind == "westergaard":
            M = self.added_mass(mass.lumped if mass is not None else False)
            f = -(M @ a_abs)
            an = np.einsum("nd,nd->n", a_abs.reshape(-1, dim)[self.nodes], self.normals)
            depth = self.level - self.model.coords[self.nodes, self.axis]
            p = westergaard_coefficient(depth, self.depth, self.density) * an
            return {"hydrodynamic_force": f.reshape(-1, dim).sum(axis=0), "face_pressure": p}
        A = self.acoustic
        if self.incompressible:
            p = self._pressure_incompressible(a_abs, a_bottom)
        else:
            p = fluid_state.p if fluid_state is not None else np.zeros(A.Q.shape[1])
        f = A.Q @ p
        at = np.searchsorted(A.face_nodes, self.nodes)
        return {"hydrodynamic_force": f.reshape(-1, dim).sum(axis=0), "face_pressure": A.face_pressure(p)[at]}

    def describe(self) -> str:
        if self.kind == "westergaard":
            return (f"Westergaard added mass 7/8 rho sqrt(H z) n n^T on '{self.face.name}' (H = {self.depth:g} m)")
        A = self.acoustic
        what = ("incompressible water: added mass rho Q H^-1 Q^T" if self.incompressible else
                f"compressible water (c = {self.spec['acoustic']['sound_speed']:g} m/s) stepped with the dam")
        return (f"acoustic reservoir of {A.G.shape[0]} pressure unknowns, {self.length:g} m long, on "
                f"'{self.face.name}' (H = {self.depth:g} m): {what}; bottom reflection "
                f"{self.spec['acoustic']['bottom_reflection']:g}, Sommerfeld far end")


def describe(scene, model) -> list[str]:
    r = scene.get("reservoir")
    if not r or r["dynamic"] == "none":
        return []
    if r["dynamic"] == "westergaard":
        return [f"reservoir in the dynamic and modal stages: Westergaard added mass 7/8 rho sqrt(H z) n n^T on "
                f"'{r['face']}' (Westergaard 1933; Kuo 1982)"]
    a = r["acoustic"]
    c = a["sound_speed"]
    if c == "incompressible":
        what = "incompressible water (added mass rho Q H^-1 Q^T)"
    else:  # how the dynamic stages step it: condensed into an implicit step, or explicitly with the dam
        integrators = {st.get("integrator") for st in scene.get("stages", []) if st.get("type") == "dynamic"}
        how = [w for w, used in (("condensed into the implicit step", bool(integrators - {"central_difference"})),
                                 ("stepped explicitly with the dam", "central_difference" in integrators)) if used]
        what = f"compressible water, c = {c:g} m/s, " + (" or ".join(how) or "condensed into the implicit step")
    return [f"reservoir in the dynamic and modal stages: acoustic elements on '{r['face']}', {what}, bottom "
            f"reflection {a['bottom_reflection']:g}, Sommerfeld radiation at the far end (Zienkiewicz & Bettess "
            "1978; Fenves & Chopra 1984)"]


def _effects():
    return [Effect("dynamic_water", "[reservoir] dynamic = \"westergaard\" | \"acoustic\"", __name__,
                   "Westergaard 1933, Trans. ASCE 98; Kuo 1982, UCB/EERC-82/10; Zienkiewicz & Bettess 1978, IJNME 13; "
                   "Fenves & Chopra 1984, EESD 12", "tests/effects/test_added_mass.py, tests/effects/test_acoustic.py, "
                   "tests/effects/test_acoustic_explicit.py",
                   describe)]


EFFECTS = _effects()
