"""masonrydam against OpenSees on the same jointed dam section: the coarse Koyna section under El Centro at 0.5 g.

    pip install -e ".[opensees]"       # openseespy; its Linux build needs libblas3 and liblapack3 (Debian)
    python benchmarks/bench_opensees_koyna.py [--duration 40] [--dts 0.01 0.005 0.0025 0.00125]

The model is the Koyna section of examples/koyna_el_centro.toml (Chopra & Chakrabarti 1973 profile, 10 lift
joints and the dam-foundation joint) on the coarse mesh of element_size 12 m (179 nodes, 93 quadrilaterals,
44 joint elements), built once by masonrydam and handed to OpenSees (McKenna, Fenves & Scott 2000; OpenSeesPy,
Zhu, McKenna & Scott 2018) node for node:

- blocks: four-node quadrilaterals with 2 x 2 Gauss points (OpenSees ``quad``, plane strain, ``ElasticIsotropic``),
  lumped mass in both codes, self-weight as nodal loads m g (OpenSees) and the consistent body load (masonrydam);
- joints: cohesionless Coulomb friction (tan phi = 1) with no tension and stiffnesses kn = ks = 1e11 Pa/m in both
  (the example's cohesion and tensile strength set to zero: OpenSees' node-to-node contact element
  ``zeroLengthContact2D`` has neither). masonrydam integrates each joint element at 2 Gauss points; OpenSees gets
  one contact element per node pair with the pair's tributary area (the Gauss weights lumped to the nodes), the
  penalty stiffnesses kn and ks times that area;
- Rayleigh damping of the blocks (5 % at 3 and 15 Hz, the joints excluded: OpenSees ``region -rayleigh`` with the
  initial stiffness), the trapezoidal rule (Newmark gamma = 1/2, beta = 1/4) in both;
- the ground motion: masonrydam's processed El Centro 1940 samples (NGA-West2 RSN6, scaled to PGA 0.5 g), as an
  OpenSees ``Path`` series under ``UniformExcitation``.

For each code and each dt the script times the dynamic analysis (gravity excluded), records the crest's
horizontal displacement relative to the base every 0.01 s, and compares it with the same code's finest run: the
RMS of the difference over the RMS of the finest history. It prints, per code, the largest dt within 5 % of its
own finest run and its wall time, and the ratio of the two codes' times at those dt. OpenSees
steps that do not converge with Newton are retried with Krylov-Newton, then with the initial stiffness, then
halved (up to 4 times); a step that fails all of these ends that run (reported). A benchmark: it prints its
figures and never fails on them.
"""
from __future__ import annotations

from _common import pin_one_thread  # benchmarks/ is sys.path[0] when run as a script

pin_one_thread()

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import tomllib  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from _common import cpu_model  # noqa: E402

EXAMPLES = ROOT / "examples"
G = 9.80665
#: the crest history is compared on this grid (s)
OUTPUT_DT = 0.01
#: a run is converged when its crest history is within this RMS fraction of the same code's finest run
RMS_TOLERANCE = 0.05


def scene_dict(dt, duration, element_size=12.0):
    """The comparison scene: examples/koyna_el_centro.toml, coarse, cohesionless joints, trapezoidal rule."""
    from masonrydam.scene.schema import set_time_steps

    sc = tomllib.loads((EXAMPLES / "koyna_el_centro.toml").read_text())
    sc["mesh"]["parameters"]["element_size"] = element_size
    for joint in sc["joints"].values():
        joint["cohesion"] = 0.0
        joint["tensile_strength"] = 0.0
    stage = set_time_steps(sc["stages"][1], dt, steps=int(round(duration / dt)))
    stage["integrator"] = "newmark_average"
    stage.pop("alpha", None)
    stage["output"] = {"stride": max(1, int(round(OUTPUT_DT / dt))), "nodes": ["crest"]}
    sc["stages"][1] = stage
    return sc


def run_masonrydam(dt, duration):
    """(seconds of the dynamic stage, times, crest u_x relative to the base) of masonrydam at ``dt``."""
    import masonrydam
    from masonrydam.scene import Scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = masonrydam.run(Scene(scene_dict(dt, duration), base_dir=EXAMPLES))
    dyn = ds.stage.values == ds.stage.values[-1]
    t = ds.time.values[dyn] - ds.time.values[dyn][0]
    ux = ds.displacement.sel(component="x").values[dyn].mean(axis=1)  # the crest nodes move together
    # from the state after gravity, as OpenSees' history below (the crest moves about 10 mm under gravity)
    return float(ds.attrs["dynamic_wall_time_s"]), t, ux - ux[0]


class Section:
    """The coarse section as masonrydam builds it: nodes, blocks, joints, supports, loads and the ground motion."""

    def __init__(self, duration):
        from masonrydam.scene import Scene, build_mesh, build_model, build_stages

        sc = Scene(scene_dict(0.01, duration), base_dir=EXAMPLES)
        mesh = build_mesh(sc.normalized, sc.base_dir)
        model = self.model = build_model(sc.normalized, mesh)
        stages = build_stages(sc.normalized, mesh, model)
        dyn = stages[1]
        self.coords = model.coords
        self.supports = dyn.supports.reshape(-1, 2)
        self.materials = sc.normalized["materials"]
        self.damping = dyn.settings.damping
        gm = dyn.ground_motion[0]
        self.record_dt, self.record = gm.dt, np.asarray(gm.values)
        self.crest = np.asarray(mesh.node_sets["crest"])
        self.base = np.flatnonzero(self.supports.all(axis=1))
        self.blocks = [(g.name, np.asarray(g.conn)) for g in model.cgroups]
        self.thickness = 1.0
        # joints: one contact per (bottom node, top node) pair, its tributary area (m2) and normal
        pairs = {}
        for g in model.igroups:
            ns = g.N.shape[1]
            kn, ks, tan_phi = g.params_table[0, 0], g.params_table[0, 1], g.params_table[0, 3]
            for e in range(g.n_elem):
                for a in range(ns):
                    bottom, top = int(g.conn[e, a]), int(g.conn[e, ns + a])
                    area = float(np.sum(g.N[:, a] * g.jw[e] * g.thickness[e]))
                    normal = g.frame[e, 0, -1]
                    key = (bottom, top)
                    if key in pairs:
                        pairs[key][0] += area
                    else:
                        pairs[key] = [area, normal, kn, ks, tan_phi]
        self.pairs = pairs


def run_opensees(section, dt, duration):
    """(seconds of the dynamic analysis, times, crest u_x relative to the base, note) of OpenSees at ``dt``."""
    import openseespy.opensees as ops

    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 2)
    for i, (x, y) in enumerate(section.coords):
        ops.node(i + 1, float(x), float(y))
    for i, fixed in enumerate(section.supports):
        if fixed.any():
            ops.fix(i + 1, int(fixed[0]), int(fixed[1]))
    quad_tags, tag = [], 0
    nodal_mass = np.zeros(len(section.coords))
    for k, (name, conn) in enumerate(section.blocks):
        mat = section.materials[name]
        rho = float(mat["density"])
        ops.nDMaterial("ElasticIsotropic", k + 1, float(mat["youngs_modulus"]), float(mat["poisson_ratio"]), rho)
        for c in conn:
            tag += 1
            ops.element("quad", tag, *[int(n) + 1 for n in c], section.thickness, "PlaneStrain", k + 1, 0.0, rho,
                        0.0, 0.0)
            quad_tags.append(tag)
            xy = section.coords[c]
            area = 0.5 * abs(np.dot(xy[:, 0], np.roll(xy[:, 1], 1)) - np.dot(xy[:, 1], np.roll(xy[:, 0], 1)))
            nodal_mass[c] += rho * section.thickness * area / 4.0  # the quad's lumped mass
    for (bottom, top), (area, normal, kn, ks, tan_phi) in section.pairs.items():
        tag += 1
        ops.element("zeroLengthContact2D", tag, top + 1, bottom + 1, kn * area, ks * area, tan_phi,
                    "-normal", float(normal[0]), float(normal[1]))
    d = section.damping
    ops.region(1, "-ele", *quad_tags, "-rayleigh", d.alpha, 0.0, d.beta, 0.0)
    # gravity
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    for i, m in enumerate(nodal_mass):
        if m > 0 and not section.supports[i].all():
            ops.load(i + 1, 0.0, -m * G)
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-10, 100)
    ops.algorithm("KrylovNewton")
    ops.integrator("LoadControl", 0.1)
    ops.analysis("Static")
    if ops.analyze(10) != 0:
        return None, None, None, "the gravity analysis did not converge"
    ops.loadConst("-time", 0.0)
    ops.wipeAnalysis()
    # earthquake
    ops.timeSeries("Path", 2, "-dt", section.record_dt, "-values", *section.record.tolist())
    ops.pattern("UniformExcitation", 2, 1, "-accel", 2)
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-8, 25)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    crest = [int(n) + 1 for n in section.crest]
    base = int(section.base[0]) + 1
    n_steps = int(round(duration / dt))
    stride = max(1, int(round(OUTPUT_DT / dt)))
    t_out, u_out, note = [0.0], [0.0], ""
    u0 = np.mean([ops.nodeDisp(n, 1) for n in crest]) - ops.nodeDisp(base, 1)
    t0 = time.perf_counter()
    for k in range(1, n_steps + 1):
        if not _opensees_step(ops, dt):
            note = f"stopped at t = {ops.getTime():.3f} s: a step did not converge after 4 halvings"
            break
        if k % stride == 0:
            t_out.append(k * dt)
            u_out.append(np.mean([ops.nodeDisp(n, 1) for n in crest]) - ops.nodeDisp(base, 1) - u0)
    seconds = time.perf_counter() - t0
    ops.wipe()
    return seconds, np.array(t_out), np.array(u_out), note


def _opensees_step(ops, dt, level=0):
    """One step of dt: Newton, then Krylov-Newton, then the initial stiffness, then two halves (recursively)."""
    for algorithm in (("Newton",), ("KrylovNewton",), ("ModifiedNewton", "-initial")):
        ops.algorithm(*algorithm)
        if ops.analyze(1, dt) == 0:
            if algorithm[0] != "Newton":
                ops.algorithm("Newton")
            return True
    ops.algorithm("Newton")
    if level >= 4:
        return False
    return _opensees_step(ops, dt / 2, level + 1) and _opensees_step(ops, dt / 2, level + 1)


def rms_error(t, u, t_ref, u_ref):
    """RMS of u - u_ref on the reference grid over the RMS of u_ref (histories of possibly different lengths: the
    common part)."""
    n = min(len(t_ref), int(np.searchsorted(t_ref, t[-1] + 1e-9)))
    ui = np.interp(t_ref[:n], t, u)
    return float(np.sqrt(np.mean((ui - u_ref[:n]) ** 2)) / np.sqrt(np.mean(u_ref[:n] ** 2)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=40.0)
    ap.add_argument("--dts", type=float, nargs="+", default=[0.01, 0.005, 0.0025, 0.00125])
    ap.add_argument("--codes", nargs="+", default=["masonrydam", "opensees"], choices=["masonrydam", "opensees"])
    ap.add_argument("--save", type=Path, help="write every run's crest history to this .npz file")
    args = ap.parse_args()
    dts = sorted(args.dts, reverse=True)
    print(f"# coarse Koyna section, El Centro 1940 at 0.5 g, {args.duration:g} s, cohesionless joints "
          f"({cpu_model()}, 1 thread)")
    runs = {}
    if "masonrydam" in args.codes:
        run_masonrydam(0.01, 0.1)  # numba's caches loaded outside the timings
        runs["masonrydam"] = [(dt, *run_masonrydam(dt, args.duration), "") for dt in dts]
    if "opensees" in args.codes:
        section = Section(args.duration)
        runs["opensees"] = [(dt, *run_opensees(section, dt, args.duration)) for dt in dts]
    chosen = {}
    for code, rows in runs.items():
        ref = rows[-1]
        print(f"\n[{code}] reference: its run at dt = {ref[0]:g} s")
        for dt, seconds, t, u, note in rows:
            if seconds is None:
                print(f"  dt = {dt:<8g} failed: {note}")
                continue
            err = rms_error(t, u, ref[2], ref[3]) if ref[1] is not None else float("nan")
            print(f"  dt = {dt:<8g} {seconds:8.2f} s, peak |crest u_x| {1e3 * np.abs(u).max():7.1f} mm, "
                  f"RMS difference from the reference {100 * err:6.2f} %" + (f"  ({note})" if note else ""))
            if dt != ref[0] and err <= RMS_TOLERANCE and not note and code not in chosen:
                chosen[code] = (dt, seconds)
        if code not in chosen:
            print(f"  no dt coarser than the reference is within {100 * RMS_TOLERANCE:g} % of it")
    if args.save is not None:
        np.savez(args.save, **{f"{code}_{dt:g}_{what}": arr for code, rows in runs.items()
                               for dt, seconds, t, u, note in rows if seconds is not None
                               for what, arr in (("t", t), ("u", u))})
    if len(runs) == 2 and all(rows[-1][1] is not None for rows in runs.values()):
        m, o = runs["masonrydam"][-1], runs["opensees"][-1]
        print(f"\nthe two codes' finest runs (dt = {m[0]:g} and {o[0]:g} s): OpenSees' crest history differs from "
              f"masonrydam's by {100 * rms_error(o[2], o[3], m[2], m[3]):.1f} % RMS; peaks "
              f"{1e3 * np.abs(m[3]).max():.1f} and {1e3 * np.abs(o[3]).max():.1f} mm")
    if len(chosen) == 2:
        (dm, sm), (do, so) = chosen["masonrydam"], chosen["opensees"]
        print(f"\nwithin {100 * RMS_TOLERANCE:g} % of its own finest run: masonrydam at dt = {dm:g} s in {sm:.2f} s, "
              f"OpenSees at dt = {do:g} s in {so:.2f} s: OpenSees takes {so / sm:.2f}x masonrydam's time")


if __name__ == "__main__":
    main()
