"""Streaming netCDF4 writer for analysis results.

The file is created before the first step with an unlimited ``step`` dimension; every converged
step is appended and flushed (``sync``), so a run that stops (non-convergence, a mechanism, a kill)
leaves a readable file with every finished step, marked ``completed = "false"`` with a ``status``
(``running`` until the file is closed; ``failed``, ``interrupted`` or ``terminated``) and a
``status_reason``. Where the file goes (a working file beside the target, renamed over it when the
run completes) is :mod:`masonrydam.results.files`.
``xarray.open_dataset`` reads it; every variable carries ``units`` and ``long_name``.

Time histories (scenes with a dynamic stage, ``dynamic=True``): the same unlimited ``step``
dimension carries static and dynamic steps; ``time`` (s, on ``step``) is the time since the start
of the first dynamic stage, NaN for static steps, and is listed as an auxiliary coordinate of every
step variable (``coordinates = "time"``), so that ``ds.where(ds.stage == k, drop=True)
.swap_dims(step="time")`` gives a stage's history with time as its index. One dimension for all
steps keeps the static state and the dynamic history in one file with one set of variables, and
appending is the same for both. Dynamic variables (NaN for static steps): ``velocity`` and
``acceleration`` relative to the ground, ``acceleration_absolute`` (relative plus ground),
``ground_acceleration`` (step, component) and the energies ``energy_*`` (J, cumulative since the
start of the first dynamic stage). Only recorded steps (every ``stride``-th step of a dynamic stage,
its first and last, and the last converged state before a failure) are written; memory does not
grow with the record length.
"""
from __future__ import annotations

import datetime as _dt
import json

import netCDF4
import numpy as np

from .._version import __version__

STATE_FLAGS = {"flag_values": np.array([0, 1, 2], dtype=np.int8), "flag_meanings": "stick slip open"}
#: energies of a dynamic analysis (J, cumulative since the start of the first dynamic stage)
ENERGY_VARIABLES = {
    "input": "work of the ground motion (effective earthquake forces -M iota a_g) on the relative displacements",
    "external": "work of the constant loads of the static stages (gravity) during the dynamic stages",
    "kinetic": "change of kinetic energy (relative velocities)",
    "strain": "change of elastic strain energy of the continuum",
    "damping": "energy dissipated by viscous (Rayleigh) damping",
    "joint": "work done on the joints (elastic energy stored plus energy dissipated by slip and opening)",
    "joint_stored": "change of elastic energy stored in the joints",
    "joint_dissipated": "energy dissipated in the joints (joint work minus the stored part)",
    "error": "energy balance error: input + external - (kinetic + strain + damping + joint); numerical "
             "dissipation of the integrator and the Newton tolerance",
}


class ResultWriter:
    """Write a static analysis to ``path``.

    nodes: (n_out,) node indices recorded; coords: (n_nodes, dim);
    joint_points: dict with 'x' (n_jp, dim), 'set' (n_jp,) int, 'set_names', 'element' (n_jp,),
    'point' (n_jp,), 'normal' (n_jp, dim), 'shear_axes' (n_jp, dim-1, dim), 'weight' (n_jp,) (tributary length*thickness or area, m2).
    """

    def __init__(self, path, coords, nodes, joint_points, dim, attrs: dict, dynamic: bool = False):
        self.path = str(path)
        self.dim = dim
        self.dynamic = bool(dynamic)
        self.nc = nc = netCDF4.Dataset(self.path, "w", format="NETCDF4")
        comps = ["x", "y", "z"][:dim]
        shear = ["t"] if dim == 2 else ["t1", "t2"]
        nc.createDimension("step", None)
        nc.createDimension("node", len(nodes))
        nc.createDimension("component", dim)
        nc.createDimension("joint_point", len(joint_points["element"]))
        nc.createDimension("shear_direction", dim - 1)
        self._string_coord("component", ("component",), comps, "displacement/force component")
        self._string_coord("shear_direction", ("shear_direction",), shear, "joint tangential direction")
        self._var("step", "i4", ("step",), "1", "analysis step (converged increments, all stages)")
        self._var("load_factor", "f8", ("step",), "1", "load factor within the stage (0 to 1)")
        self._var("stage", "i4", ("step",), "1", "stage index (see attribute stage_names)")
        self.nc["stage"].stage_names = json.dumps(attrs.get("stage_names", []))
        self._var("iterations", "i4", ("step",), "1", "Newton iterations of the step")
        v = self._var("node", "i8", ("node",), "1", "node index in the model")
        v[:] = nodes
        for k, c in enumerate(comps):
            v = self._var(c, "f8", ("node",), "m", f"{c} coordinate of the node (undeformed)")
            v[:] = coords[nodes, k]
        jp = joint_points
        self._var("joint_point", "i8", ("joint_point",), "1", "joint integration point index")[:] = \
            np.arange(len(jp["element"]))
        v = self._var("joint_set", "i4", ("joint_point",), "1", "joint set index (see attribute set_names)")
        v[:] = jp["set"]
        v.set_names = json.dumps(jp["set_names"])
        self._var("joint_element", "i8", ("joint_point",), "1", "interface element index within its joint set")[:] = jp["element"]
        self._var("joint_integration_point", "i4", ("joint_point",), "1", "integration point index within the element")[:] = jp["point"]
        for k, c in enumerate(comps):
            self._var(f"joint_{c}", "f8", ("joint_point",), "m", f"{c} coordinate of the joint integration point")[:] = jp["x"][:, k]
            self._var(f"joint_normal_{c}", "f8", ("joint_point",), "1", f"{c} component of the joint unit normal (bottom to top)")[:] = jp["normal"][:, k]
        v = self._var("joint_shear_axis", "f8", ("joint_point", "shear_direction", "component"), "1",
                      "unit vector of each shear direction of the joint (global components)")
        v[:] = jp["shear_axes"]
        self._var("joint_weight", "f8", ("joint_point",), "m2",
                  "joint area represented by the integration point (length x thickness in 2D)")[:] = jp["weight"]
        self._var("displacement", "f8", ("step", "node", "component"), "m",
                  "nodal displacement relative to the moving ground" if self.dynamic else "nodal displacement")
        self._var("reaction", "f8", ("step", "node", "component"), "N",
                  "reaction force at constrained DOFs (zero elsewhere)")
        self._var("joint_opening", "f8", ("step", "joint_point"), "m",
                  "normal relative displacement top minus bottom (opening positive)")
        self._var("joint_slip", "f8", ("step", "joint_point", "shear_direction"), "m",
                  "tangential relative displacement top minus bottom")
        self._var("joint_plastic_slip", "f8", ("step", "joint_point", "shear_direction"), "m",
                  "irreversible (plastic) part of the tangential relative displacement")
        self._var("joint_traction_normal", "f8", ("step", "joint_point"), "Pa",
                  "normal traction on the joint (tension positive)")
        self._var("joint_traction_shear", "f8", ("step", "joint_point", "shear_direction"), "Pa",
                  "shear traction on the joint")
        v = self._var("joint_state", "i1", ("step", "joint_point"), "1", "joint state: 0 stick, 1 slip, 2 open")
        v.flag_values = STATE_FLAGS["flag_values"]
        v.flag_meanings = STATE_FLAGS["flag_meanings"]
        if self.dynamic:
            self._dynamic_variables()
        nc.Conventions = "CF-1.8"
        nc.title = attrs.get("title", "masonrydam analysis")
        nc.source = f"masonrydam {__version__}"
        nc.masonrydam_version = __version__
        nc.history = f"{_dt.datetime.now(_dt.timezone.utc).isoformat(timespec='seconds')} created by masonrydam {__version__}"
        for k, val in attrs.items():
            if k in ("title", "stage_names"):
                continue
            nc.setncattr(k, val if isinstance(val, (str, int, float)) else json.dumps(val))
        nc.completed = "false"
        nc.status = "running"
        nc.sync()
        self.n = 0
        #: the step variables, looked up once; records are appended by ``Variable._put`` (see _append)
        self._step_vars = {name: nc[name] for name in nc.variables
                           if nc[name].dimensions and nc[name].dimensions[0] == "step"}
        self._fast_append = hasattr(netCDF4.Variable, "_put")

    def _dynamic_variables(self):
        nc = self.nc
        v = self._var("time", "f8", ("step",), "s", "time since the start of the first dynamic stage "
                                                      "(NaN for static steps)", fill_value=np.nan)
        v.standard_name = "time"
        v.axis = "T"
        self._var("velocity", "f8", ("step", "node", "component"), "m/s",
                  "nodal velocity relative to the ground (supports)", fill_value=np.nan)
        self._var("acceleration", "f8", ("step", "node", "component"), "m/s2",
                  "nodal acceleration relative to the ground (supports)", fill_value=np.nan)
        self._var("acceleration_absolute", "f8", ("step", "node", "component"), "m/s2",
                  "absolute nodal acceleration (relative acceleration plus ground acceleration)",
                  fill_value=np.nan)
        self._var("ground_acceleration", "f8", ("step", "component"), "m/s2",
                  "ground (support) acceleration of the uniform base excitation", fill_value=np.nan)
        for name, text in ENERGY_VARIABLES.items():
            self._var(f"energy_{name}", "f8", ("step",), "J", text, fill_value=np.nan)
        for name in nc.variables:
            var = nc[name]
            if var.dimensions and var.dimensions[0] == "step" and name not in ("step", "time"):
                var.coordinates = "time"

    def _string_coord(self, name, dims, values, long_name):
        v = self.nc.createVariable(name, str, dims)
        for i, s in enumerate(values):
            v[i] = s
        v.long_name = long_name
        v.units = "1"

    def _var(self, name, dtype, dims, units, long_name, fill_value=None):
        v = self.nc.createVariable(name, dtype, dims, zlib=False, fill_value=fill_value)
        v.units = units
        v.long_name = long_name
        return v

    def _append(self, name, k, value):
        """Write record ``k`` of the step variable ``name``.

        Through netCDF4-python's low-level ``Variable._put(data, start, count, stride)`` when it has one:
        the public ``var[k] = value`` spends about 0.12 ms per call in Python (index parsing, masking)
        around a write that takes 0.02 ms (measured with netCDF4 1.7.5), and a seismic run writes 26
        variables per recorded step, which made the output the largest cost of a run outside the
        solver. ``_put`` is private but has had this signature since netCDF4-python 1.0; if it is
        missing or refuses the call, this writer switches to the public API for good (same file)."""
        var = self._step_vars[name]
        if self._fast_append:
            shape = var.shape[1:]
            data = np.ascontiguousarray(value, dtype=var.dtype).reshape((1,) + shape)
            nd = len(shape) + 1
            start = np.zeros(nd, dtype=np.intp)
            start[0] = k
            count = np.array((1,) + shape, dtype=np.intp)
            try:
                var._put(data, start, count, np.ones(nd, dtype=np.intp))
                return
            except (AttributeError, TypeError):
                self._fast_append = False
        var[k] = value

    def write_step(self, stage, load_factor, iterations, displacement, reaction, joints, dynamic=None):
        """Append one converged step. displacement, reaction: (n_out, dim);
        joints: dict opening (n_jp,), slip (n_jp, dim-1), plastic_slip, t_normal, t_shear, state;
        dynamic (time-history files, dynamic steps): dict time (s), velocity, acceleration,
        acceleration_absolute (n_out, dim), ground_acceleration (dim,), energy (dict name -> J)."""
        k = self.n
        put = self._append
        if self.dynamic:
            if dynamic is None:
                put("time", k, np.nan)
            else:
                put("time", k, dynamic["time"])
                put("velocity", k, dynamic["velocity"])
                put("acceleration", k, dynamic["acceleration"])
                put("acceleration_absolute", k, dynamic["acceleration_absolute"])
                put("ground_acceleration", k, dynamic["ground_acceleration"])
                for name in ENERGY_VARIABLES:
                    put(f"energy_{name}", k, dynamic["energy"][name])
        elif dynamic is not None:
            raise ValueError("this writer was created without dynamic=True")
        put("step", k, k)
        put("load_factor", k, load_factor)
        put("stage", k, stage)
        put("iterations", k, iterations)
        put("displacement", k, displacement)
        put("reaction", k, reaction)
        if len(joints["opening"]):
            put("joint_opening", k, joints["opening"])
            put("joint_slip", k, joints["slip"])
            put("joint_plastic_slip", k, joints["plastic_slip"])
            put("joint_traction_normal", k, joints["t_normal"])
            put("joint_traction_shear", k, joints["t_shear"])
            put("joint_state", k, joints["state"])
        self.n += 1
        self.nc.sync()

    def close(self, completed: bool, status: str, extra_attrs: dict | None = None, reason: str | None = None):
        """Finish the file: ``completed`` ("true"/"false"), ``status`` (``"completed"``, ``"failed"``,
        ``"interrupted"``, ``"terminated"``; a file never closed keeps ``"running"``) and, for a run
        that ended early, ``status_reason`` (the error or the step it stopped at)."""
        if not self.nc.isopen():
            return
        for k, val in (extra_attrs or {}).items():
            self.nc.setncattr(k, val if isinstance(val, (str, int, float)) else json.dumps(val))
        self.nc.completed = "true" if completed else "false"
        self.nc.status = status
        if reason is not None:
            self.nc.status_reason = reason
        self.nc.close()
