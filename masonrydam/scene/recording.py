"""What a run records besides the effects' own variables: the recorded nodes and joint points, the joint
results of a step, the block cells and element centroids, the pushover stages and the ground motions of
the dynamic stages (result attributes and records at their own rate)."""
from __future__ import annotations

import json

import numpy as np

from ..elements.shapes import ELEMENT_TYPES
from ..errors import SceneError
from ..solvers.dynamic import DynamicStage
from .build import node_set


def output_selection(scene, mesh, model):
    """Recorded nodes and joint groups: the ``[output]`` section, or the ``output`` of a dynamic stage
    (which then applies to the whole file)."""
    scene = dict(scene, output=dict(scene["output"]))
    for st in scene["stages"]:
        if st["type"] == "dynamic":
            for k in ("nodes", "joints"):
                if st["output"][k] is not None:
                    scene["output"][k] = st["output"][k]
    sel = scene["output"]["nodes"]
    if sel == "all":
        nodes = np.arange(model.n_nodes)
    else:
        nodes = np.unique(np.concatenate([node_set(mesh, s, "output.nodes") for s in sel]))
    jsel = scene["output"]["joints"]
    names = sorted({g.name for g in model.igroups})
    if jsel != "all":
        for s in jsel:
            if s not in names:
                raise SceneError("output.joints", f"no joint set '{s}' (joint sets: {names})")
    groups = [g for g in model.igroups if jsel == "all" or g.name in jsel]
    return nodes, groups, names


def joint_points(groups, set_names, dim):
    xs, sets, elems, pts, normals, axes, weights = [], [], [], [], [], [], []
    for g in groups:
        ne, nip = g.n_elem, g.nip
        xs.append(g.points.reshape(-1, dim))
        sets.append(np.full(ne * nip, set_names.index(g.name)))
        elems.append(np.repeat(np.arange(ne), nip))
        pts.append(np.tile(np.arange(nip), ne))
        normals.append(g.frame[:, :, dim - 1, :].reshape(-1, dim))
        axes.append(g.frame[:, :, : dim - 1, :].reshape(-1, dim - 1, dim))
        weights.append((g.jw * g.thickness[:, None]).ravel())
    if not groups:
        z = np.zeros((0, dim))
        return {"x": z, "set": np.zeros(0, int), "set_names": set_names, "element": np.zeros(0, int),
                "point": np.zeros(0, int), "normal": z, "shear_axes": np.zeros((0, dim - 1, dim)), "weight": np.zeros(0),
                "nodes": np.zeros((0, 2, 1), int), "shape": np.zeros((0, 1))}
    n_face = max(g.conn.shape[1] // 2 for g in groups)
    nodes = np.full((sum(g.n_elem * g.nip for g in groups), 2, n_face), -1, dtype=np.int64)
    shape = np.zeros((len(nodes), n_face))
    k = 0
    for g in groups:  # each point: the faces of its element (conn: bottom face nodes, then top face nodes)
        ns, n = g.conn.shape[1] // 2, g.n_elem * g.nip
        nodes[k:k + n, :, :ns] = np.repeat(g.conn.reshape(g.n_elem, 2, ns), g.nip, axis=0)
        shape[k:k + n, :ns] = np.tile(g.N, (g.n_elem, 1))
        k += n
    return {"x": np.vstack(xs), "set": np.concatenate(sets), "set_names": set_names, "element": np.concatenate(elems),
            "point": np.concatenate(pts), "normal": np.vstack(normals), "shear_axes": np.concatenate(axes),
            "weight": np.concatenate(weights), "nodes": nodes, "shape": shape}


def joint_results(groups, dim):
    if not groups:
        z = np.zeros(0)
        return {"opening": z, "slip": z.reshape(0, dim - 1), "plastic_slip": z.reshape(0, dim - 1),
                "t_normal": z, "t_shear": z.reshape(0, dim - 1), "state": z.astype(np.int8)}
    d = np.concatenate([g.delta.reshape(-1, dim) for g in groups])
    t = np.concatenate([g.traction.reshape(-1, dim) for g in groups])
    slip = np.concatenate([g.plastic_slip().reshape(-1, dim - 1) for g in groups])  # (each law's own columns)
    return {"opening": d[:, -1], "slip": d[:, :-1], "plastic_slip": slip,
            "t_normal": t[:, -1], "t_shear": t[:, :-1], "state": np.concatenate([g.result_states().ravel() for g in groups])}


def block_cells(model) -> dict:
    """Corner nodes of every continuum element (element group after group), -1 padded to the largest
    count, with each element's group: the connectivity of the result file (``block_cell_nodes``)."""
    corners = [g.conn[:, :ELEMENT_TYPES[g.type].corner_nodes] for g in model.cgroups]
    nodes = np.full((sum(len(c) for c in corners), max((c.shape[1] for c in corners), default=1)), -1, np.int64)
    k = 0
    for c in corners:
        nodes[k:k + len(c), :c.shape[1]] = c
        k += len(c)
    return {"nodes": nodes, "group": np.repeat(np.arange(len(corners)), [len(c) for c in corners]),
            "group_names": [g.name for g in model.cgroups], "group_types": [g.type for g in model.cgroups]}


def element_info(model) -> dict:
    """Groups and centroids of the continuum elements, for ``[output] stress = "element"``."""
    return {"group": np.concatenate([np.full(g.n_elem, i) for i, g in enumerate(model.cgroups)]),
            "group_names": [g.name for g in model.cgroups],
            "centroid": np.vstack([model.coords[g.conn].mean(axis=1) for g in model.cgroups])}


def pushover_stages(static_stages, model) -> str:
    """JSON ``{component: [stage indices]}``: for each component, the static stages that prescribe a non-zero
    displacement increment of a DOF the last driving stage drives (a cyclic test's successive pushes), in
    order: the steps of a pushover or hysteresis curve (:func:`masonrydam.results.pushover.pushover_data`)."""
    driven = driven_dofs(static_stages, model)
    out = {}
    if driven is None:
        return json.dumps(out)
    for c in range(model.dim):
        last = int(driven[:, c].max())
        if last == 0:
            continue
        dofs = np.flatnonzero(driven[:, c] == last) * model.dim + c
        out["xyz"[c]] = [i for i, st in enumerate(static_stages)
                         if (st.prescribed[dofs] & (st.increment[dofs] != 0.0)).any()]
    return json.dumps(out)


def driven_dofs(static_stages, model):
    """(n_nodes, dim) int: 1 + the index of the last static stage that prescribes a non-zero displacement
    increment of each DOF (0: none), the actuator of a pushover; None when no stage does."""
    out = np.zeros(model.n_dof, dtype=np.int32)
    for i, st in enumerate(static_stages):
        out[st.prescribed & (st.increment != 0.0)] = i + 1
    return out.reshape(-1, model.dim) if out.any() else None


def dynamic_attrs(stages) -> dict:
    """Ground-motion provenance and integrator settings of the dynamic stages, as netCDF attributes."""
    out = {}
    for i, st in enumerate(stages):
        if not isinstance(st, DynamicStage):
            continue
        out[f"stage{i}_dynamic_settings"] = json.dumps(st.settings.as_dict(), sort_keys=True)
        out[f"stage{i}_duration_s"] = float(st.duration)
        out[f"stage{i}_output_stride"] = int(st.output_stride)
        for g in st.ground_motion:
            c = "xyz"[g.component]
            prefix = f"stage{i}_ground_motion_{c}_"
            out[prefix + "name"] = g.name
            out[prefix + "pga_m_s2"] = float(np.max(np.abs(g.values)))
            for k, v in g.attrs.items():
                out[prefix + k] = v
    out["time_history_conventions"] = ("displacement, velocity and acceleration are relative to the ground "
                                       "(supports); acceleration_absolute = acceleration + ground_acceleration; "
                                       "time is NaN for static steps")
    return out


def ground_records(dyn_stages) -> dict:
    """``{component letter: (time (n,), acceleration (n,))}``: the ground-acceleration samples the dynamic
    stages use, at the records' own rate (:meth:`~masonrydam.results.writer.ResultWriter.write_ground_records`):
    each stage's samples within its duration, at the stage's start time plus ``i dt`` (time since the start of
    the first dynamic stage, the result's ``time``); a NaN value (at the next stage's first time) between two
    stages' records of one component, so that no line joins them."""
    out = {}
    t0 = 0.0
    for st in dyn_stages:
        for g in st.ground_motion:
            n = min(len(g.values), int(np.floor(st.duration / g.dt * (1.0 + 1e-12))) + 1)
            t = t0 + np.arange(n) * g.dt
            parts = out.setdefault("xyz"[g.component], [])
            if parts:
                parts.append((t[:1], np.array([np.nan])))
            parts.append((t, g.values[:n]))
        t0 += st.duration
    return {c: (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))
            for c, parts in out.items()}
