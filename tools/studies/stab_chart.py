#!/usr/bin/env python3
"""Chart of the Flow:stabilization study on the 2D EV drum (docs/granular.md,
"Stabilisation"): the surface speed (largest mid-chord speed,
tools/analysis/drum_analysis.py) against dr at t = 2.5, 5 and 10 s for monaghan
(alpha_av 3.162 at E 1e4 Pa, the alpha sqrt(E) rule) and riemann, from
docs/data/stabilization/drum_ev_runs.csv, beside the paper's DEM
surface speed (6 cm/s at 20 s, 7 at 40 s: paper §5.3, a later time than these).

  /usr/bin/python3 -m tools.studies.stab_chart [--csv CSV] [--png docs/data/stabilization/granular_stabilization.png]
"""
import argparse
import csv
import os

from tools import ROOT  # noqa: E402
DR = {"1": 1.0, "05": 0.5, "025": 0.25}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "data", "stabilization", "drum_ev_runs.csv"))
    ap.add_argument("--png", default=os.path.join(ROOT, "docs", "data", "stabilization", "granular_stabilization.png"))
    a = ap.parse_args()
    pts = {}  # (stab, t) -> {dr: speed}; the latest call wins (B after A)
    for r in csv.DictReader(open(a.csv)):
        run = r["run"]
        if run.endswith("s0") or run.endswith("e5") or run[0] not in "mrd":
            continue
        stab = {"m": "monaghan", "r": "riemann", "d": "delta"}[run[0]]
        pts.setdefault((stab, float(r["t_s"])), {})[DR[run[1:]]] = float(r["surface_speed_cm_s"])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4))
    style = {"monaghan": ("C0", "o"), "riemann": ("C3", "s"), "delta": ("C2", "^")}
    ls = {2.5: ":", 5.0: "-", 10.0: "--"}
    for (stab, t), d in sorted(pts.items()):
        if t not in ls:
            continue
        xs = sorted(d)
        c, m = style[stab]
        ax.plot(xs, [d[x] for x in xs], ls[t], color=c, marker=m, label="%s, t = %g s" % (stab, t))
    ax.axhspan(6.0, 7.0, color="0.85", label="paper's DEM, 20-40 s")
    ax.set_xscale("log", base=2)
    ax.set_xticks([0.25, 0.5, 1.0])
    ax.set_xticklabels(["0.25", "0.5", "1"])
    ax.invert_xaxis()
    ax.set_xlabel("dr (mm)")
    ax.set_ylabel("surface speed (cm/s)")
    ax.set_title("2D EV drum, E 1e4 Pa, chi 0.2: surface speed against resolution", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(a.png, dpi=120)
    print("wrote " + a.png)


if __name__ == "__main__":
    main()
