//! Relief impostors (paper 3, "Software Shaders in Interactive Environments Using Relief
//! Impostors", §2–5; docs/conventions.md §5): an orthographic colour + displacement image of an
//! object, made by a CPU "software shader" (the BVH ray tracer with hard shadows and mirror
//! bounces), re-used for many frames by 3-D image warping, and replaced when it goes stale.
//!
//! * [`ReliefFrame`], [`ReliefImpostor`] — the base plane, its texel axes and the images on it.
//! * [`shader`] — the software shader: impostor generation and the true render it stands for.
//! * [`prewarp`](mod@prewarp) — the relief pre-warp (paper Eq. 2–3), two 1-D passes in occlusion-compatible
//!   order with two-neighbour hole filling, direct and by lookup table (§5).
//! * [`texture`] — the texture-mapping phase: the pre-warped image on the base quad, drawn into
//!   a frame with per-pixel depth.
//! * [`mcmillan`] — McMillan's full 3-D warp of a perspective depth image (Eq. 1), the reference.
//! * [`validity`] — the interpolated-texel ratio and the critical-point heuristic (§3).
//! * [`pipeline`] — the warping loop and the rendering thread, the state machine, the cache.
//! * [`frames`] — what the pipeline hands back a frame: each object's state, the draws.
//! * [`raster`] — the objects drawn directly (fallbacks, objects without relief).
//! * [`walk`](mod@walk) — a camera path walked through the pipeline and scored against the true render.
//!
//! Invariants: the base plane is the front of the object (paper Fig. 2: the image plane of the
//! orthographic camera that made it); a displacement `d` is a signed height along its unit
//! normal `f` (toward the viewer), in world units, so the object lies at `−max_depth ≤ d ≤ 0`
//! and its depth into the impostor is `δ = −d`; texel `(u, v)` has its centre at
//! `(u + 0.5, v + 0.5)` in texel coordinates; a background texel has alpha 0. Warps are
//! deterministic: the same impostor and eye give the same pre-warped image on any thread count.

pub mod frames;
pub mod mcmillan;
pub mod pipeline;
pub mod prewarp;
pub mod raster;
pub mod shader;
pub mod texture;
pub mod validity;
pub mod walk;

use crate::frame::Rgba;
use glam::{DVec3, Vec3};
use thiserror::Error;

pub use frames::{ObjectState, PreparedDraws, PreparedFrame, ReliefDraw};
pub use pipeline::{Pipeline, PipelineSettings};
pub use prewarp::{Coefficients, Eye, Prewarped, prewarp};
pub use shader::SoftwareShader;
pub use walk::{WalkReport, WalkSettings, walk};

/// Errors of relief impostors.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReliefError {
    /// A resolution no impostor can have.
    #[error("relief resolution {0}: must be between 4 and 4096 texels a side")]
    Resolution(u32),
    /// The object has no extent (no triangles, or all at one point).
    #[error("object {object}: it has no extent, so no relief impostor can frame it")]
    Empty {
        /// The object (ids count from 0 in the scene file's order).
        object: usize,
    },
    /// There is no such object.
    #[error("object {object}: the scene has only {count} objects")]
    NoObject {
        /// The requested object.
        object: usize,
        /// How many the scene has.
        count: usize,
    },
    /// The eye is inside the object's bounding sphere, where no relief frame faces it.
    #[error("the eye at {eye:?} is inside object {object}'s bounding sphere")]
    EyeInside {
        /// The object.
        object: usize,
        /// The eye.
        eye: [f32; 3],
    },
    /// A frame or image could not be allocated.
    #[error(transparent)]
    Frame(#[from] crate::frame::FrameError),
    /// A camera could not be made.
    #[error(transparent)]
    Camera(#[from] crate::camera::CameraError),
    /// The scene could not be placed at the time asked.
    #[error(transparent)]
    View(#[from] crate::scene::ViewError),
    /// Rendering a reference or fallback frame failed.
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// The relief images would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] crate::memory::OverBudget),
    /// A pipeline setting out of its range: a share or angle that is not a positive number.
    #[error("relief setting {name} = {value}: {reason}")]
    Setting {
        /// The setting's name (`threshold`, `fallback` …).
        name: &'static str,
        /// The value given.
        value: f64,
        /// The range it must lie in.
        reason: &'static str,
    },
    /// The rendering thread stopped unexpectedly.
    #[error("the relief rendering thread stopped: {0}")]
    Worker(&'static str),
}

/// An sRGB-encoded RGBA8 texel (alpha linear).
pub type Srgba8 = [u8; 4];

/// Encodes a linear colour as [`Srgba8`].
pub fn encode(c: Rgba) -> Srgba8 {
    let q = |x: f32| (crate::frame::linear_to_srgb(x.clamp(0.0, 1.0)) * 255.0).round() as u8;
    [
        q(c.x),
        q(c.y),
        q(c.z),
        (c.w.clamp(0.0, 1.0) * 255.0).round() as u8,
    ]
}

/// Decodes an [`Srgba8`] to linear colour (a table lookup).
#[inline]
pub fn decode(c: Srgba8) -> Rgba {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    let t = TABLE
        .get_or_init(|| std::array::from_fn(|i| crate::frame::srgb_to_linear(i as f32 / 255.0)));
    Rgba::new(
        t[c[0] as usize],
        t[c[1] as usize],
        t[c[2] as usize],
        c[3] as f32 / 255.0,
    )
}

/// Smallest and largest relief resolution, texels a side.
pub const RESOLUTION_RANGE: (u32, u32) = (4, 4096);

/// The base plane of a relief impostor: texel `(u, v)` at displacement `d` is the world point
/// `origin + u·a + v·b + d·f` (continuous texel coordinates). `a` and `b` are orthogonal, of the
/// same length (one texel), and `f = normalize(b × a)`: the base plane's normal, toward the
/// side the impostor was made from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReliefFrame {
    /// Corner of texel `(0, 0)` on the base plane (`d = 0`).
    pub origin: DVec3,
    /// World step of one texel in `+u`.
    pub a: DVec3,
    /// World step of one texel in `+v` (image rows go down).
    pub b: DVec3,
    /// Unit normal of the base plane, toward the side the impostor was made from.
    pub f: DVec3,
    /// Texels a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Largest depth into the impostor (`MAX_DEPTH` of paper §5): the object's extent along `f`.
    pub max_depth: f64,
}

impl ReliefFrame {
    /// The frame of an object bounded by the sphere `(centre, radius)`, seen from `eye`: the base
    /// plane perpendicular to the direction from the centre to the eye, tangent to the sphere on
    /// the eye's side, with `resolution²` texels covering the sphere's silhouette;
    /// `max_depth = 2·radius`. Seen from near its own eye, every texel then shrinks under the
    /// pre-warp (it lies behind the plane), so interpolation measures disocclusion only.
    pub fn facing(
        centre: DVec3,
        radius: f64,
        eye: DVec3,
        resolution: u32,
    ) -> Result<Self, ReliefError> {
        if !(RESOLUTION_RANGE.0..=RESOLUTION_RANGE.1).contains(&resolution) {
            return Err(ReliefError::Resolution(resolution));
        }
        // Rows follow world "down" where they can (y up), else the z axis.
        let toward_eye = (eye - centre).normalize_or_zero();
        let up = if toward_eye.cross(DVec3::Y).length_squared() > 1e-6 {
            DVec3::Y
        } else {
            DVec3::Z
        };
        // The base plane faces the eye: the eye's look-at frame toward the centre, reversed.
        let [forward, right, true_up] = crate::camera::look_at_basis(eye, centre, up)?;
        let (f, down) = (-forward, (-true_up).normalize());
        let s = 2.0 * radius / resolution as f64;
        let (a, b) = (right * s, down * s);
        let half = resolution as f64 * 0.5;
        Ok(Self {
            origin: centre + f * radius - a * half - b * half,
            a,
            b,
            f,
            width: resolution,
            height: resolution,
            max_depth: 2.0 * radius,
        })
    }

    /// The world point at continuous texel coordinates `(u, v)` and displacement `d`.
    pub fn point(&self, u: f64, v: f64, d: f64) -> DVec3 {
        self.origin + self.a * u + self.b * v + self.f * d
    }

    /// A world point's continuous texel coordinates and displacement `(u, v, d)`.
    pub fn coordinates(&self, p: DVec3) -> DVec3 {
        let r = p - self.origin;
        DVec3::new(
            r.dot(self.a) / self.a.length_squared(),
            r.dot(self.b) / self.b.length_squared(),
            r.dot(self.f),
        )
    }

    /// The centre of the sphere the frame was made around ([`ReliefFrame::facing`]): the
    /// middle of the image, `max_depth / 2` behind the plane.
    pub fn centre(&self) -> DVec3 {
        self.point(
            self.width as f64 * 0.5,
            self.height as f64 * 0.5,
            -self.max_depth * 0.5,
        )
    }

    /// Texel size in world units.
    pub fn texel_size(&self) -> f64 {
        self.a.length()
    }
}

/// How displacements are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DepthEncoding {
    /// Eight bits of depth into the impostor over `[0, max_depth]`, as in paper §5 (and its
    /// lookup-table pre-warp).
    #[default]
    U8,
    /// One `f32` a texel.
    F32,
}

/// Stored displacements.
#[derive(Clone, Debug, PartialEq)]
pub enum Displacements {
    /// Depth into the impostor in eight-bit steps of `max_depth / 255`: `d = −code·max/255`.
    U8(Vec<u8>),
    /// Signed displacement `d`, world units.
    F32(Vec<f32>),
}

/// A relief impostor: colour and displacement over a [`ReliefFrame`], made for one eye.
#[derive(Clone, Debug, PartialEq)]
pub struct ReliefImpostor {
    /// Its base plane.
    pub frame: ReliefFrame,
    /// The eye it was made for.
    pub eye: DVec3,
    /// Colour as sRGB-encoded RGBA8 (as an engine uploads it; paper §5), alpha 0 where the
    /// object is absent (row-major, `width × height`).
    pub color: Vec<Srgba8>,
    /// Displacements (meaningless where alpha is 0).
    pub depth: Displacements,
}

impl ReliefImpostor {
    /// Displacement `d` of texel `i` (row-major), world units (`≤ 0` for an impostor a shader
    /// made: the object lies behind the base plane).
    #[inline]
    pub fn displacement(&self, i: usize) -> f64 {
        match &self.depth {
            Displacements::U8(d) => -(d[i] as f64) * self.frame.max_depth / 255.0,
            Displacements::F32(d) => d[i] as f64,
        }
    }

    /// Whether texel `i` shows the object.
    #[inline]
    pub fn covered(&self, i: usize) -> bool {
        self.color[i][3] > 0
    }

    /// How its displacements are stored.
    pub fn encoding(&self) -> DepthEncoding {
        match self.depth {
            Displacements::U8(_) => DepthEncoding::U8,
            Displacements::F32(_) => DepthEncoding::F32,
        }
    }

    /// Texels showing the object.
    pub fn covered_count(&self) -> usize {
        self.color.iter().filter(|c| c[3] > 0).count()
    }

    /// Bytes of its images (colour and depth).
    pub fn bytes(&self) -> usize {
        let texels = self.color.len();
        texels * 4
            + match self.depth {
                Displacements::U8(_) => texels,
                Displacements::F32(_) => texels * 4,
            }
    }

    /// The colour as a linear image (for previews and reports).
    pub fn color_image(&self) -> Result<crate::frame::Image<Rgba>, crate::frame::FrameError> {
        let data = self.color.iter().map(|&c| decode(c)).collect();
        crate::frame::Image::from_vec(self.frame.width, self.frame.height, data)
    }

    /// The depth as a grey image, white at the base plane, black `max_depth` behind it,
    /// background transparent.
    pub fn depth_image(&self) -> Result<crate::frame::Image<Rgba>, crate::frame::FrameError> {
        let data = (0..self.color.len())
            .map(|i| {
                if self.covered(i) {
                    let g = (1.0 + self.displacement(i) / self.frame.max_depth) as f32;
                    Vec3::splat(g).extend(1.0)
                } else {
                    Rgba::ZERO
                }
            })
            .collect();
        crate::frame::Image::from_vec(self.frame.width, self.frame.height, data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_faces_its_eye_and_frames_the_sphere() {
        let (c, r) = (DVec3::new(0.2, 0.5, -0.1), 0.7);
        let eye = DVec3::new(2.0, 1.5, 3.0);
        let fr = ReliefFrame::facing(c, r, eye, 64).unwrap();
        assert!((fr.f - (eye - c).normalize()).length() < 1e-12);
        assert!(fr.a.dot(fr.b).abs() < 1e-12 && fr.a.dot(fr.f).abs() < 1e-12);
        assert!((fr.b.cross(fr.a).normalize() - fr.f).length() < 1e-12);
        // The sphere's centre is at the image centre, r behind the plane.
        let centre = fr.coordinates(c);
        assert!(
            (centre - DVec3::new(32.0, 32.0, -r)).length() < 1e-9,
            "{centre}"
        );
        assert!((fr.point(centre.x, centre.y, centre.z) - c).length() < 1e-12);
        assert!((fr.centre() - c).length() < 1e-12);
        assert!(ReliefFrame::facing(c, r, eye, 2).is_err());
    }
}
