#!/usr/bin/env bash
# Denoises a mesh with meshdenoise-server using curl: synchronously, then as an async job (both
# give the same bytes). The output's format is its file extension's.
# Usage: denoise.sh <input> <output> [params-json]
#   output: .off .obj .ply .stl .drc .glb or .gltf (sets the parameters' output.format)
# Environment: MDN_URL (default http://127.0.0.1:8080), MDN_TOKEN (bearer token, if the server wants one).
# Exit status: 0 done; 2 bad arguments (an input that cannot be read, an output extension that
# names no format, parameters that are not a JSON object), nothing sent; 1 the server could not
# be reached or refused the mesh (its problem+json title and detail are printed). Needs curl and
# python3 (for the JSON).
set -euo pipefail
fail() { echo "denoise.sh: $2" >&2; exit "$1"; }
[ $# -ge 2 ] && [ $# -le 3 ] || fail 2 "usage: denoise.sh <input> <output> [params-json]"
input=$1; output=$2; params=${3:-"{}"}
url="${MDN_URL:-http://127.0.0.1:8080}"
auth=()
if [ -n "${MDN_TOKEN:-}" ]; then auth=(-H "Authorization: Bearer $MDN_TOKEN"); fi

# Check everything before sending anything.
[ -f "$input" ] || fail 2 "cannot read $input: no such file"
[ -r "$input" ] || fail 2 "cannot read $input: permission denied"
case "${input,,}" in
  *.glb) type=model/gltf-binary ;;
  *.gltf) type=model/gltf+json ;;
  *.drc) type=model/x-draco ;;
  *.off) type=model/x-off ;;
  *.obj) type=model/obj ;;
  *.ply) type=model/x-ply ;;
  *.stl) type=model/stl ;;
  *) type=application/octet-stream ;;  # the server tells the format from the bytes
esac
format="${output##*.}"; format="${format,,}"
case "$output" in
  *.*) case "$format" in off|obj|ply|stl|drc|glb|gltf) ;; *) format="" ;; esac ;;
  *) format="" ;;
esac
[ -n "$format" ] || fail 2 "cannot write $output: its extension names no format (use .off, .obj, .ply, .stl, .drc, .glb or .gltf)"
[ -d "$(dirname -- "$output")" ] || fail 2 "cannot write $output: the folder $(dirname -- "$output") does not exist"
# The parameters with output.format set from OUTPUT's extension (a different one given is refused).
if ! params=$(python3 -c '
import json, sys
try:
    p = json.loads(sys.argv[1])
except ValueError as e:
    sys.exit("the parameters are not JSON: %s" % e)
if not isinstance(p, dict) or not isinstance(p.get("output", {}), dict):
    sys.exit("the parameters must be a JSON object (with \"output\" an object)")
given = p.get("output", {}).get("format")
if given not in (None, sys.argv[2]):
    sys.exit("the parameters ask for output.format \"%s\" but %s is .%s" % (given, sys.argv[3], sys.argv[2]))
p.setdefault("output", {})["format"] = sys.argv[2]
print(json.dumps(p, separators=(",", ":")))' "$params" "$format" "$output" 2>&1); then
  fail 2 "$params"
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# call BODY_FILE curl-arguments...: the HTTP status on stdout; one line and exit 1 when the
# server cannot be reached or answers 4xx/5xx (an RFC 9457 problem+json body).
call() {
  local body=$1 status
  shift
  if ! status=$(curl --silent --show-error "${auth[@]}" -o "$body" -w '%{http_code}' "$@" 2>"$tmp/curl.err"); then
    fail 1 "cannot reach the server at $url: $(sed 's/^curl: ([0-9]*) //' "$tmp/curl.err" | head -n 1) (is meshdenoise-server running? MDN_URL sets its address)"
  fi
  if [ "$status" -ge 400 ]; then
    fail 1 "$(python3 -c '
import json, sys
try:
    p = json.load(open(sys.argv[1]))
    print("the server answered %s %s: %s" % (sys.argv[2], p.get("title"), p.get("detail")))
except Exception:
    print("the server answered %s: %s" % (sys.argv[2], open(sys.argv[1], errors="replace").read(200).strip()))' "$body" "$status")"
  fi
  echo "$status"
}
json_field() { python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])' "$1" "$2"; }

# 1. Synchronous: the denoised mesh is the response body; --data-binary (never -d) sends the
#    bytes unchanged. It goes to OUTPUT only once the server said 200.
call "$tmp/sync" -D "$tmp/sync.headers" -H "Content-Type: $type" -H "X-Denoise-Params: $params" \
  --data-binary @"$input" "$url/v1/denoise" >/dev/null
grep -i '^x-denoise-params:\|^x-denoise-summary:\|^server-timing:' "$tmp/sync.headers" >&2 || true

# 2. Asynchronous: 202 + Location, wait until finished (long polls: each GET answers when the
#    job finishes, or after 30 s), download the result.
call "$tmp/job.json" -H "Content-Type: $type" -H "X-Denoise-Params: $params" \
  --data-binary @"$input" "$url/v1/jobs" >/dev/null
location=$(json_field "$tmp/job.json" id); location="/v1/jobs/$location"
while :; do
  call "$tmp/job.json" "$url$location?wait=30" >/dev/null
  state=$(json_field "$tmp/job.json" state)
  case "$state" in
    succeeded) break ;;
    failed|cancelled) fail 1 "the job $state: $(python3 -c 'import json, sys; print(json.load(open(sys.argv[1])).get("error", {}).get("detail"))' "$tmp/job.json")" ;;
    *) ;;
  esac
done
call "$tmp/async" "$url$location/result" >/dev/null
cmp -s "$tmp/sync" "$tmp/async" || fail 1 "the synchronous and asynchronous results differ"
mv "$tmp/sync" "$output"
