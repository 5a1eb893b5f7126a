"""What the reservoir adds to a run (:class:`ReservoirRun`): the static water and pore pressures the
static stages carry into the dynamic ones, the levels, pore pressures and stability measures of the joint
lines in the result, the reservoir moving with the dam in the dynamic and modal stages (added mass,
acoustic water), the uplift during the shaking, and the diagnosis of a stage that found no equilibrium."""
from __future__ import annotations

import numpy as np

from ...assembly.joint_lines import JointLines
from ...results.assess import SECTION_VARIABLES, SectionAssessment
from ...results.variables import ResultDimension, ResultVariable
from ...solvers.dynamic import coupled_modal_analysis
from ..base import EffectRun
from .moving import DynamicWater
from .water import StageWater


def activate(context):
    """The :class:`ReservoirRun` of a scene with a ``[reservoir]`` section, or None."""
    if not context.scene.get("reservoir"):
        return None
    return ReservoirRun(context)


def assessed_lines(model, reservoir):
    """The joint lines of ``model`` under ``reservoir`` (:class:`~masonrydam.effects.reservoir.water.Reservoir`)
    to assess: those of the uplift joint sets where the scene has uplift, else those of every joint
    set; of them, :class:`SectionAssessment` keeps the lines closer to horizontal than to vertical
    (``JointLines.horizontal``: base and lift joints, not contraction joints or bench risers). None for a
    model without joints."""
    if reservoir.uplift is not None:
        return reservoir.uplift.lines
    if not model.igroups:
        return None
    return JointLines(model, model.igroups, reservoir.downstream, reservoir.vertical, reservoir.face_nodes)


class ReservoirRun(EffectRun):
    """What a run records of the water of its scene (:mod:`masonrydam.effects.reservoir`): the levels,
    the pore pressures of the recorded joints and the stability measures of the joint lines
    (:mod:`masonrydam.results.assess`); with ``[reservoir] dynamic`` the water moving with the dam
    (:class:`~masonrydam.effects.reservoir.moving.DynamicWater`) in the dynamic and modal stages."""

    def __init__(self, context):
        model, static_stages, jgroups = context.model, context.static_stages, context.recorded_joint_groups
        self.stages = [st for st in static_stages if isinstance(st.varying, StageWater)]
        self.reservoir = self.stages[0].varying.reservoir if self.stages else None
        self.uplift = None if self.reservoir is None else self.reservoir.uplift
        self.last = None  # (stage, load factor) of the last static step with water
        self.assessment = None
        self.last_measures = None  # the section measures of the last recorded step
        #: per recorded joint group, its index in the model and its number of points
        self._record_groups = [(model.igroups.index(g), g.n_elem * g.nip) for g in jgroups]
        if self.reservoir is not None:
            lines = assessed_lines(model, self.reservoir)
            if lines is not None and lines.horizontal.any():
                self.assessment = SectionAssessment(model, lines)

        spec = context.scene["reservoir"]
        #: the reservoir moving with the dam, or None
        self.moving = None
        if context.has_dynamics and spec["dynamic"] != "none":
            level = self.stages[-1].varying.levels(1.0)[0]
            self.moving = DynamicWater(spec, self.reservoir, model, level, context.scene["model"]["thickness"],
                                       context.mesh)
        self.model = model
        self.dynamic = bool(context.dynamic_stages)

    def attrs(self) -> dict:
        out = {}
        if self.reservoir is not None:
            out["reservoir_downstream_direction"] = [float(v) for v in self.reservoir.downstream]
        if self.moving is not None:
            out["reservoir_dynamic"] = self.moving.describe()
        return out

    def result_variables(self) -> list:
        out = []
        if self.uplift is not None:
            out.append(ResultVariable("joint_pore_pressure", ("step", "joint_point"), "Pa",
                                      "pore pressure (uplift) inside the joint; joint_traction_normal is the "
                                      "effective traction"))
        if self.reservoir is not None:
            out.append(ResultVariable("reservoir_level", ("step",), "m", "reservoir water level (vertical coordinate)"))
            out.append(ResultVariable("tailwater_level", ("step",), "m",
                                      "tailwater level (vertical coordinate; NaN: none)", fill_value=np.nan))
        a = self.assessment
        if a is not None:
            out += self._section_variables(a)
        if self.moving is not None and self.dynamic:
            out += self._hydrodynamic_variables()
        return out

    def _section_variables(self, a) -> list:
        """The joint lines assessed for stability (:mod:`masonrydam.results.assess`): dimension ``section``
        with its names, lengths and joint sets, and a variable per measure on (step, section)."""
        L, k = a.lines, a.keep
        out = [ResultDimension("section", len(a.names)),
               ResultVariable("section", ("section",), "1", "joint line (joint set, or set/k from the bottom)",
                              dtype=str, values=a.names),
               ResultVariable("section_joint_set", ("section",), "1", "joint set of the joint line", dtype=str,
                              values=[L.set_names[i] for i in k]),
               ResultVariable("section_length", ("section",), "m",
                              "length of the joint line from its upstream to its downstream end", values=L.length[k])]
        centre = L.centre[k]
        for j, c in enumerate("xyz"[: self.model.dim]):
            out.append(ResultVariable(f"section_{c}", ("section",), "m", f"{c} coordinate of the centre of the joint "
                                      "line", values=centre[:, j]))
        for name, (units, long_name) in SECTION_VARIABLES.items():
            out.append(ResultVariable(name, ("step", "section"), units, long_name))
        return out

    def _hydrodynamic_variables(self) -> list:
        """The moving reservoir: dimension ``face_node`` (the wetted face nodes) and, per dynamic step, the
        resultant of the hydrodynamic pressure on the dam and the pressure at the face nodes."""
        nodes = self.moving.nodes
        coords = self.model.coords[nodes]
        out = [ResultDimension("face_node", len(nodes)),
               ResultVariable("face_node", ("face_node",), "1", "model node index of the wetted face node",
                              dtype="i8", values=nodes)]
        for j, c in enumerate("xyz"[: self.model.dim]):
            out.append(ResultVariable(f"face_{c}", ("face_node",), "m", f"{c} coordinate of the wetted face node",
                                      values=coords[:, j]))
        out.append(ResultVariable("hydrodynamic_force", ("step", "component"), "N",
                                  "resultant of the hydrodynamic water pressure on the dam (static pressure excluded; "
                                  "per unit thickness in 2D)", dynamic_only=True))
        out.append(ResultVariable("face_pressure", ("step", "face_node"), "Pa",
                                  "hydrodynamic water pressure on the wetted face (compression positive; static "
                                  "pressure excluded)", dynamic_only=True))
        return out

    def static_values(self, stage, load_factor) -> dict:
        return self.extra(stage, load_factor)

    def dynamic_values(self, record, mass) -> dict:
        out = self.extra(None, None)
        if self.moving is not None:
            out.update(self.moving.outputs(record["a_abs"], record["bottom_acceleration"], record["fluid"], mass))
        return out

    def after_static(self, model, u) -> None:
        if self.moving is not None and self.moving.coupled_nodes is not None:
            model.add_coupling(self.moving.coupled_nodes)  # the water condensed on the wetted face

    def mass_terms(self, lumped: bool) -> dict:
        if self.moving is None:
            return {}
        return {"added": self.moving.added_mass(lumped), "extra_influence": self.moving.extra_influence}

    def carried_static_force(self, model, u, f_static) -> None:
        f_static += self.static_force()

    def state_force(self):
        """Uplift during the shaking (``uplift.earthquake``): a function () -> (n_dof,) N of the change of
        the pore forces from the state the static stages left (the same reference for every dynamic
        stage), or None (``"static"``: the static pore forces stay as they were)."""
        if self.uplift is None:
            return None
        level, tail, _ = self.stages[-1].varying.levels(1.0)
        pore = self.uplift.earthquake_force(level, tail)
        if pore is None:
            return None
        static_pore = pore()
        return lambda: pore() - static_pore

    def dynamic_terms(self, stage, terms) -> None:
        if self.moving is not None:
            terms.fluid = self.moving.fluid_step()

    def modal_analysis(self, model, stage, u, mass):
        """The coupled dam-water modes of a compressible reservoir (None otherwise: the added mass is in
        the mass matrix)."""
        if self.moving is None or self.moving.fluid_step() is None:
            return None
        return coupled_modal_analysis(model, stage.modes, self.moving.fluid_step(), lumped=stage.lumped, u=u,
                                      mass=mass())

    def summary_lines(self, ds) -> list[str]:
        """The joint line with the lowest sliding factor and the largest cracked ratio at the last step."""
        lines = []
        if "section" in ds.dims and ds.sizes.get("step", 0):
            last = ds.isel(step=-1)
            sf = last.sliding_safety_factor.values
            k = int(np.nanargmin(np.where(np.isfinite(sf), sf, np.inf)))
            lines.append(f"stability  : {ds.sizes['section']} joint lines; lowest sliding factor {sf[k]:.3g} on "
                         f"'{str(last.section.values[k])}', largest cracked ratio "
                         f"{float(np.nanmax(last.cracked_length_ratio.values)):.3g} (masonrydam assess FILE)")
        return lines

    def extra(self, st, lam) -> dict:
        """Step values for the writer; ``st``/``lam``: the static stage and load factor (None: a dynamic
        step, which keeps the water of the last static step)."""
        if self.reservoir is None:
            return {}
        if st is not None and isinstance(st.varying, StageWater):
            self.last = (st, lam)
        if self.last is None:  # a static stage before the water (the water persists once applied)
            return self._values((self.reservoir.face.bottom, None, None))
        stage, lam = self.last
        return self._values(stage.varying.levels(lam))

    def _values(self, levels) -> dict:
        out = {"reservoir_level": levels[0], "tailwater_level": np.nan if levels[1] is None else levels[1]}
        up = self.uplift
        if up is not None:
            pressures = [up.group_pressure(i) for i, _ in self._record_groups]
            out["joint_pore_pressure"] = np.concatenate(
                [np.zeros(0)] + [np.zeros(n) if p is None else p for p, (_, n) in zip(pressures, self._record_groups)])
        if self.assessment is not None:
            lines_up = up is not None and self.assessment.lines is up.lines
            self.last_measures = self.assessment.measures(up.line_forces() if lines_up else None)
            out.update(self.last_measures)
        return out

    def diagnosis(self) -> tuple[str, str] | None:
        """What the joint lines say about a stage that found no equilibrium, from the last converged
        state (the recorded section measures): ``(kind, text)`` with kind ``"sliding"`` (a line's sliding
        factor within 5 % of 1), ``"overturning"`` (a line open over 90 % of its length or its resultant
        within 5 % of its toe), ``"crack"`` (in the failed attempt a crack grew over more than a fifth
        of its line: unstable crack growth) or ``"convergence"`` (none of these: every line still holds
        with margin, so the stage most likely stopped because the joint iterations did not converge, not
        because the dam failed)."""
        m = self.last_measures  # (the tractions of the model are those of the failed attempt)
        if m is None:
            return None
        names = self.assessment.names
        sf, cr = m["sliding_safety_factor"], m["cracked_length_ratio"]
        where = m["resultant_position"] / np.maximum(self.assessment.lines.length[self.assessment.keep], 1e-300)
        k, j = int(np.argmin(sf)), int(np.argmax(cr))
        text = (f"at the last converged step the lowest sliding factor is {sf[k]:.3g} ('{names[k]}') and the "
                f"largest cracked length {100 * cr[j]:.0f} % ('{names[j]}')")
        failed = [st.varying.last_failure for st in self.stages if st.varying.last_failure is not None]
        grow = failed[-1] if failed else None
        if sf[k] < 1.05:
            return "sliding", text + f": '{names[k]}' slides"
        if cr[j] > 0.9 or np.nanmax(where) > 0.95:
            i = j if cr[j] > 0.9 else int(np.nanargmax(where))
            return "overturning", text + f": the resultant on '{names[i]}' reaches its toe"
        if grow is not None and grow["open_after"] - grow["open_before"] > 0.2:
            return "crack", text + (f"; in the failed attempt the crack of '{grow['line']}' ran from "
                                    f"{100 * grow['open_before']:.0f} % to {100 * grow['open_after']:.0f} % of its "
                                    "length in one small increment: unstable crack growth (with uplift in the "
                                    "crack), a failure of the section")
        return "convergence", text + ("; every joint line still holds with margin: the stage most likely stopped "
                                      "because the joint iterations did not converge (joints on tiny tractions "
                                      "changing state), not because the dam failed; more steps or other "
                                      "solver settings may pass it")

    def static_force(self):
        """The water and pore forces (n_dof,) N at the end of the static stages (committed joint states)."""
        if not self.stages:
            return 0.0
        return self.stages[-1].varying.total(1.0, trial=False)
