#!/usr/bin/env python3
"""The 3D drum without end walls (issue 57): a drum periodic along its axis against the 2D drum at the same dr.

  python3 -m tools.studies.periodic_drum commands [--dr 0.0014 0.001 0.0007] [--sphseg BIN]
  python3 -m tools.studies.periodic_drum table FILE... [--csv docs/data/drum/periodic_3d.csv]
  python3 -m tools.studies.periodic_drum chart [--csv ...] [--png docs/data/drum/periodic_3d.png]

commands: the runs, one line each: the 2D EV scene (inputs/drum_2d_EV.yml) and the
same drum as a 3D container (its cylinder turning, a fill region to
H = (2 fill - 1) R, Geometry:dim 3, Geometry:periodic z over a depth of 24 dr,
no end walls), both at E 10 kPa, chi 0.2, with the scene's flow, to 5 s, each
followed by its drum_analysis (`--times 1 2 3 4 5`), and the walled R35 3D
drum (inputs/drum_3d.yml, length 0.07 m) for the end walls' effect. The 2D
container drum gives the built-in 2D drum's bits (tests/test_own_scene.sh
checks the particles; a 300-step comparison is in the CHANGELOG).
table: each FILE holds '=== LABEL: rc ...' headers followed by that run's
drum_analysis output (as the commands write them); the CSV gets, per run, the
means over t = 3, 4, 5 s of the mid-chord speed and the segregation index of
the whole bed (projected along z) and, in 3D, of the mid-length slab.
chart: speed and index against dr, 2D, periodic 3D and walled 3D.
"""
import argparse
import csv
import os
import re
import sys

import numpy as np

from tools import ROOT

ROW = re.compile(r"^\s+([\d.]+)\s+([\d.]+)°\s+[\d.]+ dr\s+([\d.]+) cm/s\s+(-?[\d.]+)\s+([\d.]+)-([\d.]+)\s+([\d.]+) cm/s")
SLAB = re.compile(r"^\s+mid-length slab\s+([\d.]+)°\s+([\d.]+) cm/s\s+(-?[\d.]+)")
KEYS = "-P Material:E=1e4 -P Run:cfl_flow=0.2 -P Run:t_end=5 -P Output:dt=1"
T = (3.0, 4.0, 5.0)
CSV = os.path.join(ROOT, "docs", "data", "drum", "periodic_3d.csv")


def commands(a):
    H = (2 * 0.42 - 1) * 0.035
    walls = "Container:walls=[{name: drum, shape: cylinder, centre: [0, 0], radius: 0.035, motion: turning, rpm: 5, " \
            "direction: clockwise}]"
    reg = "Container:regions=[{shape: fill, level: %.4g, C: 0.5}]" % H
    for dr in a.dr:
        out = "out/periodic/2d_%g" % dr
        print(f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {KEYS}; "
              f"python3 -m tools.analysis.drum_analysis {out} --times 1 2 3 4 5")
        out = "out/periodic/3d_%g" % dr
        print(f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {KEYS} -P Geometry:type=container "
              f"-P Geometry:dim=3 -P Geometry:depth={24 * dr:.6g} -P Geometry:periodic=z -P '{walls}' -P '{reg}'; "
              f"python3 -m tools.analysis.drum_analysis {out} --times 1 2 3 4 5")
    print(f"{a.sphseg} inputs/drum_3d.yml -o out/periodic/walled_0.0014 -P Geometry:dr=0.0014 -P Geometry:length=0.07 "
          f"{KEYS}; python3 -m tools.analysis.drum_analysis out/periodic/walled_0.0014 --times 1 2 3 4 5")


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


def table(a):
    runs = {}
    for f in a.files:
        runs.update(parse(open(f).read()))
    rows = []
    for label, r in sorted(runs.items()):
        m = re.match(r"(walled )?(\dD) dr ([\d.]+)", label)
        if not m or not all(t in r["t"] for t in T):
            print("skipped %s: not every time of %s" % (label, T), file=sys.stderr)
            continue
        kind = "walled 3D" if m.group(1) else ("periodic 3D" if m.group(2) == "3D" else "2D")
        slab = r["slab"][2:5] if len(r["slab"]) >= 5 else []
        rows.append({"kind": kind, "dr_mm": float(m.group(3)) * 1e3,
                     "speed_cm_s": np.mean([r["t"][t][0] for t in T]), "index": np.mean([r["t"][t][1] for t in T]),
                     "slab_speed_cm_s": np.mean([s[0] for s in slab]) if slab else "",
                     "slab_index": np.mean([s[1] for s in slab]) if slab else ""})
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: ("%.4g" % v if isinstance(v, float) else v) for k, v in r.items()})
    print("wrote %s (%d rows)" % (a.csv, len(rows)))


def chart(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = list(csv.DictReader(open(a.csv)))
    fig, ax = plt.subplots(1, 2, figsize=(10, 4.2))
    for kind, col, mk in (("2D", "speed_cm_s", "o-"), ("periodic 3D", "slab_speed_cm_s", "s-"),
                          ("walled 3D", "slab_speed_cm_s", "^")):
        rs = sorted((r for r in rows if r["kind"] == kind), key=lambda r: float(r["dr_mm"]))
        if not rs:
            continue
        dr = [float(r["dr_mm"]) for r in rs]
        ax[0].plot(dr, [float(r[col]) for r in rs], mk, label=kind + (" (mid-length slab)" if kind != "2D" else ""))
        ax[1].plot(dr, [float(r[col.replace("speed_cm_s", "index")]) for r in rs], mk, label=kind)
    for k, lab in enumerate(("mid-chord surface speed, cm/s", "segregation index")):
        ax[k].set_xlabel("dr, mm")
        ax[k].set_ylabel(lab + "\n(means of t = 3, 4, 5 s)")
        ax[k].invert_xaxis()
        ax[k].grid(alpha=0.3)
        ax[k].legend(fontsize=8)
    fig.suptitle("EV drum, E 10 kPa, chi 0.2, the scenes' flow: 2D against 3D without end walls (one H200)", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    c = sub.add_parser("commands")
    c.add_argument("--dr", type=float, nargs="+", default=[0.0014, 0.001, 0.0007])
    c.add_argument("--sphseg", default="build/sphseg")
    t = sub.add_parser("table")
    t.add_argument("files", nargs="+")
    t.add_argument("--csv", default=CSV)
    h = sub.add_parser("chart")
    h.add_argument("--csv", default=CSV)
    h.add_argument("--png", default=os.path.join(ROOT, "docs", "data", "drum", "periodic_3d.png"))
    a = ap.parse_args()
    {"commands": commands, "table": table, "chart": chart}[a.what](a)


if __name__ == "__main__":
    main()
