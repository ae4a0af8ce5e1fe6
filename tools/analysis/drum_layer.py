#!/usr/bin/env python3
"""The flowing layer on a 2D drum's mid-chord (docs/granular.md "Stabilisation"):
the velocity along the free surface u_t(d) at depth d below it, the layer's
thickness delta (the depth where u_t turns from downslope to the bed's
upslope rotation), its downslope flux Q = integral of u_t over the layer, and
the kinematic flux the turning bed feeds it, omega L^2 / 2 (L the half chord;
a rigid bed in the rolling regime supplies exactly this through the
mid-chord). If Q matches and delta shrinks with dr, the layer's thickness,
not the supply, sets the surface speed.

  /usr/bin/python3 -m tools.analysis.drum_layer OUTDIR [OUTDIR ...] [--time T]
"""
import argparse
import os

import numpy as np

from tools.analysis import drum_analysis as da  # noqa: E402
from tools.analysis import snap  # noqa: E402

TRAPZ = getattr(np, "trapezoid", None) or np.trapz  # numpy 2 renamed it


def layer(d):
    frac, pts = d.midchord(400)
    dep = frac * d.R
    t = np.array([d.n[1], -d.n[0]])  # along the surface
    ut = d.interp(pts, d.v @ t)
    if np.nanmean(ut[: len(ut) // 10]) < 0:  # orient t downslope: the surface flows down
        ut = -ut
    ok = ~np.isnan(ut)
    dep, ut = dep[ok], ut[ok]
    k = np.argmax(ut < 0) if np.any(ut < 0) else len(ut) - 1
    delta = dep[k]
    Q = TRAPZ(ut[: k + 1], dep[: k + 1])
    Mn, M2 = float(np.dot(d.M, d.n)), float(np.dot(d.M, d.M))
    L2 = d.R ** 2 - (M2 - Mn * Mn)  # half chord^2: R^2 - (distance of the surface line from the centre)^2
    return delta, Q, ut.max(), L2


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--time", type=float, default=None, help="snapshot nearest this time (default: the last)")
    a = ap.parse_args()
    print("%-28s %6s %7s %9s %8s %10s %10s %6s" % ("run", "t (s)", "dr (mm)", "delta (mm)", "delta/dr",
                                                 "Q (m^2/s)", "w L^2/2", "u_s cm/s"))
    for o in a.outdirs:
        par = da.used_params(o)
        paths = snap.list_snapshots(o)
        p = paths[-1] if a.time is None else da.pick(paths, [a.time])[0]
        d = da.Drum(p, par)
        delta, Q, us, L2 = layer(d)
        w = abs(da.drum_wall(par)[1])
        print("%-28s %6.2f %7.2f %9.2f %8.1f %10.3e %10.3e %6.2f" % (
            os.path.basename(o.rstrip("/")), d.t, 1e3 * d.dr, 1e3 * delta, delta / d.dr, Q, w * L2 / 2, 100 * us))


if __name__ == "__main__":
    main()
