// The 3D view: every performer's skeleton (bones as lines, joints as spheres; one colour per
// performer), the rig's cameras as frusta (red while their stream is stale) and the floor grid, in
// the host's world frame (Z up, metres).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const CAMERA = 0x8a93a3, CAMERA_STALE = 0xe06060;
// [bones, joints] of performer k (subject id k; 0 in a session of one) is COLOURS[k % length].
export const COLOURS = [[0x33ccff, 0xff9919], [0x7be07b, 0xe0e040], [0xff7fbf, 0x9f7fff], [0xffb060, 0x40d0d0],
  [0xd0d0d0, 0xff6060], [0x6080ff, 0xffd080], [0xc0ff60, 0xff60ff], [0x60ffc0, 0xffa0a0]];
// A performer without a pose this long is taken away (mocapd gives a person up after 2 s unseen).
export const GONE_MS = 2500;
// Drawn at most this often: a browser beside the host on a 2-core machine (without a GPU, WebGL
// renders on the CPU) must leave the host its cores; poses still arrive at the camera rate.
const MAX_RENDER_HZ = Number(new URLSearchParams(location.search).get('fps')) || 30;  // ?fps=N: another cap

export class View {
  constructor(container) {
    THREE.Object3D.DEFAULT_UP.set(0, 0, 1);
    this.container = container;
    this.names = [];          // joint names in the drawn order (the scene's bones)
    this.parents = [];        // index of each bone's parent, -1 for the root
    this.figures = new Map(); // subject id -> {positions, seenAt, bones, joints}: the performers drawn
    this.frusta = new Map();  // camera name -> its line material
    this.changed();
    try {
      this.renderer = new THREE.WebGLRenderer({ antialias: false, powerPreference: 'low-power' });
    } catch (error) {
      this.renderer = null;
      console.warn('no WebGL:', error);
      return;
    }
    this.renderer.setClearColor(0x14161a);
    this.renderer.setPixelRatio(Number(new URLSearchParams(location.search).get('scale')) || 1);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.05, 200);
    this.camera.position.set(3.2, -3.9, 2.1);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 0.9);
    this.controls.addEventListener('change', () => { this.changed(); });
    const grid = new THREE.GridHelper(12, 24, 0x3a404a, 0x2a2f37);
    grid.rotation.x = Math.PI / 2;  // from three.js's XZ plane to our floor, XY
    this.scene.add(grid, new THREE.AxesHelper(0.5));
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
    this.renderedAt = [];  // times of the frames drawn during the last second
    this.scheduled = false;
  }

  get ok() { return this.renderer !== null; }

  // Something drawn has changed: one frame is drawn at the next animation frame the cap allows
  // (none is requested while nothing changes).
  changed() {
    this.dirty = true;
    if (this.scheduled || !this.renderer) return;
    this.scheduled = true;
    requestAnimationFrame((now) => this.render(now));
  }

  resize() {
    if (!this.ok) return;
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.changed();
  }

  // The scene message: bones [{name, parent}] and cameras [{name, centre, corners}].
  setScene(scene) {
    this.names = scene.bones.map((b) => b.name);
    const index = new Map(this.names.map((n, i) => [n, i]));
    this.parents = scene.bones.map((b) => (b.parent === null ? -1 : index.get(b.parent) ?? -1));
    for (const subject of [...this.figures.keys()]) this.remove(subject);
    if (!this.ok) return;
    for (const old of this.frusta.values()) this.scene.remove(old);
    this.frusta = new Map(scene.cameras.map((c) => [c.name, this.frustum(c)]));
    this.changed();
  }

  // Performer `subject`'s figure, made on its first pose.
  figure(subject) {
    let figure = this.figures.get(subject);
    if (figure) return figure;
    figure = { positions: new Float32Array(this.names.length * 3), seenAt: 0 };
    this.figures.set(subject, figure);
    if (!this.ok) return figure;
    const [bone, joint] = COLOURS[subject % COLOURS.length];
    const pairs = this.parents.flatMap((p, i) => (p >= 0 ? [p, i] : []));
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(pairs.length * 3), 3));
    geometry.userData.pairs = pairs;
    figure.bones = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: bone }));
    figure.joints = new THREE.InstancedMesh(new THREE.SphereGeometry(0.025, 12, 8),
      new THREE.MeshBasicMaterial({ color: joint }), this.names.length);
    figure.bones.frustumCulled = figure.joints.frustumCulled = false;
    this.scene.add(figure.bones, figure.joints);
    return figure;
  }

  remove(subject) {
    const figure = this.figures.get(subject);
    this.figures.delete(subject);
    if (!figure?.bones) return;
    this.scene.remove(figure.bones, figure.joints);
    for (const object of [figure.bones, figure.joints]) { object.geometry.dispose(); object.material.dispose(); }
    this.changed();
  }

  // Takes away the performers without a pose for GONE_MS; the subject ids still drawn.
  retire(now = performance.now()) {
    for (const [subject, figure] of [...this.figures]) if (now - figure.seenAt > GONE_MS) this.remove(subject);
    return this.people();
  }

  people() { return [...this.figures.keys()].sort((a, b) => a - b); }

  frustum(camera) {
    const [a, b, c, d] = camera.corners, o = camera.centre;
    const points = [o, a, o, b, o, c, o, d, a, b, b, c, c, d, d, a].flat();
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(points, 3));
    const lines = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: CAMERA }));
    this.scene.add(lines);
    return lines;
  }

  setCameraState(name, state) {
    const lines = this.frusta.get(name);
    if (!lines) return;
    lines.material.color.setHex(state === 'ok' ? CAMERA : CAMERA_STALE);
    this.changed();
  }

  // A pose message (of performer pose.subject): joints [[x, y, z]] named by names, in any order;
  // joints it lacks keep their place.
  setPose(pose) {
    if (!this.names.length) return;
    const figure = this.figure(pose.subject ?? 0), p = figure.positions;
    figure.seenAt = performance.now();
    const index = new Map(this.names.map((n, i) => [n, i]));
    pose.names.forEach((name, k) => {
      const i = index.get(name);
      if (i !== undefined) p.set(pose.joints[k], 3 * i);
    });
    if (!this.ok) return;
    const matrix = new THREE.Matrix4();
    for (let i = 0; i < this.names.length; i++) {
      figure.joints.setMatrixAt(i, matrix.makeTranslation(p[3 * i], p[3 * i + 1], p[3 * i + 2]));
    }
    figure.joints.instanceMatrix.needsUpdate = true;
    const line = figure.bones.geometry.attributes.position, pairs = figure.bones.geometry.userData.pairs;
    pairs.forEach((i, k) => line.setXYZ(k, p[3 * i], p[3 * i + 1], p[3 * i + 2]));
    line.needsUpdate = true;
    this.follow();
    this.changed();
  }

  // Keeps the performers in view: the orbit target and the camera move with their roots' mean on
  // the floor.
  follow() {
    const roots = [...this.figures.values()].map((f) => f.positions);
    const x = roots.reduce((sum, p) => sum + p[0], 0) / roots.length;
    const y = roots.reduce((sum, p) => sum + p[1], 0) / roots.length;
    const dx = x - this.controls.target.x, dy = y - this.controls.target.y;
    if (Math.hypot(dx, dy) < 1e-4) return;
    this.controls.target.x += dx; this.controls.target.y += dy;
    this.camera.position.x += dx; this.camera.position.y += dy;
    this.controls.update();
  }

  // Performer `subject`'s joint centres as drawn: read back from its joint spheres' matrices.
  drawnJoints(subject) {
    const figure = this.figures.get(subject);
    if (!figure) return { names: this.names, joints: [] };
    const matrix = new THREE.Matrix4(), v = new THREE.Vector3();
    const joints = this.names.map((_, i) => {
      if (!this.ok) return Array.from(figure.positions.slice(3 * i, 3 * i + 3));  // no WebGL: what would be drawn
      figure.joints.getMatrixAt(i, matrix);
      return v.setFromMatrixPosition(matrix).toArray();
    });
    return { names: this.names, joints };
  }

  render(now) {
    this.scheduled = false;
    if (!this.dirty) return;
    const last = this.renderedAt[this.renderedAt.length - 1];
    const wait = last === undefined ? 0 : 1000 / MAX_RENDER_HZ - 2 - (now - last);
    if (wait > 0) {  // too soon after the last frame: asks again once the cap allows, not every frame
      this.scheduled = true;
      setTimeout(() => requestAnimationFrame((t) => this.render(t)), wait);
      return;
    }
    this.dirty = false;
    this.renderer.render(this.scene, this.camera);
    this.renderedAt.push(now);
    while (this.renderedAt[0] < now - 1000) this.renderedAt.shift();
  }

  // Frames drawn during the last second.
  get renderHz() {
    const since = performance.now() - 1000;
    return this.renderedAt.filter((t) => t >= since).length;
  }
}
