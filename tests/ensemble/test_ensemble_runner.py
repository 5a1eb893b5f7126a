"""Ensembles on dask (masonrydam.ensemble.runner): a sliding block under 3 records x 4
intensities x 2 friction angles on a LocalCluster of 2 workers gives the same numbers as the members run one by
one; resuming after an interrupted ensemble runs only the missing members; the dataset has the ensemble's dims,
units and status; an unreachable scheduler is a named error. The members' physics is checked in
tests/test_ensemble_spec.py (against Newmark's sliding block) and the fragility fit in tests/test_fragility.py.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from masonrydam.cli.main import main
from masonrydam.ensemble import enumerate_members, load_spec, member_measures
from masonrydam.ensemble.runner import members_dir, run_ensemble, run_member
from masonrydam.errors import MasonrydamError
from test_ensemble_spec import BASE, RECORDS3

ENSEMBLE = f"""
[ensemble]
name = "block_test"
scene = "base.toml"
[axes.records]
names = {json.dumps(RECORDS3)}
[axes.intensity]
scale_to_pga = ["0.05 g", "0.1 g", "0.2 g", "0.3 g"]
[[axes.parameters]]
key = "joints.joints.friction_angle"
values = [11.31, 16.7]
"""


@pytest.fixture(scope="module")
def ensemble(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ens")
    (folder / "base.toml").write_text(BASE.replace("duration = 0.4", "duration = 0.3"))
    path = folder / "ens.toml"
    path.write_text(ENSEMBLE)
    out = folder / "ens.nc"
    ds = run_ensemble(path, out, workers=2, progress=False)
    return path, out, ds


@pytest.mark.slow
def test_dask_ensemble_equals_the_members_run_one_by_one(ensemble, tmp_path):
    path, out, ds = ensemble
    assert dict(ds.sizes) == {"record": 3, "intensity": 4, "p_friction_angle": 2}
    assert ds.attrs["workers"] == 2 and (ds.status.values == 0).all()
    spec = load_spec(path)
    members = enumerate_members(spec)
    assert len(members) == 24
    for m in members[::5]:  # a sample of members, one by one in this process
        rec = run_member(m, str(tmp_path), lambda d: member_measures(d, spec=spec))
        here = ds.isel({n: i for n, i in m.position.items()})
        for k, v in rec["measures"].items():
            assert here[k].item() == pytest.approx(v, rel=1e-12, abs=1e-15), (m.coords, k)
    # the demand grows with the intensity and falls with the friction (Newmark: less excess over mu g)
    slip = ds.peak_slip_joints
    assert (slip.diff("intensity") >= -1e-9).all()
    assert (slip.isel(p_friction_angle=1) <= slip.isel(p_friction_angle=0) + 1e-9).all()
    assert slip.attrs["units"] == "m" and ds.wall_time.attrs["units"] == "s"
    assert ds.intensity.attrs["units"] == "m/s2"
    with xr.open_dataset(out) as back:
        np.testing.assert_array_equal(back.peak_slip_joints.values, slip.values)


@pytest.mark.slow
def test_resume_runs_only_the_missing_members(ensemble, tmp_path, capsys):
    path, out, ds = ensemble
    store = members_dir(out)
    files = sorted(store.glob("*.json"))
    assert len(files) == 24
    killed = files[:5]
    mtimes = {p.name: p.stat().st_mtime_ns for p in files[5:]}
    for p in killed:  # as if the ensemble had been killed before these finished
        p.unlink()
    again = run_ensemble(path, out, workers=1, progress=True)
    err = capsys.readouterr().err
    assert "5 to run" in err
    assert {p.name: p.stat().st_mtime_ns for p in sorted(store.glob("*.json")) if p.name in mtimes} == mtimes
    assert sorted(p.name for p in store.glob("*.json")) == [p.name for p in files]
    np.testing.assert_array_equal(again.peak_slip_joints.values, ds.peak_slip_joints.values)


@pytest.mark.slow
def test_unreachable_scheduler_and_bad_workers_are_named(ensemble, capsys):
    path, out, _ = ensemble
    with pytest.raises(MasonrydamError, match="--scheduler tcp://127.0.0.1:9"):
        run_ensemble(path, out.with_name("x.nc"), scheduler="tcp://127.0.0.1:9", progress=False)
    assert main(["ensemble", str(path), "-o", str(out.with_name("y.nc")), "--workers", "0"]) == 2
    assert "--workers" in capsys.readouterr().err


@pytest.mark.slow
def test_report_from_the_command_line(ensemble, tmp_path, capsys):
    _, out, _ = ensemble
    assert main(["ensemble-report", str(out), "--demand", "peak_slip_joints", "--limit", "0.02",
                 "-o", str(tmp_path / "rep")]) == 0
    text = capsys.readouterr().out
    assert "peak_slip_joints" in text and (tmp_path / "rep_ida.png").exists()
    assert (tmp_path / "rep_fragility.csv").read_text().count("\n") == 3  # a header and one row per friction
    assert main(["ensemble-report", str(out), "--demand", "nothing"]) == 2


def test_fixed_keys_of_every_member(tmp_path):
    """``[ensemble] set``: scene keys changed for every member (here the stage's duration); a bad one is named."""
    from masonrydam.errors import SceneError

    (tmp_path / "base.toml").write_text(BASE)
    path = tmp_path / "ens.toml"
    path.write_text(ENSEMBLE.replace('scene = "base.toml"', 'scene = "base.toml"\nset = { "stages[1].duration" = 0.2 }'))
    members = enumerate_members(load_spec(path))
    assert {m.scene["stages"][1]["duration"] for m in members} == {0.2}
    path.write_text(ENSEMBLE.replace('scene = "base.toml"', 'scene = "base.toml"\nset = { "stages[7].duration" = 0.2 }'))
    with pytest.raises(SceneError) as err:
        load_spec(path)
    assert err.value.key == "ensemble.set.stages[7].duration"


@pytest.mark.slow
def test_changed_outcomes_are_rerun_and_errors_are_outcomes(ensemble, tmp_path, capsys):
    """An outcome obtained with another scene (its fingerprint differs) is run again, not reused; a member that
    cannot be run (here a scene the schema refuses) is an outcome with status 3 and its reason."""
    import dataclasses

    from masonrydam.ensemble.runner import STATUS_ERROR, fingerprint

    path, out, _ = ensemble
    store = members_dir(out)
    spec = load_spec(path)
    m = enumerate_members(spec)[7]
    changed = dataclasses.replace(m, scene={**m.scene, "model": {**m.scene["model"], "name": "other"}})
    assert fingerprint(changed, {}) != fingerprint(m, {})
    rec_path = store / f"{m.member_id}.json"
    rec = json.loads(rec_path.read_text())
    rec["fingerprint"] = "from-another-scene"
    rec_path.write_text(json.dumps(rec))
    run_ensemble(path, out, workers=1, progress=True)
    assert "23 already in" in capsys.readouterr().err
    assert json.loads(rec_path.read_text())["fingerprint"] != "from-another-scene"
    bad = dataclasses.replace(m, scene={**m.scene, "stages": [m.scene["stages"][0], {**m.scene["stages"][1],
                                                                                     "integrator": "leapfrog"}]})
    rec = run_member(bad, str(tmp_path), lambda d: {})
    assert rec["status"] == STATUS_ERROR and "integrator" in rec["reason"]


@pytest.mark.slow
def test_report_with_a_demand_and_no_limit_draws_its_ida(ensemble, tmp_path, capsys):
    _, out, ds = ensemble
    assert main(["ensemble-report", str(out), "--demand", "peak_slip_joints", "-o", str(tmp_path / "r")]) == 0
    assert "collapse" in capsys.readouterr().out
    assert main(["ensemble-report", str(out), "--limit", "0.01"]) == 2
