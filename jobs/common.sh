# jobs/common.sh — shared by the GPU, multi-rank, scaling and restart job
# scripts (sourced from the repository root, not run): OpenMP threads, the
# launcher (srun under SLURM, "mpirun --oversubscribe -np NP" without it),
# and the parser of a run's "done:" line.

# OMP_NUM_THREADS: --cpus-per-task under SLURM; otherwise as set, or 1 per
# rank when several ranks share this machine (nproc for one rank).
sphseg_omp_user=${OMP_NUM_THREADS:-} # as the user set it, before any sweep
sphseg_threads() { # ranks on this machine
    if [ -n "${SLURM_CPUS_PER_TASK:-}" ]; then
        export OMP_NUM_THREADS=$SLURM_CPUS_PER_TASK
    elif [ -n "$sphseg_omp_user" ]; then
        export OMP_NUM_THREADS=$sphseg_omp_user
    else
        local n=$(($(nproc) / ${1:-1}))
        export OMP_NUM_THREADS=$((n > 0 ? n : 1))
    fi
}

# Whether srun binds tasks to CPUs on this cluster: the TaskPlugin of
# "scontrol show config" names task/affinity or task/cgroup. Where it names
# neither (task/none) srun warns about --cpu-bind and binds nothing. No
# answer from scontrol counts as yes. Asked once per shell.
sphseg_cpu_binding() {
    if [ -z "${sphseg_task_plugin+set}" ]; then
        sphseg_task_plugin=$(scontrol show config 2>/dev/null | sed -n 's/^TaskPlugin *= *//p') || true
    fi
    [ -z "$sphseg_task_plugin" ] || [[ $sphseg_task_plugin == *affinity* || $sphseg_task_plugin == *cgroup* ]]
}

# launch=(...): the command prefix that starts NRANKS ranks, one GPU each.
# Under SLURM: srun --mpi=$SRUN_MPI (default pmix: Debian's and most Open
# MPI builds need it under srun; SRUN_MPI= leaves the site's MpiDefault)
# with one GPU per task (GPUS=0: none), GPU binding and --cpu-bind=$CPU_BIND
# (default cores; only where the cluster binds, see sphseg_cpu_binding;
# CPU_BIND= leaves it out everywhere); SRUN_FLAGS adds to it. Without:
# $MPIRUN (default "mpirun --oversubscribe --bind-to none", plus
# --allow-run-as-root for root) -np NRANKS. --bind-to none: Open
# MPI binds each of one or two ranks to a single core by default, which puts
# all of a rank's OpenMP threads on that core (measured: a 16-thread rank ran
# at one core's speed on the 16-core GPU machine).
sphseg_launcher() { # nranks
    local np=$1
    if [ -n "${SLURM_JOB_ID:-}" ]; then
        launch=(srun --ntasks="$np" --cpus-per-task="${SLURM_CPUS_PER_TASK:-1}")
        local mpi=${SRUN_MPI-pmix}
        if [ -n "$mpi" ]; then launch+=(--mpi="$mpi"); fi
        if [ "${GPUS:-1}" = 1 ]; then
            launch+=(--gpus-per-task=1 --gpu-bind="${GPU_BIND:-closest}")
        fi
        local bind=${CPU_BIND-cores}
        if [ -n "$bind" ] && sphseg_cpu_binding; then launch+=(--cpu-bind="$bind"); fi
        if [ -n "${SRUN_FLAGS:-}" ]; then
            read -r -a extra <<<"$SRUN_FLAGS"
            launch+=("${extra[@]}")
        fi
    else
        local mpirun=${MPIRUN:-mpirun --oversubscribe --bind-to none}
        [ "$(id -u)" = 0 ] && [ -z "${MPIRUN:-}" ] && mpirun="$mpirun --allow-run-as-root"
        read -r -a launch <<<"$mpirun"
        launch+=(-np "$np")
    fi
}

# Run a command (the launcher and sphseg) in the background and pass the
# stop signals the batch shell receives on to it as SIGUSR1: sphseg then
# finishes its step, writes a checkpoint and exits 0. SIGUSR1 because
# "#SBATCH --signal=B:USR1@120" sends it to this shell alone, srun and
# mpirun both forward it to every rank, and mpirun ends a job it is sent
# SIGTERM for with status 1. Returns the command's exit status.
sphseg_run() { # command...
    "$@" &
    local pid=$! rc=0 again
    trap 'kill -USR1 '"$pid"' 2>/dev/null' USR1 TERM INT
    while kill -0 "$pid" 2>/dev/null; do
        wait "$pid" && rc=0 || rc=$?
    done
    wait "$pid" 2>/dev/null && again=0 || again=$?
    [ "$again" -ne 127 ] && rc=$again
    trap - USR1 TERM INT
    return "$rc"
}

sphseg_check_binary() {
    if [ ! -x "$SPHSEG" ]; then
        echo "$(basename "$0"): $PWD/$SPHSEG not found; run make in $PWD first" >&2
        exit 1
    fi
}

# Fields of a run's log, one line "particles,steps,wall_s,rate,halo_s,io_s":
# particles from the start line ("N material + M dummy particles"), the rest
# from the final "done:" line; halo_s is empty when the line has no
# "s in halo exchange" part. Exit 1 if the log has no done: line.
sphseg_parse_log() { # logfile
    "${PYTHON:-/usr/bin/python3}" - "$1" <<'EOF'
import re, sys
text = open(sys.argv[1], errors="replace").read()
num = r"([-+0-9.eE]+|nan|inf)"
done = re.findall(r"^done: (\d+) steps, " + num + r" s wall, " + num + r" particle-steps/s(.*)$", text, re.M)
if not done:
    sys.exit(1)
steps, wall, rate, rest = done[-1]
io = re.search(num + r" s of the wall in output", rest)
halo = re.search(num + r" s in halo exchange", rest)
m = re.search(r"(\d+) material \+ (\d+) dummy particles", text)
parts = str(int(m.group(1)) + int(m.group(2))) if m else ""
print(",".join([parts, steps, wall, rate, halo.group(1) if halo else "", io.group(1) if io else ""]))
EOF
}

# The rank counts of a sweep: $RANKS if set, else 1 2 4 ... up to the
# allocation ($SLURM_NTASKS, or NP without SLURM), the allocation included.
sphseg_rank_list() {
    if [ -n "${RANKS:-}" ]; then echo "$RANKS"; return; fi
    local max=${SLURM_NTASKS:-${NP:-1}} p=1 out=""
    while [ "$p" -lt "$max" ]; do out="$out $p"; p=$((p * 2)); done
    echo "$out $max"
}

SCALING_COLUMNS=mode,ranks,particles,steps,wall_s,particle_steps_per_s,halo_s,io_s,scene,dr,scaled_key,scaled_value,max_steps,job,settings

# The keys of a named set of settings (SETTINGS of the sweeps): "scene", the
# scene's own (Table 1's in the drums, with their Flow:stabilization riemann,
# corrected gradient and shifting); "fast", "converged" and "paper", the
# presets of that name (Run:preset, docs/guide.md "Presets": fast and converged
# are the drum scenes' flow at E 30 kPa and 0.1 MPa, chi 0.2, within 2.4 % and
# 0.9 % of the converged drum at dr 0.5 mm; fast with Run:integrator
# leapfrog, one flow evaluation a step); "monaghan_soft", the paper's
# monaghan at E 10 kPa, alpha 3.162, chi 0.2, the sweeps' "fast" until
# issue 56 (it does not converge in dr: kept to compare with older sweeps).
sphseg_settings_args() {
    case $1 in
    scene) ;;
    fast|converged|paper) echo "-P Run:preset=$1" ;;
    monaghan_soft) echo "-P Flow:stabilization=monaghan -P Flow:gradient_correction=off -P Flow:shifting=off -P Material:E=1e4 -P Flow:alpha_av=3.162 -P Run:cfl_flow=0.2" ;;
    *) echo "unknown SETTINGS entry '$1' (scene | fast | converged | paper | monaghan_soft)" >&2; return 1 ;;
    esac
}

# One sweep: for each P of sphseg_rank_list, run SCENE on P ranks with
# Output:snapshots=off and Run:max_steps=$MAX_STEPS (weak: SCALE_KEY set to
# SCALE_BASE * P^SCALE_POWER), parse its done: line and append a row to $CSV.
# Extra arguments go to sphseg. Returns 1 if any run failed (the rest still run).
sphseg_scaling_sweep() { # mode (weak|strong), sphseg args...
    local mode=$1; shift
    local failed=0 P value key set
    mkdir -p "$(dirname "$CSV")" "$OUTROOT"
    [ -s "$CSV" ] || echo "$SCALING_COLUMNS" >"$CSV"
    for set in ${SETTINGS:-scene fast}; do
    local extra
    extra=$(sphseg_settings_args "$set") || return 1
    for P in $(sphseg_rank_list); do
        # shellcheck disable=SC2206 # the settings' keys: words without spaces
        local args=(--overwrite -P Output:snapshots=off -P "Run:max_steps=$MAX_STEPS" $extra)
        key="" value=""
        if [ "$mode" = weak ]; then
            key=$SCALE_KEY
            value=$("${PYTHON:-/usr/bin/python3}" -c "import sys; print(repr(float(sys.argv[1]) * int(sys.argv[2]) ** float(sys.argv[3])))" "$SCALE_BASE" "$P" "$SCALE_POWER")
            args+=(-P "$key=$value")
        fi
        local out=$OUTROOT/${mode}_${set}_P$P
        sphseg_threads "$P"
        sphseg_launcher "$P"
        echo "$mode scaling ($set settings): $P rank(s), $OMP_NUM_THREADS thread(s)/rank${key:+, $key=$value} -> $out"
        local rc=0
        sphseg_run "${launch[@]}" "$SPHSEG" "$SCENE" -o "$out" "$@" "${args[@]}" >"$out.log" 2>&1 || rc=$?
        if [ $rc -ne 0 ]; then
            echo "  run failed (exit status $rc): $out.log" >&2; grep -m1 'error' "$out.log" >&2; failed=1; continue
        fi
        local f dr
        if ! f=$(sphseg_parse_log "$out.log"); then
            echo "  no done: line in $out.log" >&2; failed=1; continue
        fi
        IFS=, read -r parts steps wall rate halo io <<<"$f"
        dr=$("${PYTHON:-/usr/bin/python3}" -c "import sys, yaml; print(yaml.safe_load(open(sys.argv[1]))['Geometry']['dr'])" "$out/used_params.yml" 2>/dev/null || true)
        echo "$mode,$P,$parts,$steps,$wall,$rate,$halo,$io,$SCENE,$dr,$key,$value,$MAX_STEPS,${SLURM_JOB_ID:-local},$set" >>"$CSV"
        echo "  $parts particles, $steps steps, $wall s, $rate particle-steps/s${halo:+, halo $halo s}"
    done
    done
    return $failed
}
