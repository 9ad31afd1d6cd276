// What the browser tests share: the server (started from STUDIO_BIN, or STUDIO_URL), headless
// Chromium with software WebGL, `ok`/`check` lines, screenshots, and the SIGINT stop.
//
// Environment:
//   STUDIO_BIN  the studio binary (default ../../../target/release/studio from this folder); may be
//               a command with arguments, e.g. "node /tmp/mock.mjs". Started with --port 0 and
//               --data in a fresh temporary folder (the case library; removed when the test
//               ends), so a test never writes in the user's own library.
//   STUDIO_URL  use a server already running at this URL instead (nothing is started or stopped).
//   CHROMIUM    the browser (default /usr/bin/chromium).

import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

export const here = path.dirname(fileURLToPath(import.meta.url));
export const shots = path.join(here, 'screenshots');

let passed = 0;
let failed = 0;

export function ok(what) {
  passed++;
  console.log(`ok - ${what}`);
}

/** Prints `ok - what`, or `not ok - what (detail)` and throws (the test stops there). */
export function check(cond, what, detail = '') {
  if (cond) return ok(what);
  failed++;
  console.log(`not ok - ${what}${detail ? ` (${detail})` : ''}`);
  throw new Error(`check failed: ${what}`);
}

/** The test's case library (`--data`): made on first use, removed when the test ends. */
let dataDir = null;

export function dataFolder() {
  if (!dataDir) dataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'studio-browser-data-'));
  return dataDir;
}

function startServer(args) {
  const bin = process.env.STUDIO_BIN || path.resolve(here, '../../../target/release/studio');
  // A path to an existing file is the binary; otherwise the value is split into a command line.
  const argv = fs.existsSync(bin) ? [bin] : bin.split(/\s+/).filter(Boolean);
  const data = ['--data', dataFolder()];
  const proc = spawn(argv[0], [...argv.slice(1), '--port', '0', ...data, ...args], { stdio: ['ignore', 'pipe', 'inherit'] });
  const exited = new Promise((resolve) => proc.on('exit', (code, signal) => resolve({ code, signal })));
  const url = new Promise((resolve, reject) => {
    let buf = '';
    let found = false;
    const timer = setTimeout(() => reject(new Error('studio did not print its address within 120 s')), 120000);
    proc.on('error', (e) => reject(new Error(`cannot start ${argv[0]}: ${e.message}`)));
    exited.then(({ code, signal }) => {
      if (!found) reject(new Error(`studio exited (code ${code}, signal ${signal}) before printing its address`));
    });
    proc.stdout.setEncoding('utf8');
    proc.stdout.on('data', (chunk) => {
      if (found) return; // keep draining
      buf += chunk;
      const m = buf.match(/^studio: (http:\/\/127\.0\.0\.1:\d+\/(?:\?token=[0-9a-f]+)?)\s*$/m);
      if (m) {
        found = true;
        clearTimeout(timer);
        resolve(m[1]);
      }
    });
  });
  return { proc, url, exited };
}

export async function shot(page, name) {
  const file = path.join(shots, name);
  await page.screenshot({ path: file });
  console.log(`# screenshot ${path.relative(process.cwd(), file)}`);
}

let server = null;

/**
 * The server's base URL (ending in "/"): STUDIO_URL, or a studio started here with `args`
 * (e.g. ['--require-token']: then the address line carries `?token=…`, returned as it is).
 */
export async function serverUrl(args = []) {
  fs.mkdirSync(shots, { recursive: true });
  let base = process.env.STUDIO_URL;
  if (!base) {
    server = startServer(args);
    base = await server.url;
  }
  if (!base.endsWith('/') && !base.includes('?')) base += '/';
  console.log(`# studio at ${base}`);
  return base;
}

export function launchBrowser() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: [
      '--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--disable-gpu-sandbox', '--disable-background-networking', '--disable-component-update',
      '--disable-sync', '--no-first-run',
    ],
  });
}

/**
 * A page whose script errors (and console errors other than failed resources) are collected
 * into the returned array.
 */
export async function newPage(browser, viewport = { width: 1400, height: 900 }) {
  // A context of its own (cookies, storage), in which a test may open more pages.
  const context = await browser.newContext({ viewport });
  const page = await context.newPage();
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => {
    // Failed requests are checked where they matter (e.g. a broken upload answers 400 on purpose).
    // A Content-Security-Policy violation is a console error too, so every test checks the
    // server's policy against the page it serves.
    if (m.type() === 'error' && !/Failed to load resource/.test(m.text())) pageErrors.push(`console: ${m.text()}`);
  });
  // The violations themselves, also those the console does not show.
  await page.addInitScript(() => {
    document.addEventListener('securitypolicyviolation', (e) => {
      console.error(`CSP violation: ${e.violatedDirective} ${e.blockedURI}`);
    });
  });
  return { page, pageErrors };
}

/**
 * Stops the server (SIGINT, checked as stopServer does) and starts another with the same `args`
 * and the same case library: the restart. Its base URL (another port). Null when STUDIO_URL.
 */
export async function restartServer(args = []) {
  if (!server) return null;
  await stopServer();
  server = startServer(args);
  let base = await server.url;
  if (!base.endsWith('/') && !base.includes('?')) base += '/';
  console.log(`# studio restarted at ${base}`);
  return base;
}

/** Sends the server SIGINT and checks it exits with code 0 within 5 s (nothing when STUDIO_URL). */
export async function stopServer() {
  if (!server) return;
  const s0 = Date.now();
  server.proc.kill('SIGINT');
  const res = await Promise.race([server.exited, new Promise((r) => setTimeout(() => r(null), 5000))]);
  if (!res) server.proc.kill('SIGKILL');
  check(res && res.code === 0, `the server exited with code 0 on SIGINT in ${Date.now() - s0} ms`, JSON.stringify(res));
}

/** Runs the test's `main`, prints the tally, never leaves the server behind, and exits. */
export function run(main) {
  main()
    .catch((e) => {
      if (!/^check failed/.test(e.message)) {
        failed++;
        console.log(`not ok - ${e.message}`);
      }
    })
    .finally(() => {
      if (server && server.proc.exitCode === null && server.proc.signalCode === null) server.proc.kill('SIGKILL');
      if (dataDir) fs.rmSync(dataDir, { recursive: true, force: true });
      console.log(`${passed} passed, ${failed} failed`);
      process.exit(failed === 0 ? 0 : 1);
    });
}
