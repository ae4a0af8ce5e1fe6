#!/usr/bin/env bash
# make bench: particle-steps per second of the concentration solver on the
# CPU (OpenMP on all cores unless OMP_NUM_THREADS is set), shear box, for a
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
        OMP_NUM_THREADS=$threads "$bin" inputs/shearbox_2d.yml -o "$tmp/$scheme$res" -P Geometry:dr=$dr \
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
