// The studio's access control in a real browser (apps/studio/SECURITY.md): a studio that needs
// its token (`--require-token`, as off loopback), opened at the address it printed; the token
// moves into an HttpOnly cookie and out of the address bar, the planner loads and runs a job over
// its WebSocket with it; without it the page is 401; and a page of another origin on this
// computer (same site, so the SameSite cookie goes along) cannot open the studio's sockets or
// read its API. Every page is checked for Content-Security-Policy violations (harness.mjs).
//
//   npm ci && node security.test.mjs
//
// Environment: see harness.mjs (STUDIO_URL must then be the printed address with its token).

import http from 'node:http';
import { ok, check, shot, serverUrl, launchBrowser, newPage, stopServer, run } from './harness.mjs';

const RUN_TIMEOUT_MS = 5 * 60 * 1000;

/** A page of another origin (another port of 127.0.0.1) that tries the studio at `studio`. */
function evilServer(studio) {
  const ws = studio.replace(/^http/, 'ws');
  const html = `<!doctype html><title>evil</title><script>
    const tryWs = (path) => new Promise((resolve) => {
      const s = new WebSocket('${ws}' + path);
      s.onopen = () => { resolve('open'); s.close(); };
      s.onerror = () => resolve('refused');
    });
    const tryFetch = (path, init) => fetch('${studio}' + path, init)
      .then((r) => (r.type === 'opaque' ? 'opaque' : 'read ' + r.status), () => 'refused');
    window.attack = Promise.all([
      tryWs('/api/ws'), tryWs('/api/trainer/ws'),
      tryFetch('/api/meshes', { credentials: 'include' }),
      tryFetch('/api/patients?shipped=table2', { method: 'POST', mode: 'no-cors', credentials: 'include' }),
    ]);
  </script>`;
  const server = http.createServer((req, res) => {
    res.writeHead(200, { 'content-type': 'text/html' });
    res.end(html);
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

async function main() {
  const base = await serverUrl(['--require-token']);
  const printed = new URL(base);
  const origin = printed.origin;
  const token = printed.searchParams.get('token');
  check(/^[0-9a-f]{32}$/.test(token || ''), 'the address line carries a 128-bit token', base);
  const browser = await launchBrowser();
  try {
    // a. No token: nothing is served.
    {
      const context = await browser.newContext();
      const page = await context.newPage();
      const answer = await page.goto(`${origin}/planner`);
      check(answer.status() === 401, `without the token the page is refused: ${answer.status()}`);
      const body = await page.textContent('body');
      check(/token/.test(body), 'and the answer says to open the printed address', body);
      await context.close();
    }

    // b. The printed address: the token goes into a cookie and out of the address bar.
    const { page, pageErrors } = await newPage(browser);
    const answer = await page.goto(base);
    check(answer.ok(), `the printed address opens the studio (${answer.status()})`);
    check(!page.url().includes('token'), `the token left the address bar: ${page.url()}`);
    const cookies = await page.context().cookies();
    const cookie = cookies.find((c) => c.name === `studio-token-${printed.port}`);
    check(cookie && cookie.value === token && cookie.httpOnly && cookie.sameSite === 'Strict',
      'the token is kept in an HttpOnly, SameSite=Strict cookie', JSON.stringify(cookies));
    check(await page.evaluate(() => document.cookie) === '', 'scripts in the page cannot read it');
    const headers = answer.headers();
    check(/^default-src 'self'/.test(headers['content-security-policy'] || '') &&
      /frame-ancestors 'none'/.test(headers['content-security-policy']) &&
      headers['x-content-type-options'] === 'nosniff' && headers['referrer-policy'] === 'no-referrer',
    'the page comes with its Content-Security-Policy, nosniff and no-referrer',
    JSON.stringify(headers));

    // c. The planner works on the cookie alone: its fetches, its WebSocket, a download.
    await page.goto(`${origin}/planner`);
    await page.waitForFunction(() => window.tissueStudio?.planner?.ready === true, null, { timeout: 120000 });
    ok('the planner loaded the default patient (fetch with the cookie)');
    await page.evaluate(() => window.tissueStudio.planner.placeAt([0, 0, 0]));
    await page.waitForFunction(() => window.tissueStudio.planner.check?.ok === true, null, { timeout: 30000 });
    await page.click('#tab-3');
    await page.getByRole('button', { name: 'Run', exact: true }).click();
    await page.waitForFunction(() => {
      const s = window.tissueStudio.planner.job.state;
      return s !== 'running' && s !== 'idle';
    }, null, { timeout: RUN_TIMEOUT_MS, polling: 200 });
    const job = await page.evaluate(() => ({ ...window.tissueStudio.planner.job, error: window.tissueStudio.planner.error }));
    check(job.state === 'finished', 'a run finished over the WebSocket (the cookie carried the token)', `${job.state}: ${job.error}`);
    const id = await page.evaluate(() => window.tissueStudio.planner.result && document.querySelector('#dl-report')?.getAttribute('href'));
    check(/^\/api\/results\/j[0-9a-f]{32}\/report\.json$/.test(id || ''), `the job's id is unguessable: ${id}`);
    const download = await page.evaluate(async (href) => (await fetch(href)).status, id);
    check(download === 200, `its report downloads (${download})`);
    await page.waitForTimeout(300);
    await shot(page, 'security-1-planner-with-token.png');

    // d. Another origin on this computer: same site, so the cookie would go along; the Origin
    //    check refuses its sockets and POSTs, and without CORS it cannot read the API.
    const evil = await evilServer(origin);
    try {
      const evilPage = await page.context().newPage();
      await evilPage.goto(`http://127.0.0.1:${evil.address().port}/`);
      const [jobs, trainer, read, post] = await evilPage.evaluate(() => window.attack);
      check(jobs === 'refused', `another origin's WebSocket to /api/ws is refused (${jobs})`);
      check(trainer === 'refused', `another origin's WebSocket to /api/trainer/ws is refused (${trainer})`);
      check(read === 'refused', `another origin cannot read /api/meshes (${read})`);
      check(post === 'refused' || post === 'opaque',
        `its no-cors POST gets nothing it can read (${post}: Cross-Origin-Resource-Policy); the server refused it (403, tests/it/security.rs)`);
      await evilPage.close();
    } finally {
      evil.close();
    }
    check(pageErrors.length === 0, 'no script errors and no CSP violations in the page', pageErrors.join(' | '));
  } finally {
    await browser.close();
  }
  await stopServer();
}

run(main);
