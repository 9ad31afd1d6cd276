// What the studio's pages share: the server's errors, JSON calls, number formatting, small DOM
// helpers and the page's error box (role="alert", id "error").

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

/** Shows `message` in the page's error box and keeps it in `hook.error`. */
export function showErrorIn(hook, message) {
  hook.error = message;
  const box = $('error');
  box.textContent = message;
  box.hidden = false;
}

/** Empties the page's error box. */
export function clearErrorIn(hook) {
  hook.error = null;
  $('error').hidden = true;
  $('error').textContent = '';
}
