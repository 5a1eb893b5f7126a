"""Elasto-plastic and elasto-viscoplastic blocks (the continuum nonlinearity of Tzamtzis & Asteris): the effect
``[materials.<group>] law = "von_mises" | "tresca" | "drucker_prager" | "mohr_coulomb"``.

The laws are descriptors (:mod:`masonrydam.materials.continuum_laws`: their keys, read by
:func:`~masonrydam.materials.continuum_laws.material_law`, and parameter rows); a group's parameter table
(one row, or one per element for a softening modulus scaled by the element size) is
:func:`masonrydam.elements.continuum_plastic.law_parameter_table`. This module gives the run's summary
lines, the reference and the tests (:data:`EFFECTS`; docs/continuum_nonlinearity.md).
"""
from __future__ import annotations

from ..materials.continuum_laws import continuum_law
from .base import Effect


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
    return [Effect("plasticity", "[materials.<group>] law = \"von_mises\" | \"tresca\" | \"drucker_prager\" | "
                                 "\"mohr_coulomb\" (with viscosity: Perzyna)", __name__,
                   "implicit return mapping and consistent tangent (Simo & Hughes 1998, Computational Inelasticity; "
                   "de Souza Neto, Peric & Owen 2008, Computational Methods for Plasticity, ch. 7-8, 11); crack-band "
                   "regularisation of softening (Bazant & Oh 1983)",
                   "tests/elements/test_continuum_plasticity.py, tests/elements/test_plastic_structures.py, tests/materials/test_von_mises.py, "
                   "tests/materials/test_tresca.py, tests/materials/test_drucker_prager.py, tests/materials/test_mohr_coulomb_solid.py", _describe)]


EFFECTS = _effects()
