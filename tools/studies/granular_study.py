#!/usr/bin/env python3
"""Where the granular solver's methods fail, and what users trade for speed
(issue "Granular flow"), on the rotating drum of inputs/drum_2d_EV.yml.

  python3 -m tools.studies.granular_study run --out DIR [--jobs N] [--sphseg B] [--sphseg-single B] [--quick]
  python3 -m tools.studies.granular_study analyze --out DIR [--docs docs/data/granular]
  python3 -m tools.studies.granular_study chart --out DIR [--docs docs/data/granular]     # from the CSV files alone

run: every case below as its own sphseg process, N at a time (one OpenMP
thread each unless the case says more), recording exit status, wall time,
steps and the error line in DIR/runs.csv. analyze: the figures of merit
into DIR/results.csv and the charts into DOCS (granular_noise.png,
granular_stability.png, granular_tradeoffs.png) with a table
granular_study.md.

Cases (EV drum, Table 1 material unless named):
  noise_*    paper figure 16: start from zero stress, t = 0.01 s, E = 10 MPa,
             dr = 0.5 mm, with no stabilisation, artificial viscosity only
             (alpha = 0.1) and the Shepard filter only (every 30 steps), and
             both (the default). Noise figure: rms over the material of
             sigma_yy minus its kernel average over the 2h neighbourhood,
             divided by rho g R.
  cfl_*      Run:cfl_flow from 0.1 to 3 (dr = 1.4 mm, E = 0.1 MPa, 1.5 s: the
             bed starts to avalanche at about 0.75 s): blows up or not.
  lam_*      Material:lambda from 0 to 100 1/s (same set-up, cfl 0.1).
  res_*      resolution dr = 2.5, 1.75, 1.25, 1.0 mm (E = 0.1 MPa, 2 s).
  mod_*      E = 10, 1, 0.1 MPa (dr = 2.5 mm, 1.5 s).
  prec_*     single against double precision (dr = 1.4 mm, E = 0.1 MPa, 1.5 s).
Accuracy of a drum case: the mid-chord speed profile against the case's
reference (finest dr; stiffest E; double precision) at the final time, as
the rms difference over d_mc divided by the reference's surface speed; the
dynamic angle and the segregation index (tools/analysis/drum_analysis.py).
"""
import argparse
import concurrent.futures as cf
import csv
import os
import re
import subprocess
import time

import numpy as np

from tools import ROOT  # noqa: E402
from tools.analysis import drum_analysis  # noqa: E402
from tools.analysis import snap  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "drum_2d_EV.yml")


def cases(quick):
    """(name, overrides, threads, binary kind) of every run."""
    k = 0.1 if quick else 1.0  # --quick: a tenth of the simulated time
    c = []
    base_noise = {"Initial:stress": "zero", "Material:E": "1e7", "Geometry:dr": "0.0005",
                  "Run:t_end": repr(0.01 * k), "Output:dt": repr(0.01 * k)}
    for name, av, sh in [("none", 0, 0), ("av", 0.1, 0), ("shepard", 0, 30), ("both", 0.1, 30)]:
        c.append(("noise_" + name, dict(base_noise, **{"Flow:alpha_av": repr(av), "Flow:shepard_every": str(sh)}),
                  2, "double"))
    base = {"Geometry:dr": "0.0014", "Material:E": "1e5", "Run:t_end": repr(1.5 * k),
            "Output:dt": repr(0.25 * k)}
    for cfl in [0.1, 0.2, 0.4, 0.7, 1.0, 1.3, 1.6, 2.0, 3.0]:
        c.append(("cfl_%g" % cfl, dict(base, **{"Run:cfl_flow": repr(cfl)}), 1, "double"))
    for lam in [0, 0.001, 0.1, 1, 10, 100]:
        c.append(("lam_%g" % lam, dict(base, **{"Material:lambda": repr(lam)}), 1, "double"))
    c.append(("prec_single", dict(base), 1, "single"))
    for dr, th in [(0.0025, 1), (0.00175, 1), (0.00125, 2), (0.001, 4)]:
        c.append(("res_%g" % (dr * 1e3), {"Geometry:dr": repr(dr), "Material:E": "1e5",
                                          "Run:t_end": repr(2.0 * k), "Output:dt": repr(0.5 * k)}, th, "double"))
    for E, th in [(1e7, 2), (1e6, 1), (1e5, 1)]:
        c.append(("mod_%g" % (E / 1e6), {"Geometry:dr": "0.0025", "Material:E": repr(E),
                                         "Run:t_end": repr(1.5 * k), "Output:dt": repr(0.5 * k)}, th, "double"))
    return c


def run_case(args, case):
    name, over, threads, kind = case
    out = os.path.join(args.out, name)
    binary = args.sphseg if kind == "double" else args.sphseg_single
    # the study's runs are monaghan's (its noise cases vary Flow:alpha_av), without the corrected gradient and the
    # shifting: the scene sets riemann and both since issue 30
    cmd = [binary, SCENE, "-o", out, "--overwrite", "-P", "Run:progress_s=1e9", "-P", "Flow:stabilization=monaghan",
           "-P", "Flow:gradient_correction=off", "-P", "Flow:shifting=off"] + sum(
        [["-P", "%s=%s" % kv] for kv in over.items()], [])
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    t0 = time.time()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=args.timeout)
        rc, stdout, err = r.returncode, r.stdout, (r.stderr.strip().splitlines() or [""])[-1] if r.returncode else ""
    except subprocess.TimeoutExpired:
        rc, stdout, err = 124, "", "not finished within --timeout %g s" % args.timeout
    wall = time.time() - t0
    m = re.search(r"done: (\d+) steps", stdout)
    return {"name": name, "rc": rc, "wall_s": "%.2f" % wall, "steps": m.group(1) if m else "",
            "threads": threads, "precision": kind, "error": err}


def cmd_run(args):
    os.makedirs(args.out, exist_ok=True)
    todo = [c for c in cases(args.quick) if not args.only or c[0] in args.only]
    todo.sort(key=lambda c: -c[2])  # the multi-thread ones first
    keys = ["name", "rc", "wall_s", "steps", "threads", "precision", "error"]
    path = os.path.join(args.out, "runs.csv")
    append = args.only and os.path.exists(path)  # later rows of a name win (load_runs)
    with open(path, "a" if append else "w", newline="") as f, cf.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        w = csv.DictWriter(f, fieldnames=keys)
        if not append:
            w.writeheader()
        for row in ex.map(lambda c: run_case(args, c), todo):
            w.writerow(row)
            f.flush()
            print("%-14s rc %d  %8s s  %s" % (row["name"], row["rc"], row["wall_s"], row["error"][:120]), flush=True)


# ---- analysis -----------------------------------------------------------------


def noise_figure(outdir):
    par = drum_analysis.used_params(outdir)
    d = drum_analysis.Drum(snap.list_snapshots(outdir)[-1], par)
    s = snap.read_snapshot(snap.list_snapshots(outdir)[-1])
    m = np.asarray(s["Kind"]) == snap.MATERIAL
    syy = np.asarray(s["Stress"])[m, 1]
    smooth = np.array([d.interp(d.x[i:i + 1], syy)[0] for i in range(len(syy))])
    rgR = par["Physics"]["rho"] * 9.81 * par["Geometry"]["radius"]
    return float(np.sqrt(np.mean((syy - smooth) ** 2)) / rgR), d, syy


def profile_error(d, ref):
    """rms over the reference's mid-chord of |u| - |u|_ref, / surface speed."""
    dm, pts = ref.midchord()
    ur = ref.interp(pts, ref.speed)
    u = d.interp(pts, d.speed)
    ok = np.isfinite(ur) & np.isfinite(u)
    return float(np.sqrt(np.mean((u[ok] - ur[ok]) ** 2)) / np.nanmax(ur))


def load_runs(out):
    with open(os.path.join(out, "runs.csv")) as f:
        return {r["name"]: r for r in csv.DictReader(f)}


def cmd_analyze(args):
    runs = load_runs(args.out)
    res = {}
    drums = {}
    for name, r in sorted(runs.items()):
        o = os.path.join(args.out, name)
        row = {"name": name, "rc": int(r["rc"]), "wall_s": float(r["wall_s"]),
               "steps": int(r["steps"]) if r["steps"] else 0, "error": r["error"]}
        if row["rc"] == 0:
            par = drum_analysis.used_params(o)
            if name.startswith("noise_"):
                row["noise"], _, _ = noise_figure(o)
            else:
                d = drum_analysis.Drum(snap.list_snapshots(o)[-1], par)
                drums[name] = d
                row.update(angle=d.angle, surface_speed=d.surface_speed(),
                           seg_index=d.segregation_index(), t=d.t)
        res[name] = row
    refs = {"res_": "res_1", "mod_": "mod_10", "prec_": "cfl_0.1", "cfl_": "cfl_0.1", "lam_": "lam_0.001"}
    for name, row in res.items():
        for pre, ref in refs.items():
            if name.startswith(pre) and name in drums and ref in drums:
                row["profile_err"] = profile_error(drums[name], drums[ref])
    keys = ["name", "rc", "wall_s", "steps", "noise", "angle", "surface_speed", "seg_index", "profile_err", "error"]
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        for name in sorted(res):
            w.writerow(res[name])
    os.makedirs(args.docs, exist_ok=True)
    chart_noise(args.out, res, os.path.join(args.docs, "granular_noise.png"))
    chart_stability(res, os.path.join(args.docs, "granular_stability.png"))
    chart_trades(res, runs, os.path.join(args.docs, "granular_tradeoffs.png"))
    table(res, os.path.join(args.docs, "granular_study.md"))


def chart_noise(out, res, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = [n for n in ["noise_none", "noise_av", "noise_shepard", "noise_both"] if res.get(n, {}).get("rc") == 0]
    labels = {"noise_none": "no stabilisation", "noise_av": "artificial viscosity", "noise_shepard": "Shepard filter",
              "noise_both": "both (default)"}
    fig, ax = plt.subplots(1, len(names) + 1, figsize=(3.3 * (len(names) + 1), 3.3))
    lo = hi = None
    fields = []
    for n in names:
        _, d, syy = noise_figure(os.path.join(out, n))
        fields.append((n, d, syy))
        lo = syy.min() if lo is None else min(lo, syy.min())
        hi = syy.max() if hi is None else max(hi, syy.max())
    for a, (n, d, syy) in zip(ax, fields):
        ms = (d.dr / (2.2 * d.R) * 2.4 * 72) ** 2
        sc = a.scatter(d.x[:, 0] * 1e3, d.x[:, 1] * 1e3, c=syy / 1e3, s=ms, cmap="viridis", vmin=lo / 1e3,
                       vmax=hi / 1e3, linewidths=0)
        a.set_aspect("equal")
        a.set_title("%s\nnoise %.3f" % (labels[n], res[n]["noise"]), fontsize=8)
        a.set_xticks([])
        a.set_yticks([])
    fig.colorbar(sc, ax=ax[len(names) - 1], shrink=0.7, label=r"$\sigma_{yy}$ (kPa)")
    ax[-1].bar(range(len(names)), [res[n]["noise"] for n in names])
    ax[-1].set_xticks(range(len(names)))
    ax[-1].set_xticklabels([labels[n].replace(" ", "\n") for n in names], fontsize=7)
    ax[-1].set_ylabel(r"rms($\sigma_{yy}$ - kernel mean) / $\rho g R$")
    fig.suptitle("stress noise at t = %g s from a zero-stress start (paper fig. 16)" % fields[0][1].t, fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def chart_stability(res, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.4))
    for a, pre, lab, logx in [(ax[0], "cfl_", r"$\chi_{CFL}$ (Run:cfl_flow)", False),
                              (ax[1], "lam_", r"$\lambda$ (Material:lambda, 1/s)", True)]:
        rows = sorted([r for n, r in res.items() if n.startswith(pre)], key=lambda r: float(r["name"][len(pre):]))
        xs = [float(r["name"][len(pre):]) for r in rows]
        xp = [max(x, 1e-4) for x in xs] if logx else xs
        for x, r in zip(xp, rows):
            if r["rc"] == 0:
                a.plot(x, r["angle"], "o", color="C0")
            else:
                a.plot(x, 0, "x", color="C3", ms=9)
        a.plot([], [], "o", color="C0", label="ran: dynamic angle at the end")
        a.plot([], [], "x", color="C3", label="blew up (exit 3)")
        if logx:
            a.set_xscale("log")
        a.set_xlabel(lab)
        a.set_ylabel("dynamic angle (deg)")
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def chart_trades(res, runs, png):
    """Top: error against cost (the reference of each trade is the dashed
    line at its cost); bottom: surface speed and dynamic angle."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(2, 3, figsize=(12, 6.4))
    trades = [("res_", "resolution: dr (mm)", "res_1"), ("mod_", "elastic modulus: E (MPa)", "mod_10"),
              ("prec", "precision", "cfl_0.1")]
    for k, (pre, title, ref) in enumerate(trades):
        if pre == "prec":
            rows = [("double", res.get("cfl_0.1")), ("single", res.get("prec_single"))]
        else:
            rows = sorted([(n[4:], r) for n, r in res.items() if n.startswith(pre)], key=lambda t: float(t[0]))
        rows = [(t, r) for t, r in rows if r and r["rc"] == 0]
        a = ax[0][k]
        for t, r in rows:
            cpu = r["wall_s"] * int(runs[r["name"]]["threads"])
            if r["name"] == ref:
                a.axvline(cpu, ls="--", color="0.5")
                a.annotate("reference " + t, (cpu, 0.5), xycoords=("data", "axes fraction"), rotation=90,
                           fontsize=7, xytext=(-9, 0), textcoords="offset points", va="center")
                continue
            a.loglog(cpu, r["profile_err"], "o", color="C0")
            a.annotate(t, (cpu, r["profile_err"]), fontsize=8, xytext=(3, 3), textcoords="offset points")
        a.set_xlabel("cost: wall time x threads (core-s)")
        a.set_ylabel("mid-chord speed error / surface speed")
        a.set_title(title, fontsize=9)
        a.grid(alpha=0.3, which="both")
        b = ax[1][k]
        xs = list(range(len(rows)))
        b.plot(xs, [100 * r["surface_speed"] for _, r in rows], "o-", color="C0")
        b.set_ylabel("surface speed (cm/s)", color="C0")
        b2 = b.twinx()
        b2.plot(xs, [r["angle"] for _, r in rows], "s--", color="C1")
        b2.set_ylabel("dynamic angle (deg)", color="C1")
        b.set_xticks(xs)
        b.set_xticklabels([t for t, _ in rows])
        b.set_xlabel(title.split(": ")[-1] + " (t = %g s)" % rows[0][1]["t"])
        b.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def cmd_chart(args):
    """Redraw the stability and trade charts and the table from results.csv
    and runs.csv alone (the noise chart needs the snapshots)."""
    runs = load_runs(args.out)
    res = {}
    with open(os.path.join(args.out, "results.csv")) as f:
        for r in csv.DictReader(f):
            row = {"name": r["name"], "rc": int(r["rc"]), "wall_s": float(r["wall_s"]),
                   "steps": int(r["steps"]), "error": r["error"]}
            for k in ("noise", "angle", "surface_speed", "seg_index", "profile_err"):
                if r.get(k):
                    row[k] = float(r[k])
            res[r["name"]] = row
    for name, r in res.items():
        if "angle" in r:
            with open(os.path.join(args.out, name, "used_params.yml")) as f:
                import yaml
                r["t"] = yaml.safe_load(f)["Run"]["t_end"]
    chart_stability(res, os.path.join(args.docs, "granular_stability.png"))
    chart_trades(res, runs, os.path.join(args.docs, "granular_tradeoffs.png"))
    table(res, os.path.join(args.docs, "granular_study.md"))


def table(res, md):
    with open(md, "w") as f:
        f.write("| case | exit | wall (s) | steps | noise | angle (deg) | surface speed (cm/s) | "
                "segregation index | speed-profile error |\n|---|---|---|---|---|---|---|---|---|\n")
        for n in sorted(res):
            r = res[n]

            def g(k, fmt):
                return fmt % r[k] if k in r else ""
            f.write("| %s | %d | %.1f | %d | %s | %s | %s | %s | %s |\n" % (
                n, r["rc"], r["wall_s"], r["steps"], g("noise", "%.4f"), g("angle", "%.1f"),
                "%.2f" % (100 * r["surface_speed"]) if "surface_speed" in r else "", g("seg_index", "%.2e"),
                g("profile_err", "%.3g")))
        bad = [(n, r["error"]) for n, r in sorted(res.items()) if r["rc"] != 0]
        if bad:
            f.write("\nBlow-ups:\n\n")
            for n, e in bad:
                f.write("- %s: `%s`\n" % (n, e))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--out", required=True)
    r.add_argument("--jobs", type=int, default=os.cpu_count())
    r.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    r.add_argument("--sphseg-single", default=os.path.join(ROOT, "build-single", "sphseg"))
    r.add_argument("--quick", action="store_true", help="a tenth of the simulated times (smoke test)")
    r.add_argument("--only", nargs="+", help="run these cases only, appending to runs.csv")
    r.add_argument("--timeout", type=float, default=None, help="wall seconds per case (rc 124 past it)")
    a = sub.add_parser("analyze")
    a.add_argument("--out", required=True)
    a.add_argument("--docs", default=os.path.join(ROOT, "docs", "data", "granular"))
    c = sub.add_parser("chart", help="redraw the stability and trade charts from the CSV files")
    c.add_argument("--out", required=True)
    c.add_argument("--docs", default=os.path.join(ROOT, "docs", "data", "granular"))
    args = ap.parse_args()
    {"run": cmd_run, "analyze": cmd_analyze, "chart": cmd_chart}[args.cmd](args)


if __name__ == "__main__":
    main()
