"""Stokes flow through a square lattice of cylinders (inputs/cylinders_2d.yml)
against the drag of Sangani & Acrivos (1982): resolution, background
pressure and solid fraction.

Reference. One cell L x L of a square array of cylinders of radius a, solid
fraction phi = pi a^2 / L^2, driven by a body force f on the fluid. Sangani &
Acrivos (1982, Int. J. Multiphase Flow 8, 193) give the drag per unit length
F = 4 pi mu U / K(phi), with the small-phi expansion

    K = -ln(phi)/2 - 0.738 + phi - 0.887 phi^2 + 2.038 phi^3

and, from their numerical solution, F / (mu U) = 15.56, 24.83, 51.53, 102.9
at phi = 0.05, 0.1, 0.2, 0.3 (their table 1). U is the superficial velocity,
the flow rate over the whole cell (L^-2 sum_i u_x,i V_i over the fluid). A
body force f on the fluid is a mean pressure gradient rho f, so in steady
flow F = rho f L^2 and U = f L^2 / (nu F/(mu U)).

The measure is U over time from the snapshots (every 0.01 s), reduced at
the end of each run into series.csv (t, U, the mean v_y and the pressure
range); its mean over [T1, t_end] = [1, 2] s, where it is statistically
steady, is compared with the reference, and so is U at 0.05 s. The Stokes
start-up decays within about (L/2 pi)^2/nu = 2.5 ms, so what changes after
0.05 s is the particles' arrangement: they start on the square lattice and
lose its order around the post within about 1 s.

Set "background" (issue 30): shifting with Flow:background_pressure excluded
(the background pressure left out of the momentum pair term, Adami, Hu &
Adams 2013) at 30 and 300 Pa and L/dr = 20, 24, 28, 32, without shifting at
300 Pa, and phi = 0.05-0.3 at L/dr = 20, 32 and 40.

Set "shifting" (issue 30): the same cell with Flow:shifting fickian (Lind et
al. 2012) at L/dr = 20, 30, 40 (30 Pa), and at L/dr = 20 and 30 the
background pressures 0 and 300 Pa with and without it: does the
regularisation make the settled drag independent of the background
pressure? Each snapshot also gives the disorder, the relative standard
deviation over the fluid particles of the kernel sum sum_j V_j W_ij (fluid
and the post's dummies, periodic): 3.7 % at t = 0 at L/dr = 20, where the
square lattice is cut by the post, whose dummies do not lie on it.

  python3 -m tools.studies.cylinders_study run --sphseg build/sphseg --out out/cylinders [--backend gpu] [--set ...]
  python3 -m tools.studies.cylinders_study report --out out/cylinders [--docs docs/data/cylinders]
"""
import csv
import glob
import math
import os
import shutil

import numpy as np

from tools import ROOT  # noqa: E402
from tools.studies import batch  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "cylinders_2d.yml")
L, F, NU = 0.01, 2.0, 1e-3  # the scene's cell, body force and kinematic viscosity
T1 = 1.0  # s: the window's start (U is statistically steady from about 1 s on)
SA_TABLE = {0.05: 15.56, 0.1: 24.83, 0.2: 51.53, 0.3: 102.9}  # Sangani & Acrivos (1982), table 1


def drag_sa(phi):
    """F / (mu U) of a square array: the table where it has phi, else the expansion."""
    for p, v in SA_TABLE.items():
        if abs(p - phi) < 1e-9:
            return v
    K = -0.5 * math.log(phi) - 0.738 + phi - 0.887 * phi ** 2 + 2.038 * phi ** 3
    return 4 * math.pi / K


def u_ref(phi):
    return F * L * L / (NU * drag_sa(phi))


def case(name, rows=40, phi=math.pi * 0.04, p0=30.0, t_end=2.0, shifting="off", background="momentum", **meta):
    a = L * math.sqrt(phi / math.pi)
    dr = round(L / rows, 12)
    over = {"Geometry:dr": dr, "Run:t_end": t_end, "Output:dt": 0.01, "Output:diag_dt": 0.01,
            "Run:progress_s": 1e9, "Initial:pressure": p0,
            "Container:walls": "[{name: post, shape: cylinder, centre: [0.005, 0.005], radius: %.9g, "
                               "material: outside}]" % a}
    if shifting != "off":
        over["Flow:shifting"] = shifting
    if background != "momentum":
        over["Flow:background_pressure"] = background
    return batch.Case(name, SCENE, over, rows=rows, phi=phi, a=a, p0=p0, t_end=t_end, dr=dr, shifting=shifting,
                      background=background, **meta)


def cases(which):
    c = []
    if which in ("full", "resolution"):
        for rows in (20, 40, 80):
            c.append(case("res%d" % rows, rows=rows))
        c.append(case("res160", rows=160, t_end=0.3))  # the ordered flow only (no window)
    if which in ("full", "pressure"):
        for p0 in (0.0, 100.0, 300.0):  # 30 is res40
            c.append(case("p%g" % p0, p0=p0))
    if which == "shifting":  # not in full: CPU-sized, issue 30
        for rows in (20, 30, 40):  # cheapest first
            c.append(case("sh_res%d" % rows, rows=rows, shifting="fickian"))
            for p0 in (0.0, 300.0) if rows < 40 else ():
                c.append(case("sh_p%g_r%d" % (p0, rows), rows=rows, p0=p0, shifting="fickian"))
                c.append(case("ns_p%g_r%d" % (p0, rows), rows=rows, p0=p0))
    if which == "background":  # not in full: CPU-sized, issue 30; shifting with p0 left out of (3.9)
        for p0 in (30.0, 300.0):
            c.append(case("shx_p%g_r20" % p0, rows=20, p0=p0, shifting="fickian", background="excluded"))
        c.append(case("nsx_p300_r20", rows=20, p0=300.0, background="excluded"))
        c.append(case("shx_res24", rows=24, shifting="fickian", background="excluded"))  # 20: shx_p30_r20
        for rows in (20, 32, 40):  # 32, 40: the fractions at finer cells (phi 0.126 is shx_res32)
            for phi in (0.05, 0.1, 0.2, 0.3):
                c.append(case("shx_phi%g_r%d" % (phi, rows), rows=rows, phi=phi, shifting="fickian",
                              background="excluded"))
        for rows in (48, 56):  # the smallest post (phi 0.05: a = 0.126 L) still 3.3 % fast at 40
            c.append(case("shx_phi0.05_r%d" % rows, rows=rows, phi=0.05, shifting="fickian", background="excluded"))
        for rows in (28, 32):  # (16 is below the period's 6 supports)
            c.append(case("shx_res%d" % rows, rows=rows, shifting="fickian", background="excluded"))
    if which in ("full", "fraction"):
        for phi in (0.05, 0.1, 0.2, 0.3):
            c.append(case("phi%g" % phi, phi=phi))
    return c


def disorder(x, V, m, h):
    """The relative standard deviation over the particles m of the kernel sum
    sum_j V_j W(|x_i - x_j|, h) (Wendland C2, 2D; all particles j, the cell
    periodic along x and y)."""
    xy = np.mod(x[:, :2], L)
    xy[xy >= L] = 0.0  # a coordinate that rounds up to L
    try:
        from scipy.spatial import cKDTree
        pairs = cKDTree(xy, boxsize=L).query_pairs(2 * h, output_type="ndarray")
    except ImportError:  # the same pairs by brute force, in blocks (the device machine has no scipy)
        found = []
        for a in range(0, len(xy), 512):
            d = xy[a:a + 512, None, :] - xy[None, :, :]
            d -= L * np.round(d / L)
            i, j = np.nonzero(np.hypot(d[..., 0], d[..., 1]) < 2 * h)
            keep = a + i < j
            found.append(np.stack([a + i[keep], j[keep]], axis=1))
        pairs = np.concatenate(found)
    d = xy[pairs[:, 0]] - xy[pairs[:, 1]]
    d -= L * np.round(d / L)
    q = np.hypot(d[:, 0], d[:, 1]) / h
    w = 7 / (4 * math.pi * h * h) * (1 - q / 2) ** 4 * (1 + 2 * q)
    k = np.full(len(xy), 7 / (4 * math.pi * h * h)) * V  # self
    np.add.at(k, pairs[:, 0], w * V[pairs[:, 1]])
    np.add.at(k, pairs[:, 1], w * V[pairs[:, 0]])
    return float(k[m].std() / k[m].mean())


def reduce_run(d, keep=False):
    """series.csv of run folder d from its snapshots; returns the rows."""
    from tools.analysis import snap
    rows = []
    for fn in snap.list_snapshots(d):
        s = snap.read_snapshot(fn)
        m = np.asarray(s["Kind"]) == 0
        u, V = np.asarray(s["Velocities"]), np.asarray(s["Volume"])
        sig = np.asarray(s["Stress"])
        p = -(sig[m, 0] + sig[m, 1] + sig[m, 2]) / 3
        x = np.asarray(s["Coordinates"])
        h = 1.5 * math.sqrt(float(np.median(V[m])))  # the scene's h_factor 1.5
        rows.append({"t": float(s["Time"]), "U": float((u[m, 0] * V[m]).sum() / L ** 2),
                     "V": float((u[m, 1] * V[m]).sum() / L ** 2), "p_min": float(p.min()), "p_max": float(p.max()),
                     "disorder": disorder(x, V, m, h)})
    with open(os.path.join(d, "series.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    if not keep:
        for fn in glob.glob(os.path.join(d, "snapshot_*.h5")):
            os.remove(fn)
    for extra in ("checkpoint", "restart"):
        shutil.rmtree(os.path.join(d, extra), ignore_errors=True)
    return rows


def reduce_done(a, c, rec):
    d = os.path.join(a.out, c.name)
    if rec["rc"] == 0:
        print("%s: %d times" % (c.name, len(reduce_run(d, a.keep))), flush=True)


def read_series(d):
    with open(os.path.join(d, "series.csv")) as f:
        r = list(csv.DictReader(f))
    return {k: np.array([float(x[k]) for x in r]) for k in r[0]}


def summarise(d, row):
    s = read_series(d)
    phi = float(row["phi"])
    ref = u_ref(phi)
    w = s["t"] >= T1 - 1e-9
    i05 = int(np.argmin(np.abs(s["t"] - 0.05)))
    Uw = s["U"][w] if w.any() else np.array([math.nan])
    dis = s["disorder"][w].mean() if "disorder" in s and w.any() else math.nan
    return {"disorder": dis, "ref": ref, "mean": Uw.mean() / ref - 1, "sd": Uw.std() / ref, "lo": Uw.min() / ref - 1,
            "hi": Uw.max() / ref - 1, "early": s["U"][i05] / ref - 1, "t": s["t"], "U": s["U"] / ref,
            "vy": np.abs(s["V"]).max() / ref, "p_min": s["p_min"].min(), "drag": F * L * L / (NU * Uw.mean())}


def shift_table(runs, S, P):
    """The shifting set's table (issue 30), if it ran."""
    sh = [n for n in S if n.startswith(("sh_", "ns_", "shx_", "nsx_"))]
    if not sh:
        return
    key = lambda n: (float(runs[n]["phi"]), int(runs[n]["rows"]), runs[n].get("shifting", "off"),
                     runs[n].get("background", "momentum"), float(runs[n]["p0"]))
    P("| phi | L/dr | Flow:shifting | Flow:background_pressure | background pressure (Pa) | lowest pressure (Pa) | "
      "U / U_SA - 1 at 0.05 s | mean over [%.1f s, t_end] | its standard deviation | disorder over the window | "
      "wall (s) | steps |" % T1)
    P("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for n in sorted(sh, key=key):
        r, s = runs[n], S[n]
        P("| %.3g | %s | %s | %s | %g | %.1f | %+.1f %% | %+.1f %% | %.1f %% | %.2f %% | %s | %s |" % (
            float(r["phi"]), r["rows"], r.get("shifting", "off"), r.get("background", "momentum"), float(r["p0"]),
            s["p_min"], 100 * s["early"], 100 * s["mean"], 100 * s["sd"], 100 * s["disorder"], r["wall_s"],
            r["steps"]))
    P("")


def cmd_report(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs, where = batch.load_runs(a.out, "series.csv")
    S = {n: summarise(os.path.join(where[n], n), r) for n, r in runs.items()}
    lines = []
    P = lines.append
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.4))
    shift_table(runs, S, P)
    res = sorted((n for n in S if n.startswith("res")), key=lambda n: int(runs[n]["rows"]))
    if res:
        P("| L/dr | a/dr | particles | U / U_SA - 1 at 0.05 s | mean over [%.1f s, t_end] | its standard deviation | "
          "its range | t_end (s) | wall (s) | backend | steps |" % T1)
        P("|---|---|---|---|---|---|---|---|---|---|---|")
        for n in res:
            r, s = runs[n], S[n]
            P("| %s | %.0f | %s | %+.1f %% | %+.1f %% | %.1f %% | %+.1f to %+.1f %% | %s | %s | %s | %s |" % (
                r["rows"], float(r["a"]) / float(r["dr"]), r["material"], 100 * s["early"], 100 * s["mean"],
                100 * s["sd"], 100 * s["lo"], 100 * s["hi"], r["t_end"], r["wall_s"], r.get("backend", ""),
                r["steps"]))
            ax[0].plot(s["t"], s["U"], label="L/dr = %s" % r["rows"])
        P("")
        P("observed order of the error at 0.05 s: %.2f (%d resolutions)" % (
            batch.observed_order([float(runs[n]["dr"]) for n in res], [abs(S[n]["early"]) for n in res]), len(res)))
        m = [S[n]["mean"] for n in res if np.isfinite(S[n]["mean"])]
        if len(m) >= 3:  # successive changes of the window mean (its error changes sign) and their limit
            p, lim = batch.richardson(m[-3], m[-2], m[-1])
            P("window mean: changes %+.1f, %+.1f %% between the last three resolutions, order %.2f, Richardson "
              "limit %+.1f %%" % (100 * (m[-2] - m[-3]), 100 * (m[-1] - m[-2]), p, 100 * lim))
        ax[0].set_title("resolution, background pressure 30 Pa")
        ax[0].axvline(T1, color="0.6", ls=":")
    # the background-pressure runs and the 40-row run of the resolution set (30 Pa)
    pres = sorted({n for n in S if (n.startswith("p") and not n.startswith("phi"))
                   or (n in res and runs[n]["rows"] == "40")}, key=lambda n: float(runs[n]["p0"]))
    if len(pres) > 1:
        P("")
        P("| background pressure (Pa) | lowest pressure (Pa) | U / U_SA at 0.05 s | mean over [%.1f s, t_end] | "
          "its range | wall (s) |" % T1)
        P("|---|---|---|---|---|---|")
        for n in pres:
            r, s = runs[n], S[n]
            P("| %g | %.1f | %+.1f %% | %+.1f %% | %+.1f to %+.1f %% | %s |" % (
                float(r["p0"]), s["p_min"], 100 * s["early"], 100 * s["mean"], 100 * s["lo"], 100 * s["hi"],
                r["wall_s"]))
            ax[1].plot(s["t"], s["U"], label="p0 = %g Pa" % float(r["p0"]))
        ax[1].set_title("background pressure, L/dr = 40")
        ax[1].axvline(T1, color="0.6", ls=":")
    frac = sorted((n for n in S if n.startswith("phi")), key=lambda n: float(runs[n]["phi"]))
    if frac:
        P("")
        P("| phi | F/(mu U), Sangani & Acrivos | SPH (mean over the window) | error of U | U at 0.05 s |")
        P("|---|---|---|---|---|")
        for n in frac:
            r, s = runs[n], S[n]
            P("| %g | %.2f | %.2f | %+.1f %% | %+.1f %% |" % (float(r["phi"]), drag_sa(float(r["phi"])), s["drag"],
                                                             100 * s["mean"], 100 * s["early"]))
        ph = np.linspace(0.03, 0.35, 100)
        ax[2].semilogy(ph, [4 * math.pi / (-0.5 * math.log(p) - 0.738 + p - 0.887 * p * p + 2.038 * p ** 3)
                            for p in ph], "k-", label="Sangani & Acrivos, expansion")
        ax[2].semilogy(list(SA_TABLE), list(SA_TABLE.values()), "ks", mfc="none", label="their table 1")
        ax[2].semilogy([float(runs[n]["phi"]) for n in frac], [S[n]["drag"] for n in frac], "o",
                       label="SPH, L/dr = 40, window mean")
        ax[2].set_xlabel("solid fraction $\\phi$"), ax[2].set_ylabel("F / ($\\mu$ U)"), ax[2].legend(fontsize=8)
    for k in (0, 1):
        ax[k].axhline(1, color="k", lw=0.8)
        ax[k].set_xlabel("t (s)"), ax[k].set_ylabel("U / U (Sangani & Acrivos)"), ax[k].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.docs, "validation_cylinders.png"), dpi=100)
    batch.report_tables(a, lines)


def main(argv=None):
    batch.study_main(__doc__, ("resolution", "pressure", "fraction", "shifting", "background"), cases, reduce_done, cmd_report, "cylinders", jobs=4,
                     argv=argv)


if __name__ == "__main__":
    main()
