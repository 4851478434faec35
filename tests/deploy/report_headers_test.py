#!/usr/bin/env python3
"""Issue 51, item 4: no response header over 1 KB, behind an nginx with its default buffers.

A meshdenoise-server on loopback behind Debian's nginx with a minimal proxy configuration:
nothing but proxy_pass, so proxy_buffer_size is nginx's default (one memory page, 4 KB), which
a response whose headers do not fit turns into a 502. Through it, an Auto job (the default
mode: the full report is 41 descriptors and 48 predicted errors, about 7 KB) is sent
  - synchronously: 200, the denoised mesh, every header under 1 KB, X-Denoise-Summary saying
    what ran;
  - synchronously with ?report=1: 200, multipart/mixed with the mesh and the result JSON whose
    reports hold the choice;
  - as an asynchronous job: created, waited for, its resource's result holds the full report,
    the result download's headers are under 1 KB.
Every answer of every endpoint used is checked for headers over 1 KB.

Usage: report_headers_test.py --server BINARY [--nginx /usr/sbin/nginx]
"""
import argparse
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deploy_support import (Processes, TestFailure, check, free_port, log, noisy_icosphere_off, request,  # noqa: E402
                            run_main, tail, wait_http)
from scale_out_test import main_conf  # noqa: E402

MAX_HEADER = 1024


def nginx_site(port, upstream):
    """Nothing but proxy_pass: every buffer at nginx's default."""
    return """access_log off;
client_max_body_size 64m;
server {{
    listen 127.0.0.1:{port};
    location / {{ proxy_pass http://127.0.0.1:{upstream}; }}
}}
""".format(port=port, upstream=upstream)


def small_headers(r, what):
    for name, value in r.headers:
        check(len(name) + len(value) + 2 < MAX_HEADER,
              "%s: header %s is %d bytes (over 1 KB): %s..." % (what, name, len(value), value[:120]))


def multipart_json(r, what):
    """The application/json part of a multipart/mixed answer."""
    ctype = r.header("Content-Type") or ""
    check(ctype.startswith("multipart/mixed; boundary="), "%s: Content-Type %r" % (what, ctype))
    boundary = b"--" + ctype.split("=", 1)[1].encode()
    parts = r.body.split(b"\r\n" + boundary)
    for part in parts:
        head, _, body = part.partition(b"\r\n\r\n")
        if b"Content-Type: application/json" in head:
            return json.loads(body)
    raise TestFailure("%s: no application/json part in %r" % (what, r.body[:200]))


def check_report(reports, what):
    check(isinstance(reports, list) and len(reports) == 1, "%s: reports %r" % (what, reports))
    check(reports[0]["mode"] == "auto" and "choice" in reports[0], "%s: no auto choice in %r" % (what, reports[0]))
    size = len(json.dumps(reports))
    check(size > 4096, "%s: the report is only %d bytes: this test needs one that no 4 KB buffer holds" % (what, size))
    return size


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--server", required=True)
    ap.add_argument("--nginx", default="/usr/sbin/nginx")
    args = ap.parse_args()
    check(shutil.which(args.nginx) is not None or os.access(args.nginx, os.X_OK),
          "nginx is not installed (scripts/install-deps.sh test installs nginx-light)")
    processes = Processes()
    with tempfile.TemporaryDirectory(prefix="mdn_report_headers_") as tmp:
        os.chmod(tmp, 0o755)  # nginx workers (nobody) write the temp paths
        port, lb = free_port(), free_port()
        server = processes.start([args.server, "--port", str(port), "--workers", "1"], os.path.join(tmp, "server.log"))
        site, conf = os.path.join(tmp, "site.conf"), os.path.join(tmp, "nginx.conf")
        with open(site, "w") as f:
            f.write(nginx_site(lb, port))
        with open(conf, "w") as f:
            f.write(main_conf(tmp, site))  # what the nginx image wraps a site in (scale_out_test)
        try:
            wait_http(port, "/readyz", 30, server)
            nginx = processes.start([args.nginx, "-p", tmp, "-c", conf, "-e", "stderr"], os.path.join(tmp, "nginx.log"))
            wait_http(lb, "/readyz", 30, nginx)
            noisy = noisy_icosphere_off(4, 0.01, 7)
            off = {"Content-Type": "model/x-off"}

            r = request(lb, "POST", "/v1/denoise", noisy, off, timeout=120)
            check(r.status == 200, "sync through nginx: %d %r\n%s" % (r.status, r.body[:300], tail(os.path.join(tmp, "nginx.log"))))
            small_headers(r, "sync")
            summary = json.loads(r.header("X-Denoise-Summary"))
            check(summary["surfaces"] == 1 and summary["ran"][0]["mode"] == "auto", "summary %r" % summary)
            check(r.body.startswith(b"OFF"), "sync: the body is not the mesh")

            r = request(lb, "POST", "/v1/denoise?report=1", noisy, off, timeout=120)
            check(r.status == 200, "sync ?report=1 through nginx: %d %r" % (r.status, r.body[:300]))
            small_headers(r, "sync ?report=1")
            size = check_report(multipart_json(r, "sync ?report=1")["reports"], "sync ?report=1")

            r = request(lb, "POST", "/v1/jobs", noisy, off)
            check(r.status == 202, "POST /v1/jobs: %d %r" % (r.status, r.body[:300]))
            small_headers(r, "POST /v1/jobs")
            job = r.json()
            r = request(lb, "GET", "/v1/jobs/%s?wait=60" % job["id"], timeout=90)
            small_headers(r, "GET /v1/jobs/{id}")
            check(r.status == 200 and r.json()["state"] == "succeeded", "job: %d %r" % (r.status, r.body[:300]))
            check_report(r.json()["result"]["reports"], "job resource")
            r = request(lb, "GET", "/v1/jobs/%s/result" % job["id"])
            check(r.status == 200, "GET result: %d %r" % (r.status, r.body[:300]))
            small_headers(r, "GET /v1/jobs/{id}/result")
            for path in ("/healthz", "/readyz", "/v1/params", "/v1/params/schema", "/v1/report/schema", "/"):
                small_headers(request(lb, "GET", path), "GET " + path)
            log("an Auto job's report of %d bytes reached the client through nginx's default buffers; "
                "every header under 1 KB" % size)
        finally:
            processes.stop_all()
    log("ok")


if __name__ == "__main__":
    run_main(main)
