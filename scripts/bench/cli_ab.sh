#!/bin/bash
# A/B of the command-line tool on one input, whole process: alternates two or more builds of
# meshdenoise, one run each per round (`meshdenoise --params PARAMS --report IN out.glb` under
# /usr/bin/time), and writes per run "TAG TIME wall user system peak_KiB" and "TAG STAGES
# name=ms ..." (the report's stage times, from its "timings_ms"). scripts/bench/ab_sum.py OUT
# takes the medians of the TIME lines.
#
# Usage: scripts/bench/cli_ab.sh ROUNDS PARAMS IN OUT BIN1 BIN2 ...
#   e.g. scripts/bench/cli_ab.sh 3 '{}' bunny_1m2_noisy.glb cli.txt ../before/build/release/cli/meshdenoise \
#          build/release/cli/meshdenoise
set -euo pipefail
. "$(dirname "$0")/ab_lib.sh"
ab_need_args 5 "$@"
rounds=$1 params=$2 in=$3 out=$4
shift 4
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
run_one() {  # BIN TAG
  /usr/bin/time -o "$work/time" -f "%e %U %S %M" "$1" --params "$params" --report "$in" "$work/out.glb" \
    > "$work/report.json" 2> "$work/stderr" || { cat "$work/stderr" >&2; exit 1; }
  echo "$2 TIME $(cat "$work/time")" >> "$out"
  python3 - "$work/report.json" "$2" >> "$out" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
timings = {}
def find(node):
    if isinstance(node, dict):
        for k, v in node.items():
            if k == "timings_ms" and isinstance(v, dict):
                for name, ms in v.items():
                    if isinstance(ms, (int, float)):
                        timings[name] = timings.get(name, 0) + ms
            else:
                find(v)
    elif isinstance(node, list):
        for v in node:
            find(v)
find(report)
print(sys.argv[2], "STAGES", " ".join("%s=%.1f" % kv for kv in timings.items()))
PY
}
ab_alternate "$rounds" "$out" run_one "$@"
