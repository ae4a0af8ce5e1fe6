#!/usr/bin/env python3
"""The 2D drum's flowing layer against its mass depth: SPH at several spacings
beside the finite-element mu(I) reference (docs/granular.md "The layer point by
point").

  /usr/bin/python3 -m tools.studies.layer_fe_chart --fe FE_prof.csv --png OUT.png \
      --run "LABEL=A_particles.csv,B_particles.csv" [--run ...] [--d 0.000375] [--rho-s 2500] [--table FILE]

Each --run is one or more `drum_layer --stress` particle files (zeta, u_t, p,
gdot, ...) whose profiles are averaged on a common zeta grid (several
snapshots of one run). --fe is `drum_mui_ref --profile` (depth, u, p). Three
panels against the depth zeta: the speed along the surface; the SPH's speed
over the FE's less one; the SPH's inertial number I = gdot d / sqrt(p / rho_s)
(d: the grain size, the FE's well-mixed 0.375 mm for a run without
segregation) with the lower edge of mu(I)'s well-posed window (Barker et al.
2015; tools/analysis/inertial_range.py) and the ill-posed band below it (--partial: the band where the partially regularised
law of Material:mu_law partial applies, well posed).
"""
import argparse
import warnings

import numpy as np

from tools.analysis import inertial_range as ir  # noqa: E402
from tools.analysis.drum_fe_read import read_profile  # noqa: E402


def average(paths, grid):
    cols = {}
    for path in paths:
        a = np.genfromtxt(path, delimiter=",", names=True)
        for k in ("u_t", "p", "gdot"):
            cols.setdefault(k, []).append(np.interp(grid, a["zeta"], a[k], left=np.nan, right=np.nan))
    with warnings.catch_warnings():  # past a run's deepest bin every file is NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        return {k: np.nanmean(v, axis=0) for k, v in cols.items()}


def binned(grid, u, lo, hi):
    """The mean of u over the grid points in [lo, hi), in cm/s (nan where none)."""
    m = (grid >= lo) & (grid < hi) & ~np.isnan(u)
    return "%.3f" % (100 * u[m].mean()) if m.any() else "nan"


def write_table(path, rows):
    """One line per zeta bin: the bin, then each column (the runs, the FE)."""
    with open(path, "w") as f:
        f.write("# speed along the surface (cm/s), the mean over each bin of mass depth zeta\n")
        f.write(" | ".join(label for label, _ in rows) + "\n")
        for i in range(len(rows[0][1])):
            f.write(" | ".join(col[i] for _, col in rows) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fe", required=True, help="drum_mui_ref --profile CSV")
    ap.add_argument("--run", action="append", required=True, help="LABEL=CSV[,CSV...] (drum_layer particle files)")
    ap.add_argument("--png", required=True)
    ap.add_argument("--d", type=float, default=0.000375, help="grain size in I, m (default 0.000375)")
    ap.add_argument("--rho-s", type=float, default=2500.0, help="grain density in I (default 2500)")
    ap.add_argument("--zmax", type=float, default=0.009, help="deepest zeta drawn, m (default 0.009)")
    ap.add_argument("--partial", action="store_true",
                    help="the runs and the FE use Material:mu_law partial: below I_N1 the partially regularised "
                         "law, well posed (the band is labelled so)")
    ap.add_argument("--title", default=None, help="a title over the three panels")
    ap.add_argument("--table", default=None,
                    help="also write each run's speed and the FE's, averaged over 1-mm bins of zeta, to this file")
    a = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    zf, uf, _ = read_profile(a.fe)
    grid = np.linspace(0.0, a.zmax, 181)
    lo, _ = ir.window(0.382, 0.682, 0.279)
    fig, ax = plt.subplots(1, 3, figsize=(13, 4.6), sharey=True)
    ax[0].plot(100 * uf[zf <= a.zmax], 1e3 * zf[zf <= a.zmax], "k-", lw=2, label="FE mu(I)")
    ufe = np.interp(grid, zf, uf)
    edges = np.arange(0.0, a.zmax + 1e-9, 1e-3)
    bins = list(zip(edges[:-1], edges[1:]))
    rows = [("zeta (mm)", ["%g-%g" % (1e3 * lo_, 1e3 * hi) for lo_, hi in bins])]
    for spec in a.run:
        label, files = spec.split("=", 1)
        r = average(files.split(","), grid)
        rows.append((label, [binned(grid, r["u_t"], lo_, hi) for lo_, hi in bins]))
        ok = ~np.isnan(r["u_t"])
        ax[0].plot(100 * r["u_t"][ok], 1e3 * grid[ok], ".-", ms=3, label=label)
        rel = np.where(np.abs(ufe) > 0.01 * np.abs(uf).max(), r["u_t"] / ufe - 1, np.nan)
        ax[1].plot(100 * rel[ok], 1e3 * grid[ok], ".-", ms=3, label=label)
        I = ir.inertial_number(r["gdot"], a.d, np.maximum(r["p"], 1e-9), a.rho_s)
        ax[2].semilogx(I[ok], 1e3 * grid[ok], ".-", ms=3, label=label)
    ax[0].set_xlabel("speed along the surface (cm/s)")
    ax[0].set_ylabel("mass depth zeta (mm)")
    ax[0].axvline(0, color="0.7", lw=0.8)
    ax[1].set_xlabel("SPH / FE - 1 (%)")
    ax[1].axvline(0, color="0.7", lw=0.8)
    ax[1].set_xlim(-25, 15)
    ax[2].set_xlabel("inertial number I (SPH)")
    ax[2].axvline(lo, color="r", lw=1)
    ax[2].axvspan(1e-5, lo, color="r", alpha=0.08)
    ax[2].set_xlim(1e-4, 0.3)
    ax[2].text(lo * 0.9, 0.3, ("partial law\n(well posed)\nI < %.4f" if a.partial else "ill-posed\nI < %.4f") % lo,
               color="r", ha="right", va="top", fontsize=8)
    for x in ax:
        x.grid(alpha=0.3)
        x.legend(fontsize=8)
    ax[0].invert_yaxis()
    if a.title:
        fig.suptitle(a.title, fontsize=10)
    fig.tight_layout()
    fig.savefig(a.png, dpi=120)
    print("wrote %s" % a.png)
    if a.table:
        rows.append(("FE mu(I)", [binned(grid, ufe, lo_, hi) for lo_, hi in bins]))
        write_table(a.table, rows)
        print("wrote %s" % a.table)


if __name__ == "__main__":
    main()
