#!/usr/bin/env bash
# The command a stopped run prints continues it (issue 55, defect 2). A run
# stopped by SIGTERM prints the command it was started with (the binary as
# argv[0] named it; on N ranks after "mpirun -np N") with --restart OUTDIR;
# run as printed (bash -c), it continues the run in the same folder:
# - 1 rank, a renamed scene, no -o (OUTDIR out/my): stopped, continued,
#   stopped again (the second command has one --restart, not two), continued
#   to t_end; diagnostics.csv holds every row once, in step order, and the
#   last snapshot is bit-identical to a run never stopped;
# - 2 ranks under mpirun, with -o: the command starts "mpirun -np 2" and
#   continues the run on 2 ranks in its folder (run here with Open MPI's
#   environment for root and oversubscription, which a cluster would not
#   need);
# - --restart DIR without -o, the scene file renamed: the run continues in
#   DIR (its diagnostics.csv grows, its first rows kept), not out/<scene>.
set -u
bin=$(realpath "${1:?usage: test_continue.sh build/sphseg}")
PY=${PYTHON:-/usr/bin/python3}
repo=$(pwd)
. "$(dirname "$0")/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
export OMP_NUM_THREADS=1
cd "$tmp" || exit 1
cp "$repo/inputs/shearbox_2d.yml" my.yml
opts=(-P Run:t_end=78 -P Output:dt=13 -P Run:progress_s=0.01)

printed() { grep -A1 '^stopping at' "$1" | tail -1 | sed 's/^  //'; }
# diagnostics.csv: one header, steps from 0 strictly increasing, ending at t_end (78 s)
diag_whole() {
    "$PY" - "$1" <<'PYEOF'
import sys
rows = open(sys.argv[1]).read().splitlines()
assert rows[0].startswith("step,time") and sum(r.startswith("step") for r in rows) == 1, "headers"
steps = [int(r.split(",")[0]) for r in rows[1:]]
assert steps[0] == 0 and all(a < b for a, b in zip(steps, steps[1:])), steps
assert abs(float(rows[-1].split(",")[1]) - 78) < 1e-9, rows[-1]
PYEOF
}

# ---- 1 rank, no -o: stop, continue, stop, continue --------------------------
start_run one.log "$bin" my.yml "${opts[@]}"
kill -TERM $pid; wait $pid; rc=$?
cmd1=$(printed one.log)
check "1 rank: SIGTERM, exit 0; the command is the one given, with --restart out/my: $cmd1" \
    "[ $rc -eq 0 ] && [ \"\$cmd1\" = \"$bin my.yml ${opts[*]} --restart out/my\" ]" || tail -3 one.log
start_run one_b.log bash -c "$cmd1"
kill -TERM $pid; wait $pid; rc=$?
cmd2=$(printed one_b.log)
check "1 rank: the printed command continues from out/my, stopped again prints one --restart" \
    "[ $rc -eq 0 ] && grep -q '^restart from out/my/checkpoint.h5' one_b.log && [ \"\$cmd2\" = \"\$cmd1\" ]" ||
    { tail -3 one_b.log; echo "second command: $cmd2"; }
bash -c "$cmd2" >one_c.log 2>&1
check "1 rank: the second command continues to t_end in out/my, no other folder" \
    "[ $? -eq 0 ] && grep -q '^restart from out/my/checkpoint.h5' one_c.log && grep -q '^done:' one_c.log && [ \"\$(ls out)\" = my ]" ||
    tail -3 one_c.log
check "1 rank: out/my/diagnostics.csv holds every row once, in order, to t_end" "diag_whole out/my/diagnostics.csv"
"$bin" my.yml -o straight "${opts[@]}" >straight.log 2>&1
last=$(printf 'snapshot_%05d.h5' $(( $(ls straight/snapshot_*.h5 | wc -l) - 1 )))
check "1 rank: stopped twice and continued = never stopped, bit for bit ($last)" "'$PY' - out/my/$last straight/$last <<'PYEOF'
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
assert a['Header'].attrs['Time'] == b['Header'].attrs['Time']
for k in b['Particles']:
    assert np.array_equal(a['Particles'][k][()], b['Particles'][k][()]), k
PYEOF"

# ---- 2 ranks under mpirun, -o -----------------------------------------------
# SIGTERM to each rank, as SLURM signals every task (mpirun signalled itself exits 1 once its ranks end)
start_run two.log mpirun --oversubscribe --allow-run-as-root -np 2 "$bin" my.yml -o "$tmp/two" "${opts[@]}"
kill -TERM $(pgrep -P $pid); wait $pid; rc=$?
cmd=$(printed two.log)
check "2 ranks: SIGTERM, exit 0; the command starts with mpirun -np 2: $cmd" \
    "[ $rc -eq 0 ] && [ \"\$cmd\" = \"mpirun -np 2 $bin my.yml -o $tmp/two ${opts[*]} --restart $tmp/two\" ]" || tail -3 two.log
OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 bash -c "$cmd" >two_b.log 2>&1
check "2 ranks: the printed command continues on 2 ranks in the same folder to t_end" \
    "[ $? -eq 0 ] && grep -q '^restart from $tmp/two/checkpoint.h5' two_b.log && grep -q ' 2 rank(s)' two_b.log && diag_whole '$tmp/two/diagnostics.csv'" ||
    tail -3 two_b.log

# ---- --restart DIR without -o, the scene renamed -----------------------------
cp my.yml renamed.yml
rows=$(wc -l <"$tmp/two/diagnostics.csv")
head -2 "$tmp/two/diagnostics.csv" >head.csv  # the header and the row of t = 0 (later rows are rewritten from the checkpoint on)
"$bin" renamed.yml -P Run:t_end=104 -P Output:dt=13 --restart "$tmp/two" >renamed.log 2>&1
check "--restart DIR without -o continues in DIR: its diagnostics.csv grows, its row of t = 0 kept; no out/renamed" \
    "[ $? -eq 0 ] && [ \$(wc -l <'$tmp/two/diagnostics.csv') -gt $rows ] && [ \"\$(head -2 '$tmp/two/diagnostics.csv')\" = \"\$(cat head.csv)\" ] && [ ! -e out/renamed ] && ! grep -q 'rows start afresh' renamed.log" ||
    tail -3 renamed.log
exit $fail
