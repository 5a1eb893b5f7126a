"""Elasto-plastic and elasto-viscoplastic blocks (issue 17; the seed's continuum nonlinearity): the effect
``[materials.<group>] law = "von_mises" | "tresca" | "drucker_prager" | "mohr_coulomb"``.

Schema fragment: :data:`CONTINUUM_LAWS` and :func:`material_law` (the law's keys of a material table);
model contribution: :func:`law_params`, the parameter table of a group (one row, or one per element
for a softening modulus scaled by the element size) for the element kernel
:mod:`masonrydam.elements.continuum_plastic` and the point laws of :mod:`masonrydam.materials`;
reference and tests: :data:`EFFECTS` (docs/continuum_nonlinearity.md).
"""
from __future__ import annotations

import numpy as np

from ..checks import choice as _choice
from ..checks import number as _number
from ..checks import positive as _positive
from ..errors import SceneError
from ..materials.continuum_laws import ELASTIC_LAW, continuum_law, continuum_laws

#: continuum laws of ``[materials.<group>] law`` and their own keys (with defaults; None: required), from the
#: laws' descriptors (:mod:`masonrydam.materials.continuum_laws`)
CONTINUUM_LAWS = {law.name: dict(law.keys) for law in continuum_laws()}
#: keys that may be absent (None: not given)
_OPTIONAL_LAW_KEYS = ("dilation_angle", "regularisation_length")


def material_law(d, key) -> dict:
    """The elasto-plastic part of a material (``law`` and its parameters; SI, angles in degrees)."""
    law = _choice(d.get("law", ELASTIC_LAW), tuple(CONTINUUM_LAWS), f"{key}.law")
    spec = CONTINUUM_LAWS[law]
    for k in d:
        if k in {kk for other in CONTINUUM_LAWS.values() for kk in other} and k not in spec:
            raise SceneError(f"{key}.{k}", f"is a parameter of another law; law is \"{law}\"")
    out = {"law": law}
    for k, default in spec.items():
        if k not in d:
            if default is None and k not in _OPTIONAL_LAW_KEYS:
                raise SceneError(f"{key}.{k}", f"is required for law = \"{law}\"")
            out[k] = default
            continue
        v = d[k]
        if k in ("yield_stress", "cohesion"):
            out[k] = _positive(v, "stress", f"{key}.{k}", allow_zero=(k == "cohesion"))
        elif k in ("residual_yield_stress", "residual_cohesion"):
            out[k] = _positive(v, "stress", f"{key}.{k}", allow_zero=True)
        elif k == "regularisation_length":
            out[k] = _positive(v, "length", f"{key}.{k}")
        elif k in ("isotropic_hardening", "kinematic_hardening", "cohesion_hardening"):
            out[k] = _number(v, f"{key}.{k}")
            if out[k] < 0.0 and k == "kinematic_hardening":
                raise SceneError(f"{key}.{k}", f"must be >= 0 (Pa), got {v!r}")
            if out[k] < 0.0 and "regularisation_length" not in d:
                raise SceneError(f"{key}.{k}", f"{v!r} is softening: a softening continuum needs a regularisation "
                                               "length (regularisation_length, m: the element size this softening "
                                               "modulus holds for; each element's modulus is scaled by its size so "
                                               "that the fracture energy does not depend on the mesh); or use a "
                                               "hardening modulus >= 0")
        elif k == "viscosity":
            out[k] = _number(v, f"{key}.{k}")
            if out[k] < 0.0:
                raise SceneError(f"{key}.{k}", f"the Perzyna viscosity (Pa s) must be >= 0, got {v!r}")
        elif k in ("friction_angle", "dilation_angle"):
            out[k] = _number(v, f"{key}.{k}", 0.0, 89.9)
        else:  # match
            out[k] = _choice(v, ("plane_strain", "outer", "inner"), f"{key}.{k}")
    return out



def element_sizes(coords: np.ndarray, conn: np.ndarray, type_name: str) -> np.ndarray:
    """Characteristic length of each element (ne,) m: the square root of its area (2D) or the cube root of
    its volume (3D), the crack-band width of a softening element (Bazant & Oh 1983, Mater. Struct. 16)."""
    from ..elements.continuum import element_tables

    _, dN, w = element_tables(type_name)
    J = np.einsum("gin,enj->egij", dN, coords[conn])
    size = np.einsum("g,eg->e", w, np.abs(np.linalg.det(J)))
    return size ** (1.0 / coords.shape[1])


def law_params(m: dict, name: str, dim: int, hypothesis: str, coords=None, conn=None, type_name=None):
    """The parameter table of an elasto-plastic material, None for an elastic one: one row (1, P), or one
    row per element (ne, P) when a softening modulus is regularised by the element size (crack band:
    ``H_e = H l_e / regularisation_length`` keeps the energy dissipated per unit area of a localised band
    independent of the mesh; Bazant & Oh 1983; Pietruszczak & Mroz 1981, IJNME 17, for plasticity)."""
    law = continuum_law(m.get("law", ELASTIC_LAW))
    if not law.plastic:
        return None
    key = f"materials.{name}"
    if dim == 2 and hypothesis != "plane_strain":
        raise SceneError(f"{key}.law", f"\"{law.name}\" needs plane strain in 2D ([model] hypothesis = "
                                       f"\"plane_strain\"; the laws keep the out-of-plane stress), got {hypothesis!r}")
    soft_key, column = law.hardening_key, law.hardening_column

    def row(h, where=""):
        try:
            r = law.parameters(m, h)
        except ValueError as exc:
            raise SceneError(key if not where else f"{key}.{soft_key}", str(exc) + where) from None
        return np.asarray(r, dtype=np.float64)

    h = m[soft_key]
    base = row(h)
    length = m.get("regularisation_length")
    if length is None or h >= 0.0 or conn is None:
        return np.ascontiguousarray(base.reshape(1, -1))
    sizes = element_sizes(coords, conn, type_name)
    big = int(np.argmax(sizes))
    # the steepest softening is that of the largest element: it must not snap back within the element
    row(h * sizes[big] / length, f" (element {big} of '{name}', size {sizes[big]:.4g} m, scaled from "
                                 f"regularisation_length = {length:g} m: refine the mesh there, or soften less)")
    table = np.repeat(base.reshape(1, -1), len(conn), axis=0)
    table[:, column] = h * sizes / length
    return np.ascontiguousarray(table)


def _describe(scene: dict, model) -> list[str]:
    out = []
    for g in model.cgroups:
        if g.plastic:
            mat = scene["materials"][g.name]
            what = continuum_law(g.law).summary(mat)
            if mat.get("viscosity", 0.0) > 0.0:
                what += f", Perzyna viscosity {mat['viscosity']:g} Pa s"
            if mat.get("regularisation_length") is not None:
                what += (f", softening regularised by the element size (crack band, l_ref = "
                         f"{mat['regularisation_length']:g} m)")
            out.append(f"elasto-plastic continuum '{g.name}': {what}, implicit return mapping, consistent tangent "
                       "(Simo & Hughes 1998; de Souza Neto et al. 2008)")
    return out


def _effects():
    from . import Effect

    return [Effect("plasticity", "[materials.<group>] law = \"von_mises\" | \"tresca\" | \"drucker_prager\" | "
                                 "\"mohr_coulomb\" (with viscosity: Perzyna)", __name__,
                   "implicit return mapping and consistent tangent (Simo & Hughes 1998, Computational Inelasticity; "
                   "de Souza Neto, Peric & Owen 2008, Computational Methods for Plasticity, ch. 7-8, 11); crack-band "
                   "regularisation of softening (Bazant & Oh 1983)",
                   "tests/test_continuum_plasticity.py, tests/test_plastic_structures.py, tests/test_von_mises.py, "
                   "tests/test_tresca.py, tests/test_drucker_prager.py, tests/test_mohr_coulomb_solid.py", _describe)]


EFFECTS = _effects()
