// The parameters an equation uses, read client-side so that a new equation can be sent with a
// value for each (the server's reply then lists them with their values and the sliders follow it).
//
// Mirrors the language's lexer (core/expr/lexer.cpp): a name is a letter or '_' followed by
// letters, digits and '_'; a name made only of x, y and z is a product of coordinates (`xy`);
// `pi`, `π`, `e`, `∞` are constants; a function is a name followed by '('.

const FUNCTIONS = new Set(
  'sin cos tan asin acos atan atan2 sinh cosh tanh exp ln log lg ld sqrt cbrt abs sgn floor ceil round min max'.split(' '),
);
const CONSTANTS = new Set(['pi', 'π', 'e', '∞', 'inf']);
const NAME = /[\p{L}_][\p{L}\p{N}_]*/gu;

/** The parameter names of `expression`, in order of first use. */
export function parameterNames(expression) {
  const names = [];
  for (const match of expression.matchAll(NAME)) {
    const name = match[0];
    const rest = expression.slice(match.index + name.length);
    if (/^[xyz]+$/.test(name) || CONSTANTS.has(name)) continue;
    if (FUNCTIONS.has(name) && /^\s*\(/.test(rest)) continue;
    if (/^\p{N}/u.test(name)) continue;
    if (!names.includes(name)) names.push(name);
  }
  return names;
}

/** Values for `names`: the current ones where known, else `fallback`. */
export function valuesFor(names, current, fallback = 1) {
  return Object.fromEntries(names.map((name) => [name, current[name] ?? fallback]));
}
