#!/usr/bin/env python3
"""Time to solution of the 3D drum: device-hours (or core-hours) per revolution.

  python3 -m tools.studies.time_to_solution run [--sphseg build/sphseg] [--backend gpu] [--steps 200]
                                [--scene inputs/drum_3d.yml] [-P Section:key=value ...]
  python3 -m tools.studies.time_to_solution chart [--data docs/data/gpu/time_to_solution.csv] [--png docs/data/gpu/time_to_solution.png]
  python3 -m tools.studies.time_to_solution plan --tolerance PCT (--dr DR | --particles N) [--length L]

plan: the cheapest of the measured settings of the drum scenes' flow
(docs/data/gpu/time_to_solution_pair.csv) whose surface speed and
segregation index both lie within PCT per cent of the converged answer, at the
measured spacing nearest above or at DR (errors fall as dr does), with its
keys (and the Run:preset that sets them), the accuracy it rests on and its
source row, and the GPU-hours per revolution scaled from the measured ones as
dr^-4 (particles as dr^-3, steps as dr^-1).

run: the drum (by default inputs/drum_3d.yml at dr = 0.25 mm and length 0.1 m,
1.1e7 particles, the issue's drum, with Flow:stabilization monaghan and
Flow:gradient_correction and Flow:shifting off, with which the CSV's points
were measured; -P changes any key, e.g. -P
Material:E=1e5 -P Flow:alpha_av=1) runs STEPS steps with snapshots off, and
the tool prints the measured rate (particle-steps/s of sphseg's "done:"
line, which leaves out set-up and output), the time step the run took (the
last diagnostics row's dt: the flow's acoustic step, 3.19) and from them

    steps per revolution  = (60 / Walls:rpm) / dt
    hours per revolution  = steps per revolution / (rate / particles) / 3600

in GPU-hours on --backend gpu (one GPU), core-hours on the CPU (times
OMP_NUM_THREADS). With concentration windows (Segregation:every, auto by
default) STEPS should cover at least one window (K <= 100): the default 200
does. The rate of a short run stands for the whole revolution: a turning
drum's cost per step does not change with time (the neighbour counts do not).

chart: docs/data/gpu/time_to_solution.png from the CSV of measured points
(--data, --png; --reference and --error-note name what the errors are
against, e.g. for time_to_solution_riemann.csv) (one row
per combination of levers: the hours per revolution from `run`, the error
columns from the 2D EV drum studies of docs/gpu.md, each row naming its
source); rows whose error was not measured are drawn on the cost axis only.
"""
import argparse
import csv
import os
import re
import subprocess
import sys
import tempfile

from tools import ROOT  # noqa: E402
from tools.analysis import snap  # noqa: E402

# the paper's monaghan, without the corrected gradient and the shifting, as every point of time_to_solution.csv
# (the drum scene sets riemann with both since issue 30); -P overrides them
DRUM = ["Geometry:dr=0.00025", "Geometry:length=0.1", "Flow:stabilization=monaghan", "Flow:gradient_correction=off",
        "Flow:shifting=off"]


def measure(sphseg, scene, backend, steps, over, work):
    """Run the drum briefly; returns a dict of what the hours come from."""
    out = os.path.join(work, "tts")
    cmd = [sphseg, scene, "-o", out, "--backend", backend, "-P", "Run:max_steps=%d" % steps,
           "-P", "Output:snapshots=off", "-P", "Run:progress_s=1e9"]
    for o in DRUM + list(over):
        cmd += ["-P", o]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("time_to_solution: sphseg exited with %d: %s" % (r.returncode, (r.stderr or r.stdout).strip()[-400:]))
    log = r.stdout
    n = re.search(r"(\d+) material \+ (\d+) dummy particles", log)
    done = re.search(r"done: (\d+) steps, .* ([\d.e+-]+) particle-steps/s", log)
    rpm = re.search(r"^\s*rpm: ([\d.e+-]+)", open(os.path.join(out, "used_params.yml")).read(), re.M)
    if not (n and done and rpm):
        sys.exit("time_to_solution: could not read the particle count, the rate or Walls:rpm from the run")
    dg = snap.read_diagnostics(out)
    npart = int(n.group(1)) + int(n.group(2))
    rate = float(done.group(2))
    dt = float(dg["dt"][-1])
    threads = int(os.environ.get("OMP_NUM_THREADS", os.cpu_count() or 1)) if backend == "cpu" else 1
    steps_rev = 60.0 / float(rpm.group(1)) / dt
    hours = steps_rev / (rate / npart) / 3600.0 * threads
    windows = re.search(r"concentration: (\d+) windows of ([\d.]+) flow steps", log)
    return {"particles": npart, "rate": rate, "dt": dt, "steps_per_rev": steps_rev, "hours_per_rev": hours,
            "unit": "GPU-hours" if backend == "gpu" else "core-hours (%d threads)" % threads,
            "windows": windows.group(0) if windows else "C in every flow step"}


def cmd_run(a):
    with tempfile.TemporaryDirectory() as work:
        m = measure(a.sphseg, a.scene, a.backend, a.steps, a.P, work)
    print("drum: %s %s, %d particles; %s" % (a.scene, " ".join("-P " + o for o in DRUM + a.P), m["particles"],
                                              m["windows"]))
    print("rate %.4g particle-steps/s (%.4g steps/s), dt %.4g s, %.4g steps per revolution"
          % (m["rate"], m["rate"] / m["particles"], m["dt"], m["steps_per_rev"]))
    print("%.4g %s per revolution (%.3g days)" % (m["hours_per_rev"], m["unit"], m["hours_per_rev"] / 24))


def cmd_chart(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = list(csv.DictReader(open(a.data)))
    panels = [("speed_err", "surface speed"), ("seg_err", "segregation index")]
    panels = [p for p in panels if any(r[p[0]].strip() for r in rows)]  # a column nobody measured: no panel
    fig, ax = plt.subplots(1, len(panels), figsize=(12 if len(panels) > 1 else 10, 6.6), sharex=True, squeeze=False)
    ax = ax[0]
    hours = [float(r["gpu_hours_per_rev"]) for r in rows]
    for k, (col, lab) in enumerate(panels):
        for n, r in enumerate(rows):
            h = float(r["gpu_hours_per_rev"])
            e = r[col].strip()
            if e:  # one colour per row in every panel, whichever rows a panel lacks
                t10 = r.get("t_s", "5").strip() == "10"
                mk = "s" if t10 else "oD^v"[(n // 10) % 4]  # past ten rows the colours repeat: another marker
                ax[k].loglog(h, max(abs(float(e)), 1e-3), mk, ms=7, color="C%d" % (n % 10),
                             label=r["label"] + (" (t = 10 s)" if t10 else ""))
            else:
                ax[k].axvline(h, ls=":", lw=1, color="gray")
                ax[k].annotate(r["label"] + "\n(error not measured)", (h, 1.2e-3), fontsize=6, rotation=90,
                               ha="right", va="bottom", color="gray")
        ax[k].axvline(a.goal, color="k", lw=0.8, ls="--")
        ax[k].annotate(" goal: %g h%s" % (a.goal, a.goal_note), (a.goal, 0.5), fontsize=8, ha="left")
        if a.band:
            ax[k].axhline(a.band, color="g", lw=0.8, ls="--")
            ax[k].annotate(" %g %% of the reference" % (100 * a.band), (min(hours) / 1.4, a.band * 1.1), fontsize=8)
        ax[k].set_xlabel("GPU-hours per revolution (measured rate, one H100 or H200: the row's source)\n3D drum: 1.1e7 particles at dr 0.25 mm unless named")
        ax[k].set_ylabel("|relative error| of the %s\n(%s)" % (lab, a.error_note))
        errs = [abs(float(r[col])) for r in rows if r[col].strip()]
        ax[k].set_ylim(1e-3, max([1.5] + [1.5 * e for e in errs]))
        ax[k].grid(alpha=0.3, which="both")
        ax[k].set_xlim(min(3.0, min(hours) / 1.5), max(hours) * 1.5)
    h, l = ax[0].get_legend_handles_labels()
    fig.legend(h, l, fontsize=8, loc="lower center", ncol=2)
    fig.suptitle("Time to solution against accuracy (errors below 1e-3 drawn at 1e-3)\nreference: %s" % a.reference,
                 fontsize=9)
    fig.tight_layout(rect=(0, 0.06 + 0.032 * ((len(h) + 1) // 2), 1, 0.93))
    fig.savefig(a.png, dpi=120)
    print("wrote %s" % a.png)


# The drum scenes' flow (the pair: the corrected gradient with Fickian shifting, on riemann with bed damping),
# whose rows of time_to_solution_pair.csv the planner reads; the keys each row adds to it are E and chi.
SCENE_FLOW = ["Flow:stabilization=riemann", "Flow:bed_damping=1", "Flow:gradient_correction=on",
              "Flow:shifting=fickian", "Segregation:every=auto"]
# Run:preset's sets that are rows of the planner (src/scene/scene_keys.h holds them; keep the two alike)
PRESETS = {"fast": {"Material:E": 3e4, "Run:cfl_flow": 0.2}, "converged": {"Material:E": 1e5, "Run:cfl_flow": 0.2}}
# and their Run:integrator (a row's is leapfrog where its label says so, else the predictor-corrector)
PRESET_INTEGRATOR = {"fast": "leapfrog", "converged": "predictor_corrector"}
# Run:integrator leapfrog's rate over the predictor-corrector's with which the rows' hours were measured, on the
# 1.1e7 3D drum, the scenes' flow at E 10 kPa, chi 0.2, single, one H200 (docs/performance.md "One evaluation a step",
# docs/gpu.md "GPU kernels" and "The flow pass's code", tools/bench/drum_rates.sh): a chain of ratios each measured
# within one device call, 1.728e8 / 1.029e8 (the leapfrog against the predictor-corrector, 2026-11-29) x
# 1.888e8 / 1.718e8 (the pair loops' square roots and divisors) x 2.200e8 / 1.890e8 (the fused shift's stack frame)
# x 2.46e8 / 2.31e8 (two threads a particle, not one; at Run:preset fast) x 2.3465e8 / 2.2945e8 (the shift's L
# from the flow pass) x 2.43e8 / 2.32e8 (the bed weights once a particle) x 2.633e8 / 2.452e8 (the single build's
# fast division, 5 blocks); the fast preset runs it (src/scene/scene_preset.c)
LEAPFROG_RATE = ((1.728e8 / 1.029e8) * (1.888e8 / 1.718e8) * (2.200e8 / 1.890e8) * (2.46e8 / 2.31e8)
                 * (2.3465e8 / 2.2945e8) * (2.43e8 / 2.32e8) * (2.633e8 / 2.452e8))
RAW_DATA_MOVE = "b1945a9"  # the commit that took the studies' raw data out of docs/data (docs/CHANGELOG.md)
TTS_DRUM = {"dr": 0.00025, "length": 0.1, "particles": 1.12e7}  # the drum the hours were measured on at dr 0.25 mm


def plan_rows(path):
    """The measured rows of the scenes' flow: dr (m), E, chi, hours per revolution, errors, label, source."""
    rows = []
    for r in csv.DictReader(open(path)):
        m = re.search(r"dr ([\d.]+) mm", r["label"])
        if not r["label"].startswith("the pair") or not m or not r["speed_err"].strip() or not r["seg_err"].strip():
            continue
        rows.append({"dr": float(m.group(1)) * 1e-3, "E": float(r["E_Pa"]), "chi": float(r["cfl_flow"]),
                     "hours": float(r["gpu_hours_per_rev"]), "speed_err": float(r["speed_err"]),
                     "seg_err": float(r["seg_err"]), "label": r["label"], "source": r["source"],
                     "integrator": "leapfrog" if "leapfrog" in r["label"] else "predictor_corrector"})
    return rows


def plan(rows, tol, dr):
    """The cheapest measured setting within tol (fraction) on both errors at the measured dr nearest above or at
    dr (errors fall with dr: a finer run is at least as accurate); returns (row, hours at dr) or (None, why)."""
    drs = sorted({r["dr"] for r in rows})
    at = [d for d in drs if d >= dr * (1 - 1e-9)]
    if not at:
        return None, "dr %.3g mm is coarser than every measured spacing (%s mm): no measured accuracy" % (
            dr * 1e3, ", ".join("%g" % (d * 1e3) for d in drs))
    base = min(at)
    ok = [r for r in rows if r["dr"] == base and abs(r["speed_err"]) <= tol and abs(r["seg_err"]) <= tol]
    if not ok:
        best = min((r for r in rows if r["dr"] == base), key=lambda r: max(abs(r["speed_err"]), abs(r["seg_err"])))
        return None, "no measured setting at dr %g mm is within %g %% (the closest: %s, %+.1f %% speed, %+.1f %% " \
            "index)" % (base * 1e3, tol * 100, best["label"], 100 * best["speed_err"], 100 * best["seg_err"])
    r = min(ok, key=lambda r: r["hours"])
    return r, r["hours"] * (r["dr"] / dr) ** 4  # particles ~ dr^-3 (3D), steps ~ dr^-1 (the acoustic step)


def cmd_plan(a):
    if (a.dr is None) == (a.particles is None):
        sys.exit("time_to_solution plan: give one of --dr and --particles")
    ref = TTS_DRUM
    dr = a.dr if a.dr is not None else ref["dr"] * (ref["particles"] * a.length / ref["length"] / a.particles) ** (1 / 3)
    n = ref["particles"] * (a.length / ref["length"]) * (ref["dr"] / dr) ** 3
    rows = plan_rows(a.data)
    r, h = plan(rows, a.tolerance / 100, dr)
    print("3D drum (inputs/drum_3d.yml), length %g m, dr %.4g mm: about %.3g particles" % (a.length, dr * 1e3, n))
    if r is None:
        print("no plan: " + h)
        return 1
    keys = SCENE_FLOW + ["Material:E=%g" % r["E"], "Run:cfl_flow=%g" % r["chi"]]
    if r["integrator"] == "leapfrog":
        keys.append("Run:integrator=leapfrog")
    preset = [k for k, v in PRESETS.items() if v["Material:E"] == r["E"] and v["Run:cfl_flow"] == r["chi"]
              and PRESET_INTEGRATOR[k] == r["integrator"]]
    print("settings: " + " ".join("-P " + k for k in keys) + ("  (= -P Run:preset=%s)" % preset[0] if preset else ""))
    print("accuracy: surface speed %+.1f %%, segregation index %+.1f %% at dr %g mm, against the scenes' flow at "
          "dr 0.25 mm, E 0.1 MPa, chi 0.2 (2D EV drum, means of t = 3-5 s)"
          % (100 * r["speed_err"], 100 * r["seg_err"], r["dr"] * 1e3))
    if "reference" in r["label"]:  # the row the errors are measured against: its own error is 0 by definition
        coarse = [q for q in rows if q["E"] == r["E"] and q["chi"] == r["chi"] and q["dr"] > r["dr"]]
        print("  (this is the reference setting itself: its error is 0 by definition; from dr %s mm it moved the speed "
              "by %s)" % (", ".join("%g" % (q["dr"] * 1e3) for q in coarse) or "-",
                          ", ".join("%+.1f %%" % (-100 * q["speed_err"]) for q in coarse) or "-"))
    print("cost: %.3g GPU-hours per revolution (one GPU, single build, as the source row says; measured %.4g h at dr %g "
          "mm, scaled by (dr_measured / dr)^4)" % (h * a.length / ref["length"], r["hours"], r["dr"] * 1e3))
    if r["integrator"] != "leapfrog" and r["E"] == PRESETS["fast"]["Material:E"] and r["chi"] == PRESETS["fast"]["Run:cfl_flow"]:
        print("  with the preset's Run:integrator leapfrog: about %.3g GPU-hours (the hours above over its measured "
              "rate ratio %.2f; accuracy cost within 0.4 %% on the 2D drums, docs/performance.md)"
              % (h * a.length / ref["length"] / LEAPFROG_RATE, LEAPFROG_RATE))
    print("source row: %s\n  %s" % (r["label"], r["source"]))
    gone = sorted({m for m in re.findall(r"docs/data/[\w./-]+", r["source"]) if not os.path.exists(os.path.join(ROOT, m))})
    if gone:  # the raw data left the tree with the docs' move (b1945a9): in git history
        print("  (%s: in git history, e.g. git show %s^:%s)" % (", ".join(gone), RAW_DATA_MOVE, gone[0]))
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run")
    r.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    r.add_argument("--scene", default=os.path.join(ROOT, "inputs", "drum_3d.yml"))
    r.add_argument("--backend", default="gpu", choices=["gpu", "cpu"])
    r.add_argument("--steps", type=int, default=200)
    r.add_argument("-P", action="append", default=[], help="Section:key=value, after the drum's own")
    c = sub.add_parser("chart")
    c.add_argument("--data", default=os.path.join(ROOT, "docs", "data", "gpu", "time_to_solution.csv"))
    c.add_argument("--png", default=os.path.join(ROOT, "docs", "data", "gpu", "time_to_solution.png"))
    c.add_argument("--reference", default="Table 1, C in every step", help="what the errors are against (title)")
    c.add_argument("--error-note", default="2D EV drum, Table 1 resolution, t = 5 s (o) or 10 s (s)",
                   help="where the errors come from (axis label)")
    c.add_argument("--band", type=float, help="draw this relative error as a line (e.g. 0.02)")
    c.add_argument("--goal", type=float, default=6.0, help="draw this cost as the goal line, GPU-hours (default 6)")
    c.add_argument("--goal-note", default="", help="text after the goal's hours")
    p = sub.add_parser("plan", help="the cheapest measured settings within a tolerance, and their GPU-hours")
    p.add_argument("--tolerance", type=float, required=True, help="PCT: largest error of speed and index, per cent")
    p.add_argument("--dr", type=float, help="particle spacing, m")
    p.add_argument("--particles", type=float, help="particle count of the 3D drum (instead of --dr)")
    p.add_argument("--length", type=float, default=0.1, help="drum length, m (default 0.1)")
    p.add_argument("--data", default=os.path.join(ROOT, "docs", "data", "gpu", "time_to_solution_pair.csv"))
    a = ap.parse_args()
    if a.what == "plan":
        sys.exit(cmd_plan(a))
    cmd_run(a) if a.what == "run" else cmd_chart(a)


if __name__ == "__main__":
    main()
