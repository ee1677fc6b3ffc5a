#!/usr/bin/env bash
# Installs the Debian packages vproxq needs (only those missing; as root or through sudo),
# then configures and builds a Release tree in ./build. Idempotent: a second run only rebuilds.
#   bash scripts/setup.sh            # packages + build
#   bash scripts/setup.sh --no-build # packages only
#   bash scripts/setup.sh --bench    # also the benchmark-only packages (FCL, gnuplot, jq)
set -euo pipefail
cd "$(dirname "$0")/.."

build=1
bench=0
for arg in "$@"; do
  case "$arg" in
    --no-build) build=0 ;;
    --bench) bench=1 ;;
    *) echo "setup.sh: unknown option '$arg' (valid: --no-build, --bench)" >&2; exit 2 ;;
  esac
done

packages=(
  g++ cmake make pkg-config
  libeigen3-dev libcli11-dev nlohmann-json3-dev libassimp-dev libhdf5-dev
  libgtest-dev
  # h5dump: a test checks that the HDF5 output reads back with the HDF5 tools.
  hdf5-tools
  # Headless OpenGL: EGL loader and headers, Mesa's EGL and llvmpipe driver.
  libegl1 libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
)
if [ "$bench" = 1 ]; then
  packages+=(libfcl-dev gnuplot-nox jq)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ "${#missing[@]}" -gt 0 ]; then
  echo "setup.sh: installing ${missing[*]}"
  if [ "$(id -u)" = 0 ]; then
    sudo=()
  elif command -v sudo >/dev/null 2>&1; then
    sudo=(sudo)
  else
    echo "setup.sh: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  if ! "${sudo[@]}" apt-get install -y --no-install-recommends "${missing[@]}"; then
    "${sudo[@]}" apt-get update
    "${sudo[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
  fi
fi

if [ "$build" = 1 ]; then
  jobs=$(nproc 2>/dev/null || echo 2)
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
  cmake --build build -j"$jobs"
fi
