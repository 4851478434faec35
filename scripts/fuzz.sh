#!/usr/bin/env bash
# Builds the libFuzzer harnesses (preset "fuzz": clang, ASan + UBSan), generates their seed
# corpora and runs each one (smoke and campaign: as many at a time as there are cores); exits
# non-zero if a harness has a finding (crash, sanitizer report, leak, timeout, out of memory),
# whose reproducer is left in build/fuzz/findings/.
#
#   scripts/fuzz.sh smoke [SECONDS]      # each harness SECONDS (default 12), what run-tests.sh runs
#   scripts/fuzz.sh campaign [SECONDS]   # each harness SECONDS (default 7200) or 10M runs, corpora kept
#   scripts/fuzz.sh campaign 600 ply drc # only these harnesses
#   scripts/fuzz.sh long SECONDS [H...]  # each harness SECONDS, however many runs, one after the
#                                        # other, on its persistent corpus; then minimised into
#                                        # tests/fuzz/corpus/<harness> (commit what it changed)
#
# Corpora grow in build/fuzz/corpus/<harness> (seeds from fuzz_seeds in build/fuzz/seeds/, and
# the committed minimised corpus tests/fuzz/corpus/<harness>); each harness prints libFuzzer's
# final line (executions, cov, ft) to build/fuzz/logs/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
mode="${1:-smoke}"
case "$mode" in
  smoke) seconds="${2:-12}"; runs=0 ;;
  campaign) seconds="${2:-7200}"; runs=10000000 ;;
  long) seconds="${2:?long needs SECONDS}"; runs=0 ;;
  *) echo "usage: $0 smoke|campaign|long [SECONDS] [HARNESS...]" >&2; exit 2 ;;
esac
shift $(( $# > 1 ? 2 : $# ))
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(off obj ply drc glb gltf stl params job http_framing)

build="$root/build/fuzz"
cmake --preset fuzz -S "$root" >/dev/null
targets=(fuzz_seeds)
for h in "${harnesses[@]}"; do targets+=("fuzz_$h"); done
cmake --build "$build" -j"$(nproc)" --target "${targets[@]}"
rm -rf "$build/seeds"
"$build/tests/fuzz/fuzz_seeds" "$build/seeds"
mkdir -p "$build/findings" "$build/logs"

# One harness: its run, and in long mode the minimisation; non-zero on a finding.
run_harness() {
  local h="$1" dict corpus committed inputs log timeout
  dict="$root/tests/fuzz/dict/$h.dict"
  [ "$h" = glb ] && dict="$root/tests/fuzz/dict/gltf.dict"
  if [ "$h" = job ]; then  # parameters, then a mesh: the two dictionaries in one
    dict="$build/job.dict"
    cat "$root/tests/fuzz/dict/params.dict" "$root/tests/fuzz/dict/off.dict" "$root/tests/fuzz/dict/gltf.dict" >"$dict"
  fi
  corpus="$build/corpus/$h"
  committed="$root/tests/fuzz/corpus/$h"
  mkdir -p "$corpus"
  inputs=("$corpus" "$build/seeds/$h")
  [ -d "$committed" ] && inputs+=("$committed")
  # Reproducers of past findings, each kept whatever the minimisation keeps.
  [ -d "$root/tests/fuzz/regressions/$h" ] && inputs+=("$root/tests/fuzz/regressions/$h")
  log="$build/logs/$h.log"
  # fuzz_job denoises every input: "mode": "search" takes about 80 ms on a 20-face mesh in the
  # Release build and 16-18 s under ASan + UBSan at -O1 (found by the long run of 2026-12-05),
  # so its inputs get 60 s; the decoders' 10 s.
  timeout=10
  [ "$h" = job ] && timeout=60
  # -rss_limit_mb / -malloc_limit_mb: the harnesses decode with 64 MB of decoded bytes allowed;
  # a run past 1 GB means a limit was not enforced. -timeout: one input may take $timeout s at most.
  if "$build/tests/fuzz/fuzz_$h" "${inputs[@]}" -dict="$dict" -max_total_time="$seconds" \
       -runs="$([ "$runs" -gt 0 ] && echo "$runs" || echo -1)" -timeout="$timeout" -rss_limit_mb=1024 -malloc_limit_mb=1024 \
       -max_len=262144 -print_final_stats=1 -artifact_prefix="$build/findings/$h-" >"$log" 2>&1; then
    echo "fuzz_$h: $(grep -E '^#[0-9]+.*(DONE|cov:)' "$log" | tail -1)"
    if [ "$mode" = long ]; then
      # The committed corpus: a small set of inputs that keeps every feature found (set cover).
      rm -rf "$build/minimised/$h" && mkdir -p "$build/minimised/$h"
      "$build/tests/fuzz/fuzz_$h" -set_cover_merge=1 "$build/minimised/$h" "${inputs[@]}" -timeout="$timeout" -rss_limit_mb=1024 \
        -malloc_limit_mb=1024 -max_len=262144 >"$build/logs/$h-merge.log" 2>&1
      rm -rf "$committed" && mkdir -p "$committed" && cp "$build/minimised/$h"/* "$committed"/ 2>/dev/null || true
      echo "fuzz_$h: corpus $(ls "$committed" | wc -l) files, $(du -sk "$committed" | cut -f1) KiB in tests/fuzz/corpus/$h"
    fi
  else
    echo "fuzz_$h: FINDING (see $log and $build/findings/$h-*)" >&2
    grep -E "ERROR|FINDING|SUMMARY|==[0-9]+==" "$log" | head -20 >&2 || true
    return 1
  fi
}

# smoke and campaign run nproc harnesses at a time (each is one process), long one after the
# other; each harness's status goes to a file, so none is lost to the order they end in.
slots="$(nproc)"
[ "$mode" = long ] && slots=1
rm -f "$build"/logs/*.rc
for h in "${harnesses[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$slots" ]; do wait -n || true; done
  { rc=0; run_harness "$h" || rc=$?; echo "$rc" >"$build/logs/$h.rc"; } &
done
wait
failed=0
for h in "${harnesses[@]}"; do
  [ "$(cat "$build/logs/$h.rc" 2>/dev/null)" = 0 ] || failed=1
done
exit "$failed"
