#!/usr/bin/env bash
# The 3D drum at the drum scenes' flow (riemann with bed damping, the corrected
# gradient, Fickian shifting; E 10 kPa, chi 0.2: issue 56's settings), one run
# per (binary, integrator, neighbour form) given: particle-steps/s (sphseg's
# "done:" line, set-up and output excluded), the per-stage profile
# (SPHSEG_GPU_PROFILE=1, with the run's "tuning:" line: the settings it saw) and
# the peak device memory (nvidia-smi every 100 ms, and the backend's "gpu memory:"
# line where the binary prints it). Run them on one
# otherwise idle GPU, one after the other (this script does): compare the rows
# of one run as ratios.
#   tools/bench/drum_rates.sh OUT STEPS LENGTH_M SPEC [SPEC ...]
#     SPEC = NAME:BINARY:INTEGRATOR:FORM   (INTEGRATOR predictor_corrector | leapfrog | - (the
#            binary's default, for one that lacks Run:integrator); FORM list | list16 | cells | -)
#   e.g. tools/bench/drum_rates.sh out/rates 100 0.1 pc:build/sphseg:predictor_corrector:list \
#        lf:build/sphseg:leapfrog:list lf16:build/sphseg:leapfrog:list16
# LENGTH_M 0.1 at dr 0.25 mm gives 1.12e7 particles; 1.35 gives 1.47e8. Writes
# OUT/rates.csv (one row a run) and OUT/profiles.txt.
set -uo pipefail
out=${1:?usage: drum_rates.sh OUT STEPS LENGTH_M SPEC...}; steps=${2:?}; len=${3:?}; shift 3
mkdir -p "$out"
F=(-P Flow:stabilization=riemann -P Flow:bed_damping=1 -P Flow:gradient_correction=on -P Flow:shifting=fickian
   -P Material:E=1e4 -P Run:cfl_flow=0.2 -P Geometry:dr=0.00025 -P Geometry:length="$len")
gpu=$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1)
csv=$out/rates.csv
echo "name,binary,integrator,form,particles,steps,wall_s,particle_steps_per_s,peak_smi_MiB,gpu" > "$csv"
: > "$out/profiles.txt"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
for spec in "$@"; do
    IFS=: read -r name bin integ form <<< "$spec"
    args=(); [ "$integ" != - ] && args+=(-P Run:integrator="$integ")
    envs=(SPHSEG_GPU_PROFILE=1); [ "$form" != - ] && envs+=(SPHSEG_GPU_NBR="$form")
    nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 100 > "$tmp/mem" 2>/dev/null &
    smi=$!
    env "${envs[@]}" "$bin" inputs/drum_3d.yml -o "$tmp/run" --overwrite --backend gpu -P Run:max_steps="$steps" \
        -P Output:snapshots=off -P Run:progress_s=1e9 -P Output:diag_dt=1e9 "${F[@]}" "${args[@]}" > "$tmp/log" 2>&1
    rc=$?
    kill $smi 2>/dev/null; wait $smi 2>/dev/null
    line=$(grep '^done:' "$tmp/log")
    n=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1 \2/p' "$tmp/log" | head -1 | awk '{print $1+$2}')
    wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
    rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
    peak=$(sort -n "$tmp/mem" | tail -1)
    [ $rc -ne 0 ] && rate="failed rc $rc"
    echo "$name,$(basename "$bin"),$integ,$form,$n,$steps,$wall,$rate,$peak,$gpu" >> "$csv"
    { echo "== $name (exit $rc)"; grep -E "^tuning|^gpu|^fields|ms/step|^done" "$tmp/log"; } >> "$out/profiles.txt"
    echo "$name: $rate particle-steps/s, peak $peak MiB"
done
