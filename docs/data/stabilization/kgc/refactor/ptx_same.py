# Are two PTX files the same program up to a renaming of virtual registers and the order of a
# commutative pair of factors (mul, add, fma)? Zero initialisations (mov from 0 or from a register so
# set) fix no mapping: all such registers hold the same value. python3 ptx_same.py A.ptx B.ptx
import re, sys
A, B = open(sys.argv[1]).read().splitlines(), open(sys.argv[2]).read().splitlines()
assert len(A) == len(B), (len(A), len(B))
pat = re.compile(r"%(?:fd|rd|r|p|f|rs|h)\d+")
zmov = re.compile(r"^\s*mov\.f(?:64|32)\s+(%fd?\d+),\s*(0d0000000000000000|0f00000000|%fd?\d+);")
fwd, bwd, bad, nfunc, za, zb = {}, {}, 0, 0, set(), set()
for x, y in zip(A, B):
    if x.startswith((".visible .entry", ".entry", ".func", ".visible .func", ".weak .func")):
        fwd, bwd, za, zb = {}, {}, set(), set(); nfunc += 1
    if pat.sub("R", x) != pat.sub("R", y):
        bad += 1; print("text differs:", x, "|", y); continue
    mx, my = zmov.match(x), zmov.match(y)
    if mx and my and (mx.group(2).startswith(("0d", "0f")) or mx.group(2) in za) and (my.group(2).startswith(("0d", "0f")) or my.group(2) in zb) \
            and mx.group(1) not in fwd and my.group(1) not in bwd:
        za.add(mx.group(1)); zb.add(my.group(1)); continue
    rx, ry = pat.findall(x), pat.findall(y)
    op = x.split()[0] if x.split() else ""
    # commutative operands (mul, add; fma's two factors): swapped in y when that fits the mapping
    if op.split(".")[0] in ("mul", "add", "fma") and len(rx) >= 3 and fwd.get(rx[1]) == ry[2] and fwd.get(rx[2]) == ry[1]:
        ry = [ry[0], ry[2], ry[1]] + ry[3:]
    for u, v in zip(rx, ry):
        if fwd.setdefault(u, v) != v or bwd.setdefault(v, u) != u:
            bad += 1; print("mapping conflict:", u, v, "|", x, "|", y); break
    for u, v in zip(pat.findall(x), pat.findall(y)):
        if (u in za) != (v in zb): bad += 1; print("zero mismatch", u, v)
print("functions", nfunc, "lines", len(A), "conflicts", bad)
