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
:data:`MAX_STABILIZATIONS` times a step.
"""
from __future__ import annotations

#: tangent factor of open joint points once the step's state pattern repeats
OPEN_TANGENT_STABILIZED = 1.0
#: times a step may switch to the stabilized iteration
MAX_STABILIZATIONS = 4


class ChatterGuard:
    """The guard of one step on ``model``; ``regular_open_tangent``: the open points' tangent factor outside
    the stabilized iterations (the solver's own)."""

    def __init__(self, model, regular_open_tangent: float):
        self.model, self.regular = model, regular_open_tangent
        self.stabilized = False
        self.seen, self.prev = set(), None
        self.toggles = self.same = 0

    def observe(self) -> str | None:
        """After an iteration's evaluation: "stabilize" where the joint-state pattern cycles (the open tangent
        is stiffened and broken bonds latched), "release" where it has settled (the tangent is regular again),
        else None. After either action the caller evaluates again at the same displacements."""
        m = self.model
        sig = m.state_signature()
        action = None
        if not self.stabilized and sig != self.prev and sig in self.seen and self.toggles < MAX_STABILIZATIONS:
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
        self.seen.add(sig)
        self.prev = sig
        return action
