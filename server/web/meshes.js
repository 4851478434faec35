// Mesh files to triangles for display, mesh information and how far the result's vertices
// moved. Every format the service reads is drawn: OFF, OBJ, PLY and STL are read in the page's
// worker (mesh_worker.js), off the main thread; glb / gltf (GLTFLoader, Draco through
// DRACOLoader, which has its own workers) and drc (DRACOLoader) here. A mesh is one indexed
// BufferGeometry in world coordinates.
import * as THREE from './vendor/three/build/three.module.js';
import { GLTFLoader } from './vendor/three/examples/jsm/loaders/GLTFLoader.js';
import { DRACOLoader } from './vendor/three/examples/jsm/loaders/DRACOLoader.js';

const draco = new DRACOLoader().setDecoderPath('/web/vendor/three/examples/jsm/libs/draco/');

// The formats the service reads, by extension (what the file input accepts).
export const FORMATS = ['glb', 'gltf', 'drc', 'off', 'obj', 'ply', 'stl'];
const NAMES = { glb: 'glTF binary', gltf: 'glTF', drc: 'Draco', off: 'OFF', obj: 'OBJ', ply: 'PLY', stl: 'STL' };
export const formatName = (format) => NAMES[format] ?? 'mesh';

// ---------------------------------------------------------------- the worker
const worker = new Worker(new URL('./mesh_worker.js', import.meta.url), { type: 'module' });
const pending = new Map();
let nextId = 0;
worker.onmessage = ({ data }) => {
  const p = pending.get(data.id);
  pending.delete(data.id);
  if (data.error !== undefined) p?.reject(new Error(data.error));
  else p?.resolve(data.result);
};
worker.onerror = (e) => {
  e.preventDefault();
  for (const p of pending.values()) p.reject(new Error('the browser stopped reading it'));
  pending.clear();
};
function call(message, transfer = []) {
  return new Promise((resolve, reject) => {
    const id = ++nextId;
    pending.set(id, { resolve, reject });
    worker.postMessage({ ...message, id }, transfer);
  });
}

// The container of a file: its extension, else its first bytes (as the server sniffs).
export async function formatOf(name, blob) {
  const ext = /\.([a-z0-9]+)$/i.exec(name ?? '')?.[1]?.toLowerCase();
  if (FORMATS.includes(ext)) return ext;
  const head = new TextDecoder().decode(await blob.slice(0, 84).arrayBuffer());
  if (head.startsWith('glTF')) return 'glb';
  if (head.startsWith('DRACO')) return 'drc';
  if (/^\s*\{/.test(head)) return 'gltf';
  if (/^ply\s/.test(head)) return 'ply';
  if (/^\s*[CN]*OFF/.test(head)) return 'off';
  if (/^solid\s/.test(head)) return 'stl';
  if (/^\s*(#|v |o |g |mtllib)/m.test(head)) return 'obj';
  return null;
}

function geometryOf(positions, indices) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  g.setIndex(new THREE.BufferAttribute(indices, 1));
  g.computeBoundingSphere();
  return g;
}

// Flattens every triangle mesh of an object tree into one indexed geometry (world frame).
function merge(root) {
  root.updateMatrixWorld(true);
  const positions = [], indices = [];
  let offset = 0;
  root.traverse((node) => {
    if (!node.isMesh) return;  // points and lines are not surfaces
    const g = node.geometry;
    const p = g.getAttribute('position');
    if (!p) return;
    const m = node.matrixWorld, v = new THREE.Vector3();
    for (let i = 0; i < p.count; ++i) {
      v.fromBufferAttribute(p, i).applyMatrix4(m);
      positions.push(v.x, v.y, v.z);
    }
    if (g.index) for (let i = 0; i < g.index.count; ++i) indices.push(g.index.getX(i) + offset);
    else for (let i = 0; i < p.count; ++i) indices.push(i + offset);
    offset += p.count;
  });
  return { positions: new Float32Array(positions), indices: Uint32Array.from(indices) };
}

async function parseHere(blob, format) {
  const bytes = await blob.arrayBuffer();
  if (format === 'drc') {
    const g = await new Promise((resolve, reject) => draco.parse(bytes, resolve, reject));
    const p = g.getAttribute('position');
    return { positions: Float32Array.from(p.array), indices: g.index ? Uint32Array.from(g.index.array) : Uint32Array.from({ length: p.count }, (_, i) => i) };
  }
  const loader = new GLTFLoader().setDRACOLoader(draco);
  const gltf = await new Promise((resolve, reject) => loader.parse(format === 'glb' ? bytes : new TextDecoder().decode(bytes), '', resolve, reject));
  return merge(gltf.scene);
}

// A file (Blob) -> { geometry, info }. Throws an Error whose message completes "The browser could
// not draw this file: ..." (the server is the judge of what it reads; the page then shows the
// result alone).
// Without `info` (a result: its counts come from the server) the edge count is skipped.
export async function loadMesh(blob, format, { info = true } = {}) {
  if (!FORMATS.includes(format)) throw new Error('its format was not recognised');
  let mesh;
  if (['glb', 'gltf', 'drc'].includes(format)) {
    try {
      mesh = await parseHere(blob, format);
    } catch {
      throw new Error(`it is not a ${formatName(format)} file the browser can read`);
    }
    if (mesh.indices.length === 0) throw new Error('it holds no triangles');
    if (info) mesh.info = await call({ op: 'info', positions: mesh.positions, indices: mesh.indices });
  } else {
    mesh = await call({ op: 'parse', blob, format, info });
  }
  return { geometry: geometryOf(mesh.positions, mesh.indices), info: mesh.info };
}

// How far each vertex of `after` moved: {moved, signed (along the result's normal, outwards
// positive), exact (matched by index; else by nearest position), edge (the mean edge length of
// `before`, the heat map's unit)}, in model units. Computed in the worker.
export function displacements(before, after) {
  return call({ op: 'moved', before: before.getAttribute('position').array, beforeIndices: before.index.array,
                after: after.getAttribute('position').array, afterIndices: after.index.array });
}
