"""Why the held Eindhoven wall J4D hardens past its first peak: the reference loading
(examples/eindhoven_J4D.toml: the top beam kept level and at its height, Lourenco & Rots 1997) against variants
of one parameter or of the geometry each, printing for every run the horizontal force H and the vertical
force V that holding the top adds (kN, the reactions on the driven top nodes; V = 0 at the start of the push,
negative in compression) at 1, 2, 3 and 4 mm, and how many joint points of each set slide, are open or are on
the compression cap ("crush") at 2 mm and at the end.

    python benchmarks/study_eindhoven_held.py [--variants example fc_7.5 ...] [--list]

Variants (``--list`` prints them with their changes):

- ``example``: the example as it is (relaxation time 0.0025 ms, 40 push steps, 2 elements per unit);
- ``fc_7.5``, ``fc_5``: the cap's compressive strength of the bed and head joints (10.5 MPa in the example,
  Lourenco & Rots 1997);
- ``kappa_p_0.02``: the cap's peak plastic relative displacement (0.09 mm in the example, an assumption);
- ``gfc_1``: the cap's fracture energy 1 N/mm (5 N/mm);
- ``css_1``: the cap's shear factor 1 (9);
- ``weak_units``: the units' potential cracks at ft = 1 MPa, c = 1.4 MPa (2 and 2.8 MPa);
- ``16_courses``: 16 courses of masonry (992 mm) between the beams instead of 18 (1116 mm);
- ``J6D``, ``J7D``: the precompression of walls J6D and J7D, 1.21 and 2.12 MPa (0.30 MPa: J4D, J5D);
- ``tau_0.00025``: every composite set's relaxation time a tenth of the example's (0.00025 ms);
- ``unit_k_1e4``, ``unit_k_1e4_tau_0.00025``: the units' potential cracks with a penalty stiffness of 1e4 N/mm3
  (1e6 in the example), at the example's relaxation time and at a tenth of it.
- ``one_viscosity_0.25``, ``one_viscosity_0.025``, ``one_viscosity_0.0025``: one viscosity ``tau kn`` for every
  set: the mortar joints at the relaxation time named, the unit cracks at it times 82 / 1e6 (their stiffness ratio);
- ``unit_k_1e4_one_viscosity_0.025`` (``_0.0025``, ``_0.00025``): the same with the unit cracks' penalty at 1e4 N/mm3
  (their relaxation time the mortar joints' times 82 / 1e4).

Each run also prints, per joint set, the largest traction beyond the set's virgin strength over the push: the
normal traction beyond ``ft`` and the shear beyond ``c - tan(phi) t_n`` (MPa). The inviscid law never goes
beyond them (softening only lowers the surfaces), so what is printed is the viscous regularisation's overstress
(at least).

A study, not a test: it prints what each run gives, including a run that stops (its error's class and where).
One process, one thread; about twenty-two minutes for all of them on a 2-core AMD EPYC.
"""
from __future__ import annotations

from _common import cpu_model, pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse  # noqa: E402
import json  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "eindhoven_J4D.toml"
CAP_SETS = ("bed_joints", "head_joints")


def _both(key, value):
    return {f"joints.{s}.{key}": value for s in CAP_SETS}


VARIANTS = {
    "example": {},
    "fc_7.5": _both("compressive_strength", "7.5 MPa"),
    "fc_5": _both("compressive_strength", "5 MPa"),
    "kappa_p_0.02": _both("cap_peak_plastic_strain", "0.02 mm"),
    "gfc_1": _both("cap_fracture_energy", "1 N/mm"),
    "css_1": _both("cap_shear_factor", 1.0),
    "weak_units": {"joints.unit_cracks.tensile_strength": "1.0 MPa", "joints.unit_cracks.cohesion": "1.4 MPa"},
    "16_courses": {"mesh.parameters.height": "992 mm"},
    "J6D": {"stages[0].loads[1].pressure": "1.21 MPa"},
    "J7D": {"stages[0].loads[1].pressure": "2.12 MPa"},
    "tau_0.00025": {f"joints.{s}.relaxation_time": "0.00025 ms" for s in (*CAP_SETS, "unit_cracks")},
    "unit_k_1e4": {"joints.unit_cracks.normal_stiffness": "1e4 N/mm3",
                   "joints.unit_cracks.shear_stiffness": "1e4 N/mm3"},
    "unit_k_1e4_tau_0.00025": {"joints.unit_cracks.normal_stiffness": "1e4 N/mm3",
                               "joints.unit_cracks.shear_stiffness": "1e4 N/mm3",
                               **{f"joints.{s}.relaxation_time": "0.00025 ms" for s in (*CAP_SETS, "unit_cracks")}},
    # one viscosity eta = tau kn for every set: the unit cracks' relaxation time is the mortar joints' times
    # 82 / 1e6 (their stiffness ratio), so that both carry the same overstress eta * plastic rate
    **{f"one_viscosity_{t}": {**_both("relaxation_time", f"{t} ms"),
                              "joints.unit_cracks.relaxation_time": f"{float(t) * 82e-6:.4g} ms"}
       for t in ("0.25", "0.025", "0.0025")},
    # the same with the unit cracks' penalty at 1e4 N/mm3 (their relaxation time the mortar's times 82 / 1e4)
    **{f"unit_k_1e4_one_viscosity_{t}": {**_both("relaxation_time", f"{t} ms"),
                                         "joints.unit_cracks.normal_stiffness": "1e4 N/mm3",
                                         "joints.unit_cracks.shear_stiffness": "1e4 N/mm3",
                                         "joints.unit_cracks.relaxation_time": f"{float(t) * 82e-4:.4g} ms"}
       for t in ("0.025", "0.0025", "0.00025")},
}


def run_variant(name: str) -> None:
    import masonrydam
    from masonrydam.results.pushover import pushover_data, value_at_push
    from masonrydam.scene.scene import Scene, set_key

    sc = Scene.from_toml(EXAMPLE)
    data = sc.data
    for key, value in VARIANTS[name].items():
        set_key(data, key, value)
    t0 = time.perf_counter()
    stopped = ""
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "j4d.nc"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                masonrydam.run(Scene(data, base_dir=sc.base_dir), output=out)
            except masonrydam.MasonrydamError as exc:  # the converged steps are kept in the result file
                stopped = type(exc).__name__
        wall = time.perf_counter() - t0
        if not out.exists():
            print(f"{name:14s} stopped ({stopped}) before its first step; {wall:.1f} s", flush=True)
            return
        ds = xr.load_dataset(out)
    d, h, steps = pushover_data(ds, "x")
    top = ds.driven.sel(component="x").values == ds.driven.sel(component="x").values.max()
    v = ds.reaction.sel(component="y").values[steps][:, top].sum(axis=1)
    mm = d * 1e3

    def at(x, values):
        value = value_at_push(d, values, x * 1e-3)
        return "     -" if np.isnan(value) else f"{value / 1e3:6.1f}"

    k = int(np.argmax(h))
    print(f"{name:14s} peak {h[k] / 1e3:5.1f} kN at {mm[k]:4.2f} mm | H at 1/2/3/4 mm "
          + " ".join(at(x, h) for x in (1, 2, 3, 4)) + " | V " + " ".join(at(x, v) for x in (1, 2, 3, 4))
          + f" | reached {mm[-1]:4.2f} mm{' (' + stopped + ')' if stopped else ''}, {wall:.1f} s", flush=True)
    names = json.loads(ds.joint_set.attrs["set_names"])
    sets = ds.joint_set.values
    for label, j in (("2 mm", int(np.argmin(abs(mm - 2.0)))), ("end", len(steps) - 1)):
        state = ds.joint_state.values[steps[j]]
        counts = []
        for i, n in enumerate(names):
            c = np.bincount(state[sets == i], minlength=4)
            if c[1:].any():
                counts.append(f"{n} {c[1]}/{c[2]}/{c[3]} of {int((sets == i).sum())}")
        print(f"{'':14s}   slide/open/crush at {label}: " + ", ".join(counts), flush=True)
    print(f"{'':14s}   beyond the virgin strength (MPa, tension / shear): "
          + ", ".join(beyond_virgin_strength(ds, steps, data["joints"])), flush=True)


def beyond_virgin_strength(ds, steps, joints: dict) -> list[str]:
    """Per composite joint set: the largest normal traction beyond its tensile strength and the largest shear
    traction beyond ``c - tan(phi) t_n`` (MPa, tension positive) over the recorded steps ``steps``."""
    from masonrydam.units import quantity

    names = json.loads(ds.joint_set.attrs["set_names"])
    sets = ds.joint_set.values
    tn = ds.joint_traction_normal.values[steps]
    ts = np.abs(ds.joint_traction_shear.values[steps][..., 0])
    out = []
    for i, n in enumerate(names):
        spec = joints.get(n, {})
        if spec.get("law") != "composite":
            continue
        ft = quantity(spec["tensile_strength"], "stress", f"joints.{n}.tensile_strength")
        c = quantity(spec["cohesion"], "stress", f"joints.{n}.cohesion")
        tan_phi = np.tan(np.radians(float(spec["friction_angle"])))
        m = sets == i
        tension = (tn[:, m] - ft).max() / 1e6
        shear = (ts[:, m] - (c - tan_phi * tn[:, m])).max() / 1e6
        out.append(f"{n} {tension:+.3f} / {shear:+.3f}")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--list", action="store_true", help="print the variants and their changes")
    args = ap.parse_args(argv)
    if args.list:
        for name, changes in VARIANTS.items():
            print(f"{name:14s} {changes or '(the example)'}")
        return 0
    print(f"# the held J4D wall, variants one change each ({cpu_model()}, 1 thread); H, V in kN", flush=True)
    for name in args.variants:
        run_variant(name)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
