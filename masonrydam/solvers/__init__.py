"""Solvers, in three rooms with no import cycle (linear <- dynamic <- static):

- :mod:`.linear`: factorizations and iterative solvers of the tangent;
- :mod:`.static`: load stepping and path control (arc-length, indirect displacement control);
- :mod:`.dynamic`: time integrators, the joint-space step, mass, damping, modes and the acoustic reservoir;

and :mod:`.diagnostics` (free parts and mechanisms, used by both static and dynamic).
"""
