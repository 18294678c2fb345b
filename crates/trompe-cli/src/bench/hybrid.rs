//! Hybrid-reflection workloads (paper 2 Tables 1 and 2: a ~4000-triangle mirror teapot reflecting
//! a diffuse model, at two point densities each; the paper's Bunny0 frame took 264 ms on a 2006
//! GPU). Beside each: the same frame ray traced exactly through the BVH and with paper 1's
//! impostors, timed in the same run, with FLIP against the exact frame.

use super::BenchError;
use std::sync::Arc;
use std::time::{Duration, Instant};
use trompe::eval::fixtures::Shipped;
use trompe::frame::metrics;
use trompe::hybrid::{HybridReflections, HybridSettings, TreeStats};
use trompe::render::{Method, render_at};
use trompe::scene::Scene;

/// The models reflected, as the shipped assets name them.
pub const MODELS: [(&str, &str); 3] = [
    ("Bunny", "meshes/bunny.obj"),
    ("Dragon", "meshes/dragon_res4.obj"),
    ("Suzanne", "gltf/Suzanne.glb"),
];

/// One scene of the tables.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Model and density (`0` dense, `1` at twice the spacing).
    pub name: String,
    /// Points.
    pub points: usize,
    /// Their tree.
    pub tree: TreeStats,
    /// Time to build it.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub build: Duration,
    /// The hybrid frame (median of the runs), its statistics.
    pub stats: trompe::hybrid::FrameStats,
    /// The hybrid frame's wall time, everything included.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub frame: Duration,
    /// The same frame with the paper's algorithm (no level of detail, no occlusion by mirrors):
    /// culling and projection.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub paper_reflection: Duration,
    /// Its valid-projection ratio.
    pub paper_valid: f64,
    /// The exact frame's wall time.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub exact: Duration,
    /// The impostor frame's wall time.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub impostor: Duration,
    /// Mean FLIP against the exact frame: hybrid, hybrid without level of detail, impostors.
    pub flip: [f64; 3],
}

/// Both tables.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Tables {
    /// What ran.
    pub heading: String,
    /// One row a scene.
    pub rows: Vec<Row>,
}

/// The scene `c3rc-bunny.toml` with its bunny replaced by each model of [`MODELS`].
fn table_scenes(inputs: &Shipped) -> Result<Vec<(&'static str, Scene)>, BenchError> {
    let base = Scene::load(&inputs.scenes.join("c3rc-bunny.toml")).map_err(Box::new)?;
    let fit = base.objects[1].mesh.bounds().extent().max_element();
    MODELS
        .into_iter()
        .map(|(name, file)| {
            let mesh = trompe::geom::io::load(&inputs.assets.join(file))?.mesh;
            let mut scene = base.clone();
            scene.objects[1].mesh = Arc::new(fitted(&mesh, fit));
            scene.objects[1].name = name.to_string();
            Ok((name, scene))
        })
        .collect()
}

/// Paper 2 Table 2's frames by the `c3rc` method on the GPU (the `trompe_gpu::hybrid` pass),
/// each beside the same method on the CPU and beside the GPU's exact tracer, at 1920 × 1080
/// (`quick`: 320 × 240), each model at the dense spacing and at twice it.
pub fn gpu_frames(
    gpu: &trompe_gpu::Gpu,
    inputs: &Shipped,
    quick: bool,
) -> Result<Vec<super::Figure>, BenchError> {
    use trompe::methods::{MethodKind, MethodSettings};
    let (w, h) = if quick { (320, 240) } else { (1920, 1080) };
    let mut out = Vec::new();
    for (name, mut scene) in table_scenes(inputs)? {
        (scene.camera.width, scene.camera.height) = (w, h);
        let dense = HybridReflections::prepare(&scene, HybridSettings::default())?;
        let spacing = dense.clouds.first().map_or(0.01, |c| c.spacing);
        let exact = super::gpu::exact_frame_time(gpu, &scene)?;
        for (k, widen) in [1.0f32, 2.0].into_iter().enumerate() {
            let settings = MethodSettings {
                hybrid: HybridSettings {
                    spacing: Some(spacing * widen),
                    ..HybridSettings::default()
                },
                ..MethodSettings::default()
            };
            let on = |device| super::gpu::frame_time(device, &scene, MethodKind::C3rc, &settings);
            let (cpu, on_gpu) = (on(None)?, on(Some(gpu))?);
            let ms = on_gpu.as_secs_f64() * 1e3;
            for (peer, time) in [("CPU", cpu), ("the GPU's exact tracer", exact)] {
                out.push(super::Figure {
                    name: format!("c3rc, {name}{k} (paper 2 Table 2), {w} × {h}: GPU frame"),
                    value: ms,
                    unit: "ms",
                    versus: Some((
                        on_gpu.as_secs_f64() / time.as_secs_f64().max(1e-12),
                        peer.to_string(),
                    )),
                });
            }
        }
    }
    Ok(out)
}

/// The tables on the shipped scene `c3rc-bunny.toml`, its bunny replaced by each model.
pub fn tables(inputs: &Shipped, quick: bool) -> Result<Tables, BenchError> {
    let base = Scene::load(&inputs.scenes.join("c3rc-bunny.toml")).map_err(Box::new)?;
    let runs = if quick { 1 } else { 3 };
    let mut rows = Vec::new();
    for (name, scene) in table_scenes(inputs)? {
        let t = scene.render.time;
        let (exact, exact_time) = median_of(runs, || render_at(&scene, t, Method::Trace, &()))?;
        let (imp, impostor_time) =
            median_of(runs, || render_at(&scene, t, Method::Impostor(512), &()))?;
        let flip_imp = metrics::flip(&exact.0.color, &imp.0.color, None)?;
        let dense = HybridReflections::prepare(&scene, HybridSettings::default())?;
        let spacings: Vec<f32> = dense.clouds.iter().map(|c| c.spacing).collect();
        for (k, widen) in [1.0f32, 2.0].into_iter().enumerate() {
            let settings = HybridSettings {
                spacing: Some(spacings.first().copied().unwrap_or(0.01) * widen),
                ..HybridSettings::default()
            };
            let clouds = HybridReflections::prepare(&scene, settings)?;
            let Some(cloud) = clouds.clouds.first() else {
                continue;
            };
            let (hybrid, frame) = median_of(runs, || clouds.render_at(&scene, t, &()))?;
            let paper = HybridReflections {
                settings: HybridSettings {
                    level_of_detail: false,
                    mirrors_occlude: false,
                    ..settings
                },
                ..clouds.clone()
            };
            let (paper_frame, _) = median_of(1, || paper.render_at(&scene, t, &()))?;
            rows.push(Row {
                name: format!("{name}{k}"),
                points: cloud.points.len(),
                tree: cloud.tree.stats(),
                build: cloud.build_time,
                stats: hybrid.stats,
                frame,
                paper_reflection: paper_frame.stats.reflection_time(),
                paper_valid: paper_frame.stats.valid_ratio(),
                exact: exact_time,
                impostor: impostor_time,
                flip: [
                    metrics::flip(&exact.0.color, &hybrid.frame.color, None)?,
                    metrics::flip(&exact.0.color, &paper_frame.frame.color, None)?,
                    flip_imp,
                ],
            });
        }
    }
    Ok(Tables {
        heading: format!(
            "trompe bench c3rc: {} × {} frames, {} threads, {runs} runs a figure (median)",
            base.camera.width,
            base.camera.height,
            rayon::current_num_threads()
        ),
        rows,
    })
}

/// `mesh` scaled so its largest extent is `fit`, centred on `x = z = 0`, resting on `y = 0` (as
/// a scene's `fit` places it).
fn fitted(mesh: &trompe::geom::Mesh, fit: f32) -> trompe::geom::Mesh {
    use glam::{Mat4, Vec3};
    let b = mesh.bounds();
    let s = fit / b.extent().max_element().max(f32::MIN_POSITIVE);
    let base = Vec3::new(b.center().x, b.min.y, b.center().z);
    mesh.transformed(&(Mat4::from_scale(Vec3::splat(s)) * Mat4::from_translation(-base)))
}

/// Runs `f` `runs` times; the last result and the median wall time.
fn median_of<T, E>(runs: usize, mut f: impl FnMut() -> Result<T, E>) -> Result<(T, Duration), E> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        last = Some(f()?);
        times.push(start.elapsed());
    }
    times.sort();
    let median = times[times.len() / 2];
    match last {
        Some(v) => Ok((v, median)),
        None => unreachable!("runs.max(1) ≥ 1"),
    }
}

impl std::fmt::Display for Tables {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        writeln!(f, "{}", self.heading)?;
        writeln!(f, "\nkd-tree construction (paper 2 Table 1)")?;
        writeln!(
            f,
            "| scene | points | time [ms] | mean depth | points a leaf |"
        )?;
        writeln!(f, "|---|---|---|---|---|")?;
        for r in &self.rows {
            writeln!(
                f,
                "| {} | {} | {:.1} | {:.1} | {:.0} |",
                r.name,
                r.points,
                ms(r.build),
                r.tree.mean_depth,
                r.tree.points_per_leaf
            )?;
        }
        writeln!(
            f,
            "\nreflection rendering (paper 2 Table 2), 4000-triangle mirror teapot; times in ms"
        )?;
        writeln!(
            f,
            "| scene | culling | projection | valid | proj./point | frame | paper's algorithm: cull + project | valid | exact frame | impostor frame | FLIP hybrid | FLIP paper's | FLIP impostor |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|---|---|---|---|---|")?;
        for r in &self.rows {
            writeln!(
                f,
                "| {} | {:.1} | {:.1} | {:.0} % | {:.2} | {:.1} | {:.1} | {:.0} % | {:.1} | {:.1} | {:.4} | {:.4} | {:.4} |",
                r.name,
                ms(r.stats.cull),
                ms(r.stats.project),
                100.0 * r.stats.valid_ratio(),
                r.stats.projections_per_point(),
                ms(r.frame),
                ms(r.paper_reflection),
                100.0 * r.paper_valid,
                ms(r.exact),
                ms(r.impostor),
                r.flip[0],
                r.flip[1],
                r.flip[2]
            )?;
        }
        Ok(())
    }
}
