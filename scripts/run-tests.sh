#!/usr/bin/env bash
# Installs what is needed, builds everything (Release) and runs every test with ctest.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/install-deps.sh" build test
cmake --preset release -S "$root" -DMDN_BUILD_TESTS=ON -DMDN_BUILD_BENCH=ON >/dev/null
cmake --build "$root/build/release" -j"$(nproc)"
cd "$root/build/release"
ctest --output-on-failure -j"$(nproc)" --timeout 600 "$@"
