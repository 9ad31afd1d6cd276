// The trainer's side of apps/studio/API.md ("The trainer"): the organ calls, the session socket and
// the binary surface frames.

import { ApiError, MAX_UPLOAD, ReconnectingSocket, call } from './common.js';

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
 * The page's one session socket, `/api/trainer/ws` (common.js's ReconnectingSocket opens it, and
 * again after a loss: `onOpen({ reconnected })` says so). Text messages go to `onMessage(msg)`;
 * binary frames are parsed and kept as the newest one only (`takeFrame()` hands it over once): if
 * several arrive between two animation frames, only the last is drawn — but an index buffer a
 * skipped frame carried is kept with the frame that replaces it.
 */
export class TrainerSocket extends ReconnectingSocket {
  constructor({ onMessage, onOpen, onClose, onFrameReceived }) {
    super('/api/trainer/ws', {
      onText: onMessage,
      onBinary: (buffer) => this.onFrame(buffer),
      onOpen,
      onClose: () => {
        this.pending = null;
        onClose();
      },
    });
    this.onFrameReceived = onFrameReceived || (() => {});
    this.pending = null;
    this.badFrames = 0;
  }

  onFrame(buffer) {
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
}
