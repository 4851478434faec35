#!/usr/bin/env node
// meshdenoise-server client for Node 18+ (built-in fetch; no packages).
// Usage: node denoise_client.mjs <input> <output> [params-json]
//   output: .off .obj .ply .stl .drc .glb or .gltf (sets the parameters' output.format)
// Environment: MDN_URL (default http://127.0.0.1:8080), MDN_TOKEN (bearer token, optional).
// Exit status: 0 done; 2 bad arguments (an input that cannot be read, an output extension that
// names no format, parameters that are not a JSON object), nothing sent; 1 the server could not
// be reached or refused the mesh (its problem+json title and detail are printed).
import { readFile, writeFile, stat } from 'node:fs/promises';
import { dirname, extname } from 'node:path';

const MEDIA_TYPES = {
  '.glb': 'model/gltf-binary', '.gltf': 'model/gltf+json', '.drc': 'model/x-draco',
  '.off': 'model/x-off', '.obj': 'model/obj', '.ply': 'model/x-ply', '.stl': 'model/stl',
};

// A failure with its exit status; the message is the one line printed.
export class ClientError extends Error {
  constructor(message, exitCode) {
    super(message);
    this.exitCode = exitCode;
  }
}

export async function denoise(bytes, mediaType, params = {}, baseUrl = process.env.MDN_URL ?? 'http://127.0.0.1:8080') {
  const headers = { 'Content-Type': mediaType, 'X-Denoise-Params': JSON.stringify(params) };
  if (process.env.MDN_TOKEN) headers.Authorization = `Bearer ${process.env.MDN_TOKEN}`;
  let response;
  try {
    response = await fetch(`${baseUrl}/v1/denoise`, { method: 'POST', headers, body: bytes });
  } catch (e) {  // refused, unknown host: fetch says "fetch failed", the cause says why
    throw new ClientError(`cannot reach the server at ${baseUrl}: ${e.cause?.code ?? e.cause?.message ?? e.message} ` +
                          '(is meshdenoise-server running? MDN_URL sets its address)', 1);
  }
  if (!response.ok) {
    // RFC 9457 problem+json: type, title, status, detail, request_id (and field for parameters).
    const text = await response.text();
    let problem;
    try {
      problem = JSON.parse(text);
    } catch {
      throw new ClientError(`the server answered ${response.status}: ${text.slice(0, 200).trim()}`, 1);
    }
    throw new ClientError(`the server answered ${response.status} ${problem.title}: ${problem.detail}`, 1);
  }
  return {
    bytes: new Uint8Array(await response.arrayBuffer()),
    mediaType: response.headers.get('Content-Type'),
    params: JSON.parse(response.headers.get('X-Denoise-Params')),
    timing: response.headers.get('Server-Timing'),
    // What ran, bounded (issue 51); the full report: ?report=1 or the async job's result.reports.
    summary: JSON.parse(response.headers.get('X-Denoise-Summary') ?? 'null'),
  };
}

// The input's bytes and media type and the parameters with output.format, or a ClientError (2).
async function checkedArguments(input, output, paramsText) {
  let bytes;
  try {
    bytes = await readFile(input);
  } catch (e) {
    throw new ClientError(`cannot read ${input}: ${e.code === 'ENOENT' ? 'no such file' : e.code ?? e.message}`, 2);
  }
  const ext = extname(output).toLowerCase();
  if (!(ext in MEDIA_TYPES))
    throw new ClientError(`cannot write ${output}: its extension names no format (use ${Object.keys(MEDIA_TYPES).join(', ')})`, 2);
  const folder = dirname(output);
  if (!(await stat(folder).then((s) => s.isDirectory(), () => false)))
    throw new ClientError(`cannot write ${output}: the folder ${folder} does not exist`, 2);
  let params;
  try {
    params = JSON.parse(paramsText);
  } catch (e) {
    throw new ClientError(`the parameters are not JSON: ${e.message}`, 2);
  }
  const isObject = (v) => typeof v === 'object' && v !== null && !Array.isArray(v);
  if (!isObject(params) || (params.output !== undefined && !isObject(params.output)))
    throw new ClientError('the parameters must be a JSON object (with "output" an object)', 2);
  const given = params.output?.format;
  if (given !== undefined && given !== ext.slice(1))
    throw new ClientError(`the parameters ask for output.format "${given}" but ${output} is ${ext}`, 2);
  params.output = { ...params.output, format: ext.slice(1) };
  return { bytes, mediaType: MEDIA_TYPES[extname(input).toLowerCase()] ?? 'application/octet-stream', params };
}

if (import.meta.url === `file://${process.argv[1]}`) {
  const args = process.argv.slice(2);
  try {
    if (args.length < 2 || args.length > 3) throw new ClientError('usage: node denoise_client.mjs <input> <output> [params-json]', 2);
    const [input, output, params = '{}'] = args;
    const checked = await checkedArguments(input, output, params);
    const result = await denoise(checked.bytes, checked.mediaType, checked.params);
    console.error('timings:', result.timing);
    await writeFile(output, result.bytes);
  } catch (e) {
    if (!(e instanceof ClientError)) throw e;
    console.error(`denoise_client.mjs: ${e.message}`);
    process.exitCode = e.exitCode;
  }
}
