"""Run many sphseg cases side by side and keep what each one costs.

The validation studies (tools/chute_study.py, tools/collapse_study.py,
tools/silo_study.py, tools/poiseuille_study.py) describe each run as a
Case: a name, a scene, -P overrides and the output folder. run_all starts up
to `jobs` of them at once (small 2D cases leave a GPU mostly idle, so several
share it), each under a wall-clock limit, and records for each its exit
status, wall time and sphseg's own "done:" line (steps, particle-steps/s) in
DIR/runs.csv. A case that fails or runs out of time is recorded as such, with
the tail of its output, and the others go on: a study reports what ran.
"""
import csv
import os
import re
import subprocess
import sys
import time

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
            log=sys.stdout):
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
            p = subprocess.Popen(c.command(sphseg, root, backend), stdout=f, stderr=subprocess.STDOUT)
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
    keys = []
    for r in done.values():
        keys += [k for k in r if k not in keys]
    with open(os.path.join(root, "runs.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for c in cases:
            if c.name in done:
                w.writerow(done[c.name])
    return done


def read_runs(root):
    """root/runs.csv as {name: row}."""
    with open(os.path.join(root, "runs.csv")) as f:
        return {r["name"]: r for r in csv.DictReader(f)}


def observed_order(h, e):
    """Least-squares slope of log e against log h (the observed order)."""
    import numpy as np
    h, e = np.asarray(h, float), np.asarray(e, float)
    ok = (h > 0) & (e > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(h[ok]), np.log(e[ok]), 1)[0])
