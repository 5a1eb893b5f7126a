"""Figures and figures' numbers of docs/dam_reservoir_foundation.md: the moving reservoir
and the foundation with mass.

    python benchmarks/figures_dam_water.py [--koyna-duration 20] [--dts 0.005 0.0025]

Writes docs/figures/dam_water_face_pressure.png (a rigid wall under a slowly rising ground
acceleration: the face pressure of Westergaard's added mass, of acoustic elements incompressible
and compressible, and the exact series), docs/figures/dam_water_rock_column.png (a shear pulse
through a 200 m rock column with an absorbing and with a rigid base) and
docs/figures/dam_water_koyna.png (examples/koyna_full_reservoir.toml: crest displacement, ground
displacement and the hydrodynamic force, for each dt asked), and prints the numbers the page quotes.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
for p in (str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "effects")):  # the water and rock scenes of tests/effects
    if p not in sys.path:
        sys.path.insert(0, p)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import masonrydam  # noqa: E402

FIG = ROOT / "docs" / "figures"


def face_pressure():
    from test_acoustic_dynamic import rigid_dam

    acc = np.linspace(0.0, 2.0, 51)
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    H = 10.0
    for label, kw, style in (("Westergaard added mass", {"dynamic": "westergaard"}, "s"),
                             ("acoustic, incompressible", {"sound_speed": "incompressible"}, "o"),
                             ("acoustic, c = 1440 m/s", {"sound_speed": 1440.0}, "^")):
        s = rigid_dam(height=H, level=H, size=0.5, ground={"values": acc.tolist(), "dt": 0.01}, **kw)
        ds = masonrydam.run(s)
        last = ds.isel(step=-1)
        a = float(last.ground_acceleration.sel(component="x"))
        p = -last.face_pressure.values / (1000.0 * a * H)
        y = ds.face_y.values / H
        o = np.argsort(y)
        F = -float(last.hydrodynamic_force.sel(component="x")) / (1000.0 * a * H * H)
        print(f"rigid wall, {label}: resultant {F:.4f} rho a H^2, base pressure {p[o][0]:.4f} rho a H")
        ax.plot(p[o], y[o], style, ms=3, label=f"{label} (resultant {F:.3f})")
    z = np.linspace(0.0, 1.0, 201)
    m = np.arange(1, 4001, 2)
    exact = 8.0 / np.pi**2 * np.sum(np.sin(m[None, :] * np.pi * z[:, None] / 2) / m[None, :] ** 2, axis=1)
    ax.plot(exact, 1.0 - z, "k-", lw=1, label="exact series (Westergaard 1933), 0.543")
    ax.set_xlabel("hydrodynamic pressure / (rho a H)")
    ax.set_ylabel("height above the base / H")
    ax.set_title("Rigid vertical face, H = 10 m, slowly rising a_g", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(FIG / "dam_water_face_pressure.png", dpi=110)
    plt.close(fig)


def rock_column():
    from test_foundation_run import CS, HC, T_PULSE, column

    fig, ax = plt.subplots(figsize=(6.5, 3.5))
    for motion, label in (("outcrop", "absorbing base, outcrop motion"),
                          ("within", "rigid base, within-rock motion (relative to the base)")):
        ds = masonrydam.run(column(motion=motion))
        d = ds.where(~np.isnan(ds.time), drop=True)
        t = d.time.values
        v = d.velocity.sel(component="x").values.mean(axis=1)
        ax.plot(t, v, label=f"surface velocity, {label}")
        gone = t > 2 * HC / CS + T_PULSE + 0.05
        print(f"rock column, {label}: peak surface velocity {np.abs(v).max():.4f} m/s, largest after the pulse has "
              f"left {np.abs(v[gone]).max():.2e} m/s ({100 * np.abs(v[gone]).max() / np.abs(v).max():.2f} %)")
    tt = np.linspace(0.0, 0.75, 1000)
    vo = np.where((tt > 0) & (tt < T_PULSE), T_PULSE / (2 * np.pi) * (1 - np.cos(2 * np.pi * tt / T_PULSE)), 0.0)
    ax.plot(tt + HC / CS, vo, "k--", lw=1, label="outcrop velocity, delayed by H / c_s")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("velocity (m/s)")
    ax.set_title("Shear pulse in a 200 m rock column (c_s = 1000 m/s)")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(FIG / "dam_water_rock_column.png", dpi=110)
    plt.close(fig)


def koyna(duration, dts):
    from masonrydam.results.mode_plot import mode_figure

    # the mode shape on every node: the example without its dynamic stage (which records the faces only)
    base = tomllib.loads((ROOT / "examples" / "koyna_full_reservoir.toml").read_text())
    base["stages"] = base["stages"][:3]
    mf = mode_figure(masonrydam.run(base), 1)
    mf.savefig(FIG / "dam_water_koyna_mode1.png", dpi=110)
    plt.close(mf)
    fig, axes = plt.subplots(2, 1, figsize=(7.5, 6), sharex=True)
    for dt in dts:
        sc = tomllib.loads((ROOT / "examples" / "koyna_full_reservoir.toml").read_text())
        if dt == 0.0:  # dt = "auto" at its default tolerance
            sc["stages"][3]["dt"], sc["stages"][3]["dt_max"] = "auto", 0.01
        else:
            sc["stages"][3]["dt"] = dt
        sc["stages"][3]["duration"] = duration
        t0 = time.perf_counter()
        ds = masonrydam.run(sc)
        wall = time.perf_counter() - t0
        d = ds.where(~np.isnan(ds.time), drop=True)
        t = d.time.values
        crest = ds.y.values >= ds.y.values.max() - 1e-6  # the recorded nodes on the crest
        ux = d.displacement.sel(component="x").values[:, crest].mean(axis=1)
        F = d.hydrodynamic_force.sel(component="x").values
        ag = d.ground_acceleration.sel(component="x").values
        vg = np.concatenate([[0.0], np.cumsum(0.5 * (ag[1:] + ag[:-1]) * np.diff(t))])
        ug = np.concatenate([[0.0], np.cumsum(0.5 * (vg[1:] + vg[:-1]) * np.diff(t))])
        at = {x: 1e3 * ux[np.searchsorted(t, x)] for x in (5.0, 10.0)}
        print(f"koyna full reservoir, dt {dt or 'auto'} s: {int(ds.attrs['dynamic_steps'])} steps, "
              f"{float(ds.attrs['dynamic_ms_per_step']):.2f} ms/step, run {wall:.1f} s; crest at 5 s {at[5.0]:.0f} mm, "
              f"at 10 s {at[10.0]:.0f} mm, |u_x| max "
              f"{1e3 * np.abs(ux).max():.0f} mm, crest minus outcrop displacement at the end "
              f"{1e3 * (ux[-1] - ug[-1]):.0f} mm; hydrodynamic force peak {np.abs(F).max() / 1e6:.1f} MN/m; "
              f"frequencies {np.round(ds.frequency.values, 3).tolist()} Hz")
        axes[0].plot(t, 1e3 * ux, lw=1, label=f"crest, dt = {dt or 'auto'} s")
        axes[1].plot(t, F / 1e6, lw=1, label=f"dt = {dt or 'auto'} s")
        if dt == dts[0]:
            axes[0].plot(t, 1e3 * ug, "k--", lw=0.8, label="ground (outcrop record integrated)")
    axes[0].set_ylabel("horizontal displacement (mm)")
    axes[0].legend(fontsize=7, loc="upper left")
    axes[1].set_ylabel("hydrodynamic force (MN/m)")
    axes[1].set_xlabel("time (s)")
    axes[1].legend(fontsize=7, loc="upper left")
    axes[0].set_title("Koyna, full reservoir (acoustic), rock with mass, El Centro at 0.5 g (outcrop)")
    fig.tight_layout()
    fig.savefig(FIG / "dam_water_koyna.png", dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--koyna-duration", type=float, default=20.0)
    ap.add_argument("--dts", type=float, nargs="+", default=[0.0025, 0.00125, 0.000625, 0.0],
                    help="time steps of the Koyna runs (s; 0: dt = \"auto\")")
    ap.add_argument("--skip-koyna", action="store_true")
    args = ap.parse_args()
    FIG.mkdir(parents=True, exist_ok=True)
    face_pressure()
    rock_column()
    if not args.skip_koyna:
        koyna(args.koyna_duration, args.dts)


if __name__ == "__main__":
    main()
