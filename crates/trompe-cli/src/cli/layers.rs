//! `trompe layers build | render`: layered view-dependent projective textures (paper 4) on the
//! command line — parse, call `trompe::layers`, print its report.

use super::render::DeviceArg;
use super::views::{BlendArgs, CameraArg, RigArg, parse_size};
use super::{bar, check_plan};
use anyhow::{Context, Result};
use clap::{Subcommand, ValueEnum};
use std::path::PathBuf;
use trompe::files::{FolderKind, OutputPlan};
use trompe::frame::io;
use trompe::layers::{self, BuildSettings, OrderSettings, Ordering};
use trompe::scene::Scene;

/// `trompe layers …`.
#[derive(Subcommand, Debug)]
pub enum LayersCommand {
    /// Capture views of a scene (or read a COLMAP model of it), sort its objects into
    /// visibility layers per view, cut the photographs into image layers and write one
    /// OpenRaster file a view (GIMP and Krita open and save them), layers.json and the
    /// cameras.
    Build(BuildArgs),
    /// Render the scene from its camera textured by the layers (as saved, or as an artist
    /// edited them), or by plain projective texturing of the whole photographs.
    Render(RenderArgs),
}

impl LayersCommand {
    pub(super) fn run(&self, verbose: bool) -> Result<()> {
        match self {
            LayersCommand::Build(args) => args.build(verbose),
            LayersCommand::Render(args) => args.render(),
        }
    }
}

/// `--ordering`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum OrderingArg {
    /// The paper's item-buffer passes with the authors' fix.
    ItemBuffer,
    /// The exact per-pixel criterion.
    Exact,
}

/// `trompe layers build`.
#[derive(clap::Args, Debug)]
pub struct BuildArgs {
    /// The scene (its objects are what the layers sort).
    scene: PathBuf,
    /// A COLMAP model of the scene (text or binary) instead of a synthetic capture.
    #[arg(long)]
    model: Option<PathBuf>,
    /// The model's images folder (default: the model's folder, or its images/).
    #[arg(long, requires = "model")]
    images: Option<PathBuf>,
    /// Views to capture (without --model).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=1000))]
    views: u32,
    /// Where the captured cameras stand.
    #[arg(long, value_enum, default_value_t = RigArg::Ring)]
    rig: RigArg,
    /// Captured image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    size: (u32, u32),
    /// Camera distance from the scene's centre, in bounding radii.
    #[arg(long, default_value_t = 1.4)]
    distance: f64,
    /// Vertical field of view of the captured views, degrees.
    #[arg(long, default_value_t = 50.0)]
    fov: f64,
    /// The visibility ordering.
    #[arg(long, value_enum, default_value_t = OrderingArg::ItemBuffer)]
    ordering: OrderingArg,
    /// One image layer an object a visibility layer (no power-of-two clustering).
    #[arg(long)]
    no_clustering: bool,
    /// Fill hidden texels by push-pull (otherwise they are left transparent for an artist).
    #[arg(long)]
    fill: bool,
    /// Output folder (made if missing; must be empty or hold earlier layers).
    #[arg(short, long)]
    output: PathBuf,
}

impl BuildArgs {
    fn build(&self, verbose: bool) -> Result<()> {
        let out = &self.output;
        let scene = Scene::load(&self.scene)?;
        let mut plan = OutputPlan::new();
        plan.reads(scene.files.iter().cloned())
            .writes_folder(out, FolderKind::LayerSet)
            .writes(out.join(layers::file::PROJECT), &["json"])
            .creating_folders();
        let model = match &self.model {
            Some(m) => {
                let set = super::views::load_views(m, self.images.as_deref(), verbose)?;
                plan.reads(trompe::views::colmap::model_files(m))
                    .reads(set.views.iter().map(|v| set.image_folder.join(&v.name)));
                Some(set)
            }
            None => None,
        };
        check_plan(&plan)?;
        let views = match model {
            Some(mut set) => {
                for w in &set.warnings {
                    eprintln!("warning: {w}");
                }
                set.load_images()?;
                set.views
            }
            None => {
                use trompe::views::capture::{CaptureSettings, Rig, capture_of};
                let settings = CaptureSettings {
                    rig: match self.rig {
                        RigArg::Sphere => Rig::Sphere,
                        RigArg::Hemisphere => Rig::Hemisphere,
                        RigArg::Ring => Rig::Ring,
                    },
                    count: self.views as usize,
                    size: self.size,
                    distance: self.distance,
                    fov_y: self.fov,
                    ..CaptureSettings::default()
                };
                let progress = bar("capturing", self.views as u64);
                capture_of(scene.clone(), &settings, progress.as_ref())?.views
            }
        };
        let (meshes, names) = layers::scene_objects(&scene)?;
        let settings = BuildSettings {
            order: OrderSettings {
                ordering: match self.ordering {
                    OrderingArg::ItemBuffer => Ordering::ItemBuffer,
                    OrderingArg::Exact => Ordering::Exact,
                },
                ..OrderSettings::default()
            },
            clustering: !self.no_clustering,
            fill: self.fill,
        };
        let progress = bar("layering", views.len() as u64);
        let set = layers::build(meshes, names, &views, &settings, progress.as_ref())?;
        drop(progress);
        layers::file::save(out, &set)?;
        let mut text = layers::REPORT_HEADER.to_string();
        for r in &set.reports {
            text += &format!("\n{r}");
        }
        text += &format!(
            "\n{} views, {} objects: layers.json, cameras and one .ora a view written to {}",
            set.views.len(),
            set.names.len(),
            out.display()
        );
        let result = serde_json::json!({
            "views": set.views.len(),
            "objects": set.names,
            "folder": out,
            "reports": set.reports,
        });
        crate::output::report("layers build", text, &result)
    }
}

/// `--method` of `trompe layers render`.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
pub enum TextureArg {
    /// Each object through the image layers that hold it (the paper's method).
    Layered,
    /// The whole photographs projected on everything, hidden or not (the baseline).
    Projective,
}

/// `trompe layers render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The scene the layers were built from (its camera is the new viewpoint).
    scene: PathBuf,
    /// The layers' folder (from `trompe layers build`, possibly edited).
    #[arg(long)]
    layers: PathBuf,
    /// How to texture.
    #[arg(long, value_enum, default_value_t = TextureArg::Layered)]
    method: TextureArg,
    /// Fill the layers' hidden texels by push-pull before rendering (in memory only).
    #[arg(long)]
    fill: bool,
    #[command(flatten)]
    camera: CameraArg,
    #[command(flatten)]
    blend: BlendArgs,
    /// Where the blend runs: the CPU; the GPU (every image layer and its depth in
    /// texture arrays, each object through its layer's sub-frustum, blended in a compute
    /// shader; a hardware adapter, else a software one such as Mesa's lavapipe); or auto (a
    /// hardware GPU where present, else the CPU). The GPU blends every weighting but a
    /// seamless best face, without a lens; `--method projective` projects the photographs
    /// whole from a texture array.
    #[arg(long, value_enum, default_value_t = DeviceArg::Cpu)]
    device: DeviceArg,
    /// Output image (.png or .exr); pixels nothing textures are transparent.
    #[arg(short, long)]
    output: PathBuf,
}

impl RenderArgs {
    fn render(&self) -> Result<()> {
        let settings = self.blend.settings()?;
        let mut scene = Scene::load(&self.scene)?;
        self.camera.apply(&mut scene)?;
        let mut plan = OutputPlan::new();
        plan.reads(scene.files.iter().cloned())
            .reads(self.camera.files()?)
            .reads([self.layers.join(layers::file::PROJECT)])
            .writes(&self.output, &["png", "exr"]);
        check_plan(&plan)?;
        let (meshes, names) = layers::scene_objects(&scene)?;
        let mut set = layers::file::load(&self.layers, meshes, names)
            .with_context(|| format!("loading the layers in {}", self.layers.display()))?;
        if self.fill {
            let n = set.fill();
            crate::output::note(format_args!("filled {n} hidden texels"));
        }
        let camera = scene.camera.at(scene.render.time)?;
        let lens = scene.camera.lens.as_ref();
        let gpu = trompe_gpu::open(self.device.into()).context("opening the GPU")?;
        if let Some(gpu) = &gpu {
            crate::output::note(format_args!("rendering on {}", gpu.name()));
        }
        let start = std::time::Instant::now();
        let blend = match self.method {
            TextureArg::Layered => {
                trompe_gpu::layers::render_through(gpu.as_ref(), (&camera, lens), &set, &settings)?
            }
            TextureArg::Projective => {
                let views = layers::file::photographs(&self.layers, &set)?;
                let meshes = set.mesh_refs();
                trompe_gpu::layers::render_projective_through(
                    gpu.as_ref(),
                    (&camera, lens),
                    &meshes,
                    &views,
                    &settings,
                )?
            }
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        io::write_color(&self.output, &blend.image)?;
        println!("wrote {}: {blend}, {ms:.1} ms", self.output.display());
        Ok(())
    }
}
