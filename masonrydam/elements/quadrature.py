"""Quadrature rules on reference elements.

All rules return ``(points, weights)`` with ``points`` of shape ``(n_points, dim_ref)``
and ``weights`` of shape ``(n_points,)`` in the element's natural coordinates.

Reference domains: line and quadrilateral/hexahedron on ``[-1, 1]^d``; triangle on the unit
simplex ``{xi >= 0, eta >= 0, xi + eta <= 1}`` (area 1/2); tetrahedron on the unit simplex
``{xi, eta, zeta >= 0, xi + eta + zeta <= 1}`` (volume 1/6).

Schemes for interfaces (Schellekens & de Borst 1993, IJNME 36, 43-66):

- ``"gauss"``: Gauss-Legendre, exact for polynomials of degree ``2n-1``;
- ``"lobatto"`` (alias ``"newton-cotes"``): Gauss-Lobatto points, which for the ``n`` equal to the
  number of nodes along an edge coincide with the nodes (2 points: trapezoid, 3 points: Simpson);
- ``"lumped"``: nodal integration, one point at each node with the weight equal to the integral of
  that node's shape function (row sum of the consistent matrix).
"""
from __future__ import annotations

import numpy as np

QUADRATURE_SCHEMES = ("gauss", "lobatto", "newton-cotes", "lumped")


def gauss_legendre_1d(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre rule with ``n`` points on [-1, 1]: points (n,), weights (n,)."""
    if n < 1:
        raise ValueError(f"Gauss-Legendre rule needs at least 1 point, got {n}")
    x, w = np.polynomial.legendre.leggauss(n)
    return x.astype(np.float64), w.astype(np.float64)


def gauss_lobatto_1d(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Lobatto rule with ``n >= 2`` points on [-1, 1], end points included.

    Interior points are the roots of P'_{n-1}; weights 2 / (n (n-1) P_{n-1}(x)^2)
    (Abramowitz & Stegun 25.4.32).
    """
    if n < 2:
        raise ValueError(f"Gauss-Lobatto rule needs at least 2 points, got {n}")
    p = np.polynomial.legendre.Legendre.basis(n - 1)
    interior = np.sort(p.deriv().roots().real) if n > 2 else np.zeros(0)
    x = np.concatenate(([-1.0], interior, [1.0]))
    w = 2.0 / (n * (n - 1) * p(x) ** 2)
    return x.astype(np.float64), w.astype(np.float64)


def line_rule(scheme: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """1D rule on [-1, 1] as ``(points (n, 1), weights (n,))``."""
    if scheme == "gauss":
        x, w = gauss_legendre_1d(n)
    elif scheme in ("lobatto", "newton-cotes"):
        x, w = gauss_lobatto_1d(n)
    else:
        raise ValueError(f"unknown line quadrature scheme {scheme!r}; use one of {QUADRATURE_SCHEMES}")
    return x[:, None], w


def tensor_rule(scheme: str, n: int, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Tensor-product rule on [-1, 1]^dim: points (n**dim, dim), weights (n**dim,).

    The first coordinate varies fastest.
    """
    x, w = line_rule(scheme, n)
    x = x[:, 0]
    grids = np.meshgrid(*([x] * dim), indexing="ij")
    wgrids = np.meshgrid(*([w] * dim), indexing="ij")
    pts = np.stack([g.ravel(order="F") for g in grids], axis=1)
    wts = np.prod(np.stack([g.ravel(order="F") for g in wgrids], axis=1), axis=1)
    return pts.astype(np.float64), wts.astype(np.float64)


def triangle_rule(n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric triangle rules on the unit simplex (weights sum to 1/2).

    1 point (degree 1), 3 points (degree 2, Strang & Fix), 6 points (degree 4, Dunavant 1985).
    """
    if n_points == 1:
        return np.array([[1 / 3, 1 / 3]]), np.array([0.5])
    if n_points == 3:
        p = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
        return p, np.full(3, 1 / 6)
    if n_points == 6:
        a, b = 0.445948490915965, 0.091576213509771
        wa, wb = 0.223381589678011 / 2, 0.109951743655322 / 2
        p = np.array([[a, a], [1 - 2 * a, a], [a, 1 - 2 * a], [b, b], [1 - 2 * b, b], [b, 1 - 2 * b]])
        return p, np.array([wa, wa, wa, wb, wb, wb])
    raise ValueError(f"no triangle rule with {n_points} points (use 1, 3 or 6)")


def collapsed_triangle_rule(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Collapsed (Duffy) Gauss rule on the unit triangle ``{xi, eta >= 0, xi + eta <= 1}``.

    ``(xi, eta) = (u, v (1 - u))`` with ``u, v`` the ``n``-point Gauss-Legendre points on [0, 1] and the
    weight ``w_u w_v (1 - u)``; exact for polynomials of total degree ``2 n - 2`` (a monomial
    ``xi^a eta^b`` becomes ``u^a (1 - u)^(b + 1) v^b``; Stroud, *Approximate Calculation of Multiple
    Integrals*, 1971; Karniadakis & Sherwin, *Spectral/hp Element Methods*, 2nd ed. 2005, sec. 4.1.1).
    Returns points (n*n, 2) and weights (n*n,) summing to 1/2. All points are interior, all weights
    positive.
    """
    x, w = gauss_legendre_1d(n)
    t, wt = 0.5 * (x + 1.0), 0.5 * w
    u, v = np.meshgrid(t, t, indexing="ij")
    wu, wv = np.meshgrid(wt, wt, indexing="ij")
    pts = np.stack([u.ravel(), (v * (1.0 - u)).ravel()], axis=1)
    return pts, (wu * wv * (1.0 - u)).ravel()


def _tet_orbit_31(a: float) -> np.ndarray:
    """The 4 points with volume coordinates (a, a, a, 1 - 3a) and permutations: (4, 3)."""
    L = np.full((4, 4), a)
    L[np.arange(4), np.arange(4)] = 1.0 - 3.0 * a
    return L[:, 1:]


def _tet_orbit_22(b: float) -> np.ndarray:
    """The 6 points with volume coordinates (b, b, 1/2 - b, 1/2 - b) and permutations: (6, 3)."""
    pairs = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
    L = np.full((6, 4), b)
    for r, (i, j) in enumerate(pairs):
        L[r, [i, j]] = 0.5 - b
    return L[:, 1:]


def tetrahedron_rule(n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric rules on the unit tetrahedron (weights sum to 1/6), all weights positive.

    - 1 point (degree 1): the centroid.
    - 4 points (degree 2): volume coordinates (a, a, a, 1 - 3a), ``a = (5 - sqrt 5) / 20``, weights
      1/24 (Zienkiewicz, Taylor & Zhu 2013, ch. 6, table of tetrahedron rules; Keast 1986).
    - 14 points (degree 5): two (a, a, a, 1 - 3a) orbits and one (b, b, 1/2 - b, 1/2 - b) orbit
      (N. Walkington, "Quadrature on simplices of arbitrary dimension", CNA report, Carnegie Mellon
      Univ. 2000; A. Jaskowiec & N. Sukumar, "High-order cubature rules for tetrahedra", Int. J.
      Numer. Methods Eng. 121 (2020) 2418-2436). The digits below solve the six symmetric moment
      equations of degree <= 5 to machine precision (checked in tests/elements/test_solid3d.py against
      ``int xi^a eta^b zeta^c = a! b! c! / (a + b + c + 3)!``). Exact for ``N_a N_b`` of tet10 (degree 4),
      so it is the rule for the consistent tet10 mass matrix.

    Returns ``points`` (n, 3) and ``weights`` (n,).
    """
    if n_points == 1:
        return np.array([[0.25, 0.25, 0.25]]), np.array([1.0 / 6.0])
    if n_points == 4:
        a = (5.0 - np.sqrt(5.0)) / 20.0
        return _tet_orbit_31(a), np.full(4, 1.0 / 24.0)
    if n_points == 14:
        a1, w1 = 0.0927352503108912, 0.01224884051939366
        a2, w2 = 0.3108859192633006, 0.01878132095300264
        b, w3 = 0.0455037041256496, 0.00709100346284691
        pts = np.vstack([_tet_orbit_31(a1), _tet_orbit_31(a2), _tet_orbit_22(b)])
        w = np.concatenate([np.full(4, w1), np.full(4, w2), np.full(6, w3)])
        return np.ascontiguousarray(pts), w
    raise ValueError(f"no tetrahedron rule with {n_points} points (use 1, 4 or 14)")
