#!/usr/bin/env python3
"""The bed's solid-body rotation in a 2D drum snapshot: the mean angular velocity
of the material at r/R 0.9-0.97, 0.8-0.9 and 0.6-0.8 below y = -0.6 R (the
bed's bottom, away from the flowing layer), over the wall's (Walls:rpm 5,
R 35 mm: inputs/drum_2d_EV.yml). A slipping or creeping bed carries less
flux into the flowing layer (docs/granular.md "Stabilisation").

  /usr/bin/python3 tools/drum_bed_rotation.py OUTDIR/snapshot_00004.h5 [...]
"""
import sys, glob
sys.path.insert(0, __import__("os").path.dirname(__import__("os").path.abspath(__file__)))
import snap, numpy as np
R, W = 0.035, 5 * 2 * np.pi / 60
for f in sys.argv[1:]:
    s = snap.read_snapshot(f)
    m = s["Kind"] == 0
    x, u = s["Coordinates"][m], s["Velocities"][m]
    r = np.hypot(x[:, 0], x[:, 1])
    om = (x[:, 0] * u[:, 1] - x[:, 1] * u[:, 0]) / r**2
    out = []
    for lo, hi in ((0.9, 0.97), (0.8, 0.9), (0.6, 0.8)):
        k = (r > lo * R) & (r < hi * R) & (x[:, 1] < -0.6 * R)   # the bed's bottom, away from the surface
        out.append("r/R %.1f-%.2f: omega/omega_wall %.4f (n %d)" % (lo, hi, -om[k].mean() / W, k.sum()))
    print("%-40s t=%.1f  " % (f.split("/")[-2] + "/" + f.split("/")[-1], s["Time"]) + "; ".join(out))
