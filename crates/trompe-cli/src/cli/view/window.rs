//! The viewer's window: winit for the window and input over `crate::viewer::Viewer`, shown
//! through a wgpu surface on the GPU the methods run on (`trompe_gpu::present`), else through
//! softbuffer; a script fed on the window's own clock, and `--quit-after` to close it.
//!
//! Invariant: the window shows the frames the headless viewer renders for the same inputs; only
//! the render scale while moving and the clock differ.

use super::{Output, handle};
use crate::viewer::script::{self, Script};
use crate::viewer::{Input, Request, Viewer, hud};
use anyhow::{Context, Result};
use std::num::NonZeroU32;
use std::sync::Arc;
use std::time::Instant;
use trompe_gpu::{Gpu, WindowSurface};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

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
pub(super) fn window<'a>(
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
