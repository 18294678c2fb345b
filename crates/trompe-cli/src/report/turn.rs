//! The report's interactive page: the Duck's octahedral bake (its self-contained `.glb`)
//! turned by the reader in the browser with trompe's three.js runtime (`web/trompe-octahedral.js`),
//! beside the exact renders of a turntable round it. One HTML file that opens from the disk:
//! the bake and the runtime are embedded in it, three.js comes from a CDN at the version the
//! runtime is tested with.

use super::ReportError;
use std::fmt::Write as _;
use std::path::Path;

/// The runtime, as the repository ships it.
const RUNTIME: &str = include_str!("../../../../web/trompe-octahedral.js");

/// The three.js version the runtime is tested with (web/package.json).
const THREE: &str = "0.187.0";

/// The page's lighting: the sky's radiance, the sun's direction and irradiance.
pub(super) struct PageLighting {
    pub sky: [f32; 3],
    pub sun_direction: [f32; 3],
    pub sun_irradiance: [f32; 3],
}

/// Writes `page` (an `.html` file in `out`) drawing the bake `glb` through `eye` toward
/// `target`, with `turntable` (image files beside it, with captions) shown below.
pub(super) fn write_page(
    out: &Path,
    page: &str,
    glb: &[u8],
    (eye, target): ([f32; 3], [f32; 3]),
    lighting: &PageLighting,
    turntable: &[(String, String)],
) -> Result<(), ReportError> {
    let bake = base64::encode(glb);
    let mut exact = String::new();
    for (file, caption) in turntable {
        let _ = write!(
            exact,
            "<figure><img src=\"{file}\" alt=\"{caption}\"><figcaption>{caption}</figcaption></figure>"
        );
    }
    let settings = serde_json::json!({
        "eye": eye, "target": target,
        "sky": lighting.sky, "sunDirection": lighting.sun_direction,
        "sunIrradiance": lighting.sun_irradiance,
    });
    let html = format!(
        r#"<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>trompe: the Duck's octahedral impostor, turned in the browser</title>
<style>body{{font-family:system-ui,sans-serif;max-width:1150px;margin:2em auto;padding:0 1em;color:#222}}
canvas{{border:1px solid #ddd;cursor:grab}}.row{{display:flex;flex-wrap:wrap;gap:.6em}}figure{{margin:0}}
figure img{{width:128px;border:1px solid #ddd}}figcaption{{font-size:.8em;color:#555}}#status{{color:#a00}}</style>
<script type="importmap">{{"imports":{{"three":"https://cdn.jsdelivr.net/npm/three@{THREE}/build/three.module.js",
"three/addons/":"https://cdn.jsdelivr.net/npm/three@{THREE}/examples/jsm/"}}}}</script></head>
<body><h1>The Duck's octahedral impostor, in three.js</h1>
<p>Drag to turn, scroll to zoom: each frame of the card is drawn by <code>web/trompe-octahedral.js</code>
from the bake <code>trompe impostor bake assets/gltf/Duck.glb --octahedral 16 -o duck.glb</code> writes
(16 × 16 frames blended three at a time, parallax-corrected, alpha-tested, lit by a sun and a sky).
Below, the exact renders of the mesh from 8 directions round it, lit alike. <a href="index.html">Back to the report</a>.</p>
<canvas id="view" width="512" height="512"></canvas><p id="status"></p>
<h2>The exact turntable</h2><div class="row">{exact}</div>
<script type="text/plain" id="runtime">{RUNTIME}</script>
<script type="application/octet-stream" id="bake">{bake}</script>
<script type="module">
import * as THREE from 'three';
import {{ GLTFLoader }} from 'three/addons/loaders/GLTFLoader.js';
import {{ OrbitControls }} from 'three/addons/controls/OrbitControls.js';
const settings = {settings};
const status = document.getElementById('status');
try {{
  const source = document.getElementById('runtime').textContent;
  const runtime = await import(URL.createObjectURL(new Blob([source], {{ type: 'text/javascript' }})));
  const text = document.getElementById('bake').textContent.trim();
  const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
  const gltf = await new GLTFLoader().parseAsync(bytes.buffer, '');
  const atlas = await runtime.readOctahedralAtlas(gltf);
  const canvas = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({{ canvas, antialias: true, preserveDrawingBuffer: true }});
  const scene = new THREE.Scene();
  scene.background = new THREE.Color().setRGB(...settings.sky, THREE.LinearSRGBColorSpace);
  scene.add(new runtime.OctahedralImpostor(atlas, 1, {{
    sunDirection: new THREE.Vector3(...settings.sunDirection),
    sunIrradiance: new THREE.Vector3(...settings.sunIrradiance),
    ambient: new THREE.Vector3(...settings.sky),
  }}));
  const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 100);
  camera.position.set(...settings.eye);
  const controls = new OrbitControls(camera, canvas);
  controls.target.set(...settings.target);
  controls.update();
  const draw = () => renderer.render(scene, camera);
  controls.addEventListener('change', draw);
  draw();
}} catch (e) {{
  status.textContent = `The page could not draw the impostor: ${{e.message}} (it needs WebGL 2, and three.js from cdn.jsdelivr.net).`;
}}
</script></body></html>
"#
    );
    let path = out.join(page);
    trompe::files::write_atomically(&path, html.as_bytes()).map_err(super::io_err(&path))
}
