// The pointer on the planner's 3D view: a click on the skin places the expander, a drag that
// starts on its centre marker moves it over the skin (the live preview follows), shift+drag on
// the skin turns it about its centre, and hovering over a result reads the colour map's value.
// What each does to the page is the page's (`actions`); this module only reads the gestures.

const CLICK_SLOP_PX = 5;
/** A press within this many pixels of the expander's centre grabs it (a drag moves it). */
export const GRAB_RADIUS_PX = 24;

/**
 * Listens on `view`'s canvas. `actions`:
 * - `canPlace()`, `place(hit, t)` — whether a click may place, and the placing (`t`: the event's
 *   time stamp);
 * - `drag(hit, t, last)` — the expander dragged to a surface point (`last`: let go there);
 * - `clickRefused()` — a click that may not place;
 * - `centre()` — the placement `{ point, normal }` or null; `rotation()` and `rotate(deg)`;
 * - `readout(hit)` — the text under the cursor for a surface hit, or null for none.
 */
export function setupPointer(view, actions) {
  const canvas = view.canvas;
  const box = document.getElementById('readout');
  let down = null;
  let rotating = null;
  let dragging = false;
  // Capture phase on the canvas: runs before OrbitControls' own listener, so a shift+drag that
  // turns the expander does not also pan the camera.
  canvas.addEventListener('pointerdown', (e) => {
    down = { x: e.clientX, y: e.clientY, button: e.button, shift: e.shiftKey };
    const centre = actions.centre();
    if (e.button === 0 && e.shiftKey && centre && actions.canPlace() && view.pick(e.clientX, e.clientY)) {
      const c = view.screenOf(centre.point);
      rotating = {
        c,
        start: Math.atan2(-(e.clientY - c.y), e.clientX - c.x),
        rotation: actions.rotation(),
        sign: view.seesFront(centre.point, centre.normal || [0, 0, 1]) ? 1 : -1,
      };
      view.controls.enabled = false;
      canvas.setPointerCapture(e.pointerId);
      return;
    }
    if (e.button === 0 && !e.shiftKey && centre && actions.canPlace()) {
      const c = view.screenOf(centre.point);
      if (c.visible && Math.hypot(e.clientX - c.x, e.clientY - c.y) <= GRAB_RADIUS_PX) {
        // Grabbed: the camera stays, the expander follows the pointer over the skin.
        dragging = true;
        view.controls.enabled = false;
        canvas.setPointerCapture(e.pointerId);
      }
    }
  }, { capture: true });

  canvas.addEventListener('pointermove', (e) => {
    if (dragging) {
      const hit = view.pick(e.clientX, e.clientY);
      if (hit) actions.drag(hit, e.timeStamp);
      return;
    }
    if (rotating) {
      const a = Math.atan2(-(e.clientY - rotating.c.y), e.clientX - rotating.c.x);
      const deg = rotating.rotation + rotating.sign * ((a - rotating.start) * 180) / Math.PI;
      actions.rotate(Math.round(((((deg + 180) % 360) + 360) % 360) - 180));
      return;
    }
    if (e.buttons === 0) hover(e);
  });

  const end = (e) => {
    const start = down;
    down = null;
    if (dragging && e.type === 'pointerup') {
      const hit = view.pick(e.clientX, e.clientY);
      if (hit) actions.drag(hit, e.timeStamp, true);
    }
    if (rotating || dragging) {
      rotating = null;
      dragging = false;
      view.controls.enabled = true;
      return;
    }
    if (!start || e.type !== 'pointerup') return;
    const moved = Math.hypot(e.clientX - start.x, e.clientY - start.y);
    if (start.button !== 0 || start.shift || moved >= CLICK_SLOP_PX) return;
    if (!actions.canPlace()) {
      actions.clickRefused();
      return;
    }
    const hit = view.pick(e.clientX, e.clientY);
    if (hit) actions.place(hit, e.timeStamp);
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
  canvas.addEventListener('pointerleave', () => {
    box.hidden = true;
  });

  // The readout, once per animation frame at most.
  let frame = 0;
  let last = null;
  function hover(e) {
    last = e;
    if (frame) return;
    frame = requestAnimationFrame(() => {
      frame = 0;
      const hit = view.pick(last.clientX, last.clientY);
      const text = hit ? actions.readout(hit) : null;
      box.hidden = !text;
      if (!text) return;
      box.textContent = text;
      const rect = view.container.getBoundingClientRect();
      box.style.left = `${last.clientX - rect.left + 14}px`;
      box.style.top = `${last.clientY - rect.top + 14}px`;
    });
  }
}
