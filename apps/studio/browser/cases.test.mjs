// The case library in a real browser: two plans of Table 2 run and saved through the planner's
// own controls, the server restarted on the same --data folder, then the Cases page: the list,
// a plan opened at once from what was stored (the mesh and colour map the run drew, no job run),
// the two compared (figures, difference map), rename, note, delete a plan, export, erase the
// patient, import the case back. Plain node script; exit code 0 when every check passes.
//
//   npm ci && node cases.test.mjs
//
// Environment: see harness.mjs (STUDIO_BIN, CHROMIUM; STUDIO_URL cannot restart the server, so
// the restart is skipped with it).

import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { ok, check, shot, serverUrl, restartServer, launchBrowser, newPage, stopServer, run } from './harness.mjs';

const RUN_TIMEOUT_MS = 5 * 60 * 1000;
const STEPS = '300';

/** JSON with sorted keys: two values equal as data print the same. */
function canonical(v) {
  if (Array.isArray(v)) return `[${v.map(canonical).join(',')}]`;
  if (v && typeof v === 'object') return `{${Object.keys(v).sort().map((k) => `${JSON.stringify(k)}:${canonical(v[k])}`).join(',')}}`;
  return JSON.stringify(v);
}

/** Runs the planner at `volume` cm³ through its controls and saves it as `name` (null: the default). */
async function runAndSave(page, volume, name) {
  await page.click('#tab-2');
  await page.fill('#volume', String(volume));
  await page.waitForFunction(() => window.tissueStudio.planner.check?.ok === true && !document.getElementById('run').disabled,
    null, { timeout: 60000, polling: 100 });
  await page.click('#tab-3');
  await page.getByRole('button', { name: 'Run', exact: true }).click();
  await page.waitForFunction(() => {
    const s = window.tissueStudio.planner.job.state;
    return s !== 'running' && s !== 'idle';
  }, null, { timeout: RUN_TIMEOUT_MS, polling: 200 });
  const job = await page.evaluate(() => ({ ...window.tissueStudio.planner.job, error: window.tissueStudio.planner.error }));
  check(job.state === 'finished', `the ${volume} cm³ run finished (${STEPS} steps at most)`, `${job.state}: ${job.error}`);
  await page.waitForSelector('#save-case:not([hidden])', { timeout: 5000 });
  const suggested = await page.inputValue('#save-name');
  check(new RegExp(`^${volume} cm³ round, \\d{4}-\\d\\d-\\d\\d \\d\\d:\\d\\d$`).test(suggested),
    `the Save box suggests a name: "${suggested}"`);
  if (name) await page.fill('#save-name', name);
  await page.fill('#save-note', `run at ${volume} cm³`);
  await page.getByRole('button', { name: 'Save to cases', exact: true }).click();
  await page.waitForFunction(() => window.tissueStudio.planner.saved || window.tissueStudio.planner.error, null, { timeout: 30000 });
  const saved = await page.evaluate(() => window.tissueStudio.planner.saved);
  check(saved && saved.uid && saved.name === (name || suggested), `saved as "${saved?.name}" (${saved?.uid})`,
    await page.evaluate(() => window.tissueStudio.planner.error));
  // What the run drew, and the job's report as downloaded: what the Cases view must show again.
  const drawn = await page.evaluate(async () => {
    const p = window.tissueStudio.planner;
    const after = Float32Array.from(p.lastRun.fields.after);
    let sum = 0;
    for (let i = 0; i < after.length; i++) sum += after[i];
    const maxDisplacement = p.lastRun.fields.displacement.reduce((m, v) => Math.max(m, v), -Infinity);
    const report = await (await fetch(`/api/results/${p.lastRun.job}/report.json`)).text();
    return { positionSum: sum, vertices: after.length / 3, maxDisplacement, reportText: report, report: p.lastRun.report };
  });
  return { saved, ...drawn };
}

async function main() {
  let base = await serverUrl();
  const browser = await launchBrowser();
  try {
    // a. two plans run and saved through the planner's controls
    const planner = await newPage(browser);
    let page = planner.page;
    await page.goto(`${base}planner`);
    await page.waitForFunction(() => window.tissueStudio?.planner?.ready === true, null, { timeout: 120000 });
    const centre = await page.evaluate(() => window.tissueStudio.planner.screenOf([0, 0, 0]));
    await page.mouse.click(centre.x, centre.y);
    await page.waitForFunction(() => window.tissueStudio.planner.check?.ok === true, null, { timeout: 30000 });
    await page.click('#tab-2');
    if (!(await page.isVisible('#max-steps'))) await page.click('details.advanced summary');
    await page.fill('#max-steps', STEPS);
    const small = await runAndSave(page, 60, 'Small, 60 cm³');
    await shot(page, 'cases-0-saved.png');
    const large = await runAndSave(page, 120, null);
    check(large.report.area_gain_cm2 > small.report.area_gain_cm2,
      `120 cm³ gains more than 60 cm³: ${large.report.area_gain_cm2.toFixed(2)} > ${small.report.area_gain_cm2.toFixed(2)} cm²`);
    check(planner.pageErrors.length === 0, 'no script errors in the planner', planner.pageErrors.join(' | '));
    await page.context().close();

    // b. the restart: another server process on the same case library
    const restarted = await restartServer();
    if (restarted) {
      base = restarted;
      ok('the server was restarted on the same --data folder');
    }

    // c. the Cases page lists the patient with both plans, newest first
    const cases = await newPage(browser);
    page = cases.page;
    const sockets = [];
    page.on('websocket', (ws) => sockets.push(ws.url()));
    await page.goto(`${base}`);
    await page.getByRole('link', { name: /Cases/ }).click();
    await page.waitForFunction(() => window.tissueStudio?.cases?.ready === true, null, { timeout: 30000 });
    const list = await page.evaluate(() => window.tissueStudio.cases.patients);
    check(list.length === 1 && list[0].plans.length === 2, `one patient with two plans (${list.length} patients)`, JSON.stringify(list).slice(0, 300));
    check(list[0].plans[0].uid === large.saved.uid && list[0].plans[1].uid === small.saved.uid, 'the plans newest first');
    const listed = await page.textContent('#patients');
    check(listed.includes('Small, 60 cm³') && listed.includes('run at 60 cm³'), 'the list shows the names and notes');
    await shot(page, 'cases-1-list.png');

    // d. a plan opened: the stored result at once, nothing recomputed
    await page.getByRole('button', { name: 'Open Small, 60 cm³' }).click();
    await page.waitForFunction(() => window.tissueStudio.cases.showing === 'plan' && window.tissueStudio.cases.opened?.ms != null, null, { timeout: 30000 });
    const opened = await page.evaluate(() => {
      const c = window.tissueStudio.cases;
      return { ms: c.opened.ms, fetchMs: c.opened.fetchMs, report: c.opened.report, drawn: c.drawn(), uid: c.opened.plan.uid };
    });
    check(canonical(opened.report) === canonical(small.report), 'the opened plan shows the run\'s report as it was');
    check(opened.drawn.vertices === small.vertices && opened.drawn.positionSum === small.positionSum,
      `the 3D view draws the run's skin after, bit for bit (${opened.drawn.vertices} vertices, position sum ${opened.drawn.positionSum})`,
      `${opened.drawn.positionSum} vs ${small.positionSum}`);
    check(opened.drawn.coloured && opened.drawn.colorRange?.[0] === 0 && Math.abs(opened.drawn.colorRange[1] - small.maxDisplacement) < 1e-12,
      `coloured by the stored displacement, 0 to ${small.maxDisplacement.toFixed(4)} cm`, JSON.stringify(opened.drawn.colorRange));
    const report = await page.evaluate(async (uid) => (await fetch(`/api/cases/plans/${uid}/files/report.json`)).text(), opened.uid);
    check(report === small.reportText, 'its report.json download is byte for byte the job\'s');
    check(sockets.length === 0, `no job socket opened: nothing ran (${sockets.length} sockets)`);
    check(opened.ms < 5000, `the plan opened and was drawn in ${opened.ms.toFixed(0)} ms (${opened.fetchMs.toFixed(0)} ms the answer)`);
    const shown = await page.textContent('#report-figures');
    check(shown.includes(small.report.area_gain_cm2.toFixed(2)), 'the panel shows its gain');
    await page.waitForTimeout(300);
    const stats = await page.evaluate(() => window.tissueStudio.cases.pixelStats());
    check(stats.nonBackground / (stats.width * stats.height) > 0.05 && stats.distinctColours > 50,
      `the view draws the coloured skin (${stats.distinctColours} colours)`);
    await shot(page, 'cases-2-opened.png');

    // e. the two side by side
    await page.getByRole('checkbox', { name: 'Compare Small, 60 cm³' }).check();
    await page.getByRole('checkbox', { name: `Compare ${large.saved.name}` }).check();
    await page.getByRole('button', { name: 'Compare the two checked' }).click();
    await page.waitForFunction(() => window.tissueStudio.cases.showing === 'compare' && window.tissueStudio.cases.comparison?.ms != null, null, { timeout: 30000 });
    const c = await page.evaluate(() => {
      const k = window.tissueStudio.cases;
      return { a: k.comparison.a.uid, b: k.comparison.b.uid, figures: k.comparison.figures, max: k.comparison.max_difference, drawn: k.drawn(), ms: k.comparison.ms };
    });
    const gain = c.figures.find((f) => f.name === 'area_gain_cm2');
    check(c.a === small.saved.uid && c.b === large.saved.uid && gain
      && gain.a === small.report.area_gain_cm2 && gain.b === large.report.area_gain_cm2
      && Math.abs(gain.difference - (gain.b - gain.a)) < 1e-9,
      `the figures side by side: gain ${gain?.a?.toFixed(2)} and ${gain?.b?.toFixed(2)} cm², B − A ${gain?.difference?.toFixed(2)} cm²`);
    check(c.max > 0 && c.drawn.coloured && c.drawn.colorRange?.[1] === c.max,
      `the difference map is drawn, largest ${c.max.toFixed(4)} cm (${c.ms.toFixed(0)} ms)`);
    const table = await page.textContent('#compare-table');
    const bar = await page.textContent('#colorbar');
    check(/B − A/.test(table) && /Area gain/.test(table) && /cm\b/.test(bar), 'the table and the colour bar (in the scan\'s unit) are shown', bar);
    await page.waitForTimeout(300);
    await shot(page, 'cases-3-compare.png');

    // f. rename and note
    await page.getByRole('button', { name: 'Open Small, 60 cm³' }).click();
    await page.waitForFunction(() => window.tissueStudio.cases.showing === 'plan', null, { timeout: 30000 });
    await page.fill('#plan-name', 'Small plan');
    await page.getByRole('button', { name: 'Rename', exact: true }).click();
    await page.fill('#plan-note', 'too little skin');
    await page.getByRole('button', { name: 'Save note' }).click();
    // The list is reloaded after each change: wait for the one that shows both.
    const renamed = await page.waitForFunction(() => {
      const k = window.tissueStudio.cases;
      const p = k.patients[0]?.plans.find((q) => q.name === 'Small plan');
      return k.lastAction?.kind === 'note' && !k.loading && p?.note === 'too little skin' ? p : null;
    }, null, { timeout: 10000 }).then((h) => h.jsonValue()).catch(() => null);
    const listed2 = await page.textContent('#patients');
    check(renamed && listed2.includes('Small plan') && listed2.includes('too little skin'), 'the plan renamed and its note set, in the list');

    // g. delete a plan (confirmed)
    await page.getByRole('button', { name: `Open ${large.saved.name}` }).click();
    await page.waitForFunction((uid) => window.tissueStudio.cases.opened?.plan.uid === uid, large.saved.uid, { timeout: 30000 });
    let dialog = '';
    page.once('dialog', (d) => {
      dialog = d.message();
      d.accept();
    });
    await page.getByRole('button', { name: 'Delete this plan…' }).click();
    await page.waitForFunction(() => window.tissueStudio.cases.lastAction?.kind === 'delete-plan' && window.tissueStudio.cases.patients[0]?.plans.length === 1,
      null, { timeout: 10000 });
    check(dialog.includes(large.saved.name), `the delete was confirmed first: "${dialog}"`);
    ok('the plan is deleted: one left');

    // h. rename the patient, search by label
    const label0 = (await page.evaluate(() => window.tissueStudio.cases.patients[0].patient.label));
    await page.getByRole('button', { name: `Rename ${label0}` }).click();
    await page.getByRole('textbox', { name: 'Patient label' }).fill('Mrs T., left breast');
    await page.getByRole('button', { name: 'Save', exact: true }).click();
    await page.waitForFunction(() => window.tissueStudio.cases.patients[0]?.patient.label === 'Mrs T., left breast', null, { timeout: 10000 });
    await page.fill('#search', 'nobody');
    await page.waitForFunction(() => window.tissueStudio.cases.search === 'nobody' && !window.tissueStudio.cases.loading && window.tissueStudio.cases.patients.length === 0, null, { timeout: 10000 });
    await page.fill('#search', 'mrs t');
    await page.waitForFunction(() => window.tissueStudio.cases.search === 'mrs t' && !window.tissueStudio.cases.loading && window.tissueStudio.cases.patients.length === 1, null, { timeout: 10000 });
    ok('the patient renamed; the search finds it by its label, and not by another');

    // i. export the case (a zip download)
    const [download] = await Promise.all([
      page.waitForEvent('download'),
      page.getByRole('link', { name: 'Export Mrs T., left breast as a zip' }).click(),
    ]);
    const zip = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 'studio-case-')), 'case.zip');
    await download.saveAs(zip);
    const zipBytes = fs.readFileSync(zip);
    check(zipBytes.length > 1000 && zipBytes.subarray(0, 2).toString() === 'PK', `the case exported as a zip (${zipBytes.length} bytes)`);

    // j. erase the patient (confirmed, naming what goes)
    page.once('dialog', (d) => {
      dialog = d.message();
      d.accept();
    });
    await page.getByRole('button', { name: 'Erase Mrs T., left breast' }).click();
    await page.waitForFunction(() => window.tissueStudio.cases.lastAction?.kind === 'erase' && window.tissueStudio.cases.patients.length === 0, null, { timeout: 30000 });
    check(/Mrs T\., left breast/.test(dialog) && /1 plan/.test(dialog) && /Small plan/.test(dialog) && /cannot be recovered/.test(dialog),
      `the erasure was confirmed, naming what goes: "${dialog}"`);
    await page.fill('#search', '');
    await page.waitForFunction(() => window.tissueStudio.cases.search === '' && !window.tissueStudio.cases.loading, null, { timeout: 10000 });
    const after = await page.evaluate(() => ({ patients: window.tissueStudio.cases.patients.length, showing: window.tissueStudio.cases.showing }));
    check(after.patients === 0 && after.showing === 'none', 'the patient and everything of theirs are gone from the list and the view');
    await shot(page, 'cases-4-erased.png');

    // k. import the case back
    await page.setInputFiles('#import-file', zip);
    await page.waitForFunction(() => window.tissueStudio.cases.imported && window.tissueStudio.cases.patients.length === 1, null, { timeout: 30000 });
    const imported = await page.evaluate(() => window.tissueStudio.cases.patients[0]);
    check(imported.plans.length === 1 && imported.plans[0].name === 'Small plan' && imported.patient.label === 'Mrs T., left breast',
      'the exported case imports back: the patient and its plan');
    fs.rmSync(path.dirname(zip), { recursive: true, force: true });
    await shot(page, 'cases-5-imported.png');
    check(cases.pageErrors.length === 0, 'no script errors or CSP violations in the Cases page', cases.pageErrors.join(' | '));

    // l. Plan again: the planner opens on the stored patient (its label, its mesh), ready to place
    await page.getByRole('link', { name: 'Plan again on Mrs T., left breast' }).click();
    await page.waitForFunction(() => window.tissueStudio?.planner?.ready === true, null, { timeout: 60000 });
    const again = await page.evaluate(() => ({ label: window.tissueStudio.planner.patient.label,
      vertices: window.tissueStudio.planner.patient.summary.vertices, case: window.tissueStudio.planner.patient.case_patient }));
    check(again.label === 'Mrs T., left breast' && again.vertices === small.vertices && again.case === imported.patient.uid,
      `Plan again opens the planner on the stored patient (${again.label}, ${again.vertices} vertices)`, JSON.stringify(again));
    check(cases.pageErrors.length === 0, 'no script errors in the planner opened on it', cases.pageErrors.join(' | '));
  } finally {
    await browser.close();
  }
  await stopServer();
}

run(main);
