"""Results written in blocks: buffering, chunking, single precision and compression change
how the steps reach the file, never what is in it.

The reference is the same run written one step at a time (``buffer_steps = 1``); single precision
must give the float32 rounding of the double values (IEEE 754 round to nearest), compression the
same bits in a smaller file.
"""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import masonrydam
from masonrydam.errors import SceneError
from masonrydam.results.writer import BUFFER_BYTES_MAX, OutputOptions, ResultWriter
from scenes import sliding_block

FIELDS = ("displacement", "reaction", "velocity", "acceleration", "acceleration_absolute", "joint_opening",
          "joint_slip", "joint_plastic_slip", "joint_traction_normal", "joint_traction_shear")


def run_with(tmp_path, name, **output):
    """The Newmark sliding block (gravity, then 0.3 s of a 0.4 g pulse: 151 recorded steps) written
    with the [output] options given."""
    sc = sliding_block(duration=0.3)
    sc["output"] = output
    path = tmp_path / f"{name}.nc"
    masonrydam.run(sc, output=path)
    return xr.load_dataset(path), path


@pytest.mark.slow
def test_blocks_of_any_size_give_the_same_file_contents(tmp_path):
    one, _ = run_with(tmp_path, "one", buffer_steps=1)
    seven, _ = run_with(tmp_path, "seven", buffer_steps=7)  # 151 steps: 21 blocks and a remainder of 4
    timed, _ = run_with(tmp_path, "timed", buffer_steps=100000, flush_seconds=1e-6)
    assert one.sizes["step"] == 152
    for other in (seven, timed):
        assert set(other.data_vars) == set(one.data_vars)
        for v in one.variables:
            np.testing.assert_array_equal(other[v].values, one[v].values, err_msg=v)
    # the static step of a time-history file keeps NaN in the dynamic variables
    assert np.isnan(seven.time.values[0]) and np.isnan(seven.velocity.values[0]).all()
    assert np.isnan(seven.energy_input.values[0])


def test_single_precision_is_the_float32_rounding_of_double(tmp_path):
    double, dpath = run_with(tmp_path, "double")
    single, spath = run_with(tmp_path, "single", precision="single")
    for v in FIELDS:
        assert single[v].dtype == np.float32, v
        np.testing.assert_array_equal(single[v].values, double[v].values.astype(np.float32), err_msg=v)
    for v in ("time", "load_factor", "energy_input", "energy_error"):
        assert single[v].dtype == np.float64
        np.testing.assert_array_equal(single[v].values, double[v].values, err_msg=v)
    assert spath.stat().st_size < 0.7 * dpath.stat().st_size


@pytest.mark.slow
def test_compression_keeps_every_bit(tmp_path):
    plain, ppath = run_with(tmp_path, "plain")
    packed, cpath = run_with(tmp_path, "packed", compression=4)
    for v in plain.variables:
        np.testing.assert_array_equal(packed[v].values, plain[v].values, err_msg=v)
    assert cpath.stat().st_size < ppath.stat().st_size
    chunks = packed.displacement.encoding["chunksizes"]
    assert chunks[0] > 1 and packed.displacement.encoding["zlib"]


def test_a_block_is_bounded_in_memory(tmp_path):
    """A model whose step takes 2 MB holds at most BUFFER_BYTES_MAX / 2 MB steps in memory."""
    n_nodes = 2**17  # 2**17 nodes x 2 components x 8 bytes = 2 MB per displacement record
    coords = np.zeros((n_nodes, 2))
    jp = {"x": np.zeros((0, 2)), "set": np.zeros(0, int), "set_names": [], "element": np.zeros(0, int),
          "point": np.zeros(0, int), "normal": np.zeros((0, 2)), "shear_axes": np.zeros((0, 1, 2)),
          "weight": np.zeros(0)}
    w = ResultWriter(tmp_path / "big.nc", coords, np.arange(n_nodes), jp, 2, {}, options=OutputOptions())
    try:
        record = sum(b[0].nbytes for b in w._buffers.values())
        assert record >= 4 * 2**20  # displacement and reaction
        assert w.block_steps == BUFFER_BYTES_MAX // record < OutputOptions().buffer_steps
        assert "joint_opening" not in w._buffers  # no joint points: nothing to buffer or write
    finally:
        w.close(True, "completed")


def test_output_options_are_checked_with_their_key():
    for output, key in (({"precision": "half"}, "output.precision"), ({"compression": 12}, "output.compression"),
                        ({"buffer_steps": 0}, "output.buffer_steps"), ({"flush_seconds": -1}, "output.flush_seconds"),
                        ({"buffer": 10}, "output.buffer")):
        sc = sliding_block()
        sc["output"] = output
        with pytest.raises(SceneError) as ei:
            masonrydam.Scene(sc)
        assert ei.value.key == key, (output, ei.value)
