// What the studio's pages share: the server's errors, JSON calls, the reconnecting WebSocket,
// number formatting, small DOM helpers, the page's error box (role="alert", id "error") and the
// server's field errors shown at their inputs.

/** An error carrying the server's `{kind, field, message}`. */
export class ApiError extends Error {
  constructor(error, status) {
    super(error && error.message ? error.message : 'The server gave an unexpected answer.');
    this.kind = error && error.kind ? error.kind : 'unknown';
    this.field = error ? error.field ?? null : null;
    this.status = status;
  }
}

/** Fetches `url` and returns its JSON, or throws an ApiError with the server's message. */
export async function call(url, init) {
  let response;
  try {
    response = await fetch(url, init);
  } catch {
    throw new ApiError({ kind: 'unknown', field: null,
      message: 'Cannot reach the studio server. Is it still running?' }, 0);
  }
  let body = null;
  try {
    body = await response.json();
  } catch {
    body = null;
  }
  if (!response.ok) {
    if (body && body.error) throw new ApiError(body.error, response.status);
    throw new ApiError({ kind: 'unknown', field: null,
      message: `The server answered ${response.status} ${response.statusText}.` }, response.status);
  }
  if (body === null) throw new ApiError(null, response.status);
  return body;
}

const LOST = 'Cannot open the connection to the studio server. Is it still running?';

/**
 * One WebSocket to `path` on this server, opened on first use. After an open socket closes it is
 * opened again with a growing delay (0.5 s doubling to 10 s), unless `close()` was called; `send`
 * waits for the socket to be open, so messages sent meanwhile go out in order once it is.
 * The page's socket classes keep only their messages: `onText(msg)` gets every text message
 * (parsed JSON), `onBinary(buffer)` every binary one, `onOpen({ reconnected })` each opening and
 * `onClose()` each loss of an open socket.
 */
export class ReconnectingSocket {
  constructor(path, { onText, onBinary = () => {}, onOpen = () => {}, onClose = () => {} }) {
    Object.assign(this, { path, onText, onBinary, onOpen, onClose });
    this.ws = null;
    this.opening = null;
    this.wanted = false; // reopen after a loss
    this.delayMs = 500;
    this.timer = null;
    this.everOpened = false;
  }

  /** Resolves with the open socket (reusing the current one), or rejects with an ApiError. */
  open() {
    this.wanted = true;
    clearTimeout(this.timer);
    if (this.isOpen()) return Promise.resolve(this.ws);
    if (this.opening) return this.opening;
    this.opening = new Promise((resolve, reject) => {
      const fail = () => {
        this.opening = null;
        reject(new ApiError({ kind: 'unknown', field: null, message: LOST }, 0));
      };
      let ws;
      try {
        const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
        ws = new WebSocket(`${scheme}//${location.host}${this.path}`);
      } catch {
        fail();
        return;
      }
      ws.binaryType = 'arraybuffer';
      let opened = false;
      ws.addEventListener('open', () => {
        opened = true;
        this.ws = ws;
        this.opening = null;
        this.delayMs = 500;
        const reconnected = this.everOpened;
        this.everOpened = true;
        resolve(ws);
        this.onOpen({ reconnected });
      });
      ws.addEventListener('message', (ev) => {
        if (ev.data instanceof ArrayBuffer) {
          this.onBinary(ev.data);
          return;
        }
        let msg;
        try {
          msg = JSON.parse(ev.data);
        } catch {
          return;
        }
        this.onText(msg);
      });
      ws.addEventListener('close', () => {
        if (this.ws === ws) this.ws = null;
        if (opened) this.onClose();
        else fail();
        this.scheduleReopen();
      });
    });
    return this.opening;
  }

  scheduleReopen() {
    if (!this.wanted || this.opening || this.isOpen()) return;
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.open().catch(() => {}), this.delayMs);
    this.delayMs = Math.min(10000, this.delayMs * 2);
  }

  /** Sends `msg` as JSON once the socket is open (opening it if needed). */
  async send(msg) {
    const ws = await this.open();
    ws.send(JSON.stringify(msg));
  }

  /** Sends now if the socket is open (pointer moves: never queued behind a reconnect). */
  sendIfOpen(msg) {
    if (!this.isOpen()) return false;
    this.ws.send(JSON.stringify(msg));
    return true;
  }

  isOpen() {
    return !!this.ws && this.ws.readyState === WebSocket.OPEN;
  }

  /** Closes the socket and stops reopening it (until the next `open` or `send`). */
  close() {
    this.wanted = false;
    clearTimeout(this.timer);
    if (this.ws) this.ws.close();
  }
}

/** The largest upload the server takes (bytes). */
export const MAX_UPLOAD = 64 * 1024 * 1024;

export const $ = (id) => document.getElementById(id);

/** `x` with `digits` decimals (no "-0.00"), or a dash. */
export function fmt(x, digits = 2) {
  if (x === null || x === undefined || !Number.isFinite(Number(x))) return '—';
  let v = Number(x);
  if (Math.abs(v) < 0.5 * 10 ** -digits) v = 0;
  return v.toLocaleString('en-GB', { minimumFractionDigits: digits, maximumFractionDigits: digits });
}

/** A count with thousands separators, or a dash. */
export function fmtInt(x) {
  if (x === null || x === undefined || !Number.isFinite(Number(x))) return '—';
  return Number(x).toLocaleString('en-GB');
}

export function setText(id, text) {
  $(id).textContent = text;
}

/** A new element with attributes (`class` → className) and children. */
export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

/** Offers `blob` as a download named `name`. */
export function saveBlob(blob, name) {
  const url = URL.createObjectURL(blob);
  const a = el('a', { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

/** Shows `message` in the page's error box and keeps it in `state.error`. */
export function showErrorIn(state, message) {
  state.error = message;
  const box = $('error');
  box.textContent = message;
  box.hidden = false;
}

/** Empties the page's error box. */
export function clearErrorIn(state) {
  state.error = null;
  $('error').hidden = true;
  $('error').textContent = '';
}

/**
 * Shows each `{field: message}` of `errors` at the input that sets that field (`inputOf(field)`
 * gives its id, or null): the input is marked invalid (`aria-invalid`, described by the message)
 * and the message is shown in its `.field`. Inputs not named in `errors` are cleared. Returns the
 * messages of fields without an input (for the page's error box).
 */
export function renderFieldErrors(errors, inputOf) {
  const shown = new Set();
  const unplaced = [];
  for (const [field, message] of Object.entries(errors)) {
    const input = inputOf(field) && $(inputOf(field));
    if (!input) {
      unplaced.push(message);
      continue;
    }
    shown.add(input.id);
    const box = input.closest('.field') || input.parentElement;
    let p = $(`${input.id}-error`);
    if (!p) {
      p = el('p', { id: `${input.id}-error`, class: 'field-error', role: 'alert' });
      box.append(p);
    }
    p.textContent = message;
    box.classList.add('invalid');
    input.setAttribute('aria-invalid', 'true');
    input.setAttribute('aria-describedby', p.id);
  }
  for (const p of document.querySelectorAll('.field-error')) {
    const id = p.id.replace(/-error$/, '');
    if (shown.has(id)) continue;
    p.remove();
    const input = $(id);
    if (!input) continue;
    input.removeAttribute('aria-invalid');
    input.removeAttribute('aria-describedby');
    (input.closest('.field') || input.parentElement).classList.remove('invalid');
  }
  return unplaced;
}
