#!/usr/bin/env bash
# Builds the libFuzzer harnesses (preset "fuzz": clang, ASan + UBSan), generates their seed
# corpora and runs each one; exits non-zero on the first harness with a finding (crash,
# sanitizer report, leak, timeout, out of memory), whose reproducer is left in build/fuzz/findings/.
#
#   scripts/fuzz.sh smoke [SECONDS]      # each harness SECONDS (default 12), what run-tests.sh runs
#   scripts/fuzz.sh campaign [SECONDS]   # each harness SECONDS (default 7200) or 10M runs, corpora kept
#   scripts/fuzz.sh campaign 600 ply drc # only these harnesses
#
# Corpora grow in build/fuzz/corpus/<harness> (seeds from fuzz_seeds in build/fuzz/seeds/);
# each harness prints libFuzzer's final line (executions, cov, ft) to build/fuzz/logs/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
mode="${1:-smoke}"
case "$mode" in
  smoke) seconds="${2:-12}"; runs=0 ;;
  campaign) seconds="${2:-7200}"; runs=10000000 ;;
  *) echo "usage: $0 smoke|campaign [SECONDS] [HARNESS...]" >&2; exit 2 ;;
esac
shift $(( $# > 1 ? 2 : $# ))
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(off obj ply drc glb gltf stl params)

build="$root/build/fuzz"
cmake --preset fuzz -S "$root" >/dev/null
cmake --build "$build" -j"$(nproc)" --target fuzzers
rm -rf "$build/seeds"
"$build/tests/fuzz/fuzz_seeds" "$build/seeds"
mkdir -p "$build/findings" "$build/logs"

failed=0
for h in "${harnesses[@]}"; do
  dict="$root/tests/fuzz/dict/$h.dict"
  [ "$h" = glb ] && dict="$root/tests/fuzz/dict/gltf.dict"
  corpus="$build/corpus/$h"
  mkdir -p "$corpus"
  log="$build/logs/$h.log"
  # -rss_limit_mb / -malloc_limit_mb: the harnesses decode with 64 MB of decoded bytes allowed;
  # a run past 1 GB means a limit was not enforced. -timeout: one input may take 10 s at most.
  if "$build/tests/fuzz/fuzz_$h" "$corpus" "$build/seeds/$h" -dict="$dict" -max_total_time="$seconds" \
       -runs="$([ "$runs" -gt 0 ] && echo "$runs" || echo -1)" -timeout=10 -rss_limit_mb=1024 -malloc_limit_mb=1024 \
       -max_len=262144 -print_final_stats=1 -artifact_prefix="$build/findings/$h-" >"$log" 2>&1; then
    echo "fuzz_$h: $(grep -E '^#[0-9]+.*(DONE|cov:)' "$log" | tail -1)"
  else
    echo "fuzz_$h: FINDING (see $log and $build/findings/$h-*)" >&2
    grep -E "ERROR|FINDING|SUMMARY|==[0-9]+==" "$log" | head -20 >&2 || true
    failed=1
  fi
done
exit "$failed"
