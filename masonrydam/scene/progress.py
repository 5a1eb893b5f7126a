"""The progress bar of a run (tqdm on stderr): the stages done and what the current one is doing."""
from __future__ import annotations

import math
import sys
import time
from collections import deque

from tqdm import tqdm


class Progress:
    """The progress bar of a run: the stages done (``__call__``) and what the current stage is doing (``status``): for a
    long static step its load factor, iteration, residual and cuts, so that a run stuck in its first step is visibly
    alive; for a dynamic stage :class:`DynamicProgress`'s line."""

    def __init__(self, n_stages, enabled):
        self.bar = None
        if enabled:
            self.bar = tqdm(total=n_stages, unit="stage",
                            bar_format="{l_bar}{bar}| {n:.2f}/{total} stages [{elapsed}]{postfix}",
                            file=sys.stderr, leave=True)
        self.done = 0.0
        self._shown = 0.0
        self._pending = False  # a text set but not yet shown (the rate limit)

    @property
    def enabled(self) -> bool:
        """Whether the bar is shown (the dynamic stages' words are not composed where it is not)."""
        return self.bar is not None

    def __call__(self, stage_index, lam):
        if self.bar is not None:
            pos = stage_index + lam
            self.bar.update(pos - self.done)
            self.done = pos

    def status(self, text: str, force: bool = False):
        """Show ``text`` after the bar: at most twice a second (a Newton iteration can take 1 ms) unless ``force``
        (a new stage: the last stage's words must not stay)."""
        if self.bar is not None:
            now = time.monotonic()
            if force and self._pending:  # the last words of the stage before, shown once before they go
                self.bar.refresh()
            refresh = force or now - self._shown >= 0.5
            self.bar.set_postfix_str(text, refresh=refresh)
            self._pending = not refresh
            if refresh:
                self._shown = now

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _duration(seconds: float) -> str:
    """``seconds`` as ``1h02m``, ``3m05s`` or ``12s``."""
    s = int(round(seconds))
    if s >= 3600:
        return f"{s // 3600}h{s % 3600 // 60:02d}m"
    if s >= 60:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s}s"


def dynamic_status(name: str, t: float, t_end: float, dt: float | None, refused: int | None,
                   seconds_left: float | None) -> str:
    """The words after the bar during a dynamic stage: its name, the simulated time against the stage's end (s), the
    recent step size ``dt`` (s; None before the first step), the steps refused and retried smaller (``dt = "auto"``;
    None at a fixed step) and the wall time left at the recent rate (None until it can be estimated)."""
    words = [f"{name}: t = {t:.4g} of {t_end:.4g} s"]
    if dt is not None:
        words.append(f"dt {dt:.3g} s")
    if refused is not None:
        words.append(f"{refused} refused")
    if seconds_left is not None and math.isfinite(seconds_left):
        words.append(f"about {_duration(seconds_left)} left")
    return ", ".join(words)


class DynamicProgress:
    """The progress of a dynamic stage (the solver's ``progress(fraction)``): moves the bar and shows
    :func:`dynamic_status`, read from the solver's last converged state and statistics, every :data:`UPDATE_S` seconds
    and at the stage's end. The time left is the stage's remaining fraction over the rate of the last
    :data:`RATE_WINDOW_S` seconds of wall time."""

    #: wall seconds over which the rate of the time left is measured
    RATE_WINDOW_S = 10.0
    #: wall seconds between two compositions of the words (the bar shows them at most twice a second; a step can
    #: take 0.2 ms, and composing them every step cost 2.8 us a step)
    UPDATE_S = 0.5

    def __init__(self, bar: Progress, stage_index: int, stage, solver, t_start: float, clock=time.monotonic):
        self.bar, self.stage_index, self.stage, self.solver = bar, stage_index, stage, solver
        self.t_start = t_start  # simulated time (s) at the stage's start
        self.clock = clock
        self.samples = deque()  # (wall s, fraction, simulated t, steps)
        self._composed = -math.inf  # wall time of the last words
        bar.status(dynamic_status(stage.name, t_start, t_start + stage.duration, None,
                                  0 if stage.settings.adaptive else None, None), force=True)

    def __call__(self, fraction: float) -> None:
        self.bar(self.stage_index, fraction)
        if not self.bar.enabled:
            return
        now = self.clock()
        if now - self._composed < self.UPDATE_S and fraction < 1.0:
            return
        self._composed = now
        last = getattr(self.solver, "_last_converged", None)
        t = self.t_start + fraction * self.stage.duration if last is None else last[1].t
        stats = self.solver.stats
        self.samples.append((now, fraction, t, stats.steps))
        while len(self.samples) > 2 and now - self.samples[1][0] >= self.RATE_WINDOW_S:
            self.samples.popleft()
        w0, f0, t0, n0 = self.samples[0]
        dt = (t - t0) / (stats.steps - n0) if stats.steps > n0 else None
        left = (1.0 - fraction) * (now - w0) / (fraction - f0) if fraction > f0 and now > w0 else None
        self.bar.status(dynamic_status(self.stage.name, t, self.t_start + self.stage.duration, dt,
                                       stats.steps_rejected if self.stage.settings.adaptive else None, left))
