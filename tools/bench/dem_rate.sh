#!/usr/bin/env bash
# The rate of the coupled DEM-SPH step at scale (issue 58, "Rate"): a 3D box of
# water (dr 1.33 mm, h 2 mm, periodic along x and z over 12.5 cm, 20 cm deep on a
# base: 1.3e6 fluid particles) holding a lattice of 47 x 47 x 47 = 103 823 free
# grains (d 2 mm, spacing 2.67 mm, eps 0.779; the scene inputs/dem_block_settling.yml
# scaled by a half in d and a quarter in dr, two-way coupled), against the same
# fluid with no grains (DEM:d 0). One run each on one otherwise idle GPU, one
# after the other: particle-steps/s of the fluid (sphseg's "done:" line, set-up
# and output excluded), the wall time a fluid step, the DEM steps a fluid step
# and the per-stage profile (SPHSEG_GPU_PROFILE=1).
#   tools/bench/dem_rate.sh OUT STEPS BINARY [BACKEND]      (BACKEND gpu, default, or cpu)
# Writes OUT/dem_rate.csv (one row a run) and OUT/logs.txt.
set -uo pipefail
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-16}
out=${1:?usage: dem_rate.sh OUT STEPS BINARY [BACKEND]}; steps=${2:?}; bin=${3:?}; backend=${4:-gpu}
mkdir -p "$out"
L=0.12549 # 47 spacings of 2.67 mm
S=(-P Geometry:dr=0.00133 -P Geometry:width=$L -P Geometry:depth=$L
   -P "Container:walls=[{name: base, from: [0, 0], to: [$L, 0]}]" -P "Container:regions=[{shape: fill, level: 0.2, C: 0}]"
   -P DEM:d=0.002 -P DEM:motion=free -P "DEM:block_n=[47, 47, 47]" -P DEM:block_spacing=0.00267
   -P "DEM:block_origin=[0.001335, 0.03, 0.001335]" -P Run:max_steps="$steps" -P Output:snapshots=off
   -P Run:progress_s=1e9 -P Output:diag_dt=1e9)
csv=$out/dem_rate.csv
echo "name,backend,fluid_particles,grains,steps,wall_s,particle_steps_per_s,ms_per_step" > "$csv"
: > "$out/logs.txt"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
for spec in grains:0.002 fluid:0; do
    IFS=: read -r name d <<< "$spec"
    SPHSEG_GPU_PROFILE=1 "$bin" inputs/dem_block_settling.yml -o "$tmp/run" --overwrite --backend "$backend" \
        "${S[@]}" -P DEM:d="$d" > "$tmp/log" 2>&1
    rc=$?
    { echo "=== $name (DEM:d $d): rc $rc"; cat "$tmp/log"; } >> "$out/logs.txt"
    line=$(grep '^done:' "$tmp/log")
    nf=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1/p' "$tmp/log" | head -1)
    ng=$([ "$d" = 0 ] && echo 0 || echo $((47 * 47 * 47)))
    wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
    rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
    ms=$(awk -v w="$wall" -v s="$steps" 'BEGIN { if (s > 0 && w != "") printf "%.3f", 1000 * w / s }')
    echo "$name,$backend,$nf,$ng,$steps,$wall,$rate,$ms" >> "$csv"
    echo "$name: rc $rc, $line" | cut -c1-200
done
cat "$csv"
