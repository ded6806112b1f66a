// What the browser tests share: Debian's chromium (never a downloaded browser) driven by
// playwright-core, a real isomesh-server on a free loopback port, a guard that every request
// stays on 127.0.0.1 (the viewer works without internet access), and helpers that read the
// viewer's state (window.isomesh) and save screenshots to build/test-artifacts/web/.

import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before } from 'node:test';

import { chromium } from 'playwright-core';

import { REPO, startServer } from './server.js';

export const CHROMIUM = process.env.ISOMESH_CHROMIUM ?? '/usr/bin/chromium';
export const ARTIFACTS = join(REPO, 'build/test-artifacts/web');
export const WAIT_MS = 60000;

/**
 * Starts a server and a browser context. Resolves with {server, context, page, pageErrors,
 * offHostRequests, close()}; `close` stops both and saves the server's log as `${name}-server.log`.
 */
export async function openViewer(name, { viewport = { width: 1280, height: 800 }, serverArgs = [], relay = false } = {}) {
  mkdirSync(ARTIFACTS, { recursive: true });
  const server = await startServer(serverArgs);
  const profile = mkdtempSync(join(tmpdir(), 'isomesh-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
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
    viewport,
    acceptDownloads: true,
  });
  const messages = relay ? await relayWebSockets(context) : null;
  const pageErrors = [];
  const offHostRequests = [];
  await context.route('**/*', (route) => {
    const url = new URL(route.request().url());
    if (url.hostname === '127.0.0.1' || url.protocol === 'data:' || url.protocol === 'blob:') return route.continue();
    offHostRequests.push(url.href);
    return route.abort();
  });
  const watch = (page) => {
    page.on('pageerror', (error) => pageErrors.push(`${page.url()}: ${error.message}`));
    page.on('console', (message) => {
      if (message.type() === 'error') pageErrors.push(`console: ${message.text()}`);
    });
  };
  context.on('page', watch);
  const page = context.pages()[0] ?? (await context.newPage());
  watch(page);
  const close = async () => {
    await context.close();
    rmSync(profile, { recursive: true, force: true });
    const { code, signal } = await server.stop();
    writeFileSync(join(ARTIFACTS, `${name}-server.log`), server.log.join('\n') + '\n');
    return { code, signal };
  };
  return { server, context, page, pageErrors, offHostRequests, messages, close };
}

/**
 * Passes every WebSocket of `context` through the test, as a slow network would deliver it.
 * Resolves with {holdAfter(predicate), release()}: after a server message (parsed JSON text, or
 * null for a binary frame) for which `predicate` holds, that message reaches the page and the
 * server's later ones wait until `release()`. A test thus sees the page in a state the server
 * passes through, however fast the server and however slow the browser.
 */
async function relayWebSockets(context) {
  let hold = null;
  let held = null; // [[page side, message]] once holding
  const control = {
    holdAfter(predicate) {
      hold = predicate;
    },
    release() {
      const queued = held ?? [];
      hold = null;
      held = null;
      for (const [page, message] of queued) page.send(message);
    },
  };
  await context.routeWebSocket(/\/ws/, (page) => {
    const server = page.connectToServer();
    page.onMessage((message) => server.send(message));
    server.onMessage((message) => {
      if (held) {
        held.push([page, message]);
        return;
      }
      page.send(message);
      if (hold?.(typeof message === 'string' ? JSON.parse(message) : null)) held = [];
    });
  });
  return control;
}

/**
 * A test file's viewer: opened before its tests, closed after them (the server must exit
 * cleanly). Returns an object that holds openViewer's fields once the tests run; `onOpen(viewer)`
 * runs in the same hook (node:test runs a file's top-level `before` hooks concurrently).
 */
export function viewerForTests(name, options = {}, onOpen = () => {}) {
  const viewer = {};
  before(async () => {
    Object.assign(viewer, await openViewer(name, options));
    onOpen(viewer);
  });
  after(async () => {
    if (!viewer.close) return;
    const { code, signal } = await viewer.close();
    assert.ok(code === 0 || signal === 'SIGTERM', `server ended with ${code ?? signal}`);
  });
  return viewer;
}

/** Resolves with the viewer's snapshot once `predicate(snapshot, arg)` holds (evaluated in the page). */
export async function waitForSnapshot(page, predicateSource, arg = null) {
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

/** Every surface converged; the active one on `arg.expression` with `arg.parameters` if given. */
export const convergedOn = `(s, arg) => s.status === 'converged' &&
  (!arg || arg.expression === undefined || s.expression === arg.expression) &&
  Object.entries(arg?.parameters ?? {}).every(([k, v]) => Math.abs(s.parameters[k] - v) < 1e-9)`;

export const snapshot = (page) => page.evaluate(() => window.isomesh.snapshot());

/** The view box's corners in normalized device coordinates (on screen: x and y within ±1). */
export const boxCornersOnScreen = (page) =>
  page.evaluate(() => {
    const { camera } = window.isomesh.viewer;
    const b = window.isomesh.snapshot().box;
    camera.updateMatrixWorld();
    const corners = [];
    for (const x of [b[0], b[1]]) for (const y of [b[2], b[3]]) for (const z of [b[4], b[5]]) corners.push(camera.position.clone().set(x, y, z).project(camera));
    return corners.map((v) => [v.x, v.y]);
  });

/** Saves the canvas (`${name}.png`) and the whole page (`${name}-page.png`); returns the canvas PNG. */
export async function canvasShot(page, name) {
  const png = await page.locator('#canvas-host canvas').screenshot();
  writeFileSync(join(ARTIFACTS, `${name}.png`), png);
  await page.screenshot({ path: join(ARTIFACTS, `${name}-page.png`) });
  return png;
}

/** Types `text` into the equation field of row `index` (0-based) and presses Enter. */
export async function typeEquation(page, text, index = 0) {
  const input = page.getByRole('textbox', { name: 'Equation', exact: true }).nth(index);
  await input.fill(text);
  await input.press('Enter');
}

/** The number the status line shows before "triangles". */
export async function statusTriangles(page) {
  const text = await page.getByRole('status').first().textContent();
  const match = /(\d+) triangles/.exec(text);
  return match ? Number(match[1]) : null;
}
