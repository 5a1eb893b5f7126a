"""Figures of docs/dam_3d.md from a result of examples/dam_3d_earthquake.toml.

    masonrydam run examples/dam_3d_earthquake.toml -o dam3d_eq.nc       # about 10 minutes
    python benchmarks/figures_dam_3d.py dam3d_eq.nc

Writes, in docs/figures/:

* ``dam_3d_crest.png``: the crest's mean displacement along the stream (y) and along the axis (x) in time, with
  the ground accelerations;
* ``dam_3d_contraction_joints.png``: the opening of each contraction joint in the top lift (the largest over its
  points), along the crest (x) and in time;
* ``dam_3d_base_sliding.png``: the permanent slip of each monolith's base joint (mean over its points, along the
  stream) in time;
* ``dam_3d_sliding_factors.png``: the sliding factor of every joint line (each monolith's base and lifts) at the
  end of the reservoir stage and after the shaking;

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

from masonrydam.results.files import open_result  # noqa: E402

FIG = ROOT / "docs" / "figures"
G = 9.80665


def stage_steps(ds, name):
    names = json.loads(ds.stage.attrs["stage_names"])
    return np.nonzero(ds.stage.values == names.index(name))[0]


def plot_crest(ds, dyn, t, ux, uy, x_label, ylabel, path):
    """Crest displacements ``ux``, ``uy`` (step,) m relative to the static state against ``t`` (step,) s, over the
    ground accelerations of the steps ``dyn``; written to ``path`` (also used by figures_arch_dam.py)."""
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    ax1.plot(t, 1e3 * uy, lw=0.8, label="along the stream (y)")
    ax1.plot(t, 1e3 * ux, lw=0.8, label=x_label)
    ax1.set_ylabel(f"{ylabel}\nrelative to the static state")
    ax1.legend(loc="upper right", fontsize=8)
    ax1.grid(alpha=0.3)
    if "ground_acceleration" in ds:
        ag = ds.ground_acceleration.values[dyn]
        for c, lab in ((1, "y"), (0, "x"), (2, "z")):
            ax2.plot(t, ag[:, c] / G, lw=0.6, label=lab)
        ax2.legend(loc="upper right", fontsize=8)
    ax2.set_ylabel("ground acceleration (g)")
    ax2.set_xlabel("time (s)")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("result", help="result file of examples/dam_3d_earthquake.toml")
    ap.add_argument("--stage", default="el_centro")
    ap.add_argument("--out", default=str(FIG))
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    ds = open_result(a.result)
    dyn = stage_steps(ds, a.stage)
    static_end = dyn[0] - 1 if dyn[0] > 0 else 0
    t = ds.time.values[dyn]
    t = t - t[0]
    u = ds.displacement.values[dyn]  # (step, node, component), the recorded nodes: the crest
    ux, uy = u[:, :, 0].mean(axis=1), u[:, :, 1].mean(axis=1)
    ux0, uy0 = ux[0], uy[0]

    # -- crest -----------------------------------------------------------------------------------
    plot_crest(ds, dyn, t, ux - ux0, uy - uy0, "along the axis (x)", "crest displacement (mm)",
               out / "dam_3d_crest.png")
    print(f"crest: peak {1e3 * np.abs(uy - uy0).max():.2f} mm along the stream at t = {t[np.argmax(np.abs(uy - uy0))]:.2f} s, "
          f"{1e3 * np.abs(ux - ux0).max():.2f} mm along the axis; permanent {1e3 * (uy[-1] - uy0):.2f} mm / "
          f"{1e3 * (ux[-1] - ux0):.2f} mm")

    # -- contraction joints in the top lift -----------------------------------------------------------
    set_names = json.loads(ds.joint_set.attrs["set_names"])
    js = ds.joint_set.values
    xj, zj = ds.joint_x.values, ds.joint_z.values
    cj = js == set_names.index("contraction_joints")
    top = zj[cj].max()
    lift = 6.0
    sel = np.nonzero(cj & (zj > top - lift))[0]
    xs = np.round(xj[sel], 3)
    joints = np.unique(xs)
    opening = ds.joint_opening.values[dyn][:, sel]  # (step, point)
    per_joint = np.stack([np.nanmax(opening[:, xs == x], axis=1) for x in joints], axis=1)  # (step, joint)
    fig, ax = plt.subplots(figsize=(8, 4))
    im = ax.pcolormesh(t, joints, 1e3 * np.clip(per_joint, 0, None).T, shading="nearest", cmap="magma_r")
    fig.colorbar(im, ax=ax, label="largest opening in the top lift (mm)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("contraction joint: position along the crest x (m)")
    fig.tight_layout()
    fig.savefig(out / "dam_3d_contraction_joints.png", dpi=130)
    k = np.unravel_index(np.nanargmax(per_joint), per_joint.shape)
    print(f"contraction joints: largest opening {1e3 * per_joint[k]:.2f} mm at x = {joints[k[1]]:.1f} m, t = "
          f"{t[k[0]]:.2f} s; open at the end: {int((per_joint[-1] > 1e-5).sum())} of {len(joints)} joints (> 0.01 mm)")

    # -- base sliding per monolith -------------------------------------------------------------------
    bj = np.nonzero(js == set_names.index("base_joint"))[0]
    slip = ds.joint_plastic_slip.values[dyn][:, bj, :]  # (step, point, shear direction)
    axes = ds.joint_shear_axis.values[bj]  # (point, shear direction, component)
    slip_y = np.einsum("spd,pd->sp", slip, axes[:, :, 1])  # the slip's component along the stream
    slip_y = slip_y - slip_y[0]
    if "section" in ds:
        sec = [str(s) for s in ds.section.values]
    xb = np.round(xj[bj], 0)
    # monoliths: group the base points by the contraction joints' positions along x
    edges = np.concatenate([[-np.inf], joints, [np.inf]])
    mono = np.digitize(xb, edges) - 1
    fig, ax = plt.subplots(figsize=(8, 4))
    finals = []
    for m in np.unique(mono):
        s = np.nanmean(slip_y[:, mono == m], axis=1)
        finals.append(s[-1])
        ax.plot(t, 1e3 * s, lw=0.8, label=f"monolith {m + 1}")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("base joint permanent slip\nalong the stream (mm)")
    ax.legend(fontsize=7, ncol=4)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "dam_3d_base_sliding.png", dpi=130)
    print("base sliding after the shaking (mm, monoliths 1..): " + ", ".join(f"{1e3 * f:.2f}" for f in finals))

    # -- sliding factors before and after ------------------------------------------------------------
    if "sliding_safety_factor" in ds:
        sf = ds.sliding_safety_factor.values
        before, after = sf[static_end], sf[dyn[-1]]
        order = np.arange(len(sec))
        fig, ax = plt.subplots(figsize=(10, 4))
        w = 0.4
        ax.bar(order - w / 2, np.clip(before, 0, 20), w, label="after the reservoir stage")
        ax.bar(order + w / 2, np.clip(after, 0, 20), w, label="after the shaking")
        ax.axhline(1.1, color="k", lw=0.8, ls="--", label="extreme load condition (1.1)")
        ax.set_xticks(order, sec, rotation=90, fontsize=6)
        ax.set_ylabel("sliding factor (clipped at 20)")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(out / "dam_3d_sliding_factors.png", dpi=130)
        i_b, i_a = int(np.nanargmin(before)), int(np.nanargmin(after))
        print(f"sliding factors: lowest {before[i_b]:.2f} on {sec[i_b]} after the reservoir stage, {after[i_a]:.2f} on "
              f"{sec[i_a]} after the shaking")
        low = np.nanmin(sf[dyn], axis=0)
        i_l = int(np.nanargmin(low))
        print(f"lowest during the shaking: {low[i_l]:.2f} on {sec[i_l]} (instantaneous, from the joint tractions)")
    print("energy: " + ", ".join(f"{k} {ds.attrs[k]}" for k in ("energy_error_relative",) if k in ds.attrs))


if __name__ == "__main__":
    main()
