"""Central difference with Westergaard's added mass on a curved face (masonrydam/solvers/dynamic/explicit.py,
``node_mass_blocks``): lumped at the nodes of an arch's extrados, ``m_a n n^T`` couples the x and y DOFs of
each wet node, and the explicit step solves a small block per node instead of dividing by a diagonal.

Checks, on a small linear arch (sticking joints) with the reservoir at its crest under 0.1 s of two horizontal
components of El Centro 1940:

- the explicit history equals the implicit trapezoidal rule's (Newmark average acceleration) with the same
  lumped mass at the same step: both are second-order accurate (Hughes 2000, sec. 9.1), so at a step far below
  the periods that matter they agree to a small fraction of the response (measured: 0.074 % of the crest's peak;
  with the diagonals of the blocks alone, i.e. the x-y coupling of the water dropped, 7.4 %);
- the energy balance of the explicit run closes to round-off with the blocks' kinetic energy and inertia work;
- the blocks are those of the lumped matrix and are inverted exactly, and a consistent added mass (coupling
  the DOFs of different nodes) is refused by the block split.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import masonrydam
from generators.arch_dams import arch_dam_3d
from masonrydam.effects.reservoir.added_mass import westergaard_mass
from masonrydam.solvers.dynamic.explicit import node_mass_blocks

PARAMS = dict(height=8.0, crest_radius=12.0, central_angle_deg=100.0, crest_thickness=3.0, n_monoliths=2,
              element_size=1.5)
LINEAR = {"law": "linear", "normal_stiffness": 1e11, "shear_stiffness": 1e11}


def scene(integrator, dt):
    ground = {c: {"record": r, "scale_to_pga": "0.3 g", "processing": [{"step": "trim"}]} for c, r in (("y", "elcentro_1940_ns_ngaw2"),
                                                                     ("x", "elcentro_1940_ew_ngaw2"))}
    return {"model": {"name": "arch_blocks", "dimension": 3},
            "mesh": {"generator": "arch_dam_3d", "parameters": {**PARAMS, "reservoir_level": PARAMS["height"]}},
            "materials": {"dam": {"youngs_modulus": 25e9, "poisson_ratio": 0.2, "density": 2400.0}},
            "joints": {"contraction_joints": dict(LINEAR)},
            "reservoir": {"level": PARAMS["height"], "face": "upstream_face", "dynamic": "westergaard"},
            "supports": [{"set": "base"}],
            "stages": [{"name": "water", "loads": [{"type": "reservoir"}]},
                       {"name": "shaking", "type": "dynamic", "integrator": integrator, "dt": dt, "duration": 0.1,
                        "ground_motion": ground, "output": {"dt": 0.005, "nodes": ["crest"]}}]}


def crest_history(ds):
    """(step, 2) m: the crest nodes' mean x and y displacement over the shaking, from the static state."""
    names = __import__("json").loads(ds.stage.attrs["stage_names"])
    dyn = np.nonzero(ds.stage.values == names.index("shaking"))[0]
    u = ds.displacement.values[dyn][:, :, :2].mean(axis=1)
    return u - u[0]


def test_node_blocks_of_the_lumped_westergaard_mass_on_an_arch():
    mesh = arch_dam_3d(**PARAMS, reservoir_level=PARAMS["height"])
    wet = mesh.facet_sets["upstream_wet"]
    Ma = westergaard_mass(mesh.points, wet.type, wet.facets, level=8.0, reservoir_depth=8.0, density=1000.0,
                          vertical_axis=2, lumped=True)
    free = np.arange(3 * mesh.n_nodes)
    blocks = node_mass_blocks(Ma + sp.identity(3 * mesh.n_nodes), free, 3)
    assert blocks, "the curved face couples x and y at its nodes"
    idx, Mb, Minv = blocks[0]
    assert np.allclose(np.einsum("bij,bjk->bik", Mb, Minv), np.eye(idx.shape[1]))
    # off the crown the x-y coupling is there; each block is symmetric
    assert np.abs(Mb[:, 0, 1]).max() > 0 and np.allclose(Mb, np.transpose(Mb, (0, 2, 1)))
    consistent = westergaard_mass(mesh.points, wet.type, wet.facets, level=8.0, reservoir_depth=8.0,
                                  density=1000.0, vertical_axis=2, lumped=False)
    assert node_mass_blocks(consistent + sp.identity(3 * mesh.n_nodes), free, 3) is None


@pytest.mark.slow
def test_explicit_step_with_node_blocks_matches_the_implicit_one():
    explicit = masonrydam.run(scene("central_difference", "auto"))
    dt = float(explicit.attrs["dynamic_dt_smallest"])
    assert float(explicit.attrs["energy_error_relative"]) < 1e-10
    implicit = masonrydam.run(scene("newmark_average", dt))
    ue, ui = crest_history(explicit), crest_history(implicit)
    peak = np.abs(ui).max()
    assert peak > 1e-4  # the shaking moves the crest (m)
    assert np.abs(ue[:, 0]).max() > 0.05 * peak  # across the valley too
    assert np.abs(ue - ui).max() < 0.005 * peak
