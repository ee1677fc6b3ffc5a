#!/usr/bin/env bash
# vproxq against FCL on the paper's "200 objects through a funnel" scene, in one command:
# installs libfcl-dev if missing (as root or through sudo), configures a Release build with
# the benchmark into build-bench/, builds it, generates the scene into bench-out/, and runs
# the benchmark, printing the per-frame table (also saved as bench-out/blobs-200/fcl-bench.txt):
# vproxq's inter-object distance with each Stage II backend (off, cpu, gpu) and FCL's, side by
# side, on the same frames (gpu: Mesa's llvmpipe on a machine without a GPU; left out with a
# note where no EGL context can be made).
#
#   bash scripts/bench.sh                      # 200 blobs x 180 triangles, 5 frames, 2 threads
#   THREADS=4 REPEAT=5 bash scripts/bench.sh   # environment overrides (see below)
#   bash scripts/bench.sh --fcl-threads 1      # extra options go to vproxq-bench-fcl
#   bash scripts/bench.sh --repeat 1 --voronoi off   # and win over THREADS, REPEAT, VORONOI
#
# Environment: THREADS (2), REPEAT (3), OBJECTS (200), FREQUENCY (3: 180 triangles per blob),
# FRAMES (5), SEED (1), VORONOI (off,cpu,gpu: the backends to time), JOBS (build jobs, default:
# nproc), BIN_DIR (a folder with prebuilt vproxq-gen and vproxq-bench-fcl: skips the setup and
# the build, e.g. on a GPU machine without the packages). The other build dependencies come
# from scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

threads=${THREADS:-2}
repeat=${REPEAT:-3}
objects=${OBJECTS:-200}
frequency=${FREQUENCY:-3}
frames=${FRAMES:-5}
seed=${SEED:-1}
voronoi=${VORONOI:-off,cpu,gpu}
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}

bin_dir=${BIN_DIR:-}
# shellcheck source=prebuilt.sh
source scripts/prebuilt.sh

if [ -n "$bin_dir" ]; then
  gen=$bin_dir/vproxq-gen
  fcl_bench=$bin_dir/vproxq-bench-fcl
  prebuilt_tools bench.sh "$bin_dir" vproxq-gen vproxq-bench-fcl
else
  # FCL and the other Debian packages: the setup script installs what is missing.
  bash scripts/setup.sh --bench --no-build

  cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DVPROXQ_BUILD_BENCH=ON \
    -DVPROXQ_BUILD_TESTS=OFF
  cmake --build build-bench --target vproxq-gen vproxq-bench-fcl -j"$jobs"
  gen=build-bench/sample_scenes/vproxq-gen
  fcl_bench=build-bench/bench/vproxq-bench-fcl
fi

scene_dir=bench-out/blobs-$objects
"$gen" blobs --objects "$objects" --frequency "$frequency" \
  --frames "$frames" --seed "$seed" --out "$scene_dir"

# THREADS, REPEAT and VORONOI give --threads, --repeat and --voronoi unless the command line
# does (vproxq-bench-fcl takes each once).
given() {
  local arg
  for arg in "${@:2}"; do
    case $arg in "$1" | "$1"=*) return 0 ;; esac
  done
  return 1
}
defaults=()
given --threads "$@" || defaults+=(--threads "$threads")
given --repeat "$@" || defaults+=(--repeat "$repeat")
given --voronoi "$@" || defaults+=(--voronoi "$voronoi")

echo
"$fcl_bench" "$scene_dir/scene.json" "${defaults[@]}" "$@" | tee "$scene_dir/fcl-bench.txt"
