//! The cameras an impostor is built through (paper 1 §3–5): pinhole, orthographic, SPOC and
//! graph camera as one closed set, dispatched once per query, and [`ViewCamera`], a camera
//! placed to look at one object.
//!
//! Invariant: every camera answers the same questions — its size, where a point lands, the
//! point at a texel — so the builder and the walks match once and run through the concrete
//! camera.

use crate::camera::{GraphCamera, ImagePoint, Orthographic, Pinhole, Projection, Spoc};
use glam::{DVec2, DVec3, Vec3};

/// The cameras an impostor can be built through (a closed set, dispatched once per query).
#[derive(Clone, Debug, PartialEq)]
pub enum ImpostorCamera {
    /// Planar pinhole.
    Pinhole(Pinhole),
    /// Parallel projection.
    Orthographic(Orthographic),
    /// Single-pole occlusion camera.
    Spoc(Spoc),
    /// Graph camera: a tree of pinhole frusta.
    Graph(GraphCamera),
}

/// A camera placed to look at one object: what [`ImpostorCamera::around`] builds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewCamera {
    /// Planar pinhole framing the object's bounding sphere.
    Pinhole,
    /// Parallel projection framing the bounding sphere.
    Orthographic,
    /// SPOC; its strength from [`Spoc::strength_for_region`] unless given.
    Spoc(Option<f64>),
}

impl ImpostorCamera {
    /// A camera at `eye` looking at the sphere (`center`, `radius`), `size²` texels. `region`
    /// is the radius of the region the secondary rays come from (the SPOC strength rule
    /// k ≈ 2Δ/z_O, docs/conventions.md §3.2).
    pub fn around(
        kind: ViewCamera,
        eye: Vec3,
        center: Vec3,
        radius: f32,
        region: f64,
        size: u32,
    ) -> Result<ImpostorCamera, crate::camera::CameraError> {
        Self::around_framed(kind, eye, center, radius, region, size, 1.0)
    }

    /// The camera `trompe impostor bake` places for `mesh`: its viewpoint `distance` bounding
    /// radii from the mesh's centre along `from`, framed tightly on the mesh
    /// ([`ImpostorCamera::fitted`]), a SPOC's strength chosen for rays from within one radius of
    /// the viewpoint.
    pub fn facing_mesh(
        kind: ViewCamera,
        mesh: &crate::geom::Mesh,
        from: Vec3,
        distance: f32,
        size: u32,
    ) -> Result<ImpostorCamera, crate::camera::CameraError> {
        let b = mesh.bounds();
        let (center, radius) = (b.center(), b.radius());
        let dir = from
            .try_normalize()
            .ok_or(crate::camera::CameraError::Degenerate(
                "the direction to the camera is zero",
            ))?;
        let eye = center + dir * radius * distance;
        Self::fitted(
            kind,
            eye,
            center,
            radius,
            radius as f64,
            size,
            &mesh.positions,
        )
    }

    /// [`ImpostorCamera::around`], then framed tightly on `points` (the object's vertices):
    /// the view is narrowed until their image fills 95 % of the half-width, so no texel is
    /// spent on the empty corners of the bounding sphere's image. If a point does not project,
    /// the sphere's framing is kept.
    #[allow(clippy::too_many_arguments)]
    pub fn fitted(
        kind: ViewCamera,
        eye: Vec3,
        center: Vec3,
        radius: f32,
        region: f64,
        size: u32,
        points: &[Vec3],
    ) -> Result<ImpostorCamera, crate::camera::CameraError> {
        let first = Self::around(kind, eye, center, radius, region, size)?;
        let half = size as f64 / 2.0;
        let mut extent = 0.0f64;
        for p in points {
            let Some(q) = first.project(p.as_dvec3()) else {
                return Ok(first);
            };
            extent = extent.max((q.uv - DVec2::splat(half)).abs().max_element());
        }
        let scale = extent / half / 0.95;
        if !(scale > 1e-3 && scale.is_finite()) {
            return Ok(first);
        }
        Self::around_framed(kind, eye, center, radius, region, size, scale)
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn around_framed(
        kind: ViewCamera,
        eye: Vec3,
        center: Vec3,
        radius: f32,
        region: f64,
        size: u32,
        scale: f64,
    ) -> Result<ImpostorCamera, crate::camera::CameraError> {
        let d = eye.distance(center) as f64;
        let r = radius as f64;
        if !(r > 0.0 && d > r * 1.0001) {
            return Err(crate::camera::CameraError::Degenerate(
                "the eye must lie outside the object's bounding sphere",
            ));
        }
        let up = if (center - eye).normalize().y.abs() > 0.99 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        Ok(match kind {
            ViewCamera::Pinhole => {
                let half = (r / (d * d - r * r).max(1e-12).sqrt()) * 1.05 * scale;
                let cam =
                    Pinhole::look_at(eye, center, up, 2.0 * half.atan().to_degrees(), size, size)?;
                ImpostorCamera::Pinhole(cam.with_near((d - r) * 0.5))
            }
            ViewCamera::Orthographic => {
                // The image plane at the eye, deep enough to hold the whole sphere.
                ImpostorCamera::Orthographic(Orthographic::look_at(
                    eye,
                    center,
                    up,
                    r * 1.05 * scale,
                    d + r * 1.05,
                    size,
                    size,
                )?)
            }
            ViewCamera::Spoc(k) => {
                let k = k.unwrap_or_else(|| Spoc::strength_for_region(region, d));
                ImpostorCamera::Spoc(Spoc::around_framed(eye, center, radius, k, size, scale)?)
            }
        })
    }

    /// The point the camera sees from: its centre of projection (a pinhole's, the SPOC's
    /// reference pinhole's, the graph camera's root apex), or for a parallel projection the
    /// centre of its image plane. The rays an impostor answers come from around it (the region
    /// its SPOC strength is chosen for, §3.2).
    pub fn viewpoint(&self) -> DVec3 {
        match self {
            ImpostorCamera::Pinhole(c) => c.position(),
            ImpostorCamera::Orthographic(c) => {
                let (corner, a, b, _, _) = c.parameters();
                let (w, h) = c.resolution();
                corner + a * (w as f64 * 0.5) + b * (h as f64 * 0.5)
            }
            ImpostorCamera::Spoc(c) => c.pinhole().position(),
            ImpostorCamera::Graph(g) => g.root().position(),
        }
    }

    /// True when straight world segments project to curves, so triangles must be tessellated
    /// and ray walks must sample the curve.
    pub fn is_curved(&self) -> bool {
        matches!(self, ImpostorCamera::Spoc(_))
    }

    /// Direction from world point `p` back toward the camera (its centre of projection, or
    /// against the viewing direction for parallel projection); not normalized.
    #[inline]
    pub fn toward_camera(&self, p: DVec3) -> DVec3 {
        match self {
            ImpostorCamera::Pinhole(c) => c.position() - p,
            ImpostorCamera::Orthographic(c) => -c.parameters().3,
            ImpostorCamera::Spoc(c) => c.pinhole().position() - p,
            ImpostorCamera::Graph(g) => {
                let j = g.locate(p).unwrap_or(0);
                g.frusta()[j].apex - p
            }
        }
    }

    /// Whether an impostor through this camera keeps its texels' world positions in a map
    /// (a graph camera) rather than deriving them from `gd` ([`Impostor::position_at`]).
    pub fn stores_positions(&self) -> bool {
        matches!(self, ImpostorCamera::Graph(_))
    }

    /// The unit direction toward the camera along its ray through image point `(uv, gd)`, at
    /// the point `p` there: how a surface at `p` is seen, for the slant of a texel's footprint
    /// on it. [`ImpostorCamera::toward_camera`], except for the SPOC, whose rays curve (§3.2):
    /// deeper than `z_n` they leave the direction of its eye, and a surface the eye sees
    /// edge-on is seen more squarely along them — which is what the SPOC is for. Its direction
    /// is then the ray's tangent, toward larger `gd`.
    pub fn toward_camera_along_ray(&self, uv: DVec2, gd: f64, p: DVec3) -> DVec3 {
        match self {
            ImpostorCamera::Spoc(c) if gd > 0.0 => {
                let h = gd * 1e-4;
                (c.unproject(uv, gd + h) - c.unproject(uv, gd - h)).normalize_or_zero()
            }
            _ => self.toward_camera(p).normalize_or_zero(),
        }
    }

    /// A box holding the image of every point of the world segment `[a, b]` (`None` if an end
    /// is outside the camera's domain). Pinhole and orthographic images of a segment are the
    /// segment between the ends' images; the SPOC's lies in the trapezoid spanned by the pinhole
    /// images of the ends scaled about the pole by the extreme `1 + κ(z)` of the segment.
    pub fn segment_image_bounds(&self, a: DVec3, b: DVec3) -> Option<(DVec2, DVec2)> {
        match self {
            ImpostorCamera::Pinhole(_) | ImpostorCamera::Orthographic(_) => {
                let (pa, pb) = (self.project(a)?, self.project(b)?);
                Some((pa.uv.min(pb.uv), pa.uv.max(pb.uv)))
            }
            ImpostorCamera::Spoc(s) => s.segment_image_bounds(a, b),
            // A segment may cross frusta: no simple bound (the walk then never skips).
            ImpostorCamera::Graph(_) => None,
        }
    }

    /// Short name (`pinhole`, `orthographic`, `spoc`).
    pub fn kind(&self) -> &'static str {
        match self {
            ImpostorCamera::Pinhole(_) => "pinhole",
            ImpostorCamera::Orthographic(_) => "orthographic",
            ImpostorCamera::Spoc(_) => "spoc",
            ImpostorCamera::Graph(_) => "graph",
        }
    }
}

/// An impostor camera is not itself a [`Projection`]: a graph camera has no near boundary
/// affine in the world point (its frusta bend), so it cannot keep that trait's promise. What
/// every impostor camera can answer — its size, where a point lands, the point at a texel — is
/// here; the builder and the walks match once and run through the concrete camera.
impl ImpostorCamera {
    /// Image size in texels `(width, height)`.
    pub fn resolution(&self) -> (u32, u32) {
        match self {
            ImpostorCamera::Pinhole(c) => c.resolution(),
            ImpostorCamera::Orthographic(c) => c.resolution(),
            ImpostorCamera::Spoc(c) => c.resolution(),
            ImpostorCamera::Graph(c) => c.resolution(),
        }
    }

    /// Where a world point lands ([`Projection::project`]; for a graph camera, in the frustum
    /// that holds it).
    pub fn project(&self, p: DVec3) -> Option<ImagePoint> {
        match self {
            ImpostorCamera::Pinhole(c) => c.project(p),
            ImpostorCamera::Orthographic(c) => c.project(p),
            ImpostorCamera::Spoc(c) => c.project(p),
            ImpostorCamera::Graph(c) => c.project(p),
        }
    }

    /// The world point at image coordinates `uv` and generalized depth `gd > 0`.
    pub fn unproject(&self, uv: DVec2, gd: f64) -> DVec3 {
        match self {
            ImpostorCamera::Pinhole(c) => c.unproject(uv, gd),
            ImpostorCamera::Orthographic(c) => c.unproject(uv, gd),
            ImpostorCamera::Spoc(c) => c.unproject(uv, gd),
            ImpostorCamera::Graph(c) => c.unproject(uv, gd),
        }
    }

    /// [`ImpostorCamera::project`] of an `f32` point.
    pub fn project_f32(&self, p: Vec3) -> Option<ImagePoint> {
        self.project(p.as_dvec3())
    }
}
