"""Ground-motion records: readers, bundled catalog, processing with provenance, measures, spectra, CLI."""
from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import obspy
import pytest
from scipy.linalg import expm

from masonrydam import MasonrydamError
from masonrydam import records as rec
from masonrydam.cli.main import main as cli_main
from masonrydam.records import measures
from masonrydam.records import processing as proc
from repository_paths import REPOSITORY_ROOT

G = 9.80665
REPO = REPOSITORY_ROOT
CATALOG = rec.load_catalog()
NAMES = list(CATALOG)

# N, dt [s] and peak from the provenance table shared/records/SOURCES.md (PGA in g to 4 decimals,
# PGD in cm to 2 decimals), independent of catalog.toml.
SOURCES_MD = {
    "elcentro_1940_NS_IELC180_PEER.AT2": (4000, 0.01, 0.3129),
    "elcentro_1940_NS_IELC180_PEER.DT2": (4000, 0.01, 13.31),
    "elcentro_1940_NS_peknold_OpenSees.AT2": (1559, 0.02, 0.3188),
    "elcentro_1940_NS_RSN6_I-ELC180_NGAW2.AT2": (5372, 0.01, 0.2808),
    "elcentro_1940_EW_RSN6_I-ELC270_NGAW2.AT2": (5346, 0.01, 0.2107),
    "elcentro_1940_UP_RSN6_I-ELC-UP_NGAW2.AT2": (5378, 0.01, 0.1781),
    "sanfernando_1971_pacoimadam_PUL164_RSN77_NGAW2.AT2": (4172, 0.01, 1.2190),
    "sanfernando_1971_pacoimadam_PUL254_RSN77_NGAW2.AT2": (4172, 0.01, 1.2383),
    "sanfernando_1971_pacoimadam_PULDWN_RSN77_NGAW2.AT2": (4172, 0.01, 0.6874),
    "lomaprieta_1989_CLSUP_RSN753_LOMAP_CLS-UP.AT2": (7999, 0.005, 0.4578),
    "lomaprieta_1989_CLS000_RSN753_LOMAP_CLS000.AT2": (7995, 0.005, 0.6447),
    "lomaprieta_1989_CLS090_RSN753_LOMAP_CLS090.AT2": (7999, 0.005, 0.4828),
    "northridge_1994_ARL360_PEER.AT2": (2000, 0.02, 0.3081),
}


@pytest.fixture(scope="module")
def elcentro():
    return rec.load_record("elcentro_1940_ns_peknold")


# ---------------------------------------------------------------------------------------------
# bundled library and PEER readers
# ---------------------------------------------------------------------------------------------

def test_catalog_covers_every_bundled_file():
    files = {e["file"] for e in CATALOG.values()}
    assert files == set(SOURCES_MD)
    lib = rec.library_dir()
    for f in files:
        assert (lib / f).is_file()
    assert len(set(NAMES)) == len(NAMES) == 13


@pytest.mark.parametrize("name", NAMES)
def test_peer_reader_matches_catalog_and_sources(name):
    e = CATALOG[name]
    path = Path(str(rec.library_dir() / e["file"]))
    assert hashlib.sha256(path.read_bytes()).hexdigest() == e["sha256"]
    # read without any hint: format, quantity and units come from the header
    st = rec.read_record(path, quantity=e["quantity"])
    assert isinstance(st, obspy.Stream) and len(st) == 1
    tr = st[0]
    m = tr.stats.masonrydam
    assert tr.stats.npts == e["npts"]
    assert tr.stats.delta == pytest.approx(e["dt"], rel=1e-12)
    assert m.format == "PEER" and m.format_variant == e["format"]
    assert len(m.header_lines) == e["header_lines"]
    assert m.original_units == e["units"]
    n_src, dt_src, peak_src = SOURCES_MD[e["file"]]
    assert (tr.stats.npts, tr.stats.delta) == (n_src, pytest.approx(dt_src))
    if e["quantity"] == "acceleration":
        assert m.units == "m/s2"
        pga_g = np.abs(tr.data).max() / G
        assert pga_g == pytest.approx(e["pga_g"], rel=1e-12)
        assert round(pga_g, 4) == pytest.approx(peak_src, abs=1e-9)
        assert rec.pga(tr) == pytest.approx(e["pga_g"] * G, rel=1e-12)
    else:
        assert m.units == "m"
        assert np.abs(tr.data).max() * 100 == pytest.approx(e["pgd_cm"], rel=1e-12)
        assert round(np.abs(tr.data).max() * 100, 2) == pytest.approx(peak_src, abs=1e-9)


def test_header_metadata_is_parsed():
    tr = rec.read_trace(rec.record_path("elcentro_1940_ns_ngaw2"))
    m = tr.stats.masonrydam
    assert (m.event, m.date, m.station, m.component) == ("Imperial Valley-02", "5/19/1940", "El Centro Array #9", "180")
    tr = rec.read_trace(rec.record_path("northridge_1994_arleta_360"))
    m = tr.stats.masonrydam
    assert (m.event, m.date, m.time, m.station, m.component) == ("NORTHRIDGE", "01/17/94", "1231", "ARLETA", "360")
    assert m.header_lines[0].startswith("PACIFIC ENGINEERING")


def test_load_record_by_name_adds_catalog_metadata(elcentro):
    m = elcentro.stats.masonrydam
    assert m.catalog_name == "elcentro_1940_ns_peknold"
    assert m.date == "1940-05-19" and m.source_repository == "OpenSees/OpenSees"
    assert m.provenance[0]["step"] == "read" and m.provenance[0]["parameters"]["catalog_name"] == m.catalog_name
    assert elcentro.data.dtype == np.float64
    assert m.end_marker == "*** End Data ***"


def test_unknown_record_name_suggests_close_names():
    with pytest.raises(rec.RecordError, match="did you mean 'elcentro_1940_ns_peknold'"):
        rec.load_record("elcentro_1940_peknold")
    assert issubclass(rec.RecordError, MasonrydamError)
    assert [e["name"] for e in rec.list_records(quantity="displacement")] == ["elcentro_1940_ns_peer_displacement"]


def test_displacement_file_is_never_read_as_acceleration():
    path = rec.record_path("elcentro_1940_ns_peer_displacement")
    with pytest.raises(rec.RecordError, match="displacement record .*DISPLACEMENT TIME HISTORY IN UNITS OF CM"
                                              ".*cannot be used as an acceleration"):
        rec.read_record(path)
    with pytest.raises(rec.RecordError, match="displacement"):
        rec.read_record(path, units="g")
    tr = rec.load_record("elcentro_1940_ns_peer_displacement")
    assert tr.stats.masonrydam.quantity == "displacement" and tr.stats.masonrydam.units == "m"
    with pytest.raises(rec.RecordError, match="need an acceleration record"):
        rec.pgv(tr)
    with pytest.raises(rec.RecordError, match="acceleration"):
        proc.scale_to_pga(tr, 1.0)


def test_integrating_peer_acceleration_reproduces_its_displacement_file():
    """PEER's IELC180 .AT2 and .DT2 come from one processing: the trapezoidal double integral of the
    acceleration equals the provider's displacement up to the initial displacement and velocity."""
    acc = rec.load_record("elcentro_1940_ns_peer")
    disp = rec.load_record("elcentro_1940_ns_peer_displacement")
    d = measures.displacement(acc)
    t = np.arange(d.size) * acc.stats.delta
    A = np.c_[np.ones_like(t), t]
    c = np.linalg.lstsq(A, disp.data - d, rcond=None)[0]
    assert np.max(np.abs(d + A @ c - disp.data)) < 5e-4  # m
    assert rec.pgd(acc) == pytest.approx(0.1331, rel=0.03)


def _write(path, text):
    path.write_text(text)
    return path


def test_peer_layout_with_npts_dt_columns_and_errors(tmp_path):
    vals = [0.001, -0.002, 0.003, 0.0005, -0.25, 0.1, 0.0]
    body = "\n".join("  ".join(f"{v: .7E}" for v in vals[i:i + 5]) for i in range(0, len(vals), 5))
    hdr = "PEER NGA STRONG MOTION DATABASE RECORD\nSome Event, 1/2/2003, Some Station, 90\n" \
          "ACCELERATION TIME SERIES IN UNITS OF G\n"
    f = _write(tmp_path / "new.AT2", hdr + "    7    0.0050    NPTS, DT\n" + body + "\n")
    tr = rec.read_trace(f)
    assert tr.stats.npts == 7 and tr.stats.delta == 0.005
    assert tr.stats.masonrydam.format_variant.startswith("PEER NGA (<npts> <dt> NPTS, DT")
    np.testing.assert_allclose(tr.data, np.array(vals) * G, rtol=1e-12)
    # header count and the data disagree
    f = _write(tmp_path / "short.AT2", hdr + "NPTS=      8, DT=   .0050 SEC,\n" + body + "\n")
    with pytest.raises(rec.RecordError, match="NPTS=8, but 7 values"):
        rec.read_record(f)
    # units and dt given by the caller must agree with the header
    f = _write(tmp_path / "ok.AT2", hdr + "NPTS=      7, DT=   .0050 SEC,\n" + body + "\n")
    with pytest.raises(rec.RecordError, match="contradicts the header"):
        rec.read_record(f, units="cm/s2")
    with pytest.raises(rec.RecordError, match="dt=0.01 contradicts"):
        rec.read_record(f, dt=0.01)
    assert rec.read_trace(f, units="g", dt=0.005).stats.npts == 7
    # a header that states no units
    f = _write(tmp_path / "nounits.AT2", "SOME RECORD\nNPTS=      7, DT=   .0050 SEC\n" + body + "\n")
    with pytest.raises(rec.RecordError, match="(?s)units are not stated.*SOME RECORD"):
        rec.read_record(f)
    assert rec.read_trace(f, units="gal").data[4] == pytest.approx(-0.25e-2)
    # an acceleration header in a file named as displacement
    f = _write(tmp_path / "named.DT2", hdr + "NPTS=      7, DT=   .0050 SEC,\n" + body + "\n")
    with pytest.raises(rec.RecordError, match="extension '.DT2' means displacement"):
        rec.read_record(f)
    # garbage in the data block
    f = _write(tmp_path / "bad.AT2", hdr + "NPTS=      7, DT=   .0050 SEC,\n" + body + "\n1.0 x2\n")
    with pytest.raises(rec.RecordError, match="not a list of numbers"):
        rec.read_record(f)


# ---------------------------------------------------------------------------------------------
# plain text and obspy formats
# ---------------------------------------------------------------------------------------------

def test_text_one_and_two_columns_with_units(tmp_path):
    a = np.array([0.0, 0.1, -0.2, 0.05, 0.3])
    one = tmp_path / "one.txt"
    np.savetxt(one, a)
    tr = rec.read_trace(one, units="g", dt=0.01)
    np.testing.assert_allclose(tr.data, a * G)
    assert tr.stats.delta == 0.01 and tr.stats.masonrydam.format == "TEXT"
    assert tr.stats.masonrydam.original_units == "g"
    for unit, factor in (("cm/s2", 0.01), ("gal", 0.01), ("mm/s2", 1e-3), ("m/s2", 1.0), ("CM/SEC/SEC", 0.01)):
        np.testing.assert_allclose(rec.read_trace(one, units=unit, dt=0.02).data, a * factor)
    two = tmp_path / "two.csv"
    t = 3.0 + 0.005 * np.arange(a.size)
    two.write_text("# time [s], acceleration [cm/s2]\n" + "\n".join(f"{ti:.3f}, {ai}" for ti, ai in zip(t, a)))
    tr = rec.read_trace(two, units="cm/s2")
    np.testing.assert_allclose(tr.data, a * 0.01)
    assert tr.stats.delta == pytest.approx(0.005) and tr.stats.masonrydam.time_start == 3.0
    # units and dt declared in comment lines
    decl = tmp_path / "declared.txt"
    decl.write_text("# units: g\n# dt = 0.02\n" + "\n".join(str(v) for v in a))
    tr = rec.read_trace(decl)
    assert tr.stats.delta == 0.02 and tr.stats.masonrydam.units_from == "'# units:' declaration"
    with pytest.raises(rec.RecordError, match="contradicts"):
        rec.read_record(decl, units="m/s2")


@pytest.mark.filterwarnings("ignore::UserWarning")  # obspy's format probes comment on the random bytes
def test_text_errors_say_what_was_found(tmp_path):
    one = tmp_path / "one.txt"
    np.savetxt(one, np.arange(5.0))
    with pytest.raises(rec.RecordError, match="units are not stated.*pass units=.*plain text with 1 column"):
        rec.read_record(one)
    with pytest.raises(rec.RecordError, match="1 column.*time step is not stated.*dt="):
        rec.read_record(one, units="g")
    with pytest.raises(rec.RecordError, match="unknown unit 'furlong/s2'"):
        rec.read_record(one, units="furlong/s2", dt=0.01)
    with pytest.raises(rec.RecordError, match="this is a velocity record"):
        rec.read_record(one, units="cm/s", dt=0.01)
    uneven = tmp_path / "uneven.txt"
    np.savetxt(uneven, np.c_[[0.0, 0.01, 0.02, 0.035, 0.045], np.ones(5)])
    with pytest.raises(rec.RecordError, match="not uniformly spaced.*rows 3 and 4"):
        rec.read_record(uneven, units="g")
    three = tmp_path / "three.txt"
    np.savetxt(three, np.ones((4, 3)))
    with pytest.raises(rec.RecordError, match="3 value columns found.*column=N"):  # one trace asked for
        rec.read_trace(three, units="g", dt=0.01)
    prose = tmp_path / "notes.txt"  # free text after the data began (before it, it is a header)
    prose.write_text("0.1\nStation: somewhere\nsampling unknown\n0.2\n")
    with pytest.raises(rec.RecordError, match="line 2 'Station: somewhere' is not a row of numbers.*line 1"):
        rec.read_record(prose, units="g", dt=0.01)
    binary = tmp_path / "blob.bin"
    binary.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(rec.RecordError, match="binary file that obspy does not recognise"):
        rec.read_record(binary)
    with pytest.raises(rec.RecordError, match="not found"):
        rec.read_record(tmp_path / "missing.AT2")


@pytest.mark.parametrize("fmt,ext,rtol", [("SAC", "sac", 1e-6), ("MSEED", "mseed", 0.0)])
def test_obspy_formats_round_trip(tmp_path, elcentro, fmt, ext, rtol):
    out = obspy.Trace(data=elcentro.data.copy(), header={"delta": elcentro.stats.delta, "network": "XX",
                                                         "station": "ELC", "channel": "HNN"})
    path = tmp_path / f"elc.{ext}"
    out.write(str(path), format=fmt)
    with pytest.raises(rec.RecordError, match=f"obspy format {fmt}.*pass units="):
        rec.read_record(path)
    st = rec.read_record(path, units="m/s2")
    tr = st[0]
    assert tr.stats.masonrydam.format == fmt
    assert tr.stats.npts == elcentro.stats.npts and tr.stats.delta == pytest.approx(elcentro.stats.delta)
    np.testing.assert_allclose(tr.data, elcentro.data, rtol=rtol, atol=1e-6 * rec.pga(elcentro) if rtol else 0)
    assert rec.read_trace(path, units="cm/s2", format=fmt).data[100] == pytest.approx(tr.data[100] / 100)
    assert tr.stats.masonrydam.station == "ELC"


# ---------------------------------------------------------------------------------------------
# processing and provenance
# ---------------------------------------------------------------------------------------------

def test_processing_steps_are_recorded(elcentro, tmp_path):
    tr = proc.baseline_correct(elcentro, "linear")
    tr = proc.taper(tr, 0.05)
    tr = proc.bandpass(tr, 0.1, 20.0, corners=4)
    tr = proc.resample(tr, 0.01)
    tr = proc.trim_significant_duration(tr, pad=1.0)
    tr = proc.scale_to_pga(tr, 0.3, units="g")
    steps = [p["step"] for p in tr.stats.masonrydam.provenance]
    assert steps == ["read", "baseline_correction", "taper", "bandpass", "resample", "trim_significant_duration",
                     "scale_to_pga"]
    for p in tr.stats.masonrydam.provenance[1:]:
        assert p["function"] and p["library"] and isinstance(p["parameters"], dict)
    assert tr.stats.masonrydam.provenance[3]["parameters"]["zerophase"] is True
    assert tr.stats.masonrydam.provenance[3]["function"] == "obspy.core.trace.Trace.filter"
    # the input trace is untouched
    assert len(elcentro.stats.masonrydam.provenance) == 1
    assert rec.pga(elcentro) == pytest.approx(0.31882 * G)
    attrs = proc.provenance_attrs(tr)
    assert all(isinstance(v, (str, int, float)) for v in attrs.values())
    assert [p["step"] for p in json.loads(attrs["record_provenance"])] == steps
    assert attrs["record_catalog_name"] == "elcentro_1940_ns_peknold" and attrs["record_dt"] == 0.01
    assert json.loads(attrs["record_header_lines"])[-1].startswith("NPTS=")
    # the netCDF library accepts them
    netCDF4 = pytest.importorskip("netCDF4")
    with netCDF4.Dataset(tmp_path / "attrs.nc", "w") as nc:
        nc.setncatts(attrs)
    with netCDF4.Dataset(tmp_path / "attrs.nc") as nc:
        assert json.loads(nc.record_provenance)[-1]["parameters"]["target"] == 0.3


def _block_on_ground_scene(ground_x):
    """A small elastic block on a linear joint over a fixed base, shaken by ``ground_x``: 60 steps of 0.01 s."""
    return {
        "model": {"name": "processed_record", "thickness": 1.0},
        "mesh": {"generator": "blocks_2d", "parameters": {"blocks": [
            {"x0": 0, "y0": 0, "x1": 1, "y1": 0.5, "group": "base"},
            {"x0": 0, "y0": 0.5, "x1": 1, "y1": 1.0, "group": "block"}], "element_size": 0.5}},
        "materials": {g: {"youngs_modulus": 30e9, "poisson_ratio": 0.2, "density": 2400} for g in ("base", "block")},
        "joints": {"joints": {"law": "linear", "normal_stiffness": 1e10, "shear_stiffness": 1e10}},
        "supports": [{"set": "base", "components": ["x", "y"]}],
        "stages": [{"name": "shake", "type": "dynamic", "dt": 0.01, "steps": 60, "ground_motion": {"x": ground_x}}],
    }


def test_scene_processing_steps_reach_the_result_attributes(tmp_path):
    """A scene's ground motion processed in the scene (baseline, taper, band-pass, resampling, D5-95 trim,
    then scaling to a target Sa(T)): the run shakes the model with the same record as the Python API
    gives for the same steps, the file's provenance attribute lists every step in order, and the record
    hits its Sa target (the response spectrum is linear in the record: Chopra 2012, sec. 6.6)."""
    import masonrydam

    steps = [{"step": "baseline", "method": "linear"}, {"step": "taper", "max_percentage": 0.05},
             {"step": "bandpass", "freqmin": 0.1, "freqmax": 20.0, "corners": 4}, {"step": "resample", "dt": 0.01},
             {"step": "trim", "start": 0.05, "end": 0.95, "pad": 1.0}]
    target = {"sa": "0.6 g", "period": 0.3, "damping": 0.05}
    ds = masonrydam.run(_block_on_ground_scene({"record": "elcentro_1940_ns_peknold", "processing": steps,
                                                "scale_to_sa": target}), output=tmp_path / "p.nc")
    prov = json.loads(ds.attrs["stage0_ground_motion_x_provenance"])
    assert [p["step"] for p in prov] == ["read", "baseline_correction", "taper", "bandpass", "resample",
                                         "trim_significant_duration", "scale_to_sa"]
    tr = rec.load_record("elcentro_1940_ns_peknold")
    tr = proc.trim_significant_duration(proc.resample(proc.bandpass(proc.taper(proc.baseline_correct(tr, "linear"),
                                                                                 0.05), 0.1, 20.0, 4), 0.01), pad=1.0)
    tr = proc.scale_to_sa(tr, 0.6, 0.3, 0.05, units="g")
    assert measures.spectral_acceleration(tr, None, 0.3, 0.05) == pytest.approx(0.6 * G, rel=1e-9)
    # the file records the ground acceleration at every step: the processed record's first samples
    ag = ds.ground_acceleration.sel(component="x").values
    np.testing.assert_allclose(ag[:50], tr.data[:50], rtol=0, atol=1e-9 * np.abs(tr.data).max())
    assert prov[-1]["parameters"]["period"] == 0.3


@pytest.mark.parametrize("ground, key, words", [
    ({"record": "elcentro_1940_ns_peknold", "processing": [{"step": "smooth"}]}, "processing[0].step", "must be one of"),
    ({"record": "elcentro_1940_ns_peknold", "processing": [{"step": "bandpass", "fmin": 1.0}]}, "processing[0]", "fmin"),
    ({"record": "elcentro_1940_ns_peknold", "processing": [{"step": "bandpass", "freqmin": 80.0}]}, "processing[0]",
     "Nyquist"),
    ({"record": "elcentro_1940_ns_peknold", "scale_to_pga": "0.3 g", "scale_to_sa": {"sa": "0.5 g", "period": 0.2}},
     "scale_to_sa", "not"),
    ({"record": "elcentro_1940_ns_peknold", "scale_to_sa": {"sa": "0.5 g"}}, "scale_to_sa.period", "required"),
])
def test_scene_processing_errors_name_the_key(ground, key, words):
    import masonrydam
    from masonrydam.errors import SceneError

    with pytest.raises(SceneError) as exc:
        masonrydam.run(_block_on_ground_scene(ground))
    assert key in str(exc.value) and words in str(exc.value)


def test_scaling_hits_targets_exactly(elcentro):
    tr = proc.scale_to_pga(elcentro, 2.5)
    assert rec.pga(tr) == pytest.approx(2.5, rel=1e-14)
    tr = proc.scale_to_pga(elcentro, 0.4, units="g")
    assert rec.pga(tr) / G == pytest.approx(0.4, rel=1e-14)
    tr = proc.scale_to_sa(elcentro, 0.75, period=0.6, damping=0.05, units="g")
    assert rec.spectral_acceleration(tr, None, 0.6, 0.05) / G == pytest.approx(0.75, rel=1e-12)
    assert tr.stats.masonrydam.provenance[-1]["parameters"]["period"] == 0.6
    with pytest.raises(rec.RecordError, match="acceleration unit"):
        proc.scale_to_pga(elcentro, 1.0, units="cm")
    with pytest.raises(rec.RecordError, match="positive"):
        proc.scale_to_pga(elcentro, -1.0)


def _trace(a, dt):
    return obspy.Trace(data=np.asarray(a, dtype=np.float64), header={"delta": dt})


def test_bandpass_removes_a_low_frequency_sine():
    dt = 0.01
    t = np.arange(6000) * dt
    low = 1.0 * np.sin(2 * np.pi * 0.05 * t)
    mid = 0.5 * np.sin(2 * np.pi * 2.0 * t)
    tr = proc.bandpass(_trace(low + mid, dt), 0.5, 10.0, corners=4)
    inner = slice(1000, 5000)  # away from the filter's edge transients
    resid = tr.data[inner] - mid[inner]
    assert np.max(np.abs(resid)) < 0.01 * np.max(np.abs(low))
    with pytest.raises(rec.RecordError, match="Nyquist"):
        proc.bandpass(_trace(low, dt), 0.1, 60.0)


def test_resample_and_baseline_and_taper():
    dt = 0.01
    t = np.arange(2000) * dt
    sig = np.sin(2 * np.pi * 1.0 * t)
    up = proc.resample(_trace(sig, dt), 0.005)
    assert up.stats.delta == 0.005 and up.stats.npts == 4000
    tu = np.arange(4000) * 0.005
    np.testing.assert_allclose(up.data[200:-200], np.sin(2 * np.pi * tu[200:-200]), atol=2e-3)
    down = proc.resample(_trace(sig, dt), 0.02)
    assert down.stats.npts == 1000
    assert proc.resample(_trace(sig, dt), 0.004, method="fourier").stats.delta == pytest.approx(0.004)
    with pytest.raises(rec.RecordError, match="method='fourier'"):
        proc.resample(_trace(sig, dt), 0.01 * math.pi)
    tilted = proc.baseline_correct(_trace(sig + 0.3 + 0.2 * t, dt), "linear")
    assert abs(np.polyfit(t, tilted.data, 1)[0]) < 1e-3 and abs(tilted.data.mean()) < 1e-3
    quad = proc.baseline_correct(_trace(sig + 0.1 * t ** 2, dt), "polynomial", order=2)
    assert np.max(np.abs(quad.data - sig)) < 0.05
    tp = proc.taper(_trace(np.ones(1000), dt), 0.1)
    assert tp.data[0] == pytest.approx(0.0, abs=1e-12) and tp.data[500] == 1.0


def test_trim_to_significant_duration():
    dt = 0.01
    a = np.zeros(3000)
    a[1000:2000] = 1.0  # uniform energy from 10 s to 20 s
    tr = proc.trim_significant_duration(_trace(a, dt))
    p = tr.stats.masonrydam.provenance[-1]["parameters"]
    # trapezoidal energy: half a step of ramp at 9.99-10.00 s and 19.99-20.00 s, uniform in between
    # (total 10.00 s of a**2 = 1), so H reaches 5 % at 10 + 0.5 - 0.005 s and 95 % at 10 + 9.5 - 0.005 s
    assert p["t_start"] == pytest.approx(10.495, abs=1e-9)
    assert p["t_end"] == pytest.approx(19.495, abs=1e-9)
    assert tr.stats.npts == pytest.approx(0.9 * 1000, abs=2)
    padded = proc.trim_significant_duration(_trace(a, dt), pad=2.0)
    assert padded.stats.npts == pytest.approx(tr.stats.npts + 400, abs=2)


# ---------------------------------------------------------------------------------------------
# measures
# ---------------------------------------------------------------------------------------------

def test_arias_duration_cav_of_a_sine_burst_closed_forms():
    """a = A sin(2 pi f t) for an integer number of cycles over Td, zero before and after:
    Ia = pi/(2g) A^2 Td/2, CAV = 2 A Td / pi, PGV = 2 A / (2 pi f), D5-95 ~ 0.9 Td."""
    A, f, Td, dt = 2.0, 4.0, 8.0, 0.001
    n0 = 2000
    nb = int(round(Td / dt))
    a = np.zeros(n0 + nb + 3000)
    a[n0:n0 + nb + 1] = A * np.sin(2 * np.pi * f * np.arange(nb + 1) * dt)
    assert rec.arias_intensity(a, dt) == pytest.approx(math.pi / (2 * G) * A ** 2 * Td / 2, rel=1e-6)
    assert rec.cav(a, dt) == pytest.approx(2 * A * Td / math.pi, rel=1e-4)
    assert rec.pgv(a, dt) == pytest.approx(2 * A / (2 * math.pi * f), rel=1e-4)
    # closed-form Husid function of the burst: H(s) = s/Td - sin(4 pi f s)/(4 pi f Td), s = t - t0
    from scipy.optimize import brentq

    def s_at(frac):
        return brentq(lambda s: s / Td - math.sin(4 * math.pi * f * s) / (4 * math.pi * f * Td) - frac, 0.0, Td)

    t5, t95 = rec.husid_times(a, dt, (0.05, 0.95))
    assert t5 == pytest.approx(n0 * dt + s_at(0.05), abs=1e-4)
    assert t95 == pytest.approx(n0 * dt + s_at(0.95), abs=1e-4)
    assert rec.significant_duration(a, dt) == pytest.approx(s_at(0.95) - s_at(0.05), abs=2e-4)
    # and its wiggle keeps D5-95 within 2/(4 pi f) of 0.9 Td
    assert abs(rec.significant_duration(a, dt) - 0.9 * Td) < 2 / (4 * math.pi * f)


def test_uniform_energy_record_duration_and_husid_fractions():
    dt, n = 0.02, 1001
    a = np.where(np.arange(n) % 2 == 0, 1.5, -1.5)  # |a| constant: a**2 is uniform
    dur = (n - 1) * dt
    assert rec.significant_duration(a, dt) == pytest.approx(0.9 * dur, rel=1e-12)
    assert rec.significant_duration(a, dt, 0.25, 0.75) == pytest.approx(0.5 * dur, rel=1e-12)
    np.testing.assert_allclose(rec.husid_times(a, dt, [0.0, 0.5, 1.0]), [0.0, 0.5 * dur, dur], atol=1e-12)
    assert rec.arias_intensity(a, dt) == pytest.approx(math.pi / (2 * G) * 1.5 ** 2 * dur, rel=1e-12)
    with pytest.raises(rec.RecordError, match="identically zero"):
        rec.significant_duration(np.zeros(10), dt)
    with pytest.raises(rec.RecordError, match="dt"):
        rec.arias_intensity(a)


# ---------------------------------------------------------------------------------------------
# response spectrum
# ---------------------------------------------------------------------------------------------

def _exact_piecewise_linear_peak(a, dt, T, z):
    """Independent exact solution for a piecewise-linear excitation: the state [u, v, p, p'] of
    u'' + 2 z w u' + w^2 u = p, p'' = 0 is advanced over each step with scipy's matrix exponential."""
    w = 2 * np.pi / T
    M = np.zeros((4, 4))
    M[0, 1] = 1.0
    M[1, 0], M[1, 1], M[1, 2] = -w * w, -2 * z * w, 1.0
    M[2, 3] = 1.0
    E = expm(M * dt)
    p = -np.asarray(a)
    x = np.zeros(4)
    peak = 0.0
    for i in range(p.size - 1):
        x[2], x[3] = p[i], (p[i + 1] - p[i]) / dt
        x = E @ x
        peak = max(peak, abs(x[0]))
    return peak


def test_spectrum_kernel_is_the_exact_piecewise_linear_solution(elcentro):
    a, dt = elcentro.data[:600], elcentro.stats.delta
    T = np.array([0.05, 0.3, 1.0, 3.0])
    Z = np.array([0.0, 0.05])
    Sa, Sv, Sd = rec.response_spectrum(a, dt, T, Z, min_samples_per_period=1)
    assert Sd.shape == Sv.shape == Sa.shape == (2, 4)
    for j, z in enumerate(Z):
        for k, t in enumerate(T):
            assert Sd[j, k] == pytest.approx(_exact_piecewise_linear_peak(a, dt, t, z), rel=1e-10)
    w = 2 * np.pi / T
    np.testing.assert_allclose(Sv, Sd * w, rtol=1e-15)
    np.testing.assert_allclose(Sa, Sd * w * w, rtol=1e-15)


def test_spectrum_against_closed_form_harmonic_response():
    """u'' + 2 z wn u' + wn^2 u = -ag, ag = a0 sin(w t), from rest: the closed-form damped harmonic
    response (Chopra, Dynamics of Structures, sec. 3.2, with p0 = -a0 per unit mass)
    u = exp(-z wn t)(A cos wD t + B sin wD t) + C sin wt + D cos wt, A and B from u(0) = u'(0) = 0.
    The record is finely sampled so that its linear interpolation matches the sine to 1e-5."""
    a0, w = 1.3, 2 * np.pi * 1.5
    dt, n = 0.0005, 16001
    t = np.arange(n) * dt
    ag = a0 * np.sin(w * t)
    for Tn, z in ((0.4, 0.05), (1.0, 0.02), (0.25, 0.0), (2.0, 0.1)):
        wn = 2 * np.pi / Tn
        wd = wn * math.sqrt(1 - z * z)
        beta = w / wn
        den = (1 - beta ** 2) ** 2 + (2 * z * beta) ** 2
        ust = -a0 / wn ** 2
        C = ust * (1 - beta ** 2) / den
        D = ust * (-2 * z * beta) / den
        A = -D
        B = (z * wn * A - w * C) / wd
        u = np.exp(-z * wn * t) * (A * np.cos(wd * t) + B * np.sin(wd * t)) + C * np.sin(w * t) + D * np.cos(w * t)
        _, _, Sd = rec.response_spectrum(ag, dt, [Tn], [z], min_samples_per_period=1)
        assert Sd[0, 0] == pytest.approx(np.max(np.abs(u)), rel=1e-4)


def _rk4_peaks(a, dt, periods, zetas, sub):
    """Brute force: classical RK4 with dt/sub steps, ground acceleration interpolated linearly, all
    oscillators at once; the peak is taken over every fine step."""
    T, Z = np.meshgrid(periods, zetas)
    w = 2 * np.pi / T
    u = np.zeros_like(w)
    v = np.zeros_like(w)
    peak = np.zeros_like(w)
    h = dt / sub
    fine = np.interp(np.arange((a.size - 1) * sub + 1) * h, np.arange(a.size) * dt, a)
    half = 0.5 * (fine[:-1] + fine[1:])
    for i in range(fine.size - 1):
        p0, pm, p1 = -fine[i], -half[i], -fine[i + 1]
        k1u, k1v = v, p0 - 2 * Z * w * v - w * w * u
        k2u = v + 0.5 * h * k1v
        k2v = pm - 2 * Z * w * k2u - w * w * (u + 0.5 * h * k1u)
        k3u = v + 0.5 * h * k2v
        k3v = pm - 2 * Z * w * k3u - w * w * (u + 0.5 * h * k2u)
        k4u = v + h * k3v
        k4v = p1 - 2 * Z * w * k4u - w * w * (u + h * k3u)
        u = u + h / 6 * (k1u + 2 * k2u + 2 * k3u + k4u)
        v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        np.maximum(peak, np.abs(u), out=peak)
    return peak


@pytest.mark.slow
def test_spectrum_against_brute_force_fine_step_integration_on_el_centro(elcentro):
    a, dt = elcentro.data[:800], elcentro.stats.delta  # the strong part, first 16 s
    periods = np.array([0.1, 0.2, 0.5, 1.0, 2.0, 4.0])
    zetas = np.array([0.02, 0.05])
    brute = _rk4_peaks(a, dt, periods, zetas, sub=40)
    _, _, Sd = rec.response_spectrum(a, dt, periods, zetas)  # default sub-stepping (>= 32 samples/period)
    np.testing.assert_allclose(Sd, brute, rtol=5e-3)
    # the same sampling of the peak (40 sub-steps everywhere): agreement to RK4's own error
    for k, T in enumerate(periods):
        _, _, Sd40 = rec.response_spectrum(a, dt, [T], zetas, min_samples_per_period=40 * T / dt)
        np.testing.assert_allclose(Sd40[:, 0], brute[:, k], rtol=1e-5)


def test_spectrum_rigid_limit_and_input_checks(elcentro):
    Sa, Sv, Sd = rec.response_spectrum(elcentro, None, [0.0, 0.001], [0.05])
    pga = rec.pga(elcentro)
    assert Sa[0, 0] == pga and Sv[0, 0] == 0.0 and Sd[0, 0] == 0.0
    assert Sa[0, 1] == pytest.approx(pga, rel=1e-3)
    assert rec.spectral_acceleration(elcentro, None, 0.0) == pga
    for bad_T in ([-0.1], [np.nan], [np.inf]):
        with pytest.raises(rec.RecordError, match="periods"):
            rec.response_spectrum(elcentro, None, bad_T, [0.05])
    for bad_z in ([1.0], [-0.01], [np.nan]):
        with pytest.raises(rec.RecordError, match="damping"):
            rec.response_spectrum(elcentro, None, [0.5], bad_z)
    with pytest.raises(rec.RecordError, match="periods"):
        rec.response_spectrum(elcentro, None, [], [0.05])
    Sa, _, _ = rec.response_spectrum(elcentro, None, [0.5, 1.0], 0.05)
    assert Sa.shape == (1, 2)


# ---------------------------------------------------------------------------------------------
# command line and packaging
# ---------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_cli_records_list_and_show(tmp_path, capsys):
    assert cli_main(["records", "list"]) == 0
    out = capsys.readouterr().out
    for name in NAMES:
        assert name in out
    assert "0.3188" in out
    png = tmp_path / "elc.png"
    assert cli_main(["records", "show", "elcentro_1940_ns_peknold", "-o", str(png), "--damping", "0.02"]) == 0
    out = capsys.readouterr().out
    for key in ("PGA", "PGV", "PGD", "Arias", "D5-95", "CAV"):
        assert key in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # what is drawn: the record itself (peak 0.3188 g at its own samples) and its 2 % spectrum, whose
    # value at T = 0.5 s is Chopra's (2012, Fig. 6.4.1) A = 1.09 g for El Centro NS
    from masonrydam.records.plotting import record_figure

    tr = rec.load_record("elcentro_1940_ns_peknold")
    acc, vel, disp, spec = record_figure(tr, damping=0.02).axes
    assert [ax.get_ylabel() for ax in (acc, vel, disp)] == ["acceleration [g]", "velocity [cm/s]", "displacement [cm]"]
    (a_line,) = acc.get_lines()
    assert len(a_line.get_ydata()) == tr.stats.npts
    assert np.abs(a_line.get_ydata()).max() == pytest.approx(0.3188, abs=5e-5)
    assert a_line.get_xdata()[-1] == pytest.approx((tr.stats.npts - 1) * tr.stats.delta)
    (sa,) = spec.get_lines()
    assert spec.get_xscale() == "log" and "2 % damping" in spec.get_ylabel()
    assert np.interp(np.log(0.5), np.log(sa.get_xdata()), sa.get_ydata()) == pytest.approx(1.09, rel=0.02)
    assert cli_main(["records", "show", "elcentro_1940_peknold"]) == 2
    assert "did you mean" in capsys.readouterr().err


def test_cli_records_show_a_text_file_with_declared_units(tmp_path, capsys):
    """`records show FILE --units g --dt 0.01` reads a one-column text file (units and step declared, as
    the file cannot state them) and prints its PGA: 0.25 g for a file whose largest value is 0.25; without
    --units the error says what is missing."""
    f = tmp_path / "motion.txt"
    f.write_text("\n".join(f"{v:.6f}" for v in 0.25 * np.sin(np.linspace(0, 6 * np.pi, 300))))
    png = tmp_path / "motion.png"
    assert cli_main(["records", "show", str(f), "--units", "g", "--dt", "0.01", "-o", str(png)]) == 0
    out = capsys.readouterr().out
    assert "(0.2500 g)" in out and png.is_file()
    assert cli_main(["records", "show", str(f), "--dt", "0.01", "-o", str(png)]) == 2
    assert "units" in capsys.readouterr().err
    assert cli_main(["records", "show", "elcentro_1940_ns_peknold", "--units", "g"]) == 2
    assert "--units applies to a record file" in capsys.readouterr().err


def test_pyproject_lists_every_package():
    """pyproject.toml lists packages explicitly (to map records/ to masonrydam._bundled_records); a new
    sub-package that is not listed would be missing from `pip install .`."""
    tomllib = pytest.importorskip("tomllib")
    pyproject = REPO / "pyproject.toml"
    if not (REPO / "records" / "catalog.toml").is_file() or not pyproject.is_file():
        pytest.skip("not a source checkout")
    from setuptools import find_namespace_packages

    cfg = tomllib.loads(pyproject.read_text())["tool"]["setuptools"]
    listed = set(cfg["packages"])
    found = {p for p in find_namespace_packages(str(REPO), include=["masonrydam*", "generators*"])
             if "__pycache__" not in p}
    assert found - listed == set(), "add these packages to [tool.setuptools] packages in pyproject.toml"
    assert cfg["package-dir"]["masonrydam._bundled_records"] == "records"
    globs = cfg["package-data"]["masonrydam._bundled_records"]
    import fnmatch

    for e in CATALOG.values():
        assert any(fnmatch.fnmatch(e["file"], g) for g in globs), e["file"]
    assert "catalog.toml" in globs
