// Browser test of the viewer as a GeoGebra 3D or Desmos 3D user meets it (issue 13): Debian's
// chromium loads the viewer from a real isomesh-server; the test types equations, drags sliders
// with the mouse and the keys, edits a slider's range and animates it, reloads and opens the link
// elsewhere, shows two surfaces at once, exports every format (the .glb checked by Khronos's
// glTF validator), meets every message a silent outcome used to hide, and says what the server
// found out about a shape (PROTOCOL.md 3.4: being found, no surface, a region, a budget below
// what the shape needs, not proven everywhere). Screenshots go to build/test-artifacts/web/.

import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { test } from 'node:test';

import validator from 'gltf-validator';
import { PNG } from 'pngjs';

import { ARTIFACTS, WAIT_MS, boxCornersOnScreen, canvasShot, convergedOn, snapshot, statusTriangles, typeEquation, viewerForTests, waitForSnapshot } from './browser.js';
import { coloredFraction, differingFraction } from './pixels.js';

let page;
const viewer = viewerForTests('viewer', { relay: true }, (v) => (page = v.page));

const slider = (name) => page.getByRole('slider', { name, exact: true });
const button = (name) => page.getByRole('button', { name, exact: true });

/** The displayed count is the count of the triangles the viewer holds, whatever the budget. */
async function assertCountIsTheTruth() {
  const shown = await statusTriangles(page);
  const held = await page.evaluate(() => window.isomesh.meshSignature().triangles);
  assert.equal(shown, held, 'the status line shows the triangles held');
  return held;
}

let sphere; // the screenshot and snapshot of x^2+y^2+z^2=a at a = 1

test('the viewer loads from the server and shows its first example', async () => {
  await page.goto(viewer.server.url);
  const s = await waitForSnapshot(page, convergedOn);
  assert.ok(s.triangles > 0, 'a mesh is shown');
  assert.ok(s.firstMeshMs > 0, 'time to first mesh is measured');
  assert.ok(s.bytesReceived > 0);
  assert.match(await page.getByRole('status').textContent(), /^\d+ triangles · .* received · first mesh .* converged$/);
  assert.equal(await assertCountIsTheTruth(), s.triangles);
  await canvasShot(page, '0-first-example');
});

test('typing an equation with a parameter meshes it and makes a slider named after it', async () => {
  await typeEquation(page, 'x^2+y^2+z^2=a');
  const s = await waitForSnapshot(page, convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: 1 } });
  assert.ok(s.triangles > 100, `${s.triangles} triangles`);
  assert.equal(await slider('a').count(), 1, 'an input[type=range] named "a"');
  assert.equal(await slider('a').evaluate((e) => e.type), 'range');
  assert.equal(await page.locator('.equation-error:not([hidden])').count(), 0, 'no error is shown');
  const png = await canvasShot(page, '1-sphere');
  const pixels = coloredFraction(png);
  assert.ok(pixels.fraction > 0.01, `the canvas shows a surface (${(100 * pixels.fraction).toFixed(2)}% colored pixels)`);
  sphere = { pixels, snapshot: s, signature: await page.evaluate(() => window.isomesh.meshSignature()) };
});

test('a mouse drag of the slider moves the surface at every step the server can follow', async (t) => {
  const before = await snapshot(page);
  const shownBefore = before.surfaces[0].versionsShown;
  await page.evaluate(() => {
    window.inputEvents = 0;
    document.querySelector('input[type=range][aria-label="a"]').addEventListener('input', () => ++window.inputEvents);
  });
  const box = await slider('a').boundingBox();
  const x = (value) => box.x + 8 + ((value + 5) / 10) * (box.width - 16); // the thumb is 16 px wide
  const y = box.y + box.height / 2;
  const steps = 30;
  const [gpuBefore] = await page.evaluate(() => window.isomesh.geometryStats());
  await page.mouse.move(x(1), y);
  await page.mouse.down();
  for (let i = 1; i <= steps; ++i) {
    await page.mouse.move(x(1 + (3 * i) / steps), y);
    await page.waitForTimeout(40); // a hand moves about this fast
  }
  await page.mouse.up();
  const [gpuAfter] = await page.evaluate(() => window.isomesh.geometryStats());
  const focused = await page.evaluate(() => document.activeElement?.getAttribute('aria-label'));
  const inputs = await page.evaluate(() => window.inputEvents);
  const value = Number(await slider('a').inputValue());
  const s = await waitForSnapshot(page, convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: value } });
  const moves = s.surfaces[0].versionsShown - shownBefore;
  t.diagnostic(`${steps}-step drag: ${inputs} input events, the surface moved ${moves} times, a = ${value}`);
  assert.ok(inputs >= 20, `${inputs} input events from a ${steps}-step drag`);
  assert.ok(Math.abs(value - 4) < 0.25, `the thumb followed the mouse to a = ${value}`);
  assert.ok(moves >= 10, `the surface moved ${moves} times during the drag (journal: ${JSON.stringify(await page.evaluate(() => window.isomesh.journal()[0].slice(-40)))})`);
  // The moved vertices are written into the GPU buffers in place (protocol version 2 moves): no
  // buffer made anew while the slider moved the surface.
  t.diagnostic(`GPU buffers during the drag: ${gpuAfter.rebinds - gpuBefore.rebinds} made anew, ${gpuAfter.rangeFloats - gpuBefore.rangeFloats} floats updated in place`);
  assert.equal(gpuAfter.rebinds, gpuBefore.rebinds, 'no GPU buffer made anew during the drag');
  assert.ok(gpuAfter.rangeFloats > gpuBefore.rangeFloats, 'the moves were uploaded in place');
  assert.equal(focused, 'a', 'the slider keeps the focus after the server answers');
  assert.equal(await page.getByRole('spinbutton', { name: 'Value of a' }).inputValue(), String(value));
  const png = await canvasShot(page, '2-sphere-dragged');
  const pixels = coloredFraction(png);
  assert.ok(pixels.fraction > 1.8 * sphere.pixels.fraction, `radius 2 covers more: ${(100 * pixels.fraction).toFixed(2)}% vs ${(100 * sphere.pixels.fraction).toFixed(2)}%`);
  assert.notDeepEqual(await page.evaluate(() => window.isomesh.meshSignature()), sphere.signature);
  await assertCountIsTheTruth();
});

test('arrow keys step the slider, and the focus stays on it while the surface follows', async () => {
  await slider('a').focus();
  const start = Number(await slider('a').inputValue());
  const before = (await snapshot(page)).surfaces[0].versionsShown;
  for (let i = 0; i < 5; ++i) {
    await page.keyboard.press('ArrowRight');
    await page.waitForTimeout(60);
  }
  const expected = Number((start + 0.5).toFixed(6));
  const s = await waitForSnapshot(page, convergedOn, { parameters: { a: expected } });
  assert.equal(Number(await slider('a').inputValue()), expected, '5 presses, 5 steps of 0.1');
  assert.ok(s.surfaces[0].versionsShown - before >= 3, `the surface moved ${s.surfaces[0].versionsShown - before} times`);
  assert.equal(await page.evaluate(() => document.activeElement?.getAttribute('aria-label')), 'a');
});

test("a slider's min, max and step are editable, and play animates it", async () => {
  await button('Range of a').click();
  const max = page.getByRole('spinbutton', { name: 'max of a', exact: true });
  await max.fill('8');
  await max.press('Tab');
  assert.equal(await slider('a').getAttribute('max'), '8');
  const step = page.getByRole('spinbutton', { name: 'step of a', exact: true });
  await step.fill('0.5');
  await step.press('Tab');
  assert.equal(await slider('a').getAttribute('step'), '0.5');
  await button('Range of a').click();

  const before = await snapshot(page);
  await button('Animate a').click();
  assert.equal(await button('Animate a').getAttribute('aria-pressed'), 'true');
  await page.waitForTimeout(1500);
  await button('Animate a').click();
  const s = await waitForSnapshot(page, convergedOn);
  // The values the server was sent since the animation started (the journal's `state v<version>
  // {parameters}` lines). The sweep goes back and forth, so the last value may be the first one.
  const values = await page.evaluate(
    (version) =>
      window.isomesh
        .journal()[0]
        .map((e) => /^state v(\d+) (.*)$/.exec(e))
        .filter((m) => m && Number(m[1]) > version)
        .map((m) => JSON.parse(m[2]).a),
    before.surfaces[0].version,
  );
  assert.ok(s.surfaces[0].versionsShown - before.surfaces[0].versionsShown >= 3, `the animation moved the surface: ${JSON.stringify(values)}`);
  assert.ok(new Set(values).size >= 3, `the animation sent several values: ${JSON.stringify(values)}`);
  assert.ok(values.every((a) => a >= -5 && a <= 8 && Math.round(a / 0.5) * 0.5 === a), `on the 0.5 grid within [-5, 8]: ${JSON.stringify(values)}`);
  assert.equal(values.at(-1), s.parameters.a, 'the surface stops at the last value sent');
  await page.waitForTimeout(300);
  assert.equal((await snapshot(page)).parameters.a, s.parameters.a, 'stopped: the value stays');
  // Back to a known value for what follows.
  const value = page.getByRole('spinbutton', { name: 'Value of a' });
  await value.fill('4');
  await value.press('Enter');
  await waitForSnapshot(page, convergedOn, { parameters: { a: 4 } });
});

test('reload, a second tab and a copied link restore the equation, parameters, box and camera', async () => {
  await page.waitForTimeout(400); // the URL is written 250 ms after the last change
  const url = new URL(page.url());
  assert.deepEqual(url.searchParams.getAll('eq'), ['x^2+y^2+z^2=a']);
  assert.ok(url.searchParams.getAll('p').some((p) => p.startsWith('a:4')), url.search);
  const camera = await page.evaluate(() => window.isomesh.viewer.getCamera());

  await page.reload();
  let s = await waitForSnapshot(page, convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: 4 } });
  assert.equal(await page.getByRole('textbox', { name: 'Equation', exact: true }).inputValue(), 'x^2+y^2+z^2=a');
  assert.equal(Number(await slider('a').inputValue()), 4);
  assert.equal(await slider('a').getAttribute('max'), '8', 'the slider keeps its range');
  const restored = await page.evaluate(() => window.isomesh.viewer.getCamera());
  for (let i = 0; i < 3; ++i) assert.ok(Math.abs(restored.position[i] - camera.position[i]) < 0.01, 'the camera is back');

  const tab = await viewer.context.newPage();
  await tab.goto(viewer.server.url); // no query: the last scene of this browser
  s = await waitForSnapshot(tab, convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: 4 } });
  await tab.close();

  await viewer.context.grantPermissions(['clipboard-read', 'clipboard-write'], { origin: viewer.server.url.replace(/\/$/, '') });
  await button('Copy link').click();
  await page.getByText('Link copied').waitFor();
  const copied = await page.evaluate(() => navigator.clipboard.readText());
  assert.equal(copied, page.url());
  const other = await viewer.context.newPage();
  await other.goto(copied);
  s = await waitForSnapshot(other, convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: 4 } });
  assert.deepEqual(s.box, [-3, 3, -3, 3, -3, 3]);
  await other.close();
});

test('two surfaces at once: an object list with colour, visibility and delete, one slider per parameter', async () => {
  await button('Add surface').click();
  assert.equal(await page.getByRole('textbox', { name: 'Equation', exact: true }).count(), 2);
  assert.equal(await page.evaluate(() => document.activeElement?.getAttribute('aria-label')), 'Equation', 'the new row has the cursor');
  await typeEquation(page, '(x-2)^2+y^2+z^2=a/4', 1);
  const s = await waitForSnapshot(page, `(s) => s.status === 'converged' && s.surfaces.length === 2 && s.surfaces.every((f) => f.triangles > 0)`);
  assert.equal(await page.getByRole('slider').count(), 1, 'a is one slider for both surfaces');
  assert.notEqual(s.surfaces[0].color, s.surfaces[1].color);
  assert.notEqual(s.surfaces[0].session, s.surfaces[1].session, 'a session each');
  assert.equal(s.triangles, s.surfaces[0].triangles + s.surfaces[1].triangles);
  assert.equal(await assertCountIsTheTruth(), s.triangles);
  const both = await canvasShot(page, '3-two-surfaces');

  await button('Show surface 2').click();
  await page.waitForTimeout(200);
  const one = await canvasShot(page, '3-second-hidden');
  assert.ok(differingFraction(both, one) > 0.005, 'hiding the second surface changes the picture');
  assert.equal(await button('Show surface 2').getAttribute('aria-pressed'), 'false');
  await button('Show surface 2').click();

  await page.getByLabel('Colour of surface 2').evaluate((input) => {
    input.value = '#2e9e44';
    input.dispatchEvent(new Event('input', { bubbles: true }));
  });
  await page.waitForTimeout(200);
  const green = coloredFraction(await canvasShot(page, '3-second-green'));
  assert.ok(green.mean[1] > green.mean[2] * 0.8 || green.mean[1] > 110, `green shows: mean ${green.mean}`);

  // Moving a moves both surfaces.
  const value = page.getByRole('spinbutton', { name: 'Value of a' });
  await value.fill('2');
  await value.press('Enter');
  const moved = await waitForSnapshot(page, convergedOn, { parameters: { a: 2 } });
  assert.ok(moved.surfaces.every((f) => f.parameters.a === 2), 'both sessions got a = 2');
});

/** The JSON chunk of a GLB (glTF 2.0 binary container). */
function glbJson(bytes) {
  assert.equal(bytes.subarray(0, 4).toString('latin1'), 'glTF');
  assert.equal(bytes.readUInt32LE(4), 2, 'GLB version');
  assert.equal(bytes.readUInt32LE(8), bytes.length, 'GLB length');
  const length = bytes.readUInt32LE(12);
  assert.equal(bytes.subarray(16, 20).toString('latin1'), 'JSON');
  return JSON.parse(bytes.subarray(20, 20 + length).toString('utf8'));
}

async function download(format) {
  await button('Export').click();
  const [file] = await Promise.all([page.waitForEvent('download'), page.getByRole('menuitem').filter({ hasText: format }).click()]);
  return { name: file.suggestedFilename(), bytes: readFileSync(await file.path()) };
}

test('export: .glb (valid glTF), .stl, .obj and a PNG of what is shown', async () => {
  const s = await waitForSnapshot(page, convergedOn);
  const triangles = s.surfaces.filter((f) => f.visible).reduce((n, f) => n + f.triangles, 0);

  const glb = await download('.glb');
  assert.equal(glb.name, 'isomesh.glb');
  const report = await validator.validateBytes(new Uint8Array(glb.bytes));
  const errors = report.issues.messages.filter((m) => m.severity === 0);
  assert.equal(report.issues.numErrors, 0, JSON.stringify(errors.slice(0, 5), null, 1));
  const gltf = glbJson(glb.bytes);
  assert.equal(gltf.meshes.length, 2, 'one mesh per surface');
  const indexed = gltf.meshes.flatMap((m) => m.primitives).reduce((n, p) => n + gltf.accessors[p.indices].count / 3, 0);
  assert.equal(indexed, triangles, 'the glb holds the triangles shown');
  assert.equal(report.info.totalTriangleCount, triangles, "the validator's count");

  const stl = await download('.stl');
  const count = stl.bytes.readUInt32LE(80);
  assert.equal(count, triangles, 'STL triangle count');
  assert.equal(stl.bytes.length, 84 + 50 * count, 'binary STL size');
  for (let t = 0; t < count; t += Math.ceil(count / 200)) {
    for (let k = 3; k < 12; ++k) assert.ok(Number.isFinite(stl.bytes.readFloatLE(84 + 50 * t + 4 * k)));
  }

  const obj = (await download('.obj')).bytes.toString('utf8');
  const lines = obj.split('\n');
  const vertices = lines.filter((l) => l.startsWith('v ')).length;
  const faces = lines.filter((l) => l.startsWith('f '));
  assert.equal(faces.length, triangles, 'OBJ faces');
  assert.equal(lines.filter((l) => l.startsWith('o ')).length, 2, 'one object per surface');
  for (const face of faces) {
    for (const corner of face.slice(2).split(' ')) {
      const v = Number(corner.split('/')[0]);
      assert.ok(Number.isInteger(v) && v >= 1 && v <= vertices, `vertex ${corner} of ${vertices}`);
    }
  }

  const png = await download('.png');
  const image = PNG.sync.read(png.bytes);
  const canvas = await page.locator('#canvas-host canvas').evaluate((c) => [c.width, c.height]);
  assert.deepEqual([image.width, image.height], canvas);
  assert.ok(coloredFraction(png.bytes).fraction > 0.01, 'the PNG shows the surfaces');
  await page.getByText(/Saved isomesh\.png/).waitFor();
});

test('axes with ticks and labels, a grid on the xy-plane, and colouring by height or normal', async () => {
  await button('Delete surface 2').click();
  await waitForSnapshot(page, `(s) => s.surfaces.length === 1 && s.status === 'converged'`);
  const shown = await canvasShot(page, '4-axes-grid');
  await page.getByLabel('Grid (xy-plane)').uncheck();
  await page.waitForTimeout(150);
  const noGrid = await canvasShot(page, '4-no-grid');
  assert.ok(differingFraction(shown, noGrid) > 0.002, 'the grid shows');
  await page.getByLabel('Axes').uncheck();
  await page.waitForTimeout(150);
  const noAxes = await canvasShot(page, '4-no-axes');
  assert.ok(differingFraction(noGrid, noAxes) > 0.001, 'the axes and their labels show');
  await page.getByLabel('Axes').check();
  await page.getByLabel('Grid (xy-plane)').check();

  const uniform = coloredFraction(shown).mean;
  await page.getByLabel('Colouring', { exact: true }).selectOption('height');
  await page.waitForTimeout(150);
  const height = coloredFraction(await canvasShot(page, '5-colour-height')).mean;
  await page.getByLabel('Colouring', { exact: true }).selectOption('normal');
  await page.waitForTimeout(150);
  const normal = coloredFraction(await canvasShot(page, '5-colour-normal')).mean;
  const distance = (p, q) => Math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
  assert.ok(distance(uniform, height) > 20, `height colours differ: ${uniform} vs ${height}`);
  assert.ok(distance(uniform, normal) > 20 && distance(height, normal) > 10, `normal colours differ: ${normal}`);
  await page.getByLabel('Colouring', { exact: true }).selectOption('uniform');
});

test('an open surface is one colour on both sides (no orange inside)', async () => {
  await typeEquation(page, 'z=tan(x)');
  await waitForSnapshot(page, convergedOn, { expression: 'z=tan(x)' });
  const { mean } = coloredFraction(await canvasShot(page, '6-tan'));
  assert.ok(mean[2] > mean[0], `blue both sides: mean colour ${mean}`);
});

/** Types `text` in row 1 and waits until the row says `message` (a note or an error). */
async function expectMessage(text, pattern) {
  await typeEquation(page, text);
  const s = await waitForSnapshot(
    page,
    `(s, arg) => { const f = s.surfaces[0]; return [...f.notes, f.message ?? ''].some((m) => new RegExp(arg).test(m)); }`,
    pattern.source,
  );
  return s;
}

test('every silent case says what happened', async () => {
  const kept = await snapshot(page);
  await expectMessage('', /Type an equation/);
  assert.equal((await snapshot(page)).triangles, kept.triangles, 'an empty Enter keeps the surface');
  await canvasShot(page, '7-empty-enter');

  let s = await expectMessage('1/x=0', /No surface in the view box/);
  assert.equal(s.surfaces[0].triangles, 0);
  assert.equal(s.surfaces[0].outcome?.outcome, 'no_surface', "the server's answer: a pole, not a root");
  s = await expectMessage('x^2+y^2+z^2', /No “=”: drawing x\^2\+y\^2\+z\^2 = 0/);
  await canvasShot(page, '7-no-equals');

  s = await expectMessage('X^2+Y^2+Z^2=4', /X, Y, Z read as the coordinates x, y, z/);
  assert.equal(await page.getByRole('textbox', { name: 'Equation', exact: true }).inputValue(), 'x^2+y^2+z^2=4');
  s = await waitForSnapshot(page, convergedOn, { expression: 'x^2+y^2+z^2=4' });
  assert.ok(s.triangles > 0);
  assert.equal(await page.getByRole('slider').count(), 0, 'no sliders X, Y, Z');

  const xmin = page.getByRole('spinbutton', { name: 'x min' });
  await xmin.fill('5');
  await xmin.press('Tab');
  await page.locator('#box-error:not([hidden])').waitFor();
  assert.match(await page.locator('#box-error').textContent(), /x min \(5\) must be less than x max \(3\)/);
  await page.waitForTimeout(300);
  assert.deepEqual((await snapshot(page)).box, [-3, 3, -3, 3, -3, 3], 'the previous box stays');
  await canvasShot(page, '7-invalid-box');
  await xmin.fill('-3');
  await xmin.press('Tab');
  assert.equal(await page.locator('#box-error').isHidden(), true);
});

test('a bad equation shows the error under the input with its column marked, and keeps the surface', async () => {
  const before = await snapshot(page);
  const bad = 'x^2+(y+z^2=1';
  await typeEquation(page, bad);
  await page.waitForSelector('.equation-error:not([hidden])', { timeout: WAIT_MS });
  const s = await snapshot(page);
  assert.equal(s.error?.code, 'bad_expression');
  assert.ok(Number.isInteger(s.error.column) && s.error.column >= 1 && s.error.column <= bad.length + 1, `column ${s.error.column}`);
  const marked = await page.$eval('.equation-error .marked', (code) => {
    const mark = code.querySelector('mark');
    return { before: mark?.previousSibling?.textContent ?? '', mark: mark?.textContent ?? null };
  });
  assert.notEqual(marked.mark, null, 'a character is marked');
  assert.equal(Array.from(marked.before).length, s.error.column - 1, 'the mark sits at the column');
  assert.equal(s.triangles, before.triangles, 'the previous surface stays');
  await canvasShot(page, '8-bad-equation');
  await typeEquation(page, 'x^2+(y+z)^2=1');
  await waitForSnapshot(page, convergedOn, { expression: 'x^2+(y+z)^2=1' });
  assert.equal(await page.locator('.equation-error:not([hidden])').count(), 0);
});

test('? opens the keyboard help; shortcuts act outside text fields', async () => {
  await page.locator('#canvas-host canvas').click({ position: { x: 5, y: 5 } });
  await page.keyboard.press('?');
  const help = page.getByRole('dialog');
  await help.waitFor();
  assert.match(await help.textContent(), /Reset the view/);
  await page.screenshot({ path: `${ARTIFACTS}/9-help-page.png` });
  await page.keyboard.press('Escape');
  await help.waitFor({ state: 'hidden' });
  await page.keyboard.press('w');
  assert.equal(await page.getByLabel('Wireframe').isChecked(), true);
  await page.keyboard.press('w');
  assert.equal(await page.getByLabel('Wireframe').isChecked(), false);
});

test('a gallery example brings its own sliders and box; the wireframe shows over it', async () => {
  await page.getByRole('combobox', { name: 'Examples' }).selectOption({ label: 'Torus' });
  const s = await waitForSnapshot(page, convergedOn, { expression: '(sqrt(x^2+y^2)-R)^2+z^2=r^2', parameters: { R: 2, r: 0.7 } });
  assert.deepEqual(Object.keys(s.parameters).sort(), ['R', 'r']);
  assert.deepEqual(s.box, [-3.2, 3.2, -3.2, 3.2, -1.2, 1.2]);
  assert.deepEqual(s.surfaces[0].box, s.box, 'the session meshes the example box');
  assert.deepEqual((await page.getByRole('slider').evaluateAll((all) => all.map((e) => e.getAttribute('aria-label')))).sort(), ['R', 'r']);
  assert.equal(await page.getByRole('textbox', { name: 'Equation', exact: true }).inputValue(), '(sqrt(x^2+y^2)-R)^2+z^2=r^2');
  const shaded = await canvasShot(page, '10-torus');
  assert.ok(coloredFraction(shaded).fraction > 0.01);
  await page.getByLabel('Wireframe').check();
  await page.waitForTimeout(300);
  const wire = await canvasShot(page, '10-torus-wireframe');
  const changed = differingFraction(shaded, wire);
  assert.ok(changed > 0.002, `the wireframe shows (${(100 * changed).toFixed(2)}% of pixels changed)`);
  await page.getByLabel('Wireframe').uncheck();
});

const budgetField = () => page.getByRole('spinbutton', { name: 'Max triangles' });

async function setBudget(triangles) {
  await budgetField().fill(String(triangles));
  await budgetField().press('Tab');
}

async function setBox(box) {
  const names = ['x min', 'x max', 'y min', 'y max', 'z min', 'z max'];
  for (let i = 0; i < 6; ++i) {
    await page.getByRole('spinbutton', { name: names[i], exact: true }).fill(String(box[i]));
    await page.getByRole('spinbutton', { name: names[i], exact: true }).press('Tab');
  }
}

const rowProgress = () => page.locator('.object .progress').first().textContent();

test('budget 100: exactly 100 triangles for a torus, and the status line and the row show the triangles held', async () => {
  await setBudget(100);
  const s = await waitForSnapshot(page, `(s) => s.status === 'converged' && s.constraints?.triangles === 100`);
  const held = await assertCountIsTheTruth();
  assert.equal(held, s.triangles);
  assert.ok(held >= 99 && held <= 100, `the budget is met within one: ${held} triangles`);
  assert.equal(s.surfaces[0].outcome.budgetUnreachable, false);
  assert.equal(s.surfaces[0].outcome.triangles, held, "the server's count is the count held");
  assert.match(await rowProgress(), new RegExp(`^${held} triangles$`), 'the row says the same');
  assert.deepEqual(s.surfaces[0].notes, [], 'nothing else to say');
  await canvasShot(page, '11-budget-100');
});

/** Types `text` in row 1 and waits until the server's `outcome` for it shows with a note matching `pattern`. */
async function expectOutcome(text, outcome, pattern) {
  await typeEquation(page, text);
  return waitForSnapshot(
    page,
    `(s, [text, outcome, pattern]) => { const f = s.surfaces[0]; return s.expression === text && f.outcome?.outcome === outcome && f.notes.some((m) => new RegExp(pattern).test(m)); }`,
    [text, outcome, pattern.source],
  );
}

test("what the server found: no surface in the box, a region that is not a surface", async () => {
  let s = await expectOutcome('x^2+y^2+z^2=-1', 'no_surface', /^No surface in the view box: the equation has no solution there/);
  assert.equal(s.surfaces[0].triangles, 0, 'a negative radius² has no sphere');
  await canvasShot(page, '12-no-surface');
  s = await expectOutcome('floor(x)=0', 'region_not_surface', /^Not a surface: the equation holds on a whole region of the view box/);
  assert.equal(s.surfaces[0].triangles, 0);
  assert.equal(s.surfaces[0].notes.length, 1, 'one message, not the no-surface one too');
  await canvasShot(page, '12-region');
  s = await expectOutcome('x=x', 'region_not_surface', /^Not a surface/);
});

test('a budget below what the shape needs: "finding the shape…" while the server resolves it, then the count it needs, held and shown', async () => {
  // The gyroid on ±7 needs about 300 triangles for its topology. A new session (a new row) shows
  // its first mesh at once while the server resolves the topology, saying so in the `progress`
  // that follows that keyframe (an update finds the new shape aside and sends it whole). The server's messages
  // after its first `progress` that says so wait until the row has been seen saying so: a busy
  // browser may otherwise apply the first mesh only once the topology is resolved.
  const direction = () => page.evaluate(() => {
    const { position, target } = window.isomesh.viewer.getCamera();
    const d = position.map((p, i) => p - target[i]);
    const length = Math.hypot(...d);
    return d.map((c) => c / length);
  });
  const lookingFrom = await direction();
  await setBox([-7, 7, -7, 7, -7, 7]);
  await waitForSnapshot(page, `(s) => s.box?.[1] === 7 && s.box[5] === 7`);
  const corners = await boxCornersOnScreen(page);
  assert.ok(corners.every(([x, y]) => Math.abs(x) <= 1 && Math.abs(y) <= 1), `the camera shows the whole new box: ${JSON.stringify(corners)}`);
  (await direction()).forEach((c, i) => assert.ok(Math.abs(c - lookingFrom[i]) < 1e-6, 'from the side the user looked from'));
  await button('Add surface').click();
  await page.evaluate(() => {
    window.progressTexts = [];
    const text = document.querySelectorAll('.object .progress .text')[1];
    new MutationObserver(() => window.progressTexts.push(text.textContent)).observe(text, { childList: true, characterData: true, subtree: true });
  });
  const gyroid = 'sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=0';
  viewer.messages.holdAfter((m) => m?.type === 'progress' && m.resolving);
  await typeEquation(page, gyroid, 1);
  try {
    await page.waitForFunction(() => /^finding the shape… · \d+ triangles$/.test(document.querySelectorAll('.object .progress')[1]?.textContent ?? ''), null, { timeout: 60000, polling: 50 });
  } finally {
    viewer.messages.release();
  }
  // The rows are redrawn at the next animation frame: the outcome may be in the snapshot a frame
  // before the row's note.
  const s = await waitForSnapshot(page, `(s, arg) => s.status === 'converged' && s.surfaces[1]?.expression === arg && s.surfaces[1].outcome?.budgetUnreachable && s.surfaces[1].notes.length > 0`, gyroid);
  const held = await assertCountIsTheTruth();
  const f = s.surfaces[1];
  assert.equal(s.surfaces[0].triangles, 0, 'row 1 (x=x) holds none');
  assert.equal(f.triangles, held);
  assert.equal(f.outcome.triangles, held, "the server's fewest is the count held");
  assert.ok(held > 100, `${held} triangles: more than the budget, as the shape needs`);
  assert.deepEqual(f.notes, [`This shape needs at least ${held} triangles (for all its pieces and holes), more than the maximum of 100: it is shown with ${held}.`]);
  assert.match(await page.locator('.object .progress').nth(1).textContent(), new RegExp(`^${held} triangles$`));
  const texts = await page.evaluate(() => window.progressTexts);
  const progress = await page.evaluate(() => window.isomesh.journal()[1].filter((e) => e.startsWith('progress')));
  assert.ok(progress.some((e) => e.endsWith('resolving')), `the server said it was resolving: ${JSON.stringify(progress)}`);
  assert.ok(texts.some((t) => /^finding the shape… · \d+ triangles$/.test(t)), `the row said so: ${JSON.stringify(texts)}`);
  await canvasShot(page, '13-budget-unreachable');
  await button('Delete surface 2').click();
});

test('a shape not proven everywhere (the tip of a cone off the grid) is marked, quietly', async () => {
  await setBudget(2000);
  await setBox([-3, 3, -3, 3, -3, 3]);
  const cone = '(x-0.123)^2+(y-0.0377)^2=(z-0.219)^2';
  await typeEquation(page, cone);
  const s = await waitForSnapshot(page, convergedOn, { expression: cone });
  const f = s.surfaces[0];
  assert.equal(f.outcome.certified, false);
  assert.ok(f.outcome.unresolvedCells > 0, `${f.outcome.unresolvedCells} cells without proof`);
  const mark = page.locator('.object .progress .uncertain').first();
  assert.equal(await mark.textContent(), ' · approximate in places');
  assert.match(await mark.getAttribute('title'), /tip of a cone/);
  assert.deepEqual(f.notes, [], 'no message: only the mark');
  await canvasShot(page, '14-not-certified');
  await setBudget(20000);
  await waitForSnapshot(page, `(s) => s.status === 'converged' && s.constraints?.triangles === 20000`);
});

test('the page stayed on 127.0.0.1 and raised no errors', () => {
  assert.deepEqual(viewer.offHostRequests, []);
  assert.deepEqual(viewer.pageErrors, []);
});
