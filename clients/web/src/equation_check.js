// What the viewer checks and rewrites in an equation before sending it, so that no input ends
// silently. Pure: no DOM. What the server finds (no surface in the box, a region rather than a
// surface) is the server's to say: outcome.js words it.
//
// - An empty equation is refused with a message (an empty Enter does nothing otherwise).
// - Capital X, Y, Z are the coordinates, as GeoGebra reads them: the server's language is
//   case-sensitive (X would be a parameter with a slider), so `X^2+Y^2+Z^2=4` is sent as
//   `x^2+y^2+z^2=4` and a note says so. A name made only of coordinate letters (`XY`) is a product
//   of coordinates, as `xy` is.
// - An equation without a relation (`x^2+y^2+z^2`) is meshed as `... = 0`, as the server reads it;
//   a note says so, since the user probably forgot the right-hand side.

import { TOKEN } from './parameters.js';

export const EMPTY_MESSAGE = 'Type an equation in x, y and z, for example x^2+y^2+z^2=4, then press Enter.';

/**
 * {ok: false, message} for an equation that cannot be sent, else {ok: true, expression, notes}:
 * the text to send and what the user should know about how it was read.
 */
export function prepareEquation(text) {
  const trimmed = text.trim();
  if (trimmed === '') return { ok: false, message: EMPTY_MESSAGE };
  const notes = [];
  let expression = '';
  let last = 0;
  const capitals = new Set();
  for (const match of trimmed.matchAll(TOKEN)) {
    const name = match[1];
    if (name === undefined || !/^[xyzXYZ]+$/.test(name) || !/[XYZ]/.test(name)) continue;
    for (const c of name) if (c >= 'X' && c <= 'Z') capitals.add(c);
    expression += trimmed.slice(last, match.index) + name.toLowerCase();
    last = match.index + name.length;
  }
  expression += trimmed.slice(last);
  if (capitals.size > 0) {
    const list = [...capitals].sort();
    notes.push(`${list.join(', ')} read as the coordinate${list.length > 1 ? 's' : ''} ${list.map((c) => c.toLowerCase()).join(', ')}.`);
  }
  if (!/[=<>≤≥≠]/.test(expression)) notes.push(`No “=”: drawing ${expression} = 0.`);
  return { ok: true, expression, notes };
}
