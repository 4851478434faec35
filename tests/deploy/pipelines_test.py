#!/usr/bin/env python3
"""The pipelines users already run (issue 18), with the real tools pinned in tests/tools:

  gltf-transform optimize (EXT_meshopt_compression) -> service -> gltfpack -> Khronos validator
  gltfpack -c (EXT_meshopt_compression, KHR_mesh_quantization) -> service -> gltfpack -> validator
  gltf-transform draco    (KHR_draco_mesh_compression) -> service -> Khronos validator

against a live meshdenoise-server on loopback. The service must keep the input's compression
(meshopt in: meshopt out, quantized positions kept quantized, issue 51; Draco in: Draco out);
every output validates with no errors and loads in three.js (GLTFLoader + DRACOLoader +
MeshoptDecoder in headless Chromium, tests/tools/check_three.mjs).

Usage: pipelines_test.py --server BINARY --cli BINARY --tools DIR
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deploy_support import (Processes, TestFailure, check, free_port, log, noisy_icosphere_off, request,  # noqa: E402
                            run_main, tail, wait_http)


def run(args, cwd=None, what=None):
    r = subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise TestFailure("%s failed (exit %d):\n%s\n%s" % (what or args[0], r.returncode, r.stdout[-2000:], r.stderr[-2000:]))
    return r.stdout


def validate(tools, path):
    """check_gltf.mjs's report (Khronos validator + glTF-Transform read back)."""
    out = run(["node", os.path.join(tools, "check_gltf.mjs"), path], cwd=tools, what="check_gltf.mjs " + path)
    report = json.loads(out.strip().splitlines()[-1])
    check(report["errors"] == 0, "%s: %d validator errors: %s" % (path, report["errors"], report["messages"]))
    return report


def glb_position_type(glb):
    """(componentType, normalized) of the first primitive's POSITION in a .glb."""
    length = int.from_bytes(glb[12:16], "little")
    doc = json.loads(glb[20:20 + length])
    accessor = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]]
    return accessor["componentType"], accessor.get("normalized", False)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--server", required=True)
    ap.add_argument("--cli", required=True)
    ap.add_argument("--tools", required=True)
    args = ap.parse_args()
    bin_dir = os.path.join(args.tools, "node_modules", ".bin")
    gltf_transform, gltfpack = os.path.join(bin_dir, "gltf-transform"), os.path.join(bin_dir, "gltfpack")
    for tool in (gltf_transform, gltfpack):
        check(os.path.exists(tool), "%s missing: run npm ci --prefix tests/tools (scripts/install-deps.sh test)" % tool)

    processes = Processes()
    with tempfile.TemporaryDirectory(prefix="mdn_pipelines_") as tmp:
        p = lambda name: os.path.join(tmp, name)  # noqa: E731
        with open(p("noisy.off"), "wb") as f:
            f.write(noisy_icosphere_off(4, 0.2, 7))
        run([args.cli, "--mode", "none", p("noisy.off"), p("plain.glb")], what="meshdenoise --mode none")
        port = free_port()
        server = processes.start([args.server, "--port", str(port), "--workers", "1"], p("server.log"))
        try:
            wait_http(port, "/readyz", 30, server)

            def denoise(src, dst):
                with open(src, "rb") as f:
                    r = request(port, "POST", "/v1/denoise", f.read(), {"Content-Type": "model/gltf-binary"})
                check(r.status == 200, "POST %s: %d %s\n%s" % (src, r.status, r.body[:500], tail(server.log_path)))
                with open(dst, "wb") as f:
                    f.write(r.body)
                return r.body

            # 1. meshopt: glTF-Transform's default pipeline, then the service, then gltfpack.
            run([gltf_transform, "optimize", p("plain.glb"), p("optimized.glb")], what="gltf-transform optimize")
            check(b"EXT_meshopt_compression" in open(p("optimized.glb"), "rb").read(),
                  "gltf-transform optimize wrote no EXT_meshopt_compression")
            out = denoise(p("optimized.glb"), p("optimized-denoised.glb"))
            check(b"KHR_draco_mesh_compression" not in out and b"EXT_meshopt_compression" in out,
                  "meshopt in should give a meshopt glTF out")
            run([gltfpack, "-i", p("optimized-denoised.glb"), "-o", p("packed.glb")], what="gltfpack")
            # 1b. gltfpack's own meshopt (quantized positions), the service, gltfpack again.
            run([gltfpack, "-c", "-i", p("plain.glb"), "-o", p("gltfpack.glb")], what="gltfpack -c")
            out = denoise(p("gltfpack.glb"), p("gltfpack-denoised.glb"))
            check(b"EXT_meshopt_compression" in out and b"KHR_mesh_quantization" in out,
                  "a gltfpack input should come back with EXT_meshopt_compression and KHR_mesh_quantization")
            check(glb_position_type(out) == glb_position_type(open(p("gltfpack.glb"), "rb").read()),
                  "POSITION should keep gltfpack's component type: %s, was %s"
                  % (glb_position_type(out), glb_position_type(open(p("gltfpack.glb"), "rb").read())))
            run([gltfpack, "-c", "-i", p("gltfpack-denoised.glb"), "-o", p("gltfpack-repacked.glb")], what="gltfpack -c (again)")
            # 2. Draco: glTF-Transform's draco, then the service: Draco stays.
            run([gltf_transform, "draco", p("plain.glb"), p("draco.glb")], what="gltf-transform draco")
            check(b"KHR_draco_mesh_compression" in open(p("draco.glb"), "rb").read(), "gltf-transform draco wrote no Draco")
            out = denoise(p("draco.glb"), p("draco-denoised.glb"))
            check(b"KHR_draco_mesh_compression" in out, "Draco in should give Draco out")
        finally:
            processes.stop_all()

        outputs = ["optimized-denoised.glb", "packed.glb", "gltfpack-denoised.glb", "gltfpack-repacked.glb",
                   "draco-denoised.glb"]
        for name in outputs:
            report = validate(args.tools, p(name))
            log("%s: %d errors, %d warnings, %d bytes" % (name, report["errors"], report["warnings"], os.path.getsize(p(name))))
        three = run(["node", os.path.join(args.tools, "check_three.mjs"), tmp] + outputs, cwd=args.tools, what="check_three.mjs")
        reports = json.loads(three.strip().splitlines()[-1])["reports"]
        check(len(reports) == len(outputs), "three.js reported on %d of %d files" % (len(reports), len(outputs)))
        for r in reports:
            check("error" not in r and r.get("objects"), "three.js could not load %s: %s" % (r.get("file"), r))
            log("three.js loaded %s: %d objects" % (r["file"], len(r["objects"])))
    log("ok")


if __name__ == "__main__":
    run_main(main)
