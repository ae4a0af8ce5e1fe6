#!/usr/bin/env python3
"""Errors of drum runs against a reference run of the same drum:

  python3 -m tools.analysis.drum_compare REF RUN [RUN ...] [--times 5 10] [--slab W] [--csv FILE]

For every snapshot time the runs share (or the --times asked, nearest
snapshot), each RUN is compared with REF on what a user of a drum reads
(tools/analysis/drum_analysis.py defines each quantity):

  C          rms and max over material particles of |C - C_ref|, matched by
             ParticleIDs (both runs start from the same lattice);
  seg        the segregation index, and its difference from REF's;
  angle      the dynamic angle, and its difference from REF's (degrees);
  speed      the rms difference of the mid-chord speed profile, sampled at
             the same 60 normalised depths d_mc/R in each run, over REF's
             largest mid-chord speed (the error figure of docs/granular.md);
  drift      the largest |relative drift of sum C_i V_i| of the run,
             recomputed here from the snapshots (sum over material of
             Concentration * Volume against the first snapshot's), not read
             from diagnostics.csv.

Prints one row per run and time; --csv writes them too. time_to_solution.py
calls compare() for its accuracy axis.
"""
import argparse
import csv
import os

import numpy as np

from tools.analysis import drum_analysis as da  # noqa: E402
from tools.analysis import snap  # noqa: E402

DEPTHS = np.linspace(0.0, 0.5, 60)  # d_mc / R where the speed profiles are compared (the flowing layer and below)


def _by_id(s):
    """Material C and IDs of a snapshot dict, sorted by ID."""
    m = np.asarray(s["Kind"]) == snap.MATERIAL
    ids = np.asarray(s["ParticleIDs"])[m]
    o = np.argsort(ids)
    return ids[o], np.asarray(s["Concentration"])[m][o]


def small_volume_drift(outdir):
    """Largest |relative drift of sum C_i V_i| over the snapshots of outdir."""
    tot = []
    for p in snap.list_snapshots(outdir):
        s = snap.read_snapshot(p)
        m = np.asarray(s["Kind"]) == snap.MATERIAL
        tot.append(float(np.sum(np.asarray(s["Concentration"])[m] * np.asarray(s["Volume"])[m])))
    tot = np.array(tot)
    return float(np.max(np.abs(tot - tot[0]) / abs(tot[0]))) if len(tot) else float("nan")


def speed_profile(d):
    """Speed on the mid-chord at DEPTHS (m/s)."""
    dm, pts = d.midchord(npts=400)
    sp = d.interp(pts, d.speed)
    ok = np.isfinite(sp)
    return np.interp(DEPTHS, dm[ok], sp[ok], right=np.nan)


def compare_one(ref_path, run_path, par_ref, par_run, slab=None):
    """The errors of one snapshot of a run against the reference's."""
    a, b = snap.read_snapshot(ref_path), snap.read_snapshot(run_path)
    ia, ca = _by_id(a)
    ib, cb = _by_id(b)
    if not np.array_equal(ia, ib):
        raise SystemExit("drum_compare: %s and %s hold different material particles" % (ref_path, run_path))
    da_, db_ = da.Drum(ref_path, par_ref, slab), da.Drum(run_path, par_run, slab)
    ua, ub = speed_profile(da_), speed_profile(db_)
    ok = np.isfinite(ua) & np.isfinite(ub)
    return {"t": db_.t, "C_rms": float(np.sqrt(np.mean((cb - ca) ** 2))), "C_max": float(np.max(np.abs(cb - ca))),
            "seg": db_.segregation_index(), "seg_ref": da_.segregation_index(),
            "angle": db_.angle, "angle_ref": da_.angle,
            "speed_err": float(np.sqrt(np.mean((ub[ok] - ua[ok]) ** 2)) / np.nanmax(ua)),
            "surface_speed": float(np.nanmax(ub)), "surface_speed_ref": float(np.nanmax(ua))}


def compare(ref, run, times=None, slab=None):
    """Rows of compare_one for the snapshot times of run (or those nearest
    `times`) that ref also has (to 1e-9 s), plus each row's drift."""
    pr, pu = da.used_params(ref), da.used_params(run)
    rp, up = snap.list_snapshots(ref), snap.list_snapshots(run)
    rt = np.array([snap.snapshot_time(p) for p in rp])
    if times:
        up = da.pick(up, times)
    drift = small_volume_drift(run)
    rows = []
    for p in up:
        t = snap.snapshot_time(p)
        k = int(np.argmin(np.abs(rt - t)))
        if abs(rt[k] - t) > 1e-9 * max(1.0, t) or t == 0:
            continue
        r = compare_one(rp[k], p, pr, pu, slab)
        r["drift"] = drift
        rows.append(r)
    return rows


COLS = ["t", "C_rms", "C_max", "seg", "seg_ref", "angle", "angle_ref", "speed_err", "surface_speed",
        "surface_speed_ref", "drift"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("ref")
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--times", type=float, nargs="+")
    ap.add_argument("--slab", type=float, help="3D drums: the mid-length slab width, m (drum_analysis.py)")
    ap.add_argument("--csv", help="write the rows here")
    a = ap.parse_args()
    out = []
    print("%-28s %7s %9s %9s %9s %9s %8s %8s %9s %9s" % ("run", "t (s)", "C rms", "C max", "seg", "seg ref",
                                                       "angle", "ref", "speed err", "drift"))
    for run in a.runs:
        for r in compare(a.ref, run, a.times, a.slab):
            r["run"] = run
            out.append(r)
            print("%-28s %7.3f %9.2e %9.2e %9.5f %9.5f %7.2f° %7.2f° %9.2e %9.2e"
                  % (os.path.basename(run.rstrip("/"))[:28], r["t"], r["C_rms"], r["C_max"], r["seg"], r["seg_ref"],
                     r["angle"], r["angle_ref"], r["speed_err"], r["drift"]))
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=["run"] + COLS)
            w.writeheader()
            for r in out:
                w.writerow({k: r[k] for k in ["run"] + COLS})


if __name__ == "__main__":
    main()
