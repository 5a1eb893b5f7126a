"""The long run of the fuzzed scene suite: many mutated scenes (tests/scene_fuzzing.py), each checked and run as
the command line does, and what was found: how many scenes were tried, how many ran, were refused in one line by the
check or stopped in the run, and the distinct failures of the property (a traceback, a NaN in a completed result, a
message of more than one line or without its key, an earlier result changed), each with one scene that shows it.

    python benchmarks/fuzz_scenes.py [--scenes 200] [--seed 1] [--max-changes 3]

Not a test (minutes); the test suite runs a seeded few (tests/scene/test_scene_fuzz.py).
"""
from __future__ import annotations

import argparse
import collections
import random
import re
import signal
import sys
import tempfile
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for p in (ROOT, ROOT / "tests"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

from scene_fuzzing import BASE_SCENES, OPERATIONS, mutate, outcome  # noqa: E402


class Hung(Exception):
    """A scene that took longer than the time limit (a check or a run that does not end in reasonable time)."""


def _alarm(signum, frame):
    raise Hung("took longer than the time limit")


def _reason(what: str) -> str:
    """``refused by check: SceneError: scene key 'stages[1].dt': ...`` as ``check: SceneError stages[].dt``."""
    stage, rest = what.split(": ", 1)
    name, _, message = rest.partition(": ")
    key = re.match(r"scene key '([^']*)'", message)
    where = re.sub(r"\[\d+\]", "[]", key.group(1)) if key else message[:60]
    return f"{stage.split()[0]}: {name} {where}"


def _where(exc: BaseException) -> str:
    """The innermost frame of masonrydam's own code in ``exc``'s traceback, as ``file:line``."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if "/masonrydam/" in f.filename]
    if not frames:
        return "tests"
    f = frames[-1]
    return f"{f.filename.split('/masonrydam/')[-1]}:{f.lineno}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--max-changes", type=int, default=3)
    ap.add_argument("--show", type=int, default=12, help="how many of the most frequent refusals to print")
    ap.add_argument("--time-limit", type=float, default=60.0, help="seconds a scene may take before it counts as hung")
    args = ap.parse_args(argv)
    rng = random.Random(args.seed)
    signal.signal(signal.SIGALRM, _alarm)
    kinds = collections.Counter()
    reasons = collections.Counter()
    late = {}
    failures = {}
    t0 = time.perf_counter()
    slowest = (0.0, "")
    for n in range(args.scenes):
        base = rng.choice(sorted(BASE_SCENES))
        scene = BASE_SCENES[base]()
        words = [base]
        for _ in range(rng.randint(1, args.max_changes)):
            op = rng.choice(OPERATIONS)
            done = mutate(scene, op, rng.randrange(10**6), rng.randrange(10**6))
            if done:
                words.append(done)
        t = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            try:
                signal.setitimer(signal.ITIMER_REAL, args.time_limit)
                what = outcome(scene, Path(tmp))
                signal.setitimer(signal.ITIMER_REAL, 0)
                kinds[what.split(":")[0]] += 1
                if ":" in what:
                    reasons[_reason(what)] += 1
                    if what.startswith("run"):  # refused by the run, not by the check: a check raised late?
                        late.setdefault(_reason(what), ("; ".join(words), what.split(": ", 1)[1][:300]))
            except BaseException as exc:  # the property failed: a traceback, a NaN, a changed file
                if isinstance(exc, KeyboardInterrupt) and not type(exc).__module__.startswith("masonrydam"):
                    raise
                signal.setitimer(signal.ITIMER_REAL, 0)
                key = (type(exc).__name__, _where(exc))
                kinds["property failed"] += 1
                failures.setdefault(key, [0, "; ".join(words), str(exc).splitlines()[0][:200] if str(exc) else ""])
                failures[key][0] += 1
        dt = time.perf_counter() - t
        if dt > slowest[0]:
            slowest = (dt, "; ".join(words))
    wall = time.perf_counter() - t0
    print(f"scenes tried: {args.scenes} (seed {args.seed}, 1 to {args.max_changes} changes each), {wall:.0f} s, "
          f"slowest {slowest[0]:.1f} s ({slowest[1]})")
    for what, count in kinds.most_common():
        print(f"  {count:5d}  {what}")
    print(f"distinct refusals (error and scene key, list indices dropped): {len(reasons)}; the most frequent:")
    for why, count in reasons.most_common(args.show):
        print(f"  {count:5d}  {why}")
    print(f"refused by the run after the check passed ({len(late)} kinds), one scene each:")
    for why, (example, message) in late.items():
        print(f"  {why}\n         e.g. {example}\n         {message}")
    print(f"distinct failures of the property: {len(failures)}")
    for (name, where), (count, example, message) in sorted(failures.items(), key=lambda kv: -kv[1][0]):
        print(f"  {count:5d}  {name} at {where}: {message}\n         e.g. {example}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
