"""Compare a sphseg shear-box run with the 1D finite-volume reference.

    /usr/bin/python3 -m tools.analysis.shearbox_compare OUTDIR [--cells 800]
        [--times-over-T 20 40 80] [--strict]

Reads OUTDIR/used_params.yml and OUTDIR/snapshot_*.h5, picks the snapshots
at the requested t/T (nearest; must agree to 1e-6 relative), solves the
reference once (cached in OUTDIR/reference.npz under a parameter hash),
prints MAE / RMSE (paper eqs. 5.3-5.4) and max error of the row-averaged SPH
profile against it, and writes OUTDIR/compare.csv and OUTDIR/C_profile.png.
"""
import argparse
import dataclasses
import hashlib
import json
import os
import sys

import numpy as np
import yaml

from tools.analysis import seg1d  # noqa: E402
from tools.analysis import snap  # noqa: E402

REL_TOL = 1e-6


def match_times(snap_times, wanted, period, rel_tol=REL_TOL):
    """For each wanted time return the index of the nearest snapshot or None.

    A match must satisfy |t_snap - t| <= rel_tol * max(|t|, period).
    """
    snap_times = np.asarray(snap_times, float)
    found = []
    for t in wanted:
        i = int(np.argmin(np.abs(snap_times - t)))
        ok = abs(snap_times[i] - t) <= rel_tol * max(abs(t), period)
        found.append(i if ok else None)
    return found


def reference_key(p, n_cells, times):
    """Hash of everything the cached reference depends on."""
    blob = json.dumps({"params": dataclasses.asdict(p), "cells": n_cells,
                       "times": [float(f"{t:.12g}") for t in times]},
                      sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def cached_reference(outdir, p, n_cells, times):
    """Reference profiles at `times`, loaded from or saved to reference.npz."""
    path = os.path.join(outdir, "reference.npz")
    key = reference_key(p, n_cells, times)
    if os.path.exists(path):
        with np.load(path) as z:
            if str(z["key"]) == key:
                print(f"reference: cached {path} (key {key})")
                return z["y"], z["C"]
    y, C = seg1d.solve(p, times, n_cells)
    np.savez(path, key=key, y=y, C=C, times=np.asarray(times, float))
    print(f"reference: solved with {n_cells} cells, saved {path} (key {key})")
    return y, C


def read_dr(outdir):
    """Particle spacing Geometry.dr from used_params.yml."""
    with open(os.path.join(outdir, "used_params.yml")) as fh:
        return float(yaml.safe_load(fh)["Geometry"]["dr"])


def errors(C_sph, C_ref):
    """(MAE, RMSE, max |error|) of the SPH rows against the reference."""
    return (seg1d.mae(C_sph, C_ref), seg1d.rmse(C_sph, C_ref),
            float(np.max(np.abs(np.asarray(C_sph) - C_ref))))


def space_time_map(paths, dr):
    """Row profiles of all snapshots: (times, y_rows, C[n_rows, n_snaps])."""
    times, y_rows, columns = [], None, []
    for path in paths:
        s = snap.read_snapshot(path)
        y, C = snap.row_profile(s, dr)
        if y_rows is None:
            y_rows = y
        times.append(float(s["Time"]))
        columns.append(np.interp(y_rows, y, C))
    return np.array(times), y_rows, np.array(columns).T


def _edges(x, pad):
    """Cell edges around sorted centres x (width 2*pad for a single centre)."""
    x = np.asarray(x, float)
    if x.size == 1:
        return np.array([x[0] - pad, x[0] + pad])
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate([[2 * x[0] - mid[0]], mid, [2 * x[-1] - mid[-1]]])


def plot(path, p, stmap, picks, y_ref, C_ref):
    """Space-time map of SPH C (left) and profiles at picked times (right)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t_all, y_rows, C_map = stmap
    n = max(len(picks), 1)
    fig, axes = plt.subplots(1, 1 + n, figsize=(4.5 + 2.6 * n, 4.2),
                             gridspec_kw={"width_ratios": [2.0] + [1.0] * n},
                             squeeze=False)
    ax = axes[0, 0]
    mesh = ax.pcolormesh(_edges(t_all / p.period, 0.5), _edges(y_rows / p.H, 0.01),
                         C_map, vmin=0.0, vmax=1.0, cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="C (small grains)")
    ax.set(xlabel="t/T", ylabel="z/H", title="SPH row-averaged C")
    for k, (t, y_sph, C_sph) in enumerate(picks):
        a = axes[0, 1 + k]
        a.plot(C_ref[k], y_ref / p.H, "-", color="k", lw=1.2, label="FV ref.")
        a.plot(C_sph, y_sph / p.H, "o", ms=2.5, mfc="none", color="C3",
               label="SPH")
        a.set(xlim=(-0.02, 1.02), ylim=(0, 1), xlabel="C",
              title=f"t/T = {t / p.period:g}")
        if k == 0:
            a.set_ylabel("z/H")
            a.legend(loc="best", fontsize=8)
        else:
            a.set_yticklabels([])
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def write_csv(path, rows):
    """Write compare.csv: one line per compared time."""
    with open(path, "w") as fh:
        fh.write("t_over_T,time,snapshot,n_rows,MAE,RMSE,max_err\n")
        for r in rows:
            fh.write("{:.10g},{:.10g},{},{},{:.6e},{:.6e},{:.6e}\n".format(*r))


def main(argv=None):
    """CLI entry point; returns the process exit status."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--cells", type=int, default=800)
    ap.add_argument("--times-over-T", type=float, nargs="+",
                    default=[20.0, 40.0, 80.0])
    ap.add_argument("--strict", action="store_true",
                    help="fail if any requested time has no snapshot")
    args = ap.parse_args(argv)

    paths = snap.list_snapshots(args.outdir)
    if not paths:
        print(f"error: no snapshot_*.h5 in {args.outdir}", file=sys.stderr)
        return 1
    p = seg1d.params_from_yaml(args.outdir)
    dr = read_dr(args.outdir)
    stmap = space_time_map(paths, dr)
    t_all = stmap[0]
    print(f"found {len(paths)} snapshots, t/T = {t_all.min() / p.period:g} "
          f"... {t_all.max() / p.period:g}")

    wanted = [tau * p.period for tau in args.times_over_T]
    found = match_times(t_all, wanted, p.period)
    hits = [i for i in found if i is not None]
    for tau, i in zip(args.times_over_T, found):
        if i is None:
            near = t_all[np.argmin(np.abs(t_all - tau * p.period))] / p.period
            print(f"warning: no snapshot at t/T = {tau:g} (nearest {near:.8g})",
                  file=sys.stderr)
    if not hits or (args.strict and len(hits) < len(found)):
        print(f"error: {len(hits)} of {len(found)} requested t/T found "
              f"(snapshot times must match to {REL_TOL:g} relative)",
              file=sys.stderr)
        return 1

    y_ref, C_ref = cached_reference(args.outdir, p, args.cells, t_all[hits])
    rows, picks = [], []
    print(f"{'t/T':>8} {'MAE':>11} {'RMSE':>11} {'max err':>11}  snapshot")
    for k, i in enumerate(hits):
        y_sph, C_sph = snap.row_profile(snap.read_snapshot(paths[i]), dr)
        e = errors(C_sph, seg1d.profile_at(y_ref, C_ref[k], y_sph))
        tau = t_all[i] / p.period
        print(f"{tau:8.4g} {e[0]:11.4e} {e[1]:11.4e} {e[2]:11.4e}  "
              f"{os.path.basename(paths[i])}")
        rows.append((tau, t_all[i], os.path.basename(paths[i]), len(y_sph)) + e)
        picks.append((t_all[i], y_sph, C_sph))

    write_csv(os.path.join(args.outdir, "compare.csv"), rows)
    plot(os.path.join(args.outdir, "C_profile.png"), p, stmap, picks, y_ref, C_ref)
    print(f"wrote {args.outdir}/compare.csv and {args.outdir}/C_profile.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
