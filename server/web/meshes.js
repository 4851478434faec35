// Mesh bytes to triangles for display, and how far the result's vertices moved.
// Every format the service reads is drawn: glb / gltf (GLTFLoader, Draco through DRACOLoader),
// drc (DRACOLoader), obj (OBJLoader), ply (PLYLoader), off (read here: three.js has no OFF
// reader). The result is one indexed BufferGeometry in world coordinates.
import * as THREE from './vendor/three/build/three.module.js';
import { GLTFLoader } from './vendor/three/examples/jsm/loaders/GLTFLoader.js';
import { DRACOLoader } from './vendor/three/examples/jsm/loaders/DRACOLoader.js';
import { OBJLoader } from './vendor/three/examples/jsm/loaders/OBJLoader.js';
import { PLYLoader } from './vendor/three/examples/jsm/loaders/PLYLoader.js';

const draco = new DRACOLoader().setDecoderPath('/web/vendor/three/examples/jsm/libs/draco/');

// The container of a file: its extension, else its first bytes (as the server sniffs).
export function formatOf(name, bytes) {
  const ext = /\.([a-z0-9]+)$/i.exec(name ?? '')?.[1]?.toLowerCase();
  if (['glb', 'gltf', 'drc', 'off', 'obj', 'ply'].includes(ext)) return ext;
  const head = new TextDecoder().decode(new Uint8Array(bytes, 0, Math.min(64, bytes.byteLength)));
  if (head.startsWith('glTF')) return 'glb';
  if (head.startsWith('DRACO')) return 'drc';
  if (/^\s*\{/.test(head)) return 'gltf';
  if (/^ply\s/.test(head)) return 'ply';
  if (/^\s*[CN]*OFF/.test(head)) return 'off';
  if (/^\s*(#|v |o |g |mtllib)/m.test(head)) return 'obj';
  return null;
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
  return geometryOf(new Float32Array(positions), indices);
}

function geometryOf(positions, indices) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  g.setIndex(new THREE.BufferAttribute(positions.length / 3 > 65535 ? new Uint32Array(indices) : new Uint16Array(indices), 1));
  return g;
}

// OFF, COFF, NOFF, CNOFF (ASCII), line by line: a vertex line's first three numbers are its
// position (colours and normals follow), a face line is a count and that many indices (a colour
// may follow); polygons are fanned into triangles.
function parseOff(text) {
  const lines = text.split('\n').map((l) => l.replace(/#.*/, '').trim()).filter((l) => l !== '');
  const first = lines.shift()?.split(/\s+/) ?? [];
  if (!/^[CN]*OFF$/.test(first[0] ?? '')) throw new Error('not an OFF file');
  const counts = (first.length > 1 ? first.slice(1) : lines.shift()?.split(/\s+/) ?? []).map(Number);
  const [nv, nf] = counts;
  if (!(nv >= 0 && nf >= 0) || lines.length < nv + nf) throw new Error('OFF counts do not match the file');
  const positions = new Float32Array(nv * 3);
  for (let i = 0; i < nv; ++i) {
    const xyz = lines[i].split(/\s+/, 3).map(Number);
    positions.set(xyz, 3 * i);
  }
  const indices = [];
  for (let f = 0; f < nf; ++f) {
    const t = lines[nv + f].split(/\s+/).map(Number);
    for (let k = 2; k < t[0]; ++k) indices.push(t[1], t[k], t[k + 1]);
  }
  if (!indices.every((i) => Number.isInteger(i) && i >= 0 && i < nv)) throw new Error('OFF face index out of range');
  return geometryOf(positions, indices);
}

// Bytes -> { geometry, format }. Throws when the browser cannot draw them (the server decides
// what it accepts; the page then shows the result alone).
export async function loadMesh(bytes, format) {
  switch (format) {
    case 'glb': case 'gltf': {
      const loader = new GLTFLoader().setDRACOLoader(draco);
      const gltf = await new Promise((resolve, reject) => loader.parse(format === 'glb' ? bytes : new TextDecoder().decode(bytes), '', resolve, reject));
      return merge(gltf.scene);
    }
    case 'drc': {
      const g = await new Promise((resolve, reject) => draco.parse(bytes, resolve, reject));
      return geometryOf(g.getAttribute('position').array.slice(), g.index ? Array.from(g.index.array) : [...Array(g.getAttribute('position').count).keys()]);
    }
    case 'obj':
      return merge(new OBJLoader().parse(new TextDecoder().decode(bytes)));
    case 'ply': {
      const g = new PLYLoader().parse(bytes);
      const p = g.getAttribute('position');
      return geometryOf(p.array.slice(), g.index ? Array.from(g.index.array) : [...Array(p.count).keys()]);
    }
    case 'off':
      return parseOff(new TextDecoder().decode(bytes));
    default:
      throw new Error(`no reader for ${format ?? 'this file'}`);
  }
}

// Mean length of the triangle edges (each edge once per triangle side).
export function meanEdgeLength(geometry) {
  const p = geometry.getAttribute('position').array, idx = geometry.index.array;
  let sum = 0, n = 0;
  for (let f = 0; f + 2 < idx.length; f += 3) {
    for (let k = 0; k < 3; ++k) {
      const a = 3 * idx[f + k], b = 3 * idx[f + (k + 1) % 3];
      sum += Math.hypot(p[a] - p[b], p[a + 1] - p[b + 1], p[a + 2] - p[b + 2]);
      ++n;
    }
  }
  return n ? sum / n : 0;
}

// For every vertex of `after`, its distance to the nearest vertex of `before`: how far it moved,
// whatever order the two files store their vertices in (Draco reorders them). Equal to the true
// displacement while a vertex moves less than half the distance to its neighbours, which holds
// for denoising; a uniform grid of cell `cell` keeps it linear in the vertex count.
export function displacements(before, after, cell) {
  const P = before.getAttribute('position').array, Q = after.getAttribute('position').array;
  const size = cell > 0 ? cell : 1;
  const grid = new Map();
  const key = (x, y, z) => `${x},${y},${z}`;
  for (let i = 0; i < P.length; i += 3) {
    const k = key(Math.floor(P[i] / size), Math.floor(P[i + 1] / size), Math.floor(P[i + 2] / size));
    let list = grid.get(k);
    if (!list) grid.set(k, list = []);
    list.push(i);
  }
  const out = new Float32Array(Q.length / 3);
  for (let j = 0; j < Q.length; j += 3) {
    const cx = Math.floor(Q[j] / size), cy = Math.floor(Q[j + 1] / size), cz = Math.floor(Q[j + 2] / size);
    let best = Infinity;
    // Rings of cells around the point, until no unvisited cell can hold a closer vertex.
    for (let r = 0; r < 64 && !(best <= (r - 1) * size); ++r) {
      for (let dx = -r; dx <= r; ++dx) for (let dy = -r; dy <= r; ++dy) for (let dz = -r; dz <= r; ++dz) {
        if (Math.max(Math.abs(dx), Math.abs(dy), Math.abs(dz)) !== r) continue;
        const list = grid.get(key(cx + dx, cy + dy, cz + dz));
        if (!list) continue;
        for (const i of list) {
          const d = (P[i] - Q[j]) ** 2 + (P[i + 1] - Q[j + 1]) ** 2 + (P[i + 2] - Q[j + 2]) ** 2;
          if (d < best * best) best = Math.sqrt(d);
        }
      }
    }
    out[j / 3] = best;
  }
  return out;
}
