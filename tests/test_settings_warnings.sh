#!/usr/bin/env bash
# The warnings for flow settings outside the measured range (src/settings_check.c,
# settings_warn_drum; docs/gpu.md "Stiffness, artificial viscosity and CFL"):
# alpha_av sqrt(E) more than 2x off Table 1's (0.1 at 10 MPa; Flow:stabilization
# monaghan only, which the probes of it set: the drum scene runs riemann with the
# corrected gradient and fickian shifting), and
# Run:cfl_flow > 0.2, and E below the softest measured accurate (10 kPa); the
# pressure diffusion's (settings_warn_stabilization); Material:mu_law partial's
# (settings_warn_mu_law); Flow:gradient_correction on without Flow:shifting
# (settings_warn_gradient_correction); and the Shepard filter's interval below 3 acoustic times,
# Flow:shepard_every * Run:cfl_flow (docs/granular.md "The time step and the Shepard
# filter"). Each probe is a 1-step CPU drum; the warning must be
# there when the setting is off and absent when it is in range.
set -u
bin=${1:?usage: test_settings_warnings.sh BUILD/sphseg}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
probe() { # name, expect (yes|no), pattern, -P overrides...
    local name=$1 want=$2 pat=$3; shift 3
    local args=() o
    for o in "$@"; do args+=(-P "$o"); done
    OMP_NUM_THREADS=1 "$bin" "$here/../inputs/drum_2d_EV.yml" -o "$tmp/o" --overwrite --backend cpu -P Geometry:dr=0.0025 \
        -P Run:max_steps=1 -P Run:progress_s=1e9 "${args[@]}" >"$tmp/log" 2>&1 || { echo "FAIL $name: exit $?"; fail=1; return; }
    local got=no
    grep -q "warning: .*$pat" "$tmp/log" && got=yes
    if [ "$got" = "$want" ]; then echo "ok   $name"; else echo "FAIL $name: warning '$pat' $got, expected $want"; fail=1; fi
}
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
probe "cfl_flow 0.2: no CFL warning" no "cfl_flow" Run:cfl_flow=0.2
probe "cfl_flow 0.3: CFL warning" yes "Run:cfl_flow = 0.3 > 0.2" Run:cfl_flow=0.3
probe "cfl_flow 0.05, shepard_every 30 (1.5 acoustic times): filter warning" yes \
    "Flow:shepard_every \* Run:cfl_flow = 1.5 < 3" Run:cfl_flow=0.05
probe "cfl_flow 0.05, shepard_every 60 (3 acoustic times): no filter warning" no "shepard_every" \
    Run:cfl_flow=0.05 Flow:shepard_every=60
probe "cfl_flow 0.05, the filter off: no filter warning" no "shepard_every" Run:cfl_flow=0.05 Flow:shepard_every=0
probe "cfl_flow 0.15, shepard_every 20 (3, the bound): no filter warning" no "shepard_every" \
    Run:cfl_flow=0.15 Flow:shepard_every=20
exit $fail
