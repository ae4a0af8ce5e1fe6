#!/bin/bash
# issue 30: the CI-sized drum of tests/validate_kgc_wall.py (the correction alone, threshold 0.1) with
# one setting changed; the deepest reach past the wall by wall_trace.py (README.md one folder up).
#   OUT=DIR bash docs/data/stabilization/kgc_wall/cpu_probes/run.sh TAG [Section:key=value ...]
# from the repository root, with a CPU build in build-cpu/.
tag=$1; shift; args=(); for o in "$@"; do args+=(-P "$o"); done
rm -rf "$OUT/$tag"
OMP_NUM_THREADS=1 ./build-cpu/sphseg inputs/drum_2d_EV.yml -o "$OUT/$tag" -P Geometry:dr=0.001 -P Material:E=1e4 \
  -P Run:cfl_flow=0.2 -P Output:dt=0.25 -P Run:t_end=1.5 -P Segregation:enabled=off -P Flow:gradient_correction=on \
  -P Flow:gradient_correction_det=0.1 "${args[@]}" > "$OUT/$tag.log" 2>&1
/usr/bin/python3 docs/data/stabilization/kgc_wall/wall_trace.py "$OUT/$tag" "$OUT/$tag.log" "$OUT/tr_$tag" > /dev/null 2>&1
echo "$tag $*: $(grep -o 'error: .*' "$OUT/$tag.log" | cut -c1-90) $(awk 'NR>1{printf "%s:%+.3f ", $1,$2}' "$OUT/tr_$tag.txt")"
