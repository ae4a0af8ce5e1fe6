#!/usr/bin/env bash
# Snapshots in global particle-ID order on any rank count (DESIGN.md "Files a
# run writes"): tests/test_io_ranks.c writes the same shuffled, sparse-ID
# particle set from 1, 2 and 3 ranks (uneven counts, one rank with none) and
# checks its own file; here h5py checks the three files are identical field by
# field (data, dtype, shape, attributes, header) and ID-sorted. Also
# tests/test_io.c on 3 ranks, and a duplicated ID refused with exit 1.
#   bash tests/test_io_ranks.sh build/tests/test_io_ranks [build/tests/test_io]
set -u
bin=${1:?usage: test_io_ranks.sh build/tests/test_io_ranks [build/tests/test_io]}
io=${2:-$(dirname "$bin")/test_io}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
MPIRUN="mpirun --allow-run-as-root --oversubscribe"
fail=0
check() { if eval "$2"; then echo "PASS $1"; else echo "FAIL $1"; fail=1; return 1; fi; }

for np in 1 2 3; do
    timeout 120 $MPIRUN -np $np "$bin" "$tmp" >"$tmp/np$np.log" 2>&1
    check "$np rank(s): written and checked by the writer" "[ $? -eq 0 ]" || tail -n 20 "$tmp/np$np.log"
done

${PYTHON:-/usr/bin/python3} - "$tmp" <<'EOF'
import sys
import h5py, numpy as np
d = sys.argv[1]
files = [h5py.File(f"{d}/snapshot_{np_:05d}.h5", "r") for np_ in (1, 2, 3)]
bad = 0
def report(ok, what):
    global bad
    print(("PASS " if ok else "FAIL ") + what)
    bad += not ok
ref = files[0]
ids = ref["Particles/ParticleIDs"][...]
report(len(ids) == 1001 and np.all(np.diff(ids) > 0), "1 rank: ParticleIDs strictly increasing, 1001 rows")
for f, np_ in zip(files[1:], (2, 3)):
    report(set(f["Particles"]) == set(ref["Particles"]), f"{np_} ranks: same fields")
    for name, a in ref["Particles"].items():
        b = f["Particles"][name]
        same = a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a[...], b[...])
        same = same and dict(a.attrs) == dict(b.attrs)
        report(same, f"{np_} ranks: /Particles/{name} identical to 1 rank")
    report(dict(f["Header"].attrs) == dict(ref["Header"].attrs), f"{np_} ranks: same /Header")
sys.exit(1 if bad else 0)
EOF
check "files identical field by field across rank counts" "[ $? -eq 0 ]"

timeout 120 $MPIRUN -np 3 "$io" >"$tmp/io3.log" 2>&1
check "test_io on 3 ranks" "[ $? -eq 0 ]" || tail -n 30 "$tmp/io3.log"

mkdir -p "$tmp/dup"
timeout 120 $MPIRUN -np 3 "$bin" "$tmp/dup" dup >"$tmp/dup.log" 2>&1
rc=$?
check "duplicate ID refused (exit $rc)" "[ $rc -ne 0 ] && grep -q 'is held twice' '$tmp/dup.log'"
check "duplicate ID: no final snapshot" "[ ! -e '$tmp/dup/snapshot_00003.h5' ]"
exit $fail
