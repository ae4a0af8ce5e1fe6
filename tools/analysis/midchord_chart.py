#!/usr/bin/env python3
"""Mid-chord speed profiles of several drum runs side by side, one panel per
time, beside the values the paper's text gives for its DEM reference:

  python3 -m tools.analysis.midchord_chart --run "EV, dr 0.5 mm=A.csv" --run "EV, dr 0.25 mm=B.csv" \\
      --times 20 30 40 --png OUT.png [--dem-ev] [--table]

Each CSV is a `drum_analysis --profiles` file (t, d_mc/R, speed m/s, shear
rate, C). --dem-ev marks the surface speeds of the EV drum's DEM as Zhu, Peng
& Wu (2024, §6.2, text to figures 20-21) state them: "around 6 cm/s at t = 20
s to 7 cm/s at t = 40 s" (at d_mc = 0; the figures' scattered DEM points are
not given as numbers). --fem LABEL=CSV adds a steady profile of the
finite-element mu(I) reference (tools/analysis/drum_mui_ref.py --profile:
depth_m, u_x_m_per_s; drawn in every panel, its |u_x| against depth / R, R
from --radius, default 0.035 m). --table prints each run's largest speed on
the mid-chord (the surface speed of drum_analysis) per time.
"""
import argparse
import csv
from collections import defaultdict

DEM_EV_SURFACE = {20.0: 6.0, 40.0: 7.0}  # cm/s, paper §6.2 text


def read_profiles(path):
    """{t: (d_mc list, speed cm/s list)} of one --profiles CSV."""
    out = defaultdict(lambda: ([], []))
    with open(path) as f:
        for r in csv.DictReader(f):
            d, u = out[round(float(r["t"]), 3)]
            if d and float(r["d_mc"]) <= d[-1]:  # a second profile of the same time: keep the first
                continue
            d.append(float(r["d_mc"]))
            u.append(100 * float(r["speed"]) if r["speed"] not in ("nan", "") else float("nan"))
    return dict(out)


def read_fem(path, radius):
    """(depth / R list, |u_x| cm/s list) of one drum_mui_ref --profile CSV."""
    from tools.analysis.drum_fe_read import read_profile
    depth, u, _ = read_profile(path)
    return list(depth / radius), list(100 * abs(u))


def nearest(prof, t):
    k = min(prof, key=lambda s: abs(s - t))
    return k, prof[k]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", action="append", required=True, help="LABEL=CSV (drum_analysis --profiles)")
    ap.add_argument("--times", type=float, nargs="+", default=[20, 30, 40])
    ap.add_argument("--png")
    ap.add_argument("--dem-ev", action="store_true", help="mark the EV drum's DEM surface speeds of the paper's text")
    ap.add_argument("--fem", action="append", default=[], help="LABEL=CSV (drum_mui_ref --profile), steady")
    ap.add_argument("--radius", type=float, default=0.035, help="the drum's radius for --fem, m")
    ap.add_argument("--table", action="store_true")
    a = ap.parse_args()
    fems = [(spec.rsplit("=", 1)[0], read_fem(spec.rsplit("=", 1)[1], a.radius)) for spec in a.fem]
    runs = []
    for spec in a.run:
        label, path = spec.rsplit("=", 1)
        runs.append((label, read_profiles(path)))
    if a.table:
        print("%-34s" % "run" + "".join("%10s" % ("t=%gs" % t) for t in a.times))
        for label, prof in runs:
            row = []
            for t in a.times:
                k, (_, u) = nearest(prof, t)
                row.append("%10.2f" % max(v for v in u if v == v) if abs(k - t) < 0.5 else "%10s" % "-")
            print("%-34s" % label + "".join(row))
        for label, (_, u) in fems:
            print("%-34s" % label + "".join("%10.2f" % max(u) for _ in a.times))
        if a.dem_ev:
            print("%-34s" % "DEM (EV), paper's text" + "".join(
                "%10s" % ("%.1f" % DEM_EV_SURFACE[t] if t in DEM_EV_SURFACE else "-") for t in a.times))
    if not a.png:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, len(a.times), figsize=(3.8 * len(a.times), 4.0), sharey=True, squeeze=False)
    for q, t in enumerate(a.times):
        axq = ax[0][q]
        for i, (label, prof) in enumerate(runs):
            k, (d, u) = nearest(prof, t)
            if abs(k - t) < 0.5:
                axq.plot(u, d, color="C%d" % i, ls="-" if i % 2 == 0 else "--", label=label)
        for i, (label, (d, u)) in enumerate(fems):
            axq.plot(u, d, color="k", ls=[":", "-.", "--"][i % 3], lw=1.5, label=label)
        if a.dem_ev and t in DEM_EV_SURFACE:
            axq.plot([DEM_EV_SURFACE[t]], [0.0], "k*", ms=12, label="DEM surface (EV), paper's text")
        axq.set_title("t = %g s" % t, fontsize=10)
        axq.set_xlabel("speed |u| on the mid-chord (cm/s)")
        axq.grid(alpha=0.3)
    ax[0][0].set_ylabel(r"mid-chord depth $d_{mc}/R$")
    ax[0][0].invert_yaxis()
    ax[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.png, dpi=120)
    print("wrote %s" % a.png)


if __name__ == "__main__":
    main()
