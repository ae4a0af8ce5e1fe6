"""Convergence of plane Poiseuille flow (inputs/poiseuille_2d.yml) against the
start-up series of Morris, Fox & Zhu (1997).

The scene: a Newtonian fluid (nu = eta / rho = 1e-3 m^2/s) between the no-slip
base (y = 0) and a no-slip lid (y = H = 1 cm), periodic along x, at rest at
t = 0 and driven along x by a body force F = 2 m/s^2. Reference (Morris, Fox &
Zhu 1997, J. Comput. Phys. 136, eq. 21):

    u(y, t) = F/(2 nu) y (H - y)
              - sum_n 4 F H^2 / (nu pi^3 (2n+1)^3) sin((2n+1) pi y / H)
                      exp(-(2n+1)^2 pi^2 nu t / H^2),

steady u_max = F H^2 / (8 nu) = 0.025 m/s; the slowest mode decays as
exp(-pi^2 nu t / H^2) (0.01 s), so at t_end = 0.3 s the series is steady to
round-off (checked and printed).

The scene is run at H/dr = 10, 20, 40 (--rows; the CPU build, two runs at
a time of one thread each on a 2-core machine: 2, 7 and 43 s; 80 takes
68,000 steps, 5.4 minutes with both cores, so it is not in the default set)
to --t-end (0.3 s), with the period
along x 20 dr at every resolution (the minimum is 6 supports 2h = 18 dr; the
flow is uniform along x, so the period changes nothing but the cost: the row
means agree to 1e-16). For each resolution:

  e(t)     the largest error of a row-mean velocity against the series over
           the rows, as a fraction of u_max, at t = 0.01, 0.02, 0.05, 0.1 and
           t_end (the steady state);
  excess   the steady centreline excess, max row mean / max of the series at
           the same rows - 1;
  order    the observed order of e between successive resolutions,
           log2(e(2 dr) / e(dr)), and by least squares over all;
  cost     wall time, and sphseg's "done:" line (steps, particle-steps/s).

The walls: a least-squares parabola u = F/(2 nu_eff) (y - y0)(y1 - y) through
the steady row means separates the curvature (the effective viscosity nu_eff)
from the walls' effective positions y0 (base) and y1 (lid), in units of dr;
and e at t_end is also given against the steady parabola of an effective
channel H + f dr centred on the real one (f = 1/2, 1), to see whether the
error is the walls' position. (With Morris's operator as it was, eta^2 =
(0.1 h)^2 in it, it was not: the walls lay within 0.05 dr of y = 0 and H and
converged at about second order, while nu_eff stayed about 1.5 % low, the
lattice sum of the operator at h = 1.5 dr, printed with the table: a floor
at fixed h/dr. The operator now has no eta^2 and is divided by its lattice
moment, mom_visc_lattice in src/physics/momentum.h, so nu_eff is nu on the
lattice and what is left is the walls', converging at second order.)

  python3 -m tools.studies.poiseuille_study --sphseg build-dev/sphseg --out /tmp/pois_study [--table file] [--docs docs]

Runs --jobs (2) at once, each with OMP_NUM_THREADS = cores / jobs unless set.

--sphseg may carry arguments ("build/sphseg --backend gpu"). Writes under
--out one folder per run (its snapshots), runs.csv (tools/studies/batch.py: exit
status, wall time, steps, rate), profiles.csv (the row means at every
snapshot) and errors.csv; prints the markdown table (--table PATH writes it
too) and draws validation_poiseuille.png in --docs (default --out): left the
row-mean profiles of the finest run at several times against the series,
right e against dr, log-log, with slopes 1 and 2 for reference. --reuse skips
the runs whose snapshots are already there.
"""
import argparse
import csv
import math
import os
import shlex
import sys
import time

import numpy as np

from tools import ROOT  # noqa: E402
from tools.studies import batch  # noqa: E402
from tools.analysis import snap  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "poiseuille_2d.yml")
# inputs/poiseuille_2d.yml
H, NU, F = 0.01, 1.5 / 1500.0, 2.0
UMAX = F * H * H / (8 * NU)
TIMES = (0.01, 0.02, 0.05, 0.1)
PERIOD_DR = 20
SHIFTS = (0.5, 1.0)


def series(y, t, h=H, nu=NU, n=400):
    """Morris et al. (1997) eq. 21 at heights y (walls at 0 and h)."""
    y = np.asarray(y, float)
    k = 2 * np.arange(n) + 1
    return F / (2 * nu) * y * (h - y) - (4 * F * h ** 2 / (nu * np.pi ** 3) * np.sin(np.outer(y, k) * np.pi / h) / k ** 3
                                         * np.exp(-(k * np.pi / h) ** 2 * nu * t)).sum(1)


def steady(y, h=H, nu=NU, y0=0.0):
    """The steady parabola between walls at y0 and y0 + h."""
    y = np.asarray(y, float) - y0
    return F / (2 * nu) * y * (h - y)


def row_means(s, dr):
    """Row-mean height and x velocity of the material of snapshot s, rows of
    the lattice y = (j + 1/2) dr, and the largest spread of u within a row."""
    mat = np.asarray(s["Kind"]) == 0
    y, u = np.asarray(s["Coordinates"])[mat, 1], np.asarray(s["Velocities"])[mat, 0]
    row = np.rint(y / dr - 0.5).astype(int)
    rows = np.unique(row)
    return (np.array([y[row == k].mean() for k in rows]), np.array([u[row == k].mean() for k in rows]),
            max(float(np.ptp(u[row == k])) for k in rows))


def fit_parabola(y, u):
    """u = F/(2 nu_eff) (y - y0)(y1 - y) by least squares (a quadratic in y):
    returns nu_eff, y0, y1."""
    a, b, c = np.polyfit(y, u, 2)
    nu_eff = -F / (2 * a)
    disc = math.sqrt(b * b - 4 * a * c)
    r = sorted(((-b - disc) / (2 * a), (-b + disc) / (2 * a)))
    return nu_eff, r[0], r[1]


def lattice_laplacian(h_factor=1.5, eta=0.1):
    """The viscous operator of src/physics/momentum.h (Morris et al. 1997,
    eq. 8: sum_j V_j 2 (x_ij . grad W) / (r^2 + eta^2 h^2) u_ij, the Wendland
    C2 kernel) applied to u = y^2 / 2 on the square lattice, whose Laplacian
    is 1: the factor on nu of the discrete operator far from walls, with and
    without the regularisation eta^2 h^2."""
    h = float(h_factor)
    i = np.arange(-int(2 * h) - 1, int(2 * h) + 2)
    x, y = np.meshgrid(i, i)
    r = np.hypot(x, y)
    m = (r > 0) & (r < 2 * h)
    q, r2, y2 = r[m] / h, r[m] ** 2, y[m] ** 2
    f = -5 * 7 / (4 * np.pi * h * h) * (1 - q / 2) ** 3 / h ** 2
    return float(-(f * y2 * r2 / (r2 + (eta * h) ** 2)).sum()), float(-(f * y2).sum())


def order(h, e):
    """Observed orders between successive resolutions (h ascending or not)."""
    out = []
    for i in range(len(h) - 1):
        ok = e[i] > 0 and e[i + 1] > 0
        out.append(math.log(e[i] / e[i + 1]) / math.log(h[i] / h[i + 1]) if ok else float("nan"))
    return out


class _Case(batch.Case):
    """A batch.Case with extra sphseg arguments (from --sphseg)."""

    def __init__(self, name, scene, over, extra, **meta):
        super().__init__(name, scene, over, **meta)
        self.extra = list(extra)

    def command(self, sphseg, root, backend=None):
        return super().command(sphseg, root, backend) + self.extra


def analyse(out, rows, t_end):
    """Per resolution: its errors, excess, wall fit and profiles."""
    res = {}
    for n in rows:
        dr = H / n
        paths = snap.list_snapshots(os.path.join(out, "rows%d" % n))
        if not paths:
            continue
        r = {"rows": n, "dr": dr, "t": [], "err": [], "centre": [], "spread": 0.0, "prof": {}}
        for p in paths:
            s = snap.read_snapshot(p)
            t = float(s["Time"])
            y, u, spread = row_means(s, dr)
            ref = series(y, t)
            r["t"].append(t)
            r["err"].append(float(np.abs(u - ref).max() / UMAX))
            r["centre"].append(float(u.max()))
            r["spread"] = max(r["spread"], spread / UMAX)
            r["prof"][round(t, 9)] = (y, u)
        r["t"], r["err"] = np.array(r["t"]), np.array(r["err"])
        tl = r["t"].max()
        r["t_last"] = tl
        r["at"] = {}
        for t in TIMES + (t_end,):
            k = np.nonzero(np.abs(r["t"] - t) < 1e-9)[0]
            if len(k):
                r["at"][t] = r["err"][k[0]]
        y, u = r["prof"][round(tl, 9)]
        r["excess"] = u.max() / series(y, tl).max() - 1
        # change of the row means over the last output interval (is it steady?)
        ts = sorted(r["prof"])
        if len(ts) > 1:
            y0_, u0_ = r["prof"][ts[-2]]
            r["drift"] = float(np.abs(u - u0_).max() / UMAX)
        nu_eff, y0, y1 = fit_parabola(y, u)
        r["nu_eff"], r["y0"], r["y1"] = nu_eff, y0, y1
        r["fit_resid"] = float(np.abs(u - steady(y, y1 - y0, nu_eff, y0)).max() / UMAX)
        r["shifted"] = {f: float(np.abs(u - steady(y, H + f * dr, NU, -f * dr / 2)).max() / UMAX) for f in SHIFTS}
        res[n] = r
    return res


def write_csv(out, res):
    with open(os.path.join(out, "profiles.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["rows", "t", "y", "u", "series"])
        for n, r in res.items():
            for t, (y, u) in sorted(r["prof"].items()):
                for yi, ui, si in zip(y, u, series(y, t)):
                    w.writerow([n, t, "%.9g" % yi, "%.9g" % ui, "%.9g" % si])
    with open(os.path.join(out, "errors.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["rows", "t", "err_over_umax", "centre"])
        for n, r in res.items():
            for t, e, c in zip(r["t"], r["err"], r["centre"]):
                w.writerow([n, t, "%.6g" % e, "%.9g" % c])


def table(res, runs, t_end):
    """The markdown tables (results, orders, the walls)."""
    ns = sorted(res)
    times = [t for t in TIMES if t < t_end - 1e-9] + [t_end]
    lab = ["t = %g" % t for t in TIMES if t < t_end - 1e-9] + ["t_end = %g" % t_end]
    L = ["Plane Poiseuille flow (inputs/poiseuille_2d.yml), H = 1 cm, nu = 1e-3 m^2/s, F = 2 m/s^2, "
         "u_max = %.4g m/s. Error: largest |row-mean u - series| over the rows, %% of u_max." % UMAX, ""]
    L.append("| H/dr | particles | " + " | ".join(lab) + " | steady excess | steps | wall s | particle-steps/s |")
    L.append("|" + " --- |" * (len(lab) + 6))
    for n in ns:
        r, run = res[n], runs.get("rows%d" % n, {})
        part = ("%s + %s" % (run.get("material", ""), run.get("dummy", ""))) if run.get("material") else ""
        rate = run.get("pstep_per_s", "")
        rate = "%.2e" % float(rate) if rate not in ("", None) else ""
        wall = run.get("wall_s", "")
        wall = "%.1f" % float(wall) if wall not in ("", None) else ""
        errs = ["%.2f" % (100 * r["at"][t]) if t in r["at"] else "-" for t in times]
        L.append("| %d | %s | %s | %+.2f %% | %s | %s | %s |" % (n, part, " | ".join(errs), 100 * r["excess"],
                                                                run.get("steps", ""), wall, rate))
    if len(ns) > 1:
        h = [res[n]["dr"] for n in ns]
        cols = [[res[n]["at"].get(t, float("nan")) for n in ns] for t in times]
        exc = [abs(res[n]["excess"]) for n in ns]
        for i in range(len(ns) - 1):
            o = [order(h, c)[i] for c in cols]
            L.append("| order %d-%d | | %s | %.2f | | | |" % (ns[i], ns[i + 1], " | ".join("%.2f" % v for v in o),
                                                           order(h, exc)[i]))
        if len(ns) > 2:
            o = [batch.observed_order(h, c) for c in cols]
            L.append("| order, least squares | | %s | %.2f | | | |" % (" | ".join("%.2f" % v for v in o),
                                                                     batch.observed_order(h, exc)))
    L += ["", "The walls at t_end: the parabola u = F/(2 nu_eff) (y - y0)(y1 - y) fitted to the row means "
          "(walls at y0, y1; a wall at 0 and H is y0 = 0, y1 = H); the error against the steady parabola of a "
          "channel H + f dr centred on the real one (% of u_max).", ""]
    L.append("| H/dr | nu_eff / nu - 1 | -y0 / dr | (y1 - H) / dr | (y1 - y0) / H - 1 | fit residual | "
             + " | ".join("e, H + %g dr" % f for f in SHIFTS) + " | e, H | spread along a row | last change |")
    L.append("|" + " --- |" * (9 + len(SHIFTS)))
    for n in ns:
        r, dr = res[n], res[n]["dr"]
        L.append("| %d | %+.2f %% | %.3f | %.3f | %+.2f %% | %.2f %% | %s | %.2f %% | %.0e | %.0e |" % (
            n, 100 * (r["nu_eff"] / NU - 1), -r["y0"] / dr, (r["y1"] - H) / dr, 100 * ((r["y1"] - r["y0"]) / H - 1),
            100 * r["fit_resid"], " | ".join("%.2f %%" % (100 * r["shifted"][f]) for f in SHIFTS),
            100 * r["at"].get(t_end, float("nan")), r["spread"], r.get("drift", float("nan"))))
    lat, lat0 = lattice_laplacian()
    L += ["", "Morris's viscous operator on the lattice (h = 1.5 dr, far from walls) gives %.4f of the Laplacian with "
          "eta^2 = (0.1 h)^2 (the code before issue 30: nu_eff / nu - 1 = %+.2f %% at every dr) and %.4f without it "
          "(%+.2f %%); the code divides it by that lattice moment (mom_visc_lattice), which leaves nu_eff = nu on "
          "the lattice." % (lat, 100 * (lat - 1), lat0, 100 * (lat0 - 1))]
    return "\n".join(L) + "\n"


def figure(res, t_end, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.ticker
    import matplotlib.pyplot as plt
    ns = sorted(res)
    fine = res[ns[-1]]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
    yy = np.linspace(0, H, 201)
    times = [t for t in TIMES + (t_end,) if round(t, 9) in fine["prof"]]
    for i, t in enumerate(times):
        col = "C%d" % i
        a.plot(series(yy, t) / UMAX, yy / H, "-", color=col, lw=1, label="series, t = %g s" % t)
        y, u = fine["prof"][round(t, 9)]
        a.plot(u / UMAX, y / H, "o", ms=3, color=col, mfc="none")
    a.set_xlabel("u / u_max  (u_max = F H^2 / 8 nu = %.3g m/s)" % UMAX)
    a.set_ylabel("y / H")
    a.set_title("row means, H/dr = %d (circles), Morris et al. 1997 (lines)" % ns[-1], fontsize=9)
    a.legend(fontsize=7, loc="lower right")
    h = np.array([res[n]["dr"] for n in ns])
    for i, t in enumerate(TIMES + (t_end,)):
        e = np.array([res[n]["at"].get(t, np.nan) for n in ns])
        if np.all(np.isnan(e)) or (t in TIMES and t >= t_end - 1e-9):
            continue
        p = batch.observed_order(h, e)
        b.loglog(h * 1e3, 100 * e, "o-", color="C%d" % i, label="t = %g s (order %.2f)" % (t, p))
    exc = np.array([abs(res[n]["excess"]) for n in ns])
    b.loglog(h * 1e3, 100 * exc, "k^--", label="steady centreline excess (order %.2f)" % batch.observed_order(h, exc))
    nue = np.array([abs(res[n]["nu_eff"] / NU - 1) for n in ns])
    wall = np.array([abs((res[n]["y1"] - res[n]["y0"]) / H - 1) for n in ns])
    b.loglog(h * 1e3, 100 * nue, "s--", color="0.5", mfc="none",
             label="steady fit: |nu_eff / nu - 1| (order %.2f)" % batch.observed_order(h, nue))
    b.loglog(h * 1e3, 100 * wall, "v--", color="0.5", mfc="none",
             label="steady fit: walls' offset (y1 - y0) / H - 1 (order %.2f)" % batch.observed_order(h, wall))
    lat = lattice_laplacian()[0]
    b.axhline(100 * (1 - lat), color="0.5", lw=0.8, ls=":",
              label="the floor of Morris's operator with eta^2 (h = 1.5 dr): %.2f %%" % (100 * (1 - lat)))
    e0 = 100 * res[ns[0]]["at"].get(t_end, np.nan)
    for p, ls in ((1, ":"), (2, "-.")):
        b.loglog(h * 1e3, e0 * (h / h[0]) ** p, "k" + ls, lw=0.8, label="slope %d" % p)
    b.set_xlabel("dr, mm  (H/dr = %s)" % ", ".join(str(n) for n in ns))
    b.set_ylabel("largest row-mean error, % of u_max")
    b.set_title("error against the series; the steady state's fit: viscosity and walls", fontsize=9)
    b.legend(fontsize=7)
    b.grid(True, which="both", alpha=0.3)
    b.set_xticks(h * 1e3)
    b.set_xticklabels(["%g" % v for v in h * 1e3])
    b.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    b.yaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sphseg", required=True, help="the binary, with any arguments (\"build/sphseg --backend gpu\")")
    ap.add_argument("--out", required=True)
    ap.add_argument("--table", help="also write the markdown table here")
    ap.add_argument("--docs", help="folder for validation_poiseuille.png (default --out)")
    ap.add_argument("--rows", default="10,20,40", help="H/dr of the runs (default 10,20,40)")
    ap.add_argument("--t-end", type=float, default=0.3, help="s (default 0.3)")
    ap.add_argument("--jobs", type=int, default=2, help="runs at once (default 2)")
    ap.add_argument("--limit-s", type=float, default=1800.0, help="wall limit of one run, s (default 1800)")
    ap.add_argument("--reuse", action="store_true", help="skip the runs whose snapshots are there")
    a = ap.parse_args()
    rows = [int(v) for v in a.rows.split(",")]
    # the CPU build is OpenMP: share the cores between the runs at once
    # (two runs of two threads on two cores slow the small cases fourfold)
    os.environ.setdefault("OMP_NUM_THREADS", str(max(1, (os.cpu_count() or 1) // max(1, a.jobs))))
    tok = shlex.split(a.sphseg)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)

    y = np.linspace(0, H, 101)
    gap = float(np.abs(series(y, a.t_end) - steady(y)).max() / UMAX)
    slow = 32 / math.pi ** 3 * math.exp(-math.pi ** 2 * NU * a.t_end / H ** 2)
    print("series at t_end = %g s: %.1e of u_max from steady (slowest mode %.1e)%s" % (
        a.t_end, gap, slow, "" if gap < 1e-3 else "  WARNING: not steady, raise --t-end"))

    cases = []
    for n in rows:
        dr = H / n
        over = {"Geometry:dr": repr(dr), "Geometry:width": repr(PERIOD_DR * dr), "Run:t_end": repr(a.t_end),
                "Output:dt": "0.01", "Run:progress_s": "1e9"}
        name = "rows%d" % n
        if a.reuse and snap.list_snapshots(os.path.join(out, name)):
            continue
        cases.append(_Case(name, SCENE, over, tok[1:], rows=n, dr=dr))
    old = {}
    if a.reuse and os.path.exists(os.path.join(out, "runs.csv")):
        old = batch.read_runs(out)
    t0 = time.time()
    if cases:
        done = batch.run_all(cases, tok[0], out, jobs=a.jobs, limit_s=a.limit_s)
        old.update({k_: {kk: str(v) for kk, v in r.items()} for k_, r in done.items()})
        batch.write_runs(out, old, ["rows%d" % n for n in rows])
        print("runs: %.1f s" % (time.time() - t0))
    res = analyse(out, rows, a.t_end)
    if not res:
        sys.exit("no runs to analyse in %s" % out)
    write_csv(out, res)
    text = table(res, old, a.t_end)
    print(text)
    if a.table:
        with open(a.table, "w") as f:
            f.write(text)
    fig = os.path.join(a.docs or out, "validation_poiseuille.png")
    figure(res, a.t_end, fig)
    print("figure: %s" % fig)


if __name__ == "__main__":
    main()
