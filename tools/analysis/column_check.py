#!/usr/bin/env python3
"""The granular column at rest (inputs/column_2d.yml): vertical stress
against rho g (H - y), and creep after settling.

  python3 -m tools.analysis.column_check OUTDIR [--png FILE]

Stress error: mean and max of |sigma_yy - (-rho g (H - y))| / (rho g H) over
the interior material particles of the last snapshot, i.e. those farther than
a quarter width from either side wall and than 0.1 H from base and surface
(the unit-free error figure). H is the top of the settled column (highest
particle + dr/2), so the elastic settlement is not counted as error.
Creep: displacement of each material particle between the first snapshot at
or after Flow:damping_until and the last one (median and max, in units of
dr), and the largest speed in the last snapshot.
"""
import argparse
import os

import numpy as np
import yaml

from tools.analysis import snap  # noqa: E402


def used_params(outdir):
    with open(os.path.join(outdir, "used_params.yml")) as f:
        return yaml.safe_load(f)


def by_id(s):
    o = np.argsort(s["ParticleIDs"])
    return {k: np.asarray(s[k])[o] for k in ("Coordinates", "Velocities", "Stress", "Kind")}


def analyze(outdir):
    par = used_params(outdir)
    dr, W = par["Geometry"]["dr"], par["Geometry"]["width"]
    rho, g = par["Physics"]["rho"], -par["Physics"]["gravity"][1]
    paths = snap.list_snapshots(outdir)
    last = by_id(snap.read_snapshot(paths[-1]))
    m = last["Kind"] == snap.MATERIAL
    x, S, v = last["Coordinates"][m], last["Stress"][m], last["Velocities"][m]
    H = x[:, 1].max() + 0.5 * dr
    ref = -rho * g * (H - x[:, 1])
    inner = ((x[:, 0] > 0.25 * W) & (x[:, 0] < 0.75 * W) & (x[:, 1] > 0.1 * H) & (x[:, 1] < 0.9 * H))
    err = np.abs(S[inner, 1] - ref[inner]) / (rho * g * H)
    t_settle = par["Flow"]["damping_until"]
    first = next(p for p in paths if snap.snapshot_time(p) >= t_settle - 1e-12)
    a = by_id(snap.read_snapshot(first))
    disp = np.hypot(*(x - a["Coordinates"][m])[:, :2].T) / dr
    return {"H": H, "dr": dr, "rhogH": rho * g * H, "err_mean": float(err.mean()), "err_max": float(err.max()),
            "creep_t0": snap.snapshot_time(first), "creep_t1": snap.snapshot_time(paths[-1]),
            "creep_median_dr": float(np.median(disp)), "creep_max_dr": float(disp.max()),
            "creep_max_at": x[np.argmax(disp), :2].tolist(),
            "speed_max": float(np.hypot(v[:, 0], v[:, 1]).max()),
            "y": x[:, 1], "syy": S[:, 1], "ref": ref, "inner": inner}


def plot(r, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(4.5, 4))
    ax.plot(-r["syy"] / 1e3, r["y"] / r["H"], ".", ms=2, color="0.6", label="SPH, all material particles")
    ax.plot(-r["syy"][r["inner"]] / 1e3, r["y"][r["inner"]] / r["H"], ".", ms=2, label="SPH, interior")
    yy = np.linspace(0, 1, 50)
    ax.plot(r["rhogH"] * (1 - yy) / 1e3, yy, "k-", lw=1, label=r"$\rho g (H - y)$")
    ax.set_xlabel(r"$-\sigma_{yy}$ (kPa)")
    ax.set_ylabel("y / H")
    ax.set_title("column at rest: mean error %.2g, max %.2g of $\\rho g H$" % (r["err_mean"], r["err_max"]),
                 fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--png", help="write the stress-profile plot here")
    a = ap.parse_args()
    r = analyze(a.outdir)
    print("column: H = %.5g m, dr = %.3g m" % (r["H"], r["dr"]))
    print("sigma_yy vs rho g (H - y), interior: mean |error| %.3e, max %.3e (of rho g H)"
          % (r["err_mean"], r["err_max"]))
    print("creep t = %.3g -> %.3g s: median displacement %.3e dr, max %.3e dr at (%.4g, %.4g) m; "
          "max speed at the end %.3e m/s" % (r["creep_t0"], r["creep_t1"], r["creep_median_dr"],
                                             r["creep_max_dr"], *r["creep_max_at"], r["speed_max"]))
    if a.png:
        plot(r, a.png)
        print("wrote", a.png)


if __name__ == "__main__":
    main()
