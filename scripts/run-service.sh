#!/usr/bin/env bash
# Installs what is needed, builds in Release and runs meshdenoise-server on 127.0.0.1:8080.
# Extra arguments go to the server (e.g. --host 0.0.0.0 --port 9000); see --help. Nothing is
# forced: the I/O threads, workers and limits take their defaults, sized to this machine.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bash "$root/scripts/install-deps.sh" build
cmake --preset release -S "$root" -DMDN_BUILD_TESTS=OFF -DMDN_BUILD_BENCH=OFF >/dev/null
cmake --build "$root/build/release" -j"$(nproc)" --target meshdenoise-server meshdenoise
exec "$root/build/release/server/meshdenoise-server" "$@"
