"""Build a model from a normalised scene: mesh, element groups, supports and stage load vectors.

Only what the scene asks for is created: no mass, no damping, no joint state for linear joints
(their state never changes), no load vector for a load type that is absent. :func:`effects`
lists what is simulated; it goes into the run summary and the dataset attributes.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..assembly.dofmap import DofMap
from ..assembly.groups import ContinuumGroup, InterfaceGroup
from ..assembly.model import Model
from ..errors import SceneError
from ..materials import mohr_coulomb as mc
from ..materials.elastic import elasticity_matrix
from ..effects import plasticity
from ..materials.plasticity import P_VISCOSITY
from ..mesh.io import read_mesh
from ..mesh.model import Mesh
from ..solvers.static.stepping import StaticStage

#: parameters of a joint that never slips or opens (law = "linear")
_UNBREAKABLE = 1e300


def build_mesh(scene: dict, base_dir: Path) -> Mesh:
    spec = scene["mesh"]
    if "generator" in spec:
        from generators import GENERATORS

        return GENERATORS[spec["generator"]](**spec["parameters"])
    path = Path(spec["file"])
    if not path.is_absolute():
        path = base_dir / path
    return read_mesh(path, spec["joints"], scene["model"]["dimension"])


def joint_param_vector(spec: dict, key: str = "joints") -> np.ndarray:
    """Parameter vector of the joint law (:func:`mohr_coulomb_update`, or
    :func:`~masonrydam.materials.composite_interface.composite_params`) for a normalised joint spec."""
    if spec["law"] == "composite":
        from ..materials import composite_interface as ci

        names = ("dilatancy_confinement", "dilatancy_decay", "compressive_strength", "cap_shear_factor",
                 "cap_fracture_energy", "cap_peak_plastic_strain", "shear_stiffness_2", "residual_friction_angle",
                 "dilatancy_angle", "relaxation_time")
        try:
            row = ci.composite_params(spec["normal_stiffness"], spec["shear_stiffness"], spec["tensile_strength"],
                                      spec["mode_I_fracture_energy"], spec["cohesion"], spec["friction_angle"],
                                      mode_II_fracture_energy=spec["mode_II_fracture_energy"],
                                      **{k: spec[k] for k in names if k in spec})
            # the longest elastic bar in series without a snap-back is 0: the joint alone would snap back
            # (its sign does not depend on the bar's moduli, so unit moduli serve)
            l_one, l_two = ci.snap_back_length(row, 1.0, 1.0)
            if l_one == 0.0:
                raise ValueError(f"mode_I_fracture_energy = {spec['mode_I_fracture_energy']:g} N/m is below "
                                 f"ft^2 / kn = {spec['tensile_strength'] ** 2 / spec['normal_stiffness']:g} N/m: the "
                                 "joint alone would snap back (its elastic energy at the peak exceeds what its "
                                 "softening dissipates)")
            if l_two == 0.0:
                raise ValueError(f"mode_II_fracture_energy = {spec['mode_II_fracture_energy']:g} N/m is below "
                                 f"c^2 / ks = {spec['cohesion'] ** 2 / spec['shear_stiffness']:g} N/m: the joint "
                                 "alone would snap back in shear")
        except ValueError as exc:
            raise SceneError(key, str(exc)) from None
        return row
    if spec["law"] == "linear":
        return mc.joint_params(spec["normal_stiffness"], spec["shear_stiffness"], cohesion=_UNBREAKABLE,
                               friction_angle_deg=0.0, tensile_strength=_UNBREAKABLE)
    return mc.joint_params(spec["normal_stiffness"], spec["shear_stiffness"], spec["cohesion"], spec["friction_angle"],
                           spec["tensile_strength"], spec["residual_shear_stiffness"])


def build_model(scene: dict, mesh: Mesh) -> Model:
    dim = mesh.dim
    hyp = scene["model"]["hypothesis"]
    t = scene["model"]["thickness"]
    mats = scene["materials"]
    mesh_groups = mesh.group_names()
    for name in mesh_groups:
        if name not in mats:
            raise SceneError("materials", f"element group '{name}' of the mesh has no material; "
                                          f"add [materials.{name}] (mesh groups: {mesh_groups})")
    for name in mats:
        if name not in mesh_groups:
            raise SceneError(f"materials.{name}", f"the mesh has no element group '{name}' (mesh groups: {mesh_groups})")
    kinematics = scene["model"].get("kinematics", "small")
    cgroups = []
    for b in mesh.blocks:
        m = mats[b.name]
        D = elasticity_matrix(m["youngs_modulus"], m["poisson_ratio"], hyp)[None, :, :]
        ne = len(b.cells)
        law = m.get("law", "elastic")
        if kinematics == "large" and law != "elastic":
            raise SceneError(f"materials.{b.name}.law", f"\"{law}\" is a small-strain law: with [model] kinematics = "
                                                        "\"large\" the blocks must be elastic (St. Venant-Kirchhoff); "
                                                        "use kinematics = \"small\" for elasto-plastic blocks")
        law_params = plasticity.law_params(m, b.name, dim, hyp, mesh.points, b.cells, b.type)
        try:
            cgroups.append(ContinuumGroup(b.name, b.type, b.cells, DofMap.node_dofs(b.cells, dim),
                                          np.ascontiguousarray(D), np.zeros(ne, dtype=np.int64), np.full(ne, t),
                                          np.full(ne, m["density"]), law=law, law_params=law_params,
                                          kinematics=kinematics, integration=m.get("integration", "full")))
        except ValueError as exc:
            raise SceneError(f"materials.{b.name}.integration", str(exc)) from None
    joint_specs = scene["joints"]
    mesh_joints = mesh.joint_set_names()
    for name in mesh_joints:
        if name not in joint_specs:
            raise SceneError("joints", f"joint set '{name}' of the mesh has no parameters; add [joints.{name}] "
                                       f"(mesh joint sets: {mesh_joints})")
    for name in joint_specs:
        if name not in mesh_joints:
            raise SceneError(f"joints.{name}", f"the mesh has no joint set '{name}' (mesh joint sets: {mesh_joints})")
    igroups = []
    for j in mesh.joints:
        spec = joint_specs[j.name]
        if "frame" in spec and kinematics != "large":
            raise SceneError(f"joints.{j.name}.frame", "chooses the turning frame of large kinematics; with [model] "
                                                       "kinematics = \"small\" the frame is the reference one "
                                                       "(remove it, or set kinematics = \"large\")")
        scheme = spec["integration"]
        if j.type == "interface_quad8" and scheme == "lumped" and not spec.get("integration_given", True):
            scheme = "lobatto"  # 3x3 Newton-Cotes: the lumped corner weights of quad8 are negative
        params = joint_param_vector(spec, f"joints.{j.name}")
        try:
            igroups.append(InterfaceGroup(j.name, j.type, j.cells, mesh.points, dim, params,
                                          np.full(len(j.cells), t), spec["law"], scheme, spec.get("points"),
                                          kinematics=kinematics, frame=spec.get("frame", "mid_surface")))
        except ValueError as exc:
            raise SceneError(f"joints.{j.name}.integration", str(exc)) from None
    model = Model(mesh.points, cgroups, igroups)
    for i, s in enumerate(scene["supports"]):
        if s["kind"] == "tied":  # the set moves as one in these components (a loading beam kept level)
            nodes = _node_set(mesh, s["set"], f"supports[{i}].set")
            if len(np.unique(nodes)) < 2:
                raise SceneError(f"supports[{i}].set", f"set '{s['set']}' has {len(np.unique(nodes))} node: a tie "
                                                       "needs at least two")
            try:
                model.add_tie(nodes, ["xyz".index(c) for c in s["components"]])
            except ValueError as exc:
                raise SceneError(f"supports[{i}]", str(exc)) from None
    return model


def _load_vector(scene: dict, mesh: Mesh, model: Model, ld: dict, key: str) -> np.ndarray:
    """Consistent nodal force vector (n_dof,) N of a normalised ``nodal``, ``traction`` or ``pressure`` load."""
    from ..effects import loads as L

    if ld["type"] == "nodal":
        return L.nodal_force(model, _node_set(mesh, ld["set"], f"{key}.set"), ld["force"])
    if ld["set"] not in mesh.facet_sets:
        what = "edge" if mesh.dim == 2 else "face"
        raise SceneError(f"{key}.set", f"no facet ({what}) set '{ld['set']}' in the mesh "
                                       f"(facet sets: {sorted(mesh.facet_sets)})")
    fs = mesh.facet_sets[ld["set"]]
    if ld["type"] == "traction":
        return L.facet_traction(model, fs.type, fs.facets, scene["model"]["thickness"], traction=ld["traction"])
    return L.facet_traction(model, fs.type, fs.facets, scene["model"]["thickness"], pressure=ld["pressure"],
                            owner_centroids=_owner_centroids(mesh, fs.facets))


def _loads_in_time(scene: dict, mesh: Mesh, model: Model, st: dict, i: int, base_dir):
    """``force(t)`` (n_dof,) N of a dynamic stage's loads given in time (:mod:`masonrydam.effects.dynamic_loads`),
    or None without such loads."""
    from ..effects.dynamic_loads import STEPS_PER_TIME_SCALE, TimeFunction, load_history, time_scale

    if not st.get("loads"):
        return None
    parts = []
    for j, ld in enumerate(st["loads"]):
        key = f"stages[{i}].loads[{j}]"
        kind = {"edge_traction": "traction", "edge_pressure": "pressure"}.get(ld["type"], ld["type"])
        tf = TimeFunction.build(ld["time_function"], f"{key}.time_function", base_dir)
        scale = time_scale(tf)
        if st["dt"] > scale / STEPS_PER_TIME_SCALE:
            what = "dt_max" if st.get("adaptive") else "dt"
            raise SceneError(f"stages[{i}].{what}", f"{st['dt']:g} s is too long for {key}.time_function, which "
                                                    f"changes within {scale:g} s: the steps could pass over it; use "
                                                    f"{what} <= {scale / STEPS_PER_TIME_SCALE:g} s")
        parts.append((_load_vector(scene, mesh, model, dict(ld, type=kind), key), tf))
    return load_history(parts)


def _node_set(mesh: Mesh, name: str, key: str) -> np.ndarray:
    if name in mesh.node_sets:
        return mesh.node_sets[name]
    if name in mesh.facet_sets:
        return np.unique(mesh.facet_sets[name].facets)
    raise SceneError(key, f"no node set '{name}' in the mesh (node sets: {sorted(mesh.node_sets)}, "
                          f"facet sets: {sorted(mesh.facet_sets)})")


def _owner_centroids(mesh: Mesh, facets: np.ndarray) -> np.ndarray:
    """Centroid of the element owning each boundary facet (to orient pressures inward), (n, dim).

    Facets that belong to no element keep the origin as "centroid" (their own normal is used)."""
    from ..mesh.interfaces import _FacetTable

    facets = np.asarray(facets, dtype=np.int64)
    table = _FacetTable(mesh)
    nc = 2 if mesh.dim == 2 else {3: 3, 6: 3, 4: 4, 8: 4}[facets.shape[1]]
    k = table.lookup(_FacetTable.keys(facets, np.full(len(facets), nc)))
    cents = np.vstack([mesh.points[b.cells].mean(axis=1) for b in mesh.blocks])
    out = np.zeros((len(facets), mesh.dim))
    ok = k >= 0
    out[ok] = cents[table.elem[table.first[k[ok]]]]
    return out


def _synthetic_trace(values, dt, source: str, parameters: dict):
    """An obspy Trace (m/s2) for a ground motion given in the scene (values or a pulse), with provenance."""
    import obspy
    from obspy.core.util import AttribDict

    tr = obspy.Trace(data=np.ascontiguousarray(values, dtype=np.float64))
    tr.stats.delta = dt
    tr.stats.masonrydam = AttribDict(quantity="acceleration", units="m/s2", source_file=source,
                                     format="scene", provenance=[{"step": "define", "parameters": parameters,
                                                                  "function": "masonrydam.scene.build", "library": "masonrydam"}])
    return tr


def pulse_samples(shape: str, amplitude: float, duration: float, dt: float) -> np.ndarray:
    """Samples every ``dt`` of a pulse followed by one zero sample.

    rectangular: a zero sample at t = 0 (the structure starts at rest), then ``amplitude`` for
    ``floor(duration / dt)`` samples and one sample with the remainder, so that the trapezoidal
    integral of the samples is the impulse ``amplitude * duration``. The linear interpolation of the
    samples is the pulse from t = dt/2 to dt/2 + duration with its two jumps spread over one dt each
    (same impulse; the time shift does not change the response). half_sine: ``amplitude sin(pi t / duration)`` for
    0 <= t <= duration, zero after.
    """
    if shape == "rectangular":
        n = int(math.floor(duration / dt + 1e-9))
        frac = max(duration / dt - n, 0.0)  # in [0, 1)
        if n == 0:
            raise SceneError("ground_motion.pulse.duration", f"the pulse ({duration:g} s) is shorter than dt ({dt:g} s)")
        # 0, n x amplitude, [frac x amplitude], 0: trapezoidal integral = amplitude (n + frac) dt
        vals = [0.0] + [amplitude] * n + ([amplitude * frac] if frac > 1e-9 else []) + [0.0]
        return np.array(vals)
    n = int(math.ceil(duration / dt - 1e-9))
    t = np.arange(n + 2) * dt
    vals = np.where(t <= duration * (1 + 1e-12), amplitude * np.sin(np.pi * np.minimum(t, duration) / duration), 0.0)
    vals[-1] = 0.0
    return vals


#: scene processing step -> the function of masonrydam.records that does it (each records itself in
#: the trace's provenance, which the result attributes carry)
_PROCESSING = {"baseline": "baseline_correct", "taper": "taper", "bandpass": "bandpass", "resample": "resample",
               "trim": "trim_significant_duration"}


def build_ground_motion(spec: dict, component: int, key: str, stage_dt: float, base_dir: Path | None = None):
    """A :class:`GroundMotion` from a normalised ground-motion component (record, file, values or pulse),
    processed (baseline, taper, band-pass, resampling, significant-duration trim, in the scene's order)
    and scaled as asked; its ``attrs`` hold the record's provenance with every step
    (``records.provenance_attrs``)."""
    from .. import records as rec
    from ..records import RecordError
    from ..solvers.dynamic import GroundMotion

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
            tr = _synthetic_trace(pulse_samples(p["shape"], p["amplitude"], p["duration"], dt), dt,
                                  f"{p['shape']} pulse", dict(p, dt=dt))
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


def dynamic_settings(st: dict, index: int, linear_solver: str = "auto"):
    """DynamicSettings of a normalised dynamic stage; ``linear_solver``: the scene's ``solver.linear_solver``
    (an iterative choice applies to the static stages; dynamic stages use a direct solver)."""
    from ..solvers.dynamic import DynamicSettings
    from ..solvers.linear.direct import DIRECT_SOLVERS
    from ..assembly.damping import RayleighDamping

    if linear_solver not in DIRECT_SOLVERS:
        linear_solver = "auto"

    d = st["damping"]
    damping = None
    if d is not None:
        if "ratio" in d:
            damping = RayleighDamping.from_frequencies(d["frequencies"][0], d["frequencies"][1], d["ratio"],
                                                       d["exclude_joints"])
        else:
            damping = RayleighDamping(d["alpha"], d["beta"], d["exclude_joints"])
    return DynamicSettings(integrator=st["integrator"], dt=st["dt"], alpha=st["alpha"], rho_inf=st["rho_inf"],
                           max_iterations=st["max_iterations"], force_tolerance=st["force_tolerance"],
                           energy_tolerance=st["energy_tolerance"], max_substeps=st["max_substeps"], mass=st["mass"],
                           damping=damping, linear_solver=linear_solver, low_rank_max=st["low_rank_max"],
                           joint_space=st["joint_space"], adaptive=st["adaptive"], tolerance=st["tolerance"],
                           dt_min=st["dt_min"], key=f"stages[{index}].")


def build_stages(scene: dict, mesh: Mesh, model: Model, base_dir: Path | None = None) -> list:
    """Stage objects in scene order: :class:`StaticStage` and :class:`~masonrydam.solvers.dynamic.DynamicStage`.

    A dynamic stage keeps the supports and holds the DOFs prescribed by the last static stage at their
    values (they move with the ground); its ground motion is read and scaled here."""
    from ..effects import loads as L
    from ..solvers.dynamic import DynamicStage

    dim = mesh.dim
    supports = np.zeros(model.n_dof, dtype=bool)
    for i, s in enumerate(scene["supports"]):
        if s["kind"] != "fixed":
            continue
        nodes = _node_set(mesh, s["set"], f"supports[{i}].set")
        for c in s["components"]:
            supports[nodes * dim + "xyz".index(c)] = True
    stages = []
    weight = None
    held = np.zeros(model.n_dof, dtype=bool)
    reservoir = water_levels = None
    if scene.get("reservoir"):
        from ..effects.reservoir import Reservoir

        reservoir = Reservoir(scene["reservoir"], mesh, model, scene["model"]["thickness"])
    for i, st in enumerate(scene["stages"]):
        if st["type"] == "modal":
            from ..solvers.dynamic import ModalStage

            stages.append(ModalStage(st["name"], st["modes"], st["mass"] == "lumped", supports | held))
            continue
        if st["type"] == "dynamic":
            settings = dynamic_settings(st, i, scene["solver"]["linear_solver"])
            # a pulse is sampled at the analysis step (dt = "auto": at its smallest, so that the steps,
            # not the samples, decide how sharply its start and end are resolved)
            sample_dt = settings.dt_min if settings.adaptive else st["dt"]
            gms = [build_ground_motion(spec, "xyz".index(c), f"stages[{i}].ground_motion.{c}", sample_dt, base_dir)
                   for c, spec in st["ground_motion"].items()]
            if st["steps"] is not None:
                duration = st["steps"] * st["dt"]
            elif st["duration"] is not None:
                duration = st["duration"]
            else:
                duration = max(g.duration for g in gms)
            v0 = None if st.get("initial_velocity") is None else \
                initial_velocity_field(model, st["initial_velocity"], f"stages[{i}].initial_velocity")
            u0 = None if st.get("initial_displacement") is None else \
                initial_velocity_field(model, st["initial_displacement"], f"stages[{i}].initial_displacement",
                                       "displacement", "rotation")
            stages.append(DynamicStage(st["name"], duration, supports | held, gms, settings, st["output"]["stride"],
                                       initial_velocity=v0, loads=_loads_in_time(scene, mesh, model, st, i, base_dir),
                                       initial_displacement=u0))
            continue
        force = np.zeros(model.n_dof)
        presc = np.zeros(model.n_dof, dtype=bool)
        incr = np.zeros(model.n_dof)
        for j, ld in enumerate(st["loads"]):
            key = f"stages[{i}].loads[{j}]"
            if ld["type"] == "reservoir":  # the water rises to its level over the stage (effects.reservoir)
                start = reservoir.empty() if water_levels is None else water_levels[1]
                end = reservoir.full(ld["level"]) if water_levels is None else \
                    (ld["level"] if ld["level"] is not None else start[0],) + tuple(start[1:])
                if water_levels is None and ld["level"] is not None and ld["level"] <= reservoir.face.bottom:
                    raise SceneError(f"{key}.level", f"{ld['level']:g} m is not above the lowest point of the face "
                                                     f"'{reservoir.face.name}' ({reservoir.face.bottom:g} m)")
                water_levels = (start, end)
            elif ld["type"] == "self_weight" and "acceleration" in ld:  # a body force in its own direction
                force += ld["factor"] * L.self_weight(model, ld["acceleration"])
            elif ld["type"] == "self_weight":
                if weight is None:
                    weight = L.self_weight(model, scene["model"]["gravity"])
                force += ld["factor"] * weight
            elif ld["type"] in ("nodal", "traction", "pressure"):
                force += _load_vector(scene, mesh, model, ld, key)
            else:  # displacement
                nodes = _node_set(mesh, ld["set"], f"{key}.set")
                for c, v in zip(ld["components"], ld["value"]):
                    d = nodes * dim + "xyz".index(c)
                    if supports[d].any():
                        raise SceneError(f"{key}.set", f"prescribes component {c} on nodes that are supports")
                    presc[d] = True
                    incr[d] = v
        water = None
        if water_levels is not None:
            from ..effects.reservoir import StageWater

            start, end = water_levels
            water = StageWater(reservoir, start, end)
            water_levels = (end, end)  # later stages keep the water where this one left it
        viscous = [g.name for g in model.cgroups if g.plastic and g.law_params[0, P_VISCOSITY] > 0]
        if viscous and "duration" not in st:
            raise SceneError(f"stages[{i}].duration", f"blocks {viscous} have Perzyna viscosity: a static stage needs "
                                                      "its duration (s), the time over which its load is applied (set "
                                                      "viscosity = 0 for a rate-independent law)")
        relaxing = [g.name for g in model.igroups if g.relaxation_time > 0]
        if relaxing and "duration" not in st:
            raise SceneError(f"stages[{i}].duration", f"joint sets {relaxing} have a relaxation_time (viscous "
                                                      "regularisation): a static stage needs its duration (s), the "
                                                      "time over which its load is applied")
        if water is not None and st.get("control", "load") != "load":
            raise SceneError(f"stages[{i}].control", f"\"{st['control']}\": path following does not carry the reservoir's "
                             "water on this stage (its loads follow the level and the cracks, not one load factor); "
                             "use \"load\"")
        if st.get("control") == "dissipation":
            softening = [g for g in model.igroups if g.nonlinear]
            large = [g.name for g in softening if g.kinematics != "small"]
            if not softening or large:
                raise SceneError(f"stages[{i}].control", "\"dissipation\" follows the energy dissipated by joints "
                                 "that crack or slip with small displacements: " + (
                                     f"joint sets {large} use large kinematics" if large else
                                     "this model has no composite or Mohr-Coulomb joint set")
                                 + " (use \"arc_length\")")
        stages.append(StaticStage(st["name"], st["steps"], force, presc, incr, supports.copy(), water=water,
                                  until_failure=st.get("until_failure", False), duration=st.get("duration", 0.0),
                                  control=st.get("control", "load")))
        held = presc.copy()
    return stages


def initial_velocity_field(model: Model, items: list, key: str, translation="velocity",
                           rotation="angular_velocity") -> np.ndarray:
    """(n_dof,) m/s: the initial velocities of a dynamic stage (normalised ``initial_velocity`` items) at
    the nodes of their element groups, NaN elsewhere; a rotation is ``v = w x (x - c)`` (small-rotation
    rigid motion). With ``translation="displacement", rotation="rotation"`` the initial displacements (m) of
    ``initial_displacement`` items, ``u = theta x (x - c)`` for a (small) rotation."""
    dim = model.dim
    v = np.full(model.n_dof, np.nan)
    names = sorted({g.name for g in model.cgroups})
    for j, it in enumerate(items):
        nodes = []
        for name in it["groups"]:
            found = [g for g in model.cgroups if g.name == name]
            if not found:
                raise SceneError(f"{key}.groups" if len(items) == 1 else f"{key}[{j}].groups",
                                 f"no element group '{name}' (groups: {names})")
            nodes += [np.unique(g.conn) for g in found]
        nodes = np.unique(np.concatenate(nodes))
        if translation in it:
            vel = np.tile(np.asarray(it[translation], dtype=float), (len(nodes), 1))
        else:
            r = model.coords[nodes] - np.asarray(it["rotation_center"], dtype=float)
            w = it[rotation]
            vel = (np.stack([-w * r[:, 1], w * r[:, 0]], axis=1) if dim == 2 else
                   np.cross(np.asarray(w, dtype=float), r))
        v[(nodes[:, None] * dim + np.arange(dim)).ravel()] = vel.ravel()
    return v


def effects(scene: dict, model: Model) -> list[str]:
    """Human-readable list of what the run simulates."""
    m = scene["model"]
    groups = ', '.join(sorted({g.name for g in model.cgroups if not g.plastic}))
    out = []
    kind = "elastic (St. Venant-Kirchhoff)" if model.large else "linear elastic"
    if groups:
        if model.dim == 2:
            out = [f"{m['hypothesis'].replace('_', ' ')} {kind} continuum ({groups}; thickness {m['thickness']:g} m)"]
        else:
            out = [f"3D {kind} continuum ({groups})"]
    mc_sets = [g.name for g in model.igroups if g.law == "mohr_coulomb"]
    lin_sets = [g.name for g in model.igroups if g.law == "linear"]
    if mc_sets:
        out.append("Mohr-Coulomb joints with slip, opening and re-contact (Tzamtzis & Asteris, sec. 3.4): " + ", ".join(sorted(set(mc_sets))))
    if lin_sets:
        out.append("linear elastic joints: " + ", ".join(sorted(set(lin_sets))))
    comp_sets = [g.name for g in model.igroups if g.law == "composite"]
    if comp_sets:
        out.append("composite masonry joints (Lourenco & Rots 1997): tension cut-off with exponential softening "
                   "(GfI), Coulomb friction with cohesion softening (GfII) and dilatancy, compression cap where "
                   "given: " + ", ".join(sorted(set(comp_sets))))
    relaxing = [f"{g.name} {g.relaxation_time * 1e3:g} ms" for g in model.igroups if g.relaxation_time > 0]
    if relaxing:
        out.append("viscous regularisation of the composite joints (Duvaut-Lions; an approximation of the "
                   "inviscid law, to be converged in the relaxation time): " + ", ".join(relaxing))
    tied = [f"{s['set']} ({', '.join(s['components'])})" for s in scene["supports"] if s["kind"] == "tied"]
    if tied:
        out.append("tied supports (the set moves as one in these components): " + ", ".join(tied))
    controls = sorted({st.get("control", "load") for st in scene["stages"] if st["type"] == "static"} - {"load"})
    if controls:
        out.append("static path following: " + ", ".join(
            {"arc_length": "arc-length control (Crisfield's cylindrical)",
             "opening": "indirect displacement control on the opening of the cracking joints (de Borst 1987)",
             "dissipation": "dissipation-based arc-length control on the joints' plastic work (Gutierrez 2004; "
                            "Verhoosel et al. 2009)"}[c]
            for c in controls))
    from ..effects import simulated

    return out + simulated(scene, model)
