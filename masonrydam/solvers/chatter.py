"""The chatter guard of a Newton step with joints, shared by the static and the dynamic solvers
(:meth:`~masonrydam.solvers.static.stepping.StaticSolver._newton_iterations`,
:meth:`~masonrydam.solvers.dynamic.implicit.ImplicitStep.solve`).

Newton on joints that stick, slide, open and close can cycle between joint-state patterns. When the pattern
of an iteration repeats one seen before in the step, other than the previous iteration's (a pattern that
stays from one iteration to the next is ordinary convergence), open points get their initial stiffness in
the iteration matrix (``OPEN_TANGENT_STABILIZED``; the residual is unchanged, convergence linear) and bonds
that broke stay broken (``Model.latch_broken_bonds``): with cohesion the shear traction jumps from up to c
to 0 when a point opens, and letting iterations "un-break" a bond cycles across that jump. Once the pattern
has stayed the same for two iterations, the consistent tangent comes back (quadratic convergence; where many
points are open the initial stiffness stalled Newton at 1-4 % per iteration), at most
:data:`MAX_STABILIZATIONS` times a step. In static steps a residual that stagnates while the pattern keeps
moving, never exactly as before, has the broken bonds latched too, with the consistent tangent kept
(:class:`ChatterGuard`, ``stagnation``).
"""
from __future__ import annotations

#: tangent factor of open joint points once the step's state pattern repeats
OPEN_TANGENT_STABILIZED = 1.0
#: times a step may switch to the stabilized iteration
MAX_STABILIZATIONS = 4
#: a static step whose residual has not halved (STAGNATION_RATIO) over this many iterations while the joint-state
#: pattern keeps changing is treated as cycling too (the stagnation trigger, see ChatterGuard)
STAGNATION_WINDOW = 4
STAGNATION_RATIO = 0.5


class ChatterGuard:
    """The guard of one step on ``model``; ``regular_open_tangent``: the open points' tangent factor outside
    the stabilized iterations (the solver's own).

    ``stagnation`` (static steps): where the pattern keeps changing, never exactly as before, while the residual
    has not fallen by STAGNATION_RATIO over the last STAGNATION_WINDOW iterations, the bonds broken in the
    current iterate are latched (the consistent tangent stays), at most MAX_STABILIZATIONS times a step. On a
    large model the exact pattern seldom comes back: on the 8-monolith dam's reservoir on the general path
    (joint space off) about a hundred points at the crack tips flipped between open (bond broken) and closed
    (bond intact) while Newton stayed at a residual of 1-4e-2 for 10-17 iterations, and at element_size 3
    (22 488 joint points) for 30 iterations, when the step was cut. Latching them is the joint space's remedy
    (:meth:`~masonrydam.solvers.joint_space.JointSpace._bond_chatter`, where the argument that a bond broken
    by an iterate of the step is an admissible end state is made) for every point at once, as the exact-repeat
    trigger does. The stiffened open tangent is not taken here: while the front of the crack still moves it
    converges linearly (on the 8-monolith dam 15 iterations to fall from 2.8e-2 to 5e-3). The dynamic steps keep
    the exact-repeat trigger alone (their histories are the reference figures of the dynamic benchmarks)."""

    def __init__(self, model, regular_open_tangent: float, stagnation: bool = False):
        self.model, self.regular = model, regular_open_tangent
        self.stagnation = bool(stagnation)
        self.stabilized = False
        self.seen, self.prev = set(), None
        self.toggles = self.same = self.latches = 0
        self.residuals = []  # the residual norms observed since the last action (the stagnation trigger)

    def _stagnates(self) -> bool:
        """The residual has not fallen by STAGNATION_RATIO over the last STAGNATION_WINDOW iterations."""
        r = self.residuals
        return self.stagnation and len(r) > STAGNATION_WINDOW and r[-1] > STAGNATION_RATIO * r[-1 - STAGNATION_WINDOW]

    def observe(self, residual_norm: float | None = None) -> str | None:
        """After an iteration's evaluation (``residual_norm``: its residual's norm, N, for the stagnation
        trigger): "stabilize" where the joint-state pattern cycles (the open tangent is stiffened and broken
        bonds latched), "release" where it has settled (the tangent is regular again), "latch" where the
        residual stagnates while the pattern moves and some bonds were newly latched broken (``stagnation``),
        else None. After any action the caller evaluates again at the same displacements."""
        m = self.model
        sig = m.state_signature()
        if residual_norm is not None:
            self.residuals.append(float(residual_norm))
        action = None
        if not self.stabilized and sig != self.prev and sig not in self.seen and self._stagnates() \
                and self.latches < MAX_STABILIZATIONS:
            self.latches += 1
            action = "latch" if m.latch_broken_bonds() else None
            self.residuals = []
        elif not self.stabilized and sig != self.prev and sig in self.seen and self.toggles < MAX_STABILIZATIONS:
            self.stabilized, self.same = True, 0
            self.toggles += 1
            m.set_open_tangent(OPEN_TANGENT_STABILIZED)
            m.latch_broken_bonds()
            action = "stabilize"
        elif self.stabilized:
            self.same = self.same + 1 if sig == self.prev else 0
            if self.same >= 2:
                self.stabilized = False
                m.set_open_tangent(self.regular)
                self.seen = set()
                action = "release"
        if action is not None:
            self.residuals = []
        self.seen.add(sig)
        self.prev = sig
        return action
