// Browser test of the viewer: Debian's chromium (never a downloaded browser) driven by
// playwright-core loads the viewer from a real isomesh-server on a free loopback port, types an
// equation, waits for `converged`, checks that the canvas shows a surface (pixels of a
// screenshot), moves a slider and sees the mesh change, switches to a gallery example, toggles the
// wireframe, and types a bad equation and sees the error with its column marked.
//
// Screenshots go to build/test-artifacts/web/. Every request the page makes must stay on
// 127.0.0.1: the viewer works without internet access.

import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';

import { chromium } from 'playwright-core';

import { coloredFraction, differingFraction } from './pixels.js';
import { REPO, startServer } from './server.js';

const CHROMIUM = process.env.ISOMESH_CHROMIUM ?? '/usr/bin/chromium';
const ARTIFACTS = join(REPO, 'build/test-artifacts/web');
const WAIT_MS = 60000;

let server;
let context;
let page;
let profile;
const pageErrors = [];
const offHostRequests = [];

before(async () => {
  mkdirSync(ARTIFACTS, { recursive: true });
  server = await startServer();
  profile = mkdtempSync(join(tmpdir(), 'isomesh-chromium-'));
  context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    headless: true,
    args: [
      '--headless',
      '--no-sandbox',
      '--disable-gpu',
      '--disable-quic',
      '--no-first-run',
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
    ],
    viewport: { width: 1280, height: 800 },
  });
  await context.route('**/*', (route) => {
    const url = new URL(route.request().url());
    if (url.hostname === '127.0.0.1' || url.protocol === 'data:') return route.continue();
    offHostRequests.push(url.href);
    return route.abort();
  });
  page = context.pages()[0] ?? (await context.newPage());
  page.on('pageerror', (error) => pageErrors.push(error.message));
  page.on('console', (message) => {
    if (message.type() === 'error') pageErrors.push(`console: ${message.text()}`);
  });
});

after(async () => {
  await context?.close();
  if (profile) rmSync(profile, { recursive: true, force: true });
  if (server) {
    const { code, signal } = await server.stop();
    writeFileSync(join(ARTIFACTS, 'server.log'), server.log.join('\n') + '\n');
    assert.ok(code === 0 || signal === 'SIGTERM', `server ended with ${code ?? signal}`);
  }
});

/** Resolves with the viewer's snapshot once `predicate(snapshot)` holds (evaluated in the page). */
async function waitForSnapshot(predicateSource, arg) {
  const handle = await page.waitForFunction(
    ([source, value]) => {
      const s = window.isomesh?.snapshot();
      // eslint-disable-next-line no-new-func
      return s && new Function('s', 'arg', `return (${source})(s, arg)`)(s, value) ? s : null;
    },
    [predicateSource, arg],
    { timeout: WAIT_MS, polling: 50 },
  );
  return handle.jsonValue();
}

const convergedOn = `(s, arg) => s.status === 'converged' && s.expression === arg.expression &&
  Object.entries(arg.parameters ?? {}).every(([k, v]) => s.parameters[k] === v)`;

async function canvasShot(name) {
  const png = await page.locator('#canvas-host canvas').screenshot();
  writeFileSync(join(ARTIFACTS, `${name}.png`), png);
  await page.screenshot({ path: join(ARTIFACTS, `${name}-page.png`) });
  return png;
}

async function typeEquation(text) {
  await page.fill('#equation', text);
  await page.press('#equation', 'Enter');
}

let sphere; // the screenshot and snapshot of x^2+y^2+z^2=a at a = 1

test('the viewer loads from the server and shows its first example', async () => {
  await page.goto(server.url);
  const s = await waitForSnapshot(`(s) => s.status === 'converged'`);
  assert.ok(s.triangles > 0, 'a mesh is shown');
  assert.ok(s.firstMeshMs > 0, 'time to first mesh is measured');
  assert.ok(s.bytesReceived > 0);
  assert.match(await page.textContent('#status'), /triangles .* received .* first mesh .* converged/);
});

test('typing an equation with a parameter meshes it and makes a slider', async () => {
  await typeEquation('x^2+y^2+z^2=a');
  const s = await waitForSnapshot(convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: 1 } });
  assert.ok(s.triangles > 100, `${s.triangles} triangles`);
  assert.equal(await page.locator('.slider[data-parameter="a"] input[type=range]').count(), 1);
  assert.equal(await page.isHidden('#equation-error'), true, 'no error is shown');
  const png = await canvasShot('1-sphere');
  const pixels = coloredFraction(png);
  assert.ok(pixels.fraction > 0.01, `the canvas shows a surface (${(100 * pixels.fraction).toFixed(2)}% colored pixels)`);
  sphere = { png, pixels, snapshot: s, signature: await page.evaluate(() => window.isomesh.meshSignature()) };
});

test('moving the slider changes the mesh', async () => {
  const slider = page.locator('.slider[data-parameter="a"] input[type=range]');
  for (const value of ['1.5', '2', '2.5', '3', '3.5', '4']) await slider.fill(value); // a quick drag
  const s = await waitForSnapshot(convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: 4 } });
  assert.ok(s.version > sphere.snapshot.version, 'a new function version');
  const signature = await page.evaluate(() => window.isomesh.meshSignature());
  const journal = await page.evaluate(() => window.isomesh.journal());
  assert.notDeepEqual(signature, sphere.signature, `the mesh data changed: ${JSON.stringify({ before: sphere.signature, after: signature, journal })}`);
  const png = await canvasShot('2-sphere-a4');
  const pixels = coloredFraction(png);
  assert.ok(
    pixels.fraction > 1.8 * sphere.pixels.fraction,
    `radius 2 covers more than radius 1: ${(100 * pixels.fraction).toFixed(2)}% vs ${(100 * sphere.pixels.fraction).toFixed(2)}%`,
  );
  assert.equal(await page.inputValue('.slider[data-parameter="a"] input[type=number]'), '4');
});

test('a gallery example brings its own sliders', async () => {
  await page.selectOption('#gallery', { label: 'Torus' });
  const s = await waitForSnapshot(convergedOn, { expression: '(sqrt(x^2+y^2)-R)^2+z^2=r^2', parameters: { R: 2, r: 0.7 } });
  assert.deepEqual(Object.keys(s.parameters).sort(), ['R', 'r']);
  assert.deepEqual(s.box, [-3.2, 3.2, -3.2, 3.2, -1.2, 1.2]);
  const names = await page.$$eval('.slider', (rows) => rows.map((row) => row.dataset.parameter));
  assert.deepEqual(names.sort(), ['R', 'r']);
  assert.equal(await page.inputValue('#equation'), '(sqrt(x^2+y^2)-R)^2+z^2=r^2');
  const shaded = await canvasShot('3-torus');
  assert.ok(coloredFraction(shaded).fraction > 0.01);

  await page.check('#wireframe');
  await page.waitForTimeout(300);
  const wire = await canvasShot('4-torus-wireframe');
  const changed = differingFraction(shaded, wire);
  assert.ok(changed > 0.002, `the wireframe shows (${(100 * changed).toFixed(2)}% of pixels changed)`);
  await page.uncheck('#wireframe');
});

test('a bad equation shows the error under the input with its column marked', async () => {
  const before = await page.evaluate(() => window.isomesh.snapshot());
  const bad = 'x^2+(y+z^2=1';
  await typeEquation(bad);
  await page.waitForSelector('#equation-error:not([hidden])', { timeout: WAIT_MS });
  const s = await page.evaluate(() => window.isomesh.snapshot());
  assert.equal(s.error?.code, 'bad_expression');
  assert.ok(Number.isInteger(s.error.column) && s.error.column >= 1 && s.error.column <= bad.length + 1, `column ${s.error.column}`);
  const message = await page.textContent('#equation-error .message');
  assert.ok(message.length > 0, 'a message is shown');
  const marked = await page.$eval('#equation-error .marked', (code) => {
    const mark = code.querySelector('mark');
    return { before: mark?.previousSibling?.textContent ?? '', mark: mark?.textContent ?? null };
  });
  assert.notEqual(marked.mark, null, 'a character is marked');
  assert.equal(Array.from(marked.before).length, s.error.column - 1, 'the mark sits at the column');
  assert.ok(await page.locator('#equation.invalid').count(), 'the input is flagged');
  assert.equal(s.triangles, before.triangles, 'the previous surface stays');
  await canvasShot('5-bad-equation');

  // Fixing the equation clears the error.
  await typeEquation('x^2+(y+z)^2=1');
  await waitForSnapshot(convergedOn, { expression: 'x^2+(y+z)^2=1' });
  assert.equal(await page.isHidden('#equation-error'), true);
});

test('the page stayed on 127.0.0.1 and raised no errors', () => {
  assert.deepEqual(offHostRequests, []);
  assert.deepEqual(pageErrors, []);
});
