// Renders before/after pictures of denoised meshes in headless Chromium with three.js (both
// from tests/tools' pinned npm packages; scripts/make-figures.sh runs it): one row per mesh, the
// noisy input, the result, and the result coloured by how far each vertex moved (in mean edge
// lengths of the input), with the colour scale.
//   usage: node scripts/render_figures.mjs OUT.png STAMP TITLE NOISY.off DENOISED.off [TITLE NOISY.off DENOISED.off]...
// The OFF files must have the same vertices and faces in the same order (what meshdenoise
// writes). Bounded: 120 s, then the browser is closed and the exit status is 1.
import { createServer } from 'node:http';
import { createReadStream, readFileSync, statSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const tools = path.join(root, 'tests', 'tools');
const require = createRequire(path.join(tools, 'package.json'));
const puppeteer = require('puppeteer-core');

const [out, stamp, ...rest] = process.argv.slice(2);
if (!out || !stamp || rest.length === 0 || rest.length % 3 !== 0) {
  console.error('usage: node scripts/render_figures.mjs OUT.png STAMP TITLE NOISY.off DENOISED.off [...]');
  process.exit(2);
}

// An OFF file's positions and triangles (what meshdenoise writes: "OFF", counts, rows).
function readOff(file) {
  const tokens = readFileSync(file, 'utf8').replace(/#[^\n]*/g, ' ').split(/\s+/).filter(Boolean);
  if (!/OFF$/.test(tokens[0])) throw new Error(`${file}: not an OFF file`);
  const [nv, nf] = [Number(tokens[1]), Number(tokens[2])];
  let t = 4;
  const positions = new Float32Array(nv * 3);
  for (let i = 0; i < nv * 3; i++) positions[i] = Number(tokens[t++]);
  const indices = [];
  for (let f = 0; f < nf; f++) {
    const n = Number(tokens[t++]);
    const corners = tokens.slice(t, t + n).map(Number);
    t += n;
    for (let k = 1; k + 1 < n; k++) indices.push(corners[0], corners[k], corners[k + 1]);
  }
  return { positions: Array.from(positions), indices };
}

const meshes = [];
for (let i = 0; i < rest.length; i += 3) {
  const noisy = readOff(rest[i + 1]);
  const denoised = readOff(rest[i + 2]);
  if (noisy.positions.length !== denoised.positions.length || noisy.indices.length !== denoised.indices.length)
    throw new Error(`${rest[i + 1]} and ${rest[i + 2]} do not have the same vertices and faces`);
  meshes.push({ title: rest[i], noisy, denoised });
}

const page = `<!doctype html><html><head><meta charset="utf-8">
<script type="importmap">{ "imports": { "three": "/three/build/three.module.js" } }</script>
<style>
  body { margin: 0; background: #fff; font: 13px Helvetica, Arial, sans-serif; color: #222; }
  #grid { position: relative; }
  .label { position: absolute; font-size: 13px; }
  .row { position: absolute; font-weight: bold; font-size: 14px; }
  .legend { position: absolute; width: 180px; height: 10px; border: 1px solid #888; }
  .tick { position: absolute; font-size: 11px; }
  #stamp { position: absolute; font-size: 10px; color: #777; }
</style></head><body><div id="grid"></div><script type="module">
import * as THREE from 'three';
const meshes = await (await fetch('/meshes.json')).json();
const W = 400, H = 330, TOP = 28, ROWH = H + TOP + 34;
const grid = document.getElementById('grid');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(3 * W, meshes.length * ROWH + 20);
renderer.setClearColor(0xffffff, 1);
renderer.setScissorTest(true);
grid.appendChild(renderer.domElement);
const stops = [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551], [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]];
const colour = (t) => {  // viridis, five stops
  const x = Math.min(Math.max(t, 0), 1) * (stops.length - 1), i = Math.min(Math.floor(x), stops.length - 2), f = x - i;
  return stops[i].map((c, k) => c + f * (stops[i + 1][k] - c));
};
const add = (cls, text, x, y, style = '') => {
  const d = document.createElement('div');
  d.className = cls; d.textContent = text; d.style.left = x + 'px'; d.style.top = y + 'px'; d.style.cssText += style;
  grid.appendChild(d); return d;
};
function geometry(m, colours) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(m.positions, 3));
  g.setIndex(m.indices);
  if (colours) g.setAttribute('color', new THREE.Float32BufferAttribute(colours, 3));
  return g;
}
meshes.forEach((mesh, row) => {
  const n = mesh.noisy.positions, d = mesh.denoised.positions, idx = mesh.noisy.indices;
  // Mean edge length of the input, the unit of the displacement.
  let sum = 0, count = 0;
  for (let f = 0; f < idx.length; f += 3)
    for (let k = 0; k < 3; k++) {
      const a = idx[f + k] * 3, b = idx[f + (k + 1) % 3] * 3;
      sum += Math.hypot(n[a] - n[b], n[a + 1] - n[b + 1], n[a + 2] - n[b + 2]); count++;
    }
  const edge = sum / count;
  const moved = [];
  for (let i = 0; i < n.length; i += 3) moved.push(Math.hypot(d[i] - n[i], d[i + 1] - n[i + 1], d[i + 2] - n[i + 2]) / edge);
  const sorted = [...moved].sort((a, b) => a - b);
  const top = Math.max(sorted[Math.floor(0.99 * (sorted.length - 1))], 1e-9);  // the scale ends at the 99th percentile
  const colours = [];
  for (const m of moved) colours.push(...colour(m / top));
  const geoms = [geometry(mesh.noisy), geometry(mesh.denoised), geometry(mesh.denoised, colours)];
  geoms[0].computeBoundingSphere();
  const { center, radius } = geoms[0].boundingSphere;
  const camera = new THREE.PerspectiveCamera(30, W / H, radius / 100, radius * 100);
  camera.position.copy(center).add(new THREE.Vector3(1.0, 0.55, 1.25).normalize().multiplyScalar(radius * 3.1));
  camera.lookAt(center);
  const y0 = row * ROWH;
  add('row', mesh.title, 10, y0 + 4);
  ['noisy input', 'denoised (default parameters)', 'how far each vertex moved'].forEach((t, c) => add('label', t, c * W + 12, y0 + TOP - 4 + H + 4));
  geoms.forEach((g, c) => {
    const scene = new THREE.Scene();
    const material = c === 2 ? new THREE.MeshLambertMaterial({ vertexColors: true, flatShading: true })
                              : new THREE.MeshStandardMaterial({ color: 0xb8c0cc, roughness: 0.6, metalness: 0.0, flatShading: true });
    scene.add(new THREE.Mesh(g, material));
    scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, c === 2 ? 2.2 : 1.6));
    const light = new THREE.DirectionalLight(0xffffff, c === 2 ? 0.6 : 1.8);
    light.position.copy(camera.position).add(new THREE.Vector3(0, radius * 2, 0));
    scene.add(light);
    // three.js viewports count from the bottom of the canvas.
    const bottom = renderer.domElement.height - (y0 + TOP + H);
    renderer.setViewport(c * W, bottom, W, H);
    renderer.setScissor(c * W, bottom, W, H);
    renderer.render(scene, camera);
  });
  const bar = add('legend', '', 2 * W + 200, y0 + TOP + H + 8);
  bar.style.background = 'linear-gradient(to right, ' + stops.map((s) => 'rgb(' + s.map((c) => Math.round(c * 255)).join(',') + ')').join(',') + ')';
  add('tick', '0', 2 * W + 196, y0 + TOP + H + 20);
  add('tick', top.toFixed(2) + ' edge lengths', 2 * W + 300, y0 + TOP + H + 20, 'white-space: nowrap;');
});
add('', '', 0, 0).id = 'stamp';
const s = document.getElementById('stamp');
s.textContent = ${JSON.stringify(stamp)}; s.style.left = '10px'; s.style.top = (meshes.length * ROWH + 2) + 'px';
document.body.dataset.done = '1';
</script></body></html>`;

const threeRoot = path.join(tools, 'node_modules', 'three');
const server = createServer((req, res) => {
  const url = new URL(req.url, 'http://localhost');
  if (url.pathname === '/') return res.writeHead(200, { 'Content-Type': 'text/html' }).end(page);
  if (url.pathname === '/meshes.json') return res.writeHead(200, { 'Content-Type': 'application/json' }).end(JSON.stringify(meshes));
  const file = path.join(threeRoot, decodeURIComponent(url.pathname.replace(/^\/three\//, '')));
  let ok = false;
  try { ok = url.pathname.startsWith('/three/') && file.startsWith(threeRoot + path.sep) && statSync(file).isFile(); } catch { ok = false; }
  if (!ok) return res.writeHead(404).end('not found');
  res.writeHead(200, { 'Content-Type': file.endsWith('.js') ? 'text/javascript' : 'application/octet-stream' });
  createReadStream(file).pipe(res);
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));

const browser = await puppeteer.launch({
  executablePath: process.env.MDN_CHROMIUM ?? '/usr/bin/chromium',
  headless: true,
  // WebGL without a GPU: SwiftShader through ANGLE; only loopback is reachable.
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync', '--disable-extensions',
         '--disable-dev-shm-usage', '--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1'],
  defaultViewport: { width: 1200, height: meshes.length * 392 + 40 },
});
const timer = setTimeout(async () => {
  console.error('render_figures.mjs: the page did not finish within 120 s');
  await browser.close();
  process.exit(1);
}, 120_000);
try {
  const tab = await browser.newPage();
  const errors = [];
  tab.on('pageerror', (e) => errors.push(e.message));
  await tab.goto(`http://127.0.0.1:${server.address().port}/`);
  await tab.waitForSelector('body[data-done="1"]', { timeout: 110_000 }).catch(() => {
    throw new Error('the page did not render: ' + errors.join('; '));
  });
  await tab.screenshot({ path: out, fullPage: true });
} finally {
  clearTimeout(timer);
  await browser.close();
  server.close();
}
