// The parameters an equation uses, read client-side so that a new equation can be sent with a
// value for each (the server's reply then lists them with their values and the sliders follow it).
//
// Mirrors the language's lexer (core/expr/lexer.cpp): numbers come first (`2x` is 2 times x), a
// name is a letter or '_' followed by letters, digits and '_'; a name made only of x, y and z is a product of coordinates (`xy`);
// `pi`, `π`, `e`, `∞` are constants; a function is a name followed by '('.

const FUNCTIONS = new Set(
  'sin cos tan asin acos atan atan2 sinh cosh tanh exp ln log lg ld sqrt cbrt abs sgn floor ceil round min max'.split(' '),
);
const CONSTANTS = new Set(['pi', 'π', 'e', '∞', 'inf']);
// A number (skipped, so that the exponent of `1e-3` is no name) or a name.
export const TOKEN = /(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|([\p{L}_][\p{L}\p{N}_]*)/gu;

/** The parameter names of `expression`, in order of first use. */
export function parameterNames(expression) {
  const names = [];
  for (const match of expression.matchAll(TOKEN)) {
    const name = match[1];
    if (name === undefined || /^[xyz]+$/.test(name) || CONSTANTS.has(name)) continue;
    const rest = expression.slice(match.index + name.length);
    if (FUNCTIONS.has(name) && /^\s*\(/.test(rest)) continue;
    if (!names.includes(name)) names.push(name);
  }
  return names;
}

/** Values for `names`: the current ones where known, else `fallback`. */
export function valuesFor(names, current, fallback = 1) {
  return Object.fromEntries(names.map((name) => [name, current[name] ?? fallback]));
}

/**
 * The names a `bad_field` error says have no value ("parameters: no value for parameters 'a',
 * 'b'"), for names the scan above missed: the viewer then retries with a value for each.
 */
export function missingParameters(error) {
  if (error?.code !== 'bad_field') return [];
  const match = /no value for parameters? (.*)$/.exec(error.message ?? '');
  return match ? [...match[1].matchAll(/'([^']+)'/g)].map((m) => m[1]) : [];
}

const HTML_ATTRIBUTE = /^(id|class|style|title|lang|dir|hidden|slot|part|tabindex|is|role|aria-.*|data-.*|on.*)$/;

/**
 * Parameter values of an <isomesh-surface>: numeric attributes other than the element's own and
 * HTML's (`a="4"`), then the `parameters` list ("R: 2, r: 0.7" or "R=2; r=0.7"), which keeps the
 * case of names that HTML lowercases in attribute names.
 * @param {Iterable<{name, value}>} attributes
 */
export function parameterAttributes(attributes, listed, own = new Set()) {
  const values = {};
  for (const { name, value } of attributes) {
    if (own.has(name) || HTML_ATTRIBUTE.test(name) || value.trim() === '') continue;
    if (Number.isFinite(Number(value))) values[name] = Number(value);
  }
  for (const part of (listed ?? '').split(/[,;]/)) {
    const match = /^\s*([^:=\s]+)\s*[:=]\s*(\S+)\s*$/.exec(part);
    if (match && Number.isFinite(Number(match[2]))) values[match[1]] = Number(match[2]);
  }
  return values;
}
