#!/usr/bin/env python3
"""meshdenoise-server client using only the Python standard library.

Usage: denoise_client.py <input> <output> [params-json] [--async]
The output's format is its extension's: .off .obj .ply .stl .drc .glb or .gltf.
Environment: MDN_URL (default http://127.0.0.1:8080), MDN_TOKEN (bearer token, optional).
Exit status: 0 done; 2 bad arguments (an input that cannot be read, an output extension that
names no format, parameters that are not a JSON object), nothing sent; 1 the server could not
be reached or refused the mesh (its problem+json title and detail are printed).
"""
import json
import os
import sys
import urllib.error
import urllib.request

MEDIA_TYPES = {".glb": "model/gltf-binary", ".gltf": "model/gltf+json", ".drc": "model/x-draco",
               ".off": "model/x-off", ".obj": "model/obj", ".ply": "model/x-ply", ".stl": "model/stl"}


def fail(code, message):
    print("denoise_client.py: " + message, file=sys.stderr)
    sys.exit(code)


def request(base, method, path, body=None, headers=None):
    headers = dict(headers or {})
    if os.environ.get("MDN_TOKEN"):
        headers["Authorization"] = "Bearer " + os.environ["MDN_TOKEN"]
    req = urllib.request.Request(base + path, data=body, method=method, headers=headers)
    try:
        with urllib.request.urlopen(req, timeout=600) as resp:
            return resp.headers, resp.read()
    except urllib.error.HTTPError as e:  # 4xx/5xx: the body is a problem+json document
        text = e.read()
        try:
            problem = json.loads(text)
            fail(1, f"the server answered {e.code} {problem.get('title')}: {problem.get('detail')}")
        except ValueError:
            fail(1, f"the server answered {e.code}: {text[:200].decode(errors='replace').strip()}")
    except (urllib.error.URLError, OSError) as e:  # refused, unknown host, timeout
        reason = getattr(e, "reason", e)
        fail(1, f"cannot reach the server at {base}: {reason} (is meshdenoise-server running? MDN_URL sets its address)")


def checked_arguments(args):
    """The input's bytes and media type and the parameters with output.format, or exit 2."""
    src, dst = args[0], args[1]
    try:
        with open(src, "rb") as f:
            body = f.read()
    except OSError as e:
        fail(2, f"cannot read {src}: {e.strerror}")
    ext = os.path.splitext(dst)[1].lower()
    if ext not in MEDIA_TYPES:
        fail(2, f"cannot write {dst}: its extension names no format (use {', '.join(MEDIA_TYPES)})")
    folder = os.path.dirname(dst) or "."
    if not os.path.isdir(folder):
        fail(2, f"cannot write {dst}: the folder {folder} does not exist")
    try:
        params = json.loads(args[2] if len(args) > 2 else "{}")
    except ValueError as e:
        fail(2, f"the parameters are not JSON: {e}")
    if not isinstance(params, dict) or not isinstance(params.get("output", {}), dict):
        fail(2, 'the parameters must be a JSON object (with "output" an object)')
    given = params.get("output", {}).get("format")
    if given not in (None, ext[1:]):
        fail(2, f'the parameters ask for output.format "{given}" but {dst} is {ext}')
    params.setdefault("output", {})["format"] = ext[1:]
    media_type = MEDIA_TYPES.get(os.path.splitext(src)[1].lower(), "application/octet-stream")  # else the server sniffs
    return body, media_type, json.dumps(params, separators=(",", ":"))


def main():
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(__doc__.strip())
        return
    args = [a for a in sys.argv[1:] if a != "--async"]
    use_async = "--async" in sys.argv
    if len(args) not in (2, 3):
        print(__doc__.strip().splitlines()[2] + "\n(run with --help for more)", file=sys.stderr)
        sys.exit(2)
    body, media_type, params = checked_arguments(args)
    base = os.environ.get("MDN_URL", "http://127.0.0.1:8080").rstrip("/")
    headers = {"Content-Type": media_type, "X-Denoise-Params": params}
    if not use_async:
        resp_headers, data = request(base, "POST", "/v1/denoise", body, headers)
        print("effective parameters:", resp_headers["X-Denoise-Params"], file=sys.stderr)
        print("timings:", resp_headers["Server-Timing"], file=sys.stderr)
        # What ran, bounded; the full report is in the async job's result (or ?report=1).
        print("what ran:", resp_headers.get("X-Denoise-Summary"), file=sys.stderr)
    else:
        resp_headers, _ = request(base, "POST", "/v1/jobs", body, headers)
        location = resp_headers["Location"]
        while True:  # long polls: each answers when the job finishes, or after 30 s
            _, job_body = request(base, "GET", location + "?wait=30")
            job = json.loads(job_body)
            if job["state"] == "succeeded":
                break
            if job["state"] in ("failed", "cancelled"):
                fail(1, f"the job {job['state']}: {job.get('error', {}).get('detail')}")
        reports = job["result"]["reports"]  # the full report: measures, predictions, the pick
        print("report: %d surface(s), modes %s" % (len(reports), [r["mode"] for r in reports]), file=sys.stderr)
        _, data = request(base, "GET", location + "/result")
    with open(args[1], "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main()
