// The page's Web Worker: everything that walks a whole mesh runs here, off the main thread, so
// the page keeps answering while a 64 MB file is read. Messages {id, op, ...} are answered
// {id, result} or {id, error} (an error text a person can read). Ops:
//   parse  {blob, format, info}  OFF (read here), OBJ, PLY, STL (three.js loaders) ->
//          {positions: Float32Array, indices: Uint32Array, info (null when info is false)}; coincident vertices of
//          formats that store triangles apart (STL, OBJ as three reads it) are welded.
//   info   {positions, indices} -> info (vertices, faces, bounding box, open edges)
//   moved  {before, beforeIndices, after, afterIndices} -> per `after` vertex how far it moved
//          ({moved, signed (along the normal), exact: vertices matched by index, else by
//          nearest position}), and the mean edge length of `before` (the heat map's unit)
// glTF and Draco are decoded on the main thread (GLTFLoader needs the DOM for textures; Draco
// runs in DRACOLoader's own workers), then sent here for `info`.
import { OBJLoader } from './vendor/three/examples/jsm/loaders/OBJLoader.js';
import { PLYLoader } from './vendor/three/examples/jsm/loaders/PLYLoader.js';
import { STLLoader } from './vendor/three/examples/jsm/loaders/STLLoader.js';

// An error whose message is meant for the page as it is.
class ReadError extends Error {}

// OFF, COFF, NOFF, CNOFF (ASCII), read from the bytes without building strings (a 3.6 MB file
// in tens of milliseconds): a vertex line's first three numbers are its position (colours and
// normals follow), a face line is a count and that many indices (a colour may follow); polygons
// are fanned into triangles; '#' starts a comment, blank lines are skipped.
function parseOff(bytes) {
  const n = bytes.length;
  let at = 0, line = 1;
  // Past blanks and comments, to the start of the next line that holds something.
  const nextItem = () => {
    while (at < n) {
      const c = bytes[at];
      if (c === 10) { ++line; ++at; } else if (c === 32 || c === 9 || c === 13) ++at;
      else if (c === 35) { while (at < n && bytes[at] !== 10) ++at; } else return true;
    }
    return false;
  };
  // The next number on this line, or NaN (none before the line's end, or not a number).
  const number = () => {
    while (at < n && (bytes[at] === 32 || bytes[at] === 9 || bytes[at] === 13)) ++at;
    let c = bytes[at], sign = 1, mant = 0, scale = 0, digits = 0;
    if (c === 45) { sign = -1; c = bytes[++at]; } else if (c === 43) c = bytes[++at];
    while (c >= 48 && c <= 57) { mant = mant * 10 + (c - 48); ++digits; c = bytes[++at]; }
    if (c === 46) {
      c = bytes[++at];
      while (c >= 48 && c <= 57) { mant = mant * 10 + (c - 48); --scale; ++digits; c = bytes[++at]; }
    }
    if (digits === 0) return NaN;
    if (c === 101 || c === 69) {
      c = bytes[++at];
      let es = 1, e = 0;
      if (c === 45) { es = -1; c = bytes[++at]; } else if (c === 43) c = bytes[++at];
      while (c >= 48 && c <= 57) { e = e * 10 + (c - 48); c = bytes[++at]; }
      scale += es * e;
    }
    if (!(at >= n || c === 32 || c === 9 || c === 13 || c === 10 || c === 35)) return NaN;
    return sign * (scale === 0 ? mant : scale < 0 ? mant / 10 ** -scale : mant * 10 ** scale);
  };
  const endLine = () => { while (at < n && bytes[at] !== 10) ++at; };
  const notNumber = () => new ReadError(`line ${line} holds something that is not a number`);

  if (!nextItem()) throw new ReadError('the file is empty');
  const begin = at;
  while (at < n && bytes[at] > 32 && bytes[at] !== 35) ++at;
  if (!/^[CN]*OFF$/.test(String.fromCharCode(...bytes.subarray(begin, Math.min(at, begin + 16))))) throw new ReadError('its first line is not an OFF header');
  let nv = number();
  if (Number.isNaN(nv)) { endLine(); nextItem(); nv = number(); }
  const nf = number();
  if (!(Number.isInteger(nv) && Number.isInteger(nf) && nv >= 0 && nf >= 0)) throw new ReadError('its vertex and face counts are missing');
  endLine();
  const positions = new Float32Array(nv * 3);
  for (let i = 0; i < nv; ++i) {
    if (!nextItem()) throw new ReadError(`it declares ${nv} vertices and ${nf} faces but ends after ${i} vertices`);
    const x = number(), y = number(), z = number();
    if (Number.isNaN(x) || Number.isNaN(y) || Number.isNaN(z)) throw i === 0 && Number.isNaN(x) ? notNumber() : new ReadError(`vertex ${i} (line ${line}) is not three numbers`);
    positions[3 * i] = x; positions[3 * i + 1] = y; positions[3 * i + 2] = z;
    endLine();
  }
  let indices = new Uint32Array(Math.max(3, nf * 3));
  let used = 0;
  for (let f = 0; f < nf; ++f) {
    if (!nextItem()) throw new ReadError(`it declares ${nv} vertices and ${nf} faces but ends after ${f} faces`);
    const corners = number();
    if (!(Number.isInteger(corners) && corners >= 0)) throw new ReadError(`face ${f} (line ${line}) does not start with its corner count`);
    if (used + 3 * corners > indices.length) {
      const bigger = new Uint32Array(2 * indices.length + 3 * corners);
      bigger.set(indices);
      indices = bigger;
    }
    let first = 0, prev = 0;
    for (let c = 0; c < corners; ++c) {
      const v = number();
      if (!(Number.isInteger(v) && v >= 0 && v < nv)) {
        throw new ReadError(Number.isNaN(v) ? `face ${f} (line ${line}) lists fewer corners than its count` : `face ${f} refers to vertex ${v}, which does not exist (the file has ${nv})`);
      }
      if (c === 0) first = v;
      else if (c >= 2) { indices[used++] = first; indices[used++] = prev; indices[used++] = v; }
      prev = v;
    }
    endLine();
  }
  return { positions, indices: indices.slice(0, used) };
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
      return parseOff(new Uint8Array(bytes));
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
      const dx = p[a] - p[b], dy = p[a + 1] - p[b + 1], dz = p[a + 2] - p[b + 2];
      sum += Math.sqrt(dx * dx + dy * dy + dz * dz);
      ++n;
    }
  }
  return n ? sum / n : 0;
}

// Area-weighted vertex normals (unit, or zero for a vertex of degenerate faces only).
function vertexNormals(p, idx) {
  const nrm = new Float32Array(p.length);
  for (let f = 0; f + 2 < idx.length; f += 3) {
    const a = 3 * idx[f], b = 3 * idx[f + 1], c = 3 * idx[f + 2];
    const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
    const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
    const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;  // twice the area
    nrm[a] += nx; nrm[a + 1] += ny; nrm[a + 2] += nz;
    nrm[b] += nx; nrm[b + 1] += ny; nrm[b + 2] += nz;
    nrm[c] += nx; nrm[c + 1] += ny; nrm[c + 2] += nz;
  }
  for (let i = 0; i < nrm.length; i += 3) {
    const l = Math.sqrt(nrm[i] * nrm[i] + nrm[i + 1] * nrm[i + 1] + nrm[i + 2] * nrm[i + 2]);
    if (l > 0) { nrm[i] /= l; nrm[i + 1] /= l; nrm[i + 2] /= l; }
  }
  return nrm;
}

function sameArray(a, b) {
  if (a.length !== b.length) return false;
  for (let i = 0; i < a.length; ++i) if (a[i] !== b[i]) return false;
  return true;
}

// How far each vertex of `after` moved, unsigned and signed (along the result's vertex normal:
// positive outwards). When both meshes have the same vertices and faces in the same order (the
// service keeps the input's order in every format but Draco), vertex i of one is vertex i of the
// other and the displacement is exact. Otherwise each result vertex is matched with the nearest
// input vertex (a uniform grid of cell `cell` keeps it linear in the vertex count), which equals
// the displacement while a vertex moves less than half the distance to its neighbours.
function displacements(P, Pidx, Q, Qidx, cell) {
  const moved = new Float32Array(Q.length / 3), signed = new Float32Array(Q.length / 3);
  const normals = vertexNormals(Q, Qidx);
  const exact = P.length === Q.length && sameArray(Pidx, Qidx);
  const match = exact ? (j) => j : nearest(P, Q, cell);
  for (let j = 0; j < Q.length; j += 3) {
    const i = match(j);
    const dx = Q[j] - P[i], dy = Q[j + 1] - P[i + 1], dz = Q[j + 2] - P[i + 2];
    moved[j / 3] = Math.sqrt(dx * dx + dy * dy + dz * dz);
    signed[j / 3] = dx * normals[j] + dy * normals[j + 1] + dz * normals[j + 2];
  }
  return { moved, signed, exact };
}

// j (3 x a vertex of Q) -> 3 x the nearest vertex of P.
function nearest(P, Q, cell) {
  const size = cell > 0 ? cell : 1;
  const grid = new Map();
  const key = (x, y, z) => `${x},${y},${z}`;
  for (let i = 0; i < P.length; i += 3) {
    const k = key(Math.floor(P[i] / size), Math.floor(P[i + 1] / size), Math.floor(P[i + 2] / size));
    let list = grid.get(k);
    if (!list) grid.set(k, list = []);
    list.push(i);
  }
  return (j) => {
    const cx = Math.floor(Q[j] / size), cy = Math.floor(Q[j + 1] / size), cz = Math.floor(Q[j + 2] / size);
    let best = Infinity, at = 0;
    // Rings of cells around the point, until no unvisited cell can hold a closer vertex.
    for (let r = 0; r < 64 && !(best <= (r - 1) * size); ++r) {
      for (let dx = -r; dx <= r; ++dx) for (let dy = -r; dy <= r; ++dy) for (let dz = -r; dz <= r; ++dz) {
        if (Math.max(Math.abs(dx), Math.abs(dy), Math.abs(dz)) !== r) continue;
        const list = grid.get(key(cx + dx, cy + dy, cz + dz));
        if (!list) continue;
        for (const i of list) {
          const d = (P[i] - Q[j]) ** 2 + (P[i + 1] - Q[j + 1]) ** 2 + (P[i + 2] - Q[j + 2]) ** 2;
          if (d < best * best) { best = Math.sqrt(d); at = i; }
        }
      }
    }
    return at;
  };
}

self.onmessage = async ({ data }) => {
  const { id, op } = data;
  try {
    let result, transfer = [];
    if (op === 'parse') {
      const mesh = await parse(data.blob, data.format);
      if (mesh.indices.length === 0) throw new ReadError('it holds no triangles');
      result = { ...mesh, info: data.info === false ? null : info(mesh.positions, mesh.indices) };
      transfer = [mesh.positions.buffer, mesh.indices.buffer];
    } else if (op === 'info') {
      result = info(data.positions, data.indices);
    } else if (op === 'moved') {
      const edge = meanEdgeLength(data.before, data.beforeIndices);
      const { moved, signed, exact } = displacements(data.before, data.beforeIndices, data.after, data.afterIndices, edge);
      result = { moved, signed, exact, edge };
      transfer = [moved.buffer, signed.buffer];
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
