// Reads a glTF binary's meshes as three.js loads them (GLTFLoader with its meshopt decoder) in
// headless Chromium and writes what it read as JSON: world positions, UVs, triangle count.
//
//   node web/test/mesh.mjs --glb MESH.glb --out MESH.json
//
// Chromium as web/test/browser.mjs starts it, the files as web/test/serve.mjs serves them.

import { writeFile } from 'node:fs/promises';
import { launch, parseArgs } from './browser.mjs';
import { serve } from './serve.mjs';

const args = parseArgs();
if (!args.glb || !args.out) {
  console.error('mesh.mjs: usage: --glb MESH.glb --out MESH.json');
  process.exit(2);
}
const { server, url } = await serve(args.glb);
const browser = await launch();
let failed = false;
try {
  const page = await browser.newPage();
  page.on('pageerror', (e) => { console.error(`page error: ${e.message}`); failed = true; });
  page.on('console', (m) => {
    if (m.type() !== 'error') return;
    console.error(`console: ${m.text()}`);
    failed = true;
  });
  await page.goto(`${url}/test/mesh.html`);
  await page.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
  const mesh = await page.evaluate((glb) => window.readMesh(glb), '/bake.glb');
  await writeFile(args.out, JSON.stringify(mesh));
  console.log(`three.js read ${mesh.positions.length / 3} vertices, ${mesh.triangles} triangles`);
} catch (e) {
  console.error(`mesh.mjs: ${e.message}`);
  failed = true;
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
