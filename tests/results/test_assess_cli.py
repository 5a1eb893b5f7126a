"""``masonrydam assess`` (masonrydam.cli.main, masonrydam.results.assess): the stability table of a dam's
joint lines read back from a result file.

The printed normal and shear forces and sliding factor are the dataset's values at the printed precision;
the criteria of USACE EM 1110-2-2100 (2005), tables 3-2 and 3-4 (sliding factor 1.5 / 1.3 / 1.1,
resultant in the middle third / middle half / the base) are flagged on a cracked base whose resultant
lies at 0.8 L; the CSV holds the dataset's values to the last bit; a result without a reservoir and a step
not in the file are errors with exit code 2.

Scenes: 2D gravity dams (plane strain, thickness 1 m) on a Mohr-Coulomb base joint, full reservoir and
uplift: ``dam`` (H = 30 m, base 29 m, phi = 45 deg: sliding factor 2.09, resultant near the middle) and
``crack`` (base 20 m, stiff concrete, soft joint: the heel opens over 39 % of the base, sliding factor
1.535, resultant at 0.798 L).
"""
from __future__ import annotations

import copy
import csv

import pytest
import xarray as xr

import masonrydam
from masonrydam.cli.main import main
from scenes import dam_with_reservoir

pytest.importorskip("gmsh")

DAM = dam_with_reservoir(foundation_width=80.0, overrides={"reservoir.uplift.cracked": "full_head"})


def crack_scene():
    s = copy.deepcopy(DAM)
    s["mesh"]["parameters"].update(downstream_slope=0.5, foundation_width=40.0, foundation_depth=5.0,
                                   element_size=0.25)
    s["materials"]["dam"]["youngs_modulus"] = 1e13
    s["materials"]["foundation"]["youngs_modulus"] = 1e13
    s["joints"]["base_joint"].update(normal_stiffness=1e9, shear_stiffness=1e9, friction_angle=55.0)
    s["reservoir"]["level"] = 30.0
    s["stages"][1]["steps"] = 10
    return s


def dry_scene():
    s = copy.deepcopy(DAM)
    del s["reservoir"]
    s["stages"] = s["stages"][:1]
    return s


def _write(tmp_path_factory, name, scene):
    path = tmp_path_factory.mktemp(name) / f"{name}.nc"
    ds = masonrydam.run(scene, output=path)
    ds.close()
    return path


@pytest.fixture(scope="module")
def dam_nc(tmp_path_factory):
    return _write(tmp_path_factory, "dam", DAM)


@pytest.fixture(scope="module")
def crack_nc(tmp_path_factory):
    return _write(tmp_path_factory, "crack", crack_scene())


def load(path):
    with xr.open_dataset(path) as ds:
        return ds.load()


def table(out):
    """The header cells and the rows (name -> cells, '!' kept) of the printed table."""
    lines = out.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("section "))
    head = lines[k]
    rows = {}
    for line in lines[k + 1:]:
        if not line.strip():
            break
        cells = line.split()
        rows[cells[0]] = cells[1:]
    return head, rows


def number(cell):
    return float(cell.rstrip("!"))


def assess(capsys, *args):
    rc = main(["assess", *map(str, args)])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def test_table_matches_dataset(dam_nc, capsys):
    """Last step of the dam: rc 0; N and |T| in the header's force unit equal the dataset's to the printed
    3 decimals, the sliding factor and length too; the header names scene, stage, load factor and level;
    no '!' and the closing line says all sections pass."""
    rc, out, _ = assess(capsys, dam_nc)
    assert rc == 0
    ds = load(dam_nc)
    last = ds.isel(step=-1)
    head, rows = table(out)
    unit = head.split("N [")[1].split("]")[0]
    scale = {"kN": 1e3, "MN": 1e6}[unit]
    assert unit == "MN"  # N = 8.0 MN per m
    assert f"|T| [{unit}]" in head and f"U [{unit}]" in head
    assert set(rows) == set(ds.section.values.tolist())
    for k, name in enumerate(ds.section.values.tolist()):
        cells = rows[name]
        assert number(cells[0]) == pytest.approx(float(last.section_length[k]), abs=5e-4)
        assert number(cells[1]) == pytest.approx(float(last.normal_force[k]) / scale, abs=5e-4)
        assert number(cells[2]) == pytest.approx(float(last.shear_force[k]) / scale, abs=5e-4)
        assert number(cells[3]) == pytest.approx(float(last.sliding_safety_factor[k]), abs=5e-4)
        assert number(cells[4]) == pytest.approx(float(last.resultant_position[k]), abs=5e-4)
        assert number(cells[9]) == pytest.approx(float(last.uplift_force[k]) / scale, abs=5e-4)
    assert "!" not in "".join(" ".join(c) for c in rows.values())
    assert "scene 'dam_water'" in out and "stage 'water'" in out
    assert "load factor 1" in out and "reservoir level 28 m" in out
    assert out.rstrip().endswith("all 1 sections meet the usual criteria")


@pytest.mark.slow
def test_cracked_base_is_flagged(crack_nc, capsys, tmp_path):
    """Cracked base (resultant at 0.80 L, 39 % open, sliding factor 1.535): usual flags the resultant
    (middle third) and the cracked ratio but not the sliding factor, lists both under the table and says
    the section fails, still with rc 0; unusual flags the same (middle half, 75 % compressed); extreme
    (resultant within the base, SF >= 1.1) passes; the dataset's own values confirm the premise."""
    last = load(crack_nc).isel(step=-1, section=0)
    L = float(last.section_length)
    assert float(last.resultant_position) > 2 * L / 3
    assert float(last.cracked_length_ratio) > 0.25
    assert 1.5 < float(last.sliding_safety_factor) < 2.0

    rc, out, _ = assess(capsys, crack_nc)
    assert rc == 0
    _, rows = table(out)
    cells = rows["base_joint"]
    assert not cells[3].endswith("!")  # sliding factor 1.535 >= 1.5
    assert cells[4].endswith("!") and cells[5].endswith("!")  # resultant, m and x/L
    assert cells[6].endswith("!")  # cracked ratio
    assert "base_joint: resultant at 0.798 L, outside the middle third" in out
    assert "39.4 % of the line open" in out
    assert out.rstrip().endswith("1 of 1 sections fail the usual criteria")

    rc, out, _ = assess(capsys, crack_nc, "--condition", "unusual")
    assert rc == 0 and "outside the middle half" in out and "sections fail the unusual criteria" in out
    rc, out, _ = assess(capsys, crack_nc, "--condition", "extreme")
    assert rc == 0 and "!" not in out.split("section ", 1)[1].split("\n\n")[0]
    assert out.rstrip().endswith("all 1 sections meet the extreme criteria")


@pytest.mark.slow
def test_csv_round_trips(crack_nc, capsys, tmp_path):
    """--csv: a header row with units, one row per section whose floats equal the dataset's bit for bit
    (SI units), the step written, and the flags column naming the failures of the printed table."""
    out_csv = tmp_path / "crack.csv"
    rc, out, _ = assess(capsys, crack_nc, "--csv", out_csv)
    assert rc == 0 and f"wrote {out_csv}" in out
    ds = load(crack_nc)
    last = ds.isel(step=-1)
    with open(out_csv, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == ds.sizes["section"]
    head = list(rows[0])
    for col in ("normal_force [N]", "shear_force [N]", "sliding_safety_factor [1]", "resultant_position [m]",
                "heel_normal_stress [Pa]", "uplift_force [N]", "section_length [m]", "flags (usual)"):
        assert col in head
    for k, row in enumerate(rows):
        assert row["section"] == str(ds.section.values[k])
        assert int(row["step"]) == int(ds.step.values[-1])
        for col in head:
            var = col.split(" [")[0]
            if " [" in col and var in ds.variables:
                assert float(row[col]) == float(last[var].values[k]), col  # exact
        assert float(row["resultant_position_ratio [1]"]) == float(last.resultant_position[k] /
                                                                    last.section_length[k])
        assert "middle third" in row["flags (usual)"] and "open" in row["flags (usual)"]


def test_step_zero_and_negative(dam_nc, capsys):
    """--step 0 prints the gravity step (stage 'gravity', reservoir level 0, N = the dam's weight, |T| = 0);
    --step -5 is the same step counted from the end; --all-steps gives the lowest sliding factor at the
    last step of the filling."""
    ds = load(dam_nc)
    rc, out, _ = assess(capsys, dam_nc, "--step", 0)
    assert rc == 0
    assert "step 0 " in out and "stage 'gravity'" in out and "reservoir level 0 m" in out
    _, rows = table(out)
    assert number(rows["base_joint"][1]) == pytest.approx(float(ds.normal_force[0, 0]) / 1e6, abs=5e-4)
    assert number(rows["base_joint"][2]) == pytest.approx(0.0, abs=5e-4)
    rc, out2, _ = assess(capsys, dam_nc, "--step", -ds.sizes["step"])
    assert rc == 0 and table(out2) == table(out)
    rc, out, _ = assess(capsys, dam_nc, "--all-steps")
    assert rc == 0
    line = next(x for x in out.split("over all", 1)[1].splitlines() if x.startswith("base_joint"))
    cells = line.split()
    assert number(cells[1]) == pytest.approx(float(ds.sliding_safety_factor.min()), abs=5e-4)
    assert cells[2] == str(int(ds.step.values[-1]))


def test_dry_result_is_an_error(tmp_path_factory, capsys):
    """A scene without [reservoir] records no sections: rc 2 and a message that says so."""
    path = _write(tmp_path_factory, "dry", dry_scene())
    rc, out, err = assess(capsys, path)
    assert rc == 2 and out == ""
    assert "this result has no stability sections: the scene had no [reservoir]" in err
    assert err.startswith("masonrydam: error: ")


@pytest.mark.parametrize("step", [5, 99, -6])
def test_step_out_of_range_is_an_error(dam_nc, capsys, step):
    """Steps 0..4 (-1..-5 from the end): --step 5, 99, -6 give rc 2 and a message naming --step and the range."""
    rc, out, err = assess(capsys, dam_nc, "--step", step)
    assert rc == 2 and out == ""
    assert f"--step {step}" in err and ("0 to 4" in err or "-1 to -5" in err)


def test_missing_file_and_csv_folder(dam_nc, capsys, tmp_path):
    """A missing result file and a --csv in a missing folder: rc 2, as for `masonrydam plot`."""
    rc, _, err = assess(capsys, tmp_path / "none.nc")
    assert rc == 2 and "does not exist" in err
    rc, _, err = assess(capsys, dam_nc, "--csv", tmp_path / "no" / "t.csv")
    assert rc == 2 and "--csv" in err
