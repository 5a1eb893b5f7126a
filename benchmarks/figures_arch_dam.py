"""Figures of docs/arch_dams.md from a result of examples/arch_dam_earthquake.toml.

    masonrydam run examples/arch_dam_earthquake.toml -o arch_eq.nc
    python benchmarks/figures_arch_dam.py arch_eq.nc

Writes, in docs/figures/:

* ``arch_dam_crest.png``: the displacement of the crown's crest (the crest nodes within 2 m of x = 0, mean)
  along the stream (y) and across the valley (x) in time, relative to the static state, with the ground
  accelerations;
* ``arch_dam_contraction_joints.png``: the opening of each contraction joint in the top lift (the largest over
  its points) in time, the joints ordered along the crest (by x);
* ``arch_dam_joint_stresses.png``: the arch stress (mean normal traction of each contraction joint of the top
  lift) in time, and the cantilever stress (normal tractions of the lift joints within ``--crown`` m of x = 0)
  over the height after the reservoir and its range over the shaking;

and prints the numbers the page quotes. Reads the file only: no analysis is run here.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from figures_dam_3d import plot_crest, stage_steps  # noqa: E402  (benchmarks/ is sys.path[0] when run as a script)
from masonrydam.results.files import open_result  # noqa: E402

FIG = ROOT / "docs" / "figures"
G = 9.80665


def contraction_joints(ds, lift):
    """Point indices of each contraction joint in the top lift (the points within ``lift`` m of the highest
    one), grouped by the joint's plane: a radial joint is a vertical plane whose normal's direction (mod
    180 deg) is its own. Returns (mean x of each joint, list of point-index arrays), ordered by x."""
    set_names = json.loads(ds.joint_set.attrs["set_names"])
    cj = ds.joint_set.values == set_names.index("contraction_joints")
    zj = ds.joint_z.values
    sel = np.nonzero(cj & (zj > zj[cj].max() - lift))[0]
    ang = np.degrees(np.arctan2(ds.joint_normal_y.values[sel], ds.joint_normal_x.values[sel])) % 180.0
    key = np.round(ang, 1)
    groups = [sel[key == k] for k in np.unique(key)]
    xs = np.array([ds.joint_x.values[g].mean() for g in groups])
    order = np.argsort(xs)
    return xs[order], [groups[i] for i in order]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("result", help="result file of examples/arch_dam_earthquake.toml")
    ap.add_argument("--stage", default="el_centro")
    ap.add_argument("--lift", type=float, default=10.0, help="lift spacing (m): the top lift's height")
    ap.add_argument("--crown", type=float, default=10.0, help="half-width (m) of the crown cantilever's band in x")
    ap.add_argument("--out", default=str(FIG))
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    ds = open_result(a.result)
    dyn = stage_steps(ds, a.stage)
    t = ds.time.values[dyn]
    t = t - t[0]

    # -- crown crest -----------------------------------------------------------------------------------
    x, z = ds.x.values, ds.z.values
    crown = np.nonzero((np.abs(x) < 2.0) & (z > z.max() - 1e-3))[0]
    u = ds.displacement.values[dyn][:, crown, :]  # (step, node, component)
    ux, uy = u[:, :, 0].mean(axis=1), u[:, :, 1].mean(axis=1)
    ux, uy = ux - ux[0], uy - uy[0]
    plot_crest(ds, dyn, t, ux, uy, "across the valley (x)", "crown crest displacement (mm)", out / "arch_dam_crest.png")
    k = int(np.argmax(np.abs(uy)))
    print(f"crown crest: peak {1e3 * abs(uy[k]):.2f} mm along the stream at t = {t[k]:.2f} s, "
          f"{1e3 * np.abs(ux).max():.2f} mm across the valley; at the end {1e3 * uy[-1]:.2f} mm / {1e3 * ux[-1]:.2f} mm")

    # -- contraction joints in the top lift -------------------------------------------------------------
    xs, groups = contraction_joints(ds, a.lift)
    opening = ds.joint_opening.values[dyn]
    per_joint = np.stack([np.nanmax(opening[:, g], axis=1) for g in groups], axis=1)  # (step, joint)
    fig, ax = plt.subplots(figsize=(8, 4))
    im = ax.pcolormesh(t, np.arange(len(xs)), 1e3 * np.clip(per_joint, 0, None).T, shading="nearest", cmap="magma_r")
    ax.set_yticks(np.arange(len(xs)), [f"{v:.0f}" for v in xs], fontsize=7)
    fig.colorbar(im, ax=ax, label="largest opening in the top lift (mm)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("contraction joint: x at the crest (m)")
    fig.tight_layout()
    fig.savefig(out / "arch_dam_contraction_joints.png", dpi=130)
    k = np.unravel_index(np.nanargmax(per_joint), per_joint.shape)
    static = ds.joint_opening.values[dyn[0]]
    print(f"contraction joints (top lift): largest opening {1e3 * per_joint[k]:.2f} mm at x = {xs[k[1]]:.1f} m, "
          f"t = {t[k[0]]:.2f} s; at the start of the shaking {1e3 * max(np.nanmax(static[g]) for g in groups):.3f} mm; "
          f"open at the end: {int((per_joint[-1] > 1e-5).sum())} of {len(xs)} joints (> 0.01 mm)")
    # -- arch and cantilever stresses, from the joints they cross ---------------------------------------
    # the radial contraction joints carry the arch's horizontal thrust and the lift joints the cantilevers'
    # vertical force: their normal tractions (Pa, tension positive) are the arch and cantilever stresses
    tn = ds.joint_traction_normal.values[dyn]  # (step, point)
    arch = np.stack([tn[:, g].mean(axis=1) for g in groups], axis=1)  # (step, joint): the top lift's mean
    set_names = json.loads(ds.joint_set.attrs["set_names"])
    lj = np.nonzero((ds.joint_set.values == set_names.index("lift_joints")) & (np.abs(ds.joint_x.values) < a.crown))[0]
    zl = np.round(ds.joint_z.values[lj], 3)
    levels = np.unique(zl)
    rows = [lj[zl == z] for z in levels]
    static = np.array([tn[0, r].min() for r in rows]), np.array([tn[0, r].max() for r in rows])
    lo = np.array([tn[:, r].min() for r in rows])
    hi = np.array([tn[:, r].max() for r in rows])
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.2), gridspec_kw={"width_ratios": [1.6, 1]})
    v = np.abs(arch).max() / 1e6
    im = ax1.pcolormesh(t, np.arange(len(xs)), arch.T / 1e6, shading="nearest", cmap="RdBu_r", vmin=-v, vmax=v)
    ax1.set_yticks(np.arange(len(xs)), [f"{x:.0f}" for x in xs], fontsize=7)
    fig.colorbar(im, ax=ax1, label="arch stress: mean normal traction (MPa, tension +)")
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("contraction joint, top lift: x (m)")
    ax2.fill_betweenx(levels, lo / 1e6, hi / 1e6, color="0.85", label="range over the shaking")
    ax2.plot(static[0] / 1e6, levels, "b-", lw=1, label="after the reservoir: least")
    ax2.plot(static[1] / 1e6, levels, "r-", lw=1, label="after the reservoir: largest")
    ax2.set_xlabel("cantilever stress: lift-joint normal traction (MPa)")
    ax2.set_ylabel("z (m)")
    ax2.legend(loc="lower left", fontsize=7)
    ax2.grid(alpha=0.3)
    ax2.set_title(f"crown cantilever (|x| < {a.crown:g} m)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "arch_dam_joint_stresses.png", dpi=130)
    plt.close(fig)
    print(f"arch stress (top lift, mean normal traction of each contraction joint): after the reservoir "
          f"{arch[0].min() / 1e6:.2f} to {arch[0].max() / 1e6:.2f} MPa, over the shaking {arch.min() / 1e6:.2f} to "
          f"{arch.max() / 1e6:.2f} MPa; cantilever (crown, lift joints): after the reservoir {static[0].min() / 1e6:.2f} "
          f"to {static[1].max() / 1e6:.2f} MPa, over the shaking {lo.min() / 1e6:.2f} to {hi.max() / 1e6:.2f} MPa")
    for key in ("energy_error_relative", "dynamic_dt_smallest"):
        if key in ds.attrs:
            print(f"{key}: {ds.attrs[key]}")


if __name__ == "__main__":
    main()
