"""Stopping a run on request: Ctrl-C (SIGINT) and SIGTERM.

The first request asks the run to stop at the end of the current step (the solvers ask
:meth:`StopRequests.requested` after every converged step); a second one aborts at once with a
``KeyboardInterrupt``, except while a step is being written, where it waits for the end of that
write so that the result file never holds half a step. The handlers are installed for the time of a
run only, and only from the main thread (Python delivers signals there alone).
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

#: status written to the result file for each signal
SIGNAL_STATUS = {signal.SIGINT: "interrupted", signal.SIGTERM: "terminated"}


class StopRequests:
    """The stop requests of one run. ``status`` is None until a signal arrives, then ``"interrupted"``
    (SIGINT) or ``"terminated"`` (SIGTERM)."""

    def __init__(self):
        self.status: str | None = None
        self._writing = 0
        self._abort_pending = False
        self._previous = {}

    def requested(self) -> str | None:
        return self.status

    def install(self) -> "StopRequests":
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNAL_STATUS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def restore(self) -> None:
        for sig, handler in self._previous.items():
            # None: the previous handler was installed from C (not known to Python): the default one
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)
        self._previous.clear()

    def _handle(self, signum, frame):
        if self.status is None:
            self.status = SIGNAL_STATUS[signum]
            return
        if self._writing:
            self._abort_pending = True
            return
        raise KeyboardInterrupt

    @contextmanager
    def closing(self):
        """A section (closing the result file) after which the run is over: a second request waits for
        its end and is then dropped, since there is nothing left to stop."""
        self._writing += 1
        try:
            yield
        finally:
            self._writing -= 1
            if not self._writing:
                self._abort_pending = False

    @contextmanager
    def writing(self):
        """A section (writing a step) that a second request does not cut: the abort waits for its end."""
        self._writing += 1
        try:
            yield
        finally:
            self._writing -= 1
        if not self._writing and self._abort_pending:
            self._abort_pending = False
            raise KeyboardInterrupt
