"""Solvers, in rooms with no import cycle (linear <- joint_space <- static, dynamic; static and dynamic are siblings):

- :mod:`.linear`: factorizations and iterative solvers of the tangent, small dense LU and low-rank updates;
- :mod:`.joint_space`: a Newton step condensed on the nonlinear joints' relative displacements (static and dynamic);
- :mod:`.static`: load stepping and path control (arc-length, indirect displacement control);
- :mod:`.dynamic`: time integrators, modes and the acoustic reservoir;

and :mod:`.diagnostics` (free parts and mechanisms) and :mod:`.chatter` (the Newton chatter guard), used by both
static and dynamic. Mass, damping and elastic tangents are assembly's (:mod:`masonrydam.assembly`).
"""
