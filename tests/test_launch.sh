#!/usr/bin/env bash
# Launch checks: one rank without mpirun and under mpirun, the files of the
# DESIGN.md contract, no temporary names left, a progress line; two ranks
# run the slab decomposition and write the same diagnostics (the fields are
# compared in validate_mpi.py); more ranks than the domain has slabs for are
# refused with exit 2 before anything is written.
set -u
bin=${1:?usage: test_launch.sh build/sphseg}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
MPIRUN="mpirun --allow-run-as-root --oversubscribe"
fail=0
check() { if eval "$2"; then echo "PASS $1"; else echo "FAIL $1"; fail=1; fi; }
args=(inputs/shearbox_2d.yml -P Geometry:dr=0.00348 -P Run:t_end=26 -P Output:dt=13 -P Run:progress_s=0.001)

"$bin" "${args[@]}" -o "$tmp/a" >"$tmp/a.out" 2>"$tmp/a.err"
check "singleton exit 0" '[ $? -eq 0 ]'
for f in snapshot_00000.h5 snapshot_00001.h5 snapshot_00002.h5 snapshots.xmf diagnostics.csv used_params.yml; do
    check "singleton wrote $f" "[ -s '$tmp/a/$f' ]"
done
check "no temporary files left" "[ -z \"\$(ls '$tmp/a' | grep -E '\\.(tmp|part)\$')\" ]"
check "progress line" "grep -q 'particle-steps/s' '$tmp/a.out'"
check "diagnostics header" "head -1 '$tmp/a/diagnostics.csv' | grep -q '^step,time,dt,n_material,small_volume,small_volume_drift,kinetic_energy,max_speed,wall_s'"
check "snapshot time" "${PYTHON:-/usr/bin/python3} -c \"import h5py,sys; f=h5py.File('$tmp/a/snapshot_00002.h5'); sys.exit(0 if abs(f['Header'].attrs['Time']-26)<1e-9 else 1)\""

$MPIRUN -np 1 "$bin" "${args[@]}" -o "$tmp/b" >"$tmp/b.out" 2>"$tmp/b.err"
check "mpirun -np 1 exit 0" '[ $? -eq 0 ]'
check "mpirun -np 1 same diagnostics" "diff <(cut -d, -f1-6 '$tmp/a/diagnostics.csv') <(cut -d, -f1-6 '$tmp/b/diagnostics.csv') >/dev/null"

$MPIRUN -np 2 "$bin" "${args[@]}" -o "$tmp/c" >"$tmp/c.out" 2>"$tmp/c.err"
check "two ranks exit 0" '[ $? -eq 0 ]'
check "two ranks: slab decomposition line" "grep -q 'slab decomposition along' '$tmp/c.out'"
check "two ranks: same steps, times and n_material" "diff <(cut -d, -f1-2,4 '$tmp/a/diagnostics.csv') <(cut -d, -f1-2,4 '$tmp/c/diagnostics.csv') >/dev/null"

$MPIRUN -np 4 "$bin" "${args[@]}" -P Geometry:dr=0.009 -o "$tmp/d" >"$tmp/d.out" 2>"$tmp/d.err"
rc=$?
check "too many ranks for the domain refused with exit 2" "[ $rc -eq 2 ] && grep -q 'Parallel: 4 ranks need' '$tmp/d.err'"
exit $fail
