// The trainer's side of apps/studio/API.md ("The trainer"): the organ calls, the session socket and
// the binary surface frames.

import { ApiError, MAX_UPLOAD, call } from './common.js';

export { ApiError, MAX_UPLOAD };
export const FRAME_MAGIC = 0x31465354; // "TSF1", little-endian
const HEADER_BYTES = 48;


/** GET /api/organs → [{id, label, default}] */
export function listOrgans() {
  return call('/api/organs');
}

/** POST /api/organs?name=FILE&unit=UNIT with the file's bytes → {organ, label, nodes, tets} */
export function uploadOrgan(file, unit) {
  const q = `name=${encodeURIComponent(file.name)}&unit=${encodeURIComponent(unit)}`;
  return call(`/api/organs?${q}`, {
    method: 'POST',
    headers: { 'content-type': 'application/octet-stream' },
    body: file,
  });
}

/**
 * Reads a binary frame (API.md's table). Returns null for a buffer that is not a frame.
 * `positions` and `index` are views on `buffer` (no copy); `index` is null without flag bit 0.
 */
export function parseFrame(buffer) {
  if (!(buffer instanceof ArrayBuffer) || buffer.byteLength < HEADER_BYTES) return null;
  const dv = new DataView(buffer);
  if (dv.getUint32(0, true) !== FRAME_MAGIC) return null;
  const flags = dv.getUint32(4, true);
  const frame = dv.getUint32(8, true);
  const step = dv.getUint32(12, true);
  const vertices = dv.getUint32(16, true);
  const triangles = dv.getUint32(20, true);
  const f32 = (o) => dv.getFloat32(o, true);
  const force = [f32(24), f32(28), f32(32)];
  const tip = [f32(36), f32(40), f32(44)];
  const hasIndex = (flags & 1) !== 0;
  const need = HEADER_BYTES + 12 * vertices + (hasIndex ? 12 * triangles : 0);
  if (buffer.byteLength < need) return null;
  // Offsets are multiples of 4, so typed views need no copy (little-endian hosts: every browser
  // this page runs in).
  const positions = new Float32Array(buffer, HEADER_BYTES, 3 * vertices);
  const index = hasIndex ? new Uint32Array(buffer, HEADER_BYTES + 12 * vertices, 3 * triangles) : null;
  return { flags, frame, step, vertices, triangles, force, tip, positions, index };
}

/**
 * The page's one session socket, `/api/trainer/ws`. Text messages go to `onMessage(msg)`; binary
 * frames are parsed and kept as the newest one only (`takeFrame()` hands it over once): if
 * several arrive between two animation frames, only the last is drawn — but an index buffer a
 * skipped frame carried is kept with the frame that replaces it.
 */
export class TrainerSocket {
  constructor({ onMessage, onClose, onFrameReceived }) {
    this.onMessage = onMessage;
    this.onClose = onClose;
    this.onFrameReceived = onFrameReceived || (() => {});
    this.ws = null;
    this.opening = null;
    this.pending = null;
    this.badFrames = 0;
  }

  url() {
    const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
    return `${scheme}//${location.host}/api/trainer/ws`;
  }

  open() {
    if (this.ws && this.ws.readyState === WebSocket.OPEN) return Promise.resolve(this.ws);
    if (this.opening) return this.opening;
    this.opening = new Promise((resolve, reject) => {
      let ws;
      try {
        ws = new WebSocket(this.url());
      } catch {
        this.opening = null;
        reject(new ApiError({ kind: 'unknown', field: null, message: 'Cannot open the connection to the studio server.' }, 0));
        return;
      }
      ws.binaryType = 'arraybuffer';
      let opened = false;
      ws.addEventListener('open', () => {
        opened = true;
        this.ws = ws;
        this.opening = null;
        resolve(ws);
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
        this.onMessage(msg);
      });
      ws.addEventListener('close', () => {
        if (this.ws === ws) this.ws = null;
        this.pending = null;
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

  onBinary(buffer) {
    const frame = parseFrame(buffer);
    if (!frame) {
      if (this.badFrames++ === 0) console.warn('trainer: a binary message that is not a TSF1 frame was ignored');
      return;
    }
    this.onFrameReceived(frame);
    const prev = this.pending;
    if (prev && !frame.index && prev.index) frame.index = prev.index; // keep the skipped frame's topology
    this.pending = frame;
  }

  /** The newest frame not drawn yet, or null; each frame is handed over once. */
  takeFrame() {
    const f = this.pending;
    this.pending = null;
    return f;
  }

  /** Drops a frame waiting to be drawn (a new organ is coming). */
  dropFrames() {
    this.pending = null;
  }

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
}
