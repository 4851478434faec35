# Sourced by ab.sh and cli_ab.sh: what the two A/B scripts share.

# Prints the calling script's header comment (its usage) and exits 2 when fewer than $1
# arguments follow.
ab_need_args() {
  local need=$1
  shift
  if [ $# -lt "$need" ]; then
    sed -n '2,/^[^#]/p' "$0" | grep '^#' | sed 's/^# \{0,1\}//' >&2
    exit 2
  fi
}

# A binary's tag: the folder that holds the build/release/ it was built in (so two worktrees
# compare as their names), else the binary's own folder.
ab_tag() {
  local dir
  dir="$(cd "$(dirname "$1")" && pwd)"
  case "$dir" in
    */build/release/*) dir="${dir%%/build/release/*}"; basename "$dir" ;;
    *) basename "$dir" ;;
  esac
}

# Appends "TAG LOAD 1m 5m 15m" to file $2 for tag $1.
ab_load() {
  echo "$1 LOAD $(cut -d' ' -f1-3 /proc/loadavg)" >> "$2"
}

# The rounds: for each of $1 rounds, for each binary after $3, appends its load line to file $2
# and calls the function named $3 with the binary and its tag.
ab_alternate() {
  local rounds=$1 out=$2 run_one=$3 bin tag
  shift 3
  : > "$out"
  for _ in $(seq "$rounds"); do
    for bin in "$@"; do
      tag="$(ab_tag "$bin")"
      ab_load "$tag" "$out"
      "$run_one" "$bin" "$tag"
    done
  done
}
