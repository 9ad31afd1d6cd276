// The surgical trainer: an organ on a tray, simulated on the studio server and streamed to this
// page; probe, scalpel and needle. See apps/studio/API.md, "The trainer".

import * as THREE from 'three';
import { TrainerSocket, listOrgans, uploadOrgan, MAX_UPLOAD } from './trainer-socket.js';
import { TrainerView, ARROW_CM_PER_N } from './trainer-view.js';
import { TissuePanel } from './trainer-material.js';
import { $, clearErrorIn, el, fmt, fmtInt, setText, showErrorIn } from './common.js';

const TOOLS = ['probe', 'scalpel', 'needle'];
const CLICK_SLOP_PX = 6;
const WOUND_OFFSET_CM = 0.4;
const EVENTS_SHOWN = 200;
const PATH_SHOWN_MS = 1500;
const PATH_SPACING_PX = 6; // the scalpel's path: a surface point every few pixels the pointer moves
const MAX_PATH_POINTS = 2000;


// One `state` object holds everything the page knows; it is also the test hook
// `window.tissueStudio.trainer` (apps/studio/browser/README.md).
const state = {
  // What the browser tests read.
  ready: false, // the current organ's first frame is drawn
  steps: 0,
  stepMs: { median: null, p99: null },
  volumeDrift: null,
  events: [],
  tool: 'probe',
  force: [0, 0, 0],
  triangles: 0,
  framesDrawn: 0,
  framesReceived: 0,
  fps: { received: 0, drawn: 0 },
  renderScale: 1,
  error: null,
  paused: false, // the server's word (the stats), or what was asked until it had time to land
  organ: null, // the organ asked for last, then the scene's
  scene: null,
  scenes: 0, // scene messages received (each load, reset or demonstration)
  stats: null,
  reallocations: 0,
  lastCut: null, // { path: [[x,y,z], ...], viewDir, fromVertex }
  material: null, // { scheme, young_kpa, poisson, density, pending } (trainer-material.js)
  selfCollision: null, // in force: the server's word (the scene message, the stats), or what was asked until it had time to land; null until the server has said
  selfContacts: null, // { found, active }: the last step's self-contacts (the stats)
  // The page's own.
  organs: [],
  awaitingScene: false,
  fitPending: false,
  refused: false,
  pauseAsked: false, // what the Pause button shows
  pauseSentAt: 0,
  selfCollisionAsked: null, // what the checkbox shows: null (indeterminate) until the server's default arrives (the first scene message) or a click
  selfCollisionSentAt: 0,
  gesture: null,
  needleFirst: null,
  pathTimer: null,
  tip: [NaN, NaN, NaN],
  received: [], // arrival times of frames (ms), the last second
  drawn: [],
  adaptedAt: 0,
};
window.tissueStudio = Object.assign(window.tissueStudio || {}, { trainer: state });

const showError = (message) => showErrorIn(state, message);
const clearError = () => clearErrorIn(state);

let view;
let socket;
let tissue;

// ---------------------------------------------------------------- formatting


function setReady(on) {
  state.ready = on;
  document.body.classList.toggle('loading', !on);
  updateControls();
}

// ---------------------------------------------------------------- organs

async function initOrgans() {
  try {
    state.organs = await listOrgans();
  } catch (e) {
    showError(e.message);
    state.organs = [];
  }
  const select = $('organ-select');
  select.replaceChildren();
  const chosen = state.organs.find((o) => o.default) || state.organs[0];
  for (const o of state.organs) select.append(el('option', { value: o.id }, o.label));
  if (chosen) {
    select.value = chosen.id;
    load(chosen.id, chosen.label);
  } else {
    setText('view-empty', 'No organ to load. Upload one.');
  }
}

function organLabel(id) {
  const o = state.organs.find((x) => x.id === id);
  return o ? o.label : id;
}

async function load(id, label = organLabel(id)) {
  state.organ = id;
  state.awaitingScene = true;
  state.fitPending = true;
  state.refused = false; // (pausing is the session's, not the organ's: it stays as it is)
  state.events = [];
  state.steps = 0;
  $('events').replaceChildren();
  $('events-empty').hidden = false;
  cancelGesture();
  setNeedleFirst(null);
  state.lastCut = null;
  socket.dropFrames();
  setReady(false);
  setText('organ-status', `Loading ${label}…`);
  $('view-empty').hidden = false;
  setText('view-empty', `Loading ${label}…`);
  try {
    tissue.flush(); // a material waiting in the panel applies to this organ
    // The checkbox's setting for this session (a new connection starts with the server's
    // default); none before the server has said what its default is (the scene message then
    // sets the checkbox) or the checkbox was clicked.
    if (state.selfCollisionAsked !== null) {
      await socket.send({ type: 'self_collision', on: state.selfCollisionAsked });
    }
    await socket.send({ type: 'load', organ: id });
  } catch (e) {
    showError(e.message);
    setText('organ-status', '');
    setText('view-empty', 'Not connected to the studio server.');
  }
}

function uploadFile(file) {
  if (!file) return;
  $('file-input').value = '';
  if (file.size > MAX_UPLOAD) {
    showError(`${file.name} is larger than 64 MiB (${fmtInt(file.size)} bytes); files up to 64 MiB can be loaded.`);
    return;
  }
  const unit = $('unit-select').value;
  setText('organ-status', `Uploading ${file.name} (${unit})…`);
  $('file-input').disabled = true;
  uploadOrgan(file, unit)
    .then((answer) => {
      clearError();
      const label = `${answer.label} (uploaded, ${fmtInt(answer.nodes)} nodes, ${fmtInt(answer.tets)} tets)`;
      state.organs.push({ id: answer.organ, label });
      const select = $('organ-select');
      select.append(el('option', { value: answer.organ }, label));
      select.value = answer.organ;
      load(answer.organ, label);
    })
    .catch((e) => {
      showError(e.message);
      setText('organ-status', state.ready ? `Still showing ${organLabel(state.organ)}.` : '');
      $('organ-select').value = state.organ ?? '';
    })
    .finally(() => {
      $('file-input').disabled = false;
    });
}

// ---------------------------------------------------------------- the session's messages

function onMessage(msg) {
  switch (msg.type) {
    case 'scene':
      onScene(msg);
      break;
    case 'stats':
      onStats(msg);
      break;
    case 'event':
      if (msg.event) addEvent(msg.event);
      break;
    case 'refused':
      socket.close(); // the session runs in another tab: no reconnecting until an organ is chosen
      state.refused = true;
      state.awaitingScene = false;
      showError(msg.error?.message || 'The server refused the session.');
      setText('organ-status', '');
      setText('view-empty', 'The trainer is in use in another tab or window.');
      setReady(false);
      break;
    case 'material':
      tissue.onMaterial(msg);
      break;
    case 'failed':
      if (tissue.onFailed(msg.error)) break; // shown at its input
      showError(msg.error?.message || 'The simulation failed.');
      setText('organ-status', '');
      if (state.awaitingScene) {
        state.awaitingScene = false;
        setText('view-empty', 'The organ could not be loaded.');
      }
      break;
    default:
      break;
  }
}

function onScene(msg) {
  const newOrgan = msg.organ !== state.scene?.organ || state.fitPending;
  state.scene = msg;
  state.scenes++;
  state.organ = msg.organ;
  state.awaitingScene = false;
  state.fitPending = newOrgan;
  socket.dropFrames(); // anything before the scene belongs to the previous one
  view.allocate(msg.capacity.vertices, msg.capacity.triangles);
  if (msg.tray) view.setTray(msg.tray.size, msg.tray.top ?? 0);
  tissue.onScene(msg);
  heardSelfCollision(msg.self_collision);
  state.steps = 0;
  state.triangles = 0;
  setReady(false);
  setText('organ-badge', `${msg.label || organLabel(msg.organ)} · ${fmtInt(msg.nodes)} nodes · ${fmtInt(msg.tets)} tets`);
  setText('h-mesh', `${fmtInt(msg.nodes)} nodes · ${fmtInt(msg.tets)} tets`);
}

function onStats(msg) {
  state.stats = msg;
  // Newer than the last drawn frame (while paused, say); not before this scene's first frame.
  if (state.ready && Number.isFinite(msg.steps) && msg.steps > state.steps) state.steps = msg.steps;
  state.stepMs = { median: msg.step_ms?.median ?? null, p99: msg.step_ms?.p99 ?? null };
  state.volumeDrift = msg.volume_drift ?? null;
  state.paused = !!msg.paused;
  // The button shows what was asked; the server's word wins once the request had time to land.
  if (state.paused !== state.pauseAsked && performance.now() - state.pauseSentAt > 1000) {
    state.pauseAsked = state.paused;
    updateControls();
  }
  state.selfContacts = Number.isFinite(msg.self_contacts)
    ? { found: msg.self_contacts, active: msg.self_contacts_active ?? 0 }
    : null;
  heardSelfCollision(msg.self_collision);
  renderHud();
}

// The server's word on self-collision (the scene message, the stats): in force, and shown by the
// checkbox unless the page asked otherwise less than a second ago (the request on its way). The
// first word is the server's default (on: tissue-scenes' SessionOptions::self_collision).
function heardSelfCollision(on) {
  if (typeof on !== 'boolean') return;
  state.selfCollision = on;
  if (on !== state.selfCollisionAsked && performance.now() - state.selfCollisionSentAt > 1000) {
    state.selfCollisionAsked = on;
    const box = $('self-collision');
    box.indeterminate = false;
    box.checked = on;
  }
}

function addEvent(ev) {
  state.events.push(ev);
  $('events-empty').hidden = true;
  const list = $('events');
  const step = Number.isFinite(ev.step) ? ev.step : state.steps;
  const details = eventDetails(ev);
  const li = el('li', { class: `ev ev-${String(ev.kind).replace(/[^a-z_]/gi, '')}` },
    el('span', { class: 'ev-step' }, `step ${fmtInt(step)}`),
    el('strong', {}, eventTitle(ev.kind)));
  if (details) li.append(el('span', { class: 'ev-detail' }, details));
  list.prepend(li);
  while (list.children.length > EVENTS_SHOWN) list.lastElementChild.remove();
}

function eventTitle(kind) {
  const titles = {
    cut_advanced: 'Cut advanced',
    piece_detached: 'Piece detached',
    suture_placed: 'Suture placed',
    suture_removed: 'Suture removed',
    grabbed: 'Tissue grabbed',
    released: 'Tissue released',
    demo_started: 'Demonstration started',
    demo_finished: 'Demonstration finished',
  };
  if (titles[kind]) return titles[kind];
  const s = String(kind ?? 'event').replace(/_/g, ' ');
  return s.charAt(0).toUpperCase() + s.slice(1);
}

/**
 * The event in words: its `text` when the server gives one, otherwise its other fields
 * ("triangles split 12 · length cm 3.20").
 */
function eventDetails(ev) {
  if (typeof ev.text === 'string' && ev.text.trim() !== '') return ev.text;
  const parts = [];
  for (const [k, v] of Object.entries(ev)) {
    if (k === 'kind' || k === 'step' || k === 'type') continue;
    const name = k.replace(/_/g, ' ');
    let value;
    if (typeof v === 'number') value = Number.isInteger(v) ? fmtInt(v) : fmt(v, 2);
    else if (Array.isArray(v) && v.length === 3 && v.every((x) => typeof x === 'number')) value = `(${v.map((x) => fmt(x, 1)).join(', ')})`;
    else if (typeof v === 'string' || typeof v === 'boolean') value = String(v);
    else continue;
    parts.push(`${name} ${value}`);
  }
  return parts.join(' · ');
}

/** A socket opened again after a loss: the session starts again with the organ shown. */
function onSocketOpened({ reconnected }) {
  if (reconnected && state.organ && !state.refused) load(state.organ);
}

function onSocketClosed() {
  cancelGesture();
  setReady(false);
  state.scene = null;
  if (!state.refused) showError('The connection to the studio server was lost; reconnecting…');
  setText('hud-state', 'disconnected');
}

// ---------------------------------------------------------------- frames and drawing

function onFrameReceived() {
  state.framesReceived++;
  state.received.push(performance.now());
}

function loop() {
  requestAnimationFrame(loop);
  const frame = socket.takeFrame();
  if (frame && !state.awaitingScene && state.scene) {
    const before = view.capacity;
    if (view.applyFrame(frame)) {
      if (view.capacity !== before) state.reallocations++;
      state.steps = frame.step;
      state.triangles = view.triangles;
      const f = frame.force;
      const finite = f.every(Number.isFinite);
      state.force = finite ? [f[0], f[1], f[2]] : [0, 0, 0];
      state.tip = frame.tip;
      view.setForce(state.force, frame.tip);
      if (state.fitPending) {
        view.fit();
        state.fitPending = false;
      }
      view.renderNow();
      state.framesDrawn++;
      state.drawn.push(performance.now());
      if (!state.ready) {
        setReady(true);
        clearErrorIfStale();
        $('view-empty').hidden = true;
        setText('organ-status', '');
      }
      return;
    }
  }
  view.renderIfDirty();
}

function clearErrorIfStale() {
  // A message about a lost connection or a refused session no longer applies once a frame is drawn.
  if (state.error && /connection|in use|refused/i.test(state.error)) clearError();
}

function perSecond(times, now) {
  while (times.length && now - times[0] > 1000) times.shift();
  return times.length;
}

function renderHud() {
  const now = performance.now();
  state.fps = { received: perSecond(state.received, now), drawn: perSecond(state.drawn, now) };
  if (now - state.adaptedAt > 1000 && state.ready && !state.paused) {
    state.adaptedAt = now;
    view.adapt(state.fps.drawn, state.fps.received);
    state.renderScale = view.scale;
  }
  const s = state.stats;
  const fmag = Math.hypot(...state.force);
  setText('h-force', `${fmt(fmag, 3)} N`);
  setText('h-step-ms', s ? `${fmt(s.step_ms?.median, 2)} ms · p99 ${fmt(s.step_ms?.p99, 2)} ms` : '—');
  setText('h-sps', s ? `${fmt(s.steps_per_s, 0)} steps/s` : '—');
  const scale = view.scale < 0.99 ? ` · ${Math.round(view.scale * 100)} % res.` : '';
  setText('h-fps', `${state.fps.received} in · ${state.fps.drawn} drawn /s${scale}`);
  setText('h-drift', s && Number.isFinite(s.volume_drift) ? `${fmt(s.volume_drift * 100, 3)} %` : '—');
  const c = state.selfContacts;
  let self = '—';
  if (s && !state.selfCollision) self = 'off';
  else if (c) self = `${fmtInt(c.found)} (${fmtInt(c.active)} pushed)`;
  setText('h-self', self);
  const nodes = s?.nodes ?? state.scene?.nodes;
  const tets = s?.tets ?? state.scene?.tets;
  setText('h-mesh', `${fmtInt(nodes)} nodes · ${fmtInt(tets)} tets`);
  setText('h-surface', `${fmtInt(view.vertices)} vertices · ${fmtInt(state.triangles)} triangles`);
  setText('h-steps', fmtInt(state.steps));
  const box = state.ready ? view.organBox() : null;
  const top = state.scene?.top;
  setText('h-sag', box && Number.isFinite(top) ? `${fmt(box.max[1], 2)} cm (sag ${fmt(top - box.max[1], 2)} cm)` : '—');
  let status;
  if (state.refused) status = 'refused';
  else if (!state.ready) status = 'loading';
  else status = state.paused ? 'paused' : 'running';
  const badge = $('hud-state');
  badge.textContent = status;
  badge.dataset.state = status;
}

// ---------------------------------------------------------------- tools

const TOOL_HINTS = {
  probe: 'Probe: press on the organ and drag to pull the tissue; let go to release. The red arrow is the tissue\'s force on the probe.',
  scalpel: 'Scalpel: press on the organ and drag across its surface; the cut is made when you let go, into the surface as you see it.',
  needle: 'Needle: click one side of a wound, then the other, to place a suture. Esc forgets the first point.',
};

function setTool(tool) {
  if (!TOOLS.includes(tool)) return;
  if (tool !== state.tool) {
    cancelGesture();
    setNeedleFirst(null);
  }
  state.tool = tool;
  for (const b of document.querySelectorAll('.tool')) {
    const on = b.dataset.tool === tool;
    b.setAttribute('aria-pressed', on ? 'true' : 'false');
    b.classList.toggle('active', on);
  }
  setText('tool-hint', TOOL_HINTS[tool]);
  $('view').dataset.tool = tool;
}

function setNeedleFirst(point) {
  state.needleFirst = point;
  view.setNeedleMarker(point);
}

function cancelGesture() {
  const g = state.gesture;
  if (!g) return;
  state.gesture = null;
  if (g.tool === 'probe') socket.sendIfOpen({ type: 'release' });
  if (g.tool === 'scalpel') view.setPath(null);
  try {
    view.canvas.releasePointerCapture(g.pointerId);
  } catch {
    // not captured
  }
  view.controls.enabled = true;
}

function setupPointer() {
  const container = $('view');
  const canvas = view.canvas;
  // Capture phase on the container: this runs before OrbitControls' own pointerdown on the canvas,
  // and a left press on the organ turns the controls off for the gesture.
  container.addEventListener('pointerdown', (ev) => {
    if (ev.button !== 0 || state.gesture || !state.ready) return;
    const hit = view.pick(ev.clientX, ev.clientY);
    if (!hit) return; // the background: OrbitControls orbits
    view.controls.enabled = false;
    ev.preventDefault();
    canvas.focus({ preventScroll: true });
    try {
      canvas.setPointerCapture(ev.pointerId);
    } catch {
      // synthetic pointer
    }
    const g = { tool: state.tool, pointerId: ev.pointerId, x0: ev.clientX, y0: ev.clientY, lastX: ev.clientX, lastY: ev.clientY, hit };
    state.gesture = g;
    if (g.tool === 'probe') {
      g.grab = hit.point;
      socket.sendIfOpen({ type: 'grab', point: hit.point, triangle: hit.triangle });
    } else if (g.tool === 'scalpel') {
      clearTimeout(state.pathTimer);
      g.path = [hit.point];
      view.setPath(g.path);
    }
  }, { capture: true });

  canvas.addEventListener('pointermove', (ev) => {
    const g = state.gesture;
    if (!g || ev.pointerId !== g.pointerId) return;
    if (g.tool === 'probe') {
      const target = view.onCameraPlane(ev.clientX, ev.clientY, g.grab);
      if (target) socket.sendIfOpen({ type: 'drag', target });
    } else if (g.tool === 'scalpel') {
      // Every pointer position since the last event, and between them every few pixels: the
      // path follows the surface the pointer crossed, however fast it moved.
      const events = typeof ev.getCoalescedEvents === 'function' ? ev.getCoalescedEvents() : [];
      for (const e of events.length ? events : [ev]) {
        const dx = e.clientX - g.lastX;
        const dy = e.clientY - g.lastY;
        const n = Math.max(1, Math.ceil(Math.hypot(dx, dy) / PATH_SPACING_PX));
        for (let k = 1; k <= n; k++) {
          const hit = view.pick(g.lastX + (dx * k) / n, g.lastY + (dy * k) / n);
          if (!hit) continue; // off the organ: the path resumes where the pointer comes back
          const last = g.path[g.path.length - 1];
          const d = Math.hypot(hit.point[0] - last[0], hit.point[1] - last[1], hit.point[2] - last[2]);
          if (d > view.size * 0.002 && g.path.length < MAX_PATH_POINTS) g.path.push(hit.point);
        }
        g.lastX = e.clientX;
        g.lastY = e.clientY;
      }
      view.setPath(g.path);
    }
  });

  const end = (ev) => {
    const g = state.gesture;
    if (!g || ev.pointerId !== g.pointerId) return;
    state.gesture = null;
    view.controls.enabled = true;
    try {
      canvas.releasePointerCapture(ev.pointerId);
    } catch {
      // not captured
    }
    if (g.tool === 'probe') {
      socket.sendIfOpen({ type: 'release' });
    } else if (g.tool === 'scalpel') {
      if (ev.type === 'pointerup' && g.path.length >= 2) {
        const viewDir = view.viewDir(new THREE.Vector3()).toArray();
        socket.sendIfOpen({ type: 'cut', path: g.path, view_dir: viewDir });
        // The nodes this cut adds come after the ones there now (the frame's vertices are the
        // body's nodes): where the wound is as the organ moves on.
        state.lastCut = { path: g.path, viewDir, fromVertex: view.vertices };
        state.pathTimer = setTimeout(() => view.setPath(null), PATH_SHOWN_MS);
      } else {
        view.setPath(null);
      }
    } else if (g.tool === 'needle') {
      const moved = Math.hypot(ev.clientX - g.x0, ev.clientY - g.y0);
      if (ev.type !== 'pointerup' || moved > CLICK_SLOP_PX) return;
      const hit = view.pick(ev.clientX, ev.clientY) || g.hit;
      if (!state.needleFirst) {
        setNeedleFirst(hit.point);
      } else {
        socket.sendIfOpen({ type: 'suture', a: state.needleFirst, b: hit.point });
        setNeedleFirst(null);
      }
    }
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
  canvas.addEventListener('lostpointercapture', (ev) => {
    if (state.gesture && ev.pointerId === state.gesture.pointerId) end({ ...ev, type: 'pointercancel', pointerId: ev.pointerId, clientX: ev.clientX, clientY: ev.clientY });
  });
}

// ---------------------------------------------------------------- controls

function updateControls() {
  const pause = $('pause');
  pause.textContent = state.pauseAsked ? 'Resume' : 'Pause';
  pause.setAttribute('aria-pressed', state.pauseAsked ? 'true' : 'false');
  pause.disabled = !state.ready && !state.pauseAsked;
  $('step').disabled = !state.pauseAsked || !state.scene;
  $('reset').disabled = !state.scene;
  $('demo').disabled = !state.scene;
  renderHud();
}

function togglePause() {
  state.pauseAsked = !state.pauseAsked;
  state.pauseSentAt = performance.now();
  state.paused = state.pauseAsked;
  socket.send({ type: 'pause', paused: state.pauseAsked }).catch((e) => showError(e.message));
  updateControls();
}

function setSelfCollision(on) {
  state.selfCollisionAsked = on;
  state.selfCollisionSentAt = performance.now();
  state.selfCollision = on;
  $('self-collision').indeterminate = false;
  $('self-collision').checked = on;
  socket.send({ type: 'self_collision', on }).catch((e) => showError(e.message));
  renderHud();
}

function reset() {
  cancelGesture();
  setNeedleFirst(null);
  state.lastCut = null;
  tissue.flush(); // the panel's material applies from this reset on
  socket.send({ type: 'reset' }).catch((e) => showError(e.message));
}

function demo() {
  cancelGesture();
  setNeedleFirst(null);
  state.lastCut = null;
  tissue.flush();
  socket.send({ type: 'demo' }).catch((e) => showError(e.message));
}

function wire() {
  $('organ-select').addEventListener('change', (e) => {
    const id = e.target.value;
    if (id) load(id);
  });
  $('file-input').addEventListener('change', (e) => uploadFile(e.target.files[0]));
  for (const b of document.querySelectorAll('.tool')) b.addEventListener('click', () => setTool(b.dataset.tool));
  $('pause').addEventListener('click', togglePause);
  $('step').addEventListener('click', () => socket.send({ type: 'step' }).catch((e) => showError(e.message)));
  $('reset').addEventListener('click', reset);
  $('demo').addEventListener('click', demo);
  $('self-collision').addEventListener('change', (e) => setSelfCollision(e.target.checked));
  $('self-collision').indeterminate = true; // until the server says (heardSelfCollision) or a click
  $('reset-view').addEventListener('click', () => view.fit());
  document.addEventListener('keydown', (ev) => {
    if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
    const t = ev.target;
    if (t instanceof HTMLInputElement || t instanceof HTMLSelectElement || t instanceof HTMLTextAreaElement) return;
    const tool = { 1: 'probe', 2: 'scalpel', 3: 'needle' }[ev.key];
    if (tool) {
      setTool(tool);
      ev.preventDefault();
    } else if (ev.key === 'Escape') {
      setNeedleFirst(null);
    }
  });
}

// ---------------------------------------------------------------- test helpers

/** Two surface points either side of the last cut's middle, re-picked on the surface; or null. */
function woundSides() {
  const path = state.lastCut?.path;
  if (!path || path.length < 2) return null;
  const pts = path.map((p) => new THREE.Vector3().fromArray(p));
  const lengths = [0];
  for (let i = 1; i < pts.length; i++) lengths.push(lengths[i - 1] + pts[i].distanceTo(pts[i - 1]));
  const half = lengths[lengths.length - 1] / 2;
  let i = 1;
  while (i < pts.length - 1 && lengths[i] < half) i++;
  const seg = lengths[i] - lengths[i - 1] || 1;
  let mid = pts[i - 1].clone().lerp(pts[i], (half - lengths[i - 1]) / seg);
  // The wound where it is now: the middle of the nodes the cut added (on its walls), which
  // moved with the organ since the path was drawn. The path as drawn when there are none.
  const added = view.nodesFrom(state.lastCut.fromVertex ?? view.vertices);
  if (added) mid = added;
  // The path's direction around the middle (over a few points, steadier than one segment).
  const a = pts[Math.max(0, i - 3)];
  const b = pts[Math.min(pts.length - 1, i + 2)];
  const tangent = b.clone().sub(a).normalize();
  const across = tangent.clone().cross(view.viewDir(new THREE.Vector3())).normalize();
  if (!Number.isFinite(across.x) || across.lengthSq() < 0.5) return null;
  const sides = [];
  for (const sign of [-1, 1]) {
    const p = mid.clone().addScaledVector(across, sign * WOUND_OFFSET_CM);
    const s = view.screenOf(p.toArray());
    const hit = view.pick(s.x, s.y);
    if (!hit) return null;
    sides.push(hit.point);
  }
  return sides;
}

// ---------------------------------------------------------------- start

function main() {
  view = new TrainerView($('view'));
  socket = new TrainerSocket({ onMessage, onOpen: onSocketOpened, onClose: onSocketClosed, onFrameReceived });
  tissue = new TissuePanel({ send: (m) => socket.send(m).catch((e) => showError(e.message)), state });
  Object.assign(state, {
    screenOf: (p) => view.screenOf(p),
    surfacePointAt: (x, y) => view.pick(x, y)?.point ?? null,
    organBox: () => view.organBox(),
    woundSides,
    setTool,
  });
  wire();
  setupPointer();
  setTool('probe');
  setText('view-hint', '');
  $('view-hint').append(
    'Left-drag ', el('strong', {}, 'on the organ'), ' uses the instrument. Orbit: right-drag, or left-drag on the background. ',
    `Pan: middle-drag. Zoom: scroll. Force arrow: ${ARROW_CM_PER_N} cm per newton.`,
  );
  updateControls();
  setInterval(renderHud, 250);
  requestAnimationFrame(loop);
  tissue.init().finally(initOrgans);
}

main();
