"""The progress bar of a run (tqdm on stderr)."""
from __future__ import annotations

import sys
import time

from tqdm import tqdm


class Progress:
    """The progress bar of a run: the stages done (``__call__``) and, for a long static step, what it
    is doing (``status``: load factor, iteration, residual, cuts), so that a run stuck in its first
    step is visibly alive."""

    def __init__(self, n_stages, enabled):
        self.bar = None
        if enabled:
            self.bar = tqdm(total=n_stages, unit="stage",
                            bar_format="{l_bar}{bar}| {n:.2f}/{total} stages [{elapsed}]{postfix}",
                            file=sys.stderr, leave=True)
        self.done = 0.0
        self._shown = 0.0

    def __call__(self, stage_index, lam):
        if self.bar is not None:
            pos = stage_index + lam
            self.bar.update(pos - self.done)
            self.done = pos

    def status(self, text: str):
        if self.bar is not None:
            now = time.monotonic()
            refresh = now - self._shown >= 0.5  # at most twice a second: a Newton iteration can take 1 ms
            self.bar.set_postfix_str(text, refresh=refresh)
            if refresh:
                self._shown = now

    def close(self):
        if self.bar is not None:
            self.bar.close()
