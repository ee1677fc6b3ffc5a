# Sourced by bench.sh and report.sh: prebuilt_tools SCRIPT DIR TOOL... checks that DIR (the
# BIN_DIR of the scripts) holds each TOOL as an executable, else names the missing one and
# exits with status 2.
prebuilt_tools() {
  local script=$1 dir=$2
  shift 2
  local tool
  for tool in "$@"; do
    if [ ! -x "$dir/$tool" ]; then
      echo "$script: BIN_DIR=$dir has no executable $tool" >&2
      exit 2
    fi
  done
}
