#!/usr/bin/env bash
# The GPU neighbour pass's forms side by side (issue 56 item 1; docs/performance.md,
# "Neighbour pass"), SPHSEG_GPU_NBR=
#   list     the Verlet list, 4-byte entries (the default),
#   list16   the same list in 2-byte entries (a cell slot and an offset in the cell),
#   cells    no list: the build's cells scanned, counted within the list's radius,
#   tile     list16, its flow pass staged cell by cell in shared memory (k_flow_tile).
# (a) Bit-identity of each form against list (tools.dev.identical, --backend
#     gpu, 100 steps): the 2D EN drum and the 3D drum coarsened to about 3e4
#     particles; and tests/test_ranks_bitwise.py --backend gpu (1, 2, 3 ranks on the
#     one device) under each form.
# (b) The 3D drum of 1.1e7 particles (inputs/drum_3d.yml, dr 0.25 mm, length 0.1 m,
#     Run:preset PRESET, converged unless set), STEPS steps with SPHSEG_GPU_PROFILE=1, each form:
#     particle-steps/s (sphseg's "done:" line: set-up and output excluded), the
#     profile's ms per step, the list's size and the device's peak memory in use
#     (nvidia-smi sampled every 100 ms).
# Usage (repository root, one GPU):
#   OUT=DIR [SPHSEG_GPU=local/sphseg_gpu] [SPHSEG_GPU_DOUBLE=BIN] [STEPS=200] [PYTHON=python3] \
#     [FORMS="list list16 cells tile"] [PRESET=converged|fast] \
#     bash tools/bench/nbr_designs.sh
# SPHSEG_GPU is a single-precision build (make GPU=1 PRECISION=single); SPHSEG_GPU_DOUBLE,
# if given, a double one, timed after it. Writes under OUT: identity.txt, ranks.txt,
# nbr_designs.csv, profiles.txt, log.txt. Parts that would end past BUDGET s (460) are skipped, and say so.
set -uo pipefail
out=${OUT:?set OUT to a folder for the results}
bin=${SPHSEG_GPU:-local/sphseg_gpu}
bind=${SPHSEG_GPU_DOUBLE:-}
steps=${STEPS:-200}
py=${PYTHON:-python3}
forms=${FORMS:-list list16 cells tile}
preset=${PRESET:-converged}
mkdir -p "$out"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
log="$out/log.txt"
: > "$log"
for b in "$bin" $bind; do [ -x "$b" ] || { echo "no GPU binary at $b" | tee -a "$log"; exit 2; }; done
wrap() { # form binary: a launcher that runs the binary under SPHSEG_GPU_NBR=form
    local w="$tmp/sphseg_$1_$(basename "$2")"
    printf '#!/bin/sh\nSPHSEG_GPU_NBR=%s exec %s "$@"\n' "$1" "$(realpath "$2")" > "$w"
    chmod +x "$w"
    echo "$w"
}

left() { [ $((SECONDS + $1)) -lt "${BUDGET:-460}" ]; } # room for $1 s more within BUDGET s

# (a) bit-identity
: > "$out/identity.txt"
for f in $forms; do
    [ "$f" = list ] && continue
    echo "== $f against list (one rank, 100 steps)" >> "$out/identity.txt"
    timeout 150 "$py" -m tools.dev.identical --backend gpu --before "$(wrap list "$bin")" --after "$(wrap "$f" "$bin")" \
        --only '^drum_2d_EN|^drum_3d' --no-cases --steps 100 --max-particles 30000 >> "$out/identity.txt" 2>&1 \
        || echo "($f: identical.py exited $?)" >> "$out/identity.txt"
done
# (b) the 1.1e7 drum, single; then (a)'s rank counts, and the double build, while time is left
gpu=$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1)
csv="$out/nbr_designs.csv"
echo "form,precision,preset,particles,steps,wall_s,particle_steps_per_s,list_mib,peak_device_mib,builds,list_ms_step,flow_ms_step,walls_ms_step,shift_ms_step,kgc_ms_step,total_ms_step,gpu" > "$csv"
: > "$out/profiles.txt"
ms() { # profile row name -> ms/step
    sed -n "s/^ *$1.* \([0-9.]*\) ms\/step.*/\1/p" "$tmp/log" | head -1
}
drum() { # form precision binary
    local f=$1 prec=$2 b=$3
    nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 100 > "$tmp/mem" 2>/dev/null &
    local smi=$!
    SPHSEG_GPU_NBR=$f SPHSEG_GPU_PROFILE=1 timeout 240 "$b" inputs/drum_3d.yml -o "$tmp/run" --overwrite --backend gpu \
        -P Geometry:dr=0.00025 -P Geometry:length=0.1 -P Run:preset="$preset" -P Run:max_steps="$steps" \
        -P Run:progress_s=1e9 -P Output:snapshots=off -P Output:diag_dt=1e9 > "$tmp/log" 2>&1
    local rc=$?
    kill "$smi" 2>/dev/null; wait "$smi" 2>/dev/null
    { echo "== $f $prec (exit $rc)"; grep -E "^gpu|^  |^done:" "$tmp/log"; } >> "$out/profiles.txt"
    local line n wall rate lmib peak builds
    line=$(grep '^done:' "$tmp/log")
    if [ $rc -ne 0 ] || [ -z "$line" ]; then
        echo "$f $prec: sphseg exited $rc: $(tail -n 1 "$tmp/log")" | tee -a "$log"
        echo "$f,$prec,$preset,,,,,,,,,,,,,,failed rc $rc" >> "$csv"
        return
    fi
    n=$(sed -n 's/.*, \([0-9]*\) material + \([0-9]*\) dummy.*/\1 \2/p' "$tmp/log" | head -1 | awk '{print $1+$2}')
    wall=$(echo "$line" | sed 's/.*steps, \([0-9.]*\) s wall.*/\1/')
    rate=$(echo "$line" | sed 's/.*wall, \([0-9.e+]*\) particle.*/\1/')
    lmib=$(sed -n 's/.* \([0-9]*\) MiB of neighbour list.*/\1/p' "$tmp/log" | head -1)
    peak=$(sort -n "$tmp/mem" | tail -1)
    builds=$(sed -n 's/^gpu: \([0-9]*\) neighbour-list builds.*/\1/p' "$tmp/log" | head -1)
    echo "$f,$prec,$preset,$n,$steps,$wall,$rate,$lmib,$peak,$builds,$(ms 'neighbour list'),$(ms 'flow rates'),$(ms 'dummy walls'),$(ms 'particle shifting'),$(ms "corrected gradient's"),$(sed -n 's/^ *total *\([0-9.]*\) ms;.*/\1/p' "$tmp/log" | awk -v s="$steps" '{printf "%.4f", $1 / s}'),$gpu" >> "$csv"
    echo "$f $prec: $rate particle-steps/s, peak $peak MiB" | tee -a "$log"
}
for f in $forms; do left 60 && drum "$f" single "$bin" || echo "$f single: skipped (time)" | tee -a "$log"; done

: > "$out/ranks.txt"
for f in $forms; do
    left 60 || { echo "(out of time: $f not run)" >> "$out/ranks.txt"; continue; }
    echo "== SPHSEG_GPU_NBR=$f: tests/test_ranks_bitwise.py --backend gpu" >> "$out/ranks.txt"
    SPHSEG_GPU_NBR=$f timeout 120 "$py" -m tests.test_ranks_bitwise --backend gpu --sphseg "$bin" \
        >> "$out/ranks.txt" 2>&1; echo "(exit $?)" >> "$out/ranks.txt"
done

if [ -n "$bind" ]; then for f in $forms; do left 90 && drum "$f" double "$bind" || echo "$f double: skipped (time)" | tee -a "$log"; done; fi
cat "$csv" | tee -a "$log"
echo "total $SECONDS s" | tee -a "$log"
exit 0
