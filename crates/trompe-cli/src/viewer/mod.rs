//! The interactive viewer's state (beyond the papers; paper 3 §4 is about keeping frames
//! flowing): a camera flown or orbited by input, a clock, and the methods to switch between —
//! those of [`trompe::render`], each a [`Sequence`] that keeps its impostors between frames;
//! paper 2's hybrid reflections, paper 4's layers and paper 3's relief pipeline, each made on
//! first use. A window is a thin shell over it (the `trompe view` command); the same state, fed
//! a [`script`], renders headless frames, so the viewer is tested without a display.
//!
//! Invariants: the viewer adds no rendering method of its own; a frame depends only on the
//! inputs given and the time steps taken (never on the wall clock or the thread count), except
//! for the relief method of a [`Viewer::live`] viewer, which shows impostors when its thread
//! has made them.

pub mod hud;
pub mod script;

use glam::{Vec3, Vec4};
use std::time::Instant;
use thiserror::Error;
use trompe::camera::Pinhole;
use trompe::frame::{Image, Rgba, metrics};
use trompe::methods::{MethodError, MethodKind, MethodSettings, Renderer};
use trompe::render::{Primary, RenderError, Timings};
use trompe::scene::Scene;
use trompe_gpu::{DeviceRenderer, Gpu};

/// A control.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    /// Move along the view direction (fly), or closer to the target (orbit).
    Forward,
    /// The opposite.
    Back,
    /// Move left (fly), or turn around the target (orbit).
    Left,
    /// The opposite.
    Right,
    /// Move up.
    Up,
    /// Move down.
    Down,
    /// Switch to method `n` of [`Viewer::methods`].
    Method(usize),
    /// Toggle fly and orbit.
    Orbit,
    /// Orbit the next object of the scene (in the scene file's order).
    NextObject,
    /// Pause or resume the animation.
    Pause,
    /// Cycle the split screen: off, exact left and method right, FLIP heat map.
    Split,
    /// Ask the shell to save a screenshot.
    Screenshot,
    /// Ask the shell to save the camera as a scene `[camera]` block.
    SaveCamera,
    /// Toggle the help overlay.
    Help,
}

/// An input event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// A key went down (held keys move the camera every step).
    Down(Key),
    /// A key came up.
    Up(Key),
    /// The mouse moved by this many pixels (looks around, or orbits).
    Look(f32, f32),
    /// The wheel turned by this many notches (speed up or down).
    Scroll(f32),
}

/// What a key asks the shell to do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// Save the last frame.
    Screenshot,
    /// Save the camera block.
    SaveCamera,
}

/// The split screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Split {
    /// The chosen method alone.
    #[default]
    Off,
    /// Left half exact (`trace`), right half the chosen method.
    Halves,
    /// The FLIP error of the chosen method against `trace`, as a heat map.
    Flip,
}

/// Errors from the viewer.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ViewerError {
    /// A frame could not be rendered.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A method could not make its frame.
    #[error(transparent)]
    Method(#[from] MethodError),
    /// A method could not make its frame on its device.
    #[error(transparent)]
    Device(#[from] trompe_gpu::DeviceError),
    /// The camera became degenerate.
    #[error(transparent)]
    Camera(#[from] trompe::camera::CameraError),
    /// A frame could not be made or compared.
    #[error(transparent)]
    Frame(#[from] trompe::frame::FrameError),
}

/// Frames after its request that the relief method uses a new impostor, unless the viewer is
/// [`Viewer::live`] (the frame waits for it if need be, so the same inputs give the same frames).
pub const RELIEF_LATENCY: u32 = 2;

/// Radians a pixel of mouse motion turns the camera.
pub const LOOK_PER_PIXEL: f32 = 0.003;
/// Factor a wheel notch multiplies the speed by.
pub const SPEED_PER_NOTCH: f32 = 1.2;

/// A camera flown or orbited around a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Eye.
    pub eye: Vec3,
    /// Radians about +y; 0 looks along −z.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// What orbit mode turns around.
    pub target: Vec3,
    /// Orbiting (else flying).
    pub orbit: bool,
    /// Full vertical field of view, degrees.
    pub fov_y: f64,
    /// Near-plane distance.
    pub near: f64,
}

impl FlyCamera {
    /// Looking from `eye` at `target`, with the near plane at `near`.
    pub fn looking_at(eye: Vec3, target: Vec3, fov_y: f64, near: f64) -> Self {
        let d = (target - eye).try_normalize().unwrap_or(Vec3::NEG_Z);
        Self {
            eye,
            yaw: d.x.atan2(-d.z),
            pitch: d.y.clamp(-1.0, 1.0).asin(),
            target,
            orbit: false,
            fov_y,
            near,
        }
    }

    /// The unit view direction.
    pub fn direction(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, -cy * cp)
    }

    /// The pinhole of `w × h` pixels.
    pub fn pinhole(&self, (w, h): (u32, u32)) -> Result<Pinhole, trompe::camera::CameraError> {
        Ok(Pinhole::look_at(
            self.eye,
            self.eye + self.direction(),
            Vec3::Y,
            self.fov_y,
            w,
            h,
        )?
        .with_near(self.near))
    }

    fn turn(&mut self, dx: f32, dy: f32) {
        let limit = 89f32.to_radians();
        self.yaw += dx * LOOK_PER_PIXEL;
        self.pitch = (self.pitch - dy * LOOK_PER_PIXEL).clamp(-limit, limit);
        if self.orbit {
            let distance = self.eye.distance(self.target);
            self.eye = self.target - self.direction() * distance;
        }
    }
}

/// One frame the viewer made.
pub struct ViewFrame {
    /// Linear colour, the size asked for.
    pub image: Image<Rgba>,
    /// The steps of the chosen method's frame.
    pub timings: Timings,
    /// Wall time of the whole frame, ms (split screens included).
    pub ms: f64,
    /// The overlay's lines.
    pub hud: Vec<String>,
}

/// The viewer: camera, clock, methods and their sequences.
pub struct Viewer<'a> {
    scene: &'a Scene,
    camera: FlyCamera,
    held: Vec<Key>,
    /// Scene units a second.
    speed: f32,
    time: f32,
    paused: bool,
    /// The methods the number keys switch between, in [`MethodKind::for_scenes`] order, each
    /// on the GPU where one was given and the method has a GPU path.
    renderers: Vec<DeviceRenderer<'a>>,
    /// `trace`, for the split screen (on the CPU: the reference).
    exact: Renderer<'a>,
    gpu: Option<&'a Gpu>,
    impostor_resolution: u32,
    /// The object orbited, if one was chosen.
    selected: Option<usize>,
    current: usize,
    split: Split,
    help: bool,
}

impl<'a> Viewer<'a> {
    /// A viewer of `scene` from its camera at its time; impostors of `impostor_resolution²`;
    /// the methods with a GPU path on `gpu`, if given.
    pub fn new(
        scene: &'a Scene,
        impostor_resolution: u32,
        gpu: Option<&'a Gpu>,
    ) -> Result<Self, ViewerError> {
        let c = &scene.camera;
        let start = scene.camera.at(scene.render.time).ok();
        let (eye, target) = match start {
            Some(p) => (
                p.position().as_vec3(),
                p.position().as_vec3() + p.forward().as_vec3(),
            ),
            None => (c.position, c.look_at),
        };
        let target = if c.path.is_empty() { c.look_at } else { target };
        let renderers = renderers(scene, impostor_resolution, false, gpu);
        let exact = Renderer::new(scene, MethodKind::Trace, MethodSettings::default())?;
        Ok(Self {
            scene,
            camera: FlyCamera::looking_at(eye, target, c.fov_y, c.near),
            held: Vec::new(),
            speed: (0.5 * eye.distance(target)).max(1e-3),
            time: scene.render.time,
            paused: false,
            renderers,
            exact,
            gpu,
            impostor_resolution,
            selected: None,
            current: 1,
            split: Split::Off,
            help: false,
        })
    }

    /// Lets the relief method use each impostor as soon as its rendering thread makes it, as an
    /// interactive window wants; by default it uses it [`RELIEF_LATENCY`] frames after the
    /// request, waiting if need be, so that a frame depends only on the inputs.
    pub fn live(mut self) -> Self {
        self.renderers = renderers(self.scene, self.impostor_resolution, true, self.gpu);
        self
    }

    /// The methods the number keys switch between, in order (key 1 is the first, key 0 the
    /// tenth).
    pub fn methods(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.renderers.iter().map(|r| r.kind().name())
    }

    /// The camera.
    pub fn camera(&self) -> &FlyCamera {
        &self.camera
    }

    /// Scene time, seconds.
    pub fn time(&self) -> f32 {
        self.time
    }

    /// Scene units a second the camera moves.
    pub fn speed(&self) -> f32 {
        self.speed
    }

    /// The split-screen mode.
    pub fn split(&self) -> Split {
        self.split
    }

    /// Takes one input; returns what it asks the shell to do, if anything.
    pub fn input(&mut self, input: Input) -> Option<Request> {
        match input {
            Input::Down(key) => return self.press(key),
            Input::Up(key) => self.held.retain(|k| *k != key),
            Input::Look(dx, dy) => self.camera.turn(dx, dy),
            Input::Scroll(notches) => {
                self.speed = (self.speed * SPEED_PER_NOTCH.powf(notches)).clamp(1e-4, 1e6)
            }
        }
        None
    }

    fn press(&mut self, key: Key) -> Option<Request> {
        match key {
            // After the sequences' numbers, the hybrid and layered methods'.
            Key::Method(n) if n < self.renderers.len() => self.current = n,
            Key::Method(_) => {}
            Key::Orbit => {
                self.camera.orbit = !self.camera.orbit;
                if self.camera.orbit {
                    // Orbit what the camera looks at, at the current distance along the view.
                    let distance = self.camera.eye.distance(self.camera.target).max(1e-3);
                    self.camera.target = self.camera.eye + self.camera.direction() * distance;
                }
            }
            Key::NextObject if !self.scene.objects.is_empty() => {
                let next = self
                    .selected
                    .map_or(0, |i| (i + 1) % self.scene.objects.len());
                self.selected = Some(next);
                let o = &self.scene.objects[next];
                let centre = o
                    .world_from_object_at(self.time)
                    .transform_point3(o.mesh.bounds().center());
                let c = &mut self.camera;
                let distance = c.eye.distance(centre).max(1e-3);
                let keep = FlyCamera::looking_at(c.eye, centre, c.fov_y, c.near);
                (c.yaw, c.pitch, c.target, c.orbit) = (keep.yaw, keep.pitch, centre, true);
                c.eye = centre - c.direction() * distance;
            }
            Key::NextObject => {}
            Key::Pause => self.paused = !self.paused,
            Key::Split => {
                self.split = match self.split {
                    Split::Off => Split::Halves,
                    Split::Halves => Split::Flip,
                    Split::Flip => Split::Off,
                }
            }
            Key::Help => self.help = !self.help,
            Key::Screenshot => return Some(Request::Screenshot),
            Key::SaveCamera => return Some(Request::SaveCamera),
            movement => {
                if !self.held.contains(&movement) {
                    self.held.push(movement);
                }
            }
        }
        None
    }

    /// Advances `dt` seconds: held keys move the camera, the clock runs unless paused.
    pub fn step(&mut self, dt: f32) {
        let dt = if dt.is_finite() { dt.max(0.0) } else { 0.0 };
        if !self.paused {
            self.time += dt;
        }
        let held = |k| self.held.contains(&k);
        let axis = |plus, minus| f32::from(u8::from(held(plus))) - f32::from(u8::from(held(minus)));
        let (forward, right, up) = (
            axis(Key::Forward, Key::Back),
            axis(Key::Right, Key::Left),
            axis(Key::Up, Key::Down),
        );
        let c = &mut self.camera;
        if c.orbit {
            // Around the target at a fixed distance; forward and back change the distance.
            let distance = (c.eye.distance(c.target) - forward * self.speed * dt).max(1e-3);
            let turn = self.speed * dt / c.eye.distance(c.target).max(1e-3);
            c.yaw -= right * turn;
            c.pitch = (c.pitch + up * turn).clamp(-89f32.to_radians(), 89f32.to_radians());
            c.eye = c.target - c.direction() * distance;
        } else {
            let d = c.direction();
            let side = d.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
            let motion = d * forward + side * right + Vec3::Y * up;
            c.eye += motion * (self.speed * dt);
        }
    }

    /// The frame of `size` pixels, rendered at `scale` of it (1 for full resolution; less
    /// while the camera moves) and enlarged to `size`.
    pub fn frame(&mut self, size: (u32, u32), scale: f32) -> Result<ViewFrame, ViewerError> {
        let start = Instant::now();
        let scale = scale.clamp(0.05, 1.0);
        let small = (
            ((size.0 as f32 * scale).round() as u32).max(1),
            ((size.1 as f32 * scale).round() as u32).max(1),
        );
        let camera = self.camera.pinhole(small)?;
        let out = self.renderers[self.current].frame(self.time, Some(camera.clone()), &())?;
        let (frame, timings, report, state) = (out.frame, out.timings, out.report, out.state);
        let image = match self.split {
            Split::Off => frame.color,
            Split::Halves | Split::Flip => {
                let exact = self.exact.frame(self.time, Some(camera), &())?.frame;
                if self.split == Split::Flip {
                    metrics::heat_map(&metrics::flip_map(&exact.color, &frame.color)?)
                } else {
                    let (w, h) = exact.color.size();
                    let mut halves = Image::new(w, h, Vec4::ZERO)?;
                    for y in 0..h {
                        for x in 0..w {
                            let from = if x < w / 2 {
                                &exact.color
                            } else {
                                &frame.color
                            };
                            halves.set(x, y, from.get(x, y));
                        }
                    }
                    halves
                }
            }
        };
        let image = enlarge(&image, size)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let kind = self.renderers[self.current].kind();
        let name = kind.name();
        let resolution = matches!(kind, MethodKind::Impostor | MethodKind::PinholeImpostor)
            .then_some(self.impostor_resolution);
        let mut hud = vec![
            format!(
                "{name}{}  {ms:.0} ms ({:.1} fps)  {}x{} of {}x{}",
                resolution.map_or(String::new(), |r| format!(" {r}^2")),
                1e3 / ms.max(1e-9),
                small.0,
                small.1,
                size.0,
                size.1
            ),
            format!(
                "{:.1} M pixels/s  t {:.2} s{}  {}",
                (small.0 * small.1) as f64 / ms.max(1e-9) / 1e3,
                self.time,
                if self.paused { " (paused)" } else { "" },
                report
            ),
        ];
        hud.extend(
            timings
                .0
                .iter()
                .map(|(step, d)| format!("  {step} {:.1} ms", d.as_secs_f64() * 1e3)),
        );
        hud.extend(state);
        if self.split != Split::Off {
            hud.push(format!("split: {:?} (trace against {name})", self.split));
        }
        if self.help {
            hud.extend(HELP.iter().map(|s| s.to_string()));
        }
        Ok(ViewFrame {
            image,
            timings,
            ms,
            hud,
        })
    }

    /// The camera as a scene-file `[camera]` block that reproduces the view at `size`.
    pub fn camera_block(&self, size: (u32, u32)) -> String {
        let c = &self.camera;
        let at = c.eye + c.direction();
        format!(
            "[camera]\nposition = [{:?}, {:?}, {:?}]\nlook_at = [{:?}, {:?}, {:?}]\nfov_y = {:?}\nresolution = [{}, {}]\nnear = {:?}\n",
            c.eye.x, c.eye.y, c.eye.z, at.x, at.y, at.z, c.fov_y, size.0, size.1, c.near
        )
    }
}

/// Every method that renders a scene, prepared over `scene` as the viewer runs them: the
/// impostor and environment methods find what the eye sees by rasterizing (faster; differs on
/// silhouette pixels only); the relief method uses a new impostor [`RELIEF_LATENCY`] frames
/// after its request, or as soon as it is made when `live`. A method with a GPU path runs on
/// `gpu` when one is given.
fn renderers<'a>(
    scene: &'a Scene,
    impostor_resolution: u32,
    live: bool,
    gpu: Option<&'a Gpu>,
) -> Vec<DeviceRenderer<'a>> {
    MethodKind::for_scenes()
        .filter_map(|kind| {
            let mut settings = MethodSettings {
                impostor_resolution,
                ..Default::default()
            };
            if matches!(
                kind,
                MethodKind::Impostor | MethodKind::PinholeImpostor | MethodKind::EnvMap
            ) {
                settings.primary = Primary::Rasterized;
            }
            settings.relief.deterministic = (!live).then_some(RELIEF_LATENCY);
            let device = gpu.filter(|_| trompe_gpu::has_gpu_path(kind));
            DeviceRenderer::new(scene, kind, settings, device).ok()
        })
        .collect()
}

/// The help overlay.
pub const HELP: [&str; 9] = [
    "WASD move, Q/E down/up, mouse look, wheel speed",
    "Tab fly / orbit the point looked at, O orbit the next object",
    "1 trace 2 impostor 3 pinhole-impostor 4 envmap 5 raster",
    "6 c3rc 7 layered 8 relief 9 octahedral 0 projective",
    "V split: off / trace | method / FLIP heat map",
    "P pause the animation",
    "F12 screenshot  C save the camera block",
    "H this help  Esc quit",
    "",
];

/// `image` enlarged to `size` by nearest neighbour (itself when the sizes agree).
fn enlarge(image: &Image<Rgba>, size: (u32, u32)) -> Result<Image<Rgba>, ViewerError> {
    let (w, h) = image.size();
    if (w, h) == size {
        return Ok(image.clone());
    }
    let mut out = Image::new(size.0, size.1, Vec4::ZERO)?;
    for y in 0..size.1 {
        let sy = (y as u64 * h as u64 / size.1 as u64) as u32;
        for x in 0..size.0 {
            let sx = (x as u64 * w as u64 / size.0 as u64) as u32;
            out.set(x, y, image.get(sx, sy));
        }
    }
    Ok(out)
}
