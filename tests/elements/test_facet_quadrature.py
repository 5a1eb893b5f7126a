"""The one facet quadrature (masonrydam.elements.shapes.facet_rule / facet_quadrature) against closed forms.

On a flat facet with straight sides (an affine image of the reference facet, quadratic facets with their
mid-side nodes at the middle) the Jacobian is constant, so a rule exact to degree 2 integrates a linear
and a quadratic pressure exactly. The closed forms used here do not come from Gauss rules: the centroid
rule for a linear field (exact on segments, triangles and parallelograms), Simpson's rule on a segment and
the edge-midpoint rule on a triangle for a quadratic field (both exact to degree 2 and 3 / 2; a
parallelogram is split into two triangles).
"""
from __future__ import annotations

import numpy as np
import pytest

from masonrydam.elements.shapes import FacetQuadrature, facet_quadrature, facet_rule, reference_nodes

RULES = [(2, "collapsed"), (3, "collapsed"), (8, "collapsed"), (2, "symmetric"), (3, "symmetric")]
FACET_TYPES = ("line2", "line3", "tri3", "tri6", "quad4", "quad8", "quad9")
REFERENCE_MEASURE = {"line": 2.0, "tri": 0.5, "quad": 4.0}


def _family(facet_type):
    return facet_type[:-1] if facet_type[-1].isdigit() else facet_type


def linear_pressure(x):
    """Pa at points x (..., dim): a + b . x."""
    b = np.array([1.3e3, -2.1e3, 0.7e3])[: x.shape[-1]]
    return 4.0e4 + x @ b


def quadratic_pressure(x):
    """Pa at points x (..., dim): a hydrostatic-like square plus a cross term."""
    d = 12.0 - x[..., -1]
    return 9.81e3 * d**2 + 500.0 * x[..., 0] * x[..., -1]


def tilted_facet(facet_type):
    """One flat, tilted facet with straight sides: (corners (nc, dim), nodes (1, nfn, dim), unit normal
    by the right-hand rule (3D) or the tangent turned by -90 degrees (2D))."""
    ref = reference_nodes(facet_type)
    if _family(facet_type) == "line":
        origin, edge = np.array([1.0, 2.0]), np.array([3.0, 4.0])  # a 5 m edge at 53 degrees
        X = origin + (ref[:, :1] + 1.0) / 2.0 * edge
        normal = np.array([edge[1], -edge[0]]) / 5.0
        return X[:2], X[None], normal
    origin = np.array([0.5, -1.0, 2.0])
    e1, e2 = np.array([2.0, 0.5, 1.0]), np.array([-0.5, 1.5, 2.0])
    if _family(facet_type) == "quad":
        X = origin + (ref[:, :1] + 1.0) / 2.0 * e1 + (ref[:, 1:] + 1.0) / 2.0 * e2
    else:
        X = origin + ref[:, :1] * e1 + ref[:, 1:] * e2
    n = np.cross(e1, e2)
    corners = X[: 3 if _family(facet_type) == "tri" else 4]
    return corners, X[None], n / np.linalg.norm(n)


def _triangle_integrals(a, b, c, f):
    """(area, integral of f) on the triangle abc: edge-midpoint rule, exact for quadratics."""
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a))
    return area, area / 3.0 * (f((a + b) / 2) + f((b + c) / 2) + f((c + a) / 2))


def closed_form(corners, f, quadratic):
    """Measure and integral of ``f`` over the flat facet with these corners (2: segment, 3: triangle,
    4: parallelogram)."""
    if len(corners) == 2:
        a, b = corners
        L = np.linalg.norm(b - a)
        if not quadratic:
            return L, L * f((a + b) / 2)
        return L, L / 6.0 * (f(a) + 4.0 * f((a + b) / 2) + f(b))
    if not quadratic:
        c = corners.mean(axis=0)
        if len(corners) == 3:
            area = 0.5 * np.linalg.norm(np.cross(corners[1] - corners[0], corners[2] - corners[0]))
        else:
            area = np.linalg.norm(np.cross(corners[1] - corners[0], corners[3] - corners[0]))
        return area, area * f(c)
    if len(corners) == 3:
        return _triangle_integrals(*corners, f)
    a1, i1 = _triangle_integrals(corners[0], corners[1], corners[2], f)
    a2, i2 = _triangle_integrals(corners[0], corners[2], corners[3], f)
    return a1 + a2, i1 + i2


@pytest.mark.parametrize("facet_type", FACET_TYPES)
@pytest.mark.parametrize("points_per_direction,triangle", RULES)
def test_rule_weights_sum_to_the_reference_measure(facet_type, points_per_direction, triangle):
    pts, w = facet_rule(facet_type, points_per_direction, triangle)
    family = _family(facet_type)
    assert pts.shape == (len(w), 1 if family == "line" else 2)
    assert w.sum() == pytest.approx(REFERENCE_MEASURE[family], rel=1e-14)
    assert (w > 0).all()
    if family == "tri":
        expected = points_per_direction**2 if triangle == "collapsed" else {2: 3, 3: 6}[points_per_direction]
    else:
        expected = points_per_direction ** (1 if family == "line" else 2)
    assert len(w) == expected


@pytest.mark.parametrize("facet_type", FACET_TYPES)
@pytest.mark.parametrize("points_per_direction,triangle", RULES)
@pytest.mark.parametrize("quadratic", [False, True])
def test_pressure_on_a_tilted_facet_is_integrated_exactly(facet_type, points_per_direction, triangle, quadratic):
    corners, X, normal = tilted_facet(facet_type)
    f = quadratic_pressure if quadratic else linear_pressure
    pts, w = facet_rule(facet_type, points_per_direction, triangle)
    fq = facet_quadrature(facet_type, X, pts, w)
    q = len(w)
    assert isinstance(fq, FacetQuadrature)
    assert fq.points.shape == (1, q, X.shape[-1]) and fq.jacobian.shape == (1, q)
    assert fq.shape_values.shape == (q, X.shape[1])
    measure, integral = closed_form(corners, f, quadratic)
    assert np.sum(fq.jacobian * fq.weights) == pytest.approx(measure, rel=1e-13)
    assert np.sum(f(fq.points) * fq.jacobian * fq.weights) == pytest.approx(integral, rel=1e-12)
    # the force of the pressure along the facet's normal, and the normal itself
    unit = fq.area_normal / fq.jacobian[..., None]
    np.testing.assert_allclose(unit[0], np.broadcast_to(normal, unit[0].shape), atol=1e-14)
    force = np.einsum("nq,nqd,q->d", f(fq.points), fq.area_normal, fq.weights)
    np.testing.assert_allclose(force, integral * normal, rtol=1e-12, atol=1e-9 * abs(integral))
    # the shape functions interpolate the points (partition of unity)
    np.testing.assert_allclose(fq.shape_values.sum(axis=1), 1.0, atol=1e-14)


@pytest.mark.parametrize("facet_type", FACET_TYPES)
def test_points_on_their_own_facets_match_the_shared_rule(facet_type):
    """``owner``: each point on its own facet gives the same numbers as the rule shared by all facets."""
    _, X, _ = tilted_facet(facet_type)
    X = np.concatenate([X, 2.0 * X + 1.0])  # two facets
    pts, w = facet_rule(facet_type, 3)
    shared = facet_quadrature(facet_type, X, pts, w)
    owner = np.repeat(np.arange(2), len(w))
    own = facet_quadrature(facet_type, X, np.tile(pts, (2, 1)), np.tile(w, 2), owner=owner)
    np.testing.assert_array_equal(own.points, shared.points.reshape(-1, X.shape[-1]))
    np.testing.assert_array_equal(own.area_normal, shared.area_normal.reshape(-1, X.shape[-1]))
    np.testing.assert_array_equal(own.jacobian, shared.jacobian.ravel())


def test_facet_rule_refuses_what_it_has_not():
    with pytest.raises(ValueError, match="not a facet type"):
        facet_rule("hex8", 2)
    with pytest.raises(ValueError, match="symmetric triangle rule"):
        facet_rule("tri3", 4, triangle="symmetric")
    with pytest.raises(ValueError, match="triangle must be"):
        facet_rule("tri6", 2, triangle="duffy")
