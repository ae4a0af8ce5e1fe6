#!/bin/bash
# The glass-bead column collapse (issue 57, item 3) on one GPU: the sets lajeunesse (mu(I)),
# lajeunesse_const (mu = tan 27.4 deg) and lajeunesse_E (E x 10) of tools/studies/collapse_study.py,
# a = 0.5, 2, 4, 8 at L0/dr 10, 20, 40 (28 runs, 2D; the largest, a = 8 at L0/dr 40, holds 12800 particles), then the report. Run from the repository root:
#
#   OUT=DIR SPHSEG_GPU=local/sphseg_gpu PYTHON=python3 bash tools/studies/collapse_device.sh
#
# It writes under $OUT: tables.md (the report's tables), glass.csv (one row a run), runs.csv (cost),
# validation_collapse_glass.png (runout and height against a) and run.log. The runs themselves stay
# in a temporary folder. Six runs share the GPU at a time, under MPS where the machine has it
# (tools/bench/with_mps.sh: without it they time-slice the GPU); every run is started by 400 s.
set -euo pipefail
: "${OUT:?set OUT to the folder for the results}"
SPHSEG=${SPHSEG_GPU:-local/sphseg_gpu}
PY=${PYTHON:-python3}
W=$(mktemp -d)
mkdir -p "$OUT"
bash tools/bench/with_mps.sh "$PY" -m tools.studies.collapse_study run --sphseg "$SPHSEG" --out "$W" --backend gpu --jobs 6 --deadline-s 400 \
    --set lajeunesse,lajeunesse_const,lajeunesse_E --only '_n40,_n20,_n10' > "$OUT/run.log" 2>&1
"$PY" -m tools.studies.collapse_study report --out "$W" --docs "$OUT" --table "$OUT/tables.md" > /dev/null
cp "$W/runs.csv" "$OUT/runs.csv"
rm -rf "$W"
