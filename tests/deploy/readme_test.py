#!/usr/bin/env python3
"""The README's newcomer path, run as written: every fenced block whose info string is
`sh runnable`, in order, in one bash session (set -euo pipefail), from a copy of the repository
root (build/release, scripts/ and third_party_data/ linked into a scratch folder, HOME a
scratch folder). The blocks start the server themselves, in the background, as a user in one
terminal would; it listens on a free loopback port (MDN_PORT, and the README's 127.0.0.1:8080
rewritten to it) and must exit 0 when the block stops it. Then checks what the blocks printed:
the --metrics lines, the denoised ones far below the noisy. And every `ctest` command in the
README fails when it finds no tests (`--no-tests=error`: after scripts/run-service.sh the build
folder has none, and plain ctest prints "No tests were found!!!" and exits 0).

Usage: readme_test.py --source-dir DIR --build-dir DIR
"""
import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deploy_support import TestFailure, check, free_port, log, run_main, tail  # noqa: E402

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
    args = ap.parse_args()
    with open(os.path.join(args.source_dir, "README.md"), encoding="utf-8") as f:
        readme = f.read()
    blocks = runnable_blocks(readme)
    check(len(blocks) >= 2, "README.md has %d `sh runnable` blocks, expected the CLI's and the service's" % len(blocks))
    ctest_lines = [line for line in readme.splitlines() if re.search(r"(^|[;&|] *)ctest ", line)]
    check(len(ctest_lines) > 0, "README.md has no ctest command")
    for line in ctest_lines:
        check("--no-tests=error" in line, "this README ctest command passes with no tests: %s" % line)

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
        script = "\n".join(blocks).replace("127.0.0.1:8080", "127.0.0.1:%d" % port)
        env = dict(os.environ, HOME=home, MDN_PORT=str(port))
        log("running %d README blocks (%d lines) in %s" % (len(blocks), script.count("\n"), root))
        # Its own session: whatever the blocks leave running (a server, if they fail) is ended.
        p = subprocess.Popen(["bash", "-euo", "pipefail", "-c", script], cwd=root, env=env, start_new_session=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            out, err = p.communicate(timeout=600)
        finally:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        server_log = os.path.join(root, "try", "server.log")
        if p.returncode != 0:
            raise TestFailure("the README's blocks failed (exit %d)\n--- stdout\n%s\n--- stderr\n%s\n--- server\n%s"
                              % (p.returncode, out[-3000:], err[-3000:],
                                 tail(server_log) if os.path.exists(server_log) else "(no try/server.log)"))
        with open(server_log, encoding="utf-8", errors="replace") as f:
            check(re.search(r"listening .*port=%d" % port, f.read()) is not None,
                  "the README's server did not listen on port %d: %s" % (port, tail(server_log)))
        metrics = [o for o in json_objects(out) if "msae" in o]
        check(len(metrics) == 3, "expected 3 --metrics results (noisy, CLI, service), got %d:\n%s" % (len(metrics), out))
        noisy, cli, service = (m["msae"] for m in metrics)
        log("MSAE against fandisk.off: noisy %.3g, CLI %.3g, service %.3g" % (noisy, cli, service))
        check(cli < noisy / 4, "the CLI's result (MSAE %g) is not far below the noisy copy's (%g)" % (cli, noisy))
        check(service < noisy / 4, "the service's result (MSAE %g) is not far below the noisy copy's (%g)" % (service, noisy))
        check(os.path.isfile(os.path.join(root, "try", "denoised-by-service.glb")), "no denoised-by-service.glb")
    log("ok")


if __name__ == "__main__":
    run_main(main)
