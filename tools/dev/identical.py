#!/usr/bin/env python3
"""Are two sphseg binaries bit-identical on every scene of inputs/?

For a change that must not change results (a refactoring, a new build of
the same code), run every inputs/*.yml scene for a few steps with each
binary under the same overrides and compare what the runs wrote:

  - every snapshot_NNNNN.h5: the /Particles and /Topology datasets byte for
    byte (and their dtype, shape and attributes), the /Header attributes but
    Version, and the set of groups;
  - diagnostics.csv: the columns, and every column but wall_s, row by row,
    as text;
  - the two checkpoints (checkpoint.h5, checkpoint_prev.h5): every dataset
    byte for byte (the store's arrays, /Particles/00, 01, ..., by their index
    in the field table: a reordered table changes these and breaks restarts
    from older checkpoints, though snapshots stay the same) and every
    group's attributes but Version.

One line per scene, IDENTICAL or DIFFERS: what (or FAILED: a run's exit
status); exit status 1 on any difference or failure, 0 when all agree. Where
the last snapshot's /Particles/Concentration differs, the first DIFFERS line
is its size: max |dC| over the particles (matched by ParticleIDs) and that
relative to the range of C, as issue 54 measured it.

Each scene is sized to seconds: a probe run of the --before binary (1 step)
gives its particle count, and a scene above --max-particles (the 3D ones)
runs at a coarser Geometry:dr, scaled for that count; a second probe (N
steps, no snapshots) gives the time t_N the N steps reach, and both runs
then take Output:dt = t_N/3, Output:diag_dt = t_N/8 and
Output:checkpoint_dt = t_N/2, so that they write three or four snapshots
(t = 0, two in between, the last step's), about ten diagnostics rows and
two checkpoints (checkpoints never shorten a step: the run is the run
without them). The probes only choose the overrides; both compared
runs take the same ones.

After the scenes, the longer CASES (a scene, its overrides and a length;
--no-cases leaves them out, --only matches their names as well), each
compared as the scenes are:

  - shearbox_paper: the paper's shear box as issue 54 ran it (dr/H = 0.04,
    Geometry:dr = 0.00348 m, 275 grains; two periods, Run:t_end = 26 s, 120
    steps; a snapshot and a checkpoint each period; Segregation:every = 1 as
    the issue gave it, which prescribed flow takes anyway). Where its two
    pure layers meet, the front's tails hold pairs whose upper particle has
    fewer small grains than the lower one, both within 1.2e-3 of 0 or 1:
    the pairs the donor limiter caps (Segregation:limiter donor,
    seg_flux_donor in src/physics/seg_kern.h, the default since ddf2649,
    which moved this run's final C by 4.8e-9 of its range). The cap first
    binds after 1.2-1.5 s of flow (in step 7 here, C 5e-23 off after it;
    in step 11 at the scene's own dr, whose 40 steps reach t = 4.1 s and
    2.2e-8), and never in the drums, which start well mixed (C0 = 0.5).
    Under a second a run.
  - drum_2d_EV_300: the 2D drum (sized as the scenes are) for 300 steps with
    C advanced in every flow step (Segregation:every = 1), the segregation
    path under computed flow, which Segregation:every auto visits once in
    up to 100 steps; 6-12 s a run on one core (ddf2649's drum, b6d4235's
    with the corrected gradient and shifting), three runs with the probe.

A binary older than a key that the scene files name refuses them (exit 2,
'unknown key'; issue 54's 8fd0bc8 and inputs/ naming Segregation:limiter):
give --inputs that binary's own tree's inputs/, which both sides then read
(the newer one takes its defaults for the keys they leave out). A binary
whose snapshots hold other groups (8fd0bc8's have no /Topology) DIFFERS on
those as well, after the data. --before-args / --after-args give one side
extra arguments, e.g. to see that a difference is caught:

  /usr/bin/python3 -m tools.dev.identical --before /tmp/orig/build/sphseg --after build/sphseg
  /usr/bin/python3 -m tools.dev.identical --before B --after A --ranks 2 --only 'drum_2d_EV|silo'
  /usr/bin/python3 -m tools.dev.identical --before B --after B --only column --after-args='-P Flow:alpha_av=0.11'
  /usr/bin/python3 -m tools.dev.identical --before /tmp/old/build/sphseg --after build/sphseg \
      --inputs /tmp/old/inputs --only shearbox
"""
import argparse
import csv
import glob
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np
import yaml

from tools import ROOT  # noqa: E402
HEAD = re.compile(r"(\d+) material \+ (\d+) dummy particles")
COMPARED_GROUPS = ("Particles", "Topology")  # byte for byte
SKIP_HEADER = {"Version"}
SKIP_DIAG = {"wall_s"}
CHECKPOINTS = ("checkpoint_prev.h5", "checkpoint.h5")  # full state, the store's arrays by index
MAX_OUTPUTS = 1e5  # Output:dt may ask for at most this many snapshots up to Run:t_end (src/settings_check.c)
# The longer cases (see the docstring): (name, scene file in --inputs, -P
# overrides, steps). steps None: the run as the scene and the overrides give
# it (its own t_end and Output:dt); a number: sized as the scenes are
# (overrides()) for that many steps. --set overrides come after a case's own.
CASES = (
    ("shearbox_paper", "shearbox_2d.yml",
     {"Geometry:dr": "0.00348", "Run:t_end": "26", "Output:dt": "13", "Output:checkpoint_dt": "13",
      "Segregation:every": "1"}, None),
    ("drum_2d_EV_300", "drum_2d_EV.yml", {"Segregation:every": "1"}, 300),
)


class RunFailed(Exception):
    pass


def sig(x, digits=6):
    """x as text with `digits` significant digits (an override both sides read alike)."""
    return "%.*g" % (digits, x)


def launcher(ranks):
    if not ranks:
        return []
    cmd = ["mpirun", "--oversubscribe", "-np", str(ranks)]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.insert(1, "--allow-run-as-root")
    return cmd


def run(args, binary, scene, outdir, over, extra=(), ranks=None):
    """Run binary on scene into outdir with the -P overrides `over` (a dict);
    returns its output. Raises RunFailed on a non-zero exit or a timeout."""
    cmd = launcher(ranks) + [binary, scene, "-o", outdir, "--overwrite", "--backend", args.backend]
    for k, v in over.items():
        cmd += ["-P", "%s=%s" % (k, v)]
    cmd += list(extra)
    env = dict(os.environ, OMP_NUM_THREADS=str(args.threads))
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                           timeout=args.timeout, cwd=ROOT)
    except subprocess.TimeoutExpired:
        raise RunFailed("%s timed out after %g s" % (os.path.basename(binary), args.timeout))
    if p.returncode != 0:
        tail = [l for l in p.stdout.splitlines() if l.strip()][-1:] or ["(no output)"]
        old = "unknown key" in tail[0]
        hint = " (a binary older than the scene's keys: --inputs its own tree's inputs/)" if old else ""
        raise RunFailed("%s exited %d: %s%s" % (" ".join(cmd[len(launcher(ranks)):][:2]), p.returncode, tail[0], hint))
    return p.stdout


def geometry(outdir):
    """(dim, dr) from the run's used_params.yml."""
    with open(os.path.join(outdir, "used_params.yml")) as f:
        g = yaml.safe_load(f)["Geometry"]
    return int(g["dim"]), float(g["dr"])


def last_time(outdir):
    with open(os.path.join(outdir, "diagnostics.csv")) as f:
        rows = list(csv.DictReader(f))
    return float(rows[-1]["time"])


def last_step(outdir):
    with open(os.path.join(outdir, "diagnostics.csv")) as f:
        rows = list(csv.DictReader(f))
    return int(rows[-1]["step"])


def overrides(args, scene, work, steps, own=None):
    """The -P overrides both sides take for this scene run for `steps` steps,
    `own` (a case's) before --set (see the docstring)."""
    over = {"Run:max_steps": 1, "Output:snapshots": "on"}  # the first probe: the particle count
    over.update(own or {})
    over.update(args.set)
    probe = os.path.join(work, "probe")
    for _ in range(4):  # coarsen until the scene holds at most about max_particles
        out = run(args, args.before, scene, probe, over)
        m = HEAD.search(out)
        count = int(m.group(1)) + int(m.group(2)) if m else 0
        dim, dr = geometry(probe)
        if count <= 1.15 * args.max_particles:
            break
        dr = float(sig(dr * (count / args.max_particles) ** (1.0 / dim), 4))
        over["Geometry:dr"] = dr
    over.update({"Run:max_steps": steps, "Output:snapshots": "off"})
    run(args, args.before, scene, probe, over)
    t_n = last_time(probe)
    with open(os.path.join(probe, "used_params.yml")) as f:
        t_end = float(yaml.safe_load(f)["Run"]["t_end"])
    shutil.rmtree(probe, ignore_errors=True)
    if t_n <= 0:
        raise RunFailed("the probe's %d steps reached t = %g" % (steps, t_n))
    over.update({"Output:snapshots": "on", "Output:dt": sig(t_n / 3), "Output:diag_dt": sig(t_n / 8),
                 "Output:checkpoint_dt": sig(t_n / 2)})
    if t_end / float(over["Output:dt"]) > MAX_OUTPUTS:  # the run stops at max_steps long before
        over["Run:t_end"] = sig(1000 * t_n)
    return over, "%d particles" % count


def same_value(a, b):
    if isinstance(a, (str, bytes)) or isinstance(b, (str, bytes)):
        return type(a) is type(b) and a == b
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def describe_text(a, b):
    """The first line where two attribute values differ (texts such as Scene)."""
    la, lb = str(a).splitlines(), str(b).splitlines()
    for k in range(max(len(la), len(lb))):
        x = la[k] if k < len(la) else None
        y = lb[k] if k < len(lb) else None
        if x != y:
            return "line %d %r against %r" % (k + 1, x, y)
    return "%r against %r (types %s, %s)" % (str(a)[:60], str(b)[:60], type(a).__name__, type(b).__name__)


def describe_diff(a, b):
    """Where two arrays of one dtype and shape differ."""
    ne = a != b
    if a.dtype.kind == "f":
        ne &= ~(np.isnan(a) & np.isnan(b))
        ne |= np.signbit(a) != np.signbit(b)  # -0.0 against 0.0
    k = int(np.count_nonzero(ne))
    if k == 0:
        return "same values, different bytes"
    first = np.argwhere(ne)[0]
    s = "%d of %d values differ, first at %s (%r, %r)" % (k, ne.size, tuple(int(i) for i in first),
                                                           a[tuple(first)].item(), b[tuple(first)].item())
    if a.dtype.kind in "fiu":
        d = np.abs(a.astype(np.float64) - b.astype(np.float64))
        s += ", max |diff| %.3g" % float(np.nanmax(d))
    return s


def datasets(group):
    out = {}
    group.visititems(lambda name, obj: out.__setitem__(name, obj) if isinstance(obj, h5py.Dataset) else None)
    return out


def compare_snapshot(pa, pb, skip_header=SKIP_HEADER):
    """The differences between two snapshot files, as a list of lines."""
    diffs = []
    with h5py.File(pa, "r") as fa, h5py.File(pb, "r") as fb:
        if set(fa.keys()) != set(fb.keys()):
            diffs.append("groups %s against %s" % (sorted(fa.keys()), sorted(fb.keys())))
        ha = fa["Header"].attrs if "Header" in fa else {}
        hb = fb["Header"].attrs if "Header" in fb else {}
        ka, kb = set(ha.keys()) - skip_header, set(hb.keys()) - skip_header
        if ka != kb:
            diffs.append("/Header attributes %s against %s" % (sorted(ka), sorted(kb)))
        for k in sorted(ka & kb):
            if not same_value(ha[k], hb[k]):
                diffs.append("/Header %s: %s" % (k, describe_text(ha[k], hb[k])))
        for g in COMPARED_GROUPS:
            diffs += compare_datasets(fa, fb, g)
    return diffs


def compare_datasets(fa, fb, g):
    """Group g's datasets in two open files: names, dtype, shape, bytes, attributes."""
    if (g in fa) != (g in fb):
        return ["/%s in one file only" % g]
    if g not in fa:
        return []
    diffs = []
    da, db = datasets(fa[g]), datasets(fb[g])
    if set(da) != set(db):
        diffs.append("/%s datasets %s against %s" % (g, sorted(da), sorted(db)))
    for name in sorted(set(da) & set(db)):
        a, b, where = da[name], db[name], "/%s/%s" % (g, name)
        if a.dtype != b.dtype or a.shape != b.shape:
            diffs.append("%s: %s%s against %s%s" % (where, a.dtype, a.shape, b.dtype, b.shape))
            continue
        va, vb = np.asarray(a[()]), np.asarray(b[()])
        if va.tobytes() != vb.tobytes():
            diffs.append("%s: %s" % (where, describe_diff(va, vb)))
        if set(a.attrs) != set(b.attrs) or any(not same_value(a.attrs[k], b.attrs[k]) for k in a.attrs):
            diffs.append("%s: attributes differ" % where)
    return diffs


def compare_checkpoint(pa, pb, skip_header):
    """The differences between two checkpoints: every group's datasets byte for
    byte (the store's arrays are /Particles/00, 01, ... in the order of the
    field table, src/core/fields.h) and every group's attributes but Version."""
    diffs = []
    with h5py.File(pa, "r") as fa, h5py.File(pb, "r") as fb:
        if set(fa.keys()) != set(fb.keys()):
            return ["groups %s against %s" % (sorted(fa.keys()), sorted(fb.keys()))]
        for g in sorted(fa.keys()):
            aa, ab = fa[g].attrs, fb[g].attrs
            ka, kb = set(aa.keys()) - skip_header, set(ab.keys()) - skip_header
            if ka != kb:
                diffs.append("/%s attributes %s against %s" % (g, sorted(ka), sorted(kb)))
            for k in sorted(ka & kb):
                if not same_value(aa[k], ab[k]):
                    diffs.append("/%s %s: %s" % (g, k, describe_text(aa[k], ab[k])))
            diffs += compare_datasets(fa, fb, g)
    return diffs


def compare_diagnostics(pa, pb):
    with open(pa) as f:
        ra = list(csv.reader(f))
    with open(pb) as f:
        rb = list(csv.reader(f))
    if not ra or not rb:
        return ["diagnostics.csv empty"]
    if ra[0] != rb[0]:
        return ["diagnostics.csv columns %s against %s" % (ra[0], rb[0])]
    if len(ra) != len(rb):
        return ["diagnostics.csv %d rows against %d" % (len(ra) - 1, len(rb) - 1)]
    diffs = []
    for c, name in enumerate(ra[0]):
        if name in SKIP_DIAG:
            continue
        bad = [r for r in range(1, len(ra)) if ra[r][c] != rb[r][c]]
        if bad:
            r = bad[0]
            diffs.append("diagnostics.csv %s: %d of %d rows differ, first row %d (%s against %s)"
                         % (name, len(bad), len(ra) - 1, r, ra[r][c], rb[r][c]))
    return diffs


def final_c(da, db):
    """The last common snapshot's /Particles/Concentration in two runs, matched
    by ParticleIDs: a line giving max |dC| and that relative to the range of
    C, or None where they agree or cannot be matched."""
    common = sorted(set(os.path.basename(p) for p in glob.glob(os.path.join(da, "snapshot_*.h5")))
                    & set(os.path.basename(p) for p in glob.glob(os.path.join(db, "snapshot_*.h5"))))
    if not common:
        return None
    cs = []
    for d in (da, db):
        with h5py.File(os.path.join(d, common[-1]), "r") as f:
            if "Particles/Concentration" not in f or "Particles/ParticleIDs" not in f:
                return None
            ids, c = f["Particles/ParticleIDs"][()], f["Particles/Concentration"][()]
            t = f["Header"].attrs.get("Time") if "Header" in f else None
        order = np.argsort(ids, kind="stable")
        cs.append((ids[order], np.asarray(c[order], dtype=np.float64), t))
    (ia, ca, t), (ib, cb, _) = cs
    if ia.shape != ib.shape or (ia != ib).any() or ca.shape != cb.shape or ca.tobytes() == cb.tobytes():
        return None
    d = np.abs(ca - cb)
    span = float(np.nanmax(ca) - np.nanmin(ca)) if ca.size else 0.0
    return "final C (%s%s): max |dC| %.3g, %s of its range %.6g (%d of %d particles differ)" % (
        common[-1], ", t = %s" % sig(float(np.ravel(t)[0])) if t is not None else "", float(np.nanmax(d)),
        "%.3g" % (float(np.nanmax(d)) / span) if span > 0 else "-", span, int(np.count_nonzero(ca != cb)), ca.size)


def compare_runs(da, db, skip_header=SKIP_HEADER):
    """(differences, summary) of two output folders."""
    sa = sorted(os.path.basename(p) for p in glob.glob(os.path.join(da, "snapshot_*.h5")))
    sb = sorted(os.path.basename(p) for p in glob.glob(os.path.join(db, "snapshot_*.h5")))
    diffs = []
    if sa != sb:
        diffs.append("snapshots %s against %s" % (sa, sb))
    if len(sa) < 2:
        diffs.append("only %d snapshot(s) written" % len(sa))
    c = final_c(da, db)
    if c:
        diffs.append(c)
    nds = 0
    for name in sorted(set(sa) & set(sb)):
        diffs += ["%s %s" % (name, d) for d in compare_snapshot(os.path.join(da, name), os.path.join(db, name), skip_header)]
        with h5py.File(os.path.join(da, name), "r") as f:
            nds = sum(len(datasets(f[g])) for g in COMPARED_GROUPS if g in f)
    diffs += compare_diagnostics(os.path.join(da, "diagnostics.csv"), os.path.join(db, "diagnostics.csv"))
    with open(os.path.join(da, "diagnostics.csv")) as f:
        nrows = sum(1 for _ in f) - 1
    ck = [c for c in CHECKPOINTS if os.path.exists(os.path.join(da, c)) or os.path.exists(os.path.join(db, c))]
    for c in ck:
        if not (os.path.exists(os.path.join(da, c)) and os.path.exists(os.path.join(db, c))):
            diffs.append("%s written by one run only" % c)
            continue
        diffs += ["%s %s" % (c, d) for d in compare_checkpoint(os.path.join(da, c), os.path.join(db, c), skip_header)]
    return diffs, "%d snapshots x %d datasets, %d diagnostics rows, %d checkpoints" % (len(sa), nds, nrows, len(ck))


def one_scene(args, scene, name=None, own=None, steps=0):
    """Run a scene with both binaries and compare: sized for `steps` steps
    (0: --steps) with a case's own overrides `own`, or, steps None, with
    `own` and --set alone (the scene's own length). (differences, summary)."""
    name = name or os.path.splitext(os.path.basename(scene))[0]
    work = os.path.join(args.work, name)
    os.makedirs(work, exist_ok=True)
    if steps is None:
        over, size = dict(own or {}), None
        over.update(args.set)
    else:
        over, size = overrides(args, scene, work, steps or args.steps, own)
    da, db = os.path.join(work, "before"), os.path.join(work, "after")
    t0 = time.time()
    out = run(args, args.before, scene, da, over, args.before_args, args.ranks)
    run(args, args.after, scene, db, over, args.after_args, args.ranks)
    wall = time.time() - t0
    if size is None:
        m = HEAD.search(out)
        size = "%d particles" % (int(m.group(1)) + int(m.group(2))) if m else "? particles"
    diffs, summary = compare_runs(da, db, SKIP_HEADER | set(args.skip_header))
    return diffs, "%s; %s, %d steps; both runs %.1f s; %s" % (
        summary, size, last_step(da), wall, " ".join("%s=%s" % kv for kv in over.items()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--before", required=True, help="the reference sphseg binary")
    ap.add_argument("--after", required=True, help="the sphseg binary to hold to it")
    ap.add_argument("--work", help="folder for the runs (kept); default a temporary one, removed")
    ap.add_argument("--steps", type=int, default=40,
                    help="steps per run (Run:max_steps); default 40 (past the first Shepard filter, every 30)")
    ap.add_argument("--ranks", type=int, help="run both under mpirun -np RANKS (default: one rank, no mpirun)")
    ap.add_argument("--backend", choices=["cpu", "gpu"], default="cpu", help="default cpu")
    ap.add_argument("--only", help="only the scenes whose file name, and the CASES whose name, matches this regular "
                    "expression")
    ap.add_argument("--no-cases", action="store_true", help="leave out the longer CASES (the scenes' short runs only)")
    ap.add_argument("--max-particles", type=float, default=30000,
                    help="coarsen Geometry:dr of a bigger scene to about this many particles; default 30000")
    ap.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of each rank; default 1")
    ap.add_argument("--timeout", type=float, default=600, help="wall s per run; default 600")
    ap.add_argument("--set", action="append", default=[], metavar="Section:key=value",
                    help="an override for both sides (repeatable)")
    ap.add_argument("--before-args", default="", help="extra arguments of the --before runs only (one string)")
    ap.add_argument("--after-args", default="", help="extra arguments of the --after runs only (one string)")
    ap.add_argument("--skip-header", action="append", default=[], metavar="ATTR",
                    help="also leave this /Header attribute out (repeatable; Version always is), e.g. Scene "
                    "when one binary has a key the other lacks")
    ap.add_argument("--inputs", default=os.path.join(ROOT, "inputs"), help="the scenes' folder; default inputs/")
    args = ap.parse_args()
    args.before, args.after = os.path.abspath(args.before), os.path.abspath(args.after)
    args.before_args, args.after_args = shlex.split(args.before_args), shlex.split(args.after_args)
    args.set = dict(s.split("=", 1) for s in args.set)
    for b in (args.before, args.after):
        if not os.access(b, os.X_OK):
            sys.exit("identical.py: %s is not an executable" % b)
    scenes = sorted(glob.glob(os.path.join(args.inputs, "*.yml")))
    if args.only:
        scenes = [s for s in scenes if re.search(args.only, os.path.basename(s))]
    cases = [] if args.no_cases else [c for c in CASES if not args.only or re.search(args.only, c[0])]
    if not scenes and not cases:
        sys.exit("identical.py: no scene in %s%s" % (args.inputs, " matches " + args.only if args.only else ""))
    # (name, scene, own overrides, steps): the scenes' short runs, then the cases
    jobs = [(os.path.splitext(os.path.basename(s))[0], s, None, 0) for s in scenes]
    jobs += [(n, os.path.join(args.inputs, f), own, steps) for n, f, own, steps in cases]
    tmp = None
    if not args.work:
        tmp = args.work = tempfile.mkdtemp(prefix="identical_")
    args.work = os.path.abspath(args.work)
    print("before %s\nafter  %s\n%d steps, %s, %s" % (args.before, args.after, args.steps,
          "%d ranks" % args.ranks if args.ranks else "1 rank", args.backend), flush=True)
    bad = 0
    for name, scene, own, steps in jobs:
        try:
            if not os.path.exists(scene):
                raise RunFailed("no scene %s" % scene)
            diffs, summary = one_scene(args, scene, name, own, steps)
        except RunFailed as e:
            print("%-16s FAILED: %s" % (name, e), flush=True)
            bad += 1
            continue
        if diffs:
            bad += 1
            # C's size, then the data, then the headers
            diffs.sort(key=lambda d: 0 if d.startswith("final C") else 1 + ("/Header" in d))
            print("%-16s DIFFERS: %s%s" % (name, diffs[0], " (and %d more)" % (len(diffs) - 1) if len(diffs) > 1 else ""))
            for d in diffs[1:6]:
                print("%-16s          %s" % ("", d))
        else:
            print("%-16s IDENTICAL (%s)" % (name, summary), flush=True)
    if tmp:
        shutil.rmtree(tmp, ignore_errors=True)
    print("%d of %d identical (%d scenes, %d cases)" % (len(jobs) - bad, len(jobs), len(scenes), len(cases)))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
