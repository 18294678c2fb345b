//! The `trompe` command line: clap definitions and thin glue over the library. No algorithm
//! lives here.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use trompe::eval::check::{BakedCheckSettings, CheckSettings, check_baked, check_built};
use trompe::files::OutputPlan;
use trompe::frame::{io, metrics};
use trompe::impostor::{BakeSettings, CameraChoice, Subject, ViewCamera, bake};
use trompe::render::{self, Method, Progress, Timings};
use trompe::scene::Scene;

/// Largest impostor side the CLI accepts: a square image within the frame limits
/// ([`trompe::frame::MAX_PIXELS`]).
const MAX_IMPOSTOR_SIDE: i64 = 8192;
/// The most worker threads `--threads` asks for (each reserves a stack).
const MAX_THREADS: usize = 1024;
/// The most rays `impostor check` fires from one source (bounds its memory: 32 bytes a ray).
const MAX_CHECK_RAYS: i64 = 10_000_000;

/// Impostor-based and image-based rendering on the CPU.
#[derive(Parser, Debug)]
#[command(name = "trompe", version, about)]
pub struct Cli {
    /// Worker threads (default: every core).
    #[arg(long, global = true)]
    pub threads: Option<usize>,
    /// Largest memory one input-sized allocation may take: a frame, an impostor, a decoded
    /// texture, a glTF scene's instances (e.g. 512M, 4G; default: half the machine's memory).
    #[arg(long, global = true, value_name = "SIZE", value_parser = trompe::memory::parse_size)]
    pub memory_limit: Option<u64>,
    /// Print per-step timings and loader warnings.
    #[arg(short, long, global = true)]
    pub verbose: bool,
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene file to an image.
    Render(RenderArgs),
    /// Compare two images: PSNR, SSIM and FLIP, and optionally a FLIP heat map.
    Compare {
        /// Reference image (.png, .exr or .hdr).
        reference: PathBuf,
        /// Test image.
        test: PathBuf,
        /// Also write the FLIP heat map here (PNG).
        #[arg(long)]
        heatmap: Option<PathBuf>,
        /// Only average over pixels where this image is non-black.
        #[arg(long)]
        mask: Option<PathBuf>,
    },
    /// Describe a mesh file (counts, bounds, materials, textures) or a baked impostor (its
    /// camera, size, coverage and box).
    Info {
        /// .obj, .ply, .gltf or .glb; or an impostor's .json sidecar.
        mesh: PathBuf,
    },
    /// Render the demo scenes and write an HTML report.
    Demo {
        /// Output directory.
        #[arg(short, long, default_value = "out/demo")]
        output: PathBuf,
    },
    /// Build, save and check impostors.
    #[command(subcommand)]
    Impostor(ImpostorCommand),
    /// Calibrated views: capture a model, texture it from views, score the result.
    #[command(subcommand)]
    Views(ViewsCommand),
    /// Measure throughput against peers measured in the same run.
    Bench {
        /// Shorter timings (less stable figures).
        #[arg(long)]
        quick: bool,
        /// Mesh to measure on (default: the shipped 56k-triangle bunny).
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// Time only the SPOC build's goal line (a fresh 512² SPOC impostor beside a depth +
        /// id rasterization through its reference pinhole), this many times, 3 s each; prints
        /// each ratio, then their range and median.
        #[arg(long, value_name = "RUNS",
              value_parser = clap::value_parser!(u32).range(1..=1000))]
        goal: Option<u32>,
    },
}

/// `trompe impostor …`.
#[derive(Subcommand, Debug)]
pub enum ImpostorCommand {
    /// Build an impostor of a mesh (or a maze, with --camera graph) and save it: a JSON
    /// sidecar, the EXR of its maps beside it, and a PNG preview of its colour.
    Bake(BakeArgs),
    /// Fire rays at an object and compare every impostor answer with the exact BVH.
    Check(CheckArgs),
}

/// `trompe views …`.
#[derive(Subcommand, Debug)]
pub enum ViewsCommand {
    /// Render calibrated views of a model with the exact tracer and write them as PNG images
    /// and a COLMAP text model (cameras.txt, images.txt).
    Capture(CaptureArgs),
    /// Leave each of some views out, render it from the others, and score it against its image
    /// (PSNR / SSIM / FLIP on covered pixels), for each weighting.
    Score(ScoreArgs),
    /// Render the mesh from a scene file's camera, textured from the views.
    Render(ViewsRenderArgs),
}

/// `trompe views capture`.
#[derive(clap::Args, Debug)]
pub struct CaptureArgs {
    /// The model (.obj, .ply, .gltf, .glb).
    mesh: PathBuf,
    /// Where the cameras stand.
    #[arg(long, value_enum, default_value_t = RigArg::Ring)]
    rig: RigArg,
    /// Number of views.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    count: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "320x240", value_parser = parse_size2)]
    size: (u32, u32),
    /// Camera distance from the model's centre, in bounding radii.
    #[arg(long, default_value_t = 3.0)]
    distance: f64,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 40.0)]
    fov: f64,
    /// Error in the recorded camera centres, in bounding radii.
    #[arg(long, default_value_t = 0.0, value_parser = parse_strength)]
    pose_noise: f64,
    /// Noise on every linear colour channel, uniform in ±this.
    #[arg(long, default_value_t = 0.0, value_parser = parse_strength)]
    colour_noise: f64,
    /// Output folder (made if missing; must be empty or hold an earlier capture).
    #[arg(short, long)]
    output: PathBuf,
}

/// `--rig`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum RigArg {
    /// Evenly over the sphere.
    Sphere,
    /// Over the upper hemisphere.
    Hemisphere,
    /// A horizontal circle, 15° up.
    Ring,
}

/// `--weights`.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum WeightsArg {
    /// Unstructured Lumigraph (angle + 0.1 × resolution penalty).
    Ulr,
    /// VDTM (inverse angle).
    Vdtm,
    /// Debevec's view map: at most three views a triangle, barycentric weights.
    ViewMap,
    /// One view a face, the largest projected area (a single-texture baseline).
    BestFace,
}

impl WeightsArg {
    fn weighting(self) -> trompe::views::Weighting {
        match self {
            WeightsArg::Ulr => trompe::views::Weighting::Ulr { beta: 0.1 },
            WeightsArg::Vdtm => trompe::views::Weighting::Vdtm,
            WeightsArg::ViewMap => trompe::views::Weighting::ViewMap,
            WeightsArg::BestFace => trompe::views::Weighting::BestFace,
        }
    }
}

/// `trompe views score`.
#[derive(clap::Args, Debug)]
pub struct ScoreArgs {
    /// The COLMAP model's folder (text or binary).
    model: PathBuf,
    /// The mesh, in the model's frame.
    #[arg(long)]
    mesh: PathBuf,
    /// The images' folder (default: the model's folder, or its images/).
    #[arg(long)]
    images: Option<PathBuf>,
    /// Weightings to score (default: all four).
    #[arg(long, value_enum, value_delimiter = ',')]
    weights: Vec<WeightsArg>,
    /// Most views blended at a point.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    k: u32,
    /// Score every N-th view (default: about 12 views in all).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    every: Option<u32>,
}

/// `trompe views render`.
#[derive(clap::Args, Debug)]
pub struct ViewsRenderArgs {
    /// The COLMAP model's folder (text or binary).
    model: PathBuf,
    /// The mesh, in the model's frame.
    #[arg(long)]
    mesh: PathBuf,
    /// The images' folder (default: the model's folder, or its images/).
    #[arg(long)]
    images: Option<PathBuf>,
    /// A scene file whose camera to render from (its objects are ignored).
    #[arg(long)]
    scene: PathBuf,
    /// Weighting.
    #[arg(long, value_enum, default_value_t = WeightsArg::Ulr)]
    weights: WeightsArg,
    /// Most views blended at a point.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    k: u32,
    /// Output image (.png or .exr); pixels no view sees are transparent.
    #[arg(short, long)]
    output: PathBuf,
}

/// Parses "WIDTHxHEIGHT".
fn parse_size2(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("{text:?}: expected WIDTHxHEIGHT"))?;
    let side = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (1..=trompe::frame::MAX_DIMENSION).contains(&v))
            .ok_or_else(|| format!("{text:?}: sides must be whole numbers from 1 to 16384"))
    };
    Ok((side(w)?, side(h)?))
}

impl CaptureArgs {
    fn capture(&self) -> Result<()> {
        use trompe::views::capture::{CaptureSettings, Rig, capture, write_capture};
        let out = &self.output;
        if out.exists() {
            let foreign = std::fs::read_dir(out)
                .with_context(|| format!("reading {}", out.display()))?
                .next()
                .is_some()
                && !out.join("cameras.txt").is_file();
            if foreign {
                bail!(
                    "{}: the folder holds files that are not a capture; give an empty or new folder",
                    out.display()
                );
            }
        }
        let mut plan = OutputPlan::new();
        plan.reads([&self.mesh])
            .writes(out.join("cameras.txt"), &["txt"])
            .creating_folders();
        check_plan(&plan)?;
        plan.make_folders()
            .with_context(|| format!("making {}", out.display()))?;
        let settings = CaptureSettings {
            rig: match self.rig {
                RigArg::Sphere => Rig::Sphere,
                RigArg::Hemisphere => Rig::Hemisphere,
                RigArg::Ring => Rig::Ring,
            },
            count: self.count as usize,
            size: self.size,
            distance: self.distance,
            fov_y: self.fov,
            pose_noise: self.pose_noise,
            colour_noise: self.colour_noise as f32,
            seed: 1,
        };
        let progress = bar("capturing", self.count as u64);
        let set = capture(&self.mesh, &settings, progress.as_ref())?;
        write_capture(out, &set)?;
        println!(
            "{} views of {} at {} × {} written to {} (COLMAP text model, images/)",
            set.views.len(),
            self.mesh.display(),
            self.size.0,
            self.size.1,
            out.display()
        );
        Ok(())
    }
}

impl ScoreArgs {
    fn score(&self) -> Result<()> {
        let mut set = trompe::views::ViewSet::load(&self.model, self.images.as_deref())?;
        for w in &set.warnings {
            eprintln!("warning: {w}");
        }
        set.load_images()?;
        let mesh = load_mesh(&self.mesh)?;
        let weights = if self.weights.is_empty() {
            vec![
                WeightsArg::Ulr,
                WeightsArg::Vdtm,
                WeightsArg::ViewMap,
                WeightsArg::BestFace,
            ]
        } else {
            self.weights.clone()
        };
        let weightings: Vec<_> = weights.iter().map(|w| w.weighting()).collect();
        let n = set.views.len();
        let every = self.every.map_or((n / 12).max(1), |e| e as usize);
        let which: Vec<usize> = (0..n).step_by(every).collect();
        let settings = trompe::views::BlendSettings {
            k: self.k as usize,
            ..Default::default()
        };
        let progress = bar("leaving out", which.len() as u64);
        let reports = trompe::views::score::leave_one_out(
            &set,
            &mesh,
            &settings,
            &weightings,
            &which,
            progress.as_ref(),
        )?;
        println!(
            "{n} views; each of {} left out and rendered from the others:",
            which.len()
        );
        for r in reports {
            println!("  {r}");
        }
        Ok(())
    }
}

impl ViewsRenderArgs {
    fn render(&self) -> Result<()> {
        let mut plan = OutputPlan::new();
        plan.reads([&self.mesh, &self.scene, &self.model])
            .writes(&self.output, &["png", "exr"]);
        check_plan(&plan)?;
        let mut set = trompe::views::ViewSet::load(&self.model, self.images.as_deref())?;
        set.load_images()?;
        let mesh = load_mesh(&self.mesh)?;
        let scene = Scene::load(&self.scene).context("loading the scene")?;
        let camera = scene.view(scene.render.time)?.camera;
        let depth = trompe::views::visibility::DepthMap::of_all(&set.views, &mesh)?;
        let settings = trompe::views::BlendSettings {
            weighting: self.weights.weighting(),
            k: self.k as usize,
            ..Default::default()
        };
        let b = trompe::views::blend::render(&camera, &mesh, &set.views, &depth, &settings, None)?;
        io::write_color(&self.output, &b.image)?;
        println!(
            "wrote {}: {} pixels show the mesh, {} of them seen by no view",
            self.output.display(),
            b.covered,
            b.holes
        );
        Ok(())
    }
}

/// `trompe impostor check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// The object (.obj, .ply, .gltf, .glb), in its own coordinates; or a floor plan (.maze)
    /// for --camera graph, with the reflector standing in its first corridor.
    mesh: PathBuf,
    /// Impostor camera.
    #[arg(long, value_enum, default_value_t = CameraArg::Spoc)]
    camera: CameraArg,
    /// SPOC strength k (default: the rule k = 2Δ/z_O from the reflector's region).
    #[arg(long, value_parser = parse_strength)]
    k: Option<f64>,
    /// Impostor resolution (square).
    #[arg(long, default_value_t = 512,
          value_parser = clap::value_parser!(u32).range(1..=MAX_IMPOSTOR_SIDE))]
    resolution: u32,
    /// The reflector whose reflected rays are fired (default: a built-in sphere), scaled to
    /// 0.8 of the object's largest extent.
    #[arg(long)]
    reflector: Option<PathBuf>,
    /// Distance between the object's and the reflector's centres, in the object's largest
    /// extents.
    #[arg(long, default_value_t = 1.4)]
    distance: f32,
    /// Resolution of the view of the reflector that spawns the rays.
    #[arg(long, default_value_t = 1024)]
    view: u32,
    /// Also fire this many rays from a sphere around the object, aimed at it.
    #[arg(long, default_value_t = 0,
          value_parser = clap::value_parser!(u32).range(0..=MAX_CHECK_RAYS))]
    sphere_rays: u32,
    /// Save the impostor (JSON sidecar; the EXR goes beside it).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Check this baked impostor (its JSON sidecar, from `impostor bake`) rather than
    /// building one. MESH is then the object it was baked from, in its own coordinates,
    /// and the rays come from around the impostor's viewpoint (`--region`) — for a graph
    /// camera, from the reflector in the maze's first corridor.
    #[arg(long, conflicts_with_all = ["camera", "k", "resolution", "output", "distance"])]
    impostor: Option<PathBuf>,
    /// With --impostor: radius of the region around its viewpoint the rays come from, in
    /// bounding radii of the object (`bake` chooses the SPOC strength for 1).
    #[arg(long, default_value_t = 1.0, requires = "impostor")]
    region: f32,
    /// With --impostor: how many rays come from that region.
    #[arg(long, default_value_t = 20_000, requires = "impostor",
          value_parser = clap::value_parser!(u32).range(1..=MAX_CHECK_RAYS))]
    rays: u32,
}

/// `trompe render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML; see scenes/README.md).
    scene: PathBuf,
    /// Output image: .png (sRGB) or .exr (linear float).
    #[arg(short, long)]
    output: PathBuf,
    /// Renderer.
    #[arg(long, value_enum, default_value_t = MethodArg::Trace)]
    method: MethodArg,
    /// Impostor resolution (square), for --method impostor.
    #[arg(long, default_value_t = render::DEFAULT_IMPOSTOR_RESOLUTION,
          value_parser = clap::value_parser!(u32).range(1..=MAX_IMPOSTOR_SIDE))]
    impostor_resolution: u32,
    /// Time in seconds (camera path and animation); default: the scene's.
    #[arg(long)]
    time: Option<f32>,
    /// Also write the depth (distance) as a float EXR.
    #[arg(long)]
    depth: Option<PathBuf>,
    /// Also write the shading normals as a float EXR.
    #[arg(long)]
    normals: Option<PathBuf>,
}

/// `trompe impostor bake`.
#[derive(clap::Args, Debug)]
pub struct BakeArgs {
    /// The object (.obj, .ply, .gltf, .glb), in its own coordinates; or a floor plan
    /// (.maze) for --camera graph.
    input: PathBuf,
    /// Impostor camera.
    #[arg(long, value_enum, default_value_t = CameraArg::Spoc)]
    camera: CameraArg,
    /// Impostor resolution (square).
    #[arg(long, default_value_t = 512,
          value_parser = clap::value_parser!(u32).range(1..=MAX_IMPOSTOR_SIDE))]
    resolution: u32,
    /// Direction from the object's centre toward the camera, "x,y,z".
    #[arg(long, default_value = "0,0.3,1", value_parser = parse_vec3)]
    from: glam::Vec3,
    /// Camera distance from the object's centre, in bounding-sphere radii.
    #[arg(long, default_value_t = 3.0)]
    distance: f32,
    /// SPOC strength k (default: the rule k = 2Δ/z_O with Δ one bounding radius).
    #[arg(long, value_parser = parse_strength)]
    k: Option<f64>,
    /// The sidecar to write (NAME.json; NAME.exr and NAME.png go beside it).
    #[arg(short, long)]
    output: PathBuf,
}

/// `--camera` of `impostor`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum CameraArg {
    /// Planar pinhole depth image.
    Pinhole,
    /// Parallel projection.
    Orthographic,
    /// Single-pole occlusion camera.
    Spoc,
    /// Graph camera following a maze's corridors (input: a .maze floor plan).
    Graph,
}

impl CameraArg {
    /// The library's name for this camera, with the SPOC strength when given.
    fn choice(self, k: Option<f64>) -> CameraChoice {
        match self {
            CameraArg::Pinhole => CameraChoice::Placed(ViewCamera::Pinhole),
            CameraArg::Orthographic => CameraChoice::Placed(ViewCamera::Orthographic),
            CameraArg::Spoc => CameraChoice::Placed(ViewCamera::Spoc(k)),
            CameraArg::Graph => CameraChoice::Graph,
        }
    }
}

/// Parses a SPOC strength: a finite, non-negative number.
fn parse_strength(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(k) if k.is_finite() && k >= 0.0 => Ok(k),
        Ok(_) => Err(format!("{text:?}: must be a finite number ≥ 0")),
        Err(e) => Err(format!("{text:?}: {e}")),
    }
}

/// Parses "x,y,z".
fn parse_vec3(text: &str) -> Result<glam::Vec3, String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{text:?}: {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("{text:?}: expected three finite numbers \"x,y,z\"")),
    }
}

/// Whether `path` ends in `.ext` (any case).
fn has_extension(path: &Path, ext: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(ext))
}

/// `--method`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MethodArg {
    /// Rasterize and shade (environment-mapped mirrors and glass).
    Raster,
    /// Whitted ray tracing through the exact BVH.
    Trace,
    /// Exact primary rays; rays from mirrors and glass answered by SPOC impostors of the diffuse
    /// objects (paper 1).
    Impostor,
}

impl MethodArg {
    /// The renderer, with the impostor resolution for `Impostor`.
    fn method(self, impostor_resolution: u32) -> Method {
        match self {
            MethodArg::Raster => Method::Raster,
            MethodArg::Trace => Method::Trace,
            MethodArg::Impostor => Method::Impostor(impostor_resolution),
        }
    }
}

/// A progress bar over rows.
struct Bar(ProgressBar);

impl Progress for Bar {
    fn advance(&self, rows: u64) {
        self.0.inc(rows);
    }
}

fn bar(label: &str, total: u64) -> Box<dyn Progress> {
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template("{msg:>28} [{bar:30}] {percent:>3}% {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(label.to_string());
    Box::new(Bar(pb))
}

/// Runs `work` under a spinner labelled `label` (for steps that report no progress of their
/// own, such as writing a large file); the spinner is cleared when it ends.
fn with_spinner<T>(label: &str, work: impl FnOnce() -> T) -> T {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    pb.set_message(label.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    let out = work();
    pb.finish_and_clear();
    out
}

/// Loads a mesh under a spinner (a large scan takes seconds to parse) and prints what the loader
/// survived (dropped degenerate triangles, skipped elements) as warnings.
fn load_mesh(path: &Path) -> Result<trompe::Mesh> {
    let label = format!("loading {}", path.display());
    let loaded = with_spinner(&label, || trompe::geom::io::load(path))?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    Ok(loaded.mesh)
}

/// Checks a command's outputs against what it reads, before any work ([`OutputPlan::check`]).
fn check_plan(plan: &OutputPlan) -> Result<()> {
    Ok(plan.check()?)
}

/// Prints the steps' durations (with `--verbose`).
fn print_timings(verbose: bool, t: &Timings) {
    if verbose {
        for (name, d) in &t.0 {
            eprintln!("  {name:<16} {:>9.1} ms", d.as_secs_f64() * 1e3);
        }
    }
}

/// Loads a mesh or a maze under a spinner, printing what the loader survived as warnings.
fn load_subject(path: &Path) -> Result<Subject> {
    let label = format!("loading {}", path.display());
    let (subject, warnings) = with_spinner(&label, || Subject::load(path))?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    Ok(subject)
}

/// A reflector given on the command line (and the files it read), or the built-in one.
fn load_reflector(path: Option<&Path>) -> Result<(Option<trompe::Mesh>, Vec<PathBuf>)> {
    let Some(path) = path else {
        return Ok((None, Vec::new()));
    };
    let label = format!("loading {}", path.display());
    let loaded = with_spinner(&label, || trompe::geom::io::load(path))?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    Ok((Some(loaded.mesh), loaded.files))
}

/// Writes a rendered frame: colour, and depth and normals when asked.
fn write_frame(
    frame: &trompe::Frame,
    output: &Path,
    depth: Option<&Path>,
    normals: Option<&Path>,
) -> Result<()> {
    io::write_color(output, &frame.color)?;
    if let Some(d) = depth {
        io::write_exr_depth(d, &frame.depth)?;
    }
    if let Some(n) = normals {
        io::write_exr_normals(n, &frame.normal)?;
    }
    Ok(())
}

/// Reads the mask of `compare --mask`: pixels where the image is non-black.
fn read_mask(path: Option<&Path>) -> Result<Option<trompe::Image<bool>>> {
    let Some(m) = path else { return Ok(None) };
    let img = io::read_color(m).with_context(|| format!("reading {}", m.display()))?;
    Ok(Some(img.map(|p| p.truncate().max_element() > 0.0)))
}

impl RenderArgs {
    /// Loads the scene, renders it, writes the images; prints what it wrote.
    fn render(self, verbose: bool) -> Result<()> {
        // Checked before loading, then again with everything the scene reads.
        let mut plan = OutputPlan::new();
        plan.reads([&self.scene])
            .writes(&self.output, &["png", "exr"]);
        for extra in [&self.depth, &self.normals].into_iter().flatten() {
            plan.writes(extra, &["exr"]);
        }
        plan.check_overwrites()?;
        let mut timings = Timings::default();
        let s = timings
            .time("load scene", || Scene::load(&self.scene))
            .context("loading the scene")?;
        check_plan(plan.reads(s.files.iter().cloned()))?;
        s.warnings.iter().for_each(|w| eprintln!("warning: {w}"));
        let method = self.method.method(self.impostor_resolution);
        let pb = bar(&format!("{method}"), s.camera.height as u64);
        let t = self.time.unwrap_or(s.render.time);
        let (frame, steps) = render::render_at(&s, t, method, pb.as_ref()).context("rendering")?;
        timings.0.extend(steps.0);
        let (depth, normals) = (self.depth.as_deref(), self.normals.as_deref());
        timings
            .time("write", || {
                write_frame(&frame, &self.output, depth, normals)
            })
            .context("writing the output")?;
        eprintln!("wrote {}", self.output.display());
        print_timings(verbose, &timings);
        Ok(())
    }
}

impl BakeArgs {
    /// Refuses outputs that are inputs, loads the input, bakes.
    fn bake(self) -> Result<trompe::impostor::BakeReport> {
        let mut plan = OutputPlan::new();
        plan.creating_folders()
            .reads([&self.input])
            .writes(&self.output, &["json"])
            .writes(self.output.with_extension("exr"), &["exr"])
            .writes(self.output.with_extension("png"), &["png"]);
        plan.check_overwrites()?;
        let subject = load_subject(&self.input)?;
        check_plan(plan.reads(subject.files()))?;
        plan.make_folders()
            .context("creating the output's folder")?;
        let settings = BakeSettings {
            camera: self.camera.choice(self.k),
            resolution: self.resolution,
            from: self.from,
            distance: self.distance,
        };
        let report = with_spinner("baking the impostor", || {
            bake(&subject, &settings, &self.output)
        })?;
        Ok(report)
    }
}

impl CheckArgs {
    /// Loads the inputs, checks, and returns what was measured.
    fn check(self) -> Result<trompe::eval::check::CheckReport> {
        let subject = load_subject(&self.mesh)?;
        let (reflector, reflector_files) = load_reflector(self.reflector.as_deref())?;
        let mut plan = OutputPlan::new();
        plan.reads(subject.files()).reads(reflector_files);
        if let Some(sidecar) = &self.impostor {
            plan.reads([sidecar.clone(), sidecar.with_extension("exr")]);
        }
        if let Some(o) = &self.output {
            plan.writes(o, &["json"])
                .writes(o.with_extension("exr"), &["exr"]);
        }
        check_plan(&plan)?;
        let Some(path) = &self.impostor else {
            let settings = CheckSettings {
                camera: self.camera.choice(self.k),
                resolution: self.resolution,
                reflector,
                distance: self.distance,
                view: self.view,
                sphere_rays: self.sphere_rays,
            };
            return Ok(check_built(&subject, &settings)?);
        };
        let baked = trompe::impostor::file::load(path).context("loading the impostor")?;
        let settings = BakedCheckSettings {
            reflector,
            view: self.view,
            region: self.region,
            rays: self.rays,
        };
        Ok(check_baked(&subject, baked, path, &settings)?)
    }
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<ExitCode> {
    if let Some(bytes) = cli.memory_limit {
        trompe::memory::set_limit(bytes);
    }
    if let Some(n) = cli.threads {
        if n == 0 || n > MAX_THREADS {
            bail!("--threads {n}: must be between 1 and {MAX_THREADS}");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("setting up the thread pool")?;
    }
    let verbose = cli.verbose;
    match cli.command {
        Command::Render(args) => args.render(verbose)?,
        Command::Compare {
            reference,
            test,
            heatmap,
            mask,
        } => {
            let mut plan = OutputPlan::new();
            plan.reads([&reference, &test]).reads(mask.iter());
            if let Some(h) = &heatmap {
                plan.writes(h, &["png"]);
            }
            check_plan(&plan)?;
            let read =
                |p: &Path| io::read_color(p).with_context(|| format!("reading {}", p.display()));
            let (a, b) = (read(&reference)?, read(&test)?);
            let mask = read_mask(mask.as_deref())?;
            let s = metrics::compare(&a, &b, mask.as_ref()).context("comparing")?;
            println!(
                "PSNR {:.3} dB\nSSIM {:.5}\nFLIP {:.5}",
                s.psnr, s.ssim, s.flip
            );
            if let Some(h) = heatmap {
                io::write_png(&h, &metrics::heat_map(&metrics::flip_map(&a, &b)?))?;
                eprintln!("wrote {}", h.display());
            }
        }
        Command::Info { mesh } if has_extension(&mesh, "json") => {
            let imp = trompe::impostor::file::load(&mesh).context("loading the impostor")?;
            println!("{}", imp.summary(&mesh));
        }
        Command::Info { mesh } => {
            let loaded = trompe::geom::io::load(&mesh)?;
            println!("{}", loaded.summary(&mesh));
            loaded
                .warnings
                .iter()
                .for_each(|w| eprintln!("warning: {w}"));
        }
        Command::Demo { output } => {
            let inputs = trompe::eval::fixtures::Shipped::locate();
            let summary = trompe::report::demo(&inputs, &output, &|label, rows| bar(label, rows))
                .context("building the demo report")?;
            println!("{summary}");
        }
        Command::Impostor(ImpostorCommand::Check(args)) => {
            let output = args.output.clone();
            let report = with_spinner("checking", || args.check())?;
            println!("{report}");
            if let Some(o) = &output {
                trompe::impostor::file::save(&report.impostor, o).context("saving the impostor")?;
                eprintln!("wrote {}", o.display());
            }
            print_timings(verbose, &report.timings);
        }
        Command::Impostor(ImpostorCommand::Bake(args)) => {
            let report = args.bake()?;
            println!("{report}");
            print_timings(verbose, &report.timings);
        }
        Command::Views(ViewsCommand::Capture(args)) => args.capture()?,
        Command::Views(ViewsCommand::Score(args)) => args.score()?,
        Command::Views(ViewsCommand::Render(args)) => args.render()?,
        Command::Bench { quick, mesh, goal } => {
            let inputs = trompe::eval::fixtures::Shipped::locate();
            let path = mesh.unwrap_or_else(|| inputs.assets.join("meshes/bunny.obj"));
            let m = load_mesh(&path)?;
            match goal {
                Some(runs) => println!("{}", trompe::bench::goal(&path, &m, runs)),
                None => println!("{}", trompe::bench::run(&path, &m, &inputs, quick)?),
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
