#!/usr/bin/env bash
# Many small runs on one GPU: the aggregate rate of N copies of one small scene
# run side by side, plainly (the driver time-slices the processes: their
# kernels never overlap) and under CUDA MPS (one server: the kernels of every
# process share the SMs). A 10^4-particle 2D drum leaves most of a large GPU
# idle, so ensembles and parameter sweeps (the studies' --jobs, a SLURM
# array packed onto one GPU) gain only with MPS.
#   tools/bench/gpu_share.sh OUT SPHSEG [N ...]      (default N: 1 4 8 16)
#   SCENE=inputs/drum_2d_EN.yml STEPS=40000 tools/bench/gpu_share.sh out/share build/sphseg 1 4 8
# Writes OUT/share.csv: mode (alone, sliced, mps), N, wall s, aggregate
# steps/s. Each N is timed from launch to the last exit (set-up included). MPS
# needs nvidia-cuda-mps-control on the PATH; the daemon (tools/bench/with_mps.sh)
# runs in OUT/mps and stops at the end. Run on an otherwise idle GPU.
set -uo pipefail
out=${1:?usage: gpu_share.sh OUT SPHSEG [N ...]}; bin=${2:?}; shift 2
ns=("$@"); [ ${#ns[@]} -gt 0 ] || ns=(1 4 8 16)
scene=${SCENE:-inputs/drum_2d_EN.yml}; steps=${STEPS:-40000}
mkdir -p "$out"; out=$(cd "$out" && pwd)
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
csv=$out/share.csv
echo "mode,N,wall_s,aggregate_steps_per_s,scene,steps,gpu" > "$csv"
gpu=$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1)

batch() { # mode N
    local mode=$1 n=$2 t0 t1 k fail=0
    t0=$(date +%s%N)
    for k in $(seq 1 "$n"); do
        "$bin" "$scene" --backend gpu -o "$out/run_${mode}${n}_$k" --overwrite -P Run:max_steps="$steps" \
            -P Output:snapshots=off -P Output:diag_dt=1e9 > "$out/run_${mode}${n}_$k.log" 2>&1 &
    done
    for k in $(seq 1 "$n"); do wait -n || fail=1; done
    t1=$(date +%s%N)
    [ $fail = 0 ] || { echo "gpu_share: a run of $mode N=$n failed (see $out/run_${mode}${n}_*.log)" >&2; status=1; return 1; }
    awk -v m="$mode" -v n="$n" -v t0="$t0" -v t1="$t1" -v s="$steps" -v sc="$scene" -v g="$gpu" \
        'BEGIN { w = (t1 - t0) / 1e9; printf "%s,%d,%.2f,%.0f,%s,%d,%s\n", m, n, w, n * s / w, sc, s, g }' | tee -a "$csv"
}

status=0
batch alone 1
for n in "${ns[@]}"; do [ "$n" -gt 1 ] && batch sliced "$n"; done
. "$(dirname "$0")/with_mps.sh"
if mps_start "$out/mps"; then
    trap mps_stop EXIT
    for n in "${ns[@]}"; do batch mps "$n"; done
else
    echo "gpu_share: no mps rows" >&2
fi
echo "wrote $csv"
exit $status
