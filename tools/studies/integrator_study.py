"""Run:integrator: the leapfrog (one flow evaluation a step) against the
predictor-corrector (two), issue 56 item 3.

  python3 -m tools.studies.integrator_study oscillator
      the growth factor a step of both schemes on the linear wave u' = -w s,
      s' = w u (no run; the numbers src/sim/integrate.c quotes);
  python3 -m tools.studies.integrator_study run --out DIR [--sphseg build/sphseg] [--backend cpu|gpu]
        [--size small|gpu] [--jobs N]
      (a) the stability limit in chi (Run:cfl_flow) of each integrator on a 2D
      drum (raised until exit 3, a non-finite state, or the kinetic energy
      grows to ten times the predictor-corrector's at chi 0.1), and in
      Run:cfl_diffusion on the shear box (C alone: the leapfrog's bound is
      halved, integrate_dt); (b) both integrators at the same settings on the
      2D EV and EN drums, the chute and the shear box. --size small: dr 2.5 mm
      drums for 0.5 s, minutes on a laptop; gpu: the drums at their shipped dr
      with Run:preset converged for 2 s (tools/studies/integrator_device.sh);
  python3 -m tools.studies.integrator_study analyze --out DIR
      DIR/integrator.csv (one row a case: steps, dt, steps/s, wall, the
      measured quantity) and DIR/integrator_accuracy.csv (leapfrog against
      predictor-corrector: surface speed and segregation index of the drums,
      the chute's mean speed, the shear box's largest |dC|; the relative
      difference), and DIR/integrator.png.
"""
import argparse
import csv
import os
import sys

import numpy as np

from tools import ROOT
from tools.studies import batch

INTS = ("predictor_corrector", "leapfrog")
SC = lambda n: os.path.join(ROOT, "inputs", n)  # noqa: E731


def growth(z, scheme, c=0.0):
    """Largest |eigenvalue| of one step on u' = -w s - c w u, s' = w u at z = w dt."""
    A = np.array([[-c, -1.0], [1.0, 0.0]]) * z
    if scheme == "predictor_corrector":
        return max(abs(np.linalg.eigvals(np.eye(2) + A + A @ A / 2)))
    # leapfrog: state (y, r), r the stored corrector rate: y' = y + A (y + r/2), r' = A (y + r/2)
    M = np.block([[np.eye(2) + A, A / 2], [A, A / 2]])
    return max(abs(np.linalg.eigvals(M)))


def oscillator():
    print("z = w dt   growth a step: predictor_corrector  leapfrog   (damping c = 0, then 0.2)")
    for c in (0.0, 0.2):
        for z in (0.05, 0.1, 0.3, 0.5, 0.8, 1.0):
            print("c %.1f z %.2f   %.7f   %.7f" % (c, z, growth(z, INTS[0], c), growth(z, INTS[1], c)))
        lim = [min(z for z in np.arange(0.01, 3.0, 0.01) if growth(z, i, c) > 1 + 1e-12) for i in INTS]
        print("c %.1f stable below w dt = %.2f (predictor_corrector), %.2f (leapfrog)" % (c, lim[0], lim[1]))


def cases(size):
    out = []
    if size == "small":
        drum = ["Geometry:dr=0.0025", "Material:E=1e5", "Run:t_end=0.5", "Output:dt=0.25", "Run:progress_s=1e9"]
        chis = (0.1, 0.2, 0.3, 0.4, 0.6, 0.8)
        stab = ["Geometry:dr=0.0025", "Material:E=1e5", "Run:t_end=0.1", "Output:dt=0.1", "Run:progress_s=1e9"]
    else:
        drum = ["Run:preset=converged", "Run:t_end=2", "Output:dt=1", "Run:progress_s=1e9"]
        chis = (0.2, 0.3, 0.4, 0.6)
        stab = ["Run:preset=converged", "Run:t_end=0.2", "Output:dt=0.2", "Run:progress_s=1e9"]
    for i in INTS:
        I = {"Run:integrator": i}
        o = lambda lst: dict(kv.split("=", 1) for kv in lst)  # noqa: E731
        for chi in chis:
            out.append(batch.Case("stab_drum_%s_%g" % (i, chi), SC("drum_2d_EV.yml"),
                                  {**o(stab), **I, "Run:cfl_flow": chi}, kind="stab", integ=i, chi=chi))
        for cd in (0.05, 0.1, 0.14, 0.2, 0.3):
            out.append(batch.Case("stab_box_%s_%g" % (i, cd), SC("shearbox_2d.yml"),
                                  {"Geometry:dr": 0.00348, "Run:t_end": 13, "Output:dt": 13, "Run:cfl_diffusion": cd,
                                   "Run:progress_s": 1e9, **I}, kind="stab_box", integ=i, chi=cd))
        for d in ("EV", "EN"):
            out.append(batch.Case("drum_%s_%s" % (d, i), SC("drum_2d_%s.yml" % d), {**o(drum), **I},
                                  kind="drum", integ=i))
        out.append(batch.Case("chute_%s" % i, SC("chute_2d.yml"), {"Run:t_end": 0.2 if size == "small" else 1.0,
                                                                  "Run:progress_s": 1e9, **I}, kind="chute", integ=i))
        out.append(batch.Case("box_%s" % i, SC("shearbox_2d.yml"), {"Geometry:dr": 0.00348, "Run:t_end": 52,
                                                                    "Output:dt": 13, "Run:progress_s": 1e9, **I},
                              kind="box", integ=i))
    return out


def last_material(d):
    from tools.analysis import snap
    paths = snap.list_snapshots(d)
    if not paths:
        return None
    s = snap.read_snapshot(paths[-1])
    m = s["Kind"] == snap.MATERIAL
    o = np.argsort(s["ParticleIDs"][m])
    return {k: s[k][m][o] for k in ("Coordinates", "Velocities", "Concentration")}, s


def measure(out, name, kind):
    """The case's measured quantities (dict), from its output folder."""
    d = os.path.join(out, name)
    r = {}
    try:
        diag = np.genfromtxt(os.path.join(d, "diagnostics.csv"), delimiter=",", names=True)
        r["dt_last"] = float(diag["dt"][-1])
        r["ke_max"] = float(np.nanmax(diag["kinetic_energy"]))
        r["t_end"] = float(diag["time"][-1])
    except (OSError, ValueError, IndexError):
        return r
    if kind == "drum":
        from tools.analysis import drum_analysis as da
        from tools.analysis import snap
        par = da.used_params(d)
        dr = da.Drum(snap.list_snapshots(d)[-1], par)
        r["surface_speed"], r["segregation_index"] = dr.surface_speed(), dr.segregation_index()
    if kind == "chute":  # the layer's mean downslope speed (the profile's integral, tools/analysis/chute_profile.py)
        got = last_material(d)
        if got:
            r["mean_speed"] = float(np.mean(got[0]["Velocities"][:, 0]))
    return r


def analyze(out):
    runs = {}
    with open(os.path.join(out, "runs.csv")) as f:
        for row in csv.DictReader(f):
            runs[row["name"]] = row
    rows = []
    for name, row in sorted(runs.items()):
        kind = row.get("kind", "")
        m = measure(out, name, kind) if str(row["rc"]) == "0" else {}
        steps, wall = row.get("steps") or "", row.get("sphseg_wall_s") or ""
        sps = float(steps) / float(wall) if steps and wall and float(wall) > 0 else ""
        rows.append(dict(name=name, kind=kind, integrator=row.get("integ", ""), chi=row.get("chi", ""), rc=row["rc"],
                         steps=steps, wall_s=wall, steps_per_s=sps, **m))
    keys = sorted({k for r in rows for k in r}, key=lambda k: (k not in ("name", "kind", "integrator", "chi", "rc"), k))
    with open(os.path.join(out, "integrator.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    by = {r["name"]: r for r in rows}
    acc = []
    for base, qs in (("drum_EV_%s", ("surface_speed", "segregation_index")),
                     ("drum_EN_%s", ("surface_speed", "segregation_index")), ("chute_%s", ("mean_speed",))):
        a, b = by.get(base % INTS[0], {}), by.get(base % INTS[1], {})
        for q in qs:
            if q in a and q in b:
                rel = abs(b[q] - a[q]) / max(abs(a[q]), 1e-30)
                acc.append(dict(case=base % "", quantity=q, pc=a[q], leapfrog=b[q], rel_diff=rel,
                                speedup_steps_per_s=(b["steps_per_s"] / a["steps_per_s"]
                                                     if a.get("steps_per_s") and b.get("steps_per_s") else "")))
    ga, gb = last_material(os.path.join(out, "box_" + INTS[0])), last_material(os.path.join(out, "box_" + INTS[1]))
    if ga and gb:
        acc.append(dict(case="box", quantity="max |dC|", pc=0.0,
                        leapfrog=float(np.abs(ga[0]["Concentration"] - gb[0]["Concentration"]).max()),
                        rel_diff=float(np.abs(ga[0]["Concentration"] - gb[0]["Concentration"]).max()),
                        speedup_steps_per_s=""))
    with open(os.path.join(out, "integrator_accuracy.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["case", "quantity", "pc", "leapfrog", "rel_diff", "speedup_steps_per_s"])
        w.writeheader()
        w.writerows(acc)
    for r in acc:
        print("%-10s %-18s pc %.6g  leapfrog %.6g  rel %.3e  speed-up %s" % (
            r["case"], r["quantity"], r["pc"], r["leapfrog"], r["rel_diff"], r["speedup_steps_per_s"]))
    chart(out, rows, acc)


def chart(out, rows, acc):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for i, mk in zip(INTS, "os"):
        st = sorted((float(r["chi"]), 1 if str(r["rc"]) == "0" else 0) for r in rows
                    if r["kind"] == "stab" and r["integrator"] == i)
        if st:
            ax[0].plot([s[0] for s in st], [s[1] for s in st], mk + "-", label=i)
    ax[0].set_xlabel("Run:cfl_flow (chi)")
    ax[0].set_ylabel("ran to t_end (1) or blew up (0)")
    ax[0].set_title("2D drum: stability in chi")
    ax[0].legend()
    if acc:
        ax[1].bar(range(len(acc)), [max(a["rel_diff"], 1e-12) for a in acc])
        ax[1].set_xticks(range(len(acc)))
        ax[1].set_xticklabels(["%s\n%s" % (a["case"], a["quantity"]) for a in acc], fontsize=7, rotation=30)
        ax[1].set_yscale("log")
        ax[1].axhline(0.01, color="k", ls="--", lw=0.8)
        ax[1].set_title("leapfrog against predictor-corrector")
        ax[1].set_ylabel("relative difference")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "integrator.png"), dpi=110)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=("oscillator", "run", "analyze"))
    ap.add_argument("--out", default="out/integrator_study")
    ap.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    ap.add_argument("--backend", default=None)
    ap.add_argument("--size", choices=("small", "gpu"), default="small")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--deadline", type=float, default=None, help="wall s for all the runs")
    a = ap.parse_args(argv)
    if a.what == "oscillator":
        return oscillator()
    if a.what == "run":
        batch.run_all(cases(a.size), a.sphseg, a.out, backend=a.backend, jobs=a.jobs, limit_s=480,
                      deadline_s=a.deadline)
        return analyze(a.out)
    return analyze(a.out)


if __name__ == "__main__":
    sys.exit(main())
