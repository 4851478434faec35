#!/usr/bin/env python3
"""meshdenoise-server client using only the Python standard library.

Usage: denoise_client.py <input> <output> [params-json] [--async]
Environment: MDN_URL (default http://127.0.0.1:8080), MDN_TOKEN (bearer token, optional).
Errors come back as RFC 9457 problem+json; they are printed and the exit status is 1.
"""
import json
import os
import sys
import urllib.error
import urllib.request

MEDIA_TYPES = {".glb": "model/gltf-binary", ".gltf": "model/gltf+json", ".drc": "model/x-draco",
               ".off": "model/x-off", ".obj": "model/obj", ".ply": "model/x-ply", ".stl": "model/stl"}


def request(method, url, body=None, headers=None):
    headers = dict(headers or {})
    if os.environ.get("MDN_TOKEN"):
        headers["Authorization"] = "Bearer " + os.environ["MDN_TOKEN"]
    req = urllib.request.Request(url, data=body, method=method, headers=headers)
    try:
        with urllib.request.urlopen(req, timeout=600) as resp:
            return resp.status, resp.headers, resp.read()
    except urllib.error.HTTPError as e:  # 4xx/5xx: the body is a problem+json document
        problem = json.loads(e.read() or b"{}")
        sys.exit(f"{e.code} {problem.get('title')}: {problem.get('detail')} (request {problem.get('request_id')})")


def main():
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(__doc__.strip())
        return
    args = [a for a in sys.argv[1:] if a != "--async"]
    use_async = "--async" in sys.argv
    if len(args) not in (2, 3):
        print(__doc__.strip().splitlines()[2] + "\n(run with --help for more)", file=sys.stderr)
        sys.exit(2)
    src, dst = args[0], args[1]
    params = args[2] if len(args) > 2 else "{}"
    base = os.environ.get("MDN_URL", "http://127.0.0.1:8080")
    with open(src, "rb") as f:
        body = f.read()
    headers = {"Content-Type": MEDIA_TYPES.get(os.path.splitext(src)[1].lower(), "application/octet-stream"),
               "X-Denoise-Params": params}
    if not use_async:
        status, resp_headers, data = request("POST", base + "/v1/denoise", body, headers)
        print("effective parameters:", resp_headers["X-Denoise-Params"], file=sys.stderr)
        print("timings:", resp_headers["Server-Timing"], file=sys.stderr)
    else:
        status, resp_headers, data = request("POST", base + "/v1/jobs", body, headers)
        location = resp_headers["Location"]
        while True:  # long polls: each answers when the job finishes, or after 30 s
            _, _, job_body = request("GET", base + location + "?wait=30")
            job = json.loads(job_body)
            if job["state"] == "succeeded":
                break
            if job["state"] in ("failed", "cancelled"):
                sys.exit(f"job {job['state']}: {job.get('error', {}).get('detail')}")
        _, _, data = request("GET", base + location + "/result")
    with open(dst, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main()
