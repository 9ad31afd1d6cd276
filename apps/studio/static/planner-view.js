// The planner's 3D view: the patient's skin, the placement overlays and the colour maps.
// Plain WebGL through three.js (works with software WebGL, SwiftShader). Renders on demand.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export const BACKGROUND = 0xe8ecf0;
const SKIN = 0xe2b49a;
const FOOTPRINT = 0x1257c7;
const REGION = 0x138a5a;
const MARKER = 0x0b3d91;
/** The live preview's dome: a colour of its own, so that it is not taken for a result. */
export const DOME_PREVIEW = 0xd9480f;

/** Viridis, five stops: the colour bar's CSS gradient uses the same ones. */
export const RAMP = ['#440154', '#3b528b', '#21918c', '#5ec962', '#fde725'];
const RAMP_RGB = RAMP.map((hex) => new THREE.Color(hex));

/** The ramp's colour (linear RGB, into `out`) for t in [0, 1]. */
function rampColor(t, out) {
  const x = Math.min(1, Math.max(0, Number.isFinite(t) ? t : 0)) * (RAMP_RGB.length - 1);
  const i = Math.min(RAMP_RGB.length - 2, Math.floor(x));
  return out.copy(RAMP_RGB[i]).lerp(RAMP_RGB[i + 1], x - i);
}

export class PlannerView {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
    this.renderer.setClearColor(BACKGROUND, 1);
    this.canvas = this.renderer.domElement;
    this.canvas.setAttribute('aria-label', 'Patient surface');
    this.canvas.tabIndex = 0;
    container.appendChild(this.canvas);

    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1000);
    this.camera.position.set(0, 0, 50);

    // Light: a sky/ground fill and a key light from the viewer's upper left, carried with the
    // camera, so that a plane seen straight on is lit evenly but not flat white, and any relief
    // shows as shading.
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x7a6a60, 0.9));
    this.scene.add(new THREE.AmbientLight(0xffffff, 0.25));
    // The key light is a point light above the viewer's upper left (no fall-off with distance):
    // its angle changes across a flat patch, which then shows a gentle gradient.
    this.key = new THREE.PointLight(0xffffff, 2.2, 0, 0);
    this.key.position.set(-10, 12, 0);
    this.fill = new THREE.DirectionalLight(0xffffff, 0.35);
    this.fill.position.set(1.0, -0.4, 0.6);
    this.camera.add(this.key, this.fill, this.fill.target);
    this.fill.target.position.set(0, 0, -1);
    this.scene.add(this.camera);

    this.material = new THREE.MeshPhongMaterial({
      color: SKIN, specular: 0x1c1c1c, shininess: 18, side: THREE.DoubleSide,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
    });
    this.edgeMaterial = new THREE.MeshBasicMaterial({
      color: 0x5a4034, wireframe: true, transparent: true, opacity: 0.18, depthWrite: false,
    });
    this.mesh = null;
    this.edges = null;
    this.overlay = new THREE.Group();
    this.scene.add(this.overlay);
    this.basePositions = null;
    this.size = 1;
    // The live preview's dome (the coarse simulation surface after its run): its own mesh,
    // translucent, drawn over the skin in the placement view.
    this.dome = null;
    this.domeMaterial = new THREE.MeshPhongMaterial({
      color: DOME_PREVIEW, transparent: true, opacity: 0.55, side: THREE.DoubleSide, shininess: 30,
      // In front of the skin where the two lie flat on each other (the region's rim).
      depthWrite: false, polygonOffset: true, polygonOffsetFactor: -2, polygonOffsetUnits: -4,
    });
    this.domeEdges = new THREE.MeshBasicMaterial({
      color: DOME_PREVIEW, wireframe: true, transparent: true, opacity: 0.6, depthWrite: false,
    });

    this.controls = new OrbitControls(this.camera, this.canvas);
    this.controls.enableDamping = false;
    this.controls.addEventListener('change', () => this.requestRender());

    this.raycaster = new THREE.Raycaster();
    this.pending = false;
    this.onResize();
    new ResizeObserver(() => this.onResize()).observe(container);
  }

  onResize() {
    const w = Math.max(1, this.container.clientWidth);
    const h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.renderNow();
  }

  requestRender() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      this.renderNow();
    });
  }

  renderNow() {
    this.renderer.render(this.scene, this.camera);
  }

  /** Shows a new patient: `positions` flat cm, `triangles` flat indices. */
  setMesh(positions, triangles) {
    if (this.mesh) {
      this.scene.remove(this.mesh, this.edges);
      this.mesh.geometry.dispose();
    }
    this.clearOverlay();
    this.setDome(null);
    this.basePositions = Float32Array.from(positions);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(positions), 3));
    const n = positions.length / 3;
    const index = n > 65535 ? Uint32Array.from(triangles) : Uint16Array.from(triangles);
    geometry.setIndex(new THREE.BufferAttribute(index, 1));
    geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(n * 3).fill(1), 3));
    geometry.computeVertexNormals();
    geometry.computeBoundingBox();
    geometry.computeBoundingSphere();
    this.mesh = new THREE.Mesh(geometry, this.material);
    this.edges = new THREE.Mesh(geometry, this.edgeMaterial);
    this.edges.visible = this.edgesShown || false;
    this.scene.add(this.mesh, this.edges);
    this.setColors(null);
    const box = geometry.boundingBox;
    this.size = Math.max(1e-3, box.getSize(new THREE.Vector3()).length());
    this.fit();
  }

  /** Camera straight down the −z axis (y up) onto the mesh's bounding box, all of it in view. */
  fit() {
    if (!this.mesh) return;
    const box = this.mesh.geometry.boundingBox;
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    const vfov = THREE.MathUtils.degToRad(this.camera.fov);
    const hfov = 2 * Math.atan(Math.tan(vfov / 2) * this.camera.aspect);
    // Distance so that the box's x–y extent fits with a margin, from above its top.
    const distV = (size.y / 2) / Math.tan(vfov / 2);
    const distH = (size.x / 2) / Math.tan(hfov / 2);
    const dist = Math.max(distV, distH, this.size * 0.3) * 1.12 + size.z / 2;
    this.camera.position.set(centre.x, centre.y, centre.z + dist);
    this.camera.up.set(0, 1, 0);
    this.camera.near = Math.max(1e-3, dist / 200);
    this.camera.far = dist * 20 + this.size * 10;
    this.camera.updateProjectionMatrix();
    this.key.position.set(-0.45 * this.size, 0.55 * this.size, 0);
    this.controls.target.copy(centre);
    this.controls.minDistance = this.size * 0.05;
    this.controls.maxDistance = this.size * 10;
    this.controls.update();
    this.requestRender();
  }

  /**
   * The default view tipped by `degrees` about the screen's horizontal axis, so that a dome
   * raised towards the camera shows its height (the result's first view).
   */
  oblique(degrees = 50) {
    this.fit();
    const target = this.controls.target.clone();
    const offset = this.camera.position.clone().sub(target);
    this.camera.updateMatrixWorld();
    const right = new THREE.Vector3().setFromMatrixColumn(this.camera.matrixWorld, 0).normalize();
    // Positive about the right axis: the camera goes down the screen (south of a plane seen
    // from +z), so the far side stays at the top.
    offset.applyAxisAngle(right, THREE.MathUtils.degToRad(degrees));
    this.camera.position.copy(target).add(offset);
    this.camera.lookAt(target);
    this.controls.update();
    this.requestRender();
  }

  /** Replaces the displayed positions (flat cm), e.g. the deformed skin; null restores the scan. */
  setPositions(positions) {
    if (!this.mesh) return;
    const attr = this.mesh.geometry.getAttribute('position');
    attr.array.set(positions || this.basePositions);
    attr.needsUpdate = true;
    this.mesh.geometry.computeVertexNormals();
    this.mesh.geometry.computeBoundingSphere();
    this.mesh.geometry.computeBoundingBox();
    this.requestRender();
  }

  /**
   * The live preview's dome: the coarse surface `positions` (flat cm) with `triangles` (flat
   * indices), drawn translucent in the preview colour with its edges; null removes it.
   */
  setDome(positions, triangles) {
    if (this.dome) {
      this.scene.remove(this.dome);
      this.dome.geometry.dispose();
      this.dome = null;
    }
    if (positions && triangles && triangles.length) {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(positions), 3));
      geometry.setIndex(new THREE.BufferAttribute(Uint32Array.from(triangles), 1));
      geometry.computeVertexNormals();
      geometry.computeBoundingSphere();
      this.dome = new THREE.Mesh(geometry, this.domeMaterial);
      this.dome.add(new THREE.Mesh(geometry, this.domeEdges));
      this.dome.renderOrder = 1;
      this.dome.visible = this.overlay.visible;
      this.scene.add(this.dome);
    }
    this.requestRender();
  }

  /** Colours each vertex by `values` scaled from `min` to `max` on the ramp; null: skin colour. */
  setColors(values, min = 0, max = 1) {
    if (!this.mesh) return;
    const attr = this.mesh.geometry.getAttribute('color');
    if (!values) {
      this.material.vertexColors = false;
      this.material.color.setHex(SKIN);
    } else {
      const c = new THREE.Color();
      const span = max - min || 1;
      for (let v = 0; v < attr.count; v++) {
        rampColor((values[v] - min) / span, c);
        attr.setXYZ(v, c.r, c.g, c.b);
      }
      attr.needsUpdate = true;
      this.material.vertexColors = true;
      this.material.color.setHex(0xffffff);
    }
    this.material.needsUpdate = true;
    this.requestRender();
  }

  showEdges(on) {
    this.edgesShown = on;
    if (this.edges) this.edges.visible = on;
    this.requestRender();
  }

  clearOverlay() {
    for (const child of [...this.overlay.children]) {
      this.overlay.remove(child);
      child.geometry?.dispose();
      child.material?.dispose();
    }
    this.requestRender();
  }

  /** A closed polyline (array of [x,y,z], cm) drawn as a thin tube of colour `color`. */
  addLoop(points, color) {
    if (!points || points.length < 2) return;
    const radius = Math.max(0.012, this.size * 0.0022);
    const geometry = new THREE.CylinderGeometry(radius, radius, 1, 8, 1, true);
    const material = new THREE.MeshBasicMaterial({ color });
    const n = points.length;
    const tubes = new THREE.InstancedMesh(geometry, material, n);
    const a = new THREE.Vector3();
    const b = new THREE.Vector3();
    const dir = new THREE.Vector3();
    const up = new THREE.Vector3(0, 1, 0);
    const q = new THREE.Quaternion();
    const m = new THREE.Matrix4();
    const s = new THREE.Vector3();
    let count = 0;
    for (let i = 0; i < n; i++) {
      a.fromArray(points[i]);
      b.fromArray(points[(i + 1) % n]);
      dir.subVectors(b, a);
      const len = dir.length();
      if (len < 1e-9) continue;
      q.setFromUnitVectors(up, dir.divideScalar(len));
      // Slightly longer than the segment so the joints close.
      s.set(1, len + radius, 1);
      m.compose(a.clone().add(b).multiplyScalar(0.5), q, s);
      tubes.setMatrixAt(count++, m);
    }
    tubes.count = count;
    tubes.instanceMatrix.needsUpdate = true;
    tubes.computeBoundingSphere();
    tubes.renderOrder = 2;
    this.overlay.add(tubes);
  }

  /** The placement: implant base, region outline(s), the marker at `point` along `normal`. */
  setOverlay({ footprint, regionOutline, point, normal }) {
    this.clearOverlay();
    if (regionOutline) for (const loop of regionOutline) this.addLoop(loop, REGION);
    if (footprint && footprint.length) this.addLoop(footprint, FOOTPRINT);
    if (point) {
      const r = Math.max(0.05, this.size * 0.007);
      const marker = new THREE.Mesh(
        new THREE.SphereGeometry(r, 16, 12),
        new THREE.MeshPhongMaterial({ color: MARKER, shininess: 40 }),
      );
      marker.position.fromArray(point);
      this.overlay.add(marker);
      if (normal) {
        const n = new THREE.Vector3().fromArray(normal).normalize();
        const len = r * 5;
        const stem = new THREE.Mesh(
          new THREE.CylinderGeometry(r * 0.25, r * 0.25, len, 8),
          new THREE.MeshBasicMaterial({ color: MARKER }),
        );
        stem.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), n);
        stem.position.fromArray(point).addScaledVector(n, len / 2);
        this.overlay.add(stem);
      }
    }
    this.requestRender();
  }

  showOverlay(on) {
    this.overlay.visible = on;
    if (this.dome) this.dome.visible = on;
    this.requestRender();
  }

  /**
   * The surface under the client point (cx, cy), or null: `point` (cm), `face` [a, b, c],
   * `bary` [wa, wb, wc], `vertex` (the face's vertex nearest the point), `normal`.
   */
  pick(cx, cy) {
    if (!this.mesh) return null;
    const rect = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(
      ((cx - rect.left) / rect.width) * 2 - 1,
      -((cy - rect.top) / rect.height) * 2 + 1,
    );
    this.raycaster.setFromCamera(ndc, this.camera);
    const hit = this.raycaster.intersectObject(this.mesh, false)[0];
    if (!hit || !hit.face) return null;
    const pos = this.mesh.geometry.getAttribute('position');
    const face = [hit.face.a, hit.face.b, hit.face.c];
    const corners = face.map((i) => new THREE.Vector3().fromBufferAttribute(pos, i));
    const bary = new THREE.Vector3();
    new THREE.Triangle(...corners).getBarycoord(hit.point, bary);
    let vertex = face[0];
    let best = Infinity;
    corners.forEach((c, k) => {
      const d = c.distanceToSquared(hit.point);
      if (d < best) {
        best = d;
        vertex = face[k];
      }
    });
    return {
      point: hit.point.toArray(),
      face,
      bary: bary.toArray(),
      vertex,
      normal: hit.face.normal.toArray(),
    };
  }

  /** Client (viewport) CSS pixels of the world point `p` (cm), as page.mouse takes them. */
  screenOf(p) {
    const v = new THREE.Vector3().fromArray(p).project(this.camera);
    const rect = this.canvas.getBoundingClientRect();
    return {
      x: rect.left + ((v.x + 1) / 2) * rect.width,
      y: rect.top + ((1 - v.y) / 2) * rect.height,
      visible: v.z > -1 && v.z < 1 && Math.abs(v.x) <= 1 && Math.abs(v.y) <= 1,
    };
  }

  /** Whether the camera is on the side of `normal` at `point` (seeing the outside). */
  seesFront(point, normal) {
    const toCam = this.camera.position.clone().sub(new THREE.Vector3().fromArray(point));
    return toCam.dot(new THREE.Vector3().fromArray(normal)) >= 0;
  }

  /** Renders and counts the pixels that differ from the background, and the distinct colours. */
  pixelStats() {
    this.renderNow();
    const gl = this.renderer.getContext();
    const w = gl.drawingBufferWidth;
    const h = gl.drawingBufferHeight;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    // The clear colour is written as given (sRGB bytes).
    const br = (BACKGROUND >> 16) & 255;
    const bgG = (BACKGROUND >> 8) & 255;
    const bb = BACKGROUND & 255;
    let nonBackground = 0;
    const colours = new Set();
    for (let i = 0; i < px.length; i += 4) {
      const r = px[i], g = px[i + 1], b = px[i + 2];
      if (Math.abs(r - br) + Math.abs(g - bgG) + Math.abs(b - bb) > 6) nonBackground++;
      colours.add((r << 16) | (g << 8) | b);
    }
    return { width: w, height: h, nonBackground, distinctColours: colours.size };
  }

  /** The current view as a PNG blob. */
  toPng() {
    this.renderNow();
    return new Promise((resolve) => this.canvas.toBlob(resolve, 'image/png'));
  }
}
