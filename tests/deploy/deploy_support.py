"""Shared helpers of the deployment tests (python3 standard library only).

- read_dockerfile(): the runtime stage of docker/Dockerfile (packages, RUN, ENV, USER,
  ENTRYPOINT, HEALTHCHECK), so the tests use the Dockerfile as their one source of truth.
- icosphere_off() / read_off() / sphere_deviation(): a seeded noisy sphere to send, and an
  independent reader for what comes back.
- request(): one HTTP request with a timeout; Processes: every child started by a test, stopped at
  the end even when the test fails.

A test that cannot do its job raises TestFailure with the reason: it fails, it never skips.
"""

import http.client
import json
import math
import os
import random
import re
import shlex
import signal
import socket
import subprocess
import sys
import time


class TestFailure(Exception):
    """The test failed; the message says why."""


def check(condition, message):
    if not condition:
        raise TestFailure(message)


def log(message):
    print(message, flush=True)


# ----------------------------------------------------------------------------- Dockerfile


class RuntimeStage:
    """What the tests need from the Dockerfile's last stage."""

    def __init__(self):
        self.base = ""              # FROM image, ARGs expanded
        self.packages = []          # RUNTIME_PACKAGES
        self.package_run = ""       # the RUN that installs them (mmdebstrap replaces it)
        self.other_runs = []        # every other RUN, in order (run in the chroot as root)
        self.env = {}               # ENV
        self.user = ""              # USER (numeric uid:gid)
        self.entrypoint = []        # ENTRYPOINT, exec form
        self.healthcheck = []       # HEALTHCHECK CMD, exec form
        self.expose = []            # EXPOSE
        self.copies = []            # COPY --from=... sources and destination
        self.name = ""              # FROM ... AS name
        self.workdir = "/"          # WORKDIR
        self.local_copies = []      # COPY from the build context: [sources..., destination]


def _instructions(text):
    """Dockerfile instructions as (KEYWORD, argument text), continuation lines joined."""
    out, current = [], ""
    for raw in text.splitlines():
        line = raw.rstrip()
        if not current and (not line.strip() or line.lstrip().startswith("#")):
            continue
        if current and line.lstrip().startswith("#"):
            continue  # comment inside a continued instruction
        if line.endswith("\\"):
            current += line[:-1] + " "
            continue
        current += line
        keyword, _, rest = current.strip().partition(" ")
        out.append((keyword.upper(), rest.strip()))
        current = ""
    check(not current, "Dockerfile ends inside a continued line")
    return out


def _expand(value, variables):
    def repl(m):
        name = m.group(1) or m.group(2)
        return variables.get(name, "")
    return re.sub(r"\$\{([A-Za-z_][A-Za-z0-9_]*)\}|\$([A-Za-z_][A-Za-z0-9_]*)", repl, value)


def _parse_assignments(text):
    """ARG/ENV in the key=value form (values may be double-quoted)."""
    out = {}
    for token in shlex.split(text):
        check("=" in token, "expected KEY=value in the Dockerfile, got '%s'" % token)
        key, _, value = token.partition("=")
        out[key] = value
    return out


def read_dockerfile(path):
    """The runtime (last) stage, checked for what the tests rely on."""
    return read_stages(path)[-1]


def read_stages(path):
    """Every stage of the Dockerfile, in order; the last one is checked as the runtime stage."""
    with open(path, encoding="utf-8") as f:
        instructions = _instructions(f.read())
    global_args, stage_vars, stages = {}, {}, []
    stage = None
    for keyword, rest in instructions:
        if keyword == "FROM":
            stage = RuntimeStage()
            stages.append(stage)
            stage_vars = {}
            words = rest.split()
            stage.base = _expand(words[0], global_args)
            if len(words) == 3 and words[1].upper() == "AS":
                stage.name = words[2]
            continue
        if stage is None:
            if keyword == "ARG":
                global_args.update(_parse_assignments(rest))
            continue
        if keyword == "ARG":
            stage_vars.update(_parse_assignments(rest))
        elif keyword == "ENV":
            stage.env.update(_parse_assignments(rest))
        elif keyword == "RUN":
            if "RUNTIME_PACKAGES" in rest:
                stage.package_run = rest
            else:
                stage.other_runs.append(rest)
        elif keyword == "USER":
            stage.user = rest
        elif keyword == "ENTRYPOINT":
            stage.entrypoint = json.loads(rest)
        elif keyword == "HEALTHCHECK":
            m = re.search(r"\bCMD\s+(\[.*\])\s*$", rest)
            check(m is not None, "HEALTHCHECK must use the exec form CMD [...]: " + rest)
            stage.healthcheck = json.loads(m.group(1))
        elif keyword == "EXPOSE":
            stage.expose += rest.split()
        elif keyword == "COPY" and rest.startswith("--from="):
            stage.copies.append(rest.split()[1:])
        elif keyword == "COPY":
            stage.local_copies.append(rest.split())
        elif keyword == "WORKDIR":
            stage.workdir = os.path.join(stage.workdir, rest)
        if "RUNTIME_PACKAGES" in stage_vars:
            stage.packages = stage_vars["RUNTIME_PACKAGES"].split()
    check(stages, "no FROM in " + path)
    runtime = stages[-1]
    check(runtime.packages, "the last stage of %s has no ARG RUNTIME_PACKAGES=\"...\"" % path)
    check(runtime.package_run, "no RUN installs ${RUNTIME_PACKAGES} in the last stage of " + path)
    check(re.fullmatch(r"\d+(:\d+)?", runtime.user or "") is not None,
          "USER of the runtime stage must be numeric uid[:gid], got '%s'" % runtime.user)
    check(runtime.user.split(":")[0] != "0", "the runtime stage runs as root")
    check(runtime.entrypoint, "ENTRYPOINT must be in exec form [\"...\"]")
    check(runtime.healthcheck, "the runtime stage has no HEALTHCHECK")
    return stages


# ----------------------------------------------------------------------------- meshes


def icosphere(subdivisions):
    """Unit icosphere: (vertices, faces), counter-clockwise seen from outside."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdivisions):
        midpoint, new_faces = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                p = [(verts[a][k] + verts[b][k]) / 2 for k in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                verts.append(tuple(x / n for x in p))
                midpoint[key] = len(verts) - 1
            return midpoint[key]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new_faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new_faces
    return verts, faces


def noisy_icosphere_off(subdivisions, sigma, seed):
    """OFF text of a unit icosphere with Gaussian noise of std sigma on every coordinate."""
    verts, faces = icosphere(subdivisions)
    rng = random.Random(seed)
    noisy = [tuple(c + rng.gauss(0.0, sigma) for c in v) for v in verts]
    lines = ["OFF", "%d %d 0" % (len(noisy), len(faces))]
    lines += ["%.9g %.9g %.9g" % v for v in noisy]
    lines += ["3 %d %d %d" % f for f in faces]
    return ("\n".join(lines) + "\n").encode()


def read_off(data):
    """(vertices, faces) of an OFF file; raises TestFailure when it is not one."""
    try:
        tokens = [t for line in data.decode().splitlines()
                  for t in line.split("#", 1)[0].split()]
        check(tokens and tokens[0] == "OFF", "not an OFF file: %r" % data[:40])
        nv, nf = int(tokens[1]), int(tokens[2])
        pos = 4
        verts = []
        for _ in range(nv):
            verts.append(tuple(float(x) for x in tokens[pos:pos + 3]))
            pos += 3
        faces = []
        for _ in range(nf):
            k = int(tokens[pos])
            faces.append(tuple(int(x) for x in tokens[pos + 1:pos + 1 + k]))
            pos += 1 + k
        return verts, faces
    except (ValueError, IndexError, UnicodeDecodeError) as e:
        raise TestFailure("the response is not a readable OFF file: %s" % e)


def sphere_deviation(verts):
    """Root mean square of |p| - 1: how far the vertices are from the unit sphere."""
    return math.sqrt(sum((math.sqrt(sum(c * c for c in v)) - 1.0) ** 2 for v in verts) / len(verts))


def check_denoised(body, noisy_off, what):
    """The body is the noisy sphere, denoised: same connectivity, closer to the sphere."""
    noisy_v, noisy_f = read_off(noisy_off)
    out_v, out_f = read_off(body)
    check(len(out_v) == len(noisy_v) and out_f == noisy_f,
          "%s: the result has %d vertices / %d faces, expected %d / %d with the same faces"
          % (what, len(out_v), len(out_f), len(noisy_v), len(noisy_f)))
    before, after = sphere_deviation(noisy_v), sphere_deviation(out_v)
    check(after < 0.7 * before,
          "%s: not denoised: RMS distance to the sphere %.4g before, %.4g after" % (what, before, after))
    return before, after


# ----------------------------------------------------------------------------- HTTP


class Response:
    def __init__(self, status, headers, body):
        self.status, self.headers, self.body = status, headers, body

    def header(self, name):
        for k, v in self.headers:
            if k.lower() == name.lower():
                return v
        return None

    def json(self):
        try:
            return json.loads(self.body)
        except ValueError:
            raise TestFailure("expected JSON, got %d %r" % (self.status, self.body[:200]))


def request(port, method, path, body=None, headers=None, timeout=60, host="127.0.0.1", source=None):
    """One request on a fresh connection (from the local address `source` if given, e.g. another
    loopback address). Raises OSError/http.client errors on failure."""
    conn = http.client.HTTPConnection(host, port, timeout=timeout, source_address=(source, 0) if source else None)
    try:
        conn.request(method, path, body=body, headers=headers or {})
        r = conn.getresponse()
        return Response(r.status, r.getheaders(), r.read())
    finally:
        conn.close()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_http(port, path, deadline_s, process=None, expect=200):
    """Polls until GET path answers `expect`; fails if the process exits or time runs out."""
    end = time.monotonic() + deadline_s
    last = None
    while time.monotonic() < end:
        if process is not None and process.poll() is not None:
            raise TestFailure("the process exited with %s before %s answered" % (process.returncode, path))
        try:
            r = request(port, "GET", path, timeout=2)
            if r.status == expect:
                return r
            last = "%d %r" % (r.status, r.body[:200])
        except (OSError, http.client.HTTPException) as e:
            last = repr(e)
        time.sleep(0.1)
    raise TestFailure("GET %s on port %d did not answer %d within %gs (last: %s)"
                      % (path, port, expect, deadline_s, last))


def metric(port, name, labels):
    """Value of one Prometheus sample (0 if absent), read from the server's /metrics."""
    text = request(port, "GET", "/metrics", timeout=5).body.decode()
    total = 0.0
    for line in text.splitlines():
        if not line.startswith(name + "{") and not line.startswith(name + " "):
            continue
        m = re.match(r"([a-zA-Z_:][a-zA-Z0-9_:]*)(?:\{(.*)\})?\s+(\S+)$", line)
        if not m or m.group(1) != name:
            continue
        have = dict(re.findall(r'(\w+)="((?:[^"\\]|\\.)*)"', m.group(2) or ""))
        if all(have.get(k) == v for k, v in labels.items()):
            total += float(m.group(3))
    return total


# ----------------------------------------------------------------------------- processes


class Processes:
    """Children of one test. stop_all() ends every one still running (SIGTERM, then SIGKILL)."""

    def __init__(self):
        self.children = []

    def start(self, args, log_path, **kwargs):
        out = open(log_path, "wb")
        p = subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT, start_new_session=True, **kwargs)
        p.log_path = log_path
        out.close()
        self.children.append(p)
        return p

    def stop_all(self):
        for p in self.children:
            if p.poll() is None:
                try:
                    os.killpg(p.pid, signal.SIGTERM)
                except ProcessLookupError:
                    pass
        end = time.monotonic() + 10
        for p in self.children:
            try:
                p.wait(max(0.1, end - time.monotonic()))
            except subprocess.TimeoutExpired:
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                p.wait()


def tail(path, lines=30):
    try:
        with open(path, errors="replace") as f:
            return "".join(f.readlines()[-lines:])
    except OSError:
        return "(no log)"


def run_main(main):
    """Runs main(); prints the reason and exits 1 on failure."""
    try:
        main()
    except TestFailure as e:
        print("FAIL: %s" % e, file=sys.stderr, flush=True)
        sys.exit(1)
    print("PASS", flush=True)
