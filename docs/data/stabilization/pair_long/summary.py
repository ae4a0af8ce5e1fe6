# issue 30, the pair to 40 s and the 3D drum to 36 s (README.md here): the numbers the docs quote, from the
# files here. python3 docs/data/stabilization/pair_long/summary.py (from the repository root)
import csv
import os
import re
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROW = re.compile(r"^\s+([\d.]+)\s+([\d.]+)°\s+[\d.]+ dr\s+([\d.]+) cm/s\s+(-?[\d.]+)\s+([\d.]+)-([\d.]+)\s+([\d.]+) cm/s")


def ana(tag):
    """t -> (angle, mid-chord speed, segregation index, top grains) of drum_analysis's first table"""
    out = {}
    for line in open(os.path.join(HERE, tag + ".ana")):
        m = ROW.match(line)
        if not m: continue
        if line.startswith("axial") or float(m.group(1)) in out: break
        out[float(m.group(1))] = tuple(float(m.group(k)) for k in (2, 3, 4, 7))
    return out


def diag(tag):
    rows = list(csv.DictReader(open(os.path.join(HERE, tag + ".diag.csv"))))
    c = [(float(r["C_min"]), float(r["C_max"])) for r in rows]
    drift = max(abs(float(r["small_volume_drift"])) for r in rows)
    return len(rows), float(rows[-1]["time"]), min(a for a, _ in c), max(b for _, b in c), drift


def wall(tag):
    v = [float(l.split()[1]) for l in open(os.path.join(HERE, tag + ".txt")) if not l.startswith("#")]
    return min(v[1:]), max(v[1:])


def mean(a, ts, k):
    return float(np.mean([a[t][k] for t in ts]))


print("2D drums, the scenes as they ship (E 10 kPa, chi 0.2): means over t = 20, 21, ..., 40 s")
late = [float(t) for t in range(20, 41)]
for drum in ("EV", "EN"):
    a, b = ana(drum + "05k"), ana(drum + "025k")
    for k, name in ((1, "mid-chord speed (cm/s)"), (3, "top grains (cm/s)"), (0, "angle (deg)")):
        u, v = mean(a, late, k), mean(b, late, k)
        print(f"  {drum} {name:24s} dr 0.5 mm {u:7.3f}   dr 0.25 mm {v:7.3f}   change {100 * (v / u - 1):+.1f} %")
    for t in (20.0, 40.0):
        print(f"  {drum} segregation index at {t:.0f} s: dr 0.5 mm {a[t][2]:.4f}, dr 0.25 mm {b[t][2]:.4f} "
              f"({100 * (b[t][2] / a[t][2] - 1):+.1f} %)")
    for tag in (drum + "05k", drum + "025k"):
        n, tend, cmin, cmax, drift = diag(tag)
        lo, hi = wall(tag)
        print(f"  {tag}: {n} diagnostics rows to {tend:g} s, C in [{cmin:.4f}, {cmax:.4f}], |drift| max {drift:.2e}; "
              f"deepest reach past the wall {lo:.3f} to {hi:.3f} mm")
print("3D R35 drum with the pair (E 10 kPa, chi 0.2)")
n, tend, cmin, cmax, drift = diag("r35p")
lo, hi = wall("r35p")
print(f"  r35p (dr 1 mm): {n} diagnostics rows to {tend:g} s, C in [{cmin:.4f}, {cmax:.4f}], |drift| max {drift:.2e}; "
      f"deepest reach past the wall {lo:.3f} to {hi:.3f} mm")
a = ana("r35p")
u = [a[t][1] for t in sorted(a) if t >= 3]
print(f"  mid-chord speed, t = 3-36 s: {min(u):.2f}-{max(u):.2f} cm/s; segregation index at 36 s {a[36.0][2]:.4f}")
SLAB = re.compile(r"^\s+mid-length slab\s+[\d.]+°\s+([\d.]+) cm/s")


def slab(tag):
    """t -> the mid-length slab's largest speed on its mid-chord (the axial analysis of a 3D drum)"""
    out, t = {}, None
    for line in open(os.path.join(HERE, tag + ".ana")):
        m = re.match(r"^t = ([\d.]+) s", line)
        if m: t = float(m.group(1))
        m = SLAB.match(line)
        if m and t is not None: out[t] = float(m.group(1))
    return out


print("3D R35 drum against the 2D EV drum at the same dr: means of t = 3, 4, 5 s, cm/s")
T = (3.0, 4.0, 5.0)
rows = [(1.4, "r35p14", "EV14c"), (1.0, "r35q10", "EV10c"), (0.7, "r35q07", "EV07c"), (0.5, None, "EV05k"),
        (0.25, None, "EV025k")]
prev = None
for dr, t3, t2 in rows:
    d2 = mean(ana(t2), T, 1) if os.path.exists(os.path.join(HERE, t2 + ".ana")) else float("nan")
    if t3:
        sl = float(np.mean([slab(t3)[t] for t in T]))
        wb = mean(ana(t3), T, 1)
        line = f"  dr {dr:4} mm: 3D slab {sl:5.2f}, whole bed {wb:5.2f}; 2D {d2:5.2f}; slab / 2D {sl / d2:.3f}"
        if prev: line += f"; step from the last dr: slab {100 * (sl / prev[0] - 1):+.1f} %, whole bed " \
                         f"{100 * (wb / prev[1] - 1):+.1f} %, 2D {100 * (d2 / prev[2] - 1):+.1f} %"
        prev = (sl, wb, d2)
    else:
        line = f"  dr {dr:4} mm: 2D {d2:5.2f}; step from the last dr, 2D {100 * (d2 / prev[2] - 1):+.1f} %"
        prev = (prev[0], prev[1], d2)
    print(line)
ref = mean(ana("EV025k"), T, 1)
print(f"  the 3D slab at dr 1 mm against the 2D drum at dr 0.25 mm: "
      f"{100 * (float(np.mean([slab('r35q10')[t] for t in T])) / ref - 1):+.1f} %")

if len(sys.argv) > 2 and sys.argv[1] == "--png":  # the refinement chart: speed against dr
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    d3 = [(dr, float(np.mean([slab(t3)[t] for t in T])), mean(ana(t3), T, 1)) for dr, t3, _ in rows if t3]
    d2 = [(dr, mean(ana(t2), T, 1)) for dr, _, t2 in rows]
    ax.plot([r[0] for r in d2], [r[1] for r in d2], "o-", label="2D EV drum")
    ax.plot([r[0] for r in d3], [r[1] for r in d3], "s-", label="3D R35 drum, mid-length slab")
    ax.plot([r[0] for r in d3], [r[2] for r in d3], "^--", label="3D R35 drum, whole bed projected")
    ax.axhline(8.04, color="k", ls=":", label="FE μ(I), well mixed (steady)")
    ax.set_xscale("log")
    ax.set_xticks([0.25, 0.5, 0.7, 1.0, 1.4])
    ax.set_xticklabels(["0.25", "0.5", "0.7", "1.0", "1.4"])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.invert_xaxis()
    ax.set_xlabel("dr (mm)")
    ax.set_ylabel("largest speed on the mid-chord (cm/s)")
    ax.set_title("the pair (E 10 kPa, χ 0.2), means of t = 3, 4, 5 s", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=130)
    print("wrote", sys.argv[2])
