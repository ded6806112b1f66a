// Browser test of the viewer across a server crash: Debian's chromium shows a surface served by an
// isomesh-server with its SQLite session store; the server is killed (SIGKILL) and the status line
// says the viewer is disconnected; the server starts again on the same port and file, and the
// viewer, through the client library's reconnection, shows the same session again with the
// identical mesh (the same triangles at bit-equal positions). Screenshots of the three moments go
// to build/test-artifacts/web/reconnect-*.png.

import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';

import { chromium } from 'playwright-core';

import { REPO, startServer } from './server.js';

const CHROMIUM = process.env.ISOMESH_CHROMIUM ?? '/usr/bin/chromium';
const ARTIFACTS = join(REPO, 'build/test-artifacts/web');

/** The page's mesh as sorted triangles of float32 position bits (corners rotated to the smallest). */
function meshInPage() {
  const session = window.isomesh.app.session;
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
    await page.goto(`${server.url}?expr=${encodeURIComponent('x^2+y^2+z^2+2cos(2x)=5')}`);
    await status('converged');
    const before = await page.evaluate(meshInPage);
    assert.ok(before.triangles.length > 100);
    await page.screenshot({ path: join(ARTIFACTS, 'reconnect-1-before.png') });

    await server.kill();
    await status('disconnected');
    assert.match(await page.textContent('#status'), /disconnected/);
    await page.screenshot({ path: join(ARTIFACTS, 'reconnect-2-disconnected.png') });

    server = await startServer([...store, '--port', String(server.port)]);
    await page.waitForFunction((id) => {
      const s = window.isomesh?.snapshot();
      return s?.status === 'converged' && s.session === id;
    }, before.session, { timeout: 60000, polling: 50 });
    const after = await page.evaluate(meshInPage);
    assert.equal(after.session, before.session, 'the same session, resubscribed');
    assert.deepEqual(after.triangles, before.triangles, 'the identical mesh');
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
