#!/usr/bin/env python3
"""Noise in a 2D drum's quasi-static bed, and what it does to C: in the bed
below the flowing layer (r/R 0.7-0.95, y < -0.6 R) the material should turn
with the wall as a rigid body, whose strain rate is zero; so the shear rate
the code computes there (gdot, which drives the segregation velocity
V = chi_V gdot d, eq. 2.7) and the speed off the rigid rotation are noise.
Printed per snapshot: the bed's gdot (median, 90th percentile), the median
|u - omega x r| there, and the mean C in the bed and in the material row at
the wall (r > R - max(0.015 R, 1.5 dr), y < -0.3 R), where small grains driven down by a noisy
gdot collect (docs/granular.md, "The bed's noise drives the segregation").
The drum's radius and wall rate come from the run's used_params.yml beside
each snapshot; CSV files carry none, so --radius, --rpm and --direction give
them (defaults: inputs/drum_2d_EV.yml's R 35 mm, 5 rpm, clockwise).

  /usr/bin/python3 -m tools.analysis.drum_bed_noise OUTDIR/snapshot_00003.h5 [...]
  /usr/bin/python3 -m tools.analysis.drum_bed_noise --csv FILE.csv [...]   # x,y,u,v,C,gdot,V of the material
"""
import argparse
import os

import numpy as np

from tools.analysis import drum_analysis as da  # noqa: E402
from tools.analysis import snap  # noqa: E402


def measure(x, y, u, v, C, g, dr, R, OMEGA):
    """The bed's noise in one snapshot; R the drum's radius (m), OMEGA the
    wall's signed rate (rad/s about +z, clockwise negative)."""
    r = np.hypot(x, y)
    bed = (r > 0.7 * R) & (r < 0.95 * R) & (y < -0.6 * R)
    wall = (r > R - max(0.015 * R, 1.5 * dr)) & (y < -0.3 * R)  # the material row at the wall (two at dr <= 0.35 mm)
    off = np.hypot(u + OMEGA * y, v - OMEGA * x)  # |u - omega x r|, omega along z
    return {"bed_n": int(bed.sum()), "gdot_median": float(np.median(g[bed])), "gdot_p90": float(np.percentile(g[bed], 90)),
            "off_rigid_median": float(np.median(off[bed])), "C_bed": float(C[bed].mean()), "wall_n": int(wall.sum()),
            "C_wall": float(C[wall].mean()), "gdot_wall_median": float(np.median(g[wall])), "C_max": float(C.max())}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--csv", action="store_true", help="the files are CSV (x,y,u,v,C,gdot,V) of the material")
    ap.add_argument("--radius", type=float, default=0.035, help="CSV only: the drum's radius, m (default 0.035)")
    ap.add_argument("--rpm", type=float, default=5.0, help="CSV only: the wall's rate, rev/min (default 5)")
    ap.add_argument("--direction", choices=("clockwise", "counterclockwise"), default="clockwise",
                    help="CSV only: the wall's sense, seen with y up (default clockwise)")
    a = ap.parse_args()
    print("%-28s %8s %10s %10s %12s %7s %7s %9s %6s" % ("file", "bed n", "gdot med", "gdot p90", "|u-wxr| med",
                                                         "C bed", "C wall", "gdot wall", "C max"))
    for f in a.files:
        if a.csv:
            x, y, u, v, C, g, V = np.loadtxt(f, delimiter=",", skiprows=1, usecols=range(7)).T
            R, om = da.drum_wall({"Geometry": {"radius": a.radius}, "Walls": {"rpm": a.rpm, "direction": a.direction}})
        else:
            R, om = da.drum_wall(da.used_params(os.path.dirname(os.path.abspath(f))))
            s = snap.read_snapshot(f)
            m = s["Kind"] == snap.MATERIAL
            x, y = s["Coordinates"][m, 0], s["Coordinates"][m, 1]
            u, v = s["Velocities"][m, 0], s["Velocities"][m, 1]
            C, g = np.asarray(s["Concentration"])[m], np.asarray(s["ShearRate"])[m]
            V = np.asarray(s["Volume"])[m]
        r = measure(x, y, u, v, C, g, float(np.sqrt(np.median(V))), R, om)  # 2D: V = dr^2
        name = os.path.basename(os.path.dirname(os.path.abspath(f))) + "/" + os.path.basename(f)
        print("%-28s %8d %8.2f/s %8.2f/s %9.2e m/s %7.3f %7.3f %7.2f/s %6.3f" % (
            name[-28:], r["bed_n"], r["gdot_median"], r["gdot_p90"], r["off_rigid_median"], r["C_bed"], r["C_wall"],
            r["gdot_wall_median"], r["C_max"]))


if __name__ == "__main__":
    main()
