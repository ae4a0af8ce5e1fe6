#!/bin/bash
# tools/dev/mem_device.sh — issue 56 item 4 on one GPU: the 3D drum's peak device
# memory and bytes a particle (the backend's "gpu memory:" line), single and
# double, at 1.1e7 particles (inputs/drum_3d.yml, Run:preset converged,
# Geometry:dr 0.25 mm, Geometry:length 0.1 m, as tools/studies/time_to_solution.py
# makes the issue's drum), with the permutation's time (SPHSEG_GPU_PROFILE);
# then the largest drums in single: 5e7, 1e8 and 1.5e8 particles (the same
# dr, lengths 0.45, 0.9 and 1.35 m), 3 steps each (a drum that does not fit
# ends with "GPU out of memory", in summary.txt). Run from the repository root:
#
#   SPHSEG_GPU=local/sphseg_gpu SPHSEG_GPU_SINGLE=local/sphseg_gpu_single \
#     [SPHSEG_GPU_BEFORE=local/sphseg_gpu_main] bash tools/dev/mem_device.sh
#
# SPHSEG_GPU_SINGLE: this branch built with PRECISION=single GPU=1 (skipped if
# absent); SPHSEG_GPU_BEFORE (optional): main's double binary: first six small
# scenes' diagnostics rows, 150 steps on the GPU, against this branch's
# ("same ... IDENTICAL" in summary.txt), then the 1.1e7 drum for its memory and
# permutation time beside this branch's.
# Writes under $OUT: mem_drum3d.csv (one row a run), summary.txt (the memory and
# permute lines), and each run's log tail. About 4-7 minutes on one H200; each
# run has its own timeout, so the script ends within 8 minutes.
set -u
cd "$(dirname "$0")/../.."
[ -d local/lib ] && export LD_LIBRARY_PATH=$PWD/local/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
B=${SPHSEG_GPU:-local/sphseg_gpu}
BS=${SPHSEG_GPU_SINGLE:-local/sphseg_gpu_single}
BB=${SPHSEG_GPU_BEFORE:-}
OUT=${OUT:-/tmp/mem_device}
mkdir -p "$OUT"
CSV=$OUT/mem_drum3d.csv
SUM=$OUT/summary.txt
T0=$(date +%s)
echo "run,binary,length_m,particles,steps,rc,wall_s,peak_GB,before_GB,bytes_per_particle,store,spares,list,other,permute_ms_per_build,builds,smi_peak_MiB" >"$CSV"
: >"$SUM"
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader >>"$SUM" 2>&1

# run NAME BINARY LENGTH STEPS TIMEOUT_S [PROFILE]
run() {
    local name=$1 bin=$2 len=$3 steps=$4 to=$5 prof=${6:-0} log=$OUT/$1.log work=/tmp/mem_device_$1
    if [ ! -x "$bin" ]; then echo "$name: no binary $bin, skipped" | tee -a "$SUM"; return; fi
    local left=$((470 - ($(date +%s) - T0)))
    if [ "$left" -lt 30 ]; then echo "$name: skipped, the script's 8 minutes are nearly spent" | tee -a "$SUM"; return; fi
    [ "$to" -gt "$left" ] && to=$left
    local s=$(date +%s)
    # the device's memory in use, sampled every 0.2 s (a binary without the memory line: main's)
    nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 200 >"$work.smi" 2>/dev/null &
    local smi=$!
    SPHSEG_GPU_PROFILE=$prof timeout "$to" "$bin" inputs/drum_3d.yml -o "$work" --overwrite --backend gpu \
        -P Run:preset=converged -P Geometry:dr=0.00025 -P Geometry:length="$len" -P Run:max_steps="$steps" \
        -P Output:snapshots=off -P Run:progress_s=1e9 >"$work.log" 2>&1
    local rc=$? w=$(($(date +%s) - s))
    kill "$smi" 2>/dev/null
    wait "$smi" 2>/dev/null
    echo "nvidia-smi peak: $(sort -n "$work.smi" | tail -1) MiB in use" >>"$work.log"
    grep -E "^sphseg |fields:|gpu: device|gpu memory:|permute arrays|neighbour-list builds|done:|error|out of memory|nvidia-smi peak" \
        "$work.log" | head -20 >"$log"
    tail -5 "$work.log" >>"$log"
    rm -rf "$work" "$work.log" "$work.smi"
    echo "== $name ($bin, length $len m, $steps steps): rc $rc, ${w}s" >>"$SUM"
    grep -E "fields:|gpu memory:|permute arrays|neighbour-list builds|error|out of memory|nvidia-smi peak" "$log" >>"$SUM"
    python3 - "$name" "$bin" "$len" "$steps" "$rc" "$w" "$log" >>"$CSV" <<'EOF'
import re, sys
name, binary, length, steps, rc, wall, log = sys.argv[1:]
t = open(log).read()
n = re.search(r"(\d+) material \+ (\d+) dummy particles", t)
m = re.search(r"gpu memory: peak ([\d.]+) GB in use \(([\d.]+) GB before.*?\), (-?\d+) bytes a particle over \d+ "
              r"particles \(rank 0\): store (-?\d+) \(\d+ of \d+ fields\), permutation spares (-?\d+), neighbour list "
              r"(-?\d+), other scratch (-?\d+)", t)
p = re.search(r"permute arrays\s+([\d.]+) ms", t)
b = re.search(r"gpu: (\d+) neighbour-list builds", t)
builds = int(b.group(1)) if b else 0
perm = "%.3f" % (float(p.group(1)) / builds) if p and builds else ""
smi = re.search(r"nvidia-smi peak: (\d+) MiB", t)
print(",".join([name, binary, length, str(int(n.group(1)) + int(n.group(2))) if n else "", steps, rc, wall]
               + (list(m.groups()) if m else [""] * 7) + [perm, str(builds), smi.group(1) if smi else ""]))
EOF
}

# same: with SPHSEG_GPU_BEFORE, the diagnostics rows (every column but wall_s, as text) of both
# binaries, 150 steps of small scenes on the GPU, a row every step: the flow, C and dt bit for bit
same() {
    local scene=$1 rc=0
    for side in before after; do
        local bin=$BB
        [ $side = after ] && bin=$B
        timeout 60 "$bin" "inputs/$scene.yml" -o "/tmp/mem_same_$side" --overwrite --backend gpu -P Run:max_steps=150 \
            -P Output:snapshots=off -P Output:diag_dt=1e-5 -P Run:t_end=1 -P Run:progress_s=1e9 >/dev/null 2>&1 || rc=1
    done
    python3 - "$scene" "$rc" >>"$SUM" <<'EOF'
import csv, sys
scene, rc = sys.argv[1], sys.argv[2]
try:
    a, b = [[{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(open("/tmp/mem_same_%s/diagnostics.csv" % s))]
            for s in ("before", "after")]
    print("same %-14s %s (%d diagnostics rows%s)" % (scene, "IDENTICAL" if a == b and a else "DIFFERS", len(a),
                                                     "" if rc == "0" else "; a run failed"))
except OSError as e:
    print("same %-14s FAILED: %s" % (scene, e))
EOF
}
if [ -n "$BB" ]; then for sc in drum_2d_EV drum_2d_EN shearbox_2d silo_2d chute_2d column_2d; do same $sc; done; fi

run double_1e7 "$B" 0.1 20 90 1
[ -n "$BB" ] && run before_double_1e7 "$BB" 0.1 20 90 1
run single_1e7 "$BS" 0.1 20 90 1
run single_5e7 "$BS" 0.45 3 110
run single_1e8 "$BS" 0.9 3 150
run single_1.5e8 "$BS" 1.35 3 200
echo "total $(($(date +%s) - T0)) s" >>"$SUM"
cat "$SUM"
