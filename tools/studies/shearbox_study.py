"""The full shear-box study (paper §5): accuracy, convergence, conservation
and speed of the concentration schemes against the 1D FV reference.

  python3 -m tools.studies.shearbox_study run --out DIR [--res 0.04 0.02 0.01 0.005]
        [--schemes paper direct conservative] [--cases sym_const ...] [--jobs N]
        [--sphseg build/sphseg]
      runs sphseg once per (case, scheme, dr/H), OMP_NUM_THREADS=1 each, N at a
      time, and records the wall time of every run in DIR/runs.csv (needs only
      the Python standard library, so it runs on any machine with the binary);
  python3 -m tools.studies.shearbox_study analyze --out DIR [DIR ...] [--docs docs/data/shearbox]
      compares every run with the reference at t/T = 20, 40, 80 (MAE, RMSE,
      eqs. 5.3-5.4; saved in DIR/errors.csv, which later analyses reuse when
      DIR/runs.csv and the snapshots are gone), merges the folders, and writes docs/data/shearbox/shearbox_table.md (error table,
      observed orders, drift of sum C_i V_i, wall times) and the charts
      docs/data/shearbox/shearbox_convergence.png, docs/data/shearbox/shearbox_speed_accuracy.png,
      docs/data/shearbox/shearbox_drift.png.
A run that stops with exit status 3 (numerical blow-up) is recorded as
unstable with the time it reached.
"""
import argparse
import concurrent.futures as cf
import csv
import os
import subprocess
import sys
import time

from tools import ROOT  # noqa: E402
H, T = 0.087, 13.0
SCENE = os.path.join(ROOT, "inputs", "shearbox_2d.yml")
CASES = {
    "sym_const": {"Segregation:flux": "symmetric", "Segregation:model": "constant"},
    "asym_const": {"Segregation:flux": "asymmetric", "Segregation:model": "constant"},
    "sym_shear": {"Segregation:flux": "symmetric", "Segregation:model": "shear_rate"},
    "asym_shear": {"Segregation:flux": "asymmetric", "Segregation:model": "shear_rate"},
}
TAUS = (20, 40, 80)


def run_dir(out, case, scheme, res):
    return os.path.join(out, f"{case}_{scheme}_{res:g}")


def run_one(sphseg, out, case, scheme, res, threads=1, extra=()):
    """One sphseg run; returns a row for runs.csv."""
    d = run_dir(out, case, scheme, res)
    over = dict(CASES[case])
    over.update({"Segregation:scheme": scheme, "Geometry:dr": repr(res * H),
                 "Run:t_end": repr(max(TAUS) * T), "Output:dt": repr(min(TAUS) * T),
                 "Output:diag_dt": repr(T), "Run:progress_s": "1e9"})
    over.update(dict(kv.split("=", 1) for kv in extra))
    cmd = [sphseg, SCENE, "-o", d, "--overwrite"] + sum([["-P", f"{k}={v}"] for k, v in over.items()], [])
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    with open(d + ".log", "w") as f:
        f.write(r.stdout + r.stderr)
    rate = ""
    for line in r.stdout.splitlines():
        if line.startswith("done:"):
            rate = line.split(",")[2].split()[0]
    return {"case": case, "scheme": scheme, "res": res, "rc": r.returncode, "wall_s": f"{wall:.3f}",
            "threads": threads, "particle_steps_per_s": rate,
            "message": (r.stderr.strip().splitlines() or [""])[-1][:300]}


RUN_FIELDS = ["case", "scheme", "res", "rc", "wall_s", "threads", "particle_steps_per_s", "message"]


def cmd_run(a):
    """Runs every job; each finished run is appended to DIR/runs.csv at once,
    so a study cut short keeps what it finished."""
    os.makedirs(a.out, exist_ok=True)
    jobs = [(c, s, r) for r in a.res for s in a.schemes for c in a.cases]
    jobs.sort(key=lambda j: j[2])  # finest (longest) runs first
    path = os.path.join(a.out, "runs.csv")
    if not os.path.exists(path):
        with open(path, "w", newline="") as f:
            csv.DictWriter(f, fieldnames=RUN_FIELDS).writeheader()
    with cf.ThreadPoolExecutor(max_workers=a.jobs) as ex:
        futs = [ex.submit(run_one, a.sphseg, a.out, c, s, r, a.threads, a.set) for c, s, r in jobs]
        for f in cf.as_completed(futs):
            row = f.result()
            with open(path, "a", newline="") as fh:
                csv.DictWriter(fh, fieldnames=RUN_FIELDS).writerow(row)
            print(f"{row['case']:10s} {row['scheme']:12s} dr/H={row['res']:<6g} rc={row['rc']} "
                  f"wall={row['wall_s']} s {row['message'] if row['rc'] else ''}", flush=True)


ERR_FIELDS = ["case", "scheme", "res", "rc", "wall_s", "t_fail", "drift_max"] + \
    [f"{m}_{t}" for t in TAUS for m in ("mae", "rmse", "max")]


def _errors_from_runs(out):
    """Compare every run in OUT/runs.csv with the reference; also saved to
    OUT/errors.csv so that charts can be redrawn without the snapshots."""
    from tools.studies import study
    from tools.analysis import snap
    rows = []
    with open(os.path.join(out, "runs.csv")) as f:
        for r in csv.DictReader(f):
            row = {"case": r["case"], "scheme": r["scheme"], "res": float(r["res"]), "rc": int(r["rc"]),
                   "wall_s": float(r["wall_s"]), "t_fail": "", "drift_max": ""}
            d = run_dir(out, r["case"], r["scheme"], row["res"])
            if row["rc"] == 0:
                e = study.case_errors(d, TAUS)
                row["drift_max"] = e["drift_max"]
                for t in TAUS:
                    for m in ("mae", "rmse", "max"):
                        row[f"{m}_{t}"] = e["errors"][t][m]
            else:
                diag = snap.read_diagnostics(d)
                row["t_fail"] = float(diag["time"][-1]) if len(diag["time"]) else 0.0
            rows.append(row)
    with open(os.path.join(out, "errors.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=ERR_FIELDS)
        w.writeheader()
        w.writerows(rows)
    return rows


def _load_rows(out):
    """Rows of errors (from OUT/errors.csv if the snapshots are gone), each
    with its diagnostics when OUT/<run>/diagnostics.csv exists."""
    from tools.analysis import snap
    path, runs = os.path.join(out, "errors.csv"), os.path.join(out, "runs.csv")
    rows = []
    if os.path.exists(path):
        with open(path) as f:
            rows = list(csv.DictReader(f))
    threads = {}
    if os.path.exists(runs):
        with open(runs) as f:
            threads = {(r["case"], r["scheme"], float(r["res"])): int(r.get("threads") or 1)
                       for r in csv.DictReader(f)}
        if set(threads) != {(r["case"], r["scheme"], float(r["res"])) for r in rows}:
            rows = _errors_from_runs(out)  # new runs since errors.csv was written
    for r in rows:
        r["res"], r["rc"], r["wall_s"] = float(r["res"]), int(r["rc"]), float(r["wall_s"])
        r["core_s"] = r["wall_s"] * threads.get((r["case"], r["scheme"], r["res"]), 1)
        if r["rc"] != 0:
            r["t_fail"] = float(r["t_fail"])
            continue
        r["drift_max"] = float(r["drift_max"])
        r["errors"] = {t: {m: float(r[f"{m}_{t}"]) for m in ("mae", "rmse", "max")} for t in TAUS}
        d = run_dir(out, r["case"], r["scheme"], r["res"])
        r["diag"] = snap.read_diagnostics(d) if os.path.exists(os.path.join(d, "diagnostics.csv")) else None
    return rows


def _table(rows):
    from tools.studies import study
    lines = ["| case | scheme | dr/H | MAE t/T=20 | MAE 40 | MAE 80 | RMSE 80 | order (MAE 80) | max drift | "
             "wall s x threads |", "|---|---|---|---|---|---|---|---|---|---|"]
    key = {}
    for r in rows:
        key[(r["case"], r["scheme"], r["res"])] = r
    for r in sorted(rows, key=lambda r: (r["case"], r["scheme"], -r["res"])):
        if r["rc"] != 0:
            lines.append(f"| {r['case']} | {r['scheme']} | {r['res']:g} | unstable: stopped (exit {r['rc']}) "
                         f"at t/T = {r['t_fail'] / T:.1f} | | | | | | {r['core_s']:.0f} |")
            continue
        e = r["errors"]
        coarse = key.get((r["case"], r["scheme"], r["res"] * 2))
        order = ""
        if coarse is not None and coarse["rc"] == 0:
            order = f"{study.order(coarse['errors'][80]['mae'], e[80]['mae']):.2f}"
        lines.append(f"| {r['case']} | {r['scheme']} | {r['res']:g} | {e[20]['mae']:.4f} | {e[40]['mae']:.4f} | "
                     f"{e[80]['mae']:.4f} | {e[80]['rmse']:.4f} | {order} | {r['drift_max']:.1e} | "
                     f"{r['core_s']:.0f} |")
    return "\n".join(lines)


COLORS = {"paper": "C0", "direct": "C1", "conservative": "C2"}
MARKS = {"sym_const": "o", "asym_const": "s", "sym_shear": "^", "asym_shear": "v"}


def _save(fig, ax, xlabel, title, path):
    """Common labels, legend and file output of the study's charts."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel("MAE of C at t/T = 80")
    ax.legend(fontsize=6)
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=130)


def _chart_convergence(plt, np, ok, path):
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for (case, scheme) in sorted({(r["case"], r["scheme"]) for r in ok}):
        rr = sorted([r for r in ok if r["case"] == case and r["scheme"] == scheme], key=lambda r: r["res"])
        ax.loglog([r["res"] for r in rr], [r["errors"][80]["mae"] for r in rr], marker=MARKS[case],
                  color=COLORS[scheme], label=f"{scheme}, {case}")
    x = np.array([0.005, 0.04])
    ax.loglog(x, 0.05 * (x / 0.04) ** 1.25, "k:", label="order 1.25 (paper)")
    ax.loglog(x, 0.05 * (x / 0.04) ** 2, "k--", label="order 2")
    _save(fig, ax, "dr / H", "Shear box: convergence to the 1D FV reference", path)


def _chart_speed(plt, ok, path):
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for r in ok:
        ax.loglog(r["core_s"], r["errors"][80]["mae"], marker=MARKS[r["case"]], color=COLORS[r["scheme"]],
                  linestyle="none")
        ax.annotate(f"{r['res']:g}", (r["core_s"], r["errors"][80]["mae"]), fontsize=5)
    for s, c in COLORS.items():
        ax.plot([], [], color=c, marker="o", linestyle="none", label=s)
    for k, m in MARKS.items():
        ax.plot([], [], color="gray", marker=m, linestyle="none", label=k)
    _save(fig, ax, "cost of the run to t/T = 80: wall s x OpenMP threads",
          "Speed against accuracy (labels: dr/H)", path)


def _chart_drift(plt, np, ok, path):
    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    for r in ok:
        if r["case"] != "sym_const" or r["diag"] is None:
            continue
        t = np.asarray(r["diag"]["time"], float) / T
        dft = np.abs(np.asarray(r["diag"]["small_volume_drift"], float)) + 1e-17
        axs[0].semilogy(t, dft, color=COLORS[r["scheme"]], alpha=min(1.0, 0.4 + 0.15 * np.log2(0.04 / r["res"])),
                        label=f"{r['scheme']} dr/H={r['res']:g}")
    axs[0].set_xlabel("t / T")
    axs[0].set_ylabel("|relative drift of sum C_i V_i|")
    axs[0].legend(fontsize=6)
    axs[0].set_title("Conservation, sym_const")
    for r in ok:
        axs[1].loglog(r["drift_max"] + 1e-17, r["errors"][80]["mae"], marker=MARKS[r["case"]],
                      color=COLORS[r["scheme"]], linestyle="none")
    for s, c in COLORS.items():
        axs[1].plot([], [], color=c, marker="o", linestyle="none", label=s)
    _save(fig, axs[1], "max |drift| over the run", "Accuracy against drift (all runs)", path)


def _charts(rows, docs):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    ok = [r for r in rows if r["rc"] == 0]
    _chart_convergence(plt, np, ok, os.path.join(docs, "shearbox_convergence.png"))
    _chart_speed(plt, ok, os.path.join(docs, "shearbox_speed_accuracy.png"))
    _chart_drift(plt, np, ok, os.path.join(docs, "shearbox_drift.png"))


def cmd_analyze(a):
    rows = [r for out in a.out for r in _load_rows(out)]
    os.makedirs(a.docs, exist_ok=True)
    _charts(rows, a.docs)
    table = _table(rows)
    with open(os.path.join(a.docs, "shearbox_table.md"), "w") as f:
        f.write(table + "\n")
    print(table)


def add_run_parser(sub):
    """The `run` command of a shear-box study (this one, limiter_study.py):
    --out, --res, --cases, --jobs; the caller adds its own."""
    r = sub.add_parser("run")
    r.add_argument("--out", required=True)
    r.add_argument("--res", type=float, nargs="+", default=[0.04, 0.02, 0.01])
    r.add_argument("--cases", nargs="+", default=list(CASES))
    r.add_argument("--jobs", type=int, default=os.cpu_count())
    return r


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = add_run_parser(sub)
    r.add_argument("--schemes", nargs="+", default=["paper", "direct", "conservative"])
    r.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of each run")
    r.add_argument("--set", nargs="*", default=[], help="extra Section:key=value overrides")
    r.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    z = sub.add_parser("analyze")
    z.add_argument("--out", required=True, nargs="+", help="study folders (merged)")
    z.add_argument("--docs", default=os.path.join(ROOT, "docs", "data", "shearbox"))
    a = ap.parse_args(argv)
    return cmd_run(a) if a.cmd == "run" else cmd_analyze(a)


if __name__ == "__main__":
    sys.exit(main())
