"""The energy the joints dissipate in a static step, and its derivative: the constraint of dissipation-based
path following (``control = "dissipation"``, :class:`~.arc_length.ArcLengthStage`).

Dissipation-based arc-length control makes every step dissipate a chosen energy ``Delta tau`` (Gutierrez 2004,
Commun. Numer. Meth. Eng. 20:19-29; Verhoosel, Remmers & Gutierrez 2009, Int. J. Numer. Meth. Eng.
77:1290-1321). Energy is dissipated only while cracks grow or joints slip, so the constraint passes through
snap-backs (the dissipated energy grows monotonically where the load and the displacements both turn back)
and does not admit the elastic unloading branch that the cylindrical arc can pick there.

Here the dissipation is the joints' plastic work, summed over their integration points, evaluated locally
as Borjesson, Remmers & Fagerstrom (2023, Comput. Mech. 71:1161-1176) do for cohesive elements. With the
joint's elastic compliance ``C_e = diag(1/ks, (1/ks2,) 1/kn)`` its plastic relative displacement is
``p = delta - C_e t``, and the work of the traction on it over a step, by the trapezoidal rule, is

    D = sum_points w [ 1/2 (t0 + t1) . (delta1 - delta0) - 1/2 (t1 . C_e t1 - t0 . C_e t0) ]

(w = area of the point, m2; subscripts 0 and 1: the start and the end of the step): the work on the joints,
by the trapezoidal rule (second order in the step: exact where the traction varies linearly over it), less
the change of their stored elastic energy (exact). For the composite (plasticity) law, whose unloading
stiffness is the elastic one, it is the plastic work; an elastic step dissipates nothing. For the Mohr-Coulomb law of
Tzamtzis & Asteris, the open joint (no stiffness, no traction) stores and dissipates nothing and a sliding
one dissipates friction work. Its derivative with respect to the end displacements, through the point tangent
``K_t = dt1/d delta1`` (:func:`~masonrydam.elements.interface.interface_point_tangents`), is

    dD/d delta1 = 1/2 (t0 + t1) + K_t^T (1/2 (delta1 - delta0) - C_e t1)

assembled over the points like a traction (``B^T (.) w``). It vanishes where a point is elastic
(``K_t = C_e^-1``) and equals the mean traction where it yields perfectly (``K_t`` = 0 along the slip).
The blocks' own dissipation (continuum plasticity) is not counted: the constraint follows the joints.
"""
from __future__ import annotations

import numpy as np

from ...errors import NumericalError


class JointDissipation:
    """The joints' dissipation over a step (J) and its gradient (J/m, full DOF vector) for the nonlinear
    interface groups of ``model``: :meth:`mark_start` at a converged state (its tractions and relative
    displacements are those of the model's last evaluation), :meth:`of_step` after an evaluation inside the
    step."""

    def __init__(self, model, where: str):
        self.model = model
        self.groups = [g for g in model.igroups if g.nonlinear]
        if not self.groups:
            raise NumericalError(f"{where}: dissipation-based control needs joints that crack or slip (a "
                                 "composite or Mohr-Coulomb joint set); this model has none")
        large = [g.name for g in self.groups if g.kinematics != "small"]
        if large:
            raise NumericalError(f"{where}: dissipation-based control is written for small-displacement joints; "
                                 f"joint set(s) {', '.join(large)} use large kinematics (use control = "
                                 "\"arc_length\" or \"opening\")")
        # (ne, dim) each: 1/ks, (1/ks2,) 1/kn of the element's law (JointLaw.compliance)
        self.compliance = [g.compliance() for g in self.groups]
        self.area = [g.jw * g.thickness[:, None] for g in self.groups]  # (ne, nip) m2
        self.start = None

    def mark_start(self):
        """Keep the tractions and relative displacements of the last evaluation as the step's start."""
        self.start = [(g.traction.copy(), g.delta.copy()) for g in self.groups]

    def of_step(self, want_gradient=True):
        """(D, gradient): the dissipation (J) from the start to the model's last evaluation and, if wanted,
        its derivative with respect to the displacements (J/m, (n_dof,)); else None."""
        m = self.model
        total = 0.0
        grad = np.zeros(m.n_dof) if want_gradient else None
        for g, (t0, d0), ce, area in zip(self.groups, self.start, self.compliance, self.area):
            t1, d1 = g.traction, g.delta
            dd = d1 - d0
            energy1 = np.einsum("eqk,ek,eqk->eq", t1, ce, t1)
            energy0 = np.einsum("eqk,ek,eqk->eq", t0, ce, t0)
            per_point = 0.5 * np.einsum("eqk,eqk->eq", t0 + t1, dd) - 0.5 * (energy1 - energy0)
            total += float((per_point * area).sum())
            if not want_gradient:
                continue
            kt = g.point_tangents()
            a = 0.5 * (t0 + t1) + np.einsum("eqrk,eqr->eqk", kt, 0.5 * dd - ce[:, None, :] * t1)
            a_global = np.einsum("eqrk,eqr->eqk", g.frame, a) * area[:, :, None]  # R^T a w
            nodal = np.einsum("qa,eqk->eak", g.N, a_global)  # (ne, ns, dim)
            fe = np.concatenate([-nodal, nodal], axis=1).reshape(len(g.conn), -1)
            np.add.at(grad, g.dofs, fe)
        return total, grad

