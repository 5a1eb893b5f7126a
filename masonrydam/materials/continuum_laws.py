"""Continuum (block) laws as descriptors: what the rest of masonrydam needs to know about the law of
``[materials.<group>] law = ...``, in one place.

A :class:`ContinuumLaw` gives the law's kernel id (the branch of
:func:`masonrydam.elements.continuum_plastic.continuum_plastic_evaluate`), the size of its state row per Gauss
point, its scene keys with their defaults, the parameter row it builds from a normalised material table,
the key and column of the hardening modulus that a softening regularisation scales per element, and the
run summary's words. The schema (:mod:`masonrydam.effects.plasticity`, the plasticity effect's fragment),
the element groups and the scene reference read these; none tests a law by name.

Laws (in this order): ``elastic`` (:mod:`masonrydam.materials.elastic`; no state, no kernel of its own: the
linear stiffness), ``von_mises``, ``drucker_prager``, ``tresca``, ``mohr_coulomb`` (the solid's, not the
joints'): implicit return mapping with a consistent tangent and optional Perzyna viscosity (Simo & Hughes
1998, *Computational Inelasticity*; de Souza Neto, Peric & Owen 2008, *Computational Methods for
Plasticity*, ch. 7-8, 11). A new law is a point kernel with the signature of
:func:`~masonrydam.materials.von_mises.von_mises_point`, a branch of the element kernel and a descriptor here.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..checks import choice, number, positive
from ..errors import SceneError
from . import drucker_prager, mohr_coulomb_solid, tresca, von_mises

#: the elastic law's name (the default of ``[materials.<group>] law``)
ELASTIC_LAW = "elastic"


@dataclass(frozen=True)
class ContinuumLaw:
    """What masonrydam knows of one continuum law.

    name: the value of ``[materials.<group>] law``; title: the law in messages ("von Mises"); keys: the law's
    own scene keys and their defaults (SI, angles in degrees; None: required, or optional where the schema says
    so); kernel_id: the law branch of :func:`~masonrydam.elements.continuum_plastic.continuum_plastic_evaluate`
    (None: the elastic law, no plastic kernel); state_size: columns of a Gauss point's state row (0: none);
    parameters: ``(material, hardening) -> (n_params,) float64``, the parameter row of a normalised material
    table (``youngs_modulus``, ``poisson_ratio`` and the law's keys) with the hardening modulus ``hardening``
    (Pa; the table's, or one scaled by an element's size); ValueError in words that name the key;
    hardening_key / hardening_column: the key and the parameter column of that modulus (negative: softening);
    summary: ``(material) -> str``, the law in the run summary; reference: the books and sections.
    """

    name: str
    title: str
    keys: dict
    kernel_id: int | None
    state_size: int
    parameters: Callable[[dict, float], np.ndarray] | None
    hardening_key: str | None
    hardening_column: int | None
    summary: Callable[[dict], str]
    reference: str

    @property
    def plastic(self) -> bool:
        """An elasto-plastic law (evaluated by the plastic element kernel at every iteration)."""
        return self.kernel_id is not None


def _von_mises_row(m, h):
    return von_mises.von_mises_params(m["youngs_modulus"], m["poisson_ratio"], m["yield_stress"], h,
                                      m["kinematic_hardening"], m["residual_yield_stress"], m["viscosity"])


def _drucker_prager_row(m, h):
    return drucker_prager.drucker_prager_params(m["youngs_modulus"], m["poisson_ratio"], m["cohesion"],
                                                m["friction_angle"], m["dilation_angle"], h, m["residual_cohesion"],
                                                m["viscosity"], m["match"])


def _tresca_row(m, h):
    return tresca.tresca_params(m["youngs_modulus"], m["poisson_ratio"], m["yield_stress"], h,
                                m["residual_yield_stress"], m["viscosity"])


def _mohr_coulomb_row(m, h):
    return mohr_coulomb_solid.mohr_coulomb_solid_params(m["youngs_modulus"], m["poisson_ratio"], m["cohesion"],
                                                        m["friction_angle"], m["dilation_angle"], h,
                                                        m["residual_cohesion"], m["viscosity"])


_PLASTICITY = ("implicit return mapping and consistent tangent (Simo & Hughes 1998, Computational Inelasticity; "
               "de Souza Neto, Peric & Owen 2008, Computational Methods for Plasticity")

ELASTIC = ContinuumLaw(
    name=ELASTIC_LAW, title="elastic", keys={}, kernel_id=None, state_size=0, parameters=None,
    hardening_key=None, hardening_column=None, summary=lambda m: "linear elastic",
    reference="Zienkiewicz, Taylor & Zhu 2013, The Finite Element Method, sec. 6.2, 6.7 "
              "(masonrydam.materials.elastic)")

VON_MISES = ContinuumLaw(
    name="von_mises", title="von Mises",
    keys={"yield_stress": None, "isotropic_hardening": 0.0, "kinematic_hardening": 0.0, "viscosity": 0.0,
          "residual_yield_stress": 0.0, "regularisation_length": None},
    kernel_id=1, state_size=von_mises.N_VM_STATE, parameters=_von_mises_row,
    hardening_key="isotropic_hardening", hardening_column=von_mises.P_H_ISO,
    summary=lambda m: f"von Mises, yield stress {m['yield_stress']:g} Pa",
    reference=_PLASTICITY + ", ch. 7) (masonrydam.materials.von_mises)")

DRUCKER_PRAGER = ContinuumLaw(
    name="drucker_prager", title="Drucker-Prager",
    keys={"cohesion": None, "friction_angle": None, "dilation_angle": None, "cohesion_hardening": 0.0,
          "viscosity": 0.0, "match": "plane_strain", "residual_cohesion": 0.0, "regularisation_length": None},
    kernel_id=2, state_size=drucker_prager.N_DP_STATE, parameters=_drucker_prager_row,
    hardening_key="cohesion_hardening", hardening_column=drucker_prager.P_COHESION_HARDENING,
    summary=lambda m: (f"Drucker-Prager ({m['match'].replace('_', ' ')} match), c {m['cohesion']:g} Pa, phi "
                       f"{m['friction_angle']:g} deg"),
    reference=_PLASTICITY + ", sec. 8.3) (masonrydam.materials.drucker_prager)")

TRESCA = ContinuumLaw(
    name="tresca", title="Tresca",
    keys={"yield_stress": None, "isotropic_hardening": 0.0, "viscosity": 0.0, "residual_yield_stress": 0.0,
          "regularisation_length": None},
    kernel_id=3, state_size=tresca.N_TRESCA_STATE, parameters=_tresca_row,
    hardening_key="isotropic_hardening", hardening_column=tresca.P_H_ISO,
    summary=lambda m: f"Tresca, yield stress {m['yield_stress']:g} Pa",
    reference=_PLASTICITY + ", sec. 8.1) (masonrydam.materials.tresca)")

MOHR_COULOMB = ContinuumLaw(
    name="mohr_coulomb", title="Mohr-Coulomb",
    keys={"cohesion": None, "friction_angle": None, "dilation_angle": None, "cohesion_hardening": 0.0,
          "viscosity": 0.0, "residual_cohesion": 0.0, "regularisation_length": None},
    kernel_id=4, state_size=mohr_coulomb_solid.N_MC_STATE, parameters=_mohr_coulomb_row,
    hardening_key="cohesion_hardening", hardening_column=mohr_coulomb_solid.P_COHESION_HARDENING,
    summary=lambda m: (f"Mohr-Coulomb, c {m['cohesion']:g} Pa, phi {m['friction_angle']:g} deg (principal-space "
                       "return: plane, edges, apex)"),
    reference=_PLASTICITY + ", sec. 8.2) (masonrydam.materials.mohr_coulomb_solid)")

_LAWS = {law.name: law for law in (ELASTIC, VON_MISES, DRUCKER_PRAGER, TRESCA, MOHR_COULOMB)}


def continuum_laws() -> tuple:
    """The continuum laws, elastic first."""
    return tuple(_LAWS.values())


def continuum_law(name: str) -> ContinuumLaw:
    """The law ``name``; ValueError naming the laws otherwise."""
    try:
        return _LAWS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown continuum law {name!r}; laws: {list(_LAWS)}") from None


# -- the law keys of a material table ([materials.<group>]) --------------------------------------------------

#: continuum laws of ``[materials.<group>] law`` and their own keys (with defaults; None: required), from the
#: descriptors above
CONTINUUM_LAWS = {law.name: dict(law.keys) for law in continuum_laws()}
#: keys that may be absent (None: not given)
_OPTIONAL_LAW_KEYS = ("dilation_angle", "regularisation_length")


def material_law(d, key) -> dict:
    """The elasto-plastic part of a material (``law`` and its parameters; SI, angles in degrees)."""
    law = choice(d.get("law", ELASTIC_LAW), tuple(CONTINUUM_LAWS), f"{key}.law")
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
            out[k] = positive(v, "stress", f"{key}.{k}", allow_zero=(k == "cohesion"))
        elif k in ("residual_yield_stress", "residual_cohesion"):
            out[k] = positive(v, "stress", f"{key}.{k}", allow_zero=True)
        elif k == "regularisation_length":
            out[k] = positive(v, "length", f"{key}.{k}")
        elif k in ("isotropic_hardening", "kinematic_hardening", "cohesion_hardening"):
            out[k] = number(v, f"{key}.{k}")
            if out[k] < 0.0 and k == "kinematic_hardening":
                raise SceneError(f"{key}.{k}", f"must be >= 0 (Pa), got {v!r}")
            if out[k] < 0.0 and "regularisation_length" not in d:
                raise SceneError(f"{key}.{k}", f"{v!r} is softening: a softening continuum needs a regularisation "
                                               "length (regularisation_length, m: the element size this softening "
                                               "modulus holds for; each element's modulus is scaled by its size so "
                                               "that the fracture energy does not depend on the mesh); or use a "
                                               "hardening modulus >= 0")
        elif k == "viscosity":
            out[k] = number(v, f"{key}.{k}")
            if out[k] < 0.0:
                raise SceneError(f"{key}.{k}", f"the Perzyna viscosity (Pa s) must be >= 0, got {v!r}")
        elif k in ("friction_angle", "dilation_angle"):
            out[k] = number(v, f"{key}.{k}", 0.0, 89.9)
        else:  # match
            out[k] = choice(v, ("plane_strain", "outer", "inner"), f"{key}.{k}")
    return out
