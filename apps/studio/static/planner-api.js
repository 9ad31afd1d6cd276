// The planner's side of apps/studio/API.md: HTTP calls and the page's one WebSocket.

import { ApiError, call } from './common.js';

export { ApiError };

/** GET /api/meshes */
export function listMeshes() {
  return call('/api/meshes');
}

/** POST /api/patients?shipped=ID */
export function loadShipped(id) {
  return call(`/api/patients?shipped=${encodeURIComponent(id)}`, { method: 'POST' });
}

/** POST /api/patients?name=FILE&unit=UNIT with the file's bytes. */
export function uploadPatient(file, unit) {
  const q = `name=${encodeURIComponent(file.name)}&unit=${encodeURIComponent(unit)}`;
  return call(`/api/patients?${q}`, {
    method: 'POST',
    headers: { 'content-type': 'application/octet-stream' },
    body: file,
  });
}

/** POST /api/preview */
export function preview(patient, request) {
  return call('/api/preview', {
    method: 'POST',
    headers: { 'content-type': 'application/json' },
    body: JSON.stringify({ patient, request }),
  });
}

/** Download links of a finished job. */
export function resultUrl(job, file) {
  return `/api/results/${encodeURIComponent(job)}/${file}`;
}

/**
 * The page's one WebSocket to /api/ws, opened on first use and again if it closed.
 * `onMessage(msg)` gets every server message; `onClose()` is told when an open socket closes.
 */
export class JobSocket {
  constructor(onMessage, onClose) {
    this.onMessage = onMessage;
    this.onClose = onClose;
    this.ws = null;
    this.opening = null;
  }

  url() {
    const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
    return `${scheme}//${location.host}/api/ws`;
  }

  /** Resolves with an open socket (reusing the current one). */
  open() {
    if (this.ws && this.ws.readyState === WebSocket.OPEN) return Promise.resolve(this.ws);
    if (this.opening) return this.opening;
    this.opening = new Promise((resolve, reject) => {
      let ws;
      try {
        ws = new WebSocket(this.url());
      } catch (e) {
        this.opening = null;
        reject(new ApiError({ kind: 'unknown', field: null, message: 'Cannot open the connection to the studio server.' }, 0));
        return;
      }
      let opened = false;
      ws.addEventListener('open', () => {
        opened = true;
        this.ws = ws;
        this.opening = null;
        resolve(ws);
      });
      ws.addEventListener('message', (ev) => {
        let msg;
        try {
          msg = JSON.parse(ev.data);
        } catch {
          return;
        }
        this.onMessage(msg);
      });
      ws.addEventListener('close', () => {
        if (this.ws === ws) this.ws = null;
        if (!opened) {
          this.opening = null;
          reject(new ApiError({ kind: 'unknown', field: null, message: 'Cannot open the connection to the studio server. Is it still running?' }, 0));
        } else {
          this.onClose();
        }
      });
    });
    return this.opening;
  }

  /** Sends `msg` as JSON, opening the socket first if needed. */
  async send(msg) {
    const ws = await this.open();
    ws.send(JSON.stringify(msg));
  }

  /** Whether the socket is open now. */
  isOpen() {
    return !!this.ws && this.ws.readyState === WebSocket.OPEN;
  }
}
