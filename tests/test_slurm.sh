#!/usr/bin/env bash
# A one-node SLURM, for real (issue 19, defect 10): `make test-slurm`.
# As root, installs Debian's slurm-wlm (slurmctld, slurmd, client) and munge
# when missing, starts munged, slurmctld and slurmd directly (no systemd)
# with a private configuration (ProctrackType=proctrack/linuxproc,
# TaskPlugin=task/none, no GPUs) under a temporary directory, and submits
# through the real sbatch:
#  1. jobs/drum_1rank.sbatch, a small drum and its analysis;
#  2. a 2-rank job through srun (jobs/common.sh's launcher, --mpi=pmix; no
#     --cpu-bind under TaskPlugin=task/none, so no srun warning);
#  3. jobs/restart_chain.sh, K = 4 jobs chained by afterok, the first two
#     ending by Run:max_wall_time (MAX_WALL) and by SIGUSR1 to the batch
#     shell (what --signal=B:USR1 sends), the rest reaching t_end; every
#     snapshot of the chain is bit-identical to an uninterrupted run's;
#  4. a job killed by its time limit (SIGTERM from slurmd: sphseg writes a
#     checkpoint), then resumed with --restart OUTDIR to t_end;
#  5. (issue 33) jobs/restart_chain.sh on a partition too small for it
#     ("small": MaxCPUsPerNode=1, MaxTime=5 min): sbatch --test-only refuses
#     2 CPUs per task, so nothing is submitted; a TIME over its MaxTime
#     passes --test-only, and the first job, pending for ever, is cancelled;
#     both exit 2 and name SBATCH_FLAGS.
# Not root, or no apt and no slurm: exit 77 (not run). The daemons are
# stopped at the end. Needs build/sphseg (or $1) built with GPU support off
# or on (the jobs run --backend cpu).
set -u
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/sphseg}")
PY=${PYTHON:-/usr/bin/python3}
[ "$(id -u)" = 0 ] || { echo "test_slurm: needs root to start slurmd and munged: not run"; exit 77; }
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null ||
    ! command -v munged >/dev/null; then
    echo "test_slurm: installing slurmctld slurmd slurm-client munge"
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends slurmctld slurmd slurm-client munge \
        >/tmp/test_slurm_apt.log 2>&1 || { echo "test_slurm: cannot install SLURM: not run"; exit 77; }
fi
work=$(mktemp -d /tmp/sphseg_slurm.XXXXXX)
chmod 755 "$work"
host=$(hostname -s)
export SLURM_CONF=$work/slurm.conf
pids=()
stop() {
    scancel --user=root >/dev/null 2>&1
    for f in "$work"/slurmctld.pid "$work"/slurmd.pid; do [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null; done
    [ -f "$work/munged.pid" ] && kill "$(cat "$work/munged.pid")" 2>/dev/null
}
trap stop EXIT
fail=0
check() { if eval "$2"; then echo "PASS $1"; else echo "FAIL $1"; fail=1; return 1; fi; }

# ---- munge and the daemons ------------------------------------------------------
mkdir -p /run/munge /etc/munge /var/lib/munge /var/log/munge
[ -s /etc/munge/munge.key ] || dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
chmod 400 /etc/munge/munge.key
munged --force --socket=/run/munge/munge.socket.2 --pid-file="$work/munged.pid" \
    --log-file="$work/munged.log" --key-file=/etc/munge/munge.key --seed-file="$work/munge.seed" ||
    { echo "test_slurm: munged does not start: not run"; exit 77; }
mem=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 1024))
mkdir -p "$work/state" "$work/spool"
cat >"$SLURM_CONF" <<EOF
ClusterName=sphsegtest
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ReturnToService=2
KillWait=30
MinJobAge=600
InactiveLimit=0
NodeName=$host CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:4
PartitionName=small Nodes=ALL Default=NO MaxTime=5 MaxCPUsPerNode=1 State=UP
EOF
slurmctld || { echo "test_slurm: slurmctld does not start: not run"; cat "$work/slurmctld.log"; exit 77; }
slurmd || { echo "test_slurm: slurmd does not start: not run"; cat "$work/slurmd.log"; exit 77; }
for _ in $(seq 60); do sinfo -h -o %t 2>/dev/null | grep -q idle && break; sleep 1; done
sinfo -h -o %t | grep -q idle || { echo "test_slurm: the node never became idle: not run"; sinfo; exit 77; }
echo "test_slurm: one-node SLURM $(sinfo --version) up on $host, $(nproc) CPUs"

jstate() { scontrol show job "$1" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }
jexit() { scontrol show job "$1" 2>/dev/null | grep -o ' ExitCode=[0-9:]*' | cut -d= -f2; }
wait_job() { # jobid, seconds
    for _ in $(seq "$2"); do
        case $(jstate "$1") in COMPLETED | FAILED | TIMEOUT | CANCELLED | NODE_FAIL | OUT_OF_MEMORY) return 0 ;; esac
        sleep 1
    done
    return 1
}
export SPHSEG=$bin OMP_NUM_THREADS=1 GPUS=0
common=(--mem=1G --cpus-per-task=1 --chdir="$PWD")

# 1. the single-rank drum, with its analysis
j=$(sbatch --parsable "${common[@]}" --time=10 -o "$work/drum.out" --export="ALL,OUTDIR=$work/drum,TIMES=0.05" \
    jobs/drum_1rank.sbatch -P Geometry:dr=0.004 -P Run:t_end=0.05 -P Output:dt=0.05 --backend cpu)
wait_job "$j" 300
check "sbatch jobs/drum_1rank.sbatch: COMPLETED, exit 0:0, analysis written" \
    "[ \"\$(jstate $j)\" = COMPLETED ] && [ \"\$(jexit $j)\" = 0:0 ] && ls '$work/drum'/drum_*.png >/dev/null 2>&1" ||
    tail -5 "$work/drum.out"

# 2. two ranks through srun (the launcher of jobs/common.sh: --mpi=pmix)
cat >"$work/two.sbatch" <<'EOF'
#!/usr/bin/env bash
set -euo pipefail
source jobs/common.sh
sphseg_threads 2
sphseg_launcher 2
echo "launch: ${launch[*]}"
sphseg_run "${launch[@]}" "$SPHSEG" inputs/shearbox_2d.yml -o "$OUTDIR" -P Run:t_end=2 -P Output:dt=1 --backend cpu
EOF
j=$(sbatch --parsable --ntasks=2 "${common[@]}" --time=10 -o "$work/two.out" --export="ALL,OUTDIR=$work/two" \
    "$work/two.sbatch")
wait_job "$j" 300
check "a 2-rank job through srun --mpi=pmix: COMPLETED, 2 ranks, done; task/none: no --cpu-bind, no srun warning" \
    "[ \"\$(jstate $j)\" = COMPLETED ] && grep -q 'srun --ntasks=2 .*--mpi=pmix' '$work/two.out' && grep -q '2 rank(s)' '$work/two.out' && grep -q '^done:' '$work/two.out' && ! grep -q 'cpu-bind\|support for cpu binding' '$work/two.out'" ||
    tail -8 "$work/two.out"

# 3. the restart chain: link 1 ends by Run:max_wall_time, link 2 by --signal
#    (SIGUSR1 to the batch shell, passed on), link 3 reaches t_end
chain=(-P Geometry:dr=0.00087 -P Run:t_end=65 -P Output:dt=13 --backend cpu)
"$bin" inputs/shearbox_2d.yml -o "$work/straight" "${chain[@]}" >"$work/straight.log" 2>&1
SCENE=inputs/shearbox_2d.yml K=4 TIME=3:00 MAX_WALL=6 OUTDIR="$work/chain" \
    SBATCH_FLAGS="${common[*]} -o $work/chain-%j.out" bash jobs/restart_chain.sh "${chain[@]}" >"$work/chain.log" 2>&1
mapfile -t jobs < <(sed -n 's/^restart_chain: job [0-9]*\/4: \([0-9]*\).*/\1/p' "$work/chain.log")
check "restart_chain.sh submitted 4 jobs" "[ \${#jobs[@]} -eq 4 ]" || cat "$work/chain.log"
if [ ${#jobs[@]} -eq 4 ]; then
    wait_job "${jobs[0]}" 300
    # link 2: SIGUSR1 to the batch shell (what --signal=B:USR1 sends) ends it, 4 s in
    for _ in $(seq 120); do [ "$(jstate "${jobs[1]}")" = RUNNING ] && break; sleep 1; done
    sleep 4
    scancel --batch --signal=USR1 "${jobs[1]}"
    wait_job "${jobs[1]}" 300
    wait_job "${jobs[2]}" 600
    wait_job "${jobs[3]}" 600
    for k in 0 1 2 3; do
        check "chain job $((k + 1)): COMPLETED, exit 0:0" "[ \"\$(jstate ${jobs[$k]})\" = COMPLETED ] && [ \"\$(jexit ${jobs[$k]})\" = 0:0 ]" ||
            tail -5 "$work/chain-${jobs[$k]}.out"
    done
    check "link 1 stopped by Run:max_wall_time" "grep -q 'next step would pass Run:max_wall_time' '$work/chain-${jobs[0]}.out'"
    check "link 2 stopped by the forwarded signal" "grep -q 'received SIGUSR1' '$work/chain-${jobs[1]}.out'"
    check "the chain reached t_end: every snapshot bit-identical to the uninterrupted run's" "'$PY' - '$work/chain' '$work/straight' <<'PYEOF'
import glob, os, sys, h5py, numpy as np
names = sorted(os.path.basename(n) for n in glob.glob(sys.argv[2] + '/snapshot_*.h5'))
assert len(names) == 6, names
for n in names:
    a, b = h5py.File(sys.argv[1] + '/' + n, 'r'), h5py.File(sys.argv[2] + '/' + n, 'r')
    assert a['Header'].attrs['Time'] == b['Header'].attrs['Time'], n
    for k in b['Particles']:
        assert np.array_equal(a['Particles'][k][()], b['Particles'][k][()]), (n, k)
PYEOF"
fi

# 4. a job killed by its time limit (1 minute; no --signal, no max_wall_time:
#    slurmd's SIGTERM reaches sphseg, which checkpoints), then resumed
cat >"$work/limit.sbatch" <<'EOF'
#!/usr/bin/env bash
set -euo pipefail
source jobs/common.sh
sphseg_launcher 1
sphseg_run "${launch[@]}" "$SPHSEG" inputs/shearbox_2d.yml -o "$OUTDIR" -P Geometry:dr=0.0005 -P Run:t_end=5000 \
    -P Output:dt=500 --backend cpu
EOF
j=$(sbatch --parsable "${common[@]}" --time=1 -o "$work/limit.out" --export="ALL,OUTDIR=$work/limit" "$work/limit.sbatch")
wait_job "$j" 240
check "a job at its time limit: TIMEOUT, and sphseg wrote a checkpoint on SIGTERM" \
    "[ \"\$(jstate $j)\" = TIMEOUT ] && grep -q 'received SIGTERM' '$work/limit.out' && [ -f '$work/limit/checkpoint.h5' ]" ||
    tail -5 "$work/limit.out"
t=$(sed -n 's/^stopping at step [0-9]*, t = \([0-9.e+-]*\) s.*/\1/p' "$work/limit.out")
cat >"$work/resume.sbatch" <<EOF
#!/usr/bin/env bash
set -euo pipefail
source jobs/common.sh
sphseg_launcher 1
sphseg_run "\${launch[@]}" "\$SPHSEG" inputs/shearbox_2d.yml -o "\$OUTDIR" --restart "\$OUTDIR" -P Geometry:dr=0.0005 \\
    -P Run:t_end=\$("$PY" -c "print(float('${t:-0}') + 1)") -P Output:dt=500 --backend cpu
EOF
j=$(sbatch --parsable "${common[@]}" --time=5 -o "$work/resume.out" --export="ALL,OUTDIR=$work/limit" "$work/resume.sbatch")
wait_job "$j" 240
check "resumed from it: COMPLETED, restart from its checkpoint, done" \
    "[ \"\$(jstate $j)\" = COMPLETED ] && grep -q '^restart from $work/limit/checkpoint.h5' '$work/resume.out' && grep -q '^done:' '$work/resume.out'" ||
    tail -5 "$work/resume.out"

# 5. the chain on a partition too small for it: refused before it could pend for ever
njobs() { squeue -h -t all -o %i | wc -l; }
n=$(njobs)
K=2 TIME=3:00 MARGIN=60 OUTDIR="$work/small" SBATCH_FLAGS="${common[*]} --cpus-per-task=2 --partition=small" \
    bash jobs/restart_chain.sh >"$work/small.log" 2>&1
check "restart_chain, 2 CPUs per task on a MaxCPUsPerNode=1 partition: --test-only refuses, exit 2, SBATCH_FLAGS named, no job" \
    "[ $? -eq 2 ] && [ \$(njobs) -eq $n ] && grep -q 'sbatch --test-only' '$work/small.log' && grep -q 'SBATCH_FLAGS=' '$work/small.log'" ||
    cat "$work/small.log"
K=2 TIME=10:00 MARGIN=60 OUTDIR="$work/small" SBATCH_FLAGS="${common[*]} --partition=small" \
    bash jobs/restart_chain.sh >"$work/maxtime.log" 2>&1
rc=$?
first=$(sed -n 's/.*job \([0-9]*\) would pend for ever.*/\1/p' "$work/maxtime.log")
check "restart_chain, TIME over the partition's MaxTime: the first job (pending for ever) cancelled, exit 2, no second job" \
    "[ $rc -eq 2 ] && [ -n '$first' ] && [ \$(njobs) -eq $((n + 1)) ] && [ \"\$(jstate ${first:-0})\" = CANCELLED ] && grep -q 'SBATCH_FLAGS=' '$work/maxtime.log'" ||
    cat "$work/maxtime.log"

echo "test_slurm: logs in $work"
exit $fail
