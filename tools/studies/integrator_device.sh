#!/usr/bin/env bash
# Run:integrator on the GPU (issue 56 item 3): both integrators on the 2D EV
# and EN drums at their shipped dr with Run:preset converged (2 s each), the
# chute, the shear box, and the stability sweep in Run:cfl_flow; steps/s,
# dt and the accuracy ratios into $OUT (integrator.csv,
# integrator_accuracy.csv, integrator.png, runs.csv). Under 8 minutes on an
# H200 (runs 4 at a time, every case killed at 480 s, none started after 420 s).
#   OUT=/tmp/o SPHSEG_GPU=local/sphseg_gpu PYTHON=python3 bash tools/studies/integrator_device.sh
set -eu
cd "$(dirname "$0")/../.."
BIN=${SPHSEG_GPU:-local/sphseg_gpu}
PY=${PYTHON:-python3}
W=$(mktemp -d)
OMP_NUM_THREADS=2 "$PY" -m tools.studies.integrator_study run --out "$W" --sphseg "$BIN" --backend gpu --size gpu \
    --jobs 4 --deadline 420 | tee "$OUT/integrator_log.txt"
cp "$W"/integrator.csv "$W"/integrator_accuracy.csv "$W"/integrator.png "$W"/runs.csv "$OUT"/ 2>/dev/null || true
