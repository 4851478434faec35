// Before and after in one WebGL canvas with one camera: side by side (two viewports) or swipe
// (one viewport, the result drawn right of a movable split). Flat shading, so that noise and
// creases show; the result can be coloured by how far each vertex moved. Draws on demand only.
import * as THREE from './vendor/three/build/three.module.js';
import { OrbitControls } from './vendor/three/examples/jsm/controls/OrbitControls.js';

export const BACKGROUND = 0x1d232c;
const SURFACE = 0xd9dde3;

// A perceptually ordered colour scale (viridis, 7 stops): dark blue (did not move) to yellow.
const SCALE = [[68, 1, 84], [68, 57, 131], [49, 104, 142], [33, 145, 140], [53, 183, 121], [144, 215, 67], [253, 231, 37]];
export function scaleColour(t) {
  const x = Math.min(1, Math.max(0, t)) * (SCALE.length - 1);
  const i = Math.min(SCALE.length - 2, Math.floor(x)), f = x - i;
  return SCALE[i].map((c, k) => (c + (SCALE[i + 1][k] - c) * f) / 255);
}

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
    this.controls.listenToKeyEvents(canvas);  // arrow keys pan while the canvas has focus
    this.controls.addEventListener('change', () => this.draw());
    this.layout = 'side';
    this.split = 0.5;
    this.heat = false;
    this.scenes = { before: this.makeScene(), after: this.makeScene() };
    this.meshes = { before: null, after: null };
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  makeScene() {
    const scene = new THREE.Scene();
    scene.add(new THREE.HemisphereLight(0xffffff, 0x30363f, 1.0));
    const key = new THREE.DirectionalLight(0xffffff, 2.2);
    key.position.set(1, 1.5, 2);
    scene.add(key);
    scene.userData.key = key;
    return scene;
  }

  // geometry: indexed BufferGeometry; which: 'before' | 'after'. Flat shading needs no normals.
  setMesh(which, geometry) {
    const scene = this.scenes[which];
    if (this.meshes[which]) {
      scene.remove(this.meshes[which]);
      this.meshes[which].geometry.dispose();
      this.meshes[which].material.dispose();
    }
    this.meshes[which] = null;
    if (geometry) {
      const material = new THREE.MeshLambertMaterial({ color: SURFACE, flatShading: true, side: THREE.DoubleSide });
      this.meshes[which] = new THREE.Mesh(geometry, material);
      scene.add(this.meshes[which]);
      this.applyColours();
    }
    this.draw();
  }

  // values: per result vertex, in [0, 1] of the scale (null: no heat map available).
  setHeat(values) {
    const mesh = this.meshes.after;
    if (!mesh) return;
    if (values) {
      const colours = new Float32Array(values.length * 3);
      for (let i = 0; i < values.length; ++i) colours.set(scaleColour(values[i]), 3 * i);
      mesh.geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    } else {
      mesh.geometry.deleteAttribute('color');
    }
    this.applyColours();
    this.draw();
  }

  setHeatVisible(on) {
    this.heat = on;
    this.applyColours();
    this.draw();
  }

  applyColours() {
    const mesh = this.meshes.after;
    if (!mesh) return;
    const on = this.heat && mesh.geometry.getAttribute('color') !== undefined;
    mesh.material.vertexColors = on;
    mesh.material.color.set(on ? 0xffffff : SURFACE);
    mesh.material.needsUpdate = true;
  }

  setLayout(layout) { this.layout = layout; this.resize(); }
  setSplit(fraction) { this.split = fraction; this.draw(); }

  // Frames the input (or the result alone) in the camera.
  frame() {
    const mesh = this.meshes.before ?? this.meshes.after;
    if (!mesh) return;
    mesh.geometry.computeBoundingSphere();
    const { center, radius } = mesh.geometry.boundingSphere;
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
    const width = this.canvas.clientWidth, height = this.canvas.clientHeight;
    if (width === 0 || height === 0) return;
    // The key light follows the camera, from its upper left, so that every side of the model is
    // lit alike and the facets of different orientation stay apart.
    const view = new THREE.Vector3().subVectors(this.camera.position, this.controls.target).normalize();
    const right = new THREE.Vector3().setFromMatrixColumn(this.camera.matrixWorld, 0);
    const up = new THREE.Vector3().setFromMatrixColumn(this.camera.matrixWorld, 1);
    const direction = view.addScaledVector(right, -0.7).addScaledVector(up, 0.9);
    for (const scene of Object.values(this.scenes)) scene.userData.key.position.copy(direction);
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
