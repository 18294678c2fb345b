//! The demo report: `trompe demo` renders the scenes shipped in `scenes/` and writes
//! `index.html` with images and tables. Each issue adds its section here.
//!
//! Section "Foundation": every shipped scene by both methods, their agreement (PSNR,
//! SSIM, FLIP, object-id agreement) with the trace method as reference, and the FLIP heat map;
//! the shipped models' counts; rasterized depth against BVH depth on the bunny.
//!
//! Section "Non-pinhole impostors": pinhole and SPOC impostors of the teapot (colour and
//! gd false colour), their fidelity against the BVH — on a reflector's rays, and baked as
//! `impostor bake` does, on rays from around the viewpoint — and a mirror bunny whose reflected
//! rays are answered by the BVH, each impostor, or the environment alone.

use crate::frame::metrics::{self, Scores};
use crate::frame::{Frame, FrameError, io};
use crate::render::{self, Method, Progress, RenderError};
use crate::scene::{Scene, SceneError};
use glam::Vec3;
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
    /// A walk was asked of a camera it does not go with.
    #[error(transparent)]
    Walk(#[from] crate::impostor::WalkError),
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
    html.push_str("<p><b>raster</b> rasterizes through the pinhole camera and shades each pixel once (mirrors and glass are looked up in the panorama); <b>trace</b> is a Whitted ray tracer through the exact BVH (mirror reflection, refraction with Fresnel). Scores compare each image with the trace image. On the diffuse scene the two must agree: they share one shading model and differ only at silhouette pixels where a different triangle is visible. On the reflection scene, <b>impostor</b> is paper 1's method: primary rays as <b>trace</b>, and what the mirrors and the glass ball send out answered by 512² impostors of the diffuse objects built from each one's centre (a SPOC of the bunny, a parallel depth image of the ground), or by the panorama (<code>trompe render scenes/reflections.toml --method impostor</code>); the mirror and the glass ball see each other exactly, through a BVH of them alone. In the room scene the room is around the mirror: its impostor is a cube map of six pinhole depth images taken from the mirror's centre.</p>\n");
    let mut table = String::from(
        "<table><tr><th>scene</th><th>method</th><th>time</th><th>PSNR (dB)</th><th>SSIM</th><th>FLIP</th><th>object ids equal</th></tr>\n",
    );
    for name in ["diffuse", "reflections", "room"] {
        let path = inputs.scenes.join(format!("{name}.toml"));
        let scene = Scene::load(&path).map_err(Box::new)?;
        let h = scene.camera.height;
        let mut frames: Vec<(Method, Frame, Duration)> = Vec::new();
        let mut methods = vec![Method::Trace, Method::Raster];
        if name != "diffuse" {
            methods.push(Method::Impostor(crate::render::DEFAULT_IMPOSTOR_RESOLUTION));
        }
        for method in methods {
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
    let agreement = crate::eval::validate::raster_vs_bvh(&bunny, 256)?;
    let _ = writeln!(
        html,
        "<h3>Rasterizer against the exact BVH (bunny, 256²)</h3>\n<table><tr><th>covered pixels</th><th>max relative depth error</th><th>item ids equal</th><th>coverage equal</th></tr>\n<tr><td>{}</td><td>{:.2e}</td><td>{:.3} %</td><td>{:.3} %</td></tr></table>",
        agreement.covered,
        agreement.max_relative_depth_error,
        agreement.id_agreement * 100.0,
        agreement.coverage_agreement * 100.0
    );
    impostor_section(inputs, out, &mut html)?;
    maze_section(inputs, out, &mut html)?;
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

/// The colour the impostor section bakes into impostors and gives exact hits: an orange
/// Lambertian lit from one direction (view-independent, so exact and impostor agree).
fn teapot_color(n: Vec3) -> Vec3 {
    let l = Vec3::new(0.3, 0.8, 0.5).normalize();
    Vec3::new(0.9, 0.45, 0.15) * (0.25 + 0.75 * n.dot(l).max(0.0))
}

/// `gd` as a false-colour image: covered texels from dark (far) to bright (near), empty black.
fn gd_false_color(gd: &crate::frame::Image<f32>) -> crate::frame::Image<crate::frame::Rgba> {
    let covered = gd.pixels().iter().copied().filter(|&g| g > 0.0);
    let (lo, hi) = covered.fold((f32::INFINITY, 0.0f32), |(lo, hi), g| {
        (lo.min(g), hi.max(g))
    });
    let span = (hi - lo).max(f32::MIN_POSITIVE);
    metrics::heat_map(&gd.map(|g| {
        if g > 0.0 {
            0.15 + 0.85 * (g - lo) / span
        } else {
            0.0
        }
    }))
}

/// Section "Non-pinhole impostors" (paper 1 Fig. 1, 6–7).
/// The teapot in its own coordinates, baked as `trompe impostor bake` does by default (3 radii
/// away along (0, 0.3, 1)) through a pinhole and a SPOC, checked on 20 000 rays from the sphere
/// of 1/4, 1/2 and 1 bounding radius around the viewpoint (`trompe impostor check --impostor`).
fn viewpoint_table<F>(teapot: &crate::geom::Mesh, color: &F) -> Result<String, ReportError>
where
    F: Fn(&crate::impostor::SurfaceSample) -> Vec3 + Sync,
{
    use crate::eval::fidelity::{check, viewpoint_rays};
    use crate::impostor::ViewCamera;
    use crate::impostor::{ImpostorCamera, build};
    let from = Vec3::new(0.0, 0.3, 1.0);
    let mut impostors = Vec::new();
    for kind in [ViewCamera::Pinhole, ViewCamera::Spoc(None)] {
        let camera = ImpostorCamera::facing_mesh(kind, teapot, from, 3.0, 512).map_err(|e| {
            ReportError::Frame(FrameError::Codec {
                path: "teapot".into(),
                reason: e.to_string(),
            })
        })?;
        impostors.push(build(camera, teapot, 0, color)?);
    }
    let exact = crate::trace::Bvh::build(vec![std::sync::Arc::new(teapot.clone())]);
    let b = teapot.bounds();
    let mut html = String::from(
        "<h3>A baked impostor on rays from around its viewpoint</h3>\n<p>The teapot baked as <code>trompe impostor bake</code> does by default — 3 bounding radii away, the SPOC's strength chosen for rays from within one radius of its viewpoint — then checked as <code>trompe impostor check MESH --impostor FILE</code> does: 20 000 rays from points on a sphere around the viewpoint, aimed at points of the teapot's box. Close to the viewpoint the SPOC answers more rays that miss the teapot than the pinhole, which is walked exactly; from a radius out it misses fewer.</p>\n<table><tr><th>sphere radius (bounding radii)</th><th>rays</th><th>exact hits</th><th>pinhole: agreement, missed, spurious</th><th>SPOC: agreement, missed (by the walk), spurious</th></tr>\n",
    );
    for region in [0.25f32, 0.5, 1.0] {
        let rays = viewpoint_rays(&impostors[1], region * b.radius(), b, 20_000, 1);
        let [p, s] = [&impostors[0], &impostors[1]].map(|imp| check(imp, &exact, &rays));
        let _ = writeln!(
            html,
            "<tr><td>{region}</td><td>{}</td><td>{}</td><td>{:.2} %, {}, {}</td><td>{:.2} %, {} ({}), {}</td></tr>",
            s.rays,
            s.exact_hits,
            p.agreement() * 100.0,
            p.missed,
            p.spurious,
            s.agreement() * 100.0,
            s.missed,
            s.missed - s.missed_unheld,
            s.spurious
        );
    }
    html.push_str("</table>\n");
    Ok(html)
}

fn impostor_section(inputs: &DemoInputs, out: &Path, html: &mut String) -> Result<(), ReportError> {
    use crate::eval::fidelity::{self, ReflectorSetup};
    use crate::impostor::ViewCamera;
    use crate::impostor::{ImpostorCamera, build};
    let teapot = crate::geom::io::load(&inputs.assets.join("meshes/teapot.obj"))?.mesh;
    let bunny = crate::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
    let camera_error = |e: crate::camera::CameraError| {
        ReportError::Frame(FrameError::Codec {
            path: inputs.assets.clone(),
            reason: e.to_string(),
        })
    };
    html.push_str("<h2>Non-pinhole impostors (paper 1)</h2>\n<p>The Utah teapot (largest extent 1) is replaced by a 512² depth image built from the centre of a reflective bunny beside it: a pinhole depth image, and a single-pole occlusion camera (SPOC, docs/conventions.md §3.2) whose strength k = 2Δ/z<sub>O</sub> comes from the reflector's size Δ and distance z<sub>O</sub>. The SPOC pushes deeper samples away from the pole, so it sees around the silhouette.</p>\n");
    let color = |s: &crate::impostor::SurfaceSample| teapot_color(s.normal);
    let setup = ReflectorSetup::new(&teapot, &bunny, 1.4, 1024).map_err(camera_error)?;
    let exact = crate::trace::Bvh::build(vec![setup.target.clone()]);
    let rays = setup.rays();
    let mut impostors = Vec::new();
    let _ = writeln!(html, "<div class=row>");
    let mut table = String::from(
        "<table><tr><th>camera</th><th>k</th><th>rays</th><th>exact hits</th><th>agreement</th><th>agreement on hits</th><th>missed (by the walk)</th><th>spurious</th><th>error, mean / median (texel footprints)</th><th>surface captured (within 1.5 footprints / 1.5 texel extents)</th><th>texel visits / ray</th></tr>\n",
    );
    for kind in [ViewCamera::Pinhole, ViewCamera::Spoc(None)] {
        let cam = setup.camera(kind, 512).map_err(camera_error)?;
        let k = match &cam {
            ImpostorCamera::Spoc(s) => format!("{:.3}", s.strength()),
            _ => "—".into(),
        };
        let imp = build(cam, &setup.target, 0, &color)?;
        let name = imp.camera.kind();
        io::write_png(
            &out.join(format!("impostor-{name}-color.png")),
            &imp.color_image(),
        )?;
        io::write_png(
            &out.join(format!("impostor-{name}-gd.png")),
            &gd_false_color(&imp.gd),
        )?;
        let _ = writeln!(
            html,
            "<figure><img src=\"impostor-{name}-color.png\" style=\"max-width:256px\"><figcaption>{name}: colour</figcaption></figure><figure><img src=\"impostor-{name}-gd.png\" style=\"max-width:256px\"><figcaption>{name}: gd (bright = near)</figcaption></figure>"
        );
        let r = fidelity::check(&imp, &exact, &rays);
        let captured = fidelity::surface_captured(&imp, &setup.target, 50_000, 1);
        let _ = writeln!(
            table,
            "<tr><td>{name}</td><td>{k}</td><td>{}</td><td>{}</td><td>{:.2} %</td><td>{:.2} %</td><td>{} ({})</td><td>{}</td><td>{:.2} / {:.1e}</td><td>{:.1} % / {:.1} %</td><td>{:.1}</td></tr>",
            r.rays,
            r.exact_hits,
            r.agreement() * 100.0,
            r.hit_agreement() * 100.0,
            r.missed,
            r.missed - r.missed_unheld,
            r.spurious,
            r.mean_error_footprints,
            r.median_error_footprints,
            captured.within_footprint * 100.0,
            captured.within_texel * 100.0,
            r.texel_visits_per_ray
        );
        impostors.push(imp);
    }
    html.push_str("</div>\n<h3>Fidelity against the exact BVH (reflected rays of the bunny that enter the teapot's box)</h3>\n");
    table.push_str("</table>\n");
    html.push_str(&table);
    html.push_str("<p>A ray agrees when both miss, or both hit within 1.5 texel footprints. trompe's goal is SPOC ≥ 99 %. A missed ray is the walk's (in brackets) when the impostor holds the exact hit — its texel stores a point within 1.5 footprints of it — and the camera's otherwise. The paper reports that its SPOC captures “about half of the teapot”; ours captures the fractions above, measured two ways: a surface sample counts when its texel stores a point within 1.5 footprints of it (strict, the ray test's tolerance), or within 1.5 times the texel's extent on that surface (a texel on a grazing surface covers more of it). From one viewpoint a convex object shows at most half of its surface.</p>\n");

    // How agreement varies with the reflector's distance (nearer = wider spread of ray origins).
    let mut by_distance = String::from(
        "<table><tr><th>bunny–teapot centre distance</th><th>rays</th><th>pinhole agreement</th><th>SPOC agreement</th></tr>\n",
    );
    for distance in [1.1f32, 1.4, 1.8] {
        let s = ReflectorSetup::new(&teapot, &bunny, distance, 1024).map_err(camera_error)?;
        let exact = crate::trace::Bvh::build(vec![s.target.clone()]);
        let rays = s.rays();
        let mut cells = Vec::new();
        for kind in [ViewCamera::Pinhole, ViewCamera::Spoc(None)] {
            let imp = build(
                s.camera(kind, 512).map_err(camera_error)?,
                &s.target,
                0,
                &color,
            )?;
            cells.push(fidelity::check(&imp, &exact, &rays).agreement());
        }
        let _ = writeln!(
            by_distance,
            "<tr><td>{distance}</td><td>{}</td><td>{:.2} %</td><td>{:.2} %</td></tr>",
            rays.len(),
            cells[0] * 100.0,
            cells[1] * 100.0
        );
    }
    by_distance.push_str("</table>\n");
    html.push_str("<h3>Agreement against reflector distance</h3>\n");
    html.push_str(&by_distance);

    // A baked impostor's check: rays from around its viewpoint.
    html.push_str(&viewpoint_table(&teapot, &color)?);

    // The mirror view: the same frame, one renderer, with reflected rays answered four ways.
    let view_setup = ReflectorSetup::new(&teapot, &bunny, 1.4, 400).map_err(camera_error)?;
    let env =
        crate::frame::envmap::EnvMap::load(&inputs.assets.join("envmaps/studio.hdr"), 0.0, 0.6)?;
    let lighting = crate::scene::Lighting {
        environment: env,
        light: Some(crate::scene::Light {
            direction: Vec3::new(0.3, 0.8, 0.5).normalize(),
            radiance: Vec3::splat(0.75),
        }),
    };
    let orange = crate::scene::Surface::Diffuse(Some(crate::scene::DiffuseOverride {
        color: Vec3::new(0.9, 0.45, 0.15),
        texture: None,
    }));
    let mirror_view = crate::scene::View {
        camera: view_setup.view.clone(),
        meshes: vec![view_setup.target.clone(), view_setup.reflector.clone()],
        surfaces: vec![orange, crate::scene::Surface::Mirror { tint: Vec3::ONE }],
    };
    let settings = crate::scene::RenderSettings {
        max_depth: 4,
        time: 0.0,
        ray_epsilon: 1e-4,
    };
    let primary = crate::trace::Bvh::build(mirror_view.meshes.clone());
    let render_with =
        |secondary: &dyn crate::trace::SecondaryQuery| -> Result<crate::frame::Frame, ReportError> {
            let tracer = crate::render::Tracer {
                view: &mirror_view,
                primary: &primary,
                secondary,
                lighting: &lighting,
                settings: &settings,
            };
            Ok(crate::render::render_trace(&tracer, &())?)
        };
    let exact_frame = render_with(&crate::trace::Exact(&primary))?;
    let reference = exact_frame.color.clone();
    let mask = exact_frame.object_id.map(|id| id == 1);
    io::write_png(&out.join("mirror-exact.png"), &reference)?;
    // The tracer's diffuse shading baked into each impostor, as `render --method impostor` does.
    let eye = view_setup.reflector.bounds().center();
    let shaded = |s: &crate::impostor::SurfaceSample| {
        let n = if s.normal.dot(eye - s.position) < 0.0 {
            -s.normal
        } else {
            s.normal
        };
        crate::render::shading::lambert(Vec3::new(0.9, 0.45, 0.15), n, &lighting)
    };
    let mut answers = Vec::new();
    for kind in [ViewCamera::Spoc(None), ViewCamera::Pinhole] {
        let imp = build(
            view_setup.camera(kind, 512).map_err(camera_error)?,
            &view_setup.target,
            0,
            &shaded,
        )?;
        answers.push(crate::render::ReflectorImpostors::from_impostors(
            &mirror_view,
            vec![Vec::new(), vec![imp]],
        ));
    }
    let mut row = String::from(
        "<div class=row><figure><img src=\"mirror-exact.png\"><figcaption>reflected rays traced in the exact BVH</figcaption></figure>\n",
    );
    let mut scores_table = String::from(
        "<table><tr><th>reflected rays answered by</th><th>PSNR (dB)</th><th>SSIM</th><th>FLIP</th></tr>\n",
    );
    for (i, label) in ["SPOC impostor", "pinhole impostor", "environment map only"]
        .into_iter()
        .enumerate()
    {
        let frame = match answers.get(i) {
            Some(a) => render_with(a)?,
            None => render_with(&crate::trace::EnvironmentOnly)?,
        };
        let img = frame.color;
        let file = format!("mirror-{i}.png");
        io::write_png(&out.join(&file), &img)?;
        let sc = metrics::compare(&reference, &img, Some(&mask))?;
        let _ = writeln!(
            row,
            "<figure><img src=\"{file}\"><figcaption>{label}</figcaption></figure>"
        );
        let _ = writeln!(
            scores_table,
            "<tr><td>{label}</td><td>{}</td><td>{:.4}</td><td>{:.4}</td></tr>",
            fmt_psnr(sc.psnr),
            sc.ssim,
            sc.flip
        );
    }
    row.push_str("</div>\n");
    scores_table.push_str("</table>\n");
    html.push_str("<h3>The bunny as a mirror (paper 1, Fig. 1)</h3>\n<p>Primary rays see the exact scene; only the rays reflected by the bunny are answered differently. Scores compare each image with the exact one over the bunny's pixels.</p>\n");
    html.push_str(&row);
    html.push_str(&scores_table);
    Ok(())
}

/// Draws a line segment into an image (image coordinates), clipped to it.
fn draw_line(
    img: &mut crate::frame::Image<crate::frame::Rgba>,
    a: glam::DVec2,
    b: glam::DVec2,
    color: crate::frame::Rgba,
) {
    let steps = (b - a).abs().max_element().ceil().clamp(1.0, 1e5) as usize;
    let (w, h) = img.size();
    for i in 0..=steps {
        let p = a.lerp(b, i as f64 / steps as f64);
        if p.x >= 0.0 && p.y >= 0.0 && p.x < w as f64 && p.y < h as f64 {
            img.set(p.x as u32, p.y as u32, color);
        }
    }
}

/// The closed outline, seen from above (`x`, `z`), of the convex hull of `points`.
fn floor_hull(points: &[glam::DVec3]) -> Vec<glam::DVec3> {
    let flat: Vec<glam::DVec2> = points.iter().map(|q| glam::DVec2::new(q.x, q.z)).collect();
    let hull = crate::geom::convex_hull(&flat);
    hull.iter()
        .chain(hull.first())
        .map(|&i| glam::DVec3::new(points[i].x, 0.0, points[i].z))
        .collect()
}

/// Section "Graph camera" (paper 1 Fig. 4 and 9): the maze's graph-camera impostor,
/// and a top view with the frusta drawn.
fn maze_section(inputs: &DemoInputs, out: &Path, html: &mut String) -> Result<(), ReportError> {
    use crate::camera::{Orthographic, Projection};
    use crate::impostor::{ImpostorCamera, build};
    use crate::raster::{Fragment, FragmentShader, rasterize};
    let path = inputs.scenes.join("maze.maze");
    let frame_err = |reason: String| {
        ReportError::Frame(FrameError::Codec {
            path: path.clone(),
            reason,
        })
    };
    let maze = crate::scene::maze::Maze::load(&path).map_err(|e| frame_err(e.to_string()))?;
    let g = maze
        .graph_camera(768, &path)
        .map_err(|e| frame_err(e.to_string()))?;
    let mesh = maze.mesh();
    // Each wall orientation lit differently, and alternate cells a little darker (a point of a
    // wall face is given to the cell behind the face), so the unfolded corridors read in depth.
    let light = Vec3::new(0.5, 0.8, 0.3).normalize();
    let albedo = crate::impostor::albedo_of(&mesh);
    let color = |s: &crate::impostor::SurfaceSample| {
        let lit = 0.55 + 0.45 * s.normal.dot(light);
        let cell = s.position - 0.5 * s.normal;
        let odd = (cell.x.floor() + cell.z.floor()).rem_euclid(2.0) > 0.5;
        albedo(s) * lit * if odd { 0.82 } else { 1.0 }
    };
    let imp = build(ImpostorCamera::Graph(g.clone()), &mesh, 0, &color)?;
    io::write_png(&out.join("maze-graph-camera.png"), &imp.color_image())?;
    let splits = g.frusta().iter().filter(|f| f.children.len() >= 2).count();

    // Fidelity in the paper's Fig. 5 setting: a mirror bunny in the first corridor.
    let fidelity = {
        use crate::eval::fidelity::{ReflectorSetup, check_with};
        use crate::impostor::WalkMode;
        let bunny = crate::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
        let setup =
            ReflectorSetup::in_maze(&maze, &bunny, 384).map_err(|e| frame_err(e.to_string()))?;
        let exact = crate::trace::Bvh::build(vec![setup.target.clone()]);
        let rays = setup.rays();
        let mut rows = String::new();
        for (name, mode) in [
            ("algorithm 2 (exact, per frustum)", WalkMode::Exact),
            ("algorithm 1 (uniform 3-D steps)", WalkMode::Linear),
        ] {
            let r = check_with(&imp, &exact, &rays, mode)?;
            let _ = write!(
                rows,
                "<tr><td>{name}</td><td>{}</td><td>{:.2} %</td><td>{:.2} %</td><td>{:.2} / {:.1e}</td><td>{:.0}</td></tr>",
                r.rays,
                r.agreement() * 100.0,
                r.hit_agreement() * 100.0,
                r.mean_error_footprints,
                r.median_error_footprints,
                r.texel_visits_per_ray
            );
        }
        rows
    };

    // Top view: an orthographic camera looking down, the frusta drawn over it.
    let (w, h) = (maze.width() as f32, maze.height() as f32);
    let centre = Vec3::new(w / 2.0, 5.0, h / 2.0);
    let top = Orthographic::look_at(
        centre,
        centre - Vec3::Y,
        -Vec3::Z,
        (w.max(h) * 0.55) as f64,
        20.0,
        384,
        384,
    )
    .map_err(|e| frame_err(e.to_string()))?;
    struct Shade<'a, F> {
        mesh: &'a crate::geom::Mesh,
        color: &'a F,
    }
    impl<F: Fn(&crate::impostor::SurfaceSample) -> Vec3 + Sync> FragmentShader for Shade<'_, F> {
        type Output = crate::frame::Rgba;
        fn shade(&self, f: &Fragment) -> crate::frame::Rgba {
            let t = f.item.triangle as usize;
            let [a, b, c] = self.mesh.triangles[t].map(|i| i as usize);
            let p = self.mesh.positions[a] * f.bary.x
                + self.mesh.positions[b] * f.bary.y
                + self.mesh.positions[c] * f.bary.z;
            let s = crate::impostor::SurfaceSample {
                position: p,
                normal: self.mesh.face_normal(t),
                uv: glam::Vec2::ZERO,
                triangle: t as u32,
            };
            (self.color)(&s).extend(1.0)
        }
    }
    let (target, _) = rasterize(
        &top,
        &[&mesh],
        &Shade {
            mesh: &mesh,
            color: &color,
        },
        crate::frame::Rgba::ONE,
    )?;
    let mut view = target.attributes;
    let red = crate::frame::Rgba::new(1.0, 0.05, 0.05, 1.0);
    let yellow = crate::frame::Rgba::new(1.0, 0.9, 0.1, 1.0);
    let at = |p: glam::DVec3| top.project(glam::DVec3::new(p.x, 4.0, p.z)).map(|q| q.uv);
    // Each frustum's outline (red; the root yellow): its entry face and the faces where its
    // children begin, seen from above; then a few generalized rays (white, Fig. 9).
    for (k, f) in g.frusta().iter().enumerate() {
        let colour = if k == 0 { yellow } else { red };
        let mut outline: Vec<glam::DVec3> = f.entry_face.clone();
        if f.entry_face.is_empty() {
            outline.push(f.apex);
        }
        for &c in &f.children {
            outline.extend_from_slice(&g.frusta()[c].entry_face);
        }
        if f.children.is_empty() {
            outline.extend(
                f.entry_face
                    .iter()
                    .map(|v| *v + (*v - f.apex).normalize() * 3.0),
            );
        }
        for hull_edge in floor_hull(&outline).windows(2) {
            if let (Some(a), Some(b)) = (at(hull_edge[0]), at(hull_edge[1])) {
                draw_line(&mut view, a, b, colour);
            }
        }
    }
    let white = crate::frame::Rgba::ONE;
    let (gw, gh) = g.resolution();
    for i in 0..9 {
        let uv = glam::DVec2::new((i as f64 + 0.5) / 9.0 * gw as f64, gh as f64 * 0.55);
        for seg in g.ray_path(uv, 3.0).windows(2) {
            if let (Some(a), Some(b)) = (at(seg[0]), at(seg[1])) {
                draw_line(&mut view, a, b, white);
            }
        }
    }
    io::write_png(&out.join("maze-frusta.png"), &view)?;
    let _ = writeln!(
        html,
        "<h2>Graph camera (paper 1 §5)</h2>\n<p>A graph camera built from <code>scenes/maze.maze</code> by a breadth-first walk of its corridors from the entrance (docs/conventions.md §4): {} frusta — a bend at every turn, a split at each of the {} junctions. Left: the impostor it builds, every corridor the walk reached in one continuous image (deeper corridors get fewer pixels, as in the paper's Fig. 12). Right: the maze from above, each frustum outlined between its entry face and the faces of its children (root in yellow), and a few generalized rays in white (Fig. 9).</p>\n<div class=row><figure><img src=\"maze-graph-camera.png\"><figcaption>graph-camera impostor, {:.1} % of texels covered</figcaption></figure><figure><img src=\"maze-frusta.png\"><figcaption>frusta over the maze</figcaption></figure></div>\n<p>Reflected rays of a mirror bunny standing in the first corridor (Fig. 5), answered by the impostor and by the exact BVH (<code>trompe impostor check scenes/maze.maze --camera graph</code>):</p>\n<table><tr><th>walk</th><th>rays</th><th>agreement</th><th>on hits</th><th>error, mean / median (texel footprints)</th><th>texel visits / ray</th></tr>{}</table>",
        g.frusta().len(),
        splits,
        imp.coverage() * 100.0,
        fidelity
    );
    Ok(())
}

impl std::fmt::Display for DemoSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for r in &self.renders {
            writeln!(
                f,
                "{:<12} {:<7} {:>8.0} ms  PSNR {:>6.2}  SSIM {:.4}  FLIP {:.4}  ids {:.2} %",
                r.scene,
                r.method.to_string(),
                r.time.as_secs_f64() * 1e3,
                r.scores.psnr,
                r.scores.ssim,
                r.scores.flip,
                r.id_agreement * 100.0
            )?;
        }
        write!(f, "wrote {}", self.index.display())
    }
}
