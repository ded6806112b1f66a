// Browser test of the embeddable element, <isomesh-surface equation="x^2+y^2+z^2=a" a="4">, on
// its example page (build/web/embed.html): every element meshes its equation, and changing an
// attribute updates the surface live.

import assert from 'node:assert/strict';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { test } from 'node:test';

import { ARTIFACTS, WAIT_MS, viewerForTests } from './browser.js';
import { coloredFraction } from './pixels.js';

let page;
const viewer = viewerForTests('embed', {}, (v) => (page = v.page));

/** The element's snapshot once it has converged with `parameters` (all of them). */
async function converged(id, parameters = {}) {
  const handle = await page.waitForFunction(
    ([selector, wanted]) => {
      const s = document.querySelector(selector)?.snapshot();
      const ok = s && s.status === 'converged' && Object.entries(wanted).every(([k, v]) => s.parameters[k] === v);
      return ok ? s : null;
    },
    [`#${id}`, parameters],
    { timeout: WAIT_MS, polling: 50 },
  );
  return handle.jsonValue();
}

test('the example page: each <isomesh-surface> meshes its equation with its attributes', async () => {
  await page.goto(`${viewer.server.url}embed.html`);
  const sphere = await converged('sphere', { a: 4 });
  assert.equal(sphere.expression, 'x^2+y^2+z^2=a');
  assert.ok(sphere.triangles > 100);
  const torus = await converged('torus', { R: 2, r: 0.7 });
  assert.deepEqual(torus.box, [-3.2, 3.2, -3.2, 3.2, -1.2, 1.2]);
  const gyroid = await converged('gyroid');
  assert.equal(gyroid.constraints.triangles, 40000);
  assert.match(await page.locator('#sphere').evaluate((e) => e.shadowRoot.querySelector('[role=status]').textContent), /^\d+ triangles/);
  await page.screenshot({ path: join(ARTIFACTS, 'embed-page.png'), fullPage: true });
  for (const id of ['sphere', 'torus', 'gyroid']) {
    const png = await page.locator(`#${id}`).screenshot();
    writeFileSync(join(ARTIFACTS, `embed-${id}.png`), png);
    assert.ok(coloredFraction(png).fraction > 0.01, `${id} shows a surface`);
  }
});

test('changing an attribute updates the surface', async () => {
  const before = await converged('sphere', { a: 4 });
  await page.locator('#sphere').evaluate((e) => e.setAttribute('a', '1'));
  const after = await converged('sphere', { a: 1 });
  assert.ok(after.version > before.version);
  await page.locator('#sphere').evaluate((e) => e.setAttribute('equation', 'x^2+y^2=a'));
  const cylinder = await page.waitForFunction(() => {
    const s = document.querySelector('#sphere').snapshot();
    return s.status === 'converged' && s.expression === 'x^2+y^2=a' ? s : null;
  }, null, { timeout: WAIT_MS });
  assert.ok((await cylinder.jsonValue()).triangles > 0);
});

test('the example page raised no errors and stayed on 127.0.0.1', () => {
  assert.deepEqual(viewer.offHostRequests, []);
  assert.deepEqual(viewer.pageErrors, []);
});
