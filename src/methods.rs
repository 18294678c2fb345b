//! The one list of methods: every way trompe makes a frame of a scene, each behind one
//! interface — prepared once over a scene ([`Renderer::new`]), then a frame at a time, at a
//! time and through a camera ([`Renderer::frame`]), with its step timings and what it kept or
//! rebuilt. `trompe render` (one frame or `--frames`), the viewer, the report and `bench` all
//! go through it; method names and their help come from [`MethodKind`].
//!
//! | method | paper | what a frame is |
//! |---|---|---|
//! | `trace` | — | Whitted ray tracing through the exact BVH, the reference |
//! | `impostor`, `pinhole-impostor` | paper 1 §6 | secondary rays answered by SPOC (or planar) impostors kept across rigid motion |
//! | `envmap`, `raster` | paper 1 §2 | secondary rays answered by the panorama; `raster` rasterizes the eye's view too |
//! | `c3rc` | paper 2 §3 | reflections splatted from points through one continuous 3-ray camera per mirror triangle |
//! | `octahedral` | engines' octahedral impostors | every object drawn from its atlas, baked once while nothing moves |
//! | `layered`, `projective` | paper 4 §5 | the scene photographed once, then textured through each layer's sub-frustum (or by whole photographs) |
//! | `relief` | paper 3 §4–6 | relief impostors made by a software-shader thread and warped to every eye |
//! | `views`, `master` | papers 4–5 | a mesh textured from calibrated photographs: no scene file holds them, so a scene renderer refuses them (`trompe views render`, `trompe master render`) |
//!
//! ```
//! use trompe::methods::{MethodKind, MethodSettings, Renderer};
//!
//! // A mirror ball moving past a diffuse ball, under a uniform sky.
//! let scene = trompe::Scene::from_toml(
//!     r#"
//!     [camera]
//!     position = [0.0, 0.5, 3.0]
//!     look_at = [0.0, 0.0, 0.0]
//!     fov_y = 40.0
//!     resolution = [32, 24]
//!     [[object]]
//!     shape = "sphere"
//!     scale = 0.4
//!     translate = [0.5, 0.0, 0.0]
//!     [[object]]
//!     shape = "sphere"
//!     scale = 0.4
//!     translate = [-0.5, 0.0, 0.0]
//!     material = { type = "mirror" }
//!     [object.animate]
//!     velocity = [0.0, 0.5, 0.0]
//!     "#,
//!     std::path::Path::new("inline.toml"),
//! )?;
//! let settings = MethodSettings { impostor_resolution: 64, ..Default::default() };
//! let mut impostor = Renderer::new(&scene, MethodKind::Impostor, settings)?;
//! let first = impostor.frame(0.0, None, &())?;
//! let next = impostor.frame(0.1, None, &())?;
//! // The diffuse ball's impostor is built for the first frame and kept for the next (lit
//! // again: the mirror moved, and with it the shadows).
//! assert_eq!(first.report, "impostors: 1 built, 0 reused (0 relit)");
//! assert_eq!(next.report, "impostors: 0 built, 1 reused (1 relit)");
//! assert!(Renderer::new(&scene, MethodKind::Master, MethodSettings::default()).is_err());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Invariants: a method's frame depends only on the scene, its settings, the times and cameras
//! asked for so far, never on the thread count; a method that cannot render a scene file says
//! why through [`MethodKind::refusal`] before any work.

use crate::camera::Pinhole;
use crate::frame::Frame;
use crate::hybrid::{HybridReflections, HybridSettings};
use crate::layers::LayerSet;
use crate::octahedral::scene::SceneAtlases;
use crate::progress::{Progress, Timings};
use crate::relief::{Pipeline, PipelineSettings, SoftwareShader};
use crate::render::{Method, Mirrors, Primary, Refraction, RenderError, RenderOptions, Sequence};
use crate::scene::Scene;
use crate::views::CalibratedView;
use crate::views::capture::CaptureSettings;
use glam::{DVec2, Mat4};
use thiserror::Error;

/// Every way trompe makes a frame: one closed list.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MethodKind {
    /// Whitted ray tracing through the exact BVH.
    Trace,
    /// Paper 1: what mirrors and glass send out answered by SPOC impostors.
    Impostor,
    /// Paper 1's Fig. 6 baseline: planar depth images instead of SPOCs.
    PinholeImpostor,
    /// What mirrors and glass send out takes the panorama's radiance.
    EnvMap,
    /// Rasterized and shaded once; mirrors and glass look the panorama up.
    Raster,
    /// Paper 2: reflections splatted from points through continuous 3-ray cameras.
    C3rc,
    /// Every object drawn from an octahedral atlas, as engines draw distant objects.
    Octahedral,
    /// Paper 4: the scene photographed, sorted into visibility layers, textured through each
    /// layer's sub-frustum.
    Layered,
    /// Paper 4's baseline: the same photographs projected whole onto everything they see.
    Projective,
    /// Paper 3: relief impostors made on a software-shader thread, warped to every eye.
    Relief,
    /// A mesh textured view-dependently from calibrated views (ULR, VDTM, view map, best face).
    Views,
    /// Paper 5: a mesh rendered from its master textures.
    Master,
}

impl MethodKind {
    /// Every method, in the order the viewer's number keys take them.
    pub const ALL: [MethodKind; 12] = [
        MethodKind::Trace,
        MethodKind::Impostor,
        MethodKind::PinholeImpostor,
        MethodKind::EnvMap,
        MethodKind::Raster,
        MethodKind::C3rc,
        MethodKind::Layered,
        MethodKind::Relief,
        MethodKind::Octahedral,
        MethodKind::Projective,
        MethodKind::Views,
        MethodKind::Master,
    ];

    /// The methods that render a scene file: those without a [`MethodKind::refusal`].
    pub fn for_scenes() -> impl Iterator<Item = MethodKind> {
        Self::ALL.into_iter().filter(|m| m.refusal().is_none())
    }

    /// Its name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            MethodKind::Trace => "trace",
            MethodKind::Impostor => "impostor",
            MethodKind::PinholeImpostor => "pinhole-impostor",
            MethodKind::EnvMap => "envmap",
            MethodKind::Raster => "raster",
            MethodKind::C3rc => "c3rc",
            MethodKind::Octahedral => "octahedral",
            MethodKind::Layered => "layered",
            MethodKind::Projective => "projective",
            MethodKind::Relief => "relief",
            MethodKind::Views => "views",
            MethodKind::Master => "master",
        }
    }

    /// One line of help.
    pub fn about(self) -> &'static str {
        match self {
            MethodKind::Trace => "Whitted ray tracing through the exact BVH, with hard shadows",
            MethodKind::Impostor => {
                "what mirrors and glass send out answered by SPOC impostors of the diffuse objects (paper 1)"
            }
            MethodKind::PinholeImpostor => {
                "as impostor, with planar depth images instead of SPOCs (paper 1's Fig. 6 baseline)"
            }
            MethodKind::EnvMap => "what mirrors and glass send out takes the panorama's radiance",
            MethodKind::Raster => {
                "rasterize and shade once; mirrors and glass look the panorama up"
            }
            MethodKind::C3rc => {
                "reflections splatted from points through one continuous 3-ray camera per mirror triangle (paper 2)"
            }
            MethodKind::Octahedral => {
                "every object drawn from its octahedral atlas, as engines draw distant objects"
            }
            MethodKind::Layered => {
                "the scene photographed, sorted into visibility layers and textured through each layer's sub-frustum (paper 4)"
            }
            MethodKind::Projective => {
                "the same photographs projected whole onto everything they see (paper 4's baseline)"
            }
            MethodKind::Relief => {
                "relief impostors made on a software-shader thread and warped to every eye (paper 3)"
            }
            MethodKind::Views => "a mesh textured from calibrated views: `trompe views render`",
            MethodKind::Master => "a mesh rendered from master textures: `trompe master render`",
        }
    }

    /// The method named `name`.
    pub fn from_name(name: &str) -> Option<MethodKind> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Why the method cannot render a scene file, if it cannot.
    pub fn refusal(self) -> Option<&'static str> {
        match self {
            MethodKind::Views => Some(
                "it textures one mesh from a set of calibrated photographs, which a scene file does not hold: use `trompe views render MODEL --mesh MESH --scene SCENE`",
            ),
            MethodKind::Master => Some(
                "it renders one mesh from its master textures, which a scene file does not hold: use `trompe master render DIR --mesh MESH --scene SCENE`",
            ),
            _ => None,
        }
    }

    /// The ray-tracing method this kind is, if it is one ([`Sequence`] renders those).
    fn traced(self, impostor_resolution: u32) -> Option<Method> {
        match self {
            MethodKind::Trace => Some(Method::Trace),
            MethodKind::Impostor => Some(Method::Impostor(impostor_resolution)),
            MethodKind::PinholeImpostor => Some(Method::PinholeImpostor(impostor_resolution)),
            MethodKind::EnvMap => Some(Method::EnvMap),
            MethodKind::Raster => Some(Method::Raster),
            _ => None,
        }
    }
}

impl std::fmt::Display for MethodKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for MethodKind {
    type Err = MethodError;

    fn from_str(name: &str) -> Result<Self, MethodError> {
        MethodKind::from_name(name).ok_or_else(|| MethodError::Unknown {
            name: name.to_owned(),
        })
    }
}

/// The settings of every method, each reading its own part ([`MethodSettings::default`]:
/// what `trompe render` does without flags).
#[derive(Clone, Debug)]
pub struct MethodSettings {
    /// How glass refracts what the eye sees (ray-tracing methods).
    pub refraction: Refraction,
    /// How mirrors see other mirrors (impostor methods).
    pub mirrors: Mirrors,
    /// What finds the surfaces the eye sees (ray-tracing methods).
    pub primary: Primary,
    /// Texels a side of the impostors the impostor methods build.
    pub impostor_resolution: u32,
    /// Paper 2's points, trees and splats.
    pub hybrid: HybridSettings,
    /// Frames a side of each object's octahedral atlas.
    pub octahedral_frames: u32,
    /// Texels a side of each octahedral atlas frame.
    pub octahedral_frame_size: u32,
    /// The photographs the layered and projective methods take of the scene on first use.
    pub capture: CaptureSettings,
    /// How the layered and projective methods blend views.
    pub layers: crate::texturing::BlendSettings,
    /// Paper 3's pipeline.
    pub relief: PipelineSettings,
}

impl Default for MethodSettings {
    fn default() -> Self {
        Self {
            refraction: Refraction::default(),
            mirrors: Mirrors::default(),
            primary: Primary::default(),
            impostor_resolution: crate::render::DEFAULT_IMPOSTOR_RESOLUTION,
            hybrid: HybridSettings::default(),
            octahedral_frames: 16,
            octahedral_frame_size: 128,
            capture: CaptureSettings {
                count: DEFAULT_PHOTOGRAPHS,
                size: (640, 480),
                ..Default::default()
            },
            layers: crate::texturing::BlendSettings::default(),
            relief: PipelineSettings {
                // A frame uses the impostor it asked for at once, waiting for it: the same
                // inputs give the same frames.
                deterministic: Some(0),
                ..Default::default()
            },
        }
    }
}

/// Photographs the layered and projective methods take of a scene by default, on a ring.
pub const DEFAULT_PHOTOGRAPHS: usize = 6;

impl MethodSettings {
    /// The ray tracer's options for `method`.
    fn render_options(&self, method: Method) -> RenderOptions {
        RenderOptions::new(method)
            .refraction(self.refraction)
            .mirrors(self.mirrors)
            .primary(self.primary)
    }

    /// The octahedral bake the settings give.
    pub fn octahedral_bake(&self) -> crate::octahedral::BakeSettings {
        crate::octahedral::BakeSettings::new(
            crate::octahedral::Grid {
                n: self.octahedral_frames,
                coverage: crate::octahedral::Coverage::Sphere,
            },
            self.octahedral_frame_size,
        )
    }
}

/// Why a method could not make a frame.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MethodError {
    /// No method has that name.
    #[error("no method is named {name:?} (methods: {})", MethodKind::ALL.map(MethodKind::name).join(", "))]
    Unknown {
        /// The name given.
        name: String,
    },
    /// The method does not render scene files.
    #[error("method {method} does not render a scene: {reason}")]
    Refused {
        /// The method.
        method: MethodKind,
        /// Why, and what does.
        reason: &'static str,
    },
    /// The ray tracer, or a method built on it, failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The octahedral atlases could not be baked or drawn.
    #[error(transparent)]
    Octahedral(#[from] crate::octahedral::scene::SceneAtlasError),
    /// The scene could not be photographed.
    #[error(transparent)]
    Capture(#[from] crate::views::capture::CaptureError),
    /// The layers could not be built or drawn.
    #[error(transparent)]
    Layers(#[from] Box<crate::layers::LayersError>),
    /// The relief pipeline failed.
    #[error(transparent)]
    Relief(#[from] crate::relief::ReliefError),
    /// A camera could not be placed.
    #[error(transparent)]
    Camera(#[from] crate::camera::CameraError),
    /// The scene could not be placed at the time asked.
    #[error(transparent)]
    View(#[from] crate::scene::ViewError),
    /// A frame could not be allocated.
    #[error(transparent)]
    Frame(#[from] crate::frame::FrameError),
}

/// One frame a method made.
#[derive(Clone, Debug)]
pub struct MethodFrame {
    /// The frame.
    pub frame: Frame,
    /// Its steps.
    pub timings: Timings,
    /// One line: what the method kept, rebuilt or saw.
    pub report: String,
    /// Lines of state, one an object where the method keeps some (the relief pipeline's).
    pub state: Vec<String>,
}

/// A method prepared over one scene: frames at any times and through any cameras, what can be
/// kept from one frame to the next kept.
pub struct Renderer<'a> {
    scene: &'a Scene,
    kind: MethodKind,
    settings: MethodSettings,
    state: State<'a>,
}

/// What each method keeps between frames.
enum State<'a> {
    /// The ray tracer and the impostor methods: BVHs and impostors kept across rigid motion.
    Traced(Box<Sequence<'a>>),
    /// Paper 2: the points and trees, sampled on the first frame.
    Hybrid(Option<HybridReflections>),
    /// The atlases and the poses they were baked at.
    Octahedral(Option<(Vec<Mat4>, SceneAtlases)>),
    /// Paper 4: the layers, built on the first frame.
    Layered(Option<LayerSet>),
    /// Paper 4's baseline: the photographs and the meshes, taken on the first frame.
    Projective(Option<(Vec<CalibratedView>, Vec<crate::geom::Mesh>)>),
    /// Paper 3: the pipeline, started on the first frame over the scene then, and its time.
    Relief(Option<(Pipeline, f32)>),
}

impl<'a> Renderer<'a> {
    /// `kind` prepared over `scene`; refused at once if the method does not render scenes.
    pub fn new(
        scene: &'a Scene,
        kind: MethodKind,
        settings: MethodSettings,
    ) -> Result<Self, MethodError> {
        if let Some(reason) = kind.refusal() {
            return Err(MethodError::Refused {
                method: kind,
                reason,
            });
        }
        if let Some(sp) = settings
            .hybrid
            .spacing
            .filter(|s| !(s.is_finite() && *s > 0.0))
        {
            return Err(RenderError::Setting {
                name: "spacing",
                value: f64::from(sp),
                reason: "must be a positive number of scene units",
            }
            .into());
        }
        settings.relief.validate()?;
        // Only the exact tracer's own rays go through a lens; a method that draws through a
        // pinhole would draw another picture.
        if let Some(lens) = &scene.camera.lens {
            let refused = match (kind, settings.primary) {
                (MethodKind::Trace, crate::render::Primary::Traced) => None,
                (MethodKind::Trace, _) => Some("trace with rasterized primary rays"),
                (kind, _) => Some(kind.name()),
            };
            if let Some(method) = refused {
                return Err(RenderError::Lens {
                    lens: lens.model().name(),
                    method,
                }
                .into());
            }
        }
        let state = match kind.traced(settings.impostor_resolution) {
            Some(method) => State::Traced(Box::new(Sequence::new(
                scene,
                settings.render_options(method),
            ))),
            None => match kind {
                MethodKind::C3rc => State::Hybrid(None),
                MethodKind::Octahedral => State::Octahedral(None),
                MethodKind::Layered => State::Layered(None),
                MethodKind::Projective => State::Projective(None),
                _ => State::Relief(None),
            },
        };
        Ok(Self {
            scene,
            kind,
            settings,
            state,
        })
    }

    /// The method.
    pub fn kind(&self) -> MethodKind {
        self.kind
    }

    /// Its settings.
    pub fn settings(&self) -> &MethodSettings {
        &self.settings
    }

    /// The frame at time `t` (seconds) through `camera`, or the scene's camera at `t`
    /// (`progress` advances a row at a time where the method renders by rows).
    pub fn frame(
        &mut self,
        t: f32,
        camera: Option<Pinhole>,
        progress: &dyn Progress,
    ) -> Result<MethodFrame, MethodError> {
        if !t.is_finite() {
            return Err(RenderError::Time(t).into());
        }
        let scene = self.scene;
        let mut timings = Timings::default();
        let mut state = Vec::new();
        let (frame, report) = match &mut self.state {
            State::Traced(sequence) => {
                let (frame, steps, report) = sequence.frame_from(t, camera, progress)?;
                timings = steps;
                (frame, report.to_string())
            }
            State::Hybrid(kept) => {
                let clouds = match kept.take() {
                    Some(clouds) => clouds,
                    None => timings.time("sample points, build trees", || {
                        HybridReflections::prepare(scene, self.settings.hybrid)
                    })?,
                };
                // A deforming object's points follow its surface.
                let deformed = clouds.deformed_at(scene, t);
                let frame = timings.time("c3rc frame", || {
                    crate::hybrid::render_frame_from(
                        deformed.as_ref().unwrap_or(&clouds),
                        scene,
                        t,
                        camera,
                        progress,
                    )
                });
                let report = frame
                    .as_ref()
                    .map(|f| clouds.report(scene, f.stats).to_string())
                    .unwrap_or_default();
                *kept = Some(clouds);
                (frame?.frame, report)
            }
            State::Octahedral(kept) => {
                let poses = poses_at(scene, t);
                let still = scene.objects.iter().all(|o| o.deform.is_none());
                let rebake = !matches!(kept, Some((at, _)) if still && *at == poses);
                let atlases = match (rebake, kept.as_ref()) {
                    (false, Some((_, atlases))) => atlases,
                    _ => {
                        let bake = self.settings.octahedral_bake();
                        let atlases = timings
                            .time("bake atlases", || SceneAtlases::bake(scene, t, bake, &()))?;
                        &kept.insert((poses, atlases)).1
                    }
                };
                let camera = match camera {
                    Some(c) => c,
                    None => scene.camera.at(t)?,
                };
                let frame = timings.time("draw from atlases", || {
                    atlases.render_through(&camera, &scene.lighting, progress)
                })?;
                let n = self.settings.octahedral_frames;
                let report = atlases.report(n, rebake);
                (frame, report)
            }
            State::Layered(kept) => {
                let set = match kept.take() {
                    Some(set) => set,
                    None => scene_layers(scene, &self.settings, &mut timings)?,
                };
                let camera = match camera {
                    Some(c) => c,
                    None => scene.camera.at(t)?,
                };
                let blend = timings.time("layered frame", || {
                    crate::layers::render::render(&camera, &set, &self.settings.layers)
                });
                *kept = Some(set);
                let blend = blend?;
                let report = format!("{} holes of {} pixels", blend.holes, blend.covered);
                (over_environment(scene, &camera, &blend.image)?, report)
            }
            State::Projective(kept) => {
                let (views, meshes) = match kept.take() {
                    Some(taken) => taken,
                    None => scene_photographs(scene, &self.settings, &mut timings)?,
                };
                let camera = match camera {
                    Some(c) => c,
                    None => scene.camera.at(t)?,
                };
                let refs: Vec<&crate::geom::Mesh> = meshes.iter().collect();
                let blend = timings.time("projective frame", || {
                    crate::layers::render::render_projective(
                        &camera,
                        &refs,
                        &views,
                        &self.settings.layers,
                    )
                });
                *kept = Some((views, meshes));
                let blend = blend?;
                let report = format!("{} holes of {} pixels", blend.holes, blend.covered);
                (over_environment(scene, &camera, &blend.image)?, report)
            }
            State::Relief(kept) => {
                let (mut pipeline, time) = match kept.take() {
                    Some(relief) => relief,
                    None => (start_relief(scene, t, &self.settings, &mut timings)?, t),
                };
                // Relief impostors are of a still scene: the scene as it stood when the
                // pipeline started, seen through the camera of now.
                let camera = match camera {
                    Some(c) => c,
                    None => scene.camera.at(t)?,
                };
                let out = pipeline.frame(&camera);
                let report;
                (report, state) = match &out {
                    Ok(out) => relief_report(scene, &pipeline, time, &out.objects),
                    Err(_) => Default::default(),
                };
                *kept = Some((pipeline, time));
                let mut out = out?;
                timings.0.append(&mut out.timings.0);
                (out.frame, report)
            }
        };
        crate::render::check_radiance(&frame)?;
        Ok(MethodFrame {
            frame,
            timings,
            report,
            state,
        })
    }
}

/// The `relief` method's pipeline over `scene` as it stands at `t` (relief impostors are of a
/// still scene): the software shader started on its own thread, every object given a slot —
/// on either device.
pub fn start_relief(
    scene: &Scene,
    t: f32,
    settings: &MethodSettings,
    timings: &mut Timings,
) -> Result<Pipeline, MethodError> {
    let view = scene.view(t)?;
    let shader =
        SoftwareShader::new(&view, &scene.lighting, &scene.render).map_err(RenderError::from)?;
    let objects: Vec<usize> = (0..view.meshes.len()).collect();
    let settings = settings.relief.clone();
    Ok(timings.time("start the relief pipeline", || {
        Pipeline::new(shader, &objects, settings)
    })?)
}

/// A `relief` frame's report (the still scene's time, the impostors made) and its per-object
/// state lines.
pub fn relief_report(
    scene: &Scene,
    pipeline: &Pipeline,
    time: f32,
    objects: &[crate::relief::frames::ObjectFrame],
) -> (String, Vec<String>) {
    let threshold = pipeline.settings().threshold;
    let state = objects
        .iter()
        .map(|o| {
            let name = scene.objects.get(o.object).map_or("?", |s| s.name.as_str());
            o.line(name, threshold)
        })
        .collect();
    let made = pipeline.regenerations;
    (
        format!("still scene at t {time:.2} s, {made} impostors made"),
        state,
    )
}

/// Every object's pose at `t`.
fn poses_at(scene: &Scene, t: f32) -> Vec<Mat4> {
    scene
        .objects
        .iter()
        .map(|o| o.world_from_object_at(t))
        .collect()
}

/// The photographs the layered and projective methods take of `scene`.
fn photograph(
    scene: &Scene,
    settings: &CaptureSettings,
    timings: &mut Timings,
) -> Result<Vec<CalibratedView>, MethodError> {
    let set = timings.time("photograph the scene", || {
        crate::views::capture::capture_of(scene.clone(), settings, &())
    })?;
    Ok(set.views)
}

/// The `layered` method's layers of `scene` (paper 4): the scene photographed from the views
/// `settings.capture` places, sorted into visibility layers and cut into image layers — what
/// the method textures every frame by, on either device.
pub fn scene_layers(
    scene: &Scene,
    settings: &MethodSettings,
    timings: &mut Timings,
) -> Result<crate::layers::LayerSet, MethodError> {
    let views = photograph(scene, &settings.capture, timings)?;
    let (meshes, names) = crate::layers::scene_objects(scene)?;
    Ok(timings
        .time("build layers", || {
            crate::layers::build(meshes, names, &views, &Default::default(), &())
        })
        .map_err(Box::new)?)
}

/// The `projective` method's photographs of `scene` (paper 4's baseline), from the views
/// `settings.capture` places, and the scene's meshes they are projected onto.
pub fn scene_photographs(
    scene: &Scene,
    settings: &MethodSettings,
    timings: &mut Timings,
) -> Result<(Vec<CalibratedView>, Vec<crate::geom::Mesh>), MethodError> {
    let views = photograph(scene, &settings.capture, timings)?;
    let (meshes, _) = crate::layers::scene_objects(scene)?;
    Ok((views, meshes))
}

/// A blended image over the scene's environment: where the blend is transparent (no object,
/// or a hole no photograph fills), the panorama seen along the pixel's ray — the frame of the
/// texturing methods, on either device.
pub fn over_environment(
    scene: &Scene,
    camera: &Pinhole,
    image: &crate::frame::Image<crate::frame::Rgba>,
) -> Result<Frame, MethodError> {
    let (w, h) = image.size();
    let mut frame = Frame::new(w, h)?;
    let env = &scene.lighting.environment;
    for y in 0..h {
        for x in 0..w {
            let c = image.get(x, y);
            let centre = f64::from(crate::frame::PIXEL_CENTER);
            let ray = camera.ray(DVec2::new(f64::from(x) + centre, f64::from(y) + centre));
            let behind = env.radiance(ray.dir);
            let a = c.w.clamp(0.0, 1.0);
            frame
                .color
                .set(x, y, (c.truncate() * a + behind * (1.0 - a)).extend(1.0));
        }
    }
    Ok(frame)
}
