#!/usr/bin/env bash
# Inputs at the extremes (issue 19, defects 8 and 9): each is refused at
# once with exit 2 and one line, or handled, never undefined behaviour or a
# wait of minutes:
#  - Geometry:dr = 1e-8 on the 2D drum (the size is estimated in O(1) before
#    any loop) and dr = 4e-320 on the shear box (no lround overflow);
#  - Output:dt = 1e-300 with Run:t_end = 1e300 (a snapshot every step);
#  - an ETA too long for a long integer prints as such;
#  - -o '' and a scene nested 200 000 levels deep, on the file and in -P;
#  - a restart into a new OUTDIR lists in snapshots.xmf only the snapshots
#    that are there.
set -u
bin=${1:?usage: test_extremes.sh build/sphseg}
. "$(dirname "$0")/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
export OMP_NUM_THREADS=1
one_line_2() { # name, expected words, command...: exit 2, one line, under 10 s
    local name=$1 words=$2; shift 2
    local t0=$SECONDS
    timeout 60 "$@" >"$tmp/out.log" 2>&1
    local rc=$? dt=$((SECONDS - t0))
    check "$name: exit 2, one line, ${dt} s" "[ $rc -eq 2 ] && [ \$(wc -l <'$tmp/out.log') -eq 1 ] && [ $dt -lt 10 ] && grep -q -- '$words' '$tmp/out.log'" || { echo "    rc $rc"; head -c 600 "$tmp/out.log"; }
}

one_line_2 "drum, dr = 1e-8" "Geometry:dr: 1e-08 m gives about" "$bin" inputs/drum_2d_EV.yml -o "$tmp/a" -P Geometry:dr=1e-8
one_line_2 "3D drum, dr = 1e-7" "Geometry:dr: 1e-07 m gives about" "$bin" inputs/drum_3d.yml -o "$tmp/a" -P Geometry:dr=1e-7
one_line_2 "shear box, dr = 4e-320" "Geometry:dr: 4e-320 m gives about" "$bin" inputs/shearbox_2d.yml -o "$tmp/a" -P Geometry:dr=4e-320
one_line_2 "Output:dt = 1e-300, Run:t_end = 1e300" "Output:dt = 1e-300 s asks for inf outputs" "$bin" inputs/shearbox_2d.yml -o "$tmp/a" -P Output:dt=1e-300 -P Run:t_end=1e300
one_line_2 "-o ''" "-o needs a directory name" "$bin" inputs/shearbox_2d.yml -o ''
one_line_2 "--restart ''" "--restart needs a FILE or DIR" "$bin" inputs/shearbox_2d.yml --restart ''
printf 'Run:\n  t_end: %s1%s\n' "$(head -c 200000 /dev/zero | tr '\0' '[')" "$(head -c 200000 /dev/zero | tr '\0' ']')" >"$tmp/deep.yml"
one_line_2 "a value nested 200 000 levels deep" "deep.yml:2: not a scene: nested more than 64 levels" "$bin" "$tmp/deep.yml" -o "$tmp/a"
one_line_2 "-P nested 100 levels deep" "is nested more than 64 levels deep" "$bin" inputs/shearbox_2d.yml -o "$tmp/a" -P "Run:t_end=$(head -c 100 /dev/zero | tr '\0' '[')$(head -c 100 /dev/zero | tr '\0' ']')"
{ cat inputs/shearbox_2d.yml; head -c 1100000 /dev/zero | tr '\0' '#'; echo; } >"$tmp/big.yml"
one_line_2 "a 1.1 MB scene" "larger than any scene file" "$bin" "$tmp/big.yml" -o "$tmp/a"

"$bin" inputs/shearbox_2d.yml -o "$tmp/eta" -P Run:t_end=1e300 -P Output:dt=1e296 -P Output:diag_dt=1e296 -P Run:max_steps=3 \
    -P Run:progress_s=0.001 >"$tmp/eta.log" 2>&1
check "an ETA past 1e8 hours prints as such" "[ $? -eq 0 ] && grep -q 'ETA > 1e8 h' '$tmp/eta.log' && ! grep -q 'ETA -' '$tmp/eta.log'" || tail -3 "$tmp/eta.log"

"$bin" inputs/shearbox_2d.yml -o "$tmp/first" -P Run:t_end=2 -P Output:dt=0.5 -P Output:checkpoint_dt=1 >/dev/null 2>&1
"$bin" inputs/shearbox_2d.yml -o "$tmp/second" --restart "$tmp/first" -P Run:t_end=3 -P Output:dt=0.5 \
    -P Output:checkpoint_dt=1 >"$tmp/second.log" 2>&1
check "a restart into a new OUTDIR: snapshots.xmf lists only the snapshots there" "[ $? -eq 0 ] && (cd '$tmp/second' && for f in \$(grep -o 'snapshot_[0-9]*\.h5' snapshots.xmf | sort -u); do [ -f \$f ] || exit 1; done) && [ \$(grep -c '<Grid Name=\"snapshot_' '$tmp/second/snapshots.xmf') -eq 2 ] && grep -q '5 of the 5 earlier snapshots are not in' '$tmp/second.log'" || { cat "$tmp/second.log"; ls "$tmp/second"; }
exit $fail
