#!/usr/bin/env bash
# Denoises a mesh with meshdenoise-server using curl: synchronously, then as an async job.
# Usage: denoise.sh <input> <output> [params-json]
# Environment: MDN_URL (default http://127.0.0.1:8080), MDN_TOKEN (bearer token, if the server wants one).
set -euo pipefail
input="$1"; output="$2"; params="${3:-{\}}"
url="${MDN_URL:-http://127.0.0.1:8080}"
auth=()
[ -n "${MDN_TOKEN:-}" ] && auth=(-H "Authorization: Bearer $MDN_TOKEN")

case "$input" in
  *.glb) type=model/gltf-binary ;;
  *.gltf) type=model/gltf+json ;;
  *.drc) type=model/x-draco ;;
  *.off) type=model/x-off ;;
  *.obj) type=model/obj ;;
  *.ply) type=model/x-ply ;;
  *) type=application/octet-stream ;;
esac

# 1. Synchronous: the denoised mesh is the response body. --fail-with-body keeps the
#    problem+json on errors; --data-binary (never -d) sends the bytes unchanged.
curl --silent --show-error --fail-with-body "${auth[@]}" \
  -H "Content-Type: $type" -H "X-Denoise-Params: $params" \
  --data-binary @"$input" -o "$output" -D "$output.headers" "$url/v1/denoise"
grep -i '^x-denoise-params:\|^server-timing:' "$output.headers" >&2 || true

# 2. Asynchronous: 202 + Location, wait until finished (long polls: each GET answers when the
#    job finishes, or after 30 s), download the result.
location=$(curl --silent --show-error --fail-with-body "${auth[@]}" \
  -H "Content-Type: $type" -H "X-Denoise-Params: $params" \
  --data-binary @"$input" -o /dev/null -w '%header{location}' "$url/v1/jobs")
while :; do
  state=$(curl --silent --show-error --fail-with-body "${auth[@]}" "$url$location?wait=30" |
          python3 -c 'import json,sys; print(json.load(sys.stdin)["state"])')
  case "$state" in
    succeeded) break ;;
    failed|cancelled) echo "job $state" >&2; curl --silent "${auth[@]}" "$url$location" >&2; exit 1 ;;
    *) ;;
  esac
done
curl --silent --show-error --fail-with-body "${auth[@]}" -o "$output.async" "$url$location/result"
cmp "$output" "$output.async"  # both ways give the same bytes
rm -f "$output.async" "$output.headers"
