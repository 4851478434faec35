// Times reading .glb files with glTF-Transform's NodeIO (EXT_meshopt_compression through
// meshoptimizer's WebAssembly decoder, KHR_draco_mesh_compression through draco3dgltf), as a
// pipeline's loader does, and prints one JSON line: {"files": [{file, bytes, median_ms, runs}]}.
// The median of RUNS reads, the files taking turns, after five warm-up rounds (the JIT would
// otherwise charge the first file for it). Used by tests/bench/meshopt_bench.py.
//   usage: node time_gltf_read.mjs RUNS FILE...
import { readFile } from 'node:fs/promises';
import { performance } from 'node:perf_hooks';
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import { MeshoptDecoder } from 'meshoptimizer';
import draco3d from 'draco3dgltf';

const [runsText, ...files] = process.argv.slice(2);
const runs = Number(runsText);
if (!Number.isInteger(runs) || runs < 1 || files.length === 0) {
  console.error('usage: node time_gltf_read.mjs RUNS FILE...');
  process.exit(2);
}
await MeshoptDecoder.ready;
const io = new NodeIO().registerExtensions(ALL_EXTENSIONS).registerDependencies({
  'meshopt.decoder': MeshoptDecoder,
  'draco3d.decoder': await draco3d.createDecoderModule(),
});
const inputs = [];
for (const file of files) inputs.push({ file, bytes: new Uint8Array(await readFile(file)), times: [] });
for (let round = 0; round < 5; round++) for (const input of inputs) await io.readBinary(input.bytes);
for (let i = 0; i < runs; i++)
  for (const input of inputs) {
    const start = performance.now();
    await io.readBinary(input.bytes);
    input.times.push(performance.now() - start);
  }
const out = inputs.map(({ file, bytes, times }) => {
  times.sort((a, b) => a - b);
  return { file, bytes: bytes.length, median_ms: times[Math.floor(times.length / 2)], runs };
});
console.log(JSON.stringify({ files: out }));
