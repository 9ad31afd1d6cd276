// The planner's answers in words, tables and charts: the patient summary and the four reports
// (single run, series, target gain, expansion). Each function draws one answer of the server
// into its part of planner.html and keeps nothing.

import { resultUrl } from './planner-api.js';
import { svgChart } from './chart.js';
import { $, el, fmt, fmtInt, setText } from './common.js';

/** A `<dl>`'s rows from `[label, value, class?]`. */
function figures(dl, rows) {
  dl.replaceChildren();
  for (const [label, value, cls] of rows) {
    if (value === null) continue;
    const attrs = cls ? { class: cls } : {};
    dl.append(el('dt', attrs, label), el('dd', attrs, value));
  }
}

/**
 * A table of `rows` with `columns` `[{label, value(row)}]`. A row with an `error` (a failed run)
 * shows its first column, then "failed:" and the server's message across the others.
 */
function runsTable(table, rows, columns) {
  const head = el('tr');
  for (const c of columns) head.append(el('th', { scope: 'col' }, c.label));
  const body = el('tbody');
  for (const r of rows) {
    const tr = el('tr', r.error ? { class: 'failed' } : {});
    if (r.error) {
      tr.append(el('td', {}, columns[0].value(r)),
        el('td', { colspan: String(columns.length - 1) }, `failed: ${r.error.message || r.error.kind || 'no reason given'}`));
    } else {
      for (const c of columns) tr.append(el('td', {}, c.value(r)));
    }
    body.append(tr);
  }
  table.replaceChildren(el('thead', {}, head), body);
}

/** Where a finished job's `file` downloads from (a stored plan gives its own). */
const jobUrls = (job) => (file) => resultUrl(job, file);

/** The download links under a series' answer. */
function downloads(section, urlOf, extra = []) {
  let p = section.querySelector('.report-link');
  if (!p) {
    p = el('p', { class: 'downloads report-link' });
    section.append(p);
  }
  p.replaceChildren('Download: ', el('a', { href: urlOf('report.json'), download: '' }, 'report.json'));
  for (const file of extra) p.append(' · ', el('a', { href: urlOf(file), download: '' }, file));
}

/** The POST /api/patients answer: its summary and defects. */
export function renderSummary(answer) {
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

const STOP = { settled: 'settled', step_limit: 'step limit reached (not settled)' };
const MEASURED_ON = {
  simulation_surface: 'Areas and volume are measured on the simulation surface (the region remeshed).',
  patient_region: "Areas and volume are measured on the patient's own triangles in the region.",
};

/** A single run's report; `urlOf(file)` is where its downloads are (a job's by default). */
export function renderReport(r, job, urlOf = jobUrls(job)) {
  $('result').hidden = false;
  figures($('report-figures'), [
    ['Area before', `${fmt(r.area_before_cm2, 2)} cm²`],
    ['Area after', `${fmt(r.area_after_cm2, 2)} cm²`],
    ['Area gain', `${fmt(r.area_gain_cm2, 2)} cm²`, 'key'],
    ['Volume difference', `${fmt(r.volume_difference_cm3, 2)} cm³`],
    ['Implant compression', `${fmt((r.implant_compression ?? 0) * 100, 2)} %`],
    ['Max displacement', r.max_displacement_cm != null ? `${fmt(r.max_displacement_cm, 2)} cm` : null],
    ['Steps', r.max_steps ? `${fmtInt(r.steps)} of at most ${fmtInt(r.max_steps)}` : fmtInt(r.steps)],
    ['Stop reason', STOP[r.stop_reason] || String(r.stop_reason ?? '—')],
    ['Solver', r.inputs?.solver === 'quasi_static'
      ? `quasi-static: ${fmtInt(r.iterations)} iterations, residual ${r.residual_n != null ? `${r.residual_n.toExponential(2)} N` : '—'}`
      : (r.inputs?.solver ? 'explicit' : null)],
    ['Wall time', `${fmt(r.wall_time_s, 2)} s`],
    ['Region edge kept in place', r.boundary_unchanged != null ? (r.boundary_unchanged ? 'yes' : 'no') : null],
    ['Region', r.region_vertices != null ? `${fmtInt(r.region_vertices)} vertices, radius ${fmt(r.region_radius_cm, 2)} cm` : null],
  ]);
  let text = MEASURED_ON[r.measured_on] || (r.measured_on ? `Measured on: ${r.measured_on}.` : '');
  if (r.scan) {
    text += ` On the scan's own triangles: gain ${fmt(r.scan.area_gain_cm2, 2)} cm², volume difference ${fmt(r.scan.volume_difference_cm3, 2)} cm³.`;
  }
  setText('measured-on', text);
  for (const f of ['ply', 'obj', 'vtk']) $(`dl-${f}`).href = urlOf(`patient.${f}`);
  $('dl-report').href = urlOf('report.json');
}

/**
 * A series: the gain against volume, and a row per run. The finished message's `failed_runs`
 * (`[{volume_cm3, error}]`, when the server sends it) are rows marked failed; its `warnings`
 * (older servers: one sentence per failed run) are listed under the table.
 */
export function renderSweep(report, job, msg = {}, urlOf = jobUrls(job)) {
  const failed = msg.failed_runs || report.failed_runs || [];
  const runs = (report.runs || []).map((r) => ({ ...r, volume_cm3: r.volume_cm3 ?? r.inputs?.volume_cm3 }));
  const points = runs.map((r) => [r.volume_cm3, r.area_gain_cm2]);
  $('sweep-result').hidden = false;
  $('sweep-chart').replaceChildren(svgChart({
    axes: { x: { label: 'implant volume (cm³)', pad: 0.05 }, y: { label: 'area gain (cm²)', pad: 0.1 } },
    series: [{ points, dots: true, pointLabel: (y) => fmt(y, 1) }],
    label: `Area gain against volume: ${points.map((p) => `${fmt(p[0], 0)} cm³ → ${fmt(p[1], 1)} cm²`).join('; ')}`,
    empty: 'No runs to plot.',
  }));
  const rows = [...runs, ...failed].sort((a, b) => a.volume_cm3 - b.volume_cm3);
  runsTable($('sweep-table'), rows, [
    { label: 'Volume (cm³)', value: (r) => fmt(r.volume_cm3, 0) },
    { label: 'Area gain (cm²)', value: (r) => fmt(r.area_gain_cm2, 2) },
    { label: 'Volume diff. (cm³)', value: (r) => fmt(r.volume_difference_cm3, 1) },
    { label: 'Steps', value: (r) => `${fmtInt(r.steps)}${r.stop_reason && r.stop_reason !== 'settled' ? ' (limit)' : ''}` },
  ]);
  const notes = failed.length ? [] : msg.warnings || [];
  const list = $('sweep-warnings');
  list.hidden = notes.length === 0;
  list.replaceChildren(...notes.map((w) => el('li', {}, w)));
  downloads($('sweep-result'), urlOf);
}

/** A target-gain search. */
export function renderTarget(report, job, urlOf = jobUrls(job)) {
  $('target-result').hidden = false;
  figures($('target-figures'), [
    ['Target gain', `${fmt(report.target_gain_cm2, 2)} cm²`],
    ['Volume', `${fmt(report.volume_cm3, 1)} cm³`, 'key'],
    ['Its gain', `${fmt(report.area_gain_cm2, 2)} cm²`],
    ['Converged', report.converged ? 'yes' : 'no — the answer is the best run found'],
    ['Searched', report.bracket_cm3 ? `${fmt(report.bracket_cm3[0], 0)} to ${fmt(report.bracket_cm3[1], 0)} cm³` : null],
  ]);
  runsTable($('target-table'), (report.runs || []).map((r, i) => ({ ...r, n: i + 1 })), [
    { label: 'Run', value: (r) => String(r.n) },
    { label: 'Volume (cm³)', value: (r) => fmt(r.volume_cm3, 1) },
    { label: 'Area gain (cm²)', value: (r) => fmt(r.area_gain_cm2, 2) },
  ]);
  downloads($('target-result'), urlOf);
}

const DAY_SERIES = [
  { key: 'volume_cm3', color: '#5a5a5a', label: 'volume cm³' },
  { key: 'area_gain_cm2', color: '#285ac8', label: 'area gain cm²' },
  { key: 'grown_gain_cm2', color: '#1e963c', label: 'grown cm²' },
];

/** An expansion over weeks: the days' chart with the flap's band, the flap, the weeks. */
export function renderExpansion(report, job, urlOf = jobUrls(job)) {
  const days = report.days || [];
  const band = report.band?.flap_area_cm2;
  const removal = report.protocol?.removal_day ?? 0;
  $('expansion-result').hidden = false;
  $('expansion-chart').replaceChildren(svgChart({
    axes: { x: { label: 'day', include: [removal, 1] }, y: { include: [1], pad: 0.1 } },
    series: DAY_SERIES.map((s) => ({ ...s, cls: 'expansion-line', points: days.map((d) => [d.day, d[s.key]]) })),
    band: band ? { x: removal, lo: band.p5, mid: band.p50, hi: band.p95, color: '#c83c28', cls: 'expansion-band' } : null,
    label: 'Expansion over the days: volume, area gain, skin grown, and the flap at removal',
  }));
  const f = report.flap || {};
  const b = report.band;
  figures($('expansion-figures'), [
    ['Flap after removal', `${fmt(f.flap_area_cm2, 1)} cm²` + (b ? ` (P5–P95 ${fmt(b.flap_area_cm2.p5, 1)}–${fmt(b.flap_area_cm2.p95, 1)})` : ''), 'key'],
    ['Linear retraction', `${fmt(100 * f.retraction, 1)} %` + (b ? ` (${fmt(100 * b.retraction.p5, 1)}–${fmt(100 * b.retraction.p95, 1)})` : '')],
    ['Flap on the expander', `${fmt(f.dome_area_cm2, 1)} cm² (recruited ${fmt(f.recruited_area_cm2, 1)} cm²)`],
    ['Grown area', `${fmt(f.grown_area_cm2, 1)} cm²`],
    ['Geometric gain', `${fmt(f.geometric_gain_cm2, 1)} cm²`],
    ['Efficiency', `${fmt(100 * f.efficiency, 1)} %`],
  ]);
  runsTable($('expansion-table'), report.weeks || [], [
    { label: 'Week', value: (r) => String(r.week) },
    { label: 'Volume (cm³)', value: (r) => fmt(r.volume_cm3, 0) },
    { label: 'Area gain (cm²)', value: (r) => fmt(r.area_gain_cm2, 1) },
    { label: 'Grown (cm²)', value: (r) => fmt(r.grown_gain_cm2, 1) },
  ]);
  downloads($('expansion-result'), urlOf, ['chart.png']);
}

const COLORBARS = {
  displacement: { title: 'Displacement (cm)', unit: 'cm', floor: 0, least: 0.001 },
  stretch: { title: 'Stretch (area after ÷ before)', unit: '×', floor: null, least: 0.01 },
};

/** The colour bar of field `kind` over `values` (hidden for none); the [min, max] it spans. */
export function renderColorbar(kind, values) {
  const bar = COLORBARS[kind];
  $('colorbar').hidden = !bar || !values;
  if (!bar || !values) return [0, 1];
  let min = Infinity;
  let max = -Infinity;
  for (const v of values) {
    if (v < min) min = v;
    if (v > max) max = v;
  }
  if (bar.floor !== null) min = bar.floor;
  if (!(max - min > 1e-9)) max = min + bar.least;
  setText('cb-title', bar.title);
  setText('cb-min', `${fmt(min, 2)} ${bar.unit}`);
  setText('cb-max', `${fmt(max, 2)} ${bar.unit}`);
  return [min, max];
}
