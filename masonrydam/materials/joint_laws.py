"""Joint laws as descriptors: what the rest of masonrydam needs to know about a joint law, in one place.

A :class:`JointLaw` names a law of ``[joints.<set>] law = ...`` and says everything that the schema, the
scene reference (docs/scene.md), the model building, the element groups, the solvers and the results ask of
it: its scene keys with their units and meaning, the parameter row it builds from them, the size and
meaning of its state rows (state code, plastic slip, broken bond), how its state codes read as the result's
joint states (0 stick, 1 slip, 2 open, 3 crushed), its elastic stiffness and compliance, and what it
supports (dynamics, the joint-space condensation, dissipation-based path following, viscous relaxation).
Callers ask the descriptor (or the element group's methods built on it,
:class:`~masonrydam.assembly.groups.InterfaceGroup`); none reads a law's columns or tests its name.

Built-in laws (registered here, in this order):

- ``mohr_coulomb``: the joint of Tzamtzis & Asteris (sec. 3.4, eqs. 11-12;
  :mod:`masonrydam.materials.mohr_coulomb`);
- ``linear``: the same kernel with a bond that cannot break and no friction limit (an elastic joint);
- ``composite``: the masonry interface of Lourenco & Rots (1997, J. Eng. Mech. 123(7):660-668;
  :mod:`masonrydam.materials.composite`).

Their point laws are compiled into the interface kernels (:mod:`masonrydam.elements.interface`): the
*fused* path, one kernel for kinematics, law and assembly, selected by :attr:`JointLaw.kernel_id`.

A law from outside the package (a plug-in) gives a :attr:`JointLaw.point_law`: a function over the arrays
of a joint set's integration points (the contract is that of :data:`PointLaw`, below). The element group
then evaluates it on the *generic* path: relative displacements at the points
(:func:`~masonrydam.elements.interface.interface_relative_displacements`), the point law, then the
assembly of forces and tangents (:func:`~masonrydam.elements.interface.interface_assemble`). Register it
with :func:`register_joint_law`; a scene then names it in ``[joints.<set>] law``. What a plug-in law does
not support (large kinematics, the joint-space condensation, dynamics, dissipation control) is refused
with a :class:`~masonrydam.errors.SceneError` naming the key, or bypassed (the solvers skip the joint-space
condensation).

Point-law contract (:data:`PointLaw`)::

    status = point_law(params_table, param_index, state_committed, delta, time_step,
                       state_trial, traction_out, tangent_out, info)

    params_table    float64 (n_sets, n_params)      the parameter rows (:attr:`JointLaw.parameters`)
    param_index     int64 (n_elem,)                 the row of each element
    state_committed float64 (n_elem, nip, n_state)  committed state; read only
    delta           float64 (n_elem, nip, dim)      local relative displacement [s1, (s2,) n] (m), opening +
    time_step       float                           time of the step (s); 0: a rate-independent step
    state_trial     float64 (n_elem, nip, n_state)  out: the trial state
    traction_out    float64 (n_elem, nip, dim)      out: local traction [tau1, (tau2,) t_n] (Pa), tension +
    tangent_out     float64 (n_elem, nip, dim, dim) out: d traction / d delta (Pa/m)
    info            int64 (1,)                      out: the failing element where the status is not OK
    status          int                             masonrydam.errors.STATUS_OK or another STATUS_* code

It may be a numba function or plain NumPy; it is called from Python, never passed into a compiled kernel
(numba's cache does not keep kernels that take a function argument).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..checks import number, seconds
from .. import keys
from ..errors import SceneError
from ..units import SI_UNIT, quantity
from . import composite as ci
from . import mohr_coulomb as mc

# ---- the result's joint states (``joint_state`` of the result file)
RESULT_STICK = 0
RESULT_SLIP = 1
RESULT_OPEN = 2
#: on the compression cap (composite law)
RESULT_CRUSHED = 3
RESULT_STATE_NAMES = ("stick", "slip", "open", "crushed")

#: :attr:`JointLaw.kernel_id` of a law without a fused interface kernel (a plug-in: :attr:`JointLaw.point_law`)
NO_FUSED_KERNEL = -1
#: the fused interface kernels: ``kernel_id`` -> the point law compiled into them. None is the
#: Mohr-Coulomb law of Tzamtzis & Asteris: numba prunes the other branch of a None argument before typing, so that the
#: Mohr-Coulomb kernels never compile the composite law (:func:`masonrydam.elements.interface.joint_law_at`)
FUSED_KERNELS = {None: "mohr_coulomb_point", 1: "composite_point"}

#: parameters of a joint that never slips or opens (``law = "linear"``): cohesion and tensile strength (Pa)
UNBREAKABLE = 1e300


#: default of a scene key that must be given (the scene reference's own marker, :data:`masonrydam.keys.REQUIRED`)
REQUIRED = keys.REQUIRED
#: default of a scene key that may be left out without a value of its own (the feature is off, or the law
#: computes the value)
OPTIONAL = keys.Marker("optional")

#: the point-law contract of a plug-in law (see the module docstring)
PointLaw = Callable[..., int]


@dataclass(frozen=True)
class LawKey:
    """One scene key of a law, ``[joints.<set>] <name>`` (or ``[materials.<group>]``).

    name: the key; dimension: the quantity it is read as (a dimension of :data:`masonrydam.units.SI_UNIT`:
    a number in SI or a string with a unit; ``"time"``: seconds or milliseconds, 0 allowed), None: a plain
    number; meaning: one line (docs/scene.md); default: a value, :data:`REQUIRED` or :data:`OPTIONAL`;
    minimum: a lower bound (inclusive) checked after the conversion, None: none; unit: the unit shown for a
    plain number (e.g. ``"1/m"``), else the dimension's SI unit."""

    name: str
    dimension: str | None
    meaning: str
    default: object = OPTIONAL
    minimum: float | None = None
    unit: str = ""

    @property
    def si_unit(self) -> str:
        """The key's SI unit as docs/scene.md shows it ('' for a dimensionless number)."""
        return self.unit or (SI_UNIT[self.dimension] if self.dimension is not None else "")

    def read(self, value, path: str) -> float:
        """``value`` as given in a scene converted to SI (float); SceneError naming ``path`` if it is wrong."""
        if self.dimension == "time":
            v = seconds(value, path, allow_zero=True)
        elif self.dimension is None:
            v = number(value, path)
        else:
            v = quantity(value, self.dimension, path)
        if self.minimum is not None and v < self.minimum:
            raise SceneError(path, f"must be >= {self.minimum:g}, got {value!r}")
        return v


def read_law_keys(law, table: dict, key: str, fill_defaults: bool = True) -> dict:
    """The law's own keys of a scene table ``table`` (``key``: its dotted path), converted to SI: the keys
    given, and with ``fill_defaults`` the defaults of those left out (:data:`OPTIONAL` ones stay out). A
    :data:`REQUIRED` key left out is a SceneError naming it."""
    out = {}
    for k in law.keys:
        path = f"{key}.{k.name}"
        if k.name in table:
            out[k.name] = k.read(table[k.name], path)
        elif k.default is REQUIRED:
            raise SceneError(path, f"is required for the {law.title} law")
        elif fill_defaults and k.default is not OPTIONAL:
            out[k.name] = k.default
    return out


@dataclass(frozen=True)
class JointLaw:
    """What masonrydam knows of one joint law (see the module docstring).

    Identity and documentation
        name: the value of ``[joints.<set>] law``; title: the law in messages ("Mohr-Coulomb");
        description: one line for docs/scene.md; summary: the run summary's line before the joint-set names
        (also in the result's ``simulated_effects``); reference: the paper (and equations).
    Scene keys and parameters
        keys: the law's own scene keys (besides ``normal_stiffness`` and ``shear_stiffness``, which every
        law has); read_keys: ``(law, table, key, shear_stiffness) -> dict``, the normalised keys of a raw
        table (default: :func:`read_law_keys`); parameters: ``(spec) -> (n_params,) float64``, the parameter
        row of a normalised joint table (``normal_stiffness``, ``shear_stiffness`` and the law's keys, SI);
        ValueError for inadmissible values, in words that name the key.
    Kernel
        kernel_id: the fused interface kernel (:data:`FUSED_KERNELS`), or :data:`NO_FUSED_KERNEL` with a
        point_law (:data:`PointLaw`); state_size: columns of a point's state row.
    State rows (column indices; None: the law has no such column)
        code_column: the law's state code, read through result_state_map (code -> result state
        :data:`RESULT_STICK` .. :data:`RESULT_CRUSHED`); plastic_slip_column: the first of dim-1 columns of
        irreversible slip (m); bond_column: 1 where the bond has broken (no cohesion, no tensile strength).
    Parameter rows (column indices)
        stiffness_columns: the elastic stiffness ``(ks1, ks2, kn)`` (Pa/m; 2D uses ks1 and kn);
        strength_columns: ``(cohesion, tan_phi)`` of a Coulomb friction limit, None: none;
        open_tangent_column: the tangent factor of open points (a solver control), None: none;
        relaxation_time_column / time_step_column: the viscous relaxation time (s) and the time of the step,
        written before each evaluation, None: rate independent; at_rest: ``((column, value), ...)`` written
        into a copy of the rows for the elastic tangent at rest (:meth:`elastic_parameters`).
    Capabilities
        nonlinear: the state changes (else the joint is linear: its stiffness is the elastic one);
        latches_bonds: a bond that breaks in an iteration stays broken for the rest of the step
        (``InterfaceGroup.latch_broken_bonds``); dissipation_control: dissipation-based path following may
        follow it; dynamics: dynamic stages may use it; joint_space: the joint-space condensation
        (:mod:`masonrydam.solvers.joint_space`) carries it; elastic_at_rest: at zero relative displacement
        from a virgin state (with :attr:`at_rest`) its tangent is the elastic stiffness, the one of modal
        stages, Rayleigh damping and the reference factorizations; large_kinematics: it runs in the
        large-displacement interface kernel.
    """

    name: str
    title: str
    description: str
    summary: str
    reference: str
    parameters: Callable[[dict], np.ndarray]
    state_size: int
    keys: tuple = ()
    read_keys: Callable | None = None
    kernel_id: int | None = NO_FUSED_KERNEL
    point_law: PointLaw | None = None
    code_column: int | None = 0
    result_state_map: tuple = (RESULT_STICK,)
    plastic_slip_column: int | None = None
    bond_column: int | None = None
    stiffness_columns: tuple = (0, 0, 1)
    strength_columns: tuple | None = None
    open_tangent_column: int | None = None
    relaxation_time_column: int | None = None
    time_step_column: int | None = None
    at_rest: tuple = ()
    nonlinear: bool = True
    latches_bonds: bool = False
    dissipation_control: bool = False
    dynamics: bool = False
    joint_space: bool = False
    elastic_at_rest: bool = True
    large_kinematics: bool = False
    _result_map: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_result_map", np.asarray(self.result_state_map, dtype=np.int8))

    # ---- identity ------------------------------------------------------------------------------
    @property
    def fused(self) -> bool:
        """The law is compiled into the interface kernels (else: the generic path with its point law)."""
        return self.point_law is None

    @property
    def key_names(self) -> tuple:
        return tuple(k.name for k in self.keys)

    def normalize(self, table: dict, key: str, shear_stiffness: float) -> dict:
        """The law's keys of the raw scene table ``table`` (at ``key``) in SI (:attr:`read_keys`)."""
        if self.read_keys is None:
            return read_law_keys(self, table, key)
        return self.read_keys(self, table, key, shear_stiffness)

    # ---- state rows (any leading shape: (..., state_size)) ----------------------------------
    def codes(self, state: np.ndarray) -> np.ndarray:
        """The law's state codes (...,) int8 of state rows (..., state_size)."""
        if self.code_column is None:
            return np.zeros(state.shape[:-1], dtype=np.int8)
        return state[..., self.code_column].astype(np.int8)

    def result_states_of(self, codes: np.ndarray) -> np.ndarray:
        """The result's joint states (int8: 0 stick, 1 slip, 2 open, 3 crushed) of the law's codes."""
        if self.result_state_map == tuple(range(len(self.result_state_map))):
            return codes
        return self._result_map[codes]

    def result_states(self, state: np.ndarray) -> np.ndarray:
        """The result's joint states (...,) int8 of state rows (..., state_size)."""
        return self.result_states_of(self.codes(state))

    def plastic_slip(self, state: np.ndarray, dim: int) -> np.ndarray:
        """Irreversible slip (..., dim-1) m of state rows (zero for a law without plastic slip)."""
        if self.plastic_slip_column is None:
            return np.zeros(state.shape[:-1] + (dim - 1,))
        return state[..., self.plastic_slip_column:self.plastic_slip_column + dim - 1]

    def bond_broken(self, state: np.ndarray) -> np.ndarray:
        """(...,) bool: the bond has broken (cohesion and tensile strength are gone)."""
        if self.bond_column is None:
            return np.zeros(state.shape[:-1], dtype=bool)
        return state[..., self.bond_column] != 0

    def latch_broken_bonds(self, base: np.ndarray, trial: np.ndarray) -> int:
        """Mark in ``base`` the bonds broken in ``trial`` (state rows of the same shape) for a law that
        latches them (:attr:`latches_bonds`); returns the number of newly latched points (0 otherwise)."""
        if not self.latches_bonds:
            return 0
        col = self.bond_column
        new = (trial[..., col] != 0) & (base[..., col] == 0)
        n = int(new.sum())
        if n:
            base[..., col][new] = 1.0
        return n

    def keep_latched_bonds(self, into: np.ndarray, source: np.ndarray) -> None:
        """Bonds latched broken in ``source`` stay broken in ``into`` (state rows of the same shape)."""
        if self.latches_bonds:
            col = self.bond_column
            into[..., col] = np.maximum(into[..., col], source[..., col])

    # ---- parameter rows (n_sets, n_params) ---------------------------------------------------
    def elastic_stiffness(self, params: np.ndarray, dim: int) -> np.ndarray:
        """(n, dim) elastic stiffness ``[ks1, (ks2,) kn]`` (Pa/m) of parameter rows (n, n_params)."""
        s1, s2, n = self.stiffness_columns
        return params[:, [s1] + ([s2] if dim == 3 else []) + [n]]

    def compliance(self, params: np.ndarray, dim: int) -> np.ndarray:
        """(n, dim) elastic compliance ``[1/ks1, (1/ks2,) 1/kn]`` (m/Pa) of parameter rows (n, n_params)."""
        return 1.0 / self.elastic_stiffness(params, dim)

    def friction_strength(self, params: np.ndarray) -> tuple:
        """``(cohesion (n,) Pa, tan_phi (n,))`` of the law's Coulomb friction limit; ``(inf, 0)`` for a law
        without one (nothing to check against)."""
        if self.strength_columns is None:
            return np.full(len(params), np.inf), np.zeros(len(params))
        c, t = self.strength_columns
        return params[:, c], params[:, t]

    def relaxation_time(self, params: np.ndarray) -> float:
        """The largest viscous relaxation time (s) of the rows; 0 for a rate-independent law."""
        if self.relaxation_time_column is None:
            return 0.0
        return float(params[:, self.relaxation_time_column].max())

    def set_relaxation_time(self, params: np.ndarray, tau: float) -> None:
        """Write the viscous relaxation time (s) into the rows, for a law that has one."""
        if self.relaxation_time_column is not None:
            params[:, self.relaxation_time_column] = tau

    def set_time_step(self, params: np.ndarray, dt: float) -> None:
        """Write the time of the step (s) into the rows, for a law that reads it."""
        if self.time_step_column is not None:
            params[:, self.time_step_column] = dt

    def set_open_tangent(self, params: np.ndarray, factor: float) -> None:
        """Tangent factor of open points (0: consistent; 1: the initial stiffness), for a law that has one."""
        if self.open_tangent_column is not None:
            params[:, self.open_tangent_column] = factor

    def elastic_parameters(self, params: np.ndarray) -> np.ndarray:
        """A copy of the rows with which the law, at zero relative displacement from a virgin state, has its
        elastic tangent (:attr:`at_rest` written, the consistent open tangent)."""
        out = params.copy()
        for column, value in self.at_rest:
            out[:, column] = value
        self.set_open_tangent(out, 0.0)
        return out


# ---- the built-in laws ----------------------------------------------------------------------------
def _mohr_coulomb_parameters(spec: dict) -> np.ndarray:
    return mc.joint_params(spec["normal_stiffness"], spec["shear_stiffness"], spec["cohesion"],
                           spec["friction_angle"], spec["tensile_strength"], spec["residual_shear_stiffness"])


def _read_mohr_coulomb(law, table, key, shear_stiffness):
    out = read_law_keys(law, table, key)
    if not 0.0 <= out["friction_angle"] < 90.0:
        raise SceneError(f"{key}.friction_angle", f"must be in [0, 90) degrees, got {table['friction_angle']!r}")
    if out["residual_shear_stiffness"] >= shear_stiffness:
        raise SceneError(f"{key}.residual_shear_stiffness", f"must be smaller than shear_stiffness "
                                                            f"({shear_stiffness:g}), got {out['residual_shear_stiffness']:g}")
    return out


def _linear_parameters(spec: dict) -> np.ndarray:
    return mc.joint_params(spec["normal_stiffness"], spec["shear_stiffness"], cohesion=UNBREAKABLE,
                           friction_angle_deg=0.0, tensile_strength=UNBREAKABLE)


#: the composite law's keys that :func:`~masonrydam.materials.composite.composite_params` takes by name
_COMPOSITE_OPTIONS = ("dilatancy_confinement", "dilatancy_decay", "compressive_strength", "cap_shear_factor",
                      "cap_fracture_energy", "cap_peak_plastic_strain", "shear_stiffness_2", "residual_friction_angle",
                      "dilatancy_angle", "relaxation_time")


def _composite_parameters(spec: dict) -> np.ndarray:
    """The composite row (:func:`~masonrydam.materials.composite.composite_params`), refused where the
    joint alone would snap back (the longest elastic bar in series without a snap-back is 0; its sign does not
    depend on the bar's moduli, so unit moduli serve)."""
    row = ci.composite_params(spec["normal_stiffness"], spec["shear_stiffness"], spec["tensile_strength"],
                              spec["mode_I_fracture_energy"], spec["cohesion"], spec["friction_angle"],
                              mode_II_fracture_energy=spec["mode_II_fracture_energy"],
                              **{k: spec[k] for k in _COMPOSITE_OPTIONS if k in spec})
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
    return row


def _read_composite(law, table, key, shear_stiffness):
    # only the keys given: composite_params has the defaults (the normalised scene keeps what was written)
    return read_law_keys(law, table, key, fill_defaults=False)


_COHESION = "cohesion c"
_FRICTION = "friction angle, in [0, 90)"
_TENSILE = "tensile strength (0: no tension)"

MOHR_COULOMB = JointLaw(
    name="mohr_coulomb", title="Mohr-Coulomb",
    description="sticks, slides and opens (brittle: an open point loses its cohesion and tensile strength)",
    summary="Mohr-Coulomb joints with slip, opening and re-contact (Tzamtzis & Asteris, sec. 3.4)",
    reference="Tzamtzis & Asteris, sec. 3.4, eqs. 11-12 (masonrydam.materials.mohr_coulomb)",
    parameters=_mohr_coulomb_parameters, read_keys=_read_mohr_coulomb, state_size=mc.N_JOINT_STATE,
    keys=(LawKey("cohesion", "stress", _COHESION, 0.0, minimum=0.0),
          LawKey("friction_angle", "angle", _FRICTION, REQUIRED),
          LawKey("tensile_strength", "stress", _TENSILE, 0.0, minimum=0.0),
          LawKey("residual_shear_stiffness", "stiffness", "shear stiffness while sliding (kinematic hardening; 0: "
                 "perfectly plastic), below `shear_stiffness`", 0.0, minimum=0.0)),
    kernel_id=None, code_column=mc.S_CODE, result_state_map=(RESULT_STICK, RESULT_SLIP, RESULT_OPEN),
    plastic_slip_column=mc.S_PLASTIC_SLIP, bond_column=mc.S_BOND_BROKEN,
    stiffness_columns=(mc.P_KS, mc.P_KS, mc.P_KN), strength_columns=(mc.P_COHESION, mc.P_TAN_PHI),
    open_tangent_column=mc.P_OPEN_TANGENT,
    at_rest=((mc.P_COHESION, UNBREAKABLE), (mc.P_TENSILE_STRENGTH, UNBREAKABLE)),
    nonlinear=True, latches_bonds=True, dissipation_control=True, dynamics=True, joint_space=True,
    large_kinematics=True)

LINEAR = JointLaw(
    name="linear", title="linear",
    description="elastic",
    summary="linear elastic joints",
    reference="Tzamtzis & Asteris, eq. 11 (the elastic joint stiffness); the Mohr-Coulomb kernel with a bond "
              "that cannot break",
    parameters=_linear_parameters, state_size=mc.N_JOINT_STATE,
    kernel_id=None, code_column=mc.S_CODE, result_state_map=(RESULT_STICK, RESULT_SLIP, RESULT_OPEN),
    plastic_slip_column=mc.S_PLASTIC_SLIP, bond_column=mc.S_BOND_BROKEN,
    stiffness_columns=(mc.P_KS, mc.P_KS, mc.P_KN), strength_columns=(mc.P_COHESION, mc.P_TAN_PHI),
    open_tangent_column=mc.P_OPEN_TANGENT,
    at_rest=((mc.P_COHESION, UNBREAKABLE), (mc.P_TENSILE_STRENGTH, UNBREAKABLE)),
    nonlinear=False, dynamics=True, joint_space=True, large_kinematics=True)

COMPOSITE = JointLaw(
    name="composite", title="composite",
    description="Lourenço & Rots (1997) softening in tension, shear and compression (static stages)",
    summary="composite masonry joints (Lourenco & Rots 1997): tension cut-off with exponential softening (GfI), "
            "Coulomb friction with cohesion softening (GfII) and dilatancy, compression cap where given",
    reference="Lourenco & Rots (1997), J. Eng. Mech. 123(7):660-668, eqs. 1-9; Lourenco (1996), PhD thesis, ch. 4 "
              "(masonrydam.materials.composite)",
    parameters=_composite_parameters, read_keys=_read_composite, state_size=ci.N_COMPOSITE_STATE,
    keys=(LawKey("tensile_strength", "stress", _TENSILE, REQUIRED),
          LawKey("mode_I_fracture_energy", "fracture_energy", "fracture energy in tension", REQUIRED),
          LawKey("cohesion", "stress", _COHESION, REQUIRED),
          LawKey("friction_angle", "angle", _FRICTION, REQUIRED),
          LawKey("residual_friction_angle", "angle", "friction angle after shear softening (default: "
                 "`friction_angle`)"),
          LawKey("dilatancy_angle", "angle", "dilatancy angle", 0.0),
          LawKey("dilatancy_confinement", "stress", "compressive normal stress at which the dilatancy vanishes "
                 "(default: no decay)"),
          LawKey("dilatancy_decay", None, "decay of the dilatancy with the plastic slip (1/m)", 0.0, unit="1/m"),
          LawKey("mode_II_fracture_energy", "fracture_energy", "fracture energy in shear", REQUIRED),
          LawKey("compressive_strength", "stress", "strength of the compression cap (default: no cap)"),
          LawKey("cap_shear_factor", None, "shear contribution to the cap", 9.0),
          LawKey("cap_fracture_energy", "fracture_energy", "fracture energy of the cap (required with a cap)"),
          LawKey("cap_peak_plastic_strain", "length", "plastic relative displacement at the cap's peak (required "
                 "with a cap)"),
          LawKey("shear_stiffness_2", "stiffness", "3D: stiffness of the second shear direction (default: "
                 "`shear_stiffness`)"),
          LawKey("relaxation_time", "time", "Duvaut-Lions viscosity that regularises the softening (0: none; > 0: "
                 "static stages need a `duration`)", 0.0)),
    kernel_id=1, code_column=ci.S_CODE,
    # elastic, shear, tension, cap, tension-shear, shear-cap
    result_state_map=(RESULT_STICK, RESULT_SLIP, RESULT_OPEN, RESULT_CRUSHED, RESULT_OPEN, RESULT_CRUSHED),
    plastic_slip_column=ci.S_PLASTIC_SLIP, bond_column=ci.S_CRACKED,
    stiffness_columns=(ci.P_KS, ci.P_KS2, ci.P_KN), strength_columns=(ci.P_COHESION, ci.P_TAN_PHI0),
    open_tangent_column=ci.P_OPEN_TANGENT, relaxation_time_column=ci.P_RELAXATION_TIME,
    time_step_column=ci.P_TIME_STEP,
    nonlinear=True, dissipation_control=True, dynamics=False, joint_space=False, large_kinematics=True)


# ---- the registry ---------------------------------------------------------------------------------
_REGISTRY: dict[str, JointLaw] = {}


def register_joint_law(law: JointLaw, replace: bool = False) -> JointLaw:
    """Add ``law`` to the joint laws a scene may name (``[joints.<set>] law = law.name``); returns it.

    A law without a fused kernel needs its :attr:`JointLaw.point_law`. ValueError for a name already taken
    (unless ``replace``) or a descriptor that cannot work: an unknown kernel id, no point law, a state
    too small for its columns, result states outside 0..3, keys that clash with the joint's own keys."""
    if not isinstance(law, JointLaw):
        raise ValueError(f"register_joint_law takes a JointLaw, got {type(law).__name__}")
    if not law.name.isidentifier():
        raise ValueError(f"a joint law's name is a scene value like \"mohr_coulomb\", got {law.name!r}")
    if law.name in _REGISTRY and not replace:
        raise ValueError(f"joint law {law.name!r} is registered already (replace=True to replace it)")
    if law.point_law is None and law.kernel_id not in FUSED_KERNELS:
        raise ValueError(f"joint law {law.name!r}: no point_law and no fused kernel (kernel_id {law.kernel_id!r}; "
                         f"fused: {sorted(FUSED_KERNELS, key=str)})")
    if law.point_law is not None and not callable(law.point_law):
        raise ValueError(f"joint law {law.name!r}: point_law must be callable")
    columns = [c for c in (law.code_column, law.bond_column) if c is not None]
    if law.plastic_slip_column is not None:
        columns.append(law.plastic_slip_column + 1)
    if law.state_size < 1 or any(not 0 <= c < law.state_size for c in columns):
        raise ValueError(f"joint law {law.name!r}: state_size {law.state_size} does not hold its state columns")
    if not law.result_state_map or any(s not in (RESULT_STICK, RESULT_SLIP, RESULT_OPEN, RESULT_CRUSHED)
                                       for s in law.result_state_map):
        raise ValueError(f"joint law {law.name!r}: result_state_map must map codes to 0..3, got "
                         f"{law.result_state_map!r}")
    clash = set(law.key_names) & set(JOINT_KEYS)
    if clash:
        raise ValueError(f"joint law {law.name!r}: keys {sorted(clash)} are keys of every joint set")
    _REGISTRY[law.name] = law
    return law


def unregister_joint_law(name: str) -> JointLaw:
    """Remove a registered law (a plug-in withdrawn, e.g. at the end of a test); returns it."""
    if name not in _REGISTRY:
        raise ValueError(f"no joint law {name!r} is registered")
    return _REGISTRY.pop(name)


def joint_laws() -> tuple:
    """The registered joint laws, in registration order (the built-in ones first)."""
    return tuple(_REGISTRY.values())


def joint_law(name: str) -> JointLaw:
    """The registered law ``name``; ValueError naming the registered ones otherwise."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown joint law {name!r}; registered: {list(_REGISTRY)}") from None


#: keys of every joint set, whatever its law (read by the schema, not by the law)
JOINT_KEYS = ("law", "normal_stiffness", "shear_stiffness", "integration", "points", "frame")
#: the law of a joint set that names none
DEFAULT_JOINT_LAW = "mohr_coulomb"

for _law in (MOHR_COULOMB, LINEAR, COMPOSITE):
    register_joint_law(_law)
