// Before and after in one WebGL canvas with one camera: side by side (two viewports) or swipe
// (one viewport, the result drawn right of a movable split). Lit surfaces, flat (facets show
// noise and creases) or smooth; a wireframe overlay; the result can be coloured by how far each
// vertex moved, on the lit surface (the shape stays readable under the colours: each pixel is
// the legend's colour times the light's brightness, white lights only). Mouse, touch and keys:
// arrows turn the view, Shift+arrows pan, + and - zoom, 0 or Home frames the model again.
// Draws on demand only.
import * as THREE from './vendor/three/build/three.module.js';
import { OrbitControls } from './vendor/three/examples/jsm/controls/OrbitControls.js';

export const BACKGROUND = 0x1d232c;
const SURFACE = 0xd9dde3;

// A perceptually ordered colour scale (viridis, 7 stops, sRGB): dark blue (did not move) to
// yellow. The legend draws these values; the heat map renders the same ones (see setHeat).
const SCALE = [[68, 1, 84], [68, 57, 131], [49, 104, 142], [33, 145, 140], [53, 183, 121], [144, 215, 67], [253, 231, 37]];
// The signed scale (in or out along the normal): a diverging blue - grey - red (ColorBrewer's
// RdBu, reversed, its white middle darkened to a light grey so that it stays visible when lit).
const SIGNED = [[33, 102, 172], [103, 169, 207], [209, 229, 240], [214, 214, 214], [253, 219, 199], [239, 138, 98], [178, 24, 43]];
function along(stops, t) {
  const x = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x)), f = x - i;
  return stops[i].map((c, k) => (c + (stops[i + 1][k] - c) * f) / 255);
}
// t in [0, 1] of the legend -> sRGB [r, g, b] in [0, 1]; signed: 0 is the most inward, 0.5 no
// movement, 1 the most outward.
export function scaleColour(t, signed = false) { return along(signed ? SIGNED : SCALE, t); }

export class Viewer {
  constructor(canvas) {
    this.canvas = canvas;
    // preserveDrawingBuffer: the canvas can be read back (screenshots, the page's tests).
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    this.renderer.setClearColor(BACKGROUND);
    this.renderer.setScissorTest(true);
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = false;
    canvas.addEventListener('keydown', (e) => this.onKey(e));
    this.controls.addEventListener('change', () => this.draw());
    this.layout = 'side';
    this.split = 0.5;
    this.heat = false;
    this.smooth = false;
    this.wireframe = false;
    this.scenes = { before: this.makeScene(), after: this.makeScene() };
    this.meshes = { before: null, after: null };
    this.marker = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0xff4f9a }));
    this.marker.visible = false;
    this.scenes.after.add(this.marker);
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  makeScene() {
    const scene = new THREE.Scene();
    // White lights only: the heat map's colours are then only scaled by the light (its hue and
    // saturation stay the legend's).
    scene.add(new THREE.HemisphereLight(0xffffff, 0x3a3a3a, 1.0));
    const key = new THREE.DirectionalLight(0xffffff, 2.2);
    key.position.set(1, 1.5, 2);
    scene.add(key);
    scene.userData.key = key;
    return scene;
  }

  // geometry: indexed BufferGeometry; which: 'before' | 'after'.
  setMesh(which, geometry) {
    const scene = this.scenes[which];
    const old = this.meshes[which];
    if (old) {
      scene.remove(old.surface, old.wire);
      old.surface.geometry.dispose();
      for (const m of [old.lit, old.heat, old.wire.material]) m.dispose();
    }
    this.meshes[which] = null;
    if (which === 'after') this.marker.visible = false;
    if (geometry) {
      // Lambert, flat or smooth; the heat map is the same lit surface with the vertex colours as
      // its albedo. Both push their depth back a little for the wireframe on top.
      const offset = { polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1, side: THREE.DoubleSide };
      const lit = new THREE.MeshLambertMaterial({ color: SURFACE, ...offset });
      const heat = new THREE.MeshLambertMaterial({ color: 0xffffff, vertexColors: true, ...offset });
      const surface = new THREE.Mesh(geometry, lit);
      const wire = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ color: 0x10141a, wireframe: true, transparent: true, opacity: 0.45 }));
      this.meshes[which] = { surface, wire, lit, heat };
      scene.add(surface, wire);
      this.applyStyle();
    }
    this.draw();
  }

  // values: per result vertex, in [0, 1] of the scale (null: no heat map available); signed:
  // the diverging scale.
  setHeat(values, signed = false) {
    const mesh = this.meshes.after;
    if (!mesh) return;
    const g = mesh.surface.geometry;
    if (values) {
      // The scale is in sRGB (as the legend's canvas draws it); three.js takes vertex colours as
      // linear and encodes its output to sRGB, so they are converted here and come out as given.
      const colours = new Float32Array(values.length * 3), c = new THREE.Color();
      for (let i = 0; i < values.length; ++i) {
        const [r, gr, b] = scaleColour(values[i], signed);
        c.setRGB(r, gr, b, THREE.SRGBColorSpace);
        colours[3 * i] = c.r;
        colours[3 * i + 1] = c.g;
        colours[3 * i + 2] = c.b;
      }
      g.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    } else {
      g.deleteAttribute('color');
    }
    this.applyStyle();
    this.draw();
  }

  // Runs `change` (setMesh, setHeat, ...) with one draw at its end instead of one per call;
  // resolves after the next animation frame, when that draw is on screen.
  async batch(change) {
    this.holding = true;
    try {
      change();
    } finally {
      this.holding = false;
    }
    this.draw();
    await new Promise((resolve) => requestAnimationFrame(() => resolve()));
  }

  setHeatVisible(on) { this.heat = on; this.applyStyle(); this.draw(); }
  setSmooth(on) { this.smooth = on; this.applyStyle(); this.draw(); }
  setWireframe(on) { this.wireframe = on; this.applyStyle(); this.draw(); }

  applyStyle() {
    for (const [which, mesh] of Object.entries(this.meshes)) {
      if (!mesh) continue;
      const g = mesh.surface.geometry;
      if (this.smooth && !g.getAttribute('normal')) g.computeVertexNormals();
      for (const m of [mesh.lit, mesh.heat]) {
        m.flatShading = !this.smooth;
        m.needsUpdate = true;
      }
      const heat = which === 'after' && this.heat && g.getAttribute('color') !== undefined;
      mesh.surface.material = heat ? mesh.heat : mesh.lit;
      mesh.wire.visible = this.wireframe;
    }
  }

  setLayout(layout) { this.layout = layout; this.resize(); }
  setSplit(fraction) { this.split = fraction; this.draw(); }

  // The result's vertex under a point of the canvas (client pixels), or null: the viewport the
  // point is in must show the result. Returns {index, position}.
  pick(clientX, clientY) {
    const mesh = this.meshes.after;
    if (!mesh) return null;
    const rect = this.canvas.getBoundingClientRect();
    const x = clientX - rect.left, y = clientY - rect.top;
    let left = 0, width = rect.width;
    if (this.layout === 'side') {
      if (x < rect.width / 2) return null;
      left = Math.floor(rect.width / 2);
      width = rect.width - left;
    } else if (x < rect.width * this.split) {
      return null;
    }
    const ndc = new THREE.Vector2(((x - left) / width) * 2 - 1, -(y / rect.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const hit = ray.intersectObject(mesh.surface, false)[0];
    if (!hit) return null;
    // The nearest of the hit triangle's three corners.
    const p = mesh.surface.geometry.getAttribute('position');
    let best = null;
    for (const i of [hit.face.a, hit.face.b, hit.face.c]) {
      const v = new THREE.Vector3().fromBufferAttribute(p, i);
      const d = v.distanceTo(hit.point);
      if (!best || d < best.d) best = { d, index: i, position: v };
    }
    this.marker.position.copy(best.position);
    this.marker.scale.setScalar(mesh.surface.geometry.boundingSphere.radius / 70);
    this.marker.visible = true;
    this.draw();
    return { index: best.index, position: best.position };
  }

  clearPick() { this.marker.visible = false; this.draw(); }

  // The keyboard, while the canvas has the focus: arrows turn the view (15 degrees a press),
  // Shift+arrows pan, + / - (or PageUp / PageDown) zoom, 0 or Home frames the model again.
  onKey(e) {
    if (e.ctrlKey || e.metaKey || e.altKey) return;
    const step = THREE.MathUtils.degToRad(15);
    const pan = 0.08 * this.canvas.clientHeight;
    const c = this.controls;
    const act = {
      ArrowLeft: () => (e.shiftKey ? c.pan(pan, 0) : c.rotateLeft(step)),
      ArrowRight: () => (e.shiftKey ? c.pan(-pan, 0) : c.rotateLeft(-step)),
      ArrowUp: () => (e.shiftKey ? c.pan(0, pan) : c.rotateUp(step)),
      ArrowDown: () => (e.shiftKey ? c.pan(0, -pan) : c.rotateUp(-step)),
      '+': () => c.dollyOut(1.2), '=': () => c.dollyOut(1.2), PageUp: () => c.dollyOut(1.2),
      '-': () => c.dollyIn(1.2), _: () => c.dollyIn(1.2), PageDown: () => c.dollyIn(1.2),
      0: () => this.frame(), Home: () => this.frame(),
    }[e.key];
    if (!act) return;  // (three's dollyOut moves the camera closer: "zoom in")
    e.preventDefault();
    act();
    this.draw();
  }

  // Where the camera stands, for the page's tests and screenshots: azimuth and polar angle
  // (degrees) around the target, distance, and the target.
  viewState() {
    const offset = new THREE.Vector3().subVectors(this.camera.position, this.controls.target);
    const s = new THREE.Spherical().setFromVector3(offset);
    return { azimuth: THREE.MathUtils.radToDeg(s.theta), polar: THREE.MathUtils.radToDeg(s.phi), distance: s.radius,
             target: this.controls.target.toArray() };
  }

  // Frames the input (or the result alone) in the camera.
  frame() {
    const mesh = this.meshes.before ?? this.meshes.after;
    if (!mesh) return;
    const g = mesh.surface.geometry;
    g.computeBoundingSphere();
    const { center, radius } = g.boundingSphere;
    const r = radius > 0 ? radius : 1;
    // The sphere fits the narrower of the two fields of view (a tall viewport is narrow).
    const half = THREE.MathUtils.degToRad(this.camera.fov / 2);
    const fit = Math.min(half, Math.atan(Math.tan(half) * this.camera.aspect));
    const distance = r / Math.sin(fit) * 1.05;
    this.camera.near = distance / 100;
    this.camera.far = distance * 10;
    this.camera.position.copy(center).add(new THREE.Vector3(0.6, 0.55, 1).normalize().multiplyScalar(distance));
    this.controls.target.copy(center);
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.draw();
  }

  resize() {
    const width = this.canvas.clientWidth, height = this.canvas.clientHeight;
    if (width === 0 || height === 0) return;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = (this.layout === 'side' ? width / 2 : width) / height;
    this.camera.updateProjectionMatrix();
    this.draw();
  }

  draw() {
    if (this.holding) return;
    const width = this.canvas.clientWidth, height = this.canvas.clientHeight;
    if (width === 0 || height === 0) return;
    // The key light follows the camera, from its upper left, so that every side of the model is
    // lit alike and the facets of different orientation stay apart.
    const view = new THREE.Vector3().subVectors(this.camera.position, this.controls.target).normalize();
    const right = new THREE.Vector3().setFromMatrixColumn(this.camera.matrixWorld, 0);
    const up = new THREE.Vector3().setFromMatrixColumn(this.camera.matrixWorld, 1);
    const direction = view.addScaledVector(right, -0.7).addScaledVector(up, 0.9);
    for (const scene of Object.values(this.scenes)) scene.userData.key.position.copy(direction);
    this.canvas.dataset.view = JSON.stringify(this.viewState());
    const r = this.renderer;
    if (this.layout === 'side') {
      const half = Math.floor(width / 2);
      r.setViewport(0, 0, half, height); r.setScissor(0, 0, half, height);
      r.render(this.scenes.before, this.camera);
      r.setViewport(half, 0, width - half, height); r.setScissor(half, 0, width - half, height);
      r.render(this.scenes.after, this.camera);
    } else {
      const x = Math.round(width * this.split);
      r.setViewport(0, 0, width, height);
      r.setScissor(0, 0, x, height);
      r.render(this.scenes.before, this.camera);
      r.setScissor(x, 0, width - x, height);
      r.render(this.scenes.after, this.camera);
    }
  }
}
