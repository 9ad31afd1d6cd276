// The implant planner: patient → placement → simulation. See apps/studio/API.md.

import * as api from './planner-api.js';
import { PlannerView, RAMP } from './planner-view.js';
import { $, MAX_UPLOAD, clearErrorIn, el, fmt, fmtInt, setText, showErrorIn } from './common.js';

const PREVIEW_DEBOUNCE_MS = 150;
const CLICK_SLOP_PX = 5;


// ---- The state hook for tests (kept up to date; see the brief in apps/studio/browser/README.md).
const hook = {
  ready: false,
  placement: null,
  job: { state: 'idle', step: 0, settle: 0 },
  result: null,
  error: null,
  preview: null,
};
window.tissueStudio = Object.assign(window.tissueStudio || {}, { planner: hook });

const state = {
  step: 1,
  patient: null, // the POST /api/patients answer
  source: null, // { kind: 'shipped', id } | { kind: 'upload', file }
  loading: false,
  placement: null, // { point, vertex, normal }
  previewSeq: 0,
  previewTimer: null,
  previewPending: false,
  previewOk: false,
  inputProblem: null,
  jobId: null,
  jobMode: null,
  lastRun: null, // { job, mode, report, fields, patient }
  resultStale: false,
  showing: 'placement', // or 'result'
  colormap: 'displacement',
  before: false,
};

const showError = (message) => showErrorIn(hook, message);
const clearError = () => clearErrorIn(hook);

let view;
let socket;

// ---------------------------------------------------------------- formatting

function fmtPoint(p, digits = 2) {
  return `(${p.map((v) => fmt(v, digits)).join(', ')})`;
}

// ---------------------------------------------------------------- steps

function showStep(n) {
  state.step = n;
  for (const k of [1, 2, 3]) {
    $(`step-${k}`).hidden = k !== n;
    const tab = $(`tab-${k}`);
    if (k === n) tab.setAttribute('aria-current', 'step');
    else tab.removeAttribute('aria-current');
  }
  if (n === 3 && state.lastRun && state.lastRun.fields && state.lastRun.patient === state.patient?.patient) {
    showResultView();
  } else {
    showPlacementView();
  }
  updateRunControls();
}

// ---------------------------------------------------------------- patient

function setReady(on) {
  hook.ready = on;
  document.body.classList.toggle('loading', !on);
}

function patientControlsEnabled(on) {
  $('mesh-select').disabled = !on;
  $('unit-select').disabled = !on;
  $('file-input').disabled = !on;
}

async function loadPatient(fetcher, source, what) {
  const had = !!state.patient;
  state.loading = true;
  setReady(false);
  patientControlsEnabled(false);
  setText('patient-status', `Loading ${what}…`);
  updateRunControls();
  try {
    const answer = await fetcher();
    clearError();
    state.source = source;
    $('mesh-select').value = source.kind === 'shipped' ? source.id : '';
    setPatient(answer);
    setText('patient-status', '');
  } catch (e) {
    showError(e.message);
    $('mesh-select').value = state.source && state.source.kind === 'shipped' ? state.source.id : '';
    setText('patient-status', had ? `Still showing ${state.patient.label}.` : '');
  } finally {
    state.loading = false;
    patientControlsEnabled(true);
    setReady(!!state.patient);
    updateRunControls();
  }
}

function setPatient(answer) {
  state.patient = answer;
  state.placement = null;
  state.resultStale = false;
  hook.placement = null;
  hook.preview = null;
  state.previewOk = false;
  state.previewSeq++;
  clearTimeout(state.previewTimer);
  view.setMesh(answer.mesh.positions, answer.mesh.triangles);
  $('view-empty').hidden = true;
  showPlacementView();
  view.renderNow();
  $('result').hidden = true;
  $('sweep-result').hidden = true;
  $('target-result').hidden = true;
  $('preview-error').hidden = true;
  setText('preview-status', '');
  setText('patient-badge', `${answer.label} · ${answer.unit}`);
  renderSummary(answer);
  renderPlacement();
}

function renderSummary(answer) {
  const s = answer.summary;
  $('summary').hidden = false;
  setText('summary-title', answer.label);
  setText('s-vertices', fmtInt(s.vertices));
  setText('s-triangles', fmtInt(s.triangles));
  setText('s-area', `${fmt(s.area_cm2, 1)} cm²`);
  setText('s-closed', s.closed ? 'closed' : 'open');
  const loops = s.boundary_loops || [];
  setText('s-loops', loops.length === 0 ? 'none'
    : `${loops.length}: ${loops.slice(0, 4).map((l) => `${fmtInt(l.edges)} edges, ${fmt(l.length_cm, 1)} cm`).join('; ')}${loops.length > 4 ? '; …' : ''}`);
  setText('s-components', fmtInt(s.components));
  setText('s-edge', `${fmt(s.median_edge_cm, 3)} cm`);
  const size = s.bounding_box_cm?.size;
  setText('s-size', size ? `${size.map((v) => fmt(v, 1)).join(' × ')} cm` : '—');
  setText('s-unit', `${answer.unit} (${fmt(answer.cm_per_unit, answer.cm_per_unit < 1 ? 2 : 0)} cm per unit)`);
  const list = $('s-defects');
  list.replaceChildren();
  const defects = s.defects || [];
  if (defects.length === 0) list.append(el('li', { class: 'none' }, 'None found.'));
  for (const d of defects) {
    list.append(el('li', { class: `sev-${d.severity}` }, el('strong', {}, `${d.severity}: `), d.message));
  }
}

async function initMeshes() {
  let meshes = [];
  try {
    meshes = await api.listMeshes();
  } catch (e) {
    showError(e.message);
  }
  const select = $('mesh-select');
  select.replaceChildren();
  select.append(el('option', { value: '' }, '— choose a shipped mesh —'));
  let chosen = meshes.find((m) => m.default) || meshes[0];
  for (const m of meshes) {
    const o = el('option', { value: m.id }, `${m.label}`);
    if (chosen && m.id === chosen.id) o.selected = true;
    select.append(o);
  }
  if (chosen) await loadPatient(() => api.loadShipped(chosen.id), { kind: 'shipped', id: chosen.id }, chosen.label);
  else $('view-empty').textContent = 'No patient loaded. Choose or upload one.';
}

function onMeshSelect() {
  const id = $('mesh-select').value;
  if (!id) return;
  const label = $('mesh-select').selectedOptions[0].textContent;
  loadPatient(() => api.loadShipped(id), { kind: 'shipped', id }, label);
}

function uploadFile(file) {
  if (!file) return;
  if (file.size > MAX_UPLOAD) {
    showError(`${file.name} is larger than 64 MiB (${fmtInt(file.size)} bytes); files up to 64 MiB can be loaded.`);
    $('file-input').value = '';
    return;
  }
  if (!/\.(obj|ply|stl)$/i.test(file.name)) {
    showError(`${file.name}: choose an OBJ, PLY or STL file (by its extension).`);
    $('file-input').value = '';
    return;
  }
  const unit = $('unit-select').value;
  loadPatient(() => api.uploadPatient(file, unit), { kind: 'upload', file }, `${file.name} (${unit})`);
}

function onUnitChange() {
  // A file already loaded is read again in the new unit.
  if (state.source && state.source.kind === 'upload' && !state.loading) uploadFile(state.source.file);
}

// ---------------------------------------------------------------- placement

function canPlace() {
  return hook.ready && !!state.patient && hook.job.state !== 'running' && state.showing === 'placement';
}

function setPlacement(p) {
  state.placement = p;
  hook.placement = { point: p.point.slice(), vertex: p.vertex };
  state.previewOk = false;
  if (state.lastRun) state.resultStale = true;
  view.setOverlay({ point: p.point, normal: p.normal });
  renderPlacement();
  if (state.step === 1) showStep(2);
  schedulePreview();
}

function renderPlacement() {
  const p = state.placement;
  const text = p ? `Centre at ${fmtPoint(p.point)} cm, vertex ${p.vertex}.` : 'No point placed yet: click the skin.';
  setText('placement-text', text);
  $('use-suggested').disabled = !state.patient?.suggested;
  renderRunSummary();
}

/** What a click on the surface at `point` (cm) does; for tests that cannot aim a click. */
function placeAt(point) {
  if (!canPlace()) return false;
  let hit = null;
  const s = view.screenOf(point);
  if (s.visible) {
    const h = view.pick(s.x, s.y);
    const d = h ? Math.hypot(...h.point.map((v, i) => v - point[i])) : Infinity;
    if (h && d < Math.max(0.05, view.size * 0.01)) hit = h;
  }
  if (!hit) hit = { point: point.slice(), vertex: nearestVertex(point), normal: null };
  setPlacement({ point: hit.point, vertex: hit.vertex, normal: hit.normal });
  return true;
}

function nearestVertex(point) {
  const pos = state.patient.mesh.positions;
  let best = 0;
  let bestD = Infinity;
  for (let v = 0; v < pos.length / 3; v++) {
    const d = (pos[3 * v] - point[0]) ** 2 + (pos[3 * v + 1] - point[1]) ** 2 + (pos[3 * v + 2] - point[2]) ** 2;
    if (d < bestD) {
      bestD = d;
      best = v;
    }
  }
  return best;
}

function num(id) {
  const raw = $(id).value.trim();
  if (raw === '') return null;
  const x = Number(raw);
  return Number.isFinite(x) ? x : NaN;
}

/** The REQUEST of the controls, or throws an Error naming the field at fault. */
function buildRequest() {
  const shape = $('shape').value;
  const req = { shape };
  const need = (id, name, unit, min = 0) => {
    const x = num(id);
    if (x === null || Number.isNaN(x) || x <= min) {
      throw new Error(`${name} must be a number above ${min} ${unit}.`);
    }
    return x;
  };
  const optional = (id, name, unit) => {
    const x = num(id);
    if (x === null) return null;
    if (Number.isNaN(x) || x <= 0) throw new Error(`${name} must be a number above 0 ${unit}, or left empty.`);
    return x;
  };
  if (shape === 'round') {
    req.diameter_cm = need('diameter', 'Diameter', 'cm');
  } else if (shape === 'rectangular') {
    req.length_cm = need('rect-length', 'Length', 'cm');
    req.width_cm = need('rect-width', 'Width', 'cm');
    const c = num('corner-radius');
    if (c === null || Number.isNaN(c) || c < 0) throw new Error('Corner radius must be 0 cm or more.');
    req.corner_radius_cm = c;
  } else {
    req.length_cm = need('cres-length', 'Length', 'cm');
    req.width_cm = need('cres-width', 'Width', 'cm');
    req.bend_radius_cm = need('bend-radius', 'Bend radius', 'cm');
  }
  req.volume_cm3 = need('volume', 'Volume', 'cm³');
  const depth = num('depth');
  if (depth === null || Number.isNaN(depth) || depth < 0) throw new Error('Depth must be 0 cm or more.');
  req.depth_cm = depth;
  req.rotation_deg = Number($('rotation').value);
  req.region_radius_cm = optional('region-radius', 'Region radius', 'cm');
  req.sim_edge_cm = optional('sim-edge', 'Simulation edge', 'cm');
  const steps = optional('max-steps', 'Step limit', 'steps');
  if (steps !== null) req.max_steps = Math.round(steps);
  const p = state.placement;
  if (p) {
    const k = state.patient.cm_per_unit || 1;
    req.at = p.point.map((v) => v / k);
    if (p.vertex !== null && p.vertex !== undefined) req.vertex = p.vertex;
  }
  return req;
}

function onParamsChanged() {
  setText('rotation-out', `${$('rotation').value}°`);
  if (state.lastRun) state.resultStale = true;
  renderRunSummary();
  schedulePreview();
}

function schedulePreview() {
  clearTimeout(state.previewTimer);
  state.previewOk = false;
  state.previewPending = true;
  updateRunControls();
  state.previewTimer = setTimeout(runPreview, PREVIEW_DEBOUNCE_MS);
}

async function runPreview() {
  if (!state.patient) return;
  let request;
  try {
    request = buildRequest();
    state.inputProblem = null;
  } catch (e) {
    state.inputProblem = e.message;
    state.previewPending = false;
    showPreviewProblem(e.message);
    updateRunControls();
    return;
  }
  if (!state.placement) {
    state.previewPending = false;
    updateRunControls();
    return;
  }
  const seq = ++state.previewSeq;
  const patient = state.patient.patient;
  setText('preview-status', 'Checking the placement…');
  let answer;
  try {
    answer = await api.preview(patient, request);
  } catch (e) {
    answer = { ok: false, error: { kind: e.kind, field: e.field, message: e.message }, placement: null, footprint: [], region_outline: [] };
  }
  if (seq !== state.previewSeq) return; // a newer preview is on its way
  state.previewPending = false;
  hook.preview = answer;
  state.previewOk = !!answer.ok;
  const pl = answer.placement;
  const normal = pl?.normal || state.placement.normal;
  view.setOverlay({
    footprint: answer.footprint || [],
    regionOutline: answer.ok ? answer.region_outline || [] : [],
    point: state.placement.point,
    normal,
  });
  if (pl?.normal) state.placement.normal = pl.normal;
  if (answer.ok) {
    $('preview-error').hidden = true;
    const parts = [];
    if (answer.region_radius_cm != null) parts.push(`region radius ${fmt(answer.region_radius_cm, 2)} cm`);
    if (answer.region_vertices != null) parts.push(`${fmtInt(answer.region_vertices)} region vertices`);
    if (answer.sim_edge_cm != null) parts.push(`simulation edge ${fmt(answer.sim_edge_cm, 3)} cm`);
    setText('preview-status', parts.length ? `Placement checked: ${parts.join(', ')}.` : 'Placement checked.');
  } else {
    showPreviewProblem(answer.error?.message || 'The placement cannot be used.');
  }
  updateRunControls();
}

function showPreviewProblem(message) {
  $('preview-error').textContent = message;
  $('preview-error').hidden = false;
  setText('preview-status', '');
}

// Shape selector shows its dimensions.
function onShapeChange() {
  const shape = $('shape').value;
  for (const d of document.querySelectorAll('.dims')) d.hidden = d.dataset.shape !== shape;
  onParamsChanged();
}

// ---------------------------------------------------------------- pointer on the view

function setupPointer() {
  const canvas = view.canvas;
  let down = null;
  let rotating = null;
  // Capture phase on the canvas: runs before OrbitControls' own listener, so a shift+drag that
  // turns the expander does not also pan the camera.
  canvas.addEventListener('pointerdown', (e) => {
    down = { x: e.clientX, y: e.clientY, button: e.button, shift: e.shiftKey };
    if (e.button === 0 && e.shiftKey && state.placement && canPlace()) {
      const hit = view.pick(e.clientX, e.clientY);
      if (hit) {
        const c = view.screenOf(state.placement.point);
        const normal = state.placement.normal || [0, 0, 1];
        rotating = {
          c,
          start: Math.atan2(-(e.clientY - c.y), e.clientX - c.x),
          rotation: Number($('rotation').value),
          sign: view.seesFront(state.placement.point, normal) ? 1 : -1,
        };
        view.controls.enabled = false;
        canvas.setPointerCapture(e.pointerId);
      }
    }
  }, { capture: true });

  canvas.addEventListener('pointermove', (e) => {
    if (rotating) {
      const a = Math.atan2(-(e.clientY - rotating.c.y), e.clientX - rotating.c.x);
      let deg = rotating.rotation + rotating.sign * ((a - rotating.start) * 180) / Math.PI;
      deg = ((((deg + 180) % 360) + 360) % 360) - 180;
      $('rotation').value = String(Math.round(deg));
      onParamsChanged();
      return;
    }
    if (e.buttons === 0) hover(e);
  });

  const end = (e) => {
    if (rotating) {
      rotating = null;
      view.controls.enabled = true;
      down = null;
      return;
    }
    if (!down || e.type !== 'pointerup') {
      down = null;
      return;
    }
    const moved = Math.hypot(e.clientX - down.x, e.clientY - down.y);
    const wasClick = down.button === 0 && !down.shift && moved < CLICK_SLOP_PX;
    down = null;
    if (!wasClick) return;
    if (!canPlace()) {
      if (state.showing === 'result') {
        setText('job-status', 'To move the expander, go back to step 2 (Placement).');
      }
      return;
    }
    const hit = view.pick(e.clientX, e.clientY);
    if (hit) setPlacement({ point: hit.point, vertex: hit.vertex, normal: hit.normal });
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
  canvas.addEventListener('pointerleave', () => {
    $('readout').hidden = true;
  });
}

let hoverFrame = 0;
let hoverEvent = null;
function hover(e) {
  hoverEvent = e;
  if (hoverFrame) return;
  hoverFrame = requestAnimationFrame(() => {
    hoverFrame = 0;
    const ev = hoverEvent;
    const box = $('readout');
    const run = state.lastRun;
    if (state.showing !== 'result' || !run || !run.fields || state.colormap === 'none') {
      box.hidden = true;
      return;
    }
    const hit = view.pick(ev.clientX, ev.clientY);
    if (!hit) {
      box.hidden = true;
      return;
    }
    const field = run.fields[state.colormap];
    const value = hit.face.reduce((s, v, k) => s + hit.bary[k] * field[v], 0);
    box.textContent = state.colormap === 'displacement'
      ? `displacement ${fmt(value, 2)} cm`
      : `stretch ${fmt(value, 3)} × (area ratio)`;
    const rect = view.container.getBoundingClientRect();
    box.style.left = `${ev.clientX - rect.left + 14}px`;
    box.style.top = `${ev.clientY - rect.top + 14}px`;
    box.hidden = false;
  });
}

// ---------------------------------------------------------------- views

function showPlacementView() {
  state.showing = 'placement';
  view.setPositions(null);
  view.setColors(null);
  view.showOverlay(true);
  $('colorbar').hidden = true;
  $('readout').hidden = true;
  $('legend').hidden = false;
}

function showResultView() {
  const run = state.lastRun;
  state.showing = 'result';
  view.showOverlay(false);
  $('legend').hidden = true;
  view.setPositions(state.before ? null : run.fields.after);
  applyColormap();
}

function fieldRange(values, kind) {
  let min = Infinity;
  let max = -Infinity;
  for (const v of values) {
    if (v < min) min = v;
    if (v > max) max = v;
  }
  if (kind === 'displacement') min = 0;
  if (!(max - min > 1e-9)) max = min + (kind === 'stretch' ? 0.01 : 0.001);
  return [min, max];
}

function applyColormap() {
  const run = state.lastRun;
  const kind = state.colormap;
  if (state.showing !== 'result' || !run || !run.fields) return;
  if (kind === 'none') {
    view.setColors(null);
    $('colorbar').hidden = true;
    return;
  }
  const values = run.fields[kind];
  const [min, max] = fieldRange(values, kind);
  view.setColors(values, min, max);
  if (kind === 'displacement') {
    setText('cb-title', 'Displacement (cm)');
    setText('cb-min', `${fmt(min, 2)} cm`);
    setText('cb-max', `${fmt(max, 2)} cm`);
  } else {
    setText('cb-title', 'Stretch (area after ÷ before)');
    setText('cb-min', `${fmt(min, 2)} ×`);
    setText('cb-max', `${fmt(max, 2)} ×`);
  }
  $('colorbar').hidden = false;
}

// ---------------------------------------------------------------- jobs

function canRun() {
  return !!state.patient && hook.ready && !!state.placement && state.previewOk && !state.previewPending
    && !state.inputProblem && hook.job.state !== 'running';
}

function updateRunControls() {
  const running = hook.job.state === 'running';
  const ok = canRun();
  $('run').disabled = !ok;
  $('sweep-start').disabled = !ok;
  $('target-start').disabled = !ok;
  $('expansion-start').disabled = !ok;
  $('cancel').disabled = !running || state.cancelSent;
  const blocked = $('run-blocked');
  let why = null;
  if (!running) {
    if (!state.patient) why = 'Load a patient first (step 1).';
    else if (!state.placement) why = 'Place the expander first: click the skin in step 2.';
    else if (state.inputProblem) why = state.inputProblem;
    else if (!state.previewOk && !state.previewPending && hook.preview && !hook.preview.ok) {
      why = `Placement problem: ${hook.preview.error?.message || 'the placement cannot be used.'}`;
    }
  }
  blocked.hidden = !why;
  blocked.textContent = why || '';
  for (const input of document.querySelectorAll('#step-2 input, #step-2 select, #use-suggested')) {
    input.disabled = running || (input.id === 'use-suggested' && !state.patient?.suggested);
  }
  patientControlsEnabled(!running && !state.loading);
}

function renderRunSummary() {
  const p = state.placement;
  const target = $('run-summary');
  if (!state.patient || !p) {
    target.textContent = '';
    return;
  }
  const shape = $('shape').value;
  let size;
  if (shape === 'round') size = `round, ${$('diameter').value} cm across`;
  else if (shape === 'rectangular') size = `rectangular, ${$('rect-length').value} × ${$('rect-width').value} cm`;
  else size = `crescent, ${$('cres-length').value} × ${$('cres-width').value} cm`;
  target.textContent = `${size}, ${$('volume').value} cm³, ${$('depth').value} cm deep, turned ${$('rotation').value}°, `
    + `centred at ${fmtPoint(p.point)} cm on ${state.patient.label}.`;
}

function setJob(fields) {
  Object.assign(hook.job, fields);
  document.body.dataset.job = hook.job.state;
}

async function startJob(mode, extra, requestExtra) {
  if (!canRun()) return;
  let request;
  try {
    request = { ...buildRequest(), ...(requestExtra || {}) };
  } catch (e) {
    showError(e.message);
    return;
  }
  clearError();
  hook.result = null;
  state.jobId = null;
  state.jobMode = mode;
  state.cancelSent = false;
  setJob({ state: 'running', step: 0, settle: 0, run: 0, runs: 1, max_steps: 0, job: null, mode });
  renderProgress();
  setText('job-status', mode === 'single' ? 'Starting the simulation…' : 'Starting the series…');
  if (mode === 'single') {
    $('result').hidden = true;
    if (state.showing === 'result') showPlacementView();
  }
  if (mode === 'sweep') $('sweep-result').hidden = true;
  if (mode === 'target-gain') $('target-result').hidden = true;
  if (mode === 'expansion') $('expansion-result').hidden = true;
  updateRunControls();
  try {
    await socket.send({ type: 'run', patient: state.patient.patient, mode, ...extra, request });
  } catch (e) {
    setJob({ state: 'failed' });
    showError(e.message);
    setText('job-status', '');
    updateRunControls();
  }
}

function renderProgress() {
  const j = hook.job;
  const runs = j.runs || 1;
  const run = j.run || 0;
  let value = runs > 1 ? (run + (j.settle || 0)) / runs : j.settle || 0;
  if (j.state === 'finished') value = 1;
  $('progress').value = Math.min(1, Math.max(0, value));
  setText('progress-run', runs > 1 ? `run ${run + 1} of ${runs} · ` : '');
  setText('progress-step', `step ${fmtInt(j.step || 0)} of ${fmtInt(j.max_steps || 0)}`);
  setText('progress-settle', `settle ${Math.round((j.settle || 0) * 100)} %`);
}

function onSocketMessage(msg) {
  const mine = !msg.job || !state.jobId || msg.job === state.jobId;
  switch (msg.type) {
    case 'accepted':
      state.jobId = msg.job;
      setJob({ job: msg.job });
      setText('job-status', msg.mode === 'single' ? 'Simulating…' : 'Running the series…');
      break;
    case 'progress':
      if (!mine || hook.job.state !== 'running') return;
      setJob({ step: msg.step, settle: msg.settle, run: msg.run, runs: msg.runs, max_steps: msg.max_steps, elapsed_s: msg.elapsed_s });
      renderProgress();
      break;
    case 'finished':
      if (!mine) return;
      onFinished(msg);
      break;
    case 'cancelled':
      if (!mine) return;
      // From the Cancel click to the server's word that the job stopped, measured in the page.
      setJob({
        state: 'cancelled',
        step: msg.steps ?? hook.job.step,
        cancel_ms: state.cancelAt ? performance.now() - state.cancelAt : null,
      });
      state.cancelAt = null;
      setText('job-status', `Cancelled after ${fmtInt(msg.steps ?? hook.job.step)} steps.`);
      updateRunControls();
      break;
    case 'failed':
      if (!mine) return;
      setJob({ state: 'failed' });
      showError(msg.error?.message || 'The run failed.');
      setText('job-status', '');
      updateRunControls();
      break;
    case 'refused':
      if (hook.job.state !== 'running') return;
      setJob({ state: 'refused' });
      showError(msg.error?.message || 'The server refused the run.');
      setText('job-status', '');
      updateRunControls();
      break;
    default:
      break;
  }
}

function onSocketClosed() {
  if (hook.job.state === 'running') {
    setJob({ state: 'failed' });
    showError('The connection to the studio server was lost, and with it the run.');
    setText('job-status', '');
    updateRunControls();
  }
}

function onFinished(msg) {
  const report = msg.report;
  hook.result = report;
  setJob({ state: 'finished', job: msg.job });
  renderProgress();
  const mode = report.mode || state.jobMode;
  if (mode === 'sweep') {
    renderSweep(report, msg.job);
    setText('job-status', `Series finished: ${report.runs?.length ?? 0} runs.`);
  } else if (mode === 'expansion') {
    renderExpansion(report, msg.job);
    setText('job-status', `Expansion finished: flap ${fmt(report.flap?.flap_area_cm2, 1)} cm² after removal.`);
  } else if (mode === 'target-gain') {
    renderTarget(report, msg.job);
    setText('job-status', report.converged ? 'Search finished.' : 'Search finished without converging.');
  } else {
    state.lastRun = { job: msg.job, mode, report, fields: msg.fields, patient: state.patient.patient };
    state.resultStale = false;
    renderReport(report, msg.job);
    if (report.steps != null) setText('progress-step', `step ${fmtInt(report.steps)} of ${fmtInt(report.max_steps ?? hook.job.max_steps)}`);
    if (report.stop_reason === 'settled') setText('progress-settle', 'settled');
    setText('job-status', `Finished in ${fmtInt(report.steps)} steps (${report.stop_reason === 'settled' ? 'settled' : 'step limit reached'}).`);
    if (msg.fields && state.step === 3) {
      showResultView();
      // Tipped, so that the raised skin shows its height; "Reset view" looks straight on again.
      view.oblique();
    }
  }
  updateRunControls();
}

function renderReport(r, job) {
  $('result').hidden = false;
  const dl = $('report-figures');
  dl.replaceChildren();
  const row = (label, value, cls) => {
    dl.append(el('dt', cls ? { class: cls } : {}, label), el('dd', cls ? { class: cls } : {}, value));
  };
  row('Area before', `${fmt(r.area_before_cm2, 2)} cm²`);
  row('Area after', `${fmt(r.area_after_cm2, 2)} cm²`);
  row('Area gain', `${fmt(r.area_gain_cm2, 2)} cm²`, 'key');
  row('Volume difference', `${fmt(r.volume_difference_cm3, 2)} cm³`);
  row('Implant compression', `${fmt((r.implant_compression ?? 0) * 100, 2)} %`);
  if (r.max_displacement_cm != null) row('Max displacement', `${fmt(r.max_displacement_cm, 2)} cm`);
  row('Steps', r.max_steps ? `${fmtInt(r.steps)} of at most ${fmtInt(r.max_steps)}` : fmtInt(r.steps));
  row('Stop reason', r.stop_reason === 'settled' ? 'settled' : r.stop_reason === 'step_limit' ? 'step limit reached (not settled)' : String(r.stop_reason ?? '—'));
  row('Wall time', `${fmt(r.wall_time_s, 2)} s`);
  if (r.boundary_unchanged != null) row('Region edge kept in place', r.boundary_unchanged ? 'yes' : 'no');
  if (r.region_vertices != null) row('Region', `${fmtInt(r.region_vertices)} vertices, radius ${fmt(r.region_radius_cm, 2)} cm`);
  const where = {
    simulation_surface: 'Areas and volume are measured on the simulation surface (the region remeshed).',
    patient_region: "Areas and volume are measured on the patient's own triangles in the region.",
  }[r.measured_on] || (r.measured_on ? `Measured on: ${r.measured_on}.` : '');
  let text = where;
  if (r.scan) {
    text += ` On the scan's own triangles: gain ${fmt(r.scan.area_gain_cm2, 2)} cm², volume difference ${fmt(r.scan.volume_difference_cm3, 2)} cm³.`;
  }
  setText('measured-on', text);
  $('dl-ply').href = api.resultUrl(job, 'patient.ply');
  $('dl-obj').href = api.resultUrl(job, 'patient.obj');
  $('dl-vtk').href = api.resultUrl(job, 'patient.vtk');
  $('dl-report').href = api.resultUrl(job, 'report.json');
}

function runsTable(table, rows, columns) {
  table.replaceChildren();
  const head = el('tr');
  for (const c of columns) head.append(el('th', { scope: 'col' }, c.label));
  table.append(el('thead', {}, head));
  const body = el('tbody');
  for (const r of rows) {
    const tr = el('tr');
    for (const c of columns) tr.append(el('td', {}, c.value(r)));
    body.append(tr);
  }
  table.append(body);
}

function niceTicks(lo, hi, count = 5) {
  const span = hi - lo || 1;
  const step0 = span / count;
  const mag = 10 ** Math.floor(Math.log10(step0));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= step0) || step0;
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + step * 1e-6; t += step) ticks.push(+t.toPrecision(12));
  return ticks;
}

function renderSweep(report, job) {
  const runs = report.runs || [];
  $('sweep-result').hidden = false;
  const pts = runs.map((r) => [r.volume_cm3 ?? r.inputs?.volume_cm3, r.area_gain_cm2]).filter((p) => Number.isFinite(p[0]) && Number.isFinite(p[1]));
  $('sweep-chart').replaceChildren(chart(pts));
  runsTable($('sweep-table'), runs, [
    { label: 'Volume (cm³)', value: (r) => fmt(r.volume_cm3, 0) },
    { label: 'Area gain (cm²)', value: (r) => fmt(r.area_gain_cm2, 2) },
    { label: 'Volume diff. (cm³)', value: (r) => fmt(r.volume_difference_cm3, 1) },
    { label: 'Steps', value: (r) => `${fmtInt(r.steps)}${r.stop_reason && r.stop_reason !== 'settled' ? ' (limit)' : ''}` },
  ]);
  addReportLink($('sweep-result'), job);
}

function renderTarget(report, job) {
  $('target-result').hidden = false;
  const dl = $('target-figures');
  dl.replaceChildren();
  const row = (label, value, cls) => dl.append(el('dt', cls ? { class: cls } : {}, label), el('dd', cls ? { class: cls } : {}, value));
  row('Target gain', `${fmt(report.target_gain_cm2, 2)} cm²`);
  row('Volume', `${fmt(report.volume_cm3, 1)} cm³`, 'key');
  row('Its gain', `${fmt(report.area_gain_cm2, 2)} cm²`);
  row('Converged', report.converged ? 'yes' : 'no — the answer is the best run found');
  if (report.bracket_cm3) row('Searched', `${fmt(report.bracket_cm3[0], 0)} to ${fmt(report.bracket_cm3[1], 0)} cm³`);
  runsTable($('target-table'), report.runs || [], [
    { label: 'Run', value: (r) => String((report.runs || []).indexOf(r) + 1) },
    { label: 'Volume (cm³)', value: (r) => fmt(r.volume_cm3, 1) },
    { label: 'Area gain (cm²)', value: (r) => fmt(r.area_gain_cm2, 2) },
  ]);
  addReportLink($('target-result'), job);
}

function renderExpansion(report, job) {
  $('expansion-result').hidden = false;
  $('expansion-chart').replaceChildren(expansionChart(report));
  const dl = $('expansion-figures');
  dl.replaceChildren();
  const row = (label, value, cls) => dl.append(el('dt', cls ? { class: cls } : {}, label), el('dd', cls ? { class: cls } : {}, value));
  const f = report.flap || {};
  const b = report.band;
  row('Flap after removal', `${fmt(f.flap_area_cm2, 1)} cm²` + (b ? ` (P5–P95 ${fmt(b.flap_area_cm2.p5, 1)}–${fmt(b.flap_area_cm2.p95, 1)})` : ''), 'key');
  row('Linear retraction', `${fmt(100 * f.retraction, 1)} %` + (b ? ` (${fmt(100 * b.retraction.p5, 1)}–${fmt(100 * b.retraction.p95, 1)})` : ''));
  row('Flap on the expander', `${fmt(f.dome_area_cm2, 1)} cm² (recruited ${fmt(f.recruited_area_cm2, 1)} cm²)`);
  row('Grown area', `${fmt(f.grown_area_cm2, 1)} cm²`);
  row('Geometric gain', `${fmt(f.geometric_gain_cm2, 1)} cm²`);
  row('Efficiency', `${fmt(100 * f.efficiency, 1)} %`);
  runsTable($('expansion-table'), report.weeks || [], [
    { label: 'Week', value: (r) => String(r.week) },
    { label: 'Volume (cm³)', value: (r) => fmt(r.volume_cm3, 0) },
    { label: 'Area gain (cm²)', value: (r) => fmt(r.area_gain_cm2, 1) },
    { label: 'Grown (cm²)', value: (r) => fmt(r.grown_gain_cm2, 1) },
  ]);
  addReportLink($('expansion-result'), job);
  const p = $('expansion-result').querySelector('.report-link');
  p.append(' · ', el('a', { href: api.resultUrl(job, 'chart.png'), download: '' }, 'chart.png'));
}

/** An SVG chart of an expansion's days: volume (cm³), area gain and skin grown (cm²), the flap's band. */
function expansionChart(report) {
  const NS = 'http://www.w3.org/2000/svg';
  const W = 340;
  const H = 230;
  const m = { l: 44, r: 14, t: 12, b: 40 };
  const svg = document.createElementNS(NS, 'svg');
  svg.setAttribute('viewBox', `0 0 ${W} ${H}`);
  svg.setAttribute('role', 'img');
  svg.setAttribute('aria-label', 'Expansion over the days: volume, area gain, skin grown, and the flap at removal');
  const add = (tag, attrs, text) => {
    const e = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    if (text !== undefined) e.textContent = text;
    svg.append(e);
    return e;
  };
  const days = report.days || [];
  const series = [
    { key: 'volume_cm3', color: '#5a5a5a', label: 'volume cm³' },
    { key: 'area_gain_cm2', color: '#285ac8', label: 'area gain cm²' },
    { key: 'grown_gain_cm2', color: '#1e963c', label: 'grown cm²' },
  ];
  const band = report.band?.flap_area_cm2;
  const removal = report.protocol?.removal_day ?? 0;
  const ys = days.flatMap((d) => series.map((s) => d[s.key])).concat(band ? [band.p95] : []).filter(Number.isFinite);
  const x1 = Math.max(removal, ...days.map((d) => d.day), 1);
  const y1 = Math.max(1, ...ys) * 1.1;
  const X = (x) => m.l + (x / x1) * (W - m.l - m.r);
  const Y = (y) => H - m.b - (y / y1) * (H - m.t - m.b);
  for (const t of niceTicks(0, x1)) {
    add('line', { x1: X(t), x2: X(t), y1: m.t, y2: H - m.b, class: 'grid' });
    add('text', { x: X(t), y: H - m.b + 16, 'text-anchor': 'middle', class: 'tick' }, String(t));
  }
  for (const t of niceTicks(0, y1)) {
    add('line', { x1: m.l, x2: W - m.r, y1: Y(t), y2: Y(t), class: 'grid' });
    add('text', { x: m.l - 6, y: Y(t) + 4, 'text-anchor': 'end', class: 'tick' }, String(t));
  }
  add('line', { x1: m.l, x2: W - m.r, y1: H - m.b, y2: H - m.b, class: 'axis' });
  add('line', { x1: m.l, x2: m.l, y1: m.t, y2: H - m.b, class: 'axis' });
  add('text', { x: (m.l + W - m.r) / 2, y: H - 6, 'text-anchor': 'middle', class: 'axis-label' }, 'day');
  series.forEach((s, i) => {
    const pts = days.filter((d) => Number.isFinite(d[s.key])).map((d) => `${X(d.day)},${Y(d[s.key])}`);
    add('polyline', { points: pts.join(' '), fill: 'none', stroke: s.color, 'stroke-width': 2, class: 'expansion-line' });
    // The colour as SVG's own attribute: a style attribute is inline style, which the server's
    // Content-Security-Policy refuses.
    add('text', { x: m.l + 8, y: m.t + 12 + 13 * i, class: 'legend', fill: s.color }, s.label);
  });
  if (band) {
    add('line', { x1: X(removal), x2: X(removal), y1: Y(band.p5), y2: Y(band.p95), stroke: '#c83c28', 'stroke-width': 2, class: 'expansion-band' });
    add('circle', { cx: X(removal), cy: Y(band.p50), r: 4, fill: '#c83c28' });
  }
  return svg;
}

function startExpansion() {
  const weeks = Number($('expand-weeks').value);
  if (!Number.isInteger(weeks) || weeks < 1 || weeks > 52) {
    showError('Weeks of fills: give a whole number from 1 to 52 (usually 8–12).');
    return;
  }
  startJob('expansion', {}, { expand_weeks: weeks });
}

function addReportLink(section, job) {
  let p = section.querySelector('.report-link');
  if (!p) {
    p = el('p', { class: 'downloads report-link' });
    section.append(p);
  }
  p.replaceChildren('Download: ', el('a', { href: api.resultUrl(job, 'report.json'), download: '' }, 'report.json'));
}

/** An SVG chart of area gain (cm²) against volume (cm³). */
function chart(points) {
  const NS = 'http://www.w3.org/2000/svg';
  const W = 340;
  const H = 230;
  const m = { l: 52, r: 14, t: 12, b: 44 };
  const svg = document.createElementNS(NS, 'svg');
  svg.setAttribute('viewBox', `0 0 ${W} ${H}`);
  svg.setAttribute('role', 'img');
  svg.setAttribute('aria-label', `Area gain against volume: ${points.map((p) => `${fmt(p[0], 0)} cm³ → ${fmt(p[1], 1)} cm²`).join('; ')}`);
  const add = (tag, attrs, text) => {
    const e = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    if (text !== undefined) e.textContent = text;
    svg.append(e);
    return e;
  };
  if (points.length === 0) {
    add('text', { x: W / 2, y: H / 2, 'text-anchor': 'middle', class: 'axis-label' }, 'No runs to plot.');
    return svg;
  }
  const xs = points.map((p) => p[0]);
  const ys = points.map((p) => p[1]);
  let x0 = Math.min(0, ...xs);
  let x1 = Math.max(...xs);
  if (x1 - x0 < 1e-9) x1 = x0 + 1;
  x1 += (x1 - x0) * 0.05;
  let y0 = Math.min(0, ...ys);
  let y1 = Math.max(...ys);
  if (y1 - y0 < 1e-9) y1 = y0 + 1;
  y1 += (y1 - y0) * 0.1;
  const X = (x) => m.l + ((x - x0) / (x1 - x0)) * (W - m.l - m.r);
  const Y = (y) => H - m.b - ((y - y0) / (y1 - y0)) * (H - m.t - m.b);
  for (const t of niceTicks(x0, x1)) {
    add('line', { x1: X(t), x2: X(t), y1: m.t, y2: H - m.b, class: 'grid' });
    add('text', { x: X(t), y: H - m.b + 16, 'text-anchor': 'middle', class: 'tick' }, String(t));
  }
  for (const t of niceTicks(y0, y1)) {
    add('line', { x1: m.l, x2: W - m.r, y1: Y(t), y2: Y(t), class: 'grid' });
    add('text', { x: m.l - 6, y: Y(t) + 4, 'text-anchor': 'end', class: 'tick' }, String(t));
  }
  add('line', { x1: m.l, x2: W - m.r, y1: H - m.b, y2: H - m.b, class: 'axis' });
  add('line', { x1: m.l, x2: m.l, y1: m.t, y2: H - m.b, class: 'axis' });
  add('text', { x: (m.l + W - m.r) / 2, y: H - 8, 'text-anchor': 'middle', class: 'axis-label' }, 'implant volume (cm³)');
  add('text', { x: 14, y: (m.t + H - m.b) / 2, 'text-anchor': 'middle', class: 'axis-label', transform: `rotate(-90 14 ${(m.t + H - m.b) / 2})` }, 'area gain (cm²)');
  const sorted = [...points].sort((a, b) => a[0] - b[0]);
  add('polyline', { points: sorted.map((p) => `${X(p[0])},${Y(p[1])}`).join(' '), class: 'series-line' });
  for (const p of sorted) {
    add('circle', { cx: X(p[0]), cy: Y(p[1]), r: 4, class: 'series-dot' });
    add('text', { x: X(p[0]), y: Y(p[1]) - 8, 'text-anchor': 'middle', class: 'point-label' }, fmt(p[1], 1));
  }
  return svg;
}

function parseVolumes(text) {
  const parts = text.split(/[\s,;]+/).filter(Boolean);
  const values = parts.map(Number);
  if (parts.length === 0 || values.some((v) => !Number.isFinite(v) || v <= 0)) {
    throw new Error('Volumes: give numbers of cm³ above 0, separated by commas, e.g. 50, 100, 150.');
  }
  return values;
}

function startSweep() {
  let volumes;
  try {
    volumes = parseVolumes($('sweep-volumes').value);
  } catch (e) {
    showError(e.message);
    return;
  }
  startJob('sweep', { volumes_cm3: volumes });
}

function startTarget() {
  const gain = num('target-gain');
  if (gain === null || Number.isNaN(gain) || gain <= 0) {
    showError('Target gain must be a number of cm² above 0.');
    return;
  }
  const lo = num('bracket-lo');
  const hi = num('bracket-hi');
  let bracket = null;
  if (lo !== null || hi !== null) {
    if (lo === null || hi === null || Number.isNaN(lo) || Number.isNaN(hi) || lo <= 0 || hi <= lo) {
      showError('Volume bracket: give both ends in cm³, the first smaller than the second, or leave both empty.');
      return;
    }
    bracket = [lo, hi];
  }
  startJob('target-gain', { target_gain_cm2: gain, bracket_cm3: bracket });
}

async function cancelJob() {
  if (hook.job.state !== 'running') return;
  state.cancelSent = true;
  state.cancelAt = performance.now();
  updateRunControls();
  setText('job-status', 'Cancelling…');
  try {
    await socket.send({ type: 'cancel' });
  } catch (e) {
    showError(e.message);
  }
}

async function savePng() {
  const blob = await view.toPng();
  if (!blob) return;
  const url = URL.createObjectURL(blob);
  const a = el('a', { href: url, download: `studio-${state.lastRun?.job || 'view'}.png` });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

// ---------------------------------------------------------------- start

function wire() {
  for (const tab of document.querySelectorAll('.step-tab')) {
    tab.addEventListener('click', () => showStep(Number(tab.dataset.step)));
  }
  for (const b of document.querySelectorAll('[data-goto]')) {
    b.addEventListener('click', () => showStep(Number(b.dataset.goto)));
  }
  $('mesh-select').addEventListener('change', onMeshSelect);
  $('unit-select').addEventListener('change', onUnitChange);
  $('file-input').addEventListener('change', (e) => uploadFile(e.target.files[0]));
  $('use-suggested').addEventListener('click', () => {
    const s = state.patient?.suggested;
    if (!s || !canPlace()) return;
    setPlacement({ point: s.point.slice(), vertex: s.vertex, normal: null });
  });
  $('shape').addEventListener('change', onShapeChange);
  for (const input of document.querySelectorAll('#step-2 input')) {
    input.addEventListener('input', onParamsChanged);
  }
  $('run').addEventListener('click', () => startJob('single', {}));
  $('cancel').addEventListener('click', cancelJob);
  $('sweep-start').addEventListener('click', startSweep);
  $('target-start').addEventListener('click', startTarget);
  $('expansion-start').addEventListener('click', startExpansion);
  for (const r of document.querySelectorAll('input[name="beforeafter"]')) {
    r.addEventListener('change', () => {
      state.before = document.querySelector('input[name="beforeafter"]:checked').value === 'before';
      if (state.showing === 'result') showResultView();
    });
  }
  $('colormap').addEventListener('change', () => {
    state.colormap = $('colormap').value;
    $('readout').hidden = true;
    applyColormap();
  });
  $('png').addEventListener('click', savePng);
  $('reset-view').addEventListener('click', () => view.fit());
  $('show-edges').addEventListener('change', (e) => view.showEdges(e.target.checked));
  document.querySelector('.cb-ramp').style.background = `linear-gradient(to right, ${RAMP.join(', ')})`;
}

function main() {
  view = new PlannerView($('view'));
  socket = new api.JobSocket(onSocketMessage, onSocketClosed);
  Object.assign(hook, {
    placeAt,
    screenOf: (p) => view.screenOf(p),
    pixelStats: () => view.pixelStats(),
    showStep,
    startExpansion: (weeks, extra) => {
      $('expand-weeks').value = String(weeks);
      return startJob('expansion', {}, { expand_weeks: weeks, ...(extra || {}) });
    },
  });
  wire();
  setupPointer();
  showStep(1);
  renderProgress();
  initMeshes();
}

main();
