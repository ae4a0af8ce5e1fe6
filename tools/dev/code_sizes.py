#!/usr/bin/env python3
"""The largest product files and the longest functions (issue 32's limits).

Counts the lines of every C, CUDA and header file under src/, mpi/ and gpu/
(or the paths given), and the length of every function: from the first line
of its signature to its closing brace, for a definition whose body opens
with a `{` alone in column 0 (clang-format's style here) or at the end of a
signature line that starts in column 0, and closes with `}` in column 0.

  /usr/bin/python3 -m tools.dev.code_sizes                 # top 10 of each
  /usr/bin/python3 -m tools.dev.code_sizes --top 20 src/scene*.c
  /usr/bin/python3 -m tools.dev.code_sizes --max-file 900 --max-func 80   # exit 1 past either
"""
import argparse
import glob
import os
import re
import sys

EXTS = (".c", ".h", ".cu", ".cuh")
SIG = re.compile(r"^[A-Za-z_][\w \t\*]*?\b([A-Za-z_]\w*)\s*\(")
NOT_FUNC = {"if", "for", "while", "switch", "return", "sizeof", "defined"}


def files(paths):
    out = []
    for p in paths:
        if os.path.isdir(p):
            for root, _, names in os.walk(p):
                out += [os.path.join(root, n) for n in names if n.endswith(EXTS)]
        else:
            out += [q for q in glob.glob(p) if q.endswith(EXTS)]
    return sorted(set(out))


def functions(path):
    """(name, first line, length) of each function defined in path."""
    lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
    found, sig = [], None
    i = 0
    while i < len(lines):
        ln = lines[i]
        m = SIG.match(ln)
        if m and m.group(1) not in NOT_FUNC and not ln.rstrip().endswith(";") and not ln.startswith("#"):
            sig = (m.group(1), i)
        if sig is not None and (ln == "{" or (ln.endswith("{") and sig[1] <= i and not ln.startswith((" ", "\t"))
                                               and ")" in ln and "=" not in ln)):
            name, start = sig
            j = i + 1
            while j < len(lines) and lines[j] != "}":
                j += 1
            if i - start <= 6:  # the signature ran into the body: a function
                found.append((name, start + 1, j - start + 1))
            sig = None
            i = j
        elif ln.rstrip().endswith(";") and not ln.startswith((" ", "\t")):
            sig = None
        i += 1
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("paths", nargs="*", default=["src", "mpi", "gpu"])
    ap.add_argument("--top", type=int, default=10)
    ap.add_argument("--max-file", type=int, help="exit 1 when a file has more lines")
    ap.add_argument("--max-func", type=int, help="exit 1 when a function has more lines")
    a = ap.parse_args()
    fs = files(a.paths)
    sizes = sorted(((sum(1 for _ in open(f, encoding="utf-8", errors="replace")), f) for f in fs), reverse=True)
    funcs = sorted(((n, f, name, ln) for f in fs for name, ln, n in functions(f)), reverse=True)
    print(f"largest files ({len(fs)} files, {sum(s for s, _ in sizes)} lines):")
    for n, f in sizes[: a.top]:
        print(f"  {n:6d}  {f}")
    print(f"longest functions ({len(funcs)} functions):")
    for n, f, name, ln in funcs[: a.top]:
        print(f"  {n:6d}  {name}  ({f}:{ln})")
    bad = 0
    if a.max_file is not None:
        over = [(n, f) for n, f in sizes if n > a.max_file]
        for n, f in over:
            print(f"over {a.max_file} lines: {f} ({n})")
        bad |= bool(over)
    if a.max_func is not None:
        over = [(n, f, name) for n, f, name, _ in funcs if n > a.max_func]
        for n, f, name in over:
            print(f"over {a.max_func} lines: {name} in {f} ({n})")
        bad |= bool(over)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
