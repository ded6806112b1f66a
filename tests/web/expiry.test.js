// Browser test of a session the server ends on purpose: a server whose sessions expire after 3 s
// without a request (`--idle-timeout 3`; an hour by default) ends the viewer's session while the
// page sits untouched. The row then says so instead of "finding the shape…" forever, and Enter in
// its equation draws the surface again in a new session. Screenshot: build/test-artifacts/web/.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { canvasShot, convergedOn, viewerForTests, waitForSnapshot } from './browser.js';

const IDLE_S = 3;
let page;
const viewer = viewerForTests('expiry', { serverArgs: ['--idle-timeout', String(IDLE_S)] }, (v) => (page = v.page));

test('a session the server ended (idle expiry) is said, and Enter draws the surface again', async () => {
  await page.goto(`${viewer.server.url}?eq=${encodeURIComponent('x^2+y^2+z^2=4')}`);
  const before = await waitForSnapshot(page, convergedOn, { expression: 'x^2+y^2+z^2=4' });
  // The rows are redrawn at the next animation frame: the status may be in the snapshot a frame
  // before the row's note.
  const ended = await waitForSnapshot(page, `(s) => s.surfaces[0].status === 'ended' && s.surfaces[0].notes.length > 0`);
  const row = ended.surfaces[0];
  assert.equal(row.ended, 'expired');
  assert.equal(row.session, null);
  assert.deepEqual(row.notes, ["The server ended this surface's session after a long time without a change. Press Enter or change a value to draw it again."]);
  assert.equal(await page.locator('.object .progress .text').first().textContent(), 'ended');
  assert.match(await page.getByRole('status').textContent(), /session ended$/);
  assert.ok(viewer.server.log.some((line) => line.includes('"session_expired"')), 'the server expired it');
  await canvasShot(page, 'expiry-ended');

  await page.getByRole('textbox', { name: 'Equation', exact: true }).press('Enter');
  const again = await waitForSnapshot(page, `(s, id) => s.status === 'converged' && s.session !== null && s.session !== id`, before.session);
  assert.equal(again.triangles, before.triangles, 'the same surface, in a new session');
  assert.deepEqual(again.surfaces[0].notes, []);
});

test('the expiry page raised no errors and stayed on 127.0.0.1', () => {
  assert.deepEqual(viewer.offHostRequests, []);
  assert.deepEqual(viewer.pageErrors, []);
});
