#!/usr/bin/env bash
# GPU benchmark (make bench runs it when the build has the CUDA backend and a
# GPU is visible): particle-steps per second of --backend gpu against the
# particle count, in double and single precision,
#   3d_block   the full granular step in 3D (momentum, stress with return
#              mapping, dummy walls, Shepard filter every 30 steps, and the
#              concentration with the shear-rate model and the conservative
#              scheme): a cube of the Table 1 material at rest in a box
#              (inputs/column_2d.yml with dim 3, geostatic start), 1e4 to 3e7
#              particles;
#   2d_shear   the concentration solver alone: the oscillatory shear box
#              (inputs/shearbox_2d.yml, conservative scheme), 1e4 to 3e7;
#   2d_drum    the EN drum of Table 1 at its own resolution (dr = 0.5 mm,
#              about 1e4 particles): steps per second of the small problem;
#   *_win      the drums with concentration windows (Segregation:every auto,
#              the default since 44e28c2; 3d_block, 2d_drum and 3d_drum take
#              C in every flow step, Segregation:every=1, as before, so that
#              the series compare with earlier benches and the pair gives the
#              windows' ratio in one run);
#   3d_drum    the 3D drum of 1.1e7 particles (inputs/drum_3d.yml at
#              dr = 0.25 mm, length 0.1 m; when MAX_PARTICLES >= 1.2e7),
#              200 steps (two windows of 100).
# 2d_drum, 3d_drum and their _win rows run the paper's Flow:stabilization
# monaghan without the corrected gradient and the shifting, as every bench
# before the drum scenes set riemann and then the pair (issue 30), so that
# the series stay comparable; the *_scene rows run the drum scenes' own flow
# (riemann with bed damping, the corrected gradient, Fickian shifting), which
# is what users run: each drum series shows both.
# Particle-steps count material and dummy particles; the rate excludes
# set-up, output and diagnostics (the "done:" line of sphseg). peak_GB and
# bytes_per_particle: the backend's "gpu memory:" line (the device's peak in
# use during the run, and that less what was in use before, a particle).
# Usage: tools/bench/bench_gpu.sh CSV BIN_DOUBLE [BIN_SINGLE] [MAX_PARTICLES] (an empty BIN skips its precision)
set -uo pipefail
csv=${1:?usage: bench_gpu.sh CSV BIN_DOUBLE [BIN_SINGLE] [MAX_PARTICLES]}
bind=${2:-}; bins=${3:-}; nmax=${4:-3e7}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
gpu=$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1)
echo "case,precision,particles,steps,wall_s,particle_steps_per_s,steps_per_s,gpu,peak_GB,bytes_per_particle" > "$csv"
printf "%-9s %-6s %10s %6s %8s %12s %9s   (%s)\n" case prec particles steps wall_s p-steps/s steps/s "$gpu"

one() { # case precision binary steps scene overrides...
    local case=$1 prec=$2 bin=$3 steps=$4 scene=$5; shift 5
    local args=() o
    for o in "$@"; do args+=(-P "$o"); done
    "$bin" "$scene" -o "$tmp/run" --overwrite --backend gpu -P Run:max_steps="$steps" -P Run:progress_s=1e9 \
        -P Output:snapshots=off -P Output:diag_dt=1e9 "${args[@]}" > "$tmp/log" 2>&1
    local rc=$?
    local n line wall rate
    n=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1 \2/p' "$tmp/log" | awk '{print $1+$2}')
    line=$(grep '^done:' "$tmp/log")
    if [ $rc -ne 0 ] || [ -z "$line" ]; then
        echo "$case $prec: sphseg exited with $rc: $(tail -n 1 "$tmp/log")"
        return
    fi
    wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
    rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
    local sps; sps=$(python3 -c "print('%.4g' % ($rate / $n))")
    printf "%-9s %-6s %10s %6s %8s %12s %9s\n" "$case" "$prec" "$n" "$steps" "$wall" "$rate" "$sps"
    local mem; mem=$(sed -n 's/^gpu memory: peak \([0-9.]*\) GB .*), \(-*[0-9]*\) bytes a particle over.*/\1,\2/p' "$tmp/log")
    echo "$case,$prec,$n,$steps,$wall,$rate,$sps,$gpu,${mem:-,}" >> "$csv"
}

sweep() { # precision binary
    local prec=$1 bin=$2 n dr steps
    for n in 1e4 1e5 1e6 1e7 3e7; do
        python3 -c "import sys; sys.exit(0 if $n <= $nmax else 1)" || continue
        # a cube of side 0.1 m: n = (0.1/dr)^3 material particles
        dr=$(python3 -c "print('%.4g' % (0.1 / $n ** (1/3)))")
        steps=$(python3 -c "print(max(20, min(400, int(1e9 / $n))))")
        one 3d_block "$prec" "$bin" "$steps" inputs/column_2d.yml Geometry:dim=3 Geometry:dr="$dr" \
            Geometry:width=0.1 Geometry:height=0.1 Geometry:depth=0.1 Initial:stress=geostatic \
            Segregation:enabled=on Segregation:model=shear_rate Grains:d_small=0.00025 \
            Grains:d_large=0.0005 Initial:C_below=0.5 Initial:C_above=0.5 Flow:damping_until=0 Run:t_end=1e3 \
            Segregation:every=1
    done
    for n in 1e4 1e5 1e6 1e7 3e7; do
        python3 -c "import sys; sys.exit(0 if $n <= $nmax else 1)" || continue
        # 0.037 x 0.087 m: n = 0.037 * 0.087 / dr^2 material particles
        dr=$(python3 -c "print('%.4g' % ((0.037 * 0.087 / $n) ** 0.5))")
        steps=$(python3 -c "print(max(50, min(2000, int(5e9 / $n))))")
        one 2d_shear "$prec" "$bin" "$steps" inputs/shearbox_2d.yml Geometry:dr="$dr" Run:t_end=1e6
    done
    local m="Flow:stabilization=monaghan Flow:gradient_correction=off Flow:shifting=off"
    one 2d_drum "$prec" "$bin" 3000 inputs/drum_2d_EN.yml $m Segregation:every=1
    one 2d_drum_win "$prec" "$bin" 3000 inputs/drum_2d_EN.yml $m
    one 2d_drum_scene "$prec" "$bin" 3000 inputs/drum_2d_EN.yml  # the scene's own flow (the pair, riemann)
    if python3 -c "import sys; sys.exit(0 if 1.2e7 <= $nmax else 1)"; then
        one 3d_drum "$prec" "$bin" 200 inputs/drum_3d.yml $m Geometry:dr=0.00025 Geometry:length=0.1 Segregation:every=1
        one 3d_drum_win "$prec" "$bin" 200 inputs/drum_3d.yml $m Geometry:dr=0.00025 Geometry:length=0.1
        one 3d_drum_scene "$prec" "$bin" 200 inputs/drum_3d.yml Geometry:dr=0.00025 Geometry:length=0.1
    fi
}

[ -n "$bind" ] && sweep double "$bind"
[ -n "$bins" ] && sweep single "$bins"
exit 0
