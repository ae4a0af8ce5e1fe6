#!/usr/bin/env python3
"""The segregation under refinement (issue 57 item 1): what sets the concentration's resolution error
on the 2D drums, factor by factor.

  python3 -m tools.studies.seg_refine commands [--sphseg BIN] [--out DIR] [--script FILE] [--tiny]
  bash FILE                                                  (one device call: runs, analyses, deletes snapshots)
  python3 -m tools.studies.seg_refine analyse RUNDIR --json FILE [--rc RC] [--log LOG]   (the script calls it)
  python3 -m tools.studies.seg_refine table FILE.json... [--csv docs/data/drum/seg_refine.csv] [--effects CSV]
  python3 -m tools.studies.seg_refine chart [--csv ...] [--effects CSV] [--png docs/data/drum/seg_refine.png]
  python3 -m tools.studies.seg_refine mixemu FILE.json... [--csv ...]   (the mixemu runs against yielded at 0.5, 0.25 mm)
  python3 -m tools.studies.seg_refine third FILE.json... [--csv ...] [--png ...]   (yielded at dr 0.125 mm against 0.5,
                                                             0.25 mm: the observed order and Richardson's limit)
  python3 -m tools.studies.seg_refine profiles FILE.json... [--times 6 10] [--png ...]   (base's C and shear-rate profiles,
                                                             and each C profile's peak: height, depth, width)
  python3 -m tools.studies.seg_refine stiff FILE.json... [--csv ...] [--png ...]   (yieldedE against yielded at the same
                                                             dr from the 40-s table: E x 10's change per even second)
  python3 -m tools.studies.seg_refine area A0.5.json A0.25.json A0.125.json --lattice L0.125.json [--csv ...]
                                                             (yielded with Geometry:fill_by area at three spacings against
                                                             the lattice fill's: each fill's change per halving)

The runs. The scenes (inputs/drum_2d_EV.yml, drum_2d_EN.yml) with their flow (riemann, bed damping 1,
the corrected gradient, Fickian shifting, C in windows `every auto`) at E 10 kPa, chi 0.2, the
predictor-corrector (as the issue's 3-7 % were measured), Output:dt 2 s, at dr 1.0, 0.5 and 0.25 mm.
Each variant changes one existing key against the baseline `base`:
  every1    Segregation:every=1        the windows (and the window's time average of the shear rate)
  limnone   Segregation:limiter=none   the donor limiter
  const     Segregation:model=constant, V=1e-4 m/s, D=2e-8 m^2/s: V and D free of the shear rate
            (no key gives a constant D beside V = chi_V gdot d; this one removes both dependences;
            V h / D = 3.75 at dr 0.5 mm against the shear-rate model's chi_V h / (chi_D d_avg) = 7.2)
  shift05   Flow:shift_coeff=0.5       the shifting's strength (the disorder it leaves and its drift of
            particles, which carry C unchanged), against the scenes' 2
  bd3       Flow:bed_damping=3         the bed's shear-rate noise (what damps it), against 1
  chiD2     Segregation:chi_D=0.0614   twice the physical diffusion: a numerical diffusion that sets the
            error would matter half as much
  yielded   Segregation:shear_rate=yielded: eq. (2.7)'s shear rate only where the stress is on or past
            the static yield cone, 0 in the elastic bed (whose SPH shear rate grows as 1/dr)
  yieldedE  yielded at Material:E=1e5: the stiffness's share (E x 10), measured against yielded
  yieldlim  yielded without the donor limiter (Segregation:limiter=none): the limiter's share at the
            front of C below the flowing layer, measured against yielded
  mixemu    yielded at dr 0.25 mm with chi_D raised so that the flowing layer's total diffusion (eq. 2.7's plus
            the particles' own cross-stream mixing, tools/analysis/drum_mixing.py) is dr 0.5 mm's (MIXEMU):
            if the index then equals dr 0.5 mm's, that mixing is what moves it under refinement
  cfl199    Run:cfl_flow=0.199: a step 0.5 % shorter, whose own effect is nil; what it changes is the
            runs' sensitivity to a perturbation, the floor under which a variant's effect is noise (at
            dr 2 mm, development machine, 0.199 and 0.201 move the index by up to 5.2 % EV, 2.6 % EN)
  area      Geometry:fill_by=area: the fill line raised until the bed's area is the segment's (within
            one particle at every dr: 1.4e-3 at dr 2 mm, 1.5e-4 at 1-0.25 mm; tests/validate_fill_area.py)
  fill      Geometry:fill moved by one lattice row at dr 1.0 and 0.25 mm (FILL below) so that the
            three beds' areas agree within 0.6 % (base: 5 % EV, 3.2 % EN)
The initial state is well mixed (C_below = C_above), so its "interface" is the bed's free surface on
the lattice and the wall's gap: the bed's area (its mass) is first order in dr and jumps by a row of
the fill line (FILL's comment); every run's JSON has the volume at t = 0.

Budget (one H200, double build). Rates of one run alone (docs/validation.md "Rotating drums"): EV
8e5 steps in 149 s at dr 0.5 mm = 5.4e3 steps/s, 1.6e6 in 460 s at 0.25 mm = 3.5e3; EN 5.2e3 and
2.6e3; dr 1.0 mm taken as 6e3 (not measured). dt = chi 1.5 dr / c_s, c_s = 3.0 m/s at E 10 kPa:
1e-4, 5e-5, 2.5e-5 s at dr 1.0, 0.5, 0.25 mm, so 1e4, 2e4, 4e4 steps per simulated second.
Runs side by side on the one GPU gain nothing: the first call (2026-11-29, six at once, BUDGET
460 s) ran the EN drum at dr 0.25 mm at 378 steps/s (156 417 steps in 414 s, 1.52e7 particle-steps/s)
beside five others, 6 x 378 = 2.3e3 steps/s in all against 2.6e3 alone: the GPU time-slices the
processes. So the runs go one at a time (SLOTS 1), each with Run:max_wall_time = the time left of
BUDGET less 45 s (it writes a checkpoint and stops cleanly); a run that would get under 40 s is
skipped and leaves NAME.skipped. In RUNS' order, to 10 s, alone:
  EV base dr 1.0 (1e5 steps, 17 s), 0.5 (2e5, 37 s)                         54 s
  EV cfl199, area, every1 at dr 1.0 and 0.5                                162 s
  EV base dr 0.25 (4e5 steps, 115 s)                                        115 s   (331 s so far)
  EN base, area, cfl199 at dr 1.0 and 0.5                                   165 s   (496 s)
  EV shift05, limnone, const, bd3, chiD2 at dr 1.0 and 0.5                  270 s
  EV and EN fill at dr 1.0                                                   34 s
  the dr 0.25-mm variants (EV area, fill, shift05; EN base): 115-150 s each
about 1.3e3 s in all: one call of BUDGET 460 s reaches the first EN runs; the rest need a second call
(BUDGET and a shorter RUNS list by --only). CPU runs are not used: a dr 1.0-mm drum runs 30-55
steps/s on one thread of the (shared) development machine, 1e4 steps per simulated second. Output: the
device returns a limited number of files, so everything under $OUT/res (one JSON of series and
profiles and the log tail per run, about 0.2 MB each) is packed into $OUT/seg_refine_res.tgz and
the run folders are deleted (the snapshots after each analysis). Unpack with
tar xzf seg_refine_res.tgz (it holds res/).

analyse (on the device, numpy, h5py, PyYAML; scipy's cKDTree where present, else a grid): per
snapshot, through tools.analysis.drum_analysis.Drum: dynamic angle, surface speed on the
mid-chord, segregation index, C range, the mid-chord profiles (speed, shear rate, C; 120 points),
the material's volume, the bed's shear-rate noise (the volume-weighted mean shear rate of particles
that move with the drum to within 5 % of the wall speed and lie more than 2h from the wall and the
surface line, and the bed's share of the material's sum of V gdot C (1 - C), the segregation flux's drive),
where the largest C sits (its distance from the wall in dr, its depth below the surface line and its place
along that line, in R) with the volume share of C > 0.5, and the particle disorder (interior particles, up to 3000 of them: the nearest neighbour's
distance over dr, mean and standard deviation, and the standard deviation of the kernel sum
sum_j V_j W_ij).

table: per drum and variant, at each time both resolutions reached, the index change and the RMS
of the mid-chord C profiles' difference (on d_mc / R over the shorter profile) for dr 2 -> 1,
1.0 -> 0.5 and 0.5 -> 0.25 mm, the shear-rate profile's relative RMS change, the observed order where three
resolutions meet (and, where the two changes share their sign, Richardson's limit of the index and the finer
run's distance under it, "to lim%"), and the factor's share: 1 - |change with the variant| / |change of base| at the
same pair and time (1: switching the factor removes the resolution change; 0: no effect; negative:
the variant changes more). --effects: each variant against base (or REF's variant) at the same drum and dr (index,
mid-chord speed, the C profile's RMS, the bed's area), per time.
chart: the index change per refinement step per variant, and with --effects each variant against base
at the same dr beside the noise runs (cfl199, cfl201).
"""
import argparse
import csv
import json
import math
import os
import sys

from tools import ROOT
from tools.studies import batch

CSV = os.path.join(ROOT, "docs", "data", "drum", "seg_refine.csv")
PNG = os.path.join(ROOT, "docs", "data", "drum", "seg_refine.png")
FLOW = ["Material:E=1e4", "Run:cfl_flow=0.2", "Output:dt=2", "Output:diag_dt=0.25", "Run:progress_s=60"]
VARIANTS = {
    "base": [],
    "every1": ["Segregation:every=1"],
    "limnone": ["Segregation:limiter=none"],
    "const": ["Segregation:model=constant", "Segregation:V=1e-4", "Segregation:D=2e-8"],
    "shift05": ["Flow:shift_coeff=0.5"],
    "bd3": ["Flow:bed_damping=3"],
    "chiD2": ["Segregation:chi_D=0.0614"],
    "fill": [],  # Geometry:fill from FILL
    "cfl199": ["Run:cfl_flow=0.199"],
    "yielded": ["Segregation:shear_rate=yielded"],  # eq. (2.7)'s gdot only where the stress is on the static cone
    "yieldedE": ["Segregation:shear_rate=yielded", "Material:E=1e5"],  # E x 10 (after FLOW's 1e4), against yielded
    "yieldlim": ["Segregation:shear_rate=yielded", "Segregation:limiter=none"],  # the limiter's share, against yielded
    "mixemu": ["Segregation:shear_rate=yielded"],  # + chi_D from MIXEMU: dr 0.5 mm's mixing emulated at 0.25 mm
    "area": ["Geometry:fill_by=area"],  # the bed's area the segment's at every dr  # after FLOW's 0.2: the noise floor (below)
}
# The bed's area is N dr^2 of the lattice points inside R - dr/2 below the fill line (src/sim/setup.c,
# drum_disc): against the segment's exact area EV 0.9466, 0.9877, 0.9966 and EN 0.9579, 0.9894, 0.9899 at
# dr 1.0, 0.5, 0.25 mm (the wall's gap of dr/2 and the rows' quantisation of the fill line). The variant
# "fill" moves the fill line by one row where that brings the bed's area to the dr 0.5-mm one's:
# EV 0.9909, (0.9877), 0.9854; EN 0.9866, (0.9894), (0.9899); where no fill is given it is base's run.
FILL = {("EV", 0.001): 0.422857, ("EV", 0.00025): 0.418571, ("EN", 0.001): 0.594286}
# mixemu: the particles' own cross-stream mixing in the flowing layer (gdot >= 10 1/s, docs/seg_refine.md "The
# particles' own mixing", tools/studies/drum_mixing.sh) is 2.09 (EV) and 1.82 (EN) times chi_D gdot d_avg^2 at
# dr 0.5 mm and 0.50 and 0.31 times at 0.25 mm; so at dr 0.25 mm chi_D x (1 + 2.09 - 0.50) = 2.58 (EV) and
# x (1 + 1.82 - 0.31) = 2.51 (EN) gives the layer the total diffusion of dr 0.5 mm. Against yielded at dr 0.5 mm.
MIXEMU = {"EV": 0.0307 * 2.584, "EN": 0.0307 * 2.510}
# (drum, variant, dr m, t_end s), in the order they start (the long ones first; see the budget above)
RUNS = [("EV", "base", 0.001, 10), ("EV", "base", 0.0005, 10),
        ("EV", "cfl199", 0.001, 10), ("EV", "cfl199", 0.0005, 10), ("EV", "area", 0.001, 10),
        ("EV", "area", 0.0005, 10),
        ("EV", "every1", 0.001, 10), ("EV", "every1", 0.0005, 10), ("EV", "base", 0.00025, 10),
        ("EN", "base", 0.001, 10), ("EN", "base", 0.0005, 10), ("EN", "area", 0.001, 10), ("EN", "area", 0.0005, 10),
        ("EN", "cfl199", 0.001, 10), ("EN", "cfl199", 0.0005, 10)] + \
       [("EV", v, dr, 10) for v in ("shift05", "limnone", "const", "bd3", "chiD2") for dr in (0.001, 0.0005)] + \
       [("EV", "fill", 0.001, 10), ("EN", "fill", 0.001, 10), ("EV", "area", 0.00025, 10), ("EV", "fill", 0.00025, 10),
        ("EV", "shift05", 0.00025, 10), ("EN", "base", 0.00025, 10), ("EV", "const", 0.00025, 10),
        ("EV", "bd3", 0.00025, 10)] + \
       [(d, "yielded", dr, 10) for d in ("EV", "EN") for dr in (0.001, 0.0005, 0.00025)] + \
       [(d, "yieldedE", 0.0005, 10) for d in ("EV", "EN")] + \
       [("EV", "yieldlim", dr, 10) for dr in (0.0005, 0.00025)] + \
       [(d, "mixemu", 0.00025, 20) for d in ("EV", "EN")] + \
       [(d, "yielded", 0.000125, 20) for d in ("EV", "EN")]  # 1.6e6 steps, ~1000 s of one H200: by hand in two
# calls, the second with --restart (the script deletes a run's .h5, its checkpoint too; seg_refine.md "A third spacing")
# The variant each is measured against in --effects (base unless named here).
REF = {"yieldedE": "yielded", "yieldlim": "yielded", "mixemu": "yielded"}


def label_of(drum, var, dr):
    return "%s_%s_dr%g" % (drum, var, dr * 1e3)


# ---------------------------------------------------------------- commands

def commands(a):
    runs = [r for r in RUNS if not a.only or label_of(*r[:3]) in a.only]
    if a.t_end:
        runs = [(d, v, dr, a.t_end) for d, v, dr, _ in runs]
    if a.tiny:  # the local check: dr 2 mm, 0.2 s, snapshots every 0.1 s, every run once
        runs = [(d, v, 0.002, 0.2) for d, v in dict.fromkeys((d, v) for d, v, _, _ in RUNS)]
        FILL.update({("EV", 0.002): 0.43, ("EN", 0.002): 0.6})
    lines = ["#!/bin/bash",
             "# seg_refine: issue 57 item 1, one device call (written by python3 -m tools.studies.seg_refine "
             "commands). Run from the repository root:",
             "#   OUT=... BUDGET=460 bash THIS   (defaults below)",
             "set -u",
             "SPHSEG=${SPHSEG:-%s}" % a.sphseg,
             "OUT=${OUT:-%s}" % a.out,
             "SLOTS=${SLOTS:-1}  # one GPU: runs side by side gain nothing (the docstring's budget)",
             "BUDGET=${BUDGET:-%d}" % (3000 if a.tiny else 460),
             "BACKEND=${BACKEND:-%s}" % ("cpu" if a.tiny else "gpu"),
             "PY=${PY:-python3}",
             "export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}",
             "T0=$(date +%s)",
             'mkdir -p "$OUT/res" "$OUT/runs"',
             "one() {  # LABEL SCENE ARGS...: run, analyse, delete the snapshots",
             "  local label=$1 scene=$2; shift 2",
             "  local left=$((T0 + BUDGET - 45 - $(date +%s)))",
             '  if [ "$left" -lt 40 ]; then echo "skipped: ${left} s left" > "$OUT/res/$label.skipped"; return; fi',
             "  local t1=$(date +%s)",
             '  "$SPHSEG" "$scene" --backend "$BACKEND" -o "$OUT/runs/$label" -P Run:max_wall_time=$left "$@" '
             '> "$OUT/runs/$label.log" 2>&1',
             "  local rc=$? t2=$(date +%s)",
             '  tail -n 25 "$OUT/runs/$label.log" > "$OUT/res/$label.log"',
             '  $PY -m tools.studies.seg_refine analyse "$OUT/runs/$label" --json "$OUT/res/$label.json" '
             '--rc $rc --wall $((t2 - t1)) --log "$OUT/runs/$label.log" >> "$OUT/res/$label.log" 2>&1',
             '  rm -f "$OUT/runs/$label"/*.h5',
             '  echo "$label rc $rc wall $((t2 - t1)) s, done at $(( $(date +%s) - T0 )) s"',
             "}",
             "started=0"]
    for drum, var, dr, t_end in runs:
        keys = FLOW + ["Geometry:dr=%g" % dr, "Run:t_end=%g" % t_end] + VARIANTS[var]
        if var == "fill":
            keys.append("Geometry:fill=%g" % FILL[(drum, 0.002 if a.tiny else dr)])
        if var == "mixemu":
            keys.append("Segregation:chi_D=%.4g" % MIXEMU[drum])
        if a.tiny:
            keys = [{"Output:dt=2": "Output:dt=0.1", "Output:diag_dt=0.25": "Output:diag_dt=0.05"}.get(k, k) for k in keys]
        lab = label_of(drum, var, dr)
        lines.append('while [ "$(jobs -rp | wc -l)" -ge "$SLOTS" ]; do wait -n; done')
        lines.append("one %s inputs/drum_2d_%s.yml %s &" % (lab, drum, " ".join("-P '%s'" % k for k in keys)))
        lines.append("sleep 1")
    lines += ["wait", 'echo "all done at $(( $(date +%s) - T0 )) s"',
              '# the device returns a limited number of files: one archive',
              'tar czf "$OUT/seg_refine_res.tgz" -C "$OUT" res && rm -rf "$OUT/res" "$OUT/runs"',
              'ls -l "$OUT"']
    text = "\n".join(lines) + "\n"
    if a.script:
        with open(a.script, "w") as f:
            f.write(text)
        os.chmod(a.script, 0o755)
        print("wrote %s (%d runs)" % (a.script, len(runs)), file=sys.stderr)
    else:
        sys.stdout.write(text)


# ---------------------------------------------------------------- analyse

class GridTree:
    """scipy.spatial.cKDTree's query_ball_point on a uniform grid, for machines without scipy."""

    def __init__(self, x):
        import numpy as np
        self.np, self.x, self.r = np, np.asarray(x), None

    def _build(self, r):
        np = self.np
        self.r = r
        self.ij = np.floor(self.x / r).astype(np.int64)
        self.cells = {}
        for k, key in enumerate(map(tuple, self.ij)):
            self.cells.setdefault(key, []).append(k)

    def query_ball_point(self, p, r):
        np = self.np
        if self.r != r:
            self._build(r)
        i, j = (int(math.floor(p[0] / r)), int(math.floor(p[1] / r)))
        idx = [k for di in (-1, 0, 1) for dj in (-1, 0, 1) for k in self.cells.get((i + di, j + dj), ())]
        if not idx:
            return []
        idx = np.array(idx)
        d = np.hypot(*(self.x[idx] - np.asarray(p)[None, :2]).T)
        return list(idx[d <= r])


def _drum_analysis():
    try:
        import scipy.spatial  # noqa: F401
        tree = "cKDTree"
    except ImportError:  # drum_analysis imports cKDTree: give it the grid
        import types
        sp, sps = types.ModuleType("scipy"), types.ModuleType("scipy.spatial")
        sps.cKDTree = GridTree
        sp.spatial = sps
        sys.modules["scipy"], sys.modules["scipy.spatial"] = sp, sps
        tree = "grid"
    from tools.analysis import drum_analysis
    return drum_analysis, tree


def snapshot_metrics(d, om):
    """The bed's shear-rate noise and the interior's disorder of one drum_analysis.Drum."""
    import numpy as np
    x, R, h, dr = d.x, d.R, d.h, d.dr
    rw = R - np.hypot(x[:, 0], x[:, 1])  # distance from the wall
    depth = (x - d.M) @ d.n  # below the surface line
    inner = (rw > 2 * h) & (depth > 2 * h)
    rigid = np.stack([-om * x[:, 1], om * x[:, 0]], 1)
    bed = inner & (np.hypot(*(d.v - rigid).T) < 0.05 * abs(om) * R)
    w = d.vol * d.gdot * (d.C * (1 - d.C))  # V F ~ gdot F: the segregation flux's drive
    out = {"bed_gdot_mean": float(np.average(d.gdot[bed], weights=d.vol[bed])) if bed.any() else float("nan"),
           "bed_gdot_p90": float(np.percentile(d.gdot[bed], 90)) if bed.any() else float("nan"),
           "bed_drive_share": float(w[bed].sum() / w.sum()) if w.sum() > 0 else float("nan"),
           "bed_volume_share": float(d.vol[bed].sum() / d.vol.sum())}
    # where the largest C sits: its distance from the wall in dr, its depth below the surface line and its
    # place along that line from its midpoint M (in the direction (-n_y, n_x)) in R; and the volume share of C > 0.5
    k = int(np.argmax(d.C))
    out.update({"C_max_wall_dr": float(rw[k] / dr), "C_max_depth_R": float(depth[k] / R),
                "C_max_along_R": float((x[k] - d.M) @ np.array([-d.n[1], d.n[0]]) / R),
                "C_half_volume_share": float(d.vol[d.C > 0.5].sum() / d.vol.sum())})
    sel = np.flatnonzero(inner)
    if len(sel) > 3000:
        sel = np.random.default_rng(1).choice(sel, 3000, replace=False)
    nn, ks = [], []
    norm = 7 / (4 * np.pi * h * h)
    for i in sel:
        idx = np.asarray(d.tree.query_ball_point(x[i], 2 * h))
        r = np.hypot(*(x[idx] - x[i]).T)
        nn.append(np.min(r[r > 0]) / dr if (r > 0).any() else np.nan)
        q = r / h
        ks.append(float(np.sum(d.vol[idx] * (1 - q / 2) ** 4 * (2 * q + 1)) * norm))
    out.update({"nn_mean": float(np.nanmean(nn)) if nn else float("nan"),
                "nn_std": float(np.nanstd(nn)) if nn else float("nan"),
                "ksum_mean": float(np.mean(ks)) if ks else float("nan"),
                "ksum_std": float(np.std(ks)) if ks else float("nan"), "n_interior": int(inner.sum())})
    return out


def analyse(a):
    import numpy as np
    res = {"label": os.path.basename(os.path.normpath(a.rundir)), "rc": a.rc, "wall_s": a.wall, "series": [],
           "profiles": {}}
    try:
        da, res["tree"] = _drum_analysis()
        from tools.analysis import snap
        par = da.used_params(a.rundir)
        g, s = par["Geometry"], par["Segregation"]
        res.update({"dr": float(g["dr"]), "fill": float(g["fill"]), "E": float(par["Material"]["E"]),
                    "chi": float(par["Run"]["cfl_flow"]), "every": str(s.get("every")),
                    "limiter": s.get("limiter"), "model": s.get("model"),
                    "shift_coeff": float(par["Flow"].get("shift_coeff", float("nan"))),
                    "bed_damping": float(par["Flow"].get("bed_damping", float("nan"))),
                    "chi_D": float(s.get("chi_D", float("nan"))), "t_end": float(par["Run"]["t_end"])})
        _, om = da.drum_wall(par)
        for p in snap.list_snapshots(a.rundir):
            d = da.Drum(p, par)
            row = {"t": d.t, "angle": d.angle, "flatness": d.flatness, "speed": d.surface_speed(),
                   "index": d.segregation_index(), "C_min": float(d.C.min()), "C_max": float(d.C.max()),
                   "volume": float(d.vol.sum()), "n": int(len(d.C))}
            if d.t > 0:
                row.update(snapshot_metrics(d, om))
                dm, pts = d.midchord()
                res["profiles"]["%g" % round(d.t, 6)] = {
                    "d": [round(float(v), 6) for v in dm],
                    "speed": [round(float(v), 6) for v in d.interp(pts, d.speed)],
                    "gdot": [round(float(v), 5) for v in d.interp(pts, d.gdot)],
                    "C": [round(float(v), 6) for v in d.interp(pts, d.C)]}
            res["series"].append(row)
        try:
            dg = snap.read_diagnostics(a.rundir, partial=True)
            res["drift_max"] = float(np.abs(dg["small_volume_drift"]).max())
            res["diag_C_min"], res["diag_C_max"] = float(np.min(dg["C_min"])), float(np.max(dg["C_max"]))
        except Exception as e:  # noqa: BLE001
            res["diag_error"] = repr(e)
    except Exception as e:  # noqa: BLE001
        res["error"] = repr(e)
    if a.log and os.path.exists(a.log):
        res["log_done"] = [ln.strip() for ln in open(a.log, errors="replace") if ln.startswith(("done:", "concentr"))]
    with open(a.json, "w") as f:
        json.dump(res, f, separators=(",", ":"), allow_nan=True)
    print("%s: %d snapshots, last t %s, %s" % (res["label"], len(res["series"]),
                                               res["series"][-1]["t"] if res["series"] else "-",
                                               res.get("error", "ok")))


# ---------------------------------------------------------------- table and chart

def load(files):
    runs = {}
    for f in files:
        r = json.load(open(f))
        if "error" in r or "dr" not in r:
            print("skipped %s: %s" % (f, r.get("error", "no parameters")), file=sys.stderr)
            continue
        drum, var, _ = r["label"].split("_")
        r["drum"], r["var"] = drum, var
        r["t_series"] = {round(s["t"], 6): s for s in r["series"]}
        runs[(drum, var, round(r["dr"] * 1e3, 4))] = r
    for (drum, var, dr), r in list(runs.items()):  # fill: base's run where the fill line stays
        if var == "base" and (drum, round(dr * 1e-3, 8)) not in FILL:
            runs.setdefault((drum, "fill", dr), r)
    return runs


def prof_rms(pa, pb, key):
    """RMS over d_mc/R of the difference of two mid-chord profiles (on the shorter's range), and of b's
    magnitude (for a relative figure)."""
    import numpy as np
    da, db = np.array(pa["d"]), np.array(pb["d"])
    ya, yb = np.array(pa[key], float), np.array(pb[key], float)
    top = min(da.max(), db.max())
    q = np.linspace(0, top, 100)
    fa, fb = np.interp(q, da, ya), np.interp(q, db, yb)
    ok = np.isfinite(fa) & np.isfinite(fb)
    return float(np.sqrt(np.mean((fb[ok] - fa[ok]) ** 2))), float(np.sqrt(np.mean(fb[ok] ** 2)))


def table(a):
    runs = load(a.files)
    rows = []
    pairs = ((1.0, 0.5), (0.5, 0.25), (2.0, 1.0))
    for (drum, var, dr), r in sorted(runs.items()):
        for c, f in pairs:
            if dr != f or (drum, var, c) not in runs:
                continue
            rc = runs[(drum, var, c)]
            if var != "base" and rc["var"] == r["var"] == "base":
                continue  # a fill variant whose line stays at both ends: base's own row
            for t in sorted(set(r["t_series"]) & set(rc["t_series"])):
                if t <= 0:
                    continue
                ic, ifn = rc["t_series"][t]["index"], r["t_series"][t]["index"]
                row = {"drum": drum, "variant": var, "dr_coarse_mm": c, "dr_fine_mm": f, "t_s": t,
                       "index_coarse": ic, "index_fine": ifn, "index_change_pct": 100 * (ifn - ic) / ic,
                       "speed_change_pct": 100 * (r["t_series"][t]["speed"] / rc["t_series"][t]["speed"] - 1)}
                key = "%g" % t
                if key in r["profiles"] and key in rc["profiles"]:
                    row["C_rms"] = prof_rms(rc["profiles"][key], r["profiles"][key], "C")[0]
                    g, gm = prof_rms(rc["profiles"][key], r["profiles"][key], "gdot")
                    row["gdot_rel_rms"] = g / gm if gm > 0 else float("nan")
                for k in ("bed_gdot_mean", "bed_drive_share", "ksum_std", "nn_std"):
                    row[k + "_coarse"] = rc["t_series"][t].get(k, float("nan"))
                    row[k + "_fine"] = r["t_series"][t].get(k, float("nan"))
                rows.append(row)
    # the observed order where three resolutions meet, and each factor's share
    by = {(r["drum"], r["variant"], r["dr_fine_mm"], r["t_s"]): r for r in rows}
    for r in rows:
        prev = by.get((r["drum"], r["variant"], r["dr_coarse_mm"], r["t_s"]))
        if prev is not None and abs(r["index_fine"] - r["index_coarse"]) > 0:
            d1, d2 = prev["index_fine"] - prev["index_coarse"], r["index_fine"] - r["index_coarse"]
            r["order_index"], lim = batch.richardson(prev["index_coarse"], r["index_coarse"], r["index_fine"])
            if d1 * d2 > 0 and not math.isnan(lim):  # monotone: Richardson's limit from the three spacings
                r["index_limit"] = lim
                r["fine_to_limit_pct"] = 100 * (lim - r["index_fine"]) / lim
        base = by.get((r["drum"], "base", r["dr_fine_mm"], r["t_s"]))
        if base is not None and r["variant"] != "base" and base["index_change_pct"] != 0:
            r["share_index"] = 1 - abs(r["index_change_pct"]) / abs(base["index_change_pct"])
            if "C_rms" in r and base.get("C_rms"):
                r["share_C_rms"] = 1 - r["C_rms"] / base["C_rms"]
    # the variant's effect at fixed dr
    for r in rows:
        base = runs.get((r["drum"], "base", r["dr_fine_mm"]))
        if base and r["t_s"] in base["t_series"]:
            r["variant_vs_base_fine_pct"] = 100 * (r["index_fine"] / base["t_series"][r["t_s"]]["index"] - 1)
    fields = ["drum", "variant", "dr_coarse_mm", "dr_fine_mm", "t_s", "index_coarse", "index_fine",
              "index_change_pct", "C_rms", "gdot_rel_rms", "speed_change_pct", "order_index", "index_limit",
              "fine_to_limit_pct", "share_index",
              "share_C_rms", "variant_vs_base_fine_pct", "bed_gdot_mean_coarse", "bed_gdot_mean_fine",
              "bed_drive_share_coarse", "bed_drive_share_fine", "ksum_std_coarse", "ksum_std_fine",
              "nn_std_coarse", "nn_std_fine"]
    os.makedirs(os.path.dirname(os.path.abspath(a.csv)), exist_ok=True)
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("%.4g" % r[k] if isinstance(r.get(k), float) else r.get(k, "")) for k in fields})
    print("wrote %s (%d rows)" % (a.csv, len(rows)))
    print("%-3s %-8s %-10s %5s %9s %9s %8s %7s %7s %6s %7s %6s" % ("drm", "variant", "dr", "t", "I coarse", "I fine",
                                                                  "dI %", "C rms", "gd rms", "order", "to lim%",
                                                                  "share"))
    for r in rows:
        print("%-3s %-8s %4g->%-4g %5g %9.4f %9.4f %+8.2f %7.4f %7.3f %6s %7s %6s" % (
            r["drum"], r["variant"], r["dr_coarse_mm"], r["dr_fine_mm"], r["t_s"], r["index_coarse"],
            r["index_fine"], r["index_change_pct"], r.get("C_rms", float("nan")), r.get("gdot_rel_rms", float("nan")),
            "%.2f" % r["order_index"] if "order_index" in r else "",
            "%+.1f" % r["fine_to_limit_pct"] if "fine_to_limit_pct" in r else "",
            "%.2f" % r["share_index"] if "share_index" in r else ""))
    if a.effects:
        effects(runs, a.effects)
    vols = sorted({(d, dr): r["series"][0]["volume"] for (d, v, dr), r in runs.items() if v == "base"
                   if r["series"] and r["series"][0]["t"] == 0}.items())
    if vols:
        print("bed volume at t = 0 (m^2 per m): " + ", ".join("%s dr %g: %.6e" % (d, dr, v) for (d, dr), v in vols))


def effects(runs, path):
    """Each variant against base (or its REF) at the same drum and dr: the index (%), the mid-chord speed (%)
    and the RMS of the mid-chord C profiles' difference, per time both reached."""
    rows = []
    for (drum, var, dr), r in sorted(runs.items()):
        b = runs.get((drum, REF.get(var, "base"), dr))
        if var == "base" or b is None or b is r:
            continue
        for t in sorted(set(r["t_series"]) & set(b["t_series"])):
            if t <= 0:
                continue
            s, sb = r["t_series"][t], b["t_series"][t]
            row = {"drum": drum, "variant": var, "ref": REF.get(var, "base"), "dr_mm": dr, "t_s": t, "index_base": sb["index"],
                   "index": s["index"], "index_vs_base_pct": 100 * (s["index"] / sb["index"] - 1),
                   "speed_vs_base_pct": 100 * (s["speed"] / sb["speed"] - 1),
                   "area_vs_base_pct": 100 * (r["series"][0]["volume"] / b["series"][0]["volume"] - 1)}
            k = "%g" % t
            if k in r["profiles"] and k in b["profiles"]:
                row["C_rms_vs_base"] = prof_rms(b["profiles"][k], r["profiles"][k], "C")[0]
            rows.append(row)
    fields = ["drum", "variant", "ref", "dr_mm", "t_s", "index_base", "index", "index_vs_base_pct", "C_rms_vs_base",
              "speed_vs_base_pct", "area_vs_base_pct"]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("%.4g" % r[k] if isinstance(r.get(k), float) else r.get(k, "")) for k in fields})
    print("wrote %s (%d rows)" % (path, len(rows)))
    for r in rows:
        print("%-3s %-8s dr %-4g t %4g  index %+6.1f %%  C rms %.4f  speed %+5.1f %%  area %+5.1f %%" % (
            r["drum"], r["variant"], r["dr_mm"], r["t_s"], r["index_vs_base_pct"], r.get("C_rms_vs_base", float("nan")),
            r["speed_vs_base_pct"], r["area_vs_base_pct"]))


def chart(a):
    """Left: the index change per refinement step, per drum and variant; right (with --effects): each
    variant against base at the same dr, the runs a step 0.5 % off (cfl199, cfl201) drawn as the noise."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = list(csv.DictReader(open(a.csv)))
    eff = list(csv.DictReader(open(a.effects))) if a.effects else []
    drums = sorted({r["drum"] for r in rows} | {r["drum"] for r in eff})
    ncol = 2 if eff else 1
    fig, ax = plt.subplots(len(drums), ncol, figsize=(6 * ncol, 3.8 * len(drums)), squeeze=False)
    for k, drum in enumerate(drums):
        rs = [r for r in rows if r["drum"] == drum]
        for var in sorted({r["variant"] for r in rs}, key=lambda v: (v != "base", v)):
            for r0 in sorted({(r["dr_coarse_mm"], r["dr_fine_mm"]) for r in rs if r["variant"] == var}):
                p = sorted((r for r in rs if r["variant"] == var and (r["dr_coarse_mm"], r["dr_fine_mm"]) == r0),
                           key=lambda r: float(r["t_s"]))
                ax[k][0].plot([float(r["t_s"]) for r in p], [float(r["index_change_pct"]) for r in p],
                              "o-" if var == "base" else "s--", lw=2.5 if var == "base" else 1, ms=4,
                              label="%s, dr %s -> %s mm" % (var, *r0))
        if not rs:
            ax[k][0].text(0.5, 0.5, "no pair of resolutions measured", ha="center", transform=ax[k][0].transAxes)
        ax[k][0].axhspan(-3, 3, color="0.92", zorder=0)
        ax[k][0].set_ylabel("%s: index change per refinement, %%" % drum)
        ax[k][0].set_xlabel("t, s")
        ax[k][0].grid(alpha=0.3)
        ax[k][0].legend(fontsize=7)
        if not eff:
            continue
        es = [r for r in eff if r["drum"] == drum]
        for dr in sorted({r["dr_mm"] for r in es}, key=float):
            noise = [r for r in es if r["dr_mm"] == dr and r["variant"].startswith("cfl")]
            ts = sorted({float(r["t_s"]) for r in noise})
            if ts:
                lo = [min([0.0] + [float(r["index_vs_base_pct"]) for r in noise if float(r["t_s"]) == t]) for t in ts]
                hi = [max([0.0] + [float(r["index_vs_base_pct"]) for r in noise if float(r["t_s"]) == t]) for t in ts]
                ax[k][1].fill_between(ts, lo, hi, alpha=0.15, label="step 0.5 %% off (noise), dr %s mm" % dr)
            for var in sorted({r["variant"] for r in es if r["dr_mm"] == dr and not r["variant"].startswith("cfl")}):
                p = sorted((r for r in es if r["dr_mm"] == dr and r["variant"] == var), key=lambda r: float(r["t_s"]))
                ax[k][1].plot([float(r["t_s"]) for r in p], [float(r["index_vs_base_pct"]) for r in p], "o-", ms=4,
                              label="%s%s, dr %s mm" % (var, "" if p[0].get("ref", "base") == "base"
                                                            else " (against %s)" % p[0]["ref"], dr))
        ax[k][1].axhline(0, color="0.5", lw=0.8)
        ax[k][1].set_ylabel("%s: index against base (or ref) at the same dr, %%" % drum)
        ax[k][1].set_xlabel("t, s")
        ax[k][1].grid(alpha=0.3)
        ax[k][1].legend(fontsize=7)
    fig.suptitle("2D drums, E 10 kPa, chi 0.2, the scenes' flow:\nthe segregation index under refinement"
                 "%s (%s)" % (" and against each factor" if ncol > 1 else "", a.machine), fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


def c_peak(p, below=0.15):
    """The peak of a mid-chord C profile (p: d / R, C): its C, its depth d / R, and its full width (d / R) at
    half its rise over the C `below` R deeper; the width is read on the profile's own points."""
    import numpy as np
    d, C = np.asarray(p["d"], float), np.asarray(p["C"], float)
    k = int(np.argmax(C))
    half = 0.5 * (C[k] + np.interp(d[k] + below, d, C))
    lo = hi = k
    while lo > 0 and C[lo] > half:
        lo -= 1
    while hi < len(C) - 1 and C[hi] > half:
        hi += 1
    return float(C[k]), float(d[k]), float(d[hi] - d[lo])


def profiles(a):
    """One variant's runs' (--variant, base by default) mid-chord profiles of C and of the shear rate at
    each dr (rows: drums; columns: the times asked, C above the shear rate), from the runs' JSONs; prints
    each profile's C peak (c_peak: its height, depth and width at half height)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs = {k: r for k, r in load(a.files).items() if k[1] == a.variant}
    drums = sorted({k[0] for k in runs})
    fig, ax = plt.subplots(2 * len(drums), len(a.times), figsize=(4.2 * len(a.times), 3.2 * 2 * len(drums)),
                           squeeze=False, sharex=True)
    for k, drum in enumerate(drums):
        for m, t in enumerate(a.times):
            key = "%g" % t
            for (d_, _, dr), r in sorted(runs.items(), key=lambda kv: -kv[0][2]):
                if d_ != drum or key not in r["profiles"]:
                    continue
                p = r["profiles"][key]
                print("%s dr %g mm t %g s: C peak %.3f at d/R %.3f, width %.3f R" % ((drum, dr, t) + c_peak(p)))
                for row, q, lab in ((2 * k, "C", "C"), (2 * k + 1, "gdot", "shear rate, 1/s")):
                    ax[row][m].plot(p["d"], p[q], lw=1.5, label="dr %g mm" % dr)
                    ax[row][m].set_ylabel("%s: %s" % (drum, lab))
            for row in (2 * k, 2 * k + 1):
                ax[row][m].set_title("%s, t = %g s" % (drum, t), fontsize=9)
                ax[row][m].grid(alpha=0.3)
                ax[row][m].legend(fontsize=7)
    for m in range(len(a.times)):
        ax[-1][m].set_xlabel("depth below the surface on the mid-chord, d / R")
    fig.suptitle("2D drums, E 10 kPa, chi 0.2, the scenes' flow: mid-chord profiles under refinement (%s)"
                 % a.machine, fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png, dpi=100)
    print("wrote %s" % a.png)


def _against_t40(ref_csv, files):
    """(drum, t, j, index, I_0.5, I_0.25) for each run's point (its JSON j) at an even second that the 40-s
    table (ref_csv) has for yielded at dr 0.5 and 0.25 mm, t > 0."""
    import csv
    ref = {}
    with open(ref_csv) as fh:
        for r in csv.DictReader(fh):
            if r["variant"] == "yielded" and r["dr_coarse_mm"] == "0.5" and r["dr_fine_mm"] == "0.25":
                ref[(r["drum"], round(float(r["t_s"])))] = (float(r["index_coarse"]), float(r["index_fine"]))
    for f in files:
        with open(f) as fh:
            j = json.load(fh)
        drum = j["label"].split("_")[0]
        for p in j["series"]:
            k = (drum, round(p["t"]))
            if k in ref and abs(p["t"] - k[1]) < 1e-6 and k[1] > 0:
                yield (drum, k[1], j, p["index"]) + ref[k]


def _write_rows(path, rows):
    import csv
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print(" ".join("%s" % v for v in r.values()))
    print("wrote %s" % path)


def mixemu(a):
    """The mixemu runs (dr 0.25 mm, chi_D raised by the dr-0.5-mm mixing) beside yielded's index at dr 0.5 and
    0.25 mm from the 40-s table (--ref): one row per drum and even second."""
    rows = []
    for drum, t, j, x, c, fn in _against_t40(a.ref, a.files):
        rows.append({"drum": drum, "t_s": t, "chi_D": "%.4g" % j["chi_D"], "index_dr0.5": "%.4g" % c,
                     "index_dr0.25": "%.4g" % fn, "index_mixemu_dr0.25": "%.4g" % x,
                     "dr0.25_vs_dr0.5_pct": "%.2f" % (100 * (fn / c - 1)),
                     "mixemu_vs_dr0.5_pct": "%.2f" % (100 * (x / c - 1)),
                     "mixemu_vs_dr0.25_pct": "%.2f" % (100 * (x / fn - 1))})
    _write_rows(a.csv, rows)


def third(a):
    """The third spacing: yielded at dr 0.125 mm (its runs' JSONs) beside yielded's index at dr 0.5 and 0.25 mm
    from the 40-s table (--ref): one row per drum and even second, with the changes per halving, the observed
    order p = log2(change 0.5->0.25 / change 0.25->0.125) where both have one sign, and Richardson's limit
    I_0.125 + change_0.25->0.125 / (2^p - 1); the CSV and a chart of the index against dr."""
    rows = []
    for drum, t, j, fn, c, m in _against_t40(a.ref, a.files):
        e1, e2 = m - c, fn - m
        order = math.log2(e1 / e2) if e1 * e2 > 0 and e1 / e2 > 1 else float("nan")
        lim = fn + e2 / (2 ** order - 1) if order == order else float("nan")
        rows.append({"drum": drum, "t_s": t, "index_dr0.5": "%.4g" % c, "index_dr0.25": "%.4g" % m,
                     "index_dr0.125": "%.4g" % fn, "change_0.5_0.25_pct": "%.2f" % (100 * e1 / c),
                     "change_0.25_0.125_pct": "%.2f" % (100 * e2 / m), "order": "%.2f" % order,
                     "limit": "%.4g" % lim, "dr0.125_to_limit_pct": "%.2f" % (100 * (fn / lim - 1))})
    rows.sort(key=lambda r: (r["drum"], r["t_s"]))
    _write_rows(a.csv, rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    drums = sorted({r["drum"] for r in rows})
    fig, ax = plt.subplots(1, len(drums), figsize=(5.2 * len(drums), 3.8), squeeze=False)
    for k, drum in enumerate(drums):
        x = ax[0][k]
        for r in rows:
            if r["drum"] != drum or r["t_s"] % 4 != 0 and r["t_s"] != 10:
                continue
            v = [float(r["index_dr0.5"]), float(r["index_dr0.25"]), float(r["index_dr0.125"])]
            x.plot([0.5, 0.25, 0.125], [y / v[-1] for y in v], "o-", label="t = %d s" % r["t_s"])
        x.set_xscale("log", base=2)
        x.set_xticks([0.5, 0.25, 0.125], ["0.5", "0.25", "0.125"])
        x.invert_xaxis()
        x.axhspan(0.97, 1.03, color="0.9", zorder=0)
        x.set_xlabel("dr, mm")
        x.set_ylabel("segregation index / its value at dr 0.125 mm")
        x.set_title("%s drum, yielded (grey: within 3 %%)" % drum)
        x.legend(fontsize=7)
    fig.suptitle("The 2D drums at three spacings (%s)" % a.machine, fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


def stiff(a):
    """E x 10: the yieldedE runs (Material:E 1e5, its JSONs) beside yielded at E 1e4 and the same dr from the 40-s
    table (--ref, dr 0.5 or 0.25 mm): one row per drum and even second; the CSV and a chart of the change against t."""
    rows = []
    for drum, t, j, x, c, fn in _against_t40(a.ref, a.files):
        ref = {0.0005: c, 0.00025: fn}.get(round(j["dr"], 6))
        if ref is None:
            continue
        rows.append({"drum": drum, "dr_mm": j["dr"] * 1e3, "t_s": t, "index_E1e4": "%.4g" % ref,
                     "index_E1e5": "%.4g" % x, "change_pct": "%.2f" % (100 * (x / ref - 1))})
    rows.sort(key=lambda r: (r["drum"], r["dr_mm"], r["t_s"]))
    _write_rows(a.csv, rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for drum in sorted({r["drum"] for r in rows}):
        sel = [r for r in rows if r["drum"] == drum]
        ax.plot([r["t_s"] for r in sel], [float(r["change_pct"]) for r in sel], "o-", ms=3,
                label="%s drum, dr %g mm" % (drum, sel[0]["dr_mm"]))
    ax.axhspan(-3, 3, color="0.9", zorder=0)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("t, s")
    ax.set_ylabel("index at E 0.1 MPa / at 10 kPa - 1, %")
    ax.set_title("E x 10, yielded (grey: within 3 %%; %s)" % a.machine, fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)
    print("wrote %s" % a.png)


def area(a):
    """The fill by area at three spacings: the area runs' JSONs (Geometry:fill_by area, yielded, dr 0.5, 0.25,
    0.125 mm) beside the lattice fill's yielded runs (0.5, 0.25 mm from the 40-s table --ref, 0.125 mm from
    --lattice JSONs): one row per drum and even second, with each fill's change per halving."""
    lat = {}
    for f in a.lattice or []:
        with open(f) as fh:
            j = json.load(fh)
        for p in j["series"]:
            lat[(j["label"].split("_")[0], round(p["t"], 6))] = p["index"]
    runs = {}
    for f in a.files:
        with open(f) as fh:
            j = json.load(fh)
        runs[(j["label"].split("_")[0], round(j["dr"], 6))] = {round(p["t"], 6): p["index"] for p in j["series"]}
    rows = []
    for drum, t, j, x, c, m in _against_t40(a.ref, a.files):
        if round(j["dr"], 6) != 0.000125:
            continue
        ar = [runs.get((drum, dr), {}).get(float(t)) for dr in (0.0005, 0.00025, 0.000125)]
        fine = lat.get((drum, float(t)))
        if None in ar or fine is None:
            continue
        rows.append({"drum": drum, "t_s": t, "lattice_dr0.5": "%.4g" % c, "lattice_dr0.25": "%.4g" % m,
                     "lattice_dr0.125": "%.4g" % fine, "area_dr0.5": "%.4g" % ar[0], "area_dr0.25": "%.4g" % ar[1],
                     "area_dr0.125": "%.4g" % ar[2], "lattice_0.5_0.25_pct": "%.2f" % (100 * (m / c - 1)),
                     "lattice_0.25_0.125_pct": "%.2f" % (100 * (fine / m - 1)),
                     "area_0.5_0.25_pct": "%.2f" % (100 * (ar[1] / ar[0] - 1)),
                     "area_0.25_0.125_pct": "%.2f" % (100 * (ar[2] / ar[1] - 1))})
    rows.sort(key=lambda r: (r["drum"], r["t_s"]))
    _write_rows(a.csv, rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="what", required=True)
    c = sub.add_parser("commands")
    c.add_argument("--sphseg", default="local/sphseg_gpu")
    c.add_argument("--out", default="out/seg_refine", help="the runs' root where $OUT is not set (the device sets it)")
    c.add_argument("--script", help="write the script here (default: stdout)")
    c.add_argument("--only", nargs="+", help="only these runs (labels such as EV_base_dr0.25)")
    c.add_argument("--tiny", action="store_true", help="every run at dr 2 mm for 0.2 s, on the CPU (a local check)")
    c.add_argument("--t_end", type=float, help="run the selected runs to this time, s, instead of RUNS' (the same "
                   "labels: a longer run's analysis holds the shorter one's times)")
    n = sub.add_parser("analyse")
    n.add_argument("rundir")
    n.add_argument("--json", required=True)
    n.add_argument("--rc", type=int, default=0)
    n.add_argument("--wall", type=float, default=float("nan"))
    n.add_argument("--log")
    t = sub.add_parser("table")
    t.add_argument("files", nargs="+")
    t.add_argument("--csv", default=CSV)
    t.add_argument("--effects", help="also write each variant against base at the same dr to this CSV")
    h = sub.add_parser("chart")
    h.add_argument("--csv", default=CSV)
    h.add_argument("--png", default=PNG)
    h.add_argument("--effects", help="the table's --effects CSV: a second column of panels")
    h.add_argument("--machine", default="development machine", help="the runs' machine, for the title")
    f = sub.add_parser("profiles")
    f.add_argument("files", nargs="+")
    f.add_argument("--times", type=float, nargs="+", default=[6.0, 10.0])
    f.add_argument("--variant", default="base", help="the variant whose runs are drawn")
    f.add_argument("--png", default=PNG.replace(".png", "_profiles.png"))
    f.add_argument("--machine", default="development machine", help="the runs' machine, for the title")
    def against_t40(name, files_help, csv_tail, png_tail=None):  # the subcommands read against the 40-s table
        q = sub.add_parser(name)
        q.add_argument("files", nargs="+", help=files_help)
        q.add_argument("--ref", default=CSV.replace(".csv", "_h200_t40.csv"),
                       help="the 40-s table (yielded at 0.5, 0.25 mm)")
        q.add_argument("--csv", default=CSV.replace(".csv", csv_tail))
        if png_tail:
            q.add_argument("--png", default=PNG.replace(".png", png_tail))
            q.add_argument("--machine", default="one H200 a run", help="the runs' machine, for the title")
        return q
    against_t40("mixemu", "the mixemu runs' JSONs", "_mixemu.csv")
    against_t40("third", "the dr 0.125-mm runs' JSONs (yielded)", "_dr0125.csv", "_dr0125.png")
    against_t40("stiff", "the yieldedE runs' JSONs", "_E10.csv", "_E10.png")
    against_t40("area", "the area runs' JSONs (yielded, Geometry:fill_by area; dr 0.5, 0.25, 0.125 mm)",
                "_area.csv").add_argument("--lattice", nargs="+", help="yielded's dr 0.125-mm JSONs (the lattice fill)")
    a = ap.parse_args()
    {"commands": commands, "analyse": analyse, "table": table, "chart": chart, "profiles": profiles,
     "mixemu": mixemu, "third": third, "stiff": stiff, "area": area}[a.what](a)


if __name__ == "__main__":
    main()
