"""What a masonry wall's joints do at one step of a result, in numbers and in the words of the tests: which joints
are open, slip or crush, where, and the failure mechanisms they make (diagonal stair-case cracking, toe crushing,
sliding), as Raijmakers & Vermeltfoort (1992) and Lourenço & Rots (1997) describe the Eindhoven walls.

Read from a result file's joint variables (2D): ``joint_opening`` (m), ``joint_plastic_slip`` (m), ``joint_state``
(0 stick, 1 slip, 2 open, 3 crush), ``joint_x``, ``joint_y`` (m) and ``joint_set`` with its ``set_names``.

The mechanisms are named from the open, slipping and crushing points, by these rules (thresholds below):

- **diagonal cracking**: open points (opening above :data:`OPEN_AT`) in the head joints or the units' cracks, over
  at least :data:`DIAGONAL_HEIGHT_FRACTION` of the wall's height, whose centre of opening moves along the wall
  as it goes up (a stair-case, not one vertical crack): the open points' x and y correlate (``|r| >=``
  :data:`DIAGONAL_CORRELATION`);
- **toe crushing**: at least :data:`TOE_POINTS` bed-joint points on the compression cap (state 3) in a corner of
  the wall (within :data:`TOE_HEIGHT_FRACTION` of its height from the bottom or the top and
  :data:`TOE_LENGTH_FRACTION` of its length from either end), and at least :data:`TOE_SHARE` of all the cap points
  (a corner that crushes, not a corner of a band); where the cap points spread along the compressed strut instead,
  the band is named as such. The cap is where compression hardens; its softening is not in the result;
- **sliding**: a row of bed joints whose plastic slip exceeds :data:`SLIDING_SLIP` over at least
  :data:`SLIDING_ROW_FRACTION` of its points.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

#: a joint point is open where its opening exceeds this (m): 10 um, a tenth of the mortar joints' softening length
#: GfI / ft = 0.018 N/mm / 0.25 MPa = 72 um
OPEN_AT = 10e-6
#: the open points of diagonal cracking span at least this fraction of the wall's height
DIAGONAL_HEIGHT_FRACTION = 0.5
#: and their positions correlate at least this much (a line across the wall, not a vertical crack)
DIAGONAL_CORRELATION = 0.5
#: toe crushing: this many cap points in a corner region of these fractions of the height and the length
TOE_POINTS = 3
TOE_HEIGHT_FRACTION = 0.2
TOE_LENGTH_FRACTION = 0.25
TOE_SHARE = 0.25
#: a bed-joint row slides where its points' plastic slip exceeds this (m) ...
SLIDING_SLIP = 0.1e-3
#: ... over at least this fraction of its points
SLIDING_ROW_FRACTION = 0.8
#: the joint sets of a masonry wall from its generator (generators/masonry_wall_2d)
BED, HEAD, UNIT = "bed_joints", "head_joints", "unit_cracks"


@dataclass
class WallCracks:
    """The joints of a wall at one step: counts per set (``open``, ``slipping``, ``crushing``: number of points),
    the heights of the open head joints and unit cracks (m, min and max), the rows that slide (m, their heights),
    where the crushing is (m, x and y of its points' centre) and the mechanisms' names."""

    step: int
    counts: dict = field(default_factory=dict)
    open_heights: tuple | None = None
    sliding_rows: list = field(default_factory=list)
    crushing_at: tuple | None = None
    mechanisms: list = field(default_factory=list)

    def words(self) -> str:
        """One line: the mechanisms, then the counts."""
        what = ", ".join(self.mechanisms) if self.mechanisms else "no failure mechanism"
        counts = "; ".join(f"{name}: {c['open']} open, {c['slipping']} slipping, {c['crushing']} crushing"
                           for name, c in self.counts.items())
        return f"{what} ({counts})"


def wall_cracks(ds, step: int = -1) -> WallCracks:
    """The joints of the 2D wall result ``ds`` at ``step`` (index along ``step``; -1 the last): a
    :class:`WallCracks`. Raises ValueError naming what is missing where the result has no joint output or not the
    joint sets of a masonry wall (bed_joints and head_joints, optionally unit_cracks)."""
    for name in ("joint_opening", "joint_plastic_slip", "joint_state", "joint_x", "joint_y", "joint_set"):
        if name not in ds:
            raise ValueError(f"the result has no '{name}': write the joints ([output] joints = \"all\")")
    names = json.loads(ds.joint_set.attrs["set_names"])
    if BED not in names or HEAD not in names:
        raise ValueError(f"the result's joint sets {names} are not those of a masonry wall ({BED}, {HEAD})")
    n_steps = ds.sizes["step"]
    k = step if step >= 0 else n_steps + step
    if not 0 <= k < n_steps:
        raise ValueError(f"step {step} is not in the result (0 to {n_steps - 1})")
    which = ds.joint_set.values
    x, y = ds.joint_x.values, ds.joint_y.values
    opening = ds.joint_opening.values[k]
    slip = np.abs(ds.joint_plastic_slip.values[k].reshape(len(x), -1)).max(axis=1)
    state = ds.joint_state.values[k]
    out = WallCracks(step=k)
    for name in (BED, HEAD, UNIT):
        if name not in names:
            continue
        here = which == names.index(name)
        out.counts[name] = {"open": int((opening[here] > OPEN_AT).sum()), "slipping": int((state[here] == 1).sum()),
                            "crushing": int((state[here] == 3).sum())}
    bed = which == names.index(BED)
    vertical = np.isin(which, [names.index(n) for n in (HEAD, UNIT) if n in names])
    masonry = bed | vertical
    wall_bottom, wall_top = y[masonry].min(), y[masonry].max()
    wall_left, wall_right = x[masonry].min(), x[masonry].max()
    opened = vertical & (opening > OPEN_AT)
    if opened.any():
        out.open_heights = (float(y[opened].min()), float(y[opened].max()))
        span = (y[opened].max() - y[opened].min()) / max(wall_top - wall_bottom, 1e-30)
        r = np.corrcoef(x[opened], y[opened])[0, 1] if opened.sum() > 2 and np.ptp(x[opened]) > 0 else 0.0
        if span >= DIAGONAL_HEIGHT_FRACTION and abs(r) >= DIAGONAL_CORRELATION:
            out.mechanisms.append(f"diagonal stair-case cracking (head joints and units open over "
                                  f"{span:.0%} of the height)")
    crushing = bed & (state == 3)
    if crushing.any():
        out.crushing_at = (float(x[crushing].mean()), float(y[crushing].mean()))
        height, length = wall_top - wall_bottom, wall_right - wall_left
        near_y = np.minimum(y - wall_bottom, wall_top - y) <= TOE_HEIGHT_FRACTION * height
        toes = []
        for x_end in (wall_left, wall_right):
            toe = crushing & near_y & (np.abs(x - x_end) <= TOE_LENGTH_FRACTION * length)
            if toe.sum() >= max(TOE_POINTS, TOE_SHARE * crushing.sum()):
                corner = ("bottom" if y[toe].mean() < 0.5 * (wall_bottom + wall_top) else "top") + " " + \
                         ("left" if x_end == wall_left else "right")
                toes.append(f"toe crushing at the {corner} corner ({int(toe.sum())} bed-joint points on the cap)")
        if not toes and crushing.sum() >= TOE_POINTS:
            toes.append(f"a band of bed joints on the compression cap ({int(crushing.sum())} points, centred at "
                        f"x = {out.crushing_at[0]:.2f} m, y = {out.crushing_at[1]:.2f} m)")
        out.mechanisms.extend(toes)
    rows = np.round(y[bed], 6)
    for row in np.unique(rows):
        on_row = slip[bed][rows == row]
        if (on_row > SLIDING_SLIP).mean() >= SLIDING_ROW_FRACTION:
            out.sliding_rows.append(float(row))
    if out.sliding_rows:
        out.mechanisms.append("sliding along the bed joint" + ("s" if len(out.sliding_rows) > 1 else "")
                              + " at y = " + ", ".join(f"{r:.3f}" for r in out.sliding_rows) + " m")
    return out
