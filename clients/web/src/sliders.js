// The parameter sliders, as in GeoGebra: one row per parameter of the scene (a parameter used by
// several surfaces has one slider that drives them all), each with a range input (drag, arrow
// keys, Page Up/Down, Home/End), a number box, a play button that animates the value back and
// forth between min and max, and editable min, max and step (GeoGebra's default: -5 to 5 by 0.1).
//
// Rows are never moved or rebuilt while they exist: a row that holds the keyboard focus or the
// mouse keeps it while the server answers (re-appending the focused row sent focus to the page
// body and ended the drag after the first reply).

import { niceStep } from './axes.js';

export const DEFAULT_RANGE = { min: -5, max: 5, step: 0.1 };
const SWEEP_MS = 4000; // min to max while animating

/** A range that holds `value`: GeoGebra's default, or a symmetric one wide enough (5 × 2^k). */
export function rangeFor(value) {
  let span = DEFAULT_RANGE.max;
  while (Math.abs(value) > span && span < 1e12) span *= 2;
  return span === DEFAULT_RANGE.max ? { ...DEFAULT_RANGE } : { min: -span, max: span, step: niceStep(2 * span, 100) };
}

/** `value` on the slider's grid of steps from min, within [min, max], without float noise. */
export function snapToStep(value, { min, max, step }) {
  const k = Math.round((Math.min(max, Math.max(min, value)) - min) / step);
  const digits = Math.max(0, -Math.floor(Math.log10(step)) + 2);
  return Math.min(max, Number((min + k * step).toFixed(digits)));
}

export class SliderPanel {
  /**
   * @param {HTMLElement} container where the rows go
   * @param {HTMLElement} emptyNote shown when there is no parameter
   * @param {{onValue(name, value), onRange(name, range)}} handlers
   */
  constructor(container, emptyNote, handlers) {
    this.container = container;
    this.emptyNote = emptyNote;
    this.handlers = handlers;
    this.rows = new Map(); // name -> row
    this.animationFrame = null;
    this.lastTick = null;
  }

  /** Rows for `names` in this order; values and ranges (name -> {min, max, step}) of new rows. */
  setNames(names, values, ranges = {}) {
    for (const [name, row] of this.rows) {
      if (!names.includes(name)) {
        row.playing = false;
        row.element.remove();
        this.rows.delete(name);
      }
    }
    names.forEach((name, i) => {
      const row = this.rows.get(name) ?? this.#addRow(name, values[name] ?? 1, ranges[name]);
      const at = this.container.children[i];
      if (at !== row.element) this.container.insertBefore(row.element, at ?? null); // only when out of place
    });
    this.emptyNote.hidden = names.length > 0;
  }

  /** Shows `value` (set elsewhere, e.g. a gallery example), unless the user is moving this slider. */
  setValue(name, value) {
    const row = this.rows.get(name);
    if (row && !row.element.contains(document.activeElement)) row.show(value);
  }

  /** Ranges that differ from GeoGebra's default, for the URL. */
  ranges() {
    const ranges = {};
    for (const [name, row] of this.rows) {
      const r = row.range;
      if (r.min !== DEFAULT_RANGE.min || r.max !== DEFAULT_RANGE.max || r.step !== DEFAULT_RANGE.step) ranges[name] = { ...r };
    }
    return ranges;
  }

  /** Starts or stops animating `name`. */
  setPlaying(name, playing) {
    const row = this.rows.get(name);
    if (!row) return;
    row.playing = playing;
    row.playButton.setAttribute('aria-pressed', String(playing));
    row.playButton.textContent = playing ? '❚❚' : '▶';
    if (playing && this.animationFrame === null) {
      this.lastTick = null;
      this.animationFrame = requestAnimationFrame((t) => this.#animate(t));
    }
  }

  #animate(time) {
    const dt = this.lastTick === null ? 0 : Math.min(100, time - this.lastTick);
    this.lastTick = time;
    let any = false;
    for (const [name, row] of this.rows) {
      if (!row.playing) continue;
      any = true;
      const { min, max } = row.range;
      row.phase += (row.direction * dt) / SWEEP_MS;
      if (row.phase >= 1 || row.phase <= 0) {
        row.phase = Math.min(1, Math.max(0, row.phase));
        row.direction = -row.direction; // GeoGebra's "oscillating"
      }
      const value = snapToStep(min + row.phase * (max - min), row.range);
      if (value !== row.value) {
        row.show(value);
        this.handlers.onValue(name, value);
      }
    }
    this.animationFrame = any ? requestAnimationFrame((t) => this.#animate(t)) : null;
  }

  #addRow(name, value, range) {
    const element = document.createElement('div');
    element.className = 'slider';
    element.dataset.parameter = name;
    const playButton = button('▶', `Animate ${name}`, 'play');
    playButton.setAttribute('aria-pressed', 'false');
    const label = document.createElement('span');
    label.className = 'name';
    label.textContent = name;
    const input = document.createElement('input');
    input.type = 'range';
    input.setAttribute('aria-label', name);
    const number = document.createElement('input');
    number.type = 'number';
    number.step = 'any';
    number.setAttribute('aria-label', `Value of ${name}`);
    const settingsButton = button('⋯', `Range of ${name}`, 'settings');
    settingsButton.setAttribute('aria-expanded', 'false');
    const settings = document.createElement('div');
    settings.className = 'range-settings';
    settings.hidden = true;
    const fields = {};
    for (const key of ['min', 'max', 'step']) {
      const field = document.createElement('label');
      const box = document.createElement('input');
      box.type = 'number';
      box.step = 'any';
      box.setAttribute('aria-label', `${key} of ${name}`);
      field.append(key, box);
      settings.append(field);
      fields[key] = box;
    }
    element.append(playButton, label, input, number, settingsButton, settings);

    const row = {
      element,
      playButton,
      range: range ?? rangeFor(value),
      value,
      playing: false,
      phase: 0,
      direction: 1,
      applyRange: () => {
        const { min, max, step } = row.range;
        input.min = String(min);
        input.max = String(max);
        input.step = String(step);
        fields.min.value = String(min);
        fields.max.value = String(max);
        fields.step.value = String(step);
      },
      show: (v) => {
        row.value = v;
        if (v < row.range.min || v > row.range.max) {
          const wider = rangeFor(v);
          row.range = { min: Math.min(wider.min, row.range.min), max: Math.max(wider.max, row.range.max), step: row.range.step };
          row.applyRange();
          this.handlers.onRange?.(name, { ...row.range });
        }
        input.value = String(v);
        number.value = String(Number(v.toPrecision(10)));
        row.phase = (v - row.range.min) / (row.range.max - row.range.min);
      },
    };
    row.applyRange();
    row.show(value);

    const userValue = (v) => {
      row.value = v;
      row.phase = (v - row.range.min) / (row.range.max - row.range.min);
      this.handlers.onValue(name, v);
    };
    input.addEventListener('input', () => {
      const v = Number(input.value);
      number.value = String(v);
      userValue(v);
    });
    number.addEventListener('change', () => {
      const v = Number(number.value);
      if (number.value === '' || !Number.isFinite(v)) {
        number.value = String(row.value);
        return;
      }
      row.show(v);
      userValue(v);
    });
    playButton.addEventListener('click', () => this.setPlaying(name, !row.playing));
    settingsButton.addEventListener('click', () => {
      settings.hidden = !settings.hidden;
      settingsButton.setAttribute('aria-expanded', String(!settings.hidden));
    });
    for (const box of Object.values(fields)) {
      box.addEventListener('change', () => {
        const next = { min: Number(fields.min.value), max: Number(fields.max.value), step: Number(fields.step.value) };
        const valid = Object.values(next).every(Number.isFinite) && next.min < next.max && next.step > 0;
        for (const f of Object.values(fields)) f.classList.toggle('invalid', !valid);
        if (!valid) return;
        row.range = next;
        row.applyRange();
        this.handlers.onRange?.(name, { ...next });
        const clamped = Math.min(next.max, Math.max(next.min, row.value));
        const moved = clamped !== row.value;
        row.show(clamped);
        if (moved) userValue(clamped);
      });
    }
    this.rows.set(name, row);
    return row;
  }
}

function button(text, name, className) {
  const b = document.createElement('button');
  b.type = 'button';
  b.className = className;
  b.textContent = text;
  b.setAttribute('aria-label', name);
  b.title = name;
  return b;
}
