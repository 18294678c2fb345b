//! `trompe view SCENE` (or `--views MODEL` / `--master ENCODING` with `--mesh`): the interactive
//! viewer. A window (winit for the window and input) over `crate::viewer::Viewer`, shown through
//! a wgpu surface on the GPU the methods run on with `--device gpu` (`trompe_gpu::present`),
//! else through softbuffer with no GPU; or, with `--frames`, headless: a script's inputs replayed
//! at fixed time steps and every frame written.

use super::check_plan;
use super::render::DeviceArg;
use super::views::BlendArgs;
use crate::viewer::script::{self, Script};
use crate::viewer::{Input, Request, Viewer, hud};
use anyhow::{Context, Result, bail};
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use trompe::files::{FolderKind, OutputPlan};
use trompe::frame::io;
use trompe::scene::Scene;
use trompe_gpu::{Gpu, PhotoSource, TexturedMesh, WindowSurface};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

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

/// The key a window key code stands for, by its name in scripts.
fn key_of(code: KeyCode) -> Option<crate::viewer::Key> {
    let name = match code {
        KeyCode::KeyW => "W",
        KeyCode::KeyA => "A",
        KeyCode::KeyS => "S",
        KeyCode::KeyD => "D",
        KeyCode::KeyQ => "Q",
        KeyCode::KeyE => "E",
        KeyCode::Tab => "Tab",
        KeyCode::KeyP => "P",
        KeyCode::KeyV => "V",
        KeyCode::F12 => "F12",
        KeyCode::KeyC => "C",
        KeyCode::KeyH => "H",
        KeyCode::Digit1 => "1",
        KeyCode::Digit2 => "2",
        KeyCode::Digit3 => "3",
        KeyCode::Digit4 => "4",
        KeyCode::Digit5 => "5",
        KeyCode::Digit6 => "6",
        KeyCode::Digit7 => "7",
        KeyCode::Digit8 => "8",
        KeyCode::Digit9 => "9",
        KeyCode::Digit0 => "0",
        KeyCode::KeyO => "O",
        _ => return None,
    };
    script::key(name)
}

/// What shows the window's frames.
enum Surface<'a> {
    /// A CPU buffer (softbuffer): no GPU.
    Cpu(softbuffer::Surface<Arc<Window>, Arc<Window>>),
    /// A wgpu surface on the GPU the methods run on.
    Gpu(Box<WindowSurface<'static>>, &'a Gpu),
}

/// The window's state.
struct App<'a> {
    viewer: Viewer<'a>,
    script: Script,
    size: (u32, u32),
    /// The GPU the methods run on, which shows the window too.
    gpu: Option<&'a Gpu>,
    out: Output,
    quit_after: Option<f32>,
    window: Option<(Arc<Window>, Surface<'a>)>,
    start: Instant,
    last_step: Instant,
    /// Seconds of the script already fed.
    fed: f32,
    /// The last frame, without the overlay.
    last: Option<trompe::Image<trompe::Rgba>>,
    /// Render scale: below 1 while the camera moves, 1 when it rests.
    scale: f32,
    moving: bool,
    /// When the oldest input not yet shown arrived.
    pending: Option<Instant>,
    latency_ms: f64,
    cursor: Option<(f64, f64)>,
    looking: bool,
    frames: u32,
    error: Option<anyhow::Error>,
}

impl App<'_> {
    fn input(&mut self, input: Input) {
        self.pending.get_or_insert_with(Instant::now);
        self.moving = true;
        let Some(request) = self.viewer.input(input) else {
            return;
        };
        // What the GPU's surface was given last, for a screenshot.
        let shown = match (&request, &self.window) {
            (Request::Screenshot, Some((_, Surface::Gpu(surface, gpu)))) => {
                match surface.read_shown(gpu) {
                    Ok(shown) => shown,
                    Err(e) => {
                        self.error = Some(e.into());
                        return;
                    }
                }
            }
            _ => None,
        };
        if let Err(e) = handle(
            request,
            &self.viewer,
            (self.last.as_ref(), shown.as_ref()),
            self.size,
            &self.out,
            self.frames,
        ) {
            self.error = Some(e);
        }
    }

    fn redraw(&mut self) -> Result<()> {
        let now = Instant::now();
        let dt = now.duration_since(self.last_step).as_secs_f32();
        self.last_step = now;
        let clock = now.duration_since(self.start).as_secs_f32();
        let events: Vec<Input> = self.script.between(self.fed, clock).collect();
        self.fed = clock;
        for e in events {
            self.input(e);
        }
        self.viewer.step(dt);
        let Some((window, surface)) = self.window.as_mut() else {
            return Ok(());
        };
        let inner = window.inner_size();
        let size = (inner.width.max(1), inner.height.max(1));
        self.size = size;
        let scale = if self.moving { self.scale } else { 1.0 };
        let frame = self.viewer.frame(size, scale)?;
        // Hold about 30 frames a second while moving.
        if self.moving {
            self.scale = (self.scale * (33.0 / frame.ms.max(1.0)).sqrt() as f32).clamp(0.2, 1.0);
        }
        self.moving = false;
        let mut lines = frame.hud.clone();
        lines.insert(1, format!("input to screen {:.0} ms", self.latency_ms));
        match surface {
            Surface::Cpu(surface) => {
                surface
                    .resize(
                        NonZeroU32::new(size.0).unwrap_or(NonZeroU32::MIN),
                        NonZeroU32::new(size.1).unwrap_or(NonZeroU32::MIN),
                    )
                    .map_err(|e| anyhow::anyhow!("resizing the window's buffer: {e}"))?;
                let mut buffer = surface
                    .buffer_mut()
                    .map_err(|e| anyhow::anyhow!("the window's buffer: {e}"))?;
                compose(&mut buffer, &frame.image, size.0, &lines);
                buffer
                    .present()
                    .map_err(|e| anyhow::anyhow!("presenting the frame: {e}"))?;
            }
            Surface::Gpu(surface, gpu) => {
                let mut buffer = vec![0u32; size.0 as usize * size.1 as usize];
                compose(&mut buffer, &frame.image, size.0, &lines);
                surface
                    .present(gpu, &buffer, size)
                    .context("presenting the frame")?;
            }
        }
        if let Some(at) = self.pending.take() {
            self.latency_ms = at.elapsed().as_secs_f64() * 1e3;
        }
        self.last = Some(frame.image);
        self.frames += 1;
        Ok(())
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attributes = Window::default_attributes()
            .with_title("trompe view")
            .with_inner_size(winit::dpi::PhysicalSize::new(self.size.0, self.size.1));
        let made = event_loop
            .create_window(attributes)
            .map_err(|e| anyhow::anyhow!("opening a window: {e}"))
            .and_then(|w| {
                let w = Arc::new(w);
                if let Some(gpu) = self.gpu {
                    match WindowSurface::new(gpu, w.clone(), self.size) {
                        Ok(surface) => {
                            crate::output::note(format_args!(
                                "the window shows through a wgpu surface on {} ({:?})",
                                gpu.name(),
                                surface.format()
                            ));
                            return Ok((w, Surface::Gpu(Box::new(surface), gpu)));
                        }
                        Err(e) => {
                            eprintln!("warning: {e}; the window shows through a CPU buffer instead")
                        }
                    }
                }
                let context = softbuffer::Context::new(w.clone())
                    .map_err(|e| anyhow::anyhow!("the display: {e}"))?;
                let surface = softbuffer::Surface::new(&context, w.clone())
                    .map_err(|e| anyhow::anyhow!("the window's surface: {e}"))?;
                Ok((w, Surface::Cpu(surface)))
            });
        match made {
            Ok(made) => {
                made.0.request_redraw();
                self.window = Some(made);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                if code == KeyCode::Escape {
                    event_loop.exit();
                    return;
                }
                if let Some(key) = key_of(code) {
                    match event.state {
                        ElementState::Pressed if !event.repeat => self.input(Input::Down(key)),
                        ElementState::Released => self.input(Input::Up(key)),
                        _ => {}
                    }
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                self.looking = state == ElementState::Pressed;
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y))) = (self.looking, self.cursor) {
                    self.input(Input::Look(
                        (position.x - x) as f32,
                        (position.y - y) as f32,
                    ));
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.input(Input::Scroll(notches));
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw() {
                    self.error = Some(e);
                    event_loop.exit();
                    return;
                }
                let done = self
                    .quit_after
                    .is_some_and(|s| self.start.elapsed().as_secs_f32() >= s);
                if done || self.error.is_some() {
                    event_loop.exit();
                } else if let Some((w, _)) = &self.window {
                    w.request_redraw();
                }
            }
            _ => {}
        }
    }
}

/// `image` (linear colour) as a window's buffer shows it — each pixel `0x00RRGGBB`, sRGB-encoded
/// — with the overlay's `lines` drawn over it; `width` pixels a row.
fn compose(buffer: &mut [u32], image: &trompe::Image<trompe::Rgba>, width: u32, lines: &[String]) {
    for (px, c) in buffer.iter_mut().zip(image.pixels()) {
        let [r, g, b] =
            [c.x, c.y, c.z].map(|v| (trompe::frame::linear_to_srgb(v) * 255.0 + 0.5) as u32);
        *px = (r.min(255) << 16) | (g.min(255) << 8) | b.min(255);
    }
    hud::draw(buffer, width as usize, lines);
}

/// Opens the window and runs until it closes (or --quit-after); shown through a wgpu surface
/// on `gpu` if given.
fn window<'a>(
    viewer: Viewer<'a>,
    script: Script,
    (size, gpu): ((u32, u32), Option<&'a Gpu>),
    out: Output,
    quit_after: Option<f32>,
) -> Result<()> {
    let event_loop = EventLoop::new()
        .context("opening the display (is there an X server or Wayland compositor?)")?;
    let now = Instant::now();
    let mut app = App {
        viewer,
        script,
        size,
        gpu,
        out,
        quit_after,
        window: None,
        start: now,
        last_step: now,
        fed: 0.0,
        last: None,
        scale: 0.5,
        moving: false,
        pending: None,
        latency_ms: 0.0,
        cursor: None,
        looking: false,
        frames: 0,
        error: None,
    };
    event_loop.run_app(&mut app).context("running the window")?;
    match app.error {
        Some(e) => Err(e),
        None => {
            crate::output::note(format_args!("{} frames shown", app.frames));
            Ok(())
        }
    }
}
