#!/usr/bin/env bash
# test_shift_surface.sh BINARY — Flow:shift_surface, the s of shifting's
# free-surface test div r < d - s (src/sim/setup.c; src/physics/shift.h):
# its default is Lind et al.'s 1/2, the code's rule before the key, so that
# -P Flow:shift_surface=0.5 gives the default run's bits; another value
# moves the particles (s 0.25 shifts more of the surface rows of the drum:
# docs/drum3d.md measured the drums' surface speed against it). So does
# Flow:shift_surface_rule: none (the default) gives the default's bits,
# tangential (the surface rows shifted along the surface) moves them, and
# fade (no threshold: the normal part's share 2 div r / d - 1) moves them
# otherwise than tangential. The
# 2D EV drum at dr 2.5 mm (Fickian shifting on, as the scene sets it), 200
# steps.
set -u
bin=${1:?usage: $0 BINARY}
root=$(cd "$(dirname "$0")/.." && pwd)
. "$(dirname "$0")/testlib.sh"
PY=${PYTHON:-/usr/bin/python3}
run() { # out, extra -P...
    local out=$1; shift
    OMP_NUM_THREADS=1 "$bin" "$root/inputs/drum_2d_EV.yml" -o "$tmp/$out" --backend cpu -P Geometry:dr=0.0025 \
        -P Run:max_steps=200 -P Output:dt=1e3 -P Run:progress_s=1e9 "$@" > "$tmp/$out.log" 2>&1
}
run def && run half -P Flow:shift_surface=0.5 && run quarter -P Flow:shift_surface=0.25 &&
    run none -P Flow:shift_surface_rule=none && run tangential -P Flow:shift_surface_rule=tangential &&
    run fade -P Flow:shift_surface_rule=fade ||
    { echo "FAIL a run did not finish"; tail -5 "$tmp"/*.log; exit 1; }
# the largest difference of the last snapshots' positions, by particle ID (m)
diffx() {
    (cd "$root" && "$PY" - "$tmp/$1" "$tmp/$2" <<'PY'
import sys
import numpy as np
from tools.analysis import snap
a, b = (snap.read_snapshot(snap.list_snapshots(d)[-1]) for d in sys.argv[1:3])
xa, xb = (np.asarray(s["Coordinates"])[np.argsort(s["ParticleIDs"])] for s in (a, b))
print("%.3e" % np.abs(xa - xb).max())
PY
    )
}
d_half=$(diffx def half) d_quarter=$(diffx def quarter) d_none=$(diffx def none) d_tan=$(diffx def tangential)
d_fade=$(diffx tangential fade)
check "Flow:shift_surface 0.5 gives the default's bits (largest |dx| $d_half m)" "[ \"$d_half\" = 0.000e+00 ]"
check "Flow:shift_surface 0.25 moves the particles (largest |dx| $d_quarter m, above 1e-9)" \
    "awk -v d=$d_quarter 'BEGIN { exit !(d > 1e-9) }'"
check "Flow:shift_surface_rule none gives the default's bits (largest |dx| $d_none m)" "[ \"$d_none\" = 0.000e+00 ]"
check "Flow:shift_surface_rule tangential moves the particles (largest |dx| $d_tan m, above 1e-9)" \
    "awk -v d=$d_tan 'BEGIN { exit !(d > 1e-9) }'"
check "Flow:shift_surface_rule fade moves them otherwise than tangential (largest |dx| $d_fade m, above 1e-9)" \
    "awk -v d=$d_fade 'BEGIN { exit !(d > 1e-9) }'"
grep -q "shift_surface: 0.25" "$tmp/quarter/used_params.yml"
check "used_params.yml echoes Flow:shift_surface" "[ $? -eq 0 ]"
exit $fail
