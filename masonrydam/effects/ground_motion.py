"""Inertia, damping and uniform base excitation: what a dynamic stage adds to the model.

The stage's schema is :func:`masonrydam.scene.schema._dynamic_stage` (time steps, integrator, output),
its solver :mod:`masonrydam.solvers.dynamic.integration`; the records are read and processed by
:mod:`masonrydam.records`. This module says, for the run's list of simulated effects, what a scene's
dynamic stages simulate; a scene with static stages only simulates no inertia and no damping.
"""
from __future__ import annotations

_INTEGRATORS = {"newmark_average": "Newmark average acceleration", "newmark_linear": "Newmark linear acceleration",
                "hht": "HHT-alpha", "generalized_alpha": "generalized-alpha", "central_difference": "central difference"}


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
        what = _INTEGRATORS[st["integrator"]]
        if st["integrator"] == "hht":
            what += f" (alpha {st['alpha']:g})"
        elif st["integrator"] == "generalized_alpha":
            what += f" (rho_inf {st['rho_inf']:g})"
        steps = (f"dt auto (tolerance {st['tolerance']:g}, dt_max {st['dt']:g} s)" if st.get("adaptive")
                 else f"dt {st['dt']:g} s")
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


def _effects():
    from . import Effect

    return [
        Effect("static", "static stages only", __name__, "load and displacement control (solvers/static/stepping.py)",
               "tests/test_system.py", _static_only),
        Effect("inertia", "a stage with type = 'dynamic'", __name__,
               "Newmark 1959; Hilber, Hughes & Taylor 1977; Chung & Hulbert 1993", "tests/test_dynamics.py",
               _inertia),
        Effect("modes", "a stage with type = 'modal'", __name__,
               "generalized eigenproblem K phi = omega^2 M phi (Chopra, Dynamics of Structures, ch. 10, 13)",
               "tests/test_modal_stage.py", _modes),
        Effect("damping", "stages.damping", __name__, "Rayleigh damping (Chopra, Dynamics of Structures, sec. 11.4)",
               "tests/test_dynamics.py", _damping),
        Effect("ground_motion", "stages.ground_motion", __name__,
               "relative formulation, effective earthquake forces -M iota a_g (Chopra, sec. 9.4)",
               "tests/test_dynamics.py, tests/test_records.py", _ground_motion),
    ]


EFFECTS = _effects()
