#!/usr/bin/env bash
# The blow-up path of the granular solver (DESIGN.md "Errors"): a column run
# with Run:cfl_flow = 2, past the measured stability limit (1.5 blows up,
# 1 does not; docs/granular.md), must stop with exit status 3 and one error
# line naming the step, the time, the particle and the violated condition
# (besides the warnings the settings draw: cfl_flow = 2 is past 0.2),
# with the snapshots written before it intact and readable and
# diagnostics.csv complete (renamed from .part). The same run at
# Run:cfl_flow = 1 finishes with exit 0.
set -u
bin=${1:?usage: test_blowup.sh build/sphseg}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "PASS $1"; else echo "FAIL $1"; fail=1; fi; }
args=(inputs/column_2d.yml -P Geometry:dr=0.0025 -P Run:t_end=0.05 -P Output:dt=0.002 -P Run:progress_s=1e9)

"$bin" "${args[@]}" -P Run:cfl_flow=2 -o "$tmp/a" >"$tmp/a.out" 2>"$tmp/a.err"
rc=$?
check "exit status 3" "[ $rc -eq 3 ]"
check "one error line" "[ \$(grep -c '^sphseg: error' '$tmp/a.err') -eq 1 ] && ! grep -v '^sphseg: \(error\|warning\): ' '$tmp/a.err' | grep -q ."
check "names step, time, particle, condition" \
    "grep -Eq '^sphseg: error: step [0-9]+, t = [0-9.e-]+ s: particle [0-9]+ at .* CFL condition violated' '$tmp/a.err'"
check "diagnostics.csv closed" "[ -s '$tmp/a/diagnostics.csv' ] && [ ! -e '$tmp/a/diagnostics.csv.part' ]"
check "no temporary snapshot left" "[ -z \"\$(ls '$tmp/a' | grep -E '\\.tmp\$')\" ]"
check "snapshots before the blow-up readable" "${PYTHON:-/usr/bin/python3} -c \"
import glob, h5py, sys
p = sorted(glob.glob('$tmp/a/snapshot_*.h5'))
assert p, 'no snapshot'
for q in p:
    with h5py.File(q) as f:
        assert f['Particles/Stress'].shape[1] == 6
sys.exit(0)\""
cat "$tmp/a.err"

"$bin" "${args[@]}" -P Run:cfl_flow=1 -o "$tmp/b" >"$tmp/b.out" 2>"$tmp/b.err"
check "cfl_flow = 1 runs to the end" "[ $? -eq 0 ]"
exit $fail
