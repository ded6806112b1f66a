// The object list, GeoGebra's algebra view: one row per surface with its visibility dot (filled in
// the surface's colour when shown), its equation (a text input named "Equation"; Enter sends it),
// a colour picker and a delete button; under it a progress line while the surface is resolved,
// the server's error with the offending character marked, and notes on how the equation was
// read and what the server found. It holds no session logic: it shows what it is told and reports
// what the user does.

import { UNCERTAIN_TITLE } from './outcome.js';

/**
 * @param {HTMLOListElement} list
 * @param {{onEquation(row, text), onColor(row, color), onVisible(row, on), onDelete(row)}} handlers
 */
export class ObjectList {
  constructor(list, handlers) {
    this.list = list;
    this.handlers = handlers;
    this.rows = [];
  }

  /** A new row at the end; returns it. */
  addRow({ expression = '', color, visible = true }) {
    const row = new ObjectRow(this.handlers, { expression, color, visible });
    this.rows.push(row);
    this.list.append(row.element);
    this.#renumber();
    return row;
  }

  removeRow(row) {
    const i = this.rows.indexOf(row);
    if (i < 0) return;
    this.rows.splice(i, 1);
    row.element.remove();
    this.#renumber();
  }

  #renumber() {
    this.rows.forEach((row, i) => row.setNumber(i + 1));
  }
}

export class ObjectRow {
  constructor(handlers, { expression, color, visible }) {
    const element = document.createElement('li');
    element.className = 'object';
    const line = document.createElement('div');
    line.className = 'object-line';
    this.visibleButton = makeButton('visible');
    this.visibleButton.setAttribute('aria-pressed', String(visible));
    this.input = document.createElement('input');
    this.input.type = 'text';
    this.input.className = 'equation';
    this.input.spellcheck = false;
    this.input.autocomplete = 'off';
    this.input.placeholder = 'x^2+y^2+z^2=4';
    this.input.setAttribute('aria-label', 'Equation');
    this.input.value = expression;
    this.colorInput = document.createElement('input');
    this.colorInput.type = 'color';
    this.colorInput.value = color;
    this.deleteButton = makeButton('delete');
    this.deleteButton.textContent = '×';
    line.append(this.visibleButton, this.input, this.colorInput, this.deleteButton);

    this.progress = document.createElement('div');
    this.progress.className = 'progress';
    this.progressBar = document.createElement('span');
    this.progressBar.className = 'bar';
    this.progressText = document.createElement('span');
    this.progressText.className = 'text';
    this.uncertainMark = document.createElement('span');
    this.uncertainMark.className = 'uncertain';
    this.uncertainMark.title = UNCERTAIN_TITLE;
    this.progress.append(this.progressBar, this.progressText, this.uncertainMark);

    this.errorBox = document.createElement('div');
    this.errorBox.className = 'equation-error';
    this.errorBox.setAttribute('role', 'alert');
    this.errorBox.hidden = true;
    this.marked = document.createElement('code');
    this.marked.className = 'marked';
    this.errorMessage = document.createElement('span');
    this.errorMessage.className = 'message';
    this.errorBox.append(this.marked, this.errorMessage);

    this.notes = document.createElement('ul');
    this.notes.className = 'notes';
    this.notes.setAttribute('aria-live', 'polite');
    this.notes.hidden = true;

    element.append(line, this.progress, this.errorBox, this.notes);
    this.element = element;
    this.visible = visible;
    this.setColor(color);

    this.input.addEventListener('keydown', (event) => {
      if (event.key === 'Enter') handlers.onEquation(this, this.input.value);
    });
    this.input.addEventListener('input', () => this.input.classList.remove('invalid'));
    this.colorInput.addEventListener('input', () => {
      this.setColor(this.colorInput.value);
      handlers.onColor(this, this.colorInput.value);
    });
    this.visibleButton.addEventListener('click', () => {
      this.setVisible(!this.visible);
      handlers.onVisible(this, this.visible);
    });
    this.deleteButton.addEventListener('click', () => handlers.onDelete(this));
  }

  setNumber(n) {
    this.number = n;
    this.element.dataset.index = String(n);
    label(this.visibleButton, `Show surface ${n}`);
    label(this.colorInput, `Colour of surface ${n}`);
    label(this.deleteButton, `Delete surface ${n}`);
  }

  setEquation(text) {
    this.input.value = text;
    this.input.classList.remove('invalid');
  }

  setColor(color) {
    this.color = color;
    this.colorInput.value = color;
    this.element.style.setProperty('--surface-color', color);
  }

  setVisible(on) {
    this.visible = on;
    this.visibleButton.setAttribute('aria-pressed', String(on));
    this.element.classList.toggle('hidden-surface', !on);
  }

  /**
   * The error under the input: `text` with the character at the 1-based `column` (code points, as
   * the server counts them) marked, then the message. No column: the message only.
   */
  showError(text, message, column) {
    this.marked.replaceChildren();
    if (Number.isInteger(column) && column >= 1) {
      const chars = Array.from(text);
      const at = Math.min(column - 1, chars.length);
      const mark = document.createElement('mark');
      mark.textContent = chars[at] ?? ' ';
      this.marked.append(chars.slice(0, at).join(''), mark, chars.slice(at + 1).join(''));
      this.marked.hidden = false;
    } else {
      this.marked.hidden = true;
    }
    this.errorMessage.textContent = message;
    this.errorBox.hidden = false;
    this.input.classList.add('invalid');
  }

  clearError() {
    this.errorBox.hidden = true;
    this.input.classList.remove('invalid');
  }

  /** Notes on how the equation was read, or why nothing shows (an array of strings). */
  setNotes(notes) {
    const same = notes.length === this.notes.children.length && notes.every((n, i) => this.notes.children[i].textContent === n);
    if (same) return;
    this.notes.replaceChildren(...notes.map((text) => Object.assign(document.createElement('li'), { textContent: text })));
    this.notes.hidden = notes.length === 0;
  }

  /**
   * The progress line: {status, triangles, budget, uncertain}. While the shape is being found, a
   * moving bar; while refining, the share of the budget reached; converged: the triangle count
   * alone, and a discreet mark when the server could not prove the shape everywhere.
   */
  setProgress({ status, triangles, budget, uncertain = false }) {
    const count = `${triangles} triangles`;
    const text = {
      empty: 'Type an equation and press Enter',
      error: '',
      ended: 'ended',
      connecting: 'connecting…',
      disconnected: triangles > 0 ? `reconnecting… · ${count}` : 'reconnecting…',
      meshing: 'finding the shape…',
      resolving: `finding the shape… · ${count}`,
      refining: `refining · ${count}`,
      converged: count,
      paused: `paused · ${count}`,
    }[status];
    this.progressText.textContent = text ?? status;
    this.progress.dataset.status = status;
    this.uncertainMark.textContent = uncertain && status === 'converged' ? ' · approximate in places' : '';
    const fraction = status === 'refining' && budget > 0 ? Math.min(1, triangles / budget) : status === 'converged' ? 1 : 0;
    const sweeping = ['meshing', 'resolving', 'connecting', 'disconnected'].includes(status);
    this.progressBar.style.width = sweeping ? '' : `${(100 * fraction).toFixed(1)}%`;
  }
}

function makeButton(className) {
  const b = document.createElement('button');
  b.type = 'button';
  b.className = className;
  return b;
}

function label(element, name) {
  element.setAttribute('aria-label', name);
  element.title = name;
}
