#!/usr/bin/env bash
# Installs what is needed, builds everything (Release) and runs every test with ctest, then
# every libFuzzer harness for a bounded time (tests/fuzz; a clang build of the io library).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/install-deps.sh" build test
cmake --preset release -S "$root" -DMDN_BUILD_TESTS=ON -DMDN_BUILD_BENCH=ON >/dev/null
cmake --build "$root/build/release" -j"$(nproc)"
cd "$root/build/release"
ctest --output-on-failure --no-tests=error -j"$(nproc)" --timeout 600 "$@"
# Fails on any finding; MDN_FUZZ_SECONDS per harness (7 harnesses).
bash "$root/scripts/fuzz.sh" smoke "${MDN_FUZZ_SECONDS:-12}"
