#!/usr/bin/env python3
"""The flowing layer on a 2D drum's mid-chord (docs/granular.md "Stabilisation"):
the velocity along the free surface u_t(d) at depth d below it, the layer's
thickness delta (the depth where u_t turns from downslope to the bed's
upslope rotation), its downslope flux Q = integral of u_t over the layer, and
the flux a rigid bed would carry up through the mid-chord below the layer,
omega (R^2 - (r_M + delta)^2) / 2 (r_M the surface's distance from the axis;
in a steady rolling drum the layer carries down what the bed brings up), and
omega L^2 / 2 (L the half chord: the same with delta -> 0). If Q matches and
delta shrinks with dr, the layer's thickness, not the supply, sets the surface
speed.

With --stress CSV (2D drums): the stress state down the mid-chord, to hold
against the mu(I) law point by point. Per depth (Shepard interpolations of the
material particles, as drum_analysis): u_t, the pressure p = -tr sigma / 3,
sqrt(J2), their ratio, the shear rate, C, I = gdot d_avg / sqrt(p / rho_s),
the yield ratio k(mu(I)) that a particle on its yield surface would hold at
that I (Material:yield), and the lithostatic pressure rho g cos(theta) z of a
uniform layer, z = depth + dr / 2 (the top row's centres lie half a spacing
below the material's edge), and phi, the particles' kernel-summed volume
fraction sum_j V_j W_ij (1 where they hold their nominal volumes), from the
particles of a strip |s| < 0.05 R about the mid-chord. A summary is printed at
1-mm steps, with the net flux through the mid-chord twice: the integral of the
interpolated u_t, and the strip's particles' own sum V u_t / width. In a
steady drum both are 0; the first is not when the line fitted to the top
grains runs below the material's surface (it starts the mid-chord there).

It also writes CSV_particles.csv (CSV less .csv): the strip's particles
against their mass depth zeta, the volume of the strip's material above them
per width (half their own), in bins of dr: zeta, their mean depth below the
line, u_t, p, sqrt(J2), the shear rate, the compressive normal stresses
across the surface, along it and out of the plane (s_nn, s_tt, s_zz) and the
shear s_nt (frame_stress), and their count. zeta is the depth
below a flat surface holding the same material (the finite-element reference's
depth, tools/analysis/drum_mui_ref.py), whatever the fitted line misses, and
the profile's flux is the particles'.

  /usr/bin/python3 -m tools.analysis.drum_layer OUTDIR [OUTDIR ...] [--time T] [--stress CSV]
"""
import argparse
import os

import numpy as np

from tools.analysis import drum_analysis as da  # noqa: E402
from tools.analysis import inertial_range as ir  # noqa: E402
from tools.analysis import snap  # noqa: E402

TRAPZ = getattr(np, "trapezoid", None) or np.trapz  # numpy 2 renamed it
STRIP = 0.05  # --stress: half-width of the strip about the mid-chord, in R


def downslope(d, pts):
    """The unit vector along the surface line, pointing down the slope (where the mid-chord's top
    tenth, the points pts, flows)."""
    t = np.array([d.n[1], -d.n[0]])
    top = d.interp(pts[: max(len(pts) // 10, 1)], d.v @ t)
    return t if np.nanmean(top) >= 0 else -t


def layer(d):
    frac, pts = d.midchord(400)
    dep = frac * d.R
    ut = d.interp(pts, d.v @ downslope(d, pts))
    ok = ~np.isnan(ut)
    dep, ut = dep[ok], ut[ok]
    k = np.argmax(ut < 0) if np.any(ut < 0) else len(ut) - 1
    delta = dep[k]
    Q = TRAPZ(ut[: k + 1], dep[: k + 1])
    rM = float(np.hypot(*d.M))  # M is the foot of the perpendicular from the axis
    return delta, Q, ut.max(), d.R ** 2 - rM ** 2, d.R ** 2 - (rM + delta) ** 2


def stress_profile(d, s, outdir, npts=400):
    """The mid-chord columns of --stress (module doc), as a dict of arrays; "particles" holds the
    strip's profile against the mass depth (strip_profile)."""
    P = ir.params(outdir)
    S = np.asarray(s["Stress"])[np.asarray(s["Kind"]) == snap.MATERIAL]
    p, tau = ir.pressure_tau(S)
    frac, pts = d.midchord(npts)
    t = downslope(d, pts)
    o = {"depth": frac * d.R, "u_t": d.interp(pts, d.v @ t), "p": d.interp(pts, p), "sqrtJ2": d.interp(pts, tau),
         "gdot": d.interp(pts, d.gdot), "C": d.interp(pts, d.C)}
    dav = P["d_small"] * o["C"] + P["d_large"] * (1 - o["C"])
    pp = np.maximum(o["p"], 1e-12)
    o["ratio"] = o["sqrtJ2"] / pp
    o["I"] = ir.inertial_number(o["gdot"], dav, pp, P["rho_s"])
    o["k_mu_I"] = ir.yield_ratio(P, o["I"])
    ph = d.par.get("Physics", {})
    g = float(np.hypot(*np.asarray(ph.get("gravity", [0, -9.81, 0]), float)[:2]))
    rho = float(ph.get("rho", 1500.0))
    o["p_lith"] = rho * g * np.cos(np.radians(d.angle)) * (o["depth"] + 0.5 * d.dr)
    strip_profile(d, t, p, tau, o, frame_stress(S, d.n, t))
    return o


def frame_stress(S, n, t):
    """The compressive normal stresses of snapshot stresses S (N x 6: xx, yy, zz, xy, xz, yz) in the
    surface's frame: -sigma_nn across the surface (n its unit normal), -sigma_tt along it (t), -sigma_zz
    out of the plane, and the shear sigma_nt, as a dict of arrays. In a flat, uniform layer sigma_nn
    carries the weight above, and an incompressible mu(I) layer (the FE's) has -sigma_tt = -sigma_zz
    = p, so these locate an excess of p in the component the momentum balance does not hold."""
    S = np.asarray(S)

    def quad(a, b):
        return S[:, 0] * a[0] * b[0] + S[:, 1] * a[1] * b[1] + S[:, 3] * (a[0] * b[1] + a[1] * b[0])

    return {"s_nn": -quad(n, n), "s_tt": -quad(t, t), "s_zz": -S[:, 2], "s_nt": quad(n, t)}


def strip_profile(d, t, p, tau, o, comp=None):
    """The particles of the strip |s| < STRIP R about the mid-chord, into o: their kernel-summed volume
    fraction phi_i = sum_j V_j W_ij (1 where they hold their nominal volumes, below 1 within 2 h of the
    surface) in depth bins of 2 dr ("phi"), the flux they carry through the mid-chord
    ("flux_particles"), and their profile against the mass depth zeta ("particles": the volume of the
    strip's material above them per width, half their own; the FE's depth below its flat surface
    whatever the line fitted to the top grains misses), in bins of dr; with comp (frame_stress's
    components, per particle) their means too."""
    rel = d.x - d.M
    z = rel @ d.n
    strip = np.where(np.abs(rel @ t) < STRIP * d.R)[0]
    phi = np.empty(len(strip))
    for q, i in enumerate(strip):
        j = d.tree.query_ball_point(d.x[i], 2 * d.h)
        phi[q] = np.sum(d.vol[j] * da.wendland(np.hypot(*(d.x[j] - d.x[i]).T) / d.h)) * 7 / (4 * np.pi * d.h ** 2)
    k = np.digitize(z[strip], np.arange(-2 * d.dr, o["depth"][-1] + 2 * d.dr, 2 * d.dr))
    zc = np.array([z[strip][k == b].mean() for b in np.unique(k)])
    o["phi"] = np.interp(o["depth"], zc, [phi[k == b].mean() for b in np.unique(k)])
    vt = d.v @ t
    W = 2 * STRIP * d.R
    o["flux_particles"] = np.full(len(o["depth"]), float(np.sum(d.vol[strip] * vt[strip]) / W))
    order = strip[np.argsort(z[strip])]
    zeta = (np.cumsum(d.vol[order]) - 0.5 * d.vol[order]) / W
    b = np.floor(zeta / d.dr).astype(int)
    comp = comp or {}
    part = {"zeta": [], "z": [], "u_t": [], "p": [], "sqrtJ2": [], "gdot": [], **{k: [] for k in comp}, "n": []}
    for k in np.unique(b):
        sel = order[b == k]
        for key, val in (("zeta", zeta[b == k]), ("z", z[sel]), ("u_t", vt[sel]), ("p", p[sel]), ("sqrtJ2", tau[sel]),
                         ("gdot", d.gdot[sel]), *((c, v[sel]) for c, v in comp.items())):
            part[key].append(float(np.mean(val)))
        part["n"].append(len(sel))
    o["particles"] = {key: np.array(v) for key, v in part.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--time", type=float, default=None, help="snapshot nearest this time (default: the last)")
    ap.add_argument("--stress", help="2D drums: write the stress state down the mid-chord to this CSV (one run: "
                    "this name; several: RUN_ prefixed)")
    a = ap.parse_args()
    print("%-28s %6s %7s %9s %8s %10s %10s %10s %6s" % ("run", "t (s)", "dr (mm)", "delta (mm)", "delta/dr",
                                                       "Q (m^2/s)", "bed below", "w L^2/2", "u_s cm/s"))
    for o in a.outdirs:
        par = da.used_params(o)
        paths = snap.list_snapshots(o)
        p = paths[-1] if a.time is None else da.pick(paths, [a.time])[0]
        s = snap.read_snapshot(p)
        d = da.Drum(p, par, snapshot=s)
        delta, Q, us, L2, B2 = layer(d)
        w = abs(da.drum_wall(par)[1])
        run = os.path.basename(o.rstrip("/"))
        print("%-28s %6.2f %7.2f %9.2f %8.1f %10.3e %10.3e %10.3e %6.2f" % (
            run, d.t, 1e3 * d.dr, 1e3 * delta, delta / d.dr, Q, w * B2 / 2, w * L2 / 2, 100 * us))
        if a.stress:
            sp = stress_profile(d, s, o)
            path = a.stress if len(a.outdirs) == 1 else os.path.join(os.path.dirname(a.stress) or ".",
                                                                     run + "_" + os.path.basename(a.stress))
            pp = sp.pop("particles")
            np.savetxt(path[:-4] + "_particles.csv" if path.endswith(".csv") else path + "_particles",
                       np.c_[tuple(pp.values())], delimiter=",", header=",".join(pp), comments="", fmt="%.6g")
            keys = list(sp)
            np.savetxt(path, np.c_[tuple(sp[k] for k in keys)], delimiter=",", header=",".join(keys),
                       comments="", fmt="%.6g")
            print("  %6s %8s %8s %8s %8s %8s %8s %8s %8s %8s" % ("z (mm)", "u_t cm/s", "p (Pa)", "p_lith", "J2^.5/p",
                                                                   "k(mu(I))", "gdot", "I", "C", "phi"))
            for z in np.arange(0.0, 1e3 * delta + 1.0, 1.0):
                v = {k: np.interp(1e-3 * z, sp["depth"], sp[k]) for k in keys}
                print("  %6.1f %8.3f %8.2f %8.2f %8.4f %8.4f %8.2f %8.4f %8.3f %8.3f" % (
                    z, 100 * v["u_t"], v["p"], v["p_lith"], v["ratio"], v["k_mu_I"], v["gdot"], v["I"], v["C"],
                    v["phi"]))
            ok = ~np.isnan(sp["u_t"])
            print("  net flux through the mid-chord: interpolated %.3e m^2/s, the particles of the strip %.3e "
                  "(0 in a steady drum)" % (TRAPZ(sp["u_t"][ok], sp["depth"][ok]), sp["flux_particles"][0]))
            print("  wrote %s" % path)


if __name__ == "__main__":
    main()
