//! `trompe view SCENE` (or `--views MODEL` / `--master ENCODING` with `--mesh`): the interactive
//! viewer. A window (winit for the window and input) over `crate::viewer::Viewer`, shown through
//! a wgpu surface on the GPU the methods run on with `--device gpu` (`trompe_gpu::present`),
//! else through softbuffer with no GPU; or, with `--frames`, headless: a script's inputs replayed
//! at fixed time steps and every frame written.

mod window;

use super::check_plan;
use super::render::DeviceArg;
use super::views::BlendArgs;
use crate::viewer::script::Script;
use crate::viewer::{Request, Viewer};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use trompe::files::{FolderKind, OutputPlan};
use trompe::frame::io;
use trompe::scene::Scene;
use trompe_gpu::{Gpu, PhotoSource, TexturedMesh};
use window::window;

/// `trompe view`.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// Scene file (or fly around a mesh textured from photographs: --views or --master).
    #[arg(required_unless_present_any = ["views", "master"])]
    scene: Option<PathBuf>,
    /// Fly around --mesh textured from this COLMAP model's photographs (text or binary), seen
    /// through their depth maps; the number keys switch weightings.
    #[arg(long, value_name = "MODEL", conflicts_with_all = ["scene", "master"], requires = "mesh")]
    views: Option<PathBuf>,
    /// The photographs' folder, with --views (default: the model's folder, or its images/).
    #[arg(long, requires = "views")]
    images: Option<PathBuf>,
    /// Fly around --mesh textured from this master encoding (a folder `trompe master encode`
    /// wrote); the number keys switch weightings.
    #[arg(
        long,
        value_name = "ENCODING",
        conflicts_with = "scene",
        requires = "mesh"
    )]
    master: Option<PathBuf>,
    /// The mesh the photographs texture, with --views or --master.
    #[arg(long, conflicts_with = "scene")]
    mesh: Option<PathBuf>,
    /// With --views or --master: how the photographs blend (--weights is the first shown).
    #[command(flatten)]
    blend: BlendArgs,
    /// Frame size, WIDTHxHEIGHT (default: the scene camera's, or the first photograph's).
    #[arg(long, value_parser = super::views::parse_size)]
    size: Option<(u32, u32)>,
    /// Impostor resolution of the impostor methods.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(16..=4096))]
    impostor_resolution: u32,
    /// Inputs to replay (see `crate::viewer::script`): headless with --frames, or fed to the
    /// window on its own clock.
    #[arg(long)]
    script: Option<PathBuf>,
    /// Headless: render this many frames, 1/--fps seconds apart, into -o.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: Option<u32>,
    /// Time steps a second, headless.
    #[arg(long, default_value_t = 30.0)]
    fps: f32,
    /// Where frames (headless), screenshots and saved cameras go: an empty or new folder, or
    /// one the viewer wrote before.
    #[arg(short, long, default_value = "out/view")]
    output: PathBuf,
    /// Window: close after this many seconds (for scripted runs).
    #[arg(long)]
    quit_after: Option<f32>,
    /// Where the methods with a GPU path run (every one but envmap, and the photographs'
    /// blends): the CPU, the GPU (hardware first, else lavapipe), or auto (a hardware GPU if
    /// there is one). The other methods run on the CPU either way; the split screen's reference
    /// is the CPU's trace, or the photographs' blend on the CPU.
    #[arg(long, value_enum, default_value_t = DeviceArg::Cpu)]
    device: DeviceArg,
}

impl ViewArgs {
    /// Runs the viewer: headless with --frames, else in a window.
    pub(super) fn run(self) -> Result<()> {
        if !(self.fps.is_finite() && self.fps > 0.0) {
            bail!("--fps {}: must be a positive number", self.fps);
        }
        let script = match &self.script {
            Some(p) => Script::load(p)?,
            None => Script::default(),
        };
        let mut plan = OutputPlan::new();
        plan.creating_folders().reads(self.script.iter().cloned());
        match (&self.scene, &self.mesh) {
            (Some(scene), _) => {
                if self.blend.any_given() {
                    bail!(
                        "--weights, --k, --fill-holes, --prefilter and --seamless blend \
                         photographs: give them with --views or --master, not a scene"
                    );
                }
                let scene = Scene::load(scene).context("loading the scene")?;
                scene
                    .warnings
                    .iter()
                    .for_each(|w| eprintln!("warning: {w}"));
                plan.reads(self.scene.iter().cloned())
                    .reads(scene.files.iter().cloned());
                let out = self.output(plan)?;
                let gpu = self.open_gpu()?;
                let viewer = Viewer::new(&scene, self.impostor_resolution, gpu.as_ref())?;
                let size = (scene.camera.width, scene.camera.height);
                self.show(viewer, script, size, (gpu.as_ref(), out))
            }
            (None, Some(mesh)) => {
                let settings = self.blend.settings()?;
                let mesh = super::load_mesh_read_by(mesh, &mut plan)?;
                let photographs = self.photographs(&mesh, &mut plan)?;
                let out = self.output(plan)?;
                let gpu = self.open_gpu()?;
                let textured =
                    TexturedMesh::new(gpu.as_ref(), &mesh, photographs.source(), &settings)
                        .context("preparing the photographs")?;
                let viewer = Viewer::of_photographs(textured, &mesh)?;
                let size = photographs.size();
                self.show(viewer, script, size, (gpu.as_ref(), out))
            }
            (None, None) => {
                bail!("give a scene file, or --views MODEL or --master ENCODING with --mesh")
            }
        }
    }

    /// Claims the output folder, once `plan` holds everything the viewer reads.
    fn output(&self, mut plan: OutputPlan) -> Result<Output> {
        plan.writes_folder(&self.output, FolderKind::ViewerFrames);
        check_plan(&plan)?;
        trompe::files::claim_folder(&self.output, FolderKind::ViewerFrames)?;
        Ok(Output {
            dir: self.output.clone(),
            plan,
        })
    }

    /// The GPU the methods with a GPU path run on (the trace method's choice stands for them).
    fn open_gpu(&self) -> Result<Option<Gpu>> {
        let gpu = trompe_gpu::open_for(self.device.into(), trompe::methods::MethodKind::Trace)
            .context("opening the GPU")?;
        if let Some(g) = &gpu {
            let what = match self.scene {
                Some(_) => trompe_gpu::methods::gpu_methods().join(", "),
                None => "the photographs' blends".to_string(),
            };
            crate::output::note(format_args!("{what} run on {}", g.name()));
        }
        Ok(gpu)
    }

    /// The photographs --views or --master names, loaded, with what they read added to `plan`.
    fn photographs(&self, mesh: &trompe::Mesh, plan: &mut OutputPlan) -> Result<Loaded> {
        if let Some(model) = &self.views {
            let mut set = super::views::load_views(model, self.images.as_deref(), false)?;
            plan.reads(trompe::views::colmap::model_files(model))
                .reads(set.views.iter().map(|v| set.image_folder.join(&v.name)));
            set.load_images()?;
            let depth = trompe::views::visibility::DepthMap::of_all(&set.views, mesh)?;
            return Ok(Loaded::Views(set.views, depth));
        }
        let Some(encoding) = &self.master else {
            bail!("give --views MODEL or --master ENCODING with --mesh");
        };
        plan.reads([encoding])
            .reads(trompe::master::job::files_of(encoding));
        let (manifest, masters) = trompe::master::file::load(encoding)
            .with_context(|| format!("loading the encoding {}", encoding.display()))?;
        let cameras = manifest.views.iter().map(|v| v.pinhole()).collect();
        Ok(Loaded::Masters(manifest.layout, cameras, masters))
    }

    /// Shows `viewer`: headless with --frames, else in a window; frames `size` unless --size.
    fn show(
        &self,
        viewer: Viewer<'_>,
        script: Script,
        size: (u32, u32),
        (gpu, out): (Option<&Gpu>, Output),
    ) -> Result<()> {
        let size = self.size.unwrap_or(size);
        match self.frames {
            Some(frames) => headless(viewer, &script, frames, self.fps, size, &out),
            None => window(viewer.live(), script, (size, gpu), out, self.quit_after),
        }
    }
}

/// Photographs loaded for the viewer.
enum Loaded {
    /// Calibrated views, their images loaded, and their depth maps.
    Views(
        Vec<trompe::views::CalibratedView>,
        Vec<trompe::views::visibility::DepthMap>,
    ),
    /// A master encoding: its layout, its views' cameras, its masters.
    Masters(
        trompe::master::layout::Layout,
        Vec<trompe::camera::Pinhole>,
        Vec<trompe::Image<trompe::Rgba>>,
    ),
}

impl Loaded {
    fn source(&self) -> PhotoSource<'_> {
        match self {
            Loaded::Views(views, depth) => PhotoSource::Views { views, depth },
            Loaded::Masters(layout, cameras, masters) => PhotoSource::Masters {
                layout,
                cameras,
                masters,
            },
        }
    }

    /// The first photograph's size (1 × 1 without one).
    fn size(&self) -> (u32, u32) {
        use trompe::camera::Projection;
        self.source()
            .cameras()
            .first()
            .map_or((1, 1), |c| c.resolution())
    }
}

/// Where the viewer writes: its folder, every file checked against what it reads.
struct Output {
    dir: PathBuf,
    plan: OutputPlan,
}

impl Output {
    /// Writes the file `name` in the folder with `write`, unless it is a file the viewer reads.
    fn write(&self, name: &str, write: impl FnOnce(&Path) -> Result<()>) -> Result<PathBuf> {
        let path = self.dir.join(name);
        self.plan.check_output(&path)?;
        write(&path).with_context(|| format!("writing {}", path.display()))?;
        Ok(path)
    }
}

/// Replays `script` at `fps` steps a second for `frames` frames, writing each.
fn headless(
    mut viewer: Viewer<'_>,
    script: &Script,
    frames: u32,
    fps: f32,
    size: (u32, u32),
    out: &Output,
) -> Result<()> {
    let dt = 1.0 / fps;
    let mut last = None;
    for i in 0..frames {
        let (from, to) = (i as f32 * dt, (i + 1) as f32 * dt);
        for input in script.between(from, to) {
            if let Some(request) = viewer.input(input) {
                handle(request, &viewer, (last.as_ref(), None), size, out, i)?;
            }
        }
        let frame = viewer.frame(size, 1.0)?;
        out.write(&format!("frame_{i:04}.png"), |p| {
            Ok(io::write_png(p, &frame.image)?)
        })?;
        println!("frame {i:>5}  {:>7.1} ms  {}", frame.ms, frame.hud[0]);
        last = Some(frame.image);
        viewer.step(dt);
    }
    Ok(())
}

/// Saves a screenshot (the last frame, without the overlay; and where a GPU shows the window,
/// the frame as its surface was given it, overlay included, read back from the device) or the
/// camera block.
fn handle(
    request: Request,
    viewer: &Viewer<'_>,
    (last, shown): (
        Option<&trompe::Image<trompe::Rgba>>,
        Option<&trompe::Image<trompe::Rgba>>,
    ),
    size: (u32, u32),
    out: &Output,
    n: u32,
) -> Result<()> {
    match request {
        Request::Screenshot => {
            for (name, image) in [("screenshot", last), ("shown", shown)] {
                if let Some(image) = image {
                    let path = out.write(&format!("{name}_{n:04}.png"), |p| {
                        Ok(io::write_png(p, image)?)
                    })?;
                    crate::output::note(format_args!("wrote {}", path.display()));
                }
            }
        }
        Request::SaveCamera => {
            let block = viewer.camera_block(size);
            let path = out.write(&format!("camera_{n:04}.toml"), |p| {
                Ok(trompe::files::write_atomically(p, block.as_bytes())?)
            })?;
            crate::output::note(format_args!("wrote {}", path.display()));
        }
    }
    Ok(())
}
