#!/usr/bin/env bash
# The web page's drawing time after a result arrives, median of 5, at 75k and 356k faces: CGAL's
# bunny00 (a range scan, 75,408 faces) and refined_elephant subdivided once by
# tests/bench/subdivide.h's rule (355,712 faces), each with noise of 0.3 mean edge lengths added
# by `meshdenoise --add-noise`, denoised by meshdenoise-server on loopback (auto strength) and
# drawn by the page in headless Chromium (tests/tools/bench_web_draw.mjs). A benchmark: it prints
# figures and asserts nothing.
#   bash scripts/bench-web-draw.sh [BUILD_DIR] [RUNS]   (default build/release, 5; needs the
#        targets meshdenoise, meshdenoise-server and subdivide_mesh (MDN_BUILD_BENCH=ON), and
#        `scripts/install-deps.sh build test`)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build/release}" && pwd)"
runs="${2:-5}"
work="$(mktemp -d)"
server_pid=""
cleanup() { [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT

meshes="$(bash "$root/scripts/fetch-cgal-data.sh" "$root/third_party_data/cgal")"
"$build/tests/bench/subdivide_mesh" "$meshes/refined_elephant.off" "$work/elephant-356k.off" 1 >/dev/null
noise='{"kind":"along_normal","sigma":0.3,"seed":1}'
"$build/cli/meshdenoise" --add-noise "$noise" "$meshes/bunny00.off" "$work/bunny-75k.off"
"$build/cli/meshdenoise" --add-noise "$noise" "$work/elephant-356k.off" "$work/elephant-356k-noisy.off"

"$build/server/meshdenoise-server" --host 127.0.0.1 --port 0 --port-file "$work/port" --workers 1 \
  >"$work/server.log" 2>&1 &
server_pid=$!
for _ in $(seq 100); do [ -s "$work/port" ] && break; sleep 0.1; done
[ -s "$work/port" ] || { cat "$work/server.log" >&2; exit 1; }

echo "commit $(git -C "$root" rev-parse --short HEAD)$(git -C "$root" diff --quiet || echo '+changes'), $(nproc) cores"
(cd "$root/tests/tools" && node bench_web_draw.mjs "http://127.0.0.1:$(cat "$work/port")/" "$runs" \
  "$work/bunny-75k.off" "$work/elephant-356k-noisy.off")
