#!/usr/bin/env bash
# The warnings for flow settings outside the measured range (src/settings_check.c,
# settings_warn_drum; docs/gpu.md "Stiffness, artificial viscosity and CFL"):
# alpha_av sqrt(E) more than 2x off Table 1's (0.1 at 10 MPa; Flow:stabilization
# monaghan only, which the probes of it set: the drum scene runs riemann with the
# corrected gradient and fickian shifting), and
# Run:cfl_flow > 0.2, and E below the softest measured accurate (10 kPa); the
# pressure diffusion's (settings_warn_stabilization); Material:mu_law partial's
# (settings_warn_mu_law); Flow:gradient_correction on without Flow:shifting
# (settings_warn_gradient_correction); Flow:shift_surface_rule fade's (settings_warn_shift);
# and the Shepard filter's interval below 3 acoustic times,
# Flow:shepard_every * Run:cfl_flow (docs/granular.md "The time step and the Shepard
# filter"). Each probe is a 1-step CPU drum; the warning must be
# there when the setting is off and absent when it is in range.
# Issue 55, scales outside what the model is meant for (src/settings_check.c
# settings_warn_scales, src/sim/setup_container.c ctr_check_held): grains of
# 1 and 2 m (mm typed as m) against the drum (fewer than 4 large grains
# across) and against dr (more than 50 dr); a drum's Froude number
# omega^2 R / g from 0.1 (300 rpm: 3.5; 51 rpm: 0.102 warns, 50 rpm: 0.098
# does not), also of a container's turning cylinder; the hopper filled above
# its walls, its gate 5 mm short of the next wall, its gate 5 mm below the
# hopper's ends (material behind a wall), and the shipped hopper silent.
# Threads (issue 55, defect 6): twice as many OpenMP threads as cores warns
# of oversubscription, one thread does not; the first lines give the
# threads; and on 2 ranks the last progress line and the done: line count
# the same thing (the particles of all ranks per second less output), over
# the same wall time, so they agree to the progress line's 4 figures.
set -u
bin=${1:?usage: test_settings_warnings.sh BUILD/sphseg}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
# probe_in SCENE BASE_OVERRIDES name expect pattern -P overrides...: a 1-step CPU run of
# inputs/SCENE (OMP_NUM_THREADS=1 unless THREADS is set) and the warning looked for
probe_in() {
    local scene=$1 base=$2 name=$3 want=$4 pat=$5; shift 5
    local args=() o
    for o in $base "$@"; do args+=(-P "$o"); done
    OMP_NUM_THREADS=${THREADS:-1} "$bin" "$here/../inputs/$scene" -o "$tmp/o" --overwrite --backend cpu \
        -P Run:max_steps=1 -P Run:progress_s=1e9 -P Output:snapshots=off "${args[@]}" >"$tmp/log" 2>&1
    local rc=$?
    [ $rc -eq "${RC:-0}" ] || { echo "FAIL $name: exit $rc, expected ${RC:-0}"; tail -n 2 "$tmp/log"; fail=1; return; }
    local got=no
    grep -q "warning: .*$pat" "$tmp/log" && got=yes
    if [ "$got" = "$want" ]; then echo "ok   $name"; else echo "FAIL $name: warning '$pat' $got, expected $want"; fail=1; fi
}
probe() { probe_in drum_2d_EV.yml Geometry:dr=0.0025 "$@"; } # name, expect (yes|no), pattern, -P overrides...
M=Flow:stabilization=monaghan # the paper's (3.10), whose alpha_av the AV warning is about
probe "the scene (riemann, the corrected gradient, fickian shifting) at E 0.1 MPa: no warning at all" no "" \
    Material:E=1e5
probe "Table 1 settings, monaghan: no AV warning" no "alpha_av" $M
probe "E 0.1 MPa, alpha 0.1: AV warning" yes "alpha_av \* sqrt(Material:E) is 0.1 times" $M Material:E=1e5
probe "E 0.1 MPa, alpha 1.0: no AV warning" no "alpha_av" $M Material:E=1e5 Flow:alpha_av=1.0
probe "E 10 MPa, alpha 0.5: AV warning" yes "alpha_av" $M Flow:alpha_av=0.5
probe "E 10 kPa, alpha 3.162: no warning at all" no "" $M Material:E=1e4 Flow:alpha_av=3.162
probe "E 5 kPa, alpha 4.47: softness warning" yes "Material:E = 5e+03 Pa is softer" $M Material:E=5e3 Flow:alpha_av=4.472
probe "riemann's pressure diffusion: its warning" yes "Flow:riemann_diffusion on: the pressure diffusion" \
    Flow:riemann_diffusion=on
probe "Material:mu_law partial: its warning" yes "Material:mu_law partial: mu(I) has no static yield" \
    Material:E=1e5 Material:mu_law=partial
probe "Flow:gradient_correction on, no shifting: its warning" yes \
    "Flow:gradient_correction on without Flow:shifting" Material:E=1e5 Flow:gradient_correction=on Flow:shifting=off
probe "Flow:gradient_correction on with fickian shifting: no warning at all" no "" \
    Material:E=1e5 Flow:gradient_correction=on Flow:shifting=fickian
probe "Flow:gradient_correction off, no shifting (the paper's): no warning at all" no "" \
    Material:E=1e5 Flow:gradient_correction=off Flow:shifting=off
probe "Flow:shift_surface_rule fade: its warning" yes "Flow:shift_surface_rule fade keeps a share" \
    Material:E=1e5 Flow:shift_surface_rule=fade
probe "Flow:shift_surface_rule tangential: no warning at all" no "" Material:E=1e5 Flow:shift_surface_rule=tangential
probe "cfl_flow 0.2: no CFL warning" no "cfl_flow" Run:cfl_flow=0.2
probe "cfl_flow 0.3: CFL warning" yes "Run:cfl_flow = 0.3 > 0.2" Run:cfl_flow=0.3
probe "cfl_flow 0.05, shepard_every 30 (1.5 acoustic times): filter warning" yes \
    "Flow:shepard_every \* Run:cfl_flow = 1.5 < 3" Run:cfl_flow=0.05
probe "cfl_flow 0.05, shepard_every 60 (3 acoustic times): no filter warning" no "shepard_every" \
    Run:cfl_flow=0.05 Flow:shepard_every=60
probe "cfl_flow 0.05, the filter off: no filter warning" no "shepard_every" Run:cfl_flow=0.05 Flow:shepard_every=0
probe "cfl_flow 0.15, shepard_every 20 (3, the bound): no filter warning" no "shepard_every" \
    Run:cfl_flow=0.15 Flow:shepard_every=20
# issue 55: unit slips and regimes the model is not meant for
probe "grains of 1 and 2 m: more than the drum holds" yes "Grains:d_large = 2 m: the drum's diameter, 0.07 m, holds 0.035 large grains across, fewer than 4" \
    Grains:d_small=1 Grains:d_large=2
probe "grains of 1 and 2 m: 800 dr in a grain" yes "Grains:d_large = 2 m is 800 particle spacings" \
    Grains:d_small=1 Grains:d_large=2
probe "grains of 4 and 8 mm at dr 2.5 mm (8.75 across, 3.2 dr): no grain warning" no "Grains:d_large" \
    Grains:d_small=0.004 Grains:d_large=0.008
probe "300 rpm: Froude warning" yes "Walls:rpm = 300 rev/min on a drum of radius 0.035 m gives a Froude number omega^2 R / g = 3.52" \
    Walls:rpm=300
probe "51 rpm (Fr 0.102): Froude warning" yes "Froude number omega^2 R / g = 0.102" Walls:rpm=51
probe "50 rpm (Fr 0.098): no Froude warning" no "Froude" Walls:rpm=50
DRUM_C='Container:walls=[{name: drum, shape: cylinder, centre: [0, 0], radius: 0.035, motion: turning, rpm: 300}]'
probe "a container's turning cylinder at 300 rpm: Froude warning" yes "Container:walls:1:rpm = 300 rev/min .* = 3.52" \
    Geometry:type=container "$DRUM_C" "Container:regions=[{shape: fill, level: 0, C: 0.5}]"
H=hopper_2d.yml
HW='{name: left, from: [0, 0.16], to: [0, 0.04]}, {name: hopper_left, from: [0, 0.04], to: [0.04, 0]}'
HE='{name: hopper_right, from: [0.06, 0], to: [0.1, 0.04]}, {name: right, from: [0.1, 0.04], to: [0.1, 0.16]}'
probe_in $H Geometry:dr=0.002 "the shipped hopper: no warning at all" no ""
probe_in $H Geometry:dr=0.002 "the hopper filled to 0.2 m, above its 0.16-m walls: free-standing fill" yes \
    "Container:regions:1: 1000 of its sites have no wall beside them .* the fill rises above the walls' highest end" \
    "Container:regions=[{shape: fill, level: 0.2, C: 0}]"
probe_in $H Geometry:dr=0.001 "a 5-mm gap between the gate and hopper_right: material below the gate" yes \
    "no wall beside them across gravity at the start (the first at (0.0575, -0.0015) m).* hopper_right's (0.06, 0) and gate's (0.055, 0) m, 0.005 m apart" \
    "Container:walls=[$HW, {name: gate, from: [0.04, 0], to: [0.055, 0], open_at: 0.05}, $HE]"
# (that material leaves through the wall in the first step: exit 3, after the warning)
RC=3 probe_in $H Geometry:dr=0.001 "the gate 5 mm below the hopper's ends: material behind hopper_left" yes \
    "Container:regions:1: .* of its sites lie behind wall hopper_left at the start" \
    "Container:walls=[$HW, {name: gate, from: [0.04, -0.005], to: [0.06, -0.005], open_at: 0.05}, $HE]"
# threads (issue 55, defect 6)
cores=$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc) # nproc obeys OMP_NUM_THREADS; a CPU quota may give fewer
THREADS=$((2 * cores)) probe "$((2 * cores)) OpenMP threads on $cores core(s): oversubscription warning" yes \
    "$((2 * cores)) OpenMP threads on rank 0's node (1 rank(s) x $((2 * cores))) share [0-9]* core(s)"
grep -q "1 rank(s) x $((2 * cores)) OpenMP thread(s)" "$tmp/log" && grep -q "^threads: $((2 * cores)) OpenMP thread(s) per rank (OMP_NUM_THREADS=$((2 * cores)))" "$tmp/log" &&
    echo "ok   the first lines give the threads" || { echo "FAIL the first lines give the threads"; head -3 "$tmp/log"; fail=1; }
THREADS=1 probe "1 OpenMP thread: no oversubscription warning" no "OpenMP threads on"
if command -v mpirun >/dev/null; then
    OMP_NUM_THREADS=1 mpirun --oversubscribe --allow-run-as-root -np 2 "$bin" "$here/../inputs/drum_2d_EV.yml" -o "$tmp/o2" \
        --backend cpu -P Geometry:dr=0.0025 -P Run:max_steps=20 -P Run:progress_s=1e-9 -P Output:snapshots=off >"$tmp/log2" 2>&1
    p=$(grep '^step ' "$tmp/log2" | tail -n 1 | sed -n 's/.*  \([0-9.e+-]*\) particle-steps\/s (all ranks, output excluded).*/\1/p')
    d=$(sed -n 's/^done: .* s wall, \([0-9.e+-]*\) particle-steps\/s (the particles of all 2 rank(s), .*/\1/p' "$tmp/log2")
    if [ -n "$p" ] && [ -n "$d" ] && awk -v p="$p" -v d="$d" 'BEGIN { exit !(p > 0.999 * d && p < 1.001 * d) }'; then
        echo "ok   2 ranks: the last progress line ($p) and the done: line ($d) count the same, labelled"
    else
        echo "FAIL 2 ranks: the last progress line '$p' and the done: line '$d' differ or lack their labels"
        grep '^step \|^done' "$tmp/log2" | tail -n 3; fail=1
    fi
fi
exit $fail
