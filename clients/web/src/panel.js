// The panel's settings: examples, detail (triangle budget, error bound and measure), the view box
// (with a message when it is not a box), display options, and the share/export buttons. The
// object list and the sliders have their own modules. It holds no session logic: it shows what it
// is told and reports what the user does through `handlers`.

import { GALLERY } from './gallery.js';
import { validBox } from './url_state.js';

const $ = (selector) => document.querySelector(selector);
const AXES = ['x', 'y', 'z'];
const SHARE_NOTE_MS = 8000;

/**
 * @param {object} handlers onBudget(triangles), onMaxError(value), onErrorMeasure(name), onBox(box),
 *   onGallery(example), onColorMode(mode), onShown({axes, grid, box}), onWireframe(on),
 *   onResetView(), onPause(), onAddSurface(), onCopyLink(), onExport(format), onHelp(),
 *   onPanelShown(on)
 */
export class Panel {
  constructor(handlers) {
    this.handlers = handlers;
    this.budget = $('#budget');
    this.maxError = $('#max-error');
    this.errorMeasure = $('#error-measure');
    this.boxInputs = [...document.querySelectorAll('[data-box]')];
    this.boxError = $('#box-error');
    this.colorMode = $('#color-mode');
    this.checks = { axes: $('#show-axes'), grid: $('#show-grid'), box: $('#show-box') };
    this.wireframe = $('#wireframe');
    this.pauseButton = $('#pause');
    this.addButton = $('#add-surface');
    this.exportButton = $('#export');
    this.exportMenu = $('#export-menu');
    this.shareNote = $('#share-note');
    this.shareLink = $('#share-link');
    this.#wire();
  }

  #wire() {
    const h = this.handlers;
    const gallery = $('#gallery');
    GALLERY.forEach((example, i) => gallery.add(new Option(example.name, String(i))));
    gallery.addEventListener('change', () => {
      if (gallery.value !== '') h.onGallery(GALLERY[Number(gallery.value)]);
      gallery.value = '';
    });

    this.budget.addEventListener('change', () => {
      const n = Number(this.budget.value);
      const valid = Number.isInteger(n) && n >= 1;
      this.budget.classList.toggle('invalid', !valid);
      if (valid) h.onBudget(n);
    });
    this.maxError.addEventListener('change', () => {
      const value = this.maxError.value === '' ? 0 : Number(this.maxError.value);
      const valid = Number.isFinite(value) && value >= 0;
      this.maxError.classList.toggle('invalid', !valid);
      if (valid) h.onMaxError(value);
    });
    this.errorMeasure.addEventListener('change', () => h.onErrorMeasure(this.errorMeasure.value));
    for (const input of this.boxInputs) input.addEventListener('change', () => this.#boxChanged());

    this.colorMode.addEventListener('change', () => h.onColorMode(this.colorMode.value));
    for (const [key, box] of Object.entries(this.checks)) box.addEventListener('change', () => h.onShown({ [key]: box.checked }));
    this.wireframe.addEventListener('change', () => h.onWireframe(this.wireframe.checked));
    $('#reset-view').addEventListener('click', () => h.onResetView());
    this.pauseButton.addEventListener('click', () => h.onPause());
    this.addButton.addEventListener('click', () => h.onAddSurface());
    $('#copy-link').addEventListener('click', () => h.onCopyLink());
    $('#show-help').addEventListener('click', () => h.onHelp());
    $('#hide-panel').addEventListener('click', () => h.onPanelShown(false));
    $('#show-panel').addEventListener('click', () => h.onPanelShown(true));

    this.exportButton.addEventListener('click', () => this.#toggleExportMenu(this.exportMenu.hidden));
    this.exportMenu.addEventListener('click', (event) => {
      const format = event.target.closest('[data-format]')?.dataset.format;
      if (!format) return;
      this.#toggleExportMenu(false);
      h.onExport(format);
    });
    this.exportMenu.addEventListener('keydown', (event) => {
      if (event.key === 'Escape') {
        this.#toggleExportMenu(false);
        this.exportButton.focus();
      }
    });
  }

  #toggleExportMenu(open) {
    this.exportMenu.hidden = !open;
    this.exportButton.setAttribute('aria-expanded', String(open));
    if (open) this.exportMenu.querySelector('button').focus();
  }

  setConstraints({ triangles, max_error: maxError, error_measure: measure }) {
    if (measure && ![...this.errorMeasure.options].some((o) => o.value === measure)) {
      this.errorMeasure.add(new Option(measure, measure)); // a measure this page does not list
    }
    if (measure) this.errorMeasure.value = measure;
    if (Number.isFinite(triangles) && document.activeElement !== this.budget) this.budget.value = String(triangles);
    if (Number.isFinite(maxError) && document.activeElement !== this.maxError) this.maxError.value = maxError > 0 ? String(maxError) : '';
  }

  setBox(box) {
    this.boxInputs.forEach((input, i) => {
      input.value = String(box[i]);
      input.classList.remove('invalid');
    });
    this.boxError.hidden = true;
  }

  setDisplay({ colorMode, show, wireframe }) {
    if (colorMode) this.colorMode.value = colorMode;
    if (show) for (const [key, box] of Object.entries(this.checks)) box.checked = show.includes(key);
    if (wireframe !== undefined) this.wireframe.checked = wireframe;
  }

  setPaused(paused) {
    this.pauseButton.textContent = paused ? 'Resume' : 'Pause';
  }

  setCanAdd(can, why) {
    this.addButton.disabled = !can;
    this.addButton.title = can ? '' : why;
  }

  /** A short note under the share buttons (link copied, file exported, or why not). */
  showShareNote(text, link = null) {
    this.shareNote.textContent = text;
    this.shareNote.hidden = false;
    clearTimeout(this.shareNoteTimer);
    if (link === null) this.shareNoteTimer = setTimeout(() => (this.shareNote.hidden = true), SHARE_NOTE_MS);
    this.shareLink.hidden = link === null;
    if (link !== null) {
      this.shareLink.value = link;
      this.shareLink.select();
    }
  }

  #boxChanged() {
    const box = this.boxInputs.map((input) => (input.value.trim() === '' ? NaN : Number(input.value)));
    const problems = [];
    for (let axis = 0; axis < 3; ++axis) {
      const [lo, hi] = [box[2 * axis], box[2 * axis + 1]];
      const name = AXES[axis];
      if (!Number.isFinite(lo) || !Number.isFinite(hi)) problems.push(`${name} min and ${name} max must be numbers.`);
      else if (lo >= hi) problems.push(`${name} min (${lo}) must be less than ${name} max (${hi}).`);
    }
    this.boxInputs.forEach((input, i) => {
      const axis = Math.floor(i / 2);
      const [lo, hi] = [box[2 * axis], box[2 * axis + 1]];
      input.classList.toggle('invalid', !(Number.isFinite(lo) && Number.isFinite(hi) && lo < hi));
    });
    this.boxError.textContent = problems.length ? `Not a box: ${problems.join(' ')} The surfaces keep the previous box.` : '';
    this.boxError.hidden = problems.length === 0;
    if (validBox(box)) this.handlers.onBox(box);
  }
}
