"""The compiled loads and constant part of an implicit step (masonrydam.solvers.dynamic.kernels.step_loads and
step_constant) against the numpy expressions they replaced, bit for bit, signs of zeros included: the
Newmark-family step of Chung & Hulbert (1993, J. Appl. Mech. 60:371-375) whose constant part is

    const = -p1 + am/(1 - af) M a_n + af/(1 - af) ((C v_n + f_int(u_n)) - p_n)

for the trapezoidal rule (am = af = 0), HHT (am = 0, af = alpha) and generalized-alpha (both nonzero), with a
lumped and with a consistent mass. The datasets of whole runs did not change with these kernels (benchmarks/
regression_datasets.py on the dynamic examples); these tests keep the kernels to the expressions' order of
operations, which is what makes that so."""
from __future__ import annotations

import numpy as np
import pytest

from masonrydam.solvers.dynamic.kernels import step_constant, step_loads
from masonrydam.solvers.dynamic.stage import StepState


def bits(x):
    return np.ascontiguousarray(x, dtype=np.float64).view(np.uint64)


def vectors(rng, n, count):
    """Vectors whose entries span many magnitudes, with zeros of both signs (where sums round and where the
    sign of a zero shows)."""
    out = []
    for _ in range(count):
        v = rng.standard_normal(n) * 10.0 ** rng.uniform(-8, 8, n)
        v[rng.random(n) < 0.1] = 0.0
        v[rng.random(n) < 0.1] = -0.0
        out.append(v)
    return out


def test_step_loads_are_numpys_sums_in_numpys_order():
    rng = np.random.default_rng(7)
    n = 500
    static, g1, gn, sf = vectors(rng, n, 4)
    p1, pn, pg1, pg0 = (np.empty(n) for _ in range(4))
    step_loads(static, g1, gn, sf, p1, pn, pg1, pg0)
    assert np.array_equal(bits(p1), bits(static + g1 + sf))
    assert np.array_equal(bits(pn), bits(static + gn + sf))
    assert np.array_equal(bits(pg1), bits(g1 + sf))
    assert np.array_equal(bits(pg0), bits(gn + sf))


@pytest.mark.parametrize("am, af", [(0.0, 0.0), (0.0, 0.05), (-0.2, 0.15)],
                         ids=["trapezoidal", "hht", "generalized_alpha"])
@pytest.mark.parametrize("lumped", [True, False], ids=["lumped", "consistent"])
def test_step_constant_is_the_numpy_expression(am, af, lumped):
    rng = np.random.default_rng(11)
    n, n_dof = 400, 430
    free = np.sort(rng.choice(n_dof, n, replace=False)).astype(np.int64)
    p1, pn, an, cv_n, mass = vectors(rng, n, 5)
    mass = np.abs(mass)
    f_int = vectors(rng, n_dof, 1)[0]
    ma_n = vectors(rng, n, 1)[0]  # a consistent mass's product, from the caller
    const = np.empty(n)
    step_constant(p1, pn, mass if lumped else np.zeros(0), ma_n, an, am / (1.0 - af), cv_n, f_int, free,
                  af / (1.0 - af), const)
    expected = -p1
    if am != 0.0:
        expected = expected + (am / (1.0 - af)) * (mass * an if lumped else ma_n)
    if af != 0.0:
        expected = expected + (af / (1.0 - af)) * (cv_n + f_int[free] - pn)
    assert np.array_equal(bits(const), bits(expected))


def test_a_state_gathers_its_free_values_once_and_keeps_the_steps_own():
    """StepState.free_values: the free-DOF values of u, v, a; the ones the step that made the state kept
    (keep_free_values) are returned as they are, the others gathered once; another free set gathers again."""
    rng = np.random.default_rng(3)
    u, v, a = (rng.standard_normal(12) for _ in range(3))
    st = StepState(0.0, 0.0, u, v, a, np.zeros(12), None, np.zeros(2))
    free = np.array([1, 2, 5, 7, 11])
    v_kept = v[free].copy()
    st.keep_free_values(free, v_kept, None)
    uf, vf, af = st.free_values(free)
    assert vf is v_kept
    assert np.array_equal(uf, u[free]) and np.array_equal(af, a[free])
    assert st.free_values(free)[0] is uf  # gathered once
    other = np.array([0, 3])
    assert np.array_equal(st.free_values(other)[1], v[other])
