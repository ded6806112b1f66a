// The left panel, GeoGebra's "algebra view": the equation input (errors under it with the column
// marked), one slider per parameter, quality and view box settings, display toggles. It holds no
// session logic: it shows what it is told and reports what the user does through `handlers`.

import { GALLERY } from './gallery.js';

const $ = (selector) => document.querySelector(selector);

/**
 * @param {object} handlers
 *   onEquation(text), onParameter(name, value), onBudget(triangles), onMaxError(value),
 *   onErrorMeasure(name),
 *   onBox(box), onGallery(example), onWireframe(on), onShowBox(on), onResetView(), onPause()
 */
export class Panel {
  constructor(handlers) {
    this.handlers = handlers;
    this.equation = $('#equation');
    this.error = $('#equation-error');
    this.sliders = $('#parameters .sliders');
    this.noParameters = $('#parameters .empty');
    this.budget = $('#budget');
    this.budgetValue = $('#budget-value');
    this.maxError = $('#max-error');
    this.errorMeasure = $('#error-measure');
    this.boxInputs = [...document.querySelectorAll('[data-box]')];
    this.pauseButton = $('#pause');
    this.sliderRows = new Map();
    this.#wire();
  }

  #wire() {
    const h = this.handlers;
    this.equation.addEventListener('keydown', (event) => {
      if (event.key === 'Enter') h.onEquation(this.equation.value.trim());
    });
    this.equation.addEventListener('input', () => this.equation.classList.remove('invalid'));

    const gallery = $('#gallery');
    GALLERY.forEach((example, i) => gallery.add(new Option(example.name, String(i))));
    gallery.addEventListener('change', () => {
      if (gallery.value !== '') h.onGallery(GALLERY[Number(gallery.value)]);
      gallery.value = '';
    });

    this.budget.addEventListener('input', () => this.#showBudget(this.#budgetTriangles()));
    this.budget.addEventListener('change', () => h.onBudget(this.#budgetTriangles()));
    this.maxError.addEventListener('change', () => {
      const value = this.maxError.value === '' ? 0 : Number(this.maxError.value);
      if (Number.isFinite(value) && value >= 0) h.onMaxError(value);
    });
    this.errorMeasure.addEventListener('change', () => h.onErrorMeasure(this.errorMeasure.value));
    for (const input of this.boxInputs) input.addEventListener('change', () => this.#boxChanged());

    $('#wireframe').addEventListener('change', (e) => h.onWireframe(e.target.checked));
    $('#show-box').addEventListener('change', (e) => h.onShowBox(e.target.checked));
    $('#reset-view').addEventListener('click', () => h.onResetView());
    this.pauseButton.addEventListener('click', () => h.onPause());
  }

  setEquation(text) {
    this.equation.value = text;
    this.equation.classList.remove('invalid');
  }

  /**
   * Shows an error under the input: the equation with the character at the 1-based `column`
   * (code points, as the server counts them) marked, then the message. No column: message only.
   */
  showError(text, message, column) {
    const marked = this.error.querySelector('.marked');
    marked.replaceChildren();
    if (Number.isInteger(column) && column >= 1) {
      const chars = Array.from(text);
      const at = Math.min(column - 1, chars.length);
      const mark = document.createElement('mark');
      mark.textContent = chars[at] ?? ' ';
      marked.append(chars.slice(0, at).join(''), mark, chars.slice(at + 1).join(''));
      marked.hidden = false;
    } else {
      marked.hidden = true;
    }
    this.error.querySelector('.message').textContent = message;
    this.error.hidden = false;
    this.equation.classList.add('invalid');
  }

  clearError() {
    this.error.hidden = true;
    this.equation.classList.remove('invalid');
  }

  /** One slider per parameter, in the given order; existing sliders keep their ranges. */
  setParameters(parameters) {
    const names = Object.keys(parameters);
    for (const [name, row] of this.sliderRows) {
      if (!names.includes(name)) {
        row.element.remove();
        this.sliderRows.delete(name);
      }
    }
    for (const name of names) {
      const row = this.sliderRows.get(name) ?? this.#addSlider(name, parameters[name]);
      if (!row.element.contains(document.activeElement)) row.set(parameters[name]); // not while dragged
      this.sliders.append(row.element); // keeps the order of `names`
    }
    this.noParameters.hidden = names.length > 0;
  }

  #addSlider(name, value) {
    const element = document.createElement('div');
    element.className = 'slider';
    element.dataset.parameter = name;
    const label = document.createElement('span');
    label.className = 'name';
    label.textContent = name;
    const range = document.createElement('input');
    range.type = 'range';
    range.setAttribute('aria-label', `parameter ${name}`);
    const number = document.createElement('input');
    number.type = 'number';
    number.step = 'any';
    number.setAttribute('aria-label', `value of ${name}`);
    element.append(label, range, number);

    const span = Math.max(5, Math.ceil(2 * Math.abs(value)));
    const setRange = (lo, hi) => {
      range.min = String(lo);
      range.max = String(hi);
      range.step = String((hi - lo) / 1000);
    };
    setRange(-span, span);
    const row = {
      element,
      set: (v) => {
        if (v < Number(range.min) || v > Number(range.max)) {
          const wider = Math.max(5, Math.ceil(2 * Math.abs(v)));
          setRange(-wider, wider);
        }
        range.value = String(v);
        number.value = String(round(v));
      },
    };
    range.addEventListener('input', () => {
      const v = Number(range.value);
      number.value = String(round(v));
      this.handlers.onParameter(name, v);
    });
    number.addEventListener('change', () => {
      const v = Number(number.value);
      if (number.value === '' || !Number.isFinite(v)) return;
      row.set(v);
      this.handlers.onParameter(name, v);
    });
    this.sliderRows.set(name, row);
    return row;
  }

  setConstraints({ triangles, max_error: maxError, error_measure: measure }) {
    if (measure && ![...this.errorMeasure.options].some((o) => o.value === measure)) {
      this.errorMeasure.add(new Option(measure, measure)); // a measure this page does not list
    }
    if (measure) this.errorMeasure.value = measure;
    if (Number.isFinite(triangles)) {
      this.budget.value = String(Math.log10(triangles));
      this.#showBudget(triangles);
    }
    if (Number.isFinite(maxError)) this.maxError.value = maxError > 0 ? String(maxError) : '';
  }

  setBox(box) {
    this.boxInputs.forEach((input, i) => (input.value = String(box[i])));
  }

  setPaused(paused) {
    this.pauseButton.textContent = paused ? 'Resume' : 'Pause';
  }

  #budgetTriangles() {
    const raw = 10 ** Number(this.budget.value);
    const magnitude = 10 ** Math.max(0, Math.floor(Math.log10(raw)) - 1);
    return Math.round(raw / magnitude) * magnitude; // two significant digits
  }

  #showBudget(triangles) {
    this.budgetValue.textContent = triangles.toLocaleString('en-US');
  }

  #boxChanged() {
    const box = this.boxInputs.map((input) => Number(input.value));
    const valid = box.every(Number.isFinite) && box[0] < box[1] && box[2] < box[3] && box[4] < box[5];
    this.boxInputs.forEach((input) => input.classList.toggle('invalid', !valid));
    if (valid) this.handlers.onBox(box);
  }
}

function round(v) {
  return Math.round(v * 1000) / 1000;
}
