"""Inertia, damping and uniform base excitation: what a dynamic stage adds to the model.

The stage's schema is :func:`masonrydam.scene.schema._dynamic_stage` (time steps, integrator, output),
its solver :mod:`masonrydam.solvers.dynamic`; the records are read and processed by
:mod:`masonrydam.records`. This module says, for the run's list of simulated effects, what a scene's
dynamic stages simulate; a scene with static stages only simulates no inertia and no damping.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..pulses import pulse_samples
from ..solvers.dynamic import GroundMotion, scheme_named
from .base import Effect

def _dynamic_stages(scene):
    return [st for st in scene["stages"] if st["type"] == "dynamic"]


def _static_only(scene, model):
    if _dynamic_stages(scene):
        return []
    if any(st["type"] == "modal" for st in scene["stages"]):
        return ["no time integration (static and modal stages: no damping)"]
    return ["static analysis (no inertia, no damping)"]


def _inertia(scene, model):
    out = []
    for st in _dynamic_stages(scene):
        scheme = scheme_named(st["integrator"])
        what = scheme.label + "".join(f" ({name} {st[name]:g})" for name in scheme.parameters)
        steps = (f"dt auto (tolerance {st['tolerance']:g}, dt_max {st['dt']:g} s)" if st.get("adaptive")
                 else f"dt auto (the largest stable step dividing the output interval {st['dt']:g} s)"
                 if st.get("stable_step") else f"dt {st['dt']:g} s")
        out.append(f"dynamic stage '{st['name']}': {st['mass']} mass inertia, {what}, {steps}")
        for it in st.get("initial_velocity") or []:
            how = (f"velocity {it['velocity']} m/s" if "velocity" in it else
                   f"rigid rotation {it['angular_velocity']} rad/s about {it['rotation_center']}")
            out.append(f"dynamic stage '{st['name']}': initial {how} of {', '.join(it['groups'])}")
        for it in st.get("initial_displacement") or []:
            how = (f"displacement {it['displacement']} m" if "displacement" in it else
                   f"rigid rotation {it['rotation']} rad about {it['rotation_center']}")
            out.append(f"dynamic stage '{st['name']}': released from an initial {how} of {', '.join(it['groups'])}")
    return out


def _damping(scene, model):
    out = []
    for st in _dynamic_stages(scene):
        d = st["damping"]
        if d is None:
            out.append(f"dynamic stage '{st['name']}': no viscous damping")
            continue
        if d.get("model") == "local":
            out.append(f"dynamic stage '{st['name']}': local (non-viscous) damping, {100 * d['ratio']:g} % at every "
                       "frequency (Cundall 1987; Itasca 3DEC)")
            continue
        which = "continuum stiffness only (joints excluded)" if d["exclude_joints"] else "continuum and joint stiffness"
        if "ratio" in d:
            out.append(f"dynamic stage '{st['name']}': Rayleigh damping {100 * d['ratio']:g} % at "
                       f"{d['frequencies'][0]:g} and {d['frequencies'][1]:g} Hz, stiffness part on the {which}")
        else:
            out.append(f"dynamic stage '{st['name']}': Rayleigh damping alpha {d['alpha']:g} 1/s, beta {d['beta']:g} s, "
                       f"stiffness part on the {which}")
    return out


def _ground_motion(scene, model):
    out = []
    for st in _dynamic_stages(scene):
        comps = []
        for c, g in st["ground_motion"].items():
            src = g.get("record") or g.get("file") or (f"{g['pulse']['shape']} pulse" if "pulse" in g else "values")
            comps.append(f"{c}: {src}")
        if not comps:
            out.append(f"dynamic stage '{st['name']}': no ground motion (free motion from the initial velocity)")
            continue
        f = scene.get("foundation")
        if f and f.get("mass") and f.get("motion") == "outcrop":
            how = "outcrop motion entered as free-field forces at the compliant base (total displacements)"
        else:
            how = "uniform base excitation, relative formulation"
        out.append(f"dynamic stage '{st['name']}': {how} ({'; '.join(comps)})")
    return out


def _modes(scene, model):
    return [f"modal stage '{st['name']}': {st['modes']} lowest modes of the static state ({st['mass']} mass; "
            "sticking joint points elastic, open points free)" for st in scene["stages"] if st["type"] == "modal"]


def _synthetic_trace(values, dt, source: str, parameters: dict):
    """An obspy Trace (m/s2) for a ground motion given in the scene (values or a pulse), with provenance."""
    import obspy  # here, not at import: a scene without a ground motion does not load obspy (about 35 ms)
    from obspy.core.util import AttribDict

    tr = obspy.Trace(data=np.ascontiguousarray(values, dtype=np.float64))
    tr.stats.delta = dt
    tr.stats.masonrydam = AttribDict(quantity="acceleration", units="m/s2", source_file=source,
                                     format="scene", provenance=[{"step": "define", "parameters": parameters,
                                                                  "function": "masonrydam.effects.ground_motion", "library": "masonrydam"}])
    return tr


#: scene processing step -> the function of masonrydam.records that does it (each records itself in
#: the trace's provenance, which the result attributes carry)
_PROCESSING = {"baseline": "baseline_correct", "taper": "taper", "bandpass": "bandpass", "resample": "resample",
               "trim": "trim_significant_duration"}


def build_ground_motion(spec: dict, component: int, key: str, stage_dt: float, base_dir: Path | None = None):
    """A :class:`GroundMotion` from a normalised ground-motion component (record, file, values or pulse),
    processed (baseline, taper, band-pass, resampling, significant-duration trim, in the scene's order)
    and scaled as asked; its ``attrs`` hold the record's provenance with every step
    (``records.provenance_attrs``)."""
    from .. import records as rec  # obspy with it: only for a scene with a ground motion
    from ..records import RecordError

    try:
        src = spec["source"]
        if src == "record":
            tr = rec.load_record(spec["record"])
            name = spec["record"]
        elif src == "file":
            path = Path(spec["file"])
            if not path.is_absolute() and base_dir is not None:
                path = Path(base_dir) / path
            # one trace: a file with several value columns needs the component's 'column' (0-based, the
            # time column not counted); errors name the scene keys (stages[i].ground_motion.x.units)
            tr = rec.read_trace(path, format=spec["format"], units=spec["units"], dt=spec["dt"],
                                column=spec.get("column"), option_names=rec.readers.scene_option_names(key))
            name = str(spec["file"]) if spec.get("column") is None else f"{spec['file']} column {spec['column']}"
        elif src == "values":
            q, unit, factor = rec.parse_units(spec["units"], f"{key}.units")
            if q != "acceleration":
                raise SceneError(f"{key}.units", f"must be an acceleration unit (g, m/s2, cm/s2, ...), got {spec['units']!r}")
            tr = _synthetic_trace(np.asarray(spec["values"]) * factor, spec["dt"], "scene values",
                                  {"units": spec["units"], "npts": len(spec["values"]), "dt": spec["dt"]})
            name = "values"
        else:
            p = spec["pulse"]
            dt = spec["dt"] or stage_dt
            try:
                samples = pulse_samples(p["shape"], p["amplitude"], p["duration"], dt)
            except ValueError as exc:
                raise SceneError("ground_motion.pulse.duration", str(exc)) from None
            tr = _synthetic_trace(samples, dt, f"{p['shape']} pulse", dict(p, dt=dt))
            name = f"{p['shape']}_pulse"
        for j, step in enumerate(spec.get("processing", [])):
            params = {k: v for k, v in step.items() if k != "step"}
            if step["step"] == "bandpass":  # a low- or high-pass: the other corner is None
                params = {"freqmin": None, "freqmax": None, **params}
            try:
                tr = getattr(rec, _PROCESSING[step["step"]])(tr, **params)
            except RecordError as exc:
                raise SceneError(f"{key}.processing[{j}]", str(exc)) from None
        if spec["scale"] is not None:
            tr = rec.scale(tr, spec["scale"], reason="scene")
        elif spec["scale_to_pga"] is not None:
            tr = rec.scale_to_pga(tr, spec["scale_to_pga"], units="m/s2")
        elif spec.get("scale_to_sa") is not None:
            t = spec["scale_to_sa"]
            tr = rec.scale_to_sa(tr, t["sa"], t["period"], t["damping"], units="m/s2")
    except RecordError as exc:
        raise SceneError(key if exc.option is None else f"{key}.{exc.option}", str(exc)) from None
    attrs = rec.provenance_attrs(tr, prefix="")
    return GroundMotion(component, np.asarray(tr.data, dtype=np.float64), float(tr.stats.delta), name, attrs)


def _add_ground_motion(context, spec: dict, index: int, parts) -> None:
    """The ground motion of each component of the dynamic stage ``spec`` (scene order ``x``, ``y``, ``z``)."""
    for c, g in spec["ground_motion"].items():
        parts.ground_motion.append(build_ground_motion(g, "xyz".index(c), f"stages[{index}].ground_motion.{c}",
                                                       parts.sample_dt, context.base_dir))


def _effects():
    return [
        Effect("static", "static stages only", __name__, "load and displacement control (solvers/static/stepping.py)",
               "tests/system/test_system.py", _static_only),
        Effect("inertia", "a stage with type = 'dynamic'", __name__,
               "Newmark 1959; Hilber, Hughes & Taylor 1977; Chung & Hulbert 1993", "tests/solvers/test_dynamics.py",
               _inertia),
        Effect("modes", "a stage with type = 'modal'", __name__,
               "generalized eigenproblem K phi = omega^2 M phi (Chopra, Dynamics of Structures, ch. 10, 13)",
               "tests/solvers/test_modal_stage.py", _modes),
        Effect("damping", "stages.damping", __name__, "Rayleigh damping (Chopra, Dynamics of Structures, sec. 11.4); local damping of an explicit step (Cundall 1987; Itasca 3DEC manual)",
               "tests/solvers/test_dynamics.py", _damping),
        Effect("ground_motion", "stages.ground_motion", __name__,
               "relative formulation, effective earthquake forces -M iota a_g (Chopra, sec. 9.4)",
               "tests/solvers/test_dynamics.py, tests/ground_motion/test_records.py", _ground_motion, dynamic_stage=_add_ground_motion),
    ]


EFFECTS = _effects()
