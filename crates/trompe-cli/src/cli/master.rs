//! `trompe master encode|render|edit`: Master Texture Space (paper 5) on the command line —
//! parse, call one `trompe::master::job` function, print its summary.

use super::render::DeviceArg;
use super::views::{BlendArgs, CameraArg};
use super::{bar, check_plan, load_mesh_read_by};
use anyhow::{Context, Result, bail};
use clap::Subcommand;
use std::path::PathBuf;
use trompe::files::{FolderKind, OutputPlan};
use trompe::frame::io;
use trompe::scene::Scene;

/// `trompe master …`.
#[derive(Subcommand, Debug)]
pub enum MasterCommand {
    /// Encode every view of a COLMAP model of a mesh: master_NNNN.png, masters.json (packing
    /// map, one UV set, cameras), bake.png (view-independent) and mesh.glb textured by it.
    Encode(MasterEncodeArgs),
    /// Render the mesh from a scene's camera, view-dependently from the master textures.
    Render(MasterRenderArgs),
    /// Propagate an edit to every view's master texture: one view's image as an artist changed
    /// it, or an effect (a shadow) rendered from a new camera with and without it.
    Edit(MasterEditArgs),
}

impl MasterCommand {
    /// Runs the subcommand.
    pub(super) fn run(&self, verbose: bool) -> Result<()> {
        match self {
            MasterCommand::Encode(args) => args.encode(verbose),
            MasterCommand::Render(args) => args.render(),
            MasterCommand::Edit(args) => args.edit(),
        }
    }
}

/// `trompe master encode`.
#[derive(clap::Args, Debug)]
pub struct MasterEncodeArgs {
    /// The COLMAP model's folder (text or binary).
    model: PathBuf,
    /// The mesh, in the model's frame.
    #[arg(long)]
    mesh: PathBuf,
    /// The images' folder (default: the model's folder, or its images/).
    #[arg(long)]
    images: Option<PathBuf>,
    /// Texels a pixel of a face's largest view (the paper: 1).
    #[arg(long, default_value_t = trompe::master::DEFAULT_SCALE)]
    scale: f64,
    /// Output folder (new or empty, or an earlier encoding's).
    #[arg(short, long)]
    output: PathBuf,
}

/// `trompe master render`.
#[derive(clap::Args, Debug)]
pub struct MasterRenderArgs {
    /// A folder `trompe master encode` wrote.
    encoding: PathBuf,
    /// The mesh it was encoded for.
    #[arg(long)]
    mesh: PathBuf,
    /// A scene file whose camera to render from (its objects are ignored).
    #[arg(long, required_unless_present = "camera")]
    scene: Option<PathBuf>,
    #[command(flatten)]
    camera: CameraArg,
    #[command(flatten)]
    blend: BlendArgs,
    /// Where the blend runs: the CPU; the GPU (every master a layer of one texture array, the
    /// views blended in a compute shader; a hardware adapter, else a software one such as
    /// Mesa's lavapipe); or auto (a hardware GPU where present, else the CPU). The GPU blends
    /// every weighting but a seamless best face, without a lens.
    #[arg(long, value_enum, default_value_t = DeviceArg::Cpu)]
    device: DeviceArg,
    /// Output image (.png or .exr).
    #[arg(short, long)]
    output: PathBuf,
}

/// `trompe master edit`.
#[derive(clap::Args, Debug)]
pub struct MasterEditArgs {
    /// A folder `trompe master encode` wrote.
    encoding: PathBuf,
    /// The mesh it was encoded for.
    #[arg(long)]
    mesh: PathBuf,
    /// The view that was edited (its index in masters.json, from 0).
    #[arg(long, required_unless_present = "scene", conflicts_with = "scene")]
    view: Option<usize>,
    /// Or an effect seen from a new camera: this scene file's camera, with --without the render
    /// without the effect and --edited the render with it.
    #[arg(long, requires = "without")]
    scene: Option<PathBuf>,
    /// The new camera's render without the effect (with --scene).
    #[arg(long, requires = "scene")]
    without: Option<PathBuf>,
    /// The view's image as edited, or the new camera's render with the effect (same size).
    #[arg(long)]
    edited: PathBuf,
    /// Write the edited texels as they are instead of adding their change.
    #[arg(long)]
    replace: bool,
    /// Output folder for the edited encoding (new or empty; not the input).
    #[arg(short, long)]
    output: PathBuf,
}

impl MasterEncodeArgs {
    fn encode(&self, verbose: bool) -> Result<()> {
        if !(self.scale.is_finite() && (0.25..=16.0).contains(&self.scale)) {
            bail!("--scale {}: must be between 0.25 and 16", self.scale);
        }
        let set = super::views::load_views(&self.model, self.images.as_deref(), verbose)?;
        let mut plan = OutputPlan::new();
        let mesh = load_mesh_read_by(&self.mesh, &mut plan)?;
        plan.reads(trompe::views::colmap::model_files(&self.model))
            .reads(set.views.iter().map(|v| set.image_folder.join(&v.name)))
            .writes_folder(&self.output, FolderKind::MasterEncoding)
            .writes(self.output.join("masters.json"), &["json"])
            .creating_folders();
        check_plan(&plan)?;
        let count = set.views.len();
        let progress = bar("encoding views", count as u64);
        let summary = trompe::master::job::encode_folder(
            &self.model,
            self.images.as_deref(),
            &mesh,
            Some(self.scale),
            &self.output,
            progress.as_ref(),
        )?;
        let text = format!(
            "{summary}\nwrote {} files to {}",
            summary.files.len(),
            self.output.display()
        );
        crate::output::report("master encode", text, &summary)
    }
}

impl MasterRenderArgs {
    fn render(&self) -> Result<()> {
        let settings = self.blend.settings()?;
        let mut plan = OutputPlan::new();
        let mesh = load_mesh_read_by(&self.mesh, &mut plan)?;
        plan.reads(&self.scene)
            .reads([&self.encoding])
            .reads(self.camera.files()?)
            .reads(trompe::master::job::files_of(&self.encoding))
            .writes(&self.output, &["png", "exr"]);
        check_plan(&plan)?;
        let (camera, lens) = self.camera.camera(self.scene.as_deref(), &mesh)?;
        let gpu = trompe_gpu::open(self.device.into()).context("opening the GPU")?;
        if let Some(gpu) = &gpu {
            crate::output::note(format_args!("rendering on {}", gpu.name()));
        }
        let b = trompe_gpu::master::render_folder(
            gpu.as_ref(),
            &self.encoding,
            &mesh,
            (&camera, lens.as_ref()),
            &settings,
        )?;
        io::write_color(&self.output, &b.image)?;
        println!("wrote {}: {b}", self.output.display());
        Ok(())
    }
}

impl MasterEditArgs {
    fn edit(&self) -> Result<()> {
        let same = std::fs::canonicalize(&self.output).ok().is_some()
            && std::fs::canonicalize(&self.output).ok()
                == std::fs::canonicalize(&self.encoding).ok();
        if same {
            bail!(
                "{}: the edited encoding goes into a new folder, not over the one it edits",
                self.output.display()
            );
        }
        let mut plan = OutputPlan::new();
        let mesh = load_mesh_read_by(&self.mesh, &mut plan)?;
        plan.reads([&self.edited, &self.encoding])
            .reads(self.scene.iter().chain(self.without.iter()))
            .writes_folder(&self.output, FolderKind::MasterEncoding)
            .writes(self.output.join("masters.json"), &["json"])
            .creating_folders();
        check_plan(&plan)?;
        let edited = io::read_png(&self.edited)
            .with_context(|| format!("reading {}", self.edited.display()))?;
        let apply = if self.replace {
            trompe::master::edit::Apply::Replace
        } else {
            trompe::master::edit::Apply::Add
        };
        use trompe::master::job::EditSource;
        let source = match (&self.scene, &self.without, self.view) {
            (Some(scene), Some(without), _) => {
                let scene = Scene::load(scene).context("loading the scene")?;
                EditSource::Camera {
                    camera: Box::new(scene.view(scene.render.time)?.camera),
                    without: io::read_png(without)
                        .with_context(|| format!("reading {}", without.display()))?,
                }
            }
            (_, _, Some(view)) => EditSource::View(view),
            _ => bail!("give --view N, or --scene S with --without and --edited"),
        };
        let summary = trompe::master::job::edit_folder(
            &self.encoding,
            &mesh,
            &source,
            &edited,
            apply,
            &self.output,
        )?;
        println!("{summary}");
        println!("wrote {}", self.output.display());
        Ok(())
    }
}
