"""The members of an ensemble: one run of the base scene per point of the axes.

The members are the Cartesian product, in this order (the last varies fastest):

    record x intensity x (each grid parameter, in file order) x sample

where ``sample`` (the Latin hypercube points of the sampled parameters, :mod:`.spec`) is one axis, present
only when some parameter is sampled. :func:`member_axes` gives the same axes with their values and
attributes, ready to be the dimension coordinates of the ensemble's dataset, and
:func:`sample_coordinates` the sampled values along ``sample``.
"""
from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from .spec import INTENSITY_MEASURES, EnsembleSpec

#: member id length (hex digits of the SHA-1)
ID_LENGTH = 12


@dataclass
class Member:
    """One member of an ensemble.

    coords: its point on the dimension axes, ``{"record": name, "intensity": m/s2, "p_<name>": value for each
    grid parameter, "sample": k}`` (``sample`` only with sampled parameters; grid values in SI where they are
    quantities); member_id: :func:`member_id` of ``coords`` and ``sampled``; scene: the member's raw scene
    dictionary (run it with ``masonrydam.run(Scene(member.scene, base_dir=member.base_dir))``); base_dir: the
    base scene's folder; index: its position in :func:`enumerate_members`; position: its index along each
    dimension axis (``{"record": i, "intensity": j, "p_...": k, "sample": s}``, the keys of ``coords``);
    sampled: the sampled values of its sample (``{"p_<name>": SI value}``, empty without sampling);
    assignments: the ``(scene key, value)`` pairs set on the base scene (besides the ground motion).
    """

    coords: dict
    member_id: str
    scene: dict
    base_dir: Path
    index: int = 0
    position: dict = field(default_factory=dict)
    sampled: dict = field(default_factory=dict)
    assignments: list = field(default_factory=list)


class Axis(NamedTuple):
    """An axis (a dimension) or a coordinate of the ensemble dataset: ``values`` (a list of strings or numbers)
    and ``attrs`` (strings, numbers and lists of numbers: ``units``, ``long_name``, ``scene_key``, ...). As
    a tuple ``(values, attrs)``; the dimension it lies along is its name in :func:`member_axes` and
    ``"sample"`` in :func:`sample_coordinates`."""

    values: list
    attrs: dict


def member_id(coords: dict, sampled: dict | None = None) -> str:
    """A stable short id of a member: the first :data:`ID_LENGTH` hex digits of the SHA-1 of the JSON of its
    ``coords`` and, where there are, its sampled values (as ``"p_<name>(sample)"`` keys), keys sorted. The same
    coordinates give the same id in every run (and a changed seed, with other samples, another one)."""
    payload = dict(coords)
    for k, v in (sampled or {}).items():
        payload[f"{k}(sample)"] = v
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha1(text.encode("utf-8")).hexdigest()[:ID_LENGTH]


def member_axes(spec: EnsembleSpec) -> dict:
    """The dimension axes of the ensemble, in order, as ``{name: Axis(values, attrs)}``: ``record``,
    ``intensity``, one ``p_<name>`` per grid parameter and, with sampled parameters, ``sample``. These are the
    keys of every :class:`Member` ``coords``, in the order of :func:`enumerate_members` (the last varies
    fastest). The sampled values are the coordinates of :func:`sample_coordinates` along ``sample``, and
    also lists in the attributes of ``sample`` (one per sampled parameter, named ``p_<name>``).

    Attributes: all axes ``long_name``, ``units`` (``""`` where unknown) and ``scene_key`` (``sample``:
    ``sampled_keys``). ``record``: ``kinds`` and ``sources`` (JSON ``{name: "bundled" | "file"}`` and
    ``{name: bundled name | absolute file path}``); ``intensity``: ``units`` "m/s2", ``measure`` ("pga" or
    "sa"), ``given`` (JSON list of the values as written), for "sa" also ``period`` (s) and ``damping``;
    ``p_<name>``: ``given`` (JSON list as written); ``sample``: ``samples``, ``seed``, ``sampled_keys`` (JSON
    list of scene keys), ``sampled_names`` (JSON list of the ``p_<name>``) and the ``p_<name>`` lists."""
    gm = spec.ground_motion_key
    out = {}
    sources = {r.name: (r.source["record"] if r.kind == "bundled" else r.source["file"]) for r in spec.records}
    out["record"] = Axis([r.name for r in spec.records], {
        "long_name": "ground-motion record",
        "units": "",
        "scene_key": gm,
        "kinds": json.dumps({r.name: r.kind for r in spec.records}),
        "sources": json.dumps(sources),
    })
    it = spec.intensity
    attrs = {"long_name": f"{INTENSITY_MEASURES[it.scaling][1]} the records are scaled to",
             "units": "m/s2",
             "measure": it.measure,
             "scene_key": f"{gm}.{it.scaling}" + (".sa" if it.scaling == "scale_to_sa" else ""),
             "given": json.dumps(list(it.given), default=str)}
    if it.scaling == "scale_to_sa":
        attrs.update(period=it.period, damping=it.damping)
    out["intensity"] = Axis(list(it.values), attrs)
    for p in spec.grid_parameters:
        out[p.name] = Axis(list(p.coords), {"long_name": f"scene key {p.key}", "units": p.units, "scene_key": p.key,
                                            "given": json.dumps(p.values, default=str)})
    sampled = spec.sampled_parameters
    if sampled:
        attrs = {"long_name": "Latin hypercube sample of the sampled parameters", "units": "1",
                 "samples": spec.samples, "seed": spec.seed,
                 "sampled_keys": json.dumps([p.key for p in sampled]),
                 "sampled_names": json.dumps([p.name for p in sampled])}
        attrs.update({p.name: [float(v) for v in p.values] for p in sampled})
        out["sample"] = Axis(list(range(spec.samples)), attrs)
    return out


def sample_coordinates(spec: EnsembleSpec) -> dict:
    """The sampled values as coordinates along the ``sample`` axis: ``{"p_<name>": Axis(values, attrs)}`` (one
    value per sample index, SI), attributes ``long_name``, ``units``, ``scene_key`` and ``distribution`` (JSON
    of its type and SI parameters). Empty without sampled parameters."""
    return {p.name: Axis([float(v) for v in p.values], {
        "long_name": f"scene key {p.key} (sampled)", "units": p.units, "scene_key": p.key,
        "distribution": json.dumps(p.distribution)}) for p in spec.sampled_parameters}


def enumerate_members(spec: EnsembleSpec) -> list:
    """Every member of ``spec`` (a list of :class:`Member`), in the order of :func:`member_axes`."""
    axes = member_axes(spec)
    names = list(axes)
    grid = spec.grid_parameters
    sampled = spec.sampled_parameters
    out = []
    ranges = [range(len(axes[n].values)) for n in names]
    for n, idx in enumerate(itertools.product(*ranges)):
        pos = dict(zip(names, idx))
        coords = {name: axes[name].values[i] for name, i in zip(names, idx)}
        record = spec.records[pos["record"]]
        intensity = spec.intensity.values[pos["intensity"]]
        assignments = [(p.key, p.values[pos[p.name]]) for p in grid]
        samples = {}
        if sampled:
            k = pos["sample"]
            samples = {p.name: p.values[k] for p in sampled}
            assignments += [(p.key, p.values[k]) for p in sampled]
        scene = spec.member_scene(record, intensity, assignments)
        out.append(Member(coords=coords, member_id=member_id(coords, samples), scene=scene, base_dir=spec.scene_dir,
                          index=n, position=pos, sampled=samples, assignments=assignments))
    return out


__all__ = ["Member", "Axis", "member_id", "member_axes", "sample_coordinates", "enumerate_members", "ID_LENGTH"]
