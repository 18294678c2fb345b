//! The demo report: `trompe demo` renders the scenes shipped in `scenes/` and writes
//! `index.html` with images and tables. Each issue adds its section here.
//!
//! Section "Foundation" (issue 2): every shipped scene by both methods, their agreement (PSNR,
//! SSIM, FLIP, object-id agreement) with the trace method as reference, and the FLIP heat map;
//! the shipped models' counts; rasterized depth against BVH depth on the bunny.

use crate::frame::metrics::{self, Scores};
use crate::frame::{Frame, FrameError, io};
use crate::render::{self, Method, Progress, RenderError};
use crate::scene::{Scene, SceneError};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;
use thiserror::Error;

/// Errors from building the report.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReportError {
    /// A shipped scene failed to load.
    #[error(transparent)]
    Scene(#[from] Box<SceneError>),
    /// Rendering failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// An image could not be written or compared.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// A shipped mesh failed to load.
    #[error(transparent)]
    Mesh(#[from] crate::geom::MeshError),
    /// The output directory could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

/// Where the report's inputs are: the repository's `scenes/` and `assets/`.
#[derive(Clone, Debug)]
pub struct DemoInputs {
    /// Directory holding the demo scenes.
    pub scenes: PathBuf,
    /// Directory holding the shipped models.
    pub assets: PathBuf,
}

impl DemoInputs {
    /// `scenes/` and `assets/` in the current directory if present, else beside this crate's
    /// manifest (so `cargo run -- demo` works from anywhere in the checkout).
    pub fn locate() -> DemoInputs {
        let here = PathBuf::from(".");
        let root = if here.join("scenes/diffuse.toml").is_file() {
            here
        } else {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        };
        DemoInputs {
            scenes: root.join("scenes"),
            assets: root.join("assets"),
        }
    }
}

/// One rendered scene/method pair.
#[derive(Clone, Debug)]
pub struct RenderRow {
    /// Scene name.
    pub scene: String,
    /// Method.
    pub method: Method,
    /// Wall-clock time of the render.
    pub time: Duration,
    /// Scores against the trace render of the same scene.
    pub scores: Scores,
    /// Fraction of pixels with the same object id as the trace render.
    pub id_agreement: f64,
}

/// What the demo measured (also printed by the CLI).
#[derive(Clone, Debug, Default)]
pub struct DemoSummary {
    /// Renders.
    pub renders: Vec<RenderRow>,
    /// The report file.
    pub index: PathBuf,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes the demo report into `out`; `progress(label, rows)` gives a progress sink per render.
pub fn demo(
    inputs: &DemoInputs,
    out: &Path,
    progress: &dyn Fn(&str, u64) -> Box<dyn Progress>,
) -> Result<DemoSummary, ReportError> {
    std::fs::create_dir_all(out).map_err(io_err(out))?;
    let mut html = String::new();
    let mut summary = DemoSummary::default();
    html.push_str(HEAD);
    html.push_str("<h1>trompe — demo report</h1>\n<p>Impostor-based and image-based rendering on the CPU. Every figure below was measured when this page was written.</p>\n");

    html.push_str("<h2>Foundation: ground-truth renderers</h2>\n");
    html.push_str("<p><b>raster</b> rasterizes through the pinhole camera and shades each pixel once (mirrors and glass are looked up in the panorama); <b>trace</b> is a Whitted ray tracer through the exact BVH (mirror reflection, refraction with Fresnel). Scores compare each image with the trace image. On the diffuse scene the two must agree: they share one shading model and differ only at silhouette pixels where a different triangle is visible.</p>\n");
    let mut table = String::from(
        "<table><tr><th>scene</th><th>method</th><th>time</th><th>PSNR (dB)</th><th>SSIM</th><th>FLIP</th><th>object ids equal</th></tr>\n",
    );
    for name in ["diffuse", "reflections"] {
        let path = inputs.scenes.join(format!("{name}.toml"));
        let scene = Scene::load(&path).map_err(Box::new)?;
        let (h, _) = (scene.camera.height, ());
        let mut frames: Vec<(Method, Frame, Duration)> = Vec::new();
        for method in [Method::Trace, Method::Raster] {
            let bar = progress(&format!("{name} ({method})"), h as u64);
            let start = std::time::Instant::now();
            let (frame, _) = render::render(&scene, method, bar.as_ref())?;
            frames.push((method, frame, start.elapsed()));
        }
        let reference = frames[0].1.clone();
        let _ = writeln!(
            html,
            "<h3>Scene <code>{name}.toml</code></h3>\n<div class=row>"
        );
        for (method, frame, time) in &frames {
            let file = format!("{name}-{method}.png");
            io::write_png(&out.join(&file), &frame.color)?;
            let scores = metrics::compare(&reference.color, &frame.color, None)?;
            let same = frame
                .object_id
                .pixels()
                .iter()
                .zip(reference.object_id.pixels())
                .filter(|(a, b)| a == b)
                .count() as f64
                / reference.object_id.pixels().len() as f64;
            let _ = writeln!(
                html,
                "<figure><img src=\"{file}\"><figcaption>{method}, {:.0} ms</figcaption></figure>",
                time.as_secs_f64() * 1e3
            );
            let _ = writeln!(
                table,
                "<tr><td>{name}</td><td>{method}</td><td>{:.0} ms</td><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{:.2} %</td></tr>",
                time.as_secs_f64() * 1e3,
                fmt_psnr(scores.psnr),
                scores.ssim,
                scores.flip,
                same * 100.0
            );
            summary.renders.push(RenderRow {
                scene: name.to_string(),
                method: *method,
                time: *time,
                scores,
                id_agreement: same,
            });
        }
        let heat = metrics::heat_map(&metrics::flip_map(&reference.color, &frames[1].1.color)?);
        let file = format!("{name}-flip.png");
        io::write_png(&out.join(&file), &heat)?;
        let _ = writeln!(
            html,
            "<figure><img src=\"{file}\"><figcaption>FLIP error, raster vs trace</figcaption></figure></div>"
        );
    }
    table.push_str("</table>\n");
    html.push_str(&table);

    html.push_str("<h3>Shipped models</h3>\n<table><tr><th>file</th><th>vertices (file)</th><th>triangles (file)</th><th>triangles kept</th><th>materials</th><th>textured</th></tr>\n");
    for rel in ["meshes/bunny.obj", "meshes/teapot.obj", "gltf/Duck.glb"] {
        let loaded = crate::geom::io::load(&inputs.assets.join(rel))?;
        let m = &loaded.mesh;
        let _ = writeln!(
            html,
            "<tr><td><code>{rel}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            loaded.source.vertices,
            loaded.source.triangles,
            m.triangle_count(),
            m.materials.len(),
            if m.materials.iter().any(|x| x.texture.is_some()) {
                "yes"
            } else {
                "no"
            }
        );
    }
    html.push_str("</table>\n");

    let bunny = crate::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let agreement = crate::validate::raster_vs_bvh(&bunny, 256)?;
    let _ = writeln!(
        html,
        "<h3>Rasterizer against the exact BVH (bunny, 256²)</h3>\n<table><tr><th>covered pixels</th><th>max relative depth error</th><th>item ids equal</th><th>coverage equal</th></tr>\n<tr><td>{}</td><td>{:.2e}</td><td>{:.3} %</td><td>{:.3} %</td></tr></table>",
        agreement.covered,
        agreement.max_relative_depth_error,
        agreement.id_agreement * 100.0,
        agreement.coverage_agreement * 100.0
    );
    html.push_str("</body></html>\n");
    let index = out.join("index.html");
    std::fs::write(&index, html).map_err(io_err(&index))?;
    summary.index = index;
    Ok(summary)
}

fn fmt_psnr(p: f64) -> String {
    if p.is_infinite() {
        "∞".into()
    } else {
        format!("{p:.2}")
    }
}

const HEAD: &str = "<!doctype html><html><head><meta charset=utf-8><title>trompe demo</title><style>
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:.3em .6em;text-align:right}
th{background:#f4f4f4}td:first-child,td:nth-child(2){text-align:left}
.row{display:flex;flex-wrap:wrap;gap:1em}figure{margin:0}img{max-width:340px;border:1px solid #ddd}
figcaption{font-size:.9em;color:#555}</style></head><body>\n";
