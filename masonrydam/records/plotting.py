"""Four-panel PNG of a record: acceleration, velocity, displacement and its elastic spectrum.

Uses matplotlib's object API with the Agg canvas directly, so the global backend is left alone.
"""
from __future__ import annotations

import numpy as np

from . import measures
from .readers import G


def default_periods(dt: float, n: int = 120, t_max: float = 5.0) -> np.ndarray:
    """Log-spaced periods from ``max(0.02 s, 2 dt)`` to ``t_max``."""
    return np.logspace(np.log10(max(0.02, 2.0 * dt)), np.log10(t_max), n)


def plot_record(trace, path, damping: float = 0.05, periods=None, title: str | None = None):
    """Write the 4-panel figure of ``trace`` (acceleration in m/s2) to ``path`` (PNG); return the path."""
    record_figure(trace, damping, periods, title).savefig(str(path), dpi=110)
    return path


def record_figure(trace, damping: float = 0.05, periods=None, title: str | None = None):
    """The figure of :func:`plot_record` (a matplotlib Figure): acceleration (g), velocity (cm/s) and
    displacement (cm) against time, and the pseudo-acceleration spectrum (g) at ``damping``."""
    # matplotlib (a second to import) only when a figure is drawn
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    a, dt = measures.as_series(trace)
    t = np.arange(a.size) * dt
    v = measures.velocity(a, dt)
    d = measures.displacement(a, dt)
    T = default_periods(dt) if periods is None else np.asarray(periods, dtype=float)
    Sa, _, _ = measures.response_spectrum(a, dt, T, [damping])
    fig = Figure(figsize=(8.0, 9.0), layout="constrained")
    FigureCanvasAgg(fig)
    axs = fig.subplots(4, 1)
    for ax, y, label, scale in ((axs[0], a, "acceleration [g]", 1.0 / G), (axs[1], v, "velocity [cm/s]", 100.0),
                                (axs[2], d, "displacement [cm]", 100.0)):
        ax.plot(t, y * scale, lw=0.7, color="k")
        ax.set_ylabel(label)
        ax.set_xlabel("time [s]")
        ax.grid(True, alpha=0.3)
        ax.set_xlim(t[0], t[-1])
    axs[3].semilogx(T, Sa[0] / G, color="C0")
    axs[3].set_xlabel("period T [s]")
    axs[3].set_ylabel(f"Sa [g], {100 * damping:g} % damping")
    axs[3].grid(True, which="both", alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig
