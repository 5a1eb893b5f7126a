"""Engineering demand parameters of one ensemble member, from its result dataset.

:func:`member_measures` reduces the xarray Dataset that :func:`masonrydam.run` returns (or
:func:`masonrydam.open_result` reads) to a few numbers, taken over the dynamic steps and, for displacements,
relative to the state the first dynamic stage starts from: ``peak_displacement`` (m), ``peak_drift`` (1), per
demand joint set ``peak_slip_S``, ``residual_slip_S``, ``peak_opening_S``, ``residual_opening_S`` (m) and
``cracked_ratio_S`` (1), ``min_sliding_safety_factor`` (1) and ``energy_dissipated`` (J). The measures and
their units are listed in :data:`MEASURES`; :func:`measure_attrs` gives the ``units`` and ``long_name`` of a
measure's name.

Definitions: docs/ensembles.md, section "The measures" (under "The dataset").
"""
from __future__ import annotations

import json

import numpy as np

from ..errors import MasonrydamError

#: measure name pattern (``<set>``: a demand joint set, in the name and the long name) -> (units, long name)
MEASURES = {
    "peak_displacement": ("m", "peak norm of the nodal displacement change during the dynamic stages"),
    "peak_drift": ("1", "peak horizontal displacement of the top relative to the bottom of the model over its "
                        "height"),
    "peak_slip_<set>": ("m", "peak slip of joint set <set> (max over its points)"),
    "residual_slip_<set>": ("m", "residual slip of joint set <set> at the last step (max over its points)"),
    "peak_opening_<set>": ("m", "peak opening of joint set <set> (max over its points)"),
    "residual_opening_<set>": ("m", "residual opening of joint set <set> at the last step (max over its points)"),
    "cracked_ratio_<set>": ("1", "open area of joint set <set> at the last step over its area"),
    "min_sliding_safety_factor": ("1", "minimum sliding safety factor over the dynamic steps and the sections"),
    "energy_dissipated": ("J", "energy dissipated by the joints, viscous damping and the time integrator"),
}
#: the per-set measures, in the order member_measures gives them
SET_MEASURES = ("peak_slip", "residual_slip", "peak_opening", "residual_opening", "cracked_ratio")
#: energy terms summed into energy_dissipated
DISSIPATED_TERMS = ("energy_joint_dissipated", "energy_damping", "energy_numerical")


def measure_attrs(name: str) -> dict:
    """``{"units": ..., "long_name": ...}`` of the measure ``name`` (``peak_slip_bed``: of ``peak_slip_<set>``
    with ``<set>`` = ``bed``)."""
    if name in MEASURES:
        units, long_name = MEASURES[name]
        return {"units": units, "long_name": long_name}
    for prefix in SET_MEASURES:
        if name.startswith(prefix + "_"):
            units, long_name = MEASURES[prefix + "_<set>"]
            s = name[len(prefix) + 1:]
            return {"units": units, "long_name": long_name.replace("<set>", s)}
    raise KeyError(f"unknown measure {name!r}; known patterns: {', '.join(MEASURES)}")


def measure_names(demand_sets, sliding: bool = False) -> list:
    """The names :func:`member_measures` gives for ``demand_sets`` (``peak_drift`` included;
    ``min_sliding_safety_factor`` where ``sliding``)."""
    out = ["peak_displacement", "peak_drift"]
    for s in demand_sets:
        out += [f"{m}_{s}" for m in SET_MEASURES]
    if sliding:
        out.append("min_sliding_safety_factor")
    return out + ["energy_dissipated"]


def _steps(ds, stage=None):
    """(positions of the dynamic steps, position of the reference step); with ``stage`` (the index of the
    ensemble's dynamic stage in the scene's stages) only the steps from that stage on."""
    if "time" not in ds.variables:
        raise MasonrydamError("the result has no 'time': it has no dynamic stage to measure")
    t = np.asarray(ds["time"].values, dtype=float)
    finite = np.isfinite(t)
    if stage is not None and "stage" in ds.variables:
        finite &= np.asarray(ds["stage"].values) >= stage
    dyn = np.flatnonzero(finite)
    if not len(dyn):
        raise MasonrydamError("the result has no dynamic steps (every 'time' is NaN): the run stopped before its "
                              "first dynamic stage, or the scene has none")
    ref = int(dyn[0])
    if t[ref] > 0.0 and ref > 0:
        ref -= 1
    return dyn, ref


def _set_names(ds) -> list:
    if "joint_set" not in ds.variables:
        return []
    try:
        return list(json.loads(ds["joint_set"].attrs.get("set_names", "[]")))
    except (TypeError, ValueError):
        return []


def _drift(ds, du, nodes_dim="node"):
    """Peak drift from the displacement changes ``du`` (steps, nodes, components); None where undefined."""
    coords = [c for c in ("x", "y", "z") if c in ds.variables and ds[c].dims == (nodes_dim,)]
    comps = [str(c) for c in ds["component"].values] if "component" in ds.coords else coords
    if len(coords) < 2:
        return None
    vertical = coords[-1]
    horizontal = [comps.index(c) for c in coords[:-1] if c in comps]
    z = np.asarray(ds[vertical].values, dtype=float)
    if not len(z) or not horizontal:
        return None
    H = float(z.max() - z.min())
    if not H > 0:
        return None
    tol = 1e-6 * H
    top, bottom = z >= z.max() - tol, z <= z.min() + tol
    uh = du[:, :, horizontal]  # (steps, nodes, horizontal components)
    rel = uh[:, top].mean(axis=1) - uh[:, bottom].mean(axis=1)
    return float(np.max(np.linalg.norm(rel, axis=-1)) / H)


def _energy_change(ds, name, dyn, ref):
    v = np.asarray(ds[name].values, dtype=float)
    v0 = v[ref] if np.isfinite(v[ref]) else 0.0
    return float(v[dyn[-1]] - v0)


def member_measures(ds, spec=None, demand_sets=None) -> dict:
    """The engineering demand parameters (:data:`MEASURES`) of one member's result ``ds`` (an xarray Dataset):
    a dict ``{name: float}``. ``demand_sets``: the joint sets measured (default: ``spec.demand_sets``, else
    every set of the result). See the module docstring for the exact definitions."""
    if demand_sets is None:
        demand_sets = list(spec.demand_sets) if spec is not None else _set_names(ds)
    dyn, ref = _steps(ds, None if spec is None else spec.stage)
    last = int(dyn[-1])
    out = {}

    u = np.asarray(ds["displacement"].transpose("step", "node", "component").values, dtype=float)
    du = u[dyn] - u[ref]
    out["peak_displacement"] = float(np.max(np.linalg.norm(du, axis=-1))) if du.size else float("nan")
    drift = _drift(ds, du) if du.size else None
    if drift is not None:
        out["peak_drift"] = drift

    names = _set_names(ds)
    jset = np.asarray(ds["joint_set"].values) if "joint_set" in ds.variables else np.zeros(0, dtype=int)
    for s in demand_sets:
        mask = jset == names.index(s) if s in names else np.zeros(jset.shape, dtype=bool)
        if not mask.any():
            for m in SET_MEASURES:
                out[f"{m}_{s}"] = float("nan")
            continue
        # (step, point, shear direction)
        slip = np.asarray(ds["joint_slip"].transpose("step", "joint_point", ...).values, dtype=float)[:, mask]
        ds_slip = np.linalg.norm(slip[dyn] - slip[ref], axis=-1)  # (dyn steps, points)
        out[f"peak_slip_{s}"] = float(ds_slip.max())
        out[f"residual_slip_{s}"] = float(ds_slip[-1].max())
        opening = np.asarray(ds["joint_opening"].transpose("step", "joint_point").values, dtype=float)[:, mask]
        d_open = opening[dyn] - opening[ref]
        out[f"peak_opening_{s}"] = max(0.0, float(d_open.max()))
        out[f"residual_opening_{s}"] = max(0.0, float(d_open[-1].max()))
        state = np.asarray(ds["joint_state"].transpose("step", "joint_point").values)[last, mask]
        w = (np.asarray(ds["joint_weight"].values, dtype=float)[mask] if "joint_weight" in ds.variables
             else np.ones(int(mask.sum())))
        out[f"cracked_ratio_{s}"] = float(w[state == 2].sum() / w.sum()) if w.sum() > 0 else float("nan")

    if "sliding_safety_factor" in ds.variables:
        sf = np.asarray(ds["sliding_safety_factor"].transpose("step", ...).values, dtype=float)[dyn]
        sf = sf[~np.isnan(sf)]
        if sf.size:
            out["min_sliding_safety_factor"] = float(sf.min())

    total = 0.0
    if "energy_joint_dissipated" in ds.variables:
        total += _energy_change(ds, "energy_joint_dissipated", dyn, ref)
    elif "energy_joint" in ds.variables and "energy_joint_stored" in ds.variables:
        total += _energy_change(ds, "energy_joint", dyn, ref) - _energy_change(ds, "energy_joint_stored", dyn, ref)
    for name in DISSIPATED_TERMS[1:]:
        if name in ds.variables:
            total += _energy_change(ds, name, dyn, ref)
    out["energy_dissipated"] = total
    return out


__all__ = ["MEASURES", "SET_MEASURES", "DISSIPATED_TERMS", "measure_attrs", "measure_names", "member_measures"]
