#!/usr/bin/env python3
"""The 3D drum analysis of tools/analysis/drum_analysis.py (Axial) on synthetic
snapshots whose answers are known by construction (no sphseg run):

  a bed of lattice points (spacing dr) inside the drum's circle below a plane
  surface y = tan(theta) x + b, the same in every z-plane except the planes
  of the first end slab (z < W), which have their own angle; C = 1 inside a
  core of radius r0 about the bed's centroid and 0 outside, or C = 1 in one
  half of the length and 0 in the other.

Checks (the references are the construction's own numbers; the tolerances
are the lattice's: a surface fitted to the tops of 2-dr columns of points
spaced dr is within about atan(dr / chord) of the plane):
  - the angle of the whole bed, of every z-bin but the first, and of the
    mid-length slab: theta = 20 deg within 0.6 deg; of the z < W end slab
    and the first z-bin (the same planes): 30 deg within 0.6 deg;
  - a z-uniform C gives no axial banding (< 1e-12) and no small-grain
    offset between bins (the same in every bin to 1e-12 m);
  - the core: the innermost shell's mean C is 1, the outermost's 0; the
    segregation index is positive;
  - C = 1 for z < 9 mm only: the banding is 1 (all of C's variance lies
    between the z-bins, one of whose edges is 9 mm) to 1e-12, and the bins
    without small grains have no offset (NaN, not an error);
  - a core of C = 1 displaced by (dx, dy) = (3, -2) mm from the bed's
    centroid: every z-bin's small-grain offset is the disc's lattice centroid
    less the bed's (the construction's numbers, computed here) to 1e-9 m, and
    about (3, -2) mm within 0.2 dr (lattice);
  - solid-body rotation u = omega z^ x (x, y), omega = 1 rad/s, but 0.5 rad/s
    in the planes z < W: the speed profile on the mid-chord is omega |p| at
    its points p (exact for the field; its Shepard interpolation, of a norm
    curved on the scale h, is within 0.1 omega dr where the kernel's support
    is whole, more than 2h from the surface and the wall, measured 0.043, and
    within omega 2h elsewhere), at mid-length
    and at z > L - W with omega = 1, at z < W with omega = 0.5;
  - the command line with --csv writes one row per time with the per-z-bin
    columns, and its numbers are Axial's;
  - a 2D snapshot is refused.
"""
import argparse
import math
import os
import sys

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import drum_analysis as da  # noqa: E402

DR, R, L = 1e-3, 0.035, 0.024
PAR = {"Geometry": {"dr": DR, "radius": R, "length": L, "h_factor": 1.5, "dim": 3}}


def bed(theta_deg, theta_end_deg, W, b=-0.004):
    pts = []
    n = int(R / DR) + 1
    for k in range(int(round(L / DR))):
        z = (k + 0.5) * DR
        th = math.radians(theta_end_deg if z < W else theta_deg)
        for i in range(-n, n):
            for j in range(-n, n):
                x, y = (i + 0.5) * DR, (j + 0.5) * DR
                if x * x + y * y < (R - DR) ** 2 and y < math.tan(th) * x + b:
                    pts.append((x, y, z))
    return np.array(pts)


def write(path, X, C, dim=3, V=None):
    n = len(X)
    with h5py.File(path, "w") as f:
        h = f.create_group("Header")
        h.attrs["Time"] = 1.0
        h.attrs["Dimension"] = dim
        h.attrs["NumPart_Total"] = n
        p = f.create_group("Particles")
        p["Coordinates"] = X
        p["Velocities"] = np.zeros_like(X) if V is None else V
        p["Concentration"] = C
        p["ShearRate"] = np.zeros(n)
        p["Volume"] = np.full(n, DR ** 3)
        p["Kind"] = np.zeros(n, dtype=np.uint8)
        p["ParticleIDs"] = np.arange(n, dtype=np.int64)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", help="unused (the test runner passes it)")
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    fails = []

    def check(name, ok, detail):
        print("%s %s: %s" % ("ok  " if ok else "FAIL", name, detail))
        if not ok:
            fails.append(name)

    W = 3 * DR
    X = bed(20.0, 30.0, W)
    c = X[:, :2].mean(axis=0)
    r = np.hypot(*(X[:, :2] - c).T)
    core = (r < 0.3 * r.max()).astype(float)
    p1 = os.path.join(a.work, "core.h5")
    write(p1, X, core)
    ax = da.Axial(p1, PAR, nz=8)
    rest = [b.angle for b in ax.bins[1:]]
    check("angle, z-bins 2-8", max(abs(t - 20) for t in rest) < 0.6, "%s (plane: 20°)" % " ".join("%.2f" % t for t in rest))
    check("angle, mid-length slab", abs(ax.mid.angle - 20) < 0.6, "%.2f° (20°)" % ax.mid.angle)
    check("angle, end slab z < W and z-bin 1", abs(ax.end0.angle - 30) < 0.6 and abs(ax.bins[0].angle - 30) < 0.6,
          "%.2f°, %.2f° (30°)" % (ax.end0.angle, ax.bins[0].angle))
    check("angle, end slab z > L - W", abs(ax.end1.angle - 20) < 0.6, "%.2f° (20°)" % ax.end1.angle)
    # the 20-degree planes only: C is then z-uniform
    X2 = X[X[:, 2] >= W]
    X2 = X2 - np.array([0, 0, W])
    par2 = {"Geometry": dict(PAR["Geometry"], length=L - W)}
    c2 = X2[:, :2].mean(axis=0)
    core2 = (np.hypot(*(X2[:, :2] - c2).T) < 0.3 * r.max()).astype(float)
    p2 = os.path.join(a.work, "uniform.h5")
    write(p2, X2, core2)
    ax2 = da.Axial(p2, par2, nz=7)
    off = np.hypot(*ax2.offset.T)
    check("z-uniform C: no banding", ax2.banding < 1e-12, "%.2e" % ax2.banding)
    check("z-uniform C: the same offset in every bin", np.ptp(off) < 1e-12, "spread %.2e m" % np.ptp(off))
    check("core: shells inner 1, outer 0", ax2.shellC[0] == 1.0 and ax2.shellC[-1] == 0.0,
          " ".join("%.3f" % s for s in ax2.shellC))
    check("core: segregation index > 0", ax2.whole.segregation_index() > 0.1, "%.4f" % ax2.whole.segregation_index())
    half = (X2[:, 2] < 0.009).astype(float)  # z-bins of 3 mm: 9 mm is an edge
    p3 = os.path.join(a.work, "half.h5")
    write(p3, X2, half)
    ax3 = da.Axial(p3, par2, nz=7)
    check("C = 1 for z < 9 mm: banding 1", abs(ax3.banding - 1) < 1e-12, "%.12f" % ax3.banding)
    check("bins without small grains: offset NaN", np.isnan(ax3.offset[3:]).all() and not np.isnan(ax3.offset[:3]).any(),
          " ".join("%.2g" % o for o in np.hypot(*ax3.offset.T)))
    # a displaced core: the offset's reference is the construction's own centroids
    d = np.array([0.003, -0.002])
    disc = (np.hypot(*(X2[:, :2] - c2 - d).T) < 0.25 * r.max()).astype(float)
    ref = X2[disc > 0, :2].mean(axis=0) - X2[:, :2].mean(axis=0)  # the same in every z-plane (z-uniform lattice)
    # solid-body rotation, omega = 1 rad/s, 0.5 in the planes z < W of the 30-degree bed
    om = np.where(X[:, 2] < W, 0.5, 1.0)
    Vel = np.stack([-om * X[:, 1], om * X[:, 0], np.zeros(len(X))], axis=1)
    p5 = os.path.join(a.work, "disc.h5")
    write(p5, X2, disc)
    ax5 = da.Axial(p5, par2, nz=7)
    err = np.abs(ax5.offset - ref).max()
    check("displaced core: offset per z-bin", err < 1e-9 and np.abs(ax5.offset - d).max() < 0.2 * DR,
          "max |offset - lattice ref| %.1e m, offset %s mm (built: 3, -2)" % (err, 1e3 * ax5.offset[0]))
    p6 = os.path.join(a.work, "rot.h5")
    write(p6, X, core, V=Vel)
    ax6 = da.Axial(p6, PAR, nz=8)
    h = PAR["Geometry"]["h_factor"] * DR
    for tag, dd, omg in (("mid", ax6.mid, 1.0), ("end z < W", ax6.end0, 0.5), ("end z > L - W", ax6.end1, 1.0)):
        dm, pts = dd.midchord()
        u, ref_u = dd.interp(pts, dd.speed), omg * np.hypot(*pts.T)
        dep = dm * R
        inner = (dep > 2 * h) & (dep < dep.max() - 2 * h - DR)
        e_in, e_all = np.nanmax(np.abs(u - ref_u)[inner]), np.nanmax(np.abs(u - ref_u))
        check("solid rotation: mid-chord speed, %s" % tag, e_in < 0.1 * omg * DR and e_all < omg * 2 * h,
              "max error %.2e (inside) %.2e (all) m/s, omega %.1f" % (e_in, e_all, omg))
    # the command line: --csv, one row per time, the per-z-bin columns
    rd = os.path.join(a.work, "run")
    os.makedirs(rd, exist_ok=True)
    write(os.path.join(rd, "snapshot_00000.h5"), X, core, V=Vel)
    with open(os.path.join(rd, "used_params.yml"), "w") as f:
        import yaml
        yaml.safe_dump(PAR, f)
    with open(os.path.join(rd, "diagnostics.csv"), "w") as f:
        f.write("step,time,small_volume,small_volume_drift\n0,1.0,0,0\n")
    import csv
    import subprocess
    cf = os.path.join(a.work, "axial.csv")
    pr = subprocess.run([sys.executable, "-m", "tools.analysis.drum_analysis", os.path.abspath(rd), "--zbins", "8",
                         "--csv", os.path.abspath(cf)], capture_output=True, text=True, cwd=os.path.join(HERE, ".."))
    rows = list(csv.DictReader(open(cf))) if pr.returncode == 0 and os.path.exists(cf) else []
    ok = len(rows) == 1 and all(abs(float(rows[0]["angle_z%d" % k]) - ax6.bins[k].angle) < 1e-9 for k in range(8)) \
        and abs(float(rows[0]["speed_end0"]) - ax6.end0.surface_speed()) < 1e-12
    check("command line --csv", ok, "rc %d, %d row(s) %s" % (pr.returncode, len(rows), pr.stderr[-300:]))
    p4 = os.path.join(a.work, "flat.h5")
    write(p4, X2, half, dim=2)
    try:
        da.Axial(p4, par2)
        check("2D snapshot refused", False, "no error")
    except ValueError as e:
        check("2D snapshot refused", "not a 3D drum" in str(e), str(e))
    print("%d checks failed" % len(fails))
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
