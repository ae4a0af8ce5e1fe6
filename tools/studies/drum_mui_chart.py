#!/usr/bin/env python3
"""The 2D EV drum's mid-chord speed profiles, SPH beside the finite-element
mu(I) reference (tools/analysis/drum_mui_ref.py), one panel per case
(docs/granular.md, "An independent mu(I) reference"):

  /usr/bin/python3 -m tools.studies.drum_mui_chart --png OUT.png \\
      --panel "5 rpm, drucker_prager;SPH dr 0.25 mm=A_prof.csv@4;FE mu(I)=fem5.csv" \\
      --panel "10 rpm, drucker_prager;SPH dr 0.25 mm=B_prof.csv@5;FE mu(I)=fem10.csv"

A panel is TITLE;ITEM;ITEM...; an item LABEL=CSV@T is an SPH profile of
`drum_analysis --profiles` (t, d_mc, speed: |u| against depth / R) at the
snapshot nearest T s, or the mean of the snapshots T1:T2 (LABEL=CSV@3:5, on
the first one's depths); an item LABEL=CSV without @ is a `drum_mui_ref
--profile` file (depth_m, u_x_m_per_s), drawn as |u_x| against depth / R
(--radius, default 0.035 m).
"""
import argparse

import numpy as np

from tools.analysis.midchord_chart import read_fem, read_profiles


def sph_profile(path, spec):
    prof = read_profiles(path)
    lo, hi = (float(v) for v in spec.split(":")) if ":" in spec else (float(spec), float(spec))
    ts = [t for t in sorted(prof) if lo - 0.25 <= t <= hi + 0.25] or [min(prof, key=lambda t: abs(t - lo))]
    d0 = np.array(prof[ts[0]][0])
    us = [np.interp(d0, np.array(prof[t][0]), np.array(prof[t][1])) for t in ts]
    return d0, np.mean(us, axis=0), ts


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--panel", action="append", required=True)
    ap.add_argument("--radius", type=float, default=0.035)
    ap.add_argument("--depth-max", type=float, default=0.35, help="the depth / R drawn (default 0.35)")
    ap.add_argument("--png", required=True)
    a = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, len(a.panel), figsize=(3.9 * len(a.panel), 4.2), sharey=True, squeeze=False)
    for q, spec in enumerate(a.panel):
        title, *items = spec.split(";")
        axq = ax[0][q]
        for i, it in enumerate(items):
            label, path = it.rsplit("=", 1)
            if "@" in path:
                path, t = path.rsplit("@", 1)
                d, u, ts = sph_profile(path, t)
                print("%-30s %-28s t %s: surface speed %.2f cm/s" % (title, label, ",".join("%g" % s for s in ts),
                                                                     np.nanmax(u)))
                axq.plot(u, d, color="C%d" % i, lw=1.6, label="%s (t = %s s)" % (label, t.replace(":", "–")))
            else:
                d, u = read_fem(path, a.radius)
                print("%-30s %-28s steady: surface speed %.2f cm/s" % (title, label, max(u)))
                axq.plot(u, d, color="k", ls="--", lw=1.4, label=label)
        axq.set_title(title, fontsize=10)
        axq.set_xlabel("speed on the mid-chord (cm/s)")
        axq.set_ylim(a.depth_max, 0)
        axq.grid(alpha=0.3)
        axq.legend(fontsize=7, loc="lower right")
    ax[0][0].set_ylabel(r"depth below the surface on the mid-chord, $d_{mc}/R$")
    fig.tight_layout()
    fig.savefig(a.png, dpi=120)
    print("wrote %s" % a.png)


if __name__ == "__main__":
    main()
