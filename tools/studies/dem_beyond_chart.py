#!/usr/bin/env python3
"""The DEM "beyond the paper" studies (issue 58; docs/dem.md): hindered
settling against Richardson & Zaki and a packed bed at rest, from runs made
by tools/studies/dem_beyond.sh; printed as the page's tables and drawn as
one chart of three panels: the interior grains' v / v_t against eps with
eps^n (Richardson & Zaki 1954; Garside & Al-Dibouni 1977 and Rowe 1987
beside) and the code's own balance; the bed's fluid pressure against height
with the hydrostatic line; the grains' kinetic energy in time.

  /usr/bin/python3 -m tools.studies.dem_beyond_chart --hindered 0.6=DIR 0.7=DIR ... --bed DIR \\
      --png docs/data/dem/dem_beyond.png
"""
import argparse
import glob
import os

import h5py
import numpy as np

from tests import validate_dem_bed as bed
from tests import validate_dem_hindered as hs


def hindered_rows(runs):
    rows = []
    for r in runs:
        eps, out = float(r.split("=")[0]), r.split("=", 1)[1]
        c = hs.FULL
        _, n, h = hs.geometry(eps, c["layers"], c["gap"], c["above"])
        ok, row = hs.check(out, eps, n, c["layers"], h, c["t0"], c["t1"])
        row["ok"] = ok
        rows.append(row)
    return sorted(rows, key=lambda x: x["eps"])


def bed_profile(out, window):
    """The fluid's mean pressure in 2 mm bins of height over the last `window`
    s, the mean free-surface height H, and the bed's top (the highest grain's
    top)."""
    paths = sorted(glob.glob(os.path.join(out, "snapshot_*.h5")))
    with h5py.File(paths[-1], "r") as f:
        t_end = float(f["Header"].attrs["Time"])
    bins = np.arange(0, 0.14, 0.002)
    sp, sn, Hs, top = np.zeros(len(bins) - 1), np.zeros(len(bins) - 1), [], 0.0
    for p in paths:
        with h5py.File(p, "r") as f:
            if float(f["Header"].attrs["Time"]) < t_end - window - 1e-9:
                continue
            k, X, s = f["Particles/Kind"][:], f["Particles/Coordinates"][:], f["Particles/Stress"][:]
            top = float(f["DEM/Coordinates"][:, 1].max()) + 0.5 * bed.D
        m = k == 0
        y, pr = X[m, 1], -(s[m, 0] + s[m, 1] + s[m, 2]) / 3
        sp += np.histogram(y, bins, weights=pr)[0]
        sn += np.histogram(y, bins)[0]
        ncol = int(round(bed.WIDTH / bed.DR)) ** 2
        Hs.append(float(np.sort(y)[-ncol:].mean() + 0.5 * bed.DR))
    keep = sn > 0
    return 0.5 * (bins[1:] + bins[:-1])[keep], (sp / np.maximum(sn, 1))[keep], float(np.mean(Hs)), top


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hindered", nargs="*", default=[], help="EPS=DIR: a full hindered run (validate_dem_hindered --full)")
    ap.add_argument("--bed", help="the full bed run (inputs/dem_bed.yml as it stands)")
    ap.add_argument("--png")
    a = ap.parse_args(argv)
    rows = hindered_rows(a.hindered)
    if rows:
        vt, re = rows[0]["vt"], rows[0]["re"]
        print("\n| eps | eps at the interior grains | window (s) | v (m/s) | halves | snapshots | fluid up (m/s) | (1 - eps) v / eps "
              "| v_t eps^n, R-Z (m/s) | v | G-A | Rowe | code's balance |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
        for r in rows:
            e = r["eps"]
            ref = lambda n: r["v"] / (vt * e ** n) - 1  # noqa: E731
            print("| %.1f | %.4f | %.2f-%.2f | %.5f | %.1f %% | +-%.0f %% | %.5f | %.5f | %.5f | %+.1f %% | %+.1f %% | %+.1f %% | %+.1f %% |"
                  % (e, r["eps_in"], r["t0"], r["t1"], r["v"], 100 * r["steady"], 100 * r["amp"], r["uf"], (1 - e) * r["v"] / e,
                     vt * e ** hs.n_rz(re), 100 * ref(hs.n_rz(re)), 100 * ref(hs.n_ga(re)), 100 * ref(hs.n_rowe(re)),
                     100 * (r["v"] / r["bal"] - 1)))
    if a.bed:
        print()
        bed.check(a.bed, bed.FULL)
    if not a.png:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
    if rows:
        e = np.linspace(0.5, 1.0, 101)
        vt, re = rows[0]["vt"], rows[0]["re"]
        ax[0].plot(e, e ** hs.n_rz(re), "k-", label="Richardson-Zaki, n %.2f" % hs.n_rz(re))
        ax[0].plot(e, e ** hs.n_rowe(re), "k:", label="Rowe, n %.2f" % hs.n_rowe(re))
        ax[0].plot(e, e ** hs.n_ga(re), "k-.", label="Garside-Al-Dibouni, n %.2f" % hs.n_ga(re))
        ax[0].plot(e, [hs.balance(x) / vt for x in e], "b--", lw=0.8, label="the code's drag, uniform (eq. 23)")
        ax[0].plot([r["eps"] for r in rows], [r["v"] / vt for r in rows], "ro", label="run: interior grains")
        ax[0].set_xlabel("fluid fraction eps")
        ax[0].set_ylabel("v / v_t")
        ax[0].set_title("hindered settling (v_t %.4f m/s, Re_t %.0f)" % (vt, re), fontsize=9)
        ax[0].legend(fontsize=7)
    if a.bed:
        y, p, H, top = bed_profile(a.bed, bed.FULL["window"])
        ax[1].plot(p, 100 * y, "r.-", label="fluid, mean over the window")
        yy = np.linspace(0, H, 50)
        ax[1].plot(bed.RHO_F * bed.G * (H - yy), 100 * yy, "k-", label="rho_f g (H - y)")
        ax[1].axhspan(0, 100 * top, color="0.9", label="the bed")
        ax[1].set_xlabel("pressure (Pa)")
        ax[1].set_ylabel("height y (cm)")
        ax[1].set_title("packed bed at rest: the fluid's pressure", fontsize=9)
        ax[1].legend(fontsize=7)
        t, ke = bed.kinetic(a.bed)
        ax[2].semilogy(t, np.maximum(ke, 1e-16), "b-")
        ax[2].set_xlabel("t (s)")
        ax[2].set_ylabel("grains' kinetic energy (J)")
        ax[2].set_title("packed bed: coming to rest", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
