#!/usr/bin/env python3
"""A restart's scene, key by key (issue 55, defect 1): a fuzz over scene edits.

A small hopper checkpoint (inputs/hopper_2d.yml at dr = 4 mm, 3 steps) is
restarted with its own used_params.yml, edited in one key at a time. The keys
come from the key table (sphseg --keys): every key of every section, and every
key of every entry of the lists (Container:walls, Container:regions) — a key
an entry leaves out (a wall's open_at, a region's floor) is added. So a key
added to the table is fuzzed without a change here, and the test fails if the
table lists a key that used_params.yml does not echo.

Each edit is classed as the documented rule says (README "Checkpoints and
restarts"; src/output/checkpoint_keys.c):
- state keys (everything but the two classes below, the Container lists
  included): refused, exit 2, one "sphseg: error: --restart" line that says
  "1 state-defining key(s) differ" and names the key once, with both values:
  "Container:walls:3 (gate):open_at (0.05 in the checkpoint, 0.2 now)";
- model keys (Segregation but enabled/scheme/renormalize, Flow, Grains,
  Outlet): the run continues (exit 0), one warning naming it and both values;
- run-control keys (Run, Output, Parallel): the run continues, one
  "restart: 1 run-control key(s) differ" line naming it and both values.
A new value the scene check itself refuses (exit 2 naming the key in the
scene, never reaching the checkpoint) is passed over for the next candidate;
a key with no candidate left fails. Also: the unedited scene restarts with
no key named; a wall moved, restarted on 2 ranks, is refused in one line
from rank 0; a wall added is named by the list's length. The DEM section
(issue 58): a checkpoint of grains (a pile in inputs/dem_settling.yml),
restarted with each DEM key edited in turn, is refused naming that key (all
of DEM's keys are state keys: src/output/checkpoint_keys.c); every DEM key
must reach that check (a value the scene check takes).

    /usr/bin/python3 -m tests.test_restart_keys --sphseg build/sphseg --work DIR
"""
import argparse
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys
import time

MPI = ["mpirun", "--oversubscribe", "--allow-run-as-root"]
SCENE, COLUMN = "inputs/hopper_2d.yml", "inputs/column_2d.yml"
# a pile of DEM grains in the settling box (tests/validate_gpu.py's DEM_PILE), 3 supports coarser; DEM:at
# (unused by a block) inside the box, so that DEM:placement single passes the scene check
DEM = "inputs/dem_settling.yml"
DEM_P = ["-P", "DEM:d=0.004", "-P", "DEM:coupling=two_way", "-P", "DEM:placement=block", "-P", "DEM:block_n=[6, 3, 6]",
         "-P", "DEM:block_spacing=0.004001", "-P", "DEM:block_origin=[0.02, 0.002, 0.02]",
         "-P", "DEM:at=[0.032, 0.05, 0.032]"]
FAILS = []
RUN = ("Run:", "Output:", "Parallel:")
MODEL = ("Segregation:", "Flow:", "Grains:", "Outlet:")
STATE_MODULES = ("Segregation:enabled", "Segregation:scheme", "Segregation:renormalize")
# the hopper with a wall that translates (at 0 m/s) and a turning post (at 0 rpm) and a box region, so
# that every key of a wall and a region can be changed in some entry (a segment cannot turn, for one)
WALLS = ("Container:walls=[{name: left, from: [0, 0.16], to: [0, 0.04], motion: translating, velocity: [0, 0, 0]}, "
         "{name: hopper_left, from: [0, 0.04], to: [0.04, 0]}, {name: gate, from: [0.04, 0], to: [0.06, 0], "
         "open_at: 0.05}, {name: hopper_right, from: [0.06, 0], to: [0.1, 0.04]}, {name: right, from: [0.1, 0.04], "
         "to: [0.1, 0.16], centre: [0.05, 0.1], radius: 0.04}, {name: post, shape: cylinder, centre: [0.05, 0.08], radius: 0.033, from: [0.02, 0.17], "
         "to: [0.08, 0.17], material: outside, motion: turning, rpm: 0}]")
REGIONS = ("Container:regions=[{shape: fill, level: 0.06, C: 0}, {shape: fill, floor: 0.06, level: 0.09, C: 1}, "
           "{shape: fill, floor: 0.09, level: 0.12, C: 0}, {shape: box, lo: [0.01, 0.125], hi: [0.09, 0.14], "
           "floor: 0.125, level: 0.14, C: 0.5}]")
# keys the hopper does not use, set so that a change of another key passes the scene check: a period
# wide enough for Geometry:periodic x, a D for Segregation:model constant, a radius for a segment
# turned cylinder (wall 5 above)
UNUSED = ["-P", "Geometry:width=0.1", "-P", "Segregation:D=1e-7"]


def check(name, ok, detail=""):
    if not ok:
        print("FAIL " + name)
        FAILS.append(name)
        if detail:
            print("    " + detail.strip().replace("\n", "\n    ")[-1500:])
    return ok


def key_class(name):
    if name == "Run:preset":  # it sets other keys (src/scene/scene_preset.c): theirs decide
        return "preset"
    if name.startswith(RUN):
        return "run"
    if name not in STATE_MODULES and name.startswith(MODEL):
        return "model"
    return "state"


def fmt(v):
    """A number as sphseg echoes it (scene_fmt_double: the shortest of %.15g-%.17g that round-trips),
    rounded first (0.04 + 0.003 is 0.043)."""
    v = float("%.12g" % v)
    for p in (15, 16, 17):
        s = "%.*g" % (p, v)
        if float(s) == v:
            return s
    return s


def run(cmd, timeout=60):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    if cmd[0] != MPI[0]:
        env["OMPI_MCA_pml"] = "ob1"  # one rank: half the start-up time of the default (UCX)
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, errors="replace", timeout=timeout, env=env)
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired as e:
        return "timeout", str(e.stdout or ""), str(e.stderr or "")


# ---- the key table (sphseg --keys) ------------------------------------------

def key_table(sp):
    """{section: {key: (type, range)}}, the entry sections named as Container:walls."""
    rc, out, err = run([sp, "--keys"])
    if rc != 0:
        sys.exit(f"sphseg --keys: rc {rc}\n{err}")
    table, sec = {}, None
    for line in out.splitlines():
        m = re.match(r"^## (\S+)$", line)
        if m:
            sec = m.group(1)[:-2] if m.group(1).endswith(":K") else m.group(1)
            table[sec] = {}
        m = re.match(r"^\| `(\w+)` \|", line)
        if m and sec:
            cols = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
            table[sec][m.group(1)] = (cols[1], cols[3])
    return table


# ---- used_params.yml as lines, and list entries as items --------------------

def split_items(inside):
    """'k: v, k: [a, b], ...' -> ['k: v', 'k: [a, b]', ...] (brackets and quotes kept whole)."""
    items, depth, quoted, start, i = [], 0, False, 0, 0
    while i < len(inside):
        c = inside[i]
        if quoted:
            if c == "\\":
                i += 1
            elif c == '"':
                quoted = False
        elif c == '"':
            quoted = True
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "," and depth == 0 and inside[i + 1:i + 2] == " ":
            items.append(inside[start:i])
            start = i + 2
            i += 1
        i += 1
    items.append(inside[start:])
    return [tuple(it.split(": ", 1)) for it in items]


def parse_used(text):
    """[(section, key, value, line index)] for the plain keys and
    [(section, key, entry K, [(k, v), ...], line index)] for list entries."""
    plain, entries, sec, lst, k = [], [], None, None, 0
    for n, line in enumerate(text.splitlines()):
        if re.match(r"^\w+:\s*$", line):
            sec, lst = line.strip()[:-1], None
        elif line.startswith("    - {") and lst:
            k += 1
            entries.append((sec, lst, k, split_items(line.strip()[3:-1]), n))
        elif re.match(r"^  \w+:", line):
            key, _, val = line.strip().partition(":")
            val = val.strip()
            lst, k = (key, 0) if val == "" else (None, 0)
            if val:
                plain.append((sec, key, val, n))
    return plain, entries


def entry_line(items):
    return "    - {" + ", ".join(f"{a}: {b}" for a, b in items) + "}"


# ---- candidate values ---------------------------------------------------------

def in_range(v, rng):
    m = re.match(r"^([\[(])(\S+), (\S+)([\])])$", rng or "")
    if not m:
        return True
    lo, hi = float(m.group(2)), float(m.group(3))
    return (v > lo if m.group(1) == "(" else v >= lo) and (v < hi if m.group(4) == ")" else v <= hi)


def numbers(v, rng):
    x = float(v)
    cands = [x * 1.25, x * 0.8, x + 0.003, x - 0.003, x + 1] if x else [0.01, 0.003, 0.3, 1.0, 2.0]
    return [fmt(c) for c in cands if in_range(c, rng) and fmt(c) != v]


def vector(v):
    xs = [float(a) for a in v.strip("[]").split(",")]
    out = []
    for i, d in ((0, 0.003), (1, 0.003), (0, -0.3)):
        ys = list(xs)
        ys[i] = float("%.12g" % (ys[i] + d))
        out.append("[" + ", ".join(fmt(y) for y in ys) + "]")
    if all(x == int(x) for x in xs):  # whole numbers (DEM:block_n): last, a count one larger
        out.append("[" + ", ".join(str(int(x) + (i == 0)) for i, x in enumerate(xs)) + "]")
    return out


def candidates(kind, rng, v):
    """New values for a key of type kind (the table's value column), now v (None: absent)."""
    if kind.startswith("`"):
        names = re.findall(r"`(\w+)`", kind)
        return [n for n in names if n != v]
    if kind == "whole number >= 0":
        x = int(v or 0)
        return [str(c) for c in (x + 1, x + 2, x - 1) if c >= 0]
    if kind.endswith("numbers"):
        return vector(v) if v else []
    if kind == "text":  # a name, Run:backend, Segregation:every
        return [c for c in ('"renamed"', '"cpu"', '"2"') if c != v]
    if kind == "number":
        return (numbers(v, rng) if v is not None else [fmt(c) for c in (0.3, 0.01, 0.06)])[:4]
    return []


# ---- one edit ---------------------------------------------------------------

def verdict(res, shown, cls, was, now):
    """'ok', 'scene' (the scene check refused the value: try another) or why it failed."""
    rc, out, err = res
    note = f"{shown} ({was} in the checkpoint, {now} now)"
    errors = [l for l in err.splitlines() if l.startswith("sphseg: error")]
    said = out + err
    if rc == 2 and len(errors) == 1 and "--restart" not in errors[0]:
        return "scene", errors[0]
    if cls == "preset":  # another preset changes state keys (Material:E) of the checkpoint's: refused naming them
        ok = rc == 2 and len(errors) == 1 and errors[0].startswith("sphseg: error: --restart") and \
            "state-defining key(s) differ" in errors[0] and "Material:E (" in errors[0]
        return ("ok", "") if ok else ("bad", f"rc {rc}; expected a refusal naming Material:E (preset)\n{err[-1200:]}")
    if cls == "state":  # the scene key check's line, or the header's (Geometry:dim: a 2D checkpoint, a 3D scene)
        ok = (rc == 2 and len(errors) == 1 and errors[0].startswith("sphseg: error: --restart") and note in errors[0]
              and said.count(shown) == 1 and ("state-defining key(s) differ" not in errors[0] or
                                              "1 state-defining key(s) differ: " + note + " (restart" in errors[0]))
    else:  # one line of the restart's names it (other warnings may name the key too: a setting's own)
        want = ("sphseg: warning: --restart" if cls == "model" else "restart: 1 run-control key(s) differ")
        lines = [l for l in said.splitlines() if shown in l and l.startswith(("sphseg: warning: --restart", "restart:"))]
        ok = rc == 0 and len(lines) == 1 and lines[0].startswith(want) and note in lines[0] and \
            lines[0].count(shown) == 1 and ("1 model key(s)" in lines[0] or cls == "run")
    return ("ok", "") if ok else ("bad", f"rc {rc}; expected one line with '{note}' ({cls} key)\n{err[-1200:]}\n"
                                  f"{out[-600:]}")


def fuzz_one(sp, work, ck, lines, job):
    """Try the candidates of one key until one reaches the checkpoint's check."""
    tag, shown, cls, was, cands, edit = job
    tried = []
    for c in cands[:4]:
        text = list(lines)
        edit(text, c)
        path = os.path.join(work, tag + ".yml")
        with open(path, "w") as f:
            f.write("\n".join(text) + "\n")
        out = os.path.join(work, "r_" + tag)
        v, why = verdict(run([sp, path, "-o", out, "--restart", ck]), shown, cls, was, c)
        shutil.rmtree(out, ignore_errors=True)
        if v != "scene":
            return shown, c, v, why
        tried.append((c, why))
    return shown, None, "scene", tried


def plain_edit(n, key):
    def f(text, c):
        text[n] = f"  {key}: {c}"
    return f


def entry_edit(n, items, key):
    def f(text, c):
        new = [(a, c if a == key else b) for a, b in items]
        if key not in dict(items):
            new.append((key, c))
        text[n] = entry_line(new)
    return f


def jobs_for(table, plain, entries):
    jobs, seen = [], set()
    for sec, key, val, n in plain:
        name = f"{sec}:{key}"
        seen.add(name)
        kind, rng = table.get(sec, {}).get(key, ("?", "-"))
        jobs.append((name.replace(":", "_"), name, key_class(name), val, candidates(kind, rng, val),
                     plain_edit(n, key)))
    for sec, lst, k, items, n in entries:
        d = dict(items)
        label = d.get("name", "").strip('"')
        for key, (kind, rng) in table[f"{sec}:{lst}"].items():
            was = d.get(key)
            shown = f"{sec}:{lst}:{k}" + (f" ({label})" if label and key != "name" else "") + f":{key}"
            if key == "name":
                shown = f"{sec}:{lst}:{k} (renamed):name"  # the entry is shown by its name now
            jobs.append((f"{lst}{k}_{key}", shown, "state", was if was is not None else "(absent)",
                         candidates(kind, rng, was), entry_edit(n, items, key)))
        seen.add(f"{sec}:{lst}")
    return jobs, seen


def make_base(sp, work, name, scene, extra):
    """A checkpoint of scene after 3 steps; its folder and used_params.yml text."""
    base = os.path.join(work, name)
    rc, out, err = run([sp, scene, "-o", base, "-P", "Run:max_steps=3", "-P", "Output:checkpoint_dt=1"] + extra)
    if rc != 0:
        sys.exit(f"cannot make the checkpoint of {scene}: rc {rc}\n{err}")
    return base, open(base + "/used_params.yml").read()


def fuzz(sp, work, ck, text, jobs):
    lines = text.splitlines()
    with concurrent.futures.ThreadPoolExecutor(2) as ex:
        return list(ex.map(lambda j: fuzz_one(sp, work, ck, lines, j), jobs))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    sp, work = os.path.abspath(a.sphseg), os.path.abspath(a.work)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    t0 = time.time()
    base, text = make_base(sp, work, "base", SCENE, ["-P", "Geometry:dr=0.004", "-P", WALLS, "-P", REGIONS] + UNUSED)
    ck = base + "/checkpoint.h5"
    lines = text.splitlines()
    table = key_table(sp)
    plain, entries = parse_used(text)
    jobs, seen = jobs_for(table, plain, entries)

    # every key of the table is in used_params.yml (and so fuzzed), and no other
    listed = {f"{s}:{k}" for s, keys in table.items() if s.count(":") == 0 for k in keys}
    check("every key of the key table is echoed in used_params.yml and fuzzed", listed == seen,
          f"table only: {sorted(listed - seen)}; echo only: {sorted(seen - listed)}")
    check("the fuzz scene has walls and regions", {e[1] for e in entries} == {"walls", "regions"})

    # the unedited scene restarts, naming no key
    rc, out, err = run([sp, base + "/used_params.yml", "-o", work + "/same", "--restart", ck])
    check("the checkpoint's own used_params.yml restarts (exit 0), no key named", rc == 0 and "differ" not in out + err,
          f"rc {rc}\n{err}\n{out[-500:]}")

    res = fuzz(sp, work, ck, text, jobs)
    # the keys of a column (Geometry:lid, runout, outlet_width ...) that no container takes: in a column
    plain_only = {s for s, c, v, why in res if v == "scene" and ":K:" not in re.sub(r":\d+( \(\w+\))?:", ":K:", s)}
    col, ctext = make_base(sp, work, "column", COLUMN, ["-P", "Geometry:dr=0.005"])
    cjobs = [j for j in jobs_for(table, *parse_used(ctext))[0] if j[1] in plain_only]
    cres = fuzz(sp, work, col + "/checkpoint.h5", ctext, cjobs)
    in_column = {s for s, c, v, why in cres if v == "ok"}
    for s, c, v, why in cres:
        if v == "bad":
            check(f"column: {s} -> {c}", False, why)
    res = [(s, c, "ok" if s in in_column else v, why) for s, c, v, why in res]
    # an entry's key reached the checkpoint's check in some entry of its list
    reached = {re.sub(r":\d+( \(\w+\))?:", ":K:", s) for s, c, v, why in res if v == "ok"}
    scene_only = []
    for s, c, v, why in res:
        if v == "scene":  # the scene check refused every new value, naming the key (or its entry) itself
            at = re.sub(r" \(\w+\)", "", s)
            named = all(at in w or (":K:" in re.sub(r":\d+:", ":K:", at) and at.rsplit(":", 1)[0] + ":" in w)
                        for c_, w in why)
            other = ":K:" not in re.sub(r":\d+( \(\w+\))?:", ":K:", s) or re.sub(r":\d+( \(\w+\))?:", ":K:", s) in reached
            if check(f"{s}: the scene check refuses every value tried, naming it; the key reaches the checkpoint's "
                     "check in another entry", bool(why) and named and other, "\n".join(f"{c_}: {w}" for c_, w in why)):
                scene_only.append(s)
        elif v != "ok":
            check(f"{s} -> {c}", False, why)
    counts = {c: sum(1 for j in jobs if j[2] == c) for c in ("state", "model", "run")}
    print(f"column: {', '.join(sorted(in_column))} refused there; {', '.join(sorted(plain_only - in_column))} "
          "are refused by the scene check in the column too")
    print(f"fuzz: {len(jobs)} keys edited one at a time ({counts['state']} state: refused; {counts['model']} model: "
          f"a warning; {counts['run']} run-control: listed); {len(scene_only)} of them no value the scene check "
          f"takes (it refuses them before the checkpoint is read): {', '.join(scene_only)}")

    # DEM grains: every DEM key is a state key, refused by name
    dem, dtext = make_base(sp, work, "dem", DEM, DEM_P)
    djobs = [j for j in jobs_for(table, *parse_used(dtext))[0] if j[1].startswith("DEM:")]
    check("the DEM checkpoint's scene echoes every DEM key", {j[1] for j in djobs} ==
          {"DEM:" + k for k in table.get("DEM", {})}, str(sorted(j[1] for j in djobs)))
    for s, c, v, why in fuzz(sp, work, dem + "/checkpoint.h5", dtext, djobs):
        check(f"DEM checkpoint, {s} -> {c}: refused naming it", v == "ok", str(why))
    print(f"DEM: {len(djobs)} keys edited one at a time on a checkpoint of grains: refused")

    # a wall moved, on 2 ranks: one line, from rank 0
    n = next(e[4] for e in entries if e[2] == 4 and e[1] == "walls")
    items = next(e[3] for e in entries if e[2] == 4 and e[1] == "walls")
    was = dict(items)["to"]
    moved = list(lines)
    entry_edit(n, items, "to")(moved, "[0.1, 0.043]")
    path = os.path.join(work, "moved.yml")
    open(path, "w").write("\n".join(moved) + "\n")
    rc, out, err = run(MPI + ["-np", "2", sp, path, "-o", work + "/moved2", "--restart", ck], timeout=90)
    lines2 = [l for l in err.splitlines() if "sphseg: error" in l]
    check("2 ranks, the fourth wall moved: exit 2, one line from rank 0, the wall named once with both values",
          rc == 2 and len(lines2) == 1 and lines2[0].startswith("sphseg: error: --restart")
          and f"Container:walls:4 (hopper_right):to ({was} in the checkpoint, [0.1, 0.043] now)" in lines2[0]
          and (out + err).count("hopper_right") == 1, f"rc {rc}\n{err}\n{out[-300:]}")

    # a wall added: the list's length, once (not each key of the new entry)
    added = list(lines)
    last = max(e[4] for e in entries if e[1] == "walls")
    added.insert(last + 1, entry_line([("name", '"lid"'), ("from", "[0.1, 0.16]"), ("to", "[0, 0.16]")]))
    open(path, "w").write("\n".join(added) + "\n")
    rc, out, err = run([sp, path, "-o", work + "/added", "--restart", ck])
    nwalls = sum(1 for e in entries if e[1] == "walls")
    check("a wall added: refused naming Container:walls' length once",
          rc == 2 and f"1 state-defining key(s) differ: Container:walls ({nwalls} entries in the checkpoint, "
          f"{nwalls + 1} entries now)" in err and "lid" not in err, f"rc {rc}\n{err}")
    print(f"{len(FAILS)} failed ({time.time() - t0:.0f} s)")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
