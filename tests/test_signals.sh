#!/usr/bin/env bash
# Signals (issue 19, defect 1): SIGTERM, SIGUSR1 and SIGINT make every rank
# finish its step, write a checkpoint and exit 0, printing the command that
# continues; diagnostics.csv is closed (no .part left). The printed command
# continues the run, and its end is bit-identical to a run never stopped.
# A second SIGTERM ends the process at once (status 128 + 15), unless it
# comes within 0.25 s of the first (a copy of it, as srun delivers).
set -u
bin=${1:?usage: test_signals.sh build/sphseg}
PY=${PYTHON:-/usr/bin/python3}
. "$(dirname "$0")/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
export OMP_NUM_THREADS=1
MPI="mpirun --oversubscribe --allow-run-as-root"
scene=inputs/shearbox_2d.yml
long=(-P Run:t_end=2000 -P Output:dt=13 -P Run:progress_s=0.01)

START_TRIES=200 # start_run (testlib.sh): 10 s for a run to start stepping

for sig in TERM USR1 INT; do
    d=$tmp/one_$sig
    start_run "$d.log" "$bin" $scene -o "$d" "${long[@]}"
    kill -$sig $pid; wait $pid; rc=$?
    check "1 rank, SIG$sig: exit 0, checkpoint, restart command" \
        "[ $rc -eq 0 ] && grep -q 'received SIG$sig; wrote $d/checkpoint.h5' '$d.log' && grep -q -- '--restart $d' '$d.log' && [ -f '$d/checkpoint.h5' ] && [ -f '$d/diagnostics.csv' ] && [ ! -e '$d/diagnostics.csv.part' ]" || tail -5 "$d.log"
done

d=$tmp/two_USR1
start_run "$d.log" $MPI -np 2 "$bin" $scene -o "$d" "${long[@]}"
kill -USR1 $pid; wait $pid; rc=$?
check "2 ranks under mpirun, SIGUSR1: exit 0, checkpoint" \
    "[ $rc -eq 0 ] && grep -q 'received SIGUSR1' '$d.log' && [ -f '$d/checkpoint.h5' ]" || tail -5 "$d.log"

# the printed command continues to a t_end past the stop; the end matches a straight run
d=$tmp/one_TERM
t_stop=$(sed -n 's/^stopping at step [0-9]*, t = \([0-9.e+-]*\) s.*/\1/p' "$d.log")
t_end=$("$PY" -c "import math; print(13 * (math.floor(float('$t_stop') / 13) + 2))")
cmd=$(grep -A1 '^stopping at' "$d.log" | tail -1 | sed "s|^  ||; s|Run:t_end=2000|Run:t_end=$t_end|") # the command as printed (its binary the one run), t_end changed
eval "$cmd" >"$d.restart.log" 2>&1
check "the printed command continues the run to t_end = $t_end" "[ $? -eq 0 ] && grep -q '^done:' '$d.restart.log'" || tail -5 "$d.restart.log"
"$bin" $scene -o "$tmp/straight" -P Run:t_end=$t_end -P Output:dt=13 >"$tmp/straight.log" 2>&1
last=$(printf 'snapshot_%05d.h5' $(( $(ls "$tmp/straight"/snapshot_*.h5 | wc -l) - 1 )))
check "stopped by SIGTERM and continued = never stopped, bit for bit ($last)" "'$PY' - '$d/$last' '$tmp/straight/$last' <<'PYEOF'
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
assert a['Header'].attrs['Time'] == b['Header'].attrs['Time']
for k in b['Particles']:
    assert np.array_equal(a['Particles'][k][()], b['Particles'][k][()]), k
PYEOF"

# a second SIGTERM ends the process at once; one within 0.25 s of the first
# is a copy of it (SLURM signals every task and srun forwards its own copy)
# and does not. A fine lattice (steps of a second or more): the signals land
# in the step after a progress line.
fine=(-P Geometry:dr=0.0001)
d=$tmp/twice
start_run "$d.log" "$bin" $scene -o "$d" "${long[@]}" "${fine[@]}"
kill -TERM $pid; sleep 0.5; kill -TERM $pid; wait $pid; rc=$?
check "a second SIGTERM 0.5 s later ends at once (status $rc = 143)" "[ $rc -eq 143 ] && [ ! -e '$d/checkpoint.h5' ]"
d=$tmp/echo
start_run "$d.log" "$bin" $scene -o "$d" "${long[@]}" "${fine[@]}"
kill -TERM $pid; kill -TERM $pid; wait $pid; rc=$?
check "the same SIGTERM twice at once (as under srun): one stop, checkpoint, exit 0" \
    "[ $rc -eq 0 ] && grep -q 'received SIGTERM' '$d.log' && [ -f '$d/checkpoint.h5' ]" || tail -3 "$d.log"
exit $fail
