"""Helpers shared by the benchmark scripts."""
from __future__ import annotations

import platform
from pathlib import Path


#: thread-count variables of numba, OpenMP, MKL and OpenBLAS
THREAD_VARIABLES = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


def pin_one_thread() -> None:
    """One thread for numba, OpenMP, MKL and OpenBLAS: call it before numpy, scipy or masonrydam are
    imported (the libraries read these variables when they load)."""
    import os

    for name in THREAD_VARIABLES:
        os.environ[name] = "1"


def peak_rss_mib() -> float:
    """High-water resident memory of this process (VmHWM, MiB). Not ``ru_maxrss``: on Linux that
    survives fork + exec, so a child would report the parent's peak when it is larger."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def cpu_model() -> str:
    """CPU model name from /proc/cpuinfo (or the platform's processor string)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


class RssSampler:
    """Samples the resident memory of this process every ``dt`` s in a thread; ``peak`` in MiB after
    the ``with`` block. With ``limit_bytes``, the process exits (status 3, after printing a
    ``JSON:{"error": ...}`` line) when its RSS passes the limit, so that a solver whose memory was
    under-predicted cannot take the machine down."""

    def __init__(self, limit_bytes=None, dt=0.005):
        import threading

        import psutil

        self.proc = psutil.Process()
        self.dt, self.limit = dt, limit_bytes
        self.peak = 0
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        import json
        import os
        import time

        while not self._stop.is_set():
            rss = self.proc.memory_info().rss
            self.peak = max(self.peak, rss)
            if self.limit is not None and rss > self.limit:
                print("JSON:" + json.dumps({"error": f"memory limit: RSS {rss / 2**30:.1f} GiB > "
                                                     f"{self.limit / 2**30:.1f} GiB, stopped"}), flush=True)
                os._exit(3)
            time.sleep(self.dt)

    def __enter__(self):
        self.peak = self.proc.memory_info().rss
        self._t.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()
        self.peak = max(self.peak, self.proc.memory_info().rss) / 2**20


def child_result(cmd: list, marker: str = "RESULT ") -> dict:
    """Run ``cmd`` (a benchmark's child process) and return the JSON of its last stdout line starting with
    ``marker``; RuntimeError with the tails of its output when it printed none."""
    import json
    import subprocess

    proc = subprocess.run(cmd, capture_output=True, text=True)
    lines = [x for x in proc.stdout.splitlines() if x.startswith(marker)]
    if not lines:
        raise RuntimeError(f"run failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}")
    return json.loads(lines[-1][len(marker):])


def example_module(name: str):
    """The example script ``examples/<name>.py``, imported as a module (its ``__main__`` block does not run)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, Path(__file__).resolve().parents[1] / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
