#!/usr/bin/env python3
"""Scaling charts from the CSV files of jobs/scaling_weak.sbatch and
jobs/scaling_strong.sbatch.

Columns read: mode (weak|strong), ranks, particles, steps, wall_s,
particle_steps_per_s, halo_s (may be empty), settings (the job scripts' named
set of keys, "scene" or "fast"; "scene" where the column is missing). Rows of
the same mode, settings and rank count (repeats, several CSV files) are
averaged; each mode and settings is a curve of its own.

  weak efficiency    E_w(P) = r(P)/P / r(1)     (r: particle-steps/s; per-rank rate
                                                 relative to one rank)
  strong efficiency  E_s(P) = T(1) / (P T(P))   (T = particles * steps / r: the
                                                 stepping time, output left out)
  halo share         halo_s / wall_s
  --strong-same-cores: the strong sweep ran every P on the same cores (P ranks
                     of C/P threads each, as on one node): E_s(P) = r(P) / r(1),
                     the rate gained or lost by trading threads for ranks

The reference is the 1-rank row of the mode, or its smallest rank count when
there is none (said in the table). Writes one PNG (three panels against ranks)
and prints a markdown table.

--model: beside each curve, tools/bench/scaling_model.py's prediction at its
settings (the model's defaults, calibrated on two H200, with the device
exchange's measured build cost; weak at the CSV's particles per rank, strong
at its particle count).

  /usr/bin/python3 -m tools.bench.scaling_plot out/scaling_*.csv --png scaling.png [--model]
"""
import argparse
import csv
import math
import sys
from collections import defaultdict

REQUIRED = ("mode", "ranks", "particles", "steps", "wall_s", "particle_steps_per_s", "halo_s")


def num(s):
    """float of a CSV cell; nan when empty or not a number."""
    try:
        return float(s)
    except (TypeError, ValueError):
        return math.nan


def mean(xs):
    xs = [x for x in xs if not math.isnan(x)]
    return sum(xs) / len(xs) if xs else math.nan


def read_rows(paths):
    rows = []
    for path in paths:
        with open(path, newline="") as f:
            r = csv.DictReader(f)
            missing = [c for c in REQUIRED if c not in (r.fieldnames or [])]
            if missing:
                sys.exit(f"scaling_plot: {path}: missing column(s) {', '.join(missing)}")
            rows += list(r)
    return rows


def summarise(rows):
    """{"mode" or "mode (settings)": [dict(ranks, particles, steps, wall, rate, halo, n) by ranks]}"""
    groups = defaultdict(list)
    for row in rows:
        groups[(row["mode"], row.get("settings") or "scene", int(row["ranks"]))].append(row)
    several = len({k[1] for k in groups}) > 1
    out = defaultdict(list)
    for (mode, settings, p), rs in sorted(groups.items()):
        out[f"{mode} ({settings})" if several else mode].append(dict(settings=settings,
            ranks=p, n=len(rs),
            particles=mean([num(r["particles"]) for r in rs]),
            steps=mean([num(r["steps"]) for r in rs]),
            wall=mean([num(r["wall_s"]) for r in rs]),
            rate=mean([num(r["particle_steps_per_s"]) for r in rs]),
            halo=mean([num(r["halo_s"]) for r in rs])))
    return out


def efficiencies(curve, pts, same_cores=False):
    """Adds eff (and ref, the reference rank count) to each point."""
    ref = pts[0]  # sorted by ranks: the 1-rank row when there is one
    mode = curve.split()[0]
    for q in pts:
        if mode == "strong" and same_cores:
            q["eff"] = q["rate"] / ref["rate"]
        elif mode == "strong":  # T = stepping time = particles * steps / rate
            t, t1 = (x["particles"] * x["steps"] / x["rate"] for x in (q, ref))
            q["eff"] = (ref["ranks"] * t1) / (q["ranks"] * t)
        else:
            q["eff"] = (q["rate"] / q["ranks"]) / (ref["rate"] / ref["ranks"])
        q["ref"] = ref["ranks"]
        q["halo_share"] = q["halo"] / q["wall"] if q["wall"] > 0 else math.nan
    return pts


def fmt(x, spec):
    return "" if math.isnan(x) else format(x, spec)


def table(summary):
    lines = ["| mode | ranks | particles | steps | wall (s) | particle-steps/s | per rank | efficiency | halo share |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for mode, pts in summary.items():
        for q in pts:
            eff = fmt(q["eff"], ".3f") + ("" if q["ref"] == 1 else f" (vs {q['ref']} ranks)")
            lines.append(f"| {mode} | {q['ranks']} | {fmt(q['particles'], '.0f')} | {fmt(q['steps'], '.0f')} | "
                         f"{fmt(q['wall'], '.3f')} | {fmt(q['rate'], '.4g')} | {fmt(q['rate'] / q['ranks'], '.4g')} | "
                         f"{eff} | {fmt(q['halo_share'], '.3f')} |")
    return "\n".join(lines)


def model_curve(curve, pts):
    """tools/bench/scaling_model.py's efficiency at the curve's rank counts and settings."""
    from tools.bench import scaling_model
    mode = curve.split()[0]
    settings = pts[0]["settings"]
    ref = pts[0]
    if mode == "weak":
        a = scaling_model.model_for(settings, per_gpu=ref["particles"] / ref["ranks"])
        return [scaling_model.weak(a, q["ranks"])[0] for q in pts]
    a = scaling_model.model_for(settings)
    return [scaling_model.strong(a, ref["particles"], q["ranks"])[0] for q in pts]


def plot(summary, png, same_cores=False, title="sphseg scaling", model=False):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    style = {"weak": ("o-", "C0", "weak $E_w = r(P)/P\\,/\\,r(1)$"),
             "strong": ("s-", "C1", "strong, same cores $r(P)/r(1)$" if same_cores else
                        "strong $E_s = T(1)/(P\\,T(P))$")}
    allp = sorted({q["ranks"] for pts in summary.values() for q in pts}) or [1]
    for k, (curve, pts) in enumerate(summary.items()):
        mode = curve.split()[0]
        mk, _, label = style.get(mode, ("^-", "C2", mode))
        col = "C%d" % k
        if curve != mode:
            label = curve
        P = [q["ranks"] for q in pts]
        ax[0].plot(P, [q["eff"] for q in pts], mk, color=col, label=label)
        if model and not (mode == "strong" and same_cores):
            ax[0].plot(P, model_curve(curve, pts), ":", color=col, lw=1.2, label=label.split(" $")[0] + ", model")
        ax[1].plot(P, [q["rate"] / q["ranks"] for q in pts], mk, color=col, label=curve)
        share = [q["halo_share"] for q in pts]
        if any(not math.isnan(s) for s in share):
            ax[2].plot(P, share, mk, color=col, label=curve)
    ax[0].axhline(1.0, color="0.5", lw=0.8, ls="--")
    ax[0].set_ylabel("parallel efficiency")
    ax[0].set_ylim(0, 1.15 * max([1.0] + [q["eff"] for pts in summary.values() for q in pts
                                          if not math.isnan(q["eff"])]))
    ax[1].set_ylabel("particle-steps/s per rank")
    ax[2].set_ylabel("halo share of wall time (halo_s / wall_s)")
    if not ax[2].lines:
        ax[2].text(0.5, 0.5, "no halo_s in the CSV", ha="center", va="center", transform=ax[2].transAxes)
    for a in ax:
        a.set_xlabel("ranks P")
        a.set_xscale("log", base=2)
        a.set_xticks(allp)
        a.set_xticklabels([str(p) for p in allp])
        a.set_xlim(allp[0] / 1.5, allp[-1] * 1.5)
        a.grid(alpha=0.3)
        if a.lines:
            a.legend(fontsize=8)
    ax[2].set_ylim(bottom=0)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=120)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", nargs="+", help="CSV file(s) written by jobs/scaling_*.sbatch")
    ap.add_argument("--png", default="scaling.png", help="chart to write (default scaling.png)")
    ap.add_argument("--strong-same-cores", action="store_true",
                    help="strong runs used the same cores at every P: E_s = r(P)/r(1)")
    ap.add_argument("--title", default="sphseg scaling", help="chart title (e.g. the machine and scene)")
    ap.add_argument("--model", action="store_true",
                    help="draw tools/bench/scaling_model.py's prediction beside each efficiency curve")
    a = ap.parse_args(argv)
    rows = read_rows(a.csv)
    if not rows:
        sys.exit("scaling_plot: no rows in " + " ".join(a.csv))
    summary = {c: efficiencies(c, pts, a.strong_same_cores) for c, pts in summarise(rows).items()}
    print(table(summary))
    plot(summary, a.png, a.strong_same_cores, a.title, a.model)
    print(f"\nwrote {a.png}")


if __name__ == "__main__":
    main()
