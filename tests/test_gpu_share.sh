#!/usr/bin/env bash
# tools/bench/gpu_share.sh and tools/bench/with_mps.sh without a GPU: a stub
# sphseg (it records its arguments) and a stub nvidia-cuda-mps-control (it
# records -d and what it is sent). gpu_share writes a row for alone, for each
# N > 1 side by side and for each N under MPS, with N runs each, to distinct
# output folders, starts the daemon once and sends it quit; it exits 1 when a
# run fails. with_mps passes the command's exit status on, starts and stops
# the daemon around it, and without the daemon runs the command plainly.
set -u
. "$(dirname "$0")/testlib.sh"
mkdir -p "$tmp/bin"
cat > "$tmp/sphseg" <<STUB
#!/bin/bash
echo "\$@" >> "$tmp/args"
[ -n "\${STUB_FAIL:-}" ] && exit 3
echo "done: stub"
STUB
cat > "$tmp/bin/nvidia-cuda-mps-control" <<STUB
#!/bin/bash
if [ "\${1:-}" = -d ]; then echo "start \$CUDA_MPS_PIPE_DIRECTORY" >> "$tmp/mps"; else echo "send \$(cat)" >> "$tmp/mps"; fi
STUB
chmod +x "$tmp/sphseg" "$tmp/bin/nvidia-cuda-mps-control"

PATH="$tmp/bin:$PATH" STEPS=7 bash tools/bench/gpu_share.sh "$tmp/out" "$tmp/sphseg" 1 3 > "$tmp/log" 2>&1
check "gpu_share exit 0" "[ $? -eq 0 ]" || cat "$tmp/log"
check "gpu_share rows: alone 1, sliced 3, mps 1, mps 3" \
    "[ \"\$(cut -d, -f1,2 '$tmp/out/share.csv' | tail -n +2 | tr '\n' ' ')\" = 'alone,1 sliced,3 mps,1 mps,3 ' ]" \
    || cat "$tmp/out/share.csv"
check "gpu_share: 8 runs, each to its own folder, with the step count" \
    "[ \$(wc -l < '$tmp/args') -eq 8 ] && [ \$(grep -o -- '-o [^ ]*' '$tmp/args' | sort -u | wc -l) -eq 8 ] \
     && [ \$(grep -c 'Run:max_steps=7' '$tmp/args') -eq 8 ]"
check "gpu_share: the daemon started once in OUT/mps and sent quit" \
    "[ \"\$(cat '$tmp/mps')\" = \"start $tmp/out/mps/pipe
send quit\" ]" || cat "$tmp/mps"
STUB_FAIL=1 PATH="$tmp/bin:$PATH" bash tools/bench/gpu_share.sh "$tmp/out2" "$tmp/sphseg" 1 > "$tmp/log2" 2>&1
check "gpu_share exits 1 when a run fails" "[ $? -eq 1 ] && grep -q 'failed' '$tmp/log2'"

rm -f "$tmp/mps"
PATH="$tmp/bin:$PATH" MPS_DIR="$tmp/m" bash tools/bench/with_mps.sh bash -c 'echo "pipe=$CUDA_MPS_PIPE_DIRECTORY"; exit 5' > "$tmp/log3" 2>&1
check "with_mps: the command's exit status, the pipe folder, start then quit" \
    "[ $? -eq 5 ] && grep -q 'pipe=$tmp/m/pipe' '$tmp/log3' && [ \"\$(cut -d' ' -f1 '$tmp/mps' | tr '\n' ' ')\" = 'start send ' ]"
mkdir -p "$tmp/nomps" # a PATH without nvidia-cuda-mps-control, even on a GPU machine
for c in mktemp mkdir true; do ln -s "$(command -v $c)" "$tmp/nomps/$c"; done
PATH="$tmp/nomps" "$(command -v bash)" tools/bench/with_mps.sh true > "$tmp/log4" 2>&1
check "with_mps without the daemon: the command runs, with a warning" "[ $? -eq 0 ] && grep -q 'time-slice' '$tmp/log4'"
exit $fail
