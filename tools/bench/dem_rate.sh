#!/usr/bin/env bash
# The rate of the coupled DEM-SPH step at scale (issue 58, "Rate"): a 3D box of
# water (dr 1.33 mm, h 2 mm, periodic along x and z over 12.5 cm, 20 cm deep on a
# base: 1.3e6 fluid particles) holding a lattice of 47 x 47 x 47 = 103 823 free
# grains (d 2 mm, spacing 2.67 mm, eps 0.779; the scene inputs/dem_block_settling.yml
# scaled by a half in d and a quarter in dr, two-way coupled), against the same
# fluid with no grains (DEM:d 0). One run each on one otherwise idle GPU, one
# after the other: particle-steps/s of the fluid (sphseg's "done:" line, set-up
# and output excluded), the wall time a fluid step (output excluded), the DEM steps a fluid step
# and the per-stage profile (SPHSEG_GPU_PROFILE=1).
#   tools/bench/dem_rate.sh OUT STEPS BINARY [BACKEND]      (BACKEND gpu, default, or cpu)
#   NAME=label (default grains) and EXTRA='-P DEM:coupling=one_way ...' change the grains' run;
#   ONLY=grains skips the fluid alone; LAUNCH='mpirun -np 2' runs each on several ranks (one GPU a rank);
#   SCALE=2 widens the box S times along x and z (S^2 times the fluid and the grains: 47 S x 47 x 47 S).
#   Rows are appended to OUT/dem_rate.csv and OUT/logs.txt.
set -uo pipefail
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-16}
out=${1:?usage: dem_rate.sh OUT STEPS BINARY [BACKEND]}; steps=${2:?}; bin=${3:?}; backend=${4:-gpu}
mkdir -p "$out"
S=${SCALE:-1}
L=$(awk -v s="$S" 'BEGIN { printf "%.5f", 0.12549 * s }') # 47 S spacings of 2.67 mm
NB=$((47 * S))
S=(-P Geometry:dr=0.00133 -P Geometry:width=$L -P Geometry:depth=$L
   -P "Container:walls=[{name: base, from: [0, 0], to: [$L, 0]}]" -P "Container:regions=[{shape: fill, level: 0.2, C: 0}]"
   -P DEM:d=0.002 -P DEM:motion=free -P "DEM:block_n=[$NB, 47, $NB]" -P DEM:block_spacing=0.00267
   -P "DEM:block_origin=[0.001335, 0.03, 0.001335]" -P Run:max_steps="$steps" -P Output:snapshots=off
   -P Run:progress_s=1e9 -P Output:diag_dt=1e9)
csv=$out/dem_rate.csv
[ -f "$csv" ] || echo "name,binary,backend,fluid_particles,grains,steps,wall_s,particle_steps_per_s,ms_per_step,dem_steps_per_step" > "$csv"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
read -r -a extra <<< "${EXTRA:-}"
specs=("${NAME:-grains}:0.002"); [ "${ONLY:-}" = grains ] || specs+=(fluid:0)
for spec in "${specs[@]}"; do
    IFS=: read -r name d <<< "$spec"
    more=(); [ "$d" != 0 ] && more=("${extra[@]}")
    read -r -a launch <<< "${LAUNCH:-}"
    SPHSEG_GPU_PROFILE=1 "${launch[@]}" "$bin" inputs/dem_block_settling.yml -o "$tmp/run" --overwrite --backend "$backend" \
        "${S[@]}" -P DEM:d="$d" "${more[@]}" > "$tmp/log" 2>&1
    rc=$?
    { echo "=== $name (DEM:d $d): rc $rc"; cat "$tmp/log"; } >> "$out/logs.txt"
    line=$(grep '^done:' "$tmp/log")
    nf=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1/p' "$tmp/log" | head -1)
    ng=$(sed -n 's/^dem: \([0-9]*\) grains of.*/\1/p' "$tmp/log"); ng=${ng:-0}
    wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
    rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
    io=$(echo "$line" | sed 's/.*, \([0-9.]*\) s of the wall in output.*/\1/')
    ms=$(awk -v w="$wall" -v o="$io" -v s="$steps" 'BEGIN { if (s > 0 && w != "") printf "%.3f", 1000 * (w - o) / s }')
    per=$(sed -n 's/^dem: .* DEM steps in .* fluid steps (\([0-9.]*\) a fluid step).*/\1/p' "$tmp/log")
    echo "$name,$bin,$backend,$nf,$ng,$steps,$wall,$rate,$ms,$per" >> "$csv"
    echo "$name: rc $rc, $line" | cut -c1-200
done
cat "$csv"
