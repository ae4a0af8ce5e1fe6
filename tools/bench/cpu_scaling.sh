#!/usr/bin/env bash
# tools/bench/cpu_scaling.sh — OpenMP scaling of the CPU backend on the 3D granular
# block of tools/bench/bench.sh (column of the Table 1 material at rest, geostatic
# start, segregation with the shear-rate model in every step): one rank, no
# MPI launcher, the same run on each thread count. Prints a CSV:
#   threads,particles,steps,wall_s,particle_steps_per_s,speedup,efficiency
# speed-up and efficiency against the first thread count of the list.
# Usage: tools/bench/cpu_scaling.sh [binary] (the CPU backend also of a GPU build); environment:
#   THREADS  thread counts (default "1 2 4 8 16")
#   DR       particle spacing in m (default 0.001: about 1.1e5 particles)
#   STEPS    steps per run (default 100; dt = 0.1 h / c_s, as bench.sh)
#   REPEAT   runs per thread count, the best kept (default 1)
#   BIND     1 (default) to set OMP_PROC_BIND=close OMP_PLACES=cores unless set
set -euo pipefail
bin=${1:-build/sphseg}
threads=${THREADS:-"1 2 4 8 16"}
dr=${DR:-0.001}
steps=${STEPS:-100}
repeat=${REPEAT:-1}
if [ "${BIND:-1}" = 1 ]; then
    export OMP_PROC_BIND=${OMP_PROC_BIND:-close} OMP_PLACES=${OMP_PLACES:-cores}
fi
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
tend=$(python3 -c "print($steps*0.1*1.5*$dr/29.96)")
echo "# sphseg cpu_scaling: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) cores visible, 3D block dr=$dr m, $steps steps, best of $repeat" >&2
echo "threads,particles,steps,wall_s,particle_steps_per_s,speedup,efficiency"
base=""
for t in $threads; do
    best=0 n=0 nsteps=0 wall=0
    for ((r = 0; r < repeat; ++r)); do
        OMP_NUM_THREADS=$t "$bin" inputs/column_2d.yml -o "$tmp/out" --overwrite --backend cpu -P Geometry:dim=3 -P Geometry:dr=$dr \
            -P Geometry:width=0.04 -P Geometry:height=0.05 -P Geometry:depth=0.04 -P Initial:stress=geostatic \
            -P Segregation:enabled=on -P Segregation:model=shear_rate -P Grains:d_small=0.00025 \
            -P Grains:d_large=0.0005 -P Initial:C_below=0.5 -P Initial:C_above=0.5 -P Flow:damping_until=0 \
            -P Run:t_end=$tend -P Output:dt=$tend -P Run:progress_s=1e9 -P Segregation:every=1 \
            > "$tmp/log" 2>&1 || { echo "run on $t thread(s) failed:" >&2; tail -5 "$tmp/log" >&2; exit 1; }
        line=$(grep '^done:' "$tmp/log")
        rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
        if python3 -c "import sys; sys.exit(0 if $rate > $best else 1)"; then
            best=$rate
            n=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1 \2/p' "$tmp/log" | awk '{print $1+$2}')
            nsteps=$(echo "$line" | sed 's/done: \([0-9]*\) steps.*/\1/')
            wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
        fi
    done
    [ -n "$base" ] || base="$t $best"
    python3 -c "
bt, br = '$base'.split(); bt, br = int(bt), float(br); t, r = $t, float('$best')
s = r / br
print(f'$t,$n,$nsteps,$wall,{r:.4e},{s:.3f},{s * bt / t:.3f}')"
done
