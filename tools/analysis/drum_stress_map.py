#!/usr/bin/env python3
"""The stress a 2D drum's bed carries, mapped in the free surface's frame
(docs/granular.md "The bed's stress under the layer").

In an incompressible mu(I) fluid (the FE reference, drum_mui_ref.py) the
normal stresses along the surface and across it are equal wherever the flow
is simple shear. sphseg's material is elastoplastic: below its yield cone it
is an elastic solid that keeps the stress it had when it stopped flowing, and
carries it round with the turning bed. This tool shows where the two differ:
the normal stress along the surface less the one across it, over the
pressure, (s_tt - s_nn) / p with s = -sigma (compression positive), binned on
a square grid over the material particles of one snapshot.

  extract OUTDIR NPZ --times T [T ...]
      the material particles of the snapshots at these times (coordinates,
      velocities, stress, volume, shear rate) as one compressed npz, a few MB
      where the run's snapshots are hundreds (to carry a run's state off the
      machine that ran it);
  map NAME=SOURCE[@DEG] [...] --time T [--angle DEG] [--csv CSV] [--png PNG]
      SOURCE an npz of extract or a run's output directory; DEG the surface's
      dynamic angle (drum_analysis's "angle" column at that time), per run or
      for all. Prints, per run, the mean of (s_tt - s_nn) / p over the
      particles under the mid-chord (within 1.75 mm of it, the strip of
      drum_layer) at 7-10 mm below the surface (under_midchord); writes the
      maps (one CSV: name, x, y, value, count per cell) and a chart of them;
  components PARTICLES_CSV [...] --fe FE_PROFILE [--depths MM ...]
      from drum_layer --stress's CSV_particles.csv files (snapshots
      pooled): p and the compressive normal stresses across the surface,
      along it and out of the plane over the FE profile's pressure, the
      shear over p, sqrt(J2) / p and the speed along the surface, at these
      mass depths (the strip's rows within 0.3 mm);
  factor PARTICLES_CSV [...] --fe FE_PROFILE --out CSV [--capacity]
      the table of drum_mui_ref --p-factor that puts a run's own pressure
      under its layer into the FE reference: from drum_layer --stress's
      CSV_particles.csv files (snapshots averaged), p over the FE profile's
      pressure in 0.5-mm bins of the mass depth from 6 to 11 mm (1 above
      and below). With --capacity, instead the shear a particle there can
      carry, sqrt((k p)^2 - N^2) with N^2 the part of J2 its normal stresses
      make (s_nn, s_tt, s_zz about p) and k = k(mu_s) 0.3495, over the FE's
      k p: the stress the memory spends on its normal part is not there to
      carry shear.

    /usr/bin/python3 -m tools.analysis.drum_stress_map extract out/drum t.npz --times 3 3.5
    /usr/bin/python3 -m tools.analysis.drum_stress_map map "dr 0.5 mm=a.npz" "dr 0.25 mm=b.npz" --time 3.5 --angle 21.3 --png m.png

Signs and frame: the EV drum turns clockwise, so its surface falls to +x; t =
(cos a, -sin a) runs down it and n = (sin a, cos a) is its upward normal. The
sign of t or n does not change s_tt or s_nn.
"""
import argparse
import os

import numpy as np

from tools.analysis import inertial_range as ir  # noqa: E402
from tools.analysis import snap  # noqa: E402
from tools.analysis.drum_layer import frame_stress  # noqa: E402

FIELDS = ("Coordinates", "Velocities", "Stress", "Volume", "ShearRate")
CELL = 1.0e-3  # the map's cell, m


def surface_frame(angle_deg):
    """(t, n): the unit vectors down the surface and normal to it, up, for a surface falling to +x at
    angle_deg."""
    a = np.radians(angle_deg)
    return np.array([np.cos(a), -np.sin(a)]), np.array([np.sin(a), np.cos(a)])


def tt_minus_nn(S, angle_deg):
    """(s_tt - s_nn) / p of stresses S (N x 6: xx, yy, zz, xy, xz, yz), s = -sigma (drum_layer's
    frame_stress); nan where p <= 0."""
    S = np.asarray(S)
    t, n = surface_frame(angle_deg)
    c = frame_stress(S, n, t)
    p = ir.pressure_tau(S)[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(p > 0, (c["s_tt"] - c["s_nn"]) / p, np.nan)


def grid_map(x, val, cell=CELL):
    """Bin val at the points x (N x 2) on square cells of side cell: (xc, yc, mean, count) for every
    cell that holds a finite value."""
    ok = np.isfinite(val)
    ij = np.floor(x[ok] / cell).astype(int)
    keys, inv, cnt = np.unique(ij, axis=0, return_inverse=True, return_counts=True)
    s = np.bincount(inv.ravel(), weights=val[ok])
    return (keys[:, 0] + 0.5) * cell, (keys[:, 1] + 0.5) * cell, s / cnt, cnt


def extract(outdir, npz, times):
    """extract (module doc): the material particles of the snapshots at these times into npz, keys
    't<T>_<field>'. Returns the times written."""
    d, got, seen = {}, [], []
    for f in snap.list_snapshots(outdir):
        t = float(snap.snapshot_time(f))
        seen.append(t)
        if not any(abs(t - x) < 1e-6 for x in times):
            continue
        s = snap.read_snapshot(f)
        m = np.asarray(s["Kind"]) == snap.MATERIAL
        for name in FIELDS:
            if name in s:
                d["t%g_%s" % (t, name)] = np.asarray(s[name])[m]
        got.append(t)
    if not got:
        raise SystemExit("%s has no snapshot at t = %s (it has: %s)" % (
            outdir, ", ".join("%g" % t for t in times), ", ".join("%g" % t for t in seen) or "none"))
    np.savez_compressed(npz, **d)
    return got


def load(source, time):
    """(coordinates N x 2, stress N x 6) of the material particles at this time, from an npz of extract
    (one that also holds t<T>_Kind, every particle's, is cut to the material) or a run's output
    directory (its snapshot nearest that time)."""
    if os.path.isdir(source):
        paths = snap.list_snapshots(source)
        f = min(paths, key=lambda p: abs(snap.snapshot_time(p) - time))
        s = snap.read_snapshot(f)
        m = np.asarray(s["Kind"]) == snap.MATERIAL
        return np.asarray(s["Coordinates"])[m, :2], np.asarray(s["Stress"])[m]
    z = np.load(source)
    k = "t%g_" % time
    if k + "Stress" not in z:
        raise SystemExit("%s holds no snapshot at t = %g (it has: %s)" % (
            source, time, ", ".join(sorted({n.split("_")[0] for n in z.files}))))
    x, S = z[k + "Coordinates"][:, :2], z[k + "Stress"]
    if k + "Kind" in z:
        m = z[k + "Kind"] == 0
        x, S = x[m], S[m]
    return x, S


def under_midchord(x, val, angle_deg, depth=(7e-3, 10e-3), half_width=1.75e-3):
    """The mean of val (and the count) over the points within half_width of the mid-chord and between
    these depths below the surface. The drum's axis is the origin; the surface is the line normal to n
    (surface_frame) at the height h_s of the mean of the top 2 % of the points' x.n among those within
    10 mm of the axis's normal to it, and the mid-chord is that normal (through the foot h_s n)."""
    t, n = surface_frame(angle_deg)
    h, s = x @ n, x @ t
    mid = np.abs(s) < 10e-3
    hm = h[mid]
    hs = float(np.mean(hm[hm >= np.quantile(hm, 0.98)]))
    dz = hs - h
    m = (np.abs(s) < half_width) & (dz >= depth[0]) & (dz < depth[1]) & np.isfinite(val)
    return float(np.mean(val[m])), int(m.sum())


K_MU_S = float(ir.kmu(0.382))  # k(mu_s) of Table 1's drucker_prager cone, 0.3495
BASE = (6.0e-3, 11.0e-3)  # factor: the depths of the layer's base and the bed's top, m


def factor_table(parts, fe_depth, fe_p, capacity=False, base=BASE, step=0.5e-3):
    """factor (module doc): rows (depth, factor) from the particles' tables parts (dicts of arrays:
    zeta, p, s_nn, s_tt, s_zz), bracketed by factor 1 half a step outside base."""
    z = np.concatenate([q["zeta"] for q in parts])
    col = {k: np.concatenate([q[k] for q in parts]) for k in ("p", "s_nn", "s_tt", "s_zz")}
    rows = [(base[0] - step, 1.0)]
    for lo in np.arange(base[0], base[1] - 1e-12, step):
        m = (z >= lo) & (z < lo + step)
        if not m.any():
            continue
        zc = float(z[m].mean())
        pl = float(np.interp(zc, fe_depth, fe_p))
        ps = float(col["p"][m].mean())
        if capacity:
            n2 = 0.5 * sum((float(col[k][m].mean()) - ps) ** 2 for k in ("s_nn", "s_tt", "s_zz"))
            rows.append((zc, np.sqrt(max((K_MU_S * ps) ** 2 - n2, 0.0)) / (K_MU_S * pl)))
        else:
            rows.append((zc, ps / pl))
    rows.append((base[1] + step, 1.0))
    return rows


def components(parts, fe_depth, fe_p, depths, half=0.3e-3):
    """components (module doc): rows (depth, p, s_nn, s_tt, s_zz over the FE's p, s_nt / p, sqrt(J2) / p,
    u_t, number of the strip's rows pooled)."""
    z = np.concatenate([q["zeta"] for q in parts])
    col = {k: np.concatenate([q[k] for q in parts]) for k in ("p", "s_nn", "s_tt", "s_zz", "s_nt", "sqrtJ2", "u_t")}
    rows = []
    for d in depths:
        m = np.abs(z - d) < half
        pf = float(np.interp(z[m].mean(), fe_depth, fe_p))  # at the pooled rows' own mean depth
        rows.append((d,) + tuple(float(col[k][m].mean()) / pf for k in ("p", "s_nn", "s_tt", "s_zz"))
                    + (float(col["s_nt"][m].mean() / col["p"][m].mean()),
                       float(np.mean(col["sqrtJ2"][m] / col["p"][m])), float(col["u_t"][m].mean()), int(m.sum())))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("extract")
    e.add_argument("outdir")
    e.add_argument("npz")
    e.add_argument("--times", type=float, nargs="+", required=True)
    m = sub.add_parser("map")
    m.add_argument("runs", nargs="+", help="NAME=SOURCE[@DEG] (an npz of extract or a run's output directory; DEG "
                                           "the run's own angle, else --angle)")
    m.add_argument("--time", type=float, required=True)
    m.add_argument("--angle", type=float, default=None, help="the surface's dynamic angle, degrees (for the runs "
                                                            "that give none)")
    m.add_argument("--cell", type=float, default=CELL, help="the map's cell, m (default 1 mm)")
    m.add_argument("--csv")
    m.add_argument("--png")
    f = sub.add_parser("factor")
    f.add_argument("particles", nargs="+", help="drum_layer --stress's CSV_particles.csv files")
    f.add_argument("--fe", required=True, help="drum_mui_ref --profile's CSV (depth_m, u_x, p)")
    f.add_argument("--out", required=True)
    f.add_argument("--capacity", action="store_true")
    c = sub.add_parser("components")
    c.add_argument("particles", nargs="+", help="drum_layer --stress's CSV_particles.csv files")
    c.add_argument("--fe", required=True, help="drum_mui_ref --profile's CSV (depth_m, u_x, p)")
    c.add_argument("--depths", type=float, nargs="+", default=[2, 4, 6, 7, 7.5, 8, 8.5, 9, 10, 12], help="mm")
    a = ap.parse_args(argv)
    if a.cmd == "components":
        fe = np.loadtxt(a.fe, delimiter=",", skiprows=1)
        parts = [np.genfromtxt(p, delimiter=",", names=True) for p in a.particles]
        print("zeta (mm)   p/p_FE  s_nn/p_FE s_tt/p_FE s_zz/p_FE  s_nt/p  J2^.5/p  u_t cm/s  rows")
        for r in components([{k: q[k] for k in q.dtype.names} for q in parts], fe[:, 0], fe[:, 2],
                            [1e-3 * d for d in a.depths]):
            print("%8.1f   %7.3f %9.3f %9.3f %9.3f %+8.3f %8.4f %+9.2f %5d"
                  % ((1e3 * r[0],) + r[1:7] + (100 * r[7], r[8])))
        return
    if a.cmd == "factor":
        fe = np.loadtxt(a.fe, delimiter=",", skiprows=1)
        parts = [np.genfromtxt(p, delimiter=",", names=True) for p in a.particles]
        rows = factor_table([{k: q[k] for k in q.dtype.names} for q in parts], fe[:, 0], fe[:, 2], a.capacity)
        np.savetxt(a.out, rows, delimiter=",", header="depth_m,factor", comments="", fmt="%.6g")
        print("wrote %s: %s" % (a.out, " ".join("%.1f mm %.3f" % (1e3 * r[0], r[1]) for r in rows)))
        return
    if a.cmd == "extract":
        got = extract(a.outdir, a.npz, a.times)
        print("wrote %s: t = %s" % (a.npz, ", ".join("%g" % t for t in got)))
        return
    maps = []
    for r in a.runs:
        name, src = r.split("=", 1)
        src, _, ang = src.partition("@")
        ang = float(ang) if ang else a.angle
        if ang is None:
            raise SystemExit("no angle for %s: give NAME=SOURCE@DEG or --angle" % name)
        x, S = load(src, a.time)
        v = tt_minus_nn(S, ang)
        mc, nmc = under_midchord(x, v, ang)
        print("%-24s t %g s, angle %.2f deg: mean (s_tt - s_nn) / p under the mid-chord at 7-10 mm %+.3f "
              "(%d particles)" % (name, a.time, ang, mc, nmc))
        maps.append((name, grid_map(x, v, a.cell)))
    if a.csv:
        with open(a.csv, "w") as f:
            f.write("run,x_m,y_m,tt_minus_nn_over_p,count\n")
            for name, (xc, yc, mv, cnt) in maps:
                for row in zip(xc, yc, mv, cnt):
                    f.write("%s,%.5f,%.5f,%.4f,%d\n" % ((name,) + row))
        print("wrote %s" % a.csv)
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axs = plt.subplots(1, len(maps), figsize=(4.4 * len(maps) + 1.2, 3.0), squeeze=False,
                                constrained_layout=True)
        for ax, (name, (xc, yc, mv, cnt)) in zip(axs[0], maps):
            sc = ax.scatter(1e3 * xc, 1e3 * yc, c=mv, s=14 * (a.cell / 1e-3) ** 2, marker="s", cmap="RdBu_r",
                            vmin=-0.4, vmax=0.4, linewidths=0)
            ax.set_aspect("equal")
            ax.set_title(name, fontsize=10)
            ax.set_xlabel("x (mm)")
        axs[0][0].set_ylabel("y (mm)")
        fig.colorbar(sc, ax=axs[0].tolist(), shrink=0.9, label="(s_tt - s_nn) / p")
        fig.suptitle("normal stress along the surface less across it, over p; t = %g s, %g-mm cells"
                     % (a.time, 1e3 * a.cell), fontsize=10)
        fig.savefig(a.png, dpi=110)
        print("wrote %s" % a.png)


if __name__ == "__main__":
    main()
