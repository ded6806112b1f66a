// Browser test of the viewer's layout: a 390 px phone screen (the panel under the view, both
// usable, the panel collapsible) and dark mode (prefers-color-scheme). Screenshots go to
// build/test-artifacts/web/.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { boxCornersOnScreen, canvasShot, convergedOn, typeEquation, viewerForTests, waitForSnapshot } from './browser.js';
import { coloredFraction } from './pixels.js';

const PHONE = { width: 390, height: 844 };
let page;
const viewer = viewerForTests('layout', { viewport: PHONE }, (v) => (page = v.page));

const box = (locator) => locator.boundingBox();

test('on a 390 px screen the view and the panel are both usable', async () => {
  await page.goto(`${viewer.server.url}?eq=x%5E2%2By%5E2%2Bz%5E2%3Da&p=a:2`);
  await waitForSnapshot(page, convergedOn, { expression: 'x^2+y^2+z^2=a', parameters: { a: 2 } });
  const canvas = await box(page.locator('#canvas-host canvas'));
  assert.ok(canvas.width >= 380 && canvas.height >= 0.4 * PHONE.height, `the view is ${canvas.width}×${canvas.height}`);
  const equation = page.getByRole('textbox', { name: 'Equation', exact: true });
  const field = await box(equation);
  assert.ok(field.width >= 250, `the equation field is ${field.width} px wide`);
  assert.ok(field.y >= 0 && field.y + field.height <= PHONE.height, 'the equation field is on screen');
  assert.ok(await page.evaluate(() => document.documentElement.scrollWidth <= window.innerWidth), 'no sideways scrolling');
  await canvasShot(page, 'phone-1');

  await typeEquation(page, 'x^2+y^2-z^2=a');
  await waitForSnapshot(page, convergedOn, { expression: 'x^2+y^2-z^2=a', parameters: { a: 2 } });
  const slider = page.getByRole('slider', { name: 'a', exact: true });
  await slider.scrollIntoViewIfNeeded();
  const thumb = await box(slider);
  assert.ok(thumb.width >= 120, `the slider is ${thumb.width} px wide`);
  await slider.focus();
  await page.keyboard.press('ArrowRight');
  await waitForSnapshot(page, convergedOn, { parameters: { a: 2.1 } });
  const s = await canvasShot(page, 'phone-2-hyperboloid');
  assert.ok(coloredFraction(s).fraction > 0.01);

  await page.getByRole('button', { name: 'Hide panel' }).click();
  const full = await box(page.locator('#canvas-host canvas'));
  assert.ok(full.height >= PHONE.height - 2, `hidden panel: the view is ${full.height} px high`);
  const corners = await boxCornersOnScreen(page);
  assert.ok(corners.every(([x]) => Math.abs(x) <= 1), `the taller view keeps the box's width on screen: ${JSON.stringify(corners)}`);
  await canvasShot(page, 'phone-3-panel-hidden');
  await page.getByRole('button', { name: 'Show panel' }).click();
  assert.ok(await equation.isVisible());
});

test('dark mode follows prefers-color-scheme', async () => {
  await page.setViewportSize({ width: 1280, height: 800 });
  await page.emulateMedia({ colorScheme: 'dark' });
  await page.waitForTimeout(300);
  const png = await canvasShot(page, 'dark-mode');
  const corner = await page.evaluate(() => getComputedStyle(document.querySelector('#panel')).backgroundColor);
  const [r, g, b] = corner.match(/\d+/g).map(Number);
  assert.ok(r + g + b < 150, `the panel is dark: ${corner}`);
  const { PNG } = await import('pngjs');
  const image = PNG.sync.read(png);
  const background = [0, 1, 2].map((k) => image.data[4 * (5 * image.width + 5) + k]);
  assert.ok(background.every((c) => c < 60), `the view is dark: ${background}`);
  assert.ok(coloredFraction(png).fraction > 0.01, 'the surface shows on it');
  await page.emulateMedia({ colorScheme: 'light' });
});

test('the layout raised no page errors and stayed on 127.0.0.1', () => {
  assert.deepEqual(viewer.offHostRequests, []);
  assert.deepEqual(viewer.pageErrors, []);
});
