// Renders views of a trompe octahedral impostor (.glb) with the three.js runtime in headless
// Chromium (WebGL 2 through SwiftShader, on the CPU) and writes one PNG a view.
//
//   node web/test/render.mjs --glb BAKE.glb --views views.json --out DIR
//
// views.json: a list of views as render.html reads them. Prints the WebGL renderer's name.
// Chromium as web/test/browser.mjs starts it.

import { createServer } from 'node:http';
import { readFile, writeFile, mkdir } from 'node:fs/promises';
import { extname, join, normalize, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { launch } from './browser.mjs';

const args = Object.fromEntries(
  process.argv.slice(2).reduce((pairs, a, i, all) => (a.startsWith('--') ? [...pairs, [a.slice(2), all[i + 1]]] : pairs), []),
);
for (const need of ['glb', 'views', 'out']) {
  if (!args[need]) {
    console.error(`render.mjs: --${need} is missing (usage: --glb BAKE.glb --views views.json --out DIR)`);
    process.exit(2);
  }
}
const web = resolve(dirname(fileURLToPath(import.meta.url)), '..');
const types = {
  '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.glb': 'model/gltf-binary', '.wasm': 'application/wasm',
};

// The runtime, three.js from node_modules, and the bake at /bake.glb; nothing else.
const server = createServer(async (req, res) => {
  try {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    const file = path === '/bake.glb' ? resolve(args.glb) : join(web, normalize(path));
    if (path !== '/bake.glb' && !file.startsWith(web)) throw new Error('outside');
    const body = await readFile(file);
    res.writeHead(200, { 'content-type': types[extname(file)] || 'application/octet-stream' });
    res.end(body);
  } catch {
    res.writeHead(404);
    res.end();
  }
});
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const url = `http://127.0.0.1:${server.address().port}`;

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
