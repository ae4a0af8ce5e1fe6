#!/usr/bin/env python3
"""Every declared row has its counterparts (docs/architecture.md, "What a change touches").

The code declares three things as table rows, each once; a row is only half
of a change, and this test fails on the other half missing:

- a stage id (src/sim/stage_table.h, enum stage_id) needs a row in
  stage_table[] and a case in each backend: `case ST_X` in
  src/cpu/backend_cpu.c and in gpu/gpu_step.cu (a backend that fuses a
  stage into another's pass still names it);
- a particle field (src/core/fields.h, PART_FIELDS) needs code that uses
  its member (p->member or .member outside the field table), else it is
  memory every run allocates for nothing;
- a scene key (src/scene/scene_keys.h) needs code that reads it
  (.key or ->key outside the key table and the generic loader), else the
  key is a promise the code does not keep.

It reads the tree only (no build). Names that the generic code serves
(the loader's own keys) are listed in GENERIC with the reason.
"""
import glob
import os
import re
import sys

from tools import ROOT

CODE_GLOBS = ("src/*.c", "src/*/*.c", "src/*/*.h", "mpi/*.c", "mpi/*.h", "gpu/*.cu", "gpu/*.cuh")
KEY_TABLE = "src/scene/scene_keys.h"
FIELD_TABLE = "src/core/fields.h"
STAGE_TABLE = "src/sim/stage_table.h"
BACKENDS = ("src/cpu/backend_cpu.c", "gpu/gpu_step.cu")
# keys read by name through the loader's generic paths, not as members
GENERIC = {}


def read(rel):
    return open(os.path.join(ROOT, rel), encoding="utf-8").read()


def code_text(skip):
    """All code but the files in skip, comments removed."""
    out = []
    for pat in CODE_GLOBS:
        for f in sorted(glob.glob(os.path.join(ROOT, pat))):
            rel = os.path.relpath(f, ROOT)
            if rel in skip:
                continue
            t = open(f, encoding="utf-8").read()
            t = re.sub(r"/\*.*?\*/", " ", t, flags=re.S)
            t = re.sub(r"//[^\n]*", " ", t)
            out.append(t)
    return "\n".join(out)


def stage_problems():
    tbl = read(STAGE_TABLE)
    enum = tbl[tbl.index("enum stage_id"):tbl.index("ST_N")]
    ids = re.findall(r"\b(ST_[A-Z0-9_]+)\s*,", enum)
    rows = tbl[tbl.index("#ifdef STAGE_TABLE_ROWS"):]
    row_ids = set(re.findall(r"\{\s*(ST_[A-Z0-9_]+)\s*,", rows))
    problems = []
    for st in ids:
        if st not in row_ids:
            problems.append(f"stage {st}: no row in stage_table[] ({STAGE_TABLE})")
        for be in BACKENDS:
            if not re.search(r"case\s+" + st + r"\s*:", read(be)):
                problems.append(f"stage {st}: no `case {st}:` in {be}")
    for st in row_ids - set(ids):
        problems.append(f"stage {st}: a row but no id in enum stage_id")
    return problems, len(ids)


def field_problems():
    fields = re.findall(r"^\s*F\((\w+),", read(FIELD_TABLE), flags=re.M)
    code = code_text({FIELD_TABLE})
    problems = [f"field {m}: declared in {FIELD_TABLE} but no code uses ->{m} or .{m}"
                for m in fields if not re.search(r"(->|\.)" + re.escape(m) + r"\b", code)]
    return problems, len(fields)


def key_problems():
    rows = re.findall(r"^\s*(E?K[FEUSVL])\(\s*\"([^\"]+)\"\s*,\s*(\w+)\s*,\s*(\w+)\s*,\s*(\w+)",
                      read(KEY_TABLE), flags=re.M)
    code = code_text({KEY_TABLE})
    problems = []
    n = 0
    for kind, sec, a, b, c in rows:
        key = b if kind.startswith("E") else c  # EK*(sec, st, k, ...) / K*(sec, m, st, k, ...)
        n += 1
        if f"{sec}:{key}" in GENERIC:
            continue
        if not re.search(r"(->|\.)" + re.escape(key) + r"\b", code):
            problems.append(f"key {sec}:{key}: in {KEY_TABLE} but no code reads .{key}")
    return problems, n


def main():
    total = 0
    counts = []
    for name, fn in (("stages", stage_problems), ("fields", field_problems), ("keys", key_problems)):
        problems, n = fn()
        counts.append(f"{n} {name}")
        for p in problems:
            print("FAIL", p)
        total += len(problems)
    if total:
        print(f"{total} rows lack a counterpart")
        return 1
    print("ok: " + ", ".join(counts) + ", each with its counterparts")
    return 0


if __name__ == "__main__":
    sys.exit(main())
