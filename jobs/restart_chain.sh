#!/usr/bin/env bash
# ---- edit these for your cluster -------------------------------------------
# The #SBATCH lines apply to every job of the chain (each job runs this same
# script with --step). The submission passes --time=TIME and, with GPUS=1
# (the default), --gpus-per-task=1 (GPUS=0 for a CPU partition, with
# SRUN: no GPU flags either); TIME sets Run:max_wall_time; SBATCH_FLAGS
# (e.g. "--cpus-per-task=2 --mem=4G --partition=NAME") overrides the lines
# below.
#SBATCH --job-name=sphseg_chain
#SBATCH --nodes=1
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=8
#SBATCH --mem=16G
#SBATCH --time=24:00:00
#SBATCH --output=%x-%j.out
#SBATCH --signal=B:USR1@120
##SBATCH --partition=CHANGE_ME
##SBATCH --account=CHANGE_ME
# -----------------------------------------------------------------------------
#
# restart_chain.sh — a long run as K jobs in a row. Each job runs
#   sphseg SCENE -o OUTDIR [--restart OUTDIR] -P Run:max_wall_time=W ARGS...
# with --restart only if OUTDIR holds a checkpoint (sphseg takes the newest
# valid one, checkpoint.h5 or checkpoint_prev.h5; else a fresh start), and
# W = the job's time limit minus MARGIN seconds, so that sphseg writes its
# checkpoint and exits 0 before SLURM kills the job; SIGUSR1 120 s before
# the limit (--signal) or a SIGTERM (scancel, preemption) also make it
# checkpoint and exit 0. Job k+1 starts only if job k succeeded (sbatch
# --dependency=afterok:<job k>). TIME - MARGIN > 0, and (sbatch
# --test-only) that the cluster could ever start such a job, are checked
# before any job is submitted (exit 2, saying what to set), rather than
# leave the chain pending for ever (reason PartitionConfig); the script may
# be started from any directory.
#
#   bash jobs/restart_chain.sh [SPHSEG_ARGS...]     (login node: submits K jobs)
#   bash jobs/restart_chain.sh [SPHSEG_ARGS...]     (no sbatch: K steps in a loop here)
#
# Jobs left once the run has reached Run:t_end restart from the final
# checkpoint and end at once; scancel them or choose K with some margin.
#
# ---- the chain: edit here or set in the environment -------------------------
SCENE=${SCENE:-inputs/drum_2d_EV.yml}
K=${K:-4}                   # jobs (or local steps) in the chain
TIME=${TIME:-24:00:00}      # each job's time limit ([D-]HH:MM:SS, = --time above)
MARGIN=${MARGIN:-600}       # seconds kept free for the checkpoint and exit
OUTDIR=${OUTDIR:-}          # default out/<scene>_chain_<date-time>; the same for all jobs
# NP (ranks; default 1; SLURM: the job's tasks), MAX_WALL (seconds; overrides
# TIME - MARGIN), SBATCH_FLAGS (extra sbatch flags), SUBMIT_CHECK=0 (skip
# both checks below), DRYRUN=1 (print the commands instead of
# running or submitting), SPHSEG, MPIRUN, SRUN_FLAGS, CPU_BIND,
# OMP_NUM_THREADS as in jobs/README.md.
# -----------------------------------------------------------------------------
set -euo pipefail
self=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/$(basename "${BASH_SOURCE[0]}") # before any cd

if [ -n "${SLURM_JOB_ID:-}" ]; then
    root=${SLURM_SUBMIT_DIR:-$PWD} # sbatch runs a copy of this script
    [ -f "$root/jobs/common.sh" ] || root=$root/..
else
    root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
fi
cd "$root"
source jobs/common.sh
SPHSEG=${SPHSEG:-build/sphseg}
OUTDIR=${OUTDIR:-out/$(basename "$SCENE" .yml)_chain_$(date +%Y%m%d-%H%M%S)}

# [D-]HH:MM:SS, HH:MM:SS, MM:SS or MM -> seconds
to_seconds() {
    local t=$1 d=0 h=0 m=0 s=0
    [[ $t == *-* ]] && d=${t%%-*} && t=${t#*-}
    IFS=: read -r -a f <<<"$t"
    case ${#f[@]} in
    3) h=${f[0]} m=${f[1]} s=${f[2]} ;;
    2) m=${f[0]} s=${f[1]} ;;
    1) m=${f[0]} ;;
    esac
    echo $((10#$d * 86400 + 10#$h * 3600 + 10#$m * 60 + 10#$s))
}

wall=${MAX_WALL:-$(($(to_seconds "$TIME") - MARGIN))}
if [ "$wall" -le 0 ]; then
    echo "restart_chain: TIME $TIME leaves no time after MARGIN $MARGIN s: nothing submitted" >&2
    exit 2
fi

# One link of the chain: fresh start or restart, stopping W seconds in.
chain_step() { # sphseg args...
    local np=${SLURM_NTASKS:-${NP:-1}}
    local restart=()
    if [ -f "$OUTDIR/checkpoint.h5" ] || [ -f "$OUTDIR/checkpoint_prev.h5" ]; then restart=(--restart "$OUTDIR"); fi
    sphseg_threads "$np"
    sphseg_launcher "$np"
    echo "restart_chain: ${restart[*]:-fresh start}, Run:max_wall_time=$wall s, $np rank(s) -> $OUTDIR"
    local cmd=("${launch[@]}" "$SPHSEG" "$SCENE" -o "$OUTDIR" ${restart[@]+"${restart[@]}"} -P "Run:max_wall_time=$wall" "$@")
    if [ "${DRYRUN:-0}" = 1 ]; then echo "+ ${cmd[*]}"; else sphseg_run "${cmd[@]}"; fi
}

# Could SLURM ever start a job of the chain? Before submitting: sbatch
# --test-only with the first job's arguments (more CPUs, memory or GPUs than
# a node of the partition has: the jobs would pend for ever, reason
# PartitionConfig). --test-only lets pass the partition's MaxTime and
# MaxMemPerNode (SLURM 22.05), so the first job's pending reason is read
# once it is submitted, and that job cancelled if it can never start. Both
# print SLURM's answer, what a job asks for and what to set, and exit 2.
chain_check() { # sbatch arguments of the first job (options, script, its arguments)...
    [ "${SUBMIT_CHECK:-1}" = 0 ] && return 0
    if [ "${DRYRUN:-0}" = 1 ]; then echo "+ sbatch --test-only $*"; fi
    local out
    out=$(sbatch --test-only "$@" 2>&1) && return 0
    chain_advice "a job of the chain could never start (sbatch --test-only); nothing submitted" "$out" "$@"
}
chain_check_pending() { # jobid, sbatch arguments of that job...
    [ "${SUBMIT_CHECK:-1}" = 0 ] && return 0
    local reason
    reason=$(squeue -h -j "$1" -o %r 2>/dev/null) || return 0
    case $reason in PartitionConfig | PartitionTimeLimit | PartitionNodeLimit | MaxMemPerLimit) ;; *) return 0 ;; esac
    scancel "$1" || true
    chain_advice "job $1 would pend for ever (reason $reason): cancelled, nothing else submitted" "" "${@:2}"
}
chain_advice() { # what happened, SLURM's answer, sbatch arguments...
    local a asked=()
    for a in "${@:3}"; do # the command line's options, less the bookkeeping
        [ "$a" = "$self" ] && break
        case $a in --parsable | --export=* | --chdir=* | --output=* | --error=*) ;; *) asked+=("$a") ;; esac
    done
    {
        echo "restart_chain: $1:"
        if [ -n "$2" ]; then sed 's/^/    /' <<<"$2"; fi
        echo "  each job asks for $(sed -n 's/^#SBATCH \(--\(nodes\|ntasks\|cpus-per-task\|mem[a-z-]*\|gpus[a-z-]*\|gres\|partition\|account\)=[^ ]*\).*/\1/p' "$self" | tr '\n' ' ')(#SBATCH lines of $self), then ${asked[*]}"
        echo "  ask for what your partition has (sinfo -o '%P %c %m %l %G': CPUs and memory in MB per node, time limit, GPUs), e.g."
        echo "    SBATCH_FLAGS=\"--cpus-per-task=2 --mem=4G\" (add --partition=NAME, --account=NAME as needed), GPUS=0 on a CPU partition, TIME within the partition's limit"
    } >&2
    exit 2
}

sphseg_check_binary
if [ "${1:-}" = --step ]; then # a job of the chain
    shift
    chain_step "$@"
elif command -v sbatch >/dev/null && [ -z "${NO_SLURM:-}" ]; then # submit the chain
    OUTDIR=$(mkdir -p "$(dirname "$OUTDIR")" && cd "$(dirname "$OUTDIR")" && pwd)/$(basename "$OUTDIR")
    read -r -a flags <<<"${SBATCH_FLAGS:-}"
    if [ "${GPUS:-1}" = 1 ]; then flags+=(--gpus-per-task=1); fi
    opts=(--time="$TIME" --chdir="$root"
        --export="ALL,SCENE=$SCENE,OUTDIR=$OUTDIR,TIME=$TIME,MARGIN=$MARGIN,GPUS=${GPUS:-1}")
    chain_check "${opts[@]}" ${flags[@]+"${flags[@]}"} "$self" --step "$@"
    dep=()
    for k in $(seq 1 "$K"); do
        cmd=(sbatch --parsable "${opts[@]}" ${dep[@]+"${dep[@]}"} ${flags[@]+"${flags[@]}"} "$self" --step "$@")
        if [ "${DRYRUN:-0}" = 1 ]; then echo "+ ${cmd[*]}"; jid=DRYRUN$k; else jid=$("${cmd[@]}"); jid=${jid%%;*}; fi
        if [ "$k" = 1 ] && [ "${DRYRUN:-0}" != 1 ]; then chain_check_pending "$jid" "${cmd[@]:1}"; fi
        echo "restart_chain: job $k/$K: $jid${dep[*]:+ (${dep[*]})}"
        dep=(--dependency="afterok:$jid")
    done
else # no SLURM: the same steps in a loop here
    for k in $(seq 1 "$K"); do
        echo "restart_chain: step $k/$K"
        chain_step "$@"
    done
fi
