"""Tied supports (``[[supports]] kind = "tied"``: a set whose nodes share one displacement in some components,
free to translate together, e.g. a loading beam kept level) and scene-key overrides (``masonrydam run
--set KEY=VALUE``).

The tie is a penalty (masonrydam.assembly.model.Model.add_tie); it is checked against the exact solution of
the same constrained problem by elimination of the tied DOFs onto one master DOF (Cook et al., Concepts and
Applications of Finite Element Analysis, 4th ed., 2002, sec. 9.2, multipoint constraints by transformation),
and against the closed form of a block under a level rigid loading beam (uniform uniaxial stress for
Poisson's ratio 0: top displacement P H / (E A)).
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import SceneError
from masonrydam.scene import build_mesh, build_model
from masonrydam.scene.scene import Scene, parse_assignment, set_key

E, W, H, P = 10e9, 1.0, 2.0, 1.0e5


def block(tie=True, load_set="right"):
    """A W x H block (plane stress, thickness 1 m, nu = 0) fixed at its base, its top tied in y, loaded by
    vertical forces -P at every node of ``load_set`` (eccentric: the right edge)."""
    supports = [{"set": "base", "components": ["x", "y"]}]
    if tie:
        supports.append({"set": "top", "components": ["y"], "kind": "tied"})
    return {"model": {"name": "tie", "thickness": 1.0, "gravity": [0.0, 0.0]},
            "mesh": {"generator": "blocks_2d", "parameters": {"element_size": 0.25, "blocks": [
                {"x0": 0, "y0": 0, "x1": W, "y1": H, "group": "a"}]}},
            "materials": {"a": {"youngs_modulus": E, "poisson_ratio": 0.0, "density": 0.0}},
            "supports": supports,
            "stages": [{"name": "load", "steps": 1, "loads": [
                {"type": "nodal", "set": load_set, "force": [0.0, -P]}]}]}


@pytest.mark.slow
def test_tie_matches_the_exact_constrained_solution():
    ds = masonrydam.run(block())
    sc = Scene(block(tie=False))
    mesh = build_mesh(sc.normalized, sc.base_dir)
    model = build_model(sc.normalized, mesh)
    K = model.K_continuum.tocsr()
    n = model.n_dof
    f = np.zeros(n)
    f[mesh.node_sets["right"] * 2 + 1] = -P
    fixed = np.zeros(n, bool)
    fixed[mesh.node_sets["base"] * 2] = fixed[mesh.node_sets["base"] * 2 + 1] = True
    tied = mesh.node_sets["top"] * 2 + 1
    tied = tied[~fixed[tied]]
    # u = T q: the free DOFs other than the tied ones, and one master for the tied y DOFs
    others = np.flatnonzero(~fixed & ~np.isin(np.arange(n), tied))
    rows = np.concatenate([others, tied])
    cols = np.concatenate([np.arange(len(others)), np.full(len(tied), len(others))])
    T = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, len(others) + 1))
    q = spla.spsolve((T.T @ K @ T).tocsc(), T.T @ f)
    exact = (T @ q).reshape(-1, 2)
    got = ds.displacement.values[-1]
    assert np.abs(got - exact).max() <= 1e-4 * np.abs(exact).max()
    top_y = got[mesh.node_sets["top"], 1]
    assert np.ptp(top_y) <= 1e-4 * np.abs(top_y).max()
    # without the tie the eccentric load tilts the top
    free = masonrydam.run(block(tie=False)).displacement.values[-1][mesh.node_sets["top"], 1]
    assert np.ptp(free) > 0.1 * np.abs(free).max()


def test_level_beam_closed_form_and_free_translation():
    """Loaded on its whole top (uniform forces), nu = 0: the tie changes nothing, u_top = P n H / (E A); the
    tie also lets the tied set translate together (it is no support)."""
    ds = masonrydam.run(block(load_set="top"))
    sc = Scene(block())
    n_top = len(build_mesh(sc.normalized, sc.base_dir).node_sets["top"])
    top = ds.y.values > H - 1e-9
    u = ds.displacement.sel(component="y").values[-1, top]
    assert u.mean() == pytest.approx(-P * n_top * H / (E * W), rel=1e-6)
    assert ds.reaction.sel(component="y").values[-1].sum() == pytest.approx(P * n_top, rel=1e-9)


def test_tie_on_large_kinematics_blocks():
    """Large kinematics blocks are not in the linear stiffness: the tie's penalty comes from their initial elastic
    stiffness, so the top still stays level (a zero penalty would let it tilt freely)."""
    s = block()
    s["model"]["kinematics"] = "large"
    ds = masonrydam.run(s)
    top_y = ds.displacement.sel(component="y").values[-1][ds.y.values > H - 1e-9]
    assert np.ptp(top_y) <= 1e-4 * np.abs(top_y).max()


def test_bad_tie_input_is_named():
    s = block()
    s["supports"][1]["kind"] = "glued"
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "supports[1].kind"
    s = block()
    s["supports"][1]["set"] = "nowhere"
    with pytest.raises(SceneError) as err:
        masonrydam.run(s)
    assert err.value.key == "supports[1].set"


def test_set_key_and_assignment_parsing():
    data = {"stages": [{"loads": [{"type": "self_weight"}, {"type": "edge_pressure", "pressure": "0.30 MPa"}]}]}
    set_key(data, *parse_assignment("stages[0].loads[1].pressure = 1.21 MPa"))
    set_key(data, *parse_assignment("solver.max_iterations=50"))
    set_key(data, *parse_assignment('model.name="x"'))
    set_key(data, *parse_assignment("stages[0].loads[0].factor=[1, 2]"))
    assert data["stages"][0]["loads"][1]["pressure"] == "1.21 MPa"
    assert data["solver"]["max_iterations"] == 50 and data["model"]["name"] == "x"
    assert data["stages"][0]["loads"][0]["factor"] == [1, 2]
    set_key(data, *parse_assignment("joints.bed-joints.cohesion=1"))  # TOML bare keys may hold '-'
    assert data["joints"]["bed-joints"]["cohesion"] == 1
    for bad, key in (("stages[3].steps=2", "stages[3].steps"), ("solver..x=1", "solver..x"),
                     ("stages.steps=2", "stages.steps"), ("solver[0].x=1", "solver[0].x")):
        with pytest.raises(SceneError) as err:
            set_key(data, *parse_assignment(bad))
        assert err.value.key == key
    with pytest.raises(SceneError) as err:
        parse_assignment("no_equals_sign")
    assert err.value.key == "--set"


BLOCK_TOML = """
[model]
name = "block"
thickness = 1.0
gravity = [0.0, 0.0]
[mesh]
generator = "blocks_2d"
[mesh.parameters]
element_size = 0.5
blocks = [{x0 = 0, y0 = 0, x1 = 1, y1 = 2, group = "a"}]
[materials.a]
youngs_modulus = 10e9
poisson_ratio = 0.0
[[supports]]
set = "base"
components = ["x", "y"]
[[stages]]
name = "load"
[[stages.loads]]
type = "nodal"
set = "top"
force = [0.0, -1e5]
"""


def test_cli_set_changes_the_run(tmp_path, capsys):
    import json

    import xarray as xr

    path = tmp_path / "block.toml"
    path.write_text(BLOCK_TOML)
    out = tmp_path / "b.nc"
    runs = {}
    for modulus in ("10e9", "20e9"):
        assert main(["run", str(path), "-o", str(out), "--no-progress", "--set",
                     f"materials.a.youngs_modulus={modulus}"]) == 0
        with xr.open_dataset(out) as ds:
            assert json.loads(ds.attrs["scene"])["materials"]["a"]["youngs_modulus"] == float(modulus)
            runs[modulus] = ds.displacement.values[-1].copy()
    np.testing.assert_allclose(runs["20e9"], runs["10e9"] / 2, rtol=1e-9, atol=1e-18)
    assert main(["run", str(path), "-o", str(out), "--no-progress", "--set", "stages[5].steps=1"]) != 0
    assert "stages[5].steps" in capsys.readouterr().err
