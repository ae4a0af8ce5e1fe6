#!/usr/bin/env bash
# The job scripts in their no-SLURM mode: jobs/scaling_weak.sbatch on a tiny
# shear box with RANKS=1 writes a CSV with the documented columns and a
# positive rate; tools/bench/scaling_plot.py reads it (1-rank rows only) and writes
# its PNG and table; the done: parser reads halo_s when present and leaves it
# empty when not; restart_chain.sh submits K jobs chained by afterok (a stub
# sbatch) and passes --restart OUTDIR only when OUTDIR holds a checkpoint;
# issue 19: the chain checks TIME - MARGIN before submitting, resubmits
# itself by its full path from any directory, drops GPU flags with GPUS=0;
# the launcher returns 0 with SRUN_FLAGS empty and passes --mpi=pmix;
# sphseg_run passes the batch shell's signals on to sphseg; issue 33: the
# chain asks sbatch --test-only first (the same arguments as its first
# submission) and, where the job could never start, says what to set
# (SBATCH_FLAGS) and submits nothing; the launcher passes --cpu-bind only
# where scontrol's TaskPlugin binds (task/affinity, task/cgroup).
set -u
bin=${1:?usage: test_jobs.sh build/sphseg}
PY=${PYTHON:-/usr/bin/python3}
. "$(dirname "$0")/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
unset "${!SLURM_@}" # the no-SLURM mode, even inside a job

for s in jobs/*.sbatch jobs/*.sh; do check "bash -n $s" "bash -n '$s'"; done

RANKS=1 SETTINGS=scene SCENE=inputs/shearbox_2d.yml SCALE_KEY=Geometry:dr SCALE_BASE=0.00348 SCALE_POWER=-0.5 MAX_STEPS=5 \
    CSV="$tmp/weak.csv" OUTROOT="$tmp/runs" SPHSEG="$bin" OMP_NUM_THREADS=1 \
    bash jobs/scaling_weak.sbatch >"$tmp/weak.log" 2>&1
check "scaling_weak RANKS=1 exit 0" "[ $? -eq 0 ]" || cat "$tmp/weak.log"
check "scaling_weak CSV: columns, one row, positive rate" "$PY - '$tmp/weak.csv' <<'PYEOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
want = 'mode,ranks,particles,steps,wall_s,particle_steps_per_s,halo_s,io_s,scene,dr,scaled_key,scaled_value,max_steps,job,settings'
assert open(sys.argv[1]).readline().strip() == want, 'header'
assert len(rows) == 1, rows
r = rows[0]
assert r['mode'] == 'weak' and r['ranks'] == '1' and r['steps'] == '5' and r['settings'] == 'scene', r
assert float(r['particle_steps_per_s']) > 0 and float(r['wall_s']) > 0 and int(r['particles']) > 0, r
assert r['scaled_key'] == 'Geometry:dr' and float(r['scaled_value']) == 0.00348 and float(r['dr']) == 0.00348, r
assert float(r['halo_s']) == 0, r  # one rank: no halo exchange
PYEOF"
"$PY" -m tools.bench.scaling_plot "$tmp/weak.csv" --png "$tmp/s.png" >"$tmp/plot.log" 2>&1
check "scaling_plot on 1-rank rows" "[ $? -eq 0 ] && [ -s '$tmp/s.png' ] && grep -q '^| weak | 1 |.*| 1.000 |' '$tmp/plot.log'" || cat "$tmp/plot.log"

source jobs/common.sh
line='done: 20 steps, 1.500 s wall, 8.5657e+05 particle-steps/s, max |drift of sum C V| 1.221e-15, 0.250 s of the wall in output and diagnostics (not in the rate)'
printf 'sphseg 0.1.0: x, 275 material + 219 dummy particles\n%s, 0.031 s in halo exchange\n' "$line" >"$tmp/a.log"
printf '%s\n' "$line" >"$tmp/b.log"
check "done: parser with halo" "[ \"\$(sphseg_parse_log '$tmp/a.log')\" = '494,20,1.500,8.5657e+05,0.031,0.250' ]"
check "done: parser without halo" "[ \"\$(sphseg_parse_log '$tmp/b.log')\" = ',20,1.500,8.5657e+05,,0.250' ]"
check "done: parser, no done line" "! sphseg_parse_log /dev/null"

mkdir -p "$tmp/bin" "$tmp/chain"
# stub sbatch: a submission is appended to calls (job ids 101, 102, ...);
# --test-only to tests, answered as SLURM answers it: "could never start"
# when the job asks for more CPUs per task (its script's #SBATCH line, then
# the command line) than FAKE_CPUS (a small partition; unset: any number)
cat >"$tmp/bin/sbatch" <<'SH'
#!/usr/bin/env bash
log=$(dirname "$0")/..
case " $* " in *" --test-only "*) ;; *)
    echo "$*" >>"$log/calls"; echo "$((100 + $(wc -l <"$log/calls")));cluster"; exit 0 ;;
esac
echo "$*" >>"$log/tests"
for a in "$@"; do case $a in -*) ;; *) script=$a; break ;; esac; done
cpus=$(sed -n 's/^#SBATCH --cpus-per-task=//p' "$script")
for a in "$@"; do [ "$a" = "$script" ] && break; case $a in --cpus-per-task=*) cpus=${a#*=} ;; esac; done
if [ -n "${FAKE_CPUS:-}" ] && [ "${cpus:-1}" -gt "$FAKE_CPUS" ]; then
    echo "allocation failure: Requested node configuration is not available" >&2; exit 1 # SLURM 22.05's words
fi
echo "sbatch: Job 123 to start at 2030-01-01T00:00:00 using ${cpus:-1} processors on nodes n1 in partition p" >&2
SH
# stub squeue (a job's pending reason: FAKE_REASON, default None) and scancel (to cancels)
printf '#!/bin/sh\necho "${FAKE_REASON:-None}"\n' >"$tmp/bin/squeue"
printf '#!/bin/sh\necho "$*" >>"%s/cancels"\n' "$tmp" >"$tmp/bin/scancel"
chmod +x "$tmp/bin/sbatch" "$tmp/bin/squeue" "$tmp/bin/scancel"
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

# issue 33: a partition smaller than the #SBATCH lines (8 CPUs per task):
# the jobs would pend for ever (reason PartitionConfig); sbatch --test-only
# says so before anything is submitted, and the advice makes it fit
rm -f "$tmp/calls" "$tmp/tests"
PATH="$tmp/bin:$PATH" FAKE_CPUS=2 K=2 TIME=1:00:00 OUTDIR="$tmp/chain3" SPHSEG="$bin" \
    bash jobs/restart_chain.sh -P Geometry:dr=0.004 >"$tmp/small.log" 2>&1
check "restart_chain on a 2-CPU partition: --test-only fails -> exit 2, advice names SBATCH_FLAGS, nothing submitted" \
    "[ $? -eq 2 ] && [ -s '$tmp/tests' ] && [ ! -e '$tmp/calls' ] && grep -q 'Requested node configuration is not available' '$tmp/small.log' && grep -q 'SBATCH_FLAGS=\"--cpus-per-task=2 --mem=4G\"' '$tmp/small.log' && grep -q -- '--partition' '$tmp/small.log'" ||
    cat "$tmp/small.log"
rm -f "$tmp/calls" "$tmp/tests"
PATH="$tmp/bin:$PATH" FAKE_CPUS=2 K=2 TIME=1:00:00 OUTDIR="$tmp/chain3" SPHSEG="$bin" SBATCH_FLAGS="--cpus-per-task=2 --mem=4G" \
    bash jobs/restart_chain.sh -P Geometry:dr=0.004 >"$tmp/fits.log" 2>&1
check "restart_chain with that advice: --test-only with the first submission's arguments, then the 2 jobs" \
    "[ $? -eq 0 ] && [ -s '$tmp/tests' ] && [ \$(wc -l <'$tmp/tests') -eq 1 ] && [ \$(wc -l <'$tmp/calls') -eq 2 ] && [ \"\$(sed 's/^--test-only //' '$tmp/tests')\" = \"\$(head -1 '$tmp/calls' | sed 's/^--parsable //')\" ] && grep -q -- '--cpus-per-task=2 --mem=4G .*restart_chain.sh --step -P Geometry:dr=0.004\$' '$tmp/tests'" ||
    cat "$tmp/fits.log" "$tmp/tests" "$tmp/calls"
# a limit --test-only lets pass (SLURM 22.05: the partition's MaxTime): the
# first job pends with reason PartitionTimeLimit -> cancelled, no second job
rm -f "$tmp/calls" "$tmp/tests"
PATH="$tmp/bin:$PATH" FAKE_REASON=PartitionTimeLimit K=2 TIME=1:00:00 OUTDIR="$tmp/chain3" SPHSEG="$bin" \
    bash jobs/restart_chain.sh >"$tmp/maxtime.log" 2>&1
check "restart_chain: first job pending for ever (PartitionTimeLimit) -> cancelled, exit 2, advice, no second job" \
    "[ $? -eq 2 ] && [ \$(wc -l <'$tmp/calls') -eq 1 ] && [ \"\$(cat '$tmp/cancels')\" = 101 ] && grep -q 'reason PartitionTimeLimit' '$tmp/maxtime.log' && grep -q 'SBATCH_FLAGS=' '$tmp/maxtime.log' && grep -q 'TIME within' '$tmp/maxtime.log'" ||
    cat "$tmp/maxtime.log"

# stub scontrol: "scontrol show config" with TaskPlugin task/<dir name>
for p in none affinity cgroup; do
    mkdir -p "$tmp/task_$p"
    printf '#!/bin/sh\nprintf "TaskPlugin              = task/%s\\nTaskPluginParam         = (null type)\\n"\n' "$p" >"$tmp/task_$p/scontrol"
    chmod +x "$tmp/task_$p/scontrol"
done
launcher_is() { # expected, env assignments...: sphseg_launcher under SLURM (set -e, task/affinity) gives expected
    (set -e; export PATH="$tmp/task_affinity:$PATH" SLURM_JOB_ID=1 GPUS=0 "${@:2}"; sphseg_launcher 2; [ "${launch[*]}" = "$1" ])
}
check "sphseg_launcher under SLURM, SRUN_FLAGS empty: status 0 (set -e), --mpi=pmix" \
    "launcher_is 'srun --ntasks=2 --cpus-per-task=1 --mpi=pmix --cpu-bind=cores' SRUN_FLAGS="
check "sphseg_launcher: SRUN_MPI= leaves the site's default, SRUN_FLAGS appended" \
    "launcher_is 'srun --ntasks=2 --cpus-per-task=1 --cpu-bind=cores --exclusive -l' SRUN_MPI= 'SRUN_FLAGS=--exclusive -l'"
check "sphseg_launcher: --cpu-bind only where TaskPlugin binds (task/none: left out; task/cgroup, task/affinity: cores; CPU_BIND=: left out)" \
    "launcher_is 'srun --ntasks=2 --cpus-per-task=1 --mpi=pmix' PATH='$tmp/task_none:$PATH' &&
     launcher_is 'srun --ntasks=2 --cpus-per-task=1 --mpi=pmix --cpu-bind=cores' PATH='$tmp/task_cgroup:$PATH' &&
     launcher_is 'srun --ntasks=2 --cpus-per-task=1 --mpi=pmix --cpu-bind=cores' &&
     launcher_is 'srun --ntasks=2 --cpus-per-task=1 --mpi=pmix' CPU_BIND="
# the batch shell gets the signal (--signal=B:USR1, scancel): sphseg_run passes it on as SIGUSR1
bash -c "source jobs/common.sh; OMP_NUM_THREADS=1 sphseg_run '$bin' inputs/shearbox_2d.yml -o '$tmp/fwd' -P Run:t_end=5000 -P Output:dt=100 -P Run:progress_s=0.01" >"$tmp/fwd.log" 2>&1 &
pid=$!
for _ in $(seq 200); do grep -q '^step ' "$tmp/fwd.log" && break; sleep 0.05; done
kill -TERM $pid; wait $pid; rc=$?
check "sphseg_run: SIGTERM to the batch shell -> sphseg checkpoints, the shell exits 0" "[ $rc -eq 0 ] && grep -q 'received SIGUSR1' '$tmp/fwd.log' && [ -f '$tmp/fwd/checkpoint.h5' ]" || { echo "rc $rc"; tail -3 "$tmp/fwd.log"; }
exit $fail
