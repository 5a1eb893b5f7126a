"""Why the Newton solves of the holds fail on the inviscid Eindhoven wall J4D (docs/masonry_softening.md, "Why the
holds' Newton solves fail"). The wall is pushed with ``limit_point = "relax"`` (``examples/eindhoven_walls.py``).
The first hold steps that fail are solved a second time with up to ``--iterations`` Newton iterations (a solve
still ends where its residual stagnates, as in the hold), each iterate recorded, and are then reverted, so the run
goes on as it would have.

    python benchmarks/study_hold_failures.py [--failures 3] [--push-mm 4.0] [--iterations 30]

For each failed hold step it prints:
- the pseudo-time step ``r = dt / tau`` and the relative residual of every iterate;
- the secant line searches (:func:`masonrydam.solvers.newton.secant_line_search`): the step length taken, and
  ``g(1) / g(0)``, the work of the full step over the work at its start. An iteration whose full step is accepted
  without a search is not listed;
- how many composite joint points change return region from one evaluation with the tangent to the next (the
  iterates and the full steps tried), and which transitions. The regions are elastic 0, shear 1, tension 2, cap 3,
  tension/shear 4 and shear/cap 5 (:mod:`masonrydam.materials.composite.columns`);
- the tangent check: over every point off the elastic branch at every such evaluation, the largest difference between
  the law's tangent (the viscous one of the hold step) and central differences of its tractions, relative to the
  tangent's largest entry at that point, and how many points differ by more than 1 %;
- the continuity check: along the segment between two such evaluations, at each point that changed region, the law
  sampled at 2 001 points. A spike is a step of the tractions more than 20 times both of its neighbours, and above
  1 Pa; it is a jump where it is still a spike when sampled again at 2 001 points between its two samples, and a
  steep stretch (the units' cracks' penalty) where it is not.

How: it wraps the hold step (``relaxation._step``), the Newton loop (``stepping.newton_iterations``, for the
residuals), the secant line search and ``Model.evaluate`` (the states of the composite groups) in this process. A
study, not a test: it stops after the failures asked for. Six failures: 30 s on a 2-core AMD EPYC, one thread, with
numba's cache warm, and 55 s compiling.
"""
from __future__ import annotations

from _common import cpu_model, example_module, pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse  # noqa: E402
import collections  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

import masonrydam  # noqa: E402
from masonrydam.assembly.model import Model  # noqa: E402
from masonrydam.errors import NumericalError  # noqa: E402
from masonrydam.materials.composite.batch import composite_evaluate  # noqa: E402
from masonrydam.materials.composite.columns import S_CODE  # noqa: E402
from masonrydam.solvers.static import line_search, relaxation, stepping  # noqa: E402

SAMPLES = 2001  # points along a segment in the continuity check
TANGENT_MISMATCH = 1e-2  # a tangent that differs from central differences by more than this, relative


class Enough(Exception):
    """Raised once the failures asked for have been studied."""


class Recorder:
    """What the wrapped functions record while a failed hold step is solved again."""

    def __init__(self):
        self.on = False
        self.states = []  # per evaluation with the tangent: [(code, delta, state_base, params) per composite group]
        self.searches = []  # (step length, g(1) / g(0) or None)
        self.residuals = []  # relative residual of each iterate of the last Newton solve


def composite_groups(model):
    return [g for g in model.igroups if g.joint_law.name == "composite"]


def instrument(rec: Recorder):
    """Wrap the model's evaluation, the Newton loop and the line search to record into ``rec``."""
    evaluate = Model.evaluate

    def recording_evaluate(self, u, want_tangent=True):
        out = evaluate(self, u, want_tangent)
        if rec.on and want_tangent:
            rec.states.append([(g.state_trial[:, :, S_CODE].copy(), g.delta.copy(), g.state_base.copy(),
                                g.params_table[g.param_index].copy()) for g in composite_groups(self)])
        return out

    newton = stepping.newton_iterations

    def recording_newton(step, start, test, max_iterations, guard=None, on_check=None, give_up=None):
        rec.residuals = []

        def check(it, rn, scale):
            rec.residuals.append(rn / scale if scale > 0 else rn)
            if on_check is not None:
                on_check(it, rn, scale)
        return newton(step, start, test, max_iterations, guard=guard, on_check=check, give_up=give_up)

    search = line_search.secant_line_search

    def recording_search(directional_residual, g0, max_tries=6, first=None):
        s, searched = search(directional_residual, g0, max_tries, first)
        if rec.on:
            rec.searches.append((s, None if first is None else first / g0))
        return s, searched

    Model.evaluate = recording_evaluate
    stepping.newton_iterations = recording_newton
    line_search.secant_line_search = recording_search


def off_elastic(code):
    """(elements, points) of the points whose return region is not elastic."""
    e, g = np.nonzero(code != 0)
    return e, g


def tangent_check(states) -> tuple[float, int, int]:
    """The largest relative difference between the law's tangent and central differences, the points above
    TANGENT_MISMATCH, and the point states checked."""
    worst, bad, checked = 0.0, 0, 0
    for groups in states:
        for code, delta, base, params in groups:
            e, g = off_elastic(code)
            if e.size == 0:
                continue
            d, s, p = delta[e, g], base[e, g], params[e]
            _, tangent, _ = composite_evaluate(d, p, s)
            scale = np.maximum(np.abs(tangent).max(axis=(1, 2)), 1.0)
            h = 1e-9 * np.maximum(np.abs(d).max(axis=1), 1e-7)
            err = np.zeros(e.size)
            for j in range(d.shape[1]):
                plus, minus = d.copy(), d.copy()
                plus[:, j] += h
                minus[:, j] -= h
                try:
                    diff = (composite_evaluate(plus, p, s)[0] - composite_evaluate(minus, p, s)[0]) / (2 * h[:, None])
                except NumericalError:
                    continue
                err = np.maximum(err, np.abs(diff - tangent[:, :, j]).max(axis=1) / scale)
            worst, bad, checked = max(worst, float(err.max())), bad + int((err > TANGENT_MISMATCH).sum()), \
                checked + e.size
    return worst, bad, checked


def _largest_spike(d0, d1, base, params, t0, t1):
    """The law sampled at SAMPLES points between ``d0 + t0 (d1 - d0)`` and ``d0 + t1 (d1 - d0)``: the largest step
    of the tractions (Pa) that is more than 20 times both of its neighbours and above 1 Pa, and where (None, None
    without one); the largest step of all."""
    t = np.linspace(t0, t1, SAMPLES)
    seg = d0[None, :] + t[:, None] * (d1 - d0)[None, :]
    trac = composite_evaluate(seg, params, np.repeat(base[None, :], SAMPLES, axis=0))[0]
    step = np.abs(np.diff(trac, axis=0)).max(axis=1)
    neighbours = np.maximum(np.r_[step[1:], 0.0], np.r_[0.0, step[:-1]])
    at = np.nonzero((step > 20.0 * neighbours) & (step > 1.0))[0]
    if at.size == 0:
        return None, None, float(step.max())
    k = int(at[np.argmax(step[at])])
    return float(step[k]), (float(t[k]), float(t[k + 1])), float(step.max())


def continuity_check(before, after) -> tuple[int, int, list[str]]:
    """Points that changed region between two evaluations, those whose tractions jump on the segment between
    them, and in words the jumps and the steep stretches. A spike of the first sampling is sampled again between
    its two samples: a jump stays a spike there, a steep but continuous stretch (a stiff penalty) does not."""
    changed, jumps, words = 0, 0, []
    for (c0, d0, base, params), (c1, d1, _, _) in zip(before, after):
        for e, g in np.argwhere(c0 != c1):
            changed += 1
            try:
                spike, where, _ = _largest_spike(d0[e, g], d1[e, g], base[e, g], params[e], 0.0, 1.0)
                if spike is None:
                    continue
                again, _, largest = _largest_spike(d0[e, g], d1[e, g], base[e, g], params[e], *where)
            except NumericalError:
                continue
            span = float(np.abs(d1[e, g] - d0[e, g]).max()) * (where[1] - where[0])
            if again is not None:
                jumps += 1
                words.append(f"element {e} point {g}: a jump of {again:.3g} Pa near {where[0]:.4f} of the segment")
            else:
                words.append(f"element {e} point {g}: steep, not a jump: {spike:.3g} Pa over {span:.2g} m, "
                             f"no step above {largest:.3g} Pa sampled again")
    return changed, jumps, words


def report(r: float, rec: Recorder, converged: bool) -> None:
    print(f"\nfailed hold step at r = {r:.4g}; solved again: {'converged' if converged else 'failed again'}")
    print("  residuals: " + " ".join(f"{x:.1e}" for x in rec.residuals))
    print("  line searches (s, g(1)/g(0)): " + " ".join(
        f"{s:.2f} ({'-' if ratio is None else f'{ratio:.2f}'})" for s, ratio in rec.searches))
    for k in range(1, len(rec.states)):
        flat = [np.concatenate([grp[0].ravel() for grp in rec.states[i]]) for i in (k - 1, k)]
        moved = np.nonzero(flat[0] != flat[1])[0]
        pairs = collections.Counter((int(flat[0][i]), int(flat[1][i])) for i in moved)
        print(f"  evaluation {k}: {moved.size} points change region "
              + ", ".join(f"{a}->{b} {n}" for (a, b), n in sorted(pairs.items())))
    worst, bad, checked = tangent_check(rec.states)
    print(f"  tangent check: {checked} point states off the elastic branch, largest difference {worst:.2e}, "
          f"{bad} above {TANGENT_MISMATCH:g}")
    changed = jumps = 0
    for k in range(1, len(rec.states)):
        c, j, words = continuity_check(rec.states[k - 1], rec.states[k])
        changed, jumps = changed + c, jumps + j
        for w in words[:3]:
            print(f"  between evaluations {k - 1} and {k}, {w}")
    print(f"  continuity check: {changed} points changed region, {jumps} with a jump on the segment")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--failures", type=int, default=3, help="failed hold steps to study")
    ap.add_argument("--push-mm", type=float, default=4.0, help="the push, in 0.1 mm nominal steps")
    ap.add_argument("--iterations", type=int, default=30, help="Newton iterations of the second solve")
    args = ap.parse_args(argv)
    scene = example_module("eindhoven_walls").wall_scene("J4D")
    steps = int(round(args.push_mm / 0.1))
    scene["stages"][1]["loads"][0]["value"] = [f"{args.push_mm} mm", "0 mm"]
    scene["stages"][1]["steps"] = steps
    scene["stages"][1]["duration"] = steps / 40.0

    rec = Recorder()
    instrument(rec)
    hold_step = relaxation._step
    studied = []

    def studied_hold_step(solver, trial, f_ext, max_iterations):
        result = hold_step(solver, trial, f_ext, max_iterations)
        if max_iterations != relaxation.HOLD_MAX_ITERATIONS or result[0]:
            return result
        model = solver.model
        model.revert()
        rec.on, rec.states, rec.searches = True, [], []
        try:
            again = hold_step(solver, trial, f_ext, args.iterations)
        finally:
            rec.on = False
        model.revert()
        report(model.time_step, rec, bool(again[0]))
        studied.append(model.time_step)
        if len(studied) >= args.failures:
            raise Enough
        return result

    relaxation._step = studied_hold_step
    print(f"study_hold_failures: J4D pushed {args.push_mm} mm, {cpu_model()}, one thread", flush=True)
    t0 = time.perf_counter()
    try:
        masonrydam.run(scene, progress=False)
    except Enough:
        pass
    print(f"\n{len(studied)} failed hold step(s) studied in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
