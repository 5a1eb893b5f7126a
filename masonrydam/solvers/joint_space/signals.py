"""Stop signals held while compiled code runs: :func:`stop_signals_held`."""
from __future__ import annotations

import signal
from contextlib import contextmanager

#: the signals a run's stop handler answers (masonrydam.scene.stopping): held while compiled steps run
_STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM}


@contextmanager
def stop_signals_held():
    """SIGINT and SIGTERM held pending (POSIX ``pthread_sigmask``) for the duration, then delivered. A second stop
    request raises KeyboardInterrupt from its handler at once; arriving while the compiled step runs, the handler
    ran inside numba's boxing of the step's returned arrays (a callback into Python) and the run ended with a
    SystemError traceback instead of its one-line stop. A call takes microseconds to milliseconds (one joint-space
    step), or the steps of one output interval (the compiled step loop, :mod:`masonrydam.solvers.dynamic.loop_kernel`),
    so the stop is not delayed noticeably. Elsewhere (no ``pthread_sigmask``) nothing is held."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)
