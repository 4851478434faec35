#!/usr/bin/env python3
"""Runtime completeness of the container image, without a container engine.

Builds a Debian root filesystem the way docker/Dockerfile's runtime stage does (mmdebstrap
minbase, the image bookworm-slim is made the same way, plus exactly ARG RUNTIME_PACKAGES, then the
stage's other RUN lines as root), copies the built executables to the COPY destination, and then,
in fresh network, PID and mount namespaces:
  - every library the executables link resolves inside the root filesystem (ldd);
  - the ENTRYPOINT starts as PID 1 under the numeric USER with the stage's ENV (0.0.0.0:8080), on a
    read-only root filesystem (compose read_only, Kubernetes readOnlyRootFilesystem);
  - the HEALTHCHECK command succeeds, a denoise request succeeds, the CLI denoises a file;
  - SIGTERM to PID 1 drains: the request in flight completes, the server exits 0, and the
    HEALTHCHECK then fails.
The root filesystem is cached under --cache-dir, keyed by everything that shapes it.

Needs root (mmdebstrap's root mode, chroot, namespaces) and access to a Debian mirror.
"""

import argparse
import fcntl
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deploy_support import (Processes, TestFailure, check, check_denoised, log, request,  # noqa: E402
                            noisy_icosphere_off, read_dockerfile, run_main, tail, wait_http)

# What Docker gives a container that sets no PATH of its own.
DOCKER_PATH = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"


def parse_args():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dockerfile", required=True)
    p.add_argument("--binary", action="append", required=True,
                   help="a built executable the runtime stage copies in (repeat)")
    p.add_argument("--cache-dir", required=True, help="where the root filesystem is kept between runs")
    p.add_argument("--mirror", default="http://deb.debian.org/debian")
    p.add_argument("--security-mirror", default="http://deb.debian.org/debian-security")
    p.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--rootfs", help=argparse.SUPPRESS)
    return p.parse_args()


# ----------------------------------------------------------------------------- root filesystem


def suite_of(base):
    """debian:bookworm-slim -> bookworm. Only Debian slim bases can be rebuilt with mmdebstrap."""
    name, _, tag = base.partition(":")
    check(name in ("debian", "docker.io/library/debian") and tag.endswith("-slim"),
          "the runtime stage is FROM %s; this test rebuilds only debian:<suite>-slim" % base)
    return tag[: -len("-slim")]


def build_rootfs(stage, args):
    """The cached root filesystem for this runtime stage: (path, seconds spent building, 0 if cached)."""
    suite = suite_of(stage.base)
    mirrors = ["deb %s %s main" % (args.mirror, suite),
               "deb %s %s-updates main" % (args.mirror, suite),
               "deb %s %s-security main" % (args.security_mirror, suite)]
    recipe = {"suite": suite, "variant": "minbase", "packages": stage.packages,
              "runs": stage.other_runs, "mirrors": mirrors, "version": 1}
    key = hashlib.sha256(json.dumps(recipe, sort_keys=True).encode()).hexdigest()[:16]
    entry = os.path.join(args.cache_dir, key)
    rootfs = os.path.join(entry, "rootfs")
    if os.path.exists(os.path.join(entry, "complete")):
        log("root filesystem: cached %s (%s)" % (entry, " ".join(stage.packages)))
        return rootfs, 0.0

    # Other recipes' root filesystems are stale: the Dockerfile changed.
    for name in os.listdir(args.cache_dir):
        path = os.path.join(args.cache_dir, name)
        if name != key and os.path.isdir(path):
            shutil.rmtree(path, ignore_errors=True)
    shutil.rmtree(entry, ignore_errors=True)
    os.makedirs(entry)

    for tool in ("mmdebstrap", "chroot", "unshare", "ip", "mount"):
        check(shutil.which(tool) is not None,
              "%s is not installed (scripts/install-deps.sh test installs mmdebstrap, iproute2 ...)" % tool)
    log("root filesystem: mmdebstrap --variant=minbase %s with %s" % (suite, " ".join(stage.packages)))
    start = time.monotonic()
    cmd = ["mmdebstrap", "--mode=root", "--variant=minbase", "--quiet",
           "--include=" + ",".join(stage.packages), suite, rootfs] + mirrors
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=1200)
    check(r.returncode == 0, "mmdebstrap failed (exit %d): is a Debian mirror reachable?\n%s"
          % (r.returncode, r.stdout.decode(errors="replace")[-4000:]))
    # The stage's other RUN lines (the user), as Docker runs them: /bin/sh -c as root.
    for run in stage.other_runs:
        r = subprocess.run(["chroot", rootfs, "/bin/sh", "-c", run], env={"PATH": DOCKER_PATH},
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        check(r.returncode == 0, "RUN %s failed in the root filesystem:\n%s" % (run, r.stdout.decode(errors="replace")))
    seconds = time.monotonic() - start
    size = subprocess.run(["du", "-sm", rootfs], stdout=subprocess.PIPE).stdout.split()[0].decode()
    log("root filesystem: built in %.1f s, %s MiB" % (seconds, size))
    with open(os.path.join(entry, "complete"), "w") as f:
        f.write(json.dumps(recipe, indent=1) + "\n")
    return rootfs, seconds


def install_binaries(stage, rootfs, binaries):
    """COPY --from=build ... DEST: the built executables, by name, into the root filesystem."""
    check(len(stage.copies) == 1, "expected one COPY --from=build in the runtime stage, got %s" % stage.copies)
    sources, dest = stage.copies[0][:-1], stage.copies[0][-1]
    wanted = sorted(os.path.basename(s) for s in sources)
    given = sorted(os.path.basename(b) for b in binaries)
    check(wanted == given, "the Dockerfile copies %s, the test was given %s" % (wanted, given))
    check(dest.endswith("/"), "COPY destination %s should be a directory" % dest)
    target_dir = os.path.join(rootfs, dest.lstrip("/"))
    os.makedirs(target_dir, exist_ok=True)
    for b in binaries:
        check(os.access(b, os.X_OK), "not built: " + b)
        target = os.path.join(target_dir, os.path.basename(b))
        shutil.copyfile(b, target + ".new")
        os.chmod(target + ".new", 0o755)
        os.replace(target + ".new", target)
    return [os.path.join(dest, os.path.basename(b)) for b in binaries]


# ----------------------------------------------------------------------------- inside the namespaces


def container_env(stage, uid):
    env = {"PATH": DOCKER_PATH, "HOSTNAME": "meshdenoise-test", "HOME": "/"}
    env.update(stage.env)
    return env


def server_pid_of(unshare_pid):
    """The host PID of the process unshare --fork started (PID 1 of the new namespace)."""
    for _ in range(100):
        try:
            with open("/proc/%d/task/%d/children" % (unshare_pid, unshare_pid)) as f:
                children = f.read().split()
            if children:
                return int(children[0])
        except OSError:
            pass
        time.sleep(0.05)
    raise TestFailure("could not find the server process under unshare (pid %d)" % unshare_pid)


def proc_status(pid):
    with open("/proc/%d/status" % pid) as f:
        return dict(line.rstrip("\n").split(":\t", 1) for line in f if ":\t" in line)


def listening_addresses(port):
    """Local IPv4 addresses with a listening TCP socket on `port` in this network namespace."""
    out = []
    with open("/proc/net/tcp") as f:
        for line in f.readlines()[1:]:
            fields = line.split()
            addr, hex_port = fields[1].split(":")
            if fields[3] == "0A" and int(hex_port, 16) == port:  # 0A: TCP_LISTEN
                out.append(".".join(str(b) for b in reversed(bytes.fromhex(addr))))
    return out


def check_namespaces():
    r = subprocess.run(["unshare", "--net", "--pid", "--mount", "--fork", "true"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    check(r.returncode == 0, "cannot create network/PID/mount namespaces here (unshare: %s); "
          "this test needs root with CAP_SYS_ADMIN" % r.stdout.decode(errors="replace").strip())


def run_healthcheck(stage, rootfs, env):
    """Docker runs HEALTHCHECK CMD [...] inside the container, as its user, with its ENV."""
    try:
        r = subprocess.run(["chroot", "--userspec=" + stage.user, rootfs] + stage.healthcheck, env=env,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=10)
    except subprocess.TimeoutExpired:
        return 124, "timed out"
    return r.returncode, r.stdout.decode(errors="replace")


def inner(args):
    stage = read_dockerfile(args.dockerfile)
    rootfs = args.rootfs
    r = subprocess.run(["ip", "link", "set", "lo", "up"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    check(r.returncode == 0, "cannot bring up loopback in the new network namespace: " + r.stdout.decode())
    installed = install_binaries(stage, rootfs, args.binary)
    uid = stage.user.split(":")[0]

    # 1. Every linked library is in the root filesystem.
    for exe in installed:
        r = subprocess.run(["chroot", rootfs, "/usr/bin/ldd", exe], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        out = r.stdout.decode(errors="replace")
        missing = [line.strip() for line in out.splitlines() if "not found" in line]
        check(not missing, "%s lacks libraries in the runtime image (add their packages to RUNTIME_PACKAGES):\n  %s"
              % (exe, "\n  ".join(missing)))
        check(r.returncode == 0, "ldd %s failed in the root filesystem:\n%s" % (exe, out))
    log("ldd: every library of %s resolves" % ", ".join(installed))

    env = container_env(stage, uid)
    port = int(env.get("MDN_PORT", "8080"))
    check(str(port) in [e.split("/")[0] for e in stage.expose], "EXPOSE %s does not match MDN_PORT=%d" % (stage.expose, port))
    check(env.get("MDN_HOST") == "0.0.0.0", "the image must listen on 0.0.0.0 (ENV MDN_HOST), has %s" % env.get("MDN_HOST"))

    # 2. The CLI denoises a file (as the user, in a writable /tmp of its own).
    noisy = noisy_icosphere_off(3, 0.02, seed=7)
    work = tempfile.mkdtemp(dir=os.path.join(rootfs, "tmp"))
    os.chmod(work, 0o777)
    with open(os.path.join(work, "in.off"), "wb") as f:
        f.write(noisy)
    inside = "/" + os.path.relpath(work, rootfs)
    cli = [e for e in installed if os.path.basename(e) == "meshdenoise"]
    if cli:
        r = subprocess.run(["chroot", "--userspec=" + stage.user, rootfs, cli[0], inside + "/in.off", inside + "/out.off"],
                           env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
        check(r.returncode == 0, "meshdenoise failed in the runtime image:\n" + r.stdout.decode(errors="replace"))
        with open(os.path.join(work, "out.off"), "rb") as f:
            before, after = check_denoised(f.read(), noisy, "meshdenoise (CLI)")
        log("CLI: denoised, RMS distance to the sphere %.4f -> %.4f" % (before, after))
    shutil.rmtree(work)

    # 3. The server: ENTRYPOINT as PID 1 of a new PID namespace, USER, ENV, read-only root.
    procs = Processes()
    logdir = tempfile.mkdtemp(prefix="mdn-runtime-")
    script = ('set -e; root="$1"; user="$2"; shift 2; '
              'mount --bind "$root" "$root"; mount -o remount,bind,ro "$root"; '
              'mount -t proc proc "$root/proc"; '
              'exec chroot --userspec="$user" "$root" "$@"')
    try:
        server = procs.start(["unshare", "--pid", "--mount", "--fork", "--kill-child",
                              "/bin/sh", "-c", script, "sh", rootfs, stage.user] + stage.entrypoint,
                             os.path.join(logdir, "server.log"), env=env)
        try:
            wait_http(port, "/healthz", 30, server)
        except TestFailure as e:
            raise TestFailure("%s\nserver log:\n%s" % (e, tail(server.log_path)))
        pid = server_pid_of(server.pid)
        status = proc_status(pid)
        check(status["Uid"].split()[0] == uid, "the server runs as uid %s, USER says %s" % (status["Uid"], uid))
        check(status["NSpid"].split()[-1] == "1", "the server is not PID 1 in its namespace: NSpid %s" % status["NSpid"])
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            argv = [a.decode() for a in f.read().split(b"\0") if a]
        check(argv == stage.entrypoint, "PID 1 is %s, ENTRYPOINT is %s" % (argv, stage.entrypoint))
        addresses = listening_addresses(port)
        check(addresses == ["0.0.0.0"], "the server listens on %s:%d, expected 0.0.0.0 only" % (addresses, port))
        log("server: PID 1, uid %s, %s, listening on 0.0.0.0:%d, read-only root" % (uid, argv[0], port))

        rc, out = run_healthcheck(stage, rootfs, env)
        check(rc == 0, "HEALTHCHECK failed against a running server (exit %d): %s" % (rc, out))
        log("HEALTHCHECK: exit 0 while serving")

        r = request(port, "POST", "/v1/denoise", noisy, {"Content-Type": "model/x-off"}, timeout=120)
        check(r.status == 200, "POST /v1/denoise: %d %r" % (r.status, r.body[:300]))
        before, after = check_denoised(r.body, noisy, "POST /v1/denoise")
        log("POST /v1/denoise: 200, RMS distance to the sphere %.4f -> %.4f" % (before, after))

        # 4. SIGTERM to PID 1 drains: a job in flight finishes, then the process exits 0.
        heavy = noisy_icosphere_off(4, 0.01, seed=11)
        result = {}

        def slow_request():
            try:
                result["r"] = request(port, "POST", "/v1/denoise", heavy,
                                   {"Content-Type": "model/x-off",
                                    "X-Denoise-Params": json.dumps({"n_normal": 400, "n_vertex": 200})}, timeout=300)
            except Exception as e:  # reported below
                result["error"] = repr(e)

        t = threading.Thread(target=slow_request)
        t.start()
        end = time.monotonic() + 60
        while time.monotonic() < end:
            ready = request(port, "GET", "/readyz", timeout=5)
            if ready.status == 200 and ready.json().get("running", 0) >= 1:
                break
            check("error" not in result and "r" not in result, "the slow request ended before SIGTERM: %s" % result)
            time.sleep(0.02)
        else:
            raise TestFailure("the slow request never started running")
        os.kill(pid, signal.SIGTERM)
        t.join(300)
        check("error" not in result, "the request in flight failed during the drain: %s" % result.get("error"))
        check(result["r"].status == 200, "the request in flight got %d during the drain: %r"
              % (result["r"].status, result["r"].body[:300]))
        check_denoised(result["r"].body, heavy, "the request in flight during the drain")
        try:
            code = server.wait(60)
        except subprocess.TimeoutExpired:
            raise TestFailure("the server did not exit within 60 s of SIGTERM")
        check(code == 0, "the server exited %d after SIGTERM (expected 0)\n%s" % (code, tail(server.log_path)))
        log("SIGTERM: the request in flight completed, the server exited 0")

        rc, out = run_healthcheck(stage, rootfs, env)
        check(rc != 0, "HEALTHCHECK still succeeds after the server stopped: %s" % out)
        log("HEALTHCHECK: exit %d once the server is gone" % rc)
    finally:
        procs.stop_all()
        shutil.rmtree(logdir, ignore_errors=True)


# ----------------------------------------------------------------------------- outside


def outer(args):
    check(os.geteuid() == 0, "needs root (mmdebstrap root mode, chroot, namespaces); run ctest as root")
    stage = read_dockerfile(args.dockerfile)
    check_namespaces()
    os.makedirs(args.cache_dir, exist_ok=True)
    # One run at a time per cache: the root filesystem is built once and its /usr/local/bin changes.
    with open(os.path.join(args.cache_dir, ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        rootfs, _ = build_rootfs(stage, args)
        # The server part runs in a fresh network namespace: the image's own port 8080 is free
        # there whatever else runs on this machine, and nothing reaches the network.
        cmd = ["unshare", "--net", "--", sys.executable, os.path.abspath(__file__), "--inner",
               "--rootfs", rootfs, "--dockerfile", args.dockerfile, "--cache-dir", args.cache_dir]
        for b in args.binary:
            cmd += ["--binary", os.path.abspath(b)]
        r = subprocess.run(cmd)
        check(r.returncode == 0, "the checks in the root filesystem failed (see above)")


def main():
    args = parse_args()
    if args.inner:
        inner(args)
    else:
        outer(args)


if __name__ == "__main__":
    run_main(main)
