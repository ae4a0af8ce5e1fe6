#!/usr/bin/env python3
"""One DEM grain settling two ways (inputs/dem_settling.yml, the paper's box
12 x 12 x 20 dr, h = 8 mm) at several diameters d: its settling velocity v and
its speed relative to the fluid at it, v - u_f, against eq. (27)'s v_t (with
the run's eps at the grain), both as errors against h/d, the mean over
0.25-0.3 s; printed as a table and drawn as a chart (docs/validation.md "DEM
grains in a fluid"). Each run:

  sphseg inputs/dem_settling.yml -o DIR -P DEM:d=D -P DEM:coupling=two_way \\
      -P Flow:stabilization=monaghan -P Flow:alpha_av=0 -P Run:t_end=0.3 -P Output:dt=0.01

  /usr/bin/python3 -m tools.studies.dem_hd_chart D=DIR [D=DIR ...] --png OUT.png
"""
import argparse

import numpy as np

from tests.validate_dem_settling import grain, terminal

H = 0.008


def row(d, out):
    w = [x for x in grain(out) if x[0] >= 0.25 - 1e-9]
    v = -np.mean([x[1] for x in w])
    uf = -np.mean([x[3] for x in w])
    eps = np.mean([x[2] for x in w])
    vt = terminal(d, eps)
    return {"hd": H / d, "d": d, "eps": eps, "v": v, "uf": uf, "vt": vt, "ev": (v - vt) / vt, "er": (v - uf - vt) / vt}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="D=DIR: a run's grain diameter (m) and output folder")
    ap.add_argument("--png")
    a = ap.parse_args(argv)
    rows = sorted((row(float(r.split("=")[0]), r.split("=", 1)[1]) for r in a.runs), key=lambda r: r["hd"])
    print("| h/d | d (mm) | eps at the grain | v (m/s) | u_f at the grain, down (m/s) | eq. (27) v_t (m/s) | v | v - u_f |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print("| %.2f | %.2f | %.4f | %.5f | %.5f | %.5f | %+.1f %% | %+.1f %% |"
              % (r["hd"], 1e3 * r["d"], r["eps"], r["v"], r["uf"], r["vt"], 100 * r["ev"], 100 * r["er"]))
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(5.5, 3.6))
        hd = [r["hd"] for r in rows]
        ax.plot(hd, [100 * r["ev"] for r in rows], "o-", label="grain's velocity v")
        ax.plot(hd, [100 * r["er"] for r in rows], "s--", label="v relative to the fluid at it")
        ax.axhline(0, color="k", lw=0.8)
        ax.axvspan(2, max(hd) + 0.2, color="0.9", label="h >= 2 d (Robinson et al. 2014)")
        ax.set_xlabel("h / d (h = 8 mm)")
        ax.set_ylabel("error against eq. (27) (%)")
        ax.set_title("one grain settling, two-way coupling")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.png, dpi=120)


if __name__ == "__main__":
    main()
