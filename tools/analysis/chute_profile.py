#!/usr/bin/env python3
"""A chute run's rows against the Bagnold profile of its own mu(I)
(inputs/chute_2d.yml or any periodic layer on a base; tools/studies/chute_study.py
gives the reference).

  /usr/bin/python3 -m tools.analysis.chute_profile OUTDIR [--from T0] [--to T1] [--rows]

The run's parameters come from OUTDIR/used_params.yml: the slope theta from
Physics:gravity, the depth H from Geometry:height, dr, the yield surface's
reading of mu(I) (Material:yield) and the grain size (Grains:d_large, the
size at C = 0; these layers run without segregation). The snapshots in
[T0, T1] (default 2.5 s to the end) are cut into the lattice's rows (row k
holds the particles with round(y / dr - 1/2) = k) and averaged: per row the
height y, the speed along the slope u, the pressure p = -tr(sigma) / 3 and
sqrt(J2). Printed: the depth mean of the rows' u against the Bagnold profile
sampled at the same heights, the top row's u against Bagnold's at its height,
and (--rows) each row with u / u_B, p against the lithostatic rho g cos(theta)
(H - y) and sqrt(J2) / p (tan theta in a steady uniform layer whose stress is
simple shear).
"""
import argparse
import math

import numpy as np

from tools.studies.chute_study import RHO, READING, G, bagnold  # noqa: E402


def rows_of(y, u, sig, dr):
    """Row means of one snapshot's material particles: {k: (y, u, p, sqrt J2)}; sig as the snapshot's
    Stress (xx, yy, zz, xy, xz, yz)."""
    sig = np.asarray(sig, float)
    p = -(sig[:, 0] + sig[:, 1] + sig[:, 2]) / 3
    dev = sig[:, :3] + p[:, None]
    sj = np.sqrt(0.5 * (dev ** 2).sum(axis=1) + (sig[:, 3:] ** 2).sum(axis=1))
    k = np.rint(np.asarray(y) / dr - 0.5).astype(int)
    return {int(r): (y[k == r].mean(), u[k == r].mean(), p[k == r].mean(), sj[k == r].mean()) for r in np.unique(k)}


def mean_rows(snapshots):
    """The rows present in every snapshot, averaged over them: arrays y, u, p, sqrt J2 by height."""
    keys = sorted(set.intersection(*[set(s) for s in snapshots]))
    a = np.array([[np.mean([s[k][i] for s in snapshots]) for i in range(4)] for k in keys])
    return a[:, 0], a[:, 1], a[:, 2], a[:, 3]


def compare(y, u, theta, H, reading, d):
    """(depth-mean ratio over the rows, top row's ratio): the rows' u against Bagnold's at their heights."""
    ub = np.asarray(bagnold(y, theta, H, reading, d=d), float)
    top = int(np.argmax(y))
    return float(u.sum() / ub.sum()), float(u[top] / ub[top])


def params(outdir):
    import yaml
    with open(outdir + "/used_params.yml") as f:
        par = yaml.safe_load(f)
    ini = par.get("Initial", {})
    if float(ini.get("C_below", 0)) != 0 or float(ini.get("C_above", 0)) != 0:
        raise SystemExit(f"{outdir}: the small grains' fraction C is not 0 (Initial:C_below/C_above), so the "
                         "grain size in mu(I) is not Grains:d_large alone: not read here")
    g = par["Physics"]["gravity"]
    theta = math.degrees(math.atan2(g[0], -g[1]))
    return {"theta": theta, "H": float(par["Geometry"]["height"]), "dr": float(par["Geometry"]["dr"]),
            "reading": READING[par["Material"].get("yield", "drucker_prager")],
            "d": float(par["Grains"]["d_large"]), "rho": float(par["Physics"].get("rho", RHO))}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    ap.add_argument("--from", dest="t0", type=float, default=2.5)
    ap.add_argument("--to", dest="t1", type=float, default=math.inf)
    ap.add_argument("--rows", action="store_true", help="print every row")
    a = ap.parse_args(argv)
    from tools.analysis import snap
    c = params(a.outdir)
    snaps, times = [], []
    for path in snap.list_snapshots(a.outdir):
        s = snap.read_snapshot(path)
        t = float(s["Time"])
        if not (a.t0 - 1e-9 <= t <= a.t1 + 1e-9):
            continue
        m = np.asarray(s["Kind"]) == snap.MATERIAL
        x = np.asarray(s["Coordinates"])[m]
        snaps.append(rows_of(x[:, 1], np.asarray(s["Velocities"])[m, 0], np.asarray(s["Stress"])[m], c["dr"]))
        times.append(t)
    if not snaps:
        raise SystemExit(f"{a.outdir}: no snapshot in [{a.t0}, {a.t1}] s")
    y, u, p, sj = mean_rows(snaps)
    rm, rt = compare(y, u, c["theta"], c["H"], c["reading"], c["d"])
    print(f"{a.outdir}: theta {c['theta']:.2f} deg, H {1e3 * c['H']:g} mm, H/dr {c['H'] / c['dr']:.0f}, d "
          f"{1e3 * c['d']:g} mm, {c['reading']}; {len(times)} snapshots, t = {times[0]:g}-{times[-1]:g} s")
    print(f"depth mean of the rows / Bagnold's at their heights: {rm:.4f}; top row (y = {y[-1] / c['dr']:.2f} dr): "
          f"{u[-1]:.4f} m/s, / Bagnold's {rt:.4f}")
    if a.rows:
        ub = np.asarray(bagnold(y, c["theta"], c["H"], c["reading"], d=c["d"]), float)
        pl = c["rho"] * G * math.cos(math.radians(c["theta"])) * (c["H"] - y)
        print(f"{'y/dr':>6s} {'u (m/s)':>8s} {'u_B':>8s} {'u/u_B':>6s} {'p/p_lith':>8s} {'sqrtJ2/p':>8s}")
        for i in range(len(y)):
            print(f"{y[i] / c['dr']:6.2f} {u[i]:8.4f} {ub[i]:8.4f} {u[i] / max(ub[i], 1e-12):6.3f} "
                  f"{p[i] / pl[i]:8.3f} {sj[i] / p[i]:8.4f}")


if __name__ == "__main__":
    main()
