// The viewer's state in the page's query string, so that a reload, a shared link or a bookmark
// shows the same scene. Pure: no DOM.
//
//   eq=EQUATION           one per surface, in the object list's order (legacy: expr=EQUATION)
//   color=3d7fd6,d9553d   the surfaces' colours, in the same order
//   hidden=2,3            the surfaces (1-based) that are hidden
//   p=a:4                 one per parameter: name:value, or name:value:min:max:step
//   box=x0,x1,y0,y1,z0,z1 budget=N  maxerror=E  measure=distance|epsilon4|max_distance
//   cam=px,py,pz,tx,ty,tz the camera's position and the point it looks at
//   colormode=uniform|height|normal  show=axes,grid,box (what is drawn)  wire=1
//
// Decoding checks every value and drops what does not parse (a hand-edited link never breaks
// the page); `server` and unknown keys are left alone.

export const MAX_SURFACES = 16;
export const COLOR_MODES = ['uniform', 'height', 'normal'];
export const DEFAULT_SHOW = ['axes', 'grid', 'box'];
const MEASURES = ['distance', 'epsilon4', 'max_distance'];
const STATE_KEYS = ['eq', 'expr', 'color', 'hidden', 'p', 'box', 'budget', 'maxerror', 'measure', 'cam', 'colormode', 'show', 'wire'];
const MAX_EXPRESSION_CHARS = 65536;

/** Numbers as short as they can be without losing what the user sees (6 significant digits). */
function short(x) {
  return String(Number(x.toPrecision(6)));
}

function numbers(text, count) {
  const values = (text ?? '').split(',').map((t) => (t.trim() === '' ? NaN : Number(t)));
  return values.length === count && values.every(Number.isFinite) ? values : null;
}

export function validBox(box) {
  return Array.isArray(box) && box.length === 6 && box.every(Number.isFinite) && box[0] < box[1] && box[2] < box[3] && box[4] < box[5];
}

/**
 * The query string (without '?') for `state`:
 * {surfaces: [{expression, color, visible}], parameters: {name: value},
 *  sliders: {name: {min, max, step}}, box, constraints: {triangles, max_error, error_measure},
 *  camera: {position, target}, display: {colorMode, show: [...], wireframe}}.
 * `keep` (a URLSearchParams) contributes its non-state keys first (e.g. `server`).
 */
export function encodeState(state, keep = new URLSearchParams()) {
  const query = new URLSearchParams();
  for (const [key, value] of keep) if (!STATE_KEYS.includes(key)) query.append(key, value);
  const surfaces = state.surfaces ?? [];
  for (const s of surfaces) query.append('eq', s.expression);
  if (surfaces.length > 0) query.set('color', surfaces.map((s) => s.color.replace('#', '')).join(','));
  const hidden = surfaces.flatMap((s, i) => (s.visible === false ? [i + 1] : []));
  if (hidden.length > 0) query.set('hidden', hidden.join(','));
  for (const [name, value] of Object.entries(state.parameters ?? {})) {
    const range = state.sliders?.[name];
    const fields = [name, short(value)];
    if (range) fields.push(short(range.min), short(range.max), short(range.step));
    query.append('p', fields.join(':'));
  }
  if (validBox(state.box)) query.set('box', state.box.map(short).join(','));
  const c = state.constraints ?? {};
  if (Number.isInteger(c.triangles)) query.set('budget', String(c.triangles));
  if (Number.isFinite(c.max_error) && c.max_error > 0) query.set('maxerror', short(c.max_error));
  if (c.error_measure && c.error_measure !== 'distance') query.set('measure', c.error_measure);
  const cam = state.camera;
  if (cam) query.set('cam', [...cam.position, ...cam.target].map((x) => String(Math.round(x * 1000) / 1000)).join(','));
  const d = state.display ?? {};
  if (d.colorMode && d.colorMode !== 'uniform') query.set('colormode', d.colorMode);
  if (d.show && [...d.show].sort().join(',') !== [...DEFAULT_SHOW].sort().join(',')) query.set('show', d.show.join(',') || 'none');
  if (d.wireframe) query.set('wire', '1');
  return query.toString();
}

/** The state a query string describes (only the parts it gives), or null when it gives none. */
export function decodeState(search) {
  const query = new URLSearchParams(search);
  if (!STATE_KEYS.some((key) => query.has(key))) return null;
  const state = {};
  const expressions = [...query.getAll('eq'), ...query.getAll('expr')]
    .filter((e) => e.length <= MAX_EXPRESSION_CHARS)
    .slice(0, MAX_SURFACES);
  if (expressions.length > 0) {
    const colors = (query.get('color') ?? '').split(',');
    const hidden = new Set((query.get('hidden') ?? '').split(',').map(Number));
    state.surfaces = expressions.map((expression, i) => ({
      expression,
      color: /^[0-9a-fA-F]{6}$/.test(colors[i] ?? '') ? `#${colors[i].toLowerCase()}` : null,
      visible: !hidden.has(i + 1),
    }));
  }
  const parameters = {};
  const sliders = {};
  for (const entry of query.getAll('p')) {
    const [name, ...rest] = entry.split(':');
    const values = rest.map(Number);
    if (name === '' || !values.every(Number.isFinite) || (values.length !== 1 && values.length !== 4)) continue;
    parameters[name] = values[0];
    const [min, max, step] = values.slice(1);
    if (values.length === 4 && min < max && step > 0) sliders[name] = { min, max, step };
  }
  if (Object.keys(parameters).length > 0) state.parameters = parameters;
  if (Object.keys(sliders).length > 0) state.sliders = sliders;
  const box = numbers(query.get('box'), 6);
  if (validBox(box)) state.box = box;
  const constraints = {};
  const budget = Number(query.get('budget'));
  if (query.has('budget') && Number.isInteger(budget) && budget >= 1) constraints.triangles = budget;
  const maxError = Number(query.get('maxerror'));
  if (query.has('maxerror') && Number.isFinite(maxError) && maxError >= 0) constraints.max_error = maxError;
  if (MEASURES.includes(query.get('measure'))) constraints.error_measure = query.get('measure');
  if (Object.keys(constraints).length > 0) state.constraints = constraints;
  const cam = numbers(query.get('cam'), 6);
  if (cam) state.camera = { position: cam.slice(0, 3), target: cam.slice(3) };
  const display = {};
  if (COLOR_MODES.includes(query.get('colormode'))) display.colorMode = query.get('colormode');
  if (query.has('show')) display.show = query.get('show').split(',').filter((s) => DEFAULT_SHOW.includes(s));
  if (query.has('wire')) display.wireframe = query.get('wire') === '1';
  if (Object.keys(display).length > 0) state.display = display;
  return state;
}
