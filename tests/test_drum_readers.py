#!/usr/bin/env python3
"""How the drum tools read a mid-chord (tools/analysis/drum_analysis.py,
drum_layer.py, drum_fe_read.py), checked on beds whose answer is known
without them (no sphseg run; a few seconds):

A layer u(z) = U (1 - (z / delta)^1.5) (Bagnold's shape, U 8 cm/s, delta 6 mm,
0 below), p(z) = rho g cos(theta) z, laid by drum_fe_read.lattice_drum on a
lattice of spacing dr in the 35-mm drum's segment below a surface at 21.2 deg,
5.6 mm from the axis (the EV drum's), rows parallel to it, the top row's
centres dr / 2 below it. dr 0.7 and 0.5 mm put exactly W / dr columns in the
strip of width W = 0.1 R of drum_layer, so a row of the strip holds W dr of
material, as a disordered bed does on average.

- drum_analysis: the fitted angle is the surface's (1e-9 deg); the top grains'
  speed is u(dr / 2) exactly (round-off: they are the top row), and so it reads
  (to the table's 0.01 cm/s) from the printed table through read_table and
  filter_interval_chart.top_grains (its time window too); binned along the
  chord (surface_grains_along) every bin but the two at the wall (the corners)
  reads u(dr / 2) at height 0 above the fitted line, and the bins hold every
  surface grain; the largest
  Shepard-interpolated speed reads below u(0), by less at the finer dr (the
  reading's bias of docs/granular.md, which drum_fe_read measures);
- drum_layer.layer: the squared half chord is R^2 - r_M^2 and the squared
  radius below the layer R^2 - (r_M + delta_read)^2 (r_M the fitted line's
  distance from the axis, 5.6 mm + dr / 2), to 1e-12 (the formula before this
  test returned R^2);
- drum_layer's mass depth zeta: the strip's rows come out at zeta = (k + 1/2)
  dr, the depth below the material's edge (1e-9 of dr), each with u(zeta) and
  p(zeta) (1e-9 relative); the particles' flux is the row sum of u dr, and the
  interpolated mid-chord profile, which starts at the fitted line, carries less
  (it misses the top half row);
- the lithostatic pressure of --stress (depth + dr / 2) matches the
  interpolated p inside the bed (depth 3-5 mm, 1e-3 relative);
- drum_layer's frame_stress: the laid isotropic p reads p across, along and
  out of the surface with no shear (1e-9), and a stress given in the tilted
  frame and turned into x, y comes back (1e-12);
- drum_stress_map: a uniform stress given in the surface's frame reads its
  (s_tt - s_nn) / p in every cell and under the mid-chord (1e-12); on the laid
  bed, whose p is the reference's, its factor tables (p and capacity, 0.5-mm
  bins of 1-4 mm) and its components read 1 (1e-9);
- layer_fe_chart --table's bins: the mean of a linear speed over each 1-mm
  bin is its value at the bin's centre (to the table's 0.001 cm/s), nan
  where a run has no value;
- periodic_drum table: on drum_analysis tables of known speeds and indices, a
  run's means over t = 3-5 s go to the CSV and an ensemble's ('2D dr X run K')
  count, mean and sample SD to the _spread CSV, not to the CSV (to its 4 digits);
- periodic_drum depth: on a made-up mid-chord profile u = U (1 - d/D)^2 above
  the layer's foot D and a bed rising beyond it, with the particles' shear rate
  k |du/dd| (k = 1, 1.2), the layer's depth is D (to one sample), the speeds at
  1 and 3 dr the profile's (to the samples' spacing) and the shear-rate ratio
  k (1e-2: finite differences of the sampled profile);
- periodic_drum surface: means over the times a 2D run and its slab share.

    /usr/bin/python3 -m tests.test_drum_readers [--sphseg IGNORED --work IGNORED]
"""
import argparse
import copy
import csv
import os
import sys
import tempfile

import numpy as np

from tests.checks import check, parse_args, summary  # noqa: E402
from tools.analysis import drum_analysis as da  # noqa: E402
from tools.analysis import drum_fe_read as fr  # noqa: E402
from tools.analysis import drum_layer as dl  # noqa: E402
from tools.analysis import drum_stress_map as dsm  # noqa: E402
from tools.studies import filter_interval_chart as fic  # noqa: E402
from tools.studies import layer_fe_chart as lfc  # noqa: E402
from tools.studies import periodic_drum as pdrum  # noqa: E402

R, YS, THETA, U, DELTA, RHO, G = 0.035, 0.0056, 21.2, 0.08, 0.006, 1500.0, 9.81


def profile():
    z = np.linspace(0.0, R - YS, 4001)
    u = np.where(z < DELTA, U * (1 - np.clip(z / DELTA, 0, 1) ** 1.5), 0.0)
    p = RHO * G * np.cos(np.radians(THETA)) * z
    return z, u, p


def params_dir(work):
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "used_params.yml"), "w") as f:
        f.write("Material:\n  mu_s: 0.382\n  mu_d: 0.682\n  I0: 0.279\n  rho_s: 2500\n  yield: drucker_prager\n"
                "Grains:\n  d_small: 0.00025\n  d_large: 0.0005\nPhysics:\n  rho: %g\n  gravity: [0, %g, 0]\n"
                % (RHO, -G))
    return work


def along_roundtrip(d, work, dr):
    """drum_analysis --along's file (write_along) of the snapshot at t = 3 and 3.5 s, read back by
    read_along over [3, 3.5]: {bin: (s/R, speed, se, height, snapshots)}."""
    a, b = copy.copy(d), copy.copy(d)
    a.t, b.t = 3.0, 3.5
    path = os.path.join(work, "along_%g.csv" % dr)
    da.write_along([a, b], path)
    return da.read_along(path, 3.0, 3.5)


def table_roundtrip(d, work, dr):
    """drum_analysis's printed table (TABLE_HEAD, table_row at two times) read back by read_table
    and filter_interval_chart.top_grains: the top grains' speed in cm/s, after checking that both
    lines and only they come back."""
    d = copy.copy(d)
    d.C = np.full_like(d.C, 0.5)  # the lattice is laid with C = 0: its segregation index is undefined
    path = os.path.join(work, "table_%g.ana" % dr)
    with open(path, "w") as f:
        f.write("preamble 1.0 dr 2.0 cm/s\n" + da.TABLE_HEAD + "\n")
        for t in (3.0, 3.5):
            d.t = t
            f.write(da.table_row(d) + "\n")
        f.write("wrote profiles.csv\nmax |relative drift of sum C_i V_i|: 0.000e+00\n")
    rows = da.read_table(path)
    check("dr %.1f mm printed table: snapshots read back" % (1e3 * dr), len(rows), 2,
          [r[0] for r in rows] == [3.0, 3.5], "two lines under the header, nothing else")
    tg = fic.top_grains(path, 3.25)
    return float(tg[0, 1])


def main():
    a = parse_args(__doc__, "directory for the run parameters (default: a temporary one)")
    work = params_dir(a.work or tempfile.mkdtemp(prefix="drum_readers_"))
    z, u, p = profile()
    bias = {}
    for dr in (0.0007, 0.0005):
        s, par = fr.lattice_drum(z, u, THETA, R, dr, 1.5, p=p)
        d = da.Drum(None, par, snapshot=s)
        tag = "dr %.1f mm" % (1e3 * dr)
        check(tag + " fitted angle - theta (deg)", abs(d.angle - THETA), 1e-9, abs(d.angle - THETA) < 1e-9,
              "the lattice's rows")
        ug = d.surface_grain_speed()
        uh = np.interp(0.5 * dr, z, u)
        check(tag + " top grains / u(dr/2) - 1", abs(ug / uh - 1), 1e-12, abs(ug / uh - 1) < 1e-12, "the top row")
        al = d.surface_grains_along(np.linspace(-1, 1, 21))
        inner = [b for b in al[1:-1] if b[3]]  # the end bins hold the corners at the wall
        ea = max(max(abs(b[1] / uh - 1) for b in inner), max(abs(b[2]) for b in inner))
        check(tag + " surface grains along the chord: speed / u(dr/2) - 1, height in dr", ea, 1e-9,
              ea < 1e-9 and len(inner) == 18 and sum(b[3] for b in al) == len(d.top),
              "the top row, on the fitted line, in every bin but the two at the wall")
        ra = along_roundtrip(d, work, dr)
        ei = max(abs(ra[b][1] / uh - 1) for b in range(1, 19))
        check(tag + " --along file read back: speed / u(dr/2) - 1 in the inner bins", ei, 1e-5,
              ei < 1e-5 and sorted(ra) == list(range(20)) and all(ra[b][4] == 2 for b in ra),
              "write_along and read_along (6 digits), both snapshots in every bin")
        rt = table_roundtrip(d, work, dr)
        check(tag + " printed table read back: top grains - u(dr/2), cm/s", abs(rt - 100 * uh), 0.005,
              abs(rt - 100 * uh) <= 0.005, "read_table of table_row, as filter_interval_chart reads it")
        bias[dr] = d.surface_speed() / U - 1
        check(tag + " Shepard reading / u(0) - 1", bias[dr], "in (-0.1, 0)", -0.1 < bias[dr] < 0,
              "a one-sided average below the surface")
        delta, Q, us, L2, B2 = dl.layer(d)
        rM = YS + 0.5 * dr
        eL = abs(L2 - (R * R - rM * rM)) / (R * R)
        check(tag + " half chord^2", eL, 1e-12, eL < 1e-12, "R^2 - r_M^2")
        eB = abs(B2 - (R * R - (rM + delta) ** 2)) / (R * R)
        check(tag + " radius^2 below the layer", eB, 1e-12, eB < 1e-12, "R^2 - (r_M + delta)^2")
        sp = dl.stress_profile(d, s, work)
        pp = sp["particles"]
        nrow = min(len(pp["zeta"]), int(0.9 * DELTA / dr))
        k = np.arange(nrow)
        ez = np.max(np.abs(pp["zeta"][:nrow] - (k + 0.5) * dr)) / dr
        check(tag + " zeta of the rows - (k + 1/2) dr, in dr", ez, 1e-9, ez < 1e-9, "the lattice's rows")
        zr = (k + 0.5) * dr
        eu = np.max(np.abs(pp["u_t"][:nrow] - np.interp(zr, z, u))) / U
        check(tag + " u_t(zeta) - u", eu, 1e-9, eu < 1e-9, "the laid profile")
        ep = np.max(np.abs(pp["p"][1:nrow] / np.interp(zr[1:], z, p) - 1))
        check(tag + " p(zeta) / p - 1", ep, 1e-9, ep < 1e-9, "the laid pressure")
        rows = np.sum(np.interp((np.arange(int(DELTA / dr) + 2) + 0.5) * dr, z, u)) * dr
        fp = sp["flux_particles"][0]
        check(tag + " particles' flux / row sum - 1", abs(fp / rows - 1), 1e-9, abs(fp / rows - 1) < 1e-9,
              "sum over the rows of u dr")
        ok = ~np.isnan(sp["u_t"])
        fi = dl.TRAPZ(sp["u_t"][ok], sp["depth"][ok])
        check(tag + " interpolated flux / particles' flux", fi / fp, "< 1", fi / fp < 1,
              "the mid-chord starts at the fitted line, half a row down")
        inb = (sp["depth"] > 0.003) & (sp["depth"] < 0.005)
        el = np.max(np.abs(sp["p"][inb] / sp["p_lith"][inb] - 1))
        check(tag + " interpolated p / lithostatic - 1 at 3-5 mm", el, 1e-3, el < 1e-3, "rho g cos(theta) (z + dr/2)")
        # drum_stress_map factor and components on the laid bed, whose p is the reference's: 1 everywhere
        ft = dsm.factor_table([pp], z, p, base=(1.0e-3, 4.0e-3))
        ft += dsm.factor_table([pp], z, p, capacity=True, base=(1.0e-3, 4.0e-3))
        cp = dsm.components([pp], z, p, [2e-3, 3e-3])
        ec = max(max(abs(r[1] - 1) for r in ft), max(abs(v - 1) for r in cp for v in r[1:5]),
                 max(abs(r[5]) + abs(r[6]) for r in cp))  # no shear, no deviator: s_nt / p and sqrt(J2) / p 0
        check(tag + " drum_stress_map factor and components of the laid p: - 1", ec, 1e-9,
              ec < 1e-9 and len(ft) >= 2 * (2 + 4), "p over the reference's own p")
        fs = pp["s_nn"][1:nrow] / np.interp(zr[1:], z, p) - 1, pp["s_tt"][1:nrow] / np.interp(zr[1:], z, p) - 1
        ef = max(np.max(np.abs(fs[0])), np.max(np.abs(fs[1])), np.max(np.abs(pp["s_nt"][1:nrow])) / np.max(p))
        check(tag + " laid isotropic p: s_nn / p - 1, s_tt / p - 1, s_nt / p", ef, 1e-9, ef < 1e-9, "frame_stress")
    # frame_stress of a stress given in a tilted frame (n, t) and turned into x, y: the components come back
    ang = np.radians(THETA)
    n, t = np.array([np.sin(ang), -np.cos(ang)]), np.array([np.cos(ang), np.sin(ang)])
    snn, stt, szz, snt = -3.0, -2.0, -1.5, 0.7
    Q = np.c_[n, t]  # sigma = Q diag-block Q^T, columns n and t
    Sl = Q @ np.array([[snn, snt], [snt, stt]]) @ Q.T
    fsd = dl.frame_stress(np.array([[Sl[0, 0], Sl[1, 1], szz, Sl[0, 1], 0.0, 0.0]]), n, t)
    ef = max(abs(fsd["s_nn"][0] + snn), abs(fsd["s_tt"][0] + stt), abs(fsd["s_zz"][0] + szz), abs(fsd["s_nt"][0] - snt))
    check("frame_stress: a tilted stress turned back into its frame", ef, 1e-12, ef < 1e-12,
          "-sigma_nn, -sigma_tt, -sigma_zz, sigma_nt")
    # drum_stress_map: a block of particles under a surface at THETA, each with s_nn 3, s_tt 2.4, s_zz 2.7
    # Pa (compression positive) turned into x, y: every cell and the mid-chord's mean read (2.4 - 3) / 2.7
    xs = np.stack(np.meshgrid(np.arange(-0.02, 0.02, 2.5e-4), np.arange(-0.02, 0.0, 2.5e-4)), -1).reshape(-1, 2)
    tv, nv = dsm.surface_frame(THETA)
    xs = xs[:, :1] * tv + xs[:, 1:] * nv  # the block's top is the surface line
    Q = np.c_[nv, tv]
    Sl = Q @ np.diag([-3.0, -2.4]) @ Q.T
    S6 = np.tile([Sl[0, 0], Sl[1, 1], -2.7, Sl[0, 1], 0.0, 0.0], (len(xs), 1))
    v = dsm.tt_minus_nn(S6, THETA)
    xc, yc, mv, cnt = dsm.grid_map(xs, v)
    mc, nmc = dsm.under_midchord(xs, v, THETA)
    em = max(float(np.max(np.abs(mv + 0.6 / 2.7))), abs(mc + 0.6 / 2.7))
    check("drum_stress_map: (s_tt - s_nn) / p of a uniform tilted stress, every cell and the mid-chord", em, 1e-12,
          em < 1e-12 and cnt.sum() == len(xs) and nmc > 0, "(2.4 - 3) / 2.7")
    check("reading bias shrinks with dr", abs(bias[0.0005]) / abs(bias[0.0007]), "< 1",
          abs(bias[0.0005]) < abs(bias[0.0007]), "a support of 2 h = 3 dr")
    g = (np.arange(400) + 0.5) * 1e-5  # 100 grid points in each 1-mm bin of zeta, none on an edge
    ug = np.where(g < 0.003, 0.08 - 10 * g, np.nan)  # a linear speed, absent from 3 mm on
    got = [lfc.binned(g, ug, lo, lo + 1e-3) for lo in (0.0, 1e-3, 2e-3, 3e-3)]
    eb = max(abs(float(got[k]) - 100 * (0.08 - 10 * (1e-3 * k + 5e-4))) for k in range(3))
    check("layer_fe_chart --table: 1-mm bin means of a linear speed - its bin centre's, cm/s", eb, 5e-4,
          eb <= 5e-4 and got[3] == "nan", "the mean of a linear profile over a bin; nan where the run has none")
    spread_table(work)
    depth_profiles(work)
    sys.exit(summary("test_drum_readers"))


def spread_table(work):
    """periodic_drum table on made-up drum_analysis tables: a run to the CSV, an ensemble's spread to _spread."""
    def block(label, speeds, idx):
        rows = "".join("   %.3f    21.00°     0.10 dr      %.2f cm/s       %.4f 0.100-0.600     %.2f cm/s\n"
                       % (t, v, c, v) for t, v, c in zip((1.0, 2.0, 3.0, 4.0, 5.0), speeds, idx))
        return "=== %s: rc 0\n   t (s)     angle   flatness   max |u| mc    seg index    C range  top grains u\n%s" % (
            label, rows)
    txt = (block("2D dr 0.001", (9, 9, 7.0, 7.1, 7.2), (0, 0, 0.020, 0.021, 0.022))
           + block("2D dr 0.001 run 0", (9, 9, 7.0, 7.0, 7.0), (0, 0, 0.020, 0.020, 0.020))
           + block("2D dr 0.001 run 1", (9, 9, 7.3, 7.3, 7.3), (0, 0, 0.024, 0.024, 0.024)))
    src, out = os.path.join(work, "periodic_runs.txt"), os.path.join(work, "periodic.csv")
    with open(src, "w") as f:
        f.write(txt)
    pdrum.table(argparse.Namespace(files=[src], csv=out))
    rows = list(csv.DictReader(open(out)))
    sp = list(csv.DictReader(open(pdrum.spread_path(out))))
    want = [7.1, 0.021, 2, 7.15, 0.3 / np.sqrt(2), 0.022, 0.004 / np.sqrt(2)]
    got = [float(rows[0]["speed_cm_s"]), float(rows[0]["index"])] + [float(sp[0][k]) for k in (
        "runs", "speed_mean_cm_s", "speed_sd_cm_s", "index_mean", "index_sd")] if len(rows) == len(sp) == 1 else []
    err = max(abs(g / w - 1) for g, w in zip(got, want)) if got else np.inf
    check("periodic_drum table: a run's means and an ensemble's count, mean, SD (relative)", err, 1e-3,
          err < 1e-3, "the made-up tables' values, to the CSV's 4 digits")


def depth_profiles(work):
    """periodic_drum depth on a made-up profile of known layer depth, speeds and shear-rate ratio."""
    R, dr, U, D = 0.035, 0.0007, 0.08, 0.0063
    d = np.linspace(0, 0.8 * R, 801)  # 3.5e-5 m apart: 0.05 dr
    u = np.where(d < D, U * (1 - d / D) ** 2, 0.5 * (d - D))
    du = np.abs(np.gradient(u, d))
    errs = []
    for k in (1.0, 1.2):
        path = os.path.join(work, "x_%g_profiles.csv" % k)
        with open(path, "w") as f:
            f.write("t,d_mc,speed,gdot,C\n")
            f.writelines("3,%.9g,%.9g,%.9g,0.5\n" % (q / R, v, k * g) for q, v, g in zip(d, u, du))
        (t, top, sp, gd, lay, ratio), = pdrum.depth_rows(path, dr)
        want = [U * (1 - q * dr / D) ** 2 for q in (1, 3)]
        errs.append((abs(lay - D) / (d[1] - d[0]), max(abs(sp[i] / want[i] - 1) for i in (0, 1)), abs(ratio / k - 1)))
    e = np.max(errs, axis=0)
    check("periodic_drum depth: layer's foot - D (samples)", e[0], 1.0, e[0] <= 1.0, "where u is least")
    check("periodic_drum depth: speed at 1, 3 dr / the profile's - 1", e[1], 2e-2, e[1] < 2e-2,
          "the nearest sample, 0.05 dr away at most")
    check("periodic_drum depth: shear-rate ratio / k - 1 (k = 1, 1.2)", e[2], 1e-2, e[2] < 1e-2,
          "finite differences of the sampled profile")
    path = os.path.join(work, "surface.csv")
    with open(path, "w") as f:
        f.write("call,variant,dim,dr_m,threshold_frac,t_s,speed_cm_s,seg_index\n"
                "1,base,2D,0.0005,0.75,2,8,0.01\n1,base,2D,0.0005,0.75,3,9,0.02\n1,base,2D,0.0005,0.75,4,20,0.9\n"
                "1,base,3D,0.0005,0.8333,1,50,0.5\n1,base,3D,0.0005,0.8333,2,7,0.01\n1,base,3D,0.0005,0.8333,3,8,0.01\n")
    runs = pdrum.surface_runs(path)
    two, three = runs[("base", "2D", 0.0005, 0.75)], runs[("base", "3D", 0.0005, 0.8333)]
    ts = sorted(set(two) & set(three))
    got = pdrum._mean(two, ts) + pdrum._mean(three, ts)
    e = max(abs(g - w) for g, w in zip(got, (8.5, 0.015, 7.5, 0.01)))
    check("periodic_drum surface: means over the shared t = 2-3 s (t = 1 and 4 left out)", e, 1e-12,
          e < 1e-12 and ts == [2.0, 3.0], "the made-up rows")


if __name__ == "__main__":
    main()
