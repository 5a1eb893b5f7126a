"""Static analysis (a room of :mod:`masonrydam.solvers`): load stepping and path control.

- :mod:`.stepping`: the static stages (:class:`~.stepping.StaticStage`, :class:`~.stepping.StaticSolver`): load and
  displacement control with Newton or modified Newton, line search, step cutting, the chatter guard and the
  joint-space fast path;
- :mod:`.arc_length`: Crisfield's cylindrical arc-length and indirect displacement control on the opening of the
  cracking joints, past peaks and through snap-backs.

Imports the linear and joint-space rooms and assembly's elastic tangents; never the dynamic room.
"""
