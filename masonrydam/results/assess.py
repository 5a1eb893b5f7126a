"""Stability of a dam's joint lines: the quantities of the gravity method, from the joint tractions.

For each line of the assessed joint sets (the base, each lift; in 3D each monolith's base and lifts:
:class:`~masonrydam.assembly.joint_lines.JointLines`) and each recorded step, from the effective
tractions of the joint law (the pore pressure, ``joint_pore_pressure``, is not in them):

- ``normal_force`` N (N, compression positive): minus the sum of the effective normal tractions times
  the point weights (in 2D per model thickness): the W - U of the gravity method;
- ``shear_force`` |T| (N): magnitude of the resultant of the shear tractions;
- ``sliding_safety_factor`` (c A_c + N tan(phi)) / |T| with A_c the area of the points in compression
  whose bond is intact (a cracked or opened point has no cohesion, Tzamtzis & Asteris sec. 3.4): the shear-friction
  factor of USACE EM 1110-2-2200 (1995) sec. 4-4 and USBR Design of Small Dams (1987) sec. 5.11;
- ``resultant_position`` (m from the upstream end of the line): where the normal force acts, the
  centroid of the effective normal tractions (moment equilibrium of the gravity method);
- ``cracked_length_ratio``: area of open points over the line's area;
- ``heel_normal_stress``, ``toe_normal_stress`` (Pa, tension positive as ``joint_traction_normal``):
  mean effective normal traction of the points at the line's upstream and downstream ends;
- ``uplift_force`` (N): the resultant of the pore pressures on the line (zero without uplift).

Criteria printed by ``masonrydam assess`` (USACE EM 1110-2-2100, Stability Analysis of Concrete
Structures, 2005, table 3-2 and 3-4; FERC Engineering Guidelines ch. 3): sliding factor at least 1.5
(usual), 1.3 (unusual), 1.1 (extreme); resultant within the middle third of the line (usual: the
whole base in compression), the middle half (unusual: 75 % of it), the line (extreme).
"""
from __future__ import annotations

import csv
import json

import numpy as np

from ..errors import MasonrydamError
from ..materials.joint_laws import RESULT_OPEN
from .files import step_position

#: the section variables: name -> (units, long name)
SECTION_VARIABLES = {
    "normal_force": ("N", "resultant of the effective normal tractions on the joint line (compression positive; "
                          "W - U of the gravity method)"),
    "shear_force": ("N", "magnitude of the resultant of the shear tractions on the joint line"),
    "sliding_safety_factor": ("1", "shear-friction safety factor (c A_compressed + N tan(phi)) / |T| of the joint line"),
    "resultant_position": ("m", "position of the normal force resultant, measured from the upstream end of the line"),
    "cracked_length_ratio": ("1", "open (cracked) area of the joint line over its area"),
    "heel_normal_stress": ("Pa", "effective normal traction at the upstream end of the line (tension positive)"),
    "toe_normal_stress": ("Pa", "effective normal traction at the downstream end of the line (tension positive)"),
    "uplift_force": ("N", "resultant of the pore pressure (uplift) on the joint line"),
}

#: sliding safety factor required by load condition (USACE EM 1110-2-2100, 2005, table 3-2)
SLIDING_CRITERIA = {"usual": 1.5, "unusual": 1.3, "extreme": 1.1}


class SectionAssessment:
    """Section measures of the joint lines ``lines`` of ``model``.

    ``cohesion``, ``tan_phi``: (n_points,) from the joint parameters of each point's group."""

    def __init__(self, model, lines):
        self.model, self.lines = model, lines
        dim = model.dim
        self.dim = dim
        L = lines
        # (the Coulomb limit of each group's law, InterfaceGroup.friction_strength; per element, repeated per point)
        strength = [g.friction_strength() for g in L.groups]
        self.cohesion = L.gather([np.repeat(c[:, None], g.nip, axis=1) for g, (c, _) in zip(L.groups, strength)])
        self.tan_phi = L.gather([np.repeat(t[:, None], g.nip, axis=1) for g, (_, t) in zip(L.groups, strength)])
        # a "linear" joint carries cohesion 1e300 (and a law without a Coulomb limit inf): no sliding check means
        # anything there
        self.cohesion = np.where(self.cohesion > 1e200, np.inf, self.cohesion)
        scale = float(L.length.max()) if L.n_lines else 1.0
        # (n_lines,) m: points this close in s are one row; wider on a curved line, whose centre is fitted
        tol = np.where(L.curved, L.end_tolerance, 1e-6 * max(scale, 1.0))
        smin = np.full(L.n_lines, np.inf)
        smax = np.full(L.n_lines, -np.inf)
        np.minimum.at(smin, L.line, L.s)
        np.maximum.at(smax, L.line, L.s)
        self.heel = L.s <= smin[L.line] + tol[L.line]
        self.toe = L.s >= smax[L.line] - tol[L.line]
        # what does not change from step to step: the points' shear axes (n_points, dim-1, dim), the line
        # areas, their friction coefficient and the number of heel and toe points
        self.shear_axes = np.concatenate([g.frame[:, :, : dim - 1, :].reshape(-1, dim - 1, dim) for g in L.groups]) \
            if L.groups else np.zeros((0, dim - 1, dim))
        self.area = self._sum(L.weight)
        self.tan_phi_line = self._sum(self.tan_phi * L.weight) / np.maximum(self.area, 1e-300)
        self.n_heel = self._sum(self.heel.astype(float))
        self.n_toe = self._sum(self.toe.astype(float))
        #: the lines assessed: those closer to horizontal than vertical (JointLines.horizontal)
        self.keep = np.nonzero(L.horizontal)[0]
        self.names = [L.names[k] for k in self.keep]

    def _sum(self, values):
        return np.bincount(self.lines.line, weights=values, minlength=self.lines.n_lines)

    def measures(self, uplift_force: np.ndarray | None = None) -> dict:
        """The section variables of the assessed lines (each (len(keep),)) at the joints' committed state
        (the last converged step). uplift_force: (n_lines,) N, the resultant pore pressure on every
        line, or None."""
        L, dim = self.lines, self.dim
        t = L.gather([g.traction.reshape(g.n_elem, g.nip, dim) for g in L.groups]) if L.n_points else np.zeros(0)
        t = t.reshape(-1, dim)
        state = L.gather([g.result_states() for g in L.groups])
        broken = L.gather([g.bond_broken() for g in L.groups])
        w = L.weight
        tn = t[:, -1]
        N = -self._sum(tn * w)
        # shear resultant in global components: sum over the points of the shear tractions along their axes
        shear = np.einsum("pj,pjk->pk", t[:, :-1], self.shear_axes) * w[:, None]
        T = np.sqrt(sum(self._sum(shear[:, k]) ** 2 for k in range(dim)))
        compressed = (tn < 0) & ~broken & (state != RESULT_OPEN)
        cA = self._sum(np.where(compressed, self.cohesion * w, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            resisting = cA + np.maximum(N, 0.0) * self.tan_phi_line
            sf = np.where(T > 0, resisting / T, np.inf)
            pos = np.where(N > 0, self._sum(-tn * w * L.s) / N, np.nan)
            heel = self._sum(np.where(self.heel, tn, 0.0)) / self.n_heel
            toe = self._sum(np.where(self.toe, tn, 0.0)) / self.n_toe
        cracked = self._sum(np.where(state == RESULT_OPEN, w, 0.0)) / np.maximum(self.area, 1e-300)
        uplift = np.zeros(L.n_lines) if uplift_force is None else uplift_force
        out = {"normal_force": N, "shear_force": T, "sliding_safety_factor": sf, "resultant_position": pos,
               "cracked_length_ratio": cracked, "heel_normal_stress": heel, "toe_normal_stress": toe,
               "uplift_force": uplift}
        return {k: v[self.keep] for k, v in out.items()}


def criteria_flags(ds_step, condition: str = "usual") -> dict:
    """Per section, the criteria a step's values fail (list of sentences), for ``masonrydam assess``:
    the messages of :func:`criteria_checks`, in the order of the section variables."""
    return {name: list(checks.values()) for name, checks in criteria_checks(ds_step, condition).items()}


#: resultant position required by load condition, as the part of the line it must lie in: (from, to) as
#: fractions of the length from the upstream end (USACE EM 1110-2-2100, 2005, table 3-2 "resultant
#: location at base": middle third for usual, middle half for unusual, within the base for extreme)
RESULTANT_CRITERIA = {"usual": (1.0 / 3.0, 2.0 / 3.0), "unusual": (0.25, 0.75), "extreme": (0.0, 1.0)}

#: largest open (cracked) part of the line by load condition, the same table read as "part of the base in
#: compression": 100 % (usual), 75 % (unusual), any (extreme: only the resultant within the base)
CRACKED_CRITERIA = {"usual": 0.0, "unusual": 0.25, "extreme": 1.0}

#: the load conditions, in the order of the command line's choices
CONDITIONS = tuple(SLIDING_CRITERIA)

#: relative tolerance of the geometric criteria (resultant bounds, cracked ratio): a resultant exactly at
#: L/3 is in the middle third
CRITERIA_RTOL = 1e-9


def criteria_text(condition: str = "usual") -> str:
    """One line naming the criteria of ``condition`` (for the header of ``masonrydam assess``)."""
    _check_condition(condition)
    lo, hi = RESULTANT_CRITERIA[condition]
    where = {"usual": "in the middle third", "unusual": "in the middle half",
             "extreme": "within the line"}[condition]
    comp = {"usual": "whole line in compression (no open part, heel and toe not in tension)",
            "unusual": "at least 75 % of the line in compression",
            "extreme": "no compression requirement"}[condition]
    return (f"{condition} load condition (USACE EM 1110-2-2100, 2005, tables 3-2 and 3-4): sliding factor >= "
            f"{SLIDING_CRITERIA[condition]:g}, resultant {where} ({lo:.3g} L to {hi:.3g} L), {comp}")


def _check_condition(condition):
    if condition not in SLIDING_CRITERIA:
        raise MasonrydamError(f"load condition must be one of {list(CONDITIONS)}, got {condition!r}")


def criteria_checks(ds_step, condition: str = "usual") -> dict:
    """Per section (name -> dict), the section variables of one step (``ds_step``: the result dataset at
    one step, e.g. ``ds.isel(step=-1)``) that fail the criteria of ``condition`` (``"usual"``,
    ``"unusual"``, ``"extreme"``), each with a sentence saying why (variable name -> text). Criteria
    (USACE EM 1110-2-2100, Stability Analysis of Concrete Structures, 2005, tables 3-2 and 3-4; FERC
    Engineering Guidelines ch. 3):

    - ``sliding_safety_factor`` at least :data:`SLIDING_CRITERIA` (1.5, 1.3, 1.1); a NaN fails;
    - ``resultant_position`` (m from the upstream end) within the part of the line of
      :data:`RESULTANT_CRITERIA` (middle third, middle half, the line); no resultant (N <= 0: the
      line carries no compression) fails;
    - ``cracked_length_ratio`` at most :data:`CRACKED_CRITERIA` (0, 0.25, 1): the part of the line in
      compression of the same table (100 %, 75 %, any);
    - ``heel_normal_stress``, ``toe_normal_stress`` (Pa, tension positive): not in tension for the usual
      condition (whole line in compression).

    Sections whose values are all within the criteria have an empty dict."""
    _check_condition(condition)
    need = SLIDING_CRITERIA[condition]
    lo, hi = RESULTANT_CRITERIA[condition]
    crack_max = CRACKED_CRITERIA[condition]
    out = {}
    for i, name in enumerate(ds_step["section"].values.tolist()):
        fails = {}
        sf = float(ds_step["sliding_safety_factor"].values[i])
        if np.isnan(sf):
            fails["sliding_safety_factor"] = f"no sliding factor (nan; {condition} needs >= {need:g})"
        elif sf < need:
            fails["sliding_safety_factor"] = f"sliding factor {sf:.3f} < {need:g} ({condition})"
        pos = float(ds_step["resultant_position"].values[i])
        length = float(ds_step["section_length"].values[i])
        tol = CRITERIA_RTOL * max(length, 1.0)
        if not np.isfinite(pos):
            fails["resultant_position"] = "no resultant: the line carries no compression (N <= 0)"
        elif pos < -tol or pos > length + tol:
            fails["resultant_position"] = (f"resultant outside the line ({pos:.3f} m from the upstream end, "
                                           f"length {length:.3f} m)")
        elif pos < lo * length - tol or pos > hi * length + tol:
            part = {"usual": "middle third", "unusual": "middle half"}[condition]
            fails["resultant_position"] = (f"resultant at {pos / length:.3f} L, outside the {part} "
                                           f"({lo:.3g} L to {hi:.3g} L, {condition})")
        cr = float(ds_step["cracked_length_ratio"].values[i])
        if cr > crack_max + CRITERIA_RTOL:
            need_c = "the whole line" if crack_max == 0 else f"{100 * (1 - crack_max):g} % of the line"
            fails["cracked_length_ratio"] = (f"{100 * cr:.1f} % of the line open ({condition}: {need_c} "
                                             "in compression)")
        if condition == "usual":
            for var, end in (("heel_normal_stress", "heel"), ("toe_normal_stress", "toe")):
                s = float(ds_step[var].values[i])
                if s > 0:
                    fails[var] = f"{end} in tension ({s / 1e6:.3f} MPa; usual: whole line in compression)"
        out[str(name)] = fails
    return out


def _no_sections_error(ds, label):
    """The error for a result without section variables (a scene without a reservoir, or whose reservoir
    has no joint line to assess)."""
    try:
        reservoir = json.loads(ds.attrs.get("scene", "{}")).get("reservoir")
    except (TypeError, ValueError):
        reservoir = None
    if reservoir:
        why = ("the scene's [reservoir] has no uplift joint set and the model no joint set closer to horizontal "
               "than vertical (base or lift joints) to assess")
    else:
        why = ("the scene had no [reservoir] section (the stability of the base and lift joints is recorded only "
               "for scenes with a reservoir)")
    return MasonrydamError(f"'{label}': this result has no stability sections: {why}")


def select_step(ds, step: int | None, label: str = "result", option: str = "--step") -> int:
    """The position along ``step`` of the step ``step`` of a result with sections: a value of the file's
    ``step`` coordinate (0 or more), or a negative index from the end (-1: the last step, the default
    for None). Errors (:class:`~masonrydam.errors.MasonrydamError`) for a result without sections or
    steps, or a step that is not in it, naming ``option``."""
    if "section" not in ds.dims or "sliding_safety_factor" not in ds.variables:
        raise _no_sections_error(ds, label)
    return step_position(ds, step, option, f"'{label}'")


def stage_name(ds, i: int) -> str:
    """Name of the stage of the step at position ``i`` (attribute ``stage_names`` of ``stage``)."""
    if "stage" not in ds.variables:
        return "?"
    k = int(ds["stage"].values[i])
    try:
        names = json.loads(ds["stage"].attrs.get("stage_names", "[]"))
        return str(names[k])
    except (TypeError, ValueError, IndexError):
        return str(k)


def step_time(ds, i: int) -> float:
    """Time (s) of the step at position ``i``, NaN for a static step or a result without time."""
    if "time" not in ds.variables:
        return float("nan")
    return float(ds["time"].values[i])


def _f(v, fmt):
    return fmt.format(v) if np.isfinite(v) else ("inf" if v == np.inf else "-inf" if v == -np.inf else "nan")


def _sf_text(v):
    return _f(v, "{:.3f}") if not np.isfinite(v) or abs(v) < 1000 else f"{v:.3g}"


def force_unit(values) -> tuple[str, float]:
    """The unit to print forces of magnitude ``values`` (N) in: ("MN", 1e6) from 1 MN, else ("kN", 1e3)."""
    v = np.abs(np.asarray(values, dtype=float))
    v = v[np.isfinite(v)]
    return ("MN", 1e6) if len(v) and v.max() >= 1e6 else ("kN", 1e3)


def _columns(widths_rows, sep="  "):
    """Rows of cells (text, failed) as aligned lines: names left, values right with a '!' (failed) or a
    space after them."""
    rows = widths_rows
    widths = [max(len(r[k][0]) for r in rows) for k in range(len(rows[0]))]
    lines = []
    for r in rows:
        cells = []
        for k, (text, fail) in enumerate(r):
            if k == 0:
                cells.append(text.ljust(widths[k]))
            else:
                cells.append(text.rjust(widths[k]) + ("!" if fail else " "))
        lines.append(sep.join(cells).rstrip())
    return lines


def assessment_report(ds, i: int, condition: str = "usual", label: str = "result") -> tuple[list, bool]:
    """The text of ``masonrydam assess`` for the step at position ``i`` of result ``ds``: header lines
    (scene, step, stage, load factor, water levels, time of dynamic steps; criteria), the table (one row
    per section: length L (m), normal force N and shear force |T| (kN or MN, whichever reads better),
    sliding factor, resultant position (m from the upstream end and over L), cracked ratio (%), heel
    and toe normal stress (MPa, tension positive), uplift U (unit of N); '!' after a value that fails
    :func:`criteria_checks`), the failures per section and a closing line. Returns (lines, all_ok)."""
    _check_condition(condition)
    st = ds.isel(step=i)
    checks = criteria_checks(st, condition)
    names = [str(n) for n in st["section"].values.tolist()]
    N, T, U = (np.asarray(st[v].values, float) for v in ("normal_force", "shear_force", "uplift_force"))
    unit, scale = force_unit(np.concatenate([N, T, U]))
    dim = int(ds.attrs.get("dimension", 2))
    thick = _thickness(ds)
    lines = [f"scene '{ds.attrs.get('scene_name', '?')}' ({label}), step {int(ds['step'].values[i])} "
             f"(steps {int(ds['step'].values[0])} to {int(ds['step'].values[-1])}): stage '{stage_name(ds, i)}', " + _levels(ds, i)]
    if dim == 2:
        lines.append(f"2D: forces for the model thickness ({thick:g} m); N compression positive, stresses "
                     "tension positive" if thick is not None else "2D: forces for the model thickness")
    else:
        lines.append("3D: forces on the whole joint line; N compression positive, stresses tension positive")
    lines.append("criteria: " + criteria_text(condition) + "; '!' marks a value that fails")
    lines.append("")
    head = ["section", "L [m]", f"N [{unit}]", f"|T| [{unit}]", "SF [1]", "x_R [m]", "x_R/L", "cracked [%]",
            "heel [MPa]", "toe [MPa]", f"U [{unit}]"]
    rows = [[(h, False) for h in head]]
    for k, name in enumerate(names):
        fails = checks[name]
        L = float(st["section_length"].values[k])
        pos = float(st["resultant_position"].values[k])
        rpos = "resultant_position" in fails
        rows.append([
            (name, False),
            (_f(L, "{:.3f}"), False),
            (_f(N[k] / scale, "{:.3f}"), False),
            (_f(T[k] / scale, "{:.3f}"), False),
            (_sf_text(float(st["sliding_safety_factor"].values[k])), "sliding_safety_factor" in fails),
            (_f(pos, "{:.3f}"), rpos),
            (_f(pos / L if L > 0 else np.nan, "{:.3f}"), rpos),
            (_f(100 * float(st["cracked_length_ratio"].values[k]), "{:.1f}"), "cracked_length_ratio" in fails),
            (_f(float(st["heel_normal_stress"].values[k]) / 1e6, "{:.3f}"), "heel_normal_stress" in fails),
            (_f(float(st["toe_normal_stress"].values[k]) / 1e6, "{:.3f}"), "toe_normal_stress" in fails),
            (_f(U[k] / scale, "{:.3f}"), False),
        ])
    lines += _columns(rows)
    failing = [n for n in names if checks[n]]
    if failing:
        lines.append("")
        for n in failing:
            lines.append(f"{n}: " + "; ".join(checks[n].values()))
    lines.append("")
    if failing:
        lines.append(f"{len(failing)} of {len(names)} sections fail the {condition} criteria")
    else:
        lines.append(f"all {len(names)} sections meet the {condition} criteria")
    return lines, not failing


def _thickness(ds):
    try:
        return float(json.loads(ds.attrs.get("scene", "{}"))["model"]["thickness"])
    except (TypeError, ValueError, KeyError):
        return None


def _levels(ds, i):
    parts = []
    if "load_factor" in ds.variables:
        parts.append(f"load factor {float(ds['load_factor'].values[i]):g}")
    for var, what in (("reservoir_level", "reservoir level"), ("tailwater_level", "tailwater level")):
        if var in ds.variables:
            v = float(ds[var].values[i])
            parts.append(f"{what} {v:g} m" if np.isfinite(v) else f"no {what.split()[0]}")
    t = step_time(ds, i)
    if np.isfinite(t):
        parts.append(f"time {t:.4g} s")
    return ", ".join(parts)


def assessment_columns(dim: int) -> list:
    """The CSV columns of :func:`write_assessment_csv`: (header text, source) with units in brackets."""
    cols = [("section", None), ("joint_set", None), ("step", None), ("section_length [m]", "section_length")]
    cols += [(f"section_{c} [m]", f"section_{c}") for c in "xyz"[:dim]]
    cols += [(f"{name} [{units}]", name) for name, (units, _) in SECTION_VARIABLES.items()]
    cols.append(("resultant_position_ratio [1]", None))
    return cols


def write_assessment_csv(ds, i: int, path, condition: str = "usual") -> None:
    """The table of the step at position ``i`` to the CSV file ``path``: one row per section, SI units
    (N, m, Pa, ratios as 1) at full precision (Python's shortest repr that round-trips), a header row
    naming each column and its units, the flags of :func:`criteria_flags` (``"; "``-joined, empty
    when none) in the last column ``flags (CONDITION)``."""
    st = ds.isel(step=i)
    dim = 3 if "section_z" in ds.variables else 2
    cols = assessment_columns(dim)
    flags = criteria_flags(st, condition)
    step = int(ds["step"].values[i])
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow([c for c, _ in cols] + [f"flags ({condition})"])
        for k, name in enumerate(str(n) for n in st["section"].values.tolist()):
            row = []
            for head, src in cols:
                if head == "section":
                    row.append(name)
                elif head == "joint_set":
                    row.append(str(st["section_joint_set"].values[k]) if "section_joint_set" in st else "")
                elif head == "step":
                    row.append(step)
                elif src is None:  # resultant_position_ratio
                    L = float(st["section_length"].values[k])
                    row.append(repr(float(st["resultant_position"].values[k]) / L) if L > 0 else "nan")
                else:
                    row.append(repr(float(st[src].values[k])))
            row.append("; ".join(flags[name]))
            w.writerow(row)


def extreme_over_steps(ds, condition: str = "usual") -> list:
    """Per section, over all steps of result ``ds``: the lowest sliding factor and the position of its step,
    the largest cracked ratio and the position of its step (the first where there are ties), and whether
    that lowest factor fails :data:`SLIDING_CRITERIA` of ``condition``. A list of dicts (name, sf_min,
    sf_step, sf_fails, cracked_max, cracked_step); NaN values are left out (all NaN: NaN, step None)."""
    _check_condition(condition)
    need = SLIDING_CRITERIA[condition]
    sf = np.asarray(ds["sliding_safety_factor"].values, float)
    cr = np.asarray(ds["cracked_length_ratio"].values, float)
    out = []
    for k, name in enumerate(str(n) for n in ds["section"].values.tolist()):
        row = {"name": name}
        col = sf[:, k]
        if np.isnan(col).all():
            row.update(sf_min=np.nan, sf_step=None, sf_fails=True)
        else:
            j = int(np.nanargmin(col))
            row.update(sf_min=float(col[j]), sf_step=j, sf_fails=bool(col[j] < need))
        col = cr[:, k]
        if np.isnan(col).all():
            row.update(cracked_max=np.nan, cracked_step=None)
        else:
            j = int(np.nanargmax(col))
            row.update(cracked_max=float(col[j]), cracked_step=j)
        out.append(row)
    return out


def over_steps_report(ds, condition: str = "usual") -> list:
    """Lines of ``masonrydam assess --all-steps``: per section, the lowest sliding factor over all steps
    with its step (stage, time of a dynamic step; '!' when it is below :data:`SLIDING_CRITERIA`), and
    the largest cracked ratio (%) with its step."""
    dynamic = "time" in ds.variables and np.isfinite(np.asarray(ds["time"].values, float)).any()
    steps = np.asarray(ds["step"].values).astype(int)

    def where(j):
        if j is None:
            return "-"
        t = step_time(ds, j)
        return f"{steps[j]} ({stage_name(ds, j)}" + (f", t = {t:.4g} s)" if dynamic and np.isfinite(t) else ")")

    rows = [[("section", False), ("min SF [1]", False), ("at step", False), ("max cracked [%]", False),
             ("at step", False)]]
    for r in extreme_over_steps(ds, condition):
        rows.append([(r["name"], False), (_sf_text(r["sf_min"]), r["sf_fails"]), (where(r["sf_step"]), False),
                     (_f(100 * r["cracked_max"], "{:.1f}"), False), (where(r["cracked_step"]), False)])
    return [f"over all {len(steps)} steps ({condition}: '!' marks a sliding factor below "
            f"{SLIDING_CRITERIA[condition]:g}):"] + _columns(rows)
