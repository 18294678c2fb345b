//! Ground-truth renderers (all papers): `raster` shades what the rasterizer sees, `trace` is a
//! Whitted ray tracer over any [`RayQuery`](crate::trace::RayQuery) — the reference later methods are compared with.
//! And the first of those methods, `impostor` (paper 1 §6): the tracer with the rays mirrors and
//! glass send out answered by impostors.
//!
//! Every method shares one shading path ([`shading::surface_radiance`]): Lambert with the sun
//! (hard shadows) plus the environment's diffuse irradiance; mirrors and glass reflect and
//! refract. The raster method is the tracer on the rasterizer's primary hits at depth 1, so
//! mirrors and glass look the environment map up (classic environment mapping); `trace` follows
//! the rays. On diffuse-only scenes the two differ
//! only where the visible triangle differs (silhouette pixels), which the tests measure.
//!
//! [`Sequence`] plays frames of an animated scene, keeping impostors between them.
//!
//! Invariants: pixel `(i, j)` is shaded at its centre; the result does not depend on the thread
//! count; colours are linear.

mod impostor;
mod raster;
pub mod sequence;
pub mod shading;
mod trace;
pub mod wyman;

pub use impostor::{DEFAULT_IMPOSTOR_RESOLUTION, render_impostor};
pub use impostor::{
    ImpostorDrawer, ImpostorInputs, ReflectorImpostors, SeenImpostor, StandIns, placed_cameras,
};
pub use raster::{primary_hits, render_raster};
pub use sequence::{FrameReport, PreparedFrame, Sequence};
pub use trace::{Tracer, render_trace, shade_pixels, shade_rows};

use crate::frame::{Frame, FrameError};
pub use crate::progress::{Progress, Timings};
use crate::scene::{Lighting, RenderSettings, Scene, View};
use crate::trace::{Bvh, EnvironmentOnly, Exact};
use thiserror::Error;

/// Which renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Rasterize, shade directly, environment-map mirrors and glass.
    Raster,
    /// Whitted ray tracing through the BVH.
    Trace,
    /// Primary rays through the BVH; what mirrors and glass send out answered by SPOC
    /// impostors of the diffuse objects, this many texels square (paper 1).
    Impostor(u32),
    /// As [`Method::Impostor`], with planar (pinhole) depth images from the same points instead
    /// of SPOCs: the baseline of paper 1's Fig. 6.
    PinholeImpostor(u32),
    /// Primary rays through the BVH; what mirrors and glass send out takes the environment's
    /// radiance (environment mapping: what engines do without ray tracing).
    EnvMap,
}

impl Method {
    /// Texels a side of the impostors the method builds, if it builds any.
    pub fn impostor_resolution(self) -> Option<u32> {
        match self {
            Method::Impostor(r) | Method::PinholeImpostor(r) => Some(r),
            _ => None,
        }
    }
}

impl Method {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Raster => "raster",
            Method::Trace => "trace",
            Method::Impostor(_) => "impostor",
            Method::PinholeImpostor(_) => "pinhole-impostor",
            Method::EnvMap => "envmap",
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How the eye's refractions into glass objects are found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Refraction {
    /// Traced through the object: both interfaces exact.
    #[default]
    Exact,
    /// Wyman's image-space approximation of the second interface ([`wyman`]).
    Wyman,
}

/// How mirrors see one another under the impostor methods.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mirrors {
    /// Traced exactly, through a BVH of the mirror and glass objects alone (beyond the paper).
    #[default]
    Exact,
    /// As impostors that store their normals (paper 1 §6, second-order reflections): a ray
    /// meeting one reflects off the stored surface, and the reflected ray is answered again by
    /// that mirror's impostors, up to the scene's `max_depth`. Each mirror still sees itself
    /// and the glass exactly.
    Impostor,
}

/// What finds the surface each pixel sees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Primary {
    /// A ray through each pixel centre, through the BVH.
    #[default]
    Traced,
    /// The rasterizer's visibility buffer (paper 1 §6 rasterizes the primary pass); it differs
    /// from tracing on silhouette pixels only. Used by the ray-tracing methods.
    Rasterized,
}

/// How a frame is rendered: the method and the choices it leaves open.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions {
    /// What answers the rays.
    pub method: Method,
    /// How the eye's refractions into glass are found.
    pub refraction: Refraction,
    /// How mirrors see one another (impostor methods).
    pub mirrors: Mirrors,
    /// What finds the surfaces the eye sees.
    pub primary: Primary,
}

impl RenderOptions {
    /// `method`, with exact refraction and exact mirror-to-mirror rays.
    pub fn new(method: Method) -> Self {
        Self {
            method,
            refraction: Refraction::Exact,
            mirrors: Mirrors::Exact,
            primary: Primary::Traced,
        }
    }

    /// The same, the surfaces the eye sees found as `primary` says.
    pub fn primary(self, primary: Primary) -> Self {
        Self { primary, ..self }
    }

    /// The same, glass refracting the eye's rays by `refraction`.
    pub fn refraction(self, refraction: Refraction) -> Self {
        Self { refraction, ..self }
    }

    /// The same, mirrors seeing one another as `mirrors` says.
    pub fn mirrors(self, mirrors: Mirrors) -> Self {
        Self { mirrors, ..self }
    }
}

impl From<Method> for RenderOptions {
    fn from(method: Method) -> Self {
        Self::new(method)
    }
}

/// Errors from rendering.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The frame could not be allocated.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// The camera has a lens (a real camera's distortion) and the method cannot draw through
    /// it.
    #[error(
        "the camera has {lens} lens distortion, which only the trace method renders (with traced \
         primary rays); {method} draws through a pinhole"
    )]
    Lens {
        /// The lens's COLMAP model.
        lens: &'static str,
        /// What was asked to draw through it.
        method: &'static str,
    },
    /// The camera at the requested time is invalid.
    #[error(transparent)]
    Camera(#[from] crate::camera::CameraError),
    /// The scene could not be placed at the time asked.
    #[error(transparent)]
    View(#[from] crate::scene::ViewError),
    /// A mirror or glass object cannot have an impostor of an object (ids count from 0 in the
    /// scene file's order).
    #[error("object {object} seen from mirror/glass object {reflector}: {reason}")]
    Impostor {
        /// The object the impostor would replace.
        object: usize,
        /// The mirror or glass object.
        reflector: usize,
        /// Why not.
        reason: &'static str,
    },
    /// The device that draws impostors for the impostor methods could not draw one.
    #[error(
        "object {object} seen from mirror/glass object {reflector}: drawing its impostor: {reason}"
    )]
    Drawn {
        /// The object the impostor replaces.
        object: usize,
        /// The mirror or glass object.
        reflector: usize,
        /// The device's, or the library's resolve's, reason.
        reason: String,
    },
    /// The frame, the BVH or the impostors would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::OverBudget),
    /// A setting out of its range.
    #[error("{name} {value}: {reason}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// The time asked for is not a finite number.
    #[error("time {0}: must be a finite number of seconds")]
    Time(f32),
    /// A pixel's radiance passed `f32`'s range (or was made of such a value): the scene's
    /// environment, light or material values are too large to render.
    #[error(
        "the frame's pixel ({x}, {y}) is {value}: the scene's radiance passes f32's range (lower \
         its environment or light intensity, or its colours)"
    )]
    Radiance {
        /// Column.
        x: u32,
        /// Row.
        y: u32,
        /// The channel that is not finite (`inf`, `NaN`).
        value: f32,
    },
    /// An object's coordinates, placed and animated, are beyond
    /// [`crate::geom::MAX_COORDINATE`] or not finite.
    #[error(
        "object {object}: a vertex reaches {value:e}: beyond ±{:e} (or not a number), where \
         trompe's arithmetic overflows f32 (placed or animated too far)",
        crate::geom::MAX_COORDINATE
    )]
    OutOfRange {
        /// The object (ids count from 0 in the scene file's order).
        object: usize,
        /// The largest coordinate magnitude it reaches.
        value: f32,
    },
    /// A baked impostor a scene object names could not be loaded.
    #[error("object {object}: {source}")]
    BakedImpostor {
        /// The object (ids count from 0 in the scene file's order).
        object: usize,
        /// Why.
        source: crate::impostor::file::ImpostorFileError,
    },
    /// A baked impostor was not baked from the object as the scene places it.
    #[error(
        "object {object}: {path} was not baked from the object as the scene places it (the impostor's box {impostor_box:?} is not the object's {object_box:?}); bake the mesh as the scene places it, or place it with no fit, translate, rotate or scale"
    )]
    BakedMismatch {
        /// The object.
        object: usize,
        /// The impostor's sidecar.
        path: std::path::PathBuf,
        /// The impostor's box, min and max.
        impostor_box: [[f32; 3]; 2],
        /// The object's box in the scene, min and max.
        object_box: [[f32; 3]; 2],
    },
}

/// Renders `scene` at its default time with `method`.
pub fn render(
    scene: &Scene,
    method: Method,
    progress: &dyn Progress,
) -> Result<(Frame, Timings), RenderError> {
    render_at(scene, scene.render.time, method, progress)
}

/// Renders `scene` at time `t` with `method`.
pub fn render_at(
    scene: &Scene,
    t: f32,
    method: Method,
    progress: &dyn Progress,
) -> Result<(Frame, Timings), RenderError> {
    render_with(scene, t, RenderOptions::new(method), progress)
}

/// Renders `scene` at time `t` as `options` say (the raster method ignores the refraction
/// and mirror choices: it looks both up in the panorama).
pub fn render_with(
    scene: &Scene,
    t: f32,
    options: RenderOptions,
    progress: &dyn Progress,
) -> Result<(Frame, Timings), RenderError> {
    if !t.is_finite() {
        return Err(RenderError::Time(t));
    }
    let mut timings = Timings::default();
    let view = timings.time("evaluate scene", || scene.view(t))?;
    check_memory(&view, options.method)?;
    let frame = render_view(
        &view,
        (&scene.lighting, &scene.render),
        options,
        &StandIns::of(scene),
        progress,
        &mut timings,
    )?;
    Ok((frame, timings))
}

/// Bytes a frame pixel costs while it is rendered: the [`Frame`] (36) and the tracer's working
/// state and the encoded output beside it.
pub const BYTES_PER_PIXEL: u64 = 64;

/// Refuses a render whose frame, BVH and impostors would need more than the memory budget (an
/// impostor side no image can have is refused as such first).
pub fn check_memory(view: &View, method: Method) -> Result<(), RenderError> {
    use crate::memory::{check, times};
    let (w, h) = crate::camera::Projection::resolution(&view.camera);
    let triangles: u64 = view.meshes.iter().map(|m| m.triangle_count() as u64).sum();
    let mut needed = times(w as u64 * h as u64, BYTES_PER_PIXEL)
        .saturating_add(times(triangles, crate::trace::BVH_BUILD_BYTES_PER_TRIANGLE));
    let mut what = format!("a {w} × {h} render of {triangles} triangles");
    if let Some(side) = method.impostor_resolution() {
        crate::frame::check_size(side as u64, side as u64)?;
        // At most one impostor an object.
        let objects = view.meshes.len() as u64;
        let each = times(side as u64 * side as u64, crate::impostor::BYTES_PER_TEXEL);
        needed = needed.saturating_add(times(objects, each));
        what.push_str(&format!(
            " with up to {objects} impostors of {side} × {side}"
        ));
    }
    Ok(check(|| what, needed)?)
}

/// Renders an evaluated view; `stand_ins` says what stands in for its objects under the
/// impostor methods (baked impostors, mazes; `StandIns::default()`: nothing).
pub fn render_view(
    view: &View,
    (lighting, settings): (&Lighting, &RenderSettings),
    options: RenderOptions,
    stand_ins: &StandIns,
    progress: &dyn Progress,
    timings: &mut Timings,
) -> Result<Frame, RenderError> {
    check_finite(view)?;
    if let Some(lens) = &view.lens {
        let method = match (options.method, options.primary) {
            (Method::Trace | Method::EnvMap, Primary::Traced) => None,
            (Method::Trace | Method::EnvMap, Primary::Rasterized) => {
                Some("rasterized primary rays")
            }
            (m, _) => Some(m.name()),
        };
        if let Some(method) = method {
            return Err(RenderError::Lens {
                lens: lens.model().name(),
                method,
            });
        }
    }
    let refraction = options.refraction;
    let frame = match options.method {
        Method::Raster => render_raster(view, lighting, settings, progress, timings),
        Method::Trace => {
            let bvh = timings.time("build BVH", || Bvh::build(view.meshes.clone()))?;
            let tracer = Tracer {
                view,
                primary: &bvh,
                secondary: &Exact(&bvh),
                lighting,
                settings,
            };
            trace_frame(&tracer, (refraction, options.primary), progress, timings)
        }
        Method::Impostor(resolution) | Method::PinholeImpostor(resolution) => {
            let inputs = ImpostorInputs {
                baked: &stand_ins.baked,
                mazes: &stand_ins.mazes,
                pinhole: matches!(options.method, Method::PinholeImpostor(_)),
                refraction,
                mirrors: options.mirrors,
                primary: options.primary,
                ..ImpostorInputs::new(resolution)
            };
            render_impostor(view, lighting, settings, inputs, progress, timings)
        }
        Method::EnvMap => {
            let bvh = timings.time("build BVH", || Bvh::build(view.meshes.clone()))?;
            let tracer = Tracer {
                view,
                primary: &bvh,
                secondary: &EnvironmentOnly,
                lighting,
                settings,
            };
            trace_frame(&tracer, (refraction, options.primary), progress, timings)
        }
    }?;
    check_radiance(&frame)?;
    Ok(frame)
}

/// Refuses a frame whose colour is not finite somewhere (radiance past `f32`'s range: an
/// environment intensity of 3e38), naming the first such pixel: such a frame is no picture.
pub fn check_radiance(frame: &Frame) -> Result<(), RenderError> {
    let (w, _) = frame.color.size();
    match (frame.color.pixels().iter().enumerate()).find(|(_, c)| !c.is_finite()) {
        Some((i, c)) => Err(RenderError::Radiance {
            x: i as u32 % w,
            y: i as u32 / w,
            value: c
                .to_array()
                .into_iter()
                .find(|v| !v.is_finite())
                .unwrap_or(f32::NAN),
        }),
        None => Ok(()),
    }
}

/// Refuses geometry past [`crate::geom::MAX_COORDINATE`] (a translation of 3e38, an animation
/// run far) before any structure is built over it: a view built by hand, not by
/// [`crate::scene::Scene::view`], which refuses it itself.
pub(crate) fn check_finite(view: &View) -> Result<(), RenderError> {
    match view.out_of_range() {
        Some((object, value)) => Err(RenderError::OutOfRange { object, value }),
        None => Ok(()),
    }
}

/// Traces a frame with `tracer`, the surfaces the eye sees found as `primary` says and its
/// refractions into glass as `refraction` says.
pub fn trace_frame<P: crate::trace::RayQuery, S: crate::trace::SecondaryQuery + ?Sized>(
    tracer: &Tracer<'_, P, S>,
    (refraction, primary): (Refraction, Primary),
    progress: &dyn Progress,
    timings: &mut Timings,
) -> Result<Frame, RenderError> {
    let rasterized = match primary {
        Primary::Traced => None,
        Primary::Rasterized => {
            Some(timings.time("rasterize primary", || primary_hits(tracer.view))?)
        }
    };
    let primary_hit = |pixel: usize, ray: &crate::geom::Ray| match &rasterized {
        Some(hits) => hits.get(pixel).copied().flatten(),
        None => tracer.primary.closest_hit(ray, f32::INFINITY),
    };
    match refraction {
        Refraction::Exact => timings.time("trace", || match &rasterized {
            // Traced: each row's primary rays as one batch.
            None => render_trace(tracer, progress),
            Some(_) => shade_pixels(tracer, progress, primary_hit),
        }),
        Refraction::Wyman => {
            let backs = timings.time("back faces (Wyman pass 1)", || {
                wyman::BackFaces::build(tracer.view)
            })?;
            timings.time("trace", || {
                wyman::render(tracer, &backs, progress, primary_hit)
            })
        }
    }
}
