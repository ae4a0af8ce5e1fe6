#!/usr/bin/env python3
"""The plane Couette layer (inputs/couette_2d.yml) against dr under the two mu(I)
laws at low I, from the tables of tools/analysis/couette.py: per run the mean
and spread over its snapshots of tau / tau_ref(U), of the flux over the
reference's and of the depth where u falls to 5 % of U less the reference's,
printed as a table and drawn as a chart (docs/granular.md "The base alone").

  /usr/bin/python3 -m tools.studies.couette_chart TABLE [TABLE ...] --png OUT.png

A run's law is read from its name: runs named p... are Material:mu_law partial,
the others regularized (docs/data/stabilization/couette/README.md).
"""
import argparse
from collections import OrderedDict

import numpy as np

from tools.analysis import couette as cu  # noqa: E402

LADDER = 0.0005 / 2.0 ** np.arange(6)  # the study's spacings; the older tables print dr to 3 decimals in mm


def summarise(paths):
    runs = OrderedDict()
    for p in paths:
        for r in cu.read_table(p):
            runs.setdefault(r["run"], []).append(r)
    out = []
    for name, rs in runs.items():
        dr = float(LADDER[np.argmin(np.abs(LADDER - rs[0]["dr"]))])
        g = {k: np.array([r[k] for r in rs]) for k in ("ratio", "flux")}
        g["dz5"] = np.array([r["z5"] - r["z5_ref"] for r in rs])
        out.append({"run": name, "law": "partial" if name.startswith("p") else "regularized", "dr": dr, "n": len(rs),
                    **{k + "_m": float(v.mean()) for k, v in g.items()}, **{k + "_s": float(v.std()) for k, v in g.items()}})
    return sorted(out, key=lambda r: (r["law"], -r["dr"]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("tables", nargs="+")
    ap.add_argument("--png")
    a = ap.parse_args(argv)
    rows = summarise(a.tables)
    print("%-10s %-11s %7s %3s %17s %17s %22s" % ("run", "law", "dr mm", "n", "tau/tau_ref", "flux/ref",
                                               "5%U depth - ref, mm"))
    for r in rows:
        print("%-10s %-11s %7.4f %3d %9.4f +- %.4f %9.4f +- %.4f %12.3f +- %.3f" % (
            r["run"], r["law"], 1e3 * r["dr"], r["n"], r["ratio_m"], r["ratio_s"], r["flux_m"], r["flux_s"],
            1e3 * r["dz5_m"], 1e3 * r["dz5_s"]))
    if not a.png:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    for law, mk in (("regularized", "o-"), ("partial", "s--")):
        rs = [r for r in rows if r["law"] == law]
        x = [1e3 * r["dr"] for r in rs]
        for i, (key, scale) in enumerate((("ratio", 1), ("flux", 1), ("dz5", 1e3))):
            ax[i].errorbar(x, [scale * r[key + "_m"] for r in rs], yerr=[scale * r[key + "_s"] for r in rs], fmt=mk,
                           capsize=3, label="mu_law %s" % law)
    for i, (lab, ref) in enumerate((("tau / tau_ref(U)", 1), ("flux / reference's", 1),
                                    ("depth of u = 5 % U - reference's (mm)", 0))):
        ax[i].axhline(ref, color="k", lw=0.8)
        ax[i].set_xscale("log", base=2)
        ax[i].set_xlabel("dr (mm)")
        ax[i].set_ylabel(lab)
        ax[i].invert_xaxis()
        ax[i].grid(alpha=0.3)
    ax[0].legend()
    fig.suptitle("Plane Couette layer with a yield base (inputs/couette_2d.yml) against the local mu(I) rheology; "
                 "means over t = 0.3-0.5 s", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


if __name__ == "__main__":
    main()
