#!/usr/bin/env bash
# test_inputs.sh BINARY — every scene in inputs/ and inputs/examples/ loads and
# steps: 5 steps of each, no snapshots, exit 0, a done: line and no warning
# (one OpenMP thread: the oversubscription warning depends on the machine).
# The scenes are the documented starting points users copy; a key renamed, a
# check tightened or a warning added must not leave one of them broken or
# warned about. Prints PASS/FAIL per scene; exits 1 on any FAIL.
set -u
bin=${1:?usage: $0 BINARY}
here=$(cd "$(dirname "$0")" && pwd)
. "$(dirname "$0")/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
for scene in "$here"/../inputs/*.yml "$here"/../inputs/examples/*.yml; do
    name=$(basename "$scene" .yml)
    [ "$(basename "$(dirname "$scene")")" = examples ] && name=examples_$name
    # the 3D drum at its default resolution holds 1.7e5 particles: coarser here
    extra=()
    [ "$name" = drum_3d ] && extra=(-P Geometry:dr=0.002 -P Geometry:length=0.01)
    [ "$name" = collapse_3d ] && extra=(-P Geometry:dr=0.002)
    if OMP_NUM_THREADS=1 "$bin" "$scene" -o "$tmp/$name" --backend cpu -P Run:max_steps=5 -P Output:snapshots=off \
        -P Run:progress_s=1e9 "${extra[@]}" >"$tmp/$name.log" 2>&1 && grep -q '^done: 5 steps' "$tmp/$name.log" &&
        ! grep -q 'warning:' "$tmp/$name.log"; then
        echo "PASS $name"
    else
        echo "FAIL $name"
        tail -n 3 "$tmp/$name.log" | sed 's/^/    /'
        fail=1
    fi
done
exit $fail
