#!/usr/bin/env bash
# The job scripts in their no-SLURM mode: jobs/scaling_weak.sbatch on a tiny
# shear box with RANKS=1 writes a CSV with the documented columns and a
# positive rate; tools/scaling_plot.py reads it (1-rank rows only) and writes
# its PNG and table; the done: parser reads halo_s when present and leaves it
# empty when not; restart_chain.sh submits K jobs chained by afterok (a stub
# sbatch) and passes --restart OUTDIR only when OUTDIR holds a checkpoint;
# issue 19: the chain checks TIME - MARGIN before submitting, resubmits
# itself by its full path from any directory, drops GPU flags with GPUS=0;
# the launcher returns 0 with SRUN_FLAGS empty and passes --mpi=pmix;
# sphseg_run passes the batch shell's signals on to sphseg.
set -u
bin=${1:?usage: test_jobs.sh build/sphseg}
PY=${PYTHON:-/usr/bin/python3}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "PASS $1"; else echo "FAIL $1"; fail=1; return 1; fi; }
unset "${!SLURM_@}" # the no-SLURM mode, even inside a job

for s in jobs/*.sbatch jobs/*.sh; do check "bash -n $s" "bash -n '$s'"; done

RANKS=1 SCENE=inputs/shearbox_2d.yml SCALE_KEY=Geometry:dr SCALE_BASE=0.00348 SCALE_POWER=-0.5 MAX_STEPS=5 \
    CSV="$tmp/weak.csv" OUTROOT="$tmp/runs" SPHSEG="$bin" OMP_NUM_THREADS=1 \
    bash jobs/scaling_weak.sbatch >"$tmp/weak.log" 2>&1
check "scaling_weak RANKS=1 exit 0" "[ $? -eq 0 ]" || cat "$tmp/weak.log"
check "scaling_weak CSV: columns, one row, positive rate" "$PY - '$tmp/weak.csv' <<'PYEOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
want = 'mode,ranks,particles,steps,wall_s,particle_steps_per_s,halo_s,io_s,scene,dr,scaled_key,scaled_value,max_steps,job'
assert open(sys.argv[1]).readline().strip() == want, 'header'
assert len(rows) == 1, rows
r = rows[0]
assert r['mode'] == 'weak' and r['ranks'] == '1' and r['steps'] == '5', r
assert float(r['particle_steps_per_s']) > 0 and float(r['wall_s']) > 0 and int(r['particles']) > 0, r
assert r['scaled_key'] == 'Geometry:dr' and float(r['scaled_value']) == 0.00348 and float(r['dr']) == 0.00348, r
assert float(r['halo_s']) == 0, r  # one rank: no halo exchange
PYEOF"
"$PY" tools/scaling_plot.py "$tmp/weak.csv" --png "$tmp/s.png" >"$tmp/plot.log" 2>&1
check "scaling_plot on 1-rank rows" "[ $? -eq 0 ] && [ -s '$tmp/s.png' ] && grep -q '^| weak | 1 |.*| 1.000 |' '$tmp/plot.log'" || cat "$tmp/plot.log"

source jobs/common.sh
line='done: 20 steps, 1.500 s wall, 8.5657e+05 particle-steps/s, max |drift of sum C V| 1.221e-15, 0.250 s of the wall in output and diagnostics (not in the rate)'
printf 'sphseg 0.1.0: x, 275 material + 219 dummy particles\n%s, 0.031 s in halo exchange\n' "$line" >"$tmp/a.log"
printf '%s\n' "$line" >"$tmp/b.log"
check "done: parser with halo" "[ \"\$(sphseg_parse_log '$tmp/a.log')\" = '494,20,1.500,8.5657e+05,0.031,0.250' ]"
check "done: parser without halo" "[ \"\$(sphseg_parse_log '$tmp/b.log')\" = ',20,1.500,8.5657e+05,,0.250' ]"
check "done: parser, no done line" "! sphseg_parse_log /dev/null"

mkdir -p "$tmp/bin" "$tmp/chain"
printf '#!/bin/sh\necho "$*" >>"%s/calls"\necho "$((100 + $(wc -l <"%s/calls")));cluster"\n' "$tmp" "$tmp" >"$tmp/bin/sbatch"
chmod +x "$tmp/bin/sbatch"
PATH="$tmp/bin:$PATH" K=3 TIME=1:00:00 OUTDIR="$tmp/chain" SPHSEG="$bin" bash jobs/restart_chain.sh -P Geometry:dr=0.004 >"$tmp/chain.log" 2>&1
check "restart_chain submits 3 jobs chained by afterok" "[ \$(wc -l <'$tmp/calls') -eq 3 ] && ! head -1 '$tmp/calls' | grep -q dependency && sed -n 2p '$tmp/calls' | grep -q -- '--dependency=afterok:101 ' && sed -n 3p '$tmp/calls' | grep -q -- '--dependency=afterok:102 ' && grep -q -- '--time=1:00:00 .*--step -P Geometry:dr=0.004' '$tmp/calls'" || cat "$tmp/chain.log"
NO_SLURM=1 DRYRUN=1 K=1 TIME=1:00:00 OUTDIR="$tmp/chain" SPHSEG="$bin" bash jobs/restart_chain.sh >"$tmp/d1.log" 2>&1
check "restart_chain fresh start, max_wall_time = TIME - MARGIN" "grep -q -- '-o $tmp/chain -P Run:max_wall_time=3000\$' '$tmp/d1.log'" || cat "$tmp/d1.log"
touch "$tmp/chain/checkpoint.h5"
NO_SLURM=1 DRYRUN=1 K=1 TIME=1:00:00 OUTDIR="$tmp/chain" SPHSEG="$bin" bash jobs/restart_chain.sh >"$tmp/d2.log" 2>&1
check "restart_chain restarts from OUTDIR (its newest valid checkpoint)" "grep -q -- '--restart $tmp/chain -P Run:max_wall_time=3000\$' '$tmp/d2.log'" || cat "$tmp/d2.log"
rm "$tmp/chain/checkpoint.h5"; touch "$tmp/chain/checkpoint_prev.h5"
NO_SLURM=1 DRYRUN=1 K=1 TIME=1:00:00 OUTDIR="$tmp/chain" SPHSEG="$bin" bash jobs/restart_chain.sh >"$tmp/d3.log" 2>&1
check "restart_chain restarts when only checkpoint_prev.h5 is left" "grep -q -- '--restart $tmp/chain -P' '$tmp/d3.log'" || cat "$tmp/d3.log"

# issue 19, defect 10: what a real SLURM showed
rm -f "$tmp/calls"
(cd /tmp && PATH="$tmp/bin:$PATH" K=2 TIME=5:00 MARGIN=600 OUTDIR="$tmp/chain2" SPHSEG="$bin" bash "$OLDPWD/jobs/restart_chain.sh" >"$tmp/early.log" 2>&1)
check "restart_chain: TIME - MARGIN <= 0 refused before any submission" "[ $? -eq 2 ] && [ ! -e '$tmp/calls' ] && grep -q 'nothing submitted' '$tmp/early.log'" || cat "$tmp/early.log"
(cd /tmp && PATH="$tmp/bin:$PATH" K=1 TIME=1:00:00 GPUS=0 OUTDIR="$tmp/chain2" SPHSEG="$bin" bash "$OLDPWD/jobs/restart_chain.sh" >"$tmp/cpu.log" 2>&1)
check "restart_chain from another directory, GPUS=0: the script by its full path, --chdir, no GPU flag" "grep -q -- '--chdir=$PWD .*$PWD/jobs/restart_chain.sh --step' '$tmp/calls' && ! grep -q gpus '$tmp/calls'" || cat "$tmp/calls" "$tmp/cpu.log"
launcher_is() { # expected, env assignments...: sphseg_launcher under SLURM (set -e) gives expected
    (set -e; export SLURM_JOB_ID=1 GPUS=0 "${@:2}"; sphseg_launcher 2; [ "${launch[*]}" = "$1" ])
}
check "sphseg_launcher under SLURM, SRUN_FLAGS empty: status 0 (set -e), --mpi=pmix" \
    "launcher_is 'srun --ntasks=2 --cpus-per-task=1 --mpi=pmix --cpu-bind=cores' SRUN_FLAGS="
check "sphseg_launcher: SRUN_MPI= leaves the site's default, SRUN_FLAGS appended" \
    "launcher_is 'srun --ntasks=2 --cpus-per-task=1 --cpu-bind=cores --exclusive -l' SRUN_MPI= 'SRUN_FLAGS=--exclusive -l'"
# the batch shell gets the signal (--signal=B:USR1, scancel): sphseg_run passes it on as SIGUSR1
bash -c "source jobs/common.sh; OMP_NUM_THREADS=1 sphseg_run '$bin' inputs/shearbox_2d.yml -o '$tmp/fwd' -P Run:t_end=5000 -P Output:dt=100 -P Run:progress_s=0.01" >"$tmp/fwd.log" 2>&1 &
pid=$!
for _ in $(seq 200); do grep -q '^step ' "$tmp/fwd.log" && break; sleep 0.05; done
kill -TERM $pid; wait $pid; rc=$?
check "sphseg_run: SIGTERM to the batch shell -> sphseg checkpoints, the shell exits 0" "[ $rc -eq 0 ] && grep -q 'received SIGUSR1' '$tmp/fwd.log' && [ -f '$tmp/fwd/checkpoint.h5' ]" || { echo "rc $rc"; tail -3 "$tmp/fwd.log"; }
exit $fail
