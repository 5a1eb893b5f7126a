"""Running an ensemble on dask.distributed, keeping every member's outcome, and the ensemble dataset.

Each member (:func:`masonrydam.ensemble.members.enumerate_members`) is one task: it runs the member's scene
(:func:`masonrydam.run`), measures its demands (:func:`masonrydam.ensemble.measures.member_measures`) and writes
its outcome as one small JSON file, ``<output>.members/<member_id>.json``, atomically (written beside, then
renamed). A member that fails (a mechanism or collapse, no convergence, a numerical failure) is an outcome,
recorded with its status and reason, not a crash of the ensemble. A second call with the same file skips the
members whose outcome is already there (the run is resumable after a kill). The dataset is assembled from the
outcomes: dims ``record``, ``intensity``, the swept parameters (``p_<name>``) and ``sample``, one variable per
demand with units and a long name, ``status`` and ``status_reason``, ``wall_time``; written to ``output`` (netCDF,
readable by ``xarray.open_dataset``).

Execution: a ``dask.distributed.LocalCluster`` of ``workers`` single-threaded processes by default, or the
scheduler at ``scheduler`` (``tcp://host:8786``): a user who outgrows one machine changes one option. Each
worker first runs a short version of the base scene (numba compiles or loads its cache once per worker, not
inside the first member's wall time). Progress: members done, failed and the estimated time left.

Why a folder of JSON outcomes and not one shared store: workers write concurrently and a killed ensemble must
keep what finished; one file per member needs no locking and makes resuming a directory listing.
"""
from __future__ import annotations

import contextlib
import copy
import functools
import hashlib
import io
import json
import math
import os
import sys
import time
from pathlib import Path

import numba
import numpy as np
import xarray as xr

import masonrydam

from ..errors import ConvergenceError, MasonrydamError, MechanismError, NumericalError
from ..scene.scene import Scene
from .measures import measure_attrs, member_measures
from .members import enumerate_members, member_axes, sample_coordinates
from .spec import load_spec

#: member status codes (the dataset's ``status``)
STATUS_COMPLETED = 0
#: a mechanism or collapse: the structure found no equilibrium (an outcome). A dynamic stage that finds none
#: within its step cuts is counted here too, as incremental dynamic analysis does (Vamvatsikos & Cornell 2002,
#: Earthq. Eng. Struct. Dyn. 31(3): non-convergence taken as collapse); its reason says so
STATUS_COLLAPSE = 1
STATUS_NUMERICAL = 2  # a numerical failure before the record (a static stage), excluded from fragility fits
STATUS_ERROR = 3  # the member could not be run (a model error, an exception): excluded, with its reason
STATUS_NOT_RUN = -1
STATUS_MEANINGS = ("0 completed, 1 collapse, mechanism or no convergence in the dynamic stage, 2 numerical failure "
                   "before it, 3 error (not run through), -1 not run")


def members_dir(output: str | os.PathLike) -> Path:
    """The folder of the members' outcomes beside ``output``."""
    p = Path(output)
    return p.with_name(p.name + ".members")


def _write_json_atomic(path: Path, data: dict) -> None:
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps(data, sort_keys=True, default=float))
    os.replace(tmp, path)


def fingerprint(member, settings: dict) -> str:
    """A hash of what decides a member's outcome: its whole scene (base scene, fixed keys, record, intensity,
    parameters) and the ensemble ``settings`` that shape its measures (demand sets, history). An outcome in the
    store is reused only when its fingerprint is the member's (a changed base scene reruns the members)."""
    text = json.dumps({"scene": member.scene, "base_dir": str(member.base_dir), **settings}, sort_keys=True,
                      default=str)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def run_member(member, store: str, measure, keep_history: bool = False, fp: str = "",
               dynamic_stage: str | None = None) -> dict:
    """Run one member (a task on a worker): its scene, its measures (``measure(ds) -> dict``), its outcome
    written to ``store/<member_id>.json``; returns the outcome (dict: member_id, fingerprint, coords, status,
    reason, wall_time, measures). Every failure is an outcome: a mechanism, or no convergence in the dynamic
    stage ``dynamic_stage``, is a collapse; other non-convergence a numerical failure; anything else an error
    with its type and message."""
    store = Path(store)
    history = store / f"{member.member_id}.nc" if keep_history else None
    t0 = time.perf_counter()
    status, reason, measures = STATUS_COMPLETED, "", {}
    threads = numba.get_num_threads()
    # one numba thread (for this task's thread): the members share the cores, one worker process each, and a
    # member's composite joints would otherwise spread over every core too (InterfaceGroup._evaluate_kernel)
    numba.set_num_threads(1)
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            ds = masonrydam.run(Scene(member.scene, base_dir=member.base_dir), output=history)
        measures = measure(ds)
        ds.close()
    except MechanismError as exc:
        status, reason = STATUS_COLLAPSE, f"{type(exc).__name__}: {exc}"
    except (ConvergenceError, NumericalError) as exc:
        in_record = dynamic_stage is not None and f"stage '{dynamic_stage}'" in str(exc)
        status = STATUS_COLLAPSE if in_record else STATUS_NUMERICAL
        reason = (("no convergence in the dynamic stage, counted as collapse: " if in_record else "")
                  + f"{type(exc).__name__}: {exc}")
    except Exception as exc:  # noqa: BLE001 (an outcome, not a crash of the ensemble)
        status, reason = STATUS_ERROR, f"{type(exc).__name__}: {exc}"
    finally:
        numba.set_num_threads(threads)
    out = {"member_id": member.member_id, "fingerprint": fp, "coords": member.coords, "status": status,
           "reason": reason, "wall_time": time.perf_counter() - t0, "measures": measures}
    _write_json_atomic(store / f"{member.member_id}.json", out)
    return out


def done_members(store: Path) -> dict[str, dict]:
    """The outcomes already in ``store`` (member_id -> outcome); unreadable files are ignored (rerun)."""
    out = {}
    if not store.is_dir():
        return out
    for p in store.glob("*.json"):
        try:
            rec = json.loads(p.read_text())
            out[rec["member_id"]] = rec
        except (OSError, ValueError, KeyError, TypeError):
            continue
    return out


def _warm(scene: dict, base_dir: str) -> float:
    """A short run of ``scene`` on a worker (numba compiles or loads its cache); returns its wall time (s)."""
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            masonrydam.run(Scene(scene, base_dir=base_dir))
        except masonrydam.MasonrydamError:
            pass  # a warm-up that fails still compiled what it reached
    return time.perf_counter() - t0


def short_scene(scene: dict, steps: int = 3) -> dict:
    """``scene`` with every dynamic stage cut to ``steps`` steps (for the warm-up)."""
    s = copy.deepcopy(scene)
    for st in s.get("stages", []):
        if st.get("type") == "dynamic":
            st.pop("duration", None)
            st["steps"] = steps
    return s


def connect(workers: int | None = None, scheduler: str | None = None, timeout: float = 10.0):
    """A ``dask.distributed.Client``: to ``scheduler`` (an address), or to a new LocalCluster of ``workers``
    single-threaded worker processes. MasonrydamError naming ``--scheduler`` (or ``[execution] scheduler``)
    when it cannot be reached."""
    # dask.distributed (a second to import) only for running an ensemble
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            return Client(scheduler, timeout=timeout)
        except (OSError, TimeoutError, ValueError) as exc:
            raise MasonrydamError(f"--scheduler {scheduler} ([execution] scheduler): cannot reach the dask "
                                  f"scheduler ({exc})") from None
    n = workers or os.cpu_count() or 1
    if n < 1:
        raise MasonrydamError(f"--workers must be at least 1, got {workers}")
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        return Client(cluster)
    except Exception:
        cluster.close()
        raise


def run_members(members, store: Path, measure, client, keep_history=False, warm=None, progress=True,
                settings: dict | None = None, dynamic_stage: str | None = None) -> dict:
    """Run the ``members`` whose outcome is not yet in ``store`` (or was obtained with another fingerprint,
    :func:`fingerprint` of ``settings``) on ``client`` (one task each); returns every outcome in the store
    (member_id -> outcome). ``warm``: ``(scene, base_dir)`` run once on each worker first."""
    # dask.distributed (a second to import) only for running an ensemble
    from distributed import as_completed

    store.mkdir(parents=True, exist_ok=True)
    done = done_members(store)
    fps = {m.member_id: fingerprint(m, settings or {}) for m in members}
    todo = [m for m in members if done.get(m.member_id, {}).get("fingerprint") != fps[m.member_id]]
    if progress:
        print(f"ensemble: {len(members)} members, {len(members) - len(todo)} already in {store}, {len(todo)} to run",
              file=sys.stderr, flush=True)
    if not todo:
        return done
    if warm is not None:
        client.run(_warm, *warm)
    futures = {client.submit(run_member, m, str(store), measure, keep_history, fps[m.member_id], dynamic_stage,
                             key=f"member-{m.member_id}-{fps[m.member_id]}", pure=False): m for m in todo}
    t0 = time.perf_counter()
    n_done = n_failed = 0
    for fut in as_completed(futures):
        try:
            rec = fut.result()
        except Exception as exc:  # noqa: BLE001 (a worker that died, a cancelled task: an outcome too)
            m = futures[fut]
            rec = {"member_id": m.member_id, "fingerprint": fps[m.member_id], "coords": m.coords,
                   "status": STATUS_ERROR, "reason": f"{type(exc).__name__}: {exc}", "wall_time": float("nan"),
                   "measures": {}}
            _write_json_atomic(store / f"{m.member_id}.json", rec)
        done[rec["member_id"]] = rec
        n_done += 1
        n_failed += rec["status"] != STATUS_COMPLETED
        if progress:
            left = (time.perf_counter() - t0) / n_done * (len(todo) - n_done)
            print(f"\rensemble: {n_done}/{len(todo)} done, {n_failed} failed, about {_eta(left)} left   ",
                  end="", file=sys.stderr, flush=True)
    if progress:
        print(file=sys.stderr, flush=True)
    return done


def assemble(outcomes: dict, axes: dict, attrs: dict, members: dict):
    """The ensemble ``xarray.Dataset`` from the members' outcomes (member_id -> outcome).

    axes: ordered ``name -> (values, attrs)`` of the member coordinates (``record``, ``intensity``, ``p_<name>``,
    ``sample``); members: ``member_id -> Member``, whose ``position`` (axis -> index) places its outcome (an outcome
    of no member is left out). The demand variables' units and long names are :func:`~.measures.measure_attrs`."""
    names = list(axes)
    shape = tuple(len(axes[n][0]) for n in names)
    data: dict[str, np.ndarray] = {}
    status = np.full(shape, STATUS_NOT_RUN, dtype=np.int8)
    reason = np.full(shape, "", dtype=object)
    wall = np.full(shape, np.nan)
    for rec in outcomes.values():
        member = members.get(rec["member_id"])
        if member is None:
            continue  # an outcome of another ensemble definition left in the store
        pos = tuple(member.position[n] for n in names)
        status[pos] = rec["status"]
        reason[pos] = rec["reason"]
        wall[pos] = rec["wall_time"]
        for k, v in rec["measures"].items():
            if k not in data:
                data[k] = np.full(shape, np.nan)
            data[k][pos] = np.nan if v is None else float(v)
    coords = {n: xr.Variable((n,), np.asarray(axes[n][0]), axes[n][1]) for n in names}
    ds = xr.Dataset(coords=coords, attrs=attrs)
    for k, arr in sorted(data.items()):
        ds[k] = xr.Variable(names, arr, measure_attrs(k))
    ds["status"] = xr.Variable(names, status, {"units": "1", "long_name": "member outcome: " + STATUS_MEANINGS,
                                              "flag_values": np.array([-1, 0, 1, 2, 3], np.int8),
                                              "flag_meanings": "not_run completed collapse numerical_failure error"})
    ds["status_reason"] = xr.Variable(names, reason.astype(str), {"units": "1",
                                                                  "long_name": "why the member failed (empty: it did not)"})
    ds["wall_time"] = xr.Variable(names, wall, {"units": "s", "long_name": "wall time of the member's run"})
    return ds


def write_dataset(ds, output: Path) -> None:
    """Write ``ds`` to ``output`` (netCDF) atomically (a working file renamed over it)."""
    tmp = output.with_name(output.name + ".partial")
    ds.to_netcdf(tmp)
    os.replace(tmp, output)


def _eta(seconds: float) -> str:
    return f"{seconds / 60:.1f} min" if seconds >= 120 else f"{seconds:.0f} s" if math.isfinite(seconds) else "?"


def run_ensemble(path, output, workers: int | None = None, scheduler: str | None = None, progress: bool = True):
    """Run the ensemble file ``path`` into ``output`` (netCDF; outcomes in ``<output>.members/``) and return the
    dataset. ``workers`` / ``scheduler`` override the file's ``[execution]``; the members already in the store
    are not run again."""
    spec = load_spec(path)
    members = enumerate_members(spec)
    axes = member_axes(spec)
    output = Path(output)
    store = members_dir(output)
    client = connect(workers if workers is not None else spec.workers,
                     scheduler if scheduler is not None else spec.scheduler)
    t0 = time.perf_counter()
    try:
        warm = (short_scene(members[0].scene), str(members[0].base_dir)) if members else None
        settings = {"demand_sets": list(spec.demand_sets), "history": bool(spec.history)}
        outcomes = run_members(members, store, functools.partial(member_measures, spec=spec), client,
                               keep_history=spec.history, warm=warm, progress=progress, settings=settings,
                               dynamic_stage=spec.stage_name)
        n_workers = len(client.scheduler_info().get("workers", {}))
    finally:
        client.close()
        cluster = getattr(client, "cluster", None)
        if cluster is not None:
            cluster.close()
    attrs = {"title": f"masonrydam ensemble: {spec.name}", "ensemble_file": str(path),
             "base_scene": str(spec.scene_path), "members": len(members),
             "workers": n_workers, "wall_time_s": round(time.perf_counter() - t0, 3),
             "status_meanings": STATUS_MEANINGS}
    ds = assemble({m.member_id: outcomes[m.member_id] for m in members if m.member_id in outcomes}, axes,
                  attrs, {m.member_id: m for m in members})
    for name, (values, a) in sample_coordinates(spec).items():  # the sampled values along ``sample``
        ds = ds.assign_coords({name: ("sample", np.asarray(values, dtype=float), a)})
    write_dataset(ds, output)
    return ds
