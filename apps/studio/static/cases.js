// The Cases view: the case library's patients with their plans (newest first, searched by label),
// a plan opened at once from what was stored (the 3D view, its colour map, its report: nothing is
// recomputed and no job runs), two plans of a patient side by side with the difference map,
// rename, note, delete, erase, export and import. See apps/studio/API.md ("Cases").
//
// One `state` object holds what the page knows; it is also the test hook
// `window.tissueStudio.cases` (apps/studio/browser/README.md).

import { PlannerView, RAMP } from './planner-view.js';
import { renderColorbar, renderExpansion, renderReport, renderSweep, renderTarget } from './planner-report.js';
import { $, ApiError, MAX_UPLOAD, call, clearErrorIn, el, fmt, fmtInt, setText, showErrorIn } from './common.js';

const SEARCH_DEBOUNCE_MS = 200;

const state = {
  // What the browser tests read (apps/studio/browser/README.md).
  ready: false, // the list has been loaded once
  loading: false,
  patients: [], // GET /api/cases/patients: [{ patient, plans }]
  search: '',
  checked: [], // plan uids checked for comparison (of one patient)
  opened: null, // the plan opened: GET /api/cases/plans/{uid} answer, + ms (request to drawn)
  comparison: null, // GET /api/cases/compare answer, + ms
  showing: 'none', // 'plan' | 'compare'
  colormap: 'displacement',
  colorRange: null, // [min, max] of the colours drawn
  before: false,
  error: null,
  lastAction: null, // the last change made: { kind, uid, answer }
  imported: null, // the last import's summary
};
window.tissueStudio = Object.assign(window.tissueStudio || {}, { cases: state });

const showError = (message) => showErrorIn(state, message);
const clearError = () => clearErrorIn(state);

let view;
let searchTimer = null;

const enc = encodeURIComponent;
const planUrl = (uid) => `/api/cases/plans/${enc(uid)}`;
const fileUrl = (uid) => (file) => `${planUrl(uid)}/files/${file}`;

function postJson(url, body = {}) {
  return call(url, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify(body) });
}

/** "2026-11-29 10:42" in local time, from RFC 3339. */
function when(iso) {
  const d = new Date(iso);
  if (Number.isNaN(d.getTime())) return iso || '—';
  const p = (n) => String(n).padStart(2, '0');
  return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${p(d.getHours())}:${p(d.getMinutes())}`;
}

function bytes(n) {
  if (n >= 1024 * 1024) return `${fmt(n / (1024 * 1024), 1)} MiB`;
  if (n >= 1024) return `${fmt(n / 1024, 0)} KiB`;
  return `${fmtInt(n)} bytes`;
}

const MODES = { single: 'single run', sweep: 'series', 'target-gain': 'target gain', expansion: 'expansion' };

/** A plan's line in a list: mode, gain, volume, when. */
function planSummary(p) {
  const parts = [MODES[p.mode] || p.mode];
  if (p.volume_cm3 != null) parts.push(`${fmt(p.volume_cm3, 0)} cm³`);
  if (p.area_gain_cm2 != null) parts.push(`gain ${fmt(p.area_gain_cm2, 2)} cm²`);
  parts.push(when(p.run_at));
  return parts.join(' · ');
}

// ---------------------------------------------------------------- the list

let listSeq = 0;

/** Loads the list (for the search typed); an answer overtaken by a newer request is dropped. */
async function loadList() {
  const seq = ++listSeq;
  state.loading = true;
  setText('list-status', 'Loading the cases…');
  try {
    const q = state.search ? `?search=${enc(state.search)}` : '';
    const answer = await call(`/api/cases/patients${q}`);
    if (seq !== listSeq) return;
    state.patients = answer.patients;
    const known = new Set(state.patients.flatMap((e) => e.plans.map((p) => p.uid)));
    state.checked = state.checked.filter((uid) => known.has(uid));
    renderList();
    const plans = state.patients.reduce((n, e) => n + e.plans.length, 0);
    setText('list-status', state.patients.length === 0
      ? (state.search ? `No patient's label contains "${state.search}".` : 'No cases yet: save a plan from the planner, or import a case.')
      : `${fmtInt(state.patients.length)} patient${state.patients.length === 1 ? '' : 's'}, ${fmtInt(plans)} plan${plans === 1 ? '' : 's'}.`);
  } catch (e) {
    if (seq !== listSeq) return;
    showError(e.message);
    setText('list-status', '');
  } finally {
    if (seq === listSeq) {
      state.loading = false;
      state.ready = true;
    }
  }
}

function renderList() {
  const list = $('patients');
  list.replaceChildren(...state.patients.map(patientItem));
}

function patientItem({ patient, plans }) {
  const li = el('li', { class: 'case-patient', 'data-uid': patient.uid });
  const label = el('strong', { class: 'case-label' }, patient.label);
  const meta = el('span', { class: 'case-meta' },
    `${patient.scan_name} · ${patient.unit} · ${fmtInt(plans.length)} plan${plans.length === 1 ? '' : 's'} · added ${when(patient.added_at)}`);
  const head = el('div', { class: 'case-head' }, label, meta);
  const actions = el('div', { class: 'case-actions' });
  const again = el('a', { class: 'button small', href: `/planner?case=${enc(patient.uid)}` }, 'Plan again');
  again.setAttribute('aria-label', `Plan again on ${patient.label}`);
  const exp = el('a', { class: 'button small', href: `/api/cases/patients/${enc(patient.uid)}/export`, download: '' }, 'Export');
  exp.setAttribute('aria-label', `Export ${patient.label} as a zip`);
  const rename = el('button', { type: 'button', class: 'small' }, 'Rename');
  rename.setAttribute('aria-label', `Rename ${patient.label}`);
  rename.addEventListener('click', () => editInline(head, label, patient.label, 'Patient label', (v) => renamePatient(patient.uid, v)));
  const erase = el('button', { type: 'button', class: 'small danger' }, 'Erase…');
  erase.setAttribute('aria-label', `Erase ${patient.label}`);
  erase.addEventListener('click', () => erasePatient(patient, plans));
  actions.append(again, exp, rename, erase);

  const ul = el('ul', { class: 'case-plans' });
  for (const p of plans) ul.append(planItem(p));
  const compare = el('button', { type: 'button', class: 'small compare-button' }, 'Compare the two checked');
  const mine = plans.filter((p) => state.checked.includes(p.uid));
  compare.disabled = mine.length !== 2;
  compare.addEventListener('click', () => {
    const two = plans.filter((p) => state.checked.includes(p.uid));
    // Older first: A the older plan, B the newer (B − A is what changed).
    if (two.length === 2) comparePlans(two[1].uid, two[0].uid);
  });
  li.append(head, actions, ul);
  if (plans.length >= 2) li.append(el('div', { class: 'case-compare' }, compare));
  return li;
}

function planItem(p) {
  const li = el('li', { class: 'case-plan', 'data-uid': p.uid });
  if (state.opened?.plan.uid === p.uid && state.showing === 'plan') li.classList.add('current');
  const box = el('input', { type: 'checkbox' });
  box.checked = state.checked.includes(p.uid);
  box.setAttribute('aria-label', `Compare ${p.name}`);
  box.addEventListener('change', () => {
    if (box.checked) {
      // Two of one patient at most: the oldest check goes.
      const same = state.patients.find((e) => e.plans.some((q) => q.uid === p.uid));
      const ofPatient = new Set(same ? same.plans.map((q) => q.uid) : []);
      state.checked = [...state.checked.filter((u) => ofPatient.has(u)), p.uid].slice(-2);
    } else {
      state.checked = state.checked.filter((u) => u !== p.uid);
    }
    renderList();
  });
  const open = el('button', { type: 'button', class: 'link open-plan' }, p.name);
  open.setAttribute('aria-label', `Open ${p.name}`);
  open.addEventListener('click', () => openPlan(p.uid));
  const meta = el('span', { class: 'case-meta' }, planSummary(p));
  li.append(box, el('div', { class: 'case-plan-text' }, open, meta));
  if (p.note) li.append(el('p', { class: 'case-note' }, p.note));
  return li;
}

/** Replaces `shown` in `box` by a text input and Save/Cancel; `save(value)` is awaited. */
function editInline(box, shown, value, label, save) {
  if (box.querySelector('.inline-edit')) return;
  const input = el('input', { type: 'text', value, maxlength: '200' });
  input.setAttribute('aria-label', label);
  const ok = el('button', { type: 'button', class: 'small primary' }, 'Save');
  const cancel = el('button', { type: 'button', class: 'small' }, 'Cancel');
  const form = el('div', { class: 'inline inline-edit' }, input, ok, cancel);
  shown.hidden = true;
  box.prepend(form);
  input.focus();
  input.select();
  const close = () => {
    form.remove();
    shown.hidden = false;
  };
  cancel.addEventListener('click', close);
  const submit = async () => {
    ok.disabled = true;
    if (await save(input.value)) close();
    else ok.disabled = false;
  };
  ok.addEventListener('click', submit);
  input.addEventListener('keydown', (e) => {
    if (e.key === 'Enter') submit();
    if (e.key === 'Escape') close();
  });
}

// ---------------------------------------------------------------- a plan opened

async function openPlan(uid) {
  clearError();
  const t0 = performance.now();
  setText('case-badge', 'Opening the plan…');
  let answer;
  try {
    answer = await call(planUrl(uid));
  } catch (e) {
    showError(e.message);
    setText('case-badge', '');
    return false;
  }
  const fetched = performance.now();
  state.opened = answer;
  state.comparison = null;
  state.showing = 'plan';
  renderPlan();
  view.renderNow();
  state.opened.ms = performance.now() - t0;
  state.opened.fetchMs = fetched - t0;
  renderList();
  return true;
}

function renderPlan() {
  const o = state.opened;
  const { plan, patient, report } = o;
  $('compare-detail').hidden = true;
  $('detail-empty').hidden = true;
  $('plan-detail').hidden = false;
  setText('plan-title', plan.name);
  setText('plan-meta', `${patient.label} · ${planSummary(plan)} · ${plan.tool} ${plan.library_version}, solver ${plan.solver || '—'}`);
  $('plan-name').value = plan.name;
  $('plan-note').value = plan.note;
  setText('case-badge', `${patient.label} · ${plan.name}`);
  for (const id of ['result', 'sweep-result', 'target-result', 'expansion-result']) $(id).hidden = true;
  const urlOf = fileUrl(plan.uid);
  const mode = report.mode || plan.mode;
  if (mode === 'sweep') renderSweep(report, plan.uid, { failed_runs: report.failed_runs }, urlOf);
  else if (mode === 'expansion') renderExpansion(report, plan.uid, urlOf);
  else if (mode === 'target-gain') renderTarget(report, plan.uid, urlOf);
  else renderReport(report, plan.uid, urlOf);
  if (o.mesh) {
    view.setMesh(o.mesh.positions, o.mesh.triangles);
    $('view-empty').hidden = true;
    showResult();
    view.oblique();
  } else {
    $('colorbar').hidden = true;
    $('view-empty').hidden = false;
    $('view-empty').textContent = 'This plan has no result on the patient (a series, a search or an expansion): its report is in the panel.';
  }
}

function showResult() {
  const fields = state.opened?.fields;
  if (!fields) return;
  view.setPositions(state.before ? null : fields.after);
  applyColormap();
}

function applyColormap() {
  const fields = state.showing === 'plan' && state.opened?.fields;
  if (!fields) return;
  const values = state.colormap === 'none' ? null : fields[state.colormap];
  const [min, max] = renderColorbar(state.colormap, values);
  state.colorRange = values ? [min, max] : null;
  view.setColors(values, min, max);
}

async function renamePlan() {
  const uid = state.opened?.plan.uid;
  if (!uid) return;
  clearError();
  try {
    const plan = await postJson(`${planUrl(uid)}/rename`, { name: $('plan-name').value });
    state.opened.plan = plan;
    setText('plan-title', plan.name);
    await loadList();
    state.lastAction = { kind: 'rename-plan', uid, answer: plan };
  } catch (e) {
    showError(e.message);
  }
}

async function saveNote() {
  const uid = state.opened?.plan.uid;
  if (!uid) return;
  clearError();
  try {
    const plan = await postJson(`${planUrl(uid)}/note`, { note: $('plan-note').value });
    state.opened.plan = plan;
    await loadList();
    state.lastAction = { kind: 'note', uid, answer: plan };
  } catch (e) {
    showError(e.message);
  }
}

async function deletePlan() {
  const plan = state.opened?.plan;
  if (!plan) return;
  if (!window.confirm(`Delete the plan "${plan.name}" (${planSummary(plan)})? Its report and result go; the patient and other plans stay.`)) return;
  clearError();
  try {
    const answer = await postJson(`${planUrl(plan.uid)}/delete`);
    closeDetail();
    await loadList();
    state.lastAction = { kind: 'delete-plan', uid: plan.uid, answer };
  } catch (e) {
    showError(e.message);
  }
}

function closeDetail() {
  state.opened = null;
  state.comparison = null;
  state.showing = 'none';
  state.colorRange = null;
  $('plan-detail').hidden = true;
  $('compare-detail').hidden = true;
  $('detail-empty').hidden = false;
  $('colorbar').hidden = true;
  setText('case-badge', '');
  if (view.mesh) {
    view.scene.remove(view.mesh, view.edges);
    view.mesh = null;
    view.renderNow();
  }
  $('view-empty').hidden = false;
  $('view-empty').textContent = 'Open a plan, or check two plans of a patient and compare them.';
}

// ---------------------------------------------------------------- two plans side by side

// The figures a comparison shows first, in this order, with their labels; the others follow in the
// library's order, labelled from their JSON names (`dome_height_cm` → "Dome height (cm)").
const FIGURE_LABELS = {
  area_gain_cm2: 'Area gain (cm²)',
  implant_volume_cm3: 'Implant volume (cm³)',
  volume_cm3: 'Implant volume (cm³)',
  max_displacement_cm: 'Max displacement (cm)',
  dome_height_cm: 'Dome height (cm)',
  volume_difference_cm3: 'Volume difference (cm³)',
  area_before_cm2: 'Area before (cm²)',
  area_after_cm2: 'Area after (cm²)',
  implant_compression: 'Implant compression',
  steps: 'Steps',
  max_steps: 'Step limit',
  wall_time_s: 'Wall time (s)',
};
const UNITS = [['_cm2', 'cm²'], ['_cm3', 'cm³'], ['_cm', 'cm'], ['_s', 's']];

function figureLabel(name) {
  if (FIGURE_LABELS[name]) return FIGURE_LABELS[name];
  let text = name;
  let unit = '';
  for (const [suffix, u] of UNITS) {
    if (text.endsWith(suffix)) {
      text = text.slice(0, -suffix.length);
      unit = u;
      break;
    }
  }
  text = text.replace(/_/g, ' ');
  text = text.charAt(0).toUpperCase() + text.slice(1);
  return unit ? `${text} (${unit})` : text;
}

/** Key figures first (FIGURE_LABELS' order), then the others as the library lists them. */
function orderFigures(figures) {
  const rank = Object.keys(FIGURE_LABELS);
  const r = (f) => (rank.includes(f.name) ? rank.indexOf(f.name) : rank.length);
  return figures.map((f, i) => [f, i]).sort((x, y) => r(x[0]) - r(y[0]) || x[1] - y[1]).map(([f]) => f);
}

/** A figure with the digits it needs: counts whole, small values with 4 significant digits. */
function fmtFigure(v, whole) {
  if (v == null) return '—';
  if (whole) return fmtInt(v);
  const a = Math.abs(v);
  if (a !== 0 && a < 0.01) return v.toPrecision(3);
  return fmt(v, a < 1 ? 3 : 2);
}

async function comparePlans(a, b) {
  clearError();
  const t0 = performance.now();
  setText('case-badge', 'Comparing…');
  let answer;
  try {
    answer = await call(`/api/cases/compare?a=${enc(a)}&b=${enc(b)}`);
  } catch (e) {
    showError(e.message);
    setText('case-badge', '');
    return false;
  }
  state.comparison = answer;
  state.opened = null;
  state.showing = 'compare';
  renderComparison();
  view.renderNow();
  state.comparison.ms = performance.now() - t0;
  renderList();
  return true;
}

function renderComparison() {
  const c = state.comparison;
  $('plan-detail').hidden = true;
  $('detail-empty').hidden = true;
  $('compare-detail').hidden = false;
  setText('case-badge', `${c.patient.label} · ${c.a.name} and ${c.b.name}`);
  const head = el('tr', {}, el('th', { scope: 'col' }, 'Figure'), el('th', { scope: 'col' }, 'A'),
    el('th', { scope: 'col' }, 'B'), el('th', { scope: 'col' }, 'B − A'));
  $('compare-plans').replaceChildren(
    el('dt', {}, 'A'), el('dd', {}, `${c.a.name} (${when(c.a.run_at)})`),
    el('dt', {}, 'B'), el('dd', {}, `${c.b.name} (${when(c.b.run_at)})`));
  const body = el('tbody');
  for (const f of orderFigures(c.figures)) {
    const whole = Number.isInteger(f.a ?? 0) && Number.isInteger(f.b ?? 0);
    const diff = f.difference == null ? '—' : `${f.difference > 0 ? '+' : ''}${fmtFigure(f.difference, whole)}`;
    body.append(el('tr', {}, el('th', { scope: 'row' }, figureLabel(f.name)), el('td', {}, fmtFigure(f.a, whole)),
      el('td', {}, fmtFigure(f.b, whole)), el('td', { class: 'diff' }, diff)));
  }
  $('compare-table').replaceChildren(el('thead', {}, head), body);
  view.setMesh(c.mesh.positions, c.mesh.triangles);
  $('view-empty').hidden = true;
  if (c.difference.length) {
    view.setPositions(c.after_b || null);
    const max = c.max_difference > 1e-9 ? c.max_difference : 1e-3;
    view.setColors(c.difference, 0, max);
    state.colorRange = [0, max];
    $('colorbar').hidden = false;
    setText('cb-title', `Difference |after B − after A| (${c.unit})`);
    setText('cb-min', `0 ${c.unit}`);
    setText('cb-max', `${fmt(c.max_difference, c.max_difference < 0.1 ? 3 : 2)} ${c.unit}`);
    setText('compare-note', `The skin is drawn as plan B left it, coloured by how far each point lies from where plan A left it (largest ${fmt(c.max_difference, 3)} ${c.unit}, in the scan's unit).`);
    view.oblique();
  } else {
    view.setColors(null);
    state.colorRange = null;
    $('colorbar').hidden = true;
    setText('compare-note', 'No difference map: it needs two single runs (a series, a search or an expansion has no result on the patient).');
  }
}

// ---------------------------------------------------------------- patients

async function renamePatient(uid, label) {
  clearError();
  try {
    const answer = await postJson(`/api/cases/patients/${enc(uid)}/rename`, { label });
    await loadList();
    state.lastAction = { kind: 'rename-patient', uid, answer };
    return true;
  } catch (e) {
    showError(e.message);
    return false;
  }
}

async function erasePatient(patient, plans) {
  const what = `${patient.label}: the scan ${patient.scan_name} (${bytes(patient.scan_bytes)}) and ${plans.length} plan${plans.length === 1 ? '' : 's'}`
    + (plans.length ? ` (${plans.map((p) => p.name).join(', ')})` : '');
  if (!window.confirm(`Erase ${what}? Everything of this patient is removed from the case library and cannot be recovered. Export the case first to keep a copy.`)) return false;
  clearError();
  try {
    const answer = await postJson(`/api/cases/patients/${enc(patient.uid)}/erase`);
    state.lastAction = { kind: 'erase', uid: patient.uid, answer };
    const shown = state.opened?.patient.uid === patient.uid || state.comparison?.patient.uid === patient.uid;
    if (shown) closeDetail();
    await loadList();
    setText('list-status', `Erased ${patient.label} and ${plans.length} plan${plans.length === 1 ? '' : 's'}. ${$('list-status').textContent}`);
    return true;
  } catch (e) {
    showError(e.message);
    return false;
  }
}

async function importFile(file) {
  if (!file) return;
  clearError();
  if (file.size > MAX_UPLOAD) {
    showError(`${file.name} is larger than 64 MiB (${fmtInt(file.size)} bytes): a case archive up to 64 MiB can be imported.`);
    $('import-file').value = '';
    return;
  }
  setText('list-status', `Importing ${file.name}…`);
  try {
    const summary = await call('/api/cases/import', {
      method: 'POST', headers: { 'content-type': 'application/octet-stream' }, body: file,
    });
    state.imported = summary;
    await loadList();
    setText('list-status', `Imported ${summary.patient.label}: ${summary.plans_added} plan${summary.plans_added === 1 ? '' : 's'} added`
      + (summary.plans_skipped ? `, ${summary.plans_skipped} already here` : '') + '.');
  } catch (e) {
    showError(e instanceof ApiError ? e.message : String(e));
    setText('list-status', '');
  } finally {
    $('import-file').value = '';
  }
}

// ---------------------------------------------------------------- start

function wire() {
  $('search').addEventListener('input', () => {
    clearTimeout(searchTimer);
    searchTimer = setTimeout(() => {
      state.search = $('search').value.trim();
      loadList();
    }, SEARCH_DEBOUNCE_MS);
  });
  $('import-file').addEventListener('change', (e) => importFile(e.target.files[0]));
  $('plan-rename').addEventListener('click', renamePlan);
  $('plan-note-save').addEventListener('click', saveNote);
  $('plan-delete').addEventListener('click', deletePlan);
  for (const r of document.querySelectorAll('input[name="beforeafter"]')) {
    r.addEventListener('change', () => {
      state.before = document.querySelector('input[name="beforeafter"]:checked').value === 'before';
      if (state.showing === 'plan') showResult();
    });
  }
  $('colormap').addEventListener('change', () => {
    state.colormap = $('colormap').value;
    applyColormap();
  });
  $('reset-view').addEventListener('click', () => view.fit());
  $('show-edges').addEventListener('change', (e) => view.showEdges(e.target.checked));
  document.querySelector('.cb-ramp').style.background = `linear-gradient(to right, ${RAMP.join(', ')})`;
}

/** What the view draws now: vertices, the sum of its positions, whether coloured. */
function drawn() {
  const mesh = view.mesh;
  if (!mesh) return null;
  const pos = mesh.geometry.getAttribute('position').array;
  let sum = 0;
  for (let i = 0; i < pos.length; i++) sum += pos[i];
  return { vertices: pos.length / 3, positionSum: sum, coloured: !!view.material.vertexColors, colorRange: state.colorRange };
}

function main() {
  view = new PlannerView($('view'));
  Object.assign(state, {
    openPlan,
    comparePlans,
    reload: loadList,
    drawn,
    pixelStats: () => view.pixelStats(),
  });
  wire();
  // /cases?plan=ID (the planner's "Open in Cases"): that plan opened once the list is in.
  const plan = new URLSearchParams(location.search).get('plan');
  loadList().then(() => (plan ? openPlan(plan) : null));
}

main();
