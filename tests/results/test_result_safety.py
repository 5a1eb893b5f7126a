"""A run never destroys a result, and a stopped run keeps every converged step.

- the working file ``NAME.partial.nc`` is moved over the target only when the run completes: a failing
  run leaves an earlier result byte for byte, also while another process holds it open;
- Ctrl-C (SIGINT) and SIGTERM stop a real ``masonrydam run`` process at the end of a step with exit
  code 130 / 143, one line naming the step and the file, and no traceback; the steps kept equal those
  of an uninterrupted run (the kernels are deterministic);
- a second request aborts at once; SIGKILL leaves the earlier result and a readable working file
  that :func:`masonrydam.results.files.open_result` reports as left by a run that did not finish.

The physics of the scene (the Newmark sliding block of scenes.sliding_block) is checked in test_dynamics; here the
kept steps are compared with a complete run of the same scene.
"""
from __future__ import annotations

import hashlib
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
import xarray as xr

import masonrydam
from masonrydam.cli.main import main
from masonrydam.errors import RunStopped
from masonrydam.results.files import IncompleteResultWarning, open_result, partial_path
from masonrydam.scene.stopping import StopRequests
from scenes import sliding_block, toml_text

def sliding_toml(duration) -> str:
    """The Newmark sliding block of scenes.sliding_block (mu = 0.2, a 0.4 g rectangular pulse of 0.2 s),
    stepped with the trapezoidal rule for ``duration`` s, as a TOML scene for the command line."""
    return toml_text(sliding_block(duration=duration, integrator="newmark_average"))


def sha256(path) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def failing_scene():
    """Fails after validation, in its first dynamic steps: one Newton iteration allowed, no sub-steps,
    and the block starts to slide (as in test_dynamics' non-converging test)."""
    return sliding_block(duration=0.2, dt=0.002, max_iterations=1, max_substeps=0, joint_space="off")


def write_earlier_result(path):
    ds = masonrydam.run(sliding_block(duration=0.05), output=path)
    assert ds.attrs["completed"] == "true"
    return ds


@pytest.mark.slow
def test_failing_run_keeps_an_open_earlier_result(tmp_path):
    """Another process holds the earlier result open (lazily, with xarray); a run that fails after
    validation leaves that file byte for byte, the reader reads its old values, and the failed run's
    converged steps go to out.partial.nc, which the error names."""
    out = tmp_path / "out.nc"
    old = write_earlier_result(out)
    digest = sha256(out)
    reader = subprocess.Popen(
        [sys.executable, "-c",
         "import sys, xarray as xr; ds = xr.open_dataset(sys.argv[1]); print('open', flush=True); "
         "sys.stdin.readline(); u = ds.displacement.values; print(repr(float(abs(u).sum())), u.shape[0], "
         "ds.attrs['completed'], flush=True)", str(out)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert reader.stdout.readline().strip() == "open"
        with pytest.raises(masonrydam.ConvergenceError) as ei:
            masonrydam.run(failing_scene(), output=out)
        answer, _ = reader.communicate("go\n", timeout=60)
    finally:
        reader.kill()
    total, steps, completed = answer.split()
    assert float(total) == float(np.abs(old.displacement.values).sum())
    assert int(steps) == old.sizes["step"] and completed == "true"
    assert sha256(out) == digest
    notes = " ".join(getattr(ei.value, "__notes__", []))
    partial = partial_path(out)
    assert str(partial) in notes and "unchanged" in notes
    with pytest.warns(IncompleteResultWarning, match="status 'failed'"):
        ds = open_result(partial)
    assert ds.attrs["completed"] == "false" and ds.attrs["status"] == "failed"
    assert "ConvergenceError" in ds.attrs["status_reason"]
    assert ds.sizes["step"] >= 2 and np.isfinite(ds.displacement.values).all()


def test_failing_run_without_earlier_result_keeps_its_steps_at_the_target(tmp_path):
    out = tmp_path / "out.nc"
    with pytest.raises(masonrydam.ConvergenceError) as ei:
        masonrydam.run(failing_scene(), output=out)
    assert f"kept in {out}" in " ".join(ei.value.__notes__)
    assert not partial_path(out).exists()
    ds = xr.load_dataset(out)
    assert ds.attrs["status"] == "failed" and ds.sizes["step"] >= 2


def test_completed_run_replaces_the_result_and_leaves_no_working_file(tmp_path):
    """A completed run moves its working file over the earlier result (a stale working file of an
    earlier stopped run is overwritten), and the new result is the new scene's."""
    out = tmp_path / "out.nc"
    write_earlier_result(out)
    partial_path(out).write_bytes(b"left by an earlier stopped run")
    ds = masonrydam.run(sliding_block(duration=0.1), output=out)
    assert not partial_path(out).exists()
    again = xr.load_dataset(out)
    assert again.attrs["completed"] == "true" and again.sizes["step"] == ds.sizes["step"]
    assert float(again.time.values[-1]) == pytest.approx(0.1)


def test_output_path_errors_come_before_any_work(tmp_path, monkeypatch):
    run_module = sys.modules["masonrydam.scene.run"]

    def _forbidden(*a, **k):
        raise AssertionError("the mesh was built although the output path is unusable")

    monkeypatch.setattr(run_module, "build_mesh", _forbidden)
    with pytest.raises(masonrydam.MasonrydamError, match="is a folder"):
        masonrydam.run(sliding_block(), output=tmp_path)
    with pytest.raises(masonrydam.MasonrydamError, match="does not exist; create it first"):
        masonrydam.run(sliding_block(), output=tmp_path / "missing" / "out.nc")


# ------------------------------------------------------------------------------------------------
# stopping a real process
# ------------------------------------------------------------------------------------------------
def start_cli_run(tmp_path, duration=600.0):
    scene = tmp_path / "slide.toml"
    scene.write_text(sliding_toml(duration))
    out = tmp_path / "out.nc"
    proc = subprocess.Popen([sys.executable, "-m", "masonrydam.cli.main", "run", str(scene), "-o", str(out),
                             "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return proc, out


def stop_lines(stderr: str) -> list[str]:
    """The lines of ``stderr`` but the scene's warning (the stage runs 600 s on a pulse of 0.2 s, on purpose: a run
    long enough to be stopped)."""
    return [ln for ln in stderr.strip().splitlines() if not ln.startswith("masonrydam: warning: ")]


def wait_for_steps(proc, work, settle=2.0, timeout=120.0):
    """Wait until the working file exists, then ``settle`` seconds more (the run is stepping)."""
    deadline = time.time() + timeout
    while not work.exists():
        assert proc.poll() is None, "the run ended by itself: " + proc.stderr.read()
        assert time.time() < deadline, "no working file appeared"
        time.sleep(0.05)
    time.sleep(settle)
    assert proc.poll() is None, "the run ended by itself"


@pytest.mark.parametrize("sig, code, status", [(signal.SIGINT, 130, "interrupted"),
                                               (signal.SIGTERM, 143, "terminated")])
@pytest.mark.slow
def test_signal_stops_at_the_end_of_a_step_and_keeps_the_steps(tmp_path, sig, code, status):
    """SIGINT / SIGTERM on `masonrydam run` over an earlier result: exit 130 / 143, one line naming the
    step, the time and the file, no traceback; the earlier result stays byte for byte; the kept steps
    are those of an uninterrupted run, the last one the step it stopped at."""
    proc, out = start_cli_run(tmp_path)
    out.write_bytes(b"an earlier result")
    work = partial_path(out)
    wait_for_steps(proc, work)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == code, stderr
    lines = stop_lines(stderr)
    assert "Traceback" not in stderr and len(lines) == 1, stderr
    line = lines[0]
    assert line.startswith("masonrydam: stopped at step ") and f"kept in {work}" in line, line
    assert "(t = " in line and "of 300000" in line
    assert out.read_bytes() == b"an earlier result"
    with pytest.warns(IncompleteResultWarning, match=f"status '{status}'"):
        ds = open_result(work)
    assert ds.attrs["completed"] == "false" and ds.attrs["status"] == status
    k = int(line.split("stopped at step ")[1].split()[0])
    assert ds.attrs["status_reason"].startswith(f"stopped at step {k} of 300000")
    t_last = float(ds.time.values[-1])
    assert t_last == pytest.approx(0.002 * k)
    assert f"{ds.sizes['step']} recorded steps kept" in line
    # the kept history equals an uninterrupted run of the same scene up to the step it stopped at (to
    # round-off: the static solve's last bits differ between processes with a threaded direct solver)
    ref = masonrydam.run(sliding_block(duration=t_last, dt=0.002, integrator="newmark_average"))
    assert ref.sizes["step"] == ds.sizes["step"]
    u_ref = ref.displacement.values
    np.testing.assert_allclose(ds.displacement.values, u_ref, rtol=0, atol=1e-8 * np.abs(u_ref).max())
    np.testing.assert_array_equal(ds.joint_state.values, ref.joint_state.values)


@pytest.mark.slow
def test_two_quick_ctrl_c_end_the_process_without_a_traceback(tmp_path):
    """Two SIGINT in a row (the second stops at once if the step has not ended yet): exit 130, one
    line, no traceback, and a readable file with the steps converged before."""
    proc, out = start_cli_run(tmp_path)
    wait_for_steps(proc, partial_path(out))
    proc.send_signal(signal.SIGINT)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    lines = stop_lines(stderr)
    assert "Traceback" not in stderr and len(lines) == 1, stderr
    assert lines[0].startswith("masonrydam: stopped ") and f"kept in {out}" in lines[0]
    with pytest.warns(IncompleteResultWarning, match="status 'interrupted'"):
        ds = open_result(out)
    assert ds.sizes["step"] >= 3 and np.isfinite(ds.displacement.values).all()


@pytest.mark.slow
def test_sigkill_leaves_the_earlier_result_and_a_readable_running_file(tmp_path):
    proc, out = start_cli_run(tmp_path)
    write_earlier_result(out)
    digest = sha256(out)
    work = partial_path(out)
    wait_for_steps(proc, work)
    proc.kill()
    proc.communicate(timeout=60)
    assert sha256(out) == digest
    with pytest.warns(IncompleteResultWarning, match="did not finish .status 'running'.*killed"):
        ds = open_result(work)
    assert ds.attrs["completed"] == "false" and ds.sizes["step"] >= 3
    assert np.isfinite(ds.displacement.values).all()


def test_second_request_aborts_at_once(tmp_path, monkeypatch):
    """Two requests inside one step: the run stops in that step, without converging it, keeps the steps
    before it and raises RunStopped (what the command line turns into one line and exit 130)."""
    from masonrydam.solvers.dynamic import DynamicSolver

    calls = {"n": 0}
    original = DynamicSolver._maybe_emit

    def emit_then_signal(self, stage, k, st, n_steps):
        original(self, stage, k, st, n_steps)
        calls["n"] += 1
        if calls["n"] == 5:  # inside the sixth step: two Ctrl-C before it converges
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGINT)

    previous = signal.getsignal(signal.SIGINT)
    monkeypatch.setattr(DynamicSolver, "_maybe_emit", emit_then_signal)
    out = tmp_path / "out.nc"
    with pytest.raises(RunStopped) as ei:
        masonrydam.run(sliding_block(duration=1.0), output=out)
    assert signal.getsignal(signal.SIGINT) is previous, "the run must restore the signal handlers"
    err = ei.value
    assert err.status == "interrupted" and err.exit_code == 130 and "at once" in str(err)
    assert err.kept == out
    ds = xr.load_dataset(out)
    assert ds.attrs["status"] == "interrupted" and "at once" in ds.attrs["status_reason"]
    # gravity step, the initial state and the five converged dynamic steps; none half written
    assert ds.sizes["step"] == err.steps == 7
    assert np.isfinite(ds.displacement.values).all() and np.isfinite(ds.energy_kinetic.values[1:]).all()


def test_an_abort_waits_for_the_end_of_a_write():
    stops = StopRequests()
    stops._handle(signal.SIGTERM, None)
    assert stops.requested() == "terminated"
    with pytest.raises(KeyboardInterrupt):
        with stops.writing():
            stops._handle(signal.SIGINT, None)  # deferred: the write is not cut
            written = True
    assert written and stops.requested() == "terminated"
    with pytest.raises(KeyboardInterrupt):
        stops._handle(signal.SIGINT, None)


# ------------------------------------------------------------------------------------------------
# command-line messages
# ------------------------------------------------------------------------------------------------
def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return code, err


def test_file_system_mistakes_are_one_line_messages(tmp_path, capsys):
    scene = tmp_path / "slide.toml"
    scene.write_text(sliding_toml(0.01))
    missing = tmp_path / "missing"
    cases = [
        (("run", scene, "-o", tmp_path), "is a folder"),
        (("run", scene, "-o", missing / "out.nc"), f"the folder '{missing}' does not exist"),
        (("run", tmp_path, "-o", tmp_path / "x.nc"), "is a folder; give a scene TOML file"),
        (("check", tmp_path), "is a folder; give a scene TOML file"),
        (("export-mesh", scene, "-o", missing / "mesh.vtu"), "does not exist"),
        (("records", "show", "elcentro_1940_ns_peknold", "-o", missing / "r.png"), "does not exist"),
    ]
    for argv, text in cases:
        code, err = cli(capsys, *argv)
        assert code == 2 and text in err and len(err.strip().splitlines()) == 1, (argv, err)


@pytest.mark.slow
def test_plot_names_what_is_wrong_with_the_file(tmp_path, capsys):
    text = tmp_path / "notes.nc"
    text.write_text("not a result")
    code, err = cli(capsys, "plot", text)
    assert code == 2 and "is not a netCDF file" in err
    empty = tmp_path / "empty.nc"
    s = sliding_block()
    s["supports"] = []  # a mechanism before the first step: a result file without steps
    with pytest.raises(masonrydam.MechanismError):
        masonrydam.run(s, output=empty)
    code, err = cli(capsys, "plot", empty)
    assert code == 2 and "has no steps to plot" in err
    good = tmp_path / "good.nc"
    write_earlier_result(good)
    code, err = cli(capsys, "plot", good, "-o", tmp_path / "missing" / "p.png")
    assert code == 2 and "does not exist" in err
    code, err = cli(capsys, "plot", good, "-o", tmp_path / "p.png")
    assert code == 0 and (tmp_path / "p.png").stat().st_size > 1000


def test_version(capsys):
    with pytest.raises(SystemExit) as ei:
        main(["--version"])
    assert ei.value.code == 0
    assert capsys.readouterr().out.strip() == f"masonrydam {masonrydam.__version__}"


@pytest.mark.parametrize("flag", ["--version", "--help"])
def test_version_and_help_import_no_numerics(flag):
    """``masonrydam --version`` and ``--help`` answer without importing numpy, numba, scipy, xarray or any room
    below the command line (target: under 0.3 s on any machine; the start-up is timed by
    benchmarks/bench_default_scene.py, not here). Before, --version imported the solvers and took 1.1-2.2 s."""
    heavy = ("numpy", "numba", "scipy", "xarray", "obspy", "gmsh", "masonrydam.scene", "masonrydam.solvers")
    code = ("import sys\n"
            "from masonrydam.cli.main import main\n"
            "try:\n"
            f"    main([{flag!r}])\n"
            "except SystemExit as e:\n"
            "    assert e.code == 0, e.code\n"
            f"print('LOADED', sorted(m for m in sys.modules if m.split('.')[0] in {heavy!r} or m in {heavy!r}))\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = p.stdout.rsplit("LOADED", 1)[1].strip()
    assert loaded == "[]", f"masonrydam {flag} imported {loaded}"
    assert ("masonrydam" in p.stdout.splitlines()[0]) if flag == "--version" else ("usage: masonrydam" in p.stdout)


def test_summary_wall_time_is_the_whole_process(tmp_path):
    """``masonrydam run`` as a process: the summary's wall time counts from the package's first import (the
    process's start less the interpreter's own) and is printed after the result is read back, so it is what
    ``time masonrydam run`` shows. Before, it left out the imports, the reading back and the
    interpreter's teardown: 2.4 of 4.4 s on the default scene (Xeon). The margin allows for the start of the
    process (fork, exec and the interpreter) and a loaded machine."""
    scene = tmp_path / "slide.toml"
    scene.write_text(sliding_toml(0.5))
    out = tmp_path / "out.nc"
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "masonrydam.cli.main", "run", str(scene), "-o", str(out),
                        "--no-progress"], capture_output=True, text=True)
    process = time.perf_counter() - t0
    assert p.returncode == 0, p.stderr
    said = float(re.search(r"wall time\s*:\s*([\d.]+) s", p.stdout).group(1))
    assert said <= process + 0.02
    assert said >= process - max(0.5, 0.15 * process), (said, process)
    with xr.open_dataset(out) as ds:  # the quick exit kept the file whole
        assert ds.attrs["status"] == "completed"


@pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")
def test_summary_wall_time_leaves_out_what_a_shell_did_before_exec(tmp_path):
    """A shell that runs ``masonrydam run`` as its last command execs it in its own process (README command 1,
    ``... && pip install . && masonrydam run --default``): the process's start from /proc is then the shell's, and
    the summary said 89 s for a 25 s run after a 65 s install. It counts from the package's import instead: the
    2 s the shell sleeps first are not in it."""
    scene = tmp_path / "slide.toml"
    scene.write_text(sliding_toml(0.5))
    out = tmp_path / "out.nc"
    command = (f"sleep 2 && exec {shlex.quote(sys.executable)} -m masonrydam.cli.main run {shlex.quote(str(scene))} "
               f"-o {shlex.quote(str(out))} --no-progress")
    t0 = time.perf_counter()
    p = subprocess.run(["bash", "-c", command], capture_output=True, text=True)
    process = time.perf_counter() - t0 - 2.0  # the run after the shell's sleep
    assert p.returncode == 0, p.stderr
    said = float(re.search(r"wall time\s*:\s*([\d.]+) s", p.stdout).group(1))
    assert said <= process + 0.02, (said, process)
    assert said >= process - max(0.5, 0.15 * process), (said, process)


def test_package_entry_points_load_on_first_use():
    """``masonrydam.run``, ``masonrydam.Scene`` and ``masonrydam.open_result`` are the scene's and the results'
    own objects, loaded when first asked for (PEP 562); an unknown name is an AttributeError naming it."""
    from masonrydam.results.files import open_result as files_open_result
    from masonrydam.scene import Scene, run

    assert masonrydam.run is run and masonrydam.Scene is Scene and masonrydam.open_result is files_open_result
    assert {"run", "Scene", "open_result"} <= set(dir(masonrydam))
    with pytest.raises(AttributeError, match="no_such_thing"):
        masonrydam.no_such_thing  # noqa: B018


def test_open_result_of_a_completed_run_is_silent(tmp_path):
    out = tmp_path / "out.nc"
    write_earlier_result(out)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ds = open_result(out)
    assert ds.attrs["status"] == "completed"


def test_a_run_never_truncates_another_runs_working_file(tmp_path):
    """A working file that another run is writing (HDF5's exclusive lock) is refused with a message; one
    left by an earlier run and open in a reader is replaced by a new file, the reader keeps its copy."""
    import netCDF4

    out = tmp_path / "out.nc"
    work = partial_path(out)
    busy = netCDF4.Dataset(work, "w")  # as a run writing to the same output holds it
    busy.createDimension("step", None)
    busy.sync()
    try:
        with pytest.raises(masonrydam.MasonrydamError, match="being written by another run"):
            masonrydam.run(sliding_block(duration=0.05), output=out)
    finally:
        busy.close()
    assert netCDF4.Dataset(work).dimensions["step"].isunlimited()
    write_earlier_result(out)
    with pytest.raises(masonrydam.ConvergenceError):
        masonrydam.run(failing_scene(), output=out)  # its steps stay in out.partial.nc
    stale = xr.open_dataset(work)  # a reader of the failed run's steps
    try:
        masonrydam.run(sliding_block(duration=0.1), output=out)
        assert not work.exists() and xr.load_dataset(out).attrs["completed"] == "true"
        assert stale.attrs["status"] == "failed" and np.isfinite(stale.displacement.values).all()
        assert stale.sizes["step"] >= 2
    finally:
        stale.close()


def test_progress_shows_what_a_static_step_is_doing(capsys):
    """The progress bar names the stage, the load factor, the Newton iteration and the residual of the
    step being solved, so that a long first step is visibly alive."""
    sc = sliding_block(duration=0.01)
    sc["solver"] = {"joint_space": "off"}
    masonrydam.run(sc, progress=True)
    err = capsys.readouterr().err
    assert "gravity: load factor 1, iteration 0, residual " in err
    # the last iteration shown is the converged one: the residual below the force tolerance (1e-6)
    last = re.findall(r"gravity: load factor 1, iteration (\d+), residual ([0-9.e+-]+)", err)[-1]
    assert int(last[0]) >= 1 and float(last[1]) < 1e-6
