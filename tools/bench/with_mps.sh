#!/usr/bin/env bash
# Run a command with a CUDA MPS daemon, so that the GPU runs it starts side by
# side share the SMs instead of time-slicing: for ensembles and sweeps of
# small runs on one GPU (the 10^4-particle 2D EN drum: 3.3 times the rate of one
# run with eight under MPS, 0.75 times without; docs/performance.md, "Many
# small runs on one GPU: MPS"). The daemon is started with its pipe and log folders in a
# temporary folder (MPS_DIR to choose), and stopped when the command ends; it
# changes no setting of the GPU. Without nvidia-cuda-mps-control, or where the
# daemon does not start, the command runs plainly, with a warning.
#   tools/bench/with_mps.sh python3 -m tools.studies.collapse_study run --sphseg BIN --out DIR --backend gpu --jobs 8 ...
# Sourced, it defines mps_start DIR (0 when the daemon runs) and mps_stop.

mps_start() {
    command -v nvidia-cuda-mps-control > /dev/null || {
        echo "with_mps: no nvidia-cuda-mps-control on the PATH: runs time-slice the GPU" >&2; return 1; }
    export CUDA_MPS_PIPE_DIRECTORY=$1/pipe CUDA_MPS_LOG_DIRECTORY=$1/log
    mkdir -p "$CUDA_MPS_PIPE_DIRECTORY" "$CUDA_MPS_LOG_DIRECTORY"
    nvidia-cuda-mps-control -d || {
        echo "with_mps: the MPS daemon did not start (see $CUDA_MPS_LOG_DIRECTORY): runs time-slice the GPU" >&2
        unset CUDA_MPS_PIPE_DIRECTORY CUDA_MPS_LOG_DIRECTORY; return 1; }
}

mps_stop() {
    [ -n "${CUDA_MPS_PIPE_DIRECTORY:-}" ] && echo quit | nvidia-cuda-mps-control
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
    set -u
    [ $# -gt 0 ] || { echo "usage: with_mps.sh COMMAND [ARG ...]" >&2; exit 2; }
    dir=${MPS_DIR:-$(mktemp -d)}
    mps_start "$dir" && trap mps_stop EXIT
    "$@"
fi
