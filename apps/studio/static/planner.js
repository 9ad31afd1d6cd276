// The implant planner: patient → placement → simulation. See apps/studio/API.md.
//
// One `state` object holds everything the page knows; it is also the test hook
// `window.tissueStudio.planner` (apps/studio/browser/README.md). The server owns every rule about
// the numbers: the page sends what was typed, and shows the server's field errors at the inputs.

import * as api from './planner-api.js';
import { PlannerView, RAMP } from './planner-view.js';
import { setupPointer } from './planner-pointer.js';
import { renderColorbar, renderExpansion, renderReport, renderSummary, renderSweep, renderTarget } from './planner-report.js';
import { $, MAX_UPLOAD, clearErrorIn, el, fmt, fmtInt, renderFieldErrors, saveBlob, setText, showErrorIn } from './common.js';

const PREVIEW_DEBOUNCE_MS = 150;

const state = {
  // What the browser tests read (apps/studio/browser/README.md).
  ready: false, // the patient's mesh is shown
  placement: null, // { point (cm), vertex, normal }
  job: { state: 'idle', step: 0, settle: 0 }, // + run, runs, max_steps, job, mode, cancel_ms
  result: null, // the last finished report
  saved: null, // the last plan saved to the case library (its PlanInfo), for the finished job
  spec: null, // the job started last: { mode, ...JobSpec members, request }
  error: null, // the message in #error
  check: null, // the last placement check (POST /api/preview) answer
  preview: null, // the live preview: { ms, gain, edge_cm, stale, seq, steps, computed }
  // The errors shown at the inputs, by request field: the page's own (a number field holding
  // something that is not a number), and the server's for the last run (until the input is edited).
  inputErrors: {},
  runErrors: {},
  // The page's own.
  step: 1,
  patient: null, // the POST /api/patients answer
  source: null, // { kind: 'shipped', id } | { kind: 'upload', file }
  loading: false,
  previewSeq: 0,
  previewTimer: null,
  previewPending: false,
  lastRun: null, // { job, mode, report, fields, patient }
  showing: 'placement', // or 'result'
  colormap: 'displacement',
  before: false,
  cancelSent: false,
  cancelAt: null,
};
window.tissueStudio = Object.assign(window.tissueStudio || {}, { planner: state });

const showError = (message) => showErrorIn(state, message);
const clearError = () => clearErrorIn(state);

let view;
let socket;

function fmtPoint(p, digits = 2) {
  return `(${p.map((v) => fmt(v, digits)).join(', ')})`;
}

// ---------------------------------------------------------------- requests and their errors

// The number inputs of step 2 and the request fields they set (length and width: the inputs of
// the shape chosen).
const REQUEST_INPUTS = {
  diameter_cm: 'diameter', corner_radius_cm: 'corner-radius', bend_radius_cm: 'bend-radius',
  volume_cm3: 'volume', depth_cm: 'depth', region_radius_cm: 'region-radius', sim_edge_cm: 'sim-edge',
  max_steps: 'max-steps',
};
const REQUEST_FIELDS = [...Object.keys(REQUEST_INPUTS), 'length_cm', 'width_cm'];
// The other fields a server error may name, and where the page sets them.
const OTHER_INPUTS = {
  rotation_deg: 'rotation', tangent: 'rotation', volumes_cm3: 'sweep-volumes',
  target_gain_cm2: 'target-gain', bracket_cm3: 'bracket-lo', expand_weeks: 'expand-weeks',
  solver: 'solver',
};

/** The id of the input that sets request field `field`, or null. */
function inputOf(field) {
  const shape = $('shape').value;
  const prefix = shape === 'rectangular' ? 'rect' : 'cres';
  if ((field === 'length_cm' || field === 'width_cm') && shape !== 'round') return `${prefix}-${field.slice(0, -3)}`;
  return REQUEST_INPUTS[field] || OTHER_INPUTS[field] || null;
}

/** The number in input `id`: undefined when empty, NaN when the browser holds a non-number. */
function readNumber(id, field, errors) {
  const input = $(id);
  if (input.validity?.badInput) {
    errors[field] = 'Enter a number.';
    return NaN;
  }
  const raw = input.value.trim();
  return raw === '' ? undefined : Number(raw);
}

/**
 * The REQUEST of the controls, as typed (an empty input leaves its field to the library's
 * default), and the inputs that hold no number.
 */
function buildRequest(extra = {}) {
  const errors = {};
  const shape = $('shape').value;
  const request = { shape };
  const fields = shape === 'round' ? ['diameter_cm']
    : shape === 'rectangular' ? ['length_cm', 'width_cm', 'corner_radius_cm'] : ['length_cm', 'width_cm', 'bend_radius_cm'];
  for (const field of [...fields, 'volume_cm3', 'depth_cm', 'region_radius_cm', 'sim_edge_cm', 'max_steps']) {
    const x = readNumber(inputOf(field), field, errors);
    if (x !== undefined) request[field] = x;
  }
  request.rotation_deg = Number($('rotation').value);
  request.solver = $('solver').value;
  const p = state.placement;
  if (p) {
    const k = state.patient.cm_per_unit || 1;
    request.at = p.point.map((v) => v / k);
    if (p.vertex !== null && p.vertex !== undefined) request.vertex = p.vertex;
  }
  return { request: { ...request, ...extra }, errors };
}

/** The field errors at the inputs: the page's own, the preview's (when current), the last run's. */
function renderErrors() {
  const errors = { ...state.runErrors };
  const e = state.check?.error;
  if (!state.previewPending && state.check && !state.check.ok && e?.field && inputOf(e.field)) errors[e.field] = e.message;
  Object.assign(errors, state.inputErrors);
  for (const [field, message] of Object.entries(errors)) {
    const details = inputOf(field) && $(inputOf(field))?.closest('details');
    if (details && message) details.open = true;
  }
  return renderFieldErrors(errors, inputOf);
}

/** Whether a request field's input holds something that is not a number. */
function requestInputErrors() {
  return REQUEST_FIELDS.some((f) => f in state.inputErrors);
}

/** An edit of input `id` clears the errors shown at it. */
function onInputEdited(id) {
  for (const errors of [state.runErrors, state.inputErrors]) {
    for (const field of Object.keys(errors)) if (inputOf(field) === id) delete errors[field];
  }
  renderErrors();
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
  if (n === 3 && state.lastRun?.fields && state.lastRun.patient === state.patient?.patient) showResultView();
  else showPlacementView();
  renderRunControls();
}

// ---------------------------------------------------------------- patient

function setReady(on) {
  state.ready = on;
  document.body.classList.toggle('loading', !on);
}

async function loadPatient(fetcher, source, what) {
  const had = !!state.patient;
  state.loading = true;
  setReady(false);
  setText('patient-status', `Loading ${what}…`);
  renderRunControls();
  try {
    const answer = await fetcher();
    clearError();
    state.source = source;
    $('mesh-select').value = source.kind === 'shipped' ? source.id : '';
    setPatient(answer);
    setText('patient-status', '');
  } catch (e) {
    showError(e.message);
    $('mesh-select').value = state.source?.kind === 'shipped' ? state.source.id : '';
    setText('patient-status', had ? `Still showing ${state.patient.label}.` : '');
  } finally {
    state.loading = false;
    setReady(!!state.patient);
    renderRunControls();
  }
}

function setPatient(answer) {
  Object.assign(state, { patient: answer, placement: null, check: null, preview: null, previewPending: false, runErrors: {} });
  resetLive();
  state.previewSeq++;
  clearTimeout(state.previewTimer);
  view.setMesh(answer.mesh.positions, answer.mesh.triangles);
  $('view-empty').hidden = true;
  showPlacementView();
  view.renderNow();
  for (const id of ['result', 'sweep-result', 'target-result', 'expansion-result']) $(id).hidden = true;
  renderPreview();
  setText('patient-badge', `${answer.label} · ${answer.unit}`);
  renderSummary(answer);
  renderPlacement();
}

async function initMeshes() {
  // /planner?case=PATIENT: a patient of the case library, to plan on again.
  const stored = new URLSearchParams(location.search).get('case');
  if (stored) {
    await loadPatient(() => api.openStoredPatient(stored), { kind: 'stored', id: stored }, 'the stored patient');
  }
  let meshes = [];
  try {
    meshes = await api.listMeshes();
  } catch (e) {
    showError(e.message);
  }
  const select = $('mesh-select');
  const chosen = meshes.find((m) => m.default) || meshes[0];
  select.replaceChildren(el('option', { value: '' }, '— choose a shipped mesh —'),
    ...meshes.map((m) => el('option', { value: m.id }, m.label)));
  if (stored && state.patient) {
    select.value = '';
  } else if (chosen) {
    select.value = chosen.id;
    await loadPatient(() => api.loadShipped(chosen.id), { kind: 'shipped', id: chosen.id }, chosen.label);
  } else {
    $('view-empty').textContent = 'No patient loaded. Choose or upload one.';
  }
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
  const unit = $('unit-select').value;
  loadPatient(() => api.uploadPatient(file, unit), { kind: 'upload', file }, `${file.name} (${unit})`);
}

function onUnitChange() {
  // A file already loaded is read again in the new unit.
  if (state.source?.kind === 'upload' && !state.loading) uploadFile(state.source.file);
}

// ---------------------------------------------------------------- placement

function canPlace() {
  return state.ready && !!state.patient && state.job.state !== 'running' && state.showing === 'placement';
}

function setPlacement(p, t = performance.now()) {
  state.placement = { point: p.point.slice(), vertex: p.vertex, normal: p.normal };
  view.setOverlay({ point: p.point, normal: p.normal });
  renderPlacement();
  if (state.step === 1) showStep(2);
  schedulePreview();
  livePreview(t, true);
}

/**
 * A drag of the expander over the skin, at event time `t`: the marker follows, the preview too
 * (`last`: the expander let go there).
 */
function dragPlacement(hit, t, last = false) {
  if (!canPlace()) return;
  state.placement = { point: hit.point.slice(), vertex: hit.vertex, normal: hit.normal };
  view.setOverlay({ point: hit.point, normal: hit.normal });
  renderPlacement();
  schedulePreview();
  livePreview(t, last);
}

function renderPlacement() {
  const p = state.placement;
  setText('placement-text', p ? `Centre at ${fmtPoint(p.point)} cm, vertex ${p.vertex}.` : 'No point placed yet: click the skin.');
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
  setPlacement(hit || { point: point.slice(), vertex: nearestVertex(point), normal: null });
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

// ---------------------------------------------------------------- the preview

// The sliders beside number inputs, and the input each sets.
const SLIDERS = { 'volume-slider': 'volume', 'depth-slider': 'depth' };

function onParamsChanged(e) {
  const id = e?.target?.id;
  if (SLIDERS[id]) $(SLIDERS[id]).value = e.target.value;
  for (const [slider, input] of Object.entries(SLIDERS)) {
    if (id === input && e.target.value.trim() !== '' && !e.target.validity?.badInput) $(slider).value = e.target.value;
  }
  setText('rotation-out', `${$('rotation').value}°`);
  renderRunSummary();
  schedulePreview();
  livePreview(e?.timeStamp);
  if (id) onInputEdited(SLIDERS[id] || id);
}

function onShapeChange() {
  const shape = $('shape').value;
  for (const d of document.querySelectorAll('.dims')) d.hidden = d.dataset.shape !== shape;
  onParamsChanged();
}

function schedulePreview() {
  clearTimeout(state.previewTimer);
  state.previewPending = true;
  renderPreview();
  state.previewTimer = setTimeout(runPreview, PREVIEW_DEBOUNCE_MS);
}

async function runPreview() {
  if (!state.patient) return;
  const { request, errors } = buildRequest();
  for (const field of REQUEST_FIELDS) delete state.inputErrors[field];
  Object.assign(state.inputErrors, errors);
  if (Object.keys(errors).length || !state.placement) {
    state.previewPending = false;
    state.check = null;
    renderPreview();
    return;
  }
  const seq = ++state.previewSeq;
  setText('preview-status', 'Checking the placement…');
  let answer;
  try {
    answer = await api.preview(state.patient.patient, request);
  } catch (e) {
    answer = { ok: false, error: { kind: e.kind, field: e.field, message: e.message }, placement: null, footprint: [], region_outline: [] };
  }
  if (seq !== state.previewSeq) return; // a newer preview is on its way
  state.previewPending = false;
  state.check = answer;
  if (answer.placement?.normal) state.placement.normal = answer.placement.normal;
  view.setOverlay({
    footprint: answer.footprint || [],
    regionOutline: answer.ok ? answer.region_outline || [] : [],
    point: state.placement.point,
    normal: state.placement.normal,
  });
  renderPreview();
}

/** The preview's answer: its figures, or its error (at the input it names, or in the box). */
function renderPreview() {
  const a = state.previewPending ? null : state.check;
  const atInput = !!(a?.error?.field && inputOf(a.error.field));
  const box = $('preview-error');
  box.hidden = !a || a.ok || atInput;
  box.textContent = box.hidden ? '' : a.error?.message || 'The placement cannot be used.';
  const parts = [];
  if (a?.ok) {
    if (a.region_radius_cm != null) parts.push(`region radius ${fmt(a.region_radius_cm, 2)} cm`);
    if (a.region_vertices != null) parts.push(`${fmtInt(a.region_vertices)} region vertices`);
    if (a.sim_edge_cm != null) parts.push(`simulation edge ${fmt(a.sim_edge_cm, 3)} cm`);
  }
  if (!state.previewPending) setText('preview-status', !a?.ok ? '' : parts.length ? `Placement checked: ${parts.join(', ')}.` : 'Placement checked.');
  renderErrors();
  renderRunControls();
}

// ---------------------------------------------------------------- the live preview
//
// While the expander is dragged or a parameter moves, the server runs the request coarse
// (tissue-planner's Previewer) and the page draws the dome and its gain, marked "preview". One
// preview is in flight at a time; inputs meanwhile only mark the newest as queued, and it is sent
// when the one in flight answers. `state.preview.ms` is from the input event that the drawn
// preview answers (the newest one folded into its request) to the preview drawn.

const live = { seq: 0, inFlight: null, queued: null };

function resetLive() {
  Object.assign(live, { inFlight: null, queued: null });
  state.preview = null;
  view.setDome(null);
  renderLivePreview();
}

/**
 * An input that changes the dome, at event time `t` (performance.now()'s clock). `last`: the
 * gesture's end (the expander let go): sent at once, the server cancels the one in flight.
 */
function livePreview(t, last = false) {
  if (!state.patient || !state.placement || state.job.state === 'running') return;
  live.queued = { t0: Number.isFinite(t) && t > 0 ? t : performance.now() };
  state.preview = { ms: null, gain: null, edge_cm: null, ...state.preview, stale: true };
  renderLivePreview();
  if (!live.inFlight || last) sendLivePreview();
}

async function sendLivePreview() {
  const queued = live.queued;
  live.queued = null;
  if (!queued || !state.patient || !state.placement) return;
  const { request, errors } = buildRequest();
  if (Object.keys(errors).length) {
    state.preview = { ...state.preview, stale: false };
    renderLivePreview();
    return;
  }
  const json = JSON.stringify(request);
  if (live.inFlight?.json === json) {
    // The one in flight is this request already (the pointer let go where it last moved): its
    // answer answers this input too.
    live.inFlight.t0 = queued.t0;
    return;
  }
  const seq = ++live.seq;
  live.inFlight = { seq, t0: queued.t0, sent: performance.now(), json };
  try {
    await socket.send({ type: 'preview', patient: state.patient.patient, seq, request });
  } catch (e) {
    live.inFlight = null;
    state.preview = { ...state.preview, stale: false, error: e.message };
    renderLivePreview();
  }
}

function onLivePreview(msg) {
  if (!live.inFlight || msg.seq !== live.inFlight.seq) return; // not the one in flight
  const { t0, sent } = live.inFlight;
  const arrived = performance.now();
  live.inFlight = null;
  const p = msg.preview;
  if (p && state.job.state !== 'running') {
    view.setDome(p.positions, p.triangles);
    view.renderNow();
  } else {
    view.setDome(null);
  }
  const ms = performance.now() - t0;
  state.preview = {
    ms, gain: p ? p.gain_cm2 : null, edge_cm: p ? p.edge_cm : null, stale: !!live.queued,
    seq: msg.seq, steps: p?.steps ?? null, settled: p?.settled ?? null, computed: msg.computed,
    compute_ms: p?.compute_ms ?? null,
    // Where the time went: input to sent, sent to answer, answer to drawn.
    parts_ms: [Math.max(0, sent - t0), arrived - Math.max(sent, t0), performance.now() - arrived],
    error: msg.error?.message || null,
  };
  renderLivePreview();
  if (live.queued) sendLivePreview();
}

function renderLivePreview() {
  const box = $('live-preview');
  const p = state.preview;
  box.hidden = !p || state.showing !== 'placement';
  if (box.hidden) return;
  let text;
  if (p.error) text = `Preview: ${p.error}`;
  else if (p.gain == null) text = 'Preview: computing…';
  else text = `Preview: gain ${fmt(p.gain, 1)} cm² (coarse, edge ${fmt(p.edge_cm, 2)} cm, ${fmtInt(Math.round(p.ms))} ms)`;
  if (p.stale && p.gain != null) text += ' · updating…';
  box.textContent = text;
  box.classList.toggle('stale', !!p.stale);
}

// ---------------------------------------------------------------- views

function showPlacementView() {
  state.showing = 'placement';
  renderLivePreview();
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
  $('live-preview').hidden = true;
  $('legend').hidden = true;
  view.setPositions(state.before ? null : run.fields.after);
  applyColormap();
}

function applyColormap() {
  const fields = state.showing === 'result' && state.lastRun?.fields;
  if (!fields) return;
  const values = state.colormap === 'none' ? null : fields[state.colormap];
  const [min, max] = renderColorbar(state.colormap, values);
  view.setColors(values, min, max);
}

// ---------------------------------------------------------------- jobs

function canRun() {
  return !!state.patient && state.ready && !!state.placement && !state.previewPending && !!state.check?.ok
    && !requestInputErrors() && state.job.state !== 'running';
}

/** Why Run is disabled, in words, or null. */
function runBlocked() {
  if (state.job.state === 'running') return null;
  if (!state.patient) return 'Load a patient first (step 1).';
  if (!state.placement) return 'Place the expander first: click the skin in step 2.';
  if (requestInputErrors()) return 'Correct the inputs marked in step 2.';
  const e = !state.previewPending && state.check && !state.check.ok ? state.check.error : null;
  if (e) return `${e.field && inputOf(e.field) ? 'Step 2' : 'Placement problem'}: ${e.message || 'the placement cannot be used.'}`;
  return null;
}

function renderRunControls() {
  const running = state.job.state === 'running';
  for (const id of ['run', 'sweep-start', 'target-start', 'expansion-start']) $(id).disabled = !canRun();
  $('cancel').disabled = !running || state.cancelSent;
  const why = runBlocked();
  $('run-blocked').hidden = !why;
  $('run-blocked').textContent = why || '';
  for (const input of document.querySelectorAll('#step-2 input, #step-2 select, #use-suggested')) {
    input.disabled = running || (input.id === 'use-suggested' && !state.patient?.suggested);
  }
  for (const id of ['mesh-select', 'unit-select', 'file-input']) $(id).disabled = running || state.loading;
}

function renderRunSummary() {
  const p = state.placement;
  if (!state.patient || !p) {
    setText('run-summary', '');
    return;
  }
  const v = (id) => $(id).value;
  const size = {
    round: () => `round, ${v('diameter')} cm across`,
    rectangular: () => `rectangular, ${v('rect-length')} × ${v('rect-width')} cm`,
    crescent: () => `crescent, ${v('cres-length')} × ${v('cres-width')} cm`,
  }[v('shape')]();
  setText('run-summary', `${size}, ${v('volume')} cm³, ${v('depth')} cm deep, turned ${v('rotation')}°, `
    + `centred at ${fmtPoint(p.point)} cm on ${state.patient.label}.`);
}

function setJob(fields) {
  Object.assign(state.job, fields);
  document.body.dataset.job = state.job.state;
  renderSave();
}

/** Starts a job of `mode` with the JobSpec members `spec` and the request's `extra` fields. */
async function startJob(mode, spec = {}, extra = {}) {
  if (!canRun()) return;
  const { request } = buildRequest(extra);
  clearError();
  state.runErrors = {};
  renderErrors();
  state.result = null;
  state.cancelSent = false;
  setJob({ state: 'running', step: 0, settle: 0, run: 0, runs: 1, max_steps: 0, job: null, mode });
  renderProgress();
  setText('job-status', mode === 'single' ? 'Starting the simulation…' : 'Starting the series…');
  if (mode === 'single') {
    $('result').hidden = true;
    if (state.showing === 'result') showPlacementView();
  }
  const section = { sweep: 'sweep-result', 'target-gain': 'target-result', expansion: 'expansion-result' }[mode];
  if (section) $(section).hidden = true;
  renderRunControls();
  state.spec = { mode, ...spec, request };
  state.saved = null;
  renderSave();
  try {
    await socket.send({ type: 'run', patient: state.patient.patient, mode, ...spec, request });
  } catch (e) {
    endJob('failed', { message: e.message });
  }
}

function renderProgress() {
  const j = state.job;
  const runs = j.runs || 1;
  const run = j.run || 0;
  const value = j.state === 'finished' ? 1 : runs > 1 ? (run + (j.settle || 0)) / runs : j.settle || 0;
  $('progress').value = Math.min(1, Math.max(0, value));
  setText('progress-run', runs > 1 ? `run ${run + 1} of ${runs} · ` : '');
  setText('progress-step', `step ${fmtInt(j.step || 0)} of ${fmtInt(j.max_steps || 0)}`);
  setText('progress-settle', `settle ${Math.round((j.settle || 0) * 100)} %`);
}

/**
 * The job ended without a result (`failed`, `refused`): the server's error is shown at the input
 * that sets its field, or in the page's error box (also when that input is out of sight).
 */
function endJob(how, error) {
  setJob({ state: how });
  const message = error?.message || (how === 'refused' ? 'The server refused the run.' : 'The run failed.');
  const input = error?.field && inputOf(error.field) && $(inputOf(error.field));
  if (input) {
    state.runErrors[error.field] = message;
    renderErrors();
  }
  if (!input || !input.offsetParent) showError(message);
  setText('job-status', '');
  renderRunControls();
}

function onSocketMessage(msg) {
  const mine = !msg.job || !state.job.job || msg.job === state.job.job;
  switch (msg.type) {
    case 'accepted':
      setJob({ job: msg.job });
      setText('job-status', msg.mode === 'single' ? 'Simulating…' : 'Running the series…');
      break;
    case 'progress':
      if (!mine || state.job.state !== 'running') return;
      setJob({ step: msg.step, settle: msg.settle, run: msg.run, runs: msg.runs, max_steps: msg.max_steps, elapsed_s: msg.elapsed_s });
      renderProgress();
      break;
    case 'finished':
      if (mine) onFinished(msg);
      break;
    case 'cancelled':
      if (!mine) return;
      // From the Cancel click to the server's word that the job stopped, measured in the page.
      setJob({ state: 'cancelled', step: msg.steps ?? state.job.step, cancel_ms: state.cancelAt ? performance.now() - state.cancelAt : null });
      state.cancelAt = null;
      setText('job-status', `Cancelled after ${fmtInt(state.job.step)} steps.`);
      renderRunControls();
      break;
    case 'failed':
      if (mine) endJob('failed', msg.error);
      break;
    case 'refused':
      if (state.job.state === 'running') endJob('refused', msg.error);
      break;
    case 'preview':
      onLivePreview(msg);
      break;
    default:
      break;
  }
}

function onSocketClosed() {
  if (live.inFlight) {
    // Lost with the socket: the newest input is sent again on the next one.
    live.queued = live.queued || { t0: live.inFlight.t0 };
    live.inFlight = null;
  }
  if (state.job.state === 'running') endJob('failed', { message: 'The connection to the studio server was lost, and with it the run.' });
}

function onFinished(msg) {
  const report = msg.report;
  const mode = report.mode || state.job.mode;
  state.result = report;
  setJob({ state: 'finished', job: msg.job });
  renderProgress();
  $('save-name').value = defaultPlanName(mode);
  $('save-note').value = '';
  setText('save-status', '');
  renderSave();
  if (mode === 'sweep') {
    renderSweep(report, msg.job, msg);
    setText('job-status', `Series finished: ${report.runs?.length ?? 0} runs.`);
  } else if (mode === 'expansion') {
    renderExpansion(report, msg.job);
    setText('job-status', `Expansion finished: flap ${fmt(report.flap?.flap_area_cm2, 1)} cm² after removal.`);
  } else if (mode === 'target-gain') {
    renderTarget(report, msg.job);
    setText('job-status', report.converged ? 'Search finished.' : 'Search finished without converging.');
  } else {
    state.lastRun = { job: msg.job, mode, report, fields: msg.fields, patient: state.patient.patient };
    renderReport(report, msg.job);
    const settled = report.stop_reason === 'settled';
    if (report.steps != null) setText('progress-step', `step ${fmtInt(report.steps)} of ${fmtInt(report.max_steps ?? state.job.max_steps)}`);
    if (settled) setText('progress-settle', 'settled');
    setText('job-status', `Finished in ${fmtInt(report.steps)} steps (${settled ? 'settled' : 'step limit reached'}).`);
    if (msg.fields && state.step === 3) {
      showResultView();
      // Tipped, so that the raised skin shows its height; "Reset view" looks straight on again.
      view.oblique();
    }
  }
  renderRunControls();
}

// ---------------------------------------------------------------- save to cases

const SHAPES = { round: 'round', rectangular: 'rectangular', crescent: 'crescent' };

/** "100 cm³ round, 2026-11-29 10:42": what the finished job ran, and now. */
function defaultPlanName(mode) {
  const d = new Date();
  const p = (n) => String(n).padStart(2, '0');
  const now = `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${p(d.getHours())}:${p(d.getMinutes())}`;
  const r = state.spec?.request || {};
  const shape = SHAPES[r.shape] || 'round';
  const volume = r.volume_cm3 ?? 100;
  const what = {
    sweep: () => `series ${(state.spec?.volumes_cm3 || []).join(', ')} cm³ ${shape}`,
    'target-gain': () => `${state.spec?.target_gain_cm2 ?? '—'} cm² target, ${shape}`,
    expansion: () => `${volume} cm³ ${shape} over ${r.expand_weeks ?? 10} weeks`,
  }[mode];
  return `${what ? what() : `${volume} cm³ ${shape}`}, ${now}`;
}

/** The Save box: shown once a job finished, until the next starts. */
function renderSave() {
  const finished = state.job.state === 'finished' && !!state.job.job;
  $('save-case').hidden = !finished;
  $('save-button').disabled = !finished || !!state.saved;
  $('save-open').hidden = !state.saved;
  if (state.saved) $('save-open').href = `/cases?plan=${encodeURIComponent(state.saved.uid)}`;
}

async function saveCase(e) {
  e?.preventDefault();
  if (state.job.state !== 'finished' || state.saved) return;
  $('save-button').disabled = true;
  setText('save-status', 'Saving…');
  try {
    const plan = await api.saveCase(state.job.job, $('save-name').value, $('save-note').value);
    state.saved = plan;
    setText('save-status', `Saved as "${plan.name}" in the case library.`);
  } catch (err) {
    setText('save-status', '');
    showError(err.message);
  } finally {
    renderSave();
  }
}

/** The page's own errors of a series' inputs (not numbers; half a bracket); true when none. */
function seriesInputsOk(errors) {
  for (const id of ['sweep-volumes', 'target-gain', 'bracket-lo', 'expand-weeks']) onInputEdited(id);
  Object.assign(state.inputErrors, errors);
  renderErrors();
  return Object.keys(errors).length === 0;
}

function startSweep() {
  const parts = $('sweep-volumes').value.split(/[\s,;]+/).filter(Boolean);
  const volumes = parts.map(Number);
  if (!seriesInputsOk(volumes.some(Number.isNaN) ? { volumes_cm3: 'Give numbers (cm³) separated by commas, e.g. 50, 100, 150.' } : {})) return;
  startJob('sweep', { volumes_cm3: volumes });
}

function startTarget() {
  const errors = {};
  const gain = readNumber('target-gain', 'target_gain_cm2', errors);
  const lo = readNumber('bracket-lo', 'bracket_cm3', errors);
  const hi = readNumber('bracket-hi', 'bracket_cm3', errors);
  if ((lo === undefined) !== (hi === undefined)) errors.bracket_cm3 = 'Give both ends of the bracket, or neither.';
  if (!seriesInputsOk(errors)) return;
  startJob('target-gain', { target_gain_cm2: gain ?? null, bracket_cm3: lo === undefined ? null : [lo, hi] });
}

function startExpansion(extra = {}) {
  const errors = {};
  const weeks = readNumber('expand-weeks', 'expand_weeks', errors);
  if (!seriesInputsOk(errors)) return;
  startJob('expansion', {}, { ...(weeks === undefined ? {} : { expand_weeks: weeks }), ...extra });
}

async function cancelJob() {
  if (state.job.state !== 'running') return;
  state.cancelSent = true;
  state.cancelAt = performance.now();
  renderRunControls();
  setText('job-status', 'Cancelling…');
  try {
    await socket.send({ type: 'cancel' });
  } catch (e) {
    showError(e.message);
  }
}

async function savePng() {
  const blob = await view.toPng();
  if (blob) saveBlob(blob, `studio-${state.lastRun?.job || 'view'}.png`);
}

// ---------------------------------------------------------------- start

function wire() {
  for (const b of document.querySelectorAll('.step-tab, [data-goto]')) {
    b.addEventListener('click', () => showStep(Number(b.dataset.step || b.dataset.goto)));
  }
  $('mesh-select').addEventListener('change', onMeshSelect);
  $('unit-select').addEventListener('change', onUnitChange);
  $('file-input').addEventListener('change', (e) => uploadFile(e.target.files[0]));
  $('use-suggested').addEventListener('click', () => {
    const s = state.patient?.suggested;
    if (s && canPlace()) setPlacement({ point: s.point, vertex: s.vertex, normal: null });
  });
  $('shape').addEventListener('change', onShapeChange);
  for (const input of document.querySelectorAll('#step-2 input')) input.addEventListener('input', onParamsChanged);
  for (const input of document.querySelectorAll('.series input')) input.addEventListener('input', () => onInputEdited(input.id === 'bracket-hi' ? 'bracket-lo' : input.id));
  $('run').addEventListener('click', () => startJob('single'));
  $('cancel').addEventListener('click', cancelJob);
  $('sweep-start').addEventListener('click', startSweep);
  $('target-start').addEventListener('click', startTarget);
  $('expansion-start').addEventListener('click', () => startExpansion());
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
  $('save-case').addEventListener('submit', saveCase);
  $('reset-view').addEventListener('click', () => view.fit());
  $('show-edges').addEventListener('change', (e) => view.showEdges(e.target.checked));
  document.querySelector('.cb-ramp').style.background = `linear-gradient(to right, ${RAMP.join(', ')})`;
}

function main() {
  view = new PlannerView($('view'));
  socket = new api.JobSocket(onSocketMessage, onSocketClosed);
  Object.assign(state, {
    placeAt,
    screenOf: (p) => view.screenOf(p),
    pixelStats: () => view.pixelStats(),
    showStep,
    // What "Simulate expansion" does with `weeks` typed, plus other request fields (`extra`).
    startExpansion: (weeks, extra) => {
      $('expand-weeks').value = String(weeks);
      onInputEdited('expand-weeks');
      return startExpansion(extra);
    },
  });
  wire();
  setupPointer(view, {
    canPlace,
    place: (hit, t) => setPlacement(hit, t),
    drag: (hit, t, last) => dragPlacement(hit, t, last),
    clickRefused: () => {
      if (state.showing === 'result') setText('job-status', 'To move the expander, go back to step 2 (Placement).');
    },
    centre: () => state.placement,
    rotation: () => Number($('rotation').value),
    rotate: (deg) => {
      $('rotation').value = String(deg);
      onParamsChanged({ target: $('rotation') });
    },
    readout: (hit) => {
      const field = state.showing === 'result' && state.colormap !== 'none' && state.lastRun?.fields?.[state.colormap];
      if (!field) return null;
      const value = hit.face.reduce((s, v, k) => s + hit.bary[k] * field[v], 0);
      return state.colormap === 'displacement' ? `displacement ${fmt(value, 2)} cm` : `stretch ${fmt(value, 3)} × (area ratio)`;
    },
  });
  showStep(1);
  renderProgress();
  initMeshes();
}

main();
