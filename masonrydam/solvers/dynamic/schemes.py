"""The time integrators, as one table of schemes.

Every implicit scheme is a member of the generalized-alpha family (Chung & Hulbert 1993, J. Appl. Mech.
60:371-375) with Newmark's updates (Newmark 1959, J. Eng. Mech. Div. ASCE 85(EM3):67-94), given by its four
parameters ``(beta, gamma, alpha_m, alpha_f)``; central difference is the explicit scheme. A scheme's entry
says what the solver, the scene schema, the scene reference and the run summary need to know of it: its
name in a scene, its display name, its parameters (scene keys), whether it is explicit, its stability bound
``Omega_crit = omega h`` (None where unconditionally stable) and the constant of its local error
(Zienkiewicz & Xie 1991). The equations and their references are in docs/dynamics.md.

To add an integrator: a :class:`Scheme` row in :data:`SCHEMES` (an implicit one is its four parameters;
an explicit one also needs its step in :mod:`.explicit`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable


def _newmark_average(alpha: float, rho_inf: float) -> tuple[float, float, float, float]:
    return 0.25, 0.5, 0.0, 0.0


def _newmark_linear(alpha: float, rho_inf: float) -> tuple[float, float, float, float]:
    return 1.0 / 6.0, 0.5, 0.0, 0.0


def _hilber_hughes_taylor(alpha: float, rho_inf: float) -> tuple[float, float, float, float]:
    a = alpha
    return (1.0 - a) ** 2 / 4.0, (1.0 - 2.0 * a) / 2.0, 0.0, -a


def _generalized_alpha(alpha: float, rho_inf: float) -> tuple[float, float, float, float]:
    r = rho_inf
    am, af = (2.0 * r - 1.0) / (r + 1.0), r / (r + 1.0)
    return (1.0 - am + af) ** 2 / 4.0, 0.5 - am + af, am, af


@dataclass(frozen=True)
class Scheme:
    """One time integrator.

    name: its name in a scene (``integrator = "hht"``); label: its display name; parameters: the scene keys of
    its own parameters (``alpha``, ``rho_inf``); explicit: an explicit scheme (lumped mass, no Newton);
    stability_bound: the largest ``Omega = omega_max h`` it is stable for without damping (None:
    unconditionally stable); coefficients: ``(alpha, rho_inf) -> (beta, gamma, alpha_m, alpha_f)`` of an
    implicit scheme, None for an explicit one; reference: where the scheme is defined.
    """

    name: str
    label: str
    parameters: tuple[str, ...]
    explicit: bool
    stability_bound: float | None
    coefficients: Callable[[float, float], tuple[float, float, float, float]] | None
    reference: str

    def parameters_of(self, alpha: float, rho_inf: float) -> tuple[float, float, float, float]:
        """(beta, gamma, alpha_m, alpha_f) with the stage's HHT ``alpha`` and generalized-alpha ``rho_inf``."""
        if self.coefficients is None:
            raise ValueError(f"{self.name} is explicit")
        return self.coefficients(alpha, rho_inf)

    def error_constant(self, alpha: float, rho_inf: float) -> float:
        """``|beta - 1/6|``: the local displacement error of a step is ``h^2 |beta - 1/6| |a_{n+1} - a_n|``
        (Zienkiewicz & Xie 1991, Earthquake Eng. Struct. Dyn. 20:871-887); zero where the scheme is third-order
        accurate in displacement (linear acceleration), where the estimate says nothing."""
        beta = self.parameters_of(alpha, rho_inf)[0]
        return abs(beta - 1.0 / 6.0)


#: the integrators, in the order the scene reference lists them
SCHEMES: tuple[Scheme, ...] = (
    Scheme("newmark_average", "Newmark average acceleration", (), False, None, _newmark_average,
           "Newmark 1959 (trapezoidal rule); Hughes 2000, sec. 9.3"),
    Scheme("newmark_linear", "Newmark linear acceleration", (), False, math.sqrt(12.0), _newmark_linear,
           "Newmark 1959; Hughes 2000, Table 9.1.1"),
    Scheme("hht", "HHT-alpha", ("alpha",), False, None, _hilber_hughes_taylor,
           "Hilber, Hughes & Taylor 1977, Earthquake Eng. Struct. Dyn. 5:283-292"),
    Scheme("generalized_alpha", "generalized-alpha", ("rho_inf",), False, None, _generalized_alpha,
           "Chung & Hulbert 1993, J. Appl. Mech. 60:371-375, eqs. 17, 20 and 25"),
    Scheme("central_difference", "central difference", (), True, 2.0, None,
           "Hughes 2000, sec. 9.1.2; Belytschko, Liu & Moran 2000, Box 6.1"),
)

#: scene names of the integrators
INTEGRATORS: tuple[str, ...] = tuple(s.name for s in SCHEMES)

_BY_NAME = {s.name: s for s in SCHEMES}


def scheme_named(name: str) -> Scheme:
    """The :class:`Scheme` of scene name ``name`` (KeyError if there is none)."""
    return _BY_NAME[name]
