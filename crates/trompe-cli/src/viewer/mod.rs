//! The interactive viewer's state (beyond the papers; paper 3 §4 is about keeping frames
//! flowing): a camera flown or orbited by input, a clock, and the methods to switch between —
//! those of [`mod@trompe::render`], each a [`trompe::render::Sequence`] that keeps its
//! impostors between frames; paper 2's hybrid reflections, paper 4's layers and paper 3's relief
//! pipeline, each made on first use — or, in place of a scene, a mesh textured from photographs
//! or master textures, one weighting a key (`photographs.rs`). A window is a thin shell over it
//! (the `trompe view` command); the same state, fed a [`script`], renders headless frames, so
//! the viewer is tested without a display.
//!
//! Invariants: the viewer adds no rendering method of its own; a frame depends only on the
//! inputs given and the time steps taken (never on the wall clock or the thread count), except
//! for the relief method of a [`Viewer::live`] viewer, which shows impostors when its thread
//! has made them.

mod camera;
pub mod hud;
mod photographs;
mod scene;
pub mod script;

pub use camera::{FlyCamera, LOOK_PER_PIXEL, SPEED_PER_NOTCH};

use glam::Vec4;
use photographs::Photographs;
use scene::SceneMethods;
use std::time::Instant;
use thiserror::Error;
use trompe::frame::{Image, Rgba, metrics};
use trompe::geom::Mesh;
use trompe::methods::MethodError;
use trompe::render::{RenderError, Timings};
use trompe::scene::Scene;
use trompe_gpu::{Gpu, TexturedMesh};

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
    /// Photographs to fly around hold none.
    #[error("the {what} hold no photograph to start from")]
    NoPhotographs {
        /// What was given: "views" or "masters".
        what: &'static str,
    },
}

/// Frames after its request that the relief method uses a new impostor, unless the viewer is
/// [`Viewer::live`] (the frame waits for it if need be, so the same inputs give the same frames).
pub const RELIEF_LATENCY: u32 = 2;

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

/// The viewer: camera, clock, what it shows and the methods to switch between.
pub struct Viewer<'a> {
    subject: Subject<'a>,
    camera: FlyCamera,
    held: Vec<Key>,
    /// Scene units a second.
    speed: f32,
    time: f32,
    paused: bool,
    current: usize,
    split: Split,
    help: bool,
}

/// What the viewer shows, with the methods the number keys switch between.
enum Subject<'a> {
    /// A scene, through its methods.
    Scene(Box<SceneMethods<'a>>),
    /// A mesh textured from photographs, one weighting a key.
    Photographs(Box<Photographs<'a>>),
}

/// What a method shows through one camera.
struct Shown {
    /// Linear colour.
    image: Image<Rgba>,
    /// The split screen's reference through the same camera, when asked for.
    reference: Option<Image<Rgba>>,
    timings: Timings,
    /// The method's name in the overlay.
    name: String,
    /// One line: what the method kept, rebuilt or saw.
    report: String,
    /// Lines of state.
    state: Vec<String>,
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
        let methods = SceneMethods::new(scene, impostor_resolution, gpu)?;
        let camera = FlyCamera::looking_at(eye, target, c.up, c.fov_y, c.near);
        Ok(Self::showing(
            Subject::Scene(Box::new(methods)),
            camera,
            0.5 * eye.distance(target),
            scene.render.time,
            1,
        ))
    }

    /// A viewer of a mesh textured from photographs, from the first photograph's camera; the
    /// number keys switch between the weightings (ULR, VDTM, the view map, best face), starting from
    /// `textured`'s, and the key that orbits the next object goes to the next photograph.
    pub fn of_photographs(textured: TexturedMesh<'a>, mesh: &Mesh) -> Result<Self, ViewerError> {
        let photographs = Photographs::new(textured, mesh)?;
        let camera = photographs.start();
        let speed = 0.5 * camera.eye.distance(mesh.bounds().center());
        let current = photographs.current();
        Ok(Self::showing(
            Subject::Photographs(Box::new(photographs)),
            camera,
            speed,
            0.0,
            current,
        ))
    }

    fn showing(
        subject: Subject<'a>,
        camera: FlyCamera,
        speed: f32,
        time: f32,
        current: usize,
    ) -> Self {
        Self {
            subject,
            camera,
            held: Vec::new(),
            speed: speed.max(1e-3),
            time,
            paused: false,
            current,
            split: Split::Off,
            help: false,
        }
    }

    /// Lets the relief method use each impostor as soon as its rendering thread makes it, as an
    /// interactive window wants; by default it uses it [`RELIEF_LATENCY`] frames after the
    /// request, waiting if need be, so that a frame depends only on the inputs.
    pub fn live(mut self) -> Self {
        if let Subject::Scene(m) = &mut self.subject {
            m.go_live();
        }
        self
    }

    /// The methods the number keys switch between, in order (key 1 is the first, key 0 the
    /// tenth).
    pub fn methods(&self) -> Vec<&'static str> {
        match &self.subject {
            Subject::Scene(m) => m.names(),
            Subject::Photographs(p) => p.names(),
        }
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
            Key::Method(n) if n < self.methods().len() => self.current = n,
            Key::Method(_) => {}
            Key::Orbit => {
                self.camera.orbit = !self.camera.orbit;
                if self.camera.orbit {
                    // Orbit what the camera looks at, at the current distance along the view.
                    let distance = self.camera.eye.distance(self.camera.target).max(1e-3);
                    self.camera.target = self.camera.eye + self.camera.direction() * distance;
                }
            }
            Key::NextObject => match &mut self.subject {
                Subject::Scene(m) => m.orbit_next(&mut self.camera, self.time),
                Subject::Photographs(p) => p.next_photograph(&mut self.camera),
            },
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
            let side = d.cross(c.up).try_normalize().unwrap_or(c.level().1);
            let motion = d * forward + side * right + c.up * up;
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
        let reference = self.split != Split::Off;
        let shown = match &mut self.subject {
            Subject::Scene(m) => m.frame(self.current, self.time, &camera, reference)?,
            Subject::Photographs(p) => p.frame(self.current, &camera, reference)?,
        };
        let Shown {
            image,
            reference,
            timings,
            name,
            report,
            state,
        } = shown;
        let image = match (self.split, reference) {
            (Split::Flip, Some(exact)) => metrics::heat_map(&metrics::flip_map(&exact, &image)?),
            (Split::Halves, Some(exact)) => {
                let (w, h) = exact.size();
                let mut halves = Image::new(w, h, Vec4::ZERO)?;
                for y in 0..h {
                    for x in 0..w {
                        let from = if x < w / 2 { &exact } else { &image };
                        halves.set(x, y, from.get(x, y));
                    }
                }
                halves
            }
            _ => image,
        };
        let image = enlarge(&image, size)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let mut hud = vec![
            format!(
                "{name}  {ms:.0} ms ({:.1} fps)  {}x{} of {}x{}",
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
            let against = match &self.subject {
                Subject::Scene(_) => "trace",
                Subject::Photographs(_) => "the same blend on the CPU",
            };
            hud.push(format!(
                "split: {:?} ({against} against {name})",
                self.split
            ));
        }
        if self.help {
            hud.extend(self.help());
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
            "[camera]\nposition = [{:?}, {:?}, {:?}]\nlook_at = [{:?}, {:?}, {:?}]\nup = [{:?}, {:?}, {:?}]\nfov_y = {:?}\nresolution = [{}, {}]\nnear = {:?}\n",
            c.eye.x,
            c.eye.y,
            c.eye.z,
            at.x,
            at.y,
            at.z,
            c.up.x,
            c.up.y,
            c.up.z,
            c.fov_y,
            size.0,
            size.1,
            c.near
        )
    }
}

impl Viewer<'_> {
    /// The help overlay: the controls, and the methods by key.
    pub fn help(&self) -> Vec<String> {
        let (next, reference, animation) = match &self.subject {
            Subject::Scene(_) => ("O orbit the next object", "trace", "P pause the animation"),
            Subject::Photographs(_) => ("O go to the next photograph", "CPU blend", ""),
        };
        let methods = self.methods();
        let keys: Vec<String> = methods
            .iter()
            .enumerate()
            .map(|(i, name)| format!("{} {name}", (i + 1) % 10))
            .collect();
        let mut lines = vec![
            "WASD move, Q/E down/up, mouse look, wheel speed".to_string(),
            format!("Tab fly / orbit the point looked at, {next}"),
        ];
        lines.extend(keys.chunks(5).map(|c| c.join(" ")));
        lines.push(format!(
            "V split: off / {reference} | method / FLIP heat map"
        ));
        lines.extend(
            [
                animation,
                "F12 screenshot  C save the camera block",
                "H this help  Esc quit",
            ]
            .iter()
            .filter(|l| !l.is_empty())
            .map(|l| l.to_string()),
        );
        lines
    }
}

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
