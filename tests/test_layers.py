#!/usr/bin/env python3
"""The rooms of the source and their layer order (docs/architecture.md).

Each C, CUDA or header file of src/, mpi/ and gpu/ lies in a room; a room may
include its own files and those of the rooms below it, never above:

    core < physics < mpi < scene < dem < sim < {cpu, gpu} < output < driver

- core     src/core/      store, field table, errors, tuning, hd.h, version
- physics  src/physics/   header-only bodies, CPU and GPU alike
- mpi      mpi/           decomposition, halo, migration, reductions
- scene    src/scene/     the key table, the loader, the checks
- dem      src/dem/       the DEM grains: their store, contacts, sub-cycling, coupling
- sim      src/sim/       a run's state (sim.h), the stage table, the integrator, setup
- cpu, gpu src/cpu/, gpu/ the two backends (neither includes the other)
- output   src/output/    snapshots, XDMF, checkpoints, diagnostics
- driver   src/*          the command line, the run loop, its log

The test resolves every quoted #include as the compiler does (the
including file's folder, then -I. and -Isrc) and fails on an include that
goes up, on a file in no room, on an include that resolves to nothing, and
on more than 12 files at the top of src/. It reads the tree only (no build).
"""
import glob
import os
import re
import sys

from tools import ROOT

ORDER = {"core": 0, "physics": 1, "mpi": 2, "scene": 3, "dem": 4, "sim": 5, "cpu": 6, "gpu": 6, "output": 7,
         "driver": 8}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
TOP_MAX = 12  # files at the top of src/ (issue 54)


def room_of(rel):
    """The room of a repository-relative path, or None."""
    parts = rel.split("/")
    if parts[0] in ("mpi", "gpu"):
        return parts[0]
    if parts[0] == "src":
        if len(parts) == 2:
            return "driver"
        return parts[1] if parts[1] in ORDER else None
    return None


def resolve(includer, name):
    """The repository-relative path a quoted include names, or None."""
    for base in (os.path.dirname(includer), ".", "src"):
        cand = os.path.normpath(os.path.join(base, name))
        if os.path.isfile(os.path.join(ROOT, cand)):
            return cand
    return None


def check(root=ROOT):
    """Problems found, one line each."""
    problems = []
    files = []
    for pat in ("src/*.[ch]", "src/*/*.[ch]", "mpi/*.[ch]", "gpu/*.cu", "gpu/*.cuh"):
        files += [os.path.relpath(f, root) for f in glob.glob(os.path.join(root, pat))]
    for rel in sorted(files):
        room = room_of(rel)
        if room is None:
            problems.append(f"{rel}: in no room (rooms: {', '.join(ORDER)})")
            continue
        text = open(os.path.join(root, rel), encoding="utf-8").read()
        for name in INCLUDE.findall(text):
            tgt = resolve(rel, name)
            if tgt is None:
                problems.append(f'{rel}: #include "{name}" resolves to no file')
                continue
            troom = room_of(tgt)
            if troom is None:
                problems.append(f'{rel}: #include "{name}" ({tgt}) is in no room')
            elif troom != room and ORDER[troom] >= ORDER[room]:
                problems.append(f'{rel} ({room}): #include "{name}" goes up to {troom} ({tgt})')
    top = [f for f in os.listdir(os.path.join(root, "src")) if os.path.isfile(os.path.join(root, "src", f))]
    if len(top) > TOP_MAX:
        problems.append(f"src/ holds {len(top)} files at its top (at most {TOP_MAX}): {' '.join(sorted(top))}")
    return problems, len(files)


def main():
    problems, n = check()
    for p in problems:
        print("FAIL", p)
    if problems:
        print(f"{len(problems)} layer problems in {n} files")
        return 1
    print(f"ok: {n} files in {len(ORDER)} rooms, no include goes up")
    return 0


if __name__ == "__main__":
    sys.exit(main())
