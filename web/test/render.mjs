// Renders views of a trompe octahedral impostor (.glb) with the three.js runtime in headless
// Chromium (WebGL 2 through SwiftShader, on the CPU) and writes one PNG a view.
//
//   node web/test/render.mjs --glb BAKE.glb --views views.json --out DIR
//
// views.json: a list of views as render.html reads them. Prints the WebGL renderer's name.
// Chromium as web/test/browser.mjs starts it, the files as web/test/serve.mjs serves them.

import { readFile, writeFile, mkdir } from 'node:fs/promises';
import { join } from 'node:path';
import { launch, parseArgs } from './browser.mjs';
import { serve } from './serve.mjs';

const args = parseArgs();
for (const need of ['glb', 'views', 'out']) {
  if (!args[need]) {
    console.error(`render.mjs: --${need} is missing (usage: --glb BAKE.glb --views views.json --out DIR)`);
    process.exit(2);
  }
}
const { server, url } = await serve(args.glb);

const browser = await launch();
let failed = false;
try {
  const page = await browser.newPage();
  page.on('pageerror', (e) => { console.error(`page error: ${e.message}`); failed = true; });
  // A shader that does not compile is a console error: it fails the run.
  page.on('console', (m) => {
    if (!['error', 'warning'].includes(m.type()) || m.text().includes('GPU stall due to ReadPixels')) return;
    console.error(`console: ${m.text()}`);
    failed = failed || m.type() === 'error';
  });
  await page.goto(`${url}/test/render.html`);
  await page.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
  const views = JSON.parse(await readFile(args.views, 'utf8'));
  const result = await page.evaluate(([glb, v]) => window.renderViews(glb, v), ['/bake.glb', views]);
  await mkdir(args.out, { recursive: true });
  for (const [k, data] of result.images.entries()) {
    await writeFile(join(args.out, `view-${k}.png`), Buffer.from(data.split(',')[1], 'base64'));
  }
  console.log(`renderer: ${result.renderer}`);
  console.log(`wrote ${result.images.length} views to ${args.out}`);
} catch (e) {
  console.error(`render.mjs: ${e.message}`);
  failed = true;
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
