"""Streaming netCDF4 writer for analysis results.

The file is created before the first step with an unlimited ``step`` dimension. Converged steps are
collected in memory and appended in blocks (:class:`OutputOptions`: every ``buffer_steps`` steps or
``flush_seconds`` seconds, whichever comes first), each block with one write per variable and one
flush (``sync``), in chunks along ``step``; memory stays bounded by the block, whatever the length of
the record. ``close`` writes the steps still in memory, so a run that stops cleanly (an error, Ctrl-C,
SIGTERM) loses no converged step; a killed process leaves a readable file with every block written
before it, ``status = "running"``. A closed file is marked ``completed`` ``"true"`` or ``"false"``
with a ``status`` (``failed``, ``interrupted`` or ``terminated``) and a ``status_reason``. Where the
file goes (a working file beside the target, renamed over it when the run completes) is
:mod:`masonrydam.results.files`. ``xarray.open_dataset`` reads it; every variable carries ``units``
and ``long_name``.

The mesh is written once, as static variables: the continuum elements' corner nodes
(``block_cell_nodes``, model node indices, -1 padding) and groups (``block_cell_group``), and for each
joint point the faces of its interface element with the shape functions at the point
(``joint_point_nodes``, ``joint_point_shape``), so that a step can be drawn deformed
(:mod:`masonrydam.results.deformed`).

Time histories (scenes with a dynamic stage, ``dynamic=True``): the same unlimited ``step``
dimension carries static and dynamic steps; ``time`` (s, on ``step``) is the time since the start
of the first dynamic stage, NaN for static steps, and is listed as an auxiliary coordinate of every
step variable (``coordinates = "time"``), so that ``ds.where(ds.stage == k, drop=True)
.swap_dims(step="time")`` gives a stage's history with time as its index. One dimension for all
steps keeps the static state and the dynamic history in one file with one set of variables, and
appending is the same for both. Dynamic variables (NaN for static steps): ``velocity`` and
``acceleration`` relative to the ground, ``acceleration_absolute`` (relative plus ground),
``ground_acceleration`` (step, component) and the energies ``energy_*`` (J, cumulative since the
start of the first dynamic stage); off the ``step`` dimension, each ground-motion component's record at
its own sampling rate (``ground_acceleration_record_<c>`` on ``ground_record_<c>``, with its time
``ground_record_time_<c>``: :meth:`ResultWriter.write_ground_records`). Only recorded steps (every
``stride``-th step of a dynamic stage, its first and last, and the last converged state before a
failure) are written; memory does not grow with the record length.
"""
from __future__ import annotations

import datetime as _dt
import json
import time
from dataclasses import dataclass

import netCDF4
import numpy as np

from .._version import __version__
from .variables import ResultDimension

#: joint states (``InterfaceGroup.result_states``); 3 (crush: on the compression cap) only with composite joints
STATE_FLAGS = {"flag_values": np.array([0, 1, 2, 3], dtype=np.int8), "flag_meanings": "stick slip open crush"}
#: energies of a dynamic analysis (J, cumulative since the start of the first dynamic stage)
ENERGY_VARIABLES = {
    "input": "work of the ground motion (effective earthquake forces -M iota a_g on the relative displacements, or "
             "free-field forces at a compliant base) and of the pore pressure entering opening joints",
    "external": "work of the constant loads of the static stages (gravity) during the dynamic stages",
    "hydrodynamic": "work of the hydrodynamic pressure of an acoustic (compressible) reservoir on the dam",
    "kinetic": "change of kinetic energy (relative velocities)",
    "strain": "change of elastic strain energy of the continuum",
    "damping": "energy dissipated by viscous (Rayleigh) damping",
    "joint": "work done on the joints (elastic energy stored plus energy dissipated by slip and opening)",
    "joint_stored": "change of elastic energy stored in the joints",
    "joint_dissipated": "energy dissipated in the joints (joint work minus the stored part)",
    "joint_friction": "energy dissipated by friction in the joints (traction times plastic slip)",
    "joint_bond_break": "energy released where joint bonds broke (tension cut off, Tzamtzis & Asteris sec. 3.4)",
    "joint_contact": "energy lost at joint impacts (points closing), less that gained where compressed points "
                     "opened within a step (trapezoidal rule over a contact event)",
    "numerical": "numerical dissipation of the time integrator (HHT, generalized-alpha: high-frequency "
                 "damping; zero for the trapezoidal rule)",
    "error": "energy balance error: input + external + hydrodynamic - (kinetic + strain + damping + joint_stored + "
             "joint_friction + joint_bond_break + joint_contact + numerical): Newton tolerance and round-off",
}


@dataclass(frozen=True)
class OutputOptions:
    """How the steps reach the file (scene section ``[output]``).

    buffer_steps: steps collected in memory before they are written as one block (also capped so that
    a block takes at most :data:`BUFFER_BYTES_MAX`); flush_seconds: a block is written at the latest
    this long after the previous one, so that a slow run shows its progress in the file and a killed
    one loses at most that much; precision: ``"double"`` (float64) or ``"single"`` (float32: half the
    size, about 7 significant digits) for the nodal and joint fields (times, load factors and energies
    stay double); compression: zlib level 0 (none) to 9 of the step variables (with byte shuffling).
    """

    buffer_steps: int = 256
    flush_seconds: float = 2.0
    precision: str = "double"
    compression: int = 0


#: largest memory (bytes) of one block of buffered steps; a block of a large model holds fewer steps
BUFFER_BYTES_MAX = 64 * 2**20
#: target size (bytes) of one HDF5 chunk of a step variable along ``step``
CHUNK_BYTES = 2**20


def _record_size(var) -> int:
    """Values in one step of a step variable."""
    return int(np.prod(var.shape[1:], dtype=np.int64))


class ResultWriter:
    """Write an analysis to ``path``, step by step (``write_step``), in blocks (``options``).

    nodes: (n_out,) node indices recorded; coords: (n_nodes, dim);
    joint_points: dict with 'x' (n_jp, dim), 'set' (n_jp,) int, 'set_names', 'element' (n_jp,),
    'point' (n_jp,), 'normal' (n_jp, dim), 'shear_axes' (n_jp, dim-1, dim), 'weight' (n_jp,) (tributary length*thickness or area, m2),
    optionally 'nodes' (n_jp, 2, n_face) int (model node indices of the element's bottom and top face, -1
    padding) and 'shape' (n_jp, n_face) (face shape functions at the point, 0 padding);
    blocks: dict with 'nodes' (n_cells, n_corners) int (model node indices of the corner nodes of each
    continuum element, -1 padding), 'group' (n_cells,) int, 'group_names', 'group_types' (per group).
    """

    #: step variables of time-history files that static steps leave NaN
    _DYNAMIC_ONLY = frozenset(["time", "velocity", "acceleration", "acceleration_absolute", "ground_acceleration"]
                              + [f"energy_{name}" for name in ENERGY_VARIABLES])

    def __init__(self, path, coords, nodes, joint_points, dim, attrs: dict, dynamic: bool = False,
                 options: OutputOptions | None = None, elements: dict | None = None, modes: int | None = None,
                 driven: np.ndarray | None = None, blocks: dict | None = None, variables=()):
        self.path = str(path)
        self.dim = dim
        self.dynamic = bool(dynamic)
        self.options = options = options or OutputOptions()
        if options.precision not in ("double", "single"):
            raise ValueError(f"precision must be 'double' or 'single', got {options.precision!r}")
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
        if driven is not None:  # (n_nodes, dim) stage index + 1 of the last static stage driving the DOF, 0: none
            self._var("driven", "i4", ("node", "component"), "1",
                      "1 + index of the last static stage that prescribes a displacement increment of the DOF "
                      "(0: none): the actuator DOFs of a pushover")[:] = driven[nodes]
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
        if "nodes" in jp:
            self._joint_interpolation(jp["nodes"], jp["shape"])
        if blocks is not None:
            self._block_variables(blocks)
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
        v = self._var("joint_state", "i1", ("step", "joint_point"), "1", "joint state: 0 stick, 1 slip, 2 open, 3 crush")
        v.flag_values = STATE_FLAGS["flag_values"]
        v.flag_meanings = STATE_FLAGS["flag_meanings"]
        dynamic_only = set()
        for item in variables:  # what the effects of the run record (masonrydam.results.variables)
            if self._declare(item):
                dynamic_only.add(item.name)
        if elements:
            self._element_variables(elements)
        if modes:
            self._mode_variables(modes)
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
        #: steps written or collected so far (all of them are in the file after ``flush``/``close``)
        self.n = 0
        #: the step variables with a non-empty record, and a block buffer for each
        self._step_vars = {name: nc[name] for name in nc.variables
                           if nc[name].dimensions[:1] == ("step",) and _record_size(nc[name]) > 0}
        record_bytes = sum(v.dtype.itemsize * _record_size(v) for v in self._step_vars.values())
        self.block_steps = max(1, min(options.buffer_steps, BUFFER_BYTES_MAX // max(record_bytes, 1)))
        self._buffers = {name: np.empty((self.block_steps,) + v.shape[1:], dtype=v.dtype)
                         for name, v in self._step_vars.items()}
        self._dynamic_names = [name for name in self._step_vars if name in self._DYNAMIC_ONLY or name in dynamic_only]
        self._in_buffer = 0  # steps in the buffers, not yet in the file
        self._last_flush = time.monotonic()
        self._fast_append = hasattr(netCDF4.Variable, "_put")

    def _block_variables(self, blocks):
        """The continuum elements (static, for drawing the deformed blocks): dimension ``block_cell`` (every
        continuum element, element group after group: the order of ``element`` where stress is written),
        ``block_cell_nodes`` (block_cell, block_cell_node) the model node indices (values of the ``node``
        coordinate) of the element's corner nodes in the element's order (in 2D the boundary order), -1
        padding, and ``block_cell_group`` (block_cell) the index of its element group."""
        nodes = np.asarray(blocks["nodes"])
        self.nc.createDimension("block_cell", len(nodes))
        self.nc.createDimension("block_cell_node", nodes.shape[1])
        self._var("block_cell_nodes", "i4", ("block_cell", "block_cell_node"), "1",
                  "model node index (as the node coordinate) of each corner node of the continuum element, "
                  "in the element's corner order (-1: padding)")[:] = nodes
        v = self._var("block_cell_group", "i4", ("block_cell",), "1",
                      "element group index of the continuum element (see attributes group_names, group_types)")
        v[:] = blocks["group"]
        v.group_names = json.dumps(list(blocks["group_names"]))
        v.group_types = json.dumps(list(blocks["group_types"]))

    def _joint_interpolation(self, nodes, shape):
        """Where a joint point takes its displacement from: ``joint_point_nodes`` (joint_point, joint_side,
        joint_face_node) the model node indices of the bottom and top face of its interface element (-1
        padding) and ``joint_point_shape`` (joint_point, joint_face_node) the face shape functions at the
        point, so that the displacement of side s at point p is sum_k shape[p, k] u[nodes[p, s, k]]."""
        self.nc.createDimension("joint_side", 2)
        self.nc.createDimension("joint_face_node", np.shape(nodes)[2])
        self._string_coord("joint_side", ("joint_side",), ["bottom", "top"], "face of the interface element")
        self._var("joint_point_nodes", "i4", ("joint_point", "joint_side", "joint_face_node"), "1",
                  "model node index (as the node coordinate) of each node of the bottom and top face of the "
                  "joint point's interface element (-1: padding)")[:] = nodes
        self._var("joint_point_shape", "f8", ("joint_point", "joint_face_node"), "1",
                  "face shape function of each face node at the joint point (interpolation weight of the "
                  "face displacement; 0: padding)")[:] = shape

    def _declare(self, item) -> bool:
        """Create a :class:`~masonrydam.results.variables.ResultDimension` or
        :class:`~masonrydam.results.variables.ResultVariable`; True for a step variable that static steps
        leave NaN."""
        if isinstance(item, ResultDimension):
            self.nc.createDimension(item.name, item.size)
            return False
        if item.dtype is str:
            self._string_coord(item.name, item.dims, item.values, item.long_name)
            return False
        v = self._var(item.name, item.dtype, item.dims, item.units, item.long_name, fill_value=item.fill_value)
        for k, val in item.attrs.items():
            v.setncattr(k, val)
        if item.values is not None and not item.per_step:
            v[:] = item.values
        return item.per_step and item.dynamic_only

    def _element_variables(self, el):
        """Continuum stress per element (``[output] stress = "element"``): dimension ``element`` (every
        continuum element, element group after group) with its group and centroid, and ``stress`` on
        (step, element, stress_component)."""
        names = ["xx", "yy", "xy"] if self.dim == 2 else ["xx", "yy", "zz", "xy", "yz", "zx"]
        self.nc.createDimension("element", len(el["group"]))
        self.nc.createDimension("stress_component", len(names))
        self._string_coord("stress_component", ("stress_component",), names, "stress component (Voigt order)")
        v = self._var("element_group", "i4", ("element",), "1", "element group index (see attribute group_names)")
        v[:] = el["group"]
        v.group_names = json.dumps(el["group_names"])
        for k, c in enumerate(["x", "y", "z"][: self.dim]):
            self._var(f"element_{c}", "f8", ("element",), "m", f"{c} coordinate of the element centroid")[:] = \
                el["centroid"][:, k]
        self._var("stress", "f8", ("step", "element", "stress_component"), "Pa",
                  "continuum stress, mean of the element's integration points (tension positive; 2D plane "
                  "strain szz not included)")

    def _mode_variables(self, n):
        """The modes of a modal stage (NaN until it has run): dimension ``mode`` (1, 2, ...)."""
        self.nc.createDimension("mode", n)
        self._var("mode", "i4", ("mode",), "1", "mode number, by increasing frequency")[:] = np.arange(1, n + 1)
        self._var("frequency", "f8", ("mode",), "Hz", "natural frequency", fill_value=np.nan)
        self._var("period", "f8", ("mode",), "s", "natural period", fill_value=np.nan)
        self._var("mode_shape", "f8", ("mode", "node", "component"), "kg-0.5",
                  "mode shape, mass-normalised (phi^T M phi = 1)", fill_value=np.nan)
        self._var("effective_mass", "f8", ("mode", "component"), "kg",
                  "effective modal mass per direction (Gamma^2 for mass-normalised modes)", fill_value=np.nan)
        self._var("effective_mass_ratio", "f8", ("mode", "component"), "1",
                  "effective modal mass over the mass on the free DOFs, per direction", fill_value=np.nan)

    def write_modes(self, frequency, period, shape, effective_mass, ratio):
        """The results of a modal stage: frequency, period (n_modes,), shape (n_modes, n_out, dim),
        effective mass and its ratio (n_modes, dim); written at once (not per step)."""
        nc = self.nc
        nc["frequency"][:] = frequency
        nc["period"][:] = period
        nc["mode_shape"][:] = shape
        nc["effective_mass"][:] = effective_mass
        nc["effective_mass_ratio"][:] = ratio
        nc.sync()

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

    def write_ground_records(self, records: dict):
        """The ground-acceleration records of the dynamic stages at their own sampling rate (the step
        variable ``ground_acceleration`` holds them at the output steps only, which can miss the peak):
        for each component ``c`` of ``records`` (``{c: (time (n,), acceleration (n,))}``) a dimension
        ``ground_record_<c>``, the samples' time ``ground_record_time_<c>`` (s, since the start of the
        first dynamic stage, like ``time``) and ``ground_acceleration_record_<c>`` (m/s2), with the time
        as its coordinate; a NaN value separates two stages' records."""
        for c, (t, a) in records.items():
            dim = f"ground_record_{c}"
            self.nc.createDimension(dim, len(t))
            kw = dict(zlib=True, complevel=self.options.compression, shuffle=True) if self.options.compression else {}
            v = self.nc.createVariable(f"ground_record_time_{c}", "f8", (dim,), **kw)
            v.units = "s"
            v.long_name = (f"time of the samples of ground_acceleration_record_{c}, since the start of the first "
                           "dynamic stage")
            v[:] = t
            v = self.nc.createVariable(f"ground_acceleration_record_{c}", "f8", (dim,), fill_value=np.nan, **kw)
            v.units = "m/s2"
            v.long_name = (f"ground acceleration {c} at the record's own sampling rate (the input motion of the "
                           "dynamic stages, linear between samples, zero after a record's last sample; NaN "
                           "between stages)")
            v.coordinates = f"ground_record_time_{c}"
            v[:] = a
        self.nc.sync()

    def _string_coord(self, name, dims, values, long_name):
        v = self.nc.createVariable(name, str, dims)
        for i, s in enumerate(values):
            v[i] = s
        v.long_name = long_name
        v.units = "1"

    def _var(self, name, dtype, dims, units, long_name, fill_value=None):
        """A variable with units and long name. Step variables are chunked along ``step`` (chunks of
        about :data:`CHUNK_BYTES`, at most a block), compressed as the options say, and the nodal and
        joint fields stored in single precision where asked."""
        kw = {}
        if dims[:1] == ("step",):
            o = self.options
            if dtype == "f8" and o.precision == "single" and len(dims) > 1:
                dtype = "f4"
                fill_value = None if fill_value is None else np.float32(fill_value)
            shape = [len(self.nc.dimensions[d]) for d in dims[1:]]
            record = max(int(np.prod(shape, dtype=np.int64)), 1) * np.dtype(dtype).itemsize
            kw["chunksizes"] = [max(1, min(o.buffer_steps, CHUNK_BYTES // record))] + [max(n, 1) for n in shape]
            if o.compression:
                kw.update(zlib=True, complevel=o.compression, shuffle=True)
        v = self.nc.createVariable(name, dtype, dims, fill_value=fill_value, **kw)
        v.units = units
        v.long_name = long_name
        return v

    def _write_block(self, name, k0, block):
        """Write ``block`` (n steps of variable ``name``) at step ``k0``.

        Through netCDF4-python's low-level ``Variable._put(data, start, count, stride)`` when it has one:
        the public ``var[k0:k0 + n] = block`` spends about 0.12 ms per call in Python (index parsing,
        masking) around the write itself (measured with netCDF4 1.7.5 for one step per call). ``_put``
        is private but has had this signature since netCDF4-python 1.0; if it is missing or refuses the
        call, this writer switches to the public API for good (same file)."""
        var = self._step_vars[name]
        if self._fast_append:
            nd = block.ndim
            start = np.zeros(nd, dtype=np.intp)
            start[0] = k0
            try:
                var._put(np.ascontiguousarray(block), start, np.array(block.shape, dtype=np.intp),
                         np.ones(nd, dtype=np.intp))
                return
            except (AttributeError, TypeError):
                self._fast_append = False
        var[k0:k0 + len(block)] = block

    def flush(self):
        """Write the steps collected in memory to the file as one block, and flush the file."""
        n = self._in_buffer
        if n:
            k0 = self.n - n
            for name, buf in self._buffers.items():
                self._write_block(name, k0, buf[:n])
            self._in_buffer = 0
            self.nc.sync()
        self._last_flush = time.monotonic()

    def write_step(self, stage, load_factor, iterations, displacement, reaction, joints, dynamic=None, extra=None):
        """Add one converged step (written with its block, see :class:`OutputOptions`).
        displacement, reaction: (n_out, dim); joints: dict opening (n_jp,), slip (n_jp, dim-1),
        plastic_slip, t_normal, t_shear, state; dynamic (time-history files, dynamic steps): dict time
        (s), velocity, acceleration, acceleration_absolute (n_out, dim), ground_acceleration (dim,),
        energy (dict name -> J); extra: values of the optional step variables the writer was created
        with (``stress`` and the step variables of ``variables``, name -> value)."""
        if dynamic is not None and not self.dynamic:
            raise ValueError("this writer was created without dynamic=True")
        i = self._in_buffer
        buf = self._buffers
        if self.dynamic:
            if dynamic is None:
                for name in self._dynamic_names:
                    buf[name][i] = np.nan
            else:
                buf["time"][i] = dynamic["time"]
                buf["velocity"][i] = dynamic["velocity"]
                buf["acceleration"][i] = dynamic["acceleration"]
                buf["acceleration_absolute"][i] = dynamic["acceleration_absolute"]
                buf["ground_acceleration"][i] = dynamic["ground_acceleration"]
                for name in ENERGY_VARIABLES:
                    buf[f"energy_{name}"][i] = dynamic["energy"][name]
        buf["step"][i] = self.n
        buf["load_factor"][i] = load_factor
        buf["stage"][i] = stage
        buf["iterations"][i] = iterations
        buf["displacement"][i] = displacement
        buf["reaction"][i] = reaction
        if "joint_opening" in buf:
            buf["joint_opening"][i] = joints["opening"]
            buf["joint_slip"][i] = joints["slip"]
            buf["joint_plastic_slip"][i] = joints["plastic_slip"]
            buf["joint_traction_normal"][i] = joints["t_normal"]
            buf["joint_traction_shear"][i] = joints["t_shear"]
            buf["joint_state"][i] = joints["state"]
        for name, value in (extra or {}).items():
            buf[name][i] = value
        self.n += 1
        self._in_buffer = i + 1
        if self._in_buffer == self.block_steps or time.monotonic() - self._last_flush >= self.options.flush_seconds:
            self.flush()

    def close(self, completed: bool, status: str, extra_attrs: dict | None = None, reason: str | None = None):
        """Finish the file: ``completed`` ("true"/"false"), ``status`` (``"completed"``, ``"failed"``,
        ``"interrupted"``, ``"terminated"``; a file never closed keeps ``"running"``) and, for a run
        that ended early, ``status_reason`` (the error or the step it stopped at)."""
        if not self.nc.isopen():
            return
        try:
            self.flush()
            for k, val in (extra_attrs or {}).items():
                self.nc.setncattr(k, val if isinstance(val, (str, int, float)) else json.dumps(val))
            self.nc.completed = "true" if completed else "false"
            self.nc.status = status
            if reason is not None:
                self.nc.status_reason = reason
        finally:  # never leave the file (and its HDF5 lock) open, also when the disk is full
            self.nc.close()
