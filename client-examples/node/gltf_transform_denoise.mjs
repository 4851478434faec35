#!/usr/bin/env node
// A glTF-Transform custom transform that sends the document through meshdenoise-server as one
// step of a pipeline: the document is written as GLB, denoised by the service, and read back
// into the same Document (its root is replaced by the denoised asset's).
//
//   import { denoiseTransform } from './gltf_transform_denoise.mjs';
//   await document.transform(dedup(), denoiseTransform({ params: { n_normal: 20 } }), prune());
//
// Usage as a script: node gltf_transform_denoise.mjs <in.glb> <out.glb> [params-json]
// Needs @gltf-transform/core, /extensions, /functions and draco3dgltf (tests/tools/package.json pins them).
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import { mergeDocuments } from '@gltf-transform/functions';
import draco3d from 'draco3dgltf';
import { ClientError, denoise } from './denoise_client.mjs';

export async function createIO() {
  return new NodeIO().registerExtensions(ALL_EXTENSIONS).registerDependencies({
    'draco3d.decoder': await draco3d.createDecoderModule(),
    'draco3d.encoder': await draco3d.createEncoderModule(),
  });
}

export function denoiseTransform({ params = {}, baseUrl } = {}) {
  return async function denoiseStep(document) {
    const io = await createIO();
    const glb = await io.writeBinary(document);
    const result = await denoise(glb, 'model/gltf-binary', { ...params, output: { format: 'glb', ...(params.output ?? {}) } },
                                 baseUrl);
    const denoised = await io.readBinary(result.bytes);
    // Replace the document's content with the denoised one, keeping the Document object (the
    // service may reorder vertices, e.g. through Draco, so positions cannot be copied by index).
    const root = document.getRoot();
    for (const list of [root.listScenes(), root.listNodes(), root.listMeshes(), root.listSkins(), root.listAnimations(),
                        root.listCameras(), root.listMaterials(), root.listTextures(), root.listAccessors(),
                        root.listBuffers()]) {
      for (const property of list) property.dispose();
    }
    mergeDocuments(document, denoised);
    const scenes = root.listScenes();
    if (scenes.length) root.setDefaultScene(scenes[0]);
    document.getLogger().info(`meshdenoise: ${result.timing}`);
  };
}

if (import.meta.url === `file://${process.argv[1]}`) {
  const [input, output, params = '{}'] = process.argv.slice(2);
  try {
    const io = await createIO();
    const document = await io.read(input);
    await document.transform(denoiseTransform({ params: JSON.parse(params) }));
    await io.write(output, document);
  } catch (e) {
    if (!(e instanceof ClientError)) throw e;
    console.error(`gltf_transform_denoise.mjs: ${e.message}`);  // the server could not be reached or refused the mesh
    process.exitCode = e.exitCode;
  }
}
