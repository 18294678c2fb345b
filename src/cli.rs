//! The `trompe` command line: clap definitions and thin glue over the library. No algorithm
//! lives here.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use trompe::frame::{io, metrics};
use trompe::impostor::fidelity;
use trompe::render::{self, Method, Progress, Timings};
use trompe::scene::Scene;

/// Largest impostor side the CLI accepts: a square image within the frame limits
/// ([`trompe::frame::MAX_PIXELS`]).
const MAX_IMPOSTOR_SIDE: i64 = 8192;
/// The most rays `impostor check` fires from one source (bounds its memory: 32 bytes a ray).
const MAX_CHECK_RAYS: i64 = 10_000_000;

/// Impostor-based and image-based rendering on the CPU.
#[derive(Parser, Debug)]
#[command(name = "trompe", version, about)]
pub struct Cli {
    /// Worker threads (default: every core).
    #[arg(long, global = true)]
    pub threads: Option<usize>,
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
    Render {
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
    },
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
    /// Measure throughput against peers measured in the same run.
    Bench {
        /// Shorter timings (less stable figures).
        #[arg(long)]
        quick: bool,
        /// Mesh to measure on (default: the shipped 56k-triangle bunny).
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// Time only the goal's line of issue 3 (a fresh 512² SPOC impostor beside a depth +
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
    Bake {
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
        #[arg(long)]
        k: Option<f64>,
        /// The sidecar to write (NAME.json; NAME.exr and NAME.png go beside it).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Fire rays at an object and compare every impostor answer with the exact BVH.
    Check {
        /// The object (.obj, .ply, .gltf, .glb), scaled to largest extent 1; or a floor plan
        /// (.maze) for --camera graph, with the reflector standing in its first corridor.
        mesh: PathBuf,
        /// Impostor camera.
        #[arg(long, value_enum, default_value_t = CameraArg::Spoc)]
        camera: CameraArg,
        /// SPOC strength k (default: the rule k = 2Δ/z_O from the reflector's region).
        #[arg(long)]
        k: Option<f64>,
        /// Impostor resolution (square).
        #[arg(long, default_value_t = 512,
              value_parser = clap::value_parser!(u32).range(1..=MAX_IMPOSTOR_SIDE))]
        resolution: u32,
        /// The reflector whose reflected rays are fired (default: the shipped bunny).
        #[arg(long)]
        reflector: Option<PathBuf>,
        /// Distance between the object's and the reflector's centres.
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
    },
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
    fn view(self, k: Option<f64>) -> Option<trompe::impostor::ViewCamera> {
        use trompe::impostor::ViewCamera;
        match self {
            CameraArg::Pinhole => Some(ViewCamera::Pinhole),
            CameraArg::Orthographic => Some(ViewCamera::Orthographic),
            CameraArg::Spoc => Some(ViewCamera::Spoc(k)),
            CameraArg::Graph => None,
        }
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

/// Whether `path` names a maze floor plan.
fn is_maze(path: &Path) -> bool {
    has_extension(path, "maze")
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

/// Refuses an output path that is one of the inputs: nothing a user gave is overwritten.
fn check_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    let canon = |p: &Path| std::fs::canonicalize(p).ok();
    if let Some(o) = canon(output) {
        for i in inputs {
            if canon(i).as_ref() == Some(&o) {
                bail!("{}: refusing to overwrite an input file", output.display());
            }
        }
    }
    Ok(())
}

/// Where `impostor check` takes its rays from.
enum RaySource {
    /// The reflected rays of a reflector beside the object (a mesh's is placed `distance`
    /// away; in a maze it stands in the first corridor), seen by a `view²` viewer.
    Reflector {
        path: PathBuf,
        distance: f32,
        view: u32,
    },
    /// For a baked impostor: `rays` rays from the sphere of `region` bounding radii around its
    /// viewpoint; for a graph camera, the reflector's rays in the maze as above.
    Viewpoint {
        reflector: PathBuf,
        view: u32,
        region: f32,
        rays: u32,
    },
}

/// An impostor to check, the object it replaces, the rays to fire, and the camera of a pinhole
/// depth image from the same point to set beside it (for a SPOC).
struct Checked {
    impostor: trompe::impostor::Impostor,
    target: std::sync::Arc<trompe::geom::Mesh>,
    rays: Vec<trompe::geom::Ray>,
    pinhole_beside: Option<trompe::impostor::ImpostorCamera>,
}

/// Places the object (scaled to largest extent 1) and a reflector beside it — or the reflector
/// in a maze — and builds the impostor through a camera at the reflector.
fn build_checked(
    input: &Path,
    kind: Option<trompe::impostor::ViewCamera>,
    resolution: u32,
    source: RaySource,
    timings: &mut Timings,
) -> Result<Checked> {
    use trompe::impostor::ImpostorCamera;
    use trompe::impostor::fidelity::ReflectorSetup;
    let RaySource::Reflector {
        path,
        distance,
        view,
    } = source
    else {
        bail!("a built impostor is checked with a reflector's rays");
    };
    let refl = timings.time("load reflector", || load_mesh(&path))?;
    let (setup, cam) = match (kind, is_maze(input)) {
        (None, true) => {
            let maze = trompe::scene::maze::Maze::load(input)?;
            let setup =
                ReflectorSetup::in_maze(&maze, &refl, view).context("placing the reflector")?;
            let g = maze.graph_camera(resolution, input)?;
            println!("graph camera: {} frusta", g.frusta().len());
            (setup, ImpostorCamera::Graph(g))
        }
        (Some(kind), false) => {
            let target = timings.time("load mesh", || load_mesh(input))?;
            let setup = ReflectorSetup::new(&target, &refl, distance, view)
                .context("placing the reflector")?;
            let cam = setup
                .camera(kind, resolution)
                .context("building the impostor camera")?;
            (setup, cam)
        }
        (None, false) => bail!(
            "{}: --camera graph is built from a maze floor plan (.maze)",
            input.display()
        ),
        (Some(_), true) => bail!(
            "{}: a maze floor plan needs --camera graph",
            input.display()
        ),
    };
    let impostor = timings
        .time("build impostor", || {
            let color = trompe::impostor::albedo_of(&setup.target);
            trompe::impostor::build(cam, &setup.target, 0, &color)
        })
        .context("building the impostor")?;
    let pinhole_beside = match &impostor.camera {
        ImpostorCamera::Spoc(_) => Some(
            setup
                .camera(trompe::impostor::ViewCamera::Pinhole, resolution)
                .context("building the pinhole camera")?,
        ),
        _ => None,
    };
    let rays = timings.time("reflected rays", || setup.rays());
    Ok(Checked {
        impostor,
        target: setup.target,
        rays,
        pinhole_beside,
    })
}

/// Loads a baked impostor and the object it was baked from (in its own coordinates, as `bake`
/// reads it), and makes sure they go together.
fn load_checked(
    input: &Path,
    sidecar: &Path,
    source: RaySource,
    timings: &mut Timings,
) -> Result<Checked> {
    use trompe::impostor::ImpostorCamera;
    let RaySource::Viewpoint {
        reflector,
        view,
        region,
        rays,
    } = source
    else {
        bail!("a baked impostor is checked with rays from around its viewpoint");
    };
    let impostor = timings
        .time("load impostor", || trompe::impostor::file::load(sidecar))
        .context("loading the impostor")?;
    let graph = matches!(impostor.camera, ImpostorCamera::Graph(_));
    let (target, setup) = match (graph, is_maze(input)) {
        (true, true) => {
            let maze = trompe::scene::maze::Maze::load(input)?;
            let refl = timings.time("load reflector", || load_mesh(&reflector))?;
            let setup = trompe::impostor::fidelity::ReflectorSetup::in_maze(&maze, &refl, view)
                .context("placing the reflector")?;
            (setup.target.clone(), Some(setup))
        }
        (false, false) => (
            std::sync::Arc::new(timings.time("load mesh", || load_mesh(input))?),
            None,
        ),
        (true, false) => bail!(
            "{}: holds a graph-camera impostor, which is checked against its maze floor plan (.maze), not {}",
            sidecar.display(),
            input.display()
        ),
        (false, true) => bail!(
            "{}: holds a {} impostor; a maze floor plan goes with a graph-camera one",
            sidecar.display(),
            impostor.camera.kind()
        ),
    };
    if !impostor.was_built_from(&target) {
        let (ib, tb) = (impostor.bounds, target.bounds());
        bail!(
            "{}: was not baked from {} as it is (the impostor's box {:?} .. {:?} is not the object's {:?} .. {:?}, padded by 10⁻⁴ of its extent)",
            sidecar.display(),
            input.display(),
            ib.min.to_array(),
            ib.max.to_array(),
            tb.min.to_array(),
            tb.max.to_array()
        );
    }
    let b = target.bounds();
    let (rays, pinhole_beside) = match setup {
        Some(setup) => (timings.time("reflected rays", || setup.rays()), None),
        None => {
            let rays =
                fidelity::viewpoint_rays(&impostor, region * b.radius(), b, rays as usize, 1);
            let pinhole = match &impostor.camera {
                ImpostorCamera::Spoc(_) => Some(
                    ImpostorCamera::fitted(
                        trompe::impostor::ViewCamera::Pinhole,
                        impostor.camera.viewpoint().as_vec3(),
                        b.center(),
                        b.radius(),
                        f64::from(region * b.radius()),
                        impostor.gd.size().0,
                        &target.positions,
                    )
                    .context("building the pinhole camera")?,
                ),
                _ => None,
            };
            (rays, pinhole)
        }
    };
    Ok(Checked {
        impostor,
        target,
        rays,
        pinhole_beside,
    })
}

/// Prints what `info` says of a baked impostor.
fn print_impostor_info(path: &Path, imp: &trompe::impostor::Impostor) {
    use trompe::impostor::ImpostorCamera;
    let (w, h) = imp.gd.size();
    let v = imp.camera.viewpoint();
    println!("{}", path.display());
    println!("  impostor   {} camera, {w}×{h} texels", imp.camera.kind());
    println!("  viewpoint  [{:.4}, {:.4}, {:.4}]", v.x, v.y, v.z);
    match &imp.camera {
        ImpostorCamera::Spoc(s) => {
            let (near, far) = s.depth_range();
            println!(
                "  SPOC       strength k = {:.4}, depth ramp from {near:.4} to {far:.4}",
                s.strength()
            );
        }
        ImpostorCamera::Graph(g) => println!("  frusta     {}", g.frusta().len()),
        ImpostorCamera::Pinhole(_) | ImpostorCamera::Orthographic(_) => {}
    }
    println!("  covered    {:.1} % of texels", imp.coverage() * 100.0);
    let b = imp.bounds;
    println!(
        "  bounds     [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
}

/// Prints what `impostor check` measured.
fn print_fidelity(r: &fidelity::FidelityReport, captured: &fidelity::SurfaceCapture) {
    println!("rays      {} ({} hit the object)", r.rays, r.exact_hits);
    println!(
        "agreement {:.3} % of rays (hit/miss and position within 1.5 texels)",
        r.agreement() * 100.0
    );
    println!(
        "          {:.3} % of the rays that either method says hit",
        r.hit_agreement() * 100.0
    );
    println!(
        "missed    {} ({} on surface the impostor does not hold, {} by the walk)   spurious {}",
        r.missed,
        r.missed_unheld,
        r.missed - r.missed_unheld,
        r.spurious
    );
    println!(
        "position  mean error {:.3e} world units = {:.3} texel footprints (median {:.2e})",
        r.mean_position_error, r.mean_error_footprints, r.median_error_footprints
    );
    println!(
        "surface   {:.1} % captured within 1.5 footprints, {:.1} % within 1.5 texel extents on the surface",
        captured.within_footprint * 100.0,
        captured.within_texel * 100.0
    );
    println!(
        "walk      {:.1} texel visits per ray",
        r.texel_visits_per_ray
    );
}

fn print_timings(t: &Timings) {
    for (name, d) in &t.0 {
        eprintln!("  {name:<16} {:>9.1} ms", d.as_secs_f64() * 1e3);
    }
}

/// `trompe bench --goal RUNS`: the goal's pair alone, `runs` times (see
/// [`trompe::bench::goal_pair`]).
fn bench_goal_only(mesh: &trompe::geom::Mesh, runs: u32) {
    let size = trompe::bench::GOAL_SIZE;
    println!(
        "fresh SPOC impostor {size}² / depth + id rasterization through its reference pinhole (goal ≤ 1.5)"
    );
    let mut ratios = Vec::new();
    for run in 1..=runs {
        let (build, peer) = trompe::bench::goal_pair(mesh, std::time::Duration::from_secs(3));
        let ratio = build.as_secs_f64() / peer.as_secs_f64();
        println!(
            "  run {run}: build {:.3} ms, peer {:.3} ms, {ratio:.3} ×",
            build.as_secs_f64() * 1e3,
            peer.as_secs_f64() * 1e3
        );
        ratios.push(ratio);
    }
    ratios.sort_by(f64::total_cmp);
    let n = ratios.len();
    let median = trompe::impostor::fidelity::median(&ratios);
    println!(
        "{n} runs: {:.3} – {:.3} ×, median {median:.3} ×",
        ratios[0],
        ratios[n - 1]
    );
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<ExitCode> {
    if let Some(n) = cli.threads {
        if n == 0 {
            bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("setting up the thread pool")?;
    }
    match cli.command {
        Command::Render {
            scene,
            output,
            method,
            impostor_resolution,
            time,
            depth,
            normals,
        } => {
            for o in [Some(&output), depth.as_ref(), normals.as_ref()]
                .into_iter()
                .flatten()
            {
                check_output(o, &[&scene])?;
            }
            let mut timings = Timings::default();
            let s = timings
                .time("load scene", || Scene::load(&scene))
                .context("loading the scene")?;
            for w in &s.warnings {
                eprintln!("warning: {w}");
            }
            let t = time.unwrap_or(s.render.time);
            let method = method.method(impostor_resolution);
            let pb = bar(&format!("{method}"), s.camera.height as u64);
            let (frame, steps) =
                render::render_at(&s, t, method, pb.as_ref()).context("rendering")?;
            timings.0.extend(steps.0);
            timings
                .time("write", || -> Result<()> {
                    io::write_color(&output, &frame.color)?;
                    if let Some(d) = &depth {
                        io::write_exr_depth(d, &frame.depth)?;
                    }
                    if let Some(n) = &normals {
                        io::write_exr_normals(n, &frame.normal)?;
                    }
                    Ok(())
                })
                .context("writing the output")?;
            eprintln!("wrote {}", output.display());
            if cli.verbose {
                print_timings(&timings);
            }
        }
        Command::Compare {
            reference,
            test,
            heatmap,
            mask,
        } => {
            if let Some(h) = &heatmap {
                check_output(h, &[&reference, &test])?;
            }
            let a = io::read_color(&reference)
                .with_context(|| format!("reading {}", reference.display()))?;
            let b = io::read_color(&test).with_context(|| format!("reading {}", test.display()))?;
            let mask = match mask {
                Some(m) => {
                    let img =
                        io::read_color(&m).with_context(|| format!("reading {}", m.display()))?;
                    Some(img.map(|p| p.truncate().max_element() > 0.0))
                }
                None => None,
            };
            let s = metrics::compare(&a, &b, mask.as_ref()).context("comparing")?;
            println!("PSNR {:.3} dB", s.psnr);
            println!("SSIM {:.5}", s.ssim);
            println!("FLIP {:.5}", s.flip);
            if let Some(h) = heatmap {
                let heat = metrics::heat_map(&metrics::flip_map(&a, &b)?);
                io::write_png(&h, &heat)?;
                eprintln!("wrote {}", h.display());
            }
        }
        Command::Info { mesh } if has_extension(&mesh, "json") => {
            let imp = trompe::impostor::file::load(&mesh).context("loading the impostor")?;
            print_impostor_info(&mesh, &imp);
        }
        Command::Info { mesh } => {
            let loaded = trompe::geom::io::load(&mesh)?;
            let m = &loaded.mesh;
            let b = m.bounds();
            println!("{}", mesh.display());
            println!(
                "  vertices   {} in the file, {} after splitting by attribute",
                loaded.source.vertices,
                m.positions.len()
            );
            println!(
                "  triangles  {} in the file, {} kept",
                loaded.source.triangles,
                m.triangle_count()
            );
            println!(
                "  bounds     [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]",
                b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
            );
            println!("  surface    {:.6} square units", m.area());
            println!(
                "  UVs        {}",
                if m.uvs.is_some() { "yes" } else { "no" }
            );
            println!("  materials  {}", m.materials.len());
            for mat in &m.materials {
                let c = mat.base_color;
                let tex = mat.texture.as_ref().map_or("no texture".to_string(), |t| {
                    format!("texture {}×{}", t.width(), t.height())
                });
                println!(
                    "    {:<24} colour [{:.3}, {:.3}, {:.3}], {tex}",
                    mat.name, c.x, c.y, c.z
                );
            }
            for w in &loaded.warnings {
                eprintln!("warning: {w}");
            }
        }
        Command::Demo { output } => {
            let inputs = trompe::report::DemoInputs::locate();
            let summary = trompe::report::demo(&inputs, &output, &|label, rows| bar(label, rows))
                .context("building the demo report")?;
            for r in &summary.renders {
                println!(
                    "{:<12} {:<7} {:>8.0} ms  PSNR {:>6.2}  SSIM {:.4}  FLIP {:.4}  ids {:.2} %",
                    r.scene,
                    r.method.to_string(),
                    r.time.as_secs_f64() * 1e3,
                    r.scores.psnr,
                    r.scores.ssim,
                    r.scores.flip,
                    r.id_agreement * 100.0
                );
            }
            println!("wrote {}", summary.index.display());
        }
        Command::Impostor(ImpostorCommand::Check {
            mesh,
            camera,
            k,
            resolution,
            reflector,
            distance,
            view,
            sphere_rays,
            output,
            impostor,
            region,
            rays,
        }) => {
            if let Some(o) = &output {
                check_output(o, &[&mesh])?;
            }
            let reflector = reflector.unwrap_or_else(|| {
                trompe::report::DemoInputs::locate()
                    .assets
                    .join("meshes/bunny.obj")
            });
            let mut timings = Timings::default();
            let checked = match &impostor {
                None => {
                    let source = RaySource::Reflector {
                        path: reflector,
                        distance,
                        view,
                    };
                    build_checked(&mesh, camera.view(k), resolution, source, &mut timings)?
                }
                Some(path) => {
                    if !(region.is_finite() && region > 0.0) {
                        bail!("--region {region}: must be a positive number of radii");
                    }
                    let source = RaySource::Viewpoint {
                        reflector,
                        view,
                        region,
                        rays,
                    };
                    load_checked(&mesh, path, source, &mut timings)?
                }
            };
            let Checked {
                impostor: imp,
                target,
                mut rays,
                pinhole_beside,
            } = checked;
            if let trompe::impostor::ImpostorCamera::Spoc(s) = &imp.camera {
                println!("SPOC strength k = {:.3}", s.strength());
            }
            let exact = timings.time("build BVH", || {
                trompe::trace::Bvh::build(vec![target.clone()])
            });
            let b = target.bounds();
            rays.extend(fidelity::sphere_rays(
                b.center(),
                b.radius() * 3.0,
                b,
                sphere_rays as usize,
                1,
            ));
            let label = format!("checking {} rays", rays.len());
            let r = timings.time("check", || {
                with_spinner(&label, || fidelity::check(&imp, &exact, &rays))
            });
            let captured = timings.time("surface captured", || {
                fidelity::surface_captured(&imp, &target, 50_000, 1)
            });
            let (w, h) = imp.gd.size();
            println!(
                "impostor  {} {w}×{h}, {:.1} % of texels covered",
                imp.camera.kind(),
                imp.coverage() * 100.0
            );
            print_fidelity(&r, &captured);
            if let Some(pinhole) = pinhole_beside {
                // Paper 1 Fig. 6–7: the pinhole depth image from the same point, beside it.
                let p = timings
                    .time("build pinhole impostor", || {
                        let color = trompe::impostor::albedo_of(&target);
                        trompe::impostor::build(pinhole, &target, 0, &color)
                    })
                    .context("building the pinhole impostor")?;
                let rp = timings.time("check pinhole", || {
                    with_spinner("checking the pinhole depth image", || {
                        fidelity::check(&p, &exact, &rays)
                    })
                });
                let cp = fidelity::surface_captured(&p, &target, 50_000, 1);
                println!(
                    "beside it, the pinhole depth image from the same point: agreement {:.3} %, on hits {:.3} %, missed {}, surface {:.1} % / {:.1} %",
                    rp.agreement() * 100.0,
                    rp.hit_agreement() * 100.0,
                    rp.missed,
                    cp.within_footprint * 100.0,
                    cp.within_texel * 100.0
                );
            }
            if matches!(imp.camera, trompe::impostor::ImpostorCamera::Graph(_)) {
                // The default walk is §4.6's algorithm 2; algorithm 1 beside it.
                let r1 = timings.time("check (algorithm 1)", || {
                    fidelity::check_with(&imp, &exact, &rays, trompe::impostor::WalkMode::Linear)
                });
                println!(
                    "algorithm 1 (uniform 3-D steps): agreement {:.3} %, on hits {:.3} %, {:.1} texel visits per ray",
                    r1.agreement() * 100.0,
                    r1.hit_agreement() * 100.0,
                    r1.texel_visits_per_ray
                );
            }
            if let Some(o) = &output {
                trompe::impostor::file::save(&imp, o).context("saving the impostor")?;
                eprintln!("wrote {}", o.display());
            }
            if cli.verbose {
                print_timings(&timings);
            }
        }
        Command::Impostor(ImpostorCommand::Bake {
            input,
            camera,
            resolution,
            from,
            distance,
            k,
            output,
        }) => {
            let preview = output.with_extension("png");
            for o in [&output, &output.with_extension("exr"), &preview] {
                check_output(o, &[&input])?;
            }
            if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("creating {}", dir.display()))?;
            }
            let mut timings = Timings::default();
            let (mesh, cam) = match (camera.view(k), is_maze(&input)) {
                (None, true) => {
                    let maze = trompe::scene::maze::Maze::load(&input)?;
                    let g = maze.graph_camera(resolution, &input)?;
                    (maze.mesh(), trompe::impostor::ImpostorCamera::Graph(g))
                }
                (Some(kind), false) => {
                    let mesh = timings.time("load mesh", || load_mesh(&input))?;
                    if from.length_squared() == 0.0 {
                        bail!("--from must not be zero");
                    }
                    if !(distance.is_finite() && distance > 1.0) {
                        bail!("--distance {distance}: must be more than 1 radius");
                    }
                    let cam = trompe::impostor::ImpostorCamera::facing_mesh(
                        kind, &mesh, from, distance, resolution,
                    )
                    .with_context(|| format!("{}: placing the camera", input.display()))?;
                    (mesh, cam)
                }
                (None, false) => bail!(
                    "{}: --camera graph is built from a maze floor plan (.maze)",
                    input.display()
                ),
                (Some(_), true) => bail!(
                    "{}: a maze floor plan needs --camera graph",
                    input.display()
                ),
            };
            let imp = timings
                .time("build impostor", || {
                    with_spinner("building the impostor", || {
                        let color = trompe::impostor::albedo_of(&mesh);
                        trompe::impostor::build(cam, &mesh, 0, &color)
                    })
                })
                .context("building the impostor")?;
            timings
                .time("save", || {
                    with_spinner("saving the impostor", || {
                        trompe::impostor::file::save(&imp, &output)
                    })
                })
                .context("saving the impostor")?;
            timings.time("write preview", || {
                io::write_png(&preview, &imp.color_image())
            })?;
            println!(
                "{} impostor {resolution}², {:.1} % of texels covered",
                imp.camera.kind(),
                imp.coverage() * 100.0
            );
            println!(
                "wrote {}, {} and {}",
                output.display(),
                output.with_extension("exr").display(),
                preview.display()
            );
            if cli.verbose {
                print_timings(&timings);
            }
        }
        Command::Bench { quick, mesh, goal } => {
            let path = mesh.unwrap_or_else(|| {
                trompe::report::DemoInputs::locate()
                    .assets
                    .join("meshes/bunny.obj")
            });
            let m = load_mesh(&path)?;
            println!(
                "trompe bench on {} ({} triangles), {} threads",
                path.display(),
                m.triangle_count(),
                rayon::current_num_threads()
            );
            if let Some(runs) = goal {
                bench_goal_only(&m, runs);
                return Ok(ExitCode::SUCCESS);
            }
            let assets = trompe::report::DemoInputs::locate().assets;
            let teapot = trompe::geom::io::load(&assets.join("meshes/teapot.obj"))?.mesh;
            let bunny = trompe::geom::io::load(&assets.join("meshes/bunny.obj"))?.mesh;
            let maze_path = trompe::report::DemoInputs::locate()
                .scenes
                .join("maze.maze");
            let maze = trompe::scene::maze::Maze::load(&maze_path)?;
            let duck_path = assets.join("gltf/Duck.glb");
            let duck = trompe::geom::io::load(&duck_path)?.mesh;
            let figures = trompe::bench::foundation(&m, quick)
                .into_iter()
                .chain(trompe::bench::impostors(&m, &teapot, &bunny, quick))
                .chain(trompe::bench::textured_impostor(&duck, "Duck.glb", quick))
                .chain(trompe::bench::graph_impostors(
                    &maze, &maze_path, &bunny, quick,
                ));
            for f in figures {
                let versus = f
                    .versus
                    .map_or(String::new(), |(r, peer)| format!("   ({r:.2} {peer})"));
                println!("  {:<48} {:>12.4} {:<7}{versus}", f.name, f.value, f.unit);
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
