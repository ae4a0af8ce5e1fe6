"""Run many sphseg cases side by side and keep what each one costs.

The validation studies (tools/studies/chute_study.py, tools/studies/collapse_study.py,
tools/studies/silo_study.py, tools/studies/poiseuille_study.py) describe each run as a
Case: a name, a scene, -P overrides and the output folder. run_all starts up
to `jobs` of them at once (small 2D cases leave a GPU mostly idle, so several
share it), each under a wall-clock limit, and records for each its exit
status, wall time and sphseg's own "done:" line (steps, particle-steps/s) in
DIR/runs.csv. A case that fails or runs out of time is recorded as such, with
the tail of its output, and the others go on: a study reports what ran.
"""
import csv
import math
import os
import re
import subprocess
import sys
import time
from tools import ROOT

DONE = re.compile(r"done: (\d+) steps, ([0-9.e+-]+) s wall, ([0-9.e+-]+) particle-steps/s")
HEAD = re.compile(r"(\d+) material \+ (\d+) dummy particles")


class Case:
    """One sphseg run: `over` is a dict of Section:key -> value."""

    def __init__(self, name, scene, over, **meta):
        self.name, self.scene, self.over, self.meta = name, scene, dict(over), meta

    def command(self, sphseg, root, backend=None):
        cmd = [sphseg, self.scene, "-o", os.path.join(root, self.name), "--overwrite"]
        if backend:
            cmd += ["--backend", backend]
        for k, v in self.over.items():
            cmd += ["-P", "%s=%s" % (k, v)]
        return cmd


def run_all(cases, sphseg, root, backend=None, jobs=4, limit_s=540.0, deadline_s=None, on_done=None,
            log=sys.stdout, env=None):
    """Run the cases (at most `jobs` at once, each killed after limit_s, and
    all by deadline_s from now: cases not started by then are skipped);
    on_done(case, record) is called as each ends. Returns {name: record} and
    writes root/runs.csv."""
    os.makedirs(root, exist_ok=True)
    pending, running, done = list(cases), [], {}
    t_start = time.time()
    end = t_start + deadline_s if deadline_s else float("inf")
    while pending or running:
        if time.time() > end and pending:
            print("batch: deadline reached, %d cases not started: %s" % (len(pending), " ".join(c.name for c in pending)),
                  file=log, flush=True)
            pending = []
        while pending and len(running) < jobs:
            c = pending.pop(0)
            f = open(os.path.join(root, c.name + ".log"), "w")
            p = subprocess.Popen(c.command(sphseg, root, backend), stdout=f, stderr=subprocess.STDOUT, env=env)
            running.append((c, p, f, time.time()))
        time.sleep(0.2)
        for item in list(running):
            c, p, f, t0 = item
            rc = p.poll()
            if rc is None and (time.time() - t0 > limit_s or time.time() > end):
                p.kill()
                rc = p.wait()
                rc = "timeout"
            if rc is None:
                continue
            f.close()
            running.remove(item)
            text = open(os.path.join(root, c.name + ".log")).read()
            m, h = DONE.search(text), HEAD.search(text)
            rec = {"name": c.name, "rc": rc, "wall_s": round(time.time() - t0, 3),
                   "steps": int(m.group(1)) if m else "", "sphseg_wall_s": float(m.group(2)) if m else "",
                   "pstep_per_s": float(m.group(3)) if m else "",
                   "material": int(h.group(1)) if h else "", "dummy": int(h.group(2)) if h else ""}
            rec.update(c.meta)
            done[c.name] = rec
            print("%-28s rc %-7s %8.1f s  %s" % (c.name, rc, rec["wall_s"],
                                                 m.group(0) if m else text.strip().splitlines()[-1:] or ""),
                  file=log, flush=True)
            if on_done:
                on_done(c, rec)
    print("batch: %d cases in %.1f s" % (len(cases), time.time() - t_start), file=log, flush=True)
    write_runs(root, done, [c.name for c in cases])
    return done


def write_runs(root, records, order):
    """root/runs.csv: the records ({name: row}) in the order of the names
    given, with the union of their columns."""
    keys = []
    for r in records.values():
        keys += [k for k in r if k not in keys]
    with open(os.path.join(root, "runs.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for n in order:
            if n in records:
                w.writerow(records[n])


def select(cases, only):
    """The cases whose names match one of the comma-separated regular
    expressions of `only` (all when None), in the order of the first pattern
    each matches."""
    if not only:
        return list(cases)
    keys = only.split(",")
    first = lambda c: min([i for i, k in enumerate(keys) if re.search(k, c.name)] or [len(keys)])
    return sorted((c for c in cases if first(c) < len(keys)), key=first)


def load_runs(outs, needs):
    """The runs of several run folders merged: ({name: runs.csv row},
    {name: its folder}), keeping those whose folder holds the file `needs`."""
    runs, where = {}, {}
    for out in outs:
        for n, r in read_runs(out).items():
            if os.path.exists(os.path.join(out, n, needs)):
                runs[n], where[n] = r, out
    return runs, where


def run_cases_or_exit(cases, sphseg, work, limit_s=900, side_by_side=False):
    """For the tests: the cases one at a time, or with side_by_side two at a
    time on one thread each, as the other tests that share CI's two cores do
    (for cases of like length, which use a core better alone than two
    threads do: validate_chute took 182 s so against 261 s one at a time on
    the 2-core development machine); exits the script with FAIL and the
    run's last output when one fails. Returns run_all's records."""
    jobs = min(len(cases), 2) if side_by_side else 1
    env = dict(os.environ, OMP_NUM_THREADS="1") if jobs > 1 else None
    recs = run_all(cases, sphseg, work, jobs=jobs, limit_s=limit_s, env=env)
    for c in cases:
        if recs[c.name]["rc"] != 0:
            print("FAIL %s: sphseg ended with %s" % (c.name, recs[c.name]["rc"]))
            print(open(os.path.join(work, c.name + ".log")).read()[-2000:])
            sys.exit(1)
    return recs


def study_main(doc, sets, cases_of, on_done, cmd_report, study, jobs=1, argv=None, merge=None):
    """The command line the validation studies share: `run` (the cases of
    --set through `cases_of`, picked by --only, on_done(args, case, record)
    as each ends) and `report` (cmd_report(args) over --out folders; its
    charts into --docs, by default the study's data folder docs/data/STUDY)."""
    import argparse
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--sphseg", required=True)
    r.add_argument("--out", required=True)
    r.add_argument("--backend")
    r.add_argument("--set", default="full", help="full | " + " | ".join(sets) + " (comma-separated)")
    r.add_argument("--only", help="comma-separated patterns (regular expressions) of case names; runs in their order")
    r.add_argument("--jobs", type=int, default=jobs)
    r.add_argument("--limit-s", type=float, default=540.0)
    r.add_argument("--deadline-s", type=float, help="end every run by then, start none after")
    r.add_argument("--keep", action="store_true", help="keep the snapshots")
    p = sub.add_parser("report")
    p.add_argument("--out", required=True, nargs="+", help="the run folders (several: their cases merged)")
    p.add_argument("--docs", default=os.path.join(ROOT, "docs", "data", study),
                   help="folder for the charts (default docs/data/%s)" % study)
    p.add_argument("--table", help="also write the tables (markdown) here")
    if merge:  # the study's report can keep rows of its earlier CSV (merge: the flag's help)
        p.add_argument("--merge", action="store_true", help=merge)
    a = ap.parse_args(argv)
    if a.cmd == "report":
        return cmd_report(a)
    todo = select([c for w in a.set.split(",") for c in cases_of(w)], a.only)
    for c in todo:
        c.meta["backend"] = a.backend or "cpu"
    run_all(todo, a.sphseg, a.out, backend=a.backend, jobs=a.jobs, limit_s=a.limit_s, deadline_s=a.deadline_s,
            on_done=lambda c, rec: on_done(a, c, rec))


def report_tables(a, lines):
    """The end of a study's report: its tables (markdown lines) printed, and
    written to a.table where --table was given."""
    text = "\n".join(lines) + "\n"
    print(text)
    if a.table:
        with open(a.table, "w") as f:
            f.write(text)


def read_runs(root):
    """root/runs.csv as {name: row}."""
    with open(os.path.join(root, "runs.csv")) as f:
        return {r["name"]: r for r in csv.DictReader(f)}


def write_csv(path, header, rows):
    """path (a CSV file) with the header row and then rows."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def richardson(a, b, c, r=2.0):
    """Three values at spacings h, h/r, h/r^2 (a the coarsest): the observed order of their two changes and
    Richardson's limit c + (c - b) / (r^p - 1), NaN where the order is not positive (or a change is 0)."""
    d1, d2 = b - a, c - b
    if d1 == 0 or d2 == 0:
        return math.nan, math.nan
    p = math.log(abs(d1 / d2)) / math.log(r)
    return p, (c + d2 / (r ** p - 1) if p > 0 else math.nan)


def observed_order(h, e):
    """Least-squares slope of log e against log h (the observed order)."""
    import numpy as np
    h, e = np.asarray(h, float), np.asarray(e, float)
    ok = (h > 0) & (e > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(h[ok]), np.log(e[ok]), 1)[0])
