"""Chart of the GPU benchmark (tools/bench/bench_gpu.sh CSVs): particle-steps per
second against particle count, one line per case and precision.
Usage: python3 -m tools.bench.bench_chart OUT.png BENCH.csv [BENCH.csv ...]"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="the chart, PNG")
    ap.add_argument("files", nargs="+", help="tools/bench/bench_gpu.sh CSVs")
    a = ap.parse_args()
    out, files = a.out, a.files
    rows = [r for f in files for r in csv.DictReader(open(f))]
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    gpu = rows[0]["gpu"] if rows else ""
    for case in ("3d_block", "2d_shear"):
        for prec, ls in (("double", "-"), ("single", "--")):
            pts = sorted((int(r["particles"]), float(r["particle_steps_per_s"])) for r in rows
                         if r["case"] == case and r["precision"] == prec)
            if pts:
                ax.loglog(*zip(*pts), ls, marker="o", label="%s, %s" % (case, prec))
    for r in rows:
        if r["case"] == "2d_drum":
            ax.loglog(int(r["particles"]), float(r["particle_steps_per_s"]), "k^" if r["precision"] == "double" else "kv")
    ax.axhline(3e8, color="grey", lw=0.8, ls=":")
    ax.text(1.2e4, 3.3e8, "issue target, 3D double", fontsize=7, color="grey")
    ax.set_xlabel("particles (material + dummy)")
    ax.set_ylabel("particle-steps per second")
    ax.set_title("sphseg --backend gpu, %s" % gpu, fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main()
