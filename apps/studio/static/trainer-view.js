// The trainer's 3D view: the organ's surface from the session's frames (buffers allocated once
// per scene, updated in place), the tray, the instruments' marks and the force arrow.
// Plain WebGL through three.js (works with software WebGL, SwiftShader).

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export const BACKGROUND = 0xe8ecf0;
const TISSUE = 0xd88a82;
const TRAY = 0xa9b4be;
const CUT_LINE = 0x1257c7;
const NEEDLE = 0x138a5a;
const FORCE = 0xd14343;
/** The force arrow: centimetres of arrow per newton, and its longest share of the organ's size. */
export const ARROW_CM_PER_N = 5;
const ARROW_MAX_SHARE = 0.6;
const PATH_CAPACITY = 4096;

const MIN_SCALE = 0.5;

/** Whether WebGL runs in software (SwiftShader, llvmpipe): every pixel costs CPU time. */
function softwareWebGl() {
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    if (!gl) return false;
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
    gl.getExtension('WEBGL_lose_context')?.loseContext();
    return /swiftshader|llvmpipe|softpipe|software/i.test(name);
  } catch {
    return false;
  }
}

export class TrainerView {
  constructor(container) {
    this.container = container;
    // The surface changes at up to 60 frames a second: in software WebGL, no multisampling, and
    // the resolution adapts to keep up (see adapt()).
    this.software = softwareWebGl();
    this.renderer = new THREE.WebGLRenderer({ antialias: !this.software, preserveDrawingBuffer: false });
    this.maxScale = Math.min(2, window.devicePixelRatio || 1);
    this.scale = this.software ? Math.min(1, this.maxScale) : this.maxScale;
    this.renderer.setPixelRatio(this.scale);
    this.renderer.setClearColor(BACKGROUND, 1);
    this.canvas = this.renderer.domElement;
    this.canvas.setAttribute('aria-label', 'Organ on the tray');
    this.canvas.tabIndex = 0;
    container.appendChild(this.canvas);

    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.05, 2000);
    this.camera.position.set(0, 25, 40);

    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x6d625c, 0.85));
    this.scene.add(new THREE.AmbientLight(0xffffff, 0.2));
    this.sun = new THREE.DirectionalLight(0xffffff, 1.4); // from above, front left
    this.sun.position.set(-0.5, 1, 0.6);
    this.scene.add(this.sun);
    // A light carried with the camera: the side turned to the viewer is never dark.
    this.headlight = new THREE.DirectionalLight(0xffffff, 0.55);
    this.headlight.position.set(0.3, 0.4, 1);
    this.headlight.target.position.set(0, 0, -1);
    this.camera.add(this.headlight, this.headlight.target);
    this.scene.add(this.camera);

    // The tray: a box whose top is y = 0 (sized by the scene message).
    this.tray = new THREE.Mesh(
      new THREE.BoxGeometry(1, 1, 1),
      new THREE.MeshLambertMaterial({ color: TRAY }),
    );
    this.tray.visible = false;
    this.scene.add(this.tray);
    this.grid = null; // 1 cm squares on the tray's top

    this.material = new THREE.MeshPhongMaterial({
      color: TISSUE, specular: 0x2a2020, shininess: 30, side: THREE.DoubleSide,
    });
    this.mesh = null;
    this.capacity = { vertices: 0, triangles: 0 };
    this.vertices = 0;
    this.triangles = 0;
    this.box = new THREE.Box3();
    this.size = 10;

    // The scalpel's path while dragging (preallocated line).
    const pathGeometry = new THREE.BufferGeometry();
    pathGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * PATH_CAPACITY), 3));
    pathGeometry.setDrawRange(0, 0);
    this.pathLine = new THREE.Line(pathGeometry, new THREE.LineBasicMaterial({ color: CUT_LINE, depthTest: false }));
    this.pathLine.renderOrder = 3;
    this.pathLine.frustumCulled = false;
    this.pathLine.visible = false;
    this.scene.add(this.pathLine);

    // The needle's first point.
    this.needleMarker = new THREE.Mesh(
      new THREE.SphereGeometry(1, 16, 12),
      new THREE.MeshPhongMaterial({ color: NEEDLE, shininess: 40, depthTest: false }),
    );
    this.needleMarker.renderOrder = 4;
    this.needleMarker.visible = false;
    this.scene.add(this.needleMarker);

    // The force of the tissue on the tool, at the tool's tip.
    this.arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 1, 0), new THREE.Vector3(), 1, FORCE);
    this.arrow.visible = false;
    for (const child of this.arrow.children) {
      child.material.depthTest = false;
      child.renderOrder = 5;
    }
    this.scene.add(this.arrow);

    this.controls = new OrbitControls(this.camera, this.canvas);
    this.controls.enableDamping = false;
    // Left-drag on the organ is the instrument's (the page turns the controls off for it);
    // left-drag on the background and right-drag orbit, middle-drag pans.
    this.controls.mouseButtons = { LEFT: THREE.MOUSE.ROTATE, MIDDLE: THREE.MOUSE.PAN, RIGHT: THREE.MOUSE.ROTATE };
    this.controls.addEventListener('change', () => { this.dirty = true; });

    this.raycaster = new THREE.Raycaster();
    this.dirty = true;
    this.onResize();
    new ResizeObserver(() => this.onResize()).observe(container);
  }

  onResize() {
    const w = Math.max(1, this.container.clientWidth);
    const h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.dirty = true;
  }

  /**
   * Resolution for the frame rate, once a second: when frames arrive faster than they are drawn
   * (and fewer than 20 a second are drawn), render fewer pixels (down to half the CSS
   * resolution); when drawing keeps up with ease, more again. Returns true when it changed.
   */
  adapt(drawnPerS, receivedPerS) {
    let next = this.scale;
    if (drawnPerS < 20 && receivedPerS > drawnPerS * 1.2 && this.scale > MIN_SCALE) {
      next = Math.max(MIN_SCALE, this.scale * 0.75);
    } else if (drawnPerS >= 50 && this.scale < this.maxScale) {
      next = Math.min(this.maxScale, this.scale / 0.75);
    }
    if (Math.abs(next - this.scale) < 1e-3) return false;
    console.info(`trainer: ${drawnPerS} frames drawn per second of ${receivedPerS} received: `
      + `rendering at ${Math.round(next * 100)} % of the CSS resolution`);
    this.scale = next;
    this.renderer.setPixelRatio(next);
    this.onResize();
    return true;
  }

  /** Renders if anything changed since the last render; true if it rendered. */
  renderIfDirty() {
    if (!this.dirty) return false;
    this.dirty = false;
    this.renderer.render(this.scene, this.camera);
    return true;
  }

  renderNow() {
    this.dirty = false;
    this.renderer.render(this.scene, this.camera);
  }

  /** The tray from the scene message: `size` [sx, sz] cm, its top at y = `top`. */
  setTray(size, top = 0) {
    const [sx, sz] = size;
    const thick = Math.max(0.3, 0.04 * Math.max(sx, sz));
    this.tray.scale.set(sx, thick, sz);
    this.tray.position.set(0, top - thick / 2, 0);
    this.tray.visible = true;
    if (this.grid) {
      this.scene.remove(this.grid);
      this.grid.geometry.dispose();
      this.grid.material.dispose();
    }
    const cells = Math.ceil(Math.max(sx, sz));
    this.grid = new THREE.GridHelper(cells, cells, 0x4f5a65, 0x4f5a65);
    this.grid.scale.set(sx / cells, 1, sz / cells);
    this.grid.position.set(0, top + 0.002, 0);
    this.grid.material.transparent = true;
    this.grid.material.opacity = 0.3;
    this.scene.add(this.grid);
    this.trayTop = top;
    this.traySize = [sx, sz];
    this.dirty = true;
  }

  /**
   * Buffers for `vertices` and `triangles` (the scene's capacity): positions, normals and a u32
   * index, drawn up to the frame's counts with setDrawRange. Called per scene, and again only
   * when a frame is larger than the capacity.
   */
  allocate(vertices, triangles) {
    if (this.mesh) {
      this.scene.remove(this.mesh);
      this.mesh.geometry.dispose();
    }
    const geometry = new THREE.BufferGeometry();
    const position = new THREE.BufferAttribute(new Float32Array(3 * vertices), 3);
    const normal = new THREE.BufferAttribute(new Float32Array(3 * vertices), 3);
    position.setUsage(THREE.DynamicDrawUsage);
    normal.setUsage(THREE.DynamicDrawUsage);
    geometry.setAttribute('position', position);
    geometry.setAttribute('normal', normal);
    const index = new THREE.BufferAttribute(new Uint32Array(3 * triangles), 1);
    index.setUsage(THREE.DynamicDrawUsage);
    geometry.setIndex(index);
    geometry.setDrawRange(0, 0);
    geometry.boundingBox = new THREE.Box3();
    geometry.boundingSphere = new THREE.Sphere();
    this.mesh = new THREE.Mesh(geometry, this.material);
    this.scene.add(this.mesh);
    this.capacity = { vertices, triangles };
    this.vertices = 0;
    this.triangles = 0;
    this.hasIndex = false;
    this.dirty = true;
  }

  /** The centroid of the vertices from index `from` on (a THREE.Vector3), or null if none. */
  nodesFrom(from) {
    if (!this.mesh || from >= this.vertices) return null;
    const p = this.mesh.geometry.attributes.position.array;
    let x = 0, y = 0, z = 0;
    for (let i = 3 * from, end = 3 * this.vertices; i < end; i += 3) {
      x += p[i]; y += p[i + 1]; z += p[i + 2];
    }
    return new THREE.Vector3(x, y, z).divideScalar(this.vertices - from);
  }

  /**
   * Copies a frame into the buffers. Returns false when it cannot be drawn (no index buffer
   * received yet for this scene). Reallocates (and logs it) only when the frame exceeds the
   * capacity.
   */
  applyFrame(frame) {
    if (!this.mesh) return false;
    const V = frame.vertices;
    const T = frame.index ? frame.triangles : this.triangles;
    if (!frame.index && !this.hasIndex) return false;
    if (V > this.capacity.vertices || T > this.capacity.triangles) {
      if (!frame.index) return false; // the old index cannot be kept through a reallocation
      const v = Math.max(this.capacity.vertices, Math.ceil(V * 1.25));
      const t = Math.max(this.capacity.triangles, Math.ceil(T * 1.25));
      console.info(`trainer: frame ${frame.frame} has ${V} vertices and ${T} triangles, over the capacity `
        + `${this.capacity.vertices} / ${this.capacity.triangles}: buffers reallocated for ${v} / ${t}`);
      this.allocate(v, t);
      this.reallocations = (this.reallocations || 0) + 1;
    }
    const geometry = this.mesh.geometry;
    const position = geometry.getAttribute('position');
    position.array.set(frame.positions);
    position.clearUpdateRanges();
    position.addUpdateRange(0, 3 * V);
    position.needsUpdate = true;
    if (frame.index) {
      const index = geometry.getIndex();
      index.array.set(frame.index);
      index.clearUpdateRanges();
      index.addUpdateRange(0, 3 * frame.triangles);
      index.needsUpdate = true;
      this.triangles = frame.triangles;
      this.hasIndex = true;
    }
    this.vertices = V;
    geometry.setDrawRange(0, 3 * this.triangles);
    this.computeNormals();
    this.computeBounds();
    this.dirty = true;
    return true;
  }

  /** Area-weighted vertex normals over the triangles in use (not the whole capacity). */
  computeNormals() {
    const geometry = this.mesh.geometry;
    const p = geometry.getAttribute('position').array;
    const normal = geometry.getAttribute('normal');
    const n = normal.array;
    const idx = geometry.getIndex().array;
    const V = this.vertices;
    n.fill(0, 0, 3 * V);
    for (let t = 0, end = 3 * this.triangles; t < end; t += 3) {
      const a = 3 * idx[t], b = 3 * idx[t + 1], c = 3 * idx[t + 2];
      if (a >= 3 * V || b >= 3 * V || c >= 3 * V) continue;
      const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
      const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
      const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
      n[a] += nx; n[a + 1] += ny; n[a + 2] += nz;
      n[b] += nx; n[b + 1] += ny; n[b + 2] += nz;
      n[c] += nx; n[c + 1] += ny; n[c + 2] += nz;
    }
    for (let i = 0, end = 3 * V; i < end; i += 3) {
      const l = Math.hypot(n[i], n[i + 1], n[i + 2]);
      if (l > 0) {
        n[i] /= l; n[i + 1] /= l; n[i + 2] /= l;
      }
    }
    normal.clearUpdateRanges();
    normal.addUpdateRange(0, 3 * V);
    normal.needsUpdate = true;
  }

  /** The bounding box and sphere of the vertices in use (for picking, culling and organBox). */
  computeBounds() {
    const geometry = this.mesh.geometry;
    const p = geometry.getAttribute('position').array;
    const box = this.box.makeEmpty();
    const v = new THREE.Vector3();
    for (let i = 0, end = 3 * this.vertices; i < end; i += 3) box.expandByPoint(v.set(p[i], p[i + 1], p[i + 2]));
    geometry.boundingBox.copy(box);
    box.getBoundingSphere(geometry.boundingSphere);
    if (!box.isEmpty()) this.size = Math.max(1e-3, box.getSize(v).length());
  }

  /** The camera onto the organ, from the front and above, organ and tray in view. */
  fit() {
    if (this.box.isEmpty()) return;
    const centre = this.box.getCenter(new THREE.Vector3());
    const radius = Math.max(0.5, this.box.getSize(new THREE.Vector3()).length() / 2);
    const vfov = THREE.MathUtils.degToRad(this.camera.fov);
    const hfov = 2 * Math.atan(Math.tan(vfov / 2) * this.camera.aspect);
    const dist = (radius / Math.sin(Math.min(vfov, hfov) / 2)) * 1.35;
    const dir = new THREE.Vector3(0.0, 0.62, 1).normalize();
    this.camera.position.copy(centre).addScaledVector(dir, dist);
    this.camera.up.set(0, 1, 0);
    this.camera.near = Math.max(0.01, dist / 100);
    this.camera.far = dist * 20 + 200;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.minDistance = radius * 0.3;
    this.controls.maxDistance = dist * 6;
    this.controls.update();
    this.needleMarker.scale.setScalar(Math.max(0.08, this.size * 0.012));
    this.dirty = true;
  }

  ndc(cx, cy) {
    const rect = this.canvas.getBoundingClientRect();
    return new THREE.Vector2(((cx - rect.left) / rect.width) * 2 - 1, -((cy - rect.top) / rect.height) * 2 + 1);
  }

  /** The organ's surface under the client point (cx, cy): `{point, triangle}`, or null. */
  pick(cx, cy) {
    if (!this.mesh || this.triangles === 0) return null;
    this.camera.updateMatrixWorld();
    this.raycaster.setFromCamera(this.ndc(cx, cy), this.camera);
    const hit = this.raycaster.intersectObject(this.mesh, false)[0];
    if (!hit) return null;
    return { point: hit.point.toArray(), triangle: hit.faceIndex };
  }

  /** The ray through (cx, cy) met with the plane through `point` facing the camera; or null. */
  onCameraPlane(cx, cy, point) {
    this.camera.updateMatrixWorld();
    this.raycaster.setFromCamera(this.ndc(cx, cy), this.camera);
    const normal = this.viewDir(new THREE.Vector3());
    const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(normal, new THREE.Vector3().fromArray(point));
    const out = new THREE.Vector3();
    return this.raycaster.ray.intersectPlane(plane, out) ? out.toArray() : null;
  }

  /** The camera's viewing direction (unit). */
  viewDir(out = new THREE.Vector3()) {
    return this.camera.getWorldDirection(out);
  }

  /** Client (viewport) CSS pixels of the world point `p` (cm), as page.mouse takes them. */
  screenOf(p) {
    this.camera.updateMatrixWorld();
    const v = new THREE.Vector3().fromArray(p).project(this.camera);
    const rect = this.canvas.getBoundingClientRect();
    return {
      x: rect.left + ((v.x + 1) / 2) * rect.width,
      y: rect.top + ((1 - v.y) / 2) * rect.height,
      visible: v.z > -1 && v.z < 1 && Math.abs(v.x) <= 1 && Math.abs(v.y) <= 1,
    };
  }

  /** The scalpel's path so far (array of [x, y, z]); null hides it. */
  setPath(points) {
    if (!points || points.length === 0) {
      this.pathLine.visible = false;
      this.dirty = true;
      return;
    }
    const attr = this.pathLine.geometry.getAttribute('position');
    const n = Math.min(points.length, PATH_CAPACITY);
    for (let i = 0; i < n; i++) attr.setXYZ(i, points[i][0], points[i][1], points[i][2]);
    attr.clearUpdateRanges();
    attr.addUpdateRange(0, 3 * n);
    attr.needsUpdate = true;
    this.pathLine.geometry.setDrawRange(0, n);
    this.pathLine.visible = true;
    this.dirty = true;
  }

  /** The needle's first point, or null. */
  setNeedleMarker(point) {
    this.needleMarker.visible = !!point;
    if (point) this.needleMarker.position.fromArray(point);
    this.dirty = true;
  }

  /** The force arrow: `force` N at `tip` cm; hidden when the tip is not finite or the force is 0. */
  setForce(force, tip) {
    const f = new THREE.Vector3().fromArray(force);
    const magnitude = f.length();
    const show = tip.every(Number.isFinite) && Number.isFinite(magnitude) && magnitude > 1e-6;
    if (show !== this.arrow.visible) this.dirty = true;
    this.arrow.visible = show;
    if (!show) return;
    const len = Math.min(ARROW_MAX_SHARE * this.size, Math.max(0.05 * this.size, ARROW_CM_PER_N * magnitude));
    this.arrow.position.fromArray(tip);
    this.arrow.setDirection(f.divideScalar(magnitude));
    this.arrow.setLength(len, Math.min(0.35 * len, 0.08 * this.size), Math.min(0.2 * len, 0.045 * this.size));
    this.dirty = true;
  }

  /** The surface's bounding box, cm. */
  organBox() {
    if (this.box.isEmpty()) return null;
    return { min: this.box.min.toArray(), max: this.box.max.toArray() };
  }
}
