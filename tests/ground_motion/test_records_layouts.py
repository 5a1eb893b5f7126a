"""Ground-motion text files as users have them: header lines, a time column, several
value columns, units stated in the header. Every file is written here, into tmp_path, so that the
expected physical values are known exactly: the PGA of a trace is the largest absolute value written
times the factor of its units (g = 9.80665 m/s2, cm/s2 = gal = 0.01 m/s2), and dt is the spacing of the
written time column (or the given dt)."""
from __future__ import annotations

import numpy as np
import pytest

from masonrydam import records as rec
from masonrydam.cli.main import main as cli_main
from masonrydam.errors import SceneError
from masonrydam.records import G
from test_records import _block_on_ground_scene

DT = 0.005
N = 400
T = DT * np.arange(N)
NS = 0.31 * np.sin(2 * np.pi * 2.0 * T) * np.exp(-T)        # written values (in the file's units)
EW = -0.17 * np.cos(2 * np.pi * 3.0 * T) * np.exp(-0.5 * T)
FACTORS = {"g": G, "m/s2": 1.0, "cm/s2": 0.01, "cm/sec^2": 0.01, "gal": 0.01}


def _csv_with_header(path, unit="g"):
    """First line `time,acc (<unit>)`, then `t,a` rows."""
    path.write_text(f"time,acc ({unit})\n" + "".join(f"{t:.3f},{a:.6f}\n" for t, a in zip(T, NS)))
    return path


def _text_with_free_header(path, unit="g"):
    """Free-text header lines, a tab-separated `Time[s]<TAB>Accel[<unit>]` column line, tab-separated rows."""
    head = ("STRONG MOTION RECORD - test station TST\n"
            "Event: synthetic, 2024/05/01 12:00 UTC\n"
            "Processed: none. Sampling 200 samples/s\n"
            f"Time[s]\tAccel[{unit}]\n")
    path.write_text(head + "".join(f"{t:.3f}\t{a:.6f}\n" for t, a in zip(T, NS)))
    return path


def _two_components(path):
    """Two acceleration components, no time column, `%` comment lines (also one inside the data)."""
    rows = [f"{a: .6f}  {b: .6f}" for a, b in zip(NS, EW)]
    rows.insert(100, "% --- a comment inside the data ---")
    path.write_text("% synthetic two-component record\n% NS and EW, sampled every 5 ms\n" + "\n".join(rows) + "\n")
    return path


def _peak(x) -> float:
    """Largest absolute value as written (6 decimals), in the file's units."""
    return float(np.max(np.abs(np.round(x, 6))))


# ---------------------------------------------------------------------------------------------
# the three layouts
# ---------------------------------------------------------------------------------------------

def test_csv_with_a_header_line_and_a_time_column(tmp_path):
    tr = rec.read_trace(_csv_with_header(tmp_path / "rec.csv"))
    meta = tr.stats.masonrydam
    assert tr.stats.npts == N and tr.stats.delta == pytest.approx(DT, rel=1e-12)
    assert rec.pga(tr) == pytest.approx(_peak(NS) * G, rel=1e-12)
    np.testing.assert_allclose(tr.data, np.round(NS, 6) * G, rtol=0, atol=1e-12)
    assert meta.header_lines == ["time,acc (g)"]
    assert meta.original_units == "g" and meta.units_from == "column line" and meta.units_source == "time,acc (g)"
    assert meta.time_column == "time" and meta.dt_from == "time column" and meta.time_start == 0.0
    assert meta.column == 0 and meta.column_name == "acc (g)" and meta.value_columns == 1


def test_free_text_header_and_tab_separated_column_line(tmp_path):
    path = _text_with_free_header(tmp_path / "rec.txt")
    st = rec.read_record(path)
    assert len(st) == 1
    tr = st[0]
    meta = tr.stats.masonrydam
    assert tr.stats.delta == pytest.approx(DT, rel=1e-12) and tr.stats.npts == N
    assert rec.pga(tr) == pytest.approx(_peak(NS) * G, rel=1e-12)
    assert meta.header_lines[0] == "STRONG MOTION RECORD - test station TST"
    assert len(meta.header_lines) == 4 and meta.header_lines[-1] == "Time[s]\tAccel[g]"
    assert meta.units_source == "Time[s]\tAccel[g]" and meta.time_column == "Time[s]"


def test_two_components_without_time_column_give_two_traces(tmp_path):
    path = _two_components(tmp_path / "two.txt")
    st = rec.read_record(path, units="cm/s2", dt=DT)
    assert len(st) == 2
    for k, (tr, written) in enumerate(zip(st, (NS, EW))):
        assert tr.stats.npts == N and tr.stats.delta == DT
        assert rec.pga(tr) == pytest.approx(_peak(written) * 0.01, rel=1e-12)
        assert tr.stats.masonrydam.column == k and tr.stats.masonrydam.time_column is None
        assert tr.stats.masonrydam.header_lines[:2] == ["% synthetic two-component record",
                                                        "% NS and EW, sampled every 5 ms"]
    # column= picks one of them: the same trace as the Stream's k-th
    tr = rec.read_trace(path, units="cm/s2", dt=DT, column=1)
    np.testing.assert_array_equal(tr.data, st[1].data)
    assert rec.read_record(path, units="cm/s2", dt=DT, column=0)[0].stats.masonrydam.column == 0


def test_several_value_columns_after_a_time_column(tmp_path):
    """Time, NS, EW: column counts the value columns from 0, the time column not counted."""
    path = tmp_path / "three.dat"
    path.write_text("t [s]   NS (gal)   EW (gal)\n"
                    + "".join(f"{t:.3f} {a:.6f} {b:.6f}\n" for t, a, b in zip(T, NS, EW)))
    st = rec.read_record(path)
    assert [tr.stats.masonrydam.column_name for tr in st] == ["NS (gal)", "EW (gal)"]
    assert [rec.pga(tr) for tr in st] == pytest.approx([_peak(NS) * 0.01, _peak(EW) * 0.01], rel=1e-12)
    tr = rec.read_trace(path, column=1)
    assert tr.stats.masonrydam.column_name == "EW (gal)" and tr.stats.delta == pytest.approx(DT)
    with pytest.raises(rec.RecordError) as exc:
        rec.read_trace(path)
    msg = str(exc.value)
    assert exc.value.option == "column"
    for words in ("2 value columns", "column=N", "0 = 'NS (gal)'", "1 = 'EW (gal)'", "'t [s]' not counted"):
        assert words in msg
    with pytest.raises(rec.RecordError, match="column=2 is not a value column.*2 value columns"):
        rec.read_trace(path, column=2)


# ---------------------------------------------------------------------------------------------
# units and time step
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("unit", list(FACTORS))
def test_units_taken_from_the_header(tmp_path, unit):
    factor = FACTORS[unit]
    tr = rec.read_trace(_text_with_free_header(tmp_path / "rec.txt", unit))
    assert rec.pga(tr) == pytest.approx(_peak(NS) * factor, rel=1e-12)
    assert tr.stats.masonrydam.unit_factor == factor and tr.stats.masonrydam.units_from == "column line"
    # the same unit on a 'units:' line of a headed one-column file
    one = tmp_path / "one.txt"
    one.write_text(f"Station TST\nUnits: {unit}\ndt = {DT}\n" + "".join(f"{a:.6f}\n" for a in NS))
    tr = rec.read_trace(one)
    assert rec.pga(tr) == pytest.approx(_peak(NS) * factor, rel=1e-12) and tr.stats.delta == DT
    assert tr.stats.masonrydam.units_source == f"Units: {unit}"
    assert tr.stats.masonrydam.units_from == "header line 2"


def test_units_not_stated_are_required_and_contradictions_are_errors(tmp_path):
    path = tmp_path / "nounits.csv"
    path.write_text("time,acceleration\n" + "".join(f"{t:.3f},{a:.6f}\n" for t, a in zip(T, NS)))
    with pytest.raises(rec.RecordError, match="units are not stated.*pass units=") as exc:
        rec.read_trace(path)
    assert exc.value.option == "units"
    assert rec.pga(rec.read_trace(path, units="m/s2")) == pytest.approx(_peak(NS), rel=1e-12)
    headed = _csv_with_header(tmp_path / "g.csv", "g")
    assert rec.pga(rec.read_trace(headed, units="g")) == pytest.approx(_peak(NS) * G, rel=1e-12)  # agrees
    with pytest.raises(rec.RecordError, match=r"units='cm/s2' \(acceleration\) contradicts the column line "
                                              r"'time,acc \(g\)'") as exc:
        rec.read_trace(headed, units="cm/s2")
    assert exc.value.option == "units"
    # two header statements that disagree
    both = tmp_path / "both.txt"
    both.write_text("units: g\ntime  acc (cm/s2)\n" + "".join(f"{t:.3f} {a:.6f}\n" for t, a in zip(T, NS)))
    with pytest.raises(rec.RecordError, match="'acc \\(cm/s2\\)' is in 'cm/s2'.*says 'g'"):
        rec.read_trace(both)


def test_dt_from_the_time_column_is_checked_against_a_given_dt(tmp_path):
    path = _csv_with_header(tmp_path / "rec.csv")
    assert rec.read_trace(path, dt=DT).stats.delta == pytest.approx(DT, rel=1e-12)
    with pytest.raises(rec.RecordError) as exc:
        rec.read_trace(path, dt=0.01)
    assert exc.value.option == "dt"
    assert "dt=0.01 contradicts the time column 'time', whose step is 0.005 s" in str(exc.value)
    assert "np." not in str(exc.value)
    # a time column must be evenly spaced; the error shows plain numbers
    bad = tmp_path / "bad.csv"
    t = T.copy()
    t[10:] += 0.002
    bad.write_text("time,acc (g)\n" + "".join(f"{ti:.3f},{a:.6f}\n" for ti, a in zip(t, NS)))
    with pytest.raises(rec.RecordError, match=r"not uniformly spaced.*\(t = 0.045, 0.052\)") as exc:
        rec.read_trace(bad)
    assert "np.float64" not in str(exc.value)


def test_records_messages_show_no_numpy_reprs():
    """Numbers reach messages as plain numbers even when given as NumPy scalars."""
    with pytest.raises(rec.RecordError) as exc:
        rec.measures.husid_times(np.ones(10), 0.01, fractions=np.array([0.1, 1.5]))
    assert "np.float64" not in str(exc.value) and "1.5" in str(exc.value)
    with pytest.raises(rec.RecordError) as exc:
        rec.processing.scale_to_pga(rec.load_record("elcentro_1940_ns_peknold"), np.float64(-1.0))
    assert "np.float64" not in str(exc.value) and "-1.0" in str(exc.value)


# ---------------------------------------------------------------------------------------------
# scene and command line
# ---------------------------------------------------------------------------------------------

def _ground_motion(ground_x):
    from masonrydam.effects.ground_motion import build_ground_motion
    from masonrydam.scene.schema import normalize

    spec = normalize(_block_on_ground_scene(ground_x))["stages"][0]["ground_motion"]["x"]
    return build_ground_motion(spec, 0, "stages[0].ground_motion.x", 0.01)


def test_scene_ground_motion_column(tmp_path):
    path = _two_components(tmp_path / "two.txt")
    gm = _ground_motion({"file": str(path), "units": "cm/s2", "dt": DT, "column": 1})
    assert float(np.max(np.abs(gm.values))) == pytest.approx(_peak(EW) * 0.01, rel=1e-12)  # m/s2
    assert gm.dt == DT and gm.attrs["column"] == 1
    # several value columns and no column: the error names the scene key to set
    with pytest.raises(SceneError) as exc:
        _ground_motion({"file": str(path), "units": "cm/s2", "dt": DT})
    assert exc.value.key == "stages[0].ground_motion.x.column"
    assert "stages[0].ground_motion.x.column = N" in str(exc.value) and "column=" not in str(exc.value)
    # units missing: the scene key, not units=
    with pytest.raises(SceneError) as exc:
        _ground_motion({"file": str(path), "dt": DT, "column": 0})
    assert exc.value.key == "stages[0].ground_motion.x.units"
    assert "set stages[0].ground_motion.x.units" in str(exc.value) and "units=" not in str(exc.value)
    with pytest.raises(SceneError) as exc:
        _ground_motion({"file": str(path), "units": "cm/s2", "dt": DT, "column": 5})
    assert exc.value.key == "stages[0].ground_motion.x.column"


@pytest.mark.parametrize("ground,words", [
    ({"file": "x.txt", "column": "1"}, "expected an integer"),
    ({"file": "x.txt", "column": -1}, "must be >= 0"),
    ({"record": "elcentro_1940_ns_peknold", "column": 0}, "applies to 'file' only"),
    ({"values": [0.0, 1.0], "dt": 0.01, "column": 0}, "applies to 'file' only"),
    ({"pulse": {"shape": "half_sine", "amplitude": 1.0, "duration": 0.1}, "column": 0}, "no meaning for a pulse"),
])
def test_scene_column_is_validated_with_its_key(ground, words):
    from masonrydam.scene.schema import normalize

    with pytest.raises(SceneError) as exc:
        normalize(_block_on_ground_scene(ground))
    assert exc.value.key == "stages[0].ground_motion.x.column" and words in str(exc.value)


@pytest.mark.slow
def test_cli_records_show_column_and_option_names(tmp_path, capsys):
    path = _two_components(tmp_path / "two.txt")
    png = tmp_path / "two.png"
    assert cli_main(["records", "show", str(path), "--units", "gal", "--dt", str(DT), "--column", "1",
                     "-o", str(png)]) == 0
    out = capsys.readouterr().out
    assert f"({_peak(EW) * 0.01 / G:.4f} g)" in out and png.is_file()
    # missing units: the message names --units, not the Python argument
    assert cli_main(["records", "show", str(path), "--dt", str(DT), "--column", "1", "-o", str(png)]) == 2
    err = capsys.readouterr().err
    assert "--units" in err and "units=" not in err
    # several columns and no --column; a --dt that contradicts a time column
    assert cli_main(["records", "show", str(path), "--units", "gal", "--dt", str(DT), "-o", str(png)]) == 2
    err = capsys.readouterr().err
    assert "--column N" in err and "column=" not in err
    csv = _csv_with_header(tmp_path / "rec.csv")
    assert cli_main(["records", "show", str(csv), "--dt", "0.01", "-o", str(png)]) == 2
    err = capsys.readouterr().err
    assert "--dt 0.01 contradicts the time column" in err and "0.005 s" in err
    assert cli_main(["records", "show", str(csv), "-o", str(png)]) == 0
    assert f"({_peak(NS):.4f} g)" in capsys.readouterr().out
