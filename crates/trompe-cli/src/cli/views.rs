//! `trompe views capture | score | render`: calibrated views on the command line — parse, call
//! `trompe::views`, print its report.

use super::render::DeviceArg;
use super::{bar, check_plan, load_mesh, load_mesh_read_by, parse_strength};
use anyhow::{Context, Result};
use clap::ValueEnum;
use std::path::PathBuf;
use trompe::files::{FolderKind, OutputPlan};
use trompe::frame::io;
use trompe::scene::Scene;

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
    #[arg(long, default_value = "320x240", value_parser = parse_size)]
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
    pub(super) fn weighting(self) -> trompe::views::Weighting {
        match self {
            WeightsArg::Ulr => trompe::views::Weighting::Ulr { beta: 0.1 },
            WeightsArg::Vdtm => trompe::views::Weighting::Vdtm,
            WeightsArg::ViewMap => trompe::views::Weighting::ViewMap,
            WeightsArg::BestFace => trompe::views::Weighting::BestFace,
        }
    }
}

/// How a projective render blends its views: `--weights`, `--k` (shared by `views render`,
/// `layers render` and `master render`, one renderer behind them).
#[derive(clap::Args, Debug)]
pub struct BlendArgs {
    /// View weighting.
    #[arg(long, value_enum, default_value_t = WeightsArg::Ulr)]
    weights: WeightsArg,
    /// Most views blended at a point.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    k: u32,
    /// Fill the pixels of the mesh no view sees from the nearest pixel one does (counted
    /// across the mesh's pixels); without it they are transparent.
    #[arg(long)]
    fill_holes: bool,
    /// Prefilter each view's image to the render's pixel: where a pixel covers two or more of
    /// a view's texels, average lookups across it (a box filter) rather than take one.
    #[arg(long)]
    prefilter: bool,
    /// With `--weights best-face`: make its one-view-a-face bake seamless — leave a view out
    /// of a face where its colour disagrees with the other views' (something passed in front),
    /// give each view one gain a channel (its exposure), and level the seams between faces from
    /// different views.
    #[arg(long)]
    seamless: bool,
}

impl BlendArgs {
    /// Whether any blend option differs from its default.
    pub(super) fn any_given(&self) -> bool {
        self.weights != WeightsArg::Ulr
            || self.k != 4
            || self.fill_holes
            || self.prefilter
            || self.seamless
    }

    /// The library's settings.
    pub(super) fn settings(&self) -> anyhow::Result<trompe::texturing::BlendSettings> {
        if self.seamless && self.weights != WeightsArg::BestFace {
            anyhow::bail!(
                "--seamless makes the best-face bake seamless: it needs --weights best-face, not {}",
                self.weights.weighting().name()
            );
        }
        Ok(trompe::texturing::BlendSettings {
            weighting: self.weights.weighting(),
            k: self.k as usize,
            holes: match self.fill_holes {
                true => trompe::texturing::Holes::Nearest,
                false => trompe::texturing::Holes::Transparent,
            },
            prefilter: self.prefilter,
            seamless: self.seamless,
            ..Default::default()
        })
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
    #[arg(long, required_unless_present = "camera")]
    scene: Option<PathBuf>,
    #[command(flatten)]
    camera: CameraArg,
    #[command(flatten)]
    blend: BlendArgs,
    /// Where the blend runs: the CPU; the GPU (the views' images and depth maps in texture
    /// arrays, blended in a compute shader; a hardware adapter, else a software one such as
    /// Mesa's lavapipe); or auto (a hardware GPU where present, else the CPU). The GPU blends
    /// every weighting but a seamless best face, from views without lens distortion.
    #[arg(long, value_enum, default_value_t = DeviceArg::Cpu)]
    device: DeviceArg,
    /// Output image (.png or .exr); pixels no view sees are transparent.
    #[arg(short, long)]
    output: PathBuf,
}

/// Parses "WIDTHxHEIGHT" for clap ([`trompe::frame::parse_size`]).
pub(super) fn parse_size(text: &str) -> Result<(u32, u32), String> {
    trompe::frame::parse_size(text).map_err(|e| e.to_string())
}

impl CaptureArgs {
    pub(super) fn capture(&self) -> Result<()> {
        use trompe::views::capture::{CaptureSettings, Rig, capture, write_capture};
        let out = &self.output;
        let mut plan = OutputPlan::new();
        plan.reads([&self.mesh])
            .writes_folder(out, FolderKind::Capture)
            .writes(out.join("cameras.txt"), &["txt"])
            .creating_folders();
        check_plan(&plan)?;
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

/// `--camera MODEL:IMAGE`: render from where a photograph was taken.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct CameraArg {
    /// Render from a photograph's camera: image IMAGE (its name or id) of the COLMAP model in
    /// the folder MODEL, at its pose and size with its intrinsics (undistorted).
    #[arg(long, value_name = "MODEL:IMAGE")]
    pub camera: Option<String>,
    /// With --camera: render the photograph's distorted frame, through its lens, rather than
    /// its undistorted one (each pixel's ray traced; `render` takes it with --method trace).
    #[arg(long, requires = "camera")]
    pub distort: bool,
}

impl CameraArg {
    /// The model's folder and the image's name or id, when given.
    fn parts(&self) -> Result<Option<(PathBuf, &str)>> {
        let Some(text) = &self.camera else {
            return Ok(None);
        };
        match text.rsplit_once(':') {
            Some((model, key)) if !model.is_empty() && !key.is_empty() => {
                Ok(Some((PathBuf::from(model), key)))
            }
            _ => anyhow::bail!(
                "--camera {text}: expected MODEL:IMAGE (a COLMAP model's folder, then an image's \
                 name or id)"
            ),
        }
    }

    /// The model's files it reads (for an output plan).
    pub fn files(&self) -> Result<Vec<PathBuf>> {
        Ok(self
            .parts()?
            .map(|(model, _)| trompe::views::colmap::model_files(&model))
            .unwrap_or_default())
    }

    /// Replaces `scene`'s camera by the photograph's, keeping its near plane.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        if let Some((model, key)) = self.parts()? {
            scene.camera = trompe::views::camera_of(&model, key, scene.camera.near, self.distort)
                .with_context(|| {
                format!("--camera {}", self.camera.as_deref().unwrap_or(""))
            })?;
        }
        Ok(())
    }

    /// The camera to render `mesh` from, and the lens its pixels look through when it has
    /// one: the photograph's when given, else `scene`'s.
    pub fn camera(
        &self,
        scene: Option<&std::path::Path>,
        mesh: &trompe::geom::Mesh,
    ) -> Result<(trompe::camera::Pinhole, Option<trompe::camera::Intrinsics>)> {
        if let Some((model, key)) = self.parts()? {
            let near = 1e-3 * mesh.bounds().radius().max(1e-6) as f64;
            let spec = trompe::views::camera_of(&model, key, near, self.distort)
                .with_context(|| format!("--camera {}", self.camera.as_deref().unwrap_or("")))?;
            return Ok((spec.at(0.0)?, spec.lens));
        }
        let Some(scene) = scene else {
            anyhow::bail!("give --scene or --camera MODEL:IMAGE");
        };
        let scene = Scene::load(scene).context("loading the scene")?;
        let view = scene.view(scene.render.time)?;
        Ok((view.camera, view.lens.map(|l| (*l).clone())))
    }
}

/// Reads a COLMAP model, printing what was skipped as warnings and, with `--verbose`, what the
/// model held (cameras, images, rigs, frames).
pub(super) fn load_views(
    model: &std::path::Path,
    images: Option<&std::path::Path>,
    verbose: bool,
) -> Result<trompe::views::ViewSet> {
    let set = trompe::views::ViewSet::load(model, images)?;
    for w in &set.warnings {
        eprintln!("warning: {w}");
    }
    if verbose {
        eprintln!("{}: {}", model.display(), set.summary);
    }
    Ok(set)
}

impl ScoreArgs {
    pub(super) fn score(&self, verbose: bool) -> Result<()> {
        let mut set = load_views(&self.model, self.images.as_deref(), verbose)?;
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
        let mut text = format!(
            "{n} views; each of {} left out and rendered from the others:",
            which.len()
        );
        for r in &reports {
            text += &format!("\n  {r}");
        }
        let result = serde_json::json!({
            "views": n,
            "left_out": which.len(),
            "weightings": reports,
        });
        crate::output::report("views score", text, &result)
    }
}

impl ViewsRenderArgs {
    pub(super) fn render(&self, verbose: bool) -> Result<()> {
        let settings = self.blend.settings()?;
        let mut plan = OutputPlan::new();
        let mesh = load_mesh_read_by(&self.mesh, &mut plan)?;
        let mut set = load_views(&self.model, self.images.as_deref(), verbose)?;
        plan.reads(&self.scene)
            .reads(self.camera.files()?)
            .reads(trompe::views::colmap::model_files(&self.model))
            .reads(set.views.iter().map(|v| set.image_folder.join(&v.name)))
            .writes(&self.output, &["png", "exr"]);
        check_plan(&plan)?;
        set.load_images()?;
        let (camera, lens) = self.camera.camera(self.scene.as_deref(), &mesh)?;
        let gpu = trompe_gpu::open(self.device.into()).context("opening the GPU")?;
        if let Some(gpu) = &gpu {
            crate::output::note(format_args!("rendering on {}", gpu.name()));
        }
        let depth = trompe::views::visibility::DepthMap::of_all(&set.views, &mesh)?;
        let b = trompe_gpu::views::render_through(
            gpu.as_ref(),
            (&camera, lens.as_ref()),
            &mesh,
            (&set.views, &depth),
            &settings,
            None,
        )?;
        io::write_color(&self.output, &b.image)?;
        println!("wrote {}: {b}", self.output.display());
        Ok(())
    }
}
