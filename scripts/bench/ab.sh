#!/bin/bash
# A/B of tests/bench/scale_bench: alternates two or more builds of it, one run each per round,
# so that each binary draws the machine's load alike (the speed rounds' "ab.sh", docs/experiments/
# 2026-12-04-scan-scale-speed-rounds.md). Each row of scale_bench is kept, prefixed with the
# binary's tag (ab_lib.sh: the folder that holds its build/release/), with the load average
# before the run ("TAG LOAD 1m 5m 15m") and the run's CPU and wall ("TAG TIME user system wall",
# from /usr/bin/time). scripts/bench/ab_sum.py OUT takes the medians.
#
# Usage: scripts/bench/ab.sh ROUNDS MESHES PARAMS OUT BIN1 BIN2 ...
#   e.g. scripts/bench/ab.sh 3 fandisk:0,bunny00:2 paper,heavy,auto ab.txt \
#          ../before/build/release/tests/bench/scale_bench build/release/tests/bench/scale_bench
# Environment: THR threads (default 2); DATA the CGAL data folder scale_bench --data takes
# (default third_party_data/cgal, from scripts/fetch-cgal-data.sh).
set -euo pipefail
. "$(dirname "$0")/ab_lib.sh"
ab_need_args 5 "$@"
rounds=$1 meshes=$2 params=$3 out=$4
shift 4
data="${DATA:-third_party_data/cgal}"
one="$(mktemp)"
trap 'rm -f "$one"' EXIT
run_one() {  # BIN TAG
  /usr/bin/time -f "TIME %U %S %e" "$1" --data "$data" --meshes "$meshes" --params "$params" --runs 1 \
    --threads "${THR:-2}" > "$one" 2>&1 || { cat "$one" >&2; exit 1; }
  grep -E "^(fandisk|bunny)" "$one" | sed "s/^/$2 /" >> "$out"
  grep "^TIME" "$one" | sed "s/^/$2 /" >> "$out"
}
ab_alternate "$rounds" "$out" run_one "$@"
