// The planner's side of apps/studio/API.md: HTTP calls and the page's one WebSocket.

import { ApiError, ReconnectingSocket, call } from './common.js';

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

/** POST /api/cases/save: finished job `job` kept in the case library as plan `name`. */
export function saveCase(job, name, note) {
  return call('/api/cases/save', {
    method: 'POST',
    headers: { 'content-type': 'application/json' },
    body: JSON.stringify({ job, name, note }),
  });
}

/** POST /api/cases/patients/{uid}/open: a stored patient loaded to plan on. */
export function openStoredPatient(uid) {
  return call(`/api/cases/patients/${encodeURIComponent(uid)}/open`, { method: 'POST' });
}

/** Download links of a finished job. */
export function resultUrl(job, file) {
  return `/api/results/${encodeURIComponent(job)}/${file}`;
}

/**
 * The page's one job socket, `/api/ws` (common.js's ReconnectingSocket opens it, and again after
 * a loss). `onMessage(msg)` gets every server message; `onClose()` is told when an open socket
 * closes (a running job is lost with it).
 */
export class JobSocket extends ReconnectingSocket {
  constructor(onMessage, onClose) {
    super('/api/ws', { onText: onMessage, onClose });
  }
}
