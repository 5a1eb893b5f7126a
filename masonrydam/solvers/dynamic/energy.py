"""The energy balance of the dynamic stages: :class:`EnergyBalance` and :func:`energy_warnings`.

Per step, trapezoidal works on the relative displacement increment (J, cumulative since the first dynamic
stage): input ``-(M iota a_g) . du``, external (constant static loads), damping ``C v . du``, joints
``f_joint . du``, plus the kinetic, blocks' strain and joints' stored energies; the joint work split point by
point into stored energy, friction, bond breaks and contact events (:func:`~.kernels.joint_step_energy`); and the
integrator's numerical dissipation. ``error`` = input + external - (kinetic + strain + damping + joint stored +
friction + bond breaks + contact + numerical). Theory, references and what the terms measured on the examples
are in docs/dynamics.md ("Energy").
"""
from __future__ import annotations

import numpy as np

from .kernels import dot_product, joint_step_energy, joint_stored_energy, step_works
from .schemes import scheme_named
from .stage import DynamicStats

ENERGY_KEYS = ("input", "external", "hydrodynamic", "kinetic", "strain", "damping", "joint", "joint_stored",
               "joint_dissipated", "joint_friction", "joint_bond_break", "joint_contact", "numerical", "error")
#: the terms whose largest magnitude so far scales the balance ("% of the largest energy term")
ENERGY_SCALE_KEYS = ("input", "external", "kinetic", "strain", "joint", "damping")

#: an energy balance whose error, or whose energy created at contact events, exceeds this fraction of its
#: largest term is reported (every example closes to 1 %)
ENERGY_WARNING_FRACTION = 0.01


def energy_growth(e) -> float:
    """Mechanical energy gained beyond what the loads supplied (J) in the energies ``e``: kinetic + strain +
    joint stored + damping - external - input. Physically <= 0."""
    return (e["kinetic"] + e["strain"] + e["joint_stored"] + e["damping"] - e["external"] - e["input"]
            - e.get("hydrodynamic", 0.0))


class EnergyBalance:
    """The energy balance of one dynamic stage on ``model`` (``settings``: the stage's
    :class:`~.settings.DynamicSettings`, ``equations``: its :class:`~.equations.StageEquations`).

    :meth:`start` takes the stage's initial state, :meth:`record` adds the works of a step to its end state's
    ``energy``, :meth:`accept` keeps the largest terms of an accepted step in ``stats``; :attr:`scale` is the
    largest energy term so far (J).
    """

    def __init__(self, model, settings, equations, stats):
        self.model, self.s, self.eq, self.stats = model, settings, equations, stats
        self.scale = 0.0
        self._reference = None
        self._compliance = None
        self._weight = None

    def start(self, st, energy0):
        """The stage's initial state ``st`` (its joint snapshot taken here) with the energies ``energy0`` carried
        over from the stages before (None: all zero): the kinetic, strain and stored energies of ``st`` are the
        reference the stage's terms are changes of."""
        free = self.eq.free
        u, v = st.u, st.v
        st.joints = self.joint_snapshot()
        en = dict.fromkeys(ENERGY_KEYS, 0.0) if energy0 is None else dict(energy0)
        self._reference = {"kinetic0": 0.5 * float(v[free] @ self.eq.mass_times(v[free])) - en.get("kinetic", 0.0),
                           "strain0": self.strain_energy(u, st.Kc_u) - en.get("strain", 0.0),
                           "stored0": self.joint_stored() - en.get("joint_stored", 0.0)}
        st.energy = en
        # (with the kinetic energy the stage starts with: a launched block's energy terms are changes of it)
        self.scale = max([abs(en.get(key, 0.0)) for key in ENERGY_SCALE_KEYS]
                         + [0.5 * float(v[free] @ self.eq.mass_times(v[free]))])

    def joint_snapshot(self):
        """Copies of every joint set's (delta, traction, state) after the last evaluation: the end of a
        step for the energy split of :meth:`record` (and the start of the next)."""
        return [(g.delta.copy(), g.traction.copy(), g.state_trial.copy()) for g in self.model.igroups]

    def restore_joint_fields(self, st):
        """After a refused step: the joints' relative displacements and tractions of the committed state
        ``st`` (``revert`` restores the law's state only), so that a retry accepted without a new
        evaluation (residual within tolerance at the predictor) records the right joint energies."""
        for g, (d, t, _) in zip(self.model.igroups, st.joints):
            g.delta[...] = d
            g.traction[...] = t

    def joint_stored(self):
        """Elastic energy stored in the joints (J): sum over contact points of (t_n^2/kn + |tau|^2/ks)/2
        times the point's area; open points store nothing. Back stresses of the residual-stiffness
        hardening are counted as dissipated."""
        if self._compliance is None:  # w / (2 kn) and w / (2 ks) per point (m^3/N), once per stage
            self._compliance = []
            for g in self.model.igroups:
                # (ne, dim) elastic stiffness [ks, (ks,) kn] of each element's parameters (Pa/m)
                k = g.joint_law.elastic_stiffness(g.params_table[g.param_index], self.model.dim)
                w = g.jw * g.thickness[:, None]
                self._compliance.append((np.ascontiguousarray(0.5 * w / k[:, -1][:, None]),
                                         np.ascontiguousarray(0.5 * w / k[:, 0][:, None])))
        return sum((joint_stored_energy(g.traction, cn, cs) for g, (cn, cs) in zip(self.model.igroups,
                                                                                   self._compliance)), 0.0)

    def strain_energy(self, u, Kc_u) -> float:
        """The blocks' elastic energy (J) at ``u`` (``Kc_u`` their forces there): ``u K_c u / 2`` for linear
        blocks, plus the exact St. Venant-Kirchhoff energy of large-kinematics groups."""
        if self.model.large:
            return self.model.continuum_energy(u)
        return 0.5 * dot_product(u, Kc_u)

    def _weights(self):
        """Tributary areas (m^2) of the joint points per joint set, (ne, nip) each."""
        if self._weight is None:
            self._weight = [np.ascontiguousarray(g.jw * g.thickness[:, None]) for g in self.model.igroups]
        return self._weight

    def record(self, st, prev, pg0, pg1):
        """Accumulate the works of the step prev -> st (Hughes 2000, sec. 9.1.4) and the balance error; ``pg0``,
        ``pg1`` (n_eq,) N the earthquake loads (ground, time-given and state forces) at the step's two ends, as the
        step summed them (:func:`~.kernels.step_loads`).

        Terms (J, cumulative): the trapezoidal works of the loads, damping and joints; kinetic, strain and
        joint stored energies; the joint work split by :func:`~.kernels.joint_step_energy` into
        friction, bond breaks and contact events; and the integrator's numerical dissipation
        ``numerical = du . M (a0 + a1)/2 - dT - du . T_alpha`` with ``T_alpha = (am - 1/2) M da +
        (af - 1/2) (C dv + df - dp)``: the generalized-alpha equation of the step differs from the
        trapezoidal average of the equations at its two ends by exactly ``T_alpha`` (write both out), and
        the Newmark updates with gamma != 1/2 make the inertia work differ from the change of kinetic
        energy dT. Both vanish for the trapezoidal rule (beta = 1/4, gamma = 1/2, am = af = 0); for HHT and
        generalized-alpha their sum is the energy the scheme takes out of the high modes (its cumulative
        value is the dissipation plus a bounded "algorithmic energy" of order h^2 a.M a; Krenk 2006, Comput.
        Methods Appl. Mech. Eng. 195:6110-6124). For central difference ``numerical`` is the kinematic
        part ``-h^2/8 d(a.M a)`` alone, and its damping work is that of the half-step damping forces the steps
        applied (:func:`~.explicit_kernels.central_difference_correct`). What is left, ``error``, is the Newton
        tolerance and round-off."""
        eq = self.eq
        free = eq.free
        _, v0f, a0f = prev.free_values(free)
        _, v1f, a1f = st.free_values(free)
        if eq.damped:  # the products the steps computed where they kept them
            cv0 = prev.cv if prev.cv is not None else eq.damping_force(v0f)
            cv1 = st.cv if st.cv is not None else eq.damping_force(v1f)
        else:
            cv0 = cv1 = eq.zeros_free
        if eq.mass_diagonal is not None:
            mv1 = ma0 = ma1 = eq.zeros_free
        else:
            mv1, ma0, ma1 = eq.mass_times(v1f), eq.mass_times(a0f), eq.mass_times(a1f)
        w = np.empty(10)
        hydro = 0.0
        if eq.fluid is not None:
            wet = eq.fluid.wet_eq
            pg0, pg1 = pg0.copy(), pg1.copy()
            pg0[wet] += prev.fw
            pg1[wet] += st.fw
            hydro = 0.5 * float((prev.fw + st.fw) @ (st.u[free][wet] - prev.u[free][wet]))
        step_works(free, prev.u, st.u, pg0, pg1, eq.static_load, cv0, cv1, prev.f_int, st.f_int, prev.Kc_u, st.Kc_u,
                   v1f, eq.kernel_mass_diagonal, mv1, prev.a, st.a, ma0, ma1, w)
        self.record_works(st, prev, w, hydro)

    def record_works(self, st, prev, w, hydro=0.0):
        """The second half of :meth:`record`: the step's works ``w`` (10,) J in the order of
        :func:`~.kernels.step_works` (computed by :meth:`record`, or by the explicit step's fused kernel,
        :func:`~.explicit_kernels.central_difference_correct`) added to ``prev``'s energies, the stored and
        joint energies of ``st``, the balance error; ``hydro`` J the compressible water's work on the dam."""
        e = dict(prev.energy)
        e["input"] += float(w[0]) - hydro
        e["hydrodynamic"] = e.get("hydrodynamic", 0.0) + hydro
        e["external"] += float(w[1])
        e["damping"] += float(w[2])
        e["joint"] += float(w[3])
        kinetic_before = e["kinetic"]
        e["kinetic"] = float(w[4]) - self._reference["kinetic0"]
        if self.model.plastic:  # the blocks' work, trapezoidal: stored energy and plastic dissipation together
            e["strain"] = prev.energy["strain"] + 0.5 * float((st.u - prev.u) @ (prev.Kc_u + st.Kc_u))
        else:
            e["strain"] = self.strain_energy(st.u, st.Kc_u) - self._reference["strain0"]
        numerical = float(w[5]) - (e["kinetic"] - kinetic_before)
        if not self.s.scheme.explicit:
            _, _, am, af = self.s.coefficients()
            numerical -= (am - 0.5) * float(w[6]) + (af - 0.5) * (float(w[8]) + float(w[7]) - float(w[9]))
        e["numerical"] = e.get("numerical", 0.0) + numerical
        if self.model.igroups:
            e["joint_stored"] = self.joint_stored() - self._reference["stored0"]
            st.joints = self.joint_snapshot()
            split = np.zeros(5)
            for (d0, t0, s0), (d1, t1, s1), wt in zip(prev.joints, st.joints, self._weights()):
                joint_step_energy(d0, t0, s0, d1, t1, s1, wt, split)
            for key, x in zip(("joint_friction", "joint_bond_break", "joint_contact"), split[:3]):
                e[key] = e.get(key, 0.0) + float(x)
        e["joint_dissipated"] = e["joint"] - e["joint_stored"]
        e["error"] = e["input"] + e["external"] + e["hydrodynamic"] - (e["kinetic"] + e["strain"] + e["damping"]
                                                                       + e["joint_stored"] + e["joint_friction"]
                                                                       + e["joint_bond_break"] + e["joint_contact"]
                                                                       + e["numerical"])
        st.energy = e

    def accept(self, st):
        """Keep the energies of the accepted step's end state ``st`` in the largest terms and in ``stats``."""
        e = st.energy
        self.scale = max([self.scale] + [abs(e[key]) for key in ENERGY_SCALE_KEYS])
        g = energy_growth(e)
        if g > self.stats.energy_growth_max:
            self.stats.energy_growth_max = g
        err = abs(e["error"])
        self.stats.energy_error_max = max(self.stats.energy_error_max, err)
        if self.scale > 0:  # largest error over the largest energy term, both so far
            self.stats.energy_error_relative = self.stats.energy_error_max / self.scale
        self.stats.energy_scale = self.scale
        self.stats.energy_numerical = e["numerical"]
        self.stats.energy_contact = e["joint_contact"]
        self.stats.energy_bond_break = e["joint_bond_break"]


def energy_warnings(stats: DynamicStats, integrator: str, dt: str) -> list[str]:
    """The energy balance's warnings for a finished run (empty when it closes): the unexplained error
    above :data:`ENERGY_WARNING_FRACTION` of the largest term (Newton tolerance), energy *created* at
    contact events (compressed joint points that open within a step: the trapezoidal work of a jump in
    the contact traction, Laursen & Chawla 1997) above the same fraction. Each names the likely cause.
    The numerical dissipation is reported (result attributes, run summary), not warned about: with
    stiff joints the integrator damps their rattle after every impact even at a converged dt (a free
    rocking block at dt = 0.5 ms: 9 % of the input), which is how the model's impacts lose energy."""
    scale = stats.energy_scale
    if not scale > 0:
        return []
    out = []
    err = stats.energy_error_max / scale
    if err > ENERGY_WARNING_FRACTION:
        scheme = scheme_named(integrator)
        cause = (f"{scheme.label} balances its works exactly up to round-off, so this is a defect: please report "
                 "the scene" if scheme.explicit else
                 "the Newton tolerances (force_tolerance, energy_tolerance) are too loose for this run, or steps "
                 "were accepted at their last halving")
        out.append(f"the energy balance misses by {100 * err:.3g} % of its largest term ({stats.energy_error_max:.3g} "
                   f"J): {cause}")
    created = -stats.energy_contact / scale
    if created > ENERGY_WARNING_FRACTION:
        scheme = scheme_named(integrator)
        advice = ("an explicit step near the critical one resolves a contact event in a few steps only: give a "
                  "fixed dt a few times below dt_crit and converge it (docs/dam_3d.md)" if scheme.explicit else
                  "converge dt (a smaller dt, or dt = \"auto\"; docs/accuracy.md)")
        out.append(f"joint contact events created {100 * created:.3g} % of the largest energy term "
                   f"({-stats.energy_contact:.3g} J: compressed points opening within a step): dt = {dt} is "
                   f"too large for the joint stiffness and contact events are stepped over ({integrator}); "
                   + advice)
    return out
