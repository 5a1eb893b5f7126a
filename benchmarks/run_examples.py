"""Run every example the README's examples table lists and print its wall time: the table's "run time" column.

    python benchmarks/run_examples.py                 # the examples that take under about 3 minutes
    python benchmarks/run_examples.py --all           # every example (the 3D earthquakes and the walls: an hour)
    python benchmarks/run_examples.py --only koyna    # the examples whose file name contains "koyna"

Each example runs as its README line runs it (``masonrydam run FILE -o OUT.nc``, ``masonrydam ensemble ...``,
``python FILE``), in a fresh process, one after the other, in a temporary folder, with one thread per library
(``OMP_NUM_THREADS=1`` and the like), after one run of the default scene that fills the numba cache. The time
printed is the wall time of the whole command (start-up, compiled code loaded from the cache, the run, the
result file). Print the CPU model with the figures: machines of one kind differ up to 2.6x.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import cpu_model  # benchmarks/ is sys.path[0] when run as a script

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"

#: (file, command arguments after the interpreter or the console script, long): long ones run only with --all.
RUNS = [
    ("block_on_incline.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("block_3d_oblique.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("sliding_block_pulse.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("housner_rocking.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("wall_push_api.py", None, False),
    ("wall_3d_english.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("wall_el_centro.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("eindhoven_J4D.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("eindhoven_J4D_cyclic.py", None, False),
    ("koyna_reservoir.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("koyna_el_centro.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("koyna_full_reservoir.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("dam_3d_gravity.toml", ["run", "{file}", "-o", "out.nc"], False),
    ("dam_3d_reservoir.toml", ["run", "{file}", "-o", "out.nc"], True),
    ("wall_ensemble.toml", ["ensemble", "{file}", "-o", "ens.nc", "--workers", "1"], True),
    ("dam_3d_earthquake.toml", ["run", "{file}", "-o", "out.nc"], True),
    ("arch_dam_earthquake.toml", ["run", "{file}", "-o", "out.nc"], True),
    ("eindhoven_walls.py", None, True),
]


def command(name: str, args: list[str] | None) -> list[str]:
    """The command line that runs one example (a Python example runs with this interpreter)."""
    file = str(EXAMPLES / name)
    if args is None:
        return [sys.executable, file]
    return [sys.executable, "-m", "masonrydam.cli.main"] + [a.replace("{file}", file) for a in args]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--all", action="store_true", help="also the long examples (about an hour in all)")
    parser.add_argument("--only", default="", help="run the examples whose file name contains this text")
    options = parser.parse_args(argv)
    env = dict(os.environ, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", NUMBA_NUM_THREADS="1",
               MPLBACKEND="Agg")
    print(f"CPU: {cpu_model()}, {os.cpu_count()} cores; one thread per library; {time.strftime('%Y-%m-%d')}")
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, "-m", "masonrydam.cli.main", "run", "--default", "-o", "warm.nc"], cwd=tmp,
                       env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        print(f"{'example':32s} {'wall time':>10s}  exit")
        failed = 0
        for name, args, long in RUNS:
            if (long and not options.all) or options.only not in name:
                continue
            start = time.perf_counter()
            done = subprocess.run(command(name, args), cwd=tmp, env=env, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.PIPE, text=True, check=False)
            seconds = time.perf_counter() - start
            print(f"{name:32s} {seconds:9.1f} s  {done.returncode}", flush=True)
            if done.returncode != 0:
                failed += 1
                print("    " + "\n    ".join(done.stderr.strip().splitlines()[-3:]))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
