#!/usr/bin/env bash
# make bench: particle-steps per second of the concentration solver and of the
# full granular step on the
# CPU (OpenMP on all cores unless OMP_NUM_THREADS is set): shear box for a
# few particle counts and the three schemes. One step = predictor and
# corrector (two rate evaluations, two neighbour-list builds).
set -euo pipefail
bin=${1:-build/sphseg}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
threads=${OMP_NUM_THREADS:-$(nproc)}
echo "sphseg bench: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $threads thread(s)"
printf "%-13s %8s %10s %7s %9s %16s\n" scheme dr/H particles steps wall_s particle-steps/s
for res in 0.04 0.02 0.01 0.005; do
    dr=$(python3 -c "print(0.087*$res)")
    # about 200 steps: dt = h / |u|_max with h = 1.5 dr, |u|_max = 0.0243 m/s
    tend=$(python3 -c "print(200*1.5*$dr/0.0243)")
    for scheme in conservative paper direct; do
        OMP_NUM_THREADS=$threads "$bin" inputs/shearbox_2d.yml -o "$tmp/$scheme$res" --overwrite -P Geometry:dr=$dr \
            -P Segregation:scheme=$scheme -P Run:t_end=$tend -P Output:dt=$tend -P Run:progress_s=1e9 \
            > "$tmp/log" 2>&1 || true
        n=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1 \2/p' "$tmp/log" | awk '{print $1+$2}')
        line=$(grep '^done:' "$tmp/log" || echo "done: 0 steps, 0 s wall, 0 particle-steps/s")
        steps=$(echo "$line" | sed 's/done: \([0-9]*\) steps.*/\1/')
        wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
        rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
        printf "%-13s %8s %10s %7s %9s %16s\n" "$scheme" "$res" "$n" "$steps" "$wall" "$rate"
    done
done

# The full granular step (momentum, stress with return mapping, dummy walls,
# Shepard filter every 30 steps, and the concentration with the shear-rate
# model): a column block of the Table 1 material at rest (geostatic start,
# E = 1 MPa), 2D and 3D, about 100 steps (dt = 0.1 h / c_s). Particle-steps
# count material and dummy particles. C in every flow step
# (Segregation:every=1, as the benches before 44e28c2), and once with
# concentration windows ("win": every=auto, one window of the 100 steps).
echo
printf "%-13s %8s %10s %7s %9s %16s\n" granular dr_mm particles steps wall_s particle-steps/s
# Each block runs twice: with the paper's flow (monaghan, the key defaults)
# and with the drum scenes' flow ("pair": riemann with bed damping, the
# corrected gradient and Fickian shifting), which is what users of the drums run.
SCENE_FLOW="-P Flow:stabilization=riemann -P Flow:bed_damping=1 -P Flow:gradient_correction=on -P Flow:shifting=fickian"
gran() { # dim dr width height depth [every [flow]]
    local dim=$1 dr=$2 W=$3 H=$4 D=$5 every=${6:-1} flow=${7:-paper} extra=""
    [ "$flow" = pair ] && extra=$SCENE_FLOW
    local tend; tend=$(python3 -c "print(100*0.1*1.5*$dr/29.96)")
    OMP_NUM_THREADS=$threads "$bin" inputs/column_2d.yml -o "$tmp/g$dim$dr" --overwrite -P Geometry:dim=$dim -P Geometry:dr=$dr \
        -P Geometry:width=$W -P Geometry:height=$H -P Geometry:depth=$D -P Initial:stress=geostatic \
        -P Segregation:enabled=on -P Segregation:model=shear_rate -P Grains:d_small=0.00025 \
        -P Grains:d_large=0.0005 -P Initial:C_below=0.5 -P Initial:C_above=0.5 -P Flow:damping_until=0 \
        -P Run:t_end=$tend -P Output:dt=$tend -P Run:progress_s=1e9 -P Segregation:every=$every $extra > "$tmp/log" 2>&1 || true
    local n line steps wall rate
    n=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1 \2/p' "$tmp/log" | awk '{print $1+$2}')
    line=$(grep '^done:' "$tmp/log" || echo "done: 0 steps, 0 s wall, 0 particle-steps/s")
    steps=$(echo "$line" | sed 's/done: \([0-9]*\) steps.*/\1/')
    wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
    rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
    printf "%-13s %8s %10s %7s %9s %16s\n" "${dim}D $([ "$flow" = pair ] && echo pair || echo block)$([ "$every" = 1 ] || echo " win")" "$(python3 -c "print($dr*1e3)")" "$n" "$steps" "$wall" "$rate"
}
for flow in paper pair; do
    gran 2 0.002 0.05 0.1 0.05 1 $flow      # ~1.6e3 particles
    gran 2 0.0005 0.05 0.1 0.05 1 $flow     # ~2.1e4
    gran 2 0.00015 0.05 0.1 0.05 1 $flow    # ~2.3e5
    gran 3 0.002 0.03 0.04 0.03 1 $flow     # ~5e3
    gran 3 0.001 0.04 0.05 0.04 1 $flow     # ~1e5
    gran 3 0.001 0.04 0.05 0.04 auto $flow  # the same with concentration windows
done
