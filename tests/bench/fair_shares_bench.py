#!/usr/bin/env python3
"""Fair shares of the job store and queued bytes (issue 49, items 4 and 5). Prints figures,
asserts nothing (never part of ctest).

  memory:     finding 5's attack on one server: one worker busy with a long job, then 25 bodies
              of 40 MB submitted to POST /v1/jobs (each a comment-only OFF file, refused only
              once a worker decodes it); the server's resident memory (VmRSS) before, once all
              are submitted (and its peak, VmHWM), and 3 s after every job was cancelled.
  lockout:    finding 4's attack: with two API keys, one submits tiny jobs it never fetches until
              it is refused (or 1,100 are accepted); then the other submits 20 (fetching each):
              how many of the other's were accepted, and what the first was answered.
  throughput: tiny asynchronous jobs, submitted, long-polled and downloaded by 4 clients in a
              loop for --seconds; jobs a second.

Usage: fair_shares_bench.py [--server build/release/server/meshdenoise-server] [--seconds 20]
                            [--what memory,lockout,throughput] [-- extra server flags...]
Run it once with the binary of each commit to compare (the flags after -- go to the server).
"""
import argparse
import json
import os
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "deploy"))
from deploy_support import Processes, free_port, noisy_icosphere_off, request, wait_http  # noqa: E402

HEAVY = json.dumps({"n_normal": 1000, "n_vertex": 1000, "n_aniso": 20})


def status_mib(pid, field):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def start_server(procs, binary, tmp, name, flags):
    port = free_port()
    p = procs.start([binary, "--port", str(port), "--log-level", "warn"] + flags, os.path.join(tmp, name + ".log"))
    wait_http(port, "/readyz", 30, p)
    return port, p


def submit(port, body, params=None, content_type="model/x-off"):
    path = "/v1/jobs" + ("?params=" + params if params else "")
    return request(port, "POST", path, body, {"Content-Type": content_type}, timeout=120)


def memory(binary, tmp, flags):
    procs = Processes()
    try:
        port, p = start_server(procs, binary, tmp, "memory", ["--workers", "1"] + flags)
        rss0 = status_mib(p.pid, "VmRSS")
        from urllib.parse import quote
        busy = submit(port, noisy_icosphere_off(7, 0.2, 1), quote(HEAVY))
        if busy.status != 202:
            sys.exit("the long job was refused: %d %r" % (busy.status, busy.body[:300]))
        ids = [busy.json()["id"]]
        time.sleep(3)
        rss_busy = status_mib(p.pid, "VmRSS")
        body = b"OFF\n#" + b"x" * (40 << 20) + b"\n"
        statuses = {}
        for _ in range(25):
            r = submit(port, body)
            statuses[r.status] = statuses.get(r.status, 0) + 1
            if r.status == 202:
                ids.append(r.json()["id"])
        rss_full, hwm = status_mib(p.pid, "VmRSS"), status_mib(p.pid, "VmHWM")
        states = {}
        for i in ids[1:]:
            state = request(port, "GET", "/v1/jobs/" + i).json()["state"]
            states[state] = states.get(state, 0) + 1
        long_job = request(port, "GET", "/v1/jobs/" + ids[0]).json()["state"]
        for i in ids:
            request(port, "DELETE", "/v1/jobs/" + i)
        time.sleep(3)
        rss_after = status_mib(p.pid, "VmRSS")
        print("memory: answers to the 25 bodies %s, then their states %s (the long job %s); VmRSS %.0f MiB before, %.0f MiB with the long job running, "
              "%.0f MiB with them submitted (VmHWM %.0f MiB), %.0f MiB 3 s after cancelling all"
              % (statuses, states, long_job, rss0, rss_busy, rss_full, hwm, rss_after))
    finally:
        procs.stop_all()


def lockout(binary, tmp, flags):
    keys = os.path.join(tmp, "keys")
    with open(keys, "w") as f:
        f.write("greedy:key-greedy-aaaaaaaaaaaa\nother:key-other-bbbbbbbbbbbbb\n")
    procs = Processes()
    try:
        port, _ = start_server(procs, binary, tmp, "lockout", ["--api-keys", keys] + flags)
        tiny = noisy_icosphere_off(1, 0.2, 1)

        def post(key):
            return request(port, "POST", "/v1/jobs", tiny, {"Content-Type": "model/x-off", "Authorization": "Bearer " + key})

        greedy, refusal = 0, None
        start = time.monotonic()
        while greedy < 1100:
            r = post("key-greedy-aaaaaaaaaaaa")
            if r.status != 202:
                refusal = "%d %s (Retry-After %s)" % (r.status, r.json().get("type", "").split(":")[-1], r.header("Retry-After"))
                break
            greedy += 1
        took = time.monotonic() - start
        other = 0
        for _ in range(20):
            r = post("key-other-bbbbbbbbbbbbb")
            if r.status == 202:
                job = r.json()["id"]
                auth = {"Authorization": "Bearer key-other-bbbbbbbbbbbbb"}
                request(port, "GET", "/v1/jobs/%s?wait=30" % job, headers=auth)
                if request(port, "GET", "/v1/jobs/%s/result" % job, headers=auth).status == 200:
                    other += 1
        print("lockout: the greedy key had %d jobs accepted in %.1f s, then %s; the other key: %d of 20 accepted "
              "and downloaded" % (greedy, took, refusal, other))
    finally:
        procs.stop_all()


def throughput(binary, tmp, flags, seconds):
    procs = Processes()
    try:
        port, p = start_server(procs, binary, tmp, "throughput", flags)
        tiny = noisy_icosphere_off(1, 0.2, 1)
        done, refused, errors = [0], {}, []
        lock = threading.Lock()
        end = time.monotonic() + seconds

        def client():
            while time.monotonic() < end:
                try:
                    r = submit(port, tiny)
                    if r.status != 202:
                        with lock:
                            refused[r.status] = refused.get(r.status, 0) + 1
                        time.sleep(float(r.header("Retry-After") or 1))
                        continue
                    job = r.json()["id"]
                    request(port, "GET", "/v1/jobs/%s?wait=30" % job)
                    res = request(port, "GET", "/v1/jobs/%s/result" % job)
                    with lock:
                        if res.status == 200:
                            done[0] += 1
                        else:
                            refused["result %d" % res.status] = refused.get("result %d" % res.status, 0) + 1
                except OSError as e:
                    errors.append(repr(e))

        start = time.monotonic()
        threads = [threading.Thread(target=client) for _ in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        elapsed = time.monotonic() - start
        print("throughput: %d tiny jobs submitted, waited for and downloaded in %.1f s by 4 clients: %.1f jobs/s; "
              "refusals %s; errors %d" % (done[0], elapsed, done[0] / elapsed, refused, len(errors)))
    finally:
        procs.stop_all()


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    ap = argparse.ArgumentParser()
    ap.add_argument("--server", default=os.path.join(ROOT, "build", "release", "server", "meshdenoise-server"))
    ap.add_argument("--seconds", type=float, default=20)
    ap.add_argument("--what", default="memory,lockout,throughput")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        if "memory" in args.what:
            memory(args.server, tmp, extra)
        if "lockout" in args.what:
            lockout(args.server, tmp, extra)
        if "throughput" in args.what:
            throughput(args.server, tmp, extra, args.seconds)


if __name__ == "__main__":
    main()
