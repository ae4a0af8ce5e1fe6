#!/usr/bin/env python3
"""The particles' own mixing of C (issue 57 item 1): how fast material particles wander off the
continuum's motion, as a diffusivity to set beside the physical one, D = chi_D gdot d_avg^2 (eq. 2.7).

C rides with the particles (the conservative scheme moves no C with a particle's motion), so any
motion of a particle relative to its neighbours mixes C as a diffusion would: the SPH particles'
velocity noise, and the shifting's displacements. This tool measures that motion between closely
spaced snapshots of one run (same particles, found by ParticleIDs):

- for each material particle i and each pair of snapshots (t, t + tau), its neighbours j != i
  within --radius h of it at t give a least-squares fit of their displacements,
  x_j(t + tau) - x_j(t) ~ a + G dx + (second order in dx, --order 2), dx = x_j(t) - x_i(t):
  the continuum's motion over tau, with its gradient and curvature, at i's place;
- i's departure from it is delta_i = (x_i(t + tau) - x_i(t)) - a; its mean square is divided by
  1 + [A^-1]_00 (A the fit's normal matrix), the intercept's share of the neighbours' own noise
  for independent errors of equal size;
- only particles whose neighbourhood is full are fitted: at least --full of the median count
  (the material's interior: the free surface and the wall's row have one-sided neighbourhoods);
- the mean square departure M(tau) is taken per class of shear rate (the snapshots' ShearRate,
  the mean of the two times) over every pair of snapshots at each lag; a diffusion of D_num in a
  simple shear of rate gdot gives M = D_num (2 dim tau + (2/3) gdot^2 tau^3) + M0: the first term
  the walk itself, the second its shear dispersion (a walk across the streamlines carried apart
  by the shear; Taylor's, the variance along the flow growing as 2 D gdot^2 tau^3 / 3), M0 a
  jitter that does not grow with tau (a particle rattling in its cage of neighbours does not
  mix C). D_num and M0 are the least-squares fit of that line over the lags, with the class's
  mean gdot^2; dim is the run's dimension (2: the drum's plane). Its standard error (D_num_se)
  is the spread of the same fit over the particles split into 8 groups by ID;
- D_perp, the one segregation feels: the departure's part across the streamline in the x, y
  plane (normal to the fitted motion a there; a drum turning about z, in 2D or 3D), whose mean
  square M_perp = 2 D_perp tau + M0_perp has no shear dispersion; fitted over the lags of at
  least --fit-from intervals. The walk is ballistic at first (M grows as tau^2 while a particle
  keeps its velocity off its neighbours', 20-40 ms on the drums), so the slopes are taken past
  that: in the drums' study, lags 10-160 ms with the slopes from 40 ms;
- D_phys in a class is the mean of chi_D gdot d_avg^2 over the same particles and times, with
  d_avg = d_small C + d_large (1 - C) and chi_D, d_small, d_large from the run's
  used_params.yml; under Segregation:shear_rate yielded the mean still takes every particle's
  gdot (the ratio then states the mixing against the diffusion where the grains flow).

The fit's radius sets what counts as the continuum: motion coherent over 2h moves C as the flow
does; motion relative to the neighbours within 2h is mixing at the resolution's scale. The fit
follows a smooth deformation (second order over the neighbourhood; the JSON records the largest
gdot tau of each class). Snapshots must be evenly spaced: e.g. restart a developed flow from its
checkpoint with -P Output:dt=0.01 -P Run:t_end=T+0.2 (tools/studies/drum_mixing.sh). In a
container periodic along an axis, the particles within the radius of the periodic faces have no
full neighbourhood in the snapshot (no images) and are left out with the rest.

  python3 -m tools.analysis.drum_mixing RUNDIR [--lags 1 2 4 8 12] [--fit-from 1] [--stride 1]
                                       [--radius 2] [--order 2] [--json F]
  python3 -m tools.analysis.drum_mixing table F.json... --csv C   (a row per run and class of shear rate)
  python3 -m tools.analysis.drum_mixing chart --csv C --png P     (D_perp / D_phys in the layer against dr)

Reads h5py, numpy, PyYAML; needs no scipy (a cell list of its own).
"""
import argparse
import json
import math
import os
import sys

import numpy as np

from tools.analysis import snap  # noqa: E402

BINS = (0.0, 0.5, 2.0, 5.0, 10.0, math.inf)  # shear-rate classes, 1/s: the bed's noise, the layer's base, the layer


def read_params(rundir):
    """What the measurement reads of the run's used_params.yml, which holds every key the run used
    (defaults included): a missing key is an error, not a default the run may not have had."""
    import yaml
    with open(os.path.join(rundir, "used_params.yml")) as f:
        par = yaml.safe_load(f)
    g, sg = par["Geometry"], par["Segregation"]
    gr = par.get("Grains", sg)  # an output written before the Grains section: Segregation's (as drum_analysis)
    fl = par.get("Flow", {})
    dr = float(g["dr"])
    return {"dr": dr, "h": float(g["h_factor"]) * dr, "chi_D": float(sg["chi_D"]),
            "d_small": float(gr["d_small"]), "d_large": float(gr["d_large"]),
            "shift_coeff": fl.get("shift_coeff"), "shifting": str(fl.get("shifting", "?"))}  # labels only


def load(rundir):
    """The material of each snapshot, rows in ParticleIDs order: (times, dim, [dict x, gdot, C, id])."""
    frames, times, dim = [], [], 2
    for p in snap.list_snapshots(rundir):
        s = snap.read_snapshot(p)
        dim = int(s.get("Dimension", 2))
        m = np.asarray(s["Kind"]) == snap.MATERIAL
        ids = np.asarray(s["ParticleIDs"])[m]
        o = np.argsort(ids, kind="stable")
        frames.append({"id": ids[o], "x": np.asarray(s["Coordinates"])[m][o, :dim],
                       "gdot": np.asarray(s["ShearRate"])[m][o], "C": np.asarray(s["Concentration"])[m][o]})
        times.append(float(s["Time"]))
    return np.array(times), dim, frames


def pairs_within(x, r):
    """Every ordered pair (i, j), i != j, with |x_i - x_j| < r: a cell list of side r, numpy only."""
    n, dim = x.shape
    c = np.floor((x - x.min(0)) / r).astype(np.int64)
    span = c.max(0) + 3
    key = np.zeros(n, np.int64)
    for d in range(dim):
        key = key * span[d] + (c[:, d] + 1)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    I, J = [], []
    for off in np.ndindex(*([3] * dim)):
        dk = 0
        for d in range(dim):
            dk = dk * span[d] + (off[d] - 1)
        lo = np.searchsorted(ks, key + dk, "left")
        hi = np.searchsorted(ks, key + dk, "right")
        cnt = hi - lo
        if cnt.sum() == 0:
            continue
        i = np.repeat(np.arange(n), cnt)
        start = np.repeat(lo - np.concatenate(([0], np.cumsum(cnt)[:-1])), cnt)
        j = order[start + np.arange(cnt.sum())]
        I.append(i)
        J.append(j)
    I, J = np.concatenate(I), np.concatenate(J)
    dx = x[J] - x[I]
    keep = (I != J) & (np.einsum("ij,ij->i", dx, dx) < r * r)
    return I[keep], J[keep]


def basis(dx, order):
    """The fit's functions of dx (scaled by the radius): 1, dx, and with order 2 the products."""
    cols = [np.ones(len(dx))] + [dx[:, d] for d in range(dx.shape[1])]
    if order >= 2:
        cols += [dx[:, a] * dx[:, b] for a in range(dx.shape[1]) for b in range(a, dx.shape[1])]
    return np.stack(cols, 1)


def fit_frame(x0, r, order, full):
    """The least-squares fit's operator at one frame (positions x0): each particle's neighbours j != i
    within r, their basis rows, the inverse normal matrices and the fitted mask."""
    n = len(x0)
    I, J = pairs_within(x0, r)
    cnt = np.bincount(I, minlength=n)
    phi = basis((x0[J] - x0[I]) / r, order)
    k = phi.shape[1]
    ok = cnt >= max(full * np.median(cnt[cnt > 0]), 2 * k)
    A = np.zeros((n, k, k))
    for a in range(k):
        for b in range(a, k):
            A[:, a, b] = A[:, b, a] = np.bincount(I, weights=phi[:, a] * phi[:, b], minlength=n)
    A[~ok] = np.eye(k)
    Ainv = np.linalg.inv(A)
    ok &= np.isfinite(Ainv[:, 0, 0]) & (Ainv[:, 0, 0] > 0) & (Ainv[:, 0, 0] < 1)  # a well-posed intercept
    return {"I": I, "J": J, "phi": phi, "Ainv": Ainv, "ok": ok}


def departures(fit, x0, x1):
    """Each particle's departure from its neighbours' fitted motion between two frames (positions x0,
    x1 of the same particles, fit from fit_frame(x0)): the mean-square departure corrected for the
    fit's own noise."""
    I, J, phi, Ainv = fit["I"], fit["J"], fit["phi"], fit["Ainv"]
    n, k = len(x0), phi.shape[1]
    disp = x1 - x0
    B = np.zeros((n, k, disp.shape[1]))
    for a in range(k):
        for d in range(disp.shape[1]):
            B[:, a, d] = np.bincount(I, weights=phi[:, a] * disp[J, d], minlength=n)
    a0 = np.einsum("nk,nkd->nd", Ainv[:, 0, :], B)  # the fitted motion at x_i: the intercept
    delta = disp - a0
    corr = 1 + Ainv[:, 0, 0]
    msd = np.einsum("ij,ij->i", delta, delta) / corr
    # across the streamline in the drum's plane: the departure's part in x, y normal to the fitted motion a0's
    # (in 3D the flow is taken to lie in x, y, as a drum turning about z: motion along z mixes no C there)
    amag = np.hypot(a0[:, 0], a0[:, 1])
    amag[amag == 0] = 1
    perp = (delta[:, 0] * a0[:, 1] - delta[:, 1] * a0[:, 0]) / amag
    return msd, perp * perp / corr


def measure(rundir, lags=(1, 2, 4, 8, 12), radius=2.0, order=2, full=0.85, bins=BINS, fit_from=1, stride=1):
    par = read_params(rundir)
    times, dim, frames = load(rundir)
    if len(times) < 2:
        raise SystemExit("drum_mixing: %s: fewer than two snapshots" % rundir)
    dt = np.diff(times)
    step = float(np.median(dt))
    if np.max(np.abs(dt - step)) > 0.01 * step:
        raise SystemExit("drum_mixing: %s: snapshots not evenly spaced (%.3g to %.3g s)" % (rundir, dt.min(), dt.max()))
    lags = [L for L in lags if L < len(times)]
    nb = len(bins) - 1
    G = 8  # particles split by ID mod G: the spread of D_num over the G groups gives its standard error
    acc = {L: {k: np.zeros(nb) for k in ("m", "mp", "n", "g", "g2", "D", "gt")} for L in lags}
    accg = {L: {k: np.zeros(nb * G) for k in ("m", "mp", "n")} for L in lags}
    r = radius * par["h"]
    fits = {}
    for L in lags:
        for k in range(0, len(times) - L, stride):
            f0, f1 = frames[k], frames[k + L]
            if np.array_equal(f0["id"], f1["id"]):  # the same particles (a closed drum): one fit per origin
                common, i0, i1 = f0["id"], slice(None), slice(None)
                if k not in fits:
                    fits[k] = fit_frame(f0["x"], r, order, full)
                fit = fits[k]
            else:
                common, i0, i1 = np.intersect1d(f0["id"], f1["id"], return_indices=True)
                fit = fit_frame(f0["x"][i0], r, order, full)
            x0, x1 = f0["x"][i0], f1["x"][i1]
            (msd, mperp), ok = departures(fit, x0, x1), fit["ok"]
            g = 0.5 * (f0["gdot"][i0] + f1["gdot"][i1])
            C = f0["C"][i0]
            d = par["d_small"] * C + par["d_large"] * (1 - C)
            Dp = par["chi_D"] * g * d * d
            b = np.clip(np.searchsorted(bins, g, "right") - 1, 0, nb - 1)
            a = acc[L]
            a["m"] += np.bincount(b[ok], weights=msd[ok], minlength=nb)
            a["mp"] += np.bincount(b[ok], weights=mperp[ok], minlength=nb)
            a["n"] += np.bincount(b[ok], minlength=nb)
            a["g"] += np.bincount(b[ok], weights=g[ok], minlength=nb)
            a["g2"] += np.bincount(b[ok], weights=g[ok] ** 2, minlength=nb)
            bg = (b * G + common % G)[ok]
            accg[L]["m"] += np.bincount(bg, weights=msd[ok], minlength=nb * G)
            accg[L]["n"] += np.bincount(bg, minlength=nb * G)
            accg[L]["mp"] += np.bincount(bg, weights=mperp[ok], minlength=nb * G)
            a["D"] += np.bincount(b[ok], weights=Dp[ok], minlength=nb)
            a["gt"] = np.maximum(a["gt"], [g[ok & (b == q)].max() * L * step if (ok & (b == q)).any() else 0
                                           for q in range(nb)])
    classes = []
    tau = np.array([L * step for L in lags])
    use = np.array([L >= fit_from for L in lags])  # the lags the slopes are fitted over
    for q in range(nb):
        n = np.array([acc[L]["n"][q] for L in lags])
        if n.min() == 0:
            continue
        g2 = sum(acc[L]["g2"][q] for L in lags) / n.sum()
        f_tot = 2 * dim * tau + (2.0 / 3.0) * g2 * tau ** 3  # M = D_num f + M0
        f_perp = 2 * tau  # across the streamline: no shear dispersion

        def fit(M, f):
            if use.sum() > 1:
                return np.linalg.lstsq(np.stack([f[use], np.ones(use.sum())], 1), M[use], rcond=None)[0]
            return M[use][0] / f[use][0], 0.0

        def fitted(key, f):
            M = np.array([acc[L][key][q] for L in lags]) / n
            D, icpt = fit(M, f)
            Dg = []
            for gi in range(G):
                ng = np.array([accg[L]["n"][q * G + gi] for L in lags])
                if ng.min() > 0:
                    Dg.append(fit(np.array([accg[L][key][q * G + gi] for L in lags]) / ng, f)[0])
            se = float(np.std(Dg, ddof=1) / math.sqrt(len(Dg))) if len(Dg) > 2 else None
            return M, float(D), float(icpt), se
        M, Dn, icpt, se = fitted("m", f_tot)
        Dph = sum(acc[L]["D"][q] for L in lags) / n.sum()
        c = {"gdot_lo": bins[q], "gdot_hi": None if math.isinf(bins[q + 1]) else bins[q + 1],
             "n": int(n.sum()), "gdot_mean": float(sum(acc[L]["g"][q] for L in lags) / n.sum()),
             "D_phys": float(Dph), "D_num": Dn, "D_num_se": se, "ratio": Dn / Dph if Dph > 0 else None,
             "M0": icpt, "msd": [float(m) for m in M],
             "msd_over_2dim_tau": [float(m / (2 * dim * t)) for m, t in zip(M, tau)],
             "gdot_tau_max": float(max(acc[L]["gt"][q] for L in lags))}
        # across the streamline in the x, y plane
        Mp, Dp, icp, sep = fitted("mp", f_perp)
        c.update({"D_perp": Dp, "D_perp_se": sep, "ratio_perp": Dp / Dph if Dph > 0 else None, "M0_perp": icp,
                  "msd_perp_over_2tau": [float(m / (2 * t)) for m, t in zip(Mp, tau)]})
        classes.append(c)
    return {"run": os.path.abspath(rundir), "dr": par["dr"], "h": par["h"], "dim": dim, "t0": float(times[0]),
            "t1": float(times[-1]), "snapshot_dt": step, "lags_s": [float(t) for t in tau],
            "fit_from_s": float(fit_from * step), "radius_h": radius,
            "order": order, "full": full, "shifting": par["shifting"], "shift_coeff": par["shift_coeff"],
            "classes": classes}


def report(res):
    print("%s: dr %.3g mm, t %.4g-%.4g s, lags %s ms (slopes from %.3g ms), fit radius %g h, order %d" % (
        res["run"], res["dr"] * 1e3, res["t0"], res["t1"], " ".join("%.3g" % (t * 1e3) for t in res["lags_s"]),
        res["fit_from_s"] * 1e3, res["radius_h"], res["order"]))
    print("%-10s %8s %6s %10s %10s %8s %7s %10s %8s %7s %7s" % (
        "gdot 1/s", "samples", "mean", "D_phys", "D_num", "+-", "ratio", "D_perp", "+-",
        "ratio", "gdot tau"))
    for c in res["classes"]:
        rng = "%g-%s" % (c["gdot_lo"], "" if c["gdot_hi"] is None else "%g" % c["gdot_hi"])
        r = lambda x: "-" if x is None else "%.3f" % x
        print("%-10s %8d %6.3g %10.3e %10.3e %8.1e %7s %10s %8s %7s %7.3g" % (
            rng, c["n"], c["gdot_mean"], c["D_phys"], c["D_num"], c["D_num_se"] or float("nan"), r(c["ratio"]),
            "%.3e" % c["D_perp"], "%.1e" % (c["D_perp_se"] or float("nan")), r(c["ratio_perp"]), c["gdot_tau_max"]))


CSV_COLS = ["label", "dr_mm", "radius_h", "lags_ms", "fit_from_ms", "gdot_lo", "gdot_hi", "n", "gdot_mean", "D_phys",
            "D_num", "D_num_se", "ratio", "D_perp", "D_perp_se", "ratio_perp", "k_perp"]


def table(files, path):
    """One CSV row per run and class of shear rate; k_perp = D_perp / (gdot_mean dr^2)."""
    import csv
    rows = []
    for f in files:
        with open(f) as fh:
            r = json.load(fh)
        lab = r.get("label", os.path.basename(r["run"]).rsplit("_dr", 1)[0])
        for c in r["classes"]:
            rows.append({"label": lab, "dr_mm": "%g" % (r["dr"] * 1e3), "radius_h": "%g" % r["radius_h"],
                         "lags_ms": " ".join("%g" % (t * 1e3) for t in r["lags_s"]),
                         "fit_from_ms": "%g" % (r["fit_from_s"] * 1e3), "gdot_lo": "%g" % c["gdot_lo"],
                         "gdot_hi": "" if c["gdot_hi"] is None else "%g" % c["gdot_hi"], "n": c["n"],
                         "gdot_mean": "%.4g" % c["gdot_mean"], "D_phys": "%.4g" % c["D_phys"],
                         "D_num": "%.4g" % c["D_num"], "D_num_se": "%.2g" % (c["D_num_se"] or 0),
                         "ratio": "%.4g" % (c["ratio"] or 0), "D_perp": "%.4g" % c.get("D_perp", 0),
                         "D_perp_se": "%.2g" % (c.get("D_perp_se") or 0), "ratio_perp": "%.4g" % (c.get("ratio_perp") or 0),
                         "k_perp": "%.4g" % (c.get("D_perp", 0) / (c["gdot_mean"] * r["dr"] ** 2))})
    rows.sort(key=lambda x: (x["label"], x["radius_h"], -float(x["dr_mm"]), float(x["gdot_lo"])))
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, CSV_COLS)
        w.writeheader()
        w.writerows(rows)
    print("wrote %s (%d rows)" % (path, len(rows)))


def chart(csv_path, png, radius="2"):
    """D_perp / D_phys in the flowing layer (gdot >= 10 1/s) and at its base (5-10) against dr, per drum and
    shifting, with the slope of dr^2."""
    import csv
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    with open(csv_path) as fh:
        rows = [r for r in csv.DictReader(fh) if r["radius_h"] == radius]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    labels = sorted({r["label"] for r in rows})
    colours = {"EV": "tab:blue", "EN": "tab:red", "EV3D": "tab:green"}
    for lab in labels:
        for lo, ls, mk in (("10", "-", "o"), ("5", ":", "s")):
            pts = sorted((float(r["dr_mm"]), float(r["ratio_perp"])) for r in rows if r["label"] == lab and r["gdot_lo"] == lo)
            if not pts:
                continue
            drum, var = lab.split("_", 1)
            ax.plot(*zip(*pts), ls if var == "shift" else "--", marker=mk, color=colours.get(drum, "k"),
                    alpha=1.0 if var == "shift" else 0.5, mfc="none" if var != "shift" else None,
                    label="%s, %s, gdot %s" % (drum.replace("3D", " periodic 3D"), "Fickian shifting" if var == "shift" else "no shifting",
                                                ">= 10 1/s" if lo == "10" else "5-10 1/s"))
    x = [min(float(r["dr_mm"]) for r in rows), max(float(r["dr_mm"]) for r in rows)]
    ax.plot(x, [0.4 * (v / 0.25) ** 2 for v in x], color="0.5", lw=0.8, label="slope dr^2")
    ax.axhline(1, color="0.7", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("dr (mm)")
    ax.set_ylabel("D_perp / (chi_D gdot d_avg^2)")
    ax.legend(fontsize=6.5, ncol=2)
    ax.set_title("the particles' own cross-stream mixing against eq. 2.7's diffusion (fit radius %s h)" % radius,
                 fontsize=8.5)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    print("wrote", png)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "table":
        ap = argparse.ArgumentParser(prog="drum_mixing table")
        ap.add_argument("files", nargs="+")
        ap.add_argument("--csv", required=True)
        a = ap.parse_args(argv[1:])
        table(a.files, a.csv)
        return 0
    if argv and argv[0] == "chart":
        ap = argparse.ArgumentParser(prog="drum_mixing chart")
        ap.add_argument("--csv", required=True)
        ap.add_argument("--png", required=True)
        ap.add_argument("--radius", default="2", help="the fit radius's rows (in h; default 2)")
        a = ap.parse_args(argv[1:])
        chart(a.csv, a.png, a.radius)
        return 0
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rundir")
    ap.add_argument("--lags", type=int, nargs="+", default=[1, 2, 4, 8, 12], help="lags in snapshot intervals")
    ap.add_argument("--stride", type=int, default=1, help="time origins every this many snapshots (default 1: all)")
    ap.add_argument("--fit-from", type=int, default=1, help="the slopes over the lags of at least this many intervals")
    ap.add_argument("--radius", type=float, default=2.0, help="the fit's radius, in h (default 2: the kernel's support)")
    ap.add_argument("--order", type=int, choices=(1, 2), default=2, help="1: affine fit; 2: with curvature (default)")
    ap.add_argument("--full", type=float, default=0.85, help="fitted where the count is >= this x the median")
    ap.add_argument("--label", default=None, help="the run's name in the JSON (default: the folder's, less _drN)")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    res = measure(a.rundir, a.lags, a.radius, a.order, a.full, fit_from=a.fit_from, stride=a.stride)
    if a.label:
        res["label"] = a.label
    report(res)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
