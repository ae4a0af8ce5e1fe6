#!/usr/bin/env python3
"""The 3D drum without end walls (issue 57): a drum periodic along its axis against the 2D drum at the same dr.

  python3 -m tools.studies.periodic_drum commands [--dr 0.0014 0.001 0.0007] [--sphseg BIN] [--ensemble N]
  python3 -m tools.studies.periodic_drum table FILE... [--csv docs/data/drum/periodic_3d.csv]
  python3 -m tools.studies.periodic_drum chart [--csv ...] [--png docs/data/drum/periodic_3d.png]
  python3 -m tools.studies.periodic_drum axial OUT... [--from 2.5] [--flowing 0.02]
  python3 -m tools.studies.periodic_drum depth PROFILES... [--dr DR]
  python3 -m tools.studies.periodic_drum surface [--csv docs/data/drum/surface/surface_shift.csv] [--png PNG]

commands: the runs, one line each: the 2D EV scene (inputs/drum_2d_EV.yml) and the
same drum as a 3D container (its cylinder turning, a fill region to
H = (2 fill - 1) R, Geometry:dim 3, Geometry:periodic z over a depth of 24 dr,
no end walls), both at E 10 kPa, chi 0.2, with the scene's flow, to 5 s, each
followed by its drum_analysis (`--times 1 2 3 4 5`), and the walled R35 3D
drum (inputs/drum_3d.yml, length 0.07 m) for the end walls' effect. The 2D
container drum gives the built-in 2D drum's bits (tests/test_own_scene.sh
checks the particles; a 300-step comparison is in the CHANGELOG). Each line
writes its run's log to OUT.log and echoes the '=== LABEL: rc N' header that
table reads, so `commands ... | bash > FILE` makes table's input.
--ensemble N: the 2D drum alone, N runs a spacing whose step bound differs by
1e-4 of chi (Run:cfl_flow 0.2, 0.2001, ...), a perturbation far under the
discretisation's after which the runs part (the flow is chaotic): their spread
is what the means of one run carry. --profiles: each analysis also writes the
mid-chord profiles to OUT_profiles.csv (drum_analysis --profiles; a 3D run's
over its whole depth, --slab 24 dr), which depth reads.
table: each FILE holds '=== LABEL: rc ...' headers followed by that run's
drum_analysis output; the CSV gets, per run, the means over t = 3, 4, 5 s of
the mid-chord speed and the segregation index of the whole bed (projected along
z) and, in 3D, of the mid-length slab. Ensemble runs ('2D dr X run K') go to
the CSV's _spread file instead: per spacing the runs' count, and the mean and
sample standard deviation of the same means.
chart: speed and index against dr, 2D, periodic 3D and walled 3D, and, where
the spread file has a spacing, the 2D ensemble's mean with +-1 standard
deviation of one run.
axial: for each 3D run OUT, per snapshot from t = 2.5 s, the RMS of the axial
velocity u_z over the flowing material (in-plane speed above 2 cm/s) against
their in-plane RMS speed: how far the periodic drum's flow leaves the plane.
depth: for each mid-chord profile file (drum_analysis --profiles) and each time in
it, where along the depth the runs differ: the speed and the shear rate
interpolated from the particles at 1, 3, 6, 9 and 12 dr below the surface, the
flowing layer's depth (where the speed is least over the upper half of the
mid-chord: the turning point above the bed's rotation), and over
the layer where the speed is above 0.3 of the surface's the ratio of the
particles' shear rate to the profile's own |d speed / d depth| (1 where the
particles' shear rate carries no noise the mean flow lacks). --dr: the spacing
in the depths' unit (default: read from the file name, "_0.0007").
surface: the runs of the shifting's free-surface study (docs/drum3d.md): per
variant, spacing and threshold, the mean mid-chord speed and segregation index
over t = 2-4 s in 2D and in the periodic slab, and the slab against 2D; --png
draws the speed against the threshold and the speed along the depth (the
--profiles files beside the CSV).
"""
import argparse
import csv
import os
import re
import sys

import numpy as np

from tools import ROOT
from tools.studies import batch

ROW = re.compile(r"^\s+([\d.]+)\s+([\d.]+)°\s+[\d.]+ dr\s+([\d.]+) cm/s\s+(-?[\d.]+)\s+([\d.]+)-([\d.]+)\s+([\d.]+) cm/s")
SLAB = re.compile(r"^\s+mid-length slab\s+([\d.]+)°\s+([\d.]+) cm/s\s+(-?[\d.]+)")
KEYS = "-P Material:E=1e4 -P Run:cfl_flow=0.2 -P Run:t_end=5 -P Output:dt=1"
T = (3.0, 4.0, 5.0)
CSV = os.path.join(ROOT, "docs", "data", "drum", "periodic_3d.csv")


def _line(label, cmd, out, prof=""):
    """One run: sphseg's output to OUT.log, the header table reads, the analysis."""
    return (f"{cmd} > {out}.log 2>&1; echo '=== {label}: rc '$?; "
            f"python3 -m tools.analysis.drum_analysis {out} --times 1 2 3 4 5{prof}")


def _prof(a, out, slab=None):
    """drum_analysis's --profiles (and a 3D run's --slab) where commands has --profiles."""
    if not a.profiles:
        return ""
    return f" --profiles {out}_profiles.csv" + (f" --slab {slab:.6g}" if slab else "")


def commands(a):
    H = (2 * 0.42 - 1) * 0.035
    walls = "Container:walls=[{name: drum, shape: cylinder, centre: [0, 0], radius: 0.035, motion: turning, rpm: 5, " \
            "direction: clockwise}]"
    reg = "Container:regions=[{shape: fill, level: %.4g, C: 0.5}]" % H
    print("mkdir -p out/periodic")
    for dr in a.dr:
        if a.ensemble:
            for k in range(a.ensemble):
                out = "out/periodic/2d_%g_run%d" % (dr, k)
                keys = KEYS.replace("Run:cfl_flow=0.2", "Run:cfl_flow=%.4f" % (0.2 + 1e-4 * k))
                print(_line("2D dr %g run %d" % (dr, k),
                            f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {keys}", out))
            continue
        out = "out/periodic/2d_%g" % dr
        print(_line("2D dr %g" % dr, f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {KEYS}", out,
                    _prof(a, out)))
        out = "out/periodic/3d_%g" % dr
        print(_line("3D dr %g" % dr, f"{a.sphseg} inputs/drum_2d_EV.yml -o {out} -P Geometry:dr={dr} {KEYS} "
                    f"-P Geometry:type=container -P Geometry:dim=3 -P Geometry:depth={24 * dr:.6g} "
                    f"-P Geometry:periodic=z -P '{walls}' -P '{reg}'", out, _prof(a, out, 24 * dr)))
    if not a.ensemble:
        out = "out/periodic/walled_0.0014"
        print(_line("walled 3D dr 0.0014", f"{a.sphseg} inputs/drum_3d.yml -o {out} -P Geometry:dr=0.0014 "
                    f"-P Geometry:length=0.07 {KEYS}", out))


def parse(text):
    runs, cur = {}, None
    for line in text.splitlines():
        m = re.match(r"=== (.*?): rc", line)
        if m:
            cur = m.group(1)
            runs[cur] = {"t": {}, "slab": [], "axial": False}
            continue
        if cur is None:
            continue
        if line.startswith("axial"):
            runs[cur]["axial"] = True
        m = ROW.match(line)
        if m and not runs[cur]["axial"] and float(m.group(1)) not in runs[cur]["t"]:
            runs[cur]["t"][float(m.group(1))] = (float(m.group(3)), float(m.group(4)))
        m = SLAB.match(line)
        if m:
            runs[cur]["slab"].append((float(m.group(2)), float(m.group(3))))
    return runs


def spread_path(path):
    return os.path.splitext(path)[0] + "_spread.csv"


def write_csv(path, rows):
    """rows (dicts of one set of keys) to path, floats to 4 digits."""
    batch.write_csv(path, list(rows[0]), [["%.4g" % v if isinstance(v, float) else v for v in r.values()]
                                          for r in rows])
    print("wrote %s (%d rows)" % (path, len(rows)))


def table(a):
    runs = {}
    for f in a.files:
        runs.update(parse(open(f).read()))
    rows, members = [], {}
    for label, r in sorted(runs.items()):
        m = re.match(r"(walled )?(\dD) dr ([\d.]+)( run \d+)?$", label)
        if not m or not all(t in r["t"] for t in T):
            print("skipped %s: not every time of %s" % (label, T), file=sys.stderr)
            continue
        speed, index = np.mean([r["t"][t][0] for t in T]), np.mean([r["t"][t][1] for t in T])
        if m.group(4):  # an ensemble member
            members.setdefault(float(m.group(3)) * 1e3, []).append((speed, index))
            continue
        kind = "walled 3D" if m.group(1) else ("periodic 3D" if m.group(2) == "3D" else "2D")
        slab = r["slab"][2:5] if len(r["slab"]) >= 5 else []
        rows.append({"kind": kind, "dr_mm": float(m.group(3)) * 1e3, "speed_cm_s": speed, "index": index,
                     "slab_speed_cm_s": np.mean([s[0] for s in slab]) if slab else "",
                     "slab_index": np.mean([s[1] for s in slab]) if slab else ""})
    if not rows and not members:
        sys.exit("no run with every time of %s in %s" % (T, " ".join(a.files)))
    if rows:
        write_csv(a.csv, rows)
    if members:
        spread = []
        for dr, v in sorted(members.items()):
            v = np.array(v)
            if len(v) < 2:
                sys.exit("dr %g mm: one ensemble run, no spread" % dr)
            spread.append({"kind": "2D", "dr_mm": dr, "runs": len(v), "speed_mean_cm_s": v[:, 0].mean(),
                           "speed_sd_cm_s": v[:, 0].std(ddof=1), "index_mean": v[:, 1].mean(),
                           "index_sd": v[:, 1].std(ddof=1)})
        write_csv(spread_path(a.csv), spread)


def chart(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = list(csv.DictReader(open(a.csv)))
    sd = {float(r["dr_mm"]): r for r in csv.DictReader(open(spread_path(a.csv)))} \
        if os.path.exists(spread_path(a.csv)) else {}
    fig, ax = plt.subplots(1, 2, figsize=(10, 5))
    for kind, col, mk in (("2D", "speed_cm_s", "o-"), ("periodic 3D", "slab_speed_cm_s", "s-"),
                          ("walled 3D", "slab_speed_cm_s", "^")):
        rs = sorted((r for r in rows if r["kind"] == kind), key=lambda r: float(r["dr_mm"]))
        if not rs:
            continue
        dr = [float(r["dr_mm"]) for r in rs]
        lab = kind + (" (mid-length slab)" if kind != "2D" else ", one run")
        ax[0].plot(dr, [float(r[col]) for r in rs], mk, label=lab)
        ax[1].plot(dr, [float(r[col.replace("speed_cm_s", "index")]) for r in rs], mk, label=lab)
    if sd:  # the 2D ensembles: their means with +-1 sample SD of one run, at every spacing the spread file has
        dr = sorted(sd)
        for k, (val, err) in enumerate((("speed_mean_cm_s", "speed_sd_cm_s"), ("index_mean", "index_sd"))):
            ax[k].errorbar(dr, [float(sd[d][val]) for d in dr], yerr=[float(sd[d][err]) for d in dr], fmt="D",
                           ms=4, color="C3", capsize=4, label="2D, mean of an ensemble +- one run's SD (%d-%d runs)"
                           % (min(int(sd[d]["runs"]) for d in dr), max(int(sd[d]["runs"]) for d in dr)))
    for k, lab in enumerate(("mid-chord surface speed, cm/s", "segregation index")):
        ax[k].set_xlabel("dr, mm")
        ax[k].set_ylabel(lab + "\n(means of t = 3, 4, 5 s)")
        ax[k].invert_xaxis()
        ax[k].grid(alpha=0.3)
    fig.suptitle("EV drum, E 10 kPa, chi 0.2, the scenes' flow: 2D against 3D without end walls "
                 "(machines: docs/validation.md)", fontsize=9)
    fig.legend(*ax[0].get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8)
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


def axial(a):
    from tools.analysis import snap
    for out in a.outs:
        for path in snap.list_snapshots(out):
            s = snap.read_snapshot(path)
            u = np.asarray(s["Velocities"])
            if s["Time"] < a.t_from or u.ndim < 2 or u.shape[1] < 3:
                continue
            u = u[np.asarray(s["Kind"]) == snap.MATERIAL]
            sp = np.hypot(u[:, 0], u[:, 1])
            f = sp > a.flowing
            w, v = np.sqrt(np.mean(u[f, 2] ** 2)), np.sqrt(np.mean(sp[f] ** 2))
            print("%s t = %.2f s: %d flowing of %d, RMS u_z %.3g cm/s, in-plane %.3g cm/s, ratio %.3g"
                  % (out, s["Time"], f.sum(), len(u), 100 * w, 100 * v, w / v))


def depth_rows(path, dr):
    """Per time of a --profiles file: (t, surface speed, speeds and shear rates at DEPTHS dr, the layer's
    depth (m), the particles' shear rate over the profile's own)."""
    R = 0.035  # the EV drum's radius: d_mc is in units of it
    with open(path) as f:
        rows = [r for r in csv.DictReader(f)]
    out = []
    for t in sorted({float(r["t"]) for r in rows}):
        rr = [r for r in rows if float(r["t"]) == t]
        d = np.array([float(r["d_mc"]) for r in rr]) * R
        s = np.array([float(r["speed"]) for r in rr])
        g = np.array([float(r["gdot"]) for r in rr])
        ok = np.isfinite(s) & np.isfinite(g)
        d, s, g = d[ok], s[ok], g[ok]
        k0 = int(np.argmin(s[: len(s) // 2 + 5]))  # the least speed over the upper half: the layer's foot
        near = [int(np.argmin(np.abs(d - q * dr))) for q in DEPTHS]
        lay = (np.arange(len(s)) < k0) & (s > 0.3 * s.max())
        ratio = g[lay].mean() / np.abs(np.gradient(s, d))[lay].mean()
        out.append((t, s.max(), s[near], g[near], d[k0], ratio))
    return out


DEPTHS = (1, 3, 6, 9, 12)


def depth(a):
    head = " ".join("%5d" % q for q in DEPTHS)
    print("%-34s %5s %6s | speed (cm/s) at dr below: %s | shear rate (1/s): %s | layer (mm) | gdot / du/dn" % (
        "profiles", "t (s)", "u_max", head, head))
    for path in a.files:
        m = re.search(r"_(0\.\d+)", os.path.basename(path))
        dr = a.dr or (float(m.group(1)) if m else None)
        if not dr:
            sys.exit("depth: no --dr and none in the file name %s" % path)
        for t, top, sp, gd, lay, ratio in depth_rows(path, dr):
            print("%-34s %5.1f %6.2f | %s | %s | %5.2f | %.3f" % (
                os.path.basename(path)[-34:], t, 100 * top, " ".join("%5.2f" % (100 * v) for v in sp),
                " ".join("%5.1f" % v for v in gd), 1e3 * lay, ratio))


SURFACE = os.path.join(ROOT, "docs", "data", "drum", "surface", "surface_shift.csv")


def surface_runs(path):
    """{(variant, dim, dr, frac): {t: (speed, index)}} for t = 2-4 s."""
    runs = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            if 2 <= float(r["t_s"]) <= 4:
                k = (r["variant"], r["dim"], float(r["dr_m"]), round(float(r["threshold_frac"]), 4))
                runs.setdefault(k, {})[float(r["t_s"])] = (float(r["speed_cm_s"]), float(r["seg_index"]))
    return runs


def _mean(run, ts):
    return np.mean([run[t][0] for t in ts]), np.mean([run[t][1] for t in ts])


def surface(a):
    runs = surface_runs(a.csv)
    print("%-9s %6s %5s %5s | %-8s | %-15s | %-15s | slab / 2D: speed, index" % (
        "variant", "dr", "f 2D", "f 3D", "t (s)", "2D speed, index", "slab"))
    for (var, dim, dr, f), run in sorted(runs.items(), key=lambda kv: (kv[0][0], -kv[0][2], kv[0][3], kv[0][1])):
        pair = [(k, v) for k, v in runs.items() if k[:3] == (var, "3D", dr)] if dim == "2D" else []
        if dim == "2D" and var == "frac":
            pair = []  # the threshold varied in 2D alone
        if dim == "3D" and any(k[:3] == (var, "2D", dr) for k in runs) and var != "frac":
            continue  # printed with its 2D run
        if not pair:
            sp, ix = _mean(run, sorted(run))
            two = "%.2f, %.4f" % (sp, ix)
            print("%-9s %6g %5s %5s | %-8s | %-15s | %-15s |" % (
                var, dr, "%.3f" % f if dim == "2D" else "", "%.3f" % f if dim == "3D" else "",
                ",".join("%g" % t for t in sorted(run)), two if dim == "2D" else "", two if dim == "3D" else ""))
        for k, r3 in pair:
            ts = sorted(set(run) & set(r3))
            (sp, ix), (s3, i3) = _mean(run, ts), _mean(r3, ts)
            print("%-9s %6g %5.3f %5.3f | %-8s | %.2f, %.4f    | %.2f, %.4f    | %+.1f %%, %+.1f %%" % (
                var, dr, f, k[3], ",".join("%g" % t for t in ts), sp, ix, s3, i3, 100 * (s3 / sp - 1),
                100 * (i3 / ix - 1)))
    m = {k: _mean(v, sorted(v)) for k, v in runs.items()}
    if not a.png:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.4))
    for dim, mk in (("2D", "o"), ("3D", "s")):
        for dr, col in ((0.0007, "C0"), (0.0005, "C1")):
            pts = sorted((k[3], v[0]) for k, v in m.items() if k[1] == dim and k[2] == dr and k[0] in ("base", "frac"))
            if pts:
                ax.plot(*zip(*pts), mk + ("-" if dim == "2D" else "--"), color=col,
                        label="%s%s, dr %g mm" % (dim, "" if dim == "2D" else " slab", 1e3 * dr))
    for dim, mk in (("2D", "o"), ("3D", "s")):  # the tangential rule at its thresholds, open; fade (none) as a line
        pts = sorted((k[3], v[0]) for k, v in m.items() if k[1] == dim and k[2] == 0.0007 and k[0].startswith("tang"))
        if pts:
            ax.plot(*zip(*pts), mk, mfc="none", color="C2", label="%s%s, dr 0.7 mm, tangential" % (
                dim, "" if dim == "2D" else " slab"))
        fd = [v[0] for k, v in m.items() if k[1] == dim and k[2] == 0.0007 and k[0] == "fade"]
        if fd:
            ax.axhline(fd[0], color="C3", lw=0.9, ls="-" if dim == "2D" else "--",
                       label="%s%s, dr 0.7 mm, fade (no threshold)" % (dim, "" if dim == "2D" else " slab"))
    ax.axvline(0.75, color="0.7", lw=0.8)
    ax.axvline(5 / 6, color="0.7", lw=0.8)
    ax.text(0.752, ax.get_ylim()[0], " d - 1/2 in 2D", rotation=90, va="bottom", fontsize=8, color="0.4")
    ax.text(0.835, ax.get_ylim()[0], " d - 1/2 in 3D", rotation=90, va="bottom", fontsize=8, color="0.4")
    ax.set_xlabel("shifting's free-surface threshold: div r < f d")
    ax.set_ylabel("mid-chord surface speed, t = 2-4 s (cm/s)")
    ax.legend(fontsize=7)
    ax.set_title("(a) the surface speed against the threshold", fontsize=10)
    here = os.path.dirname(a.csv)
    for name, lab, st in (("2d_0.0005", "2D, dr 0.5 mm", "-"), ("3d_0.0005", "3D slab, dr 0.5 mm", "--"),
                          ("3d_0.0007_frac075", "3D slab, dr 0.7 mm, f 0.75", ":")):
        path = os.path.join(here, name + "_profiles.csv")
        if not os.path.exists(path):
            continue
        dr = float(re.search(r"_(0\.\d+)", name).group(1))
        with open(path) as f:
            rows = [r for r in csv.DictReader(f) if 3 <= float(r["t"]) <= 4]
        d = sorted({float(r["d_mc"]) for r in rows})
        sp = [np.nanmean([float(r["speed"]) for r in rows if float(r["d_mc"]) == q]) for q in d]
        dd = np.array(d) * 0.035 / dr
        keep = dd <= 16
        bx.plot(100 * np.array(sp)[keep], dd[keep], st, label=lab)
    bx.invert_yaxis()
    bx.set_xlabel("speed on the mid-chord, t = 3-4 s (cm/s)")
    bx.set_ylabel("depth below the surface (dr)")
    bx.legend(fontsize=8)
    bx.set_title("(b) where the slab and 2D part", fontsize=10)
    fig.suptitle("EV drum, E 10 kPa, chi 0.2, the scenes' flow: the shifting's free-surface rule", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    c = sub.add_parser("commands")
    c.add_argument("--dr", type=float, nargs="+", default=[0.0014, 0.001, 0.0007])
    c.add_argument("--sphseg", default="build/sphseg")
    c.add_argument("--ensemble", type=int, default=0, metavar="N",
                   help="the 2D drum alone, N runs a spacing with chi 0.2 + 1e-4 k (k < N)")
    c.add_argument("--profiles", action="store_true", help="each analysis also writes OUT_profiles.csv (for depth)")
    t = sub.add_parser("table")
    t.add_argument("files", nargs="+")
    t.add_argument("--csv", default=CSV)
    h = sub.add_parser("chart")
    h.add_argument("--csv", default=CSV)
    h.add_argument("--png", default=os.path.join(ROOT, "docs", "data", "drum", "periodic_3d.png"))
    x = sub.add_parser("axial")
    x.add_argument("outs", nargs="+")
    x.add_argument("--from", dest="t_from", type=float, default=2.5, help="first snapshot time read (s)")
    x.add_argument("--flowing", type=float, default=0.02, help="in-plane speed of the flowing material (m/s)")
    d = sub.add_parser("depth")
    d.add_argument("files", nargs="+", help="drum_analysis --profiles CSVs")
    d.add_argument("--dr", type=float, default=None, help="the runs' spacing (m; default from the file name)")
    u = sub.add_parser("surface")
    u.add_argument("--csv", default=SURFACE)
    u.add_argument("--png", default=None)
    a = ap.parse_args()
    {"commands": commands, "table": table, "chart": chart, "axial": axial, "depth": depth, "surface": surface}[a.what](a)


if __name__ == "__main__":
    main()
