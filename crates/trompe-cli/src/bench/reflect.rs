//! Reflection workloads (paper 1 §6, Tables 1 and 2): frame time against output resolution
//! and against impostor resolution on the teapot-in-bunny scene, with the longest image path
//! a reflected ray walks; every method on every reflection scene against `trace`; and the
//! secondary pass as the reflected mesh grows tenfold. Frames of the impostor method are timed
//! as a [`Sequence`] plays them: the first frame builds the impostors, the next ones keep them
//! (nothing deforms), as in the paper's interactive runs.

use super::BenchError;
use std::sync::Arc;
use std::time::{Duration, Instant};
use trompe::eval::fixtures::Shipped;
use trompe::frame::metrics;
use trompe::geom::Ray;
use trompe::geom::optics::{facing, reflect};
use trompe::render::{Method, Mirrors, Primary, RenderOptions, Sequence, Timings};
use trompe::scene::{Scene, Surface};
use trompe::trace::{Bvh, RayQuery};

/// The scenes of the method table, as `scenes/` names them.
pub const SCENES: [&str; 7] = [
    "teapot-in-bunny.toml",
    "intersecting.toml",
    "teapots.toml",
    "pinhole-misses.toml",
    "maze.toml",
    "reflections.toml",
    "room.toml",
];

/// All four tables.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ReflectTables {
    /// What ran.
    pub heading: String,
    /// Table 1: frame time against output resolution.
    pub by_output: Vec<OutputRow>,
    /// Table 2: frame time against impostor resolution.
    pub by_impostor: Vec<ImpostorRow>,
    /// Every method on every scene.
    pub methods: Vec<MethodRow>,
    /// The secondary pass as the reflected mesh grows.
    pub growth: Vec<GrowthRow>,
}

/// A row of Table 1.
#[derive(Clone, Debug, serde::Serialize)]
pub struct OutputRow {
    /// Pixels.
    pub size: (u32, u32),
    /// The first frame, impostors built.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub first: Duration,
    /// A later frame, impostors kept (median).
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub kept: Duration,
    /// The same, the primary pass rasterized (median).
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub rasterized: Duration,
    /// The same frame traced exactly (median).
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub trace: Duration,
}

/// A row of Table 2.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ImpostorRow {
    /// Texels a side.
    pub side: u32,
    /// Building and lighting the impostors.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub build: Duration,
    /// A frame with the impostors kept (median).
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub kept: Duration,
    /// Longest image path of a reflected ray through an impostor, in texels.
    pub max_projection: u64,
    /// Mean texels read a walk.
    pub mean_visits: f64,
    /// FLIP against `trace`.
    pub flip: f64,
}

/// A row of the method table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MethodRow {
    /// Scene file.
    pub scene: String,
    /// Method (and mirror choice).
    pub method: String,
    /// The tracing step less the same step with secondary rays answered by the environment.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub secondary: Duration,
    /// The whole frame, impostors built.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub frame: Duration,
    /// Against `trace`.
    pub flip: f64,
    /// Against `trace`, dB.
    pub psnr: f64,
}

/// A row of the growth table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GrowthRow {
    /// Triangles of the reflected mesh.
    pub triangles: usize,
    /// Secondary pass through impostors (kept), and through the exact BVH.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub impostor: Duration,
    /// Through the exact BVH.
    #[serde(serialize_with = "trompe::progress::serialize_seconds")]
    pub trace: Duration,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn step(timings: &Timings, name: &str) -> Duration {
    timings
        .0
        .iter()
        .filter(|(n, _)| *n == name)
        .map(|(_, d)| *d)
        .sum()
}

/// The median of `runs` frames of `sequence` at time `t` (after one that builds).
fn kept_frame(
    sequence: &mut Sequence<'_>,
    t: f32,
    runs: usize,
) -> Result<(Duration, Timings), BenchError> {
    let mut times = Vec::with_capacity(runs);
    let mut last = Timings::default();
    for _ in 0..runs {
        let start = Instant::now();
        let (_, timings, _) = sequence.frame(t, &())?;
        times.push(start.elapsed());
        last = timings;
    }
    times.sort();
    Ok((times[runs / 2], last))
}

/// Which rows the tables hold.
#[derive(Clone, Debug)]
pub struct Selection {
    /// Table 1's output resolutions.
    pub sizes: Vec<(u32, u32)>,
    /// Table 2's impostor sides.
    pub sides: Vec<u32>,
    /// The method table's scenes.
    pub scenes: Vec<&'static str>,
    /// Subdivision levels of the reflected bunny in the growth table.
    pub levels: Vec<u32>,
    /// Frames timed for each median.
    pub runs: usize,
}

impl Selection {
    /// Every row: what `trompe bench reflect` prints.
    pub fn full() -> Self {
        Self {
            sizes: vec![(640, 480), (800, 600), (1024, 768), (1280, 1024)],
            sides: vec![128, 256, 512, 1024],
            scenes: SCENES.to_vec(),
            levels: vec![0, 2],
            runs: 7,
        }
    }

    /// A row of each table: `--quick`.
    pub fn quick() -> Self {
        Self {
            sizes: vec![(640, 480)],
            sides: vec![256],
            scenes: SCENES[..2].to_vec(),
            levels: vec![0],
            runs: 3,
        }
    }

    /// The paper's two tables alone, at their ends (the demo report, which renders every
    /// scene by every method itself).
    pub fn paper_tables() -> Self {
        Self {
            sizes: vec![(640, 480), (1280, 1024)],
            sides: vec![128, 256, 512, 1024],
            scenes: Vec::new(),
            levels: Vec::new(),
            runs: 3,
        }
    }
}

/// The tables `selection` asks for, on the shipped scenes under `inputs`.
pub fn tables(inputs: &Shipped, selection: &Selection) -> Result<ReflectTables, BenchError> {
    let runs = selection.runs.max(1);
    let load = |name: &str| Scene::load(&inputs.scenes.join(name)).map_err(Box::new);
    let mut out = ReflectTables {
        heading: format!(
            "trompe bench reflect, {} threads",
            rayon::current_num_threads()
        ),
        ..Default::default()
    };
    let base = load("teapot-in-bunny.toml")?;
    let t = base.render.time;

    // Table 1: output resolution.
    for &size in &selection.sizes {
        let mut scene = base.clone();
        (scene.camera.width, scene.camera.height) = size;
        let mut sequence = Sequence::new(&scene, RenderOptions::new(Method::Impostor(512)));
        let start = Instant::now();
        sequence.frame(t, &())?;
        let first = start.elapsed();
        let (kept, _) = kept_frame(&mut sequence, t, runs)?;
        let options = RenderOptions::new(Method::Impostor(512)).primary(Primary::Rasterized);
        let mut sequence = Sequence::new(&scene, options);
        sequence.frame(t, &())?;
        let (rasterized, _) = kept_frame(&mut sequence, t, runs)?;
        let mut exact = Sequence::new(&scene, RenderOptions::new(Method::Trace));
        let (trace, _) = kept_frame(&mut exact, t, runs)?;
        out.by_output.push(OutputRow {
            size,
            first,
            kept,
            rasterized,
            trace,
        });
    }

    // Table 2: impostor resolution, at 640 × 480.
    let (truth, _, _) = Sequence::new(&base, RenderOptions::new(Method::Trace)).frame(t, &())?;
    for &side in &selection.sides {
        let mut sequence = Sequence::new(&base, RenderOptions::new(Method::Impostor(side)));
        let (frame, first, _) = sequence.frame(t, &())?;
        let (kept, _) = kept_frame(&mut sequence, t, runs)?;
        let (max_projection, mean_visits) = walk_lengths(&base, t, side)?;
        out.by_impostor.push(ImpostorRow {
            side,
            build: step(&first, "build, keep and light impostors"),
            kept,
            max_projection,
            mean_visits,
            flip: metrics::compare(&truth.color, &frame.color, None)?.flip,
        });
    }

    // Every method on every scene.
    let methods: [(&str, RenderOptions); 5] = [
        ("trace", RenderOptions::new(Method::Trace)),
        ("impostor", RenderOptions::new(Method::Impostor(512))),
        (
            "impostor, mirrors as impostors",
            RenderOptions::new(Method::Impostor(512)).mirrors(Mirrors::Impostor),
        ),
        (
            "pinhole-impostor",
            RenderOptions::new(Method::PinholeImpostor(512)),
        ),
        ("envmap", RenderOptions::new(Method::EnvMap)),
    ];
    for name in &selection.scenes {
        let scene = load(name)?;
        let t = scene.render.time;
        let mut frames = Vec::new();
        for (label, options) in methods {
            let start = Instant::now();
            let (frame, timings, _) = Sequence::new(&scene, options).frame(t, &())?;
            frames.push((label, frame, start.elapsed(), step(&timings, "trace")));
        }
        let environment = frames[frames.len() - 1].3;
        let reference = frames[0].1.color.clone();
        for (label, frame, wall, tracing) in frames {
            let score = metrics::compare(&reference, &frame.color, None)?;
            out.methods.push(MethodRow {
                scene: name.to_string(),
                method: label.to_string(),
                secondary: tracing.saturating_sub(environment),
                frame: wall,
                flip: score.flip,
                psnr: score.psnr,
            });
        }
    }

    // The secondary pass as the reflected mesh grows: the bunny of `c3rc-bunny.toml` as
    // shipped and subdivided twice (16× the triangles).
    let c3rc = load("c3rc-bunny.toml")?;
    for &level in &selection.levels {
        let mut scene = c3rc.clone();
        let Some(bunny) = scene
            .objects
            .iter_mut()
            .find(|o| matches!(o.surface, Surface::Diffuse(_)))
        else {
            continue;
        };
        let mut mesh = bunny.mesh.as_ref().clone();
        for _ in 0..level {
            mesh = mesh.subdivided();
        }
        let triangles = mesh.triangle_count();
        bunny.mesh = Arc::new(mesh);
        let t = scene.render.time;
        let secondary = |options: RenderOptions| -> Result<Duration, BenchError> {
            let mut sequence = Sequence::new(&scene, options);
            sequence.frame(t, &())?;
            let (_, timings) = kept_frame(&mut sequence, t, runs)?;
            Ok(step(&timings, "trace"))
        };
        let environment = secondary(RenderOptions::new(Method::EnvMap))?;
        let impostor = secondary(RenderOptions::new(Method::Impostor(512)))?;
        let trace = secondary(RenderOptions::new(Method::Trace))?;
        out.growth.push(GrowthRow {
            triangles,
            impostor: impostor.saturating_sub(environment),
            trace: trace.saturating_sub(environment),
        });
    }
    Ok(out)
}

/// The longest image path, in texels, of the rays the scene's mirrors reflect from the eye's
/// rays, walked through the impostors of `side²` texels built for them; and the mean texels
/// read a walk.
fn walk_lengths(scene: &Scene, t: f32, side: u32) -> Result<(u64, f64), BenchError> {
    let view = scene.view(t)?;
    let bvh = Bvh::build(view.meshes.clone())?;
    let mut timings = Timings::default();
    let answers = trompe::render::ReflectorImpostors::build(
        &view,
        &scene.lighting,
        trompe::render::ImpostorInputs::new(side),
        &mut timings,
    )?;
    let (w, h) = trompe::camera::Projection::resolution(&view.camera);
    let (mut longest, mut visits, mut walks) = (0u64, 0u64, 0u64);
    // Every fourth pixel each way: the longest path is a property of the scene, not of one ray.
    for y in (0..h).step_by(4) {
        for x in (0..w).step_by(4) {
            let ray = view
                .camera
                .ray(trompe::frame::pixel_centre(x as f64, y as f64));
            let Some(hit) = bvh.closest_hit(&ray, f32::INFINITY) else {
                continue;
            };
            if !matches!(view.surfaces[hit.object as usize], Surface::Mirror { .. }) {
                continue;
            }
            let (n, ng, _) = facing(ray.dir, hit.normal, hit.geometric_normal);
            let out = Ray::new(
                hit.position + ng * scene.render.ray_epsilon,
                reflect(ray.dir, n),
            );
            for imp in answers.of(hit.object) {
                let (_, stats) = imp.walk(&out, f32::INFINITY);
                longest = longest.max(stats.projection_length);
                visits += stats.texel_visits;
                walks += 1;
            }
        }
    }
    Ok((longest, visits as f64 / walks.max(1) as f64))
}

impl std::fmt::Display for ReflectTables {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}", self.heading)?;
        writeln!(
            f,
            "\nframe time against output resolution (paper 1 Table 1), teapot-in-bunny.toml, 512² impostors"
        )?;
        writeln!(
            f,
            "| pixels | first frame (impostors built) [ms] | later frame (kept) [ms] | kept, primary pass rasterized [ms] | frames/s (rasterized) | trace [ms] | kept / trace |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|")?;
        for r in &self.by_output {
            writeln!(
                f,
                "| {}×{} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} |",
                r.size.0,
                r.size.1,
                ms(r.first),
                ms(r.kept),
                ms(r.rasterized),
                1e3 / ms(r.rasterized).max(1e-9),
                ms(r.trace),
                ms(r.kept) / ms(r.trace).max(1e-9)
            )?;
        }
        writeln!(
            f,
            "\nframe time against impostor resolution (paper 1 Table 2), teapot-in-bunny.toml at 640×480"
        )?;
        writeln!(
            f,
            "| texels a side | build and light [ms] | later frame [ms] | longest ray projection [texels] | texels read a walk | FLIP vs trace |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|")?;
        for r in &self.by_impostor {
            writeln!(
                f,
                "| {} | {:.1} | {:.1} | {} | {:.1} | {:.4} |",
                r.side,
                ms(r.build),
                ms(r.kept),
                r.max_projection,
                r.mean_visits,
                r.flip
            )?;
        }
        writeln!(
            f,
            "\nevery method on every scene (first frames: impostors built); secondary pass = tracing step less the envmap method's"
        )?;
        writeln!(
            f,
            "| scene | method | secondary pass [ms] | frame [ms] | FLIP vs trace | PSNR [dB] |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|")?;
        for r in &self.methods {
            writeln!(
                f,
                "| {} | {} | {:.1} | {:.1} | {:.4} | {:.1} |",
                r.scene,
                r.method,
                ms(r.secondary),
                ms(r.frame),
                r.flip,
                r.psnr
            )?;
        }
        writeln!(
            f,
            "\nsecondary pass as the reflected mesh grows (c3rc-bunny.toml, 512² impostors kept)"
        )?;
        writeln!(
            f,
            "| reflected triangles | impostor [ms] | exact BVH [ms] | impostor / BVH |"
        )?;
        writeln!(f, "|---|---|---|---|")?;
        for r in &self.growth {
            writeln!(
                f,
                "| {} | {:.1} | {:.1} | {:.2} |",
                r.triangles,
                ms(r.impostor),
                ms(r.trace),
                ms(r.impostor) / ms(r.trace).max(1e-9)
            )?;
        }
        Ok(())
    }
}
