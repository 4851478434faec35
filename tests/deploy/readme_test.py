#!/usr/bin/env python3
"""The README's newcomer path, run as written: every fenced block whose info string is
`sh runnable`, in order, in one bash session (set -euo pipefail), from a copy of the repository
root (build/release, scripts/ and third_party_data/ linked into a scratch folder, HOME a
scratch folder so `cmake --install ... --prefix ~/.local` lands there), against a live
meshdenoise-server on a free loopback port (the README's 127.0.0.1:8080 rewritten to it).
Then checks what the blocks printed: the --metrics lines, the denoised ones far below the noisy.

Usage: readme_test.py --source-dir DIR --build-dir DIR --server BINARY
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deploy_support import Processes, TestFailure, check, free_port, log, run_main, tail, wait_http  # noqa: E402

RUNNABLE = re.compile(r"^```sh runnable\n(.*?)^```", re.S | re.M)


def runnable_blocks(readme):
    return RUNNABLE.findall(readme)


def json_objects(text):
    """Every top-level JSON object printed on stdout, in order."""
    decoder = json.JSONDecoder()
    found, i = [], 0
    while True:
        i = text.find("{", i)
        if i < 0:
            return found
        try:
            value, end = decoder.raw_decode(text, i)
        except json.JSONDecodeError:
            i += 1
            continue
        found.append(value)
        i = end


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--build-dir", required=True)
    ap.add_argument("--server", required=True)
    args = ap.parse_args()
    with open(os.path.join(args.source_dir, "README.md"), encoding="utf-8") as f:
        blocks = runnable_blocks(f.read())
    check(len(blocks) >= 2, "README.md has %d `sh runnable` blocks, expected the CLI's and the service's" % len(blocks))

    processes = Processes()
    with tempfile.TemporaryDirectory(prefix="mdn_readme_") as tmp:
        root, home = os.path.join(tmp, "root"), os.path.join(tmp, "home")
        os.makedirs(os.path.join(root, "build"))
        os.makedirs(home)
        os.symlink(os.path.abspath(args.build_dir), os.path.join(root, "build", "release"))
        os.symlink(os.path.join(args.source_dir, "scripts"), os.path.join(root, "scripts"))
        # The fetched meshes are kept in the source tree's (git-ignored) third_party_data.
        data = os.path.join(args.source_dir, "third_party_data")
        os.makedirs(data, exist_ok=True)
        os.symlink(data, os.path.join(root, "third_party_data"))

        port = free_port()
        server = processes.start([args.server, "--port", str(port), "--workers", "1"], os.path.join(tmp, "server.log"))
        try:
            wait_http(port, "/readyz", 30, server)
            script = "\n".join(blocks).replace("127.0.0.1:8080", "127.0.0.1:%d" % port)
            env = dict(os.environ, HOME=home)
            log("running %d README blocks (%d lines) in %s" % (len(blocks), script.count("\n"), root))
            r = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=root, env=env,
                               capture_output=True, text=True, timeout=600)
            if r.returncode != 0:
                raise TestFailure("the README's blocks failed (exit %d)\n--- stdout\n%s\n--- stderr\n%s\n--- server\n%s"
                                  % (r.returncode, r.stdout[-3000:], r.stderr[-3000:], tail(server.log_path)))
        finally:
            processes.stop_all()
        check(os.path.isfile(os.path.join(home, ".local", "bin", "meshdenoise")), "cmake --install put no meshdenoise in ~/.local/bin")
        check(os.path.isfile(os.path.join(home, ".local", "bin", "meshdenoise-server")), "no meshdenoise-server in ~/.local/bin")
        metrics = [o for o in json_objects(r.stdout) if "msae" in o]
        check(len(metrics) == 3, "expected 3 --metrics results (noisy, CLI, service), got %d:\n%s" % (len(metrics), r.stdout))
        noisy, cli, service = (m["msae"] for m in metrics)
        log("MSAE against fandisk.off: noisy %.3g, CLI %.3g, service %.3g" % (noisy, cli, service))
        check(cli < noisy / 4, "the CLI's result (MSAE %g) is not far below the noisy copy's (%g)" % (cli, noisy))
        check(service < noisy / 4, "the service's result (MSAE %g) is not far below the noisy copy's (%g)" % (service, noisy))
        check(os.path.isfile(os.path.join(root, "try", "denoised-by-service.glb")), "no denoised-by-service.glb")
    log("ok")


if __name__ == "__main__":
    run_main(main)
