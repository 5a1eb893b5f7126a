"""Output files that are never lost: checks before writing, the working file of a run, its atomic
replacement of the target, and a reader that says when a file is not a finished result.

A run writes to a *working file* beside its target, ``NAME.partial.nc`` for ``NAME.nc``
(:func:`partial_path`), so that the target is never truncated while a run is going on:

- the run completes: the working file is moved over the target with :func:`os.replace` (an atomic
  rename in one folder). A reader that holds the old file open keeps reading the old contents;
- the run ends early (an error after validation, Ctrl-C, SIGTERM): the working file is closed with
  ``completed = "false"`` and a ``status``; it takes the target's name when no file was there, and
  stays beside it otherwise, so an earlier result stays byte for byte;
- the process is killed (SIGKILL, power loss): the working file stays with ``status = "running"`` and
  every flushed step; :func:`open_result` says so when it opens it.
"""
from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import MasonrydamError, OutputError

try:  # HDF5's lock on a working file is seen through flock, where the platform has it (POSIX)
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None


#: first bytes of a netCDF classic file and of a netCDF-4 (HDF5) file
NETCDF_CLASSIC_MAGIC = b"CDF"
HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"


class IncompleteResultWarning(UserWarning):
    """A result file that is not a completed run: stopped, failed, or left by a killed process."""


def partial_path(target) -> Path:
    """The working file of a run whose result goes to ``target``: ``out.nc`` -> ``out.partial.nc``
    (``out`` -> ``out.partial``), in the same folder, so that :func:`os.replace` is an atomic rename."""
    t = Path(target)
    return t.with_name(f"{t.stem}.partial{t.suffix}")


def claim_working_file(work: Path) -> None:
    """Make ``work`` free for a new run. A working file left by an earlier run is unlinked rather than
    truncated, so a program that reads it keeps its contents; one that another run is still writing
    (it holds HDF5's exclusive lock, taken with ``flock``) is an error, since truncating it would
    destroy that run's steps. Without ``fcntl`` (or with HDF5's locking switched off) this check is
    skipped."""
    if not work.exists():
        return
    try:
        if fcntl is not None:
            with open(work, "rb") as fh:
                try:  # a shared lock is refused only while a writer holds the exclusive one
                    fcntl.flock(fh, fcntl.LOCK_SH | fcntl.LOCK_NB)
                except OSError:
                    raise OutputError(f"'{work}' is being written by another run to the same output; wait for "
                                      "it, stop it, or give another -o") from None
        work.unlink()
    except OutputError:
        raise
    except OSError as exc:  # a folder of that name, no permission
        raise OutputError(f"cannot replace '{work}', the working file of this output: "
                          f"{exc.strerror or exc}") from None


def settle_partial(work: Path, target: Path) -> Path:
    """Where the closed working file of a run that ended early stays (the path returned): at the
    target when no file is there, beside it (``work``) when one is (an earlier result, or one that
    another run wrote meanwhile), at the target when the working file was already moved there."""
    if not work.exists():
        return target
    if target.exists():
        return work
    os.replace(work, target)
    return target


def result_state_note(path, attrs: dict, steps: int) -> str | None:
    """A one-line note for a result file that is not a completed run (None for a completed one)."""
    if attrs.get("completed") == "true":
        return None
    status = str(attrs.get("status", "unknown"))
    if status == "running":
        return (f"'{path}' was left by a run that did not finish (status 'running'): the process was killed or "
                f"is still running; it holds {steps} recorded step(s)")
    reason = attrs.get("status_reason")
    return (f"'{path}' is an incomplete result (status '{status}'{': ' + str(reason) if reason else ''}); "
            f"it holds {steps} recorded step(s)")


def open_result(path, load: bool = True):
    """Open a result file written by :func:`masonrydam.run` as an ``xarray.Dataset`` (loaded in memory,
    or lazily with ``load=False``). A file that is not a completed run (``completed != "true"``) opens
    with an :class:`IncompleteResultWarning` that says what it is: a run that was stopped or failed (its
    ``status``), or one left by a killed process (``status = "running"``). A file that is not netCDF,
    or not a masonrydam result, raises :class:`~masonrydam.errors.OutputError` naming the path."""
    p = Path(path)
    if not p.exists():
        raise OutputError(f"result file '{p}' does not exist")
    if p.is_dir():
        raise OutputError(f"'{p}' is a folder, not a result file")
    with open(p, "rb") as fh:
        magic = fh.read(8)
    if not (magic.startswith(NETCDF_CLASSIC_MAGIC) or magic == HDF5_MAGIC):
        raise OutputError(f"'{p}' is not a netCDF file (a masonrydam result is written by `masonrydam run`)")
    try:
        ds = xr.load_dataset(p) if load else xr.open_dataset(p)
    except Exception as exc:  # netCDF4/h5netcdf/scipy backends raise OSError, ValueError, ...
        first = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
        raise OutputError(f"'{p}' is not a readable netCDF file ({first})") from None
    if "displacement" not in ds.variables or "step" not in ds.dims:
        ds.close()
        raise OutputError(f"'{p}' is a netCDF file but not a masonrydam result (no 'displacement' on 'step')")
    note = result_state_note(p, ds.attrs, int(ds.sizes["step"]))
    if note is not None:
        warnings.warn(note, IncompleteResultWarning, stacklevel=2)
    return ds


def step_position(ds, step: int | None, option: str = "--step", label: str = "the result") -> int:
    """Position along ``step`` of ``step``: a value of the ``step`` coordinate (0 or more), or a negative index
    from the end (None: the last step). MasonrydamError for a result without steps or a step not in it, naming
    ``option``, the step and the range."""
    n = int(ds.sizes.get("step", 0))
    if n == 0:
        raise MasonrydamError(f"{label} has no steps (status '{ds.attrs.get('status', '?')}': the run stopped "
                              "before its first converged step)")
    if step is None:
        return n - 1
    steps = np.asarray(ds["step"].values).astype(int)
    if step < 0:
        if -step > n:
            raise MasonrydamError(f"{option} {step}: the result has {n} steps ({int(steps.min())} to "
                                  f"{int(steps.max())}, or -1 to {-n} from the end)")
        return n + step
    hit = np.flatnonzero(steps == step)
    if not len(hit):
        raise MasonrydamError(f"{option} {step}: not a step of the result ({int(steps.min())} to "
                              f"{int(steps.max())}, or -1 to {-n} from the end)")
    return int(hit[0])
