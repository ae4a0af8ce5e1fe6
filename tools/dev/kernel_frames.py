#!/usr/bin/env python3
"""The pair kernels' registers, stack frames and spills, as ptxas reports them.

  python3 -m tools.dev.kernel_frames [--precision single|double] [--arch sm_90] [--check]
                                     [--log FILE]

compiles gpu/gpu_pairs.cu (every neighbour-loop kernel: the flow pass in its
template cases <RENORM, KGC, SHIFT, FORM>, the walls, the shift, the Shepard
sums, dC/dt, the classification) with `nvcc -Xptxas -v`, about 90 s on 2
cores, and prints one row per host function and template case: the largest
register count, stack frame and spill stores over its team sizes.

A stack frame in a pair kernel is local memory that every thread writes and
reads. A loop bounded by the run's dimension that indexes the particle store's
pointer table (p->x_n[d] with d < k->dim) puts the whole table there: the fused
leapfrog pass had a 728-byte frame and 208 bytes of spills from one such loop in
shift_finish, and lost 16 % of its rate to it (docs/performance.md, "The flow
pass's code"). Write such loops with a fixed trip count and a break, as
flow_advance and shift_finish do.

--check: exit 1 when a kernel of the per-step passes (the flow pass without the
L it sums only when a scheme needs it, in both its list kernels and its staged
one, k_flow_tile; the shift pass) has a frame of more than
LIMIT bytes (32; today none has one in the single build: the fused leapfrog
pass takes 122, 128 and 127 registers in its list, list16 and cells forms); the rest (the L's 3x3 solve, the Shepard
filter's MLS solve, dC/dt) keep small frames of once-per-particle arrays and are
listed only. Exit 77 when nvcc is not installed.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

from tools import ROOT

LIMIT = 32  # bytes of stack frame a per-step pair kernel may keep (0 today: docs/performance.md)
# the per-step passes --check holds to LIMIT: the flow pass without the owned L (RENORM 0), the shift pass
CHECKED = re.compile(r"^gpu_flow_pass<0, \d, \d, \d>$|^gpu_shift_f<\d>$|^k_flow_tile<\d+, 0, \d, \d>$")


def compile_report(precision, arch, log):
    """ptxas's verbose report of gpu/gpu_pairs.cu (the Makefile's flags)."""
    cmd = ["nvcc", "-O3", "-std=c++17", "-arch=" + arch, "--extended-lambda", "-I.", "-Isrc", "-Xptxas", "-v",
           "-c", "gpu/gpu_pairs.cu", "-o", os.devnull]
    if precision == "single":
        cmd.insert(1, "-DSPHSEG_SINGLE")
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if log:
        with open(log, "w") as f:
            f.write(r.stderr)
    if r.returncode != 0:
        sys.exit("nvcc failed (exit %d):\n%s" % (r.returncode, r.stderr[-2000:]))
    return r.stderr


def demangle(names):
    r = subprocess.run(["c++filt"], input="\n".join(names), capture_output=True, text=True)
    return r.stdout.splitlines() if r.returncode == 0 else names


def rows(report):
    """{host function with its template case: (registers, stack bytes, spill-store bytes)}, the largest over
    the team sizes (the staged flow pass k_flow_tile: a row a team size)."""
    blocks = report.split("Compiling entry function")[1:]
    names = [b.split("'")[1] for b in blocks]
    out = {}
    for b, dm in zip(blocks, demangle(names)):
        st = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores", b)
        rg = re.search(r"Used (\d+) registers", b)
        m = re.search(r"(gpu_\w+|k_flow_tile)(<[^>]*>)?\(", dm)
        if not (st and rg and m):
            continue
        key = m.group(1) + (m.group(2) or "")
        v = (int(rg.group(1)), int(st.group(1)), int(st.group(2)))
        old = out.get(key, (0, 0, 0))
        out[key] = tuple(max(a, c) for a, c in zip(old, v))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--precision", choices=("single", "double"), default="single")
    ap.add_argument("--arch", default="sm_90")
    ap.add_argument("--check", action="store_true", help="fail on a frame over LIMIT bytes in the per-step passes")
    ap.add_argument("--log", help="keep ptxas's whole report here")
    a = ap.parse_args()
    if not shutil.which("nvcc"):
        print("nvcc not installed: nothing to compile")
        sys.exit(77)
    table = rows(compile_report(a.precision, a.arch, a.log))
    if not table:
        sys.exit("no pair kernels found in ptxas's report")
    bad = []
    print("%-34s %9s %12s %13s  (gpu/gpu_pairs.cu, %s, %s; the largest over team sizes)"
          % ("kernel <RENORM, KGC, SHIFT, FORM>", "registers", "stack bytes", "spill stores", a.precision, a.arch))
    for k in sorted(table):
        reg, stack, spill = table[k]
        held = bool(CHECKED.match(k))
        if held and stack > LIMIT:
            bad.append(k)
        print("%-34s %9d %12d %13d%s" % (k, reg, stack, spill, "  <- over the limit" if k in bad else ""))
    if not any(CHECKED.match(k) for k in table):
        sys.exit("none of the checked kernels (%s) in the report" % CHECKED.pattern)
    if a.check:
        if bad:
            print("FAIL: %d per-step pair kernel(s) keep a stack frame over %d bytes: %s"
                  % (len(bad), LIMIT, ", ".join(bad)))
            sys.exit(1)
        print("ok: the flow pass (without L) and the shift pass keep no stack frame over %d bytes" % LIMIT)


if __name__ == "__main__":
    main()
