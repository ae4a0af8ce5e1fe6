#!/usr/bin/env python3
"""Plane Couette flow of a granular layer under gravity (inputs/couette_2d.yml)
against the local mu(I) rheology: the drum's flowing layer and its yield base
without the drum's change along the chord (docs/granular.md "The base alone").

The layer fills 0 < y < H between a fixed base and a lid translating at U along
x, periodic in x, under gravity g along -y. In the steady state nothing varies
along x, so the shear stress tau = -sigma_xy is the same at every depth and the
vertical stress carries the weight, -sigma_yy = sigma_top + rho g z at the depth
z = H - y below the lid. Where the flow shears, steady isochoric simple shear
drives the normal stresses together (p = -sigma_yy; tests/test_stress.c), and
the local rheology sqrt(J2) = k(mu(I)) p with I = gdot d / sqrt(p / rho_s)
gives the shear rate at each depth:

    k(mu(I(z))) = tau / (sigma_top + rho g z),

k of Material:yield (drucker_prager k_mu(mu), mu_I mu). The ratio falls with
depth, so the shear is largest under the lid and stops at the yield depth
z_y = (tau / k(mu_s) - sigma_top) / (rho g): below it the material rests on
the base. The lid's speed is U = integral of gdot from z_y to 0 (no slip at
both walls), which fixes tau for a given U and sigma_top (tau_for_lid).

A run is read per row of particles (bins of dr in y; lid and base rows
excluded from the stresses): tau and sigma_top from the rows (sigma_top =
mean of -sigma_yy - rho g z, exact in equilibrium), then the tau the local
rheology needs to drive the lid at U with that sigma_top. tau / tau_ref(U) is
the check: it is well conditioned, the lid's speed being far more sensitive
to tau than tau is to it. Beside it: the reference's yield depth z_y at
tau_ref, the depth where u falls to 5 % of U (the run's rows, interpolated,
and the reference's), and the flux (the rows' sum of u dr over the
reference's integral). The last two are the drum-like, ill-conditioned
readings (a drum fixes the flux and lets the layer's depth follow), and they
carry the rows at the lid, which move with it.

  /usr/bin/python3 -m tools.analysis.couette OUTDIR [OUTDIR ...] [--times T ...] [--rows CSV]
"""
import argparse
import os

import numpy as np

from tools.analysis import inertial_range as ir  # noqa: E402
from tools.analysis import snap  # noqa: E402

TRAPZ = getattr(np, "trapezoid", None) or np.trapz  # numpy 2 renamed it
DEEP = 1e-3  # m: the flux below this depth leaves out the rows that move with the lid
ROWS = "t,z,u,u_ref,sigma_xy,sigma_yy,gdot,gdot_ref"


def scene(outdir):
    """What the reference needs from the run's used_params.yml: the rheology (inertial_range.params), the
    grain size d (d_large: the scene's C is 0; refused otherwise), H, the lid's speed U, rho and g."""
    import yaml
    with open(os.path.join(outdir, "used_params.yml")) as f:
        u = yaml.safe_load(f)
    P = ir.params(outdir)
    P["lambda"] = float(u["Material"].get("lambda", 1e-3))
    regions = u["Container"]["regions"]
    if any(float(r.get("C", 0)) != 0 for r in regions):
        raise SystemExit("couette: the reference takes one grain size, d_large (C = 0 throughout)")
    lids = [w for w in u["Container"]["walls"] if w.get("motion") == "translating"]
    if len(lids) != 1:
        raise SystemExit("couette: expected one translating wall (the lid), found %d" % len(lids))
    P.update(d=P["d_large"], H=float(u["Geometry"]["height"]), dr=float(u["Geometry"]["dr"]),
             U=abs(float(lids[0]["velocity"][0])), rho=float(u["Physics"]["rho"]),
             g=abs(float(u["Physics"]["gravity"][1])))
    return P


def k_of_mu(mu, P):
    """The yield ratio sqrt(J2) / p at friction mu on P's Material:yield."""
    return mu if P["yield"] == "mu_I" else float(ir.kmu(mu))


def shear_rate(tau, p, P):
    """The local rheology's shear rate where the stress ratio is tau / p, inf at or above mu_d (no
    steady shear there). Regularized law: 0 at or below mu_s (the solver's floor lambda on the shear
    rate, 1e-3 1/s, left out). Partial law (Barker & Gray 2017, as src/physics/stress.h stress_mu):
    below mu(I_N1), I = A exp(-alpha / mu^2) of sqrt(gdot^2 + lambda^2), so the shear rate is 0 only
    where that I is below the floor's."""
    I = ir.inertial_number_of_ratio(tau / p, P)
    g = I * np.sqrt(p / P["rho_s"]) / P["d"]
    if P["mu_law"] != "partial":
        return g
    low = I < ir.partial_regularisation(P["mu_s"], P["mu_d"], P["I0"], P["pr_alpha"])[0]
    return np.where(low, np.sqrt(np.maximum(g * g - P["lambda"] ** 2, 0.0)), g)


def profile(tau, s_top, P, n=20001):
    """Depth z below the lid (0 to H), u(z) (0 at the base, rising to the lid), gdot(z) and p(z) of the
    local rheology at the shear stress tau and the lid's normal stress s_top."""
    z = np.linspace(0.0, P["H"], n)
    p = s_top + P["rho"] * P["g"] * z
    gd = shear_rate(tau, p, P)
    seg = 0.5 * (gd[1:] + gd[:-1]) * np.diff(z)
    u = np.concatenate([np.cumsum(seg[::-1])[::-1], [0.0]])
    return z, u, gd, p


def yield_depth(tau, s_top, P):
    """z_y = (tau / k(mu_s) - s_top) / (rho g), clipped to [0, H] (under the partial law, which has no
    static yield, where the stress ratio falls to k(mu_s))."""
    k = k_of_mu(P["mu_s"], P)
    return float(np.clip((tau / k - s_top) / (P["rho"] * P["g"]), 0.0, P["H"]))


def tau_for_lid(U, s_top, P):
    """The shear stress at which the local rheology's lid moves at U (bisection on u(0), which rises
    with tau), between the static yield stress (0 under the partial law, whose bed creeps at any tau)
    and mu_d's."""
    lo = 0.0 if P["mu_law"] == "partial" else k_of_mu(P["mu_s"], P) * s_top
    hi = k_of_mu(P["mu_d"], P) * s_top
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if profile(mid, s_top, P, 4001)[1][0] < U:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def rows(s, P):
    """Per row of particles (bins of dr in y, top row first): depth z below the lid, u_x, sigma_xy,
    sigma_yy, the shear rate."""
    m = np.asarray(s["Kind"]) == snap.MATERIAL
    x, v = np.asarray(s["Coordinates"])[m], np.asarray(s["Velocities"])[m]
    S, gd = np.asarray(s["Stress"])[m], np.asarray(s["ShearRate"])[m]
    k = np.floor(x[:, 1] / P["dr"]).astype(int)
    out = []
    for b in np.unique(k)[::-1]:
        sel = k == b
        out.append((P["H"] - x[sel, 1].mean(), v[sel, 0].mean(), S[sel, 3].mean(), S[sel, 1].mean(), gd[sel].mean()))
    return np.array(out).T


def measure(s, P):
    """The run's reading of one snapshot against the reference (module doc), as a dict."""
    z, u, sxy, syy, gd = rows(s, P)
    inner = (z > 2 * P["dr"]) & (z < P["H"] - 2 * P["dr"])
    tau = float(np.mean(np.abs(sxy[inner])))
    s_top = float(np.mean(-syy[inner] - P["rho"] * P["g"] * z[inner]))
    tref = tau_for_lid(P["U"], s_top, P)
    zr, ur, gr, _ = profile(tref, s_top, P)

    def depth(zz, uu, frac):  # the first depth from the lid where u falls to frac U
        i = np.nonzero(uu <= frac * P["U"])[0]
        if not len(i) or i[0] == 0:
            return float("nan")
        a = i[0]
        return float(zz[a - 1] + (zz[a] - zz[a - 1]) * (uu[a - 1] - frac * P["U"]) / (uu[a - 1] - uu[a]))

    deep = z - 0.5 * P["dr"] >= DEEP - 0.25 * P["dr"]  # the rows whose cells (z -+ dr / 2) lie below DEEP
    zd = zr >= DEEP
    return {"t": float(s["Time"]), "tau": tau, "s_top": s_top, "tau_ref": tref, "ratio": tau / tref,
            "z_yield_ref": yield_depth(tref, s_top, P),
            "z5": depth(z, u, 0.05), "z5_ref": depth(zr, ur, 0.05),
            "flux": float(np.sum(u) * P["dr"]), "flux_ref": float(TRAPZ(ur, zr)),
            "flux_deep": float(np.sum(u[deep]) * P["dr"]), "flux_deep_ref": float(TRAPZ(ur[zd], zr[zd])),
            "u_lid": float(u[0] - np.interp(z[0], zr, ur)) / P["U"],
            "rows": np.c_[z, u, np.interp(z, zr, ur), sxy, syy, gd, np.interp(z, zr, gr)]}


HEAD = "%-22s %6s %6s %8s %8s %9s %8s %7s %7s %15s %8s %8s %7s" % (
    "run", "t (s)", "dr mm", "tau Pa", "s_top Pa", "tau/s_top", "tau_ref", "ratio", "z_y mm",
    "5%U z (ref) mm", "flux/ref", "deep/ref", "lid/U")


def line(run, P, r):
    return "%-22s %6.3f %6.4f %8.3f %8.3f %9.4f %8.3f %7.4f %7.3f %7.3f (%5.3f) %8.4f %8.4f %7.4f" % (
        run, r["t"], 1e3 * P["dr"], r["tau"], r["s_top"], r["tau"] / r["s_top"], r["tau_ref"], r["ratio"],
        1e3 * r["z_yield_ref"], 1e3 * r["z5"], 1e3 * r["z5_ref"], r["flux"] / r["flux_ref"],
        r["flux_deep"] / r["flux_deep_ref"], r["u_lid"])


def read_table(path):
    """The rows of line() in a file of this tool's output (other lines skipped), as dicts: run, t, dr (m),
    tau, s_top, tau_ref, ratio, z_y, z5, z5_ref (m), flux (over the reference's) and, where printed,
    deep (the same below DEEP) and lid (the lid's row over U)."""
    out = []
    for ln in open(path):
        f = ln.replace("(", " ").replace(")", " ").split()
        if len(f) < 12 or f[0] in ("run", "==") or ln[:1].isspace():
            continue
        try:
            v = [float(x) for x in f[1:]]
        except ValueError:
            continue
        r = {"run": f[0], "t": v[0], "dr": 1e-3 * v[1], "tau": v[2], "s_top": v[3], "tau_ref": v[5], "ratio": v[6],
             "z_y": 1e-3 * v[7], "z5": 1e-3 * v[8], "z5_ref": 1e-3 * v[9], "flux": v[10]}
        if len(v) >= 13:
            r.update(deep=v[11], lid=v[12])
        out.append(r)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("outdirs", nargs="+")
    ap.add_argument("--times", type=float, nargs="+", help="snapshots nearest these times (default: the last)")
    ap.add_argument("--rows", help="write every row of the picked snapshots with the reference beside it to this "
                    "CSV (%s; one run: this name, several: RUN_ prefixed)" % ROWS)
    a = ap.parse_args(argv)
    print(HEAD)
    for o in a.outdirs:
        P = scene(o)
        paths = snap.list_snapshots(o)
        picks = [paths[-1]] if not a.times else sorted({min(paths, key=lambda f: abs(snap.snapshot_time(f) - t))
                                                        for t in a.times})
        res = [measure(snap.read_snapshot(f), P) for f in picks]
        run = os.path.basename(o.rstrip("/"))
        for r in res:
            print(line(run, P, r))
        if a.rows:
            path = a.rows if len(a.outdirs) == 1 else os.path.join(os.path.dirname(a.rows) or ".",
                                                                   run + "_" + os.path.basename(a.rows))
            np.savetxt(path, np.vstack([np.c_[np.full(len(r["rows"]), r["t"]), r["rows"]] for r in res]),
                       delimiter=",", header=ROWS, comments="", fmt="%.6g")
        if len(res) > 1:
            rat = np.array([r["ratio"] for r in res])
            print("%-22s mean tau / tau_ref %.4f, s.d. %.4f over %d snapshots" % ("", rat.mean(), rat.std(), len(res)))


if __name__ == "__main__":
    main()
