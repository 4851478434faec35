// Reads a .glb / .gltf with tools we did not write and prints one JSON line:
// {"errors": n, "warnings": n, "messages": [...], "meshes": [[{"mode", "vertices", "indices", "attributes"}]]}
// errors / warnings: the Khronos glTF validator; meshes: glTF-Transform (Draco via draco3dgltf,
// EXT_meshopt_compression via meshoptimizer's decoder); meshWorld[m]: the world matrix (column-
// major) of the first node that instances mesh m, or null (quantized positions need it).
import { readFile } from 'node:fs/promises';
import validator from 'gltf-validator';
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import draco3d from 'draco3dgltf';
import { MeshoptDecoder } from 'meshoptimizer';

const path = process.argv[2];
const bytes = new Uint8Array(await readFile(path));
const report = await validator.validateBytes(bytes, { maxIssues: 50 });
const messages = report.issues.messages.filter((m) => m.severity <= 1).map((m) => `${m.code} ${m.pointer ?? ''} ${m.message}`);

const io = new NodeIO().registerExtensions(ALL_EXTENSIONS).registerDependencies({
  'draco3d.decoder': await draco3d.createDecoderModule(),
  'meshopt.decoder': await MeshoptDecoder.ready.then(() => MeshoptDecoder),
});
const doc = path.endsWith('.gltf') ? await io.readJSON({ json: JSON.parse(new TextDecoder().decode(bytes)), resources: {} })
                                   : await io.readBinary(bytes);
const meshes = doc.getRoot().listMeshes().map((mesh) => mesh.listPrimitives().map((prim) => {
  const attributes = {};
  for (const semantic of prim.listSemantics()) {
    const acc = prim.getAttribute(semantic);
    attributes[semantic] = { count: acc.getCount(), type: acc.getType(), componentType: acc.getComponentType() };
  }
  const pos = prim.getAttribute('POSITION');
  const uv = prim.getAttribute('TEXCOORD_0');
  const idx = prim.getIndices();
  // Per corner: position and uv, so the test can compare against the input independent of vertex order.
  const corners = [];
  const n = idx ? idx.getCount() : pos.getCount();
  for (let i = 0; i < n; i++) {
    const v = idx ? idx.getScalar(i) : i;
    corners.push([...pos.getElement(v, []), ...(uv ? uv.getElement(v, []) : [])]);
  }
  return { mode: prim.getMode(), vertices: pos.getCount(), indices: idx ? idx.getCount() : null, attributes, corners };
}));
const meshWorld = doc.getRoot().listMeshes().map((mesh) => {
  const node = doc.getRoot().listNodes().find((n) => n.getMesh() === mesh);
  return node ? node.getWorldMatrix() : null;
});
console.log(JSON.stringify({ errors: report.issues.numErrors, warnings: report.issues.numWarnings, messages, meshes, meshWorld,
  extensionsUsed: doc.getRoot().listExtensionsUsed().map((e) => e.extensionName) }));
