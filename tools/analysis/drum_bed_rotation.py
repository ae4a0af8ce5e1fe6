#!/usr/bin/env python3
"""The bed's solid-body rotation in a 2D drum snapshot: the mean angular
velocity of the material at r/R 0.9-0.97, 0.8-0.9 and 0.6-0.8 below
y = -0.6 R (the bed's bottom, away from the flowing layer), over the wall's
(its radius, Walls:rpm and Walls:direction read from the run's
used_params.yml beside each snapshot). A slipping or
creeping bed carries less flux into the flowing layer (docs/granular.md
"Stabilisation").

  /usr/bin/python3 -m tools.analysis.drum_bed_rotation OUTDIR/snapshot_00004.h5 [...]
"""
import argparse
import os

import numpy as np

from tools.analysis import drum_analysis as da  # noqa: E402
from tools.analysis import snap  # noqa: E402

BANDS = ((0.9, 0.97), (0.8, 0.9), (0.6, 0.8))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("snapshots", nargs="+")
    a = ap.parse_args()
    for f in a.snapshots:
        R, OMEGA = da.drum_wall(da.used_params(os.path.dirname(os.path.abspath(f))))  # OMEGA signed
        s = snap.read_snapshot(f)
        m = s["Kind"] == snap.MATERIAL
        x, u = s["Coordinates"][m], s["Velocities"][m]
        r = np.hypot(x[:, 0], x[:, 1])
        om = (x[:, 0] * u[:, 1] - x[:, 1] * u[:, 0]) / r ** 2
        out = []
        for lo, hi in BANDS:
            k = (r > lo * R) & (r < hi * R) & (x[:, 1] < -0.6 * R)
            out.append("r/R %.1f-%.2f: omega/omega_wall %.4f (n %d)" % (lo, hi, om[k].mean() / OMEGA, k.sum()))
        name = os.path.basename(os.path.dirname(os.path.abspath(f))) + "/" + os.path.basename(f)
        print("%-40s t=%.1f  " % (name, s["Time"]) + "; ".join(out))


if __name__ == "__main__":
    main()
