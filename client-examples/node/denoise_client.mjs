#!/usr/bin/env node
// meshdenoise-server client for Node 18+ (built-in fetch; no packages).
// Usage: node denoise_client.mjs <input> <output> [params-json]
// Environment: MDN_URL (default http://127.0.0.1:8080), MDN_TOKEN (bearer token, optional).
import { readFile, writeFile } from 'node:fs/promises';
import { extname } from 'node:path';

const MEDIA_TYPES = {
  '.glb': 'model/gltf-binary', '.gltf': 'model/gltf+json', '.drc': 'model/x-draco',
  '.off': 'model/x-off', '.obj': 'model/obj', '.ply': 'model/x-ply',
};

export async function denoise(bytes, mediaType, params = {}, baseUrl = process.env.MDN_URL ?? 'http://127.0.0.1:8080') {
  const headers = { 'Content-Type': mediaType, 'X-Denoise-Params': JSON.stringify(params) };
  if (process.env.MDN_TOKEN) headers.Authorization = `Bearer ${process.env.MDN_TOKEN}`;
  const response = await fetch(`${baseUrl}/v1/denoise`, { method: 'POST', headers, body: bytes });
  if (!response.ok) {
    // RFC 9457 problem+json: type, title, status, detail, request_id (and field for parameters).
    const problem = await response.json();
    throw new Error(`${problem.status} ${problem.title}: ${problem.detail} (request ${problem.request_id})`);
  }
  return {
    bytes: new Uint8Array(await response.arrayBuffer()),
    mediaType: response.headers.get('Content-Type'),
    params: JSON.parse(response.headers.get('X-Denoise-Params')),
    timing: response.headers.get('Server-Timing'),
  };
}

if (import.meta.url === `file://${process.argv[1]}`) {
  const [input, output, params = '{}'] = process.argv.slice(2);
  const bytes = await readFile(input);
  const result = await denoise(bytes, MEDIA_TYPES[extname(input).toLowerCase()] ?? 'application/octet-stream',
                               JSON.parse(params));
  console.error('timings:', result.timing);
  await writeFile(output, result.bytes);
}
