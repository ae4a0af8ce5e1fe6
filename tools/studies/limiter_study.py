"""The cost and the effect of Segregation:limiter on the shear box (paper §5):
the conservative scheme with limiter none and donor, at several dr/H, against
the 1D FV reference (tools/analysis/seg1d.py): MAE at t/T = 20, 40, 80 (eq. 5.3), the
lowest and highest C of the diagnostics rows (one every T/20) and the drift of
sum C_i V_i.

  python3 -m tools.studies.limiter_study run --out DIR [--res 0.04 0.02 0.01]
        [--cases sym_const ...] [--jobs N] [--sphseg build/sphseg]
      runs tools/studies/shearbox_study.py's cases once per limiter into DIR/none and
      DIR/donor (one thread each, N at a time; DIR/<limiter>/runs.csv);
  python3 -m tools.studies.limiter_study report --out DIR [--csv FILE] [--png FILE]
      the table (markdown, printed), FILE.csv with one row per run, and the
      chart: MAE at t/T = 80 and the largest excursion of C outside [0, 1],
      each against dr/H. With --csv FILE alone (no DIR runs) the table and
      chart are redrawn from FILE;
  python3 -m tools.studies.limiter_study steady --out DIR [--res 0.04] [--pe 5 20 40 100]
      the steady column of tests/validate_steady.py (at rest, uniform phi0,
      constant V and D, to t = 4 H^2/D; the same keys) with each limiter,
      against Gray & Chugunov's profile (seg1d.steady_analytic): MAE, largest
      error and C range, one markdown line per run.
"""
import argparse
import csv
import os
import sys

from tools import ROOT  # noqa: E402
from tools.studies import shearbox_study  # noqa: E402

LIMITERS = ("none", "donor")
TAUS = (20, 40, 80)
FIELDS = ["case", "limiter", "res", "rc", "wall_s", "C_min", "C_max", "drift_max"] + [f"mae_{t}" for t in TAUS]


def cmd_run(a):
    for lim in LIMITERS:
        shearbox_study.main(["run", "--out", os.path.join(a.out, lim), "--res", *map(str, a.res),
                             "--schemes", "conservative", "--cases", *a.cases, "--jobs", str(a.jobs),
                             "--sphseg", a.sphseg, "--set", f"Segregation:limiter={lim}", "Output:diag_dt=0.65"])
    return 0


def collect(out):
    """One row per finished run of DIR/none and DIR/donor."""
    import numpy as np
    from tools.analysis import snap
    from tools.studies import study
    rows = []
    for lim in LIMITERS:
        with open(os.path.join(out, lim, "runs.csv")) as f:
            for r in csv.DictReader(f):
                d = shearbox_study.run_dir(os.path.join(out, lim), r["case"], r["scheme"], float(r["res"]))
                row = {"case": r["case"], "limiter": lim, "res": float(r["res"]), "rc": int(r["rc"]),
                       "wall_s": float(r["wall_s"])}
                if row["rc"] == 0:
                    e = study.case_errors(d, TAUS)
                    dg = snap.read_diagnostics(d)
                    row.update({"C_min": float(np.min(np.asarray(dg["C_min"], float))),
                                "C_max": float(np.max(np.asarray(dg["C_max"], float))),
                                "drift_max": e["drift_max"]})
                    row.update({f"mae_{t}": e["errors"][t]["mae"] for t in TAUS})
                rows.append(row)
    return rows


def read_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k in FIELDS[2:]:
            r[k] = float(r[k]) if r.get(k, "") != "" else None
    return rows


def table(rows):
    """Markdown: one line per (case, dr/H), none against donor."""
    key = {(r["case"], r["limiter"], r["res"]): r for r in rows}
    cases = [c for c in shearbox_study.CASES if any(r["case"] == c for r in rows)]
    res = sorted({r["res"] for r in rows}, reverse=True)
    out = ["| case | dr/H | MAE t/T = 20, none / donor | 40 | 80 | C range, none | C range, donor | "
           "drift, none / donor |", "|---|---|---|---|---|---|---|---|"]
    for c in cases:
        for h in res:
            n, d = key.get((c, "none", h)), key.get((c, "donor", h))
            if not n or not d or n["rc"] or d["rc"]:
                continue
            maes = " | ".join(f"{n[f'mae_{t}']:.4f} / {d[f'mae_{t}']:.4f}" for t in TAUS)
            out.append(f"| {c} | {h:g} | {maes} | [{n['C_min']:.4f}, {n['C_max']:.4f}] | "
                       f"[{d['C_min']:.4f}, {d['C_max']:.4f}] | {n['drift_max']:.1e} / {d['drift_max']:.1e} |")
    return "\n".join(out)


def chart(rows, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    colours = dict(zip(shearbox_study.CASES, ("C0", "C1", "C2", "C3")))
    for c in shearbox_study.CASES:
        for lim, style in (("none", "--o"), ("donor", "-s")):
            rs = sorted((r for r in rows if r["case"] == c and r["limiter"] == lim and not r["rc"]),
                        key=lambda r: r["res"])
            if not rs:
                continue
            h = [r["res"] for r in rs]
            ax[0].loglog(h, [r["mae_80"] for r in rs], style, color=colours[c], label=f"{c}, {lim}")
            excess = [max(-r["C_min"], r["C_max"] - 1, 1e-12) for r in rs]
            ax[1].loglog(h, excess, style, color=colours[c], label=f"{c}, {lim}")
    ax[0].set_xlabel("dr/H")
    ax[0].set_ylabel("MAE at t/T = 80")
    ax[0].set_title("accuracy against the 1D reference")
    ax[1].axhline(1e-3, color="k", lw=0.8)
    ax[1].set_xlabel("dr/H")
    ax[1].set_ylabel("max(-min C, max C - 1); none outside: drawn at 1e-12")
    ax[1].set_title("C outside [0, 1] (line: 1e-3)")
    ax[1].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def cmd_report(a):
    if a.out:
        rows = collect(a.out)
        if a.csv:
            with open(a.csv, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=FIELDS)
                w.writeheader()
                w.writerows(rows)
    else:
        rows = read_csv(a.csv)
    print(table(rows))
    if a.png:
        chart(rows, a.png)
    return 0


STEADY = {5.0: 0.5, 20.0: 0.3, 40.0: 0.7, 100.0: 0.5}  # Pe: phi0 (tests/validate_steady.py, docs/data/steady/steady_table.md)


def cmd_steady(a):
    import subprocess
    import numpy as np
    from tools.analysis import seg1d
    from tools.analysis import snap
    from tools.studies import study
    H, D = study.H, 1e-6
    print("| dr/H | phi0 | Pe | limiter | MAE | max error | C range |\n|---|---|---|---|---|---|---|")
    for Pe in a.pe:
        phi0, t_end = STEADY[Pe], 4 * H * H / D
        for lim in LIMITERS:
            out = os.path.join(a.out, f"steady_{a.res:g}_{Pe:g}_{lim}")
            over = {"Kinematics:velocity": "rest", "Segregation:flux": "symmetric",
                    "Segregation:model": "constant", "Segregation:V": repr(Pe * D / H), "Segregation:D": repr(D),
                    "Segregation:scheme": "conservative", "Segregation:limiter": lim,
                    "Initial:C_below": repr(phi0), "Initial:C_above": repr(phi0),
                    "Geometry:dr": repr(a.res * H), "Geometry:width": repr(H / 4), "Run:t_end": repr(t_end),
                    "Output:dt": repr(t_end), "Output:diag_dt": repr(t_end / 20), "Run:progress_s": "1e9"}
            cmd = [a.sphseg, study.SCENE, "-o", out, "--overwrite"]
            cmd += sum([["-P", f"{k}={v}"] for k, v in over.items()], [])
            subprocess.run(cmd, check=True, capture_output=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
            y, C = snap.row_profile(snap.read_snapshot(snap.list_snapshots(out)[-1]), a.res * H)
            ref = seg1d.steady_analytic(y / H, phi0, Pe)
            dg = snap.read_diagnostics(out)
            print(f"| {a.res:g} | {phi0} | {Pe:g} | {lim} | {seg1d.mae(C, ref):.4f} | {np.max(np.abs(C - ref)):.4f} | "
                  f"[{np.min(dg['C_min']):.4f}, {np.max(dg['C_max']):.4f}] |", flush=True)
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = shearbox_study.add_run_parser(sub)
    r.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    z = sub.add_parser("report")
    z.add_argument("--out", help="study folder (DIR/none, DIR/donor); without it, --csv is read")
    z.add_argument("--csv")
    z.add_argument("--png")
    y = sub.add_parser("steady")
    y.add_argument("--out", required=True)
    y.add_argument("--res", type=float, default=0.04)
    y.add_argument("--pe", type=float, nargs="+", default=sorted(STEADY), choices=sorted(STEADY))
    y.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    a = ap.parse_args(argv)
    if a.cmd == "report" and not a.out and not a.csv:
        ap.error("report needs --out or --csv")
    return {"run": cmd_run, "report": cmd_report, "steady": cmd_steady}[a.cmd](a)


if __name__ == "__main__":
    sys.exit(main())
