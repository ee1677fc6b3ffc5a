#!/usr/bin/env bash
# Intra-object (self) distance benchmark: one mesh as one object, per-triangle nearest
# non-adjacent triangle, with --voronoi=off|cpu|gpu and several grid resolutions. Runs the
# built CLI (build/app/vproxq) and prints, per run, the intra-object times from the frame's
# stats (2-ring bounds + self Stage II; Stage III), the exact tests and the reduction against
# --voronoi=off, the median of REPEAT runs. Not a test: numbers depend on the machine.
#
#   bash scripts/bench_self.sh                                  # cloth-funnel frame 227
#   MESH=path.ply GRIDS="0 128 256" BACKENDS="off cpu" bash scripts/bench_self.sh
#
# Environment: MESH (tests/data/frames/cloth-funnel/frames/227.ply), THREADS (2), REPEAT (3),
# GRIDS ("0 96 128 192 256 384"; 0 = the default self grid), BACKENDS ("off cpu gpu"),
# VPROXQ (build/app/vproxq). Needs jq (scripts/setup.sh --bench installs it).
set -euo pipefail
cd "$(dirname "$0")/.."

mesh=${MESH:-tests/data/frames/cloth-funnel/frames/227.ply}
threads=${THREADS:-2}
repeat=${REPEAT:-3}
grids=${GRIDS:-0 96 128 192 256 384}
backends=${BACKENDS:-off cpu gpu}
vproxq=${VPROXQ:-build/app/vproxq}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# One run: prints "intra_bounds_ms + intra_voronoi_ms, intra_exact_ms intra_exact_tests grid_x samples".
run_once() {
  local backend=$1 grid=$2
  local args=(--queries distance --voronoi="$backend" --threads "$threads" --quiet -o "$out/r")
  [ "$grid" != 0 ] && args+=(--grid "$grid")
  "$vproxq" "$mesh" "${args[@]}"
  jq -r '.frames[0] | [.stats.time_ms.intra_bounds + .stats.time_ms.intra_voronoi, .stats.time_ms.intra_exact,
          .stats.intra_exact_tests, (.stats.self_voronoi.grid[0] // 0),
          (.stats.self_voronoi.samples // 0)] | @tsv' "$out/r/results.json"
}

median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

printf '%-7s %6s %9s %10s %10s %10s %12s %9s\n' backend grid samples "2ring+II" "III" total \
  exact_tests "vs off"
off_tests=
for backend in $backends; do
  for grid in $grids; do
    [ "$backend" = off ] && [ "$grid" != 0 ] && continue
    rows=()
    for ((k = 0; k < repeat; ++k)); do rows+=("$(run_once "$backend" "$grid")"); done
    v=$(printf '%s\n' "${rows[@]}" | cut -f1 | median)
    e=$(printf '%s\n' "${rows[@]}" | cut -f2 | median)
    t=$(printf '%s\n' "${rows[@]}" | awk -F'\t' '{print $1 + $2}' | median)
    tests=$(printf '%s\n' "${rows[@]}" | head -1 | cut -f3)
    gx=$(printf '%s\n' "${rows[@]}" | head -1 | cut -f4)
    samples=$(printf '%s\n' "${rows[@]}" | head -1 | cut -f5)
    [ "$backend" = off ] && off_tests=$tests
    ratio=-
    [ -n "$off_tests" ] && ratio=$(awk -v a="$off_tests" -v b="$tests" 'BEGIN {printf "%.1fx", a / b}')
    printf '%-7s %6s %9s %10.1f %10.1f %10.1f %12s %9s\n' "$backend" "$gx" "$samples" "$v" "$e" \
      "$t" "$tests" "$ratio"
  done
done
