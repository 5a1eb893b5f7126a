"""Modal study of the Koyna non-overflow section (Chopra & Chakrabarti 1973) with and without its reservoir,
for the comparison with published frequencies in docs/koyna_modes.md.

    python benchmarks/koyna_modes.py [--cases NAME ...] [--sizes 2.9 1.45 0.725] [--list]

Every case starts from ``examples/koyna_el_centro.toml`` ([model], [mesh] generator gravity_dam_2d
preset "koyna", [materials.dam]: E = 31 GPa, nu = 0.2, rho = 2643 kg/m3, plane strain) and ends with a
modal stage of 6 modes after self-weight (and, with water, a reservoir stage bringing the water to its
1967 level of 91.75 m). The cases:

- foundation ``rigid``: the example's rock block, [materials.foundation] and [joints.base_joint] are
  removed and the base of the dam is fixed (support set "base"); ``rock``: the example as given, the
  dam on its base joint on a 140 x 20 m massless rock block (E = 18 GPa) fixed at its bottom;
- ``joints``: the 10 lift joints of the example (Mohr-Coulomb, sticking under self-weight: the modal
  stage uses their elastic stiffness kn = ks = 1e11 Pa/m); ``solid``: no lift joints (a monolith);
- water ``empty``: no reservoir; ``westergaard``: Westergaard's added mass 7/8 rho sqrt(H z) on the
  upstream face; ``incompressible``: acoustic elements, incompressible water (the exact added mass of
  the discretised reservoir); ``compressible``: acoustic elements with c = 1440 m/s, the coupled
  dam-water eigenproblem (closed reservoir 3 H long, radiation left out), whose spectrum also holds
  reservoir modes from c / (4 H) = 3.92 Hz up;
- element size 2.9, 1.45 (the example's) or 0.725 m (linear quadrilaterals, quad4), and one case with
  quadratic ones (quad8) as a check of the mesh convergence;
- two plane-stress cases (the example is plane strain; the Abaqus Koyna example, after earlier studies, is
  plane stress).

Printed per case: f1..f4 (Hz), the period of mode 1, the dam's fundamental mode (the mode with the
largest effective mass ratio in x: with compressible water a reservoir mode can come first), its
frequency and x effective mass ratio, 2N (twice the node count, joint faces counted twice: the size of
the model before supports) and the run's wall time (masonrydam.run, mesh to modes), on one thread.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse
import copy
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402

SCENE_FILE = ROOT / "examples" / "koyna_el_centro.toml"
LEVEL = 91.75  # m, the reservoir in December 1967
SOUND_SPEED = 1440.0  # m/s

#: name -> (foundation, joints, water, element sizes, element order[, model hypothesis])
CASES = {
    "rigid-joints-empty": ("rigid", True, "empty", (2.9, 1.45, 0.725), 1),
    "rigid-solid-empty": ("rigid", False, "empty", (2.9, 1.45, 0.725), 1),
    "rigid-solid-empty-quad8": ("rigid", False, "empty", (2.9, 1.45), 2),
    "rigid-joints-westergaard": ("rigid", True, "westergaard", (1.45,), 1),
    "rigid-joints-incompressible": ("rigid", True, "incompressible", (1.45,), 1),
    "rigid-joints-compressible": ("rigid", True, "compressible", (2.9, 1.45, 0.725), 1),
    "rigid-solid-westergaard": ("rigid", False, "westergaard", (1.45,), 1),
    "rigid-solid-incompressible": ("rigid", False, "incompressible", (1.45,), 1),
    "rigid-solid-compressible": ("rigid", False, "compressible", (1.45,), 1),
    "rock-joints-empty": ("rock", True, "empty", (1.45,), 1),
    "rock-solid-empty": ("rock", False, "empty", (1.45,), 1),
    # plane stress, as the Abaqus Koyna example (after earlier studies): a check, not the example's model
    "rigid-solid-empty-planestress": ("rigid", False, "empty", (1.45,), 1, "plane_stress"),
    "rigid-solid-westergaard-planestress": ("rigid", False, "westergaard", (1.45,), 1, "plane_stress"),
}


def scene(foundation: str, joints: bool, water: str, element_size: float, order: int = 1,
          hypothesis: str | None = None, modes: int = 6) -> dict:
    """The modal scene of one case (see the module docstring)."""
    base = tomllib.loads(SCENE_FILE.read_text())
    sc = {"model": copy.deepcopy(base["model"]), "mesh": copy.deepcopy(base["mesh"]),
          "materials": {"dam": dict(base["materials"]["dam"])}}
    if hypothesis is not None:
        sc["model"]["hypothesis"] = hypothesis
    sc["model"]["name"] = f"koyna_modes_{foundation}_{'joints' if joints else 'solid'}_{water}"
    p = sc["mesh"]["parameters"]
    p["element_size"] = element_size
    if order != 1:
        p["order"] = order
    if foundation == "rigid":
        p.pop("foundation_width")
        p.pop("foundation_depth")
        sc["supports"] = [{"set": "base"}]
        if joints:
            sc["joints"] = {"lift_joints": dict(base["joints"]["lift_joints"])}
    elif foundation == "rock":
        sc["materials"]["foundation"] = dict(base["materials"]["foundation"])
        sc["supports"] = copy.deepcopy(base["supports"])
        sc["joints"] = {"base_joint": dict(base["joints"]["base_joint"])}
        if joints:
            sc["joints"]["lift_joints"] = dict(base["joints"]["lift_joints"])
    else:
        raise ValueError(f"foundation must be 'rigid' or 'rock', got {foundation!r}")
    if not joints:
        p.pop("lift_heights")
    stages = [{"name": "gravity", "loads": [{"type": "self_weight"}]}]
    if water != "empty":
        res = {"level": LEVEL, "face": "upstream_face"}
        if water == "westergaard":
            res["dynamic"] = "westergaard"
        elif water in ("incompressible", "compressible"):
            res["dynamic"] = "acoustic"
            res["acoustic"] = {"sound_speed": "incompressible" if water == "incompressible" else SOUND_SPEED}
        else:
            raise ValueError(f"unknown water {water!r}")
        sc["reservoir"] = res
        stages.append({"name": "reservoir", "steps": 2, "loads": [{"type": "reservoir"}]})
    stages.append({"name": "modes", "type": "modal", "modes": modes})
    sc["stages"] = stages
    return sc


def run_case(name: str, element_size: float) -> dict:
    import masonrydam

    foundation, joints, water, _, order, *hyp = CASES[name]
    sc = scene(foundation, joints, water, element_size, order, *hyp)
    t0 = time.perf_counter()
    ds = masonrydam.run(sc)
    wall = time.perf_counter() - t0
    f = ds.frequency.values
    mx = ds.effective_mass_ratio.sel(component="x").values
    k = int(np.argmax(mx))
    out = {"case": name, "h": element_size, "f": f, "T1": float(ds.period.values[0]), "mx1": float(mx[0]),
           "dam_mode": k + 1, "dam_f": float(f[k]), "dam_mx": float(mx[k]), "ndof": 2 * ds.sizes["node"],
           "wall": wall}
    ds.close()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--sizes", nargs="+", type=float, default=None,
                    help="element sizes (m) to run, among each case's own (default: all of them)")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    args = ap.parse_args()
    if args.list:
        for name, (fnd, jts, water, sizes, order, *hyp) in CASES.items():
            print(f"{name:36s} foundation {fnd}, lift joints {jts}, water {water}, h {sizes}, order {order}"
                  f"{', ' + hyp[0] if hyp else ''}")
        return
    print(f"# Koyna section, modal analysis, 6 modes ({cpu_model()}, 1 thread)")
    run_case("rigid-joints-empty", 2.9)  # JIT and the numba cache outside the timings
    hdr = (f"{'case':36s} {'h (m)':>6s} {'f1':>6s} {'f2':>6s} {'f3':>6s} {'f4':>6s} {'T1 (s)':>7s} {'mx1':>5s} "
           f"{'dam mode':>8s} {'f dam':>6s} {'mx dam':>6s} {'2N':>6s} {'run (s)':>7s}")
    print(hdr)
    for name in args.cases:
        for h in CASES[name][3]:
            if args.sizes is not None and not any(abs(h - s) < 1e-9 for s in args.sizes):
                continue
            r = run_case(name, h)
            f = r["f"]
            print(f"{name:36s} {h:6.3f} {f[0]:6.3f} {f[1]:6.3f} {f[2]:6.3f} {f[3]:6.3f} {r['T1']:7.4f} "
                  f"{r['mx1']:5.3f} {r['dam_mode']:8d} {r['dam_f']:6.3f} {r['dam_mx']:6.3f} {r['ndof']:6d} "
                  f"{r['wall']:7.2f}", flush=True)


if __name__ == "__main__":
    main()
