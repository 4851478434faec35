#!/usr/bin/env python3
"""meshopt output against gltfpack's for the same denoised mesh (issue 51). Prints figures,
asserts nothing (never part of ctest).

For each mesh (noisy icospheres, and CGAL's Fandisk and bunny when third_party_data/cgal is
there): the CLI denoises it into an uncompressed float32 .glb (the reference), then
  ours:     meshdenoise --mode none ref.glb ours.glb   with output.compression "meshopt"
  gltfpack: gltfpack -c -vp BITS -vn NBITS -i ref.glb -o gltfpack.glb
at the same position and normal bits. Sizes (raw and gzip -9, as a web server would send
them) and the median time glTF-Transform's reader takes on each (meshoptimizer's WebAssembly
decoder, tests/tools/time_gltf_read.mjs), and our own reader's (meshdenoise --mode none to OFF,
whole process, median of the runs).

Usage: meshopt_bench.py [--cli build/release/cli/meshdenoise] [--tools tests/tools] [--runs 15]
"""
import argparse
import gzip
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "deploy"))
from deploy_support import noisy_icosphere_off  # noqa: E402


def run(args, cwd=None):
    r = subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        sys.exit("%s failed (exit %d):\n%s%s" % (" ".join(args), r.returncode, r.stdout[-2000:], r.stderr[-2000:]))
    return r.stdout


def meshes(tmp):
    """(name, path of a noisy OFF)."""
    out = []
    for level in (5, 6):
        path = os.path.join(tmp, "icosphere%d.off" % level)
        with open(path, "wb") as f:
            f.write(noisy_icosphere_off(level, 0.01, 7))
        out.append(("icosphere L%d" % level, path))
    cgal = os.path.join(ROOT, "third_party_data", "cgal", "data", "meshes")
    for name in ("fandisk.off", "bunny00.off"):
        if os.path.exists(os.path.join(cgal, name)):
            out.append((name[:-4], os.path.join(cgal, name)))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "release", "cli", "meshdenoise"))
    ap.add_argument("--tools", default=os.path.join(ROOT, "tests", "tools"))
    ap.add_argument("--runs", type=int, default=15)
    args = ap.parse_args()
    gltfpack = os.path.join(args.tools, "node_modules", ".bin", "gltfpack")
    print("commit %s; gltfpack %s; %d runs per median"
          % (run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"]).strip(),
             run([gltfpack, "-v"]).strip().splitlines()[0], args.runs))
    print("%-14s %7s %6s | %9s %9s %6s | %9s %9s %6s | %8s %8s | %8s %8s"
          % ("mesh", "faces", "bits", "ours B", "gltfpack", "ratio", "ours gz", "gp gz", "ratio",
             "ours ms", "gp ms", "cli ours", "cli gp"))
    with tempfile.TemporaryDirectory(prefix="mdn_meshopt_bench_") as tmp:
        for name, off in meshes(tmp):
            ref = os.path.join(tmp, "ref.glb")
            run([args.cli, off, ref, "--params", '{"output": {"format": "glb", "compression": "none"}}'])
            faces = int(open(off).read().split(None, 3)[2]) if off.endswith(".off") else 0
            for bits, nbits in ((14, 8), (16, 10)):
                ours, gp = os.path.join(tmp, "ours.glb"), os.path.join(tmp, "gltfpack.glb")
                params = {"mode": "none", "output": {"compression": "meshopt", "position_bits": bits, "normal_bits": nbits}}
                run([args.cli, ref, ours, "--params", json.dumps(params)])
                run([gltfpack, "-c", "-vp", str(bits), "-vn", str(nbits), "-i", ref, "-o", gp])
                sizes = [os.path.getsize(f) for f in (ours, gp)]
                gz = [len(gzip.compress(open(f, "rb").read(), 9)) for f in (ours, gp)]
                timed = json.loads(run(["node", "time_gltf_read.mjs", str(args.runs), ours, gp], cwd=args.tools).strip().splitlines()[-1])
                ms = [f["median_ms"] for f in timed["files"]]
                cli_ms = []
                for f in (ours, gp):
                    times = []
                    for _ in range(max(3, args.runs // 3)):
                        start = time.perf_counter()
                        run([args.cli, "--mode", "none", f, os.path.join(tmp, "back.off")])
                        times.append((time.perf_counter() - start) * 1000)
                    cli_ms.append(statistics.median(times))
                print("%-14s %7d %3d/%-2d | %9d %9d %6.3f | %9d %9d %6.3f | %8.2f %8.2f | %8.1f %8.1f"
                      % (name, faces, bits, nbits, sizes[0], sizes[1], sizes[0] / sizes[1], gz[0], gz[1], gz[0] / gz[1],
                         ms[0], ms[1], cli_ms[0], cli_ms[1]))


if __name__ == "__main__":
    main()
