#!/usr/bin/env python3
"""What drum_analysis reads from the finite-element mu(I) drum at a particle
spacing dr: the bias of its surface-speed readings, resolution by resolution.

  python3 -m tools.analysis.drum_fe_read PROFILE.csv [--dr 0.0005 0.00025 0.000125]
      [--radius 0.035] [--h-factor 1.5] [--jitter 0.1 --seeds 8]

PROFILE.csv is the FE reference's mid-chord profile (tools/analysis/drum_mui_ref.py
--profile: depth below the flat surface, speed along it, p; the dynamic angle in
its header). The profile runs from the surface to the wall, so the surface lies
R - depth_max from the axis.

The FE field is laid onto particles as an SPH run would carry it: a lattice of
spacing dr filling the disk segment below the surface, rows parallel to it, the
top row's centres dr / 2 below it (each particle holds dr^2 of the bed, so the
material ends half a spacing above the last centres), every particle moving
along the surface at the FE speed of its depth. With --jitter S each particle
is moved by a normal deviate of S dr in x and y (a disordered bed) and takes
the FE speed of its new depth; --seeds draws that many beds and reports their
mean and spread. The particles are then read exactly as drum_analysis reads a
snapshot (its Drum class, the same code):

  surface_speed        the largest Shepard-interpolated speed on the mid-chord
                       (kernel support 2 h, h = h_factor dr) -- the "surface
                       speed" of docs/granular.md's drum tables;
  surface_grain_speed  the mean speed of the top grains within 0.1 R of the
                       mid-chord's foot.

Each is printed with its ratio to the FE's own surface speed u(0). That ratio
is what a converged SPH run with exactly the FE's field would show at that dr:
the reading's bias, to be taken out before the SPH and the FE are compared.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
from tools.analysis import drum_analysis as da  # noqa: E402
from tools.analysis import snap  # noqa: E402


def read_profile(path, pressure=False):
    """depth (m), speed along the surface (m/s) and the angle (deg) of a drum_mui_ref --profile CSV
    (and its pressure, Pa, after the speed, with pressure=True)."""
    with open(path) as f:
        head = f.readline()
    theta = float(head.split("theta")[1].split("deg")[0])
    a = np.loadtxt(path, delimiter=",", skiprows=1)
    return (a[:, 0], a[:, 1], a[:, 2], theta) if pressure else (a[:, 0], a[:, 1], theta)


def lattice_drum(depth, u, theta, R, dr, h_factor, jitter=0.0, rng=None, p=None):
    """A synthetic snapshot and parameters: the FE field on particles of spacing dr (module doc); with
    p (Pa, on depth) an isotropic stress -p I, else none."""
    th = np.radians(theta)
    t = np.array([np.cos(th), np.sin(th)])  # along the surface
    n = np.array([np.sin(th), -np.cos(th)])  # into the bed
    ys = R - depth[-1]  # the surface's distance from the axis
    M = ys * n  # the foot of the perpendicular from the axis (the surface lies below it: fill < 1/2)
    rows = np.arange(0.5, depth[-1] / dr + 1) * dr
    cols = np.arange(-R / dr - 1, R / dr + 1) * dr
    S, D = np.meshgrid(cols, rows)
    x = M[None, :] + S.reshape(-1, 1) * t[None, :] + D.reshape(-1, 1) * n[None, :]
    if jitter:
        x = x + rng.normal(0.0, jitter * dr, x.shape)
    d = (x - M) @ n  # depth below the FE surface
    keep = (np.hypot(*x.T) < R - 0.5 * dr) & (d > 0)
    x, d = x[keep], d[keep]
    v = np.interp(d, depth, u)[:, None] * t[None, :]
    N = len(x)
    s = {"Time": 0.0, "Dimension": 2, "Kind": np.full(N, snap.MATERIAL),
         "Coordinates": np.c_[x, np.zeros(N)], "Velocities": np.c_[v, np.zeros(N)],
         "Concentration": np.zeros(N), "ShearRate": np.zeros(N), "Volume": np.full(N, dr * dr)}
    if p is not None:
        s["Stress"] = np.zeros((N, 6))
        s["Stress"][:, :3] = -np.interp(d, depth, p)[:, None]
    par = {"Geometry": {"dr": dr, "radius": R, "h_factor": h_factor}}
    return s, par


def read(depth, u, theta, R, dr, h_factor, jitter=0.0, seeds=1):
    """(surface_speed, surface_grain_speed, angle) per bed, as arrays over the seeds."""
    out = []
    for k in range(seeds if jitter else 1):
        s, par = lattice_drum(depth, u, theta, R, dr, h_factor, jitter, np.random.default_rng(k))
        d = da.Drum(None, par, snapshot=s)
        out.append((d.surface_speed(), d.surface_grain_speed(), d.angle))
    return np.array(out).T


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("profile", help="drum_mui_ref --profile CSV")
    ap.add_argument("--dr", type=float, nargs="+", default=[0.0005, 0.00025, 0.000125], help="spacings, m")
    ap.add_argument("--radius", type=float, default=0.035, help="drum radius R, m (default 0.035)")
    ap.add_argument("--h-factor", type=float, default=1.5, help="h / dr (default 1.5, the drum scenes')")
    ap.add_argument("--jitter", type=float, default=0.0, help="random displacement, in dr (default 0: a lattice)")
    ap.add_argument("--seeds", type=int, default=8, help="beds drawn with --jitter (default 8)")
    a = ap.parse_args()
    depth, u, theta = read_profile(a.profile)
    u0 = u[0]
    print("FE profile %s: theta %.3f deg, u(0) = %.4f cm/s, surface %.2f mm from the axis; h = %.2f dr, "
          "jitter %.2f dr" % (a.profile, theta, 100 * u0, 1e3 * (a.radius - depth[-1]), a.h_factor, a.jitter))
    print("%10s %14s %8s %16s %8s %10s %14s" % ("dr (mm)", "surface_speed", "/ u(0)", "top grains", "/ u(0)",
                                               "angle", "u(dr/2)/u(0)"))
    for dr in a.dr:
        ss, sg, ang = read(depth, u, theta, a.radius, dr, a.h_factor, a.jitter, a.seeds)
        spread = (lambda x: " ±%.4f" % x.std()) if len(ss) > 1 else (lambda x: "")
        print("%10.4g %9.4f cm/s %8.4f%s %9.4f cm/s %8.4f%s %9.3f° %14.4f"
              % (1e3 * dr, 100 * ss.mean(), ss.mean() / u0, spread(ss / u0), 100 * sg.mean(), sg.mean() / u0,
                 spread(sg / u0), ang.mean(), np.interp(0.5 * dr, depth, u) / u0))


if __name__ == "__main__":
    main()
