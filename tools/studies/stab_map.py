#!/usr/bin/env python3
"""Where the drums' stabilisation fails (issue 30): the 2D EV drum over the
elastic modulus E and the time-step factor chi_CFL, at three resolutions.

  python3 -m tools.studies.stab_map run --sphseg build/sphseg --out DIR [--set riemann,fine,gpu,monaghan,pair,pair_gpu] [--jobs 2] [--backend gpu]
  python3 -m tools.studies.stab_map report --out DIR [--docs docs/data/granular] [--table FILE]

Cases: inputs/drum_2d_EV.yml to t = 1.5 s (the bed starts to avalanche at
about 0.75 s), snapshots every 0.25 s.
  riemann   dr 1.4 mm, E = 10 kPa, 0.1 MPa, 1 MPa, chi_CFL 0.2 ... 2.0
  fine      dr 0.7 mm, E = 10 kPa, the same chi_CFL
  gpu       dr 0.7 and 0.35 mm, E = 10 kPa, 0.1 MPa, 1 MPa, the same chi_CFL
            (the finer and stiffer corners, for --backend gpu)
  monaghan  dr 1.4 mm, E = 10 kPa, 0.1 MPa, monaghan with alpha = 0.1 sqrt(1e7/E)
            (the alpha sqrt(E) rule), for comparison
  pair      dr 1.4 mm, E = 10 kPa, 0.1 MPa, 1 MPa, the drum scenes' setting since
            issue 30's last step: riemann with Flow:gradient_correction on and
            Flow:shifting fickian (stabilisation "pair")
  pair_gpu  the pair at dr 0.7 and 0.35 mm, E = 10 kPa, 0.1 MPa, 1 MPa (for --backend gpu)
Every case names its stabilisation's keys in full (riemann: the correction and
the shifting off; pair: both on), so a case means the same whatever the scene
sets.
Each run: ran or not, and how it failed (the error line of its log: a
particle moved more than h in one step, left its container, ...; or the
wall-clock limit). Accuracy of a run that ran: the rms difference of its
mid-chord speed profile at 1.5 s from the chi_CFL = 0.2 run of the same E,
dr and stabilisation, over that run's surface speed (0.2 is what the drums
use; 0.1 against 0.2 differed by 1 % under monaghan, docs/granular.md).
The chart (report): chi_CFL against E, one panel per (stabilisation, dr),
dots coloured by that error, crosses where a run failed, written as
stability_map_STABS.png (STABS: the stabilisations of the rows, joined by _).
"""
import math
import os
import re

from tools import ROOT
from tools.analysis import drum_analysis, snap
from tools.studies import batch

SCENE = os.path.join(ROOT, "inputs", "drum_2d_EV.yml")
CFLS = (0.2, 0.4, 0.7, 1.0, 1.3, 1.6, 2.0)
REF_CFL = 0.2
SETS = ("riemann", "fine", "gpu", "monaghan", "pair", "pair_gpu")
PAIR = {"Flow:gradient_correction": "on", "Flow:shifting": "fickian"}
LABEL = {"pair": "riemann + correction + shifting"}
PLAIN = {"Flow:gradient_correction": "off", "Flow:shifting": "off"}


def case(stab, dr, E, cfl):
    name = "%s_dr%g_E%g_c%g" % (stab, dr * 1e3, E, cfl)
    over = {"Geometry:dr": dr, "Material:E": E, "Run:cfl_flow": cfl, "Run:t_end": 1.5, "Output:dt": 0.25,
            "Run:progress_s": 1e9, "Flow:stabilization": "riemann" if stab == "pair" else stab}
    over.update(PAIR if stab == "pair" else PLAIN)
    if stab == "monaghan":
        over["Flow:alpha_av"] = round(0.1 * math.sqrt(1e7 / E), 4)
    return batch.Case(name, SCENE, over, stab=stab, dr=dr, E=E, cfl=cfl)


def cases(which):
    c = []
    if which in ("full", "riemann"):
        c += [case("riemann", 0.0014, E, x) for E in (1e4, 1e5, 1e6) for x in CFLS]
    if which in ("full", "fine"):
        c += [case("riemann", 0.0007, 1e4, x) for x in CFLS]
    if which in ("full", "gpu"):
        c += [case("riemann", dr, E, x) for dr in (0.0007, 0.00035) for E in (1e4, 1e5, 1e6) for x in CFLS
              if not (dr == 0.0007 and E == 1e4 and which == "full")]  # "full" has that row from "fine"
    if which in ("full", "monaghan"):
        c += [case("monaghan", 0.0014, E, x) for E in (1e4, 1e5) for x in CFLS]
    if which in ("full", "pair"):
        c += [case("pair", 0.0014, E, x) for E in (1e4, 1e5, 1e6) for x in CFLS]
    if which in ("full", "pair_gpu"):
        c += [case("pair", dr, E, x) for dr in (0.0007, 0.00035) for E in (1e4, 1e5, 1e6) for x in CFLS]
    return c


def failure(text):
    """How a run that did not finish failed, from its log."""
    for pat, what in ((r"moved [0-9.e+-]+ m > h", "moved > h in a step"),
                      (r"left its container", "left the container"),
                      (r"not finite|NaN|nan", "not finite")):
        if re.search(pat, text):
            return what
    last = text.strip().splitlines()[-1:] or [""]
    return last[0][:80]


def on_done(args, c, rec):
    pass  # everything is read at report time from the run folders


def reduce_run(out, name, row):
    """Ran: angle, surface speed, the last snapshot's Drum; failed: how."""
    text = open(os.path.join(out, name + ".log")).read()
    if str(row["rc"]) != "0":
        return {"ok": False, "how": "not finished (wall-clock limit)" if row["rc"] == "timeout" else failure(text)}
    o = os.path.join(out, name)
    d = drum_analysis.Drum(snap.list_snapshots(o)[-1], drum_analysis.used_params(o))
    return {"ok": True, "drum": d, "angle": d.angle, "speed": d.surface_speed()}


def read_or_rebuild(out):
    """out/runs.csv, or, for a batch stopped before it wrote one, the rows
    rebuilt from the cases' logs (a log without "done:" or an error line is a
    run that was stopped: "stopped")."""
    if os.path.exists(os.path.join(out, "runs.csv")):
        return batch.read_runs(out)
    meta = {c.name: c.meta for w in SETS for c in cases(w)}
    rows = {}
    for n, m in meta.items():
        log = os.path.join(out, n + ".log")
        if not os.path.exists(log):
            continue
        text = open(log).read()
        done = batch.DONE.search(text)
        rc = "0" if done else ("3" if "error:" in text else "timeout")
        rows[n] = dict(m, name=n, rc=rc, steps=done.group(1) if done else "",
                       wall_s=done.group(2) if done else "")
    return rows


def profile_error(d, ref):
    import numpy as np
    dm, pts = ref.midchord()
    ur, u = ref.interp(pts, ref.speed), d.interp(pts, d.speed)
    ok = np.isfinite(ur) & np.isfinite(u)
    return float(np.sqrt(np.mean((u[ok] - ur[ok]) ** 2)) / np.nanmax(ur))


ROW_KEYS = ("stab", "dr", "E", "cfl", "ok", "how", "angle", "speed", "err", "steps", "wall_s")


def reduce_all(outs):
    """Every run of the folders outs, reduced (reduce_run) with its profile error against the chi 0.2 run
    of its (stabilisation, dr, E), as dicts of ROW_KEYS."""
    runs, where = {}, {}
    for out in outs:
        for n, r in read_or_rebuild(out).items():
            runs[n], where[n] = r, out
    R = {n: dict(reduce_run(where[n], n, r), **{k: r[k] for k in ("stab", "dr", "E", "cfl", "wall_s", "steps")})
         for n, r in runs.items()}
    for n, r in R.items():
        ref = "%s_dr%g_E%g_c%g" % (r["stab"], float(r["dr"]) * 1e3, float(r["E"]), REF_CFL)
        if r["ok"] and ref in R and R[ref]["ok"]:
            r["err"] = profile_error(r["drum"], R[ref]["drum"])
    return {n: {k: r[k] for k in ROW_KEYS if k in r} for n, r in R.items()}


def read_rows(path):
    """The rows a report wrote (stability_map_rows.csv), typed as reduce_all gives them."""
    import csv
    R = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            r = {k: v for k, v in r.items() if v != "" or k in ("steps", "wall_s")}  # how, angle, err: absent
            r["ok"] = r["ok"] == "True"
            for k in ("angle", "speed", "err"):
                if k in r:
                    r[k] = float(r[k])
            R[r.pop("name")] = r
    return R


def cmd_report(a):
    """The table, stability_map_rows.csv (the reduced runs) and the chart into --docs. --out: the run
    folders, or one stability_map_rows.csv of an earlier report (the chart redrawn without the runs)."""
    import csv
    if len(a.out) == 1 and a.out[0].endswith(".csv"):
        R = read_rows(a.out[0])
    else:
        R = reduce_all(a.out)
        os.makedirs(a.docs, exist_ok=True)
        with open(os.path.join(a.docs, "stability_map_rows.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(("name",) + ROW_KEYS)
            for n in sorted(R):
                w.writerow([n] + [R[n].get(k, "") for k in ROW_KEYS])
    panels = sorted({(r["stab"], float(r["dr"])) for r in R.values()}, key=lambda p: (p[0] != "riemann", -p[1]))
    lines = ["| stabilisation | dr (mm) | E (Pa) | chi_CFL | result | angle | surface speed (cm/s) | "
             "profile error against chi 0.2 | steps | wall (s) |", "|---|---|---|---|---|---|---|---|---|---|"]
    key = lambda n: (R[n]["stab"], -float(R[n]["dr"]), float(R[n]["E"]), float(R[n]["cfl"]))
    for n in sorted(R, key=key):
        r = R[n]
        lines.append("| %s | %g | %g | %g | %s | %s | %s | %s | %s | %s |" % (
            r["stab"], float(r["dr"]) * 1e3, float(r["E"]), float(r["cfl"]), "ran" if r["ok"] else r["how"],
            "%.1f°" % r["angle"] if r["ok"] else "", "%.2f" % (100 * r["speed"]) if r["ok"] else "",
            "%.3f" % r["err"] if "err" in r else "", r["steps"], r["wall_s"]))
    try:
        import matplotlib
    except ImportError:
        print("matplotlib is missing: no chart; redraw it with report --out %s"
              % os.path.join(a.docs, "stability_map_rows.csv"))
        return batch.report_tables(a, lines)
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.8), squeeze=False)
    sc = None
    for a_, (stab, dr) in zip(ax[0], panels):
        rows = [r for r in R.values() if r["stab"] == stab and float(r["dr"]) == dr]
        good = [r for r in rows if r["ok"] and "err" in r]
        noref = [r for r in rows if r["ok"] and "err" not in r]  # ran, no chi 0.2 run to compare with
        bad = [r for r in rows if not r["ok"]]
        if good:
            sc = a_.scatter([float(r["cfl"]) for r in good], [float(r["E"]) for r in good], s=90,
                            c=[r["err"] for r in good], cmap="viridis_r", vmin=0, vmax=0.3,
                            edgecolors="k", linewidths=0.5)
        for r in noref:
            a_.plot(float(r["cfl"]), float(r["E"]), "o", color="0.6", mec="k", ms=10)
            a_.annotate("ran (no χ 0.2 run)", (float(r["cfl"]), float(r["E"])), fontsize=6, xytext=(4, -10),
                        textcoords="offset points")
        a_.set_xlim(0.1, 2.3)
        said = set()  # (E, how): a failure mode is named once per row, at its smallest chi
        for r in sorted(bad, key=lambda r: float(r["cfl"])):
            if r["how"].startswith("not finished"):  # no verdict: drawn apart from a failure
                a_.plot(float(r["cfl"]), float(r["E"]), "o", mfc="none", color="0.5", ms=10)
                continue
            a_.plot(float(r["cfl"]), float(r["E"]), "x", color="C3", ms=11, mew=2)
            if (r["E"], r["how"]) not in said:
                said.add((r["E"], r["how"]))
                a_.annotate(r["how"].replace(" in a step", ""), (float(r["cfl"]), float(r["E"])), fontsize=6,
                            xytext=(0, -13), ha="center", textcoords="offset points", color="C3")
        a_.set_yscale("log")
        Es = [float(r["E"]) for r in rows]
        a_.set_ylim(min(Es) / 2.5, max(Es) * 2.5)
        a_.set_xlabel(r"$\chi_{CFL}$ (Run:cfl_flow)")
        a_.set_ylabel("E (Pa)")
        a_.set_title("%s, dr %g mm" % (LABEL.get(stab, stab), dr * 1e3), fontsize=9)
        a_.grid(alpha=0.3)
    if sc is not None:
        fig.colorbar(sc, ax=ax[0][-1], label=r"speed-profile error against $\chi$ 0.2")
    fig.suptitle("2D EV drum to 1.5 s: dots ran (colour: error), crosses failed, open circles not finished "
                 "in the time allowed", fontsize=8)
    fig.tight_layout()
    os.makedirs(a.docs, exist_ok=True)
    fig.savefig(os.path.join(a.docs, "stability_map_%s.png" % "_".join(sorted({p[0] for p in panels}))), dpi=110)
    batch.report_tables(a, lines)


def main(argv=None):
    batch.study_main(__doc__, SETS, cases, on_done, cmd_report, "granular", jobs=2,
                     argv=argv)


if __name__ == "__main__":
    main()
