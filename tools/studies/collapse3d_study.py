"""Axisymmetric collapse of a granular column (inputs/collapse_3d.yml, one
quarter) against the experimental scaling laws of Lube, Huppert, Sparks &
Hallworth (2004, J. Fluid Mech. 508, 175).

A column of radius R0 and height H0 = a R0 is released at t = 0 from its
geostatic stress and spreads over a no-slip floor. Lube et al. measured, for
sand, salt, rice and sugar alike,

    (r_inf - R0) / R0 = 1.24 a       for a < 1.7,
                      = 1.6 a^(1/2)  for a > 1.7.

The front is the largest distance from the axis, sqrt(x^2 + z^2), of the
material that is not a lone particle (its radial bin of width 2 dr holds at
least two); the final height is the highest material within 2 dr of the
axis. Runs go to 7 sqrt(H0 / g) (the flow stops within about 3). The floor
reaches twice the law's runout plus R0 beyond the column (FLOOR_LAW, FLOOR_R0);
a front within 4 dr of its end wall is a bound ("≥" in the report).

  python3 -m tools.studies.collapse3d_study run --sphseg build/sphseg --out out/collapse3d [--backend gpu] [--set ...]
  python3 -m tools.studies.collapse3d_study report --out out/collapse3d [--docs docs/data/collapse3d]
"""
import math
import os

import numpy as np

from tools import ROOT  # noqa: E402
from tools.studies import batch  # noqa: E402
from tools.studies.collapse_study import AT_WALL, bound  # noqa: E402  (the 2D study's wall test and "≥")

SCENE = os.path.join(ROOT, "inputs", "collapse_3d.yml")
G = 9.81


def lube_runout(a):
    """(r_inf - R0) / R0 of Lube et al. (2004)."""
    a = np.asarray(a, float)
    return np.where(a < 1.7, 1.24 * a, 1.6 * np.sqrt(a))


# The floor's reach from the axis, FLOOR_LAW times the law's runout plus FLOOR_R0 R0 (at least 3 R0). The runouts
# rise with resolution (a = 2: 1.03, 1.23, 1.35 of the law at R0/dr 10, 20, 40, heading for about 1.5; a = 4: 1.44
# at 20), so the floor leaves half the law and one R0 beyond 1.5 times it. Until 2026-11-30 it was 1.4 (1 + law)
# R0: the a = 4 front at R0/dr 20 stopped 5.7 dr from that wall (the 2D study's floor, too short, had read its
# wall's place as runouts: collapse_study.py). A front within AT_WALL dr of the wall is reported as a bound.
FLOOR_LAW, FLOOR_R0 = 2.0, 2.0
OLD_FLOOR = 1.4  # X = OLD_FLOOR (1 + law) R0, for runs from before x_end was recorded


def floor_reach(a, R0, dr, old=False, floor=(FLOOR_LAW, FLOOR_R0)):
    """The floor's end, m from the axis, on the lattice: floor[0] times the law's runout plus floor[1] R0."""
    law = float(lube_runout(a))
    X = max(3.0, OLD_FLOOR * (1 + law) if old else floor[0] * law + floor[1]) * R0
    return math.ceil(X / dr) * dr


def at_end_wall(r, front):
    """Whether a run's final front (m from the axis) lies at its floor's end wall (runs.csv row r)."""
    R0, dr, a = float(r["R0"]), float(r["dr"]), float(r["a"])
    x_end = float(r["x_end"]) if r.get("x_end") else floor_reach(a, R0, dr, old=True)
    return front >= x_end - AT_WALL * dr


def case(name, a, R0=0.01, rows=20, floor=(FLOOR_LAW, FLOOR_R0), **extra):
    """A quarter column R0 wide and a R0 high, R0 / dr = rows, on a floor
    reaching floor[0] (FLOOR_LAW) times the law's runout plus floor[1]
    (FLOOR_R0) R0 (at least 3 R0)."""
    dr = round(R0 / rows, 12)
    H0 = a * R0
    X = floor_reach(a, R0, dr, floor=floor)
    top = round(1.5 * H0, 9)
    t_end = 7 * math.sqrt(H0 / G)
    walls = ("[{name: axis_x, from: [0, %.9g], to: [0, 0], slip: free_slip}, {name: floor, from: [0, 0], "
             "to: [%.9g, 0]}, {name: far_x, from: [%.9g, 0], to: [%.9g, %.9g], slip: free_slip}, "
             "{shape: ends, slip: free_slip}]" % (top, X, X, X, top))
    over = {"Geometry:dr": dr, "Geometry:depth": round(X, 9), "Container:walls": walls,
            "Container:regions": "[{shape: column, centre: [0, 0], r_out: %.9g, level: %.9g}]" % (R0, H0),
            "Run:t_end": round(t_end, 4), "Output:dt": 0.01, "Output:diag_dt": 0.01, "Run:progress_s": 1e9}
    over.update(extra)
    return batch.Case(name, SCENE, over, a=a, R0=R0, H0=H0, dr=dr, rows=rows, t_end=t_end, x_end=round(X, 9))


def cases(which):
    c = []
    if which in ("full", "resolution"):
        for rows in (10, 20, 40):
            c.append(case("a2_rows%d" % rows, 2, rows=rows))
    if which in ("full", "aspect"):
        for a in (0.5, 1, 3, 4):  # 2 is a2_rows20
            c.append(case("a%g" % a, a))
    return c


def reduce_run(outdir, dr, keep=False):
    """front.csv (t, front radius, height on the axis, max speed) and
    deposit.csv (the final surface against r) from the snapshots."""
    from tools.analysis import snap
    rows, last = [], None
    for p in snap.list_snapshots(outdir):
        s = snap.read_snapshot(p)
        mat = np.asarray(s["Kind"]) == snap.MATERIAL
        x = np.asarray(s["Coordinates"])[mat]
        v = np.asarray(s["Velocities"])[mat]
        r = np.hypot(x[:, 0], x[:, 2])
        b = np.floor(r / (2 * dr)).astype(int)
        ok = np.bincount(b)[b] >= 2
        axis = x[r < 2 * dr, 1]
        rows.append((float(s["Time"]), float(r[ok].max()), float(axis.max() + 0.5 * dr) if axis.size else 0.0,
                     float(np.sqrt((v ** 2).sum(1)).max())))
        last = (r, x[:, 1])
        if not keep:
            os.remove(p)
    batch.write_csv(os.path.join(outdir, "front.csv"), ["t", "front", "height_at_axis", "max_speed"], rows)
    if last is not None:
        r, y = last
        b = np.floor(r / (2 * dr)).astype(int)
        batch.write_csv(os.path.join(outdir, "deposit.csv"), ["r", "top"],
                        [[(k + 0.5) * 2 * dr, y[b == k].max() + 0.5 * dr] for k in np.unique(b)])
    return len(rows)


def reduce_done(a, c, rec):
    d = os.path.join(a.out, c.name)
    if os.path.isdir(d) and rec["rc"] == 0:
        print("%s: %d snapshots reduced" % (c.name, reduce_run(d, c.meta["dr"], a.keep)), flush=True)


def load(out, name):
    return np.genfromtxt(os.path.join(out, name, "front.csv"), delimiter=",", names=True)


def summarise(f, R0):
    """Final runout (r_inf - R0) / R0, final height on the axis / R0, and
    whether the front has stopped (moved < 1 % of R0 over the last 0.05 s)."""
    t, fr = f["t"], f["front"]
    before = fr[np.argmin(np.abs(t - (t[-1] - 0.05)))]
    return (fr[-1] - R0) / R0, f["height_at_axis"][-1] / R0, abs(fr[-1] - before) < 0.01 * R0


def cmd_report(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs, where = batch.load_runs(a.out, "front.csv")
    lines = []
    P = lines.append
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.3))
    res = sorted((n for n in runs if n.startswith("a2_rows")), key=lambda n: int(runs[n]["rows"]))
    if res:
        P("| R0/dr | particles | runout (r_inf - R0)/R0 | law | ratio | height on the axis / R0 | stopped | wall (s) | "
          "backend | steps |")
        P("|---|---|---|---|---|---|---|---|---|---|")
        vals = []
        for n in res:
            r = runs[n]
            f = load(where[n], n)
            R0 = float(r["R0"])
            run, hgt, stopped = summarise(f, R0)
            vals.append(run)
            law = float(lube_runout(2.0))
            w = at_end_wall(r, f["front"][-1])  # "≥": the front stopped at the floor's end wall
            P("| %s | %s | %s | %.3f | %s | %.3f | %s | %s | %s | %s |" % (
                r["rows"], r["material"], bound(run, w, 3), law, bound(run / law, w), hgt, "yes" if stopped else "no",
                r["wall_s"], r.get("backend", ""), r["steps"]))
            ax[1].plot(f["t"] / math.sqrt(float(r["H0"]) / G), (f["front"] - R0) / R0, label="R0/dr = %s" % r["rows"])
        if len(vals) >= 3:  # the change between successive resolutions
            d = [abs(vals[i + 1] - vals[i]) for i in range(len(vals) - 1)]
            P("")
            P("runout change between successive resolutions: %s; observed order %.2f" % (
                ", ".join("%.3f" % x for x in d), math.log(d[0] / d[1]) / math.log(2) if d[1] > 0 else float("nan")))
        ax[1].axhline(float(lube_runout(2.0)), color="k", ls="--", label="Lube et al. (2004), a = 2")
        ax[1].set_xlabel("t / sqrt(H0/g)"), ax[1].set_ylabel("(r_f - R0) / R0"), ax[1].legend(fontsize=8)
        ax[1].set_title("front against time, a = 2")
    asp = sorted((n for n in runs if runs[n]["rows"] == "20"), key=lambda n: float(runs[n]["a"]))
    if asp:
        P("")
        P("| a | runout (r_inf - R0)/R0 | Lube et al. | ratio | height on the axis / R0 | stopped | wall (s) | backend |")
        P("|---|---|---|---|---|---|---|---|")
        A, Rn = [], []
        for n in asp:
            r = runs[n]
            f = load(where[n], n)
            R0, aa = float(r["R0"]), float(r["a"])
            run, hgt, stopped = summarise(f, R0)
            law = float(lube_runout(aa))
            A.append(aa), Rn.append(run)
            w = at_end_wall(r, f["front"][-1])
            P("| %g | %s | %.3f | %s | %.3f | %s | %s | %s |" % (aa, bound(run, w, 3), law, bound(run / law, w), hgt,
                                                                "yes" if stopped else "no", r["wall_s"],
                                                                r.get("backend", "")))
            dep = np.genfromtxt(os.path.join(where[n], n, "deposit.csv"), delimiter=",", names=True)
            ax[2].plot(dep["r"] / R0, dep["top"] / R0, label="a = %g" % aa)
        aa = np.linspace(0.3, 5, 100)
        ax[0].plot(aa, lube_runout(aa), "k-", label="Lube et al. (2004)")
        ax[0].plot(A, Rn, "o", label="SPH, R0/dr = 20")
        ax[0].set_xlabel("a = H0 / R0"), ax[0].set_ylabel("(r_inf - R0) / R0"), ax[0].legend(fontsize=8)
        ax[2].set_xlabel("r / R0"), ax[2].set_ylabel("deposit height / R0"), ax[2].legend(fontsize=8)
        ax[2].set_title("final deposits")
    fig.tight_layout()
    fig.savefig(os.path.join(a.docs, "validation_collapse3d.png"), dpi=100)
    batch.report_tables(a, lines)


def main(argv=None):
    batch.study_main(__doc__, ("resolution", "aspect"), cases, reduce_done, cmd_report, "collapse3d", jobs=1, argv=argv)


if __name__ == "__main__":
    main()
