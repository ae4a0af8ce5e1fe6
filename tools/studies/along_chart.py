#!/usr/bin/env python3
"""The 2D drum's surface grains along the surface at two or more spacings: where
along the chord the speed changes with dr (docs/granular.md "Along the surface").

  /usr/bin/python3 -m tools.studies.along_chart [--png OUT.png] [--from T0] [--to T1] \
      --run "LABEL;DR_MM;RUN_along.csv" --run ...

Each --run is one `drum_analysis --along` file with its spacing in mm; the
snapshots in [T0, T1] (default 2.5 s to the end) are averaged per bin of 0.1 R
along the fitted surface line (s / R, growing with x: downslope in the
clockwise drums). Prints per bin each run's speed (cm/s) with its standard error
over the snapshots, each later run's ratio to the first, and each run's height
of the surface above the fitted line in mm (the surface's shape); draws the
speeds, the ratios and the heights against s / R.
"""
import argparse
import math

from tools.analysis.drum_analysis import read_along  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", action="append", required=True, help="LABEL;DR_MM;RUN_along.csv")
    ap.add_argument("--from", dest="t0", type=float, default=2.5)
    ap.add_argument("--to", dest="t1", type=float, default=math.inf)
    ap.add_argument("--png")
    a = ap.parse_args(argv)
    runs = []
    for spec in a.run:
        parts = spec.split(";")
        if len(parts) != 3:
            raise SystemExit(f"--run {spec!r}: expected LABEL;DR_MM;RUN_along.csv")
        runs.append((parts[0], float(parts[1]), read_along(parts[2], a.t0, a.t1)))
    bins = sorted(set.intersection(*[set(r[2]) for r in runs]))
    head = " s/R  " + " ".join(f"{lab[:16]:>16s}" for lab, _, _ in runs)
    head += " " + " ".join(f"{'ratio':>10s}" for _ in runs[1:])
    head += " " + " ".join(f"{'h mm, ' + lab[:10]:>16s}" for lab, _, _ in runs)
    print(f"snapshots in [{a.t0:g}, {a.t1:g}] s: " + ", ".join(f"{lab} {r[bins[0]][4]}" for lab, _, r in runs))
    print(head)
    for b in bins:
        line = f"{runs[0][2][b][0]:5.2f} "
        line += " ".join(f"{100 * r[b][1]:8.2f} +- {100 * r[b][2]:4.2f}" for _, _, r in runs)
        line += " " + " ".join(f"{r[b][1] / runs[0][2][b][1]:10.3f}" for _, _, r in runs[1:])
        line += " " + " ".join(f"{r[b][3] * dr:16.2f}" for _, dr, r in runs)
        print(line)
    if not a.png:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(3, 1, figsize=(7.5, 8.5), sharex=True)
    for lab, dr, r in runs:
        s = [r[b][0] for b in bins]
        ax[0].errorbar(s, [100 * r[b][1] for b in bins], yerr=[100 * r[b][2] for b in bins], marker="o", ms=3,
                       capsize=2, label=lab)
        ax[2].plot(s, [r[b][3] * dr for b in bins], marker="o", ms=3, label=lab)
    for lab, dr, r in runs[1:]:
        ax[1].plot([r[b][0] for b in bins], [r[b][1] / runs[0][2][b][1] for b in bins], marker="o", ms=3,
                   label=f"{lab} / {runs[0][0]}")
    ax[1].axhline(1.03, color="grey", ls=":", lw=1, label="+3 % (issue 30's target)")
    ax[0].set_ylabel("surface grains' speed (cm/s)")
    ax[1].set_ylabel("ratio")
    ax[2].set_ylabel("height above the fitted line (mm)")
    ax[2].set_xlabel("s / R along the surface (downslope to the right)")
    for x in ax:
        x.grid(alpha=0.3)
        x.legend(fontsize=8)
    ax[0].set_title(f"2D EV drum, 5 rpm, E 0.1 MPa: the surface along the chord, t = {a.t0:g}-{a.t1:g} s",
                    fontsize=10)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print(f"wrote {a.png}")


if __name__ == "__main__":
    main()
