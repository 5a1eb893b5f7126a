"""Modal study of the arch dam of ``examples/arch_dam_earthquake.toml``: the first six
frequencies under mesh refinement (hex8 and hex20, element sizes halving) with the reservoir empty and full
(Westergaard's added mass), for docs/arch_dams.md.

    python benchmarks/arch_dam_modes.py [--cases NAME ...] [--list]

No measured frequencies of a reproducible arch geometry were at hand, so the study checks the model against
itself: successive refinements must close in on one value (for a smooth problem the error of hex8 falls as
h^2, so successive differences shrink about 4-fold, and Richardson's extrapolation of the three finest hex8
results estimates the limit), and hex20 must get there on coarser grids. Published forced-vibration
frequencies of a real arch of similar height (Pacoima dam, 113 m: about 5.4 Hz symmetric and 5.7 Hz
antisymmetric with the water 36 m below the crest; Alves & Hall 2006, EESD 35:1321) are an order of
magnitude to compare with, not a reference: the geometry is not Pacoima's.

Every case takes the example's dam ([mesh.parameters] and [materials.dam]) without its rock block: the dam
stands on a rigid canyon (support set ``base``: the valley floor and the benches), so the refinement acts on
the arch alone. Its lift and contraction joints are linear penalty joints (kn = ks = 1e11 Pa/m, the
example's): the dam as one grouted, sticking body, the state in which its modes are defined. With water
(``full``), a static stage applies the reservoir at the example's 97 m and the modal stage includes
Westergaard's added mass 7/8 rho sqrt(H z) n n^T on the wetted extrados (Westergaard 1933; Kuo 1982 for
the normal on a curved face); the joints are linear, so the static stage leaves the stiffness unchanged.

Printed per case: element order and size h, DOF (three per node, joint faces counted twice), f1..f6 (Hz),
the symmetry of modes 1 and 2 about the crown (S symmetric, A antisymmetric: the sign of the correlation
of the crest's upstream-downstream displacement at x and -x), and the run's wall time on one thread; then
Richardson's estimate of f1 from the three hex8 sizes that halve the elements in every direction and the full/empty ratio of f1 per size.
Writes nothing.
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

SCENE_FILE = ROOT / "examples" / "arch_dam_earthquake.toml"
MODES = 6
JOINT = {"law": "linear", "normal_stiffness": 1e11, "shear_stiffness": 1e11}

#: sizes on which the refinement halves the elements in every direction: through the 20 m base thickness
#: ceil(20 / h) = 2, 4, 8 (at h = 20 m the thickness keeps the generator's minimum of 2, so 20 -> 10 halves the
#: arc and the height only, and Richardson's ratio needs a true halving)
HALVING = (10.0, 5.0, 2.5)

#: name -> (element order, element sizes (m), water)
CASES = {
    "hex8-empty": (1, (20.0, 10.0, 5.0, 2.5), "empty"),
    "hex20-empty": (2, (20.0, 10.0, 5.0), "empty"),
    "hex8-full": (1, (20.0, 10.0, 5.0, 2.5), "full"),
    "hex20-full": (2, (20.0, 10.0, 5.0), "full"),
}


def scene(element_size: float, order: int, water: str, modes: int = MODES) -> dict:
    """The modal scene of one case (see the module docstring)."""
    base = tomllib.loads(SCENE_FILE.read_text())
    p = copy.deepcopy(base["mesh"]["parameters"])
    for k in ("foundation_depth", "foundation_extent"):
        p.pop(k, None)
    p["element_size"], p["order"] = element_size, order
    sc = {"model": {"name": f"arch_modes_{water}", "dimension": 3},
          "mesh": {"generator": "arch_dam_3d", "parameters": p},
          "materials": {"dam": dict(base["materials"]["dam"])},
          "joints": {"lift_joints": dict(JOINT), "contraction_joints": dict(JOINT)},
          "supports": [{"set": "base"}],
          "stages": [{"name": "modes", "type": "modal", "modes": modes}]}
    if water == "full":
        r = base["reservoir"]
        sc["reservoir"] = {"level": r["level"], "density": r["density"], "face": r["face"], "dynamic": "westergaard"}
        sc["stages"].insert(0, {"name": "reservoir", "loads": [{"type": "reservoir"}]})
    elif water != "empty":
        raise ValueError(f"water must be 'empty' or 'full', got {water!r}")
    return sc


def symmetry(ds, k: int) -> str:
    """'S' or 'A': the sign of the correlation of mode k's displacement along y at the crest nodes at x
    and at -x (the arch is symmetric about x = 0)."""
    x, y, z = ds.x.values, ds.y.values, ds.z.values
    top = np.nonzero(z > z.max() - 1e-3)[0]
    uy = ds.mode_shape.isel(mode=k).values[top, 1]
    xt, yt = x[top], y[top]
    # the mirror of each crest node: the crest node nearest to (-x, y)
    d = (xt[:, None] + xt[None, :]) ** 2 + (yt[:, None] - yt[None, :]) ** 2
    mirror = np.argmin(d, axis=1)
    c = float(np.sum(uy * uy[mirror]))
    return "S" if c > 0.0 else "A"


def run_case(element_size: float, order: int, water: str) -> dict:
    import masonrydam

    sc = scene(element_size, order, water)
    t0 = time.perf_counter()
    ds = masonrydam.run(sc)
    wall = time.perf_counter() - t0
    out = {"f": ds.frequency.values.copy(), "ndof": 3 * ds.sizes["node"], "wall": wall,
           "sym": "".join(symmetry(ds, k) for k in range(2))}
    ds.close()
    return out


def richardson(f_coarse: float, f_mid: float, f_fine: float) -> tuple[float, float]:
    """Aitken's extrapolation of three results on sizes halving: (limit, observed order p), with
    2^p = (f_coarse - f_mid) / (f_mid - f_fine)."""
    d1, d2 = f_coarse - f_mid, f_mid - f_fine
    p = float(np.log2(d1 / d2)) if d1 * d2 > 0 else float("nan")
    return f_fine - d2 * d2 / (d1 - d2), p


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    args = ap.parse_args()
    if args.list:
        for name, (order, sizes, water) in CASES.items():
            print(f"{name:12s} order {order}, h {sizes}, water {water}")
        return
    print(f"# arch dam of examples/arch_dam_earthquake.toml on a rigid canyon, {MODES} modes "
          f"({cpu_model()}, 1 thread)")
    run_case(20.0, 1, "empty")  # JIT and the numba cache outside the timings
    print(f"{'case':12s} {'h (m)':>6s} {'DOF':>7s} " + " ".join(f"{'f' + str(i + 1):>6s}" for i in range(MODES))
          + f" {'sym':>4s} {'run (s)':>7s}")
    res = {}
    for name in args.cases:
        order, sizes, water = CASES[name]
        for h in sizes:
            r = run_case(h, order, water)
            res[(name, h)] = r
            print(f"{name:12s} {h:6.2f} {r['ndof']:7d} " + " ".join(f"{v:6.3f}" for v in r["f"])
                  + f" {r['sym']:>4s} {r['wall']:7.2f}", flush=True)
    for name in args.cases:
        order, sizes, water = CASES[name]
        halving = [h for h in sizes if h in HALVING]
        if len(halving) >= 3:
            f = [res[(name, h)]["f"][0] for h in halving[-3:]]
            lim, p = richardson(*f)
            print(f"{name}: f1 differences {f[0] - f[1]:+.4f}, {f[1] - f[2]:+.4f} Hz (ratio {(f[0] - f[1]) / (f[1] - f[2]):.2f}); "
                  f"Richardson limit of the sizes {tuple(halving[-3:])}: {lim:.4f} Hz, observed order {p:.2f}")
    for order_name in ("hex8", "hex20"):
        e, w = f"{order_name}-empty", f"{order_name}-full"
        if e in args.cases and w in args.cases:
            for h in CASES[e][1]:
                fe, fw = res[(e, h)]["f"], res[(w, h)]["f"]
                print(f"{order_name} h {h:g}: full / empty, modes 1-{MODES}: " + " ".join(f"{a / b:.3f}" for a, b in zip(fw, fe)))


if __name__ == "__main__":
    main()
