"""Linear isotropic elasticity (Hooke's law) in Voigt notation.

Strain vectors use engineering shear strains (``docs/architecture.md``):

- 2D: ``[exx, eyy, gxy]`` -> stresses ``[sxx, syy, sxy]``;
- 3D: ``[exx, eyy, ezz, gxy, gyz, gzx]`` -> ``[sxx, syy, szz, sxy, syz, szx]``.

References
----------
- O.C. Zienkiewicz, R.L. Taylor, J.Z. Zhu, *The Finite Element Method: Its Basis and Fundamentals*,
  7th ed., Butterworth-Heinemann 2013, sections 6.2 (plane stress / plane strain, eqs. 6.12-6.15)
  and 6.7 (three-dimensional isotropic elasticity).
- R.D. Cook, D.S. Malkus, M.E. Plesha, R.J. Witt, *Concepts and Applications of Finite Element
  Analysis*, 4th ed., Wiley 2002, section 1.7 (eqs. 1.7-3 to 1.7-5).
"""
from __future__ import annotations

import math

import numpy as np

HYPOTHESES = ("plane_stress", "plane_strain", "3d")


def _check_parameters(youngs_modulus, poisson_ratio) -> tuple[float, float]:
    try:
        E = float(youngs_modulus)
    except (TypeError, ValueError):
        raise ValueError(f"youngs_modulus must be a positive number (Pa), got {youngs_modulus!r}") from None
    try:
        nu = float(poisson_ratio)
    except (TypeError, ValueError):
        raise ValueError(f"poisson_ratio must be a number in (-1, 0.5), got {poisson_ratio!r}") from None
    if not (math.isfinite(E) and E > 0.0):
        raise ValueError(f"youngs_modulus must be finite and > 0 (Pa), got {youngs_modulus!r}")
    if not (math.isfinite(nu) and -1.0 < nu < 0.5):
        raise ValueError(
            f"poisson_ratio must satisfy -1 < poisson_ratio < 0.5 (strictly; 0.5 is incompressible), "
            f"got {poisson_ratio!r}"
        )
    return E, nu


def elasticity_matrix(youngs_modulus: float, poisson_ratio: float, hypothesis: str) -> np.ndarray:
    """Isotropic linear elastic constitutive matrix ``D`` with ``sigma = D @ eps``.

    Parameters
    ----------
    youngs_modulus : float
        Young's modulus ``E`` in Pa, finite and > 0.
    poisson_ratio : float
        Poisson's ratio ``nu``, strictly in (-1, 0.5). The incompressible limit 0.5 is rejected
        for every hypothesis (``D`` is singular or infinite there).
    hypothesis : {"plane_stress", "plane_strain", "3d"}
        Kinematic / stress hypothesis.

    Returns
    -------
    ndarray, float64, C-contiguous
        ``(3, 3)`` for the 2D hypotheses (strain ``[exx, eyy, gxy]``), ``(6, 6)`` for ``"3d"``
        (strain ``[exx, eyy, ezz, gxy, gyz, gzx]``); units Pa.

        - plane stress (``szz = 0``): ``E/(1-nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1-nu)/2]]``;
        - plane strain (``ezz = 0``): ``E/((1+nu)(1-2nu)) [[1-nu, nu, 0], [nu, 1-nu, 0],
          [0, 0, (1-2nu)/2]]`` (``szz = nu (sxx + syy)`` is not part of the vector);
        - 3D: Lame form, ``lambda = E nu/((1+nu)(1-2nu))``, ``G = E/(2(1+nu))``; normal block
          ``lambda + 2G`` on the diagonal, ``lambda`` off-diagonal, ``G`` for the shear terms.

        (Zienkiewicz, Taylor & Zhu 2013, sec. 6.2 and 6.7; Cook et al. 2002, sec. 1.7.)

    Raises
    ------
    ValueError
        naming the parameter and the offending value.
    """
    E, nu = _check_parameters(youngs_modulus, poisson_ratio)
    if hypothesis == "plane_stress":
        c = E / (1.0 - nu * nu)
        D = c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 0.5 * (1.0 - nu)]])
    elif hypothesis == "plane_strain":
        c = E / ((1.0 + nu) * (1.0 - 2.0 * nu))
        D = c * np.array([[1.0 - nu, nu, 0.0], [nu, 1.0 - nu, 0.0], [0.0, 0.0, 0.5 * (1.0 - 2.0 * nu)]])
    elif hypothesis == "3d":
        lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
        G = E / (2.0 * (1.0 + nu))
        D = np.zeros((6, 6))
        D[:3, :3] = lam
        D[[0, 1, 2], [0, 1, 2]] = lam + 2.0 * G
        D[[3, 4, 5], [3, 4, 5]] = G
    else:
        raise ValueError(f"hypothesis must be one of {HYPOTHESES}, got {hypothesis!r}")
    return np.ascontiguousarray(D, dtype=np.float64)
