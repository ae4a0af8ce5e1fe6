#!/usr/bin/env bash
# Install the Debian/Ubuntu packages sphseg's build, tests and tools need,
# only those missing. Run as root (or with sudo available); otherwise it
# prints the apt-get command to run and exits 1.
#   bash tools/dev/deps.sh          build, unit tests, tools   (make deps)
#   bash tools/dev/deps.sh --tests  also what the whole test suite uses: ParaView's
#                               pvbatch under xvfb (tests/test_paraview.sh;
#                               about 1 GB with its Qt)      (make deps-test)
set -euo pipefail
pkgs=(build-essential pkg-config libopenmpi-dev openmpi-bin libhdf5-openmpi-dev libmetis-dev
      libcyaml-dev libyaml-dev libcmocka-dev python3 python3-numpy python3-scipy python3-h5py
      python3-matplotlib python3-yaml)
if [ "${1:-}" = --tests ]; then pkgs+=(paraview python3-paraview xvfb xauth); fi
missing=()
for p in "${pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
    echo "deps: all ${#pkgs[@]} packages present"
    exit 0
fi
if ! command -v apt-get >/dev/null; then
    echo "deps: no apt-get here; install the equivalents of: ${missing[*]}" >&2
    echo "      (or point the Makefile at modules: make HDF5_DIR=... CYAML_DIR=... MPICC=...)" >&2
    exit 1
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
        sudo="sudo"
    else
        echo "deps: missing packages: ${missing[*]}" >&2
        echo "deps: run as root:  apt-get update && apt-get install -y ${missing[*]}" >&2
        exit 1
    fi
fi
echo "deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "deps: done"
