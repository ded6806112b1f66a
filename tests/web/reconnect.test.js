// Browser test of the viewer across a server crash: Debian's chromium shows two surfaces (a row and
// a session each) served by an isomesh-server with its SQLite session store; the server is killed
// (SIGKILL) and the status line says the viewer is disconnected and reconnecting, the meshes still
// shown; the server starts again on the same port and file, and the viewer, through the client
// library's reconnection, shows every row's same session again with the identical mesh (the same
// triangles at bit-equal positions). The <isomesh-surface> element on its example page says it is
// disconnected and comes back to its session too. Screenshots of the three moments go to
// build/test-artifacts/web/reconnect-*.png.

import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';

import { chromium } from 'playwright-core';

import { REPO, startServer } from './server.js';

const CHROMIUM = process.env.ISOMESH_CHROMIUM ?? '/usr/bin/chromium';
const ARTIFACTS = join(REPO, 'build/test-artifacts/web');

const EQUATIONS = ['x^2+y^2+z^2+2cos(2x)=5', '(x-1)^2+y^2=1'];

/** Each row's mesh as sorted triangles of float32 position bits (corners rotated to the smallest). */
function meshesInPage() {
  return window.isomesh.app.rows.map(({ surface: { session } }) => {
    if (!session) return null;
    const { positions, indices } = session.mesh.toIndexed();
    const bits = new Uint32Array(positions.buffer, positions.byteOffset, positions.length);
    const corner = (v) => `${bits[3 * v]},${bits[3 * v + 1]},${bits[3 * v + 2]}`;
    const triangles = [];
    for (let t = 0; t < indices.length; t += 3) {
      const c = [corner(indices[t]), corner(indices[t + 1]), corner(indices[t + 2])];
      const first = c.indexOf([...c].sort()[0]);
      triangles.push(`${c[first]} ${c[(first + 1) % 3]} ${c[(first + 2) % 3]}`);
    }
    return { session: session.id, triangles: triangles.sort() };
  });
}

test('the viewer shows a server crash and comes back to the same session and mesh', async () => {
  mkdirSync(ARTIFACTS, { recursive: true });
  const dir = mkdtempSync(join(tmpdir(), 'isomesh-web-reconnect-'));
  const store = ['--store', `sqlite:${join(dir, 'sessions.db')}`];
  let server = await startServer(store);
  const profile = mkdtempSync(join(tmpdir(), 'isomesh-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking'],
    viewport: { width: 1280, height: 800 },
  });
  const pageErrors = [];
  try {
    const page = context.pages()[0] ?? (await context.newPage());
    page.on('pageerror', (error) => pageErrors.push(error.message));
    const status = (wanted) => page.waitForFunction((w) => window.isomesh?.snapshot().status === w, wanted, { timeout: 60000, polling: 50 });
    await page.goto(`${server.url}?${EQUATIONS.map((e) => `eq=${encodeURIComponent(e)}`).join('&')}`);
    await page.waitForFunction(() => window.isomesh?.snapshot().surfaces.filter((f) => f.status === 'converged').length === 2, null, { timeout: 60000, polling: 50 });
    const before = await page.evaluate(meshesInPage);
    assert.ok(before.every((m) => m.triangles.length > 100), 'two surfaces shown');
    assert.notEqual(before[0].session, before[1].session, 'a session each');
    await page.screenshot({ path: join(ARTIFACTS, 'reconnect-1-before.png') });
    // The <isomesh-surface> element, on its example page, goes through the same crash.
    const embed = await context.newPage();
    embed.on('pageerror', (error) => pageErrors.push(`embed: ${error.message}`));
    await embed.goto(`${server.url}embed.html`);
    const element = (predicate, arg) =>
      embed.waitForFunction(
        ([source, value]) => {
          const e = document.querySelector('#sphere');
          const s = e?.snapshot();
          const line = e?.shadowRoot.querySelector('[role=status]').textContent ?? '';
          // eslint-disable-next-line no-new-func
          return s && new Function('s', 'line', 'arg', `return (${source})(s, line, arg)`)(s, line, value) ? { ...s, line } : null;
        },
        [predicate, arg],
        { timeout: 60000, polling: 50 },
      ).then((handle) => handle.jsonValue());
    const elementBefore = await element(`(s) => s.status === 'converged' && s.triangles > 100`);

    await server.kill();
    await status('disconnected');
    assert.match(await page.textContent('#status'), /disconnected \(reconnecting\)/);
    const during = await page.evaluate(() => window.isomesh.snapshot().surfaces.map((f) => [f.session, f.triangles, f.status]));
    assert.deepEqual(during.map(([id]) => id), before.map((m) => m.session), 'the rows keep their sessions while disconnected');
    assert.deepEqual(during.map(([, count]) => count), before.map((m) => m.triangles.length), 'and their meshes stay shown');
    assert.match(await page.locator('.object .progress').first().textContent(), /^reconnecting… · \d+ triangles$/);
    await page.screenshot({ path: join(ARTIFACTS, 'reconnect-2-disconnected.png') });
    const elementDuring = await element(`(s, line) => line.startsWith('disconnected')`);
    assert.equal(elementDuring.line, `disconnected (reconnecting) · ${elementBefore.triangles} triangles`, 'the element says so, its mesh still shown');
    await embed.locator('#sphere').screenshot({ path: join(ARTIFACTS, 'reconnect-2-element.png') });

    server = await startServer([...store, '--port', String(server.port)]);
    await page.waitForFunction((ids) => {
      const s = window.isomesh?.snapshot();
      return s?.status === 'converged' && s.surfaces.every((f, i) => f.status === 'converged' && f.session === ids[i]);
    }, before.map((m) => m.session), { timeout: 60000, polling: 50 });
    const after = await page.evaluate(meshesInPage);
    for (let i = 0; i < EQUATIONS.length; ++i) {
      assert.equal(after[i].session, before[i].session, `row ${i + 1}: the same session, resubscribed`);
      assert.deepEqual(after[i].triangles, before[i].triangles, `row ${i + 1}: the identical mesh`);
    }
    assert.equal(await page.evaluate(() => window.isomesh.app.client.reconnects), 1, "the library's reconnection");
    assert.doesNotMatch(await page.textContent('#status'), /disconnected/);
    const elementAfter = await element(`(s, line, id) => s.status === 'converged' && s.session === id && !line.startsWith('disconnected')`, elementBefore.session);
    assert.equal(elementAfter.triangles, elementBefore.triangles, 'the element: the same session and triangle count');
    assert.match(elementAfter.line, /^\d+ triangles · converged$/);
    await page.screenshot({ path: join(ARTIFACTS, 'reconnect-3-after.png') });
    assert.deepEqual(pageErrors, []);
  } finally {
    await context.close();
    rmSync(profile, { recursive: true, force: true });
    const { code } = await server.stop();
    rmSync(dir, { recursive: true, force: true });
    assert.equal(code, 0);
  }
});
