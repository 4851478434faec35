// The page's Web Worker: everything that walks a whole mesh runs here, off the main thread, so
// the page keeps answering while a 64 MB file is read. Messages {id, op, ...} are answered
// {id, result} or {id, error} (an error text a person can read). Ops:
//   parse  {blob, format}  OFF (read here), OBJ, PLY, STL (three.js loaders) ->
//          {positions: Float32Array, indices: Uint32Array, info}; coincident vertices of
//          formats that store triangles apart (STL, OBJ as three reads it) are welded.
//   info   {positions, indices} -> info (vertices, faces, bounding box, open edges)
//   moved  {before, after, cell} -> per `after` vertex, the distance to the nearest `before`
//          vertex, and the mean edge length of `before` (the heat map's unit)
// glTF and Draco are decoded on the main thread (GLTFLoader needs the DOM for textures; Draco
// runs in DRACOLoader's own workers), then sent here for `info`.
import { OBJLoader } from './vendor/three/examples/jsm/loaders/OBJLoader.js';
import { PLYLoader } from './vendor/three/examples/jsm/loaders/PLYLoader.js';
import { STLLoader } from './vendor/three/examples/jsm/loaders/STLLoader.js';

// An error whose message is meant for the page as it is.
class ReadError extends Error {}

// OFF, COFF, NOFF, CNOFF (ASCII), line by line: a vertex line's first three numbers are its
// position (colours and normals follow), a face line is a count and that many indices (a colour
// may follow); polygons are fanned into triangles.
function parseOff(text) {
  const lines = text.split('\n').map((l) => l.replace(/#.*/, '').trim()).filter((l) => l !== '');
  const first = lines.shift()?.split(/\s+/) ?? [];
  if (!/^[CN]*OFF$/.test(first[0] ?? '')) throw new ReadError('its first line is not an OFF header');
  const counts = (first.length > 1 ? first.slice(1) : lines.shift()?.split(/\s+/) ?? []).map(Number);
  const [nv, nf] = counts;
  if (!(nv >= 0 && nf >= 0)) throw new ReadError('its vertex and face counts are missing');
  if (lines.length < nv + nf) throw new ReadError(`it declares ${nv} vertices and ${nf} faces but has fewer lines`);
  const positions = new Float32Array(nv * 3);
  for (let i = 0; i < nv; ++i) {
    const xyz = lines[i].split(/\s+/, 3).map(Number);
    if (!xyz.every(Number.isFinite)) throw new ReadError(`vertex ${i} is not three numbers`);
    positions.set(xyz, 3 * i);
  }
  const indices = [];
  for (let f = 0; f < nf; ++f) {
    const t = lines[nv + f].split(/\s+/).map(Number);
    for (let k = 2; k < t[0]; ++k) indices.push(t[1], t[k], t[k + 1]);
  }
  if (!indices.every((i) => Number.isInteger(i) && i >= 0 && i < nv)) throw new ReadError('a face refers to a vertex that does not exist');
  return { positions, indices: Uint32Array.from(indices) };
}

// Positions of separate triangles (or of an object tree flattened) -> shared vertices: equal
// coordinates become one vertex, so that counts and open edges mean what they do in the file's
// own mesh.
function weld(soup) {
  const map = new Map();
  const positions = [];
  const indices = new Uint32Array(soup.length / 3);
  for (let i = 0; i < soup.length; i += 3) {
    const key = `${soup[i]},${soup[i + 1]},${soup[i + 2]}`;
    let v = map.get(key);
    if (v === undefined) {
      v = positions.length / 3;
      map.set(key, v);
      positions.push(soup[i], soup[i + 1], soup[i + 2]);
    }
    indices[i / 3] = v;
  }
  return { positions: new Float32Array(positions), indices };
}

// Every mesh of a three.js object tree (OBJLoader's groups), world frame, welded.
function flatten(root) {
  root.updateMatrixWorld(true);
  const soup = [];
  root.traverse((node) => {
    if (!node.isMesh) return;  // points and lines are not surfaces
    const g = node.geometry.index ? node.geometry.toNonIndexed() : node.geometry;
    const p = g.getAttribute('position');
    if (!p) return;
    const e = node.matrixWorld.elements;
    for (let i = 0; i < p.count; ++i) {
      const x = p.getX(i), y = p.getY(i), z = p.getZ(i);
      soup.push(e[0] * x + e[4] * y + e[8] * z + e[12], e[1] * x + e[5] * y + e[9] * z + e[13], e[2] * x + e[6] * y + e[10] * z + e[14]);
    }
  });
  return weld(soup);
}

async function parse(blob, format) {
  const bytes = await blob.arrayBuffer();
  switch (format) {
    case 'off':
      return parseOff(new TextDecoder().decode(bytes));
    case 'obj':
      return flatten(new OBJLoader().parse(new TextDecoder().decode(bytes)));
    case 'ply': {
      const g = new PLYLoader().parse(bytes);
      const p = g.getAttribute('position');
      if (!g.index) return weld(p.array);
      return { positions: Float32Array.from(p.array), indices: Uint32Array.from(g.index.array) };
    }
    case 'stl':
      return weld(new STLLoader().parse(bytes).getAttribute('position').array);
    default:
      throw new ReadError('the browser has no reader for it');
  }
}

// Counts, bounding box and edges. An open edge belongs to one triangle (a hole's rim or the
// border of a patch); a non-manifold one to three or more.
function info(positions, indices) {
  const nv = positions.length / 3;
  const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i += 3) {
    for (let k = 0; k < 3; ++k) {
      const c = positions[i + k];
      if (c < min[k]) min[k] = c;
      if (c > max[k]) max[k] = c;
    }
  }
  const edges = new Map();
  for (let f = 0; f + 2 < indices.length; f += 3) {
    for (let k = 0; k < 3; ++k) {
      const a = indices[f + k], b = indices[f + (k + 1) % 3];
      const key = a < b ? a * nv + b : b * nv + a;
      edges.set(key, (edges.get(key) ?? 0) + 1);
    }
  }
  let open = 0, nonManifold = 0;
  for (const n of edges.values()) {
    if (n === 1) ++open;
    else if (n > 2) ++nonManifold;
  }
  return { vertices: nv, faces: Math.floor(indices.length / 3), edges: edges.size, open_edges: open,
           non_manifold_edges: nonManifold, min, max };
}

// Mean length of the triangle edges (each edge once per triangle side).
function meanEdgeLength(p, idx) {
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
function displacements(P, Q, cell) {
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

self.onmessage = async ({ data }) => {
  const { id, op } = data;
  try {
    let result, transfer = [];
    if (op === 'parse') {
      const mesh = await parse(data.blob, data.format);
      if (mesh.indices.length === 0) throw new ReadError('it holds no triangles');
      result = { ...mesh, info: info(mesh.positions, mesh.indices) };
      transfer = [mesh.positions.buffer, mesh.indices.buffer];
    } else if (op === 'info') {
      result = info(data.positions, data.indices);
    } else if (op === 'moved') {
      const edge = meanEdgeLength(data.before, data.beforeIndices);
      const moved = displacements(data.before, data.after, edge);
      result = { moved, edge };
      transfer = [moved.buffer];
    } else {
      throw new Error(`unknown op ${op}`);
    }
    self.postMessage({ id, result }, transfer);
  } catch (e) {
    // Our own reasons are for people; a loader's internal message ("Invalid typed array length")
    // is not, and is replaced by a plain one.
    self.postMessage({ id, error: e instanceof ReadError ? e.message : 'its contents are not what its format requires' });
  }
};
