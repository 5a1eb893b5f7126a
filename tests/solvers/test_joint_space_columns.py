"""The joint flexibility computed column by column when a step first needs it (large joint sets).

Above ``JOINT_SPACE_MAX`` joint unknowns the dense flexibility ``S = B K_ref^-1 B^T`` (8 m^2 bytes) is
not set up; :class:`~masonrydam.solvers.joint_space.FlexibilityColumns` computes the columns that an
iteration reads and keeps them in a bounded store. These tests check that the columns are those of
``S``, that the store evicts the columns used longest ago and refuses a step that needs more than it
holds, and that runs with the store give the histories of the dense flexibility and the closed form
of Newmark's (1965) sliding block, also when the store is too small to keep every column (the
oldest are evicted and computed again) or too small for a step (the step goes on in the general
Newton path).
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import masonrydam
from masonrydam.solvers.joint_space import condensation as js_module
from masonrydam.solvers.static import stepping as static_module
from masonrydam.solvers.joint_space import ColumnStoreFull, FlexibilityColumns
from repository_paths import EXAMPLES
from scenes import sliding_block  # Newmark (1965): a block on a joint with mu = 0.2, a 0.2 s pulse

G = 9.80665


class _DenseSolve:
    """``solve(b)`` with a dense matrix (numpy), for a small test matrix."""

    def __init__(self, K):
        self.K = K

    def solve(self, b):
        return np.linalg.solve(self.K, b)


def _random_flexibility(n=30, m=12, seed=3):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    B = sp.random(m, n, density=0.2, random_state=seed, format="csr") + sp.eye(m, n, format="csr")
    S = B.toarray() @ np.linalg.solve(K, B.toarray().T)
    return _DenseSolve(K), B.tocsr(), S


def test_columns_are_those_of_the_flexibility_and_the_oldest_are_evicted(monkeypatch):
    """Lazy store of 5 columns of a 12 x 12 flexibility (no fetching ahead): a column asked for equals
    ``B K^-1 B^T e_j``; a full store makes room by evicting the column used longest ago (never one of
    the current step); a step that needs more columns than the store holds raises ColumnStoreFull."""
    monkeypatch.setattr(js_module, "PREFETCH_COLUMNS", 0)
    fact, B, S = _random_flexibility()
    cols = FlexibilityColumns(fact, B, B.T.tocsc(), capacity=5, lazy=True)
    assert cols.capacity == 5 and (cols.slot < 0).all()

    def column(j):
        return cols.ST[cols.slot[j]]

    cols.new_step()
    cols.ensure(np.array([3, 7, 3]))
    assert cols.computed == 2
    for j in (3, 7):
        np.testing.assert_allclose(column(j), S[:, j], rtol=1e-12, atol=1e-14 * np.abs(S).max())
    cols.new_step()
    cols.ensure(np.array([1, 2, 4]))
    assert cols.n_free == 0
    cols.new_step()
    cols.ensure(np.array([7, 9]))  # 7 is stored (and now used in this step); 9 evicts 3, the oldest
    assert cols.slot[3] == -1 and cols.slot[7] >= 0 and cols.computed == 6
    np.testing.assert_allclose(column(9), S[:, 9], rtol=1e-12, atol=1e-14 * np.abs(S).max())
    for j in (1, 2, 4, 7):  # the others are untouched
        np.testing.assert_allclose(column(j), S[:, j], rtol=1e-12, atol=1e-14 * np.abs(S).max())
    cols.new_step()
    with pytest.raises(ColumnStoreFull, match="more than 5 columns"):
        cols.ensure(np.arange(6))
    # a dense store computes every column at once and never computes more
    dense = FlexibilityColumns(fact, B, B.T.tocsc(), capacity=1, lazy=False)
    np.testing.assert_array_equal(dense.slot, np.arange(12))
    np.testing.assert_allclose(dense.ST, S.T, rtol=1e-12, atol=1e-14 * np.abs(S).max())
    dense.ensure(np.arange(12))
    assert dense.computed == 0


def test_a_small_fetch_brings_the_neighbours_which_stay_evictable(monkeypatch):
    """A fetch of fewer than PREFETCH_COLUMNS columns is filled up with the nearest columns not stored
    (the next points along the joint); those are exact columns too, and a later need of the same
    step may evict them (they are not counted as the step's own)."""
    monkeypatch.setattr(js_module, "PREFETCH_COLUMNS", 3)
    fact, B, S = _random_flexibility()
    cols = FlexibilityColumns(fact, B, B.T.tocsc(), capacity=5, lazy=True)
    cols.new_step()
    cols.ensure(np.array([5]))
    assert sorted(np.flatnonzero(cols.slot >= 0)) == [4, 5, 6]  # 5 and its nearest neighbours
    for j in (4, 5, 6):
        np.testing.assert_allclose(cols.ST[cols.slot[j]], S[:, j], rtol=1e-12, atol=1e-14 * np.abs(S).max())
    cols.ensure(np.array([0, 11]))  # fills the store; no room left to fetch ahead
    assert cols.n_free == 0 and cols.computed == 5
    cols.ensure(np.array([9]))  # same step: evicts a column fetched ahead (4 or 6), never 0, 5 or 11
    assert all(cols.slot[j] >= 0 for j in (0, 5, 9, 11))
    assert (cols.slot[4] < 0) != (cols.slot[6] < 0)


def _slip(ds):
    top = np.nonzero(np.isclose(ds.y.values, 0.75))[0]
    return -ds.displacement.sel(component="x").isel(node=top).mean(axis=1).values


@pytest.mark.reference
def test_lazy_columns_give_the_dense_history_and_newmark_slip(monkeypatch):
    """The sliding block (every step of the pulse slides) with the columns of S computed when first
    needed (JOINT_SPACE_MAX lowered to 0) gives the history of the dense flexibility to round-off and
    Newmark's permanent slip s = A t_p^2 (A - a_y) / (2 a_y), a_y = mu g, within 0.05 %; the run
    reports the columns it computed (static and dynamic), fewer than the joint unknowns' m each."""
    dense = masonrydam.run(sliding_block())
    monkeypatch.setattr(js_module, "JOINT_SPACE_MAX", 0)
    lazy = masonrydam.run(sliding_block())
    a = lazy.attrs
    m = int(a["dynamic_joint_space_size"])
    assert int(dense.attrs["dynamic_joint_space_flexibility_columns"]) == 0
    assert 0 < int(a["dynamic_joint_space_flexibility_columns"]) <= m
    assert int(a["dynamic_joint_space_steps"]) == int(a["dynamic_steps"])
    assert int(a["dynamic_joint_space_fallbacks"]) == 0 and int(a["dynamic_factorizations"]) == 1
    s_dense, s_lazy = _slip(dense), _slip(lazy)
    np.testing.assert_allclose(s_lazy, s_dense, rtol=0, atol=1e-9 * np.abs(s_dense).max())
    A, tp, ay = 0.4 * G, 0.2, 0.2 * G
    assert s_lazy[-1] == pytest.approx(A * tp**2 * (A - ay) / (2 * ay), rel=5e-4)


def test_a_store_smaller_than_the_joint_set_evicts_and_keeps_the_history(monkeypatch):
    """A store with room for 24 of the sliding block's 32 columns (a sliding step reads its 16 shear
    components and fetches neighbours ahead): columns are evicted (more are computed than the store
    holds), every step is still solved in joint space, and the history is the dense flexibility's
    to round-off."""
    dense = masonrydam.run(sliding_block())
    monkeypatch.setattr(js_module, "JOINT_SPACE_MAX", 0)
    m = int(dense.attrs["dynamic_joint_space_size"])
    capacity = 24
    assert m > capacity
    monkeypatch.setattr(js_module, "FLEXIBILITY_MEMORY_MAX", capacity * 8 * m)
    small = masonrydam.run(sliding_block())
    a = small.attrs
    assert int(a["dynamic_joint_space_flexibility_columns"]) > capacity  # the store was full and evicted
    assert int(a["dynamic_joint_space_steps"]) == int(a["dynamic_steps"])
    assert int(a["dynamic_joint_space_store_full"]) == 0
    s_dense = _slip(dense)
    np.testing.assert_allclose(_slip(small), s_dense, rtol=0, atol=1e-9 * np.abs(s_dense).max())


def test_a_store_too_small_for_a_step_hands_it_to_the_general_path(monkeypatch):
    """With room for 4 columns (the sliding block's steps need about 30) no sliding step can be solved
    in joint space: each goes on in the general Newton path (not halved: a large joint set has no
    joint space at sub-step sizes), never a failed run, and the slip is still Newmark's within 0.05 %;
    the sticking steps after the pulse stay in joint space (they read no column)."""
    monkeypatch.setattr(js_module, "JOINT_SPACE_MAX", 0)
    probe = masonrydam.run(sliding_block(duration=0.002))
    m = int(probe.attrs["dynamic_joint_space_size"])
    monkeypatch.setattr(js_module, "FLEXIBILITY_MEMORY_MAX", 4 * 8 * m)
    ds = masonrydam.run(sliding_block(duration=0.6))  # the block slides until about 0.4 s
    a = ds.attrs
    assert str(a["completed"]) == "true"
    assert int(a["dynamic_joint_space_fallbacks"]) > 0 and int(a["dynamic_newton_iterations"]) > 0
    assert int(a["dynamic_joint_space_store_full"]) == int(a["dynamic_joint_space_fallbacks"])
    assert int(a["dynamic_joint_space_splits"]) == 0
    assert 0 < int(a["dynamic_joint_space_steps"]) < int(a["dynamic_steps"])
    A, tp, ay = 0.4 * G, 0.2, 0.2 * G
    assert _slip(ds)[-1] == pytest.approx(A * tp**2 * (A - ay) / (2 * ay), rel=5e-4)


@pytest.mark.slow
def test_static_steps_with_lazy_columns_reach_the_dense_state(monkeypatch):
    """The 3D dam example (coarse: element_size 20) under self-weight, where contraction-joint points
    slide and open: static steps solved in joint space with the columns computed when first needed
    end in the state of the dense flexibility (same joint states, displacements to 1e-9)."""
    import tomllib
    from pathlib import Path

    sc = tomllib.loads((EXAMPLES / "dam_3d_gravity.toml").read_text())
    sc["mesh"]["parameters"]["element_size"] = 20.0
    dense = masonrydam.run(sc)
    monkeypatch.setattr(js_module, "JOINT_SPACE_MAX", 0)
    monkeypatch.setattr(static_module, "STATIC_COLUMNS_MIN_EQUATIONS", 0)  # the coarse model is small
    lazy = masonrydam.run(sc)
    monkeypatch.setattr(static_module, "STATIC_COLUMNS_MIN_EQUATIONS", 10**9)
    general = masonrydam.run(sc)
    assert int(general.attrs["joint_space_size"]) == 0  # too small for columns: the general path
    assert int(lazy.attrs["joint_space_flexibility_columns"]) > 0
    assert int(dense.attrs["joint_space_flexibility_columns"]) == 0
    assert int(lazy.attrs["joint_space_steps"]) == int(dense.attrs["joint_space_steps"]) > 0
    u_d, u_l = dense.displacement.values, lazy.displacement.values
    np.testing.assert_allclose(u_l, u_d, rtol=0, atol=1e-9 * np.abs(u_d).max())
    states = [v for v in dense.data_vars if v.endswith("state")]
    assert states
    for v in states:
        np.testing.assert_array_equal(lazy[v].values, dense[v].values)
    codes = np.concatenate([dense[v].values[-1].ravel() for v in states])
    assert (codes != 0).any(), "some joint points leave the stick state"
