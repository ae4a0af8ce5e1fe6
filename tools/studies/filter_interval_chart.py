#!/usr/bin/env python3
"""The 2D drum's surface speed against the Shepard filter's interval in acoustic
times (docs/granular.md "The time step and the Shepard filter").

The filter (3.12) runs every Flow:shepard_every = N steps. A step is
Run:cfl_flow = chi times the acoustic time h / c_s (where the sound speed
bounds it, as in the drums at E 0.1 MPa), so N chi is the filter's interval in
acoustic times: the same N filters twice as often per second at half the chi.

  /usr/bin/python3 -m tools.studies.filter_interval_chart --png OUT.png \
      --run "LABEL;N_CHI;RUN.ana[;TMIN[;TMAX]]" [--run ...]

Each --run is one `drum_analysis` output (its table of snapshots, column "top
grains u"), with the run's interval N chi (0 = the filter off, drawn at the
right edge) and the snapshots' time window (default t >= 2.5 s). Prints, per
run, the mean of the top grains' speed over the window, its standard error
(the snapshots' spread over sqrt(n)) and its ratio to the first run; draws
the means against N chi, one series per label prefix before ':' (e.g.
"dr 0.5 mm: cfl 0.05").
"""
import argparse
import math

import numpy as np

from tools.analysis.drum_analysis import read_window  # noqa: E402


def top_grains(path, tmin=2.5, tmax=math.inf):
    """(t, top grains u in cm/s) of the snapshots of a drum_analysis output in [tmin, tmax]."""
    return np.array([(r[0], r[4]) for r in read_window(path, tmin, tmax)])


def parse_run(spec):
    parts = spec.split(";")
    if len(parts) < 3:
        raise SystemExit(f"--run {spec!r}: expected LABEL;N_CHI;RUN.ana[;TMIN[;TMAX]]")
    tmin = float(parts[3]) if len(parts) > 3 else 2.5
    tmax = float(parts[4]) if len(parts) > 4 else math.inf
    return parts[0], float(parts[1]), parts[2], tmin, tmax


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", action="append", required=True, help="LABEL;N_CHI;RUN.ana[;TMIN[;TMAX]]")
    ap.add_argument("--png", help="write the chart here (needs matplotlib)")
    ap.add_argument("--title",
                    default="2D drums at 5 rpm, E 0.1 MPa: surface speed against the Shepard filter's interval")
    a = ap.parse_args(argv)
    runs = []
    for spec in a.run:
        label, nchi, path, tmin, tmax = parse_run(spec)
        r = top_grains(path, tmin, tmax)
        u = r[:, 1]
        se = u.std(ddof=1) / math.sqrt(len(u)) if len(u) > 1 else float("nan")
        runs.append((label, nchi, u.mean(), se, len(u), r[0, 0], r[-1, 0]))
    ref = runs[0][2]
    print(f"{'run':34s} {'N chi':>6s} {'t (s)':>9s} {'n':>2s} {'top grains (cm/s)':>18s} {'/ first':>8s}")
    for label, nchi, m, se, n, t0, t1 in runs:
        iv = "off" if nchi == 0 else f"{nchi:g}"
        print(f"{label:34s} {iv:>6s} {t0:4.1f}-{t1:<4.1f} {n:2d} {m:9.3f} +- {se:5.3f} {m / ref:8.4f}")
    if not a.png:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    finite = [r[1] for r in runs if r[1] > 0]
    off_x = 2 * max(finite) if finite else 1.0
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    series = {}
    for label, nchi, m, se, n, t0, t1 in runs:
        series.setdefault(label.split(":")[0], []).append((nchi if nchi > 0 else off_x, m, se, label))
    for k, (name, pts) in enumerate(series.items()):
        pts.sort()
        x = [p[0] for p in pts]
        y = [p[1] for p in pts]
        e = [p[2] for p in pts]
        ax.errorbar([xx * (1 + 0.03 * k) for xx in x], y, yerr=e, marker="o", capsize=3, label=name)
        seen = {}
        for xx, yy, _, lab in pts:  # runs at one interval: their labels stacked
            n = seen[xx] = seen.get(xx, -1) + 1
            ax.annotate(lab.split(":", 1)[-1].strip(), (xx * (1 + 0.03 * k), yy), textcoords="offset points",
                        xytext=(6, -10 + 11 * n), fontsize=7)
    ax.set_xscale("log")
    ticks = sorted(set(finite)) + [off_x]
    ax.set_xticks(ticks)
    ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
    ax.set_xticklabels([f"{t:g}" for t in ticks[:-1]] + ["off"])
    ax.set_xlabel("filter interval N chi (acoustic times h / c_s)")
    ax.set_ylabel("top grains' speed (cm/s), mean +- s.e.")
    ax.set_title(a.title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print(f"wrote {a.png}")


if __name__ == "__main__":
    main()
