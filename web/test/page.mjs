// Opens the demo report's interactive page (`trompe demo` writes octahedral-turn.html) in
// headless Chromium, with three.js served from web/node_modules in place of the CDN the page
// names, and checks that it draws the impostor: no page error, and the canvas not one flat
// colour. Usage: node web/test/page.mjs REPORT/octahedral-turn.html
//
// Chromium as web/test/browser.mjs starts it.

import { readFile } from 'node:fs/promises';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { launch } from './browser.mjs';

const page_path = process.argv[2];
if (!page_path) {
  console.error('page.mjs: give the page (REPORT/octahedral-turn.html)');
  process.exit(2);
}
const three = resolve(dirname(fileURLToPath(import.meta.url)), '..', 'node_modules', 'three');
const browser = await launch();
let failed = false;
try {
  const page = await browser.newPage();
  page.on('pageerror', (e) => { console.error(`page error: ${e.message}`); failed = true; });
  // The CDN's three.js, from the npm package of the same version.
  await page.route(/cdn\.jsdelivr\.net\/npm\/three@[^/]+\/(.*)$/, async (route) => {
    const rest = route.request().url().replace(/^.*three@[^/]+\//, '');
    route.fulfill({ body: await readFile(join(three, rest)), contentType: 'text/javascript' });
  });
  await page.goto(pathToFileURL(resolve(page_path)).href);
  await page.waitForFunction(() => document.getElementById('status').textContent !== '' ||
    window.performance.now() > 1000, null, { timeout: 60000 });
  await page.waitForTimeout(1500);
  const status = await page.evaluate(() => document.getElementById('status').textContent);
  if (status) throw new Error(status);
  // Read the canvas back through a 2-D copy: count its distinct colours.
  const colours = await page.evaluate(() => {
    const c = document.getElementById('view');
    const copy = document.createElement('canvas');
    copy.width = c.width; copy.height = c.height;
    const g = copy.getContext('2d');
    g.drawImage(c, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    const seen = new Set();
    for (let i = 0; i < d.length; i += 4 * 7) seen.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
    return seen.size;
  });
  console.log(`the page drew the impostor: ${colours} distinct colours on its canvas`);
  if (colours < 50) throw new Error(`the canvas holds ${colours} colours: nothing drawn`);
} catch (e) {
  console.error(`page.mjs: ${e.message}`);
  failed = true;
} finally {
  await browser.close();
}
process.exit(failed ? 1 : 0);
