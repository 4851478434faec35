#!/usr/bin/env python3
"""Scale-out: three meshdenoise-server replicas on loopback behind Debian's nginx, configured
with docker/nginx/meshdenoise.conf itself (only its upstream addresses and listen port are
rewritten to loopback), sharing one redis-server as their job store (MDN_QUEUE, as in
docker-compose.yml).

  1. Load: concurrent POST /v1/denoise through nginx all succeed with a denoised mesh, and every
     replica's own /metrics shows it served a share of them.
  2. Response desync: GETs whose body is a whole request, sent beside victims' requests, never
     get (or cause) another request's answer (issue 49, item 1).
  3. Failover: one replica is killed (SIGKILL) while it runs requests; no synchronous request is
     lost (nginx resends it to another replica, seen in its access log), and afterwards the two
     survivors serve everything.
  4. Graceful stop: SIGTERM to a busy replica; it drains (503 to new work, which nginx resends)
     and exits 0 while every request still succeeds.
  5. Asynchronous jobs through the balancer: created, polled, fetched and deleted through nginx,
     whichever replica each request reaches. The balancer's own answers: an oversized body
     refused with 413 before any replica sees it, /metrics not proxied, and a replica's own
     error passed through unchanged and not retried.
  6. Fair shares per client through nginx (decision 86): the replicas trust nginx's address
     (MDN_TRUSTED_PROXIES), so clients at 127.0.0.2 and 127.0.0.3 have a share each; one over
     its MDN_CLIENT_MAX_STORED_JOBS gets 429 while the other is served, and an X-Forwarded-For
     it writes itself does not make it another client.

Every process started here is stopped at the end, also when a check fails.
"""

import argparse
import concurrent.futures
import http.client
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deploy_support import (Processes, TestFailure, check, check_denoised, free_port, request, log,  # noqa: E402
                            metric, noisy_icosphere_off, run_main, tail, wait_http)

DENOISE_OK = {"route": "/v1/denoise", "method": "POST", "status": "200"}
CLIENT_JOBS = 8  # --client-max-stored-jobs of the replicas


def parse_args():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--server", required=True, help="the built meshdenoise-server")
    p.add_argument("--nginx-conf", required=True, help="docker/nginx/meshdenoise.conf")
    p.add_argument("--nginx", default="/usr/sbin/nginx")
    p.add_argument("--redis-server", default="/usr/bin/redis-server")
    p.add_argument("--replicas", type=int, default=3)
    p.add_argument("--requests", type=int, default=60, help="requests of the load phase")
    p.add_argument("--concurrency", type=int, default=6)
    return p.parse_args()


# ----------------------------------------------------------------------------- nginx


def render_site(conf_text, replica_ports, listen_port):
    """docker/nginx/meshdenoise.conf with the replicas and the listen port on loopback."""
    m = re.search(r"^([ \t]*)# upstream-servers-begin\n(.*?)^[ \t]*# upstream-servers-end\n",
                  conf_text, re.S | re.M)
    check(m is not None, "docker/nginx/meshdenoise.conf lost its upstream-servers-begin/end markers")
    servers = re.findall(r"^\s*server\s+(\S+)((?:\s+[^;\s]+)*)\s*;", m.group(2), re.M)
    check(len(servers) == 1, "expected one server line between the markers, found %d" % len(servers))
    params = servers[0][1]  # max_fails=..., fail_timeout=...: kept as they are
    lines = "".join("%sserver 127.0.0.1:%d%s;\n" % (m.group(1), p, params) for p in replica_ports)
    text = conf_text[:m.start()] + lines + conf_text[m.end():]
    check(len(re.findall(r"^\s*listen\s+80;", text, re.M)) == 1,
          "docker/nginx/meshdenoise.conf should have exactly one 'listen 80;'")
    return re.sub(r"^(\s*)listen\s+80;", r"\g<1>listen 127.0.0.1:%d;" % listen_port, text, flags=re.M)


def main_conf(prefix, site_path):
    """What the nginx image's own nginx.conf provides around conf.d/*.conf, in a private prefix."""
    return """daemon off;
worker_processes 2;
pid {p}/nginx.pid;
error_log stderr notice;
events {{ worker_connections 512; }}
http {{
    client_body_temp_path {p}/body;
    proxy_temp_path {p}/proxy;
    fastcgi_temp_path {p}/fastcgi;
    uwsgi_temp_path {p}/uwsgi;
    scgi_temp_path {p}/scgi;
    include {site};
}}
""".format(p=prefix, site=site_path)


def read_access_log(path):
    entries = []
    with open(path, errors="replace") as f:
        for line in f:
            line = line.strip()
            if line.startswith("{"):
                try:
                    entries.append(json.loads(line))
                except ValueError:
                    raise TestFailure("nginx wrote an access log line that is not JSON: " + line)
    return entries


# ----------------------------------------------------------------------------- load


def denoise_through(port, body, request_id, params=None):
    headers = {"Content-Type": "model/x-off", "X-Request-Id": request_id}
    if params:
        headers["X-Denoise-Params"] = json.dumps(params)
    try:
        return request(port, "POST", "/v1/denoise", body, headers, timeout=300)
    except (OSError, http.client.HTTPException) as e:
        raise TestFailure("request %s failed at the client: %r" % (request_id, e))


def run_batch(port, body, ids, concurrency, params=None, on_submit=None):
    """All requests, `concurrency` at a time; every one must be 200 with a denoised mesh."""
    with concurrent.futures.ThreadPoolExecutor(concurrency) as pool:
        futures = {pool.submit(denoise_through, port, body, rid, params): rid for rid in ids}
        if on_submit:
            on_submit()
        for f in concurrent.futures.as_completed(futures):
            rid = futures[f]
            r = f.result()
            check(r.status == 200, "request %s: %d %r" % (rid, r.status, r.body[:300]))
            check(r.header("X-Request-Id") == rid, "request %s came back with X-Request-Id %s"
                  % (rid, r.header("X-Request-Id")))
            check_denoised(r.body, body, "request " + rid)


def served(replicas):
    return [int(metric(port, "mdn_http_requests_total", DENOISE_OK)) for port in replicas]


def main():
    args = parse_args()
    check(shutil.which(args.nginx) is not None or os.access(args.nginx, os.X_OK),
          "nginx is not installed (scripts/install-deps.sh test installs nginx-light)")
    check(os.access(args.server, os.X_OK), "not built: " + args.server)
    check(os.access(args.redis_server, os.X_OK),
          "redis-server is not installed (scripts/install-deps.sh test installs it)")
    with open(args.nginx_conf) as f:
        conf_text = f.read()

    tmp = tempfile.mkdtemp(prefix="mdn-scale-out-")
    os.chmod(tmp, 0o755)  # nginx workers (nobody) write the temp paths below
    procs = Processes()
    try:
        # The shared job store, as the compose file runs it (append-only file).
        redis_port = free_port()
        redis = procs.start([args.redis_server, "--port", str(redis_port), "--bind", "127.0.0.1", "--dir", tmp,
                             "--appendonly", "yes", "--appendfsync", "always", "--save", ""], os.path.join(tmp, "redis.log"))
        end = time.monotonic() + 30
        while True:
            check(redis.poll() is None, "redis-server exited: %s" % tail(redis.log_path))
            try:
                with socket.create_connection(("127.0.0.1", redis_port), timeout=2) as sock:
                    sock.sendall(b"PING\r\n")
                    if sock.recv(64).startswith(b"+PONG"):
                        break
            except OSError:
                pass
            check(time.monotonic() < end, "redis-server did not answer PING")
            time.sleep(0.05)
        queue_url = "redis://127.0.0.1:%d/0" % redis_port

        # Replicas: the defaults of docker-compose.yml, except one worker each (two shared cores),
        # a small share of stored jobs per client (step 6; step 5 holds 6 at once), and nginx's
        # address alone trusted (the compose file trusts the private ranges nginx lives in; here
        # the clients are on loopback too).
        replicas, servers = [], []
        for i in range(args.replicas):
            port_file = os.path.join(tmp, "replica-%d.port" % i)
            p = procs.start([args.server, "--host", "127.0.0.1", "--port", "0", "--port-file", port_file,
                             "--workers", "1", "--log-format", "json", "--log-level", "warn", "--queue", queue_url,
                             "--trusted-proxies", "127.0.0.1/32", "--client-max-stored-jobs", str(CLIENT_JOBS)],
                            os.path.join(tmp, "replica-%d.log" % i))
            end = time.monotonic() + 30
            while not os.path.exists(port_file):
                check(p.poll() is None, "replica %d exited: %s" % (i, tail(p.log_path)))
                check(time.monotonic() < end, "replica %d wrote no port file" % i)
                time.sleep(0.05)
            with open(port_file) as f:
                replicas.append(int(f.read()))
            servers.append(p)
            wait_http(replicas[-1], "/readyz", 30, p)
        log("replicas on 127.0.0.1:%s" % ", ".join(map(str, replicas)))

        lb = free_port()
        site = os.path.join(tmp, "meshdenoise.conf")
        with open(site, "w") as f:
            f.write(render_site(conf_text, replicas, lb))
        conf = os.path.join(tmp, "nginx.conf")
        with open(conf, "w") as f:
            f.write(main_conf(tmp, site))
        r = subprocess.run([args.nginx, "-t", "-p", tmp, "-c", conf, "-e", "stderr"],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        check(r.returncode == 0, "nginx rejects docker/nginx/meshdenoise.conf:\n" + r.stdout.decode(errors="replace"))
        access_log = os.path.join(tmp, "access.log")
        nginx = procs.start([args.nginx, "-p", tmp, "-c", conf, "-e", "stderr"], access_log)
        wait_http(lb, "/healthz", 30, nginx)
        log("nginx %s on 127.0.0.1:%d" % (subprocess.run([args.nginx, "-v"], stderr=subprocess.PIPE)
                                          .stderr.decode().strip(), lb))

        # 1. Load through the balancer.
        small = noisy_icosphere_off(3, 0.02, seed=1)
        start = time.monotonic()
        run_batch(lb, small, ["load-%03d" % i for i in range(args.requests)], args.concurrency)
        elapsed = time.monotonic() - start
        counts = served(replicas)
        log("load: %d requests (%d at a time) in %.2f s, %.1f requests/s; per replica %s"
            % (args.requests, args.concurrency, elapsed, args.requests / elapsed, counts))
        check(sum(counts) == args.requests,
              "the replicas served %d denoise requests for %d sent: %s" % (sum(counts), args.requests, counts))
        for port, n in zip(replicas, counts):
            check(n >= args.requests // 10,
                  "replica %d served %d of %d requests: least_conn did not spread them (%s)"
                  % (port, n, args.requests, counts))

        # 2. A response desync (issue 49, item 1): attackers send GET /healthz with a whole second
        # request as its body, while victims denoise their own meshes, all through nginx's
        # kept-alive upstream connections. A replica that parsed the body as a request would
        # write a second answer that nginx hands to whoever uses that connection next.
        desync_end = time.monotonic() + 8
        smuggled = b"GET /readyz HTTP/1.1\r\nHost: x\r\n\r\n"

        def attack():
            conn, answers = http.client.HTTPConnection("127.0.0.1", lb, timeout=30), 0
            try:
                while time.monotonic() < desync_end:
                    conn.request("GET", "/healthz", body=smuggled)
                    r = conn.getresponse()
                    body = r.read()
                    check(r.status == 200 and json.loads(body).get("status") == "ok",
                          "the attacker got another answer than its own: %d %r" % (r.status, body[:200]))
                    answers += 1
            finally:
                conn.close()
            return answers

        def victim(k):
            mesh, done = noisy_icosphere_off(3, 0.02, seed=100 + k), 0
            while time.monotonic() < desync_end:
                rid = "victim-%d-%d" % (k, done)
                r = denoise_through(lb, mesh, rid)
                check(r.status == 200 and r.header("X-Request-Id") == rid,
                      "victim %s got another answer than its own: %d, X-Request-Id %s, %r"
                      % (rid, r.status, r.header("X-Request-Id"), r.body[:120]))
                check_denoised(r.body, mesh, "victim " + rid)
                done += 1
            return done

        with concurrent.futures.ThreadPoolExecutor(6) as pool:
            attacks = [pool.submit(attack) for _ in range(3)]
            victims = [pool.submit(victim, k) for k in range(3)]
            attacked, served_victims = sum(f.result() for f in attacks), sum(f.result() for f in victims)
        check(attacked > 0 and served_victims > 0, "the desync phase ran no request")
        log("desync: %d smuggling GETs and %d victims' denoise requests through nginx, none answered "
            "with another request's answer" % (attacked, served_victims))

        # 3. Kill one replica while it is running requests.
        victim = 1
        heavy = noisy_icosphere_off(4, 0.01, seed=2)
        heavy_params = {"n_normal": 100, "n_vertex": 50}
        heavy_ids = ["failover-%03d" % i for i in range(4 * args.replicas)]

        def kill_when_busy():
            end = time.monotonic() + 60
            while time.monotonic() < end:
                ready = request(replicas[victim], "GET", "/readyz", timeout=5)
                if ready.status == 200 and ready.json().get("running", 0) >= 1:
                    servers[victim].send_signal(signal.SIGKILL)
                    servers[victim].wait()
                    log("killed replica %d (SIGKILL) while it ran a request" % replicas[victim])
                    return
                time.sleep(0.01)
            raise TestFailure("replica %d never ran a request to be killed in" % replicas[victim])

        run_batch(lb, heavy, heavy_ids, args.concurrency, heavy_params, on_submit=kill_when_busy)
        check(servers[victim].returncode == -signal.SIGKILL, "replica %d was not killed" % replicas[victim])
        entries = {e["request_id"]: e for e in read_access_log(access_log)}
        victim_addr = "127.0.0.1:%d" % replicas[victim]
        retried = [rid for rid in heavy_ids
                   if rid in entries and entries[rid]["upstream_addr"].count(",") >= 1
                   and entries[rid]["upstream_addr"].split(",")[0].strip() == victim_addr]
        check(retried, "no request was resent after the kill (access log: %s)"
              % [entries.get(rid) for rid in heavy_ids])
        for rid in retried:
            check(entries[rid]["status"] == 200, "resent request %s: %s" % (rid, entries[rid]))
        log("failover: %d requests all 200; %d were running on the killed replica and were resent "
            "by nginx (e.g. upstream %s, statuses %s)"
            % (len(heavy_ids), len(retried), entries[retried[0]]["upstream_addr"],
               entries[retried[0]]["upstream_status"]))

        # After the kill: the survivors serve everything.
        survivors = [p for i, p in enumerate(replicas) if i != victim]
        before = [served([p])[0] for p in survivors]
        after_ids = ["after-%03d" % i for i in range(args.requests // 2)]
        run_batch(lb, small, after_ids, args.concurrency)
        gained = [served([p])[0] - b for p, b in zip(survivors, before)]
        log("after the kill: %d requests all 200, survivors served %s" % (len(after_ids), gained))
        check(sum(gained) == len(after_ids), "survivors served %s of %d requests" % (gained, len(after_ids)))
        check(all(g > 0 for g in gained), "one survivor got nothing after the kill: %s" % gained)

        # 4. A graceful stop (what docker stop / a rolling update does) under load: SIGTERM to a
        # busy replica. It finishes what it accepted and answers 503 to new work, which nginx
        # resends to the last replica; no request fails and the replica exits 0.
        draining = 0

        def stop_when_busy():
            end = time.monotonic() + 60
            while time.monotonic() < end:
                ready = request(replicas[draining], "GET", "/readyz", timeout=5)
                if ready.status == 200 and ready.json().get("running", 0) >= 1:
                    servers[draining].send_signal(signal.SIGTERM)
                    return
                time.sleep(0.01)
            raise TestFailure("replica %d never ran a request to be stopped in" % replicas[draining])

        drain_ids = ["drain-%03d" % i for i in range(4 * args.replicas)]
        run_batch(lb, heavy, drain_ids, args.concurrency, heavy_params, on_submit=stop_when_busy)
        try:
            code = servers[draining].wait(60)
        except subprocess.TimeoutExpired:
            raise TestFailure("replica %d did not exit within 60 s of SIGTERM" % replicas[draining])
        check(code == 0, "replica %d exited %d after SIGTERM" % (replicas[draining], code))
        entries = {e["request_id"]: e for e in read_access_log(access_log)}
        refused = sum(1 for rid in drain_ids if "503" in entries.get(rid, {}).get("upstream_status", ""))
        log("graceful stop: %d requests all 200 while replica %d drained and exited 0 "
            "(%d answered 503 by it and resent)" % (len(drain_ids), replicas[draining], refused))

        # 5. Asynchronous jobs through the balancer: each request may reach another replica (the
        # one stopped above refuses connections and nginx moves on); the shared queue answers.
        job_ids = []
        for i in range(2 * args.replicas):
            r = request(lb, "POST", "/v1/jobs", small, {"Content-Type": "model/x-off", "X-Request-Id": "job-%d" % i})
            check(r.status == 202, "POST /v1/jobs through the balancer: %d %r" % (r.status, r.body[:300]))
            job_ids.append(r.json()["id"])
        for jid in job_ids:
            end = time.monotonic() + 120
            while True:
                r = request(lb, "GET", "/v1/jobs/" + jid)
                check(r.status == 200, "GET /v1/jobs/%s through the balancer: %d %r" % (jid, r.status, r.body[:300]))
                state = r.json()["state"]
                if state not in ("queued", "running"):
                    break
                check(time.monotonic() < end, "job %s still %s after 120 s" % (jid, state))
                time.sleep(0.05)
            check(state == "succeeded", "job %s: %s" % (jid, r.body[:300]))
            r = request(lb, "GET", "/v1/jobs/%s/result" % jid)
            check(r.status == 200, "GET /v1/jobs/%s/result through the balancer: %d" % (jid, r.status))
            check_denoised(r.body, small, "job " + jid)
            r = request(lb, "DELETE", "/v1/jobs/" + jid)
            check(r.status == 204, "DELETE /v1/jobs/%s through the balancer: %d" % (jid, r.status))
        log("jobs: %d created, polled, fetched and deleted through the balancer (shared Redis queue)" % len(job_ids))

        # 6. Each client its share: nginx forwards the address it saw, the replicas believe it.
        def submit(source, headers=None):
            h = {"Content-Type": "model/x-off"}
            h.update(headers or {})
            r = request(lb, "POST", "/v1/jobs", small, h, source=source)
            check(r.status in (202, 429), "POST /v1/jobs from %s: %d %r" % (source, r.status, r.body[:300]))
            if r.status == 429:
                check(r.json().get("type") == "urn:meshdenoise:problem:over-client-share", "429 from %s: %r"
                      % (source, r.body[:300]))
            return r.status
        greedy = [submit("127.0.0.2") for _ in range(CLIENT_JOBS + 1)]
        check(greedy == [202] * CLIENT_JOBS + [429], "127.0.0.2's jobs through nginx: %s" % greedy)
        spoofed = submit("127.0.0.2", {"X-Forwarded-For": "127.0.0.3"})
        check(spoofed == 429, "127.0.0.2 writing X-Forwarded-For: 127.0.0.3 was another client (%d)" % spoofed)
        check(submit("127.0.0.3") == 202, "127.0.0.3 was refused with 127.0.0.2's share full: one share for all")
        log("shares: 127.0.0.2 refused 429 after %d jobs (also when it writes X-Forwarded-For), 127.0.0.3 served"
            % CLIENT_JOBS)

        conn = http.client.HTTPConnection("127.0.0.1", lb, timeout=30)
        try:
            conn.putrequest("POST", "/v1/denoise")
            conn.putheader("Content-Type", "model/x-off")
            conn.putheader("Content-Length", str(300 << 20))
            conn.endheaders()
            resp = conn.getresponse()
            status, ctype, body = resp.status, resp.getheader("Content-Type") or "", resp.read()
        finally:
            conn.close()
        check(status == 413 and ctype.startswith("application/problem+json"),
              "a 300 MiB body through the balancer: %d %s %r" % (status, ctype, body[:200]))
        check(json.loads(body).get("type") == "urn:meshdenoise:problem:too-large", "413 problem: %r" % body)

        r = request(lb, "GET", "/metrics")
        check(r.status == 404 and r.json().get("status") == 404, "/metrics through the balancer: %d" % r.status)

        bad = request(lb, "POST", "/v1/denoise", b"OFF\n3 1 0\n0 0 0\n1 0 0\n", {"Content-Type": "model/x-off",
                                                                            "X-Request-Id": "bad-mesh"})
        check(bad.status == 400 and bad.json().get("type", "").startswith("urn:meshdenoise:problem:"),
              "a malformed mesh through the balancer: %d %r" % (bad.status, bad.body[:300]))
        # nginx writes the access-log line when it finalises the request, which can be just
        # after the client has the answer: wait for the line (2 s at most).
        deadline = time.monotonic() + 2.0
        entries = {e["request_id"]: e for e in read_access_log(access_log)}
        while "bad-mesh" not in entries and time.monotonic() < deadline:
            time.sleep(0.05)
            entries = {e["request_id"]: e for e in read_access_log(access_log)}
        check("bad-mesh" in entries, "nginx logged no line for the bad-mesh request")
        # nginx may first try the replica stopped above (502: connection refused) and move on;
        # what must not happen is a 400 answered by one replica and then sent to another.
        statuses = [x.strip() for x in entries["bad-mesh"]["upstream_status"].split(",")]
        check(statuses[-1] == "400" and "400" not in statuses[:-1],
              "a 400 from a replica was retried on another: %s" % entries["bad-mesh"])
        log("balancer: 300 MiB body 413 problem, /metrics 404, a replica's 400 passed through once")

        # Per-client connections (limit_conn 64): 64 requests whose bodies have not come yet hold
        # their slots; the 65th request from the same address gets nginx's 503 problem.
        held = []
        try:
            for _ in range(64):
                sock = socket.create_connection(("127.0.0.1", lb), timeout=10)
                sock.sendall(b"POST /v1/denoise HTTP/1.1\r\nHost: x\r\nContent-Type: model/x-off\r\nContent-Length: 1000\r\n\r\n")
                held.append(sock)
            time.sleep(0.3)  # nginx has read every head
            over = request(lb, "GET", "/healthz")
            check(over.status == 503 and over.json().get("type") == "urn:meshdenoise:problem:queue-full"
                  and over.header("Retry-After") == "1",
                  "the 65th request from one address: %d %r" % (over.status, over.body[:300]))
        finally:
            for sock in held:
                sock.close()
        end = time.monotonic() + 10
        while request(lb, "GET", "/healthz").status != 200:
            check(time.monotonic() < end, "the per-client slots were not freed")
            time.sleep(0.1)
        log("balancer: limit_conn 64 per address answers the 65th request 503 (problem, Retry-After)")

        nginx.send_signal(signal.SIGQUIT)  # graceful stop; errors in its log would show below
        nginx.wait(30)
        errors = [l for l in tail(access_log, 2000).splitlines() if "[emerg]" in l or "[alert]" in l or "[crit]" in l]
        check(not errors, "nginx logged errors:\n" + "\n".join(errors))
    except TestFailure as e:
        logs = "\n".join("--- %s\n%s" % (os.path.basename(p.log_path), tail(p.log_path, 15)) for p in procs.children)
        raise TestFailure("%s\n%s" % (e, logs))
    finally:
        procs.stop_all()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    run_main(main)
