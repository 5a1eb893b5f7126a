"""Mode shapes of a result file (``masonrydam plot OUT.nc --mode N``).

A modal stage (``{ type = "modal", modes = N }`` in ``[[stages]]``) writes, besides the static steps,
the dimension ``mode`` (numbers 1, 2, ...) and ``frequency`` (Hz), ``period`` (s), ``mode_shape``
(mode, node, component; mass-normalised, phi^T M phi = 1, in kg^-0.5), ``effective_mass`` (kg) and
``effective_mass_ratio`` (1) on (mode, component) (:meth:`masonrydam.results.writer.ResultWriter.write_modes`).

A result file holds no mesh connectivity: the recorded nodes (coordinates ``x``, ``y`` [, ``z``] on
``node``, m) and the joint integration points (``joint_x`` ... on ``joint_point``, with the interface
element they belong to). :func:`mode_figure` therefore draws

- the undeformed nodes as grey points, and the joints as grey lines (2D: the integration points of each
  interface element joined, which traces the joint lines) or grey crosses (3D: the integration points);
- the deformed nodes ``coords + scale * mode_shape`` as points coloured by the amplitude of the shape at
  the node relative to its largest value (``|phi| / max |phi|``).

The joints are drawn undeformed only: the file has no displacement at the joint points. Nodes on the two
faces of a joint coincide in the undeformed geometry and separate in the deformed one where the mode
opens or slides the joint.

2D results are drawn in the x-y plane, 3D results in a 3D axes (mplot3d) with equal scales on the three
axes, viewed from matplotlib's default elevation and azimuth. Mode shapes have an arbitrary sign and a
mass-normalised amplitude (kg^-0.5), so the displacement drawn is ``scale * mode_shape`` with ``scale``
(kg^0.5 m per unit of shape, i.e. the drawn displacement is in m) given, or chosen so that the largest
nodal displacement (Euclidean norm over the components) is :data:`AUTO_FRACTION` of the model's largest
extent (the largest side of the bounding box of the recorded nodes). Uses matplotlib's object API with the
Agg canvas, so the global backend is left alone.
"""
from __future__ import annotations

import numpy as np

from ..errors import MasonrydamError

#: the automatic scale makes the largest drawn nodal displacement this fraction of the model's largest extent
AUTO_FRACTION = 0.10


def node_coordinates(ds) -> np.ndarray:
    """Undeformed coordinates (n_node, dim) of the recorded nodes of a result, m (variables ``x``, ``y``
    [, ``z``] on ``node``, in the order of the ``component`` coordinate)."""
    return np.stack([np.asarray(ds[str(c)].values, dtype=float) for c in ds.component.values], axis=1)


def model_extent(coords: np.ndarray) -> float:
    """Largest side (m) of the bounding box of ``coords`` (n, dim); 1.0 where it is nil (one node)."""
    if not len(coords):
        return 1.0
    ext = float(np.max(coords.max(axis=0) - coords.min(axis=0)))
    return ext if ext > 0 else 1.0


def auto_scale(coords: np.ndarray, shape: np.ndarray, fraction: float = AUTO_FRACTION) -> float:
    """The scale of a shape ``shape`` (n_node, dim; a mode in kg^-0.5, or displacements in m) that makes its
    largest nodal displacement (Euclidean norm over the components) ``fraction`` of the largest extent of
    ``coords`` (n_node, dim; m): ``fraction * extent / max |phi|``; 1.0 for a nil shape."""
    peak = float(np.max(np.linalg.norm(shape, axis=1))) if len(shape) else 0.0
    if not peak > 0:
        return 1.0
    return fraction * model_extent(coords) / peak


def mode_data(ds, mode: int, where: str = "the result"):
    """Position of mode number ``mode`` (as the ``mode`` coordinate: 1, 2, ...) in ``ds`` and its shape
    (n_node, dim; kg^-0.5), after the checks of ``masonrydam plot --mode``: the result has modes, ``mode``
    is one of them and the modal stage has run (finite frequency and shape). Errors
    (:class:`~masonrydam.errors.MasonrydamError`) name ``where`` (the file) and the option ``--mode``."""
    if not ds.sizes.get("mode", 0) or "mode_shape" not in ds.variables:
        raise MasonrydamError(f"--mode: {where} has no modal stage; add {{ type = \"modal\", modes = N }} to "
                              "[[stages]] and run the scene again")
    numbers = np.asarray(ds.mode.values).astype(int)
    hit = np.nonzero(numbers == int(mode))[0]
    if not len(hit):
        valid = f"from {numbers.min()} to {numbers.max()}" if len(numbers) > 1 else f"{numbers[0]} (its only mode)"
        raise MasonrydamError(f"--mode {mode}: {where} has {len(numbers)} mode(s); give a mode number {valid}")
    k = int(hit[0])
    shape = np.asarray(ds.mode_shape.isel(mode=k).transpose("node", "component").values, dtype=float)
    freq = float(ds.frequency.values[k])
    if not (np.isfinite(freq) and np.isfinite(shape).all()):
        status = ds.attrs.get("status", "?")
        reason = ds.attrs.get("status_reason")
        raise MasonrydamError(f"--mode {mode}: the modes in {where} are NaN: its modal stage did not run (status "
                              f"'{status}'{': ' + str(reason) if reason else ''}); fix the run and run it again")
    return k, shape


def mode_title(ds, k: int, mode: int, title: str | None = None) -> str:
    """Title of the plot of the mode at position ``k`` (number ``mode``): ``title`` (if any) on its own
    line, then the mode number, frequency (Hz, 4 significant digits), period (s, 4 significant digits)
    and the effective mass ratio per direction in % (1 decimal)."""
    f = float(ds.frequency.values[k])
    T = float(ds.period.values[k])
    ratio = np.asarray(ds.effective_mass_ratio.isel(mode=k).values, dtype=float)
    ratios = ", ".join(f"{c} {100 * r:.1f} %" for c, r in zip(ds.component.values, ratio))
    line = f"mode {mode}: f = {f:.4g} Hz, T = {T:.4g} s; effective mass {ratios}"
    return f"{title}\n{line}" if title else line


def mode_figure(ds, mode: int, scale: float | None = None, title: str | None = None):
    """The figure of ``masonrydam plot OUT.nc --mode N`` (a matplotlib Figure, not drawn to screen).

    ds: a result (``xarray.Dataset``) with the variables of a modal stage; mode: the mode number, as the
    ``mode`` coordinate (1-based); scale: factor of the drawn displacement ``scale * mode_shape`` (kg^0.5
    m per unit of shape, so that the drawn displacement is in m; negative flips the arbitrary sign of the
    shape), default :func:`auto_scale` (largest displacement 10 % of the model's largest extent); title:
    an optional first line of the title (the file name on the command line), also naming the result in
    the errors.

    Draws, in an x-y axes (2D) or a 3D axes (3D), the undeformed nodes (grey, ``gid="undeformed"``), the
    joints (grey, undeformed, ``gid="joints"``: lines in 2D, crosses in 3D) and the deformed nodes
    ``coords + scale * shape`` (coloured by ``|phi| / max |phi|``, ``gid="deformed"``). Errors
    (:class:`~masonrydam.errors.MasonrydamError`) name the option (``--mode``, ``--scale``): a result
    without modes, a mode number not in it, NaN modes (the modal stage did not run), a nil or non-finite
    scale."""
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    k, shape = mode_data(ds, mode, f"'{title}'" if title else "the result")
    coords = node_coordinates(ds)
    if scale is None:
        scale = auto_scale(coords, shape)
    elif not (np.isfinite(scale) and scale != 0):
        raise MasonrydamError(f"--scale must be a non-zero finite number, got {scale!r}")
    scale = float(scale)
    deformed = coords + scale * shape
    amp = np.linalg.norm(shape, axis=1)
    rel = amp / amp.max() if len(amp) and amp.max() > 0 else np.zeros_like(amp)
    dim = coords.shape[1]
    comps = [str(c) for c in ds.component.values]

    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    FigureCanvasAgg(fig)
    if dim == 3:
        ax = fig.add_subplot(projection="3d")  # registers mplot3d's "3d" projection on first use
        ax.scatter(*coords.T, s=4, color="0.7", depthshade=False, label="undeformed", gid="undeformed")
        jp = _joint_points(ds, comps)
        if len(jp):
            ax.scatter(*jp.T, s=10, marker="x", color="0.55", depthshade=False, label="joints (undeformed)",
                       gid="joints")
        sc = ax.scatter(*deformed.T, s=8, c=rel, cmap="viridis", vmin=0.0, vmax=1.0, depthshade=False,
                        label=f"mode {mode}, scale {scale:.3g}", gid="deformed")
        ax.set_zlabel(f"{comps[2]} [m]")
        both = np.vstack([coords, deformed])
        ax.set_box_aspect(np.maximum(np.ptp(both, axis=0), 1e-3 * model_extent(both)))
    else:
        ax = fig.add_subplot()
        ax.scatter(*coords.T, s=4, color="0.7", label="undeformed", gid="undeformed", zorder=1)
        first = True
        for seg in _joint_segments(ds, comps):
            ax.plot(seg[:, 0], seg[:, 1], color="0.55", lw=1.0, gid="joints", zorder=2,
                    label="joints (undeformed)" if first else None)
            first = False
        sc = ax.scatter(*deformed.T, s=8, c=rel, cmap="viridis", vmin=0.0, vmax=1.0, zorder=3,
                        label=f"mode {mode}, scale {scale:.3g}", gid="deformed")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
    ax.set_xlabel(f"{comps[0]} [m]")
    ax.set_ylabel(f"{comps[1]} [m]")
    fig.colorbar(sc, ax=ax, shrink=0.7, label="|phi| / max |phi|")
    ax.legend(fontsize=7, loc="best")
    ax.set_title(mode_title(ds, k, mode, title), fontsize=9)
    return fig


def _joint_points(ds, comps) -> np.ndarray:
    """Coordinates (n_joint_point, dim) of the joint integration points (m); (0, dim) without joints."""
    if not ds.sizes.get("joint_point", 0) or f"joint_{comps[0]}" not in ds.variables:
        return np.zeros((0, len(comps)))
    return np.stack([np.asarray(ds[f"joint_{c}"].values, dtype=float) for c in comps], axis=1)


def _joint_segments(ds, comps) -> list:
    """2D joint lines: for each interface element (joint set, element index), its integration points
    (n_ip, 2) in the order of their index along the element."""
    x = _joint_points(ds, comps)
    if not len(x) or "joint_element" not in ds.variables:
        return []
    sets = np.asarray(ds.joint_set.values) if "joint_set" in ds.variables else np.zeros(len(x), int)
    elem = np.asarray(ds.joint_element.values)
    ip = (np.asarray(ds.joint_integration_point.values) if "joint_integration_point" in ds.variables
          else np.arange(len(x)))
    order = np.lexsort((ip, elem, sets))
    keys = np.stack([sets[order], elem[order]], axis=1)
    cuts = np.nonzero(np.any(np.diff(keys, axis=0) != 0, axis=1))[0] + 1
    return [x[idx] for idx in np.split(order, cuts) if len(idx) > 1]
