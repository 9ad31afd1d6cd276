// The trainer's Tissue panel (issue 32): the organ's material — a preset tissue, custom E, ν, ρ, or
// the classic realtime preset — sent to the server as the socket's `material` command, applied by
// the server on the next reset (or load). See apps/studio/API.md, "The trainer".
//
// The panel holds no rules of the server's: every value goes to the server, whose refusals (naming
// `young_kpa`, `poisson` or `density`) are shown at their inputs.

import { $, call, el, fmt, renderFieldErrors, setText } from './common.js';

/** E's slider: a log scale from E_MIN to E_MAX kPa in E_STEPS positions. */
const E_MIN = 1;
const E_MAX = 300;
const E_STEPS = 1000;

/** The material's fields (their JSON names) and the ids of their number inputs. */
const INPUTS = { young_kpa: 'young-kpa', poisson: 'poisson', density: 'density' };

/** GET /api/tissues → [{id, label, young_kpa, poisson, density, source}] */
export function listTissues() {
  return call('/api/tissues');
}

const eToSlider = (e) => Math.round((E_STEPS * Math.log(e / E_MIN)) / Math.log(E_MAX / E_MIN));
const sliderToE = (p) => E_MIN * (E_MAX / E_MIN) ** (p / E_STEPS);
/** Three significant digits (5.41, 10.8, 123): what a slider position means. */
const sig3 = (x) => Number(x.toPrecision(3));

const sameMaterial = (a, b) => !!a && !!b && a.scheme === b.scheme
  && (a.scheme === 'realtime' || ['young_kpa', 'poisson', 'density'].every((k) => Math.abs(a[k] - b[k]) < 1e-9));

/** "E 5.4 kPa · ν 0.49 · ρ 1.06 g/cm³" */
function describeValues(m) {
  return `E ${fmt(m.young_kpa, m.young_kpa < 10 ? 2 : 1)} kPa · ν ${fmt(m.poisson, 3)} · ρ ${fmt(m.density, 2)} g/cm³`;
}

/**
 * The Tissue panel. `send(msg)` sends a command on the session socket; `state` is the page's state
 * object (the test hook), whose `material` this keeps: `{ scheme, young_kpa, poisson, density,
 * pending }` — the material in force (the numbers null for realtime, everything null before the
 * first scene) and `pending`, the panel's material while it differs from the one in force (null
 * otherwise).
 */
export class TissuePanel {
  constructor({ send, state }) {
    this.send = send;
    this.state = state;
    this.presets = [];
    this.inForce = null; // the scene's material
    this.lastSent = null; // the material last sent (the server keeps it for the next reset)
    this.fieldErrors = {}; // {field: message}: the server's, or the page's own (not a number)
    state.material = { scheme: null, young_kpa: null, poisson: null, density: null, pending: null };
    this.wire();
  }

  async init() {
    try {
      this.presets = await listTissues();
    } catch {
      this.presets = [];
    }
    const select = $('tissue-preset');
    const options = this.presets.map((p) => el('option', { value: p.id, title: p.source },
      `${p.label} (E ${fmt(p.young_kpa, p.young_kpa < 10 ? 2 : 0)} kPa)`));
    options.push(el('option', { value: 'custom' }, 'custom'));
    options.push(el('option', { value: 'realtime' }, 'classic (realtime)'));
    select.replaceChildren(...options);
    if (this.inForce) this.showInForce(true);
  }

  wire() {
    $('tissue-preset').addEventListener('change', (e) => this.pickPreset(e.target.value));
    for (const [field, id] of Object.entries(INPUTS)) {
      const input = $(id);
      const slider = $(`${id}-slider`);
      input.addEventListener('input', () => {
        $('tissue-preset').value = 'custom';
        const v = parseFloat(input.value);
        if (Number.isFinite(v)) slider.value = String(field === 'young_kpa' ? eToSlider(v) : v);
        this.update();
      });
      input.addEventListener('change', () => this.flush());
      slider.addEventListener('input', () => {
        $('tissue-preset').value = 'custom';
        const p = parseFloat(slider.value);
        input.value = String(field === 'young_kpa' ? sig3(sliderToE(p)) : p);
        this.update();
      });
      slider.addEventListener('change', () => this.flush());
    }
  }

  /** A preset moves the sliders; "classic (realtime)" leaves them as they are. */
  pickPreset(id) {
    const p = this.presets.find((x) => x.id === id);
    if (p) this.setValues(p);
    this.update();
    this.flush();
  }

  setValues(m) {
    for (const [field, id] of Object.entries(INPUTS)) {
      $(id).value = String(m[field]);
      $(`${id}-slider`).value = String(field === 'young_kpa' ? eToSlider(m[field]) : m[field]);
    }
  }

  /** The material the panel shows, or null when an input holds no number (with its error). */
  wanted() {
    if ($('tissue-preset').value === 'realtime') return { scheme: 'realtime' };
    const m = { scheme: 'material' };
    const own = {};
    for (const [field, id] of Object.entries(INPUTS)) {
      const v = Number($(id).value.trim() === '' ? NaN : $(id).value);
      if (!Number.isFinite(v)) own[field] = 'Type a number.';
      m[field] = v;
    }
    this.ownErrors = own;
    return Object.keys(own).length ? null : m;
  }

  /** The hook, the note and the errors after any change (nothing before the first scene). */
  update() {
    if (!this.inForce) return;
    const m = this.wanted();
    const pending = m && !sameMaterial(m, this.inForce) ? m : null;
    const unreadable = !m;
    Object.assign(this.state.material, { pending: unreadable ? this.state.material.pending : pending });
    $('tissue-pending').hidden = !(pending || unreadable);
    const disabled = $('tissue-preset').value === 'realtime';
    for (const id of Object.values(INPUTS)) $(`${id}-slider`).closest('.tissue-row').classList.toggle('off', disabled);
    this.renderErrors();
  }

  /** Sends the panel's material when it changed since the last sent (a change, or before Reset). */
  flush() {
    if (!this.inForce) return;
    const m = this.wanted();
    this.update();
    if (!m || sameMaterial(m, this.lastSent)) return;
    this.lastSent = m;
    // A new value: the server's earlier refusal no longer applies.
    this.fieldErrors = {};
    this.renderErrors();
    const material = m.scheme === 'realtime' ? { scheme: 'realtime' } : m;
    this.send({ type: 'material', material });
  }

  renderErrors() {
    renderFieldErrors({ ...this.fieldErrors, ...(this.ownErrors || {}) }, (f) => INPUTS[f]);
  }

  /** The server's answer to a material command. */
  onMaterial(msg) {
    if (msg.in_force) this.inForce = msg.in_force;
    this.fieldErrors = {};
    this.update();
  }

  /**
   * A failure the panel shows at its input (the server named one of its fields); true when it
   * was one. The panel's material is then not kept by the server.
   */
  onFailed(error) {
    const field = error?.field;
    if (!field || !INPUTS[field]) return false;
    this.fieldErrors = { [field]: error.message };
    this.lastSent = null;
    this.update();
    return true;
  }

  /** A scene: its material is in force; the panel shows it (what was pending has been applied). */
  onScene(scene) {
    if (!scene.material) return;
    this.inForce = scene.material;
    this.lastSent = scene.material;
    this.fieldErrors = {};
    this.showInForce(true);
  }

  /** The material in force in the hook and the panel; with `controls`, the controls show it too. */
  showInForce(controls) {
    const m = this.inForce;
    const realtime = m.scheme === 'realtime';
    Object.assign(this.state.material, {
      scheme: m.scheme,
      young_kpa: realtime ? null : m.young_kpa,
      poisson: realtime ? null : m.poisson,
      density: realtime ? null : m.density,
    });
    const preset = realtime ? null : this.presets.find((p) => sameMaterial({ scheme: 'material', ...p }, m));
    if (controls) {
      if (!realtime) this.setValues(m);
      else if ($('young-kpa').value === '') this.setValues(this.presets[0] || { young_kpa: 10, poisson: 0.45, density: 1.05 });
      if (this.presets.length) $('tissue-preset').value = realtime ? 'realtime' : (preset ? preset.id : 'custom');
    }
    setText('tissue-in-force', '');
    const name = realtime ? 'classic realtime preset' : (preset ? preset.label : 'custom tissue');
    const what = realtime ? 'no material constants: the stiffness is what the solver\'s iterations leave'
      : `${describeValues(m)}; neo-Hookean, 32 substeps`;
    $('tissue-in-force').append('In force: ', el('strong', {}, name), ` — ${what}.`);
    this.update();
  }
}
