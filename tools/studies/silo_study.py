"""Discharge of a flat-bottomed 2D silo (inputs/silo_2d.yml) against the
Beverloo law, its independence of the fill height, and the small-grain
fraction of a bidisperse outflow over time.

Reference: Beverloo, Leniger & van de Velde (1961), in its two-dimensional
form (mass per unit depth and time)

    Q = C rho_b sqrt(g) (W - k d)^(3/2),

with rho_b the bulk density, W the outlet width, d the grain diameter and C,
k material constants (k of order 1-3 in experiments). The rate does not depend on
the fill height once it exceeds about the silo width (Janssen screening).
The study fits C and k (Q^(2/3) linear in W) and the exponent of Q against
W - k d, and measures the rate at three fill heights.

The rate is the slope of the cumulative outflow (diagnostics.csv n_outflow,
each particle rho dr^2 per unit depth) over the window from T0 after the
opening opens to the time half of the fill has left.

  python3 -m tools.studies.silo_study run --sphseg build/sphseg --out out/silo_study [--backend gpu]
  python3 -m tools.studies.silo_study report --out out/silo_study [--docs docs/data/silo]
"""
import glob
import math
import os
import re

import numpy as np

from tools import ROOT  # noqa: E402
from tools.studies import batch  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "silo_2d.yml")
G, RHO, D_LARGE = 9.81, 1500.0, 0.002
T0 = 0.15  # s: the start-up of the discharge left out of the rate


def case(name, W, H=0.1, dr=0.001, t_end=0.8, mixed=False, **meta):
    over = {"Geometry:dr": dr, "Geometry:height": H, "Geometry:outlet_width": W, "Run:t_end": t_end,
            "Output:dt": 0.1, "Output:diag_dt": 0.01, "Run:progress_s": 1e9}
    if mixed:  # a well-mixed bidisperse fill, segregating as it flows (the scene's shear-rate model)
        over.update({"Initial:C_below": 0.5, "Initial:C_above": 0.5, "Output:dt": 0.25})
    else:     # one grain size, no segregation: the Beverloo runs need the flow alone
        over.update({"Segregation:enabled": "off", "Initial:C_below": 0.0, "Initial:C_above": 0.0})
    return batch.Case(name, SCENE, over, W=W, H=H, dr=dr, t_end=t_end, mixed=int(mixed), **meta)


def cases(which):
    c = []
    if which in ("full", "beverloo"):
        for W in (0.008, 0.012, 0.016, 0.020, 0.024):
            c.append(case("W%g" % (W * 1e3), W))
            c.append(case("W%g_dr0.5" % (W * 1e3), W, dr=0.0005))
    if which in ("full", "height"):
        for H in (0.06, 0.15):  # 0.1 is W12 above
            c.append(case("W12_H%g" % (H * 100), 0.012, H=H))
            c.append(case("W12_H%g_dr0.5" % (H * 100), 0.012, H=H, dr=0.0005))
    if which in ("full", "resolution"):
        c.append(case("W12_dr2", 0.012, dr=0.002))  # 1 and 0.5 mm are W12 and W12_dr0.5 above
    if which in ("full", "mixed"):
        c.append(case("mixed_W12", 0.012, t_end=2.5, mixed=True))
    return c


def outflow(out, name):
    d = np.genfromtxt(os.path.join(out, name, "diagnostics.csv"), delimiter=",", names=True)
    return d


def rate(d, dr, n0):
    """Mass flow rate (kg/m/s) over [T0, the time half the fill has left]."""
    t, n = d["time"], d["n_outflow"]
    end = t[np.argmax(n >= n0 / 2.0)] if n[-1] >= n0 / 2.0 else t[-1]
    m = (t >= T0) & (t <= end)
    if m.sum() < 3:
        return math.nan, (T0, end)
    return float(np.polyfit(t[m], n[m], 1)[0] * RHO * dr * dr), (T0, float(end))


def tidy_done(a, c, rec):
    """After each run: the snapshots go (the rates come from diagnostics.csv)."""
    if not a.keep:
        for p in glob.glob(os.path.join(a.out, c.name, "snapshot_*.h5")):
            os.remove(p)


def cmd_report(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs, where = batch.load_runs(a.out, "diagnostics.csv")
    lines = []
    P = lines.append
    Q = {}
    for n, r in runs.items():
        dr = float(r["dr"])
        n0 = int(r["material"]) if r["material"] else 0
        Q[n] = rate(outflow(where[n], n), dr, n0) + (n0,)
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.3))
    for dr_tag, mark in (("", "o"), ("_dr0.5", "s")):
        bev = sorted((n for n in runs if re.fullmatch(r"W[0-9.]+" + re.escape(dr_tag), n)),
                     key=lambda n: float(runs[n]["W"]))
        if len(bev) < 2:
            continue
        dr = float(runs[bev[0]]["dr"])
        W = np.array([float(runs[n]["W"]) for n in bev])
        q = np.array([Q[n][0] for n in bev])
        s, i = np.polyfit(W, q ** (2.0 / 3.0), 1)
        kd = -i / s
        C = s ** 1.5 / (RHO * math.sqrt(G))
        expo = np.polyfit(np.log(W - kd), np.log(q), 1)[0]
        expo0 = np.polyfit(np.log(W), np.log(q), 1)[0]
        fit = C * RHO * math.sqrt(G) * np.clip(W - kd, 0, None) ** 1.5
        P("")
        P("| dr (mm) | W (mm) | W/d | W/dr | rate (kg/m/s) | Beverloo fit | deviation | window (s) | wall (s) | backend |")
        P("|---|---|---|---|---|---|---|---|---|---|")
        for n, w, qq, ff in zip(bev, W, q, fit):
            P("| %g | %g | %.0f | %.0f | %.3f | %.3f | %+.1f %% | %.2f-%.2f | %s | %s |" % (
                dr * 1e3, w * 1e3, w / D_LARGE, w / dr, qq, ff, 100 * (qq / ff - 1), Q[n][1][0], Q[n][1][1],
                runs[n]["wall_s"], runs[n].get("backend", "")))
        P("")
        P("dr %g mm: Beverloo fit (Q^(2/3) linear in W): C = %.3f, k d = %.2f mm (%.2f dr; k = %.2f with d = 2 mm); "
          "exponent of Q against W - k d: %.3f (against W alone: %.3f)"
          % (dr * 1e3, C, kd * 1e3, kd / dr, kd / D_LARGE, expo, expo0))
        Wx = np.linspace(max(kd, 0) * 1.01, W.max() * 1.1, 100)
        ax[0].plot(W * 1e3, q, mark, label="SPH, dr %g mm" % (dr * 1e3))
        ax[0].plot(Wx * 1e3, C * RHO * math.sqrt(G) * (Wx - kd) ** 1.5, "k-" if not dr_tag else "k--",
                   label="C $\\rho\\sqrt{g}$ (W - k d)$^{3/2}$: C %.2f, kd %.1f mm" % (C, kd * 1e3))
    ax[0].set_xlabel("outlet width W (mm)"), ax[0].set_ylabel("Q (kg/m/s)"), ax[0].legend(fontsize=7)
    ax[0].set_title("Beverloo")
    hs = sorted((n for n in runs if n in ("W12", "W12_dr0.5") or n.startswith("W12_H")),
                key=lambda n: (float(runs[n]["dr"]), float(runs[n]["H"])))
    if hs:
        P("")
        P("| dr (mm) | fill height (m) | rate (kg/m/s) | relative to H = 0.1 m |")
        P("|---|---|---|---|")
        for n in hs:
            dr = float(runs[n]["dr"])
            ref = Q.get("W12" if dr == 0.001 else "W12_dr0.5", (math.nan,))[0]
            P("| %g | %g | %.3f | %+.1f %% |" % (dr * 1e3, float(runs[n]["H"]), Q[n][0], 100 * (Q[n][0] / ref - 1)))
            d = outflow(where[n], n)
            ax[1].plot(d["time"], d["n_outflow"] * RHO * dr ** 2, "-" if dr == 0.001 else "--",
                       label="dr %g mm, fill %g m: %.2f kg/m/s" % (dr * 1e3, float(runs[n]["H"]), Q[n][0]))
        ax[1].set_xlabel("t (s)"), ax[1].set_ylabel("mass out (kg/m)"), ax[1].legend(fontsize=8)
        ax[1].set_title("W = 12 mm, three fill heights")
    rs = sorted((n for n in runs if n == "W12" or re.fullmatch(r"W12_dr[0-9.]+", n)), key=lambda n: -float(runs[n]["dr"]))
    if rs:
        P("")
        P("| W = 12 mm, dr (mm) | W/dr | particles | rate (kg/m/s) | change from the next coarser | wall (s) | "
          "steps | backend |")
        P("|---|---|---|---|---|---|---|---|")
        prev, hh, ee = None, [], []
        for n in rs:
            r = runs[n]
            qq = Q[n][0]
            P("| %g | %.0f | %s | %.3f | %s | %s | %s | %s |" % (
                float(r["dr"]) * 1e3, float(r["W"]) / float(r["dr"]), r["material"], qq,
                "%+.1f %%" % (100 * (qq / prev - 1)) if prev else "-", r["wall_s"], r["steps"], r.get("backend", "")))
            if prev:
                hh.append(float(r["dr"])), ee.append(abs(qq - prev))
            prev = qq
        P("")
        P("observed order of the rate's change between resolutions: %.2f" % batch.observed_order(hh, ee))
    if "mixed_W12" in runs:
        d = outflow(where["mixed_W12"], "mixed_W12")
        n, sv, t = d["n_outflow"], d["small_volume_outflow"], d["time"]
        dr = float(runs["mixed_W12"]["dr"])
        win = 10
        frac = (sv[win:] - sv[:-win]) / np.maximum((n[win:] - n[:-win]) * dr * dr, 1e-30)
        ax[2].plot(0.5 * (t[win:] + t[:-win]), frac, label="outflow, over %.2f s" % (t[win] - t[0]))
        ax[2].plot(t, sv / np.maximum(n * dr * dr, 1e-30), "--", label="cumulative")
        ax[2].axhline(0.5, color="k", lw=0.6)
        ax[2].set_xlabel("t (s)"), ax[2].set_ylabel("small-grain fraction of the outflow"), ax[2].legend(fontsize=8)
        ax[2].set_title("bidisperse fill, C = 0.5 mixed")
        P("")
        P("bidisperse fill (C = 0.5, shear-rate segregation): %d of %s particles out by t = %.2f s; small-grain "
          "fraction of the outflow %s" % (n[-1], runs["mixed_W12"]["material"], t[-1],
                                          ", ".join("%.3f at %.1f s" % (f, tt) for f, tt in
                                                    list(zip(frac, 0.5 * (t[win:] + t[:-win])))[::40])))
    fig.tight_layout()
    fig.savefig(os.path.join(a.docs, "validation_silo.png"), dpi=110)
    batch.report_tables(a, lines)


def main(argv=None):
    batch.study_main(__doc__, ("beverloo", "height", "resolution", "mixed"), cases, tidy_done, cmd_report, "silo", argv=argv)


if __name__ == "__main__":
    main()
