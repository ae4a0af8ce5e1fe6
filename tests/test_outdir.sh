#!/usr/bin/env bash
# One run per output directory, and checkpoints that survive a kill
# (issue 19, defects 3 and 4):
#  - a fresh run into an OUTDIR holding another run exits 2 with one line,
#    touching nothing; --overwrite replaces the earlier run's files (no old
#    snapshot stays beside the new ones);
#  - a run holds OUTDIR/sphseg.lock: a second run into it exits 2 at once;
#    the lock of a killed run (SIGKILL) is gone with it;
#  - killed between the two steps of the checkpoint rotation (a test-only
#    LD_PRELOAD shim, tests/shim_kill.c, with SHIM_KILL=/checkpoint.h5:2:
#    rank 0 is killed after linking the first checkpoint to
#    checkpoint_prev.h5, just before the second is renamed to
#    checkpoint.h5), OUTDIR still has checkpoint.h5, and
#    --restart OUTDIR continues;
#  - --restart OUTDIR takes the newest valid checkpoint: checkpoint_prev.h5
#    when checkpoint.h5 is damaged; both damaged: exit 2 naming both.
set -u
bin=${1:?usage: test_outdir.sh build/sphseg}
. "$(dirname "$0")/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
export OMP_NUM_THREADS=1
scene=inputs/shearbox_2d.yml
short=(-P Run:t_end=3 -P Output:dt=1 -P Output:checkpoint_dt=1)

o=$tmp/run
"$bin" $scene -o "$o" "${short[@]}" >"$tmp/a.log" 2>&1
check "a first run" "[ $? -eq 0 ] && [ -f '$o/snapshot_00003.h5' ]"
listing() { ls -l --time-style=+%s.%N "$1" | grep -v sphseg.lock | md5sum; }
before=$(listing "$o")
"$bin" $scene -o "$o" -P Run:t_end=1 -P Output:dt=0.5 >"$tmp/b.log" 2>&1
rc=$?
check "a fresh run into it: exit 2, one line, nothing touched" \
    "[ $rc -eq 2 ] && [ \$(wc -l <'$tmp/b.log') -eq 1 ] && grep -q 'holds another run.*--overwrite' '$tmp/b.log' && [ \"\$(listing '$o')\" = '$before' ]" || cat "$tmp/b.log"
"$bin" $scene -o "$o" -P Run:t_end=1 -P Output:dt=0.5 --overwrite >"$tmp/c.log" 2>&1
check "--overwrite: the old run's files are gone, the new run's written" \
    "[ $? -eq 0 ] && [ -f '$o/snapshot_00002.h5' ] && [ ! -e '$o/snapshot_00003.h5' ] && [ ! -e '$o/checkpoint.h5' ] && [ \"\$(tail -1 '$o/diagnostics.csv' | cut -d, -f2)\" = 1 ]" || { cat "$tmp/c.log"; ls "$o"; }

# the lock: a run in progress, then a second one into the same OUTDIR
"$bin" $scene -o "$tmp/busy" -P Run:t_end=5000 -P Output:dt=100 -P Run:progress_s=0.01 >"$tmp/busy.log" 2>&1 &
pid=$!
for _ in $(seq 200); do grep -q '^step ' "$tmp/busy.log" && break; sleep 0.05; done
"$bin" $scene -o "$tmp/busy" --overwrite -P Run:t_end=1 -P Output:dt=0.5 >"$tmp/second.log" 2>&1
rc=$?
check "a second run into an OUTDIR in use: exit 2 naming the lock" \
    "[ $rc -eq 2 ] && grep -q 'another sphseg run is writing there.*sphseg.lock: pid $pid' '$tmp/second.log'" || cat "$tmp/second.log"
kill -KILL $pid; wait $pid 2>/dev/null
"$bin" $scene -o "$tmp/busy" --overwrite -P Run:t_end=1 -P Output:dt=0.5 >"$tmp/third.log" 2>&1
check "after the first was killed (SIGKILL), its lock is gone" "[ $? -eq 0 ]" || cat "$tmp/third.log"

# killed in the middle of the rotation: checkpoint.h5 is still there
o=$tmp/rot
rc=none
if cc -O2 -shared -fPIC -o "$tmp/shim_kill.so" tests/shim_kill.c -ldl; then
    SHIM_KILL=/checkpoint.h5:2 LD_PRELOAD="$tmp/shim_kill.so" "$bin" $scene -o "$o" "${short[@]}" >"$tmp/rot.log" 2>&1
    rc=$?
fi
check "killed between linking checkpoint_prev.h5 and renaming the new checkpoint: checkpoint.h5 exists" \
    "[ $rc = 137 ] && [ -f '$o/checkpoint.h5' ] && [ -f '$o/checkpoint_prev.h5' ]" || { echo "exit $rc"; ls "$o"; }
"$bin" $scene -o "$o" --restart "$o" "${short[@]}" >"$tmp/rot2.log" 2>&1
check "--restart OUTDIR continues from it" "[ $? -eq 0 ] && grep -q '^restart from $o/checkpoint.h5: step 10,' '$tmp/rot2.log'" || cat "$tmp/rot2.log"

# the newest valid checkpoint of a directory
o=$tmp/pick
"$bin" $scene -o "$o" "${short[@]}" >/dev/null 2>&1
printf '\x55' | dd of="$o/checkpoint.h5" bs=1 seek=20000 conv=notrunc status=none
"$bin" $scene -o "$o" --restart "$o" -P Run:t_end=4 -P Output:dt=1 >"$tmp/pick.log" 2>&1
check "checkpoint.h5 damaged: --restart OUTDIR takes checkpoint_prev.h5, saying why" \
    "[ $? -eq 0 ] && grep -q 'checkpoint.h5: damaged: its checksum does not match.*taking checkpoint_prev.h5' '$tmp/pick.log' && grep -q '^restart from $o/checkpoint_prev.h5: step' '$tmp/pick.log'" || cat "$tmp/pick.log"
o=$tmp/pick2
"$bin" $scene -o "$o" "${short[@]}" >/dev/null 2>&1
for f in checkpoint.h5 checkpoint_prev.h5; do printf '\x55' | dd of="$o/$f" bs=1 seek=20000 conv=notrunc status=none; done
"$bin" $scene -o "$o" --restart "$o/checkpoint.h5" "${short[@]}" >"$tmp/file.log" 2>&1
rc=$?
check "a damaged FILE: exit 2, one line, pointing to the directory" \
    "[ $rc -eq 2 ] && [ \$(wc -l <'$tmp/file.log') -eq 1 ] && grep -q 'checkpoint_prev.h5 is beside it: --restart $o takes' '$tmp/file.log'" || cat "$tmp/file.log"
"$bin" $scene -o "$o" --restart "$o" "${short[@]}" >"$tmp/both.log" 2>&1
rc=$?
check "both damaged: exit 2, one line naming both" \
    "[ $rc -eq 2 ] && [ \$(wc -l <'$tmp/both.log') -eq 1 ] && grep -q 'no valid checkpoint in it: checkpoint.h5: damaged.*checkpoint_prev.h5: damaged' '$tmp/both.log'" || cat "$tmp/both.log"
"$bin" $scene -o "$tmp/empty_run" --restart "$tmp" "${short[@]}" >"$tmp/none.log" 2>&1
rc=$?
check "--restart DIR without checkpoints: exit 2, one line" "[ $rc -eq 2 ] && [ \$(wc -l <'$tmp/none.log') -eq 1 ]" || cat "$tmp/none.log"
exit $fail
