#!/usr/bin/env bash
# test_badinput.sh BINARY — every kind of bad input must stop sphseg before it
# writes anything (DESIGN.md "Errors"): exit status 2, exactly one line on
# stderr, "sphseg: error: FILE:LINE: Section:key: why" (or "-P ARG: ..." for a
# bad override), and no output directory.
#
# Cases: each tests/scenes_bad/*.yml and setup/*.yml, whose first line "# expect: NAME:LINE: ..."
# gives the start of the message after the directory; a missing file; a
# directory; an empty file and one of comments only; bad -P overrides on
# inputs/shearbox_2d.yml; too many particles blamed on the key set by -P (a
# drum's radius, a box's width, a container's walls) rather than on dr.
# Prints PASS name / FAIL name lines; exits 1 if any case fails.
#   tests/test_badinput.sh build/sphseg
set -u

bin=${1:?usage: $0 BINARY}
here=$(cd "$(dirname "$0")" && pwd)
bad=$here/scenes_bad
good=$(dirname "$here")/inputs/shearbox_2d.yml
if [ ! -x "$bin" ]; then
    echo "FAIL setup: $bin is not an executable"
    exit 1
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
n_fail=0
n_pass=0

# check NAME PREFIX SCENE [ARGS...]: run BINARY SCENE -o OUT ARGS..., and want
# exit 2, one stderr line starting "sphseg: error: PREFIX", no OUT.
check() {
    local name=$1 prefix=$2 scene=$3
    shift 3
    local out=$tmp/out why="" rc lines line
    rm -rf "$out"
    "$bin" "$scene" -o "$out" "$@" >"$tmp/stdout" 2>"$tmp/stderr" </dev/null
    rc=$?
    lines=$(awk 'END { print NR }' "$tmp/stderr")
    line=$(head -n 1 "$tmp/stderr")
    [ "$rc" -eq 2 ] || why="$why; exit status $rc, want 2"
    [ "$lines" -eq 1 ] || why="$why; $lines lines on stderr, want 1"
    [[ "$line" == "sphseg: error: $prefix"* ]] || why="$why; stderr does not start with 'sphseg: error: $prefix'"
    [ ! -e "$out" ] || why="$why; $out was created"
    if [ -z "$why" ]; then
        echo "PASS $name"
        n_pass=$((n_pass + 1))
    else
        echo "FAIL $name: ${why#; }"
        sed -n '1,5s/^/    stderr: /p' "$tmp/stderr"
        n_fail=$((n_fail + 1))
    fi
}

# scenes_bad/setup/: errors found when the particles are built (a container's
# regions), not by the scene parser (tests/test_scene.c reads the others)
for f in "$bad"/*.yml "$bad"/setup/*.yml; do
    expect=$(sed -n '1s/^# expect: //p' "$f")
    if [ -z "$expect" ]; then
        echo "FAIL $(basename "$f"): no '# expect: ' first line"
        n_fail=$((n_fail + 1))
        continue
    fi
    check "$(basename "$f" .yml)" "$(dirname "$f")/$expect" "$f"
done

check missing_file "$bad/does_not_exist.yml: cannot read" "$bad/does_not_exist.yml"
check directory "$bad: cannot read" "$bad"
check override_unknown_key "-P Run:foo=1: Run:foo: unknown key" "$good" -P Run:foo=1
check override_unknown_section "-P Foo:dr=1: Foo: unknown section" "$good" -P Foo:dr=1
check override_malformed "-P Geometry:dr: malformed override" "$good" -P Geometry:dr
check override_range "-P Geometry:dr=-1: Geometry:dr: must be > 0" "$good" -P Geometry:dr=-1
check yielded_prescribed "-P Segregation:shear_rate=yielded: Segregation:shear_rate: yielded needs Kinematics:velocity computed" \
    "$good" -P Segregation:shear_rate=yielded
check memory_need "-P Geometry:dr=1e-7: Geometry:dr: 1e-07 m gives" "$good" -P Geometry:dr=1e-7
# issue 55: the key most likely mistyped is the one named (a size set by -P, not dr)
drum2d=$(dirname "$here")/inputs/drum_2d_EV.yml
check memory_need_radius "-P Geometry:radius=50: Geometry:radius: 50 m with Geometry:dr 0.0005 m gives about" \
    "$drum2d" -P Geometry:radius=50
check memory_need_width "-P Geometry:width=1e5: Geometry:width: 1e+05 m with Geometry:dr 0.00174 m gives about" \
    "$good" -P Geometry:width=1e5
check memory_need_walls "-P Container:walls=[{from: [0, 1000], to: [0, 0]}, {from: [0, 0], to: [1000, 0]}]: Container:walls: walls and regions spanning 1e+03 x 1e+03 m with Geometry:dr 0.001 m give about" \
    "$(dirname "$here")/inputs/hopper_2d.yml" -P "Container:walls=[{from: [0, 1000], to: [0, 0]}, {from: [0, 0], to: [1000, 0]}]"
# issue 55: an empty scene file is said to be empty, not missing Run:t_end
: >"$tmp/empty.yml"
printf '# a scene to come\n\n' >"$tmp/comments.yml"
check empty_file "$tmp/empty.yml: the file is empty (0 bytes)" "$tmp/empty.yml"
check empty_file_comments "$tmp/comments.yml: the file is empty (no YAML content" "$tmp/comments.yml"
check override_type "-P Run:t_end=abc: Run:t_end: expected a number" "$good" -P Run:t_end=abc
check override_nan "-P Segregation:D=.nan: Segregation:D: not a finite number" \
    "$good" -P Segregation:D=.nan
check override_gravity "-P Physics:gravity=[0,0,0]: Physics:gravity: must not be all zero" \
    "$good" -P "Physics:gravity=[0,0,0]"
check override_enum "-P Segregation:flux=fast: Segregation:flux: expected one of" \
    "$good" -P Segregation:flux=fast
check override_after_good "-P Run:t_end=0: Run:t_end: must be > 0" \
    "$good" -P Run:t_end=2 -P Run:t_end=0
# granular-flow keys (inputs/drum_2d_EV.yml documents them)
check flow_nu "-P Material:nu=0.5: Material:nu: must be in [0, 0.5), got 0.5" "$good" -P Material:nu=0.5
check flow_cfl "-P Run:cfl_flow=11: Run:cfl_flow: must be in (0, 10], got 11" "$good" -P Run:cfl_flow=11
check flow_mu "-P Material:mu_d=0.1: Material:mu_d: must be >= Material:mu_s" "$good" -P Material:mu_d=0.1
check flow_in_shearbox "-P Kinematics:velocity=computed: Kinematics:velocity: computed needs Geometry:type column or drum" \
    "$good" -P Kinematics:velocity=computed
check flow_direction "-P Walls:direction=up: Walls:direction: expected one of clockwise|counterclockwise" \
    "$good" -P Walls:direction=up
check coulomb_no_mu "$good:1: Walls:mu_w: a wall with slip coulomb needs Walls:mu_w > 0" "$good" -P Walls:slip=coulomb
check coulomb_end_no_mu "$good:1: Walls:mu_w: a wall with slip coulomb needs Walls:mu_w > 0" "$good" -P Walls:end_slip=coulomb
check end_slip_enum "-P Walls:end_slip=rough: Walls:end_slip: expected one of side|no_slip|free_slip|coulomb" \
    "$good" -P Walls:end_slip=rough
check drum_small "-P Geometry:radius=0.01: Geometry:radius: must be >= 8*dr" \
    "$good" -P Geometry:type=drum -P Kinematics:velocity=computed -P Geometry:radius=0.01
check shearbox_3d "-P Geometry:dim=3: Geometry:dim: 3D is supported for Geometry:type column or drum only" \
    "$good" -P Geometry:dim=3
# the 3D drum's length (inputs/drum_3d.yml documents it)
drum3d=$(dirname "$here")/inputs/drum_3d.yml
check drum3d_length_negative "-P Geometry:length=-0.01: Geometry:length: must be > 0, got -0.01" \
    "$drum3d" -P Geometry:length=-0.01
check drum3d_length_small "-P Geometry:length=0.001: Geometry:length: must be >= 4*dr" \
    "$drum3d" -P Geometry:length=0.001
check nothing_to_solve "-P Segregation:enabled=off: Segregation:enabled: off with prescribed velocity leaves nothing to solve" \
    "$good" -P Segregation:enabled=off
# checkpoint keys and bad restart files (src/output/checkpoint.c; the restart cases
# that need a checkpoint written first are in tests/validate_restart.py)
check ckpt_dt_range "-P Output:checkpoint_dt=-1: Output:checkpoint_dt: must be >= 0, got -1" \
    "$good" -P Output:checkpoint_dt=-1
check wall_time_type "-P Run:max_wall_time=1h: Run:max_wall_time: expected a number" \
    "$good" -P Run:max_wall_time=1h
check restart_missing "--restart $tmp/none.h5: cannot read it" "$good" --restart "$tmp/none.h5"
check restart_not_sealed "--restart $good: not a sphseg checkpoint (no checksum block" "$good" --restart "$good"
check restart_no_file "command line: --restart needs a FILE" "$good" --restart
# a tuning setting set to something it cannot mean (src/core/tuning.c; README "Tuning and diagnostics settings")
SPHSEG_BALANCE_SKEW=3 check skew_no_factor "SPHSEG_BALANCE_SKEW=3: expected RANK:FACTOR" "$good"
SPHSEG_BALANCE_SKEW=0:-1 check skew_negative "SPHSEG_BALANCE_SKEW=0:-1: expected RANK:FACTOR" "$good"
SPHSEG_BALANCE_SKEW=1:3 check skew_no_such_rank "SPHSEG_BALANCE_SKEW=1:3: rank 1, but the run has 1 rank(s)" "$good"

echo "test_badinput: $n_pass passed, $n_fail failed"
[ "$n_fail" -eq 0 ]
