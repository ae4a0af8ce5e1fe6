#!/usr/bin/env python3
"""The 3D drum without end walls (issue 57): a drum periodic along its axis against the 2D drum at the same dr.

  python3 -m tools.studies.periodic_drum commands [--dr 0.0014 0.001 0.0007] [--sphseg BIN] [--ensemble N]
  python3 -m tools.studies.periodic_drum table FILE... [--csv docs/data/drum/periodic_3d.csv]
  python3 -m tools.studies.periodic_drum chart [--csv ...] [--png docs/data/drum/periodic_3d.png]
  python3 -m tools.studies.periodic_drum axial OUT... [--from 2.5] [--flowing 0.02]

commands: the runs, one line each: the 2D EV scene (inputs/drum_2d_EV.yml) and the
same drum as a 3D container (its cylinder turning, a fill region to
H = (2 fill - 1) R, Geometry:dim 3, Geometry:periodic z over a depth of 24 dr,
no end walls), both at E 10 kPa, chi 0.2, with the scene's flow, to 5 s, each
followed by its drum_analysis (`--times 1 2 3 4 5`), and the walled R35 3D
drum (inputs/drum_3d.yml, length 0.07 m) for the end walls' effect. The 2D
container drum gives the built-in 2D drum's bits (tests/test_own_scene.sh
checks the particles; a 300-step comparison is in the CHANGELOG). Each line
writes its run's log to OUT.log and echoes the '=== LABEL: rc N' header that
table reads, so `commands ... | bash > FILE` makes table's input.
--ensemble N: the 2D drum alone, N runs a spacing whose step bound differs by
1e-4 of chi (Run:cfl_flow 0.2, 0.2001, ...), a perturbation far under the
discretisation's after which the runs part (the flow is chaotic): their spread
is what the means of one run carry.
table: each FILE holds '=== LABEL: rc ...' headers followed by that run's
drum_analysis output; the CSV gets, per run, the means over t = 3, 4, 5 s of
the mid-chord speed and the segregation index of the whole bed (projected along
z) and, in 3D, of the mid-length slab. Ensemble runs ('2D dr X run K') go to
the CSV's _spread file instead: per spacing the runs' count, and the mean and
sample standard deviation of the same means.
chart: speed and index against dr, 2D, periodic 3D and walled 3D, and, where
the spread file has a spacing, the 2D ensemble's mean with +-1 standard
deviation of one run.
axial: for each 3D run OUT, per snapshot from t = 2.5 s, the RMS of the axial
velocity u_z over the flowing material (in-plane speed above 2 cm/s) against
their in-plane RMS speed: how far the periodic drum's flow leaves the plane.
"""
import argparse
import csv
import os
import re
import sys

import numpy as np

from tools import ROOT
from tools.studies import batch

ROW = re.compile(r"^\s+([\d.]+)\s+([\d.]+)°\s+[\d.]+ dr\s+([\d.]+) cm/s\s+(-?[\d.]+)\s+([\d.]+)-([\d.]+)\s+([\d.]+) cm/s")
SLAB = re.compile(r"^\s+mid-length slab\s+([\d.]+)°\s+([\d.]+) cm/s\s+(-?[\d.]+)")
KEYS = "-P Material:E=1e4 -P Run:cfl_flow=0.2 -P Run:t_end=5 -P Output:dt=1"
T = (3.0, 4.0, 5.0)
CSV = os.path.join(ROOT, "docs", "data", "drum", "periodic_3d.csv")


def _line(label, cmd, out):
    """One run: sphseg's output to OUT.log, the header table reads, the analysis."""
    return (f"{cmd} > {out}.log 2>&1; echo '=== {label}: rc '$?; "
            f"python3 -m tools.analysis.drum_analysis {out} --times 1 2 3 4 5")


def commands(a):
    H = (2 * 0.42 - 1) * 0.035
    walls = "Container:walls=[{name: drum, shape: cylinder, centre: [0, 0], radius: 0.035, motion: turning, rpm: 5, " \
            "direction: clockwise}]"
    reg = "Container:regions=[{shape: fill, level: %.4g, C: 0.5}]" % H
    print("mkdir -p out/periodic")
    for dr in a.dr:
        if a.ensemble:
            for k in range(a.ensemble):
                out = "out/periodic/2d_%g_run%d" % (dr, k)
                keys = KEYS.replace("Run:cfl_flow=0.2", "Run:cfl_flow=%.4f" % (0.2 + 1e-4 * k))
                print(_line("2D dr %g run %d" % (dr, k),
                            f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {keys}", out))
            continue
        out = "out/periodic/2d_%g" % dr
        print(_line("2D dr %g" % dr, f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {KEYS}", out))
        out = "out/periodic/3d_%g" % dr
        print(_line("3D dr %g" % dr, f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {KEYS} "
                    f"-P Geometry:type=container -P Geometry:dim=3 -P Geometry:depth={24 * dr:.6g} "
                    f"-P Geometry:periodic=z -P '{walls}' -P '{reg}'", out))
    if not a.ensemble:
        out = "out/periodic/walled_0.0014"
        print(_line("walled 3D dr 0.0014", f"{a.sphseg} inputs/drum_3d.yml -o {out} -P Geometry:dr=0.0014 "
                    f"-P Geometry:length=0.07 {KEYS}", out))


def parse(text):
    runs, cur = {}, None
    for line in text.splitlines():
        m = re.match(r"=== (.*?): rc", line)
        if m:
            cur = m.group(1)
            runs[cur] = {"t": {}, "slab": [], "axial": False}
            continue
        if cur is None:
            continue
        if line.startswith("axial"):
            runs[cur]["axial"] = True
        m = ROW.match(line)
        if m and not runs[cur]["axial"] and float(m.group(1)) not in runs[cur]["t"]:
            runs[cur]["t"][float(m.group(1))] = (float(m.group(3)), float(m.group(4)))
        m = SLAB.match(line)
        if m:
            runs[cur]["slab"].append((float(m.group(2)), float(m.group(3))))
    return runs


def spread_path(path):
    return os.path.splitext(path)[0] + "_spread.csv"


def write_csv(path, rows):
    """rows (dicts of one set of keys) to path, floats to 4 digits."""
    batch.write_csv(path, list(rows[0]), [["%.4g" % v if isinstance(v, float) else v for v in r.values()]
                                          for r in rows])
    print("wrote %s (%d rows)" % (path, len(rows)))


def table(a):
    runs = {}
    for f in a.files:
        runs.update(parse(open(f).read()))
    rows, members = [], {}
    for label, r in sorted(runs.items()):
        m = re.match(r"(walled )?(\dD) dr ([\d.]+)( run \d+)?$", label)
        if not m or not all(t in r["t"] for t in T):
            print("skipped %s: not every time of %s" % (label, T), file=sys.stderr)
            continue
        speed, index = np.mean([r["t"][t][0] for t in T]), np.mean([r["t"][t][1] for t in T])
        if m.group(4):  # an ensemble member
            members.setdefault(float(m.group(3)) * 1e3, []).append((speed, index))
            continue
        kind = "walled 3D" if m.group(1) else ("periodic 3D" if m.group(2) == "3D" else "2D")
        slab = r["slab"][2:5] if len(r["slab"]) >= 5 else []
        rows.append({"kind": kind, "dr_mm": float(m.group(3)) * 1e3, "speed_cm_s": speed, "index": index,
                     "slab_speed_cm_s": np.mean([s[0] for s in slab]) if slab else "",
                     "slab_index": np.mean([s[1] for s in slab]) if slab else ""})
    if not rows and not members:
        sys.exit("no run with every time of %s in %s" % (T, " ".join(a.files)))
    if rows:
        write_csv(a.csv, rows)
    if members:
        spread = []
        for dr, v in sorted(members.items()):
            v = np.array(v)
            if len(v) < 2:
                sys.exit("dr %g mm: one ensemble run, no spread" % dr)
            spread.append({"kind": "2D", "dr_mm": dr, "runs": len(v), "speed_mean_cm_s": v[:, 0].mean(),
                           "speed_sd_cm_s": v[:, 0].std(ddof=1), "index_mean": v[:, 1].mean(),
                           "index_sd": v[:, 1].std(ddof=1)})
        write_csv(spread_path(a.csv), spread)


def chart(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = list(csv.DictReader(open(a.csv)))
    sd = {float(r["dr_mm"]): r for r in csv.DictReader(open(spread_path(a.csv)))} \
        if os.path.exists(spread_path(a.csv)) else {}
    fig, ax = plt.subplots(1, 2, figsize=(10, 5))
    for kind, col, mk in (("2D", "speed_cm_s", "o-"), ("periodic 3D", "slab_speed_cm_s", "s-"),
                          ("walled 3D", "slab_speed_cm_s", "^")):
        rs = sorted((r for r in rows if r["kind"] == kind), key=lambda r: float(r["dr_mm"]))
        if not rs:
            continue
        dr = [float(r["dr_mm"]) for r in rs]
        lab = kind + (" (mid-length slab)" if kind != "2D" else ", one run")
        ax[0].plot(dr, [float(r[col]) for r in rs], mk, label=lab)
        ax[1].plot(dr, [float(r[col.replace("speed_cm_s", "index")]) for r in rs], mk, label=lab)
    if sd:  # the 2D ensembles: their means with +-1 sample SD of one run, at every spacing the spread file has
        dr = sorted(sd)
        for k, (val, err) in enumerate((("speed_mean_cm_s", "speed_sd_cm_s"), ("index_mean", "index_sd"))):
            ax[k].errorbar(dr, [float(sd[d][val]) for d in dr], yerr=[float(sd[d][err]) for d in dr], fmt="D",
                           ms=4, color="C3", capsize=4, label="2D, mean of an ensemble +- one run's SD (%d-%d runs)"
                           % (min(int(sd[d]["runs"]) for d in dr), max(int(sd[d]["runs"]) for d in dr)))
    for k, lab in enumerate(("mid-chord surface speed, cm/s", "segregation index")):
        ax[k].set_xlabel("dr, mm")
        ax[k].set_ylabel(lab + "\n(means of t = 3, 4, 5 s)")
        ax[k].invert_xaxis()
        ax[k].grid(alpha=0.3)
    fig.suptitle("EV drum, E 10 kPa, chi 0.2, the scenes' flow: 2D against 3D without end walls "
                 "(machines: docs/validation.md)", fontsize=9)
    fig.legend(*ax[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


def axial(a):
    from tools.analysis import snap
    for out in a.outs:
        for path in snap.list_snapshots(out):
            s = snap.read_snapshot(path)
            u = np.asarray(s["Velocities"])
            if s["Time"] < a.t_from or u.ndim < 2 or u.shape[1] < 3:
                continue
            u = u[np.asarray(s["Kind"]) == snap.MATERIAL]
            sp = np.hypot(u[:, 0], u[:, 1])
            f = sp > a.flowing
            w, v = np.sqrt(np.mean(u[f, 2] ** 2)), np.sqrt(np.mean(sp[f] ** 2))
            print("%s t = %.2f s: %d flowing of %d, RMS u_z %.3g cm/s, in-plane %.3g cm/s, ratio %.3g"
                  % (out, s["Time"], f.sum(), len(u), 100 * w, 100 * v, w / v))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    c = sub.add_parser("commands")
    c.add_argument("--dr", type=float, nargs="+", default=[0.0014, 0.001, 0.0007])
    c.add_argument("--sphseg", default="build/sphseg")
    c.add_argument("--ensemble", type=int, default=0, metavar="N",
                   help="the 2D drum alone, N runs a spacing with chi 0.2 + 1e-4 k (k < N)")
    t = sub.add_parser("table")
    t.add_argument("files", nargs="+")
    t.add_argument("--csv", default=CSV)
    h = sub.add_parser("chart")
    h.add_argument("--csv", default=CSV)
    h.add_argument("--png", default=os.path.join(ROOT, "docs", "data", "drum", "periodic_3d.png"))
    x = sub.add_parser("axial")
    x.add_argument("outs", nargs="+")
    x.add_argument("--from", dest="t_from", type=float, default=2.5, help="first snapshot time read (s)")
    x.add_argument("--flowing", type=float, default=0.02, help="in-plane speed of the flowing material (m/s)")
    a = ap.parse_args()
    {"commands": commands, "table": table, "chart": chart, "axial": axial}[a.what](a)


if __name__ == "__main__":
    main()
