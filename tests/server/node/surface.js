// The tests' own reading of the function language (core/expr/compile.h), to check meshes against
// the surface independently of the server: numbers, x y z, parameters, the constants pi and e,
// + - * / ^ with implicit multiplication and GeoGebra's precedence (prefix minus binds ^ but not
// *), `lhs = rhs`, and the functions of the language. Bars |x| and the real roots of x^(p/q) are
// not needed by the tests and not read. `harness.test.js` checks it against `isomesh eval`.

const FUNCTIONS = {
  sin: Math.sin, cos: Math.cos, tan: Math.tan, asin: Math.asin, acos: Math.acos, atan: Math.atan,
  arcsin: Math.asin, arccos: Math.acos, arctan: Math.atan, atan2: Math.atan2,
  sinh: Math.sinh, cosh: Math.cosh, tanh: Math.tanh, exp: Math.exp, ln: Math.log,
  log: (a, b) => (b === undefined ? Math.log(a) : Math.log(b) / Math.log(a)),
  lg: Math.log10, log10: Math.log10, ld: Math.log2, log2: Math.log2, sqrt: Math.sqrt,
  cbrt: Math.cbrt, abs: Math.abs, sgn: Math.sign, sign: Math.sign, floor: Math.floor,
  ceil: Math.ceil, round: Math.round, min: Math.min, max: Math.max,
};
const CONSTANTS = { pi: Math.PI, 'π': Math.PI, e: Math.E };
const TOKEN = /\s*(?:(\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?)|([\p{L}_][\p{L}\p{N}_]*)|(\S))/uy;

function tokenize(text) {
  const tokens = [];
  TOKEN.lastIndex = 0;
  for (let m; TOKEN.lastIndex < text.length && (m = TOKEN.exec(text));) {
    if (m[1] !== undefined) tokens.push({ number: Number(m[1]) });
    else if (m[2] !== undefined && /^[xyz]+$/.test(m[2])) for (const c of m[2]) tokens.push({ name: c });
    else if (m[2] !== undefined) tokens.push({ name: m[2] });
    else if (m[3] !== undefined) tokens.push({ op: m[3].replace('−', '-').replace(/[·⋅×]/, '*') });
  }
  return tokens;
}

/**
 * Compiles `expression` to f(x, y, z, parameters): lhs − rhs for an equation.
 * Throws on input outside the subset above.
 */
export function compileSurface(expression) {
  const tokens = tokenize(expression);
  let i = 0;
  const peek = () => tokens[i];
  const isOp = (op) => peek()?.op === op;
  const expect = (op) => {
    if (!isOp(op)) throw new Error(`expected '${op}' in ${expression}`);
    ++i;
  };
  // A token that can start an operand: implicit multiplication continues with it.
  const startsOperand = (t) => t !== undefined && (t.number !== undefined || t.name !== undefined || t.op === '(');

  function primary() {
    const t = tokens[i++];
    if (t?.number !== undefined) return () => t.number;
    if (t?.op === '(') {
      const inner = sum();
      expect(')');
      return inner;
    }
    if (t?.name === undefined) throw new Error(`unexpected ${JSON.stringify(t)} in ${expression}`);
    const name = t.name;
    if (FUNCTIONS[name] && isOp('(')) {
      ++i;
      const args = [sum()];
      while (isOp(',')) {
        ++i;
        args.push(sum());
      }
      expect(')');
      const fn = FUNCTIONS[name];
      return (x, y, z, p) => fn(...args.map((a) => a(x, y, z, p)));
    }
    if (name === 'x') return (x) => x;
    if (name === 'y') return (x, y) => y;
    if (name === 'z') return (x, y, z) => z;
    if (name in CONSTANTS) return () => CONSTANTS[name];
    return (x, y, z, p) => {
      if (!(name in p)) throw new Error(`no value for parameter ${name}`);
      return p[name];
    };
  }
  function power() {
    const base = primary();
    if (!isOp('^') && !isOp('²') && !isOp('³')) return base;
    const op = tokens[i++].op;
    const exponent = op === '²' ? () => 2 : op === '³' ? () => 3 : signed(power);
    return (x, y, z, p) => Math.pow(base(x, y, z, p), exponent(x, y, z, p));
  }
  function signed(operand) {
    if (isOp('-') || isOp('+')) {
      const negative = tokens[i++].op === '-';
      const inner = signed(operand);
      return negative ? (x, y, z, p) => -inner(x, y, z, p) : inner;
    }
    return operand();
  }
  function product() {
    let left = signed(power);
    for (;;) {
      if (isOp('*') || isOp('/')) {
        const divide = tokens[i++].op === '/';
        const right = signed(power);
        const l = left;
        left = divide ? (x, y, z, p) => l(x, y, z, p) / right(x, y, z, p) : (x, y, z, p) => l(x, y, z, p) * right(x, y, z, p);
      } else if (startsOperand(peek())) {
        const right = power();
        const l = left;
        left = (x, y, z, p) => l(x, y, z, p) * right(x, y, z, p);
      } else {
        return left;
      }
    }
  }
  function sum() {
    let left = product();
    while (isOp('+') || isOp('-')) {
      const minus = tokens[i++].op === '-';
      const right = product();
      const l = left;
      left = minus ? (x, y, z, p) => l(x, y, z, p) - right(x, y, z, p) : (x, y, z, p) => l(x, y, z, p) + right(x, y, z, p);
    }
    return left;
  }
  const lhs = sum();
  let f = lhs;
  if (isOp('=')) {
    ++i;
    const rhs = sum();
    f = (x, y, z, p) => lhs(x, y, z, p) - rhs(x, y, z, p);
  }
  if (i !== tokens.length) throw new Error(`unread input at token ${i} of ${expression}`);
  return f;
}

/** f and its gradient (forward differences: four values) at a point. */
export function valueAndGradient(f, x, y, z, parameters, h = 1e-7) {
  const value = f(x, y, z, parameters);
  const gradient = [
    (f(x + h, y, z, parameters) - value) / h,
    (f(x, y + h, z, parameters) - value) / h,
    (f(x, y, z + h, parameters) - value) / h,
  ];
  return { value, gradient };
}
