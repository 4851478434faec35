#!/usr/bin/env bash
# Makes the web page's pictures in docs/ from a real run: a real scan (the Stanford bunny,
# bunny00.off of Debian's libcgal-demo data, fetched by scripts/fetch-cgal-data.sh, never
# committed) with synthetic noise added by `meshdenoise --add-noise`, denoised by meshdenoise-server on loopback and shown by the
# page in headless Chromium (tests/tools/screenshot_web_page.mjs).
#
#   bash scripts/web-screenshots.sh [BUILD_DIR]     (default build/release; needs the build and
#                                                    `scripts/install-deps.sh build test`)
# Writes docs/web-page.png (1280x800, side by side), docs/web-displacement.png (the heat map,
# a picked vertex) and docs/web-narrow.png (400x800).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build/release}" && pwd)"
work="$(mktemp -d)"
server_pid=""
cleanup() { [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT

meshes="$(bash "$root/scripts/fetch-cgal-data.sh" "$root/third_party_data")"
# sigma 0.3 mean edge lengths along the normals: clearly visible noise, as in the paper's figures.
"$build/cli/meshdenoise" --add-noise '{"kind":"along_normal","sigma":0.3,"seed":1}' \
  "$meshes/bunny00.off" "$work/bunny-noisy.off"

"$build/server/meshdenoise-server" --host 127.0.0.1 --port 0 --port-file "$work/port" --workers 1 \
  >"$work/server.log" 2>&1 &
server_pid=$!
for _ in $(seq 100); do [ -s "$work/port" ] && break; sleep 0.1; done
[ -s "$work/port" ] || { cat "$work/server.log" >&2; exit 1; }

(cd "$root/tests/tools" && node screenshot_web_page.mjs "http://127.0.0.1:$(cat "$work/port")/" \
  "$work/bunny-noisy.off" "$root/docs")
