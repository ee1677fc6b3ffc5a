#!/usr/bin/env bash
# The benchmark report, in one command: the paper's five benchmarks (skirt, cloth-ball, bowl,
# funnel, breaking; section 6.2) generated with vproxq-gen, every query run on each with
# --voronoi=off, cpu and gpu, FCL on the inter-object distance, a grid sweep (figure 14), and
# the aggregate: a Markdown table like the paper's Table 1, CSVs of every number, and PNG
# plots of figures 13 and 14 drawn by gnuplot (no display needed).
#
#   bash scripts/report.sh                          # everything, defaults below
#   QUERIES=distance MODES="off cpu" bash scripts/report.sh
#   SCENES=bowl FRAMES=5 GRIDS="32 64" bash scripts/report.sh   # a quick look
#
# Steps: installs libfcl-dev and gnuplot-nox if missing (scripts/setup.sh --bench, as root or
# through sudo); configures a Release build with the benchmark tools into build-bench/;
# generates the scenes into bench-out/scenes/<scene>/ (kept while the generator and its
# arguments are unchanged); runs into bench-out/report/runs/<scene>/<run>/; aggregates into
# bench-out/report/: report.md, results.csv (per frame), summary.csv (per run), fig13.png,
# fig14.png (and the .dat/.gp files behind them), machine.txt.
#
# A run that fails (e.g. --voronoi=gpu without EGL/OpenGL 4.3) is recorded as n/a with its
# error message; the report still comes out. Queries this vproxq does not implement yet are
# left out, and the report says which ran.
#
# Environment (defaults):
#   QUERIES      distance,ccd,pd     queries for vproxq --queries
#   MODES        "off cpu gpu"       Stage II modes
#   SCENES       "skirt cloth-ball bowl funnel breaking"
#   FRAMES       (generator default, 40)   frames to generate per scene
#   SEED         1                   generator seed
#   RANGE        (all)               vproxq/FCL --frames A:B for the mode and FCL runs
#   THREADS      2                   vproxq --threads, FCL threads
#   FCL          1                   0: skip FCL
#   REPEAT       1                   FCL bench: runs per frame, fastest kept
#   PNS          1                   0: skip vproxq-bench-pns (exact tests against their floor
#                                    and the paper's fixed-bound PNS, same frames as RANGE)
#   GRID_SCENES  "funnel skirt"      scenes of the grid sweep (the paper's figure 14 used its
#                                    200-object scene; skirt's exact tests fall with the grid,
#                                    funnel's stay near their floor); "" skips the sweep
#   GRIDS        "32 48 64 96 128 192 256 384 512"  --grid values of the sweep (--voronoi=GRID_MODE)
#   GRID_RANGE   (all)               --frames A:B of the sweep runs
#   OUT          bench-out/report    report folder (its runs/ is replaced)
#   JOBS         2                   build jobs
#   BIN_DIR      (build-bench)       a folder with prebuilt vproxq, vproxq-gen, vproxq-bench-fcl,
#                                    vproxq-bench-pns and vproxq-report: skips the setup and the
#                                    build (a machine without the packages or the compiler)
#   GRID_MODE    cpu                 the Stage II backend of the grid sweep (cpu or gpu)
set -euo pipefail
cd "$(dirname "$0")/.."

queries=${QUERIES:-distance,ccd,pd}
modes=${MODES:-off cpu gpu}
scenes=${SCENES:-skirt cloth-ball bowl funnel breaking}
frames=${FRAMES:-}
seed=${SEED:-1}
range=${RANGE:-}
threads=${THREADS:-2}
fcl=${FCL:-1}
pns=${PNS:-1}
repeat=${REPEAT:-1}
grid_scenes=${GRID_SCENES-funnel skirt}
grids=${GRIDS:-32 48 64 96 128 192 256 384 512}
grid_range=${GRID_RANGE:-}
out=${OUT:-bench-out/report}
jobs=${JOBS:-2}
bin_dir=${BIN_DIR:-}
# shellcheck source=prebuilt.sh
source scripts/prebuilt.sh
grid_mode=${GRID_MODE:-cpu}

if [ -n "$bin_dir" ]; then
  gen=$bin_dir/vproxq-gen
  vproxq=$bin_dir/vproxq
  fcl_bench=$bin_dir/vproxq-bench-fcl
  pns_bench=$bin_dir/vproxq-bench-pns
  report=$bin_dir/vproxq-report
  prebuilt_tools report.sh "$bin_dir" vproxq-gen vproxq vproxq-bench-fcl vproxq-bench-pns vproxq-report
else
  bash scripts/setup.sh --bench --no-build

  cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DVPROXQ_BUILD_BENCH=ON \
    -DVPROXQ_BUILD_TESTS=OFF
  cmake --build build-bench --target vproxq vproxq-gen vproxq-bench-fcl vproxq-bench-pns \
    vproxq-report -j"$jobs"

  gen=build-bench/sample_scenes/vproxq-gen
  vproxq=build-bench/app/vproxq
  fcl_bench=build-bench/bench/vproxq-bench-fcl
  pns_bench=build-bench/bench/vproxq-bench-pns
  report=build-bench/bench/report/vproxq-report
fi

# The requested queries that this vproxq implements (it says "not implemented" otherwise).
ran_queries=()
skipped_queries=()
for q in ${queries//,/ }; do
  if "$vproxq" sample_scenes/two-cubes/scene.json --queries="$q" --frames 0 -q >/dev/null 2>&1; then
    ran_queries+=("$q")
  else
    skipped_queries+=("$q")
  fi
done
if [ "${#ran_queries[@]}" -eq 0 ]; then
  echo "report.sh: none of the queries '$queries' runs with this vproxq" >&2
  exit 2
fi
query_list=$(IFS=,; echo "${ran_queries[*]}")
skipped_note=""
if [ "${#skipped_queries[@]}" -gt 0 ]; then
  skipped_note=" (not implemented in this vproxq, left out: ${skipped_queries[*]})"
  echo "report.sh: note: queries$skipped_note"
fi

rm -rf "$out/runs"
mkdir -p "$out/runs" bench-out/scenes

# Runs one vproxq configuration into DIR; on failure records the reason in DIR/error.txt.
run_vproxq() {
  local dir=$1
  shift
  mkdir -p "$dir"
  echo "  vproxq $*"
  local status=0
  "$vproxq" "$@" -q -o "$dir" >"$dir/log.txt" 2>&1 || status=$?
  if [ "$status" -ne 0 ]; then
    echo "vproxq failed (exit status $status): $(tail -n 3 "$dir/log.txt" | tr '\n' ' ')" \
      >"$dir/error.txt"
    echo "    n/a: $(cat "$dir/error.txt")"
  fi
}

for scene in $scenes; do
  dir=bench-out/scenes/$scene
  args=("$scene" --seed "$seed")
  if [ -n "$frames" ]; then args+=(--frames "$frames"); fi
  # Regenerate unless the same generator binary already wrote this scene with these arguments.
  if [ -f "$dir/scene.json" ] && [ -f "$dir/command.txt" ] &&
    [ "$(cat "$dir/command.txt")" = "${args[*]}" ] && [ "$dir/scene.json" -nt "$gen" ]; then
    echo "== $scene: using $dir (generated earlier with: vproxq-gen ${args[*]})"
  else
    echo "== $scene: generating into $dir"
    rm -rf "$dir"
    "$gen" "${args[@]}" --out "$dir" | tail -n 2
    echo "${args[*]}" >"$dir/command.txt"
  fi

  for mode in $modes; do
    run_vproxq "$out/runs/$scene/$mode" "$dir/scene.json" --voronoi="$mode" \
      --threads "$threads" --queries="$query_list" ${range:+--frames "$range"}
  done

  if [ "$fcl" = 1 ]; then
    echo "  vproxq-bench-fcl (inter-object distance)"
    mkdir -p "$out/runs/$scene"
    status=0
    "$fcl_bench" "$dir/scene.json" --threads "$threads" --repeat "$repeat" \
      ${range:+--frames "$range"} --json "$out/runs/$scene/fcl.json" \
      >"$out/runs/$scene/fcl.txt" 2>&1 || status=$?
    if [ "$status" -ne 0 ]; then
      if [ ! -f "$out/runs/$scene/fcl.json" ]; then
        echo "vproxq-bench-fcl failed (exit status $status): $(tail -n 3 "$out/runs/$scene/fcl.txt" | tr '\n' ' ')" \
          >"$out/runs/$scene/fcl-error.txt"
        echo "    n/a: $(cat "$out/runs/$scene/fcl-error.txt")"
      else
        echo "    FCL and vproxq disagree on some distances: see $out/runs/$scene/fcl.txt"
      fi
    fi
  fi

  if [ "$pns" = 1 ]; then
    echo "  vproxq-bench-pns (exact tests, floors, fixed-bound PNS)"
    mkdir -p "$out/runs/$scene"
    "$pns_bench" "$dir/scene.json" --threads "$threads" ${range:+--frames "$range"} \
      --json "$out/runs/$scene/pns.json" >"$out/runs/$scene/pns.txt" 2>&1 ||
      echo "    vproxq-bench-pns failed: $(tail -n 2 "$out/runs/$scene/pns.txt" | tr '\n' ' ')"
  fi

  for g in $grids; do
    case " $grid_scenes " in
      *" $scene "*)
        run_vproxq "$out/runs/$scene/grid-$g" "$dir/scene.json" --voronoi="$grid_mode" --grid "$g" \
          --threads "$threads" --queries="$query_list" ${grid_range:+--frames "$grid_range"}
        ;;
    esac
  done
done

# The machine the numbers come from.
{
  echo "date:      $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "commit:    $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet 2>/dev/null || echo ' (with local changes)')"
  echo "system:    $(uname -srm)"
  echo "cpu:       $(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ *//')"
  echo "cores:     $(nproc 2>/dev/null || echo ?)"
  echo "memory:    $(awk '/MemTotal/ {printf "%.1f GiB", $2 / 1048576}' /proc/meminfo 2>/dev/null)"
  if command -v nvidia-smi >/dev/null 2>&1; then
    echo "gpu:       $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | head -n 1)"
  fi
  echo "settings:  threads $threads; queries $query_list$skipped_note; modes $modes; FCL repeat $repeat"
  echo "load:      $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null) (1, 5, 15 min averages when the runs ended)"
} >"$out/machine.txt"

"$report" --runs "$out/runs" --out "$out" --machine "$out/machine.txt"
if command -v gnuplot >/dev/null 2>&1; then
  (cd "$out" && gnuplot fig13.gp && gnuplot fig14.gp)
else
  echo "report.sh: note: no gnuplot here, fig13.png and fig14.png not drawn (their .gp files are in $out)"
fi
echo
sed -n '/^## Table 1/,/^## Stages/p' "$out/report.md" | sed '$d'
echo "report.sh: wrote $out/report.md, results.csv, summary.csv, fig13.png, fig14.png"
