"""Rayleigh damping ``C = alpha M + beta K_el``: :func:`rayleigh_coefficients` and :class:`RayleighDamping`.

Rayleigh damping ``C = a M + b K`` (Chopra, *Dynamics of Structures*, 4th ed. 2012, sec. 11.4.1):
``zeta(omega) = a / (2 omega) + b omega / 2``; the two coefficients give ``zeta`` at ``f1`` and ``f2``:
``a = 2 zeta w1 w2 / (w1 + w2)``, ``b = 2 zeta / (w1 + w2)`` (Chopra eq. 11.4.9 with zeta_i = zeta_j).

``K`` in ``b K`` is constant: the elastic stiffness, by default the continuum stiffness only
(``exclude_joints = True``). Why: the joint penalty stiffnesses kn, ks are chosen huge so that the
joints stay thin; in ``b K`` they give each joint a dashpot ``b kn`` that (1) damps the very high
joint modes heavily, (2) transmits large damping forces through a joint that opens or slides (the
dashpot keeps pulling the blocks together while the joint has no stiffness), i.e. spurious tension
and shear across a crack, and (3) damps the rigid-body-like rocking and sliding of blocks, which in
the structure is resisted by impact and friction, not viscosity. Hall (2006), "Problems encountered
from the use (or misuse) of Rayleigh damping", Earthquake Eng. Struct. Dyn. 35:525-545, shows that
stiffness-proportional damping on stiff elements that soften or open produces such unrealistic damping
forces and recommends bounding them; here they are removed by keeping joints out of ``b K``. The
Rayleigh frequencies should then be those of the structure (blocks on elastic joints) and the
damping ratio of a joint-dominated mode is lower than ``zeta``: a user who wants the joints damped
sets ``exclude_joints = false``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SceneError


def rayleigh_coefficients(f1: float, f2: float, zeta: float) -> tuple[float, float]:
    """Rayleigh coefficients ``(a, b)`` (1/s, s) giving damping ratio ``zeta`` at ``f1`` and ``f2`` (Hz).

    ``C = a M + b K`` with ``a = 2 zeta w1 w2 / (w1 + w2)``, ``b = 2 zeta / (w1 + w2)``, ``w = 2 pi f``
    (Chopra 2012, eq. 11.4.9 with equal ratios at both frequencies).
    """
    for name, v in (("f1", f1), ("f2", f2)):
        if not (np.isfinite(v) and v > 0):
            raise SceneError(f"damping.frequencies ({name})", f"must be a positive frequency in Hz, got {v!r}")
    if not f1 < f2:
        raise SceneError("damping.frequencies", f"need f1 < f2, got [{f1!r}, {f2!r}] Hz")
    if not (np.isfinite(zeta) and 0.0 <= zeta < 1.0):
        raise SceneError("damping.ratio", f"must be in [0, 1), got {zeta!r}")
    w1, w2 = 2.0 * np.pi * f1, 2.0 * np.pi * f2
    return 2.0 * zeta * w1 * w2 / (w1 + w2), 2.0 * zeta / (w1 + w2)


@dataclass
class RayleighDamping:
    """``C = alpha M + beta K_el`` (alpha 1/s, beta s); ``K_el`` = continuum only if ``exclude_joints``."""

    alpha: float = 0.0
    beta: float = 0.0
    exclude_joints: bool = True

    @classmethod
    def from_frequencies(cls, f1: float, f2: float, zeta: float, exclude_joints: bool = True) -> "RayleighDamping":
        a, b = rayleigh_coefficients(f1, f2, zeta)
        return cls(a, b, exclude_joints)

    def ratio(self, f_hz):
        """Damping ratio at frequency ``f_hz`` (Chopra eq. 11.4.8)."""
        w = 2.0 * np.pi * np.asarray(f_hz, dtype=np.float64)
        return self.alpha / (2.0 * w) + self.beta * w / 2.0

    @property
    def active(self) -> bool:
        return self.alpha != 0.0 or self.beta != 0.0


def local_damping_coefficient(zeta: float) -> float:
    """The coefficient ``alpha_L`` of local (non-viscous) damping that gives a linear oscillator the decay of
    damping ratio ``zeta`` per cycle: ``alpha_L = tanh(pi zeta)``.

    Local damping (Cundall 1987, "Distinct element models of rock and soil structure", in *Analytical and
    Computational Methods in Engineering Rock Mechanics*, ch. 4; Itasca, 3DEC manual, "Mechanical damping")
    adds at every DOF the force ``-alpha_L |f_i| sign(v_i)``, with ``f_i`` the force that drives the
    oscillation there. On an oscillator ``m u'' + k u = 0`` the spring force is ``(1 - alpha_L) k u`` while
    the mass moves toward rest and ``(1 + alpha_L) k u`` while it moves away, so energy conservation over each
    quarter cycle gives the amplitude ratio ``(1 - alpha_L) / (1 + alpha_L)`` per cycle, whatever the
    frequency: the logarithmic decrement ``ln((1 + alpha_L)/(1 - alpha_L)) = 2 pi zeta`` holds with
    ``alpha_L = tanh(pi zeta)`` (3DEC's ``alpha_L = pi D`` is its first-order form). Being rate independent,
    it damps every mode by the same ratio and leaves the stable explicit step alone."""
    if not (np.isfinite(zeta) and 0.0 <= zeta < 1.0):
        raise SceneError("damping.ratio", f"must be in [0, 1), got {zeta!r}")
    return float(np.tanh(np.pi * zeta))


def local_damping_ratio(alpha_l: float) -> float:
    """The damping ratio (per-cycle decay of a linear oscillator) of local damping ``alpha_L``: the inverse of
    :func:`local_damping_coefficient`, ``atanh(alpha_L) / pi``."""
    return float(np.arctanh(alpha_l) / np.pi)
