#!/usr/bin/env python3
"""The pair kernels' registers, stack frames and spills, as ptxas reports them.

  python3 -m tools.dev.kernel_frames [--precision single|double] [--arch sm_90] [--check]
                                     [--log FILE]

compiles gpu/gpu_pairs.cu (every neighbour-loop kernel: the flow pass in its
template cases <RENORM, KGC, SHIFT, FORM, SPEC>, the walls, the shift, the Shepard
sums, dC/dt, the classification) with the Makefile's flags for it (`make
print-nvflags-pairs`) and `-Xptxas -v`, about 2 minutes on 2
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
LIMIT bytes (32; today none has one in the single build at 4 blocks a SM),
or, bound to NARROW_MINB (5) blocks, of more than NARROW_LIMIT (64: the single
build's fused leapfrog pass at 1 or 2 threads a particle, 96 registers, keeps
56 bytes of spills there, measured faster); the rest (the L's 3x3 solve, the Shepard
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
# The single build's fused pass runs 5 blocks a SM (96 registers) at 1 or 2 threads a particle
# (SPHSEG_FUSED_MINB_T2, gpu/gpu_launch.cuh): a 56-byte frame of spills, measured faster than none
# at 4 blocks. Instantiations bound to NARROW_MINB blocks or more are held to NARROW_LIMIT instead.
NARROW_MINB, NARROW_LIMIT = 5, 64
# the per-step passes --check holds to LIMIT: the flow pass without the owned L (RENORM 0), the shift pass
CHECKED = re.compile(r"^gpu_flow_pass<0, \d, \d, \d, \d>$|^gpu_shift_f<\d>$|^k_flow_tile<\d+, 0, \d, \d>$")


def make_flags(precision, arch):
    """The flags the Makefile compiles gpu/gpu_pairs.cu with (its NVFLAGS and NVFLAGS_PAIRS)."""
    r = subprocess.run(["make", "-s", "--no-print-directory", "print-nvflags-pairs", "GPU=1", "PRECISION=" + precision,
                        "CUDA_ARCH=" + arch], cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0 or not r.stdout.split():
        sys.exit("make print-nvflags-pairs failed (exit %d): %s" % (r.returncode, r.stderr[-500:]))
    return r.stdout.split()


def compile_report(precision, arch, log):
    """ptxas's verbose report of gpu/gpu_pairs.cu (the Makefile's flags)."""
    cmd = ["nvcc"] + make_flags(precision, arch) + ["-Xptxas", "-v", "-c", "gpu/gpu_pairs.cu", "-o", os.devnull]
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
    """{host function with its template case: (registers, stack bytes, spill-store bytes, stack bytes at
    NARROW_MINB blocks)}, the largest over the team sizes (the staged flow pass k_flow_tile: a row a team
    size); the fourth, of the instantiations bound to NARROW_MINB or more blocks a SM (k_team<T, MB>)."""
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
        mb = re.match(r"void k_team<\d+, (\d+),", dm)
        narrow = bool(mb) and int(mb.group(1)) >= NARROW_MINB
        v = (int(rg.group(1)), 0 if narrow else int(st.group(1)), int(st.group(2)), int(st.group(1)) if narrow else 0)
        old = out.get(key, (0, 0, 0, 0))
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
          % ("kernel <RENORM, KGC, SHIFT, FORM, SPEC>", "registers", "stack bytes", "spill stores", a.precision, a.arch))
    for k in sorted(table):
        reg, stack, spill, narrow = table[k]
        held = bool(CHECKED.match(k))
        if held and (stack > LIMIT or narrow > NARROW_LIMIT):
            bad.append(k)
        at5 = "  (%d at %d+ blocks a SM)" % (narrow, NARROW_MINB) if narrow else ""
        print("%-34s %9d %12d %13d%s%s" % (k, reg, stack, spill, at5, "  <- over the limit" if k in bad else ""))
    if not any(CHECKED.match(k) for k in table):
        sys.exit("none of the checked kernels (%s) in the report" % CHECKED.pattern)
    if a.check:
        if bad:
            print("FAIL: %d per-step pair kernel(s) keep a stack frame over %d bytes (%d at %d+ blocks a SM): %s"
                  % (len(bad), LIMIT, NARROW_LIMIT, NARROW_MINB, ", ".join(bad)))
            sys.exit(1)
        print("ok: the flow pass (without L) and the shift pass keep no stack frame over %d bytes (%d at %d+ blocks"
              " a SM)" % (LIMIT, NARROW_LIMIT, NARROW_MINB))


if __name__ == "__main__":
    main()
